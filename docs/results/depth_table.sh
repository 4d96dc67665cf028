#!/usr/bin/env bash
# The six blending methods on the colon with the projection surface at infinity
# (the thesis), the best fixed sphere, the simulator's true depth and the estimated depth; the depth
# error and the boundary maps against the true occlusion boundaries; far-field photos with and
# without the estimate.
#   docs/results/depth_table.sh [OUT_DIR]
# Writes OUT_DIR/table.md and prints it. Uses build/omma (OMMA=...). SEEDS (default "1 2 3"),
# PROJECTIONS (default "vr180 equirect"), VR_SIZE / EQ_SIZE (1080x1080 / 1920x512), RADII (the
# fixed spheres tried, mm), PHOTOS (far-field scenes; default louvre and lake).
# Colon seed s: `omma simulate --scene colon --seed s --dome-z 12(s-1)` (sim::colon_case).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-depth-table}
OMMA=${OMMA:-build/omma}
SEEDS=${SEEDS:-"1 2 3"}
PROJECTIONS=${PROJECTIONS:-"vr180 equirect"}
VR_SIZE=${VR_SIZE:-1080x1080}
EQ_SIZE=${EQ_SIZE:-1920x512}
RADII=${RADII:-"15 18 22 27 35"}
DATA=${DATA:-../shared/data}
PHOTOS=${PHOTOS:-"louvre lake"}
METHODS="nn linear gaussian mrf mrf-spherical sad"
mkdir -p "$OUT"
table="$OUT/table.md"
get() { python3 -c "
import json,sys
d=json.load(open(sys.argv[1]))
for k in sys.argv[2].split('.'): d=d[k]
print('n/a' if d is None else (f'{d:.2f}' if isinstance(d,float) else d))" "$@"; }
stitch_eval() {  # dir proj size method depth tag [extra stitch args]
  local dir=$1 proj=$2 size=$3 m=$4 depth=$5 tag=$6; shift 6
  "$OMMA" -q stitch --rig "$dir/rig.json" --frames "$dir" --method "$m" --projection "$proj" --size "$size" \
    --depth "$depth" --out "$dir/p_${m}_$tag.png" --single-camera "$dir/single.png" "$@" --json > "$dir/s_${m}_$tag.json"
  "$OMMA" -q eval --pano "$dir/p_${m}_$tag.png" --truth "$dir/truth.png" --mask "$dir/single.png" --json \
    > "$dir/e_${m}_$tag.json"
}
{
  echo "| case | method | inf | best sphere | truth | estimate | gap closed (all / seam) |"
  echo "|---|---|---|---|---|---|---|"
} > "$table"
cases="$OUT/cases.md"
{
  echo "| case | best R mm | depth median rel. error | within 10 % | L_ob at inf P/R/F1 (best th) | L_ob with estimate P/R/F1 (best th) | jumps of the estimate P/R/F1 | estimate s |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$cases"
for proj in $PROJECTIONS; do
  size=$EQ_SIZE; [ "$proj" = vr180 ] && size=$VR_SIZE
  for seed in $SEEDS; do
    dir="$OUT/colon-$proj-$seed"
    [ -f "$dir/truth_depth.tiff" ] || "$OMMA" -q simulate --scene colon --seed "$seed" --dome-z $((12 * (seed - 1))) \
      --projection "$proj" --truth-size "$size" --out "$dir" >&2
    best=0; bestp=0
    for R in $RADII; do
      stitch_eval "$dir" "$proj" "$size" mrf "sphere:$R" "r$R"
      p=$(get "$dir/e_mrf_r$R.json" psnr_db)
      if python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) > float(sys.argv[2]) else 1)" "$p" "$bestp"; then best=$R; bestp=$p; fi
    done
    stitch_eval "$dir" "$proj" "$size" mrf inf inf --boundary "$dir/b_inf.png"
    stitch_eval "$dir" "$proj" "$size" mrf estimate est --boundary "$dir/b_est.png" --depth-out "$dir/est.png"
    "$OMMA" -q eval --pano "$dir/p_mrf_est.png" --truth "$dir/truth.png" --projection "$proj" \
      --truth-depth "$dir/truth_depth.tiff" --depth "$dir/est.tiff" --boundary "$dir/b_est.png" --json > "$dir/d_est.json"
    "$OMMA" -q eval --pano "$dir/p_mrf_inf.png" --truth "$dir/truth.png" --projection "$proj" \
      --truth-depth "$dir/truth_depth.tiff" --boundary "$dir/b_inf.png" --json > "$dir/d_inf.json"
    bp() { echo "$(get "$1" "$2.precision")/$(get "$1" "$2.recall")/$(get "$1" "$2.f1")"; }
    echo "| colon $proj seed $seed | $best | $(get "$dir/d_est.json" depth.median_rel) | $(get "$dir/d_est.json" depth.within_10) |" \
      "$(bp "$dir/d_inf.json" boundary.best) | $(bp "$dir/d_est.json" boundary.best) |" \
      "$(bp "$dir/d_est.json" depth.boundary_from_depth) | $(python3 -c "import json; print(round(json.load(open('$dir/s_mrf_est.json'))['depth_ms']/1000,1))") |" >> "$cases"
    for m in $METHODS; do
      [ "$m" = mrf ] || stitch_eval "$dir" "$proj" "$size" "$m" inf inf
      [ "$m" = mrf ] && cp "$dir/e_mrf_r$best.json" "$dir/e_mrf_best.json" || stitch_eval "$dir" "$proj" "$size" "$m" "sphere:$best" best
      stitch_eval "$dir" "$proj" "$size" "$m" "truth:$dir/truth_depth.tiff" truth
      [ "$m" = mrf ] || stitch_eval "$dir" "$proj" "$size" "$m" "truth:$dir/est.tiff" est
      row=$(python3 - "$dir" "$m" <<'PY'
import json, sys
d, m = sys.argv[1], sys.argv[2]
e = {t: json.load(open(f"{d}/e_{m}_{t}.json")) for t in ("inf", "best", "truth", "est")}
f = lambda t: f"{e[t]['psnr_db']:.2f} ({e[t]['seam_psnr_db']:.2f})"
g = lambda k: 100 * (e['est'][k] - e['best'][k]) / (e['truth'][k] - e['best'][k])
print(f"| {f('inf')} | {f('best')} | {f('truth')} | {f('est')} | {g('psnr_db'):.0f} % / {g('seam_psnr_db'):.0f} % |")
PY
)
      echo "| colon $proj seed $seed | $m $row" >> "$table"
    done
  done
done
far="$OUT/far.md"
{
  echo "| photo | method | inf | estimate | difference |"
  echo "|---|---|---|---|---|"
} > "$far"
for photo in $PHOTOS; do
  dir="$OUT/$photo-vr180"
  [ -f "$dir/truth.png" ] || "$OMMA" -q simulate --scene "photo:$DATA/$photo.jpg" --truth-size "$VR_SIZE" --out "$dir" >&2
  stitch_eval "$dir" vr180 "$VR_SIZE" mrf estimate est --depth-out "$dir/est.png"
  for m in $METHODS; do
    stitch_eval "$dir" vr180 "$VR_SIZE" "$m" inf inf
    [ "$m" = mrf ] || stitch_eval "$dir" vr180 "$VR_SIZE" "$m" "truth:$dir/est.tiff" est
    a=$(get "$dir/e_${m}_inf.json" psnr_db); b=$(get "$dir/e_${m}_est.json" psnr_db)
    echo "| $photo vr180 | $m | $a | $b | $(python3 -c "print(f'{$b-$a:+.2f}')") |" >> "$far"
  done
done
cat "$table" "$cases" "$far"
