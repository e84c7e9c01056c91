#include <chrono>

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
