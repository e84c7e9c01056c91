#include <deal.II/base/utilities.h>

#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_solver.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/expressions.h>
#include <perideal/io/checkpoint.h>
#include <perideal/io/node_output.h>
#include <perideal/io/time_series.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace PeriDEAL
{
  template <int dim>
  void
  DiffusionRunParameters<dim>::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Geometry");
    Domain<dim>::declare_parameters(prm);
    prm.leave_subsection();

    prm.enter_subsection("Discretization");
    LatticeParameters::declare_parameters(prm);
    prm.leave_subsection();

    prm.enter_subsection("Model");
    DiffusionModelParameters::declare_parameters(prm);
    prm.declare_entry("Initial condition", "0", Patterns::Anything(),
                      "C(x, 0) as a muparser expression in x, y, z.");
    prm.declare_entry("Source", "0", Patterns::Anything(),
                      "Source S(x, t) of (2.41), expression in x, y, z, t.");
    prm.declare_entry("Constants", "", Patterns::Anything(),
                      "Constants usable in every expression, e.g. 'delta=0.1, k=2'.");
    prm.leave_subsection();

    prm.enter_subsection("Boundary conditions");
    prm.declare_entry("Dirichlet value", "0", Patterns::Anything(),
                      "C(x, t) prescribed on the nodes of the volume constraint layer "
                      "(Discretization/Volume constraint layer > 0).");
    prm.declare_entry("Exact solution", "", Patterns::Anything(),
                      "Optional exact solution C(x, t); if given, the relative l2 "
                      "error (3.79) over the body nodes is reported.");
    prm.leave_subsection();

    prm.enter_subsection("Time stepping");
    prm.declare_entry("Scheme", "forward Euler",
                      Patterns::Selection("forward Euler|backward Euler"),
                      "forward Euler (3.10), or backward Euler with the modified "
                      "Newton scheme (3.16)-(3.17) and Trilinos CG/GMRES + AMG.");
    prm.declare_entry("Time step", "0", Patterns::Double(),
                      "dt (> 0). For forward Euler it must not exceed the stability "
                      "bound of the discrete operator; 0 picks 0.9 x that bound.");
    prm.declare_entry("End time", "1", Patterns::Double(), "Final time (> 0).");
    prm.declare_entry("Linear solver tolerance", "1e-12", Patterns::Double(),
                      "Relative residual of the linear solves (0 < tol < 1).");
    prm.declare_entry("Newton tolerance", "1e-10", Patterns::Double(),
                      "Newton stops when |F| <= tol |F_0| (0 < tol < 1).");
    prm.declare_entry("Max Newton iterations", "10", Patterns::Integer(1),
                      "Upper limit of Newton iterations per step.");
    prm.declare_entry("Preconditioner", "auto", Patterns::Selection("auto|AMG|Jacobi"),
                      "Preconditioner of the linear solves: ML algebraic multigrid, "
                      "Jacobi, or auto: Jacobi when dt is at most 10x the explicit "
                      "stability bound (the matrix I/dt - L is then strongly "
                      "diagonally dominant), AMG otherwise.");
    prm.leave_subsection();

    prm.enter_subsection("Hybrid");
    prm.declare_entry("Quadrature", "standard", Patterns::Selection("standard|wls|hybrid"),
                      "standard: the standard scheme (3.4) on every node. wls: the WLS "
                      "collocation quadrature (Sect. 3.2) on every interior node. hybrid: "
                      "the fixed hybrid configuration of Sect. 3.3, standard scheme on "
                      "Omega_s (see 'Standard region width' and 'Standard region'), WLS "
                      "elsewhere. With backward Euler the WLS rows enter the Jacobian "
                      "(non-symmetric: GMRES) for linear diffusion; corrosion with WLS needs "
                      "forward Euler, and a WLS row falls back to the standard one where its "
                      "collocation nodes are of mixed phase.");
    prm.declare_entry("Standard region width", "0", Patterns::Double(),
                      "hybrid: interior nodes closer than this (>= 0) to the boundary of "
                      "the body (signed distance of the geometry) use the standard "
                      "scheme.");
    prm.declare_entry("Standard region", "0", Patterns::Anything(),
                      "hybrid: expression in x, y, z; interior nodes where it is > 0 also "
                      "use the standard scheme (e.g. '(abs(x) < 0.2) * (abs(y) < 0.2)').");
    prm.enter_subsection("WLS");
    WlsParameters::declare_parameters(prm);
    prm.leave_subsection();
    prm.leave_subsection();

    prm.enter_subsection("Output");
    prm.declare_entry("Directory", "output", Patterns::Anything(),
                      "Where VTU/PVD snapshots, the CSV time series, checkpoints and "
                      "a copy of the parameter file go.");
    prm.declare_entry("Snapshot interval", "0", Patterns::Integer(0),
                      "Steps between ParaView snapshots; 0: first and last only.");
    prm.declare_entry("Time series interval", "1", Patterns::Integer(1),
                      "Steps between rows of the CSV time series.");
    prm.declare_entry("Checkpoint interval", "0", Patterns::Integer(0),
                      "Steps between checkpoints; 0: none.");
    prm.declare_entry("Resume", "false", Patterns::Bool(),
                      "Resume from the checkpoint in the output directory if there is "
                      "one (also: perideal --resume).");
    prm.declare_entry("Progress interval", "10", Patterns::Double(0.),
                      "Seconds of wall time between progress lines.");
    prm.declare_entry("Write node table", "false", Patterns::Bool(),
                      "Write final node values sorted by node id (nodes.csv).");
    prm.leave_subsection();
  }

  template <int dim>
  void
  DiffusionRunParameters<dim>::parse_parameters(ParameterHandler &p)
  {
    p.enter_subsection("Geometry");
    domain = Domain<dim>::create(p);
    p.leave_subsection();

    p.enter_subsection("Discretization");
    lattice.parse_parameters(p);
    p.leave_subsection();

    p.enter_subsection("Model");
    model.parse_parameters(p, dim);
    initial_condition = p.get("Initial condition");
    source            = p.get("Source");
    constants         = p.get("Constants");
    p.leave_subsection();

    p.enter_subsection("Boundary conditions");
    dirichlet_value = p.get("Dirichlet value");
    exact_solution  = p.get("Exact solution");
    p.leave_subsection();

    p.enter_subsection("Time stepping");
    scheme                = p.get("Scheme");
    time_step             = p.get_double("Time step");
    end_time              = p.get_double("End time");
    linear_tolerance      = p.get_double("Linear solver tolerance");
    newton_tolerance      = p.get_double("Newton tolerance");
    max_newton_iterations = p.get_integer("Max Newton iterations");
    preconditioner        = p.get("Preconditioner");
    p.leave_subsection();
    check_parameter(time_step >= 0., "Time stepping/Time step", time_step,
                    "a positive number (or 0 for automatic with forward Euler)");
    check_parameter(scheme == "forward Euler" || time_step > 0., "Time stepping/Time step",
                    time_step, "a positive number for backward Euler");
    check_parameter(end_time > 0., "Time stepping/End time", end_time, "a positive number");
    check_parameter(linear_tolerance > 0. && linear_tolerance < 1.,
                    "Time stepping/Linear solver tolerance", linear_tolerance, "(0, 1)");
    check_parameter(newton_tolerance > 0. && newton_tolerance < 1.,
                    "Time stepping/Newton tolerance", newton_tolerance, "(0, 1)");

    p.enter_subsection("Hybrid");
    quadrature      = p.get("Quadrature");
    standard_width  = p.get_double("Standard region width");
    standard_region = p.get("Standard region");
    p.enter_subsection("WLS");
    wls.parse_parameters(p);
    p.leave_subsection();
    p.leave_subsection();
    check_parameter(standard_width >= 0., "Hybrid/Standard region width", standard_width,
                    "a non-negative number");
    check_parameter(quadrature == "standard" || scheme == "forward Euler" ||
                      model.type == "diffusion",
                    "Hybrid/Quadrature", quadrature,
                    "standard for corrosion with backward Euler (the phase-dependent WLS "
                    "rows are explicit only)");

    p.enter_subsection("Output");
    output_directory     = p.get("Directory");
    snapshot_interval    = p.get_integer("Snapshot interval");
    time_series_interval = p.get_integer("Time series interval");
    checkpoint_interval  = p.get_integer("Checkpoint interval");
    resume               = p.get_bool("Resume");
    progress_interval    = p.get_double("Progress interval");
    write_node_table     = p.get_bool("Write node table");
    p.leave_subsection();
  }

  template <int dim>
  struct DiffusionSolver<dim>::OutputState
  {
    std::unique_ptr<NodeOutput<dim>> vtu;
    std::unique_ptr<TimeSeries>      csv;
    Timer                            wall;
    double                           last_progress = 0.;
  };

  namespace
  {
    template <int dim>
    void
    init_function(FunctionParser<dim> &f,
                  const std::string   &expression,
                  const std::string   &constants,
                  const std::string   &parameter)
    {
      init_expression(f, expression, constants, parameter, "Model/Constants");
    }
  } // namespace

  template <int dim>
  DiffusionSolver<dim>::DiffusionSolver(const MPI_Comm comm, const DiffusionRunParameters<dim> &p)
    : mpi_communicator(comm)
    , prm(p)
    , pcout(std::cout, Utilities::MPI::this_mpi_process(comm) == 0)
    , computing_timer(pcout, TimerOutput::never, TimerOutput::wall_times)
    , disc(comm)
  {}

  template <int dim>
  DiffusionSolver<dim>::~DiffusionSolver() = default;

  template <int dim>
  std::string
  DiffusionSolver<dim>::signature() const
  {
    std::ostringstream s;
    s.precision(16);
    s << dim << " " << disc.n_global() << " " << prm.lattice.dx << " " << prm.lattice.delta
      << " " << prm.model.type << " " << dt;
    return s.str();
  }

  template <int dim>
  void
  DiffusionSolver<dim>::setup()
  {
    TimerOutput::Scope scope(computing_timer, "setup");
    disc.setup(*prm.domain, prm.lattice);
    op = std::make_unique<DiffusionOperator<dim>>(disc, prm.model);
    setup_quadrature();

    FunctionParser<dim> initial;
    init_function(initial, prm.initial_condition, prm.constants, "Model/Initial condition");
    init_function(source_function, prm.source, prm.constants, "Model/Source");
    init_function(dirichlet_function, prm.dirichlet_value, prm.constants,
                  "Boundary conditions/Dirichlet value");
    has_source = !(prm.source == "0" || prm.source.empty());
    has_exact  = !prm.exact_solution.empty();
    if (has_exact)
      init_function(exact_function, prm.exact_solution, prm.constants,
                    "Boundary conditions/Exact solution");

    disc.initialize_vector(C);
    disc.initialize_vector(rate);
    disc.initialize_vector(phase);
    initial.set_time(0.);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      C.local_element(i) = initial.value(disc.position[i]);
    apply_dirichlet(C, 0.);
    if (op->is_corrosion())
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        phase.local_element(i) = C.local_element(i) >= prm.model.saturation ? 1. : 0.;
    C.update_ghost_values();
    phase.update_ghost_values();

    dt_critical = op->critical_time_step();
    dt          = prm.time_step;
    if (prm.scheme == "forward Euler")
      {
        if (dt == 0.) // the largest step <= 0.9 x bound that ends on the end time
          dt = prm.end_time / std::ceil(prm.end_time / (0.9 * dt_critical));
        std::ostringstream bound;
        bound.precision(6);
        bound << "a value <= the forward Euler stability bound " << dt_critical
              << " (Gershgorin bound min_i 2/(|l_ii| + R_i) of the iteration matrix for "
              << (disc.parameters().layer_thickness > 0. ?
                    "Dirichlet values on the volume-constraint layer" :
                    "homogeneous nonlocal Neumann ends")
              << ", i.e. 1/max_i sum_j kappa_ij w_ij in the bulk, (16) of paper 003"
              << (op->is_corrosion() ? ", with the largest micro-diffusivity" : "")
              << (n_wls_global > 0 ? ", WLS rows included" : "")
              << "); use 'backward Euler' for larger steps";
        check_parameter(dt <= dt_critical * (1. + 1e-10), "Time stepping/Time step", dt,
                        bound.str());
      }
    total_steps = (unsigned int)std::llround(prm.end_time / dt);
    check_parameter(total_steps >= 1, "Time stepping/End time", prm.end_time,
                    "a value of at least one time step");
    current_time = 0.;
    current_step = 0;
    matrix_valid = false;
    recorded.clear();
  }

  template <int dim>
  void
  DiffusionSolver<dim>::setup_quadrature()
  {
    n_wls_global = 0;
    if (prm.quadrature == "standard")
      return;
    const bool by_width = prm.quadrature == "hybrid" && prm.standard_width > 0.;
    check_parameter(!by_width || prm.domain->has_signed_distance(),
                    "Hybrid/Standard region width", prm.standard_width,
                    "0 for a geometry without a signed distance (use 'Standard region')");
    FunctionParser<dim> region;
    init_function(region, prm.standard_region, prm.constants, "Hybrid/Standard region");
    std::vector<unsigned int> rows;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (disc.region[i] != Discretization<dim>::interior)
          continue;
        const Point<dim> &x        = disc.position[i];
        const bool        standard = prm.quadrature == "hybrid" &&
                              ((by_width && prm.domain->signed_distance(x) > -prm.standard_width) ||
                               region.value(x) > 0.);
        if (!standard)
          rows.push_back(i);
      }
    op->set_wls_rows(prm.wls, rows);
    n_wls_global = Utilities::MPI::sum<types::global_dof_index>(rows.size(), mpi_communicator);
  }

  template <int dim>
  void
  DiffusionSolver<dim>::replace_wls_rows()
  {
    // Row i of I/dt - L becomes 1/dt - w_ii on the diagonal and -w_ij for
    // the interior collocation nodes; the standard row's entries are zeroed
    // first. The collocation nodes are family nodes, so every entry is in
    // the pattern assemble_backward_euler() built (interior family).
    const auto *wls = op->wls_quadrature();
    if (wls == nullptr)
      return;
    const auto &part = *disc.partitioner();
    for (unsigned int k = 0; k < wls->node.size(); ++k)
      {
        const unsigned int            i   = wls->node[k];
        const types::global_dof_index row = part.local_to_global(i);
        for (auto it = matrix.begin(row); it != matrix.end(row); ++it)
          it->value() = 0.;
        for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
          {
            const unsigned int j = wls->col[e];
            if (disc.region[j] != Discretization<dim>::interior)
              continue;
            const double v = (j == i ? 1. / dt : 0.) - wls->weight[e];
            matrix.set(row, part.local_to_global(j), v);
          }
      }
    matrix.compress(VectorOperation::insert);
  }

  template <int dim>
  void
  DiffusionSolver<dim>::apply_dirichlet(Vector &v, const double t)
  {
    dirichlet_function.set_time(t);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::constrained)
        v.local_element(i) = dirichlet_function.value(disc.position[i]);
  }

  template <int dim>
  void
  DiffusionSolver<dim>::advance()
  {
    if (prm.scheme == "forward Euler")
      explicit_step();
    else
      implicit_step();
    ++current_step;
    current_time = current_step * dt;
    if (op->is_corrosion())
      update_phase();
  }

  template <int dim>
  void
  DiffusionSolver<dim>::explicit_step()
  {
    {
      TimerOutput::Scope scope(computing_timer, "operator");
      // Only the interior rows: the layer is overwritten by apply_dirichlet()
      // and rate is read nowhere else.
      op->apply(C, rate, &phase, DiffusionOperator<dim>::Rows::interior);
    }
    const double t_new = current_time + dt;
    source_function.set_time(current_time);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::interior)
        C.local_element(i) +=
          dt * (rate.local_element(i) +
                (has_source ? source_function.value(disc.position[i]) : 0.));
    apply_dirichlet(C, t_new);
    C.update_ghost_values();
  }

  template <int dim>
  void
  DiffusionSolver<dim>::implicit_step()
  {
    TimerOutput::Scope scope(computing_timer, "implicit solve");
    const double       t_new = current_time + dt;
    // Frozen Jacobian K = I/dt - L(phase^n): reassembled only when the bond
    // diffusivities changed (phase change) -- (3.16)-(3.17).
    if (!matrix_valid)
      {
        op->assemble_backward_euler(dt, matrix, &phase);
        replace_wls_rows();
        use_amg = prm.preconditioner == "AMG" ||
                  (prm.preconditioner == "auto" && dt > 10. * dt_critical);
        if (use_amg)
          {
            TrilinosWrappers::PreconditionAMG::AdditionalData data;
            data.elliptic              = true;
            data.higher_order_elements = false;
            data.smoother_sweeps       = 2;
            data.aggregation_threshold = 0.02;
            amg.initialize(matrix, data);
          }
        else
          jacobi.initialize(matrix);
        matrix_valid = true;
      }

    const auto &owned = disc.partitioner()->locally_owned_range();
    TrilinosWrappers::MPI::Vector rhs(owned, mpi_communicator), x(owned, mpi_communicator),
      residual(owned, mpi_communicator), delta_c(owned, mpi_communicator);

    // b = C^n / dt + S^{n+1} + couplings to the layer at t^{n+1};
    // layer rows hold the prescribed values.
    Vector b;
    disc.initialize_vector(b);
    Vector C_new = C;
    apply_dirichlet(C_new, t_new);
    C_new.update_ghost_values();
    source_function.set_time(t_new);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      b.local_element(i) =
        disc.region[i] == Discretization<dim>::interior ?
          C.local_element(i) / dt +
            (has_source ? source_function.value(disc.position[i]) : 0.) :
          C_new.local_element(i);
    op->add_constrained_coupling(C_new, b, &phase);
    if (const auto *wls = op->wls_quadrature())
      // WLS rows: C^n/dt + S + sum over prescribed collocation nodes w_ij C_j
      // (add_constrained_coupling() added the standard row's couplings).
      for (unsigned int k = 0; k < wls->node.size(); ++k)
        {
          const unsigned int i = wls->node[k];
          double             s = C.local_element(i) / dt +
                     (has_source ? source_function.value(disc.position[i]) : 0.);
          for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
            if (disc.region[wls->col[e]] != Discretization<dim>::interior)
              s += wls->weight[e] * C_new.local_element(wls->col[e]);
          b.local_element(i) = s;
        }

    // Trilinos vectors hold the owned range in the same order.
    std::copy(b.begin(), b.begin() + disc.n_owned(), rhs.begin());
    std::copy(C_new.begin(), C_new.begin() + disc.n_owned(), x.begin());

    newton_iterations = 0;
    linear_iterations = 0;
    double f0         = -1.;
    for (unsigned int m = 0; m < prm.max_newton_iterations; ++m)
      {
        // F(C^m) = K C^m - b
        matrix.vmult(residual, x);
        residual -= rhs;
        const double f = residual.l2_norm();
        if (f0 < 0.)
          f0 = std::max(f, rhs.l2_norm() * 1e-300);
        if (f <= prm.newton_tolerance * rhs.l2_norm() || f == 0.)
          break;
        SolverControl control(10000, prm.linear_tolerance * f);
        delta_c = 0.;
        const TrilinosWrappers::PreconditionBase &preconditioner =
          use_amg ? static_cast<const TrilinosWrappers::PreconditionBase &>(amg) :
                    static_cast<const TrilinosWrappers::PreconditionBase &>(jacobi);
        if (op->is_corrosion() || n_wls_global > 0)
          {
            TrilinosWrappers::SolverGMRES solver(control);
            solver.solve(matrix, delta_c, residual, preconditioner);
          }
        else
          {
            TrilinosWrappers::SolverCG solver(control);
            solver.solve(matrix, delta_c, residual, preconditioner);
          }
        linear_iterations += control.last_step();
        x.add(-1., delta_c); // lambda = 1
        ++newton_iterations;
      }
    AssertThrow(newton_iterations < prm.max_newton_iterations,
                ExcMessage("Newton did not converge in 'Time stepping/Max Newton "
                           "iterations' = " +
                           std::to_string(prm.max_newton_iterations) + " iterations."));
    std::copy(x.begin(), x.begin() + disc.n_owned(), C.begin());
    C.update_ghost_values();
  }

  template <int dim>
  void
  DiffusionSolver<dim>::update_phase()
  {
    const bool changed = update_corrosion_phase(prm.model, C, phase, disc.n_owned());
    phase.update_ghost_values();
    if (Utilities::MPI::logical_or(changed, mpi_communicator))
      matrix_valid = false;
  }

  template <int dim>
  DiffusionDiagnostics
  DiffusionSolver<dim>::diagnostics() const
  {
    double local[5] = {0., 0., 0., 0., 0.};
    if (has_exact)
      exact_function.set_time(current_time);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::interior)
        {
          const double c = C.local_element(i), V = disc.volume[i];
          local[0] += c * V;
          local[1] += c * c * V;
          local[2] += phase.local_element(i) * V;
          if (has_exact)
            {
              const double e = exact_function.value(disc.position[i]);
              local[3] += (c - e) * (c - e);
              local[4] += e * e;
            }
        }
    double global[5];
    Utilities::MPI::sum(ArrayView<const double>(local, 5), mpi_communicator,
                        ArrayView<double>(global, 5));
    DiffusionDiagnostics d;
    d.time         = current_time;
    d.mass         = global[0];
    d.pi           = global[1];
    d.solid_volume = global[2];
    d.error        = has_exact && global[4] > 0. ? std::sqrt(global[3] / global[4]) : 0.;
    return d;
  }

  template <int dim>
  void
  DiffusionSolver<dim>::write_checkpoint()
  {
    TimerOutput::Scope scope(computing_timer, "output");
    PeriDEAL::write_checkpoint<dim>(prm.output_directory + "/checkpoint.bin",
                          disc,
                          current_step,
                          current_time,
                          {&C, &phase},
                          signature());
  }

  template <int dim>
  bool
  DiffusionSolver<dim>::read_checkpoint()
  {
    unsigned int step = 0;
    double       t    = 0.;
    if (!PeriDEAL::read_checkpoint<dim>(prm.output_directory + "/checkpoint.bin",
                                        disc, step, t, {&C, &phase}, signature()))
      return false;
    current_step = step;
    current_time = current_step * dt;
    C.update_ghost_values();
    phase.update_ghost_values();
    matrix_valid = false;
    return true;
  }

  template <int dim>
  void
  DiffusionSolver<dim>::record_and_output(const bool force_snapshot)
  {
    TimerOutput::Scope scope(computing_timer, "output");
    const bool         last = current_step == total_steps;
    if (current_step % prm.time_series_interval == 0 || last)
      {
        const DiffusionDiagnostics d = diagnostics();
        recorded.push_back(d);
        output->csv->add_row({d.time, d.mass, d.pi, d.solid_volume, d.error});
      }
    const bool snapshot = force_snapshot || last ||
                          (prm.snapshot_interval > 0 &&
                           current_step % prm.snapshot_interval == 0);
    if (snapshot)
      output->vtu->write(current_time, current_step, {{"concentration", &C}, {"phase", &phase}});
  }

  template <int dim>
  void
  DiffusionSolver<dim>::run(const unsigned int max_steps)
  {
    if (!op)
      setup();
    output       = std::make_unique<OutputState>();
    output->vtu  = std::make_unique<NodeOutput<dim>>(disc, prm.output_directory, "solution");
    output->csv  = std::make_unique<TimeSeries>(mpi_communicator,
                                               prm.output_directory + "/time_series.csv",
                                               std::vector<std::string>{"time", "mass", "Pi",
                                                                        "solid_volume",
                                                                        "relative_l2_error"});
    bool resumed = false;
    if (prm.resume)
      resumed = read_checkpoint();
    if (resumed)
      {
        output->csv->load_existing();
        output->csv->truncate_after(current_time * (1. + 1e-12));
        output->vtu->restart(current_time);
        pcout << "Resumed from checkpoint at step " << current_step << ", t = " << current_time
              << std::endl;
      }

    pcout << "PD " << prm.model.type << " in " << dim << "D: " << disc.n_global() << " nodes, "
          << disc.n_global_bonds() << " bonds, kappa = " << op->kernel().constant
          << ", dt = " << dt << " (forward Euler bound " << dt_critical << "), "
          << total_steps << " steps, scheme: " << prm.scheme << std::endl;
    if (n_wls_global > 0)
      pcout << "  quadrature: " << prm.quadrature << ", WLS-" << prm.wls.order << " on "
            << n_wls_global << " nodes (Omega_w), standard scheme on the others"
            << (op->gershgorin_proves_stability() ?
                  "" :
                  "; WLS rows are not diagonally dominant: the step bound is 2/rho "
                  "(Gershgorin bound of the spectral radius), not a proof")
            << std::endl;

    if (!resumed)
      record_and_output(true);

    unsigned int done = 0;
    while (current_step < total_steps && done < max_steps)
      {
        advance();
        ++done;
        record_and_output(false);
        if (prm.checkpoint_interval > 0 && current_step % prm.checkpoint_interval == 0)
          write_checkpoint();
        const double elapsed = output->wall.wall_time();
        if (elapsed - output->last_progress >= prm.progress_interval &&
            current_step < total_steps)
          {
            output->last_progress = elapsed;
            const double remaining =
              elapsed / done * double(total_steps - current_step);
            pcout << "  step " << current_step << "/" << total_steps << "  t = " << current_time
                  << "  elapsed " << std::fixed << std::setprecision(1) << elapsed
                  << " s  remaining ~" << remaining << " s" << std::defaultfloat
                  << std::setprecision(6) << std::endl;
          }
      }
    if (prm.write_node_table && current_step == total_steps)
      PeriDEAL::write_node_table<dim>(prm.output_directory + "/nodes.csv", disc,
                            {{"concentration", &C}, {"phase", &phase}});
  }

  template struct DiffusionRunParameters<1>;
  template struct DiffusionRunParameters<2>;
  template struct DiffusionRunParameters<3>;
  template class DiffusionSolver<1>;
  template class DiffusionSolver<2>;
  template class DiffusionSolver<3>;
} // namespace PeriDEAL
