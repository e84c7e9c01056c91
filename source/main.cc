// The `perideal` driver: one parameter file in, one run out.
//
//   perideal FILE.prm                 run (also under mpirun -np N)
//   perideal --print-parameters       every parameter with documentation and range
//   perideal --resume FILE.prm        resume from the checkpoint in the output directory
//   perideal --stop-after-steps N FILE.prm   stop after N steps (tests of restart)
//   perideal --compare A.csv B.csv TOL  compare two node tables (exit 1 if max diff > TOL)

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/utilities.h>

#include <perideal/base/exceptions.h>
#include <perideal/io/checkpoint.h>
#include <perideal/io/plot.h>
#include <perideal/time_stepping/diffusion_solver.h>
#include <perideal/time_stepping/mechanics_solver.h>
#include <perideal/time_stepping/nnpp_run.h>
#include <perideal/time_stepping/static_mechanics.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;

namespace
{
  // deal.II exceptions carry a banner and a stack trace; users need the
  // explanation only.
  std::string
  user_message(const std::string &what)
  {
    const auto info = what.find("Additional information:");
    if (info == std::string::npos)
      return what;
    std::string text  = what.substr(info + 23);
    const auto  stack = text.find("Stacktrace:");
    if (stack != std::string::npos)
      text = text.substr(0, stack);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ' || text.back() == '-'))
      text.pop_back();
    return text;
  }

  void
  declare_all(ParameterHandler &prm)
  {
    prm.declare_entry("Dimension", "2", Patterns::Integer(1, 3),
                      "Spatial dimension of the run (1, 2 or 3).");
    prm.declare_entry("Problem", "diffusion", Patterns::Selection("diffusion|mechanics|static mechanics|nnpp"),
                      "diffusion: PD diffusion and bi-material corrosion (Model/Type); "
                      "mechanics: dynamic bond-based PD or LPS with brittle fracture "
                      "(Mechanics/Model, Model/Bond-based or Model/LPS, Mechanics); static mechanics: static equilibrium "
                      "of linearized bond-based PD or LPS (Static mechanics); nnpp: the nonlocal "
                      "Nernst-Planck-Poisson system with corrosion (NNPP).");
    // The entries do not depend on the dimension; declare them once.
    DiffusionRunParameters<2>::declare_parameters(prm);
    MechanicsRunParameters<2>::declare_parameters(prm);
    StaticMechanicsParameters<2>::declare_parameters(prm);
    NnppRunParameters<2>::declare_parameters(prm);
  }

  // A PNG of the time series.
  void
  plot_time_series(const std::string &dir, const bool corrosion, const bool has_error)
  {
    const std::string csv = "'" + dir + "/time_series.csv'";
    std::string       gp  = gnuplot_png_preamble(dir + "/time_series.png") +
                     "set datafile separator ','\nset key autotitle columnhead\nset xlabel 'time'\n";
    if (corrosion)
      gp += "set ylabel 'solid volume'\nset y2label 'Pi = sum C^2 V'\nset y2tics\nplot " + csv +
            " using 1:4 with lines lw 2, '' using 1:3 axes x1y2 with lines lw 2\n";
    else if (has_error)
      gp += "set ylabel 'relative l2 error (3.79)'\nset logscale y\nplot " + csv +
            " using 1:5 with lines lw 2\n";
    else
      gp += "set ylabel 'mass, Pi'\nplot " + csv +
            " using 1:2 with lines lw 2, '' using 1:3 with lines lw 2\n";
    run_gnuplot(dir + "/plot.gp", gp, dir + "/time_series.png");
  }

  // The parameter file used, next to the output.
  void
  write_used_parameters(const ParameterHandler &prm, const std::string &directory)
  {
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      {
        std::filesystem::create_directories(directory);
        const std::string used = directory + "/parameters.prm";
        std::ofstream     out(used + ".tmp");
        prm.print_parameters(out, ParameterHandler::PRM);
        out.close();
        std::filesystem::rename(used + ".tmp", used);
      }
    MPI_Barrier(MPI_COMM_WORLD);
  }

  template <int dim>
  void
  run_mechanics(ParameterHandler &prm, const bool resume, const unsigned int stop_after)
  {
    MechanicsRunParameters<dim> parameters;
    parameters.parse_parameters(prm);
    if (resume)
      parameters.resume = true;
    write_used_parameters(prm, parameters.output_directory);
    MechanicsSolver<dim> solver(MPI_COMM_WORLD, parameters);
    solver.setup();
    solver.run(stop_after);
    // Both are collective: evaluate them on every rank.
    const double        energy = solver.total_energy();
    const std::uint64_t broken = solver.model().n_broken_bonds();
    const auto          m      = solver.measure();
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      {
        std::cout << "Final: t = " << solver.integrator().time() << ", total energy = " << energy
                  << ", broken bonds = " << broken << std::endl;
        if (parameters.measure_crack)
          std::cout << "Crack: angle " << m.crack_angle << " deg (" << m.n_crack_nodes
                    << " nodes), length " << m.crack_length << std::endl;
        std::cout << "Stepping: " << solver.stepping_wall_time() << " s wall, "
                  << solver.bond_updates_per_second_per_core()
                  << " bond updates per second per core" << std::endl;
        const std::string dir = parameters.output_directory;
        const std::string csv = "'" + dir + "/time_series.csv'";
        run_gnuplot(dir + "/plot.gp",
                    gnuplot_png_preamble(dir + "/time_series.png") +
                      "set datafile separator ','\nset key autotitle columnhead\n"
                      "set xlabel 'time'\nset ylabel 'energy'\nplot " + csv +
                      " using 1:2 with lines lw 2, '' using 1:3 with lines lw 2, '' using 1:4 "
                      "with lines lw 2\n",
                    dir + "/time_series.png");
      }
  }

  template <int dim>
  void
  run_nnpp_problem(ParameterHandler &prm)
  {
    NnppRunParameters<dim> parameters;
    parameters.parse_parameters(prm);
    const std::string dir = parameters.output_directory;
    if (!dir.empty())
      write_used_parameters(prm, dir);
    const auto history = run_nnpp<dim>(parameters, MPI_COMM_WORLD);
    if (!dir.empty() && Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      {
        // Columns: time, amount_0 ... amount_{N-1}, solid_volume, max_abs_phi.
        const unsigned int n   = parameters.model.n_species();
        const std::string  csv = "'" + dir + "/time_series.csv'";
        std::string        gp  = gnuplot_png_preamble(dir + "/time_series.png") +
                         "set datafile separator ','\nset key autotitle columnhead\n"
                         "set xlabel 'time'\nset ylabel 'amount, solid volume'\n"
                         "set y2label 'max |phi|'\nset y2tics\nplot ";
        for (unsigned int k = 0; k < n; ++k)
          gp += (k == 0 ? csv : std::string("''")) + " using 1:" + std::to_string(k + 2) +
                " with lines lw 2, ";
        gp += "'' using 1:" + std::to_string(n + 2) + " with lines lw 2, '' using 1:" +
              std::to_string(n + 3) + " axes x1y2 with lines lw 2\n";
        run_gnuplot(dir + "/plot.gp", gp, dir + "/time_series.png");
      }
  }

  template <int dim>
  void
  run(ParameterHandler &prm, const bool resume, const unsigned int stop_after)
  {
    if (prm.get("Problem") == "static mechanics")
      {
        write_used_parameters(prm, prm.get({"Output"}, "Directory"));
        run_static_mechanics<dim>(prm, MPI_COMM_WORLD);
        return;
      }
    if (prm.get("Problem") == "nnpp")
      {
        // NNPP runs write no checkpoints yet: refuse rather than ignore.
        if (resume || stop_after != std::numeric_limits<unsigned int>::max())
          throw ParameterError("command line", resume ? "--resume" : "--stop-after-steps",
                               "no restart options for Problem = nnpp (no checkpoints yet)");
        run_nnpp_problem<dim>(prm);
        return;
      }
    if (prm.get("Problem") == "mechanics")
      {
        run_mechanics<dim>(prm, resume, stop_after);
        return;
      }
    DiffusionRunParameters<dim> parameters;
    parameters.parse_parameters(prm);
    if (resume)
      parameters.resume = true;

    const MPI_Comm comm = MPI_COMM_WORLD;
    write_used_parameters(prm, parameters.output_directory);

    DiffusionSolver<dim> solver(comm, parameters);
    solver.setup();
    solver.run(stop_after);

    const auto d = solver.diagnostics();
    if (Utilities::MPI::this_mpi_process(comm) == 0)
      {
        std::cout << "Final: t = " << d.time << ", mass = " << d.mass << ", Pi = " << d.pi;
        if (solver.get_operator().is_corrosion())
          std::cout << ", solid volume = " << d.solid_volume;
        if (!parameters.exact_solution.empty())
          std::cout << ", relative l2 error = " << d.error;
        std::cout << std::endl;
        if (solver.step() == solver.n_steps())
          plot_time_series(parameters.output_directory,
                           solver.get_operator().is_corrosion(),
                           !parameters.exact_solution.empty());
      }
    solver.timer().print_wall_time_statistics(comm);
  }
} // namespace

int
main(int argc, char **argv)
{
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;

      ParameterHandler prm;
      declare_all(prm);

      bool         resume     = false;
      unsigned int stop_after = std::numeric_limits<unsigned int>::max();
      std::string  file;
      for (int a = 1; a < argc; ++a)
        {
          const std::string arg = argv[a];
          if (arg == "--print-parameters")
            {
              if (root)
                prm.print_parameters(std::cout,
                                     ParameterHandler::PRM |
                                       ParameterHandler::KeepDeclarationOrder);
              return 0;
            }
          else if (arg == "--resume")
            resume = true;
          else if (arg == "--stop-after-steps" && a + 1 < argc)
            stop_after = std::stoul(argv[++a]);
          else if (arg == "--compare" && a + 3 < argc)
            {
              const double diff = compare_node_tables(argv[a + 1], argv[a + 2]);
              const double tol  = std::stod(argv[a + 3]);
              if (root)
                std::cout << "max difference " << diff << " (tolerance " << tol << ")"
                          << std::endl;
              return diff <= tol ? 0 : 1;
            }
          else if (arg == "--help" || arg == "-h")
            {
              if (root)
                std::cout << "usage: perideal [--resume] [--stop-after-steps N] FILE.prm\n"
                             "       perideal --print-parameters\n"
                             "       perideal --compare NODES_A.csv NODES_B.csv TOL\n";
              return 0;
            }
          else if (!arg.empty() && arg[0] == '-')
            throw ParameterError("command line", arg,
                                 "--print-parameters, --resume, --stop-after-steps N, "
                                 "--compare A B TOL, or a parameter file");
          else
            file = arg;
        }
      if (file.empty())
        throw ParameterError("command line", "(no parameter file)",
                             "a parameter file: perideal FILE.prm (see --print-parameters)");
      if (!std::ifstream(file))
        throw ParameterError("command line", file, "a readable parameter file");
      try
        {
          prm.parse_input(file);
        }
      catch (std::exception &e)
        {
          throw std::runtime_error("Could not read parameter file '" + file + "':\n" +
                                   user_message(e.what()));
        }

      switch (prm.get_integer("Dimension"))
        {
          case 1:
            run<1>(prm, resume, stop_after);
            break;
          case 2:
            run<2>(prm, resume, stop_after);
            break;
          default:
            run<3>(prm, resume, stop_after);
        }
    }
  catch (std::exception &e)
    {
      std::cerr << "\nperideal: error: " << user_message(e.what()) << std::endl;
      return 1;
    }
  catch (...)
    {
      std::cerr << "\nperideal: unknown error" << std::endl;
      return 1;
    }
  return 0;
}
