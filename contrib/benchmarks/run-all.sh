#!/usr/bin/env bash
# Build and run every PeriDEAL benchmark; print one `key: value` line per
# figure (see doc/benchmarks.md for the meaning of each key).
#
# Environment:
#   BUILD_DIR   build directory (default <repo>/build-bench)
#   JOBS        parallel build jobs (default: nproc)
#   RANKS       MPI ranks per benchmark (default 1)
#   CASES       cases to run (default "2d_m3 2d_m12 3d_m3 3d_m12")
#   SECONDS_PER_LOOP  target wall time of each timed loop (default 1)
#   SKIP_BUILD  1 to use an existing build
set -euo pipefail

top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${BUILD_DIR:-$top/build-bench}"
jobs="${JOBS:-$(nproc)}"
ranks="${RANKS:-1}"
cases="${CASES:-2d_m3 2d_m12 3d_m3 3d_m12}"
loop_seconds="${SECONDS_PER_LOOP:-1}"

# Dependencies: nothing is installed when deal.II is already there.
have_dealii() {
  [ -n "${DEAL_II_DIR:-}${deal_II_DIR:-}" ] && return 0
  dpkg-query -W -f='${Status}' libdeal.ii-dev 2>/dev/null | grep -q "install ok installed" && return 0
  compgen -G "/usr/lib/*/cmake/deal.II/deal.IIConfig.cmake" > /dev/null && return 0
  compgen -G "/usr/share/cmake/deal.II/deal.IIConfig.cmake" > /dev/null && return 0
  return 1
}
if ! have_dealii; then
  if [ -x "$top/contrib/utilities/install-dependencies.sh" ]; then
    "$top/contrib/utilities/install-dependencies.sh" >&2
  else
    echo "run-all: deal.II not found and contrib/utilities/install-dependencies.sh missing" >&2
  fi
fi

if [ "${SKIP_BUILD:-0}" != 1 ]; then
  mkdir -p "$build"
  cmake -S "$top" -B "$build" -DCMAKE_BUILD_TYPE=Release -DPERIDEAL_BUILD_BENCHMARKS=ON \
    -DPERIDEAL_ENABLE_TESTS=OFF > "$build/benchmark-configure.log" 2>&1 \
    || { cat "$build/benchmark-configure.log" >&2; exit 1; }
  cmake --build "$build" --target diffusion_benchmark -j"$jobs" > "$build/benchmark-build.log" 2>&1 \
    || { tail -60 "$build/benchmark-build.log" >&2; exit 1; }
fi
exe="$build/contrib/benchmarks/diffusion_benchmark"
[ -x "$exe" ] || { echo "run-all: $exe was not built" >&2; exit 1; }

export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMP_NUM_THREADS=1
launch=()
if command -v mpirun > /dev/null; then
  launch=(mpirun -np "$ranks")
elif [ "$ranks" != 1 ]; then
  echo "run-all: mpirun not found, cannot run on $ranks ranks" >&2
  exit 1
fi
extra=()

results="$build/benchmark-results.txt"
: > "$results"
model="$(lscpu 2>/dev/null | sed -n 's/^Model name:[[:space:]]*//p' | head -1)"
echo "machine_cpu: ${model:-unknown}" | tee -a "$results"
echo "machine_cores: $(getconf _NPROCESSORS_ONLN)" | tee -a "$results"
echo "machine_load_average_before: $(cut -d' ' -f1 /proc/loadavg)" | tee -a "$results"
echo "mpi_ranks: $ranks" | tee -a "$results"

# One process per case, so that RSS figures belong to one case.
for c in $cases; do
  "${launch[@]}" "$exe" --case "$c" --seconds "$loop_seconds" "${extra[@]}" \
    | grep -v '^setup_seconds_per_million_bonds:' | tee -a "$results"
done

# Aggregate setup cost over all cases: sum of setup seconds / sum of bonds.
awk -F': ' '
  /^diffusion_.*_setup_seconds: / { s += $2 }
  /^diffusion_.*_bonds: /         { b += $2 }
  END { if (b > 0) printf "setup_seconds_per_million_bonds: %.6g\n", s / (b / 1e6) }
' "$results" | tee -a "$results"
echo "run-all: results in $results" >&2
