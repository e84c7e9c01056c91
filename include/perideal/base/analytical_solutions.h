#ifndef perideal_base_analytical_solutions_h
#define perideal_base_analytical_solutions_h

#include <perideal/base/kernel.h>

#include <functional>
#include <vector>

namespace PeriDEAL
{
  /**
   * Closed-form and semi-analytical solutions of linear PD diffusion, for
   * verification. Everything rests on one fact: for a kernel k(|xi|) the 1D
   * operator
   * @f[ L C(x) = \int_{-\delta}^{\delta} k(|\xi|) (C(x+\xi) - C(x)) d\xi @f]
   * maps cos(kx) and sin(kx) to -lambda(k) times themselves, with the
   * decay-rate symbol
   * @f[ \lambda(k) = 2 \int_0^\delta k(r) (1 - \cos kr) dr. @f]
   * A solution of dC/dt = L C is therefore a sum (eigen-expansion on a
   * bounded rod, separation of variables) or an integral (Fourier transform
   * on the line) of decaying modes. The symbol is passed as a function, so
   * the same evaluators serve the kernel of paper 003 (d/xi^2, closed form
   * (52)), the J_q kernels of the dissertation (by quadrature from a
   * ScalarKernel) and the local limit lambda = D k^2.
   */
  namespace Analytical
  {
    /** lambda(k): decay rate of the mode cos(kx) under the PD operator. */
    using Symbol = std::function<double(double)>;

    /** The sine integral Si(x) = int_0^x sin(z)/z dz (adaptive Gauss-Kronrod). */
    double
    sine_integral(const double x);

    /**
     * lambda(k) = 2 int_0^delta k(r)(1 - cos kr) dr for @p kernel (its
     * constant included; dimension ignored, 1D integral), by adaptive
     * Gauss-Kronrod quadrature; accurate to ~1e-13 relative.
     */
    double
    pd_symbol_1d(const ScalarKernel &kernel, const double k);

    /**
     * Closed form (52) of paper 003 for the kernel (D/delta)/xi^2 (micro-
     * diffusivity d = D/delta (4), mu = xi^-2):
     * lambda = D psi(k), psi = (2/delta)[k Si(k delta) + (cos(k delta) - 1)/delta]
     * (the sign of the printed integrand is wrong, see the errata; psi > 0
     * and psi -> k^2 as delta -> 0).
     */
    double
    pd_symbol_inverse_square_1d(const double D, const double delta, const double k);

    /** Symbol functor of pd_symbol_inverse_square_1d(). */
    Symbol
    inverse_square_symbol(const double D, const double delta);

    /** Symbol functor of pd_symbol_1d() for @p kernel. */
    Symbol
    kernel_symbol(const ScalarKernel &kernel);

    /** The local limit lambda = D k^2. */
    Symbol
    local_symbol(const double D);

    /**
     * A finite eigen-expansion
     * @f[ C(x, t) = c_0 + \sum_m a_m \phi_m(k_m (x - x_0)) e^{-\lambda(k_m) t}, @f]
     * phi = cos or sin, the separation-of-variables solution of linear PD
     * diffusion on a rod whose data outside the rod is the (anti)symmetric
     * extension the modes imply (the "infinite body" of 003 Sect. 4.1).
     */
    class EigenExpansion
    {
    public:
      enum class Basis
      {
        cosine,
        sine
      };

      /** @p offset c_0, @p origin x_0. */
      EigenExpansion(const double offset = 0., const double origin = 0.);

      /** Append a mode with amplitude a, wavenumber k and decay rate lambda. */
      void
      add_mode(const double amplitude,
               const double wavenumber,
               const double decay_rate,
               const Basis  basis = Basis::cosine);

      /** C(x, t). */
      double
      value(const double x, const double t) const;

      /** dC/dt(x, t). */
      double
      time_derivative(const double x, const double t) const;

      unsigned int
      n_modes() const
      {
        return modes.size();
      }

    private:
      struct Mode
      {
        double a, k, lambda;
        Basis  basis;
      };
      double            offset, origin;
      std::vector<Mode> modes;
      /** exp(-lambda_m t) of the last t asked for (error sweeps over many x). */
      mutable double              cached_time = -1.;
      mutable std::vector<double> cached_decay;

      const std::vector<double> &
      decay(const double t) const;
    };

    /**
     * Paper 003 (50)-(51): rod -l/2 < x < l/2, C(+-l/2, t) = Cbar,
     * C(x, 0) = 4 Cbar x^2 / l^2. With the errata's coefficient
     * 32 sin(k_m l/2) / (k_m^3 l^3) (the printed k_m^2 is dimensionally
     * wrong), k_m = (2m - 1) pi / l, m = 1..n_terms (the paper uses 200).
     */
    EigenExpansion
    rod_quadratic_initial_data(const double  length,
                               const double  Cbar,
                               const Symbol &symbol,
                               const unsigned int n_terms = 200);

    /**
     * Paper 003 (53)-(54): the same rod with the discontinuous initial
     * condition C(x, 0) = 0 inside: coefficient 4 sin(k_m l/2)/(k_m l).
     */
    EigenExpansion
    rod_zero_initial_data(const double  length,
                          const double  Cbar,
                          const Symbol &symbol,
                          const unsigned int n_terms = 200);

    /**
     * Solution on the infinite line for even initial data C_0 with cosine
     * transform @p transform (C_0(x) = (1/pi) int_0^inf T(k) cos(kx) dk):
     * @f[ C(x, t) = \frac{1}{\pi} \int_0^{k_{max}} T(k) \cos(kx) e^{-\lambda(k) t} dk, @f]
     * by adaptive Gauss-Kronrod quadrature; @p k_max must be where T is
     * negligible.
     */
    double
    fourier_integral_1d(const std::function<double(double)> &transform,
                        const Symbol                        &symbol,
                        const double                         x,
                        const double                         t,
                        const double                         k_max);

    /**
     * The line solution for the Gaussian C_0 = A exp(-(x - x_0)^2 / (2 s^2))
     * (transform A s sqrt(2 pi) exp(-k^2 s^2 / 2), cut at k s = 40).
     */
    double
    gaussian_1d(const double  amplitude,
                const double  width,
                const double  center,
                const Symbol &symbol,
                const double  x,
                const double  t);

    /**
     * The manufactured moving-interface problem of paper 003, Sect. 5.1, on
     * the rod -l/2 < x < l/2:
     * C(x, t) = Cbar [1 + (4 x^2 / l^2 - 1)(1 - t/t_f)]              (57)
     * with the phase-change concentration C_i: the interface sits at
     * x_i = (l/2) sqrt(1 + (C_i/Cbar - 1) t_f/(t_f - t))            (59)
     * (points with |x| < x_i are below C_i), and the source (60) that makes
     * (57) solve the two-phase PD equation with bond micro-diffusivities
     * d_low (both ends below C_i), d_high (both above), d_mixed (6), kernel
     * 1/xi^2, evaluated in closed form with the antiderivative (61)
     * (errata: xi + 2x ln|xi|, the segment through xi = 0 as a principal
     * value).
     */
    class MovingInterfaceManufactured
    {
    public:
      MovingInterfaceManufactured(const double length,
                                  const double Cbar,
                                  const double t_final,
                                  const double C_interface,
                                  const double delta,
                                  const double d_low,
                                  const double d_high,
                                  const double d_mixed);

      /** (57). */
      double
      value(const double x, const double t) const;

      /** (59): the interface position x_i >= 0, 0 once C > C_i everywhere. */
      double
      interface_position(const double t) const;

      /**
       * (60) at (x, t) with the phases split at +-@p x_interface (the exact
       * (59) or, as in 003 Sect. 5.2, the numerical interface). The
       * quadratic (57) is used on the whole horizon, also beyond the rod.
       */
      double
      source(const double x, const double t, const double x_interface) const;

    private:
      double length, Cbar, t_final, C_interface, delta, d_low, d_high, d_mixed;
    };
  } // namespace Analytical
} // namespace PeriDEAL

#endif
