#include <deal.II/base/quadrature_lib.h>

#include <deal.II/dofs/dof_tools.h>

#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>

#include <deal.II/lac/dynamic_sparsity_pattern.h>

#include <deal.II/numerics/matrix_creator.h>
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
      DynamicSparsityPattern dsp(dof_handler.n_dofs());
      DoFTools::make_sparsity_pattern(dof_handler, dsp);
      sparsity.copy_from(dsp);
      mass.reinit(sparsity);
      stiffness.reinit(sparsity);
      system.reinit(sparsity);
      const QGauss<dim> quadrature(fe.degree + 1);
      MatrixCreator::create_mass_matrix(dof_handler, quadrature, mass);
      MatrixCreator::create_laplace_matrix(dof_handler, quadrature, stiffness);
      stiffness *= prm.diffusivity;
      // Lumped mass: Gauss-Lobatto quadrature at the support points of FE_Q
      // (equidistant = Gauss-Lobatto for degree <= 2), i.e. the row sums.
      lumped.reinit(dof_handler.n_dofs());
      for (unsigned int i = 0; i < dof_handler.n_dofs(); ++i)
        for (auto e = mass.begin(i); e != mass.end(i); ++e)
          lumped[i] += e->value();

      C.reinit(dof_handler.n_dofs());
      rhs.reinit(dof_handler.n_dofs());
      tmp.reinit(dof_handler.n_dofs());
      VectorTools::interpolate(dof_handler, initial, C);
      t = 0.;

      // Absorbing nodes: the boundary DoFs; normal: sum of the adjacent
      // boundary-face normals (corners get the diagonal).
      std::vector<unsigned int>   absorbing;
      std::vector<Tensor<1, dim>> normals;
      if (boundary == Abc::TruncationBoundary::absorbing)
        {
          std::vector<Tensor<1, dim>>          normal_sum(dof_handler.n_dofs());
          std::vector<bool>                    on_boundary(dof_handler.n_dofs(), false);
          std::vector<types::global_dof_index> face_dofs(fe.n_dofs_per_face());
          for (const auto &cell : dof_handler.active_cell_iterators())
            for (const unsigned int f : cell->face_indices())
              if (cell->face(f)->at_boundary())
                {
                  Tensor<1, dim> n;
                  if (dim == 1)
                    n[0] = f == 0 ? -1. : 1.;
                  else
                    {
                      // Outward normal of a planar face: from the cell centre.
                      n = cell->face(f)->center() - cell->center();
                      n /= n.norm();
                    }
                  cell->face(f)->get_dof_indices(face_dofs);
                  for (const auto d : face_dofs)
                    {
                      normal_sum[d] += n;
                      on_boundary[d] = true;
                    }
                }
          for (unsigned int i = 0; i < dof_handler.n_dofs(); ++i)
            if (on_boundary[i])
              {
                absorbing.push_back(i);
                normals.push_back(normal_sum[i] / normal_sum[i].norm());
              }
          std::vector<Point<dim>> points(dof_handler.n_dofs());
          DoFTools::map_dofs_to_support_points(MappingQ1<dim>(), dof_handler, points);
          std::vector<types::global_dof_index> ids(dof_handler.n_dofs());
          for (unsigned int i = 0; i < ids.size(); ++i)
            ids[i] = i;
          abc.reinit(points, ids, absorbing, normals,
                     Abc::DiffusionDispersion::local(prm.diffusivity), prm.time_step,
                     abc_parameters, MPI_COMM_SELF);
        }
      else
        abc = Abc::EbfDiffusionAbc<dim>();

      // System matrix: M (consistent explicit) or M + dt K (implicit), with
      // identity rows for the absorbing DoFs (their values are given).
      const bool explicit_lumped = prm.scheme == "forward Euler" && prm.lumped_mass;
      use_solver                 = !explicit_lumped;
      if (use_solver)
        {
          system.copy_from(mass);
          if (prm.lumped_mass)
            {
              system = 0.;
              for (unsigned int i = 0; i < dof_handler.n_dofs(); ++i)
                system.set(i, i, lumped[i]);
            }
          if (prm.scheme == "backward Euler")
            system.add(prm.time_step, stiffness);
          for (const unsigned int i : absorbing)
            {
              for (auto e = system.begin(i); e != system.end(i); ++e)
                e->value() = 0.;
              system.set(i, i, 1.);
            }
          solver.initialize(system);
        }

      // Forward Euler stability: 2 / lambda_max(M^-1 K) by power iteration
      // (M lumped or consistent, natural boundary: the largest spectrum).
      critical_time_step = 0.;
      if (prm.scheme == "forward Euler")
        {
          SparseDirectUMFPACK mass_solver;
          if (!prm.lumped_mass)
            mass_solver.initialize(mass);
          dealii::Vector<double> x(dof_handler.n_dofs()), y(dof_handler.n_dofs());
          for (unsigned int i = 0; i < x.size(); ++i)
            x[i] = (i % 2 ? 1. : -1.) * (1. + 0.1 * std::sin(double(i)));
          double lambda = 0.;
          for (unsigned int it = 0; it < 200; ++it)
            {
              x /= x.l2_norm();
              stiffness.vmult(y, x);
              for (unsigned int i = 0; i < y.size() && prm.lumped_mass; ++i)
                y[i] /= lumped[i];
              if (!prm.lumped_mass)
                mass_solver.solve(y);
              lambda = x * y;
              x      = y;
            }
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
      const auto abc_end = clock::now();
      const auto &absorbing = abc.absorbing_points();
      const double dt = prm.time_step;
      if (prm.scheme == "forward Euler")
        {
          stiffness.vmult(tmp, C);
          if (!use_solver)
            for (unsigned int i = 0; i < C.size(); ++i)
              C[i] -= dt * tmp[i] / lumped[i];
          else
            {
              mass.vmult(rhs, C);
              rhs.add(-dt, tmp);
            }
        }
      else if (prm.lumped_mass)
        for (unsigned int i = 0; i < C.size(); ++i)
          rhs[i] = lumped[i] * C[i];
      else
        mass.vmult(rhs, C);
      const auto set_start = clock::now();
      if (use_solver)
        {
          for (unsigned int a = 0; a < absorbing.size(); ++a)
            rhs[absorbing[a]] = boundary_values[a];
          solver.solve(rhs);
          C = rhs;
        }
      else
        for (unsigned int a = 0; a < absorbing.size(); ++a)
          C[absorbing[a]] = boundary_values[a];
      const auto end = clock::now();
      t += dt;
      abc_seconds += std::chrono::duration<double>(abc_end - start).count() +
                     (use_solver ? 0. : std::chrono::duration<double>(end - set_start).count());
      step_seconds += std::chrono::duration<double>(end - start).count();
    }

    template <int dim>
    double
    FemDiffusion<dim>::energy(const BoundingBox<dim> &region) const
    {
      // integral of C_h^2 = sum over cells of C_c^T M_c C_c; the cell mass
      // matrices of the region are computed once.
      if (energy_dofs.empty() || energy_region.get_boundary_points() != region.get_boundary_points())
        {
          energy_region = region;
          energy_dofs.clear();
          energy_mass.clear();
          const QGauss<dim> quadrature(fe.degree + 1);
          FEValues<dim>     fe_values(fe, quadrature, update_values | update_JxW_values);
          for (const auto &cell : dof_handler.active_cell_iterators())
            if (region.point_inside(cell->center(), 1e-10))
              {
                fe_values.reinit(cell);
                FullMatrix<double> m(fe.n_dofs_per_cell(), fe.n_dofs_per_cell());
                for (unsigned int q = 0; q < quadrature.size(); ++q)
                  for (unsigned int i = 0; i < m.m(); ++i)
                    for (unsigned int j = 0; j < m.n(); ++j)
                      m(i, j) += fe_values.shape_value(i, q) * fe_values.shape_value(j, q) * fe_values.JxW(q);
                energy_dofs.emplace_back(fe.n_dofs_per_cell());
                cell->get_dof_indices(energy_dofs.back());
                energy_mass.push_back(m);
              }
        }
      double e = 0.;
      for (unsigned int c = 0; c < energy_dofs.size(); ++c)
        for (unsigned int i = 0; i < energy_dofs[c].size(); ++i)
          for (unsigned int j = 0; j < energy_dofs[c].size(); ++j)
            e += C[energy_dofs[c][i]] * energy_mass[c](i, j) * C[energy_dofs[c][j]];
      return e;
    }

    template <int dim>
    double
    FemDiffusion<dim>::max_error(Function<dim> &exact, const BoundingBox<dim> &region) const
    {
      exact.set_time(t);
      std::vector<Point<dim>> points(dof_handler.n_dofs());
      DoFTools::map_dofs_to_support_points(MappingQ1<dim>(), dof_handler, points);
      double     e      = 0.;
      for (unsigned int i = 0; i < points.size(); ++i)
        if (region.point_inside(points[i], 1e-10))
          e = std::max(e, std::abs(C[i] - exact.value(points[i])));
      return e;
    }

    template class FemDiffusion<1>;
    template class FemDiffusion<2>;
  } // namespace Fem
} // namespace PeriDEAL
