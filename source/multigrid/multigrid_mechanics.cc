#include <deal.II/base/utilities.h>

#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/lapack_full_matrix.h>
#include <deal.II/lac/vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/wls_quadrature.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/lattice_sweep_kernel.h>
#include <perideal/multigrid/multigrid_mechanics.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <limits>

#if defined(__AVX512F__) && defined(__AVX512VL__)
#  include <immintrin.h>
#  define PERIDEAL_MULTIGRID_AVX512 1
#endif

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

      // CPU time of the calling thread [s] (timing(): not inflated by the
      // other processes on a shared machine as wall time is).
      double
      thread_cpu_seconds()
      {
        timespec t;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
        return t.tv_sec + 1e-9 * t.tv_nsec;
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

      // Chunk size of the lattice sweep (box positions): the chunk's forces,
      // positions and the reactions it reaches stay in L2.
      constexpr unsigned int sweep_chunk = 512;

#ifdef PERIDEAL_MULTIGRID_AVX512
      // The lattice-sweep kernel of BondBasedOperator (bitwise the same
      // stretch and breaking decisions): NO offsets over the listed groups
      // of eight box positions of a chunk.
      using internal::LatticeSweep::sweep_offsets;
#endif

      // The portable counterpart of sweep_offsets() for one offset h.
      template <int dim>
      inline void
      sweep_offset_scalar(const double                               *p,
                          double                                     *reaction,
                          double                                     *acc,
                          std::uint8_t                               *live,
                          const std::size_t                           n_bytes,
                          const std::size_t                           N,
                          const unsigned int                          C,
                          const std::size_t                           c0,
                          const unsigned int                          n,
                          const long                                 *o,
                          const unsigned int                          h,
                          const double                               *k,
                          const double                               *r,
                          const double                                s0,
                          std::vector<std::pair<unsigned int, long>> &broken)
      {
        std::uint8_t *bits = live + h * n_bytes + c0 / 8;
        for (unsigned int v = 0; v < n; ++v)
          if ((bits[v / 8] >> (v % 8)) & 1u)
            {
              const std::size_t L = c0 + v;
              double            y[dim], l2 = 0.;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  y[d] = p[d * N + L + o[h]] - p[d * N + L];
                  l2 += y[d] * y[d];
                }
              const double l  = std::sqrt(l2);
              const double dl = l - r[h];
              if (dl > s0 * r[h])
                {
                  bits[v / 8] &= std::uint8_t(~(1u << (v % 8)));
                  broken.emplace_back(h, long(L));
                  continue;
                }
              const double scale = k[h] * dl / l;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  acc[d * C + v] += scale * y[d];
                  reaction[d * N + L + o[h]] += scale * y[d];
                }
            }
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
      // WLS rows are not pairwise (no reactions), and with the pay-back
      // the hybrid's momentum drift grew (1.7e-2 -> 1.2e-1 in
      // multiadapt.conservative_coupling): standard quadrature only
      check_parameter(!conservative_coupling || model != MechanicsModel::adaptive_hybrid,
                      "Conservative coupling", "true with adaptive hybrid",
                      "false with Model = adaptive hybrid (WLS rows are not pairwise)");
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
      setup_box(coarse);
      setup_box(fine);
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
    MechanicsSolver<dim>::setup_box(const Grid g)
    {
      const Lattice &L = grids[g];
      Box           &B = boxes[g];
      const int      R = L.radius;
      B.n_box          = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          B.stride[d] = B.n_box;
          B.n_box *= L.n[d] + 2 * R;
        }
      B.offset.clear();
      B.k.clear();
      B.coefficient.clear();
      B.length.clear();
      for (unsigned int k = 0; k < L.offset.size(); ++k)
        {
          long o = 0;
          for (unsigned int d = 0; d < dim; ++d)
            o += L.offset[k][d] * B.stride[d];
          if (o <= 0)
            continue;
          B.offset.push_back(o);
          B.k.push_back(k);
          B.coefficient.push_back(L.coefficient[k]);
          B.length.push_back(L.length[k]);
        }
      B.o_max   = B.offset.empty() ? 0 : *std::max_element(B.offset.begin(), B.offset.end());
      B.n_bytes = (B.n_box + sweep_chunk - 1) / sweep_chunk * sweep_chunk / 8;
      B.n_alloc = 8 * B.n_bytes + B.o_max + 16;
      B.position.resize(L.n_nodes);
      B.state.assign(B.n_alloc, 0);
      B.reference.assign(dim * B.n_alloc, 0.);
      // Reference positions relative to the lattice centre (small
      // magnitudes: round-off of y = p_j - p_i ~ eps |x - x_c|).
      std::array<int, dim> mid;
      for (unsigned int d = 0; d < dim; ++d)
        mid[d] = L.n[d] / 2;
      for (unsigned int i = 0; i < L.n_nodes; ++i)
        {
          const auto ix = L.index(i);
          long       P  = 0;
          for (unsigned int d = 0; d < dim; ++d)
            P += (ix[d] + R) * B.stride[d];
          B.position[i] = P;
          B.state[P]    = 1;
          for (unsigned int d = 0; d < dim; ++d)
            B.reference[d * B.n_alloc + P] = (ix[d] - mid[d]) * L.dx;
        }
      B.first = L.n_nodes > 0 ? B.position.front() : 0;
      B.last  = L.n_nodes > 0 ? B.position.back() + 1 : 0;
      B.p     = B.reference;
      B.reaction.assign(dim * B.n_alloc, 0.);
      B.valid = false;
    }

    template <int dim>
    void
    MechanicsSolver<dim>::build_box_bits(const Grid g)
    {
      const Lattice     &L = grids[g];
      Box               &B = boxes[g];
      const unsigned int S = L.offset.size(), H = B.offset.size();
      const std::size_t  W = B.n_bytes / 8;
      if (!B.intact_valid)
        {
          // From the broken flags (after set-up and pre-cracks; bonds
          // broken by the sweep clear their bit there).
          B.intact.assign(H * W, 0);
          for (unsigned int i = 0; i < L.n_nodes; ++i)
            {
              const bool in = L.interior(i);
              const auto ix = L.index(i);
              const long P  = B.position[i];
              for (unsigned int h = 0; h < H; ++h)
                {
                  const unsigned int k = B.k[h];
                  if (broken[g][std::size_t(i) * S + k])
                    continue;
                  if (!in)
                    {
                      auto jx = ix;
                      for (unsigned int d = 0; d < dim; ++d)
                        jx[d] += L.offset[k][d];
                      if (!L.inside(jx))
                        continue;
                    }
                  B.intact[h * W + P / 64] |= std::uint64_t(1) << (P % 64);
                }
            }
          B.intact_valid = true;
        }
      B.evaluated.clear();
      B.evaluated_position.clear();
      B.evaluated_bits.assign(W + B.o_max / 64 + 2, 0);
      for (const unsigned int i : active[g])
        if (evaluated(g, i))
          {
            const long P = B.position[i];
            B.evaluated.push_back(i);
            B.evaluated_position.push_back(P);
            B.evaluated_bits[P / 64] |= std::uint64_t(1) << (P % 64);
          }
      B.paid.clear();
      B.paid_position.clear();
      if (prm.conservative_coupling)
        {
          std::vector<std::pair<long, unsigned int>> f;
          for (const unsigned int i : fictitious[g])
            f.emplace_back(B.position[i], i);
          std::sort(f.begin(), f.end());
          for (const auto &[P, i] : f)
            {
              B.paid.push_back(i);
              B.paid_position.push_back(P);
            }
        }
      if (!B.state_valid)
        for (unsigned int i = 0; i < L.n_nodes; ++i)
          B.state[B.position[i]] = 1 + active_flag[g][i];
      B.state_valid = true;
      // live = intact & (evaluated(P) | evaluated(P + o)), 64 positions at
      // a time: bit P of the evaluated bits shifted by o is bit P + o. A
      // change of E at Q changes the live bits of P = Q - o .. Q only.
      std::size_t w_begin = 0, w_end = W;
      if (B.live_valid && B.live.size() == H * W && B.any.size() == W)
        {
          w_begin = std::max<long>(B.dirty_lo - B.o_max, 0) / 64;
          w_end   = B.dirty_hi > B.dirty_lo ? std::min<std::size_t>((B.dirty_hi + 63) / 64, W) : 0;
        }
      else
        {
          B.live.resize(H * W);
          B.any.assign(W, 0);
        }
      const std::uint64_t *E = B.evaluated_bits.data();
      for (unsigned int h = 0; h < H; ++h)
        {
          const std::size_t   q = B.offset[h] / 64;
          const unsigned int  r = B.offset[h] % 64;
          const std::uint64_t *I = B.intact.data() + h * W;
          std::uint64_t       *Z = B.live.data() + h * W;
          for (std::size_t w = w_begin; w < w_end; ++w)
            {
              const std::uint64_t shifted =
                r == 0 ? E[w + q] : (E[w + q] >> r) | (E[w + q + 1] << (64 - r));
              Z[w] = I[w] & (E[w] | shifted);
            }
        }
      // Groups of eight positions with a live bit for some offset, per
      // chunk (the sweep visits only these).
      // Over all words: the sweep has cleared the live bits of the bonds
      // broken since the last build, so groups may have emptied anywhere.
      std::fill(B.any.begin(), B.any.end(), 0);
      for (unsigned int h = 0; h < H; ++h)
        for (std::size_t w = 0; w < W; ++w)
          B.any[w] |= B.live[h * W + w];
      const auto &any = B.any;
      B.live_valid    = true;
      B.dirty_lo      = std::numeric_limits<long>::max();
      B.dirty_hi      = std::numeric_limits<long>::min();
      const unsigned int groups_per_chunk = sweep_chunk / 8;
      B.group_start.assign(1, 0);
      B.groups.clear();
      for (std::size_t c = 0; c < W * 64 / sweep_chunk; ++c)
        {
          for (unsigned int gi = 0; gi < groups_per_chunk; ++gi)
            {
              const std::size_t byte = c * groups_per_chunk + gi;
              if ((any[byte / 8] >> (8 * (byte % 8))) & 0xFFu)
                B.groups.push_back(gi);
            }
          B.group_start.push_back(B.groups.size());
        }
      B.valid = true;
    }

    template <int dim>
    void
    MechanicsSolver<dim>::fill_box_positions(const Grid g)
    {
      Box &B = boxes[g];
      if (B.filled == u_version)
        return;
      B.filled          = u_version;
      const std::size_t N = B.n_alloc;
      const double     *U = u[g].data();
      for (const auto &[i0, n] : filled_runs[g])
        {
          const long P = B.position[i0];
          for (unsigned int d = 0; d < dim; ++d)
            {
              double *__restrict       p = B.p.data() + d * N + P;
              const double *__restrict x = B.reference.data() + d * N + P;
              const double *__restrict w = U + dim * i0 + d;
              for (unsigned int t = 0; t < n; ++t)
                p[t] = x[t] + w[dim * t];
            }
        }
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
      std::vector<long>       lin(1, 0), box(1, 0);
      for (unsigned int k = 0; k < L.offset.size(); ++k)
        {
          position.emplace_back(Point<dim>() + L.xi[k]);
          lin.push_back(L.linear_offset[k]);
          long o = 0;
          for (unsigned int d = 0; d < dim; ++d)
            o += L.offset[k][d] * boxes[coarse].stride[d];
          box.push_back(o);
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
      wls_box_offset.clear();
      wls_weight.clear();
      for (auto b = wls.row_start[0]; b < wls.row_start[1]; ++b)
        {
          wls_offset.push_back(lin[wls.col[b]]);
          wls_box_offset.push_back(box[wls.col[b]]);
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
          boxes[g].valid       = false;
          boxes[g].state_valid = false;
          boxes[g].live_valid  = false;
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
      // in its stencil.
      if (!active[coarse].empty())
        for (unsigned int i = 0; i < C.n_nodes; ++i)
          if (refined[i] && has_active_neighbour(coarse, i))
            fictitious[coarse].push_back(i);
      if (!active[fine].empty() && !active[coarse].empty())
        {
          // Only fine nodes of unrefined cells with a refined cell in reach
          // of their stencil can be fictitious: count the refined cells in
          // the box of coarse cells the stencil touches by a summed-area
          // table (O(2^dim) per node), then search the stencil.
          std::array<int, dim> m;
          std::size_t          n_table = 1;
          for (unsigned int d = 0; d < dim; ++d)
            {
              m[d] = C.n[d] + 1;
              n_table *= m[d];
            }
          const auto table_index = [&](const std::array<int, dim> &t) {
            std::size_t k = 0;
            for (int d = dim - 1; d >= 0; --d)
              k = k * m[d] + t[d];
            return k;
          };
          std::vector<unsigned int> table(n_table, 0);
          for (unsigned int i = 0; i < C.n_nodes; ++i)
            if (refined[i])
              {
                auto t = C.index(i);
                for (unsigned int d = 0; d < dim; ++d)
                  ++t[d];
                table[table_index(t)] = 1;
              }
          for (unsigned int d = 0; d < dim; ++d)
            for (std::size_t k = 0; k < n_table; ++k)
              {
                std::array<int, dim> t;
                std::size_t          rest = k;
                for (unsigned int e = 0; e < dim; ++e)
                  {
                    t[e] = rest % m[e];
                    rest /= m[e];
                  }
                if (t[d] == 0)
                  continue;
                auto s = t;
                --s[d];
                table[k] += table[table_index(s)];
              }
          const int R = F.radius;
          for (unsigned int f = 0; f < F.n_nodes; ++f)
            {
              const unsigned int cell = cell_of(f);
              if (refined[cell])
                continue;
              const auto           fx = F.index(f);
              std::array<int, dim> lo, hi;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  lo[d] = std::max(fx[d] - R, 0) / int(ratio);
                  hi[d] = std::min(fx[d] + R, F.n[d] - 1) / int(ratio) + 1;
                }
              // Inclusion-exclusion over the 2^dim corners of [lo, hi).
              long count = 0;
              for (unsigned int corner = 0; corner < (1u << dim); ++corner)
                {
                  std::array<int, dim> t;
                  int                  sign = 1;
                  for (unsigned int d = 0; d < dim; ++d)
                    {
                      const bool up = corner & (1u << d);
                      t[d]          = up ? hi[d] : lo[d];
                      sign *= up ? 1 : -1;
                    }
                  count += sign * long(table[table_index(t)]);
                }
              if (count > 0 && has_active_neighbour(fine, f))
                fictitious[fine].push_back(f);
            }
        }

      update_interpolation_rows({}, {});
      update_runs();
    }

    template <int dim>
    unsigned int
    MechanicsSolver<dim>::child(const unsigned int cell, const unsigned int q) const
    {
      const auto           ix = grids[coarse].index(cell);
      std::array<int, dim> fx;
      unsigned int         rest = q;
      for (unsigned int d = 0; d < dim; ++d)
        {
          fx[d] = ix[d] * ratio + rest % ratio;
          rest /= ratio;
        }
      return grids[fine].node(fx);
    }

    template <int dim>
    bool
    MechanicsSolver<dim>::has_active_neighbour(const Grid g, const unsigned int i) const
    {
      // The stencil is symmetric: search i's own stencil.
      return grids[g].any_neighbour(i, [&](const unsigned int j) { return active_flag[g][j] != 0; });
    }

    template <int dim>
    void
    MechanicsSolver<dim>::update_node_sets(const std::vector<unsigned int> &cells)
    {
      // Only the new fine nodes (children of @p cells) become active and
      // only these cells' coarse nodes inactive. So a fine node becomes
      // fictitious only if it is inactive and in the stencil of a new fine
      // node, and stops being fictitious only by becoming active; a coarse
      // node can change only if it is one of the cells or was fictitious.
      // The result equals update_node_sets() (same ascending lists).
      const Lattice     &F          = grids[fine];
      const unsigned int n_children = Utilities::fixed_power<dim>(ratio);
      std::vector<unsigned int> children;
      children.reserve(cells.size() * n_children);
      const auto mark_dirty = [&](const Grid g, const unsigned int i) {
        Box &B     = boxes[g];
        B.dirty_lo = std::min(B.dirty_lo, B.position[i]);
        B.dirty_hi = std::max(B.dirty_hi, B.position[i] + 1);
      };
      for (const unsigned int i : cells)
        {
          active_flag[coarse][i]                          = 0;
          boxes[coarse].state[boxes[coarse].position[i]] = 1;
          mark_dirty(coarse, i);
          for (unsigned int q = 0; q < n_children; ++q)
            {
              const unsigned int f = child(i, q);
              active_flag[fine][f]                      = 1;
              boxes[fine].state[boxes[fine].position[f]] = 2;
              mark_dirty(fine, f);
              children.push_back(f);
            }
        }
      std::sort(children.begin(), children.end());
      for (const unsigned int g : {0u, 1u})
        boxes[g].valid = false;
      auto &ac = active[coarse];
      ac.erase(std::remove_if(ac.begin(), ac.end(),
                              [&](const unsigned int i) { return !active_flag[coarse][i]; }),
               ac.end());
      {
        std::vector<unsigned int> merged(active[fine].size() + children.size());
        std::merge(active[fine].begin(), active[fine].end(), children.begin(), children.end(),
                   merged.begin());
        active[fine].swap(merged);
      }

      std::vector<unsigned int> fict_fine, fict_coarse;
      std::vector<std::uint8_t> &mark = fine_mark;
      mark.resize(F.n_nodes, 0);
      for (const unsigned int f : fictitious[fine])
        if (!active_flag[fine][f])
          {
            fict_fine.push_back(f);
            mark[f] = 1;
          }
      for (const unsigned int f : children)
        F.any_neighbour(f, [&](const unsigned int j) {
          if (!active_flag[fine][j] && !mark[j])
            {
              mark[j] = 1;
              fict_fine.push_back(j);
            }
          return false;
        });
      for (const unsigned int f : fict_fine)
        mark[f] = 0;
      std::sort(fict_fine.begin(), fict_fine.end());
      const std::vector<unsigned int> &old_fictitious = fictitious[coarse];
      for (const auto *list : {&old_fictitious, &cells})
        for (const unsigned int i : *list)
          if (has_active_neighbour(coarse, i))
            fict_coarse.push_back(i);
      std::sort(fict_coarse.begin(), fict_coarse.end());
      fict_coarse.erase(std::unique(fict_coarse.begin(), fict_coarse.end()), fict_coarse.end());

      const std::vector<unsigned int> old_fine = std::move(fictitious[fine]),
                                      old_coarse = coarse_interpolated;
      fictitious[fine].swap(fict_fine);
      fictitious[coarse].swap(fict_coarse);
      update_interpolation_rows(old_fine, old_coarse);
      update_runs();
    }

    template <int dim>
    void
    MechanicsSolver<dim>::update_runs()
    {
      const auto make_runs = [](const Lattice                                      &L,
                                const auto                                         &include,
                                std::vector<std::pair<unsigned int, unsigned int>> &runs) {
        runs.clear();
        for (unsigned int i = 0; i < L.n_nodes; ++i)
          if (include(i))
            {
              if (!runs.empty() && runs.back().first + runs.back().second == i &&
                  i % L.n[0] != 0)
                ++runs.back().second;
              else
                runs.emplace_back(i, 1);
            }
      };
      for (const unsigned int g : {0u, 1u})
        {
          const auto &flag = active_flag[g];
          make_runs(grids[g], [&](const unsigned int i) { return flag[i] != 0; }, active_runs[g]);
          // Fictitious nodes are inactive: mark them to merge the two lists.
          std::vector<std::uint8_t> filled(flag);
          for (const unsigned int i : fictitious[g])
            filled[i] = 1;
          make_runs(grids[g], [&](const unsigned int i) { return filled[i] != 0; },
                    filled_runs[g]);
          prescribed_active[g].clear();
          for (const unsigned int i : active[g])
            if (prescribed[g][i])
              prescribed_active[g].push_back(i);
        }
      wls_runs.clear();
      if (!use_wls.empty())
        make_runs(grids[coarse],
                  [&](const unsigned int i) { return active_flag[coarse][i] && use_wls[i]; },
                  wls_runs);
    }

    template <int dim>
    void
    MechanicsSolver<dim>::update_interpolation_rows(const std::vector<unsigned int> &old_fine,
                                                    const std::vector<unsigned int> &old_coarse)
    {
      // Every inactive coarse node that is fictitious or a source of a fine
      // fictitious node (interpolated from the fine nodes around it, all
      // active), then the fine fictitious nodes (from coarse nodes).
      const Lattice &C = grids[coarse], &F = grids[fine];
      std::vector<std::pair<unsigned int, double>> src;
      // Node list, CSR rows and the row of node i: copied from the old rows
      // if i is in the old list (ascending, like the new one), else computed.
      const auto rows = [&](const Grid                       g,
                            const std::vector<unsigned int> &list,
                            const std::vector<unsigned int> &old_list,
                            const auto                      &point,
                            const auto                      &on_source) {
        const std::vector<unsigned int> old_start  = std::move(interp_start[g]),
                                        old_source = std::move(interp_source[g]);
        const std::vector<double>       old_weight = std::move(interp_weight[g]);
        interp_start[g].assign(1, 0);
        interp_source[g].clear();
        interp_weight[g].clear();
        std::size_t r_old = 0;
        for (const unsigned int i : list)
          {
            while (r_old < old_list.size() && old_list[r_old] < i)
              ++r_old;
            if (r_old < old_list.size() && old_list[r_old] == i)
              for (auto b = old_start[r_old]; b < old_start[r_old + 1]; ++b)
                {
                  interp_source[g].push_back(old_source[b]);
                  interp_weight[g].push_back(old_weight[b]);
                }
            else
              {
                interpolation_sources(Grid(1 - g), point(i), src);
                for (const auto &[j, w] : src)
                  {
                    interp_source[g].push_back(j);
                    interp_weight[g].push_back(w);
                  }
              }
            for (auto b = interp_start[g].back(); b < interp_source[g].size(); ++b)
              on_source(interp_source[g][b]);
            interp_start[g].push_back(interp_source[g].size());
          }
      };
      std::vector<std::uint8_t> mark(C.n_nodes, 0);
      for (const auto i : fictitious[coarse])
        mark[i] = 1;
      rows(fine, fictitious[fine], old_fine, [&](const unsigned int f) { return F.point(f); },
           [&](const unsigned int j) {
             if (!active_flag[coarse][j])
               mark[j] = 1;
           });
      coarse_interpolated.clear();
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (mark[i])
          coarse_interpolated.push_back(i);
      rows(coarse, coarse_interpolated, old_coarse,
           [&](const unsigned int i) { return C.point(i); },
           [&](const unsigned int j) { AssertThrow(active_flag[fine][j], ExcInternalError()); });
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
      Box &B = boxes[g];
      fictitious_force[g].clear();
      if (!B.valid)
        build_box_bits(g);
      if (B.evaluated.empty())
        return;
      fill_box_positions(g);
      const Lattice      &Lt      = grids[g];
      const unsigned int  S       = Lt.offset.size();
      const std::size_t   N       = B.n_alloc;
      const double        inv_rho = 1. / prm.density;
      // Coarse bonds break only in the uniform coarse model (see
      // compute_accelerations()): an infinite s0 never breaks.
      const double        s_break = allow_breaking ? s0 : std::numeric_limits<double>::infinity();
      constexpr unsigned int C = sweep_chunk;
      alignas(64) double     acc[dim * C];
      double                *R      = B.reaction.data();
      const std::size_t      n_bits = 8 * B.n_bytes;
      const unsigned int     H = B.offset.size(), n_pairs = H / 2;
      // Reactions are written from the first chunk with work on: zero
      // from there (zero_begin) up to what the chunks reach (zeroed).
      std::size_t            zero_begin = 0, zeroed = 0, e = 0;
      bool                   started = false;
      const std::size_t      E      = B.evaluated.size();
      auto                  &A      = a[g];
      // conservative coupling: the same force (the reactions of the
      // active-fictitious bonds) on the fictitious positions
      std::size_t            e_paid = 0;
      const std::size_t      E_paid = B.paid.size();
      auto                  &F_paid = fictitious_force[g];
      if (E_paid > 0)
        F_paid.assign(dim * Lt.n_nodes, 0.);
      B.newly_broken.clear();
      // Byte view of the live words (little endian: bit P % 8 of byte P / 8).
      static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "bit layout of the live words");
      std::uint8_t *live = reinterpret_cast<std::uint8_t *>(B.live.data());
      for (std::size_t c0 = 0; c0 < n_bits && (e < E || e_paid < E_paid); c0 += C)
        {
          const unsigned int n    = std::min<std::size_t>(C, n_bits - c0);
          const std::uint8_t *groups   = B.groups.data() + B.group_start[c0 / C];
          const unsigned int  n_groups = B.group_start[c0 / C + 1] - B.group_start[c0 / C];
          const bool          work     = n_groups > 0;
          if (work)
            {
              if (!started)
                {
                  zero_begin = zeroed = c0;
                  started             = true;
                }
              const std::size_t need = std::min<std::size_t>(N, c0 + n + B.o_max + 8);
              for (unsigned int d = 0; d < dim; ++d)
                std::fill(R + d * N + zeroed, R + d * N + std::max(zeroed, need), 0.);
              zeroed = std::max(zeroed, need);
              std::fill(acc, acc + dim * C, 0.);
#ifdef PERIDEAL_MULTIGRID_AVX512
              // Two offsets per pass (shared loads of p_L and of the force).
              for (unsigned int h = 0; h < n_pairs; ++h)
                {
                  const unsigned int hs[2] = {h, h + n_pairs};
                  sweep_offsets<dim, 2>(B.p.data(), R, acc, {live, B.n_bytes, 1, nullptr}, N,
                                        C, c0, groups, n_groups,
                                        B.offset.data(), hs, B.coefficient.data(),
                                        B.length.data(), s_break, B.newly_broken);
                }
              if (H % 2)
                {
                  const unsigned int hs[1] = {H - 1};
                  sweep_offsets<dim, 1>(B.p.data(), R, acc, {live, B.n_bytes, 1, nullptr}, N,
                                        C, c0, groups, n_groups,
                                        B.offset.data(), hs, B.coefficient.data(),
                                        B.length.data(), s_break, B.newly_broken);
                }
#else
              (void)n_pairs;
              (void)groups;
              for (unsigned int h = 0; h < H; ++h)
                sweep_offset_scalar<dim>(B.p.data(), R, acc, live, B.n_bytes, N, C, c0,
                                         n, B.offset.data(), h, B.coefficient.data(),
                                         B.length.data(), s_break, B.newly_broken);
#endif
            }
          // F = (forces on L) - (reactions on L): final once L's chunk is
          // done, reactions coming from lower positions only.
          for (; e < E && std::size_t(B.evaluated_position[e]) < c0 + n; ++e)
            {
              const std::size_t P = B.evaluated_position[e];
              const unsigned int i = B.evaluated[e];
              for (unsigned int d = 0; d < dim; ++d)
                A[dim * i + d] =
                  ((work ? acc[d * C + P - c0] : 0.) -
                   (P >= zero_begin && P < zeroed ? R[d * N + P] : 0.)) *
                  inv_rho;
            }
          for (; e_paid < E_paid && std::size_t(B.paid_position[e_paid]) < c0 + n; ++e_paid)
            {
              const std::size_t  P = B.paid_position[e_paid];
              const unsigned int i = B.paid[e_paid];
              for (unsigned int d = 0; d < dim; ++d)
                F_paid[dim * i + d] =
                  ((work ? acc[d * C + P - c0] : 0.) -
                   (P >= zero_begin && P < zeroed ? R[d * N + P] : 0.)) *
                  inv_rho;
            }
        }
      // Both copies of the newly broken bonds (rare).
      for (const auto &[h, P] : B.newly_broken)
        {
          std::array<int, dim> ix;
          long                 rest = P;
          for (int d = dim - 1; d >= 0; --d)
            {
              ix[d] = int(rest / B.stride[d]) - Lt.radius;
              rest %= B.stride[d];
            }
          const unsigned int i = Lt.node(ix), k = B.k[h];
          const unsigned int j = i + Lt.linear_offset[k];
          broken[g][std::size_t(i) * S + k]           = 1;
          broken[g][std::size_t(j) * S + Lt.mirror[k]] = 1;
          B.intact[h * (B.n_bytes / 8) + P / 64] &= ~(std::uint64_t(1) << (P % 64));
        }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::wls_forces()
    {
      // Over the runs of active WLS nodes (consecutive coarse box
      // positions), one stencil offset at a time (contiguous, vectorized).
      Box              &B = boxes[coarse];
      const std::size_t N = B.n_alloc;
      if (wls_runs.empty())
        return;
      if (wls_u.size() != dim * N)
        wls_u.assign(dim * N, 0.);
      const double *U = u[coarse].data();
      for (const auto &[i0, n] : filled_runs[coarse])
        {
          const long P = B.position[i0];
          for (unsigned int d = 0; d < dim; ++d)
            for (unsigned int t = 0; t < n; ++t)
              wls_u[d * N + P + t] = U[dim * (i0 + t) + d];
        }
      // Chunks of a run (the chunk's forces in L1); per pass over a chunk
      // two offsets, all components (per position the same sum order as
      // one offset and one component at a time: offset, then component of u).
      constexpr unsigned int C = 256;
      alignas(64) double     f[dim][C];
      const double           inv_rho = 1. / prm.density;
      double                *A       = a[coarse].data();
      const unsigned int     K       = wls_box_offset.size();
      for (const auto &[i0, n_run] : wls_runs)
        for (unsigned int t0 = 0; t0 < n_run; t0 += C)
          {
            const unsigned int n  = std::min(C, n_run - t0);
            const std::size_t  c0 = B.position[i0] + t0;
            for (unsigned int d = 0; d < dim; ++d)
              std::fill(f[d], f[d] + n, 0.);
            for (unsigned int k = 0; k < K; k += 2)
              {
                const unsigned int n_k = std::min(2u, K - k);
                const double      *u0[dim], *u1[dim];
                for (unsigned int e2 = 0; e2 < dim; ++e2)
                  {
                    u0[e2] = wls_u.data() + e2 * N + c0 + wls_box_offset[k];
                    u1[e2] = wls_u.data() + e2 * N + c0 + wls_box_offset[k + n_k - 1];
                  }
                const double *w0 = &wls_weight[k * dim * dim],
                             *w1 = &wls_weight[(k + n_k - 1) * dim * dim];
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    double *__restrict fd = f[d];
                    if (n_k == 2)
                      {
#pragma omp simd
                        for (unsigned int q = 0; q < n; ++q)
                          {
                            double s = fd[q];
                            for (unsigned int e2 = 0; e2 < dim; ++e2)
                              s += w0[d * dim + e2] * u0[e2][q];
                            for (unsigned int e2 = 0; e2 < dim; ++e2)
                              s += w1[d * dim + e2] * u1[e2][q];
                            fd[q] = s;
                          }
                      }
                    else
                      {
#pragma omp simd
                        for (unsigned int q = 0; q < n; ++q)
                          {
                            double s = fd[q];
                            for (unsigned int e2 = 0; e2 < dim; ++e2)
                              s += w0[d * dim + e2] * u0[e2][q];
                            fd[q] = s;
                          }
                      }
                  }
              }
            double *Ai = A + dim * (i0 + t0);
            for (unsigned int q = 0; q < n; ++q)
              for (unsigned int d = 0; d < dim; ++d)
                Ai[dim * q + d] = f[d][q] * inv_rho;
          }
    }

    template <int dim>
    void
    MechanicsSolver<dim>::compute_accelerations()
    {
      ++u_version;
      double start = thread_cpu_seconds();
      std::vector<double> *fields[2] = {&u[coarse], &u[fine]};
      interpolate_fictitious(fields);
      timing[1] += thread_cpu_seconds() - start;
      start = thread_cpu_seconds();
      standard_forces(fine, true);
      // Coarse bonds break only in the uniform coarse model: in the
      // adaptive ones their cells are refined before they reach s0.
      standard_forces(coarse, prm.model == MechanicsModel::uniform_coarse);
      if (!use_wls.empty())
        wls_forces();
      if (prm.conservative_coupling)
        pay_back_fictitious_forces();
      timing[0] += thread_cpu_seconds() - start;
    }

    template <int dim>
    void
    MechanicsSolver<dim>::pay_back_fictitious_forces()
    {
      // Total force T_j = F_j V_j of fictitious node j goes to its sources
      // with the interpolation weights, as force density w T_j / V_a; the
      // fine fictitious rows first (their inactive coarse corners collect
      // T in `pending`), then the coarse interpolated rows (fine sources,
      // all active). Sum of the weights 1: the total force is unchanged.
      const double V[2] = {std::pow(prm.coarse_dx, dim), std::pow(prm.fine_dx, dim)};
      const auto  &Fc = fictitious_force[coarse], &Ff = fictitious_force[fine];
      std::vector<double> pending(dim * grids[coarse].n_nodes, 0.);
      if (!Ff.empty())
        for (unsigned int r = 0; r < fictitious[fine].size(); ++r)
          {
            const unsigned int j = fictitious[fine][r];
            for (auto b = interp_start[fine][r]; b < interp_start[fine][r + 1]; ++b)
              {
                const unsigned int s = interp_source[fine][b];
                const double       w = interp_weight[fine][b] * V[fine];
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    const double T = w * Ff[dim * j + d];
                    if (active_flag[coarse][s])
                      a[coarse][dim * s + d] += T / V[coarse];
                    else
                      pending[dim * s + d] += T;
                  }
              }
          }
      for (unsigned int r = 0; r < coarse_interpolated.size(); ++r)
        {
          const unsigned int j = coarse_interpolated[r];
          double             T[dim];
          for (unsigned int d = 0; d < dim; ++d)
            T[d] = pending[dim * j + d] + (Fc.empty() ? 0. : Fc[dim * j + d] * V[coarse]);
          for (auto b = interp_start[coarse][r]; b < interp_start[coarse][r + 1]; ++b)
            {
              const unsigned int s = interp_source[coarse][b];
              for (unsigned int d = 0; d < dim; ++d)
                a[fine][dim * s + d] += interp_weight[coarse][b] * T[d] / V[fine];
            }
        }
    }

    // ------------------------------------------------------------------ switching

    template <int dim>
    bool
    MechanicsSolver<dim>::find_critical(std::vector<std::uint8_t> &zone)
    {
      const Lattice     &L = grids[coarse];
      Box               &B = boxes[coarse];
      const std::size_t  N = B.n_alloc;
      const double       threshold = prm.switching_sigma * s0;
      zone.clear();
      if (active[coarse].empty())
        return false;
      if (!B.valid)
        build_box_bits(coarse);
      fill_box_positions(coarse);
      // H(x): the node and its neighbours within delta.
      const auto mark_family = [&](const unsigned int i) {
        zone[i]       = 1;
        const auto ix = L.index(i);
        for (unsigned int k = 0; k < L.offset.size(); ++k)
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
      const auto node_at = [&](const long P) {
        std::array<int, dim> ix;
        long                 rest = P;
        for (int d = dim - 1; d >= 0; --d)
          {
            ix[d] = int(rest / B.stride[d]) - L.radius;
            rest %= B.stride[d];
          }
        return L.node(ix);
      };
      // (3.80) for every bond (once, as (P, P + o), o > 0) with both ends
      // in the lattice and an active end, broken or not: |y| - r >= sigma
      // s0 r, i.e. |y|^2 >= ((1 + sigma s0) r)^2. A branch-free pass per
      // offset (vectorized) finds whether any bond is critical; only then a
      // second pass finds which.
      const std::uint8_t *state = B.state.data();
      const double       *p     = B.p.data();
      bool                any   = false;
      for (unsigned int h = 0; h < B.offset.size(); ++h)
        {
          const long   o     = B.offset[h];
          const double bound = (1. + threshold) * B.length[h];
          const double lim   = bound * bound;
          const auto   critical = [&](const long P) {
            double y2 = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                const double y = p[d * N + P + o] - p[d * N + P];
                y2 += y * y;
              }
            return (y2 >= lim) & (state[P] + state[P + o] >= 3);
          };
          int hit = 0;
#pragma omp simd reduction(| : hit)
          for (long P = B.first; P < B.last; ++P)
            hit |= critical(P);
          if (!hit)
            continue;
          if (!any)
            zone.assign(L.n_nodes, 0);
          any = true;
          for (long P = B.first; P < B.last; ++P)
            if (critical(P))
              {
                mark_family(node_at(P));
                mark_family(node_at(P + o));
              }
        }
      return any;
    }

    template <int dim>
    unsigned int
    MechanicsSolver<dim>::refine(const std::vector<std::uint8_t> &zone)
    {
      const Lattice &C = grids[coarse], &F = grids[fine];
      // Current values of the inactive coarse nodes that are sources of
      // the new fine nodes (the corners of the coarse lattice cells holding
      // them: within one coarse cell of the zone) from the fine nodes
      // around them.
      std::vector<std::uint8_t> source(C.n_nodes, 0);
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (zone[i] && !refined[i])
          {
            const auto           ix = C.index(i);
            std::array<int, dim> jx, o;
            const auto           visit = [&](auto &&self, const unsigned int d) -> void {
              if (d == dim)
                {
                  for (unsigned int e = 0; e < dim; ++e)
                    jx[e] = ix[e] + o[e];
                  if (C.inside(jx))
                    source[C.node(jx)] = 1;
                  return;
                }
              for (o[d] = -1; o[d] <= 1; ++o[d])
                self(self, d + 1);
            };
            visit(visit, 0);
          }
      std::vector<std::pair<unsigned int, double>> src;
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (refined[i] && source[i])
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
      std::vector<unsigned int> new_cells;
      const unsigned int n_children = std::pow(ratio, dim);
      std::vector<unsigned int> children(n_children);
      for (unsigned int i = 0; i < C.n_nodes; ++i)
        if (zone[i] && !refined[i])
          {
            new_cells.push_back(i);
            for (unsigned int q = 0; q < n_children; ++q)
              children[q] = child(i, q);
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
      ++u_version;
      if (!new_cells.empty())
        {
          update_node_sets(new_cells);
          for (const Grid g : {coarse, fine})
            build_box_bits(g);
        }
      return new_cells.size();
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
      // Over runs of consecutive active nodes (contiguous dim-interleaved values).
      for (const unsigned int g : {0u, 1u})
        for (const auto &[i0, n] : active_runs[g])
          {
            double *__restrict       U = u[g].data() + dim * i0;
            double *__restrict       V = v[g].data() + dim * i0;
            const double *__restrict A = a[g].data() + dim * i0;
            for (unsigned int j = 0; j < dim * n; ++j)
              {
                V[j] += h * A[j];
                U[j] += dt * V[j];
              }
          }
      compute_accelerations();
      // Prescribed nodes keep their velocity: a = 0 (v + h 0 = v).
      for (const unsigned int g : {0u, 1u})
        for (const unsigned int i : prescribed_active[g])
          for (unsigned int d = 0; d < dim; ++d)
            a[g][dim * i + d] = 0.;
      for (const unsigned int g : {0u, 1u})
        for (const auto &[i0, n] : active_runs[g])
          {
            double *__restrict       V = v[g].data() + dim * i0;
            const double *__restrict A = a[g].data() + dim * i0;
            for (unsigned int j = 0; j < dim * n; ++j)
              V[j] += h * A[j];
          }
      t += dt;
      ++n_step;
      if (prm.model == MechanicsModel::adaptive_standard ||
          prm.model == MechanicsModel::adaptive_hybrid)
        {
          double                    start = thread_cpu_seconds();
          std::vector<std::uint8_t> zone;
          const bool                critical = find_critical(zone);
          timing[2] += thread_cpu_seconds() - start;
          if (critical)
            {
              start = thread_cpu_seconds();
              if (refine(zone) > 0)
                ++switches;
              timing[3] += thread_cpu_seconds() - start;
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
          // A bond crossing the segment has its end within the bond
          // length (at most radius dx) of the segment's bounding box.
          const double reach = L.radius * L.dx;
          for (unsigned int i = 0; i < L.n_nodes; ++i)
            {
              const auto       ix = L.index(i);
              const Point<dim> xi = L.point(i);
              bool             near = true;
              for (unsigned int d = 0; d < dim; ++d)
                near = near && xi[d] >= std::min(p[d], q[d]) - reach &&
                       xi[d] <= std::max(p[d], q[d]) + reach;
              if (!near)
                continue;
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
          boxes[g].valid        = false;
          boxes[g].intact_valid = false;
          boxes[g].live_valid   = false;
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
      update_runs();
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
      p.conservative_coupling = conservative_coupling;
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
          const auto   start = std::chrono::steady_clock::now();
          const double cpu   = thread_cpu_seconds();
          s.advance();
          r.cpu_seconds += thread_cpu_seconds() - cpu;
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
