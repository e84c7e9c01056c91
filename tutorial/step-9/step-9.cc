// step-9: the meshfree WLS collocation quadrature (dissertation Sect. 3.2)
// against the standard scheme.
//
// The idea of this step: the standard scheme integrates the PD operator with
// one quadrature point per family node (weights beta V kernel); the WLS
// scheme fits a complete polynomial of order k through n_c collocation nodes
// (weighted least squares, (3.24)-(3.31)) and integrates the fit exactly over
// the full ball, so each node gets n_c weights w_i = L Q_i and the scheme
// is exact for polynomials up to degree k (C^k consistency), independently
// of dx. Two examples of the source:
//
// E1 (Sect. 3.2.5, Table 3.1): 1D static elasticity on (-100, 100),
//   0 = int c (u' - u)/|xi| dxi + b, c = 2E/delta^2, E = 1, u = sin(x/10).
//   (a) m-convergence at delta = 6 with the exact nonlocal source (3.74);
//   (b) delta-convergence at m = 12 with the local source (3.76).
//   Standard scheme (the DiffusionOperator with kernel exponent 1, as in
//   step-3) against WLS-2/4/6 (n_c = 5/11/13).
// E2 (Sect. 3.2.6, Table 3.2): 2D transient PD diffusion on (-0.5, 0.5)^2,
//   kappa = 1, q = 2, omega_0, manufactured solution (3.77)-(3.78),
//   dx = 1/39, delta = 5 dx, forward Euler dt = 1e-5, on a uniform and a
//   randomly perturbed (<= 0.35 dx) grid: standard against WLS-2 (29
//   collocation nodes) and WLS-4 (49).
//
// The program prints tables, writes CSVs and PNG plots and returns non-zero
// unless the checks (see the Checks sections) pass.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/timer.h>

#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/io/plot.h>
#include <perideal/models/diffusion.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step9
{
  std::string
  num(const double x, const int digits = 4)
  {
    std::ostringstream s;
    s << std::setprecision(digits) << x;
    return s.str();
  }

  std::vector<double>
  parse_list(const std::string &s)
  {
    std::vector<double> v;
    for (const auto &t : Utilities::split_string_list(s))
      v.push_back(Utilities::string_to_double(t));
    return v;
  }

  // @sect3{E1: 1D static elasticity}
  //
  // Scheme 0 is the standard scheme, k = 2, 4, 6 are WLS-k.
  struct StaticResult
  {
    double delta = 0., m = 0.;
    int    scheme = 0;
    double error  = std::numeric_limits<double>::quiet_NaN();
    double cond_min = 0., cond_max = 0.;
  };

  // The exact nonlocal source factor of (3.74) by quadrature of the smooth
  // integrand: -L sin(x/10) = 2c int_0^delta (1 - cos(s/10))/s ds sin(x/10)
  // (equal to 2c [gamma - Ci(delta/10) + ln(delta/10)]; step-3 evaluates
  // that form with a series).
  double
  nonlocal_source_factor(const double delta, const double young)
  {
    const double    c = 2. * young / (delta * delta);
    const QGauss<1> q(20);
    double          s = 0.;
    for (unsigned int i = 0; i < q.size(); ++i)
      {
        const double t = delta * q.point(i)[0];
        s += q.weight(i) * delta * (1. - std::cos(t / 10.)) / t;
      }
    return 2. * c * s;
  }

  // Solve 0 = L u + f sin(x/10) on (-100, 100) with u = sin(x/10) on the
  // layer of thickness delta; relative l2 error over the body nodes.
  StaticResult
  solve_static(const double delta, const double m, const int scheme, const bool partial_volume,
               const double young, const double source_factor)
  {
    StaticResult r;
    r.delta  = delta;
    r.m      = m;
    r.scheme = scheme;
    LatticeParameters lattice;
    lattice.dx              = delta / m;
    lattice.delta           = delta;
    lattice.layer_thickness = delta;
    lattice.partial_volume  = partial_volume;
    BoxDomain<1>      box(Point<1>(-100.), Point<1>(100.));
    Discretization<1> disc(MPI_COMM_SELF);
    disc.setup(box, lattice);
    const unsigned int n     = disc.n_owned();
    auto               exact = [](const double x) { return std::sin(x / 10.); };
    std::vector<double> u(n);

    if (scheme == 0)
      {
        // The standard scheme: the J_1 diffusion operator of step-3
        // (c = 2E/delta^2 from the kernel's second moment), one direct solve.
        DiffusionModelParameters model;
        model.omega             = InfluenceFunction::constant;
        model.exponent          = 1.;
        model.diffusivity       = young;
        model.micro_diffusivity = 0.;
        const DiffusionOperator<1>     op(disc, model);
        TrilinosWrappers::SparseMatrix matrix;
        op.assemble_backward_euler(std::numeric_limits<double>::infinity(), matrix);
        PeriDEAL::Vector layer, rhs;
        disc.initialize_vector(layer);
        disc.initialize_vector(rhs);
        for (unsigned int i = 0; i < n; ++i)
          {
            const double x = disc.position[i][0];
            if (disc.region[i] == Discretization<1>::interior)
              rhs.local_element(i) = source_factor * exact(x);
            else
              layer.local_element(i) = rhs.local_element(i) = exact(x);
          }
        op.add_constrained_coupling(layer, rhs);
        const auto                   &part = *disc.partitioner();
        TrilinosWrappers::MPI::Vector b(part.locally_owned_range(), MPI_COMM_SELF), x(b);
        for (unsigned int i = 0; i < n; ++i)
          b[part.local_to_global(i)] = rhs.local_element(i);
        b.compress(VectorOperation::insert);
        SolverControl                  control(1, 0.);
        TrilinosWrappers::SolverDirect direct(control);
        direct.solve(matrix, x, b);
        for (unsigned int i = 0; i < n; ++i)
          u[i] = x[part.local_to_global(i)];
      }
    else
      {
        // WLS-k: row i of the body is sum_j w_ij u_j = -f sin(x_i/10), the
        // layer rows are the identity. Non-symmetric and banded: sparse LU.
        ScalarKernel kernel;
        kernel.dim      = 1;
        kernel.omega    = InfluenceFunction::constant;
        kernel.exponent = 1.;
        kernel.delta    = delta;
        kernel.constant = 2. * young / (delta * delta);
        WlsParameters prm;
        prm.order = scheme;
        WlsQuadrature<1> wls(prm, kernel);
        try
          {
            wls.build(disc);
          }
        catch (const ParameterError &)
          {
            return r; // too few nodes in the horizon for this order: NaN
          }
        std::tie(r.cond_min, r.cond_max) = wls.condition_range();
        std::vector<Eigen::Triplet<double>> t;
        Eigen::VectorXd                     b(n);
        for (unsigned int i = 0; i < n; ++i)
          if (disc.region[i] != Discretization<1>::interior)
            {
              t.emplace_back(i, i, 1.);
              b(i) = exact(disc.position[i][0]);
            }
        for (unsigned int k = 0; k < wls.node.size(); ++k)
          {
            const unsigned int i = wls.node[k];
            for (auto e = wls.row_start[k]; e < wls.row_start[k + 1]; ++e)
              t.emplace_back(i, wls.col[e], wls.weight[e]);
            b(i) = -source_factor * exact(disc.position[i][0]);
          }
        Eigen::SparseMatrix<double> A(n, n);
        A.setFromTriplets(t.begin(), t.end());
        Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(A);
        AssertThrow(lu.info() == Eigen::Success, ExcMessage("WLS system is singular"));
        const Eigen::VectorXd x = lu.solve(b);
        for (unsigned int i = 0; i < n; ++i)
          u[i] = x(i);
      }
    double e2 = 0., n2 = 0.;
    for (unsigned int i = 0; i < n; ++i)
      if (disc.region[i] == Discretization<1>::interior)
        {
          const double ue = exact(disc.position[i][0]);
          e2 += (u[i] - ue) * (u[i] - ue);
          n2 += ue * ue;
        }
    r.error = std::sqrt(e2 / n2);
    return r;
  }

  // @sect3{E2: 2D transient diffusion}
  //
  // (3.77) C = sin(5t) P(x, y), P = x^2y^2 + x^3y + x^4 + xy^3 + y^4, and
  // (3.78) S = 5 cos(5t) P - (pi delta^2/16) sin(5t) (7 delta^2 + 56 x^2 +
  // 48 xy + 56 y^2), the exact nonlocal source for kappa = 1, q = 2, omega_0.
  double
  polynomial_p(const Point<2> &p)
  {
    const double x = p[0], y = p[1];
    return x * x * y * y + x * x * x * y + x * x * x * x + x * y * y * y + y * y * y * y;
  }

  double
  source_s(const Point<2> &p, const double t, const double delta)
  {
    const double x = p[0], y = p[1];
    return 5. * std::cos(5. * t) * polynomial_p(p) -
           M_PI * delta * delta / 16. * std::sin(5. * t) *
             (7. * delta * delta + 56. * x * x + 48. * x * y + 56. * y * y);
  }

  struct TransientResult
  {
    std::string         name;
    bool                perturbed = false;
    std::vector<double> times, errors;
    double              cond_min = 0., cond_max = 0.;
    /** Spectral abscissa max Re(lambda) of the body block of the operator
        and the forward Euler amplification max |1 + dt lambda| (if computed). */
    double max_real = std::numeric_limits<double>::quiet_NaN(),
           max_amplification = std::numeric_limits<double>::quiet_NaN();
  };

  // Nodes of the body (-0.5, 0.5)^2 at cell centres, dx = 1/n, plus a layer of
  // thickness delta; optionally each node moved by a random vector of length
  // uniform in [0, perturbation dx].
  void
  e2_nodes(const unsigned int n, const unsigned int layer, const double perturbation,
           const unsigned int seed, std::vector<Point<2>> &pts, std::vector<bool> &body)
  {
    const double                           dx = 1. / n;
    std::mt19937                           gen(seed);
    std::uniform_real_distribution<double> radius(0., perturbation * dx), angle(0., 2. * M_PI);
    pts.clear();
    body.clear();
    const int lo = -int(layer), hi = int(n + layer);
    for (int j = lo; j < hi; ++j)
      for (int i = lo; i < hi; ++i)
        {
          Point<2> p(-0.5 + (i + 0.5) * dx, -0.5 + (j + 0.5) * dx);
          if (perturbation > 0.)
            {
              const double r = radius(gen), a = angle(gen);
              p += Tensor<1, 2>({r * std::cos(a), r * std::sin(a)});
            }
          pts.push_back(p);
          body.push_back(i >= 0 && i < int(n) && j >= 0 && j < int(n));
        }
  }

  // Forward Euler C^{n+1} = C^n + dt (L C^n + S^n) on the body, exact values
  // on the layer; scheme 0 standard (partial volumes, V = dx^2), k WLS-k.
  TransientResult
  run_transient(const int scheme, const bool perturbed, const unsigned int n,
                const double perturbation, const unsigned int seed, const double dt,
                const std::vector<double> &report_times, const bool spectrum,
                const unsigned int n_collocation)
  {
    const double       dx = 1. / n, delta = 5. * dx;
    const unsigned int layer = 5;
    TransientResult    r;
    r.name      = scheme == 0 ? "standard" : "WLS-" + std::to_string(scheme);
    r.perturbed = perturbed;
    std::vector<Point<2>> pts;
    std::vector<bool>     body;
    e2_nodes(n, layer, perturbed ? perturbation : 0., seed, pts, body);
    std::vector<std::uint64_t> fs;
    std::vector<std::int32_t>  f;
    build_node_families<2>(pts, delta + 0.5 * dx, fs, f);
    std::vector<unsigned int> rows;
    for (unsigned int i = 0; i < pts.size(); ++i)
      if (body[i])
        rows.push_back(i);

    // One CSR operator for both schemes: rows = body nodes.
    std::vector<std::uint64_t> start(1, 0);
    std::vector<std::int32_t>  col;
    std::vector<double>        w;
    if (scheme == 0)
      for (const unsigned int i : rows)
        {
          double diag = 0.;
          for (auto b = fs[i]; b < fs[i + 1]; ++b)
            {
              const double r2   = pts[f[b]].distance(pts[i]);
              const double beta = Discretization<2>::volume_factor(r2, delta, dx, true);
              if (beta == 0.)
                continue;
              const double wij = beta * dx * dx / (r2 * r2);
              col.push_back(f[b]);
              w.push_back(wij);
              diag -= wij;
            }
          col.push_back(i);
          w.push_back(diag);
          start.push_back(col.size());
        }
    else
      {
        ScalarKernel kernel;
        kernel.dim      = 2;
        kernel.omega    = InfluenceFunction::constant;
        kernel.exponent = 2.;
        kernel.delta    = delta;
        kernel.constant = 1.;
        WlsParameters prm;
        prm.order         = scheme;
        prm.n_collocation = n_collocation;
        WlsQuadrature<2> wls(prm, kernel);
        wls.build(pts, fs, f, rows);
        start = wls.row_start;
        col   = wls.col;
        w     = wls.weight;
        std::tie(r.cond_min, r.cond_max) = wls.condition_range();
      }

    // The body block of the operator (layer values are data): its
    // eigenvalues decide the stability of the semi-discrete system (Re < 0)
    // and of forward Euler (|1 + dt lambda| <= 1).
    if (spectrum)
      {
        std::vector<int> body_index(pts.size(), -1);
        for (unsigned int k = 0; k < rows.size(); ++k)
          body_index[rows[k]] = k;
        Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows.size(), rows.size());
        for (unsigned int k = 0; k < rows.size(); ++k)
          for (auto e = start[k]; e < start[k + 1]; ++e)
            if (body_index[col[e]] >= 0)
              A(k, body_index[col[e]]) += w[e];
        const Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
        r.max_real = -std::numeric_limits<double>::infinity();
        r.max_amplification = 0.;
        for (const auto &l : es.eigenvalues())
          {
            r.max_real          = std::max(r.max_real, l.real());
            r.max_amplification = std::max(r.max_amplification, std::abs(1. + dt * l));
          }
      }

    std::vector<double> C(pts.size(), 0.), rate(rows.size());
    double              t    = 0.;
    const double        tend = report_times.back();
    unsigned int        next = 0;
    const auto          n_steps = static_cast<unsigned long>(std::llround(tend / dt));
    for (unsigned long s = 1; s <= n_steps; ++s)
      {
        for (unsigned int k = 0; k < rows.size(); ++k)
          {
            double v = 0.;
            for (auto e = start[k]; e < start[k + 1]; ++e)
              v += w[e] * C[col[e]];
            rate[k] = v + source_s(pts[rows[k]], t, delta);
          }
        for (unsigned int k = 0; k < rows.size(); ++k)
          C[rows[k]] += dt * rate[k];
        t = s * dt;
        for (unsigned int i = 0; i < pts.size(); ++i)
          if (!body[i])
            C[i] = std::sin(5. * t) * polynomial_p(pts[i]);
        if (next < report_times.size() && t >= report_times[next] - 0.5 * dt)
          {
            // (3.79): relative l2 error over the body nodes.
            double e2 = 0., n2 = 0.;
            for (const unsigned int i : rows)
              {
                const double ce = std::sin(5. * t) * polynomial_p(pts[i]);
                e2 += (C[i] - ce) * (C[i] - ce);
                n2 += ce * ce;
              }
            r.times.push_back(t);
            r.errors.push_back(std::sqrt(e2 / n2));
            ++next;
          }
      }
    return r;
  }

  // @sect3{Parameters}
  struct Parameters
  {
    double              young = 1., m_delta = 6., delta_m = 12.;
    std::vector<double> m_values, delta_values;
    double              wls4_min = 1., wls4_max = 3., wls6_min = 4., wls6_max = 6.;
    unsigned int        e2_n = 39, e2_seed = 1;
    double              e2_dt = 1e-5, e2_perturbation = 0.35;
    std::vector<double> e2_times;
    double              max_wls_change = 0.15;
    bool                e2_spectrum    = false;
    double              e2_check_end   = 1e300;
    std::vector<unsigned int> e2_nc{29, 49};
    std::string         output = "step-9-output";

    static void
    declare(ParameterHandler &prm)
    {
      prm.enter_subsection("E1");
      prm.declare_entry("Young's modulus", "1", Patterns::Double(0.), "");
      prm.declare_entry("m-convergence horizon", "6", Patterns::Double(0.), "");
      prm.declare_entry("m values", "2, 3, 4, 6, 8, 12, 16, 24, 33",
                        Patterns::List(Patterns::Double(1.)), "");
      prm.declare_entry("delta-convergence m", "12", Patterns::Double(1.), "");
      prm.declare_entry("delta values", "6, 4, 3, 2, 1.5, 1, 0.75",
                        Patterns::List(Patterns::Double(0.)), "");
      prm.declare_entry("WLS-4 gain band", "1, 3", Patterns::List(Patterns::Double()),
                        "Allowed log10(e_WLS2/e_WLS4) at the finest m (source: about 2).");
      prm.declare_entry("WLS-6 gain band", "4, 6", Patterns::List(Patterns::Double()),
                        "Allowed log10(e_WLS2/e_WLS6) at the finest m (source: about 5).");
      prm.leave_subsection();
      prm.enter_subsection("E2");
      prm.declare_entry("Nodes per side", "39", Patterns::Integer(10), "dx = 1/n, delta = 5 dx.");
      prm.declare_entry("Time step", "1e-5", Patterns::Double(0.), "");
      prm.declare_entry("Report times", "0.005, 0.01, 0.015, 0.02",
                        Patterns::List(Patterns::Double(0.)), "Increasing; the last is the end.");
      prm.declare_entry("Perturbation", "0.35", Patterns::Double(0., 0.5),
                        "Largest node displacement in units of dx.");
      prm.declare_entry("Random seed", "1", Patterns::Integer(0), "");
      prm.declare_entry("Collocation nodes", "29, 49", Patterns::List(Patterns::Integer(0)),
                        "n_c of WLS-2 and WLS-4 (Table 3.2: 29, 49).");
      prm.declare_entry("Check end time", "1e300", Patterns::Double(0.),
                        "The checks use the reported times up to this one.");
      prm.declare_entry("Spectrum", "false", Patterns::Bool(),
                        "Compute the eigenvalues of the body block of each operator.");
      prm.declare_entry("Maximum WLS error change", "0.15", Patterns::Double(0.),
                        "Allowed relative change of the WLS-4 error uniform -> perturbed.");
      prm.leave_subsection();
      prm.declare_entry("Output directory", "step-9-output", Patterns::Anything(), "");
    }

    void
    parse(ParameterHandler &prm)
    {
      prm.enter_subsection("E1");
      young        = prm.get_double("Young's modulus");
      m_delta      = prm.get_double("m-convergence horizon");
      m_values     = parse_list(prm.get("m values"));
      delta_m      = prm.get_double("delta-convergence m");
      delta_values = parse_list(prm.get("delta values"));
      const auto b4 = parse_list(prm.get("WLS-4 gain band")),
                 b6 = parse_list(prm.get("WLS-6 gain band"));
      check_parameter(b4.size() == 2 && b6.size() == 2, "E1/WLS-4 gain band",
                      prm.get("WLS-4 gain band"), "two numbers (both bands)");
      wls4_min = b4[0], wls4_max = b4[1], wls6_min = b6[0], wls6_max = b6[1];
      check_parameter(m_values.size() >= 2, "E1/m values", prm.get("m values"),
                      "at least two values");
      check_parameter(delta_values.size() >= 3, "E1/delta values", prm.get("delta values"),
                      "at least three values");
      prm.leave_subsection();
      prm.enter_subsection("E2");
      e2_n            = prm.get_integer("Nodes per side");
      e2_dt           = prm.get_double("Time step");
      e2_times        = parse_list(prm.get("Report times"));
      e2_perturbation = prm.get_double("Perturbation");
      e2_seed         = prm.get_integer("Random seed");
      e2_spectrum     = prm.get_bool("Spectrum");
      e2_check_end    = prm.get_double("Check end time");
      const auto nc   = parse_list(prm.get("Collocation nodes"));
      check_parameter(nc.size() == 2, "E2/Collocation nodes", prm.get("Collocation nodes"),
                      "two numbers (WLS-2, WLS-4)");
      e2_nc = {static_cast<unsigned int>(nc[0]), static_cast<unsigned int>(nc[1])};
      max_wls_change  = prm.get_double("Maximum WLS error change");
      check_parameter(!e2_times.empty() && std::is_sorted(e2_times.begin(), e2_times.end()) &&
                        e2_times.front() > 0.,
                      "E2/Report times", prm.get("Report times"),
                      "a non-empty increasing list of positive times");
      prm.leave_subsection();
      output = prm.get("Output directory");
    }
  };
} // namespace Step9

int
main(int argc, char **argv)
{
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      check_parameter(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) == 1, "MPI ranks",
                      Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD),
                      "1 (step-9 is a serial study)");
      ParameterHandler prm;
      Step9::Parameters::declare(prm);
      prm.parse_input(argc > 1 ? argv[1] : "step-9.prm");
      Step9::Parameters par;
      par.parse(prm);
      std::filesystem::create_directories(par.output);
      Timer timer;

      bool ok     = true;
      auto report = [&](const bool c, const std::string &what) {
        std::cout << (c ? "  ok    " : "  FAIL  ") << what << "\n";
        ok = ok && c;
      };
      using Step9::num;
      const std::vector<int>         schemes = {0, 2, 4, 6};
      const std::vector<std::string> names   = {"standard", "WLS-2", "WLS-4", "WLS-6"};

      // @sect3{E1}
      const double f_nonlocal = Step9::nonlocal_source_factor(par.m_delta, par.young);
      if (par.m_delta == 6. && par.young == 1.)
        report(std::abs(f_nonlocal - 0.0098512) < 5e-8,
               "source (3.74), delta = 6: b = " + num(f_nonlocal, 8) +
                 " sin(x/10) (catalog 0.0098512)");
      // The standard scheme of the source: full volumes (beta = 1); the
      // partial-volume variant is shown as "standard (pv)" (see step-3).
      std::vector<std::vector<Step9::StaticResult>> mres(5), dres(5);
      for (unsigned int s = 0; s < 5; ++s)
        {
          const int  scheme = s < 4 ? schemes[s] : 0;
          const bool pv     = s == 4;
          for (const double m : par.m_values)
            mres[s].push_back(
              Step9::solve_static(par.m_delta, m, scheme, pv, par.young, f_nonlocal));
          for (const double d : par.delta_values)
            dres[s].push_back(
              Step9::solve_static(d, par.delta_m, scheme, pv, par.young, par.young / 100.));
        }
      auto e1_table = [&](const std::vector<std::vector<Step9::StaticResult>> &res,
                          const bool by_m, const std::string &file) {
        std::ofstream csv(par.output + "/" + file);
        csv << (by_m ? "m" : "delta") << ",standard,WLS-2,WLS-4,WLS-6,standard_pv\n";
        std::cout << "| " << (by_m ? "m" : "delta")
                  << " | standard (beta=1) | WLS-2 | WLS-4 | WLS-6 | standard (partial vol.) |\n"
                  << "|---:|---:|---:|---:|---:|---:|\n";
        for (unsigned int k = 0; k < res[0].size(); ++k)
          {
            const double x = by_m ? res[0][k].m : res[0][k].delta;
            csv << x;
            std::cout << "| " << x;
            for (unsigned int s = 0; s < 5; ++s)
              {
                csv << "," << std::setprecision(6) << res[s][k].error;
                std::cout << " | "
                          << (std::isnan(res[s][k].error) ? std::string("-") :
                                                            num(res[s][k].error, 4));
              }
            csv << "\n";
            std::cout << " |\n";
          }
      };
      std::cout << "\nE1 (a) m-convergence, delta = " << par.m_delta
                << ", nonlocal source (3.74): rel. l2 error\n";
      e1_table(mres, true, "e1_m_convergence.csv");
      std::cout << "\nE1 (b) delta-convergence, m = " << par.delta_m
                << ", local source (3.76): rel. l2 error\n";
      e1_table(dres, false, "e1_delta_convergence.csv");
      for (unsigned int s = 1; s < 4; ++s)
        std::cout << "  cond(A_i) " << names[s] << " at m = " << mres[s].back().m << ": ["
                  << num(mres[s].back().cond_min) << ", " << num(mres[s].back().cond_max)
                  << "]\n";

      // @sect3{E1 checks}
      // (i) WLS-k is C^k: at fixed delta its error does not fall with m
      //     (plateau): error(finest m) >= 0.5 error(first m where the order
      //     fits). Measured: the WLS errors change by < 1 % over m.
      // (ii) WLS-4 and WLS-6 are "about two and five orders" more accurate
      //     than WLS-2 (source, Fig. 3.4): log10 gains at the finest m in the
      //     bands of the parameter file (the catalog's suggestion, 2 +- 1
      //     and 5 +- 1: the figure is only read by eye, and the gains depend
      //     on how the collocation nodes sit in the horizon).
      // (iii) WLS-2 at the coarsest m where it runs beats the standard
      //     scheme (beta = 1) at the finest m.
      // (iv) delta-convergence: every WLS error decreases monotonically; the
      //     standard scheme with beta = 1 does not converge (its error at the
      //     smallest delta is not below half its error at the largest, see
      //     step-3 for the E_eff = (1 + 1/m) E reason).
      for (unsigned int s = 1; s < 4; ++s)
        {
          double first = std::numeric_limits<double>::quiet_NaN();
          for (const auto &r : mres[s])
            if (!std::isnan(r.error))
              {
                first = r.error;
                break;
              }
          const double last = mres[s].back().error;
          report(last >= 0.5 * first && last <= 2. * first,
                 names[s] + " m-convergence plateau: error " + num(first) + " -> " + num(last));
        }
      const double g4 = std::log10(mres[1].back().error / mres[2].back().error),
                   g6 = std::log10(mres[1].back().error / mres[3].back().error);
      report(g4 >= par.wls4_min && g4 <= par.wls4_max,
             "log10(e_WLS2/e_WLS4) = " + num(g4, 3) + " in [" + num(par.wls4_min) + ", " +
               num(par.wls4_max) + "] (source: about 2)");
      report(g6 >= par.wls6_min && g6 <= par.wls6_max,
             "log10(e_WLS2/e_WLS6) = " + num(g6, 3) + " in [" + num(par.wls6_min) + ", " +
               num(par.wls6_max) + "] (source: about 5)");
      {
        double e_wls2 = std::numeric_limits<double>::quiet_NaN(), m_wls2 = 0.;
        for (const auto &r : mres[1])
          if (!std::isnan(r.error))
            {
              e_wls2 = r.error;
              m_wls2 = r.m;
              break;
            }
        report(e_wls2 < mres[0].back().error,
               "WLS-2 at m = " + num(m_wls2) + " (" + num(e_wls2) + ") beats standard at m = " +
                 num(mres[0].back().m) + " (" + num(mres[0].back().error) + ")");
      }
      for (unsigned int s = 1; s < 4; ++s)
        {
          bool mono = true;
          for (unsigned int k = 1; k < dres[s].size(); ++k)
            mono = mono && dres[s][k].error < dres[s][k - 1].error;
          report(mono, names[s] + " delta-convergence monotone: " + num(dres[s].front().error) +
                         " -> " + num(dres[s].back().error));
        }
      report(dres[0].back().error > 0.5 * dres[0].front().error,
             "standard (beta = 1) does not delta-converge: " + num(dres[0].front().error) +
               " -> " + num(dres[0].back().error));

      // @sect3{E2}
      std::vector<Step9::TransientResult> e2;
      for (const bool pert : {false, true})
        for (const int s : {0, 2, 4})
          e2.push_back(Step9::run_transient(s, pert, par.e2_n, par.e2_perturbation,
                                            par.e2_seed, par.e2_dt, par.e2_times,
                                            par.e2_spectrum,
                                            s == 2 ? par.e2_nc[0] : s == 4 ? par.e2_nc[1] : 0));
      std::cout << "\nE2 2D diffusion, dx = 1/" << par.e2_n << ", delta = 5 dx, dt = "
                << par.e2_dt << ": rel. l2 error (3.79)\n| t | standard | WLS-2 | WLS-4 | "
                << "standard (pert.) | WLS-2 (pert.) | WLS-4 (pert.) |\n"
                << "|---:|---:|---:|---:|---:|---:|---:|\n";
      {
        std::ofstream csv(par.output + "/e2_error.csv");
        csv << "t,standard,WLS-2,WLS-4,standard_pert,WLS-2_pert,WLS-4_pert\n";
        for (unsigned int k = 0; k < e2[0].times.size(); ++k)
          {
            std::cout << "| " << num(e2[0].times[k]);
            csv << e2[0].times[k];
            for (const auto &r : e2)
              {
                std::cout << " | " << num(r.errors[k]);
                csv << "," << std::setprecision(8) << r.errors[k];
              }
            std::cout << " |\n";
            csv << "\n";
          }
      }
      for (const auto &r : e2)
        if (r.name != "standard")
          std::cout << "  cond(A_i) " << r.name << (r.perturbed ? " perturbed" : " uniform")
                    << ": [" << num(r.cond_min) << ", " << num(r.cond_max) << "]\n";
      if (par.e2_spectrum)
        for (const auto &r : e2)
          std::cout << "  spectrum " << r.name << (r.perturbed ? " perturbed" : " uniform")
                    << ": max Re(lambda) = " << num(r.max_real)
                    << ", max |1 + dt lambda| = " << num(r.max_amplification, 10) << "\n";

      // @sect3{E2 checks}
      // Evaluated at the reported times t <= 'Check end time' (index kc);
      // see the doc page for why (the WLS-4 operator with n_c = 49 has
      // eigenvalues with positive real part, so its error eventually grows
      // like exp(max Re(lambda) t) whatever dt is).
      // (i) perturbed grid: WLS-4 < WLS-2 < standard at every checked time
      //     (source Fig. 3.6: WLS more accurate at all times, WLS-4 best);
      // (ii) uniform grid: WLS-4 < WLS-2, and WLS-2 within 5 % of the
      //     standard scheme: on a uniform lattice with partial volumes the
      //     standard scheme is itself exact for quadratics (step-3), so WLS-2
      //     has no consistency advantage there; measured 0.9 % below it at
      //     t <= 0.02 and 3 % above at t = 0.1 (the source's "WLS better at all
      //     times" is reproduced for WLS-4 only);
      // (iii) relative change of the error at the last checked time from the
      //     uniform to the perturbed grid: WLS-4 below 'Maximum WLS error
      //     change' (source 7.09 %; WLS-4 is exact for the quartic (3.77), so
      //     only the time discretization and round-off see the nodes), and the
      //     standard scheme's change at least 10 times either WLS change
      //     (source 38.63 % vs 6.53 / 7.09 %, a factor 5.5; measured here
      //     factors > 60: our standard scheme keeps V = dx^2 and beta on the
      //     perturbed grid, which is O(1)-inconsistent, while its uniform error
      //     is small).
      unsigned int kc = 0;
      while (kc + 1 < e2[0].times.size() && e2[0].times[kc + 1] <= par.e2_check_end * (1 + 1e-12))
        ++kc;
      {
        bool order_p = true, order_u = true, close_u = true;
        for (unsigned int k = 0; k <= kc; ++k)
          {
            order_p = order_p && e2[5].errors[k] < e2[4].errors[k] &&
                      e2[4].errors[k] < e2[3].errors[k];
            order_u = order_u && e2[2].errors[k] < e2[1].errors[k];
            close_u = close_u && e2[1].errors[k] < 1.05 * e2[0].errors[k];
          }
        const std::string upto = " for t <= " + num(e2[0].times[kc]);
        report(order_p, "perturbed grid: WLS-4 < WLS-2 < standard" + upto);
        report(order_u, "uniform grid: WLS-4 < WLS-2" + upto);
        report(close_u, "uniform grid: WLS-2 < 1.05 standard" + upto);
      }
      std::vector<double> change(3);
      for (unsigned int s = 0; s < 3; ++s)
        change[s] = std::abs(e2[s + 3].errors[kc] - e2[s].errors[kc]) / e2[s].errors[kc];
      std::cout << "  relative change of the error at t = " << num(e2[0].times[kc])
                << " uniform -> perturbed: standard " << num(100 * change[0]) << " %, WLS-2 "
                << num(100 * change[1]) << " %, WLS-4 " << num(100 * change[2])
                << " % (source, final time: 38.63 / 6.53 / 7.09 %)\n";
      report(change[2] < par.max_wls_change,
             "WLS-4 error change < " + num(100 * par.max_wls_change) + " %");
      report(change[0] > 10. * std::max(change[1], change[2]),
             "standard scheme's change > 10 x either WLS change");
      if (par.e2_spectrum)
        for (const unsigned int s : {0u, 1u, 3u, 4u})
          report(e2[s].max_real < 0. && e2[s].max_amplification <= 1.,
                 e2[s].name + (e2[s].perturbed ? " perturbed" : " uniform") +
                   ": stable (max Re(lambda) < 0, forward Euler amplification <= 1)");

      // @sect3{Plots}
      const std::string o = par.output + "/";
      run_gnuplot(o + "e1.gp",
                  gnuplot_png_preamble(o + "e1.png") +
                    "set datafile separator ','\nset logscale xy\nset format y '10^{%T}'\n"
                    "set grid\nset key outside right\nset multiplot layout 1,2\n"
                    "set title 'E1 m-convergence, delta = 6'\nset xlabel 'm'\n"
                    "set ylabel 'relative l2 error'\n"
                    "plot for [c=2:6] '" + o + "e1_m_convergence.csv' using 1:c with linespoints "
                    "lw 2 title columnheader(c)\n"
                    "set title 'E1 delta-convergence, m = 12'\nset xlabel 'delta'\n"
                    "plot for [c=2:6] '" + o + "e1_delta_convergence.csv' using 1:c with "
                    "linespoints lw 2 title columnheader(c)\nunset multiplot\n",
                  o + "e1.png");
      run_gnuplot(o + "e2.gp",
                  gnuplot_png_preamble(o + "e2.png") +
                    "set datafile separator ','\nset logscale y\nset format y '10^{%T}'\n"
                    "set grid\nset key outside right\nset title 'E2 2D diffusion, dx = 1/" +
                    std::to_string(par.e2_n) + ", delta = 5 dx'\nset xlabel 't'\n"
                    "set ylabel 'relative l2 error (3.79)'\n"
                    "plot for [c=2:4] '" + o + "e2_error.csv' using 1:c with linespoints lw 2 "
                    "title columnheader(c), for [c=5:7] '" + o + "e2_error.csv' using 1:c with "
                    "linespoints lw 2 dt 2 title columnheader(c)\n",
                  o + "e2.png");
      std::cout << "wall time " << num(timer.wall_time(), 3) << " s\n"
                << (ok ? "PASSED" : "FAILED") << std::endl;
      return ok ? 0 : 1;
    }
  catch (std::exception &e)
    {
      std::cerr << "step-9: " << e.what() << std::endl;
      return 1;
    }
}
