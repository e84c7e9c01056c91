// step-4: the Kalthoff-Winkler experiment with bond-based PD and brittle
// fracture (dissertation Sect. 3.3.1 / 3.5.1; multi-adaptive paper Sect. 4.1).
//
// The idea of this step: a dynamic fracture run through the library's
// mechanics driver (MechanicsSolver, the code behind `perideal` with
// `Problem = mechanics`), and *measurements* taken from the damage field by
// the library while the run goes on: the crack angle, the crack length and
// tip speed, and the energy in a circle around the upper pre-crack tip. All
// of them are columns of the CSV time series, so a run can be judged
// without ParaView, and this program checks them against the experiment and
// against theory.
//
// Problem: a 100 mm x 200 mm plate of 18Ni1900 maraging steel (plane
// strain, nu = 1/4, E = 190 GPa, rho = 8000 kg/m^3, G0 = 22170 J/m^2) with
// two 50 mm pre-cracks 50 mm apart; the part of the left edge between them
// moves with v0 = 16.5 m/s for the whole run (87.5 us). In the experiment
// (Kalthoff 2000) cracks grow from the tips at about 68 degrees to the
// impact direction.
//
// The crack angle: the nodes up and to the right of the upper tip with
// damage (2.36) >= 0.35 (nodes next to a crack lose about half their bonds,
// phi ~ 0.4-0.5; the pre-crack's shadow ahead of the tip stays below 0.3),
// at a distance between delta (outside the tip's own damage) and 50 mm from
// the tip, are fitted by a total-least-squares line (principal axis of their
// volume-weighted covariance); its angle to the x axis is the crack angle.
// The crack length is the largest distance of such a node from the tip, and
// the tip speed its growth between rows of the CSV.
//
// Checks (exit code):
//  1. Crack angle at the end within 68 +- 8 degrees: the experiment
//     ("about 68 degrees") plus the few degrees by which the model choices
//     (bond-based, nu = 1/4, constant influence function, delta = 4 mm, the
//     held 16.5 m/s instead of the 32 m/s impact) and a coarse lattice may
//     move it. The band was fixed before the first run, not fitted to this
//     code's output; measured: 62.1 (m = 4), 62.5 (m = 12), see doc.md.
//  2. The mean tip speed over the propagation phase is positive and below
//     the Rayleigh wave speed c_R = 0.9194 c_s (nu = 1/4), the theoretical
//     limit of a mode-I crack.
//  3. Energy balance of the reaction force: until the first bond breaks,
//     E(t) - E(0) = int_0^t R(s) . v0 ds (the work of the support on the
//     held edge; no bond energy is lost yet), within 1 %: the error is that
//     of the trapezoidal rule on the CSV rows (R oscillates; 0.2 % with a row
//     every 2 steps at m = 4, 0.9 % every 4 steps, 0.7 % every 5 steps at
//     m = 12) and of Verlet.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <perideal/base/exceptions.h>
#include <perideal/io/plot.h>
#include <perideal/io/time_series.h>
#include <perideal/time_stepping/diffusion_solver.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include <algorithm>
#include <cmath>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step4
{
  // The mean crack-tip speed: slope of the least-squares line through the
  // crack length over the rows where the crack is growing (length beyond
  // delta and below the fit radius).
  double
  mean_tip_speed(const std::vector<std::vector<double>> &rows,
                 const unsigned int                      length_col,
                 const double                            from,
                 const double                            to)
  {
    double n = 0., st = 0., sl = 0., stt = 0., stl = 0.;
    for (const auto &r : rows)
      if (r[length_col] > from && r[length_col] < to)
        {
          n += 1.;
          st += r[0];
          sl += r[length_col];
          stt += r[0] * r[0];
          stl += r[0] * r[length_col];
        }
    return n >= 3. ? (n * stl - st * sl) / (n * stt - st * st) : 0.;
  }

  int
  run(const std::string &file, const bool evaluate_only)
  {
    ParameterHandler prm;
    prm.declare_entry("Dimension", "2", Patterns::Integer(2, 2), "2 only.");
    prm.declare_entry("Problem", "mechanics", Patterns::Selection("mechanics"), "mechanics only.");
    // The driver's entries (Geometry, Discretization, Time stepping, Output
    // are declared with the diffusion runs).
    DiffusionRunParameters<2>::declare_parameters(prm);
    MechanicsRunParameters<2>::declare_parameters(prm);
    prm.parse_input(file);

    MechanicsRunParameters<2> parameters;
    parameters.parse_parameters(prm);
    check_parameter(parameters.measure_crack && parameters.energy_radius > 0.,
                    "Measurements", "(off)", "a crack origin and an energy circle");
    MechanicsSolver<2> solver(MPI_COMM_WORLD, parameters);
    const auto         cols = solver.time_series_columns();
    std::vector<std::vector<double>> rows;
    double                           bond_rate = 0., stepping_time = 0.;
    if (evaluate_only)
      {
        // The CSV of an earlier run of this parameter file.
        TimeSeries series(MPI_COMM_WORLD, parameters.output_directory + "/time_series.csv", cols, true);
        rows = series.rows();
        AssertThrow(rows.size() > 1, ExcMessage("No time series to evaluate."));
      }
    else
      {
        solver.setup();
        solver.run();
        rows          = solver.time_series();
        bond_rate     = solver.bond_updates_per_second_per_core();
        stepping_time = solver.stepping_wall_time();
      }

    const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
    const auto col  = [&](const std::string &name) {
      return (unsigned int)(std::find(cols.begin(), cols.end(), name) - cols.begin());
    };
    const auto  &last  = rows.back();
    const double angle = last[col("crack_angle")], length = last[col("crack_length")];
    const double delta = parameters.lattice.delta;
    const double speed =
      mean_tip_speed(rows, col("crack_length"), delta, parameters.crack_fit_max_radius);
    const double E = parameters.model.youngs_modulus, nu = 0.25, rho = parameters.density;
    const double c_s = std::sqrt(E / (2. * (1. + nu)) / rho), c_R = 0.9194 * c_s;

    // Energy balance until the first bond (beyond the pre-cracks) breaks.
    const unsigned int broken_col = col("broken_bonds"), rx = col("reaction_1_x");
    const double       v0         = 16.5e3;
    double             work = 0., balance = 0., t_balance = 0.;
    for (std::size_t k = 1; k < rows.size() && rows[k][broken_col] == rows[0][broken_col]; ++k)
      {
        work += 0.5 * (rows[k][rx] + rows[k - 1][rx]) * v0 * (rows[k][0] - rows[k - 1][0]);
        const double gained = rows[k][col("total_energy")] - rows[0][col("total_energy")];
        balance             = std::abs(gained - work) / std::max(std::abs(work), 1e-300);
        t_balance           = rows[k][0];
      }

    // Energy in the circle: its largest value and when.
    double e_max = 0., t_e_max = 0.;
    for (const auto &r : rows)
      if (r[col("circle_energy")] > e_max)
        {
          e_max   = r[col("circle_energy")];
          t_e_max = r[0];
        }

    int failures = 0;
    if (root)
      {
        std::cout << "\nResults at t = " << last[0] << " s:\n"
                  << "  crack angle          " << angle << " deg (" << last[col("crack_nodes")]
                  << " nodes with damage >= " << parameters.damage_threshold << ")\n"
                  << "  crack length         " << length << " mm from the upper tip\n"
                  << "  mean tip speed       " << speed << " mm/s (c_R = " << c_R
                  << " mm/s, ratio " << speed / c_R << ")\n"
                  << "  circle energy max    " << e_max << " N mm at t = " << t_e_max << " s\n"
                  << "  energy balance       " << balance << " (relative, up to t = " << t_balance
                  << " s)\n"
                  << "  wall time            " << last[col("wall_time")] << " s (with output)\n";
        if (!evaluate_only)
          std::cout << "  stepping wall time   " << stepping_time << " s, " << bond_rate
                    << " bond updates per second per core\n";
        const auto check = [&](const bool ok, const std::string &what) {
          std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
          failures += ok ? 0 : 1;
        };
        check(std::abs(angle - 68.) <= 8., "crack angle within 68 +- 8 deg");
        check(speed > 0. && speed < c_R, "mean tip speed in (0, c_R)");
        check(t_balance > 0. && balance <= 1e-2, "E(t) - E(0) = work of the reaction force");

        // Damage field plot from the node table.
        const std::string dir = parameters.output_directory;
        const Point<2>    o   = parameters.crack_origin;
        const double      a = angle * M_PI / 180., r = parameters.crack_fit_max_radius;
        run_gnuplot(dir + "/damage.gp",
                    gnuplot_png_preamble(dir + "/damage.png") +
                      "set datafile separator ','\nset size ratio -1\nset xrange [0:100]\n"
                      "set yrange [-100:100]\nset cbrange [0:1]\nset xlabel 'x (mm)'\n"
                      "set ylabel 'y (mm)'\nset cblabel 'damage'\n"
                      "set palette defined (0 'white', 0.2 '#ffe090', 0.4 '#e04010', 1 'black')\n"
                      // The fitted crack line from the upper tip.
                      "set arrow from " + std::to_string(o[0]) + "," + std::to_string(o[1]) +
                      " rto " + std::to_string(r * std::cos(a)) + "," +
                      std::to_string(r * std::sin(a)) + " nohead dt 2 lw 2 lc rgb 'blue'\n"
                      "plot '" + dir + "/nodes.csv' every ::1 using 2:3:8 with points pt 5 "
                      "ps 0.15 lc palette notitle\n",
                    dir + "/damage.png");
        // Crack length and energy in the circle over time.
        const std::string csv = "'" + dir + "/time_series.csv'";
        run_gnuplot(dir + "/history.gp",
                    gnuplot_png_preamble(dir + "/history.png") +
                      "set datafile separator ','\nset xlabel 'time (us)'\n"
                      "set ylabel 'crack length from the upper tip (mm)'\n"
                      "set y2label 'energy in the 10 mm circle (N mm)'\nset y2tics\nset ytics nomirror\n"
                      "set key top left\nplot " + csv + " every ::1 using ($1*1e6):" +
                      std::to_string(col("crack_length") + 1) + " with lines lw 2 title 'crack length', " +
                      csv + " every ::1 using ($1*1e6):" + std::to_string(col("circle_energy") + 1) +
                      " axes x1y2 with lines lw 2 title 'kinetic + strain energy in the circle'\n",
                    dir + "/history.png");
      }
    return Utilities::MPI::max(failures, MPI_COMM_WORLD) == 0 ? 0 : 1;
  }
} // namespace Step4

int
main(int argc, char **argv)
{
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      // step-4 [FILE.prm] [--evaluate]: run, or evaluate the CSV of a run.
      std::string file = "step-4.prm";
      bool        evaluate_only = false;
      for (int a = 1; a < argc; ++a)
        if (std::string(argv[a]) == "--evaluate")
          evaluate_only = true;
        else
          file = argv[a];
      return Step4::run(file, evaluate_only);
    }
  catch (std::exception &e)
    {
      std::cerr << "step-4: error: " << e.what() << std::endl;
      return 1;
    }
}
