#!/usr/bin/env bash
# Speed of the depth-adaptive renderer (docs/results/depth_table.md, "Engine"): `omma bench
# --depth` beside the static mrf map (target: >= 56 panoramas/s at 1080x1080 on 2 cores with the
# depth estimated every panorama, `target_56fps_met`; the depth workload alternates two random frame
# sets), then `omma run --depth` on the simulated colon, twice (estimate_ms_mean, render_ms_mean,
# latency_ms in the JSON). Benchmarks on a shared machine are noisy: compare with the static map's
# figure of the same run (vs_static).
#   docs/results/depth_bench.sh                 (OMMA=...; run on an idle machine)
set -euo pipefail
cd "$(dirname "$0")/../.."
OMMA=${OMMA:-build/omma}
"$OMMA" bench --depth --only omma-mrf-1080x1080 --only omma-mrf-depth-1080x1080 --seconds 6 --rounds 3 --json
for i in 1 2; do
  "$OMMA" run --rig thesis-24 --source sim:colon --depth --fps 0 --duration 20 --json
done
