// Tests of the EBF absorbing boundary for 2D bond-based PD elastic waves
// (dissertation Sect. 4.3): the discrete P/S dispersion relation against
// the near-field operator, the continuum series of Table 4.2 and the
// frequencies measured from simulated plane waves; the truncated near field
// with the ABC against an extended-domain reference (E16, reduced) and the
// free / fixed truncations; energy decay; rank independence.

#include <deal.II/base/function.h>
#include <deal.II/base/timer.h>

#include <perideal/abc/ebf_elastic_abc.h>
#include <perideal/base/exceptions.h>

#include "../check.h"
#include "../wave_settings.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <map>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEAL::Abc;
using namespace PeriDEALTests;

namespace
{
  /** Plane stress, omega_0, E = rho = 1 (nu = 1/3, c = 9E/(pi delta^3) (2.31)). */
  BondBasedModelParameters
  linear_model()
  {
    BondBasedModelParameters m;
    m.youngs_modulus = 1.;
    m.plane_stress   = true;
    m.linearized     = true;
    return m;
  }

  Tensor<1, 2>
  unit(const double phi)
  {
    Tensor<1, 2> n;
    n[0] = std::cos(phi);
    n[1] = std::sin(phi);
    return n;
  }

  // (a) The discrete relation is the symbol of the near-field operator, it
  // converges to the continuum series of Table 4.2 as delta/dx grows, and
  // the frequencies measured from simulated plane P and S waves are its
  // eigenvalues.
  void
  dispersion()
  {
    const BondBasedModelParameters model = linear_model();
    // Operator symbol: F(gamma cos(k.x)) = -M(k) gamma cos(k.x) at nodes
    // whose family is complete (at least delta + dx from the boundary).
    {
      LatticeParameters lp;
      lp.dx    = 0.5;
      lp.delta = 1.5;
      Discretization<2> disc(MPI_COMM_WORLD);
      BoxDomain<2>      box(Point<2>(-5., -5.), Point<2>(5., 5.));
      disc.setup(box, lp);
      BondBasedOperator<2> op(disc, model);
      const auto           rel = ElasticDispersion::discrete(model, lp, 1., 0.);
      const Tensor<1, 2>   k   = 1.3 * unit(0.4);
      Tensor<1, 2>         g;
      g[0] = 0.3;
      g[1] = -0.8;
      BondBasedOperator<2>::VectorField u, F;
      op.initialize(u);
      op.initialize(F);
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int q = 0; q < 2; ++q)
          u[q].local_element(i) = g[q] * std::cos(k * disc.position[i]);
      for (auto &x : u)
        x.update_ghost_values();
      op.compute_forces(u, F);
      const Tensor<1, 2> Mg = rel.acoustic_matrix(k) * g;
      double             err = 0., ref = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const Point<2> &x = disc.position[i];
          if (std::max(std::abs(x[0]), std::abs(x[1])) > 5. - lp.delta - lp.dx)
            continue;
          for (unsigned int q = 0; q < 2; ++q)
            {
              err = std::max(err, std::abs(F[q].local_element(i) + Mg[q] * std::cos(k * x)));
              ref = std::max(ref, std::abs(Mg[q]));
            }
        }
      err = Utilities::MPI::max(err, MPI_COMM_WORLD);
      check(err <= 1e-12 * ref, "discrete M(k) is the symbol of the linearized operator: max error " + sci(err / ref));
    }
    // Table 4.2 (N = 3, plane stress, omega_0): omega_P^2 = 9E/(8 rho) k^2
    // (1 - (k d)^2/24 + (k d)^4/1152), omega_S^2 = 3E/(8 rho) k^2 (1 -
    // (k d)^2/40 + (k d)^4/2688). The truncation error is O((k d)^6) (below
    // 1e-4 relative at k delta = 0.5); the discrete relation approaches the
    // series as m = delta/dx grows.
    {
      const double delta = 1., kd = 0.5, k = kd / delta, phi = 0.3;
      const double wp2 = 9. / 8. * k * k * (1. - kd * kd / 24. + std::pow(kd, 4) / 1152.);
      const double ws2 = 3. / 8. * k * k * (1. - kd * kd / 40. + std::pow(kd, 4) / 2688.);
      double       prev = 1e300;
      for (const int m : {2, 4, 8, 16})
        {
          LatticeParameters lp;
          lp.delta       = delta;
          lp.dx          = delta / m;
          const auto rel = ElasticDispersion::discrete(model, lp, 1., 0.);
          const auto md  = rel.modes(k, unit(phi));
          const double ep = std::abs(std::norm(md[0].frequency) / wp2 - 1.);
          const double es = std::abs(std::norm(md[1].frequency) / ws2 - 1.);
          if (root())
            std::cout << "    m = " << m << ": |w_P^2/w_P,4.2^2 - 1| = " << sci(ep)
                      << ", |w_S^2/w_S,4.2^2 - 1| = " << sci(es) << ", gamma_P . n = "
                      << md[0].polarization * unit(phi) << std::endl;
          check(std::max(ep, es) < prev, "discrete -> Table 4.2 as m grows (m = " + std::to_string(m) + ")");
          prev = std::max(ep, es);
        }
      // Measured 4.4e-3 at m = 16 (the partial-volume quadrature error).
      check(prev < 1e-2, "m = 16: discrete P and S within 1% of Table 4.2 (N = 3)");
      // The local relation (4.110) is the k -> 0 limit of both.
      const auto loc = ElasticDispersion::local(1., true, 1., 0.).modes(k, unit(phi));
      check_close(std::norm(loc[0].frequency), 9. / 8. * k * k, 1e-13, "local omega_P^2 = 9E k^2/(8 rho)");
      check_close(std::norm(loc[1].frequency), 3. / 8. * k * k, 1e-13, "local omega_S^2 = 3E k^2/(8 rho)");
    }
    // Plane waves simulated with velocity Verlet: the centre node of a free
    // box started from u = gamma cos(k.x), v = 0 oscillates with the
    // Verlet-discrete frequency cos(theta) = 1 - dt^2 omega^2/2 until the
    // disturbance of the free surfaces arrives: the run stops when a P
    // front from the surface would be half way to the centre (the
    // Verlet-discrete solution also has a fast-decaying precursor ahead of
    // the physical front, one horizon per step).
    {
      LatticeParameters lp;
      lp.dx    = 1.;
      lp.delta = 3.;
      const double L = 80., dt = 0.5, phi = 0.3;
      BoxDomain<2> box(Point<2>(-L / 2, -L / 2), Point<2>(L / 2, L / 2));
      const auto   rel = ElasticDispersion::discrete(model, lp, 1., 0.);
      for (const double k : {0.4, 1.2})
        for (unsigned int b = 0; b < 2; ++b)
          {
            const auto          mode = rel.modes(k, unit(phi))[b];
            const Tensor<1, 2>  kv   = k * unit(phi);
            const Tensor<1, 2>  g    = mode.polarization;
            FunctionFromFunctionObjects<2> u0(
              {[&](const Point<2> &x) { return g[0] * std::cos(kv * x); },
               [&](const Point<2> &x) { return g[1] * std::cos(kv * x); }});
            PdUnboundedElastic pd(MPI_COMM_WORLD);
            ElasticWaveParameters wp;
            wp.time_step = dt;
            pd.setup(box, lp, model, wp, ElasticTruncation::free, WaveAbcParameters(), u0);
            const auto centre = [](const Point<2> &x) { return x.norm() < 1e-9; };
            std::vector<Tensor<1, 2>> history;
            const unsigned int n_steps = static_cast<unsigned int>((L / 2 - lp.delta) / (2. * 1.1) / dt);
            for (unsigned int n = 0; n <= n_steps; ++n)
              {
                history.push_back(pd.gather(centre).at(0).displacement);
                pd.advance();
              }
            // Measured omega^2 from u^{n+1} + u^{n-1} = 2 cos(theta) u^n
            // (least squares over the run, both components).
            double num = 0., den = 0., pol = 0.;
            for (unsigned int n = 1; n + 1 < history.size(); ++n)
              {
                const Tensor<1, 2> s = history[n + 1] + history[n - 1];
                num += s * history[n];
                den += 2. * history[n] * history[n];
                pol = std::max(pol, std::abs(history[n][0] * g[1] - history[n][1] * g[0]));
              }
            const double cos_theta = num / den;
            const double measured  = 2. * (1. - cos_theta) / (dt * dt);
            const std::string name = std::string(b == 0 ? "P" : "S") + " wave, k = " + sci(k);
            check_close(measured, std::norm(mode.frequency), 1e-9, name + ": measured omega^2 vs the discrete relation");
            check(pol < 1e-9, name + ": the polarization stays gamma (deviation " + sci(pol) + ")");
            // The local relation is off by the nonlocal dispersion (a
            // control that the measurement discriminates).
            const auto loc = ElasticDispersion::local(1., true, 1., 0.).modes(k, unit(phi))[b];
            if (k > 1.)
              check(std::abs(measured / std::norm(loc.frequency) - 1.) > 0.05,
                    name + ": differs from the local relation by " + sci(std::abs(measured / std::norm(loc.frequency) - 1.)));
          }
    }
  }

  // E16 (reduced): radial Gaussian pulse u0 = (x/w) exp(-r^2/w^2) in a disc
  // of radius R, delta = 3 dx, against a free disc large enough that no
  // reflection returns before T (reference_radius with c_P).
  struct Case
  {
    double R, T, w, dx, delta, dt;
    unsigned int n_samples;
    /** d of the run (the E16 runs: 2% of omega_P(k = 1), see run_case()). */
    double damping = 0.02;
    /** Pulse centre (offset, 0): oblique incidence (first_order_scan only). */
    double offset = 0.;
  };

  Case
  ci_case()
  {
    return {16., 48., 2.5, 1., 3., 0.5, 12};
  }

  WaveAbcParameters
  abc_parameters()
  {
    WaveAbcParameters prm;
    prm.wave_number_range = 1.;
    prm.n_wave_numbers    = 2;
    prm.n_directions      = 2;
    // Delta phi <= pi/8 (Sect. 4.3.4, from [95]).
    prm.direction_range = M_PI / 8.;
    prm.cone_angle      = M_PI / 4.;
    // ||V|| <= 1 for bond-based PD (Sect. 4.3.4; errata 11).
    prm.max_update_norm = 1.;
    prm.dispersion      = "discrete";
    prm.n_time_levels   = 2;
    return prm;
  }

  /** Set up @p pd for case @p c on a disc of @p radius with truncation @p tr. */
  void
  setup_case(PdUnboundedElastic &pd, const Case &c, const double radius, const ElasticTruncation tr,
             const WaveAbcParameters &prm)
  {
    LatticeParameters lp;
    lp.dx    = c.dx;
    lp.delta = c.delta;
    ElasticWaveParameters wp;
    wp.time_step = c.dt;
    // A light damping (d / omega_P(k = 1) = 2%): without it the coupled
    // recursion of near field and absorbing update grows slowly (measured
    // ~1.4% energy growth per step after t ~ 100, the analogue of the 2D
    // scalar-wave instability; doc/design.md). The reference is damped alike.
    wp.damping = c.damping;
    const double                   w = c.w;
    const Point<2>                 o(c.offset, 0.);
    FunctionFromFunctionObjects<2> u0(
      {[w, o](const Point<2> &x) { return (x[0] - o[0]) / w * std::exp(-(x - o).norm_square() / (w * w)); },
       [w, o](const Point<2> &x) { return (x[1] - o[1]) / w * std::exp(-(x - o).norm_square() / (w * w)); }});
    pd.setup(BallDomain<2>(Point<2>(), radius), lp, linear_model(), wp, tr, prm, u0);
  }

  ElasticRunHistory
  run_case(const Case &c, const double radius, const ElasticTruncation tr, const WaveAbcParameters &prm,
           const MPI_Comm comm = MPI_COMM_WORLD)
  {
    PdUnboundedElastic pd(comm);
    setup_case(pd, c, radius, tr, prm);
    const double R = c.R, delta = c.delta;
    return run_elastic_waves(pd, c.T, c.n_samples,
                             [R, delta](const Point<2> &x) { return x.norm() < R - delta - 1e-9; });
  }

  /** The PML of the elastic near field: sigma_max, width w, exponent p. */
  WaveAbcParameters
  pml_parameters(const double sigma_max, const double w, const double p)
  {
    WaveAbcParameters prm = abc_parameters();
    prm.method            = "pml";
    prm.pml_damping       = sigma_max;
    prm.pml_thickness     = w;
    prm.pml_exponent      = p;
    return prm;
  }

  /** The conventional first-order (Lysmer-type) ABC of the elastic near field. */
  WaveAbcParameters
  first_order_parameters()
  {
    WaveAbcParameters prm = abc_parameters();
    prm.method            = "first order";
    return prm;
  }
  /**
   * One-step spectral radius of the R = 7 disc (dx 1, delta 3 dx, linear
   * model) with @p prm and @p truncation; @p n_up: eigenvalues of modulus
   * > 1 + 1e-8.
   */
  double
  disc7_radius(const WaveAbcParameters &prm, const double damping, const double dt, const ElasticTruncation truncation,
               unsigned int &n_up, double *max_update_norm = nullptr)
  {
    LatticeParameters lp;
    lp.dx    = 1.;
    lp.delta = 3.;
    FunctionFromFunctionObjects<2> u0({[](const Point<2> &) { return 0.; }, [](const Point<2> &) { return 0.; }});
    ElasticWaveParameters          wp;
    wp.time_step = dt;
    wp.damping   = damping;
    PdUnboundedElastic pd(MPI_COMM_SELF);
    pd.setup(BallDomain<2>(Point<2>(), 7.), lp, linear_model(), wp, truncation, prm, u0);
    n_up = 0;
    const double r = pd.one_step_spectral_radius(4000, &n_up);
    if (max_update_norm)
      *max_update_norm = pd.absorbing_boundary().statistics().max_update_norm;
    return r;
  }



  /**
   * sum |u - u_ref|^2 / sum |u0|^2 over the compared region at the final
   * time (nodes matched by position: the lattices of both discs coincide).
   */
  double
  field_error(const ElasticRunHistory &h, const ElasticRunHistory &ref, const double w)
  {
    std::map<std::pair<long, long>, Tensor<1, 2>> u_ref;
    const auto key = [](const Point<2> &x) { return std::make_pair(std::lround(1e6 * x[0]), std::lround(1e6 * x[1])); };
    double     norm0 = 0.;
    for (const auto &s : ref.final_state)
      {
        u_ref[key(s.position)] = s.displacement;
        norm0 += std::exp(-2. * s.position.square() / (w * w)) * s.position.square() / (w * w);
      }
    if (h.final_state.size() != ref.final_state.size())
      check(false, "field_error: different compared node sets");
    double       diff    = 0.;
    unsigned int missing = 0;
    for (const auto &s : h.final_state)
      {
        const auto it = u_ref.find(key(s.position));
        if (it == u_ref.end())
          ++missing;
        else
          diff += (s.displacement - it->second).norm_square();
      }
    if (missing > 0)
      check(false, "field_error: " + std::to_string(missing) + " compared nodes not in the reference");
    return diff / norm0;
  }

  /**
   * Largest increase between samples, relative to the value at t = 0, of
   * the total energy or (@p verlet) of the energy Verlet conserves.
   */
  double
  max_energy_increase(const ElasticRunHistory &h, const bool verlet = false)
  {
    const auto &e      = verlet ? h.verlet : h.total;
    double      growth = -1.;
    for (unsigned int s = 1; s < e.size(); ++s)
      growth = std::max(growth, (e[s] - e[s - 1]) / e[0]);
    return growth;
  }

  /** |Pi - Pi_ref| / Pi_ref(0) at sample s. */
  double
  energy_error(const ElasticRunHistory &h, const ElasticRunHistory &ref, const unsigned int s)
  {
    return std::abs(h.energy(s) - ref.energy(s)) / ref.energy(0);
  }

  void
  unbounded_case(const Case &c, const double long_end)
  {
    Timer        timer;
    const auto   prm    = abc_parameters();
    const double cp     = std::sqrt(9. / 8.);
    // Rounded to whole dx so that both lattices coincide.
    const double radius = std::ceil(reference_radius(cp * 1.02, c.T, 3. * c.w, c.R, 2. * c.delta) / c.dx) * c.dx;
    const auto   ref    = run_case(c, radius, ElasticTruncation::free, prm);
    const auto   abc    = run_case(c, c.R, ElasticTruncation::absorbing, prm);
    const auto   free   = run_case(c, c.R, ElasticTruncation::free, prm);
    const auto   fixed  = run_case(c, c.R, ElasticTruncation::fixed, prm);
    const unsigned int last = c.n_samples;
    if (root())
      {
        std::cout << "    nodes: reference " << ref.n_nodes << ", truncated " << abc.n_nodes << " ("
                  << abc.n_layer_nodes << " absorbing); modes " << abc.stats.n_modes << ", clouds "
                  << abc.stats.min_cloud_size << ".." << abc.stats.max_cloud_size << ", cond "
                  << sci(abc.stats.max_condition_number) << ", max|V| " << sci(abc.stats.max_update_norm)
                  << ", thinned " << abc.stats.n_thinned << " (stride " << abc.stats.max_stride << ")\n";
        for (unsigned int s = 0; s <= last; ++s)
          std::cout << "    t = " << ref.times[s] << ": Pi_ref/Pi0 " << sci(ref.energy(s) / ref.energy(0))
                    << " |Pi-Pi_ref|/Pi0: ABC " << sci(energy_error(abc, ref, s)) << " free "
                    << sci(energy_error(free, ref, s)) << " fixed " << sci(energy_error(fixed, ref, s))
                    << "  total ABC/E0 " << sci(abc.total[s] / abc.total[0]) << std::endl;
      }
    check(abc.stats.max_condition_number <= prm.max_condition_number &&
            abc.stats.max_update_norm <= prm.max_update_norm,
          "guards hold: cond " + sci(abc.stats.max_condition_number) + ", max|V| " + sci(abc.stats.max_update_norm));
    const double e_abc = energy_error(abc, ref, last), e_free = energy_error(free, ref, last),
                 e_fixed = energy_error(fixed, ref, last);
    // (b) the energy left in the compared disc at T.
    // Measured 7.6e-4 (free 3.8e-2, fixed 1.2e-1); asserted with a 2.5x margin.
    check(e_abc < 2e-3, "ABC: |Pi - Pi_ref|/Pi_ref(0) at T = " + sci(e_abc) + " < 2e-3");
    check(10. * e_abc < e_free, "ABC at least 10x closer than the free truncation: " + sci(e_abc) + " vs " + sci(e_free));
    check(10. * e_abc < e_fixed, "ABC at least 10x closer than the fixed truncation: " + sci(e_abc) + " vs " + sci(e_fixed));
    // (c) the total energy of the truncated domain never increases between
    // samples (the damped continuous problem dissipates; the ABC must not
    // feed energy back).
    double growth = -1.;
    for (unsigned int s = 1; s <= last; ++s)
      growth = std::max(growth, (abc.total[s] - abc.total[s - 1]) / abc.total[0]);
    check(growth <= 0., "ABC: total energy non-increasing: max relative increase between samples " + sci(growth));
    check(abc.total[last] < 0.05 * abc.total[0], "ABC: at most 5% of the energy left at T (" + sci(abc.total[last] / abc.total[0]) + ")");
    if (long_end > 0.)
      {
        // Stability: continue the ABC run alone (no reference of that size).
        Case c2      = c;
        c2.T         = long_end;
        c2.n_samples = 20;
        const auto h = run_case(c2, c.R, ElasticTruncation::absorbing, prm);
        double     late_growth = -1.;
        for (unsigned int s = 1; s < h.times.size(); ++s)
          late_growth = std::max(late_growth, (h.total[s] - h.total[s - 1]) / h.total[0]);
        if (root())
          for (unsigned int s = 0; s < h.times.size(); ++s)
            std::cout << "    long run t = " << h.times[s] << ": total/E0 " << sci(h.total[s] / h.total[0]) << std::endl;
        check(late_growth <= 0., "long run to t = " + sci(long_end) + " (" + std::to_string(static_cast<unsigned int>(long_end / c.dt)) + " steps): energy non-increasing, max increase " + sci(late_growth));
      }
    if (root())
      std::cout << "    ABC share of the step time " << abc.abc_seconds / abc.step_seconds << ", "
                << timer.wall_time() << " s" << std::endl;
  }

  void
  unbounded()
  {
    unbounded_case(ci_case(), 0.);
  }

  // The full case: a larger disc and pulse compared with the reference to
  // T = 96, then the ABC run alone for 20,000 steps (stability, E16: 1e5 steps).
  void
  unbounded_long()
  {
    unbounded_case({32., 96., 5., 1., 3., 0.5, 24}, 10000.);
  }

  // (d) The ABC run on all ranks equals the run on each rank alone; so
  // do the PML run (its band rows and memories are owned) and the
  // first-order ABC run.
  void
  ranks()
  {
    Case c      = ci_case();
    c.T         = 24.;
    c.n_samples = 2;
    // "curved": the preset ElasticAbcLayers::curved_tikhonov (session 19).
    for (const std::string method : {"ebf", "pml", "first order", "curved"})
      {
        const bool        with_pml = method == "pml";
        const std::string name     = with_pml              ? "PML" :
                                     method == "ebf"       ? "EBF" :
                                     method == "curved"    ? "EBF curved_tikhonov" :
                                                             "first order";
        const auto        prm      = with_pml              ? pml_parameters(1., 6., 2.) :
                                     method == "ebf"       ? abc_parameters() :
                                     method == "curved"    ? ElasticAbcLayers::curved_tikhonov(c.dx, c.R) :
                                                             first_order_parameters();
        const double      radius = with_pml ? c.R + 3. : c.R;
        const auto        all    = run_case(c, radius, ElasticTruncation::absorbing, prm, MPI_COMM_WORLD);
        const auto        self   = run_case(c, radius, ElasticTruncation::absorbing, prm, MPI_COMM_SELF);
        check(all.final_state.size() == self.final_state.size() && !all.final_state.empty(), name + ": same nodes");
        double diff = 0., norm = 0.;
        for (unsigned int i = 0; i < all.final_state.size(); ++i)
          {
            diff = std::max(diff, (all.final_state[i].displacement - self.final_state[i].displacement).norm());
            norm = std::max(norm, self.final_state[i].displacement.norm());
          }
        check(diff <= 1e-12 * norm, name + ": u on " + std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)) +
                                       " ranks equals u on 1 rank: max |diff| / max |u| = " + sci(diff / norm));
        check_close(all.energy(2), self.energy(2), 1e-12, name + ": energy at T on all ranks vs 1 rank");
      }
  }

  /** max over the samples of |Pi - Pi_ref| / Pi_ref(0). */
  double
  max_energy_error(const ElasticRunHistory &h, const ElasticRunHistory &ref)
  {
    double e = 0.;
    for (unsigned int s = 0; s < h.times.size(); ++s)
      e = std::max(e, energy_error(h, ref, s));
    return e;
  }

  struct FirstOrderErrors
  {
    // max over the run of |Pi - Pi_ref|/Pi_ref(0), the field error at T.
    double e_ebf, e_fo, e_free, e_pml, f_ebf, f_fo, f_free, f_pml, fo_growth, fo_verlet_growth;
    // Largest increase of the EBF run's total energy between samples (/E0).
    double ebf_growth;
    // |Pi - Pi_ref|/Pi_ref(0) at T.
    double e_ebf_T, e_fo_T, e_free_T, e_pml_T;
  };

  /**
   * E16 with the EBF layer, the first-order ABC, the free truncation and
   * the PML (sigma_max 1, p 2, w = 6 from R - delta) against the free
   * reference disc.
   */
  FirstOrderErrors
  first_order_case(const Case &c, const WaveAbcParameters &ebf_prm = abc_parameters(),
                   const WaveAbcParameters &fo_prm = first_order_parameters())
  {
    Timer        timer;
    const double cp     = std::sqrt(9. / 8.);
    const double radius = std::ceil(reference_radius(cp * 1.02, c.T, 3. * c.w + c.offset, c.R, 2. * c.delta) / c.dx) * c.dx;
    const auto   ref    = run_case(c, radius, ElasticTruncation::free, abc_parameters());
    const auto   ebf    = run_case(c, c.R, ElasticTruncation::absorbing, ebf_prm);
    const auto   fo     = run_case(c, c.R, ElasticTruncation::absorbing, fo_prm);
    const auto   free   = run_case(c, c.R, ElasticTruncation::free, abc_parameters());
    const auto   pml    = run_case(c, c.R - c.delta + 6., ElasticTruncation::absorbing, pml_parameters(1., 6., 2.));
    FirstOrderErrors r;
    r.e_ebf            = max_energy_error(ebf, ref);
    r.e_fo             = max_energy_error(fo, ref);
    r.e_free           = max_energy_error(free, ref);
    r.e_pml            = max_energy_error(pml, ref);
    r.f_ebf            = field_error(ebf, ref, c.w);
    r.f_fo             = field_error(fo, ref, c.w);
    r.f_free           = field_error(free, ref, c.w);
    r.f_pml            = field_error(pml, ref, c.w);
    r.fo_growth        = max_energy_increase(fo);
    r.fo_verlet_growth = max_energy_increase(fo, true);
    r.ebf_growth       = max_energy_increase(ebf);
    const unsigned int last = c.n_samples;
    r.e_ebf_T          = energy_error(ebf, ref, last);
    r.e_fo_T           = energy_error(fo, ref, last);
    r.e_free_T         = energy_error(free, ref, last);
    r.e_pml_T          = energy_error(pml, ref, last);
    if (root())
      {
        std::cout << "    R = " << c.R << ", T = " << c.T << ", d = " << c.damping << ": first-order layer "
                  << fo.n_layer_nodes << " nodes, fit points " << fo.stats.min_cloud_size << ".."
                  << fo.stats.max_cloud_size << ", max |coefficient| " << sci(fo.stats.max_update_norm) << "\n";
        for (unsigned int s = 0; s < ref.times.size(); ++s)
          std::cout << "    t = " << ref.times[s] << ": |Pi-Pi_ref|/Pi0: EBF " << sci(energy_error(ebf, ref, s))
                    << " first order " << sci(energy_error(fo, ref, s)) << " free " << sci(energy_error(free, ref, s))
                    << " PML " << sci(energy_error(pml, ref, s)) << "  total FO/E0 " << sci(fo.total[s] / fo.total[0])
                    << std::endl;
        std::cout << "    max over the run |Pi - Pi_ref|/Pi0: EBF " << sci(r.e_ebf) << ", first order " << sci(r.e_fo)
                  << ", free " << sci(r.e_free) << ", PML " << sci(r.e_pml) << "; first order / EBF "
                  << r.e_fo / r.e_ebf << "\n    field error at T: EBF " << sci(r.f_ebf) << ", first order " << sci(r.f_fo)
                  << ", free " << sci(r.f_free) << ", PML " << sci(r.f_pml) << "; first order / EBF " << r.f_fo / r.f_ebf
                  << "\n    at T |Pi - Pi_ref|/Pi0: EBF " << sci(r.e_ebf_T) << ", first order " << sci(r.e_fo_T) << ", free "
                  << sci(r.e_free_T) << ", PML " << sci(r.e_pml_T) << "; first order / EBF " << r.e_fo_T / r.e_ebf_T
                  << "\n    first order: max energy increase between samples " << sci(r.fo_growth) << " (Verlet "
                  << sci(r.fo_verlet_growth) << "); " << timer.wall_time() << " s" << std::endl;
      }
    return r;
  }

  // The conventional first-order ABC as the baseline of the EBF layer
  // (issue 4; doc/design.md, session 18) on E16 at CI size.
  void
  first_order()
  {
    // (a) R = 16, pulse width 2.5 (the CI case of elastic_abc.unbounded).
    Case c      = ci_case();
    c.n_samples = 48;
    const auto r = first_order_case(c);
    // Measured (48 samples): max over the run EBF 2.59e-3, first order
    // 2.60e-2, free 6.22e-2; at T: energy EBF 7.6e-4, first order 2.07e-2,
    // free 3.78e-2; field EBF 2.74e-4, first order 5.81e-3, free 1.26e-2.
    // Sanity: the first-order ABC absorbs (measured 0.42x / 0.55x / 0.46x
    // of free; bound 0.7x).
    check(r.e_fo < 0.7 * r.e_free && r.fo_growth <= 0.,
          "R = 16, first order: max energy error " + sci(r.e_fo) + " < 0.7 x free " + sci(r.e_free) +
            ", total energy non-increasing (" + sci(r.fo_growth) + ")");
    check(r.f_fo < 0.7 * r.f_free,
          "R = 16, first order: field error at T " + sci(r.f_fo) + " < 0.7 x free " + sci(r.f_free));
    // The 10x at the end of the run (measured 27x energy, 21x
    // field: a 2x margin).
    const double e_fo_T = r.e_fo_T, e_ebf_T = r.e_ebf_T;
    check(10. * e_ebf_T < e_fo_T,
          "R = 16: EBF at least 10x closer than first order, energy at T: " + sci(e_ebf_T) + " vs " + sci(e_fo_T));
    check(10. * r.f_ebf < r.f_fo,
          "R = 16: EBF at least 10x closer than first order, field at T: " + sci(r.f_ebf) + " vs " + sci(r.f_fo));
    // Over the whole run the ratio is only 10.0x (the EBF's worst sample,
    // t = 19, is the first arrival at the layer): asserted 8x, not 10x.
    check(8. * r.e_ebf < r.e_fo,
          "R = 16: max energy error over the run EBF " + sci(r.e_ebf) + " at least 8x below first order " + sci(r.e_fo));

    // (b) R = 32, pulse width 5 (the case of elastic_abc.unbounded_long to
    // T = 96): long waves at normal incidence, where the Lysmer condition
    // is nearly exact. Measured: max over the run EBF 5.26e-3, first order
    // 4.81e-3 (first order better), free 1.32e-1; at T energy EBF 1.02e-4,
    // first order 2.97e-4 (2.9x), field EBF 3.80e-5, first order 5.46e-5
    // (1.44x). With the default EBF setting the 10x is NOT reached
    // here (doc/design.md, session 18; see (b') for a matched setting).
    const auto r32 = first_order_case({32., 96., 5., 1., 3., 0.5, 48});
    check(10. * r32.e_fo < r32.e_free && 10. * r32.f_fo < r32.f_free && r32.fo_growth <= 0.,
          "R = 32, first order: at least 10x below free (energy " + sci(r32.e_fo) + " vs " + sci(r32.e_free) +
            ", field " + sci(r32.f_fo) + " vs " + sci(r32.f_free) + "), energy non-increasing");
    // Ordering at T as measured, bounds at about half the measured ratios
    // (2.9x -> 1.5x, 1.44x -> 1.2x); over the run EBF within 1.5x of first
    // order (measured 1.09x).
    check(1.5 * r32.e_ebf_T < r32.e_fo_T && 1.2 * r32.f_ebf < r32.f_fo && r32.e_ebf < 1.5 * r32.e_fo,
          "R = 32: EBF closer than first order at T (energy " + sci(r32.e_ebf_T) + " vs " + sci(r32.e_fo_T) +
            ", field " + sci(r32.f_ebf) + " vs " + sci(r32.f_fo) + "), over the run within 1.5x (" +
            sci(r32.e_ebf) + " vs " + sci(r32.e_fo) + ")");

    // (b') The same R = 32 case with the EBF modes matched to the longer
    // pulse (Delta k 0.5 instead of 1, Delta k w = 2.5 as for R = 16) and a
    // truncated pseudo-inverse (singular values below 3e-2 sigma_max
    // dropped; max|V| 0.29, cond 33): measured at T energy 8.46e-6 (35x
    // below first order), field 1.93e-6 (28x), over the run 5.62e-4
    // (8.6x). Asserted: 10x at T (a 2.8x margin), 5x over the run. Not
    // the default: on R = 16 this setting is only 6.5x (doc/design.md).
    WaveAbcParameters matched        = abc_parameters();
    matched.wave_number_range        = 0.5;
    matched.pseudo_inverse_tolerance = 3e-2;
    const auto m32 = first_order_case({32., 96., 5., 1., 3., 0.5, 48}, matched);
    check(10. * m32.e_ebf_T < m32.e_fo_T && 10. * m32.f_ebf < m32.f_fo && 5. * m32.e_ebf < m32.e_fo,
          "R = 32, EBF Delta k 0.5, truncation 3e-2: at least 10x closer than first order at T (energy " +
            sci(m32.e_ebf_T) + " vs " + sci(m32.e_fo_T) + ", field " + sci(m32.f_ebf) + " vs " + sci(m32.f_fo) +
            "), 5x over the run (" + sci(m32.e_ebf) + " vs " + sci(m32.e_fo) + ")");

    // (c) Stability of the first-order layer: one-step radius of the R = 7
    // disc (as spectral_radius for the EBF layer: 1 + 1.5e-2 at d = 0,
    // 1 + 5.0e-3 at d = 0.02). Measured 1 + 3.0e-3 (46 eigenvalues outside)
    // at d = 0, 1 - 7.0e-3 at d = 0.02.
    std::map<double, double> radius;
    for (const double d : {0., 0.02})
      {
        unsigned int n_up = 0;
        radius[d]         = disc7_radius(first_order_parameters(), d, 0.5, ElasticTruncation::absorbing, n_up);
        if (root())
          std::cout << "    first order, R = 7, d = " << d << ": spectral radius - 1 = " << sci(radius[d] - 1.) << " ("
                    << n_up << " eigenvalues of modulus > 1 + 1e-8)" << std::endl;
      }
    // 1e-12: round-off of the dense eigenproblem.
    check(radius[0.02] <= 1. + 1e-12, "first order, d = 0.02: one-step radius <= 1 (1 + " + sci(radius[0.02] - 1.) + ")");
    // Undamped it is unstable, as the EBF layer, but 5x more slowly
    // (asserted: between 1 + 1e-3 and 1 + 1e-2).
    check(radius[0.] > 1. + 1e-3 && radius[0.] < 1. + 1e-2,
          "first order, d = 0: one-step radius 1 + " + sci(radius[0.] - 1.) + " in (1 + 1e-3, 1 + 1e-2)");
  }

  // The preset ElasticAbcLayers::curved_tikhonov (doc/design.md, session
  // 19): one EBF setting >= 10x closer to the reference than the
  // first-order ABC on both E16 sizes, and long-run stable.
  void
  curved_tikhonov()
  {
    Timer timer;
    // (a) R = 16, w 2.5, (b) R = 32, w 5 (the source's size) and (b') R = 32
    // with the pulse at (16, 0) (oblique incidence), 48 samples. Measured
    // FO/EBF over the run, energy at T, field at T: R = 16 66x, 336x, 214x;
    // R = 32 25x, 865x, 571x; R = 32 off centre 19x, 83x, 38x (session 19;
    // the default abc_parameters() has 0.91x, 2.9x, 1.44x on R = 32 and
    // 0.81x, 1.09x, 0.56x off centre). Asserted: the 10x at T in
    // energy and field (margins >= 3.7x) and over the run (margin >= 1.9x).
    for (const Case &c : {Case{16., 48., 2.5, 1., 3., 0.5, 48}, Case{32., 96., 5., 1., 3., 0.5, 48},
                         Case{32., 96., 5., 1., 3., 0.5, 48, 0.02, 16.}})
      {
        const auto r = first_order_case(c, ElasticAbcLayers::curved_tikhonov(c.dx, c.R));
        const std::string name = "curved_tikhonov, R = " + sci(c.R) + ", pulse at x = " + sci(c.offset) + ": ";
        check(10. * r.e_ebf_T < r.e_fo_T,
              name + "EBF at least 10x closer than first order, energy at T: " + sci(r.e_ebf_T) + " vs " + sci(r.e_fo_T));
        check(10. * r.f_ebf < r.f_fo,
              name + "EBF at least 10x closer than first order, field at T: " + sci(r.f_ebf) + " vs " + sci(r.f_fo));
        check(10. * r.e_ebf < r.e_fo,
              name + "EBF at least 10x closer than first order over the run: " + sci(r.e_ebf) + " vs " + sci(r.e_fo));
        // Damped runs: the total energy of the near field falls between samples.
        check(r.ebf_growth <= 0., name + "total energy non-increasing between samples (" + sci(r.ebf_growth) + ")");
      }
    // Bad settings of the session-19 options name their parameter.
    const auto fails_naming = [](const WaveAbcParameters &bad, const std::string &name) {
      LatticeParameters lp;
      lp.dx    = 1.;
      lp.delta = 3.;
      ElasticWaveParameters wp;
      wp.time_step = 0.5;
      FunctionFromFunctionObjects<2> u0({[](const Point<2> &) { return 0.; }, [](const Point<2> &) { return 0.; }});
      PdUnboundedElastic pd(MPI_COMM_SELF);
      try
        {
          pd.setup(BallDomain<2>(Point<2>(), 7.), lp, linear_model(), wp, ElasticTruncation::absorbing, bad, u0);
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what()).find(name) != std::string::npos;
        }
      return false;
    };
    WaveAbcParameters bad = ElasticAbcLayers::curved_tikhonov(1., 7.);
    bad.fit_form          = "slope";
    check(fails_naming(bad, "Fit form"), "Fit form = slope: ParameterError naming 'Fit form'");
    bad                          = ElasticAbcLayers::curved_tikhonov(1., 7.);
    bad.pseudo_inverse_tolerance = 0.;
    check(fails_naming(bad, "Pseudo-inverse regularization"),
          "tikhonov without a tolerance: ParameterError naming 'Pseudo-inverse regularization'");
    // Curvature radius 2 < the cloud radius delta = 3.
    check(fails_naming(ElasticAbcLayers::curved_tikhonov(1., 2.), "Curvature radius"),
          "Curvature radius 2 <= cloud radius 3: ParameterError naming 'Curvature radius'");

    // (c) One-step radius of the R = 7 disc at d = 0.02 (curvature 7):
    // measured 1 - 6.0e-3 (the default: 1 + 5.0e-3); 1e-12: round-off of
    // the dense eigenproblem.
    unsigned int n_up = 0;
    double       vmax = 0.;
    const double r7   = disc7_radius(ElasticAbcLayers::curved_tikhonov(1., 7.), 0.02, 0.5, ElasticTruncation::absorbing,
                                     n_up, &vmax);
    if (root())
      std::cout << "    R = 7, d = 0.02: spectral radius - 1 = " << sci(r7 - 1.) << " (" << n_up
                << " eigenvalues of modulus > 1 + 1e-8), max|V| " << sci(vmax) << std::endl;
    check(r7 <= 1. + 1e-12, "curved_tikhonov, R = 7, d = 0.02: one-step radius <= 1 (1 + " + sci(r7 - 1.) + ")");
    // (d) R = 32 to t = 5000 (10,000 steps, 500 samples = every 20 steps):
    // measured decay to 1.6e-82 E0 without a rise between samples, also
    // every 10 steps (per step: rises at 356 steps from t = 1876 on, at the
    // 1e-41 E0 level); the default layer ends at 3.4e-33 E0. Asserted:
    // non-increasing at every sample and below 1e-40 E0 at the end (42
    // orders of margin; a round-off-level floor such as that of session
    // 18's Delta k 0.5 setting, 4e-37 .. 7.8e-37 E0, would fail it).
    Case c      = {32., 5000., 5., 1., 3., 0.5, 500};
    const auto h = run_case(c, c.R, ElasticTruncation::absorbing, ElasticAbcLayers::curved_tikhonov(c.dx, c.R));
    const double growth = max_energy_increase(h);
    if (root())
      std::cout << "    R = 32 to t = 5000: E/E0 " << sci(h.total.back() / h.total[0])
                << ", max increase between samples " << sci(growth) << "; " << timer.wall_time() << " s" << std::endl;
    check(growth <= 0. && h.total.back() < 1e-40 * h.total[0],
          "curved_tikhonov, R = 32 long run: energy non-increasing (" + sci(growth) + ") and E(5000) " +
            sci(h.total.back() / h.total[0]) + " E0 < 1e-40 E0");
  }

  // Exploration (not in CI): E16_FO_SCAN="<mode> [key=value ...]" with the
  // EBF keys of with_wave_settings (tests/wave_settings.h: dk, nk, nphi,
  // dphi, cone, maxv, tol, ...) on top of abc_parameters();
  // mode 16, 32 (E16 sizes), d0 (16 undamped), 16o / 32o (pulse at (R/2, 0)),
  // 16l / 32l (first order with the continuum speeds):
  // the comparison of first_order_case() with that EBF setting;
  // keys w=, T=, dt=: pulse width, final time, time step; ns=: samples of long16 / long32;
  // key "preset": on top of ElasticAbcLayers::curved_tikhonov (session 19);
  // sr: one-step radius of the R = 7 disc (first order and that EBF,
  // d = 0 and 0.02); sre: the EBF's alone at d = 0.02 (with " d0" also
  // d = 0); long16 / long32: that EBF run alone to t = 5000.
  void
  first_order_scan()
  {
    const char       *env   = std::getenv("E16_FO_SCAN");
    const std::string which = env ? env : "32";
    std::istringstream in(which);
    std::string        size;
    in >> size;
    std::string rest;
    std::getline(in, rest);
    // Key "preset": start from Abc::ElasticAbcLayers::curved_tikhonov
    // (curvature radius: 7 for sr / sre, else the case's R) instead of
    // abc_parameters().
    const auto   kv          = PeriDEALTests::key_values(rest);
    const double base_radius = size.rfind("sr", 0) == 0 ? 7. : size.find("32") != std::string::npos ? 32. : 16.;
    const WaveAbcParameters prm = PeriDEALTests::with_wave_settings(
      kv.count("preset") ? ElasticAbcLayers::curved_tikhonov(1., base_radius) : abc_parameters(), kv);
    try
      {
        if (size == "sre")
          {
            // The EBF layer alone at d = 0.02 (d0: also d = 0).
            for (const double d : {0.02, 0.})
              {
                if (d == 0. && which.find(" d0") == std::string::npos)
                  continue;
                unsigned int n_up = 0;
                double       vmax = 0.;
                const double r = disc7_radius(prm, d, 0.5, ElasticTruncation::absorbing, n_up, &vmax);
                if (root())
                  std::cout << "SCAN " << which << ": EBF, R = 7, d = " << d << ": spectral radius - 1 = "
                            << sci(r - 1.) << " (" << n_up << " eigenvalues of modulus > 1 + 1e-8), max|V| "
                            << sci(vmax) << std::endl;
              }
            return;
          }
        if (size == "sr")
          {
            LatticeParameters lp;
            lp.dx    = 1.;
            lp.delta = 3.;
            // The long-wave speeds the first-order ABC uses (discrete relation).
            const auto rel = ElasticDispersion::discrete(linear_model(), lp, 1., 0.);
            for (const double phi : {0., M_PI / 8., M_PI / 4.})
              {
                const auto md = rel.modes(1e-4, unit(phi));
                if (root())
                  std::cout << "SCAN sr: phi " << phi << ": c_P^2 " << std::norm(md[0].frequency) / 1e-8 << ", c_S^2 "
                            << std::norm(md[1].frequency) / 1e-8 << " (continuum 9/8, 3/8)" << std::endl;
              }
            for (const bool fo : {true, false})
              for (const double d : {0., 0.02})
                {
                  unsigned int n_up = 0;
                  double       vmax = 0.;
                  const double r    = disc7_radius(fo ? first_order_parameters() : prm, d, 0.5,
                                                   ElasticTruncation::absorbing, n_up, &vmax);
                  if (root())
                    std::cout << "SCAN " << which << ": " << (fo ? "first order" : "EBF") << ", R = 7, d = " << d
                              << ": spectral radius - 1 = " << sci(r - 1.) << " (" << n_up
                              << " eigenvalues of modulus > 1 + 1e-8), max|V| " << sci(vmax) << std::endl;
                }
            return;
          }
        Case c = size.find("32") != std::string::npos ? Case{32., 96., 5., 1., 3., 0.5, 48} : ci_case();
        if (size == "d0")
          c.damping = 0.;
        // Keys w, T: another pulse width / final time (robustness of a setting).
        if (kv.count("w"))
          c.w = std::stod(kv.at("w"));
        if (kv.count("T"))
          c.T = std::stod(kv.at("T"));
        if (kv.count("dt"))
          c.dt = std::stod(kv.at("dt"));
        c.n_samples = 48;
        if (size.rfind("long", 0) == 0)
          {
            c.T         = 5000.;
            // Key ns=: number of samples (10000: every step).
            c.n_samples  = kv.count("ns") ? std::stoi(kv.at("ns")) : 50;
            const auto h = run_case(c, c.R, ElasticTruncation::absorbing, prm);
            if (root())
              {
                // Samples after which the total / Verlet energy rose.
                unsigned int n_rise = 0, n_rise_verlet = 0, first_rise = 0;
                for (unsigned int s = 1; s < h.times.size(); ++s)
                  {
                    if (h.total[s] > h.total[s - 1] && n_rise++ == 0)
                      first_rise = s;
                    n_rise_verlet += h.verlet[s] > h.verlet[s - 1] ? 1 : 0;
                  }
                std::cout << "SCAN " << which << ": rises between samples: total " << n_rise << " (first at t = "
                          << (n_rise ? h.times[first_rise] : 0.) << "), Verlet " << n_rise_verlet
                          << ", max Verlet increase " << sci(max_energy_increase(h, true)) << std::endl;
                for (unsigned int s = 0; s < h.times.size(); s += h.times.size() / 10)
                  std::cout << "    t = " << h.times[s] << ": total/E0 " << sci(h.total[s] / h.total[0]) << std::endl;
                std::cout << "SCAN " << which << ": max|V| " << sci(h.stats.max_update_norm) << ", cond "
                          << sci(h.stats.max_condition_number) << ", thinned " << h.stats.n_thinned << ", E(5000)/E0 "
                          << sci(h.total.back() / h.total[0]) << ", max increase between samples "
                          << sci(max_energy_increase(h)) << std::endl;
              }
            return;
          }
        // "16o", "32o": the pulse at (R/2, 0).
        if (size.back() == 'o')
          c.offset = c.R / 2.;
        // "16l", "32l": the first-order ABC with the continuum (local) speeds.
        WaveAbcParameters fo_prm = first_order_parameters();
        if (size.back() == 'l')
          fo_prm.dispersion = "local";
        const auto r = first_order_case(c, prm, fo_prm);
        if (root())
          std::cout << "SCAN " << which << ": EBF max " << sci(r.e_ebf) << " T " << sci(r.e_ebf_T) << " field "
                    << sci(r.f_ebf) << " | FO/EBF max " << r.e_fo / r.e_ebf << " T " << r.e_fo_T / r.e_ebf_T << " field "
                    << r.f_fo / r.f_ebf << std::endl;
      }
    catch (const std::exception &e)
      {
        if (root())
          std::cout << "SCAN " << which << ": " << e.what() << std::endl;
      }
  }

  // The coupled near-field/ABC recursion: spectral radius of the one-step
  // map of a small disc (R = 7) with and without the damping d = 0.02.
  void
  spectral_radius()
  {
    std::map<std::pair<double, double>, double> rho;
    for (const auto &[d, dt] : {std::make_pair(0., 0.5), std::make_pair(0.02, 0.5), std::make_pair(0., 0.25)})
      {
        unsigned int n_up = 0;
        rho[{d, dt}]      = disc7_radius(abc_parameters(), d, dt, ElasticTruncation::absorbing, n_up);
        if (root())
          std::cout << "    d = " << d << ", dt = " << dt << ": spectral radius - 1 = " << sci(rho[{d, dt}] - 1.) << " ("
                    << n_up << " eigenvalues of modulus > 1 + 1e-8)" << std::endl;
      }
    // Measured (R = 7): d = 0 gives 1 + 1.5e-2 (44 eigenvalues outside the
    // unit circle), d = 0.02 gives 1 + 5.0e-3 (4): the damping reduces but
    // does not remove the instability of this small disc (a run of it
    // decays to 2e-18 E0 by t = 1500 and then grows from round-off), while
    // the R = 16 and R = 32 runs decay for 10,000 and 20,000 steps. Asserted
    // as measured, not as the source's claim of unconditional stability.
    const double r0 = rho[{0., 0.5}], r2 = rho[{0.02, 0.5}], r0h = rho[{0., 0.25}];
    check(r0 > 1. + 1e-3, "d = 0: the coupled recursion is unstable (spectral radius " + sci(r0) + ")");
    check(r2 - 1. < 0.5 * (r0 - 1.), "d = 0.02 reduces the growth rate at least 2x: " + sci(r2 - 1.) + " vs " + sci(r0 - 1.));
    // As for the scalar waves (wave_abc.semi_discrete): the growth rate per
    // unit time (rho - 1)/dt hardly changes when dt is halved (measured
    // 3.04e-2 vs 2.65e-2), so the growth belongs to the semi-discrete
    // coupled system (near field + layer extrapolation), not to the time
    // levels of the recursion (a level shift would halve the rate).
    const double rate = (r0 - 1.) / 0.5, rate_h = (r0h - 1.) / 0.25;
    check(rate_h > 0.6 * rate && rate_h < 1.5 * rate,
          "d = 0: growth rate per unit time independent of dt within the bounds (0.6, 1.5): " + sci(rate) + " (dt = 0.5) vs " + sci(rate_h) + " (dt = 0.25)");
  }


  // The energy-stable damping sponge (doc/design.md, session 7) on the
  // elastic near field: nothing overwritten, damping d + sigma(x) per node,
  // sigma = sigma_max min(1, (w - s)/w)^p at depth s. The linearized
  // bond-based force is symmetric, so the argument of the scalar case
  // (wave_abc.sponge) applies: one-step radius <= 1 for any sigma >= 0,
  // here checked without the physical damping (d = 0), where the EBF layer
  // has 1 + 1.5e-2 (test spectral_radius).
  void
  sponge()
  {
    WaveAbcParameters prm  = abc_parameters();
    prm.sponge_thickness   = 3.;
    prm.sponge_damping     = 0.5;
    prm.sponge_exponent    = 2.;
    {
      unsigned int n_up = 0;
      const double r    = disc7_radius(prm, 0., 0.5, ElasticTruncation::sponge, n_up);
      if (root())
        std::cout << "    sponge, R = 7, d = 0: spectral radius - 1 = " << sci(r - 1.) << " (" << n_up << ")" << std::endl;
      // 1e-12: round-off of the dense eigenproblem (the rigid motions have
      // eigenvalue 1).
      check(r <= 1. + 1e-12 && n_up == 0, "sponge, d = 0: one-step spectral radius <= 1 (" + sci(r - 1.) + ")");
    }
    const Case   c      = ci_case();
    const double cp     = std::sqrt(9. / 8.);
    const double radius = std::ceil(reference_radius(cp * 1.02, c.T, 3. * c.w, c.R, 2. * c.delta) / c.dx) * c.dx;
    const auto   ref    = run_case(c, radius, ElasticTruncation::free, prm);
    const auto   free   = run_case(c, c.R, ElasticTruncation::free, prm);
    const auto   abc    = run_case(c, c.R, ElasticTruncation::absorbing, abc_parameters());
    const unsigned int last = c.n_samples;
    // Scanned (w = delta = 3, |Pi - Pi_ref|/Pi0 at T): (sigma_max, p) =
    // (0.25, 2) 4.5e-3, (0.5, 2) 2.1e-3, (1, 2) 3.0e-3, (0.5, 4) 5.4e-3,
    // (1, 4) 5.2e-3, (2, 4) 6.8e-3; the EBF layer 7.6e-4, free 3.8e-2.
    const auto   h      = run_case(c, c.R, ElasticTruncation::sponge, prm);
    double       growth = -1.;
    for (unsigned int s = 1; s <= last; ++s)
      growth = std::max(growth, (h.total[s] - h.total[s - 1]) / h.total[0]);
    const double e_sponge = energy_error(h, ref, last), e_abc = energy_error(abc, ref, last),
                 e_free = energy_error(free, ref, last);
    if (root())
      std::cout << "    sponge sigma_max 0.5, p 2: |Pi - Pi_ref|/Pi0 at T " << sci(e_sponge) << " (EBF " << sci(e_abc) << ", free "
                << sci(e_free) << "), max energy increase between samples " << sci(growth) << std::endl;
    check(growth <= 0., "sponge: total energy non-increasing between samples (" + sci(growth) + ")");
    // Measured 2.1e-3 (2x margin); NOT as accurate as the EBF layer (7.6e-4).
    check(e_sponge < 4.3e-3 && 10. * e_sponge < e_free,
          "sponge: |Pi - Pi_ref|/Pi0 at T = " + sci(e_sponge) + " < 4.3e-3 and 10x below free " + sci(e_free));
  }

  // The PML of the elastic near field (doc/design.md, session 9) on E16
  // (CI size): sigma_max 1, p 2, w = 2 delta = 6 from R - delta (where the
  // EBF layer begins) to R + 3, so 3 dx of extra nodes outside R.
  void
  pml()
  {
    const Case   c      = ci_case();
    const double w      = 6., start = c.R - c.delta;
    const auto   prm    = pml_parameters(1., w, 2.);
    const double cp     = std::sqrt(9. / 8.);
    const double radius = std::ceil(reference_radius(cp * 1.02, c.T, 3. * c.w, c.R, 2. * c.delta) / c.dx) * c.dx;
    const auto   ref    = run_case(c, radius, ElasticTruncation::free, abc_parameters());
    const auto   free   = run_case(c, c.R, ElasticTruncation::free, abc_parameters());
    // The free truncation with as many nodes as the PML run.
    const auto         free_big = run_case(c, start + w, ElasticTruncation::free, abc_parameters());
    const auto         ebf      = run_case(c, c.R, ElasticTruncation::absorbing, abc_parameters());
    const auto         h        = run_case(c, start + w, ElasticTruncation::absorbing, prm);
    const unsigned int last     = c.n_samples;
    const double e_pml = energy_error(h, ref, last), e_free = energy_error(free, ref, last),
                 e_big = energy_error(free_big, ref, last), e_ebf = energy_error(ebf, ref, last);
    const double f_pml = field_error(h, ref, c.w), f_free = field_error(free, ref, c.w),
                 f_big = field_error(free_big, ref, c.w), f_ebf = field_error(ebf, ref, c.w);
    if (root())
      std::cout << "    nodes: PML " << h.n_nodes << " (" << h.n_layer_nodes << " in the PML), EBF/free " << ebf.n_nodes
                << ", free " << free_big.n_nodes << "\n    |Pi - Pi_ref|/Pi0 at T: PML " << sci(e_pml) << ", EBF "
                << sci(e_ebf) << ", free " << sci(e_free) << ", free R + 3 " << sci(e_big)
                << "\n    sum |u - u_ref|^2/sum |u0|^2 at T: PML " << sci(f_pml) << ", EBF " << sci(f_ebf) << ", free "
                << sci(f_free) << ", free R + 3 " << sci(f_big) << std::endl;
    // Measured 2.56e-4 (EBF 7.6e-4, free 3.78e-2, free R + 3 3.4e-2?) and
    // field 5.1e-5 (EBF 2.7e-4, free 1.26e-2); bounds with a 2x margin.
    check(e_pml < 5.2e-4, "PML: |Pi - Pi_ref|/Pi0 at T = " + sci(e_pml) + " < 5.2e-4");
    check(f_pml < 1.1e-4, "PML: field error at T = " + sci(f_pml) + " < 1.1e-4");
    check(10. * e_pml < std::min(e_free, e_big) && 10. * f_pml < std::min(f_free, f_big),
          "PML at least 10x closer to the reference than the free truncations (R and R + 3): energy " + sci(e_pml) +
            " vs " + sci(std::min(e_free, e_big)) + ", field " + sci(f_pml) + " vs " + sci(std::min(f_free, f_big)));
    check(max_energy_increase(h) <= 0. && max_energy_increase(h, true) <= 0.,
          "PML: total and Verlet energy non-increasing between samples (" + sci(max_energy_increase(h)) + ", " +
            sci(max_energy_increase(h, true)) + ")");

    // The same without damping (d = 0), where the EBF layer grows (one-step
    // radius 1.015) and the comparison above needed d = 0.02.
    Case c0    = c;
    c0.damping = 0.;
    const auto ref0 = run_case(c0, radius, ElasticTruncation::free, abc_parameters());
    const auto free0 = run_case(c0, c.R, ElasticTruncation::free, abc_parameters());
    const auto h0    = run_case(c0, start + w, ElasticTruncation::absorbing, prm);
    const double e0_pml = energy_error(h0, ref0, last), e0_free = energy_error(free0, ref0, last);
    const double f0_pml = field_error(h0, ref0, c.w), f0_free = field_error(free0, ref0, c.w);
    // The diagnostic: the undamped free disc keeps its Verlet energy.
    double drift = 0.;
    for (unsigned int k = 0; k <= last; ++k)
      drift = std::max(drift, std::abs(free0.verlet[k] / free0.verlet[0] - 1.));
    if (root())
      std::cout << "    d = 0: |Pi - Pi_ref|/Pi0 at T: PML " << sci(e0_pml) << ", free " << sci(e0_free) << "; field PML "
                << sci(f0_pml) << ", free " << sci(f0_free) << "; free disc Verlet energy drift " << sci(drift) << std::endl;
    if (root())
      for (unsigned int k = 0; k <= last; ++k)
        std::cout << "    d = 0, PML: t " << h0.times[k] << " E/E0 " << sci(h0.total[k] / h0.total[0]) << " Verlet "
                  << sci(h0.verlet[k] / h0.verlet[0]) << " (" << sci(k > 0 ? (h0.verlet[k] - h0.verlet[k - 1]) / h0.verlet[0] : 0.) << ")" << std::endl;
    check(drift < 1e-12, "d = 0, free disc: Verlet energy conserved to " + sci(drift) + " < 1e-12");
    // Measured 1.78e-3 (free 0.255) and field 2.75e-4 (free 8.1e-2).
    check(e0_pml < 3.6e-3 && 10. * e0_pml < e0_free && 10. * f0_pml < f0_free,
          "PML, d = 0: energy " + sci(e0_pml) + " < 3.6e-3 and >= 10x below free " + sci(e0_free) + ", field " +
            sci(f0_pml) + " >= 10x below free " + sci(f0_free));
    // A PML is not dissipative: while the front enters the layer (t 4..8)
    // the Verlet energy rises by 4.2e-5 E0 (measured); then it decreases
    // at every sample. Asserted: rise < 1e-4 E0, none from t = 12 on.
    double late = -1.;
    for (unsigned int k = 4; k <= last; ++k)
      late = std::max(late, (h0.verlet[k] - h0.verlet[k - 1]) / h0.verlet[0]);
    check(max_energy_increase(h0, true) < 1e-4 && late <= 0.,
          "PML, d = 0: Verlet energy rise " + sci(max_energy_increase(h0, true)) +
            " E0 < 1e-4 E0 (front entering the layer), non-increasing from t = 12 (" + sci(late) + ")");

    // Undamped (d = 0, where the EBF layer's one-step radius is 1.015): a
    // disc of radius 11 (PML from 5) for 10,000 steps, the total energy
    // sampled every 500 steps.
    Case small      = c;
    small.damping   = 0.;
    small.T         = 5000.;
    small.n_samples = 20;
    small.R         = 5.;
    const auto s    = run_case(small, 5. + w, ElasticTruncation::absorbing, prm);
    if (root())
      for (unsigned int k = 0; k < s.times.size(); ++k)
        std::cout << "    d = 0, disc 11: t " << s.times[k] << " E/E0 " << sci(s.total[k] / s.total[0]) << std::endl;
    check(max_energy_increase(s) <= 0. && max_energy_increase(s, true) <= 0.,
          "PML, d = 0: total and Verlet energy non-increasing over 10,000 steps (max increase " +
            sci(max_energy_increase(s)) + ", " + sci(max_energy_increase(s, true)) + ")");
    check(s.total.back() < 1e-6 * s.total[0], "PML, d = 0: E(t = 5000) = " + sci(s.total.back() / s.total[0]) + " E0 < 1e-6 E0");

    // Bad PML parameters name themselves.
    const auto fails_naming = [&](const WaveAbcParameters &bad, const std::string &name) {
      try
        {
          run_case(small, 5. + w, ElasticTruncation::absorbing, bad);
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what()).find(name) != std::string::npos;
        }
      return false;
    };
    check(fails_naming(pml_parameters(0., w, 2.), "PML damping"), "PML damping 0: ParameterError naming 'PML damping'");
    check(fails_naming(pml_parameters(1., 1.5, 2.), "PML thickness"), "PML thickness 1.5 dx: ParameterError naming 'PML thickness'");
    check(fails_naming(pml_parameters(1., w, 0.5), "PML exponent"), "PML exponent 0.5: ParameterError naming 'PML exponent'");
    // "first order" is a method of the elastic near field since session 18
    // (elastic_abc.first_order); an unknown method is still refused.
    WaveAbcParameters unknown = abc_parameters();
    unknown.method            = "second order";
    check(fails_naming(unknown, "Method"), "Method = second order (elastic): ParameterError naming 'Method'");
    // A physical free surface (keep filter) or the nonlinear model: refused.
    const auto setup_fails_naming = [&](const bool with_keep, const std::string &name) {
      LatticeParameters lp;
      lp.dx    = 1.;
      lp.delta = 3.;
      ElasticWaveParameters wp;
      wp.time_step                        = 0.5;
      BondBasedModelParameters       model = linear_model();
      FunctionFromFunctionObjects<2> u0({[](const Point<2> &) { return 0.; }, [](const Point<2> &) { return 0.; }});
      model.linearized = with_keep;
      PdUnboundedElastic pd(MPI_COMM_SELF);
      try
        {
          pd.setup(BallDomain<2>(Point<2>(), 11.), lp, model, wp, ElasticTruncation::pml, prm, u0,
                   with_keep ? [](const Point<2> &, const Tensor<1, 2> &n) { return n[1] < 0.5; } :
                               std::function<bool(const Point<2> &, const Tensor<1, 2> &)>());
        }
      catch (const ParameterError &e)
        {
          return std::string(e.what()).find(name) != std::string::npos;
        }
      return false;
    };
    check(setup_fails_naming(true, "Method"), "PML with a keep filter: ParameterError naming 'Method'");
    check(setup_fails_naming(false, "Linearized"), "PML with the nonlinear model: ParameterError naming 'Linearized'");
  }

  // One-step spectral radius of the undamped PML near field (a disc small
  // enough for the dense map with one state entry per band bond: radius
  // 5.5, w 2; ~25 s CPU per map, so long).
  void
  pml_spectral_radius()
  {
    LatticeParameters lp;
    lp.dx    = 1.;
    lp.delta = 3.;
    FunctionFromFunctionObjects<2> u0({[](const Point<2> &) { return 0.; }, [](const Point<2> &) { return 0.; }});
    ElasticWaveParameters          wp;
    wp.time_step = 0.5;
    const double radius = std::getenv("PML_RADIUS") ? std::atof(std::getenv("PML_RADIUS")) : 5.5;
    const double w      = std::getenv("PML_W") ? std::atof(std::getenv("PML_W")) : 2.;
    std::map<double, double> rho;
    for (const double d : {0., 0.02})
      {
        wp.damping = d;
        PdUnboundedElastic pd(MPI_COMM_SELF);
        pd.setup(BallDomain<2>(Point<2>(), radius), lp, linear_model(), wp, ElasticTruncation::pml,
                 pml_parameters(1., w, 2.), u0);
        Timer        timer;
        unsigned int n_up = 0;
        rho[d]            = pd.one_step_spectral_radius(20000, &n_up);
        if (root())
          std::cout << "    PML disc " << radius << ", w " << w << ", d = " << d << ": spectral radius - 1 = "
                    << sci(rho[d] - 1.) << " (" << n_up << " eigenvalues of modulus > 1 + 1e-8), " << timer.cpu_time()
                    << " s CPU" << std::endl;
      }
    // d = 0: the rigid motions (translations, the infinitesimal rotation)
    // feel no bond force and no PML: u = a + b t, three 2 x 2 Jordan blocks
    // at 1, which round-off eps splits by ~sqrt(eps) = 1.5e-8 (measured
    // 1 + 8.4e-9). Bound 1e-7: anything growing faster (the EBF layer has
    // 1 + 1.5e-2 at R = 7) fails. With d > 0 the rigid velocities decay, the
    // blocks are gone and the radius is 1 (u = a) to round-off.
    check(rho[0.] <= 1. + 1e-7, "PML, d = 0: one-step spectral radius <= 1 + 1e-7 (sqrt(eps) splitting of the rigid-motion Jordan blocks): 1 + " + sci(rho[0.] - 1.));
    check(rho[0.02] <= 1. + 1e-12, "PML, d = 0.02: one-step spectral radius <= 1 + 1e-12: 1 + " + sci(rho[0.02] - 1.));
  }

  // 1e6 undamped steps of the disc of test pml (radius 11, PML from 5):
  // the total energy sampled every 10,000 steps.
  void
  pml_long()
  {
    Case c      = ci_case();
    c.damping   = 0.;
    c.R         = 5.;
    c.T         = 5e5;
    c.n_samples = 100;
    const auto h = run_case(c, 11., ElasticTruncation::absorbing, pml_parameters(1., 6., 2.));
    if (root())
      for (unsigned int k = 0; k < h.times.size(); k += 5)
        std::cout << "    t " << h.times[k] << " E/E0 " << sci(h.total[k] / h.total[0]) << std::endl;
    check(max_energy_increase(h) <= 0. && max_energy_increase(h, true) <= 0.,
          "PML, d = 0: total and Verlet energy non-increasing over 1e6 steps (max increase " +
            sci(max_energy_increase(h)) + ", " + sci(max_energy_increase(h, true)) + ")");
    check(h.total.back() < 1e-12 * h.total[0], "PML, d = 0: E_end = " + sci(h.total.back() / h.total[0]) + " E0 < 1e-12 E0");
  }

  // Parameter scan of the elastic PML (doc/design.md, session 9):
  // PML_SCAN="w sigma p start; ..." with start the radius where the PML
  // begins (the disc has radius start + w); ELASTIC_D sets d (default 0.02).
  void
  pml_scan()
  {
    Case c = ci_case();
    if (const char *e = std::getenv("ELASTIC_D"))
      c.damping = std::atof(e);
    const double cp     = std::sqrt(9. / 8.);
    const double radius = std::ceil(reference_radius(cp * 1.02, c.T, 3. * c.w, c.R, 2. * c.delta) / c.dx) * c.dx;
    const auto   ref    = run_case(c, radius, ElasticTruncation::free, abc_parameters());
    for (const auto tr : {ElasticTruncation::free, ElasticTruncation::absorbing})
      {
        Timer      timer;
        const auto h = run_case(c, c.R, tr, abc_parameters());
        std::cout << "    " << (tr == ElasticTruncation::free ? "free" : "EBF") << " (" << h.n_nodes << " nodes, "
                  << timer.cpu_time() << " s): dPi/Pi0 at T " << sci(energy_error(h, ref, c.n_samples)) << " field "
                  << sci(field_error(h, ref, c.w)) << " max increase " << sci(max_energy_increase(h)) << " step s "
                  << sci(h.step_seconds) << std::endl;
      }
    const char        *env = std::getenv("PML_SCAN");
    std::istringstream in(env ? env : "6 1 2 16");
    std::string        item;
    while (std::getline(in, item, ';'))
      {
        std::istringstream one(item);
        double             w = 0., sigma = 0., p = 0., start = 0.;
        if (!(one >> w >> sigma >> p >> start))
          continue;
        Timer      timer;
        const auto h = run_case(c, start + w, ElasticTruncation::absorbing, pml_parameters(sigma, w, p));
        std::cout << "    PML w " << w << " sigma " << sigma << " p " << p << " start " << start << " (" << h.n_nodes
                  << " nodes, " << timer.cpu_time() << " s): dPi/Pi0";
        for (unsigned int s = 1; s <= c.n_samples; ++s)
          std::cout << " " << sci(energy_error(h, ref, s));
        double e_max = 0.;
        for (unsigned int s = 1; s <= c.n_samples; ++s)
          e_max = std::max(e_max, energy_error(h, ref, s));
        std::cout << " | dPi/Pi0 at T " << sci(energy_error(h, ref, c.n_samples)) << " max " << sci(e_max) << " field " << sci(field_error(h, ref, c.w)) << " max increase " << sci(max_energy_increase(h))
                  << " E_T/E0 " << sci(h.total.back() / h.total[0]) << " step s " << sci(h.step_seconds) << std::endl;
        if (const char *n_long = std::getenv("PML_LONG"))
          {
            Case c2      = c;
            c2.T         = std::atof(n_long) * c.dt;
            c2.n_samples = 20;
            const auto l = run_case(c2, start + w, ElasticTruncation::absorbing, pml_parameters(sigma, w, p));
            for (unsigned int s = 0; s < l.times.size(); ++s)
              std::cout << "      t " << l.times[s] << " E/E0 " << sci(l.total[s] / l.total[0]) << std::endl;
          }
      }
  }

  // CPU cost of the truncations of E16 (CI size): set-up and 1,000 steps,
  // PML_COST_ROUNDS interleaved rounds (default 5), medians (std::clock).
  void
  pml_cost()
  {
    const Case c = ci_case();
    struct Config
    {
      std::string       name;
      double            radius;
      ElasticTruncation tr;
      WaveAbcParameters prm;
    };
    WaveAbcParameters sponge = abc_parameters();
    sponge.sponge_damping    = 0.5;
    sponge.sponge_thickness  = 3.;
    sponge.sponge_exponent   = 2.;
    std::vector<Config> configs = {{"free", c.R, ElasticTruncation::free, abc_parameters()},
                                   {"EBF", c.R, ElasticTruncation::absorbing, abc_parameters()},
                                   {"sponge", c.R, ElasticTruncation::sponge, sponge}};
    for (const double w : {3., 4., 5., 6.})
      configs.push_back({"PML w " + std::to_string(int(w)), c.R - c.delta + w, ElasticTruncation::absorbing,
                         pml_parameters(1., w, 2.)});
    const unsigned int rounds = std::getenv("PML_COST_ROUNDS") ? std::atoi(std::getenv("PML_COST_ROUNDS")) : 5;
    std::vector<std::vector<double>> setup(configs.size()), steps(configs.size());
    for (unsigned int r = 0; r < rounds; ++r)
      for (unsigned int k = 0; k < configs.size(); ++k)
        {
          PdUnboundedElastic pd(MPI_COMM_SELF);
          const std::clock_t t0 = std::clock();
          setup_case(pd, c, configs[k].radius, configs[k].tr, configs[k].prm);
          const std::clock_t t1 = std::clock();
          for (unsigned int n = 0; n < 1000; ++n)
            pd.advance();
          const std::clock_t t2 = std::clock();
          setup[k].push_back(double(t1 - t0) / CLOCKS_PER_SEC);
          steps[k].push_back(double(t2 - t1) / CLOCKS_PER_SEC);
        }
    const auto median = [](std::vector<double> x) {
      std::sort(x.begin(), x.end());
      return x[x.size() / 2];
    };
    for (unsigned int k = 0; k < configs.size(); ++k)
      std::cout << "    " << configs[k].name << " (disc " << configs[k].radius << "): set-up " << sci(median(setup[k]))
                << " s, 1000 steps " << sci(median(steps[k])) << " s CPU (median of " << rounds << ")" << std::endl;
  }

  // Bad input: a clear ParameterError.
  void
  guards()
  {
    Case              c   = ci_case();
    WaveAbcParameters prm = abc_parameters();
    prm.wave_number_range = 4.;
    bool thrown           = false;
    try
      {
        run_case(c, c.R, ElasticTruncation::absorbing, prm);
      }
    catch (const ParameterError &e)
      {
        thrown = std::string(e.what()).find("Wave number range") != std::string::npos;
      }
    check(thrown, "Delta k > pi/dx: ParameterError naming 'Wave number range'");
    prm                 = abc_parameters();
    prm.max_update_norm = 1e-3;
    thrown              = false;
    try
      {
        run_case(c, c.R, ElasticTruncation::absorbing, prm);
      }
    catch (const ParameterError &e)
      {
        thrown = std::string(e.what()).find("max |V_G|") != std::string::npos;
      }
    check(thrown, "unattainable max|V| guard: ParameterError reporting the cloud");
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"dispersion", dispersion},
              {"unbounded", unbounded},
              {"unbounded_long", unbounded_long},
              {"ranks", ranks},
              {"spectral_radius", spectral_radius},
              {"sponge", sponge},
              {"guards", guards},
              {"pml", pml},
              {"pml_long", pml_long},
              {"pml_spectral_radius", pml_spectral_radius},
              {"pml_scan", pml_scan},
              {"pml_cost", pml_cost},
              {"first_order", first_order},
              {"first_order_scan", first_order_scan},
              {"curved_tikhonov", curved_tikhonov}});
}
