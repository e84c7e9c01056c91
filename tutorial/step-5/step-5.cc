// step-5: 1D classical (deal.II FEM) and PD diffusion on an unbounded
// domain with EBF absorbing boundary conditions (dissertation Sect. 4.1.4,
// paper 002 Example 1).
//
// The idea of this step: the real line is truncated to a near field
// (-L, L); on its boundary (FEM: the two end DoFs; PD: the nodes within
// delta_L of the ends) the value at t^{n+1} is extrapolated from a cloud of
// nearby values at t^n with exponential far-field modes
// exp(k x + D k^2 t), k < 0 in a frame whose axis points outward, through a
// precomputed updating vector (4.31). The same Abc::EbfDiffusionAbc class
// serves both near fields.
//
// Problem: C_t = D C_xx (FEM) or the PD operator with J_1 and constant
// micro-diffusivity (PD, delta = 4 dx), D = 1, C0 = exp(-4x^2), dx = 0.125,
// dt = 0.001, n_b = 20 modes, t_f = 250; the reference is the same solver
// on (-150, 150) with homogeneous Neumann ends (nothing reaches them: the
// heat kernel is 3e-12 there at t = 250). Compared: ABC vs Neumann
// truncation, and the PD absorbing layer delta_L = 1..4 dx (Figs.
// 4.5-4.11). The energy Pi = int_{-L}^{L} C^2 (002, eq. 48) and the
// normalized energy difference (4.35) are written to CSV and plotted.

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <deal.II/grid/grid_generator.h>

#include <perideal/abc/pd_unbounded_diffusion.h>
#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_diffusion.h>
#include <perideal/io/plot.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>

using namespace dealii;
using namespace PeriDEAL;

namespace Step5
{
  /** C0 = exp(-4 x^2) and its free-space evolution (heat kernel). */
  class Gaussian : public Function<1>
  {
  public:
    double
    value(const Point<1> &p, const unsigned int = 0) const override
    {
      const double s = 1. + 16. * this->get_time();
      return std::exp(-4. * p[0] * p[0] / s) / std::sqrt(s);
    }
  };

  struct Parameters
  {
    double                    L = 30., L_ref = 150., dx = 0.125, dt = 1e-3, t_end = 250.;
    double                    horizon_factor = 4., record_interval = 1.;
    std::vector<unsigned int> layers{1, 2, 3, 4};
    std::string               output_directory = "step-5-output";
    Abc::EbfParameters        abc;

    void
    read(const std::string &file)
    {
      ParameterHandler prm;
      prm.enter_subsection("Problem");
      prm.declare_entry("Near-field half width", "30", Patterns::Double(0.));
      prm.declare_entry("Reference half width", "150", Patterns::Double(0.));
      prm.declare_entry("Grid spacing", "0.125", Patterns::Double(0.));
      prm.declare_entry("Time step", "0.001", Patterns::Double(0.));
      prm.declare_entry("End time", "250", Patterns::Double(0.));
      prm.declare_entry("Horizon factor", "4", Patterns::Double(1.));
      prm.declare_entry("Record interval", "1", Patterns::Double(0.));
      prm.declare_entry("Layer study", "1, 2, 3, 4", Patterns::List(Patterns::Integer(1)));
      prm.declare_entry("Output directory", "step-5-output", Patterns::Anything());
      prm.leave_subsection();
      prm.enter_subsection("Absorbing boundary");
      Abc::EbfParameters::declare_parameters(prm);
      prm.leave_subsection();
      prm.parse_input(file);
      prm.enter_subsection("Problem");
      L               = prm.get_double("Near-field half width");
      L_ref           = prm.get_double("Reference half width");
      dx              = prm.get_double("Grid spacing");
      dt              = prm.get_double("Time step");
      t_end           = prm.get_double("End time");
      horizon_factor  = prm.get_double("Horizon factor");
      record_interval = prm.get_double("Record interval");
      layers.clear();
      for (const auto &s : Utilities::split_string_list(prm.get("Layer study")))
        layers.push_back(Utilities::string_to_int(s));
      output_directory = prm.get("Output directory");
      prm.leave_subsection();
      check_parameter(L_ref > L && L > 0 && dx > 0, "Problem/Reference half width", L_ref,
                      "> Near-field half width > 0");
      prm.enter_subsection("Absorbing boundary");
      abc.parse_parameters(prm);
      prm.leave_subsection();
    }
  };

  /** Energy on (-L, L) at the record times 0, record_interval, ..., t_end. */
  template <typename Run>
  std::vector<double>
  energy_history(Run &run, const Parameters &p, bool &monotone)
  {
    const BoundingBox<1> region(std::make_pair(Point<1>(-p.L), Point<1>(p.L)));
    const auto n_steps = static_cast<unsigned int>(std::round(p.t_end / p.dt));
    const auto every   = std::max(1u, static_cast<unsigned int>(std::round(p.record_interval / p.dt)));
    std::vector<double> e{run.energy(region)};
    double              previous = e[0];
    monotone                     = true;
    for (unsigned int n = 1; n <= n_steps; ++n)
      {
        run.advance();
        // Energy every step for the monotonicity check (cheap in 1D).
        const double en = run.energy(region);
        monotone        = monotone && en <= previous * (1. + 1e-13);
        previous        = en;
        if (n % every == 0 || n == n_steps)
          e.push_back(en);
      }
    return e;
  }

  struct Series
  {
    std::string         name;
    std::vector<double> energy;
    bool                monotone = true;
    double              seconds = 0., abc_fraction = 0.;
  };

  int
  run(const std::string &prm_file)
  {
    Parameters p;
    p.read(prm_file);
    std::filesystem::create_directories(p.output_directory);
    const Gaussian c0;
    std::vector<Series> fem, pd;

    // FEM: Q1, lumped mass, forward Euler (as the source).
    Fem::FemDiffusionParameters fp;
    fp.time_step = p.dt;
    for (const auto &[name, half, boundary] :
         std::vector<std::tuple<std::string, double, Abc::TruncationBoundary>>{
           {"reference", p.L_ref, Abc::TruncationBoundary::neumann},
           {"ABC", p.L, Abc::TruncationBoundary::absorbing},
           {"Neumann", p.L, Abc::TruncationBoundary::neumann}})
      {
        Triangulation<1> tria;
        GridGenerator::subdivided_hyper_cube(tria, static_cast<unsigned int>(std::round(2 * half / p.dx)),
                                             -half, half);
        Fem::FemDiffusion<1> solver(tria, fp);
        solver.setup(boundary, p.abc, c0);
        Timer  timer;
        Series s{"FEM " + name, {}, true, 0., 0.};
        s.energy       = energy_history(solver, p, s.monotone);
        s.seconds      = timer.wall_time();
        s.abc_fraction = solver.abc_seconds / solver.step_seconds;
        if (boundary == Abc::TruncationBoundary::absorbing)
          {
            const auto &st = solver.absorbing_boundary().statistics();
            std::cout << "FEM clouds: " << st.min_cloud_size << " points, Delta k "
                      << st.wave_number_range << " (bound (4.33) " << st.wave_number_bound
                      << "), condition " << st.max_condition_number << ", max |V| "
                      << st.max_update_norm << std::endl;
            Gaussian exact;
            std::cout << "FEM ABC: max |C - heat kernel| at t_f = "
                      << solver.max_error(exact, BoundingBox<1>(std::make_pair(Point<1>(-p.L), Point<1>(p.L))))
                      << std::endl;
          }
        fem.push_back(s);
      }

    // PD: delta = m dx, J_1, constant micro-diffusivity, d_inf = delta / 2.
    LatticeParameters lp;
    lp.dx    = p.dx;
    lp.delta = p.horizon_factor * p.dx;
    DiffusionModelParameters model;
    model.exponent    = 1.;
    model.diffusivity = 1.;
    std::vector<std::tuple<std::string, double, Abc::TruncationBoundary, double>> pd_runs{
      {"reference", p.L_ref, Abc::TruncationBoundary::neumann, 0.},
      {"Neumann", p.L, Abc::TruncationBoundary::neumann, 0.}};
    for (const unsigned int l : p.layers)
      pd_runs.emplace_back("ABC delta_L=" + std::to_string(l) + "dx", p.L,
                           Abc::TruncationBoundary::absorbing, l * p.dx);
    for (const auto &[name, half, boundary, layer] : pd_runs)
      {
        BoxDomain<1>                 box(Point<1>(-half), Point<1>(half));
        Abc::PdUnboundedDiffusion<1> solver(MPI_COMM_WORLD);
        Abc::EbfParameters           ap = p.abc;
        ap.layer_thickness              = layer;
        // The study reports the diverging delta_L = dx run; the setup's
        // stability check would stop it (one-step growth 1.048).
        ap.stability_check_steps = 0;
        solver.setup(box, lp, model, p.dt, boundary, ap, c0);
        Timer  timer;
        Series s{"PD " + name, {}, true, 0., 0.};
        s.energy       = energy_history(solver, p, s.monotone);
        s.seconds      = timer.wall_time();
        s.abc_fraction = solver.abc_seconds / solver.step_seconds;
        pd.push_back(s);
      }

    // Normalized energy differences (4.35) and the table.
    const auto difference = [](const Series &s, const Series &ref, const unsigned int r) {
      return std::abs(s.energy[r] - ref.energy[r]) / ref.energy[0];
    };
    std::ofstream csv(p.output_directory + "/energy_difference.csv");
    csv << "t";
    for (const auto *set : {&fem, &pd})
      for (unsigned int i = 1; i < set->size(); ++i)
        csv << ",\"" << (*set)[i].name << "\"";
    csv << "\n";
    const unsigned int n_records = fem[0].energy.size();
    for (unsigned int r = 0; r < n_records; ++r)
      {
        csv << std::min(r * p.record_interval, p.t_end);
        for (const auto *set : {&fem, &pd})
          for (unsigned int i = 1; i < set->size(); ++i)
            csv << "," << difference((*set)[i], (*set)[0], r);
        csv << "\n";
      }
    csv.close();

    std::cout << std::setprecision(4);
    std::cout << "\n" << std::left << std::setw(24) << "run" << std::setw(14) << "Pi(tf)/Pi0"
              << std::setw(16) << "max dPi/Pi0" << std::setw(16) << "dPi/Pi0(tf)" << std::setw(10)
              << "monotone" << std::setw(10) << "wall s" << "ABC share" << std::endl;
    std::map<std::string, double> final_difference, max_difference;
    for (const auto *set : {&fem, &pd})
      for (const auto &s : *set)
        {
          double m = 0.;
          for (unsigned int r = 0; r < n_records; ++r)
            m = std::max(m, difference(s, (*set)[0], r));
          final_difference[s.name] = difference(s, (*set)[0], n_records - 1);
          max_difference[s.name]   = m;
          std::cout << std::setw(24) << s.name << std::setw(14) << s.energy.back() / s.energy[0]
                    << std::setw(16) << m << std::setw(16) << final_difference[s.name]
                    << std::setw(10) << (s.monotone ? "yes" : "NO") << std::setw(10) << s.seconds
                    << s.abc_fraction << std::endl;
        }

    // Plot.
    std::ostringstream gp;
    gp << gnuplot_png_preamble(p.output_directory + "/energy_difference.png")
       << "set datafile separator ','\nset key autotitle columnhead outside right\n"
       << "set logscale y\nset yrange [1e-7:1]\nset xlabel 't'\n"
       << "set ylabel 'normalized energy difference |Pi - Pi_ref| / Pi_ref(0)'\n"
       << "plot for [i=2:" << fem.size() + pd.size() - 1 << "] '" << p.output_directory
       << "/energy_difference.csv' using 1:i with lines lw 2\n";
    run_gnuplot(p.output_directory + "/energy_difference.gp", gp.str(),
                p.output_directory + "/energy_difference.png");

    // Checks: what the source reports, measured (see doc.md).
    int failures = 0;
    const auto check = [&failures](const bool ok, const std::string &what) {
      std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
      failures += !ok;
    };
    std::cout << "\nChecks" << std::endl;
    const std::string pd_full = "PD ABC delta_L=" + std::to_string(p.layers.back()) + "dx";
    check(final_difference["FEM Neumann"] > 10. * final_difference["FEM ABC"],
          "FEM: ABC >= 10x closer to the reference than Neumann at t_f (Fig. 4.5)");
    check(final_difference["PD Neumann"] > 10. * final_difference[pd_full],
          "PD: ABC (largest delta_L) >= 10x closer than Neumann at t_f");
    check(max_difference["FEM ABC"] < 1e-3 && max_difference[pd_full] < 1e-3,
          "max Delta Pi/Pi0 over the run < 1e-3 for FEM and PD with ABC");
    // Layer study: the error decreases with delta_L from 2 dx on. The
    // thinnest layer (dx) diverges in our runs (the source: reduced accuracy
    // only); it is reported, and excluded from the energy check.
    std::vector<double> layer_error;
    for (const unsigned int l : p.layers)
      layer_error.push_back(max_difference["PD ABC delta_L=" + std::to_string(l) + "dx"]);
    bool decreasing = true;
    for (unsigned int i = 1; i + 1 < layer_error.size(); ++i)
      decreasing = decreasing && layer_error[i] > layer_error[i + 1];
    check(decreasing, "PD: error decreases as delta_L grows (from the second layer size on, Fig. 4.11)");
    for (const auto *set : {&fem, &pd})
      for (const auto &s : *set)
        if (std::isfinite(s.energy.back()))
          check(s.monotone, s.name + ": energy non-increasing every step");
        else
          std::cout << "  note  " << s.name << " diverged" << std::endl;
    return failures == 0 ? 0 : 1;
  }
} // namespace Step5

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  try
    {
      return Step5::run(argc > 1 ? argv[1] : "step-5.prm");
    }
  catch (const std::exception &e)
    {
      std::cerr << "Error: " << e.what() << std::endl;
      return 1;
    }
}
