#include <deal.II/base/quadrature_lib.h>

#include <deal.II/dofs/dof_tools.h>

#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>

#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/lac/trilinos_solver.h>

#include <perideal/fem/near_field.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace PeriDEAL
{
  namespace Fem
  {
    namespace
    {
      /** Points binned on a grid of width w (neighbour search within w). */
      template <int dim>
      struct PointBins
      {
        double                                                     w;
        std::map<std::array<long, dim>, std::vector<unsigned int>> bins;
        std::array<long, dim>
        bin_of(const Point<dim> &p) const
        {
          std::array<long, dim> b;
          for (unsigned int d = 0; d < dim; ++d)
            b[d] = static_cast<long>(std::floor(p[d] / w));
          return b;
        }
        /** Is any binned point (of @p points) within r of @p p? */
        bool
        any_within(const std::vector<Point<dim>> &points, const Point<dim> &p, const double r) const
        {
          const auto         b0 = bin_of(p);
          const unsigned int nb = dim == 1 ? 3 : (dim == 2 ? 9 : 27);
          for (unsigned int n = 0; n < nb; ++n)
            {
              auto         b = b0;
              unsigned int c = n;
              for (unsigned int d = 0; d < dim; ++d, c /= 3)
                b[d] += long(c % 3) - 1;
              const auto it = bins.find(b);
              if (it != bins.end())
                for (const unsigned int j : it->second)
                  if (points[j].distance(p) <= r)
                    return true;
            }
          return false;
        }
      };
    } // namespace

    template <int dim>
    void
    NearFieldLayout<dim>::reinit(const DoFHandler<dim> &dh, const double cloud_radius)
    {
      dof_handler = &dh;
      comm        = dh.get_triangulation().get_communicator();
      owned       = dh.locally_owned_dofs();
      DoFTools::extract_locally_relevant_dofs(dh, relevant);
      const MappingQ1<dim>                              mapping;
      std::map<types::global_dof_index, Point<dim>>     support;
      DoFTools::map_dofs_to_support_points(mapping, dh, support);

      // Boundary DoFs (owned) and the sum of the adjacent boundary-face
      // normals: every cell touching an owned DoF is owned or ghost.
      std::map<types::global_dof_index, Tensor<1, dim>> normal_sum;
      std::map<types::global_dof_index, std::pair<double, double>> curvature_sum;
      {
        const QGauss<dim - 1>                qf(1);
        FEFaceValues<dim>                    ff(mapping, dh.get_fe(), qf, update_normal_vectors);
        std::vector<types::global_dof_index> fdofs(dh.get_fe().n_dofs_per_face());
        double                               hmin = std::numeric_limits<double>::max(), hmax = 0.;
        for (const auto &cell : dh.active_cell_iterators())
          if (!cell->is_artificial())
            {
              if (cell->is_locally_owned())
                {
                  hmin = std::min(hmin, cell->minimum_vertex_distance());
                  hmax = std::max(hmax, cell->minimum_vertex_distance());
                }
              for (const unsigned int f : cell->face_indices())
                if (cell->face(f)->at_boundary())
                  {
                    ff.reinit(cell, f);
                    cell->face(f)->get_dof_indices(fdofs);
                    for (const auto i : fdofs)
                      if (owned.is_element(i))
                        normal_sum[i] += ff.normal_vector(0);
                  }
            }
        // Curvature: the normal curvature along the chord from each owned
        // boundary DoF to the centres of its adjacent boundary faces.
        for (const auto &cell : dh.active_cell_iterators())
          if (!cell->is_artificial())
            for (const unsigned int f : cell->face_indices())
              if (cell->face(f)->at_boundary())
                {
                  ff.reinit(cell, f);
                  cell->face(f)->get_dof_indices(fdofs);
                  const Point<dim> centre = cell->face(f)->center();
                  for (const auto i : fdofs)
                    if (owned.is_element(i))
                      {
                        const Tensor<1, dim> chord = centre - support.at(i);
                        // (A Q2 face-centre DoF has no chord.)
                        const double h = cell->minimum_vertex_distance();
                        if (chord.norm_square() <= 1e-12 * h * h)
                          continue;
                        const Tensor<1, dim> n = normal_sum.at(i) / normal_sum.at(i).norm();
                        auto                &c = curvature_sum[i];
                        c.first += (ff.normal_vector(0) - n) * chord / chord.norm_square();
                        c.second += 1.;
                      }
                }
        min_cell_size = Utilities::MPI::min(hmin, comm);
        max_cell_size = Utilities::MPI::max(hmax, comm);
      }

      // Cloud ghosts: every DoF within the cloud radius of an owned boundary
      // DoF of this rank. Boundary points of all ranks, then the owned DoFs
      // near any of them (the candidates) of all ranks, then the filter.
      IndexSet ghosts = relevant;
      std::map<types::global_dof_index, Point<dim>> extra;
      if (cloud_radius > 0.)
        {
          const double            r = cloud_radius * (1. + 1e-9);
          std::vector<Point<dim>> my_boundary;
          for (const auto &[i, n] : normal_sum)
            my_boundary.push_back(support.at(i));
          std::vector<Point<dim>> all_boundary;
          for (const auto &part : Utilities::MPI::all_gather(comm, my_boundary))
            all_boundary.insert(all_boundary.end(), part.begin(), part.end());
          PointBins<dim> bins{r, {}};
          for (unsigned int j = 0; j < all_boundary.size(); ++j)
            bins.bins[bins.bin_of(all_boundary[j])].push_back(j);
          std::vector<std::pair<types::global_dof_index, Point<dim>>> my_candidates;
          for (const auto i : owned)
            if (bins.any_within(all_boundary, support.at(i), r))
              my_candidates.emplace_back(i, support.at(i));
          std::vector<Point<dim>> mine = my_boundary;
          PointBins<dim>          my_bins{r, {}};
          for (unsigned int j = 0; j < mine.size(); ++j)
            my_bins.bins[my_bins.bin_of(mine[j])].push_back(j);
          for (const auto &part : Utilities::MPI::all_gather(comm, my_candidates))
            for (const auto &[i, p] : part)
              if (!owned.is_element(i) && my_bins.any_within(mine, p, r))
                {
                  ghosts.add_index(i);
                  extra[i] = p;
                }
        }
      ghosts.compress();
      partitioner = std::make_shared<Utilities::MPI::Partitioner>(owned, ghosts, comm);
      const unsigned int n_local = partitioner->locally_owned_size() + partitioner->n_ghost_indices();
      points.resize(n_local);
      ids.resize(n_local);
      for (unsigned int l = 0; l < n_local; ++l)
        {
          ids[l]        = partitioner->local_to_global(l);
          const auto it = support.find(ids[l]);
          points[l]     = it != support.end() ? it->second : extra.at(ids[l]);
        }
      boundary.clear();
      normals.clear();
      curvatures.clear();
      for (const auto &[i, n] : normal_sum)
        {
          boundary.push_back(partitioner->global_to_local(i));
          normals.push_back(n / n.norm());
          const auto c = curvature_sum.find(i);
          curvatures.push_back(c != curvature_sum.end() && c->second.second > 0. ?
                                 (dim - 1.) * c->second.first / c->second.second :
                                 0.);
        }
    }

    template <int dim>
    void
    NearFieldLayout<dim>::reinit_matrix(TrilinosWrappers::SparseMatrix &matrix) const
    {
      DynamicSparsityPattern dsp(relevant);
      DoFTools::make_sparsity_pattern(*dof_handler, dsp);
      SparsityTools::distribute_sparsity_pattern(dsp, owned, comm, relevant);
      matrix.reinit(owned, owned, dsp, comm);
    }

    template <int dim>
    void
    NearFieldLayout<dim>::assemble(TrilinosWrappers::SparseMatrix &mass,
                                   TrilinosWrappers::SparseMatrix &laplace,
                                   DistributedVector              &lumped_mass,
                                   DistributedVector              &lumped_boundary_mass) const
    {
      reinit_matrix(mass);
      reinit_matrix(laplace);
      const auto              &fe = dof_handler->get_fe();
      const MappingQ1<dim>     mapping;
      const QGauss<dim>        q(fe.degree + 1);
      const QGaussLobatto<dim - 1> qf(fe.degree + 1);
      FEValues<dim>     fv(mapping, fe, q, update_values | update_gradients | update_JxW_values);
      FEFaceValues<dim> ff(mapping, fe, qf, update_values | update_JxW_values);
      const unsigned int                   nc = fe.n_dofs_per_cell();
      FullMatrix<double>                   m(nc, nc), k(nc, nc);
      std::vector<types::global_dof_index> dofs(nc);
      lumped_boundary_mass.reinit(partitioner);
      for (const auto &cell : dof_handler->active_cell_iterators())
        if (cell->is_locally_owned())
          {
            fv.reinit(cell);
            cell->get_dof_indices(dofs);
            m = 0.;
            k = 0.;
            for (unsigned int p = 0; p < q.size(); ++p)
              for (unsigned int i = 0; i < nc; ++i)
                for (unsigned int j = 0; j < nc; ++j)
                  {
                    m(i, j) += fv.shape_value(i, p) * fv.shape_value(j, p) * fv.JxW(p);
                    k(i, j) += fv.shape_grad(i, p) * fv.shape_grad(j, p) * fv.JxW(p);
                  }
            mass.add(dofs, m);
            laplace.add(dofs, k);
            for (const unsigned int f : cell->face_indices())
              if (cell->face(f)->at_boundary())
                {
                  ff.reinit(cell, f);
                  for (unsigned int i = 0; i < nc; ++i)
                    for (unsigned int p = 0; p < qf.size(); ++p)
                      lumped_boundary_mass(dofs[i]) += ff.shape_value(i, p) * ff.JxW(p);
                }
          }
      mass.compress(VectorOperation::add);
      laplace.compress(VectorOperation::add);
      lumped_boundary_mass.compress(VectorOperation::add);
      DistributedVector ones(partitioner);
      ones = 1.;
      lumped_mass.reinit(partitioner);
      mass.vmult(lumped_mass, ones);
    }

    template <int dim>
    double
    NearFieldLayout<dim>::largest_eigenvalue(const TrilinosWrappers::SparseMatrix &stiffness,
                                             const TrilinosWrappers::SparseMatrix &mass,
                                             const DistributedVector              &lumped_mass,
                                             const bool                            lumped,
                                             const unsigned int                    iterations) const
    {
      TrilinosWrappers::SolverDirect::AdditionalData ad(false, "Amesos_Klu");
      SolverControl                                  sc;
      TrilinosWrappers::SolverDirect                 mass_solver(sc, ad);
      if (!lumped)
        mass_solver.initialize(mass);
      DistributedVector x(partitioner), y(partitioner), z(partitioner);
      // Start vector from the support points (not the numbering), so that the
      // estimate does not depend on the partition.
      for (unsigned int l = 0; l < n_owned(); ++l)
        x.local_element(l) = std::sin(12.9898 * points[l][0] + (dim > 1 ? 78.233 * points[l][dim - 1] : 0.));
      double lambda = 0.;
      for (unsigned int it = 0; it < iterations; ++it)
        {
          x /= x.l2_norm();
          stiffness.vmult(y, x);
          if (lumped)
            for (unsigned int l = 0; l < n_owned(); ++l)
              y.local_element(l) /= lumped_mass.local_element(l);
          else
            {
              mass_solver.solve(z, y);
              y = z;
            }
          lambda = x * y;
          x      = y;
        }
      return lambda;
    }

    template <int dim>
    std::vector<std::pair<Point<dim>, double>>
    gather_by_point(const NearFieldLayout<dim> &layout, const DistributedVector &u)
    {
      std::vector<std::pair<Point<dim>, double>> mine, all;
      for (unsigned int l = 0; l < layout.n_owned(); ++l)
        mine.emplace_back(layout.points[l], u.local_element(l));
      for (const auto &part : Utilities::MPI::all_gather(layout.comm, mine))
        all.insert(all.end(), part.begin(), part.end());
      std::sort(all.begin(), all.end(), [](const auto &a, const auto &b) {
        for (unsigned int d = 0; d < dim; ++d)
          if (std::abs(a.first[d] - b.first[d]) > 1e-9)
            return a.first[d] < b.first[d];
        return false;
      });
      return all;
    }

    template class NearFieldLayout<1>;
    template class NearFieldLayout<2>;
    template class NearFieldLayout<3>;
    template std::vector<std::pair<Point<1>, double>>
    gather_by_point(const NearFieldLayout<1> &, const DistributedVector &);
    template std::vector<std::pair<Point<2>, double>>
    gather_by_point(const NearFieldLayout<2> &, const DistributedVector &);
    template std::vector<std::pair<Point<3>, double>>
    gather_by_point(const NearFieldLayout<3> &, const DistributedVector &);
  } // namespace Fem
} // namespace PeriDEAL
