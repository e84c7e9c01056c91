// Static equilibrium of the linearized PD models (bond-based (2.32), LPS
// (2.18)-(2.19)) with assembled Trilinos stiffness matrices, and the LPS
// critical time step and bond breaking:
//   matrix        K u = -f(u) (matrix-free) for random u, K symmetric, 2D/3D
//   patch         homogeneous fields on the constraint layer are reproduced
//   manufactured  quadratic u with the Navier body force: m-convergence
//   trig          sin field: delta-convergence at fixed m (reported rates)
//   equilibrium   reaction = -total body force; energy = -1/2 sum V u.f
//   rank          (run on 2 ranks) solution identical to a 1-rank solve
//   lps_time_step Gershgorin step vs power-iteration eigenvalue and Verlet
//   lps_breaking  critical stretch, damage, cut bonds vs a geometric count

#include <deal.II/lac/trilinos_vector.h>

#include <perideal/discretization/discretization.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/diffusion.h>
#include <perideal/models/lps.h>
#include <perideal/models/stiffness.h>
#include <perideal/time_stepping/static_mechanics.h>

#include "../check.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <map>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  const double K_bulk = 2.1, G_shear = 0.9, E_young = 1.7;

  // A rank-independent pseudo-random number in [-1, 1] from a node id.
  double
  noise(const types::particle_index id, const unsigned int c)
  {
    const double s = std::sin(12.9898 * double(id) + 78.233 * (c + 1)) * 43758.5453;
    return 2. * (s - std::floor(s)) - 1.;
  }

  // lambda + mu and mu of the Navier operator of each model (nu = 1/4 for
  // the bond-based model in plane strain and 3D: lambda = mu = 0.4 E).
  std::pair<double, double>
  navier_constants(const std::string &model)
  {
    if (model == "LPS")
      return {K_bulk + G_shear / 3., G_shear};
    return {0.8 * E_young, 0.4 * E_young};
  }

  template <int dim>
  StaticMechanicsParameters<dim>
  parameters(const std::string &model,
             const double       delta,
             const unsigned int m,
             const double       layers,
             const double       length = 1.)
  {
    StaticMechanicsParameters<dim> p;
    Point<dim>                     hi;
    for (unsigned int d = 0; d < dim; ++d)
      hi[d] = length;
    p.domain                  = std::make_shared<BoxDomain<dim>>(Point<dim>(), hi);
    p.lattice.dx              = delta / m;
    p.lattice.delta           = delta;
    // The bonds reach delta + dx/2 (partial volumes): a layer of that
    // thickness gives every body node its full family, also at convex
    // corners, where a layer of thickness delta misses the outer shell.
    p.lattice.layer_thickness = layers * (delta + 0.5 * delta / m);
    p.model                   = model;
    p.bond_based.youngs_modulus = E_young;
    p.bond_based.plane_stress   = false;
    p.bond_based.linearized     = true;
    p.lps.bulk_modulus          = K_bulk;
    p.lps.shear_modulus         = G_shear;
    p.body_force         = [](const Point<dim> &) { return Tensor<1, dim>(); };
    p.layer_displacement = p.body_force;
    p.tolerance          = 1e-12;
    return p;
  }

  // max over body nodes |u - u_ex| / max |u_ex| (all ranks).
  template <int dim, typename Exact>
  double
  max_error(const StaticMechanicsSolver<dim> &s, const Exact &exact)
  {
    const auto &disc = s.discretization();
    double      e = 0., n = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (!s.fixed_nodes()[i])
        {
          const auto ue = exact(disc.position[i]);
          for (unsigned int d = 0; d < dim; ++d)
            {
              e = std::max(e, std::abs(s.displacement()[d].local_element(i) - ue[d]));
              n = std::max(n, std::abs(ue[d]));
            }
        }
    return Utilities::MPI::max(e, MPI_COMM_WORLD) / Utilities::MPI::max(n, MPI_COMM_WORLD);
  }

  // ------------------------------------------------------------------ matrix
  template <int dim>
  void
  matrix_case(const std::string &model, const unsigned int m)
  {
    const double delta = 0.3;
    // Layer delta: the layer nodes have partial families, the general case.
    StaticMechanicsSolver<dim> s(MPI_COMM_WORLD,
                                 parameters<dim>(model, delta, m, 1., dim == 2 ? 1. : 0.6));
    s.setup();
    const auto &disc = s.discretization();

    typename StaticMechanicsSolver<dim>::VectorField u, w, f;
    for (unsigned int d = 0; d < dim; ++d)
      {
        disc.initialize_vector(u[d]);
        disc.initialize_vector(w[d]);
        disc.initialize_vector(f[d]);
      }
    for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        {
          u[d].local_element(i) = noise(disc.id[i], d);
          w[d].local_element(i) = noise(disc.id[i], d + 3);
        }
    s.compute_forces(u, f);

    TrilinosWrappers::SparseMatrix K;
    s.assemble(K);
    const IndexSet                owned = Stiffness::owned_dofs(disc);
    TrilinosWrappers::MPI::Vector U(owned, MPI_COMM_WORLD), W(U), KU(U), KW(U), F(U);
    Stiffness::to_dofs(disc, u, U);
    Stiffness::to_dofs(disc, w, W);
    Stiffness::to_dofs(disc, f, F);
    K.vmult(KU, U);
    K.vmult(KW, W);
    const double wku = W * KU, ukw = U * KW;
    KU += F;
    const double rel = KU.linfty_norm() / F.linfty_norm();
    const std::string tag = model + " " + std::to_string(dim) + "D m=" + std::to_string(m) +
                            " (" + std::to_string(disc.n_global()) + " nodes, nnz " +
                            std::to_string(K.n_nonzero_elements()) + ")";
    // Round-off: the force sums ~10^2 bonds of O(1) terms.
    check(rel < 1e-12, tag + ": max|K u + f(u)| / max|f| = " + sci(rel) + " < 1e-12");
    const double sym = std::abs(wku - ukw) / std::abs(ukw);
    check(sym < 1e-12, tag + ": |w.Ku - u.Kw| / |u.Kw| = " + sci(sym) + " < 1e-12");

    // The reduced matrix: K_II on the free rows, identity on fixed rows.
    TrilinosWrappers::SparseMatrix Kr;
    s.assemble(Kr, s.fixed_nodes());
    for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
      if (s.fixed_nodes()[i])
        for (unsigned int d = 0; d < dim; ++d)
          u[d].local_element(i) = 0.;
    s.compute_forces(u, f);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (s.fixed_nodes()[i])
        for (unsigned int d = 0; d < dim; ++d)
          f[d].local_element(i) = 0.;
    Stiffness::to_dofs(disc, u, U);
    Stiffness::to_dofs(disc, f, F);
    Kr.vmult(KU, U);
    KU += F;
    const double rel_r = KU.linfty_norm() / F.linfty_norm();
    check(rel_r < 1e-12, tag + ": reduced K_II u_I = -f_I(u_I, 0): " + sci(rel_r));
  }

  void
  test_matrix()
  {
    matrix_case<2>("linearized bond-based", 3);
    matrix_case<2>("LPS", 3);
    matrix_case<3>("linearized bond-based", 2);
    matrix_case<3>("LPS", 2);
  }

  // ------------------------------------------------------------------- patch
  template <int dim>
  void
  patch_case(const std::string &model, const std::string &solver, const unsigned int m,
             const double layer_factor)
  {
    const double delta = 0.3;
    auto         p     = parameters<dim>(model, delta, m, layer_factor);
    p.solver           = solver;
    const double a[3][3] = {{1.3e-3, 0.4e-3, -0.7e-3}, {0.2e-3, -0.5e-3, 0.9e-3},
                            {0.6e-3, -0.3e-3, 0.8e-3}};
    const auto   exact   = [a](const Point<dim> &x) {
      Tensor<1, dim> v;
      for (unsigned int d = 0; d < dim; ++d)
        {
          v[d] = 1e-3 * (d + 1);
          for (unsigned int e = 0; e < dim; ++e)
            v[d] += a[d][e] * x[e];
        }
      return v;
    };
    p.layer_displacement = exact;
    StaticMechanicsSolver<dim> s(MPI_COMM_WORLD, p);
    s.setup();
    s.solve();
    const double err = max_error(s, exact);
    const std::string tag = model + " " + std::to_string(dim) + "D m=" + std::to_string(m) +
                            " " + solver + ", layer " + std::to_string(layer_factor).substr(0, 3) +
                            " (delta + dx/2): patch test max error " + sci(err) + " (" +
                            std::to_string(s.n_iterations()) + " it.)";
    // Exact up to the solver: CG reduces the residual by 1e-12, and K has a
    // condition number ~ 1e2 .. 1e3 here.
    check(err < 1e-9, tag + " < 1e-9");
  }

  void
  test_patch()
  {
    patch_case<2>("linearized bond-based", "cg-amg", 3, 1.);
    patch_case<2>("linearized bond-based", "direct", 3, 1.);
    // LPS: theta of a constraint node within one bond of the body needs a
    // full family, so the layer is two bond lengths thick (with one the
    // partial families of the layer nodes produce a surface effect, below).
    patch_case<2>("LPS", "cg-amg", 3, 2.);
    patch_case<2>("LPS", "direct", 3, 2.);
    patch_case<3>("linearized bond-based", "cg-amg", 2, 1.);
    patch_case<3>("LPS", "cg-amg", 2, 2.);

    // Measured, not a requirement: the LPS surface effect with a delta layer.
    const double delta = 0.3;
    auto         p     = parameters<2>("LPS", delta, 3, 1.);
    p.layer_displacement = [](const Point<2> &x) { return Tensor<1, 2>({1e-3 * x[1], 0.}); };
    StaticMechanicsSolver<2> s(MPI_COMM_WORLD, p);
    s.setup();
    s.solve();
    const double err = max_error(s, p.layer_displacement);
    check(err > 1e-6, "LPS 2D with a one-horizon layer: simple shear is NOT reproduced (max error " +
                        sci(err) + "): theta of partial families at the layer");
  }

  // ------------------------------------------------------------ manufactured
  // Quadratic u_d = sum A^d_pq x_p x_q: the continuum PD operators of both
  // models reproduce the Navier operator exactly for quadratic fields (the
  // Taylor series ends at second order), so b = -L u_ex is constant and the
  // nonlocal solution with u_ex on the layer is u_ex itself: the error is
  // the quadrature (discretization) error of the meshfree scheme.
  template <int dim>
  double
  quadratic_error(const std::string &model, const double delta, const unsigned int m,
                  const double layer_factor, unsigned int *nodes = nullptr,
                  const std::string &solver = "cg-amg")
  {
    const double A[3][3][3] = {{{0.3, 0.1, -0.2}, {0.1, -0.4, 0.05}, {-0.2, 0.05, 0.2}},
                               {{-0.1, 0.25, 0.1}, {0.25, 0.2, -0.15}, {0.1, -0.15, 0.3}},
                               {{0.2, -0.05, 0.1}, {-0.05, 0.1, 0.2}, {0.1, 0.2, -0.3}}};
    auto exact = [A](const Point<dim> &x) {
      Tensor<1, dim> v;
      for (unsigned int c = 0; c < dim; ++c)
        for (unsigned int p = 0; p < dim; ++p)
          for (unsigned int q = 0; q < dim; ++q)
            v[c] += A[c][p][q] * x[p] * x[q];
      return v;
    };
    const auto [lm, mu] = navier_constants(model);
    Tensor<1, dim> b;
    for (unsigned int c = 0; c < dim; ++c)
      for (unsigned int e = 0; e < dim; ++e)
        b[c] -= 2. * mu * A[c][e][e] + 2. * lm * A[e][c][e];
    auto p               = parameters<dim>(model, delta, m, layer_factor);
    p.solver             = solver;
    p.layer_displacement = exact;
    p.body_force         = [b](const Point<dim> &) { return b; };
    StaticMechanicsSolver<dim> s(MPI_COMM_WORLD, p);
    s.setup();
    s.solve();
    if (nodes)
      *nodes = s.discretization().n_global();
    return max_error(s, exact);
  }

  // The m-error of the partial-volume scheme is not monotone (the quadrature
  // of the second moments depends on how the lattice meets the horizon
  // sphere; e.g. 2D bond-based 2.6e-3 at m = 4, 2.7e-3 at m = 5, 1.2e-3 at
  // m = 6, 4.2e-5 at m = 8, 6.9e-4 at m = 10: `static_tests scan`), so the
  // observed order is the least-squares slope of log e over log m.
  template <int dim>
  void
  m_convergence(const std::string &model, const std::vector<unsigned int> &ms,
                const double layer_factor, const double min_order)
  {
    const double        delta = 0.25;
    std::vector<double> e;
    double              sx = 0., sy = 0., sxx = 0., sxy = 0.;
    for (const unsigned int m : ms)
      {
        unsigned int n;
        e.push_back(quadratic_error<dim>(model, delta, m, layer_factor, &n));
        if (root())
          std::cout << "  " << model << " " << dim << "D delta = " << delta << " m = " << m
                    << " nodes " << n << ": max rel. error " << sci(e.back()) << std::endl;
        const double x = std::log(double(m)), y = std::log(e.back());
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
      }
    const double n     = ms.size();
    const double order = -(n * sxy - sx * sy) / (n * sxx - sx * sx);
    check(order > min_order, model + " " + std::to_string(dim) + "D m = " +
                               std::to_string(ms.front()) + " .. " + std::to_string(ms.back()) +
                               ": least-squares order " + sci(order) + " > " + sci(min_order));
    check(e.back() < e.front(), "error at m = " + std::to_string(ms.back()) + " below that at m = " +
                                  std::to_string(ms.front()));
  }

  // Not a ctest: the error table behind the thresholds of test_manufactured.
  void
  scan()
  {
    for (const std::string model : {"linearized bond-based", "LPS"})
      for (unsigned int m = 2; m <= 10; ++m)
        {
          unsigned int n;
          const double e = quadratic_error<2>(model, 0.25, m, model == "LPS" ? 2. : 1., &n);
          if (root())
            std::cout << "  " << model << " 2D m = " << m << " nodes " << n << ": " << sci(e)
                      << std::endl;
        }
  }

  void
  test_manufactured()
  {
    // Measured least-squares orders 2.4 (bond-based) and 2.4 (LPS) in 2D,
    // 1.9 from two points in 3D; asserted with a margin for the scatter.
    m_convergence<2>("linearized bond-based", {2, 3, 4, 5, 6}, 1., 1.5);
    m_convergence<2>("LPS", {2, 3, 4, 5, 6}, 2., 1.5);
    m_convergence<3>("linearized bond-based", {2, 3}, 1., 1.);
  }


  // ------------------------------------------------------------------- trig
  // u = (sin(a x + b y), cos(c x + d y)) with the body force of the local
  // Navier operator: the PD solution differs from u by the model error
  // O(delta^2) plus the quadrature error of the meshfree scheme.
  double
  trig_error(const std::string &model, const double delta, const unsigned int m)
  {
    const double a = 2., b = 1., c = 1.5, d = -2.5;
    auto         exact = [=](const Point<2> &x) {
      return Tensor<1, 2>({std::sin(a * x[0] + b * x[1]), std::cos(c * x[0] + d * x[1])});
    };
    const auto [lm, mu] = navier_constants(model);
    auto p              = parameters<2>(model, delta, m, model == "LPS" ? 2. : 1.);
    p.layer_displacement = exact;
    p.body_force         = [=, lm = lm, mu = mu](const Point<2> &x) {
      const double s1 = std::sin(a * x[0] + b * x[1]), c2 = std::cos(c * x[0] + d * x[1]);
      const Tensor<1, 2> lap({-(a * a + b * b) * s1, -(c * c + d * d) * c2});
      const Tensor<1, 2> grad_div({-a * a * s1 - d * c * c2, -a * b * s1 - d * d * c2});
      return Tensor<1, 2>(-(mu * lap + lm * grad_div));
    };
    StaticMechanicsSolver<2> s(MPI_COMM_WORLD, p);
    s.setup();
    s.solve();
    return max_error(s, exact);
  }

  void
  test_trig()
  {
    for (const std::string model : {"linearized bond-based", "LPS"})
      {
        std::vector<double> e;
        for (const double delta : {0.2, 0.1, 0.05})
          {
            e.push_back(trig_error(model, delta, 3));
            if (root())
              std::cout << "  " << model << " m = 3 delta = " << delta << ": max rel. error "
                        << sci(e.back()) << std::endl;
          }
        for (unsigned int k = 1; k < e.size(); ++k)
          if (root())
            std::cout << "  observed delta-order " << std::log(e[k - 1] / e[k]) / std::log(2.)
                      << std::endl;
        // Measured: at fixed m the error levels off at the quadrature error
        // of the m = 3 stencil (bond-based 2.3e-2 -> 1.9e-2, LPS 2.2e-2 ->
        // 1.2e-2): the standard scheme with partial volumes is not
        // asymptotically compatible. Asserted as measured.
        check(e.back() > 0.4 * e.front(),
              model + ": delta -> 0 at m = 3 levels off (" + sci(e.front()) + " -> " +
                sci(e.back()) + ")");
        std::vector<double> em;
        for (const unsigned int m : {2u, 4u, 6u})
          {
            em.push_back(trig_error(model, 0.1, m));
            if (root())
              std::cout << "  " << model << " delta = 0.1 m = " << m << ": max rel. error "
                        << sci(em.back()) << std::endl;
          }
        // m -> infinity at fixed delta: converges (to the nonlocal solution,
        // which differs from u by the O(delta^2) model error).
        check(em.back() < 0.5 * em.front(),
              model + ": m-refinement at delta = 0.1 reduces the error (" + sci(em.front()) +
                " -> " + sci(em.back()) + ")");
      }
  }


  // ------------------------------------------------------------------- 1D
  // step-3 solves 1D static PD elasticity with the J_1 diffusion matrix
  // (DiffusionOperator::assemble_backward_euler with dt = infinity). The
  // linearized bond-based stiffness in 1D is the same operator (block
  // c omega beta V / |xi|), so step-3 could use Stiffness::assemble: the two
  // reduced matrices agree to round-off.
  void
  test_step3_1d()
  {
    const double      delta = 1.5;
    LatticeParameters lp;
    lp.dx              = delta / 4.3;
    lp.delta           = delta;
    lp.layer_thickness = delta;
    Discretization<1> disc(MPI_COMM_WORLD);
    disc.setup(BoxDomain<1>(Point<1>(-10.), Point<1>(10.)), lp);

    BondBasedModelParameters bp;
    bp.youngs_modulus = 1.3;
    bp.linearized     = true;
    const BondBasedOperator<1> bb(disc, bp);
    DiffusionModelParameters dp;
    dp.omega             = InfluenceFunction::constant;
    dp.exponent          = 1.;
    dp.diffusivity       = 1.3;
    const DiffusionOperator<1> diffusion(disc, dp);

    std::vector<unsigned char> fixed(disc.n_owned() + disc.n_ghost());
    for (unsigned int i = 0; i < fixed.size(); ++i)
      fixed[i] = disc.region[i] == Discretization<1>::constrained;
    TrilinosWrappers::SparseMatrix Kb, Kd;
    Stiffness::assemble(bb, Kb, fixed);
    diffusion.assemble_backward_euler(std::numeric_limits<double>::infinity(), Kd);

    TrilinosWrappers::MPI::Vector x(Stiffness::owned_dofs(disc), MPI_COMM_WORLD), yb(x), yd(x);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      x[disc.partitioner()->local_to_global(i)] = noise(disc.id[i], 0);
    x.compress(VectorOperation::insert);
    Kb.vmult(yb, x);
    Kd.vmult(yd, x);
    const double scale = yd.linfty_norm();
    yb -= yd;
    check(yb.linfty_norm() < 1e-13 * scale,
          "1D: linearized bond-based stiffness = step-3's J_1 matrix (max diff " +
            sci(yb.linfty_norm() / scale) + " relative)");

    // The Gershgorin step of the unconstrained 1D matrix is (3.8): the row
    // sum is 2 sum_j c omega beta V_j / |xi|.
    TrilinosWrappers::SparseMatrix Kfull;
    Stiffness::assemble(bb, Kfull);
    check_close(Stiffness::critical_time_step(Kfull, 2.5), bb.critical_time_step(2.5), 1e-13,
                "1D: Gershgorin step of K = (3.8)");
  }

  // ------------------------------------------------------------ equilibrium
  template <int dim>
  void
  equilibrium_case(const std::string &model)
  {
    const double delta = 0.3;
    // 3D: m = 2 on a smaller box keeps the two-hop LPS matrix small.
    auto         p     = parameters<dim>(model, delta, dim == 2 ? 3 : 2, 2., dim == 2 ? 1. : 0.6);
    p.layer_displacement = [](const Point<dim> &x) {
      Tensor<1, dim> v;
      v[0] = 1e-2 * x[0] * x[0];
      return v;
    };
    p.body_force = [](const Point<dim> &x) {
      Tensor<1, dim> v;
      v[dim - 1] = std::cos(x[0]);
      return v;
    };
    StaticMechanicsSolver<dim> s(MPI_COMM_WORLD, p);
    s.setup();
    s.solve();
    const auto R = s.reaction_force(), B = s.total_body_force();
    // Sum_i V_i f_i = 0 (pairwise antisymmetric forces): R = -sum b V.
    check((R + B).norm() < 1e-9 * B.norm(),
          model + " " + std::to_string(dim) + "D: reaction " + sci(R[dim - 1]) +
            " balances the body force " + sci(B[dim - 1]) + " (|R + B| = " +
            sci((R + B).norm()) + ")");
    // Quadratic energy: E(u) = 1/2 u . grad E = -1/2 sum V u . f(u).
    const auto &disc = s.discretization();
    typename StaticMechanicsSolver<dim>::VectorField f;
    for (auto &c : f)
      disc.initialize_vector(c);
    s.compute_forces(s.displacement(), f);
    double w = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        w -= 0.5 * disc.volume[i] * s.displacement()[d].local_element(i) * f[d].local_element(i);
    w = Utilities::MPI::sum(w, MPI_COMM_WORLD);
    check_close(s.strain_energy(), w, 1e-12,
                model + " " + std::to_string(dim) + "D: strain energy = -1/2 sum V u.f(u)");
  }

  void
  test_equilibrium()
  {
    equilibrium_case<2>("linearized bond-based");
    equilibrium_case<2>("LPS");
    equilibrium_case<3>("LPS");
  }

  // -------------------------------------------------------------------- rank
  // Run on 2 ranks: the 2-rank solution equals the solution on a
  // communicator with one rank (rank 0 alone solves again) to the solver
  // tolerance.
  template <int dim>
  void
  rank_case(const std::string &model, const std::string &solver)
  {
    auto p = parameters<dim>(model, 0.3, dim == 2 ? 3 : 2, 2., dim == 2 ? 1. : 0.6);
    p.solver = solver;
    p.layer_displacement = [](const Point<dim> &x) {
      Tensor<1, dim> v;
      v[0] = 1e-2 * x[1] * x[0];
      v[1] = -1e-2 * x[0];
      return v;
    };
    p.body_force = [](const Point<dim> &x) {
      Tensor<1, dim> v;
      v[0] = std::sin(3. * x[1]);
      return v;
    };
    StaticMechanicsSolver<dim> s(MPI_COMM_WORLD, p);
    s.setup();
    s.solve();
    std::map<types::particle_index, Tensor<1, dim>> mine;
    const auto &disc = s.discretization();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        mine[disc.id[i]][d] = s.displacement()[d].local_element(i);
    const auto all = Utilities::MPI::gather(MPI_COMM_WORLD, mine, 0);

    MPI_Comm self;
    const int rank = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD);
    MPI_Comm_split(MPI_COMM_WORLD, rank == 0 ? 0 : MPI_UNDEFINED, 0, &self);
    if (rank == 0)
      {
        StaticMechanicsSolver<dim> s1(self, p);
        s1.setup();
        s1.solve();
        double diff = 0., norm = 0.;
        const auto &d1 = s1.discretization();
        std::map<types::particle_index, unsigned int> local;
        for (unsigned int i = 0; i < d1.n_owned(); ++i)
          local[d1.id[i]] = i;
        std::size_t n = 0;
        for (const auto &part : all)
          for (const auto &[id, v] : part)
            {
              ++n;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  const double v1 = s1.displacement()[d].local_element(local.at(id));
                  diff = std::max(diff, std::abs(v[d] - v1));
                  norm = std::max(norm, std::abs(v1));
                }
            }
        check(n == d1.n_global(), "every node compared");
        // CG stops at a relative residual 1e-12; with cond(K) ~ 1e3 the
        // solutions agree to ~1e-9 relative; the direct solver to round-off.
        const double tol = solver == "direct" ? 1e-11 : 1e-8;
        check(diff <= tol * norm, model + " " + std::to_string(dim) + "D " + solver +
                                    ": 2 ranks vs 1 rank max diff " + sci(diff / norm) +
                                    " (relative) <= " + sci(tol));
        MPI_Comm_free(&self);
      }
  }

  void
  test_rank()
  {
    rank_case<2>("linearized bond-based", "cg-amg");
    rank_case<2>("LPS", "cg-amg");
    rank_case<2>("LPS", "direct");
    rank_case<3>("LPS", "cg-amg");
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"matrix", test_matrix},
              {"patch", test_patch},
              {"manufactured", test_manufactured},
              {"equilibrium", test_equilibrium},
              {"rank", test_rank},
              {"trig", test_trig},
              {"step3_1d", test_step3_1d},
              {"scan", scan}});
}
