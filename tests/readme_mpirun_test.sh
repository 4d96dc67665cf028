#!/usr/bin/env bash
# The README's MPI lines, run as written: the indented block after the line
# "<!-- mpirun example, run by tests/readme_mpirun_test.sh -->", from a folder where `build` is the
# build folder, as the current user, and, when that is root, again as the unprivileged user nobody
# (Open MPI refuses root unless told; the README's lines must work for both). Checks the panorama's
# size with exiftool. Usage: tests/readme_mpirun_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src="$1"
build="$(realpath "$2")"
block="$(awk '/<!-- mpirun example, run by tests\/readme_mpirun_test.sh -->/{f=1;next} f&&/^    /{print substr($0,5);next} f&&NF{exit}' "$src/README.md")"
[ -n "$block" ] || { echo "no mpirun example block in README.md" >&2; exit 1; }
grep -q '^mpirun ' <<< "$block" || { echo "the README's block has no mpirun line" >&2; exit 1; }
run_block() {  # run_block DIR [setpriv args...]: the block in DIR, optionally as another user
  local dir="$1"
  shift
  ln -s "$build" "$dir/build"
  (cd "$dir" && "$@" env -i PATH="$PATH" HOME="$dir" bash -euo pipefail -c "$block")
  size="$(exiftool -s3 -ImageSize "$dir/pano.tif")"
  [ "$size" = "2048x1024" ] || { echo "pano.tif is $size, not 2048x1024" >&2; exit 1; }
  echo "README mpirun block ran${*:+ as $*}: pano.tif $size"
}
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/me"
run_block "$tmp/me"
if [ "$(id -u)" -eq 0 ] && command -v setpriv >/dev/null; then
  mkdir -m 0777 "$tmp/user"
  chmod 0755 "$tmp"
  run_block "$tmp/user" setpriv --reuid=65534 --regid=65534 --clear-groups
fi
