#ifndef perideal_time_stepping_static_mechanics_h
#define perideal_time_stepping_static_mechanics_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/tensor.h>

#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/lps.h>

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of a static equilibrium run of a linearized PD model
   * (`Problem = static mechanics`): geometry and discretization (shared with
   * the other runs), the model (linearized bond-based (2.32), Model/Bond-based,
   * or linearized LPS (2.18)-(2.19), Model/LPS), body force, prescribed
   * displacements, the linear solver and the output directory.
   */
  template <int dim>
  struct StaticMechanicsParameters
  {
    /** A vector field of the position. */
    using Field = std::function<Tensor<1, dim>(const Point<dim> &)>;

    std::shared_ptr<Domain<dim>> domain;
    LatticeParameters            lattice;
    /** "linearized bond-based" or "LPS". */
    std::string              model = "LPS";
    BondBasedModelParameters bond_based;
    LPSModelParameters       lps;
    /** Body force density b (the body's nodes). */
    Field body_force;
    /** Displacement prescribed on the volume-constraint layer. */
    Field layer_displacement;
    /** Further node sets {level set <= 0} of the body with prescribed displacement. */
    std::vector<std::pair<std::function<double(const Point<dim> &)>, Field>>
      prescribed_displacements;
    /**
     * "cg-amg" (CG with ML AMG) or "direct" (Amesos KLU). With quadrature
     * = wls: "cg-amg" is matrix-free GMRES with the AMG of the standard
     * stiffness as right preconditioner, "direct" factorizes the WLS matrix
     * assembled by probing (robust where the WLS spectrum is far from the
     * standard one, e.g. WLS-4 at m >= 6).
     */
    std::string  solver = "cg-amg";
    double       tolerance = 1e-10;
    unsigned int max_iterations = 10000;
    /** "standard" or "wls" (LPS only: LinearizedLPSOperator::set_wls_rows() on the free interior nodes). */
    std::string   quadrature = "standard";
    WlsParameters wls;
    /** Output directory; empty: no files. */
    std::string output_directory;

    /** Declare Model/LPS and "Static mechanics" (the rest is declared elsewhere). */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate; throws ParameterError naming the entry. */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Static equilibrium f(u) + b = 0 of the linearized bond-based or LPS
   * model: the stiffness K (Stiffness::assemble) of the free nodes is
   * assembled once, the prescribed displacements u_C of the constraint
   * layer and node sets enter the right-hand side as -K_IC u_C = f(u_C)
   * (matrix-free), and K_II u_I = b_I + f_I(u_C) is solved with CG + AMG
   * (constant modes per component) or a direct solver. The constraint
   * layer removes the rigid-body modes; without any prescribed node the
   * system is singular and setup() throws.
   */
  template <int dim>
  class StaticMechanicsSolver
  {
  public:
    /** One node Vector per component. */
    using VectorField = std::array<Vector, dim>;

    StaticMechanicsSolver(const MPI_Comm comm, const StaticMechanicsParameters<dim> &parameters);

    /** Build lattice and model and mark the prescribed nodes. */
    void
    setup();

    /** Assemble and solve; afterwards displacement() holds u (ghosts updated). */
    void
    solve();

    /** Write solution.pvtu (u components, |u|) and summary.txt to the output directory. */
    void
    output();

    /** Force density f(u) of the model (owned entries); @p u with valid ghosts. */
    void
    compute_forces(const VectorField &u, VectorField &f);

    /** The stiffness K (K u = -f(u)); with @p fixed see Stiffness::assemble. */
    void
    assemble(TrilinosWrappers::SparseMatrix   &matrix,
             const std::vector<unsigned char> &fixed = {}) const;

    /** @name Results */
    /** @{ */
    const Discretization<dim> &
    discretization() const
    {
      return disc;
    }
    const VectorField &
    displacement() const
    {
      return u;
    }
    /** The LPS operator (Model = LPS, after setup()), else nullptr. */
    const LinearizedLPSOperator<dim> *
    lps_operator() const
    {
      return lps.get();
    }
    /** Nonzero for prescribed nodes (owned and ghost entries). */
    const std::vector<unsigned char> &
    fixed_nodes() const
    {
      return fixed;
    }
    /** Total strain energy sum_i W_i V_i of the solution. */
    double
    strain_energy() const;
    /**
     * Reaction force on the prescribed nodes, R = -sum_{i prescribed} f_i(u) V_i:
     * what the constraint exerts; R + sum over the body of b V = 0 at equilibrium.
     */
    Tensor<1, dim>
    reaction_force();
    /** Sum of b_i V_i over the free nodes. */
    Tensor<1, dim>
    total_body_force() const;
    unsigned int
    n_iterations() const
    {
      return iterations;
    }
    /** ||K u - rhs|| / ||rhs|| of the solved system. */
    double
    relative_residual() const
    {
      return residual;
    }
    /** @} */

  private:
    /**
     * The system matrix of the free unknowns with the WLS force rows
     * (non-symmetric, no bond structure), recovered from compute_forces()
     * by probing with one colour class of nodes per evaluation; prescribed
     * rows and columns removed, unit diagonal. Collective; every rank holds
     * the (node, global index) table, meant for the sizes of static tests.
     */
    void
    assemble_by_probing(TrilinosWrappers::SparseMatrix &matrix);

    MPI_Comm                                     mpi_communicator;
    StaticMechanicsParameters<dim>               prm;
    Discretization<dim>                          disc;
    std::unique_ptr<BondBasedOperator<dim>>      bond_based;
    std::unique_ptr<LinearizedLPSOperator<dim>>  lps;
    std::vector<unsigned char>                   fixed;
    /** Prescribed displacement of the fixed nodes (owned and ghosts). */
    std::vector<Tensor<1, dim>>                  prescribed;
    VectorField                                  u;
    unsigned int                                 iterations = 0;
    double                                       residual   = 0.;
    double                                       solve_seconds = 0.;
  };

  /**
   * The driver's `Problem = static mechanics`: parse the parameters, set
   * up, solve, write VTU and summary.txt, and print a one-line result on
   * rank 0 (copying the parameter file is the caller's job). Throws
   * ParameterError for dim = 1.
   */
  template <int dim>
  void
  run_static_mechanics(ParameterHandler &prm, const MPI_Comm comm);
} // namespace PeriDEAL

#endif
