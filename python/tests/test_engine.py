"""omma.Engine: the compiled map rendered from Python, against the reference stitcher, with the
output written in place and the GIL released while rendering."""
import sys
import threading
import time

import numpy as np
import pytest

import omma
from conftest import SIZE, random_frames


@pytest.fixture(scope="module")
def engines(rig):
    return {m: omma.Engine(rig, method=m, size=SIZE) for m in ("nn", "mrf", "sad")}


@pytest.mark.parametrize("method", ["nn", "mrf", "sad"])
def test_render_matches_the_reference_stitch(rig, frames, engines, method):
    eng = engines[method]
    assert (eng.width, eng.height, eng.method, eng.projection) == (SIZE[0], SIZE[1], method, "vr180")
    fast = eng.render(frames)
    assert fast.dtype == np.uint8 and fast.shape == (SIZE[1], SIZE[0], 3)
    ref = omma.to_u8(omma.stitch(rig, frames, method=method, size=SIZE))
    # The engine quantises weights to 1/128 and drops faint mrf taps (min_weight 1/20); measured on
    # seeds 1-3: nn 68 dB, mrf 56-57 dB, sad 66 dB from the reference stitch.
    assert omma.psnr(fast, ref) > 50


def test_render_into_out_and_from_stored_frames(rig, frames, engines):
    eng = engines["mrf"]
    first = eng.render(frames)
    out = np.zeros((SIZE[1], SIZE[0], 3), np.uint8)
    back = eng.render(frames, out=out)
    assert back is out and np.array_equal(out, first)
    video = np.zeros((3, SIZE[1], SIZE[0], 3), np.uint8)  # recording into one preallocated array
    eng.render(frames, out=video[1])
    assert np.array_equal(video[1], first) and not video[0].any() and not video[2].any()
    assert np.array_equal(eng.render(), first)  # the frames stay in the engine's store
    other = random_frames(rig, seed=5)
    eng.set_frames(other)
    assert not np.array_equal(eng.render(), first)
    assert np.array_equal(eng.render(np.stack(frames)), first)  # (N, H, W, 3) in one array


def test_engine_without_frames_raises(rig):
    eng = omma.Engine(rig, method="nn", size=(64, 64))
    with pytest.raises(ValueError, match="no frames yet"):
        eng.render()


def test_map_cache(rig, frames, tmp_path):
    a = omma.Engine(rig, method="linear", size=(128, 64), projection="equirect", cache_dir=str(tmp_path))
    b = omma.Engine(rig, method="linear", size=(128, 64), projection="equirect", cache_dir=str(tmp_path))
    assert not a.map_from_cache and b.map_from_cache
    assert np.array_equal(a.render(frames), b.render(frames))


def test_kernels_agree(rig, frames):
    """The scalar and the fastest kernel give the same bytes through the bindings too."""
    fast = omma.Engine(rig, method="mrf", size=(96, 96))
    scalar = omma.Engine(rig, method="mrf", size=(96, 96), kernel="scalar", threads=1)
    assert scalar.kernel == "scalar"
    assert np.array_equal(fast.render(frames), scalar.render(frames))


def test_render_releases_the_gil(rig, frames):
    """While one thread is inside render(), another runs Python code. The switch interval is made
    huge, so a render holding the GIL would let the main thread count nothing until it ends."""
    eng = omma.Engine(rig, method="mrf", size=(540, 540), kernel="scalar", threads=1)
    eng.set_frames(frames)
    counter = [0]
    seen = []
    done = threading.Event()

    def worker():
        for _ in range(20):  # renders until the main thread was seen running during one
            before = counter[0]
            eng.render()
            seen.append(counter[0] - before)
            if seen[-1] > 0:
                break
        done.set()

    old = sys.getswitchinterval()
    sys.setswitchinterval(30)
    try:
        t = threading.Thread(target=worker)
        t.start()
        while not done.is_set():
            counter[0] += 1
            time.sleep(0)  # hands the GIL back whenever the worker wants it
        t.join()
    finally:
        sys.setswitchinterval(old)
    assert max(seen) > 0, seen


def test_concurrent_renders_are_serialised(rig, frames):
    eng = omma.Engine(rig, method="nn", size=(200, 100), projection="equirect")
    expected = eng.render(frames)
    results = []
    threads = [threading.Thread(target=lambda: results.append(eng.render(frames))) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(results) == 4 and all(np.array_equal(r, expected) for r in results)
