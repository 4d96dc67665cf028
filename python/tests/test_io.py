"""Recordings (record from a source, open, frame sets with timestamps), offline rendering to
(Big)TIFF, Hugin PTO import/export, the planner and built-in rig names, from Python. Figures are
read back by outside tools where one exists: h5dump (HDF5 streams), exiftool (TIFF headers),
checkpto (Hugin's project checker) and the `omma` command (plan)."""
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

import omma
from conftest import SIZE, omma_binary


def test_rig_load_takes_builtin_names(rig):
    assert omma.Rig.load("thesis-24").to_dict() == rig.to_dict()
    giga = omma.Rig.load("gigaeye-44")
    assert len(giga) == 44 and giga.name == "gigaeye-44"
    skip1 = omma.load_rig("gigaeye-44-skip1")
    assert set(skip1.camera_sizes) == {(1296, 972)}  # Table 7.1 rows 3-6
    assert "gigaeye-44-window" in omma.builtin_rig_names()
    with pytest.raises(omma.RigError, match="neither a rig file nor a built-in rig"):
        omma.Rig.load("thesis-25")


@pytest.fixture(scope="module")
def recording(rig, frames_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("rec") / "rec"
    summary = omma.record(rig, f"frames:{frames_dir}", out, frames=3, fps=10)
    return out, summary


def h5_values(path, dataset):
    text = subprocess.run(["h5dump", "-d", dataset, str(path)], check=True, capture_output=True, text=True).stdout
    data = text[text.index("DATA {"):text.index("}", text.index("DATA {"))]
    return [int(v) for v in re.findall(r"(?<![(\d])-?\d+(?![):\d])", data.split("DATA {", 1)[1])]


@pytest.mark.skipif(shutil.which("h5dump") is None, reason="h5dump (hdf5-tools) not installed")
def test_record_and_read_frame_sets(rig, frames, recording):
    out, summary = recording
    assert summary["frames"] == [3] * len(rig) and summary["dropped"] == [0] * len(rig)
    assert summary["bytes"] == 3 * sum(w * h * 2 for w, h in rig.camera_sizes)
    assert summary["error"] is None
    rec = omma.Recording(out)
    assert (len(rec), rec.cameras, rec.bits, rec.fps, rec.complete) == (3, len(rig), 12, 10.0, True)
    assert rec.frame_counts == [3] * len(rig) and rec.complete_sets == 3
    assert rec.rig.to_dict() == rig.to_dict()
    # Timestamps and sequence numbers as h5dump reads them from the streams.
    for cam in (0, len(rig) - 1):
        path = out / rec.manifest["streams"][cam]["file"]
        assert rec.timestamps(cam).tolist() == h5_values(path, "/t_ns")
        assert rec.sequence(cam).tolist() == h5_values(path, "/seq") == [0, 1, 2]
    sets = list(rec)
    assert [s.index for s in sets] == [0, 1, 2]
    for s in sets:
        assert s.complete and s.frame_indices.tolist() == [s.index] * len(rig)
        # Every frame within half a period (1/fps = 100 ms) of the set's instant.
        assert s.timestamps_ns.dtype == np.int64 and np.abs(s.timestamps_ns - s.t_ns).max() <= 50_000_000
    # The recorded mosaic is the frame mosaicked RGGB and scaled to 12 bits (io/recording.h).
    raw = sets[1].frames[5]
    assert raw.dtype == np.uint16 and raw.shape == frames[5].shape[:2]
    r = frames[5][0::2, 0::2, 2].astype(np.float64)
    np.testing.assert_array_equal(raw[0::2, 0::2], np.round(r * 4095 / 255).astype(np.uint16))
    np.testing.assert_array_equal(rec.read(5, 1), raw)
    # Developed: demosaicked, no white balance, the 12-bit values taken as linear and sRGB-encoded.
    dev = rec.frame_set(1, develop=True, awb="none", photometric=False).frames[5]
    assert dev.dtype == np.uint8 and dev.shape == frames[5].shape
    x = frames[5] / 255.0
    srgb = np.round(255 * np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)).astype(np.uint8)
    assert omma.psnr(dev, srgb) > 22  # 24.5 dB measured (demosaicking loses the finest detail)
    with pytest.raises(IndexError):
        rec[3]
    with pytest.raises(omma.RecordingError):
        omma.Recording(out / "missing")


def exif(path, *tags):
    out = subprocess.run(["exiftool", "-j", *[f"-{t}" for t in tags], str(path)], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)[0]


@pytest.mark.skipif(shutil.which("exiftool") is None, reason="exiftool not installed")
def test_render_recording_to_bigtiff(recording, tmp_path):
    out, _ = recording
    r = omma.render(out, tmp_path / "pano_{set}.btf", size=(720, 200), method="linear", cache_dir=False)
    assert r["outputs"] == [str(tmp_path / f"pano_{i:05d}.btf") for i in range(3)]
    assert r["frame_sets"] == 3 and r["projection"] == "equirect-100"
    info = exif(r["outputs"][2], "FileType", "ImageWidth", "ImageHeight")
    assert (info["FileType"], info["ImageWidth"], info["ImageHeight"]) == ("BTF", 720, 200)
    one = omma.render(out, tmp_path / "one.tif", size=(720, 200), method="linear", cache_dir=False, sets=2)
    assert one["outputs"] == [str(tmp_path / "one.tif")] and one["frame_sets"] == 1
    # The same frame set gives the same pixels, BigTIFF or classic TIFF.
    assert omma.psnr(omma.read_image(one["outputs"][0]), omma.read_image(r["outputs"][2])) == float("inf")
    with pytest.raises(ValueError, match="outside the recording's 3 frame sets"):
        omma.render(out, tmp_path / "x.tif", size=(720, 200), sets=(2, 5))


def test_render_frames_in_memory_matches_engine(rig, frames, tmp_path):
    r = omma.render(frames, tmp_path / "pano.btf", rig=rig, size=SIZE, projection="vr180", method="mrf",
                    cache_dir=False, photometric=False)
    assert r["width"] == SIZE[0] and r["height"] == SIZE[1]
    banded = omma.read_image(tmp_path / "pano.btf")
    engine = omma.Engine(rig, method="mrf", size=SIZE).render(frames)
    # Band maps hold the taps of the whole grid's map: the panoramas agree to the 8-bit rounding.
    assert omma.psnr(banded, engine) > 50
    with pytest.raises(ValueError, match="needs rig="):
        omma.render(frames, tmp_path / "x.tif")


def test_pto_export_import_round_trip(rig, tmp_path):
    path = tmp_path / "rig.pto"
    ex = omma.export_pto(rig, path, frames_dir=tmp_path / "frames", pano_width=720)
    assert path.read_text() == ex["text"]
    assert ex["text"].count("\ni ") + ex["text"].startswith("i ") == len(rig)
    assert "frames/cam_00.png" in ex["text"]
    if shutil.which("checkpto"):  # Hugin's own reader of the project
        out = subprocess.run(["checkpto", str(path)], capture_output=True, text=True).stdout
        assert f"contains\n{len(rig)} images" in out or re.search(rf"\b{len(rig)} images", out), out
    im = omma.import_pto(path)
    assert isinstance(im["rig"], omma.Rig) and len(im["rig"]) == len(rig)
    d = omma.rig_diff(im["rig"], rig)
    assert d["ray_error_deg"]["max"] < 0.01 and d["orientation_error_deg"]["max"] < 0.01
    assert omma.import_pto(text=ex["text"])["rig"].camera_sizes == rig.camera_sizes
    with pytest.raises(omma.PtoError):
        omma.import_pto(text="# no images\n")
    with pytest.raises(ValueError, match="path or text"):
        omma.import_pto()


def test_plan_matches_the_command():
    p = omma.plan()
    mib = 2592 * 1944 * 9.5 * 12 / 8 / 2 ** 20
    assert p["camera"]["mib_per_s"] == pytest.approx(mib, rel=1e-12)
    assert p["feasible"] and p["rig"]["devices"] == 22
    assert p["input"]["device_bytes"] == 128e9 and p["input"]["device_rate_bytes_per_s"] == 150e6
    over = omma.plan(minutes=1000, device_size=256e9)
    assert not over["feasible"] and "device-capacity" in over["failed"]
    assert [c["name"] for c in over["checks"] if not c["ok"]] == ["device-capacity"]
    rows = omma.table71()
    assert [r["option"] for r in rows] == list(range(1, 9))
    exe = omma_binary()
    if exe:
        for args, kwargs in ((["--row", "3", "--minutes", "20"], dict(row=3, minutes=20)),
                             (["--resolution", "1296x972", "--fps", "30", "--device-size", "1TB"],
                              dict(resolution=(1296, 972), fps=30, device_size="1TB"))):
            run = subprocess.run([exe, "plan", *args, "--json"], capture_output=True, text=True)
            cli = json.loads(run.stdout)
            py = omma.plan(**kwargs)
            cli.pop("omma_version", None)
            assert {k: py[k] for k in cli} == cli  # the same JSON, and the same verdict as the exit status
            assert run.returncode == (0 if py["feasible"] else 1)
        cli71 = json.loads(subprocess.run([exe, "plan", "--table71", "--json"], check=True, capture_output=True,
                                          text=True).stdout)
        assert [r["bandwidth_mib_s"] for r in cli71["rows"]] == [r["bandwidth_mib_s"] for r in rows]
    with pytest.raises(ValueError, match="row must be 1..8"):
        omma.plan(row=9)


def test_render_never_renders_a_missing_camera_black(rig, tmp_path):
    """A recording whose second camera stops early: sets 3..5 lack it. render() holds a recent frame,
    skips the rest, or refuses (incomplete='fail'), as `omma render --incomplete`; a warning gives the
    counts, and the result dict holds them."""
    d = rig.to_dict()
    d["cameras"] = d["cameras"][:2]
    two = omma.Rig.from_dict(d)
    sources = []
    for c, n in enumerate((6, 3)):
        folder = tmp_path / f"s{c}"
        folder.mkdir()
        w, h = two.camera_sizes[c]
        for k in range(n):
            omma.write_image(folder / f"f{k}.png", np.full((h, w, 3), 40 + 20 * k, np.uint8))
        sources.append(str(folder))
    out = tmp_path / "rec"
    omma.record(two, sources, out, frames=6, fps=10)
    rec = omma.Recording(out)
    assert (len(rec), rec.complete_sets) == (6, 3)
    common = dict(size=(128, 64), projection="equirect-full", method="linear", cache_dir=False)
    with pytest.warns(RuntimeWarning, match="3 of 6 frame sets lack cameras"):
        skip = omma.render(out, tmp_path / "skip_{set}.png", incomplete="skip", **common)
    assert [p[-9:-4] for p in skip["outputs"]] == ["00000", "00001", "00002"]
    assert (skip["incomplete"]["skipped"], skip["incomplete"]["held_sets"]) == (3, 0)
    with pytest.warns(RuntimeWarning):
        hold = omma.render(out, tmp_path / "hold_{set}.png", incomplete="hold", hold_max_age_ms=150, **common)
    assert (hold["incomplete"]["held_sets"], hold["incomplete"]["skipped"]) == (1, 2)
    assert len(hold["outputs"]) == 4 and hold["outputs"][-1].endswith("hold_00003.png")
    with pytest.raises(omma.RecordingError, match="lacks camera"):
        omma.render(out, tmp_path / "fail_{set}.png", incomplete="fail", **common)
    with pytest.raises(ValueError, match="hold_max_age_ms"):
        omma.render(out, tmp_path / "x.png", hold_max_age_ms=-1, **common)
