#include <deal.II/base/mpi.h>
#include <deal.II/base/quadrature_lib.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/wls_quadrature.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace PeriDEAL
{
  namespace
  {
    std::string
    point_string(const double *x, const int dim)
    {
      std::ostringstream s;
      s.precision(8);
      s << "(";
      for (int d = 0; d < dim; ++d)
        s << (d ? ", " : "") << x[d];
      s << ")";
      return s.str();
    }

    // Allowed orders and the auxiliary radii r_a whose lattice balls hold the
    // collocation counts of Tables 3.1/3.2 (1D: 5/11/13, 2D: 29/49, 3D: 123;
    // 3D order 4 uses r_a = 4, 257 points, not in the source).
    unsigned int
    default_auxiliary_radius(const int dim, const unsigned int order)
    {
      if (dim == 1)
        return order == 2 ? 2 : order == 4 ? 5 : 6;
      return order == 2 ? 3 : 4;
    }

    bool
    order_supported(const int dim, const unsigned int order)
    {
      if (dim == 1)
        return order == 2 || order == 4 || order == 6;
      return order == 2 || order == 4;
    }
  } // namespace

  // ---------------------------------------------------------------- basis
  template <int dim>
  MonomialBasis<dim>::MonomialBasis(const unsigned int order)
    : degree(order)
  {
    for (unsigned int k = 0; k <= order; ++k)
      {
        // All exponent tuples of total degree k, first exponent descending.
        std::array<unsigned int, dim> e{};
        std::vector<std::array<unsigned int, dim>> level;
        if constexpr (dim == 1)
          {
            e[0] = k;
            level.push_back(e);
          }
        else if constexpr (dim == 2)
          for (int a = k; a >= 0; --a)
            {
              e[0] = a;
              e[1] = k - a;
              level.push_back(e);
            }
        else
          for (int a = k; a >= 0; --a)
            for (int b = k - a; b >= 0; --b)
              {
                e[0] = a;
                e[1] = b;
                e[2] = k - a - b;
                level.push_back(e);
              }
        exponent.insert(exponent.end(), level.begin(), level.end());
      }
  }

  template <int dim>
  unsigned int
  MonomialBasis<dim>::degree_of(const unsigned int a) const
  {
    unsigned int s = 0;
    for (int d = 0; d < dim; ++d)
      s += exponent[a][d];
    return s;
  }

  template <int dim>
  void
  MonomialBasis<dim>::evaluate(const Tensor<1, dim> &xi, const double scale, double *values) const
  {
    // Powers of each coordinate, then products.
    std::array<std::array<double, 16>, dim> pw;
    for (int d = 0; d < dim; ++d)
      {
        pw[d][0] = 1.;
        for (unsigned int k = 1; k <= degree; ++k)
          pw[d][k] = pw[d][k - 1] * xi[d] / scale;
      }
    for (unsigned int a = 0; a < exponent.size(); ++a)
      {
        double v = 1.;
        for (int d = 0; d < dim; ++d)
          v *= pw[d][exponent[a][d]];
        values[a] = v;
      }
  }

  // ------------------------------------------------------- operator rows
  template <int dim>
  double
  sphere_monomial_integral(const std::array<unsigned int, dim> &alpha)
  {
    double sum_b = 0., log_prod = 0.;
    for (int d = 0; d < dim; ++d)
      {
        if (alpha[d] % 2 == 1)
          return 0.;
        const double b = (alpha[d] + 1.) / 2.;
        sum_b += b;
        log_prod += std::lgamma(b);
      }
    return 2. * std::exp(log_prod - std::lgamma(sum_b));
  }

  double
  radial_power_integral(const InfluenceFunction omega, const double delta, const double s)
  {
    check_parameter(s > -1., "Kernel exponent", s,
                    "a kernel whose radial moments int omega r^s dr exist: the power "
                    "s = degree - exponent + dim - 1 (the value shown) must exceed -1");
    const double p = std::pow(delta, s + 1.);
    return omega == InfluenceFunction::constant ? p / (s + 1.) : p / ((s + 1.) * (s + 2.));
  }

  template <int dim>
  std::vector<double>
  scalar_operator_row(const ScalarKernel &kernel, const MonomialBasis<dim> &basis)
  {
    check_parameter(kernel.dim == dim, "Kernel dimension", kernel.dim,
                    "the space dimension " + std::to_string(dim));
    std::vector<double> row(basis.size(), 0.);
    // a = 0 is the constant: p(xi) - p(0) = 0.
    for (unsigned int a = 1; a < basis.size(); ++a)
      {
        const double ang = sphere_monomial_integral<dim>(basis.exponents(a));
        if (ang != 0.)
          row[a] = kernel.constant * ang *
                   radial_power_integral(kernel.omega, kernel.delta,
                                         basis.degree_of(a) - kernel.exponent + dim - 1.);
      }
    return row;
  }

  namespace
  {
    // Gauss points of the radial interval (0, delta], geometrically graded
    // towards 0 so that integrable singularities r^s, s > -1, are resolved.
    std::vector<std::pair<double, double>>
    radial_rule(const double delta)
    {
      const QGauss<1>                       q(16);
      std::vector<std::pair<double, double>> rule;
      double                                b = delta;
      for (unsigned int j = 0; j < 80; ++j)
        {
          const double a = (j == 79 ? 0. : 0.5 * b);
          for (unsigned int i = 0; i < q.size(); ++i)
            rule.emplace_back(a + (b - a) * q.point(i)[0], (b - a) * q.weight(i));
          b = a;
        }
      return rule;
    }

    // Unit vectors and weights of an angular rule on S^{dim-1}, exact for
    // polynomials of degree < 32.
    template <int dim>
    std::vector<std::pair<Tensor<1, dim>, double>>
    angular_rule()
    {
      std::vector<std::pair<Tensor<1, dim>, double>> rule;
      const unsigned int                           n_theta = 64;
      if (dim == 1)
        for (const double s : {-1., 1.})
          {
            Tensor<1, dim> n;
            n[0] = s;
            rule.emplace_back(n, 1.);
          }
      else
        {
          const QGauss<1> qz(20);
          for (unsigned int t = 0; t < n_theta; ++t)
            {
              const double theta = 2. * M_PI * (t + 0.5) / n_theta;
              if (dim == 2)
                {
                  Tensor<1, dim> n;
                  n[0] = std::cos(theta);
                  n[1] = std::sin(theta);
                  rule.emplace_back(n, 2. * M_PI / n_theta);
                }
              else
                for (unsigned int i = 0; i < qz.size(); ++i)
                  {
                    const double   z = 2. * qz.point(i)[0] - 1., s = std::sqrt(1. - z * z);
                    Tensor<1, dim> n;
                    n[0]       = s * std::cos(theta);
                    n[1]       = s * std::sin(theta);
                    n[dim - 1] = z;
                    rule.emplace_back(n, 2. * qz.weight(i) * 2. * M_PI / n_theta);
                  }
            }
        }
      return rule;
    }
  } // namespace

  template <int dim>
  std::vector<double>
  scalar_operator_row_numerical(const ScalarKernel &kernel, const MonomialBasis<dim> &basis)
  {
    std::vector<double> row(basis.size(), 0.), p(basis.size()), p0(basis.size());
    basis.evaluate(Tensor<1, dim>(), 1., p0.data());
    const auto radial  = radial_rule(kernel.delta);
    const auto angular = angular_rule<dim>();
    for (const auto &[r, wr] : radial)
      {
        const double k = kernel(r) * std::pow(r, dim - 1.) * wr;
        for (const auto &[n, wa] : angular)
          {
            basis.evaluate(r * n, 1., p.data());
            for (unsigned int a = 0; a < basis.size(); ++a)
              row[a] += k * wa * (p[a] - p0[a]);
          }
      }
    return row;
  }

  template <int dim>
  std::vector<double>
  bond_based_operator_rows(const double              micromodulus,
                           const InfluenceFunction   omega,
                           const double              delta,
                           const MonomialBasis<dim> &basis)
  {
    // c omega xi_a xi_b / r^3: the pair tensor with s = 3.
    return pair_tensor_operator_rows(micromodulus, omega, delta, 3., basis);
  }

  template <int dim>
  std::vector<double>
  vector_operator_rows(const double              constant,
                       const InfluenceFunction   omega,
                       const double              delta,
                       const MonomialBasis<dim> &basis)
  {
    const unsigned int  np = basis.size();
    std::vector<double> rows(dim * np, 0.);
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int al = 1; al < np; ++al)
        {
          // omega xi_a xi^alpha: radial power |alpha| + 1 + dim - 1.
          auto e = basis.exponents(al);
          ++e[a];
          const double ang = sphere_monomial_integral<dim>(e);
          if (ang != 0.)
            rows[a * np + al] =
              constant * ang * radial_power_integral(omega, delta, basis.degree_of(al) + dim);
        }
    return rows;
  }

  template <int dim>
  std::vector<double>
  pair_tensor_operator_rows(const double              constant,
                            const InfluenceFunction   omega,
                            const double              delta,
                            const double              s,
                            const MonomialBasis<dim> &basis)
  {
    const unsigned int  np = basis.size();
    std::vector<double> rows(dim * dim * np, 0.);
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int b = 0; b < dim; ++b)
        for (unsigned int al = 1; al < np; ++al)
          {
            // omega xi_a xi_b / r^s xi^alpha: radial power |alpha| + 2 - s + dim - 1.
            auto e = basis.exponents(al);
            ++e[a];
            ++e[b];
            const double ang = sphere_monomial_integral<dim>(e);
            if (ang != 0.)
              rows[(a * dim + b) * np + al] =
                constant * ang *
                radial_power_integral(omega, delta, basis.degree_of(al) + 1. - s + dim);
          }
    return rows;
  }

  template <int dim>
  double
  lps_weighted_volume(const InfluenceFunction omega, const double delta)
  {
    return sphere_monomial_integral<dim>(std::array<unsigned int, dim>{}) *
           radial_power_integral(omega, delta, dim + 1.);
  }

  template <int dim>
  std::vector<double>
  lps_deviatoric_moment_matrix(const InfluenceFunction   omega,
                               const double              delta,
                               const MonomialBasis<dim> &basis)
  {
    const unsigned int np = basis.size(), n = dim * np;
    const auto         theta_row =
      vector_operator_rows<dim>(dim / lps_weighted_volume<dim>(omega, delta), omega, delta, basis);
    std::vector<double> M(n * n, 0.), p(np), p0(np), phi(n);
    basis.evaluate(Tensor<1, dim>(), 1., p0.data());
    // The integrand is a polynomial in r of degree <= 2 order + dim + 2:
    // Gauss on [0, delta] is exact.
    const QGauss<1> qr(basis.order() + dim / 2 + 3);
    for (unsigned int q = 0; q < qr.size(); ++q)
      {
        const double r = delta * qr.point(q)[0], wr = delta * qr.weight(q);
        const double w = influence(omega, r, delta) * std::pow(r, dim - 1.) * wr;
        for (const auto &[nv, wa] : angular_rule<dim>())
          {
            basis.evaluate(r * nv, 1., p.data());
            for (unsigned int a = 0; a < dim; ++a)
              for (unsigned int al = 0; al < np; ++al)
                phi[a * np + al] = nv[a] * (p[al] - p0[al]) - r * theta_row[a * np + al] / dim;
            for (unsigned int x = 0; x < n; ++x)
              for (unsigned int y = 0; y < n; ++y)
                M[x * n + y] += w * wa * phi[x] * phi[y];
          }
      }
    return M;
  }

  double
  wls_weight_function(const double r, const double r_bar)
  {
    const double e64 = std::exp(-64.);
    return (std::exp(-16. * r * r / (r_bar * r_bar)) - e64) / (1. - e64);
  }

  // ----------------------------------------------------------- parameters
  void
  WlsParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Order", "2", Patterns::Integer(2, 6),
                      "Order k of the complete monomial basis: 2, 4, 6 in 1D; 2, 4 in 2D/3D.");
    prm.declare_entry("Number of collocation nodes", "0", Patterns::Integer(0),
                      "n_c; 0: 5/11/13 (1D), 29/49 (2D), 123/257 (3D) for order 2/4/6.");
  }

  void
  WlsParameters::parse_parameters(ParameterHandler &prm)
  {
    order         = prm.get_integer("Order");
    n_collocation = prm.get_integer("Number of collocation nodes");
  }

  // ------------------------------------------------------- the quadrature
  template <int dim>
  WlsQuadrature<dim>::WlsQuadrature(const WlsParameters &parameters_in, const ScalarKernel &kernel)
    : parameters(parameters_in)
    , basis(order_supported(dim, parameters_in.order) ? parameters_in.order : 2)
    , components(1)
    , delta(kernel.delta)
  {
    init_auxiliary_grid();
    op_row = scalar_operator_row<dim>(kernel, basis);
    shapes = {{1u, 1u}};
  }

  template <int dim>
  WlsQuadrature<dim>::WlsQuadrature(const WlsParameters    &parameters_in,
                                    const double            micromodulus,
                                    const InfluenceFunction omega,
                                    const double            delta_in)
    : parameters(parameters_in)
    , basis(order_supported(dim, parameters_in.order) ? parameters_in.order : 2)
    , components(dim)
    , delta(delta_in)
  {
    init_auxiliary_grid();
    op_row = bond_based_operator_rows<dim>(micromodulus, omega, delta, basis);
    shapes = {{dim, dim}};
  }

  template <int dim>
  WlsQuadrature<dim>::WlsQuadrature(const WlsParameters            &parameters_in,
                                    const double                    delta_in,
                                    const std::vector<WlsOperator> &operators)
    : parameters(parameters_in)
    , basis(order_supported(dim, parameters_in.order) ? parameters_in.order : 2)
    , components(operators.empty() ? 1 : operators[0].n_out)
    , delta(delta_in)
  {
    init_auxiliary_grid();
    AssertThrow(!operators.empty(), ExcMessage("WlsQuadrature: no operator given"));
    for (unsigned int k = 0; k < operators.size(); ++k)
      {
        const auto &o = operators[k];
        AssertThrow(o.n_out > 0 && o.n_in > 0 &&
                      o.rows.size() == std::size_t(o.n_out) * o.n_in * basis.size(),
                    ExcMessage("WlsOperator " + std::to_string(k) + ": rows must hold n_out x "
                               "n_in x n_p = " + std::to_string(o.n_out * o.n_in * basis.size()) +
                               " entries (the basis of the given WLS order)"));
        shapes.emplace_back(o.n_out, o.n_in);
        if (k == 0)
          op_row = o.rows;
        else
          extra_row.push_back(o.rows);
      }
    extra_weight.resize(extra_row.size());
  }

  template <int dim>
  void
  WlsQuadrature<dim>::init_auxiliary_grid()
  {
    check_parameter(order_supported(dim, parameters.order), "WLS/Order", parameters.order,
                    dim == 1 ? "2, 4 or 6 in 1D" : "2 or 4 in 2D and 3D");
    check_parameter(delta > 0., "Horizon", delta, "> 0");
    aux_radius = default_auxiliary_radius(dim, parameters.order);
    const auto count = [](const int ra) {
      unsigned int n = 0;
      for (int i = -ra; i <= ra; ++i)
        for (int j = (dim > 1 ? -ra : 0); j <= (dim > 1 ? ra : 0); ++j)
          for (int k = (dim > 2 ? -ra : 0); k <= (dim > 2 ? ra : 0); ++k)
            n += (i * i + j * j + k * k <= ra * ra);
      return n;
    };
    n_colloc = parameters.n_collocation ? parameters.n_collocation : count(aux_radius);
    check_parameter(n_colloc >= basis.size(), "WLS/Number of collocation nodes", n_colloc,
                    "at least n_p = " + std::to_string(basis.size()) +
                      " (the number of monomials) or 0 for the default");
    check_parameter(n_colloc <= 100000, "WLS/Number of collocation nodes", n_colloc, "<= 100000");
    // Smallest lattice ball holding n_c points (the default keeps r_a).
    if (parameters.n_collocation)
      {
        aux_radius = 1;
        while (count(aux_radius) < n_colloc)
          ++aux_radius;
      }
    const int                                    ra = aux_radius;
    std::vector<std::pair<int, Tensor<1, dim>>> pts;
    for (int i = -ra; i <= ra; ++i)
      for (int j = (dim > 1 ? -ra : 0); j <= (dim > 1 ? ra : 0); ++j)
        for (int k = (dim > 2 ? -ra : 0); k <= (dim > 2 ? ra : 0); ++k)
          if (i * i + j * j + k * k <= ra * ra)
            {
              const std::array<int, 3> ijk{{i, j, k}};
              Tensor<1, dim>           t;
              for (int d = 0; d < dim; ++d)
                t[d] = ijk[d];
              pts.emplace_back(i * i + j * j + k * k, t * (delta / ra));
            }
    // Nearest first; stable so that ties keep the (symmetric) loop order.
    std::stable_sort(pts.begin(), pts.end(),
                     [](const auto &a, const auto &b) { return a.first < b.first; });
    aux_offsets.clear();
    for (unsigned int n = 0; n < n_colloc; ++n)
      aux_offsets.push_back(pts[n].second);
  }

  template <int dim>
  void
  WlsQuadrature<dim>::build(const std::vector<Point<dim>>    &position,
                            const std::vector<std::uint64_t> &family_start,
                            const std::vector<std::int32_t>  &family,
                            const std::vector<unsigned int>  &rows)
  {
    const unsigned int np = basis.size(), nc = n_colloc;
    node = rows;
    row_start.assign(1, 0);
    col.clear();
    weight.clear();
    condition_number.clear();
    col.reserve(rows.size() * nc);
    weight.reserve(rows.size() * nc * shapes[0].first * shapes[0].second);
    for (unsigned int k = 1; k < shapes.size(); ++k)
      {
        extra_weight[k - 1].clear();
        extra_weight[k - 1].reserve(rows.size() * nc * shapes[k].first * shapes[k].second);
      }

    std::vector<unsigned int>  cand;
    std::vector<char>          used;
    std::vector<double>        p(np);
    std::vector<unsigned int>  chosen;
    Eigen::MatrixXd            A(np, np), B(np, nc);
    for (const unsigned int i : rows)
      {
        AssertIndexRange(i + 1, family_start.size());
        const Point<dim> &xi = position[i];
        cand.assign(1, i);
        for (auto b = family_start[i]; b < family_start[i + 1]; ++b)
          cand.push_back(family[b]);
        if (cand.size() < nc)
          throw ParameterError("WLS/Number of collocation nodes", std::to_string(nc),
                               "at most the number of nodes in the horizon of node " +
                                 point_string(&xi[0], dim) + " (" +
                                 std::to_string(cand.size()) +
                                 " including itself); lower the order or refine the grid");
        // Each auxiliary point takes the nearest unused family node; ties
        // are broken by distance to x_i, then by position, so the choice is
        // symmetric on lattices and rank independent.
        used.assign(cand.size(), 0);
        chosen.clear();
        for (const auto &offset : aux_offsets)
          {
            const Point<dim> target = xi + offset;
            int              best   = -1;
            double           best_d = 0.;
            for (unsigned int c = 0; c < cand.size(); ++c)
              if (!used[c])
                {
                  const double d = position[cand[c]].distance_square(target);
                  bool         better = best < 0 || d < best_d * (1. - 1e-12);
                  if (!better && d <= best_d * (1. + 1e-12))
                    {
                      // A tie: the node nearer x_i wins (keeps the set
                      // symmetric on a lattice), then the position.
                      const auto  &pa = position[cand[c]], &pb = position[cand[best]];
                      const double ra = pa.distance_square(xi), rb = pb.distance_square(xi);
                      if (ra < rb * (1. - 1e-12))
                        better = true;
                      else if (ra <= rb * (1. + 1e-12))
                        for (int k = 0; k < dim; ++k)
                          if (pa[k] != pb[k])
                            {
                              better = pa[k] < pb[k];
                              break;
                            }
                    }
                  if (better)
                    {
                      best   = c;
                      best_d = d;
                    }
                }
            used[best] = 1;
            chosen.push_back(cand[best]);
          }

        double r_bar = 0.;
        for (const unsigned int j : chosen)
          r_bar = std::max(r_bar, position[j].distance(xi));
        // (3.28)-(3.29) in the basis p(xi / rbar).
        A.setZero();
        for (unsigned int c = 0; c < nc; ++c)
          {
            const Tensor<1, dim> d = position[chosen[c]] - xi;
            basis.evaluate(d, r_bar, p.data());
            const double w = wls_weight_function(d.norm(), r_bar);
            for (unsigned int a = 0; a < np; ++a)
              {
                B(a, c) = w * p[a];
                for (unsigned int b = 0; b < np; ++b)
                  A(a, b) += w * p[a] * p[b];
              }
          }
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A);
        const auto &s = svd.singularValues();
        condition_number.push_back(s(np - 1) > 0. ? s(0) / s(np - 1)
                                                   : std::numeric_limits<double>::infinity());
        Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(A);
        cod.setThreshold(1e-13);
        if (cod.rank() < static_cast<Eigen::Index>(np))
          throw ParameterError("WLS/Number of collocation nodes", std::to_string(nc),
                               "enough non-degenerate collocation nodes for a regular moment "
                               "matrix A_i (rank " + std::to_string(cod.rank()) + " of n_p = " +
                                 std::to_string(np) + " at node " + point_string(&xi[0], dim) +
                                 ")");
        const Eigen::MatrixXd Q = cod.solve(B);

        // w = L Q with L in the scaled basis: L_a / rbar^{|a|}.
        std::vector<double> scale(np);
        for (unsigned int a = 0; a < np; ++a)
          scale[a] = std::pow(r_bar, -double(basis.degree_of(a)));
        for (unsigned int c = 0; c < nc; ++c)
          col.push_back(chosen[c]);
        for (unsigned int k = 0; k < shapes.size(); ++k)
          {
            const std::vector<double> &L   = k == 0 ? op_row : extra_row[k - 1];
            std::vector<double>       &out = k == 0 ? weight : extra_weight[k - 1];
            const unsigned int         nab = shapes[k].first * shapes[k].second;
            for (unsigned int c = 0; c < nc; ++c)
              for (unsigned int ab = 0; ab < nab; ++ab)
                {
                  double w = 0.;
                  for (unsigned int a = 0; a < np; ++a)
                    w += L[ab * np + a] * scale[a] * Q(a, c);
                  out.push_back(w);
                }
          }
        row_start.push_back(col.size());
      }
  }

  template <int dim>
  void
  WlsQuadrature<dim>::build(const Discretization<dim> &disc, std::vector<unsigned int> rows)
  {
    if (rows.empty())
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (disc.region[i] == Discretization<dim>::interior)
          rows.push_back(i);
    const auto &nb = disc.neighborhood;
    build(disc.position, nb.row_start, nb.col, rows);
  }

  template <int dim>
  std::pair<double, double>
  WlsQuadrature<dim>::condition_range() const
  {
    if (condition_number.empty())
      return {0., 0.};
    const auto mm = std::minmax_element(condition_number.begin(), condition_number.end());
    return {*mm.first, *mm.second};
  }

  template <int dim>
  void
  WlsQuadrature<dim>::apply(const double *u, double *out) const
  {
    Assert(components == 1, ExcMessage("apply() is for scalar operators"));
    for (unsigned int k = 0; k < node.size(); ++k)
      {
        double s = 0.;
        for (auto b = row_start[k]; b < row_start[k + 1]; ++b)
          s += weight[b] * u[col[b]];
        out[node[k]] = s;
      }
  }

  template <int dim>
  void
  WlsQuadrature<dim>::apply(const Vector &u, Vector &out) const
  {
    apply(u.begin(), out.begin());
  }

  template <int dim>
  void
  WlsQuadrature<dim>::apply_vector(const double *u, double *out) const
  {
    Assert(components == dim, ExcMessage("apply_vector() is for the bond-based operator"));
    for (unsigned int k = 0; k < node.size(); ++k)
      {
        std::array<double, dim> s{};
        for (auto b = row_start[k]; b < row_start[k + 1]; ++b)
          for (unsigned int a = 0; a < dim; ++a)
            for (unsigned int c = 0; c < dim; ++c)
              s[a] += weight[b * dim * dim + a * dim + c] * u[dim * col[b] + c];
        for (unsigned int a = 0; a < dim; ++a)
          out[dim * node[k] + a] = s[a];
      }
  }

  template <int dim>
  void
  build_node_families(const std::vector<Point<dim>> &position,
                      const double                   radius,
                      std::vector<std::uint64_t>    &family_start,
                      std::vector<std::int32_t>     &family)
  {
    // Bins of size radius: neighbours lie in the 3^dim surrounding bins.
    std::map<std::array<long, dim>, std::vector<unsigned int>> bins;
    auto key = [&](const Point<dim> &x) {
      std::array<long, dim> k;
      for (int d = 0; d < dim; ++d)
        k[d] = static_cast<long>(std::floor(x[d] / radius));
      return k;
    };
    for (unsigned int i = 0; i < position.size(); ++i)
      bins[key(position[i])].push_back(i);
    family_start.assign(1, 0);
    family.clear();
    const double r2 = radius * radius;
    for (unsigned int i = 0; i < position.size(); ++i)
      {
        const auto k0 = key(position[i]);
        for (int o = 0; o < static_cast<int>(std::pow(3, dim)); ++o)
          {
            auto k = k0;
            int  r = o;
            for (int d = 0; d < dim; ++d, r /= 3)
              k[d] += r % 3 - 1;
            const auto it = bins.find(k);
            if (it != bins.end())
              for (const unsigned int j : it->second)
                if (j != i && position[j].distance_square(position[i]) <= r2)
                  family.push_back(j);
          }
        family_start.push_back(family.size());
      }
  }

#define PERIDEAL_INSTANTIATE(dim)                                                              \
  template class MonomialBasis<dim>;                                                           \
  template class WlsQuadrature<dim>;                                                           \
  template double sphere_monomial_integral<dim>(const std::array<unsigned int, dim> &);        \
  template std::vector<double> scalar_operator_row<dim>(const ScalarKernel &,                  \
                                                        const MonomialBasis<dim> &);           \
  template std::vector<double> scalar_operator_row_numerical<dim>(const ScalarKernel &,        \
                                                                  const MonomialBasis<dim> &); \
  template std::vector<double> bond_based_operator_rows<dim>(                                  \
    const double, const InfluenceFunction, const double, const MonomialBasis<dim> &);          \
  template std::vector<double> vector_operator_rows<dim>(                                      \
    const double, const InfluenceFunction, const double, const MonomialBasis<dim> &);          \
  template std::vector<double> pair_tensor_operator_rows<dim>(                                 \
    const double, const InfluenceFunction, const double, const double,                         \
    const MonomialBasis<dim> &);                                                               \
  template double              lps_weighted_volume<dim>(const InfluenceFunction, const double); \
  template std::vector<double> lps_deviatoric_moment_matrix<dim>(                              \
    const InfluenceFunction, const double, const MonomialBasis<dim> &);                        \
  template void build_node_families<dim>(const std::vector<Point<dim>> &, const double,        \
                                         std::vector<std::uint64_t> &,                         \
                                         std::vector<std::int32_t> &);
  PERIDEAL_INSTANTIATE(1)
  PERIDEAL_INSTANTIATE(2)
  PERIDEAL_INSTANTIATE(3)
#undef PERIDEAL_INSTANTIATE
} // namespace PeriDEAL
