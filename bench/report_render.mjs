// Opens a report page in Debian's headless Chromium; prints "ms_until_drawn ms_per_orbit_frame"
// (bench/report_render.py).
import { createRequire } from 'node:module';
import { dirname, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const require = createRequire(resolve(dirname(fileURLToPath(import.meta.url)), '../web/package.json'));
const { chromium } = require('playwright-core');
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const t0 = Date.now();
  await page.goto('file://' + resolve(process.argv[2]));
  await page.waitForFunction(() => window.idyReport && window.idyReport.ready, null, { timeout: 300000 });
  const drawn = Date.now() - t0;
  const ms = await page.evaluate(() => window.idyReport.viewers[0].timeOrbit(30));
  console.log(`${drawn} ${ms}`);
} finally {
  await browser.close();
}
