// 1D scalar waves (dissertation Sects. 4.2.4-4.2.5): the EBF ABC against the
// CONVENTIONAL FIRST-ORDER ABC (4.75) (not only the free truncation), for
// the PD near field (E12b n_b study, E12c highly dispersive waves) and the
// FEM near field (Fem::FemWave<1>), each against an extended-domain
// reference computed by the same code (doc/design.md, session 18, waves1d).
//
// Metrics of every run against the reference, over the samples of the run:
//   energy: max_s |E(t_s) - E_ref(t_s)| / E0 on the compared region,
//   end:    max |u - u_ref| / max|u0| over the compared nodes at t_end,
//   run:    the same maximum over all samples.
//
// Exploration: WAVES_1D_SCAN="key=value ..." (the EBF keys of
// tests/wave_settings.h, plus for the FEM h, L, dt, T, scheme=verlet|newmark)
// with the test names pd_scan_b, pd_scan_c, fem_scan; keys rho (one-step
// spectral radius), vel=1 (FEM Extrapolate velocity), lumped=0|1 (FEM mass),
// evan=outgoing (PD: Evanescent modes), emargin=n (FEM energy
// without n boundary cells); WAVES_1D_WHERE=dx prints where the PD field
// error at t_end is (positions scaled by dx); WAVES_1D_TRACE=1 prints the FEM
// energy differences at every sample.

#include <deal.II/base/function.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_wave.h>

#include "../check.h"
#include "../wave_settings.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEAL::Abc;
using namespace PeriDEALTests;

namespace
{
  /** The three metrics of one truncated run against its reference. */
  struct Errors
  {
    double energy = 0., end = 0., run = 0.;
  };

  std::string
  format(const std::string &name, const Errors &e)
  {
    return name + ": max |E - E_ref|/E0 " + sci(e.energy) + ", |u - u_ref| at t_end " + sci(e.end) + ", over the run " +
           sci(e.run);
  }

  std::map<std::string, std::string>
  scan_keys()
  {
    const char *s = std::getenv("WAVES_1D_SCAN");
    return key_values(s ? s : "");
  }

  // ---------------------------------------------------------------- PD ----

  /** Energies and fields (position -> u) at the samples of one PD run. */
  struct PdHistory
  {
    std::vector<double>                  energy;
    std::vector<std::map<long, double>>  fields;
    WaveCloudStatistics                  stats;
  };

  PdHistory
  pd_run(const BoxDomain<1> &domain, const LatticeParameters &lp, const ScalarWaveParameters &mp,
         const WaveTruncation truncation, const WaveAbcParameters &prm, const Function<1> &u0, const double T,
         const unsigned int n_samples, const double L_compare)
  {
    PdUnboundedWave<1> pd(MPI_COMM_WORLD);
    pd.setup(domain, lp, mp, truncation, prm, u0);
    const auto         inner   = [&](const Point<1> &p) { return std::abs(p[0]) < L_compare - 1e-9; };
    const unsigned int n_steps = static_cast<unsigned int>(std::round(T / mp.time_step));
    PdHistory          h;
    for (unsigned int s = 0; s <= n_samples; ++s)
      {
        const unsigned int target = n_steps * s / n_samples;
        while (std::round(pd.time() / mp.time_step) < target)
          pd.advance();
        h.energy.push_back(pd.energy(inner));
        std::map<long, double> f;
        for (const auto &q : pd.gather(inner))
          f[std::lround(q.first[0] / lp.dx)] = q.second;
        h.fields.push_back(f);
      }
    h.stats = pd.absorbing_boundary().statistics();
    return h;
  }

  Errors
  pd_errors(const PdHistory &h, const PdHistory &ref, const double u_max)
  {
    Errors e;
    for (unsigned int s = 0; s < h.energy.size(); ++s)
      {
        e.energy = std::max(e.energy, std::abs(h.energy[s] - ref.energy[s]) / ref.energy[0]);
        double m = 0.;
        for (const auto &q : h.fields[s])
          m = std::max(m, std::abs(q.second - ref.fields[s].at(q.first)));
        e.run = std::max(e.run, m / u_max);
        if (s + 1 == h.energy.size())
          {
            e.end = m / u_max;
            if (std::getenv("WAVES_1D_WHERE") && root())
              for (const auto &q : h.fields[s])
                if (std::abs(q.second - ref.fields[s].at(q.first)) >= 0.5 * m)
                  std::cout << "      x = " << q.first * std::stod(std::getenv("WAVES_1D_WHERE")) << ": u - u_ref = "
                            << sci(q.second - ref.fields[s].at(q.first)) << ", u_ref = " << sci(ref.fields[s].at(q.first))
                            << std::endl;
          }
      }
    return e;
  }

  /** E12b: delta 0.6, dx 0.2, p = 0, chi = 1, d = 0, (-10, 10) vs (-50, 50), T = 25. */
  struct E12b
  {
    LatticeParameters    lp;
    ScalarWaveParameters mp;
    double               L = 10., L_ref = 50., T = 25.;
    unsigned int         n_samples = 25;
    E12b()
    {
      lp.dx         = 0.2;
      lp.delta      = 0.6;
      mp.exponent   = 0.;
      mp.wave_speed = 1.;
      mp.damping    = 0.;
      mp.time_step  = 1e-3;
    }
  };

  /** E12c reduced (as wave_abc.pd_1d_dispersive): (-3, 3), T = 3, chi^2 = 10, d = 5e-4, m = 25. */
  struct E12c
  {
    LatticeParameters    lp;
    ScalarWaveParameters mp;
    double               L = 3., L_ref = 0., T = 3.;
    unsigned int         n_samples = 30;
    E12c()
    {
      lp.dx         = 0.01;
      lp.delta      = 0.25;
      mp.exponent   = 0.;
      mp.wave_speed = std::sqrt(10.);
      mp.damping    = 5e-4;
      mp.time_step  = 1e-4;
      // As pd_1d_dispersive: nothing reflected at L_ref is back in (-L, L)
      // before T, a multiple of dx so both lattices share nodes.
      L_ref = lp.dx * std::ceil((0.5 * (mp.wave_speed * T + L + 1.) + 1.) / lp.dx);
    }
  };

  WaveAbcParameters
  e12b_ebf(const std::string &relation, const unsigned int nb)
  {
    WaveAbcParameters prm;
    prm.wave_number_range = M_PI / 2.;
    prm.dispersion        = relation;
    prm.n_wave_numbers    = nb;
    return prm;
  }

  WaveAbcParameters
  e12c_ebf()
  {
    WaveAbcParameters prm;
    prm.wave_number_range        = 1.;
    prm.n_wave_numbers           = 20;
    prm.pseudo_inverse_tolerance = 1e-12;
    return prm;
  }

  /** Reference, free, first-order and the given EBF settings of one PD case; returns the errors by name. */
  template <typename Case>
  std::map<std::string, Errors>
  pd_compare(const Case &c, const Function<1> &u0, const std::vector<std::pair<std::string, WaveAbcParameters>> &ebf)
  {
    const BoxDomain<1> near(Point<1>(-c.L), Point<1>(c.L)), far(Point<1>(-c.L_ref), Point<1>(c.L_ref));
    const double       L_compare = c.L - c.lp.delta;
    const auto ref = pd_run(far, c.lp, c.mp, WaveTruncation::free, ebf[0].second, u0, c.T, c.n_samples, L_compare);
    std::map<std::string, Errors> r;
    r["free"]        = pd_errors(pd_run(near, c.lp, c.mp, WaveTruncation::free, ebf[0].second, u0, c.T, c.n_samples, L_compare), ref, 1.);
    // The first-order ABC (4.75) takes chi as the long-wave speed of the
    // relation: always the lattice's (discrete), whatever the EBF uses.
    WaveAbcParameters first = ebf[0].second;
    first.dispersion        = "discrete";
    r["first order"] = pd_errors(pd_run(near, c.lp, c.mp, WaveTruncation::first_order, first, u0, c.T, c.n_samples, L_compare), ref, 1.);
    for (const auto &e : ebf)
      {
        const auto h = pd_run(near, c.lp, c.mp, WaveTruncation::absorbing, e.second, u0, c.T, c.n_samples, L_compare);
        r[e.first]   = pd_errors(h, ref, 1.);
        if (root())
          std::cout << "    " << e.first << ": cond " << sci(h.stats.max_condition_number) << ", max|V| "
                    << sci(h.stats.max_update_norm) << ", thinned " << h.stats.n_thinned << std::endl;
      }
    if (root())
      for (const auto &e : r)
        std::cout << "    " << format(e.first, e.second) << std::endl;
    return r;
  }

  double
  one_step_radius_pd(const BoxDomain<1> &domain, const LatticeParameters &lp, const ScalarWaveParameters &mp,
                     const WaveTruncation truncation, const WaveAbcParameters &prm, const Function<1> &u0)
  {
    PdUnboundedWave<1> pd(MPI_COMM_SELF);
    pd.setup(domain, lp, mp, truncation, prm, u0);
    return pd.one_step_spectral_radius(4000);
  }

  const ScalarFunctionFromFunctionObject<1> e12b_u0([](const Point<1> &p) { return std::exp(-p[0] * p[0]); });
  const ScalarFunctionFromFunctionObject<1> e12c_u0(
    [](const Point<1> &p) { return std::exp(-20. * std::log(2.) * p[0] * p[0]); });

  /**
   * E12b: the source's n_b = 4 settings (wave_abc.pd_1d_modes, both
   * relations), the discrete n_b = 5 with one time level (step-7), and a
   * wide local set (Delta alpha = 3, n_b = 6, found by pd_scan_b) against
   * first order. Measured (session 19; until then the near field lost
   * its end node x = L to round-off, see doc/design.md, and the EBF
   * looked worse than first order):
   *   setting                  energy    u at t_end  u over run  rho - 1
   *   free                     0.997     0.385       0.784
   *   first order              2.97e-2   4.23e-2     6.51e-2     1.4e-6
   *   discrete n_b 4 (source)  2.49e-4   1.46e-3     1.46e-3     3.8e-5
   *   local n_b 4              1.33e-4   4.03e-3     7.30e-3
   *   discrete n_b 5, 1 level  2.32e-4   4.77e-3     5.57e-3
   *   local Delta alpha 3 n_b 6 1.47e-4  3.84e-3     7.36e-3     1.1e-6
   *   source + evanescent      2.28e-3   3.85e-2     4.29e-2     -3.1e-9
   * E12c reduced (source settings): energy 3.27e-5 vs 2.46e-3 (75x), u at
   * t_end 3.46e-4 vs 7.85e-3 (22.7x), over the run 3.46e-4 vs 1.24e-2 (36x).
   */
  void
  pd_1d_first_order()
  {
    {
      if (root())
        std::cout << "  E12b" << std::endl;
      const E12b c;
      auto       one_level    = e12b_ebf("discrete", 5);
      one_level.n_time_levels = 1;
      auto wide               = e12b_ebf("local", 6);
      wide.wave_number_range  = 3.;
      // The source's modes plus the outgoing evanescent lattice modes
      // (session 19, waves1d2).
      auto evanescent             = e12b_ebf("discrete", 4);
      evanescent.evanescent_modes = "outgoing";
      const auto r = pd_compare(c, e12b_u0,
                                {{"EBF discrete n_b 4", e12b_ebf("discrete", 4)},
                                 {"EBF local n_b 4", e12b_ebf("local", 4)},
                                 {"EBF discrete n_b 5 one level", one_level},
                                 {"EBF local wide", wide},
                                 {"EBF discrete n_b 4 evanescent", evanescent}});
      const auto &f = r.at("first order"), &src = r.at("EBF discrete n_b 4"), &w = r.at("EBF local wide");
      for (const auto &e : r)
        if (e.first != "free")
          check(e.second.energy < 0.1 * r.at("free").energy, "E12b " + e.first + ": energy 10x closer than the free truncation");
      // The source's settings: 119x in energy, 29x in the field at t_end,
      // 45x over the run; asserted 10x (the runs are deterministic; the
      // smallest margin, 2.9x in the field, is what a regression may eat).
      check(10. * src.energy < f.energy, "E12b source's EBF: max energy difference 10x below first order (" +
                                           sci(src.energy) + " vs " + sci(f.energy) + ")");
      check(10. * src.end < f.end, "E12b source's EBF: field at t_end 10x below first order (" + sci(src.end) +
                                     " vs " + sci(f.end) + ")");
      check(10. * src.run < f.run, "E12b source's EBF: field over the run 10x below first order (" +
                                     sci(src.run) + " vs " + sci(f.run) + ")");
      // Wide local modes: energy 203x, field at t_end 11x (asserted 10x
      // and 5x).
      check(10. * w.energy < f.energy, "E12b wide local EBF: max energy difference 10x below first order (" +
                                         sci(w.energy) + " vs " + sci(f.energy) + ")");
      check(5. * w.end < f.end, "E12b wide local EBF: field at t_end 5x below first order (" + sci(w.end) +
                                  " vs " + sci(f.end) + ")");
      if (Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) == 1)
        {
          // Weakly unstable (measured 1 + 1.1e-6 per step: 3 % over the
          // 25,000 steps); asserted below 1e-5 so that a real blow-up fails.
          const double rho = one_step_radius_pd(BoxDomain<1>(Point<1>(-c.L), Point<1>(c.L)), c.lp, c.mp,
                                                WaveTruncation::absorbing, wide, e12b_u0);
          if (root())
            std::cout << "    EBF local wide: one-step spectral radius - 1 = " << sci(rho - 1.) << std::endl;
          check(rho < 1. + 1e-5, "E12b wide local EBF: one-step radius - 1 = " + sci(rho - 1.) + " < 1e-5 (NOT <= 1)");
          // Outgoing evanescent modes: stable (measured 1 - 3.1e-9; the
          // source's n_b 4 without them 1 + 3.8e-5).
          const double rho_e = one_step_radius_pd(BoxDomain<1>(Point<1>(-c.L), Point<1>(c.L)), c.lp, c.mp,
                                                  WaveTruncation::absorbing, evanescent, e12b_u0);
          if (root())
            std::cout << "    EBF evanescent: one-step spectral radius - 1 = " << sci(rho_e - 1.) << std::endl;
          check(rho_e <= 1. + 1e-8, "E12b evanescent EBF: one-step radius - 1 = " + sci(rho_e - 1.) + " <= 1e-8");
        }
      {
        // Bad input: the evanescent roots need a lattice relation (the local
        // one, omega = chi k, has none).
        auto bad             = e12b_ebf("local", 4);
        bad.evanescent_modes = "outgoing";
        bool thrown          = false;
        try
          {
            pd_run(BoxDomain<1>(Point<1>(-c.L), Point<1>(c.L)), c.lp, c.mp, WaveTruncation::absorbing, bad,
                   e12b_u0, 0., 0, c.L);
          }
        catch (const ParameterError &)
          {
            thrown = true;
          }
        check(thrown, "E12b: Evanescent modes with the local relation is rejected with a ParameterError");
      }
      // Outgoing evanescent modes (session 19): stable but less accurate
      // than the source's modes alone: energy 2.28e-3 (13x below first
      // order), field at t_end 3.85e-2 (1.1x); asserted 5x / below first
      // order. Opt-in.
      const auto &ev = r.at("EBF discrete n_b 4 evanescent");
      check(5. * ev.energy < f.energy, "E12b evanescent EBF: max energy difference 5x below first order (" +
                                         sci(ev.energy) + " vs " + sci(f.energy) + ")");
      check(ev.end < f.end, "E12b evanescent EBF: field at t_end below first order (" + sci(ev.end) + " vs " +
                              sci(f.end) + ")");
    }
    {
      if (root())
        std::cout << "  E12c reduced" << std::endl;
      const E12c c;
      const auto r = pd_compare(c, e12c_u0, {{"EBF discrete n_b 20", e12c_ebf()}});
      const auto &f = r.at("first order"), &e = r.at("EBF discrete n_b 20");
      // Measured 75x / 22.7x / 36x: the 10x with margins >= 2.2.
      check(10. * e.energy < f.energy, "E12c: max energy difference 10x below first order (" + sci(e.energy) + " vs " + sci(f.energy) + ")");
      check(10. * e.end < f.end, "E12c: field at t_end 10x below first order (" + sci(e.end) + " vs " + sci(f.end) + ")");
      check(10. * e.run < f.run, "E12c: field over the run 10x below first order (" + sci(e.run) + " vs " + sci(f.run) + ")");
    }
  }

  void
  pd_scan(const bool dispersive)
  {
    const auto kv = scan_keys();
    auto prm = with_wave_settings(dispersive ? e12c_ebf() : e12b_ebf("discrete", 4), kv);
    // evan=none|outgoing|incoming|all: evanescent lattice modes (session 19).
    if (kv.count("evan"))
      prm.evanescent_modes = kv.at("evan");
    if (dispersive)
      pd_compare(E12c(), e12c_u0, {{"EBF scan", prm}});
    else
      {
        // dx=: another lattice spacing (same delta) for E12b.
        E12b b;
        if (kv.count("dx"))
          b.lp.dx = std::stod(kv.at("dx"));
        // w=: pulse exp(-(x/w)^2) (E12b: w = 1).
        const double w = kv.count("w") ? std::stod(kv.at("w")) : 1.;
        const ScalarFunctionFromFunctionObject<1> u0([w](const Point<1> &p) { return std::exp(-p[0] * p[0] / (w * w)); });
        pd_compare(b, u0, {{"EBF scan", prm}});
      }
    if (kv.count("rho"))
      {
        const E12b b;
        const E12c c;
        const double rho = dispersive ?
          one_step_radius_pd(BoxDomain<1>(Point<1>(-c.L), Point<1>(c.L)), c.lp, c.mp, WaveTruncation::absorbing, prm, e12c_u0) :
          one_step_radius_pd(BoxDomain<1>(Point<1>(-b.L), Point<1>(b.L)), b.lp, b.mp, WaveTruncation::absorbing, prm, e12b_u0);
        auto first       = prm;
        first.dispersion = "discrete";
        const double rho_first = dispersive ?
          one_step_radius_pd(BoxDomain<1>(Point<1>(-c.L), Point<1>(c.L)), c.lp, c.mp, WaveTruncation::first_order, first, e12c_u0) :
          one_step_radius_pd(BoxDomain<1>(Point<1>(-b.L), Point<1>(b.L)), b.lp, b.mp, WaveTruncation::first_order, first, e12b_u0);
        if (root())
          std::cout << "    one-step spectral radius - 1 = " << sci(rho - 1.) << " (first order " << sci(rho_first - 1.) << ")" << std::endl;
      }
  }

  // --------------------------------------------------------------- FEM ----

  /** FEM 1D case: Q1 on (-L, L), chi = 1, d = 0.0125 (E13), u0 = exp(-log 2 x^2 / 9). */
  struct Fem1d
  {
    double                 L = 16., h = 0.5, dt = 0.02, T = 32.;
    /** Cells left out of the energy region at each end (exploration only; 0 in the tests). */
    double                 energy_margin = 0.;
    Fem::FemWaveParameters fem;
    WaveAbcParameters      abc;
    Fem1d()
    {
      fem.damping           = 0.0125;
      abc.wave_number_range = 1.;
      abc.dispersion        = "local";
    }
  };

  double
  fem_pulse(const Point<1> &p)
  {
    return std::exp(-std::log(2.) * p[0] * p[0] / 9.);
  }

  const ScalarFunctionFromFunctionObject<1> fem_u0(fem_pulse);

  std::map<std::string, Errors>
  fem_compare(const Fem1d &c, const std::vector<std::pair<std::string, WaveAbcParameters>> &ebf, double *radius = nullptr)
  {
    Fem::FemWaveParameters fp = c.fem;
    fp.time_step              = c.dt;
    // The pulse has half-width ~6 (u0(16) = 2.7e-9); a front reflected at
    // L_ref is back in (-L, L) after 2 L_ref - L - 6 > T (3 units margin).
    const double L_ref = c.h * std::ceil((0.5 * (c.T + c.L + 6.) + 3.) / c.h);
    Triangulation<1> near, far;
    GridGenerator::subdivided_hyper_cube(near, static_cast<unsigned int>(std::round(2. * c.L / c.h)), -c.L, c.L);
    GridGenerator::subdivided_hyper_cube(far, static_cast<unsigned int>(std::round(2. * L_ref / c.h)), -L_ref, L_ref);
    std::vector<std::pair<std::string, std::unique_ptr<Fem::FemWave<1>>>> runs;
    runs.emplace_back("first order", std::make_unique<Fem::FemWave<1>>(near, fp, Fem::WaveBoundary::first_order, c.abc, fem_u0));
    for (const auto &e : ebf)
      {
        runs.emplace_back(e.first, std::make_unique<Fem::FemWave<1>>(near, fp, Fem::WaveBoundary::absorbing, e.second, fem_u0));
        const auto &st = runs.back().second->absorbing_boundary().statistics();
        if (root())
          std::cout << "    " << e.first << " (" << runs.back().second->dispersion().name << "): clouds "
                    << st.min_cloud_size << ".." << st.max_cloud_size << ", cond " << sci(st.max_condition_number)
                    << ", max|V| " << sci(st.max_update_norm) << std::endl;
      }
    Fem::FemWave<1> ref(far, fp, Fem::WaveBoundary::dirichlet, c.abc, fem_u0);
    const auto      inside  = [&](const Point<1> &p) { return std::abs(p[0]) < c.L - c.energy_margin * c.h - 1e-9; };
    const double    e0      = ref.energy(inside);
    const unsigned int n_steps = static_cast<unsigned int>(std::round(c.T / c.dt));
    const unsigned int every   = std::max(1u, n_steps / 64);
    const unsigned int n_nodes = static_cast<unsigned int>(std::round(2. * c.L / c.h));
    std::map<std::string, Errors> r;
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        ref.advance();
        for (auto &w : runs)
          w.second->advance();
        if (s % every != 0 && s != n_steps)
          continue;
        const double er = ref.energy(inside);
        for (auto &w : runs)
          {
            auto &e  = r[w.first];
            e.energy = std::max(e.energy, std::abs(w.second->energy(inside) - er) / e0);
            if (std::getenv("WAVES_1D_TRACE") && root())
              std::cout << "      t " << s * c.dt << " " << w.first << ": (E - E_ref)/E0 "
                        << sci((w.second->energy(inside) - er) / e0) << ", E_ref/E0 " << sci(er / e0) << std::endl;
            double m = 0.;
            for (unsigned int j = 0; j <= n_nodes; ++j)
              {
                const Point<1> p(-c.L + j * c.h);
                m = std::max(m, std::abs(w.second->value_at(p) - ref.value_at(p)));
              }
            e.run = std::max(e.run, m);
            if (s == n_steps)
              e.end = m;
          }
      }
    if (root())
      for (const auto &e : r)
        std::cout << "    " << format(e.first, e.second) << std::endl;
    if (radius)
      {
        // One-step spectral radius of the first EBF setting on the same
        // near field (the state is small in 1D).
        Fem::FemWave<1> w(near, fp, Fem::WaveBoundary::absorbing, ebf[0].second, fem_u0);
        unsigned int    n_up = 0;
        *radius              = w.one_step_spectral_radius(4000, &n_up);
        if (root())
          std::cout << "    " << ebf[0].first << ": one-step spectral radius - 1 = " << sci(*radius - 1.) << " ("
                    << n_up << " > 1 + 1e-8)" << std::endl;
      }
    return r;
  }

  Fem1d
  fem_case(const std::string &scheme)
  {
    Fem1d c;
    if (scheme == "newmark")
      {
        c.fem.scheme      = "Newmark";
        c.fem.lumped_mass = false;
      }
    return c;
  }

  /**
   * FEM 1D, h = 0.25, Delta k = 0.5 (fem_scan: Delta k = 1 gives 9.0x at
   * t_end with Verlet at h = 0.25, 0.3-0.6 give 7.6-9.0x at h = 0.5 and 13x at h =
   * 0.25), local relation, default clouds (x_i + 2 DoFs). Measured:
   *   run                      energy    u at t_end  rho - 1
   *   Verlet, first order      2.50e-5   1.49e-3
   *   Verlet, EBF              4.43e-5   1.14e-4     2e-12
   *   Verlet, EBF, V_H velocity 4.18e-6  1.14e-4     1e-12
   *   Newmark cons., first     1.08e-5   1.50e-3
   *   Newmark cons., EBF       4.60e-6   1.10e-4     8.4e-9 (split -1)
   */
  void
  fem_1d_first_order()
  {
    for (const std::string scheme : {"verlet", "newmark"})
      for (const bool velocity : {false, true})
        {
          if (scheme == "newmark" && velocity)
            continue;
          if (root())
            std::cout << "  FEM 1D, " << scheme << (velocity ? ", Extrapolate velocity" : "") << std::endl;
          Fem1d c                     = fem_case(scheme);
          c.h                         = 0.25;
          c.abc.wave_number_range     = 0.5;
          c.fem.extrapolate_velocity  = velocity;
          double     rho              = 0.;
          const auto r                = fem_compare(c, {{"EBF local", c.abc}}, &rho);
          const auto &f = r.at("first order"), &e = r.at("EBF local");
          const std::string what = "FEM 1D " + scheme + (velocity ? " (V_H velocity)" : "");
          // Measured 13.0x (Verlet) / 13.6x (Newmark); margin 1.3.
          check(10. * e.end < f.end, what + ": field at t_end 10x below first order (" + sci(e.end) + " vs " + sci(f.end) + ")");
          check(10. * e.run < f.run, what + ": field over the run 10x below first order (" + sci(e.run) + " vs " + sci(f.run) + ")");
          if (scheme == "verlet" && !velocity)
            // The difference-quotient boundary velocity (the default) is half a
            // step off in the boundary cell's energy: 4.4e-5 E0, worse than
            // first order (2.5e-5; without the boundary cells 3.7e-6 vs 2.0e-5).
            check(e.energy < 1e-4, what + ": energy difference " + sci(e.energy) + " < 1e-4 E0 (first order " + sci(f.energy) + ", NOT 10x)");
          else if (scheme == "verlet")
            // Measured 6.0x; asserted 4x.
            check(4. * e.energy < f.energy, what + ": energy difference 4x below first order (" + sci(e.energy) + " vs " + sci(f.energy) + "; NOT 10x)");
          else
            // Measured 2.3x; asserted below first order.
            check(e.energy < f.energy, what + ": energy difference below first order (" + sci(e.energy) + " vs " + sci(f.energy) + "; NOT 10x)");
          // Verlet: no tangential direction, so no backward-wave sawtooth
          // (2D: 1.0025); measured 1 + 2e-12. Newmark + consistent mass: the
          // round-off split of the defective -1 (~sqrt(eps)), as in 2D.
          const double bound = scheme == "verlet" ? 1e-8 : 1e-6;
          check(rho <= 1. + bound, what + ": one-step spectral radius - 1 = " + sci(rho - 1.) + " <= " + sci(bound));
        }
    // The 10x in energy AND field (session 19, waves1d2): the modes
    // with the scheme's own semi-discrete relation (discrete: the Q1 row
    // over the lumped mass, or over the consistent mass symbol) instead of
    // omega = chi k. The local relation's phase error (kh)^2/24 is the
    // EBF's energy floor (4.2e-6 / 4.6e-6 above).
    for (const std::string scheme : {"verlet", "newmark"})
      {
        if (root())
          std::cout << "  FEM 1D, " << scheme << ", discrete relation" << std::endl;
        Fem1d c                    = fem_case(scheme);
        c.h                        = 0.25;
        c.abc.wave_number_range    = 0.5;
        c.abc.dispersion           = "discrete";
        c.fem.extrapolate_velocity = scheme == "verlet";
        double     rho             = 0.;
        const auto r               = fem_compare(c, {{"EBF discrete", c.abc}}, &rho);
        const auto &f = r.at("first order"), &e = r.at("EBF discrete");
        const std::string what = "FEM 1D " + scheme + " (discrete relation" +
                                 (scheme == "verlet" ? ", V_H velocity)" : ")");
        // Measured: Verlet + V_H energy 6.71e-7 vs 2.50e-5 (37x), field at
        // t_end 1.20e-4 vs 1.49e-3 (12.5x); Newmark + consistent energy
        // 3.73e-7 vs 1.08e-5 (29x), field 1.03e-4 vs 1.50e-3 (14.5x).
        // Asserted the 10x (margins >= 1.25, deterministic runs).
        check(10. * e.energy < f.energy, what + ": energy difference 10x below first order (" + sci(e.energy) + " vs " + sci(f.energy) + ")");
        check(10. * e.end < f.end, what + ": field at t_end 10x below first order (" + sci(e.end) + " vs " + sci(f.end) + ")");
        check(10. * e.run < f.run, what + ": field over the run 10x below first order (" + sci(e.run) + " vs " + sci(f.run) + ")");
        // Verlet measured 1 - 1e-12; Newmark + consistent 1 + 3.3e-8 (the
        // round-off split of the defective -1, as above).
        const double bound = scheme == "verlet" ? 1e-8 : 1e-6;
        check(rho <= 1. + bound, what + ": one-step spectral radius - 1 = " + sci(rho - 1.) + " <= " + sci(bound));
      }
  }

  void
  fem_scan()
  {
    const auto kv  = scan_keys();
    const auto num = [&](const std::string &k, const double def) { return kv.count(k) ? std::stod(kv.at(k)) : def; };
    Fem1d      c   = fem_case(kv.count("scheme") ? kv.at("scheme") : "verlet");
    c.h            = num("h", c.h);
    c.L            = num("L", c.L);
    c.dt           = num("dt", c.dt);
    c.T            = num("T", c.T);
    c.energy_margin = num("emargin", 0.);
    c.fem.extrapolate_velocity = num("vel", 0.) != 0.;
    // lumped=1: Newmark with the lumped mass (for the discrete relation).
    if (kv.count("lumped"))
      c.fem.lumped_mass = num("lumped", 1.) != 0.;
    double rho     = 0.;
    fem_compare(c, {{"EBF scan", with_wave_settings(c.abc, kv)}}, kv.count("rho") ? &rho : nullptr);
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"pd_1d_first_order", pd_1d_first_order},
              {"fem_1d_first_order", fem_1d_first_order},
              {"pd_scan_b", [] { pd_scan(false); }},
              {"pd_scan_c", [] { pd_scan(true); }},
              {"fem_scan", fem_scan}});
}
