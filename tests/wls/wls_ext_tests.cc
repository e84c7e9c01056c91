// WLS collocation quadrature beyond scalar diffusion and bond-based
// elasticity (issue 5): the linearized LPS model (dissertation (3.32)-(3.51)),
// the PD scalar wave equation (2.40) and backward Euler diffusion with WLS
// rows in the Jacobian. Every case compares with something independent of
// the discretization: closed forms of the source, the continuum operator of
// polynomial and plane-wave fields, the continuum dispersion relation, the
// manufactured solution (3.77)-(3.78).

#include <deal.II/base/function.h>
#include <deal.II/base/quadrature_lib.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/domain.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/lps.h>
#include <perideal/models/scalar_wave.h>
#include <perideal/time_stepping/diffusion_solver.h>
#include <perideal/time_stepping/static_mechanics.h>

#include "check.h"

#include <cmath>
#include <iomanip>
#include <map>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  // Plane-strain LPS moduli of the tests (K_2 = K + G/3 = 2.4).
  constexpr double K_bulk = 2.1, G_shear = 0.9;

  // ------------------------------------------------------------------
  // Operator rows against the source's closed forms (3D, order 2, with the
  // errata: 3/m-bar kept in (3.36), so 3 lambda_theta / m-bar = 1).
  void
  lps_rows()
  {
    const MonomialBasis<3> b(2);
    const double           delta = 1.3, K = 2.1, G = 0.9;
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        const std::string name = omega == InfluenceFunction::constant ? "omega_0" : "omega_1";
        const double      mbar = lps_weighted_volume<3>(omega, delta);
        // (2.15): 4 pi delta^5/5 (omega_0), 4 pi delta^5/30 (omega_1).
        check_close(mbar,
                    (omega == InfluenceFunction::constant ? 4. / 5. : 4. / 30.) * M_PI *
                      std::pow(delta, 5),
                    1e-14, name + ": m-bar");
        // (3.39): lambda_theta = 4 pi delta^5/15 or 2 pi delta^5/45, times 3/m-bar = 1.
        const double lt =
          (omega == InfluenceFunction::constant ? 4. / 15. : 2. / 45.) * M_PI * std::pow(delta, 5);
        check_close(3. * lt / mbar, 1., 1e-14, name + ": 3 lambda_theta / m-bar (3.39)");
        const auto th = vector_operator_rows<3>(3. / mbar, omega, delta, b);
        double     dev = 0.;
        for (unsigned int a = 0; a < 3; ++a)
          for (unsigned int al = 0; al < b.size(); ++al)
            dev = std::max(dev, std::abs(th[a * b.size() + al] - (al == 1 + a ? 1. : 0.)));
        check(dev < 1e-14, name + ": L_theta = (3.38) with 3 lambda_theta/m-bar = 1, max dev " +
                             sci(dev));
        // (3.45): L_I = (3K - 5G)/3 times the selection of x, y, z.
        const auto LI = vector_operator_rows<3>((3. * K - 5. * G) / mbar, omega, delta, b);
        dev           = 0.;
        for (unsigned int a = 0; a < 3; ++a)
          for (unsigned int al = 0; al < b.size(); ++al)
            dev = std::max(dev, std::abs(LI[a * b.size() + al] -
                                         (al == 1 + a ? (3. * K - 5. * G) / 3. : 0.)));
        check(dev < 1e-14, name + ": L_I = (3K - 5G)/3 selection (3.45), max dev " + sci(dev));
        // (3.50): L_J = 6G times the pattern (1 on the own second derivative,
        // 1/3 on the others and the mixed ones), basis (1,x,y,z,x2,xy,xz,y2,yz,z2).
        const auto LJ = pair_tensor_operator_rows<3>(30. * G / mbar, omega, delta, 2., b);
        const double pattern[3][3][10] = {
          {{0, 0, 0, 0, 1, 0, 0, 1. / 3, 0, 1. / 3}, {0, 0, 0, 0, 0, 1. / 3, 0, 0, 0, 0},
           {0, 0, 0, 0, 0, 0, 1. / 3, 0, 0, 0}},
          {{0, 0, 0, 0, 0, 1. / 3, 0, 0, 0, 0}, {0, 0, 0, 0, 1. / 3, 0, 0, 1, 0, 1. / 3},
           {0, 0, 0, 0, 0, 0, 0, 0, 1. / 3, 0}},
          {{0, 0, 0, 0, 0, 0, 1. / 3, 0, 0, 0}, {0, 0, 0, 0, 0, 0, 0, 0, 1. / 3, 0},
           {0, 0, 0, 0, 1. / 3, 0, 0, 1. / 3, 0, 1}}};
        // (3.50) prints L_J,u as the block acting on u: rows a = x, y, z of the
        // force, so entry (a, u-component) is pattern[0][a].
        dev = 0.;
        for (unsigned int a = 0; a < 3; ++a)
          for (unsigned int c = 0; c < 3; ++c)
            for (unsigned int al = 0; al < 10; ++al)
              dev = std::max(dev, std::abs(LJ[(a * 3 + c) * 10 + al] - 6. * G * pattern[c][a][al]));
        check(dev < 1e-13, name + ": L_J = 6G (3.50), max dev " + sci(dev));
        // s = 3 is the bond-based operator.
        const auto bb  = bond_based_operator_rows<3>(1.7, omega, delta, b);
        const auto pt3 = pair_tensor_operator_rows<3>(1.7, omega, delta, 3., b);
        dev            = 0.;
        for (unsigned int e = 0; e < bb.size(); ++e)
          dev = std::max(dev, std::abs(bb[e] - pt3[e]));
        check(dev < 1e-14, name + ": pair tensor s = 3 = bond-based rows, max dev " + sci(dev));
      }
    // Deviatoric moment: a linear field u = H x, H symmetric, gives
    // int omega (e - theta r/d)^2 = 2 |dev H|^2 m-bar/(d (d+2)), so that
    // alpha/2 c^T M c = G |dev H|^2 (the CCM deviatoric energy).
    auto dev_check = [](auto dim_tag) {
      constexpr int          dim = decltype(dim_tag)::value;
      const MonomialBasis<dim> b(2);
      const auto             omega = InfluenceFunction::linear;
      const double           delta = 0.7, mbar = lps_weighted_volume<dim>(omega, delta);
      const auto             M     = lps_deviatoric_moment_matrix<dim>(omega, delta, b);
      Tensor<2, dim>         H;
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int c = 0; c < dim; ++c)
          H[a][c] = 0.3 + 0.1 * a - 0.2 * c + (a == c ? 0.5 * a : 0.) + 0.1 * (a + c);
      H = symmetrize(H);
      const unsigned int  np = b.size(), n = dim * np;
      std::vector<double> c(n, 0.);
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int d = 0; d < dim; ++d)
          c[a * np + 1 + d] = H[a][d];
      double q = 0.;
      for (unsigned int x = 0; x < n; ++x)
        for (unsigned int y = 0; y < n; ++y)
          q += c[x] * M[x * n + y] * c[y];
      const Tensor<2, dim> D = H - trace(H) / dim * unit_symmetric_tensor<dim>();
      check_close(q, 2. * scalar_product(D, D) * mbar / (dim * (dim + 2.)), 1e-12,
                  std::to_string(dim) + "D: c^T M c of a homogeneous strain");
    };
    dev_check(std::integral_constant<int, 2>());
    dev_check(std::integral_constant<int, 3>());
  }

  // ------------------------------------------------------------------
  // 2D LPS helpers.
  StaticMechanicsParameters<2>
  lps_parameters(const double delta, const unsigned int m, const std::string &quadrature,
                 const unsigned int order)
  {
    StaticMechanicsParameters<2> p;
    p.domain                  = std::make_shared<BoxDomain<2>>(Point<2>(), Point<2>(1., 1.));
    p.lattice.dx              = delta / m;
    p.lattice.delta           = delta;
    // 2 delta (+ the partial-volume shell): every node within delta of the
    // body has a full family, so the dilatations the body's forces read are
    // full-ball fits (WLS) or full sums (standard).
    p.lattice.layer_thickness = 2. * (delta + 0.5 * delta / m);
    p.model                   = "LPS";
    p.lps.bulk_modulus        = K_bulk;
    p.lps.shear_modulus       = G_shear;
    p.body_force         = [](const Point<2> &) { return Tensor<1, 2>(); };
    p.layer_displacement = p.body_force;
    p.tolerance          = 1e-12;
    p.solver             = "direct";
    p.quadrature         = quadrature;
    p.wls.order          = order;
    return p;
  }

  // A quadratic field, its Navier operator (K_2 grad div + G Laplace, the
  // continuum LPS operator of a quadratic) and a symmetric homogeneous strain.
  Tensor<1, 2>
  quadratic_u(const Point<2> &p)
  {
    const double x = p[0], y = p[1];
    Tensor<1, 2> u;
    u[0] = 0.1 + 0.3 * x - 0.2 * y + 0.5 * x * x + 0.7 * x * y - 0.4 * y * y;
    u[1] = -0.2 + 0.1 * x + 0.4 * y - 0.3 * x * x + 0.6 * x * y + 0.8 * y * y;
    return u;
  }
  Tensor<1, 2>
  quadratic_navier()
  {
    // u_xx = (1, -0.6), u_xy = (0.7, 0.6), u_yy = (-0.8, 1.6).
    const double K2 = K_bulk + G_shear / 3.;
    Tensor<1, 2> f;
    // grad div u = (u0_xx + u1_xy, u0_xy + u1_yy); Laplace u = u_xx + u_yy.
    f[0] = K2 * (1. + 0.6) + G_shear * (1. - 0.8);
    f[1] = K2 * (0.7 + 1.6) + G_shear * (-0.6 + 1.6);
    return f;
  }

  // Fields on all (owned + ghost) nodes.
  template <typename F>
  void
  fill(const Discretization<2> &disc, std::array<PeriDEAL::Vector, 2> &u, const F &f)
  {
    for (auto &c : u)
      disc.initialize_vector(c);
    for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
      {
        const auto v = f(disc.position[i]);
        u[0].local_element(i) = v[0];
        u[1].local_element(i) = v[1];
      }
  }

  bool
  deep_interior(const Discretization<2> &disc, const unsigned int i)
  {
    return disc.region[i] == Discretization<2>::interior;
  }

  // WLS-2 reproduces the continuum LPS operator of a quadratic field, the
  // patch test (homogeneous strain: zero force, theta = tr H, W = CCM energy
  // density), and the static problem with a quadratic exact solution; the
  // standard scheme is shown next to it. Run with 1 and 2 ranks.
  void
  lps_polynomial()
  {
    const double delta = 0.25;
    const double K2    = K_bulk + G_shear / 3.;
    for (const std::string q : {"standard", "wls"})
      {
        const unsigned int m = 3;
        // b = -Navier(u): a constant body force.
        auto p       = lps_parameters(delta, m, q, 2);
        const auto b = -quadratic_navier();
        p.body_force = [b](const Point<2> &) { return b; };
        p.layer_displacement = quadratic_u;
        StaticMechanicsSolver<2> solver(MPI_COMM_WORLD, p);
        solver.setup();
        const auto &disc = solver.discretization();
        const auto &op   = *solver.lps_operator();

        // (a) Operator on the quadratic field.
        std::array<PeriDEAL::Vector, 2> u, f;
        fill(disc, u, quadratic_u);
        fill(disc, f, [](const Point<2> &) { return Tensor<1, 2>(); });
        solver.compute_forces(u, f);
        const auto   nav = quadratic_navier();
        double       err = 0.;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (deep_interior(disc, i))
            for (unsigned int d = 0; d < 2; ++d)
              err = std::max(err, std::abs(f[d].local_element(i) - nav[d]) / nav.norm());
        err = Utilities::MPI::max(err, MPI_COMM_WORLD);
        if (q == "wls")
          check(err < 1e-10, "WLS-2 force of a quadratic field = Navier operator, rel. error " +
                               sci(err));
        else
          {
            check(err > 1e-6, "standard scheme (m = 3): quadrature error of the quadratic's "
                              "force " + sci(err) + " (the WLS gain is real)");
          }

        // (b) Patch test: u = H x, H symmetric.
        Tensor<2, 2> H;
        H[0][0] = 0.012;
        H[1][1] = -0.005;
        H[0][1] = H[1][0] = 0.004;
        fill(disc, u, [&](const Point<2> &x) { return H * Tensor<1, 2>(x); });
        solver.compute_forces(u, f);
        PeriDEAL::Vector W;
        disc.initialize_vector(W);
        op.strain_energy_density(u, W);
        const Tensor<2, 2> D       = H - 0.5 * trace(H) * unit_symmetric_tensor<2>();
        const double       W_ccm   = 0.5 * K2 * trace(H) * trace(H) + G_shear * scalar_product(D, D);
        // plane-strain CCM: K tr^2/2 + G |dev_3D H|^2.
        const double tr3 = trace(H) / 3.;
        const double W_3d = 0.5 * K_bulk * trace(H) * trace(H) +
                            G_shear * (std::pow(H[0][0] - tr3, 2) + std::pow(H[1][1] - tr3, 2) +
                                       2. * H[0][1] * H[0][1] + tr3 * tr3);
        check_close(W_ccm, W_3d, 1e-13, "K_2 tr^2/2 + G |dev_2 H|^2 = plane-strain CCM energy");
        double ferr = 0., terr = 0., werr = 0.;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (deep_interior(disc, i))
            {
              for (unsigned int d = 0; d < 2; ++d)
                ferr = std::max(ferr, std::abs(f[d].local_element(i)));
              terr = std::max(terr, std::abs(op.dilatation().local_element(i) - trace(H)));
              werr = std::max(werr, std::abs(W.local_element(i) - W_ccm) / W_ccm);
            }
        ferr = Utilities::MPI::max(ferr, MPI_COMM_WORLD);
        terr = Utilities::MPI::max(terr, MPI_COMM_WORLD);
        werr = Utilities::MPI::max(werr, MPI_COMM_WORLD);
        // Force scale: K_2 |H| / delta times the number of stencil terms.
        const double fscale = K2 * H.norm() / delta;
        check(ferr < 1e-11 * fscale, q + ": patch test force " + sci(ferr) + " (scale " +
                                       sci(fscale) + ")");
        check(terr < 1e-12, q + ": patch test theta = tr H, error " + sci(terr));
        if (q == "wls")
          check(werr < 1e-11, "WLS-2 patch test: W = CCM energy density, rel. error " + sci(werr));
        else
          check(werr > 1e-4, "standard: W of a homogeneous strain differs from the CCM value by " +
                               sci(werr) + " (discrete angular moments)");

        // (c) Static solve with the quadratic exact solution.
        solver.solve();
        double uerr = 0., un = 0.;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (!solver.fixed_nodes()[i])
            {
              const auto ue = quadratic_u(disc.position[i]);
              for (unsigned int d = 0; d < 2; ++d)
                {
                  uerr = std::max(uerr, std::abs(solver.displacement()[d].local_element(i) - ue[d]));
                  un   = std::max(un, std::abs(ue[d]));
                }
            }
        uerr = Utilities::MPI::max(uerr, MPI_COMM_WORLD) / Utilities::MPI::max(un, MPI_COMM_WORLD);
        if (root())
          std::cout << "    " << q << ": static quadratic, " << solver.n_iterations()
                    << " iterations, residual " << sci(solver.relative_residual())
                    << ", max rel. error " << sci(uerr) << std::endl;
        if (q == "wls")
          check(uerr < 1e-9, "WLS-2 static solution = quadratic exact solution, error " +
                               sci(uerr));
        else
          check(uerr > 1e-5, "standard static solution has a quadrature error " + sci(uerr));
      }
  }

  // ------------------------------------------------------------------
  // m-convergence of the 2D LPS (Table 3.1 style, in 2D): delta fixed, the
  // manufactured solution u = sum of plane waves A sin(k.x + phi), whose
  // continuum LPS operator is -S(k) A sin(k.x + phi) with
  //   S(k) = (d a_vol/m^2) g g^T + (2 a_dev/m) H,
  //   g = int omega xi sin(k.xi) dV, H = int omega n n^T (1 - cos(k.xi)) dV
  // (a_vol = d K_d - (d+2) G, a_dev = d (d+2) G), by polar quadrature
  // independent of the lattice.
  struct PlaneWave
  {
    Tensor<1, 2> k, A;
    double       phi;
    Tensor<2, 2> S;
  };

  std::vector<PlaneWave>
  lps_plane_waves(const double delta)
  {
    const double K2 = K_bulk + G_shear / 3., G = G_shear, d = 2.;
    const double m     = lps_weighted_volume<2>(InfluenceFunction::constant, delta);
    const double a_vol = d * K2 - (d + 2.) * G, a_dev = d * (d + 2.) * G;
    std::vector<PlaneWave> waves(2);
    waves[0].k   = Tensor<1, 2>({3., 1.5});
    waves[0].A   = Tensor<1, 2>({0.01, 0.004});
    waves[0].phi = 0.3;
    waves[1].k   = Tensor<1, 2>({-1., 2.5});
    waves[1].A   = Tensor<1, 2>({-0.003, 0.008});
    waves[1].phi = 1.1;
    const QGauss<1> qr(40);
    const unsigned int n_theta = 256;
    for (auto &w : waves)
      {
        Tensor<1, 2> g;
        Tensor<2, 2> H;
        for (unsigned int q = 0; q < qr.size(); ++q)
          {
            const double r = delta * qr.point(q)[0], wr = delta * qr.weight(q) * r;
            for (unsigned int t = 0; t < n_theta; ++t)
              {
                const double   th = 2. * M_PI * (t + 0.5) / n_theta, wt = 2. * M_PI / n_theta;
                Tensor<1, 2>   n({std::cos(th), std::sin(th)});
                const double   kx = w.k * (r * n);
                g += wr * wt * r * std::sin(kx) * n;
                H += wr * wt * (1. - std::cos(kx)) * outer_product(n, n);
              }
          }
        w.S = d * a_vol / (m * m) * outer_product(g, g) + 2. * a_dev / m * H;
      }
    return waves;
  }

  // Relative l2 error of the static solution over the body; in @p consistency
  // the truncation error of the scheme, ||f_h(u_exact) + b|| / ||b|| over the
  // free nodes (the force of the exact field against the continuum's).
  double
  lps_m_error(const double delta, const unsigned int m, const std::string &q,
              const unsigned int order, double &consistency, double &residual,
              const std::string &linear_solver = "direct")
  {
    const auto waves = lps_plane_waves(delta);
    auto       exact = [waves](const Point<2> &x) {
      Tensor<1, 2> u;
      for (const auto &w : waves)
        u += std::sin(w.k * Tensor<1, 2>(x) + w.phi) * w.A;
      return u;
    };
    auto p       = lps_parameters(delta, m, q, order);
    p.solver     = linear_solver;
    p.tolerance  = 1e-11;
    p.body_force = [waves](const Point<2> &x) {
      Tensor<1, 2> b;
      for (const auto &w : waves)
        b += std::sin(w.k * Tensor<1, 2>(x) + w.phi) * (w.S * w.A);
      return b;
    };
    p.layer_displacement = exact;
    StaticMechanicsSolver<2> solver(MPI_COMM_WORLD, p);
    solver.setup();
    const auto &disc = solver.discretization();
    {
      std::array<PeriDEAL::Vector, 2> ue, f;
      fill(disc, ue, exact);
      fill(disc, f, exact);
      solver.compute_forces(ue, f);
      double t2 = 0., b2 = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (!solver.fixed_nodes()[i])
          {
            const auto b = p.body_force(disc.position[i]);
            for (unsigned int c = 0; c < 2; ++c)
              {
                t2 += std::pow(f[c].local_element(i) + b[c], 2);
                b2 += b[c] * b[c];
              }
          }
      consistency = std::sqrt(Utilities::MPI::sum(t2, MPI_COMM_WORLD) /
                              Utilities::MPI::sum(b2, MPI_COMM_WORLD));
    }
    solver.solve();
    residual = solver.relative_residual();
    double      e2 = 0., n2 = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (!solver.fixed_nodes()[i])
        {
          const auto ue = exact(disc.position[i]);
          for (unsigned int c = 0; c < 2; ++c)
            {
              e2 += std::pow(solver.displacement()[c].local_element(i) - ue[c], 2);
              n2 += ue[c] * ue[c];
            }
        }
    return std::sqrt(Utilities::MPI::sum(e2, MPI_COMM_WORLD) / Utilities::MPI::sum(n2, MPI_COMM_WORLD));
  }

  void
  lps_m_convergence()
  {
    const double delta = 0.25;
    // The exact nonlocal solution of the continuum: the standard scheme's
    // consistency check is that its error falls with m; WLS-k is exact for
    // polynomials of degree <= k (lps_polynomial), so for the plane waves its
    // error is the polynomial-fit error of the fields over one horizon,
    // O((|k| delta)^(k+1)) with |k| delta = 0.84, independent of m: a plateau.
    // All WLS systems are solved by the direct factorization of the
    // assembled (probed) WLS matrix; with the standard-K-preconditioned
    // GMRES WLS-4 did not converge at m = 6, 8.
    std::map<std::string, std::map<unsigned int, double>> err, tau;
    const std::vector<unsigned int> ms = {3, 4, 6, 8};
    auto run_case = [&](const std::string &name, const unsigned int m, const std::string &q,
                        const unsigned int order) {
      double res = 0.;
      err[name][m] = lps_m_error(delta, m, q, order, tau[name][m], res);
      if (root())
        std::cout << "    " << name << ", m = " << m << ": error " << sci(err[name][m])
                  << ", truncation error " << sci(tau[name][m]) << ", solver residual "
                  << sci(res) << std::endl;
      check(res < 1e-10, name + ", m = " + std::to_string(m) + ": linear system solved, residual " +
                           sci(res));
    };
    {
      // the iterative path: GMRES, right-preconditioned with the AMG of the
      // standard stiffness, stopping on the true residual
      double t, res;
      const double e = lps_m_error(delta, 4, "wls", 2, t, res, "cg-amg");
      const double e_direct = lps_m_error(delta, 4, "wls", 2, t, t);
      if (root())
        std::cout << "    WLS-2, m = 4, GMRES + AMG: error " << sci(e) << ", residual "
                  << sci(res) << " (direct: error " << sci(e_direct) << ")" << std::endl;
      check(res < 1e-10 && std::abs(e - e_direct) < 1e-6 * e_direct,
            "WLS-2, m = 4: GMRES + AMG reaches the direct solution");
    }
    for (const unsigned int m : ms)
      {
        run_case("standard", m, "standard", 2);
        run_case("WLS-2", m, "wls", 2);
        if (m >= 4)
          run_case("WLS-4", m, "wls", 4);
      }
    if (root())
      {
        std::cout << "    2D LPS m-convergence, delta = " << delta
                  << ", relative l2 error over the body (truncation error)\n"
                     "    m   standard              WLS-2                 WLS-4\n";
        for (const unsigned int m : ms)
          std::cout << "    " << std::setw(2) << m << "  " << sci(err["standard"][m]) << " ("
                    << sci(tau["standard"][m]) << ")  " << sci(err["WLS-2"][m]) << " ("
                    << sci(tau["WLS-2"][m]) << ")  "
                    << (err["WLS-4"].count(m) ? sci(err["WLS-4"][m]) + " (" +
                                                  sci(tau["WLS-4"][m]) + ")" :
                                                std::string("-"))
                    << "\n";
      }
    for (unsigned int k = 1; k < ms.size(); ++k)
      check(err["standard"][ms[k]] < err["standard"][ms[k - 1]],
            "standard error decreases with m (m = " + std::to_string(ms[k]) + ")");
    // Plateaus: the WLS truncation errors vary by less than 25 % over m = 3..8
    // (resp. 4..8) while the standard one falls (the fit error does not
    // depend on the node count); the WLS-2 solution error likewise.
    auto spread = [](const std::map<unsigned int, double> &e) {
      double lo = 1e300, hi = 0.;
      for (const auto &[m, v] : e)
        lo = std::min(lo, v), hi = std::max(hi, v);
      return hi / lo;
    };
    for (const std::string name : {"WLS-2", "WLS-4"})
      check(spread(tau[name]) < 1.25,
            name + ": truncation error plateaus (max/min over m " + sci(spread(tau[name])) +
              " < 1.25)");
    check(spread(err["WLS-2"]) < 1.25,
          "WLS-2: solution error plateaus (max/min over m " + sci(spread(err["WLS-2"])) + ")");
    check(tau["standard"][3] > 2. * tau["standard"][8],
          "standard truncation error falls with m (m = 3: " + sci(tau["standard"][3]) +
            ", m = 8: " + sci(tau["standard"][8]) + ")");
    // Order: the 1D source (Table 3.1) reports WLS-4 about two orders below
    // WLS-2; measured here 82-97x in the truncation error. Asserted: more
    // than 1.5 orders (30x) at every m.
    for (const unsigned int m : ms)
      if (m >= 4)
        check(tau["WLS-4"][m] < tau["WLS-2"][m] / 30.,
              "m = " + std::to_string(m) + ": WLS-4 truncation error " + sci(tau["WLS-4"][m]) +
                " < WLS-2's / 30 (" + sci(tau["WLS-2"][m]) + ")");
    // The solution error is the truncation error times the stability
    // constant of the non-symmetric WLS matrix; for WLS-4 that constant
    // grows at m = 8 (error/truncation 1.2, 1.1, 3.7 at m = 4, 6, 8: the 49
    // collocation nodes of a ~200-node family control the grid-scale modes
    // less well), so only the ordering is asserted for the solution:
    for (const unsigned int m : ms)
      if (m >= 4)
        check(err["WLS-4"][m] < err["WLS-2"][m] / 10.,
              "m = " + std::to_string(m) + ": WLS-4 solution error " + sci(err["WLS-4"][m]) +
                " < WLS-2's / 10 (" + sci(err["WLS-2"][m]) + ")");
  }

  // ------------------------------------------------------------------
  // Scalar waves (2.40), 1D, p = 0, omega_0, chi = 1: the standing wave
  // cos(kx) cos(Omega t) of the scheme (layer data at the scheme's own
  // Verlet frequency) is simulated, its frequency measured from the zero
  // crossings at x = 0 and compared with the continuum PD relation
  // omega^2 = 2 c_s (delta - sin(k delta)/k), c_s = 3 chi^2/delta^3 (4.90).
  class StandingWave : public Function<1>
  {
  public:
    StandingWave(const double k, const double omega)
      : k(k)
      , omega(omega)
    {}
    double
    value(const Point<1> &p, const unsigned int = 0) const override
    {
      return std::cos(k * p[0]) * std::cos(omega * get_time());
    }

  private:
    double k, omega;
  };

  double
  continuum_omega_1d(const double k, const double delta)
  {
    return std::sqrt(2. * 3. / std::pow(delta, 3) * (delta - std::sin(k * delta) / k));
  }

  // Measured (zero crossings over 3 periods) and semi-discrete omega_h of
  // the scheme; checks that the run reproduces omega_h through Verlet.
  std::pair<double, double>
  measured_omega(const unsigned int m, const double kdelta, const std::string &q,
                 const unsigned int order)
  {
    const double dx = 0.1, L = 10., delta = m * dx, k = kdelta / delta;
    LatticeParameters lp;
    lp.dx              = dx;
    lp.delta           = delta;
    lp.layer_thickness = delta;
    BoxDomain<1>      box(Point<1>(-L), Point<1>(L));
    Discretization<1> disc(MPI_COMM_WORLD);
    disc.setup(box, lp);
    ScalarWaveParameters wp;
    wp.exponent   = 0.;
    wp.wave_speed = 1.;
    wp.quadrature = q;
    wp.wls.order  = order;
    wp.time_step  = 1e-3;
    // dt small enough that the O((omega dt)^2) error of the linearly
    // interpolated crossings stays below 3e-7 up to k delta = 3.
    const double dt = 0.02 * ScalarWaveSolver<1>(disc, wp).critical_time_step();
    wp.time_step    = dt;

    int center = -1;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (std::abs(disc.position[i][0]) < 0.5 * dx)
        center = i;
    auto center_value = [&](const PeriDEAL::Vector &v) {
      return Utilities::MPI::sum(center >= 0 ? v.local_element(center) : 0., MPI_COMM_WORLD);
    };
    // omega_h^2 = -(L cos(kx))(0).
    double w_h;
    {
      ScalarWaveSolver<1> s(disc, wp);
      StandingWave        g(k, 0.);
      s.set_initial_values(g);
      s.set_boundary_values(std::make_shared<StandingWave>(k, 0.));
      s.initialize();
      w_h = std::sqrt(-center_value(s.acceleration));
    }
    const double verlet = 2. / dt * std::asin(0.5 * w_h * dt);
    ScalarWaveSolver<1> s(disc, wp);
    auto                g = std::make_shared<StandingWave>(k, verlet);
    s.set_boundary_values(g);
    g->set_time(0.);
    s.set_initial_values(*g);
    s.initialize();
    std::vector<double> crossings;
    double              u_old = center_value(s.displacement);
    while (s.time() < 3. * 2. * M_PI / w_h)
      {
        s.advance();
        const double u_new = center_value(s.displacement);
        if ((u_old > 0.) != (u_new > 0.))
          crossings.push_back(s.time() - dt * u_new / (u_new - u_old));
        u_old = u_new;
      }
    const double n  = crossings.size();
    double       sj = 0., st = 0., sjj = 0., sjt = 0.;
    for (unsigned int j = 0; j < crossings.size(); ++j)
      {
        sj += j;
        st += crossings[j];
        sjj += double(j) * j;
        sjt += j * crossings[j];
      }
    const double w_meas = M_PI * (n * sjj - sj * sj) / (n * sjt - sj * st);
    if (q == "wls" && order == 4)
      {
        // WLS-4 (n_c = 11) runs unstable near the layer (NaN by t ~ 3
        // periods, like the WLS-4 growth of step-9's E2): only its
        // semi-discrete omega_h (the operator at t = 0) is used.
        if (root())
          std::cout << "    WLS-4, m = " << m << ", k delta = " << kdelta
                    << ": run measured " << w_meas << " (unstable), omega_h " << w_h
                    << std::endl;
        return {w_meas, w_h};
      }
    // O(dt^3) crossing interpolation: 3e-7 as in waves.standing_wave.
    check_close(w_meas, verlet, 3e-7,
                q + (q == "wls" ? "-" + std::to_string(order) : std::string()) + ", m = " +
                  std::to_string(m) + ", k delta = " + std::to_string(kdelta) +
                  ": measured = Verlet-shifted omega_h");
    return {w_meas, w_h};
  }

  void
  wave_dispersion()
  {
    struct Scheme
    {
      std::string  name, q;
      unsigned int order, m_min;
    };
    const std::vector<Scheme> schemes = {
      {"standard", "standard", 2, 1}, {"WLS-2", "wls", 2, 2}, {"WLS-4", "wls", 4, 5},
      {"WLS-6", "wls", 6, 6}};
    std::map<std::string, std::map<std::pair<unsigned int, double>, double>> err;
    for (const unsigned int m : {3u, 6u})
      for (const double kd : {0.5, 1., 2., 3.})
        for (const auto &sc : schemes)
          if (m >= sc.m_min)
            {
              const auto   w  = measured_omega(m, kd, sc.q, sc.order);
              const double wc = continuum_omega_1d(kd / (m * 0.1), m * 0.1);
              // The semi-discrete omega_h against the continuum (the measured one
              // carries the Verlet shift (omega dt)^2/24).
              err[sc.name][{m, kd}] = std::abs(w.second - wc) / wc;
            }
    if (root())
      {
        std::cout << "    |omega_h - omega_PD| / omega_PD (1D, p = 0, omega_0)\n"
                     "    m  k delta  standard   WLS-2      WLS-4      WLS-6\n";
        for (const unsigned int m : {3u, 6u})
          for (const double kd : {0.5, 1., 2., 3.})
            {
              std::cout << "    " << m << "  " << std::setw(5) << kd;
              for (const auto &sc : schemes)
                std::cout << "  "
                          << (err[sc.name].count({m, kd}) ? sci(err[sc.name][{m, kd}]) :
                                                            std::string("   -     "));
              std::cout << "\n";
            }
      }
    // What holds (measured): in the long-wave range k delta = 0.5 every WLS
    // order beats the standard scheme at the same m; WLS-4/6 beat it up to
    // k delta = 2 (at k delta = 3 the standard scheme is closer than all WLS,
    // 5.2e-4 vs 1.7e-3 for WLS-6); WLS-2 is worse than the
    // standard scheme for k delta >= 1 (m = 6) and >= 2 (m = 3).
    check(err["WLS-2"][{3, 0.5}] < err["standard"][{3, 0.5}] &&
            err["WLS-2"][{6, 0.5}] < err["standard"][{6, 0.5}],
          "k delta = 0.5: WLS-2 closer to the continuum than the standard scheme (m = 3, 6)");
    for (const double kd : {0.5, 1., 2.})
      check(err["WLS-4"][{6, kd}] < err["standard"][{6, kd}],
            "m = 6, k delta = " + std::to_string(kd) + ": WLS-4 closer than standard");
    for (const double kd : {0.5, 1., 2.})
      check(err["WLS-6"][{6, kd}] < 0.5 * err["standard"][{6, kd}],
            "m = 6, k delta = " + std::to_string(kd) + ": WLS-6 at least 2x closer than standard");
    check(err["WLS-2"][{6, 2.}] > err["standard"][{6, 2.}],
          "m = 6, k delta = 2: WLS-2 farther than standard (short waves, reported)");
  }

  // Undamped energy of a 2D Gaussian pulse with a zero layer (d = 0):
  // bounded by the Verlet oscillation, for the standard scheme and WLS-2;
  // and the same numbers on any number of ranks (serial copy in-process).
  double
  wave_energy_run(const MPI_Comm comm, const std::string &q, std::vector<double> &energy)
  {
    LatticeParameters lp;
    lp.dx              = 0.05;
    lp.delta           = 3. * lp.dx;
    lp.layer_thickness = lp.delta;
    BoxDomain<2>      box(Point<2>(-1., -1.), Point<2>(1., 1.));
    Discretization<2> disc(comm);
    disc.setup(box, lp);
    ScalarWaveParameters wp;
    wp.quadrature = q;
    wp.time_step  = 1e-3;
    wp.time_step  = 0.5 * ScalarWaveSolver<2>(disc, wp).critical_time_step();
    ScalarWaveSolver<2> s(disc, wp);
    class Pulse : public Function<2>
    {
    public:
      double
      value(const Point<2> &p, const unsigned int = 0) const override
      {
        return std::exp(-(p - Point<2>(0.1, -0.05)).norm_square() / 0.0625);
      }
    } pulse;
    s.set_initial_values(pulse);
    s.initialize();
    energy.assign(1, s.energy());
    // To t = 3: the pulse reflects off the layer about twice.
    while (s.time() < 3.)
      {
        s.advance();
        energy.push_back(s.energy());
      }
    return s.time_step();
  }

  void
  wave_energy()
  {
    for (const std::string q : {"standard", "wls"})
      {
        std::vector<double> e, e_serial;
        const double        dt = wave_energy_run(MPI_COMM_WORLD, q, e);
        wave_energy_run(MPI_COMM_SELF, q, e_serial);
        double dev = 0., dev_first = 0., rank_diff = 0.;
        for (unsigned int n = 0; n < e.size(); ++n)
          {
            const double r = std::abs(e[n] - e[0]) / e[0];
            dev            = std::max(dev, r);
            if (n < e.size() / 4)
              dev_first = std::max(dev_first, r);
            rank_diff = std::max(rank_diff, std::abs(e[n] - e_serial[n]) / e[0]);
          }
        if (root())
          std::cout << "    " << q << ": dt = " << dt << ", " << e.size() - 1
                    << " steps, max |E - E0|/E0 = " << sci(dev) << " (first quarter "
                    << sci(dev_first) << "), end " << sci((e.back() - e[0]) / e[0]) << std::endl;
        // Standard scheme: the bond energy 1/4 sum w (u_j - u_i)^2 is not the
        // Verlet invariant (layer bonds count once), so it is only reported.
        // WLS: -1/2 u.M L u; Verlet at dt = dt_crit/2 oscillates by up to
        // (omega dt)^2/8 of the high-frequency content (measured 5.8e-3).
        if (q == "wls")
          {
            check(dev < 1e-2, q + ": undamped energy conserved to " + sci(dev));
            check(dev < 1.5 * dev_first, q + ": no drift (max deviation " + sci(dev) +
                                           " vs first quarter " + sci(dev_first) + ")");
          }
        check(rank_diff < 1e-12, q + ": energies equal to the serial run, max diff " +
                                   sci(rank_diff));
      }
  }

  // ------------------------------------------------------------------
  // Backward Euler with WLS rows: the manufactured solution (3.77)-(3.78)
  // (kappa = 1, q = 2, omega_0), Table 3.2 setting reduced to dx = 1/19.
  std::string
  e2_parameters(const std::string &scheme, const std::string &quadrature,
                const unsigned int order, const double dt, const double end)
  {
    std::ostringstream s;
    s.precision(17);
    s << "subsection Geometry\n set Domain = box\n set Lower corner = -0.5, -0.5\n"
         " set Upper corner = 0.5, 0.5\nend\n"
         "subsection Discretization\n set Grid spacing = "
      << 1. / 19. << "\n set Horizon factor = 5\n set Volume constraint layer = -1\nend\n"
      << "subsection Model\n set Micro-diffusivity = 1\n set Kernel exponent = 2\n"
         " set Constants = d = "
      << 5. / 19.
      << "\n set Initial condition = 0\n"
         " set Source = 5*cos(5*t)*(x^2*y^2 + x^3*y + x^4 + x*y^3 + y^4) - "
         "pi*d^2/16*sin(5*t)*(7*d^2 + 56*x^2 + 48*x*y + 56*y^2)\nend\n"
         "subsection Boundary conditions\n"
         " set Dirichlet value = sin(5*t)*(x^2*y^2 + x^3*y + x^4 + x*y^3 + y^4)\n"
         " set Exact solution = sin(5*t)*(x^2*y^2 + x^3*y + x^4 + x*y^3 + y^4)\nend\n"
         "subsection Time stepping\n set Scheme = "
      << scheme << "\n set Time step = " << dt << "\n set End time = " << end
      << "\nend\nsubsection Hybrid\n set Quadrature = " << quadrature
      << "\n subsection WLS\n  set Order = " << order << "\n end\nend\n"
         "subsection Output\n set Directory = be_wls_output\nend\n";
    return s.str();
  }

  struct E2Run
  {
    double       error = 0.;
    unsigned int max_newton = 0, min_newton = 1000;
  };

  E2Run
  e2_run(const MPI_Comm comm, const std::string &scheme, const std::string &quadrature,
         const unsigned int order, const double dt, const double end)
  {
    const auto p =
      parameters_from_text<DiffusionRunParameters<2>>(e2_parameters(scheme, quadrature, order, dt, end));
    DiffusionSolver<2> s(comm, p);
    s.setup();
    E2Run r;
    while (s.step() < s.n_steps())
      {
        s.advance();
        if (scheme == "backward Euler")
          {
            r.max_newton = std::max(r.max_newton, s.last_newton_iterations());
            r.min_newton = std::min(r.min_newton, s.last_newton_iterations());
          }
      }
    r.error = s.diagnostics().error;
    return r;
  }

  void
  be_diffusion()
  {
    const double dt = 2e-4, end = 0.06;
    std::map<std::string, E2Run> r;
    r["FE standard"] = e2_run(MPI_COMM_WORLD, "forward Euler", "standard", 2, dt, end);
    r["FE WLS-2"]    = e2_run(MPI_COMM_WORLD, "forward Euler", "wls", 2, dt, end);
    r["BE standard"] = e2_run(MPI_COMM_WORLD, "backward Euler", "standard", 2, dt, end);
    r["BE WLS-2"]    = e2_run(MPI_COMM_WORLD, "backward Euler", "wls", 2, dt, end);
    r["BE WLS-4"]    = e2_run(MPI_COMM_WORLD, "backward Euler", "wls", 4, dt, end);
    const E2Run serial = e2_run(MPI_COMM_SELF, "backward Euler", "wls", 2, dt, end);
    if (root())
      for (const auto &[name, v] : r)
        std::cout << "    " << name << ": relative l2 error (3.79) at t = " << end << ": "
                  << sci(v.error)
                  << (name[0] == 'B' ? ", Newton iterations per step " + std::to_string(v.min_newton) +
                                         ".." + std::to_string(v.max_newton) :
                                       std::string())
                  << std::endl;
    for (const std::string n : {"BE standard", "BE WLS-2", "BE WLS-4"})
      check(r[n].max_newton == 1 && r[n].min_newton == 1,
            n + ": Newton converges in one iteration every step (linear problem)");
    check_close(serial.error, r["BE WLS-2"].error, 1e-8, "BE WLS-2: same error on 1 rank");
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv, {{"lps_rows", lps_rows},
              {"lps_polynomial", lps_polynomial},
              {"lps_m_convergence", lps_m_convergence},
              {"wave_dispersion", wave_dispersion},
              {"wave_energy", wave_energy},
              {"be_diffusion", be_diffusion}});
}
