// step-2: the 1D bi-material PD corrosion problem of dissertation Sect. 3.4.1
// on uniform grids.
//
// The idea of this step: a model whose bonds change with the state. A node is
// solid while its concentration stays at or above C_sat (2.79); bonds between
// two liquid nodes carry kappa_liq, solid-liquid bonds kappa_int, solid-solid
// bonds nothing. The solid [-5, 5] (C = 1) dissolves into the liquid
// (C = 0) of [-50, 50] under homogeneous nonlocal Neumann conditions.
//
// The sources' numbers: delta = 1, C_sat = 0.85, kappa_liq = 2,
// kappa_int = 0.1, dt = 0.025; Coarse dx = 0.5 (201 nodes), Fine dx = 0.125
// (801 nodes; the printed 0.025 contradicts the printed node count, see the
// errata). The kernel exponent is not printed; we use J_1 (q = 1), the form
// the dissertation's units imply for its 3D corrosion examples, and keep it a
// parameter.
//
// This program marches each grid with forward and backward Euler until the
// solid has vanished, records the solid volume over time, and checks what the
// sources report qualitatively (Coarse versus Fine vanishing time) and checks
// invariants: mass conservation, a monotone corrosion front, and the
// agreement of the explicit and implicit vanishing times.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/table_handler.h>

#include <perideal/base/exceptions.h>
#include <perideal/io/plot.h>
#include <perideal/time_stepping/diffusion_solver.h>

#include <filesystem>
#include <fstream>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step2
{
  struct Run
  {
    std::string             grid, scheme;
    double                  dx = 0.;
    types::global_dof_index nodes = 0;
    double                  vanishing_time = -1.;
    double                  mass_error = 0.;
    bool                    front_monotone = true;
    std::vector<std::array<double, 3>> history; // t, solid volume, front position
    double seconds = 0.;
  };

  // Right end of the solid phase (the problem is symmetric).
  double
  front_position(const DiffusionSolver<1> &s)
  {
    double x = -1e300;
    for (unsigned int i = 0; i < s.discretization().n_owned(); ++i)
      if (s.phase_field().local_element(i) > 0.5)
        x = std::max(x, s.discretization().position[i][0]);
    return Utilities::MPI::max(x, MPI_COMM_WORLD);
  }

  // @sect3{One run}
  // The time loop is written out here (rather than DiffusionSolver::run())
  // because the run ends when the solid is gone.
  Run
  run_one(ParameterHandler &prm, const std::string &grid, const double dx,
          const std::string &scheme, const double t_max)
  {
    DiffusionRunParameters<1> p;
    p.parse_parameters(prm);
    p.lattice.dx = dx;
    p.scheme     = scheme;
    Run r;
    r.grid   = grid;
    r.scheme = scheme;
    r.dx     = dx;

    Timer              timer;
    DiffusionSolver<1> solver(MPI_COMM_WORLD, p);
    solver.setup();
    r.nodes            = solver.discretization().n_global();
    const double mass0 = solver.diagnostics().mass;
    double       last_front = front_position(solver);
    r.history.push_back({{0., solver.diagnostics().solid_volume, last_front}});
    while (solver.time() < t_max)
      {
        solver.advance();
        const auto   d     = solver.diagnostics();
        const double front = front_position(solver);
        r.history.push_back({{d.time, d.solid_volume, front}});
        r.mass_error = std::max(r.mass_error, std::abs(d.mass - mass0) / mass0);
        r.front_monotone = r.front_monotone && front <= last_front;
        last_front       = front;
        if (d.solid_volume == 0.)
          {
            r.vanishing_time = d.time;
            break;
          }
      }
    r.seconds = timer.wall_time();
    return r;
  }
} // namespace Step2

int
main(int argc, char **argv)
{
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;

      ParameterHandler prm;
      DiffusionRunParameters<1>::declare_parameters(prm);
      prm.enter_subsection("Study");
      prm.declare_entry("Coarse grid spacing", "0.5", Patterns::Double(0.), "dx+ (201 nodes).");
      prm.declare_entry("Fine grid spacing", "0.125", Patterns::Double(0.), "dx- (801 nodes).");
      prm.declare_entry("Schemes", "forward Euler, backward Euler",
                        Patterns::List(Patterns::Selection("forward Euler|backward Euler")), "");
      prm.declare_entry("Maximum time", "5000", Patterns::Double(0.),
                        "Give up if the solid has not vanished by then.");
      prm.declare_entry("Scheme agreement", "0.02", Patterns::Double(0.),
                        "Accepted relative difference of the vanishing times of the schemes.");
      prm.declare_entry("Output directory", "step-2-output", Patterns::Anything(), "");
      prm.leave_subsection();
      prm.parse_input(argc > 1 ? argv[1] : "step-2.prm");

      prm.enter_subsection("Study");
      const double      dx_coarse = prm.get_double("Coarse grid spacing");
      const double      dx_fine   = prm.get_double("Fine grid spacing");
      const auto        schemes   = Utilities::split_string_list(prm.get("Schemes"));
      const double      t_max     = prm.get_double("Maximum time");
      const double      agreement = prm.get_double("Scheme agreement");
      const std::string out       = prm.get("Output directory");
      prm.leave_subsection();

      std::vector<Step2::Run> runs;
      for (const auto &scheme : schemes)
        for (const auto &[grid, dx] : {std::make_pair(std::string("Coarse"), dx_coarse),
                                       std::make_pair(std::string("Fine"), dx_fine)})
          runs.push_back(Step2::run_one(prm, grid, dx, scheme, t_max));

      bool ok = true;
      if (root)
        {
          TableHandler table;
          for (const auto &r : runs)
            {
              table.add_value("grid", r.grid);
              table.add_value("dx", r.dx);
              table.add_value("nodes", r.nodes);
              table.add_value("scheme", r.scheme);
              table.add_value("vanishing time", r.vanishing_time);
              table.add_value("max rel. mass change", r.mass_error);
              table.add_value("wall s", r.seconds);
              table.set_scientific("max rel. mass change", true);
              table.set_precision("max rel. mass change", 2);
              table.set_precision("vanishing time", 6);
              table.set_precision("wall s", 2);
            }
          std::cout << "\n";
          table.write_text(std::cout, TableHandler::org_mode_table);

          std::filesystem::create_directories(out);
          std::ofstream csv(out + "/solid_volume.csv");
          csv << "grid,scheme,time,solid_volume,front\n";
          for (const auto &r : runs)
            for (const auto &h : r.history)
              csv << r.grid << "," << (r.scheme == "forward Euler" ? "explicit" : "implicit")
                  << "," << h[0] << "," << h[1] << "," << h[2] << "\n";
          csv.close();
          std::string gp = gnuplot_png_preamble(out + "/solid_volume.png") +
                           "set datafile separator ','\nset xlabel 'time'\n"
                           "set ylabel 'solid volume (length)'\nplot ";
          bool first = true;
          for (const auto &r : runs)
            {
              const std::string tag = r.scheme == "forward Euler" ? "explicit" : "implicit";
              gp += std::string(first ? "" : ", ") + "'" + out + "/solid_volume.csv' using (strcol(1) eq '" +
                    r.grid + "' && strcol(2) eq '" + tag + "' ? $3 : 1/0):4 with lines lw 2 title '" +
                    r.grid + " " + tag + "'";
              first = false;
            }
          run_gnuplot(out + "/plot.gp", gp + "\n", out + "/solid_volume.png");

          // @sect3{Checks}
          auto report = [&](const bool c, const std::string &what) {
            std::cout << (c ? "  ok    " : "  FAIL  ") << what << "\n";
            ok = ok && c;
          };
          for (const auto &r : runs)
            {
              const std::string tag = r.grid + " " + r.scheme;
              report(r.vanishing_time > 0., tag + ": the solid vanishes");
              // Round-off: the flux of every bond is antisymmetric.
              report(r.mass_error < 1e-12, tag + ": mass conserved to 1e-12");
              report(r.front_monotone, tag + ": the front moves monotonically");
            }
          // The sources report (Fig. 3.23) that the Coarse solid vanishes
          // earlier than the Fine one. Which grid wins depends on details the
          // sources do not print (kernel exponent, partial volumes; see the
          // doc page), so this is reported, not asserted.
          for (const auto &scheme : schemes)
            {
              double coarse = 0., fine = 0.;
              for (const auto &r : runs)
                if (r.scheme == scheme)
                  (r.grid == "Coarse" ? coarse : fine) = r.vanishing_time;
              std::cout << "  note  " << scheme << ": vanishing time Coarse " << coarse
                        << ", Fine " << fine << " (source, Fig. 3.23: Coarse earlier)\n";
            }
          if (schemes.size() == 2)
            for (const std::string grid : {"Coarse", "Fine"})
              {
                double t[2] = {0., 0.};
                for (const auto &r : runs)
                  if (r.grid == grid)
                    t[r.scheme == "forward Euler" ? 0 : 1] = r.vanishing_time;
                // Both are first order in dt = 0.025 and the vanishing time is
                // resolved to one step: they agree to O(dt / t_vanish) plus
                // the step quantization.
                const double rel = std::abs(t[0] - t[1]) / t[0];
                report(rel <= agreement, grid + ": explicit and implicit vanishing times differ by " +
                                           std::to_string(100 * rel) + " % (accepted " +
                                           std::to_string(100 * agreement) + " %)");
              }
          std::cout << (ok ? "step-2: PASSED" : "step-2: FAILED") << std::endl;
        }
      ok = Utilities::MPI::logical_or(!ok, MPI_COMM_WORLD) ? false : true;
      return ok ? 0 : 1;
    }
  catch (std::exception &e)
    {
      std::cerr << "\nstep-2: error: " << e.what() << std::endl;
      return 1;
    }
}
