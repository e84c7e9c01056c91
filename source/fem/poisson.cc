#include <deal.II/base/function.h>
#include <deal.II/base/quadrature_lib.h>

#include <deal.II/boost_adaptors/bounding_box.h>
#include <deal.II/boost_adaptors/point.h>

#include <deal.II/dofs/dof_tools.h>

#include <deal.II/fe/fe_values.h>

#include <deal.II/grid/grid_refinement.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/manifold_lib.h>
#include <deal.II/grid/tria_accessor.h>
#include <deal.II/grid/tria_iterator.h>

#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/sparse_direct.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>

#include <deal.II/numerics/error_estimator.h>
#include <deal.II/numerics/rtree.h>
#include <deal.II/numerics/vector_tools.h>

#include <perideal/base/exceptions.h>
#include <perideal/fem/poisson.h>

#include <cmath>
#include <limits>
#include <map>

namespace PeriDEAL
{
  namespace Fem
  {
    PoissonReference::PoissonReference(std::unique_ptr<Triangulation<2>> triangulation,
                                       const unsigned int                degree,
                                       const FacePredicate              &is_dirichlet,
                                       const ScalarFunction             &dirichlet_value,
                                       const ScalarFunction             &neumann_flux)
      : tria(std::move(triangulation))
      , fe(degree)
      , mapping(degree)
      , dof_handler(*tria)
      , is_dirichlet(is_dirichlet)
      , dirichlet_value(dirichlet_value)
      , neumann_flux(neumann_flux)
    {
      check_parameter(degree >= 1 && degree <= 4, "FEM degree", degree, "1 ... 4");
    }

    void
    PoissonReference::solve()
    {
      for (const auto &cell : tria->active_cell_iterators())
        for (const auto &face : cell->face_iterators())
          if (face->at_boundary())
            face->set_boundary_id(is_dirichlet(face->center()) ? 1 : 0);

      dof_handler.distribute_dofs(fe);
      constraints.clear();
      DoFTools::make_hanging_node_constraints(dof_handler, constraints);
      VectorTools::interpolate_boundary_values(
        mapping, dof_handler, 1,
        ScalarFunctionFromFunctionObject<2>([this](const Point<2> &p) { return dirichlet_value(p); }),
        constraints);
      constraints.close();

      DynamicSparsityPattern dsp(dof_handler.n_dofs());
      DoFTools::make_sparsity_pattern(dof_handler, dsp, constraints, false);
      SparsityPattern sp;
      sp.copy_from(dsp);
      SparseMatrix<double> matrix(sp);
      Vector<double>       rhs(dof_handler.n_dofs());
      solution.reinit(dof_handler.n_dofs());

      const QGauss<2>     quadrature(fe.degree + 1);
      const QGauss<1>     face_quadrature(fe.degree + 1);
      FEValues<2>         fe_values(mapping, fe, quadrature, update_gradients | update_JxW_values);
      FEFaceValues<2>     fe_face(mapping, fe, face_quadrature,
                              update_values | update_quadrature_points | update_JxW_values);
      const unsigned int  n = fe.n_dofs_per_cell();
      FullMatrix<double>  cell_matrix(n, n);
      Vector<double>      cell_rhs(n);
      std::vector<types::global_dof_index> dofs(n);
      for (const auto &cell : dof_handler.active_cell_iterators())
        {
          fe_values.reinit(cell);
          cell_matrix = 0.;
          cell_rhs    = 0.;
          for (unsigned int q = 0; q < quadrature.size(); ++q)
            for (unsigned int i = 0; i < n; ++i)
              for (unsigned int j = 0; j < n; ++j)
                cell_matrix(i, j) +=
                  fe_values.shape_grad(i, q) * fe_values.shape_grad(j, q) * fe_values.JxW(q);
          if (neumann_flux)
            for (const auto f : cell->face_indices())
              if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == 0)
                {
                  fe_face.reinit(cell, f);
                  for (unsigned int q = 0; q < face_quadrature.size(); ++q)
                    {
                      const double g = neumann_flux(fe_face.quadrature_point(q));
                      for (unsigned int i = 0; i < n; ++i)
                        cell_rhs(i) += g * fe_face.shape_value(i, q) * fe_face.JxW(q);
                    }
                }
          cell->get_dof_indices(dofs);
          constraints.distribute_local_to_global(cell_matrix, cell_rhs, dofs, matrix, rhs);
        }
      SparseDirectUMFPACK direct;
      direct.initialize(matrix);
      direct.vmult(solution, rhs);
      constraints.distribute(solution);
    }

    void
    PoissonReference::refine_kelly(const double top_fraction)
    {
      check_parameter(top_fraction > 0. && top_fraction <= 1., "Kelly refinement fraction",
                      top_fraction, "(0, 1]");
      Vector<float> indicators(tria->n_active_cells());
      KellyErrorEstimator<2>::estimate(mapping, dof_handler, QGauss<1>(fe.degree + 1), {},
                                       solution, indicators);
      GridRefinement::refine_and_coarsen_fixed_number(*tria, indicators, top_fraction, 0.);
      tria->execute_coarsening_and_refinement();
    }

    void
    PoissonReference::refine_around(const Point<2> &p, const double radius, const unsigned int times)
    {
      for (unsigned int k = 0; k < times; ++k)
        {
          for (const auto &cell : tria->active_cell_iterators())
            for (const auto v : cell->vertex_indices())
              if (cell->vertex(v).distance(p) <= radius)
                {
                  cell->set_refine_flag();
                  break;
                }
          tria->execute_coarsening_and_refinement();
        }
    }

    std::vector<double>
    PoissonReference::values_at(const std::vector<Point<2>> &points) const
    {
      // Candidate cells from an R-tree of (slightly enlarged, since the
      // mapping curves boundary cells) vertex bounding boxes; the owner is
      // the first candidate whose inverse mapping lands in the unit cell.
      using CellIt = typename DoFHandler<2>::active_cell_iterator;
      std::vector<std::pair<BoundingBox<2>, unsigned int>> boxes;
      std::vector<CellIt>                                 cells;
      for (const auto &cell : dof_handler.active_cell_iterators())
        {
          BoundingBox<2> box = cell->bounding_box();
          box.extend(0.1 * cell->diameter());
          boxes.emplace_back(box, cells.size());
          cells.push_back(cell);
        }
      const auto tree = pack_rtree(boxes);

      std::vector<double>                  values(points.size(), std::numeric_limits<double>::quiet_NaN());
      std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
      for (unsigned int k = 0; k < points.size(); ++k)
        {
          std::vector<std::pair<BoundingBox<2>, unsigned int>> hits;
          tree.query(boost::geometry::index::intersects(points[k]), std::back_inserter(hits));
          for (const auto &h : hits)
            {
              const CellIt &cell = cells[h.second];
              Point<2>      unit;
              try
                {
                  unit = mapping.transform_real_to_unit_cell(cell, points[k]);
                }
              catch (...)
                {
                  continue;
                }
              if (!GeometryInfo<2>::is_inside_unit_cell(unit, 1e-10))
                continue;
              cell->get_dof_indices(dofs);
              double u = 0.;
              for (unsigned int i = 0; i < dofs.size(); ++i)
                u += solution(dofs[i]) * fe.shape_value(i, unit);
              values[k] = u;
              break;
            }
        }
      return values;
    }

    std::unique_ptr<Triangulation<2>>
    cracked_disk(const double       radius,
                 const double       half_length,
                 const bool         crossing,
                 const unsigned int n_refinements)
    {
      check_parameter(radius > 0., "Disk radius", radius, "a positive number");
      check_parameter(half_length > 0. && half_length <= 0.5 * radius, "Crack half length",
                      half_length, "(0, radius / 2]");
      check_parameter(n_refinements >= 1, "Crack mesh refinements", n_refinements, ">= 1");
      const double a = half_length, s = radius / std::sqrt(2.);

      // The five-cell disk of GridGenerator::hyper_ball with the inner square
      // [-a, a]^2, so that the cracks run along its mid lines.
      Triangulation<2> coarse;
      {
        const std::vector<Point<2>> v = {{-a, -a}, {a, -a}, {-a, a}, {a, a},
                                         {-s, -s}, {s, -s}, {-s, s}, {s, s}};
        const unsigned int          c[5][4] = {
          {0, 1, 2, 3}, {4, 5, 0, 1}, {2, 3, 6, 7}, {4, 0, 6, 2}, {1, 5, 3, 7}};
        std::vector<CellData<2>> cells(5);
        for (unsigned int i = 0; i < 5; ++i)
          for (unsigned int j = 0; j < 4; ++j)
            cells[i].vertices[j] = c[i][j];
        GridTools::consistently_order_cells(cells);
        coarse.create_triangulation(v, cells, SubCellData());
      }
      const SphericalManifold<2> circle;
      // Boundary faces on the circle (not on a crack: those are within
      // a of the center) follow the circle.
      const auto mark_circle = [&](Triangulation<2> &t, const double threshold) {
        for (const auto &cell : t.active_cell_iterators())
          for (const auto &face : cell->face_iterators())
            if (face->at_boundary() && face->center().norm() > threshold)
              face->set_manifold_id(0);
        t.set_manifold(0, circle);
      };
      mark_circle(coarse, 0.);
      coarse.refine_global(n_refinements);

      // Duplicate the vertices on the open cracks: one copy per side.
      const double               eps      = 1e-10 * radius;
      const std::vector<Point<2>> &old_v = coarse.get_vertices();
      std::vector<Point<2>>        vertices(old_v.begin(), old_v.end());
      std::map<std::pair<unsigned int, unsigned int>, unsigned int> copies;
      std::vector<CellData<2>>                                     cells;
      for (const auto &cell : coarse.active_cell_iterators())
        {
          CellData<2>    data;
          const Point<2> c = cell->center();
          for (const auto v : cell->vertex_indices())
            {
              const unsigned int index = cell->vertex_index(v);
              const Point<2>    &p     = old_v[index];
              unsigned int       side  = 0; // bits: on crack 1, above; on crack 2, right
              if (std::abs(p[1]) < eps && std::abs(p[0]) < a - eps)
                side |= 1u | (c[1] > 0 ? 2u : 0u);
              if (crossing && std::abs(p[0]) < eps && std::abs(p[1]) < a - eps)
                side |= 4u | (c[0] > 0 ? 8u : 0u);
              unsigned int target = index;
              if (side != 0)
                {
                  const auto it = copies.find({index, side});
                  if (it != copies.end())
                    target = it->second;
                  else
                    {
                      // The first side keeps the original vertex.
                      bool first = true;
                      for (const auto &e : copies)
                        if (e.first.first == index)
                          first = false;
                      if (!first)
                        {
                          target = vertices.size();
                          vertices.push_back(p);
                        }
                      copies[{index, side}] = target;
                    }
                }
              data.vertices[v] = target;
            }
          cells.push_back(data);
        }
      // Drop vertices the coarse hierarchy had but the active cells do not use.
      std::vector<bool> referenced(vertices.size(), false);
      for (const auto &c : cells)
        for (const auto v : c.vertices)
          referenced[v] = true;
      std::vector<unsigned int> renumber(vertices.size(), numbers::invalid_unsigned_int);
      std::vector<Point<2>>     compact;
      for (unsigned int i = 0; i < vertices.size(); ++i)
        if (referenced[i])
          {
            renumber[i] = compact.size();
            compact.push_back(vertices[i]);
          }
      for (auto &c : cells)
        for (auto &v : c.vertices)
          v = renumber[v];

      auto tria = std::make_unique<Triangulation<2>>();
      tria->create_triangulation(compact, cells, SubCellData());
      mark_circle(*tria, a + 0.5 * (radius - a));
      return tria;
    }
  } // namespace Fem
} // namespace PeriDEAL
