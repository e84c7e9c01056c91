#ifndef perideal_models_diffusion_h
#define perideal_models_diffusion_h

#include <deal.II/base/parameter_handler.h>

#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/solid_neighbor_count.h>

#include <algorithm>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of the scalar PD transport models: linear PD diffusion
   * (2.41)-(2.42) and the bi-material corrosion model (2.48)-(2.49) with the
   * phase rule (2.79).
   */
  struct DiffusionModelParameters
  {
    /** "diffusion" or "corrosion". */
    std::string type = "diffusion";
    /** Influence function omega. */
    InfluenceFunction omega = InfluenceFunction::constant;
    /**
     * Exponent of |xi| in the kernel denominator: q for J_q of (2.42), or
     * n_d + 2q for the corrosion convention of (2.49) (set by the parser from
     * 'Kernel convention').
     */
    double exponent = 2.;
    /** Local diffusivity D; used to compute kappa when 'Micro-diffusivity' is 0. */
    double diffusivity = 1.;
    /** kappa; if > 0 it is used as given (the sources often state kappa). */
    double micro_diffusivity = 0.;
    /** Corrosion: kappa of liquid-liquid, solid-liquid and solid-solid bonds. */
    double kappa_liquid = 1., kappa_interface = 0.1, kappa_solid = 0.;
    /** Corrosion: saturation concentration C_sat of (2.79). */
    double saturation = 0.85;
    /**
     * Corrosion: false (default) for the one-way rule (2.79) (solid turns
     * liquid below C_sat, never back); true for the phase-change model of
     * paper 003, eq. (6): a node is solid ("above C_i") whenever C >= C_sat
     * at the end of a step, so the interface can move both ways. The bond
     * table (liquid-liquid, interface, solid-solid) is the same; only a node
     * exactly at C_sat differs ((6) makes all its bonds mixed).
     */
    bool reversible_phase = false;

    static void
    declare_parameters(ParameterHandler &prm);
    /** The caller has entered "Model". */
    void
    parse_parameters(ParameterHandler &prm, const unsigned int dim);
  };

  /**
   * Bond micro-diffusivity of a two-phase body whose phase follows the
   * current concentration (paper 003, eq. 6): @p low if both end points are
   * below the phase-change concentration C_i, @p high if both are above,
   * @p mixed otherwise (one end at or across C_i). Unlike the corrosion model
   * (2.79), where a node's phase is stored and changes one way only, the
   * phase here is a function of C and may change back. With the corrosion
   * model's names: low = liquid-liquid, high = solid-solid, mixed =
   * interface.
   */
  struct PhaseChangeDiffusivity
  {
    double low = 1., high = 1., mixed = 1.;
    /** C_i; +infinity: a single phase with diffusivity @p low. */
    double threshold = std::numeric_limits<double>::infinity();

    double
    operator()(const double c_x, const double c_xp) const
    {
      if (c_x < threshold && c_xp < threshold)
        return low;
      if (c_x > threshold && c_xp > threshold)
        return high;
      return mixed;
    }

    /** The largest of the three (Remark 1 of 003: it bounds the time step). */
    double
    max() const
    {
      return std::max(low, std::max(high, mixed));
    }

    /** One phase with micro-diffusivity @p d. */
    static PhaseChangeDiffusivity
    single_phase(const double d)
    {
      PhaseChangeDiffusivity p;
      p.low = p.high = p.mixed = d;
      return p;
    }
  };

  /**
   * The corrosion phase rule on the first @p n_owned entries: one-way (2.79),
   * solid (1) to liquid (0) once C < C_sat, or with
   * DiffusionModelParameters::reversible_phase the rule (6) of 003 (solid
   * whenever C >= C_sat). Returns true if a node changed on this rank; the
   * caller updates the ghosts.
   */
  bool
  update_corrosion_phase(const DiffusionModelParameters &parameters,
                         const Vector                   &C,
                         Vector                         &phase,
                         const unsigned int              n_owned);

  /**
   * The standard-scheme PD transport operator (3.4)
   * @f[ (L C)_i = \sum_{j \in F_i} \kappa_{ij} \, \omega(|\xi|) |\xi|^{-p}
   *      \beta(\xi) V_j \, (C_j - C_i), @f]
   * with kappa_ij constant (diffusion) or chosen by the phases of the bond's
   * end points (corrosion: liquid-liquid, interface, solid-solid). Kernel
   * weights share the Neighborhood's table layout, so interior rows use
   * one stencil table.
   */
  template <int dim>
  class DiffusionOperator
  {
  public:
    /** Build the kernel weights for @p discretization. */
    DiffusionOperator(const Discretization<dim>      &discretization,
                      const DiffusionModelParameters &parameters);

    /** The kernel (with kappa as its constant for linear diffusion). */
    const ScalarKernel &
    kernel() const
    {
      return scalar_kernel;
    }

    /** True for the bi-material corrosion model. */
    bool
    is_corrosion() const
    {
      return corrosion;
    }

    /**
     * rate_i = (L C)_i for the owned nodes. @p C must have up-to-date ghost
     * values. For corrosion, @p phase (1 solid, 0 liquid, ghosts up to date)
     * selects kappa per bond; it is ignored for linear diffusion.
     */
    void
    apply(const Vector &C, Vector &rate, const Vector *phase = nullptr) const;

    /** Which rows apply() computes. */
    enum class Rows
    {
      /** Every owned row, also those of the volume-constraint layer. */
      all,
      /**
       * Only the owned interior rows; the entries of @p rate at the
       * volume-constraint layer are left untouched. For time steppers that
       * overwrite the layer with prescribed values (DiffusionSolver): in 3D
       * the layer can hold more nodes than the body (doc/design.md).
       */
      interior
    };

    /** apply() restricted to @p rows; bitwise the same values on those rows. */
    void
    apply(const Vector &C, Vector &rate, const Vector *phase, const Rows rows) const;

    /**
     * Linear diffusion without WLS rows: rate_i = (L C)_i only for the owned
     * rows i in the half-open ranges @p rows, bitwise the values of apply();
     * the other entries of @p rate are untouched. For time steppers whose
     * other rows are overwritten (the EBF absorbing layer of
     * Abc::PdUnboundedWave), so that their sums are not computed at all.
     */
    void
    apply(const Vector &C, Vector &rate, const std::vector<std::array<unsigned int, 2>> &rows) const;

    /**
     * Largest forward Euler step the Gershgorin theorem proves stable for
     * this boundary treatment: min_i 2 / (|l_ii| + R_i) over the rows of the
     * unknowns, R_i the sum of the couplings to other unknowns (nodes of the
     * volume-constraint layer are prescribed and carry no error). In the bulk
     * this is 1 / sum_j kappa w_ij, (16) of 003 with beta and the actual bond
     * coefficients. For corrosion the largest of the three kappas is used,
     * which bounds every phase configuration (Remark 1 of 003).
     */
    double
    critical_time_step() const;

    /**
     * Assemble the backward Euler matrix A = M/dt - L restricted to the
     * interior rows (constrained rows are identity; couplings to constrained
     * nodes are left out and must go to the right hand side through
     * constrained_coupling()). Symmetric for equal node volumes.
     */
    void
    assemble_backward_euler(const double                   dt,
                            TrilinosWrappers::SparseMatrix &matrix,
                            const Vector                   *phase = nullptr) const;

    /**
     * rhs_i += sum over constrained neighbours j of kappa_ij w_ij C_j, for the
     * interior rows (the couplings assemble_backward_euler() left out).
     */
    void
    add_constrained_coupling(const Vector &C, Vector &rhs, const Vector *phase = nullptr) const;

    /**
     * Hybrid configuration (dissertation Sect. 3.3, "hybrid fixed"): the
     * owned interior nodes @p rows (Omega_w) use the meshfree WLS collocation
     * weights (WlsQuadrature, built here for the kernel with its kappa); all
     * other rows keep the standard scheme (Omega_s). apply() and
     * critical_time_step() then use the WLS row for these nodes (forward
     * Euler only). Corrosion: a WLS row is used with the kappa of its node's
     * phase while all its collocation nodes share that phase, and falls back
     * to the standard row once the interface reaches them (Omega_s should
     * cover the interface's path, as in E4 of the dissertation).
     */
    void
    set_wls_rows(const WlsParameters &parameters, const std::vector<unsigned int> &rows);

    /** The WLS quadrature of Omega_w, or nullptr for the pure standard scheme. */
    const WlsQuadrature<dim> *
    wls_quadrature() const
    {
      return wls.get();
    }

    /**
     * True if every row is weakly diagonally dominant over the unknowns
     * (l_ii <= 0 and R_i <= |l_ii|), i.e. if the Gershgorin discs of the
     * forward Euler matrix lie in the unit disc for dt <= critical_time_step()
     * and the bound is a proof. Always true for the standard scheme; WLS rows
     * have negative off-diagonal weights and may violate it, and then
     * critical_time_step() is only the bound 2/rho with rho the Gershgorin
     * bound of the spectral radius (collective over the communicator).
     */
    bool
    gershgorin_proves_stability() const;

    /**
     * Corrosion: classify the rows by the phases of their neighbours
     * (default true). A row whose neighbours all have one phase has one
     * micro-diffusivity on every bond and is summed without looking up the
     * neighbours' phases (the same value up to round-off, four summation chains;
     * exactly 0 without summing if
     * that kappa is 0, e.g. the solid interior); a WLS row whose family is
     * of one phase skips the per-step check of its collocation nodes. The
     * per-row counts of solid neighbours are updated incrementally when
     * phases flip. false: the per-bond kernel on every row (reference).
     */
    void
    set_phase_classification(const bool on)
    {
      classify = on;
    }

    /** The bond coefficient kappa for end-point phases (0 liquid, 1 solid). */
    double
    bond_kappa(const bool solid_i, const bool solid_j) const
    {
      return kappa_table[2 * solid_i + solid_j];
    }

  private:
    const Discretization<dim> &disc;
    ScalarKernel               scalar_kernel;
    bool                       corrosion;
    std::array<double, 4>      kappa_table;
    /** omega(r) r^-p beta V per table entry of the Neighborhood. */
    std::vector<double> geometric_weight;
    /** Row sums of geometric_weight. */
    std::vector<double> row_sum;
    /** Hybrid: WLS rows (Omega_w) and a per-owned-node flag; empty if none. */
    std::unique_ptr<WlsQuadrature<dim>> wls;
    std::vector<unsigned char>          is_wls;
    /** Owned interior rows that use the standard scheme (Rows::interior). */
    std::vector<unsigned int> interior_standard_rows;
    /** Corrosion: solid neighbours per owned row (set_phase_classification()). */
    bool                       classify = true;
    mutable SolidNeighborCount solid_count;

    /** |l_ii| + R_i and l_ii <= 0 && R_i <= |l_ii| of WLS row k. */
    std::pair<double, bool>
    wls_gershgorin(const unsigned int k) const;
  };
} // namespace PeriDEAL

#endif
