// Tests of the adaptive hybrid configuration (dissertation Sect. 3.3) for
// bond-based fracture: standard PMB on Omega_s, WLS-2 collocation of the
// linearized bond force on Omega_w, switching by (3.80).
//  patch:     linear fields give zero force in the bulk and quadratic
//             fields the closed-form PD force int c xi(x)xi/|xi|^3 u dV on
//             the WLS nodes (WLS-2 is exact for quadratics);
//  kw:        the Kalthoff-Winkler run at CI size against the uniform
//             standard scheme (damage, crack length and angle; Omega_s grows
//             only near the crack);
//  rank_invariance: 1 vs 2 ranks give the same Omega_s and damage (full-
//             and half-stencil Omega_s rows);
//  bad_input: ParameterError for bad Hybrid entries;
//  stretch_budget: the bound of StretchBudget (stretch_budget_test.h);
//  kw_classes: amortized = every-step test with two bond length classes
//             (StretchBudget);
//  kw_lattice: amortized = every-step test with the lattice bound (and
//             fewer exact node tests than with StretchBudget);
//  kw_equivalence: the fast switching test = the exact test of every bond
//             at every step (KW at CI size, 1 or 2 ranks);
//  grouped_test: the exact test's kernel grouped by bond length = the
//             per-offset masked kernel (the same exact node tests too);
//  row_test:  the same with the grouped kernel's loads shared along the
//             stencil rows (row_shared_test);
//  lattice_order: nodes numbered by lattice index = numbered by cells
//             (bit for bit, 1 or 2 ranks);
//  half_stencil: the half-stencil Omega_s sweep = the full-stencil rows
//             (broken bonds, switching, damage; forces to round-off);
//  initial_fraction: the initial Omega_s (pre-cracks and boundaries) at the
//             source's horizon delta = 2 mm covers the source's 9.72 % of
//             the plate (Table 3.3), and twice that at delta = 4 mm.

#include <deal.II/base/mpi.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/models/hybrid_bond_based.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include "../check.h"
#include "kalthoff_winkler_case.h"
#include "stretch_budget_test.h"

#include <functional>
#include <map>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  // The 40 x 40 box of (a), (d) and (i): dx = 1, delta = 4 (m = 4),
  // cell-centred.
  constexpr double box_size = 40.;
  LatticeParameters
  setup_box(Discretization<2> &disc)
  {
    LatticeParameters lp;
    lp.dx            = 1.;
    lp.delta         = 4.;
    lp.cell_centered = true;
    disc.setup(BoxDomain<2>(Point<2>(0., 0.), Point<2>(box_size, box_size)), lp);
    return lp;
  }

  // (a) Patch test on a 40 x 40 box, dx = 1, delta = 4 (m = 4), E = 1,
  // plane strain, no breaking. Omega_s = the band of width delta along the
  // boundary plus the left half, so bulk nodes of both schemes exist.
  void
  patch()
  {
    Discretization<2>       disc(MPI_COMM_WORLD);
    const LatticeParameters lp = setup_box(disc);
    const double            L  = box_size;
    BondBasedModelParameters mp;
    mp.plane_stress = false;
    BondBasedOperator<2> op(disc, mp);
    std::vector<bool>    standard(disc.n_owned());
    const auto           boundary_distance = [&](const Point<2> &x) {
      return std::min(std::min(x[0], L - x[0]), std::min(x[1], L - x[1]));
    };
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      standard[i] = boundary_distance(disc.position[i]) < lp.delta || disc.position[i][0] < L / 2;
    HybridMechanicsParameters hp;
    HybridBondBasedModel<2>   model(op, InfluenceFunction::constant, hp, standard);
    const double              c = op.micromodulus(), delta = lp.delta;

    MechanicsModel<2>::VectorField u, f;
    model.initialize(u);
    model.initialize(f);
    const auto evaluate = [&](const std::function<Tensor<1, 2>(const Point<2> &)> &field) {
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int d = 0; d < 2; ++d)
          u[d].local_element(i) = field(disc.position[i])[d];
      for (auto &v : u)
        v.update_ghost_values();
      model.compute_forces(u, f);
    };
    // Bulk: the full family (delta + dx/2 with partial volumes) inside.
    const auto bulk = [&](const unsigned int i) {
      return boundary_distance(disc.position[i]) > delta + lp.dx;
    };

    // Linear field u = H x (stretch, shear and rotation): the PD force
    // vanishes in the bulk. Scale: c |H| delta^3, the force of one half
    // of a horizon.
    const double H[2][2] = {{1e-3, 4e-4}, {-2e-4, 6e-4}};
    evaluate([&](const Point<2> &x) {
      return Tensor<1, 2>({H[0][0] * x[0] + H[0][1] * x[1], H[1][0] * x[0] + H[1][1] * x[1]});
    });
    const double scale = c * 1e-3 * std::pow(delta, 3);
    double       max_f[2] = {0., 0.};
    unsigned int n[2]     = {0, 0};
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (bulk(i))
        {
          const unsigned int s = model.scheme().local_element(i) > 0.5; // 1: WLS
          ++n[s];
          max_f[s] = std::max(max_f[s], std::hypot(f[0].local_element(i), f[1].local_element(i)));
        }
    for (unsigned int s = 0; s < 2; ++s)
      {
        max_f[s] = Utilities::MPI::max(max_f[s], MPI_COMM_WORLD);
        n[s]     = Utilities::MPI::sum(n[s], MPI_COMM_WORLD);
      }
    check(n[0] > 50 && n[1] > 50, "bulk nodes: " + std::to_string(n[0]) + " standard, " +
                                    std::to_string(n[1]) + " WLS");
    // Round-off of sums of O(scale) terms (the WLS weights are O(c delta),
    // with cancellation over 29 nodes; the PMB force cancels in +-xi pairs).
    check(max_f[1] <= 1e-9 * scale, "linear field, WLS bulk nodes: max |F| = " + sci(max_f[1]) +
                                      " <= 1e-9 c |H| delta^3 = " + sci(1e-9 * scale));
    check(max_f[0] <= 1e-9 * scale, "linear field, standard bulk nodes: max |F| = " +
                                      sci(max_f[0]) + " <= 1e-9 c |H| delta^3");

    // Quadratic field u = (a x^2 / 2, b x^2 / 2): the linearized PD force
    // over the full ball is, in polar coordinates (omega = 1),
    // F_x = (c a / 2) int_0^delta r^2 dr int cos^4 = c a pi delta^3 / 8,
    // F_y = (c b / 2) int_0^delta r^2 dr int cos^2 sin^2 = c b pi delta^3 / 24,
    // independently of x. WLS-2 reproduces quadratics exactly, so the WLS
    // nodes must match to round-off (relative to the x^2 values, which grow
    // to L^2 = 1600 times the curvature term: tolerance 1e-8).
    const double a = 2e-5, b = -3e-5;
    evaluate([&](const Point<2> &x) {
      return Tensor<1, 2>({0.5 * a * x[0] * x[0], 0.5 * b * x[0] * x[0]});
    });
    const double Fx = c * a * M_PI * std::pow(delta, 3) / 8.,
                 Fy = c * b * M_PI * std::pow(delta, 3) / 24.;
    double err[2] = {0., 0.};
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (bulk(i))
        {
          const unsigned int s = model.scheme().local_element(i) > 0.5;
          err[s] = std::max(err[s], std::hypot(f[0].local_element(i) - Fx, f[1].local_element(i) - Fy));
        }
    for (double &e : err)
      e = Utilities::MPI::max(e, MPI_COMM_WORLD) / std::hypot(Fx, Fy);
    check(err[1] <= 1e-8, "quadratic field, WLS bulk nodes: max |F - F_exact| / |F_exact| = " +
                            sci(err[1]) + " <= 1e-8");
    // The standard scheme is only a quadrature of the same integral (partial
    // volumes at m = 4, PMB nonlinearity O(strain)): printed, and bounded by
    // the few-percent quadrature error known for m = 4.
    check(err[0] <= 0.1, "quadratic field, standard bulk nodes (quadrature error): " +
                           sci(err[0]) + " <= 0.1");
  }

  // Damage of the owned nodes keyed by node id.
  // (d) The lattice sweeps against the row loops: on the patch of (a)
  // (s0 = infinity, no breaking) with a smooth random-phase displacement,
  // (i) the shared weights of the interior collocation pattern equal each
  // row's own WLS weights (from its own fit) to round-off, (ii) the forces
  // of the shared-pattern WLS rows equal sum_c W_ic u_c over the row's own
  // CSR weights, (iii) the forces of the Omega_s rows equal the
  // BondBasedOperator's (its own loops) up to summation-order round-off.
  void
  sweep()
  {
    Discretization<2>       disc(MPI_COMM_WORLD);
    const LatticeParameters lp = setup_box(disc);
    const double            L  = box_size;
    BondBasedModelParameters mp;
    BondBasedOperator<2>     op(disc, mp);
    std::vector<bool>        standard(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const auto &x = disc.position[i];
        standard[i]   = x[0] < L / 2 || std::min(std::min(x[0], L - x[0]), std::min(x[1], L - x[1])) <
                                        lp.delta;
      }
    HybridBondBasedModel<2> model(op, InfluenceFunction::constant, HybridMechanicsParameters(),
                                  standard);
    if (!model.uses_lattice_sweep())
      {
        if (root())
          std::cout << "  lattice sweep not compiled (no AVX-512): nothing to compare" << std::endl;
        return;
      }
    const auto &wls = model.wls_quadrature();
    const auto &W   = model.shared_pattern_weights();
    double      w_max = 0.;
    for (const double w : W)
      w_max = std::max(w_max, std::abs(w));
    unsigned int n_shared = 0, size_differs = 0;
    double       weight_diff = 0.;
    for (unsigned int k = 0; k < wls.node.size(); ++k)
      if (model.uses_shared_pattern(wls.node[k]))
        {
          ++n_shared;
          const auto begin = 4 * wls.row_start[k];
          size_differs += 4 * wls.row_start[k + 1] - begin != W.size();
          for (std::size_t e = 0; e < W.size() && e < 4 * wls.row_start[k + 1] - begin; ++e)
            weight_diff = std::max(weight_diff, std::abs(wls.weight[begin + e] - W[e]));
        }
    n_shared    = Utilities::MPI::sum(n_shared, MPI_COMM_WORLD);
    weight_diff = Utilities::MPI::max(weight_diff, MPI_COMM_WORLD) / w_max;
    size_differs = Utilities::MPI::sum(size_differs, MPI_COMM_WORLD);
    check(n_shared > 100 && W.size() == 4 * 29 && size_differs == 0,
          std::to_string(n_shared) + " WLS rows share the interior pattern of 29 nodes");
    check(weight_diff <= 1e-12,
          "shared vs own WLS weights: max |W_shared - W_i| / max |W| = " + sci(weight_diff) +
            " <= 1e-12 (round-off of the per-node fits)");

    MechanicsModel<2>::VectorField u, f, g;
    model.initialize(u);
    model.initialize(f);
    model.initialize(g);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const auto &x = disc.position[i];
        u[0].local_element(i) = 1e-3 * std::sin(0.3 * x[0] + 0.7 * x[1] + 0.1);
        u[1].local_element(i) = 1e-3 * std::cos(0.5 * x[0] - 0.2 * x[1]);
      }
    for (auto &v : u)
      v.update_ghost_values();
    model.compute_forces(u, f);
    op.compute_forces(u, g);
    double wls_diff = 0., std_diff = 0., f_max = 0.;
    for (unsigned int k = 0; k < wls.node.size(); ++k)
      {
        const unsigned int i = wls.node[k];
        double             F[2] = {0., 0.};
        for (auto e = wls.row_start[k]; e < wls.row_start[k + 1]; ++e)
          for (unsigned int a = 0; a < 2; ++a)
            for (unsigned int b = 0; b < 2; ++b)
              F[a] += wls.weight[4 * e + 2 * a + b] * u[b].local_element(wls.col[e]);
        for (unsigned int a = 0; a < 2; ++a)
          {
            wls_diff = std::max(wls_diff, std::abs(F[a] - f[a].local_element(i)));
            f_max    = std::max(f_max, std::abs(F[a]));
          }
      }
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (model.scheme().local_element(i) < 0.5)
        for (unsigned int a = 0; a < 2; ++a)
          {
            std_diff = std::max(std_diff, std::abs(f[a].local_element(i) - g[a].local_element(i)));
            f_max    = std::max(f_max, std::abs(g[a].local_element(i)));
          }
    f_max    = Utilities::MPI::max(f_max, MPI_COMM_WORLD);
    wls_diff = Utilities::MPI::max(wls_diff, MPI_COMM_WORLD) / f_max;
    std_diff = Utilities::MPI::max(std_diff, MPI_COMM_WORLD) / f_max;
    // Sums of ~30 (WLS) and ~50 (PMB) terms of size up to the forces'
    // scale in another order, and 1/l by rsqrt and Newton steps: 1e-12.
    check(wls_diff <= 1e-12, "WLS sweep rows vs own-weight rows: max |dF| / max |F| = " +
                               sci(wls_diff) + " <= 1e-12");
    check(std_diff <= 1e-12, "standard sweep rows vs BondBasedOperator: max |dF| / max |F| = " +
                               sci(std_diff) + " <= 1e-12");
  }

  // (i) The half-stencil Omega_s sweep (HybridMechanicsParameters::
  // half_stencil, each bond once with its reaction) against the full-stencil
  // rows on the box of (d) with breaking (s0 = 0.01): a ragged Omega_s
  // (a slanted half, the boundary band and isolated nodes inside Omega_w)
  // and a displacement jump across y = 20.3 whose height grows with x, so
  // that some crossing bonds break and others do not. Two evaluations (the
  // second after breaking and switching): the same broken bonds, switched
  // nodes and damage, forces equal up to the summation order.
  void
  half_stencil()
  {
    Discretization<2>       disc(MPI_COMM_WORLD);
    const LatticeParameters lp = setup_box(disc);
    const double            L  = box_size;
    BondBasedModelParameters mp;
    mp.critical_stretch = 0.01;
    std::vector<bool> standard(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const auto &x = disc.position[i];
        standard[i]   = x[0] + 0.7 * x[1] < 23. ||
                      std::min(std::min(x[0], L - x[0]), std::min(x[1], L - x[1])) < lp.delta ||
                      disc.id[i] % 37 == 0;
      }
    BondBasedOperator<2> op_half(disc, mp), op_full(disc, mp);
    HybridMechanicsParameters hp;
    hp.sigma        = 0.8;
    hp.half_stencil = true;
    HybridBondBasedModel<2> half(op_half, InfluenceFunction::constant, hp, standard);
    hp.half_stencil = false;
    HybridBondBasedModel<2> full(op_full, InfluenceFunction::constant, hp, standard);
    if (!half.uses_lattice_sweep())
      {
        if (root())
          std::cout << "  lattice sweep not compiled (no AVX-512): nothing to compare" << std::endl;
        return;
      }
    MechanicsModel<2>::VectorField u, f, g;
    half.initialize(u);
    half.initialize(f);
    half.initialize(g);
    for (const double amplitude : {1., 1.6})
      {
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          {
            const auto &x = disc.position[i];
            u[0].local_element(i) =
              amplitude * (1e-3 * std::sin(0.3 * x[0] + 0.7 * x[1]) + (x[1] > 20.3 ? 3e-2 * x[0] / L : 0.));
            u[1].local_element(i) = amplitude * 1e-3 * std::cos(0.5 * x[0] - 0.2 * x[1]);
          }
        for (auto &v : u)
          v.update_ghost_values();
        half.compute_forces(u, f);
        full.compute_forces(u, g);
        double       diff = 0., f_max = 0.;
        unsigned int scheme_differ = 0;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          {
            scheme_differ += half.scheme().local_element(i) != full.scheme().local_element(i);
            for (unsigned int a = 0; a < 2; ++a)
              {
                diff  = std::max(diff, std::abs(f[a].local_element(i) - g[a].local_element(i)));
                f_max = std::max(f_max, std::abs(g[a].local_element(i)));
              }
          }
        diff = Utilities::MPI::max(diff, MPI_COMM_WORLD) / Utilities::MPI::max(f_max, MPI_COMM_WORLD);
        scheme_differ = Utilities::MPI::sum(scheme_differ, MPI_COMM_WORLD);
        const auto  &bh = half.broken(), &bf = full.broken();
        unsigned int flags_differ = Utilities::MPI::sum(unsigned(bh != bf), MPI_COMM_WORLD);
        PeriDEAL::Vector dh, df;
        disc.initialize_vector(dh);
        disc.initialize_vector(df);
        half.damage(dh);
        full.damage(df);
        double damage_diff = 0., damage_max = 0.;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          {
            damage_diff = std::max(damage_diff, std::abs(dh.local_element(i) - df.local_element(i)));
            damage_max  = std::max(damage_max, df.local_element(i));
          }
        damage_diff = Utilities::MPI::max(damage_diff, MPI_COMM_WORLD);
        damage_max  = Utilities::MPI::max(damage_max, MPI_COMM_WORLD);
        const std::string at = " (amplitude " + std::to_string(amplitude) + ")";
        check(full.n_standard_nodes() == half.n_standard_nodes() && scheme_differ == 0 &&
                half.n_switch_events() == full.n_switch_events(),
              "Omega_s: " + std::to_string(half.n_standard_nodes()) + " nodes, " +
                std::to_string(half.n_switch_events()) + " switch events, " +
                std::to_string(scheme_differ) + " nodes differ" + at);
        check(flags_differ == 0 && half.n_broken_bonds() == full.n_broken_bonds() &&
                half.n_broken_bonds() > 0,
              "broken bonds: " + std::to_string(half.n_broken_bonds()) + " (half stencil) / " +
                std::to_string(full.n_broken_bonds()) + " (full), flags identical" + at);
        check(damage_diff == 0. && damage_max > 0.,
              "max |damage difference| = " + sci(damage_diff) + ", max damage " + sci(damage_max) + at);
        // Sums of up to 50 terms in another order (the PMB forces cancel in
        // +-xi pairs, so round-off is relative to the bond forces).
        check(diff <= 1e-12, "half vs full stencil: max |dF| / max |F| = " + sci(diff) + " <= 1e-12" + at);
      }
  }

  std::map<types::particle_index, double>
  damage_by_id(const MechanicsSolver<2> &s)
  {
    PeriDEAL::Vector phi;
    s.discretization().initialize_vector(phi);
    s.model().damage(phi);
    std::map<types::particle_index, double> m;
    for (unsigned int i = 0; i < s.discretization().n_owned(); ++i)
      m[s.discretization().id[i]] = phi.local_element(i);
    return m;
  }

  // Amortized (StretchBudget) vs every-step test of (3.80), both run: the
  // same node switches at the same force evaluation, hence bitwise the same
  // run; and at most @p max_ratio of the exact node tests are run.
  void
  check_same_as_every_step(const MechanicsSolver<2> &hybrid,
                           const MechanicsSolver<2> &every,
                           const double              max_ratio)
  {
    const auto *hm   = hybrid.hybrid_model();
    const auto *he   = every.hybrid_model();
    const auto &disc = hybrid.discretization();
    std::map<types::particle_index, int> every_switch;
    for (unsigned int i = 0; i < every.discretization().n_owned(); ++i)
      every_switch[every.discretization().id[i]] = he->switch_evaluation()[i];
    unsigned int differ = 0, n_switched = 0;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        differ += hm->switch_evaluation()[i] != every_switch.at(disc.id[i]);
        n_switched += hm->switch_evaluation()[i] >= 0;
      }
    const auto dh = damage_by_id(hybrid), de = damage_by_id(every);
    double     damage_diff = 0.;
    for (const auto &[id, d] : dh)
      damage_diff = std::max(damage_diff, std::abs(d - de.at(id)));
    check(n_switched > 0 && differ == 0 && hm->n_switch_events() == he->n_switch_events() &&
            hm->n_overstretched_bonds() == he->n_overstretched_bonds(),
          "amortized switching test: " + std::to_string(n_switched) +
            " switched nodes, each at the same force evaluation as with the every-step test (" +
            std::to_string(differ) + " differ; " + std::to_string(hm->n_switch_events()) + " / " +
            std::to_string(he->n_switch_events()) + " switch events)");
    check(damage_diff == 0. &&
            hybrid.model().n_broken_bonds() == every.model().n_broken_bonds(),
          "amortized vs every-step: max |damage difference| = " + sci(damage_diff) +
            ", broken bonds " + std::to_string(hybrid.model().n_broken_bonds()) + " / " +
            std::to_string(every.model().n_broken_bonds()));
    // The point of the bound: exact node tests are skipped.
    check(double(hm->n_exact_node_tests()) < max_ratio * double(he->n_exact_node_tests()),
          "exact node tests of (3.80): " + std::to_string(hm->n_exact_node_tests()) +
            " (amortized) vs " + std::to_string(he->n_exact_node_tests()) + " (every step)");
  }

  // (b) KW at CI size: dx = 1 mm, delta = 4 mm (m = 4, 20,000 nodes), to
  // 87.5 us, the same time step for both (0.9 x the hybrid's bound, which
  // is the smaller one). Serial.
  void
  kw()
  {
    const double dx = 1., delta = 4., T = 87.5e-6;
    auto         ph = kalthoff_winkler(dx, delta, T, "hybrid adaptive", 0.8, "kw-hybrid");
    MechanicsSolver<2> hybrid(MPI_COMM_SELF, ph);
    hybrid.setup();
    auto ps      = kalthoff_winkler(dx, delta, T, "standard", 0.8, "kw-standard");
    ps.time_step = hybrid.integrator().time_step();
    MechanicsSolver<2> standard(MPI_COMM_SELF, ps);
    // The reference of the amortized switching test: (3.80) on every bond
    // at every step.
    auto pe                   = ph;
    pe.hybrid.switching_bound = false;
    pe.output_directory       = "kw-hybrid-every-step";
    MechanicsSolver<2> every(MPI_COMM_SELF, pe);
    const auto        &disc = hybrid.discretization();
    const auto        *hm   = hybrid.hybrid_model();
    std::vector<bool>  initial_wls(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      initial_wls[i] = hm->scheme().local_element(i) > 0.5;
    const double initial_fraction = hm->standard_fraction();
    hybrid.run();
    every.run();
    standard.run();
    const auto mh = hybrid.measure(), ms = standard.measure();
    const auto dh = damage_by_id(hybrid), ds = damage_by_id(standard);
    // Most exact node tests skipped (measured: 6.2 % of the every-step count
    // with the lattice bound, 22 % with StretchBudget, i.e. without AVX-512).
    check_same_as_every_step(hybrid, every, 0.25);
    if (root())
      std::cout << "  KW dx = 1, m = 4, " << disc.n_global() << " nodes, "
                << hybrid.integrator().step() << " steps: Omega_s " << 100. * initial_fraction
                << "% -> " << 100. * hm->standard_fraction() << "%, stepping "
                << standard.stepping_wall_time() << " s (standard) / "
                << hybrid.stepping_wall_time() << " s (hybrid), "
                << every.stepping_wall_time() << " s (hybrid, every-step test); switch events "
                << hm->n_switch_events() << "\n  crack angle " << ms.crack_angle << " / "
                << mh.crack_angle << " deg, length " << ms.crack_length << " / "
                << mh.crack_length << " mm, broken bonds " << standard.model().n_broken_bonds()
                << " / " << hybrid.model().n_broken_bonds() << std::endl;

    check(hm->n_overstretched_bonds() == 0,
          "no bond exceeded s0 while in Omega_w (sigma = 0.8): " +
            std::to_string(hm->n_overstretched_bonds()));
    check(hm->standard_fraction() > initial_fraction && hm->n_switch_events() > 0,
          "Omega_s grew with the crack");
    // Damage maps: a node cracked (damage >= 0.35) in one run should have a
    // cracked node of the other run within 2 dx (the suggested KW check of
    // the source catalogue: crack positions within 2 dx). The two are
    // different discretizations of Omega_w (WLS on the full ball vs partial
    // volumes, linearized vs PMB force), so the crack bands differ in their
    // flank nodes, which is what 2 dx allows.
    std::vector<Point<2>> cracked[2];
    // Away from the impacted and the far edge (2 delta): there the coarse
    // (m = 4) standard run also damages the impacted column and spalls at
    // the free edge (the source notes a secondary crack opposite the impact
    // for its uniform coarse run only), which the hybrid does not.
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double x = disc.position[i][0];
        if (x < 2. * delta || x > 100. - 2. * delta)
          continue;
        if (ds.at(disc.id[i]) >= 0.35)
          cracked[0].push_back(disc.position[i]);
        if (dh.at(disc.id[i]) >= 0.35)
          cracked[1].push_back(disc.position[i]);
      }
    unsigned int unmatched[2] = {0, 0};
    for (unsigned int r = 0; r < 2; ++r)
      for (const auto &x : cracked[r])
        {
          bool near = false;
          for (const auto &y : cracked[1 - r])
            near = near || x.distance(y) <= 2. * dx * (1. + 1e-12);
          unmatched[r] += !near;
        }
    check(cracked[0].size() > 100 && unmatched[0] <= 0.03 * cracked[0].size() &&
            unmatched[1] <= 0.03 * cracked[1].size(),
          "damage maps: " + std::to_string(unmatched[0]) + " of " +
            std::to_string(cracked[0].size()) + " cracked nodes (standard) and " +
            std::to_string(unmatched[1]) + " of " + std::to_string(cracked[1].size()) +
            " (hybrid) farther than 2 dx from a cracked node of the other run (<= 3%)");
    check_close(double(hybrid.model().n_broken_bonds()), double(standard.model().n_broken_bonds()),
                0.05, "broken bonds (5%: the crack band, same reason)");
    check_close(mh.crack_length, ms.crack_length, 0., "crack length (within 2 dx)", 2. * dx);
    // The crack angle fits a line to a band 2-3 nodes wide over 25-50 mm
    // (6-12 mm of which at dx = 2 are near the tip): a one-node shift of the
    // far end moves it by ~atan(2/30) = 4 deg; allow 6 deg (the source
    // shows agreement of the maps only graphically).
    check_close(mh.crack_angle, ms.crack_angle, 0., "crack angle (6 deg)", 6.);

    // Omega_s grows only near fracture: every switched node lies within
    // 2 delta of a node damaged (> 0) in the hybrid or in the standard run.
    // (3.80) switches at sigma s0 = 0.8 s0, so tension that nearly breaks
    // bonds (the reflection from the far edge, where the coarse standard run
    // spalls) switches too; anything farther would be a spurious switch.
    std::vector<Point<2>> damaged;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (dh.at(disc.id[i]) > 0. || ds.at(disc.id[i]) > 0.)
        damaged.push_back(disc.position[i]);
    unsigned int far = 0, beyond = 0, switched = 0;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (initial_wls[i] && hm->scheme().local_element(i) < 0.5)
        {
          ++switched;
          double dmin = 1e300;
          for (const auto &q : damaged)
            dmin = std::min(dmin, q.distance(disc.position[i]));
          far += dmin > 2. * delta;
          beyond += dmin > 3. * delta;
        }
    // Measured: 10 of 3490 switched nodes lie 2-2.3 delta from damage, next
    // to the far-edge tension zone; none beyond 3 delta.
    check(switched > 0 && far <= 0.01 * switched && beyond == 0,
          std::to_string(switched) + " switched nodes, " + std::to_string(far) +
            " farther than 2 delta from damage in either run (<= 1%), " + std::to_string(beyond) +
            " farther than 3 delta (none)");
  }

  // (c) The same run to 50 us on MPI_COMM_WORLD and on rank 0 alone: the
  // same Omega_s and the same damage per node.
  // With the full-stencil Omega_s rows and with the half-stencil sweep
  // (@p half_stencil).
  void
  rank_invariance_with(const bool half_stencil)
  {
    const double dx = 2., delta = 8., T = 50e-6;
    const auto   parameters = [&](const std::string &dir) {
      auto p                = kalthoff_winkler(dx, delta, T, "hybrid adaptive", 0.8, dir);
      p.hybrid.half_stencil = half_stencil;
      return p;
    };
    if (root())
      std::cout << "  Omega_s rows: " << (half_stencil ? "half" : "full") << " stencil" << std::endl;
    MechanicsSolver<2> dist(MPI_COMM_WORLD, parameters("ri-dist"));
    dist.run();
    // (id, damage, scheme) of every node, gathered on rank 0.
    std::vector<double> mine;
    const auto          dd = damage_by_id(dist);
    for (unsigned int i = 0; i < dist.discretization().n_owned(); ++i)
      {
        const auto id = dist.discretization().id[i];
        mine.insert(mine.end(),
                    {double(id), dd.at(id), dist.hybrid_model()->scheme().local_element(i)});
      }
    const auto   all = Utilities::MPI::gather(MPI_COMM_WORLD, mine, 0);
    const auto   n_standard = dist.hybrid_model()->n_standard_nodes();
    const auto   n_broken   = dist.model().n_broken_bonds();
    const auto   events     = dist.hybrid_model()->n_switch_events();
    if (!root())
      return;
    MechanicsSolver<2> serial(MPI_COMM_SELF, parameters("ri-serial"));
    serial.run();
    check(events > 0 && n_standard == serial.hybrid_model()->n_standard_nodes(),
          "Omega_s nodes: " + std::to_string(n_standard) + " (distributed, " +
            std::to_string(events) + " switch events) = " +
            std::to_string(serial.hybrid_model()->n_standard_nodes()) + " (serial)");
    check(n_broken == serial.model().n_broken_bonds() && n_broken > 0,
          "broken bonds: " + std::to_string(n_broken) + " = " +
            std::to_string(serial.model().n_broken_bonds()));
    const auto ds = damage_by_id(serial);
    std::map<types::particle_index, double> serial_scheme;
    for (unsigned int i = 0; i < serial.discretization().n_owned(); ++i)
      serial_scheme[serial.discretization().id[i]] =
        serial.hybrid_model()->scheme().local_element(i);
    double       diff = 0.;
    unsigned int scheme_diff = 0, n = 0;
    for (const auto &part : all)
      for (std::size_t k = 0; k < part.size(); k += 3, ++n)
        {
          const auto id = types::particle_index(part[k]);
          diff          = std::max(diff, std::abs(part[k + 1] - ds.at(id)));
          scheme_diff += part[k + 2] != serial_scheme.at(id);
        }
    check(n == serial.discretization().n_global(), "every node compared");
    check(scheme_diff == 0, "scheme per node identical (" + std::to_string(scheme_diff) + " differ)");
    // Same bonds broken (bitwise the same stretches): identical damage.
    check(diff == 0., "max |damage_dist - damage_serial| = " + sci(diff));
  }

  void
  rank_invariance()
  {
    rank_invariance_with(false);
    rank_invariance_with(true);
  }

  void
  bad_input()
  {
    const auto expect = [](const std::function<void()> &f, const std::string &name) {
      bool thrown = false;
      try
        {
          f();
        }
      catch (const ParameterError &e)
        {
          thrown = std::string(e.what()).find(name) != std::string::npos;
        }
      check(thrown, "ParameterError naming '" + name + "'");
    };
    const auto solver = [](const MechanicsRunParameters<2> &p) {
      MechanicsSolver<2> s(MPI_COMM_SELF, p);
      s.setup();
    };
    auto p = kalthoff_winkler(4., 8., 1e-6, "hybrid adaptive", 1.5, "bad");
    expect([&] { solver(p); }, "Sigma");
    p                       = kalthoff_winkler(4., 8., 1e-6, "hybrid adaptive", 0.9, "bad");
    p.hybrid.check_interval = 0;
    expect([&] { solver(p); }, "Switching interval");
    p              = kalthoff_winkler(4., 8., 1e-6, "hybrid adaptive", 0.9, "bad");
    p.model.linearized = true;
    expect([&] { solver(p); }, "Linearized");
    p                 = kalthoff_winkler(4., 8., 1e-6, "hybrid adaptive", 0.9, "bad");
    p.standard_region = "x +";
    expect([&] { solver(p); }, "Standard region");
    // m = 2: fewer than 29 nodes in a horizon.
    p = kalthoff_winkler(4., 8., 1e-6, "hybrid adaptive", 0.9, "bad");
    expect([&] { solver(p); }, "collocation");
  }

  // (e) Two bond length classes (m = 6.4 > 4: bonds up to 4 dx and longer
  // ones), which test only the bonds of the class whose bound fired: the
  // same run as the every-step test, and fewer bond tests than whole rows.
  // The KW case of (e) and (g): dx = 1.25, delta = 8 (m = 6.4), to
  // 87.5 us, output in @p dir; and the same with the every-step test.
  std::pair<MechanicsRunParameters<2>, MechanicsRunParameters<2>>
  kw_long_bonds(const std::string &dir, const bool lattice_bound)
  {
    auto ph = kalthoff_winkler(1.25, 8., 87.5e-6, "hybrid adaptive", 0.8, dir);
    ph.hybrid.lattice_bound   = lattice_bound;
    auto pe                   = ph;
    pe.hybrid.switching_bound = false;
    pe.output_directory       = dir + "-every-step";
    return {ph, pe};
  }

  void
  kw_classes()
  {
    const auto [ph, pe] = kw_long_bonds("kw-classes", false);
    MechanicsSolver<2> hybrid(MPI_COMM_SELF, ph), every(MPI_COMM_SELF, pe);
    hybrid.run();
    every.run();
    // At this coarse lattice (8 x 16 blocks of the long class over the
    // plate) the wave fronts cover a larger part of the blocks: measured
    // 0.39. The equivalence is the point here.
    check_same_as_every_step(hybrid, every, 0.5);
    const auto  *hm      = hybrid.hybrid_model();
    const auto  &nb      = hybrid.discretization().neighborhood;
    const double stencil = double(nb.stencil_size);
    // (The portable row loop, without AVX-512, tests whole rows.)
    if (hm->uses_lattice_sweep())
      check(hm->n_exact_bond_tests() < 0.9 * stencil * double(hm->n_exact_node_tests()),
            "bond tests per exact node test: " +
              std::to_string(double(hm->n_exact_bond_tests()) / double(hm->n_exact_node_tests())) +
              " of a stencil of " + std::to_string(nb.stencil_size) + " (classes tested apart)");
  }

  // (g) The lattice bound (default in 2D sweeps) on the case of (e): the
  // same run as the every-step test, and fewer exact node tests than
  // StretchBudget's classes there.
  void
  kw_lattice()
  {
    const auto [ph, pe] = kw_long_bonds("kw-lattice", true);
    MechanicsSolver<2> hybrid(MPI_COMM_SELF, ph), every(MPI_COMM_SELF, pe);
    auto               pb   = ph;
    pb.hybrid.lattice_bound = false;
    pb.output_directory     = "kw-lattice-budget";
    MechanicsSolver<2> budget(MPI_COMM_SELF, pb);
    hybrid.run();
    every.run();
    budget.run();
    const auto *hm = hybrid.hybrid_model(), *hb = budget.hybrid_model();
    // Measured: 12 % of the every-step count (StretchBudget: 39 %, the
    // bound without AVX-512).
    check_same_as_every_step(hybrid, every, hm->uses_lattice_sweep() ? 0.2 : 0.5);
    if (hm->uses_lattice_sweep())
      check(hm->n_exact_node_tests() < hb->n_exact_node_tests(),
            "exact node tests: " + std::to_string(hm->n_exact_node_tests()) +
              " (lattice bound) vs " + std::to_string(hb->n_exact_node_tests()) +
              " (StretchBudget)");
  }

  /**
   * KW at CI size (dx = 1 mm, delta = 4 mm, 20,000 nodes, sigma = 0.8) on
   * MPI_COMM_WORLD with two variants of the hybrid's parameters (@p a is
   * the path under test, @p b the reference): checks per node the same
   * switch evaluation (hence the same switched set), the same switch
   * events, broken and overstretched bonds, bitwise the same damage and
   * displacement. Output below @p dir. Returns the exact node tests of (a,
   * b).
   */
  std::pair<std::uint64_t, std::uint64_t>
  check_kw_same_run(const std::function<void(MechanicsRunParameters<2> &)> &a,
                    const std::function<void(MechanicsRunParameters<2> &)> &b,
                    const std::string &reference, const std::string &dir)
  {
    const double dx = 1., delta = 4., T = 87.5e-6;
    auto         pf = kalthoff_winkler(dx, delta, T, "hybrid adaptive", 0.8, dir);
    auto         pe = pf;
    pe.output_directory = dir + "-reference";
    a(pf);
    b(pe);
    MechanicsSolver<2> fast(MPI_COMM_WORLD, pf), every(MPI_COMM_WORLD, pe);
    fast.run();
    every.run();
    const auto *hf = fast.hybrid_model(), *he = every.hybrid_model();
    // Per id on this rank: switch evaluation, damage, displacement (both
    // runs partition the plate alike; an id owned in one run only counts as
    // a difference).
    struct State
    {
      int    switched;
      double damage, u[2];
    };
    const auto states = [](const MechanicsSolver<2> &s) {
      std::map<types::particle_index, State> m;
      const auto dmg = damage_by_id(s);
      const auto &disc = s.discretization();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        m[disc.id[i]] = {s.hybrid_model()->switch_evaluation()[i], dmg.at(disc.id[i]),
                         {s.integrator().displacement[0].local_element(i),
                          s.integrator().displacement[1].local_element(i)}};
      return m;
    };
    const auto   sf = states(fast), se = states(every);
    unsigned int n_switched = 0, switch_differ = 0, missing = 0;
    double       damage_diff = 0., u_diff = 0., u_max = 0.;
    for (const auto &[id, st] : sf)
      {
        const auto it = se.find(id);
        if (it == se.end())
          {
            ++missing;
            continue;
          }
        const State &o = it->second;
        n_switched += st.switched >= 0;
        switch_differ += st.switched != o.switched;
        damage_diff = std::max(damage_diff, std::abs(st.damage - o.damage));
        for (unsigned int d = 0; d < 2; ++d)
          {
            u_diff = std::max(u_diff, std::abs(st.u[d] - o.u[d]));
            u_max  = std::max(u_max, std::abs(o.u[d]));
          }
      }
    const MPI_Comm comm = MPI_COMM_WORLD;
    n_switched          = Utilities::MPI::sum(n_switched, comm);
    switch_differ       = Utilities::MPI::sum(switch_differ, comm);
    missing             = Utilities::MPI::sum(missing + unsigned(sf.size() != se.size()), comm);
    damage_diff         = Utilities::MPI::max(damage_diff, comm);
    u_diff              = Utilities::MPI::max(u_diff, comm);
    u_max               = Utilities::MPI::max(u_max, comm);
    const std::uint64_t tests_fast = Utilities::MPI::sum(hf->n_exact_node_tests(), comm),
                        tests_every = Utilities::MPI::sum(he->n_exact_node_tests(), comm);
    const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
    check(missing == 0, "the same nodes owned in both runs (" + std::to_string(n_ranks) + " rank(s))");
    check(n_switched > 1000 && switch_differ == 0 &&
            hf->n_switch_events() == he->n_switch_events() &&
            hf->n_standard_nodes() == he->n_standard_nodes(),
          std::to_string(n_switched) + " switched nodes, each at the same force evaluation as "
            "with " + reference + " (" + std::to_string(switch_differ) + " differ; " +
            std::to_string(hf->n_switch_events()) + " / " + std::to_string(he->n_switch_events()) +
            " switch events)");
    check(hf->n_overstretched_bonds() == he->n_overstretched_bonds() &&
            fast.model().n_broken_bonds() == every.model().n_broken_bonds() &&
            fast.model().n_broken_bonds() > 0,
          "broken bonds " + std::to_string(fast.model().n_broken_bonds()) + " / " +
            std::to_string(every.model().n_broken_bonds()));
    check(damage_diff == 0. && u_diff == 0. && u_max > 0.,
          "max |damage difference| = " + sci(damage_diff) + ", max |u difference| = " +
            sci(u_diff) + " (max |u| = " + sci(u_max) + ")");
    if (root())
      std::cout << "  lattice sweep: " << (hf->uses_lattice_sweep() ? "yes" : "no")
                << ", exact node tests " << tests_fast << " / " << tests_every << " (" << reference
                << ")" << std::endl;
    return {tests_fast, tests_every};
  }

  /** check_kw_same_run() with variants of the hybrid's parameters only. */
  std::pair<std::uint64_t, std::uint64_t>
  check_kw_same(const std::function<void(HybridMechanicsParameters &)> &a,
                const std::function<void(HybridMechanicsParameters &)> &b,
                const std::string &reference, const std::string &dir)
  {
    return check_kw_same_run([&](MechanicsRunParameters<2> &p) { a(p.hybrid); },
                             [&](MechanicsRunParameters<2> &p) { b(p.hybrid); }, reference, dir);
  }

  // (h) The fast switching test (lattice bound, p formed only where read)
  // against the exact test of every bond at every step, on KW at CI size
  // on 1 or 2 ranks (check_kw_same()).
  void
  kw_equivalence()
  {
    const auto [tests_fast, tests_every] = check_kw_same(
      [](HybridMechanicsParameters &) {},
      [](HybridMechanicsParameters &h) { h.switching_bound = false; },
      "the exact test of every bond at every step", "kw-equivalence");
    // The fast path is the one under test: the lattice sweep with its
    // bound (AVX-512; else the portable rows with StretchBudget) skips most
    // exact node tests.
    check(tests_fast < 0.25 * tests_every, "most exact node tests skipped");
  }

  // A variant @p kernel of the exact test's kernel against the per-offset
  // masked kernel, on KW at CI size on 1 or 2 ranks: both compute q = max
  // |y|^2 / T^2 bit for bit, so the slack of every node, hence the exact
  // node tests (not only the outcome), must be the same, as must the
  // switches, damage and displacements. A q that is too small would skip
  // needed tests (the switch evaluations differ, see kw_equivalence), a q
  // that is too large adds exact tests.
  void
  check_same_as_masked(const std::function<void(HybridMechanicsParameters &)> &kernel,
                       const std::string &dir)
  {
    const auto [tests_kernel, tests_masked] = check_kw_same(
      kernel, [](HybridMechanicsParameters &h) { h.length_grouped_test = false; },
      "the per-offset masked kernel", dir);
    check(tests_kernel == tests_masked && tests_kernel > 0,
          "the same exact node tests: " + std::to_string(tests_kernel) + " / " +
            std::to_string(tests_masked));
  }

  // The grouped kernel, with loads shared along the stencil rows or not.
  std::function<void(HybridMechanicsParameters &)>
  grouped_kernel(const bool by_rows)
  {
    return [by_rows](HybridMechanicsParameters &h) {
      h.length_grouped_test = true;
      h.row_shared_test     = by_rows;
    };
  }

  // (h2) The exact test's kernel grouped by bond length (no lane masks,
  // length_grouped_test) with a load per offset.
  void
  grouped_test()
  {
    check_same_as_masked(grouped_kernel(false), "kw-grouped-test");
  }

  // (h3) The grouped kernel with one load per stencil row and dimension
  // (row_shared_test, the default: offsets shifted out of the row's
  // vectors), at CI size with the stencil of radius 4.
  void
  row_test()
  {
    check_same_as_masked(grouped_kernel(true), "kw-row-test");
    // The path under test is taken (AVX-512 lattice sweeps only; else
    // neither kernel exists).
    MechanicsSolver<2> s(MPI_COMM_WORLD,
                         kalthoff_winkler(1., 4., 87.5e-6, "hybrid adaptive", 0.8, "kw-row-test-setup"));
    s.setup();
    const auto *hm = s.hybrid_model();
    check(hm->uses_row_shared_test() == hm->uses_lattice_sweep(),
          std::string("the row-shared kernel is used: ") +
            (hm->uses_row_shared_test() ? "yes" : "no") + " (lattice sweep: " +
            (hm->uses_lattice_sweep() ? "yes" : "no") + ")");
  }

  // (h4) Nodes numbered by lattice index (LatticeParameters::lattice_order,
  // the hybrid run of kw_hybrid_benchmark) against the default numbering by
  // cells, on KW at CI size on 1 or 2 ranks: the same nodes per rank and
  // the same arithmetic in every sweep, so bit for bit the same switches,
  // damage and displacements, and the same exact node tests. The numbering
  // must differ (else the test checks nothing), and on one rank the owned
  // nodes must be in lattice order.
  void
  lattice_order()
  {
    const auto [tests_lattice, tests_cells] = check_kw_same_run(
      [](MechanicsRunParameters<2> &p) { p.lattice.lattice_order = true; },
      [](MechanicsRunParameters<2> &p) { p.lattice.lattice_order = false; },
      "the nodes numbered by cells", "kw-lattice-order");
    check(tests_lattice == tests_cells && tests_lattice > 0,
          "the same exact node tests: " + std::to_string(tests_lattice) + " / " +
            std::to_string(tests_cells));
    auto p = kalthoff_winkler(1., 4., 87.5e-6, "hybrid adaptive", 0.8, "kw-lattice-order-setup");
    Discretization<2> by_cells(MPI_COMM_WORLD), by_lattice(MPI_COMM_WORLD);
    by_cells.setup(*p.domain, p.lattice);
    p.lattice.lattice_order = true;
    by_lattice.setup(*p.domain, p.lattice);
    unsigned int moved = 0, unsorted = 0;
    for (unsigned int i = 0; i < by_lattice.n_owned(); ++i)
      {
        moved += by_lattice.id[i] != by_cells.id[i];
        unsorted += i > 0 && by_lattice.id[i] <= by_lattice.id[i - 1];
      }
    moved    = Utilities::MPI::sum(moved, MPI_COMM_WORLD);
    unsorted = Utilities::MPI::sum(unsorted, MPI_COMM_WORLD);
    check(moved > 0 && unsorted == 0 &&
            by_lattice.neighborhood.n_bonds() == by_cells.neighborhood.n_bonds(),
          std::to_string(moved) + " nodes numbered otherwise than by cells, owned ids increasing (" +
            std::to_string(unsorted) + " not), the same bonds");
  }

  // (f) Initial Omega_s of the KW plate (driver defaults: nodes within one
  // horizon of the boundary or two of a pre-crack). Its area is a band
  // whose width is proportional to delta, so the fraction depends on delta,
  // not on dx: at the source's delta = 2 mm (Sect. 3.3.1, m = 8 at
  // dx = 0.25) it is the 9.72 % of Table 3.3; at delta = 4 mm (the CI and
  // the dx = 0.5 benchmark) about twice that. dx = 0.5, m = 4 for delta = 2
  // (setup only, no steps), dx = 1, m = 4 for delta = 4.
  void
  initial_fraction()
  {
    const auto fraction = [](const double dx, const double delta) {
      MechanicsSolver<2> s(MPI_COMM_WORLD,
                           kalthoff_winkler(dx, delta, 1e-6, "hybrid adaptive", 0.95, "kw-initial"));
      s.setup();
      return s.hybrid_model()->standard_fraction();
    };
    const double f2 = fraction(0.5, 2.), f4 = fraction(1., 4.);
    // 0.5 percentage points: the source's lattice is vertex-centred
    // (401 x 801 nodes) and it does not print its band widths; the same
    // bands on its vertex lattice cover 9.87 % (counted separately).
    check_close(100. * f2, 9.72, 0., "initial Omega_s [%] at delta = 2 mm vs Table 3.3", 0.5);
    // Pre-crack tips and corners make the band area slightly sub-linear
    // in delta: 1.8-2.1.
    check(f4 / f2 > 1.8 && f4 / f2 < 2.1,
          "initial Omega_s at delta = 4 mm: " + std::to_string(100. * f4) + " %, " +
            std::to_string(f4 / f2) + " x that at delta = 2 mm");
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"patch", patch},
              {"kw", kw},
              {"rank_invariance", rank_invariance},
              {"bad_input", bad_input},
              {"sweep", sweep},
              {"initial_fraction", initial_fraction},
              {"kw_classes", kw_classes},
              {"kw_lattice", kw_lattice},
              {"kw_equivalence", kw_equivalence},
              {"grouped_test", grouped_test},
              {"row_test", row_test},
              {"half_stencil", half_stencil},
              {"lattice_order", lattice_order},
              {"stretch_budget", StretchBudgetTest::stretch_budget}});
}
