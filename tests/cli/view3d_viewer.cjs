// Drives headless Chromium (playwright-core from web/node_modules, the system's /usr/bin/chromium)
// through the page of `omma view3d`, opened from file:// (no server, no network); called by
// tests/cli/view3d_test.cc, which checks the screenshots.
//   node view3d_viewer.cjs PAGE.html OUT_DIR WEB_DIR
// Writes OUT_DIR/{loaded,again,dragged,zoomed}.png (the canvas alone) and prints one JSON object on
// stdout: the page's window.omma3d at each step ({ready, points, bounds, renders, camera, error}), the
// console's errors, and `failure` if a step did not happen.
'use strict';
const path = require('path');
const [page_file, outDir, webDir] = process.argv.slice(2);
const { chromium } = require(path.join(webDir, 'node_modules', 'playwright-core'));

(async () => {
  const result = {};
  // WebGL in headless Chromium without a GPU: ANGLE on SwiftShader (software).
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--ignore-gpu-blocklist'],
  });
  try {
    const context = await browser.newContext({ viewport: { width: 480, height: 360 } });
    // Nothing may come from the network: the page is self-contained.
    result.requests = [];
    await context.route(/^(?!file:|blob:|data:)/, (route) => {
      result.requests.push(route.request().url());
      route.abort();
    });
    const page = await context.newPage();
    page.on('console', (m) => { if (m.type() === 'error') (result.console = result.console || []).push(m.text()); });
    page.on('pageerror', (e) => (result.console = result.console || []).push(String(e)));
    await page.goto('file://' + path.resolve(page_file));
    const state = () => page.evaluate(() => Object.assign({}, window.omma3d));
    await page.waitForFunction(() => window.omma3d && (window.omma3d.ready || window.omma3d.error), null,
                               { timeout: 40000 });
    await page.waitForTimeout(300);
    const canvas = await page.$('#view canvas');
    result.loaded = await state();
    await canvas.screenshot({ path: path.join(outDir, 'loaded.png') });
    await page.waitForTimeout(300);
    await canvas.screenshot({ path: path.join(outDir, 'again.png') });  // nothing moves on its own
    const box = await canvas.boundingBox();
    result.canvas = box;
    // Left drag across the canvas: OrbitControls turns the view around the cloud's centre.
    const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
    await page.mouse.move(cx - 80, cy);
    await page.mouse.down();
    await page.mouse.move(cx + 60, cy + 30, { steps: 12 });
    await page.mouse.up();
    await page.waitForTimeout(300);
    result.dragged = await state();
    await canvas.screenshot({ path: path.join(outDir, 'dragged.png') });
    // The wheel zooms in.
    await page.mouse.move(cx, cy);
    await page.mouse.wheel(0, -400);
    await page.waitForTimeout(300);
    result.zoomed = await state();
    await canvas.screenshot({ path: path.join(outDir, 'zoomed.png') });
  } catch (e) {
    result.failure = String(e);
  } finally {
    await browser.close();
  }
  process.stdout.write(JSON.stringify(result) + '\n');
})();
