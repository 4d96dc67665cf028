#!/usr/bin/env python3
"""Record, inspect, render and play back live, from Python: the peers of `omma record`, `omma
recording check`, `omma render` and `omma run`.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/record_and_render.py [--rig thesis-24]

Records simulated free-running cameras (sim:SCENE, or --source SPEC) for --seconds into OUT/rec
(12-bit RGGB mosaics with capture timestamps, HDF5), prints how the frames matched into frame sets,
renders the first frame set to OUT/pano.tif (BigTIFF when large) in the rig's projection, and runs
the live engine on the same source for --frames panoramas into OUT/live.mp4, printing the latency.
"""
import argparse
import shutil
from pathlib import Path

import numpy as np

import omma


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rig", default="thesis-24", help="rig file or built-in name (default thesis-24)")
    ap.add_argument("--source", help="camera source spec (default: sim:colon, loop --sim-loop s)")
    ap.add_argument("--sim-loop", type=float, default=0.2, help="pre-rendered loop of sim: sources, s")
    ap.add_argument("--seconds", type=float, default=1.0, help="recording length, s")
    ap.add_argument("--frames", type=int, default=10, help="live panoramas")
    ap.add_argument("--projection", default=None, choices=omma.PROJECTIONS,
                    help="panorama projection (default: equirect-full for a sphere rig, else vr180)")
    ap.add_argument("--size", default="540x540", help="panorama size WxH")
    ap.add_argument("--out", default="record-and-render", help="output folder (replaced)")
    a = ap.parse_args()

    rig = omma.Rig.load(a.rig)
    projection = a.projection or ("equirect-full" if rig.to_dict().get("dome", {}).get("sphere") else "vr180")
    source = a.source or "sim:colon"
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)

    s = omma.record(rig, source, out / "rec", duration=a.seconds, fps=30)
    print(f"recorded {sum(s['frames'])} frames of {len(rig)} cameras ({sum(s['dropped'])} dropped) "
          f"at {s['mb_per_s']:.1f} MB/s")
    rec = omma.Recording(out / "rec")
    spans = [float(np.ptp(fs.timestamps_ns[fs.frame_indices >= 0])) / 1e6 for fs in rec]
    print(f"{len(rec)} frame sets ({rec.complete_sets} complete); frames of a set within "
          f"{max(spans, default=0):.2f} ms of each other (half a period: {500 / rec.fps:.1f} ms)")

    r = omma.render(out / "rec", out / "pano.tif", size=a.size, projection=projection, method="mrf", sets=0)
    print(f"rendered {r['outputs'][0]} ({r['width']}x{r['height']} {r['projection']}) in "
          f"{r['seconds']['render']:.2f} s")

    live = omma.run(rig, source=source, frames=a.frames, size=a.size, projection=projection,
                    sinks=[out / "live.mp4"], sim_loop=a.sim_loop)
    latencies = []
    for pano in live:
        latencies.append(live.latency_ms)
    print(f"live: {len(latencies)} panoramas {pano.shape[1]}x{pano.shape[0]}, latency "
          f"{np.mean(latencies):.1f} ms mean, {live.summary['fps']:.1f} fps -> {out / 'live.mp4'}")


if __name__ == "__main__":
    main()
