"""360-degree metadata through the Python API, read back by exiftool and ffprobe; an MP4 whose movie
box precedes its media data ("fast start", chunk offsets moved) still decodes to the same frames."""
import json
import shutil
import subprocess

import numpy as np
import pytest

import omma


def run(*cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


@pytest.mark.skipif(shutil.which("exiftool") is None, reason="exiftool not installed")
@pytest.mark.parametrize("ext", ["jpg", "png"])
def test_write_image_with_projection_carries_gpano(tmp_path, ext):
    img = np.random.default_rng(1).integers(0, 256, size=(100, 400, 3), dtype=np.uint8)
    path = tmp_path / f"p.{ext}"
    omma.write_image(str(path), img, projection="equirect")
    tags = json.loads(run("exiftool", "-j", "-n", "-XMP-GPano:All", str(path)))[0]
    assert tags["ProjectionType"] == "equirectangular"
    assert (tags["FullPanoWidthPixels"], tags["FullPanoHeightPixels"]) == (400, 200)
    assert (tags["CroppedAreaImageWidthPixels"], tags["CroppedAreaImageHeightPixels"]) == (400, 100)
    assert (tags["CroppedAreaLeftPixels"], tags["CroppedAreaTopPixels"]) == (0, 0)
    back = omma.read_image(str(path))
    if ext == "png":
        assert np.array_equal(back, img)
    omma.write_image(str(tmp_path / "plain.png"), img)
    assert "ProjectionType" not in json.loads(run("exiftool", "-j", "-XMP-GPano:All", str(tmp_path / "plain.png")))[0]


@pytest.mark.skipif(shutil.which("ffmpeg") is None or shutil.which("ffprobe") is None, reason="ffmpeg not installed")
def test_fast_start_mp4_keeps_its_frames(tmp_path):
    mp4 = tmp_path / "v.mp4"
    run("ffmpeg", "-v", "error", "-f", "lavfi", "-i", "testsrc=size=256x256:rate=10", "-frames:v", "6", "-c:v",
        "mpeg4", "-movflags", "+faststart", str(mp4))
    head = mp4.read_bytes()[:4096]
    assert head.find(b"moov") < head.find(b"mdat") or head.find(b"mdat") < 0  # movie box first
    before = run("ffmpeg", "-v", "error", "-i", str(mp4), "-f", "framemd5", "-")
    omma.add_spherical_video_metadata(str(mp4), "vr180", (256, 256))
    after = run("ffmpeg", "-v", "error", "-i", str(mp4), "-f", "framemd5", "-")
    assert after == before and before.count("\n0,") == 6
    s = json.loads(run("ffprobe", "-v", "error", "-print_format", "json", "-show_streams", str(mp4)))["streams"][0]
    sph = next(d for d in s["side_data_list"] if d["side_data_type"] == "Spherical Mapping")
    assert sph["projection"] == "tiled equirectangular"
    assert abs(sph["bound_left"] - 128) <= 1 and abs(sph["bound_right"] - 128) <= 1
    with pytest.raises(omma.IoError, match="not an MP4 file"):
        (tmp_path / "x.mp4").write_text("hello")
        omma.add_spherical_video_metadata(str(tmp_path / "x.mp4"), "vr180", (256, 256))
