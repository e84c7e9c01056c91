// Parameter files of the 3D hybrid corrosion case (dissertation Sect. 3.3.2,
// reduced), shared by tests/multigrid and contrib/benchmarks.
#ifndef perideal_tests_multigrid_corrosion_3d_cases_h
#define perideal_tests_multigrid_corrosion_3d_cases_h

#include <sstream>
#include <string>

namespace PeriDEALTests
{
  // ---------------------------------------------------------------------
  // 3D corrosion with the hybrid fixed configuration, dissertation Sect.
  // 3.3.2 (E4) at a reduced size: the source's material and discretization
  // (kappa_liq = 0.0126, kappa_int = 0.0029 s^-1 mm^-2, C_sat = 5100,
  // C_solid = 143000 mol/m^3, q = 1, delta = 0.6 mm, dx = 0.1 mm, m = 6,
  // WLS-2 with n_c = 123), the Stanford bunny replaced by a solid ball of
  // radius r_s in a liquid ball of radius R (C = 0 on a layer of thickness
  // delta outside it, as the source's "C = 0 within delta of the sphere").
  // Omega_s (standard scheme) = the shell |x| < r_s + w around the solid,
  // where the phase interface lives; WLS-2 elsewhere.
  inline std::string
  corrosion_3d_hybrid_parameters(const double R, const double r_s, const double dt,
                                 const double end_time, const std::string &hybrid)
  {
    std::ostringstream s;
    s.precision(17);
    s << "subsection Geometry\n set Domain = ball\n set Center = 0, 0, 0\n set Radius = " << R
      << "\nend\n"
      << "subsection Discretization\n set Grid spacing = 0.1\n set Horizon = 0.6\n"
      << " set Lattice = cell centered\n set Volume constraint layer = -1\nend\n"
      << "subsection Model\n set Type = corrosion\n set Kernel exponent = 1\n"
      << " set Initial condition = 143000 * (x^2 + y^2 + z^2 < " << r_s * r_s << ")\n"
      << " subsection Corrosion\n  set Liquid micro-diffusivity = 0.0126\n"
      << "  set Interface micro-diffusivity = 0.0029\n  set Saturation concentration = 5100\n"
      << " end\nend\n"
      << "subsection Time stepping\n set End time = " << end_time << "\n set Time step = " << dt
      << "\nend\nsubsection Output\n set Time series interval = 1000000\nend\n"
      << "subsection Hybrid\n" << hybrid << "end\n";
    return s.str();
  }

  inline std::string
  corrosion_3d_hybrid_region(const double r_s, const double w)
  {
    std::ostringstream s;
    s.precision(17);
    s << " set Quadrature = hybrid\n set Standard region = x^2 + y^2 + z^2 < "
      << (r_s + w) * (r_s + w) << "\n";
    return s.str();
  }

} // namespace PeriDEALTests

#endif
