#!/usr/bin/env bash
# Set up, build and run the test suite (everything but the 'long' label).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1
bash "$top/contrib/utilities/install-dependencies.sh"
bash "$top/contrib/utilities/build.sh"
cd "${BUILD_DIR:-$top/build}"
ctest -LE long -j2 --output-on-failure --timeout 1200 "$@"
