#include <deal.II/base/function_parser.h>
#include <deal.II/base/utilities.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/expressions.h>
#include <perideal/io/node_output.h>
#include <perideal/io/time_series.h>
#include <perideal/time_stepping/nnpp_run.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

namespace PeriDEAL
{
  namespace
  {
    // ';'-separated expressions (commas belong to muparser functions).
    std::vector<std::string>
    expression_list(const std::string &text)
    {
      if (text.find_first_not_of(" \t") == std::string::npos)
        return {};
      return Utilities::split_string_list(text, ';');
    }

    template <int dim>
    std::unique_ptr<FunctionParser<dim>>
    make_function(const std::string &expression,
                  const std::string &constants,
                  const std::string &parameter)
    {
      auto f = std::make_unique<FunctionParser<dim>>();
      init_expression(*f, expression, constants, parameter, "NNPP/Constants");
      return f;
    }
  } // namespace

  template <int dim>
  void
  NnppRunParameters<dim>::declare_parameters(ParameterHandler &prm)
  {
    NnppParameters::declare_parameters(prm);
    prm.enter_subsection("NNPP");
    prm.declare_entry("Initial concentrations", "", Patterns::Anything(),
                      "Problem = nnpp: C_k(x, 0), one muparser expression in x, y, z per "
                      "species, separated by ';' (as many as Valences).");
    prm.declare_entry("Initial phase", "", Patterns::Anything(),
                      "Problem = nnpp: expression in x, y, z; solid (1) where > 0, liquid "
                      "elsewhere. Empty: solid where C_(Phase species) >= Saturation "
                      "concentration if a phase species is set, else all liquid.");
    prm.declare_entry("Boundary potential", "0", Patterns::Anything(),
                      "Problem = nnpp: phi(x, t) on the volume-constraint layer (the "
                      "Dirichlet layer of the Poisson equation; Discretization/Volume "
                      "constraint layer must be non-zero, delta + dx/2 recommended).");
    prm.declare_entry("Boundary concentrations", "", Patterns::Anything(),
                      "Problem = nnpp, Species boundary = dirichlet: C_k(x, t) on the layer, "
                      "one expression per species separated by ';'.");
    prm.declare_entry("Constants", "", Patterns::Anything(),
                      "Problem = nnpp: constants usable in the expressions, e.g. 'c0=0.1, L=2'.");
    prm.declare_entry("End time", "1", Patterns::Double(),
                      "Problem = nnpp: final time (> 0, at least one NNPP/Time step).");
    prm.leave_subsection();
  }

  template <int dim>
  void
  NnppRunParameters<dim>::parse_parameters(ParameterHandler &p)
  {
    p.enter_subsection("Geometry");
    domain = Domain<dim>::create(p);
    p.leave_subsection();
    p.enter_subsection("Discretization");
    lattice.parse_parameters(p);
    p.leave_subsection();
    check_parameter(lattice.layer_thickness > 0., "Discretization/Volume constraint layer",
                    lattice.layer_thickness,
                    "a non-zero thickness for Problem = nnpp (phi is prescribed on the layer; "
                    "delta + dx/2 recommended)");

    model.parse_parameters(p);
    const unsigned int n = model.n_species();
    p.enter_subsection("NNPP");
    initial_concentrations  = expression_list(p.get("Initial concentrations"));
    initial_phase           = p.get("Initial phase");
    boundary_potential      = p.get("Boundary potential");
    boundary_concentrations = expression_list(p.get("Boundary concentrations"));
    constants               = p.get("Constants");
    end_time                = p.get_double("End time");
    p.leave_subsection();
    const auto count = [n](const std::vector<std::string> &v) {
      return std::to_string(v.size()) + " expressions (there are " + std::to_string(n) +
             " valences)";
    };
    check_parameter(initial_concentrations.size() == n, "NNPP/Initial concentrations",
                    count(initial_concentrations),
                    "one expression per species, separated by ';'");
    check_parameter(model.species_boundary != "dirichlet" || boundary_concentrations.size() == n,
                    "NNPP/Boundary concentrations", count(boundary_concentrations),
                    "one expression per species for Species boundary = dirichlet");
    check_parameter(end_time >= model.time_step * (1. - 1e-12), "NNPP/End time", end_time,
                    "a value of at least one NNPP/Time step");

    p.enter_subsection("Output");
    output_directory     = p.get("Directory");
    snapshot_interval    = p.get_integer("Snapshot interval");
    time_series_interval = p.get_integer("Time series interval");
    p.leave_subsection();

    // Surface expression errors now, named, rather than in the middle of a run.
    for (unsigned int k = 0; k < n; ++k)
      make_function<dim>(initial_concentrations[k], constants, "NNPP/Initial concentrations");
    if (!boundary_concentrations.empty())
      for (unsigned int k = 0; k < boundary_concentrations.size(); ++k)
        make_function<dim>(boundary_concentrations[k], constants, "NNPP/Boundary concentrations");
    make_function<dim>(boundary_potential, constants, "NNPP/Boundary potential");
    if (!initial_phase.empty())
      make_function<dim>(initial_phase, constants, "NNPP/Initial phase");
  }

  template <int dim>
  std::vector<NnppDiagnostics>
  run_nnpp(const NnppRunParameters<dim> &prm,
           const MPI_Comm                comm,
           const bool                    verbose,
           const std::function<void(const Discretization<dim> &, const NnppSolver<dim> &)>
             &on_finish)
  {
    const bool         root = Utilities::MPI::this_mpi_process(comm) == 0;
    const unsigned int n    = prm.model.n_species();

    Discretization<dim> disc(comm);
    disc.setup(*prm.domain, prm.lattice);

    // Each callback owns its parser and sets the time before evaluating.
    auto phi_b = std::shared_ptr<FunctionParser<dim>>(
      make_function<dim>(prm.boundary_potential, prm.constants, "NNPP/Boundary potential"));
    std::vector<std::shared_ptr<FunctionParser<dim>>> c_b;
    for (const auto &e : prm.boundary_concentrations)
      c_b.emplace_back(make_function<dim>(e, prm.constants, "NNPP/Boundary concentrations"));

    NnppSources<dim> sources;
    sources.boundary_potential = [phi_b](const Point<dim> &x, const double t) {
      phi_b->set_time(t);
      return phi_b->value(x);
    };
    if (!c_b.empty())
      sources.boundary_concentration = [c_b](const unsigned int k, const Point<dim> &x,
                                             const double t) {
        c_b[k]->set_time(t);
        return c_b[k]->value(x);
      };

    NnppSolver<dim> solver(disc, prm.model, sources);
    for (unsigned int k = 0; k < n; ++k)
      {
        const auto f =
          make_function<dim>(prm.initial_concentrations[k], prm.constants, "NNPP/Initial concentrations");
        f->set_time(0.);
        solver.set_concentration(k, [&f](const Point<dim> &x) { return f->value(x); });
      }
    if (!prm.initial_phase.empty())
      {
        const auto f = make_function<dim>(prm.initial_phase, prm.constants, "NNPP/Initial phase");
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          solver.phase.local_element(i) = f->value(disc.position[i]) > 0. ? 1. : 0.;
      }
    else if (prm.model.phase_species >= 0)
      // As the diffusion solver's corrosion runs: solid where C >= C_sat (2.79).
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        solver.phase.local_element(i) =
          solver.C[prm.model.phase_species].local_element(i) >= prm.model.saturation ? 1. : 0.;
    solver.phase.update_ghost_values();
    solver.phase_changed();

    const double       dt      = prm.model.time_step;
    const unsigned int n_steps = (unsigned int)std::llround(prm.end_time / dt);

    const bool                  files = !prm.output_directory.empty();
    std::unique_ptr<NodeOutput<dim>> vtu;
    std::unique_ptr<TimeSeries>      csv;
    std::vector<std::string>         names;
    for (unsigned int k = 0; k < n; ++k)
      names.push_back("C_" + std::to_string(k));
    if (files)
      {
        vtu = std::make_unique<NodeOutput<dim>>(disc, prm.output_directory, "solution");
        std::vector<std::string> columns{"time"};
        for (unsigned int k = 0; k < n; ++k)
          columns.push_back("amount_" + std::to_string(k));
        columns.push_back("solid_volume");
        columns.push_back("max_abs_phi");
        csv = std::make_unique<TimeSeries>(comm, prm.output_directory + "/time_series.csv", columns);
      }

    std::vector<NnppDiagnostics> history;
    const auto record = [&](const unsigned int step, const bool snapshot) {
      // phi of the current concentrations (the step's phi is that of C^n).
      solver.solve_potential();
      NnppDiagnostics d;
      d.time = solver.time();
      for (unsigned int k = 0; k < n; ++k)
        d.amount.push_back(solver.mass(k));
      double solid = 0., phi_max = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (disc.region[i] == Discretization<dim>::interior)
          {
            solid += disc.volume[i] * solver.phase.local_element(i);
            phi_max = std::max(phi_max, std::abs(solver.phi.local_element(i)));
          }
      d.solid_volume = Utilities::MPI::sum(solid, comm);
      d.max_abs_phi  = Utilities::MPI::max(phi_max, comm);
      history.push_back(d);
      if (csv)
        {
          std::vector<double> row{d.time};
          row.insert(row.end(), d.amount.begin(), d.amount.end());
          row.push_back(d.solid_volume);
          row.push_back(d.max_abs_phi);
          csv->add_row(row);
        }
      if (vtu && snapshot)
        {
          std::vector<std::pair<std::string, const Vector *>> fields;
          for (unsigned int k = 0; k < n; ++k)
            fields.emplace_back(names[k], &solver.C[k]);
          fields.emplace_back("phi", &solver.phi);
          fields.emplace_back("phase", &solver.phase);
          vtu->write(d.time, step, fields);
        }
    };

    record(0, true);
    for (unsigned int step = 1; step <= n_steps; ++step)
      {
        solver.step();
        const bool last     = step == n_steps;
        const bool snapshot = last || (prm.snapshot_interval > 0 && step % prm.snapshot_interval == 0);
        if (last || snapshot || step % prm.time_series_interval == 0)
          record(step, snapshot);
      }
    if (verbose && root)
      {
        const auto &d = history.back();
        std::cout << "Final: t = " << d.time << ", amounts =";
        for (const double a : d.amount)
          std::cout << " " << a;
        std::cout << ", solid volume = " << d.solid_volume << ", max |phi| = " << d.max_abs_phi
                  << " (" << disc.n_global() << " nodes, " << n_steps << " steps)" << std::endl;
      }
    if (on_finish)
      on_finish(disc, solver);
    return history;
  }

  template struct NnppRunParameters<1>;
  template struct NnppRunParameters<2>;
  template struct NnppRunParameters<3>;
  template std::vector<NnppDiagnostics>
  run_nnpp(const NnppRunParameters<1> &, const MPI_Comm, const bool,
           const std::function<void(const Discretization<1> &, const NnppSolver<1> &)> &);
  template std::vector<NnppDiagnostics>
  run_nnpp(const NnppRunParameters<2> &, const MPI_Comm, const bool,
           const std::function<void(const Discretization<2> &, const NnppSolver<2> &)> &);
  template std::vector<NnppDiagnostics>
  run_nnpp(const NnppRunParameters<3> &, const MPI_Comm, const bool,
           const std::function<void(const Discretization<3> &, const NnppSolver<3> &)> &);
} // namespace PeriDEAL
