#!/usr/bin/env bash
# Build and run every PeriDEAL benchmark; print one `key: value` line per
# figure (see doc/benchmarks.md for the meaning of each key).
#
# Environment:
#   BUILD_DIR   build directory (default <repo>/build-bench)
#   JOBS        parallel build jobs (default: nproc)
#   RANKS       MPI ranks per benchmark (default 1)
#   CASES       diffusion cases (default "2d_m3 2d_m12 3d_m3 3d_m12")
#   PMB_CASES   PMB cases (default "2d_m3 2d_m12 2d_m24 3d_m3 3d_m12")
#   PMB_2D_STEPS  timed Verlet steps (1..S, from the initial state) of the
#               2d_m12 and 2d_m24 cases (default 30: 5-10 s per repeat)
#   PMB_2D_REPEATS  fresh-state runs of them, the keys are their median
#               (default 3)
#   PMB_3D_STEPS  Verlet steps of the 3d_m3 case, run by both PeriDEAL and
#               LAMMPS (default 50)
#   PMB_3D_ROUNDS  interleaved rounds of the 3D comparison, each one
#               PeriDEAL process and one LAMMPS run (default 5)
#   PMB_3D_REPEATS  fresh-state PeriDEAL runs per round, their median is the
#               round's figure (default 3)
#   LAMMPS      0 to skip the LAMMPS comparison (default 1: run it, installing
#               the Debian packages lammps and lammps-examples when `lmp` is
#               missing)
#   SECONDS_PER_LOOP  target wall time of each timed loop (default 1)
#   ABC_STEPS   time steps of the ABC overhead measurement (default 2000)
#   HALF_DERIVATIVE_ROUNDS  interleaved rounds of half_derivative_benchmark (default 3)
#   CORROSION_STEPS  timed steps of the 3D corrosion benchmark (default 100)
#   KW_ARGS     options of kw_multiadaptive_benchmark (default: its CI-size case)
#   KW_HYBRID_ARGS  options of kw_hybrid_benchmark (default "--dx 0.25 --m 8",
#               the source's lattice of Table 3.3;
#               empty string: skip the Kalthoff-Winkler hybrid case)
#   SKIP_BUILD  1 to use an existing build
set -euo pipefail

top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${BUILD_DIR:-$top/build-bench}"
jobs="${JOBS:-$(nproc)}"
ranks="${RANKS:-1}"
cases="${CASES-2d_m3 2d_m12 3d_m3 3d_m12}"
pmb_cases="${PMB_CASES-2d_m3 2d_m12 2d_m24 3d_m3 3d_m12}"
pmb_2d_steps="${PMB_2D_STEPS:-30}"
pmb_2d_repeats="${PMB_2D_REPEATS:-3}"
pmb_3d_steps="${PMB_3D_STEPS:-50}"
pmb_3d_rounds="${PMB_3D_ROUNDS:-5}"
pmb_3d_repeats="${PMB_3D_REPEATS:-3}"
use_lammps="${LAMMPS:-1}"
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
  cmake --build "$build" --target diffusion_benchmark pmb_benchmark abc_benchmark corrosion_benchmark kw_multiadaptive_benchmark kw_hybrid_benchmark fem_abc_benchmark half_derivative_benchmark -j"$jobs" > "$build/benchmark-build.log" 2>&1 \
    || { tail -60 "$build/benchmark-build.log" >&2; exit 1; }
fi
exe="$build/contrib/benchmarks/diffusion_benchmark"
pmb_exe="$build/contrib/benchmarks/pmb_benchmark"
abc_exe="$build/contrib/benchmarks/abc_benchmark"
corrosion_exe="$build/contrib/benchmarks/corrosion_benchmark"
fem_abc_exe="$build/contrib/benchmarks/fem_abc_benchmark"
for e in "$exe" "$pmb_exe" "$abc_exe" "$corrosion_exe" "$fem_abc_exe"; do
  [ -x "$e" ] || { echo "run-all: $e was not built" >&2; exit 1; }
done

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

# ---------------------------------------------------------------------
# PMB with fracture (pmb_benchmark); 3d_m3 runs a fixed number of steps,
# the same as LAMMPS below; 2d_m12 and 2d_m24 a fixed window of
# PMB_2D_STEPS steps, PMB_2D_REPEATS times from the initial state (their
# keys are medians: a window of a few calibrated steps carried the VM's
# speed phase directly).
pmb_log="$build/pmb-benchmark.log"
: > "$pmb_log"
for c in $pmb_cases; do
  steps=()
  [ "$c" = 3d_m3 ] && steps=(--steps "$pmb_3d_steps" --repeats "$pmb_3d_repeats")
  case "$c" in 2d_m12 | 2d_m24) steps=(--steps "$pmb_2d_steps" --repeats "$pmb_2d_repeats") ;; esac
  "${launch[@]}" "$pmb_exe" --case "$c" --seconds "$loop_seconds" "${steps[@]}" \
    | tee -a "$pmb_log" | tee -a "$results"
done
echo "pmb_3d_m24: not run (an interior row needs a cube wider than 49 nodes: >= 7.5e9 bonds, > 37 GB)" \
  | tee -a "$results"

# ---------------------------------------------------------------------
# LAMMPS pair_style peri/pmb on the same 3D problem, and the displacement
# agreement case (see doc/benchmarks.md).
value() { sed -n "s/^$1: //p" "$2" | tail -1; }
lammps_ok=0
if [ "$use_lammps" = 1 ]; then
  if ! command -v lmp > /dev/null; then
    echo "run-all: installing lammps and lammps-examples" >&2
    { apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y lammps lammps-examples; } \
      > "$build/lammps-install.log" 2>&1 || echo "run-all: LAMMPS installation failed" >&2
  fi
  command -v lmp > /dev/null && lmp -h 2> /dev/null | grep "peri/pmb" > /dev/null && lammps_ok=1
  [ "$lammps_ok" = 1 ] || echo "run-all: no lmp with peri/pmb; LAMMPS comparison skipped" >&2
fi

# LAMMPS input for a PeriDEAL case: lattice sc 1.0 (dx = 1), nodes at
# 0..n-1 per direction, atom volume 1, density rho, pair_coeff c delta s00
# alpha = 0, velocity Verlet (fix nve) with the same dt. $1 = output file,
# $2 = n, $3 = c, $4 = delta, $5 = s00, $6 = rho, $7 = dt, $8 = steps, then
# the velocity commands on stdin.
lammps_input() {
  local hi
  hi=$(awk -v n="$2" 'BEGIN { printf "%.2f", n - 0.75 }')
  {
    cat <<EOF_LMP
units           si
dimension       3
boundary        s s s
atom_style      peri
atom_modify     map array
neighbor        0.3 bin
lattice         sc 1.0
region          body block -0.25 $hi -0.25 $hi -0.25 $hi units box
create_box      1 body
create_atoms    1 region body
pair_style      peri/pmb
pair_coeff      * * $3 $4 $5 0.0
set             group all density $6
set             group all volume 1.0
EOF_LMP
    cat
    cat <<EOF_LMP
fix             1 all nve
timestep        $7
thermo          $8
EOF_LMP
  } > "$1"
}

# The 3D comparison in PMB_3D_ROUNDS interleaved rounds: per round one
# PeriDEAL process (PMB_3D_REPEATS runs of PMB_3D_STEPS steps, each from the
# initial state, median; --loop-only) and one LAMMPS run of the same steps.
# A 50-step PeriDEAL run is ~0.5 s, short enough for one slow slice of a
# shared machine to move it by 20 %, so the keys are the medians over the
# rounds (ratio = median PeriDEAL rate / median LAMMPS rate), with the
# spread of the per-round ratios as _min/_max keys.
if [ "$lammps_ok" = 1 ] && grep -q '^pmb_3d_m3_steps:' "$pmb_log"; then
  work="$build/lammps"
  mkdir -p "$work"
  n=$(value pmb_3d_m3_n_side "$pmb_log")
  xc=$(awk -v n="$n" 'BEGIN { printf "%.17g", 0.5 * (n - 1) }')
  v0=$(value pmb_3d_m3_v0 "$pmb_log")
  lammps_input "$work/in.pmb_3d_m3" "$n" "$(value pmb_3d_m3_micromodulus "$pmb_log")" \
    "$(value pmb_3d_m3_delta "$pmb_log")" "$(value pmb_3d_m3_critical_stretch "$pmb_log")" \
    "$(value pmb_3d_m3_density "$pmb_log")" "$(value pmb_3d_m3_dt "$pmb_log")" "$pmb_3d_steps" <<EOF_LMP
region          right block $xc INF INF INF INF INF units box
group           right region right
group           left subtract all right
velocity        right set $v0 0.0 0.0 sum no units box
velocity        left set -$v0 0.0 0.0 sum no units box
EOF_LMP
  echo "run             $pmb_3d_steps" >> "$work/in.pmb_3d_m3"
  rounds="$work/rounds.txt"
  : > "$rounds"
  for r in $(seq 1 "$pmb_3d_rounds"); do
    "${launch[@]}" "$pmb_exe" --case 3d_m3 --steps "$pmb_3d_steps" --repeats "$pmb_3d_repeats" \
      --loop-only > "$work/perideal_round.keys"
    ( cd "$work" && /usr/bin/time -f "lammps_max_rss_kb: %M" -o time.txt \
        lmp -in in.pmb_3d_m3 -log log.pmb_3d_m3 -screen none ) \
      || { echo "run-all: LAMMPS failed, see $work/log.pmb_3d_m3" >&2; lammps_ok=0; break; }
    log="$work/log.pmb_3d_m3"
    loop=$(awk '/^Loop time of/ { print $4 }' "$log" | tail -1)
    # "Performance: ... 98.5% CPU use with 1 MPI tasks": CPU seconds of the loop.
    lcpu=$(awk -v loop="$loop" '/% CPU use/ { for (f = 1; f <= NF; ++f) if ($f ~ /%$/) { sub("%", "", $f); print loop * $f / 100 } }' \
             "$log" | tail -1)
    # Per round: PeriDEAL wall and CPU rate, LAMMPS loop and CPU seconds.
    echo "$(value pmb_3d_m3_loop_bond_updates_per_s_per_core "$work/perideal_round.keys")" \
         "$(value pmb_3d_m3_loop_bond_updates_per_cpu_second "$work/perideal_round.keys")" \
         "$(value pmb_3d_m3_loop_seconds "$work/perideal_round.keys")" "$loop" "$lcpu" >> "$rounds"
  done
fi
if [ "$lammps_ok" = 1 ] && [ -s "$build/lammps/rounds.txt" ]; then
  work="$build/lammps"
  lsteps=$(awk '/^Loop time of/ { print $9 }' "$work/log.pmb_3d_m3" | tail -1)
  lbonds=$(awk '/total # of bonds/ { print $NF }' "$work/log.pmb_3d_m3" | tail -1)
  lrss=$(sed -n 's/^lammps_max_rss_kb: //p' "$work/time.txt")
  awk -v steps="$lsteps" -v lb="$lbonds" -v rss="$lrss" '
    function median(a, k,   i, j, t) {
      for (i = 2; i <= k; ++i) for (j = i; j > 1 && a[j - 1] > a[j]; --j) { t = a[j]; a[j] = a[j - 1]; a[j - 1] = t }
      return k % 2 ? a[(k + 1) / 2] : 0.5 * (a[k / 2] + a[k / 2 + 1])
    }
    function mn(a, k,   i, m) { m = a[1]; for (i = 2; i <= k; ++i) if (a[i] < m) m = a[i]; return m }
    function mx(a, k,   i, m) { m = a[1]; for (i = 2; i <= k; ++i) if (a[i] > m) m = a[i]; return m }
    {
      ++k
      prate[k] = $1; pcpu[k] = $2; ploop[k] = $3
      lrate[k] = lb * steps / $4; lcpu[k] = lb * steps / $5; lloop[k] = $4; lcpusec[k] = $5
      ratio[k] = prate[k] / lrate[k]; cratio[k] = pcpu[k] / lcpu[k]
    }
    END {
      pr = median(prate, k); pc = median(pcpu, k); lr = median(lrate, k); lc = median(lcpu, k)
      printf "pmb_3d_m3_rounds: %d\n", k
      printf "pmb_3d_m3_rounds_loop_bond_updates_per_s_per_core: %.6g\n", pr
      printf "pmb_3d_m3_rounds_loop_bond_updates_per_s_per_core_min: %.6g\n", mn(prate, k)
      printf "pmb_3d_m3_rounds_loop_bond_updates_per_s_per_core_max: %.6g\n", mx(prate, k)
      printf "pmb_3d_m3_rounds_loop_bond_updates_per_cpu_second: %.6g\n", pc
      printf "lammps_pmb_3d_m3_steps: %d\n", steps
      printf "lammps_pmb_3d_m3_bonds: %d\n", lb
      printf "lammps_pmb_3d_m3_loop_seconds: %.6g\n", median(lloop, k)
      printf "lammps_pmb_3d_m3_loop_cpu_seconds: %.6g\n", median(lcpusec, k)
      printf "lammps_pmb_3d_m3_bond_updates_per_s_per_core: %.6g\n", lr
      printf "lammps_pmb_3d_m3_bond_updates_per_s_per_core_min: %.6g\n", mn(lrate, k)
      printf "lammps_pmb_3d_m3_bond_updates_per_s_per_core_max: %.6g\n", mx(lrate, k)
      printf "lammps_pmb_3d_m3_bond_updates_per_cpu_second: %.6g\n", lc
      printf "lammps_pmb_3d_m3_peak_rss_bytes_per_bond: %.6g\n", rss * 1024 / lb
      printf "pmb_3d_m3_speedup_over_lammps: %.6g\n", pr / lr
      printf "pmb_3d_m3_speedup_over_lammps_round_median: %.6g\n", median(ratio, k)
      printf "pmb_3d_m3_speedup_over_lammps_min: %.6g\n", mn(ratio, k)
      printf "pmb_3d_m3_speedup_over_lammps_max: %.6g\n", mx(ratio, k)
      printf "pmb_3d_m3_cpu_time_speedup_over_lammps: %.6g\n", pc / lc
      printf "pmb_3d_m3_cpu_time_speedup_over_lammps_min: %.6g\n", mn(cratio, k)
      printf "pmb_3d_m3_cpu_time_speedup_over_lammps_max: %.6g\n", mx(cratio, k)
      printf "pmb_3d_m3_step_time_ratio_lammps_over_perideal: %.6g\n", median(lloop, k) / median(ploop, k)
    }' "$work/rounds.txt" | tee -a "$results"
fi

# The agreement case: 12^3 nodes, m = 3, LAMMPS's bond family in PeriDEAL,
# no breaking, a smooth initial velocity field, 200 steps; displacements of
# every node every 20 steps compared.
if [ "$lammps_ok" = 1 ]; then
  work="$build/lammps"
  mkdir -p "$work"
  "$pmb_exe" --agreement "$work/perideal_agreement.txt" > "$work/agreement.keys"
  a="$work/agreement.keys"
  n=$(value agreement_n_side "$a")
  L=$((n - 1))
  A=$(value agreement_amplitude "$a")
  every=$(value agreement_every "$a")
  steps=$(value agreement_steps "$a")
  lammps_input "$work/in.agreement" "$n" "$(value agreement_micromodulus "$a")" \
    "$(value agreement_delta "$a")" 1.0 1.0 "$(value agreement_dt "$a")" "$steps" <<EOF_LMP
variable        vx atom $A*sin(PI*x/$L)*cos(PI*y/$L)
variable        vy atom $A*cos(PI*z/$L)
variable        vz atom $A*sin(PI*y/$L)*sin(PI*x/$L)
velocity        all set v_vx v_vy v_vz units box
dump            1 all custom $every dump.agreement id x y z
dump_modify     1 format float %.17g sort id
EOF_LMP
  echo "run             $steps" >> "$work/in.agreement"
  ( cd "$work" && lmp -in in.agreement -log log.agreement -screen none ) \
    || echo "run-all: LAMMPS agreement run failed, see $work/log.agreement" >&2
  lbonds=$(awk '/total # of bonds/ { print $NF }' "$work/log.agreement" | tail -1)
  # u = x - round(x): the lattice points are integers, |u| << 1/2.
  awk -v lbonds="$lbonds" -v pbonds="$(value agreement_bonds_with_weight "$a")" \
      -v min_s="$(value agreement_min_stretch "$a")" '
    function rnd(v) { return v < 0 ? -int(-v + 0.5) : int(v + 0.5) }
    FNR == 1 { file++ }
    file == 1 { p[$1 " " $2 " " $3 " " $4] = $5 " " $6 " " $7; next }
    /^ITEM: TIMESTEP/ { getline; step = $1; next }
    /^ITEM: ATOMS/ { inatoms = 1; next }
    /^ITEM:/ { inatoms = 0; next }
    inatoms {
      i = rnd($2); j = rnd($3); k = rnd($4)
      key = step " " i " " j " " k
      if (!(key in p)) { missing++; next }
      split(p[key], q, " ")
      u[1] = $2 - i; u[2] = $3 - j; u[3] = $4 - k
      for (d = 1; d <= 3; ++d) {
        e = u[d] - q[d]; if (e < 0) e = -e
        if (e > diff) diff = e
        m = q[d] < 0 ? -q[d] : q[d]
        if (m > umax) umax = m
      }
      matched++
    }
    END {
      # Round-off bound (doc/benchmarks.md): LAMMPS integrates absolute
      # positions |x| <= 11, each update rounding by <= 11 * 2^-53 = 1.2e-15;
      # over 200 steps that is <= 2.5e-13 = 3e-12 max|u|, and the stable
      # linear dynamics do not amplify it by more than the step count.
      tol = 1e-10
      printf "lammps_agreement_bonds_lammps: %d\n", lbonds
      printf "lammps_agreement_bonds_perideal: %d\n", pbonds
      printf "lammps_agreement_compared_values: %d\n", 3 * matched
      printf "lammps_agreement_missing_nodes: %d\n", missing
      printf "lammps_agreement_min_stretch: %s\n", min_s
      printf "lammps_agreement_max_displacement: %.6g\n", umax
      printf "lammps_agreement_max_abs_difference: %.6g\n", diff
      printf "lammps_agreement_relative_difference: %.6g\n", diff / umax
      printf "lammps_agreement_tolerance: %g\n", tol
      ok = matched > 0 && missing == 0 && lbonds == pbonds && min_s > -0.1 && diff <= tol * umax
      printf "lammps_agreement_pass: %d\n", ok
    }' "$work/perideal_agreement.txt" "$work/dump.agreement" | tee -a "$results"
fi
# EBF absorbing boundaries: ABC work as a fraction of the step time (serial).
"$abc_exe" "${ABC_STEPS:-2000}" | grep '^abc_overhead_fraction_' | tee -a "$results"
"$fem_abc_exe" "${ABC_STEPS:-2000}" | grep '^abc_overhead_fraction_' | tee -a "$results"

# 3D corrosion: hybrid vs standard, multi-grid / adaptive hybrid vs uniform
# fine (serial; CORROSION_STEPS timed steps, default 100).
"$corrosion_exe" --steps "${CORROSION_STEPS:-100}" | grep -v '^#' | tee -a "$results"
# Multi-adaptive Kalthoff-Winkler (serial): Table 1 of paper 001 at
# KW_ARGS (default dx+ = 2 dx- = 1 mm, delta = 4 mm).
kw_exe="$build/contrib/benchmarks/kw_multiadaptive_benchmark"
if [ -x "$kw_exe" ]; then
  # shellcheck disable=SC2086
  "$kw_exe" ${KW_ARGS:-} | grep '^kw_' | tee -a "$results"
fi
# Kalthoff-Winkler: standard vs adaptive hybrid (Table 3.3), serial.
kw_hybrid_exe="$build/contrib/benchmarks/kw_hybrid_benchmark"
kw_hybrid_args="${KW_HYBRID_ARGS---dx 0.25 --m 8}"
if [ -n "$kw_hybrid_args" ] && [ -x "$kw_hybrid_exe" ]; then
  # shellcheck disable=SC2086
  ( cd "$build" && "$kw_hybrid_exe" $kw_hybrid_args --directory "$build/kw-hybrid-benchmark" ) \
    | grep '^kw_' | tee -a "$results"
fi

# Half-derivative ABC history: exact vs sum of exponentials, CPU us per step.
half_exe="$build/contrib/benchmarks/half_derivative_benchmark"
if [ -x "$half_exe" ]; then
  "$half_exe" --rounds "${HALF_DERIVATIVE_ROUNDS:-3}" | grep '^half_derivative_' | tee -a "$results"
fi

echo "machine_load_average_after: $(cut -d' ' -f1 /proc/loadavg)" | tee -a "$results"
echo "run-all: results in $results" >&2
