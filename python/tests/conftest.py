"""Shared fixtures of the omma Python tests: the thesis prototype rig and one small simulation.

The tests import the package built in the build tree (CTest sets PYTHONPATH=build/python) and run
with Debian's /usr/bin/python3 (python3-numpy, python3-pytest)."""
import os
from pathlib import Path

import numpy as np
import pytest

import omma

SIZE = (270, 270)  # panorama size of the tests (vr180): small enough for the reference stitcher


def omma_binary():
    """The built `omma` command (CTest passes its path), or None."""
    path = os.environ.get("OMMA_BINARY")
    return path if path and Path(path).exists() else None


@pytest.fixture(scope="session")
def rig():
    return omma.thesis_prototype_rig()


def smooth_photo(seed=1, w=720, h=360):
    """A far-field equirectangular 'photo' (BGR uint8): sums of random low-frequency sinusoids."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w] / np.array([h, w])[:, None, None]
    img = np.zeros((h, w, 3))
    for c in range(3):
        for _ in range(6):
            fx, fy = rng.integers(1, 8), rng.integers(1, 6)
            px, py = rng.uniform(0, 2 * np.pi, 2)
            img[:, :, c] += np.sin(2 * np.pi * fx * x + px) * np.cos(np.pi * fy * y + py)
    img = (img - img.min()) / (img.max() - img.min())
    return (img * 220 + 20).astype(np.uint8)


@pytest.fixture(scope="session")
def sim(rig):
    # The smooth far-field photo (from an array) with the default sensor effects (noise, vignetting,
    # colour gains, 10 bits).
    return omma.simulate(rig, scene=smooth_photo(1), size=SIZE, seed=1, supersample=1, truth_supersample=2)


@pytest.fixture(scope="session")
def frames(sim):
    return sim.frames


@pytest.fixture(scope="session")
def frames_dir(sim, tmp_path_factory):
    d = tmp_path_factory.mktemp("sim") / "frames"
    sim.save(str(d))
    return d


def random_frames(rig, seed=0):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, size=(h, w, 3), dtype=np.uint8) for w, h in rig.camera_sizes]
