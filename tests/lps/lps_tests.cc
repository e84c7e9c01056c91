// Tests of the linearized LPS operator (dissertation (2.14)-(2.19)):
// homogeneous strains (exact dilatation, zero force, energy vs the CCM
// value), rigid motions, convergence of the force of a quadratic field to
// the Navier operator, and rank-count invariance.

#include <perideal/discretization/discretization.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/lps.h>
#include <perideal/models/stiffness.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include "../check.h"

#include <filesystem>
#include <map>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  const double K = 2.1, G = 0.9;

  // A ball of radius 2 delta + 2 dx around the origin, a lattice node: the
  // nodes with |x| <= dx ("deep") have neighbours whose families are all
  // full, so m_j = m_i and theta_j is exact there.
  template <int dim>
  std::unique_ptr<Discretization<dim>>
  make_ball(const MPI_Comm comm, const unsigned int m, const double delta = 1.)
  {
    const double      dx = delta / m;
    LatticeParameters lp;
    lp.dx    = dx;
    lp.delta = delta;
    auto disc = std::make_unique<Discretization<dim>>(comm);
    disc->setup(BallDomain<dim>(Point<dim>(), 2. * delta + 2. * dx), lp);
    return disc;
  }

  template <int dim>
  bool
  deep(const Discretization<dim> &disc, const unsigned int i)
  {
    return disc.position[i].norm() <= disc.parameters().dx * (1. + 1e-9);
  }

  template <int dim>
  bool
  full_family(const Discretization<dim> &disc, const unsigned int i)
  {
    const auto &nb = disc.neighborhood;
    return nb.table_start[i] == 0 && nb.row_start[i + 1] - nb.row_start[i] == nb.stencil_size;
  }

  template <int dim>
  void
  set_field(const Discretization<dim>                                    &disc,
            const std::function<Tensor<1, dim>(const Point<dim> &)> &u_of_x,
            typename LinearizedLPSOperator<dim>::VectorField              &u)
  {
    for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
      {
        const auto v = u_of_x(disc.position[i]);
        for (unsigned int d = 0; d < dim; ++d)
          u[d].local_element(i) = v[d];
      }
  }

  template <int dim>
  Tensor<2, dim>
  strain(const bool symmetric)
  {
    const double   a[3][3] = {{1.3, 0.4, -0.7}, {0.2, -0.5, 0.9}, {0.6, -0.3, 0.8}};
    Tensor<2, dim> H;
    for (unsigned int r = 0; r < dim; ++r)
      for (unsigned int c = 0; c < dim; ++c)
        H[r][c] = 1e-3 * (symmetric ? 0.5 * (a[r][c] + a[c][r]) : 0.5 * (a[r][c] - a[c][r]));
    return H;
  }

  std::string
  tag(const unsigned int dim, const InfluenceFunction omega, const unsigned int m)
  {
    return std::to_string(dim) + "D " + to_string(omega) + " m = " + std::to_string(m) + ": ";
  }

  // u = H x, H symmetric. theta = tr H to round-off at full-family nodes
  // (m_i is the discrete sum); the force vanishes at deep nodes (symmetric
  // stencil, equal m_j and theta_j); W at the centre approaches the CCM
  // value K tr(H)^2/2 + G |dev H|^2 (plane strain in 2D) with the lattice
  // quadrature error of the 4th moment, returned.
  template <int dim>
  double
  homogeneous_case(const unsigned int m, const InfluenceFunction omega)
  {
    const auto         disc = make_ball<dim>(MPI_COMM_WORLD, m);
    LPSModelParameters p;
    p.omega         = omega;
    p.bulk_modulus  = K;
    p.shear_modulus = G;
    LinearizedLPSOperator<dim>                       op(*disc, p);
    typename LinearizedLPSOperator<dim>::VectorField u, f;
    op.initialize(u);
    op.initialize(f);
    const Tensor<2, dim> H = strain<dim>(true);
    set_field<dim>(*disc, [&](const Point<dim> &x) { return H * x; }, u);
    op.compute_forces(u, f);
    PeriDEAL::Vector W;
    disc->initialize_vector(W);
    op.strain_energy_density(u, W);

    const double   tr = trace(H);
    Tensor<2, dim> dev3 = H;
    for (unsigned int d = 0; d < dim; ++d)
      dev3[d][d] -= tr / 3.;
    // 3D deviator; in 2D the out-of-plane entry -tr/3 is added.
    const double W_ccm = 0.5 * K * tr * tr + G * (dev3.norm_square() + (dim == 2 ? tr * tr / 9. : 0.));
    // Force scale: (K + G) |H| / delta (delta = 1).
    const double f_scale = (K + G) * H.norm();

    double theta_err = 0., f_max = 0., w_err = -1.;
    unsigned int n_full = 0, n_deep = 0;
    for (unsigned int i = 0; i < disc->n_owned(); ++i)
      {
        if (full_family(*disc, i))
          {
            ++n_full;
            theta_err = std::max(theta_err, std::abs(op.dilatation().local_element(i) - tr));
          }
        if (deep(*disc, i))
          {
            ++n_deep;
            double n = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              n += f[d].local_element(i) * f[d].local_element(i);
            f_max = std::max(f_max, std::sqrt(n));
            if (disc->position[i].norm() < 1e-12)
              w_err = std::abs(W.local_element(i) - W_ccm) / W_ccm;
          }
      }
    theta_err = Utilities::MPI::max(theta_err, MPI_COMM_WORLD);
    f_max     = Utilities::MPI::max(f_max, MPI_COMM_WORLD);
    w_err     = Utilities::MPI::max(w_err, MPI_COMM_WORLD);
    n_full    = Utilities::MPI::sum(n_full, MPI_COMM_WORLD);
    n_deep    = Utilities::MPI::sum(n_deep, MPI_COMM_WORLD);
    const std::string t = tag(dim, omega, m);
    check(n_full > 0 && n_deep == (2 * dim + 1), t + std::to_string(n_full) + " full-family nodes, " +
                                                   std::to_string(n_deep) + " deep nodes");
    check(theta_err <= 1e-12 * std::abs(tr), t + "max |theta - tr H| = " + sci(theta_err) +
                                               " (tr H = " + sci(tr) + ")");
    check(f_max <= 1e-11 * f_scale, t + "max |f| at deep nodes = " + sci(f_max) + " (scale (K+G)|H|/delta = " +
                                      sci(f_scale) + ")");
    return w_err;
  }

  void
  homogeneous()
  {
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        double previous = 1.;
        for (const unsigned int m : {3u, 6u, 12u})
          {
            const double e = homogeneous_case<2>(m, omega);
            check(e >= 0. && e < previous && (m < 6 || e < 0.05),
                  tag(2, omega, m) + "relative energy error vs CCM " + sci(e));
            previous = e;
          }
      }
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        double previous = 1.;
        for (const unsigned int m : {3u, 6u})
          {
            const double e = homogeneous_case<3>(m, omega);
            check(e >= 0. && e < previous && (m < 6 || e < 0.05),
                  tag(3, omega, m) + "relative energy error vs CCM " + sci(e));
            previous = e;
          }
      }
  }

  // Translation and infinitesimal rotation (H antisymmetric): theta and the
  // force vanish at every node, including the boundary ones.
  template <int dim>
  void
  rigid_case(const InfluenceFunction omega)
  {
    const auto         disc = make_ball<dim>(MPI_COMM_WORLD, 3);
    LPSModelParameters p;
    p.omega         = omega;
    p.bulk_modulus  = K;
    p.shear_modulus = G;
    LinearizedLPSOperator<dim>                       op(*disc, p);
    typename LinearizedLPSOperator<dim>::VectorField u, f;
    op.initialize(u);
    op.initialize(f);
    const Tensor<2, dim> Wr = strain<dim>(false);
    Tensor<1, dim>       c;
    for (unsigned int d = 0; d < dim; ++d)
      c[d] = 1e-3 * (d + 1.);
    for (const bool rotation : {false, true})
      {
        set_field<dim>(*disc, [&](const Point<dim> &x) { return rotation ? Tensor<1, dim>(Wr * x) : c; }, u);
        op.compute_forces(u, f);
        double th = 0., fm = 0.;
        for (unsigned int i = 0; i < disc->n_owned(); ++i)
          {
            th = std::max(th, std::abs(op.dilatation().local_element(i)));
            for (unsigned int d = 0; d < dim; ++d)
              fm = std::max(fm, std::abs(f[d].local_element(i)));
          }
        th = Utilities::MPI::max(th, MPI_COMM_WORLD);
        fm = Utilities::MPI::max(fm, MPI_COMM_WORLD);
        const double      scale = rotation ? Wr.norm() : c.norm();
        const std::string t = std::to_string(dim) + "D " + to_string(omega) +
                              (rotation ? " rotation: " : " translation: ");
        check(th <= 1e-13 * scale, t + "max |theta| = " + sci(th));
        check(fm <= 1e-12 * (K + G) * scale, t + "max |f| = " + sci(fm));
      }
  }

  void
  rigid_motion()
  {
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        rigid_case<2>(omega);
        rigid_case<3>(omega);
      }
  }

  // u_a = 1/2 Q_abc x_b x_c: the Navier operator is the constant
  // L_a = (K + G/3) Q_bba + G Q_abb. Relative error of f at the centre.
  template <int dim>
  double
  navier_error(const unsigned int m, const InfluenceFunction omega)
  {
    const auto         disc = make_ball<dim>(MPI_COMM_WORLD, m);
    LPSModelParameters p;
    p.omega         = omega;
    p.bulk_modulus  = K;
    p.shear_modulus = G;
    LinearizedLPSOperator<dim>                       op(*disc, p);
    typename LinearizedLPSOperator<dim>::VectorField u, f;
    op.initialize(u);
    op.initialize(f);
    double Q[3][3][3];
    for (unsigned int a = 0; a < 3; ++a)
      for (unsigned int b = 0; b < 3; ++b)
        for (unsigned int c = b; c < 3; ++c)
          Q[a][b][c] = Q[a][c][b] = 1e-3 * std::sin(1. + a + 2. * b + 3.7 * c);
    set_field<dim>(*disc,
                   [&](const Point<dim> &x) {
                     Tensor<1, dim> v;
                     for (unsigned int a = 0; a < dim; ++a)
                       for (unsigned int b = 0; b < dim; ++b)
                         for (unsigned int c = 0; c < dim; ++c)
                           v[a] += 0.5 * Q[a][b][c] * x[b] * x[c];
                     return v;
                   },
                   u);
    op.compute_forces(u, f);
    Tensor<1, dim> L;
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int b = 0; b < dim; ++b)
        L[a] += (K + G / 3.) * Q[b][b][a] + G * Q[a][b][b];
    double err = -1.;
    for (unsigned int i = 0; i < disc->n_owned(); ++i)
      if (disc->position[i].norm() < 1e-12)
        {
          Tensor<1, dim> fi;
          for (unsigned int d = 0; d < dim; ++d)
            fi[d] = f[d].local_element(i);
          err = (fi - L).norm() / L.norm();
        }
    return Utilities::MPI::max(err, MPI_COMM_WORLD);
  }

  void
  navier()
  {
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        double previous = 1.;
        for (const unsigned int m : {3u, 6u, 12u})
          {
            const double e = navier_error<2>(m, omega);
            check(e >= 0. && e < previous && (m < 12 || e < 1e-3), tag(2, omega, m) + "relative error of f vs Navier " + sci(e));
            previous = e;
          }
        previous = 1.;
        for (const unsigned int m : {3u, 6u})
          {
            const double e = navier_error<3>(m, omega);
            check(e >= 0. && e < previous && (m < 6 || e < 5e-3), tag(3, omega, m) + "relative error of f vs Navier " + sci(e));
            previous = e;
          }
      }
  }

  // Forces of a smooth pseudo-random field on comm, keyed by node id
  // (complete on rank 0 of comm).
  template <int dim>
  std::map<types::particle_index, std::array<double, 3>>
  random_forces(const MPI_Comm comm)
  {
    LatticeParameters lp;
    lp.dx    = 0.1;
    lp.delta = 0.3;
    Point<dim> upper;
    for (unsigned int d = 0; d < dim; ++d)
      upper[d] = dim == 2 ? 2. : 1.;
    Discretization<dim> disc(comm);
    disc.setup(BoxDomain<dim>(Point<dim>(), upper), lp);
    LPSModelParameters p;
    p.omega         = InfluenceFunction::linear;
    p.bulk_modulus  = K;
    p.shear_modulus = G;
    LinearizedLPSOperator<dim>                       op(disc, p);
    typename LinearizedLPSOperator<dim>::VectorField u, f;
    op.initialize(u);
    op.initialize(f);
    set_field<dim>(disc,
                   [](const Point<dim> &x) {
                     Tensor<1, dim> v;
                     for (unsigned int a = 0; a < dim; ++a)
                       for (unsigned int b = 0; b < dim; ++b)
                         v[a] += 1e-3 * std::sin(0.7 + 1.9 * a + 2.3 * b + (1.3 + a + 0.4 * b) * x[b]);
                     return v;
                   },
                   u);
    op.compute_forces(u, f);
    check(Utilities::MPI::min(disc.n_owned(), comm) > 0 &&
            (Utilities::MPI::n_mpi_processes(comm) == 1 || Utilities::MPI::max(disc.n_ghost(), comm) > 0),
          std::to_string(dim) + "D: every rank owns nodes (" + std::to_string(Utilities::MPI::n_mpi_processes(comm)) +
            " ranks)");
    std::vector<std::pair<types::particle_index, std::array<double, 3>>> mine;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        std::array<double, 3> v{{0., 0., 0.}};
        for (unsigned int d = 0; d < dim; ++d)
          v[d] = f[d].local_element(i);
        mine.emplace_back(disc.id[i], v);
      }
    std::map<types::particle_index, std::array<double, 3>> result;
    for (const auto &part : Utilities::MPI::gather(comm, mine, 0))
      for (const auto &e : part)
        result[e.first] = e.second;
    return result;
  }

  template <int dim>
  void
  rank_invariance_case()
  {
    const auto world = random_forces<dim>(MPI_COMM_WORLD);
    // (every rank of MPI_COMM_WORLD owns nodes: checked in random_forces)
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) != 0)
      return;
    const auto   self = random_forces<dim>(MPI_COMM_SELF);
    double       diff = 0., fmax = 0.;
    unsigned int matched = 0;
    for (const auto &e : self)
      {
        const auto it = world.find(e.first);
        if (it == world.end())
          continue;
        ++matched;
        for (unsigned int d = 0; d < dim; ++d)
          {
            diff = std::max(diff, std::abs(it->second[d] - e.second[d]));
            fmax = std::max(fmax, std::abs(e.second[d]));
          }
      }
    const std::string t = std::to_string(dim) + "D " +
                          std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)) + " ranks vs 1: ";
    check(matched == self.size() && matched == world.size() && matched > 0,
          t + std::to_string(matched) + " nodes matched");
    check(diff <= 1e-12 * fmax, t + "max |f diff| = " + sci(diff) + " (max |f| " + sci(fmax) + ")");
  }

  // The force is minus the gradient of the total energy E = sum_i W_i V_i
  // (uniform V_i, symmetric beta): E is quadratic, so for a random field u
  // and direction v, E(u + v) - E(u - v) = -2 sum_i f_i(u) . v_i V_i exactly.
  // Checked on a box (boundary nodes included, where m_j != m_i).
  template <int dim>
  void
  energy_gradient_case()
  {
    LatticeParameters lp;
    lp.dx    = 0.1;
    lp.delta = 0.3;
    Point<dim> upper;
    for (unsigned int d = 0; d < dim; ++d)
      upper[d] = 1.;
    Discretization<dim> disc(MPI_COMM_WORLD);
    disc.setup(BoxDomain<dim>(Point<dim>(), upper), lp);
    LPSModelParameters p;
    p.bulk_modulus  = K;
    p.shear_modulus = G;
    LinearizedLPSOperator<dim>                       op(disc, p);
    typename LinearizedLPSOperator<dim>::VectorField u, v, w, f;
    op.initialize(u);
    op.initialize(v);
    op.initialize(w);
    op.initialize(f);
    auto field = [](const Point<dim> &x, const double s) {
      Tensor<1, dim> r;
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int b = 0; b < dim; ++b)
          r[a] += 1e-3 * std::sin(s + 1.9 * a + 2.3 * b + (3.1 + a + 0.4 * b + s) * x[b]);
      return r;
    };
    set_field<dim>(disc, [&](const Point<dim> &x) { return field(x, 0.3); }, u);
    set_field<dim>(disc, [&](const Point<dim> &x) { return field(x, 1.7); }, v);
    op.compute_forces(u, f);
    double work = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        work += f[d].local_element(i) * v[d].local_element(i) * disc.volume[i];
    work = Utilities::MPI::sum(work, MPI_COMM_WORLD);
    double e[2];
    for (const int sign : {1, -1})
      {
        set_field<dim>(disc, [&](const Point<dim> &x) { return field(x, 0.3) + sign * field(x, 1.7); }, w);
        e[sign > 0 ? 0 : 1] = op.total_strain_energy(w);
      }
    check_close(e[0] - e[1], -2. * work, 1e-10,
                std::to_string(dim) + "D: E(u+v) - E(u-v) vs -2 sum f(u).v V");
  }

  void
  energy_gradient()
  {
    energy_gradient_case<2>();
    energy_gradient_case<3>();
  }


  // Critical time step of LPS from the Gershgorin bound of the assembled
  // stiffness, checked against an independent estimate of lambda_max(K)
  // (power iteration) and explicit Verlet runs on the matrix-free forces.
  void
  time_step()
  {
    const double rho = 7.;
    LatticeParameters lp;
    lp.dx    = 0.1;
    lp.delta = 0.3;
    Discretization<2> disc(MPI_COMM_WORLD);
    disc.setup(BoxDomain<2>(Point<2>(), Point<2>(1., 1.)), lp);
    LPSModelParameters p;
    p.bulk_modulus  = K;
    p.shear_modulus = G;
    LinearizedLPSOperator<2>       op(disc, p);
    TrilinosWrappers::SparseMatrix Km;
    Stiffness::assemble(op, Km);
    const double dt_c = Stiffness::critical_time_step(Km, rho);

    // lambda_max by power iteration (an underestimate, so dt_est >= the
    // true critical step 2 sqrt(rho / lambda_max)).
    TrilinosWrappers::MPI::Vector x(Stiffness::owned_dofs(disc), MPI_COMM_WORLD), y(x);
    for (const auto k : x.locally_owned_elements())
      x[k] = std::sin(1.3 * k + 0.7);
    x.compress(VectorOperation::insert);
    double lambda = 0.;
    for (unsigned int it = 0; it < 2000; ++it)
      {
        x /= x.l2_norm();
        Km.vmult(y, x);
        lambda = x * y;
        x      = y;
      }
    const double dt_est = 2. * std::sqrt(rho / lambda);
    check(dt_c <= dt_est, "Gershgorin dt_c = " + sci(dt_c) + " <= 2 sqrt(rho/lambda_max) = " +
                            sci(dt_est) + " (ratio " + sci(dt_c / dt_est) + ")");
    // Measured ratio 0.6-0.7: the bound is not uselessly conservative.
    check(dt_c >= 0.5 * dt_est, "dt_c >= 0.5 x the eigenvalue step");
    // The matrix-free bound of the explicit runs bounds every Gershgorin row
    // sum from above, so it may not exceed the matrix one.
    const double dt_mf = op.critical_time_step(rho);
    check(dt_mf <= dt_c * (1. + 1e-12) && dt_mf >= 0.5 * dt_c,
          "matrix-free dt = " + sci(dt_mf) + " in [0.5, 1] x Gershgorin dt_c (ratio " + sci(dt_mf / dt_c) + ")");

    // Verlet on the matrix-free forces from a random displacement.
    auto run = [&](const double dt) {
      typename LinearizedLPSOperator<2>::VectorField u, v, a;
      op.initialize(u);
      op.initialize(v);
      op.initialize(a);
      for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
        for (unsigned int d = 0; d < 2; ++d)
          u[d].local_element(i) = 1e-3 * std::sin(17.1 * disc.id[i] + 3.3 * d);
      const double u0 = u[0].linfty_norm();
      op.compute_forces(u, a);
      for (unsigned int step = 0; step < 300; ++step)
        {
          for (unsigned int d = 0; d < 2; ++d)
            for (unsigned int i = 0; i < disc.n_owned(); ++i)
              {
                v[d].local_element(i) += 0.5 * dt * a[d].local_element(i) / rho;
                u[d].local_element(i) += dt * v[d].local_element(i);
              }
          for (auto &c : u)
            c.update_ghost_values();
          op.compute_forces(u, a);
          for (unsigned int d = 0; d < 2; ++d)
            for (unsigned int i = 0; i < disc.n_owned(); ++i)
              v[d].local_element(i) += 0.5 * dt * a[d].local_element(i) / rho;
        }
      return std::max(u[0].linfty_norm(), u[1].linfty_norm()) / u0;
    };
    const double g_stable = run(dt_c), g_unstable = run(1.05 * dt_est);
    check(g_stable < 10., "Verlet at dt_c: max|u|/max|u0| = " + sci(g_stable) + " after 300 steps");
    check(g_unstable > 1e6, "Verlet at 1.05 x 2 sqrt(rho/lambda_max): max|u|/max|u0| = " +
                              sci(g_unstable) + " (diverges)");
  }

  // Bond breaking of LPS: the critical stretch criterion on the linearized
  // stretch, irreversibility, damage (2.36), and the cut bonds of a jump
  // field counted independently by the bond-based pre-crack (segment
  // intersection) on the same lattice.
  void
  breaking()
  {
    LatticeParameters lp;
    lp.dx    = 0.1;
    lp.delta = 0.3;
    Discretization<2> disc(MPI_COMM_WORLD);
    disc.setup(BoxDomain<2>(Point<2>(-1., -0.5), Point<2>(1., 0.5)), lp);
    const double       s0 = 1e-4, xc = 0.05;
    LPSModelParameters p;
    p.bulk_modulus     = K;
    p.shear_modulus    = G;
    p.critical_stretch = s0;
    typename LinearizedLPSOperator<2>::VectorField u, f;
    {
      // Uniform expansion: every bond has stretch eps.
      LinearizedLPSOperator<2> op(disc, p);
      op.initialize(u);
      op.initialize(f);
      set_field<2>(disc, [&](const Point<2> &x) { return Tensor<1, 2>(0.99 * s0 * x); }, u);
      op.compute_forces(u, f);
      check(op.n_broken_bonds() == 0, "stretch 0.99 s0: no bond breaks");
      set_field<2>(disc, [&](const Point<2> &x) { return Tensor<1, 2>(1.01 * s0 * x); }, u);
      op.compute_forces(u, f);
      check(op.n_broken_bonds() == disc.n_global_bonds(),
            "stretch 1.01 s0: all " + std::to_string(disc.n_global_bonds()) + " bonds break");
      check(std::max(f[0].linfty_norm(), f[1].linfty_norm()) == 0., "force 0 without bonds");
      PeriDEAL::Vector phi;
      disc.initialize_vector(phi);
      op.damage(phi);
      check(phi.linfty_norm() == 1. && phi.mean_value() == 1., "damage 1 everywhere");
    }
    // A jump of the x displacement across x = xc.
    LinearizedLPSOperator<2> op(disc, p);
    set_field<2>(disc, [&](const Point<2> &x) { return Tensor<1, 2>({x[0] > xc ? 1e-2 : 0., 0.}); },
                 u);
    {
      LPSModelParameters intact = p;
      intact.critical_stretch   = 0.;
      LinearizedLPSOperator<2> op0(disc, intact);
      op0.compute_forces(u, f);
      check(f[0].linfty_norm() > 1e-3, "intact: the jump loads the bonds (max|f_x| = " +
                                         sci(f[0].linfty_norm()) + ")");
    }
    op.compute_forces(u, f);
    BondBasedModelParameters bp;
    BondBasedOperator<2>     cut(disc, bp);
    cut.add_precrack(Point<2>(xc, -10.), Point<2>(xc, 10.));
    check(op.n_broken_bonds() == cut.n_broken_bonds() && cut.n_broken_bonds() > 0,
          std::to_string(op.n_broken_bonds()) + " broken bonds = " +
            std::to_string(cut.n_broken_bonds()) + " bonds crossing x = xc");
    const double fmax = std::max(f[0].linfty_norm(), f[1].linfty_norm());
    check(fmax == 0., "after breaking the two rigid halves exert no force: max|f| = " + sci(fmax));
    PeriDEAL::Vector phi, phi_cut;
    disc.initialize_vector(phi);
    disc.initialize_vector(phi_cut);
    op.damage(phi);
    cut.damage(phi_cut);
    double diff = 0., far = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        diff = std::max(diff, std::abs(phi.local_element(i) - phi_cut.local_element(i)));
        if (std::abs(disc.position[i][0] - xc) > lp.delta + lp.dx)
          far = std::max(far, phi.local_element(i));
      }
    diff = Utilities::MPI::max(diff, MPI_COMM_WORLD);
    far  = Utilities::MPI::max(far, MPI_COMM_WORLD);
    check(diff < 1e-15, "damage equals the pre-crack damage (max diff " + sci(diff) + ")");
    check(far == 0., "damage 0 farther than delta + dx from the cut");
    check(phi.linfty_norm() > 0.3, "max damage at the cut " + sci(phi.linfty_norm()));
    // Irreversible: unloading does not heal.
    set_field<2>(disc, [](const Point<2> &) { return Tensor<1, 2>(); }, u);
    const auto n = op.n_broken_bonds();
    op.compute_forces(u, f);
    check(op.n_broken_bonds() == n, "unloading keeps the broken bonds");
  }


  // ---------------------------------------------------------------------
  // LPS in explicit mechanics runs (MechanicsSolver, Mechanics/Model = LPS).

  template <int dim>
  MechanicsRunParameters<dim>
  lps_run(const Point<dim> &lower, const Point<dim> &upper, const double dx, const double delta)
  {
    MechanicsRunParameters<dim> p;
    p.domain                = std::make_shared<BoxDomain<dim>>(lower, upper);
    p.lattice.dx            = dx;
    p.lattice.delta         = delta;
    p.lattice.cell_centered = true;
    p.model_type            = "LPS";
    p.lps.bulk_modulus      = K;
    p.lps.shear_modulus     = G;
    p.density               = 1.3;
    p.initial_velocity      = dim == 2 ? "0; 0" : "0; 0; 0";
    p.body_force            = p.initial_velocity;
    p.end_time              = 1.;
    p.output_directory      = "lps_output_" + std::to_string(dim) + "d_np" +
                         std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD));
    return p;
  }

  template <int dim>
  std::string
  linear_field(const Tensor<2, dim> &H)
  {
    std::ostringstream s;
    s.precision(17);
    const char *xyz[3] = {"x", "y", "z"};
    for (unsigned int r = 0; r < dim; ++r)
      {
        s << (r ? "; " : "");
        for (unsigned int c = 0; c < dim; ++c)
          s << (c ? " + " : "") << "(" << H[r][c] << ") * " << xyz[c];
      }
    return s.str();
  }

  // Patch test through the driver: the initial displacement u = H x of an
  // LPS run. Isotropic expansion: W = d^2 K_d e^2 / 2 = the CCM value
  // K tr^2/2 + G |dev_3D H|^2 (plane strain in 2D) to round-off at every
  // full-family node (theta is exact with the discrete m, the deviatoric
  // extension vanishes). A general symmetric H: W at a node in the middle
  // within the lattice quadrature error of the 4th angular moment (measured
  // independently of the driver by lps.homogeneous: a few % at m = 3).
  template <int dim>
  void
  explicit_patch_case()
  {
    Point<dim> lower, upper;
    for (unsigned int d = 0; d < dim; ++d)
      {
        lower[d] = -2.;
        upper[d] = 2.;
      }
    const double dx = dim == 2 ? 0.25 : 0.5, delta = 3. * dx;
    for (const bool expansion : {true, false})
      {
        auto           p = lps_run<dim>(lower, upper, dx, delta);
        Tensor<2, dim> H = strain<dim>(true);
        if (expansion)
          H = 1e-3 * unit_symmetric_tensor<dim>();
        p.initial_displacement = linear_field<dim>(H);
        MechanicsSolver<dim> solver(MPI_COMM_WORLD, p);
        solver.setup();
        const auto &disc = solver.discretization();
        PeriDEAL::Vector W;
        disc.initialize_vector(W);
        solver.model().strain_energy_density(solver.integrator().displacement, W);
        const double   tr   = trace(H);
        Tensor<2, dim> dev3 = H;
        for (unsigned int d = 0; d < dim; ++d)
          dev3[d][d] -= tr / 3.;
        const double W_ccm = 0.5 * K * tr * tr + G * (dev3.norm_square() + (dim == 2 ? tr * tr / 9. : 0.));
        double       err = 0., center = -1.;
        unsigned int n = 0;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          {
            if (full_family(disc, i))
              {
                err = std::max(err, std::abs(W.local_element(i) - W_ccm));
                ++n;
              }
            if (disc.position[i].norm() < dx)
              center = std::max(center, std::abs(W.local_element(i) - W_ccm));
          }
        err    = Utilities::MPI::max(err, MPI_COMM_WORLD) / W_ccm;
        center = Utilities::MPI::max(center, MPI_COMM_WORLD) / W_ccm;
        n      = Utilities::MPI::sum(n, MPI_COMM_WORLD);
        const std::string t = std::to_string(dim) + "D LPS run, " +
                              (expansion ? "isotropic expansion" : "general strain") + ": ";
        if (expansion)
          check(n > 0 && err <= 1e-12, t + "max |W - W_ccm| / W_ccm over " + std::to_string(n) +
                                         " full-family nodes = " + sci(err));
        else
          // Measured 2.0e-2 (2D) and 4.9e-3 (3D) at m = 3: the fourth-moment
          // quadrature error of the lattice, as lps.homogeneous finds it.
          check(center >= 0. && center < 0.05,
                t + "|W - W_ccm| / W_ccm in the middle = " + sci(center) + " (< 5 %, lattice m = 3)");
        // The CSV energy is the same sum.
        const auto m = solver.measure();
        check_close(m.strain_energy, solver.model().total_strain_energy(solver.integrator().displacement),
                    1e-13, t + "measured strain energy = sum W V");
      }
  }

  void
  explicit_patch()
  {
    explicit_patch_case<2>();
    explicit_patch_case<3>();
  }

  // An isolated LPS body with a non-uniform initial velocity (stretch,
  // shear and spin), bonds breaking on the way: the linear momentum
  // sum rho V v and the angular momentum sum rho V x x v (reference x: the
  // linearized LPS pair forces are parallel to xi, so sum x_i x f_i V_i = 0
  // exactly, and Verlet's v update is a sum of forces) stay constant to
  // round-off of the momentum scale sum rho V |x| |v|.
  template <int dim>
  void
  explicit_momentum_case()
  {
    Point<dim> lower, upper;
    for (unsigned int d = 0; d < dim; ++d)
      upper[d] = dim == 2 ? 6. - d : 3.;
    auto p = lps_run<dim>(lower, upper, 0.25, 0.76);
    p.initial_velocity = dim == 2 ? "0.02 * x + 0.01 * sin(y) - 0.03 * y; 0.05 * cos(x) * y + 0.03 * x" :
                                    "0.02 * x + 0.01 * sin(y) - 0.03 * y; 0.05 * cos(x) * y + 0.03 * x; "
                                    "0.01 * x * z - 0.02 * y";
    p.lps.critical_stretch = 0.05;
    p.end_time             = 25.;
    p.time_series_interval = 1000000;
    MechanicsSolver<dim> solver(MPI_COMM_WORLD, p);
    solver.setup();
    const auto &disc = solver.discretization();
    const auto  momenta = [&]() {
      // P (dim entries) and L (1 entry in 2D, 3 in 3D) and the scale.
      double s[7] = {};
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const double    mass = p.density * disc.volume[i];
          Tensor<1, dim>  v;
          for (unsigned int d = 0; d < dim; ++d)
            v[d] = solver.integrator().velocity[d].local_element(i);
          const Point<dim> &x = disc.position[i];
          for (unsigned int d = 0; d < dim; ++d)
            s[d] += mass * v[d];
          if constexpr (dim == 2)
            s[3] += mass * (x[0] * v[1] - x[1] * v[0]);
          else
            {
              const Tensor<1, 3> L = cross_product_3d(Tensor<1, 3>(x), v);
              for (unsigned int d = 0; d < 3; ++d)
                s[3 + d] += mass * L[d];
            }
          s[6] += mass * x.norm() * v.norm();
        }
      Utilities::MPI::sum(ArrayView<const double>(s, 7), MPI_COMM_WORLD, ArrayView<double>(s, 7));
      return std::vector<double>(s, s + 7);
    };
    const auto   start = momenta();
    solver.run();
    const auto   end = momenta();
    double       dP = 0., dL = 0.;
    for (unsigned int d = 0; d < 3; ++d)
      {
        dP = std::max(dP, std::abs(end[d] - start[d]));
        dL = std::max(dL, std::abs(end[3 + d] - start[3 + d]));
      }
    const std::string t = std::to_string(dim) + "D LPS, " + std::to_string(solver.integrator().step()) +
                          " steps, " + std::to_string(solver.model().n_broken_bonds()) + " broken bonds: ";
    check(solver.model().n_broken_bonds() > 0, t + "bonds break");
    check(dP <= 1e-13 * start[6], t + "max |P - P0| = " + sci(dP) + " (scale " + sci(start[6]) + ")");
    check(dL <= 1e-13 * start[6], t + "max |L - L0| = " + sci(dL) + " (scale " + sci(start[6]) + ")");
  }

  void
  explicit_momentum()
  {
    explicit_momentum_case<2>();
    explicit_momentum_case<3>();
  }

  // A 2D LPS plate (plane strain) in tension, pulled by grips moving at
  // +-V, with a pre-crack from the left edge to the middle; s0 from G0.
  // Runs until the crack (damage >= 0.35 ahead of the pre-crack tip) is
  // 2 delta long or max_steps.
  struct LPSCrack
  {
    std::map<types::particle_index, std::array<double, 3>> nodes; // u_x, u_y, damage
    std::uint64_t         n_broken = 0;
    unsigned int          steps    = 0;
    MechanicsMeasurements start, end;
    double                far_damage = 0., s0 = 0.;
  };

  const double lps_crack_y = 29.5, lps_crack_tip = 19.5;

  MechanicsRunParameters<2>
  lps_crack_parameters(const MPI_Comm comm)
  {
    auto p = lps_run<2>(Point<2>(0, 0), Point<2>(59, 59), 1., 3.015);
    p.lattice.cell_centered = false;
    p.density               = 1.;
    // s0 = sqrt(pi G0 / (3 K_2 delta)) = 0.01007 for K_2 = K + G/3 = 2.4.
    p.lps.fracture_energy      = 7e-4;
    p.precracks                = {{Point<2>(-1, lps_crack_y), Point<2>(lps_crack_tip, lps_crack_y)}};
    p.prescribed_velocities    = {{"y - 2.5", "0; -5e-4"}, {"56.5 - y", "0; 5e-4"}};
    p.measure_crack            = true;
    p.crack_origin             = Point<2>(lps_crack_tip, lps_crack_y);
    p.crack_region             = std::to_string(lps_crack_tip) + " - x";
    p.end_time                 = 1e6;
    p.time_series_interval     = 1000000;
    p.output_directory = std::string("lps_crack_np") + std::to_string(Utilities::MPI::n_mpi_processes(comm));
    return p;
  }

  LPSCrack
  lps_crack_run(const MPI_Comm comm, const unsigned int max_steps)
  {
    const auto         p = lps_crack_parameters(comm);
    MechanicsSolver<2> solver(comm, p);
    solver.setup();
    LPSCrack r;
    r.s0    = solver.model().critical_stretch();
    r.start = solver.measure();
    const double delta = p.lattice.delta;
    while (solver.integrator().step() < max_steps)
      {
        solver.run(20);
        if (solver.measure().crack_length >= 2. * delta)
          break;
      }
    r.steps    = solver.integrator().step();
    r.end      = solver.measure();
    r.n_broken = solver.model().n_broken_bonds();
    const auto &disc = solver.discretization();
    PeriDEAL::Vector phi;
    disc.initialize_vector(phi);
    solver.model().damage(phi);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        r.nodes[disc.id[i]] = {{solver.integrator().displacement[0].local_element(i),
                                solver.integrator().displacement[1].local_element(i),
                                phi.local_element(i)}};
        if (std::abs(disc.position[i][1] - lps_crack_y) > 2. * delta)
          r.far_damage = std::max(r.far_damage, phi.local_element(i));
      }
    r.far_damage = Utilities::MPI::max(r.far_damage, comm);
    return r;
  }

  const unsigned int lps_crack_steps = 3000;

  // The crack grows from the tip, straight ahead (mode I), and damage
  // stays 0 farther than 2 delta from the crack line.
  void
  explicit_crack()
  {
    const LPSCrack r = lps_crack_run(MPI_COMM_WORLD, lps_crack_steps);
    check(std::abs(r.s0 - std::sqrt(M_PI * 7e-4 / (3. * (K + G / 3.) * 3.015))) < 1e-15,
          "s0 from G0 = " + sci(r.s0));
    check(r.start.crack_length < 3.015, "initially no crack node ahead of the tip beyond delta (" +
                                          sci(r.start.crack_length) + ")");
    check(r.steps < lps_crack_steps && r.end.crack_length >= 2. * 3.015,
          "the crack ran 2 delta ahead of the tip after " + std::to_string(r.steps) +
            " steps (length " + sci(r.end.crack_length) + ")");
    const double a = r.end.crack_angle > 90. ? 180. - r.end.crack_angle : r.end.crack_angle;
    check(a < 5., "straight ahead: crack angle " + sci(r.end.crack_angle) + " deg (" +
                    std::to_string(r.end.n_crack_nodes) + " nodes)");
    check(r.far_damage == 0., "damage 0 farther than 2 delta from the crack line");
  }

  // Checkpoint and resume of an LPS run while the crack grows: stop 40
  // steps after the checkpoint at step 200, resume (back to step 200) and
  // run to step 300: bitwise the uninterrupted run (displacements and the
  // broken bonds restored from the checkpoint by node ids).
  void
  explicit_resume()
  {
    auto p = lps_crack_parameters(MPI_COMM_WORLD);
    p.output_directory += "_resume";
    std::filesystem::remove_all(p.output_directory);
    const auto state = [](const MechanicsSolver<2> &s) {
      std::map<types::particle_index, std::array<double, 2>> u;
      for (unsigned int i = 0; i < s.discretization().n_owned(); ++i)
        u[s.discretization().id[i]] = {{s.integrator().displacement[0].local_element(i),
                                        s.integrator().displacement[1].local_element(i)}};
      return u;
    };
    MechanicsSolver<2> straight(MPI_COMM_WORLD, p);
    straight.run(300);
    const auto reference = state(straight);
    p.checkpoint_interval = 200;
    std::uint64_t broken_at_checkpoint = 0;
    {
      MechanicsSolver<2> first(MPI_COMM_WORLD, p);
      first.run(200);
      broken_at_checkpoint = first.model().n_broken_bonds();
      first.run(40);
    }
    p.resume = true;
    MechanicsSolver<2> resumed(MPI_COMM_WORLD, p);
    resumed.run(100);
    check(resumed.integrator().step() == 300, "resumed at step 200, now at " +
                                                std::to_string(resumed.integrator().step()));
    const auto u    = state(resumed);
    double     diff = 0.;
    for (const auto &e : reference)
      for (unsigned int d = 0; d < 2; ++d)
        diff = std::max(diff, std::abs(u.at(e.first)[d] - e.second[d]));
    diff = Utilities::MPI::max(diff, MPI_COMM_WORLD);
    check(straight.model().n_broken_bonds() > broken_at_checkpoint,
          "bonds break after the checkpoint (" + std::to_string(broken_at_checkpoint) + " -> " +
            std::to_string(straight.model().n_broken_bonds()) + ")");
    check(resumed.model().n_broken_bonds() == straight.model().n_broken_bonds(),
          "broken bonds " + std::to_string(resumed.model().n_broken_bonds()) + " = uninterrupted " +
            std::to_string(straight.model().n_broken_bonds()));
    check(diff == 0., "max |u - u_uninterrupted| = " + sci(diff));
  }

  // s0 from G0 (lps_critical_stretch): the closed forms for omega_0, and
  // G0 recovered by brute-force Cartesian quadrature of the energy of the
  // bonds crossing a unit crack area, G = int_{|xi| < delta, xi_n > 0}
  // w(xi) xi_n dxi (the normal distance z of the lower end point runs over
  // (0, xi_n)), with the pair energy w = A omega |xi| s0^2 normalized by
  // (1/2) int_H w dxi = d^2 K_d s0^2 / 2, the LPS energy density of the
  // isotropic expansion at stretch s0. Midpoint rule on N^d cells: the
  // error is set by the cells cut by the sphere |xi| = delta.
  template <int dim>
  double
  crack_energy(const InfluenceFunction omega, const double delta, const double K_d, const double s0,
               const unsigned int N)
  {
    const double h = 2. * delta / N;
    double       moment = 0., crossing = 0.; // int omega |xi|, int_{xi_n > 0} omega |xi| xi_n
    std::array<unsigned int, 3> k = {{0, 0, 0}};
    const unsigned int          n_cells = dim == 2 ? N * N : N * N * N;
    for (unsigned int c = 0; c < n_cells; ++c)
      {
        k[0] = c % N;
        k[1] = (c / N) % N;
        k[2] = c / (N * N);
        double xi[dim], r2 = 0.;
        for (unsigned int d = 0; d < dim; ++d)
          {
            xi[d] = -delta + (k[d] + 0.5) * h;
            r2 += xi[d] * xi[d];
          }
        const double r = std::sqrt(r2);
        if (r >= delta)
          continue;
        const double w = influence(omega, r, delta) * r;
        moment += w;
        if (xi[dim - 1] > 0.)
          crossing += w * xi[dim - 1];
      }
    const double A = dim * dim * K_d / moment; // the cell volume h^d cancels in A * crossing
    return A * crossing * s0 * s0;
  }

  void
  fracture_energy()
  {
    const double delta = 1.7, G0 = 0.3, K_3 = K, K_2 = K + G / 3.;
    const double s3 = lps_critical_stretch(3, InfluenceFunction::constant, delta, K_3, G0);
    const double s2 = lps_critical_stretch(2, InfluenceFunction::constant, delta, K_2, G0);
    check_close(s3, std::sqrt(5. * G0 / (9. * K_3 * delta)), 1e-14, "3D omega_0: s0 = sqrt(5 G0 / (9 K delta))");
    check_close(s2, std::sqrt(M_PI * G0 / (3. * K_2 * delta)), 1e-14,
                "2D omega_0: s0 = sqrt(pi G0 / (3 (K + G/3) delta))");
    for (const auto omega : {InfluenceFunction::constant, InfluenceFunction::linear})
      {
        const double s2o = lps_critical_stretch(2, omega, delta, K_2, G0);
        const double s3o = lps_critical_stretch(3, omega, delta, K_3, G0);
        // Measured quadrature errors: 2D <= 3e-6 (N = 3000), 3D <= 2e-5 (N = 200).
        check_close(crack_energy<2>(omega, delta, K_2, s2o, 3000), G0, 1e-4,
                    "2D " + to_string(omega) + ": energy of the bonds crossing a unit length = G0");
        check_close(crack_energy<3>(omega, delta, K_3, s3o, 200), G0, 2e-4,
                    "3D " + to_string(omega) + ": energy of the bonds crossing a unit area = G0");
      }
    // The operator uses it when only G0 is given.
    LatticeParameters lp;
    lp.dx    = 0.5;
    lp.delta = delta;
    Discretization<2> disc(MPI_COMM_WORLD);
    disc.setup(BoxDomain<2>(Point<2>(), Point<2>(4., 4.)), lp);
    LPSModelParameters p;
    p.bulk_modulus    = K;
    p.shear_modulus   = G;
    p.fracture_energy = G0;
    check_close(LinearizedLPSOperator<2>(disc, p).critical_stretch(), s2, 1e-15, "operator s0 from G0");
    p.critical_stretch = 0.123;
    check(LinearizedLPSOperator<2>(disc, p).critical_stretch() == 0.123, "an explicit s0 wins");
  }

  // ---------------------------------------------------------------------
  // Time-dependent loads and reaction forces (any model; 1D/2D bond-based).

  // A 1D PD bar (E = 4, rho = 1, c = 2) driven at the left end by the
  // velocity pulse v0(t) = V sin^2(pi t / T) (t < T), or by the equivalent
  // displacement u0(t) = int v0, and pulled at the right end by the
  // traction pulse T(t) = S sin^2(pi t / T) on a layer of thickness h.
  // Classical 1D wave theory (d'Alembert): v(x, t) = v0(t - (x - x_L)/c)
  // and v(x, t) = T(t - (x_R - x)/c) / (rho c), x_L and x_R the ends of
  // the loaded layers (the held layer moves rigidly; the traction layer's
  // force acts over h, centre x_R = 400 - h/2). The pulse is 27 delta
  // long: the PD bar's dispersion is small; the error budget is
  // measured in the test and asserted with the margin stated there.
  void
  wave()
  {
    const double V = 1e-3, S = 2e-3, Tp = 20., c = 2., h = 1.5, t_end = 90.;
    auto sin2 = [](const double a, const double tp) {
      return std::to_string(a) + " * (t < " + std::to_string(tp) + " ? sin(pi * t / " + std::to_string(tp) +
             ")^2 : 0)";
    };
    auto v0 = [&](const double t) { return t > 0. && t < Tp ? std::pow(std::sin(M_PI * t / Tp), 2) : 0.; };
    for (const bool by_displacement : {false, true})
      {
        MechanicsRunParameters<1> p;
        p.domain                = std::make_shared<BoxDomain<1>>(Point<1>(0.), Point<1>(400.));
        p.lattice.dx            = 0.5;
        p.lattice.delta         = 1.5;
        p.lattice.cell_centered = true;
        p.model.youngs_modulus  = 4.;
        p.density               = 1.;
        p.initial_velocity      = "0";
        p.body_force            = "0";
        p.end_time              = t_end;
        p.output_directory      = "lps_wave_np" + std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD));
        if (by_displacement)
          // u0 = V (t/2 - T/(4 pi) sin(2 pi t / T)) for t < T, V T / 2 after.
          p.prescribed_displacements = {{"x - 1.5", std::to_string(V) + " * (t < " + std::to_string(Tp) +
                                                      " ? t / 2 - " + std::to_string(Tp) +
                                                      " / (4 * pi) * sin(2 * pi * t / " + std::to_string(Tp) +
                                                      ") : " + std::to_string(Tp / 2.) + ")"}};
        else
          p.prescribed_velocities = {{"x - 1.5", sin2(V, Tp)}};
        p.tractions = {{"398.5 - x", sin2(S, Tp), h}};
        MechanicsSolver<1> solver(MPI_COMM_WORLD, p);
        solver.setup();
        solver.run();
        const double t    = solver.integrator().time();
        const auto  &disc = solver.discretization();
        // Per pulse (0 left, 1 right): sum v, sum x v, peak, and the
        // profile error after shifting the closed form by the measured
        // centroid offset (second pass).
        double       m[2][3] = {};
        const double amplitude[2] = {V, S / c};
        const auto   in_pulse = [](const double x) { return x > 1.5 && x < 398.5 ? (x < 200. ? 0 : 1) : -1; };
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          {
            const double x = disc.position[i][0], v = solver.integrator().velocity[0].local_element(i);
            const int    k = in_pulse(x);
            if (k < 0)
              continue;
            m[k][0] += v;
            m[k][1] += x * v;
            m[k][2] = std::max(m[k][2], v / amplitude[k]);
          }
        double centroid[2], expected[2], shift[2], err[2] = {0., 0.}, impulse[2];
        for (unsigned int k = 0; k < 2; ++k)
          {
            m[k][0]     = Utilities::MPI::sum(m[k][0], MPI_COMM_WORLD);
            m[k][1]     = Utilities::MPI::sum(m[k][1], MPI_COMM_WORLD);
            m[k][2]     = Utilities::MPI::max(m[k][2], MPI_COMM_WORLD);
            centroid[k] = m[k][1] / m[k][0];
            // int v dx = c int v0 dt = c A T / 2 (d'Alembert).
            impulse[k] = m[k][0] * p.lattice.dx / (c * amplitude[k] * Tp / 2.);
          }
        expected[0] = 1.5 + c * (t - Tp / 2.);
        expected[1] = 400. - h / 2. - c * (t - Tp / 2.);
        for (unsigned int k = 0; k < 2; ++k)
          shift[k] = centroid[k] - expected[k];
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          {
            const double x = disc.position[i][0], v = solver.integrator().velocity[0].local_element(i);
            const int    k = in_pulse(x);
            if (k == 0)
              err[0] = std::max(err[0], std::abs(v / V - v0(t - (x - shift[0] - 1.5) / c)));
            else if (k == 1)
              err[1] = std::max(err[1], std::abs(v / amplitude[1] - v0(t - (400. - h / 2. - x + shift[1]) / c)));
          }
        const char *name[2] = {by_displacement ? "left pulse by the displacement u0(t)" :
                                                 "left pulse by the velocity v0(t)",
                               "right pulse by the traction T(t)"};
        for (unsigned int k = 0; k < 2; ++k)
          {
            err[k] = Utilities::MPI::max(err[k], MPI_COMM_WORLD);
            const std::string n = name[k];
            // Measured: centroid offsets -0.43 (left) and +0.75 (right;
            // both lag behind the closed form), peaks 0.998 and 0.996,
            // impulse ratios 1 to 1e-4, shape errors after the shift
            // 1.7e-2 and 1.8e-2 (the dispersion of the discrete PD bar
            // distorts the pulse edges). A lag below 2 dx = one horizon is
            // the group delay of that dispersion plus the ambiguity of
            // where a loaded layer ends (dx / 2).
            check(std::abs(shift[k]) < 2. * p.lattice.dx,
                  n + ": centroid " + sci(centroid[k]) + " vs x_0 +- c (t - T/2) = " + sci(expected[k]) +
                    " (offset " + sci(shift[k]) + ")");
            check(std::abs(m[k][2] - 1.) < 0.01, n + ": peak / amplitude = " + sci(m[k][2]));
            check(std::abs(impulse[k] - 1.) < 1e-3, n + ": int v dx / (c A T / 2) = " + sci(impulse[k]));
            check(err[k] < 0.03, n + ": max |v - closed form (shifted by the offset)| / amplitude = " + sci(err[k]));
          }
      }
  }

  // Reaction forces with the inertia of the held nodes. (a) A 2D plate
  // whose bottom layer follows u0(t) = (A sin(w1 t), B sin(w2 t)): the
  // reaction equals the rate of change of the total momentum,
  // R^n = sum_all rho V (u^{n+1} - 2 u^n + u^{n-1}) / dt^2 (Verlet: free
  // nodes' second difference is dt^2 a^n; internal forces cancel), to
  // round-off; without the inertia term the balance would be off by the
  // held mass times its acceleration (checked to be large). (b) The whole
  // body held: R = M u0''(t) = -M A w^2 sin(w t) up to the O((w dt)^2 / 12)
  // of the central difference.
  void
  reaction_inertia()
  {
    MechanicsRunParameters<2> p;
    p.domain                = std::make_shared<BoxDomain<2>>(Point<2>(0, 0), Point<2>(20, 10));
    p.lattice.dx            = 1.;
    p.lattice.delta         = 3.015;
    p.lattice.cell_centered = true;
    p.model.plane_stress    = false;
    p.density               = 2.;
    p.initial_velocity      = "0; 0";
    p.body_force            = "0; 0";
    p.end_time              = 100.;
    p.output_directory = "lps_reaction_np" + std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD));
    const double A = 0.01, B = 0.02, w1 = 0.3, w2 = 0.5;
    p.prescribed_displacements = {{"y - 3", std::to_string(A) + " * sin(" + std::to_string(w1) + " * t); " +
                                               std::to_string(B) + " * sin(" + std::to_string(w2) + " * t)"}};
    {
      MechanicsSolver<2> solver(MPI_COMM_WORLD, p);
      solver.setup();
      const auto &disc = solver.discretization();
      const double dt  = solver.integrator().time_step();
      // sum rho V u, and the held mass times the held acceleration.
      auto weighted_u = [&]() {
        Tensor<1, 2> s;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          for (unsigned int d = 0; d < 2; ++d)
            s[d] += p.density * disc.volume[i] * solver.integrator().displacement[d].local_element(i);
        return Utilities::MPI::sum(s, MPI_COMM_WORLD);
      };
      auto held_inertia = [&]() {
        Tensor<1, 2> s;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (solver.integrator().is_held(i))
            s += p.density * disc.volume[i] * solver.integrator().held_acceleration(i);
        return Utilities::MPI::sum(s, MPI_COMM_WORLD);
      };
      Tensor<1, 2> previous = weighted_u(), current, R, inertia;
      double       err = 0., err_without = 0., scale = 0.;
      solver.run(1);
      current = weighted_u();
      for (unsigned int n = 1; n < 50; ++n)
        {
          R       = solver.reaction_force(0);
          inertia = held_inertia();
          solver.run(1);
          const Tensor<1, 2> next = weighted_u();
          const Tensor<1, 2> rate = (next - 2. * current + previous) / (dt * dt);
          err         = std::max(err, (R - rate).norm());
          err_without = std::max(err_without, (R - inertia - rate).norm());
          scale       = std::max(scale, R.norm());
          previous    = current;
          current     = next;
        }
      check(err <= 1e-9 * scale, "R^n = d^2/dt^2 sum rho V u: max error " + sci(err) + " (max |R| " + sci(scale) +
                                   "; round-off of the second difference ~ 1e-16 max|sum rho V u| / dt^2)");
      check(err_without > 1e3 * err, "without the held inertia the error would be " + sci(err_without));
    }
    // (b) Everything held.
    p.prescribed_displacements = {{"-1", std::to_string(A) + " * sin(" + std::to_string(w1) + " * t); 0"}};
    MechanicsSolver<2> solver(MPI_COMM_WORLD, p);
    solver.setup();
    solver.run(17);
    const double t = solver.integrator().time(), dt = solver.integrator().time_step();
    const double M = p.density * 200.;
    const auto   R = solver.reaction_force(0);
    // The central difference of A sin(w t) is exactly
    // A sin(w t) 2 (cos(w dt) - 1) / dt^2 = u0''(t) (1 - (w dt)^2 / 12 + ...).
    check_close(R[0], M * A * std::sin(w1 * t) * 2. * (std::cos(w1 * dt) - 1.) / (dt * dt), 1e-11,
                "rigid body: R_x = M x central difference of u0 (t = " + sci(t) + ")");
    check_close(R[0], -M * A * w1 * w1 * std::sin(w1 * t), 0., "rigid body: R_x = M u0''(t)",
                1.01 * std::pow(w1 * dt, 2) / 12. * M * A * w1 * w1);
    // Round-off: PMB stretches of a translated lattice are ~1e-16, not 0.
    check(std::abs(R[1]) < 1e-12 * std::abs(R[0]), "R_y = " + sci(R[1]) + " = 0 to round-off");
  }

  // The crack run on all ranks and on rank 0 alone.
  void
  explicit_crack_ranks()
  {
    const LPSCrack world = lps_crack_run(MPI_COMM_WORLD, lps_crack_steps);
    const auto     all   = Utilities::MPI::gather(MPI_COMM_WORLD, world.nodes, 0);
    if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) != 0)
      return;
    const LPSCrack self = lps_crack_run(MPI_COMM_SELF, lps_crack_steps);
    std::map<types::particle_index, std::array<double, 3>> merged;
    for (const auto &m : all)
      merged.insert(m.begin(), m.end());
    double       diff = 0., umax = 0.;
    unsigned int matched = 0;
    for (const auto &e : self.nodes)
      {
        const auto it = merged.find(e.first);
        if (it == merged.end())
          continue;
        ++matched;
        for (unsigned int d = 0; d < 3; ++d)
          {
            diff = std::max(diff, std::abs(it->second[d] - e.second[d]));
            umax = std::max(umax, std::abs(e.second[d]));
          }
      }
    const std::string tag = std::to_string(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD)) + " ranks vs 1: ";
    check(matched == self.nodes.size() && matched == merged.size(), tag + std::to_string(matched) + " nodes matched");
    check(diff <= 1e-12 * std::max(1., umax), tag + "max |u, damage diff| = " + sci(diff));
    check(world.steps == self.steps && world.n_broken == self.n_broken,
          tag + "steps " + std::to_string(world.steps) + " vs " + std::to_string(self.steps) +
            ", broken bonds " + std::to_string(world.n_broken) + " vs " + std::to_string(self.n_broken));
  }

  void
  rank_invariance()
  {
    rank_invariance_case<2>();
    rank_invariance_case<3>();
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"homogeneous", homogeneous},
              {"rigid_motion", rigid_motion},
              {"navier", navier},
              {"energy_gradient", energy_gradient},
              {"rank_invariance", rank_invariance},
              {"time_step", time_step},
              {"breaking", breaking},
              {"explicit_patch", explicit_patch},
              {"explicit_momentum", explicit_momentum},
              {"explicit_crack", explicit_crack},
              {"explicit_crack_ranks", explicit_crack_ranks},
              {"explicit_resume", explicit_resume},
              {"fracture_energy", fracture_energy},
              {"wave", wave},
              {"reaction_inertia", reaction_inertia}});
}
