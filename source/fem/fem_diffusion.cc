#include <deal.II/base/quadrature_lib.h>

#include <deal.II/fe/fe_values.h>

#include <deal.II/numerics/vector_tools.h>

#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_diffusion.h>

#include <chrono>

namespace PeriDEAL
{
  namespace Fem
  {
    template <int dim>
    FemDiffusion<dim>::FemDiffusion(const Triangulation<dim>     &tria,
                                    const FemDiffusionParameters &parameters)
      : tria(tria)
      , prm(parameters)
      , fe((check_parameter(parameters.degree >= 1 && parameters.degree <= 2, "FEM/Degree",
                            parameters.degree, "1 or 2"),
            parameters.degree))
    {
      check_parameter(prm.scheme == "forward Euler" || prm.scheme == "backward Euler",
                      "FEM/Scheme", prm.scheme, "forward Euler or backward Euler");
      check_parameter(prm.time_step > 0., "FEM/Time step", prm.time_step, "> 0");
      check_parameter(prm.diffusivity > 0., "FEM/Diffusivity", prm.diffusivity, "> 0");
    }

    template <int dim>
    void
    FemDiffusion<dim>::setup(const Abc::TruncationBoundary boundary,
                             const Abc::EbfParameters     &abc_parameters,
                             const Function<dim>          &initial)
    {
      dof_handler.reinit(tria);
      dof_handler.distribute_dofs(fe);
      const bool absorbing = boundary == Abc::TruncationBoundary::absorbing;
      near_field.reinit(dof_handler, absorbing ? abc_parameters.cloud_radius : 0.);
      near_field.assemble(mass, stiffness, lumped, boundary_lumped);
      stiffness *= prm.diffusivity;
      const auto &part = near_field.partitioner;
      C.reinit(part);
      rhs.reinit(part);
      tmp.reinit(part);
      VectorTools::interpolate(dof_handler, initial, C);
      C.update_ghost_values();
      t             = 0.;
      energy_cached = false;

      // Absorbing nodes: the owned boundary DoFs, local frames from their
      // outward normals; clouds from every available point (ghosts included).
      std::vector<unsigned int> absorbing_dofs;
      if (absorbing)
        {
          absorbing_dofs = near_field.boundary;
          abc.reinit(near_field.points, near_field.ids, absorbing_dofs, near_field.normals,
                     Abc::DiffusionDispersion::local(prm.diffusivity), prm.time_step,
                     abc_parameters, near_field.comm);
        }
      else
        abc = Abc::EbfDiffusionAbc<dim>();

      // System matrix: M (consistent explicit) or M + dt K (implicit), with
      // identity rows for the absorbing DoFs (their values are given).
      const bool explicit_lumped = prm.scheme == "forward Euler" && prm.lumped_mass;
      solver.reset();
      if (!explicit_lumped)
        {
          system.copy_from(mass);
          if (prm.lumped_mass)
            {
              system = 0.;
              for (unsigned int l = 0; l < near_field.n_owned(); ++l)
                system.set(near_field.ids[l], near_field.ids[l], lumped.local_element(l));
              system.compress(VectorOperation::insert);
            }
          if (prm.scheme == "backward Euler")
            system.add(prm.time_step, stiffness);
          std::vector<types::global_dof_index> rows;
          for (const unsigned int l : absorbing_dofs)
            rows.push_back(near_field.ids[l]);
          system.clear_rows(rows, 1.);
          solver = std::make_unique<TrilinosWrappers::SolverDirect>(
            solver_control, TrilinosWrappers::SolverDirect::AdditionalData(false, "Amesos_Klu"));
          solver->initialize(system);
        }

      // Forward Euler stability: 2 / lambda_max(M^-1 K) by power iteration
      // (M lumped or consistent, natural boundary: the largest spectrum).
      critical_time_step = 0.;
      if (prm.scheme == "forward Euler")
        {
          const double lambda = near_field.largest_eigenvalue(stiffness, mass, lumped, prm.lumped_mass);
          // The Rayleigh quotient approaches lambda_max from below: 2 % margin.
          critical_time_step = 2. / (1.02 * lambda);
          check_parameter(prm.time_step <= critical_time_step, "FEM/Time step", prm.time_step,
                          "<= " + std::to_string(critical_time_step) +
                            " (forward Euler bound 2/lambda_max(M^-1 K))");
        }
    }

    template <int dim>
    void
    FemDiffusion<dim>::advance()
    {
      using clock      = std::chrono::steady_clock;
      const auto start = clock::now();
      abc.compute(C.begin(), boundary_values);
      const auto    abc_end   = clock::now();
      const auto   &absorbing = abc.absorbing_points();
      const double  dt        = prm.time_step;
      const unsigned int n    = near_field.n_owned();
      if (prm.scheme == "forward Euler")
        {
          stiffness.vmult(tmp, C);
          if (!solver)
            for (unsigned int i = 0; i < n; ++i)
              C.local_element(i) -= dt * tmp.local_element(i) / lumped.local_element(i);
          else
            {
              mass.vmult(rhs, C);
              rhs.add(-dt, tmp);
            }
        }
      else if (prm.lumped_mass)
        for (unsigned int i = 0; i < n; ++i)
          rhs.local_element(i) = lumped.local_element(i) * C.local_element(i);
      else
        mass.vmult(rhs, C);
      const auto set_start = clock::now();
      if (solver)
        {
          for (unsigned int a = 0; a < absorbing.size(); ++a)
            rhs.local_element(absorbing[a]) = boundary_values[a];
          C.zero_out_ghost_values();
          solver->solve(C, rhs);
        }
      else
        for (unsigned int a = 0; a < absorbing.size(); ++a)
          C.local_element(absorbing[a]) = boundary_values[a];
      C.update_ghost_values();
      const auto end = clock::now();
      t += dt;
      abc_seconds += std::chrono::duration<double>(abc_end - start).count() +
                     (solver ? 0. : std::chrono::duration<double>(end - set_start).count());
      step_seconds += std::chrono::duration<double>(end - start).count();
    }

    template <int dim>
    double
    FemDiffusion<dim>::energy(const BoundingBox<dim> &region) const
    {
      // integral of C_h^2 = sum over owned cells of C_c^T M_c C_c; the cell
      // mass matrices of the region are computed once.
      if (!energy_cached || energy_region.get_boundary_points() != region.get_boundary_points())
        {
          energy_region = region;
          energy_cached = true;
          energy_dofs.clear();
          energy_mass.clear();
          const QGauss<dim> quadrature(fe.degree + 1);
          FEValues<dim>     fe_values(fe, quadrature, update_values | update_JxW_values);
          std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
          for (const auto &cell : dof_handler.active_cell_iterators())
            if (cell->is_locally_owned() && region.point_inside(cell->center(), 1e-10))
              {
                fe_values.reinit(cell);
                FullMatrix<double> m(fe.n_dofs_per_cell(), fe.n_dofs_per_cell());
                for (unsigned int q = 0; q < quadrature.size(); ++q)
                  for (unsigned int i = 0; i < m.m(); ++i)
                    for (unsigned int j = 0; j < m.n(); ++j)
                      m(i, j) += fe_values.shape_value(i, q) * fe_values.shape_value(j, q) * fe_values.JxW(q);
                cell->get_dof_indices(dofs);
                energy_dofs.emplace_back();
                for (const auto g : dofs)
                  energy_dofs.back().push_back(near_field.partitioner->global_to_local(g));
                energy_mass.push_back(m);
              }
        }
      double e = 0.;
      for (unsigned int c = 0; c < energy_dofs.size(); ++c)
        for (unsigned int i = 0; i < energy_dofs[c].size(); ++i)
          for (unsigned int j = 0; j < energy_dofs[c].size(); ++j)
            e += C.local_element(energy_dofs[c][i]) * energy_mass[c](i, j) *
                 C.local_element(energy_dofs[c][j]);
      return Utilities::MPI::sum(e, near_field.comm);
    }

    template <int dim>
    double
    FemDiffusion<dim>::max_error(Function<dim> &exact, const BoundingBox<dim> &region) const
    {
      exact.set_time(t);
      double e = 0.;
      for (unsigned int i = 0; i < near_field.n_owned(); ++i)
        if (region.point_inside(near_field.points[i], 1e-10))
          e = std::max(e, std::abs(C.local_element(i) - exact.value(near_field.points[i])));
      return Utilities::MPI::max(e, near_field.comm);
    }

    template class FemDiffusion<1>;
    template class FemDiffusion<2>;
  } // namespace Fem
} // namespace PeriDEAL
