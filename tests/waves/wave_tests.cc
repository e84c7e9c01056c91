// Tests of the PD scalar wave solver (2.40) with velocity Verlet (3.9)/(4.62):
// the discrete dispersion relation (4.95) against its local and continuum
// limits and against simulated standing waves, energy conservation and
// decay, the time step bound and rank-count invariance.

#include <deal.II/base/function.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>
#include <perideal/models/scalar_wave.h>

#include "../check.h"

#include <cmath>
#include <map>
#include <memory>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  // The standard-scheme dispersion relation (4.95) for d = 0 in 1D, p = 0,
  // omega_0: omega^2 = sum_{l != 0} c_s (1 - cos(k l dx)) beta(l dx) dx,
  // evaluated here independently of the solver (beta from the
  // partial-volume rule (3.2), the kernel held at its horizon value).
  double
  discrete_omega_1d(const double k, const double chi, const double delta, const double dx)
  {
    const double c_s = 3. * chi * chi / (delta * delta * delta); // (4.90)
    double       w2  = 0.;
    for (int l = 1; l * dx < delta + dx; ++l)
      {
        const double r    = l * dx;
        const double beta = Discretization<1>::volume_factor(r, delta, dx, true);
        w2 += 2. * c_s * (1. - std::cos(k * r)) * beta * dx;
      }
    return std::sqrt(w2);
  }

  // Continuum nonlocal relation (4.90) with d = 0:
  // omega^2 = c_s int_{-delta}^{delta} (1 - cos k xi) dxi = 2 c_s (delta - sin(k delta)/k).
  double
  continuum_omega_1d(const double k, const double chi, const double delta)
  {
    const double c_s = 3. * chi * chi / (delta * delta * delta);
    return std::sqrt(2. * c_s * (delta - std::sin(k * delta) / k));
  }

  void
  dispersion_relation()
  {
    const double chi = 1.;
    // The quadrature calibration equals (4.90): c_s = 3 chi^2 / delta^3.
    {
      ScalarKernel kern;
      kern.dim      = 1;
      kern.exponent = 0.;
      kern.delta    = 0.7;
      check_close(kern.micro_constant_for(chi * chi), 3. / std::pow(0.7, 3), 1e-12,
                  "1D p = 0 omega_0: c_s = 3 chi^2/delta^3 (4.90)");
    }
    // Local limit k delta -> 0: omega/(chi k) -> sqrt(M_h/M), where the
    // discrete second moment of the stencil with beta(delta) = 1/2 is
    // M_h = 2 dx^3 (sum_{l<m} l^2 + m^2/2) = M (1 + 1/(2 m^2)), M = 2 delta^3/3.
    // So the discrete relation tends to chi k only as m grows; at
    // k delta = 0.05 the remaining (k delta)^2/40 term is 6e-5.
    const double kd = 0.05;
    for (const int m : {4, 10, 40})
      {
        const double delta = 1., dx = delta / m, k = kd / delta;
        const double w     = discrete_omega_1d(k, chi, delta, dx);
        check_close(w / (chi * k), std::sqrt(1. + 0.5 / (m * m)), 1e-4,
                    "m = " + std::to_string(m) +
                      ": omega_h/(chi k) at k delta = 0.05 vs sqrt(1 + 1/(2 m^2))");
        if (m == 40)
          check_close(w, chi * k, 1e-3, "m = 40: omega_h -> chi k at k delta = 0.05");
        if (root())
          std::cout << "    m = " << m << ": |omega_h - chi k|/(chi k) = "
                    << std::abs(w - chi * k) / (chi * k) << " at k delta = 0.05"
                    << std::endl;
      }
    // Continuum limit m -> infinity at fixed k delta.
    for (const double kdelta : {1., 2., 4.})
      {
        double last = 1e300;
        for (const int m : {4, 10, 40})
          {
            const double delta = 1., dx = delta / m, k = kdelta / delta;
            const double err = std::abs(discrete_omega_1d(k, chi, delta, dx) -
                                        continuum_omega_1d(k, chi, delta)) /
                               continuum_omega_1d(k, chi, delta);
            if (root())
              std::cout << "    k delta = " << kdelta << ", m = " << m
                        << ": |omega_h - omega_cont|/omega_cont = " << err << std::endl;
            check(err < last, "k delta = " + std::to_string(kdelta) + ", m = " +
                                std::to_string(m) + ": continuum error decreases (" +
                                std::to_string(err) + ")");
            last = err;
          }
        check(last < 2e-3, "k delta = " + std::to_string(kdelta) +
                             ": m = 40 within 2e-3 of (4.90)");
      }
  }

  // cos(k x) cos(omega t): the exact standing wave of the semi-discrete
  // system, used as Dirichlet data on the layer.
  class StandingWave : public Function<1>
  {
  public:
    StandingWave(const double k, const double omega)
      : k(k)
      , omega(omega)
    {}
    double
    value(const Point<1> &p, const unsigned int = 0) const override
    {
      return std::cos(k * p[0]) * std::cos(omega * get_time());
    }

  private:
    double k, omega;
  };

  // Simulated standing waves in 1D: the center node oscillates at the
  // discrete omega(k) of (4.95), up to Verlet's frequency error.
  void
  standing_wave()
  {
    const double chi = 1., dx = 0.1, L = 10.;
    struct Case
    {
      int m, n; // delta = m dx, k = n * (2 pi / 2L)
    };
    for (const Case c : {Case{4, 12}, Case{10, 5}})
      {
        const double delta = c.m * dx, k = c.n * M_PI / L;
        LatticeParameters lp;
        lp.dx              = dx;
        lp.delta           = delta;
        lp.layer_thickness = delta;
        BoxDomain<1>      box(Point<1>(-L), Point<1>(L));
        Discretization<1> disc(MPI_COMM_WORLD);
        disc.setup(box, lp);

        const double w_h = discrete_omega_1d(k, chi, delta, dx);
        ScalarWaveParameters wp;
        wp.exponent   = 0.;
        wp.wave_speed = chi;
        wp.time_step  = 1.; // replaced below
        // dt: 5 % of the critical step (closed form for 1D p = 0:
        // row sum c_s (2m - 1) dx).
        const double c_s     = 3. * chi * chi / std::pow(delta, 3);
        const double dt_crit = 2. / std::sqrt(2. * c_s * (2 * c.m - 1) * dx);
        wp.time_step         = 0.05 * dt_crit;
        ScalarWaveSolver<1> s0(disc, wp);
        check_close(s0.critical_time_step(), dt_crit, 1e-12,
                    "m = " + std::to_string(c.m) + ": critical step 2/sqrt(2 c_s (2m-1) dx)");
        check_close(s0.micro_constant(), c_s, 1e-12, "c_s by quadrature");

        // Verlet advances cos(k x) exactly with cos(Omega t), where
        // cos(Omega dt) = 1 - (omega_h dt)^2/2, i.e.
        // Omega = (2/dt) asin(omega_h dt/2) = omega_h (1 + (omega_h dt)^2/24 + ...).
        const double dt     = s0.time_step();
        const double wdt    = w_h * dt;
        const double verlet = 2. / dt * std::asin(0.5 * wdt);
        // Layer data: first the exact semi-discrete wave cos(kx) cos(omega_h t)
        // (it runs (omega dt)^2/24 ahead of the interior's Omega, a small
        // boundary disturbance), then the fully discrete one cos(kx) cos(Omega t).
        for (const bool layer_at_verlet : {false, true})
          {
            ScalarWaveSolver<1> s(disc, wp);
            auto g = std::make_shared<StandingWave>(k, layer_at_verlet ? verlet : w_h);
            s.set_boundary_values(g);
            g->set_time(0.);
            s.set_initial_values(*g);
            s.initialize();

            // The operator applied to cos(k x) at the center is -omega_h^2.
            int center = -1;
            for (unsigned int i = 0; i < disc.n_owned(); ++i)
              if (std::abs(disc.position[i][0]) < 0.5 * dx)
                center = i;
            auto center_value = [&](const PeriDEAL::Vector &v) {
              return Utilities::MPI::sum(center >= 0 ? v.local_element(center) : 0.,
                                         MPI_COMM_WORLD);
            };
            check_close(center_value(s.acceleration), -w_h * w_h, 1e-10,
                        "m = " + std::to_string(c.m) + ": (L cos(kx))(0) = -omega_h^2");

            // Zero crossings t_j = (2j + 1) pi / (2 Omega) over 3 periods, by
            // linear interpolation (error O(dt^3): u'' = 0 at a crossing).
            const double        T = 3. * 2. * M_PI / w_h;
            std::vector<double> crossings;
            double              u_old = center_value(s.displacement);
            while (s.time() < T)
              {
                s.advance();
                const double u_new = center_value(s.displacement);
                if ((u_old > 0.) != (u_new > 0.))
                  crossings.push_back(s.time() - dt * u_new / (u_new - u_old));
                u_old = u_new;
              }
            // Least-squares slope of t_j over j: pi / Omega.
            const double n  = crossings.size();
            double       sj = 0., st = 0., sjj = 0., sjt = 0.;
            for (unsigned int j = 0; j < crossings.size(); ++j)
              {
                sj += j;
                st += crossings[j];
                sjj += double(j) * j;
                sjt += j * crossings[j];
              }
            const double slope  = (n * sjt - sj * st) / (n * sjj - sj * sj);
            const double w_meas = M_PI / slope;
            const double tol    = 1.5 * wdt * wdt / 24.;
            std::ostringstream what;
            what.precision(10);
            what << "m = " << c.m << ", k delta = " << k * delta << ", layer at "
                 << (layer_at_verlet ? "Omega" : "omega_h") << ": " << crossings.size()
                 << " zero crossings, measured omega = " << w_meas << ", omega_h (4.95) = " << w_h
                 << ", Verlet Omega = " << verlet << ", local chi k = " << chi * k
                 << ", continuum (4.90) = " << continuum_omega_1d(k, chi, delta)
                 << ", (omega dt)^2/24 = " << wdt * wdt / 24.;
            if (root())
              std::cout << "    " << what.str() << std::endl;
            check(crossings.size() == 6, "6 zero crossings in 3 periods");
            check_close(w_meas, w_h, tol, "measured vs discrete omega_h, tol 1.5 (omega dt)^2/24");
            // With the layer at omega_h the boundary mismatch (8e-5 relative
            // in frequency) leaks into the center at the 1e-6 level; with the
            // layer at Omega the solution is exact up to the O(dt^3)
            // interpolation of the crossings (measured 6.5e-8).
            check_close(w_meas, verlet, layer_at_verlet ? 3e-7 : 1e-5,
                        "measured vs Verlet-shifted (2/dt) asin(omega_h dt/2)");
            check(std::abs(w_meas - chi * k) > 20. * tol * w_h,
                  "measured omega distinguishes (4.95) from the local chi k");
          }
      }
  }

  // 2D isolated body (no layer): undamped energy conservation and damped decay.
  std::unique_ptr<Discretization<2>>
  isolated_box(const MPI_Comm comm, const double dx, const double L)
  {
    LatticeParameters lp;
    lp.dx              = dx;
    lp.delta           = 3. * dx;
    lp.layer_thickness = 0.;
    BoxDomain<2> box(Point<2>(-L, -L), Point<2>(L, L));
    auto         disc = std::make_unique<Discretization<2>>(comm);
    disc->setup(box, lp);
    return disc;
  }

  double
  acceleration_norm(const ScalarWaveSolver<2> &s, const Discretization<2> &disc)
  {
    double a = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      a += s.acceleration.local_element(i) * s.acceleration.local_element(i) * disc.volume[i];
    return Utilities::MPI::sum(a, disc.get_mpi_communicator());
  }

  void
  energy()
  {
    const double L    = 2.;
    auto         disc = isolated_box(MPI_COMM_WORLD, 0.02, L);
    // Smooth data with zero normal derivative at the free edges: the lowest
    // modes cos(pi x/L) + cos(pi y/L), started with velocity chi k times
    // them (phase ~pi/4), so that the bounded O((omega dt)^2) oscillation of
    // E in Verlet, dt^2/8 (A - A0) with A = sum a^2 V, is centred:
    // amplitude (omega dt)^2/8.
    ScalarFunctionFromFunctionObject<2> u0([L](const Point<2> &p) {
      return std::cos(M_PI * p[0] / L) + std::cos(M_PI * p[1] / L);
    });
    ScalarFunctionFromFunctionObject<2> v0([L](const Point<2> &p) {
      return M_PI / L * (std::cos(M_PI * p[0] / L) + std::cos(M_PI * p[1] / L));
    });
    ScalarWaveParameters wp;
    wp.exponent   = 2.;
    wp.wave_speed = 1.;
    {
      ScalarWaveParameters probe = wp;
      probe.time_step            = 1e-12;
      ScalarWaveSolver<2> p(*disc, probe);
      wp.time_step = 0.5 * p.critical_time_step();
      check_close(p.micro_constant(), 4. / (M_PI * std::pow(3. * 0.02, 2)), 1e-12,
                  "2D p = 2 omega_0: c_s = 4 chi^2/(pi delta^2) (4.47)");
    }
    {
      ScalarWaveSolver<2> s(*disc, wp);
      s.set_initial_values(u0, &v0);
      s.initialize();
      const double dt = s.time_step();
      // E - dt^2/8 sum a^2 V is the exact invariant of undamped velocity
      // Verlet for a symmetric linear operator (equal node volumes).
      const double E0 = s.energy(), H0 = E0 - dt * dt / 8. * acceleration_norm(s, *disc);
      double       drift = 0., hdrift = 0.;
      for (unsigned int n = 0; n < 2000; ++n)
        {
          s.advance();
          const double E = s.energy();
          drift          = std::max(drift, std::abs(E - E0) / E0);
          hdrift = std::max(hdrift, std::abs(E - dt * dt / 8. * acceleration_norm(s, *disc) - H0) / H0);
        }
      std::ostringstream what;
      what << disc->n_global() << " nodes, dt = 0.5 dt_crit = " << dt
           << ", 2000 steps: max |E - E0|/E0 = " << drift
           << ", max rel. change of E - dt^2/8 |a|^2 = " << hdrift
           << "; (chi k dt)^2/8 = " << std::pow(M_PI / L * dt, 2) / 8.;
      check(drift < 1e-4, what.str() + " (< 1e-4)");
      check(hdrift < 1e-10, "modified Verlet energy conserved to round-off (< 1e-10)");
    }
    {
      wp.damping = 0.5;
      ScalarWaveSolver<2> s(*disc, wp);
      s.set_initial_values(u0);
      s.initialize();
      double       E_prev = s.energy();
      const double E0     = E_prev;
      bool         monotone = true;
      double       worst    = 0.;
      for (unsigned int n = 0; n < 1000; ++n)
        {
          s.advance();
          const double E = s.energy();
          if (E > E_prev)
            {
              monotone = false;
              worst    = std::max(worst, (E - E_prev) / E0);
            }
          E_prev = E;
        }
      std::ostringstream what;
      what << "damping d = 0.5, 1000 steps: E/E0 = " << E_prev / E0
           << ", continuum estimate exp(-2 d t) average ~ " << std::exp(-0.5 * 2. * s.time())
           << ", largest step increase " << worst;
      check(monotone, what.str() + ": E non-increasing every step");
      check(E_prev < 0.9 * E0, "energy decays");
    }
  }

  void
  time_step_bound()
  {
    auto disc = isolated_box(MPI_COMM_WORLD, 0.1, 1.);
    ScalarWaveParameters wp;
    wp.time_step = 1e-12;
    const double dt_crit = ScalarWaveSolver<2>(*disc, wp).critical_time_step();
    wp.time_step         = 1.01 * dt_crit;
    bool thrown = false;
    try
      {
        ScalarWaveSolver<2> s(*disc, wp);
      }
    catch (const ParameterError &e)
      {
        thrown = std::string(e.what()).find("Time step") != std::string::npos;
        if (root())
          std::cout << "    " << e.what() << std::endl;
      }
    check(thrown, "dt = 1.01 dt_crit throws ParameterError naming 'Time step'");
    wp.time_step = dt_crit;
    bool ok      = true;
    try
      {
        ScalarWaveSolver<2> s(*disc, wp);
      }
    catch (...)
      {
        ok = false;
      }
    check(ok, "dt = dt_crit is accepted");
    wp.time_step = -1.;
    thrown       = false;
    try
      {
        ScalarWaveSolver<2> s(*disc, wp);
      }
    catch (const ParameterError &e)
      {
        thrown = std::string(e.what()).find("Time step") != std::string::npos;
      }
    check(thrown, "dt < 0 throws ParameterError naming 'Time step'");
  }

  class LayerData : public Function<2>
  {
  public:
    double
    value(const Point<2> &p, const unsigned int = 0) const override
    {
      return 0.1 * p[0] * std::sin(3. * get_time()) + 0.05 * p[1];
    }
  };

  std::map<std::uint64_t, double>
  run_rank_case(const MPI_Comm comm)
  {
    LatticeParameters lp;
    lp.dx              = 0.025;
    lp.delta           = 3.015 * 0.025;
    lp.layer_thickness = lp.delta;
    BoxDomain<2>      box(Point<2>(-1., -1.), Point<2>(1., 1.));
    Discretization<2> disc(comm);
    disc.setup(box, lp);
    if (comm == MPI_COMM_WORLD)
      check(Utilities::MPI::min(disc.n_owned(), comm) > 0, "every rank owns nodes");
    ScalarWaveParameters wp;
    wp.exponent   = 1.;
    wp.omega      = InfluenceFunction::linear;
    wp.damping    = 0.3;
    wp.time_step  = 1e-12;
    wp.time_step  = 0.9 * ScalarWaveSolver<2>(disc, wp).critical_time_step();
    ScalarWaveSolver<2> s(disc, wp);
    ScalarFunctionFromFunctionObject<2> u0(
      [](const Point<2> &p) { return (p.norm_square() < 0.3) + 0.2 * std::sin(3 * p[0]) * std::cos(2 * p[1]); });
    ScalarFunctionFromFunctionObject<2> v0([](const Point<2> &p) { return p[0] * p[1]; });
    s.set_initial_values(u0, &v0);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      s.body_force.local_element(i) = 0.5 * disc.position[i][0];
    s.set_boundary_values(std::make_shared<LayerData>());
    s.initialize();
    for (unsigned int n = 0; n < 200; ++n)
      s.advance();
    // Keys: node id (u), id + 2^40 (v), 2^50 (energy).
    std::vector<std::pair<std::uint64_t, double>> mine;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        mine.emplace_back(disc.id[i], s.displacement.local_element(i));
        mine.emplace_back(std::uint64_t(disc.id[i]) + (std::uint64_t(1) << 40),
                          s.velocity.local_element(i));
      }
    std::map<std::uint64_t, double> out;
    for (const auto &part : Utilities::MPI::gather(comm, mine, 0))
      for (const auto &e : part)
        out[e.first] = e.second;
    const double E = s.energy();
    out[std::uint64_t(1) << 50] = E;
    return out;
  }

  void
  rank_invariance()
  {
    const auto world = run_rank_case(MPI_COMM_WORLD);
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
      {
        const auto   self     = run_rank_case(MPI_COMM_SELF);
        double       max_diff = 0., max_val = 0.;
        unsigned int matched  = 0;
        for (const auto &e : self)
          {
            const auto it = world.find(e.first);
            if (it == world.end())
              continue;
            ++matched;
            max_diff = std::max(max_diff, std::abs(it->second - e.second));
            max_val  = std::max(max_val, std::abs(e.second));
          }
        std::ostringstream what;
        what << Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)
             << " ranks vs 1 rank, 200 damped steps with layer data and body force: "
             << matched << " values (u, v, E) matched, max |diff| = " << max_diff
             << " (max |value| " << max_val << ")";
        check(matched == self.size() && matched == world.size(), what.str() + " (all matched)");
        check(max_diff <= 1e-12 * std::max(1., max_val), what.str());
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"dispersion_relation", dispersion_relation},
              {"standing_wave", standing_wave},
              {"energy", energy},
              {"time_step_bound", time_step_bound},
              {"rank_invariance", rank_invariance}});
}
