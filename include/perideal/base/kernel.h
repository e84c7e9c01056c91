#ifndef perideal_base_kernel_h
#define perideal_base_kernel_h

#include <string>

namespace PeriDEAL
{
  /**
   * Influence functions of the dissertation: constant omega_0 (2.12) and
   * linear omega_1 (2.13), both zero beyond the horizon.
   */
  enum class InfluenceFunction
  {
    constant,
    linear
  };

  /** Parse "constant" or "linear"; throws ParameterError otherwise. */
  InfluenceFunction
  parse_influence_function(const std::string &name,
                           const std::string &parameter = "Influence function");

  /** The name used in parameter files. */
  std::string
  to_string(const InfluenceFunction omega);

  /** omega(r) for 0 <= r <= delta, zero beyond. */
  inline double
  influence(const InfluenceFunction omega, const double r, const double delta)
  {
    if (r > delta)
      return 0.;
    return omega == InfluenceFunction::constant ? 1. : 1. - r / delta;
  }

  /**
   * A radial scalar PD kernel k(r) = constant * omega(r) / r^exponent on the
   * horizon @p delta, the single definition used by every discretization of
   * the scalar models (diffusion J_q of (2.42) with exponent q; corrosion
   * (2.49) with exponent n_d + 2q; scalar waves (2.40) with exponent p).
   *
   * The micro-constant that makes the nonlocal operator
   * @f[ L C(x) = \int_{H_x} k(|\xi|) (C(x+\xi) - C(x)) dV_\xi @f]
   * converge to D times the Laplacian is computed by quadrature from the
   * kernel definition: applying L to C = x_1^2 gives
   * @f[ 2 D = \text{constant} \int_{H} \omega(|\xi|) \xi_1^2 / |\xi|^{p} dV, @f]
   * which is evaluated as (angular integral of n_1^2) times (radial
   * integral of omega(r) r^{2-p+d-1}), both by Gauss quadrature. The closed
   * forms of Table 4.1 are checked against this in the tests.
   */
  struct ScalarKernel
  {
    unsigned int      dim      = 2;
    InfluenceFunction omega    = InfluenceFunction::constant;
    double            exponent = 2.;
    double            delta    = 1.;
    double            constant = 1.;

    /** k(r); zero for r > delta. @p r must be positive. */
    double
    operator()(const double r) const;

    /**
     * The second moment M = int_H omega(|xi|) xi_1^2 / |xi|^exponent dV,
     * computed by quadrature (constant factor not included).
     */
    double
    second_moment() const;

    /**
     * The micro-constant that reproduces the local diffusivity (or wave
     * speed squared, or 1D Young's modulus) @p local_coefficient:
     * 2 * local_coefficient / second_moment().
     */
    double
    micro_constant_for(const double local_coefficient) const;

    /**
     * The local coefficient this kernel (with its current constant)
     * converges to: constant * second_moment() / 2.
     */
    double
    local_coefficient() const;
  };

  /**
   * Radial integral int_0^delta omega(r) r^s dr for s > -1 by composite
   * Gauss-Legendre quadrature on geometrically graded intervals (exact to
   * round-off for integer s, and accurate to ~1e-14 for fractional s).
   */
  double
  radial_moment(const InfluenceFunction omega,
                const double            delta,
                const double            s);

  /**
   * Integral of n_1^2 over the unit sphere S^{dim-1} (2 in 1D, pi in 2D,
   * 4 pi / 3 in 3D), by Gauss quadrature in polar/spherical angles.
   */
  double
  angular_second_moment(const unsigned int dim);

  /**
   * Closed-form micro-diffusivity of Table 4.1 and (2.43) of the
   * dissertation for kernel J_q = kappa omega Theta / |xi|^q, in terms of the
   * diffusion coefficient @p D; throws for combinations the table does not
   * list. Used by the tests only, to check ScalarKernel::micro_constant_for.
   */
  double
  table_4_1_micro_diffusivity(const unsigned int      dim,
                              const unsigned int      q,
                              const InfluenceFunction omega,
                              const double            delta,
                              const double            D);
} // namespace PeriDEAL

#endif
