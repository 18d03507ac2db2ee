// idyvins report: the page `idyvins report` writes. Reads the JSON the command inlines
// (element #idy-data, see apps/idyvins/report_data.cpp) and draws every panel; window.idyReport
// exposes the viewers and a `ready` flag to the browser test (tests/report/browser_test.mjs).
import 'uplot/dist/uPlot.min.css';
import './report.css';
import { el, fmt, statCell, chi2Bin, decimalsFor, RUN_COLORS } from './util.js';
import { lineChart, topView } from './charts.js';
import { createViewer, LAYERS } from './map3d.js';

const data = JSON.parse(document.getElementById('idy-data').textContent);
const runs = data.runs;
const app = document.getElementById('app');
window.idyReport = { data, viewers: [], ready: false, errors: [] };

const color = (i) => RUN_COLORS[i % RUN_COLORS.length];

function section(title, id, ...intro) {
  const s = el('section', { id }, el('h2', { text: title }), ...intro);
  app.append(s);
  return s;
}

// Initialization (green) and resets (red) of every run, as chart marks in seconds.
function marks() {
  const out = [];
  runs.forEach((r) => {
    if (r.summary.initialized_at_s >= 0) out.push({ x: r.summary.initialized_at_s, color: '#2ca02c' });
    for (const e of r.summary.resets || []) out.push({ x: (e.t_ns - r.summary.first_t_ns) / 1e9, color: '#d62728' });
  });
  return out;
}

function header() {
  const commits = [...new Set(runs.map((r) => (r.summary.build && r.summary.build.commit) || 'unknown'))];
  app.append(
    el('header', {},
      el('h1', { text: `idyvins report: ${runs.map((r) => r.name).join(' vs ')}` }),
      el('p', { class: 'note', text: `${runs.length} run${runs.length > 1 ? 's' : ''} of one sequence (${fmt(runs[0].summary.sequence_s, 1)} s, ${runs[0].summary.frames} frames); built from commit ${commits.join(', ')}. Marks on time plots: green dashed = initialization, red dashed = reset.` }),
      el('nav', {}, ...['summary', 'trajectory', 'map', 'dynamic', 'timing', 'reproduce'].map((id) => el('a', { href: `#${id}`, text: id })))));
}

function summaryTable() {
  const rows = [
    ['mode', 'summary.mode', null],
    ['ATE RMSE (m, SE(3)-aligned)', 'summary.ate_rmse_m', 3],
    ['ATE of trajectory_loop.tum (m)', 'summary.loop_closure.ate_rmse_m', 3],
    ['loops closed', 'summary.loop_closure.loops', 0],
    ['path length (m, ground truth)', 'summary.path_length_m', 1],
    ['estimate: path length (m)', 'summary.estimate_path_length_m', 'auto'],
    ['estimate: duration (s)', 'summary.estimate_duration_s', 2],
    ['frames', 'summary.frames', 0],
    ['resets', 'summary.resets.length', 0],
    ['initialized at (s)', 'summary.initialized_at_s', 2],
    ['real-time factor', 'summary.realtime_factor', 2],
    ['static map points', 'summary.map_static_points', 0],
    ['dynamic map points', 'summary.map_dynamic_points', 0],
    ['moving observations flagged (%)', 'summary.classification.moving_detected_fraction', 1, 100],
    ['static observations flagged (%)', 'summary.classification.static_flagged_fraction', 2, 100],
    ['precision / recall / F1', null, null],
    ['static map points on moving objects (%)', 'summary.classification.static_map_fraction_on_moving', 2, 100],
  ];
  const table = el('table', {}, el('tr', {}, el('th', { text: '' }), ...runs.map((r, i) => el('th', { style: `color:${color(i)}`, text: r.name }))));
  for (const [label, path, digits, scale] of rows) {
    const tr = el('tr', {}, el('th', { text: label }));
    runs.forEach((r, i) => {
      if (path === 'summary.mode') tr.append(el('td', { text: r.summary.mode }));
      else if (path === null) {
        const c = r.summary.classification;
        tr.append(c ? el('td', { text: `${fmt(c.precision)} / ${fmt(c.recall)} / ${fmt(c.f1)}` }) : el('td', { text: '–' }));
      } else if (digits === 'auto') {  // small runs (1 cm of motion) keep their digits
        const vals = runs.map((q) => path.split('.').reduce((o, k) => (o == null ? undefined : o[k]), q));
        tr.append(statCell(r, i, path, decimalsFor(Math.max(...vals.filter((v) => typeof v === 'number')), 1), scale || 1));
      } else tr.append(statCell(r, i, path, digits, scale || 1));
    });
    table.append(tr);
  }
  const s = section('Summary', 'summary', table);
  if (runs.some((r) => !r.summary.classification))
    s.append(el('p', { class: 'note', text: 'Classification needs ground-truth masks (mav0/cam0/mask): runs without them show –.' }));
}

function trajectorySection() {
  const s = section('Trajectory', 'trajectory');
  const withGt = runs.filter((r) => r.gt);
  runs.filter((r) => !r.gt).forEach((r) => s.append(el('p', { class: 'missing', 'data-missing': 'groundtruth', text: `${r.name}: ${r.gt_note}. Shown: the estimate in its own frame; no ATE or RPE panels.` })));
  const grid = el('div', { class: 'grid' });
  s.append(grid);
  const paths = [];
  if (withGt.length) paths.push({ label: 'ground truth', x: withGt[0].gt.x, y: withGt[0].gt.y, color: '#111', width: 2.2 });
  runs.forEach((r, i) => {
    paths.push({ label: r.name, x: r.est.x, y: r.est.y, color: color(i) });
    if (r.loop) paths.push({ label: `${r.name} loop-corrected`, x: r.loop.x, y: r.loop.y, color: color(i), dash: '4 3' });
  });
  topView(grid, withGt.length ? 'Top view, estimates aligned to the ground truth (SE(3))' : 'Top view (odometry frame)', paths);
  // Tracked features of every run (the front end, any mode): all, with a right match, new corners.
  runs.forEach((r, i) => {
    const f = r.frames;
    if (!f.features_right || f.features_right.every((v) => v === null)) return;
    lineChart(grid, `${r.name}: features tracked per frame`, [
      { label: 'tracked', x: f.t, y: f.features, color: color(i), width: 2 },
      { label: 'with a right match', x: f.t, y: f.features_right, color: '#2ca02c' },
      { label: 'new corners', x: f.t, y: f.features_new, color: '#ff7f0e' },
    ], { ylabel: 'features', marks: marks() });
  });
  const height = runs.map((r, i) => ({ label: r.name, x: r.est.t, y: r.est.z, color: color(i) }));
  if (withGt.length) height.unshift({ label: 'ground truth', x: withGt[0].gt.t, y: withGt[0].gt.z, color: '#111' });
  lineChart(grid, 'Height z over time', height, { ylabel: 'z (m)', marks: marks() });
  if (!withGt.length) return;
  lineChart(grid, 'ATE over time', runs.filter((r) => r.ate).map((r) => ({ label: r.name, x: r.ate.t, y: r.ate.err, color: color(runs.indexOf(r)) })), { ylabel: 'position error (m)', marks: marks() });
  runs.filter((r) => r.loop_events && r.ate).forEach((r) => {
    const e = r.loop_events;
    const loopErr = r.loop_ate || null;
    lineChart(grid, `${r.name}: loops closed (purple: when; the odometry's ATE beside)`, [
      { label: 'odometry ATE', x: r.ate.t, y: r.ate.err, color: color(runs.indexOf(r)) },
      ...(loopErr ? [{ label: 'loop-corrected ATE', x: loopErr.t, y: loopErr.err, color: '#9467bd' }] : []),
    ], { ylabel: 'position error (m)', marks: [...marks(), ...e.t.map((t) => ({ x: t, color: '#9467bd55' }))] });
    grid.append(el('p', { class: 'note', text: `${r.name}: ${e.t.length} loops closed${e.t.length ? `, the first at ${fmt(e.t[0], 1)} s (to ${fmt(e.old_t[0], 1)} s), inliers ${Math.min(...e.inliers)}-${Math.max(...e.inliers)}` : ''}.` }));
  });
  lineChart(grid, 'ATE along the path', runs.filter((r) => r.ate).map((r) => ({ label: r.name, x: r.ate.dist, y: r.ate.err, color: color(runs.indexOf(r)) })), { xlabel: 'distance along ground truth (m)', ylabel: 'position error (m)' });
  const rpe = el('table', {}, el('tr', {}, el('th', { text: 'RPE (translation, evo: delta in metres)' }), ...runs.map((r, i) => el('th', { style: `color:${color(i)}`, text: `${r.name}: RMSE / max (m)` }))));
  for (const delta of [1, 5, 10]) {
    rpe.append(el('tr', {}, el('th', { text: `${delta} m` }), ...runs.map((r) => {
      const e = (r.rpe || []).find((x) => x.delta_m === delta);
      return el('td', { text: e ? `${fmt(e.rmse)} / ${fmt(e.max)} (${e.n} pairs)` : '–' });
    })));
  }
  s.append(rpe);
  runs.filter((r) => r.summary.segments).forEach((r) => s.append(el('p', { class: 'note', text: `${r.name}: ATE per segment between resets: ${r.summary.segments.map((g) => fmt(g.ate_rmse_m)).join(', ')} m.` })));
}

function mapSection() {
  const s = section('Map (3D: drag to orbit, wheel to zoom, right-drag to pan)', 'map');
  const toggles = el('div', { class: 'toggles' });
  s.append(toggles);
  const row = el('div', { class: 'viewers' });
  s.append(row);
  const width = runs.length > 1 ? 560 : 900;
  runs.forEach((r, i) => {
    const box = el('figure', { class: 'viewer', style: `width:${width}px` }, el('figcaption', { style: `color:${color(i)}`, text: `${r.name} (${r.summary.mode})` }));
    row.append(box);
    try {
      const v = createViewer(box, r, width, 420);
      window.idyReport.viewers.push(v);
      const m = r.maps;
      box.append(el('p', { class: 'note', text: `${m.points_total} map points${m.stride > 1 ? `, every ${m.stride}th shown` : ''}: ${m.static.length / 3} static (${m.ghosts.length / 3} of them on moving objects), ${m.eliminated.length / 3} eliminated, ${m.confirmed.length / 3} confirmed dynamic${m.static_loop.length ? `, ${m.static_loop.length / 3} loop-corrected static` : ''}.` }));
    } catch (e) {
      box.append(el('p', { class: 'missing', text: `No 3D view: this browser gave no WebGL context (${e.message}).` }));
    }
  });
  for (const layer of LAYERS) {
    if (!window.idyReport.viewers.some((v) => v.layers.includes(layer.key))) continue;
    const box = el('input', { type: 'checkbox', 'data-layer': layer.key });
    box.checked = true;
    box.addEventListener('change', () => window.idyReport.viewers.forEach((v) => v.setLayer(layer.key, box.checked)));
    toggles.append(el('label', { style: `border-color:#${layer.color.toString(16).padStart(6, '0')}` }, box, ` ${layer.label}`));
  }
  if (runs.some((r) => r.summary.mode === 'baseline'))
    s.append(el('p', { class: 'note', text: 'The baseline keeps every landmark in its static map, those on moving vehicles too: the "ghosts" (magenta: static-map points whose track was mostly on moving objects by the ground-truth masks). idy eliminates such features (red) or confirms them dynamic (orange) and keeps them out of its static map.' }));
}

function dynamicSection() {
  const s = section('Dynamic preprocessing', 'dynamic');
  const dyn = runs.filter((r) => r.ds_hist);
  if (!dyn.length) {
    s.append(el('p', { class: 'missing', text: 'No run in idy mode: no motion prior, so no d_s, CV or candidates to show.' }));
    return;
  }
  const grid = el('div', { class: 'grid' });
  s.append(grid);
  const edges = [...Array(21).keys()];
  const series = [];
  dyn.forEach((r) => {
    const total = r.ds_hist.counts.reduce((a, b) => a + b, 0) || 1;
    series.push({ label: `${r.name} all tracked`, x: edges.slice(0, 20).map((e) => e + 0.5), y: r.ds_hist.counts.slice(0, 20).map((c) => c / total), color: color(runs.indexOf(r)), bars: true });
  });
  series.push({ label: 'chi2(1)', x: edges.slice(0, 20).map((e) => e + 0.5), y: edges.slice(0, 20).map((e) => chi2Bin(e, e + 1)), color: '#111', width: 2 });
  lineChart(grid, 'd_s distribution (share per 1 px² bin) against chi2(1)', series, { xlabel: 'd_s (px², normalized)', ylabel: 'share', log: true });
  dyn.forEach((r) => {
    const f = r.frames;
    const sqrt2 = f.t.map(() => Math.SQRT2);
    lineChart(grid, `${r.name}: CV of d_s per frame (Fig. 7)`, [
      { label: 'CV before elimination', x: f.t, y: f.cv_before, color: '#d62728' },
      { label: 'CV after', x: f.t, y: f.cv_after, color: '#1f77b4' },
      { label: '√2', x: f.t, y: sqrt2, color: '#111', dash: [6, 4] },
    ], { ylabel: 'CV', marks: marks() });
    lineChart(grid, `${r.name}: dynamic features per frame`, [
      { label: 'eliminated', x: f.t, y: f.eliminated, color: '#e61e1e' },
      { label: 'new candidates', x: f.t, y: f.candidates, color: '#ff9600' },
      { label: 'confirmed dynamic (window)', x: f.t, y: f.confirmed_dynamic, color: '#8c564b' },
    ], { ylabel: 'count', marks: marks() });
    const over = r.ds_hist.counts[20];
    grid.append(el('p', { class: 'note', text: `${r.name}: ${over} of ${r.ds_hist.counts.reduce((a, b) => a + b, 0)} d_s values above 20 px² (not drawn); chi2(1) puts ${fmt(100 * chi2Bin(20, Infinity), 4)} % there.` }));
  });
}

function timingSection() {
  const s = section('Timing per stage (Table II)', 'timing');
  const stages = [['tracking_ms', 'front end (tracking)', '#1f77b4'], ['filter_ms', 'dynamic filter', '#d62728'], ['optimization_ms', 'optimization', '#2ca02c'], ['marginalization_ms', 'marginalization', '#9467bd']];
  const table = el('table', {}, el('tr', {}, el('th', { text: 'mean per frame (ms)' }), ...runs.map((r, i) => el('th', { style: `color:${color(i)}`, text: r.name }))));
  for (const [key, label] of stages) table.append(el('tr', {}, el('th', { text: label }), ...runs.map((r, i) => statCell(r, i, `summary.mean_${key}`, 2))));
  table.append(el('tr', {}, el('th', { text: 'real-time factor (sequence s / wall s)' }), ...runs.map((r, i) => statCell(r, i, 'summary.realtime_factor', 2))));
  s.append(table, el('p', { class: 'note', text: 'Machine-dependent: the figures of the machine and load the run had.' }));
  const grid = el('div', { class: 'grid' });
  s.append(grid);
  runs.forEach((r) => lineChart(grid, `${r.name}: time per frame`, stages.map(([key, label, c]) => ({ label, x: r.frames.t, y: r.frames[key], color: c })), { ylabel: 'ms', marks: marks() }));
}

function reproduceSection() {
  const s = section('Reproduce', 'reproduce');
  runs.forEach((r) => {
    s.append(el('h3', { text: r.name }));
    if (!r.run) {
      s.append(el('p', { class: 'missing', text: r.run_note }));
      return;
    }
    s.append(el('pre', { class: 'command', text: `cd ${r.run.cwd}\n${r.run.command}` }));
    for (const f of r.run.config_files) s.append(el('details', {}, el('summary', { text: f.path }), el('pre', { text: f.text })));
  });
}

try {
  header();
  summaryTable();
  trajectorySection();
  mapSection();
  dynamicSection();
  timingSection();
  reproduceSection();
} catch (e) {
  app.append(el('p', { class: 'missing', text: `The page failed to draw: ${e.message}` }));
  throw e;
} finally {
  window.idyReport.ready = true;
}
