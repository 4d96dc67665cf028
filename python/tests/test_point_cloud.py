"""omma.write_ply: the point cloud of a depth map (io/point_cloud.h), read back from the PLY bytes."""
import numpy as np
import pytest

import omma


def read_ply(path):
    """(header lines, xyz float32 (N, 3), rgb uint8 (N, 3)) of omma's binary PLY."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    n = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    rec = np.frombuffer(data[end:], dtype=np.dtype([("xyz", "<f4", 3), ("rgb", "u1", 3)]), count=n)
    return header, rec["xyz"], rec["rgb"]


def test_sphere_depth_gives_points_on_the_sphere(tmp_path):
    h = w = 40
    depth = np.full((h, w), 75.0, np.float32)
    depth[:4] = np.inf  # no points
    colour = np.random.default_rng(1).integers(0, 256, (h, w, 3), dtype=np.uint8)
    n = omma.write_ply(tmp_path / "c.ply", depth, colour, projection="vr180", step=2)
    header, xyz, rgb = read_ply(tmp_path / "c.ply")
    assert n == len(xyz) == (h - 4) // 2 * (w // 2)
    assert any("millimetres in the rig (dome) frame" in l for l in header)
    assert np.abs(np.linalg.norm(xyz, axis=1) - 75.0).max() < 1e-3
    # BGR -> red, green, blue; the first point is pixel (row 4, col 0).
    assert tuple(rgb[0]) == tuple(colour[4, 0, ::-1])


def test_confidence_and_bad_input(tmp_path):
    depth = np.full((10, 10), 50.0, np.float32)
    colour = np.zeros((10, 10, 3), np.uint8)
    conf = np.tile(np.arange(10, dtype=np.float32) / 10, (10, 1))  # columns 0.0 .. 0.9
    assert omma.write_ply(tmp_path / "c.ply", depth, colour, min_confidence=0.55, confidence=conf) == 10 * 4
    with pytest.raises(ValueError):
        omma.write_ply(tmp_path / "d.ply", depth, colour, step=0)
    with pytest.raises(ValueError):
        omma.write_ply(tmp_path / "d.ply", depth, colour[:5])
    assert not (tmp_path / "d.ply").exists()
