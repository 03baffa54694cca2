#!/usr/bin/env bash
# Loads an export folder's LinuxCNC compensation tables (comp-tables.ini + joint*.comp, as
# `vmc-twin export --format linuxcnc` writes them) into a headless LinuxCNC of the machine,
# moves every joint to eight positions from below and from above, and compares
# joint.N.motor-pos-cmd - joint.N.pos-cmd with the tables (comp_check.py).
#
#   comp-check.sh [--machine TOML] [--run-dir DIR] [--tol-mm MM] [--timeout S] [--strict]
#                 [--servo-period-ns NS] EXPORT_DIR
#   comp-check.sh --probe        # exit 0 if LinuxCNC can run here, 77 with the reason if not
#
# Exit status: 0 every arrival at the table's value (default tolerance 1e-6 mm) or held by
# LinuxCNC's compensation ramp dead band (--strict: those fail too); 1 a mismatch or a failed
# session; 2 bad input; 77 LinuxCNC not available (a test skips). The run folder (INI, tables,
# CSV comp-check.csv) is kept when given with --run-dir or when the check fails.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
export PYTHONDONTWRITEBYTECODE=1
repo=$(cd "$here/../.." && pwd)
machine=$repo/machines/vmc-reference.toml
run_dir=
tol_mm=1e-6
timeout_s=240
probe=no
strict=
servo_period_ns=1000000
export_dir=
while [ $# -gt 0 ]; do
  case "$1" in
    --machine) machine=$2; shift 2 ;;
    --run-dir) run_dir=$2; shift 2 ;;
    --tol-mm) tol_mm=$2; shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --probe) probe=yes; shift ;;
    --strict) strict=--strict; shift ;;
    --servo-period-ns) servo_period_ns=$2; shift 2 ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "comp-check: error: unknown option $1" >&2; exit 2 ;;
    *) export_dir=$1; shift ;;
  esac
done

# LinuxCNC's Python modules live in the distribution's Python.
unavailable() {
  if ! command -v linuxcnc >/dev/null; then
    echo "LinuxCNC is not installed (no linuxcnc on PATH; deploy/linuxcnc/install.sh)"
  elif ! /usr/bin/python3 -c 'import linuxcnc, hal' 2>/dev/null; then
    echo "LinuxCNC's Python modules do not load in /usr/bin/python3"
  elif ! python3 -c 'import tomllib' 2>/dev/null; then
    echo "python3 is older than 3.11 (no tomllib)"
  fi
}
reason=$(unavailable)
if [ -n "$reason" ]; then
  echo "comp-check: skipped: $reason"
  exit 77
fi
if [ "$probe" = yes ]; then
  version=$(dpkg-query -W -f='${Version}' linuxcnc-uspace 2>/dev/null || echo "(version unknown)")
  echo "comp-check: LinuxCNC $version is available"
  exit 0
fi
if [ -z "$export_dir" ]; then
  echo "comp-check: error: no export folder given (comp-check.sh --help)" >&2
  exit 2
fi

keep=yes
if [ -z "$run_dir" ]; then
  run_dir=$(mktemp -d "${TMPDIR:-/tmp}/vmc-linuxcnc.XXXXXX")
  keep=no
fi
t0=$(date +%s.%N)
if ! ini=$(python3 "$here/comp_check.py" prepare --machine "$machine" \
  --tables "$export_dir" --run-dir "$run_dir" --timeout-s "$timeout_s" \
  --servo-period-ns "$servo_period_ns"); then
  [ "$keep" = no ] && rm -rf "$run_dir"
  exit 2
fi
status=0
"$here/run-headless.sh" --timeout "$((${timeout_s%.*} + 30))" "$ini" || status=$?
t1=$(date +%s.%N)
if [ "$status" != 0 ]; then
  echo "comp-check: the LinuxCNC session failed (status $status); run folder kept: $run_dir" >&2
  [ "$status" = 77 ] && exit 77
  exit 1
fi
python3 "$here/comp_check.py" compare --run-dir "$run_dir" --tol-mm "$tol_mm" $strict \
  || status=$?
t2=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" -v c="$t2" \
  'BEGIN { printf "comp-check: LinuxCNC session %.1f s, whole check %.1f s\n", b - a, c - a }'
if [ "$status" != 0 ]; then
  echo "comp-check: run folder kept: $run_dir" >&2
  exit "$status"
fi
[ "$keep" = no ] && rm -rf "$run_dir"
exit 0
