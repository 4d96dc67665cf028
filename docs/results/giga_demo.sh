#!/usr/bin/env bash
# The Giga-Eye end to end (docs/results/giga_demo.md): `omma demo --rig gigaeye-44` (plan, coverage,
# a simulated raw recording, its calibration, 21.6 MP panoramas against the truth), timed; prints
# OUT_DIR/report.md. Takes about 10 minutes on two cores.
#   docs/results/giga_demo.sh [OUT_DIR]         (OMMA=...)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-giga-demo}
OMMA=${OMMA:-build/omma}
start=$(date +%s.%N)
"$OMMA" demo --rig gigaeye-44 --out "$OUT" --json > "$OUT.json"
echo "omma demo --rig gigaeye-44: $(python3 -c "print(f'{$(date +%s.%N) - $start:.0f}')") s in all" >&2
cat "$OUT/report.md"
