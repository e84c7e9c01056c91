#include <boost/math/special_functions/gamma.hpp>

#include <perideal/abc/half_derivative_history.h>
#include <perideal/base/exceptions.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace PeriDEAL
{
  namespace Abc
  {
    double
    gruenwald_letnikov_half_weight(const std::size_t j)
    {
      if (j == 0)
        return 1.;
      // Gamma(-1/2) = -2 sqrt(pi).
      return boost::math::tgamma_ratio(j - 0.5, j + 1.) / (-2. * std::sqrt(M_PI));
    }

    HalfDerivativeSoe::HalfDerivativeSoe(const double accuracy, const unsigned int exact_steps, const double horizon)
      : first(exact_steps + 1)
      , accuracy(accuracy)
      , horizon(horizon)
    {
      check_parameter(accuracy >= 1e-13 && accuracy <= 1e-3, "Absorbing boundary/Half derivative accuracy", accuracy,
                      "1e-13 <= accuracy <= 1e-3 (relative accuracy of the sum-of-exponentials weights)");
      check_parameter(exact_steps <= 1000, "Absorbing boundary/Half derivative exact steps", exact_steps,
                      "0 <= exact steps <= 1000");
      check_parameter(horizon > exact_steps && horizon <= 1e15, "Absorbing boundary/Half derivative horizon", horizon,
                      "exact steps < horizon <= 1e15 (steps over which the accuracy holds)");
      const double log_accuracy = std::log(1. / accuracy);
      const double s_min        = std::pow(accuracy, 2. / 3.) / horizon;
      const double s_max        = (log_accuracy + 6.) / (first - 0.5);
      // The trapezoidal rule in log s (see the header); measured 0.4 .. 0.8
      // times the accuracy, so the refinement below is a safeguard.
      double h = M_PI * M_PI / (log_accuracy + 6.);
      for (unsigned int attempt = 0; attempt < 6; ++attempt, h *= 0.8)
        {
          const unsigned int n = static_cast<unsigned int>(std::ceil(std::log(s_max / s_min) / h)) + 1;
          rates.resize(n);
          weights.resize(n);
          decays.resize(n);
          for (unsigned int k = 0; k < n; ++k)
            {
              const double s = s_min * std::exp(k * h);
              rates[k]       = s;
              // -(h/pi) s sqrt(1 - e^{-s}) e^{s/2}, times e^{-s first} (the
              // states count j from first).
              weights[k] = -h / M_PI * s * std::sqrt(-std::expm1(-s)) * std::exp(-s * (first - 0.5));
              decays[k]  = std::exp(-s);
            }
          max_relative_error = sampled_relative_error();
          if (max_relative_error <= accuracy)
            return;
        }
      throw std::logic_error("HalfDerivativeSoe: relative error " + std::to_string(max_relative_error) +
                             " above the requested accuracy after refinement");
    }

    double
    HalfDerivativeSoe::weight(const std::size_t j) const
    {
      const double m = double(j) - first;
      double       g = 0.;
      for (unsigned int k = 0; k < rates.size(); ++k)
        g += weights[k] * std::exp(-rates[k] * m);
      return g;
    }

    double
    HalfDerivativeSoe::sampled_relative_error() const
    {
      double     e     = 0.;
      const auto check = [&](const double j) {
        const std::size_t i = std::llround(j);
        const double      g = gruenwald_letnikov_half_weight(i);
        e                   = std::max(e, std::abs(weight(i) - g) / std::abs(g));
      };
      const double dense_end = std::min(horizon, first + 2000.);
      for (double j = first; j <= dense_end; ++j)
        check(j);
      for (double lj = std::log10(dense_end); lj < std::log10(horizon); lj += 1. / 200.)
        check(std::pow(10., lj));
      check(horizon);
      return e;
    }

    void
    HalfDerivativeHistory::reinit(const unsigned int n_dofs,
                                  const std::string &method,
                                  const double       accuracy,
                                  const unsigned int exact_steps,
                                  const double       horizon)
    {
      check_parameter(method == "exact" || method == "sum of exponentials",
                      "Absorbing boundary/Half derivative history", method, "exact or sum of exponentials");
      this->n_dofs = n_dofs;
      fast         = method == "sum of exponentials";
      n_appended   = 0;
      levels.clear();
      states.clear();
      gl_weights.assign(1, 1.);
      soe = HalfDerivativeSoe();
      if (fast)
        {
          soe     = HalfDerivativeSoe(accuracy, exact_steps, horizon);
          n_exact = exact_steps;
          levels.assign(std::size_t(n_exact + 1) * n_dofs, 0.);
          states.assign(std::size_t(n_dofs) * soe.rates.size(), 0.);
        }
      else
        n_exact = 0;
    }

    void
    HalfDerivativeHistory::append(const double *values, std::vector<double> &history)
    {
      // Level n = n_appended; H^{n+1} = sum_{j=1}^{n+1} g_j C^{n+1-j}.
      const std::size_t n = n_appended++;
      const std::size_t n_local = fast ? std::min<std::size_t>(n_exact, n + 1) : n + 1;
      while (gl_weights.size() <= n_local)
        {
          const double j = gl_weights.size();
          gl_weights.push_back(gl_weights.back() * (j - 1.5) / j);
        }
      history.assign(n_dofs, 0.);
      if (!fast)
        {
          levels.insert(levels.end(), values, values + n_dofs);
          for (std::size_t j = 1; j <= n + 1; ++j)
            {
              const double *level = levels.data() + (n + 1 - j) * n_dofs;
              for (unsigned int a = 0; a < n_dofs; ++a)
                history[a] += gl_weights[j] * level[a];
            }
          return;
        }
      // Ring buffer of the levels n - n_exact .. n (slot m mod (n_exact + 1)).
      const std::size_t n_slots = n_exact + 1;
      std::copy(values, values + n_dofs, levels.begin() + (n % n_slots) * n_dofs);
      for (std::size_t j = 1; j <= n_local; ++j)
        {
          const double *level = levels.data() + ((n + 1 - j) % n_slots) * n_dofs;
          for (unsigned int a = 0; a < n_dofs; ++a)
            history[a] += gl_weights[j] * level[a];
        }
      // The tail j >= n_exact + 1 starts once level n - n_exact exists:
      // U_k <- C^{n - n_exact} + exp(-s_k) U_k, tail = sum_k w_k U_k.
      if (n < n_exact)
        return;
      const double      *oldest = levels.data() + ((n - n_exact) % n_slots) * n_dofs;
      const unsigned int n_exp  = soe.rates.size();
      const double      *decay  = soe.decays.data();
      const double      *weight = soe.weights.data();
      for (unsigned int a = 0; a < n_dofs; ++a)
        {
          double      *u    = states.data() + std::size_t(a) * n_exp;
          const double c    = oldest[a];
          double       tail = 0.;
#pragma omp simd reduction(+ : tail)
          for (unsigned int k = 0; k < n_exp; ++k)
            {
              u[k] = c + decay[k] * u[k];
              tail += weight[k] * u[k];
            }
          history[a] += tail;
        }
    }
  } // namespace Abc
} // namespace PeriDEAL
