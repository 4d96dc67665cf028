#!/usr/bin/env bash
# The main job: install what is missing, build, run `omma demo` on the built-in default scene.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh --target omma
exec build/omma demo "$@"
