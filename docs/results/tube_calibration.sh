#!/usr/bin/env bash
# Calibration of the 24-camera prototype from 8 shots of the thesis's 35 mm
# calibration tube (§3.6), three simulation seeds, with --perturb orient=2,focal=0.03,center=5,k1=0.05
# and the default sensor effects; then the colon check: the tube calibration applied to colon
# frames of the same rig, mrf panorama against the true rig's (geometry only: --no-photometric on
# both sides).
#   docs/results/tube_calibration.sh [OUT_DIR]      (SEEDS="1 2 3" SHOTS=8 DENSE_ROUNDS=3 to change)
# The errors are given as they are and with the global rotation removed (rig-diff --align). The
# tube's axis defines the rig's z axis (its offset is estimated); TUBE_TILT=1 estimates its tilt too
# (omma calibrate --tube-tilt), and then only the 5 mm parallax holds the rig's tilt.
# Writes OUT_DIR/table.md and prints it. Uses build/omma (override with OMMA=...).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-tube-calibration}
OMMA=${OMMA:-build/omma}
SEEDS=${SEEDS:-"1 2 3"}
SHOTS=${SHOTS:-8}
DENSE_ROUNDS=${DENSE_ROUNDS:-3}
TILT=(); [ "${TUBE_TILT:-0}" = 1 ] && TILT=(--tube-tilt)
PERTURB=orient=2,focal=0.03,center=5,k1=0.05
mkdir -p "$OUT"
table="$OUT/table.md"
{
  echo "| seed | orientation median (max) | orientation, global rotation removed | focal median (max) | centre median (max) | ray error median | RMS | calibrate (s) | colon mrf: calibrated / true rig / nominal (dB) |"
  echo "|---|---|---|---|---|---|---|---|---|"
} > "$table"
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))$2)" "$1"; }
for seed in $SEEDS; do
  d="$OUT/seed$seed"
  mkdir -p "$d"
  [ -d "$d/tube" ] || "$OMMA" simulate --scene tube --shots "$SHOTS" --no-truth --perturb "$PERTURB" --seed "$seed" --out "$d/tube" >&2
  [ -d "$d/flat" ] || "$OMMA" simulate --scene flat --shots "$SHOTS" --no-truth --perturb "$PERTURB" --seed "$seed" --out "$d/flat" >&2
  [ -d "$d/colon" ] || "$OMMA" simulate --scene colon --perturb "$PERTURB" --seed "$seed" --out "$d/colon" >&2
  rig="$d/tube/shot_00/rig.json"; true_rig="$d/tube/shot_00/rig_true.json"
  start=$(date +%s.%N)
  "$OMMA" calibrate --rig "$rig" --frames "$d/tube" --flat "$d/flat" --tube 35 "${TILT[@]}" --dense-rounds "$DENSE_ROUNDS" --out "$d/calibrated.json" --json > "$d/calibrate.json"
  secs=$(python3 -c "print(f'{$(date +%s.%N) - $start:.0f}')")
  "$OMMA" rig-diff "$d/calibrated.json" "$true_rig" --json > "$d/diff.json"
  "$OMMA" rig-diff "$d/calibrated.json" "$true_rig" --align --json > "$d/diff_aligned.json"
  for which in calibrated true nominal; do
    r="$d/calibrated.json"; [ "$which" = true ] && r="$true_rig"; [ "$which" = nominal ] && r="$rig"
    "$OMMA" stitch --rig "$r" --frames "$d/colon" --method mrf --no-photometric --out "$d/colon_$which.png" > /dev/null
    "$OMMA" eval --pano "$d/colon_$which.png" --truth "$d/colon/truth.png" --json > "$d/eval_$which.json"
  done
  echo "| $seed | $(field "$d/diff.json" "['orientation_error_deg']['median']" | xargs printf '%.3f') deg ($(field "$d/diff.json" "['orientation_error_deg']['max']" | xargs printf '%.3f')) |" \
       "$(field "$d/diff_aligned.json" "['orientation_error_deg']['median']" | xargs printf '%.3f') deg ($(field "$d/diff_aligned.json" "['orientation_error_deg']['max']" | xargs printf '%.3f')) |" \
       "$(field "$d/diff.json" "['focal_error_rel']['median']*100" | xargs printf '%.2f') % ($(field "$d/diff.json" "['focal_error_rel']['max']*100" | xargs printf '%.2f')) |" \
       "$(field "$d/diff.json" "['center_error_px']['median']" | xargs printf '%.2f') px ($(field "$d/diff.json" "['center_error_px']['max']" | xargs printf '%.2f')) |" \
       "$(field "$d/diff.json" "['ray_error_deg']['median']" | xargs printf '%.3f') deg | $(field "$d/calibrate.json" "['rms_px']" | xargs printf '%.3f') px | $secs |" \
       "$(field "$d/eval_calibrated.json" "['psnr_db']" | xargs printf '%.2f') / $(field "$d/eval_true.json" "['psnr_db']" | xargs printf '%.2f') / $(field "$d/eval_nominal.json" "['psnr_db']" | xargs printf '%.2f') |" >> "$table"
done
cat "$table"
