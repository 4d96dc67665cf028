#!/usr/bin/env bash
# Lint of the RTL with the three Debian tools (run by CTest: rtl_lint_*):
#   Verilator --lint-only -Wall must print nothing (every warning class on; the few unused bits are
#   waived in place with a comment saying why),
#   Icarus Verilog must elaborate it, and Yosys must read and elaborate it (docs/results/rtl_synth.sh
#   synthesizes it)
#   (the SystemVerilog subset all three read: no int'() casts, string parameters or '{} patterns;
#   for Yosys, packages are imported by a rewrite, synth/yosys_compat.py).
# Usage: lint.sh TOP_MODULE [-GNAME=VALUE...] FILE.sv...   (-G: top-level parameters)
set -euo pipefail
top=$1
shift
params=()
while [ $# -gt 0 ] && [ "${1#-G}" != "$1" ]; do
  params+=("$1")
  shift
done
chparam=""
for p in "${params[@]+"${params[@]}"}"; do
  kv=${p#-G}
  chparam+="chparam -set ${kv%%=*} ${kv#*=} $top; "
done
status=0
if ! out=$(verilator --lint-only -Wall --top-module "$top" "${params[@]+"${params[@]}"}" "$@" 2>&1) || [ -n "$out" ]; then
  echo "verilator -Wall: $top"
  echo "$out"
  status=1
fi
if command -v iverilog >/dev/null; then
  # "sorry: constant selects in always_*" is Icarus's note that it widens a sensitivity list
  if ! out=$(iverilog -g2012 -s "$top" "${params[@]+"${params[@]/#-G/-P$top.}"}" -o /dev/null "$@" 2>&1); then
    echo "iverilog: $top"
    echo "$out" | grep -v "sorry:"
    status=1
  fi
fi
if command -v yosys >/dev/null; then
  # Yosys 0.23 takes package members only as pkg::name: read a rewritten copy (synth/yosys_compat.py)
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  python3 "$(dirname "$0")/synth/yosys_compat.py" "$tmp" "$@"
  files=$(for f in "$@"; do printf '%s ' "$tmp/$(basename "$f")"; done)
  if ! out=$(yosys -q -p "read_verilog -sv $files; $chparam hierarchy -check -top $top" 2>&1 | grep -v "Replacing memory"); then
    :
  fi
  if echo "$out" | grep -q "ERROR"; then
    echo "yosys: $top"
    echo "$out"
    status=1
  fi
fi
[ $status -eq 0 ] && echo "rtl lint: $top clean (verilator -Wall, iverilog, yosys)"
exit $status
