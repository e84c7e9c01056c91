// step-3: 1D static PD elasticity with a manufactured solution; m- and
// delta-convergence of the standard scheme.
//
// The idea of this step: a static (equilibrium) problem. The PD operator is
// assembled once into a Trilinos matrix and one linear system is solved; and
// the two notions of convergence of a nonlocal model are separated:
//   m-convergence      delta fixed, dx = delta/m -> 0: the discrete solution
//                      approaches the *nonlocal* solution (quadrature error);
//   delta-convergence  m fixed, delta -> 0: it should approach the *local*
//                      (classical) solution (quadrature + model error).
//
// Problem (dissertation Sect. 3.2.4-3.2.5): on (-100, 100),
//   0 = int_{x-delta}^{x+delta} c (u(x') - u(x)) / |x' - x| dx' + b(x)   (3.72)
// with c = 2E/delta^2, E = 1, the constant influence function, and Dirichlet
// values from u_ex = sin(x/10) (3.73) on a layer of thickness delta outside
// both ends. In 1D, the scalar PD operator of DiffusionOperator with kernel
// exponent 1 (J_1) and micro-constant c is exactly the integral of (3.72),
// and ScalarKernel::micro_constant_for(E) gives c = 2E/delta^2.
//
// (a) m-convergence, delta = 6, the exact nonlocal source (3.74)
//       b = 2c [gamma - Ci(delta/10) + ln(delta/10)] sin(x/10)
//     (the printed "e" is the Euler-Mascheroni constant gamma, see the
//     errata), so u_ex solves (3.72) exactly and the error is the quadrature
//     error of the standard scheme alone.
// (b) delta-convergence, m = 12, the local source (3.76) b = sin(x/10)/100
//     of the local limit 0 = E u'' + b (3.75), against u = sin(x/10).
//
// The program prints both tables, writes CSVs and a log-log plot, and returns
// non-zero unless what the source reports (and what we measure robustly) is
// reproduced: see the Checks section.

#include <deal.II/base/table_handler.h>
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
#include <perideal/io/plot.h>
#include <perideal/models/diffusion.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step3
{
  // @sect3{The cosine integral}
  constexpr double euler_gamma = 0.57721566490153286061;

  // Ci(x) = gamma + ln x + sum_{k>=1} (-x^2)^k / (2k (2k)!) for 0 < x <= 4.
  // The terms are computed by recurrence; the largest term is below
  // cosh(x) ~ 27 at x = 4, so at most two digits are lost to cancellation.
  double
  cosine_integral(const double x)
  {
    AssertThrow(x > 0. && x <= 4.,
                ExcMessage("cosine_integral: the series is used for 0 < x <= 4 only"));
    double term = 1., sum = 0.;
    for (unsigned int k = 1; k < 100; ++k)
      {
        term *= -x * x / ((2. * k - 1.) * (2. * k));
        sum += term / (2. * k);
        if (std::abs(term) < 1e-18 * std::abs(sum))
          break;
      }
    return euler_gamma + std::log(x) + sum;
  }

  // An independent evaluation for the self-check: gamma + ln x plus the
  // integral of the smooth function (cos t - 1)/t over (0, x) by composite
  // 12-point Gauss-Legendre quadrature on 8 intervals (error far below 1e-15
  // for x <= 4).
  double
  cosine_integral_by_quadrature(const double x)
  {
    const QGauss<1>    q(12);
    const unsigned int n = 8;
    double             s = 0.;
    for (unsigned int k = 0; k < n; ++k)
      for (unsigned int i = 0; i < q.size(); ++i)
        {
          const double t = x * (k + q.point(i)[0]) / n;
          s += q.weight(i) * (x / n) * (std::cos(t) - 1.) / t;
        }
    return euler_gamma + std::log(x) + s;
  }

  // Numbers in messages: @p digits significant digits.
  std::string
  num(const double x, const int digits = 4)
  {
    std::ostringstream s;
    s << std::setprecision(digits) << x;
    return s.str();
  }

  // @sect3{Parameters}
  struct Parameters
  {
    double              young = 1.;
    double              m_study_horizon = 6.;
    std::vector<double> m_values;
    double              delta_study_m = 12.;
    std::vector<double> delta_values;
    double              min_m_reduction = 10.;
    double              max_delta_reduction = 2.;
    std::vector<bool>   partial_volume;
    std::string         output = "step-3-output";

    static void
    declare(ParameterHandler &prm)
    {
      prm.enter_subsection("Study");
      prm.declare_entry("Young's modulus", "1", Patterns::Double(0.), "E; c = 2E/delta^2.");
      prm.declare_entry("m-convergence horizon", "6", Patterns::Double(0.),
                        "delta of the m-convergence study (nonlocal source (3.74)).");
      prm.declare_entry("m values", "2, 3, 4, 6, 8, 12, 16, 24, 33",
                        Patterns::List(Patterns::Double(1.)), "m = delta/dx of the m-convergence study.");
      prm.declare_entry("delta-convergence m", "12", Patterns::Double(1.),
                        "Fixed m = delta/dx of the delta-convergence study (local source (3.76)).");
      prm.declare_entry("delta values", "6, 4, 3, 2, 1.5, 1, 0.75",
                        Patterns::List(Patterns::Double(0.)), "Horizons of the delta-convergence study.");
      prm.declare_entry("Minimum m-convergence reduction", "10", Patterns::Double(1.),
                        "Required error(coarsest m) / error(finest m).");
      prm.declare_entry("Maximum delta-convergence reduction", "2", Patterns::Double(1.),
                        "For a variant whose E_eff differs from E (beta = 1): the "
                        "delta-convergence error must NOT fall by more than this factor "
                        "from the largest to the smallest horizon (it levels off).");
      prm.declare_entry("Partial volume variants", "true, false",
                        Patterns::List(Patterns::Bool()),
                        "Run both studies with these settings of the volume reduction "
                        "factor beta (true: partial volumes (3.2); false: beta = 1 inside "
                        "delta). Overrides Discretization/Partial volume.");
      prm.declare_entry("Output directory", "step-3-output", Patterns::Anything(), "");
      prm.leave_subsection();
    }
    void
    parse(ParameterHandler &prm)
    {
      prm.enter_subsection("Study");
      young           = prm.get_double("Young's modulus");
      m_study_horizon = prm.get_double("m-convergence horizon");
      for (const auto &s : Utilities::split_string_list(prm.get("m values")))
        m_values.push_back(Utilities::string_to_double(s));
      delta_study_m = prm.get_double("delta-convergence m");
      for (const auto &s : Utilities::split_string_list(prm.get("delta values")))
        delta_values.push_back(Utilities::string_to_double(s));
      min_m_reduction     = prm.get_double("Minimum m-convergence reduction");
      max_delta_reduction = prm.get_double("Maximum delta-convergence reduction");
      output              = prm.get("Output directory");
      for (const auto &s : Utilities::split_string_list(prm.get("Partial volume variants")))
        partial_volume.push_back(s == "true" || s == "yes");
      prm.leave_subsection();
      check_parameter(m_values.size() >= 2, "Study/m values", prm.get("Study/m values"),
                      "at least two values");
      check_parameter(delta_values.size() >= 3, "Study/delta values",
                      prm.get("Study/delta values"), "at least three values");
    }
  };

  // @sect3{One static solve}
  struct Result
  {
    double                  delta = 0., m = 0., dx = 0.;
    bool                    partial_volume = true;
    types::global_dof_index nodes = 0;
    double                  l2_error = 0., max_error = 0.;
    double                  residual = 0., kernel_constant_error = 0.;
    double                  seconds = 0.;
  };

  // Solve -L u = b on the body with u = u_ex on the layer, for horizon
  // @p delta, dx = delta/m, and the source b(x) = @p source_factor sin(x/10).
  // The error is measured against sin(x/10) over the body nodes.
  Result
  solve(const Domain<1> &domain, LatticeParameters lattice, const double delta, const double m,
        const double young, const double source_factor)
  {
    Timer  timer;
    Result r;
    r.partial_volume = lattice.partial_volume;
    r.delta = delta;
    r.m     = m;
    r.dx    = delta / m;

    lattice.dx              = delta / m;
    lattice.delta           = delta;
    lattice.layer_thickness = delta;
    Discretization<1> disc(MPI_COMM_WORLD);
    disc.setup(domain, lattice);
    r.nodes = disc.n_global();

    // J_1 kernel, constant omega, c from the local modulus by quadrature of
    // the kernel's second moment; in 1D that is 2E/delta^2 (checked below).
    DiffusionModelParameters model;
    model.type              = "diffusion";
    model.omega             = InfluenceFunction::constant;
    model.exponent          = 1.;
    model.diffusivity       = young;
    model.micro_diffusivity = 0.;
    const DiffusionOperator<1> op(disc, model);
    r.kernel_constant_error =
      std::abs(op.kernel().constant - 2. * young / (delta * delta)) / (2. * young / (delta * delta));

    // dt = infinity: I/dt - L = -L on the body rows, identity on layer rows.
    TrilinosWrappers::SparseMatrix matrix;
    op.assemble_backward_euler(std::numeric_limits<double>::infinity(), matrix);

    auto exact = [](const double x) { return std::sin(x / 10.); };
    PeriDEAL::Vector u_layer, rhs;
    disc.initialize_vector(u_layer);
    disc.initialize_vector(rhs);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double x = disc.position[i][0];
        if (disc.region[i] == Discretization<1>::interior)
          rhs.local_element(i) = source_factor * exact(x);
        else
          {
            u_layer.local_element(i) = exact(x);
            rhs.local_element(i)     = exact(x);
          }
      }
    u_layer.update_ghost_values();
    op.add_constrained_coupling(u_layer, rhs);

    const auto                 &part = *disc.partitioner();
    TrilinosWrappers::MPI::Vector b(part.locally_owned_range(), MPI_COMM_WORLD);
    TrilinosWrappers::MPI::Vector u(b), res(b);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      b[part.local_to_global(i)] = rhs.local_element(i);
    b.compress(VectorOperation::insert);

    // 1D: a banded system of a few thousand unknowns; a direct solver is
    // the simplest and exact to round-off.
    SolverControl                 control(1, 0.);
    TrilinosWrappers::SolverDirect direct(control);
    direct.solve(matrix, u, b);
    matrix.vmult(res, u);
    res -= b;
    r.residual = res.l2_norm() / b.l2_norm();

    double e2 = 0., n2 = 0., emax = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<1>::interior)
        {
          const double ue = exact(disc.position[i][0]);
          const double e  = u[part.local_to_global(i)] - ue;
          e2 += e * e;
          n2 += ue * ue;
          emax = std::max(emax, std::abs(e));
        }
    e2         = Utilities::MPI::sum(e2, MPI_COMM_WORLD);
    n2         = Utilities::MPI::sum(n2, MPI_COMM_WORLD);
    r.l2_error = std::sqrt(e2 / n2);
    r.max_error = Utilities::MPI::max(emax, MPI_COMM_WORLD);
    r.seconds   = timer.wall_time();
    return r;
  }

  // The exact nonlocal source factor of (3.74): -L sin(x/10) = f sin(x/10).
  double
  nonlocal_source_factor(const double delta, const double young)
  {
    const double c = 2. * young / (delta * delta);
    return 2. * c * (euler_gamma - cosine_integral(delta / 10.) + std::log(delta / 10.));
  }

  // The local modulus the discrete operator converges to at fixed m: apply
  // the lattice stencil to x^2/2, E_eff = (1/2) sum_j c omega/|xi_j| beta_j
  // dx xi_j^2 over both sides. With partial volumes and integer m this is
  // the trapezoidal rule for int |xi| d xi and E_eff = E exactly; with
  // beta = 1 it is sum_{j=1}^m j dx^2 / (delta^2/2) E = (1 + 1/m) E.
  double
  effective_modulus(const double young, const double m, const bool partial_volume)
  {
    const double delta = 1., dx = delta / m, c = 2. * young / (delta * delta);
    double       s = 0.;
    for (unsigned int j = 1; j * dx < delta + dx; ++j)
      {
        const double r = j * dx;
        s += c / std::min(r, delta) *
             Discretization<1>::volume_factor(r, delta, dx, partial_volume) * dx * r * r;
      }
    return s; // (1/2) * 2 sides
  }

  // The delta -> 0 limit of the discrete solution at fixed m: the local
  // problem E_eff u'' + b = 0 with b = E sin(x/10)/100 and u(+-100) =
  // sin(+-10), i.e. u = (E/E_eff) sin(x/10) + (1 - E/E_eff) sin(10) x/100.
  // Returns its relative l2 distance to sin(x/10) (uniform sampling).
  double
  delta_limit_error(const double young, const double e_eff)
  {
    double e2 = 0., n2 = 0.;
    for (int i = -100000; i <= 100000; ++i)
      {
        const double x  = i * 1e-3;
        const double u  = std::sin(x / 10.);
        const double uh = young / e_eff * u + (1. - young / e_eff) * std::sin(10.) * x / 100.;
        e2 += (uh - u) * (uh - u);
        n2 += u * u;
      }
    return std::sqrt(e2 / n2);
  }

  // One table per study; the observed order is
  //   log(e_{k-1}/e_k) / log(dx_{k-1}/dx_k),
  // positive when the error falls with dx (dx = delta/m in both studies).
  void
  write_table(const std::vector<Result> &rs, std::ostream &out)
  {
    TableHandler t;
    for (std::size_t k = 0; k < rs.size(); ++k)
      {
        const auto &r = rs[k];
        t.add_value("delta", r.delta);
        t.add_value("m", r.m);
        t.add_value("dx", r.dx);
        t.add_value("nodes", r.nodes);
        t.add_value("rel. l2 error", r.l2_error);
        std::ostringstream order;
        if (k == 0)
          order << "-";
        else
          order << std::fixed << std::setprecision(3)
                << std::log(rs[k - 1].l2_error / r.l2_error) / std::log(rs[k - 1].dx / r.dx);
        t.add_value("order", order.str());
        t.add_value("max error", r.max_error);
        t.add_value("wall s", r.seconds);
      }
    t.set_precision("dx", 5);
    t.set_precision("delta", 4);
    t.set_scientific("rel. l2 error", true);
    t.set_scientific("max error", true);
    t.set_precision("rel. l2 error", 4);
    t.set_precision("max error", 3);
    t.set_precision("wall s", 2);
    t.write_text(out, TableHandler::org_mode_table);
  }
} // namespace Step3

int
main(int argc, char **argv)
{
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      const bool root = Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;

      ParameterHandler prm;
      prm.enter_subsection("Geometry");
      Domain<1>::declare_parameters(prm);
      prm.leave_subsection();
      prm.enter_subsection("Discretization");
      LatticeParameters::declare_parameters(prm);
      prm.leave_subsection();
      Step3::Parameters::declare(prm);
      prm.parse_input(argc > 1 ? argv[1] : "step-3.prm");
      Step3::Parameters study;
      study.parse(prm);

      prm.enter_subsection("Geometry");
      const auto domain = Domain<1>::create(prm);
      prm.leave_subsection();
      LatticeParameters lattice;
      prm.enter_subsection("Discretization");
      lattice.parse_parameters(prm);
      prm.leave_subsection();

      bool ok     = true;
      auto report = [&](const bool c, const std::string &what) {
        if (root)
          std::cout << (c ? "  ok    " : "  FAIL  ") << what << "\n";
        ok = ok && c;
      };

      // @sect3{The cosine integral and the source (3.74)}
      if (root)
        std::cout << "Cosine integral: series against quadrature\n";
      for (const double x : {0.1, 0.6, 1., 2., 4.})
        {
          const double a = Step3::cosine_integral(x), q = Step3::cosine_integral_by_quadrature(x);
          report(std::abs(a - q) < 1e-13, "Ci(" + Step3::num(x) + ") = " +
                                            Step3::num(a, 15) + ", quadrature " +
                                            Step3::num(q, 15));
        }
      // The tabulated value Ci(0.6) = -0.0222707 (to 7 digits).
      report(std::abs(Step3::cosine_integral(0.6) + 0.0222706) < 1e-6,
             "Ci(0.6) = -0.0222706 to 1e-6");
      const double f_nonlocal = Step3::nonlocal_source_factor(study.m_study_horizon, study.young);
      if (study.m_study_horizon == 6. && study.young == 1.)
        report(std::abs(f_nonlocal - 0.0098512) < 5e-8,
               "source (3.74) for delta = 6: b = " + Step3::num(f_nonlocal, 10) +
                 " sin(x/10) (catalog: 0.0098512)");

      // @sect3{The two studies}
      // Each study is run for every requested setting of the partial-volume
      // factor beta (the source does not print which one its standard scheme
      // uses; see the doc page).
      const double f_local = study.young / 100.; // (3.76): -E u'' = sin(x/10)/100
      std::vector<std::vector<Step3::Result>> m_study, delta_study;
      for (const bool pv : study.partial_volume)
        {
          LatticeParameters l = lattice;
          l.partial_volume    = pv;
          m_study.emplace_back();
          delta_study.emplace_back();
          for (const double m : study.m_values)
            m_study.back().push_back(
              Step3::solve(*domain, l, study.m_study_horizon, m, study.young, f_nonlocal));
          for (const double delta : study.delta_values)
            delta_study.back().push_back(
              Step3::solve(*domain, l, delta, study.delta_study_m, study.young, f_local));
        }

      for (const auto &rss : {m_study, delta_study})
        for (const auto &rs : rss)
          for (const auto &r : rs)
            if (r.residual >= 1e-10 || r.kernel_constant_error >= 1e-12)
              report(false, "solve at delta = " + Step3::num(r.delta) +
                              ", m = " + Step3::num(r.m) +
                              ": residual or kernel constant wrong");

      auto tag = [](const bool pv) {
        return std::string(pv ? "partial volumes" : "full volumes (beta = 1)");
      };
      if (root)
        {
          for (unsigned int v = 0; v < study.partial_volume.size(); ++v)
            {
              std::cout << "\n(a) m-convergence, " << tag(study.partial_volume[v])
                        << ": delta = " << study.m_study_horizon
                        << ", nonlocal source (3.74); error against sin(x/10) over the body:\n";
              Step3::write_table(m_study[v], std::cout);
              std::cout << "\n(b) delta-convergence, " << tag(study.partial_volume[v])
                        << ": m = " << study.delta_study_m
                        << ", local source (3.76); error against the local solution sin(x/10):\n";
              Step3::write_table(delta_study[v], std::cout);
            }
          std::cout << "(order: log(e_prev/e)/log(dx_prev/dx), positive when the error falls)\n\n";

          std::filesystem::create_directories(study.output);
          for (const auto &[name, rss] :
               {std::make_pair(std::string("m_convergence"), &m_study),
                std::make_pair(std::string("delta_convergence"), &delta_study)})
            {
              std::ofstream csv(study.output + "/" + name + ".csv");
              csv << "partial_volume,delta,m,dx,nodes,rel_l2_error,max_error\n"
                  << std::setprecision(10);
              for (const auto &rs : *rss)
                for (const auto &r : rs)
                  csv << r.partial_volume << "," << r.delta << "," << r.m << "," << r.dx << ","
                      << r.nodes << "," << r.l2_error << "," << r.max_error << "\n";
            }
          const std::string png = study.output + "/convergence.png";
          std::string       gp =
            gnuplot_png_preamble(png) +
            "set datafile separator ','\nset logscale xy\nset format y '%.0e'\n"
            "set ylabel 'relative l2 error over the body'\nset grid\n"
            "set multiplot layout 1,2\n"
            "set title 'm-convergence, delta = " + Step3::num(study.m_study_horizon) +
            ", source (3.74)'\nset xlabel 'm = delta/dx'\nset key top right\nplot ";
          for (unsigned int v = 0; v < study.partial_volume.size(); ++v)
            gp += std::string(v ? ", " : "") + "'" + study.output +
                  "/m_convergence.csv' using ($1==" + std::to_string(int(study.partial_volume[v])) +
                  " ? $3 : 1/0):6 with linespoints lw 2 pt 7 title '" + tag(study.partial_volume[v]) + "'";
          gp += "\nset title 'delta-convergence, m = " + Step3::num(study.delta_study_m) +
                ", source (3.76)'\nset xlabel 'delta'\nset key bottom right\nplot ";
          for (unsigned int v = 0; v < study.partial_volume.size(); ++v)
            gp += std::string(v ? ", " : "") + "'" + study.output +
                  "/delta_convergence.csv' using ($1==" + std::to_string(int(study.partial_volume[v])) +
                  " ? $2 : 1/0):6 with linespoints lw 2 pt 7 title '" + tag(study.partial_volume[v]) + "'";
          gp += "\nunset multiplot\n";
          run_gnuplot(study.output + "/plot.gp", gp, png);
        }

      // @sect3{Checks}
      // What the source reports (Fig. 3.4) and what we assert:
      //
      // (a) "the accuracy of the standard scheme improves as m increases":
      // asserted as (i) the error decreases strictly from each m to the next,
      // (ii) error(coarsest m) / error(finest m) >= 'Minimum m-convergence
      // reduction' (10), and (iii) the observed order between the two finest
      // m. The source term is exact, so the error is the quadrature error of
      // the stencil alone. With partial volumes and integer m the weights
      // beta_j dx integrate the |xi| (second-moment) part exactly
      // (trapezoidal rule on a linear function); the first quadrature error
      // comes from the |xi|^3 (fourth-derivative) term and is O(dx^2):
      // order 2. With beta = 1 the second moment itself is wrong by the
      // factor 1 + 1/m (see effective_modulus()): order 1. We accept +-0.2
      // around these (measured: 2.00 and 0.97).
      //
      // (b) "the standard scheme oscillates and fails to converge" as
      // delta -> 0 at m = 12 against the local solution. At fixed m the
      // discrete operator tends to E_eff u'' with the E_eff of
      // effective_modulus(), and the discrete solution to the local solution
      // with E_eff (delta_limit_error()). So:
      //   E_eff != E (beta = 1, E_eff = 13/12 E): no convergence. Asserted:
      //     the error at the smallest delta is within 5 % of the predicted
      //     non-zero limit, and it did not fall by more than 'Maximum
      //     delta-convergence reduction' (2) from the largest delta (an
      //     O(delta^2) convergent scheme gains (6/0.75)^2 = 64 here).
      //   E_eff == E (partial volumes, integer m): the standard scheme DOES
      //     converge, with the model error O(delta^2) of (3.70). Asserted:
      //     observed order in [1.8, 2.2] between the two smallest delta. The
      //     source's finding is not reproduced by this variant (see the doc).
      // Oscillation is not asserted: we measure monotone curves for both.
      for (unsigned int v = 0; v < study.partial_volume.size(); ++v)
        {
          const bool        pv = study.partial_volume[v];
          const auto       &ms = m_study[v];
          const auto       &ds = delta_study[v];
          const std::string t  = tag(pv) + ": ";
          auto order = [](const Step3::Result &a, const Step3::Result &b) {
            return std::log(a.l2_error / b.l2_error) / std::log(a.dx / b.dx);
          };

          bool decreasing = true;
          for (std::size_t k = 1; k < ms.size(); ++k)
            decreasing = decreasing && ms[k].l2_error < ms[k - 1].l2_error;
          report(decreasing, t + "m-convergence: the error decreases with every increase of m");
          const double reduction = ms.front().l2_error / ms.back().l2_error;
          report(reduction >= study.min_m_reduction,
                 t + "m-convergence: error(m = " + Step3::num(ms.front().m) +
                   ") / error(m = " + Step3::num(ms.back().m) + ") = " +
                   Step3::num(reduction) + " >= " +
                   Step3::num(study.min_m_reduction));
          const double p_m      = order(ms[ms.size() - 2], ms.back());
          const double expected = pv ? 2. : 1.;
          report(std::abs(p_m - expected) <= 0.2,
                 t + "m-convergence: observed order " + Step3::num(p_m) + " in [" +
                   Step3::num(expected - 0.2) + ", " +
                   Step3::num(expected + 0.2) + "]");

          const double e_eff = Step3::effective_modulus(study.young, study.delta_study_m, pv);
          if (root)
            std::cout << "  note  " << t << "E_eff / E at m = " << study.delta_study_m << ": "
                      << e_eff / study.young << "\n";
          if (std::abs(e_eff / study.young - 1.) > 1e-3)
            {
              const double limit = Step3::delta_limit_error(study.young, e_eff);
              const double dev   = std::abs(ds.back().l2_error - limit) / limit;
              report(dev < 0.05, t + "delta-convergence: error at delta = " +
                                   Step3::num(ds.back().delta) + " is " +
                                   Step3::num(ds.back().l2_error) +
                                   ", within 5 % of the non-zero delta -> 0 limit " +
                                   Step3::num(limit) + " (no convergence)");
              const double red = ds.front().l2_error / ds.back().l2_error;
              report(red < study.max_delta_reduction,
                     t + "delta-convergence: error(delta = " +
                       Step3::num(ds.front().delta) + ") / error(delta = " +
                       Step3::num(ds.back().delta) + ") = " + Step3::num(red) +
                       " < " + Step3::num(study.max_delta_reduction));
            }
          else
            {
              const double p_d = order(ds[ds.size() - 2], ds.back());
              report(std::abs(p_d - 2.) <= 0.2,
                     t + "delta-convergence: E_eff = E, converges with observed order " +
                       Step3::num(p_d) + " in [1.8, 2.2] (source: no convergence)");
            }
        }
      if (root)
        std::cout << (ok ? "step-3: PASSED" : "step-3: FAILED") << std::endl;
      return ok ? 0 : 1;
    }
  catch (std::exception &e)
    {
      std::cerr << "\nstep-3: error: " << e.what() << std::endl;
      return 1;
    }
}
