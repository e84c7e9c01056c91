#ifndef perideal_discretization_wls_quadrature_h
#define perideal_discretization_wls_quadrature_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * The complete monomial basis p(xi) of (3.22)-(3.23) up to total degree
   * @p order in dim variables: 1, x, y, x^2, xy, y^2, ... ordered by degree
   * and, within a degree, lexicographically with the first variable's
   * exponent descending (3D order 2 is exactly (1,x,y,z,x^2,xy,xz,y^2,yz,z^2)
   * of (3.23)).
   */
  template <int dim>
  class MonomialBasis
  {
  public:
    explicit MonomialBasis(const unsigned int order);

    /** n_p: 3/5/7 (1D, order 2/4/6), 6/15 (2D, 2/4), 10/35 (3D, 2/4). */
    unsigned int
    size() const
    {
      return exponent.size();
    }
    unsigned int
    order() const
    {
      return degree;
    }
    /** Exponents of monomial @p a. */
    const std::array<unsigned int, dim> &
    exponents(const unsigned int a) const
    {
      return exponent[a];
    }
    /** Total degree of monomial @p a. */
    unsigned int
    degree_of(const unsigned int a) const;
    /** values[a] = p_a(xi / scale). */
    void
    evaluate(const Tensor<1, dim> &xi, const double scale, double *values) const;

  private:
    unsigned int                               degree;
    std::vector<std::array<unsigned int, dim>> exponent;
  };

  /**
   * Integral of n^alpha = n_1^alpha_1 ... n_d^alpha_d over the unit sphere
   * S^{d-1} in closed form: 2 prod Gamma(b_i) / Gamma(sum b_i) with
   * b_i = (alpha_i + 1)/2 if all alpha_i are even, else 0 (in 1D the
   * "sphere" is {-1, 1}).
   */
  template <int dim>
  double
  sphere_monomial_integral(const std::array<unsigned int, dim> &alpha);

  /**
   * Closed form of int_0^delta omega(r) r^s dr (s > -1):
   * delta^{s+1}/(s+1) for omega_0, delta^{s+1}/((s+1)(s+2)) for omega_1.
   */
  double
  radial_power_integral(const InfluenceFunction omega, const double delta, const double s);

  /**
   * Row L of (3.64) for a scalar kernel k(r) = constant omega(r)/r^exponent,
   * L_a = int_{|xi|<=delta} k(|xi|) (p_a(xi) - p_a(0)) dV, over the FULL
   * ball, in closed form (radial_power_integral() times
   * sphere_monomial_integral()). For dim = 3, order 2 this is
   * lambda_C (0,0,0,0,1,0,0,1,0,1) of (3.66)-(3.67). Throws ParameterError
   * if a moment diverges (exponent too large for the basis).
   */
  template <int dim>
  std::vector<double>
  scalar_operator_row(const ScalarKernel &kernel, const MonomialBasis<dim> &basis);

  /**
   * The same row by numerical quadrature of the kernel as a black box
   * (kernel(r) evaluated at Gauss points of geometrically graded radial
   * intervals times Gauss/trapezoidal angular rules): works for any
   * ScalarKernel and checks scalar_operator_row() in the tests.
   */
  template <int dim>
  std::vector<double>
  scalar_operator_row_numerical(const ScalarKernel &kernel, const MonomialBasis<dim> &basis);

  /**
   * The rows of L-bar (3.54)-(3.56) of the linearized bond-based operator
   * L u = int c omega(|xi|) (xi (x) xi)/|xi|^3 (u(x+xi) - u(x)) dV:
   * entry [(a * dim + b) * n_p + alpha] is the coefficient with which the
   * monomial coefficient alpha of component b enters component a. For 3D,
   * order 2 this is (3.58) with lambda of (3.59).
   */
  template <int dim>
  std::vector<double>
  bond_based_operator_rows(const double              micromodulus,
                           const InfluenceFunction   omega,
                           const double              delta,
                           const MonomialBasis<dim> &basis);

  /**
   * Rows of the vector moment operator
   * c int omega(|xi|) xi_a (p_alpha(xi) - p_alpha(0)) dV over the full ball,
   * entry [a * n_p + alpha], in closed form. With c = d/m-bar it is the
   * linearized dilatation L_theta of (3.35)-(3.39) (input component a, one
   * output), with c = (d K_d - (d+2) G)/m-bar the operator L_I of
   * (3.43)-(3.45) (output component a, one input: the p(0) term of (3.44)
   * integrates to zero over the ball). m-bar = lps_weighted_volume().
   */
  template <int dim>
  std::vector<double>
  vector_operator_rows(const double              constant,
                       const InfluenceFunction   omega,
                       const double              delta,
                       const MonomialBasis<dim> &basis);

  /**
   * Rows of the pair-tensor operator
   * c int omega(|xi|) (xi (x) xi)/|xi|^s (u(x+xi) - u(x)) dV, entry
   * [(a * dim + b) * n_p + alpha] as in bond_based_operator_rows() (which is
   * s = 3, c the micromodulus). s = 2 with c = 2 d (d+2) G / m-bar is the
   * operator L_J of the linearized LPS model, (3.46)-(3.50).
   */
  template <int dim>
  std::vector<double>
  pair_tensor_operator_rows(const double              constant,
                            const InfluenceFunction   omega,
                            const double              delta,
                            const double              s,
                            const MonomialBasis<dim> &basis);

  /**
   * The continuum weighted volume m-bar = int_{|xi| <= delta} omega |xi|^2 dV
   * (2.15) in closed form.
   */
  template <int dim>
  double
  lps_weighted_volume(const InfluenceFunction omega, const double delta);

  /**
   * The n_p dim x n_p dim matrix M of the deviatoric LPS energy on the
   * fitted polynomial: with the coefficients c_(a alpha) of the fit
   * (component a, monomial alpha, unscaled basis), theta = L_theta c and
   * M = int omega phi phi^T dV, phi_(a alpha)(xi) = n_a (p_alpha(xi) -
   * p_alpha(0)) - |xi| (L_theta)_(a alpha) / d, so that
   * int omega (e - theta |xi|/d)^2 dV = c^T M c (index a * n_p + alpha).
   * By numerical quadrature (radial Gauss x angular rule, exact for these
   * polynomials up to round-off).
   */
  template <int dim>
  std::vector<double>
  lps_deviatoric_moment_matrix(const InfluenceFunction   omega,
                               const double              delta,
                               const MonomialBasis<dim> &basis);

  /**
   * A linear functional of the fitted polynomial for WlsQuadrature's
   * general constructor: n_out x n_in rows over the monomials,
   * rows[(a * n_in + b) * n_p + alpha] the coefficient with which monomial
   * alpha (unscaled basis p(xi)) of input component b enters output a. The
   * quadrature weights are then a block of n_out x n_in per collocation
   * node. Identity rows (n_out = n_p, n_in = 1, rows[alpha * n_p + beta] =
   * delta_alpha,beta) give the fit coefficients N of (3.31) themselves.
   */
  struct WlsOperator
  {
    unsigned int        n_out = 1;
    unsigned int        n_in  = 1;
    std::vector<double> rows;
  };

  /**
   * The WLS weight function (3.26), written without overflow as
   * (exp(-16 r^2/rbar^2) - exp(-64)) / (1 - exp(-64)).
   */
  double
  wls_weight_function(const double r, const double r_bar);

  /**
   * Parameters of the WLS collocation quadrature (dissertation Sect. 3.2):
   * order of the monomial basis and number of collocation nodes n_c
   * (0: the values of Tables 3.1/3.2, 5/11/13 in 1D for order 2/4/6, 29/49
   * in 2D for order 2/4, 123/257 in 3D for order 2/4).
   */
  struct WlsParameters
  {
    /** Order k of the complete monomial basis (C^k consistency). */
    unsigned int order = 2;
    /** Number of collocation nodes per node; 0: the default above. */
    unsigned int n_collocation = 0;

    /** Declare "Order" and "Number of collocation nodes". */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate them (the caller has entered the subsection). */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Meshfree WLS collocation quadrature weights (3.22)-(3.31), (3.60)-(3.67)
   * and (3.52)-(3.59).
   *
   * For each requested node i (the "WLS region"; other nodes may use the
   * standard scheme, which is what the hybrid schemes of Sect. 3.3/3.5 need):
   * 1. an auxiliary Cartesian grid of spacing delta/r_a centred at x_i is
   *    cut to its n_c points closest to x_i (for the default n_c these are
   *    exactly the lattice points of the ball of radius r_a: r_a = 2/5/6 in
   *    1D, 3/4 in 2D, 3/4 in 3D);
   * 2. each auxiliary point, nearest first, takes the nearest not yet used
   *    node of the family of i (x_i itself is the first);
   * 3. with the weights (3.26), A_i (3.28) and B_i (3.29) are formed in the
   *    basis p(xi / rbar) (scaled so that cond(A_i) does not grow like
   *    delta^{2k}) and Q_i = A_i^{-1} B_i is computed with a
   *    complete orthogonal decomposition (rank revealing);
   * 4. the quadrature weights are w_i = L Q_i, L the operator applied to each
   *    monomial over the full ball (scalar_operator_row() or
   *    bond_based_operator_rows()), so (L g)(x_i) ~ sum_j w_ij g_j with no
   *    partial volumes.
   *
   * The result is a CSR matrix: row k belongs to node node[k] and holds the
   * collocation nodes' local indices and weights (for the bond-based
   * operator a dim x dim block per collocation node, row-major). The spectral
   * condition number of (scaled) A_i is kept per row.
   */
  template <int dim>
  class WlsQuadrature
  {
  public:
    /** The scalar operator int kernel(|xi|) (g(x+xi) - g(x)) dV. */
    WlsQuadrature(const WlsParameters &parameters, const ScalarKernel &kernel);

    /** The linearized bond-based operator (3.52) with micromodulus c. */
    WlsQuadrature(const WlsParameters    &parameters,
                  const double            micromodulus,
                  const InfluenceFunction omega,
                  const double            delta);

    /**
     * Several general operators on the same collocation sets (one fit per
     * node, e.g. the dilatation, L_I and L_J of the linearized LPS model):
     * operator k has operators[k].n_out x operators[k].n_in weights per
     * collocation node, in weights(k); weights(0) is #weight.
     * n_components() is operators[0].n_out. @p delta is the horizon.
     */
    WlsQuadrature(const WlsParameters &parameters, const double delta,
                  const std::vector<WlsOperator> &operators);

    /**
     * Compute the weights of the nodes @p rows. position holds all nodes
     * (local numbering); family_start/family is a CSR list of candidate
     * neighbours (not including the node itself) indexed by node, as in
     * Neighborhood. Throws ParameterError if a family has fewer than n_c
     * nodes or A_i is rank deficient.
     */
    void
    build(const std::vector<Point<dim>>    &position,
          const std::vector<std::uint64_t> &family_start,
          const std::vector<std::int32_t>  &family,
          const std::vector<unsigned int>  &rows);

    /**
     * The same on a Discretization (families = its Neighborhood; ghost
     * nodes may be collocation nodes). Empty @p rows: all owned interior
     * (non-constrained) nodes.
     */
    void
    build(const Discretization<dim> &discretization, std::vector<unsigned int> rows = {});

    /** 1 for a scalar operator, dim for the bond-based one. */
    unsigned int
    n_components() const
    {
      return components;
    }
    /** n_p. */
    unsigned int
    n_basis() const
    {
      return basis.size();
    }
    /** n_c. */
    unsigned int
    n_collocation() const
    {
      return n_colloc;
    }
    /** Auxiliary radius r_a (auxiliary spacing delta / r_a). */
    unsigned int
    auxiliary_radius() const
    {
      return aux_radius;
    }
    /** The operator row L (scalar) or rows (bond-based), see above. */
    const std::vector<double> &
    operator_row() const
    {
      return op_row;
    }

    /** @name The CSR result */
    /** @{ */
    std::vector<unsigned int>  node;
    std::vector<std::uint64_t> row_start;
    std::vector<std::int32_t>  col;
    /** n_components()^2 entries per column entry. */
    std::vector<double> weight;
    /** cond_2(A_i) of each row (scaled basis). */
    std::vector<double> condition_number;
    /** @} */

    /** Number of operators (1 for the scalar and bond-based constructors). */
    unsigned int
    n_operators() const
    {
      return 1 + extra_weight.size();
    }
    /** n_out x n_in of operator @p k. */
    std::pair<unsigned int, unsigned int>
    operator_shape(const unsigned int k) const
    {
      return {shapes[k].first, shapes[k].second};
    }
    /** Weights of operator @p k, n_out x n_in (row-major) per column entry. */
    const std::vector<double> &
    weights(const unsigned int k) const
    {
      return k == 0 ? weight : extra_weight[k - 1];
    }

    /** Smallest and largest cond(A_i) over the (local) rows. */
    std::pair<double, double>
    condition_range() const;

    /**
     * Scalar: out[node[k]] = sum_j w_kj u[col_j] for every row k (other
     * entries untouched). Works on local storage (owned + ghost).
     */
    void
    apply(const double *u, double *out) const;

    /** The same on node vectors (ghosts of @p u up to date). */
    void
    apply(const Vector &u, Vector &out) const;

    /**
     * Bond-based: u and out interleaved, u[dim * j + b]; sets
     * out[dim * node[k] + a] for every row k.
     */
    void
    apply_vector(const double *u, double *out) const;

  private:
    WlsParameters      parameters;
    MonomialBasis<dim> basis;
    unsigned int       components;
    double             delta;
    unsigned int       n_colloc;
    unsigned int       aux_radius;
    /** Auxiliary grid offsets in units of delta / r_a, nearest first. */
    std::vector<Tensor<1, dim>> aux_offsets;
    std::vector<double>         op_row;
    /** Operators 1, 2, ... of the general constructor and their weights. */
    std::vector<std::vector<double>>                   extra_row;
    std::vector<std::vector<double>>                   extra_weight;
    std::vector<std::pair<unsigned int, unsigned int>> shapes;

    void
    init_auxiliary_grid();
  };

  /**
   * CSR lists of all nodes within @p radius of each node (itself excluded)
   * for a plain node list, by binning: family_start has position.size() + 1
   * entries. For tests and small self-contained problems (perturbed grids).
   */
  template <int dim>
  void
  build_node_families(const std::vector<Point<dim>> &position,
                      const double                   radius,
                      std::vector<std::uint64_t>    &family_start,
                      std::vector<std::int32_t>     &family);
} // namespace PeriDEAL

#endif
