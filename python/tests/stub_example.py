"""A small typed use of omma, checked by mypy against the package's stubs (test_stubs.py); not a test
itself. Every annotation here must agree with omma/__init__.pyi."""
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np
import numpy.typing as npt

import omma


def stitch_and_score(folder: Path) -> Dict[str, Optional[float]]:
    rig: omma.Rig = omma.Rig.load("thesis-24")
    frames: List[npt.NDArray[np.uint8]] = [np.zeros((h, w, 3), np.uint8) for w, h in rig.camera_sizes]
    pano: npt.NDArray[np.float32] = omma.stitch(rig, frames, method="mrf", size=(270, 270))
    engine = omma.Engine(rig, size="270x270", cache_dir=None)
    fast: npt.NDArray[np.uint8] = engine.render(frames)
    omma.write_image(folder / "pano.jpg", fast, projection="vr180")
    return omma.evaluate(omma.to_u8(pano), fast)


def recording_timestamps(path: str) -> List[int]:
    rec = omma.Recording(path)
    ts: List[int] = []
    for fs in rec:
        ts.append(fs.t_ns)
        first: Optional[npt.NDArray[np.uint16]] = rec.read(0, fs.index)
        assert first is not None
    return ts


def live(rig: omma.Rig) -> int:
    n = 0
    with omma.run(rig, source="sim:colon", frames=10, sinks=["out.mp4"], sim_fps=(44.0, 56.0)) as run:
        for pano in run:
            n += int(pano.shape[0] > 0)
    summary = run.summary
    return n if summary is None else int(summary["frames"])


def plan_minutes() -> float:
    p = omma.plan(row=3, device_size="1TB")
    pto = omma.export_pto(omma.thesis_prototype_rig(), pano_width=720)
    omma.render("rec", "pano_{set}.tif", sets=(0, 2), cache_dir=False)
    return float(p["device"]["max_minutes"]) + len(str(pto["text"]))
