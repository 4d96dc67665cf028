#!/usr/bin/env python3
"""Stitch the demo's frames with two blending methods and compare them against the ground truth.

    omma demo                      # writes omma-demo/frames (rig.json, cam_XX.png, truth.png)
    PYTHONPATH=build/python /usr/bin/python3 examples/python/compare_methods.py omma-demo/frames

Without a frames folder the script simulates the demo's scene itself (the thesis's 24-camera dome in
the colon). It stitches with the reference stitcher and with the real-time engine, prints PSNR/SSIM
against the truth, and writes pano_<method>.jpg (with the 360-degree XMP) and a side-by-side image.
"""
import argparse
import json
import re
import time
import warnings
from pathlib import Path

import numpy as np

import omma


def gpano_projection(data):
    """The omma projection a GPano XMP packet (as omma.write_image(..., projection=) writes) describes,
    from the crop of the full 360 x 180 panorama; None if there is none."""
    fields = {}
    for name in ("FullPanoWidthPixels", "FullPanoHeightPixels", "CroppedAreaImageWidthPixels",
                 "CroppedAreaImageHeightPixels"):
        m = re.search(rb"GPano:%s[>=\"]+(\d+)" % name.encode(), data)
        if not m:
            return None
        fields[name] = int(m.group(1))
    w = fields["CroppedAreaImageWidthPixels"] / fields["FullPanoWidthPixels"]
    h = fields["CroppedAreaImageHeightPixels"] / fields["FullPanoHeightPixels"]
    if abs(w - 0.5) < 0.01 and abs(h - 1) < 0.01:
        return "vr180"
    if abs(w - 1) < 0.01 and abs(h - 1) < 0.01:
        return "equirect-full"
    if abs(w - 1) < 0.01 and abs(h - 0.5) < 0.01:
        return "equirect"
    return None


def folder_projection(d, given=None):
    """The projection of a frames folder's truth: --projection if given, else sim.json's truth grid
    (`omma simulate` / `omma demo` write it), else the GPano XMP of truth.png if it has one (plain text
    in the file); vr180 with a warning when the folder does not say."""
    if given:
        return given
    sim = d / "sim.json"
    if sim.exists():
        try:
            p = json.loads(sim.read_text()).get("truth", {}).get("projection")
            if p in omma.PROJECTIONS:
                return p
        except (ValueError, AttributeError):
            pass
    truth = d / "truth.png"
    if truth.exists():
        p = gpano_projection(truth.read_bytes())
        if p:
            return p
    warnings.warn(f"{d}: no sim.json or projection metadata says how the truth is projected; assuming vr180 "
                  "(give --projection if it is another: the quality figures are meaningless otherwise)",
                  stacklevel=2)
    return "vr180"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("frames", nargs="?", help="frames folder of `omma demo` / `omma simulate` (default: simulate)")
    ap.add_argument("--methods", nargs=2, default=["nn", "mrf"], choices=omma.METHODS)
    ap.add_argument("--out", default="compare-methods", help="output folder")
    ap.add_argument("--seconds", type=float, default=1.0, help="time the engine this long per method")
    ap.add_argument("--projection", choices=omma.PROJECTIONS,
                    help="projection of the folder's truth.png (default: from its sim.json, else vr180 with a "
                         "warning); without a folder: the simulated truth's (default vr180)")
    ap.add_argument("--rig", help="rig file or built-in name (default: the folder's rig.json, or thesis-24)")
    a = ap.parse_args()

    if a.frames:
        d = Path(a.frames)
        rig = omma.Rig.load(a.rig or str(d / "rig.json"))
        frames = omma.load_frames(str(d), rig)
        truth = omma.read_image(str(d / "truth.png")) if (d / "truth.png").exists() else None
        projection = folder_projection(d, a.projection)
    else:
        rig = omma.Rig.load(a.rig or "thesis-24")
        projection = a.projection or "vr180"
        size = (2160, 1080) if projection == "equirect-full" else (1080, 1080)
        sim = omma.simulate(rig, scene="colon", projection=projection, size=size, progress=True)
        frames, truth = sim.frames, sim.truth
    size = (truth.shape[1], truth.shape[0]) if truth is not None else (1080, 1080)
    seam = omma.seam_mask(rig, projection, size)
    out = Path(a.out)
    out.mkdir(exist_ok=True)

    panos = {}
    print(f"{len(rig)} cameras, {projection} {size[0]}x{size[1]}")
    print(f"{'method':<14}{'stitch s':>9}{'engine fps':>11}{'PSNR dB':>9}{'SSIM':>8}{'seam PSNR':>10}{'engine vs ref dB':>17}")
    for method in a.methods:
        t0 = time.perf_counter()
        ref = omma.to_u8(omma.stitch(rig, frames, method=method, projection=projection, size=size))
        t_ref = time.perf_counter() - t0
        engine = omma.Engine(rig, method=method, projection=projection, size=size)
        fast = engine.render(frames)
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < a.seconds:
            engine.render(frames, out=fast)
            n += 1
        fps = n / (time.perf_counter() - t0)
        q = omma.evaluate(ref, truth, seam=seam) if truth is not None else {"psnr_db": None, "ssim": None,
                                                                             "seam_psnr_db": None}
        fmt = lambda x, p: f"{x:.{p}f}" if x is not None else "-"
        print(f"{method:<14}{t_ref:>9.2f}{fps:>11.0f}{fmt(q['psnr_db'], 2):>9}{fmt(q['ssim'], 4):>8}"
              f"{fmt(q['seam_psnr_db'], 2):>10}{omma.psnr(fast, ref):>17.1f}")
        omma.write_image(str(out / f"pano_{method}.jpg"), ref, projection=projection)
        panos[method] = ref
    a_img, b_img = (panos[m] for m in a.methods)
    diff = np.abs(a_img.astype(np.int16) - b_img.astype(np.int16)).sum(axis=2)
    print(f"{a.methods[0]} vs {a.methods[1]}: PSNR {omma.psnr(a_img, b_img):.2f} dB, "
          f"{(diff > 30).mean() * 100:.1f} % of pixels differ by more than 30 levels (the seams)")
    omma.write_image(str(out / "side_by_side.png"), np.hstack([a_img, b_img]))
    print(f"wrote {out}/pano_{a.methods[0]}.jpg, pano_{a.methods[1]}.jpg, side_by_side.png")


if __name__ == "__main__":
    main()
