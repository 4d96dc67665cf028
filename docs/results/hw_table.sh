#!/usr/bin/env bash
# The bit-accurate pipeline against the float stitch (docs/results/hw_table.md): `omma hw simulate`
# on the colon, the Louvre and the lake, vr180 1080x1080 and equirect 1920x512, nn / linear / mrf,
# default widths; prints psnr_vs_float_db per case.
#   docs/results/hw_table.sh [OUT_DIR]          (OMMA=..., DATA=... for the photos)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-hw-table}
OMMA=${OMMA:-build/omma}
DATA=${DATA:-../shared/data}
mkdir -p "$OUT"
for scene in colon "photo:$DATA/louvre.jpg" "photo:$DATA/lake.jpg"; do
  name=$(basename "${scene#photo:}" .jpg)
  [ -d "$OUT/$name" ] || "$OMMA" -q simulate --rig thesis-24 --scene "$scene" --no-truth --out "$OUT/$name" >&2
  for proj in vr180 equirect; do
    size=1080x1080; [ "$proj" = equirect ] && size=1920x512
    for m in nn linear mrf; do
      p=$("$OMMA" -q hw simulate --frames "$OUT/$name" --method "$m" --projection "$proj" --size "$size" --json |
          python3 -c "import json, sys; print(f\"{json.load(sys.stdin)['psnr_vs_float_db']:.2f}\")")
      echo "| $name | $proj | $m | $p |"
    done
  done
done
