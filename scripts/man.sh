#!/usr/bin/env bash
# Man pages from omma's own --help (help2man): OUT/omma.1 for the command and its list of commands,
# and OUT/omma-COMMAND.1 for every command (git's convention: `man omma-stitch`), each with the
# command's options and examples. Usage: scripts/man.sh PATH/TO/omma OUT_DIR
set -euo pipefail
omma="$(realpath "$1")"
out="$2"
mkdir -p "$out"
version="$("$omma" --version | awk 'NR == 1 {print $2}')"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# help2man runs PROGRAM --help; one small wrapper per command shows that command's help, named as
# the user types it (exec -a: the usage line reads "omma stitch", not the build path).
page() {  # page NAME DESCRIPTION ARGS...
  local name="$1" desc="$2"
  shift 2
  printf '#!/usr/bin/env bash\nexec -a omma "%s" %s "$@"\n' "$omma" "$*" > "$tmp/$name"
  chmod +x "$tmp/$name"
  help2man --no-info --no-discard-stderr --section=1 --source="omma $version" \
           --version-string="$version" --name="$desc" --output="$out/$name.1.tmp" "$tmp/$name"
  # EXAMPLES as the help shows them, one command per line (help2man would fill them into a paragraph).
  {
    sed '/^\.SH EXAMPLES/,$d' "$out/$name.1.tmp"
    printf '.SH EXAMPLES\n.nf\n'
    "$tmp/$name" --help | sed -n '/^Examples:$/,${/^Examples:$/d;s/\\/\\\\/g;s/-/\\-/g;p}'
    printf '.fi\n'
  } > "$out/$name.1.tmp2"
  rm "$out/$name.1.tmp"
  mv "$out/$name.1.tmp2" "$out/$name.1"
}
page omma "design, calibrate and run compound-eye (multi-camera dome) panoramic cameras"
# The commands: the first word of each line under "Subcommands:" in omma --help.
"$omma" --help | awk '/^Subcommands:/{f=1;next} f&&/^  [a-z]/{print $1} f&&/^$/{f=0}' | while read -r cmd; do
  # NAME: the first line of the command's help up to its first colon, bracket or full stop.
  desc="$("$omma" "$cmd" --help | sed -n '1{s/ *[(:.].*//;p}')"
  page "omma-$cmd" "$desc" "$cmd"
done
