#!/usr/bin/env bash
# PSNR / SSIM / seam PSNR of the six blending methods against the simulator's
# ground truth, on louvre.jpg, lake.jpg and the colon scene, both projections.
#   docs/results/pano_table.sh RIG [OUT_DIR]        (RIG: e.g. the 24-camera prototype rig file)
# Writes OUT_DIR/table.md (Markdown) and prints it. Uses build/omma (override with OMMA=...).
# Sizes: equirect 1920x512 and vr180 1080x1080 (the thesis's panoramas); override with
# EQ_SIZE=WxH VR_SIZE=WxH for a quicker run. SIM_FLAGS adds simulator flags (e.g. --ideal: no
# vignetting, gains, noise or quantisation); SCENES limits the scenes (e.g. SCENES=colon).
set -euo pipefail
cd "$(dirname "$0")/../.."
RIG=${1:?usage: docs/results/pano_table.sh RIG [OUT_DIR]}
OUT=${2:-/tmp/omma-pano-table}
OMMA=${OMMA:-build/omma}
EQ_SIZE=${EQ_SIZE:-1920x512}
VR_SIZE=${VR_SIZE:-1080x1080}
DATA=${DATA:-../shared/data}
mkdir -p "$OUT"
table="$OUT/table.md"
{
  echo "| scene | projection | method | PSNR dB | SSIM | seam PSNR dB | inter-camera PSNR dB | ms |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$table"
json() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); v=d[sys.argv[2]]; print('n/a' if v is None else (f'{v:.4f}' if sys.argv[2]=='ssim' else f'{v:.2f}'))" "$@"; }
SCENES=${SCENES:-"photo:$DATA/louvre.jpg photo:$DATA/lake.jpg colon"}
SIM_FLAGS=${SIM_FLAGS:-}
for scene in $SCENES; do
  name=$(basename "${scene#photo:}" .jpg)
  for proj in equirect vr180; do
    size=$EQ_SIZE; [ "$proj" = vr180 ] && size=$VR_SIZE
    dir="$OUT/$name-$proj"
    "$OMMA" simulate --rig "$RIG" --scene "$scene" --out "$dir" --projection "$proj" --truth-size "$size" $SIM_FLAGS >&2
    for m in nn linear gaussian mrf mrf-spherical sad; do
      "$OMMA" stitch --rig "$RIG" --frames "$dir" --method "$m" --projection "$proj" --size "$size" \
        --out "$dir/pano_$m.png" --single-camera "$dir/single.png" --json > "$dir/stitch_$m.json"
      "$OMMA" eval --pano "$dir/pano_$m.png" --truth "$dir/truth.png" --mask "$dir/single.png" --json \
        > "$dir/eval_$m.json"
      echo "| $name | $proj | $m | $(json "$dir/eval_$m.json" psnr_db) | $(json "$dir/eval_$m.json" ssim) |" \
           "$(json "$dir/eval_$m.json" seam_psnr_db) | $(json "$dir/stitch_$m.json" inter_camera_psnr_db) |" \
           "$(json "$dir/stitch_$m.json" ms) |" >> "$table"
    done
  done
done
cat "$table"
