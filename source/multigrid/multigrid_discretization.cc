#include <deal.II/base/timer.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/multigrid/lattice_tools.h>
#include <perideal/multigrid/multigrid_discretization.h>

#include <Eigen/Sparse>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <unordered_map>

namespace PeriDEAL
{
  namespace MultiGrid
  {
    template <int dim>
    Region<dim>
    Region<dim>::box(const Point<dim> &lower, const Point<dim> &upper)
    {
      Region r;
      r.shape = Shape::box;
      r.lower = lower;
      r.upper = upper;
      for (unsigned int d = 0; d < dim; ++d)
        check_parameter(upper[d] > lower[d], "Fine region/Upper corner", upper[d],
                        "a value above the lower corner in every direction");
      return r;
    }

    template <int dim>
    Region<dim>
    Region<dim>::ball(const Point<dim> &center, const double radius)
    {
      check_parameter(radius > 0., "Fine region/Radius", radius, "a positive number");
      Region r;
      r.shape  = Shape::ball;
      r.center = center;
      r.radius = radius;
      return r;
    }

    template <int dim>
    Region<dim>
    Region<dim>::cylinder(const Point<dim> &center, const double radius, const double half_height)
    {
      check_parameter(radius > 0., "Fine region/Radius", radius, "a positive number");
      check_parameter(dim < 3 || half_height > 0., "Fine region/Half height", half_height,
                      "a positive number (3D cylinders)");
      Region r;
      r.shape       = Shape::cylinder;
      r.center      = center;
      r.radius      = radius;
      r.half_height = half_height;
      return r;
    }

    template <int dim>
    bool
    Region<dim>::contains(const Point<dim> &p) const
    {
      switch (shape)
        {
          case Shape::none:
            return false;
          case Shape::box:
            for (unsigned int d = 0; d < dim; ++d)
              if (p[d] < lower[d] || p[d] > upper[d])
                return false;
            return true;
          case Shape::ball:
            return p.distance(center) <= radius;
          case Shape::cylinder:
            {
              // axis along the last coordinate (3D); a disk in 2D
              const unsigned int n_radial = dim == 3 ? 2 : dim;
              double             r2       = 0.;
              for (unsigned int d = 0; d < n_radial; ++d)
                r2 += (p[d] - center[d]) * (p[d] - center[d]);
              if (dim == 3 && std::abs(p[dim - 1] - center[dim - 1]) > half_height)
                return false;
              return r2 <= radius * radius;
            }
        }
      return false;
    }

    template <int dim>
    double
    Region<dim>::min_width() const
    {
      switch (shape)
        {
          case Shape::box:
            {
              double w = upper[0] - lower[0];
              for (unsigned int d = 1; d < dim; ++d)
                w = std::min(w, upper[d] - lower[d]);
              return w;
            }
          case Shape::ball:
            return 2. * radius;
          case Shape::cylinder:
            return dim == 3 ? std::min(2. * radius, 2. * half_height) : 2. * radius;
          default:
            return std::numeric_limits<double>::infinity();
        }
    }

    template <int dim>
    void
    Parameters<dim>::check() const
    {
      for (unsigned int d = 0; d < dim; ++d)
        check_parameter(upper[d] > lower[d], "Geometry/Upper corner", upper[d],
                        "a value above the lower corner in every direction");
      check_parameter(coarse_dx > 0., "Multi-grid/Coarse grid spacing", coarse_dx,
                      "a positive number");
      check_parameter(fine_dx > 0. && fine_dx <= coarse_dx, "Multi-grid/Fine grid spacing",
                      fine_dx, "a positive number not above the coarse grid spacing");
      const double ratio = coarse_dx / fine_dx;
      check_parameter(std::abs(ratio - std::round(ratio)) < 1e-9 * ratio,
                      "Multi-grid/Fine grid spacing", fine_dx,
                      "a spacing of which the coarse grid spacing " + std::to_string(coarse_dx) +
                        " is an integer multiple (dx+ = r dx-)");
      check_parameter(delta >= coarse_dx * (1. - 1e-12), "Multi-grid/Horizon", delta,
                      "a horizon of at least the coarse grid spacing (m+ = delta/dx+ >= 1), "
                      "the same in both grids");
      check_parameter(exponent < dim + 2., "Multi-grid/Kernel exponent", exponent,
                      "an exponent below n_d + 2 (finite second moment)");
      if (fine_region.shape != Region<dim>::Shape::none)
        check_parameter(fine_region.min_width() >= 2. * delta, "Multi-grid/Fine region",
                        fine_region.min_width(),
                        "a region at least 2 delta = " + std::to_string(2. * delta) +
                          " wide in every direction (its fictitious bands, one horizon on "
                          "each side of the interface, must not overlap)");
    }

    using namespace Lattice;

    template <int dim>
    Discretization<dim>::Discretization(const Parameters<dim> &parameters)
      : prm(parameters)
    {
      prm.check();
      const double    H = prm.coarse_dx, h = prm.fine_dx;
      const long long r = std::llround(H / h);
      Index<dim>      nc, nf;
      Point<dim>      fine_origin;
      long long       n_coarse = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          nc[d] = (long long)std::floor((prm.upper[d] - prm.lower[d]) / H + 1e-9) + 1;
          nf[d] = r * nc[d];
          fine_origin[d] = prm.lower[d] - 0.5 * H + 0.5 * h;
          n_coarse *= nc[d];
        }
      check_parameter(n_coarse < (1LL << 31), "Multi-grid/Coarse grid spacing", H,
                      "a spacing giving fewer than 2^31 coarse lattice points");

      auto coarse_point = [&](const Index<dim> &K) {
        Point<dim> p;
        for (unsigned int d = 0; d < dim; ++d)
          p[d] = prm.lower[d] + K[d] * H;
        return p;
      };
      auto fine_point = [&](const Index<dim> &i) {
        Point<dim> p;
        for (unsigned int d = 0; d < dim; ++d)
          p[d] = fine_origin[d] + i[d] * h;
        return p;
      };
      auto unravel = [](long long k, const Index<dim> &n) {
        Index<dim> i;
        for (unsigned int d = 0; d < dim; ++d)
          {
            i[d] = k % n[d];
            k /= n[d];
          }
        return i;
      };

      // 1. refined cells, active nodes (coarse first, then fine)
      std::vector<bool> refined(n_coarse);
      for (long long k = 0; k < n_coarse; ++k)
        refined[k] = prm.fine_region.contains(coarse_point(unravel(k, nc)));

      std::unordered_map<long long, unsigned int> coarse_node, fine_node;
      std::vector<Index<dim>>                     lattice_index;
      for (long long k = 0; k < n_coarse; ++k)
        if (!refined[k])
          {
            coarse_node[k] = position.size();
            lattice_index.push_back(unravel(k, nc));
            position.push_back(coarse_point(lattice_index.back()));
            grid.push_back(coarse);
          }
      n_active_coarse = position.size();
      long long r_dim = 1;
      for (unsigned int d = 0; d < dim; ++d)
        r_dim *= r;
      for (long long k = 0; k < n_coarse; ++k)
        if (refined[k])
          {
            const Index<dim> K = unravel(k, nc);
            for (long long s = 0; s < r_dim; ++s)
              {
                Index<dim> i;
                long long  rest = s;
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    i[d] = K[d] * r + rest % r;
                    rest /= r;
                  }
                fine_node[linear<dim>(i, nf)] = position.size();
                lattice_index.push_back(i);
                position.push_back(fine_point(i));
                grid.push_back(fine);
              }
          }
      n_active_fine = position.size() - n_active_coarse;

      // 2. fictitious nodes: lattice points of the own grid, inactive there,
      // within the bond reach of an active node
      const auto coarse_stencil = stencil<dim>(H, prm.delta, prm.partial_volume);
      const auto fine_stencil   = stencil<dim>(h, prm.delta, prm.partial_volume);
      std::set<long long> coarse_fict, fine_fict;
      for (unsigned int a = 0; a < n_active(); ++a)
        {
          const bool  is_fine = grid[a] == fine;
          const auto &st      = is_fine ? fine_stencil : coarse_stencil;
          const auto &n       = is_fine ? nf : nc;
          const auto &own     = is_fine ? fine_node : coarse_node;
          for (const auto &[o, len] : st)
            {
              Index<dim> j;
              for (unsigned int d = 0; d < dim; ++d)
                j[d] = lattice_index[a][d] + o[d];
              if (!in_range<dim>(j, n))
                continue; // beyond the body: no bond (free nonlocal boundary)
              const long long key = linear<dim>(j, n);
              if (own.count(key) == 0)
                (is_fine ? fine_fict : coarse_fict).insert(key);
            }
        }
      // coarse corners used by fine fictitious nodes must carry values too
      std::vector<Index<dim>> corners;
      std::vector<double>     multilinear;
      for (const long long key : fine_fict)
        {
          enclosing_corners<dim>(fine_point(unravel(key, nf)), prm.lower, H, nc, corners,
                                 multilinear);
          for (const auto &K : corners)
            if (coarse_node.count(linear<dim>(K, nc)) == 0)
              coarse_fict.insert(linear<dim>(K, nc));
        }
      for (const long long key : coarse_fict)
        {
          coarse_node[key] = position.size();
          lattice_index.push_back(unravel(key, nc));
          position.push_back(coarse_point(lattice_index.back()));
          grid.push_back(coarse);
        }
      n_fictitious_coarse = coarse_fict.size();
      for (const long long key : fine_fict)
        {
          fine_node[key] = position.size();
          lattice_index.push_back(unravel(key, nf));
          position.push_back(fine_point(lattice_index.back()));
          grid.push_back(fine);
        }
      n_fictitious_fine = fine_fict.size();

      volume.resize(n_nodes());
      for (unsigned int i = 0; i < n_nodes(); ++i)
        volume[i] = std::pow(grid[i] == fine ? h : H, dim);

      // 3. bonds of the active nodes (3.82), (3.84): active and fictitious
      // neighbours of the own grid, beta and V of the own grid
      row_start.assign(1, 0);
      for (unsigned int a = 0; a < n_active(); ++a)
        {
          const bool  is_fine = grid[a] == fine;
          const auto &st      = is_fine ? fine_stencil : coarse_stencil;
          const auto &n       = is_fine ? nf : nc;
          const auto &own     = is_fine ? fine_node : coarse_node;
          const double dx     = is_fine ? h : H;
          for (const auto &[o, len] : st)
            {
              Index<dim> j;
              for (unsigned int d = 0; d < dim; ++d)
                j[d] = lattice_index[a][d] + o[d];
              if (!in_range<dim>(j, n))
                continue;
              col.push_back(own.at(linear<dim>(j, n)));
              bond_length.push_back(len);
              bond_weight.push_back(
                PeriDEAL::Discretization<dim>::volume_factor(len, prm.delta, dx,
                                                             prm.partial_volume) *
                volume[a]);
            }
          row_start.push_back(col.size());
        }

      // 4. interpolation rows, coarse fictitious (from fine active) first
      interp_start.assign(1, 0);
      std::vector<Point<dim>> corner_points;
      std::vector<double>     w;
      for (unsigned int k = n_active(); k < n_nodes(); ++k)
        {
          const bool is_coarse = grid[k] == coarse;
          // the other grid's lattice: fine nodes sit at fine_origin + i h
          enclosing_corners<dim>(position[k], is_coarse ? fine_origin : prm.lower,
                                 is_coarse ? h : H, is_coarse ? nf : nc, corners,
                                 multilinear);
          const auto &other = is_coarse ? fine_node : coarse_node;
          corner_points.clear();
          std::vector<unsigned int> src;
          for (const auto &c : corners)
            {
              const auto it = other.find(linear<dim>(c, is_coarse ? nf : nc));
              // coarse fictitious: its surrounding fine nodes lie in its own
              // refined cell; fine fictitious: corners were added above
              AssertThrow(it != other.end(), ExcInternalError());
              AssertThrow(!is_coarse || it->second < n_active(), ExcInternalError());
              src.push_back(it->second);
              corner_points.push_back(position[it->second]);
            }
          if (prm.interpolation == Interpolation::nearest_active)
            {
              // the 2^dim nearest *active* nodes of the other grid, searched
              // within 3 cells of the enclosing cell (ties: lower index)
              const Index<dim> &base = corners[0];
              const auto       &n    = is_coarse ? nf : nc;
              std::vector<std::pair<double, unsigned int>> cand;
              long long total = 1;
              for (unsigned int d = 0; d < dim; ++d)
                total *= 8;
              for (long long c = 0; c < total; ++c)
                {
                  Index<dim> j;
                  long long  rest = c;
                  for (unsigned int d = 0; d < dim; ++d)
                    {
                      j[d] = base[d] + rest % 8 - 3;
                      rest /= 8;
                    }
                  if (!in_range<dim>(j, n))
                    continue;
                  const auto it = other.find(linear<dim>(j, n));
                  if (it != other.end() && it->second < n_active())
                    cand.emplace_back(position[k].distance(position[it->second]), it->second);
                }
              std::sort(cand.begin(), cand.end());
              AssertThrow(cand.size() >= (1u << dim), ExcInternalError());
              cand.resize(1u << dim);
              src.clear();
              corner_points.clear();
              for (const auto &c : cand)
                {
                  src.push_back(c.second);
                  corner_points.push_back(position[c.second]);
                }
            }
          corner_weights<dim>(position[k], corner_points, multilinear,
                              prm.interpolation == Interpolation::multilinear ?
                                Interpolation::multilinear :
                                Interpolation::inverse_distance,
                              is_coarse ? h : H, w);
          interp_node.push_back(k);
          for (unsigned int j = 0; j < src.size(); ++j)
            if (w[j] > 0.)
              {
                interp_source.push_back(src[j]);
                interp_weight.push_back(w[j]);
              }
          interp_start.push_back(interp_source.size());
        }

      // 5. expand to active sources (coarse fictitious rows come first)
      active_interpolation.resize(n_nodes() - n_active());
      for (unsigned int row = 0; row < interp_node.size(); ++row)
        {
          std::map<unsigned int, double> acc;
          for (unsigned int q = interp_start[row]; q < interp_start[row + 1]; ++q)
            {
              const unsigned int s = interp_source[q];
              if (s < n_active())
                acc[s] += interp_weight[q];
              else
                for (const auto &[a, wa] : active_interpolation[s - n_active()])
                  acc[a] += interp_weight[q] * wa;
            }
          active_interpolation[interp_node[row] - n_active()].assign(acc.begin(), acc.end());
        }
    }

    template <int dim>
    void
    Discretization<dim>::update_fictitious(std::vector<double> &v,
                                           const unsigned int   nc) const
    {
      for (unsigned int row = 0; row < interp_node.size(); ++row)
        {
          const unsigned int k = interp_node[row];
          for (unsigned int c = 0; c < nc; ++c)
            {
              double s = 0.;
              for (unsigned int q = interp_start[row]; q < interp_start[row + 1]; ++q)
                s += interp_weight[q] * v[interp_source[q] * nc + c];
              v[k * nc + c] = s;
            }
        }
    }

    template <int dim>
    double
    Discretization<dim>::integrate(const std::vector<double> &v,
                                   const unsigned int         nc,
                                   const unsigned int         c) const
    {
      // active nodes only: each region's mass is counted in one grid
      double s = 0.;
      for (unsigned int i = 0; i < n_active(); ++i)
        s += v[i * nc + c] * volume[i];
      return s;
    }

    template <int dim>
    double
    Discretization<dim>::active_volume() const
    {
      double s = 0.;
      for (unsigned int i = 0; i < n_active(); ++i)
        s += volume[i];
      return s;
    }

    // ---------------------------------------------------------------- solver

    template <int dim>
    struct TransportSolver<dim>::Implicit
    {
      Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
      bool                                         valid = false;
    };

    template <int dim>
    TransportSolver<dim>::TransportSolver(const Discretization<dim> &discretization,
                                          const TransportParameters &parameters)
      : disc(discretization)
      , prm(parameters)
      , implicit(std::make_unique<Implicit>())
    {
      const auto &p = disc.parameters();
      check_parameter(prm.scheme == "forward Euler" || prm.scheme == "backward Euler",
                      "Time stepping/Scheme", prm.scheme,
                      "'forward Euler' or 'backward Euler'");
      if (prm.corrosion)
        {
          check_parameter(prm.kappa_liquid >= 0., "Model/Corrosion/Liquid micro-diffusivity",
                          prm.kappa_liquid, "a non-negative number");
          check_parameter(prm.kappa_interface >= 0.,
                          "Model/Corrosion/Interface micro-diffusivity", prm.kappa_interface,
                          "a non-negative number");
          check_parameter(prm.kappa_solid >= 0., "Model/Corrosion/Solid micro-diffusivity",
                          prm.kappa_solid, "a non-negative number");
        }
      else
        check_parameter(prm.kappa > 0., "Model/Micro-diffusivity", prm.kappa,
                        "a positive number");
      kernel.dim      = dim;
      kernel.omega    = p.omega;
      kernel.exponent = p.exponent;
      kernel.delta    = p.delta;
      kernel.constant = 1.;
      // as DiffusionOperator: omega at min(r, delta) for the partial-volume shell
      kernel_weight.resize(disc.col.size());
      for (std::size_t b = 0; b < kernel_weight.size(); ++b)
        kernel_weight[b] = kernel(std::min(disc.bond_length[b], p.delta)) * disc.bond_weight[b];
      if (prm.calibrate)
        {
          // discrete second moment of each grid's full stencil vs the continuum
          std::array<double, 2> factor;
          for (const unsigned int g : {0u, 1u})
            {
              const double h  = g == 0 ? p.coarse_dx : p.fine_dx;
              double       m2 = 0.;
              for (const auto &[o, len] : stencil<dim>(h, p.delta, p.partial_volume))
                m2 += kernel(std::min(len, p.delta)) *
                      PeriDEAL::Discretization<dim>::volume_factor(len, p.delta, h,
                                                                   p.partial_volume) *
                      std::pow(h, dim) * double(o[0] * o[0]) * h * h;
              factor[g] = kernel.second_moment() / m2;
            }
          for (unsigned int i = 0; i < disc.n_active(); ++i)
            for (unsigned int b = disc.row_start[i]; b < disc.row_start[i + 1]; ++b)
              kernel_weight[b] *= factor[disc.grid[i]];
        }

      // Gershgorin bound of the (fictitious-expanded) operator with the
      // largest kappa on every bond, min_i 2 / (|L_ii| + R_i). For the
      // interpolation coupling the off-diagonal entries are >= 0 (weights
      // >= 0) and the rows sum to 0, and we use the sharper max-principle
      // bound 1 / |L_ii| (the update is then a convex combination).
      check_parameter(prm.coarse_quadrature == "standard" || prm.coarse_quadrature == "wls",
                      "Multi-grid/Coarse quadrature", prm.coarse_quadrature,
                      "'standard' or 'wls'");
      check_parameter(prm.coarse_quadrature == "standard" ||
                        (prm.scheme == "forward Euler" && !prm.conservative),
                      "Multi-grid/Coarse quadrature", prm.coarse_quadrature,
                      "'standard' with backward Euler or the conservative coupling");
      constrained.assign(disc.n_active(), 0);
      wls_row.assign(disc.n_active(), -1);
      if (prm.coarse_quadrature == "wls")
        {
          // rows: coarse active nodes with the complete coarse family (the
          // box boundary truncates the others, which keep their bonds)
          const std::size_t full = stencil<dim>(p.coarse_dx, p.delta, p.partial_volume).size();
          std::vector<std::uint64_t> family_start(disc.n_nodes() + 1, 0);
          std::vector<std::int32_t>  family;
          std::vector<unsigned int>  rows;
          for (unsigned int i = 0; i < disc.n_nodes(); ++i)
            {
              if (i < disc.n_active())
                {
                  family.insert(family.end(), disc.col.begin() + disc.row_start[i],
                                disc.col.begin() + disc.row_start[i + 1]);
                  if (disc.grid[i] == disc.coarse &&
                      disc.row_start[i + 1] - disc.row_start[i] == full)
                    rows.push_back(i);
                }
              family_start[i + 1] = family.size();
            }
          wls = std::make_unique<WlsQuadrature<dim>>(prm.wls, kernel);
          wls->build(disc.position, family_start, family, rows);
          for (unsigned int k = 0; k < rows.size(); ++k)
            wls_row[rows[k]] = k;
        }

      // Gershgorin bound of the (fictitious-expanded) operator with the
      // largest kappa on every bond, min_i 2 / (|L_ii| + R_i). For the
      // interpolation coupling the off-diagonal entries are >= 0 (weights
      // >= 0) and the rows sum to 0, and we use the sharper max-principle
      // bound 1 / |L_ii| (the update is then a convex combination).
      std::vector<double> diag(disc.n_active(), 0.), off(disc.n_active(), 0.);
      if (prm.conservative)
        {
          std::map<std::pair<unsigned int, unsigned int>, double> L;
          for (const auto &[r, c, v] : operator_entries(true, true))
            L[{r, c}] += v;
          for (const auto &[rc, v] : L)
            (rc.first == rc.second ? diag[rc.first] : off[rc.first]) += std::abs(v);
        }
      else
        {
          // the same row by row (entries of row i only come from row i's
          // bonds): no global map, which 3D lattices could not afford
          const double kmax = prm.corrosion ? std::max({prm.kappa_liquid, prm.kappa_interface,
                                                        prm.kappa_solid}) :
                                              prm.kappa;
          const unsigned int                        na = disc.n_active();
          std::vector<std::pair<unsigned int, double>> row;
          for (unsigned int i = 0; i < na; ++i)
            {
              row.clear();
              for (unsigned int b = disc.row_start[i]; b < disc.row_start[i + 1]; ++b)
                {
                  const unsigned int j = disc.col[b];
                  const double       c = kmax * kernel_weight[b];
                  row.emplace_back(i, -c);
                  if (j < na)
                    row.emplace_back(j, c);
                  else
                    for (const auto &[a, w] : disc.active_interpolation[j - na])
                      row.emplace_back(a, c * w);
                }
              std::sort(row.begin(), row.end(),
                        [](const auto &x, const auto &y) { return x.first < y.first; });
              for (std::size_t k = 0; k < row.size();)
                {
                  double             v = 0.;
                  const unsigned int c = row[k].first;
                  for (; k < row.size() && row[k].first == c; ++k)
                    v += row[k].second;
                  (c == i ? diag[i] : off[i]) += std::abs(v);
                }
            }
        }
      dt_critical = std::numeric_limits<double>::infinity();
      for (unsigned int i = 0; i < disc.n_active(); ++i)
        if (diag[i] > 0.)
          dt_critical = std::min(dt_critical, prm.conservative ? 2. / (diag[i] + off[i]) :
                                                                 1. / diag[i]);
      // WLS rows (kappa_liquid or kappa; weights of both signs): Gershgorin
      // 2 / (|L_ii| + R_i), fictitious columns expanded (|w| summed)
      if (wls)
        {
          const double kw = prm.corrosion ? prm.kappa_liquid : prm.kappa;
          for (unsigned int k = 0; k < wls->node.size(); ++k)
            {
              const unsigned int i = wls->node[k];
              double             d = 0., r = 0.;
              for (auto q = wls->row_start[k]; q < wls->row_start[k + 1]; ++q)
                {
                  const unsigned int j = wls->col[q];
                  const double       w = kw * wls->weight[q];
                  if (j == i)
                    d += w;
                  else if (j < disc.n_active())
                    r += std::abs(w);
                  else
                    for (const auto &[a, v] : disc.active_interpolation[j - disc.n_active()])
                      (a == i ? d : r) += a == i ? w * v : std::abs(w * v);
                }
              if (std::abs(d) + r > 0.)
                dt_critical = std::min(dt_critical, 2. / (std::abs(d) + r));
            }
        }

      dt          = prm.time_step > 0. ? prm.time_step : 0.9 * dt_critical;
      if (prm.scheme == "forward Euler")
        check_parameter(dt <= dt_critical * (1. + 1e-12), "Time stepping/Time step", dt,
                        "a step not above the forward Euler bound " +
                          std::to_string(dt_critical));
      C.assign(disc.n_nodes(), 0.);
      phase.assign(disc.n_nodes(), 0.);
      rate.assign(disc.n_active(), 0.);
    }

    template <int dim>
    TransportSolver<dim>::~TransportSolver() = default;

    template <int dim>
    void
    TransportSolver<dim>::initialize_phase()
    {
      for (unsigned int i = 0; i < disc.n_active(); ++i)
        phase[i] = prm.corrosion && C[i] >= prm.saturation ? 1. : 0.;
      disc.update_fictitious(C);
      update_phase();
      implicit->valid = false;
      // the solid counts of the phase classification (setup, not stepping)
      if (prm.corrosion)
        solid_count.initialize(disc.n_active(), disc.row_start.data(), disc.col.data(),
                               disc.n_nodes(),
                               [&](const unsigned int j) { return phase[j] > 0.5; });
    }

    template <int dim>
    double
    TransportSolver<dim>::bond_kappa(const unsigned int i, const unsigned int j) const
    {
      if (!prm.corrosion)
        return prm.kappa;
      const bool si = phase[i] > 0.5, sj = phase[j] > 0.5;
      return si && sj ? prm.kappa_solid : (si || sj ? prm.kappa_interface : prm.kappa_liquid);
    }

    template <int dim>
    void
    TransportSolver<dim>::apply(const std::vector<double> &v, std::vector<double> &out) const
    {
      const unsigned int na = disc.n_active();
      out.assign(na, 0.);
      n_wls_used = 0;
      // Rows of one-phase neighbourhoods (interpolation coupling): one
      // kappa, the same products as the per-bond loop below in four chains
      // (equal up to round-off); kappa 0: the per-bond loop gives exactly +0.
      const bool fast = !prm.conservative && (classify || !prm.corrosion);
      if (prm.corrosion && classify)
        {
          auto solid = [&](const unsigned int j) { return phase[j] > 0.5; };
          if (!solid_count.initialized())
            solid_count.initialize(na, disc.row_start.data(), disc.col.data(), disc.n_nodes(),
                                   solid);
          else
            solid_count.update(solid);
        }
      const double kappa_table[4] = {prm.kappa_liquid, prm.kappa_interface,
                                     prm.kappa_interface, prm.kappa_solid};
      for (unsigned int i = 0; i < na; ++i)
        {
          if (constrained[i])
            continue;
          const int uniform =
            !fast ? -1 : (prm.corrosion ? solid_count.uniform_phase(i) : 0);
          if (wls_row[i] >= 0)
            {
              // WLS row, valid while the diffusivity is uniform on it
              const unsigned int k     = wls_row[i];
              bool               solid = false;
              double             s     = 0.;
              if (uniform == 0 && !(prm.corrosion && phase[i] > 0.5))
                // all collocation nodes (family nodes or x_i) liquid
                for (auto q = wls->row_start[k]; q < wls->row_start[k + 1]; ++q)
                  s += wls->weight[q] * v[wls->col[q]];
              else
                for (auto q = wls->row_start[k]; q < wls->row_start[k + 1] && !solid; ++q)
                  {
                    solid = prm.corrosion && phase[wls->col[q]] > 0.5;
                    s += wls->weight[q] * v[wls->col[q]];
                  }
              if (!solid)
                {
                  out[i] += (prm.corrosion ? prm.kappa_liquid : prm.kappa) * s;
                  ++n_wls_used;
                  continue;
                }
            }
          if (uniform >= 0)
            {
              const double kappa =
                prm.corrosion ? kappa_table[2 * (phase[i] > 0.5) + uniform] : prm.kappa;
              if (kappa == 0.)
                continue;
              const unsigned int b = disc.row_start[i];
              out[i] += PeriDEAL::internal::phase_row_sum(disc.col.data() + b, kernel_weight.data() + b,
                                                disc.row_start[i + 1] - b, v.data(), v[i],
                                                [kappa](unsigned int) { return kappa; });
              continue;
            }
          if (fast && prm.corrosion)
            {
              // corrosion, a row of both phases: kappa per bond from the
              // neighbour's phase flag (a byte gather), the products of
              // bond_kappa() below in four chains (equal up to round-off)
              const double        *kappa = kappa_table + 2 * (phase[i] > 0.5);
              const unsigned char *solid = solid_count.solid_flags();
              const unsigned int   b     = disc.row_start[i];
              out[i] += PeriDEAL::internal::phase_row_sum(disc.col.data() + b, kernel_weight.data() + b,
                                                disc.row_start[i + 1] - b, v.data(), v[i],
                                                [&](const unsigned int j) {
                                                  return kappa[solid[j]];
                                                });
              continue;
            }
          const bool skip_fictitious = prm.conservative && disc.grid[i] == disc.coarse;
          const bool pay_back        = prm.conservative && disc.grid[i] == disc.fine;
          double     s               = 0.;
          for (unsigned int b = disc.row_start[i]; b < disc.row_start[i + 1]; ++b)
            {
              const unsigned int j = disc.col[b];
              if (j >= na && skip_fictitious)
                continue;
              const double q = bond_kappa(i, j) * kernel_weight[b] * (v[j] - v[i]);
              s += q;
              if (j >= na && pay_back)
                // the mass V_i q comes from the nodes that define C_j
                for (const auto &[a, w] : disc.active_interpolation[j - na])
                  out[a] -= w * q * disc.volume[i] / disc.volume[a];
            }
          out[i] += s;
        }
    }

    template <int dim>
    void
    TransportSolver<dim>::update_phase()
    {
      bool changed = false;
      if (prm.corrosion)
        for (unsigned int i = 0; i < disc.n_active(); ++i)
          if (phase[i] > 0.5 && C[i] < prm.saturation) // (2.79), one way
            {
              phase[i] = 0.;
              changed  = true;
            }
      // fictitious phase: the interpolated phase field, thresholded at 1/2
      disc.update_fictitious(phase);
      for (unsigned int k = disc.n_active(); k < disc.n_nodes(); ++k)
        phase[k] = phase[k] >= 0.5 ? 1. : 0.;
      if (changed)
        implicit->valid = false;
    }

    template <int dim>
    std::vector<std::tuple<unsigned int, unsigned int, double>>
    TransportSolver<dim>::operator_entries(const bool expand, const bool kappa_max) const
    {
      std::vector<std::tuple<unsigned int, unsigned int, double>> out;
      const unsigned int                                          na = disc.n_active();
      const double kmax = prm.corrosion ? std::max({prm.kappa_liquid, prm.kappa_interface,
                                                    prm.kappa_solid}) :
                                          prm.kappa;
      // entry (row, col) of L; columns of fictitious nodes expanded to
      // their active sources if asked
      auto add = [&](const unsigned int row, const unsigned int c, const double v) {
        if (c < na || !expand)
          out.emplace_back(row, c, v);
        else
          for (const auto &[a, w] : disc.active_interpolation[c - na])
            out.emplace_back(row, a, v * w);
      };
      for (unsigned int i = 0; i < na; ++i)
        {
          const bool skip_fictitious = prm.conservative && disc.grid[i] == disc.coarse;
          const bool pay_back        = prm.conservative && disc.grid[i] == disc.fine;
          for (unsigned int b = disc.row_start[i]; b < disc.row_start[i + 1]; ++b)
            {
              const unsigned int j = disc.col[b];
              if (j >= na && skip_fictitious)
                continue;
              const double c = (kappa_max ? kmax : bond_kappa(i, j)) * kernel_weight[b];
              add(i, j, c);
              out.emplace_back(i, i, -c);
              if (j >= na && pay_back)
                for (const auto &[a, w] : disc.active_interpolation[j - na])
                  {
                    const double f = w * c * disc.volume[i] / disc.volume[a];
                    add(a, j, -f);
                    out.emplace_back(a, i, f);
                  }
            }
        }
      return out;
    }

    template <int dim>
    void
    TransportSolver<dim>::implicit_step()
    {
      // (3.89)-(3.90): active rows M/dt - L, fictitious rows identity minus
      // the interpolation weights; the phase is that of t^n (frozen).
      // conservative coupling: fictitious values eliminated (active unknowns only)
      const unsigned int na = disc.n_active();
      const unsigned int n  = prm.conservative ? na : disc.n_nodes();
      if (!implicit->valid)
        {
          std::vector<Eigen::Triplet<double>> tr;
          for (const auto &[r, c, v] : operator_entries(prm.conservative, false))
            tr.emplace_back(r, c, -v);
          for (unsigned int i = 0; i < na; ++i)
            tr.emplace_back(i, i, 1. / dt);
          if (!prm.conservative)
            for (unsigned int row = 0; row < disc.interp_node.size(); ++row)
              {
                const unsigned int k = disc.interp_node[row];
                tr.emplace_back(k, k, 1.);
                for (unsigned int q = disc.interp_start[row]; q < disc.interp_start[row + 1]; ++q)
                  tr.emplace_back(k, disc.interp_source[q], -disc.interp_weight[q]);
              }
          Eigen::SparseMatrix<double> A(n, n);
          A.setFromTriplets(tr.begin(), tr.end());
          A.makeCompressed();
          implicit->lu.compute(A);
          AssertThrow(implicit->lu.info() == Eigen::Success,
                      ExcMessage("multi-grid backward Euler: factorization failed"));
          implicit->valid = true;
        }
      AssertThrow(std::none_of(constrained.begin(), constrained.end(), [](char c) { return c; }),
                  ExcMessage("multi-grid backward Euler: constrained nodes not supported"));
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
      for (unsigned int i = 0; i < disc.n_active(); ++i)
        rhs[i] = C[i] / dt;
      const Eigen::VectorXd x = implicit->lu.solve(rhs);
      for (unsigned int i = 0; i < n; ++i)
        C[i] = x[i];
      if (prm.conservative)
        disc.update_fictitious(C);
    }

    template <int dim>
    void
    TransportSolver<dim>::advance()
    {
      if (prm.scheme == "forward Euler")
        {
          // (3.82)/(3.84): C^{n+1} = C^n + dt L C^n with fictitious values
          // interpolated from the other grid (3.86)/(3.88)
          apply(C, rate);
          for (unsigned int i = 0; i < disc.n_active(); ++i)
            C[i] += dt * rate[i];
        }
      else
        implicit_step();
      disc.update_fictitious(C);
      update_phase();
      t += dt;
      ++n_step;
    }


    CylinderCorrosionCase::CylinderCorrosionCase()
    {
      transport.corrosion       = true;
      transport.kappa_liquid    = 2.;
      transport.kappa_interface = 0.1;
      transport.saturation      = 0.85;
    }

    CorrosionHistory
    run_cylinder_corrosion(const CylinderCorrosionCase &c, const std::string &configuration,
                           const unsigned int max_steps)
    {
      check_parameter(configuration == "uniform fine" || configuration == "uniform coarse" ||
                        configuration == "multi-grid" || configuration == "adaptive hybrid",
                      "Configuration", configuration,
                      "'uniform fine', 'uniform coarse', 'multi-grid' or 'adaptive hybrid'");
      const double H = c.ratio * c.fine_dx, h = c.fine_dx, L = c.half_width;
      check_parameter(std::abs(L / H - std::round(L / H)) < 1e-9 * L / H, "Half width", L,
                      "a multiple of the coarse spacing " + std::to_string(H));
      Parameters<3> p;
      p.delta    = c.delta;
      p.exponent = 1.;
      if (configuration == "uniform fine")
        {
          // the multi-grid's fine nodes: odd multiples of h/2
          p.coarse_dx = p.fine_dx = h;
          for (unsigned int d = 0; d < 3; ++d)
            {
              p.lower[d] = -L - h / 2.;
              p.upper[d] = L + h / 2.;
            }
        }
      else
        {
          p.coarse_dx = H;
          p.fine_dx   = configuration == "uniform coarse" ? H : h;
          for (unsigned int d = 0; d < 3; ++d)
            {
              p.lower[d] = -L;
              p.upper[d] = L;
            }
          if (configuration != "uniform coarse")
            p.fine_region = Region<3>::cylinder(Point<3>(), c.radius + c.fine_margin,
                                                c.half_height + c.fine_margin);
        }
      CorrosionHistory r;
      Timer            timer;
      const Discretization<3> disc(p);
      TransportParameters     t = c.transport;
      t.time_step               = c.time_step;
      if (configuration == "adaptive hybrid")
        t.coarse_quadrature = "wls";
      TransportSolver<3> solver(disc, t);
      solver.set_initial([&](const Point<3> &x) {
        return x[0] * x[0] + x[1] * x[1] < c.radius * c.radius &&
                   std::abs(x[2]) < c.half_height ?
                 1. :
                 0.;
      });
      // C = 0 within delta of the faces of the electrolyte cube [-L, L]^3
      // (its cells reach L + H/2)
      const double inner = L + H / 2. - c.delta;
      solver.set_constrained([&](const Point<3> &x) {
        return std::max({std::abs(x[0]), std::abs(x[1]), std::abs(x[2])}) > inner;
      });
      r.setup_seconds   = timer.wall_time();
      r.n_active_coarse = disc.n_active_coarse;
      r.n_active_fine   = disc.n_active_fine;
      r.n_fictitious    = disc.n_fictitious_coarse + disc.n_fictitious_fine;
      r.n_constrained   = solver.n_constrained();
      r.n_wls_rows      = solver.n_wls_rows();
      r.time_step       = solver.time_step();
      const double v0   = solver.solid_volume();
      r.time.push_back(0.);
      r.loss.push_back(0.);
      Timer step_timer;
      while (solver.time() < c.end_time - 1e-9 * solver.time_step() &&
             (max_steps == 0 || solver.step() < max_steps))
        {
          solver.advance();
          r.time.push_back(solver.time());
          r.loss.push_back(1. - solver.solid_volume() / v0);
        }
      r.step_seconds     = step_timer.wall_time() / std::max(1u, solver.step());
      r.step_cpu_seconds = step_timer.cpu_time() / std::max(1u, solver.step());
      return r;
    }

    template struct Region<1>;
    template struct Region<2>;
    template struct Region<3>;
    template struct Parameters<1>;
    template struct Parameters<2>;
    template struct Parameters<3>;
    template class Discretization<1>;
    template class Discretization<2>;
    template class Discretization<3>;
    template class TransportSolver<1>;
    template class TransportSolver<2>;
    template class TransportSolver<3>;
  } // namespace MultiGrid
} // namespace PeriDEAL
