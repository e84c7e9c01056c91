#!/usr/bin/env bash
# Install what PeriDEAL needs from Debian's packages (idempotent; run as root
# or with sudo available). deal.II 9.4 brings MPI, p4est, Trilinos and PETSc.
set -euo pipefail
packages=(libdeal.ii-dev openmpi-bin libeigen3-dev libboost-dev gnuplot-nox
          cmake g++ make ccache numdiff)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-dependencies: all packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
echo "install-dependencies: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" > /tmp/perideal-apt.log 2>&1 \
  || { tail -50 /tmp/perideal-apt.log; exit 1; }
echo "install-dependencies: done"
