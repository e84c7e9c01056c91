#ifndef perideal_multigrid_octree_multigrid_h
#define perideal_multigrid_octree_multigrid_h

#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>

#include <deal.II/distributed/tria.h>

#include <deal.II/lac/la_parallel_vector.h>

#include <perideal/base/kernel.h>
#include <perideal/multigrid/multigrid_discretization.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

namespace PeriDEAL
{
  namespace MultiGrid
  {
    /**
     * Parameters of the distributed multi-grid: the node lattices, horizon,
     * kernel, interpolation and the initial fine region of the serial
     * multi-grid (MultiGrid::Parameters; here the fine region is a union of
     * octree cells), its transport model (MultiGrid::TransportParameters,
     * forward or backward Euler, the standard quadrature only), and the
     * switching of cells from coarse to fine and back.
     */
    template <int dim>
    struct OctreeParameters
    {
      Parameters<dim>     grid;
      TransportParameters transport;
      /**
       * Switch coarse cells to fine during the run: a coarse cell is
       * critical when the range max C - min C over its active nodes exceeds
       * @p indicator_threshold (a front or a steep gradient has arrived);
       * critical cells and their neighbours (a buffer of one cell, so that
       * the front moves on into an already fine region) become fine.
       */
      bool         switching           = false;
      double       indicator_threshold = 0.05;
      unsigned int switching_interval  = 10; ///< steps between indicator evaluations
      /**
       * With switching, also return fine cells to coarse once the field
       * there is smooth again (the front has passed): a fine cell becomes
       * coarse when it and all its neighbours have max C - min C <
       * @p coarsening_threshold and hold one phase only. The threshold must
       * be below indicator_threshold (hysteresis: a cell that just
       * coarsened is not critical at the next evaluation), and the
       * neighbour rule keeps the one-cell buffer around critical cells.
       */
      bool   coarsening           = false;
      double coarsening_threshold = 0.01;

      /** Throws ParameterError for inadmissible values. */
      void
      check() const;
    };

    /**
     * The multi-grid of dissertation Sect. 3.4 on a p4est octree, with MPI.
     *
     * The body is the box of MultiGrid::Parameters (coarse vertex lattice
     * lower + K dx+, each coarse node the centre of a coarse cell of side
     * dx+ that may be refined into r^dim fine cells with cell-centred fine
     * nodes, exactly as the serial MultiGrid::Discretization). It is covered
     * by a parallel::distributed::Triangulation of square cells of k x dx+,
     * k the smallest integer with k dx+ >= delta + 3/2 dx+ + dx-/2; cell
     * boundaries lie on coarse-cell boundaries, so every lattice node
     * belongs to exactly one octree cell by integer division. Each octree
     * cell carries a fine/coarse flag: its nodes are active in that grid
     * only. Fictitious nodes (the other grid's lattice points within the
     * bond reach of an active node, and the coarse corners of fine
     * fictitious nodes) are built by each rank for its owned rows and
     * interpolated locally by (3.85)-(3.88): with the cell side above, all
     * their interpolation sources are in owned or ghost cells, so one ghost
     * exchange of the active values per step suffices.
     *
     * Active nodes of owned cells are the owned entries of a
     * LinearAlgebra::distributed::Vector (cell order), those of ghost cells
     * its ghosts; node ids (coarse: lattice index; fine: n_coarse + lattice
     * index) do not depend on the partition. Operators, interpolation
     * weights and the summation order within each row are those of the
     * serial TransportSolver, so the interpolation coupling gives the same
     * numbers on any number of ranks (bit for bit) and as the serial code
     * (to round-off); the conservative coupling adds the pay-back of remote
     * rows through compress(add) (round-off differences between partitions).
     *
     * Switching (adapt()): critical coarse cells become fine; their fine
     * nodes take the values of the fine fictitious interpolation from the
     * coarse grid, shifted per coarse cell so that the mean of its r^dim
     * fine values is the coarse value (the switch conserves mass to
     * round-off; linear fields are unchanged by the shift); phase:
     * interpolated, solid iff >= 1/2. With coarsening, a smooth fine cell
     * becomes coarse and each coarse node takes the mean of the r^dim fine
     * values of its coarse cell (V+ = r^dim V-: the mass of the cell is
     * kept to round-off), phase: solid iff the mean phase >= 1/2. The mesh is then
     * repartitioned with weight (1 + bonds of the cell's active nodes), the
     * node values travel with their cell (register_data_attach), and the
     * numbering, ghosts, bonds and interpolation are rebuilt.
     *
     * Backward Euler (TransportParameters::scheme): (M/dt - L) C^{n+1} = M
     * C^n / dt with L the operator of the active rows in which every
     * fictitious value is replaced by its interpolation from active nodes,
     * i.e. the system (3.89)-(3.90) with the fictitious unknowns eliminated
     * (the same solution); phase of t^n (frozen, as the serial solver). It
     * is assembled into a distributed Trilinos matrix (pay-back entries of
     * the conservative coupling into ghost rows) and factorized with Amesos
     * KLU, once per grid and phase pattern.
     */
    template <int dim>
    class OctreeMultiGrid
    {
    public:
      using Index = std::array<long long, dim>;

      OctreeMultiGrid(const MPI_Comm comm, const OctreeParameters<dim> &parameters);
      ~OctreeMultiGrid();

      /** C0(x) on the active nodes; phase solid iff C0 >= C_sat (corrosion). */
      template <typename F>
      void
      set_initial(const F &c0)
      {
        for (unsigned int i = 0; i < n_owned; ++i)
          C.local_element(i) = c0(node_position[i]);
        initialize_phase();
      }

      /** One forward or backward Euler step; with switching, adapt() every interval. */
      void
      advance();

      /**
       * Evaluate the indicator, switch the critical coarse cells (and their
       * neighbours) to fine, repartition and rebuild. Returns the number of
       * cells switched (all ranks).
       */
      unsigned int
      adapt();

      /**
       * Set the fine/coarse flag of every cell to @p fine(centre of the
       * cell) and transfer the values (both directions, as adapt()).
       * Returns the number of cells that changed. Collective.
       */
      unsigned int
      set_fine_cells(const std::function<bool(const Point<dim> &)> &fine);

      /** @name Global quantities (collective) */
      /** @{ */
      double
      mass() const;
      double
      solid_volume() const;
      /** Sum of the active node volumes: the body's volume, counted once. */
      double
      active_volume() const;
      std::array<unsigned long long, 2>
      n_active() const; ///< {coarse, fine}
      unsigned long long
      n_fictitious() const; ///< summed over ranks (a node may be built by two)
      unsigned int
      n_fine_cells() const;
      /** max over ranks / mean of the bonds of owned rows. */
      double
      bond_imbalance() const;
      unsigned int
      n_switches() const
      {
        return n_switch_events;
      }
      /** Cells returned from fine to coarse so far. */
      unsigned int
      n_coarsened() const
      {
        return n_coarsened_cells;
      }
      /** @} */

      double
      time() const
      {
        return t;
      }
      unsigned int
      step() const
      {
        return n_step;
      }
      double
      time_step() const
      {
        return dt;
      }
      /** Gershgorin bound (see the .cc) with the largest kappa on every bond. */
      double
      critical_time_step() const
      {
        return dt_critical;
      }

      /**
       * (id, C, phase) of every active node, sorted by id, on rank 0 (empty
       * elsewhere). Collective.
       */
      std::vector<std::tuple<std::uint64_t, double, double>>
      gather() const;
      /** Id of the node of grid @p fine at @p x (a lattice point of that grid). */
      std::uint64_t
      node_id(const Point<dim> &x, const bool fine) const;

    private:
      /** sum over owned active nodes of v_i V_i (V_i if @p v is null). */
      double
      integrate(const LinearAlgebra::distributed::Vector<double> *v) const;
      void
      build(const std::unordered_map<long long, std::vector<double>> *values);
      void
      initialize_phase();
      void
      update_fictitious(std::vector<double> &v) const;
      void
      refresh_work();
      void
      apply(LinearAlgebra::distributed::Vector<double> &rate) const;
      /**
       * The entries (row, column, value) of L on the local active nodes,
       * fictitious columns expanded to their active sources, duplicates not
       * merged; rows are owned or (pay-back) ghost nodes. kappa: the bond's
       * or, with @p kappa_max, the largest one.
       */
      template <typename F>
      void
      operator_entries(const bool kappa_max, const F &emit) const;
      /** Switch to @p new_fine: values, repartition, rebuild; returns the cells changed. */
      unsigned int
      transfer(const std::vector<char> &new_fine);
      void
      implicit_step();
      void
      compute_time_step_bound();
      long long
      block_of_cell(const typename Triangulation<dim>::cell_iterator &cell) const;
      long long
      block_of_coarse(const Index &K) const;
      /** Active lattice points (grid, index) of block @p b with flag @p fine. */
      void
      block_nodes(const long long b, const bool fine, std::vector<Index> &out) const;
      std::uint64_t
      id_of(const bool fine, const Index &i) const;
      Point<dim>
      point_of(const bool fine, const Index &i) const;
      double
      bond_kappa(const double phase_i, const double phase_j) const;

      MPI_Comm                                  comm;
      OctreeParameters<dim>                     prm;
      parallel::distributed::Triangulation<dim> tria;
      double                                    H, h;
      long long                                 ratio, k_cell;
      Index                                     nc, nf, n_blocks;
      Point<dim>                                fine_origin;
      std::vector<char>                         block_fine; ///< per block, every rank
      ScalarKernel                              kernel;
      std::array<std::vector<std::pair<Index, double>>, 2> stencil; ///< coarse, fine
      std::array<std::vector<double>, 2>                   stencil_weight; ///< omega beta V

      // local nodes: active (owned, ghost; the vector layout), then fictitious
      unsigned int                 n_owned = 0, n_local_active = 0;
      std::vector<Point<dim>>      node_position;
      std::vector<char>            node_fine;
      std::vector<std::uint64_t>   node_id_local;
      std::unordered_map<std::uint64_t, unsigned int> local_of_id;
      // bonds of owned rows: local neighbour, stencil entry
      std::vector<unsigned int> row_start, col, bond_entry;
      // interpolation of fictitious nodes (coarse ones first)
      std::vector<unsigned int> interp_node, interp_start, interp_source;
      std::vector<double>       interp_weight;
      std::vector<std::vector<std::pair<unsigned int, double>>> active_interpolation;

      LinearAlgebra::distributed::Vector<double> C, phase, rate;
      std::vector<double> work_c, work_phase; ///< local active + fictitious values
      double       dt = 0., dt_critical = 0., t = 0.;
      unsigned int n_step = 0, n_switch_events = 0, n_coarsened_cells = 0;
      struct Implicit;
      std::unique_ptr<Implicit> implicit; ///< backward Euler system and factorization
      std::unordered_map<long long, std::vector<double>> incoming; ///< transfer buffer
    };
  } // namespace MultiGrid
} // namespace PeriDEAL

#endif
