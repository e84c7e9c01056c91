// step-6: PD bi-material corrosion of a solid in an unbounded electrolyte
// with EBF absorbing boundary conditions (dissertation Sect. 4.1.5, paper
// 002 Examples 2 and 3).
//
// The idea of this step: the near field is the corrosion model of step-2
// (three bond micro-diffusivities chosen by the phases of the end points,
// phase rule (2.79): a solid node turns liquid once C < C_sat). The
// electrolyte around it is unbounded. The near field is truncated by a
// circle (2D) or a sphere (3D); the nodes in the outermost delta_L are
// absorbing: their value at t^{n+1} is extrapolated from a cloud of values
// at t^n with the far-field modes exp(k n.x + D_liq k^2 t) of the liquid
// (Abc::EbfDiffusionAbc, as in step-5). A reference run on a much larger
// disc with homogeneous Neumann boundary (nothing reaches its boundary
// within the run) and a Neumann-truncated run show what the ABC buys.
//
// Problem (E10): solid letters "HZG" (polygons, C0 = 2), liquid C0 = 0,
// delta = 0.04, dx = 0.02, C_sat = 0.8, kappa_liq = 7957.70, kappa_int =
// 795.77, no solid-solid flux, near-field radius 2, reference radius 10,
// n_b = 55 modes. 3D (E11): a solid sphere of radius 3.33 (C0 = 1) in a
// near field of radius 5, delta = 0.2, dx = 0.1.
//
// Output: CSV of Pi on Omega_N (eq. 48 of 002), the normalized energy
// difference (4.35) and the solid volume; a gnuplot PNG.

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <perideal/abc/pd_unbounded_diffusion.h>
#include <perideal/base/exceptions.h>
#include <perideal/boundary/polygon_domain.h>
#include <perideal/io/plot.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

using namespace dealii;
using namespace PeriDEAL;

namespace Step6
{
  struct Parameters
  {
    unsigned int dim = 2;
    std::string  shape = "HZG";
    double       shape_size = 1., solid_concentration = 2.;
    double       R = 2., R_ref = 10., dx = 0.02, delta = 0.04, dt = 1e-5, t_end = 0.085;
    double       record_interval = 0.001;
    bool         neumann_run = true, cube = false;
    double       required_gain = 10.;
    std::string  output_directory = "step-6-output";
    DiffusionModelParameters model;
    Abc::EbfParameters       abc;

    void
    read(const std::string &file)
    {
      ParameterHandler prm;
      prm.enter_subsection("Problem");
      prm.declare_entry("Dimension", "2", Patterns::Integer(2, 3));
      prm.declare_entry("Solid shape", "HZG", Patterns::Selection("HZG|sphere"),
                        "HZG: three polygon letters (2D); sphere: a disc/ball.");
      prm.declare_entry("Shape size", "1", Patterns::Double(0.),
                        "HZG: scale of the letters (1: 0.8 high, 2.0 wide); sphere: its radius.");
      prm.declare_entry("Solid concentration", "2", Patterns::Double(0.), "C0 of the solid.");
      prm.declare_entry("Near-field radius", "2", Patterns::Double(0.),
                        "Radius of the truncated domain, absorbing layer included.");
      prm.declare_entry("Reference radius", "10", Patterns::Double(0.),
                        "Extended Neumann domain (0: no reference run).");
      prm.declare_entry("Truncation", "ball", Patterns::Selection("ball|cube"),
                        "Shape of the near field (and of the reference): the ball of the "
                        "near-field radius or the cube (-R, R)^dim.");
      prm.declare_entry("Neumann run", "true", Patterns::Bool(),
                        "Also run the near field with Neumann truncation.");
      prm.declare_entry("Required gain over Neumann", "10", Patterns::Double(0.),
                        "Check: Delta Pi/Pi0 at t_f of the Neumann run over that of the ABC run.");
      prm.declare_entry("Grid spacing", "0.02", Patterns::Double(0.));
      prm.declare_entry("Horizon", "0.04", Patterns::Double(0.));
      prm.declare_entry("Time step", "1e-5", Patterns::Double(0.));
      prm.declare_entry("End time", "0.085", Patterns::Double(0.));
      prm.declare_entry("Record interval", "0.001", Patterns::Double(0.));
      prm.declare_entry("Output directory", "step-6-output", Patterns::Anything());
      prm.leave_subsection();
      prm.enter_subsection("Model");
      prm.declare_entry("Kernel exponent", "2", Patterns::Double(0.),
                        "q of J_q = kappa / |xi|^q (the sources do not state it; see doc.md).");
      prm.declare_entry("Liquid micro-diffusivity", "7957.70", Patterns::Double(0.));
      prm.declare_entry("Interface micro-diffusivity", "795.77", Patterns::Double(0.));
      prm.declare_entry("Solid micro-diffusivity", "0", Patterns::Double(0.));
      prm.declare_entry("Saturation concentration", "0.8", Patterns::Double(0.));
      prm.leave_subsection();
      prm.enter_subsection("Absorbing boundary");
      Abc::EbfParameters::declare_parameters(prm);
      prm.leave_subsection();
      prm.parse_input(file);

      prm.enter_subsection("Problem");
      dim                 = prm.get_integer("Dimension");
      shape               = prm.get("Solid shape");
      shape_size          = prm.get_double("Shape size");
      solid_concentration = prm.get_double("Solid concentration");
      R                   = prm.get_double("Near-field radius");
      R_ref               = prm.get_double("Reference radius");
      neumann_run         = prm.get_bool("Neumann run");
      cube                = prm.get("Truncation") == "cube";
      required_gain       = prm.get_double("Required gain over Neumann");
      dx                  = prm.get_double("Grid spacing");
      delta               = prm.get_double("Horizon");
      dt                  = prm.get_double("Time step");
      t_end               = prm.get_double("End time");
      record_interval     = prm.get_double("Record interval");
      output_directory    = prm.get("Output directory");
      prm.leave_subsection();
      prm.enter_subsection("Model");
      model.type            = "corrosion";
      model.exponent        = prm.get_double("Kernel exponent");
      model.kappa_liquid    = prm.get_double("Liquid micro-diffusivity");
      model.kappa_interface = prm.get_double("Interface micro-diffusivity");
      model.kappa_solid     = prm.get_double("Solid micro-diffusivity");
      model.saturation      = prm.get_double("Saturation concentration");
      prm.leave_subsection();
      prm.enter_subsection("Absorbing boundary");
      abc.parse_parameters(prm);
      prm.leave_subsection();
      check_parameter(R_ref == 0. || R_ref > R, "Problem/Reference radius", R_ref,
                      "0 or > Near-field radius");
      check_parameter(shape == "sphere" || dim == 2, "Problem/Solid shape", shape,
                      "sphere in 3D (HZG is a 2D polygon set)");
      check_parameter(solid_concentration >= model.saturation, "Problem/Solid concentration",
                      solid_concentration, ">= Saturation concentration (else nothing is solid)");
      check_parameter(dt > 0. && t_end >= dt && record_interval >= dt, "Problem/Time step", dt,
                      "0 < dt <= Record interval, End time");
    }
  };

  /** The letters H, Z, G: 0.8 high, 0.6 wide, stroke 0.16, centred, scaled. */
  std::vector<std::unique_ptr<Boundary::PolygonDomain>>
  hzg_letters(const double scale)
  {
    const double h = 0.4, w = 0.6, s = 0.16, a = 1.2 * s; // half height, width, stroke, Z slant offset
    std::vector<std::vector<Point<2>>> letters;
    double x = -1.;
    letters.push_back({{x, -h}, {x + s, -h}, {x + s, -s / 2}, {x + w - s, -s / 2}, {x + w - s, -h},
                       {x + w, -h}, {x + w, h}, {x + w - s, h}, {x + w - s, s / 2}, {x + s, s / 2},
                       {x + s, h}, {x, h}});
    x = -0.3;
    letters.push_back({{x, h}, {x + w, h}, {x + w, h - s}, {x + a, -h + s}, {x + w, -h + s},
                       {x + w, -h}, {x, -h}, {x, -h + s}, {x + w - a, h - s}, {x, h - s}});
    x = 0.4;
    letters.push_back({{x + w, h}, {x, h}, {x, -h}, {x + w, -h}, {x + w, s / 2}, {x + w / 2, s / 2},
                       {x + w / 2, -s / 2}, {x + w - s, -s / 2}, {x + w - s, -h + s}, {x + s, -h + s},
                       {x + s, h - s}, {x + w, h - s}});
    std::vector<std::unique_ptr<Boundary::PolygonDomain>> polygons;
    for (auto &letter : letters)
      {
        for (auto &p : letter)
          p *= scale;
        polygons.push_back(std::make_unique<Boundary::PolygonDomain>(letter));
      }
    return polygons;
  }

  /** C0 in the solid, 0 in the electrolyte. */
  template <int dim>
  class InitialConcentration : public Function<dim>
  {
  public:
    InitialConcentration(const Parameters &p)
      : p(p)
    {
      if (p.shape == "HZG")
        letters = hzg_letters(p.shape_size);
    }
    double
    value(const Point<dim> &x_in, const unsigned int = 0) const override
    {
      // Letter edges run through lattice nodes, and the lattices of the
      // near field and the reference place a node differently by round-off:
      // snap to 1e-9 so that both runs start from the same solid.
      Point<dim> x;
      for (unsigned int d = 0; d < dim; ++d)
        x[d] = 1e-9 * std::round(x_in[d] * 1e9);
      bool solid = false;
      if (p.shape == "sphere")
        solid = x.norm() <= p.shape_size;
      else
        for (const auto &l : letters)
          solid = solid || l->inside(Point<2>(x[0], x[1]));
      return solid ? p.solid_concentration : 0.;
    }

  private:
    const Parameters                                      &p;
    std::vector<std::unique_ptr<Boundary::PolygonDomain>> letters;
  };

  struct Series
  {
    std::string         name;
    std::vector<double> energy, solid, mass;
    bool                monotone = true;
    double              seconds = 0., abc_fraction = 0.;
    types::global_dof_index nodes = 0, absorbing = 0;
  };

  template <int dim>
  Series
  march(const Parameters &p, const std::string &name, const double radius,
        const Abc::TruncationBoundary boundary)
  {
    LatticeParameters lp;
    lp.dx    = p.dx;
    lp.delta = p.delta;
    Point<dim> corner;
    for (unsigned int d = 0; d < dim; ++d)
      corner[d] = radius;
    BallDomain<dim>                ball(Point<dim>(), radius);
    BoxDomain<dim>                 box(-corner, corner);
    InitialConcentration<dim>      c0(p);
    Abc::PdUnboundedDiffusion<dim> run(MPI_COMM_WORLD);
    Timer                          timer;
    run.setup(p.cube ? static_cast<const Domain<dim> &>(box) : ball, lp, p.model, p.dt, boundary, p.abc, c0);
    Series s;
    s.name      = name;
    s.nodes     = run.discretization().n_global();
    s.absorbing = run.absorbing_boundary().statistics().n_absorbing;
    if (boundary == Abc::TruncationBoundary::absorbing && Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      {
        const auto &st = run.absorbing_boundary().statistics();
        std::cout << name << ": " << s.nodes << " nodes (" << s.absorbing << " absorbing), clouds "
                  << st.min_cloud_size << ".." << st.max_cloud_size << " points, Delta k "
                  << st.wave_number_range << " (bound (4.33) " << st.wave_number_bound << "), condition "
                  << st.max_condition_number << ", max |V| " << st.max_update_norm << ", max sum |V| "
                  << st.max_update_l1 << ", one-step growth " << run.stability_growth << ", setup "
                  << timer.wall_time() << " s" << std::endl;
      }
    // Pi and the mass on Omega_N of the truncated run (radius R - delta_L).
    const double layer = p.abc.layer_thickness > 0 ? p.abc.layer_thickness : p.delta;
    const typename Abc::PdUnboundedDiffusion<dim>::Region omega_n = [&](const Point<dim> &x) {
      double r = 0.; // max norm (cube) or Euclidean norm (ball)
      for (unsigned int d = 0; d < dim; ++d)
        r = std::max(r, std::abs(x[d]));
      return p.R - (p.cube ? r : x.norm()) >= layer - 1e-8 * p.dx;
    };
    const auto record = [&]() {
      s.energy.push_back(run.energy(omega_n));
      s.mass.push_back(run.mass(omega_n));
      s.solid.push_back(run.solid_volume());
    };
    record();
    const auto n_steps = static_cast<unsigned int>(std::round(p.t_end / p.dt));
    const auto every   = std::max(1u, static_cast<unsigned int>(std::round(p.record_interval / p.dt)));
    for (unsigned int n = 1; n <= n_steps; ++n)
      {
        run.advance();
        if (n % every == 0 || n == n_steps)
          {
            record();
            s.monotone = s.monotone && s.energy.back() <= s.energy[s.energy.size() - 2] * (1. + 1e-13);
          }
      }
    s.seconds      = timer.wall_time();
    s.abc_fraction = run.abc_seconds / run.step_seconds;
    return s;
  }

  template <int dim>
  int
  run(const Parameters &p)
  {
    std::filesystem::create_directories(p.output_directory);
    const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
    std::vector<Series> runs;
    runs.push_back(march<dim>(p, "ABC", p.R, Abc::TruncationBoundary::absorbing));
    if (p.neumann_run)
      runs.push_back(march<dim>(p, "Neumann", p.R, Abc::TruncationBoundary::neumann));
    if (p.R_ref > 0.)
      runs.push_back(march<dim>(p, "reference", p.R_ref, Abc::TruncationBoundary::neumann));
    const Series *ref = p.R_ref > 0. ? &runs.back() : nullptr;
    const auto    difference = [ref](const Series &s, const unsigned int r) {
      return std::abs(s.energy[r] - ref->energy[r]) / ref->energy[0];
    };

    int failures = 0;
    if (root)
      {
        std::ofstream csv(p.output_directory + "/history.csv");
        csv << "t";
        for (const auto &s : runs)
          csv << ",Pi/Pi0 " << s.name << ",V_s/V_s0 " << s.name << ",mass " << s.name;
        if (ref)
          for (unsigned int i = 0; i + 1 < runs.size(); ++i)
            csv << ",dPi/Pi0 " << runs[i].name;
        csv << "\n";
        const unsigned int n_records = runs[0].energy.size();
        for (unsigned int r = 0; r < n_records; ++r)
          {
            csv << std::min(r * p.record_interval, p.t_end);
            for (const auto &s : runs)
              csv << "," << s.energy[r] / s.energy[0] << "," << s.solid[r] / s.solid[0] << "," << s.mass[r];
            if (ref)
              for (unsigned int i = 0; i + 1 < runs.size(); ++i)
                csv << "," << difference(runs[i], r);
            csv << "\n";
          }
        csv.close();

        std::cout << std::setprecision(4) << "\n"
                  << std::left << std::setw(11) << "run" << std::setw(10) << "nodes" << std::setw(13)
                  << "Pi(tf)/Pi0" << std::setw(13) << "V_s(tf)/V0" << std::setw(13) << "max dPi/Pi0"
                  << std::setw(13) << "dPi/Pi0(tf)" << std::setw(10) << "monotone" << std::setw(10)
                  << "wall s" << "ABC share" << std::endl;
        for (const auto &s : runs)
          {
            double m = 0.;
            for (unsigned int r = 0; ref && r < n_records; ++r)
              m = std::max(m, difference(s, r));
            std::cout << std::setw(11) << s.name << std::setw(10) << s.nodes << std::setw(13)
                      << s.energy.back() / s.energy[0] << std::setw(13) << s.solid.back() / s.solid[0]
                      << std::setw(13) << (ref ? m : NAN) << std::setw(13)
                      << (ref ? difference(s, n_records - 1) : NAN) << std::setw(10)
                      << (s.monotone ? "yes" : "NO") << std::setw(10) << s.seconds << s.abc_fraction
                      << std::endl;
          }
        // Times at which the solid is gone and the near field is empty.
        for (const auto &s : runs)
          for (unsigned int r = 0; r < n_records; ++r)
            if (s.solid[r] == 0.)
              {
                std::cout << s.name << ": solid dissolved at t = " << r * p.record_interval << std::endl;
                break;
              }

        std::ostringstream gp;
        gp << gnuplot_png_preamble(p.output_directory + "/history.png")
           << "set datafile separator ','\nset key outside right\nset logscale y\nset yrange [1e-6:2]\n"
           << "set xlabel 't'\nset ylabel 'Pi/Pi0, V_s/V_s0, |Pi - Pi_ref|/Pi_ref(0)'\nplot ";
        for (unsigned int i = 0; i < runs.size(); ++i)
          gp << (i ? ", " : "") << "'" << p.output_directory << "/history.csv' using 1:" << 2 + 3 * i
             << " with lines lw 2 title 'Pi/Pi0 " << runs[i].name << "', '' using 1:" << 3 + 3 * i
             << " with lines dt 2 title 'V_s/V_s0 " << runs[i].name << "'";
        if (ref)
          for (unsigned int i = 0; i + 1 < runs.size(); ++i)
            gp << ", '' using 1:" << 2 + 3 * runs.size() + i << " with lines lw 2 dt 3 title 'dPi/Pi0 "
               << runs[i].name << "'";
        gp << "\n";
        run_gnuplot(p.output_directory + "/history.gp", gp.str(), p.output_directory + "/history.png");

        // Checks: what the source reports (Figs. 4.15, 4.16), measured.
        const auto check = [&failures](const bool ok, const std::string &what) {
          std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
          failures += !ok;
        };
        std::cout << "\nChecks" << std::endl;
        check(std::isfinite(runs[0].energy.back()), "ABC run stays finite");
        check(runs[0].monotone, "ABC: near-field energy non-increasing at every record (Fig. 4.16)");
        if (ref && p.neumann_run)
          check(difference(runs[1], n_records - 1) > p.required_gain * difference(runs[0], n_records - 1),
                "ABC >= " + std::to_string(p.required_gain) +
                  "x closer to the reference than Neumann at t_f (Fig. 4.15)");
      }
    return Utilities::MPI::max(failures, MPI_COMM_WORLD) == 0 ? 0 : 1;
  }
} // namespace Step6

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  try
    {
      Step6::Parameters p;
      p.read(argc > 1 ? argv[1] : "step-6.prm");
      return p.dim == 2 ? Step6::run<2>(p) : Step6::run<3>(p);
    }
  catch (const std::exception &e)
    {
      std::cerr << "Error: " << e.what() << std::endl;
      return 1;
    }
}
