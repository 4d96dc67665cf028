// omma's live page: the panorama in a 360-degree viewer (Pannellum), fed by /stream.mjpg, and the
// engine's stats line. Served by `omma run --sink http:PORT` (src/omma/live/sinks.h).
//
// The MJPEG stream is read with fetch() and split at its parts (each has a Content-Length); every
// JPEG is drawn into a canvas that Pannellum shows as dynamic content, re-uploaded once per new
// frame. For the tests, window.omma holds {frames, viewer, config, shownFps}.
//
// Token: where omma requires one (`--bind` other than loopback, or `--token random`), the page is
// opened as /?token=T and passes T on to every request of its own (the viewer's files need none).
//
// Displayed rate (#shown): the frames this page actually decoded and drew (into the viewer's canvas,
// which Pannellum then uploads, or the flat <img>) per second over the last 2 s, beside the engine's
// rate: lower when the browser cannot keep up (frames are skipped, the newest one wins), 0 paused.
'use strict';
const omma = { frames: 0, viewer: null, config: null, error: null, paused: false, shownFps: 0 };
window.omma = omma;

const token = new URLSearchParams(location.search).get('token');
// `path` with the page's token, if it has one.
function withToken(path) {
  return token ? path + (path.includes('?') ? '&' : '?') + 'token=' + encodeURIComponent(token) : path;
}

// Pause: the image stays as it is (the view can still be turned); the 'p' key or the stats line.
omma.setPaused = (on) => { omma.paused = on; };
document.addEventListener('keydown', (e) => { if (e.key === 'p') omma.setPaused(!omma.paused); });
document.getElementById('bar').addEventListener('click', () => omma.setPaused(!omma.paused));

// The displayed rate: the instants (ms) of the frames shown in the last kShownWindow ms.
const kShownWindow = 2000;
const shownAt = [];
let firstShown = null;
function noteShown() {
  const now = performance.now();
  if (firstShown === null) firstShown = now;
  shownAt.push(now);
  omma.frames++;
}
function updateShownRate() {
  const now = performance.now();
  while (shownAt.length && shownAt[0] <= now - kShownWindow) shownAt.shift();
  // Over the window, or since the first frame while the page is younger than that.
  const span = firstShown === null ? 0 : Math.min(kShownWindow, now - firstShown);
  omma.shownFps = span >= 250 ? shownAt.length / (span / 1000) : 0;
  document.getElementById('shown').textContent = `shown ${omma.shownFps.toFixed(1)} fps`;
}
setInterval(updateShownRate, 500);

// Pannellum's view of each of omma's projections (core/grid.h): the image spans haov x vaov degrees,
// its centre at pitch vOffset.
function viewerConfig(cfg, canvas) {
  const base = { type: 'equirectangular', panorama: canvas, dynamic: true, autoLoad: true,
                 showControls: true, showFullscreenCtrl: true, showZoomCtrl: true, mouseZoom: true,
                 hfov: 100, minHfov: 30, maxHfov: 120, compass: false };
  if (cfg.projection === 'vr180')  // dome axis at the centre: look along it, +-90 degrees around
    return Object.assign(base, { haov: 180, vaov: 180, vOffset: 0, minYaw: -90, maxYaw: 90,
                                 minPitch: -90, maxPitch: 90, yaw: 0, pitch: 0, avoidShowingBackground: true });
  if (cfg.projection === 'equirect')  // 360 x 90: the dome axis (top row) is the zenith
    return Object.assign(base, { haov: 360, vaov: 90, vOffset: 45, minPitch: 0, maxPitch: 90, pitch: 30 });
  return Object.assign(base, { haov: 360, vaov: 180, vOffset: 0 });  // equirect-full
}

function status(text) { document.getElementById('s').textContent = text; }

async function showFrame(canvas, blob) {
  const bitmap = await createImageBitmap(blob);
  canvas.getContext('2d').drawImage(bitmap, 0, 0, canvas.width, canvas.height);
  bitmap.close();
  if (omma.viewer) omma.viewer.setUpdate(false);  // one render: uploads the canvas again
  noteShown();
}

// Reads multipart/x-mixed-replace parts from the stream; calls onJpeg(Uint8Array) for each.
async function readStream(onJpeg) {
  const res = await fetch(withToken('/stream.mjpg'), { cache: 'no-store' });
  if (res.status !== 200) throw new Error((await res.text()) || ('stream: HTTP ' + res.status));
  const reader = res.body.getReader();
  let buf = new Uint8Array(0);
  const dec = new TextDecoder();
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    const joined = new Uint8Array(buf.length + value.length);
    joined.set(buf);
    joined.set(value, buf.length);
    buf = joined;
    for (;;) {  // every complete part in buf
      let headEnd = -1;
      for (let i = 0; i + 3 < buf.length; i++)
        if (buf[i] === 13 && buf[i + 1] === 10 && buf[i + 2] === 13 && buf[i + 3] === 10) { headEnd = i; break; }
      if (headEnd < 0) break;
      const m = /Content-Length:\s*(\d+)/i.exec(dec.decode(buf.subarray(0, headEnd)));
      if (!m) throw new Error('stream: a part without Content-Length');
      const start = headEnd + 4, len = parseInt(m[1], 10);
      if (buf.length < start + len) break;
      onJpeg(buf.slice(start, start + len));
      buf = buf.slice(start + len);
    }
  }
}

async function main() {
  const cfgRes = await fetch(withToken('/config.json'));
  if (cfgRes.status === 403) {
    status('this live view needs its token: open the URL with ?token=... that omma run printed');
    return;
  }
  const cfg = await cfgRes.json();
  omma.config = cfg;
  const canvas = document.createElement('canvas');
  canvas.width = cfg.width;
  canvas.height = cfg.height;
  // A CPU-backed 2D canvas (the first getContext fixes it): Pannellum re-uploads it to WebGL every
  // frame, a plain pixel copy; a GPU-backed canvas made Chromium's GPU process grow by ~70 MB/s
  // with SwiftShader (14 GB in 3.5 minutes of the live benchmark).
  canvas.getContext('2d', { willReadFrequently: true });
  const flat = !window.pannellum;
  let pending = null, busy = false;
  // A hash of the canvas's pixels (tests: the image changed).
  omma.canvasHash = () => {
    const d = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
    let h = 0;
    for (let i = 0; i < d.length; i += 7) h = (h * 31 + d[i]) | 0;
    return h;
  };
  const onJpeg = async (bytes) => {  // newest frame wins while one is being drawn
    if (omma.paused) return;
    pending = bytes;
    if (busy) return;
    busy = true;
    while (pending) {
      const b = pending;
      pending = null;
      try {
        if (flat) {
          const img = document.getElementById('flat');
          const old = img.src;
          img.src = URL.createObjectURL(new Blob([b], { type: 'image/jpeg' }));
          img.style.display = 'block';
          if (old) URL.revokeObjectURL(old);
          await img.decode();
          noteShown();
        } else {
          await showFrame(canvas, new Blob([b], { type: 'image/jpeg' }));
          if (!omma.viewer) omma.viewer = pannellum.viewer('view', viewerConfig(cfg, canvas));
        }
      } catch (e) { omma.error = String(e); }
    }
    busy = false;
  };
  for (;;) {
    try {
      await readStream(onJpeg);
    } catch (e) {
      omma.error = String(e);
      status(String(e.message || e) + ' — showing a still once a second');
      // Too many viewers (503) or the stream broke: one frame a second instead.
      try {
        const r = await fetch(withToken('/frame.jpg'), { cache: 'no-store' });
        if (r.ok) await onJpeg(new Uint8Array(await r.arrayBuffer()));
      } catch (e2) {}
      await new Promise((ok) => setTimeout(ok, 1000));
    }
  }
}

// The stats line: the engine's own figures (/stats.json; latency as defined in docs/guide/live.md);
// the engine's rate is that of its last interval (about 0.5 s), render time its mean so far.
setInterval(async () => {
  try {
    const j = await (await fetch(withToken('/stats.json'), { cache: 'no-store' })).json();
    if (j.frames === undefined) return;
    const fps = (j.window && j.window.fps) || j.fps || 0;
    status(`of engine ${fps.toFixed(1)} fps, ${j.frames} frames, ` +
           `latency ${(j.latency_ms || 0).toFixed(1)} ms, render ${(j.render_ms_mean || 0).toFixed(1)} ms, ` +
           `${j.cameras_live} cameras live at ${(j.window.camera_fps_min || 0).toFixed(1)}+ fps` +
           (omma.paused ? ' — paused (p)' : '') + (omma.error ? ' — ' + omma.error : ''));
  } catch (e) {}
}, 1000);

main();
