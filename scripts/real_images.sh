#!/usr/bin/env bash
# omma on real photographs with ground truth, beside its peers (docs/results/real_images.md):
# every case of `omma real` (bench/real.h) with --json, RUNS times (default 3: the spread of the
# times and of anything random), then the tables of docs/results/real_images.md from those objects
# and the pictures of the first run, made smaller, in docs/results/real_images/.
#   scripts/real_images.sh [WORK_DIR]        (OMMA=path/to/omma, RUNS=N, CASES="depth stitch:graf ...")
# Needs OpenCV's samples (opencv-doc), COLMAP and Hugin: scripts/install-deps.sh --test installs them.
set -euo pipefail
cd "$(dirname "$0")/.."
WORK=${1:-/tmp/omma-real-images}
OMMA=${OMMA:-build/omma}
RUNS=${RUNS:-3}
CASES=${CASES:-"stereo-calib depth stitch:leuven stitch:aero stitch:graf"}
[ -x "$OMMA" ] || { echo "real_images.sh: $OMMA not found: build first (scripts/build.sh)" >&2; exit 1; }
mkdir -p "$WORK"
for c in $CASES; do
  name=${c/:/_}
  for i in $(seq "$RUNS"); do
    echo "real_images.sh: omma real ${c/:/ } (run $i of $RUNS)" >&2
    start=$(date +%s.%N)
    # shellcheck disable=SC2086
    "$OMMA" real ${c/:/ } --out "$WORK/${name}_$i" --json > "$WORK/${name}_$i.json.tmp"
    mv "$WORK/${name}_$i.json.tmp" "$WORK/${name}_$i.json"
    echo "real_images.sh:   $(python3 -c "import time,sys; print(f'{time.time()-float(sys.argv[1]):.1f} s')" "$start")" >&2
  done
done
python3 scripts/real_images_table.py "$WORK" "$RUNS" $CASES
