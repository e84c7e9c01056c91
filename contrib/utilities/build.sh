#!/usr/bin/env bash
# Configure and build PeriDEAL (Release) into ${BUILD_DIR:-build}.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${BUILD_DIR:-$top/build}"
# Paths relative to the checkout let ccache reuse objects across clones and
# worktrees of the same tree (CI clones into a new directory every run).
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$top}"
# deal.II's Release flags carry -g, for which ccache would hash the build
# directory too.
export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
cmake -S "$top" -B "$build" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" > "$build.configure.log" 2>&1 \
  || { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j"$(nproc)"
