#!/usr/bin/env bash
# The compensation end to end through LinuxCNC's motion controller (end_to_end.py): for each
# thermal state and program, the twin's `run --compensate` reference, a headless LinuxCNC
# session with the vmc_comp component in the servo thread (between joint.N.motor-pos-cmd and
# the simulated drive) fed with the twin's sensor readings at that state, a halsampler log at
# the servo rate, and `vmc-twin replay` of that log on the twin in the same state.
#
#   end-to-end.sh --model MODEL_JSON --out DIR [--program P.ngc ...]
#                 [--state NAME=WARMUP[+WARMUP...] ...] [--seed N] [--machine TOML]
#                 [--vmc BIN] [--module SO] [--rrd] [--timeout S]
#                 [--min-reduction R] [--max-gap-points P] [--run-option OPT ...]
#   end-to-end.sh --probe      # exit 0 if it can run here, 77 with the reason if not
#
# Defaults: programs diag_xy.ngc (XY face diagonal) and diag_ppp.ngc (body diagonal), states
# after warmup_2h_4000rpm.ngc and after warmup_4h_8000rpm.ngc, seed 1. Without --module the
# component is built first (build-comp.sh, target/linuxcnc/vmc_comp.so).
#
# Exit status: 0 every program and state meets the acceptance (reduction of RMS |E| through
# LinuxCNC >= 80 % and within 2 points of run --compensate); 1 one does not, or a step failed;
# 2 bad input; 77 LinuxCNC (root, packages, namespaces) not available here.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
export PYTHONDONTWRITEBYTECODE=1

reason=$("$here/hal-check.sh" --probe 2>&1) || {
  status=$?
  if [ "$status" = 77 ]; then
    echo "end-to-end: skipped: ${reason#hal-check: skipped: }"
    exit 77
  fi
  echo "$reason" >&2
  exit 1
}
if ! command -v linuxcnc >/dev/null || ! command -v halsampler >/dev/null; then
  echo "end-to-end: skipped: LinuxCNC's linuxcnc or halsampler is missing (deploy/linuxcnc/install.sh)"
  exit 77
fi
if [ "$(id -u)" != 0 ]; then
  echo "end-to-end: skipped: not root (the session shows the module to loadrt in a private mount namespace)"
  exit 77
fi
if [ "${1:-}" = "--probe" ]; then
  echo "end-to-end: LinuxCNC $(dpkg-query -W -f='${Version}' linuxcnc-uspace 2>/dev/null) is available"
  exit 0
fi
case " $* " in
  *" --module "*) ;;
  *) "$here/build-comp.sh" >/dev/null ;;
esac
exec python3 "$here/end_to_end.py" "$@"
