// 3D corrosion run times (serial, CPU seconds of the time stepping; setup
// excluded as in [100] Table 2). Prints `key: value` lines:
//  (1) corrosion_3d_speedup_hybrid_over_standard: dissertation Sect. 3.3.2
//      (Table 3.4, bunny, 3.7x) reduced: the source's material and
//      discretization (dx = 0.1, delta = 0.6, m = 6, WLS-2 with 123
//      collocation nodes) on a solid ball of radius 1 in a liquid ball of
//      radius R = 2.27 (--radius); Omega_s = the ball of radius 1 + w
//      (--width, 0.6 = delta) around the solid: 35 % of the interior nodes
//      as in the source, and no WLS row has a solid collocation node (none
//      falls back to the standard row); standard vs hybrid, --steps steps
//      (default 100 in 20 interleaved chunks; 10 steps in 5 chunks of two
//      until session 11, whose key swung by ~25 % between runs).
//      (Until session 7: R = 2, w = 0.41, where 25 % of the WLS rows fell
//      back to the standard row, so the standard scheme ran on ~51 %.)
//  (2) corrosion_3d_speedup_adaptive_hybrid_over_uniform_fine: [100]
//      Example 2 / Table 2 (11.76x on 48 cores) reduced: a solid cylinder
//      (r = 0.3, h = 1.2) in an electrolyte cube [-1.65, 1.65]^3 (C = 0
//      within delta of its faces), dx+ = 2 dx- = 0.15, delta = 0.45 (m+ = 3,
//      m- = 6; the source has m+ = 6, m- = 12), Omega- = the solid cylinder
//      enlarged by delta. Uniform fine vs multi-grid vs adaptive hybrid,
//      --multigrid-steps steps (default 100; 10 until session 7, which
//      timed only the start, where all of Omega- is interface band).
// Usage: corrosion_benchmark [--steps N] [--case hybrid|multigrid|all|
//        'uniform fine'|'multi-grid'|'adaptive hybrid']

#include <deal.II/base/mpi.h>
#include <deal.II/base/timer.h>

#include <perideal/multigrid/multigrid_discretization.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include "../../tests/check.h"
#include "benchmark_utilities.h"
#include "../../tests/multigrid/corrosion_3d_cases.h"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <memory>
#include <vector>
#include <iomanip>
#include <iostream>
#include <string>

using namespace dealii;
using namespace PeriDEAL;

namespace
{
  using PeriDEALBenchmarks::thread_cpu_seconds;

  double
  median(std::vector<double> v)
  {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0. : v[v.size() / 2];
  }

  // Standard and hybrid solvers set up once, then stepped in interleaved
  // chunks (A, B, A, B, ...) with thread CPU time: the median chunk per step
  // of each, and the same for the operator alone (apply() on the current
  // state), so that step = operator + the per-node update overheads.
  struct HybridTiming
  {
    double step[2] = {0., 0.}, op[2] = {0., 0.}, chunk_ratio = 0.;
    types::global_dof_index n_nodes = 0, n_wls = 0, n_mixed_wls = 0;
  };

  HybridTiming
  hybrid_timing(const unsigned int steps, const double R, const double w)
  {
    const double r_s = 1., dt = 6.;
    std::array<std::unique_ptr<DiffusionSolver<3>>, 2> solver;
    for (unsigned int h = 0; h < 2; ++h)
      {
        solver[h] = std::make_unique<DiffusionSolver<3>>(
          MPI_COMM_WORLD,
          PeriDEALTests::parameters_from_text<DiffusionRunParameters<3>>(
            PeriDEALTests::corrosion_3d_hybrid_parameters(
              R, r_s, dt, (steps + 1) * dt,
              h ? PeriDEALTests::corrosion_3d_hybrid_region(r_s, w) : "")));
        solver[h]->setup();
      }
    HybridTiming                       r;
    // WLS rows with a collocation node of the other phase at the start
    // (they run the standard row instead; the solid only shrinks, so this
    // bounds the count of every later step)
    if (const auto *wls = solver[1]->get_operator().wls_quadrature())
      for (unsigned int k = 0; k < wls->node.size(); ++k)
        {
          const auto &ph    = solver[1]->phase_field();
          const bool  solid = ph.local_element(wls->node[k]) > 0.5;
          for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
            if ((ph.local_element(wls->col[e]) > 0.5) != solid)
              {
                ++r.n_mixed_wls;
                break;
              }
        }
    std::array<std::vector<double>, 2> step_t, op_t;
    // Many short chunks: a load burst on the shared machine then spoils a
    // few chunks of both solvers, which the medians drop.
    const unsigned int                 chunks = std::min(20u, steps);
    PeriDEAL::Vector                   rate;
    solver[0]->discretization().initialize_vector(rate);
    for (unsigned int c = 0; c < chunks; ++c)
      for (unsigned int h = 0; h < 2; ++h)
        {
          auto              &s = *solver[h];
          const unsigned int n = steps / chunks + (c < steps % chunks);
          double             t = thread_cpu_seconds();
          for (unsigned int k = 0; k < n; ++k)
            s.advance();
          step_t[h].push_back((thread_cpu_seconds() - t) / n);
          t = thread_cpu_seconds();
          for (unsigned int k = 0; k < n; ++k)
            s.get_operator().apply(s.solution(), rate, &s.phase_field(),
                                   DiffusionOperator<3>::Rows::interior);
          op_t[h].push_back((thread_cpu_seconds() - t) / n);
        }
    for (unsigned int h = 0; h < 2; ++h)
      {
        r.step[h] = median(step_t[h]);
        r.op[h]   = median(op_t[h]);
      }
    std::vector<double> ratio;
    for (unsigned int c = 0; c < chunks; ++c)
      ratio.push_back(step_t[0][c] / step_t[1][c]);
    r.chunk_ratio = median(ratio);
    r.n_nodes = solver[1]->discretization().n_global();
    r.n_wls   = solver[1]->n_wls_rows();

    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  unsigned int                     steps = 100, mg_steps = 100;
  std::string                      which = "all";
  double                           R = 2.27, w = 0.6;
  for (int a = 1; a + 1 < argc; a += 2)
    {
      const std::string k = argv[a];
      if (k == "--steps")
        steps = std::max(1, std::atoi(argv[a + 1]));
      else if (k == "--multigrid-steps")
        mg_steps = std::max(1, std::atoi(argv[a + 1]));
      else if (k == "--radius")
        R = std::atof(argv[a + 1]);
      else if (k == "--width")
        w = std::atof(argv[a + 1]);
      else if (k == "--case")
        which = argv[a + 1];
    }
  std::cout << std::setprecision(6);
  if (which == "all" || which == "hybrid")
    {
      const HybridTiming t = hybrid_timing(steps, R, w);
      std::cout << "corrosion_3d_hybrid_radius_and_width: " << R << " " << w << "\n"
                << "corrosion_3d_hybrid_nodes: " << t.n_nodes << "\n"
                << "corrosion_3d_hybrid_wls_rows: " << t.n_wls << "\n"
                << "corrosion_3d_hybrid_wls_rows_of_mixed_phase: " << t.n_mixed_wls << "\n"
                << "corrosion_3d_standard_seconds_per_step: " << t.step[0] << "\n"
                << "corrosion_3d_hybrid_seconds_per_step: " << t.step[1] << "\n"
                << "corrosion_3d_standard_operator_seconds: " << t.op[0] << "\n"
                << "corrosion_3d_hybrid_operator_seconds: " << t.op[1] << "\n"
                << "corrosion_3d_hybrid_operator_speedup: " << t.op[0] / t.op[1] << "\n"
                << "corrosion_3d_speedup_median_chunk: " << t.chunk_ratio << "\n"
                << "corrosion_3d_speedup_hybrid_over_standard: " << t.step[0] / t.step[1]
                << std::endl;
    }
  if (which == "uniform fine" || which == "multi-grid" || which == "adaptive hybrid")
    {
      // one configuration alone (for profiling: perf record of its steps)
      MultiGrid::CylinderCorrosionCase c;
      c.half_width  = 1.65;
      c.radius      = 0.3;
      c.half_height = 0.6;
      c.end_time    = 1e300;
      const auto r  = MultiGrid::run_cylinder_corrosion(c, which, mg_steps);
      std::cout << "corrosion_3d_" << which << "_seconds_per_100_steps: "
                << 100. * r.step_cpu_seconds << " (wall " << 100. * r.step_seconds << ")" << std::endl;
    }
  if (which == "all" || which == "multigrid")
    {
      MultiGrid::CylinderCorrosionCase c;
      c.half_width  = 1.65;
      c.radius      = 0.3;
      c.half_height = 0.6;
      c.end_time    = 1e300;
      // dt of the adaptive hybrid (the smallest bound) for all
      const auto ah = MultiGrid::run_cylinder_corrosion(c, "adaptive hybrid", mg_steps);
      c.time_step   = ah.time_step;
      const auto mg = MultiGrid::run_cylinder_corrosion(c, "multi-grid", mg_steps);
      const auto uf = MultiGrid::run_cylinder_corrosion(c, "uniform fine", mg_steps);
      std::cout << "# Table 2 analogue (serial, CPU s per 100 steps, setup excluded)\n"
                << "# configuration | active Omega+ | active Omega- | fictitious | "
                   "constrained | WLS rows | setup s | s per 100 steps | speed-up\n";
      for (const auto &[name, r] :
           {std::make_pair("uniform fine", &uf), std::make_pair("multi-grid", &mg),
            std::make_pair("adaptive hybrid", &ah)})
        std::cout << "# " << name << " | " << r->n_active_coarse << " | " << r->n_active_fine
                  << " | " << r->n_fictitious << " | " << r->n_constrained << " | "
                  << r->n_wls_rows << " | " << r->setup_seconds << " | "
                  << 100. * r->step_cpu_seconds << " | "
                  << uf.step_cpu_seconds / r->step_cpu_seconds << "\n";
      std::cout << "corrosion_3d_uniform_fine_seconds_per_100_steps: "
                << 100. * uf.step_cpu_seconds << "\n"
                << "corrosion_3d_multigrid_seconds_per_100_steps: " << 100. * mg.step_cpu_seconds
                << "\n"
                << "corrosion_3d_adaptive_hybrid_seconds_per_100_steps: "
                << 100. * ah.step_cpu_seconds << "\n"
                << "corrosion_3d_speedup_multigrid_over_uniform_fine: "
                << uf.step_cpu_seconds / mg.step_cpu_seconds << "\n"
                << "corrosion_3d_speedup_adaptive_hybrid_over_uniform_fine: "
                << uf.step_cpu_seconds / ah.step_cpu_seconds << std::endl;
    }
}
