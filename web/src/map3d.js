// The interactive 3D view of one run: static / eliminated / confirmed-dynamic map points and the
// trajectories (three.js points and lines; orbit, zoom and pan with the mouse). Renders on demand.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

// Colours of the paper's figures (and of the PLY files): static grey, eliminated red, confirmed orange.
export const LAYERS = [
  { key: 'static', label: 'static map', color: 0x8a8a8a, size: 2 },
  { key: 'eliminated', label: 'eliminated (dynamic)', color: 0xe61e1e, size: 2.5 },
  { key: 'confirmed', label: 'confirmed dynamic', color: 0xff9600, size: 2.5 },
  { key: 'ghosts', label: 'static map on moving objects (ghosts, by the masks)', color: 0xc000c0, size: 4 },
  { key: 'static_loop', label: 'static map, loop-corrected', color: 0x7b3fbf, size: 2 },
  { key: 'est', label: 'trajectory', color: 0x1f77b4, line: true },
  { key: 'gt', label: 'ground truth', color: 0x111111, line: true },
  { key: 'loop', label: 'trajectory, loop-corrected', color: 0x9467bd, line: true },
];

function pointsObject(flat, layer) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(flat, 3));
  const m = new THREE.PointsMaterial({ color: layer.color, size: layer.size, sizeAttenuation: false });
  return new THREE.Points(g, m);
}

function lineObject(path, layer) {
  const flat = new Float32Array(path.x.length * 3);
  for (let i = 0; i < path.x.length; i++) flat.set([path.x[i], path.y[i], path.z[i]], 3 * i);
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(flat, 3));
  return new THREE.Line(g, new THREE.LineBasicMaterial({ color: layer.color }));
}

// A marker (points of `size` px whatever the zoom) at the trajectory's start and end: a run that
// moved a centimetre among a map metres wide still shows where it went.
function endsObject(path, color) {
  const n = path.x.length - 1;
  const flat = [path.x[0], path.y[0], path.z[0], path.x[n], path.y[n], path.z[n]];
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(flat, 3));
  return new THREE.Points(g, new THREE.PointsMaterial({ color, size: 9, sizeAttenuation: false }));
}

// A grid in the plane z = `z` around `center` with cells of a round size (1, 2 or 5 x 10^k m) that
// fit about ten to `radius`, and the world axes at the origin (x red, y green, z blue), a cell long.
function gridAndAxes(center, radius, z) {
  const raw = radius / 5;
  const pow = 10 ** Math.floor(Math.log10(raw));
  const cell = [1, 2, 5, 10].map((k) => k * pow).find((c) => c >= raw);
  const divisions = Math.min(200, 2 * Math.ceil((2 * radius) / cell));
  const grid = new THREE.GridHelper(divisions * cell, divisions, 0xb0b0b0, 0xe0e0e0);
  grid.rotation.x = Math.PI / 2;  // GridHelper lies in x-z; the world's ground is x-y (z up)
  grid.position.set(Math.round(center.x / cell) * cell, Math.round(center.y / cell) * cell, z);
  const axes = new THREE.AxesHelper(cell);
  return { grid, axes, cell };
}

// A viewer in `parent` for run `run`; returns {canvas, setLayer(key, on), render(), layers, points, cell}.
export function createViewer(parent, run, width, height) {
  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  renderer.setSize(width, height);
  renderer.setClearColor(0xffffff);
  parent.append(renderer.domElement);
  const scene = new THREE.Scene();
  const objects = {};
  let points = 0;
  for (const layer of LAYERS) {
    if (layer.line) {
      if (run[layer.key] && run[layer.key].x.length > 1) objects[layer.key] = lineObject(run[layer.key], layer);
    } else if (run.maps[layer.key] && run.maps[layer.key].length) {
      objects[layer.key] = pointsObject(run.maps[layer.key], layer);
      points += run.maps[layer.key].length / 3;
    }
    if (objects[layer.key]) scene.add(objects[layer.key]);
  }
  // Frame the trajectory and the bulk of the map (the median point distance; far points stay out).
  const box = new THREE.Box3().setFromObject(objects.est || scene);
  const center = box.getCenter(new THREE.Vector3());
  const flat = run.maps.static || [];
  const dist = [];
  for (let i = 0; i + 2 < flat.length; i += 3 * Math.max(1, Math.floor(flat.length / 3000)))
    dist.push(Math.hypot(flat[i] - center.x, flat[i + 1] - center.y, flat[i + 2] - center.z));
  dist.sort((a, b) => a - b);
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, dist.length ? dist[dist.length >> 1] : 0, 1);
  const ground = run.est && run.est.z.length ? Math.min(...run.est.z) : box.min.z;
  const { grid, axes, cell } = gridAndAxes(center, radius, ground);
  scene.add(grid, axes);
  if (run.est && run.est.x.length > 0) {
    objects.est_ends = endsObject(run.est, LAYERS.find((l) => l.key === 'est').color);
    scene.add(objects.est_ends);
  }
  const camera = new THREE.PerspectiveCamera(50, width / height, radius / 1000, radius * 40);
  camera.up.set(0, 0, 1);
  camera.position.copy(center).add(new THREE.Vector3(-1.2 * radius, -1.6 * radius, 1.4 * radius));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(center);
  parent.append(Object.assign(document.createElement('p'), {
    className: 'note scale',
    textContent: `grid cells ${cell < 1 ? `${+(cell * 100).toFixed(3)} cm` : `${cell} m`}; axes at the world origin, a cell long (x red, y green, z blue); blue line and dots: the trajectory, its start and end`,
  }));
  const render = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);
  controls.update();
  render();
  return {
    canvas: renderer.domElement,
    layers: Object.keys(objects),
    points,
    cell,
    setLayer(key, on) {
      if (objects[key]) objects[key].visible = on;
      if (key === 'est' && objects.est_ends) objects.est_ends.visible = on;
      render();
    },
    render,
    // Mean ms per frame of `frames` renders while orbiting (each waits for the pixels): how
    // smooth the view is with this many points (bench/report_render.py).
    timeOrbit(frames) {
      const gl = renderer.getContext();
      const pixel = new Uint8Array(4);
      const t0 = performance.now();
      for (let i = 0; i < frames; i++) {
        camera.position.sub(controls.target).applyAxisAngle(camera.up, (2 * Math.PI) / frames).add(controls.target);
        camera.lookAt(controls.target);
        render();
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      }
      return (performance.now() - t0) / frames;
    },
  };
}
