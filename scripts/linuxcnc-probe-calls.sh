#!/usr/bin/env bash
# Regenerates the output of LinuxCNC's stand-alone interpreter `rs274 -g` for the calling
# programs in crates/vmc-gcode/tests/data/linuxcnc/probe-calls/*.ngc: each calls one of the
# LinuxCNC example subroutines that probe with G38.x (its folder under nc_files is named on
# the program's first line, `(subroutines: DIR)`), then moves to the probe parameters
# #5061…#5063 and A to #5070 so that their values show in the moves. The output is stored as
# <program>.out beside each program; crates/vmc-gcode/tests/linuxcnc_probe_calls.rs compares our
# moves with it. Needs `rs274` (default /usr/bin/rs274; override with RS274=...).
set -euo pipefail
cd "$(dirname "$0")/.."
RS274=${RS274:-/usr/bin/rs274}
corpus=crates/vmc-gcode/tests/data/linuxcnc
tools=$(realpath $corpus/tool.tbl)
# rs274 keeps its tool table in $HOME/.tool.mmap: a private HOME.
HOME=$(mktemp -d)
export HOME
trap 'rm -rf "$HOME"' EXIT
for prog in "$corpus"/probe-calls/*.ngc; do
  dir=$(head -n 1 "$prog" | sed -E 's/^\(subroutines: (.*)\)$/\1/')
  abs=$(realpath "$prog")
  # rs274 looks subroutine files up in its working folder.
  (cd "$corpus/nc_files/$dir" && timeout 20 "$RS274" -g -t "$tools" "$abs" </dev/null >"$abs.out" 2>&1) || true
  echo "$prog: $(grep -c STRAIGHT_PROBE "$prog.out" || true) probe moves"
done
