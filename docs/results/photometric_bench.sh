#!/usr/bin/env bash
# The cost of photometric correction in the engine and the calibration speed
# (docs/results/photometric_table.md, last sections). Run on an idle machine.
#   docs/results/photometric_bench.sh           (OMMA=..., BUILD=...)
set -euo pipefail
cd "$(dirname "$0")/../.."
OMMA=${OMMA:-build/omma}
BUILD=${BUILD:-build}
"$OMMA" bench --only omma-mrf-1080x1080 --only omma-mrf-store-1080x1080 \
  --only omma-mrf-photometric-1080x1080 --rounds 3 --json
"$BUILD/omma_calib_bench"
