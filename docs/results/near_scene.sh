#!/usr/bin/env bash
# Near scenes at Giga-Eye's scale (docs/results/near_scene.md): the room (data/scenes/room.json) seen by
# Giga-Eye, rendered at infinity, on spheres, with the estimated and the true depth; refocusing; 3D.
#   docs/results/near_scene.sh [OUT_DIR]       (OMMA=...; about 15 minutes on 2 cores)
# Writes OUT_DIR (default near_scene_out/) with every JSON summary and picture; the tables of
# near_scene.md are copied from them by hand with the machine's load stated.
set -euo pipefail
cd "$(dirname "$0")/../.."
OMMA=${OMMA:-build/omma}
OUT=${1:-near_scene_out}
mkdir -p "$OUT"

# 1. The demo (skip3 frames, 21.6 MP panoramas, previews at 1800x480): depth, refocus stack, grid, 3D.
"$OMMA" demo --rig gigaeye-44 --scene room --out "$OUT/demo" --json > "$OUT/demo.json"

# 2. Repeated measurement at a small size: three rig positions in the room (skip5, 900x250), every surface.
for i in 1 2 3; do
  at=("0,0,0" "800,200,0" "-200,-600,0")
  d="$OUT/pos$i"
  "$OMMA" simulate --rig gigaeye-44-skip5 --scene room --dome-at "${at[$((i - 1))]}" --seed "$i" --out "$d" \
    --projection equirect-100 --truth-size 900x250 --json > "$d.sim.json"
  for depth in inf sphere:1000 sphere:2000 sphere:4000 "truth:$d/truth_depth.tiff" estimate; do
    name=$(echo "$depth" | cut -d: -f1-2 | tr ':/' '__' | cut -c1-14)
    "$OMMA" render "$d" --size 900x250 --no-cache --depth "$depth" --out "$d/pano_$name.png" \
      --truth "$d/truth.png" --json > "$d.render_$name.json"
  done
done

# 3. 21.6 MP from 44 x 1296x972 frames (skip1, 2x2 rays per pixel): speed and quality of every surface,
#    --repeat 3 (the depth estimated once per frame set, the render timed three times).
"$OMMA" simulate --rig gigaeye-44-skip1 --scene room --supersample 2 --truth-supersample 1 --out "$OUT/big" \
  --projection equirect-100 --truth-size 9000x2400 --json > "$OUT/big.sim.json"
for depth in inf sphere:2000 "truth:$OUT/big/truth_depth.tiff" estimate; do
  name=$(echo "$depth" | cut -d: -f1 | cut -c1-8)
  /usr/bin/time -f "%e s %M KB" "$OMMA" render "$OUT/big" --size 9000x2400 --no-cache --depth "$depth" \
    --out "$OUT/big_$name.tif" --truth "$OUT/big/truth.png" --repeat 3 --json > "$OUT/big_$name.json" \
    2> "$OUT/big_$name.time"
done

# 3b. The full sensors: 44 x 2592x1944 (one ray per pixel), infinity and the estimate.
"$OMMA" simulate --rig gigaeye-44 --scene room --supersample 1 --truth-supersample 1 --out "$OUT/full" \
  --projection equirect-100 --truth-size 9000x2400 --json > "$OUT/full.sim.json"
for depth in inf estimate; do
  "$OMMA" render "$OUT/full" --size 9000x2400 --no-cache --depth "$depth" --out "$OUT/full_$depth.tif" \
    --truth "$OUT/full/truth.png" --repeat 3 --json > "$OUT/full_$depth.json"
done

# 4. The same under mpirun, split by bands (every rank estimates the same depth).
if command -v mpirun > /dev/null; then
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe -np 2 "$OMMA" render "$OUT/big" --size 9000x2400 --no-cache --depth estimate \
    --split tiles --out "$OUT/big_mpi.tif" --truth "$OUT/big/truth.png" --json > "$OUT/big_mpi.json"
fi

# 5. The dome in the colon: a focal stack (omma refocus) and the frames it comes from.
"$OMMA" simulate --rig thesis-24 --scene colon --out "$OUT/colon" --truth-size 540x540 --json > "$OUT/colon.sim.json"
"$OMMA" refocus --rig thesis-24 --frames "$OUT/colon" --focus 15 20 30 60 --size 540x540 \
  --out "$OUT/colon_refocus.png" --stack "$OUT/colon_stack.png" --json > "$OUT/colon_refocus.json"
echo "written to $OUT/"
