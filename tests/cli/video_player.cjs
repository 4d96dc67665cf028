// Plays video files in headless Chromium's <video> element (playwright-core from web/node_modules,
// the system's /usr/bin/chromium); called by tests/cli/video_cli_test.cc.
//   node video_player.cjs WEB_DIR VIDEO...
// Prints one JSON object on stdout: for each video (by file name) whether it played: readyState,
// duration, videoWidth/Height, the currentTime reached while playing, the mean RGB of a decoded
// frame drawn to a canvas, or the media error.
'use strict';
const fs = require('fs');
const os = require('os');
const path = require('path');
const [webDir, ...videos] = process.argv.slice(2);
const { chromium } = require(path.join(webDir, 'node_modules', 'playwright-core'));

(async () => {
  const result = {};
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--autoplay-policy=no-user-gesture-required',
           '--allow-file-access-from-files'],
  });
  try {
    const page = await browser.newPage();
    for (const video of videos) {
      // A page beside the video, so that file:// may load it.
      const html = path.join(path.dirname(video), 'play-' + path.basename(video) + '.html');
      fs.writeFileSync(html, `<!doctype html><video id="v" muted playsinline src="${path.basename(video)}"></video>` +
                                 '<canvas id="c"></canvas>');
      await page.goto('file://' + html);
      const r = await page.evaluate(async () => {
        const v = document.getElementById('v');
        const ready = await new Promise((resolve) => {
          if (v.readyState >= 2) return resolve(true);
          v.addEventListener('loadeddata', () => resolve(true));
          v.addEventListener('error', () => resolve(false));
          setTimeout(() => resolve(false), 15000);
        });
        const out = { readyState: v.readyState, duration: v.duration, width: v.videoWidth, height: v.videoHeight,
                      error: v.error ? v.error.code + ' ' + v.error.message : null };
        if (!ready) return out;
        try {
          await v.play();
        } catch (e) {
          out.playError = String(e);
        }
        const t0 = performance.now();
        while (v.currentTime < 0.3 && !v.ended && performance.now() - t0 < 10000)
          await new Promise((r) => setTimeout(r, 50));
        v.pause();
        out.currentTime = v.currentTime;
        const c = document.getElementById('c');
        c.width = v.videoWidth;
        c.height = v.videoHeight;
        const g = c.getContext('2d');
        g.drawImage(v, 0, 0);
        const d = g.getImageData(0, 0, c.width, c.height).data;
        const mean = [0, 0, 0];
        for (let i = 0; i < d.length; i += 4) for (let k = 0; k < 3; ++k) mean[k] += d[i + k];
        out.meanRGB = mean.map((m) => m / (d.length / 4));
        return out;
      });
      result[path.basename(video)] = r;
      fs.unlinkSync(html);
    }
  } catch (e) {
    result.failure = String(e);
  } finally {
    await browser.close();
  }
  process.stdout.write(JSON.stringify(result) + '\n');
})();
