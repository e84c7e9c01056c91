#ifndef perideal_fem_near_field_h
#define perideal_fem_near_field_h

#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/partitioner.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <deal.II/dofs/dof_handler.h>

#include <deal.II/lac/la_parallel_vector.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <memory>
#include <vector>

namespace PeriDEAL
{
  namespace Fem
  {
    using namespace dealii;

    /** Distributed vector of the FEM near fields (owned DoFs, then ghosts: relevant and cloud DoFs). */
    using DistributedVector = LinearAlgebra::distributed::Vector<double>;

    /**
     * The parallel layout of a FEM near field with an absorbing boundary on
     * a serial or parallel::distributed triangulation: owned DoFs, the ghost
     * set (the locally relevant DoFs extended by every DoF within the cloud
     * radius of an owned boundary DoF, so that ABC clouds may straddle
     * ranks), support points and global ids in the local numbering of
     * DistributedVector, the owned boundary DoFs with their outward normals
     * (average of the adjacent boundary-face normals of the MappingQ1
     * geometry: on a disk the radial direction, at a square's corner the
     * diagonal), and the assembled matrices (Trilinos, owned rows).
     */
    template <int dim>
    class NearFieldLayout
    {
    public:
      /**
       * Build everything for @p dof_handler (DoFs distributed); clouds of
       * radius @p cloud_radius (0: no cloud ghosts).
       */
      void
      reinit(const DoFHandler<dim> &dof_handler, const double cloud_radius);

      /**
       * Consistent mass and Laplace matrices (QGauss(degree + 1)), the
       * lumped mass (row sums of the consistent one) and the lumped boundary
       * mass (Gauss-Lobatto face quadrature, for Robin terms).
       */
      void
      assemble(TrilinosWrappers::SparseMatrix &mass,
               TrilinosWrappers::SparseMatrix &laplace,
               DistributedVector              &lumped_mass,
               DistributedVector              &lumped_boundary_mass) const;

      /** A matrix with the sparsity of the DoF couplings (values zero). */
      void
      reinit_matrix(TrilinosWrappers::SparseMatrix &matrix) const;

      /** Number of locally owned DoFs (the first entries of the local numbering). */
      unsigned int
      n_owned() const
      {
        return owned.n_elements();
      }

      /**
       * Largest eigenvalue of M^-1 K by power iteration (M lumped if
       * @p lumped_mass, consistent otherwise), from below (Rayleigh quotient).
       */
      double
      largest_eigenvalue(const TrilinosWrappers::SparseMatrix &stiffness,
                         const TrilinosWrappers::SparseMatrix &mass,
                         const DistributedVector              &lumped_mass,
                         const bool                            lumped,
                         const unsigned int                    iterations = 200) const;

      MPI_Comm                                           comm = MPI_COMM_SELF;
      const DoFHandler<dim>                             *dof_handler = nullptr;
      IndexSet                                           owned, relevant;
      std::shared_ptr<const Utilities::MPI::Partitioner> partitioner;
      /** Support point and global id per local index (owned, then ghosts). */
      std::vector<Point<dim>>              points;
      std::vector<types::global_dof_index> ids;
      /** Local indices of the owned boundary DoFs and their outward unit normals. */
      std::vector<unsigned int>   boundary;
      std::vector<Tensor<1, dim>> normals;
      /**
       * Estimated sum of the principal curvatures at the owned boundary
       * DoFs (2/R on a sphere, 1/R on a circle, 0 on flat faces): (dim - 1)
       * times the mean over the adjacent boundary faces f of
       * (n_f - n_i).(c_f - x_i) / |c_f - x_i|^2 (the normal curvature along
       * the chord to the face centre c_f). Same order as @p boundary.
       */
      std::vector<double> curvatures;
      /** Smallest vertex distance of the mesh (global). */
      double min_cell_size = 0.;
      /** Largest cell diameter-like size: max over cells of the minimum vertex distance (global). */
      double max_cell_size = 0.;
    };

    /** Every (support point, value) pair of @p u on all ranks, sorted by point (rank-count-independent comparison). */
    template <int dim>
    std::vector<std::pair<Point<dim>, double>>
    gather_by_point(const NearFieldLayout<dim> &layout, const DistributedVector &u);
  } // namespace Fem
} // namespace PeriDEAL

#endif
