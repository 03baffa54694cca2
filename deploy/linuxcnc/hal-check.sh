#!/usr/bin/env bash
# Loads the HAL component vmc_comp (build-comp.sh) with a model file into a bare HAL (halrun: a
# 1 ms servo thread, no motion controller), drives its pins through a list of steps
# (hal_check.py: sensor samples and commanded positions) and writes what it gives back, at full
# precision, with the function's tmax.
#
#   hal-check.sh [--module PATH/vmc_comp.so] [--period-ns NS] [--timeout S]
#                [--rpm RPM] [--feeds FX,FY,FZ] MODEL_JSON STEPS_CSV OUT_CSV
#   hal-check.sh --probe     # exit 0 if it can run here, 77 with the reason if not
#
# The spindle speed (rpm) and axis feeds (mm/min) are set before the thread starts and held.
# loadrt takes module names, not paths: the module is shown in /usr/lib/linuxcnc/modules
# through an overlay mount in a private mount namespace (as root; nothing is installed), or
# must already be installed there (not root).
#
# Exit status: 0 done; 1 the HAL session failed; 2 bad input; 77 not available here.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
export PYTHONDONTWRITEBYTECODE=1
modules=/usr/lib/linuxcnc/modules

# Inside the namespaces (re-executed by ourselves).
if [ "${1:-}" = "--inside-namespace" ]; then
  run=$2
  mount --make-rprivate /
  mount -t overlay overlay -o "lowerdir=$run/modules:$modules" "$modules"
  private=$run/.private-tmp
  mkdir -p "$private"
  chmod 1777 "$private"
  case "$run" in
    /tmp/*)
      # The run folder is under /tmp: show it at the same path in the private /tmp.
      rel=${run#/tmp/}
      mkdir -p "$private/$rel"
      mount --bind "$run" "$private/$rel"
      ;;
  esac
  mount --rbind "$private" /tmp
  mkdir -p /tmp/rtapi
  chown "$RTAPI_UID" /tmp/rtapi
  export RTAPI_FIFO_PATH=/tmp/rtapi/rtapi_fifo
  exec halrun -f "$run/check.hal"
fi

module=$repo/target/linuxcnc/vmc_comp.so
period_ns=1000000
timeout_s=60
rpm=0
feeds=0,0,0
probe=no
positional=()
while [ $# -gt 0 ]; do
  case "$1" in
    --module) module=$2; shift 2 ;;
    --period-ns) period_ns=$2; shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --rpm) rpm=$2; shift 2 ;;
    --feeds) feeds=$2; shift 2 ;;
    --probe) probe=yes; shift ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "hal-check: error: unknown option $1" >&2; exit 2 ;;
    *) positional+=("$1"); shift ;;
  esac
done

unavailable() {
  if ! command -v halrun >/dev/null; then
    echo "LinuxCNC is not installed (no halrun on PATH; deploy/linuxcnc/install.sh)"
  elif ! command -v halcompile >/dev/null || [ ! -e /usr/include/linuxcnc/hal.h ]; then
    echo "LinuxCNC's development files are not installed (linuxcnc-uspace-dev, python3-yapps)"
  elif ! /usr/bin/python3 -c 'import hal' 2>/dev/null; then
    echo "LinuxCNC's Python module hal does not load in /usr/bin/python3"
  elif [ "$(id -u)" != 0 ]; then
    [ -e "$modules/vmc_comp.so" ] || echo "not root and vmc_comp.so is not installed in $modules"
  elif ! unshare --ipc --mount --pid --fork --mount-proc true 2>/dev/null; then
    echo "root, but new namespaces are refused (needed to show the module to loadrt)"
  fi
}
reason=$(unavailable)
if [ -n "$reason" ]; then
  echo "hal-check: skipped: $reason"
  exit 77
fi
if [ "$probe" = yes ]; then
  echo "hal-check: LinuxCNC $(dpkg-query -W -f='${Version}' linuxcnc-uspace 2>/dev/null) is available"
  exit 0
fi
if [ ${#positional[@]} -ne 3 ]; then
  echo "hal-check: error: expected MODEL_JSON STEPS_CSV OUT_CSV (hal-check.sh --help)" >&2
  exit 2
fi
model=$(realpath "${positional[0]}")
steps=$(realpath "${positional[1]}")
out=$(realpath -m "${positional[2]}")
for f in "$model" "$steps" "$module"; do
  [ -f "$f" ] || { echo "hal-check: error: no file $f" >&2; exit 2; }
done
IFS=, read -r fx fy fz <<<"$feeds"

# The run folder: readable by rtapi_app's fallback user (it loads the model file).
run=$(mktemp -d "${TMPDIR:-/tmp}/vmc-hal-check.XXXXXX")
trap 'rm -rf "$run"' EXIT
chmod 755 "$run"
mkdir -p "$run/modules"
cp "$module" "$run/modules/vmc_comp.so"
cp "$model" "$run/model.json"
cp "$steps" "$run/steps.csv"
cp "$here/hal_check.py" "$run/hal_check.py"
chmod -R a+rX "$run"
cat >"$run/check.hal" <<EOF
loadrt threads name1=servo period1=$period_ns
loadrt vmc_comp model=$run/model.json
addf vmc-comp.0 servo
setp vmc-comp.0.spindle-speed-rpm $rpm
setp vmc-comp.0.feed-x $fx
setp vmc-comp.0.feed-y $fy
setp vmc-comp.0.feed-z $fz
start
loadusr -w /usr/bin/python3 $run/hal_check.py --period-s $(awk -v n="$period_ns" 'BEGIN { print n / 1e9 }') $run/steps.csv $run/out.csv
show funct vmc-comp.0
show param vmc-comp.0
show thread servo
EOF

status=0
if [ "$(id -u)" = 0 ]; then
  export RTAPI_UID=$(id -u nobody 2>/dev/null || echo 65534)
  timeout -s KILL "$timeout_s" unshare --ipc --mount --pid --fork --mount-proc --kill-child \
    "$0" --inside-namespace "$run" || status=$?
else
  timeout -k 10 "$timeout_s" halrun -f "$run/check.hal" || status=$?
fi
if [ "$status" != 0 ] || [ ! -f "$run/out.csv" ]; then
  echo "hal-check: the HAL session failed (status $status)" >&2
  exit 1
fi
cp "$run/out.csv" "$out"
