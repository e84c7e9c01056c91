#ifndef perideal_models_surface_node_method_h
#define perideal_models_surface_node_method_h

#include <deal.II/lac/full_matrix.h>

#include <perideal/models/diffusion.h>

#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  /**
   * How the fictitious layer of width delta outside each end of the rod is
   * filled (paper 003, Sect. 2.2 and 4.2).
   */
  enum class FictitiousExtrapolation
  {
    /** Linear Taylor about the surface node s with the slope from s and the
     *  nearest interior node b (10): C_f = (1 + c_f) C_s - c_f C_b. */
    linear_taylor,
    /** Antisymmetric about the surface value, C_f = 2 C_s - C_m (m: the
     *  mirror of f; (56) with the errata's sign), as the analytical
     *  solutions of Sect. 4.1 assume. */
    antisymmetric,
    /** Symmetric, C_f = C_m: a zero-flux (symmetry) end; no surface value. */
    symmetric
  };

  /** Parse "linear Taylor", "antisymmetric" or "symmetric" (ParameterError otherwise). */
  FictitiousExtrapolation
  parse_fictitious_extrapolation(const std::string &name, const std::string &parameter);

  /** Local condition carried by a surface node. */
  struct SurfaceCondition
  {
    enum class Type
    {
      /** C(x_s, t) = value(t). */
      dirichlet,
      /** J(x_s, n_s, t) = value(t), the PD flux (11) through the end. */
      flux
    };
    Type                          type  = Type::dirichlet;
    std::function<double(double)> value = [](double) { return 0.; };
  };

  /**
   * Parameters of SurfaceNodeRod. The kernel is mu(xi) = |xi|^-p (p = 2 in
   * 003) with micro-diffusivity d (per bond from a PhaseChangeDiffusivity).
   */
  struct SurfaceNodeRodParameters
  {
    double left = -0.5, right = 0.5;
    /** Grid spacing; the rod holds (right - left)/dx cells (must be an integer). */
    double dx = 0.0125;
    double delta = 0.05;
    /** Kernel exponent p of mu = |xi|^-p. */
    double exponent = 2.;
    PhaseChangeDiffusivity diffusivity = PhaseChangeDiffusivity::single_phase(20.);
    /** The self-transfer term (9) of the node with its own cell. */
    bool self_transfer = true;
    /** Exact partial-cell factor beta (true) or beta = 1 (the proofs' setting). */
    bool partial_volume = true;
    /** Extrapolation at the left and right end. */
    std::array<FictitiousExtrapolation, 2> extrapolation = {
      {FictitiousExtrapolation::linear_taylor, FictitiousExtrapolation::linear_taylor}};
    /** Conditions at the left and right surface node (ignored at symmetric ends). */
    std::array<SurfaceCondition, 2> condition;
  };

  /**
   * 1D PD diffusion discretized by the meshfree method with the surface node
   * method (SNM) of paper 003, Sect. 2.2: cell-centred interior nodes, a
   * surface node at each end carrying a local Dirichlet or flux condition
   * (the flux through the PD flux (2)-(5), discretized as (11)), and a
   * fictitious layer of width delta filled by extrapolation. Bond
   * micro-diffusivities follow the phase rule (6), so the rod also models a
   * moving interface. Forward Euler (12)-(13) with the time-step checked
   * against the Gershgorin bound of the actual iteration matrix (Sect. 3),
   * and classical RK4 for convergence studies that need a negligible time
   * error.
   *
   * The state is the vector of interior values; surface and fictitious
   * values are affine functions of it and of the boundary data, built once
   * (FictitiousMap) and used both by the time stepping and by the matrix
   * analysis.
   */
  class SurfaceNodeRod
  {
  public:
    explicit SurfaceNodeRod(const SurfaceNodeRodParameters &parameters);

    /** Number of interior nodes. */
    unsigned int
    n_nodes() const
    {
      return n;
    }
    /** Number of fictitious nodes per end. */
    unsigned int
    n_fictitious() const
    {
      return n_fict;
    }
    double
    position(const unsigned int i) const
    {
      return prm.left + (i + 0.5) * prm.dx;
    }
    const SurfaceNodeRodParameters &
    parameters() const
    {
      return prm;
    }

    /**
     * Additional source: called with (t, interior values) and adds
     * dC/dt contributions to the third argument (one per interior node).
     */
    using Source =
      std::function<void(double, const std::vector<double> &, std::vector<double> &)>;

    /**
     * dC/dt of every interior node at time @p t: the PD sum (8) with beta,
     * the self-transfer (9), and @p source if given.
     */
    void
    rate(const double               t,
         const std::vector<double> &C,
         std::vector<double>       &dCdt,
         const Source              &source = Source()) const;

    /** Surface values [left, right] implied by @p C and the conditions at @p t. */
    std::array<double, 2>
    surface_values(const double t, const std::vector<double> &C) const;

    /** The PD flux (11) through the left (side 0) or right (side 1) end. */
    double
    surface_flux(const unsigned int side, const double t, const std::vector<double> &C) const;

    /** One forward Euler step (12). */
    void
    forward_euler_step(double &t, const double dt, std::vector<double> &C,
                       const Source &source = Source()) const;

    /** One classical Runge-Kutta step. */
    void
    rk4_step(double &t, const double dt, std::vector<double> &C,
             const Source &source = Source()) const;

    /**
     * The matrix L_eff of the homogeneous problem (zero boundary data, no
     * source), dC/dt = L_eff C, with d the largest micro-diffusivity
     * (Remark 1). The forward Euler iteration matrix (14) is I + dt L_eff.
     */
    FullMatrix<double>
    operator_matrix() const;

    /**
     * Row-wise Gershgorin bound of forward Euler for the configured boundary
     * treatment: every disc of I + dt L_eff lies in [-1, 1] iff
     * dt <= 2 / (|l_pp| + sum_q |l_pq|) for all rows and sum_q |l_pq| <= |l_pp|
     * (condition (32), independent of dt). In the bulk this is (16); in the
     * row of the node next to a linear-Taylor end it is the Theorem's (17)
     * (with the self-transfer: (18) with mu(dx) instead of mu(dx)/2, see
     * the errata).
     */
    struct GershgorinBound
    {
      double       time_step = 0.;
      unsigned int row       = 0;
      /** Condition (32) holds in every row (the discs also stay <= 1). */
      bool upper_half_guaranteed = true;
    };
    GershgorinBound
    gershgorin_bound() const;

    /**
     * Throw ParameterError(@p parameter) unless @p dt satisfies the
     * Gershgorin bound; the message states the bound and the closed form of
     * 003 for the boundary treatment.
     */
    void
    check_time_step(const double dt, const std::string &parameter = "Time step") const;

    /**
     * The critical forward Euler step from the eigenvalues of L_eff (LAPACK):
     * the largest dt with |1 + dt lambda| <= 1 for all eigenvalues lambda.
     */
    double
    eigenvalue_time_step() const;

    /** Spectral radius of I + dt L_eff (LAPACK). */
    double
    spectral_radius(const double dt) const;

    /**
     * Positions of the phase boundaries: the midpoint between adjacent nodes
     * on different sides of C_i (003 Sect. 5.2), in increasing order.
     */
    std::vector<double>
    interface_positions(const std::vector<double> &C) const;

  private:
    /** An affine combination sum_k w_k C_k + w_s C_s of interior values and one surface value. */
    struct Combination
    {
      std::vector<std::pair<unsigned int, double>> interior;
      double                                       surface = 0.;
    };

    /** Fill the extended array [left fictitious | interior | right fictitious]. */
    void
    extend(const double t, const std::vector<double> &C, std::vector<double> &E) const;

    SurfaceNodeRodParameters prm;
    unsigned int             n, n_fict;
    /** Bond offsets 1..n_fict: mu(o dx) beta_o dx. */
    std::vector<double> bond_weight;
    /** mu(dx) dx / 2 of the self-transfer. */
    double self_weight;
    /** Fictitious node j of side s (j = 0 nearest the surface). */
    std::array<std::vector<Combination>, 2> fictitious;
    /** Flux (11) of side s as sum over crossing bonds: (interior index, fictitious j, weight). */
    std::array<std::vector<std::tuple<unsigned int, unsigned int, double>>, 2> crossing;
  };

  /**
   * The error history of a SurfaceNodeRod run against a reference solution:
   * e(t) = sqrt(sum_p (C_p - C_ref(x_p, t))^2 / N) / scale, the quantity
   * inside (55) of 003, sampled every step up to @p dense_until and every
   * @p sample_interval after.
   */
  struct RodErrorHistory
  {
    std::vector<double> time, error;
    /** (55): max of e(t) over t0 <= t (<= the end of the run). */
    double
    max_after(const double t0) const;
  };

  /**
   * March @p rod from C(x, 0) = @p initial(x) to @p t_end with forward Euler
   * or classical RK4 and record the error against @p exact(x, t).
   */
  RodErrorHistory
  run_against_reference(const SurfaceNodeRod                        &rod,
                        const std::function<double(double)>         &initial,
                        const std::function<double(double, double)> &exact,
                        const double                                 dt,
                        const double                                 t_end,
                        const bool                                   rk4,
                        const double                                 scale           = 1.,
                        const double                                 dense_until     = 1e-3,
                        const double                                 sample_interval = 1e-4);

  /**
   * Interface tracking for a manufactured two-phase problem: the rod starts
   * from exact(x, 0), receives source(x, t, x_i) with x_i the outermost
   * numerical interface (midpoint between the adjacent nodes on both sides
   * of C_i, 003 Sect. 5.2), and is marched by forward Euler to @p t_end.
   */
  struct InterfaceTrack
  {
    std::vector<double> time, numerical, exact;
    double              max_interface_error = 0., max_concentration_error = 0.;
    /** Largest outward step of the numerical interface (0: monotone inward). */
    double max_outward_step = 0.;
    /** Time of the largest concentration error. */
    double time_of_max_error = 0.;
    /** Position of the largest concentration error. */
    double position_of_max_error = 0.;
  };

  InterfaceTrack
  track_interface(const SurfaceNodeRod                                &rod,
                  const std::function<double(double, double)>         &exact,
                  const std::function<double(double)>                 &exact_interface,
                  const std::function<double(double, double, double)> &source,
                  const double                                         dt,
                  const double                                         t_end,
                  const unsigned int                                   record_every = 100);

  /**
   * Closed forms of the stability bounds of 003, Sect. 3, on a lattice with
   * bond lengths m dx, m = 1..m_bar, kernel mu, beta = 1:
   * bulk (45) = (16): 1 / (2 d sum mu(m dx) dx);
   * boundary (47) = (17): 1 / (d sum mu(m dx)(m + 1) dx);
   * boundary with self-transfer (48) = (18): 1 / (d [sum mu(m dx)(m + 1) + mu(dx)/2] dx).
   */
  namespace StabilityBounds
  {
    double
    bulk(const double d, const std::function<double(double)> &mu, const double dx,
         const unsigned int m_bar);
    double
    linear_taylor(const double d, const std::function<double(double)> &mu, const double dx,
                  const unsigned int m_bar);
    double
    linear_taylor_self_transfer(const double d, const std::function<double(double)> &mu,
                                const double dx, const unsigned int m_bar);
  } // namespace StabilityBounds
} // namespace PeriDEAL

#endif
