#ifndef perideal_time_stepping_velocity_verlet_h
#define perideal_time_stepping_velocity_verlet_h

#include <deal.II/base/tensor.h>

#include <perideal/models/bond_based.h>
#include <perideal/models/lps.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * What an explicit mechanics run needs from a PD solid model: forces,
   * energies, damage, broken-bond flags (for pre-cracks and checkpoints) and
   * the critical time step. Implemented by MechanicsModelAdapter for the
   * bond-based (PMB/GPBM) and the LPS operators, which keep their own
   * non-virtual force loops.
   */
  template <int dim>
  class MechanicsModel
  {
  public:
    using VectorField = std::array<Vector, dim>;

    virtual ~MechanicsModel() = default;

    /** The discretization. */
    virtual const Discretization<dim> &
    discretization() const = 0;
    /** Zero-initialized dim node Vectors. */
    virtual void
    initialize(VectorField &field) const = 0;
    /** Force density of the owned nodes (u with up-to-date ghosts); may break bonds. */
    virtual void
    compute_forces(const VectorField &u, VectorField &force) = 0;
    /** Strain energy density W_i ((2.26) bond-based, (2.14) LPS) of the owned nodes. */
    virtual void
    strain_energy_density(const VectorField &u, Vector &W) const = 0;
    /** sum_i W_i V_i over all ranks. */
    virtual double
    total_strain_energy(const VectorField &u) const = 0;
    /** Damage (2.36) of the owned nodes. */
    virtual void
    damage(Vector &phi) const = 0;
    /** Broken flag per CSR bond of the owned rows. */
    virtual const std::vector<std::uint8_t> &
    broken() const = 0;
    /** Replace the broken flags (both copies of a bond must agree). */
    virtual void
    set_broken_flags(const std::vector<std::uint8_t> &flags) = 0;
    /** Global number of broken bond copies. */
    virtual std::uint64_t
    n_broken_bonds() const = 0;
    /** Break the bonds crossing a pre-crack polygon (2D: segment). */
    virtual void
    add_precrack(const std::vector<Point<dim>> &polygon) = 0;
    /** Critical time step of the explicit scheme for density @p rho. */
    virtual double
    critical_time_step(const double rho) const = 0;
    /** Critical stretch (infinity: no breaking). */
    virtual double
    critical_stretch() const = 0;
    /** One line naming the model and its constants (log, checkpoint signature). */
    virtual std::string
    description() const = 0;
  };

  /** Adapter for BondBasedOperator. */
  template <int dim>
  std::unique_ptr<MechanicsModel<dim>>
  make_mechanics_model(BondBasedOperator<dim> &op);
  /** Adapter for LinearizedLPSOperator (2D/3D). */
  template <int dim>
  std::unique_ptr<MechanicsModel<dim>>
  make_mechanics_model(LinearizedLPSOperator<dim> &op);

  /**
   * Velocity-Verlet integration (3.5)-(3.6) of PD elasticity
   * rho u'' = F(u) + b (any MechanicsModel):
   *   v^{n+1/2} = v^n + dt/2 a^n,  u^{n+1} = u^n + dt v^{n+1/2},
   *   v^{n+1} = v^{n+1/2} + dt/2 a^{n+1},
   * with a = (F + b) / rho. Nodes of a prescribed-velocity set move with
   * their given velocity v(x, t): u^{n+1} = u^n + dt v(t^{n+1/2}) (exact for
   * v linear in t) and v^{n+1} = v(t^{n+1}); nodes of a prescribed-
   * displacement set follow u(x, t). The kinematic acceleration of held
   * nodes (central differences of the prescribed motion, see
   * held_acceleration) does not enter the update but the reaction forces.
   * A time-dependent body force (tractions) is re-evaluated at t^{n+1}
   * before each force evaluation. The displacement ghosts are refreshed
   * once per step, before the force evaluation.
   */
  template <int dim>
  class VelocityVerlet
  {
  public:
    using VectorField = typename MechanicsModel<dim>::VectorField;

    /**
     * @p density rho (> 0) and time step @p time_step, which must not exceed
     * the critical step of @p model (else ParameterError naming
     * 'Time step'). u, v, a and the body force start at zero.
     */
    VelocityVerlet(MechanicsModel<dim> &model, const double density, const double time_step);
    /** The same for a bond-based operator (critical step (3.8)). */
    VelocityVerlet(BondBasedOperator<dim> &model, const double density, const double time_step);

    /** Displacement, velocity, acceleration (owned entries; u has ghosts). */
    VectorField displacement, velocity, acceleration;
    /** Body force per unit volume b (owned entries). */
    VectorField body_force;

    /**
     * Nodes i < n_owned() with @p mask[i] true move with velocity @p v
     * from now on (a later set overrides an earlier one on shared nodes).
     */
    void
    add_prescribed_velocity(const std::vector<bool> &mask, const Tensor<1, dim> &v);
    /** The same with a velocity v(x, t). */
    void
    add_prescribed_velocity(
      const std::vector<bool>                                                &mask,
      const std::function<Tensor<1, dim>(const Point<dim> &, const double)> &v);

    /**
     * Evaluate the body force b(t) with @p f(t, body_force) before every
     * force evaluation (also now, at the current time).
     */
    void
    set_body_force_function(const std::function<void(const double, VectorField &)> &f);

    /**
     * The acceleration of held node @p i < n_owned() at the current time t^n
     * from its prescribed motion: (u(t+dt) - 2 u(t) + u(t-dt)) / dt^2 for a
     * displacement set, (v(t+dt/2) - v(t-dt/2)) / dt for a velocity set (the
     * second differences Verlet's own velocities satisfy); zero for free
     * nodes. rho V times this is the inertia term of a reaction force.
     */
    Tensor<1, dim>
    held_acceleration(const unsigned int i) const;

    /** True if owned node @p i is held by a prescribed velocity or displacement. */
    bool
    is_held(const unsigned int i) const
    {
      return prescribed_set[i] >= 0 || displacement_set[i] >= 0;
    }

    /** Density rho. */
    double
    density() const
    {
      return rho;
    }

    /**
     * Nodes i < n_owned() with @p mask[i] true follow the displacement
     * @p u(x, t) from now on: after each step u_i = u(x_i, t^{n+1}) and
     * v_i = (u_i^{n+1} - u_i^n) / dt (a later set, of either kind, overrides
     * an earlier one on shared nodes).
     */
    void
    add_prescribed_displacement(
      const std::vector<bool>                                                &mask,
      const std::function<Tensor<1, dim>(const Point<dim> &, const double)> &u);

    /** The internal force density F (owned entries) of the last evaluation. */
    const VectorField &
    internal_force() const
    {
      check_node_vectors_current();
      return force;
    }

    /**
     * Continue from a state read from a checkpoint: set the step counter and
     * time, refresh the displacement ghosts and recompute a from u (the
     * broken flags of the model must have been restored first).
     */
    void
    restart(const unsigned int step, const double time);

    /**
     * Apply the prescribed velocities and compute a^0 from the current
     * displacement (call after setting initial conditions).
     */
    void
    initialize();

    /** One Verlet step. */
    void
    advance();

    /**
     * @p n Verlet steps: the same as n calls of advance() (bitwise the same
     * state). With a bond-based model on the lattice sweep
     * (BondBasedOperator::uses_lattice_sweep()) and n > 1, the state stays
     * in the sweep's box layout during the n steps: the half-kick and drift
     * run as one pass over the box, the second half-kick is fused with the
     * sweep's per-chunk force output, and only the ghost layer is exchanged
     * through the node vectors. displacement, velocity, acceleration and
     * internal_force() are node-ordered again when the call returns, so
     * output, energies, reaction forces and checkpoints between calls are
     * unaffected.
     */
    void
    advance(const unsigned int n);

    /** True if advance(n) with n > 1 keeps the state in the sweep's box layout. */
    bool
    uses_box_state() const
    {
      return sweep_model != nullptr && sweep_model->uses_lattice_sweep();
    }

    /**
     * Opt-in (default off): with @p defer true, advance(n) on the box state
     * (uses_box_state(), n > 1) leaves the state in the box layout when it
     * returns, and the next such call continues from it, without the
     * conversions into and out of node order (one pass each over u, v, a
     * and F per call). Until sync_node_vectors() the node vectors
     * displacement, velocity, acceleration and internal_force() are stale:
     * kinetic_energy(), linear_momentum(), strain_energy() and
     * internal_force() throw, and a caller that reads or writes the public
     * vectors directly must call sync_node_vectors() first. advance(),
     * add_prescribed_velocity() and add_prescribed_displacement() sync
     * themselves; initialize() and restart() take the node vectors as the
     * state (they are called after setting them). The results are bitwise
     * those of advance(n) without deferral. @p defer false syncs.
     */
    void
    set_deferred_node_sync(const bool defer);

    /**
     * Write the box state back to the node vectors if they are stale (see
     * set_deferred_node_sync()); the next advance(n) reloads the box from
     * them, so the caller may then also modify them.
     */
    void
    sync_node_vectors();

    /** False between an advance(n) with deferred sync and sync_node_vectors(). */
    bool
    node_vectors_current() const
    {
      return !node_vectors_stale;
    }

    /** The critical time step (3.8) of the model for this density. */
    double
    critical_time_step() const
    {
      return model.critical_time_step(rho);
    }

    double
    time() const
    {
      return t;
    }
    unsigned int
    step() const
    {
      return n_steps;
    }
    double
    time_step() const
    {
      return dt;
    }

    /** sum_i rho V_i |v_i|^2 / 2 over all ranks. */
    double
    kinetic_energy() const;
    /** The model's total strain energy at the current displacement. */
    double
    strain_energy() const
    {
      check_node_vectors_current();
      return model.total_strain_energy(displacement);
    }
    /** sum_i rho V_i v_i over all ranks. */
    Tensor<1, dim>
    linear_momentum() const;

  private:
    /** Checks and field initialization of the constructors. */
    void
    setup();
    void
    update_accelerations();
    /** The owned nodes with a prescribed velocity (increasing). */
    std::vector<unsigned int>
    velocity_held_nodes() const;
    /** The held-velocity nodes @p nodes (velocity_held_nodes()) get v(x, @p time). */
    void
    apply_prescribed_velocities(const double time, const std::vector<unsigned int> &nodes);

    /** The adapter of the BondBasedOperator constructor (declared before model). */
    std::unique_ptr<MechanicsModel<dim>> owned_model;
    MechanicsModel<dim>                 &model;
    const Discretization<dim>           &disc;
    double                     rho, dt, t = 0.;
    unsigned int               n_steps = 0;
    VectorField                force;
    /** Per owned node: index into prescribed_values, or -1. */
    std::vector<int> prescribed_set;
    std::vector<std::function<Tensor<1, dim>(const Point<dim> &, const double)>> prescribed_values;
    std::function<void(const double, VectorField &)>                          body_force_function;
    /** Per owned node: index into prescribed_displacements, or -1. */
    std::vector<int> displacement_set;
    std::vector<std::function<Tensor<1, dim>(const Point<dim> &, const double)>>
      prescribed_displacements;
    /** Owned nodes with a prescribed displacement. */
    std::vector<unsigned int> displacement_nodes;
    void
    apply_prescribed_displacements(const double time, const bool set_velocity);

    /** The bond-based operator behind model (nullptr for other models). */
    BondBasedOperator<dim> *sweep_model = nullptr;
    /**
     * The box state of advance(n): per component (stride
     * lattice_sweep_stride()) displacement, velocity, a^n then internal
     * force, body force, deformed position and reference position x - x_c;
     * per position 2 (free owned node), 1 (held owned node) or 0.
     */
    // Each at its own page offset (PageOffsetAllocator): the kicks stream
    // over all six in step, the sweep reads box_p next to its reactions
    // (page offset 2048).
    PageOffsetVector box_u{PageOffsetAllocator<double>(512)},
      box_v{PageOffsetAllocator<double>(1024)}, box_f{PageOffsetAllocator<double>(1536)},
      box_b{PageOffsetAllocator<double>(2560)}, box_p{PageOffsetAllocator<double>(0)},
      box_x{PageOffsetAllocator<double>(3072)};
    std::vector<std::uint8_t> box_kind;
    /** box_b holds a body force (else it is zero). */
    bool box_b_nonzero = false;
    /** set_deferred_node_sync(). */
    bool defer_node_sync = false;
    /**
     * The box arrays hold the state (u, v, F, b, p) after the last step
     * (a deferred advance(n)), and nothing has touched the node vectors
     * since: the next advance(n) starts from the box.
     */
    bool box_current = false;
    /** The node vectors lag behind the box state (deferred sync). */
    bool node_vectors_stale = false;
    /** Throw if node_vectors_stale. */
    void
    check_node_vectors_current() const;
    /** Box state -> displacement, velocity, internal force, acceleration. */
    void
    unload_box();
    /**
     * Allocate the box arrays and box_x once (from initialize() and
     * restart(), so that the first advance(n) does not pay for it).
     */
    void
    allocate_box();
    /** advance(n) in the box layout. */
    void
    advance_in_box(const unsigned int n);
  };
} // namespace PeriDEAL

#endif
