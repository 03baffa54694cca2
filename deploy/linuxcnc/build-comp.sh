#!/usr/bin/env bash
# Builds the HAL component vmc_comp (vmc_comp.comp, the glue) with the vmc-rtcomp static
# library linked in: a LinuxCNC uspace real-time module vmc_comp.so.
#
#   build-comp.sh [--out DIR] [--lib PATH/libvmc_rtcomp.a]
#
# Without --lib it builds the library first (cargo build -p vmc-rtcomp --release). The module
# is compiled and linked as halcompile's Makefile.modinc does for a uspace module (its flags;
# `ld -r`, the .rtapi_export section as the version script, so that only the HAL entry points
# are exported), with the static library added: halcompile's --extra-link-args apply to
# userspace components only. Install with `cp DIR/vmc_comp.so /usr/lib/linuxcnc/modules/`
# (loadrt takes module names, not paths), or see hal-check.sh for a private mount.
#
# Exit status: 0 built (prints the module's path); 2 bad input; 77 the LinuxCNC development
# files (linuxcnc-uspace-dev, python3-yapps: halcompile, hal.h) are not installed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
out=$repo/target/linuxcnc
lib=
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    --lib) lib=$2; shift 2 ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "build-comp: error: unknown argument $1" >&2; exit 2 ;;
  esac
done

if ! command -v halcompile >/dev/null || [ ! -e /usr/include/linuxcnc/hal.h ]; then
  echo "build-comp: skipped: halcompile or hal.h missing (apt-get install linuxcnc-uspace-dev python3-yapps)"
  exit 77
fi
if [ -z "$lib" ]; then
  (cd "$repo" && cargo build -q -p vmc-rtcomp --release)
  lib=$repo/target/release/libvmc_rtcomp.a
fi
if [ ! -f "$lib" ]; then
  echo "build-comp: error: no static library at $lib" >&2
  exit 2
fi
mkdir -p "$out"
work=$(mktemp -d "$out/.build.XXXXXX")
trap 'rm -rf "$work"' EXIT

halcompile --preprocess -o "$work/vmc_comp.c" "$here/vmc_comp.comp" >/dev/null
# Makefile.modinc's flags for a uspace module.
cflags=(-Os -g -I. -I/usr/include/linuxcnc -I"$repo/crates/vmc-rtcomp/include" -DUSPACE
  -fno-fast-math -mieee-fp -fno-unsafe-math-optimizations -DRTAPI -D_GNU_SOURCE -Drealtime
  -D__MODULE__ -fno-builtin-sin -fno-builtin-cos -fno-builtin-sincos -Wframe-larger-than=2560
  -DSIM -fPIC -Wall -Werror)
gcc "${cflags[@]}" -c -o "$work/vmc_comp.o" "$work/vmc_comp.c"
# The exported symbols: those halcompile put in the .rtapi_export section.
ld -d -r -o "$work/vmc_comp.tmp" "$work/vmc_comp.o"
objcopy -j .rtapi_export -O binary "$work/vmc_comp.tmp" "$work/vmc_comp.sym"
{
  echo '{ global : '
  tr -s '\0' <"$work/vmc_comp.sym" | xargs -r0 printf '%s;\n' | grep .
  echo 'local : * ; };'
} >"$work/vmc_comp.ver"
gcc -shared -Bsymbolic -Wl,--version-script,"$work/vmc_comp.ver" -Wl,--gc-sections \
  -o "$work/vmc_comp.so" "$work/vmc_comp.o" "$lib" -lm -lpthread -ldl
chmod -x "$work/vmc_comp.so"
mv "$work/vmc_comp.so" "$out/vmc_comp.so"
echo "$out/vmc_comp.so"
