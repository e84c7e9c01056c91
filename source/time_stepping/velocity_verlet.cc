#include <perideal/base/exceptions.h>
#include <perideal/time_stepping/velocity_verlet.h>

namespace PeriDEAL
{
  template <int dim>
  VelocityVerlet<dim>::VelocityVerlet(BondBasedOperator<dim> &model,
                                      const double            density,
                                      const double            time_step)
    : model(model)
    , disc(model.discretization())
    , rho(density)
    , dt(time_step)
  {
    check_parameter(rho > 0., "Density", rho, "a positive number");
    const double dt_crit = model.critical_time_step(rho);
    check_parameter(dt > 0. && dt <= dt_crit, "Time step", dt,
                    "0 < dt <= " + std::to_string(dt_crit) +
                      " (critical time step (3.8) of the linearized model)");
    for (VectorField *f : {&displacement, &velocity, &acceleration, &body_force, &force})
      model.initialize(*f);
    prescribed_set.assign(disc.n_owned(), -1);
    displacement_set.assign(disc.n_owned(), -1);
  }

  template <int dim>
  void
  VelocityVerlet<dim>::add_prescribed_velocity(const std::vector<bool> &mask,
                                               const Tensor<1, dim>    &v)
  {
    AssertThrow(mask.size() >= disc.n_owned(), ExcMessage("The mask must cover the owned nodes."));
    prescribed_values.push_back(v);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (mask[i])
        {
          prescribed_set[i]   = prescribed_values.size() - 1;
          displacement_set[i] = -1;
        }
  }

  template <int dim>
  void
  VelocityVerlet<dim>::add_prescribed_displacement(
    const std::vector<bool>                                                &mask,
    const std::function<Tensor<1, dim>(const Point<dim> &, const double)> &u)
  {
    AssertThrow(mask.size() >= disc.n_owned(), ExcMessage("The mask must cover the owned nodes."));
    prescribed_displacements.push_back(u);
    displacement_nodes.clear();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (mask[i])
          {
            displacement_set[i] = prescribed_displacements.size() - 1;
            prescribed_set[i]   = -1;
          }
        if (displacement_set[i] >= 0)
          displacement_nodes.push_back(i);
      }
  }

  template <int dim>
  void
  VelocityVerlet<dim>::apply_prescribed_displacements(const double time, const bool set_velocity)
  {
    for (const unsigned int i : displacement_nodes)
      {
        if (displacement_set[i] < 0) // overridden by a later velocity set
          continue;
        const Tensor<1, dim> value = prescribed_displacements[displacement_set[i]](disc.position[i], time);
        for (unsigned int d = 0; d < dim; ++d)
          if (set_velocity) // before the update: v = (u(t) - u^n) / dt
            velocity[d].local_element(i) = (value[d] - displacement[d].local_element(i)) / dt;
          else // after it: exactly u(t), without the round-off of u^n + dt v
            displacement[d].local_element(i) = value[d];
      }
  }

  template <int dim>
  void
  VelocityVerlet<dim>::apply_prescribed_velocities()
  {
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (prescribed_set[i] >= 0)
        for (unsigned int d = 0; d < dim; ++d)
          velocity[d].local_element(i) = prescribed_values[prescribed_set[i]][d];
  }

  template <int dim>
  void
  VelocityVerlet<dim>::update_accelerations()
  {
    for (auto &u : displacement)
      u.update_ghost_values();
    model.compute_forces(displacement, force);
    const double inv_rho = 1. / rho;
    for (unsigned int d = 0; d < dim; ++d)
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        acceleration[d].local_element(i) =
          (prescribed_set[i] >= 0 || displacement_set[i] >= 0) ?
            0. :
            inv_rho * (force[d].local_element(i) + body_force[d].local_element(i));
  }

  template <int dim>
  void
  VelocityVerlet<dim>::initialize()
  {
    apply_prescribed_velocities();
    apply_prescribed_displacements(t, false);
    update_accelerations();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::restart(const unsigned int step, const double time)
  {
    n_steps = step;
    t       = time;
    update_accelerations();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::advance()
  {
    const unsigned int n = disc.n_owned();
    // Held nodes: u^{n+1} from the prescribed function, v = du/dt by the
    // difference quotient (set first: it needs u^n).
    apply_prescribed_displacements(t + dt, true);
    for (unsigned int d = 0; d < dim; ++d)
      {
        double       *u = displacement[d].begin();
        double       *v = velocity[d].begin();
        const double *a = acceleration[d].begin();
        for (unsigned int i = 0; i < n; ++i)
          {
            v[i] += 0.5 * dt * a[i];
            u[i] += dt * v[i];
          }
      }
    apply_prescribed_displacements(t + dt, false);
    update_accelerations();
    for (unsigned int d = 0; d < dim; ++d)
      {
        double       *v = velocity[d].begin();
        const double *a = acceleration[d].begin();
        for (unsigned int i = 0; i < n; ++i)
          v[i] += 0.5 * dt * a[i];
      }
    // Prescribed nodes have a = 0, so their velocity stays as set.
    t += dt;
    ++n_steps;
  }

  template <int dim>
  double
  VelocityVerlet<dim>::kinetic_energy() const
  {
    double e = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double v2 = 0.;
        for (unsigned int d = 0; d < dim; ++d)
          v2 += velocity[d].local_element(i) * velocity[d].local_element(i);
        e += 0.5 * rho * disc.volume[i] * v2;
      }
    return Utilities::MPI::sum(e, disc.get_mpi_communicator());
  }

  template <int dim>
  Tensor<1, dim>
  VelocityVerlet<dim>::linear_momentum() const
  {
    Tensor<1, dim> p;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        p[d] += rho * disc.volume[i] * velocity[d].local_element(i);
    return Utilities::MPI::sum(p, disc.get_mpi_communicator());
  }

  template class VelocityVerlet<1>;
  template class VelocityVerlet<2>;
  template class VelocityVerlet<3>;
} // namespace PeriDEAL
