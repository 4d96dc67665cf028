#!/usr/bin/env bash
# Table A.1 on real photographs (docs/results/isp_table.md): `omma isp --eval PHOTO` on every
# photograph in ../shared/data (or PHOTOS="a.jpg b.jpg"); one JSON summary per photograph.
#   docs/results/isp_table.sh                   (OMMA=... for another build, DATA=... for the photos)
set -euo pipefail
cd "$(dirname "$0")/../.."
OMMA=${OMMA:-build/omma}
DATA=${DATA:-../shared/data}
PHOTOS=${PHOTOS:-$(ls "$DATA"/*.jpg)}
for p in $PHOTOS; do
  echo "== $p"
  "$OMMA" -q isp --eval "$p" --json
  echo
done
