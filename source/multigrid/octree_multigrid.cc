#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>

#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/multigrid/lattice_tools.h>
#include <perideal/multigrid/octree_multigrid.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>

namespace PeriDEAL
{
  namespace MultiGrid
  {
    template <int dim>
    void
    OctreeParameters<dim>::check() const
    {
      grid.check();
      check_parameter(grid.interpolation != Interpolation::nearest_active,
                      "Multi-grid/Interpolation", "nearest active",
                      "'inverse distance' or 'multilinear' on the octree");
      check_parameter(transport.scheme == "forward Euler" || transport.scheme == "backward Euler",
                      "Time stepping/Scheme", transport.scheme,
                      "'forward Euler' or 'backward Euler' on the octree multi-grid");
      check_parameter(transport.coarse_quadrature == "standard",
                      "Multi-grid/Coarse quadrature", transport.coarse_quadrature,
                      "'standard' on the octree multi-grid");
      if (transport.corrosion)
        check_parameter(transport.kappa_liquid >= 0. && transport.kappa_interface >= 0. &&
                          transport.kappa_solid >= 0.,
                        "Model/Corrosion/Micro-diffusivities", transport.kappa_liquid,
                        "non-negative numbers");
      else
        check_parameter(transport.kappa > 0., "Model/Micro-diffusivity", transport.kappa,
                        "a positive number");
      check_parameter(indicator_threshold > 0., "Multi-grid/Indicator threshold",
                      indicator_threshold, "a positive number");
      check_parameter(switching_interval >= 1, "Multi-grid/Switching interval",
                      switching_interval, "an integer >= 1");
      if (coarsening)
        check_parameter(coarsening_threshold > 0. && coarsening_threshold < indicator_threshold,
                        "Multi-grid/Coarsening threshold", coarsening_threshold,
                        "a positive number below the indicator threshold " +
                          std::to_string(indicator_threshold));
    }

    template <int dim>
    struct OctreeMultiGrid<dim>::Implicit
    {
      TrilinosWrappers::SparseMatrix                  matrix;
      SolverControl                                   control{1, 0.};
      std::unique_ptr<TrilinosWrappers::SolverDirect> solver;
      bool                                            valid = false;
    };

    namespace
    {
      template <int dim>
      using Idx = Lattice::Index<dim>;
      using Lattice::in_range;
      using Lattice::unravel;

      template <int dim>
      long long
      linear_index(const Idx<dim> &i, const Idx<dim> &n)
      {
        return Lattice::linear<dim>(i, n);
      }

      // corners of x's cell in the lattice {origin + i s}, i in [0, n), and
      // their weights: the serial multi-grid's rule (Lattice helpers)
      template <int dim>
      void
      corner_interpolation(const Point<dim>      &x,
                           const Point<dim>      &origin,
                           const double           s,
                           const Idx<dim>        &n,
                           const Interpolation    scheme,
                           std::vector<Idx<dim>> &corners,
                           std::vector<double>   &weights)
      {
        std::vector<double> multilinear;
        Lattice::enclosing_corners<dim>(x, origin, s, n, corners, multilinear);
        std::vector<Point<dim>> points(corners.size());
        for (unsigned int c = 0; c < corners.size(); ++c)
          for (unsigned int d = 0; d < dim; ++d)
            points[c][d] = origin[d] + corners[c][d] * s;
        Lattice::corner_weights<dim>(x, points, multilinear,
                                     scheme == Interpolation::multilinear ?
                                       Interpolation::multilinear :
                                       Interpolation::inverse_distance,
                                     s, weights);
      }
    } // namespace

    template <int dim>
    OctreeMultiGrid<dim>::OctreeMultiGrid(const MPI_Comm comm_, const OctreeParameters<dim> &p)
      : comm(comm_)
      , prm(p)
      , tria(comm_)
      , implicit(std::make_unique<Implicit>())
    {
      static_assert(dim >= 2, "p4est: 2D and 3D only");
      prm.check();
      const auto &g = prm.grid;
      H             = g.coarse_dx;
      h             = g.fine_dx;
      ratio         = std::llround(H / h);
      // the cell side holds the bond reach and the interpolation chain of a
      // fictitious node (fine fictitious -> coarse corner -> fine sources)
      k_cell = (long long)std::ceil((g.delta + 1.5 * H + 0.5 * h) / H - 1e-9);
      Point<dim> p1, p2;
      std::vector<unsigned int> reps(dim);
      long long n_total_blocks = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          nc[d]          = (long long)std::floor((g.upper[d] - g.lower[d]) / H + 1e-9) + 1;
          nf[d]          = ratio * nc[d];
          n_blocks[d]    = (nc[d] + k_cell - 1) / k_cell;
          fine_origin[d] = g.lower[d] - 0.5 * H + 0.5 * h;
          p1[d]          = g.lower[d] - 0.5 * H;
          p2[d]          = p1[d] + n_blocks[d] * k_cell * H;
          reps[d]        = n_blocks[d];
          n_total_blocks *= n_blocks[d];
        }
      GridGenerator::subdivided_hyper_rectangle(tria, reps, p1, p2);

      kernel.dim      = dim;
      kernel.omega    = g.omega;
      kernel.exponent = g.exponent;
      kernel.delta    = g.delta;
      kernel.constant = 1.;
      for (const unsigned int fine : {0u, 1u})
        {
          // offsets with beta > 0 in the serial code's order (d = 0 fastest)
          const double s = fine ? h : H;
          stencil[fine]  = Lattice::stencil<dim>(s, g.delta, g.partial_volume);
          double m2      = 0.;
          for (const auto &[o, r] : stencil[fine])
            {
              // as DiffusionOperator: omega at min(r, delta) in the shell
              stencil_weight[fine].push_back(
                kernel(std::min(r, g.delta)) *
                PeriDEAL::Discretization<dim>::volume_factor(r, g.delta, s, g.partial_volume) *
                std::pow(s, dim));
              m2 += stencil_weight[fine].back() * double(o[0] * o[0]) * s * s;
            }
          if (prm.transport.calibrate)
            for (double &w : stencil_weight[fine])
              w *= kernel.second_moment() / m2;
        }

      // initial flags: a cell is fine if one of its coarse nodes is in the region
      block_fine.assign(n_total_blocks, 0);
      std::vector<Index> nodes;
      for (long long b = 0; b < n_total_blocks; ++b)
        {
          block_nodes(b, false, nodes);
          for (const auto &K : nodes)
            if (g.fine_region.contains(point_of(false, K)))
              block_fine[b] = 1;
        }
      // weight of a cell for the partition: its bonds (+1: p4est needs > 0)
      tria.signals.weight.connect(
        [this](const typename Triangulation<dim>::cell_iterator &cell,
               const typename Triangulation<dim>::CellStatus) -> unsigned int {
          const long long    b    = block_of_cell(cell);
          std::vector<Index> n;
          block_nodes(b, block_fine[b], n);
          return 1 + n.size() * stencil[block_fine[b]].size();
        });
      tria.repartition();
      build(nullptr);
    }

    template <int dim>
    OctreeMultiGrid<dim>::~OctreeMultiGrid() = default;

    template <int dim>
    long long
    OctreeMultiGrid<dim>::block_of_cell(const typename Triangulation<dim>::cell_iterator &cell) const
    {
      Index            B;
      const Point<dim> c = cell->center();
      for (unsigned int d = 0; d < dim; ++d)
        B[d] = (long long)std::floor((c[d] - (prm.grid.lower[d] - 0.5 * H)) / (k_cell * H));
      return linear_index<dim>(B, n_blocks);
    }

    template <int dim>
    long long
    OctreeMultiGrid<dim>::block_of_coarse(const Index &K) const
    {
      Index B;
      for (unsigned int d = 0; d < dim; ++d)
        B[d] = K[d] / k_cell;
      return linear_index<dim>(B, n_blocks);
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::block_nodes(const long long b, const bool fine, std::vector<Index> &out) const
    {
      out.clear();
      const Index B = unravel<dim>(b, n_blocks);
      Index       lo, n;
      long long   total = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          lo[d] = B[d] * k_cell;
          n[d]  = std::max(0LL, std::min(k_cell, nc[d] - lo[d]));
          total *= n[d];
        }
      long long r_dim = 1;
      for (unsigned int d = 0; d < dim; ++d)
        r_dim *= ratio;
      for (long long q = 0; q < total; ++q)
        {
          Index K = unravel<dim>(q, n);
          for (unsigned int d = 0; d < dim; ++d)
            K[d] += lo[d];
          if (!fine)
            out.push_back(K);
          else
            for (long long s = 0; s < r_dim; ++s)
              {
                Index     i;
                long long rest = s;
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    i[d] = K[d] * ratio + rest % ratio;
                    rest /= ratio;
                  }
                out.push_back(i);
              }
        }
    }

    template <int dim>
    std::uint64_t
    OctreeMultiGrid<dim>::id_of(const bool fine, const Index &i) const
    {
      if (!fine)
        return linear_index<dim>(i, nc);
      long long n_coarse = 1;
      for (unsigned int d = 0; d < dim; ++d)
        n_coarse *= nc[d];
      return n_coarse + linear_index<dim>(i, nf);
    }

    template <int dim>
    Point<dim>
    OctreeMultiGrid<dim>::point_of(const bool fine, const Index &i) const
    {
      Point<dim> p;
      for (unsigned int d = 0; d < dim; ++d)
        p[d] = fine ? fine_origin[d] + i[d] * h : prm.grid.lower[d] + i[d] * H;
      return p;
    }

    template <int dim>
    std::uint64_t
    OctreeMultiGrid<dim>::node_id(const Point<dim> &x, const bool fine) const
    {
      Index i;
      for (unsigned int d = 0; d < dim; ++d)
        i[d] = std::llround(fine ? (x[d] - fine_origin[d]) / h : (x[d] - prm.grid.lower[d]) / H);
      return id_of(fine, i);
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::build(const std::unordered_map<long long, std::vector<double>> *values)
    {
      // 1. owned cells in cell order: active nodes, global numbering
      node_position.clear();
      node_fine.clear();
      node_id_local.clear();
      local_of_id.clear();
      std::vector<Index>                       lattice; // per local node
      std::map<long long, std::pair<unsigned int, unsigned int>> owned_range;
      std::vector<Index>                       nodes;
      for (const auto &cell : tria.active_cell_iterators())
        if (cell->is_locally_owned())
          {
            const long long b = block_of_cell(cell);
            block_nodes(b, block_fine[b], nodes);
            owned_range[b] = {(unsigned int)node_position.size(), (unsigned int)nodes.size()};
            for (const auto &i : nodes)
              {
                lattice.push_back(i);
                node_fine.push_back(block_fine[b]);
                node_position.push_back(point_of(block_fine[b], i));
                node_id_local.push_back(id_of(block_fine[b], i));
              }
          }
      n_owned = node_position.size();
      unsigned long long start = 0, n_mine = n_owned;
      MPI_Exscan(&n_mine, &start, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
      if (Utilities::MPI::this_mpi_process(comm) == 0)
        start = 0;
      const unsigned long long n_global = Utilities::MPI::sum(n_mine, comm);

      // 2. ghost cells: the first global index of each cell from its owner
      std::map<long long, unsigned long long> ghost_start;
      GridTools::exchange_cell_data_to_ghosts<unsigned long long, Triangulation<dim>>(
        tria,
        [&](const typename Triangulation<dim>::active_cell_iterator &cell) {
          return std_cxx17::optional<unsigned long long>(start +
                                                         owned_range.at(block_of_cell(cell)).first);
        },
        [&](const typename Triangulation<dim>::active_cell_iterator &cell,
            const unsigned long long                                 s) {
          ghost_start[block_of_cell(cell)] = s;
        });
      std::vector<std::tuple<unsigned long long, long long, unsigned int>> ghosts; // global, block, k
      for (const auto &[b, s] : ghost_start)
        {
          block_nodes(b, block_fine[b], nodes);
          for (unsigned int q = 0; q < nodes.size(); ++q)
            ghosts.emplace_back(s + q, b, q);
        }
      std::sort(ghosts.begin(), ghosts.end());
      IndexSet owned_set(n_global), ghost_set(n_global);
      owned_set.add_range(start, start + n_owned);
      std::vector<types::global_dof_index> ghost_indices;
      long long                            last_block = -1;
      for (const auto &[gi, b, q] : ghosts)
        {
          if (b != last_block)
            block_nodes(b, block_fine[b], nodes), last_block = b;
          ghost_indices.push_back(gi);
          lattice.push_back(nodes[q]);
          node_fine.push_back(block_fine[b]);
          node_position.push_back(point_of(block_fine[b], nodes[q]));
          node_id_local.push_back(id_of(block_fine[b], nodes[q]));
        }
      ghost_set.add_indices(ghost_indices.begin(), ghost_indices.end());
      n_local_active = node_position.size();
      for (unsigned int i = 0; i < n_local_active; ++i)
        local_of_id[node_id_local[i]] = i;
      C.reinit(owned_set, ghost_set, comm);
      phase.reinit(C);
      rate.reinit(C);
      if (values)
        for (const auto &[b, range] : owned_range)
          {
            const auto &v = values->at(b);
            AssertThrow(v.size() == 2 * range.second, ExcInternalError());
            for (unsigned int q = 0; q < range.second; ++q)
              {
                C.local_element(range.first + q)     = v[q];
                phase.local_element(range.first + q) = v[range.second + q];
              }
          }

      // 3. bonds of the owned rows; fictitious nodes where the lattice
      // point is inactive in the row's grid
      std::unordered_map<std::uint64_t, unsigned int> fictitious;
      std::vector<unsigned int>                       fict_coarse, fict_fine;
      auto grid_fine_at = [&](const bool fine, const Index &i) {
        Index K = i;
        if (fine)
          for (unsigned int d = 0; d < dim; ++d)
            K[d] = i[d] / ratio;
        return block_fine[block_of_coarse(K)] != 0;
      };
      // local index of lattice point i of grid `fine`: active or fictitious
      auto node_of = [&](const bool fine, const Index &i) -> unsigned int {
        const std::uint64_t id = id_of(fine, i);
        if (grid_fine_at(fine, i) == fine)
          {
            const auto it = local_of_id.find(id);
            AssertThrow(it != local_of_id.end(),
                        ExcMessage("octree multi-grid: an active neighbour is not in a local "
                                   "cell (cell side too small)"));
            return it->second;
          }
        const auto it = fictitious.find(id);
        if (it != fictitious.end())
          return it->second;
        const unsigned int k = node_position.size();
        fictitious[id]       = k;
        (fine ? fict_fine : fict_coarse).push_back(k);
        lattice.push_back(i);
        node_fine.push_back(fine);
        node_position.push_back(point_of(fine, i));
        node_id_local.push_back(id);
        return k;
      };
      row_start.assign(1, 0);
      col.clear();
      bond_entry.clear();
      for (unsigned int a = 0; a < n_owned; ++a)
        {
          const bool   fine = node_fine[a];
          const Index &n    = fine ? nf : nc;
          for (unsigned int e = 0; e < stencil[fine].size(); ++e)
            {
              Index j;
              for (unsigned int d = 0; d < dim; ++d)
                j[d] = lattice[a][d] + stencil[fine][e].first[d];
              if (!in_range<dim>(j, n))
                continue; // beyond the body: no bond (free nonlocal boundary)
              col.push_back(node_of(fine, j));
              bond_entry.push_back(e);
            }
          row_start.push_back(col.size());
        }

      // 4. interpolation: coarse corners of the fine fictitious nodes
      // first (they may create coarse fictitious nodes), then the rows
      std::vector<Index>  corners;
      std::vector<double> w;
      for (std::size_t q = 0; q < fict_fine.size(); ++q)
        {
          corner_interpolation<dim>(node_position[fict_fine[q]], prm.grid.lower, H, nc,
                                    prm.grid.interpolation, corners, w);
          for (const auto &K : corners)
            node_of(false, K);
        }
      interp_node.clear();
      interp_start.assign(1, 0);
      interp_source.clear();
      interp_weight.clear();
      for (const bool fine : {false, true})
        for (const unsigned int k : fine ? fict_fine : fict_coarse)
          {
            // coarse fictitious: fine corners (active, in its refined cell);
            // fine fictitious: coarse corners (active or coarse fictitious)
            corner_interpolation<dim>(node_position[k], fine ? prm.grid.lower : fine_origin,
                                      fine ? H : h, fine ? nc : nf, prm.grid.interpolation,
                                      corners, w);
            interp_node.push_back(k);
            for (unsigned int c = 0; c < corners.size(); ++c)
              if (w[c] > 0.)
                {
                  const unsigned int s = node_of(!fine, corners[c]);
                  AssertThrow(fine || s < n_local_active, ExcInternalError());
                  interp_source.push_back(s);
                  interp_weight.push_back(w[c]);
                }
            interp_start.push_back(interp_source.size());
          }
      // expanded to active sources (coarse rows come first)
      active_interpolation.assign(node_position.size() - n_local_active, {});
      for (unsigned int row = 0; row < interp_node.size(); ++row)
        {
          std::map<unsigned int, double> acc;
          for (unsigned int q = interp_start[row]; q < interp_start[row + 1]; ++q)
            {
              const unsigned int s = interp_source[q];
              if (s < n_local_active)
                acc[s] += interp_weight[q];
              else
                for (const auto &[a, wa] : active_interpolation[s - n_local_active])
                  acc[a] += interp_weight[q] * wa;
            }
          active_interpolation[interp_node[row] - n_local_active].assign(acc.begin(), acc.end());
        }
      work_c.assign(node_position.size(), 0.);
      work_phase.assign(node_position.size(), 0.);
      C.update_ghost_values();
      phase.update_ghost_values();
      refresh_work();
      compute_time_step_bound();
    }

    template <int dim>
    template <typename F>
    void
    OctreeMultiGrid<dim>::operator_entries(const bool kappa_max, const F &emit) const
    {
      // (3.82)/(3.84) row by row as apply(): (i, j) += c, (i, i) -= c, and
      // the conservative pay-back of fine rows to the donors of C_j
      const auto  &tp   = prm.transport;
      const double kmax = tp.corrosion ? std::max({tp.kappa_liquid, tp.kappa_interface,
                                                   tp.kappa_solid}) :
                                         tp.kappa;
      auto expand = [&](const unsigned int row, const unsigned int c, const double v) {
        if (c < n_local_active)
          emit(row, c, v);
        else
          for (const auto &[a, wa] : active_interpolation[c - n_local_active])
            emit(row, a, v * wa);
      };
      for (unsigned int i = 0; i < n_owned; ++i)
        {
          const bool   fine = node_fine[i];
          const double Vi   = std::pow(fine ? h : H, dim);
          for (unsigned int b = row_start[i]; b < row_start[i + 1]; ++b)
            {
              const unsigned int j    = col[b];
              const bool         fict = j >= n_local_active;
              if (fict && tp.conservative && !fine)
                continue;
              const double c = (kappa_max ? kmax : bond_kappa(work_phase[i], work_phase[j])) *
                               stencil_weight[fine][bond_entry[b]];
              expand(i, j, c);
              emit(i, i, -c);
              if (fict && tp.conservative)
                for (const auto &[a, wa] : active_interpolation[j - n_local_active])
                  {
                    const double f = wa * c * Vi / std::pow(node_fine[a] ? h : H, dim);
                    expand(a, j, -f);
                    emit(a, i, f);
                  }
            }
        }
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::compute_time_step_bound()
    {
      // Gershgorin of the fictitious-expanded operator with the largest
      // kappa: interpolation coupling 1/|L_ii| (rows sum to 0, off-diagonal
      // entries >= 0: max principle, as the serial solver); conservative
      // coupling 2/(|L_ii| + R_i) with the pay-back entries of remote rows
      // gathered by compress(add), duplicates not merged (R_i is then an
      // upper bound of the serial solver's: the bound is never larger).
      const auto &tp = prm.transport;
      LinearAlgebra::distributed::Vector<double> diag(C), off(C);
      for (unsigned int i = 0; i < n_local_active; ++i)
        diag.local_element(i) = off.local_element(i) = 0.;
      operator_entries(true, [&](const unsigned int row, const unsigned int c, const double v) {
        if (c == row)
          diag.local_element(row) += v;
        else
          off.local_element(row) += std::abs(v);
      });
      diag.compress(VectorOperation::add);
      off.compress(VectorOperation::add);
      double bound = std::numeric_limits<double>::infinity();
      for (unsigned int i = 0; i < n_owned; ++i)
        {
          const double d = std::abs(diag.local_element(i)), r = off.local_element(i);
          if (d > 0.)
            bound = std::min(bound, tp.conservative ? 2. / (d + r) : 1. / d);
        }
      dt_critical = Utilities::MPI::min(bound, comm);
      dt          = tp.time_step > 0. ? tp.time_step : 0.9 * dt_critical;
      if (tp.scheme == "forward Euler")
        check_parameter(dt <= dt_critical * (1. + 1e-12), "Time stepping/Time step", dt,
                        "a step not above the forward Euler bound " +
                          std::to_string(dt_critical) + " of the current multi-grid");
      implicit->valid = false;
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::update_fictitious(std::vector<double> &v) const
    {
      for (unsigned int row = 0; row < interp_node.size(); ++row)
        {
          double s = 0.;
          for (unsigned int q = interp_start[row]; q < interp_start[row + 1]; ++q)
            s += interp_weight[q] * v[interp_source[q]];
          v[interp_node[row]] = s;
        }
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::refresh_work()
    {
      for (unsigned int i = 0; i < n_local_active; ++i)
        {
          work_c[i]     = C.local_element(i);
          work_phase[i] = phase.local_element(i);
        }
      update_fictitious(work_c);
      // fictitious phase: the interpolated phase field, thresholded at 1/2
      update_fictitious(work_phase);
      for (std::size_t k = n_local_active; k < work_phase.size(); ++k)
        work_phase[k] = work_phase[k] >= 0.5 ? 1. : 0.;
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::initialize_phase()
    {
      for (unsigned int i = 0; i < n_owned; ++i)
        phase.local_element(i) =
          prm.transport.corrosion && C.local_element(i) >= prm.transport.saturation ? 1. : 0.;
      C.update_ghost_values();
      phase.update_ghost_values();
      refresh_work();
    }

    template <int dim>
    double
    OctreeMultiGrid<dim>::bond_kappa(const double pi, const double pj) const
    {
      const auto &tp = prm.transport;
      if (!tp.corrosion)
        return tp.kappa;
      const bool si = pi > 0.5, sj = pj > 0.5;
      return si && sj ? tp.kappa_solid : (si || sj ? tp.kappa_interface : tp.kappa_liquid);
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::apply(LinearAlgebra::distributed::Vector<double> &out) const
    {
      // (3.82)/(3.84), as the serial TransportSolver::apply
      const bool conservative = prm.transport.conservative;
      for (unsigned int i = 0; i < n_local_active; ++i)
        out.local_element(i) = 0.;
      const std::array<double, 2> V{{std::pow(H, dim), std::pow(h, dim)}};
      for (unsigned int i = 0; i < n_owned; ++i)
        {
          const bool fine            = node_fine[i];
          const bool skip_fictitious = conservative && !fine;
          const bool pay_back        = conservative && fine;
          const auto &sw             = stencil_weight[fine];
          double      s              = 0.;
          for (unsigned int b = row_start[i]; b < row_start[i + 1]; ++b)
            {
              const unsigned int j    = col[b];
              const bool         fict = j >= n_local_active;
              if (fict && skip_fictitious)
                continue;
              const double q = bond_kappa(work_phase[i], work_phase[j]) * sw[bond_entry[b]] *
                               (work_c[j] - work_c[i]);
              s += q;
              if (fict && pay_back)
                // the mass V_i q comes from the nodes that define C_j
                for (const auto &[a, w] : active_interpolation[j - n_local_active])
                  out.local_element(a) -= w * q * V[1] / V[node_fine[a]];
            }
          out.local_element(i) += s;
        }
      if (conservative)
        out.compress(VectorOperation::add);
    }

    template <int dim>
    unsigned int
    OctreeMultiGrid<dim>::adapt()
    {
      // 1. indicator on the owned cells: range of C over the cell's active
      // nodes, and whether they hold both phases (every rank gets all cells)
      std::vector<double> range(block_fine.size(), 0.);
      std::vector<int>    mixed(block_fine.size(), 0);
      {
        std::vector<Index> nodes;
        for (const auto &cell : tria.active_cell_iterators())
          if (cell->is_locally_owned())
            {
              const long long b = block_of_cell(cell);
              block_nodes(b, block_fine[b], nodes);
              double lo = std::numeric_limits<double>::infinity(), hi = -lo;
              bool   solid = false, liquid = false;
              for (const auto &i : nodes)
                {
                  const unsigned int a = local_of_id.at(id_of(block_fine[b], i));
                  lo                   = std::min(lo, C.local_element(a));
                  hi                   = std::max(hi, C.local_element(a));
                  (phase.local_element(a) > 0.5 ? solid : liquid) = true;
                }
              range[b] = nodes.empty() ? 0. : hi - lo;
              mixed[b] = solid && liquid;
            }
      }
      MPI_Allreduce(MPI_IN_PLACE, range.data(), range.size(), MPI_DOUBLE, MPI_MAX, comm);
      MPI_Allreduce(MPI_IN_PLACE, mixed.data(), mixed.size(), MPI_INT, MPI_MAX, comm);
      auto neighbours = [&](const long long b) {
        // b itself and its 3^dim - 1 neighbours
        std::vector<long long> out;
        const Index            B = unravel<dim>(b, n_blocks);
        for (unsigned int q = 0; q < std::pow(3, dim); ++q)
          {
            Index        N;
            unsigned int rest = q;
            for (unsigned int d = 0; d < dim; ++d)
              {
                N[d] = B[d] + int(rest % 3) - 1;
                rest /= 3;
              }
            if (in_range<dim>(N, n_blocks))
              out.push_back(linear_index<dim>(N, n_blocks));
          }
        return out;
      };
      std::vector<char> new_fine = block_fine;
      for (long long b = 0; b < (long long)block_fine.size(); ++b)
        if (!block_fine[b])
          {
            // a critical coarse cell and its neighbours become fine
            for (const long long n : neighbours(b))
              if (!block_fine[n] && range[n] > prm.indicator_threshold)
                new_fine[b] = 1;
          }
        else if (prm.coarsening)
          {
            // the front has passed: smooth and single-phase all around
            // (coarsening_threshold < indicator_threshold: no flip-flop)
            bool smooth = true;
            for (const long long n : neighbours(b))
              smooth = smooth && range[n] < prm.coarsening_threshold && !mixed[n];
            if (smooth)
              new_fine[b] = 0;
          }
      return transfer(new_fine);
    }

    template <int dim>
    unsigned int
    OctreeMultiGrid<dim>::set_fine_cells(const std::function<bool(const Point<dim> &)> &fine)
    {
      std::vector<char> new_fine(block_fine.size());
      for (long long b = 0; b < (long long)block_fine.size(); ++b)
        {
          const Index B = unravel<dim>(b, n_blocks);
          Point<dim>  centre;
          for (unsigned int d = 0; d < dim; ++d)
            centre[d] = prm.grid.lower[d] - 0.5 * H + (B[d] + 0.5) * k_cell * H;
          new_fine[b] = fine(centre) ? 1 : 0;
        }
      return transfer(new_fine);
    }

    template <int dim>
    unsigned int
    OctreeMultiGrid<dim>::transfer(const std::vector<char> &new_fine)
    {
      unsigned int n_switched = 0, n_to_coarse = 0;
      for (std::size_t b = 0; b < block_fine.size(); ++b)
        if (new_fine[b] != block_fine[b])
          {
            ++n_switched;
            n_to_coarse += block_fine[b];
          }
      if (n_switched == 0)
        return 0;

      // 2. values of the owned cells under the new flags: a cell switched
      // to fine takes the fine fictitious interpolation from the coarse
      // grid, a cell switched to coarse the cell means of the fine values
      std::map<long long, std::vector<double>> outgoing;
      {
        std::vector<Index>  nodes, corners, fine_corners, old_nodes;
        std::vector<double> w, wf;
        // value of a coarse lattice point: active, or fictitious (from the
        // fine nodes of its refined cell); C and phase
        auto coarse_value = [&](const Index &K) -> std::array<double, 2> {
          if (!block_fine[block_of_coarse(K)])
            {
              const unsigned int a = local_of_id.at(id_of(false, K));
              return {{C.local_element(a), phase.local_element(a)}};
            }
          corner_interpolation<dim>(point_of(false, K), fine_origin, h, nf,
                                    prm.grid.interpolation, fine_corners, wf);
          std::array<double, 2> v{{0., 0.}};
          for (unsigned int c = 0; c < fine_corners.size(); ++c)
            if (wf[c] > 0.)
              {
                const unsigned int a = local_of_id.at(id_of(true, fine_corners[c]));
                v[0] += wf[c] * C.local_element(a);
                v[1] += wf[c] * phase.local_element(a);
              }
          return v;
        };
        for (const auto &cell : tria.active_cell_iterators())
          if (cell->is_locally_owned())
            {
              const long long b = block_of_cell(cell);
              block_nodes(b, new_fine[b], nodes);
              auto &v = outgoing[b];
              v.assign(2 * nodes.size(), 0.);
              if (new_fine[b] == block_fine[b])
                for (unsigned int q = 0; q < nodes.size(); ++q)
                  {
                    const unsigned int a = local_of_id.at(id_of(block_fine[b], nodes[q]));
                    v[q]                 = C.local_element(a);
                    v[nodes.size() + q]  = phase.local_element(a);
                  }
              else if (!new_fine[b])
                {
                  // fine -> coarse: the mean of the r^dim fine nodes of each
                  // coarse cell (block_nodes() lists them consecutively)
                  block_nodes(b, true, old_nodes);
                  const std::size_t r_dim = nodes.empty() ? 0 : old_nodes.size() / nodes.size();
                  for (std::size_t K = 0; K < nodes.size(); ++K)
                    {
                      double c = 0., ph = 0.;
                      for (std::size_t q = K * r_dim; q < (K + 1) * r_dim; ++q)
                        {
                          const unsigned int a = local_of_id.at(id_of(true, old_nodes[q]));
                          c += C.local_element(a);
                          ph += phase.local_element(a);
                        }
                      v[K]                = c / r_dim;
                      v[nodes.size() + K] = ph / r_dim >= 0.5 ? 1. : 0.;
                    }
                }
              else
                {
                  for (unsigned int q = 0; q < nodes.size(); ++q)
                    {
                      corner_interpolation<dim>(point_of(true, nodes[q]), prm.grid.lower, H, nc,
                                                prm.grid.interpolation, corners, w);
                      double ph = 0.;
                      for (unsigned int c = 0; c < corners.size(); ++c)
                        if (w[c] > 0.)
                          {
                            const auto cv = coarse_value(corners[c]);
                            v[q] += w[c] * cv[0];
                            ph += w[c] * cv[1];
                          }
                      v[nodes.size() + q] = ph >= 0.5 ? 1. : 0.;
                    }
                  // mass bookkeeping: shift the r^dim fine values of each
                  // coarse cell so that their mean is the coarse value
                  // (exact for linear C already; the shift removes the
                  // curvature error, so switching conserves mass)
                  std::vector<Index> coarse;
                  block_nodes(b, false, coarse);
                  const std::size_t r_dim = coarse.empty() ? 0 : nodes.size() / coarse.size();
                  for (std::size_t K = 0; K < coarse.size(); ++K)
                    {
                      const double c_K = C.local_element(local_of_id.at(id_of(false, coarse[K])));
                      double       mean = 0.;
                      for (std::size_t s = 0; s < r_dim; ++s)
                        mean += v[K * r_dim + s];
                      mean /= r_dim;
                      for (std::size_t s = 0; s < r_dim; ++s)
                        v[K * r_dim + s] += c_K - mean;
                    }
                }
            }
      }

      // 3. repartition with the new weights; the values travel with their cell
      block_fine = new_fine;
      const unsigned int handle = tria.register_data_attach(
        [&](const typename Triangulation<dim>::cell_iterator &cell,
            const typename Triangulation<dim>::CellStatus) {
          const auto       &v = outgoing.at(block_of_cell(cell));
          std::vector<char> buffer(v.size() * sizeof(double));
          if (!v.empty())
            std::memcpy(buffer.data(), v.data(), buffer.size());
          return buffer;
        },
        /*returns_variable_size_data=*/true);
      tria.repartition();
      incoming.clear();
      tria.notify_ready_to_unpack(
        handle,
        [&](const typename Triangulation<dim>::cell_iterator &cell,
            const typename Triangulation<dim>::CellStatus,
            const boost::iterator_range<std::vector<char>::const_iterator> &data) {
          std::vector<double> v(data.size() / sizeof(double));
          if (!v.empty())
            std::memcpy(v.data(), &*data.begin(), data.size());
          incoming[block_of_cell(cell)] = std::move(v);
        });
      build(&incoming);
      incoming.clear();
      ++n_switch_events;
      n_coarsened_cells += n_to_coarse;
      return n_switched;
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::implicit_step()
    {
      // (M/dt - L) C^{n+1} = C^n/dt, fictitious values eliminated; rows of
      // the owned nodes, the pay-back into ghost rows sent by compress()
      const auto &part = *C.get_partitioner();
      if (!implicit->valid)
        {
          IndexSet writable(part.size());
          writable.add_range(part.local_range().first, part.local_range().second);
          writable.add_indices(part.ghost_indices());
          writable.compress();
          TrilinosWrappers::SparsityPattern sp(part.locally_owned_range(),
                                               part.locally_owned_range(), writable, comm);
          auto g = [&](const unsigned int i) { return part.local_to_global(i); };
          for (unsigned int i = 0; i < n_owned; ++i)
            sp.add(g(i), g(i));
          operator_entries(false, [&](const unsigned int r, const unsigned int c, const double) {
            sp.add(g(r), g(c));
          });
          sp.compress();
          implicit->matrix.reinit(sp);
          for (unsigned int i = 0; i < n_owned; ++i)
            implicit->matrix.add(g(i), g(i), 1. / dt);
          operator_entries(false, [&](const unsigned int r, const unsigned int c, const double v) {
            implicit->matrix.add(g(r), g(c), -v);
          });
          implicit->matrix.compress(VectorOperation::add);
          implicit->solver = std::make_unique<TrilinosWrappers::SolverDirect>(implicit->control);
          implicit->solver->initialize(implicit->matrix);
          implicit->valid = true;
        }
      TrilinosWrappers::MPI::Vector rhs(part.locally_owned_range(), comm), x(rhs);
      for (unsigned int i = 0; i < n_owned; ++i)
        rhs[part.local_to_global(i)] = C.local_element(i) / dt;
      rhs.compress(VectorOperation::insert);
      implicit->solver->solve(x, rhs);
      for (unsigned int i = 0; i < n_owned; ++i)
        C.local_element(i) = x[part.local_to_global(i)];
    }

    template <int dim>
    void
    OctreeMultiGrid<dim>::advance()
    {
      if (prm.transport.scheme == "backward Euler")
        implicit_step();
      else
        {
          apply(rate);
          for (unsigned int i = 0; i < n_owned; ++i)
            C.local_element(i) += dt * rate.local_element(i);
        }
      if (prm.transport.corrosion)
        {
          int changed = 0;
          for (unsigned int i = 0; i < n_owned; ++i)
            if (phase.local_element(i) > 0.5 && C.local_element(i) < prm.transport.saturation)
              {
                phase.local_element(i) = 0.; // (2.79), one way
                changed                = 1;
              }
          // the implicit system depends on the phase (kappa of the bonds)
          if (prm.transport.scheme == "backward Euler" && Utilities::MPI::max(changed, comm))
            implicit->valid = false;
        }
      C.update_ghost_values();
      phase.update_ghost_values();
      refresh_work();
      t += dt;
      ++n_step;
      if (prm.switching && n_step % prm.switching_interval == 0)
        adapt();
    }

    template <int dim>
    double
    OctreeMultiGrid<dim>::integrate(const LinearAlgebra::distributed::Vector<double> *v) const
    {
      // active nodes only: each region's mass is counted in one grid
      double s = 0.;
      for (unsigned int i = 0; i < n_owned; ++i)
        s += (v ? v->local_element(i) : 1.) * std::pow(node_fine[i] ? h : H, dim);
      return Utilities::MPI::sum(s, comm);
    }

    template <int dim>
    double
    OctreeMultiGrid<dim>::mass() const
    {
      return integrate(&C);
    }

    template <int dim>
    double
    OctreeMultiGrid<dim>::solid_volume() const
    {
      return integrate(&phase);
    }

    template <int dim>
    double
    OctreeMultiGrid<dim>::active_volume() const
    {
      return integrate(nullptr);
    }

    template <int dim>
    std::array<unsigned long long, 2>
    OctreeMultiGrid<dim>::n_active() const
    {
      std::array<unsigned long long, 2> n{{0, 0}};
      for (unsigned int i = 0; i < n_owned; ++i)
        ++n[node_fine[i]];
      return {{Utilities::MPI::sum(n[0], comm), Utilities::MPI::sum(n[1], comm)}};
    }

    template <int dim>
    unsigned long long
    OctreeMultiGrid<dim>::n_fictitious() const
    {
      return Utilities::MPI::sum((unsigned long long)(node_position.size() - n_local_active),
                                 comm);
    }

    template <int dim>
    unsigned int
    OctreeMultiGrid<dim>::n_fine_cells() const
    {
      return std::count(block_fine.begin(), block_fine.end(), char(1));
    }

    template <int dim>
    double
    OctreeMultiGrid<dim>::bond_imbalance() const
    {
      const double n    = col.size();
      const double mean = Utilities::MPI::sum(n, comm) / Utilities::MPI::n_mpi_processes(comm);
      return mean > 0. ? Utilities::MPI::max(n, comm) / mean : 1.;
    }

    template <int dim>
    std::vector<std::tuple<std::uint64_t, double, double>>
    OctreeMultiGrid<dim>::gather() const
    {
      // flat (id, C, phase) triples: ids < 2^53 are exact in a double
      std::vector<double> mine;
      for (unsigned int i = 0; i < n_owned; ++i)
        mine.insert(mine.end(),
                    {double(node_id_local[i]), C.local_element(i), phase.local_element(i)});
      const auto all = Utilities::MPI::gather(comm, mine, 0);
      std::vector<std::tuple<std::uint64_t, double, double>> out;
      for (const auto &v : all)
        for (std::size_t q = 0; q < v.size(); q += 3)
          out.emplace_back(std::uint64_t(v[q]), v[q + 1], v[q + 2]);
      std::sort(out.begin(), out.end());
      return out;
    }

    template struct OctreeParameters<2>;
    template struct OctreeParameters<3>;
    template class OctreeMultiGrid<2>;
    template class OctreeMultiGrid<3>;
  } // namespace MultiGrid
} // namespace PeriDEAL
