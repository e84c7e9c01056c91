// step-7: PD scalar waves on unbounded domains with EBF absorbing boundary
// conditions (dissertation Sect. 4.2.4 and 4.2.6).
//
// The idea of this step: the near field is truncated to a disc (2D) or an
// interval (1D); the nodes within delta of the truncation boundary get their
// displacement and velocity at t^{n+1} extrapolated from their clouds at
// t^n and t^{n-1} with outgoing complex harmonic modes
// exp(-d t) exp(i k n.x - i w(k) t) (4.57), through precomputed updating
// vectors (4.82). The modes carry either the discrete PD dispersion relation
// of the near field's own stencil (Proposed-A, (4.85)) or the local one
// (Proposed-B, (4.39)). Each run is compared with the same code on an
// extended domain whose boundary nothing reaches (the reference), and with
// the free (untreated) truncation.
//
// 2D: u_tt = L u - 2 d u_t, p = 2, omega_0, chi = 1, d = 0.0125,
// Delta k = 1, delta = 6 dx, u0 = exp(-log 2 |x|^2). 1D (E12b): p = 0,
// delta = 0.6, dx = 0.2, (-10, 10) vs (-50, 50), u0 = exp(-x^2), dt = 1e-3,
// Delta alpha = pi/2, n_b = 1..5. 1D (E12c, highly dispersive): p = 0,
// chi^2 = 10, d = 5e-4, delta = 0.25 = 25 dx, dt = 1e-4, Delta alpha = 1,
// n_b = 20, u0 = exp(-20 log 2 x^2) on (-L, L) (the source: L = 10, t = 15).

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/abc/wave_abc_layers.h>
#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_wave.h>
#include <perideal/io/plot.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEAL::Abc;

namespace Step7
{
  struct Parameters
  {
    double       radius = 8., end_time = 16., dx = 0.25, dt = 0.02;
    unsigned int horizon_factor = 6, n_samples = 16;
    double       t_1d = 25., half_length_e12c = 10., t_e12c = 15.;
    /** FEM near field (E13): half width, mesh size, end time, curvature radius of the modes. */
    double       fem_half_width = 16., fem_h = 0.5, fem_end_time = 32., fem_curvature = 64.;
    /** The FEM solver's own entries (time step, damping, scheme, ...). */
    Fem::FemWaveParameters fem;
    std::string  output_directory = "step-7-output";
    WaveAbcParameters abc;
  };

  /** Energies (4.99) at the sample times of one run, and u at t_end on the lattice (i, j) = x/dx. */
  template <int dim>
  std::vector<double>
  energies(const Domain<dim> &domain, const LatticeParameters &lp, const ScalarWaveParameters &mp,
           const WaveTruncation trunc, const WaveAbcParameters &abc, const Function<dim> &u0,
           const double t_end, const unsigned int n_samples,
           const std::function<bool(const Point<dim> &)> &inside, std::string &stats,
           std::map<std::array<long, dim>, double> *final_field = nullptr)
  {
    PdUnboundedWave<dim> pd(MPI_COMM_WORLD);
    pd.setup(domain, lp, mp, trunc, abc, u0);
    const unsigned int  n_steps = static_cast<unsigned int>(std::round(t_end / mp.time_step));
    std::vector<double> e;
    for (unsigned int s = 0; s <= n_samples; ++s)
      {
        while (std::round(pd.time() / mp.time_step) < n_steps * s / n_samples)
          pd.advance();
        e.push_back(pd.energy(inside));
      }
    if (final_field)
      for (const auto &[x, u] : pd.gather(inside))
        {
          std::array<long, dim> key;
          for (unsigned int d = 0; d < dim; ++d)
            key[d] = std::lround(x[d] / lp.dx);
          (*final_field)[key] = u;
        }
    std::ostringstream o;
    if (trunc == WaveTruncation::absorbing)
      {
        const auto &st = pd.absorbing_boundary().statistics();
        o << st.n_absorbing << " absorbing nodes, " << st.n_modes << " modes, clouds " << st.min_cloud_size
          << ".." << st.max_cloud_size << " (stride " << st.max_stride << "), max cond "
          << st.max_condition_number << ", max |V| " << st.max_update_norm << ", ";
      }
    o << "ABC time fraction " << pd.abc_seconds / std::max(pd.step_seconds, 1e-300);
    stats = o.str();
    return e;
  }

  /** sum (u - u_ref)^2 over the nodes of @p u (all of them are in @p ref). */
  template <int dim>
  double
  squared_difference(const std::map<std::array<long, dim>, double> &u,
                     const std::map<std::array<long, dim>, double> &ref)
  {
    double s = 0.;
    for (const auto &[key, value] : u)
      s += (value - ref.at(key)) * (value - ref.at(key));
    return s;
  }

  int
  run(const std::string &file)
  {
    Parameters p;
    {
      ParameterHandler prm;
      prm.enter_subsection("Problem");
      prm.declare_entry("Near-field radius", "8", Patterns::Double(0.));
      prm.declare_entry("End time", "16", Patterns::Double(0.));
      prm.declare_entry("Grid spacing", "0.25", Patterns::Double(0.));
      prm.declare_entry("Time step", "0.02", Patterns::Double(0.));
      prm.declare_entry("Horizon factor", "6", Patterns::Integer(1, 50));
      prm.declare_entry("Number of samples", "16", Patterns::Integer(1, 10000));
      prm.declare_entry("End time 1D", "25", Patterns::Double(0.));
      prm.declare_entry("Half length E12c", "10", Patterns::Double(0.5));
      prm.declare_entry("End time E12c", "15", Patterns::Double(0.));
      prm.declare_entry("Output directory", "step-7-output", Patterns::Anything());
      prm.leave_subsection();
      prm.enter_subsection("FEM");
      prm.declare_entry("Half width", "16", Patterns::Double(0.));
      prm.declare_entry("Mesh size", "0.5", Patterns::Double(0.));
      prm.declare_entry("End time", "32", Patterns::Double(0.));
      prm.declare_entry("Curvature radius", "64", Patterns::Double(0.));
      Fem::FemWaveParameters::declare_parameters(prm);
      prm.leave_subsection();
      prm.enter_subsection("Absorbing boundary");
      WaveAbcParameters::declare_parameters(prm);
      prm.leave_subsection();
      prm.parse_input(file);
      prm.enter_subsection("FEM");
      p.fem_half_width = prm.get_double("Half width");
      p.fem_h          = prm.get_double("Mesh size");
      p.fem_end_time   = prm.get_double("End time");
      p.fem_curvature  = prm.get_double("Curvature radius");
      p.fem.parse_parameters(prm);
      prm.leave_subsection();
      prm.enter_subsection("Problem");
      p.radius           = prm.get_double("Near-field radius");
      p.end_time         = prm.get_double("End time");
      p.dx               = prm.get_double("Grid spacing");
      p.dt               = prm.get_double("Time step");
      p.horizon_factor   = prm.get_integer("Horizon factor");
      p.n_samples        = prm.get_integer("Number of samples");
      p.t_1d             = prm.get_double("End time 1D");
      p.half_length_e12c = prm.get_double("Half length E12c");
      p.t_e12c           = prm.get_double("End time E12c");
      p.output_directory = prm.get("Output directory");
      prm.leave_subsection();
      prm.enter_subsection("Absorbing boundary");
      p.abc.parse_parameters(prm);
      prm.leave_subsection();
    }
    const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
    if (root)
      std::filesystem::create_directories(p.output_directory);
    // A csv file with its header line on the root rank (closed elsewhere).
    const auto csv = [&](const std::string &name, const std::string &header) {
      std::ofstream out;
      if (root)
        {
          out.open(p.output_directory + "/" + name);
          out << header << '\n';
        }
      return out;
    };
    int        failures = 0;
    const auto check    = [&](const bool ok, const std::string &what) {
      if (root)
        std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
      failures += ok ? 0 : 1;
    };

    // 2D: reference, free truncation, Proposed-A, Proposed-B.
    {
      LatticeParameters lp;
      lp.dx    = p.dx;
      lp.delta = p.horizon_factor * p.dx;
      ScalarWaveParameters mp;
      mp.damping   = 0.0125;
      mp.time_step = p.dt;
      const ScalarFunctionFromFunctionObject<2> u0(
        [](const Point<2> &x) { return std::exp(-std::log(2.) * x.square()); });
      const double R      = p.radius;
      const auto   inside = [&](const Point<2> &x) { return x.norm() < R - lp.delta - 1e-9; };
      // Nothing reflected at R_ref is back inside R - delta before t_end.
      BallDomain<2> near(Point<2>(), R), far(Point<2>(), 0.5 * (p.end_time + R + 2.) + 3. + lp.delta);
      std::string   s_ref, s_free, s_a, s_b, s_o, s_m;
      using Field = std::map<std::array<long, 2>, double>;
      Field      f_ref, f_free, f_a, f_b, f_o, f_m;
      const auto ref = energies<2>(far, lp, mp, WaveTruncation::free, p.abc, u0, p.end_time, p.n_samples, inside, s_ref, &f_ref);
      const auto fr  = energies<2>(near, lp, mp, WaveTruncation::free, p.abc, u0, p.end_time, p.n_samples, inside, s_free, &f_free);
      WaveAbcParameters abc = p.abc;
      abc.dispersion        = "discrete";
      const auto A          = energies<2>(near, lp, mp, WaveTruncation::absorbing, abc, u0, p.end_time, p.n_samples, inside, s_a, &f_a);
      abc.dispersion        = "local";
      const auto B          = energies<2>(near, lp, mp, WaveTruncation::absorbing, abc, u0, p.end_time, p.n_samples, inside, s_b, &f_b);
      // The conventional first-order ABC (4.75) on the same layer, and the
      // long-run monotone layer found in verification (Abc::WaveAbcLayers:
      // curved normal modes, 4 dx clouds, Tikhonov; see Results).
      const auto O = energies<2>(near, lp, mp, WaveTruncation::first_order, p.abc, u0, p.end_time, p.n_samples, inside, s_o, &f_o);
      const auto M = energies<2>(near, lp, mp, WaveTruncation::absorbing, WaveAbcLayers::curved_monotone(lp.dx, R), u0,
                                 p.end_time, p.n_samples, inside, s_m, &f_m);
      double norm0 = 0.;
      for (const auto &q : f_ref)
        norm0 += std::pow(u0.value(Point<2>(q.first[0] * lp.dx, q.first[1] * lp.dx)), 2);
      const auto field = [&](const Field &f) { return squared_difference<2>(f, f_ref) / norm0; };
      if (root)
        {
          std::cout << "2D Proposed-A: " << s_a << "\n2D Proposed-B: " << s_b << "\n2D monotone layer: " << s_m
                    << "\n2D field sum (u - u_ref)^2 / sum u0^2 at t_end: Proposed-A " << field(f_a) << ", Proposed-B "
                    << field(f_b) << ", monotone layer " << field(f_m) << ", first-order " << field(f_o) << ", free "
                    << field(f_free) << std::endl;
          std::ofstream out(p.output_directory + "/energy_2d.csv");
          out << "t,reference,free,Proposed-A,Proposed-B,|A-ref|,|B-ref|,|free-ref|,|first-order-ref|,|monotone-ref|\n";
          for (unsigned int s = 0; s < ref.size(); ++s)
            out << p.end_time * s / p.n_samples << ',' << ref[s] / ref[0] << ',' << fr[s] / ref[0] << ','
                << A[s] / ref[0] << ',' << B[s] / ref[0] << ',' << std::abs(A[s] - ref[s]) / ref[0] << ','
                << std::abs(B[s] - ref[s]) / ref[0] << ',' << std::abs(fr[s] - ref[s]) / ref[0] << ','
                << std::abs(O[s] - ref[s]) / ref[0] << ',' << std::abs(M[s] - ref[s]) / ref[0] << '\n';
        }
      const double ea = std::abs(A.back() - ref.back()) / ref[0], eb = std::abs(B.back() - ref.back()) / ref[0],
                   ef = std::abs(fr.back() - ref.back()) / ref[0];
      check(ea < eb, "2D: Proposed-A closer to the reference than Proposed-B at t_end (" + std::to_string(ea) + " vs " + std::to_string(eb) + ")");
      check(10. * ea < ef, "2D: Proposed-A 10x closer than the free truncation (" + std::to_string(ea) + " vs " + std::to_string(ef) + ")");
      // wave_abc.pd_2d asserts the 10x for this layer at R = 8; the
      // step only checks the ordering, which holds at the CI radius too.
      check(field(f_m) < field(f_o), "2D: the monotone layer closer to the reference than the first-order ABC in the field at t_end");
    }

    // 1D (E12b): n_b study with the discrete and the local relation.
    {
      LatticeParameters lp;
      lp.dx    = 0.2;
      lp.delta = 0.6;
      ScalarWaveParameters mp;
      mp.exponent  = 0.;
      mp.time_step = 1e-3;
      const ScalarFunctionFromFunctionObject<1> u0([](const Point<1> &x) { return std::exp(-x[0] * x[0]); });
      const auto   inside = [](const Point<1> &x) { return std::abs(x[0]) < 10. - 0.6 - 1e-9; };
      BoxDomain<1> near(Point<1>(-10.), Point<1>(10.)), far(Point<1>(-50.), Point<1>(50.));
      WaveAbcParameters abc = p.abc;
      abc.wave_number_range = M_PI / 2.;
      std::string s;
      const unsigned int n = 100;
      const auto ref  = energies<1>(far, lp, mp, WaveTruncation::free, abc, u0, p.t_1d, n, inside, s);
      std::ofstream out = csv("modes_1d.csv", "n_b,discrete,local");
      for (unsigned int nb = 1; nb <= 5; ++nb)
        {
          double err[2];
          for (unsigned int r = 0; r < 2; ++r)
            {
              abc.n_wave_numbers = nb;
              abc.dispersion     = r == 0 ? "discrete" : "local";
              const auto e       = energies<1>(near, lp, mp, WaveTruncation::absorbing, abc, u0, p.t_1d, n, inside, s);
              err[r]             = 0.;
              for (unsigned int k = 0; k < e.size(); ++k)
                err[r] = std::max(err[r], std::abs(e[k] - ref[k]) / ref[0]);
            }
          if (root)
            out << nb << ',' << err[0] << ',' << err[1] << '\n';
        }
    }

    // 1D (E12c): 21 modes on clouds of 25 nodes. Their moment matrices
    // have singular values down to 1e-14 sigma_max (the modes exp(i alpha x),
    // |alpha| <= 1, are nearly dependent over a cloud of length 0.25), so the
    // pseudo-inverse drops those below 1e-12 sigma_max (LAPACK's rcond, as
    // the source's LAPACK inverse): no thinning is needed, as in the source.
    {
      const double          chi = std::sqrt(10.), L = p.half_length_e12c, T = p.t_e12c;
      LatticeParameters     lp;
      lp.dx    = 0.01;
      lp.delta = 0.25;
      ScalarWaveParameters mp;
      mp.exponent   = 0.;
      mp.wave_speed = chi;
      mp.damping    = 5e-4;
      mp.time_step  = 1e-4;
      WaveAbcParameters abc = p.abc;
      abc.wave_number_range        = 1.;
      abc.n_wave_numbers           = 20;
      abc.dispersion               = "discrete";
      abc.pseudo_inverse_tolerance = 1e-12;
      const ScalarFunctionFromFunctionObject<1> u0(
        [](const Point<1> &x) { return std::exp(-20. * std::log(2.) * x[0] * x[0]); });
      // Nothing reflected at L_ref is back in (-L, L) before T; a multiple
      // of dx, so that the lattices share their nodes.
      const double L_ref = lp.dx * std::ceil((0.5 * (chi * T + L + 1.) + 1.) / lp.dx);
      std::vector<std::unique_ptr<PdUnboundedWave<1>>> runs;
      for (const auto &[half, tr] : {std::make_pair(L_ref, WaveTruncation::free),
                                     std::make_pair(L, WaveTruncation::absorbing),
                                     std::make_pair(L, WaveTruncation::free)})
        {
          runs.push_back(std::make_unique<PdUnboundedWave<1>>(MPI_COMM_WORLD));
          runs.back()->setup(BoxDomain<1>(Point<1>(-half), Point<1>(half)), lp, mp, tr, abc, u0);
        }
      const auto near = [&](const Point<1> &x) { return std::abs(x[0]) < L - lp.delta - 1e-9; };
      const auto max_diff = [&](const PdUnboundedWave<1> &a) {
        std::map<long, double> r;
        for (const auto &q : runs[0]->gather(near))
          r[std::lround(q.first[0] / lp.dx)] = q.second;
        double m = 0.;
        for (const auto &q : a.gather(near))
          m = std::max(m, std::abs(q.second - r.at(std::lround(q.first[0] / lp.dx))));
        return m;
      };
      const unsigned int n_steps = static_cast<unsigned int>(std::round(T / mp.time_step)), n = 30;
      std::ofstream out = csv("e12c.csv", "t,ABC,free");
      double err = 0., err_free = 0.;
      for (unsigned int s = 1; s <= n_steps; ++s)
        {
          for (auto &r : runs)
            r->advance();
          if (s % (n_steps / n) == 0)
            {
              const double ea = max_diff(*runs[1]), ef = max_diff(*runs[2]);
              err      = std::max(err, ea);
              err_free = std::max(err_free, ef);
              if (root)
                out << runs[0]->time() << ',' << ea << ',' << ef << '\n';
            }
        }
      const auto &st = runs[1]->absorbing_boundary().statistics();
      if (root)
        std::cout << "1D E12c: (-" << L << ", " << L << "), t = " << T << ", max |u - u_ref| ABC " << err << ", free "
                  << err_free << "; max cond " << st.max_condition_number << ", max |V| " << st.max_update_norm
                  << ", thinned " << st.n_thinned << std::endl;
      check(st.n_thinned == 0, "1D E12c: no cloud thinned (the source: no node reduction needed)");
      check(10. * err < err_free, "1D E12c: ABC 10x closer to the reference than the free truncation (" +
                                    std::to_string(err) + " vs " + std::to_string(err_free) + ")");
    }

    // 2D FEM near field (E13, Sect. 4.2.5): (-L, L)^2, FE_Q(1), lumped mass,
    // velocity Verlet; the EBF ABC with curved modes of the discrete
    // relation vs the conventional first-order ABC (4.75) vs a homogeneous
    // Dirichlet reference on (-L_ref, L_ref)^2.
    {
      const double           L = p.fem_half_width, T = p.fem_end_time;
      const Fem::FemWaveParameters &fp = p.fem;
      WaveAbcParameters abc; // E13's settings, not the PD ones above
      abc.wave_number_range = 1.;
      abc.dispersion        = "discrete";
      abc.cone_angle        = 0.5;
      abc.direction_range   = M_PI / 8.; // Delta phi <= pi/8 (Sect. 4.3)
      abc.curvature_radius  = p.fem_curvature;
      // The pulse has radius ~6; nothing reflected at L_ref is back in
      // (-L, L)^2 before T.
      const double     L_ref = 0.5 * (T + L + 6.) + 3.;
      Triangulation<2> near, far;
      GridGenerator::subdivided_hyper_cube(near, static_cast<unsigned int>(std::round(2. * L / p.fem_h)), -L, L);
      GridGenerator::subdivided_hyper_cube(far, static_cast<unsigned int>(std::round(2. * L_ref / p.fem_h)), -L_ref, L_ref);
      const ScalarFunctionFromFunctionObject<2> u0(
        [](const Point<2> &x) { return std::exp(-std::log(2.) * x.square() / 9.); });
      Fem::FemWave<2> ref(far, fp, Fem::WaveBoundary::dirichlet, abc, u0);
      Fem::FemWave<2> first(near, fp, Fem::WaveBoundary::first_order, abc, u0);
      Fem::FemWave<2> ebf(near, fp, Fem::WaveBoundary::absorbing, abc, u0);
      const auto inside = [&](const Point<2> &x) { return std::max(std::abs(x[0]), std::abs(x[1])) < L - 1e-9; };
      const double       e0      = ref.energy(inside);
      const unsigned int n_steps = static_cast<unsigned int>(std::round(T / fp.time_step)), n = 32;
      std::ofstream out = csv("fem_2d.csv", "t,reference,first-order,EBF,|EBF-ref|,|first-ref|");
      double     de_ebf = 0., de_first = 0.;
      const auto sample = [&]() {
        const double er = ref.energy(inside), ef = first.energy(inside), ee = ebf.energy(inside);
        de_ebf   = std::max(de_ebf, std::abs(ee - er) / e0);
        de_first = std::max(de_first, std::abs(ef - er) / e0);
        if (root)
          out << ref.time() << ',' << er / e0 << ',' << ef / e0 << ',' << ee / e0 << ',' << std::abs(ee - er) / e0
              << ',' << std::abs(ef - er) / e0 << '\n';
      };
      sample();
      for (unsigned int s = 1; s <= n_steps; ++s)
        {
          ref.advance();
          first.advance();
          ebf.advance();
          if (s % std::max(1u, n_steps / n) == 0 || s == n_steps)
            sample();
        }
      // Field error at T: max over the near-field vertices (max u0 = 1).
      double du_ebf = 0., du_first = 0.;
      for (const auto &v : near.get_vertices())
        {
          const double ur = ref.value_at(v);
          du_ebf          = std::max(du_ebf, std::abs(ebf.value_at(v) - ur));
          du_first        = std::max(du_first, std::abs(first.value_at(v) - ur));
        }
      const auto &st = ebf.absorbing_boundary().statistics();
      if (root)
        std::cout << "2D FEM: (-" << L << ", " << L << ")^2, h = " << p.fem_h << ", t = " << T << ", rho = "
                  << p.fem_curvature << "; " << st.n_absorbing << " absorbing DoFs, max cond "
                  << st.max_condition_number << ", max |V| " << st.max_update_norm
                  << "\n  max |E - E_ref|/E0: EBF " << de_ebf << ", first-order " << de_first << " ("
                  << de_first / de_ebf << "x)\n  max |u - u_ref| at t_end: EBF " << du_ebf << ", first-order "
                  << du_first << " (" << du_first / du_ebf << "x)" << std::endl;
      check(de_ebf < de_first, "2D FEM: EBF closer to the reference in energy than the first-order ABC (" +
                                 std::to_string(de_ebf) + " vs " + std::to_string(de_first) + ")");
    }

    if (root)
      {
        std::ostringstream gp;
        gp << gnuplot_png_preamble(p.output_directory + "/energy_2d.png")
           << "set datafile separator ','\nset key autotitle columnhead top right\n"
           << "set logscale y\nset yrange [1e-7:2]\nset xlabel 't'\n"
           << "set ylabel 'E(t)/E_ref(0) and |E - E_ref|/E_ref(0) in r < R - delta'\n"
           << "plot for [i=2:10] '" << p.output_directory << "/energy_2d.csv' using 1:i with linespoints lw 2\n";
        run_gnuplot(p.output_directory + "/energy_2d.gp", gp.str(), p.output_directory + "/energy_2d.png");
        std::ostringstream g1;
        g1 << gnuplot_png_preamble(p.output_directory + "/e12c.png")
           << "set datafile separator ','\nset key autotitle columnhead top left\n"
           << "set logscale y\nset xlabel 't'\nset ylabel 'max |u - u_ref| / max |u_0| in |x| < L - delta'\n"
           << "plot for [i=2:3] '" << p.output_directory << "/e12c.csv' using 1:i with linespoints lw 2\n";
        run_gnuplot(p.output_directory + "/e12c.gp", g1.str(), p.output_directory + "/e12c.png");
        std::ostringstream g2;
        g2 << gnuplot_png_preamble(p.output_directory + "/fem_2d.png")
           << "set datafile separator ','\nset key autotitle columnhead bottom left\n"
           << "set logscale y\nset yrange [1e-6:2]\nset xlabel 't'\n"
           << "set ylabel 'E(t)/E_ref(0) and |E - E_ref|/E_ref(0) in (-L, L)^2'\n"
           << "plot for [i=2:6] '" << p.output_directory << "/fem_2d.csv' using 1:i with linespoints lw 2\n";
        run_gnuplot(p.output_directory + "/fem_2d.gp", g2.str(), p.output_directory + "/fem_2d.png");
      }
    return failures == 0 ? 0 : 1;
  }
} // namespace Step7

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  try
    {
      return Step7::run(argc > 1 ? argv[1] : "step-7.prm");
    }
  catch (const std::exception &e)
    {
      std::cerr << "Error: " << e.what() << std::endl;
      return 1;
    }
}
