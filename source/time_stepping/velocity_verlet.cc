#include <perideal/base/exceptions.h>
#include <perideal/time_stepping/velocity_verlet.h>

#include <cmath>

#include <sstream>
#include <type_traits>

namespace PeriDEAL
{
  namespace
  {
    /**
     * a = (f + b) / rho, the one expression of every acceleration update
     * (node vectors, fused half-kick, box path), so that all of them give
     * bitwise the same value.
     */
    inline double
    acceleration_of(const double f, const double b, const double inv_rho)
    {
      return inv_rho * (f + b);
    }

    // The MechanicsModel of an operator held by reference. The bond-based
    // and LPS operators share these member names.
    template <int dim, class Operator>
    class Adapter : public MechanicsModel<dim>
    {
    public:
      using VectorField = typename MechanicsModel<dim>::VectorField;
      explicit Adapter(Operator &op)
        : op(op)
      {}
      const Discretization<dim> &
      discretization() const override
      {
        return op.discretization();
      }
      void
      initialize(VectorField &f) const override
      {
        op.initialize(f);
      }
      void
      compute_forces(const VectorField &u, VectorField &f) override
      {
        op.compute_forces(u, f);
      }
      void
      strain_energy_density(const VectorField &u, Vector &W) const override
      {
        op.strain_energy_density(u, W);
      }
      double
      total_strain_energy(const VectorField &u) const override
      {
        return op.total_strain_energy(u);
      }
      void
      damage(Vector &phi) const override
      {
        op.damage(phi);
      }
      const std::vector<std::uint8_t> &
      broken() const override
      {
        return op.broken();
      }
      void
      set_broken_flags(const std::vector<std::uint8_t> &flags) override
      {
        op.set_broken_flags(flags);
      }
      std::uint64_t
      n_broken_bonds() const override
      {
        return op.n_broken_bonds();
      }
      void
      add_precrack(const std::vector<Point<dim>> &polygon) override
      {
        if constexpr (std::is_same_v<Operator, BondBasedOperator<dim>>)
          op.add_precrack(polygon);
        else
          {
            // The bond-based operator's crossing test on the same lattice,
            // then its flags merged into the LPS ones.
            BondBasedModelParameters bp;
            BondBasedOperator<dim>   cut(op.discretization(), bp);
            cut.add_precrack(polygon);
            std::vector<std::uint8_t> flags = op.broken();
            for (std::size_t b = 0; b < flags.size(); ++b)
              flags[b] |= cut.broken()[b];
            op.set_broken_flags(flags);
          }
      }
      double
      critical_time_step(const double rho) const override
      {
        return op.critical_time_step(rho);
      }
      double
      critical_stretch() const override
      {
        return op.critical_stretch();
      }
      std::string
      description() const override
      {
        std::ostringstream s;
        s.precision(16);
        if constexpr (std::is_same_v<Operator, BondBasedOperator<dim>>)
          s << "bond-based c = " << op.micromodulus();
        else
          s << "LPS K_d = " << op.dimensional_bulk_modulus() << " G = " << op.shear_modulus();
        s << " s0 = " << op.critical_stretch();
        return s.str();
      }

      /** The wrapped operator. */
      Operator &
      wrapped() const
      {
        return op;
      }

    private:
      Operator &op;
    };
  } // namespace

  template <int dim>
  std::unique_ptr<MechanicsModel<dim>>
  make_mechanics_model(BondBasedOperator<dim> &op)
  {
    return std::make_unique<Adapter<dim, BondBasedOperator<dim>>>(op);
  }

  template <int dim>
  std::unique_ptr<MechanicsModel<dim>>
  make_mechanics_model(LinearizedLPSOperator<dim> &op)
  {
    return std::make_unique<Adapter<dim, LinearizedLPSOperator<dim>>>(op);
  }

  template <int dim>
  VelocityVerlet<dim>::VelocityVerlet(BondBasedOperator<dim> &op,
                                      const double            density,
                                      const double            time_step)
    : owned_model(make_mechanics_model(op))
    , model(*owned_model)
    , disc(op.discretization())
    , rho(density)
    , dt(time_step)
    , sweep_model(&op)
  {
    setup();
  }

  template <int dim>
  VelocityVerlet<dim>::VelocityVerlet(MechanicsModel<dim> &model,
                                      const double         density,
                                      const double         time_step)
    : model(model)
    , disc(model.discretization())
    , rho(density)
    , dt(time_step)
  {
    if (auto *a = dynamic_cast<Adapter<dim, BondBasedOperator<dim>> *>(&model))
      sweep_model = &a->wrapped();
    setup();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::setup()
  {
    check_parameter(rho > 0., "Density", rho, "a positive number");
    const double dt_crit = model.critical_time_step(rho);
    check_parameter(dt > 0. && dt <= dt_crit, "Time step", dt,
                    "0 < dt <= " + std::to_string(dt_crit) +
                      " (critical time step of the linearized model)");
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
    add_prescribed_velocity(mask, [v](const Point<dim> &, const double) { return v; });
  }

  template <int dim>
  void
  VelocityVerlet<dim>::set_body_force_function(
    const std::function<void(const double, VectorField &)> &f)
  {
    body_force_function = f;
    if (f)
      f(t, body_force);
  }

  template <int dim>
  Tensor<1, dim>
  VelocityVerlet<dim>::held_acceleration(const unsigned int i) const
  {
    Tensor<1, dim> a;
    const Point<dim> &x = disc.position[i];
    if (displacement_set[i] >= 0)
      {
        const auto &u = prescribed_displacements[displacement_set[i]];
        a = (u(x, t + dt) - 2. * u(x, t) + u(x, t - dt)) / (dt * dt);
      }
    else if (prescribed_set[i] >= 0)
      {
        const auto &v = prescribed_values[prescribed_set[i]];
        a = (v(x, t + 0.5 * dt) - v(x, t - 0.5 * dt)) / dt;
      }
    return a;
  }

  template <int dim>
  void
  VelocityVerlet<dim>::add_prescribed_velocity(
    const std::vector<bool>                                                &mask,
    const std::function<Tensor<1, dim>(const Point<dim> &, const double)> &v)
  {
    AssertThrow(mask.size() >= disc.n_owned(), ExcMessage("The mask must cover the owned nodes."));
    // A node that becomes held starts from the node vectors' state.
    sync_node_vectors();
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
    sync_node_vectors();
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
  std::vector<unsigned int>
  VelocityVerlet<dim>::velocity_held_nodes() const
  {
    std::vector<unsigned int> nodes;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (prescribed_set[i] >= 0)
        nodes.push_back(i);
    return nodes;
  }

  template <int dim>
  void
  VelocityVerlet<dim>::apply_prescribed_velocities(const double                     time,
                                                   const std::vector<unsigned int> &nodes)
  {
    for (const unsigned int i : nodes)
      {
        const Tensor<1, dim> v = prescribed_values[prescribed_set[i]](disc.position[i], time);
        for (unsigned int d = 0; d < dim; ++d)
          velocity[d].local_element(i) = v[d];
      }
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
            acceleration_of(force[d].local_element(i), body_force[d].local_element(i), inv_rho);
  }

  template <int dim>
  void
  VelocityVerlet<dim>::check_node_vectors_current() const
  {
    AssertThrow(!node_vectors_stale,
                ExcMessage("VelocityVerlet: the node vectors are stale (deferred node sync); "
                           "call sync_node_vectors() first."));
  }

  template <int dim>
  void
  VelocityVerlet<dim>::set_deferred_node_sync(const bool defer)
  {
    defer_node_sync = defer;
    if (!defer)
      sync_node_vectors();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::sync_node_vectors()
  {
    if (node_vectors_stale)
      unload_box();
    node_vectors_stale = false;
    box_current        = false;
  }

  template <int dim>
  void
  VelocityVerlet<dim>::initialize()
  {
    // The caller has set the node vectors: they are the state.
    node_vectors_stale = false;
    box_current        = false;
    apply_prescribed_velocities(t, velocity_held_nodes());
    apply_prescribed_displacements(t, false);
    update_accelerations();
    allocate_box();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::restart(const unsigned int step, const double time)
  {
    node_vectors_stale = false;
    box_current        = false;
    n_steps = step;
    t       = time;
    if (body_force_function)
      body_force_function(t, body_force);
    update_accelerations();
    allocate_box();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::advance()
  {
    advance(1);
  }

  template <int dim>
  void
  VelocityVerlet<dim>::advance(const unsigned int n)
  {
    if (n > 1 && uses_box_state())
      {
        advance_in_box(n);
        return;
      }
    // What does not change within the call is read once, not per step:
    // the held nodes, the velocity-held nodes (both increasing) and whether
    // b is +0 everywhere without a body force function (a -0 would change
    // the sign of a zero force sum).
    sync_node_vectors();
    const unsigned int              n_owned       = disc.n_owned();
    const std::vector<unsigned int> velocity_held = velocity_held_nodes();
    std::vector<unsigned int>       held;
    for (unsigned int i = 0; i < n_owned; ++i)
      if (is_held(i))
        held.push_back(i);
    bool zero_body = !body_force_function;
    for (unsigned int d = 0; d < dim && zero_body; ++d)
      for (unsigned int i = 0; i < n_owned; ++i)
        {
          const double b = body_force[d].local_element(i);
          zero_body      = zero_body && b == 0. && !std::signbit(b);
        }
    std::vector<double> held_velocity(held.size());
    const double inv_rho = 1. / rho;
    for (unsigned int s = 0; s < n; ++s)
      {
        sync_node_vectors();
        // Held nodes: u^{n+1} from the prescribed function, v = du/dt by
        // the difference quotient (set first: it needs u^n); velocity sets
        // drift with the midpoint velocity.
        apply_prescribed_displacements(t + dt, true);
        apply_prescribed_velocities(t + 0.5 * dt, velocity_held);
        for (unsigned int d = 0; d < dim; ++d)
          {
            double       *u = displacement[d].begin();
            double       *v = velocity[d].begin();
            const double *a = acceleration[d].begin();
            for (unsigned int i = 0; i < n_owned; ++i)
              {
                v[i] += 0.5 * dt * a[i];
                u[i] += dt * v[i];
              }
          }
        apply_prescribed_displacements(t + dt, false);
        apply_prescribed_velocities(t + dt, velocity_held);
        if (body_force_function)
          body_force_function(t + dt, body_force);
        for (auto &u : displacement)
          u.update_ghost_values();
        model.compute_forces(displacement, force);
        // a = (f + b) / rho (update_accelerations()) and the second
        // half-kick in one pass. Held nodes have a = 0: their v gets
        // v + 0.5 dt 0 as in the separate passes (also for v = -0).
        for (unsigned int d = 0; d < dim; ++d)
          {
            double       *v = velocity[d].begin();
            double       *a = acceleration[d].begin();
            const double *f = force[d].begin();
            const double *b = body_force[d].begin();
            for (std::size_t k = 0; k < held.size(); ++k)
              held_velocity[k] = v[held[k]];
            if (zero_body)
              for (unsigned int i = 0; i < n_owned; ++i)
                {
                  a[i] = acceleration_of(f[i], 0., inv_rho);
                  v[i] += 0.5 * dt * a[i];
                }
            else
              for (unsigned int i = 0; i < n_owned; ++i)
                {
                  a[i] = acceleration_of(f[i], b[i], inv_rho);
                  v[i] += 0.5 * dt * a[i];
                }
            for (std::size_t k = 0; k < held.size(); ++k)
              {
                a[held[k]] = 0.;
                v[held[k]] = held_velocity[k] + 0.5 * dt * 0.;
              }
          }
        t += dt;
        ++n_steps;
      }
  }

  template <int dim>
  void
  VelocityVerlet<dim>::advance_in_box(const unsigned int n_now)
  {
    BondBasedOperator<dim>           &op      = *sweep_model;
    const std::size_t                 N       = op.lattice_sweep_stride();
    const std::vector<std::uint32_t> &pos     = op.lattice_sweep_positions();
    const unsigned int                n_owned = disc.n_owned();
    const std::size_t                 n_local = disc.position.size();
    const double                      inv_rho = 1. / rho;
    const bool parallel = Utilities::MPI::n_mpi_processes(disc.get_mpi_communicator()) > 1;

    allocate_box();
    box_kind.assign(N, 0);
    for (unsigned int i = 0; i < n_owned; ++i)
      box_kind[pos[i]] = is_held(i) ? 1 : 2;
    bool has_body = bool(body_force_function);
    for (unsigned int d = 0; d < dim; ++d)
      for (unsigned int i = 0; i < n_owned; ++i)
        has_body = has_body || body_force[d].local_element(i) != 0.;
    std::vector<unsigned int> velocity_nodes;
    for (unsigned int i = 0; i < n_owned; ++i)
      if (prescribed_set[i] >= 0)
        velocity_nodes.push_back(i);

    // Held nodes before (at time t of the step) and after the drift, as
    // in advance().
    const auto held_before_drift = [&](const double time) {
      for (const unsigned int i : displacement_nodes)
        if (displacement_set[i] >= 0)
          {
            const Tensor<1, dim> value =
              prescribed_displacements[displacement_set[i]](disc.position[i], time + dt);
            for (unsigned int d = 0; d < dim; ++d)
              box_v[d * N + pos[i]] = (value[d] - box_u[d * N + pos[i]]) / dt;
          }
      for (const unsigned int i : velocity_nodes)
        {
          const Tensor<1, dim> v =
            prescribed_values[prescribed_set[i]](disc.position[i], time + 0.5 * dt);
          for (unsigned int d = 0; d < dim; ++d)
            box_v[d * N + pos[i]] = v[d];
        }
    };
    const auto held_after_drift = [&](const double time) {
      for (const unsigned int i : displacement_nodes)
        if (displacement_set[i] >= 0)
          {
            const Tensor<1, dim> value =
              prescribed_displacements[displacement_set[i]](disc.position[i], time + dt);
            for (unsigned int d = 0; d < dim; ++d)
              {
                box_u[d * N + pos[i]] = value[d];
                box_p[d * N + pos[i]] = box_x[d * N + pos[i]] + value[d];
              }
          }
      for (const unsigned int i : velocity_nodes)
        {
          const Tensor<1, dim> v = prescribed_values[prescribed_set[i]](disc.position[i], time + dt);
          for (unsigned int d = 0; d < dim; ++d)
            box_v[d * N + pos[i]] = v[d];
        }
    };

    // Load the node vectors into the box, fused with the first half-kick and
    // drift with the stored a^n (0 at held nodes) of the free nodes and the
    // ghosts (v = a = 0): one pass in node order (box positions nearly
    // ascending). Held nodes are loaded, get their velocity, and then the
    // same kick and drift. Positions without a local node stay zero in every
    // array, and box_b is zero unless there is a body force.
    // Raw pointers: through the vectors, every store would reload them.
    // From a current box (deferred sync) the same kick and drift run in box
    // order with a^n = (F + b) / rho as unload_box() forms it (b: the box's
    // body force of the last step, read before it is reloaded below), and
    // a^n = 0 at held nodes; ghost positions are refreshed in every step.
    const double h0 = 0.5 * dt, tau0 = dt;
    if (box_current)
      for (unsigned int d = 0; d < dim; ++d)
        {
          const double *__restrict x          = box_x.data() + d * N;
          const double *__restrict b          = box_b.data() + d * N;
          const std::uint8_t *__restrict kind = box_kind.data();
          double *__restrict u = box_u.data() + d * N, *__restrict v = box_v.data() + d * N;
          double *__restrict p = box_p.data() + d * N, *__restrict f = box_f.data() + d * N;
          for (std::size_t L = 0; L < N; ++L)
            if (kind[L] == 2)
              {
                const double a = acceleration_of(f[L], b[L], inv_rho);
                v[L] += h0 * a;
                u[L] += tau0 * v[L];
                p[L] = x[L] + u[L];
              }
            else if (kind[L] == 1)
              f[L] = 0.;
        }
    else
      for (unsigned int d = 0; d < dim; ++d)
        {
          const double *__restrict un = displacement[d].begin();
          const double *__restrict vn = velocity[d].begin();
          const double *__restrict an = acceleration[d].begin();
          const double *__restrict x  = box_x.data() + d * N;
          const std::uint8_t *__restrict kind = box_kind.data();
          double *__restrict u = box_u.data() + d * N, *__restrict v = box_v.data() + d * N;
          double *__restrict p = box_p.data() + d * N, *__restrict f = box_f.data() + d * N;
          for (std::size_t i = 0; i < n_local; ++i)
            {
              const std::size_t L  = pos[i];
              const bool        ow = i < n_owned;
              double            ui = un[i];
              double            vi = ow ? vn[i] : 0.;
              const double      ai = ow ? an[i] : 0.;
              if (!ow || kind[L] == 2)
                {
                  vi += h0 * ai;
                  ui += tau0 * vi;
                  p[L] = x[L] + ui;
                }
              else
                f[L] = ai;
              u[L] = ui;
              v[L] = vi;
            }
        }
    if (has_body || box_b_nonzero)
      for (unsigned int d = 0; d < dim; ++d)
        for (unsigned int i = 0; i < n_owned; ++i)
          box_b[d * N + pos[i]] = body_force[d].local_element(i);
    box_b_nonzero = has_body;
    held_before_drift(t);
    const auto held_drift = [&](const unsigned int i) {
      for (unsigned int d = 0; d < dim; ++d)
        {
          const std::size_t k = d * N + pos[i];
          box_v[k] += h0 * box_f[k];
          box_u[k] += tau0 * box_v[k];
          box_p[k] = box_x[k] + box_u[k];
        }
    };
    for (unsigned int i = 0; i < n_owned; ++i)
      if (box_kind[pos[i]] == 1)
        held_drift(i);

    // Per chunk of final forces of step s: the second half-kick with
    // a = (F + b) / rho (0 at held nodes), then, unless s is the last step,
    // the first half-kick and the drift of step s + 1. Both are final for
    // the chunk: the sweep never reads a position below its current chunk
    // again. After the last step box_f holds F.
    const std::uint8_t *kind = box_kind.data();
    bool                last = false;
    const auto          kick = [&](const std::size_t c0, const unsigned int n, const double *fc,
                          const unsigned int C) {
      const std::uint8_t *__restrict k8 = kind + c0;
      // Locals, not captures: the vectorizer must see loop invariants.
      const double h = 0.5 * dt, tau = dt, ir = inv_rho;
      for (unsigned int d = 0; d < dim; ++d)
        {
          double *__restrict u       = box_u.data() + d * N + c0;
          double *__restrict v       = box_v.data() + d * N + c0;
          double *__restrict p       = box_p.data() + d * N + c0;
          double *__restrict f       = box_f.data() + d * N + c0;
          const double *__restrict b = box_b.data() + d * N + c0;
          const double *__restrict x = box_x.data() + d * N + c0;
          const double *__restrict F = fc + d * C;
          if (last)
#pragma omp simd
            for (unsigned int k = 0; k < n; ++k)
              {
                const double a = k8[k] == 2 ? ir * (F[k] + b[k]) : 0.;
                v[k] += h * a;
                f[k] = k8[k] != 0 ? F[k] : 0.;
              }
          else if (has_body)
#pragma omp simd
            for (unsigned int k = 0; k < n; ++k)
              {
                const double a = k8[k] == 2 ? ir * (F[k] + b[k]) : 0.;
                v[k] += h * a;
                v[k] += h * a;
                u[k] += tau * v[k];
                p[k] = x[k] + u[k];
              }
          else
#pragma omp simd
            for (unsigned int k = 0; k < n; ++k)
              {
                const double a = k8[k] == 2 ? ir * F[k] : 0.;
                v[k] += h * a;
                v[k] += h * a;
                u[k] += tau * v[k];
                p[k] = x[k] + u[k];
              }
        }
    };

    for (unsigned int s = 0; s < n_now; ++s)
      {
        const double t1 = t + dt;
        held_after_drift(t);
        if (body_force_function)
          {
            body_force_function(t1, body_force);
            for (unsigned int d = 0; d < dim; ++d)
              for (unsigned int i = 0; i < n_owned; ++i)
                box_b[d * N + pos[i]] = body_force[d].local_element(i);
          }
        last = s + 1 == n_now;
        // The next step's held velocities (held nodes have a = 0, so the
        // kicks of this step leave them).
        if (!last)
          held_before_drift(t1);
        // Ghost layer: the owned values other ranks import, through the
        // node vectors.
        if (parallel)
          for (unsigned int d = 0; d < dim; ++d)
            {
              Vector &ud = displacement[d];
              for (const auto &[first, end] : ud.get_partitioner()->import_indices())
                for (unsigned int i = first; i < end; ++i)
                  ud.local_element(i) = box_u[d * N + pos[i]];
              ud.update_ghost_values();
              for (std::size_t g = n_owned; g < n_local; ++g)
                {
                  box_u[d * N + pos[g]] = ud.local_element(g);
                  box_p[d * N + pos[g]] = box_x[d * N + pos[g]] + ud.local_element(g);
                }
            }
        op.lattice_sweep_forces(box_p.data(), kick);
        t = t1;
        ++n_steps;
      }

    node_vectors_stale = defer_node_sync;
    box_current        = defer_node_sync;
    if (!defer_node_sync)
      unload_box();
  }

  template <int dim>
  void
  VelocityVerlet<dim>::unload_box()
  {
    // Back to the node vectors (a as update_accelerations() sets it).
    const std::size_t                 N       = sweep_model->lattice_sweep_stride();
    const std::vector<std::uint32_t> &pos     = sweep_model->lattice_sweep_positions();
    const unsigned int                n_owned = disc.n_owned();
    const std::size_t                 n_local = disc.position.size();
    const double                      inv_rho = 1. / rho;
    for (unsigned int d = 0; d < dim; ++d)
      {
        const double *__restrict u = box_u.data() + d * N, *__restrict v = box_v.data() + d * N;
        const double *__restrict f    = box_f.data() + d * N;
        const double *__restrict b    = body_force[d].begin();
        const std::uint8_t *__restrict kind = box_kind.data();
        double *__restrict un = displacement[d].begin(), *__restrict vn = velocity[d].begin();
        double *__restrict fn = force[d].begin(), *__restrict an = acceleration[d].begin();
        for (std::size_t i = 0; i < n_local; ++i)
          un[i] = u[pos[i]];
        for (unsigned int i = 0; i < n_owned; ++i)
          {
            const std::size_t L = pos[i];
            vn[i]               = v[L];
            fn[i]               = f[L];
            an[i]               = kind[L] == 1 ? 0. : acceleration_of(f[L], b[i], inv_rho);
          }
      }
  }

  template <int dim>
  void
  VelocityVerlet<dim>::allocate_box()
  {
    if (!uses_box_state())
      return;
    const BondBasedOperator<dim> &op = *sweep_model;
    const std::size_t             N  = op.lattice_sweep_stride();
    if (box_u.size() == dim * N)
      return;
    for (PageOffsetVector *b : {&box_u, &box_v, &box_f, &box_b, &box_p, &box_x})
      b->assign(dim * N, 0.);
    box_b_nonzero                     = false;
    const std::vector<std::uint32_t> &pos = op.lattice_sweep_positions();
    const Point<dim>                  xc  = op.deformation_origin();
    for (unsigned int d = 0; d < dim; ++d)
      for (std::size_t i = 0; i < disc.position.size(); ++i)
        box_x[d * N + pos[i]] = disc.position[i][d] - xc[d];
  }

  template <int dim>
  double
  VelocityVerlet<dim>::kinetic_energy() const
  {
    check_node_vectors_current();
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
    check_node_vectors_current();
    Tensor<1, dim> p;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        p[d] += rho * disc.volume[i] * velocity[d].local_element(i);
    return Utilities::MPI::sum(p, disc.get_mpi_communicator());
  }

  template std::unique_ptr<MechanicsModel<1>> make_mechanics_model(BondBasedOperator<1> &);
  template std::unique_ptr<MechanicsModel<2>> make_mechanics_model(BondBasedOperator<2> &);
  template std::unique_ptr<MechanicsModel<3>> make_mechanics_model(BondBasedOperator<3> &);
  template std::unique_ptr<MechanicsModel<2>> make_mechanics_model(LinearizedLPSOperator<2> &);
  template std::unique_ptr<MechanicsModel<3>> make_mechanics_model(LinearizedLPSOperator<3> &);
  template class VelocityVerlet<1>;
  template class VelocityVerlet<2>;
  template class VelocityVerlet<3>;
} // namespace PeriDEAL
