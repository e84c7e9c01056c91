#include <deal.II/base/conditional_ostream.h>
#include <deal.II/base/timer.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/expressions.h>
#include <perideal/io/checkpoint.h>
#include <perideal/io/node_output.h>
#include <perideal/io/time_series.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

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
    // {f <= 0} of an unbounded level set, evaluated at the owned nodes.
    template <int dim>
    std::vector<bool>
    region_mask(const Discretization<dim> &disc, const std::string &level_set)
    {
      Point<dim> lo, hi;
      for (unsigned int d = 0; d < dim; ++d)
        {
          lo[d] = -std::numeric_limits<double>::max();
          hi[d] = std::numeric_limits<double>::max();
        }
      const LevelSetDomain<dim> set(level_set, lo, hi);
      std::vector<bool>         mask(disc.n_owned());
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        mask[i] = set.inside(disc.position[i]);
      return mask;
    }

    // True if an expression uses the variable t (a token t, not part of a name).
    bool
    depends_on_time(const std::string &text)
    {
      for (std::size_t k = text.find('t'); k != std::string::npos; k = text.find('t', k + 1))
        {
          const auto name_char = [](const char c) { return std::isalnum((unsigned char)c) || c == '_'; };
          if ((k == 0 || !name_char(text[k - 1])) && (k + 1 == text.size() || !name_char(text[k + 1])))
            return true;
        }
      return false;
    }

    // The first dim of the ';'-separated expressions (extra ones are ignored,
    // so that one parameter file serves every dimension).
    template <int dim>
    std::string
    first_dim(const std::string &text)
    {
      auto parts = Utilities::split_string_list(text, ';');
      if (parts.size() > dim)
        parts.resize(dim);
      std::string joined;
      for (unsigned int d = 0; d < parts.size(); ++d)
        joined += (d ? ";" : "") + parts[d];
      return joined;
    }

    std::vector<double>
    numbers(const std::string &text)
    {
      try
        {
          return Utilities::string_to_double(Utilities::split_string_list(text, ','));
        }
      catch (...)
        {
          return {};
        }
    }

    // Items "LEVEL SET : EXPRESSIONS[ : THICKNESS]" separated by '|'.
    template <int dim>
    std::vector<typename MechanicsRunParameters<dim>::Region>
    parse_regions(const std::string &text, const std::string &parameter, const bool with_thickness)
    {
      std::vector<typename MechanicsRunParameters<dim>::Region> regions;
      const std::string format = with_thickness ? "items 'LEVEL SET : TX; TY[; TZ] : THICKNESS' separated by '|'" :
                                                  "items 'LEVEL SET : VX; VY[; VZ]' separated by '|'";
      for (const auto &item : Utilities::split_string_list(text, '|'))
        {
          const auto parts = Utilities::split_string_list(item, ':');
          check_parameter(parts.size() == (with_thickness ? 3u : 2u), parameter, item, format);
          typename MechanicsRunParameters<dim>::Region r;
          r.level_set = parts[0];
          r.value     = first_dim<dim>(parts[1]);
          if (with_thickness)
            {
              const auto h = numbers(parts[2]);
              check_parameter(h.size() == 1 && h[0] > 0., parameter, item,
                              format + " with a positive layer thickness");
              r.thickness = h[0];
            }
          regions.push_back(r);
        }
      return regions;
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
    // Also declared by the static runs (same entries: declaring twice is harmless).
    prm.enter_subsection("LPS");
    LPSModelParameters::declare_parameters(prm);
    prm.leave_subsection();
    prm.leave_subsection();

    prm.enter_subsection("Mechanics");
    prm.declare_entry("Model", "bond-based", Patterns::Selection("bond-based|LPS"),
                      "bond-based: PMB/GPBM or linearized bond-based PD (entries in "
                      "Model/Bond-based); LPS: linearized state-based LPS (2.18)-(2.19) with "
                      "bond breaking on the linearized stretch (entries in Model/LPS; 2D: "
                      "plane strain; 2D/3D only).");
    prm.declare_entry("Density", "1", Patterns::Double(), "Mass density rho (> 0).");
    prm.declare_entry("Initial displacement", "0; 0; 0", Patterns::Anything(),
                      "Initial displacement, 'dim' expressions in x, y, z separated by ';'.");
    prm.declare_entry("Initial velocity", "0; 0; 0", Patterns::Anything(),
                      "Initial velocity, 'dim' expressions in x, y, z separated by ';' "
                      "(extra components are ignored).");
    prm.declare_entry("Body force", "0; 0; 0", Patterns::Anything(),
                      "Body force density b of (2.20), 'dim' expressions in x, y, z (and t: "
                      "then re-evaluated every step) separated by ';'.");
    prm.declare_entry("Prescribed velocities", "", Patterns::Anything(),
                      "Node sets moving with a prescribed velocity v(x, t): items "
                      "'LEVEL SET : VX; VY[; VZ]' (expressions in x, y, z, t) separated by "
                      "'|'; the set is {LEVEL SET <= 0}; later items override earlier ones. "
                      "Held nodes drift with v(t + dt/2) over a step.");
    prm.declare_entry("Prescribed displacements", "", Patterns::Anything(),
                      "Node sets with a prescribed displacement u(x, t): items "
                      "'LEVEL SET : UX; UY[; UZ]' (expressions in x, y, z, t) separated by "
                      "'|'; they override prescribed velocities on shared nodes. Their "
                      "reaction forces follow those of the velocity sets in the CSV.");
    prm.declare_entry("Tractions", "", Patterns::Anything(),
                      "Surface tractions T (force per area) applied as the body force "
                      "T / h on the nodes of a layer of thickness h (Sect. 2.2): items "
                      "'LEVEL SET : TX; TY[; TZ] : h' separated by '|' (expressions in x, y, z, "
                      "t; with t they are re-evaluated every step).");
    prm.declare_entry("Pre-cracks", "", Patterns::Anything(),
                      "2D: segments 'x0, y0, x1, y1'; 3D: planar polygons 'x0, y0, z0, x1, "
                      "y1, z1, x2, y2, z2[, ...]'; separated by ';'. Bonds crossing them are "
                      "broken before the first step.");
    prm.enter_subsection("Hybrid");
    prm.declare_entry("Quadrature", "standard", Patterns::Selection("standard|hybrid adaptive"),
                      "standard: the standard scheme (3.1) on every node. hybrid adaptive: "
                      "the adaptive hybrid configuration of Sect. 3.3 (bond-based PMB only): "
                      "standard scheme on Omega_s, WLS collocation of the linearized bond "
                      "force on Omega_w; a bond of Omega_w with stretch >= Sigma s0 (3.80) "
                      "moves the families of both its end nodes to Omega_s before the next "
                      "force evaluation.");
    prm.declare_entry("Sigma", "0.95", Patterns::Double(),
                      "Margin sigma of the switching criterion (3.80), in (0, 1).");
    prm.declare_entry("Switching interval", "1", Patterns::Integer(),
                      "Test (3.80) every this many steps (>= 1; 1: every step as in the "
                      "source). Bonds passing s0 in between are counted in the CSV column "
                      "overstretched_bonds.");
    WlsParameters::declare_parameters(prm);
    prm.declare_entry("Boundary width", "1", Patterns::Double(),
                      "Initial Omega_s: interior nodes closer than this many horizons (>= 1: "
                      "the WLS rows assume a full horizon) to the boundary of the body.");
    prm.declare_entry("Pre-crack width", "2", Patterns::Double(),
                      "Initial Omega_s: nodes closer than this many horizons (>= 0) to a 2D "
                      "pre-crack segment (must be 0 in 3D: use 'Standard region').");
    prm.declare_entry("Standard region", "0", Patterns::Anything(),
                      "Initial Omega_s also holds the nodes where this expression in x, y, z "
                      "is > 0.");
    prm.leave_subsection();
    prm.leave_subsection();

    prm.enter_subsection("Measurements");
    prm.declare_entry("Crack origin", "", Patterns::Anything(),
                      "Crack measurement (2D/3D, in the x-y plane): the point the crack "
                      "grows from (a pre-crack tip), 'x, y[, z]'; empty: off.");
    prm.declare_entry("Crack region", "", Patterns::Anything(),
                      "Level set: only nodes with f(x, y, z) <= 0 belong to the measured "
                      "crack path; empty: all nodes.");
    prm.declare_entry("Damage threshold", "0.35", Patterns::Double(),
                      "Nodes of the crack region with damage (2.36) >= this value (in (0, 1]) "
                      "are crack nodes.");
    prm.declare_entry("Crack fit radii", "0, 1e300", Patterns::Anything(),
                      "'r_min, r_max': crack nodes at this distance from the origin enter the "
                      "total-least-squares line whose angle to the x axis is the crack angle.");
    prm.declare_entry("Energy circle", "", Patterns::Anything(),
                      "'x, y[, z], R': kinetic + strain energy of the nodes within R of the "
                      "center go to the CSV; empty: off.");
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
    p.enter_subsection("LPS");
    lps.parse_parameters(p);
    p.leave_subsection();
    p.leave_subsection();

    p.enter_subsection("Mechanics");
    model_type = p.get("Model");
    check_parameter(model_type == "bond-based" || dim >= 2, "Mechanics/Model", model_type,
                    "bond-based in 1D (LPS is 2D/3D)");
    density = p.get_double("Density");
    check_parameter(density > 0., "Mechanics/Density", density, "a positive number");
    initial_displacement = first_dim<dim>(p.get("Initial displacement"));
    initial_velocity     = first_dim<dim>(p.get("Initial velocity"));
    body_force       = first_dim<dim>(p.get("Body force"));
    prescribed_velocities =
      parse_regions<dim>(p.get("Prescribed velocities"), "Mechanics/Prescribed velocities", false);
    prescribed_displacements = parse_regions<dim>(p.get("Prescribed displacements"),
                                                  "Mechanics/Prescribed displacements", false);
    tractions = parse_regions<dim>(p.get("Tractions"), "Mechanics/Tractions", true);
    precracks.clear();
    for (const auto &item : Utilities::split_string_list(p.get("Pre-cracks"), ';'))
      {
        const auto v = numbers(item);
        check_parameter((dim == 2 && v.size() == 4) ||
                          (dim == 3 && v.size() >= 9 && v.size() % 3 == 0),
                        "Mechanics/Pre-cracks", item,
                        "2D segments 'x0, y0, x1, y1' or 3D polygons of at least 3 "
                        "vertices 'x0, y0, z0, x1, y1, z1, ...', separated by ';'");
        std::vector<Point<dim>> polygon(v.size() / dim);
        for (unsigned int k = 0; k < polygon.size(); ++k)
          for (unsigned int d = 0; d < dim; ++d)
            polygon[k][d] = v[k * dim + d];
        precracks.push_back(polygon);
      }
    p.enter_subsection("Hybrid");
    quadrature = p.get("Quadrature");
    hybrid.sigma = p.get_double("Sigma");
    check_parameter(hybrid.sigma > 0. && hybrid.sigma < 1., "Mechanics/Hybrid/Sigma",
                    hybrid.sigma, "a number in (0, 1)");
    hybrid.wls.parse_parameters(p);
    const long interval = p.get_integer("Switching interval");
    check_parameter(interval >= 1, "Mechanics/Hybrid/Switching interval", interval,
                    "an integer >= 1");
    hybrid.check_interval = (unsigned int)interval;
    check_parameter(hybrid.wls.order == 2 || hybrid.wls.order == 4 ||
                      (dim == 1 && hybrid.wls.order == 6),
                    "Mechanics/Hybrid/Order", hybrid.wls.order,
                    dim == 1 ? "2, 4 or 6 in 1D" : "2 or 4 in 2D/3D");
    boundary_width  = p.get_double("Boundary width");
    precrack_width  = p.get_double("Pre-crack width");
    standard_region = p.get("Standard region");
    check_parameter(boundary_width >= 1., "Mechanics/Hybrid/Boundary width", boundary_width,
                    "a number >= 1 (horizons)");
    check_parameter(precrack_width >= 0. && (dim != 3 || precrack_width == 0. ||
                                             quadrature == "standard"),
                    "Mechanics/Hybrid/Pre-crack width", precrack_width,
                    dim == 3 ? "0 in 3D (use 'Standard region')" : "a number >= 0 (horizons)");
    check_parameter(quadrature == "standard" || model_type == "bond-based",
                    "Mechanics/Hybrid/Quadrature", quadrature,
                    "standard for the LPS model (hybrid adaptive is bond-based)");
    check_parameter(quadrature == "standard" || !model.linearized, "Mechanics/Hybrid/Quadrature",
                    quadrature, "standard for the linearized bond-based model");
    p.leave_subsection();
    p.leave_subsection();

    p.enter_subsection("Measurements");
    const std::string origin = p.get("Crack origin");
    measure_crack            = !origin.empty();
    if (measure_crack)
      {
        check_parameter(dim >= 2, "Measurements/Crack origin", origin,
                        "empty in 1D (the crack angle is measured in the x-y plane)");
        crack_origin = parse_point<dim>(origin, "Measurements/Crack origin");
      }
    crack_region     = p.get("Crack region");
    damage_threshold = p.get_double("Damage threshold");
    check_parameter(damage_threshold > 0. && damage_threshold <= 1.,
                    "Measurements/Damage threshold", damage_threshold, "a number in (0, 1]");
    const auto radii = numbers(p.get("Crack fit radii"));
    check_parameter(radii.size() == 2 && radii[0] >= 0. && radii[1] > radii[0],
                    "Measurements/Crack fit radii", p.get("Crack fit radii"),
                    "'r_min, r_max' with 0 <= r_min < r_max");
    crack_fit_min_radius = radii[0];
    crack_fit_max_radius = radii[1];
    const std::string circle = p.get("Energy circle");
    energy_radius            = 0.;
    if (!circle.empty())
      {
        const auto v = numbers(circle);
        check_parameter(v.size() == dim + 1 && v[dim] > 0., "Measurements/Energy circle", circle,
                        "'x, y[, z], R' with dim coordinates and R > 0");
        for (unsigned int d = 0; d < dim; ++d)
          energy_center[d] = v[d];
        energy_radius = v[dim];
      }
    p.leave_subsection();

    p.enter_subsection("Time stepping");
    time_step = p.get_double("Time step");
    end_time  = p.get_double("End time");
    p.leave_subsection();
    check_parameter(time_step >= 0., "Time stepping/Time step", time_step,
                    "a positive number, or 0 for 0.9 x the critical step");
    check_parameter(end_time > 0., "Time stepping/End time", end_time, "a positive number");

    p.enter_subsection("Output");
    output_directory     = p.get("Directory");
    snapshot_interval    = p.get_integer("Snapshot interval");
    time_series_interval = p.get_integer("Time series interval");
    checkpoint_interval  = p.get_integer("Checkpoint interval");
    resume               = p.get_bool("Resume");
    write_node_table     = p.get_bool("Write node table");
    progress_interval    = p.get_double("Progress interval");
    p.leave_subsection();
  }

  template <int dim>
  std::vector<bool>
  MechanicsSolver<dim>::initial_standard_region() const
  {
    const double delta = prm.lattice.delta;
    check_parameter(prm.domain->has_signed_distance(), "Mechanics/Hybrid/Quadrature",
                    prm.quadrature, "standard for a geometry without a signed distance");
    FunctionParser<dim> region(1);
    try
      {
        region.initialize(FunctionParser<dim>::default_variable_names(), prm.standard_region,
                          expression_constants(dim));
        region.value(Point<dim>());
      }
    catch (std::exception &)
      {
        throw ParameterError("Mechanics/Hybrid/Standard region", prm.standard_region,
                             "a muparser expression in x, y, z");
      }
    std::vector<bool> standard(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const Point<dim> &x = disc.position[i];
        bool s = prm.domain->signed_distance(x) > -prm.boundary_width * delta ||
                 region.value(x) > 0.;
        if constexpr (dim == 2)
          for (const auto &crack : prm.precracks)
            {
              // Distance to the segment [a, b].
              const Tensor<1, dim> ab = crack[1] - crack[0], ax = x - crack[0];
              const double t = std::clamp(ab * ax / std::max(ab * ab, 1e-300), 0., 1.);
              s = s || (ax - t * ab).norm() < prm.precrack_width * delta;
            }
        standard[i] = s;
      }
    return standard;
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
    n_global_bonds = disc.n_global_bonds();
    if (prm.model_type == "LPS")
      {
        if constexpr (dim >= 2)
          {
            lps = std::make_unique<LinearizedLPSOperator<dim>>(disc, prm.lps);
            op  = make_mechanics_model(*lps);
          }
        else
          throw ParameterError("Mechanics/Model", prm.model_type, "bond-based in 1D");
      }
    else
      {
        check_parameter(prm.model_type == "bond-based", "Mechanics/Model", prm.model_type,
                        "bond-based|LPS");
        bond_based = std::make_unique<BondBasedOperator<dim>>(disc, prm.model);
        if (prm.quadrature == "hybrid adaptive")
          {
            auto model = std::make_unique<HybridBondBasedModel<dim>>(
              *bond_based, prm.model.omega, prm.hybrid, initial_standard_region());
            hybrid = model.get();
            op     = std::move(model);
          }
        else
          op = make_mechanics_model(*bond_based);
      }
    for (const auto &crack : prm.precracks)
      op->add_precrack(crack);

    const double dt_critical = op->critical_time_step(prm.density);
    double       dt          = prm.time_step;
    if (dt == 0.) // the largest step <= 0.9 x bound that ends on the end time
      dt = prm.end_time / std::ceil(prm.end_time / (0.9 * dt_critical));
    verlet      = std::make_unique<VelocityVerlet<dim>>(*op, prm.density, dt);
    total_steps = (unsigned int)std::llround(prm.end_time / dt);

    const auto v0 = vector_function<dim>(prm.initial_velocity, "Mechanics/Initial velocity");
    const auto u0 = prm.initial_displacement.empty() ?
                      nullptr :
                      vector_function<dim>(prm.initial_displacement, "Mechanics/Initial displacement");
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        {
          verlet->displacement[d].local_element(i) = u0 ? u0->value(disc.position[i], d) : 0.;
          verlet->velocity[d].local_element(i)     = v0->value(disc.position[i], d);
        }
    // Body force and tractions (T / h on the nodes of the layer, so that
    // sum b V = T x area); re-evaluated every step if an expression has t.
    struct Load
    {
      std::shared_ptr<FunctionParser<dim>> f;
      std::vector<bool>                    mask; // empty: all nodes
      double                               scale;
    };
    auto loads = std::make_shared<std::vector<Load>>();
    bool time_dependent = depends_on_time(prm.body_force);
    loads->push_back({vector_function<dim>(prm.body_force, "Mechanics/Body force"), {}, 1.});
    for (const auto &r : prm.tractions)
      {
        loads->push_back({vector_function<dim>(r.value, "Mechanics/Tractions"),
                          region_mask(disc, r.level_set), 1. / r.thickness});
        time_dependent = time_dependent || depends_on_time(r.value);
      }
    const Discretization<dim> *dp = &disc;
    const auto evaluate_loads = [loads, dp](const double t, typename VelocityVerlet<dim>::VectorField &b) {
      for (auto &c : b)
        c = 0.;
      for (const Load &l : *loads)
        {
          l.f->set_time(t);
          for (unsigned int i = 0; i < dp->n_owned(); ++i)
            if (l.mask.empty() || l.mask[i])
              for (unsigned int d = 0; d < dim; ++d)
                b[d].local_element(i) += l.scale * l.f->value(dp->position[i], d);
        }
    };
    if (time_dependent)
      verlet->set_body_force_function(evaluate_loads);
    else
      evaluate_loads(0., verlet->body_force);

    held_by.assign(disc.n_owned(), -1);
    int k = 0;
    for (const auto &r : prm.prescribed_velocities)
      {
        const auto mask = region_mask(disc, r.level_set);
        std::shared_ptr<FunctionParser<dim>> v =
          vector_function<dim>(r.value, "Mechanics/Prescribed velocities");
        verlet->add_prescribed_velocity(mask, [v](const Point<dim> &x, const double t) {
          v->set_time(t);
          Tensor<1, dim> value;
          for (unsigned int d = 0; d < dim; ++d)
            value[d] = v->value(x, d);
          return value;
        });
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (mask[i])
            held_by[i] = k;
        ++k;
      }
    for (const auto &r : prm.prescribed_displacements)
      {
        const auto mask = region_mask(disc, r.level_set);
        std::shared_ptr<FunctionParser<dim>> u =
          vector_function<dim>(r.value, "Mechanics/Prescribed displacements");
        verlet->add_prescribed_displacement(mask, [u](const Point<dim> &x, const double t) {
          u->set_time(t);
          Tensor<1, dim> value;
          for (unsigned int d = 0; d < dim; ++d)
            value[d] = u->value(x, d);
          return value;
        });
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (mask[i])
            held_by[i] = k;
        ++k;
      }

    in_crack_region.assign(disc.n_owned(), prm.measure_crack);
    if (prm.measure_crack && !prm.crack_region.empty())
      in_crack_region = region_mask(disc, prm.crack_region);
    in_energy_circle.assign(disc.n_owned(), false);
    if (prm.energy_radius > 0.)
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        in_energy_circle[i] = disc.position[i].distance(prm.energy_center) <= prm.energy_radius;
    verlet->initialize();
  }

  template <int dim>
  MechanicsMeasurements
  MechanicsSolver<dim>::measure() const
  {
    Vector damage, W;
    disc.initialize_vector(damage);
    disc.initialize_vector(W);
    op->damage(damage);
    op->strain_energy_density(verlet->displacement, W);

    // Local sums: 0 kinetic, 1 strain, 2 circle kinetic, 3 circle strain,
    // 4..9 the weighted moments w, wx, wy, wxx, wxy, wyy of the fit, 10 count.
    double                 s[11] = {};
    double                 length = 0., max_damage = 0.;
    const double           rho = prm.density;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double V  = disc.volume[i];
        double       v2 = 0.;
        for (unsigned int d = 0; d < dim; ++d)
          v2 += verlet->velocity[d].local_element(i) * verlet->velocity[d].local_element(i);
        const double ek = 0.5 * rho * v2 * V, es = W.local_element(i) * V;
        s[0] += ek;
        s[1] += es;
        if (in_energy_circle[i])
          {
            s[2] += ek;
            s[3] += es;
          }
        const double phi = damage.local_element(i);
        max_damage       = std::max(max_damage, phi);
        if (!in_crack_region[i] || phi < prm.damage_threshold)
          continue;
        const double r = disc.position[i].distance(prm.crack_origin);
        length         = std::max(length, r);
        if (r < prm.crack_fit_min_radius || r > prm.crack_fit_max_radius)
          continue;
        // In the x-y plane (measure_crack is off in 1D; the index is kept
        // valid for the 1D instantiation).
        constexpr unsigned int Y = dim > 1 ? 1 : 0;
        const double x = disc.position[i][0] - prm.crack_origin[0],
                     y = disc.position[i][Y] - prm.crack_origin[Y];
        s[4] += V;
        s[5] += V * x;
        s[6] += V * y;
        s[7] += V * x * x;
        s[8] += V * x * y;
        s[9] += V * y * y;
        s[10] += 1.;
      }
    Utilities::MPI::sum(s, mpi_communicator, s);

    MechanicsMeasurements m;
    m.kinetic_energy        = s[0];
    m.strain_energy         = s[1];
    m.circle_kinetic_energy = s[2];
    m.circle_strain_energy  = s[3];
    m.crack_length          = Utilities::MPI::max(length, mpi_communicator);
    m.max_damage            = Utilities::MPI::max(max_damage, mpi_communicator);
    m.n_crack_nodes         = (unsigned long)s[10];
    m.crack_angle           = std::numeric_limits<double>::quiet_NaN();
    if (m.n_crack_nodes >= 3)
      {
        // Principal axis of the covariance: the total-least-squares line.
        const double w = s[4], mx = s[5] / w, my = s[6] / w;
        const double cxx = s[7] / w - mx * mx, cxy = s[8] / w - mx * my, cyy = s[9] / w - my * my;
        double       angle = 0.5 * std::atan2(2. * cxy, cxx - cyy) * 180. / M_PI;
        if (angle < 0.)
          angle += 180.;
        m.crack_angle = angle;
      }
    return m;
  }

  template <int dim>
  Tensor<1, dim>
  MechanicsSolver<dim>::reaction_force(const unsigned int k) const
  {
    Tensor<1, dim> R;
    const auto    &F = verlet->internal_force();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (held_by[i] == int(k))
        {
          const Tensor<1, dim> a = verlet->held_acceleration(i);
          for (unsigned int d = 0; d < dim; ++d)
            R[d] += (prm.density * a[d] - F[d].local_element(i) -
                     verlet->body_force[d].local_element(i)) *
                    disc.volume[i];
        }
    return Utilities::MPI::sum(R, mpi_communicator);
  }

  template <int dim>
  double
  MechanicsSolver<dim>::bond_updates_per_second_per_core() const
  {
    return stepping_time > 0. ? double(n_global_bonds) * stepped / stepping_time /
                                  Utilities::MPI::n_mpi_processes(mpi_communicator) :
                                0.;
  }

  template <int dim>
  std::vector<std::string>
  MechanicsSolver<dim>::time_series_columns() const
  {
    std::vector<std::string> c = {"time", "kinetic_energy", "strain_energy", "total_energy",
                                  "broken_bonds", "max_damage"};
    const char *xyz[3] = {"x", "y", "z"};
    for (unsigned int k = 0; k < n_prescribed_regions(); ++k)
      for (unsigned int d = 0; d < dim; ++d)
        c.push_back("reaction_" + std::to_string(k + 1) + "_" + xyz[d]);
    if (prm.measure_crack)
      for (const char *name : {"crack_angle", "crack_nodes", "crack_length", "crack_speed"})
        c.push_back(name);
    if (prm.energy_radius > 0.)
      for (const char *name : {"circle_kinetic_energy", "circle_strain_energy", "circle_energy"})
        c.push_back(name);
    if (prm.quadrature == "hybrid adaptive")
      for (const char *name : {"standard_fraction", "overstretched_bonds"})
        c.push_back(name);
    c.push_back("wall_time");
    return c;
  }

  template <int dim>
  std::string
  MechanicsSolver<dim>::signature() const
  {
    std::ostringstream s;
    s.precision(16);
    s << "mechanics " << dim << " " << disc.n_global() << " " << prm.lattice.dx << " "
      << prm.lattice.delta << " " << verlet->time_step() << " " << op->description();
    return s.str();
  }

  namespace
  {
    // The broken bonds as (id_i, id_j) pairs of the owned rows, next to the
    // node checkpoint; both carry the step, which must agree on reading.
    const std::string bonds_magic = "PERIDEAL-BROKEN-BONDS-1";
  }

  template <int dim>
  void
  MechanicsSolver<dim>::write_checkpoint() const
  {
    const auto &nb = disc.neighborhood;
    const auto &br = op->broken();
    std::vector<std::uint64_t> pairs;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
        if (br[b])
          {
            pairs.push_back(disc.id[i]);
            pairs.push_back(disc.id[nb.col[b]]);
          }
    const auto all = Utilities::MPI::gather(mpi_communicator, pairs, 0);
    const std::string dir = prm.output_directory;
    internal::run_on_root(mpi_communicator, [&]() {
      std::vector<std::uint64_t> merged;
      for (const auto &p : all)
        merged.insert(merged.end(), p.begin(), p.end());
      std::string bytes = bonds_magic;
      const std::uint64_t header[2] = {verlet->step(), merged.size()};
      bytes.append(reinterpret_cast<const char *>(header), sizeof(header));
      bytes.append(reinterpret_cast<const char *>(merged.data()), merged.size() * sizeof(std::uint64_t));
      write_file_atomically(dir + "/checkpoint_bonds.bin", bytes);
    });
    std::vector<const Vector *> fields;
    for (unsigned int d = 0; d < dim; ++d)
      fields.push_back(&verlet->displacement[d]);
    for (unsigned int d = 0; d < dim; ++d)
      fields.push_back(&verlet->velocity[d]);
    PeriDEAL::write_checkpoint<dim>(dir + "/checkpoint.bin", disc, verlet->step(), verlet->time(),
                                    fields, signature());
  }

  template <int dim>
  bool
  MechanicsSolver<dim>::read_checkpoint()
  {
    std::vector<Vector *> fields;
    for (unsigned int d = 0; d < dim; ++d)
      fields.push_back(&verlet->displacement[d]);
    for (unsigned int d = 0; d < dim; ++d)
      fields.push_back(&verlet->velocity[d]);
    unsigned int step = 0;
    double       time = 0.;
    const std::string dir = prm.output_directory;
    if (!PeriDEAL::read_checkpoint<dim>(dir + "/checkpoint.bin", disc, step, time, fields, signature()))
      return false;

    std::vector<std::uint64_t> pairs;
    std::uint64_t              bond_step = 0;
    internal::run_on_root(mpi_communicator, [&]() {
      std::ifstream in(dir + "/checkpoint_bonds.bin", std::ios::binary);
      std::string   magic(bonds_magic.size(), ' ');
      std::uint64_t header[2] = {0, 0};
      in.read(magic.data(), magic.size());
      in.read(reinterpret_cast<char *>(header), sizeof(header));
      if (!in || magic != bonds_magic)
        throw std::runtime_error("Checkpoint '" + dir + "/checkpoint_bonds.bin' is missing or malformed.");
      pairs.resize(header[1]);
      in.read(reinterpret_cast<char *>(pairs.data()), pairs.size() * sizeof(std::uint64_t));
      if (!in || header[1] % 2 != 0)
        throw std::runtime_error("Checkpoint '" + dir + "/checkpoint_bonds.bin' is truncated.");
      bond_step = header[0];
    });
    pairs     = Utilities::MPI::broadcast(mpi_communicator, pairs, 0);
    bond_step = Utilities::MPI::broadcast(mpi_communicator, bond_step, 0);
    if (bond_step != step)
      throw std::runtime_error("Checkpoint files in '" + dir + "' belong to different steps (" +
                               std::to_string(step) + " and " + std::to_string(bond_step) + ").");
    std::vector<std::pair<std::uint64_t, std::uint64_t>> broken(pairs.size() / 2);
    for (std::size_t k = 0; k < broken.size(); ++k)
      broken[k] = {pairs[2 * k], pairs[2 * k + 1]};
    std::sort(broken.begin(), broken.end());
    const auto           &nb = disc.neighborhood;
    std::vector<std::uint8_t> flags(nb.n_bonds(), 0);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
        flags[b] = std::binary_search(broken.begin(), broken.end(),
                                      std::pair<std::uint64_t, std::uint64_t>(disc.id[i], disc.id[nb.col[b]]));
    op->set_broken_flags(flags);
    for (auto &u : verlet->displacement)
      u.update_ghost_values();
    verlet->restart(step, time);
    return true;
  }

  template <int dim>
  void
  MechanicsSolver<dim>::record(const bool snapshot)
  {
    const MechanicsMeasurements m   = measure();
    std::vector<double>         row = {verlet->time(), m.kinetic_energy, m.strain_energy,
                                       m.kinetic_energy + m.strain_energy,
                                       double(op->n_broken_bonds()), m.max_damage};
    for (unsigned int k = 0; k < n_prescribed_regions(); ++k)
      {
        const auto R = reaction_force(k);
        for (unsigned int d = 0; d < dim; ++d)
          row.push_back(R[d]);
      }
    if (prm.measure_crack)
      {
        // Tip speed: growth of the crack length since the previous row.
        const unsigned int col   = 6 + dim * n_prescribed_regions() + 2;
        double             speed = 0.;
        if (!series_rows.empty() && verlet->time() > series_rows.back()[0])
          speed = (m.crack_length - series_rows.back()[col]) /
                  (verlet->time() - series_rows.back()[0]);
        row.insert(row.end(), {m.crack_angle, double(m.n_crack_nodes), m.crack_length, speed});
      }
    if (prm.energy_radius > 0.)
      row.insert(row.end(), {m.circle_kinetic_energy, m.circle_strain_energy,
                             m.circle_kinetic_energy + m.circle_strain_energy});
    if (hybrid)
      row.insert(row.end(), {hybrid->standard_fraction(), double(hybrid->n_overstretched_bonds())});
    row.push_back(wall_offset + wall.wall_time());
    csv->add_row(row);
    series_rows.push_back(row);
    if (snapshot)
      {
        Vector damage;
        disc.initialize_vector(damage);
        op->damage(damage);
        std::vector<std::pair<std::string, const Vector *>> fields;
        const char *names[3]  = {"u_x", "u_y", "u_z"};
        const char *vnames[3] = {"v_x", "v_y", "v_z"};
        for (unsigned int d = 0; d < dim; ++d)
          fields.emplace_back(names[d], &verlet->displacement[d]);
        for (unsigned int d = 0; d < dim; ++d)
          fields.emplace_back(vnames[d], &verlet->velocity[d]);
        fields.emplace_back("damage", &damage);
        if (hybrid) // 0 standard (Omega_s), 1 WLS (Omega_w)
          fields.emplace_back("scheme", &hybrid->scheme());
        if (snapshot)
          vtu->write(verlet->time(), verlet->step(), fields);
        if (prm.write_node_table && verlet->step() == total_steps)
          PeriDEAL::write_node_table<dim>(prm.output_directory + "/nodes.csv", disc, fields);
      }
  }

  template <int dim>
  void
  MechanicsSolver<dim>::run(const unsigned int max_steps)
  {
    ConditionalOStream pcout(std::cout, Utilities::MPI::this_mpi_process(mpi_communicator) == 0);
    if (!op)
      setup();
    if (!csv)
      {
        internal::run_on_root(mpi_communicator, [&]() {
          std::filesystem::create_directories(prm.output_directory);
        });
        vtu = std::make_unique<NodeOutput<dim>>(disc, prm.output_directory, "solution");
        csv = std::make_unique<TimeSeries>(mpi_communicator,
                                           prm.output_directory + "/time_series.csv",
                                           time_series_columns());
        wall.restart();
        const bool resumed = prm.resume && read_checkpoint();
        if (resumed)
          {
            csv->load_existing();
            csv->truncate_after(verlet->time() * (1. + 1e-12));
            vtu->restart(verlet->time());
            series_rows = csv->rows();
            wall_offset = series_rows.empty() ? 0. : series_rows.back().back();
            pcout << "Resumed from checkpoint at step " << verlet->step()
                  << ", t = " << verlet->time() << std::endl;
          }
        pcout << "PD mechanics in " << dim << "D: " << disc.n_global() << " nodes, "
              << disc.n_global_bonds() << " bonds, " << op->description()
              << ", dt = " << verlet->time_step()
              << " (critical " << verlet->critical_time_step() << "), " << total_steps
              << " steps" << std::endl;
        if (!resumed)
          record(true);
      }

    unsigned int done = 0;
    while (verlet->step() < total_steps && done < max_steps)
      {
        // The steps up to the next one that writes anything run as one
        // advance(n) (bitwise the same as n single steps; with the lattice
        // sweep the state stays in its box layout meanwhile).
        const unsigned int step  = verlet->step();
        unsigned int       batch = std::min(total_steps - step, max_steps - done);
        for (const unsigned int interval :
             {prm.snapshot_interval, prm.time_series_interval, prm.checkpoint_interval})
          if (interval > 0)
            batch = std::min(batch, interval - step % interval);
        const auto start = std::chrono::steady_clock::now();
        verlet->advance(batch);
        stepping_time +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        stepped += batch;
        done += batch;
        const bool last = verlet->step() == total_steps;
        const bool snap = last || (prm.snapshot_interval > 0 &&
                                   verlet->step() % prm.snapshot_interval == 0);
        if (snap || verlet->step() % prm.time_series_interval == 0)
          record(snap);
        if (prm.checkpoint_interval > 0 && verlet->step() % prm.checkpoint_interval == 0)
          write_checkpoint();
        if (wall.wall_time() - last_progress >= prm.progress_interval && !last)
          {
            last_progress = wall.wall_time();
            pcout << "  step " << verlet->step() << "/" << total_steps << "  elapsed "
                  << std::fixed << std::setprecision(1) << last_progress << " s  remaining ~"
                  << stepping_time / stepped * (total_steps - verlet->step()) << " s"
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
