#!/usr/bin/env bash
# The live simulator benchmark (docs/results/live_sim_bench.md): bench/live_sim_bench.py for five
# minutes with the live page open in headless Chromium; the summary replaces live_sim_bench.json
# beside this script. Run on an idle machine.
#   docs/results/live_sim_bench.sh [SECONDS]    (OMMA=...)
set -euo pipefail
cd "$(dirname "$0")/../.."
OMMA=${OMMA:-build/omma}
python3 bench/live_sim_bench.py --seconds "${1:-300}" --omma "$OMMA" --out docs/results/live_sim_bench.json
