#!/usr/bin/env bash
# Yosys synth_xilinx (7-series) of every RTL block and of the front end: LUTs, flip-flops, DSP48E1,
# block RAM per block (markdown table on stdout, JSON in build/hw/rtl/synth.json). Takes a few
# minutes per large block; arguments go to hw/rtl/synth/synth.py (e.g. --only cam_search).
set -euo pipefail
cd "$(dirname "$0")/../.."
scripts/install-deps.sh --test  # Verilator, Yosys, Icarus
# a build folder configured before Verilator was installed has the RTL off: switch it on
if [ -f build/CMakeCache.txt ] && ! grep -q "^OMMA_RTL:[A-Z]*=ON" build/CMakeCache.txt; then
  cmake -S . -B build -DOMMA_RTL=ON -Dverilator_DIR=/usr/share/verilator >&2
fi
scripts/build.sh --target omma_rtl_gen_files >/dev/null
cd build/hw/rtl/gen
python3 ../../../../hw/rtl/synth/synth.py . --json ../synth.json "$@"
