"""Simulator, reference stitcher and quality figures from Python, checked against the ground truth
and against the `omma` command on the same frames."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import omma
from conftest import SIZE, omma_binary


def test_simulation_arrays(rig, sim):
    assert len(sim.frames) == len(rig)
    for f in sim.frames:
        assert f.dtype == np.uint8 and f.shape == (250, 250, 3)
    assert sim.truth.dtype == np.uint8 and sim.truth.shape == (SIZE[1], SIZE[0], 3)
    assert sim.signals[0].dtype == np.float32
    assert sim.raw[0] is None  # raw=False
    assert sim.summary["scene"] == "photo:memory"
    assert sim.true_rig.to_dict() == rig.to_dict()  # no perturbation


def test_frames_share_the_simulations_buffers(sim):
    """Arrays out are views of the C++ images: two reads of .frames give the same memory."""
    assert np.shares_memory(sim.frames[0], sim.frames[0])
    assert sim.frames[0].__array_interface__["data"][0] == sim.frames[0].__array_interface__["data"][0]


@pytest.mark.parametrize("method", omma.METHODS)
def test_every_method_against_the_truth(rig, frames, sim, method):
    pano = omma.stitch(rig, frames, method=method, size=SIZE)
    assert pano.dtype == np.float32 and pano.shape == (SIZE[1], SIZE[0], 3)
    q = omma.evaluate(pano, sim.truth, seam=omma.seam_mask(rig, "vr180", SIZE))
    # The smooth far-field scene with noise, vignetting and colour gains: measured on photo/noise
    # seeds 1-3, PSNR 30.5-34.4 dB (linear lowest), seam PSNR 30.5-34.4 dB, SSIM 0.964-0.982.
    assert q["psnr_db"] > 28, q
    assert q["seam_psnr_db"] > 28, q
    assert 0.94 < q["ssim"] <= 1, q


def test_frames_in_the_wrong_order_fail_the_truth(rig, frames, sim):
    """The check above can fail: the same frames given to the wrong cameras (or as RGB) do."""
    shuffled = frames[1:] + frames[:1]
    assert omma.evaluate(omma.stitch(rig, shuffled, method="nn", size=SIZE), sim.truth)["psnr_db"] < 22
    rgb = [f[:, :, ::-1].copy() for f in frames]
    assert omma.evaluate(omma.stitch(rig, rgb, method="nn", size=SIZE), sim.truth)["psnr_db"] < 26


def test_stitch_matches_the_command_line(rig, frames, frames_dir, tmp_path):
    """Python's stitch of the in-memory frames = `omma stitch` of the saved folder, to the bit."""
    exe = omma_binary()
    if exe is None:
        pytest.skip("OMMA_BINARY not set")
    out = tmp_path / "pano.png"
    subprocess.run([exe, "stitch", "--rig", str(frames_dir / "rig.json"), "--frames", str(frames_dir), "--method",
                    "linear", "--size", f"{SIZE[0]}x{SIZE[1]}", "--out", str(out), "--json"], check=True,
                   capture_output=True)
    mine = omma.to_u8(omma.stitch(rig, omma.load_frames(str(frames_dir), rig), method="linear", size=SIZE))
    assert np.array_equal(mine, omma.read_image(str(out)))
    # The in-memory frames are the saved ones.
    assert all(np.array_equal(a, b) for a, b in zip(frames, omma.load_frames(str(frames_dir), rig)))


def test_frames_as_one_array_and_as_crops(rig, frames):
    stacked = np.stack(frames)
    a = omma.stitch(rig, frames, method="nn", size=(90, 90))
    assert np.array_equal(a, omma.stitch(rig, stacked, method="nn", size=(90, 90)))
    # Row-strided crops of bigger images are used in place (no copy needed).
    big = [np.pad(f, ((3, 5), (7, 2), (0, 0))) for f in frames]
    crops = [b[3:-5, 7:-2] for b in big]
    assert not crops[0].flags["C_CONTIGUOUS"]
    assert np.array_equal(a, omma.stitch(rig, crops, method="nn", size=(90, 90)))


def test_float_and_gray_frames(rig, frames):
    f32 = [f.astype(np.float32) / 255 for f in frames]
    a = omma.stitch(rig, frames, method="linear", size=(90, 90))
    b = omma.stitch(rig, f32, method="linear", size=(90, 90))
    assert np.abs(a - b).max() < 1e-5
    gray = [f[:, :, 1].copy() for f in frames]
    g = omma.stitch(rig, gray, method="linear", size=(90, 90))
    assert np.allclose(g[:, :, 0], g[:, :, 2])


def test_evaluate_figures(sim):
    t = sim.truth
    assert omma.evaluate(t, t)["psnr_db"] is None  # identical: infinite
    noisy = np.clip(t.astype(np.int16) + 4, 0, 255).astype(np.uint8)
    q = omma.evaluate(noisy, t)
    assert q["psnr_db"] == pytest.approx(20 * np.log10(255 / 4), abs=0.2)
    assert q["seam_psnr_db"] is None
    assert omma.psnr(noisy, t) == pytest.approx(q["psnr_db"])
    assert omma.ssim(t, t) == pytest.approx(1.0)


def test_simulate_photo_scene_from_an_array(rig):
    # An equirectangular "photo": left half blue, right half red (BGR); the truth sees both.
    photo = np.zeros((64, 128, 3), np.uint8)
    photo[:, :64, 0] = 255
    photo[:, 64:, 2] = 255
    s = omma.simulate(rig, scene=photo, size=(60, 60), ideal=True, supersample=1)
    assert s.summary["scene"] == "photo:memory"
    colours = s.truth.reshape(-1, 3)
    assert (colours[:, 0] > 200).sum() > 100 and (colours[:, 2] > 200).sum() > 100


def test_a_photo_scene_is_read_as_an_equirect_full_panorama(rig):
    # An asymmetric photo (a bright block left of centre, a gradient along the rows): its truth on
    # the equirect-full grid of the same size is the photo itself, not its mirror image.
    photo = np.full((64, 128, 3), 40, np.uint8)
    photo[:, :, 1] = np.linspace(0, 255, 128, dtype=np.uint8)[None, :]
    photo[20:40, 30:50, 2] = 250
    s = omma.simulate(rig, scene=photo, projection="equirect-full", size=(128, 64), ideal=True,
                      supersample=1)
    err = np.abs(s.truth.astype(int) - photo.astype(int)).mean()
    err_mirrored = np.abs(s.truth.astype(int) - photo[:, ::-1].astype(int)).mean()
    assert err < 2 and err_mirrored > 20


def test_simulation_save_writes_a_frames_folder(frames_dir):
    assert sorted(p.name for p in frames_dir.glob("cam_*.png"))[:2] == ["cam_00.png", "cam_01.png"]
    assert json.loads((frames_dir / "sim.json").read_text())["scene"] == "photo:memory"


def test_example_compares_two_methods(frames_dir, tmp_path):
    example = Path(__file__).resolve().parents[2] / "examples" / "python" / "compare_methods.py"
    r = subprocess.run([sys.executable, str(example), str(frames_dir), "--out", str(tmp_path), "--seconds", "0.1"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    rows = {w[0]: w for w in map(str.split, r.stdout.splitlines()) if w[:1] in (["nn"], ["mrf"]) and "vs" not in w}
    assert set(rows) == {"nn", "mrf"}
    assert all(float(rows[m][3]) > 28 for m in rows)  # PSNR against the truth, dB
    assert (tmp_path / "pano_mrf.jpg").stat().st_size > 1000 and (tmp_path / "side_by_side.png").exists()


def test_refocus_far_field_and_pinhole(rig, frames, sim):
    """Synthetic-aperture refocusing (omma refocus): a far-field scene focused at infinity is in focus
    everywhere; with a zero aperture only the camera nearest each ray contributes, which is nn."""
    r = omma.refocus(rig, frames, focus_mm=float("inf"), size=SIZE)
    assert r.dtype == np.float32 and r.shape == (SIZE[1], SIZE[0], 3)
    q = omma.evaluate(r, sim.truth)
    # Measured: 29.7 dB against the truth (the mean of the overlapping cameras).
    assert q["psnr_db"] > 28, q
    pinhole = omma.refocus(rig, frames, focus_mm=float("inf"), aperture_mm=0, size=SIZE)
    nn = omma.stitch(rig, frames, method="nn", size=SIZE)
    # Measured: identical (infinite PSNR): the same camera per direction, the same bilinear samples.
    assert omma.psnr(pinhole, nn) > 40
    with pytest.raises(ValueError):
        omma.refocus(rig, frames, focus_mm=-1, size=SIZE)
    with pytest.raises(ValueError):
        omma.refocus(rig, frames, combine="max", size=SIZE)
