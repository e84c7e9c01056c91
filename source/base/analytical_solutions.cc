#include <perideal/base/analytical_solutions.h>
#include <perideal/base/exceptions.h>

#include <boost/math/quadrature/gauss_kronrod.hpp>

#include <algorithm>
#include <cmath>

namespace PeriDEAL
{
  namespace Analytical
  {
    namespace
    {
      template <typename F>
      double
      integrate(const F &f, const double a, const double b)
      {
        if (b <= a)
          return 0.;
        // The callers split into pieces of at most ~ one period of the
        // oscillation, where the 61-point rule is exact to round-off; the
        // Kronrod estimate |K - G| is pessimistic, so a tolerance near machine
        // precision would only trigger useless bisections: cap the depth.
        return boost::math::quadrature::gauss_kronrod<double, 61>::integrate(f, a, b, 6,
                                                                             1e-13);
      }
    } // namespace

    double
    sine_integral(const double x)
    {
      if (x == 0.)
        return 0.;
      const double ax = std::abs(x);
      // Pieces of length pi keep each Kronrod panel on one half-period.
      const unsigned int n   = std::max(1u, (unsigned int)std::ceil(ax / M_PI));
      const double       h   = ax / n;
      double             sum = 0.;
      for (unsigned int i = 0; i < n; ++i)
        sum += integrate([](const double z) { return z == 0. ? 1. : std::sin(z) / z; },
                         i * h, (i + 1) * h);
      return x > 0 ? sum : -sum;
    }

    double
    pd_symbol_1d(const ScalarKernel &kernel, const double k)
    {
      const double delta = kernel.delta;
      // 1 - cos(kr) = 2 sin^2(kr/2) avoids cancellation for small kr.
      auto f = [&](const double r) {
        if (r <= 0.)
          return 0.;
        const double s = std::sin(0.5 * k * r);
        return kernel(r) * 2. * s * s;
      };
      const unsigned int n =
        std::max(1u, (unsigned int)std::ceil(std::abs(k) * delta / M_PI));
      double sum = 0.;
      for (unsigned int i = 0; i < n; ++i)
        sum += integrate(f, delta * i / n, delta * (i + 1) / n);
      return 2. * sum;
    }

    double
    pd_symbol_inverse_square_1d(const double D, const double delta, const double k)
    {
      const double kd = k * delta;
      if (std::abs(kd) < 1e-3) // series: psi = k^2 - k^4 delta^2/36 + ...
        return D * k * k * (1. - kd * kd / 36.);
      return D * 2. / delta * (k * sine_integral(kd) + (std::cos(kd) - 1.) / delta);
    }

    Symbol
    inverse_square_symbol(const double D, const double delta)
    {
      return [D, delta](const double k) { return pd_symbol_inverse_square_1d(D, delta, k); };
    }

    Symbol
    kernel_symbol(const ScalarKernel &kernel)
    {
      return [kernel](const double k) { return pd_symbol_1d(kernel, k); };
    }

    Symbol
    local_symbol(const double D)
    {
      return [D](const double k) { return D * k * k; };
    }

    EigenExpansion::EigenExpansion(const double offset, const double origin)
      : offset(offset)
      , origin(origin)
    {}

    void
    EigenExpansion::add_mode(const double amplitude,
                             const double wavenumber,
                             const double decay_rate,
                             const Basis  basis)
    {
      modes.push_back({amplitude, wavenumber, decay_rate, basis});
    }

    const std::vector<double> &
    EigenExpansion::decay(const double t) const
    {
      if (t != cached_time || cached_decay.size() != modes.size())
        {
          cached_decay.resize(modes.size());
          for (unsigned int i = 0; i < modes.size(); ++i)
            cached_decay[i] = std::exp(-modes[i].lambda * t);
          cached_time = t;
        }
      return cached_decay;
    }

    double
    EigenExpansion::value(const double x, const double t) const
    {
      const auto &e = decay(t);
      double      s = offset;
      for (unsigned int i = 0; i < modes.size(); ++i)
        {
          const auto  &m   = modes[i];
          const double arg = m.k * (x - origin);
          s += m.a * (m.basis == Basis::cosine ? std::cos(arg) : std::sin(arg)) * e[i];
        }
      return s;
    }

    double
    EigenExpansion::time_derivative(const double x, const double t) const
    {
      double s = 0.;
      for (const auto &m : modes)
        {
          const double arg = m.k * (x - origin);
          s -= m.lambda * m.a *
               (m.basis == Basis::cosine ? std::cos(arg) : std::sin(arg)) *
               std::exp(-m.lambda * t);
        }
      return s;
    }

    namespace
    {
      EigenExpansion
      rod_expansion(const double                          length,
                    const double                          Cbar,
                    const Symbol                         &symbol,
                    const unsigned int                    n_terms,
                    const std::function<double(double)> &coefficient)
      {
        check_parameter(length > 0., "rod length", length, "a positive number");
        check_parameter(n_terms >= 1, "number of terms", n_terms, "at least 1");
        EigenExpansion e(Cbar, 0.);
        for (unsigned int m = 1; m <= n_terms; ++m)
          {
            const double k = (2. * m - 1.) * M_PI / length;
            e.add_mode(-Cbar * coefficient(k), k, symbol(k));
          }
        return e;
      }
    } // namespace

    EigenExpansion
    rod_quadratic_initial_data(const double       length,
                               const double       Cbar,
                               const Symbol      &symbol,
                               const unsigned int n_terms)
    {
      return rod_expansion(length, Cbar, symbol, n_terms, [length](const double k) {
        return 32. * std::sin(0.5 * k * length) / std::pow(k * length, 3);
      });
    }

    EigenExpansion
    rod_zero_initial_data(const double       length,
                          const double       Cbar,
                          const Symbol      &symbol,
                          const unsigned int n_terms)
    {
      return rod_expansion(length, Cbar, symbol, n_terms, [length](const double k) {
        return 4. * std::sin(0.5 * k * length) / (k * length);
      });
    }

    double
    fourier_integral_1d(const std::function<double(double)> &transform,
                        const Symbol                        &symbol,
                        const double                         x,
                        const double                         t,
                        const double                         k_max)
    {
      auto f = [&](const double k) {
        return transform(k) * std::cos(k * x) * std::exp(-symbol(k) * t);
      };
      // Panels of one period of cos(kx) at most.
      const unsigned int n =
        std::max(4u, (unsigned int)std::ceil(k_max * std::abs(x) / M_PI));
      double sum = 0.;
      for (unsigned int i = 0; i < n; ++i)
        sum += integrate(f, k_max * i / n, k_max * (i + 1) / n);
      return sum / M_PI;
    }

    double
    gaussian_1d(const double  amplitude,
                const double  width,
                const double  center,
                const Symbol &symbol,
                const double  x,
                const double  t)
    {
      check_parameter(width > 0., "Gaussian width", width, "a positive number");
      const double s = width;
      return fourier_integral_1d(
        [&](const double k) {
          return amplitude * s * std::sqrt(2. * M_PI) * std::exp(-0.5 * k * k * s * s);
        },
        symbol, x - center, t, 40. / s);
    }

    MovingInterfaceManufactured::MovingInterfaceManufactured(const double length,
                                                             const double Cbar,
                                                             const double t_final,
                                                             const double C_interface,
                                                             const double delta,
                                                             const double d_low,
                                                             const double d_high,
                                                             const double d_mixed)
      : length(length)
      , Cbar(Cbar)
      , t_final(t_final)
      , C_interface(C_interface)
      , delta(delta)
      , d_low(d_low)
      , d_high(d_high)
      , d_mixed(d_mixed)
    {
      check_parameter(length > 0., "rod length", length, "a positive number");
      check_parameter(t_final > 0., "t_f", t_final, "a positive number");
      check_parameter(C_interface < Cbar, "C_i", C_interface, "a value below Cbar");
    }

    double
    MovingInterfaceManufactured::value(const double x, const double t) const
    {
      return Cbar * (1. + (4. * x * x / (length * length) - 1.) * (1. - t / t_final));
    }

    double
    MovingInterfaceManufactured::interface_position(const double t) const
    {
      if (t >= t_final)
        return 0.;
      const double a = 1. + (C_interface / Cbar - 1.) * t_final / (t_final - t);
      return a > 0. ? 0.5 * length * std::sqrt(a) : 0.;
    }

    double
    MovingInterfaceManufactured::source(const double x,
                                        const double t,
                                        const double x_interface) const
    {
      const double dCdt = -Cbar / t_final * (4. * x * x / (length * length) - 1.);
      const double K    = 4. * Cbar / (length * length) * (1. - t / t_final);
      // Phases: 0 below C_i (|y| < x_interface), 1 above.
      auto above = [&](const double y) { return std::abs(y) > x_interface; };
      auto d     = [&](const bool a, const bool b) {
        return a && b ? d_high : (!a && !b ? d_low : d_mixed);
      };
      const bool ax = above(x);
      // Breakpoints in xi: the horizon ends, 0 and the interfaces.
      std::vector<double> b = {-delta, 0., delta};
      for (const double xi : {-x_interface - x, x_interface - x})
        if (xi > -delta && xi < delta && xi != 0.)
          b.push_back(xi);
      std::sort(b.begin(), b.end());
      // int (1 + 2x/xi) dxi over [xa, xb] of one sign: (xb - xa) + 2x ln(xb/xa).
      // Segments ending at 0 contribute -+2x ln|other end| (principal value:
      // the ln(epsilon) terms of both sides cancel, d being continuous at x).
      double integral = 0.;
      for (unsigned int s = 0; s + 1 < b.size(); ++s)
        {
          const double xa = b[s], xb = b[s + 1];
          if (xb - xa <= 0.)
            continue;
          const double dk = d(ax, above(x + 0.5 * (xa + xb)));
          double       v  = xb - xa;
          if (xa == 0.)
            v += 2. * x * std::log(xb);
          else if (xb == 0.)
            v -= 2. * x * std::log(-xa);
          else
            v += 2. * x * std::log(xb / xa);
          integral += dk * v;
        }
      return dCdt - K * integral;
    }
  } // namespace Analytical
} // namespace PeriDEAL
