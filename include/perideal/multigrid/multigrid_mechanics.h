#ifndef perideal_multigrid_multigrid_mechanics_h
#define perideal_multigrid_multigrid_mechanics_h

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <perideal/base/kernel.h>
#include <perideal/multigrid/multigrid_discretization.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  namespace MultiGrid
  {
    /**
     * Which model the two-grid mechanics solver runs (multi-adaptive paper
     * 001, Sect. 4.1): the standard scheme on one uniform grid, or the
     * multi-grid coupling of dissertation Sect. 3.4 with the switching of
     * Sect. 3.5, the coarse grid discretized by the standard scheme
     * ("adaptive, standard") or by WLS collocation ("adaptive, hybrid").
     */
    enum class MechanicsModel
    {
      uniform_fine,
      uniform_coarse,
      adaptive_standard,
      adaptive_hybrid
    };

    /** Parse "uniform fine", "uniform coarse", "adaptive standard", "adaptive hybrid". */
    MechanicsModel
    parse_mechanics_model(const std::string &name, const std::string &parameter = "Model");
    std::string
    to_string(const MechanicsModel model);

    /**
     * Parameters of explicit bond-based (PMB) elasticity on a fine/coarse
     * lattice pair over the box [lower, upper]: cell-centred coarse nodes of
     * spacing coarse_dx, each coarse cell split into r^dim fine cells
     * (r = coarse_dx / fine_dx an integer) with cell-centred fine nodes.
     * Both grids use the same horizon and the same micromodulus/critical
     * stretch (bond_based_micromodulus(), bond_based_critical_stretch()).
     */
    template <int dim>
    struct MechanicsParameters
    {
      Point<dim> lower, upper;
      double     coarse_dx = 2., fine_dx = 1., delta = 4.;
      bool       partial_volume = true;
      MechanicsModel model      = MechanicsModel::adaptive_hybrid;
      /** How fictitious nodes get their values; (3.85)-(3.88) by default. */
      Interpolation interpolation = Interpolation::inverse_distance;

      InfluenceFunction omega          = InfluenceFunction::constant;
      double            youngs_modulus = 1.;
      bool              plane_stress   = false;
      double            density        = 1.;
      /** G0 (0 and critical_stretch 0: bonds never break). */
      double fracture_energy = 0.;
      /** s0, used as given if > 0. */
      double critical_stretch = 0.;

      /** WLS collocation on the coarse grid (hybrid): order and n_c (0: default). */
      unsigned int wls_order = 2, n_collocation = 49;
      /** sigma of the switching criterion (3.80). */
      double switching_sigma = 0.95;
      /**
       * Coarse cells (given by their node) refined at t = 0 in the adaptive
       * models; empty: none.
       */
      std::function<bool(const Point<dim> &)> initial_fine_region;

      /**
       * false: the coupling (3.85)-(3.88), whose forces are not pairwise (an
       * active node's bond to a fictitious node has no reaction), so the
       * momentum drifts. true: the reaction of every active-fictitious bond
       * (the force the sweep computes on the fictitious end) is paid to the
       * active nodes that define the fictitious node's displacement, with
       * the interpolation weights (the transpose of (3.86)/(3.88), through
       * the coarse fictitious corners of fine fictitious nodes), scaled by
       * V_j / V_a: action = reaction, so the standard-scheme forces conserve
       * linear momentum to round-off. Not with the adaptive hybrid model
       * (ParameterError): its WLS rows are not pairwise.
       */
      bool conservative_coupling = false;

      /** Throws ParameterError naming the entry for inadmissible values. */
      void
      check() const;
    };

    /**
     * Explicit bond-based PD elasticity on two lattices coupled by
     * fictitious nodes (dissertation Sect. 3.4, (3.81)-(3.88)) with the
     * multi-adaptive switching of Sect. 3.5 / paper 001 Sect. 3.
     *
     * Every coarse cell is either coarse (its coarse node is an active
     * material point with volume dx+^dim) or refined (its r^dim fine nodes
     * are active, each with volume dx-^dim): every material point is
     * counted exactly once. Inactive nodes within the horizon of an active
     * node of their own grid are fictitious: before every force evaluation
     * the inactive coarse nodes get u from the fine nodes around them
     * ((3.85)-(3.86); they lie inside refined cells), then the fine
     * fictitious nodes from the 2^dim coarse nodes of the coarse lattice cell
     * containing them ((3.87)-(3.88)). Velocity Verlet (3.81)-(3.84) on the
     * active nodes; the fine grid uses the PMB force with irreversible bond
     * breaking (2.34), the coarse grid the same standard scheme (adaptive,
     * standard) or the WLS collocation of the linearized bond-based operator
     * (3.52)-(3.59) (adaptive, hybrid; coarse nodes whose family is cut by
     * the body's boundary keep the standard scheme).
     *
     * Switching (Fig. 3.30): after each step every bond of an active coarse
     * node is tested with (3.80), s >= sigma s0; for a critical bond
     * (x1, x2) all coarse cells whose node lies in H(x1) u H(x2) are
     * refined: their coarse nodes are deactivated and their fine nodes
     * activated with u, v, a interpolated from the coarse grid and shifted
     * so that the cell keeps its mean displacement and momentum. The switch
     * is one-way. Since coarse bonds never get close to s0 before their
     * cells are refined, coarse bonds do not break (a coarse bond beyond s0
     * also counts as critical, the upper bound of (3.80) being for grids
     * whose bonds break).
     *
     * Serial: the whole body is held by the calling process (as the rest
     * of the multi-grid module).
     */
    template <int dim>
    class MechanicsSolver
    {
    public:
      enum Grid : unsigned int
      {
        coarse = 0,
        fine   = 1
      };

      explicit MechanicsSolver(const MechanicsParameters<dim> &parameters);

      /** 2D: break the bonds of both grids crossing the segment [a, b]. */
      void
      add_precrack(const Point<dim> &a, const Point<dim> &b);

      /** Initial velocity v(x) of every node of both grids. */
      void
      set_initial_velocity(const std::function<Tensor<1, dim>(const Point<dim> &)> &v);
      /** Initial displacement u(x) of every node of both grids (accelerations recomputed). */
      void
      set_initial_displacement(const std::function<Tensor<1, dim>(const Point<dim> &)> &u);

      /** Nodes (of either grid) in @p region move with velocity @p v for all times. */
      void
      add_prescribed_velocity(const std::function<bool(const Point<dim> &)> &region,
                              const Tensor<1, dim>                          &v);

      /**
       * Critical time step: (3.8) for the standard scheme of each grid in
       * use, and for the WLS stencil the exact limit 2 sqrt(rho / lambda_max)
       * of its Fourier symbol.
       */
      double
      critical_time_step() const;
      void
      set_time_step(const double dt_in)
      {
        dt = dt_in;
      }
      double
      time_step() const
      {
        return dt;
      }
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

      /**
       * Refine the coarse cells whose node lies in @p region now, as a
       * switching event does (returns the number of cells refined).
       */
      unsigned int
      refine_region(const std::function<bool(const Point<dim> &)> &region);

      /** One velocity-Verlet step followed by the switching test (adaptive models). */
      void
      advance();

      /** @name State and measurements */
      /** @{ */
      unsigned int
      n_nodes(const Grid g) const
      {
        return grids[g].n_nodes;
      }
      unsigned int
      n_active(const Grid g) const;
      unsigned int
      n_fictitious(const Grid g) const
      {
        return fictitious[g].size();
      }
      bool
      is_active(const Grid g, const unsigned int i) const
      {
        return active_flag[g][i];
      }
      Point<dim>
      position(const Grid g, const unsigned int i) const;
      double
      node_volume(const Grid g) const
      {
        return grids[g].volume;
      }
      /** Displacement, velocity of node i of grid g (interleaved storage). */
      Tensor<1, dim>
      displacement(const Grid g, const unsigned int i) const;
      Tensor<1, dim>
      velocity(const Grid g, const unsigned int i) const;
      Tensor<1, dim>
      acceleration(const Grid g, const unsigned int i) const;
      /** True if node i of grid g has its whole bond stencil inside the body. */
      bool
      has_full_family(const Grid g, const unsigned int i) const
      {
        return grids[g].interior(i);
      }
      /** Damage (2.36) of node i of grid g (0 for the coarse grid's unbroken bonds). */
      double
      damage(const Grid g, const unsigned int i) const;
      /** sum rho V over the active nodes. */
      double
      active_mass() const;
      /** sum rho V v over the active nodes. */
      Tensor<1, dim>
      momentum() const;
      /** sum rho V |v|^2 / 2 over the active nodes. */
      double
      kinetic_energy() const;
      /** Number of broken bonds (each counted once). */
      std::uint64_t
      n_broken_bonds() const;
      /** Number of switching events (critical coarse bonds found) so far. */
      unsigned int
      n_switches() const
      {
        return switches;
      }
      /** Thread CPU time spent in forces, interpolation, switching test, switching [s]. */
      std::array<double, 4> timing{{0., 0., 0., 0.}};
      double
      micromodulus() const
      {
        return c;
      }
      double
      critical_stretch() const
      {
        return s0;
      }
      const MechanicsParameters<dim> &
      parameters() const
      {
        return prm;
      }
      /** Coarse cells refined so far (indexed by coarse node). */
      const std::vector<std::uint8_t> &
      refined_cells() const
      {
        return refined;
      }
      /**
       * Total-least-squares angle (degrees, to the x axis, in (-90, 90])
       * through the active fine nodes with damage >= @p threshold whose
       * position satisfies @p region and whose distance from @p origin is in
       * [r_min, r_max] (2D); NaN if fewer than 3. @p n_nodes returns the count.
       */
      double
      crack_angle(const Point<dim>                              &origin,
                  const std::function<bool(const Point<dim> &)> &region,
                  const double                                   threshold,
                  const double                                   r_min,
                  const double                                   r_max,
                  unsigned int                                  &n_nodes) const;
      /** @} */

    private:
      /** One lattice with its bond stencil. */
      struct Lattice
      {
        double                     dx = 0., volume = 0.;
        Point<dim>                 origin; ///< first node
        std::array<int, dim>       n{};
        unsigned int               n_nodes = 0;
        std::vector<std::array<int, dim>> offset;
        std::vector<long>          linear_offset;
        std::vector<Tensor<1, dim>> xi;
        std::vector<double>        length;
        /** c omega beta V / |xi| (PMB force: coef (|y| - |xi|) y / |y|). */
        std::vector<double>        coefficient;
        /** beta V (damage). */
        std::vector<double>        weight;
        std::vector<unsigned int>  mirror;
        int                        radius = 0; ///< stencil half width in nodes

        std::array<int, dim>
        index(const unsigned int i) const;
        unsigned int
        node(const std::array<int, dim> &ix) const;
        bool
        inside(const std::array<int, dim> &ix) const;
        Point<dim>
        point(const unsigned int i) const;
        /** True if every stencil neighbour of i exists. */
        bool
        interior(const unsigned int i) const;
        /**
         * Calls @p visit(j) for the stencil neighbours j of node i in the
         * lattice (stencil order) until it returns true; returns whether it did.
         */
        template <typename Visitor>
        bool
        any_neighbour(const unsigned int i, const Visitor &visit) const
        {
          const auto ix = index(i);
          const bool in = interior(i);
          for (unsigned int k = 0; k < offset.size(); ++k)
            {
              if (!in)
                {
                  auto jx = ix;
                  for (unsigned int d = 0; d < dim; ++d)
                    jx[d] += offset[k][d];
                  if (!inside(jx))
                    continue;
                }
              if (visit(static_cast<unsigned int>(i + linear_offset[k])))
                return true;
            }
          return false;
        }
      };

      /**
       * A grid's bonds as a lattice sweep (the idea of BondBasedOperator's
       * sweep): the lattice padded by the stencil radius on every side, so
       * that a bond is a fixed offset o > 0 between box positions (L, L + o)
       * and each bond is evaluated once (Newton's third law: the force on L,
       * its reaction on L + o). Per positive offset a bit per box position
       * says the bond is to be evaluated: unbroken, both ends in the lattice
       * and at least one end "evaluated" (an active node whose force the
       * grid's standard scheme gives). The other end is active or
       * fictitious; reactions on fictitious (or WLS) nodes are discarded.
       */
      struct Box
      {
        std::array<long, dim> stride{};
        long                  n_box = 0, o_max = 0;
        std::size_t           n_bytes = 0, n_alloc = 0;
        /** Positive stencil offsets: box offset, stencil index k, coefficient, length. */
        std::vector<long>         offset;
        std::vector<unsigned int> k;
        std::vector<double>       coefficient, length;
        /** Box position of node i. */
        std::vector<long> position;
        /**
         * Per positive offset (n_bytes each, as 64-bit words): intact bits
         * (both ends in the lattice, bond unbroken) and live bits (intact
         * and an evaluated end); per chunk the groups of 8 positions with
         * a live bit (CSR: group_start per chunk, groups within the chunk).
         */
        std::vector<std::uint64_t> intact, live;
        std::vector<unsigned int>  group_start;
        std::vector<std::uint8_t>  groups;
        /** Evaluated nodes as bits per box position (padded for shifted reads). */
        std::vector<std::uint64_t> evaluated_bits;
        bool                       intact_valid = false;
        /** The evaluated nodes (ascending) and their box positions. */
        std::vector<unsigned int> evaluated;
        std::vector<long>         evaluated_position;
        /** Conservative coupling: the fictitious nodes (ascending box position) and their positions. */
        std::vector<unsigned int> paid;
        std::vector<long>         paid_position;
        /** x - x_c + u and reactions per box position, dim arrays of n_alloc. */
        std::vector<double> p, reaction;
        /** Scratch: (offset, position) of bonds broken in this sweep. */
        std::vector<std::pair<unsigned int, long>> newly_broken;
        /** x - x_c per box position (dim arrays of n_alloc). */
        std::vector<double> reference;
        /** Per box position: 0 outside the lattice, 1 inactive node, 2 active node. */
        std::vector<std::uint8_t> state;
        /** Box positions of the first and one past the last node. */
        long first = 0, last = 0;
        /** u_version when p was filled. */
        std::uint64_t filled = 0;
        /** False when the active set or the broken flags changed since the bits were built. */
        bool valid = false;
        /** False when `state` must be rebuilt from the active flags (a switch updates it in place). */
        bool state_valid = false;
        /**
         * False when all live bits must be rebuilt; else only those of the
         * positions whose bonds reach [dirty_lo, dirty_hi), the box positions
         * of the nodes a switch made (non-)evaluated. Per word: any live bit.
         */
        bool                       live_valid = false;
        long                       dirty_lo = 0, dirty_hi = 0;
        std::vector<std::uint64_t> any;
      };

      MechanicsParameters<dim> prm;
      unsigned int             ratio;
      double                   c, s0, dt = 0., t = 0.;
      unsigned int             n_step = 0, switches = 0;
      std::array<Lattice, 2>   grids;
      std::array<Box, 2>       boxes;
      /** Incremented whenever u of some node may have changed (box positions stale). */
      std::uint64_t            u_version = 1;
      /** Interleaved u, v, a per grid. */
      std::array<std::vector<double>, 2> u, v, a;
      std::array<std::vector<std::uint8_t>, 2> active_flag, broken;
      /** Prescribed velocity index + 1 per node (0: free). */
      std::array<std::vector<unsigned int>, 2> prescribed;
      std::vector<Tensor<1, dim>>             prescribed_velocity;
      std::vector<std::uint8_t>               refined;
      std::array<std::vector<unsigned int>, 2> active, fictitious;
      /** Interior coarse nodes using the WLS stencil (hybrid). */
      std::vector<std::uint8_t> use_wls;
      /** The WLS stencil: lattice offset and dim x dim weights (row-major). */
      std::vector<long>   wls_offset;
      std::vector<double> wls_weight;
      /** Stability limit of velocity Verlet with the WLS stencil (its symbol). */
      double wls_stable_step = 0.;
      /** Conservative coupling: force density on the fictitious nodes (dim per node). */
      std::array<std::vector<double>, 2> fictitious_force;
      /** Interpolation rows: node, then sources/weights (CSR) for each grid's fictitious list. */
      std::array<std::vector<unsigned int>, 2> interp_start, interp_source;
      std::array<std::vector<double>, 2>       interp_weight;
      /** Coarse nodes to interpolate before the fine fictitious ones (inactive corners too). */
      std::vector<unsigned int> coarse_interpolated;
      /**
       * Runs of consecutive node indices within one lattice row (first
       * node, length): their u, v, a and box positions are contiguous, so
       * the Verlet updates and box fills vectorize. Per grid: the active
       * nodes, the active and fictitious nodes, and (coarse) the active WLS
       * nodes; with the active nodes that have a prescribed velocity.
       */
      std::array<std::vector<std::pair<unsigned int, unsigned int>>, 2> active_runs, filled_runs;
      std::vector<std::pair<unsigned int, unsigned int>>                 wls_runs;
      std::array<std::vector<unsigned int>, 2>                           prescribed_active;
      /** The runs above from the node lists (after every change of the lists). */
      void
      update_runs();
      /** Scratch flags per fine node (all 0 between uses). */
      std::vector<std::uint8_t> fine_mark;

      void
      setup_lattice(const Grid g, const double dx);
      /** Box geometry and positive offsets of grid g (after setup_lattice). */
      void
      setup_box(const Grid g);
      /** Live bits of grid g from the broken flags and the evaluated nodes. */
      void
      build_box_bits(const Grid g);
      /** True if grid g's standard scheme gives node i's force. */
      bool
      evaluated(const Grid g, const unsigned int i) const
      {
        return active_flag[g][i] && !(g == coarse && !use_wls.empty() && use_wls[i]);
      }
      void
      setup_wls();
      /** Conservative coupling: the fictitious reactions to their active donors. */
      void
      pay_back_fictitious_forces();
      /** Rebuild active/fictitious lists and interpolation rows from @p refined. */
      void
      update_node_sets();
      /**
       * The same sets after the coarse cells @p cells were refined, updated
       * where they can change (within a stencil of the new fine nodes).
       */
      void
      update_node_sets(const std::vector<unsigned int> &cells);
      /** Fine node q (0 .. r^dim - 1, x fastest) of coarse cell @p cell. */
      unsigned int
      child(const unsigned int cell, const unsigned int q) const;
      /** True if an active node of grid g has the inactive node i in its stencil. */
      bool
      has_active_neighbour(const Grid g, const unsigned int i) const;
      /**
       * Interpolation rows of the fictitious lists; rows of the nodes in
       * @p old_fine / @p old_coarse (the lists the current rows belong to)
       * are copied, since a row depends only on the node's position.
       */
      void
      update_interpolation_rows(const std::vector<unsigned int> &old_fine,
                                const std::vector<unsigned int> &old_coarse);
      /** IDW / d-linear sources in grid @p from for point @p x. */
      void
      interpolation_sources(const Grid                                   from,
                            const Point<dim>                            &x,
                            std::vector<std::pair<unsigned int, double>> &out) const;
      /** u (and optionally v, a) of the fictitious nodes. */
      void
      interpolate_fictitious(std::vector<double> *const field[2]);
      /** a = F / rho on the active nodes. */
      void
      compute_accelerations();
      void
      standard_forces(const Grid g, const bool allow_breaking);
      void
      wls_forces();
      /** Refine the coarse cells flagged in @p zone; returns how many. */
      unsigned int
      refine(const std::vector<std::uint8_t> &zone);
      /** Coarse cells to refine after the step (3.80); empty result if none. */
      bool
      find_critical(std::vector<std::uint8_t> &zone);
      /** p = x - x_c + u in grid g's box for its active and fictitious nodes. */
      void
      fill_box_positions(const Grid g);
      /** WLS displacements per coarse box position and the forces (hybrid). */
      std::vector<double> wls_u;
      std::vector<long>   wls_box_offset;
      void
      apply_prescribed();
    };

    /**
     * The Kalthoff-Winkler experiment of dissertation Sect. 3.5.1 / paper
     * 001 Sect. 4.1 on the two-grid solver (units mm, s, tonne, N as in
     * tutorial/step-4): plate (0, -100)-(100, 100), pre-cracks 50 mm long
     * from the impacted edge at y = +-25, E = 190e3, nu = 1/4 (plane
     * strain), rho = 8e-9, G0 = 22.17, v0 = 16.5e3 held on the fine nodes
     * of the first column (x < dx-) between the pre-cracks, T = 87.5e-6.
     * The initial fine region (adaptive models) is every coarse cell whose
     * node lies within delta of the plate's boundary or of a pre-crack
     * (paper 001, Fig. 7: "the pre-cracks and the boundaries").
     */
    struct KalthoffWinkler
    {
      MechanicsModel model     = MechanicsModel::adaptive_hybrid;
      double         coarse_dx = 2., fine_dx = 1., delta = 8.;
      double         end_time  = 87.5e-6;
      Interpolation  interpolation = Interpolation::inverse_distance;
      /** MechanicsParameters::conservative_coupling. */
      bool conservative_coupling = false;

      MechanicsParameters<2>
      parameters() const;
      /** Pre-cracks and the impact velocity. */
      void
      load(MechanicsSolver<2> &solver) const;
      /** Number of steps: 0.9 x the critical step, rounded to end on end_time. */
      unsigned int
      n_steps(const MechanicsSolver<2> &solver) const;
      /**
       * Angle of the upper crack (tutorial/step-4's measurement): damaged
       * (>= 0.35) fine nodes up and to the right of the tip (50, 25), at
       * delta to 50 mm from it.
       */
      double
      crack_angle(const MechanicsSolver<2> &solver, unsigned int &n_nodes) const;
      /** Largest distance of a damaged (>= 0.35) fine node of that region from the tip. */
      double
      crack_length(const MechanicsSolver<2> &solver) const;

      /** What run() measures. */
      struct Result
      {
        unsigned int coarse_begin = 0, fine_begin = 0, coarse_end = 0, fine_end = 0;
        unsigned int steps = 0, switches = 0, crack_nodes = 0;
        double       angle = 0., length = 0.;
        /** Wall time of the time loop (setup excluded) [s]. */
        double seconds = 0.;
        /** Thread CPU time of the time loop (setup excluded) [s]. */
        double cpu_seconds = 0.;
        /** MechanicsSolver::timing (CPU): forces, interpolation, switching test, switching. */
        std::array<double, 4> timing{{0., 0., 0., 0.}};
      };
      /**
       * Set up, load and run to end_time; @p monitor (if set) is called
       * after setup and every @p interval steps and at the end (not timed).
       */
      Result
      run(const std::function<void(const MechanicsSolver<2> &)> &monitor  = {},
          const unsigned int                                     interval = 0) const;
    };
  } // namespace MultiGrid
} // namespace PeriDEAL

#endif
