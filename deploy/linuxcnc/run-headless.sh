#!/usr/bin/env bash
# Runs one headless LinuxCNC session of a run folder (see assemble.py): `linuxcnc INI`, whose
# display is driver.py; returns the driver's exit status. Output of LinuxCNC and the driver
# goes to stdout/stderr (RUNTESTS=1: without a terminal the linuxcnc script would otherwise
# send it to temporary files it deletes).
#
#   run-headless.sh [--timeout SECONDS] RUN_DIR/vmc-machine.ini
#
# As root (the sandbox and CI containers), rtapi_app needs a fallback user: RTAPI_UID (nobody)
# and RTAPI_FIFO_PATH, the path of its socket (not a folder), in a folder that user can reach
# and write.
#
# HAL modules: a folder `modules` in the run folder (e.g. vmc_comp.so) is shown to loadrt in
# /usr/lib/linuxcnc/modules through an overlay mount inside the namespaces (as root); without
# namespaces the modules must be installed there.
#
# Isolation and clean-up: as root, the session runs in its own PID, IPC and mount namespaces
# with a private /tmp. LinuxCNC's start script finds and kills "its" processes by name
# (pidof milltask, ...), keeps its lock in /tmp/linuxcnc.lock and its HAL and NML data in
# System V shared memory: in the namespaces none of that can touch another LinuxCNC on the same
# machine, and when the session ends or the timeout fires, the kernel ends every process left
# in the PID namespace (rtapi_app included) and frees its shared memory. Without namespaces
# (not root, or unshare refused) the session runs directly and refuses to start while another
# LinuxCNC holds /tmp/linuxcnc.lock.
set -euo pipefail

timeout_s=300
if [ "${1:-}" = "--timeout" ]; then
  timeout_s=$2
  shift 2
fi

# Inside the namespaces (re-executed by ourselves): private /tmp, the run folder kept at its
# path, then LinuxCNC.
if [ "${1:-}" = "--inside-namespace" ]; then
  ini=$2
  run=$(dirname "$ini")
  mount --make-rprivate /
  if [ -d "$run/modules" ]; then
    # HAL modules of the run folder (e.g. vmc_comp.so): loadrt takes names, not paths, so
    # they are shown in LinuxCNC's modules folder through an overlay (nothing installed).
    modules=/usr/lib/linuxcnc/modules
    mount -t overlay overlay -o "lowerdir=$run/modules:$modules" "$modules"
  fi
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
  if [ -n "${RTAPI_UID:-}" ]; then
    # rtapi_app's socket in the private /tmp, whatever the run folder's permissions.
    mkdir -p /tmp/rtapi
    chown "$RTAPI_UID" /tmp/rtapi
    export RTAPI_FIFO_PATH=/tmp/rtapi/rtapi_fifo
  fi
  exec linuxcnc "$ini"
fi

if [ $# -ne 1 ]; then
  echo "usage: run-headless.sh [--timeout SECONDS] RUN_DIR/vmc-machine.ini" >&2
  exit 2
fi
ini=$(realpath "$1")
run=$(dirname "$ini")
if [ "$run" = /tmp ] || [ "$run" = / ]; then
  echo "run-headless: the run folder must be a folder of its own, not $run" >&2
  exit 2
fi
if ! command -v linuxcnc >/dev/null; then
  echo "run-headless: LinuxCNC is not installed (deploy/linuxcnc/install.sh)" >&2
  exit 77
fi

export RUNTESTS=1
export HOME=$run/home
mkdir -p "$HOME"
isolated=no
if [ "$(id -u)" = 0 ]; then
  export RTAPI_UID=$(id -u nobody 2>/dev/null || echo 65534)
  if unshare --ipc --mount --pid --fork --mount-proc true 2>/dev/null; then
    isolated=yes
  else
    # The socket in the run folder: every folder on the way must be readable and searchable
    # by that user and by root's group, which rtapi_app keeps (it refuses the bind
    # otherwise; mktemp -d makes 0700 folders).
    mkdir -p "$run/rtapi"
    chown "$RTAPI_UID" "$run/rtapi"
    chmod go+rx "$run"
    export RTAPI_FIFO_PATH=$run/rtapi/rtapi_fifo
  fi
fi

status=0
if [ "$isolated" = yes ]; then
  # On the timeout unshare gets SIGKILL (it waits through SIGTERM); --kill-child then sends
  # SIGKILL to the namespace's first process and the kernel ends every other process of the
  # namespace with it.
  timeout -s KILL "$timeout_s" unshare --ipc --mount --pid --fork --mount-proc --kill-child \
    "$0" --inside-namespace "$ini" || status=$?
else
  if [ -e /tmp/linuxcnc.lock ]; then
    echo "run-headless: another LinuxCNC is running (/tmp/linuxcnc.lock); not starting" >&2
    exit 1
  fi
  # On SIGTERM the linuxcnc script shuts its session down itself.
  timeout -k 30 "$timeout_s" linuxcnc "$ini" || status=$?
fi
if [ "$status" = 124 ] || [ "$status" = 137 ]; then
  echo "run-headless: LinuxCNC did not finish within $timeout_s s and was stopped" >&2
fi
exit "$status"
