#include <deal.II/base/quadrature_lib.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/kernel.h>

#include <cmath>

namespace PeriDEAL
{
  using namespace dealii;

  InfluenceFunction
  parse_influence_function(const std::string &name,
                           const std::string &parameter)
  {
    if (name == "constant")
      return InfluenceFunction::constant;
    if (name == "linear")
      return InfluenceFunction::linear;
    throw ParameterError(parameter, name, "one of 'constant', 'linear'");
  }

  std::string
  to_string(const InfluenceFunction omega)
  {
    return omega == InfluenceFunction::constant ? "constant" : "linear";
  }

  double
  ScalarKernel::operator()(const double r) const
  {
    return constant * influence(omega, r, delta) / std::pow(r, exponent);
  }

  double
  radial_moment(const InfluenceFunction omega, const double delta, const double s)
  {
    check_parameter(s > -1., "kernel exponent", s,
                    "a kernel whose second moment exists (2 - exponent + dim - 1 > -1)");
    // Geometric grading toward r = 0 resolves the r^s singularity for
    // fractional s; each interval is smooth so 12-point Gauss is enough.
    const QGauss<1> gauss(12);
    double          sum = 0.;
    double          b   = delta;
    for (unsigned int level = 0; level < 200; ++level)
      {
        const double a = (level == 199 ? 0. : 0.5 * b);
        double       part = 0.;
        for (unsigned int q = 0; q < gauss.size(); ++q)
          {
            const double r = a + (b - a) * gauss.point(q)[0];
            part += gauss.weight(q) * (b - a) * influence(omega, r, delta) *
                    std::pow(r, s);
          }
        sum += part;
        if (std::abs(part) < 1e-18 * std::abs(sum))
          break;
        b = a;
      }
    return sum;
  }

  double
  angular_second_moment(const unsigned int dim)
  {
    switch (dim)
      {
        case 1:
          return 2.; // n_1 = +-1
        case 2:
          {
            // int_0^{2 pi} cos^2(theta) dtheta; the trapezoidal rule is
            // exact for trigonometric polynomials of degree < 16.
            const unsigned int n   = 16;
            double             sum = 0.;
            for (unsigned int q = 0; q < n; ++q)
              sum += 2. * M_PI / n * std::pow(std::cos(2. * M_PI * q / n), 2);
            return sum;
          }
        case 3:
          {
            // int_0^pi int_0^{2 pi} cos^2(phi) sin(phi) dtheta dphi
            const QGauss<1> g(12);
            double          sum = 0.;
            for (unsigned int q = 0; q < g.size(); ++q)
              {
                const double phi = M_PI * g.point(q)[0];
                sum += g.weight(q) * M_PI * 2. * M_PI *
                       std::pow(std::cos(phi), 2) * std::sin(phi);
              }
            return sum;
          }
        default:
          throw ParameterError("Dimension", std::to_string(dim), "1, 2 or 3");
      }
  }

  double
  ScalarKernel::second_moment() const
  {
    check_parameter(delta > 0., "Horizon", delta, "a positive number");
    return angular_second_moment(dim) *
           radial_moment(omega, delta, 2. - exponent + (double(dim) - 1.));
  }

  double
  ScalarKernel::micro_constant_for(const double local_coefficient) const
  {
    return 2. * local_coefficient / second_moment();
  }

  double
  ScalarKernel::local_coefficient() const
  {
    return 0.5 * constant * second_moment();
  }

  double
  table_4_1_micro_diffusivity(const unsigned int      dim,
                              const unsigned int      q,
                              const InfluenceFunction omega,
                              const double            d,
                              const double            D)
  {
    const bool   c  = (omega == InfluenceFunction::constant);
    const double pi = M_PI;
    if (dim == 1 && q == 0)
      return (c ? 3. : 12.) * D / std::pow(d, 3);
    if (dim == 1 && q == 1)
      return (c ? 2. : 6.) * D / std::pow(d, 2);
    if (dim == 2 && q == 0)
      return (c ? 8. : 40.) * D / (pi * std::pow(d, 4));
    if (dim == 2 && q == 1)
      return (c ? 6. : 24.) * D / (pi * std::pow(d, 3));
    if (dim == 2 && q == 2) // also (2.43)
      return (c ? 4. : 12.) * D / (pi * std::pow(d, 2));
    if (dim == 3 && q == 1)
      return (c ? 6. : 30.) * D / (pi * std::pow(d, 4));
    if (dim == 3 && q == 2)
      return (c ? 9. / 2. : 18.) * D / (pi * std::pow(d, 3));
    throw ParameterError("Table 4.1 entry",
                         std::to_string(dim) + "D J" + std::to_string(q),
                         "one of 1D J0/J1, 2D J0/J1/J2, 3D J1/J2");
  }
} // namespace PeriDEAL
