// ---------------------------------------------------------------------
// Kalthoff-Winkler (dissertation Sect. 3.3.1, Table 3.3): the uniform
// standard scheme against the adaptive hybrid configuration (standard PMB on
// Omega_s, WLS-2 on Omega_w, switching (3.80)) at the same resolution and
// time step. Prints a table like Table 3.3 and `key: value` lines.
//
//   kw_hybrid_benchmark [--dx 0.5] [--m 8] [--end-time 87.5e-6]
//                       [--sigma 0.95] [--interval 1] [--directory kw-hybrid-benchmark]
//
// The plate is that of tutorial/step-4 (100 x 200 mm, pre-cracks of 50 mm
// at y = +-25); the source uses dx = 0.25 mm, delta = 2 mm (m = 8), 43,500
// steps, which takes hours on one core, so the default is dx = 0.5,
// delta = 4 (m = 8, 80,000 nodes) with 0.9 x the critical step.
// ---------------------------------------------------------------------

#include <deal.II/base/mpi.h>

#include <perideal/time_stepping/mechanics_solver.h>

#include "../../tests/hybrid_kw/kalthoff_winkler_case.h"

#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>

using namespace dealii;
using namespace PeriDEAL;


int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  double      dx = 0.5, m = 8., end_time = 87.5e-6, sigma = 0.95;
  int         interval = 1;
  std::string dir = "kw-hybrid-benchmark";
  for (int a = 1; a + 1 < argc; a += 2)
    {
      const std::string key = argv[a], value = argv[a + 1];
      if (key == "--dx")
        dx = std::stod(value);
      else if (key == "--m")
        m = std::stod(value);
      else if (key == "--end-time")
        end_time = std::stod(value);
      else if (key == "--sigma")
        sigma = std::stod(value);
      else if (key == "--interval")
        interval = std::stoi(value);
      else if (key == "--directory")
        dir = value;
      else
        {
          std::cerr << "unknown option " << key << std::endl;
          return 2;
        }
    }
  const bool   root  = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  const double delta = m * dx;

  // Hybrid first: its time step bound (WLS symbol) is the smaller one, and
  // both runs use it.
  Timer              setup_timer(MPI_COMM_WORLD, true);
  auto ph = kalthoff_winkler(dx, delta, end_time, "hybrid adaptive", sigma, dir + "/hybrid", 100000000);
  ph.hybrid.check_interval = interval;
  MechanicsSolver<2> hybrid(MPI_COMM_WORLD, ph);
  hybrid.setup();
  const double hybrid_setup = setup_timer.wall_time();
  const double initial      = hybrid.hybrid_model()->standard_fraction();
  auto ps = kalthoff_winkler(dx, delta, end_time, "standard", sigma, dir + "/standard", 100000000);
  ps.time_step = hybrid.integrator().time_step();
  setup_timer.restart();
  MechanicsSolver<2> standard(MPI_COMM_WORLD, ps);
  standard.setup();
  const double standard_setup = setup_timer.wall_time();

  standard.run();
  hybrid.run();
  const auto   ms = standard.measure(), mh = hybrid.measure();
  const auto  *hm = hybrid.hybrid_model();
  const double ts = Utilities::MPI::max(standard.stepping_wall_time(), MPI_COMM_WORLD),
               th = Utilities::MPI::max(hybrid.stepping_wall_time(), MPI_COMM_WORLD);
  const double final_fraction = hm->standard_fraction();
  std::array<double, 3> parts = hm->seconds;
  for (double &s : parts)
    s = Utilities::MPI::max(s, MPI_COMM_WORLD);
  const auto overstretched = hm->n_overstretched_bonds();
  if (!root)
    return 0;

  std::cout << std::setprecision(4) << "Kalthoff-Winkler, dx = " << dx << " mm, delta = " << delta
            << " mm (m = " << m << "), " << standard.discretization().n_global() << " nodes, "
            << standard.discretization().n_global_bonds() << " bonds, "
            << hybrid.integrator().step() << " steps of " << hybrid.integrator().time_step()
            << " s, sigma = " << sigma << ", switching test every " << interval << " step(s)\n\n"
            << "                               Standard    Adaptive   (source: Table 3.3)\n"
            << "  Initial Omega_s portion [%]  " << std::setw(8) << 100. << "    " << std::setw(8)
            << 100. * initial << "   (100 / 9.72)\n"
            << "  Final Omega_s portion [%]    " << std::setw(8) << 100. << "    " << std::setw(8)
            << 100. * final_fraction << "   (100 / 14.70)\n"
            << "  Run time (stepping) [s]      " << std::setw(8) << ts << "    " << std::setw(8)
            << th << "   (53.25 / 23.59)\n"
            << "  Setup [s]                    " << std::setw(8) << standard_setup << "    "
            << std::setw(8) << hybrid_setup << "\n"
            << "  Crack angle [deg]            " << std::setw(8) << ms.crack_angle << "    "
            << std::setw(8) << mh.crack_angle << "\n"
            << "  Crack length [mm]            " << std::setw(8) << ms.crack_length << "    "
            << std::setw(8) << mh.crack_length << "\n"
            << "  Broken bonds                 " << std::setw(8)
            << standard.model().n_broken_bonds() << "    " << std::setw(8)
            << hybrid.model().n_broken_bonds() << "\n\n"
            << "  Hybrid step time: switching test " << parts[0] << " s, standard rows " << parts[1]
            << " s, WLS rows " << parts[2] << " s (rest: Verlet update, ghost exchange)\n\n";
  std::cout << std::setprecision(6) << "kw_hybrid_nodes: " << standard.discretization().n_global()
            << "\nkw_hybrid_m: " << m << "\nkw_hybrid_steps: " << hybrid.integrator().step()
            << "\nkw_hybrid_standard_seconds: " << ts << "\nkw_hybrid_adaptive_seconds: " << th
            << "\nkw_hybrid_initial_standard_percent: " << 100. * initial
            << "\nkw_hybrid_final_standard_percent: " << 100. * final_fraction
            << "\nkw_hybrid_switch_test_seconds: " << parts[0]
            << "\nkw_hybrid_standard_rows_seconds: " << parts[1]
            << "\nkw_hybrid_wls_rows_seconds: " << parts[2]
            << "\nkw_hybrid_overstretched_bonds: " << overstretched
            << "\nkw_hybrid_crack_angle_standard: " << ms.crack_angle
            << "\nkw_hybrid_crack_angle_adaptive: " << mh.crack_angle
            << "\nkw_speedup_hybrid_adaptive_over_standard: " << ts / th << std::endl;
  return 0;
}
