#include <deal.II/base/timer.h>

#include <deal.II/distributed/shared_tria.h>
#include <deal.II/distributed/tria.h>

#include <deal.II/fe/mapping_q1.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace PeriDEAL
{
  void
  LatticeParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Grid spacing", "0.1", Patterns::Double(),
                      "Lattice spacing dx of the standard meshfree scheme (> 0).");
    prm.declare_entry("Horizon", "0", Patterns::Double(),
                      "Horizon delta (>= Grid spacing). If 0, 'Horizon factor' * dx "
                      "is used.");
    prm.declare_entry("Horizon factor", "3", Patterns::Double(),
                      "m = delta / dx, used when 'Horizon' is 0 (>= 1).");
    prm.declare_entry("Partial volume", "true", Patterns::Bool(),
                      "Use the volume reduction factor beta of (3.2) for bonds "
                      "cut by the horizon; otherwise beta = 1 for |xi| <= delta.");
    prm.declare_entry("Lattice", "vertex", Patterns::Selection("vertex|cell centered"),
                      "vertex: nodes at lower corner + i dx (nodes on the boundary); "
                      "cell centered: at lower corner + (i + 1/2) dx.");
    prm.declare_entry("Volume constraint layer", "0", Patterns::Double(),
                      "Thickness of the layer of constrained (Dirichlet) nodes added "
                      "outside the body; 0: none (homogeneous nonlocal Neumann by "
                      "omission of missing neighbours); a negative value means the "
                      "reach of the bonds: delta + dx/2 with partial volumes, "
                      "delta without (a thinner layer leaves out bonds at "
                      "convex corners).");
    prm.declare_entry("Node order", "cells", Patterns::Selection("cells|lattice"),
                      "Local numbering of the owned nodes: cells (the octree's "
                      "space-filling curve, lattice order within a cell) or lattice "
                      "(by lattice index, x fastest). The same nodes, bonds and "
                      "results; lattice order makes the hybrid model's copies into "
                      "its lattice box long contiguous runs.");
  }

  void
  LatticeParameters::parse_parameters(ParameterHandler &prm)
  {
    dx = prm.get_double("Grid spacing");
    check_parameter(dx > 0., "Discretization/Grid spacing", dx, "a positive number");
    delta = prm.get_double("Horizon");
    if (delta == 0.)
      {
        const double m = prm.get_double("Horizon factor");
        check_parameter(m >= 1., "Discretization/Horizon factor", m,
                        "a number >= 1 (the horizon must not be smaller than the grid spacing)");
        delta = m * dx;
      }
    check_parameter(delta > 0., "Discretization/Horizon", delta, "a positive number");
    check_parameter(delta >= dx * (1. - 1e-12), "Discretization/Horizon", delta,
                    "a value >= Grid spacing (dx = " + std::to_string(dx) + ")");
    partial_volume = prm.get_bool("Partial volume");
    cell_centered  = (prm.get("Lattice") == "cell centered");
    layer_thickness = prm.get_double("Volume constraint layer");
    // The constraint layer must hold every node a body node is bonded to:
    // with partial volumes (3.2) that reaches delta + dx/2, which a layer
    // of delta misses at convex corners (e.g. the (3, 1) dx bond at m = 3).
    if (layer_thickness < 0.)
      layer_thickness = partial_volume ? delta + 0.5 * dx : delta;
    lattice_order = (prm.get("Node order") == "lattice");
  }

  std::size_t
  Neighborhood::memory_consumption() const
  {
    return row_start.capacity() * sizeof(std::uint64_t) +
           col.capacity() * sizeof(std::int32_t) +
           table_start.capacity() * sizeof(std::uint64_t) +
           (bond_length.capacity() + bond_weight.capacity()) * sizeof(double);
  }

  template <int dim>
  Discretization<dim>::Discretization(const MPI_Comm comm)
    : mpi_communicator(comm)
  {}

  template <int dim>
  Discretization<dim>::~Discretization()
  {
    // The particle handler refers to the triangulation: release it first.
    particle_handler.reset();
    triangulation.reset();
  }

  template <int dim>
  double
  Discretization<dim>::volume_factor(const double r,
                                     const double delta,
                                     const double dx,
                                     const bool   partial_volume)
  {
    if (!partial_volume)
      return r <= delta * (1. + 1e-12) ? 1. : 0.;
    if (r <= delta - 0.5 * dx)
      return 1.;
    if (r >= delta + 0.5 * dx)
      return 0.;
    return (delta + 0.5 * dx - r) / dx;
  }

  template <int dim>
  Point<dim>
  Discretization<dim>::lattice_point(const std::array<int, dim> &index) const
  {
    Point<dim> p;
    for (unsigned int d = 0; d < dim; ++d)
      p[d] = lattice_origin[d] + index[d] * lattice.dx;
    return p;
  }

  template <int dim>
  std::uint64_t
  Discretization<dim>::n_global_bonds() const
  {
    return Utilities::MPI::sum<std::uint64_t>(neighborhood.n_bonds(), mpi_communicator);
  }

  template <int dim>
  void
  Discretization<dim>::setup(const Domain<dim> &domain, const LatticeParameters &p)
  {
    lattice = p;
    check_parameter(p.dx > 0., "Discretization/Grid spacing", p.dx, "a positive number");
    check_parameter(p.delta >= p.dx * (1. - 1e-12), "Discretization/Horizon", p.delta,
                    "a value >= Grid spacing (dx = " + std::to_string(p.dx) + ")");
    check_parameter(p.layer_thickness >= 0., "Discretization/Volume constraint layer",
                    p.layer_thickness, "a non-negative thickness");

    Timer timer;
    // Lattice extents: the body's box, plus the layer rounded up to whole
    // lattice steps.
    const BoundingBox<dim> box = domain.bounding_box();
    const double           dx  = p.dx;
    const int    k_layer = int(std::ceil(p.layer_thickness / dx - 1e-9));
    double       n_total = 1.;
    for (unsigned int d = 0; d < dim; ++d)
      {
        const double L = box.get_boundary_points().second[d] - box.get_boundary_points().first[d];
        long long    n = p.cell_centered ? (long long)std::floor(L / dx + 1e-9) :
                                           (long long)std::floor(L / dx + 1e-9) + 1;
        n                 = std::max<long long>(n, 1) + 2 * k_layer;
        lattice_origin[d] = box.get_boundary_points().first[d] +
                            (p.cell_centered ? 0.5 * dx : 0.) - k_layer * dx;
        n_total *= double(n);
        check_parameter(n < (1LL << 31), "Discretization/Grid spacing", dx,
                        "a spacing giving fewer than 2^31 lattice points per direction");
        n_lattice[d] = (unsigned int)n;
      }
    check_parameter(n_total < 4.0e9, "Discretization/Grid spacing", dx,
                    "a spacing giving fewer than 4e9 lattice points in the bounding box "
                    "(node ids are 32-bit in this deal.II build)");

    const double longest = p.partial_volume ? p.delta + 0.5 * dx : p.delta;
    Point<dim>   lo, hi;
    for (unsigned int d = 0; d < dim; ++d)
      {
        lo[d] = lattice_origin[d] - 0.5 * dx;
        hi[d] = lattice_origin[d] + (n_lattice[d] - 1) * dx + 0.5 * dx;
      }
    create_background_mesh(BoundingBox<dim>(std::make_pair(lo, hi)), longest);
    insert_nodes(domain);
    setup_seconds[0] = timer.wall_time();

    timer.restart();
    number_nodes_and_exchange_ghosts();
    setup_seconds[1] = timer.wall_time();

    timer.restart();
    build_neighborhoods();
    // Second balance by the actual bond count per cell (cells cut by the
    // boundary or holding constraint-layer nodes have fewer bonds than the
    // particle count suggests); then number, exchange and search again.
    if (dim > 1 && Utilities::MPI::n_mpi_processes(mpi_communicator) > 1)
      {
        std::vector<unsigned int> bonds(triangulation->n_active_cells(), 0);
        unsigned int              row = 0;
        for (const auto &cell : triangulation->active_cell_iterators())
          if (cell->is_locally_owned())
            for (std::size_t k = 0; k < nodes_in_cell[cell->active_cell_index()].size(); ++k, ++row)
              bonds[cell->active_cell_index()] +=
                neighborhood.row_start[row + 1] - neighborhood.row_start[row];
        repartition(bonds);
        number_nodes_and_exchange_ghosts();
        build_neighborhoods();
      }
    setup_seconds[2] = timer.wall_time();
  }

  template <int dim>
  void
  Discretization<dim>::create_background_mesh(const BoundingBox<dim> &box,
                                              const double            min_cell_size)
  {
    const Point<dim> lo = box.get_boundary_points().first;
    const Point<dim> hi = box.get_boundary_points().second;
    mesh_lower          = lo;

    std::array<unsigned int, dim> n_cells;
    unsigned int                  n_min = std::numeric_limits<unsigned int>::max();
    for (unsigned int d = 0; d < dim; ++d)
      {
        // Cells no smaller than the longest bond: one ghost layer then holds
        // every neighbour.
        const double L = hi[d] - lo[d];
        n_cells[d]     = std::max(1u, (unsigned int)std::floor(L / (min_cell_size * (1. + 1e-10))));
        n_min          = std::min(n_min, n_cells[d]);
      }

    // p4est prefers few trees and refinement: keep at least 4 trees per
    // direction so that the cells are at most 25 % larger than needed.
    unsigned int refinements = 0;
    if (dim > 1)
      while ((n_min >> (refinements + 1)) >= 4)
        ++refinements;
    std::vector<unsigned int> repetitions(dim);
    for (unsigned int d = 0; d < dim; ++d)
      {
        repetitions[d] = std::max(1u, n_cells[d] >> refinements);
        cell_width[d]  = (hi[d] - lo[d]) / (double(repetitions[d]) * (1u << refinements));
      }

    if constexpr (dim == 1)
      triangulation = std::make_unique<parallel::shared::Triangulation<dim>>(
        mpi_communicator,
        Triangulation<dim>::none,
        false,
        parallel::shared::Triangulation<dim>::partition_zorder);
    else
      triangulation = std::make_unique<parallel::distributed::Triangulation<dim>>(
        mpi_communicator,
        Triangulation<dim>::none,
        parallel::distributed::Triangulation<dim>::no_automatic_repartitioning);

    GridGenerator::subdivided_hyper_rectangle(*triangulation, repetitions, lo, hi);
    if (refinements > 0)
      triangulation->refine_global(refinements);
  }

  template <int dim>
  void
  Discretization<dim>::insert_nodes(const Domain<dim> &domain)
  {
    static const MappingQ1<dim> mapping;
    particle_handler =
      std::make_unique<Particles::ParticleHandler<dim>>(*triangulation, mapping, 2);

    const double dx = lattice.dx;
    const double t  = lattice.layer_thickness;

    // Offsets for the discrete dilation test of layer nodes (domains without
    // a signed distance), shortest first so inside hits exit early.
    std::vector<std::pair<double, Tensor<1, dim>>> dilation;
    if (t > 0. && !domain.has_signed_distance())
      {
        const int K = int(std::ceil(t / dx));
        std::array<int, dim> o;
        std::function<void(unsigned int)> loop = [&](unsigned int d) {
          if (d == dim)
            {
              Tensor<1, dim> v;
              for (unsigned int e = 0; e < dim; ++e)
                v[e] = o[e] * dx;
              if (v.norm() > 0 && v.norm() <= t * (1. + 1e-12))
                dilation.emplace_back(v.norm(), v);
              return;
            }
          for (o[d] = -K; o[d] <= K; ++o[d])
            loop(d + 1);
        };
        loop(0);
        std::sort(dilation.begin(), dilation.end(),
                  [](const auto &a, const auto &b) { return a.first < b.first; });
      }

    auto classify = [&](const Point<dim> &x) -> int {
      if (domain.inside(x))
        return interior;
      if (t <= 0.)
        return -1;
      if (domain.has_signed_distance())
        return domain.signed_distance(x) <= t * (1. + 1e-12) ? constrained : -1;
      for (const auto &o : dilation)
        if (domain.inside(x + o.second))
          return constrained;
      return -1;
    };

    std::vector<double> properties(2, 0.);
    for (const auto &cell : triangulation->active_cell_iterators())
      {
        if (!cell->is_locally_owned())
          continue;
        const Point<dim> c_lo = cell->vertex(0);
        const Point<dim> c_hi = cell->vertex(GeometryInfo<dim>::vertices_per_cell - 1);
        std::array<int, dim> i_lo, i_hi, k_cell;
        for (unsigned int d = 0; d < dim; ++d)
          {
            k_cell[d] = int(std::lround((c_lo[d] - mesh_lower[d]) / cell_width[d]));
            i_lo[d] = std::max(0, int(std::floor((c_lo[d] - lattice_origin[d]) / dx)) - 1);
            i_hi[d] = std::min(int(n_lattice[d]) - 1,
                               int(std::ceil((c_hi[d] - lattice_origin[d]) / dx)) + 1);
          }
        // Each lattice point belongs to exactly one cell, decided by the
        // same integer formula everywhere.
        auto owner_cell = [&](const Point<dim> &x, const unsigned int d) {
          return int(std::floor((x[d] - mesh_lower[d]) / cell_width[d]));
        };
        std::array<int, dim> i = i_lo;
        while (true)
          {
            const Point<dim> x    = lattice_point(i);
            bool             mine = true;
            for (unsigned int d = 0; d < dim; ++d)
              mine = mine && owner_cell(x, d) == k_cell[d];
            if (mine)
              {
                const int r = classify(x);
                if (r >= 0)
                  {
                    types::particle_index pid = 0;
                    for (int d = dim - 1; d >= 0; --d)
                      pid = pid * n_lattice[d] + i[d];
                    Point<dim> ref;
                    for (unsigned int d = 0; d < dim; ++d)
                      ref[d] = (x[d] - c_lo[d]) / (c_hi[d] - c_lo[d]);
                    properties[1] = r;
                    particle_handler->insert_particle(x, ref, pid, cell,
                                                      ArrayView<const double>(properties));
                  }
              }
            // next multi-index
            unsigned int d = 0;
            for (; d < dim; ++d)
              {
                if (i[d] < i_hi[d])
                  {
                    ++i[d];
                    break;
                  }
                i[d] = i_lo[d];
              }
            if (d == dim)
              break;
          }
      }
    particle_handler->update_cached_numbers();

    check_parameter(particle_handler->n_global_particles() > 0, "Geometry/Domain",
                    "(the body)", "a body that contains at least one lattice node; "
                                  "check the geometry and the grid spacing");

    // First balance: every node of a full family carries one stencil of
    // bonds, so the particle count is a good first guess of the bond count.
    std::vector<unsigned int> weights(triangulation->n_active_cells(), 0);
    for (const auto &cell : triangulation->active_cell_iterators())
      if (cell->is_locally_owned())
        weights[cell->active_cell_index()] = particle_handler->n_particles_in_cell(cell);
    repartition(weights);
  }

  template <int dim>
  void
  Discretization<dim>::repartition(const std::vector<unsigned int> &cell_weights)
  {
    if constexpr (dim > 1)
      if (Utilities::MPI::n_mpi_processes(mpi_communicator) > 1)
        {
          auto &tria = dynamic_cast<parallel::distributed::Triangulation<dim> &>(*triangulation);
          // Weights are read during repartition() from the cells as they are
          // before it; p4est wants unsigned int, so scale large counts down.
          const unsigned int max_w =
            Utilities::MPI::max(cell_weights.empty() ? 0u :
                                                       *std::max_element(cell_weights.begin(),
                                                                         cell_weights.end()),
                                mpi_communicator);
          const unsigned int divisor = 1 + max_w / 100000;
          auto               connection = tria.signals.weight.connect(
            [&](const typename Triangulation<dim>::cell_iterator &cell,
                const typename Triangulation<dim>::CellStatus) -> unsigned int {
              return 1 + cell_weights[cell->active_cell_index()] / divisor;
            });
          particle_handler->prepare_for_coarsening_and_refinement();
          tria.repartition();
          particle_handler->unpack_after_coarsening_and_refinement();
          connection.disconnect();
        }
  }

  template <int dim>
  void
  Discretization<dim>::number_nodes_and_exchange_ghosts()
  {
    nodes_in_cell.assign(triangulation->n_active_cells(), {});
    position.clear();
    volume.clear();
    id.clear();
    region.clear();
    lattice_index.clear();

    auto lattice_of = [&](types::particle_index pid) {
      std::array<int, dim> i;
      for (unsigned int d = 0; d < dim; ++d)
        {
          i[d] = int(pid % n_lattice[d]);
          pid /= n_lattice[d];
        }
      return i;
    };

    // Owned nodes in cell order (the octree's space-filling curve), and in
    // lattice order within a cell: neighbours end up close in memory. Or, with
    // LatticeParameters::lattice_order, all owned nodes by lattice index.
    n_owned_nodes = particle_handler->n_locally_owned_particles();
    const types::global_dof_index offset = [&] {
      types::global_dof_index mine = n_owned_nodes, before = 0;
      MPI_Exscan(&mine, &before, 1, Utilities::MPI::mpi_type_id_for_type<decltype(mine)>,
                 MPI_SUM, mpi_communicator);
      return Utilities::MPI::this_mpi_process(mpi_communicator) == 0 ? 0 : before;
    }();
    n_global_nodes = Utilities::MPI::sum<types::global_dof_index>(n_owned_nodes, mpi_communicator);

    using ParticleIterator = typename Particles::ParticleHandler<dim>::particle_iterator;
    std::vector<std::pair<ParticleIterator, unsigned int>> owned_nodes;
    owned_nodes.reserve(n_owned_nodes);
    for (const auto &cell : triangulation->active_cell_iterators())
      {
        if (!cell->is_locally_owned())
          continue;
        const std::size_t first = owned_nodes.size();
        auto              range = particle_handler->particles_in_cell(cell);
        for (auto p = range.begin(); p != range.end(); ++p)
          owned_nodes.emplace_back(p, cell->active_cell_index());
        std::sort(owned_nodes.begin() + first, owned_nodes.end(),
                  [](const auto &a, const auto &b) { return a.first->get_id() < b.first->get_id(); });
      }
    if (lattice.lattice_order)
      std::sort(owned_nodes.begin(), owned_nodes.end(),
                [](const auto &a, const auto &b) { return a.first->get_id() < b.first->get_id(); });

    const double cell_volume = std::pow(lattice.dx, dim);
    cell_of_owned_node.clear();
    cell_of_owned_node.reserve(n_owned_nodes);
    for (auto &[p, cell_index] : owned_nodes)
      {
        const unsigned int local = position.size();
        nodes_in_cell[cell_index].push_back(local);
        cell_of_owned_node.push_back(cell_index);
        position.push_back(p->get_location());
        volume.push_back(cell_volume);
        id.push_back(p->get_id());
        region.push_back((unsigned char)(p->get_properties()[1]));
        lattice_index.push_back(lattice_of(p->get_id()));
        p->get_properties()[0] = double(offset + local);
      }
    AssertThrow(position.size() == n_owned_nodes, ExcInternalError());

    particle_handler->exchange_ghost_particles(false);

    struct Ghost
    {
      types::global_dof_index index;
      Point<dim>              x;
      types::particle_index   pid;
      unsigned char           region;
      unsigned int            cell;
    };
    std::vector<Ghost> ghosts;
    for (auto p = particle_handler->begin_ghost(); p != particle_handler->end_ghost(); ++p)
      ghosts.push_back({types::global_dof_index(p->get_properties()[0]),
                        p->get_location(),
                        p->get_id(),
                        (unsigned char)(p->get_properties()[1]),
                        p->get_surrounding_cell()->active_cell_index()});
    std::sort(ghosts.begin(), ghosts.end(),
              [](const Ghost &a, const Ghost &b) { return a.index < b.index; });
    n_ghost_nodes = ghosts.size();

    IndexSet owned(n_global_nodes), ghost_set(n_global_nodes);
    owned.add_range(offset, offset + n_owned_nodes);
    for (const auto &g : ghosts)
      ghost_set.add_index(g.index);
    ghost_set.compress();
    node_partitioner =
      std::make_shared<Utilities::MPI::Partitioner>(owned, ghost_set, mpi_communicator);

    for (const auto &g : ghosts)
      {
        const unsigned int local = position.size();
        nodes_in_cell[g.cell].push_back(local);
        position.push_back(g.x);
        volume.push_back(cell_volume);
        id.push_back(g.pid);
        region.push_back(g.region);
        lattice_index.push_back(lattice_of(g.pid));
      }
  }

  template <int dim>
  void
  Discretization<dim>::build_neighborhoods()
  {
    const double dx      = lattice.dx;
    const double delta   = lattice.delta;
    const double longest = lattice.partial_volume ? delta + 0.5 * dx : delta;
    const int    M       = int(std::ceil(longest / dx));
    const int    W       = 2 * M + 1;

    // The interior stencil: every lattice offset with beta > 0, in
    // lexicographic order; a dense table maps offsets to stencil slots.
    unsigned int n_box = 1;
    for (unsigned int d = 0; d < dim; ++d)
      n_box *= W;
    std::vector<int> slot_of_offset(n_box, -1);
    neighborhood     = Neighborhood();
    auto &nb         = neighborhood;
    const double V   = std::pow(dx, dim);
    for (unsigned int b = 0; b < n_box; ++b)
      {
        unsigned int rest = b;
        double       r2   = 0.;
        for (unsigned int d = 0; d < dim; ++d)
          {
            const int o = int(rest % W) - M;
            rest /= W;
            r2 += double(o) * o;
          }
        const double r = std::sqrt(r2) * dx;
        if (r2 == 0.)
          continue;
        const double beta = volume_factor(r, delta, dx, lattice.partial_volume);
        if (beta <= 0.)
          continue;
        slot_of_offset[b] = nb.bond_length.size();
        nb.bond_length.push_back(r);
        nb.bond_weight.push_back(beta * V);
      }
    nb.stencil_size = nb.bond_length.size();

    const auto vertex_to_cells = GridTools::vertex_to_cell_map(*triangulation);

    nb.row_start.assign(1, 0);
    nb.row_start.reserve(n_owned_nodes + 1);
    nb.table_start.reserve(n_owned_nodes);
    nb.col.reserve(std::size_t(n_owned_nodes) * nb.stencil_size);

    // The cells around each owned cell (its own included), sorted.
    std::vector<std::vector<unsigned int>> neighbor_cells_of(triangulation->n_active_cells());
    for (const auto &cell : triangulation->active_cell_iterators())
      {
        if (!cell->is_locally_owned() || nodes_in_cell[cell->active_cell_index()].empty())
          continue;
        auto &neighbor_cells = neighbor_cells_of[cell->active_cell_index()];
        for (const unsigned int v : cell->vertex_indices())
          for (const auto &nc : vertex_to_cells[cell->vertex_index(v)])
            neighbor_cells.push_back(nc->active_cell_index());
        std::sort(neighbor_cells.begin(), neighbor_cells.end());
        neighbor_cells.erase(std::unique(neighbor_cells.begin(), neighbor_cells.end()),
                             neighbor_cells.end());
      }

    // Rows in local order (by cells or by lattice index); a row's bonds are
    // in stencil order either way.
    std::vector<int> slot(nb.stencil_size, -1);
    for (unsigned int i = 0; i < n_owned_nodes; ++i)
      {
        const auto  &neighbor_cells = neighbor_cells_of[cell_of_owned_node[i]];
        const auto  &li             = lattice_index[i];
        unsigned int n_found        = 0;
        for (const unsigned int nc : neighbor_cells)
          for (const unsigned int j : nodes_in_cell[nc])
            {
              const auto  &lj = lattice_index[j];
              unsigned int b = 0, stride = 1;
              bool         in_box = true;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  const int o = lj[d] - li[d];
                  in_box      = in_box && (o >= -M && o <= M);
                  b += (o + M) * stride;
                  stride *= W;
                }
              if (!in_box)
                continue;
              const int s = slot_of_offset[b];
              if (s >= 0)
                {
                  slot[s] = j;
                  ++n_found;
                }
            }
        if (n_found == nb.stencil_size)
          {
            nb.table_start.push_back(0);
            ++nb.n_regular_rows;
          }
        else
          nb.table_start.push_back(nb.bond_length.size());
        for (unsigned int s = 0; s < nb.stencil_size; ++s)
          if (slot[s] >= 0)
            {
              nb.col.push_back(slot[s]);
              if (n_found != nb.stencil_size)
                {
                  nb.bond_length.push_back(nb.bond_length[s]);
                  nb.bond_weight.push_back(nb.bond_weight[s]);
                }
              slot[s] = -1;
            }
        nb.row_start.push_back(nb.col.size());
      }
    nb.col.shrink_to_fit();
    nb.bond_length.shrink_to_fit();
    nb.bond_weight.shrink_to_fit();
  }

  template class Discretization<1>;
  template class Discretization<2>;
  template class Discretization<3>;
} // namespace PeriDEAL
