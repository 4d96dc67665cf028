"""float32 images outside [0, 1] are clipped where they are used: every image argument warns
(RuntimeWarning with the count, minimum and maximum); NaN and infinity are refused (ValueError)."""
import warnings

import numpy as np
import pytest

import omma
from conftest import SIZE


def float_frames(frames):
    return [f.astype(np.float32) / 255 for f in frames]


def test_out_of_range_float_frames_warn_with_counts(rig, frames):
    f = float_frames(frames)
    f[3] = f[3].copy()
    f[3][0, :10] = 1.5    # 30 values above 1
    f[3][1, :2, 0] = -0.25  # 2 below 0
    with pytest.warns(RuntimeWarning) as rec:
        omma.Engine(rig, method="nn", size=SIZE).render(f)
    msgs = [str(w.message) for w in rec]
    assert msgs == ["frames[3]: 32 of 187500 float32 values outside [0, 1] (2 below 0, min -0.25; 30 above 1, "
                    "max 1.5) are clipped to [0, 1]"]
    assert rec[0].filename == __file__  # points at the caller's line
    # In range: silent.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        omma.Engine(rig, method="nn", size=SIZE).render(float_frames(frames))
        omma.to_u8(np.ones((4, 4, 3), np.float32))
    # Clipped: the same panorama as the frames clipped by NumPy.
    engine = omma.Engine(rig, method="nn", size=SIZE)
    with pytest.warns(RuntimeWarning):
        a = engine.render(f).copy()
    b = engine.render([np.clip(x, 0, 1) for x in f])
    np.testing.assert_array_equal(a, b)


def test_warning_can_be_an_error(rig):
    img = np.full((8, 8, 3), 2.0, np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(RuntimeWarning, match="image: 192 of 192 float32 values outside"):
            omma.to_u8(img)


def test_nan_and_inf_are_refused(rig, frames):
    f = float_frames(frames)
    f[0] = f[0].copy()
    f[0][5, 5] = np.nan
    f[0][6, 6, 1] = np.inf
    with pytest.raises(ValueError, match=r"frames\[0\] holds 4 NaN or infinite value\(s\) of 187500"):
        omma.stitch(rig, f, size=SIZE)
    with pytest.raises(ValueError, match="NaN or infinite"):
        omma.psnr(np.full((4, 4), np.nan, np.float32), np.zeros((4, 4), np.float32))
