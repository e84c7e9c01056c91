#ifndef perideal_abc_half_derivative_history_h
#define perideal_abc_half_derivative_history_h

#include <cstddef>
#include <string>
#include <vector>

namespace PeriDEAL
{
  namespace Abc
  {
    /**
     * Gruenwald-Letnikov weight g_j of the half derivative, (-1)^j
     * binom(1/2, j) = Gamma(j - 1/2) / (Gamma(-1/2) Gamma(j + 1)): g_0 = 1,
     * g_1 = -1/2, g_j ~ -j^{-3/2} / (2 sqrt(pi)). Closed form (Boost.Math's
     * Gamma ratio, accurate to round-off for every j), independent of the
     * recurrence the exact history uses.
     */
    double
    gruenwald_letnikov_half_weight(const std::size_t j);

    /**
     * Sum-of-exponentials approximation of the Gruenwald-Letnikov weights of
     * the half derivative, g_j ~ sum_k weights[k] exp(-rates[k] (j - first)),
     * for first <= j <= horizon with relative accuracy @p accuracy (fast
     * history in the manner of Jiang, Zhang, Zhang, Greengard, "Fast
     * evaluation of the Caputo fractional derivative", 2017, applied to the
     * exact discrete weights). The weights are a Laplace transform in j,
     *   g_j = -(1/pi) int_0^inf exp(-s (j - 1/2)) sqrt(1 - exp(-s)) ds, j >= 1,
     * (Beta integral of Gamma(j - 1/2)/Gamma(j + 1), x = exp(-s)), discretized
     * by the trapezoidal rule in x = log s: step h = pi^2 / (log(1/accuracy)
     * + 6) (the integrand is analytic in |Im x| < pi/2, error ~ exp(-pi^2/h)),
     * s from accuracy^{2/3} / horizon (the cut-off part is below accuracy
     * |g_horizon|) to (log(1/accuracy) + 6) / (first - 1/2) (the cut-off
     * part is below accuracy |g_first|). Beyond the horizon the absolute
     * error of a weight stays below accuracy |g_horizon|. Measured max
     * relative error 0.4 .. 0.8 times @p accuracy for 1e-13 .. 1e-3; the
     * constructor checks it on all j <= first + 2000 and 200 points per
     * decade beyond (max_relative_error) and refines h if needed.
     * first = @p exact_steps + 1. ParameterError (naming Absorbing
     * boundary/Half derivative accuracy, .../exact steps, .../horizon) on
     * input outside 1e-13 <= accuracy <= 1e-3, 0 <= exact steps <= 1000,
     * exact steps < horizon <= 1e15.
     */
    struct HalfDerivativeSoe
    {
      HalfDerivativeSoe() = default;
      HalfDerivativeSoe(const double accuracy, const unsigned int exact_steps, const double horizon);

      /** The approximation of g_j, j >= first. */
      double
      weight(const std::size_t j) const;

      /** Max relative error over the sampled j in [first, horizon] (see above). */
      double
      sampled_relative_error() const;

      unsigned int        first = 1;
      double              accuracy = 0., horizon = 0.;
      std::vector<double> rates, weights;
      /** exp(-rates[k]): the one-step decay of the recursive states. */
      std::vector<double> decays;
      double              max_relative_error = 0.;
    };

    /**
     * The history part of the Gruenwald-Letnikov half derivative of the
     * values of @p n_dofs points (the boundary DoFs of
     * EbfParameters::imposed = "half derivative"):
     *   H_a^{n+1} = sum_{j=1}^{n+1} g_j C_a^{n+1-j}
     * from the levels C^0 .. C^n appended so far. "exact" sums every past
     * level (O(n) per step and point, the levels are stored). "sum of
     * exponentials" sums the last @p exact_steps levels exactly and the
     * older ones through HalfDerivativeSoe: one recursive state per
     * exponential and point, U_k <- C^{n - exact_steps} + exp(-s_k) U_k,
     * tail = sum_k w_k U_k (O(number of exponentials) per step and point).
     * Since sum_{j >= 1} |g_j| = 1, the two differ by at most accuracy
     * times max_m |C_a^m| per step (within the horizon).
     */
    class HalfDerivativeHistory
    {
    public:
      HalfDerivativeHistory() = default;

      /**
       * Start an empty history. ParameterError naming Absorbing
       * boundary/Half derivative history (exact or sum of exponentials)
       * and those of HalfDerivativeSoe.
       */
      void
      reinit(const unsigned int n_dofs,
             const std::string &method,
             const double       accuracy,
             const unsigned int exact_steps,
             const double       horizon);

      /** Append the level C^n (@p values, n_dofs of them) and set @p history to H^{n+1}. */
      void
      append(const double *values, std::vector<double> &history);

      /** Number of exponentials (0 for "exact"). */
      unsigned int
      n_exponentials() const
      {
        return soe.rates.size();
      }
      const HalfDerivativeSoe &
      approximation() const
      {
        return soe;
      }
      /** Levels appended so far. */
      std::size_t
      n_levels() const
      {
        return n_appended;
      }

    private:
      unsigned int        n_dofs = 0, n_exact = 0;
      bool                fast   = false;
      std::size_t         n_appended = 0;
      HalfDerivativeSoe   soe;
      /** g_0, g_1, ... by the recurrence g_j = g_{j-1} (j - 3/2) / j. */
      std::vector<double> gl_weights;
      /** exact: every level (level-major); fast: the last n_exact + 1 levels, ring buffer. */
      std::vector<double> levels;
      /** fast: the recursive states, point-major (n_exponentials per point). */
      std::vector<double> states;
    };
  } // namespace Abc
} // namespace PeriDEAL

#endif
