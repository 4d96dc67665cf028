#!/usr/bin/env bash
# The full 1080 x 1080 panorama through the Verilated RTL, compared pixel by pixel with the
# bit-accurate model; prints one JSON object per run (simulated cycles, cycles per pixel against the
# model's throughput count, simulation wall time). Arguments go to every run (e.g. --scene louvre).
#   docs/results/rtl_bench.sh                     # colon, vr180 1080x1080, nn and linear
set -euo pipefail
cd "$(dirname "$0")/../.."
scripts/install-deps.sh --test  # Verilator, Yosys, Icarus
# a build folder configured before Verilator was installed has the RTL off: switch it on
if [ -f build/CMakeCache.txt ] && ! grep -q "^OMMA_RTL:[A-Z]*=ON" build/CMakeCache.txt; then
  cmake -S . -B build -DOMMA_RTL=ON -Dverilator_DIR=/usr/share/verilator >&2
fi
scripts/build.sh --target omma_rtl_pano_bench omma_rtl_gen_files >/dev/null
cd build/hw/rtl/gen  # the sin/cos ROM images are read from here
for m in nn linear; do
  ../omma_rtl_pano_bench --method "$m" "$@"
done
