#!/usr/bin/env bash
# Set up, build and run the main job: the perideal driver on the small
# default parameter file (2D corrosion of a disk); output in ./output-default.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
bash "$top/contrib/utilities/install-dependencies.sh"
bash "$top/contrib/utilities/build.sh"
mpirun --oversubscribe -np "${NP:-2}" "${BUILD_DIR:-$top/build}/perideal" "$top/contrib/parameters/default.prm"
