// step-8: 2D bond-based PD elastic waves on unbounded domains with EBF
// absorbing boundary conditions (dissertation Sect. 4.3.5) and dynamic
// brittle fracture in a half-space (Sect. 4.3.6).
//
// The idea of this step: the near field is truncated; the nodes within
// delta of the truncation boundary get their displacement and velocity at
// t^{n+1} from their clouds at t^n and t^{n-1} through updating blocks
// fitted to outgoing P and S modes gamma exp(i k n.x - i w(k) t) whose
// frequencies and polarizations are the eigenpairs of the discrete
// "generalized mass" matrix of the near field's own bond stencil
// ((4.144)-(4.151)). Each run is compared with the same code on an extended
// domain that nothing reflected from returns from (the reference) and with
// the free (traction-free) and fixed truncations.
//
// "Absorbing boundary/Method" selects the truncation of Part 1: ebf (the
// above), first order (the conventional Lysmer-type one-way condition on the
// same layer, the baseline of doc/design.md session 18), sponge (a damping
// band, energy-stable but less accurate) or pml
// (a perfectly matched layer of width "PML thickness" beginning where the
// EBF layer begins, at R - delta: each bond's elongation is complex-stretched
// along the outward normal with exponential memories; stable without
// damping, doc/design.md session 9). Part 2 has a physical free surface on
// top, which the PML cannot leave out, so it uses the EBF layer with pml.
//
// Part 1 (E16, reduced): linearized bond-based, plane stress, omega_0,
// E = rho = 1, dx = 1, delta = 3 dx, radial pulse u0 = (x/w) exp(-r^2/w^2)
// in a disc. Part 2 (E17, reduced): PMB with bond breaking in a half-space
// box whose top is a free surface; two vertical notches; a rigid impactor
// between them pushes down with constant velocity; absorbing on the
// sides and the bottom only.

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <perideal/abc/ebf_elastic_abc.h>
#include <perideal/base/exceptions.h>
#include <perideal/io/plot.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEAL::Abc;

namespace Step8
{
  struct Parameters
  {
    // Part 1.
    double       radius = 16., end_time = 48., pulse_width = 2.5;
    unsigned int n_samples = 24;
    // Both parts.
    double dx = 1., dt = 0.5, damping = 0.02;
    unsigned int horizon_factor = 3;
    // Part 2.
    double half_width = 30., depth = 30., fracture_end_time = 80., notch_offset = 6.,
           notch_length = 8., impact_half_width = 2., impact_velocity = 0.02, critical_stretch = 0.01;
    bool        run_fracture = true;
    std::string output_directory = "step-8-output";
    WaveAbcParameters abc;
  };

  Parameters
  read(const std::string &file)
  {
    Parameters       p;
    ParameterHandler prm;
    prm.enter_subsection("Problem");
    prm.declare_entry("Near-field radius", "16", Patterns::Double(0.));
    prm.declare_entry("End time", "48", Patterns::Double(0.));
    prm.declare_entry("Pulse width", "2.5", Patterns::Double(0.));
    prm.declare_entry("Number of samples", "24", Patterns::Integer(1, 10000));
    prm.declare_entry("Grid spacing", "1", Patterns::Double(0.));
    prm.declare_entry("Time step", "0.5", Patterns::Double(0.));
    prm.declare_entry("Damping", "0.02", Patterns::Double(0.));
    prm.declare_entry("Horizon factor", "3", Patterns::Integer(1, 50));
    prm.declare_entry("Output directory", "step-8-output", Patterns::Anything());
    prm.leave_subsection();
    prm.enter_subsection("Fracture");
    prm.declare_entry("Run", "true", Patterns::Bool());
    prm.declare_entry("Half width", "30", Patterns::Double(0.));
    prm.declare_entry("Depth", "30", Patterns::Double(0.));
    prm.declare_entry("End time", "80", Patterns::Double(0.));
    prm.declare_entry("Notch offset", "6", Patterns::Double(0.));
    prm.declare_entry("Notch length", "8", Patterns::Double(0.));
    prm.declare_entry("Impact half width", "2", Patterns::Double(0.));
    prm.declare_entry("Impact velocity", "0.02", Patterns::Double(0.));
    prm.declare_entry("Critical stretch", "0.01", Patterns::Double(0.));
    prm.leave_subsection();
    prm.enter_subsection("Absorbing boundary");
    WaveAbcParameters::declare_parameters(prm);
    prm.leave_subsection();
    prm.parse_input(file);
    prm.enter_subsection("Problem");
    p.radius           = prm.get_double("Near-field radius");
    p.end_time         = prm.get_double("End time");
    p.pulse_width      = prm.get_double("Pulse width");
    p.n_samples        = prm.get_integer("Number of samples");
    p.dx               = prm.get_double("Grid spacing");
    p.dt               = prm.get_double("Time step");
    p.damping          = prm.get_double("Damping");
    p.horizon_factor   = prm.get_integer("Horizon factor");
    p.output_directory = prm.get("Output directory");
    prm.leave_subsection();
    prm.enter_subsection("Fracture");
    p.run_fracture      = prm.get_bool("Run");
    p.half_width        = prm.get_double("Half width");
    p.depth             = prm.get_double("Depth");
    p.fracture_end_time = prm.get_double("End time");
    p.notch_offset      = prm.get_double("Notch offset");
    p.notch_length      = prm.get_double("Notch length");
    p.impact_half_width = prm.get_double("Impact half width");
    p.impact_velocity   = prm.get_double("Impact velocity");
    p.critical_stretch  = prm.get_double("Critical stretch");
    prm.leave_subsection();
    prm.enter_subsection("Absorbing boundary");
    p.abc.parse_parameters(prm);
    prm.leave_subsection();
    return p;
  }

  /** Record an ok/FAIL line and count failures. */
  struct Checker
  {
    bool root;
    int  failures = 0;
    void
    operator()(const bool ok, const std::string &what)
    {
      if (root)
        std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
      failures += ok ? 0 : 1;
    }
  };

  std::string
  sci(const double x)
  {
    std::ostringstream s;
    s.precision(3);
    s << std::scientific << x;
    return s.str();
  }

  std::string
  statistics(const ElasticRunHistory &h)
  {
    std::ostringstream o;
    o << h.n_nodes << " nodes, " << h.n_layer_nodes << " absorbing, " << h.stats.n_modes
      << " P+S modes, clouds " << h.stats.min_cloud_size << ".." << h.stats.max_cloud_size
      << " (stride " << h.stats.max_stride << "), max cond " << h.stats.max_condition_number
      << ", max |V| " << h.stats.max_update_norm << ", ABC time fraction "
      << h.abc_seconds / std::max(h.step_seconds, 1e-300);
    return o.str();
  }

  void
  write_energies(const std::string &file, const std::vector<std::string> &names,
                 const std::vector<const ElasticRunHistory *> &runs, const bool by_final)
  {
    std::ofstream out(file);
    // Normalized by the reference energy at t = 0 (pulse) or at t_end (impact).
    const double e0 = runs[0]->energy(by_final ? runs[0]->times.size() - 1 : 0);
    out << "t";
    for (const auto &n : names)
      out << ',' << n << " kinetic," << n << " strain," << n << " total";
    out << '\n';
    for (unsigned int s = 0; s < runs[0]->times.size(); ++s)
      {
        out << runs[0]->times[s];
        for (const auto *h : runs)
          out << ',' << h->kinetic[s] / e0 << ',' << h->strain[s] / e0 << ',' << h->energy(s) / e0;
        out << '\n';
      }
  }

  void
  plot(const std::string &dir, const std::string &name, const std::string &title, const unsigned int n_runs,
       const bool log_scale)
  {
    std::ostringstream gp;
    gp << gnuplot_png_preamble(dir + "/" + name + ".png")
       << "set datafile separator ','\nset key autotitle columnhead top right\n"
       << (log_scale ? "set logscale y\nset yrange [1e-4:2]\nset ylabel 'Pi/Pi_ref(0) (compared region)'\n" :
                       "set ylabel 'Pi/Pi_ref(t_end) (compared region)'\n")
       << "set xlabel 't'\nset title '" << title << "'\n"
       << "plot for [i=0:" << n_runs - 1 << "] '" << dir << "/" << name
       << ".csv' using 1:(column(4+3*i)) with linespoints lw 2 title columnhead(4+3*i), "
       << "for [i=0:" << n_runs - 1 << "] '' using 1:(column(2+3*i)) with lines dt 2 title columnhead(2+3*i)\n";
    run_gnuplot(dir + "/" + name + ".gp", gp.str(), dir + "/" + name + ".png");
  }

  // Part 1: the radial pulse in a disc (E16).
  void
  unbounded(const Parameters &p, Checker &check)
  {
    LatticeParameters lp;
    lp.dx    = p.dx;
    lp.delta = p.horizon_factor * p.dx;
    BondBasedModelParameters model;
    model.linearized = true;
    ElasticWaveParameters wp;
    wp.time_step = p.dt;
    wp.damping   = p.damping;
    const double                   w = p.pulse_width, R = p.radius, delta = lp.delta;
    FunctionFromFunctionObjects<2> u0(
      {[w](const Point<2> &x) { return x[0] / w * std::exp(-x.square() / (w * w)); },
       [w](const Point<2> &x) { return x[1] / w * std::exp(-x.square() / (w * w)); }});
    const auto inside = [R, delta](const Point<2> &x) { return x.norm() < R - delta - 1e-9; };
    // P speed of the local relation (the discrete one is slower), 2% margin.
    const double cp = 1.02 * std::sqrt(9. / 8.);
    // Rounded to whole dx so that both lattices coincide.
    const double r_ref = std::ceil(reference_radius(cp, p.end_time, 3. * w, R, 2. * delta) / p.dx) * p.dx;
    const auto   run   = [&](const double radius, const ElasticTruncation tr) {
      PdUnboundedElastic pd(MPI_COMM_WORLD);
      pd.setup(BallDomain<2>(Point<2>(), radius), lp, model, wp, tr, p.abc, u0);
      return run_elastic_waves(pd, p.end_time, p.n_samples, inside);
    };
    // The PML occupies [R - delta, R - delta + w]: w - delta of extra nodes.
    const bool   pml   = p.abc.method == "pml";
    const double r_abc = pml ? R - delta + p.abc.pml_thickness : R;
    const auto ref = run(r_ref, ElasticTruncation::free), abc = run(r_abc, ElasticTruncation::absorbing),
               fr = run(R, ElasticTruncation::free), fx = run(R, ElasticTruncation::fixed);
    if (check.root)
      {
        std::cout << "Part 1 (radial pulse): reference " << ref.n_nodes << " nodes (radius " << r_ref
                  << ")\n  ABC (method " << p.abc.method << ", radius " << r_abc << "): "
                  << (pml ? std::to_string(abc.n_nodes) + " nodes, " + std::to_string(abc.n_layer_nodes) + " in the PML" :
                            statistics(abc))
                  << std::endl;
        write_energies(p.output_directory + "/energy_pulse.csv", {"reference", "ABC", "free", "fixed"},
                       {&ref, &abc, &fr, &fx}, false);
        plot(p.output_directory, "energy_pulse", "radial pulse: total (solid) and kinetic (dashed)", 4, true);
      }
    const unsigned int last = p.n_samples;
    const auto err = [&](const ElasticRunHistory &h) { return std::abs(h.energy(last) - ref.energy(last)) / ref.energy(0); };
    if (check.root)
      std::cout << "  |Pi - Pi_ref|/Pi_ref(0) at t = " << p.end_time << ": ABC " << sci(err(abc)) << ", free "
                << sci(err(fr)) << ", fixed " << sci(err(fx)) << std::endl;
    check(10. * err(abc) < err(fr) && 10. * err(abc) < err(fx), "ABC at least 10x closer to the reference than the free and fixed truncations");
    // The energy Verlet conserves (PdUnboundedElastic::verlet_energy): the
    // plain kinetic + strain energy at whole steps oscillates by O(dt^2)
    // even without truncation, visible when d = 0.
    double growth = -1.;
    for (unsigned int s = 1; s <= last; ++s)
      growth = std::max(growth, (abc.verlet[s] - abc.verlet[s - 1]) / abc.verlet[0]);
    // A PML is not dissipative: while a front enters it the Verlet energy
    // can rise a little (measured 3.8e-5 E0 at d = 0, doc/design.md session 9).
    if (pml)
      check(growth < 1e-4, "PML: Verlet energy of the near field rises by less than 1e-4 E0 (max increase " + sci(growth) + ")");
    else
      check(growth <= 0., "ABC: Verlet energy of the near field non-increasing (max increase " + sci(growth) + ")");
  }

  // Part 2: notched half-space under impact (E17).
  void
  fracture(const Parameters &p, Checker &check)
  {
    LatticeParameters lp;
    lp.dx    = p.dx;
    lp.delta = p.horizon_factor * p.dx;
    BondBasedModelParameters model;
    model.linearized       = false;
    model.critical_stretch = p.critical_stretch;
    ElasticWaveParameters wp;
    wp.time_step = p.dt;
    wp.damping   = p.damping;
    const double delta = lp.delta, W = p.half_width, D = p.depth;
    const Functions::ZeroFunction<2> u0(2);
    const double cp = 1.02 * std::sqrt(9. / 8.);
    // Reference box: nothing reflected at its sides or bottom is back in
    // the compared box before the end time.
    const double W_ref =
      std::ceil(reference_radius(cp, p.fracture_end_time, 0., std::max(W, D), 2. * delta) / p.dx) * p.dx;
    const auto inside = [W, D, delta](const Point<2> &x) {
      return std::abs(x[0]) < W - delta - 1e-9 && x[1] > -D + delta + 1e-9;
    };
    struct Result
    {
      ElasticRunHistory history;
      std::vector<double> tip_depth; // deepest damaged node (damage >= 0.3) below each notch
      double              damaged = 0.;
    };
    WaveAbcParameters abc_prm = p.abc;
    if (abc_prm.method == "pml")
      {
        abc_prm.method = "ebf";
        if (check.root)
          std::cout << "Part 2: the EBF layer (the PML cannot exempt the free top surface)" << std::endl;
      }
    const auto run = [&](const double half_width, const double depth, const ElasticTruncation tr) {
      PdUnboundedElastic pd(MPI_COMM_WORLD);
      BoxDomain<2> box(Point<2>(-half_width, -depth), Point<2>(half_width, 0.));
      // The top is a physical free surface: absorb on the sides and the bottom only.
      pd.setup(box, lp, model, wp, tr, abc_prm, u0,
               [](const Point<2> &, const Tensor<1, 2> &n) { return n[1] < 0.5; });
      for (const double s : {-1., 1.})
        pd.add_precrack(Point<2>(s * p.notch_offset, 0.5 * lp.dx), Point<2>(s * p.notch_offset, -p.notch_length));
      const double a = p.impact_half_width, v0 = p.impact_velocity, h = lp.dx;
      pd.set_prescribed_velocity(
        [a, h](const Point<2> &x) { return std::abs(x[0]) <= a + 1e-9 && x[1] > -h - 1e-9; },
        [v0](const Point<2> &, double) { return Tensor<1, 2>({0., -v0}); });
      Result r;
      r.history = run_elastic_waves(pd, p.fracture_end_time, p.n_samples, inside);
      r.tip_depth.assign(2, 0.);
      for (const auto &s : r.history.final_state)
        if (s.damage >= 0.3)
          {
            r.damaged += 1.;
            const unsigned int side = s.position[0] < 0. ? 0 : 1;
            if (std::abs(std::abs(s.position[0]) - p.notch_offset) < 0.5 * (p.notch_offset + 1.))
              r.tip_depth[side] = std::max(r.tip_depth[side], -s.position[1]);
          }
      if (check.root)
        {
          std::ofstream out(p.output_directory + "/damage_" +
                            (tr == ElasticTruncation::absorbing ? std::string("abc") :
                             half_width > W ? std::string("reference") : std::string("free")) + ".csv");
          out << "x,y,damage,ux,uy\n";
          for (const auto &s : r.history.final_state)
            out << s.position[0] << ',' << s.position[1] << ',' << s.damage << ',' << s.displacement[0] << ','
                << s.displacement[1] << '\n';
        }
      return r;
    };
    const auto ref = run(W_ref, W_ref, ElasticTruncation::free), abc = run(W, D, ElasticTruncation::absorbing),
               fr = run(W, D, ElasticTruncation::free);
    const unsigned int last = p.n_samples;
    const auto err = [&](const Result &r) {
      return std::abs(r.history.energy(last) - ref.history.energy(last)) / ref.history.energy(last);
    };
    if (check.root)
      {
        std::cout << "Part 2 (notched half-space): reference " << ref.history.n_nodes << " nodes\n  ABC: "
                  << statistics(abc.history) << std::endl;
        for (const auto *r : {&ref, &abc, &fr})
          std::cout << "  " << (r == &ref ? "reference" : r == &abc ? "ABC      " : "free     ") << ": "
                    << r->damaged << " nodes with damage >= 0.3, crack depth below the notches "
                    << r->tip_depth[0] << " / " << r->tip_depth[1] << ", |Pi - Pi_ref|/Pi_ref at t_end "
                    << sci(err(*r)) << std::endl;
        write_energies(p.output_directory + "/energy_fracture.csv", {"reference", "ABC", "free"},
                       {&ref.history, &abc.history, &fr.history}, true);
        plot(p.output_directory, "energy_fracture", "notched half-space: total (solid) and kinetic (dashed)", 3, false);
      }
    check(err(abc) < err(fr), "half-space: the ABC energy is closer to the reference than the free truncation's");
    const double tip_abc = std::abs(abc.tip_depth[0] - ref.tip_depth[0]) + std::abs(abc.tip_depth[1] - ref.tip_depth[1]);
    const double tip_free = std::abs(fr.tip_depth[0] - ref.tip_depth[0]) + std::abs(fr.tip_depth[1] - ref.tip_depth[1]);
    check(tip_abc <= tip_free, "half-space: crack depths of the ABC run at least as close to the reference as the free run's (" +
                                 std::to_string(tip_abc) + " vs " + std::to_string(tip_free) + ")");
  }

  int
  run(const std::string &file)
  {
    const Parameters p = read(file);
    Checker          check{Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0};
    if (check.root)
      std::filesystem::create_directories(p.output_directory);
    unbounded(p, check);
    if (p.run_fracture)
      fracture(p, check);
    return check.failures == 0 ? 0 : 1;
  }
} // namespace Step8

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  try
    {
      return Step8::run(argc > 1 ? argv[1] : "step-8.prm");
    }
  catch (const std::exception &e)
    {
      std::cerr << "Error: " << e.what() << std::endl;
      return 1;
    }
}
