// step-12: local boundary conditions in steady PD diffusion on a cracked
// disk: the naive, Taylor and mirror fictitious-node methods (FNM) of paper
// 004 (Zhao, Jafarzadeh, Chen, Bobaru), against a deal.II FEM solution of
// the same classical problem.
//
// The idea of this step: a nonlocal model has no boundary on which to
// impose u = u_b or du/dn = q. Instead the body is surrounded by a
// fictitious collar Gamma of width delta, and the values there are chosen so
// that the local condition holds approximately:
//   naive   every fictitious node takes the boundary value (Dirichlet) or
//           is dropped (zero flux);
//   Taylor  per bond, a linear extrapolation through the boundary point on
//           the bond, stabilized by lambda = 1.5 (eq. 7);
//   mirror  every fictitious node x_G has a mirror node x_m inside, found
//           automatically (Sect. 3.4) from the PD gradient of the index
//           function r (14)-(16); then u_G = 2 u_b - u_m (Dirichlet) or
//           u_G = u_m - |x_G x_m| q (Neumann).
// A crack is the same thing from inside: bonds crossing it are cut, and a
// node across the crack acts as a fictitious node, mirrored on the node's
// own side (insulated crack faces: u_G = u_m).
//
// Problem: unit disk, straight crack [-1/2, 1/2] x {0} (and, with 'Crossing
// cracks', also {0} x [-1/2, 1/2]), u = y + x/2 on the circle, insulated
// crack faces; steady PD diffusion with kernel 1/|xi|^2 (eq. 4). Reference:
// Q2 FEM on a disk mesh with the cracks as slits, adaptively refined by the
// Kelly estimator.
//
// The program prints max |u_PD - u_FEM| for each method and grid, writes the
// error fields of the finest grid and plots them, and returns non-zero
// unless every method converges.
//
// Second part (transient, 'Transient grid spacing' > 0): forward Euler with
// the mirror FNM operator from u = 0 on the disk with one crack; at
// 'Crack time' the second crack {0} x [-1/2, 1/2] appears (fracture), at
// 'Corrosion time' a pit of radius 1/4 around (1, 0) dissolves (corrosion).
// Each change rebuilds the index function and the mirror nodes near it
// (FictitiousNodeProblem::change_domain). The run must end at the steady
// solution of a problem set up from scratch on the final geometry.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/utilities.h>

#include <perideal/base/exceptions.h>
#include <perideal/boundary/fictitious_nodes.h>
#include <perideal/boundary/fnm_benchmarks.h>
#include <perideal/io/plot.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEAL::Boundary;

namespace
{
  /** max |a - b| over the body nodes of @p fnm (b on the same lattice). */
  double
  max_difference(const FictitiousNodeProblem<2> &fnm, const std::vector<double> &a, const std::vector<double> &b)
  {
    double d = 0.;
    for (unsigned int i = 0; i < fnm.position.size(); ++i)
      if (fnm.in_domain[i])
        d = std::max(d, std::abs(a[i] - b[i]));
    return d;
  }

  /** The transient run with a crack and a corrosion pit appearing; true if it ends at the steady state. */
  bool
  transient_run(const double dx, const double m, const double crack_time, const double corrosion_time,
                const double end_time, const std::string &out, const bool root)
  {
    const BallDomain<2>       disk(Point<2>(), 1.);
    const LevelSetDomain<2>   pitted("max(sqrt(x^2 + y^2) - 1, 0.25 - sqrt((x - 1)^2 + y^2))", Point<2>(-1., -1.),
                                   Point<2>(1., 1.));
    const auto                cracks = Benchmarks::disk_cracks(true);
    FictitiousNodeParameters  p;
    p.dx     = dx;
    p.delta  = m * dx;
    p.method = FictitiousNodeMethod::mirror;
    // u = y + x/2 (harmonic) on the circle and on the pit surface.
    const BoundaryData<2> bc = [](const Point<2> &x) { return LocalCondition::make_dirichlet(x[1] + 0.5 * x[0]); };

    // The steady states of the three geometries, from scratch.
    // (The scratch lattices are the same, but hold fewer collar nodes:
    // values are transferred by position.)
    FictitiousNodeProblem fnm(MPI_COMM_WORLD, disk, {cracks[0]}, p);
    std::vector<std::vector<double>> steady;
    std::vector<unsigned int>        n_fictitious;
    const std::vector<std::pair<const Domain<2> *, std::vector<Crack>>> geometries = {
      {&disk, {cracks[0]}}, {&disk, cracks}, {&pitted, cracks}};
    for (const auto &g : geometries)
      {
        FictitiousNodeProblem scratch(MPI_COMM_WORLD, *g.first, g.second, p);
        scratch.solve(bc);
        steady.emplace_back(fnm.position.size(), 0.);
        for (unsigned int i = 0; i < fnm.position.size(); ++i)
          if (g.first->inside(fnm.position[i]))
            steady.back()[i] = scratch.value_at(fnm.position[i]);
        n_fictitious.push_back(scratch.fictitious.size());
      }

    fnm.solution.assign(fnm.position.size(), 0.);
    const double       dt       = fnm.gershgorin_time_step(bc).time_step;
    const unsigned int chunk    = std::max(1u, unsigned(std::lround(0.02 / dt)));
    double             t        = 0.;
    unsigned int       geometry = 0;
    std::ofstream      history;
    if (root)
      {
        history.open(out + "/transient.dat");
        history << "# t  max|u - u_steady(current geometry)|  max|u - u_steady(final geometry)|\n";
        std::cout << "\nTransient mirror FNM run, dx = " << dx << ", delta = " << m * dx << ", "
                  << fnm.n_unknowns() << " nodes, Gershgorin dt = " << dt << "\n";
      }
    const auto step_over = [&](const double until) {
      while (t < until - 0.5 * dt)
        {
          const unsigned int n = std::min<unsigned int>(chunk, std::lround((until - t) / dt));
          fnm.advance([&](const Point<2> &x, double) { return bc(x); }, TransientSource<2>(), t, dt, std::max(n, 1u));
          if (root)
            history << t << ' ' << max_difference(fnm, fnm.solution, steady[geometry]) << ' '
                    << max_difference(fnm, fnm.solution, steady.back()) << '\n';
        }
    };
    const auto change = [&](const Domain<2> *body, const std::vector<Crack> &new_cracks, const char *what) {
      const unsigned int rebuilt = fnm.change_domain(body, new_cracks);
      ++geometry;
      if (root)
        std::cout << "t = " << t << ": " << what << ", mirror data of " << rebuilt << " of "
                  << fnm.fictitious.size() << " fictitious nodes recomputed (from scratch: "
                  << n_fictitious[geometry] << " fictitious nodes)\n";
    };
    step_over(crack_time);
    change(nullptr, {cracks[1]}, "second crack");
    step_over(corrosion_time);
    change(&pitted, {}, "corrosion pit");
    step_over(end_time);
    const double final_difference = max_difference(fnm, fnm.solution, steady.back());
    if (root)
      {
        history.close();
        std::cout << "t = " << t << ": max |u - u_steady(final geometry, from scratch)| = " << final_difference
                  << " (" << fnm.n_unknowns() << " nodes)\n";
        std::ostringstream script;
        script << gnuplot_png_preamble(out + "/transient.png") << "set logscale y\nset xlabel 't'\nset xrange [0:" << end_time << "]\n"
               << "set ylabel 'max |u - u_{steady}|'\nset grid\nset key top right\n"
               << "set arrow from " << crack_time << ", graph 0 to " << crack_time
               << ", graph 1 nohead dt 2\nset arrow from " << corrosion_time << ", graph 0 to " << corrosion_time
               << ", graph 1 nohead dt 2\nset title 'mirror FNM, forward Euler: second crack at t = " << crack_time
               << ", corrosion pit at t = " << corrosion_time << "'\nplot '" << out
               << "/transient.dat' using 1:2 with lines lw 2 title 'to the steady state of the current geometry', '"
               << out << "/transient.dat' using 1:3 with lines lw 2 title 'to the steady state of the final geometry'\n";
        run_gnuplot(out + "/transient.gp", script.str(), out + "/transient.png");
      }
    // The slowest mode decays like exp(-7.3 t) (measured in transient.dat,
    // doc.md): from ~0.1 at t = 0.3 to ~1e-9 at t = 3; 1e-6 leaves room for
    // shorter runs (End time >= 2).
    return final_difference < 1e-6;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  try
    {
      ParameterHandler prm;
      prm.enter_subsection("Problem");
      prm.declare_entry("Crossing cracks", "false", Patterns::Bool(), "Add the crack {0} x [-1/2, 1/2].");
      prm.declare_entry("Grid spacings", "0.04, 0.02, 0.01", Patterns::List(Patterns::Double(0.)),
                        "Lattice spacings dx (decreasing).");
      prm.declare_entry("Horizon factor", "4", Patterns::Double(1.), "m = delta / dx.");
      prm.declare_entry("FEM initial refinements", "3", Patterns::Integer(1, 8), "");
      prm.declare_entry("FEM Kelly cycles", "8", Patterns::Integer(0, 20), "");
      prm.declare_entry("Output directory", "step-12-output", Patterns::Anything(), "");
      prm.declare_entry("Transient grid spacing", "0.04", Patterns::Double(0.),
                        "dx of the transient run (0: no transient run).");
      prm.declare_entry("Crack time", "0.1", Patterns::Double(0.), "The second crack appears.");
      prm.declare_entry("Corrosion time", "0.3", Patterns::Double(0.), "The pit at (1, 0) dissolves.");
      prm.declare_entry("End time", "3", Patterns::Double(0.), "");
      prm.leave_subsection();
      if (argc > 1)
        prm.parse_input(argv[1]);
      prm.enter_subsection("Problem");
      const bool   crossing = prm.get_bool("Crossing cracks");
      const double m        = prm.get_double("Horizon factor");
      std::vector<double> dxs;
      for (const auto &s : Utilities::split_string_list(prm.get("Grid spacings")))
        dxs.push_back(Utilities::string_to_double(s));
      const unsigned int initial = prm.get_integer("FEM initial refinements");
      const unsigned int cycles  = prm.get_integer("FEM Kelly cycles");
      const std::string  out     = prm.get("Output directory");
      const double       transient_dx   = prm.get_double("Transient grid spacing");
      const double       crack_time     = prm.get_double("Crack time");
      const double       corrosion_time = prm.get_double("Corrosion time");
      const double       end_time       = prm.get_double("End time");
      prm.leave_subsection();
      check_parameter(crack_time <= corrosion_time && corrosion_time <= end_time, "Problem/End time", end_time,
                      ">= Corrosion time >= Crack time");
      check_parameter(!dxs.empty(), "Problem/Grid spacings", "an empty list", "at least one spacing");
      if (root)
        std::filesystem::create_directories(out);

      // The reference.
      const auto fem = Benchmarks::cracked_disk_fem(crossing, initial, cycles);
      if (root)
        std::cout << "FEM reference: Q2, " << fem->get_triangulation().n_active_cells() << " cells, "
                  << fem->n_dofs() << " dofs (" << cycles << " Kelly cycles)\n\n"
                  << std::setw(8) << "dx" << std::setw(8) << "delta" << std::setw(9) << "nodes"
                  << std::setw(13) << "naive" << std::setw(13) << "taylor" << std::setw(13) << "mirror"
                  << std::setw(11) << "t_mirror" << "   (max |u_PD - u_FEM|, solve time [s])\n";

      const FictitiousNodeMethod methods[3] = {FictitiousNodeMethod::naive, FictitiousNodeMethod::taylor,
                                               FictitiousNodeMethod::mirror};
      const BallDomain<2>        body(Point<2>(), 1.);
      std::vector<std::array<double, 3>> table;
      for (unsigned int l = 0; l < dxs.size(); ++l)
        {
          std::array<double, 3> diff, rms;
          double                seconds = 0.;
          unsigned int          n_nodes = 0;
          for (unsigned int k = 0; k < 3; ++k)
            {
              FictitiousNodeParameters p;
              p.dx     = dxs[l];
              p.delta  = m * dxs[l];
              p.method = methods[k];
              FictitiousNodeProblem fnm(MPI_COMM_WORLD, body, Benchmarks::disk_cracks(crossing), p);
              fnm.solve([](const Point<2> &x) {
                return LocalCondition::make_dirichlet(Benchmarks::disk_dirichlet(x));
              });
              seconds = fnm.last_solve_seconds;
              n_nodes = fnm.n_unknowns();
              std::vector<Point<2>> nodes;
              std::vector<double>   pd;
              for (unsigned int i = 0; i < fnm.position.size(); ++i)
                if (fnm.in_domain[i])
                  {
                    nodes.push_back(fnm.position[i]);
                    pd.push_back(fnm.solution[i]);
                  }
              const auto ref = fem->values_at(nodes);
              diff[k]        = 0.;
              double sum2 = 0.;
              unsigned int n_found = 0;
              std::ofstream field;
              if (root && l + 1 == dxs.size())
                field.open(out + "/error-" + to_string(methods[k]) + ".dat");
              for (unsigned int i = 0; i < nodes.size(); ++i)
                if (!std::isnan(ref[i]))
                  {
                    diff[k] = std::max(diff[k], std::abs(pd[i] - ref[i]));
                    sum2 += (pd[i] - ref[i]) * (pd[i] - ref[i]);
                    ++n_found;
                    if (field)
                      field << nodes[i][0] << ' ' << nodes[i][1] << ' ' << pd[i] - ref[i] << ' ' << pd[i]
                            << '\n';
                  }
              rms[k] = std::sqrt(sum2 / std::max(n_found, 1u));
            }
          table.push_back(diff);
          if (root)
            std::cout << std::setw(8) << dxs[l] << std::setw(8) << m * dxs[l] << std::setw(9) << n_nodes
                      << std::scientific << std::setprecision(3) << std::setw(13) << diff[0] << std::setw(13)
                      << diff[1] << std::setw(13) << diff[2] << std::defaultfloat << std::setprecision(4)
                      << std::setw(11) << seconds << "\n" << std::setw(25) << "rms:" << std::scientific
                      << std::setprecision(3) << std::setw(13) << rms[0] << std::setw(13) << rms[1]
                      << std::setw(13) << rms[2] << std::defaultfloat << std::endl;
        }

      if (root)
        {
          std::ostringstream script;
          script << "set terminal pngcairo size 1500,480 font ',10'\nset output '" << out << "/errors.png'\n"
                 << "set multiplot layout 1,3\nset size ratio -1\nset palette defined "
                 << "(-1 'blue', 0 'white', 1 'red')\nset cbrange [-0.05:0.05]\nunset key\n";
          for (const auto &method : {"naive", "taylor", "mirror"})
            script << "set title 'u_{PD} - u_{FEM}, " << method << " FNM (dx = " << dxs.back()
                   << ", m = " << m << ")'\nplot '" << out << "/error-" << method
                   << ".dat' using 1:2:3 with points pt 5 ps 0.3 lc palette\n";
          script << "unset multiplot\n";
          run_gnuplot(out + "/errors.gp", script.str(), out + "/errors.png");
        }

      // Check: the max-norm difference of every method to the classical
      // solution decreases under delta-refinement (Sect. 4.3 of paper 004).
      // The paper's claim that the mirror FNM is the closest is NOT
      // reproduced in the max norm here (its maximum sits at the crack tips);
      // see doc.md.
      bool ok = true;
      for (unsigned int l = 1; l < table.size(); ++l)
        for (unsigned int k = 0; k < 3; ++k)
          ok = ok && table[l][k] < table[l - 1][k];
      if (root)
        std::cout << (ok ? "PASSED" : "FAILED")
                  << ": max |u_PD - u_FEM| decreases under delta-refinement for all three methods" << std::endl;
      if (transient_dx > 0.)
        {
          const bool steady_reached = transient_run(transient_dx, m, crack_time, corrosion_time, end_time, out, root);
          if (root)
            std::cout << (steady_reached ? "PASSED" : "FAILED")
                      << ": the transient run with the changing domain ends at the steady FNM solution of the "
                         "final geometry set up from scratch (< 1e-6)"
                      << std::endl;
          ok = ok && steady_reached;
        }
      return ok ? 0 : 1;
    }
  catch (const std::exception &e)
    {
      std::cerr << "step-12: " << e.what() << std::endl;
      return 1;
    }
}
