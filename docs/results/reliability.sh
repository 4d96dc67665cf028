#!/usr/bin/env bash
# The fuzzing and sanitizer figures (docs/results/reliability.md): 1,000,000 libFuzzer executions
# of the rig, map and PTO targets (fuzz/run.sh), then the sanitizer stage (scripts/test-asan.sh),
# each timed. Takes about 20 minutes on two idle cores.
#   docs/results/reliability.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/../.."
RUNS=${1:-1000000}
for t in rig map pto; do
  start=$(date +%s.%N)
  fuzz/run.sh "$RUNS" "$t"
  echo "fuzz $t: $(python3 -c "print(f'{$(date +%s.%N) - $start:.0f}')") s" >&2
done
start=$(date +%s.%N)
scripts/test-asan.sh
echo "sanitizer stage: $(python3 -c "print(f'{$(date +%s.%N) - $start:.0f}')") s" >&2
