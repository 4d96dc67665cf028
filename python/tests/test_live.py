"""The live engine as a Python iterator: omma.run(rig, source=..., sinks=[...]). The panoramas are
compared with omma.Engine's, the video read back by ffprobe."""
import json
import shutil
import subprocess

import numpy as np
import pytest

import omma
from conftest import SIZE


def ffprobe_frames(path):
    out = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                          "stream=nb_read_frames,width,height", "-of", "json", str(path)],
                         check=True, capture_output=True, text=True).stdout
    s = json.loads(out)["streams"][0]
    return int(s["nb_read_frames"]), s["width"], s["height"]


@pytest.mark.skipif(shutil.which("ffprobe") is None, reason="ffprobe not installed")
def test_run_yields_panoramas_and_feeds_the_sinks(rig, frames, frames_dir, tmp_path):
    video, pngs = tmp_path / "out.mp4", tmp_path / "png"
    live = omma.run(rig, source=f"frames:{frames_dir}", frames=5, size=SIZE, fps=60, source_fps=60,
                    sinks=[video, f"png:{pngs}"], cache_dir=False, photometric=False)
    panos = [p.copy() for p in live]
    assert len(panos) == 5 and live.index == 4
    assert all(p.dtype == np.uint8 and p.shape == (SIZE[1], SIZE[0], 3) for p in panos)
    # The same stills through the same map: omma.Engine's panorama, pixel for pixel.
    ref = omma.Engine(rig, method="linear", size=SIZE).render(frames)
    assert omma.psnr(panos[-1], ref) == float("inf"), live.summary
    s = live.summary
    assert s["frames"] == 5 and s["cameras_live"] == len(rig) and s["sinks"] == [str(video), f"png:{pngs}"]
    assert s["fps"] > 0 and s["latency_ms"] > 0
    assert ffprobe_frames(video) == (5, SIZE[0], SIZE[1])
    assert len(list(pngs.glob("frame_*.png"))) == 5
    np.testing.assert_array_equal(omma.read_image(sorted(pngs.glob("frame_*.png"))[-1]), panos[-1])


@pytest.mark.skipif(shutil.which("ffprobe") is None, reason="ffprobe not installed")
def test_leaving_the_loop_stops_the_engine_and_finishes_the_video(rig, frames_dir, tmp_path):
    video = tmp_path / "early.mp4"
    with omma.run(rig, source=f"frames:{frames_dir}", size=SIZE, fps=60, source_fps=60, sinks=[video],
                  cache_dir=False) as live:  # no frame or time limit: runs until stopped
        for i, _ in enumerate(live):
            if i == 2:
                break
    s = live.summary
    # Rendered ahead of the loop: at most the queue (2) and the one waiting to enter it.
    assert s is not None and 3 <= s["frames"] <= 3 + 2 + 1, s
    assert ffprobe_frames(video)[0] == s["frames"]  # finished: playable, every frame in it
    with pytest.raises(StopIteration):
        next(live)


def test_run_errors(rig, frames_dir, tmp_path):
    with pytest.raises(omma.SourceError):
        omma.run(rig, source=str(tmp_path / "nothing.mp4"), frames=1, size=SIZE)
    with pytest.raises(omma.SinkError):
        omma.run(rig, source=f"frames:{frames_dir}", frames=1, size=SIZE,
                 sinks=[tmp_path / "missing" / "deeper" / "file.xyz"])
    with pytest.raises(ValueError, match="unknown method"):
        omma.run(rig, source=f"frames:{frames_dir}", method="blend", size=SIZE)


CTRL_C = r"""
import json, os, signal, sys, threading, time
import omma
rig, src, out = omma.thesis_prototype_rig(), sys.argv[1], sys.argv[2]
result = {}
def interrupt_after(seconds):
    threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
interrupt_after(0.8)
t0 = time.monotonic()
try:
    omma.record(rig, src, out + "/rec", duration=60, fps=30)
except KeyboardInterrupt:
    result["record_s"] = time.monotonic() - t0
rec = omma.Recording(out + "/rec")
result["record_complete"], result["record_sets"] = rec.complete, len(rec)
live = omma.run(rig, source=src, size=(270, 270), source_fps=2, fps=0, sinks=[out + "/live.mp4"], cache_dir=False)
n = 0
interrupt_after(0.8)
t0 = time.monotonic()
try:
    for pano in live:  # 2 frames/s: waiting for the next one when Ctrl-C comes
        n += 1
except KeyboardInterrupt:
    result["run_s"] = time.monotonic() - t0
result["run_frames"], result["summary_frames"] = n, live.summary["frames"]
print(json.dumps(result))
"""


def test_ctrl_c_stops_record_and_run_cleanly(frames_dir, tmp_path):
    import subprocess
    import sys
    r = subprocess.run([sys.executable, "-c", CTRL_C, f"frames:{frames_dir}", str(tmp_path)], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout.splitlines()[-1])
    assert 0.7 < res["record_s"] < 5 and res["record_complete"] and res["record_sets"] >= 5
    assert 0.7 < res["run_s"] < 5 and res["run_frames"] >= 1 and res["summary_frames"] >= res["run_frames"]
    if shutil.which("ffprobe"):
        assert ffprobe_frames(tmp_path / "live.mp4")[0] == res["summary_frames"]  # finished, playable
