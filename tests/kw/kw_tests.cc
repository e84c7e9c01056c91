// Tests of the mechanics driver features: 3D polygon pre-cracks, the
// measurements from the damage field (crack angle/length, energy in a
// circle), prescribed displacements, reaction forces and tractions.
// Each is checked against something computed independently: brute-force
// geometry, a pre-crack of known angle, closed-form areas, the equivalent
// prescribed-velocity run, and the discrete momentum balance.

#include <deal.II/base/mpi.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/models/bond_based.h>
#include <perideal/time_stepping/diffusion_solver.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include "../check.h"

#include <map>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  // Break every bond of @p op for which @p cut(p, q) holds (p, q ordered by
  // node id, as break_bonds() calls it) and count the copies.
  template <int dim, typename Cut>
  std::uint64_t
  count_bonds(const Discretization<dim> &disc, const Cut &cut)
  {
    const auto   &nb = disc.neighborhood;
    std::uint64_t n  = 0;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
        {
          const auto j     = nb.col[b];
          const bool first = disc.id[i] < disc.id[j];
          n += first ? cut(disc.position[i], disc.position[j]) :
                       cut(disc.position[j], disc.position[i]);
        }
    return Utilities::MPI::sum(n, MPI_COMM_WORLD);
  }

  // 3D polygon pre-cracks against brute-force geometry written differently:
  // a triangle by barycentric coordinates of the crossing point, a square
  // covering the whole cross-section by the half-space test alone.
  void
  precrack_3d()
  {
    LatticeParameters lp;
    lp.dx    = 1.;
    lp.delta = 2.015;
    Discretization<3> disc(MPI_COMM_WORLD);
    disc.setup(BoxDomain<3>(Point<3>(), Point<3>(9, 9, 9)), lp);
    BondBasedModelParameters mp;

    // (1) A tilted triangle.
    // Vertices chosen so that no bond crosses the plane within 1e-9 of an
    // edge (a crossing exactly on an edge is decided by round-off).
    const Point<3> A(1.31, 1.17, 2.23), B(7.73, 2.41, 5.19), C(3.27, 7.93, 6.37);
    {
      BondBasedOperator<3> op(disc, mp);
      op.add_precrack(std::vector<Point<3>>{A, B, C});
      const Tensor<1, 3> n = cross_product_3d(B - A, C - A);
      const auto expected  = count_bonds(disc, [&](const Point<3> &p, const Point<3> &q) {
        const double sp = n * (p - A), sq = n * (q - A);
        if (!(sp * sq < 0.))
          return false;
        const Point<3> X = p + sp / (sp - sq) * (q - p);
        // Barycentric coordinates by areas.
        const double area = n.norm();
        const double a    = (cross_product_3d(B - X, C - X) * n) / (area * area);
        const double b    = (cross_product_3d(C - X, A - X) * n) / (area * area);
        return a > 0. && b > 0. && a + b < 1.;
      });
      check(expected > 100, "triangle cuts " + std::to_string(expected) + " bond copies");
      check(op.n_broken_bonds() == expected,
            "triangle pre-crack: " + std::to_string(op.n_broken_bonds()) + " broken vs " +
              std::to_string(expected) + " by barycentric coordinates");
    }
    // (2) A square (given as a non-convex-safe 4-gon) larger than the body in
    // the plane z = 4.5 + 0.3 (x - 4.5): every bond crossing the plane.
    {
      BondBasedOperator<3> op(disc, mp);
      const auto z = [](const double x) { return 4.5 + 0.3 * (x - 4.5); };
      op.add_precrack(std::vector<Point<3>>{Point<3>(-5, -5, z(-5)), Point<3>(15, -5, z(15)),
                                            Point<3>(15, 15, z(15)), Point<3>(-5, 15, z(-5))});
      const auto expected = count_bonds(disc, [&](const Point<3> &p, const Point<3> &q) {
        return (p[2] - z(p[0])) * (q[2] - z(q[0])) < 0.;
      });
      check(op.n_broken_bonds() == expected,
            "plane pre-crack: " + std::to_string(op.n_broken_bonds()) + " broken vs " +
              std::to_string(expected) + " crossing the plane");
      // A node next to the plane far from the boundary lost about half its
      // family: the damage of the plane's neighbours is in (0.3, 0.5).
    }
    // (3) Bad input.
    bool thrown = false;
    try
      {
        BondBasedOperator<3> op(disc, mp);
        op.add_precrack(std::vector<Point<3>>{A, B, C, Point<3>(0, 0, 9)});
      }
    catch (const ParameterError &e)
      {
        thrown = e.parameter == "Pre-crack";
      }
    check(thrown, "a non-planar polygon throws ParameterError 'Pre-crack'");
  }

  MechanicsRunParameters<2>
  plate(const double side, const double dx, const double delta)
  {
    MechanicsRunParameters<2> p;
    p.domain         = std::make_shared<BoxDomain<2>>(Point<2>(0, 0), Point<2>(side, side));
    p.lattice.dx     = dx;
    p.lattice.delta  = delta;
    p.lattice.cell_centered = true;
    p.model.youngs_modulus  = 1.;
    p.model.plane_stress    = false;
    p.density               = 1.;
    p.initial_velocity      = "0; 0";
    p.body_force            = "0; 0";
    p.end_time              = 1.;
    return p;
  }

  // The crack angle and length measured from the damage of a pre-crack of
  // known direction; the energy in a circle of a uniformly moving body.
  void
  measurements()
  {
    for (const double angle : {68., 30., 115.})
      {
        auto           p = plate(100., 0.5, 2.);
        const Point<2> o(50.2, 50.1);
        const double   L = 35.;
        const Point<2> e(o[0] + L * std::cos(angle * M_PI / 180.),
                         o[1] + L * std::sin(angle * M_PI / 180.));
        p.precracks         = {{o, e}};
        p.measure_crack     = true;
        p.crack_origin      = o;
        p.crack_fit_min_radius = 2.;
        p.crack_fit_max_radius = 30.;
        p.initial_velocity  = "3; -4";
        p.energy_center     = Point<2>(30., 40.);
        p.energy_radius     = 10.;
        MechanicsSolver<2> solver(MPI_COMM_WORLD, p);
        solver.setup();
        const auto m = solver.measure();
        // The damaged band is symmetric about the segment up to the lattice:
        // a few tenths of a degree.
        check_close(m.crack_angle, angle, 0., "crack angle of a pre-crack at " + std::to_string(angle), 0.5);
        // Nodes beyond the end of the segment keep most bonds: the length is
        // L to within delta.
        check_close(m.crack_length, L, 0., "crack length", p.lattice.delta);
        if (angle == 68.)
          {
            // Uniform velocity |v| = 5: 1/2 rho |v|^2 pi R^2 (lattice area
            // error of a circle of radius 20 dx: < 1 %).
            check_close(m.circle_kinetic_energy, 12.5 * M_PI * 100., 1e-2, "kinetic energy in the circle");
            check_close(m.kinetic_energy, 12.5 * 100. * 100., 1e-12, "kinetic energy of the plate");
            check(m.circle_strain_energy == 0., "no strain energy at rest");
          }
      }
  }

  // A prescribed displacement u = v0 t reproduces the run with the
  // prescribed velocity v0 (same motion, different code path); the reaction
  // force satisfies the discrete momentum balance of the free nodes,
  // P_free^{n+1} - P_free^n = dt/2 (R^n + R^{n+1}); a traction layer applies
  // the total force T x length.
  void
  prescribed_and_reaction()
  {
    auto p = plate(30., 1., 3.);
    p.model.critical_stretch = 0.02;
    p.precracks              = {{Point<2>(-1, 15), Point<2>(10, 15)}};
    p.end_time               = 60.;
    const std::string np = "_np" + std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD));
    auto pv = p, pd = p;
    pv.output_directory = "kw_prescribed_velocity" + np;
    pd.output_directory = "kw_prescribed_displacement" + np;
    pv.prescribed_velocities    = {{"y - 3", "0; -0.01"}, {"27 - y", "0; 0.01"}};
    pd.prescribed_displacements = {{"y - 3", "0; -0.01 * t"}, {"27 - y", "0; 0.01 * t"}};
    MechanicsSolver<2> sv(MPI_COMM_WORLD, pv), sd(MPI_COMM_WORLD, pd);
    sv.setup();
    sd.setup();
    double      diff = 0., balance = 0., scale = 0.;
    const auto &disc = sv.discretization();
    const double dt  = sv.integrator().time_step();
    // Momentum of the free nodes.
    const auto free_momentum = [&](const MechanicsSolver<2> &s) {
      Tensor<1, 2> P;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const double y = disc.position[i][1];
          if (y > 3. && y < 27.)
            for (unsigned int d = 0; d < 2; ++d)
              P[d] += s.integrator().velocity[d].local_element(i) * disc.volume[i];
        }
      return Utilities::MPI::sum(P, MPI_COMM_WORLD);
    };
    unsigned int steps = 0;
    while (sv.integrator().time() < 60. - 1e-9)
      {
        const Tensor<1, 2> P0 = free_momentum(sv);
        const Tensor<1, 2> R0 = sv.reaction_force(0) + sv.reaction_force(1);
        sv.run(1);
        sd.run(1);
        ++steps;
        const Tensor<1, 2> R1 = sv.reaction_force(0) + sv.reaction_force(1);
        const Tensor<1, 2> dP = free_momentum(sv) - P0 - 0.5 * dt * (R0 + R1);
        balance               = std::max(balance, dP.norm());
        scale                 = std::max(scale, (0.5 * dt * (R0 + R1)).norm());
        double d              = 0.;
        for (unsigned int c = 0; c < 2; ++c)
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            d = std::max(d, std::abs(sv.integrator().displacement[c].local_element(i) -
                                     sd.integrator().displacement[c].local_element(i)));
        diff = std::max(diff, Utilities::MPI::max(d, MPI_COMM_WORLD));
      }
    const auto R = sv.reaction_force(1);
    check(sv.model().n_broken_bonds() > sv.time_series().front()[4],
          "bonds break during the run (" + std::to_string(sv.model().n_broken_bonds()) + ")");
    check(R[1] > 0., "the top grip pulls: reaction_2_y = " + std::to_string(R[1]) + " > 0");
    check_close(diff, 0., 0., "u = v0 t equals v = v0 over " + std::to_string(steps) +
                                " steps: max |u diff|", 1e-12);
    // Impulse scale max |dt/2 (R^n + R^{n+1})|: round-off relative to it.
    check_close(balance, 0., 0., "momentum balance of the free nodes with the reaction forces",
                1e-12 * scale + 1e-15);
    check(sd.time_series().size() == sv.time_series().size() &&
            sd.time_series_columns().size() == sv.time_series_columns().size(),
          "same CSV layout for displacement and velocity sets");

    // Traction: T = (0.3, -0.2) on a layer of 2 rows (h = 2 dx) at the top.
    auto pt      = plate(30., 1., 3.);
    pt.tractions = {{"28 - y", "0.3; -0.2", 2.}};
    MechanicsSolver<2> st(MPI_COMM_WORLD, pt);
    st.setup();
    Tensor<1, 2> total;
    for (unsigned int i = 0; i < st.discretization().n_owned(); ++i)
      for (unsigned int d = 0; d < 2; ++d)
        total[d] += st.integrator().body_force[d].local_element(i) * st.discretization().volume[i];
    total = Utilities::MPI::sum(total, MPI_COMM_WORLD);
    check_close(total[0], 0.3 * 30., 1e-13, "traction layer: total force x = T_x * length");
    check_close(total[1], -0.2 * 30., 1e-13, "traction layer: total force y = T_y * length");

    // A sinusoidal displacement is followed exactly by the held nodes.
    auto ps = plate(20., 1., 3.);
    ps.end_time = 10.;
    ps.prescribed_displacements = {{"x - 1", "0.01 * sin(t); 0"}};
    ps.output_directory         = "kw_sine" + np;
    MechanicsSolver<2> ss(MPI_COMM_WORLD, ps);
    ss.setup();
    ss.run();
    double err = 0.;
    for (unsigned int i = 0; i < ss.discretization().n_owned(); ++i)
      if (ss.discretization().position[i][0] < 1.)
        err = std::max(err, std::abs(ss.integrator().displacement[0].local_element(i) -
                                     0.01 * std::sin(ss.integrator().time())));
    check(Utilities::MPI::max(err, MPI_COMM_WORLD) <= 1e-15,
          "held nodes follow u = 0.01 sin(t) to round-off");
  }

  // A traction T pulling the end of a 1D bar: behind the wave front the bar
  // moves with the particle velocity v = T / (rho c), c = sqrt(E / rho)
  // (classical 1D wave theory; the PD bar is calibrated to E in the long-wave
  // limit). The plateau is averaged over 100 length units behind the front;
  // dispersion ripples of the discrete PD bar average out (measured 2e-4).
  void
  traction_wave()
  {
    MechanicsRunParameters<1> p;
    p.domain                 = std::make_shared<BoxDomain<1>>(Point<1>(0.), Point<1>(400.));
    p.lattice.dx             = 0.5;
    p.lattice.delta          = 1.5;
    p.lattice.cell_centered  = true;
    p.model.youngs_modulus   = 4.;
    p.density                = 1.;
    p.initial_velocity       = "0";
    p.body_force             = "0";
    p.end_time               = 150.;
    p.output_directory       = "kw_traction_wave_np" + std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD));
    const double T           = 1e-3, h = 1.5;
    p.tractions              = {{"398.5 - x", std::to_string(T), h}};
    MechanicsSolver<1> solver(MPI_COMM_WORLD, p);
    solver.setup();
    solver.run();
    const double c = std::sqrt(p.model.youngs_modulus / p.density), t = solver.integrator().time();
    // Plateau: from 20 behind the front (x = 400 - c t = 100) to 20 before the layer.
    double sum = 0., n = 0.;
    const auto &disc = solver.discretization();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double x = disc.position[i][0];
        if (x > 400. - c * t + 20. && x < 398.5 - 20.)
          {
            sum += solver.integrator().velocity[0].local_element(i);
            n += 1.;
          }
      }
    sum = Utilities::MPI::sum(sum, MPI_COMM_WORLD);
    n   = Utilities::MPI::sum(n, MPI_COMM_WORLD);
    check_close(sum / n, T / (p.density * c), 5e-3,
                "mean particle velocity behind the front = T / (rho c)");
  }

  // Bad mechanics input: one ParameterError naming the entry.
  void
  bad_input()
  {
    const std::vector<std::pair<std::string, std::string>> cases = {
      {"subsection Mechanics\n set Tractions = y - 1 : 0; 1\nend\n", "Mechanics/Tractions"},
      {"subsection Mechanics\n set Tractions = y - 1 : 0; 1 : -2\nend\n", "Mechanics/Tractions"},
      {"subsection Mechanics\n set Pre-cracks = 0, 0, 1, 1, 2, 2\nend\n", "Mechanics/Pre-cracks"},
      {"subsection Mechanics\n set Prescribed displacements = y - 1\nend\n",
       "Mechanics/Prescribed displacements"},
      {"subsection Measurements\n set Crack origin = 1, 2, 3, 4\nend\n", "Measurements/Crack origin"},
      {"subsection Measurements\n set Damage threshold = 1.5\nend\n", "Measurements/Damage threshold"},
      {"subsection Measurements\n set Crack fit radii = 5, 2\nend\n", "Measurements/Crack fit radii"},
      {"subsection Measurements\n set Energy circle = 1, 2\nend\n", "Measurements/Energy circle"}};
    for (const auto &[text, entry] : cases)
      {
        ParameterHandler prm;
        DiffusionRunParameters<2>::declare_parameters(prm);
        MechanicsRunParameters<2>::declare_parameters(prm);
        prm.parse_input_from_string(text);
        std::string thrown = "(nothing)";
        try
          {
            MechanicsRunParameters<2> p;
            p.parse_parameters(prm);
          }
        catch (const ParameterError &e)
          {
            thrown = e.parameter;
          }
        check(thrown == entry, "ParameterError '" + thrown + "' for " + entry);
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"precrack_3d", precrack_3d},
              {"measurements", measurements},
              {"prescribed", prescribed_and_reaction},
              {"traction_wave", traction_wave},
              {"bad_input", bad_input}});
}
