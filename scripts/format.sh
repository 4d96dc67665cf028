#!/usr/bin/env bash
# Formats omma's C++ files with clang-format (.clang-format). --check: change nothing, list the files
# that differ and exit 1 if any does (scripts/test.sh runs this first, so CI refuses unformatted code).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null || { echo "format.sh: clang-format is missing (scripts/install-deps.sh --test)" >&2; exit 1; }
mapfile -t files < <(git ls-files -- '*.h' '*.cc' '*.cpp' | grep -v '^web/')
if [ "${1:-}" = --check ]; then
  bad=()
  for f in "${files[@]}"; do
    clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
  done
  if [ ${#bad[@]} -gt 0 ]; then
    printf 'not formatted (run scripts/format.sh): %s\n' "${bad[@]}" >&2
    exit 1
  fi
  echo "format: ${#files[@]} files formatted as .clang-format says"
else
  clang-format -i "${files[@]}"
fi
