#ifndef perideal_fem_poisson_h
#define perideal_fem_poisson_h

#include <deal.II/base/point.h>

#include <deal.II/dofs/dof_handler.h>

#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/mapping_q.h>

#include <deal.II/grid/tria.h>

#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/vector.h>

#include <functional>
#include <memory>
#include <vector>

namespace PeriDEAL
{
  namespace Fem
  {
    using namespace dealii;

    /**
     * Classical reference solutions for the PD boundary-condition studies:
     * the Laplace problem
     * @f[ \Delta u = 0 \text{ in } \Omega, \quad u = g_D \text{ on } \Gamma_D,
     *     \quad \nabla u \cdot n = g_N \text{ on } \partial\Omega\setminus\Gamma_D @f]
     * with continuous FE_Q elements (serial; sparse direct solve), adaptive
     * refinement by the Kelly estimator and evaluation at arbitrary points.
     * Faces on crack slits (duplicated vertices) are boundary faces and get
     * the Neumann condition unless the Dirichlet predicate claims them.
     */
    class PoissonReference
    {
    public:
      /** Which boundary faces are Dirichlet (by face center). */
      using FacePredicate = std::function<bool(const Point<2> &)>;
      /** A scalar function of the position. */
      using ScalarFunction = std::function<double(const Point<2> &)>;

      /**
       * Take @p triangulation (its manifolds attached by the caller) and the
       * boundary data; @p neumann_flux may be empty (zero flux).
       */
      PoissonReference(std::unique_ptr<Triangulation<2>> triangulation,
                       const unsigned int                degree,
                       const FacePredicate              &is_dirichlet,
                       const ScalarFunction             &dirichlet_value,
                       const ScalarFunction             &neumann_flux = ScalarFunction());

      /** Assemble and solve on the current mesh. */
      void
      solve();

      /**
       * Refine the fraction @p top_fraction of cells with the largest Kelly
       * indicators (and coarsen none); call solve() again afterwards.
       */
      void
      refine_kelly(const double top_fraction);

      /** Refine every cell having a vertex within @p radius of @p p, @p times times. */
      void
      refine_around(const Point<2> &p, const double radius, const unsigned int times);

      /**
       * The solution at @p points; points outside the mesh get NaN (a point
       * on a cell boundary takes the value of the first cell found).
       */
      std::vector<double>
      values_at(const std::vector<Point<2>> &points) const;

      /** Number of degrees of freedom. */
      types::global_dof_index
      n_dofs() const
      {
        return dof_handler.n_dofs();
      }

      /** The mesh. */
      const Triangulation<2> &
      get_triangulation() const
      {
        return *tria;
      }

    private:
      std::unique_ptr<Triangulation<2>> tria;
      FE_Q<2>                           fe;
      MappingQ<2>                       mapping;
      DoFHandler<2>                     dof_handler;
      AffineConstraints<double>         constraints;
      Vector<double>                    solution;
      FacePredicate                     is_dirichlet;
      ScalarFunction                    dirichlet_value, neumann_flux;
    };

    /**
     * The disk of radius @p radius about the origin with the straight crack
     * [-a, a] x {0} (a = @p half_length <= radius / 2) and, if @p crossing,
     * also {0} x [-a, a]. A five-cell disk (inner square [-a, a]^2) is refined
     * @p n_refinements >= 1 times so that the cracks are unions of edges;
     * then the vertices on the open cracks are duplicated per side (four
     * copies at the crossing point), which makes the crack faces boundary
     * faces. The circle carries a SphericalManifold (id 0).
     */
    std::unique_ptr<Triangulation<2>>
    cracked_disk(const double       radius,
                 const double       half_length,
                 const bool         crossing,
                 const unsigned int n_refinements);
  } // namespace Fem
} // namespace PeriDEAL

#endif
