#include <deal.II/base/quadrature_lib.h>

#include <deal.II/dofs/dof_tools.h>

#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>

#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/lapack_full_matrix.h>

#include <deal.II/numerics/matrix_creator.h>
#include <deal.II/numerics/vector_tools.h>

#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_wave.h>

#include <chrono>
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
      , extrapolate_velocity(prm.extrapolate_velocity)
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
      set_acceleration();
      u_old.assign(u.begin(), u.end());
      v_old.assign(v.begin(), v.end());

      if (type != WaveBoundary::absorbing)
        return;
      // Measured: with FE_Q(2) the EBF update has one-step spectral radius
      // 1.008 (dt = 0.02, h = 0.5; 1.0002 even with a truncated
      // pseudo-inverse), against 1.0025 for FE_Q(1) which truncation fixes.
      check_parameter(prm.degree == 1, "FEM/Degree", prm.degree,
                      "1 with the EBF absorbing boundary (FE_Q(2) + EBF is unstable: one-step spectral radius > 1)");
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
      check_parameter(ap.dispersion == "local" || ap.dispersion == "discrete",
                      "Absorbing boundary/Dispersion relation", ap.dispersion,
                      "local or discrete for a FEM near field");
      if (ap.dispersion == "local")
        relation = Abc::WaveDispersion<dim>::local(chi, d);
      else
        {
          // The semi-discrete symbol of the lumped-mass scheme from the
          // stiffness row of the DoF nearest the centre. Q2 has vertex, edge
          // and cell DoFs with different rows: no single scalar symbol.
          check_parameter(prm.degree == 1, "FEM/Degree", prm.degree,
                          "1 with Dispersion relation = discrete (Q2 has no single-row symbol; use local)");
          Point<dim> centre;
          for (const auto &p : points)
            centre += p / double(n);
          unsigned int c = 0;
          for (unsigned int i = 1; i < n; ++i)
            if (points[i].distance(centre) < points[c].distance(centre))
              c = i;
          std::vector<Tensor<1, dim>> offsets;
          std::vector<double>         weights;
          for (auto it = stiffness.begin(c); it != stiffness.end(c); ++it)
            if (it->column() != c)
              {
                offsets.push_back(points[it->column()] - points[c]);
                weights.push_back(-chi * chi * it->value() / mass[c]);
              }
          relation = Abc::WaveDispersion<dim>::stencil(offsets, weights, d, "discrete Q1 lumped");
        }
      abc.reinit(points, ids, boundary_dofs, normals, relation, dt, spacing, ap, MPI_COMM_SELF);
      constant_defect.assign(boundary_dofs.size(), 0.);
      if (prm.preserve_constants)
        {
          const std::vector<double> ones(n, 1.), zeros(n, 0.);
          abc.compute(ones.data(), ones.data(), zeros.data(), zeros.data(), u_abc, v_abc);
          for (unsigned int c = 0; c < u_abc.size(); ++c)
            constant_defect[c] = 1. - u_abc[c];
        }
      // Optional global stability guard (the cloud guards of Sect. 4.2.3 are
      // not sufficient, see doc/design.md).
      if (ap.spectral_check_size > 0 && 2 * (n + abc.cloud_points().size()) <= ap.spectral_check_size)
        {
          unsigned int n_up = 0;
          spectral_radius   = one_step_spectral_radius(ap.spectral_check_size, &n_up);
          if (spectral_radius > ap.max_spectral_radius)
            throw ParameterError("Absorbing boundary/Pseudo-inverse tolerance",
                                 std::to_string(ap.pseudo_inverse_tolerance),
                                 "a value for which the one-step spectral radius (here " +
                                   std::to_string(spectral_radius) + ", " + std::to_string(n_up) +
                                   " eigenvalues > 1) is <= " + std::to_string(ap.max_spectral_radius));
        }
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
    FemWave<dim>::set_acceleration()
    {
      stiffness.vmult(Ku, u);
      const bool robin = type == WaveBoundary::first_order;
      for (unsigned int i = 0; i < u.size(); ++i)
        {
          const double b = robin ? chi * boundary_mass[i] / mass[i] : 0.;
          a[i]           = -chi * chi * Ku[i] / mass[i] - b * d * u[i] - (2. * d + b) * v[i];
        }
    }

    template <int dim>
    double
    FemWave<dim>::one_step_spectral_radius(const unsigned int    max_size,
                                           unsigned int         *n_unstable,
                                           std::complex<double> *dominant)
    {
      const unsigned int               n = u.size();
      const std::vector<unsigned int> &c = abc.cloud_points();
      const bool                       absorbing = type == WaveBoundary::absorbing;
      const unsigned int               m = 2 * n + (absorbing ? 2 * c.size() : 0);
      check_parameter(m <= max_size, "State size of the spectral radius check", m,
                      "<= " + std::to_string(max_size) + " (dense eigenvalue problem)");
      const dealii::Vector<double> u0 = u, v0 = v, a0 = a;
      const std::vector<double>    uo0 = u_old, vo0 = v_old;
      const double                 t0 = t, abc0 = abc_seconds, step0 = step_seconds;
      LAPACKFullMatrix<double>     map(m, m);
      for (unsigned int col = 0; col < m; ++col)
        {
          u = 0.;
          v = 0.;
          if (absorbing)
            for (const unsigned int q : c)
              u_old[q] = v_old[q] = 0.;
          if (col < n)
            u[col] = 1.;
          else if (col < 2 * n)
            v[col - n] = 1.;
          else if (col < 2 * n + c.size())
            u_old[c[col - 2 * n]] = 1.;
          else
            v_old[c[col - 2 * n - c.size()]] = 1.;
          set_acceleration();
          advance();
          for (unsigned int i = 0; i < n; ++i)
            {
              map(i, col)     = u[i];
              map(n + i, col) = v[i];
            }
          if (absorbing)
            for (unsigned int q = 0; q < c.size(); ++q)
              {
                map(2 * n + q, col)            = u_old[c[q]];
                map(2 * n + c.size() + q, col) = v_old[c[q]];
              }
        }
      u            = u0;
      v            = v0;
      a            = a0;
      u_old        = uo0;
      v_old        = vo0;
      t            = t0;
      abc_seconds  = abc0;
      step_seconds = step0;
      map.compute_eigenvalues(false, false);
      double       rho  = 0.;
      unsigned int n_up = 0;
      for (unsigned int i = 0; i < m; ++i)
        {
          const double mod = std::abs(map.eigenvalue(i));
          if (mod > rho && dominant)
            *dominant = map.eigenvalue(i);
          rho = std::max(rho, mod);
          n_up += mod > 1. + 1e-8 ? 1 : 0;
        }
      if (n_unstable)
        *n_unstable = n_up;
      return rho;
    }

    template <int dim>
    void
    FemWave<dim>::advance()
    {
      using clock                = std::chrono::steady_clock;
      const auto         start   = clock::now();
      const unsigned int n    = u.size();
      const double       half = 0.5 * dt;
      if (type == WaveBoundary::absorbing)
        {
          const auto abc_start = clock::now();
          // Only the cloud entries of the previous level are read.
          if (extrapolate_velocity)
            {
              abc.compute(u.begin(), u_old.data(), v.begin(), v_old.data(), u_abc, v_abc);
              for (const unsigned int q : abc.cloud_points())
                v_old[q] = v[q];
            }
          else
            abc.compute_values(u.begin(), u_old.data(), u_abc);
          for (const unsigned int q : abc.cloud_points())
            u_old[q] = u[q];
          abc_seconds += std::chrono::duration<double>(clock::now() - abc_start).count();
        }
      for (unsigned int i = 0; i < n; ++i)
        {
          u[i] += dt * (v[i] + half * a[i]);
          v[i] += half * a[i];
        }
      const auto &nodes = abc.absorbing_points();
      if (type == WaveBoundary::absorbing)
        for (unsigned int c = 0; c < nodes.size(); ++c)
          u[nodes[c]] = u_abc[c] + constant_defect[c] * u_old[nodes[c]];
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
          v[nodes[c]] = extrapolate_velocity ? v_abc[c] : (u[nodes[c]] - u_old[nodes[c]]) / dt;
      else if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          v[i] = a[i] = 0.;
      step_seconds += std::chrono::duration<double>(clock::now() - start).count();
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
