// Browser test of `idyvins report` (CTest ReportInBrowser; docs/report.md):
//   node browser_test.mjs PAGE.html RUN_DIR[,RUN_DIR...] SCREENSHOT_PREFIX [--no-gt]
// Opens the page in Debian's headless Chromium (driven by playwright-core from web/node_modules),
// waits for it to draw, and checks: no console errors; each 3D canvas drew non-background pixels;
// switching the dynamic layers off changes them (on the run that has dynamic points); every
// number marked data-stat equals the run's stats.json at the shown precision; with --no-gt the page
// says why it has no ground-truth panels and draws none. Saves full-page and 3D-view screenshots.
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { dirname, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(resolve(here, '../../web/package.json'));
const { chromium } = require('playwright-core');

const [page_path, run_list, shot_prefix, ...flags] = process.argv.slice(2);
const runs = run_list.split(',');
const no_gt = flags.includes('--no-gt');
const failures = [];
const check = (ok, what) => {
  if (!ok) failures.push(what);
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
};

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const console_errors = [];
  page.on('console', (m) => m.type() === 'error' && console_errors.push(m.text()));
  page.on('pageerror', (e) => console_errors.push(String(e)));
  const requests = [];
  page.on('request', (r) => !r.url().startsWith('file:') && !r.url().startsWith('data:') && requests.push(r.url()));
  const t0 = Date.now();
  await page.goto('file://' + resolve(page_path));
  await page.waitForFunction(() => window.idyReport && window.idyReport.ready, null, { timeout: 60000 });
  console.log(`page drawn in ${Date.now() - t0} ms`);
  check(console_errors.length === 0, `no console errors (${console_errors.join(' | ')})`);
  check(requests.length === 0, `no network requests (${requests.join(' ')})`);

  // Canvas pixels: count those that differ from the white background.
  const countPixels = () => page.evaluate(() => window.idyReport.viewers.map((v) => {
    v.render();
    const c = document.createElement('canvas');
    c.width = v.canvas.width;
    c.height = v.canvas.height;
    const ctx = c.getContext('2d');
    ctx.drawImage(v.canvas, 0, 0);
    const px = ctx.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    let orange_red = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (px[i] < 250 || px[i + 1] < 250 || px[i + 2] < 250) n++;
      if (px[i] > 200 && px[i + 1] < 170 && px[i + 2] < 60) orange_red++;
    }
    return { n, orange_red };
  }));
  const before = await countPixels();
  check(before.length === runs.length, `one 3D view per run (${before.length})`);
  before.forEach((b, i) => check(b.n > 100, `3D view ${i} drew ${b.n} non-background pixels`));
  const dyn = await page.evaluate(() => window.idyReport.data.runs.map((r) => r.maps.eliminated.length + r.maps.confirmed.length));
  for (const key of ['eliminated', 'confirmed']) {
    const box = page.locator(`input[data-layer="${key}"]`);
    if (await box.count()) await box.uncheck();
  }
  const after = await countPixels();
  dyn.forEach((d, i) => {
    if (d > 0) check(after[i].orange_red < before[i].orange_red && after[i].n < before[i].n,
      `run ${i}: dynamic layers off: red/orange pixels ${before[i].orange_red} -> ${after[i].orange_red}, drawn ${before[i].n} -> ${after[i].n}`);
  });
  for (const key of ['eliminated', 'confirmed']) {
    const box = page.locator(`input[data-layer="${key}"]`);
    if (await box.count()) await box.check();
  }

  // Every number the page shows from stats.json matches the file.
  const cells = await page.$$eval('[data-stat]', (es) => es.map((e) => ({ key: e.dataset.stat, digits: +e.dataset.digits, scale: +e.dataset.scale, text: e.textContent })));
  const stats = runs.map((r) => JSON.parse(readFileSync(resolve(r, 'stats.json'), 'utf8')));
  let compared = 0;
  for (const c of cells) {
    const [i, path] = [+c.key.split(':')[0], c.key.split(':')[1]];
    const v = path.split('.').reduce((o, k) => (o == null ? undefined : o[k]), stats[i]);
    if (typeof v !== 'number') {
      check(c.text === '–', `${c.key} absent from stats.json, shown as – ('${c.text}')`);
      continue;
    }
    check(Math.abs(parseFloat(c.text) - v * c.scale) <= 0.51 * 10 ** -c.digits, `${c.key}: shown ${c.text}, stats.json ${v}`);
    compared++;
  }
  check(compared >= 10 * runs.length, `${compared} numbers compared with stats.json`);

  const missing = await page.$$eval('[data-missing="groundtruth"]', (es) => es.map((e) => e.textContent));
  const ate_charts = await page.$$eval('figcaption', (es) => es.filter((e) => e.textContent.startsWith('ATE')).length);
  if (no_gt) {
    check(missing.length === runs.length && missing.every((t) => t.includes('no ground truth')), `says why there is no ground truth: ${missing[0]}`);
    check(ate_charts === 0, `no ATE panels without ground truth (${ate_charts})`);
  } else {
    check(missing.length === 0 && ate_charts === 2, `ground-truth panels drawn (${ate_charts} ATE charts)`);
  }
  // Drawings that follow the motion's size (a 1 cm run is neither a vertical line nor a staircase).
  const tum = readFileSync(resolve(runs[0], 'trajectory.tum'), 'utf8').split('\n')
    .filter((l) => l.trim() && !l.startsWith('#')).map((l) => l.trim().split(/\s+/).map(Number));
  const span = (v) => Math.max(...v) - Math.min(...v);
  const [sx, sy] = [span(tum.map((r) => r[1])), span(tum.map((r) => r[2]))];
  const top = await page.evaluate(() => {
    const line = document.querySelector('svg.topview polyline[stroke="#1f77b4"]');
    const b = line ? line.getBBox() : { width: 0, height: 0 };
    const note = document.querySelector('svg.topview').parentElement.querySelector('[data-span-m]');
    return { w: b.width, h: b.height, note: note ? note.textContent : '', span: note ? +note.dataset.spanM : 0 };
  });
  check(Math.min(top.w, top.h) >= 2, `top view: the estimate spans ${top.w.toFixed(1)} x ${top.h.toFixed(1)} px, not a line`);
  if (no_gt) {  // unaligned: the drawing keeps the file's proportions
    const want = Math.min(sx, sy) / Math.max(sx, sy), got = Math.min(top.w, top.h) / Math.max(top.w, top.h);
    check(Math.abs(got - want) < 0.05 + 0.1 * want, `top view proportions ${got.toFixed(3)} as trajectory.tum's ${want.toFixed(3)}`);
  }
  check(top.span > 0 && !/ 0\.0 m /.test(top.note), `top view scale: '${top.note}'`);
  const distinct = (v) => new Set(v.map((x) => Math.round(x * 1e7))).size;
  const page_z = await page.evaluate(() => window.idyReport.data.runs[0].est.z);
  const file_z = tum.map((r) => r[3]);
  check(distinct(page_z) >= 0.5 * distinct(file_z), `height: ${distinct(page_z)} distinct z values on the page, ${distinct(file_z)} in trajectory.tum`);
  const tracked = await page.$$eval('figcaption', (es) => es.filter((e) => e.textContent.endsWith('features tracked per frame')).length);
  check(tracked === runs.length, `features tracked per frame (all, with a right match, new): ${tracked} charts`);
  const views = await page.evaluate(() => window.idyReport.viewers.map((v) => ({ cell: v.cell, est: v.layers.includes('est'), ends: v.layers.includes('est_ends') })));
  const scales = await page.$$eval('.viewer .scale', (es) => es.map((e) => e.textContent));
  views.forEach((v, i) => check(v.cell > 0 && v.est && v.ends && (scales[i] || '').startsWith('grid cells'),
    `3D view ${i}: grid of ${v.cell} m cells, axes, the trajectory and its ends drawn ('${scales[i]}')`));
  await page.screenshot({ path: `${shot_prefix}page.png`, fullPage: true });
  await page.locator('#summary').screenshot({ path: `${shot_prefix}summary.png` });
  await page.locator('#trajectory').screenshot({ path: `${shot_prefix}trajectory.png` });
  await page.locator('.viewers').screenshot({ path: `${shot_prefix}map.png` });
  const dynamic = page.locator('#dynamic');
  await dynamic.screenshot({ path: `${shot_prefix}dynamic.png` });
} finally {
  await browser.close();
}
if (failures.length) {
  console.log(`${failures.length} check(s) failed`);
  process.exit(1);
}
console.log('all checks passed');
