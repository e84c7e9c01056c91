#ifndef perideal_models_scalar_wave_h
#define perideal_models_scalar_wave_h

#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>

#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>
#include <perideal/models/diffusion.h>

#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * Parameters of the PD scalar wave equation (2.40)
   * @f[ u_{tt} = L u - 2 d u_t + b, \quad
   *     (L u)(x) = \int_{H_x} c_s \omega(|\xi|) |\xi|^{-p} (u(x+\xi) - u(x)) dV. @f]
   */
  struct ScalarWaveParameters
  {
    /** Influence function omega. */
    InfluenceFunction omega = InfluenceFunction::constant;
    /** Exponent p of |xi| in the kernel denominator. */
    double exponent = 2.;
    /** Local wave speed chi (> 0); c_s is computed from chi^2 by quadrature. */
    double wave_speed = 1.;
    /**
     * Micro-modulus c_s; if > 0 it is used as given instead of the value
     * calibrated from chi (4.47), (4.51), (4.90).
     */
    double micro_constant = 0.;
    /** Damping coefficient d >= 0 of (2.40). */
    double damping = 0.;
    /** Time step; must not exceed critical_time_step() (else ParameterError). */
    double time_step = 0.;
    /**
     * "standard": the standard scheme (3.3); "wls": the meshfree WLS
     * collocation quadrature (Sect. 3.2) on every interior node (the
     * DiffusionOperator's WLS rows with the kernel c_s omega/r^p).
     */
    std::string quadrature = "standard";
    /** Order and collocation nodes of the WLS quadrature. */
    WlsParameters wls;

    /**
     * Declare "Influence function", "Kernel exponent", "Wave speed",
     * "Micro-modulus", "Damping", "Time step", "Quadrature" and the
     * subsection "WLS" (the caller has entered its subsection).
     */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate them. */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Explicit solver of the PD scalar wave equation (2.40) on the standard
   * meshfree discretization, with the damped velocity-Verlet scheme (3.9) /
   * (4.62):
   * @f[ a^n = L u^n + b - 2 d v^n, \quad
   *     u^{n+1} = u^n + \Delta t v^n + \tfrac{\Delta t^2}{2} a^n, @f]
   * @f[ v^{n+1} = \frac{v^n + \tfrac{\Delta t}{2} a^n
   *                     + \tfrac{\Delta t}{2} (L u^{n+1} + b)}{1 + \Delta t d}. @f]
   * L is the DiffusionOperator with kernel c_s omega(r)/r^p (the same
   * discrete operator as PD diffusion). Nodes of the volume constraint
   * layer (region == constrained) carry Dirichlet values g(x, t) from a
   * Function (or zero); their velocity is not integrated (kept at zero).
   */
  template <int dim>
  class ScalarWaveSolver
  {
  public:
    /**
     * Build the operator on @p discretization (which must outlive this
     * object) and check the time step against critical_time_step(): a time
     * step <= 0 or above it throws ParameterError naming 'Time step'.
     * u, v, b start at zero.
     */
    ScalarWaveSolver(const Discretization<dim> &discretization,
                     const ScalarWaveParameters &parameters);

    /** Displacement u (with ghosts), velocity v and acceleration a. */
    Vector displacement, velocity, acceleration;
    /** Body force b per node (owned entries, constant in time). */
    Vector body_force;

    /**
     * Dirichlet values g(x, t) on the constraint layer (time via
     * Function::set_time). nullptr (the default) means zero.
     */
    void
    set_boundary_values(const std::shared_ptr<Function<dim>> &g);

    /** u = u0(x) and v = v0(x) (zero if nullptr) at all owned nodes. */
    void
    set_initial_values(const Function<dim> &u0, const Function<dim> *v0 = nullptr);

    /**
     * Impose the boundary values at the current time, refresh ghosts and
     * compute a^0 (call after setting initial conditions and b).
     */
    void
    initialize();

    /** One damped velocity-Verlet step. */
    void
    advance();

    /**
     * Critical step of the undamped scheme 2 / sqrt(lambda_max), with the
     * Gershgorin bound lambda_max <= 2 max_i sum_j k(|xi_ij|) beta V_j
     * over the interior rows (MPI maximum).
     */
    double
    critical_time_step() const;

    /** The micro-modulus c_s in use. */
    double
    micro_constant() const
    {
      return op.kernel().constant;
    }

    /** The discrete operator L. */
    const DiffusionOperator<dim> &
    wave_operator() const
    {
      return op;
    }

    /** 1/2 sum_{i interior} v_i^2 V_i (all ranks). */
    double
    kinetic_energy() const;
    /**
     * 1/4 sum_{i interior} sum_j k(|xi_ij|) (u_j - u_i)^2 beta V_j V_i
     * (all ranks). Needs up-to-date ghosts of u (true after initialize()
     * and advance()). With the WLS quadrature (no bonds) the quadratic form
     * -1/2 sum_{i interior} u_i (L u)_i V_i of the discrete operator, which
     * velocity Verlet conserves up to O(dt^2) oscillations when M L is
     * symmetric (every interior row with the same collocation stencil, i.e.
     * a uniform lattice with a volume-constraint layer of width delta).
     */
    double
    potential_energy() const;
    /** kinetic_energy() + potential_energy(). */
    double
    energy() const
    {
      return kinetic_energy() + potential_energy();
    }

    double
    time() const
    {
      return t;
    }
    unsigned int
    step() const
    {
      return n_steps;
    }
    double
    time_step() const
    {
      return dt;
    }

  private:
    void
    apply_boundary_values(const double time);

    const Discretization<dim>    &disc;
    DiffusionOperator<dim>        op;
    double                        d, dt, t = 0.;
    unsigned int                  n_steps = 0;
    std::shared_ptr<Function<dim>> boundary;
    Vector                        Lu;
    /** k(min(r, delta)) beta V per Neighborhood table entry. */
    std::vector<double> bond_kernel_weight;
  };
} // namespace PeriDEAL

#endif
