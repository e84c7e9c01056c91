#include <chrono>
#include <random>
#include <sstream>

#include <perideal/abc/absorbing_layer.h>
#include <perideal/abc/pd_unbounded_diffusion.h>
#include <perideal/base/exceptions.h>

namespace PeriDEAL
{
  namespace Abc
  {
    template <int dim>
    PdUnboundedDiffusion<dim>::PdUnboundedDiffusion(const MPI_Comm comm)
      : disc(comm)
    {}

    template <int dim>
    void
    PdUnboundedDiffusion<dim>::setup(const Domain<dim>              &domain,
                                     const LatticeParameters        &lattice,
                                     const DiffusionModelParameters &model,
                                     const double                    time_step,
                                     const TruncationBoundary        boundary,
                                     const EbfParameters            &prm,
                                     const Function<dim>            &initial)
    {
      check_parameter(domain.has_signed_distance(), "Geometry/Domain", "without signed distance",
                      "a box or a ball (the absorbing layer needs the distance to the boundary)");
      check_parameter(prm.imposed == "value", "Absorbing boundary/Imposed", prm.imposed,
                      "value (the PD near field has no boundary flux)");
      disc.setup(domain, lattice);
      op = std::make_unique<DiffusionOperator<dim>>(disc, model);
      check_parameter(time_step > 0 && time_step <= op->critical_time_step(), "Time step", time_step,
                      "0 < dt <= " + std::to_string(op->critical_time_step()) +
                        " (forward Euler bound of the PD operator)");
      dt               = time_step;
      t                = 0.;
      model_parameters = model;
      disc.initialize_vector(C);
      disc.initialize_vector(rate);
      disc.initialize_vector(phase);
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          C.local_element(i) = initial.value(disc.position[i]);
          // Initial phase as in DiffusionSolver: solid where C0 >= C_sat.
          if (op->is_corrosion())
            phase.local_element(i) = C.local_element(i) >= model.saturation ? 1. : 0.;
        }
      phase.update_ghost_values();

      const double delta = lattice.delta;
      const double layer = prm.layer_thickness > 0 ? prm.layer_thickness : delta;
      absorbing.assign(disc.n_owned(), false);
      abc = EbfDiffusionAbc<dim>();
      if (boundary == TruncationBoundary::neumann)
        return;
      // Absorbing nodes: delta_L / dx node layers inside the truncation
      // boundary.
      std::vector<unsigned int>   absorbing_nodes;
      std::vector<Tensor<1, dim>> normals;
      find_absorbing_layer(disc, domain, layer, prm.cloud_radius, absorbing_nodes, normals);
      bool solid_absorbing = false;
      for (const unsigned int i : absorbing_nodes)
        {
          absorbing[i]    = true;
          solid_absorbing = solid_absorbing || phase.local_element(i) > 0.5;
        }
      // The far field is the electrolyte: the modes solve liquid diffusion.
      check_parameter(!Utilities::MPI::logical_or(solid_absorbing, disc.get_mpi_communicator()),
                      "Initial condition", "solid (C0 >= C_sat) in the absorbing layer",
                      "a solid body at least delta_L inside the truncation boundary");
      std::vector<types::global_dof_index> ids(disc.id.begin(), disc.id.end());
      ScalarKernel far_kernel = op->kernel();
      if (op->is_corrosion())
        far_kernel.constant = model.kappa_liquid;
      const DiffusionDispersion dispersion =
        prm.dispersion == "local" ? DiffusionDispersion::local(far_kernel.local_coefficient()) :
                                    DiffusionDispersion::nonlocal(far_kernel);
      abc.reinit(disc.position, ids, absorbing_nodes, normals, dispersion, dt, prm,
                 disc.get_mpi_communicator());
      if (prm.fit == "stabilized")
        {
          // The nodes the clouds can reach, by distance (rank independent).
          std::vector<bool> in_clouds(disc.n_owned());
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            in_clouds[i] = -domain.signed_distance(disc.position[i]) < layer + prm.cloud_radius;
          stabilize(std::max(prm.stability_check_steps, 100u), prm.max_stabilization_rounds, in_clouds,
                    prm.max_update_l1);
        }
      if (prm.stability_check_steps > 0)
        check_stability(prm.stability_check_steps);
    }

    template <int dim>
    double
    PdUnboundedDiffusion<dim>::power_iteration(Vector &u, const unsigned int n_steps) const
    {
      const MPI_Comm comm = disc.get_mpi_communicator();
      Vector         r;
      disc.initialize_vector(r);
      const auto norm = [&]() {
        double e = 0.;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          e += u.local_element(i) * u.local_element(i) * disc.volume[i];
        return std::sqrt(Utilities::MPI::sum(e, comm));
      };
      // Normalized every step; the growth of the last quarter of the steps
      // approximates the spectral radius (the transient of the start
      // decays first).
      double             log_growth = 0.;
      const unsigned int window     = std::max(1u, n_steps / 4);
      std::vector<double> values;
      u /= norm();
      for (unsigned int n = 0; n < n_steps; ++n)
        {
          u.update_ghost_values();
          abc.compute(u.begin(), values);
          op->apply(u, r, &phase);
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            u.local_element(i) += dt * r.local_element(i);
          const auto &points = abc.absorbing_points();
          for (unsigned int a = 0; a < points.size(); ++a)
            u.local_element(points[a]) = values[a];
          const double g = norm();
          if (n + window >= n_steps)
            log_growth += std::log(g);
          u /= g;
        }
      u.update_ghost_values();
      return std::exp(log_growth / window);
    }

    template <int dim>
    void
    PdUnboundedDiffusion<dim>::random_vector(Vector &u) const
    {
      disc.initialize_vector(u);
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          std::minstd_rand                       gen(disc.id[i] + 1);
          std::uniform_real_distribution<double> uniform(-1., 1.);
          gen.discard(3);
          u.local_element(i) = uniform(gen);
        }
    }

    template <int dim>
    void
    PdUnboundedDiffusion<dim>::stabilize(const unsigned int       n_steps,
                                         const unsigned int       max_rounds,
                                         const std::vector<bool> &in_clouds,
                                         const double             l1_cap)
    {
      Vector u;
      // The random start is restricted to the clouds: a start over the
      // whole near field puts most of its norm into the slowly decaying
      // interior diffusion modes (1 - D dt (pi/R)^2 per step), which hide a
      // boundary mode growing by less than a few percent per step within
      // the check's steps (on the dx = 0.25 sphere a fresh start measured
      // 0.9996 for a map that diverged).
      const auto growth = [&]() {
        random_vector(u);
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (!in_clouds[i])
            u.local_element(i) = 0.;
        return power_iteration(u, n_steps);
      };
      abc.stabilize(l1_cap, max_rounds, 1. + 1e-6, growth,
                    [&u](const unsigned int j) { return u.local_element(j); },
                    disc.get_mpi_communicator());
    }

    template <int dim>
    void
    PdUnboundedDiffusion<dim>::check_stability(const unsigned int n_steps)
    {
      const MPI_Comm comm = disc.get_mpi_communicator();
      Vector         u;
      random_vector(u);
      stability_growth = power_iteration(u, n_steps);
      // A stable map decays (diffusion and absorption): its slowest mode
      // has growth 1 - O(dt D / R^2), so any growth above 1 + 1e-6 per step
      // is an instability (a doubling every 7e5 steps at the threshold).
      if (!(stability_growth <= 1. + 1e-6))
        {
          // The growing vector peaks at the unstable clouds: name the
          // absorbing node with the largest |u| (all ranks).
          const auto  &points = abc.absorbing_points();
          double       peak   = -1.;
          unsigned int where  = 0;
          for (unsigned int a = 0; a < points.size(); ++a)
            if (std::abs(u.local_element(points[a])) > peak)
              {
                peak  = std::abs(u.local_element(points[a]));
                where = a;
              }
          std::ostringstream cloud;
          if (peak >= 0.)
            {
              double l1 = 0.;
              for (const auto &[j, v] : abc.cloud(where))
                l1 += std::abs(v);
              cloud << "the cloud of absorbing node " << disc.id[points[where]] << " at ("
                    << disc.position[points[where]] << "), " << abc.cloud(where).size()
                    << " points, sum |V_j| " << l1;
            }
          const auto all = Utilities::MPI::all_gather(comm, std::make_pair(peak, cloud.str()));
          const auto top = std::max_element(all.begin(), all.end());
          std::ostringstream v;
          v << "one-step growth " << stability_growth << " (power iteration, " << n_steps
            << " steps); the growing mode peaks at " << top->second;
          throw ParameterError("Absorbing boundary/Updating vector fit, Wave number range, Cloud radius",
                               v.str(),
                               "a stable absorbing boundary: growth <= 1 + 1e-6 (the monotone fit is "
                               "stable by construction; else change Delta k or d_inf)");
        }
    }

    template <int dim>
    void
    PdUnboundedDiffusion<dim>::advance()
    {
      using clock      = std::chrono::steady_clock;
      const auto start = clock::now();
      C.update_ghost_values();
      const auto abc_start = clock::now();
      abc.compute(C.begin(), boundary_values);
      const auto abc_end = clock::now();
      op->apply(C, rate, &phase);
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        C.local_element(i) += dt * rate.local_element(i);
      const auto set_start = clock::now();
      const auto &absorbing = abc.absorbing_points();
      for (unsigned int a = 0; a < absorbing.size(); ++a)
        C.local_element(absorbing[a]) = boundary_values[a];
      const auto end = clock::now();
      // Phase rule (2.79) on C^{n+1}: changed bonds act from the next step.
      if (op->is_corrosion())
        {
          update_corrosion_phase(model_parameters, C, phase, disc.n_owned());
          phase.update_ghost_values();
        }
      t += dt;
      abc_seconds += std::chrono::duration<double>(abc_end - abc_start + end - set_start).count();
      step_seconds += std::chrono::duration<double>(end - start).count();
    }

    template <int dim>
    double
    PdUnboundedDiffusion<dim>::energy(const BoundingBox<dim> &region) const
    {
      double e = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (region.point_inside(disc.position[i], 1e-10))
          e += C.local_element(i) * C.local_element(i) * disc.volume[i];
      return Utilities::MPI::sum(e, disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedDiffusion<dim>::energy(const Region &inside) const
    {
      double e = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (inside(disc.position[i]))
          e += C.local_element(i) * C.local_element(i) * disc.volume[i];
      return Utilities::MPI::sum(e, disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedDiffusion<dim>::mass(const Region &inside) const
    {
      double m = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (inside(disc.position[i]))
          m += C.local_element(i) * disc.volume[i];
      return Utilities::MPI::sum(m, disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedDiffusion<dim>::solid_volume() const
    {
      double v = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        v += phase.local_element(i) * disc.volume[i];
      return Utilities::MPI::sum(v, disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedDiffusion<dim>::near_field_energy() const
    {
      double e = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (!absorbing[i])
          e += C.local_element(i) * C.local_element(i) * disc.volume[i];
      return Utilities::MPI::sum(e, disc.get_mpi_communicator());
    }

    template class PdUnboundedDiffusion<1>;
    template class PdUnboundedDiffusion<2>;
    template class PdUnboundedDiffusion<3>;
  } // namespace Abc
} // namespace PeriDEAL
