#ifndef perideal_time_stepping_velocity_verlet_h
#define perideal_time_stepping_velocity_verlet_h

#include <deal.II/base/tensor.h>

#include <perideal/models/bond_based.h>

#include <functional>
#include <vector>

namespace PeriDEAL
{
  /**
   * Velocity-Verlet integration (3.5)-(3.6) of bond-based PD elasticity
   * rho u'' = F(u) + b:
   *   v^{n+1/2} = v^n + dt/2 a^n,  u^{n+1} = u^n + dt v^{n+1/2},
   *   v^{n+1} = v^{n+1/2} + dt/2 a^{n+1},
   * with a = (F + b) / rho. Nodes of a prescribed-velocity set move with
   * their given velocity (their acceleration is zero). The displacement
   * ghosts are refreshed once per step, before the force evaluation.
   */
  template <int dim>
  class VelocityVerlet
  {
  public:
    using VectorField = typename BondBasedOperator<dim>::VectorField;

    /**
     * @p density rho (> 0) and time step @p time_step, which must not exceed
     * the critical step (3.8) of @p model (else ParameterError naming
     * 'Time step'). u, v, a and the body force start at zero.
     */
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
      return model.total_strain_energy(displacement);
    }
    /** sum_i rho V_i v_i over all ranks. */
    Tensor<1, dim>
    linear_momentum() const;

  private:
    void
    update_accelerations();
    void
    apply_prescribed_velocities();

    BondBasedOperator<dim>    &model;
    const Discretization<dim> &disc;
    double                     rho, dt, t = 0.;
    unsigned int               n_steps = 0;
    VectorField                force;
    /** Per owned node: index into prescribed_values, or -1. */
    std::vector<int>            prescribed_set;
    std::vector<Tensor<1, dim>> prescribed_values;
    /** Per owned node: index into prescribed_displacements, or -1. */
    std::vector<int> displacement_set;
    std::vector<std::function<Tensor<1, dim>(const Point<dim> &, const double)>>
      prescribed_displacements;
    /** Owned nodes with a prescribed displacement. */
    std::vector<unsigned int> displacement_nodes;
    void
    apply_prescribed_displacements(const double time, const bool set_velocity);
  };
} // namespace PeriDEAL

#endif
