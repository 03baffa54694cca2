#!/usr/bin/env bash
# Regenerates the expected canonical output of LinuxCNC's stand-alone interpreter for every
# example program in crates/vmc-gcode/tests/data/linuxcnc/nc_files (recursively):
#   crates/vmc-gcode/tests/data/linuxcnc/rs274-expected/<relative path>.out   program accepted: rs274 -g output
#   crates/vmc-gcode/tests/data/linuxcnc/rs274-expected/REFUSED.txt           program refused: path and error line
# and the output for the CAM-style example trajectories/cam_pocket_drill.ngc (tests/data/cam/).
# The tool table crates/vmc-gcode/tests/data/linuxcnc/tool.tbl is in inches, as rs274 reads it without an INI
# file. In mm: T1 Ø12 × 150 long, T2 Ø6 × 100, T3 Ø3 × 80, T4 Ø20 × 120 (crates/vmc-gcode/tests/linuxcnc_corpus.rs
# gives our interpreter the same tools).
# Needs LinuxCNC's `rs274` (default /usr/bin/rs274; override with RS274=...).
set -euo pipefail
cd "$(dirname "$0")/.."
RS274=${RS274:-/usr/bin/rs274}
corpus=crates/vmc-gcode/tests/data/linuxcnc
src=$corpus/nc_files
dst=$corpus/rs274-expected
tools=$(realpath $corpus/tool.tbl)
# rs274 keeps its tool table in $HOME/.tool.mmap: a private HOME keeps another rs274 running
# at the same time from overwriting it.
HOME=$(mktemp -d)
export HOME
trap 'rm -rf "$HOME"' EXIT
rm -rf "$dst"
mkdir -p "$dst"
refused=$dst/REFUSED.txt
: >"$refused"
accepted=0
while IFS= read -r -d '' prog; do
  rel=${prog#"$src"/}
  out=$dst/$rel.out
  mkdir -p "$(dirname "$out")"
  # rs274 runs in the program's folder (subroutine files are looked up there) and reads
  # nothing from stdin; a program that never ends is cut off after 20 s.
  text=$(cd "$(dirname "$prog")" && timeout 20 "$RS274" -g -t "$tools" "$(basename "$prog")" </dev/null 2>&1) || true
  # An accepted program ends with PROGRAM_END() (or reaches the end of the file); a refused
  # one prints its error message and the offending line after the last canonical call.
  last=$(printf '%s\n' "$text" | grep -Ev '^ *[0-9]+ N[^ ]* +[A-Z_0-9]+\(' | grep -v '^executing$' | grep -v '^$' | head -n 2 | tr '\n' ' ' || true)
  if [ -n "$last" ]; then
    printf '%s\t%s\n' "$rel" "$last" >>"$refused"
  else
    # Drop the line counter column and the trailing "executing" marker: stable output.
    printf '%s\n' "$text" | sed -En 's/^ *[0-9]+ (N[^ ]* +[A-Z_0-9]+\()/\1/p' >"$out"
    accepted=$((accepted + 1))
  fi
done < <(find "$src" -name '*.ngc' -print0 | sort -z)
echo "rs274 accepted $accepted programs; refused $(wc -l <"$refused") (see $refused)"

# The CAM-style example program (tests/cam_example.rs), with the same tool table.
cam=trajectories/cam_pocket_drill.ngc
(cd "$(dirname "$cam")" && "$RS274" -g -t "$tools" "$(basename "$cam")" </dev/null 2>/dev/null) |
  sed -En 's/^ *[0-9]+ (N[^ ]* +[A-Z_0-9]+\()/\1/p' >tests/data/cam/cam_pocket_drill.out
echo "rs274 output of $cam written to tests/data/cam/cam_pocket_drill.out"
