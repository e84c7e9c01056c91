// Stability, analytical nonlocal solutions and moving interfaces of PD
// diffusion (paper 003, Scabbia et al.): the Gershgorin bounds of Sect. 3
// against the eigenvalues of the iteration matrix (LAPACK), forward Euler
// just above/below the critical step, the library's time-step check, the
// closed forms (45)-(52), the surface node method (SNM) against the nonlocal
// eigen-expansions of Sect. 4.1 (m-convergence with continuous and
// discontinuous initial data) and the manufactured moving interface of
// Sect. 5. References are closed forms, the catalog's independently derived
// values (shared/reference/catalog_papers_001-004.md, Sect. 3) and LAPACK
// eigenvalues, never numbers this code produced.

#include <deal.II/base/parameter_handler.h>
#include <deal.II/lac/lapack_full_matrix.h>

#include <perideal/base/analytical_solutions.h>
#include <perideal/base/exceptions.h>
#include <perideal/models/surface_node_method.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include "../check.h"

#include <cmath>
#include <complex>
#include <iomanip>
#include <map>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  // Table 1 of 003: l = 1 cm, delta = 0.05 cm, D = 1 cm^2/s, Cbar = 1; d = D/delta (4).
  constexpr double length = 1., delta = 0.05, D = 1., Cbar = 1., d = D / delta;

  double
  mu(const double r)
  {
    return 1. / (r * r);
  }

  SurfaceNodeRodParameters
  rod(const unsigned int m_bar, const FictitiousExtrapolation ext, const bool half = false)
  {
    SurfaceNodeRodParameters p;
    p.left        = half ? 0. : -0.5 * length;
    p.right       = 0.5 * length;
    p.dx          = delta / m_bar;
    p.delta       = delta;
    p.diffusivity = PhaseChangeDiffusivity::single_phase(d);
    p.extrapolation = {{half ? FictitiousExtrapolation::symmetric : ext, ext}};
    for (auto &c : p.condition)
      c.value = [](double) { return Cbar; };
    return p;
  }

  std::string
  str(const double v)
  {
    std::ostringstream s;
    s << std::setprecision(5) << v;
    return s.str();
  }

  // (45), (47), (48) with beta = 1 against the catalog's table (4 digits),
  // and the Gershgorin bound of the assembled iteration matrix against the
  // closed forms: with beta = 1 and no self-transfer the tightest row is the
  // node b next to the surface and gives exactly (47) = Theorem (17); with
  // the self-transfer the strict row bound has mu(dx) where (48) has
  // mu(dx)/2 (catalog erratum), i.e. 1/(d [sum mu (m+1) + mu(dx)] dx).
  void
  bounds_closed_form()
  {
    struct Row
    {
      unsigned int m;
      double       bulk, taylor, taylor_st;
    };
    for (const Row r : {Row{2, 5.000e-4, 4.545e-4, 3.846e-4}, Row{4, 2.195e-4, 1.782e-4, 1.560e-4},
                        Row{16, 4.931e-5, 3.147e-5, 2.859e-5}, Row{64, 1.199e-5, 6.129e-6, 5.683e-6}})
      {
        const double dx = delta / r.m;
        const std::string m = " m = " + std::to_string(r.m);
        check_close(StabilityBounds::bulk(d, mu, dx, r.m), r.bulk, 1e-3, "(45)" + m);
        check_close(StabilityBounds::linear_taylor(d, mu, dx, r.m), r.taylor, 1e-3, "(47)" + m);
        check_close(StabilityBounds::linear_taylor_self_transfer(d, mu, dx, r.m), r.taylor_st,
                    1e-3, "(48)" + m);
        if (r.m > 16)
          continue;
        auto p           = rod(r.m, FictitiousExtrapolation::linear_taylor);
        p.partial_volume = false;
        p.self_transfer  = false;
        const auto g     = SurfaceNodeRod(p).gershgorin_bound();
        check_close(g.time_step, StabilityBounds::linear_taylor(d, mu, dx, r.m), 1e-12,
                    "Gershgorin of the assembled matrix = (17)/(47)" + m);
        check(g.row == 0 || g.row == SurfaceNodeRod(p).n_nodes() - 1,
              "tightest row is the node next to the surface" + m);
        p.self_transfer = true;
        double s        = 0.;
        for (unsigned int k = 1; k <= r.m; ++k)
          s += mu(k * dx) * (k + 1.);
        check_close(SurfaceNodeRod(p).gershgorin_bound().time_step,
                    1. / (d * (s + mu(dx)) * dx), 1e-12,
                    "Gershgorin with self-transfer = 1/(d[sum mu(m+1) + mu(dx)]dx)" + m);
      }
    // catalog: the strict row bound of (13) as written, m = 4 and 16
    for (const auto &[m, value] : std::map<unsigned int, double>{{4, 1.387e-4}, {16, 2.619e-5}})
      {
        auto p           = rod(m, FictitiousExtrapolation::linear_taylor);
        p.partial_volume = false;
        check_close(SurfaceNodeRod(p).gershgorin_bound().time_step, value, 1e-3,
                    "catalog strict Gershgorin, m = " + std::to_string(m));
      }
  }

  // LAPACK eigenvalues of the SNM iteration matrix (linear Taylor,
  // self-transfer, Dirichlet ends, as 003 runs it). The Gershgorin bound is
  // sufficient, so the true critical step must not be below it; the
  // catalog's power-iteration estimates (~3 digits) locate it; the bulk
  // bound (16) ignores the boundary rows and is unstable here, which is the
  // paper's point; the paper's steps (0.1 ms at m = 4, 1e-5 s at m = 16)
  // are stable.
  void
  eigenvalue_bound()
  {
    struct Case
    {
      unsigned int m;
      double       catalog_beta1, catalog_exact, paper_dt, unstable_dt;
    };
    for (const Case c : {Case{4, 1.69e-4, 1.74e-4, 1e-4, 1.9e-4}, Case{16, 3.31e-5, 3.33e-5, 1e-5, 3.4e-5}})
      for (const bool exact_beta : {false, true})
        {
          auto p           = rod(c.m, FictitiousExtrapolation::linear_taylor);
          p.partial_volume = exact_beta;
          const SurfaceNodeRod r(p);
          const double         dt_eig = r.eigenvalue_time_step();
          const auto           g      = r.gershgorin_bound();
          const double         dx     = delta / c.m;
          const std::string    tag =
            " (m = " + std::to_string(c.m) + (exact_beta ? ", exact beta)" : ", beta = 1)");
          std::cout << "  m = " << c.m << (exact_beta ? " exact beta" : " beta = 1")
                    << ": critical dt (eigenvalues) " << dt_eig << ", Gershgorin " << g.time_step
                    << " (ratio " << g.time_step / dt_eig << "), (48) "
                    << StabilityBounds::linear_taylor_self_transfer(d, mu, dx, c.m)
                    << ", bulk (16) " << StabilityBounds::bulk(d, mu, dx, c.m)
                    << ", (32) holds: " << g.upper_half_guaranteed << std::endl;
          // 2 % band: the catalog states "approximately" with 3 digits.
          check_close(dt_eig, exact_beta ? c.catalog_exact : c.catalog_beta1, 0.02,
                      "critical step vs catalog power iteration" + tag);
          check(g.time_step <= dt_eig, "Gershgorin bound <= critical step" + tag);
          // Gershgorin is a bound, not the eigenvalue: it is within 25 % of
          // the critical step here (measured 0.80 / 0.79 for m = 4, 16).
          check(g.time_step >= 0.75 * dt_eig, "Gershgorin bound within 25 % of critical" + tag);
          check(r.spectral_radius(0.999 * dt_eig) <= 1. + 1e-12 &&
                  r.spectral_radius(1.001 * dt_eig) > 1.,
                "rho(A) crosses 1 at the critical step" + tag);
          check(r.spectral_radius(c.paper_dt) < 1., "paper's step stable" + tag);
          check(r.spectral_radius(c.unstable_dt) > 1., "catalog's unstable step" + tag);
          check(r.spectral_radius(StabilityBounds::bulk(d, mu, dx, c.m)) > 1.,
                "bulk bound (16) is unstable with the SNM" + tag);
        }
  }

  // Forward Euler just above the critical step diverges, just below stays
  // bounded; the library check rejects steps above the Gershgorin bound
  // with a ParameterError naming the parameter.
  void
  divergence()
  {
    auto p = rod(4, FictitiousExtrapolation::linear_taylor);
    for (auto &c : p.condition)
      c.value = [](double) { return 0.; };
    const SurfaceNodeRod r(p);
    const double         dt_eig = r.eigenvalue_time_step();
    for (const double f : {0.98, 1.05})
      {
        std::vector<double> C(r.n_nodes());
        for (unsigned int i = 0; i < C.size(); ++i) // rough data exciting every mode
          C[i] = (i % 2 ? 1. : -1.) + std::sin(7. * i);
        double t = 0.;
        double peak = 0.;
        for (unsigned int s = 0; s < 600; ++s)
          {
            r.forward_euler_step(t, f * dt_eig, C);
            for (const double c : C)
              peak = std::max(peak, std::abs(c));
          }
        if (f < 1.)
          check(peak < 10., "0.98 x critical step stays bounded (max " + str(peak) + ")");
        else
          check(peak > 1e6, "1.05 x critical step diverges (max " + str(peak) + ")");
      }
    const double g = r.gershgorin_bound().time_step;
    r.check_time_step(g);
    bool thrown = false;
    try
      {
        r.check_time_step(1.01 * g, "Time stepping/Time step");
      }
    catch (ParameterError &e)
      {
        thrown = e.parameter == "Time stepping/Time step";
        std::cout << "  message: " << e.what() << std::endl;
      }
    check(thrown, "step above the Gershgorin bound throws ParameterError");
  }

  // The library's DiffusionOperator (volume-constraint layer): the bound of
  // critical_time_step() against LAPACK eigenvalues of its matrix in a small
  // 1D case, with and without the layer, constant and linear influence.
  void
  library_bound()
  {
    for (const bool layer : {false, true})
      for (const std::string omega : {"constant", "linear"})
        {
          const std::string text = std::string(R"(
subsection Geometry
  set Domain = box
  set Lower corner = 0
  set Upper corner = 2
end
subsection Discretization
  set Grid spacing = 0.05
  set Horizon factor = 4
)") + (layer ? "  set Volume constraint layer = 0.2\n" : "") +
                                   "end\nsubsection Model\n  set Influence function = " + omega +
                                   "\nend\n";
          const auto p = parameters_from_text<DiffusionRunParameters<1>>(text);
          DiffusionSolver<1> s(MPI_COMM_WORLD, p);
          s.setup();
          const auto  &disc = s.discretization();
          const auto  &op   = s.get_operator();
          std::vector<unsigned int> unknowns;
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            if (disc.region[i] == Discretization<1>::interior)
              unknowns.push_back(i);
          const unsigned int       n = unknowns.size();
          LAPACKFullMatrix<double> L(n, n);
          PeriDEAL::Vector         C = s.solution(), R = s.solution();
          for (unsigned int k = 0; k < n; ++k)
            {
              C = 0.;
              C.local_element(unknowns[k]) = 1.;
              C.update_ghost_values();
              op.apply(C, R);
              for (unsigned int i = 0; i < n; ++i)
                L(i, k) = R.local_element(unknowns[i]);
            }
          L.compute_eigenvalues();
          double dt_eig = std::numeric_limits<double>::infinity();
          for (unsigned int i = 0; i < n; ++i)
            {
              const auto l = L.eigenvalue(i);
              if (std::abs(l) > 1e-12)
                dt_eig = std::min(dt_eig, -2. * l.real() / std::norm(l));
            }
          const double      bound = s.critical_time_step();
          const std::string tag   = std::string(layer ? " with layer, " : " Neumann, ") + omega;
          std::cout << "  library" << tag << ": bound " << bound << ", eigenvalue critical "
                    << dt_eig << " (ratio " << bound / dt_eig << ")" << std::endl;
          check(bound <= dt_eig * (1. + 1e-12), "library bound <= critical step" + tag);
          // Gershgorin on the bulk rows: within a factor 2 of the eigenvalue
          // limit (the checkerboard mode only sees the odd bonds).
          check(bound >= 0.5 * dt_eig, "library bound within 2x of critical" + tag);
        }
  }

  // Closed forms of the analytical header: Si, the nonlocal factor (52)
  // (catalog values), the quadrature symbol of a ScalarKernel, the local
  // limit, the eigen-expansions (51)/(54) against the catalog's table, and
  // the Fourier integral with the local symbol against the heat kernel.
  void
  analytical()
  {
    using namespace Analytical;
    check_close(sine_integral(1.), 0.946083070367183, 1e-13, "Si(1)");
    check_close(sine_integral(M_PI), 1.851937051982466, 1e-13, "Si(pi)");
    check_close(sine_integral(10.), 1.658347594218874, 1e-13, "Si(10)");
    check_close(sine_integral(100.), 1.562225466889056, 1e-13, "Si(100)");
    const auto psi = inverse_square_symbol(D, delta);
    check_close(psi(M_PI), 9.862843, 2e-7, "psi(pi) (52)");
    check_close(psi(3 * M_PI), 88.28094, 2e-7, "psi(3 pi)");
    check_close(psi(5 * M_PI), 242.5640, 2e-7, "psi(5 pi)");
    check_close(pd_symbol_inverse_square_1d(D, 1e-4, 2.), 4., 1e-8, "psi -> k^2 as delta -> 0");
    ScalarKernel k;
    k.dim      = 1;
    k.exponent = 2.;
    k.delta    = delta;
    k.constant = d;
    for (const double kk : {0.3, M_PI, 77., 1253.})
      check_close(pd_symbol_1d(k, kk), psi(kk), 1e-11, "quadrature symbol = (52), k = " + str(kk));
    // J_1 kernel calibrated to D: its symbol tends to D k^2 for small k delta.
    k.exponent = 1.;
    k.constant = k.micro_constant_for(D);
    check_close(pd_symbol_1d(k, 0.01 / delta) / (1e-4 / (delta * delta)), D, 1e-5,
                "calibrated J_1 kernel: lambda ~ D k^2");

    const auto cont = rod_quadratic_initial_data(length, Cbar, psi, 200);
    const auto disc = rod_zero_initial_data(length, Cbar, psi, 200);
    for (const double x : {0., 0.25, 0.45})
      check_close(cont.value(x, 0.), 4. * x * x, 0., "(51) at t = 0, x = " + str(x), 1e-7);
    // catalog table (6 decimals)
    const std::map<std::pair<double, double>, std::pair<double, double>> table = {
      {{0.01, 0.}, {0.079989, 0.000994}},  {{0.01, 0.45}, {0.845996, 0.722329}},
      {{0.05, 0.}, {0.370186, 0.227564}},  {{0.05, 0.25}, {0.554000, 0.446541}},
      {{0.1, 0.25}, {0.727821, 0.664174}}, {{0.2, 0.45}, {0.977543, 0.972294}},
      {{0.5, 0.}, {0.992552, 0.990812}}};
    for (const auto &[tx, v] : table)
      {
        const std::string at = " t = " + str(tx.first) + ", x = " + str(tx.second);
        check_close(cont.value(tx.second, tx.first), v.first, 0., "(51)" + at, 6e-7);
        check_close(disc.value(tx.second, tx.first), v.second, 0., "(54)" + at, 6e-7);
      }
    // local limit of the same rod: the catalog's 0.370386 / 0.227688 at x = 0, t = 0.05
    check_close(rod_quadratic_initial_data(length, Cbar, local_symbol(D)).value(0., 0.05), 0.370386,
                0., "(51) local", 6e-7);
    check_close(rod_zero_initial_data(length, Cbar, local_symbol(D)).value(0., 0.05), 0.227688, 0.,
                "(54) local", 6e-7);
    // Fourier integral, local symbol: the heat kernel.
    const double s = 0.1, t = 0.02, A = 2.;
    for (const double x : {0., 0.07, 0.3})
      {
        const double var = s * s + 2. * D * t;
        check_close(gaussian_1d(A, s, 0.1, local_symbol(D), x + 0.1, t),
                    A * s / std::sqrt(var) * std::exp(-x * x / (2. * var)), 1e-10,
                    "Fourier integral = heat kernel, x = " + str(x));
      }
    check_close(gaussian_1d(A, s, 0., psi, 0.05, 0.), A * std::exp(-0.125), 1e-10,
                "Fourier integral at t = 0");
  }

  // The SNM with linear Taylor extrapolation reproduces linear fields: zero
  // rate everywhere, and the flux (11) of C = a x is -D a (1 - dx/(2 delta))
  // with the exact beta (the crossing bonds of length m dx number m, the
  // longest ones carry beta = 1/2) and exactly -D a with beta = 1. A flux
  // condition therefore drives the steady slope to J/(-D (1 - dx/(2 delta))).
  void
  snm_linear_field()
  {
    for (const bool exact_beta : {true, false})
      {
        auto p           = rod(4, FictitiousExtrapolation::linear_taylor);
        p.partial_volume = exact_beta;
        const double a = 0.7, c0 = 0.3;
        p.condition[0].value = [&](double) { return c0 + a * p.left; };
        p.condition[1].value = [&](double) { return c0 + a * p.right; };
        const SurfaceNodeRod r(p);
        std::vector<double>  C(r.n_nodes()), rate;
        for (unsigned int i = 0; i < C.size(); ++i)
          C[i] = c0 + a * r.position(i);
        r.rate(0., C, rate);
        double m = 0.;
        for (const double v : rate)
          m = std::max(m, std::abs(v));
        const double factor = exact_beta ? 1. - p.dx / (2. * delta) : 1.;
        const std::string tag = exact_beta ? " (exact beta)" : " (beta = 1)";
        check(m < 1e-9, "linear field: zero rate" + tag + ", max " + str(m));
        check_close(r.surface_flux(1, 0., C), -D * a * factor, 1e-12, "right flux" + tag);
        check_close(r.surface_flux(0, 0., C), D * a * factor, 1e-12, "left flux" + tag);
      }
    // flux condition J = -0.5 at the right, C = 0 at the left, from C = 0
    auto p                = rod(4, FictitiousExtrapolation::linear_taylor);
    p.left                = 0.;
    p.extrapolation[0]    = FictitiousExtrapolation::linear_taylor;
    p.condition[0].value  = [](double) { return 0.; };
    p.condition[1].type   = SurfaceCondition::Type::flux;
    p.condition[1].value  = [](double) { return -0.5; };
    const SurfaceNodeRod r(p);
    const double         dt = 0.9 * r.gershgorin_bound().time_step;
    std::vector<double>  C(r.n_nodes(), 0.);
    double               t = 0.;
    while (t < 8.)
      r.forward_euler_step(t, dt, C);
    const double slope = 0.5 / (D * (1. - p.dx / (2. * delta)));
    double       err   = 0.;
    for (unsigned int i = 0; i < C.size(); ++i)
      err = std::max(err, std::abs(C[i] - slope * r.position(i)));
    check(err < 1e-8, "flux condition: steady linear profile, max deviation " + str(err));
    check_close(r.surface_values(t, C)[1], slope * 0.5, 1e-8, "surface value of the flux end");
  }

  double
  rate_of(const double e_coarse, const double e_fine)
  {
    return std::log2(e_coarse / e_fine);
  }

  // m-convergence of Sect. 4.2 (delta fixed) with the antisymmetric
  // extrapolation the analytical solutions assume, half rod with a symmetry
  // end at x = 0 (as 003). RK4 at a quarter of the forward Euler bound so the
  // time error is negligible (checked: halving dt changes the error by < 1 %),
  // in place of forward Euler at dt = 5e-8 s. t_f = 0.5 s as 003.
  void
  convergence()
  {
    const auto psi  = Analytical::inverse_square_symbol(D, delta);
    const auto cont = Analytical::rod_quadratic_initial_data(length, Cbar, psi, 200);
    const auto disc = Analytical::rod_zero_initial_data(length, Cbar, psi, 200);
    std::vector<double> ec, ed0, ed1;
    const auto quadratic = [](const double x) { return 4. * Cbar * x * x / (length * length); };
    const auto zero      = [](const double) { return 0.; };
    const auto ref_c = [&](const double x, const double t) { return cont.value(x, t); };
    const auto ref_d = [&](const double x, const double t) { return disc.value(x, t); };
    for (const unsigned int m : {2u, 4u, 8u})
      {
        const SurfaceNodeRod r(rod(m, FictitiousExtrapolation::antisymmetric, true));
        const double         dt    = 0.25 * r.gershgorin_bound().time_step;
        const double         t_end = 0.5;
        const auto a = run_against_reference(r, quadratic, ref_c, dt, t_end, true, Cbar);
        const auto b = run_against_reference(r, zero, ref_d, dt, t_end, true, Cbar);
        ec.push_back(a.max_after(0.));
        ed0.push_back(b.max_after(0.));
        ed1.push_back(b.max_after(1e-3));
        std::cout << "  m = " << m << ": continuous " << ec.back()
                  << ", discontinuous (t0 = 1 ms) " << ed1.back() << ", (t0 = 0) " << ed0.back()
                  << std::endl;
        if (m == 4)
          {
            const auto a2 = run_against_reference(r, quadratic, ref_c, 0.5 * dt, t_end, true, Cbar);
            check_close(a2.max_after(0.), ec.back(), 0.01, "time error negligible (m = 4, dt/2)");
          }
      }
    for (unsigned int k = 0; k + 1 < ec.size(); ++k)
      std::cout << "  rates " << (2u << k) << "->" << (4u << k) << ": continuous "
                << rate_of(ec[k], ec[k + 1]) << ", discontinuous t0 = 1 ms "
                << rate_of(ed1[k], ed1[k + 1]) << ", t0 = 0 " << rate_of(ed0[k], ed0[k + 1])
                << std::endl;
    for (unsigned int k = 0; k + 1 < ec.size(); ++k)
      {
        const double rc = rate_of(ec[k], ec[k + 1]), rd = rate_of(ed1[k], ed1[k + 1]),
                     r0 = rate_of(ed0[k], ed0[k + 1]);
        check(ed1[k] > ec[k], "discontinuous error exceeds continuous");
        // Midpoint quadrature and the self-transfer are second order:
        // observed 2.52, 2.35, 2.21 (pre-asymptotic, falling towards 2).
        check(rc > 1.8 && rc < 2.8, "continuous rate in [1.8, 2.8]: " + str(rc));
        // 003 Fig. 14: the same rate once the first 1 ms is skipped;
        // catalog band +-0.3 (measured differences 0.18, 0.21, 0.18).
        check(std::abs(rd - rc) <= 0.3, "discontinuous rate (t0 = 1 ms) within 0.3 of continuous");
        // 003 Fig. 15: without skipping, the first steps dominate and the
        // rate drops (measured 0.77, 0.64, -0.26).
        check(r0 < 1., "discontinuous rate with t0 = 0 below 1: " + str(r0));
      }

    // 003 Sect. 4.2: with the linear Taylor extrapolation (mismatching the
    // antisymmetric extension the analytical solutions assume) convergence
    // is poor: the continuous case converges slowly and the discontinuous
    // one does not decrease.
    std::vector<double> lc, ld;
    for (const unsigned int m : {2u, 4u, 8u})
      {
        const SurfaceNodeRod r(rod(m, FictitiousExtrapolation::linear_taylor, true));
        const double         dt = 0.25 * r.gershgorin_bound().time_step;
        lc.push_back(run_against_reference(r, quadratic, ref_c, dt, 0.5, true, Cbar).max_after(0.));
        ld.push_back(run_against_reference(r, zero, ref_d, dt, 0.5, true, Cbar).max_after(1e-3));
        std::cout << "  linear Taylor m = " << m << ": continuous " << lc.back()
                  << ", discontinuous (t0 = 1 ms) " << ld.back() << std::endl;
      }
    // measured: continuous 5.5e-5, 1.1e-5, 9.7e-6 (stalls: rate 0.16 from 4 to 8);
    // discontinuous 2.2e-3, 2.3e-3, 3.7e-3 (grows, the "slight divergence").
    check(rate_of(lc[1], lc[2]) < 1., "linear Taylor, continuous: rate below 1 from m = 4 to 8");
    check(ld[2] > ld[0], "linear Taylor, discontinuous: the error does not decrease");
    check(ld[2] > 10. * ed1[2], "linear Taylor error >> antisymmetric error (m = 8)");
  }

  // 003 Sect. 5: half rod [0, l/2], symmetry at 0, SNM with linear Taylor
  // extrapolation and C = Cbar at l/2, phase rule (6) with C_i = 0.9 Cbar,
  // carbide-carbide d = 0, oxide-oxide D_o/delta, mixed D_i/delta, and the
  // manufactured source (60) with the numerical interface (midpoint between
  // the adjacent carbide and oxide nodes) as 003 Sect. 5.2. t_f is not
  // stated in 003; we take 0.5 s. Errors over 0 <= t <= 0.85 t_f.
  InterfaceTrack
  moving_interface_run(const unsigned int m, const double dt, const bool literal_naming = false)
  {
    const double t_f = 0.5, C_i = 0.9 * Cbar, D_o = 1., D_i = 0.8;
    auto         p   = rod(m, FictitiousExtrapolation::linear_taylor, true);
    p.diffusivity.threshold = C_i;
    p.diffusivity.low       = 0.;
    // (6) with oxide above C_i: both-above = oxide, mixed = interface. The
    // text of 003 assigns d2 = D_i/delta, d3 = D_o/delta (swapped, erratum).
    p.diffusivity.high  = (literal_naming ? D_i : D_o) / delta;
    p.diffusivity.mixed = (literal_naming ? D_o : D_i) / delta;
    const SurfaceNodeRod r(p);
    r.check_time_step(dt, "dt");
    const Analytical::MovingInterfaceManufactured exact(length, Cbar, t_f, C_i, delta,
                                                        p.diffusivity.low, p.diffusivity.high,
                                                        p.diffusivity.mixed);
    return track_interface(
      r, [&](const double x, const double t) { return exact.value(x, t); },
      [&](const double t) { return exact.interface_position(t); },
      [&](const double x, const double t, const double xi) { return exact.source(x, t, xi); },
      dt, 0.85 * t_f);
  }

  // The phase rule (6) including the equality cases (mixed bonds use <=),
  // the manufactured source against direct quadrature of (60), and the
  // interface tracking of Sect. 5.2 (m = 16, dt = 1e-5 s as 003) with
  // its m-convergence.
  void
  moving_interface()
  {
    PhaseChangeDiffusivity rule;
    rule.low = 1.; rule.high = 2.; rule.mixed = 3.; rule.threshold = 0.9;
    check(rule(0.1, 0.8) == 1. && rule(0.95, 1.) == 2. && rule(0.1, 0.95) == 3. &&
            rule(0.95, 0.1) == 3. && rule(0.9, 0.9) == 3. && rule(0.9, 0.1) == 3. &&
            rule(1., 0.9) == 3.,
          "phase rule (6): three bond classes and the equality cases");

    // (60) by the closed form vs adaptive midpoint quadrature away from the
    // singular point (the integrand (C(x')-C(x))/xi^2 is (xi + 2x)/xi times
    // a constant: quadrature on a symmetric grid about xi = 0 gives the PV).
    const Analytical::MovingInterfaceManufactured ex(length, Cbar, 0.5, 0.9, delta, 0., 20., 16.);
    for (const double x : {0.1, 0.44, 0.46, 0.49})
      for (const double xi : {0.3, 0.45, 0.47})
        {
          const double t = 0.1;
          double       q = 0.;
          const unsigned int N = 200000;
          const double       h = delta / N;
          auto above = [&](const double y) { return std::abs(y) > xi; };
          for (unsigned int k = 0; k < N; ++k)
            for (const double sgn : {-1., 1.})
              {
                const double z  = sgn * (k + 0.5) * h;
                const bool   a  = above(x), b = above(x + z);
                const double dk = a && b ? 20. : (!a && !b ? 0. : 16.);
                q += dk * (ex.value(x + z, t) - ex.value(x, t)) / (z * z) * h;
              }
          const double dCdt = -Cbar / 0.5 * (4. * x * x - 1.);
          if (std::abs(std::abs(x) - xi) < 2. * h)
            continue;
          check_close(ex.source(x, t, xi), dCdt - q, 1e-6,
                      "source (60) closed form vs quadrature, x = " + str(x) + ", x_i = " + str(xi),
                      1e-6);
        }
    check_close(ex.interface_position(0.), 0.474342, 1e-6, "x_i(0) (59)");
    check_close(ex.interface_position(0.25), 0.447214, 1e-6, "x_i(t_f/2)");

    std::vector<double> interface_error, concentration_error;
    for (const unsigned int m : {4u, 8u, 16u})
      for (const bool literal : {false, true})
        {
          const auto a = moving_interface_run(m, 1e-5, literal);
          std::cout << "  m = " << m << (literal ? " (003's literal d2/d3)" : "")
                    << ", dt = 1e-5: interface error " << a.max_interface_error
                    << ", max concentration error " << a.max_concentration_error
                    << " (t = " << a.time_of_max_error << ", x = " << a.position_of_max_error
                    << "), largest outward step " << a.max_outward_step << std::endl;
          if (literal)
            continue;
          interface_error.push_back(a.max_interface_error);
          concentration_error.push_back(a.max_concentration_error);
          const double dx = delta / m;
          // The phase rule (6) is reversible and the source follows the
          // numerical interface, so the node next to the interface may cross
          // C_i back once: the interface flickers by one node (measured: one
          // dx at every m); a drift outwards would exceed it.
          check(a.max_outward_step <= dx * (1. + 1e-9),
                "interface moves inward up to a one-node flicker, m = " + std::to_string(m));
          // 2 dx: the catalog's suggested band; measured 1.86-1.90 dx.
          check(a.max_interface_error <= 2. * dx,
                "interface within 2 dx of (59) for t <= 0.85 t_f, m = " + std::to_string(m));
        }
    // First-order convergence in dx of the interface and the concentration
    // (the interface is resolved to one cell; measured ratios 3.9 and 3.5
    // from m = 4 to 16): assert at least 3 (order >= 0.8).
    check(interface_error[0] / interface_error[2] >= 3., "interface error converges with m");
    check(concentration_error[0] / concentration_error[2] >= 3.,
          "concentration error converges with m");
  }

  // The library's corrosion model with the phase rule of 003 (6): a liquid
  // rod (C = 0.5 < C_sat = 0.85) fed by a uniform source S = 1 turns solid
  // when C reaches C_sat (t = 0.35) with the 'concentration' rule and stays
  // liquid with the one-way rule (2.79). Uniform C: the operator is zero,
  // so C = 0.5 + t exactly.
  void
  library_phase_rule()
  {
    for (const std::string rule : {"one-way", "concentration"})
      {
        const std::string text = R"(
subsection Geometry
  set Domain = box
  set Lower corner = 0
  set Upper corner = 1
end
subsection Discretization
  set Grid spacing = 0.05
end
subsection Model
  set Type = corrosion
  set Initial condition = 0.5
  set Source = 1
  subsection Corrosion
    set Phase rule = )" + rule + R"(
  end
end
subsection Time stepping
  set Time step = 0.001
  set End time = 0.5
end
)";
        const auto p = parameters_from_text<DiffusionRunParameters<1>>(text);
        DiffusionSolver<1> s(MPI_COMM_WORLD, p);
        s.setup();
        double t_solid = -1.;
        while (s.step() < s.n_steps())
          {
            s.advance();
            if (t_solid < 0. && s.diagnostics().solid_volume > 0.)
              t_solid = s.time();
          }
        const double solid = s.diagnostics().solid_volume;
        if (rule == "one-way")
          check(solid == 0., "one-way rule (2.79): stays liquid");
        else
          {
            check_close(solid, s.diagnostics().mass / s.solution().linfty_norm(), 1e-12,
                        "concentration rule (6): the whole rod turned solid");
            check_close(t_solid, 0.35, 0.01, "at C = C_sat, t = 0.35");
          }
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"bounds_closed_form", bounds_closed_form},
              {"eigenvalue_bound", eigenvalue_bound},
              {"divergence", divergence},
              {"library_bound", library_bound},
              {"analytical", analytical},
              {"snm_linear_field", snm_linear_field},
              {"convergence", convergence},
              {"moving_interface", moving_interface},
              {"library_phase_rule", library_phase_rule}});
}
