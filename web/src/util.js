// Small DOM and number helpers of the report page.

export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k === 'text') e.textContent = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}

// Value at a dotted path ("summary.classification.f1") of an object, or undefined.
export function at(obj, path) {
  return path.split('.').reduce((o, k) => (o === null || o === undefined ? undefined : o[k]), obj);
}

// A number as shown on the page; `digits` decimals, "–" when absent.
export function fmt(v, digits = 3) {
  if (v === null || v === undefined || typeof v !== 'number' || !isFinite(v)) return '–';
  return v.toFixed(digits);
}

// A length with a unit that suits it: "0.4 mm", "1.2 cm", "3.5 m", "1.2 km" (two significant digits at least).
export function fmtLength(m) {
  if (typeof m !== 'number' || !isFinite(m)) return '–';
  const a = Math.abs(m);
  const [v, unit] = a < 0.01 ? [m * 1000, 'mm'] : a < 1 ? [m * 100, 'cm'] : a < 1000 ? [m, 'm'] : [m / 1000, 'km'];
  return `${Math.abs(v) < 10 ? v.toFixed(1) : v.toFixed(0)} ${unit}`;
}

// Decimals that show a value to about three significant digits (at least `min`).
export function decimalsFor(v, min = 1) {
  if (typeof v !== 'number' || !isFinite(v) || v === 0) return min;
  return Math.max(min, Math.min(7, 2 - Math.floor(Math.log10(Math.abs(v)))));
}

// A cell showing stats.json's value at `path` of run `i`: data-stat lets the browser test compare
// the text with the file, data-scale the unit change (0.01 for percentages shown ×100).
export function statCell(run, i, path, digits = 3, scale = 1) {
  const v = at(run, path);
  const shown = typeof v === 'number' ? v * scale : v;
  return el('td', { 'data-stat': `${i}:${path}`, 'data-digits': digits, 'data-scale': scale, text: fmt(shown, digits) });
}

// erf (Abramowitz and Stegun 7.1.26, |error| < 1.5e-7), for the chi-square(1) bins.
export function erf(x) {
  const s = Math.sign(x);
  const a = Math.abs(x);
  const t = 1 / (1 + 0.3275911 * a);
  const y = 1 - ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t * Math.exp(-a * a);
  return s * y;
}

// P(a <= X < b) for X ~ chi-square with one degree of freedom.
export function chi2Bin(a, b) {
  const cdf = (v) => (v <= 0 ? 0 : erf(Math.sqrt(v / 2)));
  return (b === Infinity ? 1 : cdf(b)) - cdf(a);
}

export const RUN_COLORS = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#8c564b', '#e377c2'];
