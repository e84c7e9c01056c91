#ifndef perideal_models_stiffness_h
#define perideal_models_stiffness_h

#include <deal.II/base/index_set.h>

#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/discretization/discretization.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/lps.h>

#include <array>
#include <vector>

namespace PeriDEAL
{
  /**
   * Assembled stiffness matrices of the linearized PD models for static
   * equilibrium (dissertation (2.32) and (2.18)-(2.19)).
   *
   * Unknowns: dim displacement components per node, numbered
   * dim * g + d with g the node's index in Discretization::partitioner(),
   * so each rank owns a contiguous range. The matrix K satisfies
   * K u = -f(u) with f the force density of the matrix-free
   * compute_forces(), i.e. static equilibrium f(u) + b = 0 reads K u = b.
   *
   * With a @p fixed mask (one entry per owned and ghost node, nonzero =
   * displacement prescribed), rows and columns of fixed nodes are removed and
   * their diagonal is 1: the system of the free unknowns, symmetric if K is.
   * The coupling of the free to the fixed unknowns goes to the right-hand
   * side (StaticMechanicsSolver uses -K_IC u_C = f(u_C) on the free rows).
   */
  namespace Stiffness
  {
    /** The owned unknowns of @p disc: [dim offset, dim (offset + n_owned)). */
    template <int dim>
    IndexSet
    owned_dofs(const Discretization<dim> &disc);

    /**
     * K of the linearized bond-based model (2.32): the block of bond ij is
     * C = c omega beta V_j xi (x) xi / |xi|^3 (K_ii += C, K_ij -= C); broken
     * bonds are skipped. Throws if the operator is not linearized.
     */
    template <int dim>
    void
    assemble(const BondBasedOperator<dim>        &op,
             TrilinosWrappers::SparseMatrix      &matrix,
             const std::vector<unsigned char>    &fixed = {});

    /**
     * K of the linearized LPS model. The deviatoric part couples the end
     * points of a bond; the dilatation part couples every pair of nodes in
     * the family of a node j (theta_j enters the forces of j and all its
     * neighbours), so K has the two-hop stencil |x_s - x_t| <= 2 (delta +
     * dx/2). It is assembled node by node (j over the owned nodes) into
     * owned and ghost rows; ghost rows are sent to their owners in compress().
     */
    template <int dim>
    void
    assemble(const LinearizedLPSOperator<dim>   &op,
             TrilinosWrappers::SparseMatrix      &matrix,
             const std::vector<unsigned char>    &fixed = {});

    /** Copy a node VectorField into a dof vector (owned entries). */
    template <int dim>
    void
    to_dofs(const Discretization<dim>          &disc,
            const std::array<Vector, std::size_t(dim)>      &field,
            TrilinosWrappers::MPI::Vector      &v);

    /** Copy a dof vector into a node VectorField (owned entries, then ghosts updated). */
    template <int dim>
    void
    from_dofs(const Discretization<dim>          &disc,
              const TrilinosWrappers::MPI::Vector &v,
              std::array<Vector, std::size_t(dim)>            &field);

    /**
     * Largest Gershgorin row sum max_r sum_c |K_rc| (over all ranks), an
     * upper bound of the largest eigenvalue of K.
     */
    double
    gershgorin_bound(const TrilinosWrappers::SparseMatrix &matrix);

    /**
     * Critical time step of velocity Verlet for rho u'' = -K u: Verlet is
     * stable for dt <= 2 sqrt(rho / lambda_max(K)); with the Gershgorin bound
     * this gives dt_c = 2 sqrt(rho / max_r sum_c |K_rc|), the analogue of
     * (3.8) (for the bond-based block C of norm c omega/|xi| the row sum is
     * 2 sum_j ||C|| beta V_j in 1D, which gives (3.8) exactly).
     */
    double
    critical_time_step(const TrilinosWrappers::SparseMatrix &matrix, const double rho);
  } // namespace Stiffness
} // namespace PeriDEAL

#endif
