#ifndef perideal_discretization_discretization_h
#define perideal_discretization_discretization_h

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/partitioner.h>
#include <deal.II/base/point.h>

#include <deal.II/distributed/tria_base.h>

#include <deal.II/lac/la_parallel_vector.h>

#include <deal.II/particles/particle_handler.h>

#include <perideal/discretization/domain.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /** The node field type: owned entries first, then ghosts. */
  using Vector = LinearAlgebra::distributed::Vector<double>;

  /**
   * Parameters of the standard meshfree discretization (dissertation
   * Sect. 3.1): lattice spacing, horizon, partial-volume quadrature and the
   * volume constraint layer.
   */
  struct LatticeParameters
  {
    /** Lattice spacing dx (> 0). */
    double dx = 0.1;
    /** Horizon delta (>= dx). */
    double delta = 0.3;
    /** Use the volume reduction factor beta of (3.2); else beta = 1 inside delta. */
    bool partial_volume = true;
    /** Nodes at lower + i dx (vertex) or at lower + (i + 1/2) dx (cell-centered). */
    bool cell_centered = false;
    /**
     * Thickness of the volume constraint layer outside the body (0: none).
     * Layer nodes carry region 1 and prescribed (Dirichlet) values.
     */
    double layer_thickness = 0.;
    /**
     * Local numbering of the owned nodes: false (default) by cells (the
     * octree's space-filling curve, lattice order within a cell), true by
     * lattice index (x fastest). The same nodes, bonds and partition; only
     * the local (and global) indices differ. In lattice order the owned
     * nodes of a dense rectangular part are consecutive along lattice rows,
     * so that copies between node vectors and a lattice box (the hybrid
     * model's sweeps) are a few long runs instead of one run per cell row.
     */
    bool lattice_order = false;

    /** Declare the "Discretization" entries. */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate them (the caller has entered "Discretization"). */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Bonds of the locally owned nodes in compressed sparse row form. Column
   * indices are int32 local node indices (owned or ghost). Each row refers
   * to a slice of the bond tables (length |xi| and quadrature weight
   * beta * V_j); rows whose family is the full lattice stencil all share the
   * first slice, so interior bonds cost only their 4-byte column index.
   */
  struct Neighborhood
  {
    /** Row i has bonds row_start[i] .. row_start[i+1]. */
    std::vector<std::uint64_t> row_start;
    /** Local index of the neighbour of each bond. */
    std::vector<std::int32_t> col;
    /** Offset of row i's slice in bond_length/bond_weight. */
    std::vector<std::uint64_t> table_start;
    /** |xi| of each table entry. */
    std::vector<double> bond_length;
    /** beta(|xi|) V_j of each table entry: the quadrature weight. */
    std::vector<double> bond_weight;
    /** Number of entries of the shared interior stencil (first slice). */
    unsigned int stencil_size = 0;
    /** Number of rows that use the shared stencil. */
    unsigned int n_regular_rows = 0;

    /** Number of bonds of owned rows. */
    std::uint64_t
    n_bonds() const
    {
      return col.size();
    }
    /** Bytes used by this structure. */
    std::size_t
    memory_consumption() const;
  };

  /**
   * The standard meshfree PD discretization on deal.II infrastructure.
   *
   * The nodes of a regular lattice of spacing dx filling a Domain are
   * particles of a Particles::ParticleHandler attached to a background
   * triangulation whose cells are no smaller than the longest bond (delta +
   * dx/2 with partial volumes): a parallel::distributed::Triangulation
   * (p4est) in 2D/3D, a parallel::shared::Triangulation in 1D. Then owned
   * plus ghost cells hold every neighbour of every owned node. The mesh is
   * repartitioned twice: by particle count, then by the bond count of each
   * cell found by the first neighbour search.
   *
   * After setup the hot data leave the particle handler: node positions,
   * volumes, ids and tags are structure-of-arrays in local numbering
   * (owned nodes in cell order, then ghosts), the bonds are a CSR
   * Neighborhood, and fields are LinearAlgebra::distributed::Vector objects
   * on partitioner(), refreshed by one update_ghost_values() per step.
   *
   * Node ids are linear lattice indices and therefore do not depend on the
   * number of MPI ranks; they are what output and checkpoints are keyed by.
   */
  template <int dim>
  class Discretization
  {
  public:
    /** Node region tags. */
    enum Region : unsigned char
    {
      interior = 0,   ///< a node of the body; its value evolves
      constrained = 1 ///< a node of the volume constraint layer
    };

    explicit Discretization(const MPI_Comm comm);
    ~Discretization();

    /**
     * Generate the lattice, distribute it, find ghosts and build the
     * neighbourhoods. Throws ParameterError for bad input (delta < dx, an
     * empty body, too many nodes for 32-bit ids, ...).
     */
    void
    setup(const Domain<dim> &domain, const LatticeParameters &parameters);

    /** @name Sizes */
    /** @{ */
    unsigned int
    n_owned() const
    {
      return n_owned_nodes;
    }
    unsigned int
    n_ghost() const
    {
      return n_ghost_nodes;
    }
    types::global_dof_index
    n_global() const
    {
      return n_global_nodes;
    }
    /** Global number of bonds (sum over owned rows of all ranks). */
    std::uint64_t
    n_global_bonds() const;
    /** @} */

    /** @name Node data in local numbering (owned, then ghosts) */
    /** @{ */
    std::vector<Point<dim>>          position;
    std::vector<double>              volume;
    std::vector<types::particle_index> id;
    std::vector<unsigned char>       region;
    /** Lattice coordinates of each node. */
    std::vector<std::array<int, dim>> lattice_index;
    /** @} */

    /** The bonds of the owned nodes. */
    Neighborhood neighborhood;

    /** Parallel layout of node fields. */
    const std::shared_ptr<const Utilities::MPI::Partitioner> &
    partitioner() const
    {
      return node_partitioner;
    }

    /** A zero vector on the node layout. */
    void
    initialize_vector(Vector &v) const
    {
      v.reinit(node_partitioner);
    }

    /** The parameters used for setup. */
    const LatticeParameters &
    parameters() const
    {
      return lattice;
    }

    /** The background mesh. */
    const Triangulation<dim> &
    get_triangulation() const
    {
      return *triangulation;
    }

    /** The particle handler holding the nodes (setup only; not in hot loops). */
    const Particles::ParticleHandler<dim> &
    get_particle_handler() const
    {
      return *particle_handler;
    }

    /** Lattice sizes per direction (ids are i0 + n0 (i1 + n1 i2)). */
    const std::array<unsigned int, dim> &
    lattice_size() const
    {
      return n_lattice;
    }

    /** Position of lattice point @p index. */
    Point<dim>
    lattice_point(const std::array<int, dim> &index) const;

    /** The communicator. */
    MPI_Comm
    get_mpi_communicator() const
    {
      return mpi_communicator;
    }

    /**
     * Volume reduction factor beta of (3.2) for bond length @p r (or 1/0
     * without partial volumes).
     */
    static double
    volume_factor(const double r, const double delta, const double dx, const bool partial_volume);

    /** Wall time of the setup phases [lattice+particles, ghosts, search]. */
    std::array<double, 3> setup_seconds{{0., 0., 0.}};

  private:
    void
    create_background_mesh(const BoundingBox<dim> &box, const double min_cell_size);
    void
    insert_nodes(const Domain<dim> &domain);
    void
    repartition(const std::vector<unsigned int> &cell_weights);
    void
    number_nodes_and_exchange_ghosts();
    void
    build_neighborhoods();

    MPI_Comm                                          mpi_communicator;
    LatticeParameters                                 lattice;
    std::unique_ptr<parallel::TriangulationBase<dim>> triangulation;
    std::unique_ptr<Particles::ParticleHandler<dim>>  particle_handler;
    std::shared_ptr<const Utilities::MPI::Partitioner> node_partitioner;

    Point<dim>                    lattice_origin;
    std::array<unsigned int, dim> n_lattice;
    Point<dim>                    mesh_lower;
    std::array<double, dim>       cell_width;

    unsigned int            n_owned_nodes = 0, n_ghost_nodes = 0;
    types::global_dof_index n_global_nodes = 0;

    /** Local node lists per active cell (by active cell index). */
    std::vector<std::vector<unsigned int>> nodes_in_cell;
    /** Active cell index of each owned node. */
    std::vector<unsigned int> cell_of_owned_node;
  };
} // namespace PeriDEAL

#endif
