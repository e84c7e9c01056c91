#include <deal.II/grid/grid_generator.h>

#include <perideal/boundary/fnm_benchmarks.h>

#include <array>
#include <cmath>

namespace PeriDEAL
{
  namespace Boundary
  {
    namespace Benchmarks
    {
      PolygonDomain
      motz_domain()
      {
        return PolygonDomain({Point<2>(-1., 0.), Point<2>(1., 0.), Point<2>(1., 1.), Point<2>(-1., 1.)});
      }

      LocalCondition
      motz_condition(const Point<2> &p)
      {
        // Outside the rectangle the clamped (closest) boundary point decides,
        // and at the corners (1, 0), (1, 1) and D = (-1, 0) the Dirichlet
        // data hold (the series (21) satisfies them there).
        if (p[0] >= 1.)
          return LocalCondition::make_dirichlet(500.);
        if (p[1] <= 0.)
          return p[0] <= 0. ? LocalCondition::make_dirichlet(0.) : LocalCondition::make_neumann(0.);
        if (p[0] <= -1. || p[1] >= 1.)
          return LocalCondition::make_neumann(0.);
        const double right = std::abs(p[0] - 1.), bottom = std::abs(p[1]);
        const double left = std::abs(p[0] + 1.), top = std::abs(p[1] - 1.);
        const double other = std::min(left, top);
        if (right <= std::min(bottom, other))
          return LocalCondition::make_dirichlet(500.);
        if (bottom <= other)
          return p[0] < 0. ? LocalCondition::make_dirichlet(0.) : LocalCondition::make_neumann(0.);
        return LocalCondition::make_neumann(0.);
      }

      double
      motz_series(const Point<2> &p)
      {
        static const std::array<double, 20> D = {{
          401.162453745234,   87.6559201950879,    17.2379150794468,   -8.07121525969878,
          1.44027271702239,   0.331054885920006,   0.275437344507861,  -0.0869329945041108,
          0.0336048784027429, 0.0153843744594011,  7.30230164737158e-3, -3.18411361654663e-3,
          1.22064586154975e-3, 5.30965295822851e-4, 2.71512022889082e-4, -1.20045043773288e-4,
          5.05389241414920e-5, 2.31662561135488e-5, 1.15348467265589e-5, -5.29323807785491e-6}};
        const double rho = p.norm(), theta = std::atan2(p[1], p[0]);
        double       u   = 0.;
        for (unsigned int i = 0; i < D.size(); ++i)
          u += D[i] * std::pow(rho, i + 0.5) * std::cos((i + 0.5) * theta);
        return u;
      }

      std::unique_ptr<Fem::PoissonReference>
      motz_fem(const unsigned int global_refinements, const unsigned int graded_refinements)
      {
        auto tria = std::make_unique<Triangulation<2>>();
        GridGenerator::subdivided_hyper_rectangle(*tria, {2, 1}, Point<2>(-1., 0.), Point<2>(1., 1.));
        tria->refine_global(global_refinements);
        const auto is_dirichlet = [](const Point<2> &c) {
          return std::abs(c[0] - 1.) < 1e-12 || (std::abs(c[1]) < 1e-12 && c[0] < 0.);
        };
        const auto value = [](const Point<2> &c) { return c[0] > 0.5 ? 500. : 0.; };
        auto fem = std::make_unique<Fem::PoissonReference>(std::move(tria), 2, is_dirichlet, value);
        fem->refine_around(Point<2>(), 1e-12, graded_refinements);
        return fem;
      }

      std::vector<Crack>
      disk_cracks(const bool crossing)
      {
        std::vector<Crack> c = {{Point<2>(-0.5, 0.), Point<2>(0.5, 0.)}};
        if (crossing)
          c.push_back({Point<2>(0., -0.5), Point<2>(0., 0.5)});
        return c;
      }

      double
      disk_dirichlet(const Point<2> &p)
      {
        const double r = p.norm();
        return r > 0. ? (p[1] + 0.5 * p[0]) / r : 0.;
      }

      std::unique_ptr<Fem::PoissonReference>
      cracked_disk_fem(const bool         crossing,
                       const unsigned int initial_refinements,
                       const unsigned int cycles)
      {
        auto fem = std::make_unique<Fem::PoissonReference>(
          Fem::cracked_disk(1., 0.5, crossing, initial_refinements), 2,
          [](const Point<2> &c) { return c.norm() > 0.9; }, disk_dirichlet);
        fem->solve();
        for (unsigned int k = 0; k < cycles; ++k)
          {
            fem->refine_kelly(0.3);
            fem->solve();
          }
        return fem;
      }
    } // namespace Benchmarks
  }   // namespace Boundary
} // namespace PeriDEAL
