// Tests of the meshfree WLS collocation quadrature (dissertation Sect. 3.2):
// operator rows against closed forms and numerical quadrature, polynomial
// reproduction, bad input and rank independence. The verification examples
// E1 (1D static elasticity, Table 3.1) and E2 (2D transient diffusion,
// Table 3.2) are tutorial/step-9, run by tests.cmake with reduced parameters.

#include <deal.II/base/quadrature_lib.h>

#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/domain.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/diffusion.h>

#include <Eigen/Dense>

#include "check.h"

#include <cmath>
#include <iomanip>
#include <random>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  ScalarKernel
  make_kernel(const unsigned int dim, const InfluenceFunction omega, const double exponent,
              const double delta, const double constant = 1.)
  {
    ScalarKernel k;
    k.dim      = dim;
    k.omega    = omega;
    k.exponent = exponent;
    k.delta    = delta;
    k.constant = constant;
    return k;
  }

  // ---------------------------------------------------------------------
  // Operator rows: closed form = black-box quadrature; (3.66)-(3.67) and
  // (3.58)-(3.59); the weight function (3.26).
  template <int dim>
  void
  rows_against_quadrature(const unsigned int order)
  {
    const MonomialBasis<dim> basis(order);
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      for (const double q : {0., 1., 2., 0.5})
        {
          if (q >= dim + 1.)
            continue;
          const auto   k  = make_kernel(dim, omega, q, 1.7, 2.3);
          const auto   a  = scalar_operator_row<dim>(k, basis);
          const auto   n  = scalar_operator_row_numerical<dim>(k, basis);
          double       e = 0., s = 0.;
          for (unsigned int i = 0; i < a.size(); ++i)
            {
              e = std::max(e, std::abs(a[i] - n[i]));
              s = std::max(s, std::abs(a[i]));
            }
          check(e <= 1e-12 * s, std::to_string(dim) + "D order " + std::to_string(order) +
                                  ", " + to_string(omega) + ", exponent " + sci(q) +
                                  ": closed-form L = quadrature, max diff " + sci(e / s));
        }
  }

  void
  operator_rows()
  {
    rows_against_quadrature<1>(6);
    rows_against_quadrature<2>(4);
    rows_against_quadrature<3>(4);

    // (3.66)-(3.67): 3D, order 2, L_C = lambda_C (0,0,0,0,1,0,0,1,0,1).
    const MonomialBasis<3> b3(2);
    check(b3.size() == 10 && b3.exponents(5)[0] == 1 && b3.exponents(5)[1] == 1 &&
            b3.exponents(9)[2] == 2,
          "3D order 2 basis is (1,x,y,z,x^2,xy,xz,y^2,yz,z^2) of (3.23)");
    const double delta = 1.3, kappa = 0.7;
    for (const double q : {0., 1., 2.})
      for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
        {
          const double lambda =
            4. * M_PI * kappa * std::pow(delta, 5. - q) /
            (omega == InfluenceFunction::constant ? 15. - 3. * q : 3. * q * q - 33. * q + 90.);
          const auto   L = scalar_operator_row<3>(make_kernel(3, omega, q, delta, kappa), b3);
          const double pattern[10] = {0, 0, 0, 0, 1, 0, 0, 1, 0, 1};
          double       e           = 0.;
          for (unsigned int a = 0; a < 10; ++a)
            e = std::max(e, std::abs(L[a] - lambda * pattern[a]));
          check(e <= 1e-13 * lambda, "(3.67) lambda_C, q = " + sci(q) + ", " + to_string(omega) +
                                       ": max deviation " + sci(e / lambda));
        }

    // (3.58)-(3.59): bond-based 3D order 2, lambda = pi c delta^4 / 5 (25).
    const double c = 1.9;
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        const double lambda = M_PI * c * std::pow(delta, 4) /
                              (omega == InfluenceFunction::constant ? 5. : 25.);
        const auto L = bond_based_operator_rows<3>(c, omega, delta, b3);
        // Expected (3.58): [a][b][alpha] with x^2=4, xy=5, xz=6, y^2=7, yz=8, z^2=9.
        double expected[3][3][10] = {};
        const int sq[3] = {4, 7, 9};
        const int mixed[3][3] = {{-1, 5, 6}, {5, -1, 8}, {6, 8, -1}};
        for (int a = 0; a < 3; ++a)
          for (int s = 0; s < 3; ++s)
            expected[a][a][sq[s]] = (s == a ? 1. : 1. / 3.);
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            if (a != b)
              expected[a][b][mixed[a][b]] = 1. / 3.;
        double e = 0.;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            for (int al = 0; al < 10; ++al)
              e = std::max(e, std::abs(L[(a * 3 + b) * 10 + al] - lambda * expected[a][b][al]));
        check(e <= 1e-13 * lambda,
              "(3.58)-(3.59) bond-based rows, " + to_string(omega) + ": max deviation " +
                sci(e / lambda));
      }

    // 2D bond-based with c = 9E/(pi delta^3) (plane stress, nu = 1/3): the
    // local limit is Navier's operator, so u = (x^2, 0) gives
    // f_x = E/(1-nu^2) * 2 = 9E/4, u = (y^2, 0) gives 2 mu = 3E/4 and
    // u = (0, xy) gives f_x = lambda* + mu = 3E/4.
    {
      const double           E = 2.1, d2 = 0.8;
      const MonomialBasis<2> b2(2); // 1, x, y, x^2, xy, y^2
      const auto L = bond_based_operator_rows<2>(9. * E / (M_PI * std::pow(d2, 3)),
                                                 InfluenceFunction::constant, d2, b2);
      check_close(L[(0 * 2 + 0) * 6 + 3] * 1., 9. * E / 4., 1e-13, "2D bond-based: (x^2,0) -> f_x");
      check_close(L[(0 * 2 + 0) * 6 + 5] * 1., 3. * E / 4., 1e-13, "2D bond-based: (y^2,0) -> f_x");
      check_close(L[(0 * 2 + 1) * 6 + 4] * 1., 3. * E / 4., 1e-13, "2D bond-based: (0,xy) -> f_x");
    }

    // 1D elasticity c/|xi| with c = 2E/delta^2: L x^2 = 2E (local modulus E).
    {
      const double           d1 = 6., E = 1.;
      const MonomialBasis<1> b1(2);
      const auto L = scalar_operator_row<1>(
        make_kernel(1, InfluenceFunction::constant, 1., d1, 2. * E / (d1 * d1)), b1);
      check_close(L[2], 2. * E, 1e-14, "1D elasticity: L x^2 = 2E");
    }

    // (3.26): w(0) = 1, w(rbar) = (1 - e^48)/(1 - e^64) without overflow.
    check_close(wls_weight_function(0., 2.), 1., 1e-15, "weight (3.26) at r = 0");
    check_close(wls_weight_function(2., 2.), std::exp(-16.) * (1 - std::exp(-48.)) /
                                               (1 - std::exp(-64.)),
                1e-12, "weight (3.26) at r = rbar");
    check(std::abs(wls_weight_function(2., 2.) - 1.125e-7) < 1e-10,
          "weight (3.26) at r = rbar is 1.125e-7 (catalog)");
  }

  // ---------------------------------------------------------------------
  // Polynomial reproduction: on a uniform and a perturbed (<= 0.35 dx)
  // lattice, WLS-k applied to a polynomial of degree <= k equals the
  // continuous operator L applied to it, which is computed by the Taylor
  // expansion sum_alpha L_alpha d^alpha g / alpha! (the closed-form row, which
  // operator_rows checks against quadrature). Degree k + 2 is NOT reproduced
  // (the check can fail).
  template <int dim>
  std::vector<Point<dim>>
  lattice(const int n, const double dx, const double perturbation, const unsigned int seed)
  {
    std::mt19937                           gen(seed);
    std::uniform_real_distribution<double> u(0., 1.);
    std::vector<Point<dim>>                pts;
    const int                              n3 = dim == 3 ? n : 0, n2 = dim >= 2 ? n : 0;
    for (int k = -n3; k <= n3; ++k)
      for (int j = -n2; j <= n2; ++j)
        for (int i = -n; i <= n; ++i)
          {
            const std::array<int, 3> ijk{{i, j, k}};
            Point<dim>               p;
            for (int d = 0; d < dim; ++d)
              p[d] = ijk[d] * dx;
            if (perturbation > 0. && (i || j || k))
              {
                // Random direction (normalised Gaussian), radius uniform.
                std::normal_distribution<double> g;
                Tensor<1, dim>                   t;
                for (int d = 0; d < dim; ++d)
                  t[d] = g(gen);
                p += t / t.norm() * perturbation * dx * u(gen);
              }
            pts.push_back(p);
          }
    return pts;
  }

  // Returns max |WLS - exact| / max|exact| at the centre node for a random
  // polynomial of the given degree (coefficients of monomials around an
  // off-centre origin, so that all lower terms are present at x_i).
  template <int dim>
  double
  reproduction_error(const unsigned int order, const unsigned int degree, const double perturbation,
                     const unsigned int seed)
  {
    const double delta = 1., m = dim == 1 ? 10. : dim == 2 ? 6. : 4.;
    const double dx    = delta / m;
    const auto   pts   = lattice<dim>(int(m) + 1, dx, perturbation, seed);
    const unsigned int centre = (pts.size() - 1) / 2; // (0,...,0), unperturbed
    std::vector<std::uint64_t> fs;
    std::vector<std::int32_t>  f;
    build_node_families<dim>(pts, delta + 0.5 * dx, fs, f);
    const auto kernel = make_kernel(dim, InfluenceFunction::linear, 1., delta, 1.);
    WlsParameters prm;
    prm.order = order;
    WlsQuadrature<dim> wls(prm, kernel);
    wls.build(pts, fs, f, {centre});

    const MonomialBasis<dim> big(degree);
    std::mt19937             gen(seed + 7);
    std::uniform_real_distribution<double> u(-1., 1.);
    std::vector<double>      coef(big.size());
    for (auto &c : coef)
      c = u(gen);
    Point<dim> origin;
    for (int d = 0; d < dim; ++d)
      origin[d] = 0.3 + 0.1 * d;
    std::vector<double> p(big.size()), g(pts.size(), 0.);
    for (unsigned int j = 0; j < pts.size(); ++j)
      {
        big.evaluate(pts[j] - origin, 1., p.data());
        for (unsigned int a = 0; a < big.size(); ++a)
          g[j] += coef[a] * p[a];
      }
    // Exact L g at the centre: shift the polynomial to the centre by
    // re-expanding with the monomials of degree <= degree (least squares on
    // many points is exact for a polynomial of that degree).
    const auto         L = scalar_operator_row<dim>(kernel, big);
    const unsigned int N = big.size();
    Eigen::MatrixXd    M(3 * N, N);
    Eigen::VectorXd    rhs(3 * N);
    std::mt19937       gen2(seed + 11);
    for (unsigned int r = 0; r < 3 * N; ++r)
      {
        Tensor<1, dim> x;
        for (int d = 0; d < dim; ++d)
          x[d] = u(gen2);
        big.evaluate(x, 1., p.data());
        for (unsigned int a = 0; a < N; ++a)
          M(r, a) = p[a];
        std::vector<double> q(N);
        big.evaluate(Point<dim>() + x - origin, 1., q.data());
        rhs(r) = 0.;
        for (unsigned int a = 0; a < N; ++a)
          rhs(r) += coef[a] * q[a];
      }
    const Eigen::VectorXd local = M.colPivHouseholderQr().solve(rhs);
    double                exact = 0.;
    for (unsigned int a = 0; a < N; ++a)
      exact += L[a] * local(a);
    std::vector<double> out(pts.size(), 0.);
    wls.apply(g.data(), out.data());
    double scale = 0.;
    for (unsigned int a = 0; a < N; ++a)
      scale += std::abs(L[a] * local(a));
    return std::abs(out[centre] - exact) / scale;
  }

  template <int dim>
  void
  reproduction(const std::vector<unsigned int> &orders)
  {
    for (const unsigned int k : orders)
      for (const double pert : {0., 0.35})
        {
          double e = 0.;
          for (unsigned int deg = 2; deg <= k; ++deg)
            e = std::max(e, reproduction_error<dim>(k, deg, pert, 3 + deg));
          check(e < 1e-10, std::to_string(dim) + "D WLS-" + std::to_string(k) +
                             (pert > 0 ? " perturbed" : " uniform") +
                             ": degree <= k reproduced, rel. error " + sci(e));
          const double e2 = reproduction_error<dim>(k, k + 2, pert, 5);
          check(e2 > 1e-6, std::to_string(dim) + "D WLS-" + std::to_string(k) +
                             ": degree k+2 not reproduced (rel. error " + sci(e2) + ")");
        }
  }

  void
  polynomial_reproduction()
  {
    reproduction<1>({2, 4, 6});
    reproduction<2>({2, 4});
    reproduction<3>({2});
  }

  // The bond-based vector weights reproduce the vector operator on
  // quadratic/quartic displacement fields in 2D (against the Navier values
  // of operator_rows for quadratics): u = (x^2 + 0.5 y^2, x y) at any node
  // gives f = (9E/4 + 0.5 * 3E/4 + 3E/4, ...) with the rows above.
  void
  bond_based_reproduction()
  {
    const double E = 1., delta = 1., dx = delta / 6.;
    const double c = 9. * E / (M_PI * std::pow(delta, 3));
    for (const unsigned int order : {2u, 4u})
      for (const double pert : {0., 0.35})
        {
          const auto                 pts = lattice<2>(7, dx, pert, 17);
          const unsigned int         centre = (pts.size() - 1) / 2;
          std::vector<std::uint64_t> fs;
          std::vector<std::int32_t>  f;
          build_node_families<2>(pts, delta + 0.5 * dx, fs, f);
          WlsParameters prm;
          prm.order = order;
          WlsQuadrature<2> wls(prm, c, InfluenceFunction::constant, delta);
          wls.build(pts, fs, f, {centre});
          std::vector<double> u(2 * pts.size()), out(2 * pts.size(), 0.);
          for (unsigned int j = 0; j < pts.size(); ++j)
            {
              const double x = pts[j][0] - 0.2, y = pts[j][1] + 0.1;
              u[2 * j]     = x * x + 0.5 * y * y + (order == 4 ? x * x * x * y : 0.);
              u[2 * j + 1] = x * y + (order == 4 ? y * y * y * y : 0.);
            }
          wls.apply_vector(u.data(), out.data());
          // Navier, plane stress nu = 1/3: f = (lambda*+2mu) grad div u ... written
          // out with the rows: f_x = 9E/4 u_xx/2*2 ... use the moments directly.
          // u_x = x^2 + y^2/2 (+ x^3 y), u_y = x y (+ y^4); at the centre
          // x = -0.2, y = 0.1. Second derivatives: u_x,xx = 2 (+6xy), u_x,yy = 1,
          // u_x,xy = 0 (+3x^2); u_y,xy = 1, u_y,xx = 0, u_y,yy = 0 (+12 y^2).
          // Quartic terms: the 4th-order moments add c int n^4 r^3/r ...; we
          // compare against the continuous operator computed from the rows.
          const MonomialBasis<2> b4(4);
          const auto L = bond_based_operator_rows<2>(c, InfluenceFunction::constant, delta, b4);
          // Taylor coefficients at the centre (x0, y0) = (-0.2, 0.1) in b4 order
          // (1,x,y,x^2,xy,y^2,x^3,x^2y,xy^2,y^3,x^4,x^3y,x^2y^2,xy^3,y^4).
          const double x0 = -0.2, y0 = 0.1;
          double       ux[15] = {}, uy[15] = {};
          ux[3] = 1.;  // x^2
          ux[5] = 0.5; // y^2/2
          uy[4] = 1.;  // xy
          if (order == 4)
            {
              // x^3 y around x0,y0: terms of degree >= 2 in (dx, dy).
              ux[3] += 3. * x0 * y0;      // 3 x0 y0 dx^2
              ux[4] += 3. * x0 * x0;      // 3 x0^2 dx dy
              ux[6] += y0;                // y0 dx^3
              ux[7] += 3. * x0;           // 3 x0 dx^2 dy
              ux[11] += 1.;               // dx^3 dy
              uy[5] += 6. * y0 * y0;      // 6 y0^2 dy^2
              uy[9] += 4. * y0;           // 4 y0 dy^3
              uy[14] += 1.;               // dy^4
            }
          double force[2] = {0., 0.};
          for (unsigned int a = 0; a < 2; ++a)
            for (unsigned int al = 0; al < 15; ++al)
              force[a] += L[(a * 2 + 0) * 15 + al] * ux[al] + L[(a * 2 + 1) * 15 + al] * uy[al];
          if (order == 2)
            {
              check_close(force[0], 9. * E / 4. + 0.5 * 3. * E / 4. + 3. * E / 4., 1e-13,
                          "Navier value of f_x for the quadratic field");
              check_close(force[1], 0., 0., "Navier value of f_y for the quadratic field", 1e-13);
            }
          const double e = std::max(std::abs(out[2 * centre] - force[0]),
                                    std::abs(out[2 * centre + 1] - force[1]));
          check(e < 1e-10 * (std::abs(force[0]) + std::abs(force[1])),
                "2D bond-based WLS-" + std::to_string(order) +
                  (pert > 0 ? " perturbed" : " uniform") + ": vector field reproduced, error " +
                  sci(e));
          const auto cr = wls.condition_range();
          if (root())
            std::cout << "    cond(A_i) = " << sci(cr.first) << "\n";
        }
  }

  // ---------------------------------------------------------------------
  void
  bad_input()
  {
    auto throws = [](const std::function<void()> &f, const std::string &what,
                     const std::string &parameter) {
      try
        {
          f();
        }
      catch (const ParameterError &e)
        {
          check(e.parameter == parameter, what + ": ParameterError for '" + parameter +
                                            "': " + e.what());
          return;
        }
      catch (...)
        {
        }
      check(false, what + ": no ParameterError");
    };
    const auto k1 = make_kernel(1, InfluenceFunction::constant, 1., 6.);
    const auto k2 = make_kernel(2, InfluenceFunction::constant, 2., 1.);
    WlsParameters p;
    p.order = 3;
    throws([&] { WlsQuadrature<1> w(p, k1); }, "order 3 in 1D", "WLS/Order");
    p.order = 6;
    throws([&] { WlsQuadrature<2> w(p, k2); }, "order 6 in 2D", "WLS/Order");
    p.order         = 4;
    p.n_collocation = 10;
    throws([&] { WlsQuadrature<2> w(p, k2); }, "n_c = 10 < n_p = 15", "WLS/Number of collocation nodes");
    // 1D delta = 6, dx = 3 (m = 2): 5 family nodes, WLS-4 needs 11.
    p.n_collocation = 0;
    {
      std::vector<Point<1>> pts;
      for (int i = -4; i <= 4; ++i)
        pts.emplace_back(3. * i);
      std::vector<std::uint64_t> fs;
      std::vector<std::int32_t>  f;
      build_node_families<1>(pts, 6., fs, f);
      WlsQuadrature<1> w(p, k1);
      throws([&] { w.build(pts, fs, f, {4}); }, "WLS-4 with 5 nodes in the horizon",
             "WLS/Number of collocation nodes");
    }
    // Collinear nodes in 2D: A_i is singular for any order.
    {
      std::vector<Point<2>> pts;
      for (int i = -40; i <= 40; ++i)
        pts.emplace_back(0.02 * i, 0.);
      std::vector<std::uint64_t> fs;
      std::vector<std::int32_t>  f;
      build_node_families<2>(pts, 1., fs, f);
      p.order = 2;
      WlsQuadrature<2> w(p, k2);
      throws([&] { w.build(pts, fs, f, {40}); }, "collinear cloud (singular A_i)",
             "WLS/Number of collocation nodes");
    }
    throws([] { scalar_operator_row<2>(make_kernel(2, InfluenceFunction::constant, 4.5, 1.),
                                       MonomialBasis<2>(2)); },
           "kernel exponent 4.5 in 2D (divergent moment)", "Kernel exponent");
  }

  // ---------------------------------------------------------------------
  // The weights built on a distributed Discretization equal (node by node,
  // keyed by id) those of a serial one: same collocation ids, weights to
  // round-off. And WLS-4 applied to a quartic is the exact operator.
  void
  rank_invariance()
  {
    LatticeParameters lp;
    lp.dx              = 0.05;
    lp.delta           = 0.2;
    lp.layer_thickness = lp.delta;
    BoxDomain<2> box(Point<2>(-0.5, -0.4), Point<2>(0.5, 0.4));
    Discretization<2> dist(MPI_COMM_WORLD), serial(MPI_COMM_SELF);
    dist.setup(box, lp);
    serial.setup(box, lp);
    const auto    kernel = make_kernel(2, InfluenceFunction::constant, 2., lp.delta);
    WlsParameters prm;
    prm.order = 4;
    WlsQuadrature<2> wd(prm, kernel), ws(prm, kernel);
    wd.build(dist);
    ws.build(serial);
    std::map<types::particle_index, unsigned int> serial_row;
    for (unsigned int k = 0; k < ws.node.size(); ++k)
      serial_row[serial.id[ws.node[k]]] = k;
    double       max_diff = 0.;
    unsigned int id_mismatch = 0, missing = 0;
    for (unsigned int k = 0; k < wd.node.size(); ++k)
      {
        const auto it = serial_row.find(dist.id[wd.node[k]]);
        if (it == serial_row.end())
          {
            ++missing;
            continue;
          }
        const unsigned int s = it->second;
        for (unsigned int c = 0; c < wd.n_collocation(); ++c)
          {
            id_mismatch += dist.id[wd.col[wd.row_start[k] + c]] != serial.id[ws.col[ws.row_start[s] + c]];
            max_diff = std::max(max_diff, std::abs(wd.weight[wd.row_start[k] + c] -
                                                   ws.weight[ws.row_start[s] + c]));
          }
      }
    const auto n_rows = Utilities::MPI::sum(wd.node.size(), MPI_COMM_WORLD);
    id_mismatch = Utilities::MPI::sum(id_mismatch + missing, MPI_COMM_WORLD);
    max_diff    = Utilities::MPI::max(max_diff, MPI_COMM_WORLD);
    check(n_rows == ws.node.size(), "rows: " + std::to_string(n_rows) + " distributed = " +
                                      std::to_string(ws.node.size()) + " serial");
    check(id_mismatch == 0, "collocation node ids identical to the serial build");
    check(max_diff < 1e-12, "weights equal to the serial ones, max diff " + sci(max_diff));

    // WLS-4 on g = x^4 + x^2 y^2 + y^3: L g = exact (continuous) value
    // 12 x^2 * (pi d^2/4)/... computed from the closed-form row.
    const MonomialBasis<2> b(4);
    const auto             L = scalar_operator_row<2>(kernel, b);
    PeriDEAL::Vector       g, out;
    dist.initialize_vector(g);
    dist.initialize_vector(out);
    for (unsigned int i = 0; i < dist.n_owned() + dist.n_ghost(); ++i)
      {
        const double x = dist.position[i][0], y = dist.position[i][1];
        g.local_element(i) = x * x * x * x + x * x * y * y + y * y * y;
      }
    wd.apply(g, out);
    double err = 0., scale = 0.;
    for (const unsigned int i : wd.node)
      {
        const double x = dist.position[i][0], y = dist.position[i][1];
        // Taylor coefficients (degree 2..4) in b's order (x^2=3, xy=4, y^2=5, x^3=6,
        // x^2y=7, xy^2=8, y^3=9, x^4=10, x^2y^2=12): only even moments survive.
        const double exact = L[3] * (6. * x * x + y * y) + L[5] * (x * x + 3. * y) +
                             L[10] * 1. + L[12] * 1.;
        err   = std::max(err, std::abs(out.local_element(i) - exact));
        scale = std::max(scale, std::abs(exact));
      }
    err   = Utilities::MPI::max(err, MPI_COMM_WORLD);
    scale = Utilities::MPI::max(scale, MPI_COMM_WORLD);
    check(err < 1e-10 * scale, "WLS-4 on a quartic = continuous operator, rel. error " +
                                 sci(err / scale));
    const auto cr = wd.condition_range();
    const double cmin = Utilities::MPI::min(cr.first, MPI_COMM_WORLD),
                 cmax = Utilities::MPI::max(cr.second, MPI_COMM_WORLD);
    check(cmax < 1e8, "cond(A_i) in [" + sci(cmin) + ", " + sci(cmax) + "]");
  }

} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"operator_rows", operator_rows},
              {"polynomial_reproduction", polynomial_reproduction},
              {"bond_based_reproduction", bond_based_reproduction},
              {"bad_input", bad_input},
              {"rank_invariance", rank_invariance}});
}
