#!/usr/bin/env bash
# Far-field panoramas with estimated photometry against the same method on
# ideal-photometry frames (--vignetting 0 --color-gain 0, same seed) and on the uncorrected frames,
# all six methods, both projections, every photo in ../shared/data.
#   docs/results/photometric_table.sh [OUT_DIR]
# Per photo and projection: simulate the 24-camera prototype (default sensor effects: 50 % cos^4
# vignetting, gains in [0.9, 1.1], noise) and the same with ideal photometry; `omma calibrate
# --no-geometric --photometric` estimates vignetting and gains from the overlaps of the first
# frame set alone; `omma stitch` applies it. PSNR dB against the simulator's truth.
# Writes OUT_DIR/table.md and prints it. Uses build/omma (override with OMMA=...); EQ_SIZE, VR_SIZE
# as in pano_table.sh; PHOTOS limits the photos (e.g. PHOTOS=lake).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-photometric-table}
OMMA=${OMMA:-build/omma}
EQ_SIZE=${EQ_SIZE:-1920x512}
VR_SIZE=${VR_SIZE:-1080x1080}
DATA=${DATA:-../shared/data}
PHOTOS=${PHOTOS:-$(for f in "$DATA"/*.jpg; do basename "$f" .jpg; done)}
mkdir -p "$OUT"
table="$OUT/table.md"
{
  echo "| photo | projection | method | uncorrected | estimated photometry | ideal photometry | estimated - ideal |"
  echo "|---|---|---|---|---|---|---|"
} > "$table"
psnr() { python3 -c "import json,sys; print(f\"{json.load(open(sys.argv[1]))['psnr_db']:.2f}\")" "$1"; }
for name in $PHOTOS; do
  for proj in equirect vr180; do
    size=$EQ_SIZE; [ "$proj" = vr180 ] && size=$VR_SIZE
    dir="$OUT/$name-$proj"
    mkdir -p "$dir"
    "$OMMA" simulate --scene "photo:$DATA/$name.jpg" --out "$dir/real" --projection "$proj" --truth-size "$size" >&2
    "$OMMA" simulate --scene "photo:$DATA/$name.jpg" --out "$dir/ideal" --projection "$proj" --truth-size "$size" \
      --vignetting 0 --color-gain 0 --no-truth >&2
    "$OMMA" calibrate --rig "$dir/real/rig.json" --frames "$dir/real" --out "$dir/rig_photometric.json" \
      --no-geometric --photometric --json > "$dir/calibrate.json"
    for m in nn linear gaussian mrf mrf-spherical sad; do
      for what in uncorrected estimated ideal; do
        rig="$dir/real/rig.json"; frames="$dir/real"
        [ "$what" = estimated ] && rig="$dir/rig_photometric.json"
        [ "$what" = ideal ] && frames="$dir/ideal"
        "$OMMA" stitch --rig "$rig" --frames "$frames" --method "$m" --projection "$proj" --size "$size" \
          --out "$dir/pano_${m}_$what.png" --json > /dev/null
        "$OMMA" eval --pano "$dir/pano_${m}_$what.png" --truth "$dir/real/truth.png" --json > "$dir/eval_${m}_$what.json"
      done
      u=$(psnr "$dir/eval_${m}_uncorrected.json"); e=$(psnr "$dir/eval_${m}_estimated.json")
      i=$(psnr "$dir/eval_${m}_ideal.json")
      d=$(python3 -c "print(f'{$e - $i:+.2f}')")
      echo "| $name | $proj | $m | $u | $e | $i | $d |" >> "$table"
    done
  done
done
cat "$table"
