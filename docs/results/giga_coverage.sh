#!/usr/bin/env bash
# Giga-Eye coverage and recording plan (docs/results/giga_coverage.md): the coverage command of the
# table (colour maps in OUT_DIR) and `omma plan --table71`.
#   docs/results/giga_coverage.sh [OUT_DIR]     (OMMA=...)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-giga-coverage}
OMMA=${OMMA:-build/omma}
mkdir -p "$OUT"
"$OMMA" coverage gigaeye-44 --distance 500 --distance 1000 --distance 5000 --distance inf \
  --polar-max 100 --step 0.25 --map "$OUT/cov.png"
"$OMMA" plan --table71
