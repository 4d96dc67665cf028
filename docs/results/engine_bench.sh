#!/usr/bin/env bash
# The real-time renderer against its peers and the memcpy bound (docs/results/engine_bench.md):
# `omma bench --json` RUNS times (default 3), one JSON summary per run in OUT_DIR.
# Run it on an idle machine: the figures follow the machine's load.
#   docs/results/engine_bench.sh [OUT_DIR]      (OMMA=..., RUNS=...)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-engine-bench}
OMMA=${OMMA:-build/omma}
RUNS=${RUNS:-3}
mkdir -p "$OUT"
for i in $(seq "$RUNS"); do
  "$OMMA" bench --json > "$OUT/bench_$i.json"
  python3 -c "
import json, sys
j = json.load(open(sys.argv[1]))
print(json.dumps(j.get('ratios', {}), indent=1))" "$OUT/bench_$i.json"
done
