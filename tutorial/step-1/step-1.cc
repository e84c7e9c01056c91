// step-1: transient 2D PD diffusion with a manufactured solution.
//
// The idea of this step: how a PeriDEAL diffusion run is put together
// (geometry -> lattice on the octree -> kernel -> operator -> time stepping),
// and how to check it against an exact solution of the *nonlocal* problem.
//
// Problem (dissertation Sect. 3.2.6): on (-0.5, 0.5)^2,
//   C_ex(x, t) = sin(5t) (x^2 y^2 + x^3 y + x^4 + x y^3 + y^4)         (3.77)
// solves dC/dt = int_{|xi| <= delta} (C(x + xi) - C(x)) / |xi|^2 dA + S with
//   S = 5 cos(5t) P(x) - pi delta^2/16 sin(5t) (7 delta^2 + 56 x^2 + 48 x y + 56 y^2)  (3.78)
// i.e. kernel J_2 with kappa = 1 and the constant influence function. The
// Dirichlet values come from C_ex on a layer outside the square that holds
// every node a square node is bonded to (delta + dx/2 with partial volumes).
// The error is the relative l2 norm (3.79) over the square's nodes.
//
// The program runs the grids listed in step-1.prm (delta = 5 dx), with forward
// and backward Euler, prints the error table with observed orders, writes
// the error histories to CSV, and returns non-zero if the observed spatial
// order leaves the range set in the parameter file or the two schemes differ
// by more than their a-priori O(dt) time error.

#include <deal.II/base/convergence_table.h>
#include <deal.II/base/function_parser.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <perideal/base/exceptions.h>
#include <perideal/io/plot.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include <filesystem>
#include <fstream>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step1
{
  // @sect3{Parameters}
  // The tutorial's own entries; everything else is the standard
  // DiffusionRunParameters set (its values in step-1.prm are overwritten per
  // grid where the study needs it).
  struct Parameters
  {
    std::vector<unsigned int> divisions;
    std::vector<std::string>  schemes;
    double                    horizon_factor = 5.;
    double                    min_order = 1.5, max_order = 2.5;
    double                    implicit_time_step = 1e-5;
    std::string               output = "step-1-output";

    static void
    declare(ParameterHandler &prm)
    {
      prm.enter_subsection("Study");
      prm.declare_entry("Divisions", "19, 39, 79", Patterns::List(Patterns::Integer(2)),
                        "Grids: dx = 1/n for each n (the source uses n = 39).");
      prm.declare_entry("Schemes", "forward Euler, backward Euler",
                        Patterns::List(Patterns::Selection("forward Euler|backward Euler")),
                        "Time integrators to compare.");
      prm.declare_entry("Horizon factor", "5", Patterns::Double(1.), "m = delta/dx.");
      prm.declare_entry("Implicit time step", "1e-5", Patterns::Double(0.),
                        "dt for backward Euler (forward Euler uses Time stepping/Time step).");
      prm.declare_entry("Minimum observed order", "1.5", Patterns::Double(),
                        "Lower end of the accepted observed order between the two finest grids.");
      prm.declare_entry("Maximum observed order", "2.5", Patterns::Double(),
                        "Upper end of the accepted observed order.");
      prm.declare_entry("Output directory", "step-1-output", Patterns::Anything(), "");
      prm.leave_subsection();
    }
    void
    parse(ParameterHandler &prm)
    {
      prm.enter_subsection("Study");
      for (const auto &s : Utilities::split_string_list(prm.get("Divisions")))
        divisions.push_back(Utilities::string_to_int(s));
      schemes            = Utilities::split_string_list(prm.get("Schemes"));
      horizon_factor     = prm.get_double("Horizon factor");
      implicit_time_step = prm.get_double("Implicit time step");
      min_order          = prm.get_double("Minimum observed order");
      max_order          = prm.get_double("Maximum observed order");
      output             = prm.get("Output directory");
      prm.leave_subsection();
      check_parameter(divisions.size() >= 2, "Study/Divisions", prm.get("Study/Divisions"),
                      "at least two grids");
    }
  };

  // @sect3{One run}
  // Sets dx, delta and the scheme, then lets DiffusionSolver do the work.
  // The manufactured source needs delta, which the expressions get as a
  // constant.
  struct Result
  {
    double                                 dx, error;
    types::global_dof_index                nodes;
    std::vector<std::pair<double, double>> history;
    double                                 seconds;
    double                                 time_step;
    // Final values and C_ex at the owned body nodes (the same order for
    // every scheme on a grid), for the error of the schemes' mean.
    std::vector<double> values, exact;
  };

  Result
  run_one(ParameterHandler &prm, const unsigned int n, const std::string &scheme,
          const Parameters &study)
  {
    DiffusionRunParameters<2> p;
    p.parse_parameters(prm);
    p.lattice.dx              = 1. / n;
    p.lattice.delta           = study.horizon_factor / n;
    // The layer holds every node a body node is bonded to (partial volumes
    // reach delta + dx/2; a layer of delta misses some at the corners).
    p.lattice.layer_thickness = p.lattice.delta + 0.5 * p.lattice.dx;
    p.constants = "delta=" + Utilities::to_string(p.lattice.delta, 17);
    p.scheme    = scheme;
    if (scheme == "backward Euler")
      p.time_step = study.implicit_time_step;
    p.output_directory = study.output + "/n" + std::to_string(n) +
                         (scheme == "forward Euler" ? "-explicit" : "-implicit");

    Timer               timer;
    DiffusionSolver<2> solver(MPI_COMM_WORLD, p);
    solver.setup();
    solver.run();
    Result r;
    r.dx      = p.lattice.dx;
    r.error   = solver.diagnostics().error;
    r.nodes   = solver.discretization().n_global();
    r.seconds = timer.wall_time();
    r.time_step = p.time_step;
    FunctionParser<2> exact(1);
    exact.initialize("x,y,t", p.exact_solution, {{"pi", numbers::PI}}, true);
    exact.set_time(solver.time());
    const auto &disc = solver.discretization();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<2>::interior)
        {
          r.values.push_back(solver.solution().local_element(i));
          r.exact.push_back(exact.value(disc.position[i]));
        }
    for (const auto &d : solver.history())
      r.history.emplace_back(d.time, d.error);
    return r;
  }
} // namespace Step1

int
main(int argc, char **argv)
{
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;

      ParameterHandler prm;
      DiffusionRunParameters<2>::declare_parameters(prm);
      Step1::Parameters::declare(prm);
      prm.parse_input(argc > 1 ? argv[1] : "step-1.prm");
      Step1::Parameters study;
      study.parse(prm);

      // @sect3{The study}
      std::map<std::string, std::vector<Step1::Result>> results;
      for (const auto &scheme : study.schemes)
        for (const unsigned int n : study.divisions)
          results[scheme].push_back(Step1::run_one(prm, n, scheme, study));

      ConvergenceTable table;
      for (unsigned int k = 0; k < study.divisions.size(); ++k)
        {
          table.add_value("1/dx", study.divisions[k]);
          table.add_value("nodes", results.begin()->second[k].nodes);
          for (const auto &scheme : study.schemes)
            {
              const std::string key = scheme == "forward Euler" ? "explicit" : "implicit";
              table.add_value("e " + key, results[scheme][k].error);
              table.add_value("s " + key, results[scheme][k].seconds);
              table.set_scientific("e " + key, true);
              table.set_precision("e " + key, 3);
              table.set_precision("s " + key, 1);
            }
        }
      for (const auto &scheme : study.schemes)
        table.evaluate_convergence_rates(
          "e " + std::string(scheme == "forward Euler" ? "explicit" : "implicit"),
          "1/dx", ConvergenceTable::reduction_rate_log2, 1);

      bool ok = true;
      if (root)
        {
          std::cout << "\nRelative l2 error (3.79) at the end time, delta = "
                    << study.horizon_factor << " dx:\n";
          table.write_text(std::cout, TableHandler::org_mode_table);

          // Error histories, one CSV per grid and scheme, and a gnuplot plot.
          std::filesystem::create_directories(study.output);
          std::ofstream csv(study.output + "/error_history.csv");
          csv << "scheme,n,time,error\n";
          for (const auto &[scheme, rs] : results)
            for (unsigned int k = 0; k < rs.size(); ++k)
              for (const auto &h : rs[k].history)
                csv << (scheme == "forward Euler" ? "explicit" : "implicit") << ","
                    << study.divisions[k] << "," << h.first << "," << h.second << "\n";
          csv.close();
          std::string gp = gnuplot_png_preamble(study.output + "/error_history.png") +
                           "set datafile separator ','\nset logscale y\nset xlabel 'time'\n"
                           "set ylabel 'relative l2 error (3.79)'\nset format y '%.0e'\n"
                           "set key bottom right\nplot ";
          bool first = true;
          for (const auto &[scheme, rs] : results)
            for (unsigned int k = 0; k < rs.size(); ++k)
              {
                const std::string tag = scheme == "forward Euler" ? "explicit" : "implicit";
                gp += std::string(first ? "" : ", ") + "'" + study.output +
                      "/error_history.csv' using ($2==" + std::to_string(study.divisions[k]) +
                      " && strcol(1) eq '" + tag + "' ? $3 : 1/0):4 with lines lw 2 title '" + tag +
                      " dx = 1/" + std::to_string(study.divisions[k]) + "'";
                first = false;
              }
          run_gnuplot(study.output + "/plot.gp", gp + "\n", study.output + "/error_history.png");

          // @sect3{Checks}
          // The error of either Euler scheme is the spatial (quadrature)
          // error plus an O(dt) time error, and the two time errors have
          // opposite signs. The mean of the two final fields cancels the
          // O(dt) part, so its error is the spatial error, which at fixed m
          // scales with the effective diffusivity pi delta^2/4 ~ dx^2:
          // order 2 between the two finest grids.
          const unsigned int K = study.divisions.size();
          auto order_of = [&](const double e_coarse, const double e_fine) {
            return std::log(e_coarse / e_fine) /
                   std::log(double(study.divisions[K - 1]) / study.divisions[K - 2]);
          };
          auto check_order = [&](const std::string &what, const double order) {
            const bool in = order >= study.min_order && order <= study.max_order;
            std::cout << (in ? "  ok    " : "  FAIL  ") << what << ": observed order " << order
                      << " in [" << study.min_order << ", " << study.max_order << "]\n";
            ok = ok && in;
          };
          if (results.size() == 2)
            {
              const auto &a = results["forward Euler"], &b = results["backward Euler"];
              std::vector<double> e_mean(K);
              for (unsigned int k = 0; k < K; ++k)
                {
                  double local[2] = {0., 0.};
                  for (unsigned int i = 0; i < a[k].values.size(); ++i)
                    {
                      const double m = 0.5 * (a[k].values[i] + b[k].values[i]) - a[k].exact[i];
                      local[0] += m * m;
                      local[1] += a[k].exact[i] * a[k].exact[i];
                    }
                  double global[2];
                  Utilities::MPI::sum(ArrayView<const double>(local, 2), MPI_COMM_WORLD,
                                      ArrayView<double>(global, 2));
                  e_mean[k] = std::sqrt(global[0] / global[1]);
                }
              std::cout << "Error of the mean of the explicit and implicit fields (O(dt) cancelled):";
              for (unsigned int k = 0; k < K; ++k)
                std::cout << " " << e_mean[k];
              std::cout << "\n";
              check_order("mean of the schemes", order_of(e_mean[K - 2], e_mean[K - 1]));
              for (const auto &[scheme, rs] : results)
                std::cout << "  (" << scheme << " alone: observed order "
                          << order_of(rs[K - 2].error, rs[K - 1].error) << ", O(dt) included)\n";

              // The two schemes solve the same semi-discrete system, whose
              // operator is symmetric and dissipative, so each one's global
              // time error is at most (dt/2) T max_t |u_tt| (sum of the local
              // truncation errors); for (3.77) |u_tt| / |u(T)| = 25 / sin(5T).
              prm.enter_subsection("Time stepping");
              const double T = prm.get_double("End time");
              prm.leave_subsection();
              const double bound = 0.5 * (a[0].time_step + b[0].time_step) * T * 25. /
                                   std::abs(std::sin(5. * T));
              for (unsigned int k = 0; k < K; ++k)
                {
                  const double diff = std::abs(a[k].error - b[k].error);
                  const bool   in   = diff <= bound;
                  std::cout << (in ? "  ok    " : "  FAIL  ") << "n = " << study.divisions[k]
                            << ": explicit and implicit errors differ by " << diff
                            << " (a-priori time-error bound " << bound << ")\n";
                  ok = ok && in;
                }
            }
          else
            for (const auto &[scheme, rs] : results)
              check_order(scheme, order_of(rs[K - 2].error, rs[K - 1].error));
          std::cout << (ok ? "step-1: PASSED" : "step-1: FAILED") << std::endl;
        }
      ok = Utilities::MPI::logical_or(!ok, MPI_COMM_WORLD) ? false : true;
      return ok ? 0 : 1;
    }
  catch (std::exception &e)
    {
      std::cerr << "\nstep-1: error: " << e.what() << std::endl;
      return 1;
    }
}
