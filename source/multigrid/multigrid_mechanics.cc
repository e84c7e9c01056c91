#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/lapack_full_matrix.h>
#include <deal.II/lac/vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/bond_based.h>
#include <perideal/multigrid/multigrid_mechanics.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace PeriDEAL
{
  namespace MultiGrid
  {
    namespace
    {
      double
      seconds_since(const std::chrono::steady_clock::time_point &start)
      {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }

      // Orientation of (p, q, r): > 0 counter-clockwise.
      template <int dim>
      double
      orient(const Point<dim> &p, const Point<dim> &q, const Point<dim> &r)
      {
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
      }

      // Node i's vector of an interleaved dim-component field.
      template <int dim>
      Tensor<1, dim>
      node_vector(const std::vector<double> &field, const unsigned int i)
      {
        Tensor<1, dim> w;
        for (unsigned int d = 0; d < dim; ++d)
          w[d] = field[dim * i + d];
        return w;
      }
    } // namespace

    MechanicsModel
    parse_mechanics_model(const std::string &name, const std::string &parameter)
    {
      for (const auto m : {MechanicsModel::uniform_fine, MechanicsModel::uniform_coarse,
                           MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
        if (name == to_string(m))
          return m;
      throw ParameterError(parameter, name,
                           "uniform fine|uniform coarse|adaptive standard|adaptive hybrid");
    }

    std::string
    to_string(const MechanicsModel model)
    {
      switch (model)
        {
          case MechanicsModel::uniform_fine:
            return "uniform fine";
          case MechanicsModel::uniform_coarse:
            return "uniform coarse";
          case MechanicsModel::adaptive_standard:
            return "adaptive standard";
          default:
            return "adaptive hybrid";
        }
    }

    template <int dim>
    void
    MechanicsParameters<dim>::check() const
    {
      check_parameter(coarse_dx > 0., "Coarse grid spacing", coarse_dx, "> 0");
      check_parameter(fine_dx > 0. && fine_dx <= coarse_dx, "Fine grid spacing", fine_dx,
                      "0 < dx- <= dx+");
      const double r = coarse_dx / fine_dx;
      check_parameter(std::abs(r - std::round(r)) < 1e-9 * r, "Fine grid spacing", fine_dx,
                      "dx+ / r with an integer r");
      for (unsigned int d = 0; d < dim; ++d)
        {
          const double n = (upper[d] - lower[d]) / coarse_dx;
          check_parameter(n >= 1. && std::abs(n - std::round(n)) < 1e-9 * n, "Upper corner",
                          upper[d], "lower corner + an integer multiple of dx+ in every direction");
        }
      check_parameter(delta >= coarse_dx, "Horizon", delta, ">= dx+ (m+ >= 1)");
      check_parameter(youngs_modulus > 0., "Young's modulus", youngs_modulus, "> 0");
      check_parameter(density > 0., "Density", density, "> 0");
      check_parameter(fracture_energy >= 0., "Fracture energy", fracture_energy, ">= 0");
      check_parameter(critical_stretch >= 0., "Critical stretch", critical_stretch, ">= 0");
      check_parameter(switching_sigma > 0. && switching_sigma <= 1., "Switching sigma",
                      switching_sigma, "0 < sigma <= 1");
      check_parameter(interpolation != Interpolation::nearest_active, "Interpolation",
                      "nearest active", "inverse distance|multilinear");
    }

    // ------------------------------------------------------------------ Lattice

    template <int dim>
    std::array<int, dim>
    MechanicsSolver<dim>::Lattice::index(const unsigned int i) const
    {
      std::array<int, dim> ix;
      unsigned int         k = i;
      for (unsigned int d = 0; d < dim; ++d)
        {
          ix[d] = k % n[d];
          k /= n[d];
        }
      return ix;
    }

    template <int dim>
    unsigned int
    MechanicsSolver<dim>::Lattice::node(const std::array<int, dim> &ix) const
    {
      unsigned int i = 0;
      for (int d = dim - 1; d >= 0; --d)
        i = i * n[d] + ix[d];
      return i;
    }

    template <int dim>
    bool
    MechanicsSolver<dim>::Lattice::inside(const std::array<int, dim> &ix) const
    {
      for (unsigned int d = 0; d < dim; ++d)
        if (ix[d] < 0 || ix[d] >= n[d])
          return false;
      return true;
    }

    template <int dim>
    Point<dim>
    MechanicsSolver<dim>::Lattice::point(const unsigned int i) const
    {
      const auto ix = index(i);
      Point<dim> p  = origin;
      for (unsigned int d = 0; d < dim; ++d)
        p[d] += ix[d] * dx;
      return p;
    }

    template <int dim>
    bool
    MechanicsSolver<dim>::Lattice::interior(const unsigned int i) const
    {
      const auto ix = index(i);
      for (unsigned int d = 0; d < dim; ++d)
        if (ix[d] < radius || ix[d] >= n[d] - radius)
          return false;
      return true;
    }

    // ------------------------------------------------------------------ setup

    template <int dim>
    MechanicsSolver<dim>::MechanicsSolver(const MechanicsParameters<dim> &parameters)
      : prm(parameters)
    {
      prm.check();
      ratio = static_cast<unsigned int>(std::round(prm.coarse_dx / prm.fine_dx));
      c     = bond_based_micromodulus(dim, prm.omega, prm.delta, prm.youngs_modulus,
                                  prm.plane_stress);
      s0 = prm.critical_stretch > 0. ? prm.critical_stretch :
           prm.fracture_energy > 0.  ? bond_based_critical_stretch(dim, prm.omega, prm.delta, c,
                                                                  prm.fracture_energy) :
                                       std::numeric_limits<double>::infinity();
      setup_lattice(coarse, prm.coarse_dx);
      setup_lattice(fine, prm.fine_dx);
      for (const unsigned int g : {0u, 1u})
        {
          const auto n = grids[g].n_nodes;
          u[g].assign(dim * n, 0.);
          v[g].assign(dim * n, 0.);
          a[g].assign(dim * n, 0.);
          broken[g].assign(std::size_t(n) * grids[g].offset.size(), 0);
          prescribed[g].assign(n, 0);
        }
      refined.assign(grids[coarse].n_nodes, 0);
      for (unsigned int i = 0; i < grids[coarse].n_nodes; ++i)
        switch (prm.model)
          {
            case MechanicsModel::uniform_fine:
              refined[i] = 1;
              break;
            case MechanicsModel::uniform_coarse:
              break;
            default:
              refined[i] = prm.initial_fine_region && prm.initial_fine_region(grids[coarse].point(i));
          }
      if (prm.model == MechanicsModel::adaptive_hybrid)
        setup_wls();
      update_node_sets();
      dt = 0.9 * critical_time_step();
    }

    template <int dim>
    void
    MechanicsSolver<dim>::setup_lattice(const Grid g, const double dx)
    {
      Lattice &L = grids[g];
      L.dx       = dx;
      L.volume   = std::pow(dx, dim);
      L.n_nodes  = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          L.n[d]      = static_cast<int>(std::round((prm.upper[d] - prm.lower[d]) / dx));
          L.origin[d] = prm.lower[d] + 0.5 * dx;
          L.n_nodes *= L.n[d];
        }
      // Bonds up to delta + dx/2 carry a partial volume (3.2).
      const double reach = prm.partial_volume ? prm.delta + 0.5 * dx : prm.delta * (1. + 1e-12);
      L.radius           = static_cast<int>(std::ceil(reach / dx));
      const int M        = L.radius;
      std::array<int, dim> o;
      const auto           visit = [&](auto &&self, const unsigned int d) -> void {
        if (d == dim)
          {
            Tensor<1, dim> xi;
            for (unsigned int e = 0; e < dim; ++e)
              xi[e] = o[e] * dx;
            const double r = xi.norm();
            if (r == 0.)
              return;
            const double beta =
              PeriDEAL::Discretization<dim>::volume_factor(r, prm.delta, dx, prm.partial_volume);
            if (beta <= 0.)
              return;
            long lin = 0, stride = 1;
            for (unsigned int e = 0; e < dim; ++e)
              {
                lin += o[e] * stride;
                stride *= L.n[e];
              }
            L.offset.push_back(o);
            L.linear_offset.push_back(lin);
            L.xi.push_back(xi);
            L.length.push_back(r);
            L.weight.push_back(beta * L.volume);
            L.coefficient.push_back(c * influence(prm.omega, std::min(r, prm.delta), prm.delta) *
                                    beta * L.volume / r);
            return;
          }
        for (o[d] = -M; o[d] <= M; ++o[d])
          self(self, d + 1);
      };
      visit(visit, 0);
      const unsigned int S = L.offset.size();
      L.mirror.resize(S);
      for (unsigned int k = 0; k < S; ++k)
        for (unsigned int l = 0; l < S; ++l)
          if (L.linear_offset[l] == -L.linear_offset[k])
            L.mirror[k] = l;
    }

    template <int dim>
    void
    MechanicsSolver<dim>::setup_wls()
    {
      // The coarse lattice is uniform, so every coarse node whose family is
      // complete has the same collocation weights: compute them once on a
      // patch (the family of its centre = the bond stencil).
      const Lattice          &L = grids[coarse];
      std::vector<Point<dim>> position(1);
      std::vector<long>       lin(1, 0);
      for (unsigned int k = 0; k < L.offset.size(); ++k)
        {
          position.emplace_back(Point<dim>() + L.xi[k]);
          lin.push_back(L.linear_offset[k]);
        }
      std::vector<std::uint64_t> family_start(position.size() + 1, L.offset.size());
      family_start[0] = 0;
      std::vector<std::int32_t> family;
      for (unsigned int k = 0; k < L.offset.size(); ++k)
        family.push_back(k + 1);
      WlsParameters wp;
      wp.order         = prm.wls_order;
      wp.n_collocation = prm.n_collocation;
      WlsQuadrature<dim> wls(wp, c, prm.omega, prm.delta);
      wls.build(position, family_start, family, {0u});
      wls_offset.clear();
      wls_weight.clear();
      for (auto b = wls.row_start[0]; b < wls.row_start[1]; ++b)
        {
          wls_offset.push_back(lin[wls.col[b]]);
          for (unsigned int e = 0; e < dim * dim; ++e)
            wls_weight.push_back(wls.weight[b * dim * dim + e]);
        }
      // Stability of velocity Verlet with the WLS stencil: dt <= 2 sqrt(rho
      // / lambda_max), lambda_max the largest eigenvalue of the symbol
      // -sum_k W_k cos(kappa . xi_k) (the stencil is symmetric) over the
      // Brillouin zone (sampled; the extreme wave numbers included). The
      // Gershgorin bound used for the standard scheme, (3.8), would be
      // 1.5-2x too strict here because the WLS weights alternate in sign.
      {
        const unsigned int   n_sample = 32;
        double               lambda   = 0.;
        std::array<int, dim> q{};
        const auto           visit = [&](auto &&self, const unsigned int d) -> void {
          if (d == dim)
            {
              FullMatrix<double> S(dim, dim);
              for (unsigned int k = 0; k < wls_offset.size(); ++k)
                {
                  const auto  &x   = position[std::find(lin.begin(), lin.end(), wls_offset[k]) -
                                           lin.begin()];
                  double       arg = 0.;
                  for (unsigned int e = 0; e < dim; ++e)
                    arg += M_PI * q[e] / n_sample / L.dx * x[e];
                  for (unsigned int e = 0; e < dim; ++e)
                    for (unsigned int f = 0; f < dim; ++f)
                      S(e, f) -= wls_weight[k * dim * dim + e * dim + f] * std::cos(arg);
                }
              LAPACKFullMatrix<double> M(dim, dim);
              for (unsigned int e = 0; e < dim; ++e)
                for (unsigned int f = 0; f < dim; ++f)
                  M(e, f) = 0.5 * (S(e, f) + S(f, e));
              dealii::Vector<double> ev;
              FullMatrix<double> vecs;
              M.compute_eigenvalues_symmetric(-1e300, 1e300, 0., ev, vecs);
              for (const double x : ev)
                lambda = std::max(lambda, x);
              return;
            }
          for (q[d] = -int(n_sample); q[d] <= int(n_sample); ++q[d])
            self(self, d + 1);
        };
        visit(visit, 0);
        wls_stable_step = 2. * std::sqrt(prm.density / lambda);
      }
      // Nodes whose collocation nodes all exist use WLS (the collocation
      // nodes are a subset of the bond stencil).
      use_wls.assign(L.n_nodes, 0);
      for (unsigned int i = 0; i < L.n_nodes; ++i)
        use_wls[i] = L.interior(i);
    }

    template <int dim>
    void
    MechanicsSolver<dim>::interpolation_sources(
      const Grid                                    from,
      const Point<dim>                             &x,
      std::vector<std::pair<unsigned int, double>> &out) const
    {
      // The 2^dim nodes of the lattice cell of grid @p from containing x
      // (clamped at the boundary, where the outermost nodes are half a
      // spacing inside the body).
      const Lattice       &L = grids[from];
      std::array<int, dim> lo;
      std::array<double, dim> frac;
      for (unsigned int d = 0; d < dim; ++d)
        {
          const double s = (x[d] - L.origin[d]) / L.dx;
          lo[d]          = std::clamp(static_cast<int>(std::floor(s)), 0, std::max(L.n[d] - 2, 0));
          frac[d]        = std::clamp(s - lo[d], 0., 1.);
        }
      out.clear();
      double total = 0.;
      for (unsigned int corner = 0; corner < (1u << dim); ++corner)
        {
          std::array<int, dim> ix = lo;
          double               w  = 1.;
          for (unsigned int d = 0; d < dim; ++d)
            {
              const bool up = corner & (1u << d);
              ix[d] += up && L.n[d] > 1;
              w *= up ? frac[d] : 1. - frac[d];
            }
          const unsigned int j = L.node(ix);
          if (prm.interpolation == Interpolation::inverse_distance)
            {
              const double r = (L.point(j) - x).norm();
              if (r < 1e-12 * L.dx)
                {
                  out.assign(1, {j, 1.});
                  return;
                }
              w = 1. / r;
            }
          if (w == 0.)
            continue;
          out.emplace_back(j, w);
          total += w;
        }
      for (auto &s : out)
        s.second /= total;
    }

    template <int dim>
    void
    MechanicsSolver<dim>::update_node_sets()
    {
      const Lattice &C = grids[coarse], &F = grids[fine];
      const auto     cell_of = [&](const unsigned int f) {
        auto ix = F.index(f);
        for (unsigned int d = 0; d < dim; ++d)
          ix[d] /= ratio;
        return C.node(ix);
      };
      for (const unsigned int g : {0u, 1u})
        {
          active_flag[g].assign(grids[g].n_nodes, 0);
          active[g].clear();
          fictitious[g].clear();
        }
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (!refined[i])
          {
            active_flag[coarse][i] = 1;
            active[coarse].push_back(i);
          }
      for (unsigned int f = 0; f < F.n_nodes; ++f)
        if (refined[cell_of(f)])
          {
            active_flag[fine][f] = 1;
            active[fine].push_back(f);
          }

      // An inactive node is fictitious if an active node of its grid has it
      // in its stencil (the stencil is symmetric: search its own stencil).
      const auto has_active_neighbour = [&](const Grid g, const unsigned int i) {
        const Lattice &L  = grids[g];
        const auto     ix = L.index(i);
        const bool     in = L.interior(i);
        for (unsigned int k = 0; k < L.offset.size(); ++k)
          {
            if (!in)
              {
                auto jx = ix;
                for (unsigned int d = 0; d < dim; ++d)
                  jx[d] += L.offset[k][d];
                if (!L.inside(jx))
                  continue;
              }
            if (active_flag[g][i + L.linear_offset[k]])
              return true;
          }
        return false;
      };
      if (!active[coarse].empty())
        for (unsigned int i = 0; i < C.n_nodes; ++i)
          if (refined[i] && has_active_neighbour(coarse, i))
            fictitious[coarse].push_back(i);
      if (!active[fine].empty() && !active[coarse].empty())
        {
          // Only fine nodes of unrefined cells near a refined cell can be
          // fictitious: dilate the refined cells by the stencil reach.
          const int Rc = static_cast<int>(std::ceil((F.radius * F.dx) / C.dx)) + 1;
          std::vector<std::uint8_t> near(C.n_nodes, 0);
          for (unsigned int i = 0; i < C.n_nodes; ++i)
            if (refined[i])
              {
                const auto           ix = C.index(i);
                std::array<int, dim> jx, o;
                const auto           visit = [&](auto &&self, const unsigned int d) -> void {
                  if (d == dim)
                    {
                      for (unsigned int e = 0; e < dim; ++e)
                        jx[e] = ix[e] + o[e];
                      if (C.inside(jx))
                        near[C.node(jx)] = 1;
                      return;
                    }
                  for (o[d] = -Rc; o[d] <= Rc; ++o[d])
                    self(self, d + 1);
                };
                visit(visit, 0);
              }
          for (unsigned int f = 0; f < F.n_nodes; ++f)
            {
              const unsigned int cell = cell_of(f);
              if (!refined[cell] && near[cell] && has_active_neighbour(fine, f))
                fictitious[fine].push_back(f);
            }
        }

      // Interpolation rows: every inactive coarse node that is fictitious
      // or a source of a fine fictitious node (from the fine nodes around
      // it, all active), then the fine fictitious nodes (from coarse nodes).
      std::vector<std::pair<unsigned int, double>> src;
      std::vector<std::uint8_t>                    mark(C.n_nodes, 0);
      for (const auto i : fictitious[coarse])
        mark[i] = 1;
      interp_start[fine].assign(1, 0);
      interp_source[fine].clear();
      interp_weight[fine].clear();
      for (const auto f : fictitious[fine])
        {
          interpolation_sources(coarse, F.point(f), src);
          for (const auto &[j, w] : src)
            {
              interp_source[fine].push_back(j);
              interp_weight[fine].push_back(w);
              if (!active_flag[coarse][j])
                mark[j] = 1;
            }
          interp_start[fine].push_back(interp_source[fine].size());
        }
      coarse_interpolated.clear();
      interp_start[coarse].assign(1, 0);
      interp_source[coarse].clear();
      interp_weight[coarse].clear();
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (mark[i])
          {
            coarse_interpolated.push_back(i);
            interpolation_sources(fine, C.point(i), src);
            for (const auto &[j, w] : src)
              {
                AssertThrow(active_flag[fine][j], ExcInternalError());
                interp_source[coarse].push_back(j);
                interp_weight[coarse].push_back(w);
              }
            interp_start[coarse].push_back(interp_source[coarse].size());
          }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::interpolate_fictitious(std::vector<double> *const field[2])
    {
      const std::array<const std::vector<unsigned int> *, 2> rows{
        {&coarse_interpolated, &fictitious[fine]}};
      for (const unsigned int g : {0u, 1u})
        {
          auto       &to   = *field[g];
          const auto &from = *field[1 - g];
          const auto &list = *rows[g];
          for (unsigned int r = 0; r < list.size(); ++r)
            {
              double value[dim] = {};
              for (auto b = interp_start[g][r]; b < interp_start[g][r + 1]; ++b)
                for (unsigned int d = 0; d < dim; ++d)
                  value[d] += interp_weight[g][b] * from[dim * interp_source[g][b] + d];
              for (unsigned int d = 0; d < dim; ++d)
                to[dim * list[r] + d] = value[d];
            }
        }
    }

    // ------------------------------------------------------------------ forces

    template <int dim>
    void
    MechanicsSolver<dim>::standard_forces(const Grid g, const bool allow_breaking)
    {
      const Lattice      &L = grids[g];
      const unsigned int  S = L.offset.size();
      const double        inv_rho = 1. / prm.density;
      std::vector<double> &U = u[g], &A = a[g];
      auto               &B = broken[g];
      const bool          skip_wls = g == coarse && !use_wls.empty();
      for (const unsigned int i : active[g])
        {
          if (skip_wls && use_wls[i])
            continue;
          const bool in = L.interior(i);
          const auto ix = L.index(i);
          double     f[dim] = {};
          for (unsigned int k = 0; k < S; ++k)
            {
              if (B[std::size_t(i) * S + k])
                continue;
              if (!in)
                {
                  auto jx = ix;
                  for (unsigned int d = 0; d < dim; ++d)
                    jx[d] += L.offset[k][d];
                  if (!L.inside(jx))
                    continue;
                }
              const unsigned int j = i + L.linear_offset[k];
              double             y[dim], y2 = 0.;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  y[d] = L.xi[k][d] + U[dim * j + d] - U[dim * i + d];
                  y2 += y[d] * y[d];
                }
              const double len = std::sqrt(y2);
              const double ext = len - L.length[k];
              if (allow_breaking && ext > s0 * L.length[k])
                {
                  B[std::size_t(i) * S + k]           = 1;
                  B[std::size_t(j) * S + L.mirror[k]] = 1;
                  continue;
                }
              const double s = L.coefficient[k] * ext / len;
              for (unsigned int d = 0; d < dim; ++d)
                f[d] += s * y[d];
            }
          for (unsigned int d = 0; d < dim; ++d)
            A[dim * i + d] = f[d] * inv_rho;
        }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::wls_forces()
    {
      const unsigned int n       = wls_offset.size();
      const double       inv_rho = 1. / prm.density;
      const auto        &U       = u[coarse];
      auto              &A       = a[coarse];
      for (const unsigned int i : active[coarse])
        if (use_wls[i])
          {
            double f[dim] = {};
            for (unsigned int k = 0; k < n; ++k)
              {
                const double *w  = &wls_weight[k * dim * dim];
                const double *uj = &U[dim * (i + wls_offset[k])];
                for (unsigned int d = 0; d < dim; ++d)
                  for (unsigned int e = 0; e < dim; ++e)
                    f[d] += w[d * dim + e] * uj[e];
              }
            for (unsigned int d = 0; d < dim; ++d)
              A[dim * i + d] = f[d] * inv_rho;
          }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::compute_accelerations()
    {
      auto start = std::chrono::steady_clock::now();
      std::vector<double> *fields[2] = {&u[coarse], &u[fine]};
      interpolate_fictitious(fields);
      timing[1] += seconds_since(start);
      start = std::chrono::steady_clock::now();
      standard_forces(fine, true);
      // Coarse bonds break only in the uniform coarse model: in the
      // adaptive ones their cells are refined before they reach s0.
      standard_forces(coarse, prm.model == MechanicsModel::uniform_coarse);
      if (!use_wls.empty())
        wls_forces();
      timing[0] += seconds_since(start);
    }

    // ------------------------------------------------------------------ switching

    template <int dim>
    bool
    MechanicsSolver<dim>::find_critical(std::vector<std::uint8_t> &zone) const
    {
      const Lattice     &L = grids[coarse];
      const unsigned int S = L.offset.size();
      const auto        &U = u[coarse];
      const double       threshold = prm.switching_sigma * s0;
      bool               any       = false;
      zone.assign(L.n_nodes, 0);
      // H(x): the node and its neighbours within delta.
      const auto mark_family = [&](const unsigned int i) {
        zone[i]       = 1;
        const auto ix = L.index(i);
        for (unsigned int k = 0; k < S; ++k)
          {
            if (L.length[k] > prm.delta * (1. + 1e-12))
              continue;
            auto jx = ix;
            for (unsigned int d = 0; d < dim; ++d)
              jx[d] += L.offset[k][d];
            if (L.inside(jx))
              zone[L.node(jx)] = 1;
          }
      };
      for (const unsigned int i : active[coarse])
        {
          const bool in = L.interior(i);
          const auto ix = L.index(i);
          for (unsigned int k = 0; k < S; ++k)
            {
              if (!in)
                {
                  auto jx = ix;
                  for (unsigned int d = 0; d < dim; ++d)
                    jx[d] += L.offset[k][d];
                  if (!L.inside(jx))
                    continue;
                }
              const unsigned int j  = i + L.linear_offset[k];
              double             y2 = 0.;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  const double y = L.xi[k][d] + U[dim * j + d] - U[dim * i + d];
                  y2 += y * y;
                }
              if (std::sqrt(y2) - L.length[k] >= threshold * L.length[k])
                {
                  mark_family(i);
                  mark_family(j);
                  any = true;
                }
            }
        }
      return any;
    }

    template <int dim>
    unsigned int
    MechanicsSolver<dim>::refine(const std::vector<std::uint8_t> &zone)
    {
      const Lattice &C = grids[coarse], &F = grids[fine];
      // Current values of the inactive coarse nodes (sources of the new
      // fine nodes) from the fine nodes around them.
      std::vector<std::pair<unsigned int, double>> src;
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (refined[i])
          {
            interpolation_sources(fine, C.point(i), src);
            for (auto *field : {&u, &v, &a})
              for (unsigned int d = 0; d < dim; ++d)
                {
                  double s = 0.;
                  for (const auto &[j, w] : src)
                    s += w * (*field)[fine][dim * j + d];
                  (*field)[coarse][dim * i + d] = s;
                }
          }
      unsigned int n_new = 0;
      const unsigned int n_children = std::pow(ratio, dim);
      std::vector<unsigned int> children(n_children);
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (zone[i] && !refined[i])
          {
            ++n_new;
            const auto ix = C.index(i);
            for (unsigned int q = 0; q < n_children; ++q)
              {
                std::array<int, dim> fx;
                unsigned int         rest = q;
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    fx[d] = ix[d] * ratio + rest % ratio;
                    rest /= ratio;
                  }
                children[q] = F.node(fx);
              }
            // Interpolate, then shift so that the cell keeps its coarse
            // node's displacement, velocity and acceleration as the mean
            // (mass and momentum of the cell unchanged).
            for (auto *field : {&u, &v, &a})
              {
                double mean[dim] = {};
                for (const auto f : children)
                  {
                    interpolation_sources(coarse, F.point(f), src);
                    for (unsigned int d = 0; d < dim; ++d)
                      {
                        double s = 0.;
                        for (const auto &[j, w] : src)
                          s += w * (*field)[coarse][dim * j + d];
                        (*field)[fine][dim * f + d] = s;
                        mean[d] += s / n_children;
                      }
                  }
                for (const auto f : children)
                  for (unsigned int d = 0; d < dim; ++d)
                    (*field)[fine][dim * f + d] += (*field)[coarse][dim * i + d] - mean[d];
              }
            for (const auto f : children)
              if (prescribed[fine][f])
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    v[fine][dim * f + d] = prescribed_velocity[prescribed[fine][f] - 1][d];
                    a[fine][dim * f + d] = 0.;
                  }
            refined[i] = 1;
          }
      if (n_new > 0)
        update_node_sets();
      return n_new;
    }

    template <int dim>
    unsigned int
    MechanicsSolver<dim>::refine_region(const std::function<bool(const Point<dim> &)> &region)
    {
      check_parameter(prm.model != MechanicsModel::uniform_coarse, "Model", to_string(prm.model),
                      "a model with a fine grid to refine the coarse grid");
      std::vector<std::uint8_t> zone(grids[coarse].n_nodes, 0);
      for (unsigned int i = 0; i < zone.size(); ++i)
        zone[i] = region(grids[coarse].point(i));
      return refine(zone);
    }

    // ------------------------------------------------------------------ stepping

    template <int dim>
    void
    MechanicsSolver<dim>::apply_prescribed()
    {
      for (const unsigned int g : {0u, 1u})
        for (unsigned int i = 0; i < grids[g].n_nodes; ++i)
          if (prescribed[g][i])
            for (unsigned int d = 0; d < dim; ++d)
              {
                v[g][dim * i + d] = prescribed_velocity[prescribed[g][i] - 1][d];
                a[g][dim * i + d] = 0.;
              }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::advance()
    {
      const double h = 0.5 * dt;
      for (const unsigned int g : {0u, 1u})
        for (const unsigned int i : active[g])
          for (unsigned int d = 0; d < dim; ++d)
            {
              v[g][dim * i + d] += h * a[g][dim * i + d];
              u[g][dim * i + d] += dt * v[g][dim * i + d];
            }
      compute_accelerations();
      for (const unsigned int g : {0u, 1u})
        for (const unsigned int i : active[g])
          {
            if (prescribed[g][i])
              {
                for (unsigned int d = 0; d < dim; ++d)
                  a[g][dim * i + d] = 0.;
                continue;
              }
            for (unsigned int d = 0; d < dim; ++d)
              v[g][dim * i + d] += h * a[g][dim * i + d];
          }
      t += dt;
      ++n_step;
      if (prm.model == MechanicsModel::adaptive_standard ||
          prm.model == MechanicsModel::adaptive_hybrid)
        {
          auto                      start = std::chrono::steady_clock::now();
          std::vector<std::uint8_t> zone;
          const bool                critical = find_critical(zone);
          timing[2] += seconds_since(start);
          if (critical)
            {
              start = std::chrono::steady_clock::now();
              if (refine(zone) > 0)
                ++switches;
              timing[3] += seconds_since(start);
            }
        }
    }

    // ------------------------------------------------------------------ input

    template <int dim>
    void
    MechanicsSolver<dim>::add_precrack(const Point<dim> &p, const Point<dim> &q)
    {
      check_parameter(dim == 2, "Pre-cracks", dim, "segments in 2D only");
      if constexpr (dim == 2)
      for (const unsigned int g : {0u, 1u})
        {
          const Lattice     &L = grids[g];
          const unsigned int S = L.offset.size();
          for (unsigned int i = 0; i < L.n_nodes; ++i)
            {
              const auto       ix = L.index(i);
              const Point<dim> xi = L.point(i);
              for (unsigned int k = 0; k < S; ++k)
                {
                  auto jx = ix;
                  for (unsigned int d = 0; d < dim; ++d)
                    jx[d] += L.offset[k][d];
                  if (!L.inside(jx))
                    continue;
                  const Point<dim> xj = xi + L.xi[k];
                  if (orient(p, q, xi) * orient(p, q, xj) < 0. &&
                      orient(xi, xj, p) * orient(xi, xj, q) < 0.)
                    broken[g][std::size_t(i) * S + k] = 1;
                }
            }
        }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::set_initial_velocity(
      const std::function<Tensor<1, dim>(const Point<dim> &)> &vel)
    {
      for (const unsigned int g : {0u, 1u})
        for (unsigned int i = 0; i < grids[g].n_nodes; ++i)
          {
            const auto w = vel(grids[g].point(i));
            for (unsigned int d = 0; d < dim; ++d)
              v[g][dim * i + d] = w[d];
          }
      apply_prescribed();
    }

    template <int dim>
    void
    MechanicsSolver<dim>::set_initial_displacement(
      const std::function<Tensor<1, dim>(const Point<dim> &)> &disp)
    {
      for (const unsigned int g : {0u, 1u})
        for (unsigned int i = 0; i < grids[g].n_nodes; ++i)
          {
            const auto w = disp(grids[g].point(i));
            for (unsigned int d = 0; d < dim; ++d)
              u[g][dim * i + d] = w[d];
          }
      compute_accelerations();
      apply_prescribed();
    }

    template <int dim>
    void
    MechanicsSolver<dim>::add_prescribed_velocity(
      const std::function<bool(const Point<dim> &)> &region,
      const Tensor<1, dim>                          &vel)
    {
      prescribed_velocity.push_back(vel);
      for (const unsigned int g : {0u, 1u})
        for (unsigned int i = 0; i < grids[g].n_nodes; ++i)
          if (region(grids[g].point(i)))
            prescribed[g][i] = prescribed_velocity.size();
      apply_prescribed();
    }

    template <int dim>
    double
    MechanicsSolver<dim>::critical_time_step() const
    {
      double bound = std::numeric_limits<double>::infinity();
      for (const unsigned int g : {0u, 1u})
        {
          const bool used = (g == fine && prm.model != MechanicsModel::uniform_coarse) ||
                            (g == coarse && prm.model != MechanicsModel::uniform_fine);
          if (!used)
            continue;
          double sum = 0.;
          for (const double k : grids[g].coefficient)
            sum += k;
          bound = std::min(bound, std::sqrt(2. * prm.density / sum));
        }
      if (!wls_offset.empty())
        bound = std::min(bound, wls_stable_step);
      return bound;
    }

    // ------------------------------------------------------------------ output

    template <int dim>
    unsigned int
    MechanicsSolver<dim>::n_active(const Grid g) const
    {
      return active[g].size();
    }

    template <int dim>
    Point<dim>
    MechanicsSolver<dim>::position(const Grid g, const unsigned int i) const
    {
      return grids[g].point(i);
    }

    template <int dim>
    Tensor<1, dim>
    MechanicsSolver<dim>::displacement(const Grid g, const unsigned int i) const
    {
      return node_vector<dim>(u[g], i);
    }

    template <int dim>
    Tensor<1, dim>
    MechanicsSolver<dim>::velocity(const Grid g, const unsigned int i) const
    {
      return node_vector<dim>(v[g], i);
    }

    template <int dim>
    Tensor<1, dim>
    MechanicsSolver<dim>::acceleration(const Grid g, const unsigned int i) const
    {
      return node_vector<dim>(a[g], i);
    }

    template <int dim>
    double
    MechanicsSolver<dim>::damage(const Grid g, const unsigned int i) const
    {
      const Lattice     &L  = grids[g];
      const unsigned int S  = L.offset.size();
      const auto         ix = L.index(i);
      double             all = 0., intact = 0.;
      for (unsigned int k = 0; k < S; ++k)
        {
          auto jx = ix;
          for (unsigned int d = 0; d < dim; ++d)
            jx[d] += L.offset[k][d];
          if (!L.inside(jx))
            continue;
          all += L.weight[k];
          if (!broken[g][std::size_t(i) * S + k])
            intact += L.weight[k];
        }
      return all > 0. ? 1. - intact / all : 0.;
    }

    template <int dim>
    double
    MechanicsSolver<dim>::active_mass() const
    {
      return prm.density * (active[coarse].size() * grids[coarse].volume +
                            active[fine].size() * grids[fine].volume);
    }

    template <int dim>
    Tensor<1, dim>
    MechanicsSolver<dim>::momentum() const
    {
      Tensor<1, dim> P;
      for (const unsigned int g : {0u, 1u})
        for (const unsigned int i : active[g])
          for (unsigned int d = 0; d < dim; ++d)
            P[d] += prm.density * grids[g].volume * v[g][dim * i + d];
      return P;
    }

    template <int dim>
    double
    MechanicsSolver<dim>::kinetic_energy() const
    {
      double E = 0.;
      for (const unsigned int g : {0u, 1u})
        for (const unsigned int i : active[g])
          for (unsigned int d = 0; d < dim; ++d)
            E += 0.5 * prm.density * grids[g].volume * v[g][dim * i + d] * v[g][dim * i + d];
      return E;
    }

    template <int dim>
    std::uint64_t
    MechanicsSolver<dim>::n_broken_bonds() const
    {
      std::uint64_t n = 0;
      for (const unsigned int g : {0u, 1u})
        for (const auto b : broken[g])
          n += b;
      return n / 2;
    }

    template <int dim>
    double
    MechanicsSolver<dim>::crack_angle(const Point<dim>                              &origin,
                                      const std::function<bool(const Point<dim> &)> &region,
                                      const double                                   threshold,
                                      const double                                   r_min,
                                      const double                                   r_max,
                                      unsigned int                                  &n_nodes) const
    {
      n_nodes = 0;
      if (dim != 2)
        return std::numeric_limits<double>::quiet_NaN();
      double sx = 0., sy = 0., sxx = 0., sxy = 0., syy = 0.;
      for (const unsigned int i : active[fine])
        {
          const Point<dim> x = grids[fine].point(i);
          const double     r = x.distance(origin);
          if (r < r_min || r > r_max || !region(x) || damage(fine, i) < threshold)
            continue;
          ++n_nodes;
          sx += x[0];
          sy += x[dim - 1];
          sxx += x[0] * x[0];
          sxy += x[0] * x[dim - 1];
          syy += x[dim - 1] * x[dim - 1];
        }
      if (n_nodes < 3)
        return std::numeric_limits<double>::quiet_NaN();
      const double n = n_nodes, cxx = sxx / n - sx * sx / (n * n),
                   cxy = sxy / n - sx * sy / (n * n), cyy = syy / n - sy * sy / (n * n);
      // Principal axis of the covariance: the total-least-squares line.
      double angle = 0.5 * std::atan2(2. * cxy, cxx - cyy) * 180. / M_PI;
      if (angle <= -90.)
        angle += 180.;
      return angle;
    }

    // ------------------------------------------------------------------ KW

    namespace
    {
      const Point<2> kw_tip(50., 25.);
      bool
      kw_crack_region(const Point<2> &x)
      {
        return x[0] >= kw_tip[0] && x[1] >= kw_tip[1];
      }
      // Distance of p from the segment [a, b].
      double
      segment_distance(const Point<2> &p, const Point<2> &a, const Point<2> &b)
      {
        const Tensor<1, 2> ab = b - a;
        const double       s  = std::clamp((p - a) * ab / ab.norm_square(), 0., 1.);
        return p.distance(a + s * ab);
      }
    } // namespace

    MechanicsParameters<2>
    KalthoffWinkler::parameters() const
    {
      MechanicsParameters<2> p;
      p.lower           = Point<2>(0., -100.);
      p.upper           = Point<2>(100., 100.);
      p.coarse_dx       = coarse_dx;
      p.fine_dx         = fine_dx;
      p.delta           = delta;
      p.model           = model;
      p.interpolation   = interpolation;
      p.youngs_modulus  = 190e3;
      p.plane_stress    = false;
      p.density         = 8e-9;
      p.fracture_energy = 22.17;
      p.n_collocation   = 49;
      p.switching_sigma = 0.95;
      const double d    = delta;
      p.initial_fine_region = [d](const Point<2> &x) {
        const double boundary = std::min({x[0], 100. - x[0], x[1] + 100., 100. - x[1]});
        return boundary <= d ||
               segment_distance(x, Point<2>(0., 25.), Point<2>(50., 25.)) <= d ||
               segment_distance(x, Point<2>(0., -25.), Point<2>(50., -25.)) <= d;
      };
      return p;
    }

    void
    KalthoffWinkler::load(MechanicsSolver<2> &solver) const
    {
      solver.add_precrack(Point<2>(-1., 25.), Point<2>(50., 25.));
      solver.add_precrack(Point<2>(-1., -25.), Point<2>(50., -25.));
      const double h = fine_dx;
      solver.add_prescribed_velocity(
        [h](const Point<2> &x) { return x[0] < h && std::abs(x[1]) < 25.; },
        Tensor<1, 2>({16.5e3, 0.}));
      solver.set_time_step(end_time / n_steps(solver));
    }

    unsigned int
    KalthoffWinkler::n_steps(const MechanicsSolver<2> &solver) const
    {
      return static_cast<unsigned int>(std::ceil(end_time / (0.9 * solver.critical_time_step())));
    }

    double
    KalthoffWinkler::crack_angle(const MechanicsSolver<2> &solver, unsigned int &n_nodes) const
    {
      return solver.crack_angle(kw_tip, kw_crack_region, 0.35, delta, 50., n_nodes);
    }

    double
    KalthoffWinkler::crack_length(const MechanicsSolver<2> &solver) const
    {
      double L = 0.;
      for (unsigned int i = 0; i < solver.n_nodes(MechanicsSolver<2>::fine); ++i)
        if (solver.is_active(MechanicsSolver<2>::fine, i))
          {
            const Point<2> x = solver.position(MechanicsSolver<2>::fine, i);
            if (kw_crack_region(x) && solver.damage(MechanicsSolver<2>::fine, i) >= 0.35)
              L = std::max(L, x.distance(kw_tip));
          }
      return L;
    }

    KalthoffWinkler::Result
    KalthoffWinkler::run(const std::function<void(const MechanicsSolver<2> &)> &monitor,
                         const unsigned int                                     interval) const
    {
      MechanicsSolver<2> s(parameters());
      load(s);
      Result r;
      r.coarse_begin = s.n_active(MechanicsSolver<2>::coarse);
      r.fine_begin   = s.n_active(MechanicsSolver<2>::fine);
      r.steps        = n_steps(s);
      if (monitor)
        monitor(s);
      for (unsigned int k = 1; k <= r.steps; ++k)
        {
          const auto start = std::chrono::steady_clock::now();
          s.advance();
          r.seconds += seconds_since(start);
          if (monitor && ((interval > 0 && k % interval == 0) || k == r.steps))
            monitor(s);
        }
      r.coarse_end = s.n_active(MechanicsSolver<2>::coarse);
      r.fine_end   = s.n_active(MechanicsSolver<2>::fine);
      r.switches   = s.n_switches();
      r.angle      = crack_angle(s, r.crack_nodes);
      r.length     = crack_length(s);
      r.timing     = s.timing;
      return r;
    }

    template struct MechanicsParameters<1>;
    template struct MechanicsParameters<2>;
    template class MechanicsSolver<1>;
    template class MechanicsSolver<2>;
  } // namespace MultiGrid
} // namespace PeriDEAL
