#include <deal.II/base/quadrature_lib.h>

#include <deal.II/dofs/dof_tools.h>

#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>

#include <deal.II/lac/dynamic_sparsity_pattern.h>

#include <deal.II/numerics/matrix_creator.h>
#include <deal.II/numerics/vector_tools.h>

#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_wave.h>

#include <cmath>
#include <set>

namespace PeriDEAL
{
  namespace Fem
  {
    template <int dim>
    FemWave<dim>::FemWave(const Triangulation<dim>    &tria,
                          const FemWaveParameters      &prm,
                          const WaveBoundary            boundary,
                          const Abc::WaveAbcParameters &abc_prm,
                          const Function<dim>          &initial)
      : fe(prm.degree)
      , dof_handler(tria)
      , type(boundary)
      , chi(prm.wave_speed)
      , d(prm.damping)
      , dt(prm.time_step)
    {
      check_parameter(prm.degree == 1 || prm.degree == 2, "FEM/Degree", prm.degree, "1 or 2");
      check_parameter(chi > 0., "Model/Wave speed", chi, "> 0");
      check_parameter(d >= 0., "Model/Damping", d, ">= 0");
      dof_handler.distribute_dofs(fe);
      const unsigned int n = dof_handler.n_dofs();
      DynamicSparsityPattern dsp(n);
      DoFTools::make_sparsity_pattern(dof_handler, dsp);
      sparsity.copy_from(dsp);
      stiffness.reinit(sparsity);
      MatrixCreator::create_laplace_matrix(dof_handler, QGauss<dim>(prm.degree + 1), stiffness);

      // Lumped mass: Gauss-Lobatto points coincide with the FE_Q support
      // points for degree <= 2, so the mass matrix is diagonal.
      mass.reinit(n);
      boundary_mass.reinit(n);
      {
        const QGaussLobatto<dim>     q(prm.degree + 1);
        const QGaussLobatto<dim - 1> qf(prm.degree + 1);
        FEValues<dim>     fv(fe, q, update_values | update_JxW_values);
        FEFaceValues<dim> ff(fe, qf, update_values | update_JxW_values);
        std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
        for (const auto &cell : dof_handler.active_cell_iterators())
          {
            fv.reinit(cell);
            cell->get_dof_indices(dofs);
            for (unsigned int i = 0; i < dofs.size(); ++i)
              for (unsigned int k = 0; k < q.size(); ++k)
                mass[dofs[i]] += fv.shape_value(i, k) * fv.JxW(k);
            for (const unsigned int f : cell->face_indices())
              if (cell->face(f)->at_boundary())
                {
                  ff.reinit(cell, f);
                  for (unsigned int i = 0; i < dofs.size(); ++i)
                    for (unsigned int k = 0; k < qf.size(); ++k)
                      boundary_mass[dofs[i]] += ff.shape_value(i, k) * ff.JxW(k);
                }
          }
      }
      const double dt_crit = critical_time_step();
      check_parameter(dt > 0. && dt <= dt_crit, "Time stepping/Time step", dt,
                      "0 < dt <= " + std::to_string(dt_crit) + " (lumped-mass Verlet bound)");

      u.reinit(n);
      v.reinit(n);
      a.reinit(n);
      Ku.reinit(n);
      VectorTools::interpolate(dof_handler, initial, u);
      const IndexSet bdofs = DoFTools::extract_boundary_dofs(dof_handler);
      for (const auto i : bdofs)
        boundary_dofs.push_back(i);
      if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          u[i] = 0.;
      stiffness.vmult(Ku, u);
      for (unsigned int i = 0; i < n; ++i)
        a[i] = -chi * chi * Ku[i] / mass[i];
      u_old.assign(u.begin(), u.end());
      v_old.assign(v.begin(), v.end());

      if (type != WaveBoundary::absorbing)
        return;
      // Absorbing nodes: the boundary DoFs; outward normal: the average of
      // the normals of their boundary faces (corners: the diagonal).
      const MappingQ1<dim>      mapping;
      std::vector<Point<dim>>   points(n);
      DoFTools::map_dofs_to_support_points(mapping, dof_handler, points);
      std::vector<Tensor<1, dim>> normal(n);
      {
        const QGauss<dim - 1> qf(1);
        FEFaceValues<dim>     ff(fe, qf, update_normal_vectors);
        std::vector<types::global_dof_index> fdofs(fe.n_dofs_per_face());
        for (const auto &cell : dof_handler.active_cell_iterators())
          for (const unsigned int f : cell->face_indices())
            if (cell->face(f)->at_boundary())
              {
                ff.reinit(cell, f);
                cell->face(f)->get_dof_indices(fdofs);
                for (const auto i : fdofs)
                  normal[i] += ff.normal_vector(0);
              }
      }
      std::vector<Tensor<1, dim>> normals;
      for (const unsigned int i : boundary_dofs)
        normals.push_back(normal[i] / normal[i].norm());
      std::vector<types::global_dof_index> ids(n);
      for (unsigned int i = 0; i < n; ++i)
        ids[i] = i;
      double h = 0.;
      for (const auto &cell : tria.active_cell_iterators())
        h = std::max(h, cell->minimum_vertex_distance());
      const double             spacing = h / prm.degree;
      Abc::WaveAbcParameters   ap      = abc_prm;
      if (ap.cloud_radius <= 0.)
        ap.cloud_radius = 2. * spacing * (1. + 1e-9);
      // Classical near field: the local relation (4.39) (the 'Dispersion
      // relation' parameter is for PD near fields).
      abc.reinit(points, ids, boundary_dofs, normals, Abc::WaveDispersion<dim>::local(chi, d), dt,
                 spacing, ap, MPI_COMM_SELF);
    }

    template <int dim>
    double
    FemWave<dim>::critical_time_step() const
    {
      double lmax = 0.;
      for (unsigned int i = 0; i < mass.size(); ++i)
        {
          double row = 0.;
          for (auto it = stiffness.begin(i); it != stiffness.end(i); ++it)
            row += std::abs(it->value());
          lmax = std::max(lmax, chi * chi * row / mass[i]);
        }
      return 2. / std::sqrt(lmax);
    }

    template <int dim>
    void
    FemWave<dim>::advance()
    {
      const unsigned int n    = u.size();
      const double       half = 0.5 * dt;
      if (type == WaveBoundary::absorbing)
        {
          abc.compute(u.begin(), u_old.data(), v.begin(), v_old.data(), u_abc, v_abc);
          u_old.assign(u.begin(), u.end());
          v_old.assign(v.begin(), v.end());
        }
      for (unsigned int i = 0; i < n; ++i)
        {
          u[i] += dt * (v[i] + half * a[i]);
          v[i] += half * a[i];
        }
      const auto &nodes = abc.absorbing_points();
      if (type == WaveBoundary::absorbing)
        for (unsigned int c = 0; c < nodes.size(); ++c)
          u[nodes[c]] = u_abc[c];
      else if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          u[i] = 0.;
      t += dt;
      stiffness.vmult(Ku, u);
      // M a = -chi^2 K u - 2 d M v - chi B (v + d u); B = 0 unless first order.
      const bool robin = type == WaveBoundary::first_order;
      for (unsigned int i = 0; i < n; ++i)
        {
          const double b = robin ? chi * boundary_mass[i] / mass[i] : 0.;
          const double f = -chi * chi * Ku[i] / mass[i] - b * d * u[i];
          v[i]           = (v[i] + half * f) / (1. + dt * d + half * b);
          a[i]           = f - (2. * d + b) * v[i];
        }
      if (type == WaveBoundary::absorbing)
        for (unsigned int c = 0; c < nodes.size(); ++c)
          v[nodes[c]] = v_abc[c];
      else if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          v[i] = a[i] = 0.;
    }

    template <int dim>
    double
    FemWave<dim>::energy(const std::function<bool(const Point<dim> &)> &inside) const
    {
      const QGauss<dim>           q(fe.degree + 1);
      FEValues<dim>               fv(fe, q, update_values | update_gradients | update_JxW_values);
      std::vector<double>         vq(q.size());
      std::vector<Tensor<1, dim>> gq(q.size());
      double                      e = 0.;
      for (const auto &cell : dof_handler.active_cell_iterators())
        if (inside(cell->center()))
          {
            fv.reinit(cell);
            fv.get_function_values(v, vq);
            fv.get_function_gradients(u, gq);
            for (unsigned int k = 0; k < q.size(); ++k)
              e += 0.5 * (vq[k] * vq[k] + chi * chi * gq[k] * gq[k]) * fv.JxW(k);
          }
      return e;
    }

    template <int dim>
    double
    FemWave<dim>::value_at(const Point<dim> &p) const
    {
      return VectorTools::point_value(dof_handler, u, p);
    }

    template class FemWave<1>;
    template class FemWave<2>;
  } // namespace Fem
} // namespace PeriDEAL
