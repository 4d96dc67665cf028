#!/usr/bin/env bash
# Latency and load of the live outputs (docs/results/stream_bench.md): `omma bench --stream --json`
# RUNS times (default 3) at 1080x1080, 30 panoramas/s, the thesis rig's 24 cameras at 50 frames/s, up to
# 64 RTSP readers;
# each run's JSON in OUT_DIR, then the table of docs/results/stream_bench.md from all of them.
# Run it on an idle machine: the figures follow the machine's load.
#   docs/results/stream_bench.sh [OUT_DIR]      (OMMA=..., RUNS=...)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-stream-bench}
OMMA=${OMMA:-build/omma}
RUNS=${RUNS:-3}
mkdir -p "$OUT"
for i in $(seq "$RUNS"); do
  "$OMMA" bench --stream --max-readers 64 --json > "$OUT/stream_$i.json"
done
python3 - "$OUT" "$RUNS" <<'PY'
import json, sys
out, runs = sys.argv[1], int(sys.argv[2])
rs = [json.load(open(f"{out}/stream_{i}.json")) for i in range(1, runs + 1)]
r0 = rs[0]
print(f"{r0['cameras']} cameras at {r0['camera_fps']:g} frames/s, {r0['size']} panoramas at {r0['fps']:g}/s, "
      f"{r0['hardware_threads']} hardware threads; {runs} runs.\n")
print("| path | median ms (per run) | p90 ms (per run) | flashes |")
print("|---|---|---|---|")
for key, name in [("element", "camera frame into `ommastitch` → panorama out (appsrc → element → appsink)"),
                  ("rtsp", "engine → `rtsp://` (x264enc, gst-rtsp-server) → rtspsrc + avdec_h264"),
                  ("mjpeg", "engine → live view `/stream.mjpg` → souphttpsrc + jpegdec")]:
    med = ", ".join(f"{r[key].get('median_ms', float('nan')):.0f}" for r in rs)
    p90 = ", ".join(f"{r[key].get('p90_ms', float('nan')):.0f}" for r in rs)
    n = ", ".join(str(r[key].get('samples', 0)) for r in rs)
    print(f"| {name} | {med} | {p90} | {n} |")
print()
print("| run | engine panoramas/s (rtsp + mjpeg run) | frame age at render, ms | element's push latency, ms | RTSP readers at full rate |")
print("|---|---|---|---|---|")
for i, r in enumerate(rs, 1):
    es = r.get("element", {}).get("element_stats", {})
    print(f"| {i} | {r['engine']['fps']:.1f} | {r['engine']['latency_ms']:.1f} | "
          f"{es.get('push-latency-ms', float('nan')):.1f} | {r['max_readers_full_rate']} |")
print()
print("| readers | slowest reader frames/s (per run) | stream Mbit/s (per run) |")
print("|---|---|---|")
ks = sorted({l["readers"] for r in rs for l in r["readers"]})
for k in ks:
    vals, rates = [], []
    for r in rs:
        v = [l for l in r["readers"] if l["readers"] == k]
        vals.append(f"{v[0]['slowest_fps']:.1f}" if v else "-")
        rates.append(f"{v[0].get('stream_mbit_s', 0):.1f}" if v else "-")
    print(f"| {k} | {', '.join(vals)} | {', '.join(rates)} |")
PY
