// Drives headless Chromium (playwright-core from web/node_modules, the system's /usr/bin/chromium)
// through omma's live page; called by tests/cli/engine_cli_test.cc, which checks the screenshots.
//   node live_viewer.cjs URL OUT_DIR WEB_DIR
// URL is the page's, with its ?token=... where omma requires one. Writes
// OUT_DIR/{loaded,later,paused,paused2,dragged}.png and prints one JSON object on stdout; `rate`
// (after 2.5 s of frames) and `rate_paused` (2 s into the pause) hold the page's displayed-rate
// element (#shown) beside the engine's figures of the same moment (/stats.json, as the page asks).
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
    // The displayed rate as the page shows it, and the engine's at the same moment.
    const rate = () => page.evaluate(async () => {
      const shown = document.getElementById('shown').textContent;
      const j = await (await fetch('/stats.json' + location.search, { cache: 'no-store' })).json();
      return { shown, engine_fps: j.window ? j.window.fps : null, engine_fps_mean: j.fps,
               render_ms: j.render_ms_mean, frames: window.omma.frames };
    });
    await page.waitForFunction(() => window.omma && window.omma.viewer && window.omma.viewer.isLoaded() &&
                               window.omma.frames >= 2, null, { timeout: 40000 });
    await page.waitForTimeout(300);
    result.loaded = await state();
    await page.screenshot({ path: path.join(outDir, 'loaded.png') });
    // New frames arrive and the image changes (the test's scene turns).
    const f0 = result.loaded.frames;
    await page.waitForFunction((f) => window.omma.frames >= f + 5, f0, { timeout: 20000 });
    await page.waitForTimeout(300);
    // The stats line polls /stats.json once a second: on a loaded machine frames can arrive before
    // its first answer. Wait for it (the test then checks what it says).
    await page.waitForFunction(() => document.getElementById('s').textContent.includes('latency'), null,
                               { timeout: 10000 }).catch(() => {});
    result.later = await state();
    await page.screenshot({ path: path.join(outDir, 'later.png') });
    // A full window (2 s) of the displayed rate.
    await page.waitForTimeout(2500);
    result.rate = await rate();
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
    // Paused for over 2 s: nothing is shown any more, the engine goes on.
    await page.waitForTimeout(1500);
    result.rate_paused = await rate();
  } catch (e) {
    result.failure = String(e);
  } finally {
    await browser.close();
  }
  process.stdout.write(JSON.stringify(result) + '\n');
})();
