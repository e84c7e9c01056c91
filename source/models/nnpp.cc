#include <deal.II/base/utilities.h>

#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/models/nnpp.h>

#include <cmath>
#include <numeric>
#include <sstream>

namespace PeriDEAL
{
  namespace
  {
    std::vector<double>
    double_list(const std::string &text)
    {
      std::vector<double> v;
      for (const auto &s : Utilities::split_string_list(text, ','))
        if (!s.empty())
          v.push_back(Utilities::string_to_double(s));
      return v;
    }
  } // namespace

  void
  NnppParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("NNPP");
    prm.declare_entry("Valences", "", Patterns::List(Patterns::Double(), 0),
                      "Valences z_k of the species, one per species (their number is "
                      "the number of species N >= 1).");
    prm.declare_entry("Diffusivities", "", Patterns::List(Patterns::Double(), 0),
                      "D_k of liquid-liquid bonds, one per species (>= 0).");
    prm.declare_entry("Interface diffusivities", "", Patterns::List(Patterns::Double(), 0),
                      "D_k of solid-liquid bonds (phase rule (2.78)), one per species; "
                      "empty: the liquid values.");
    prm.declare_entry("Solid diffusivities", "", Patterns::List(Patterns::Double(), 0),
                      "D_k of solid-solid bonds, one per species; empty: the liquid "
                      "values.");
    prm.declare_entry("Conductivities", "1", Patterns::List(Patterns::Double(), 1, 3),
                      "sigma of the nonlocal Poisson equation (2.64): one value, or "
                      "liquid, interface, solid (> 0 each).");
    prm.declare_entry("Influence function", "constant", Patterns::Selection("constant|linear"),
                      "omega_0 = 1 (2.12) or omega_1 = 1 - r/delta (2.13).");
    prm.declare_entry("Diffusion exponent q1", "0", Patterns::Double(),
                      "q1 < 1: the diffusion kernel is omega / |xi|^(n_d + 2 q1).");
    prm.declare_entry("Migration exponent q2", "0", Patterns::Double(),
                      "q2 < 1: the electromigration kernel exponent.");
    prm.declare_entry("Poisson exponent q3", "0", Patterns::Double(),
                      "q3 < 1: the nonlocal Poisson kernel exponent.");
    prm.declare_entry("Faraday constant", "96485.33212", Patterns::Double(), "F > 0 [C/mol].");
    prm.declare_entry("Gas constant", "8.314462618", Patterns::Double(), "R > 0 [J/(mol K)].");
    prm.declare_entry("Temperature", "298.15", Patterns::Double(), "T > 0 [K].");
    prm.declare_entry("Calibration", "continuous", Patterns::Selection("continuous|discrete"),
                      "K1, K2, K3 from the continuous kernel moments (2.69)-(2.75) or "
                      "from the lattice sum of the interior stencil (exact for "
                      "quadratic fields; converges at fixed m).");
    prm.declare_entry("K2 convention", "local limit",
                      Patterns::Selection("local limit|thesis (2.77)"),
                      "local limit: K2 = 1/M (= K1/2 at q1 = q2), verified "
                      "numerically (doc/design.md, Session 19). thesis (2.77): "
                      "K2 = K1 as printed, which converges to twice the local "
                      "electromigration term.");
    prm.declare_entry("Species boundary", "closed", Patterns::Selection("closed|dirichlet"),
                      "closed: no species flux through bonds to the volume-constraint "
                      "layer. dirichlet: the layer holds prescribed concentrations.");
    prm.declare_entry("Phase species", "-1", Patterns::Integer(-1),
                      "Index (from 0) of the species whose concentration decides the "
                      "phase by (2.79) (solid turns liquid once it falls below "
                      "'Saturation concentration', never back); -1: the phase field "
                      "is not updated.");
    prm.declare_entry("Saturation concentration", "0.85", Patterns::Double(),
                      "C_sat of (2.79).");
    prm.declare_entry("Time step", "1e-3", Patterns::Double(), "dt > 0.");
    prm.declare_entry("Max Newton iterations", "30", Patterns::Integer(1),
                      "Modified Newton (3.16)-(3.17) iterations per species and step.");
    prm.declare_entry("Newton tolerance", "1e-12", Patterns::Double(),
                      "Stop when ||F|| <= tol ||C^n/dt|| (> 0).");
    prm.declare_entry("Linear solver tolerance", "1e-12", Patterns::Double(),
                      "Relative tolerance of CG (phi) and GMRES (C_k) (> 0).");
    prm.leave_subsection();
  }

  void
  NnppParameters::parse_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("NNPP");
    valence                 = double_list(prm.get("Valences"));
    const auto d_liquid     = double_list(prm.get("Diffusivities"));
    auto       d_interface  = double_list(prm.get("Interface diffusivities"));
    auto       d_solid      = double_list(prm.get("Solid diffusivities"));
    const auto sigma        = double_list(prm.get("Conductivities"));
    omega                   = parse_influence_function(prm.get("Influence function"),
                                         "NNPP/Influence function");
    q1                      = prm.get_double("Diffusion exponent q1");
    q2                      = prm.get_double("Migration exponent q2");
    q3                      = prm.get_double("Poisson exponent q3");
    faraday                 = prm.get_double("Faraday constant");
    gas_constant            = prm.get_double("Gas constant");
    temperature             = prm.get_double("Temperature");
    calibration             = prm.get("Calibration");
    k2_convention           = prm.get("K2 convention");
    species_boundary        = prm.get("Species boundary");
    phase_species           = prm.get_integer("Phase species");
    saturation              = prm.get_double("Saturation concentration");
    time_step               = prm.get_double("Time step");
    max_newton_iterations   = prm.get_integer("Max Newton iterations");
    newton_tolerance        = prm.get_double("Newton tolerance");
    linear_tolerance        = prm.get_double("Linear solver tolerance");
    prm.leave_subsection();

    check_parameter(!valence.empty(), "NNPP/Valences", "(empty)", "a list of at least one valence");
    const auto n    = valence.size();
    const auto list = [n](const std::vector<double> &v) {
      std::ostringstream s;
      s << v.size() << " entries";
      return s.str() + " (there are " + std::to_string(n) + " valences)";
    };
    check_parameter(d_liquid.size() == n, "NNPP/Diffusivities", list(d_liquid),
                    "one diffusivity per species");
    if (d_interface.empty())
      d_interface = d_liquid;
    if (d_solid.empty())
      d_solid = d_liquid;
    check_parameter(d_interface.size() == n, "NNPP/Interface diffusivities", list(d_interface),
                    "one diffusivity per species, or empty");
    check_parameter(d_solid.size() == n, "NNPP/Solid diffusivities", list(d_solid),
                    "one diffusivity per species, or empty");
    diffusivity.resize(n);
    for (unsigned int k = 0; k < n; ++k)
      {
        diffusivity[k] = {{d_liquid[k], d_interface[k], d_solid[k]}};
        const char *names[3] = {"NNPP/Diffusivities", "NNPP/Interface diffusivities",
                                "NNPP/Solid diffusivities"};
        for (unsigned int t = 0; t < 3; ++t)
          check_parameter(diffusivity[k][t] >= 0., names[t], diffusivity[k][t],
                          "non-negative diffusivities");
      }
    if (sigma.size() == 1)
      conductivity = {{sigma[0], sigma[0], sigma[0]}};
    else
      {
        check_parameter(sigma.size() == 3, "NNPP/Conductivities", sigma.size(),
                        "one value or three (liquid, interface, solid)");
        conductivity = {{sigma[0], sigma[1], sigma[2]}};
      }
    for (const double s : conductivity)
      check_parameter(s > 0., "NNPP/Conductivities", s, "positive conductivities");
    // The second moment int r^(1-2q) dr exists only for q < 1 ((2.72) needs q1 < 1).
    check_parameter(q1 < 1., "NNPP/Diffusion exponent q1", q1, "q1 < 1");
    check_parameter(q2 < 1., "NNPP/Migration exponent q2", q2, "q2 < 1");
    check_parameter(q3 < 1., "NNPP/Poisson exponent q3", q3, "q3 < 1");
    check_parameter(faraday > 0., "NNPP/Faraday constant", faraday, "a positive number");
    check_parameter(gas_constant > 0., "NNPP/Gas constant", gas_constant, "a positive number");
    check_parameter(temperature > 0., "NNPP/Temperature", temperature, "a positive number");
    check_parameter(phase_species < int(n), "NNPP/Phase species", phase_species,
                    "-1 or a species index below the number of valences (" + std::to_string(n) +
                      ")");
    check_parameter(time_step > 0., "NNPP/Time step", time_step, "a positive time step");
    check_parameter(newton_tolerance > 0., "NNPP/Newton tolerance", newton_tolerance,
                    "a positive number");
    check_parameter(linear_tolerance > 0. && linear_tolerance < 1.,
                    "NNPP/Linear solver tolerance", linear_tolerance, "a number in (0, 1)");
  }

  double
  nnpp_second_moment(const unsigned int      dim,
                     const InfluenceFunction omega,
                     const double            q,
                     const double            delta)
  {
    ScalarKernel k;
    k.dim      = dim;
    k.omega    = omega;
    k.exponent = dim + 2. * q;
    k.delta    = delta;
    return k.second_moment();
  }

  double
  nnpp_k1(const unsigned int dim, const InfluenceFunction omega, const double q, const double delta)
  {
    return 2. / nnpp_second_moment(dim, omega, q, delta);
  }

  double
  nnpp_k1_closed_form(const unsigned int dim, const double q, const double delta)
  {
    // M = A_d delta^(2-2q) / (2-2q), A_d = int_{S^{d-1}} n_1^2 = 2, pi, 4 pi/3.
    const double s = std::pow(delta, 2. - 2. * q);
    switch (dim)
      {
        case 1:
          return 2. * (1. - q) / s;
        case 2:
          return 4. * (1. - q) / (numbers::PI * s);
        case 3:
          return 3. * (1. - q) / (numbers::PI * s);
      }
    AssertThrow(false, ExcMessage("dim must be 1, 2 or 3"));
    return 0.;
  }

  template <int dim>
  NnppOperator<dim>::NnppOperator(const Discretization<dim> &discretization,
                                  const NnppParameters      &parameters)
    : disc(discretization)
    , prm(parameters)
    , closed(parameters.species_boundary == "closed")
  {
    const double                delta = disc.parameters().delta;
    const auto                 &nb    = disc.neighborhood;
    const std::array<double, 3> q{{prm.q1, prm.q2, prm.q3}};
    for (unsigned int a = 0; a < 3; ++a)
      {
        const double p = dim + 2. * q[a];
        weight[a].resize(nb.bond_length.size());
        for (std::size_t s = 0; s < nb.bond_length.size(); ++s)
          {
            const double r = nb.bond_length[s];
            // As in DiffusionOperator: the kernel is evaluated at
            // min(r, delta), so bonds of the partial-volume shell beyond
            // delta keep the kernel's value at the horizon, weighted by beta.
            const double rr = std::min(r, delta);
            weight[a][s]    = influence(prm.omega, rr, delta) * std::pow(rr, -p) * nb.bond_weight[s];
          }
        double M = nnpp_second_moment(dim, prm.omega, q[a], delta);
        if (prm.calibration == "discrete")
          {
            // Lattice sum over the interior stencil (the first table slice):
            // sum w xi_1^2 = sum w |xi|^2 / dim by the cubic symmetry.
            double m = 0.;
            for (unsigned int s = 0; s < nb.stencil_size; ++s)
              m += weight[a][s] * nb.bond_length[s] * nb.bond_length[s] / dim;
            AssertThrow(m > 0., ExcMessage("Discrete calibration needs the interior stencil."));
            M = m;
          }
        // K1 = 2/M and K3 = 2/M: K (M/2) Laplace = Laplace. K2 = 1/M: the
        // Taylor expansion of (phi'-phi)(C'+C) gives M div(C grad phi).
        K[a] = 2. / M;
        if (a == 1 && prm.k2_convention == "local limit")
          K[a] = 1. / M;
      }

    // One pattern for the Poisson matrix and every species Jacobian: the
    // bonds and regions do not change during a run.
    const auto &part = *disc.partitioner();
    sparsity.reinit(part.locally_owned_range(), part.locally_owned_range(),
                    disc.get_mpi_communicator(), nb.stencil_size + 1);
    std::vector<types::global_dof_index> cols;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        cols.assign(1, part.local_to_global(i));
        if (disc.region[i] == Discretization<dim>::interior)
          for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
            if (disc.region[nb.col[b]] == Discretization<dim>::interior)
              cols.push_back(part.local_to_global(nb.col[b]));
        sparsity.add_entries(part.local_to_global(i), cols.begin(), cols.end());
      }
    sparsity.compress();
  }

  template <int dim>
  void
  NnppOperator<dim>::apply_species(const unsigned int k,
                                   const Vector      &C,
                                   const Vector      &phi,
                                   Vector            &rate,
                                   const Vector      *phase,
                                   const Terms        terms) const
  {
    const auto        &nb  = disc.neighborhood;
    const double       zf  = prm.valence[k] * prm.faraday / (prm.gas_constant * prm.temperature);
    const double       a1  = terms == Terms::migration ? 0. : K[0];
    const double       a2  = terms == Terms::diffusion ? 0. : K[1] * zf;
    const double      *c   = C.begin();
    const double      *f   = phi.begin();
    const auto        &D   = prm.diffusivity[k];
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double sum = 0.;
        if (disc.region[i] == Discretization<dim>::interior)
          {
            const double *w1 = weight[0].data() + nb.table_start[i];
            const double *w2 = weight[1].data() + nb.table_start[i];
            for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
              {
                const unsigned int j = nb.col[b];
                if (!species_bond(j))
                  continue;
                const unsigned int s = b - nb.row_start[i];
                sum += D[bond_type(phase, i, j)] *
                       (a1 * w1[s] * (c[j] - c[i]) + a2 * w2[s] * (f[j] - f[i]) * (c[j] + c[i]));
              }
          }
        rate.local_element(i) = sum;
      }
  }

  template <int dim>
  void
  NnppOperator<dim>::apply_poisson(const Vector &phi, Vector &out, const Vector *phase) const
  {
    const auto   &nb = disc.neighborhood;
    const double *f  = phi.begin();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double sum = 0.;
        if (disc.region[i] == Discretization<dim>::interior)
          {
            const double *w3 = weight[2].data() + nb.table_start[i];
            for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
              {
                const unsigned int j = nb.col[b];
                sum -= K[2] * prm.conductivity[bond_type(phase, i, j)] *
                       w3[b - nb.row_start[i]] * (f[j] - f[i]);
              }
          }
        out.local_element(i) = sum;
      }
  }

  template <int dim>
  void
  NnppOperator<dim>::reinit_matrix(TrilinosWrappers::SparseMatrix &matrix) const
  {
    if (matrix.m() != sparsity.n_rows())
      matrix.reinit(sparsity);
  }

  template <int dim>
  void
  NnppOperator<dim>::assemble_poisson(TrilinosWrappers::SparseMatrix &matrix,
                                      const Vector                   *phase) const
  {
    reinit_matrix(matrix);
    const auto                          &nb   = disc.neighborhood;
    const auto                          &part = *disc.partitioner();
    std::vector<types::global_dof_index> cols;
    std::vector<double>                  values;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        cols.assign(1, part.local_to_global(i));
        values.assign(1, 1.);
        if (disc.region[i] == Discretization<dim>::interior)
          {
            const double *w3  = weight[2].data() + nb.table_start[i];
            double        sum = 0.;
            for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
              {
                const unsigned int j = nb.col[b];
                const double       a =
                  K[2] * prm.conductivity[bond_type(phase, i, j)] * w3[b - nb.row_start[i]];
                sum += a;
                if (disc.region[j] == Discretization<dim>::interior)
                  {
                    cols.push_back(part.local_to_global(j));
                    values.push_back(-a);
                  }
              }
            values[0] = sum;
          }
        matrix.set(cols[0], cols.size(), cols.data(), values.data());
      }
    matrix.compress(VectorOperation::insert);
  }

  template <int dim>
  void
  NnppOperator<dim>::add_poisson_layer_coupling(const Vector &phi,
                                                Vector       &rhs,
                                                const Vector *phase) const
  {
    const auto &nb = disc.neighborhood;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::interior)
        {
          const double *w3 = weight[2].data() + nb.table_start[i];
          for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
            {
              const unsigned int j = nb.col[b];
              if (disc.region[j] != Discretization<dim>::interior)
                rhs.local_element(i) += K[2] * prm.conductivity[bond_type(phase, i, j)] *
                                        w3[b - nb.row_start[i]] * phi.local_element(j);
            }
        }
  }

  template <int dim>
  void
  NnppOperator<dim>::assemble_species_jacobian(const unsigned int              k,
                                               const Vector                   &phi,
                                               const double                    dt,
                                               TrilinosWrappers::SparseMatrix &matrix,
                                               const Vector                   *phase,
                                               const Vector                   *dR) const
  {
    reinit_matrix(matrix);
    const auto  &nb   = disc.neighborhood;
    const auto  &part = *disc.partitioner();
    const double zf   = prm.valence[k] * prm.faraday / (prm.gas_constant * prm.temperature);
    const auto  &D    = prm.diffusivity[k];
    const double *f   = phi.begin();
    std::vector<types::global_dof_index> cols;
    std::vector<double>                  values;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        cols.assign(1, part.local_to_global(i));
        values.assign(1, 1.);
        if (disc.region[i] == Discretization<dim>::interior)
          {
            const double *w1   = weight[0].data() + nb.table_start[i];
            const double *w2   = weight[1].data() + nb.table_start[i];
            double        diag = 1. / dt - (dR != nullptr ? dR->local_element(i) : 0.);
            for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
              {
                const unsigned int j = nb.col[b];
                if (!species_bond(j))
                  continue;
                const unsigned int s  = b - nb.row_start[i];
                const double       d  = D[bond_type(phase, i, j)];
                const double       a  = K[0] * d * w1[s];
                const double       bb = K[1] * d * zf * w2[s] * (f[j] - f[i]);
                // d/dC_i of -[a (C_j - C_i) + b (C_j + C_i)] = a - b;
                // d/dC_j = -(a + b): (3.15) with the sign of the K1 term corrected.
                diag += a - bb;
                if (disc.region[j] == Discretization<dim>::interior)
                  {
                    cols.push_back(part.local_to_global(j));
                    values.push_back(-(a + bb));
                  }
              }
            values[0] = diag;
          }
        matrix.set(cols[0], cols.size(), cols.data(), values.data());
      }
    matrix.compress(VectorOperation::insert);
  }

  template <int dim>
  NnppSolver<dim>::NnppSolver(const Discretization<dim> &discretization,
                              const NnppParameters      &parameters,
                              const NnppSources<dim>    &sources)
    : disc(discretization)
    , prm(parameters)
    , sources(sources)
    , op(discretization, parameters)
  {
    C.resize(prm.n_species());
    for (auto &c : C)
      disc.initialize_vector(c);
    disc.initialize_vector(phi);
    disc.initialize_vector(phase);
  }

  template <int dim>
  void
  NnppSolver<dim>::set_layer(const unsigned int k, Vector &c, const double t) const
  {
    if (prm.species_boundary != "dirichlet")
      return;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] != Discretization<dim>::interior)
        c.local_element(i) =
          sources.boundary_concentration ? sources.boundary_concentration(k, disc.position[i], t) : 0.;
  }

  template <int dim>
  void
  NnppSolver<dim>::set_concentration(const unsigned int                               k,
                                     const std::function<double(const Point<dim> &)> &f)
  {
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      C[k].local_element(i) = f(disc.position[i]);
    set_layer(k, C[k], current_time);
    if (prm.species_boundary == "closed")
      // Layer values are never used; keep them 0 so that they are visibly inert.
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (disc.region[i] != Discretization<dim>::interior)
          C[k].local_element(i) = 0.;
    C[k].update_ghost_values();
  }

  template <int dim>
  double
  NnppSolver<dim>::mass(const unsigned int k) const
  {
    double m = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::interior)
        m += disc.volume[i] * C[k].local_element(i);
    return Utilities::MPI::sum(m, disc.get_mpi_communicator());
  }

  template <int dim>
  void
  NnppSolver<dim>::solve_potential()
  {
    const auto comm  = disc.get_mpi_communicator();
    const auto owned = disc.partitioner()->locally_owned_range();
    if (!poisson_valid)
      {
        op.assemble_poisson(poisson_matrix, &phase);
        TrilinosWrappers::PreconditionAMG::AdditionalData data;
        data.elliptic              = true;
        data.higher_order_elements = false;
        data.smoother_sweeps       = 2;
        data.aggregation_threshold = 0.02;
        poisson_amg.initialize(poisson_matrix, data);
        poisson_valid = true;
      }
    const double t = current_time;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] != Discretization<dim>::interior)
        phi.local_element(i) =
          sources.boundary_potential ? sources.boundary_potential(disc.position[i], t) : 0.;
    phi.update_ghost_values();

    Vector b;
    disc.initialize_vector(b);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (disc.region[i] != Discretization<dim>::interior)
          {
            b.local_element(i) = phi.local_element(i);
            continue;
          }
        double charge = 0.;
        for (unsigned int k = 0; k < prm.n_species(); ++k)
          charge += prm.valence[k] * C[k].local_element(i);
        b.local_element(i) = prm.faraday * charge +
                             (sources.poisson_source ? sources.poisson_source(disc.position[i], t) : 0.);
      }
    op.add_poisson_layer_coupling(phi, b, &phase);

    TrilinosWrappers::MPI::Vector rhs(owned, comm), x(owned, comm);
    std::copy(b.begin(), b.begin() + disc.n_owned(), rhs.begin());
    std::copy(phi.begin(), phi.begin() + disc.n_owned(), x.begin());
    if (rhs.l2_norm() == 0.)
      x = 0.; // no charge, phi = 0 on the layer: the solution is 0
    else
      {
        SolverControl              control(10000, prm.linear_tolerance * rhs.l2_norm());
        TrilinosWrappers::SolverCG cg(control);
        cg.solve(poisson_matrix, x, rhs, poisson_amg);
        last_linear_iterations += control.last_step();
      }
    std::copy(x.begin(), x.begin() + disc.n_owned(), phi.begin());
    phi.update_ghost_values();
  }

  template <int dim>
  void
  NnppSolver<dim>::step()
  {
    last_newton_iterations = 0;
    last_linear_iterations = 0;
    solve_potential(); // phi^n from C^n, explicit in the species equations
    const double dt    = prm.time_step;
    const double t_new = current_time + dt;
    const auto   comm  = disc.get_mpi_communicator();
    const auto   owned = disc.partitioner()->locally_owned_range();
    const unsigned int n_species = prm.n_species();

    std::vector<double> c_node(n_species);
    auto                node_concentrations = [&](const unsigned int i, const unsigned int k,
                                   const Vector &ck) {
      for (unsigned int l = 0; l < n_species; ++l)
        c_node[l] = l == k ? ck.local_element(i) : C[l].local_element(i);
    };

    Vector rate, dR, Cn;
    disc.initialize_vector(rate);
    disc.initialize_vector(dR);
    TrilinosWrappers::PreconditionAMG amg;
    TrilinosWrappers::MPI::Vector     residual(owned, comm), update(owned, comm);
    for (unsigned int k = 0; k < n_species; ++k)
      {
        Cn = C[k];
        Vector &x = C[k];
        set_layer(k, x, t_new);
        x.update_ghost_values();

        // Frozen Jacobian of (3.14)-(3.15) at C^{n+1,0} = C^n.
        const bool has_dR = static_cast<bool>(sources.reaction_derivative);
        if (has_dR)
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            {
              node_concentrations(i, k, x);
              dR.local_element(i) = sources.reaction_derivative(k, disc.position[i], t_new, c_node);
            }
        op.assemble_species_jacobian(k, phi, dt, jacobian, &phase, has_dR ? &dR : nullptr);
        TrilinosWrappers::PreconditionAMG::AdditionalData data;
        data.elliptic              = false; // migration makes K_C non-symmetric
        data.higher_order_elements = false;
        data.smoother_sweeps       = 2;
        data.aggregation_threshold = 0.02;
        amg.initialize(jacobian, data);

        double ref = 0.;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (disc.region[i] == Discretization<dim>::interior)
            ref += std::pow(Cn.local_element(i) / dt, 2);
        ref = std::sqrt(Utilities::MPI::sum(ref, comm));
        ref = std::max(ref, 1e-300);

        unsigned int m = 0;
        for (;; ++m)
          {
            // F of (3.11) at the current iterate; layer rows already hold
            // their prescribed values (F = 0).
            op.apply_species(k, x, phi, rate, &phase);
            for (unsigned int i = 0; i < disc.n_owned(); ++i)
              {
                double F = 0.;
                if (disc.region[i] == Discretization<dim>::interior)
                  {
                    F = (x.local_element(i) - Cn.local_element(i)) / dt - rate.local_element(i);
                    if (sources.reaction)
                      {
                        node_concentrations(i, k, x);
                        F -= sources.reaction(k, disc.position[i], t_new, c_node);
                      }
                  }
                // Trilinos vectors hold the owned range in the same order.
                residual.begin()[i] = F;
              }
            const double norm = residual.l2_norm();
            if (norm <= prm.newton_tolerance * ref || norm == 0.)
              break;
            std::ostringstream rel;
            rel << std::scientific << norm / ref;
            AssertThrow(m < prm.max_newton_iterations,
                        ExcMessage("NNPP: modified Newton did not converge for species " +
                                   std::to_string(k) + " in 'NNPP/Max Newton iterations' = " +
                                   std::to_string(prm.max_newton_iterations) +
                                   " iterations (||F|| / ||C^n/dt|| = " + rel.str() + ")."));
            SolverControl                 control(10000, prm.linear_tolerance * norm);
            TrilinosWrappers::SolverGMRES gmres(control);
            update = 0.;
            gmres.solve(jacobian, update, residual, amg);
            last_linear_iterations += control.last_step();
            // Delta C = -K^-1 F, lambda = 1 (3.17)
            for (unsigned int i = 0; i < disc.n_owned(); ++i)
              x.local_element(i) -= update.begin()[i];
            x.update_ghost_values();
          }
        last_newton_iterations += m;
      }
    current_time = t_new;

    last_phase_changes = 0;
    if (prm.phase_species >= 0)
      {
        // The one-way rule (2.79) of the corrosion model (update_corrosion_phase).
        unsigned int changed = 0;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (disc.region[i] == Discretization<dim>::interior && phase.local_element(i) > 0.5 &&
              C[prm.phase_species].local_element(i) < prm.saturation)
            {
              phase.local_element(i) = 0.;
              ++changed;
            }
        last_phase_changes = Utilities::MPI::sum(changed, comm);
        if (last_phase_changes > 0)
          {
            phase.update_ghost_values();
            poisson_valid = false; // sigma follows the bond types
          }
      }
  }

  template class NnppOperator<1>;
  template class NnppOperator<2>;
  template class NnppOperator<3>;
  template class NnppSolver<1>;
  template class NnppSolver<2>;
  template class NnppSolver<3>;
} // namespace PeriDEAL
