"""Bad input from Python raises a clear exception and never crashes the interpreter. The same
calls also run in a child interpreter, which must exit normally."""
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import omma
from conftest import random_frames


@pytest.fixture(scope="module")
def eng(rig):
    return omma.Engine(rig, method="nn", size=(64, 64))


def bad_calls(rig, eng):
    good = random_frames(rig)
    f64 = [f.astype(np.float64) for f in good]
    two = [f[:, :, :2] for f in good]
    strided = [np.ascontiguousarray(np.repeat(f, 2, axis=1))[:, ::2] for f in good]
    fortran = [np.asfortranarray(f) for f in good]
    flipped = [f[::-1] for f in good]
    small = [f[:100] for f in good]
    return [
        # (call, exception, text in the message)
        (lambda: eng.render(f64), TypeError, "frames[0] has dtype float64; expected uint8, uint16, float32"),
        (lambda: eng.render(two), ValueError, "frames[0] has shape (250, 250, 2); expected (H, W, 3)"),
        (lambda: eng.render(strided), ValueError, "not contiguous within its rows; pass numpy.ascontiguousarray"),
        (lambda: eng.render(fortran), ValueError, "not contiguous within its rows"),
        (lambda: eng.render(flipped), ValueError, "not contiguous within its rows"),
        (lambda: eng.render(good[:23]), ValueError, "expected 24 frames (one per rig camera, in rig order), got 23"),
        (lambda: eng.render(good + good[:1]), ValueError, "expected 24 frames"),
        (lambda: eng.render(small), ValueError, "frames[0] is 250x100 (W x H) but camera id 0 is 250x250"),
        (lambda: eng.render([f.tolist() for f in good[:1]] + good[1:]), TypeError,
         "frames[0] must be a numpy.ndarray, got list"),
        (lambda: eng.render("frames"), TypeError, "frames must be a list of numpy arrays"),
        (lambda: eng.render(np.zeros((24, 250, 250, 3, 1), np.uint8)), ValueError, "frames has shape (24, 250, 250, 3, 1)"),
        (lambda: eng.render(good, out=np.zeros((64, 64, 3), np.float32)), TypeError, "out has dtype float32"),
        (lambda: eng.render(good, out=np.zeros((32, 64, 3), np.uint8)), ValueError, "out is 64x32 (W x H)"),
        (lambda: eng.render(good, out=np.zeros((64, 64, 3), np.uint8)[:, ::-1]), ValueError, "not contiguous"),
        (lambda: omma.stitch(rig, f64), TypeError, "dtype float64"),
        (lambda: omma.stitch(rig, good, method="bogus"), ValueError, "unknown method 'bogus'"),
        (lambda: omma.stitch(rig, good, projection="cube"), ValueError, "unknown projection 'cube'"),
        (lambda: omma.stitch(rig, good, size=(0, 10)), ValueError, "size must be (width, height)"),
        (lambda: omma.stitch(rig, good, size="10by10"), ValueError, "size '10by10' must be WxH"),
        (lambda: omma.Engine(rig, method="mrf", size=(64, 64), min_weight=2), ValueError, "min_weight"),
        (lambda: omma.Engine(rig, size=(64, 64), kernel="gpu"), ValueError, "unknown kernel 'gpu'"),
        (lambda: omma.evaluate(good[0], good[1][:10]), ValueError, ""),
        (lambda: omma.evaluate(good[0], good[1], seam=np.zeros((5, 5), np.uint8)), ValueError, "mask is 5x5"),
        (lambda: omma.simulate(rig, scene="nowhere"), omma.SceneError, "nowhere"),
        (lambda: omma.simulate(rig, scene="checker", colour_gain=0.1), TypeError,
         "simulate() got an unexpected keyword argument 'colour_gain'"),
        (lambda: omma.calibrate(rig, good, thread=2), TypeError, "unexpected keyword argument 'thread'"),
        (lambda: omma.Rig.from_json("{"), ValueError, "parse error"),
        (lambda: omma.Rig.from_dict({"format": "omma-rig"}), omma.RigError, ""),
        (lambda: omma.design("spiral"), ValueError, "spiral"),
        # More renderer threads than one arena may hold (crashed the interpreter at exit), panorama
        # sizes past core/limits.h (seam_mask at 65536 x 65536 ran for minutes), a scene of NaN
        # (crashed the simulator's sRGB encoder).
        (lambda: omma.Engine(rig, size=(64, 64), threads=100000), ValueError, "threads must be 0 (all) .. 1024"),
        (lambda: omma.seam_mask(rig, size=(65536, 65536)), ValueError, "out of range"),
        (lambda: omma.coverage_map(rig, size=(100000, 10)), ValueError, "out of range"),
        (lambda: omma.stitch(rig, good, size=(20000, 20000)), ValueError, "out of range"),
        (lambda: omma.simulate(rig, scene="checker", size=(1 << 31, 2)), ValueError, "out of range"),
        # NaN/inf in any float32 image argument is refused where the array is read (arrays.h).
        (lambda: omma.simulate(rig, scene=np.full((32, 64, 3), np.nan, np.float32)), ValueError,
         "scene holds 6144 NaN or infinite value"),
        (lambda: omma.simulate(rig, scene="flat:1e308"), omma.SceneError, "flat scene"),
    ]


def test_bad_input_raises_clear_exceptions(rig, eng):
    for i, (call, error, text) in enumerate(bad_calls(rig, eng)):
        with pytest.raises(error) as e:
            call()
        assert text in str(e.value), (i, str(e.value))
    # The engine still works afterwards.
    assert eng.render(random_frames(rig)).shape == (64, 64, 3)


def test_bad_input_does_not_crash_the_interpreter():
    script = textwrap.dedent("""
        import sys
        sys.path.insert(0, %r)
        import omma, test_bad_input, conftest
        rig = omma.thesis_prototype_rig()
        eng = omma.Engine(rig, method="nn", size=(64, 64))
        n = 0
        for call, error, text in test_bad_input.bad_calls(rig, eng):
            try:
                call()
            except error:
                n += 1
        print("raised", n)
    """ % str(__import__("pathlib").Path(__file__).parent))
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip() == f"raised {len(bad_calls(omma.thesis_prototype_rig(), None))}"
