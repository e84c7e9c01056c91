#ifndef perideal_models_hybrid_bond_based_h
#define perideal_models_hybrid_bond_based_h

#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/stretch_budget.h>
#include <perideal/time_stepping/velocity_verlet.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of the adaptive hybrid configuration (dissertation Sect. 3.3)
   * for bond-based fracture: the WLS quadrature of Omega_w and the margin
   * sigma of the switching criterion (3.80).
   */
  struct HybridMechanicsParameters
  {
    /** WLS order and number of collocation nodes (WLS-2: 6 monomials, 29 nodes in 2D). */
    WlsParameters wls;
    /** Margin sigma in (0, 1) of (3.80): bonds of Omega_w with s >= sigma s0 are critical. */
    double sigma = 0.95;
    /**
     * Test (3.80) every this many force evaluations (>= 1). 1 is (3.80) as
     * stated; larger values trade the test's cost (about that of a force
     * evaluation of the Omega_w rows) against the margin: bonds that pass s0
     * in between are caught (and counted) at the next test.
     */
    unsigned int check_interval = 1;
    /**
     * Skip the exact test of (3.80) at the Omega_w nodes whose bonds provably
     * cannot have become critical since their last exact test
     * (StretchBudget). The outcome is that of the test of every bond; false
     * tests every bond at every test (the reference, for verification).
     */
    bool switching_bound = true;
    /**
     * With switching_bound, in 2D lattice sweeps (uses_lattice_sweep()):
     * bound the growth of the bond lengths by a Lipschitz bound of the
     * displacement increments on the lattice (one class, all bonds of a
     * node) instead of StretchBudget's increment boxes per length class.
     * The outcome is the same (both are conservative); only the number of
     * exact node tests differs.
     */
    bool lattice_bound = true;
    /**
     * In 2D lattice sweeps (uses_lattice_sweep()): evaluate the Omega_s
     * rows as a half-stencil sweep with reactions (each bond with an owned
     * Omega_s end once, from its end with the lower box position) instead
     * of every row over its full stencil (every bond between two Omega_s
     * nodes twice). The same bonds break; the forces differ by the
     * round-off of another summation order, which is still independent of
     * the partition (see sweep_half_rows()). Off by default: 37 % fewer
     * bond vectors, but each costs ~1.5x (the reaction update), and KW
     * dx = 0.25 measured no robust gain (doc/benchmarks.md, session 12).
     */
    bool half_stencil = false;
    /**
     * With the lattice bound (2D lattice sweeps): the exact test of a
     * vector whose tested lanes have every bond alive takes max |y|^2 over
     * the offsets of one bond length (no lane masks) and multiplies once
     * per length by 1 / T^2. The same q bit for bit (the rounding of
     * x / T^2 is monotone in x); false keeps the per-offset masked kernel
     * (the reference of test hybrid_kw.grouped_test).
     */
    bool length_grouped_test = true;
    /**
     * With length_grouped_test (2D, stencil radius <= 8): the grouped
     * kernel loads the positions of each stencil row once (three vectors
     * per row and dimension) and shifts every offset's lanes out of them
     * (valignq) instead of two unaligned loads per offset; the four offsets
     * (+-a, +-b) of one length share one multiplication. The same q bit for
     * bit; false keeps the per-offset loads of the grouped kernel.
     */
    bool row_shared_test = true;
  };

  /**
   * The adaptive hybrid bond-based model of dissertation Sect. 3.3 behind
   * the MechanicsModel interface.
   *
   * Nodes of Omega_s use the standard scheme (3.1): the nonlinear PMB bond
   * force of every family bond with partial volumes and bond breaking (the
   * BondBasedOperator's bond coefficients and critical stretch). Nodes of
   * Omega_w use the meshfree WLS collocation quadrature of the linearized
   * bond-based operator (3.52)-(3.59): F_i = sum_{c in C_i} W_ic u_c over
   * n_c collocation nodes (WLS-2 in 2D: 6 monomials, 29 nodes). The
   * dissertation derives WLS weights only for the linearized bond force
   * (Sect. 3.2.2); a pairwise nonlinear force at the collocation nodes has
   * no WLS weights (the weights act on the fitted displacement, not on
   * bonds). Omega_w is, by construction, where every stretch is below
   * sigma s0 ~ 1e-2, where the PMB force and its linearization differ by
   * O(s) relative to the force (plus rotation terms that are small in
   * KW-type problems). Bonds of Omega_w nodes never break.
   *
   * Switching (3.80): before each force evaluation (i.e. at the end of the
   * previous step, at the new displacement) every unbroken bond with at
   * least one end in Omega_w is tested; if s >= sigma s0 it is critical,
   * and the union of the families of both end nodes moves to Omega_s for
   * good (their new standard rows then break the bond in the same force
   * evaluation if s > s0). Bonds found with s > s0 while still in Omega_w
   * are counted (n_overstretched_bonds(); 0 means sigma was small enough).
   * The test compares squared lengths with precomputed squared thresholds
   * (no square root).
   *
   * Amortized test (HybridMechanicsParameters::switching_bound, default):
   * a node i of Omega_w is tested exactly (all its unbroken bonds) only
   * when StretchBudget says that some bond of i may have reached the
   * threshold T_b = r_b (1 + sigma s0) since i's last exact test. At that
   * test, with q_i = max_b |y_b|^2 / T_b^2 over the unbroken bonds of i,
   * every bond satisfies |y_b| <= sqrt(q_i) T_b, so until the growth bound
   * g_i of the bond lengths reaches the slack (1 - sqrt(q_i)) min_b T_b,
   * |y_b| <= sqrt(q_i) T_b + g_i < T_b: no bond of i is critical, and the
   * exact test of i would find nothing. Bonds only break (the intact set
   * shrinks), and a node never returns to Omega_w, so a record stays valid
   * while i is in Omega_w. Every critical bond has an Omega_w end whose
   * bound therefore fires, and that end tests it exactly: the critical bonds
   * found at every test, hence the switched nodes and the evaluation at
   * which each switches, are those of the test of every bond (verified by
   * tests/hybrid_kw, kw: identical switch evaluations and damage per node).
   * A margin of 1e-9 min_b T_b (plus 1e-13 of the lattice extent) is
   * subtracted from the slack against round-off of positions and bounds.
   * The bound of a StretchBudget grows with its reach (the width of the
   * blocks), the slack with the shortest bond; so the bonds are split into
   * length classes (r_min 4^k, r_min 4^(k+1)] (up to two), each with its
   * own StretchBudget (reach: the class's longest bond) and slack (its
   * shortest bond); a node tests (and records) the bonds of each class whose
   * bound fired, the argument above holding per class.
   * Lattice bound (HybridMechanicsParameters::lattice_bound, 2D sweeps):
   * for a bond of lattice offset (a, b), |u_j - u_i| is at most the sum of
   * the nearest-neighbour differences along the lattice path from i along
   * x to (j_x, i_y), then along y to j, so that
   * |D_j - D_i| <= |a| G_x + |b| G_y <= r_b c sqrt(G_x^2 / h_x^2 + G_y^2 / h_y^2)
   * (Cauchy-Schwarz, c = max over the offsets of |(a h_x, b h_y)| / r_b,
   * i.e. 1), with G_x the largest |d_P+1 - d_P| over the x-edges of i's
   * row within the stencil radius R, G_y the largest over the y-edges of
   * the (2R + 1) x 2R window (an edge with a missing end counts as
   * infinite), d the displacement increments since the last test. So the
   * stretch of every bond of i grows by at most H_i = c sqrt(...) per test
   * interval, whatever its length, and i needs no exact test while
   * sum H_i < (1 - sqrt(q_i)) (1 + sigma s0) minus the round-off margin.
   * The window maxima are separable sliding maxima over the box (edge
   * norms rounded up to float), O(R) per position and test.
   * Switching is rank independent: each rank marks the owned end points of
   * its critical bonds (a bond to a ghost is tested on both ranks with
   * bitwise the same length), one global sum tells whether anything is
   * critical, and only then are the critical flags and the new schemes sent
   * to the ghosts.
   *
   * Lattice sweeps (AVX-512, dim > 1, uniform bonds per lattice offset,
   * uses_lattice_sweep()): p = x - x_c + u and u are laid out over the box
   * of lattice positions (u copied every evaluation, p formed only in the
   * chunks of the box that the Omega_s rows and the exact tests read, with
   * the same bits as everywhere) and every row runs over the (signed) stencil
   * offsets, eight consecutive positions at a time, with per-offset bits
   * for the unbroken bonds: the Omega_s rows (PMB force and breaking, the
   * arithmetic of BondBasedOperator's AVX-512 loops), the exact switching
   * test (every Omega_w lane of a vector, or of a half of it, with a lane
   * whose bound fired) and
   * the WLS rows of the interior collocation pattern, which share one set
   * of weights (those of the row of lowest id; rows whose own weights
   * differ, near boundaries, keep them). A row sums its bonds in a fixed
   * offset order, so that results do not depend on the partition.
   *
   * The WLS rows of all initial Omega_w nodes are computed once at
   * construction; a switched node just stops using its row. Damage,
   * strain energy (bond energies (2.26) for every node, a diagnostic) and
   * broken-bond bookkeeping are the BondBasedOperator's, whose flags are
   * kept in sync.
   */
  template <int dim>
  class HybridBondBasedModel : public MechanicsModel<dim>
  {
  public:
    using VectorField = typename MechanicsModel<dim>::VectorField;

    /**
     * @p op provides c, s0, bond coefficients and broken flags (nonlinear
     * PMB only: throws ParameterError for the linearized model); @p omega
     * is its influence function (for the WLS operator rows).
     * @p standard: per owned node, true if it starts in Omega_s; constrained
     * (volume layer) nodes are always in Omega_s. Throws ParameterError if
     * a WLS row cannot be built (family too small: widen Omega_s).
     */
    HybridBondBasedModel(BondBasedOperator<dim>          &op,
                         const InfluenceFunction          omega,
                         const HybridMechanicsParameters &parameters,
                         const std::vector<bool>         &standard);

    const Discretization<dim> &
    discretization() const override
    {
      return disc;
    }
    void
    initialize(VectorField &field) const override
    {
      op.initialize(field);
    }
    /** Switch (3.80) at @p u, then standard rows with breaking and WLS rows. */
    void
    compute_forces(const VectorField &u, VectorField &force) override;
    void
    strain_energy_density(const VectorField &u, Vector &W) const override
    {
      sync_broken_flags();
      op.strain_energy_density(u, W);
    }
    double
    total_strain_energy(const VectorField &u) const override
    {
      sync_broken_flags();
      return op.total_strain_energy(u);
    }
    void
    damage(Vector &phi) const override
    {
      sync_broken_flags();
      op.damage(phi);
    }
    const std::vector<std::uint8_t> &
    broken() const override
    {
      sync_broken_flags();
      return op.broken();
    }
    void
    set_broken_flags(const std::vector<std::uint8_t> &flags) override
    {
      op.set_broken_flags(flags);
      broken_flag = flags;
      op_stale    = false;
      for (auto &b : budget) // bonds may have been restored
        b.invalidate();
      std::fill(lip_remaining.begin(), lip_remaining.end(), -1.);
      sweep_live_valid = false;
    }
    std::uint64_t
    n_broken_bonds() const override
    {
      sync_broken_flags();
      return op.n_broken_bonds();
    }
    void
    add_precrack(const std::vector<Point<dim>> &polygon) override
    {
      sync_broken_flags();
      op.add_precrack(polygon);
      broken_flag      = op.broken();
      sweep_live_valid = false;
    }
    /**
     * min of the standard bound (3.8) over all rows (any node may switch)
     * and, over the WLS rows, the Gershgorin-type bound
     * 2 sqrt(rho / sum_c ||W_ic||_inf) (Verlet is stable for
     * dt <= 2 / sqrt(lambda_max)).
     */
    double
    critical_time_step(const double rho) const override;
    double
    critical_stretch() const override
    {
      return op.critical_stretch();
    }
    std::string
    description() const override;

    /** @name Configuration */
    /** @{ */
    /** Per local node (owned, then ghosts): 1 Omega_w, 0 Omega_s (ghosts up to date). */
    const Vector &
    scheme() const
    {
      return wls_flag;
    }
    /** Global number of Omega_s nodes (interior and constrained). */
    types::global_dof_index
    n_standard_nodes() const;
    /** Fraction of the nodes in Omega_s (global). */
    double
    standard_fraction() const
    {
      return double(n_standard_nodes()) / double(disc.n_global());
    }
    /** Global number of bonds found with s > s0 while in Omega_w (should be 0). */
    std::uint64_t
    n_overstretched_bonds() const;
    /** Number of force evaluations at which some node switched (global). */
    unsigned int
    n_switch_events() const
    {
      return switch_events;
    }
    /**
     * Per owned node: the force evaluation (0-based count of
     * compute_forces() calls) before which it switched to Omega_s, or -1.
     */
    const std::vector<int> &
    switch_evaluation() const
    {
      return switched_at;
    }
    /** Number of exact node tests of (3.80) so far on this rank (a node per test). */
    std::uint64_t
    n_exact_node_tests() const
    {
      return exact_node_tests;
    }
    /**
     * Number of bond tests of the exact node tests so far on this rank
     * (lattice sweep: a node tests only the bonds of the length classes
     * whose bound fired).
     */
    std::uint64_t
    n_exact_bond_tests() const
    {
      return exact_bond_tests;
    }
    /**
     * True if the rows run as lattice sweeps (AVX-512, dim > 1, lattice
     * indices of all local nodes, bond stiffness and length uniform per
     * lattice offset); else the portable row loops over the CSR lists.
     */
    bool
    uses_lattice_sweep() const
    {
      return sweep_on;
    }
    /**
     * Whether the exact switching test's grouped kernel loads the stencil
     * rows once (HybridMechanicsParameters::row_shared_test, and a 2D
     * stencil of radius <= 8 with the lattice bound).
     */
    bool
    uses_row_shared_test() const
    {
      return rows_on;
    }
    /**
     * Number of owned Omega_w rows that use the shared WLS weights of the
     * interior collocation pattern (lattice sweep only; the others keep
     * their own row of weights).
     */
    unsigned int
    n_shared_pattern_rows() const
    {
      return n_shared_rows;
    }
    /**
     * The shared WLS pattern: lattice offsets (dim per collocation node) and
     * dim x dim weights per collocation node (empty if none is used).
     */
    const std::vector<int> &
    shared_pattern_offsets() const
    {
      return shared_lattice_offset;
    }
    const std::vector<double> &
    shared_pattern_weights() const
    {
      return shared_weight;
    }
    /** Per owned node: true if its WLS row uses the shared pattern weights. */
    bool
    uses_shared_pattern(const unsigned int i) const
    {
      return !shared_row.empty() && shared_row[i];
    }
    /** The WLS quadrature of the initial Omega_w rows. */
    const WlsQuadrature<dim> &
    wls_quadrature() const
    {
      return *wls;
    }
    /**
     * CPU time [switching test, standard rows, WLS rows, of the switching
     * test: the StretchBudget updates] of compute_forces() on this rank
     * (thread).
     */
    std::array<double, 4> seconds{{0., 0., 0., 0.}};
    /** @} */

  private:
    /** Test (3.80) on the bonds touching Omega_w and switch; true if anything switched. */
    bool
    switch_critical(const VectorField &u);
    /**
     * Copy the broken flags to the BondBasedOperator if bonds broke since
     * the last copy (lazily: damage and energies are read only for output).
     */
    void
    sync_broken_flags() const
    {
      if (op_stale)
        op.set_broken_flags(broken_flag);
      op_stale = false;
    }
    /** Rebuild the row lists after a change of scheme. */
    void
    update_row_lists();
    /** Set up the lattice sweep (sweep_on) if the lattice allows it. */
    void
    setup_lattice_sweep();
    /** Find the rows of Omega_w that share the interior WLS pattern. */
    void
    setup_shared_pattern();
    /** The live bits of the sweep from broken_flag. */
    void
    build_live_bits();
    /** Index of the bond of owned row @p i with lattice box index @p q (CSR). */
    std::uint64_t
    find_bond(const unsigned int i, const unsigned int q) const;
    /** Lattice box index of bond @p b of row @p i (offset + box_radius per dimension). */
    unsigned int
    box_index(const unsigned int i, const std::uint64_t b) const;
    /** The sweep versions of the switching test and of the rows. */
    std::uint64_t
    sweep_switching_test();
    /** Form p in the chunk @p c of the box (from sweep_x0 and sweep_u). */
    void
    fill_p_chunk(const std::size_t c);
    /**
     * Call @p f with every chunk of p that the rows of the eight box
     * positions from @p L0 read.
     */
    template <typename F>
    void
    for_each_p_chunk(const std::int64_t L0, const F &f) const;
    /** The lattice bound: advance it to the current sweep_u, mark the vectors to test. */
    void
    lattice_bound_vectors();
    bool
    sweep_standard_rows(VectorField &force);
    /**
     * The Omega_s rows as a half-stencil sweep (HybridMechanicsParameters::
     * half_stencil): every vector of half_groups, in their order, evaluates
     * for every positive offset g (in the order of half_offsets) the bonds
     * (L, L + o_g) of its lanes L for which L or L + o_g is an owned
     * Omega_s node, sums them in registers (stored to half_acc) and adds
     * them to half_reaction at L + o_g; F = acc - reaction. The vectors are
     * the same blocks of lattice rows on every rank (the box starts at a
     * multiple of 8 in x) and their order is a function of the lattice
     * (tiles of half_tile columns, row by row), so a row's terms arrive in
     * an order fixed by the lattice (its own: by g; its reactions: by source
     * vector, then g), and the forces do not depend on the partition. True
     * if a bond broke.
     */
    bool
    sweep_half_rows(VectorField &force);
    /** The per-vector live masks of the half-stencil sweep (half_mask). */
    void
    build_half_mask();
    /**
     * Clear both live bits and flag the owned CSR copies of the bonds in
     * sweep_broken; true if there are any.
     */
    bool
    apply_sweep_broken();
    void
    sweep_wls_rows(VectorField &force);

    BondBasedOperator<dim>    &op;
    const Discretization<dim> &disc;
    HybridMechanicsParameters  prm;
    double                     s0;
    std::unique_ptr<WlsQuadrature<dim>> wls;
    /** Per owned node: the WLS row index, or -1. */
    std::vector<int> wls_row;
    /**
     * The WLS rows packed for the vectorized force (2D): per row, chunks of
     * 8 collocation nodes (padded with zero weights), each with 8 columns
     * and the 4 x 8 weights W00, W01, W10, W11.
     */
    std::vector<std::uint64_t> packed_start;
    std::vector<std::int32_t>  packed_col;
    std::vector<double>        packed_weight;
    /** 1 in Omega_w (local, with ghosts); critical end points (local, with ghosts). */
    Vector wls_flag, critical;
    /** wls_flag as bytes (local, with ghosts), for the switching test. */
    std::vector<std::int32_t> wls_mask;
    /** Owned Omega_s rows; owned Omega_w rows. */
    std::vector<unsigned int> standard_rows, active_wls_rows;
    /** Owned Omega_w rows with their own weights (all of them without the sweep). */
    std::vector<unsigned int> own_weight_rows;
    /** Per bond table entry: (r (1 + sigma s0))^2, (r (1 + s0))^2, 1 / (r (1 + sigma s0))^2. */
    std::vector<double> critical_length2, breaking_length2, inverse_critical_length2;
    /**
     * Bonds in length classes (r_min 4^k, r_min 4^(k+1)] (the last one
     * open), each with its growth bound of the Omega_w nodes' bond lengths
     * since their last exact test, the upper length bound of the class and
     * min r (1 + sigma s0) over it.
     */
    std::vector<StretchBudget<dim>> budget;
    std::vector<double>             class_bound, min_threshold;
    /** Round-off margin subtracted from every slack. */
    double threshold_margin = 0.;
    std::vector<int> switched_at;
    std::uint64_t    exact_node_tests = 0, exact_bond_tests = 0;
    /** Broken flags of the owned rows (op's copy is updated when a bond breaks). */
    std::vector<std::uint8_t> broken_flag;
    mutable bool              op_stale = false;
    /** Scratch: deformed positions x - x_c + u, interleaved. */
    std::vector<double> deformed;
    std::uint64_t       overstretched = 0;

    /**
     * @name The lattice sweep: box positions L = sum_d (l_d - lower_d)
     * stride_d of the local nodes, every array over the box padded by pad
     * positions in front and behind (offsets up to +-pad never leave it),
     * vectors of 8 consecutive positions. Full (signed) bond offsets: a
     * row sums over all of them in a fixed order, so that the force of a
     * node does not depend on the box, i.e. on the partition.
     */
    /** @{ */
    bool                              sweep_on   = false;
    int                               box_radius = 0;
    std::array<int, dim>              sweep_lower{};
    std::array<std::int64_t, dim>     sweep_stride{};
    std::size_t                       sweep_pad = 0, sweep_n_vectors = 0, sweep_n_alloc = 0;
    /**
     * Per full offset f: linear offset, mirror offset, box index, k, r,
     * thresholds, class; k r and (r + s0 r)^2 of the force (computed once,
     * not per vector of the Omega_s rows).
     */
    std::vector<std::int64_t>  sweep_offset;
    std::vector<unsigned int>  sweep_mirror, sweep_box;
    std::vector<int>           sweep_of_box;
    std::vector<double>        sweep_k, sweep_r, sweep_L2, sweep_iL2, sweep_B2, sweep_kr, sweep_t2;
    std::vector<std::uint8_t>  sweep_class;
    /** Per length class: its full offsets. */
    std::vector<std::vector<unsigned int>> class_offsets;
    /** Box position of each local node; node (or -1) of each box position. */
    std::vector<std::uint32_t> sweep_position;
    std::vector<std::int32_t>  sweep_node;
    /**
     * Bit (f, L): bond (L, L + o_f) of an owned row exists and is unbroken,
     * at byte (L / 8) n_f + f (the offsets of a vector contiguous: the rows
     * and the test read all of them per vector).
     */
    std::vector<std::uint8_t>  sweep_live;
    bool                       sweep_live_valid = false;
    /**
     * Per vector: the lanes whose bit is set at every offset (all bonds
     * alive; the AND of the vector's bytes of sweep_live, kept with it), so
     * that the exact test picks its kernel without reading the bits.
     */
    std::vector<std::uint8_t>  full_lanes;
    /** p = x - x_c + u and u over the box (dim arrays of sweep_n_alloc). */
    std::vector<double> sweep_p, sweep_u;
    /** x - x_c over the box (layout of sweep_p). */
    std::vector<double> sweep_x0;
    /**
     * p = (x - x_c) + u is formed only where it is read, by chunks of
     * p_chunk box positions: around the Omega_s rows and the vectors of
     * exact tests (bitwise the value of a full copy). Per chunk, the
     * evaluation of its last fill; the chunks the Omega_s rows read; the
     * offsets of the stencil's rows (an offset without its x part).
     */
    static constexpr std::size_t p_chunk = 64;
    std::vector<std::uint32_t>   p_stamp, standard_chunks;
    std::vector<std::int64_t>    p_row_offsets;
    std::uint32_t                p_epoch = 0;
    /** Runs (first local node, its box position, length) of consecutive nodes at consecutive positions. */
    std::vector<std::array<std::uint32_t, 3>> fill_runs;
    /**
     * Per vector: lanes of shared-pattern WLS rows, of Omega_w rows; the
     * length classes to test (bit k).
     */
    std::vector<std::uint8_t>  shared_lanes, wls_lanes, test_lanes;
    std::vector<std::uint32_t> shared_vectors, test_vectors;
    /**
     * The Omega_s rows as runs of eight box positions starting anywhere
     * (not only at multiples of 8, so a strip of Omega_s fills the lanes):
     * first position and lanes of owned Omega_s nodes per run.
     */
    std::vector<std::uint32_t> standard_start;
    std::vector<std::uint8_t>  standard_start_lanes;
    /**
     * The half-stencil Omega_s sweep (sweep_half_rows()): on; the positive
     * full offsets (by x offset, then y offset); per vector (with spare
     * zero vectors up to the stencil reach), the lanes of owned Omega_s
     * nodes; the vectors that hold the lower end of a bond with an owned
     * Omega_s end (by tile, then box order) and those with owned Omega_s
     * lanes; reactions and own sums over the box (layout of sweep_p); the
     * tile width in lattice columns.
     */
    bool                         half_on = false;
    std::vector<unsigned int>    half_offsets;
    std::vector<std::uint8_t>    standard_lanes;
    std::vector<std::uint32_t>   half_groups, standard_vectors;
    std::vector<double>          half_reaction, half_acc;
    static constexpr std::int64_t half_tile = 64;
    /**
     * Per slot h of half_offsets: the offset and k, k r, (r + s0 r)^2; per
     * full offset its slot (or -1); per vector its index in half_groups (or
     * -1); per vector of half_groups and slot the lanes whose bond is
     * evaluated (rebuilt after a change of scheme or of the live bits, bits
     * of broken bonds cleared), and whether it is up to date; scratch:
     * the lanes broken per slot in one vector.
     */
    std::vector<std::int64_t>          half_o;
    std::vector<std::array<double, 3>> half_constants;
    std::vector<int>                   half_slot, half_index;
    std::vector<std::uint8_t>          half_mask, half_broken_lanes;
    bool                               half_mask_valid = false;
    /** Bonds broken by the sweep: (full offset, box position of the row). */
    std::vector<std::pair<unsigned int, std::uint32_t>> sweep_broken;
    /** The shared WLS pattern: linear and lattice offsets, weights; per owned node: uses it. */
    std::vector<std::int64_t> shared_offset;
    std::vector<int>          shared_lattice_offset;
    std::vector<double>       shared_weight;
    std::vector<std::uint8_t> shared_row;
    unsigned int              n_shared_rows = 0;
    /**
     * The lattice bound (2D): on; c^2 / h_d^2; margin / r_min; float pad of
     * the edge arrays; u at the last test over the box (layout of sweep_u,
     * swapped with it after a test); per box position, the slack left
     * (< 0: test); squared edge norms of the increments in x and y and the
     * x-window maxima of the latter (padded, +inf outside the box); per
     * vector and direction, the lanes whose edge has both ends; all offsets.
     */
    bool                       lattice_bound_on = false;
    std::array<double, 2>      lip_coef{};
    double                     lip_margin = 0.;
    std::size_t                lip_pad    = 0;
    std::vector<double>        lip_prev, lip_remaining;
    std::vector<float>         lip_ex, lip_ey, lip_fy;
    std::array<std::vector<std::uint8_t>, 2> lip_edge_ok;
    std::vector<unsigned int>  all_offsets;
    /**
     * The offsets grouped by equal 1 / T^2 (length_grouped_test): linear
     * offsets, group starts, 1 / T^2 per group; on.
     */
    std::vector<std::int64_t>  grouped_offset;
    std::vector<std::uint32_t> group_start;
    std::vector<double>        group_iL2;
    bool                       grouped_on = false;
    /**
     * The stencil by rows (row_shared_test): per row b in [0, R], bit a of
     * row_mask[b] says (a, b) (hence (+-a, +-b)) is an offset;
     * row_iL2[9 b + a] its 1 / T^2; on.
     */
    std::vector<std::uint16_t> row_mask;
    std::vector<double>        row_iL2;
    bool                       rows_on = false;
    bool                       lip_have_prev = false, lip_swap_pending = false;
    /** @} */
    unsigned int        n_evaluations = 0;
    unsigned int        switch_events = 0;
  };
} // namespace PeriDEAL

#endif
