#ifndef perideal_models_lps_h
#define perideal_models_lps_h

#include <deal.II/base/parameter_handler.h>

#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/wls_quadrature.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of the linearized linear peridynamic solid (LPS, dissertation
   * Sect. 2.1, (2.10)-(2.19)): the influence function and the 3D bulk and
   * shear moduli K and G. In 2D the model is the plane-strain LPS (see
   * LinearizedLPSOperator).
   */
  struct LPSModelParameters
  {
    /** Influence function omega. */
    InfluenceFunction omega = InfluenceFunction::constant;
    /** Bulk modulus K (> 0). */
    double bulk_modulus = 1.;
    /** Shear modulus G (> 0). */
    double shear_modulus = 1.;
    /**
     * Critical stretch s0 of the bond-breaking criterion (2.34) applied to
     * the linearized stretch xi . eta / |xi|^2; 0: bonds never break.
     */
    double critical_stretch = 0.;
    /**
     * Fracture energy G0 (>= 0); s0 is computed from it by
     * lps_critical_stretch() unless critical_stretch > 0.
     */
    double fracture_energy = 0.;

    /** Declare the "Model" entries of the LPS model. */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate them (the caller has entered "Model"). */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Critical stretch s0 of the LPS bond-breaking criterion for the fracture
   * energy @p G0 (dim 2: plane strain, 3). Bond energies as in Silling and
   * Askari (2005) and Madenci and Oterkus (2014, Peridynamic Theory and
   * Its Applications): the work to break
   * the bonds crossing a unit crack area, each bond loaded to s0, with the
   * pair energy w(xi) = c_eq omega(|xi|) s^2 |xi| / 2 of the bond-based
   * material that has the same energy density d^2 K_d s^2 / 2 as the LPS
   * under the isotropic expansion u = s x (all bonds at stretch s):
   *   c_eq = 2 d^2 K_d / (|S^{d-1}| int_0^delta omega r^d dr),
   * then bond_based_critical_stretch(). For omega = 1:
   *   3D: s0 = sqrt(5 G0 / (9 K delta))  (Madenci-Oterkus' LPS value
   *        sqrt(G0 / ((3 G + (3/4)^4 (K - 5G/3)) delta)) at nu = 1/4),
   *   2D: s0 = sqrt(pi G0 / (3 K_2 delta)), K_2 = K + G/3 = lambda + mu.
   */
  double
  lps_critical_stretch(const unsigned int      dim,
                       const InfluenceFunction omega,
                       const double            delta,
                       const double            dimensional_bulk_modulus,
                       const double            fracture_energy);

  /**
   * The linearized state-based LPS model on the standard meshfree scheme.
   * With d = dim, the bond xi = x_j - x_i, the quadrature weight beta V_j of
   * the Neighborhood table and omega = omega(min(|xi|, delta)):
   *
   * - weighted volume (2.15), computed per node from the discrete sum so
   *   that the dilatation of a homogeneous deformation is exact for every
   *   node with a full family:
   *   @f[ m_i = \sum_j \omega |\xi|^2 \beta V_j @f]
   * - linearized dilatation (2.19) with the linearized extension
   *   e_ij = xi . (u_j - u_i) / |xi|:
   *   @f[ \theta_i = \frac{d}{m_i} \sum_j \omega |\xi| e_{ij} \beta V_j @f]
   * - strain energy density (2.14), with alpha_i = d (d+2) G / m_i:
   *   @f[ W_i = \frac{K_d}{2} \theta_i^2 + \frac{\alpha_i}{2} \sum_j \omega
   *      (e_{ij} - \theta_i |\xi| / d)^2 \beta V_j @f]
   * - force density T_i<xi> - T_j<-xi> (2.18) with the scalar force state
   *   t_ij = omega ((d K_d - (d+2) G) theta_i |xi| / m_i + alpha_i e_ij)
   *   along xi/|xi|:
   *   @f[ f_i = \sum_j \omega \Big[ (d K_d - (d+2) G)
   *       \big(\tfrac{\theta_i}{m_i} + \tfrac{\theta_j}{m_j}\big) \xi
   *     + d (d+2) G \big(\tfrac{1}{m_i} + \tfrac{1}{m_j}\big)
   *       \frac{\xi \otimes \xi}{|\xi|^2} (u_j - u_i) \Big] \beta V_j @f]
   *   (t is dW/de; the theta-derivative of the deviatoric part vanishes
   *   because sum_j omega |xi| (e - theta |xi|/d) beta V_j = 0 exactly with
   *   the discrete m_i).
   *
   * 3D (d = 3, K_3 = K): the factors are 3/m, 3K - 5G and 15G/m of (2.18)-(2.19).
   * 2D is the plane-strain LPS: d = 2 and K_2 = K + G/3 = lambda + mu, the
   * 2D bulk modulus of plane strain, so that the 2D factors are 2/m,
   * 2K - 10G/3 and 8G/m and the energy of a homogeneous in-plane strain H
   * is K_2 tr(H)^2/2 + G |H - tr(H) I/2|^2 = the plane-strain CCM energy
   * K tr(H)^2/2 + G |dev_3D H|^2. These constants follow from the angular
   * averages <n_a n_b> = delta_ab / d and <(n.D n)^2> = 2|D|^2/(d(d+2)) of a
   * traceless D. Under m-refinement the force converges to the Navier
   * operator (K + G/3) grad div u + G Laplace u in both cases. 1D is not
   * provided.
   *
   * Bond breaking: with a critical stretch s0 > 0, compute_forces() first
   * breaks (irreversibly, one flag per CSR bond as in BondBasedOperator) every
   * bond whose linearized stretch xi . eta / |xi|^2 exceeds s0; broken bonds
   * are left out of theta and of the force. The weighted volume m_i keeps
   * its undamaged value (the convention of Peridigm's LPS), so a node that
   * lost bonds still has a consistent scale. Both copies of a bond see the
   * bitwise same stretch and break together, on any rank layout.
   *
   * theta_j of ghost neighbours is needed: compute_forces() computes theta
   * on the owned nodes and updates its ghosts before the force pass; m_j of
   * the ghosts is exchanged once in the constructor.
   */
  template <int dim>
  class LinearizedLPSOperator
  {
    static_assert(dim == 2 || dim == 3, "LinearizedLPSOperator: 2D (plane strain) or 3D");

  public:
    /** A displacement or force field: one node Vector per component. */
    using VectorField = std::array<Vector, dim>;

    LinearizedLPSOperator(const Discretization<dim> &discretization,
                          const LPSModelParameters  &parameters);

    /** The discretization. */
    const Discretization<dim> &
    discretization() const
    {
      return disc;
    }

    /** K_d: K in 3D, K + G/3 in 2D (plane strain). */
    double
    dimensional_bulk_modulus() const
    {
      return K_d;
    }

    /** Shear modulus G. */
    double
    shear_modulus() const
    {
      return G;
    }

    /** The discrete weighted volume m_i (owned and ghost entries valid). */
    const Vector &
    weighted_volume() const
    {
      return m;
    }

    /**
     * omega(min(|xi|, delta)) beta V_j per entry of the Neighborhood bond
     * tables (row i uses the slice starting at table_start[i]).
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
     * theta_i (2.19) of the owned nodes; @p u must have up-to-date ghost
     * values. Ghost entries of @p theta are not updated.
     */
    void
    compute_dilatation(const VectorField &u, Vector &theta) const;

    /**
     * force_i = f_i (force per unit volume) of the owned nodes. @p u must have
     * up-to-date ghost values. Computes theta (kept, see dilatation()) and
     * exchanges its ghost values (collective).
     */
    void
    compute_forces(const VectorField &u, VectorField &force);

    /** The critical stretch (infinity if bonds never break). */
    double
    critical_stretch() const
    {
      return s0;
    }

    /** Broken flag (1 broken) per CSR bond of the owned rows. */
    const std::vector<std::uint8_t> &
    broken() const
    {
      return broken_flag;
    }

    /**
     * Replace the broken flags of the owned rows (pre-cracks, checkpoints);
     * both copies of a bond must agree.
     */
    void
    set_broken_flags(const std::vector<std::uint8_t> &flags);

    /**
     * Critical time step 2 sqrt(rho / B) of velocity Verlet, with B >= the
     * largest Gershgorin row sum sum_c |K_rc| of the linearized stiffness
     * (an upper bound of lambda_max(K)), computed matrix-free from the
     * triangle inequality: deviatoric part 2 sum_j w_ij a_dev (1/m_i + 1/m_j)
     * |n_a| |n|_1, dilatational part |a_vol| (|sum_j w_ij xi_a| Q_i +
     * sum_j w_ij |xi_a| Q_j) with Q_k = d/m_k^2 sum_l w_kl 2 |xi_kl|_1 the
     * l1 norm of the gradient of theta_k / m_k (w = omega beta V). Intact
     * bonds (the undamaged operator bounds every damaged one). Collective.
     */
    double
    critical_time_step(const double rho) const;

    /** Global number of broken bond copies (each bond counts once per owned row). */
    std::uint64_t
    n_broken_bonds() const;

    /** Damage (2.36) 1 - sum mu beta V / sum beta V of the owned nodes. */
    void
    damage(Vector &phi) const;

    /** theta of the last compute_forces() (owned and ghost entries). */
    const Vector &
    dilatation() const
    {
      return theta;
    }

    /** W_i (2.14) of the owned nodes; @p u must have up-to-date ghost values. */
    void
    strain_energy_density(const VectorField &u, Vector &W) const;

    /** sum_i W_i V_i over all ranks. */
    double
    total_strain_energy(const VectorField &u) const;

    /**
     * Meshfree WLS collocation quadrature of the linearized LPS model
     * (dissertation Sect. 3.2, (3.32)-(3.51), with the errata of the
     * catalog: the 3/m-bar of (3.36) kept, L_I in the first term of (3.51)).
     * The owned interior nodes @p rows compute their force from one WLS fit
     * per node with the continuum weighted volume m-bar (2.15) of the full
     * ball:
     *   f_i = L_I Q_i Theta_i + L_J Q-bar_i U-bar_i,
     * L_I = ((d K_d - (d+2) G)/m-bar) int omega xi p(xi) dV and
     * L_J = (2 d (d+2) G/m-bar) int omega (xi (x) xi)/|xi|^2 (p(xi) - p(0)) dV
     * (in 3D (3.45) and (3.50): (3K - 5G)/3 and 6G times the selection
     * patterns). Theta_i holds the dilatations of the collocation nodes,
     * theta_j = L_theta Q-bar_j U-bar_j with L_theta = (d/m-bar) int omega
     * xi^T (p(xi) - p(0)) dV ((3.35)-(3.39)), computed by WLS on every owned
     * node whose family holds at least n_c nodes (also the
     * volume-constraint layer, with one-sided fits, so that an interior
     * node's Theta_i is exact for polynomial fields), by the standard sum
     * (2.19) on the others. WLS-k is then exact for polynomial displacements
     * of degree <= k: the force equals the continuum LPS operator, for
     * quadratics the Navier operator (K_d + (d-2) G/d) grad div u + G Laplace u. strain_energy_density()
     * of a WLS row integrates (2.14) on the fitted polynomial in closed form
     * (lps_deviatoric_moment_matrix()), so a homogeneous deformation gives
     * the CCM energy density exactly. Needs critical stretch 0 (no bond
     * breaking: a WLS row has no bonds); the other rows keep the standard
     * scheme (the fixed hybrid configuration of Sect. 3.3). Collective.
     */
    void
    set_wls_rows(const WlsParameters &parameters, const std::vector<unsigned int> &rows);

    /** The WLS quadrature (dilatation, L_I, L_J, fit coefficients), or nullptr. */
    const WlsQuadrature<dim> *
    wls_quadrature() const
    {
      return wls.get();
    }

    /** True if owned node @p i computes its force by WLS. */
    bool
    is_wls_force_row(const unsigned int i) const
    {
      return !wls_force.empty() && wls_force[i];
    }

  private:
    /** Break the owned-row bonds whose linearized stretch exceeds s0. */
    void
    break_bonds(const VectorField &u);

    const Discretization<dim> &disc;
    double                     K_d, G;
    InfluenceFunction          omega_in_use;
    double                     s0;
    /** omega(min(|xi|, delta)) beta V_j per table entry. */
    std::vector<double> bond_coefficient;
    Vector              m;
    Vector              theta;
    std::vector<std::uint8_t> broken_flag;
    /** WLS: the quadrature, its row per owned node (-1: standard theta) and the force rows. */
    std::unique_ptr<WlsQuadrature<dim>> wls;
    std::vector<int>                    wls_row;
    std::vector<unsigned char>          wls_force;
    /** lps_deviatoric_moment_matrix() and alpha = d (d+2) G / m-bar. */
    std::vector<double> wls_dev_moment;
    double              wls_alpha = 0.;

    /** l1 norm of d theta_i / d u of the owned nodes (critical_time_step()). */
    void
    dilatation_sensitivity(Vector &S) const;
  };
} // namespace PeriDEAL

#endif
