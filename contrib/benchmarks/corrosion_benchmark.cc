// 3D corrosion run times (serial, CPU seconds of the time stepping; setup
// excluded as in [100] Table 2). Prints `key: value` lines:
//  (1) corrosion_3d_speedup_hybrid_over_standard: dissertation Sect. 3.3.2
//      (Table 3.4, bunny, 3.7x) reduced: the source's material and
//      discretization (dx = 0.1, delta = 0.6, m = 6, WLS-2 with 123
//      collocation nodes) on a solid ball of radius 1 in a liquid ball of
//      radius 2; Omega_s = the ball of radius 1.41 around the solid, 35 % of
//      the body as in the source; standard vs hybrid, --steps steps.
//  (2) corrosion_3d_speedup_adaptive_hybrid_over_uniform_fine: [100]
//      Example 2 / Table 2 (11.76x on 48 cores) reduced: a solid cylinder
//      (r = 0.3, h = 1.2) in an electrolyte cube [-1.65, 1.65]^3 (C = 0
//      within delta of its faces), dx+ = 2 dx- = 0.15, delta = 0.45 (m+ = 3,
//      m- = 6; the source has m+ = 6, m- = 12), Omega- = the solid cylinder
//      enlarged by delta. Uniform fine vs multi-grid vs adaptive hybrid.
// Usage: corrosion_benchmark [--steps N] [--case hybrid|multigrid|all]

#include <deal.II/base/mpi.h>
#include <deal.II/base/timer.h>

#include <perideal/multigrid/multigrid_discretization.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include "../../tests/check.h"
#include "../../tests/multigrid/corrosion_3d_cases.h"

#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>

using namespace dealii;
using namespace PeriDEAL;

namespace
{
  // best of two repetitions of the stepping CPU time (load noise)
  double
  hybrid_seconds_per_step(const bool hybrid, const unsigned int steps,
                          types::global_dof_index &n_nodes, types::global_dof_index &n_wls,
                          double &operator_seconds)
  {
    const double R = 2., r_s = 1., w = 0.41, dt = 6.;
    double       best = 1e300;
    for (unsigned int rep = 0; rep < 2; ++rep)
      {
        DiffusionSolver<3> solver(
          MPI_COMM_WORLD,
          PeriDEALTests::parameters_from_text<DiffusionRunParameters<3>>(
            PeriDEALTests::corrosion_3d_hybrid_parameters(
              R, r_s, dt, steps * dt,
              hybrid ? PeriDEALTests::corrosion_3d_hybrid_region(r_s, w) : "")));
        solver.setup();
        Timer t;
        while (solver.step() < solver.n_steps())
          solver.advance();
        best    = std::min(best, t.cpu_time() / steps);
        operator_seconds =
          solver.timer().get_summary_data(TimerOutput::total_wall_time)["operator"] / steps;
        n_nodes = solver.discretization().n_global();
        n_wls   = solver.n_wls_rows();
      }
    return best;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  unsigned int                     steps = 10;
  std::string                      which = "all";
  for (int a = 1; a + 1 < argc; a += 2)
    {
      const std::string k = argv[a];
      if (k == "--steps")
        steps = std::max(1, std::atoi(argv[a + 1]));
      else if (k == "--case")
        which = argv[a + 1];
    }
  std::cout << std::setprecision(6);
  if (which == "all" || which == "hybrid")
    {
      types::global_dof_index n = 0, n_wls = 0;
      double                  so = 0., ho = 0.;
      const double s = hybrid_seconds_per_step(false, steps, n, n_wls, so);
      const double h = hybrid_seconds_per_step(true, steps, n, n_wls, ho);
      std::cout << "corrosion_3d_hybrid_nodes: " << n << "\n"
                << "corrosion_3d_hybrid_wls_rows: " << n_wls << "\n"
                << "corrosion_3d_standard_seconds_per_step: " << s << "\n"
                << "corrosion_3d_hybrid_seconds_per_step: " << h << "\n"
                << "corrosion_3d_hybrid_operator_speedup_wall: " << so / ho << "\n"
                << "corrosion_3d_speedup_hybrid_over_standard: " << s / h << std::endl;
    }
  if (which == "all" || which == "multigrid")
    {
      MultiGrid::CylinderCorrosionCase c;
      c.half_width  = 1.65;
      c.radius      = 0.3;
      c.half_height = 0.6;
      c.end_time    = 1e300;
      // dt of the adaptive hybrid (the smallest bound) for all
      const auto ah = MultiGrid::run_cylinder_corrosion(c, "adaptive hybrid", steps);
      c.time_step   = ah.time_step;
      const auto mg = MultiGrid::run_cylinder_corrosion(c, "multi-grid", steps);
      const auto uf = MultiGrid::run_cylinder_corrosion(c, "uniform fine", steps);
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
