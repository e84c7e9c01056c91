#ifndef perideal_models_bond_based_h
#define perideal_models_bond_based_h

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <perideal/base/kernel.h>
#include <perideal/base/page_offset_allocator.h>
#include <perideal/discretization/discretization.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of bond-based PD elasticity with bond breaking (dissertation
   * Sect. 2.2): the prototype microelastic brittle (PMB) / generalized
   * bond-based (GPBM) material (2.27)-(2.34) or its linearization (2.32).
   * Poisson's ratio is fixed by the model: 1/4 in 1D/3D and plane strain,
   * 1/3 in plane stress.
   */
  struct BondBasedModelParameters
  {
    /** Influence function omega. */
    InfluenceFunction omega = InfluenceFunction::constant;
    /** Young's modulus E (> 0); c is computed from it unless micromodulus > 0. */
    double youngs_modulus = 1.;
    /** c; used as given if > 0. */
    double micromodulus = 0.;
    /** 2D only: plane stress (nu = 1/3) or plane strain (nu = 1/4). */
    bool plane_stress = true;
    /** Linearized bond-based model (2.32) instead of the nonlinear PMB force. */
    bool linearized = false;
    /**
     * Fracture energy G0 (>= 0); s0 is computed from it unless
     * critical_stretch > 0. Both 0: bonds never break.
     */
    double fracture_energy = 0.;
    /** s0; used as given if > 0. */
    double critical_stretch = 0.;

    /** Declare the "Model" entries of the bond-based model. */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate them (the caller has entered "Model"). */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Strain energy density of the classical (CCM) material under the
   * isotropic expansion u = eps x, divided by eps^2: E/2 (1D),
   * 2 K_2D with K_2D = E / (2 (1 - nu)) (plane stress, nu = 1/3) or
   * lambda + mu = E / (2 (1 + nu)(1 - 2 nu)) (plane strain, nu = 1/4), and
   * 9 K / 2 with K = E / (3 (1 - 2 nu)) (3D, nu = 1/4).
   */
  double
  isotropic_expansion_energy(const unsigned int dim,
                             const double       youngs_modulus,
                             const bool         plane_stress = true);

  /**
   * The micromodulus c that makes the PD energy density of an isotropic
   * expansion in the bulk,
   * W_pd = (c eps^2 / 4) int_H omega(|xi|) |xi| dV
   *      = (c eps^2 / 4) |S^{d-1}| int_0^delta omega(r) r^d dr,
   * equal to the CCM value isotropic_expansion_energy(); computed by
   * radial quadrature. Reproduces (2.31), 2E/delta^2 (1D, (3.71)) and
   * 18K/(pi delta^4) (3D).
   */
  double
  bond_based_micromodulus(const unsigned int      dim,
                          const InfluenceFunction omega,
                          const double            delta,
                          const double            youngs_modulus,
                          const bool              plane_stress = true);

  /**
   * The critical stretch s0 for fracture energy G0 and micromodulus c: the
   * energy c omega s0^2 |xi| / 2 of every bond crossing a unit crack area,
   * summed as in Silling-Askari (2005) and (2.35), equals G0:
   *   1D: G0 = (c s0^2 / 2) int_0^delta omega r^2 dr,
   *   2D: G0 = c s0^2 int_0^delta omega r^3 dr,
   *   3D: G0 = (pi c s0^2 / 2) int_0^delta omega r^4 dr
   * (the inner integral over the crack-normal distance z is done in closed
   * form). With the plane-stress c this is (2.35); with the plane-strain
   * c = 48E/(5 pi delta^3) (omega_0) it gives s0 = sqrt(5 pi G0/(12 E delta)),
   * and with 192E/(5 pi delta^3) (omega_1) s0 = sqrt(25 pi G0/(48 E delta)).
   */
  double
  bond_based_critical_stretch(const unsigned int      dim,
                              const InfluenceFunction omega,
                              const double            delta,
                              const double            micromodulus,
                              const double            fracture_energy);

  /**
   * The bond-based PD force density of the standard scheme (3.1),
   * @f[ F_i = \sum_{j \in F_i} \mu_{ij} \, c \, \omega(|\xi|) \, s_{ij}
   *   \frac{\xi + \eta}{|\xi + \eta|} \beta V_j, @f]
   * or with the linearized bond force (2.32) c omega (xi (x) xi / |xi|^3) eta.
   * Each bond stored in a row of the Neighborhood carries an irreversible
   * broken flag mu (2.34); a bond breaks when its stretch exceeds s0. Both
   * end points decide independently from the bitwise same stretch, so the
   * two copies of a bond agree across ranks. Bond coefficients share the
   * Neighborhood's table layout (interior rows use one stencil table).
   */
  template <int dim>
  class BondBasedOperator
  {
  public:
    /** A displacement or force field: one node Vector per component. */
    using VectorField = std::array<Vector, dim>;

    BondBasedOperator(const Discretization<dim>      &discretization,
                      const BondBasedModelParameters &parameters);

    /** The micromodulus c in use. */
    double
    micromodulus() const
    {
      return c;
    }
    /** The critical stretch s0 (infinity if bonds never break). */
    double
    critical_stretch() const
    {
      return s0;
    }
    /** The discretization. */
    const Discretization<dim> &
    discretization() const
    {
      return disc;
    }
    /** True for the linearized bond force (2.32). */
    bool
    is_linearized() const
    {
      return linearized;
    }
    /**
     * c omega(min(|xi|, delta)) beta V_j / |xi| per entry of the
     * Neighborhood bond tables (row i uses the slice starting at
     * table_start[i]); the division by the bond length is the force loop's.
     */
    const std::vector<double> &
    bond_coefficients() const
    {
      return bond_coefficient;
    }

    /** Zero-initialized dim node Vectors. */
    void
    initialize(VectorField &field) const;

    /**
     * force_i = F_i (force per unit volume) for the owned nodes; breaks the
     * bonds whose stretch now exceeds s0 (their force is already zero).
     * @p u must have up-to-date ghost values.
     *
     * In 1D and 2D every bond copy is evaluated in its own row (full list)
     * by default. With the half list (the 3D default, set_half_list()) a bond between two owned nodes is
     * evaluated once, in the row of the end point from which its lattice
     * offset is lexicographically positive, and its force is added to that
     * end and subtracted from the other (Newton's third law; valid because
     * every node has the volume dx^dim, so both copies of a bond have the
     * same stiffness). A bond to a ghost node is then evaluated on each
     * rank from the owned end only, so the result does not depend on the
     * partition beyond round-off. When such a bond breaks, both copies of
     * its broken flag are set.
     */
    void
    compute_forces(const VectorField &u, VectorField &force);

    /**
     * Select the half-list (true) or the full-list loop (every bond copy
     * evaluated in its own row) of the nonlinear force. Both give the same
     * forces and broken bonds up to round-off. The half list does half the
     * bond evaluations but adds each reaction to the neighbour's record. On
     * the benchmark machine (AMD Zen 5, doc/benchmarks.md) it is 0.97-1.04x
     * the full list's rate in 3D m = 3 and 1.3-1.4x in 3D m = 12, but
     * 0.97-1.02x in 2D: the default is the half list in 3D, the full list in
     * 1D and 2D.
     */
    void
    set_half_list(const bool use_half_list)
    {
      half_list = use_half_list;
      sweep     = false;
    }

    /**
     * Select (true, the default) or deselect the lattice sweep of the
     * nonlinear force: when every bond's stiffness and length depend only
     * on its lattice offset (a uniform lattice, every node of volume
     * dx^dim), the owned and ghost nodes are placed in a padded box in
     * lattice order and the force loop runs over one positive stencil
     * offset o at a time along contiguous runs of nodes: p_i and p_{i+o}
     * are contiguous streams (no gathers, no row tails), the reaction goes
     * to node i+o (Newton's third law), and the broken flags are one bit per
     * (offset, box position). Forces equal those of the list loops up to
     * round-off; the same bonds break (bitwise the same stretch
     * arithmetic), and the CSR broken flags (broken(), damage()) are kept
     * up to date. Where the sweep is not available (see
     * lattice_sweep_available()) the list loop chosen by set_half_list() is
     * used. set_half_list() deselects the sweep.
     */
    void
    set_lattice_sweep(const bool use_sweep)
    {
      sweep = use_sweep;
    }

    /**
     * True if compute_forces() can use the lattice sweep: nonlinear force,
     * dim 2 or 3, compiled with AVX-512, lattice indices of all local
     * nodes, per-offset uniform bond stiffness and length, and a box of
     * lattice positions at most 8 times the local node count.
     */
    bool
    lattice_sweep_available() const
    {
      return sweep_available;
    }

    /**
     * Box positions per chunk of the lattice sweep (a multiple of 8, at most
     * max_sweep_chunk): a tuning knob, results do not depend on it.
     */
    void
    set_lattice_sweep_chunk(const unsigned int n);
    /**
     * Stencil offsets evaluated per pass over a chunk (1-4, sharing the
     * loads of p_L and the force accumulator): a tuning knob; the forces
     * change by round-off (summation order), the broken bonds do not.
     */
    void
    set_lattice_sweep_offsets_per_pass(const unsigned int k);
    /**
     * In 3D with four offsets per pass: evaluate the offsets o and o + D
     * (D the smallest of 1, 2 or 4 box rows that is a multiple of 8
     * positions) as pairs, the first from the positions L, the second from
     * L - D, so that both reactions land on L + o and are stored once
     * (default true; sweep_offset_pairs() in lattice_sweep_kernel.h). A
     * tuning knob like set_lattice_sweep_offsets_per_pass(): the forces
     * change by round-off (summation order), the broken bonds do not.
     */
    void
    set_lattice_sweep_pairs(const bool use_pairs);
    /** Offset pairs the sweep evaluates in paired passes (0: none). */
    unsigned int
    n_lattice_sweep_pairs() const
    {
      unsigned int n = 0;
      for (const auto &pass : sweep_pass)
        n += pass[2] ? pass[1] : 0;
      return n;
    }
    /** Largest chunk of set_lattice_sweep_chunk(). */
    static constexpr unsigned int max_sweep_chunk = 2048;
    /** True if the library was compiled with the AVX-512 sweep kernel. */
    static bool
    lattice_sweep_compiled();

    /** True if compute_forces() currently runs the lattice sweep. */
    bool
    uses_lattice_sweep() const
    {
      return sweep && sweep_available;
    }

    /**
     * @name The lattice sweep's box layout, for integrators that keep their
     * state in it (VelocityVerlet::advance(n)). Valid if uses_lattice_sweep().
     */
    /** @{ */
    /**
     * Called per chunk of box positions [first, first + n) once their forces
     * are final: component d of position first + k is f[d * stride + k]
     * (meaningless where no owned node sits).
     */
    using SweepChunkFinish = std::function<
      void(const std::size_t first, const unsigned int n, const double *f, const unsigned int stride)>;

    /** Stride of the per-component box arrays (positions plus padding). */
    std::size_t
    lattice_sweep_stride() const
    {
      return sweep_n_alloc;
    }
    /** Box positions the sweep visits: [0, extent), extent a multiple of 8, <= stride. */
    std::size_t
    lattice_sweep_extent() const
    {
      return 8 * sweep_n_bytes;
    }
    /** Box position of every local (owned and ghost) node. */
    const std::vector<std::uint32_t> &
    lattice_sweep_positions() const
    {
      return sweep_position;
    }
    /**
     * x_c of the deformed positions p = (x - x_c) + u that the force loops
     * use (the lattice centre, the same on every rank).
     */
    Point<dim>
    deformation_origin() const;
    /**
     * The lattice-sweep force for deformed positions @p p (dim arrays of
     * lattice_sweep_stride() doubles, box order, ghosts up to date),
     * handing each chunk's forces to @p finish; breaks bonds like
     * compute_forces(), bitwise the same arithmetic.
     */
    void
    lattice_sweep_forces(const double *p, const SweepChunkFinish &finish);
    /** @} */

    /**
     * W_i = 1/2 sum_j mu 1/2 c omega s^2 |xi| beta V_j (2.26)-(2.27): each
     * bond's energy split between its end points. Owned entries of @p W.
     */
    void
    strain_energy_density(const VectorField &u, Vector &W) const;

    /** sum_i W_i V_i over all ranks. */
    double
    total_strain_energy(const VectorField &u) const;

    /** Damage (2.36) 1 - sum mu beta V / sum beta V of the owned nodes. */
    void
    damage(Vector &phi) const;

    /**
     * Break every bond of the owned rows for which @p cuts(x_i, x_j) is
     * true. The predicate must be symmetric; it is called with the end
     * points ordered by node id so that the two copies of a bond agree.
     */
    void
    break_bonds(const std::function<bool(const Point<dim> &, const Point<dim> &)> &cuts);

    /**
     * 2D: pre-crack along the segment [a, b]: break the bonds whose segment
     * x_i x_j properly intersects it. Throws for dim != 2.
     */
    void
    add_precrack(const Point<dim> &a, const Point<dim> &b);

    /**
     * Pre-crack along a planar polygon (3D, at least 3 vertices in order)
     * or a segment (2D, 2 vertices): break the bonds whose segment x_i x_j
     * crosses the polygon's plane strictly (end points on opposite sides)
     * at a point inside the polygon (crossing-number test in the plane).
     * Throws ParameterError ('Pre-crack') for a degenerate or non-planar
     * polygon or in 1D.
     */
    void
    add_precrack(const std::vector<Point<dim>> &polygon);

    /**
     * Replace the broken flags of the owned rows (one per CSR bond, e.g.
     * restored from a checkpoint). Both copies of a bond must agree.
     */
    void
    set_broken_flags(const std::vector<std::uint8_t> &flags);

    /** Broken flag (1 broken) per CSR bond of the owned rows. */
    const std::vector<std::uint8_t> &
    broken() const
    {
      return broken_flag;
    }

    /** Global number of broken bond copies (each bond counts once per owned row). */
    std::uint64_t
    n_broken_bonds() const;

    /**
     * sum_j ||C(xi)|| beta V_j = sum_j c omega / |xi| beta V_j of the owned
     * row @p i: the stiffness of the linearized model used by (3.8).
     */
    double
    stiffness_row_sum(const unsigned int i) const
    {
      return row_stiffness[i];
    }

    /**
     * The critical time step (3.8) min_i sqrt(2 rho / sum_j ||C(xi)|| beta V_j)
     * over all ranks, for density @p rho.
     */
    double
    critical_time_step(const double rho) const;

  private:
    const Discretization<dim> &disc;
    double                     c, s0;
    bool                       linearized;
    /** c omega(min(|xi|, delta)) beta V_j / |xi| per table entry. */
    std::vector<double> bond_coefficient;
    std::vector<double> row_stiffness;
    std::vector<std::uint8_t> broken_flag;
    /**
     * Scratch of compute_forces(): per local node the deformed position and
     * (half list) the force accumulated so far, as one record.
     */
    std::vector<double> deformed;

    /** Use the half list in compute_forces() (nonlinear branch); see set_half_list(). */
    bool half_list = dim == 3;
    /**
     * Per owned row: bonds with a lexicographically positive lattice offset
     * (the half list) start at row_start[i] + half_offset[i] (the
     * Neighborhood lists a row's bonds in stencil order, negative offsets
     * first).
     */
    std::vector<std::uint32_t> half_offset;
    /**
     * Bonds with a negative offset to a ghost node, which no half row of
     * this rank contains: owned row ghost_row[g] has the CSR bonds
     * ghost_bond[ghost_row_start[g] .. ghost_row_start[g+1]), with their
     * column, stiffness, length and broken flag copied contiguously.
     */
    std::vector<unsigned int>  ghost_row, ghost_row_start;
    std::vector<std::uint64_t> ghost_bond;
    std::vector<std::int32_t>  ghost_col;
    std::vector<double>        ghost_stiffness, ghost_length;
    std::vector<std::uint8_t>  ghost_broken;
    /** Scratch: bonds between owned nodes broken in their half row this call. */
    std::vector<std::uint64_t> newly_broken;

    /** Lattice offset of bond @p b of row @p i as a stencil-box index (negation: n_box - 1 - index). */
    unsigned int
    box_index(const unsigned int i, const std::uint64_t b) const;
    /** CSR index of the copy of bond @p b (row @p i, owned neighbour) in the neighbour's row. */
    std::uint64_t
    mirror_bond(const unsigned int i, const std::uint64_t b) const;
    /** Box positions per chunk of the sweep (set_lattice_sweep_chunk()). */
    unsigned int sweep_chunk = 512;
    /** Offsets per pass of the sweep (set_lattice_sweep_offsets_per_pass()). */
    unsigned int sweep_offsets_per_pass = 2;
    /** Paired passes selected (set_lattice_sweep_pairs()). */
    bool sweep_pairs = true;
    /**
     * The sweep's passes in order: {first entry of sweep_pass_offset, n,
     * paired}; a plain pass evaluates the n offsets sweep_pass_offset[first
     * ...] (sweep_offsets()), a paired one the n pairs (first + q, first +
     * n + q) whose offsets differ by sweep_pair_delta (sweep_offset_pairs()).
     */
    std::vector<std::array<unsigned int, 3>> sweep_pass;
    std::vector<unsigned int>                sweep_pass_offset;
    std::int64_t                             sweep_pair_delta = 0;
    /** Lattice sweep selected (set_lattice_sweep()) and possible. */
    bool sweep = true, sweep_available = false;
    /** The sweep's live bits are in sync with broken_flag. */
    bool sweep_bits_valid = false;
    /** Box of local lattice positions: lower corner and strides (x fastest). */
    std::array<int, dim>          sweep_lower;
    std::array<std::int64_t, dim> sweep_stride;
    /** Box positions and allocated length of the per-position arrays (padded). */
    std::size_t sweep_n_box = 0, sweep_n_alloc = 0, sweep_n_bytes = 0;
    /** Per positive stencil offset h: linear box offset, box index, stiffness, length. */
    std::vector<std::int64_t> sweep_offset;
    std::vector<unsigned int> sweep_box_index;
    /**
     * Per positive offset h: its slot in a regular row (one that lists the
     * whole stencil in order; the negated offset has slot S-1-slot), so that
     * a broken bond finds its CSR copies without a binary search.
     */
    std::vector<unsigned int> sweep_slot;
    std::vector<double>       sweep_k, sweep_r;
    /** Stencil-box index -> positive offset h (or of its negation), -1 for the centre. */
    std::vector<int> sweep_half_of_box;
    /** Box position of each local node, local node of each box position (-1: none). */
    std::vector<std::uint32_t> sweep_position;
    std::vector<std::int32_t>  sweep_node;
    /**
     * Bit (h, L): bond (L, L + offset h) exists in an owned row and is not
     * broken; bit L % 8 of byte sweep_bit_slot[h] + (L / 8) sweep_bit_row
     * (the bytes of one group of eight positions together: a chunk's bits
     * are one sequential stream, and a pass's offsets are adjacent).
     */
    std::vector<std::uint8_t> sweep_live;
    std::vector<unsigned int> sweep_bit_slot;
    std::size_t               sweep_bit_row = 0;
    /**
     * The passes of the sweep (sweep_pass) and the bit slots of the offsets
     * for the current offsets per pass and pairing (invalidates the bits).
     */
    void
    set_sweep_bit_slots();
    /**
     * Deformed positions and reactions per box position, dim arrays of
     * sweep_n_alloc. The reactions start half a page after the positions
     * (and after VelocityVerlet's box positions): the sweep stores
     * reactions at L + o and loads positions at L + o' (see
     * PageOffsetAllocator).
     */
    PageOffsetVector sweep_p{PageOffsetAllocator<double>(0)},
      sweep_reaction{PageOffsetAllocator<double>(2048)};
    /** Scratch: (offset, box position) of the bonds broken in this call. */
    std::vector<std::pair<unsigned int, std::uint32_t>> sweep_broken;
    /** Set up the box, the offsets and sweep_available. */
    void
    setup_lattice_sweep();
    /** Rebuild sweep_live from broken_flag. */
    void
    build_sweep_bits();
    /** The nonlinear force by the lattice sweep. */
    void
    sweep_forces(const VectorField &u, VectorField &force);
    /**
     * CSR index, in owned row @p i, of the bond of positive sweep offset @p h
     * whose lower (@p upper false) or upper end is @p i and whose other end
     * is the local node @p partner: direct in a regular row.
     */
    std::uint64_t
    find_sweep_bond(const unsigned int i,
                    const unsigned int h,
                    const bool         upper,
                    const std::int32_t partner) const;
    /** Build half_offset and the ghost list. */
    void
    setup_half_list();
    /** The nonlinear force by the full list (the deformed records are set). */
    void
    full_list_forces(VectorField &force);
    /** The nonlinear force by the half list (the deformed records are set). */
    void
    half_list_forces(VectorField &force);
    /** Stencil-box half width M (box of (2M+1)^dim lattice offsets). */
    int box_radius = 0;
    /** Box index of the zero offset, ((2M+1)^dim - 1)/2. */
    unsigned int
    centre_index() const
    {
      unsigned int n = 1;
      for (unsigned int d = 0; d < dim; ++d)
        n *= 2 * box_radius + 1;
      return (n - 1) / 2;
    }
  };
} // namespace PeriDEAL

#endif
