#ifndef perideal_time_stepping_diffusion_solver_h
#define perideal_time_stepping_diffusion_solver_h

#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/function_parser.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/diffusion.h>

#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * Everything a PD diffusion or corrosion run reads from its parameter
   * file: geometry, discretization, model, initial/boundary data, time
   * stepping and output. declare_parameters() documents every entry with
   * its range; parse_parameters() validates them and throws
   * ParameterError naming the entry on bad input.
   */
  template <int dim>
  struct DiffusionRunParameters
  {
    std::shared_ptr<Domain<dim>> domain;
    LatticeParameters            lattice;
    DiffusionModelParameters     model;

    /** Expressions in x, y, z (and t where noted). */
    std::string initial_condition = "0";
    std::string source            = "0"; ///< S(x, t)
    std::string dirichlet_value   = "0"; ///< C on the constraint layer, (x, t)
    std::string exact_solution    = "";  ///< optional C_ex(x, t) for errors (3.79)
    std::string constants         = "";  ///< muparser constants "a=1, b=2"

    std::string  scheme              = "forward Euler";
    double       time_step           = 0.; ///< 0: 0.9 x the stability bound (explicit)
    double       end_time            = 1.;
    double       linear_tolerance    = 1e-12;
    double       newton_tolerance    = 1e-10;
    unsigned int max_newton_iterations = 10;
    /** "AMG", "Jacobi" or "auto" (Jacobi when dt is within 10x of the explicit bound). */
    std::string preconditioner = "auto";

    /**
     * Quadrature of the operator (subsection Hybrid, dissertation Sect.
     * 3.3): "standard" everywhere, "wls" (WLS collocation on every interior
     * node) or "hybrid" (fixed Omega_s = interior nodes within
     * standard_width of the boundary or where standard_region > 0, WLS
     * elsewhere). Forward Euler, or backward Euler for linear diffusion (the
     * WLS rows in the Jacobian, solved with GMRES).
     */
    std::string   quadrature      = "standard";
    WlsParameters wls;
    double        standard_width  = 0.;
    std::string   standard_region = "0"; ///< expression in x, y, z; > 0: Omega_s

    std::string  output_directory     = "output";
    unsigned int snapshot_interval    = 0; ///< steps between VTU snapshots (0: first+last)
    unsigned int time_series_interval = 1; ///< steps between CSV rows
    unsigned int checkpoint_interval  = 0; ///< steps between checkpoints (0: none)
    bool         resume               = false;
    double       progress_interval    = 10.; ///< seconds between progress lines
    bool         write_node_table     = false;

    /** Declare every entry (subsections Geometry, Discretization, Model, ...). */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate every entry. */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * One row of the time series: time, total mass, Pi = sum C^2 V (eq. 48 of
   * 002), solid volume and, if an exact solution is given, the relative
   * l2 error (3.79).
   */
  struct DiffusionDiagnostics
  {
    double time = 0., mass = 0., pi = 0., solid_volume = 0., error = 0.;
  };

  /**
   * Transient PD diffusion and bi-material corrosion with the standard
   * scheme: forward Euler (3.10) with a checked stability bound, or
   * backward Euler solved by the modified Newton scheme (3.16)-(3.17) with
   * a frozen Jacobian assembled from the lagged bond diffusivities, the
   * linear systems by Trilinos CG (diffusion) or GMRES (corrosion) with ML
   * AMG. Dirichlet values live on the volume constraint layer; homogeneous
   * nonlocal Neumann conditions need no layer. The corrosion phase is
   * updated after each step by (2.79), one way (solid to liquid).
   */
  template <int dim>
  class DiffusionSolver
  {
  public:
    DiffusionSolver(const MPI_Comm comm, const DiffusionRunParameters<dim> &parameters);
    ~DiffusionSolver();

    /** Build the discretization, operator and initial state; check the time step. */
    void
    setup();

    /**
     * March to the end time (or @p max_steps steps of this call, to simulate
     * an interruption), writing output, time series and checkpoints as
     * configured; resumes from the checkpoint if configured.
     */
    void
    run(const unsigned int max_steps = std::numeric_limits<unsigned int>::max());

    /** Advance one step of size dt from the current time. */
    void
    advance();

    /** Diagnostics of the current state. */
    DiffusionDiagnostics
    diagnostics() const;

    /** The time series recorded so far (one row per time_series_interval). */
    const std::vector<DiffusionDiagnostics> &
    history() const
    {
      return recorded;
    }

    /** @name State */
    /** @{ */
    const Discretization<dim> &
    discretization() const
    {
      return disc;
    }
    const DiffusionOperator<dim> &
    get_operator() const
    {
      return *op;
    }
    const Vector &
    solution() const
    {
      return C;
    }
    const Vector &
    phase_field() const
    {
      return phase;
    }
    double
    time() const
    {
      return current_time;
    }
    unsigned int
    step() const
    {
      return current_step;
    }
    double
    time_step() const
    {
      return dt;
    }
    unsigned int
    n_steps() const
    {
      return total_steps;
    }
    /** Forward Euler stability bound of the discrete operator. */
    double
    critical_time_step() const
    {
      return dt_critical;
    }
    /** Hybrid: global number of WLS rows (Omega_w); 0 for the standard scheme. */
    types::global_dof_index
    n_wls_rows() const
    {
      return n_wls_global;
    }
    /** Newton iterations of the last implicit step. */
    unsigned int
    last_newton_iterations() const
    {
      return newton_iterations;
    }
    /** Linear solver iterations of the last implicit step. */
    unsigned int
    last_linear_iterations() const
    {
      return linear_iterations;
    }
    /** @} */

    /** Timer summary (setup, operator, solver, output). */
    TimerOutput &
    timer()
    {
      return computing_timer;
    }

  private:
    void
    setup_quadrature();
    /** Backward Euler with WLS rows: their rows of the matrix become I/dt - w. */
    void
    replace_wls_rows();
    void
    explicit_step();
    void
    implicit_step();
    void
    update_phase();
    void
    apply_dirichlet(Vector &v, const double t);
    void
    record_and_output(const bool force_snapshot);
    void
    write_checkpoint();
    bool
    read_checkpoint();
    std::string
    signature() const;

    MPI_Comm                         mpi_communicator;
    DiffusionRunParameters<dim>      prm;
    ConditionalOStream               pcout;
    TimerOutput                      computing_timer;
    Discretization<dim>              disc;
    std::unique_ptr<DiffusionOperator<dim>> op;

    mutable FunctionParser<dim> source_function, dirichlet_function, exact_function;
    bool                        has_source = false, has_exact = false;

    Vector C, rate, phase;
    double dt = 0., dt_critical = 0., current_time = 0.;
    unsigned int current_step = 0, total_steps = 0;
    types::global_dof_index n_wls_global = 0;
    unsigned int newton_iterations = 0, linear_iterations = 0;

    TrilinosWrappers::SparseMatrix     matrix;
    TrilinosWrappers::PreconditionAMG    amg;
    TrilinosWrappers::PreconditionJacobi jacobi;
    bool                                 use_amg = true;
    bool                               matrix_valid = false;
    std::vector<DiffusionDiagnostics>  recorded;

    struct OutputState;
    std::unique_ptr<OutputState> output;
  };
} // namespace PeriDEAL

#endif
