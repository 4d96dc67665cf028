#!/usr/bin/env bash
# Lint of the RTL with the three Debian tools (run by CTest: rtl_lint_*):
#   Verilator --lint-only -Wall must print nothing (every warning class on, none waived),
#   Icarus Verilog must elaborate it, and Yosys must read, elaborate and convert its processes
#   (the SystemVerilog subset all three read: no int'() casts, string parameters or '{} patterns).
# Usage: lint.sh TOP_MODULE FILE.sv...
set -euo pipefail
top=$1
shift
status=0
if ! out=$(verilator --lint-only -Wall --top-module "$top" "$@" 2>&1) || [ -n "$out" ]; then
  echo "verilator -Wall: $top"
  echo "$out"
  status=1
fi
if command -v iverilog >/dev/null; then
  # "sorry: constant selects in always_*" is Icarus's note that it widens a sensitivity list
  if ! out=$(iverilog -g2012 -s "$top" -o /dev/null "$@" 2>&1); then
    echo "iverilog: $top"
    echo "$out" | grep -v "sorry:"
    status=1
  fi
fi
if command -v yosys >/dev/null; then
  files=$(printf '%s ' "$@")
  if ! out=$(yosys -q -p "read_verilog -sv $files; hierarchy -check -top $top; proc" 2>&1); then
    echo "yosys: $top"
    echo "$out"
    status=1
  fi
fi
[ $status -eq 0 ] && echo "rtl lint: $top clean (verilator -Wall, iverilog, yosys)"
exit $status
