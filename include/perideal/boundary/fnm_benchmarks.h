#ifndef perideal_boundary_fnm_benchmarks_h
#define perideal_boundary_fnm_benchmarks_h

#include <deal.II/base/point.h>

#include <perideal/boundary/fictitious_nodes.h>
#include <perideal/boundary/polygon_domain.h>
#include <perideal/fem/poisson.h>

#include <memory>
#include <vector>

namespace PeriDEAL
{
  namespace Boundary
  {
    /**
     * The benchmark problems of paper 004 shared by the tests and step-12:
     * geometry, boundary data and classical references.
     */
    namespace Benchmarks
    {
      /** Motz's problem (Sect. 4.2): the rectangle [-1, 1] x [0, 1]. */
      PolygonDomain
      motz_domain();
      /**
       * Motz's boundary data (20): u = 500 at x = 1, u = 0 on y = 0 for
       * x < 0, zero flux elsewhere; the edge is the one closest to the point
       * (Dirichlet wins ties).
       */
      LocalCondition
      motz_condition(const Point<2> &p);
      /**
       * Motz's series (21), u = sum_i D_i rho^(i+1/2) cos((i+1/2) theta),
       * with the 20 leading published coefficients D_0..D_19 (Li & Lu; see
       * the reference catalog); accurate to ~1e-6 for rho <= 1.
       */
      double
      motz_series(const Point<2> &p);
      /** A deal.II Q2 solution of Motz's problem, graded toward O (not yet solved). */
      std::unique_ptr<Fem::PoissonReference>
      motz_fem(const unsigned int global_refinements, const unsigned int graded_refinements);

      /**
       * The cracked unit disk of Sect. 4.3 (geometry of Fig. 19/23 not
       * printed; chosen here): crack [-1/2, 1/2] x {0} and, if @p crossing,
       * {0} x [-1/2, 1/2]; insulated crack faces; u = y + x/2 on the circle.
       */
      std::vector<Crack>
      disk_cracks(const bool crossing);
      /** The Dirichlet data u = y + x/2 (at the radial projection onto the circle). */
      double
      disk_dirichlet(const Point<2> &p);
      /**
       * The FEM reference of the cracked disk: Q2 on the slit mesh with
       * @p cycles Kelly cycles (30 % refined each), solved.
       */
      std::unique_ptr<Fem::PoissonReference>
      cracked_disk_fem(const bool crossing, const unsigned int initial_refinements,
                       const unsigned int cycles);
    } // namespace Benchmarks
  }   // namespace Boundary
} // namespace PeriDEAL

#endif
