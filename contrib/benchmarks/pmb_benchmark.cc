// ---------------------------------------------------------------------
// PeriDEAL benchmark: nonlinear bond-based PD (PMB) with fracture,
// BondBasedOperator<dim>::compute_forces inside VelocityVerlet<dim>::advance,
// on uniform lattices; and the small elastic case that
// contrib/benchmarks/run-all.sh compares with LAMMPS `pair_style peri/pmb`.
//
// Lattice: n nodes per direction on [0, n-1]^dim, dx = 1 (LAMMPS `lattice
// sc 1.0`), delta = m dx, partial volumes, constant influence, E = 1,
// rho = 1, c = bond_based_micromodulus (3D: 18K/(pi delta^4), LAMMPS's
// convention), dt = 0.5 x the critical step (3.8). Fracture case: the two
// halves x < (n-1)/2 and x > (n-1)/2 start with velocities -v0 e_x and
// +v0 e_x, v0 = 4 s0 (the speed of sound is about 1): the bonds crossing
// the mid plane break within a few steps, the halves then fly apart (a
// bounded number of broken bonds however long the run).
//
// Usage: pmb_benchmark [options]
//   --case NAME      2d_m3 | 2d_m12 | 2d_m24 | 3d_m3 | 3d_m12 (repeatable)
//   --dim D --m M --nodes N   a custom case
//   --steps S        timed steps (0: enough for --seconds)
//   --seconds T      target wall time of the timed loop (default 1)
//   --repeats R      run the timed loop R times (default 1), each from a
//                    fresh state (new operator and Verlet on the same
//                    discretization, so no bond broken, u = 0, t = 0): with
//                    --steps S every repeat times steps 1..S, as LAMMPS's
//                    `run S` does. The loop keys are the medians over the
//                    repeats, _min/_max keys their spread (a shared machine).
//                    With --steps, bond_updates_per_s_per_core (_min, _max),
//                    _per_cpu_second and step_seconds are these loop medians
//                    too (without it: the fastest of the ten calls); the
//                    fastest call is always printed as best_call_*
//   --loop-only      stop after the timed loop (run-all.sh's interleaved
//                    rounds against LAMMPS)
//   --sync-every-call  the timed advance(n) calls convert the state into and
//                    out of the sweep's box layout each (the default defers
//                    the node vectors to one sync_node_vectors() at the end
//                    of the timed loop, which is timed)
//   --no-sweep-pairs  3D sweep without paired passes (one reaction store
//                    per bond vector; for A/B runs, see
//                    BondBasedOperator::set_lattice_sweep_pairs())
//   --profile-steps S  only run S Verlet steps after setup (for profilers)
//   --trace-steps S  only run S single Verlet steps, printing each one's CPU
//                    time and the broken-bond fraction after it
//   --chunks "C ..." only time the sweep force loop (after 10 steps) for each
//                    C, round robin, CPU time: chunk C/8*8 positions with
//                    C%8 offsets per pass (C%8 == 0: two)
//   --agreement FILE the LAMMPS agreement case: 12^3 nodes, m = 3, LAMMPS's
//                    bond family (|xi| <= delta), no breaking; writes
//                    "step i j k ux uy uz" lines every --every steps to FILE
//   --agreement-steps S (default 200), --every E (default 20)
// Prints `key: value` lines (keys in doc/benchmarks.md).
// ---------------------------------------------------------------------

#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/bond_based.h>
#include <perideal/time_stepping/velocity_verlet.h>

#include "benchmark_utilities.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
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
    std::string  name; // key prefix after "pmb_"
    unsigned int dim   = 2;
    unsigned int m     = 3;
    double       nodes = 1e6;
  };

  struct Options
  {
    std::vector<Case> cases;
    unsigned int      steps         = 0;
    double            seconds       = 1.;
    unsigned int      repeats       = 1;
    bool              loop_only     = false;
    bool              sync_every_call = false;
    bool              no_sweep_pairs  = false;
    unsigned int      profile_steps = 0;
    unsigned int      trace_steps   = 0;
    std::vector<unsigned int> chunks;
    std::string       agreement_file;
    unsigned int      agreement_steps = 200;
    unsigned int      every           = 20;
  };

  Case
  preset(const std::string &name)
  {
    // 2D m = 24: 1889 bonds per node, so 500^2 nodes (4.7e8 bonds) to keep
    // the memory near that of 2D m = 12. 3D m = 3 is the LAMMPS comparison
    // problem: 40^3 nodes (an even count: no node on the mid plane), small
    // enough for LAMMPS to run the same steps in seconds. 3D m = 12: as
    // in the diffusion benchmark, 27^3 nodes (a cube must be wider than 25
    // nodes to have interior rows). 3D m = 24 does not fit: an interior
    // row needs a cube wider than 49 nodes, i.e. >= 50^3 x 6e4 = 7.5e9
    // bonds, 37 GB for column indices and broken flags alone (23 GB RAM).
    if (name == "2d_m3")
      return {name, 2, 3, 1e6};
    if (name == "2d_m12")
      return {name, 2, 12, 1e6};
    if (name == "2d_m24")
      return {name, 2, 24, 2.5e5};
    if (name == "3d_m3")
      return {name, 3, 3, 64000};
    if (name == "3d_m12")
      return {name, 3, 12, 19683};
    throw std::runtime_error("unknown case " + name +
                             " (2d_m3, 2d_m12, 2d_m24, 3d_m3, 3d_m12)");
  }

  template <int dim>
  std::unique_ptr<Discretization<dim>>
  make_lattice(const MPI_Comm comm, const unsigned int n_side, const unsigned int m)
  {
    LatticeParameters lp;
    lp.dx              = 1.;
    lp.delta           = m;
    lp.partial_volume  = true;
    lp.cell_centered   = false;
    lp.layer_thickness = 0.;
    Point<dim> upper;
    for (unsigned int d = 0; d < dim; ++d)
      upper[d] = n_side - 1.;
    auto disc = std::make_unique<Discretization<dim>>(comm);
    disc->setup(BoxDomain<dim>(Point<dim>(), upper), lp);
    return disc;
  }

  template <int dim>
  void
  run_case(const Case &c, const Options &opt, const MPI_Comm comm)
  {
    const unsigned int rank    = Utilities::MPI::this_mpi_process(comm);
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    const std::string  prefix  = "pmb_" + c.name + "_";
    auto               print   = [&](const std::string &key, const double value) {
      if (rank == 0)
        std::printf("%s%s: %.6g\n", prefix.c_str(), key.c_str(), value);
    };
    auto print_exact = [&](const std::string &key, const double value) {
      if (rank == 0)
        std::printf("%s%s: %.17g\n", prefix.c_str(), key.c_str(), value);
    };
    auto flush = [&] {
      if (rank == 0)
        std::fflush(stdout);
    };

    const unsigned int n_side = std::max(2., std::round(std::pow(c.nodes, 1. / dim)));
    const double       rss_before = rss_bytes().first;
    MPI_Barrier(comm);
    const double t0   = MPI_Wtime();
    auto         disc = make_lattice<dim>(comm, n_side, c.m);

    BondBasedModelParameters mp;
    mp.youngs_modulus = 1.;
    mp.plane_stress   = true;
    mp.linearized     = false;
    mp.critical_stretch = 1e-3;
    const double rho = 1.;
    // The operator (which owns the broken flags) and the Verlet state are
    // rebuilt for every repeat of the timed loop: fresh_state() gives the
    // initial state of the problem, two halves pulled apart (see the header).
    std::unique_ptr<BondBasedOperator<dim>> model_ptr;
    std::unique_ptr<VelocityVerlet<dim>>    verlet_ptr;
    double                                  dt = 0., v0 = 0.;
    const double                            xc = 0.5 * (n_side - 1.);
    const auto                              fresh_state = [&] {
      verlet_ptr.reset();
      model_ptr = std::make_unique<BondBasedOperator<dim>>(*disc, mp);
      model_ptr->set_lattice_sweep_pairs(!opt.no_sweep_pairs);
      dt        = 0.5 * model_ptr->critical_time_step(rho);
      v0        = 4. * model_ptr->critical_stretch();
      verlet_ptr = std::make_unique<VelocityVerlet<dim>>(*model_ptr, rho, dt);
      for (unsigned int i = 0; i < disc->n_owned(); ++i)
        verlet_ptr->velocity[0].local_element(i) = disc->position[i][0] > xc ? v0 : -v0;
      verlet_ptr->initialize();
    };
    fresh_state();
    const double t_setup = Utilities::MPI::max(MPI_Wtime() - t0, comm);

    const auto   rss_after = rss_bytes();
    BondBasedOperator<dim> *model  = model_ptr.get();
    VelocityVerlet<dim>    *verlet = verlet_ptr.get();
    const auto  &nb        = disc->neighborhood;
    const double bonds     = double(disc->n_global_bonds());
    const double nodes     = double(disc->n_global());

    // Memory: CSR; the operator's coefficient per table entry, stiffness
    // per row and broken flag per bond; the Verlet fields (u, v, a, b and
    // the force: 5 dim vectors with ghosts).
    const double nb_bytes = Utilities::MPI::sum(double(nb.memory_consumption()), comm);
    const double op_bytes = Utilities::MPI::sum(
      double(nb.bond_length.size() * sizeof(double) + disc->n_owned() * sizeof(double) +
             nb.n_bonds() * sizeof(std::uint8_t)),
      comm);
    const double vec_bytes = Utilities::MPI::sum(
      5. * dim * double(disc->n_owned() + disc->n_ghost()) * sizeof(double), comm);

    print_exact("nodes", nodes);
    print_exact("bonds", bonds);
    print_exact("stencil_size", nb.stencil_size);
    print("bonds_per_node", bonds / nodes);
    print("regular_row_fraction",
          Utilities::MPI::sum(double(nb.n_regular_rows), comm) / nodes);
    print("setup_seconds", t_setup);
    print("neighborhood_bytes_per_bond", nb_bytes / bonds);
    print("operator_bytes_per_bond", op_bytes / bonds);
    print("vector_bytes_per_bond", vec_bytes / bonds);
    print("bytes_per_bond", (nb_bytes + op_bytes + vec_bytes) / bonds);
    print("rss_bytes_per_bond",
          Utilities::MPI::sum(rss_after.first - rss_before, comm) / bonds);
    print("peak_rss_bytes_per_bond", Utilities::MPI::sum(rss_after.second, comm) / bonds);
    // Parameters a second code needs to run the same problem.
    print_exact("n_side", n_side);
    print_exact("delta", disc->parameters().delta);
    print_exact("micromodulus", model->micromodulus());
    print_exact("critical_stretch", model->critical_stretch());
    print_exact("density", rho);
    print_exact("dt", dt);
    print_exact("v0", v0);
    flush();

    // With `perf record -D -1 --control fifo:CTL,ACK`, PERIDEAL_PERF_CTL=CTL
    // and PERIDEAL_PERF_ACK=ACK, only the profiled or timed steps are
    // recorded.
    const auto perf_control = [](const char *command) {
      const char *ctl = std::getenv("PERIDEAL_PERF_CTL");
      const char *ack = std::getenv("PERIDEAL_PERF_ACK");
      if (ctl == nullptr)
        return;
      if (FILE *f = std::fopen(ctl, "w"))
        {
          std::fprintf(f, "%s\n", command);
          std::fclose(f);
        }
      if (ack != nullptr)
        if (FILE *f = std::fopen(ack, "r"))
          {
            char reply[8];
            (void)!std::fgets(reply, sizeof(reply), f);
            std::fclose(f);
          }
    };
    if (opt.profile_steps > 0)
      {
        perf_control("enable");
        verlet->advance(opt.profile_steps);
        perf_control("disable");
        return;
      }
    if (!opt.chunks.empty() && model->uses_lattice_sweep())
      {
        // Sweep chunk sizes round robin (CPU time, median of 5 rounds),
        // after 10 steps (the first bonds have broken).
        verlet->advance(10);
        typename BondBasedOperator<dim>::VectorField f;
        model->initialize(f);
        const unsigned int               reps = std::max(3., 2e8 / bonds);
        std::vector<std::vector<double>> cpu(opt.chunks.size());
        for (unsigned int round = 0; round < 5; ++round)
          for (std::size_t k = 0; k < opt.chunks.size(); ++k)
            {
              // c + K: chunk c, K offsets per pass (K < 8).
              model->set_lattice_sweep_chunk(opt.chunks[k] / 8 * 8);
              model->set_lattice_sweep_offsets_per_pass(opt.chunks[k] % 8 == 0 ? 2 : opt.chunks[k] % 8);
              const double c0 = thread_cpu_seconds();
              for (unsigned int r = 0; r < reps; ++r)
                model->compute_forces(verlet->displacement, f);
              cpu[k].push_back(thread_cpu_seconds() - c0);
            }
        for (std::size_t k = 0; k < opt.chunks.size(); ++k)
          {
            std::sort(cpu[k].begin(), cpu[k].end());
            print("chunk_" + std::to_string(opt.chunks[k]) + "_force_bond_updates_per_cpu_second",
                  bonds * reps / cpu[k][2]);
          }
        return;
      }
    if (opt.trace_steps > 0)
      {
        // Per-step CPU time of single node-ordered steps and the bonds
        // broken so far (diagnostics: when do the bonds break?).
        for (unsigned int s = 0; s < opt.trace_steps; ++s)
          {
            const double c0 = thread_cpu_seconds();
            verlet->advance();
            const double cpu = Utilities::MPI::sum(thread_cpu_seconds() - c0, comm);
            if (rank == 0)
              std::printf("%strace_step %u cpu %.4f rate %.4g broken_fraction %.5g\n",
                          prefix.c_str(), s + 1, cpu, bonds / cpu,
                          double(model->n_broken_bonds()) / bonds);
            flush();
          }
        return;
      }

    const auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v.empty() ? 0. : 0.5 * (v[(v.size() - 1) / 2] + v[v.size() / 2]);
    };
    // Without --steps, a warm-up step calibrates the number of steps, and
    // the first repeat continues from it (steps 2..S+1); with --steps S
    // every repeat starts from the initial state and times steps 1..S,
    // the steps of LAMMPS's timed loop (its setup, like initialize(), has
    // computed the forces of step 0).
    unsigned int steps = opt.steps;
    if (steps == 0)
      {
        const double t_one = time_loop(comm, 1, [&] { verlet->advance(); }).wall;
        steps = std::max(3., std::min(1e5, std::ceil(opt.seconds / std::max(t_one, 1e-9))));
      }
    // The timed steps run as ten calls of advance(n) (runs between two
    // points at which a driver checks something): with the lattice sweep
    // the state stays in its box layout within a call
    // (VelocityVerlet::advance(n)) and, with deferred node sync, between the
    // calls; the final sync_node_vectors() (the node-ordered state, as
    // LAMMPS has its state in its arrays after `run`) is part of the timed
    // loop.
    const unsigned int calls = std::min(10u, std::max(steps, 1u));
    steps = calls * ((Utilities::MPI::max(steps, comm) + calls - 1) / calls);
    print("steps", steps);
    print("repeats", opt.repeats);

    const double        bond_updates = bonds * steps;
    Timing              t_step{1e300, 1e300, 0., 0.}; // fastest call over all repeats
    std::vector<double> loop_wall, loop_cpu;
    for (unsigned int r = 0; r < std::max(opt.repeats, 1u); ++r)
      {
        if (verlet->step() > 0 && (r > 0 || opt.steps > 0))
          {
            fresh_state();
            model  = model_ptr.get();
            verlet = verlet_ptr.get();
          }
        verlet->set_deferred_node_sync(!opt.sync_every_call);
        unsigned int call = 0;
        perf_control("enable");
        const Timing t = time_loop(comm, calls, [&] {
          verlet->advance(steps / calls);
          if (++call == calls)
            verlet->sync_node_vectors();
        });
        perf_control("disable");
        verlet->set_deferred_node_sync(false);
        t_step.wall    = std::min(t_step.wall, t.wall);
        t_step.cpu     = std::min(t_step.cpu, t.cpu);
        loop_wall.push_back(t.total);
        loop_cpu.push_back(t.total_cpu);
      }
    const auto [wall_min, wall_max] = std::minmax_element(loop_wall.begin(), loop_wall.end());
    const auto [cpu_min, cpu_max]   = std::minmax_element(loop_cpu.begin(), loop_cpu.end());
    // The headline keys: with --steps (a fixed window of steps 1..S, the
    // same steps and work in every repeat) the median over the repeats of
    // the whole timed loop; without it (a few calibrated steps) the fastest
    // call, as before. The fastest call is always printed as best_call_*.
    print("best_call_step_seconds", t_step.wall / steps);
    print("best_call_bond_updates_per_s_per_core", bond_updates / (t_step.wall * n_ranks));
    print("best_call_bond_updates_per_cpu_second", bond_updates / t_step.cpu);
    if (opt.steps > 0)
      {
        print("step_seconds", median(loop_wall) / steps);
        print("bond_updates_per_s_per_core", bond_updates / (median(loop_wall) * n_ranks));
        print("bond_updates_per_s_per_core_min", bond_updates / (*wall_max * n_ranks));
        print("bond_updates_per_s_per_core_max", bond_updates / (*wall_min * n_ranks));
        print("bond_updates_per_cpu_second", bond_updates / median(loop_cpu));
      }
    else
      {
        print("step_seconds", t_step.wall / steps);
        print("bond_updates_per_s_per_core", bond_updates / (t_step.wall * n_ranks));
        print("bond_updates_per_cpu_second", bond_updates / t_step.cpu);
      }
    print("loop_seconds", median(loop_wall));
    print("loop_bond_updates_per_s_per_core", bond_updates / (median(loop_wall) * n_ranks));
    print("loop_bond_updates_per_s_per_core_min", bond_updates / (*wall_max * n_ranks));
    print("loop_bond_updates_per_s_per_core_max", bond_updates / (*wall_min * n_ranks));
    print("loop_cpu_seconds", median(loop_cpu));
    print("loop_bond_updates_per_cpu_second", bond_updates / median(loop_cpu));
    print("loop_bond_updates_per_cpu_second_min", bond_updates / *cpu_max);
    print("loop_bond_updates_per_cpu_second_max", bond_updates / *cpu_min);
    print("broken_bond_fraction", double(model->n_broken_bonds()) / bonds);
    // FNV-1a of the bytes of u, v, a and the broken flags of rank 0 after
    // the last repeat: equal for every code path that is bitwise the same
    // (e.g. with and without --sync-every-call).
    {
      std::uint64_t hash = 1469598103934665603ull;
      const auto    add  = [&](const void *data, const std::size_t n) {
        for (std::size_t k = 0; k < n; ++k)
          hash = (hash ^ static_cast<const unsigned char *>(data)[k]) * 1099511628211ull;
      };
      for (const auto *field : {&verlet->displacement, &verlet->velocity, &verlet->acceleration})
        for (unsigned int d = 0; d < dim; ++d)
          add((*field)[d].begin(), disc->n_owned() * sizeof(double));
      add(model->broken().data(), model->broken().size());
      if (rank == 0)
        std::printf("%sfinal_state_hash: %016llx\n", prefix.c_str(),
                    static_cast<unsigned long long>(hash));
    }
    flush();
    if (opt.loop_only)
      return;

    // The box-layout steps against node-ordered ones (advance() per step:
    // the deformed positions copied into the sweep's box and the forces
    // written back every step), round robin, CPU time (shared machine).
    // The comparisons below repeat their loops: they time about --seconds
    // per loop (at most the timed steps), not a long --steps window.
    const unsigned int reps =
      std::max(3., std::min<double>(steps, std::ceil(opt.seconds * steps / *wall_min)));
    if (verlet->uses_box_state())
      {
        const unsigned int  k = std::max(3u, reps / 5);
        std::vector<double> ratio;
        double              best_node = 1e300;
        for (unsigned int round = 0; round < 3; ++round)
          {
            const Timing node = time_loop(comm, 1, [&] {
              for (unsigned int s = 0; s < k; ++s)
                verlet->advance();
            });
            const Timing box = time_loop(comm, 1, [&] { verlet->advance(k); });
            ratio.push_back(node.cpu / box.cpu);
            best_node = std::min(best_node, node.cpu);
          }
        std::sort(ratio.begin(), ratio.end());
        print("step_node_order_bond_updates_per_cpu_second", bonds * k / best_node);
        print("step_box_speedup_cpu_median", ratio[1]);
        flush();
      }

    // compute_forces alone (the state keeps evolving between the chunks
    // of the loop above; here u is frozen).
    // The lattice sweep (the default where available), the half list and
    // the full list (every bond copy evaluated in its own row) are timed
    // round robin, five rounds; per loop the best round and, per round, the
    // CPU-time ratios to the full list (min and median printed): the
    // machine is shared. All count the same bond updates (bonds = both
    // copies of every bond), so the ratios are speed-ups.
    typename BondBasedOperator<dim>::VectorField force, force_full, force_sweep; // half, full, sweep
    model->initialize(force);
    model->initialize(force_full);
    model->initialize(force_sweep);
    const bool sweep_available = model->lattice_sweep_available();
    Timing     t_force, t_full, t_sweep; // half, full list, sweep
    t_force.wall = t_force.cpu = t_full.wall = t_full.cpu = t_sweep.wall = t_sweep.cpu = 1e300;
    std::vector<double> half_ratio, sweep_ratio; // per round: cpu(full) / cpu(loop)
    for (unsigned int round = 0; round < 5; ++round)
      {
        double cpu[3] = {0., 0., 0.};
        for (const int loop : {2, 1, 0}) // sweep, half, full
          {
            if (loop == 2 && !sweep_available)
              continue;
            if (loop == 2)
              model->set_lattice_sweep(true);
            else
              model->set_half_list(loop == 1);
            auto &out = loop == 2 ? force_sweep : loop == 1 ? force : force_full;
            const Timing t =
              time_loop(comm, reps, [&] { model->compute_forces(verlet->displacement, out); });
            Timing &best = loop == 2 ? t_sweep : loop == 1 ? t_force : t_full;
            best.wall    = std::min(best.wall, t.wall);
            best.cpu     = std::min(best.cpu, t.cpu);
            cpu[loop]    = t.cpu;
          }
        half_ratio.push_back(cpu[0] / cpu[1]);
        if (sweep_available)
          sweep_ratio.push_back(cpu[0] / cpu[2]);
      }
    model->set_half_list(dim == 3);
    model->set_lattice_sweep(true); // the library default
    double diff = 0., diff_sweep = 0., fmax = 0.;
    for (unsigned int d = 0; d < dim; ++d)
      for (unsigned int i = 0; i < disc->n_owned(); ++i)
        {
          diff = std::max(diff, std::abs(force[d].local_element(i) - force_full[d].local_element(i)));
          diff_sweep = std::max(diff_sweep, std::abs(force_sweep[d].local_element(i) -
                                                     force_full[d].local_element(i)));
          fmax = std::max(fmax, std::abs(force_full[d].local_element(i)));
        }
    diff       = Utilities::MPI::max(diff, comm);
    diff_sweep = Utilities::MPI::max(diff_sweep, comm);
    fmax       = Utilities::MPI::max(fmax, comm);
    const double force_updates = bonds * reps;
    // The library's default loop.
    const Timing &t_default = sweep_available ? t_sweep : dim == 3 ? t_force : t_full;
    print("force_seconds", t_default.wall / reps);
    print("force_bond_updates_per_s_per_core", force_updates / (t_default.wall * n_ranks));
    print("force_bond_updates_per_cpu_second", force_updates / t_default.cpu);
    print("force_full_list_bond_updates_per_s_per_core", force_updates / (t_full.wall * n_ranks));
    print("force_full_list_bond_updates_per_cpu_second", force_updates / t_full.cpu);
    print("force_half_list_bond_updates_per_s_per_core", force_updates / (t_force.wall * n_ranks));
    print("force_half_list_bond_updates_per_cpu_second", force_updates / t_force.cpu);
    print("force_half_list_speedup_cpu", t_full.cpu / t_force.cpu);
    print("force_half_list_speedup_cpu_min", *std::min_element(half_ratio.begin(), half_ratio.end()));
    print("force_half_list_speedup_cpu_median", median(half_ratio));
    print_exact("force_lattice_sweep_available", sweep_available);
    if (sweep_available)
      {
        print("force_sweep_bond_updates_per_s_per_core", force_updates / (t_sweep.wall * n_ranks));
        print("force_sweep_bond_updates_per_cpu_second", force_updates / t_sweep.cpu);
        print("force_sweep_speedup_cpu", t_full.cpu / t_sweep.cpu);
        print("force_sweep_speedup_cpu_min", *std::min_element(sweep_ratio.begin(), sweep_ratio.end()));
        print("force_sweep_speedup_cpu_median", median(sweep_ratio));
        print("force_sweep_full_max_difference_over_max_force", diff_sweep / fmax);
      }
    print("force_half_full_max_difference_over_max_force", diff / fmax);
    flush();
  }

  // The LAMMPS agreement case: see the header and doc/benchmarks.md.
  void
  run_agreement(const Options &opt, const MPI_Comm comm)
  {
    constexpr int      dim    = 3;
    const unsigned int n_side = 12, m = 3;
    auto               disc   = make_lattice<dim>(comm, n_side, m);
    const double       delta = m;
    // LAMMPS's family is |xi| <= delta (fix peri/neigh) with vfrac scaled
    // by (delta + dx/2 - |xi|)/dx for |xi| >= delta - dx/2: PeriDEAL's beta
    // without the shell delta < |xi| < delta + dx/2, whose weights are set
    // to zero here. Integer lattice coordinates make |xi|^2 exact, so both
    // codes classify the bonds at |xi| = delta alike.
    auto &nb = disc->neighborhood;
    for (std::size_t t = 0; t < nb.bond_length.size(); ++t)
      if (nb.bond_length[t] > delta)
        nb.bond_weight[t] = 0.;

    BondBasedModelParameters mp;
    mp.youngs_modulus = 1.;
    mp.linearized     = false;
    BondBasedOperator<dim> model(*disc, mp);
    const double           rho = 1., dt = 0.5 * model.critical_time_step(rho);
    VelocityVerlet<dim>    verlet(model, rho, dt);
    const double           A = 1e-3, L = n_side - 1.;
    for (unsigned int i = 0; i < disc->n_owned(); ++i)
      {
        const Point<dim> &p = disc->position[i];
        verlet.velocity[0].local_element(i) = A * std::sin(M_PI * p[0] / L) * std::cos(M_PI * p[1] / L);
        verlet.velocity[1].local_element(i) = A * std::cos(M_PI * p[2] / L);
        verlet.velocity[2].local_element(i) = A * std::sin(M_PI * p[1] / L) * std::sin(M_PI * p[0] / L);
      }
    verlet.initialize();

    AssertThrow(Utilities::MPI::n_mpi_processes(comm) == 1,
                ExcMessage("--agreement runs on one rank"));
    FILE *out = std::fopen(opt.agreement_file.c_str(), "w");
    AssertThrow(out != nullptr, ExcMessage("cannot write " + opt.agreement_file));
    double max_u = 0., min_stretch = 0.;
    auto   write = [&] {
      for (unsigned int i = 0; i < disc->n_owned(); ++i)
        {
          const auto &li = disc->lattice_index[i];
          std::fprintf(out, "%u %d %d %d", verlet.step(), li[0], li[1], li[2]);
          for (unsigned int d = 0; d < dim; ++d)
            {
              const double u = verlet.displacement[d].local_element(i);
              max_u          = std::max(max_u, std::abs(u));
              std::fprintf(out, " %.17g", u);
            }
          std::fprintf(out, "\n");
        }
    };
    // The smallest bond stretch seen: LAMMPS's contact force acts only on
    // pairs compressed below 0.9 |xi| (stretch < -0.1).
    auto track_stretch = [&] {
      for (unsigned int i = 0; i < disc->n_owned(); ++i)
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
          {
            const int j = nb.col[b];
            double    r2 = 0., l2 = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                const double xi = disc->position[j][d] - disc->position[i][d];
                const double y  = xi + verlet.displacement[d].local_element(j) -
                                 verlet.displacement[d].local_element(i);
                r2 += xi * xi;
                l2 += y * y;
              }
            min_stretch = std::min(min_stretch, std::sqrt(l2 / r2) - 1.);
          }
    };
    // Bonds that carry a force (the zeroed shell excluded): LAMMPS's count.
    double n_weighted = 0.;
    for (unsigned int i = 0; i < disc->n_owned(); ++i)
      for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
        n_weighted += nb.bond_weight[nb.table_start[i] + b - nb.row_start[i]] > 0.;
    write();
    for (unsigned int s = 1; s <= opt.agreement_steps; ++s)
      {
        verlet.advance();
        track_stretch();
        if (s % opt.every == 0)
          write();
      }
    std::fclose(out);
    std::printf("agreement_n_side: %u\nagreement_delta: %.17g\nagreement_micromodulus: %.17g\n"
                "agreement_dt: %.17g\nagreement_amplitude: %.17g\nagreement_steps: %u\n"
                "agreement_every: %u\nagreement_bonds_with_weight: %.0f\n"
                "agreement_max_displacement: %.6g\nagreement_min_stretch: %.6g\n",
                n_side, delta, model.micromodulus(), dt, A, opt.agreement_steps, opt.every,
                n_weighted, max_u, min_stretch);
    std::fflush(stdout);
  }

  Options
  parse(int argc, char **argv)
  {
    Options opt;
    parse_case_options(argc, argv, "pmb_benchmark", opt, preset,
                       [&](const std::string &arg, const std::function<std::string()> &next) {
                         if (arg == "--profile-steps")
                           opt.profile_steps = std::stoi(next());
                         else if (arg == "--chunks")
                           {
                             std::istringstream in(next());
                             for (unsigned int c; in >> c;)
                               opt.chunks.push_back(c);
                           }
                         else if (arg == "--repeats")
                           opt.repeats = std::max(1, std::stoi(next()));
                         else if (arg == "--loop-only")
                           opt.loop_only = true;
                         else if (arg == "--sync-every-call")
                           opt.sync_every_call = true;
                         else if (arg == "--no-sweep-pairs")
                           opt.no_sweep_pairs = true;
                         else if (arg == "--trace-steps")
                           opt.trace_steps = std::stoi(next());
                         else if (arg == "--agreement")
                           opt.agreement_file = next();
                         else if (arg == "--agreement-steps")
                           opt.agreement_steps = std::stoi(next());
                         else if (arg == "--every")
                           opt.every = std::max(1, std::stoi(next()));
                         else
                           return false;
                         return true;
                       });
    if (opt.cases.empty() && opt.agreement_file.empty())
      for (const char *name : {"2d_m3", "2d_m12", "2d_m24", "3d_m3", "3d_m12"})
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
      const Options opt = parse(argc, argv);
      if (!opt.agreement_file.empty())
        run_agreement(opt, comm);
      for (const Case &c : opt.cases)
        c.dim == 2 ? run_case<2>(c, opt, comm) : run_case<3>(c, opt, comm);
    }
  catch (const std::exception &e)
    {
      std::cerr << "pmb_benchmark: " << e.what() << std::endl;
      MPI_Abort(comm, 1);
    }
  return 0;
}
