// Tests of the deal.II FEM near fields with absorbing boundaries
// (dissertation Sect. 4.2.2, 4.2.5 (E13) and Sect. 4.1): Fem::FemWave with
// the EBF ABC vs the conventional first-order ABC (4.75) vs an extended
// homogeneous-Dirichlet reference, the one-step spectral radius, and the
// consistency of the absorbing update.

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/function.h>
#include <deal.II/base/function_lib.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/abc/half_derivative_history.h>
#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_diffusion.h>
#include <perideal/fem/fem_wave.h>

#include "../check.h"
#include "../wave_settings.h"

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <functional>
#include <memory>
#include <random>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  /** Reduced E13 set-up: near field (-L, L)^2, h = 0.5, chi = 1, d = 0.0125, Delta k = 1. */
  struct E13
  {
    double                  L = 8., h = 0.5, dt = 0.02, t_end = 16.;
    /** Half width of the extended reference (0: the default below). */
    double                  L_ref = 0.;
    unsigned int            degree = 1;
    Abc::WaveAbcParameters  abc;
    Fem::FemWaveParameters  fem;
    E13()
    {
      fem.damping          = 0.0125;
      abc.wave_number_range = 1.;
      abc.dispersion       = "local";
      abc.cone_angle       = 0.5;
    }
  };

  struct E13Result
  {
    double energy_ebf = 0., energy_first = 0., probe_ebf = 0., probe_first = 0.;
    double final_ebf = 0., final_first = 0., abc_fraction = 0.;
    /** |E - E_ref|/E0 at t_end (the last sample). */
    double energy_end_ebf = 0., energy_end_first = 0.;
  };

  double
  pulse(const Point<2> &p)
  {
    return std::exp(-std::log(2.) * p.square() / 9.);
  }

  /** Exploratory (e13_scan key where=n): print the n largest EBF field errors at t_end. */
  unsigned int e13_where = 0;

  E13Result
  run_e13(const E13 &c, const bool verbose)
  {
    Fem::FemWaveParameters fp = c.fem;
    fp.degree                 = c.degree;
    fp.time_step              = c.dt;
    const ScalarFunctionFromFunctionObject<2> u0(pulse);
    // The pulse has radius ~6; nothing reflected at L_ref is back in the
    // compared square before t_end.
    const double     L_ref = c.L_ref > 0. ? c.L_ref : 0.5 * (c.t_end + c.L + 6.) + 3.;
    Triangulation<2> near, far;
    GridGenerator::subdivided_hyper_cube(near, static_cast<unsigned int>(std::round(2. * c.L / c.h)), -c.L, c.L);
    GridGenerator::subdivided_hyper_cube(far, static_cast<unsigned int>(std::round(2. * L_ref / c.h)), -L_ref, L_ref);
    Fem::FemWave<2> ref(far, fp, Fem::WaveBoundary::dirichlet, c.abc, u0);
    Fem::FemWave<2> first(near, fp, Fem::WaveBoundary::first_order, c.abc, u0);
    Fem::FemWave<2> ebf(near, fp, Fem::WaveBoundary::absorbing, c.abc, u0);
    const auto     &st = ebf.absorbing_boundary().statistics();
    if (verbose && root())
      std::cout << "    EBF (" << ebf.dispersion().name << "): " << st.n_absorbing << " absorbing DoFs, clouds "
                << st.min_cloud_size << ".." << st.max_cloud_size << " stride " << st.max_stride << ", " << st.n_classes
                << " coefficient sets, cond "
                << sci(st.max_condition_number) << ", max|V| " << sci(st.max_update_norm) << std::endl;
    const auto inside = [&](const Point<2> &p) { return std::max(std::abs(p[0]), std::abs(p[1])) < c.L - 1e-9; };
    const double       e0      = ref.energy(inside);
    const unsigned int n_steps = static_cast<unsigned int>(std::round(c.t_end / c.dt));
    const unsigned int every   = std::max(1u, n_steps / 16);
    const Point<2>     probe(0.625 * c.L, 0.3125 * c.L); // (20, 10) scaled from L = 26-32 to L
    E13Result          r;
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        ref.advance();
        first.advance();
        ebf.advance();
        if (s % every == 0 || s == n_steps)
          {
            const double er = ref.energy(inside), ee = ebf.energy(inside), ef = first.energy(inside);
            r.energy_ebf   = std::max(r.energy_ebf, std::abs(ee - er) / e0);
            r.energy_first = std::max(r.energy_first, std::abs(ef - er) / e0);
            r.energy_end_ebf   = std::abs(ee - er) / e0;
            r.energy_end_first = std::abs(ef - er) / e0;
            const double ur = ref.value_at(probe);
            r.probe_ebf     = std::max(r.probe_ebf, std::abs(ebf.value_at(probe) - ur));
            r.probe_first   = std::max(r.probe_first, std::abs(first.value_at(probe) - ur));
            if (verbose && root())
              std::cout << "    t = " << ref.time() << ": |E-E_ref|/E0 EBF " << sci(std::abs(ee - er) / e0)
                        << " first-order " << sci(std::abs(ef - er) / e0) << ", u(probe) - u_ref: EBF "
                        << sci(ebf.value_at(probe) - ur) << " first-order " << sci(first.value_at(probe) - ur)
                        << std::endl;
          }
      }
    // Field error at the end: max over the near-field vertices.
    Point<2> where;
    const auto &dh = ebf.get_dof_handler();
    std::map<std::pair<double, double>, double> errors;
    for (const auto &cell : dh.active_cell_iterators())
      for (const unsigned int v : cell->vertex_indices())
        {
          const Point<2> p  = cell->vertex(v);
          const double   ur = ref.value_at(p);
          if (e13_where > 0)
            errors[{p[0], p[1]}] = ebf.value_at(p) - ur;
          if (std::abs(ebf.value_at(p) - ur) > r.final_ebf)
            where = p;
          r.final_ebf       = std::max(r.final_ebf, std::abs(ebf.value_at(p) - ur));
          r.final_first     = std::max(r.final_first, std::abs(first.value_at(p) - ur));
        }
    if (e13_where > 0 && root())
      {
        std::vector<std::pair<double, std::pair<double, double>>> sorted;
        for (const auto &[p, e] : errors)
          sorted.emplace_back(-std::abs(e), p);
        std::sort(sorted.begin(), sorted.end());
        for (unsigned int q = 0; q < std::min<std::size_t>(e13_where, sorted.size()); ++q)
          std::cout << "    error " << sci(errors[sorted[q].second]) << " at (" << sorted[q].second.first << ", "
                    << sorted[q].second.second << "), ref " << sci(ref.value_at(Point<2>(sorted[q].second.first, sorted[q].second.second)))
                    << std::endl;
        // Error along the boundary ring and the next rings (max over each ring).
        for (const double depth : {0., 0.5, 1., 2., 4., 8.})
          {
            double m = 0.;
            for (const auto &[p, e] : errors)
              if (std::abs(std::max(std::abs(p.first), std::abs(p.second)) - (c.L - depth)) < 1e-9)
                m = std::max(m, std::abs(e));
            std::cout << "    ring at depth " << depth << ": max error " << sci(m) << std::endl;
          }
      }
    r.abc_fraction = ebf.abc_seconds / ebf.step_seconds;
    if (verbose && root())
      std::cout << "    summary: max |E-E_ref|/E0 EBF " << sci(r.energy_ebf) << " first " << sci(r.energy_first)
                << "; max probe error EBF " << sci(r.probe_ebf) << " first " << sci(r.probe_first)
                << "; field error at t_end EBF " << sci(r.final_ebf) << " first " << sci(r.final_first)
                << " at (" << where << "); ABC time fraction " << sci(r.abc_fraction) << std::endl;
    return r;
  }

  /** The E13 set-up of the tests: L = 16 (T = 32), Q1, discrete relation, Delta phi = pi/8. */
  E13
  e13_default()
  {
    E13 c;
    c.L                   = 16.;
    c.t_end               = 32.;
    c.abc.dispersion      = "discrete";
    c.abc.direction_range = M_PI / 8.; // [95]: Delta phi <= pi/8 (Sect. 4.3)
    return c;
  }

  /** EBF at least the given factors below the first-order ABC in energy, at the probe and in the field at t_end. */
  void
  check_e13_ratios(const E13Result &r, const std::string &label, const double energy, const double probe,
                   const double field)
  {
    const auto ratio = [&](const double ebf, const double first, const double factor, const std::string &what) {
      std::ostringstream times;
      times << factor << "x";
      check(ebf * factor < first,
            label + what + ": EBF " + sci(ebf) + " at least " + times.str() + " below first-order " + sci(first));
    };
    ratio(r.energy_ebf, r.energy_first, energy, "max |E - E_ref|/E0");
    ratio(r.probe_ebf, r.probe_first, probe, "probe (0.625 L, 0.3125 L)");
    ratio(r.final_ebf, r.final_first, field, "field at t_end");
  }

  /**
   * E13 reduced from (-26, 26)^2, t = 50, dt = 5e-4 to (-16, 16)^2, t = 32,
   * dt = 0.02 (the results change by < 1 % for dt = 0.005). Proposed EBF vs
   * first-order ABC (4.75) vs the extended Dirichlet reference.
   */
  void
  e13()
  {
    const E13Result r = run_e13(e13_default(), true);
    // Measured: energy 4.8e-4 vs 5.1e-3 (10.6x), probe 4.9e-4 vs 7.2e-3
    // (14.8x), field at t_end 1.9e-3 vs 8.9e-3 (4.7x: the 10x at the
    // end of the run is NOT reached; the largest EBF errors sit at the
    // corners). Margins ~20 % below the measured ratios.
    check_e13_ratios(r, "", 8., 12., 4.);
  }

  /**
   * E13 as in e13() with curved modes (Absorbing boundary/Curvature radius
   * rho = 64 = 4 L, session 12): the plane modes cannot follow the
   * curvature of the fronts of the centred pulse at low k.
   */
  void
  e13_curved()
  {
    E13 c                  = e13_default();
    c.abc.curvature_radius = 64.;
    const E13Result r      = run_e13(c, true);
    // Measured: energy 4.55e-4 vs 5.12e-3 (11.3x), probe 2.69e-4 vs
    // 7.24e-3 (27x), field at t_end 1.00e-3 vs 8.94e-3 (8.9x; plane modes
    // 4.7x; the 10x is NOT reached). Scan of rho (field at t_end):
    // 16 2.8e-3, 24 2.0e-3, 32 1.57e-3, 48 1.14e-3, 64 1.00e-3, 80 1.19e-3,
    // 96 1.31e-3, 128 1.46e-3, infinity (plane) 1.92e-3. Margins ~20 %
    // below the measured ratios.
    check_e13_ratios(r, "curved modes: ", 9., 20., 7.);
  }

  /**
   * E13 as in e13_curved() with the tangential viscous layer of session 13
   * (layer_viscosity 0.2: one-step radius 1, energy non-increasing over
   * 1e6 steps; verlet_layer_spectral_radius, verlet_energy_decay_long). The
   * reference and the first-order run get the same layer.
   */
  void
  e13_verlet_layer()
  {
    E13 c                  = e13_default();
    c.fem.layer_viscosity  = 0.2;
    c.abc.curvature_radius = 64.;
    const E13Result r      = run_e13(c, true);
    // Measured: energy 4.28e-4 vs 5.12e-3 (12.0x), probe 3.99e-4 vs
    // 7.24e-3 (18x), field at t_end 1.26e-3 vs 8.94e-3 (7.1x; without the
    // layer 8.9x, the cost of stability). Plane modes with the layer:
    // 4.60e-4 (11.1x), 2.96e-4 (24x), 1.99e-3 (4.5x). Margins ~15-20 %.
    check_e13_ratios(r, "layer: ", 10., 15., 6.);
  }

  /**
   * E13 with curved modes (rho 64, as e13_curved) and implicit Newmark +
   * consistent mass: the long-run-stable route (newmark_curved_stability)
   * to the curved-mode accuracy, session 14.
   */
  void
  newmark_e13_curved()
  {
    E13 c                  = e13_default();
    c.fem.scheme           = "Newmark";
    c.fem.lumped_mass      = false;
    c.abc.dispersion       = "local"; // the discrete relation is the lumped-mass symbol
    c.abc.curvature_radius = 64.;
    const E13Result r      = run_e13(c, true);
    // Measured: energy 4.22e-4 vs 5.27e-3 (12.5x), probe 1.94e-4 vs 7.13e-3
    // (37x), field at t_end 9.50e-4 vs 8.60e-3 (9.05x; the 10x is
    // NOT reached; plane modes 4.7x). The field error is a smooth offset of
    // the late wake (largest at the corners, 2.7e-4 still 8 cells inside),
    // not a corner artefact (doc/design.md, session 14). Margins ~20 %.
    check_e13_ratios(r, "Newmark consistent, curved modes: ", 10., 30., 7.5);
  }

  /**
   * E13 as in e13() with implicit Newmark and consistent mass (local
   * relation: the discrete one is the lumped-mass symbol); the extended
   * reference and the first-order run use the same integrator and mass.
   */
  void
  newmark_e13()
  {
    E13 c                = e13_default();
    c.fem.scheme         = "Newmark";
    c.fem.lumped_mass    = false;
    c.abc.dispersion     = "local";
    const E13Result r    = run_e13(c, true);
    // Measured: energy 4.6e-4 vs 5.3e-3 (11.6x), probe 5.8e-4 vs 7.1e-3
    // (12.3x), field at t_end 1.8e-3 vs 8.6e-3 (4.7x, corners as with
    // Verlet). Margins ~20 % below the measured ratios.
    check(r.energy_ebf < 1e-3, "Newmark consistent: max |E - E_ref|/E0 EBF " + sci(r.energy_ebf) + " < 1e-3");
    check_e13_ratios(r, "Newmark consistent: ", 9., 10., 4.);
  }

  /**
   * A constant state u = 1, v = 0 is an exact solution. The plain min-norm
   * collocation loses it (measured max abs(u - 1) = 6.9e-3 after 800 steps; 0.59 with Delta phi = pi/4 and the local relation); the
   * constant-preserving update keeps it to round-off.
   */
  void
  constant_state()
  {
    for (const bool preserve : {true, false})
      {
        E13 c = e13_default();
        c.fem.preserve_constants = preserve;
        c.fem.time_step          = c.dt;
        const Functions::ConstantFunction<2> one(1.);
        Triangulation<2>                     tria;
        GridGenerator::subdivided_hyper_cube(tria, 8, -2., 2.);
        Fem::FemWave<2> ebf(tria, c.fem, Fem::WaveBoundary::absorbing, c.abc, one);
        for (unsigned int s = 0; s < 800; ++s)
          ebf.advance();
        const double e = std::max(std::abs(ebf.value_at(Point<2>()) - 1.), std::abs(ebf.value_at(Point<2>(2., 2.)) - 1.));
        if (preserve)
          check(e < 1e-10, "constant kept by the corrected update: " + sci(e));
        else
          check(e > 1e-3, "plain min-norm update loses the constant (documents why the correction exists): " + sci(e));
      }
  }

  double
  radius(const Fem::WaveBoundary bc, const double tolerance, const unsigned int degree = 1,
         const std::string &scheme = "velocity Verlet", const bool lumped = true, const E13 &base = e13_default(),
         const unsigned int n_cells = 12)
  {
    E13 c                        = base;
    c.fem.scheme                 = scheme;
    c.fem.lumped_mass            = lumped;
    if (!lumped) // the discrete relation is the lumped-mass symbol
      c.abc.dispersion = "local";
    c.abc.pseudo_inverse_tolerance = tolerance;
    c.fem.degree                 = degree;
    c.fem.time_step              = c.dt;
    const ScalarFunctionFromFunctionObject<2> u0(pulse);
    Triangulation<2>                          tria;
    GridGenerator::subdivided_hyper_cube(tria, n_cells, -3., 3.);
    Fem::FemWave<2>      w(tria, c.fem, bc, c.abc, u0);
    unsigned int         n_up = 0;
    std::complex<double> dom;
    const double         rho = w.one_step_spectral_radius(4000, &n_up, &dom);
    if (root())
      std::cout << "    spectral radius 1 + " << sci(rho - 1.) << " (" << n_up << " > 1, dominant " << dom << ")" << std::endl;
    return rho;
  }

  /** One-step spectral radius of the FEM near field (h = 0.5, dt = 0.02, (-3, 3)^2). */
  void
  spectral_radius()
  {
    check(radius(Fem::WaveBoundary::dirichlet, 0.) <= 1., "Dirichlet: radius <= 1");
    check(radius(Fem::WaveBoundary::first_order, 0.) <= 1., "first-order ABC: radius <= 1");
    // Measured 1.0025 (growth 0.12 per unit time, frequency ~3.9 rad per unit
    // time, a mesh-scale boundary mode); the cloud guards hold all the same.
    // Session 13: a tangential sawtooth on the edges, removed by the layer
    // (verlet_layer_spectral_radius).
    const double rho = radius(Fem::WaveBoundary::absorbing, 0.);
    check(rho > 1. + 1e-4, "EBF (full pseudo-inverse): weakly unstable, radius " + sci(rho - 1.) + " above 1 (known)");
    // A truncated pseudo-inverse (relative cutoff 2e-3) is stable: the
    // eigenvalue 1 is the preserved constant state; but it loses the
    // accuracy (E13 field error 1.5e-2, worse than first order).
    check(radius(Fem::WaveBoundary::absorbing, 2e-3) <= 1. + 1e-10, "EBF, cutoff 2e-3: radius <= 1");
    // The guard rejects the unstable set-up with a ParameterError.
    bool thrown = false;
    try
      {
        E13 c                      = e13_default();
        c.abc.spectral_check_size  = 2000;
        c.fem.time_step            = c.dt;
        const ScalarFunctionFromFunctionObject<2> u0(pulse);
        Triangulation<2>                          tria;
        GridGenerator::subdivided_hyper_cube(tria, 12, -3., 3.);
        Fem::FemWave<2> w(tria, c.fem, Fem::WaveBoundary::absorbing, c.abc, u0);
      }
    catch (const ParameterError &e)
      {
        thrown = std::string(e.what()).find("Pseudo-inverse tolerance") != std::string::npos;
      }
    check(thrown, "spectral guard throws ParameterError naming the pseudo-inverse tolerance");
  }

  /**
   * Implicit Newmark (average acceleration) with lumped or consistent mass:
   * one-step spectral radius of the truncated system with the EBF
   * constraints (same near field as spectral_radius).
   */
  void
  newmark_spectral_radius()
  {
    for (const bool lumped : {true, false})
      {
        const std::string m = lumped ? "lumped" : "consistent";
        // Dirichlet: radius exactly 1, the eigenvalue -1 of the trapezoidal
        // velocity recursion v^{n+1} = -v^n + 2 (u^{n+1} - u^n) / dt of the
        // prescribed DoFs.
        check(radius(Fem::WaveBoundary::dirichlet, 0., 1, "Newmark", lumped) <= 1. + 1e-10,
              "Newmark " + m + ", Dirichlet: radius <= 1");
        check(radius(Fem::WaveBoundary::first_order, 0., 1, "Newmark", lumped) <= 1. + 1e-10,
              "Newmark " + m + ", first-order ABC: radius <= 1");
      }
    // Measured: lumped (discrete relation) 1 + 2.5e-3, the same mode as with
    // Verlet (1 + 2.5e-3; with the local relation 1 + 3.1e-3 for both): the
    // weak EBF instability does not come from the explicit integrator.
    const double rho_lumped = radius(Fem::WaveBoundary::absorbing, 0., 1, "Newmark", true);
    check(rho_lumped > 1. + 1e-3, "Newmark lumped + EBF: weakly unstable like Verlet, radius 1 + " +
                                    sci(rho_lumped - 1.));
    // Consistent mass (local relation): 1 + 4.2e-8 with dominant -1, i.e. the
    // defective eigenvalue -1 of the prescribed-DoF velocity recursion split
    // by round-off (~sqrt(eps)); no growing mode of the EBF update.
    const double rho_consistent = radius(Fem::WaveBoundary::absorbing, 0., 1, "Newmark", false);
    check(rho_consistent < 1. + 1e-6, "Newmark consistent + EBF: radius 1 + " + sci(rho_consistent - 1.) +
                                        " < 1 + 1e-6 (stable up to the split eigenvalue -1)");
  }

  /** FE_Q(2) with the EBF ABC is rejected (radius 1.008 measured), FE_Q(3) always. */
  void
  bad_input()
  {
    // True if the set-up of E13 (dt 0.01, changed by @p configure) on a small
    // square with @p bc throws a ParameterError naming @p parameter.
    const auto rejected = [](const std::function<void(E13 &)> &configure, const Fem::WaveBoundary bc,
                             const std::string &parameter) {
      E13 c           = e13_default();
      c.fem.time_step = 0.01;
      configure(c);
      const ScalarFunctionFromFunctionObject<2> u0(pulse);
      Triangulation<2>                          tria;
      GridGenerator::subdivided_hyper_cube(tria, 4, -1., 1.);
      try
        {
          Fem::FemWave<2> w(tria, c.fem, bc, c.abc, u0);
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what()).find(parameter) != std::string::npos;
        }
      return false;
    };
    const auto degree = [](const unsigned int k) { return [k](E13 &c) { c.fem.degree = k; }; };
    check(rejected(degree(2), Fem::WaveBoundary::absorbing, "FEM/Degree"), "Q2 + EBF with velocity Verlet rejected naming FEM/Degree");
    check(rejected([](E13 &c) { c.fem.degree = 2; c.fem.scheme = "Newmark"; }, Fem::WaveBoundary::absorbing, "FEM/Degree"),
          "Q2 + EBF with Newmark and lumped mass rejected naming FEM/Degree");
    check(!rejected([](E13 &c) { c.fem.degree = 2; c.fem.scheme = "Newmark"; c.fem.lumped_mass = false; c.abc.dispersion = "local"; },
                    Fem::WaveBoundary::absorbing, "FEM/Degree"),
          "Q2 + EBF with Newmark and consistent mass accepted");
    check(!rejected(degree(2), Fem::WaveBoundary::first_order, "FEM/Degree"), "Q2 + first-order ABC accepted");
    check(rejected(degree(3), Fem::WaveBoundary::dirichlet, "FEM/Degree"), "Q3 rejected naming FEM/Degree");
    // Consistent mass needs the implicit scheme; unknown schemes are named.
    const auto scheme = [](const std::string &name, const bool lumped) {
      return [name, lumped](E13 &c) {
        c.fem.scheme      = name;
        c.fem.lumped_mass = lumped;
      };
    };
    check(rejected(scheme("velocity Verlet", false), Fem::WaveBoundary::dirichlet, "FEM/Lumped mass"),
          "consistent mass + Verlet rejected naming FEM/Lumped mass");
    check(rejected(scheme("leapfrog", true), Fem::WaveBoundary::dirichlet, "FEM/Scheme"),
          "unknown scheme rejected naming FEM/Scheme");
    // Cloud size (session 19): at most 50, and the cone within the search
    // radius (here the default 2 n h = 20, i.e. the whole 5 x 5 mesh) must
    // hold n points; 4 (the 2 h cloud of the square's edges) is accepted.
    check(rejected([](E13 &c) { c.abc.cloud_size = 51; }, Fem::WaveBoundary::absorbing, "Absorbing boundary/Cloud size"),
          "Cloud size 51 rejected naming Absorbing boundary/Cloud size");
    check(rejected([](E13 &c) { c.abc.cloud_size = 20; }, Fem::WaveBoundary::absorbing, "Absorbing boundary/Cloud size"),
          "Cloud size 20 (more than the cone holds) rejected naming Absorbing boundary/Cloud size");
    check(rejected(
            [](E13 &c) {
              c.abc.cloud_size   = 6;
              c.abc.cloud_radius = 1.;
            },
            Fem::WaveBoundary::absorbing, "Absorbing boundary/Cloud size"),
          "Cloud size 6 with the search radius 2 h (edge cones hold 4 points) rejected naming Absorbing "
          "boundary/Cloud size");
    check(!rejected([](E13 &c) { c.abc.cloud_size = 4; }, Fem::WaveBoundary::absorbing, "Cloud size"),
          "Cloud size 4 accepted");
    {
      // The entries parse into the struct.
      ParameterHandler prm;
      Abc::WaveAbcParameters::declare_parameters(prm);
      prm.set("Cloud size", "2");
      Abc::WaveAbcParameters p;
      p.parse_parameters(prm);
      check(p.cloud_size == 2, "Cloud size parsed");
    }
    // Curved modes need the centre x_i - rho n outside the cloud (the
    // default cloud radius 2 h = 1).
    check(rejected([](E13 &c) { c.abc.curvature_radius = 0.5; }, Fem::WaveBoundary::absorbing, "Curvature radius"),
          "Curvature radius below the cloud radius rejected naming Absorbing boundary/Curvature radius");
    // The wake curvature radius (session 17) needs its centre outside the cloud too.
    check(rejected([](E13 &c) { c.abc.wake_curvature_radius = 0.5; }, Fem::WaveBoundary::absorbing,
                   "Wake curvature radius"),
          "Wake curvature radius below the cloud radius rejected naming Absorbing boundary/Wake curvature radius");
    // The per-node wake radius (session 18) needs a wake radius and, at
    // every node, a radius outside the cloud (on the (-1, 1)^2 mesh of
    // rejected(): 40 cos(26.6 deg)^40 = 0.46 < 1 at the edge node (1, 0.5)).
    check(rejected([](E13 &c) { c.abc.wake_angle_exponent = 3.; }, Fem::WaveBoundary::absorbing,
                   "Wake angle exponent"),
          "Wake angle exponent without a wake radius rejected naming Absorbing boundary/Wake angle exponent");
    check(rejected(
            [](E13 &c) {
              c.abc.wake_curvature_radius = 40.;
              c.abc.wake_angle_exponent   = 40.;
            },
            Fem::WaveBoundary::absorbing, "Wake angle exponent"),
          "Wake angle exponent with radii inside the cloud rejected naming Absorbing boundary/Wake angle exponent");
    // The weighted fit: W > 0, and k_W > 0 when W != 1.
  }
  /**
   * Backward Euler diffusion with the EBF ABC on (-1, 1)^2, h = 0.125, Q1
   * lumped, d_inf = 2h, Delta k = 2/d_inf = 8 (so D Delta k^2 dt = D dt/h^2):
   * the setup's power iteration rejects D dt/h^2 = 0.64 (the step that
   * diverged within 50 steps) naming FEM/Time step and the largest stable
   * step; the dense one-step spectral radius checks the reported bound
   * independently (<= 1 at the bound, > 1 at twice the bound).
   */
  void
  backward_euler_guard()
  {
    const double h = 0.125;
    // Delta k = 0: the default 2 / d_inf.
    const auto   make = [h](const double dt, const unsigned int check_steps, const double dk = 0.) {
      Fem::FemDiffusionParameters fp;
      fp.scheme    = "backward Euler";
      fp.time_step = dt;
      Abc::EbfParameters ap;
      ap.cloud_radius          = 2. * h;
      ap.wave_number_range     = dk;
      ap.stability_check_steps = check_steps;
      auto tria                = std::make_shared<Triangulation<2>>();
      GridGenerator::subdivided_hyper_cube(*tria, 16, -1., 1.);
      auto d = std::make_shared<Fem::FemDiffusion<2>>(*tria, fp);
      d->setup(Abc::TruncationBoundary::absorbing, ap, Functions::ZeroFunction<2>());
      return std::make_pair(tria, d);
    };
    // Dense spectral radius, no guard: the unstable step (measured 1 + 2.7).
    const double rho_bad = make(0.64 * h * h, 0).second->one_step_spectral_radius();
    check(rho_bad > 1.1, "D dt/h^2 = 0.64: one-step spectral radius " + sci(rho_bad) + " > 1 (diverges)");
    std::string message;
    try
      {
        make(0.64 * h * h, 200);
      }
    catch (const ParameterError &e)
      {
        message = e.what();
      }
    if (root())
      std::cout << "    " << message << std::endl;
    check(message.find("FEM/Time step") != std::string::npos && message.find("<= ") != std::string::npos,
          "D dt/h^2 = 0.64 rejected naming FEM/Time step and a range");
    const auto   at    = message.find("0 < time step <= ");
    const double bound = at == std::string::npos ? 0. : std::atof(message.c_str() + at + 17);
    // Halving then three bisections from 0.01: the bound lies in [0.005, 0.01].
    check(bound >= 0.005 && bound < 0.01, "reported bound " + sci(bound) + " in [0.005, 0.01)");
    if (bound > 0.)
      {
        const auto   ok     = make(bound, 200);
        const double rho_ok = ok.second->one_step_spectral_radius();
        check(ok.second->stability_growth <= 1. + 5e-3 && rho_ok <= 1. + 1e-10,
              "at the reported bound the setup passes and the dense radius is " + sci(rho_ok) + " <= 1");
        const double rho_2 = make(2. * bound, 0).second->one_step_spectral_radius();
        check(rho_2 > 1. + 1e-6, "at twice the bound the dense radius is " + sci(rho_2) + " > 1");
      }

    // Slow growth (session 7): D dt/h^2 = 0.1 with Delta k = 4 (unstable)
    // and 4.5 (stable) differ by less than the non-normal transient of a
    // power iteration. Measured: dense radius 1 + 4.7e-4 / 1 - 3.0e-4,
    // power iteration over 200 steps 1 + 3.3e-3 / 1 + 1.05e-3 (the old
    // guard, threshold 1 + 5e-3, passed both), Arnoldi 1 + 4.7e-4 /
    // 1 - 3.0e-4. The setup must reject the first and accept the second.
    for (const double dk : {4., 4.5})
      {
        auto         unchecked = make(0.1 * h * h, 0, dk);
        const double dense     = unchecked.second->one_step_spectral_radius();
        const double power     = unchecked.second->power_iteration_growth(200);
        const double arnoldi   = unchecked.second->arnoldi_spectral_radius(50, 60);
        bool         rejected  = false;
        try
          {
            make(0.1 * h * h, 200, dk);
          }
        catch (const ParameterError &e)
          {
            rejected = std::string(e.what()).find("FEM/Time step") != std::string::npos;
          }
        if (root())
          std::cout << "    Delta k = " << dk << ": radius - 1 dense " << sci(dense - 1.) << ", power iteration "
                    << sci(power - 1.) << ", Arnoldi " << sci(arnoldi - 1.) << "; setup "
                    << (rejected ? "rejects" : "accepts") << std::endl;
        const bool unstable = dense > 1.;
        check(unstable == (dk == 4.), "Delta k = " + sci(dk) + ": dense radius " + sci(dense) +
                                        (dk == 4. ? " > 1 (slowly growing)" : " < 1 (stable)"));
        // The power iteration alone cannot tell these apart (both above 1).
        check(power > 1. && power < 1. + 5e-3, "power iteration " + sci(power) + " in (1, 1 + 5e-3): old guard blind");
        // Arnoldi agrees with the dense radius (measured to 4 digits).
        check(std::abs(arnoldi - dense) < 1e-5, "Arnoldi radius " + sci(arnoldi) + " = dense " + sci(dense) + " to 1e-5");
        check(rejected == unstable, std::string("setup ") + (unstable ? "rejects" : "accepts") + " Delta k = " + sci(dk));
      }
  }
  /**
   * Long-run stability of the FEM wave near field with the EBF ABC
   * (issue 4: energy non-increasing): Newmark + consistent mass (local
   * relation), a narrow pulse exp(-log 2 |x|^2) (negligible, e^-25, at
   * the boundary: the E13 pulse is wider than a small near field and feeds
   * energy in from outside, as in the infinite domain) in (-6, 6)^2,
   * h = 0.5, dt = 0.02, for @p n_steps
   * steps. The energy (4.99) over the whole near field is sampled every
   * @p every steps. Measured (20000 steps): E falls from E0 to 5e-11 E0
   * by t = 52, then rises once by 1.7e-11 E0 (t = 52-58: the residual
   * rings with the EBF boundary, which is not exactly dissipative) and
   * falls to 1.6e-17 E0 at t = 400. Asserted: no increase above 1e-10 E0
   * between samples (the "non-increasing" holds to that level) and
   * no growth: every sample of the second half below 1e-12 E0 (measured
   * 1.1e-13; a growing mode would show there). 1e6 steps (t = 2e4): E
   * settles at 6.1e-18 E0 (a non-decaying near-constant state of the
   * constant-preserving update) and stays there, largest increase between
   * samples 1.3e-20 E0: no growth over 1e6 steps.
   */
  void
  energy_decay(E13 c, const unsigned int n_steps, const unsigned int every, const bool stationary_floor = false)
  {
    c.fem.time_step   = c.dt;
    const ScalarFunctionFromFunctionObject<2> u0(
      [](const Point<2> &p) { return std::exp(-std::log(2.) * p.square()); });
    Triangulation<2> tria;
    GridGenerator::subdivided_hyper_cube(tria, 24, -6., 6.);
    Fem::FemWave<2> w(tria, c.fem, Fem::WaveBoundary::absorbing, c.abc, u0);
    const auto      all = [](const Point<2> &) { return true; };
    const double    e0  = w.energy(all);
    double          previous = e0, max_increase = 0., max_after = 0., e_mid = 0.;
    unsigned int    n_increase = 0;
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        w.advance();
        if (s % every == 0)
          {
            const double e = w.energy(all);
            if (e > previous)
              ++n_increase;
            max_increase = std::max(max_increase, (e - previous) / e0);
            if (2 * s > n_steps)
              max_after = std::max(max_after, e / e0);
            else
              e_mid = e / e0;
            previous = e;
          }
      }
    if (root())
      std::cout << "    " << n_steps << " steps (t = " << w.time() << "): E/E0 at the end " << sci(previous / e0)
                << ", max over the second half " << sci(max_after) << ", largest increase between samples "
                << sci(max_increase) << " E0 (" << n_increase << " increases)" << std::endl;
    check(max_increase <= 1e-10, "energy non-increasing between samples every " + std::to_string(every) +
                                   " steps: largest increase " + sci(max_increase) + " E0 <= 1e-10 E0");
    if (stationary_floor)
      // The energy settles on a non-decaying floor (see newmark_tikhonov_stability):
      // no growth means no sample of the second half above the floor at the
      // midpoint by more than 1 % (a mode growing by r per step exceeds that
      // for r > 0.02 / n_steps).
      check(max_after <= 1.01 * e_mid, "no growth: energy over the second half " + sci(max_after) +
                                         " E0 <= 1.01 x the energy at the midpoint " + sci(e_mid) + " E0");
    else
      check(max_after < 1e-12, "no growth: energy over the second half " + sci(max_after) + " E0 < 1e-12 E0");
  }

  E13
  newmark_consistent()
  {
    E13 c             = e13_default();
    c.fem.scheme      = "Newmark";
    c.fem.lumped_mass = false;
    c.abc.dispersion  = "local";
    return c;
  }

  void
  newmark_energy_decay_short()
  {
    energy_decay(newmark_consistent(), 20000, 100);
  }

  /**
   * One-step radius on (-3, 3)^2 below 1 + 1e-6 (the round-off split of the
   * defective -1 of the prescribed-velocity recursion, ~sqrt(eps), as for
   * the plane modes in newmark_spectral_radius) and energy decay over 2e4
   * steps on (-6, 6)^2 (energy_decay) of the Newmark set-up @p c.
   */
  void
  check_newmark_stable(const E13 &c, const std::string &what)
  {
    const double rho = radius(Fem::WaveBoundary::absorbing, 0., c.fem.degree, "Newmark", false, c);
    if (root())
      std::cout << "    " << what << ": one-step radius 1 + " << sci(rho - 1.) << std::endl;
    check(rho < 1. + 1e-6, what + ": radius 1 + " + sci(rho - 1.) + " < 1 + 1e-6");
    energy_decay(c, 20000, 100);
  }

  /**
   * FE_Q(2) + EBF with Newmark + consistent mass (accepted at setup since
   * session 18; Verlet or lumped mass stay rejected, bad_input): the
   * one-step radius on (-3, 3)^2 is that of Q1, 1 + ~5e-8 with dominant -1
   * (the round-off split of the defective -1 of the prescribed velocity
   * recursion; measured 1 + 4.6e-8 at dt 0.02, 1 + 6.2e-8 at dt 0.005),
   * and the energy decays over 2e4 steps on (-6, 6)^2 (energy_decay).
   */
  void
  newmark_q2_stability()
  {
    E13 c        = newmark_consistent();
    c.fem.degree = 2;
    check_newmark_stable(c, "Newmark consistent + Q2 + EBF");
  }

  /**
   * Newmark + consistent mass with curved modes (rho 64, the set-up of
   * newmark_e13_curved): one-step radius on (-3, 3)^2 and energy decay over
   * 2e4 steps on (-6, 6)^2 (checks of energy_decay).
   */
  void
  newmark_curved_stability()
  {
    E13 c                  = newmark_consistent();
    c.abc.curvature_radius = 64.;
    check_newmark_stable(c, "Newmark consistent + curved EBF");
  }

  /**
   * Newmark + consistent mass, curved modes (rho 64) with clouds of radius
   * 2 (4 h, 14-17 points instead of 5-6) and the Tikhonov pseudo-inverse
   * (lambda = 1e-5 sigma_max; session 15): these clouds are unstable with
   * the truncated pseudo-inverse (rcond 0: radius 1 + 5.1e-3 on (-3, 3)^2)
   * and with lambda = 1e-6 sigma_max (1 + 2.6e-3); lambda = 1e-5
   * sigma_max makes them stable. The accurate lambda is narrow and moves
   * with the time step as ~5e-4 dt (E13 dt 0.01: 1e-5 gives 1.8x in the
   * field, 5e-6 8.3x; doc/design.md, session 15): tuned to dt = 0.02.
   */
  E13
  newmark_tikhonov()
  {
    E13 c                                 = newmark_consistent();
    c.abc.curvature_radius                = 64.;
    c.abc.cloud_radius                    = 2.;
    c.abc.pseudo_inverse_regularization   = "tikhonov";
    c.abc.pseudo_inverse_tolerance        = 1e-5;
    return c;
  }

  /** One-step radius on (-3, 3)^2 and energy decay over 2e4 steps (energy_decay) of newmark_tikhonov(). */
  void
  newmark_tikhonov_stability()
  {
    const E13    c   = newmark_tikhonov();
    const double rho = radius(Fem::WaveBoundary::absorbing, c.abc.pseudo_inverse_tolerance, 1, "Newmark", false, c);
    // Measured 1 + 4.8e-8: the round-off split of the defective -1 (as in
    // newmark_curved_stability); the same clouds with lambda = 1e-6
    // sigma_max: 1 + 2.6e-3 (checked below: the regularization is what
    // makes them stable).
    check(rho < 1. + 1e-6, "Newmark + curved EBF, clouds 2, Tikhonov 1e-5: radius 1 + " + sci(rho - 1.) + " < 1 + 1e-6");
    const double weak = radius(Fem::WaveBoundary::absorbing, 1e-6, 1, "Newmark", false, c);
    check(weak > 1. + 1e-4, "same clouds, Tikhonov 1e-6: unstable (radius 1 + " + sci(weak - 1.) + ")");
    // Measured: E falls to 2.19e-10 E0 by t ~ 200 and stays there (1e6
    // steps, newmark_tikhonov_long: 2.189e-10 E0 at t = 2e4, largest
    // increase between samples 1.4e-13 E0), where the truncated 5-6 point
    // clouds settle at 6.1e-18 E0: a non-decaying state of the constant-
    // preserving update, 1e-10 E0 instead of 1e-18 E0 with the regularized
    // fits. Asserted: increases <= 1e-10 E0 and no growth above that floor.
    energy_decay(c, 20000, 100, true);
  }

  void
  newmark_tikhonov_long()
  {
    energy_decay(newmark_tikhonov(), 1000000, 1000, true);
  }

  /** E13 with newmark_tikhonov() (long: Newmark + consistent mass, 1600 steps). */
  void
  newmark_e13_tikhonov()
  {
    const E13Result r = run_e13(newmark_tikhonov(), true);
    // Measured: energy 2.23e-4 vs 5.27e-3 (23.6x), probe 4.00e-4 vs
    // 7.13e-3 (17.8x), field at t_end 9.94e-4 vs 8.60e-3 (8.6x; the
    // issue's 10x is NOT reached, the same late-wake offset as with the
    // 5-6 point clouds, 9.05x). Margins ~15-20 %.
    check_e13_ratios(r, "Newmark consistent, curved modes, clouds 2, Tikhonov 1e-5: ", 20., 15., 7.5);
  }

  /**
   * Session 17: newmark_e13_curved with n_phi 4, n_k 20 and the wake
   * curvature radius 28 for the k = 0 modes (Absorbing boundary/Wake
   * curvature radius, Wake wave number 0): the long waves get the larger
   * decay of the late 2D wake while the front keeps rho 64.
   */
  E13
  newmark_wake_curvature()
  {
    E13 c                       = newmark_consistent();
    c.abc.curvature_radius      = 64.;
    c.abc.n_directions          = 4;
    c.abc.n_wave_numbers        = 20;
    c.abc.wake_curvature_radius = 28.;
    c.abc.wake_wave_number      = 0.;
    return c;
  }

  /** One-step radius on (-3, 3)^2 and energy decay over 2e4 steps (energy_decay) of newmark_wake_curvature(). */
  void
  newmark_wake_stability()
  {
    // Measured 1 + 4.3e-8 (dominant -1); energy: largest increase 1.3e-19
    // E0, 6.8e-18 E0 at t = 400, as without the wake radius.
    check_newmark_stable(newmark_wake_curvature(), "Newmark + curved EBF, wake curvature 28");
  }

  /** E13 with newmark_wake_curvature(). */
  void
  newmark_e13_wake()
  {
    const E13Result r = run_e13(newmark_wake_curvature(), true);
    // Measured: energy 4.28e-4 vs 5.27e-3 (12.3x), probe 2.35e-4 vs
    // 7.13e-3 (30x), field at t_end 8.78e-4 vs 8.60e-3 (9.79x; the issue's
    // 10x is NOT reached; the same setting without the wake radius gives
    // 9.06e-4, 9.49x). The field factor is asserted halfway between the two
    // (9.65): the test fails if the wake radius stops acting, and leaves
    // 1.4 % for round-off across platforms; energy and probe ~20 % below.
    check_e13_ratios(r, "Newmark consistent, curved modes, wake curvature 28: ", 10., 25., 9.65);
  }

  /**
   * E13 at the source's size: (-26, 26)^2, t = 50 (dt 0.02 instead of
   * 5e-4; dt 0.005 changes the field ratio from 10.6x to 10.5x), with the
   * source's mode set (plane modes, Delta phi = pi/8, Delta k = 1, n_k =
   * n_phi = 10) and the long-run stable Newmark + consistent mass route
   * (newmark_spectral_radius, newmark_energy_decay_long), i.e. nothing
   * tuned to this problem. The reduced (-16, 16)^2 of newmark_e13 gives
   * only 4.7x in the field at t_end: its boundary is 10 units closer to
   * the pulse, and the late 2D wake there is larger and more curved.
   * @p degree 2: FE_Q(2) on the same mesh (4x the DoFs; clouds of 2 node
   * spacings, 5-6 points).
   */
  void
  e13_source_size(const unsigned int degree)
  {
    E13 c    = newmark_consistent();
    c.L      = 26.;
    c.t_end  = 50.;
    c.degree = degree;
    const E13Result   r     = run_e13(c, true);
    const std::string label = "source size, Q" + std::to_string(degree) + ": ";
    // The bounds: within a small energy difference over the whole
    // run (1e-3), and 10x closer than the first-order ABC at the end of the
    // run in the energy, the probe and the field (the runs are
    // deterministic). Measured, Q1: max over the run 5.30e-4 (first order
    // 1.76e-3), at t_end 1.01e-6 vs 4.13e-4 (407x); probe 1.20e-4 vs
    // 2.29e-3 (19x); field at t_end 4.14e-4 vs 4.40e-3 (10.6x, the
    // strictest, 6 % above the bound). Q2: 4.66e-4 (1.73e-3), 1.99e-6 vs
    // 3.84e-4 (193x), probe 14.5x, field 3.02e-4 vs 4.40e-3 (14.6x).
    check(r.energy_ebf < 1e-3, label + "max |E - E_ref|/E0 EBF " + sci(r.energy_ebf) + " < 1e-3 over the run");
    check(10. * r.energy_end_ebf < r.energy_end_first, label + "|E - E_ref|/E0 at t_end EBF " +
                                                           sci(r.energy_end_ebf) + " at least 10x below first-order " +
                                                           sci(r.energy_end_first));
    check(10. * r.probe_ebf < r.probe_first, label + "probe (20, 10) EBF " + sci(r.probe_ebf) +
                                               " at least 10x below first-order " + sci(r.probe_first));
    check(10. * r.final_ebf < r.final_first, label + "field at t_end EBF " + sci(r.final_ebf) +
                                               " at least 10x below first-order " + sci(r.final_first));
  }

  /**
   * Session 18: newmark_wake_curvature() with a per-node wake radius
   * 40 cos(theta)^3 (Absorbing boundary/Wake angle exponent 3; theta
   * between the normal and the direction from the centre): the edge nodes
   * near the corners (theta ~ 45 degrees), where the wake arrives obliquely,
   * get radii down to 14, the edge centres and the corner DoFs 40.
   */
  E13
  newmark_wake_angle()
  {
    E13 c                       = newmark_wake_curvature();
    c.abc.wake_curvature_radius = 40.;
    c.abc.wake_angle_exponent   = 3.;
    return c;
  }

  /** One-step radius on (-3, 3)^2 and energy decay over 2e4 steps (energy_decay) of newmark_wake_angle(). */
  void
  newmark_wake_angle_stability()
  {
    // Measured 1 + 4.6e-8 (dominant -1), as newmark_wake_stability.
    check_newmark_stable(newmark_wake_angle(), "Newmark + curved EBF, wake radius 40 cos^3");
  }

  /** E13 with newmark_wake_angle(): the 10x in energy, probe and field. */
  void
  newmark_e13_wake_angle()
  {
    const E13Result r = run_e13(newmark_wake_angle(), true);
    // Measured: energy 4.01e-4 vs 5.27e-3 (13.2x), probe 1.77e-4 vs
    // 7.13e-3 (40x), field at t_end 6.77e-4 vs 8.60e-3 (12.7x). Asserted:
    // the 10x in energy and field (margins 32 % and 27 %), probe 30x
    // (25 % below measured). With one wake radius (newmark_e13_wake) the
    // field is 9.79x, so the field check fails if the per-node radius stops
    // acting.
    check_e13_ratios(r, "Newmark consistent, curved modes, wake radius 40 cos^3: ", 10., 30., 10.);
  }

  void
  newmark_energy_decay_long()
  {
    energy_decay(newmark_consistent(), 1000000, 1000);
  }

  /** The E13 set-up (velocity Verlet, lumped mass, discrete relation) with the tangential layer of session 13. */
  E13
  verlet_layer(const double curvature_radius = 0.)
  {
    E13 c                  = e13_default();
    c.fem.layer_viscosity  = 0.2;
    c.abc.curvature_radius = curvature_radius;
    return c;
  }

  /**
   * Long-run stability with velocity Verlet + lumped mass + EBF and the
   * tangential viscous layer (FemWaveParameters::layer_viscosity = 0.2),
   * same near field, pulse and checks as the Newmark run above, plane and
   * curved (rho 64) modes.
   */
  void
  verlet_energy_decay_short()
  {
    energy_decay(verlet_layer(), 20000, 100);
    energy_decay(verlet_layer(64.), 20000, 100);
  }

  void
  verlet_energy_decay_long()
  {
    energy_decay(verlet_layer(), 1000000, 1000);
  }

  /**
   * One-step spectral radius of velocity Verlet + lumped mass + EBF on
   * (-3, 3)^2 (as in spectral_radius) with the tangential viscous layer.
   * Without it: 1 + 2.5e-3, the dominant eigenvector a tangential sawtooth
   * at the edges, decaying inward over ~3 rings (doc/design.md, session 13).
   */
  void
  verlet_layer_spectral_radius()
  {
    for (const double rho : {0., 64.})
      {
        const std::string modes = rho > 0. ? "curved modes rho 64" : "plane modes";
        const double      r     = radius(Fem::WaveBoundary::absorbing, 0., 1, "velocity Verlet", true, verlet_layer(rho));
        check(r <= 1. + 1e-10, "Verlet + lumped + EBF + layer 0.2, " + modes + ": radius 1 + " + sci(r - 1.) +
                                 " <= 1 + 1e-10");
      }
    // The layer only dissipates: Dirichlet and first-order stay stable.
    for (const auto bc : {Fem::WaveBoundary::dirichlet, Fem::WaveBoundary::first_order})
      check(radius(bc, 0., 1, "velocity Verlet", true, verlet_layer()) <= 1. + 1e-10,
            "layer with a non-absorbing boundary: radius <= 1 + 1e-10");
    // Measured threshold: layer 0.1 leaves 1 + 1.5e-4 (8 eigenvalues > 1),
    // 0.15 gives 1; first order (L instead of L M^-1 L) needs 0.3.
    E13 weak                   = verlet_layer();
    weak.fem.layer_viscosity   = 0.1;
    check(radius(Fem::WaveBoundary::absorbing, 0., 1, "velocity Verlet", true, weak) > 1. + 1e-5,
          "layer 0.1: still weakly unstable (the test can fail)");
    // Finer mesh (h = 0.25, (-3, 3)^2): the scaled viscosity carries over.
    check(radius(Fem::WaveBoundary::absorbing, 0., 1, "velocity Verlet", true, verlet_layer(), 24) <= 1. + 1e-10,
          "h = 0.25: radius <= 1 + 1e-10");
  }

  // Exploratory (not registered): E13_SCAN="key=value ...; ..." runs of E13
  // (e13_default) with the EBF keys of with_wave_settings, plus L, T, dt,
  // newmark=1, rho=1 (one-step spectral radius on (-3, 3)^2, h = 0.5) or
  // rhoonly=1, where=n (the n largest field errors at t_end and the max
  // error per ring along the boundary), lref (half width of the extended
  // reference) and csize (Cloud size, session 19).
  void
  e13_scan()
  {
    const char        *env = std::getenv("E13_SCAN");
    std::istringstream runs(env ? env : "");
    std::string        run;
    while (std::getline(runs, run, ';'))
      {
        const auto kv  = key_values(run);
        const auto num = [&](const std::string &k, const double def) { return kv.count(k) ? std::stod(kv.at(k)) : def; };
        E13        c   = e13_default();
        c.abc          = with_wave_settings(c.abc, kv);
        c.abc.cloud_size = static_cast<unsigned int>(num("csize", c.abc.cloud_size));
        c.L            = num("L", c.L);
        c.t_end        = num("T", c.t_end);
        c.dt           = num("dt", c.dt);
        c.degree       = static_cast<unsigned int>(num("deg", c.degree));
        c.fem.degree   = c.degree;
        c.L_ref        = num("lref", 0.);
        c.fem.layer_viscosity = num("eta", 0.);
        c.fem.layer_width     = static_cast<unsigned int>(num("width", 3));
        c.fem.layer_order     = static_cast<unsigned int>(num("order", 2));
        e13_where             = static_cast<unsigned int>(num("where", 0));
        if (kv.count("newmark"))
          {
            c.fem.scheme      = "Newmark";
            c.fem.lumped_mass = false;
            c.abc.dispersion  = "local";
          }
        std::cout << "[" << run << "]" << std::endl;
        try
          {
            if (kv.count("rho"))
              {
                c.fem.time_step = c.dt;
                const ScalarFunctionFromFunctionObject<2> u0(pulse);
                Triangulation<2>                          tria;
                GridGenerator::subdivided_hyper_cube(tria, 12, -3., 3.);
                Fem::FemWave<2>      w(tria, c.fem, Fem::WaveBoundary::absorbing, c.abc, u0);
                unsigned int         n_up = 0;
                std::complex<double> dom;
                const double         rho = w.one_step_spectral_radius(4000, &n_up, &dom);
                std::cout << "  rho - 1 = " << sci(rho - 1.) << " (" << n_up << " up, dominant " << dom << ")"
                          << std::endl;
              }
            if (!kv.count("rhoonly"))
              run_e13(c, true);
          }
        catch (std::exception &e)
          {
            std::cout << "  exception: " << e.what() << std::endl;
          }
      }
  }

  // Exploratory (not registered): MODE_SCAN="key=value ...; ..." power
  // iteration of the Verlet + lumped one-step map on (-N h, N h)^2 from rough
  // data; prints the growth per step and where the dominant mode lives
  // (rms of u over one period, per DoF, as a grid, normalized to its max).
  void
  mode_scan()
  {
    const char        *env = std::getenv("MODE_SCAN");
    std::istringstream runs(env ? env : "");
    std::string        run;
    while (std::getline(runs, run, ';'))
      {
        const auto kv  = key_values(run);
        const auto num = [&](const std::string &k, const double def) { return kv.count(k) ? std::stod(kv.at(k)) : def; };
        E13        c   = e13_default();
        c.abc          = with_wave_settings(c.abc, kv);
        c.fem.time_step = num("dt", c.dt);
        c.fem.extrapolate_velocity = num("xv", 0) != 0;
        c.fem.preserve_constants   = num("pc", 1) != 0;
        c.fem.layer_viscosity      = num("eta", 0.);
        c.fem.layer_width          = static_cast<unsigned int>(num("width", 3));
        c.fem.layer_order          = static_cast<unsigned int>(num("order", 2));
        const unsigned int N = static_cast<unsigned int>(num("N", 12)), steps = static_cast<unsigned int>(num("steps", 20000));
        const double L = 0.25 * N;
        std::cout << "[" << run << "]" << std::endl;
        class Rough : public Function<2>
        {
        public:
          double
          value(const Point<2> &p, const unsigned int = 0) const override
          {
            const double v = std::sin(12.9898 * p[0] + 78.233 * p[1] + 0.5) * 43758.5453;
            return 2. * (v - std::floor(v)) - 1.;
          }
        } rough;
        Triangulation<2> tria;
        GridGenerator::subdivided_hyper_cube(tria, N, -L, L);
        Fem::FemWave<2> w(tria, c.fem, Fem::WaveBoundary::absorbing, c.abc, rough);
        if (num("rho", 0) != 0)
          {
            unsigned int         n_up = 0;
            std::complex<double> dom;
            const double         r = w.one_step_spectral_radius(4000, &n_up, &dom);
            std::cout << "  rho - 1 = " << sci(r - 1.) << " (" << n_up << " up, dominant " << dom << ")" << std::endl;
          }
        const auto norm = [&]() { return w.solution().l2_norm(); };
        double     n0 = norm(), log_growth = 0.;
        for (unsigned int s = 1; s <= steps; ++s)
          {
            w.advance();
            if (s % 100 == 0)
              {
                const double n1 = norm();
                if (s > steps / 2)
                  log_growth += std::log(n1 / n0);
                n0 = n1;
              }
          }
        std::cout << "  growth per step (second half) " << sci(std::exp(log_growth / (steps / 2)) - 1.) << std::endl;
        const auto        &nf = w.layout();
        std::vector<double> rms(nf.points.size(), 0.);
        for (unsigned int s = 0; s < 400; ++s)
          {
            w.advance();
            for (unsigned int i = 0; i < rms.size(); ++i)
              rms[i] += w.solution().local_element(i) * w.solution().local_element(i);
          }
        double mx = 0.;
        for (double &x : rms)
          mx = std::max(mx, x = std::sqrt(x));
        std::vector<std::vector<double>> grid(N + 1, std::vector<double>(N + 1, 0.));
        for (unsigned int i = 0; i < rms.size(); ++i)
          {
            const int ix = static_cast<int>(std::round((nf.points[i][0] + L) * N / (2. * L)));
            const int iy = static_cast<int>(std::round((nf.points[i][1] + L) * N / (2. * L)));
            grid[iy][ix] = rms[i] / mx;
          }
        {
          // Snapshot of the middle column (signs: the normal structure).
          std::vector<double> col(N + 1, 0.);
          for (unsigned int i = 0; i < rms.size(); ++i)
            if (std::abs(nf.points[i][0] - (kv.count("x") ? std::stod(kv.at("x")) : 0.)) < 1e-9)
              col[static_cast<int>(std::round((nf.points[i][1] + L) * N / (2. * L)))] = w.solution().local_element(i);
          std::cout << "  column snapshot (top to bottom):";
          for (int iy = N; iy >= 0; --iy)
            std::cout << " " << std::setprecision(2) << col[iy] / w.solution().linfty_norm();
          std::cout << std::endl;
          std::vector<double> row(N + 1, 0.), row1(N + 1, 0.);
          for (unsigned int i = 0; i < rms.size(); ++i)
            {
              const int ix = static_cast<int>(std::round((nf.points[i][0] + L) * N / (2. * L)));
              if (std::abs(nf.points[i][1] - L) < 1e-9)
                row[ix] = w.solution().local_element(i);
              if (std::abs(nf.points[i][1] - L + 2. * L / N) < 1e-9)
                row1[ix] = w.solution().local_element(i);
            }
          std::cout << "  top row snapshot:";
          for (unsigned int ix = 0; ix <= N; ++ix)
            std::cout << " " << std::setprecision(2) << row[ix] / w.solution().linfty_norm();
          std::cout << std::endl << "  second row snapshot:";
          for (unsigned int ix = 0; ix <= N; ++ix)
            std::cout << " " << std::setprecision(2) << row1[ix] / w.solution().linfty_norm();
          std::cout << std::endl;
        }
        for (int iy = N; iy >= 0; --iy)
          {
            std::cout << "  ";
            for (unsigned int ix = 0; ix <= N; ++ix)
              std::cout << std::setw(5) << std::fixed << std::setprecision(2) << grid[iy][ix];
            std::cout << std::defaultfloat << std::endl;
          }
      }
  }

  /** Rough data: pseudo-random values in [-1, 1] hashed from the point. */
  class RoughField : public Function<2>
  {
  public:
    double
    value(const Point<2> &p, const unsigned int = 0) const override
    {
      const double v = std::sin(12.9898 * p[0] + 78.233 * p[1] + 0.5) * 43758.5453;
      return 2. * (v - std::floor(v)) - 1.;
    }
  };

  /**
   * Imposed = half derivative (FEM, forward Euler, lumped): the flux
   * dC/dn = -(kappa/2) C - D^{-1/2} d^{1/2}C/dt^{1/2} of the boundary DoF's
   * own history (doc/design.md, session 12). The input checks; then the
   * stability argument of FemDiffusion::setup (a sub-convex combination of
   * C^n and the history whenever the time step is below the reported
   * bound) on rough data on a square and a disk, over 4000 steps at 0.95
   * times the smaller of the forward Euler and the half-derivative bounds:
   * max |C| never exceeds its initial value and the energy never rises.
   * Last, the increment fit form: equal to the value form when no singular
   * value is cut (the square's clouds), not when rcond cuts some.
   */
  void
  half_derivative()
  {
    const auto setup = [](Triangulation<2> &tria, const double dt, const std::string &scheme, const double kappa) {
      Fem::FemDiffusionParameters fp;
      fp.time_step = dt;
      fp.scheme    = scheme;
      Abc::EbfParameters ap;
      ap.imposed            = "half derivative";
      ap.boundary_curvature = kappa;
      auto d                = std::make_unique<Fem::FemDiffusion<2>>(tria, fp);
      d->setup(Abc::TruncationBoundary::absorbing, ap, RoughField());
      return d;
    };
    const auto message = [&](Triangulation<2> &tria, const double dt, const std::string &scheme, const double kappa) {
      try
        {
          setup(tria, dt, scheme, kappa);
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what());
        }
      return std::string();
    };
    Triangulation<2> square, disk;
    GridGenerator::subdivided_hyper_cube(square, 16, -1., 1.);
    GridGenerator::hyper_ball(disk, Point<2>(), 1.);
    disk.refine_global(3);
    // Input checks.
    check(message(square, 1e-3, "backward Euler", 0.).find("FEM/Scheme") != std::string::npos,
          "backward Euler rejected naming FEM/Scheme");
    check(message(square, 1e-3, "forward Euler", -1.).find("Boundary curvature") != std::string::npos,
          "negative curvature rejected naming Absorbing boundary/Boundary curvature");
    const std::string big = message(square, 1e-2, "forward Euler", 0.);
    check(big.find("FEM/Time step") != std::string::npos, "a too large step rejected naming FEM/Time step");
    {
      const auto d = setup(square, 1e-3, "forward Euler", 0.);
      bool       rejected = false;
      try
        {
          d->arnoldi_spectral_radius(10, 10);
        }
      catch (const ParameterError &)
        {
          rejected = true;
        }
      check(rejected, "one-step map checks rejected (the half derivative has memory)");
    }

    // Stability on rough data at 0.95 times the smallest bound: the
    // half-derivative and the forward Euler bounds (read from the errors),
    // on the square also 3 h^2 / 8 = min m_i / K_ii (Cartesian Q1 lumped:
    // K_ij <= 0), below which the forward Euler map is nonnegative and the
    // max-norm argument applies; the disk's distorted cells have K_ij > 0
    // and a step near 2 / lambda_max, so there only the energy is asserted.
    for (auto *tria : {&square, &disk})
      {
        const bool   is_disk = tria == &disk;
        const double kappa   = is_disk ? 1. : 0.;
        double       dt      = is_disk ? 1. : 3. * 0.125 * 0.125 / 8.;
        // (The messages print 6 decimals: 0.999 keeps a rounded-up bound out.)
        for (unsigned int k = 0; k < 3; ++k)
          {
            const std::string msg = message(*tria, dt, "forward Euler", kappa);
            const auto        at  = msg.find("<= ");
            if (at != std::string::npos)
              dt = std::min(dt, 0.999 * std::atof(msg.c_str() + at + 3));
          }
        dt *= 0.95;
        check(dt < 0.95, "the bounds are reported");
        const auto           d = setup(*tria, dt, "forward Euler", kappa);
        const BoundingBox<2> all(std::make_pair(Point<2>(-1., -1.), Point<2>(1., 1.)));
        const double       max0 = d->solution().linfty_norm();
        double             max_ratio = 0., max_rise = -1., pi = d->energy(all);
        const double       pi0 = pi;
        for (unsigned int n = 0; n < 4000; ++n)
          {
            d->advance();
            max_ratio       = std::max(max_ratio, d->solution().linfty_norm() / max0);
            const double p2 = d->energy(all);
            max_rise        = std::max(max_rise, (p2 - pi) / pi0);
            pi              = p2;
          }
        // For comparison (printed): the same data with Neumann truncation.
        double max_neumann = 0.;
        {
          Fem::FemDiffusionParameters fp;
          fp.time_step = dt;
          Fem::FemDiffusion<2> nd(*tria, fp);
          nd.setup(Abc::TruncationBoundary::neumann, Abc::EbfParameters(), RoughField());
          for (unsigned int n = 0; n < 4000; ++n)
            {
              nd.advance();
              max_neumann = std::max(max_neumann, nd.solution().linfty_norm() / max0);
            }
        }
        if (root())
          std::cout << "  " << (is_disk ? "disk" : "square") << ": Neumann max_n max|C^n| / max|C^0| " << max_neumann
                    << std::endl;
        if (root())
          std::cout << "  " << (is_disk ? "disk" : "square") << ": dt " << sci(dt)
                    << ", 4000 steps: max_n max|C^n| / max|C^0| " << max_ratio << ", largest one-step rise of Pi/Pi0 "
                    << sci(max_rise) << ", final Pi/Pi0 " << sci(pi / pi0) << std::endl;
        if (!is_disk)
          check(max_ratio <= 1. + 1e-12, "max |C| never exceeds its initial value");
        check(max_rise <= 1e-14, "the energy never rises");
        check(pi / pi0 < 1e-2, "the rough data decay (Pi/Pi0 " + sci(pi / pi0) + ")");
      }

    // Increment fit form: V = e_i + (Psi(dt) - Psi(0)) M^+ equals the value
    // form Psi(dt) M^+ when M M^+ = I, and differs under a cut.
    const auto vectors = [&](const std::string &form, const double rcond) {
      Fem::FemDiffusionParameters fp;
      fp.time_step = 1e-3;
      Abc::EbfParameters ap;
      ap.fit_form                 = form;
      ap.pseudo_inverse_tolerance = rcond;
      ap.stability_check_steps    = 0;
      Fem::FemDiffusion<2> d(square, fp);
      d.setup(Abc::TruncationBoundary::absorbing, ap, RoughField());
      std::vector<double> v;
      for (unsigned int a = 0; a < d.absorbing_boundary().absorbing_points().size(); ++a)
        for (const auto &[j, w] : d.absorbing_boundary().cloud(a))
          v.push_back(w);
      return v;
    };
    const auto diff = [](const std::vector<double> &a, const std::vector<double> &b) {
      double m = a.size() == b.size() ? 0. : 1e300;
      for (unsigned int i = 0; i < std::min(a.size(), b.size()); ++i)
        m = std::max(m, std::abs(a[i] - b[i]));
      return m;
    };
    const auto   value = vectors("value", 0.), increment = vectors("increment", 0.);
    const double d_full = diff(value, increment), d_cut = diff(vectors("value", 1e-2), vectors("increment", 1e-2));
    if (root())
      std::cout << "  increment vs value form: max |V diff| " << sci(d_full) << " (full pseudo-inverse), " << sci(d_cut)
                << " (rcond 1e-2)" << std::endl;
    check(d_full < 1e-10, "increment = value form without a cut (" + sci(d_full) + ")");
    check(d_cut > 1e-3, "increment != value form under rcond 1e-2 (" + sci(d_cut) + ")");
  }

  /**
   * FemDiffusionParameters through the parameter file (subsection FEM):
   * the defaults equal the struct's, every entry is read, and bad values
   * end in errors naming FEM/<entry> with the allowed range (the patterns
   * reject what is outside them already while parsing).
   */
  void
  diffusion_parameters()
  {
    const Fem::FemDiffusionParameters defaults, parsed = parameters_from_text<Fem::FemDiffusionParameters>("");
    check(parsed.degree == defaults.degree && parsed.lumped_mass == defaults.lumped_mass &&
            parsed.scheme == defaults.scheme && parsed.diffusivity == defaults.diffusivity &&
            parsed.time_step == defaults.time_step,
          "the declared defaults are the struct's");
    const auto all = parameters_from_text<Fem::FemDiffusionParameters>(
      "set Degree = 2\nset Lumped mass = false\nset Scheme = backward Euler\nset Diffusivity = 0.5\n"
      "set Time step = 0.002\n");
    check(all.degree == 2 && !all.lumped_mass && all.scheme == "backward Euler" && all.diffusivity == 0.5 &&
            all.time_step == 0.002,
          "every entry is read");
    // In the FEM subsection, as an application declares it.
    const auto from_fem = [](const std::string &entries) {
      ParameterHandler prm;
      prm.enter_subsection("FEM");
      Fem::FemDiffusionParameters::declare_parameters(prm);
      prm.leave_subsection();
      prm.parse_input_from_string("subsection FEM\n" + entries + "end\n");
      Fem::FemDiffusionParameters p;
      prm.enter_subsection("FEM");
      p.parse_parameters(prm);
      prm.leave_subsection();
      return p;
    };
    Triangulation<2> square;
    GridGenerator::subdivided_hyper_cube(square, 8, -1., 1.);
    const auto error = [&](const std::string &entries, const std::string &imposed) {
      try
        {
          Fem::FemDiffusion<2> d(square, from_fem(entries));
          Abc::EbfParameters   ap;
          ap.imposed               = imposed;
          ap.stability_check_steps = 0;
          d.setup(imposed.empty() ? Abc::TruncationBoundary::neumann : Abc::TruncationBoundary::absorbing,
                  imposed.empty() ? Abc::EbfParameters() : ap, RoughField());
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what());
        }
      return std::string();
    };
    const auto names = [](const std::string &msg, const std::string &entry, const std::string &range) {
      return msg.find("'FEM/" + entry + "'") != std::string::npos && msg.find(range) != std::string::npos;
    };
    check(error("set Time step = 0.001\n", "").empty(), "valid entries accepted");
    check(names(error("set Time step = 0\n", ""), "Time step", "> 0"), "Time step = 0 rejected naming FEM/Time step");
    check(names(error("set Diffusivity = 0\n", ""), "Diffusivity", "> 0"),
          "Diffusivity = 0 rejected naming FEM/Diffusivity");
    check(names(error("set Time step = 1\n", ""), "Time step", "forward Euler bound"),
          "a forward Euler step above 2/lambda_max rejected naming FEM/Time step and the bound");
    check(names(error("set Lumped mass = false\n", "half derivative"), "Scheme", "forward Euler with lumped mass"),
          "consistent mass with Imposed = half derivative rejected naming FEM/Scheme");
    for (const std::string bad : {"set Degree = 3\n", "set Scheme = Crank-Nicolson\n", "set Diffusivity = -1\n"})
      {
        bool rejected = false;
        try
          {
            from_fem(bad);
          }
        catch (const std::exception &)
          {
            rejected = true;
          }
        check(rejected, "'" + bad.substr(0, bad.size() - 1) + "' rejected by the entry's pattern");
      }
  }

  /**
   * The sum-of-exponentials history of Imposed = half derivative (session
   * 14): (1) the approximation of the Gruenwald-Letnikov weights against
   * their closed form Gamma(j - 1/2) / (Gamma(-1/2) Gamma(j + 1)) (Boost's
   * Gamma ratio, not the recurrence of the exact history nor the Laplace
   * integral of the approximation) at every j of [exact steps + 1,
   * horizon]: relative error <= the stated accuracy; beyond the horizon
   * the absolute error <= accuracy |g_horizon|. (2) The recursive history
   * against the exact sum on random levels: since sum_{j >= 1} |g_j| = 1,
   * |H_soe - H_exact| <= accuracy max_m |C^m| at every step. (3) Bad input
   * names the parameter and its range.
   */
  void
  half_derivative_soe()
  {
    struct Case
    {
      double       accuracy;
      unsigned int exact_steps;
      double       horizon;
    };
    for (const Case c : {Case{1e-10, 5, 1e5}, Case{1e-8, 0, 3e4}, Case{1e-13, 1, 2e4}, Case{1e-3, 1000, 5e4}})
      {
        const Abc::HalfDerivativeSoe soe(c.accuracy, c.exact_steps, c.horizon);
        double                       rel = 0., beyond = 0.;
        for (std::size_t j = c.exact_steps + 1; j <= std::size_t(c.horizon); ++j)
          {
            const double g = Abc::gruenwald_letnikov_half_weight(j);
            rel            = std::max(rel, std::abs(soe.weight(j) - g) / std::abs(g));
          }
        const double g_horizon = std::abs(Abc::gruenwald_letnikov_half_weight(std::size_t(c.horizon)));
        for (double j = c.horizon; j <= 1e3 * c.horizon; j *= 1.01)
          beyond = std::max(beyond, std::abs(soe.weight(std::size_t(j)) -
                                             Abc::gruenwald_letnikov_half_weight(std::size_t(j))) / g_horizon);
        const std::string name = "accuracy " + sci(c.accuracy) + ", exact steps " + std::to_string(c.exact_steps) +
                                 ", horizon " + sci(c.horizon) + ": " + std::to_string(soe.rates.size()) +
                                 " exponentials";
        check(rel <= c.accuracy, name + ", max relative error " + sci(rel) + " on every j of the range");
        check(beyond <= c.accuracy, name + ", beyond the horizon (to 1e3 x) max |error| / |g_horizon| " +
                                      sci(beyond));
      }
    // The exact history's recurrence against the closed form (its round-off).
    {
      double g = 1., rel = 0.;
      for (std::size_t j = 1; j <= 100000; ++j)
        {
          g *= (j - 1.5) / j;
          rel = std::max(rel, std::abs(g / Abc::gruenwald_letnikov_half_weight(j) - 1.));
        }
      check(rel < 1e-12, "recurrence g_j = g_{j-1} (j - 3/2) / j = closed form to " + sci(rel) + " (j <= 1e5)");
    }

    // (2) The two histories on the same random levels (7 points, 4000 steps).
    {
      const unsigned int         n_dofs = 7;
      Abc::HalfDerivativeHistory exact, fast;
      exact.reinit(n_dofs, "exact", 1e-10, 5, 1e6);
      fast.reinit(n_dofs, "sum of exponentials", 1e-10, 5, 1e6);
      std::minstd_rand                       gen(7);
      std::uniform_real_distribution<double> uniform(-1., 1.);
      std::vector<double>                    c(n_dofs), he, hf;
      double                                 worst = 0., c_max = 0., h_max = 0.;
      for (unsigned int n = 0; n < 4000; ++n)
        {
          for (unsigned int a = 0; a < n_dofs; ++a)
            c[a] = (a % 2 ? uniform(gen) : std::cos(0.003 * n * (a + 1))), c_max = std::max(c_max, std::abs(c[a]));
          exact.append(c.data(), he);
          fast.append(c.data(), hf);
          for (unsigned int a = 0; a < n_dofs; ++a)
            worst = std::max(worst, std::abs(he[a] - hf[a]) / c_max), h_max = std::max(h_max, std::abs(he[a]));
        }
      check(worst <= 1e-10 && h_max > 0.1,
            "sum of exponentials vs exact history, 4000 random levels: max |H_soe - H_exact| / max |C| = " +
              sci(worst) + " <= 1e-10 (" + std::to_string(fast.n_exponentials()) + " exponentials, max |H| " +
              sci(h_max) + ")");
    }

    // (3) Bad input, directly, through the parameter file and the setup.
    const auto error = [](const std::function<void()> &f) {
      try
        {
          f();
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what());
        }
      return std::string();
    };
    const auto names = [](const std::string &msg, const std::string &parameter, const std::string &range) {
      return msg.find("'Absorbing boundary/Half derivative " + parameter + "'") != std::string::npos &&
             msg.find(range) != std::string::npos;
    };
    Abc::HalfDerivativeHistory h;
    for (const double a : {0., 1e-14, 1e-2})
      check(names(error([&]() { h.reinit(1, "sum of exponentials", a, 5, 1e6); }), "accuracy",
                  "1e-13 <= accuracy <= 1e-3"),
            "accuracy " + sci(a) + " rejected naming Half derivative accuracy and its range");
    check(names(error([&]() { h.reinit(1, "sum of exponentials", 1e-10, 1001, 1e6); }), "exact steps",
                "0 <= exact steps <= 1000"),
          "1001 exact steps rejected naming Half derivative exact steps and its range");
    check(names(error([&]() { h.reinit(1, "sum of exponentials", 1e-10, 5, 5); }), "horizon",
                "exact steps < horizon <= 1e15"),
          "horizon 5 with 5 exact steps rejected naming Half derivative horizon");
    check(names(error([&]() { h.reinit(1, "fast", 1e-10, 5, 1e6); }), "history", "exact or sum of exponentials"),
          "an unknown history rejected naming Half derivative history");
    Triangulation<2> square;
    GridGenerator::subdivided_hyper_cube(square, 8, -1., 1.);
    const auto ap = parameters_from_text<Abc::EbfParameters>("set Imposed = half derivative\n"
                                                              "set Half derivative accuracy = 0.1\n");
    Fem::FemDiffusionParameters fp;
    fp.time_step = 1e-3;
    Fem::FemDiffusion<2> d(square, fp);
    check(names(error([&]() { d.setup(Abc::TruncationBoundary::absorbing, ap, RoughField()); }), "accuracy",
                "<= 1e-3"),
          "Half derivative accuracy = 0.1 from the parameter file rejected by the setup, naming the entry");
    auto exact = parameters_from_text<Abc::EbfParameters>("set Imposed = half derivative\n"
                                                          "set Half derivative history = exact\n");
    d.setup(Abc::TruncationBoundary::absorbing, exact, RoughField());
    check(d.half_derivative_history().n_exponentials() == 0 &&
            parameters_from_text<Abc::EbfParameters>("").half_derivative_history == "sum of exponentials",
          "Half derivative history = exact is read (default: sum of exponentials)");
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv, {{"backward_euler_guard", backward_euler_guard}, {"newmark_energy_decay_short", newmark_energy_decay_short}, {"newmark_energy_decay_long", newmark_energy_decay_long}, {"verlet_energy_decay_short", verlet_energy_decay_short}, {"verlet_energy_decay_long", verlet_energy_decay_long}, {"verlet_layer_spectral_radius", verlet_layer_spectral_radius}, {"e13", e13}, {"e13_curved", e13_curved}, {"e13_verlet_layer", e13_verlet_layer}, {"constant_state", constant_state}, {"bad_input", bad_input}, {"spectral_radius", spectral_radius}, {"newmark_spectral_radius", newmark_spectral_radius}, {"newmark_e13", newmark_e13}, {"newmark_e13_curved", newmark_e13_curved}, {"newmark_curved_stability", newmark_curved_stability}, {"newmark_tikhonov_stability", newmark_tikhonov_stability}, {"newmark_e13_tikhonov", newmark_e13_tikhonov}, {"newmark_tikhonov_long", newmark_tikhonov_long}, {"newmark_wake_stability", newmark_wake_stability}, {"newmark_e13_wake", newmark_e13_wake}, {"newmark_e13_source_size", [] { e13_source_size(1); }}, {"newmark_e13_source_size_q2", [] { e13_source_size(2); }}, {"newmark_q2_stability", newmark_q2_stability}, {"newmark_wake_angle_stability", newmark_wake_angle_stability}, {"newmark_e13_wake_angle", newmark_e13_wake_angle}, {"e13_scan", e13_scan}, {"mode_scan", mode_scan}, {"half_derivative", half_derivative}, {"half_derivative_soe", half_derivative_soe}, {"diffusion_parameters", diffusion_parameters}});
}
