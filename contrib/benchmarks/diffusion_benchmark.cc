// ---------------------------------------------------------------------
// PeriDEAL benchmark: explicit linear PD diffusion on uniform lattices.
//
// For each case (dimension, horizon ratio m = delta/dx, node count) it
// times Discretization::setup() and the DiffusionOperator construction,
// then forward Euler steps
//     C.update_ghost_values(); op.apply(C, rate); C.add(dt, rate);
// with dt = 0.5 * op.critical_time_step(), and prints `key: value` lines:
// bond updates per second per core (global bonds x steps / (wall seconds x
// ranks); also per thread CPU second), bytes per bond, setup times. Timed
// loops keep their fastest chunk of calls: the machine may be shared. (The
// prototype loops that chose the library's short-row loop are recorded in
// doc/benchmarks.md.)
//
// Usage: diffusion_benchmark [options]
//   --case NAME      2d_m3 | 2d_m12 | 3d_m3 | 3d_m12 (preset; repeatable)
//   --dim D --m M    a custom case (with --nodes)
//   --nodes N        target number of nodes (a cube/square of side N^(1/dim))
//   --steps S        timed steps per loop (0: enough for --seconds)
//   --seconds T      target wall time of each timed loop (default 1)
//   --layer          add a volume constraint layer of thickness delta
//   --profile-apply S  only run S apply() calls after setup (for profilers)
// Without --case/--dim it runs the four presets and prints the aggregate
// setup_seconds_per_million_bonds.
// ---------------------------------------------------------------------

#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/diffusion.h>

#include "benchmark_utilities.h"

#ifdef __AVX512F__
#  include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace PeriDEAL;
using namespace PeriDEALBenchmarks;

namespace
{
  struct Case
  {
    std::string name; // key prefix after "diffusion_"
    unsigned int dim   = 2;
    unsigned int m     = 3;
    double       nodes = 1e6;
  };

  struct Options
  {
    std::vector<Case> cases;
    unsigned int      steps         = 0;
    double            seconds       = 1.;
    bool              layer         = false;
    unsigned int      profile_apply = 0;
  };

  Case
  preset(const std::string &name)
  {
    // 2D: 1000 x 1000 = 1e6 nodes for both horizons (2D m=12: ~4.8e8
    // bonds, ~2 GB of column indices, 4.7 GB peak RSS). 3D m=3: 100^3 = 1e6
    // nodes. 3D m=12 has 8216 bonds per interior node and a horizon of
    // 12.5 dx: a cube with any interior rows (> 25^3 nodes) and room to
    // spare is mostly boundary rows, which carry their own weight tables
    // (28 B/bond): 27^3 = 19683 nodes, ~8e7 bonds, ~3 GB.
    if (name == "2d_m3")
      return {name, 2, 3, 1e6};
    if (name == "2d_m12")
      return {name, 2, 12, 1e6};
    if (name == "3d_m3")
      return {name, 3, 3, 1e6};
    if (name == "3d_m12")
      return {name, 3, 12, 19683};
    throw std::runtime_error("unknown case " + name + " (2d_m3, 2d_m12, 3d_m3, 3d_m12)");
  }

  struct CaseResult
  {
    double setup_seconds = 0.;
    double bonds         = 0.;
  };

  template <int dim>
  CaseResult
  run_case(const Case &c, const Options &opt, const MPI_Comm comm)
  {
    const unsigned int rank    = Utilities::MPI::this_mpi_process(comm);
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    const std::string  prefix  = "diffusion_" + c.name + "_";
    auto               print   = [&](const std::string &key, const double value) {
      if (rank == 0)
        std::printf("%s%s: %.6g\n", prefix.c_str(), key.c_str(), value);
    };
    auto print_int = [&](const std::string &key, const double value) {
      if (rank == 0)
        std::printf("%s%s: %.0f\n", prefix.c_str(), key.c_str(), value);
    };
    auto flush = [&] {
      if (rank == 0)
        std::fflush(stdout);
    };

    // A cube [0, 1]^dim with n nodes per direction (vertex lattice).
    const unsigned int n_side = std::max(2., std::round(std::pow(c.nodes, 1. / dim)));
    LatticeParameters  lp;
    lp.dx              = 1. / (n_side - 1);
    lp.delta           = c.m * lp.dx;
    lp.partial_volume  = true;
    lp.cell_centered   = false;
    lp.layer_thickness = opt.layer ? lp.delta : 0.;
    Point<dim> upper;
    for (unsigned int d = 0; d < dim; ++d)
      upper[d] = 1.;
    BoxDomain<dim> box(Point<dim>(), upper);

    DiffusionModelParameters mp;
    mp.type              = "diffusion";
    mp.omega             = InfluenceFunction::constant;
    mp.exponent          = 1.; // q = 1 (J_q convention)
    mp.micro_diffusivity = 0.;
    mp.diffusivity       = 1.;

    const double rss_before = rss_bytes().first;
    MPI_Barrier(comm);
    double                    t0 = MPI_Wtime();
    Discretization<dim>       disc(comm);
    disc.setup(box, lp);
    const double t_disc = Utilities::MPI::max(MPI_Wtime() - t0, comm);
    MPI_Barrier(comm);
    t0 = MPI_Wtime();
    DiffusionOperator<dim> op(disc, mp);
    const double t_op = Utilities::MPI::max(MPI_Wtime() - t0, comm);

    PeriDEAL::Vector C, rate;
    disc.initialize_vector(C);
    disc.initialize_vector(rate);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double v = 1.;
        for (unsigned int d = 0; d < dim; ++d)
          v *= 0.5 + 0.5 * std::cos(3.14159265358979 * disc.position[i][d]);
        C.local_element(i) = 1. + v;
      }
    C.update_ghost_values();
    const auto   rss_after = rss_bytes();
    const auto  &nb        = disc.neighborhood;
    const double bonds     = double(disc.n_global_bonds());
    const double nodes     = double(disc.n_global());

    std::array<double, 3> phases;
    for (unsigned int p = 0; p < 3; ++p)
      phases[p] = Utilities::MPI::max(disc.setup_seconds[p], comm);

    // Memory: the CSR, the operator's weight tables (geometric_weight has
    // one entry per table entry, row_sum one per owned row), two vectors.
    const double nb_bytes  = Utilities::MPI::sum(double(nb.memory_consumption()), comm);
    const double op_bytes  = Utilities::MPI::sum(
      double(nb.bond_length.size() * sizeof(double) + disc.n_owned() * sizeof(double)), comm);
    const double vec_bytes = Utilities::MPI::sum(
      2. * double(disc.n_owned() + disc.n_ghost()) * sizeof(double), comm);
    const double rss_delta = Utilities::MPI::sum(rss_after.first - rss_before, comm);
    const double rss_peak  = Utilities::MPI::sum(rss_after.second, comm);
    const double n_regular = Utilities::MPI::sum(double(nb.n_regular_rows), comm);
    const double table_entries = Utilities::MPI::sum(double(nb.bond_length.size()), comm);

    print_int("nodes", nodes);
    print_int("bonds", bonds);
    print_int("stencil_size", nb.stencil_size);
    print("bonds_per_node", bonds / nodes);
    print("regular_row_fraction", n_regular / nodes);
    print("table_entries_per_bond", table_entries / bonds);
    print("setup_lattice_seconds", phases[0]);
    print("setup_ghost_seconds", phases[1]);
    print("setup_search_csr_seconds", phases[2]);
    print("setup_operator_seconds", t_op);
    print("setup_seconds", t_disc + t_op);
    print("setup_seconds_per_million_bonds", (t_disc + t_op) / (bonds / 1e6));
    print("neighborhood_bytes_per_bond", nb_bytes / bonds);
    print("operator_bytes_per_bond", op_bytes / bonds);
    print("vector_bytes_per_bond", vec_bytes / bonds);
    print("bytes_per_bond", (nb_bytes + op_bytes + vec_bytes) / bonds);
    print("rss_bytes_per_bond", rss_delta / bonds);
    print("peak_rss_bytes_per_bond", rss_peak / bonds);
    // Capacity the CSR holds beyond its sizes (vectors grown by push_back).
    const double unused = Utilities::MPI::sum(
      double((nb.row_start.capacity() - nb.row_start.size()) * sizeof(std::uint64_t) +
             (nb.col.capacity() - nb.col.size()) * sizeof(std::int32_t) +
             (nb.table_start.capacity() - nb.table_start.size()) * sizeof(std::uint64_t) +
             (nb.bond_length.capacity() - nb.bond_length.size() + nb.bond_weight.capacity() -
              nb.bond_weight.size()) *
               sizeof(double)),
      comm);
    print("neighborhood_unused_capacity_bytes_per_bond", unused / bonds);
    // Estimate of a layout where boundary rows refer to the shared stencil
    // through a 2-byte slot per bond instead of copies of |xi| and beta V
    // (16 B) and the operator's geometric weight (8 B), without unused
    // capacity: row_start + table_start + col + slots + stencil tables +
    // row sums + vectors.
    const double copied = double(nb.bond_length.size()) - double(nb.stencil_size);
    const double slot_layout = Utilities::MPI::sum(
      double(nb.row_start.size() * 8 + nb.table_start.size() * 8 + nb.col.size() * 4) +
        copied * 2. + nb.stencil_size * 24. + disc.n_owned() * 8.,
      comm);
    print("bytes_per_bond_with_slot_tables", (slot_layout + vec_bytes) / bonds);
    if (c.name == "3d_m3" && rank == 0)
      std::printf("diffusion_3d_bytes_per_bond: %.6g\n",
                  (nb_bytes + op_bytes + vec_bytes) / bonds);
    flush();

    if (opt.profile_apply > 0)
      {
        for (unsigned int s = 0; s < opt.profile_apply; ++s)
          op.apply(C, rate);
        return {t_disc + t_op, bonds};
      }

    const double dt = 0.5 * op.critical_time_step();
    print("dt", dt);

    // Warm-up step, which also calibrates the number of steps.
    const double t_one = time_loop(comm, 1, [&] {
                           C.update_ghost_values();
                           op.apply(C, rate);
                           C.add(dt, rate);
                         }).wall;
    unsigned int steps = opt.steps;
    if (steps == 0)
      steps = std::max(3., std::min(1e5, std::ceil(opt.seconds / std::max(t_one, 1e-9))));
    steps = Utilities::MPI::max(steps, comm);
    print_int("steps", steps);

    const double bond_updates = bonds * steps;
    auto         rate_of      = [&](const double seconds) {
      return bond_updates / (seconds * n_ranks);
    };

    const Timing t_step = time_loop(comm, steps, [&] {
      C.update_ghost_values();
      op.apply(C, rate);
      C.add(dt, rate);
    });
    print("step_seconds", t_step.wall / steps);
    print("bond_updates_per_s_per_core", rate_of(t_step.wall));
    print("bond_updates_per_cpu_second", bond_updates / t_step.cpu);
    flush();

    C.update_ghost_values();
    const Timing t_apply_timing = time_loop(comm, steps, [&] { op.apply(C, rate); });
    const double t_apply        = t_apply_timing.wall;
    print("apply_seconds", t_apply / steps);
    print("apply_bond_updates_per_s_per_core", rate_of(t_apply));
    print("apply_bond_updates_per_cpu_second", bond_updates / t_apply_timing.cpu);
    print("ghost_update_seconds",
          time_loop(comm, steps, [&] { C.update_ghost_values(); }).wall / steps);
    // (a nonzero factor: add() returns at once for 0; this also refreshes
    // the ghosts of C, which add() does for a ghosted vector)
    print("vector_add_seconds", time_loop(comm, steps, [&] { C.add(dt, rate); }).wall / steps);
    flush();

    return {t_disc + t_op, bonds};
  }

  Options
  parse(int argc, char **argv)
  {
    Options opt;
    parse_case_options(argc, argv, "diffusion_benchmark", opt, preset,
                       [&](const std::string &arg, const std::function<std::string()> &next) {
                         if (arg == "--layer")
                           opt.layer = true;
                         else if (arg == "--profile-apply")
                           opt.profile_apply = std::stoi(next());
                         else
                           return false;
                         return true;
                       });
    if (opt.cases.empty())
      for (const char *name : {"2d_m3", "2d_m12", "3d_m3", "3d_m12"})
        opt.cases.push_back(preset(name));
    return opt;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const MPI_Comm                   comm = MPI_COMM_WORLD;
  try
    {
      const Options opt   = parse(argc, argv);
      double        setup = 0., bonds = 0.;
      for (const Case &c : opt.cases)
        {
          const CaseResult r = c.dim == 2 ? run_case<2>(c, opt, comm) : run_case<3>(c, opt, comm);
          setup += r.setup_seconds;
          bonds += r.bonds;
        }
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        {
          std::printf("setup_seconds_per_million_bonds: %.6g\n", setup / (bonds / 1e6));
          std::fflush(stdout);
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << "diffusion_benchmark: " << e.what() << std::endl;
      MPI_Abort(comm, 1);
    }
  return 0;
}
