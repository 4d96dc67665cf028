#!/usr/bin/env python3
"""Python's omma.Engine.render against the C++ renderer, in the same process and the same run.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_render.py [--size 1080x1080] [--rounds 5]

One map (mrf, vr180, thesis prototype rig, random-texture frames as `omma bench` uses), rendered by
  cpp            the C++ loop around engine::render (Engine._render_loop: no Python per frame)
  python         a Python loop over engine.render()            (a new NumPy array per frame)
  python-out     a Python loop over engine.render(out=buffer)  (written in place)
and, with the frames copied into the frame store every time (what render(frames) does):
  cpp+upload / python+upload   (_render_loop(n, frames) / engine.render(frames, out=buffer))
The workloads are measured in turns (--rounds interleaved slices), so that the shared machine's
drifting speed slows them alike; the ratios python / cpp are printed per round and overall. With
--omma-bench, `omma bench --only omma-mrf-WxH` (its own process, map and frames) runs between the
rounds as a further peer (all threads only).
"""
import argparse
import json
import os
import subprocess
import time

import numpy as np

import omma


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="1080x1080")
    ap.add_argument("--method", default="mrf")
    ap.add_argument("--threads", type=int, default=0, help="renderer threads (0: all)")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=0.5, help="per workload and round")
    ap.add_argument("--omma-bench", action="store_true", help="also run `omma bench` between the rounds")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    w, h = (int(x) for x in a.size.lower().split("x"))
    rig = omma.thesis_prototype_rig()
    rng = np.random.default_rng(1)
    frames = [rng.integers(0, 256, size=(ch, cw, 3), dtype=np.uint8) for cw, ch in rig.camera_sizes]
    eng = omma.Engine(rig, method=a.method, size=(w, h), threads=a.threads)
    eng.set_frames(frames)
    buf = eng.render()

    def py_loop(call):
        def run(seconds):
            n, t0 = 0, time.perf_counter()
            while True:
                call()
                n += 1
                t = time.perf_counter() - t0
                if t >= seconds:
                    return n, t
        return run

    def cpp_loop(upload):
        per = [eng._render_loop(3, frames if upload else None) / 3]
        def run(seconds):
            n = max(3, int(seconds / max(per[0], 1e-5)))
            t = eng._render_loop(n, frames if upload else None)
            per[0] = t / n
            return n, t
        return run

    workloads = {
        "cpp": cpp_loop(False),
        "python": py_loop(lambda: eng.render()),
        "python-out": py_loop(lambda: eng.render(out=buf)),
        "cpp+upload": cpp_loop(True),
        "python+upload": py_loop(lambda: eng.render(frames, out=buf)),
    }
    omma_exe = os.environ.get("OMMA_BINARY", os.path.join(os.path.dirname(__file__), "..", "build", "omma"))
    if a.omma_bench:
        workloads["omma-bench"] = None
    totals = {k: [0, 0.0] for k in workloads}
    rounds = {k: [] for k in workloads}
    for _ in range(a.rounds):
        for name, run in workloads.items():
            if run is None:
                r = subprocess.run([omma_exe, "bench", "--only", f"omma-{a.method}-{w}x{h}", "--rounds", "1",
                                    "--seconds", str(a.seconds), "--json"], capture_output=True, text=True, check=True)
                entry = next(e for e in json.loads(r.stdout)["results"] if e["name"] == f"omma-{a.method}-{w}x{h}")
                rounds[name].append(entry["fps"])
                totals[name][0] += entry["fps"]
                totals[name][1] += 1
                continue
            n, t = run(a.seconds)
            rounds[name].append(n / t)
            totals[name][0] += n
            totals[name][1] += t
    fps = {k: v[0] / v[1] for k, v in totals.items()}
    ratio = lambda a_, b_: [x / y for x, y in zip(rounds[a_], rounds[b_])]
    result = {
        "size": f"{w}x{h}", "method": a.method, "kernel": eng.kernel, "threads": a.threads, "fps": fps, "round_fps": rounds,
        "python_over_cpp": fps["python"] / fps["cpp"],
        "python_out_over_cpp": fps["python-out"] / fps["cpp"],
        "python_upload_over_cpp_upload": fps["python+upload"] / fps["cpp+upload"],
        "python_over_cpp_rounds": ratio("python", "cpp"),
        "python_upload_over_cpp_upload_rounds": ratio("python+upload", "cpp+upload"),
    }
    if a.omma_bench:
        result["python_over_omma_bench"] = fps["python"] / fps["omma-bench"]
    if a.json:
        print(json.dumps(result))
        return
    print(f"{a.method} {w}x{h}, kernel {eng.kernel}, threads {a.threads or 'all'}, {a.rounds} rounds of "
          f"{a.seconds} s per workload")
    for k, v in fps.items():
        print(f"  {k:<14} {v:8.0f} fps   rounds: " + " ".join(f"{x:.0f}" for x in rounds[k]))
    for k in ("python_over_cpp", "python_out_over_cpp", "python_upload_over_cpp_upload", "python_over_omma_bench"):
        if k in result:
            print(f"  {k:<30} {result[k]:.3f}")
    print("  python/cpp per round: " + " ".join(f"{x:.3f}" for x in result["python_over_cpp_rounds"]))


if __name__ == "__main__":
    main()
