#!/usr/bin/env bash
# The demo's figures (docs/results/demo.md): `omma demo` on the built-in default scene, timed.
# Prints the report's tables (OUT_DIR/report.md); the JSON summary goes to OUT_DIR.json.
#   docs/results/demo_table.sh [OUT_DIR]        (OMMA=... for another build)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-demo-table}
OMMA=${OMMA:-build/omma}
start=$(date +%s.%N)
"$OMMA" demo --out "$OUT" --json > "$OUT.json"
echo "omma demo: $(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')") s in all" >&2
cat "$OUT/report.md"
