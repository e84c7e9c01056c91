#ifndef perideal_models_nnpp_h
#define perideal_models_nnpp_h

#include <deal.II/base/parameter_handler.h>

#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>

#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of the nonlocal Nernst-Planck-Poisson (NNPP) system
   * (dissertation Sect. 2.3.4, (2.63)-(2.64)) and of its semi-implicit time
   * stepping (Sect. 3.1.2). Declared in and read from the subsection "NNPP".
   *
   * Kernels use the convention of (2.49)/(2.63): omega / |xi|^(n_d + 2 q),
   * one exponent q1 (diffusion), q2 (electromigration), q3 (Poisson), each
   * q < 1 so that the second moment of the kernel exists.
   */
  struct NnppParameters
  {
    /** Valences z_k; their number is the number of species N. */
    std::vector<double> valence;
    /**
     * Diffusivities D_k of liquid-liquid, solid-liquid (interface) and
     * solid-solid bonds, one triple per species: the phase rule (2.78).
     */
    std::vector<std::array<double, 3>> diffusivity;
    /** Conductivity sigma of liquid-liquid, interface and solid-solid bonds. */
    std::array<double, 3> conductivity{{1., 1., 1.}};
    /** Influence function omega (the same for the three kernels). */
    InfluenceFunction omega = InfluenceFunction::constant;
    /** Kernel exponents q1 (diffusion), q2 (migration), q3 (Poisson). */
    double q1 = 0., q2 = 0., q3 = 0.;
    /** Faraday constant F [C/mol], gas constant R [J/(mol K)], temperature T [K]. */
    double faraday = 96485.33212, gas_constant = 8.314462618, temperature = 298.15;
    /**
     * "continuous": K1, K2, K3 from the second moment of the continuous
     * kernel, (2.69)-(2.75) (the dissertation's choice). "discrete": from the
     * lattice sum of the interior stencil (with the volume factors), so that
     * the discrete operator is exact for quadratic fields at any m and the
     * standard scheme converges at fixed m as delta -> 0.
     */
    std::string calibration = "continuous";
    /**
     * "local limit" (default): K2 = 1 / M2, which the Taylor expansion and
     * the numerical local-limit test support (= K1/2 at q1 = q2, (2.75)).
     * "thesis (2.77)": K2 = 2 / M2 as printed in (2.77) (= K1); kept only to
     * demonstrate that it converges to twice the local electromigration.
     */
    std::string k2_convention = "local limit";
    /**
     * "closed": bonds to the volume-constraint layer carry no species flux
     * (a closed body; mass is conserved). "dirichlet": layer nodes hold the
     * prescribed concentrations (NnppSources::boundary_concentration).
     * The potential always has the Dirichlet layer (NnppSources::boundary_potential,
     * default 0), which makes the Poisson matrix non-singular.
     */
    std::string species_boundary = "closed";
    /**
     * Corrosion phase rule (2.79) coupled to (2.78): index of the species
     * whose concentration decides the phase (the metal), or -1 (default:
     * the phase field stays as the user set it). After each step a solid
     * node whose C_phase_species fell below @p saturation becomes liquid
     * (one way), and the Poisson matrix is reassembled.
     */
    int phase_species = -1;
    /** C_sat of (2.79). */
    double saturation = 0.85;
    /** Time step (> 0). */
    double time_step = 1e-3;
    /** Modified Newton: at most this many iterations per species and step. */
    unsigned int max_newton_iterations = 30;
    /** Modified Newton stops once ||F|| <= tol * ||C^n / dt||. */
    double newton_tolerance = 1e-12;
    /** Relative tolerance of each linear solve (CG for phi, GMRES for C_k). */
    double linear_tolerance = 1e-12;

    /** Number of species N. */
    unsigned int
    n_species() const
    {
      return valence.size();
    }

    /** Declare the subsection "NNPP" and its entries. */
    static void
    declare_parameters(ParameterHandler &prm);
    /**
     * Enter "NNPP", read and validate (ParameterError naming the entry for
     * no species, list length mismatches, negative diffusivities,
     * non-positive conductivities or constants, q >= 1, dt <= 0).
     */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Second moment M = int_H omega(|xi|) xi_1^2 / |xi|^(n_d + 2q) dV of an
   * NNPP kernel, by the quadrature of ScalarKernel::second_moment().
   */
  double
  nnpp_second_moment(const unsigned int      dim,
                     const InfluenceFunction omega,
                     const double            q,
                     const double            delta);

  /**
   * The diffusion constant K1 = 2 / M of (2.69): the operator K1 D
   * int omega (C' - C) / |xi|^(n_d+2q) dV then tends to D Laplace C. With
   * omega_0 the closed forms are 2 (1-q) / delta^(2-2q) (1D),
   * 4 (1-q) / (pi delta^(2-2q)) (2D) and 3 (1-q) / (pi delta^(2-2q)) (3D,
   * (2.72)); see nnpp_k1_closed_form(). The same constant calibrates the
   * Poisson kernel (K3, with q3).
   */
  double
  nnpp_k1(const unsigned int dim, const InfluenceFunction omega, const double q, const double delta);

  /** The omega_0 closed forms of nnpp_k1() (tests only); throws for omega_1. */
  double
  nnpp_k1_closed_form(const unsigned int dim, const double q, const double delta);

  /**
   * User-supplied terms of the NNPP system. Every callback may be empty
   * (then the term is zero). Positions are the node positions, t the time
   * at which the term is evaluated (t^{n+1} for the implicit species
   * equations, t^n for the Poisson equation).
   */
  template <int dim>
  struct NnppSources
  {
    /**
     * R_k(x, t, C) of (2.63); @p c holds the concentrations of all species at
     * the node: species k at the current Newton iterate, the species solved
     * before k in this step at t^{n+1}, the others at t^n (semi-implicit:
     * cross-species terms explicit).
     */
    std::function<double(unsigned int k, const Point<dim> &x, double t, const std::vector<double> &c)>
      reaction;
    /** dR_k/dC_k for the frozen Jacobian (may be empty: then omitted). */
    std::function<double(unsigned int k, const Point<dim> &x, double t, const std::vector<double> &c)>
      reaction_derivative;
    /** An extra source S_phi added to F sum_k z_k C_k in (2.64) (manufactured solutions). */
    std::function<double(const Point<dim> &x, double t)> poisson_source;
    /** Prescribed C_k on the layer ("Species boundary = dirichlet"). */
    std::function<double(unsigned int k, const Point<dim> &x, double t)> boundary_concentration;
    /** Prescribed phi on the layer (default 0). */
    std::function<double(const Point<dim> &x, double t)> boundary_potential;
  };

  /**
   * The discrete NNPP operators on the standard meshfree scheme (3.11),
   * (3.18): for species k and an owned interior node i
   * @f[ (L_k C)_i = \sum_{j} \Big[ K_1 \omega D_{k,ij}
   *     \frac{C_j - C_i}{|\xi|^{n_d+2q_1}} + K_2 \omega D_{k,ij}
   *     \frac{z_k F}{RT} \frac{\phi_j - \phi_i}{|\xi|^{n_d+2q_2}} (C_j + C_i)
   *     \Big] \beta V_j , @f]
   * and the nonlocal Poisson operator
   * @f[ (P\phi)_i = -\sum_j K_3 \omega \sigma_{ij} \frac{\phi_j -
   *     \phi_i}{|\xi|^{n_d+2q_3}} \beta V_j . @f]
   * The bond coefficients D_{k,ij} and sigma_ij follow the phases of the end
   * points (2.78) (phase field: 1 solid, 0 liquid; nullptr: all liquid). The
   * quadrature weight is the library's beta V_j (Neighborhood::bond_weight);
   * (3.11) prints no beta, which is the special case without partial volumes.
   * The bond terms are antisymmetric in (i, j) for equal volumes, so the
   * closed operator conserves each species' mass exactly.
   */
  template <int dim>
  class NnppOperator
  {
  public:
    NnppOperator(const Discretization<dim> &discretization, const NnppParameters &parameters);

    /** The constants in use (after calibration). */
    double
    k1() const
    {
      return K[0];
    }
    double
    k2() const
    {
      return K[1];
    }
    double
    k3() const
    {
      return K[2];
    }

    /** Which terms apply_species() evaluates. */
    enum class Terms
    {
      all,
      diffusion,
      migration
    };

    /**
     * rate_i = (L_k C)_i on the owned interior rows (layer rows: 0). @p C,
     * @p phi (and @p phase) need up-to-date ghosts.
     */
    void
    apply_species(const unsigned int k,
                  const Vector      &C,
                  const Vector      &phi,
                  Vector            &rate,
                  const Vector      *phase = nullptr,
                  const Terms        terms = Terms::all) const;

    /** out_i = (P phi)_i on the owned interior rows (layer rows: 0). */
    void
    apply_poisson(const Vector &phi, Vector &out, const Vector *phase = nullptr) const;

    /**
     * The Poisson matrix K_phi of (3.19)-(3.21) on the interior rows
     * (identity on layer rows; couplings to layer nodes go to the right hand
     * side by add_poisson_layer_coupling()). SPD for equal volumes.
     */
    void
    assemble_poisson(TrilinosWrappers::SparseMatrix &matrix, const Vector *phase = nullptr) const;

    /** rhs_i += sum over layer neighbours j of K3 omega sigma w_ij phi_j. */
    void
    add_poisson_layer_coupling(const Vector &phi, Vector &rhs, const Vector *phase = nullptr) const;

    /**
     * The frozen Jacobian (3.14)-(3.15) of species k with the corrected
     * off-diagonal sign: K_ii = 1/dt + sum_j (a_ij - b_ij) - dR/dC_i,
     * K_ij = -(a_ij + b_ij) with a_ij = K1 omega D w, b_ij = K2 omega D
     * (z F/RT)(phi_j - phi_i) w; layer rows identity, layer columns left out.
     * @p dR (may be nullptr) holds dR_k/dC_k per owned node.
     */
    void
    assemble_species_jacobian(const unsigned int              k,
                              const Vector                   &phi,
                              const double                    dt,
                              TrilinosWrappers::SparseMatrix &matrix,
                              const Vector                   *phase = nullptr,
                              const Vector                   *dR    = nullptr) const;

    /** The parameters. */
    const NnppParameters &
    parameters() const
    {
      return prm;
    }

  private:
    const Discretization<dim> &disc;
    NnppParameters             prm;
    /** K1, K2, K3 */
    std::array<double, 3> K;
    /** omega(r) r^-(n_d+2q_a) beta V per table entry, a = 1, 2, 3. */
    std::array<std::vector<double>, 3> weight;

    /** Bond type 0 liquid, 1 interface, 2 solid. */
    unsigned int
    bond_type(const Vector *phase, const unsigned int i, const unsigned int j) const
    {
      if (phase == nullptr)
        return 0;
      return (phase->local_element(i) > 0.5) + (phase->local_element(j) > 0.5);
    }
    /** True if bond (i, j) carries species flux. */
    bool
    species_bond(const unsigned int j) const
    {
      return closed == false || disc.region[j] == Discretization<dim>::interior;
    }
    bool closed;
    /** Diagonal + interior neighbours of interior rows; built once. */
    TrilinosWrappers::SparsityPattern sparsity;

    /** Gives @p matrix the pattern unless it has it (every assembly overwrites all entries). */
    void
    reinit_matrix(TrilinosWrappers::SparseMatrix &matrix) const;
  };

  /**
   * Semi-implicit time stepping of the NNPP system (Sect. 3.1.2): per step
   * (i) the nonlocal Poisson equation (3.18) for phi from the concentrations
   * C^n (CG + AMG; the Dirichlet layer makes it non-singular), then (ii) each
   * species in turn by backward Euler (3.11) with phi explicit, solved by the
   * modified Newton scheme (3.16)-(3.17): Jacobian assembled once per step
   * and species, lambda = 1, GMRES + AMG for the updates.
   */
  template <int dim>
  class NnppSolver
  {
  public:
    /** @p discretization must outlive the solver. */
    NnppSolver(const Discretization<dim> &discretization,
               const NnppParameters      &parameters,
               const NnppSources<dim>    &sources = NnppSources<dim>());

    /** Concentrations C_k (ghosts kept up to date by the solver). */
    std::vector<Vector> C;
    /** Potential phi. */
    Vector phi;
    /** Phase per node (1 solid, 0 liquid), all liquid by default. */
    Vector phase;

    /** Set C_k = f(x) on every node (and the layer by the boundary callback). */
    void
    set_concentration(const unsigned int k, const std::function<double(const Point<dim> &)> &f);

    /** Call after changing @p phase: the Poisson matrix is reassembled. */
    void
    phase_changed()
    {
      poisson_valid = false;
    }

    /** Solve (3.18) for phi at the current time from the current C. */
    void
    solve_potential();

    /** One semi-implicit step: solve_potential(), then each species. */
    void
    step();

    /** Current time. */
    double
    time() const
    {
      return current_time;
    }
    void
    set_time(const double t)
    {
      current_time = t;
    }

    /** Total mass sum_i V_i C_{k,i} over the interior nodes (collective). */
    double
    mass(const unsigned int k) const;

    /** Number of nodes that turned liquid in the last step (all ranks). */
    unsigned int last_phase_changes = 0;

    /** Newton iterations of the last step (summed over species), CG/GMRES iterations. */
    unsigned int last_newton_iterations = 0, last_linear_iterations = 0;

    const NnppOperator<dim> &
    nnpp_operator() const
    {
      return op;
    }

  private:
    const Discretization<dim>            &disc;
    NnppParameters                        prm;
    NnppSources<dim>                      sources;
    NnppOperator<dim>                     op;
    double                                current_time = 0.;
    bool                                  poisson_valid = false;
    TrilinosWrappers::SparseMatrix        poisson_matrix;
    TrilinosWrappers::PreconditionAMG     poisson_amg;
    /** The frozen species Jacobian, refilled per step and species. */
    TrilinosWrappers::SparseMatrix        jacobian;

    void
    set_layer(const unsigned int k, Vector &c, const double t) const;
  };
} // namespace PeriDEAL

#endif
