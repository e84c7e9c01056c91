// step-10: multi-grid PD corrosion (dissertation Sect. 3.4, eqs. 3.81-3.90).
//
// The idea of this step: a fine grid only where it is needed. The body is
// covered by a coarse lattice (dx+); the cells whose node lies in a "fine
// region" are refined into r^dim cells of spacing dx- = dx+/r. Both grids
// use the same horizon. Each region is active in exactly one grid; the
// neighbourhoods of active nodes near the interface are completed by
// fictitious nodes of the same grid, whose values are interpolated from the
// active nodes of the other grid (inverse distance, (3.85)-(3.88)).
//
// (1) The 1D example of Sect. 3.4.1 (E5): [-50, 50], solid [-5, 5],
//     fine (-15.25, 15.25) at dx- = 0.125, dx+ = 0.5 elsewhere: solid volume
//     versus time for the uniform Coarse (201 nodes) and Fine (801) models of
//     the existing DiffusionSolver and the multi-grid model (404 nodes), with
//     the dissertation's coupling and with the conservative variant;
//     concentration profiles.
// (2) A 2D disk dissolving in an electrolyte box: multi-grid (fine disk
//     around the solid) against the uniform fine model: relative volume loss
//     over time, node counts and run times.
//
// The program checks what the tests check (node counts; the multi-grid
// solid volume equals the cell-centred uniform-fine one; conservative mass
// to round-off) and returns non-zero otherwise.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <perideal/base/exceptions.h>
#include <perideal/io/plot.h>
#include <perideal/multigrid/multigrid_discretization.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include <cmath>
#include <filesystem>
#include <array>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step10
{
  struct Settings
  {
    // common model
    double delta = 1., c_sat = 0.85, kappa_liq = 2., kappa_int = 0.1, q = 1.;
    bool   partial_volume = true;
    MultiGrid::Interpolation interpolation = MultiGrid::Interpolation::inverse_distance;
    bool                     calibrate     = false;
    // 1D
    double dt_1d = 0.025, end_1d = 60., fine_half_width = 15.25;
    double dx_coarse = 0.5, dx_fine = 0.125;
    std::vector<double> profile_times;
    // 2D
    bool   run_2d = true;
    double box_2d = 10., solid_radius = 3., fine_radius = 5., dx_coarse_2d = 0.5,
           dx_fine_2d = 0.25, end_2d = 20., dt_2d = 0.;
    std::string output = "step-10-output";

    void
    parse(const std::string &file)
    {
      ParameterHandler prm;
      prm.enter_subsection("Model");
      prm.declare_entry("Horizon", "1", Patterns::Double(0.));
      prm.declare_entry("Kernel exponent", "1", Patterns::Double(0., 2.99));
      prm.declare_entry("Partial volume", "true", Patterns::Bool());
      prm.declare_entry("Saturation concentration", "0.85", Patterns::Double(0.));
      prm.declare_entry("Liquid micro-diffusivity", "2", Patterns::Double(0.));
      prm.declare_entry("Interface micro-diffusivity", "0.1", Patterns::Double(0.));
      prm.declare_entry("Interpolation", "inverse distance",
                        Patterns::Selection("inverse distance|multilinear"),
                        "Fictitious-node values: (3.85)-(3.88) or d-linear.");
      prm.declare_entry("Calibrate kernels", "false", Patterns::Bool(),
                        "Scale each grid's kernel to the continuum second moment "
                        "(equal effective diffusivities in both grids).");
      prm.leave_subsection();
      prm.enter_subsection("1D");
      prm.declare_entry("Coarse grid spacing", "0.5", Patterns::Double(0.));
      prm.declare_entry("Fine grid spacing", "0.125", Patterns::Double(0.));
      prm.declare_entry("Fine half width", "15.25", Patterns::Double(0.));
      prm.declare_entry("Time step", "0.025", Patterns::Double(0.));
      prm.declare_entry("End time", "60", Patterns::Double(0.));
      prm.declare_entry("Profile times", "5, 10, 20", Patterns::List(Patterns::Double(0.)));
      prm.leave_subsection();
      prm.enter_subsection("2D");
      prm.declare_entry("Run", "true", Patterns::Bool());
      prm.declare_entry("Half box", "10", Patterns::Double(0.));
      prm.declare_entry("Solid radius", "3", Patterns::Double(0.));
      prm.declare_entry("Fine radius", "5", Patterns::Double(0.));
      prm.declare_entry("Coarse grid spacing", "0.5", Patterns::Double(0.));
      prm.declare_entry("Fine grid spacing", "0.25", Patterns::Double(0.));
      prm.declare_entry("End time", "20", Patterns::Double(0.));
      prm.declare_entry("Time step", "0", Patterns::Double(0.),
                        "0: 0.9 x the forward Euler bound of the multi-grid model");
      prm.leave_subsection();
      prm.enter_subsection("3D");
      prm.declare_entry("Run", "false", Patterns::Bool());
      prm.declare_entry("Half width", "1.05", Patterns::Double(0.));
      prm.declare_entry("Solid radius", "0.3", Patterns::Double(0.));
      prm.declare_entry("Solid half height", "0.45", Patterns::Double(0.));
      prm.declare_entry("Fine margin", "0.45", Patterns::Double(0.));
      prm.declare_entry("Fine grid spacing", "0.075", Patterns::Double(0.));
      prm.declare_entry("Horizon", "0.45", Patterns::Double(0.));
      prm.declare_entry("End time", "2.5", Patterns::Double(0.));
      prm.leave_subsection();
      prm.declare_entry("Output directory", "step-10-output", Patterns::Anything());
      prm.parse_input(file);

      prm.enter_subsection("Model");
      delta          = prm.get_double("Horizon");
      q              = prm.get_double("Kernel exponent");
      partial_volume = prm.get_bool("Partial volume");
      c_sat          = prm.get_double("Saturation concentration");
      kappa_liq      = prm.get_double("Liquid micro-diffusivity");
      kappa_int      = prm.get_double("Interface micro-diffusivity");
      calibrate      = prm.get_bool("Calibrate kernels");
      interpolation  = prm.get("Interpolation") == "multilinear" ?
                         MultiGrid::Interpolation::multilinear :
                         MultiGrid::Interpolation::inverse_distance;
      prm.leave_subsection();
      prm.enter_subsection("1D");
      dx_coarse       = prm.get_double("Coarse grid spacing");
      dx_fine         = prm.get_double("Fine grid spacing");
      fine_half_width = prm.get_double("Fine half width");
      dt_1d           = prm.get_double("Time step");
      end_1d          = prm.get_double("End time");
      profile_times.clear();
      for (const auto &s : Utilities::split_string_list(prm.get("Profile times")))
        profile_times.push_back(std::stod(s));
      prm.leave_subsection();
      prm.enter_subsection("2D");
      run_2d       = prm.get_bool("Run");
      box_2d       = prm.get_double("Half box");
      solid_radius = prm.get_double("Solid radius");
      fine_radius  = prm.get_double("Fine radius");
      dx_coarse_2d = prm.get_double("Coarse grid spacing");
      dx_fine_2d   = prm.get_double("Fine grid spacing");
      end_2d       = prm.get_double("End time");
      dt_2d        = prm.get_double("Time step");
      prm.leave_subsection();
      prm.enter_subsection("3D");
      run_3d                  = prm.get_bool("Run");
      case_3d.half_width      = prm.get_double("Half width");
      case_3d.radius          = prm.get_double("Solid radius");
      case_3d.half_height     = prm.get_double("Solid half height");
      case_3d.fine_margin     = prm.get_double("Fine margin");
      case_3d.fine_dx         = prm.get_double("Fine grid spacing");
      case_3d.delta           = prm.get_double("Horizon");
      case_3d.end_time        = prm.get_double("End time");
      prm.leave_subsection();
      output = prm.get("Output directory");
    }
    bool                             run_3d = false;
    MultiGrid::CylinderCorrosionCase case_3d;
  };

  /** One run: solid volume per step, vanishing time, mass drift, wall time. */
  struct Run
  {
    std::string                        name;
    unsigned int                       nodes = 0;
    std::vector<std::array<double, 2>> volume; // (t, V_solid)
    double vanishing = -1., mass_change = 0., wall = 0., setup = 0.;
    std::vector<std::pair<double, std::vector<std::array<double, 2>>>> profiles;
  };

  // A uniform model with the existing DiffusionSolver (box, Neumann).
  template <int dim>
  Run
  uniform(const Settings &s, const std::string &name, const double dx, const bool cell_centered,
          const double half, const std::string &c0, const double dt, const double end,
          const std::vector<double> &profile_times = {})
  {
    std::ostringstream text;
    text << std::setprecision(17);
    text << "subsection Geometry\n set Domain = box\n set Lower corner = " << -half
         << (dim == 2 ? (", " + std::to_string(-half)) : "") << "\n set Upper corner = " << half
         << (dim == 2 ? (", " + std::to_string(half)) : "")
         << "\nend\nsubsection Discretization\n set Grid spacing = " << dx
         << "\n set Horizon = " << s.delta
         << "\n set Partial volume = " << (s.partial_volume ? "true" : "false")
         << "\n set Volume constraint layer = 0\n set Lattice = "
         << (cell_centered ? "cell centered" : "vertex")
         << "\nend\nsubsection Model\n set Type = corrosion\n set Kernel exponent = " << s.q
         << "\n set Initial condition = " << c0
         << "\n subsection Corrosion\n  set Liquid micro-diffusivity = " << s.kappa_liq
         << "\n  set Interface micro-diffusivity = " << s.kappa_int
         << "\n  set Saturation concentration = " << s.c_sat
         << "\n end\nend\nsubsection Time stepping\n set Time step = " << dt
         << "\n set End time = " << end << "\nend\n";
    ParameterHandler prm;
    DiffusionRunParameters<dim>::declare_parameters(prm);
    prm.parse_input_from_string(text.str());
    DiffusionRunParameters<dim> p;
    p.parse_parameters(prm);
    p.output_directory = s.output + "/uniform";

    Timer                timer;
    DiffusionSolver<dim> solver(MPI_COMM_WORLD, p);
    solver.setup();
    Run r;
    r.setup = timer.wall_time();
    r.name          = name;
    r.nodes         = solver.discretization().n_global();
    const double m0 = solver.diagnostics().mass;
    r.volume.push_back({{0., solver.diagnostics().solid_volume}});
    std::size_t next_profile = 0;
    while (solver.step() < solver.n_steps())
      {
        solver.advance();
        const auto d = solver.diagnostics();
        r.volume.push_back({{d.time, d.solid_volume}});
        r.mass_change = std::max(r.mass_change, std::abs(d.mass - m0) / m0);
        if (d.solid_volume == 0. && r.vanishing < 0.)
          r.vanishing = d.time;
        if (next_profile < profile_times.size() &&
            d.time >= profile_times[next_profile] - 1e-9)
          {
            std::vector<std::array<double, 2>> pr;
            for (unsigned int i = 0; i < solver.discretization().n_owned(); ++i)
              pr.push_back({{solver.discretization().position[i][0],
                             solver.solution().local_element(i)}});
            std::sort(pr.begin(), pr.end());
            r.profiles.emplace_back(d.time, pr);
            ++next_profile;
          }
      }
    r.wall = timer.wall_time();
    return r;
  }

  template <int dim>
  Run
  multigrid(const Settings &s, const std::string &name, const MultiGrid::Parameters<dim> &p,
            const bool conservative, const double dt, const double end,
            const std::function<double(const Point<dim> &)> &c0,
            const std::vector<double>                     &profile_times = {})
  {
    Timer                                timer;
    const MultiGrid::Discretization<dim> disc(p);
    MultiGrid::TransportParameters       t;
    t.corrosion       = true;
    t.kappa_liquid    = s.kappa_liq;
    t.kappa_interface = s.kappa_int;
    t.saturation      = s.c_sat;
    t.time_step       = dt;
    t.conservative    = conservative;
    t.calibrate       = s.calibrate;
    MultiGrid::TransportSolver<dim> solver(disc, t);
    solver.set_initial(c0);
    Run r;
    r.setup = timer.wall_time();
    r.name          = name;
    r.nodes         = disc.n_nodes();
    const double m0 = solver.mass();
    r.volume.push_back({{0., solver.solid_volume()}});
    std::size_t next_profile = 0;
    while (solver.time() < end - 1e-9)
      {
        solver.advance();
        r.volume.push_back({{solver.time(), solver.solid_volume()}});
        r.mass_change = std::max(r.mass_change, std::abs(solver.mass() - m0) / m0);
        if (solver.solid_volume() == 0. && r.vanishing < 0.)
          r.vanishing = solver.time();
        if (next_profile < profile_times.size() &&
            solver.time() >= profile_times[next_profile] - 1e-9)
          {
            std::vector<std::array<double, 2>> pr;
            for (unsigned int i = 0; i < disc.n_active(); ++i)
              pr.push_back({{disc.position[i][0], solver.solution()[i]}});
            std::sort(pr.begin(), pr.end());
            r.profiles.emplace_back(solver.time(), pr);
            ++next_profile;
          }
      }
    r.wall = timer.wall_time();
    return r;
  }

  void
  write_volumes(const std::string &file, const std::vector<Run> &runs)
  {
    std::ofstream csv(file);
    csv << "model,time,solid_volume,relative_volume\n";
    for (const auto &r : runs)
      for (const auto &v : r.volume)
        csv << r.name << "," << v[0] << "," << v[1] << "," << v[1] / r.volume[0][1] << "\n";
  }

  std::string
  plot_volumes(const std::string &csv, const std::vector<Run> &runs, const unsigned int column)
  {
    std::string gp;
    for (std::size_t k = 0; k < runs.size(); ++k)
      gp += std::string(k ? ", " : "") + "'" + csv + "' using (strcol(1) eq '" + runs[k].name +
            "' ? $2 : 1/0):" + std::to_string(column) + " with lines lw 2 dt " +
            std::to_string(k + 1) + " title '" + runs[k].name + " (" +
            std::to_string(runs[k].nodes) + " nodes)'";
    return gp + "\n";
  }

  int
  run(const std::string &prm_file)
  {
    Settings s;
    s.parse(prm_file);
    std::filesystem::create_directories(s.output);
    bool ok     = true;
    auto report = [&](const bool c, const std::string &what) {
      std::cout << (c ? "  ok    " : "  FAIL  ") << what << "\n";
      ok = ok && c;
    };

    // @sect3{(1) E5: 1D corrosion, Sect. 3.4.1}
    const std::string solid_1d = "(x >= -5) * (x <= 5)";
    MultiGrid::Parameters<1> p1;
    p1.lower          = Point<1>(-50.);
    p1.upper          = Point<1>(50.);
    p1.coarse_dx      = s.dx_coarse;
    p1.fine_dx        = s.dx_fine;
    p1.delta          = s.delta;
    p1.partial_volume = s.partial_volume;
    p1.exponent       = s.q;
    p1.interpolation  = s.interpolation;
    p1.fine_region =
      MultiGrid::Region<1>::box(Point<1>(-s.fine_half_width), Point<1>(s.fine_half_width));
    const auto c0_1d = [](const Point<1> &x) { return std::abs(x[0]) <= 5. ? 1. : 0.; };
    {
      const MultiGrid::Discretization<1> d(p1);
      std::cout << "1D multi-grid: " << d.n_active_coarse << " coarse + " << d.n_active_fine
                << " fine + " << d.n_fictitious_coarse + d.n_fictitious_fine
                << " auxiliary (fictitious) nodes\n";
      report(d.n_active_coarse == 140 && d.n_active_fine == 244 &&
               d.n_fictitious_coarse + d.n_fictitious_fine == 20,
             "node counts 140 + 244 + 20 (Sect. 3.4.1)");
    }
    std::vector<Run> runs;
    runs.push_back(uniform<1>(s, "Coarse", s.dx_coarse, false, 50., solid_1d, s.dt_1d,
                              s.end_1d));
    runs.push_back(uniform<1>(s, "Fine", s.dx_fine, false, 50., solid_1d, s.dt_1d, s.end_1d,
                              s.profile_times));
    runs.push_back(uniform<1>(s, "Fine cell-centred", s.dx_fine, true, 50., solid_1d, s.dt_1d,
                              s.end_1d));
    runs.push_back(multigrid<1>(s, "Multi-grid", p1, false, s.dt_1d, s.end_1d, c0_1d,
                                s.profile_times));
    runs.push_back(multigrid<1>(s, "Multi-grid conservative", p1, true, s.dt_1d, s.end_1d,
                                c0_1d));

    std::cout << "\n| model | nodes | V0 | vanishing time | max rel. mass change | wall s |\n"
                 "|---|---:|---:|---:|---:|---:|\n";
    for (const auto &r : runs)
      std::cout << "| " << r.name << " | " << r.nodes << " | " << r.volume[0][1] << " | "
                << r.vanishing << " | " << std::scientific << std::setprecision(1)
                << r.mass_change << std::defaultfloat << std::setprecision(6) << " | "
                << std::fixed << std::setprecision(3) << r.wall << std::defaultfloat
                << std::setprecision(6) << " |\n";
    const std::string csv1 = s.output + "/solid_volume_1d.csv";
    write_volumes(csv1, runs);
    run_gnuplot(s.output + "/solid_volume_1d.gp",
                gnuplot_png_preamble(s.output + "/solid_volume_1d.png") +
                  "set datafile separator ','\nset xlabel 'time'\nset ylabel 'solid volume'\n"
                  "set title 'E5: 1D PD corrosion, Sect. 3.4.1'\nplot " +
                  plot_volumes(csv1, runs, 3),
                s.output + "/solid_volume_1d.png");
    // concentration profiles, multi-grid vs Fine
    {
      std::ofstream pf(s.output + "/profiles_1d.csv");
      pf << "model,time,x,C\n";
      for (const unsigned int k : {1u, 3u})
        for (const auto &[t, pr] : runs[k].profiles)
          for (const auto &xc : pr)
            pf << runs[k].name << "," << t << "," << xc[0] << "," << xc[1] << "\n";
      pf.close();
      std::string gp = gnuplot_png_preamble(s.output + "/profiles_1d.png") +
                       "set datafile separator ','\nset xlabel 'x'\nset ylabel 'C'\n"
                       "set xrange [-25:25]\nset arrow from -15.25, graph 0 to -15.25, graph 1 "
                       "nohead dt 3\nset arrow from 15.25, graph 0 to 15.25, graph 1 nohead dt "
                       "3\nplot ";
      bool first = true;
      for (const double t : s.profile_times)
        for (const std::string m : {"Fine", "Multi-grid"})
          {
            std::ostringstream sel;
            sel << "(strcol(1) eq '" << m << "' && abs($2 - " << t << ") < 1e-6 ? $3 : 1/0):4";
            gp += std::string(first ? "" : ", ") + "'" + s.output + "/profiles_1d.csv' using " +
                  sel.str() + (m == "Fine" ? " with lines lw 2" : " with points pt 7 ps 0.5") +
                  " title '" + m + " t = " + Utilities::to_string(t) + "'";
            first = false;
          }
      run_gnuplot(s.output + "/profiles_1d.gp", gp + "\n", s.output + "/profiles_1d.png");
    }
    report(runs[3].volume.size() == runs[2].volume.size(), "same number of steps");
    double dist = 0.;
    for (std::size_t n = 0; n < std::min(runs[3].volume.size(), runs[2].volume.size()); ++n)
      dist = std::max(dist, std::abs(runs[3].volume[n][1] - runs[2].volume[n][1]));
    report(dist <= s.dx_fine + 1e-12,
           "multi-grid solid volume within one fine node volume of the cell-centred Fine model "
           "at every step (max difference " +
             std::to_string(dist) + ")");
    report(runs[4].mass_change < 1e-13, "conservative coupling: mass to round-off");
    report(runs[3].vanishing > 0. && runs[1].vanishing > 0. &&
             std::abs(runs[3].vanishing - runs[1].vanishing) <= 0.03 * runs[1].vanishing,
           "multi-grid vanishing time within 3% of Fine (801 nodes)");

    // @sect3{(2) 2D: a disk dissolving in an electrolyte box}
    if (s.run_2d)
      {
        const double R = s.solid_radius, L = s.box_2d;
        MultiGrid::Parameters<2> p2;
        p2.lower          = Point<2>(-L, -L);
        p2.upper          = Point<2>(L, L);
        p2.coarse_dx      = s.dx_coarse_2d;
        p2.fine_dx        = s.dx_fine_2d;
        p2.delta          = s.delta;
        p2.partial_volume = s.partial_volume;
        p2.exponent       = s.q;
        p2.interpolation  = s.interpolation;
        p2.fine_region    = MultiGrid::Region<2>::ball(Point<2>(), s.fine_radius);
        const auto c0 = [R](const Point<2> &x) { return x.norm() <= R ? 1. : 0.; };
        const std::string c0_text = "(x*x + y*y <= " + std::to_string(R * R) + ")";
        // one time step for all models: 0.9 x the fine model's bound
        double dt = s.dt_2d;
        if (dt <= 0.)
          {
            const MultiGrid::Discretization<2> d(p2);
            MultiGrid::TransportParameters      t;
            t.corrosion       = true;
            t.kappa_liquid    = s.kappa_liq;
            t.kappa_interface = s.kappa_int;
            MultiGrid::TransportSolver<2> probe(d, t);
            dt = 0.9 * probe.critical_time_step();
          }
        // The uniform-fine reference with the same lattice as the fine grid
        // (cell-centred) spans [-L - dx+/2, L + dx+/2] like the multi-grid's
        // cells; the far boundary is irrelevant at these times.
        const double     half_fine = L + 0.5 * s.dx_coarse_2d;
        std::vector<Run> runs2;
        runs2.push_back(uniform<2>(s, "Coarse", s.dx_coarse_2d, false, L, c0_text, dt, s.end_2d));
        runs2.push_back(
          uniform<2>(s, "Fine", s.dx_fine_2d, true, half_fine, c0_text, dt, s.end_2d));
        runs2.push_back(multigrid<2>(s, "Multi-grid", p2, false, dt, s.end_2d, c0));
        runs2.push_back(multigrid<2>(s, "Multi-grid conservative", p2, true, dt, s.end_2d, c0));
        // the same (serial) multi-grid code with the whole box fine: the
        // fair speed-up reference
        MultiGrid::Parameters<2> pf = p2;
        pf.fine_region = MultiGrid::Region<2>::box(Point<2>(-2 * L, -2 * L), Point<2>(2 * L, 2 * L));
        runs2.push_back(multigrid<2>(s, "All-fine (multi-grid code)", pf, false, dt, s.end_2d, c0));

        std::cout << "\n2D disk R = " << R << " in [-" << L << ", " << L
                  << "]^2, fine disk radius " << s.fine_radius << ", dt = " << dt << "\n"
                  << "| model | nodes | V0 | V(t_end)/V0 | vanishing time | max rel. mass change | wall s | of which setup |\n"
                     "|---|---:|---:|---:|---:|---:|---:|---:|\n";
        for (const auto &r : runs2)
          std::cout << "| " << r.name << " | " << r.nodes << " | " << r.volume[0][1] << " | "
                    << r.volume.back()[1] / r.volume[0][1] << " | " << r.vanishing << " | "
                    << std::scientific << std::setprecision(1) << r.mass_change
                    << std::defaultfloat << std::setprecision(6) << " | " << std::fixed
                    << std::setprecision(2) << r.wall << " | " << r.setup << std::defaultfloat
                    << std::setprecision(6) << " |\n";
        const std::string csv2 = s.output + "/solid_volume_2d.csv";
        write_volumes(csv2, runs2);
        run_gnuplot(s.output + "/solid_volume_2d.gp",
                    gnuplot_png_preamble(s.output + "/solid_volume_2d.png") +
                      "set datafile separator ','\nset xlabel 'time'\n"
                      "set ylabel 'relative solid volume V/V0'\n"
                      "set title '2D disk in electrolyte'\nplot " +
                      plot_volumes(csv2, runs2, 4),
                    s.output + "/solid_volume_2d.png");
        double d2 = 0.;
        for (std::size_t n = 0; n < std::min(runs2[1].volume.size(), runs2[2].volume.size()); ++n)
          d2 = std::max(d2, std::abs(runs2[2].volume[n][1] / runs2[2].volume[0][1] -
                                     runs2[1].volume[n][1] / runs2[1].volume[0][1]));
        std::cout << "max |relative volume multi-grid - Fine| = " << d2
                  << "; speed-up vs all-fine (same code) "
                  << runs2[4].wall / runs2[2].wall << "\n";
        report(runs2[2].volume[0][1] == runs2[1].volume[0][1],
               "2D: same initial solid as the uniform fine model");
        report(runs2[3].mass_change < 1e-12, "2D conservative coupling: mass to round-off");
        // the corrosion front stays inside the fine disk (radius 3 -> 5)
        report(d2 < 0.02, "2D: relative volume within 0.02 of the uniform fine model");
      }
    // @sect3{(3) 3D: a cylinder dissolving in an electrolyte cube}
    // A reduced analogue of [100] Example 2 (the screw of Sect. 3.5.2):
    // uniform fine (the reference), uniform coarse, multi-grid, and the
    // multi-grid with WLS-2 on the coarse grid ("adaptive, hybrid").
    if (s.run_3d)
      {
        MultiGrid::CylinderCorrosionCase c = s.case_3d;
        c.transport.kappa_liquid    = s.kappa_liq;
        c.transport.kappa_interface = s.kappa_int;
        c.transport.saturation      = s.c_sat;
        const char *names[] = {"adaptive hybrid", "uniform fine", "uniform coarse", "multi-grid"};
        std::vector<MultiGrid::CorrosionHistory> r;
        for (const char *name : names)
          {
            r.push_back(MultiGrid::run_cylinder_corrosion(c, name));
            c.time_step = r[0].time_step; // the adaptive hybrid's (smallest) bound for all
          }
        std::cout << "\n3D cylinder r = " << c.radius << ", h = " << 2. * c.half_height
                  << " in [-" << c.half_width << ", " << c.half_width << "]^3, dt = "
                  << r[0].time_step << "\n| model | active coarse | active fine | fictitious | "
                  << "WLS rows | CPU s/step | final loss | max abs loss - fine |\n"
                  << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
        std::ofstream csv(s.output + "/volume_loss_3d.csv");
        csv << "time";
        for (const char *name : names)
          csv << "," << name;
        csv << "\n";
        for (std::size_t k = 0; k < r[1].time.size(); ++k)
          {
            csv << r[1].time[k];
            for (const auto &h : r)
              csv << "," << h.loss[k];
            csv << "\n";
          }
        csv.close();
        std::array<double, 4> dist{};
        for (unsigned int m = 0; m < 4; ++m)
          {
            for (std::size_t k = 0; k < r[1].loss.size(); ++k)
              dist[m] = std::max(dist[m], std::abs(r[m].loss[k] - r[1].loss[k]));
            std::cout << "| " << names[m] << " | " << r[m].n_active_coarse << " | "
                      << r[m].n_active_fine << " | " << r[m].n_fictitious << " | "
                      << r[m].n_wls_rows << " | " << r[m].step_cpu_seconds << " | "
                      << r[m].loss.back() << " | " << dist[m] << " |\n";
          }
        run_gnuplot(s.output + "/volume_loss_3d.gp",
                    gnuplot_png_preamble(s.output + "/volume_loss_3d.png") +
                      "set datafile separator ','\nset key autotitle columnhead left top\n"
                      "set xlabel 'time'\nset ylabel 'relative volume loss'\n"
                      "set title '3D cylinder in electrolyte'\nplot for [i=2:5] '" +
                      s.output + "/volume_loss_3d.csv' using 1:i with linespoints\n",
                    s.output + "/volume_loss_3d.png");
        report(r[1].loss.back() > 0.3, "3D: the solid corrodes (uniform fine)");
        // source criterion ([100] Fig. 15): curves within 2-3 points; a
        // lag of one step is one shell of nodes, so the bound is one step's jump
        double jump = 0.;
        for (std::size_t k = 1; k < r[1].loss.size(); ++k)
          jump = std::max(jump, r[1].loss[k] - r[1].loss[k - 1]);
        report(dist[3] <= jump && dist[0] <= jump,
               "3D: multi-grid and adaptive hybrid within one step's loss of uniform fine");
      }
    std::cout << (ok ? "step-10: all checks passed\n" : "step-10: SOME CHECKS FAILED\n");
    return ok ? 0 : 1;
  }
} // namespace Step10

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  try
    {
      return Step10::run(argc > 1 ? argv[1] : "step-10.prm");
    }
  catch (const std::exception &e)
    {
      std::cerr << "step-10: " << e.what() << std::endl;
      return 1;
    }
}
