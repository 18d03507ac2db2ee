// Time-series and histogram charts (uPlot), and the SVG top view.
import uPlot from 'uplot';
import { el, fmtLength } from './util.js';

// Vertical marks (initialization, resets) drawn over a chart: [{x, color, label}].
function marksPlugin(marks) {
  return {
    hooks: {
      draw: [
        (u) => {
          const ctx = u.ctx;
          ctx.save();
          for (const m of marks) {
            const x = u.valToPos(m.x, 'x', true);
            if (!isFinite(x) || x < u.bbox.left || x > u.bbox.left + u.bbox.width) continue;
            ctx.strokeStyle = m.color;
            ctx.setLineDash([5, 4]);
            ctx.lineWidth = 1.5 * devicePixelRatio;
            ctx.beginPath();
            ctx.moveTo(x, u.bbox.top);
            ctx.lineTo(x, u.bbox.top + u.bbox.height);
            ctx.stroke();
          }
          ctx.restore();
        },
      ],
    },
  };
}

// One chart of several series, each with its own x values (joined by uPlot.join).
// series: [{label, x: [], y: [], color, dash, bars}]; opts: {xlabel, ylabel, log, marks, width}.
export function lineChart(parent, title, series, opts = {}) {
  const box = el('figure', { class: 'chart' }, el('figcaption', { text: title }));
  parent.append(box);
  const usable = series.filter((s) => s.x.length > 0);
  if (usable.length === 0) {
    box.append(el('p', { class: 'note', text: 'no data' }));
    return null;
  }
  const tables = usable.map((s) => [s.x, s.y.map((v) => (opts.log && !(v > 0) ? null : v))]);
  const joined = tables.length === 1 ? tables[0] : uPlot.join(tables);
  const width = opts.width || Math.min(560, Math.max(320, parent.clientWidth - 24));
  const u = new uPlot(
    {
      width,
      height: opts.height || 220,
      plugins: opts.marks ? [marksPlugin(opts.marks)] : [],
      scales: { x: { time: false }, y: opts.log ? { distr: 3 } : {} },
      axes: [{ label: opts.xlabel || 't (s)' }, { label: opts.ylabel || '', size: 60 }],
      series: [
        { label: opts.xlabel || 't (s)' },
        ...usable.map((s) => ({
          label: s.label,
          stroke: s.color,
          width: s.width || 1.2,
          dash: s.dash,
          spanGaps: true,
          points: { show: false },
          fill: s.bars ? s.color + '55' : undefined,
          paths: s.bars ? uPlot.paths.bars({ size: [0.9, 40] }) : undefined,
        })),
      ],
    },
    joined,
    box,
  );
  return u;
}

// Top view (x, y) with equal axes: [{label, x: [], y: [], color, width}].
export function topView(parent, title, paths, size = 420) {
  const box = el('figure', { class: 'chart' }, el('figcaption', { text: title }));
  parent.append(box);
  let lo = [Infinity, Infinity];
  let hi = [-Infinity, -Infinity];
  for (const p of paths)
    for (let i = 0; i < p.x.length; i++) {
      lo = [Math.min(lo[0], p.x[i]), Math.min(lo[1], p.y[i])];
      hi = [Math.max(hi[0], p.x[i]), Math.max(hi[1], p.y[i])];
    }
  const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], 1e-6) * 1.08;
  const cx = (lo[0] + hi[0]) / 2;
  const cy = (lo[1] + hi[1]) / 2;
  const px = (x) => ((x - cx) / span + 0.5) * size;
  const py = (y) => (0.5 - (y - cy) / span) * size;
  const ns = 'http://www.w3.org/2000/svg';
  const svg = document.createElementNS(ns, 'svg');
  svg.setAttribute('viewBox', `0 0 ${size} ${size}`);
  svg.setAttribute('width', size);
  svg.setAttribute('height', size);
  svg.setAttribute('class', 'topview');
  for (const p of paths) {
    const line = document.createElementNS(ns, 'polyline');
    const pts = [];
    const step = Math.max(1, Math.floor(p.x.length / 4000));
    for (let i = 0; i < p.x.length; i += step) pts.push(`${px(p.x[i]).toFixed(1)},${py(p.y[i]).toFixed(1)}`);
    line.setAttribute('points', pts.join(' '));
    line.setAttribute('fill', 'none');
    line.setAttribute('stroke', p.color);
    line.setAttribute('stroke-width', p.width || 1.5);
    if (p.dash) line.setAttribute('stroke-dasharray', p.dash);
    svg.append(line);
  }
  const scale = el('div', { class: 'note', 'data-span-m': span, text: `x → right, y → up; the square is ${fmtLength(span)} wide` });
  const legend = el('div', { class: 'legend' }, ...paths.map((p) => el('span', { style: `color:${p.color}`, text: `— ${p.label} ` })));
  box.append(svg, legend, scale);
  return svg;
}
