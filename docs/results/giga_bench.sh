#!/usr/bin/env bash
# Giga-Eye benchmarks (thesis ch. 7), all in one run on this machine:
#   1. omma render at 9000x2400 (21.6 MP) from 44 x 1296x972 frames (Table 7.2's sensor mode) and at
#      17700x4650 (82.3 MP) from 44 x 2592x1944 frames (Table 7.3's), per method, cached maps, against
#      the simulator's truth; Hugin's nona on the same frames and about the same output size, timed
#      in the same run.
#   2. omma record: 44 simulated cameras -> HDF5, MB/s against the disk's sequential write rate (dd,
#      same folder, same run); the FFV1 probe (bench/ffv1_probe.cc) for the container choice.
# Usage: docs/results/giga_bench.sh [OUT_DIR] [--quick]   (--quick: 21.6 MP only, fewer repeats)
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=${1:-/tmp/omma-giga-bench}
QUICK=${2:-}
B=${OMMA:-$PWD/build/omma}
DATA=$PWD/../shared/data
mkdir -p "$OUT"
log() { echo "== $*" >&2; }
t() { local s=$(date +%s.%N); "$@"; echo "$(date +%s.%N) - $s" | bc; }

sizes=("skip1 9000x2400 21")
[ "$QUICK" = "--quick" ] || sizes+=("full 17700x4650 82")
for entry in "${sizes[@]}"; do
  read -r mode size tag <<<"$entry"
  rig=gigaeye-44; [ "$mode" = full ] || rig=gigaeye-44-$mode
  f=$OUT/f$tag
  if [ ! -f "$f/truth.png" ]; then
    log "simulate $rig ($size truth)"
    $B simulate --rig $rig --scene photo:$DATA/lake.jpg --projection equirect-100 --truth-size $size \
      --supersample 1 --truth-supersample 1 --out $f --json > $OUT/sim$tag.json
  fi
  for m in nn linear mrf; do
    log "omma render $size $m"
    $B render $f --size $size --method $m --out $OUT/p${tag}_$m.tif --truth $f/truth.png --repeat 3 --json \
      > $OUT/render${tag}_$m.json
    # once more: the maps now come from the cache
    $B render $f --size $size --method $m --out $OUT/p${tag}_$m.tif --repeat 3 --json > $OUT/render${tag}_${m}_cached.json
  done
  # Hugin's nona on the same frames: a 360 x 180 deg project (square pixels) cropped to polar 0..100 deg.
  w=${size%x*}
  $B pto export $f/rig.json $OUT/f$tag.pto --frames $f --pano-width $w --interpolator 5 --json > /dev/null
  h=$((w / 2)); crop=$((w * 100 / 360))
  sed -i "s/^p f2 w$w h$h v360 E0 R0.*/p f2 w$w h$h v360 E0 R0 S0,$w,0,$crop n\"TIFF_m c:NONE\"/" $OUT/f$tag.pto
  log "nona $w x $crop"
  /usr/bin/time -f "%e s %M KB" nona -o $OUT/nona$tag -m TIFF $OUT/f$tag.pto 2> $OUT/nona$tag.time || true
  cat $OUT/nona$tag.time >&2
done

# Recording: 44 cameras of 1296x972 (Table 7.2) from stills, as fast as the recorder goes.
log "disk sequential write (dd, 2 GB, fdatasync)"
dd if=/dev/zero of=$OUT/dd.bin bs=16M count=128 conv=fdatasync 2> $OUT/dd.txt; rm -f $OUT/dd.bin
cat $OUT/dd.txt >&2
rm -rf $OUT/rec
log "omma record 44 x 1296x972"
$B record --rig gigaeye-44-skip1 --source frames:$OUT/f21 --source-fps 0 --duration 10 --queue 8 --out $OUT/rec --json \
  > $OUT/record.json || true
cat $OUT/record.json >&2
if [ ! -x $OUT/ffv1_probe ]; then
  g++ -O2 -std=c++20 bench/ffv1_probe.cc -o $OUT/ffv1_probe $(pkg-config --cflags --libs opencv4 libavcodec libavutil)
fi
$B simulate --rig gigaeye-44-skip1 --scene photo:$DATA/lake.jpg --raw --bits 12 --supersample 1 --no-truth \
  --out $OUT/raw21 --json > /dev/null
$OUT/ffv1_probe $OUT/raw21/cam_0{0,5,9}_raw.png $OUT/raw21/cam_2{0,5}_raw.png > $OUT/ffv1.json
cat $OUT/ffv1.json >&2
