#ifndef perideal_time_stepping_mechanics_solver_h
#define perideal_time_stepping_mechanics_solver_h

#include <deal.II/base/function_parser.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/hybrid_bond_based.h>
#include <perideal/models/lps.h>
#include <perideal/time_stepping/velocity_verlet.h>

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  template <int dim>
  class NodeOutput;
  class TimeSeries;

  /**
   * Everything an explicit PD run reads from its parameter file:
   * geometry and discretization (shared with the diffusion runs), the
   * model (Mechanics/Model: bond-based with Model/Bond-based, or LPS with
   * Model/LPS), density, initial displacement and velocity, body
   * force, prescribed-velocity and prescribed-displacement regions,
   * tractions and pre-cracks (Mechanics), the measurements taken from the
   * damage and energy fields (Measurements), time stepping and output.
   */
  template <int dim>
  struct MechanicsRunParameters
  {
    /** A node set {level set <= 0} with dim expressions "f1; f2[; f3]". */
    struct Region
    {
      std::string level_set, value;
      /** Layer thickness of a traction (0 otherwise). */
      double thickness = 0.;
    };

    std::shared_ptr<Domain<dim>> domain;
    LatticeParameters            lattice;
    /** "bond-based" or "LPS". */
    std::string                  model_type = "bond-based";
    BondBasedModelParameters     model;
    LPSModelParameters           lps;
    double                       density = 1.;
    /** Initial displacement (empty: zero), velocity and body force expressions. */
    std::string                  initial_displacement, initial_velocity, body_force;
    /** Velocities v(x, t) (expressions in x, y, z, t). */
    std::vector<Region> prescribed_velocities;
    /** Displacements u(x, t) (expressions in x, y, z, t). */
    std::vector<Region> prescribed_displacements;
    /**
     * Tractions T(x, t) (force per area), applied as the body force T / h in
     * a layer of thickness h.
     */
    std::vector<Region> tractions;
    /** 2D pre-crack segments (a, b). */
    std::vector<std::vector<Point<dim>>> precracks;

    /** @name Adaptive hybrid configuration (Mechanics/Hybrid, Sect. 3.3) */
    /** @{ */
    /** "standard" or "hybrid adaptive". */
    std::string               quadrature = "standard";
    HybridMechanicsParameters hybrid;
    /**
     * Initial Omega_s: interior nodes within boundary_width delta of the
     * boundary, within precrack_width delta of a pre-crack segment (2D), or
     * where the expression standard_region is > 0.
     */
    double      boundary_width = 1., precrack_width = 2.;
    std::string standard_region = "0";
    /** @} */

    /** @name Measurements */
    /** @{ */
    /** Crack measurement on if true: origin (pre-crack tip) of the crack path. */
    bool        measure_crack = false;
    Point<dim>  crack_origin;
    /** Nodes considered for the crack path: {level set <= 0}; empty: all. */
    std::string crack_region;
    double      damage_threshold = 0.35;
    /** Nodes within [r_min, r_max] of the origin enter the angle fit. */
    double      crack_fit_min_radius = 0., crack_fit_max_radius = std::numeric_limits<double>::max();
    /** Energy circle (ball) center and radius; radius 0: off. */
    Point<dim>  energy_center;
    double      energy_radius = 0.;
    /** @} */

    double       time_step = 0., end_time = 1.;
    std::string  output_directory = "output";
    unsigned int snapshot_interval = 0, time_series_interval = 1, checkpoint_interval = 0;
    bool         resume           = false;
    bool         write_node_table = false;
    double       progress_interval = 10.;

    /** Declare the mechanics entries (Geometry etc. are declared elsewhere). */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate; throws ParameterError naming the entry. */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * What MechanicsSolver measures from the damage, displacement and
   * velocity fields at one time (all global, identical on every rank).
   */
  struct MechanicsMeasurements
  {
    /**
     * Angle (degrees, in [0, 180)) to the x axis of the total-least-squares
     * line through the nodes of the crack region with damage >= threshold
     * at distance [r_min, r_max] from the crack origin (volume weighted);
     * NaN with fewer than 3 such nodes.
     */
    double crack_angle = 0.;
    /** Number of nodes in that fit. */
    unsigned long n_crack_nodes = 0;
    /** Largest distance from the origin of a node of the crack region with damage >= threshold. */
    double crack_length = 0.;
    /** Kinetic and strain energy of the nodes in the energy circle. */
    double circle_kinetic_energy = 0., circle_strain_energy = 0.;
    /** Kinetic and strain energy of the whole body. */
    double kinetic_energy = 0., strain_energy = 0.;
    /** Largest damage. */
    double max_damage = 0.;
  };

  /**
   * Dynamic PD (bond-based PMB/GPBM with brittle fracture or linearized,
   * or the linearized state-based LPS with bond breaking) with velocity
   * Verlet: the run behind `perideal` with
   * `Problem = mechanics`. Writes displacement, velocity and damage to
   * VTU and to the CSV time series: kinetic/strain energy, broken bonds,
   * maximum damage, the reaction force of every prescribed region, the
   * crack measurements (angle, length, tip speed), the energy in a circle
   * and the wall time. Checkpoints (displacement and velocity keyed by node
   * id, broken bonds keyed by the ids of their end points) restart on any
   * number of ranks.
   */
  template <int dim>
  class MechanicsSolver
  {
  public:
    MechanicsSolver(const MPI_Comm comm, const MechanicsRunParameters<dim> &parameters);
    ~MechanicsSolver();

    /** Build the lattice, model, integrator and initial state. */
    void
    setup();

    /**
     * March to the end time (at most @p max_steps steps of this call; calls
     * continue where the last one stopped). The first call resumes from
     * the checkpoint if asked to, creates the output directory and records
     * the initial state.
     */
    void
    run(const unsigned int max_steps = std::numeric_limits<unsigned int>::max());

    /** @name State */
    /** @{ */
    const Discretization<dim> &
    discretization() const
    {
      return disc;
    }
    /** The model (bond-based or LPS) behind a common interface. */
    const MechanicsModel<dim> &
    model() const
    {
      return *op;
    }
    const VelocityVerlet<dim> &
    integrator() const
    {
      return *verlet;
    }
    /** Kinetic + strain energy. */
    double
    total_energy() const;
    /** The measurements at the current time. Collective. */
    MechanicsMeasurements
    measure() const;
    /**
     * Reaction force of prescribed region @p k (velocity regions first, then
     * displacement regions): the force the supports exert on the body,
     * sum_i (rho a_i - F_i - b_i) V_i over the nodes held by region k, with
     * a_i their acceleration from the prescribed motion
     * (VelocityVerlet::held_acceleration; zero for constant velocities),
     * so that the force balance of the held nodes closes. Collective.
     */
    Tensor<1, dim>
    reaction_force(const unsigned int k) const;
    /** The adaptive hybrid model, or nullptr for the standard scheme. */
    const HybridBondBasedModel<dim> *
    hybrid_model() const
    {
      return hybrid;
    }
    /** Number of prescribed regions. */
    unsigned int
    n_prescribed_regions() const
    {
      return prm.prescribed_velocities.size() + prm.prescribed_displacements.size();
    }
    /** Wall time of the time steps of run() (without output). */
    double
    stepping_wall_time() const
    {
      return stepping_time;
    }
    /**
     * Bond updates (bonds of all rows x steps) per second per MPI rank of
     * the time steps of run(), with this rank's stepping time. Not
     * collective.
     */
    double
    bond_updates_per_second_per_core() const;
    /** The rows written to the CSV time series (identical on all ranks). */
    const std::vector<std::vector<double>> &
    time_series() const
    {
      return series_rows;
    }
    /** The CSV column names. */
    std::vector<std::string>
    time_series_columns() const;
    /** @} */

  private:
    /** Initial Omega_s of the adaptive hybrid configuration (per owned node). */
    std::vector<bool>
    initial_standard_region() const;
    std::string
    signature() const;
    void
    write_checkpoint() const;
    bool
    read_checkpoint();
    /** Add a CSV row (and a VTU snapshot if @p snapshot). */
    void
    record(const bool snapshot);

    MPI_Comm                                mpi_communicator;
    MechanicsRunParameters<dim>             prm;
    Discretization<dim>                     disc;
    std::unique_ptr<BondBasedOperator<dim>> bond_based;
    /** LPS (dim >= 2); std::nullptr_t-like void in 1D. */
    std::unique_ptr<std::conditional_t<(dim >= 2), LinearizedLPSOperator<(dim >= 2 ? dim : 2)>, int>>
                                           lps;
    std::unique_ptr<MechanicsModel<dim>>   op;
    /** op as the adaptive hybrid model (Quadrature = hybrid adaptive), else nullptr. */
    HybridBondBasedModel<dim>             *hybrid = nullptr;
    std::unique_ptr<VelocityVerlet<dim>>    verlet;
    unsigned int                            total_steps = 0;
    std::uint64_t                           n_global_bonds = 0;
    /** Per owned node: the prescribed region holding it, or -1. */
    std::vector<int> held_by;
    /** Nodes counted by the crack measurement / the energy circle. */
    std::vector<bool> in_crack_region, in_energy_circle;
    double            stepping_time = 0.;
    unsigned int      stepped       = 0;
    std::vector<std::vector<double>> series_rows;
    /** Output, created by the first run(). */
    std::unique_ptr<NodeOutput<dim>> vtu;
    std::unique_ptr<TimeSeries>      csv;
    Timer                            wall;
    double                           wall_offset = 0., last_progress = 0.;
  };
} // namespace PeriDEAL

#endif
