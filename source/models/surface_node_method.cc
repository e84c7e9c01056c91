#include <deal.II/lac/lapack_full_matrix.h>

#include <perideal/base/exceptions.h>
#include <perideal/models/surface_node_method.h>

#include <cmath>
#include <complex>
#include <sstream>

namespace PeriDEAL
{
  FictitiousExtrapolation
  parse_fictitious_extrapolation(const std::string &name, const std::string &parameter)
  {
    if (name == "linear Taylor")
      return FictitiousExtrapolation::linear_taylor;
    if (name == "antisymmetric")
      return FictitiousExtrapolation::antisymmetric;
    if (name == "symmetric")
      return FictitiousExtrapolation::symmetric;
    throw ParameterError(parameter, name, "one of 'linear Taylor', 'antisymmetric', 'symmetric'");
  }

  SurfaceNodeRod::SurfaceNodeRod(const SurfaceNodeRodParameters &parameters)
    : prm(parameters)
  {
    const double length = prm.right - prm.left;
    check_parameter(length > 0., "Rod/Right end", prm.right, "a value > the left end");
    check_parameter(prm.dx > 0., "Rod/Grid spacing", prm.dx, "a positive number");
    check_parameter(prm.delta >= prm.dx, "Rod/Horizon", prm.delta,
                    "a value >= the grid spacing");
    check_parameter(prm.exponent < 3., "Rod/Kernel exponent", prm.exponent,
                    "a value < 3 (finite second moment in 1D)");
    n = (unsigned int)std::llround(length / prm.dx);
    check_parameter(n >= 2 && std::abs(n * prm.dx - length) < 1e-9 * length,
                    "Rod/Grid spacing", prm.dx,
                    "a value dividing the rod length into at least 2 cells");
    const auto &d = prm.diffusivity;
    check_parameter(d.low >= 0. && d.high >= 0. && d.mixed >= 0., "Rod/Micro-diffusivity",
                    d.max(), "non-negative values");

    // Offsets o >= 1 whose cell [o dx - dx/2, o dx + dx/2] overlaps the
    // horizon (0, delta); beta is the overlapping fraction (003 Fig. 5).
    const double tol = 1e-12 * prm.delta;
    for (unsigned int o = 1;; ++o)
      {
        const double r    = o * prm.dx;
        double       beta = prm.partial_volume ?
                              std::min(1., (prm.delta - (r - 0.5 * prm.dx)) / prm.dx) :
                              (r <= prm.delta + tol ? 1. : 0.);
        if (beta <= tol / prm.dx)
          break;
        bond_weight.push_back(std::pow(r, -prm.exponent) * beta * prm.dx);
      }
    n_fict = bond_weight.size();
    self_weight = prm.self_transfer ? 0.5 * std::pow(prm.dx, -prm.exponent) * prm.dx : 0.;

    for (unsigned int side = 0; side < 2; ++side)
      {
        const auto ext = prm.extrapolation[side];
        if (ext != FictitiousExtrapolation::linear_taylor)
          check_parameter(n >= n_fict, "Rod/Grid spacing", prm.dx,
                          "a value giving at least delta/dx interior nodes (mirror nodes "
                          "of the fictitious layer)");
        if (ext != FictitiousExtrapolation::symmetric &&
            prm.condition[side].type == SurfaceCondition::Type::flux)
          check_parameter(d.low == d.high && d.low == d.mixed, "Rod/Boundary condition",
                          "flux", "Dirichlet for a two-phase rod (the flux condition is "
                                  "solved as a linear equation for the surface value)");
        const unsigned int b = side == 0 ? 0 : n - 1;
        fictitious[side].resize(n_fict);
        for (unsigned int j = 0; j < n_fict; ++j)
          {
            auto &c = fictitious[side][j];
            // mirror of f about the surface node
            const unsigned int m = side == 0 ? j : n - 1 - j;
            switch (ext)
              {
                case FictitiousExtrapolation::linear_taylor:
                  {
                    // c_f = (x_f - x_s)/(x_s - x_b) = (j + 1/2) dx / (dx/2)
                    const double cf = 2. * j + 1.;
                    c.surface       = 1. + cf;
                    c.interior      = {{b, -cf}};
                    break;
                  }
                case FictitiousExtrapolation::antisymmetric:
                  c.surface  = 2.;
                  c.interior = {{m, -1.}};
                  break;
                case FictitiousExtrapolation::symmetric:
                  c.surface  = 0.;
                  c.interior = {{m, 1.}};
                  break;
              }
          }
        // Bonds crossing the surface: interior node a steps from the
        // surface, fictitious node j: length (a + j + 1) dx.
        for (unsigned int a = 0; a < std::min(n, n_fict); ++a)
          for (unsigned int j = 0; a + j + 1 <= n_fict; ++j)
            crossing[side].emplace_back(side == 0 ? a : n - 1 - a, j,
                                        bond_weight[a + j] * prm.dx);
      }
  }

  std::array<double, 2>
  SurfaceNodeRod::surface_values(const double t, const std::vector<double> &C) const
  {
    std::array<double, 2> s = {{0., 0.}};
    for (unsigned int side = 0; side < 2; ++side)
      {
        if (prm.extrapolation[side] == FictitiousExtrapolation::symmetric)
          continue;
        const auto &cond = prm.condition[side];
        if (cond.type == SurfaceCondition::Type::dirichlet)
          s[side] = cond.value(t);
        else
          {
            // J = J0 + g C_s is affine in C_s (single phase): solve J = value.
            const double d  = prm.diffusivity.low;
            double       J0 = 0., g = 0.;
            for (const auto &[i, j, w] : crossing[side])
              {
                const auto &f  = fictitious[side][j];
                double      cf = 0.;
                for (const auto &[k, a] : f.interior)
                  cf += a * C[k];
                J0 -= w * d * (cf - C[i]);
                g -= w * d * f.surface;
              }
            s[side] = (cond.value(t) - J0) / g;
          }
      }
    return s;
  }

  void
  SurfaceNodeRod::extend(const double t, const std::vector<double> &C, std::vector<double> &E) const
  {
    AssertDimension(C.size(), n);
    E.resize(n + 2 * n_fict);
    const auto s = surface_values(t, C);
    std::copy(C.begin(), C.end(), E.begin() + n_fict);
    for (unsigned int side = 0; side < 2; ++side)
      for (unsigned int j = 0; j < n_fict; ++j)
        {
          const auto &f = fictitious[side][j];
          double      v = f.surface * s[side];
          for (const auto &[k, a] : f.interior)
            v += a * C[k];
          E[side == 0 ? n_fict - 1 - j : n_fict + n + j] = v;
        }
  }

  double
  SurfaceNodeRod::surface_flux(const unsigned int         side,
                               const double               t,
                               const std::vector<double> &C) const
  {
    std::vector<double> E;
    extend(t, C, E);
    double J = 0.;
    for (const auto &[i, j, w] : crossing[side])
      {
        const double cf = E[side == 0 ? n_fict - 1 - j : n_fict + n + j];
        J -= w * prm.diffusivity(C[i], cf) * (cf - C[i]);
      }
    return J;
  }

  void
  SurfaceNodeRod::rate(const double               t,
                       const std::vector<double> &C,
                       std::vector<double>       &dCdt,
                       const Source              &source) const
  {
    std::vector<double> E;
    extend(t, C, E);
    dCdt.assign(n, 0.);
    const auto &dfun = prm.diffusivity;
    for (unsigned int i = 0; i < n; ++i)
      {
        const unsigned int e  = n_fict + i;
        const double       ce = E[e];
        double             s  = 0.;
        for (unsigned int o = 1; o <= n_fict; ++o)
          {
            const double cr = E[e + o], cl = E[e - o];
            s += bond_weight[o - 1] * (dfun(ce, cr) * (cr - ce) + dfun(ce, cl) * (cl - ce));
          }
        if (self_weight > 0.)
          s += self_weight * (dfun(ce, E[e + 1]) * (E[e + 1] - ce) +
                              dfun(ce, E[e - 1]) * (E[e - 1] - ce));
        dCdt[i] = s;
      }
    if (source)
      source(t, C, dCdt);
  }

  void
  SurfaceNodeRod::forward_euler_step(double              &t,
                                     const double         dt,
                                     std::vector<double> &C,
                                     const Source        &source) const
  {
    std::vector<double> r;
    rate(t, C, r, source);
    for (unsigned int i = 0; i < n; ++i)
      C[i] += dt * r[i];
    t += dt;
  }

  void
  SurfaceNodeRod::rk4_step(double &t, const double dt, std::vector<double> &C,
                           const Source &source) const
  {
    std::vector<double> k1, k2, k3, k4, y(n);
    rate(t, C, k1, source);
    for (unsigned int i = 0; i < n; ++i)
      y[i] = C[i] + 0.5 * dt * k1[i];
    rate(t + 0.5 * dt, y, k2, source);
    for (unsigned int i = 0; i < n; ++i)
      y[i] = C[i] + 0.5 * dt * k2[i];
    rate(t + 0.5 * dt, y, k3, source);
    for (unsigned int i = 0; i < n; ++i)
      y[i] = C[i] + dt * k3[i];
    rate(t + dt, y, k4, source);
    for (unsigned int i = 0; i < n; ++i)
      C[i] += dt / 6. * (k1[i] + 2. * k2[i] + 2. * k3[i] + k4[i]);
    t += dt;
  }

  FullMatrix<double>
  SurfaceNodeRod::operator_matrix() const
  {
    // The homogeneous problem: zero boundary data, one phase with the
    // largest micro-diffusivity. Columns by applying the rate to unit vectors.
    SurfaceNodeRodParameters h = prm;
    h.diffusivity              = PhaseChangeDiffusivity::single_phase(prm.diffusivity.max());
    for (auto &c : h.condition)
      c.value = [](double) { return 0.; };
    const SurfaceNodeRod homogeneous(h);
    FullMatrix<double>   L(n, n);
    std::vector<double>  e(n, 0.), r;
    for (unsigned int k = 0; k < n; ++k)
      {
        e[k] = 1.;
        homogeneous.rate(0., e, r);
        for (unsigned int i = 0; i < n; ++i)
          L(i, k) = r[i];
        e[k] = 0.;
      }
    return L;
  }

  SurfaceNodeRod::GershgorinBound
  SurfaceNodeRod::gershgorin_bound() const
  {
    const FullMatrix<double> L = operator_matrix();
    GershgorinBound          g;
    g.time_step = std::numeric_limits<double>::infinity();
    for (unsigned int i = 0; i < n; ++i)
      {
        double radius = 0.;
        for (unsigned int k = 0; k < n; ++k)
          if (k != i)
            radius += std::abs(L(i, k));
        const double diag = -L(i, i);
        if (radius > diag * (1. + 1e-12))
          g.upper_half_guaranteed = false;
        const double bound = 2. / (diag + radius);
        if (bound < g.time_step)
          {
            g.time_step = bound;
            g.row       = i;
          }
      }
    return g;
  }

  void
  SurfaceNodeRod::check_time_step(const double dt, const std::string &parameter) const
  {
    const auto         g = gershgorin_bound();
    std::ostringstream allowed;
    allowed.precision(6);
    const double d  = prm.diffusivity.max();
    auto         mu = [this](const double r) { return std::pow(r, -prm.exponent); };
    allowed << "a value in (0, " << g.time_step
            << "], the Gershgorin bound of the forward Euler iteration matrix (row of x = "
            << position(g.row) << "; 003 Sect. 3: bulk bound (16) = "
            << StabilityBounds::bulk(d, mu, prm.dx, n_fict);
    const bool taylor = prm.extrapolation[0] == FictitiousExtrapolation::linear_taylor ||
                        prm.extrapolation[1] == FictitiousExtrapolation::linear_taylor;
    if (taylor)
      allowed << ", linear-Taylor surface node bound "
              << (prm.self_transfer ? "(18) = " : "(17) = ")
              << (prm.self_transfer ?
                    StabilityBounds::linear_taylor_self_transfer(d, mu, prm.dx, n_fict) :
                    StabilityBounds::linear_taylor(d, mu, prm.dx, n_fict));
    allowed << ", both with beta = 1)";
    if (!g.upper_half_guaranteed)
      allowed << "; note: condition (32) fails in some row, so Gershgorin does not "
                 "guarantee stability for any step";
    check_parameter(dt > 0. && dt <= g.time_step * (1. + 1e-12), parameter, dt, allowed.str());
  }

  namespace
  {
    std::vector<std::complex<double>>
    eigenvalues(const FullMatrix<double> &L)
    {
      LAPACKFullMatrix<double> A(L.m(), L.n());
      A = L;
      A.compute_eigenvalues();
      std::vector<std::complex<double>> ev(L.m());
      for (unsigned int i = 0; i < L.m(); ++i)
        ev[i] = A.eigenvalue(i);
      return ev;
    }
  } // namespace

  double
  SurfaceNodeRod::eigenvalue_time_step() const
  {
    const auto ev    = eigenvalues(operator_matrix());
    double     scale = 0.;
    for (const auto &l : ev)
      scale = std::max(scale, std::abs(l));
    double dt = std::numeric_limits<double>::infinity();
    for (const auto &l : ev)
      {
        if (l.real() > 1e-12 * scale)
          return 0.; // a growing mode: unstable for every step
        if (std::abs(l) > 1e-14 * scale)
          dt = std::min(dt, -2. * l.real() / std::norm(l));
      }
    return dt;
  }

  double
  SurfaceNodeRod::spectral_radius(const double dt) const
  {
    double rho = 0.;
    for (const auto &l : eigenvalues(operator_matrix()))
      rho = std::max(rho, std::abs(1. + dt * l));
    return rho;
  }

  std::vector<double>
  SurfaceNodeRod::interface_positions(const std::vector<double> &C) const
  {
    const double ci    = prm.diffusivity.threshold;
    auto         phase = [ci](const double c) { return c < ci ? 0 : (c > ci ? 2 : 1); };
    std::vector<double> x;
    for (unsigned int i = 0; i + 1 < n; ++i)
      if (phase(C[i]) != phase(C[i + 1]))
        x.push_back(0.5 * (position(i) + position(i + 1)));
    return x;
  }

  double
  RodErrorHistory::max_after(const double t0) const
  {
    double e = 0.;
    for (unsigned int k = 0; k < time.size(); ++k)
      if (time[k] >= t0 * (1. - 1e-12))
        e = std::max(e, error[k]);
    return e;
  }

  RodErrorHistory
  run_against_reference(const SurfaceNodeRod                        &rod,
                        const std::function<double(double)>         &initial,
                        const std::function<double(double, double)> &exact,
                        const double                                 dt,
                        const double                                 t_end,
                        const bool                                   rk4,
                        const double                                 scale,
                        const double                                 dense_until,
                        const double                                 sample_interval)
  {
    check_parameter(dt > 0. && dt <= t_end, "time step", dt, "a value in (0, end time]");
    const unsigned int  n = rod.n_nodes();
    std::vector<double> C(n);
    for (unsigned int i = 0; i < n; ++i)
      C[i] = initial(rod.position(i));
    RodErrorHistory h;
    double          t      = 0.;
    const auto      record = [&]() {
      double s = 0.;
      for (unsigned int i = 0; i < n; ++i)
        s += std::pow(C[i] - exact(rod.position(i), t), 2);
      h.time.push_back(t);
      h.error.push_back(std::sqrt(s / n) / scale);
    };
    const unsigned int steps  = std::llround(t_end / dt);
    const unsigned int stride = std::max(1u, (unsigned int)std::llround(sample_interval / dt));
    for (unsigned int s = 1; s <= steps; ++s)
      {
        if (rk4)
          rod.rk4_step(t, dt, C);
        else
          rod.forward_euler_step(t, dt, C);
        if (t <= dense_until * (1. + 1e-12) || s % stride == 0 || s == steps)
          record();
      }
    return h;
  }

  InterfaceTrack
  track_interface(const SurfaceNodeRod                                &rod,
                  const std::function<double(double, double)>         &exact,
                  const std::function<double(double)>                 &exact_interface,
                  const std::function<double(double, double, double)> &source,
                  const double                                         dt,
                  const double                                         t_end,
                  const unsigned int                                   record_every)
  {
    const double ci     = rod.parameters().diffusivity.threshold;
    const auto   outer = [&](const std::vector<double> &C) {
      const auto x = rod.interface_positions(C);
      if (!x.empty())
        return x.back();
      // no crossing: the whole rod is on one side
      return C[0] > ci ? rod.parameters().left : rod.parameters().right;
    };
    const SurfaceNodeRod::Source src = [&](const double t, const std::vector<double> &C,
                                           std::vector<double> &rate) {
      const double xi = outer(C);
      for (unsigned int i = 0; i < C.size(); ++i)
        rate[i] += source(rod.position(i), t, xi);
    };
    std::vector<double> C(rod.n_nodes());
    for (unsigned int i = 0; i < C.size(); ++i)
      C[i] = exact(rod.position(i), 0.);
    InterfaceTrack tr;
    double         t = 0., previous = outer(C);
    tr.time.push_back(0.);
    tr.numerical.push_back(previous);
    tr.exact.push_back(exact_interface(0.));
    const unsigned int steps = std::llround(t_end / dt);
    for (unsigned int s = 1; s <= steps; ++s)
      {
        rod.forward_euler_step(t, dt, C, src);
        const double xn = outer(C), xe = exact_interface(t);
        tr.max_interface_error = std::max(tr.max_interface_error, std::abs(xn - xe));
        tr.max_outward_step    = std::max(tr.max_outward_step, xn - previous);
        previous               = xn;
        for (unsigned int i = 0; i < C.size(); ++i)
          {
            const double e = std::abs(C[i] - exact(rod.position(i), t));
            if (e > tr.max_concentration_error)
              {
                tr.max_concentration_error = e;
                tr.time_of_max_error       = t;
                tr.position_of_max_error   = rod.position(i);
              }
          }
        if (s % record_every == 0 || s == steps)
          {
            tr.time.push_back(t);
            tr.numerical.push_back(xn);
            tr.exact.push_back(xe);
          }
      }
    return tr;
  }

  namespace StabilityBounds
  {
    double
    bulk(const double d, const std::function<double(double)> &mu, const double dx,
         const unsigned int m_bar)
    {
      double s = 0.;
      for (unsigned int m = 1; m <= m_bar; ++m)
        s += mu(m * dx);
      return 1. / (2. * d * s * dx);
    }

    double
    linear_taylor(const double d, const std::function<double(double)> &mu, const double dx,
                  const unsigned int m_bar)
    {
      double s = 0.;
      for (unsigned int m = 1; m <= m_bar; ++m)
        s += mu(m * dx) * (m + 1.);
      return 1. / (d * s * dx);
    }

    double
    linear_taylor_self_transfer(const double d, const std::function<double(double)> &mu,
                                const double dx, const unsigned int m_bar)
    {
      double s = 0.;
      for (unsigned int m = 1; m <= m_bar; ++m)
        s += mu(m * dx) * (m + 1.);
      return 1. / (d * (s + 0.5 * mu(dx)) * dx);
    }
  } // namespace StabilityBounds
} // namespace PeriDEAL
