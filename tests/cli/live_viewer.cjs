// Drives headless Chromium (playwright-core from web/node_modules, the system's /usr/bin/chromium)
// through omma's live page; called by tests/cli/engine_cli_test.cc, which checks the screenshots.
//   node live_viewer.cjs URL OUT_DIR WEB_DIR
// Writes OUT_DIR/{loaded,later,paused,paused2,dragged}.png and prints one JSON object on stdout.
'use strict';
const path = require('path');
const [url, outDir, webDir] = process.argv.slice(2);
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
    const page = await browser.newPage({ viewport: { width: 480, height: 360 } });
    page.on('console', (m) => { if (m.type() === 'error') (result.console = result.console || []).push(m.text()); });
    await page.goto(url);
    const state = () => page.evaluate(() => ({
      frames: window.omma.frames, error: window.omma.error,
      loaded: !!(window.omma.viewer && window.omma.viewer.isLoaded()),
      yaw: window.omma.viewer ? window.omma.viewer.getYaw() : null,
      pitch: window.omma.viewer ? window.omma.viewer.getPitch() : null,
      canvas: window.omma.canvasHash ? window.omma.canvasHash() : null,
      stats: document.getElementById('s').textContent }));
    await page.waitForFunction(() => window.omma && window.omma.viewer && window.omma.viewer.isLoaded() &&
                               window.omma.frames >= 2, null, { timeout: 40000 });
    await page.waitForTimeout(300);
    result.loaded = await state();
    await page.screenshot({ path: path.join(outDir, 'loaded.png') });
    // New frames arrive and the image changes (the test's scene turns).
    const f0 = result.loaded.frames;
    await page.waitForFunction((f) => window.omma.frames >= f + 5, f0, { timeout: 20000 });
    await page.waitForTimeout(300);
    result.later = await state();
    await page.screenshot({ path: path.join(outDir, 'later.png') });
    // Freeze the live image (the page's pause), then drag: only the view changes.
    await page.evaluate(() => window.omma.setPaused(true));
    await page.waitForTimeout(300);
    await page.screenshot({ path: path.join(outDir, 'paused.png') });
    await page.waitForTimeout(300);
    await page.screenshot({ path: path.join(outDir, 'paused2.png') });
    result.paused = await state();
    await page.mouse.move(300, 150);
    await page.mouse.down();
    await page.mouse.move(150, 190, { steps: 12 });
    await page.mouse.up();
    await page.waitForTimeout(800);
    result.dragged = await state();
    await page.screenshot({ path: path.join(outDir, 'dragged.png') });
  } catch (e) {
    result.failure = String(e);
  } finally {
    await browser.close();
  }
  process.stdout.write(JSON.stringify(result) + '\n');
})();
