#!/usr/bin/env bash
# Widths of the bit-accurate pipeline (docs/results/hw_sweep.md): `omma hw sweep` (PSNR against the
# float stitch as each width varies alone, the smallest set that keeps 45 dB) on the three cases of
# the table: 540x540 vr180 colon / linear and louvre / mrf, 960x256 equirect lake / nn. Each case
# writes OUT_DIR/CASE/hw_sweep.csv and .svg (the louvre / mrf curves are hw_sweep_louvre_mrf.*).
#   docs/results/hw_sweep.sh [OUT_DIR]          (OMMA=..., DATA=... for the photos)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-hw-sweep}
OMMA=${OMMA:-build/omma}
DATA=${DATA:-../shared/data}
mkdir -p "$OUT"
sweep() {  # name scene method projection size
  local name=$1 scene=$2 m=$3 proj=$4 size=$5
  [ -d "$OUT/$name-frames" ] || "$OMMA" -q simulate --rig thesis-24 --scene "$scene" --no-truth --out "$OUT/$name-frames" >&2
  "$OMMA" -q hw sweep --frames "$OUT/$name-frames" --method "$m" --projection "$proj" --size "$size" \
    --out "$OUT/${name}_$m" --json
  echo
}
sweep colon colon linear vr180 540x540
sweep louvre "photo:$DATA/louvre.jpg" mrf vr180 540x540
sweep lake "photo:$DATA/lake.jpg" nn equirect 960x256
