#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/timer.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/expressions.h>
#include <perideal/io/node_output.h>
#include <perideal/io/time_series.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include <cmath>
#include <iomanip>

namespace PeriDEAL
{
  namespace
  {
    // A dim-component muparser function "f1; f2[; f3]" of x, y, z, t.
    template <int dim>
    std::unique_ptr<FunctionParser<dim>>
    vector_function(const std::string &text, const std::string &parameter)
    {
      auto       f     = std::make_unique<FunctionParser<dim>>(dim);
      const auto parts = Utilities::split_string_list(text, ';');
      check_parameter(parts.size() == dim, parameter, text,
                      std::to_string(dim) + " expressions separated by ';'");
      try
        {
          f->initialize(FunctionParser<dim>::default_variable_names() + ",t", parts, expression_constants(dim), true);
          f->value(Point<dim>(), 0);
        }
      catch (std::exception &)
        {
          throw ParameterError(parameter, text, "muparser expressions in x, y, z, t");
        }
      return f;
    }
  } // namespace

  template <int dim>
  void
  MechanicsRunParameters<dim>::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Model");
    prm.enter_subsection("Bond-based");
    BondBasedModelParameters::declare_parameters(prm);
    prm.leave_subsection();
    prm.leave_subsection();

    prm.enter_subsection("Mechanics");
    prm.declare_entry("Density", "1", Patterns::Double(), "Mass density rho (> 0).");
    prm.declare_entry("Initial velocity", "0; 0; 0", Patterns::Anything(),
                      "Initial velocity, 'dim' expressions in x, y, z separated by ';' "
                      "(extra components are ignored).");
    prm.declare_entry("Body force", "0; 0; 0", Patterns::Anything(),
                      "Body force density b of (2.20), 'dim' expressions separated by ';'.");
    prm.declare_entry("Prescribed velocities", "", Patterns::Anything(),
                      "Node sets moving with a prescribed velocity: items "
                      "'LEVEL SET : VX; VY[; VZ]' separated by '|'; the set is "
                      "{LEVEL SET <= 0}; later items override earlier ones.");
    prm.declare_entry("Pre-cracks", "", Patterns::Anything(),
                      "2D: segments 'x0, y0, x1, y1' separated by ';'; bonds crossing "
                      "them are broken before the first step.");
    prm.leave_subsection();
  }

  template <int dim>
  void
  MechanicsRunParameters<dim>::parse_parameters(ParameterHandler &p)
  {
    p.enter_subsection("Geometry");
    domain = Domain<dim>::create(p);
    p.leave_subsection();
    p.enter_subsection("Discretization");
    lattice.parse_parameters(p);
    p.leave_subsection();
    p.enter_subsection("Model");
    p.enter_subsection("Bond-based");
    model.parse_parameters(p);
    p.leave_subsection();
    p.leave_subsection();

    p.enter_subsection("Mechanics");
    density = p.get_double("Density");
    check_parameter(density > 0., "Mechanics/Density", density, "a positive number");
    auto first_dim = [](const std::string &text) {
      auto parts = Utilities::split_string_list(text, ';');
      if (parts.size() > dim)
        parts.resize(dim);
      std::string joined;
      for (unsigned int d = 0; d < parts.size(); ++d)
        joined += (d ? ";" : "") + parts[d];
      return joined;
    };
    initial_velocity = first_dim(p.get("Initial velocity"));
    body_force       = first_dim(p.get("Body force"));
    prescribed_velocities.clear();
    for (const auto &item : Utilities::split_string_list(p.get("Prescribed velocities"), '|'))
      {
        const auto colon = item.find(':');
        check_parameter(colon != std::string::npos, "Mechanics/Prescribed velocities", item,
                        "items 'LEVEL SET : VX; VY[; VZ]' separated by '|'");
        prescribed_velocities.emplace_back(item.substr(0, colon),
                                           first_dim(item.substr(colon + 1)));
      }
    precracks.clear();
    for (const auto &item : Utilities::split_string_list(p.get("Pre-cracks"), ';'))
      {
        std::vector<double> v;
        try
          {
            v = Utilities::string_to_double(Utilities::split_string_list(item, ','));
          }
        catch (...)
          {
          }
        check_parameter(dim == 2 && v.size() == 4, "Mechanics/Pre-cracks", item,
                        "2D segments 'x0, y0, x1, y1' separated by ';'");
        Point<dim> a, b;
        for (unsigned int d = 0; d < dim; ++d)
          {
            a[d] = v[d];
            b[d] = v[2 + d];
          }
        precracks.emplace_back(a, b);
      }
    p.leave_subsection();

    p.enter_subsection("Time stepping");
    time_step = p.get_double("Time step");
    end_time  = p.get_double("End time");
    p.leave_subsection();
    check_parameter(time_step >= 0., "Time stepping/Time step", time_step,
                    "a positive number, or 0 for 0.9 x the critical step (3.8)");
    check_parameter(end_time > 0., "Time stepping/End time", end_time, "a positive number");

    p.enter_subsection("Output");
    output_directory     = p.get("Directory");
    snapshot_interval    = p.get_integer("Snapshot interval");
    time_series_interval = p.get_integer("Time series interval");
    progress_interval    = p.get_double("Progress interval");
    p.leave_subsection();
  }

  template <int dim>
  MechanicsSolver<dim>::MechanicsSolver(const MPI_Comm comm, const MechanicsRunParameters<dim> &p)
    : mpi_communicator(comm)
    , prm(p)
    , disc(comm)
  {}

  template <int dim>
  MechanicsSolver<dim>::~MechanicsSolver() = default;

  template <int dim>
  double
  MechanicsSolver<dim>::total_energy() const
  {
    return verlet->kinetic_energy() + verlet->strain_energy();
  }

  template <int dim>
  void
  MechanicsSolver<dim>::setup()
  {
    disc.setup(*prm.domain, prm.lattice);
    op = std::make_unique<BondBasedOperator<dim>>(disc, prm.model);
    for (const auto &crack : prm.precracks)
      op->add_precrack(crack.first, crack.second);

    const double dt_critical = op->critical_time_step(prm.density);
    double       dt          = prm.time_step;
    if (dt == 0.) // the largest step <= 0.9 x bound that ends on the end time
      dt = prm.end_time / std::ceil(prm.end_time / (0.9 * dt_critical));
    verlet      = std::make_unique<VelocityVerlet<dim>>(*op, prm.density, dt);
    total_steps = (unsigned int)std::llround(prm.end_time / dt);

    const auto v0 = vector_function<dim>(prm.initial_velocity, "Mechanics/Initial velocity");
    const auto b  = vector_function<dim>(prm.body_force, "Mechanics/Body force");
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        {
          verlet->velocity[d].local_element(i)   = v0->value(disc.position[i], d);
          verlet->body_force[d].local_element(i) = b->value(disc.position[i], d);
        }
    for (const auto &[region, velocity] : prm.prescribed_velocities)
      {
        // An unbounded level set: the region is {f <= 0}.
        Point<dim> lo, hi;
        for (unsigned int d = 0; d < dim; ++d)
          {
            lo[d] = -std::numeric_limits<double>::max();
            hi[d] = std::numeric_limits<double>::max();
          }
        const LevelSetDomain<dim> set(region, lo, hi);
        const auto        v = vector_function<dim>(velocity, "Mechanics/Prescribed velocities");
        std::vector<bool> mask(disc.n_owned());
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          mask[i] = set.inside(disc.position[i]);
        Tensor<1, dim> value;
        for (unsigned int d = 0; d < dim; ++d)
          value[d] = v->value(Point<dim>(), d);
        verlet->add_prescribed_velocity(mask, value);
      }
    verlet->initialize();
  }

  template <int dim>
  void
  MechanicsSolver<dim>::run(const unsigned int max_steps)
  {
    ConditionalOStream pcout(std::cout, Utilities::MPI::this_mpi_process(mpi_communicator) == 0);
    if (!op)
      setup();
    NodeOutput<dim> vtu(disc, prm.output_directory, "solution");
    TimeSeries      csv(mpi_communicator, prm.output_directory + "/time_series.csv",
                   {"time", "kinetic_energy", "strain_energy", "total_energy", "broken_bonds",
                    "max_damage"});
    Vector damage, speed;
    disc.initialize_vector(damage);
    disc.initialize_vector(speed);

    pcout << "Bond-based PD in " << dim << "D: " << disc.n_global() << " nodes, "
          << disc.n_global_bonds() << " bonds, c = " << op->micromodulus()
          << ", s0 = " << op->critical_stretch() << ", dt = " << verlet->time_step()
          << " (critical " << verlet->critical_time_step() << "), " << total_steps << " steps"
          << std::endl;

    auto record = [&](const bool snapshot) {
      op->damage(damage);
      const double ek = verlet->kinetic_energy(), es = verlet->strain_energy();
      csv.add_row({verlet->time(), ek, es, ek + es, double(op->n_broken_bonds()),
                   damage.linfty_norm()});
      if (snapshot)
        {
          std::vector<std::pair<std::string, const Vector *>> fields;
          const char *names[3] = {"u_x", "u_y", "u_z"};
          const char *vnames[3] = {"v_x", "v_y", "v_z"};
          for (unsigned int d = 0; d < dim; ++d)
            fields.emplace_back(names[d], &verlet->displacement[d]);
          for (unsigned int d = 0; d < dim; ++d)
            fields.emplace_back(vnames[d], &verlet->velocity[d]);
          fields.emplace_back("damage", &damage);
          vtu.write(verlet->time(), verlet->step(), fields);
        }
    };
    record(true);
    Timer        wall;
    double       last_progress = 0.;
    unsigned int done          = 0;
    while (verlet->step() < total_steps && done < max_steps)
      {
        verlet->advance();
        ++done;
        const bool last = verlet->step() == total_steps;
        const bool snap = last || (prm.snapshot_interval > 0 &&
                                   verlet->step() % prm.snapshot_interval == 0);
        if (snap || last || verlet->step() % prm.time_series_interval == 0)
          record(snap);
        if (wall.wall_time() - last_progress >= prm.progress_interval && !last)
          {
            last_progress = wall.wall_time();
            pcout << "  step " << verlet->step() << "/" << total_steps << "  elapsed "
                  << std::fixed << std::setprecision(1) << last_progress << " s  remaining ~"
                  << last_progress / done * (total_steps - verlet->step()) << " s"
                  << std::defaultfloat << std::setprecision(6) << std::endl;
          }
      }
  }

  template struct MechanicsRunParameters<1>;
  template struct MechanicsRunParameters<2>;
  template struct MechanicsRunParameters<3>;
  template class MechanicsSolver<1>;
  template class MechanicsSolver<2>;
  template class MechanicsSolver<3>;
} // namespace PeriDEAL
