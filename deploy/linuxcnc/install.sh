#!/usr/bin/env bash
# Installs LinuxCNC (uspace: runs without a real-time kernel) from the distribution's packages,
# for the headless runs of deploy/linuxcnc (Debian 12 "bookworm" has linuxcnc-uspace 2.9).
#
#   deploy/linuxcnc/install.sh
#
# Idempotent and quiet: does nothing when LinuxCNC is already installed. Where it cannot
# install (not root, no apt-get, no such package) it says why and exits 0, so that a CI job
# carries on and the LinuxCNC tests skip with that reason (VMC_REQUIRE_LINUXCNC=1 turns such a
# skip into a failure). Any other failure of apt-get exits non-zero.
set -euo pipefail

# The development files (halcompile, hal.h) build the HAL component vmc_comp (build-comp.sh).
packages=(linuxcnc-uspace linuxcnc-uspace-dev python3-yapps)

installed=yes
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || installed=no
done
if [ "$installed" = yes ] && command -v linuxcnc >/dev/null; then
  echo "install: LinuxCNC $(dpkg-query -W -f='${Version}' linuxcnc-uspace) is already installed"
  exit 0
fi
if ! command -v apt-get >/dev/null; then
  echo "install: no apt-get here; install LinuxCNC (linuxcnc-uspace) by hand to run these checks"
  exit 0
fi
if [ "$(id -u)" != 0 ]; then
  echo "install: not root; run as root (or sudo apt-get install linuxcnc-uspace) to install it"
  exit 0
fi

export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
if ! apt-cache show "${packages[@]}" >/dev/null 2>&1; then
  echo "install: the packages ${packages[*]} are not in this system's package sources" \
    "(Debian 12 has it in main); LinuxCNC checks will skip"
  exit 0
fi
apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
echo "install: LinuxCNC $(dpkg-query -W -f='${Version}' linuxcnc-uspace) installed"
