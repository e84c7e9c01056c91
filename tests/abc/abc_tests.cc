// Tests of the EBF absorbing boundary for diffusion (dissertation Sect. 4.1,
// paper 002) with PD and deal.II FEM near fields. Every case compares with
// something independent: the heat kernel, an extended-domain run of the
// same code (wide enough that nothing reaches its boundary), the Taylor
// series (4.17) of the nonlocal dispersion relation, or the same run on a
// different number of ranks.

#include <deal.II/base/function.h>
#include <deal.II/base/quadrature_lib.h>

#include <deal.II/grid/grid_generator.h>

#include <perideal/abc/ebf_diffusion_abc.h>
#include <perideal/abc/pd_unbounded_diffusion.h>
#include <perideal/base/exceptions.h>
#include <perideal/boundary/polygon_domain.h>
#include <perideal/fem/fem_diffusion.h>

#include <chrono>

#include <check.h>

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  /** C0 = exp(-4|x|^2) and its free-space evolution under C_t = D Laplace C. */
  template <int dim>
  class HeatKernel : public Function<dim>
  {
  public:
    HeatKernel(const double D = 1.)
      : D(D)
    {}
    double
    value(const Point<dim> &p, const unsigned int = 0) const override
    {
      const double s = 1. + 16. * D * this->get_time();
      return std::pow(s, -0.5 * dim) * std::exp(-4. * p.square() / s);
    }

  private:
    double D;
  };

  template <int dim>
  BoundingBox<dim>
  cube(const double L)
  {
    Point<dim> lo, hi;
    for (unsigned int d = 0; d < dim; ++d)
      {
        lo[d] = -L;
        hi[d] = L;
      }
    return BoundingBox<dim>(std::make_pair(lo, hi));
  }

  /** Energies on the truncated domain at every @p every-th step. */
  struct History
  {
    std::vector<double> energy;
    bool                monotone = true; // Pi non-increasing every step
  };

  template <int dim, typename Run>
  History
  history(Run &run, const double L, const unsigned int n_steps, const unsigned int every = 100)
  {
    const auto region = cube<dim>(L);
    History    h;
    h.energy.push_back(run.energy(region));
    double previous = h.energy[0];
    for (unsigned int n = 1; n <= n_steps; ++n)
      {
        run.advance();
        const double e = run.energy(region);
        h.monotone     = h.monotone && e <= previous * (1. + 1e-13);
        previous       = e;
        if (n % every == 0 || n == n_steps)
          h.energy.push_back(e);
      }
    return h;
  }

  /** Normalized energy difference (4.35) of a run against a reference. */
  struct Comparison
  {
    double max_difference = 0.; // max over the run of |Pi - Pi_ref| / Pi_ref(0)
    double final_difference = 0.;
    bool   monotone = true;
    double final_energy = 0.;
  };

  Comparison
  compare(const History &run, const History &reference)
  {
    Comparison c;
    for (unsigned int r = 0; r < run.energy.size(); ++r)
      {
        const double d     = std::abs(run.energy[r] - reference.energy[r]) / reference.energy[0];
        c.max_difference   = std::max(c.max_difference, d);
        c.final_difference = d;
      }
    c.monotone     = run.monotone;
    c.final_energy = run.energy.back();
    return c;
  }

  void
  expect_error(const std::function<void()> &f, const std::string &what)
  {
    try
      {
        f();
        check(false, what + ": no ParameterError");
      }
    catch (const ParameterError &e)
      {
        check(true, what + ": " + e.what());
      }
  }

  // ------------------------------------------------------------------------
  // Nonlocal dispersion relation: quadrature of (4.13) against the Taylor
  // series (4.15)/(4.17) (2D), the 1D and 3D series of 002 App. A, and the
  // local limit omega -> D k^2 as k delta -> 0.
  void
  dispersion()
  {
    const double D = 1., delta = 0.5;
    for (const unsigned int dim : {1u, 2u, 3u})
      {
        ScalarKernel kernel;
        kernel.dim      = dim;
        kernel.omega    = InfluenceFunction::constant;
        kernel.exponent = 1.;
        kernel.delta    = delta;
        kernel.constant = kernel.micro_constant_for(D);
        const auto nonlocal = Abc::DiffusionDispersion::nonlocal(kernel);
        // Series coefficients of omega / (D k^2) in (k delta)^2, (k delta)^4:
        // 1D (derived: omega = 2 c0 sum_{n even} (k delta)^n / (n n!), c0 = 2D/delta^2), 2D (4.17), 3D (002, (58)).
        const double a2 = dim == 1 ? 1. / 24. : (dim == 2 ? 3. / 80. : 1. / 30.);
        const double a4 = dim == 1 ? 1. / 1080. : (dim == 2 ? 1. / 1344. : 1. / 1680.);
        double       previous = 1e300;
        for (const double kd : {1., 0.3, 0.1, 0.01})
          {
            const double k     = kd / delta;
            const double ratio = nonlocal(k) / (D * k * k);
            const double gap   = std::abs(ratio - 1.);
            check(gap < previous, std::to_string(dim) + "D: |omega/(D k^2) - 1| = " +
                                    std::to_string(gap) + " decreases as k delta = " +
                                    std::to_string(kd) + " -> 0");
            previous = gap;
            // The truncated series misses O((k delta)^6) (coefficient ~1e-5);
            // 1e-12: round-off of the quadrature sum.
            check_close(ratio, 1. + a2 * kd * kd + a4 * std::pow(kd, 4), 2e-4 * std::pow(kd, 6) + 1e-12,
                        std::to_string(dim) + "D nonlocal dispersion vs Taylor series, k delta = " +
                          std::to_string(kd));
          }
        check(std::abs(nonlocal(0.01 / delta) / (D * std::pow(0.01 / delta, 2)) - 1.) < 1e-4,
              "nonlocal modes converge to local ones (4.17)");
      }
  }

  // ------------------------------------------------------------------------
  // Frames, mode directions and the guards.
  void
  frames_and_guards()
  {
    for (const double angle : {0., 0.3, 1.2, 2.5, -2.})
      {
        Tensor<1, 2> n;
        n[0]                 = std::cos(angle);
        n[1]                 = std::sin(angle);
        const Tensor<1, 2> e = Abc::EbfDiffusionAbc<2>::local_frame(n) * n;
        check(std::abs(e[0] - std::sqrt(0.5)) < 1e-14 && std::abs(e[1] - std::sqrt(0.5)) < 1e-14,
              "2D frame (4.24) maps the normal at angle " + std::to_string(angle) +
                " onto the quadrant bisector");
      }
    {
      Tensor<1, 3> n;
      n[0] = 0.2;
      n[1] = -0.7;
      n[2] = 0.4;
      n /= n.norm();
      const Tensor<1, 3> e = Abc::EbfDiffusionAbc<3>::local_frame(n) * n;
      Tensor<1, 3> diagonal;
      for (unsigned int d = 0; d < 3; ++d)
        diagonal[d] = 1. / std::sqrt(3.);
      check((e - diagonal).norm() < 1e-14,
            "3D frame maps the normal onto the octant diagonal");
    }
    // Infinity condition (4.20)/(4.22): k < 0 and every mode direction in
    // the first quadrant give k cos(theta* - phi) < 0 ... <= 0 at the edges.
    for (const auto &d : Abc::EbfDiffusionAbc<2>::mode_directions(5))
      for (double th = 0.; th < M_PI / 2.; th += 0.1)
        check(-1. * (d[0] * std::cos(th) + d[1] * std::sin(th)) <= 1e-15 &&
                d[0] >= -1e-15 && d[1] >= -1e-15,
              "mode direction in the first quadrant decays at theta* = " + std::to_string(th));

    // Guards: Delta k beyond (4.33), a cloud of too few points, and an
    // unstable mode set all stop with a ParameterError naming the cloud.
    Triangulation<1> tria;
    GridGenerator::subdivided_hyper_cube(tria, 80, -5., 5.);
    Fem::FemDiffusionParameters fp;
    fp.time_step = 1e-3;
    HeatKernel<1>      c0;
    Abc::EbfParameters ap;
    ap.cloud_radius = 0.25;
    ap.wave_number_range = 40.; // 1/sqrt(D dt) = 31.6
    expect_error([&] {
      Fem::FemDiffusion<1> f(tria, fp);
      f.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    }, "Delta k above the bound (4.33)");
    ap.wave_number_range = 0.;
    ap.cloud_radius      = 0.2; // 2 points
    expect_error([&] {
      Fem::FemDiffusion<1> f(tria, fp);
      f.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    }, "cloud with fewer than 3 points");
    ap.cloud_radius    = 0.25;
    ap.max_update_norm = 0.5; // each V has its own-node weight near 1 here
    expect_error([&] {
      Fem::FemDiffusion<1> f(tria, fp);
      f.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    }, "updating vector above the max-norm guard");
    fp.time_step = 0.01; // > dx^2 / (2 D) = 0.0078
    expect_error([&] { Fem::FemDiffusion<1> f(tria, fp); f.setup(Abc::TruncationBoundary::neumann, ap, c0); },
                    "explicit FEM step above the stability bound");
  }

  // ------------------------------------------------------------------------
  // 1D classical diffusion with a deal.II FEM near field (002 Example 1,
  // reduced: (-10, 10) to t = 40 instead of (-30, 30) to t = 250, i.e. the
  // same ratio of diffusion length to domain size, sqrt(16 t) / L ~ 2.5).
  template <int dim>
  void
  fem_case(const unsigned int degree, const bool lumped, const std::string &scheme,
           const double L, const double dx, const double dt, const double t_end,
           const double energy_tolerance, const double error_tolerance)
  {
    const auto make_mesh = [dx](Triangulation<dim> &tria, const double half_width) {
      GridGenerator::subdivided_hyper_cube(tria, static_cast<unsigned int>(std::round(2. * half_width / dx)),
                                           -half_width, half_width);
    };
    Triangulation<dim> near_tria, wide_tria;
    make_mesh(near_tria, L);
    make_mesh(wide_tria, 5. * L);
    Fem::FemDiffusionParameters fp;
    fp.degree      = degree;
    fp.lumped_mass = lumped;
    fp.scheme      = scheme;
    fp.time_step   = dt;
    Abc::EbfParameters ap;
    ap.n_wave_numbers = 20;
    ap.n_directions   = 5;
    // Two node spacings (dx / degree): 3 points in 1D (002: at least 3).
    ap.cloud_radius = 2. * dx / degree * (1. + 1e-9);
    HeatKernel<dim> c0;
    const auto      n_steps = static_cast<unsigned int>(std::round(t_end / dt));

    std::ostringstream name;
    name << dim << "D FEM Q" << degree << (lumped ? " lumped " : " consistent ") << scheme;
    Fem::FemDiffusion<dim> abc_run(near_tria, fp), neumann_run(near_tria, fp), reference(wide_tria, fp);
    abc_run.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    neumann_run.setup(Abc::TruncationBoundary::neumann, ap, c0);
    reference.setup(Abc::TruncationBoundary::neumann, ap, c0);
    const auto &st = abc_run.absorbing_boundary().statistics();
    if (root())
      std::cout << "  " << name.str() << ": " << st.n_absorbing << " absorbing DoFs, clouds "
                << st.min_cloud_size << ".." << st.max_cloud_size << ", Delta k "
                << st.wave_number_range << " (bound " << st.wave_number_bound
                << "), max cond " << st.max_condition_number << ", max |V| " << st.max_update_norm
                << ", max sum|V| " << st.max_update_l1 << std::endl;
    const History    ref = history<dim>(reference, L, n_steps);
    const Comparison a   = compare(history<dim>(abc_run, L, n_steps), ref);
    const Comparison n   = compare(history<dim>(neumann_run, L, n_steps), ref);
    if (root())
      std::cout << "  " << name.str() << ": Delta Pi/Pi0 ABC max " << a.max_difference << " final "
                << a.final_difference << "; Neumann final " << n.final_difference
                << "; ratio " << n.final_difference / a.final_difference << std::endl;
    check(a.max_difference < energy_tolerance,
          name.str() + ": ABC within " + std::to_string(energy_tolerance) +
            " of the extended domain over the whole run (4.35)");
    check(n.final_difference > 10. * a.final_difference,
          name.str() + ": ABC at least 10x closer to the reference than Neumann at t_end");
    check(a.monotone, name.str() + ": near-field energy non-increasing every step");
    HeatKernel<dim> exact;
    const double    err = abc_run.max_error(exact, cube<dim>(L));
    const double    err_ref = reference.max_error(exact, cube<dim>(L));
    if (root())
      std::cout << "  " << name.str() << ": max |C - heat kernel| on the near field: ABC " << err
                << ", extended domain " << err_ref << std::endl;
    check(err < error_tolerance,
          name.str() + ": max error against the heat kernel " + std::to_string(err) + " < " +
            std::to_string(error_tolerance));
  }

  void
  fem_1d()
  {
    // Tolerances: the source shows Delta Pi / Pi0 "very small" (figure
    // only); we require 1e-3 of Pi0 over the run, i.e. well below the
    // Neumann error (> 1e-2 here). The heat-kernel error budget 2e-3 is the
    // discretization error of the extended run (printed) plus the ABC's.
    fem_case<1>(1, true, "forward Euler", 10., 0.125, 1e-3, 40., 1e-3, 2e-3);
    fem_case<1>(2, false, "backward Euler", 10., 0.25, 1e-2, 40., 1e-3, 2e-3);
    fem_case<1>(1, false, "forward Euler", 10., 0.125, 1e-3, 10., 1e-3, 2e-3);
  }

  void
  fem_2d()
  {
    // Square (-3,3)^2 to t = 3 (diffusion length sqrt(16 t) ~ 2.3 L as in
    // 1D), reference (-15,15)^2. Measured: max Delta Pi/Pi0 8.1e-4 (Neumann
    // 2.7e-2 at t_end), heat-kernel error 1.3e-3 (corner clouds have 6
    // points only); tolerances: 2e-3 for both, an order below Neumann.
    fem_case<2>(1, true, "forward Euler", 3., 0.125, 2e-3, 3., 2e-3, 2e-3);
  }

  // ------------------------------------------------------------------------
  // PD near fields against an extended PD run.
  /** Energy history of a PD run on (-half, half)^dim, measured on (-L, L)^dim. */
  template <int dim>
  History
  pd_history(const double L, const double half, const double dx, const double m, const double dt,
             const double t_end, const Abc::TruncationBoundary boundary, const double layer,
             Abc::CloudStatistics *stats = nullptr, const MPI_Comm comm = MPI_COMM_WORLD)
  {
    LatticeParameters lp;
    lp.dx    = dx;
    lp.delta = m * dx;
    DiffusionModelParameters model;
    model.exponent    = 1.; // 002: p = 1, constant micro-diffusivity
    model.diffusivity = 1.;
    Abc::EbfParameters ap;
    ap.n_wave_numbers  = 20;
    ap.n_directions    = 5;
    // d_inf = delta / 2 (002) in 1D; in 2D with m = 2 that gives corner clouds
    // of 3 points (< 5, the source's minimum), so d_inf = delta there.
    ap.cloud_radius    = (dim == 1 ? 0.5 : 1.) * lp.delta * (1. + 1e-9);
    ap.layer_thickness = layer;
    if (dim == 3)
      {
        // 3D (pd_3d): with d_inf = delta, n_k = 20, n_phi = 5 the update
        // vectors pass the |V| guard (1.63) but sum |V_j| reaches 5.9 and the
        // run diverges. d_inf = 1.44 dx (7..19 points), n_k = 5, n_phi = 11
        // (E11's layout, 555 distinct modes) gives sum |V_j| <= 1.10.
        ap.n_wave_numbers = 5;
        ap.n_directions   = 11;
        ap.cloud_radius   = 1.44 * dx;
      }
    HeatKernel<dim> c0;
    const auto      box = cube<dim>(half);
    BoxDomain<dim>  domain(box.get_boundary_points().first, box.get_boundary_points().second);
    Abc::PdUnboundedDiffusion<dim> run(comm);
    run.setup(domain, lp, model, dt, boundary, ap, c0);
    if (stats)
      *stats = run.absorbing_boundary().statistics();
    return history<dim>(run, L, static_cast<unsigned int>(std::round(t_end / dt)));
  }

  template <int dim>
  void
  pd_abc_vs_neumann(const double L, const double dx, const double m, const double dt,
                    const double t_end, const double tolerance)
  {
    Abc::CloudStatistics st;
    const History ref = pd_history<dim>(L, 5. * L, dx, m, dt, t_end, Abc::TruncationBoundary::neumann, 0.);
    const auto    a   = compare(pd_history<dim>(L, L, dx, m, dt, t_end, Abc::TruncationBoundary::absorbing, 0., &st), ref);
    const auto    n   = compare(pd_history<dim>(L, L, dx, m, dt, t_end, Abc::TruncationBoundary::neumann, 0.), ref);
    std::ostringstream name;
    name << dim << "D PD (m = " << m << ")";
    if (root())
      std::cout << "  " << name.str() << ": " << st.n_absorbing << " absorbing nodes, clouds "
                << st.min_cloud_size << ".." << st.max_cloud_size << ", max cond "
                << st.max_condition_number << ", max |V| " << st.max_update_norm
                << "; Delta Pi/Pi0 ABC max " << a.max_difference << " final " << a.final_difference
                << "; Neumann final " << n.final_difference << "; ratio "
                << n.final_difference / a.final_difference << std::endl;
    check(a.max_difference < tolerance, name.str() + ": ABC within " + std::to_string(tolerance) +
                                          " of the extended PD run over the whole run (4.35)");
    check(n.final_difference > 10. * a.final_difference,
          name.str() + ": ABC at least 10x closer to the reference than Neumann at t_end");
    check(a.monotone, name.str() + ": near-field energy non-increasing every step");
  }

  void
  pd_1d()
  {
    // 002 Example 1 reduced as fem_1d: delta = 4 dx, d_inf = delta/2,
    // delta_L = delta. Tolerance as for FEM.
    pd_abc_vs_neumann<1>(10., 0.125, 4., 1e-3, 40., 1e-3);
  }

  void
  pd_2d()
  {
    // Measured max Delta Pi/Pi0 1.6e-3 (Neumann 2.7e-2); tolerance as for FEM 2D.
    pd_abc_vs_neumann<2>(3., 0.125, 2., 1e-3, 3., 2e-3);
  }

  // Layer study of 002 Example 1 / Fig. 4.11 (reduced): the error decreases
  // with delta_L; the source finds delta_L >= 3 dx adequate.
  void
  pd_layer_study()
  {
    std::vector<double> d;
    const History ref = pd_history<1>(10., 50., 0.125, 4., 1e-3, 40., Abc::TruncationBoundary::neumann, 0.);
    // delta_L = dx diverges here (the source shows only reduced accuracy;
    // see step-5/doc.md): the setup's stability check must stop it.
    expect_error([&]() { pd_history<1>(10., 10., 0.125, 4., 1e-3, 40., Abc::TruncationBoundary::absorbing, 0.125); },
                 "delta_L = dx: the stability check stops the diverging setup");
    for (const unsigned int layers : {2u, 3u, 4u})
      {
        const auto c = compare(pd_history<1>(10., 10., 0.125, 4., 1e-3, 40., Abc::TruncationBoundary::absorbing,
                                             layers * 0.125), ref);
        d.push_back(c.max_difference);
        if (root())
          std::cout << "  delta_L = " << layers << " dx: max Delta Pi/Pi0 " << c.max_difference
                    << ", final " << c.final_difference << std::endl;
      }
    check(d[0] > d[1] && d[1] > d[2], "error decreases as delta_L grows from 2 dx to 4 dx (Fig. 4.11)");
  }

  // ------------------------------------------------------------------------
  // Bi-material corrosion as the near field (dissertation Sect. 4.1.5, 002
  // Example 2): the E10 material, the ABC in the electrolyte, against an
  // extended Neumann run of the same code.

  /**
   * The E10 model: kappa_liq = 7957.70, kappa_int = 795.77, no solid-solid
   * flux, C_sat = 0.8. The source does not state the kernel; kappa_int =
   * 4/(pi delta^2) at delta = 0.04 is exactly the 2D J_2 constant of D = 1
   * (002 Table 1), so J_2 (exponent 2) is used: D_int = 1, D_liq = 10 (2D).
   */
  DiffusionModelParameters
  e10_model()
  {
    DiffusionModelParameters model;
    model.type            = "corrosion";
    model.exponent        = 2.;
    model.kappa_liquid    = 7957.70;
    model.kappa_interface = 795.77;
    model.kappa_solid     = 0.;
    model.saturation      = 0.8;
    return model;
  }

  /** C0 inside a shape, 0 outside. */
  template <int dim>
  class ShapeIndicator : public Function<dim>
  {
  public:
    ShapeIndicator(const std::function<bool(const Point<dim> &)> &inside, const double C0)
      : inside(inside)
      , C0(C0)
    {}
    double
    value(const Point<dim> &p, const unsigned int = 0) const override
    {
      return inside(p) ? C0 : 0.;
    }

  private:
    std::function<bool(const Point<dim> &)> inside;
    double                                  C0;
  };

  struct CorrosionRecord
  {
    std::vector<double> energy, solid;
    bool                monotone = true;
    double              seconds  = 0.;
    types::global_dof_index n_nodes = 0, n_absorbing = 0;
    /** Clouds with points owned by another rank. */
    unsigned int n_straddling = 0;
    /** The ABC's cloud statistics and the setup's one-step growth. */
    Abc::CloudStatistics stats;
    double               growth = 0.;
    /** Per absorbing cloud (this rank): sum_j V_j and the blend theta. */
    std::vector<double> sum_v, theta;
  };

  /**
   * A corrosion run on the ball of @p radius; Pi recorded on |x| <= @p
   * energy_radius (Omega_N of the truncated run), every @p every steps.
   */
  template <int dim>
  CorrosionRecord
  corrosion_record(const double radius, const double energy_radius, const LatticeParameters &lp,
                   const DiffusionModelParameters &model, const Abc::EbfParameters &ap,
                   const Function<dim> &c0, const double dt, const unsigned int n_steps,
                   const unsigned int every, const Abc::TruncationBoundary boundary,
                   const MPI_Comm comm = MPI_COMM_WORLD, const bool cube_domain = false)
  {
    const auto                     start = std::chrono::steady_clock::now();
    BallDomain<dim>                ball(Point<dim>(), radius);
    const auto                     box_corners = cube<dim>(radius).get_boundary_points();
    BoxDomain<dim>                 box(box_corners.first, box_corners.second);
    Abc::PdUnboundedDiffusion<dim> run(comm);
    run.setup(cube_domain ? static_cast<const Domain<dim> &>(box) : ball, lp, model, dt, boundary, ap, c0);
    const typename Abc::PdUnboundedDiffusion<dim>::Region region =
      [energy_radius, &lp, cube_domain](const Point<dim> &x) {
        double r = 0.; // max norm on the cube, Euclidean on the ball
        for (unsigned int d = 0; d < dim; ++d)
          r = std::max(r, std::abs(x[d]));
        return (cube_domain ? r : x.norm()) <= energy_radius + 1e-8 * lp.dx;
      };
    CorrosionRecord r;
    r.n_nodes     = run.discretization().n_global();
    r.n_absorbing = run.absorbing_boundary().statistics().n_absorbing;
    const auto &abc = run.absorbing_boundary();
    for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
      for (const auto &[j, v] : abc.cloud(a))
        if (j >= run.discretization().n_owned())
          {
            ++r.n_straddling;
            break;
          }
    r.n_straddling = Utilities::MPI::sum(r.n_straddling, comm);
    r.stats        = abc.statistics();
    r.growth       = run.stability_growth;
    for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
      {
        double sum = 0.;
        for (const auto &[j, v] : abc.cloud(a))
          sum += v;
        r.sum_v.push_back(sum);
        r.theta.push_back(abc.blend(a));
      }
    double previous = run.energy(region);
    r.energy.push_back(previous);
    r.solid.push_back(run.solid_volume());
    for (unsigned int n = 1; n <= n_steps; ++n)
      {
        run.advance();
        const double e = run.energy(region);
        r.monotone     = r.monotone && e <= previous * (1. + 1e-13);
        previous       = e;
        if (n % every == 0)
          {
            r.energy.push_back(e);
            r.solid.push_back(run.solid_volume());
          }
      }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
  }

  /** max over the records of |a - b| / b(0) for energy and solid volume. */
  std::pair<double, double>
  corrosion_difference(const CorrosionRecord &a, const CorrosionRecord &ref, const bool final_only)
  {
    double de = 0., ds = 0.;
    for (unsigned int k = final_only ? a.energy.size() - 1 : 0; k < a.energy.size(); ++k)
      {
        de = std::max(de, std::abs(a.energy[k] - ref.energy[k]) / ref.energy[0]);
        ds = std::max(ds, std::abs(a.solid[k] - ref.solid[k]) / ref.solid[0]);
      }
    return {de, ds};
  }

  /** An L-shaped solid of 0.5 x 0.5 (E10's letters reduced to one stroke pair). */
  std::function<bool(const Point<2> &)>
  l_shape()
  {
    auto polygon = std::make_shared<Boundary::PolygonDomain>(std::vector<Point<2>>{
      {-0.25, -0.25}, {0.25, -0.25}, {0.25, -0.11}, {-0.11, -0.11}, {-0.11, 0.25}, {-0.25, 0.25}});
    return [polygon](const Point<2> &p) { return polygon->inside(p); };
  }

  Abc::EbfParameters
  e10_abc(const double delta)
  {
    Abc::EbfParameters ap;
    ap.n_wave_numbers = 5; // n_b = 55 = 5 x 11 (E10)
    ap.n_directions   = 11;
    // E10 has d_inf = delta / 2 = dx: the outermost nodes of a lattice disc
    // then have clouds of 3 points (< 5, the source's own minimum, which
    // the guard enforces). d_inf = delta as in pd_2d.
    ap.cloud_radius = delta * (1. + 1e-9);
    // Delta k = 1/d_inf (the source does not report it). Scan on
    // corrosion_2d (max / final Delta Pi/Pi0): 15 and below diverge, 20:
    // 4.4e-3 / 5.3e-4, 25: 3.5e-3 / 2.4e-3, 30: 4.6e-3 / 4.6e-3, 40:
    // 7.4e-3 / 7.3e-3, 50 (the 2/d_inf default): 9.5e-3 / 8.8e-3. 25 keeps
    // a margin from the unstable range.
    ap.wave_number_range = 1. / ap.cloud_radius;
    return ap;
  }

  // Same PD run on all ranks and on rank 0 alone: identical energies.
  void
  pd_rank_invariance()
  {
    for (const unsigned int dim : {1u, 2u})
      {
        const auto run = [dim](const MPI_Comm comm) {
          const History h =
            dim == 1 ? pd_history<1>(4., 4., 0.125, 4., 1e-3, 2., Abc::TruncationBoundary::absorbing, 0., nullptr, comm) :
                       pd_history<2>(2., 2., 0.125, 2., 1e-3, 0.5, Abc::TruncationBoundary::absorbing, 0., nullptr, comm);
          return compare(h, h);
        };
        const Comparison all = run(MPI_COMM_WORLD);
        Comparison       one = all;
        if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
          one = run(MPI_COMM_SELF);
        const double e1 = Utilities::MPI::broadcast(MPI_COMM_WORLD, one.final_energy, 0);
        check_close(all.final_energy, e1, 1e-13,
                    std::to_string(dim) + "D PD with ABC: near-field energy on " +
                      std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)) +
                      " ranks vs 1 rank");
      }

    // Corrosion near field (E10 material, L-shaped solid) to t = 0.003,
    // while the solid is still dissolving: Pi and V_s on all ranks vs 1.
    LatticeParameters lp;
    lp.dx    = 0.02;
    lp.delta = 0.04;
    ShapeIndicator<2> c0(l_shape(), 2.);
    const auto        run = [&](const MPI_Comm comm) {
      return corrosion_record<2>(0.6, 0.56, lp, e10_model(), e10_abc(lp.delta), c0, 5e-6, 600, 100,
                                 Abc::TruncationBoundary::absorbing, comm);
    };
    const CorrosionRecord all = run(MPI_COMM_WORLD);
    CorrosionRecord       one = all;
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      one = run(MPI_COMM_SELF);
    if (root())
      std::cout << "  corrosion: " << all.n_straddling << " of " << all.n_absorbing
                << " absorbing clouds straddle ranks; V_s(t)/V_s(0) = " << all.solid.back() / all.solid[0]
                << std::endl;
    check(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) == 1 || all.n_straddling > 0,
          "some ABC clouds straddle ranks (else the test would not test that)");
    for (unsigned int k = 0; k < all.energy.size(); ++k)
      {
        const double e1 = Utilities::MPI::broadcast(MPI_COMM_WORLD, one.energy[k], 0);
        const double s1 = Utilities::MPI::broadcast(MPI_COMM_WORLD, one.solid[k], 0);
        check_close(all.energy[k], e1, 1e-12, "2D corrosion with ABC: Pi at record " + std::to_string(k) + ", ranks vs 1 rank");
        check_close(all.solid[k], s1, 1e-12, "2D corrosion with ABC: V_s at record " + std::to_string(k) + ", ranks vs 1 rank");
      }

    // The monotone fit (NNLS per cloud) and the setup's stability check on
    // all ranks vs 1.
    auto ap_monotone = e10_abc(lp.delta);
    ap_monotone.fit  = "monotone";
    const auto run_monotone = [&](const MPI_Comm comm) {
      return corrosion_record<2>(0.6, 0.56, lp, e10_model(), ap_monotone, c0, 5e-6, 200, 100,
                                 Abc::TruncationBoundary::absorbing, comm);
    };
    const CorrosionRecord all_m = run_monotone(MPI_COMM_WORLD);
    CorrosionRecord       one_m = all_m;
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      one_m = run_monotone(MPI_COMM_SELF);
    check_close(all_m.energy.back(), Utilities::MPI::broadcast(MPI_COMM_WORLD, one_m.energy.back(), 0), 1e-12,
                "2D corrosion, monotone fit: Pi at t = 0.001, ranks vs 1 rank");

    // The stabilized fit on the lattice sphere of sphere_truncation (its
    // blend is decided by power iterations with global norms): the same
    // clouds blended and the same Pi after 100 steps on all ranks vs 1.
    LatticeParameters lp3;
    lp3.dx    = 0.1;
    lp3.delta = 0.2;
    auto ap3              = e10_abc(lp3.delta);
    ap3.wave_number_range = 0.;
    ap3.fit               = "stabilized";
    ShapeIndicator<3> c3([](const Point<3> &x) { return x.norm() <= 0.5; }, 1.);
    const auto        run_sphere = [&](const MPI_Comm comm) {
      return corrosion_record<3>(1., 0.8, lp3, e10_model(), ap3, c3, 1e-5, 100, 100,
                                 Abc::TruncationBoundary::absorbing, comm);
    };
    const CorrosionRecord all_s = run_sphere(MPI_COMM_WORLD);
    CorrosionRecord       one_s = all_s;
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      one_s = run_sphere(MPI_COMM_SELF);
    if (root())
      std::cout << "  3D sphere, stabilized fit: " << all_s.stats.n_blended << " clouds blended in "
                << all_s.stats.stabilization_rounds << " rounds" << std::endl;
    check(all_s.stats.n_blended > 0 &&
            all_s.stats.n_blended ==
              Utilities::MPI::broadcast(MPI_COMM_WORLD, one_s.stats.n_blended, 0) &&
            all_s.stats.max_blend == Utilities::MPI::broadcast(MPI_COMM_WORLD, one_s.stats.max_blend, 0),
          "3D sphere, stabilized fit: the same clouds blended on all ranks as on 1 rank");
    check_close(all_s.energy.back(), Utilities::MPI::broadcast(MPI_COMM_WORLD, one_s.energy.back(), 0), 1e-12,
                "3D sphere, stabilized fit: Pi at t = 0.001, ranks vs 1 rank");
  }

  // 1D PD diffusion of C0 = exp(-4x^2) on the real line has the
  // Fourier-integral solution
  //   C(x,t) = (1/pi) int_0^inf sqrt(pi)/2 exp(-k^2/16) exp(-lambda(k) t) cos(kx) dk
  // with the PD symbol lambda(k) = kappa int_{-delta}^{delta} (1 - cos(k xi))/|xi| dxi
  // (J_1, constant micro-diffusivity). The discrete run differs by the
  // quadrature error of the standard scheme and the time error.
  void
  pd_fourier()
  {
    const double D = 1., delta = 0.5, kappa = 2. * D / (delta * delta), t_end = 2.;
    const QGauss<1> gauss(8);
    const auto      lambda = [&](const double k) {
      double s = 0.;
      for (unsigned int i = 0; i < 16; ++i) // 16 panels on [0, delta]
        for (unsigned int q = 0; q < gauss.size(); ++q)
          {
            const double r = (i + gauss.point(q)[0]) * delta / 16.;
            s += gauss.weight(q) * delta / 16. * (1. - std::cos(k * r)) / r;
          }
      return 2. * kappa * s;
    };
    // k in [0, 40] (exp(-100) beyond), 800 Gauss panels; lambda tabulated once.
    std::vector<double> k_q, w_q, lambda_q;
    for (unsigned int i = 0; i < 800; ++i)
      for (unsigned int q = 0; q < gauss.size(); ++q)
        {
          const double k = (i + gauss.point(q)[0]) * 0.05;
          k_q.push_back(k);
          w_q.push_back(gauss.weight(q) * 0.05 * 0.5 * std::sqrt(M_PI) * std::exp(-k * k / 16.));
          lambda_q.push_back(lambda(k));
        }
    const auto fourier = [&](const double x, const double t) {
      double s = 0.;
      for (unsigned int j = 0; j < k_q.size(); ++j)
        s += w_q[j] * std::exp(-lambda_q[j] * t) * std::cos(k_q[j] * x);
      return s / M_PI;
    };
    check_close(fourier(0.3, 0.), std::exp(-4. * 0.09), 1e-10, "Fourier integral reproduces C0");
    std::vector<double> errors;
    for (const double m : {4., 8.})
      {
        LatticeParameters lp;
        lp.dx    = delta / m;
        lp.delta = delta;
        DiffusionModelParameters model;
        model.exponent = 1.;
        Abc::EbfParameters ap;
        HeatKernel<1>      c0;
        BoxDomain<1>       box(Point<1>(-20.), Point<1>(20.)); // C(20, 2) ~ exp(-48)
        Abc::PdUnboundedDiffusion<1> run(MPI_COMM_SELF);
        run.setup(box, lp, model, 1e-3, Abc::TruncationBoundary::neumann, ap, c0);
        while (run.time() < t_end - 1e-9)
          run.advance();
        double err = 0.;
        for (unsigned int i = 0; i < run.discretization().n_owned(); ++i)
          {
            const double x = run.discretization().position[i][0];
            if (std::abs(x) <= 5.)
              err = std::max(err, std::abs(run.solution().local_element(i) - fourier(x, t_end)));
          }
        errors.push_back(err);
        if (root())
          std::cout << "  m = " << m << ": max |C - C_Fourier| on [-5,5] at t = 2: " << err
                    << " (C(0,2) = " << fourier(0., t_end) << ")" << std::endl;
      }
    // Measured: 9.8e-6 (m = 4) and 2.1e-5 (m = 8), i.e. 6e-5 and 1.2e-4 of
    // C(0,2) = 0.175. This is the level of the forward Euler error
    // (dt/2) t max|C_tt| ~ 1e-5, so m-convergence is not resolved at this dt.
    // Asserted: the discrete PD solution matches the continuum Fourier solution
    // to 1e-4 (6e-4 of max C) for both m.
    check(errors[0] < 1e-4 && errors[1] < 1e-4,
          "discrete PD = Fourier-integral PD solution to 1e-4 (m = 4 and 8)");
  }

  // Long run: energy non-increasing over @p n_steps steps (1D FEM, PD with
  // the least-squares and the monotone fit).
  void
  energy_stability(const unsigned int n_steps)
  {
    for (const std::string method : {"FEM", "PD", "PD monotone"})
      {
        const bool   pd = method != "FEM";
        const double L = 10., dx = 0.125, dt = 1e-3;
        const auto   region        = cube<1>(L);
        HeatKernel<1>      c0;
        Abc::EbfParameters ap;
        ap.cloud_radius = 0.25 * (1. + 1e-9); // d_inf = delta / 2 = 2 dx
        if (method == "PD monotone")
          ap.fit = "monotone";
        bool   monotone = true;
        double e0 = 0., e = 0.;
        const auto march = [&](auto &run) {
          e0 = e = run.energy(region);
          for (unsigned int n = 0; n < n_steps; ++n)
            {
              run.advance();
              const double en = run.energy(region);
              monotone        = monotone && en <= e * (1. + 1e-13);
              e               = en;
            }
        };
        if (pd)
          {
            LatticeParameters lp;
            lp.dx    = dx;
            lp.delta = 4 * dx;
            DiffusionModelParameters model;
            model.exponent = 1.;
            BoxDomain<1> box(Point<1>(-L), Point<1>(L));
            Abc::PdUnboundedDiffusion<1> run(MPI_COMM_SELF);
            run.setup(box, lp, model, dt, Abc::TruncationBoundary::absorbing, ap, c0);
            march(run);
          }
        else
          {
            Triangulation<1> tria;
            GridGenerator::subdivided_hyper_cube(tria, 160, -L, L);
            Fem::FemDiffusionParameters fp;
            fp.time_step = dt;
            Fem::FemDiffusion<1> run(tria, fp);
            run.setup(Abc::TruncationBoundary::absorbing, ap, c0);
            march(run);
          }
        const double t_end = n_steps * dt;
        if (root())
          std::cout << "  " << method << ": Pi(t=" << t_end << ")/Pi0 = " << e / e0 << std::endl;
        check(monotone && std::isfinite(e),
              method + " 1D: energy non-increasing over " + std::to_string(n_steps) + " steps");
        // The monotone fit: stability only (its accuracy is asserted in
        // sphere_truncation).
        if (n_steps < 1000000 || method == "PD monotone")
          continue;
        // Heat kernel on (-L, L): Pi(t) = sqrt(pi/(8 s)) erf(L sqrt(8/s)), s = 1 + 16 t.
        const auto exact_pi = [L](const double t) {
          const double s = 1. + 16. * t;
          return std::sqrt(M_PI / (8. * s)) * std::erf(L * std::sqrt(8. / s));
        };
        const double ratio_exact = exact_pi(1000.) / exact_pi(0.);
        // At t = 1000 the diffusion length sqrt(16 t) is 12x the near field;
        // the ABC then over-absorbs (measured Pi/Pi0 6.6e-5 vs 2.0e-3). The
        // Neumann truncation tends to the uniform state M/(2L), M = sqrt(pi)/2:
        // the ABC must be 10x closer to the heat kernel than that limit.
        const double neumann_limit = (M_PI / 4.) / (2. * L) / exact_pi(0.);
        check(std::isfinite(e) &&
                std::abs(e / e0 - ratio_exact) < 0.1 * std::abs(neumann_limit - ratio_exact),
              "Pi(1000)/Pi(0) = " + std::to_string(e / e0) + " vs heat kernel " +
                std::to_string(ratio_exact) + ": 10x closer than the Neumann limit " +
                std::to_string(neumann_limit));
      }
  }

  /** Tolerances and what was measured, per case. */
  struct CorrosionCase
  {
    double R, R_ref, dt, t_end;
    unsigned int every;
    double energy_tolerance, solid_tolerance;
    /** Truncate by the cube (-R, R)^dim instead of the ball. */
    bool cube = false;
    /** Required ratio of the Neumann to the ABC difference at t_end. */
    double required_gain = 10.;
  };

  /**
   * ABC, Neumann and extended (Neumann, radius R_ref) runs of the same
   * corrosion problem; asserts the histories of Pi on Omega_N and of the
   * solid volume.
   */
  template <int dim>
  CorrosionRecord
  corrosion_case(const CorrosionCase &c, const LatticeParameters &lp, const DiffusionModelParameters &model,
                 const Abc::EbfParameters &ap, const Function<dim> &c0)
  {
    const unsigned int n_steps = std::round(c.t_end / c.dt);
    const double       omega_n = c.R - lp.delta; // Omega_N without the layer
    const auto abc = corrosion_record<dim>(c.R, omega_n, lp, model, ap, c0, c.dt, n_steps, c.every,
                                           Abc::TruncationBoundary::absorbing, MPI_COMM_WORLD, c.cube);
    const auto neu = corrosion_record<dim>(c.R, omega_n, lp, model, ap, c0, c.dt, n_steps, c.every,
                                           Abc::TruncationBoundary::neumann, MPI_COMM_WORLD, c.cube);
    const auto ref = corrosion_record<dim>(c.R_ref, omega_n, lp, model, ap, c0, c.dt, n_steps, c.every,
                                           Abc::TruncationBoundary::neumann, MPI_COMM_WORLD, c.cube);
    const auto da = corrosion_difference(abc, ref, false), dn = corrosion_difference(neu, ref, true),
               da_final = corrosion_difference(abc, ref, true);
    const std::string name = std::to_string(dim) + "D corrosion: ";
    if (root())
      {
        std::cout << "  " << name << "nodes: near field " << abc.n_nodes << " (" << abc.n_absorbing
                  << " absorbing), reference " << ref.n_nodes << "; seconds ABC " << abc.seconds
                  << ", Neumann " << neu.seconds << ", reference " << ref.seconds << std::endl;
        std::cout << "  Pi/Pi0 at t_end: reference " << ref.energy.back() / ref.energy[0] << ", ABC "
                  << abc.energy.back() / ref.energy[0] << ", Neumann " << neu.energy.back() / ref.energy[0]
                  << "; solid V/V0: reference " << ref.solid.back() / ref.solid[0] << ", ABC "
                  << abc.solid.back() / ref.solid[0] << ", Neumann " << neu.solid.back() / ref.solid[0]
                  << std::endl;
        std::cout << "  max over run: Delta Pi/Pi0 " << da.first << ", Delta V_s/V_s0 " << da.second
                  << "; final: ABC " << da_final.first << " / " << da_final.second << ", Neumann "
                  << dn.first << " / " << dn.second << std::endl;
      }
    check(ref.solid.back() < 0.5 * ref.solid[0], name + "the solid dissolves (V_s(t_end) < V_s(0) / 2)");
    check(da.second < c.solid_tolerance, name + "solid volume history within " + sci(c.solid_tolerance) +
                                           " V_s(0) of the extended domain");
    check(da.first < c.energy_tolerance, name + "Delta Pi/Pi0 (4.35) within " + sci(c.energy_tolerance) +
                                           " of the extended domain over the run");
    check(dn.first > c.required_gain * da_final.first,
          name + "ABC at least " + sci(c.required_gain) +
            "x closer to the reference than Neumann at t_end (ratio " +
            sci(dn.first / da_final.first) + ")");
    check(abc.monotone, name + "near-field energy non-increasing every step (Fig. 4.16)");
    return abc;
  }

  void
  corrosion_2d()
  {
    LatticeParameters lp;
    lp.dx    = 0.02;
    lp.delta = 0.04;
    ShapeIndicator<2> c0(l_shape(), 2.);
    // R_ref = 2: the same run with R_ref = 3 gives the same Pi(t_end) to 6
    // digits (1.6: 7e-6 Pi0 off), so nothing comes back from its boundary.
    // dt = 5e-6 is below the PD bound and D_liq Delta k^2 dt = 0.03 < 1.
    // The L dissolves completely by t ~ 0.004, before its concentration
    // reaches Gamma_inf: the solid history is fixed by the near field and
    // must agree with the reference to round-off (a phase flip of a single
    // node would be 4e-4 / 0.12 = 3e-3 of V_s(0)): tolerance 1e-3.
    // Pi: the source shows Delta Pi/Pi0 "small" (Fig. 4.15, figure only).
    // Measured max 3.5e-3 over the run (the ABC over-absorbs slightly),
    // Neumann 8.1e-2 at t_end; tolerance 5e-3 of Pi0.
    corrosion_case<2>({0.6, 2., 5e-6, 0.02, 100, 5e-3, 1e-3}, lp, e10_model(), e10_abc(lp.delta), c0);
  }

  /**
   * The E11 material in 3D: J_2 with kappa_liq = 7957.7, kappa_int =
   * 795.77 at delta = 0.2 (D_liq = 2 pi delta^3 kappa / 9 = 44.4, D_int =
   * 4.44), solid C0 = 1 (paper 002; the thesis does not state it).
   */
  void
  corrosion_3d()
  {
    LatticeParameters lp;
    lp.dx    = 0.1;
    lp.delta = 0.2;
    ShapeIndicator<3> c0([](const Point<3> &x) { return x.norm() <= 0.5; }, 1.);
    // d_inf = 1.44 dx (d_inf = dx leaves 6 points at face centres), Delta k =
    // 2/d_inf. dt = 1e-5 (D_liq Delta k^2 dt = 0.08): at 5e-5 (0.42) the
    // run diverges. The truncation is the cube (-1, 1)^3: on the ball of
    // radius 1 (10 dx) the run diverges (or trips the |V| guard) for every
    // tried d_inf in {1.45, 1.75} dx, Delta k in {7, 11, 16, 20}, n_phi in
    // {5, 11}. R_ref = 3: the image of its boundary is exp(-4.5^2 / (4
    // D_liq t)) ~ 1e-5. Measured: max Delta Pi/Pi0 1.1e-3, final 8.3e-4,
    // Neumann 2.4e-2; tolerances 2e-3 and 1e-3 (solid, as in 2D).
    auto ap              = e10_abc(lp.delta);
    ap.cloud_radius      = 1.44 * lp.dx;
    ap.wave_number_range = 0.;
    CorrosionCase c{1., 3., 1e-5, 0.01, 100, 2e-3, 1e-3};
    c.cube = true;
    corrosion_case<3>(c, lp, e10_model(), ap, c0);
  }

  /**
   * Truncation by a lattice sphere (radius 10 dx) in 3D, E11 material as in
   * corrosion_3d. The least-squares fit (4.31) gives clouds with sum_j |V_j|
   * up to 2.4 on the staircase of the lattice sphere; unchecked, that run
   * reaches Pi/Pi0 = 7e80 by t = 0.005. The setup's stability check must
   * stop it naming the cloud. The monotone fit (V_j >= 0, sum V_j = 1) makes every row of the
   * one-step map a convex combination: stable by construction; asserted
   * against the extended reference (ball of radius 2, 33,401 nodes).
   */
  void
  sphere_truncation()
  {
    LatticeParameters lp;
    lp.dx    = 0.1;
    lp.delta = 0.2;
    ShapeIndicator<3> c0([](const Point<3> &x) { return x.norm() <= 0.5; }, 1.);
    // d_inf = delta: with 1.44 dx (the cube's choice) the pole nodes of the
    // lattice sphere have 6 points (< 7, the guard). Delta k = 2/d_inf = 10:
    // scan of the monotone fit (max Delta Pi/Pi0): 3: 9.4e-3, 5: 1.2e-2, 10:
    // 7.5e-3, 20: 2.8e-2.
    auto ap              = e10_abc(lp.delta);
    ap.wave_number_range = 0.;
    const double dt      = 1e-5;
    // Least-squares fit: the setup's power iteration finds the growth and
    // names the cloud.
    try
      {
        BallDomain<3>                ball(Point<3>(), 1.);
        Abc::PdUnboundedDiffusion<3> run(MPI_COMM_WORLD);
        run.setup(ball, lp, e10_model(), dt, Abc::TruncationBoundary::absorbing, ap, c0);
        check(false, "lattice sphere, least-squares fit: no ParameterError");
      }
    catch (const ParameterError &e)
      {
        const std::string what = e.what();
        if (root())
          std::cout << "  " << what << std::endl;
        check(what.find("one-step growth") != std::string::npos &&
                what.find("cloud of absorbing node") != std::string::npos,
              "lattice sphere, least-squares fit: setup stops naming the growth and the cloud");
      }
    ap.fit = "monotone";
    {
      BallDomain<3>                ball(Point<3>(), 1.);
      Abc::PdUnboundedDiffusion<3> run(MPI_COMM_WORLD);
      run.setup(ball, lp, e10_model(), dt, Abc::TruncationBoundary::absorbing, ap, c0);
      const auto &abc = run.absorbing_boundary();
      double      min_v = 0., max_sum_error = 0.;
      for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
        {
          double sum = 0.;
          for (const auto &[j, v] : abc.cloud(a))
            {
              min_v = std::min(min_v, v);
              sum += v;
            }
          max_sum_error = std::max(max_sum_error, std::abs(sum - 1.));
        }
      max_sum_error = Utilities::MPI::max(max_sum_error, MPI_COMM_WORLD);
      min_v         = Utilities::MPI::min(min_v, MPI_COMM_WORLD);
      if (root())
        std::cout << "  monotone fit: min V_j " << min_v << ", max |sum V_j - 1| " << max_sum_error
                  << ", max fit residual " << abc.statistics().max_fit_residual << ", one-step growth "
                  << run.stability_growth << std::endl;
      check(min_v >= 0. && max_sum_error < 1e-12, "monotone fit: V_j >= 0 and sum_j V_j = 1 in every cloud");
    }
    // The stabilized fit: least squares except on the clouds of the
    // growing modes, blended toward the monotone fit until the power
    // iteration of the one-step map decays.
    // R_ref = 2: the run ends before the solid's concentration (gone at t =
    // 0.00275) reaches it, exp(-1.5^2 / (4 D_liq t_end)) = 0.08 of the
    // front; it is the reference for Omega_N = |x| <= 0.8 only. Measured:
    // monotone fit max Delta Pi/Pi0 7.4e-3 (the ABC under-absorbs late:
    // Pi/Pi0 0.028 vs 0.020 at t_end), Neumann 4.5e-2 at t_end, gain 6.1;
    // stabilized fit (9 rounds, 751 of 2,060 clouds blended, growth 0.9988)
    // max 3.8e-3, final 1.3e-3, gain 35.0. Asserted: 5e-3 over the run and
    // the gain >= 10 of the issue; the radius-10 dx sphere is half absorbing
    // layer (2,060 of 4,169 nodes).
    ap.fit = "stabilized";
    CorrosionCase c{1., 2., dt, 0.005, 25, 5e-3, 1e-3};
    const auto    abc = corrosion_case<3>(c, lp, e10_model(), ap, c0);
    double        max_theta_error = 0.;
    for (const double th : abc.theta)
      max_theta_error = std::max(max_theta_error, th < 0. ? -th : (th > 1. ? th - 1. : 0.));
    max_theta_error = Utilities::MPI::max(max_theta_error, MPI_COMM_WORLD);
    if (root())
      std::cout << "  stabilized fit: " << abc.stats.n_blended << " of " << abc.stats.n_absorbing
                << " clouds blended (max theta " << abc.stats.max_blend << ") in "
                << abc.stats.stabilization_rounds << " rounds, max sum |V_j| " << abc.stats.max_update_l1
                << ", one-step growth " << abc.growth << std::endl;
    check(abc.growth <= 1. && max_theta_error == 0.,
          "stabilized fit: one-step growth <= 1 and blend theta in [0, 1]");
    // Least squares where it is stable: the blend must be local, not the
    // monotone fit everywhere.
    check(abc.stats.n_blended > 0 && abc.stats.n_blended < abc.stats.n_absorbing / 2,
          "stabilized fit: the blend acts on some, fewer than half, of the clouds");
  }

  // 3D PD diffusion of C0 = exp(-4|x|^2) (J_1, D = 1, delta = 2 dx) on
  // (-1, 1)^3 with the ABC (first octant facing outward, 4.24) against the
  // extended PD run on (-3, 3)^3 and the heat kernel. At t = 0.4 the image
  // of the extended run's boundary contributes exp(-4 * 5^2 / 7.4) ~ 1e-6.
  void
  pd_3d()
  {
    Abc::CloudStatistics st;
    const double L = 1., dx = 0.125, m = 2., dt = 1e-3, t_end = 0.4;
    const auto   start = std::chrono::steady_clock::now();
    const History ref  = pd_history<3>(L, 3., dx, m, dt, t_end, Abc::TruncationBoundary::neumann, 0.);
    const double  t_ref = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto    a = compare(pd_history<3>(L, L, dx, m, dt, t_end, Abc::TruncationBoundary::absorbing, 0., &st), ref);
    const auto    n = compare(pd_history<3>(L, L, dx, m, dt, t_end, Abc::TruncationBoundary::neumann, 0.), ref);
    // Heat kernel: Pi(t) on the cube = s^-3 (sqrt(pi s / 8) erf(L sqrt(8 / s)))^3, s = 1 + 16 t.
    const auto exact_pi = [L](const double t) {
      const double s = 1. + 16. * t;
      return std::pow(s, -3.) * std::pow(std::sqrt(M_PI * s / 8.) * std::erf(L * std::sqrt(8. / s)), 3.);
    };
    const double heat = exact_pi(t_end) / exact_pi(0.);
    if (root())
      std::cout << "  3D PD: " << st.n_absorbing << " absorbing nodes, clouds " << st.min_cloud_size << ".."
                << st.max_cloud_size << ", max cond " << st.max_condition_number << ", max |V| "
                << st.max_update_norm << ", max l1 " << st.max_update_l1 << "; reference " << t_ref << " s; Pi(t_end)/Pi0: reference "
                << ref.energy.back() / ref.energy[0] << ", ABC " << a.final_energy / ref.energy[0]
                << ", Neumann " << n.final_energy / ref.energy[0] << ", heat kernel " << heat
                << "; Delta Pi/Pi0 ABC max " << a.max_difference << " final " << a.final_difference
                << ", Neumann final " << n.final_difference << std::endl;
    // Measured max 8.8e-3 (final 1.1e-3), Neumann 0.177 at t_end.
    check(a.max_difference < 1.2e-2, "3D PD: ABC within " + sci(1.2e-2) + " of the extended run (4.35)");
    check(n.final_difference > 10. * a.final_difference,
          "3D PD: ABC at least 10x closer to the reference than Neumann at t_end");
    check(a.monotone, "3D PD: near-field energy non-increasing every step");
    // The heat kernel is printed only: with delta = 0.25 against the initial
    // width 0.35 the PD solution decays faster (measured Pi ratio 0.0255 vs
    // 0.0314), as the nonlocal dispersion omega > D k^2 (4.17) says.
  }

} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"dispersion", dispersion},
              {"frames_and_guards", frames_and_guards},
              {"fem_1d", fem_1d},
              {"fem_2d", fem_2d},
              {"pd_1d", pd_1d},
              {"pd_2d", pd_2d},
              {"pd_fourier", pd_fourier},
              {"pd_layer_study", pd_layer_study},
              {"pd_rank_invariance", pd_rank_invariance},
              {"long_stability", []() { energy_stability(1000000); }},
              {"stability", []() { energy_stability(100000); }},
              {"corrosion_2d", corrosion_2d},
              {"corrosion_3d", corrosion_3d},
              {"pd_3d", pd_3d},
              {"sphere_truncation", sphere_truncation}});
}
