#ifndef perideal_multigrid_multigrid_discretization_h
#define perideal_multigrid_multigrid_discretization_h

#include <deal.II/base/point.h>

#include <perideal/base/kernel.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/solid_neighbor_count.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * The multi-grid coupling of dissertation Sect. 3.4 (eqs. 3.81-3.90):
   * a fine grid (spacing dx-) and a coarse grid (dx+ = r dx-, r integer)
   * with the same horizon, each region active in exactly one grid, and
   * fictitious nodes whose values are interpolated from the active nodes of
   * the other grid.
   */
  namespace MultiGrid
  {
    /**
     * Where the fine grid is active: a box, a ball, or a cylinder (circle in
     * 2D; axis along the last coordinate in 3D, of given half-height). A
     * coarse cell is refined when its centre (the coarse node) lies inside;
     * the refinement is therefore chosen per coarse cell, and the fine
     * region actually used is the union of the refined cells.
     */
    template <int dim>
    struct Region
    {
      enum class Shape
      {
        none,
        box,
        ball,
        cylinder
      };
      Shape      shape = Shape::none;
      Point<dim> lower, upper; ///< box
      Point<dim> center;       ///< ball, cylinder
      double     radius      = 0.;
      double     half_height = 0.; ///< cylinder in 3D

      static Region
      box(const Point<dim> &lower, const Point<dim> &upper);
      static Region
      ball(const Point<dim> &center, const double radius);
      static Region
      cylinder(const Point<dim> &center, const double radius, const double half_height);

      bool
      contains(const Point<dim> &p) const;
      /** Smallest width of the region (box edge, diameter, cylinder height). */
      double
      min_width() const;
    };

    /**
     * How a fictitious node gets its value: by default from the 2^dim
     * corners of the cell of the other grid's lattice that contains it.
     */
    enum class Interpolation
    {
      /** (3.85)-(3.88): weights 1/|x_k - x_j|, normalized. */
      inverse_distance,
      /** d-linear (tensor-product) interpolation: exact for linear fields. */
      multilinear,
      /**
       * (3.85)-(3.88) read literally: inverse distance over the 2^dim
       * nearest *active* nodes of the other grid. For a fine fictitious
       * node next to the interface these all lie on the far side (the
       * enclosing cell's inner corner is inactive in the coarse grid), so
       * the value is a convex combination of farther nodes: an O(dx+
       * |grad C|) error. Kept for comparison.
       */
      nearest_active
    };

    /**
     * Geometry and discretization of a multi-grid body: the box
     * [lower, upper] covered by a vertex lattice of spacing dx+ (as the
     * uniform Discretization: node volume dx+^dim, cell = node + [-dx+/2,
     * dx+/2]^dim), of which the cells whose node lies in @p fine_region are
     * refined into r^dim cells of spacing dx- with cell-centred fine nodes.
     */
    template <int dim>
    struct Parameters
    {
      Point<dim>     lower, upper;
      double         coarse_dx      = 0.5;
      double         fine_dx        = 0.125;
      double         delta          = 1.;
      bool           partial_volume = true;
      Region<dim>    fine_region;
      Interpolation  interpolation = Interpolation::inverse_distance;
      InfluenceFunction omega      = InfluenceFunction::constant;
      /** Exponent of |xi| in the kernel omega/|xi|^exponent (q of J_q). */
      double exponent = 1.;

      /** Throws ParameterError naming the entry for inadmissible values. */
      void
      check() const;
    };

    /**
     * The node sets and bond tables of a two-grid body (serial: every rank
     * holds the whole description; nothing here is distributed).
     *
     * Node numbering: coarse active, fine active, coarse fictitious, fine
     * fictitious. Active nodes are material points (volume dx^dim of their
     * grid); fictitious nodes only complete the neighbourhoods of active
     * nodes of their own grid within the horizon across the interface, they
     * carry no mass and their values are interpolated (3.85)-(3.88) from the
     * active nodes of the other grid. Coarse fictitious nodes lie inside
     * refined cells and interpolate from the fine active nodes around them;
     * fine fictitious nodes interpolate from the corners of their coarse
     * lattice cell, which are coarse active nodes or coarse fictitious nodes
     * (evaluated first), so the interpolation never extrapolates.
     *
     * Fields are node-major arrays with @p n_components values per node, so
     * the same interpolation serves C (scalar) and u, v (dim components).
     */
    template <int dim>
    class Discretization
    {
    public:
      enum Grid : unsigned char
      {
        coarse = 0,
        fine   = 1
      };

      explicit Discretization(const Parameters<dim> &parameters);

      const Parameters<dim> &
      parameters() const
      {
        return prm;
      }

      /** @name Node sets */
      /** @{ */
      unsigned int
      n_nodes() const
      {
        return position.size();
      }
      unsigned int
      n_active() const
      {
        return n_active_coarse + n_active_fine;
      }
      unsigned int n_active_coarse = 0, n_active_fine = 0;
      unsigned int n_fictitious_coarse = 0, n_fictitious_fine = 0;
      bool
      is_active(const unsigned int i) const
      {
        return i < n_active();
      }
      std::vector<Point<dim>>    position;
      std::vector<double>        volume; ///< dx^dim of the node's grid
      std::vector<unsigned char> grid;   ///< coarse or fine
      /** @} */

      /**
       * Bonds of the active nodes (CSR, rows 0..n_active()-1): neighbour
       * index (active or fictitious of the same grid), length |xi| and the
       * quadrature weight beta(|xi|) V_j of the node's grid.
       */
      std::vector<unsigned int> row_start, col;
      std::vector<double>       bond_length, bond_weight;

      /**
       * Interpolation rows of the fictitious nodes, in evaluation order
       * (all coarse fictitious nodes before the fine ones): node index,
       * sources and weights (weights sum to 1, all >= 0).
       */
      std::vector<unsigned int> interp_node, interp_start, interp_source;
      std::vector<double>       interp_weight;

      /**
       * The same interpolation with every source expanded to active nodes
       * (a fine fictitious node whose corner is a coarse fictitious node
       * depends on the fine active nodes around that corner). Indexed by
       * fictitious node k - n_active().
       */
      std::vector<std::vector<std::pair<unsigned int, double>>> active_interpolation;

      /** Overwrite the fictitious entries of @p values by interpolation. */
      void
      update_fictitious(std::vector<double> &values, const unsigned int n_components = 1) const;

      /** sum over active nodes of value * V (component @p c). */
      double
      integrate(const std::vector<double> &values,
                const unsigned int         n_components = 1,
                const unsigned int         c            = 0) const;

      /** Total volume of the active nodes (the body's volume, counted once). */
      double
      active_volume() const;

    private:
      Parameters<dim> prm;
    };

    /**
     * Parameters of the multi-grid transport model: linear PD diffusion with
     * micro-diffusivity kappa, or the bi-material corrosion model with the
     * one-way phase rule (2.79) of the uniform DiffusionOperator.
     */
    struct TransportParameters
    {
      bool   corrosion = false;
      double kappa     = 1.; ///< diffusion
      double kappa_liquid = 2., kappa_interface = 0.1, kappa_solid = 0.; ///< corrosion
      double saturation = 0.85; ///< C_sat
      std::string scheme = "forward Euler"; ///< or "backward Euler"
      /**
       * false: the coupling of the dissertation (3.82)-(3.90): both grids
       * use their fictitious neighbours; linear-consistent with d-linear
       * (1D: inverse-distance) interpolation, but the interface fluxes seen
       * by the two grids differ at the quadrature-error level, so the total
       * mass drifts. true: the interface bonds are evaluated once, on the
       * fine side (3.82), and the mass each fine node receives from a
       * fictitious neighbour is taken from the active nodes that define the
       * neighbour's value, with the interpolation weights (the transpose of
       * (3.88)); coarse active nodes then skip their fictitious bonds. Mass
       * is conserved to round-off; constants are preserved, linear fields
       * only up to an O(dx+) interface error at the coarse nodes.
       */
      bool conservative = false;
      /**
       * Scale the kernel of each grid so that its discrete second moment
       * sum_j omega |xi|^-p beta V_j xi_1^2 over the full lattice stencil
       * equals the continuum one (ScalarKernel::second_moment()). Without
       * it the two grids have different effective diffusivities (2D, m+ =
       * 2 vs m- = 4 with partial volumes: 1.097 vs 1.013 of D), so the
       * interface fluxes seen by the two grids differ at O(1) and the
       * interpolation coupling loses mass at that rate. Off by default: the
       * uniform models of the library are not calibrated.
       */
      bool calibrate = false;
      double      time_step = 0.;           ///< 0: 0.9 x the stability bound
      /**
       * Quadrature of the coarse active rows: "standard" (the bonds of
       * (3.84)) or "wls", the WLS collocation quadrature of Sect. 3.2 on
       * every coarse active node with a complete coarse family (the
       * "adaptive, hybrid" configuration of Sect. 3.5 and [100] Example 2:
       * WLS in Omega+, standard in Omega-). In corrosion a WLS row falls
       * back to its bonds while any of its collocation nodes is solid (the
       * bond diffusivity is then not uniform). Forward Euler with the
       * interpolation coupling only.
       */
      std::string   coarse_quadrature = "standard";
      WlsParameters wls;
    };

    /**
     * Transient PD diffusion / corrosion on a multi-grid body:
     * forward Euler (3.82)/(3.84) with fictitious values from (3.86)/(3.88)
     * before every operator evaluation, or backward Euler with the fictitious
     * rows (3.89)-(3.90) in the linear system (phase lagged one step, as the
     * frozen-Jacobian scheme of the uniform solver). The phase of a
     * fictitious node is that of the interpolated phase field (solid if
     * >= 1/2).
     */
    template <int dim>
    class TransportSolver
    {
    public:
      TransportSolver(const Discretization<dim> &discretization,
                      const TransportParameters &parameters);
      ~TransportSolver();

      /** Initial concentration C0(x) on the active nodes; phase solid iff C0 >= C_sat. */
      template <typename F>
      void
      set_initial(const F &c0)
      {
        for (unsigned int i = 0; i < disc.n_active(); ++i)
          C[i] = c0(disc.position[i]);
        initialize_phase();
      }
      void
      initialize_phase();

      /**
       * Hold the active nodes where @p inside(x) is true at their current
       * value (a Dirichlet volume constraint, e.g. C = 0 within delta of the
       * electrolyte's outer surface): their rows are not evaluated.
       */
      template <typename F>
      void
      set_constrained(const F &inside)
      {
        for (unsigned int i = 0; i < disc.n_active(); ++i)
          constrained[i] = inside(disc.position[i]);
      }
      unsigned int
      n_constrained() const
      {
        return std::count(constrained.begin(), constrained.end(), char(1));
      }
      /** Coarse active rows with WLS weights (0 for the standard quadrature). */
      unsigned int
      n_wls_rows() const
      {
        return wls ? wls->node.size() : 0;
      }
      /** WLS rows whose last evaluation used the weights (not the bonds). */
      unsigned int
      n_wls_rows_used() const
      {
        return n_wls_used;
      }

      /**
       * Corrosion: rows whose neighbours (active and fictitious) are all of
       * one phase are summed with that one kappa, without per-bond phase
       * look-ups (the same values up to round-off: four summation chains), rows with kappa 0 skipped (exactly 0), and
       * WLS rows with an all-liquid family skip the per-step phase check of
       * their collocation nodes (default true; false: the per-bond kernel on
       * every row, for reference).
       */
      void
      set_phase_classification(const bool on)
      {
        classify = on;
      }

      /** One time step. */
      void
      advance();

      /**
       * rate_i = (L C)_i on the active nodes, (3.82)/(3.84); @p values must
       * have their fictitious entries up to date.
       */
      void
      apply(const std::vector<double> &values, std::vector<double> &rate) const;

      /** Forward Euler bound of the operator with the largest kappa on every bond. */
      double
      critical_time_step() const
      {
        return dt_critical;
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
      double
      mass() const
      {
        return disc.integrate(C);
      }
      double
      solid_volume() const
      {
        return disc.integrate(phase);
      }
      /** Concentration (fictitious entries interpolated). */
      const std::vector<double> &
      solution() const
      {
        return C;
      }
      std::vector<double> &
      solution()
      {
        return C;
      }
      const std::vector<double> &
      phase_field() const
      {
        return phase;
      }

    private:
      double
      bond_kappa(const unsigned int i, const unsigned int j) const;
      void
      update_phase();
      void
      implicit_step();
      /** Entries (row, column, value) of L on the active rows (duplicates summed later). */
      std::vector<std::tuple<unsigned int, unsigned int, double>>
      operator_entries(const bool expand_fictitious, const bool use_kappa_max) const;

      const Discretization<dim> &disc;
      TransportParameters        prm;
      ScalarKernel               kernel;
      std::vector<double>        kernel_weight; ///< omega r^-p beta V per bond
      std::vector<double>        C, phase, rate;
      double                     dt = 0., dt_critical = 0., t = 0.;
      unsigned int               n_step = 0;
      struct Implicit;
      std::unique_ptr<Implicit> implicit;
      std::vector<char>         constrained; ///< per active node
      std::unique_ptr<WlsQuadrature<dim>> wls; ///< coarse WLS rows
      std::vector<int>          wls_row;       ///< per active node: row of wls or -1
      mutable unsigned int      n_wls_used = 0;
      bool                       classify = true;
      mutable SolidNeighborCount solid_count; ///< solid neighbours per active row
    };

    /**
     * A reduced analogue of the 3D bio-corrosion example of [100] (Example 2,
     * dissertation Sect. 3.5.2): a solid cylinder (the screw without thread
     * and slot; axis z, C = 1) in a cubic electrolyte (C = 0) held at C = 0
     * within delta of its outer faces, bi-material corrosion with the
     * one-way phase rule, forward Euler. Omega- is a cylinder around the
     * solid, enlarged by @p fine_margin, fixed in time. The material is that
     * of the 1D example E5 (kappa_liq = 2, kappa_int = 0.1, C_sat = 0.85,
     * q = 1): with the source's C_sat / C_solid = 1e-5 a surface node needs
     * thousands of steps to dissolve.
     */
    struct CylinderCorrosionCase
    {
      double half_width  = 1.05;  ///< the cube [-L, L]^3 of coarse nodes (L multiple of dx+)
      double radius      = 0.3;   ///< solid cylinder
      double half_height = 0.45;
      double fine_margin = 0.45;  ///< Omega- = solid cylinder enlarged by this
      double fine_dx     = 0.075;
      unsigned int ratio = 2;     ///< dx+ = ratio dx-
      double delta       = 0.45;
      double end_time    = 1.;
      double time_step   = 0.;    ///< 0: 0.9 x the bound of the uniform fine model
      TransportParameters transport; ///< corrosion = true, E5's material by default
      CylinderCorrosionCase();
    };

    /** Node counts, relative volume loss history and timing of one run. */
    struct CorrosionHistory
    {
      unsigned int n_active_coarse = 0, n_active_fine = 0, n_fictitious = 0,
                   n_constrained = 0, n_wls_rows = 0;
      double setup_seconds = 0., step_seconds = 0., step_cpu_seconds = 0., time_step = 0.;
      std::vector<double> time, loss; ///< loss = 1 - V_solid(t) / V_solid(0)
    };

    /**
     * Run the case with @p configuration "uniform fine" (one lattice of
     * spacing dx-, nodes at the fine nodes of the multi-grid), "uniform
     * coarse" (dx+), "multi-grid" (standard quadrature on both grids) or
     * "adaptive hybrid" (WLS on the coarse grid). @p max_steps > 0 stops
     * earlier (timing runs).
     */
    CorrosionHistory
    run_cylinder_corrosion(const CylinderCorrosionCase &c, const std::string &configuration,
                           const unsigned int max_steps = 0);
  } // namespace MultiGrid
} // namespace PeriDEAL

#endif
