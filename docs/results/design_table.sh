#!/usr/bin/env bash
# The dome-design checks against the thesis (docs/results/design_table.md): the commands behind
# each row, their JSON summaries printed one per line, then `omma sweep` timed.
#   docs/results/design_table.sh [OUT_DIR]      (OMMA=... for another build)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-design-table}
OMMA=${OMMA:-build/omma}
mkdir -p "$OUT"
run() { echo "== omma $*"; "$OMMA" -q "$@" --json; echo; }
run design --method max-volume --aov 64 --r-phys 5 --cam-size 1x1x2
run design --method max-volume --aov 64 --r-phys 5 --cam-size 1x1x1.85
run coverage thesis-24
run design --method layered --aov 64 --r-virtual 15
run design --method min-cameras --aov 64 --r-virtual 15
run design --method min-cameras --aov 64 --r-virtual 16
run design --method cvt --sphere --r-virtual 18
run optics
start=$(date +%s.%N)
"$OMMA" -q sweep --out "$OUT/sweep" > /dev/null
echo "omma sweep: $(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')") s"
