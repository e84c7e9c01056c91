// Tests of the two-grid explicit mechanics and the multi-adaptive scheme
// (MultiGrid::MechanicsSolver, dissertation Sect. 3.4-3.5, paper 001):
// patch tests (constant and linear fields), mass counted once, momentum,
// a 1D elastic wave against the uniform fine grid, and the CI-size
// Kalthoff-Winkler experiment with the three models.

#include <perideal/base/exceptions.h>
#include <perideal/multigrid/multigrid_mechanics.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include "../check.h"
#include "../hybrid_kw/kalthoff_winkler_case.h"

#include <filesystem>
#include <map>
#include <tuple>


using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEAL::MultiGrid;
using namespace PeriDEALTests;

namespace
{
  // The two-grid solver's names (PeriDEAL has a MechanicsSolver and a
  // MechanicsModel too).
  using MultiGrid::MechanicsModel;
  template <int dim>
  using Solver = MultiGrid::MechanicsSolver<dim>;

  // Largest |a| over the active nodes of both grids, split into nodes with
  // and without a complete family.
  template <int dim>
  std::pair<double, double>
  max_acceleration(const Solver<dim> &s)
  {
    double interior = 0., boundary = 0.;
    for (const auto g : {Solver<dim>::coarse, Solver<dim>::fine})
      for (unsigned int i = 0; i < s.n_nodes(g); ++i)
        if (s.is_active(g, i))
          {
            const double a = s.acceleration(g, i).norm();
            (s.has_full_family(g, i) ? interior : boundary) =
              std::max(s.has_full_family(g, i) ? interior : boundary, a);
          }
    return {interior, boundary};
  }

  MechanicsParameters<2>
  plate(const MechanicsModel model, const Interpolation interpolation)
  {
    MechanicsParameters<2> p;
    p.lower         = Point<2>(0., 0.);
    p.upper         = Point<2>(48., 40.);
    p.coarse_dx     = 2.;
    p.fine_dx       = 1.;
    p.delta         = 8.;
    p.model         = model;
    p.interpolation = interpolation;
    p.initial_fine_region = [](const Point<2> &x) {
      return x[0] > 14. && x[0] < 30. && x[1] > 12. && x[1] < 26.;
    };
    return p;
  }

  // A switch updates the node sets, interpolation rows and live bits only
  // near the refined cells: after three refinements the solver must equal
  // one built with the same refined cells from the start (same active and
  // fictitious nodes, bitwise the same accelerations of a nonlinear field
  // and the same state after a few steps).
  void
  incremental_switch()
  {
    for (const auto model : {MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
      {
        const std::string name = to_string(model);
        Solver<2>         s(plate(model, Interpolation::inverse_distance));
        const std::vector<std::function<bool(const Point<2> &)>> regions{
          [](const Point<2> &x) { return x.distance(Point<2>(31., 19.)) < 5.; },
          [](const Point<2> &x) { return x[1] > 33. && x[0] > 20. && x[0] < 36.; },
          [](const Point<2> &x) { return x[0] < 5. && x[1] < 9.; }};
        for (const auto &region : regions)
          check(s.refine_region(region) > 0, name + ": cells refined on request");
        const std::vector<std::uint8_t> refined = s.refined_cells();
        auto                            p       = plate(model, Interpolation::inverse_distance);
        p.initial_fine_region                   = [&refined, &p](const Point<2> &x) {
          const unsigned int ix = std::lround((x[0] - p.lower[0]) / p.coarse_dx - 0.5),
                             iy = std::lround((x[1] - p.lower[1]) / p.coarse_dx - 0.5),
                             nx = std::lround((p.upper[0] - p.lower[0]) / p.coarse_dx);
          return refined[iy * nx + ix] != 0;
        };
        Solver<2> fresh(p);
        const auto field = [](const Point<2> &x) {
          return Tensor<1, 2>({1e-3 * std::sin(x[0] / 7.) * x[1] / 40., 1e-3 * std::cos(x[1] / 5.)});
        };
        double max_a = 0., max_u = 0.;
        for (Solver<2> *t : {&s, &fresh})
          {
            t->set_initial_velocity([](const Point<2> &x) { return Tensor<1, 2>({0.1 * x[1], 0.}); });
            t->set_initial_displacement(field);
          }
        for (const auto g : {Solver<2>::coarse, Solver<2>::fine})
          {
            check(s.n_active(g) == fresh.n_active(g) && s.n_fictitious(g) == fresh.n_fictitious(g),
                  name + ": grid " + std::to_string(g) + ": active " + std::to_string(s.n_active(g)) +
                    " / " + std::to_string(fresh.n_active(g)) + ", fictitious " +
                    std::to_string(s.n_fictitious(g)) + " / " + std::to_string(fresh.n_fictitious(g)));
            for (unsigned int i = 0; i < s.n_nodes(g); ++i)
              if (s.is_active(g, i))
                max_a = std::max(max_a, (s.acceleration(g, i) - fresh.acceleration(g, i)).norm());
          }
        for (unsigned int k = 0; k < 5; ++k)
          {
            s.advance();
            fresh.advance();
          }
        for (const auto g : {Solver<2>::coarse, Solver<2>::fine})
          for (unsigned int i = 0; i < s.n_nodes(g); ++i)
            if (s.is_active(g, i) || fresh.is_active(g, i))
              max_u = std::max(max_u, (s.displacement(g, i) - fresh.displacement(g, i)).norm());
        check(max_a == 0. && max_u == 0. && max_acceleration(s).first > 0.,
              name + ": refined on request = refined from the start: max |a - a'| = " + sci(max_a) +
                ", after 5 steps max |u - u'| = " + sci(max_u) + " (bitwise 0)");
      }
  }

  // Patch tests: a rigid translation gives zero force on every node with
  // both interpolations (they reproduce constants); an affine field gives
  // zero force on every node with a complete family when the interpolation
  // is d-linear (exact for linear fields) and the coarse grid uses the
  // standard scheme (symmetric stencil) or WLS (complete to order 2).
  // Inverse-distance weighting is not linear-exact: its interface force is
  // reported.
  void
  patch()
  {
    for (const auto model : {MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
      for (const auto interp : {Interpolation::multilinear, Interpolation::inverse_distance})
        {
          const std::string name = to_string(model) + (interp == Interpolation::multilinear ?
                                                         ", d-linear" : ", IDW");
          Solver<2> s(plate(model, interp));
          check(s.n_active(Solver<2>::fine) > 0 && s.n_fictitious(Solver<2>::fine) > 0 &&
                  s.n_fictitious(Solver<2>::coarse) > 0,
                name + ": both grids have active and fictitious nodes");
          s.set_initial_displacement([](const Point<2> &) { return Tensor<1, 2>({0.3, -0.2}); });
          const double eps = 1e-3;
          const auto   t   = max_acceleration(s);
          s.set_initial_displacement([&](const Point<2> &x) {
            return Tensor<1, 2>({eps * (x[0] + 0.5 * x[1]), eps * (-0.3 * x[0] + 2. * x[1])});
          });
          const auto l = max_acceleration(s);
          // Scale: the force on the boundary nodes of the affine field.
          check(l.second > 0., name + ": boundary nodes feel the affine field");
          check(std::max(t.first, t.second) <= 1e-12 * l.second,
                name + ": translation, max |a| = " + sci(std::max(t.first, t.second)) +
                  " <= 1e-12 x " + sci(l.second));
          if (interp == Interpolation::multilinear)
            check(l.first <= 1e-10 * l.second,
                  name + ": affine field, interior max |a| = " + sci(l.first) + " <= 1e-10 x " +
                    sci(l.second));
          else
            std::cout << "  info  " << name << ": affine field, interior max |a| = " << sci(l.first)
                      << " (boundary " << sci(l.second) << ")" << std::endl;
        }
  }

  // Sum rho V |v| over the active nodes: the scale of the momentum.
  template <int dim>
  double
  momentum_scale(const Solver<dim> &s)
  {
    double sum = 0.;
    for (const auto g : {Solver<dim>::coarse, Solver<dim>::fine})
      for (unsigned int i = 0; i < s.n_nodes(g); ++i)
        if (s.is_active(g, i))
          sum += s.parameters().density * s.node_volume(g) * s.velocity(g, i).norm();
    return sum;
  }

  // Mass is counted once: active coarse and fine volumes add up to the
  // plate's area before and after switching. A switch keeps each refined
  // cell's momentum. Momentum of a free plate with switching.
  void
  mass_momentum()
  {
    const double area = 48. * 40.;
    for (const auto model : {MechanicsModel::uniform_fine, MechanicsModel::adaptive_standard,
                             MechanicsModel::adaptive_hybrid})
      {
        auto p             = plate(model, Interpolation::inverse_distance);
        p.critical_stretch = 4e-3;
        Solver<2> s(p);
        check_close(s.active_mass(), area, 1e-14, to_string(model) + ": active mass at t = 0");
        // A bump of largest gradient 0.107 x 0.04 = 4.3e-3 around (40, 20)
        // in the coarse region, its tail across the interface x = 30:
        // bonds reach sigma s0 = 3.8e-3 in the first steps.
        s.set_initial_displacement([](const Point<2> &x) {
          const double r2 = (x - Point<2>(40., 20.)).norm_square();
          return Tensor<1, 2>({0.04 * std::exp(-r2 / 64.), 0.});
        });
        const unsigned int fine0 = s.n_active(Solver<2>::fine);
        double             scale = 0.;
        for (unsigned int n = 0; n < 40; ++n)
          {
            s.advance();
            scale = std::max(scale, momentum_scale(s));
          }
        check_close(s.active_mass(), area, 1e-14, to_string(model) + ": active mass after " +
                                                    std::to_string(s.n_switches()) + " switches");
        const double P = s.momentum().norm() / scale;
        if (model == MechanicsModel::uniform_fine)
          // Lattice sweep: every bond evaluated once, f_ji = -f_ij.
          check(P < 1e-12, "uniform fine: |P| / sum rho V |v| = " + sci(P) + " < 1e-12");
        else
          {
            check(s.n_switches() > 0 && s.n_active(Solver<2>::fine) > fine0,
                  to_string(model) + ": fine region grew (" + std::to_string(fine0) + " -> " +
                    std::to_string(s.n_active(Solver<2>::fine)) + ")");
            // A switch itself keeps the momentum (next check); the forces
            // of the coupling (3.81)-(3.88) are not pairwise (a coarse
            // node's bond to a fictitious node has no reaction on the fine
            // nodes that define it), so momentum is conserved only up to the
            // interface error of a field that varies on the scale of delta.
            // Measured with IDW: 7.9e-3 (standard) and 1.68e-2 (hybrid;
            // the same with the list loop before the lattice sweep). Bound: 2 %.
            check(P < 2e-2, to_string(model) + ": |P| / sum rho V |v| = " + sci(P) + " < 2e-2");

            // Refining a band now: mass and momentum unchanged to round-off.
            const auto   P0 = s.momentum();
            const auto   n  = s.refine_region([](const Point<2> &x) { return x[1] < 10.; });
            check(n > 0, to_string(model) + ": " + std::to_string(n) + " cells refined on request");
            check((s.momentum() - P0).norm() <= 1e-13 * scale,
                  to_string(model) + ": a switch keeps the momentum (|dP| = " +
                    sci((s.momentum() - P0).norm()) + ")");
            check_close(s.active_mass(), area, 1e-14, to_string(model) + ": mass after it");
          }
      }
  }


  // The momentum-conserving coupling (MechanicsParameters::
  // conservative_coupling): the mass_momentum run of a free plate with
  // switching, with and without it; then the CI-size Kalthoff-Winkler crack
  // angle of both couplings against the uniform fine grid.
  void
  conservative_coupling()
  {
    {
      double P[2];
      for (const bool conservative : {false, true})
        {
          auto p                  = plate(MechanicsModel::adaptive_standard,
                                          Interpolation::inverse_distance);
          p.critical_stretch      = 4e-3;
          p.conservative_coupling = conservative;
          Solver<2> s(p);
          s.set_initial_displacement([](const Point<2> &x) {
            const double r2 = (x - Point<2>(40., 20.)).norm_square();
            return Tensor<1, 2>({0.04 * std::exp(-r2 / 64.), 0.});
          });
          double scale = 0.;
          for (unsigned int n = 0; n < 40; ++n)
            {
              s.advance();
              scale = std::max(scale, momentum_scale(s));
            }
          P[conservative] = s.momentum().norm() / scale;
          std::cout << "  info  adaptive standard" << (conservative ? ", conservative" : "")
                    << ": " << s.n_switches() << " switches, |P| / sum rho V |v| = "
                    << sci(P[conservative]) << std::endl;
        }
      // every force is pairwise now: round-off (the uniform fine grid
      // reaches < 1e-12 in mass_momentum)
      check(P[1] < 1e-12, "adaptive standard, conservative coupling: |P| / sum rho V |v| = " +
                            sci(P[1]) + " < 1e-12 (default coupling " + sci(P[0]) + ")");
      auto p                  = plate(MechanicsModel::adaptive_hybrid, Interpolation::inverse_distance);
      p.conservative_coupling = true;
      bool thrown             = false;
      try
        {
          Solver<2> s(p);
        }
      catch (const ParameterError &)
        {
          thrown = true;
        }
      check(thrown, "conservative coupling with adaptive hybrid -> ParameterError");
    }
    std::map<std::string, double> angle;
    for (const auto &[name, model, conservative] :
         std::vector<std::tuple<std::string, MechanicsModel, bool>>{
           {"uniform fine", MechanicsModel::uniform_fine, false},
           {"adaptive standard", MechanicsModel::adaptive_standard, false},
           {"adaptive standard, conservative", MechanicsModel::adaptive_standard, true}})
      {
        KalthoffWinkler kwp;
        kwp.model                 = model;
        kwp.conservative_coupling = conservative;
        angle[name]               = kwp.run([](const Solver<2> &) {}).angle;
        std::cout << "  info  KW " << name << ": crack angle " << angle[name] << std::endl;
      }
    // the same 3-degree band as the kw test for the default coupling
    check(std::abs(angle["adaptive standard, conservative"] - angle["uniform fine"]) < 3.,
          "KW crack angle with the conservative coupling " +
            std::to_string(angle["adaptive standard, conservative"]) + " within 3 degrees of "
            "uniform fine " + std::to_string(angle["uniform fine"]) + " (default coupling " +
            std::to_string(angle["adaptive standard"]) + ")");
  }

  // 1D elastic wave: a Gaussian pulse u0 = A exp(-(x - 70)^2 / w^2),
  // w = 8 = 4 delta, v0 = -c0 u0' (c0 = sqrt(E / rho) = 1), crossing a fine
  // region. Reference: the continuum linear PD solution by Fourier
  // transform, u(s, t) = 1/pi int_0^inf U(k) [cos(w t) cos(k s) +
  // c0 k / w sin(w t) sin(k s)] dk, U = A w sqrt(pi) exp(-k^2 w^2 / 4),
  // rho w(k)^2 = 2 c int_0^delta (1 - cos k xi) / xi dxi (the dispersion
  // relation of the 1D bond-based model, c = 2E / delta^2).
  void
  wave()
  {
    const double A = 1e-3, w = 8., x0 = 70., T = 60., delta = 2.;
    const double c = 2. / (delta * delta);
    // Simpson's rule on [a, b] with n (even) intervals.
    const auto simpson = [](const auto &f, const double a, const double b, const unsigned int n) {
      const double h = (b - a) / n;
      double       s = f(a) + f(b);
      for (unsigned int i = 1; i < n; ++i)
        s += (i % 2 ? 4. : 2.) * f(a + i * h);
      return s * h / 3.;
    };
    const unsigned int  nk = 4000;
    const double        kmax = 12. / w;
    std::vector<double> omega(nk + 1);
    for (unsigned int q = 0; q <= nk; ++q)
      {
        const double k = q * kmax / nk;
        omega[q]       = std::sqrt(2. * c * simpson([k](const double xi) {
                                 return xi > 0. ? (1. - std::cos(k * xi)) / xi : 0.;
                               }, 0., delta, 400));
      }
    const auto reference = [&](const double x) {
      const double sx = x - x0;
      return simpson([&](const double k) {
        const unsigned int q  = static_cast<unsigned int>(std::round(k / kmax * nk));
        const double       U  = A * w * std::sqrt(M_PI) * std::exp(-k * k * w * w / 4.);
        const double       om = omega[q];
        const double       sn = om > 0. ? k / om * std::sin(om * T) : T;
        return U * (std::cos(om * T) * std::cos(k * sx) + sn * std::sin(k * sx)) / M_PI;
      }, 0., kmax, nk);
    };
    // The local limit (classical wave, d'Alembert): what the order-2 WLS
    // operator of the hybrid's coarse grid converges to (exact for
    // quadratics, it drops the delta^4 u'''' dispersion of (3.70)).
    double e_local = 0.;
    for (double x = 60.; x < 200.; x += 0.25)
      e_local = std::max(e_local, std::abs(A * std::exp(-(x - x0 - T) * (x - x0 - T) / (w * w)) -
                                           reference(x)) / A);
    std::cout << "  info  local wave vs PD: max |u_local - u_PD| / A = " << sci(e_local) << std::endl;
    std::map<MechanicsModel, double> error, drift;
    for (const auto model : {MechanicsModel::uniform_fine, MechanicsModel::uniform_coarse,
                             MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
      {
        MechanicsParameters<1> p;
        p.lower[0]      = 0.;
        p.upper[0]      = 240.;
        p.coarse_dx     = 0.5;
        p.fine_dx       = 0.25;
        p.delta         = delta;
        p.model         = model;
        p.n_collocation = 0;
        p.initial_fine_region = [](const Point<1> &x) { return x[0] > 100. && x[0] < 140.; };
        Solver<1>  s(p);
        const auto g = [&](const double x) { return A * std::exp(-(x - x0) * (x - x0) / (w * w)); };
        s.set_initial_displacement([&](const Point<1> &x) { return Tensor<1, 1>({g(x[0])}); });
        s.set_initial_velocity([&](const Point<1> &x) {
          return Tensor<1, 1>({2. * (x[0] - x0) / (w * w) * g(x[0])});
        });
        const auto n = static_cast<unsigned int>(std::ceil(T / s.time_step()));
        s.set_time_step(T / n);
        const double P0 = s.momentum()[0], scale = momentum_scale(s);
        for (unsigned int k = 0; k < n; ++k)
          s.advance();
        drift[model] = std::abs(s.momentum()[0] - P0) / scale;
        double e     = 0.;
        for (const auto gr : {Solver<1>::coarse, Solver<1>::fine})
          for (unsigned int i = 0; i < s.n_nodes(gr); ++i)
            if (s.is_active(gr, i))
              {
                const double x = s.position(gr, i)[0];
                // The interval the pulse covers at T (the reference ignores the ends).
                if (x > 60. && x < 200.)
                  e = std::max(e, std::abs(s.displacement(gr, i)[0] - reference(x)));
              }
        error[model] = e / A;
        std::cout << "  info  " << to_string(model) << ": max |u - u_PD| / A = " << sci(e / A)
                  << ", |P(T) - P(0)| / sum rho V |v| = " << sci(drift[model]) << std::endl;
      }
    const double e_fine = error[MechanicsModel::uniform_fine],
                 e_coarse = error[MechanicsModel::uniform_coarse];
    // Standard scheme: quadrature error of m = 8 below that of m = 4, both
    // a modulus error of a few 1e-3 (1.1e-2 A ~ 30 eps max|g'| / A).
    check(e_fine < e_coarse && e_coarse < 2e-2,
          "uniform fine " + sci(e_fine) + " < uniform coarse " + sci(e_coarse) + " < 2e-2");
    check(drift[MechanicsModel::uniform_fine] < 1e-10 && drift[MechanicsModel::uniform_coarse] < 1e-10,
          "uniform grids conserve momentum to round-off");
    for (const auto m : {MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
      {
        // The pulse crosses the fine region: the multi-grid error may not
        // exceed the all-coarse one by more than 25 % (interface reflection
        // and interpolation).
        // The hybrid's coarse grid solves the local limit: its bound adds
        // the local-vs-PD difference.
        const double bound =
          1.25 * e_coarse + (m == MechanicsModel::adaptive_hybrid ? e_local : 0.);
        check(error[m] <= bound, to_string(m) + ": error " + sci(error[m]) + " <= " + sci(bound));
        // Momentum: the coupling is not pairwise (see mass_momentum);
        // measured 8.6e-4 (standard), 2.7e-4 (hybrid). Bound 2e-3.
        check(drift[m] < 2e-3, to_string(m) + ": momentum drift " + sci(drift[m]) + " < 2e-3");
      }
  }

  // Kalthoff-Winkler at CI size (delta = 8, dx+ = 2, dx- = 1; m+ = 4 is
  // the smallest horizon with the 49 collocation nodes of n_c = 49). The
  // reference is the uniform fine grid. At this horizon (8 % of the plate
  // width) the crack angle is 58.6 degrees, not the 68 of the experiment;
  // tutorial/step-11 compares with 68 at delta = 4.
  void
  kw()
  {
    struct Final
    {
      KalthoffWinkler::Result   r;
      std::vector<std::uint8_t> refined0, refined1;
      std::vector<double>       damage;
      double                    mass = 0.;
    };
    std::map<MechanicsModel, Final> res;
    for (const auto model : {MechanicsModel::uniform_fine, MechanicsModel::adaptive_standard,
                             MechanicsModel::adaptive_hybrid})
      {
        KalthoffWinkler kwp;
        kwp.model = model;
        Final &f  = res[model];
        f.r       = kwp.run([&](const Solver<2> &s) {
          if (s.step() == 0)
            {
              f.refined0 = s.refined_cells();
              return;
            }
          f.refined1 = s.refined_cells();
          f.mass     = s.active_mass();
          f.damage.clear();
          for (unsigned int i = 0; i < s.n_nodes(Solver<2>::fine); ++i)
            f.damage.push_back(s.is_active(Solver<2>::fine, i) ? s.damage(Solver<2>::fine, i) : 0.);
        });
        const auto &r = f.r;
        std::cout << "  info  " << to_string(model) << ": " << r.steps << " steps, angle " << r.angle
                  << " (" << r.crack_nodes << " nodes), length " << r.length << ", active coarse "
                  << r.coarse_begin << " -> " << r.coarse_end << ", fine " << r.fine_begin << " -> "
                  << r.fine_end << ", " << r.switches << " switches, " << r.seconds << " s" << std::endl;
        check_close(f.mass, 8e-9 * 100. * 200., 1e-13,
                    to_string(model) + ": active mass = plate mass at the end");
      }
    const auto &ref = res[MechanicsModel::uniform_fine];
    check(ref.r.crack_nodes > 100, "uniform fine: a crack grew (" +
                                     std::to_string(ref.r.crack_nodes) + " crack nodes)");

    // The uniform fine model is the library's standard scheme on the same
    // lattice (PeriDEAL::MechanicsSolver with BondBasedOperator, its own
    // force loop): same partial volumes, micromodulus, s0, time step and
    // Verlet steps, so the two runs differ only by round-off (summation
    // order, 1/|y| by rsqrt + Newton steps vs sqrt and division), which can
    // flip only bonds within a few ulp of s0 (measured: the same bonds
    // broke, max |damage difference| 4e-16).
    {
      const KalthoffWinkler kwp;
      const auto dir = std::filesystem::temp_directory_path() / "perideal-multiadapt-kw";
      auto p = kalthoff_winkler(kwp.fine_dx, kwp.delta, kwp.end_time, "standard", 0.95,
                                dir.string(), 100000000);
      p.time_step = kwp.end_time / ref.r.steps;
      PeriDEAL::MechanicsSolver<2> lib(MPI_COMM_WORLD, p);
      lib.setup();
      lib.run();
      const auto m = lib.measure();
      PeriDEAL::Vector phi;
      lib.discretization().initialize_vector(phi);
      lib.model().damage(phi);
      unsigned int differ = 0, damaged = 0;
      double       max_diff = 0.;
      for (unsigned int i = 0; i < lib.discretization().n_owned(); ++i)
        {
          const auto        &x = lib.discretization().position[i];
          const unsigned int f =
            std::lround((x[1] + 100.) / kwp.fine_dx - 0.5) * 100 + std::lround(x[0] / kwp.fine_dx - 0.5);
          const double d = std::abs(phi.local_element(i) - ref.damage[f]);
          damaged += ref.damage[f] > 0.2;
          differ += d > 0.2;
          max_diff = std::max(max_diff, d);
        }
      std::cout << "  info  library standard scheme: " << lib.integrator().step() << " steps, angle "
                << m.crack_angle << ", length " << m.crack_length << ", max |damage difference| "
                << max_diff << std::endl;
      check(lib.integrator().step() == ref.r.steps, "library run: the same number of steps");
      check(std::abs(m.crack_angle - ref.r.angle) < 0.1 && std::abs(m.crack_length - ref.r.length) < 1e-9,
            "uniform fine crack angle " + std::to_string(ref.r.angle) + " and length " +
              std::to_string(ref.r.length) + " = the library's " + std::to_string(m.crack_angle) +
              ", " + std::to_string(m.crack_length));
      check(differ <= damaged / 100, "uniform fine vs library: damage differs by > 0.2 at " +
                                       std::to_string(differ) + " of " + std::to_string(damaged) +
                                       " damaged nodes (<= 1 %)");
    }
    for (const auto model : {MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
      {
        const auto       &f    = res[model];
        const std::string name = to_string(model);
        // 3 degrees: about a third of the 68 +- 8 band of step-4; measured
        // 0.004 (standard) and 0.61 (hybrid).
        check(std::abs(f.r.angle - ref.r.angle) < 3., name + ": crack angle " +
                                                        std::to_string(f.r.angle) +
                                                        " within 3 deg of uniform fine");
        // Tip position: within 2 dx+ (catalog P1 item 10).
        check(std::abs(f.r.length - ref.r.length) <= 2. * 2.,
              name + ": crack length " + std::to_string(f.r.length) + " vs " +
                std::to_string(ref.r.length) + " within 2 dx+");
        // Damage maps: fine nodes whose damage differs by > 0.2, fewer than
        // 10 % of the reference's damaged nodes (measured 0.1-0.5 %).
        unsigned int differ = 0, damaged = 0;
        for (unsigned int i = 0; i < f.damage.size(); ++i)
          {
            damaged += ref.damage[i] > 0.2;
            differ += std::abs(f.damage[i] - ref.damage[i]) > 0.2;
          }
        check(differ < 0.1 * damaged, name + ": damage differs by > 0.2 at " +
                                        std::to_string(differ) + " of " + std::to_string(damaged) +
                                        " damaged nodes (< 10 %)");
        check(f.r.fine_end > f.r.fine_begin && f.r.coarse_end < f.r.coarse_begin,
              name + ": Omega- grew");
        // Growth along the cracks only: every newly refined cell lies within
        // 2 delta + dx+ of a node damaged in the reference (the switching
        // zone is H(x1) u H(x2) of a critical bond next to the crack).
        unsigned int new_cells = 0, far = 0;
        const double dmax = 2. * 8. + 2.;
        for (unsigned int c = 0; c < f.refined1.size(); ++c)
          if (f.refined1[c] && !f.refined0[c])
            {
              ++new_cells;
              const Point<2> xc(1. + 2. * (c % 50), -99. + 2. * (c / 50));
              bool           near = false;
              for (unsigned int i = 0; i < ref.damage.size() && !near; ++i)
                if (ref.damage[i] > 0.35)
                  near = xc.distance(Point<2>(0.5 + (i % 100), -99.5 + (i / 100))) <= dmax;
              far += !near;
            }
        check(new_cells > 0 && far == 0, name + ": " + std::to_string(new_cells) +
                                           " cells refined, " + std::to_string(far) +
                                           " farther than 2 delta + dx+ from the cracks");
      }
  }

  void
  bad_input()
  {
    auto p      = plate(MechanicsModel::adaptive_hybrid, Interpolation::inverse_distance);
    bool thrown = false;
    try
      {
        p.fine_dx = 0.8;
        Solver<2> s(p);
      }
    catch (const ParameterError &e)
      {
        thrown = e.parameter == "Fine grid spacing";
      }
    check(thrown, "dx+/dx- not an integer throws ParameterError 'Fine grid spacing'");
    thrown = false;
    try
      {
        parse_mechanics_model("adaptive fancy");
      }
    catch (const ParameterError &e)
      {
        thrown = e.parameter == "Model";
      }
    check(thrown, "an unknown model throws ParameterError 'Model'");
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const std::string                what = argc > 1 ? argv[1] : "";
  try
    {
      if (what == "patch")
        patch();
      else if (what == "mass_momentum")
        mass_momentum();
      else if (what == "conservative_coupling")
        conservative_coupling();
      else if (what == "wave")
        wave();
      else if (what == "kw")
        kw();
      else if (what == "bad_input")
        bad_input();
      else if (what == "incremental_switch")
        incremental_switch();
      else
        {
          std::cerr << "usage: multiadapt_tests patch|mass_momentum|conservative_coupling|wave|kw|bad_input|incremental_switch" << std::endl;
          return 2;
        }
    }
  catch (const std::exception &e)
    {
      std::cerr << "exception: " << e.what() << std::endl;
      return 1;
    }
  return failures() == 0 ? 0 : 1;
}
