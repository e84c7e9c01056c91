// The Kalthoff-Winkler case shared by the hybrid test (tests/hybrid_kw) and
// contrib/benchmarks/kw_hybrid_benchmark.cc, so both run the same problem.
#ifndef perideal_tests_hybrid_kw_kalthoff_winkler_case_h
#define perideal_tests_hybrid_kw_kalthoff_winkler_case_h

#include <perideal/discretization/domain.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include <memory>
#include <string>

namespace PeriDEAL
{
// The Kalthoff-Winkler setup of tutorial/step-4 (plate 100 x 200 mm,
// pre-cracks at y = +-25 from x = 0 to 50, v0 = 16.5 m/s between them,
// steel, G0 = 22.17 N/mm, plane strain, omega_0, cell-centred lattice).
inline MechanicsRunParameters<2>
kalthoff_winkler(const double dx, const double delta, const double end_time,
                 const std::string &quadrature, const double sigma, const std::string &dir,
                 const unsigned int time_series_interval = 1000000)
{
  MechanicsRunParameters<2> p;
  p.domain                 = std::make_shared<BoxDomain<2>>(Point<2>(0., -100.), Point<2>(100., 100.));
  p.lattice.dx             = dx;
  p.lattice.delta          = delta;
  p.lattice.cell_centered  = true;
  p.model.omega            = InfluenceFunction::constant;
  p.model.youngs_modulus   = 190e3;
  p.model.plane_stress     = false;
  p.model.fracture_energy  = 22.17;
  p.density                = 8e-9;
  p.initial_velocity       = "0; 0";
  p.body_force             = "0; 0";
  typename MechanicsRunParameters<2>::Region v;
  v.level_set = "max(x - " + std::to_string(dx) + ", abs(y) - 25)";
  v.value     = "16.5e3; 0";
  p.prescribed_velocities = {v};
  p.precracks = {{Point<2>(-1., 25.), Point<2>(50., 25.)}, {Point<2>(-1., -25.), Point<2>(50., -25.)}};
  p.measure_crack         = true;
  p.crack_origin          = Point<2>(50., 25.);
  p.crack_region          = "max(50 - x, 25 - y)";
  p.crack_fit_min_radius  = delta;
  p.crack_fit_max_radius  = 50.;
  p.time_step             = 0.;
  p.end_time              = end_time;
  p.output_directory      = dir;
  p.time_series_interval  = time_series_interval;
  p.progress_interval     = 1e9;
  p.quadrature            = quadrature;
  p.hybrid.sigma          = sigma;
  return p;
}
} // namespace PeriDEAL

#endif
