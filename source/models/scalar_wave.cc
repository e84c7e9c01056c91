#include <perideal/base/exceptions.h>
#include <perideal/models/scalar_wave.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace PeriDEAL
{
  namespace
  {
    template <int dim>
    DiffusionModelParameters
    operator_parameters(const Discretization<dim> &disc, const ScalarWaveParameters &p)
    {
      check_parameter(p.exponent < dim + 2., "Model/Kernel exponent", p.exponent,
                      "a value < n_d + 2 (finite second moment of the kernel)");
      check_parameter(p.micro_constant >= 0., "Model/Micro-modulus", p.micro_constant,
                      "a non-negative number (0: calibrate from the wave speed)");
      if (p.micro_constant == 0.)
        check_parameter(p.wave_speed > 0., "Model/Wave speed", p.wave_speed,
                        "a positive number");
      check_parameter(p.damping >= 0., "Model/Damping", p.damping, "a non-negative number");

      DiffusionModelParameters dp;
      dp.type     = "diffusion";
      dp.omega    = p.omega;
      dp.exponent = p.exponent;
      if (p.micro_constant > 0.)
        dp.micro_diffusivity = p.micro_constant;
      else
        {
          // c_s by quadrature of the kernel: L -> chi^2 Laplacian.
          ScalarKernel k;
          k.dim                = dim;
          k.omega              = p.omega;
          k.exponent           = p.exponent;
          k.delta              = disc.parameters().delta;
          dp.micro_diffusivity = k.micro_constant_for(p.wave_speed * p.wave_speed);
        }
      return dp;
    }
  } // namespace

  void
  ScalarWaveParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Influence function", "constant", Patterns::Selection("constant|linear"),
                      "omega_0 = 1 (2.12) or omega_1 = 1 - r/delta (2.13).");
    prm.declare_entry("Kernel exponent", "2", Patterns::Double(),
                      "p of |xi|^-p in (2.40) (< n_d + 2).");
    prm.declare_entry("Wave speed", "1", Patterns::Double(), "chi (> 0).");
    prm.declare_entry("Micro-modulus", "0", Patterns::Double(),
                      "c_s (>= 0); 0: calibrated from the wave speed.");
    prm.declare_entry("Damping", "0", Patterns::Double(), "d (>= 0) of (2.40).");
    prm.declare_entry("Time step", "0", Patterns::Double(),
                      "dt (> 0, at most the critical step of the undamped scheme).");
    prm.declare_entry("Quadrature", "standard", Patterns::Selection("standard|wls"),
                      "standard scheme (3.3) or the WLS collocation quadrature (Sect. 3.2) "
                      "on every interior node.");
    prm.enter_subsection("WLS");
    WlsParameters::declare_parameters(prm);
    prm.leave_subsection();
  }

  void
  ScalarWaveParameters::parse_parameters(ParameterHandler &prm)
  {
    omega          = parse_influence_function(prm.get("Influence function"), "Influence function");
    exponent       = prm.get_double("Kernel exponent");
    wave_speed     = prm.get_double("Wave speed");
    micro_constant = prm.get_double("Micro-modulus");
    damping        = prm.get_double("Damping");
    time_step      = prm.get_double("Time step");
    quadrature     = prm.get("Quadrature");
    prm.enter_subsection("WLS");
    wls.parse_parameters(prm);
    prm.leave_subsection();
  }

  template <int dim>
  ScalarWaveSolver<dim>::ScalarWaveSolver(const Discretization<dim>  &discretization,
                                          const ScalarWaveParameters &p)
    : disc(discretization)
    , op(discretization, operator_parameters(discretization, p))
    , d(p.damping)
    , dt(p.time_step)
  {
    const auto &nb = disc.neighborhood;
    bond_kernel_weight.resize(nb.bond_length.size());
    const ScalarKernel &k = op.kernel();
    for (std::size_t e = 0; e < bond_kernel_weight.size(); ++e)
      bond_kernel_weight[e] = k(std::min(nb.bond_length[e], k.delta)) * nb.bond_weight[e];

    check_parameter(p.quadrature == "standard" || p.quadrature == "wls", "Quadrature",
                    p.quadrature, "standard|wls");
    if (p.quadrature == "wls")
      {
        std::vector<unsigned int> rows;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (disc.region[i] == Discretization<dim>::interior)
            rows.push_back(i);
        op.set_wls_rows(p.wls, rows);
      }

    const double dt_crit = critical_time_step();
    check_parameter(dt > 0. && dt <= dt_crit, "Time stepping/Time step", dt,
                    "a positive number not above the critical time step 2/sqrt(lambda_max) = " +
                      std::to_string(dt_crit) + " of the undamped scheme");

    for (Vector *v : {&displacement, &velocity, &acceleration, &body_force, &Lu})
      disc.initialize_vector(*v);
  }

  template <int dim>
  double
  ScalarWaveSolver<dim>::critical_time_step() const
  {
    // DiffusionOperator::critical_time_step() = 1 / max_i sum_j k beta V_j
    // over the interior rows; lambda_max <= 2 max_i sum_j (Gershgorin).
    const double inv_row_sum = op.critical_time_step();
    if (!std::isfinite(inv_row_sum))
      return std::numeric_limits<double>::infinity();
    return 2. / std::sqrt(2. / inv_row_sum);
  }

  template <int dim>
  void
  ScalarWaveSolver<dim>::set_boundary_values(const std::shared_ptr<Function<dim>> &g)
  {
    boundary = g;
  }

  template <int dim>
  void
  ScalarWaveSolver<dim>::set_initial_values(const Function<dim> &u0, const Function<dim> *v0)
  {
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        displacement.local_element(i) = u0.value(disc.position[i]);
        velocity.local_element(i)     = v0 != nullptr ? v0->value(disc.position[i]) : 0.;
      }
  }

  template <int dim>
  void
  ScalarWaveSolver<dim>::apply_boundary_values(const double time)
  {
    if (boundary)
      boundary->set_time(time);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] != Discretization<dim>::interior)
        {
          displacement.local_element(i) = boundary ? boundary->value(disc.position[i]) : 0.;
          velocity.local_element(i)     = 0.;
        }
  }

  template <int dim>
  void
  ScalarWaveSolver<dim>::initialize()
  {
    apply_boundary_values(t);
    displacement.update_ghost_values();
    op.apply(displacement, Lu);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      acceleration.local_element(i) =
        disc.region[i] == Discretization<dim>::interior ?
          Lu.local_element(i) + body_force.local_element(i) -
            2. * d * velocity.local_element(i) :
          0.;
  }

  template <int dim>
  void
  ScalarWaveSolver<dim>::advance()
  {
    const unsigned int n    = disc.n_owned();
    double *const      u    = displacement.begin();
    double *const      v    = velocity.begin();
    double *const      a    = acceleration.begin();
    const double      *b    = body_force.begin();
    const auto        &reg  = disc.region;
    const double       half = 0.5 * dt;

    // u^{n+1} = u^n + dt v^n + dt^2/2 a^n; v* = v^n + dt/2 a^n.
    for (unsigned int i = 0; i < n; ++i)
      if (reg[i] == Discretization<dim>::interior)
        {
          u[i] += dt * (v[i] + half * a[i]);
          v[i] += half * a[i];
        }
    t += dt;
    ++n_steps;
    apply_boundary_values(t);
    displacement.update_ghost_values();
    op.apply(displacement, Lu);

    // v^{n+1} = (v* + dt/2 (L u^{n+1} + b)) / (1 + dt d);
    // a^{n+1} = L u^{n+1} + b - 2 d v^{n+1}.
    const double  scale = 1. / (1. + dt * d);
    const double *lu    = Lu.begin();
    for (unsigned int i = 0; i < n; ++i)
      if (reg[i] == Discretization<dim>::interior)
        {
          const double f = lu[i] + b[i];
          v[i]           = scale * (v[i] + half * f);
          a[i]           = f - 2. * d * v[i];
        }
  }

  template <int dim>
  double
  ScalarWaveSolver<dim>::kinetic_energy() const
  {
    double e = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::interior)
        e += 0.5 * velocity.local_element(i) * velocity.local_element(i) * disc.volume[i];
    return Utilities::MPI::sum(e, disc.get_mpi_communicator());
  }

  template <int dim>
  double
  ScalarWaveSolver<dim>::potential_energy() const
  {
    const auto   &nb = disc.neighborhood;
    const double *u  = displacement.begin();
    double        e  = 0.;
    if (op.wls_quadrature() != nullptr)
      {
        // -1/2 u . M L u: L u of the current u (ghosts of u up to date).
        Vector lu;
        disc.initialize_vector(lu);
        op.apply(displacement, lu);
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (disc.region[i] == Discretization<dim>::interior)
            e -= 0.5 * u[i] * lu.local_element(i) * disc.volume[i];
        return Utilities::MPI::sum(e, disc.get_mpi_communicator());
      }
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (disc.region[i] != Discretization<dim>::interior)
          continue;
        const double *w   = bond_kernel_weight.data() + nb.table_start[i];
        double        row = 0.;
        for (std::uint64_t k = nb.row_start[i]; k < nb.row_start[i + 1]; ++k)
          {
            const double du = u[nb.col[k]] - u[i];
            row += w[k - nb.row_start[i]] * du * du;
          }
        e += 0.25 * row * disc.volume[i];
      }
    return Utilities::MPI::sum(e, disc.get_mpi_communicator());
  }

  template class ScalarWaveSolver<1>;
  template class ScalarWaveSolver<2>;
  template class ScalarWaveSolver<3>;
} // namespace PeriDEAL
