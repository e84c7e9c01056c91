#include <perideal/base/exceptions.h>
#include <perideal/models/hybrid_bond_based.h>
#include <perideal/models/lattice_sweep_kernel.h>

#include <algorithm>
#include <ctime>
#include <immintrin.h>
#include <complex>
#include <map>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>
#include <sstream>

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
#  define PERIDEAL_HYBRID_SWEEP 1
#endif

namespace PeriDEAL
{
  namespace
  {
    /** CPU time of this thread [s] (the machine may be shared: no wall time). */
    double
    cpu_seconds()
    {
      timespec t;
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
      return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
    }

    /**
     * |p_j - p_i|^2 of a bond, the same expression in every kernel below
     * (y_0^2, then fused multiply-adds) so that the two copies of a bond,
     * on one rank or two, and the switching test and the force see bitwise
     * the same value.
     */
    template <int dim>
    inline double
    length2(const double *pj, const double *pi)
    {
      double l2 = (pj[0] - pi[0]) * (pj[0] - pi[0]);
      for (unsigned int d = 1; d < dim; ++d)
        l2 = std::fma(pj[d] - pi[d], pj[d] - pi[d], l2);
      return l2;
    }

    /**
     * Standard row (3.1) of the PMB force, portable: f = sum k (l - r) y / l
     * over the unbroken bonds; bonds with l - r > s0 r break (flag set, no
     * force). Returns the number of bonds broken now.
     */
    template <int dim>
    unsigned int
    pmb_row(const double       *p,
            const double       *pi,
            const std::int32_t *col,
            const double       *k,
            const double       *r,
            std::uint8_t       *br,
            const unsigned int  n,
            const double        s0,
            double             *f)
    {
      unsigned int n_break = 0;
      for (unsigned int b = 0; b < n; ++b)
        {
          if (br[b])
            continue;
          const double *pj = p + std::size_t(dim) * col[b];
          const double  l  = std::sqrt(length2<dim>(pj, pi));
          const double  dl = l - r[b];
          if (dl > s0 * r[b])
            {
              br[b] = 1;
              ++n_break;
              continue;
            }
          const double scale = k[b] * dl / l;
          for (unsigned int d = 0; d < dim; ++d)
            f[d] += scale * (pj[d] - pi[d]);
        }
      return n_break;
    }

    /** Most bond length classes of the amortized switching test. */
    constexpr unsigned int max_classes = 2;

    /**
     * Exact switching test of one Omega_w row, portable: the number of
     * unbroken bonds b with |y|^2 >= L2[b], and in @p q[k] the maximum of
     * |y|^2 / L2[b] = |y|^2 * iL2[b] over those of length class k, i.e.
     * r[b] <= bound[k] and (k = 0 or r[b] > bound[k - 1]) (0 if none).
     */
    template <int dim>
    unsigned int
    test_row(const double       *p,
             const double       *pi,
             const std::int32_t *col,
             const double       *L2,
             const double       *iL2,
             const double       *r,
             const double       *bound,
             const unsigned int  n_classes,
             const std::uint8_t *br,
             const unsigned int  n,
             double             *q)
    {
      unsigned int count = 0;
      for (unsigned int k = 0; k < n_classes; ++k)
        q[k] = 0.;
      for (unsigned int b = 0; b < n; ++b)
        if (br[b] == 0)
          {
            const double l2 = length2<dim>(p + std::size_t(dim) * col[b], pi);
            count += l2 >= L2[b];
            unsigned int k = 0;
            while (k + 1 < n_classes && r[b] > bound[k])
              ++k;
            q[k] = std::max(q[k], l2 * iL2[b]);
          }
      return count;
    }

#ifdef PERIDEAL_HYBRID_SWEEP
    /**
     * y = p(L + o) - p(L) of the eight positions L0..L0+7 (dim arrays of
     * stride N) and l2 = |y|^2 by the expression of length2().
     */
    template <int dim>
    inline __m512d
    lane_bonds(const double *p, const std::size_t N, const std::size_t L0, const std::int64_t o,
               const __m512d *pi, __m512d *y)
    {
      for (unsigned int d = 0; d < dim; ++d)
        y[d] = _mm512_sub_pd(_mm512_loadu_pd(p + d * N + L0 + o), pi[d]);
      __m512d l2 = _mm512_mul_pd(y[0], y[0]);
      for (unsigned int d = 1; d < dim; ++d)
        l2 = _mm512_fmadd_pd(y[d], y[d], l2);
      return l2;
    }

    /**
     * force[d] at the nodes of the @p lanes of the eight box positions from
     * @p L0 (node: the node of each box position) = value[d] of the lane.
     */
    template <int dim, typename VectorField>
    inline void
    store_lane_forces(VectorField &force, const std::int32_t *node, const std::size_t L0,
                      const unsigned int lanes, const __m512d *value)
    {
      // Eight consecutive nodes (box rows numbered in lattice order,
      // LatticeParameters::lattice_order): one masked store per dimension,
      // the same values at the same nodes. Aligned L0 only: node has
      // whole vectors of eight positions (unaligned Omega_s runs may end
      // at its last entry).
      const std::int32_t n0 = node[L0];
      if (L0 % 8 == 0 && n0 >= 0)
        {
          const __m256i nodes = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(node + L0));
          const __m256i run   = _mm256_add_epi32(_mm256_set1_epi32(n0), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
          if (_mm256_cmpeq_epi32_mask(nodes, run) == 0xff)
            {
              for (unsigned int d = 0; d < dim; ++d)
                _mm512_mask_storeu_pd(force[d].begin() + n0, __mmask8(lanes), value[d]);
              return;
            }
        }
      alignas(64) double out[dim][8];
      for (unsigned int d = 0; d < dim; ++d)
        _mm512_store_pd(out[d], value[d]);
      for (unsigned int l = 0; l < 8; ++l)
        if ((lanes >> l) & 1u)
          for (unsigned int d = 0; d < dim; ++d)
            force[d].local_element(node[L0 + l]) = out[d][l];
    }

    /** The operations of the exact switching test on W = 8 (512-bit) or 4 (256-bit) lanes. */
    template <int W>
    struct LaneVector;
    template <>
    struct LaneVector<8>
    {
      using type = __m512d;
    };
    template <>
    struct LaneVector<4>
    {
      using type = __m256d;
    };
    template <int W>
    struct Lanes
    {
      static constexpr bool wide = W == 8;
      using V                    = typename LaneVector<W>::type;
      static V load(const double *a)
      {
        if constexpr (wide)
          return _mm512_loadu_pd(a);
        else
          return _mm256_loadu_pd(a);
      }
      static V sub(const V a, const V b)
      {
        if constexpr (wide)
          return _mm512_sub_pd(a, b);
        else
          return _mm256_sub_pd(a, b);
      }
      static V mul(const V a, const V b)
      {
        if constexpr (wide)
          return _mm512_mul_pd(a, b);
        else
          return _mm256_mul_pd(a, b);
      }
      static V fmadd(const V a, const V b, const V c)
      {
        if constexpr (wide)
          return _mm512_fmadd_pd(a, b, c);
        else
          return _mm256_fmadd_pd(a, b, c);
      }
      static V max(const V a, const V b)
      {
        if constexpr (wide)
          return _mm512_max_pd(a, b);
        else
          return _mm256_max_pd(a, b);
      }
      /** q where m is 0, max(q, x) where it is 1. */
      static V mask_max(const V q, const __mmask8 m, const V x)
      {
        if constexpr (wide)
          return _mm512_mask_max_pd(q, m, q, x);
        else
          return _mm256_mask_max_pd(q, m, q, x);
      }
      static V set1(const double a)
      {
        if constexpr (wide)
          return _mm512_set1_pd(a);
        else
          return _mm256_set1_pd(a);
      }
    };

    /**
     * The exact switching test's q = max |y|^2 / T^2 = max |y|^2 iL2[f]
     * over the offsets grp[0, n_g) of the W lanes at box position L (0 in a
     * lane without an alive bond), y = p(L + o_f) - p(L), |y|^2 by the
     * expression of length2() (the same bits at either width). A bond is
     * alive in the lanes of (bits[f] >> shift) & lanes; @p grp null: all
     * offsets f < n_g in order (no indirection through the table). Four independent
     * maxima in named registers, unrolled by hand (one chain is latency
     * bound; with qm[g % 4] GCC kept the maxima on the stack); the maximum
     * is exact, so the grouping does not change q.
     */
    template <int dim, int W, bool all>
    inline typename Lanes<W>::V
    max_ratio(const double *p, const std::size_t N, const std::size_t L, const std::int64_t *offset,
              const double *iL2, const std::uint8_t *bits, const unsigned int shift,
              const __mmask8 lanes, const unsigned int *grp, const unsigned int n_g)
    {
      using S = Lanes<W>;
      typename S::V pi[dim];
      for (unsigned int d = 0; d < dim; ++d)
        pi[d] = S::load(p + d * N + L);
      const auto step = [&](typename S::V &q, const unsigned int g) {
        const unsigned int f = all ? g : grp[g];
        const __mmask8 alive = __mmask8((bits[f] >> shift) & lanes);
        typename S::V  y     = S::sub(S::load(p + L + offset[f]), pi[0]);
        typename S::V  l2    = S::mul(y, y);
        for (unsigned int d = 1; d < dim; ++d)
          {
            y  = S::sub(S::load(p + d * N + L + offset[f]), pi[d]);
            l2 = S::fmadd(y, y, l2);
          }
        q = S::mask_max(q, alive, S::mul(l2, S::set1(iL2[f])));
      };
      typename S::V q0 = S::set1(0.), q1 = q0, q2 = q0, q3 = q0;
      unsigned int  g  = 0;
      for (; g + 4 <= n_g; g += 4)
        {
          step(q0, g);
          step(q1, g + 1);
          step(q2, g + 2);
          step(q3, g + 3);
        }
      for (; g < n_g; ++g)
        step(q0, g);
      return S::max(S::max(q0, q1), S::max(q2, q3));
    }

    /**
     * max_ratio() of W lanes whose bonds at every offset are alive, in the
     * @p lanes kept (0 in the others): per group g of the offsets of one
     * 1 / T^2 (iL2[g]; offset[start[g], start[g + 1]), none empty) the
     * maximum of |y|^2, times iL2[g]. The same q bit for bit: x -> fl(x c)
     * is monotone for c > 0, so fl(max x c) = max fl(x c), and a maximum is
     * exact in any order. No lane masks and one multiplication per group
     * instead of one per offset (KW dx = 0.25: 0.88 x the cycles of
     * max_ratio(), the same q in 4.4 M of 4.4 M calls).
     */
    template <int dim, int W>
    inline typename Lanes<W>::V
    max_ratio_grouped(const double *p, const std::size_t N, const std::size_t L,
                      const std::int64_t *offset, const std::uint32_t *start, const double *iL2,
                      const unsigned int n_groups, const __mmask8 lanes)
    {
      using S = Lanes<W>;
      typename S::V pi[dim];
      for (unsigned int d = 0; d < dim; ++d)
        pi[d] = S::load(p + d * N + L);
      const auto l2_of = [&](const std::int64_t o) {
        typename S::V y  = S::sub(S::load(p + L + o), pi[0]);
        typename S::V l2 = S::mul(y, y);
        for (unsigned int d = 1; d < dim; ++d)
          {
            y  = S::sub(S::load(p + d * N + L + o), pi[d]);
            l2 = S::fmadd(y, y, l2);
          }
        return l2;
      };
      typename S::V q0 = S::set1(0.), q1 = q0;
      for (unsigned int g = 0; g < n_groups; ++g)
        {
          // Two maxima per group (one chain is latency bound).
          unsigned int       f = start[g];
          const unsigned int e = start[g + 1];
          typename S::V m0 = l2_of(offset[f]), m1 = m0;
          for (++f; f + 2 <= e; f += 2)
            {
              m0 = S::max(m0, l2_of(offset[f]));
              m1 = S::max(m1, l2_of(offset[f + 1]));
            }
          if (f < e)
            m0 = S::max(m0, l2_of(offset[f]));
          const typename S::V x = S::mul(S::max(m0, m1), S::set1(iL2[g]));
          if (g % 2 == 0)
            q0 = S::max(q0, x);
          else
            q1 = S::max(q1, x);
        }
      const typename S::V q = S::max(q0, q1);
      if constexpr (S::wide)
        return _mm512_maskz_mov_pd(lanes, q);
      else
        return _mm256_maskz_mov_pd(lanes, q);
    }

    /** f(integral_constant<int, A>) for each A, in order. */
    template <typename F, int... A>
    inline void
    for_each_column(const F &f, std::integer_sequence<int, A...>)
    {
      (f(std::integral_constant<int, A>()), ...);
    }

    /** Lanes r, ..., r + W - 1 of the concatenation (lo, hi) (valignq). */
    template <int W, int r>
    inline typename Lanes<W>::V
    shifted(const typename Lanes<W>::V lo, const typename Lanes<W>::V hi)
    {
      if constexpr (r == 0)
        return lo;
      else if constexpr (W == 8)
        return _mm512_castsi512_pd(
          _mm512_alignr_epi64(_mm512_castpd_si512(hi), _mm512_castpd_si512(lo), r));
      else
        return _mm256_castsi256_pd(
          _mm256_alignr_epi64(_mm256_castpd_si256(hi), _mm256_castpd_si256(lo), r));
    }

    /**
     * max_ratio_grouped() in 2D (stencil radius <= 8) by stencil rows: per
     * pair of rows +-b (box row stride @p row) the vectors at L +- b row +
     * W j, |j| <= 8 / W, are loaded once per dimension, and each offset's
     * lanes are shifted out of two of them (valignq) instead of two
     * unaligned loads per offset (the kernel was bound by its loads). The
     * up to four offsets (+-a, +-b) of one length share one multiplication
     * by 1 / T^2 (row_iL2[9 b + a]; bit a of row_mask[b]: (a, b) is an
     * offset). The same q bit for bit, for the reasons of
     * max_ratio_grouped(); |y|^2 by the same expression.
     */
    template <int W>
    inline typename Lanes<W>::V
    max_ratio_rows(const double *p, const std::size_t N, const std::size_t L,
                   const std::int64_t row, const std::uint16_t *row_mask,
                   const double *row_iL2, const unsigned int n_rows, const __mmask8 lanes)
    {
      using S             = Lanes<W>;
      using V             = typename S::V;
      constexpr int J     = 8 / W;
      const V       pi0   = S::load(p + L), pi1 = S::load(p + N + L);
      const auto    l2_of = [&](const V y0, const V y1) {
        const V a  = S::sub(y0, pi0);
        V       l2 = S::mul(a, a);
        const V b  = S::sub(y1, pi1);
        return S::fmadd(b, b, l2);
      };
      V q0 = S::set1(0.), q1 = q0;
      // One stencil row pair (both rows if two): v[s][d][j + J] is
      // dimension d of the vector at L + (s ? -b : b) row + W j.
      const auto rows = [&](const unsigned int b, const unsigned int mask, const auto two) {
        constexpr unsigned int ns = decltype(two)::value ? 2 : 1;
        V                      v[ns][2][2 * J + 1];
        const bool             side = mask > 1u;
        for (unsigned int s = 0; s < ns; ++s)
          for (unsigned int d = 0; d < 2; ++d)
            {
              const double *base = p + d * N + L + (s ? -std::int64_t(b) : std::int64_t(b)) * row;
              for (int j = -J; j <= J; ++j)
                v[s][d][j + J] = j == 0 || side ? S::load(base + W * j) : S::set1(0.);
            }
        const double *iL2 = row_iL2 + 9 * b;
        // Offset x-component a (compile time): its lanes in row s.
        const auto at = [&](const unsigned int s, const auto A) {
          constexpr int a = decltype(A)::value;
          constexpr int j = a >= 0 ? a / W : -((-a + W - 1) / W);
          constexpr int r = a - W * j;
          V             y[2];
          for (unsigned int d = 0; d < 2; ++d)
            {
              if constexpr (r == 0)
                y[d] = v[s][d][j + J];
              else
                y[d] = shifted<W, r>(v[s][d][j + J], v[s][d][j + J + 1]);
            }
          return l2_of(y[0], y[1]);
        };
        const auto column = [&](const auto A) {
          constexpr int a = decltype(A)::value;
          if (((mask >> a) & 1u) == 0)
            return;
          V m = at(0, std::integral_constant<int, a>());
          if constexpr (a > 0)
            m = S::max(m, at(0, std::integral_constant<int, -a>()));
          if constexpr (ns == 2)
            {
              m = S::max(m, at(1, std::integral_constant<int, a>()));
              if constexpr (a > 0)
                m = S::max(m, at(1, std::integral_constant<int, -a>()));
            }
          const V x = S::mul(m, S::set1(iL2[a]));
          if constexpr (a % 2 == 0)
            q0 = S::max(q0, x);
          else
            q1 = S::max(q1, x);
        };
        for_each_column(column, std::make_integer_sequence<int, 9>());
      };
      if (row_mask[0] != 0)
        rows(0, row_mask[0], std::false_type());
      for (unsigned int b = 1; b < n_rows; ++b)
        if (row_mask[b] != 0)
          rows(b, row_mask[b], std::true_type());
      // max(q0, q1) in the lanes kept, 0 elsewhere (the zero-masked form:
      // GCC 12 warns falsely about the unmasked intrinsic's undefined
      // pass-through operand here).
      if constexpr (S::wide)
        return _mm512_maskz_max_pd(lanes, q0, q1);
      else
        return _mm256_maskz_max_pd(lanes, q0, q1);
    }
#endif
  } // namespace

  template <int dim>
  HybridBondBasedModel<dim>::HybridBondBasedModel(BondBasedOperator<dim>          &op,
                                                  const InfluenceFunction          omega,
                                                  const HybridMechanicsParameters &parameters,
                                                  const std::vector<bool>         &standard)
    : op(op)
    , disc(op.discretization())
    , prm(parameters)
    , s0(op.critical_stretch())
    , broken_flag(op.broken())
  {
    check_parameter(!op.is_linearized(), "Model/Bond-based/Linearized", "true",
                    "false for the adaptive hybrid configuration (its Omega_s rows are the "
                    "nonlinear PMB force with breaking)");
    check_parameter(prm.sigma > 0. && prm.sigma < 1., "Hybrid/Sigma", prm.sigma,
                    "a number in (0, 1)");
    check_parameter(prm.check_interval >= 1, "Hybrid/Switching interval", prm.check_interval,
                    "an integer >= 1");
    AssertThrow(standard.size() == disc.n_owned(),
                ExcMessage("One Omega_s flag per owned node is needed."));

    disc.initialize_vector(wls_flag);
    disc.initialize_vector(critical);
    std::vector<unsigned int> rows;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (!standard[i] && disc.region[i] == Discretization<dim>::interior)
        {
          wls_flag.local_element(i) = 1.;
          rows.push_back(i);
        }
    wls_flag.update_ghost_values();
    wls = std::make_unique<WlsQuadrature<dim>>(prm.wls, op.micromodulus(),
                                               omega,
                                               disc.parameters().delta);
    wls->build(disc, rows);
    wls_row.assign(disc.n_owned(), -1);
    for (unsigned int k = 0; k < rows.size(); ++k)
      wls_row[rows[k]] = int(k);
    if constexpr (dim == 2)
      {
        packed_start.assign(1, 0);
        for (unsigned int k = 0; k < rows.size(); ++k)
          {
            const auto begin = wls->row_start[k], n = wls->row_start[k + 1] - begin;
            const auto n_chunks = (n + 7) / 8;
            for (std::uint64_t c = 0; c < n_chunks; ++c)
              for (unsigned int l = 0; l < 8; ++l)
                {
                  const std::uint64_t e = begin + 8 * c + l;
                  packed_col.push_back(e < begin + n ? wls->col[e] : wls->col[begin]);
                }
            const auto w0 = packed_weight.size();
            packed_weight.resize(w0 + 32 * n_chunks, 0.);
            for (std::uint64_t e = 0; e < n; ++e)
              for (unsigned int ab = 0; ab < 4; ++ab)
                packed_weight[w0 + 32 * (e / 8) + 8 * ab + e % 8] = wls->weight[4 * (begin + e) + ab];
            packed_start.push_back(packed_start.back() + n_chunks);
          }
      }

    // Squared thresholds per bond table entry: (3.80) and breaking (2.34)
    // compare |y|^2 with them, without a square root.
    const auto &nb = disc.neighborhood;
    critical_length2.resize(nb.bond_length.size());
    breaking_length2.resize(nb.bond_length.size());
    inverse_critical_length2.resize(nb.bond_length.size());
    double r_min = std::numeric_limits<double>::max(), r_max = 0.;
    const double s0_finite = std::isfinite(s0) ? s0 : std::numeric_limits<double>::max() / 4.;
    for (std::size_t t = 0; t < nb.bond_length.size(); ++t)
      {
        const double r = nb.bond_length[t];
        critical_length2[t] = std::isfinite(s0) ? std::pow(r * (1. + prm.sigma * s0), 2) :
                                                  std::numeric_limits<double>::infinity();
        breaking_length2[t] = std::isfinite(s0) ? std::pow(r * (1. + s0_finite), 2) :
                                                  std::numeric_limits<double>::infinity();
        inverse_critical_length2[t] = 1. / critical_length2[t];
        r_min = std::min(r_min, r);
        r_max = std::max(r_max, r);
      }
    // The amortized test (see the class documentation): the slack of a node
    // is (1 - sqrt(q)) min_b T_b minus a round-off margin: positions
    // x - x_c + u carry errors ~1e-16 of the lattice extent, squared
    // lengths and their ratios ~1e-16 relative; 1e-9 T_min + 1e-13 extent
    // exceeds both by orders of magnitude and costs nothing measurable.
    double extent = 0.;
    for (unsigned int d = 0; d < dim; ++d)
      extent = std::max(extent, disc.lattice_size()[d] * disc.parameters().dx);
    const double stretch = 1. + (std::isfinite(s0) ? prm.sigma * s0 : 0.);
    threshold_margin     = 1e-9 * r_min * stretch + 1e-13 * extent;
    // Length classes (r_min 4^k, r_min 4^(k+1)]: each class costs one
    // StretchBudget::advance() per test, a finer split fewer exact bond
    // tests. KW at m = 8 (kw_hybrid_benchmark, dx = 0.25 and 0.5): two
    // classes split at 4 r_min spend 20-25 % less CPU time in the switching
    // test than three split at 2 r_min and 4 r_min, or one.
    for (unsigned int k = 0; k < max_classes && (k == 0 || class_bound.back() < r_max); ++k)
      class_bound.push_back(k + 1 < max_classes ? r_min * std::pow(4., k + 1) * (1. + 1e-9) :
                                                  std::numeric_limits<double>::max());
    class_bound.back() = std::numeric_limits<double>::max();
    min_threshold.assign(class_bound.size(), std::numeric_limits<double>::max());
    std::vector<double> reach(class_bound.size(), 0.);
    for (const double r : nb.bond_length)
      {
        unsigned int k = 0;
        while (k + 1 < class_bound.size() && r > class_bound[k])
          ++k;
        min_threshold[k] = std::min(min_threshold[k], r * stretch);
        reach[k]         = std::max(reach[k], r);
      }
    budget.resize(class_bound.size());
    for (unsigned int k = 0; k < budget.size(); ++k)
      budget[k].reinit(disc.position, disc.n_owned(), std::max(reach[k], r_min));
    switched_at.assign(disc.n_owned(), -1);
    setup_lattice_sweep();
    update_row_lists();
  }

  template <int dim>
  unsigned int
  HybridBondBasedModel<dim>::box_index(const unsigned int i, const std::uint64_t b) const
  {
    const auto  &li = disc.lattice_index[i];
    const auto  &lj = disc.lattice_index[disc.neighborhood.col[b]];
    const int    W  = 2 * box_radius + 1;
    unsigned int index = 0, stride = 1;
    for (unsigned int d = 0; d < dim; ++d)
      {
        index += (lj[d] - li[d] + box_radius) * stride;
        stride *= W;
      }
    return index;
  }

  template <int dim>
  std::uint64_t
  HybridBondBasedModel<dim>::find_bond(const unsigned int i, const unsigned int q) const
  {
    // Rows list their bonds in increasing box index (the lattice stencil
    // order); a linear scan if not.
    const auto   &nb = disc.neighborhood;
    std::uint64_t lo = nb.row_start[i], hi = nb.row_start[i + 1];
    while (lo < hi)
      {
        const std::uint64_t mid = (lo + hi) / 2;
        if (box_index(i, mid) < q)
          lo = mid + 1;
        else
          hi = mid;
      }
    if (lo < nb.row_start[i + 1] && box_index(i, lo) == q)
      return lo;
    for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
      if (box_index(i, b) == q)
        return b;
    AssertThrow(false, ExcInternalError("A bond of the lattice sweep is missing in its row."));
    return 0;
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::setup_lattice_sweep()
  {
    sweep_on = false;
#ifdef PERIDEAL_HYBRID_SWEEP
    // Every rank decides (the shared pattern below is collective).
    std::int64_t n_box    = 1;
    const bool   local_ok = [&]() -> bool {
      const auto        &nb      = disc.neighborhood;
      const std::size_t  n_local = disc.position.size();
      const unsigned int n_owned = disc.n_owned();
      if (dim == 1 || n_owned == 0 || disc.lattice_index.size() != n_local)
        return false;
      box_radius = 0;
      for (unsigned int i = 0; i < n_owned; ++i)
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
          for (unsigned int d = 0; d < dim; ++d)
            box_radius = std::max(box_radius, std::abs(disc.lattice_index[nb.col[b]][d] -
                                                       disc.lattice_index[i][d]));
      std::array<int, dim> upper;
      for (unsigned int d = 0; d < dim; ++d)
        {
          sweep_lower[d] = std::numeric_limits<int>::max();
          upper[d]       = std::numeric_limits<int>::min();
        }
      for (const auto &li : disc.lattice_index)
        for (unsigned int d = 0; d < dim; ++d)
          {
            sweep_lower[d] = std::min(sweep_lower[d], li[d]);
            upper[d]       = std::max(upper[d], li[d]);
          }
      // The box starts at a multiple of 8 of the global lattice in x and
      // its x extent is a multiple of 8: the vectors of eight positions are
      // the same blocks of a lattice row on every rank (the half-stencil
      // sweep relies on it; the other kernels do not depend on the box).
      sweep_lower[0] -= ((sweep_lower[0] % 8) + 8) % 8;
      for (unsigned int d = 0; d < dim; ++d)
        {
          sweep_stride[d] = n_box;
          n_box *= d == 0 ? 8 * ((upper[d] - sweep_lower[d] + 8) / 8) : upper[d] - sweep_lower[d] + 1;
        }
      if (n_box > 8 * std::int64_t(n_local) + 4096 || n_box > (std::int64_t(1) << 30))
        return false;
      const int          W   = 2 * box_radius + 1;
      const unsigned int n_q = std::pow(W, dim);
      const auto linear = [&](unsigned int q) {
        std::int64_t o = 0;
        for (unsigned int d = 0; d < dim; ++d, q /= W)
          o += std::int64_t(int(q % W) - box_radius) * sweep_stride[d];
        return o;
      };
      // The full offsets that occur, each with one stiffness and length (else
      // no sweep); the mirror of each too (its bits are cleared on breaking).
      sweep_of_box.assign(n_q, -1);
      sweep_offset.clear();
      sweep_box.clear();
      sweep_k.clear();
      sweep_r.clear();
      const double *coef = op.bond_coefficients().data();
      const auto    add  = [&](const unsigned int q, const double k, const double r) {
        sweep_of_box[q] = sweep_offset.size();
        sweep_offset.push_back(linear(q));
        sweep_box.push_back(q);
        sweep_k.push_back(k);
        sweep_r.push_back(r);
      };
      bool table_checked = false;
      for (unsigned int i = 0; i < n_owned; ++i)
        {
          const std::uint64_t begin = nb.row_start[i], n = nb.row_start[i + 1] - begin;
          const bool          regular = nb.table_start[i] == 0 && n == nb.stencil_size;
          if (regular && table_checked)
            continue;
          for (std::uint64_t e = 0; e < n; ++e)
            {
              const unsigned int  q = box_index(i, begin + e);
              const std::uint64_t t = nb.table_start[i] + e;
              if (sweep_of_box[q] < 0)
                add(q, coef[t], nb.bond_length[t]);
              else if (sweep_k[sweep_of_box[q]] != coef[t] || sweep_r[sweep_of_box[q]] != nb.bond_length[t])
                return false;
            }
          table_checked = table_checked || regular;
        }
      for (unsigned int f = 0, n = sweep_offset.size(); f < n; ++f)
        if (sweep_of_box[n_q - 1 - sweep_box[f]] < 0)
          add(n_q - 1 - sweep_box[f], sweep_k[f], sweep_r[f]);
      // A row sums its bonds in the order of the offsets: the box index order
      // (the same on every rank).
      {
        std::vector<unsigned int> order(sweep_offset.size());
        for (unsigned int f = 0; f < order.size(); ++f)
          order[f] = f;
        std::sort(order.begin(), order.end(),
                  [&](const unsigned int a, const unsigned int b) { return sweep_box[a] < sweep_box[b]; });
        const auto permute = [&](auto &v) {
          auto w = v;
          for (unsigned int f = 0; f < order.size(); ++f)
            v[f] = w[order[f]];
        };
        permute(sweep_offset);
        permute(sweep_box);
        permute(sweep_k);
        permute(sweep_r);
        for (unsigned int f = 0; f < sweep_box.size(); ++f)
          sweep_of_box[sweep_box[f]] = f;
      }
      const unsigned int n_f = sweep_offset.size();
      sweep_mirror.resize(n_f);
      sweep_L2.resize(n_f);
      sweep_iL2.resize(n_f);
      sweep_B2.resize(n_f);
      sweep_class.resize(n_f);
      sweep_kr.resize(n_f);
      sweep_t2.resize(n_f);
      for (unsigned int f = 0; f < n_f; ++f)
        {
          internal::LatticeSweep::pmb_offset_constants(sweep_r[f], sweep_k[f], s0, sweep_kr[f], sweep_t2[f]);
          sweep_mirror[f] = sweep_of_box[n_q - 1 - sweep_box[f]];
          // The thresholds of the CSR tables (the same expressions of r).
          const double r = sweep_r[f];
          sweep_L2[f]    = std::isfinite(s0) ? std::pow(r * (1. + prm.sigma * s0), 2) :
                                               std::numeric_limits<double>::infinity();
          sweep_B2[f]    = std::isfinite(s0) ? std::pow(r * (1. + s0), 2) :
                                               std::numeric_limits<double>::infinity();
          sweep_iL2[f]   = 1. / sweep_L2[f];
          unsigned int k = 0;
          while (k + 1 < class_bound.size() && r > class_bound[k])
            ++k;
          sweep_class[f] = k;
        }
      class_offsets.assign(class_bound.size(), {});
      for (unsigned int f = 0; f < n_f; ++f)
        class_offsets[sweep_class[f]].push_back(f);
      return true;
    }();
    if (Utilities::MPI::min(int(local_ok), disc.get_mpi_communicator()) == 0)
      return;
    setup_shared_pattern();

    std::int64_t reach = 8;
    for (const auto o : sweep_offset)
      reach = std::max(reach, std::abs(o));
    for (const auto o : shared_offset)
      reach = std::max(reach, std::abs(o));
    // One vector more than the reach: the row-shared exact test
    // (max_ratio_rows()) loads whole vectors around a stencil row.
    sweep_pad       = 8 * std::size_t((reach + 8 + 7) / 8);
    sweep_n_vectors = (n_box + 7) / 8;
    sweep_n_alloc   = 2 * sweep_pad + 8 * sweep_n_vectors + 8;
    internal::LatticeSweep::map_box_positions<dim>(
      disc.lattice_index, sweep_lower, sweep_stride, 8 * sweep_n_vectors, sweep_position, sweep_node);
    sweep_p.assign(dim * sweep_n_alloc, 0.);
    sweep_u.assign(dim * sweep_n_alloc, 0.);
    sweep_live_valid = false;
    // x - x_c over the box once (p = (x - x_c) + u per step, bitwise the
    // value of the row loops), and the runs of consecutive nodes at
    // consecutive box positions, so that the per-step copy of u into the box
    // is a few contiguous (vectorized) loops instead of a scatter that
    // re-reads the positions (2.4 of the 5.4 s of the switching test's
    // timer at KW dx = 0.25 were that scatter).
    {
      const Point<dim> xc = op.deformation_origin();
      sweep_x0.assign(dim * sweep_n_alloc, 0.);
      const std::size_t N = sweep_n_alloc;
      for (std::size_t i = 0; i < disc.position.size(); ++i)
        for (unsigned int d = 0; d < dim; ++d)
          sweep_x0[sweep_pad + d * N + sweep_position[i]] = disc.position[i][d] - xc[d];
      fill_runs.clear();
      for (std::uint32_t i = 0; i < disc.position.size(); ++i)
        if (i > 0 && sweep_position[i] == sweep_position[i - 1] + 1)
          ++fill_runs.back()[2];
        else
          fill_runs.push_back({{i, sweep_position[i], 1}});
      // The rows of the stencil: p is read in [L0 + ro - R, L0 + ro + R + 8).
      const int W = 2 * box_radius + 1;
      p_row_offsets.assign(1, 0);
      for (unsigned int f = 0; f < sweep_offset.size(); ++f)
        p_row_offsets.push_back(sweep_offset[f] - (int(sweep_box[f] % W) - box_radius));
      std::sort(p_row_offsets.begin(), p_row_offsets.end());
      p_row_offsets.erase(std::unique(p_row_offsets.begin(), p_row_offsets.end()), p_row_offsets.end());
      p_stamp.assign((8 * sweep_n_vectors + p_chunk - 1) / p_chunk, 0);
      p_epoch = 0;
    }
    sweep_on         = true;
    half_on          = dim == 2 && prm.half_stencil;
    // The positive offsets by x offset, then y offset: consecutive ones lie
    // a lattice row or more apart, so that the reaction update of one does
    // not partially overlap the previous one's (no store forwarding).
    half_offsets.clear();
    for (unsigned int f = 0; f < sweep_offset.size(); ++f)
      if (sweep_offset[f] > 0)
        half_offsets.push_back(f);
    {
      const int W = 2 * box_radius + 1;
      std::stable_sort(half_offsets.begin(), half_offsets.end(),
                       [&](const unsigned int a, const unsigned int b) {
                         return sweep_box[a] % W < sweep_box[b] % W;
                       });
    }
    half_slot.assign(sweep_offset.size(), -1);
    half_o.resize(half_offsets.size());
    half_constants.resize(half_offsets.size());
    for (unsigned int h = 0; h < half_offsets.size(); ++h)
      {
        const unsigned int g = half_offsets[h];
        half_slot[g]         = h;
        half_o[h]            = sweep_offset[g];
        half_constants[h]    = {{sweep_k[g], sweep_kr[g], sweep_t2[g]}};
      }
    if (half_on)
      {
        half_reaction.assign(dim * sweep_n_alloc, 0.);
        half_acc.assign(dim * sweep_n_alloc, 0.);
      }

    all_offsets.resize(sweep_offset.size());
    for (unsigned int f = 0; f < all_offsets.size(); ++f)
      all_offsets[f] = f;
    lattice_bound_on = false;
    grouped_on       = false;
    rows_on          = false;
    if constexpr (dim == 2)
      if (prm.switching_bound && prm.lattice_bound && std::isfinite(s0))
        {
          // Lattice spacings h_d and c = max_f |(a h_x, b h_y)| / r_f (the
          // offsets' Euclidean lengths against their bond lengths, 1 up to
          // round-off; rounded up).
          std::array<int, dim> zero{}, unit{};
          std::array<double, dim> h;
          for (unsigned int d = 0; d < dim; ++d)
            {
              unit    = zero;
              unit[d] = 1;
              h[d]    = disc.lattice_point(unit).distance(disc.lattice_point(zero));
            }
          const int W = 2 * box_radius + 1;
          double    c = 0.;
          for (unsigned int f = 0; f < sweep_offset.size(); ++f)
            {
              double       len2 = 0.;
              unsigned int q    = sweep_box[f];
              for (unsigned int d = 0; d < dim; ++d, q /= W)
                len2 += std::pow((int(q % W) - box_radius) * h[d], 2);
              c = std::max(c, std::sqrt(len2) / sweep_r[f]);
            }
          c *= 1. + 1e-12;
          for (unsigned int d = 0; d < dim; ++d)
            lip_coef[d] = c * c / (h[d] * h[d]);
          double r_min = std::numeric_limits<double>::max();
          for (const double r : sweep_r)
            r_min = std::min(r_min, r);
          lip_margin = threshold_margin / r_min;
          // Float arrays over the box, padded by the reach of the windows
          // (R positions in x, R rows in y) and filled with +inf there.
          const std::size_t n8 = 8 * sweep_n_vectors;
          const std::int64_t row = sweep_stride[1];
          lip_pad = 16 * std::size_t((box_radius * (row + 1) + 31) / 16);
          lip_ex.assign(n8 + 2 * lip_pad, std::numeric_limits<float>::infinity());
          lip_ey = lip_ex;
          lip_fy = lip_ex;
          lip_prev.assign(dim * sweep_n_alloc, 0.);
          lip_remaining.assign(n8, -1.);
          // Edges (L, L + e_d) with both ends at local nodes, in the box
          // (an x-edge does not wrap to the next row).
          const std::int64_t n_row = sweep_stride[1];
          for (unsigned int d = 0; d < dim; ++d)
            {
              lip_edge_ok[d].assign(sweep_n_vectors, 0);
              const std::int64_t s = sweep_stride[d];
              for (std::size_t L = 0; L < n8; ++L)
                {
                  const bool in_box = std::int64_t(L) + s < std::int64_t(n8) &&
                                      (d == 1 || (std::int64_t(L) % n_row) + 1 < n_row);
                  if (in_box && sweep_node[L] >= 0 && sweep_node[L + s] >= 0)
                    lip_edge_ok[d][L / 8] |= std::uint8_t(1u << (L % 8));
                }
            }
          lip_have_prev    = false;
          lip_swap_pending = false;
          lattice_bound_on = true;
          // Offsets of bitwise equal 1 / T^2 (a bond length and its lattice
          // symmetries) as one group each, in box order within a group.
          grouped_on = prm.length_grouped_test;
          std::vector<unsigned int> by_length(all_offsets);
          std::stable_sort(by_length.begin(), by_length.end(),
                           [&](const unsigned int a, const unsigned int b) { return sweep_iL2[a] < sweep_iL2[b]; });
          grouped_offset.clear();
          group_start.clear();
          group_iL2.clear();
          for (const unsigned int f : by_length)
            {
              if (group_iL2.empty() || sweep_iL2[f] != group_iL2.back())
                {
                  group_start.push_back(grouped_offset.size());
                  group_iL2.push_back(sweep_iL2[f]);
                }
              grouped_offset.push_back(sweep_offset[f]);
            }
          group_start.push_back(grouped_offset.size());
          // The stencil by rows for max_ratio_rows(): every offset (a, b)
          // with |a|, |b| <= 8, and per (|a|, |b|) all its sign variants
          // with one 1 / T^2 (else the grouped kernel stays).
          rows_on = false;
          if (grouped_on && prm.row_shared_test && box_radius <= 8)
            {
              const int          W      = 2 * box_radius + 1;
              const unsigned int n_rows = box_radius + 1;
              std::vector<unsigned int> count(9 * n_rows, 0);
              row_mask.assign(n_rows, 0);
              row_iL2.assign(9 * n_rows, 0.);
              bool ok = true;
              for (unsigned int f = 0; f < sweep_offset.size(); ++f)
                {
                  const int a = int(sweep_box[f] % W) - box_radius,
                            b = int(sweep_box[f] / W % W) - box_radius;
                  const unsigned int c = 9 * std::abs(b) + std::abs(a);
                  if (count[c]++ == 0)
                    row_iL2[c] = sweep_iL2[f];
                  ok = ok && row_iL2[c] == sweep_iL2[f] && sweep_offset[f] == a + b * row;
                  row_mask[std::abs(b)] |= std::uint16_t(1u << std::abs(a));
                }
              for (unsigned int c = 0; c < count.size(); ++c)
                ok = ok && (count[c] == 0 || count[c] == (c % 9 > 0 ? 2u : 1u) * (c / 9 > 0 ? 2u : 1u));
              rows_on = ok && (row_mask[0] & 1u) == 0;
            }
        }
#endif
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::setup_shared_pattern()
  {
    // Rows with the full lattice stencil whose collocation nodes lie at the
    // same lattice offsets have the same WLS weights up to round-off (the
    // weights depend on the relative positions only). The pattern is the
    // most frequent one on the rank with most such rows, its weights those
    // of the row of lowest global id (the same weights for any partition).
    const auto        &nb = disc.neighborhood;
    constexpr unsigned c2 = dim * dim;
    shared_row.assign(disc.n_owned(), 0);
    shared_offset.clear();
    shared_lattice_offset.clear();
    shared_weight.clear();
    n_shared_rows = 0;
    const auto key_of = [&](const unsigned int k) {
      std::vector<int> key;
      const unsigned int i = wls->node[k];
      for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
        for (unsigned int d = 0; d < dim; ++d)
          key.push_back(disc.lattice_index[wls->col[e]][d] - disc.lattice_index[i][d]);
      return key;
    };
    const auto regular = [&](const unsigned int i) {
      return nb.table_start[i] == 0 && nb.row_start[i + 1] - nb.row_start[i] == nb.stencil_size;
    };
    std::map<std::vector<int>, unsigned int> count;
    for (unsigned int k = 0; k < wls->node.size(); ++k)
      if (regular(wls->node[k]))
        ++count[key_of(k)];
    std::vector<int> key;
    unsigned int     best = 0;
    for (const auto &[kk, n] : count)
      if (n > best)
        {
          best = n;
          key  = kk;
        }
    const MPI_Comm comm = disc.get_mpi_communicator();
    const auto     all  = Utilities::MPI::all_gather(comm, best);
    const unsigned int root = std::max_element(all.begin(), all.end()) - all.begin();
    if (all[root] == 0)
      return;
    key = Utilities::MPI::broadcast(comm, key, root);
    // The row of lowest id with that key, over all ranks.
    types::particle_index my_id = std::numeric_limits<types::particle_index>::max();
    unsigned int          my_row = 0;
    for (unsigned int k = 0; k < wls->node.size(); ++k)
      if (regular(wls->node[k]) && disc.id[wls->node[k]] < my_id && key_of(k) == key)
        {
          my_id  = disc.id[wls->node[k]];
          my_row = k;
        }
    const auto ids   = Utilities::MPI::all_gather(comm, my_id);
    const unsigned int owner = std::min_element(ids.begin(), ids.end()) - ids.begin();
    if (Utilities::MPI::this_mpi_process(comm) == owner)
      shared_weight.assign(wls->weight.begin() + c2 * wls->row_start[my_row],
                           wls->weight.begin() + c2 * wls->row_start[my_row + 1]);
    shared_weight         = Utilities::MPI::broadcast(comm, shared_weight, owner);
    shared_lattice_offset = key;
    for (std::size_t c = 0; c < key.size() / dim; ++c)
      {
        std::int64_t o = 0;
        for (unsigned int d = 0; d < dim; ++d)
          o += std::int64_t(key[dim * c + d]) * sweep_stride[d];
        shared_offset.push_back(o);
      }
    // A row uses the shared weights if its own agree to round-off (the WLS
    // fit of a row is solved to ~1e-13 relative; 1e-9 of the largest
    // weight leaves margin and still rejects any other pattern).
    double w_max = 0.;
    for (const double w : shared_weight)
      w_max = std::max(w_max, std::abs(w));
    for (unsigned int k = 0; k < wls->node.size(); ++k)
      {
        const unsigned int i = wls->node[k];
        if (!regular(i) || key_of(k) != key)
          continue;
        bool same = true;
        for (std::size_t e = 0; e < shared_weight.size() && same; ++e)
          same = std::abs(wls->weight[c2 * wls->row_start[k] + e] - shared_weight[e]) <= 1e-9 * w_max;
        if (same)
          {
            shared_row[i] = 1;
            ++n_shared_rows;
          }
      }
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::build_live_bits()
  {
    const auto        &nb = disc.neighborhood;
    const std::size_t  nv = sweep_n_vectors;
    const std::size_t  n_f = sweep_offset.size();
    // Spare vectors of zeros: the Omega_s runs read the bits of the vector
    // after theirs, the half-stencil sweep those of the vectors up to the
    // stencil reach (sweep_pad) after its own.
    sweep_live.assign(n_f * (nv + sweep_pad / 8 + 2), 0);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const std::uint32_t L = sweep_position[i];
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
          if (broken_flag[b] == 0)
            sweep_live[(L / 8) * n_f + sweep_of_box[box_index(i, b)]] |= std::uint8_t(1u << (L % 8));
      }
    full_lanes.assign(nv, 0xFF);
    for (std::size_t v = 0; v < nv; ++v)
      for (std::size_t f = 0; f < n_f; ++f)
        full_lanes[v] &= sweep_live[v * n_f + f];
    sweep_live_valid = true;
    half_mask_valid  = false;
  }

  template <int dim>
  template <typename F>
  void
  HybridBondBasedModel<dim>::for_each_p_chunk(const std::int64_t L0, const F &f) const
  {
    const std::int64_t n8 = 8 * std::int64_t(sweep_n_vectors), C = p_chunk;
    for (const std::int64_t ro : p_row_offsets)
      {
        const std::int64_t lo = std::max<std::int64_t>(0, L0 + ro - box_radius),
                           hi = std::min<std::int64_t>(n8, L0 + ro + box_radius + 8);
        for (std::int64_t c = lo / C; c * C < hi && lo < hi; ++c)
          f(std::size_t(c));
      }
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::fill_p_chunk(const std::size_t c)
  {
    // Off the nodes x - x_c and u are 0 (as p): the whole chunk.
    const std::size_t N = sweep_n_alloc, begin = c * p_chunk,
                      end = std::min(begin + p_chunk, 8 * std::size_t(sweep_n_vectors));
    for (unsigned int d = 0; d < dim; ++d)
      {
        const double *__restrict x = sweep_x0.data() + sweep_pad + d * N;
        const double *__restrict u = sweep_u.data() + sweep_pad + d * N;
        double *__restrict p       = sweep_p.data() + sweep_pad + d * N;
        for (std::size_t L = begin; L < end; ++L)
          p[L] = x[L] + u[L];
      }
    p_stamp[c] = p_epoch;
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::update_row_lists()
  {
    wls_mask.resize(disc.position.size());
    for (std::size_t k = 0; k < wls_mask.size(); ++k)
      wls_mask[k] = wls_flag.local_element(k) > 0.5;
    standard_rows.clear();
    active_wls_rows.clear();
    own_weight_rows.clear();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const bool w = wls_flag.local_element(i) > 0.5;
        (w ? active_wls_rows : standard_rows).push_back(i);
        if (w && !(sweep_on && shared_row[i]))
          own_weight_rows.push_back(i);
      }
    if (!sweep_on)
      return;
    // Lanes per vector of 8 box positions, and the vectors that have any.
    shared_lanes.assign(sweep_n_vectors, 0);
    wls_lanes.assign(sweep_n_vectors, 0);
    for (const unsigned int i : active_wls_rows)
      wls_lanes[sweep_position[i] / 8] |= std::uint8_t(1u << (sweep_position[i] % 8));
    for (const unsigned int i : active_wls_rows)
      if (shared_row[i])
        shared_lanes[sweep_position[i] / 8] |= std::uint8_t(1u << (sweep_position[i] % 8));
    shared_vectors.clear();
    for (std::uint32_t v = 0; v < sweep_n_vectors; ++v)
      if (shared_lanes[v])
        shared_vectors.push_back(v);
    // Omega_s grows by switched families with ragged edges: aligned vectors
    // fill 7.26 of 8 lanes at the end of KW dx = 0.5 (7.88 initially). Cover
    // the Omega_s positions greedily (each run starts at the first position
    // not yet covered; the fewest runs of eight): 7.61 lanes.
    std::vector<std::uint32_t> positions;
    positions.reserve(standard_rows.size());
    for (const unsigned int i : standard_rows)
      positions.push_back(sweep_position[i]);
    std::sort(positions.begin(), positions.end());
    standard_start.clear();
    standard_start_lanes.clear();
    for (const std::uint32_t L : positions)
      if (standard_start.empty() || L >= standard_start.back() + 8)
        {
          standard_start.push_back(L);
          standard_start_lanes.push_back(1);
        }
      else
        standard_start_lanes.back() |= std::uint8_t(1u << (L - standard_start.back()));
    std::vector<std::uint8_t> read(p_stamp.size(), 0);
    if (half_on)
      {
        // The vectors of owned Omega_s lanes, and every vector that holds
        // the lower end M = L - o_g of a bond of such a lane L.
        const std::size_t nv = sweep_n_vectors;
        standard_lanes.assign(nv + sweep_pad / 8 + 2, 0);
        for (const std::uint32_t L : positions)
          standard_lanes[L / 8] |= std::uint8_t(1u << (L % 8));
        std::vector<std::uint8_t> in_sweep(nv, 0);
        for (std::uint32_t v = 0; v < nv; ++v)
          if (standard_lanes[v])
            {
              in_sweep[v] = 1;
              for (const unsigned int g : half_offsets)
                {
                  const std::int64_t lo = 8 * std::int64_t(v) - sweep_offset[g];
                  for (const std::int64_t w : {lo, lo + 7})
                    if (w >= 0 && w / 8 < std::int64_t(nv))
                      in_sweep[w / 8] = 1;
                }
            }
        // Tiles of half_tile lattice columns (from a multiple of half_tile
        // of the global lattice), each row by row: the reactions and
        // positions a tile touches stay in the L1 cache (whole rows did
        // not). The order is a function of the lattice positions only.
        half_groups.clear();
        standard_vectors.clear();
        for (std::uint32_t v = 0; v < nv; ++v)
          if (in_sweep[v])
            {
              half_groups.push_back(v);
              if (standard_lanes[v])
                standard_vectors.push_back(v);
              for_each_p_chunk(8 * std::int64_t(v), [&](const std::size_t c) { read[c] = 1; });
            }
        const auto tile = [&](const std::uint32_t v) {
          const std::int64_t x = 8 * std::int64_t(v) % sweep_stride[1] + sweep_lower[0];
          return (x >= 0 ? x : x - half_tile + 1) / half_tile;
        };
        std::stable_sort(half_groups.begin(), half_groups.end(),
                         [&](const std::uint32_t a, const std::uint32_t b) { return tile(a) < tile(b); });
        half_index.assign(nv, -1);
        for (std::size_t k = 0; k < half_groups.size(); ++k)
          half_index[half_groups[k]] = k;
        half_mask_valid = false;
      }
    else
      for (const std::uint32_t L0 : standard_start)
        for_each_p_chunk(L0, [&](const std::size_t c) { read[c] = 1; });
    standard_chunks.clear();
    for (std::size_t c = 0; c < read.size(); ++c)
      if (read[c])
        standard_chunks.push_back(c);
  }

  template <int dim>
  bool
  HybridBondBasedModel<dim>::switch_critical(const VectorField &u)
  {
    const auto        &nb      = disc.neighborhood;
    double            *crit    = critical.begin();
    const double      *p       = deformed.data();
    const std::int32_t *wf     = wls_mask.data();
    if (prm.switching_bound && !lattice_bound_on)
      {
        std::array<const double *, dim> ud;
        for (unsigned int d = 0; d < dim; ++d)
          ud[d] = u[d].begin();
        const double start = cpu_seconds();
        for (auto &b : budget)
          b.advance(ud);
        seconds[3] += cpu_seconds() - start;
      }
    std::uint64_t n_critical = 0;
    if (sweep_on)
      n_critical = sweep_switching_test();
    else
      {
      // Only the Omega_w rows test: every bond with an Omega_w end is tested
      // in the row of such an end (owned by this or another rank); each of
      // them tests all its unbroken bonds, so that its record covers them.
      for (const unsigned int i : active_wls_rows)
        {
          if (prm.switching_bound)
            {
              bool needed = false;
              for (const auto &b : budget)
                needed = needed || b.needs_check(i);
              if (!needed)
                continue;
            }
          ++exact_node_tests;
          exact_bond_tests += nb.row_start[i + 1] - nb.row_start[i];
          const double       *pi    = p + std::size_t(dim) * i;
          const double       *L2    = critical_length2.data() + nb.table_start[i];
          const double       *iL2   = inverse_critical_length2.data() + nb.table_start[i];
          const auto          begin = nb.row_start[i];
          const unsigned int  n     = nb.row_start[i + 1] - begin;
          const std::int32_t *col   = nb.col.data() + begin;
          const std::uint8_t *br    = broken_flag.data() + begin;
          const double       *r     = nb.bond_length.data() + nb.table_start[i];
          const unsigned int  n_classes = class_bound.size();
          double              q[max_classes];
          const unsigned int  count =
            test_row<dim>(p, pi, col, L2, iL2, r, class_bound.data(), n_classes, br, n, q);
          for (unsigned int k = 0; k < n_classes; ++k)
            budget[k].record(i, (1. - std::sqrt(q[k])) * min_threshold[k] - threshold_margin);
          if (count == 0)
            continue;
          n_critical += count;
          const double *B2 = breaking_length2.data() + nb.table_start[i];
          for (unsigned int b = 0; b < n; ++b)
            {
              const std::int32_t j = col[b];
              if (br[b])
                continue;
              const double l2 = length2<dim>(p + std::size_t(dim) * j, pi);
              if (l2 >= L2[b])
                {
                  // Both end points, a ghost one too (sent to its owner below).
                  crit[i] = 1.;
                  crit[j] = 1.;
                  // Once per bond: a bond between two Omega_w nodes is found
                  // from both ends (both bounds fire: each record covers it),
                  // on one rank or two; the end with the lower id counts it.
                  if (l2 > B2[b] && (wf[j] == 0 || disc.id[i] < disc.id[j]))
                    ++overstretched;
                }
            }
        }
      }
    // One global sum per step; the ghost exchanges only when needed.
    if (Utilities::MPI::sum(n_critical, disc.get_mpi_communicator()) == 0)
      return false;
    critical.compress(VectorOperation::add); // marks of ghost end points to their owners
    critical.update_ghost_values();
    bool       changed = false;
    const auto switch_node = [&](const unsigned int i) {
      if (wls_flag.local_element(i) > 0.5)
        {
          wls_flag.local_element(i) = 0.;
          switched_at[i]            = int(n_evaluations) - 1;
          changed                   = true;
          // A node never returns to Omega_w: its bound need not grow.
          for (auto &b : budget)
            b.record(i, -1.);
        }
    };
    if (sweep_on)
      {
        // The families of the (few) critical nodes, owned or ghost, by the
        // lattice offsets: the family of a node is every node at a stencil
        // offset (families are symmetric), so i switches iff i or a node
        // of its family is critical, as below.
        const std::int64_t n_box = 8 * std::int64_t(sweep_n_vectors);
        const unsigned int n_owned = disc.n_owned();
        for (std::size_t c = 0; c < disc.position.size(); ++c)
          if (crit[c] > 0.)
            {
              if (c < n_owned)
                switch_node(c);
              for (const std::int64_t o : sweep_offset)
                {
                  const std::int64_t L = sweep_position[c] + o;
                  if (L >= 0 && L < n_box && sweep_node[L] >= 0 &&
                      sweep_node[L] < std::int32_t(n_owned))
                    switch_node(sweep_node[L]);
                }
            }
      }
    else
      for (const unsigned int i : active_wls_rows)
        {
          bool hit = crit[i] > 0.;
          for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1] && !hit; ++b)
            hit = crit[nb.col[b]] > 0.;
          if (hit)
            switch_node(i);
        }
    critical = 0.;
    critical.zero_out_ghost_values();
    wls_flag.update_ghost_values();
    update_row_lists();
    ++switch_events;
    return changed;
  }

  template <int dim>
  std::uint64_t
  HybridBondBasedModel<dim>::sweep_switching_test()
  {
    std::uint64_t n_critical = 0;
#ifdef PERIDEAL_HYBRID_SWEEP
    // The classes to test exactly per vector (bit k: some Omega_w lane's
    // bound of length class k fired). A class is tested on its own bonds
    // only: its record bounds only them, and every critical bond of class k
    // has an Omega_w end whose class-k bound fires (the argument of the
    // class documentation, per class).
    test_lanes.assign(sweep_n_vectors, 0);
    const bool         lip       = lattice_bound_on;
    const unsigned int n_classes = lip ? 1 : class_bound.size();
    if (lip)
      {
        const double start = cpu_seconds();
        lattice_bound_vectors();
        seconds[3] += cpu_seconds() - start;
      }
    else
      for (const unsigned int i : active_wls_rows)
        for (unsigned int k = 0; k < n_classes; ++k)
          if (!prm.switching_bound || budget[k].needs_check(i))
            test_lanes[sweep_position[i] / 8] |= std::uint8_t(1u << k);
    // A vector costs the same for one lane as for eight: test (and record)
    // every Omega_w lane of a vector with one to test. An exact test of a
    // node whose bound has not fired finds nothing critical at it (that is
    // what the bound proves), so the outcome is unchanged; its record only
    // restarts its budget. (With the lattice bound, test_lanes holds the
    // lanes whose bound fired, and a vector whose fired lanes lie in one
    // half tests only that half.)
    test_vectors.clear();
    for (std::uint32_t v = 0; v < sweep_n_vectors; ++v)
      if (test_lanes[v])
        test_vectors.push_back(v);
    const std::size_t   N  = sweep_n_alloc, n_f = sweep_offset.size();
    const double       *p  = sweep_p.data() + sweep_pad;
    const std::int64_t *offset = sweep_offset.data();
    const double       *iL2    = sweep_iL2.data();
    double             *crit = critical.begin();
    const std::int32_t *wf   = wls_mask.data();
    for (const std::uint32_t v : test_vectors)
      {
        const __mmask8    lanes   = wls_lanes[v];
        const unsigned    classes = lip ? 1u : test_lanes[v];
        const std::size_t L0      = 8 * std::size_t(v);
        for_each_p_chunk(L0, [&](const std::size_t c) {
          if (p_stamp[c] != p_epoch)
            fill_p_chunk(c);
        });
        __m512d pi[dim];
        for (unsigned int d = 0; d < dim; ++d)
          pi[d] = _mm512_loadu_pd(p + d * N + L0);
        const std::uint8_t *bits = sweep_live.data() + std::size_t(v) * n_f;
        for (unsigned int k = 0; k < n_classes; ++k)
          {
            if (((classes >> k) & 1u) == 0)
              continue;
            // The lattice bound covers all bonds of a node: one group.
            const std::vector<unsigned int> &group = lip ? all_offsets : class_offsets[k];
            // The lattice bound marks the lanes whose bound fired; if they
            // all lie in one half of the vector, only the Omega_w lanes of
            // that half are tested, with 256-bit vectors (half the work on
            // a core that splits 512-bit operations; the lanes not tested
            // keep their slack, which is still valid).
            __mmask8     tl   = lanes;
            const bool   half = dim == 2 && lip && ((test_lanes[v] & 0x0Fu) == 0 || (test_lanes[v] & 0xF0u) == 0);
            const unsigned int h = half && (test_lanes[v] & 0x0Fu) == 0 ? 1 : 0;
            if (half)
              tl = __mmask8(((lanes >> (4 * h)) & 0x0Fu) << (4 * h));
            exact_node_tests += __builtin_popcount(tl);
            exact_bond_tests += std::uint64_t(__builtin_popcount(tl)) * group.size();
            // First q = max |y|^2 / T^2 only; the (rare) vectors with
            // q >= 1 - 1e-12 are scanned again for the bonds with
            // |y|^2 >= T^2 (l2 >= L2 implies l2 fl(1/L2) >= 1 - 3e-16).
            // The lattice bound's group is every offset in order.
            // Every bond of the tested lanes alive (the usual case: Omega_w
            // nodes have full families, and a bond with an Omega_w end breaks
            // only after the end switched): the grouped kernel, no masks.
            const unsigned full = full_lanes[v];
            const bool grouped = lip && grouped_on && (full & tl) == tl;
            const bool by_rows = grouped && rows_on;
            __m512d    qmax;
            if (half)
              {
                const __mmask8 m4 = __mmask8(tl >> (4 * h));
                const __m256d  q4 =
                  by_rows ? max_ratio_rows<4>(p, N, L0 + 4 * h, sweep_stride[1], row_mask.data(),
                                              row_iL2.data(), row_mask.size(), m4) :
                  grouped ? max_ratio_grouped<dim, 4>(p, N, L0 + 4 * h, grouped_offset.data(), group_start.data(),
                                                      group_iL2.data(), group_iL2.size(), m4) :
                            max_ratio<dim, 4, true>(p, N, L0 + 4 * h, offset, iL2, bits, 4 * h, m4, nullptr,
                                                    group.size());
                qmax = h ? _mm512_insertf64x4(_mm512_setzero_pd(), q4, 1) : _mm512_zextpd256_pd512(q4);
              }
            else if (by_rows)
              qmax = max_ratio_rows<8>(p, N, L0, sweep_stride[1], row_mask.data(), row_iL2.data(),
                                       row_mask.size(), tl);
            else if (grouped)
              qmax = max_ratio_grouped<dim, 8>(p, N, L0, grouped_offset.data(), group_start.data(),
                                               group_iL2.data(), group_iL2.size(), tl);
            else if (lip)
              qmax = max_ratio<dim, 8, true>(p, N, L0, offset, iL2, bits, 0, lanes, nullptr, group.size());
            else
              qmax = max_ratio<dim, 8, false>(p, N, L0, offset, iL2, bits, 0, lanes, group.data(), group.size());
            if (__builtin_expect(
                  _mm512_cmp_pd_mask(qmax, _mm512_set1_pd(1. - 1e-12), _CMP_GE_OQ) != 0, 0))
              for (const unsigned int f : group)
                {
                  const __mmask8 alive = bits[f] & tl;
                  if (alive == 0)
                    continue;
                  __m512d        y[dim];
                  const __m512d  l2 = lane_bonds<dim>(p, N, L0, sweep_offset[f], pi, y);
                  const __mmask8 hit =
                    _mm512_mask_cmp_pd_mask(alive, l2, _mm512_set1_pd(sweep_L2[f]), _CMP_GE_OQ);
                  if (hit == 0)
                    continue;
                  alignas(64) double l2s[8];
                  _mm512_store_pd(l2s, l2);
                  for (unsigned int l = 0; l < 8; ++l)
                    if ((hit >> l) & 1u)
                      {
                        // Both end points, a ghost one too (sent to its owner).
                        const std::int32_t i = sweep_node[L0 + l],
                                           j = sweep_node[L0 + l + sweep_offset[f]];
                        crit[i] = crit[j] = 1.;
                        ++n_critical;
                        // Once per bond, as in the row loop below.
                        if (l2s[l] > sweep_B2[f] && (wf[j] == 0 || disc.id[i] < disc.id[j]))
                          ++overstretched;
                      }
                }
            if (lip)
              {
                // Slack left: (1 - sqrt(q)) (1 + sigma s0) - margin.
                const double  kappa = 1. + prm.sigma * s0;
                const __m512d slack = _mm512_sub_pd(
                  _mm512_fnmadd_pd(_mm512_set1_pd(kappa), _mm512_sqrt_pd(qmax), _mm512_set1_pd(kappa)),
                  _mm512_set1_pd(lip_margin));
                _mm512_mask_storeu_pd(lip_remaining.data() + L0, tl, slack);
                continue;
              }
            alignas(64) double q[8];
            _mm512_store_pd(q, qmax);
            for (unsigned int l = 0; l < 8; ++l)
              if ((lanes >> l) & 1u)
                budget[k].record(sweep_node[L0 + l],
                                 (1. - std::sqrt(q[l])) * min_threshold[k] - threshold_margin);
          }
      }
#endif
    return n_critical;
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::lattice_bound_vectors()
  {
#ifdef PERIDEAL_HYBRID_SWEEP
    if constexpr (dim == 2)
      {
        // (The class documentation, "Lattice bound".) Per test: d = u - u_last
        // over the box; squared edge norms ex(P) = |d(P + 1) - d(P)|^2,
        // ey(P) = |d(P + row) - d(P)|^2 (+inf for an edge with a missing
        // end), rounded up to float; fy = max of ey over [P - R, P + R];
        // at a node L: G_x^2 = max ex over [L - R, L + R - 1], G_y^2 = max
        // fy over L + k row, k in [-R, R - 1]. The three stages run in
        // chunks, each lagging the previous one by its reach, so the arrays
        // are read back from cache.
        const std::size_t  N = sweep_n_alloc, n8 = 8 * sweep_n_vectors;
        const std::int64_t row = sweep_stride[1];
        const int          R   = box_radius;
        lip_swap_pending       = true;
        if (!lip_have_prev)
          {
            // The first test: no increments yet, test every Omega_w vector.
            lip_have_prev = true;
            for (std::size_t v = 0; v < sweep_n_vectors; ++v)
              test_lanes[v] = wls_lanes[v];
            return;
          }
        const double *u = sweep_u.data() + sweep_pad, *w = lip_prev.data() + sweep_pad;
        float        *ex = lip_ex.data() + lip_pad, *ey = lip_ey.data() + lip_pad,
              *fy = lip_fy.data() + lip_pad;
        double         *rem = lip_remaining.data();
        const __m512d   inf = _mm512_set1_pd(std::numeric_limits<double>::infinity());
        const __m512d   cx = _mm512_set1_pd(lip_coef[0]), cy = _mm512_set1_pd(lip_coef[1]);
        const auto edges = [&](const std::size_t L0) {
          const __m512d d0 = _mm512_sub_pd(_mm512_loadu_pd(u + L0), _mm512_loadu_pd(w + L0));
          const __m512d d1 =
            _mm512_sub_pd(_mm512_loadu_pd(u + N + L0), _mm512_loadu_pd(w + N + L0));
          const std::int64_t s[2] = {1, row};
          float             *out[2] = {ex, ey};
          for (unsigned int e = 0; e < 2; ++e)
            {
              const std::size_t M  = L0 + s[e];
              const __m512d     a0 = _mm512_sub_pd(
                _mm512_sub_pd(_mm512_loadu_pd(u + M), _mm512_loadu_pd(w + M)), d0);
              const __m512d a1 = _mm512_sub_pd(
                _mm512_sub_pd(_mm512_loadu_pd(u + N + M), _mm512_loadu_pd(w + N + M)), d1);
              const __m512d n2 =
                _mm512_mask_mov_pd(inf, lip_edge_ok[e][L0 / 8],
                                   _mm512_fmadd_pd(a1, a1, _mm512_mul_pd(a0, a0)));
              _mm256_storeu_ps(out[e] + L0,
                               _mm512_cvt_roundpd_ps(n2, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC));
            }
        };
        const auto x_window = [&](const std::size_t L0) {
          __m256 m = _mm256_loadu_ps(ey + L0 - R);
          for (int k = -R + 1; k <= R; ++k)
            m = _mm256_max_ps(m, _mm256_loadu_ps(ey + L0 + k));
          _mm256_storeu_ps(fy + L0, m);
        };
        const auto grow = [&](const std::size_t L0) {
          const std::size_t v     = L0 / 8;
          const __mmask8    lanes = wls_lanes[v];
          if (lanes == 0)
            return;
          __m256 gx = _mm256_loadu_ps(ex + L0 - R), gy = _mm256_loadu_ps(fy + L0 - R * row);
          for (int k = -R + 1; k < R; ++k)
            {
              gx = _mm256_max_ps(gx, _mm256_loadu_ps(ex + L0 + k));
              gy = _mm256_max_ps(gy, _mm256_loadu_ps(fy + L0 + k * row));
            }
          const __m512d H = _mm512_sqrt_pd(
            _mm512_fmadd_pd(cy, _mm512_cvtps_pd(gy), _mm512_mul_pd(cx, _mm512_cvtps_pd(gx))));
          const __m512d r = _mm512_sub_pd(_mm512_loadu_pd(rem + L0), H);
          _mm512_storeu_pd(rem + L0, r);
          // Not > 0 (NaN too): test.
          test_lanes[v] = _mm512_mask_cmp_pd_mask(lanes, r, _mm512_setzero_pd(), _CMP_NGT_UQ);
        };
        const std::size_t chunk = 512, lag3 = 8 * std::size_t((R + 15) / 8),
                          lag4 = 8 * std::size_t((std::max(R - 1, 0) * row + 15) / 8);
        std::size_t f2 = 0, f3 = 0, f4 = 0;
        while (f4 < n8)
          {
            const std::size_t e2 = std::min(n8, f2 + chunk);
            for (; f2 < e2; f2 += 8)
              edges(f2);
            const std::size_t e3 = f2 == n8 ? n8 : (f2 > lag3 ? f2 - lag3 : 0);
            for (; f3 < e3; f3 += 8)
              x_window(f3);
            const std::size_t e4 = f3 == n8 ? n8 : (f3 > lag4 ? f3 - lag4 : 0);
            for (; f4 < e4; f4 += 8)
              grow(f4);
          }
      }
#endif
  }

  template <int dim>
  bool
  HybridBondBasedModel<dim>::sweep_standard_rows(VectorField &force)
  {
#ifdef PERIDEAL_HYBRID_SWEEP
    // Every owned Omega_s node sums the PMB force of all its unbroken bonds
    // (both copies of a bond between two Omega_s nodes see the same |y|^2
    // and break together; a bond to Omega_w is evaluated from its Omega_s
    // end only).
    const std::size_t  N = sweep_n_alloc;
    const double      *p = sweep_p.data() + sweep_pad;
    const unsigned int n_f = sweep_offset.size();
    // Local copies of the tables' addresses: the compiler reloaded them per
    // offset (sweep_broken.emplace_back may alias the members).
    const std::int64_t *offset = sweep_offset.data();
    const double       *kb = sweep_k.data(), *kr = sweep_kr.data(), *t2 = sweep_t2.data();
    for (const std::uint32_t c : standard_chunks)
      if (p_stamp[c] != p_epoch)
        fill_p_chunk(c);
    sweep_broken.clear();
    for (std::size_t k = 0; k < standard_start.size(); ++k)
      {
        // A run from L0 straddles the aligned vectors a and a + 1 (the bit
        // array has one spare vector of zeros): their bits of offset f, as
        // one 16-bit word, shifted by L0 % 8.
        const std::uint32_t lanes = standard_start_lanes[k];
        const std::size_t   L0    = standard_start[k];
        const unsigned int  shift = L0 % 8;
        __m512d             pi[dim], acc[dim];
        for (unsigned int d = 0; d < dim; ++d)
          {
            pi[d]  = _mm512_loadu_pd(p + d * N + L0);
            acc[d] = _mm512_setzero_pd();
          }
        const std::uint8_t *bits = sweep_live.data() + (L0 / 8) * n_f;
        for (unsigned int f = 0; f < n_f; ++f)
          {
            const __mmask8 alive = ((bits[f] | (std::uint32_t(bits[f + n_f]) << 8)) >> shift) & lanes;
            if (alive == 0)
              continue;
            __m512d       y[dim];
            const __m512d l2 = lane_bonds<dim>(p, N, L0, offset[f], pi, y);
            __mmask8      brk;
            const __m512d scale = internal::LatticeSweep::pmb_bond_scale_kr<false>(
              l2, alive, _mm512_set1_pd(kb[f]), _mm512_set1_pd(kr[f]), _mm512_set1_pd(t2[f]), brk);
            for (unsigned int d = 0; d < dim; ++d)
              acc[d] = _mm512_fmadd_pd(scale, y[d], acc[d]);
            if (__builtin_expect(brk != 0, 0))
              for (unsigned int l = 0; l < 8; ++l)
                if ((brk >> l) & 1u)
                  sweep_broken.emplace_back(f, std::uint32_t(L0 + l));
          }
        store_lane_forces<dim>(force, sweep_node.data(), L0, lanes, acc);
      }
    return apply_sweep_broken();
#else
    (void)force;
    return false;
#endif
  }

  template <int dim>
  bool
  HybridBondBasedModel<dim>::apply_sweep_broken()
  {
    const std::size_t  n_f     = sweep_offset.size();
    const std::int32_t n_owned = disc.n_owned();
    for (const auto &[f, L] : sweep_broken)
      {
        const std::uint32_t M = L + sweep_offset[f];
        const unsigned int  g = sweep_mirror[f];
        sweep_live[(L / 8) * n_f + f] &= std::uint8_t(~(1u << (L % 8)));
        sweep_live[(M / 8) * n_f + g] &= std::uint8_t(~(1u << (M % 8)));
        if (L / 8 < full_lanes.size())
          full_lanes[L / 8] &= std::uint8_t(~(1u << (L % 8)));
        if (M / 8 < full_lanes.size())
          full_lanes[M / 8] &= std::uint8_t(~(1u << (M % 8)));
        // The half-stencil sweep's entries are (positive offset, lower end).
        if (half_mask_valid && sweep_offset[f] > 0 && half_index[L / 8] >= 0)
          half_mask[std::size_t(half_index[L / 8]) * half_offsets.size() + half_slot[f]] &=
            std::uint8_t(~(1u << (L % 8)));
        if (sweep_node[L] < n_owned)
          broken_flag[find_bond(sweep_node[L], sweep_box[f])] = 1;
        if (sweep_node[M] < n_owned)
          broken_flag[find_bond(sweep_node[M], sweep_box[g])] = 1;
      }
    return !sweep_broken.empty();
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::build_half_mask()
  {
    // Bond (M, M + o_g) of lane M is evaluated if alive in M's row and M is
    // an owned Omega_s node, or alive in the row of M + o_g (the mirror
    // offset) and that one is (a ghost or Omega_w row at M is not read).
    const std::size_t   n_f = sweep_offset.size(), n_h = half_offsets.size();
    const std::uint8_t *live = sweep_live.data(), *own = standard_lanes.data();
    half_mask.assign(half_groups.size() * n_h, 0);
    for (std::size_t k = 0; k < half_groups.size(); ++k)
      {
        const std::size_t v = half_groups[k];
        for (unsigned int h = 0; h < n_h; ++h)
          {
            const unsigned int  g  = half_offsets[h];
            const std::int64_t  o  = sweep_offset[g];
            const std::size_t   w  = v + std::size_t(o) / 8;
            const std::uint8_t *bm = live + sweep_mirror[g];
            const unsigned      other =
              (bm[w * n_f] | (unsigned(bm[(w + 1) * n_f]) << 8)) & (own[w] | (unsigned(own[w + 1]) << 8));
            half_mask[k * n_h + h] = std::uint8_t((live[v * n_f + g] & own[v]) | (other >> (o % 8)));
          }
      }
    half_mask_valid = true;
  }

  template <int dim>
  bool
  HybridBondBasedModel<dim>::sweep_half_rows(VectorField &force)
  {
#ifdef PERIDEAL_HYBRID_SWEEP
    if (!half_mask_valid)
      build_half_mask();
    const std::size_t   N = sweep_n_alloc, n_h = half_offsets.size();
    const double       *p = sweep_p.data() + sweep_pad;
    double             *R = half_reaction.data() + sweep_pad, *A = half_acc.data() + sweep_pad;
    const std::uint8_t *own = standard_lanes.data();
    // Per slot h (the order of half_offsets): offset, k, k r, (r + s0 r)^2.
    const std::int64_t *o = half_o.data();
    const std::array<double, 3> *c = half_constants.data();
    for (const std::uint32_t ch : standard_chunks)
      if (p_stamp[ch] != p_epoch)
        fill_p_chunk(ch);
    // Reactions are read only at the vectors with owned Omega_s lanes; the
    // other positions of the array are written, never read.
    for (const std::uint32_t v : standard_vectors)
      for (unsigned int d = 0; d < dim; ++d)
        _mm512_storeu_pd(R + d * N + 8 * std::size_t(v), _mm512_setzero_pd());
    sweep_broken.clear();
    half_broken_lanes.assign(n_h, 0);
    std::uint8_t *const broken_lanes = half_broken_lanes.data();
    bool                any_broken   = false;
    for (std::size_t k = 0; k < half_groups.size(); ++k)
      {
        const std::size_t   L0 = 8 * std::size_t(half_groups[k]);
        const std::uint8_t *mask = half_mask.data() + k * n_h;
        __m512d             pi[dim], f[dim];
        for (unsigned int d = 0; d < dim; ++d)
          {
            pi[d] = _mm512_loadu_pd(p + d * N + L0);
            f[d]  = _mm512_setzero_pd();
          }
        for (unsigned int h = 0; h < n_h; ++h)
          {
            const __mmask8 alive = mask[h];
            if (alive == 0)
              continue;
            __m512d y[dim];
            for (unsigned int d = 0; d < dim; ++d)
              y[d] = _mm512_sub_pd(_mm512_loadu_pd(p + d * N + L0 + o[h]), pi[d]);
            __m512d l2 = _mm512_mul_pd(y[0], y[0]);
            for (unsigned int d = 1; d < dim; ++d)
              l2 = _mm512_fmadd_pd(y[d], y[d], l2);
            __mmask8      brk;
            const __m512d scale = internal::LatticeSweep::pmb_bond_scale_kr<false>(
              l2, alive, _mm512_set1_pd(c[h][0]), _mm512_set1_pd(c[h][1]), _mm512_set1_pd(c[h][2]), brk);
            for (unsigned int d = 0; d < dim; ++d)
              {
                double *r = R + d * N + L0 + o[h];
                f[d]      = _mm512_fmadd_pd(scale, y[d], f[d]);
                _mm512_storeu_pd(r, _mm512_fmadd_pd(scale, y[d], _mm512_loadu_pd(r)));
              }
            // Recorded after the loop: a call here (emplace_back) made GCC
            // keep f on the stack, a store-load chain per bond vector.
            if (__builtin_expect(brk != 0, 0))
              {
                broken_lanes[h] = brk;
                any_broken      = true;
              }
          }
        if (__builtin_expect(any_broken, 0))
          {
            for (unsigned int h = 0; h < n_h; ++h)
              for (unsigned int l = 0; l < 8; ++l)
                if ((broken_lanes[h] >> l) & 1u)
                  sweep_broken.emplace_back(half_offsets[h], std::uint32_t(L0 + l));
            std::fill(broken_lanes, broken_lanes + n_h, 0);
            any_broken = false;
          }
        if (own[L0 / 8])
          for (unsigned int d = 0; d < dim; ++d)
            _mm512_storeu_pd(A + d * N + L0, f[d]);
      }
    for (const std::uint32_t v : standard_vectors)
      {
        const std::size_t  L0   = 8 * std::size_t(v);
        __m512d F[dim];
        for (unsigned int d = 0; d < dim; ++d)
          F[d] = _mm512_sub_pd(_mm512_loadu_pd(A + d * N + L0), _mm512_loadu_pd(R + d * N + L0));
        store_lane_forces<dim>(force, sweep_node.data(), L0, own[v], F);
      }
    return apply_sweep_broken();
#else
    (void)force;
    return false;
#endif
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::sweep_wls_rows(VectorField &force)
  {
#ifdef PERIDEAL_HYBRID_SWEEP
    // F = sum_c W_c u(L + o_c) with the shared weights, eight rows at a time.
    constexpr unsigned int c2 = dim * dim;
    const std::size_t      N  = sweep_n_alloc;
    const double          *u  = sweep_u.data() + sweep_pad;
    const unsigned int     n_c = shared_offset.size();
    // Two vectors at a time: each accumulator is a chain of 2 n_c
    // dependent FMAs (latency bound with one vector: 10.9 ns per row at KW
    // dx = 0.25); two vectors keep twice the chains in flight. Every lane
    // sums the same terms in the same order as with one vector.
    const double       *Wt  = shared_weight.data();
    const std::int64_t *off = shared_offset.data();
    const auto          store = [&](const std::size_t L0, const __mmask8 lanes, const __m512d *acc) {
      store_lane_forces<dim>(force, sweep_node.data(), L0, lanes, acc);
    };
    const std::size_t n_v = shared_vectors.size();
    std::size_t       k   = 0;
    for (; k + 2 <= n_v; k += 2)
      {
        const std::size_t L0 = 8 * std::size_t(shared_vectors[k]),
                          L1 = 8 * std::size_t(shared_vectors[k + 1]);
        __m512d           acc0[dim], acc1[dim];
        for (unsigned int a = 0; a < dim; ++a)
          acc0[a] = acc1[a] = _mm512_setzero_pd();
        for (unsigned int c = 0; c < n_c; ++c)
          {
            const double *W = Wt + c2 * c;
            for (unsigned int b = 0; b < dim; ++b)
              {
                const __m512d ub0 = _mm512_loadu_pd(u + b * N + L0 + off[c]);
                const __m512d ub1 = _mm512_loadu_pd(u + b * N + L1 + off[c]);
                for (unsigned int a = 0; a < dim; ++a)
                  {
                    const __m512d w = _mm512_set1_pd(W[a * dim + b]);
                    acc0[a]         = _mm512_fmadd_pd(w, ub0, acc0[a]);
                    acc1[a]         = _mm512_fmadd_pd(w, ub1, acc1[a]);
                  }
              }
          }
        store(L0, shared_lanes[shared_vectors[k]], acc0);
        store(L1, shared_lanes[shared_vectors[k + 1]], acc1);
      }
    for (; k < n_v; ++k)
      {
        const std::size_t L0 = 8 * std::size_t(shared_vectors[k]);
        __m512d           acc[dim];
        for (unsigned int a = 0; a < dim; ++a)
          acc[a] = _mm512_setzero_pd();
        for (unsigned int c = 0; c < n_c; ++c)
          {
            const double *W = Wt + c2 * c;
            for (unsigned int b = 0; b < dim; ++b)
              {
                const __m512d ub = _mm512_loadu_pd(u + b * N + L0 + off[c]);
                for (unsigned int a = 0; a < dim; ++a)
                  acc[a] = _mm512_fmadd_pd(_mm512_set1_pd(W[a * dim + b]), ub, acc[a]);
              }
          }
        store(L0, shared_lanes[shared_vectors[k]], acc);
      }
#else
    (void)force;
#endif
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::compute_forces(const VectorField &u, VectorField &force)
  {
    double start = cpu_seconds();
    // Deformed positions x - x_c + u (x_c the lattice centre, the same on
    // every rank) of all local nodes, interleaved.
    const std::vector<Point<dim>> &x       = disc.position;
    const std::size_t              n_local = x.size();
    deformed.resize(n_local * dim);
    std::array<int, dim> mid;
    for (unsigned int d = 0; d < dim; ++d)
      mid[d] = int(disc.lattice_size()[d] / 2);
    const Point<dim> xc = disc.lattice_point(mid);
    if (sweep_on)
      {
        // p and u over the box (the same p as the row loops).
        if (!sweep_live_valid)
          build_live_bits();
        // The lattice bound keeps u of the last test: the buffer of sweep_u
        // at that test becomes lip_prev (both are zero off the nodes).
        if (lip_swap_pending)
          std::swap(sweep_u, lip_prev);
        lip_swap_pending = false;
        // u into the box; p = (x - x_c) + u only in the chunks read, just
        // before they are read (fill_p_chunk(); KW dx = 0.25: 75 % of the
        // chunks per evaluation on average, all of them in the last ~200 of
        // the 705 steps, when exact tests occur everywhere).
        if (++p_epoch == 0)
          {
            std::fill(p_stamp.begin(), p_stamp.end(), 0);
            p_epoch = 1;
          }
        const std::size_t N = sweep_n_alloc;
        for (unsigned int d = 0; d < dim; ++d)
          {
            const double *ud = u[d].begin();
            double       *vd = sweep_u.data() + sweep_pad + d * N;
            for (const auto &[i0, L0, n] : fill_runs)
              std::copy(ud + i0, ud + i0 + n, vd + L0);
          }
      }
    else
      for (unsigned int d = 0; d < dim; ++d)
        {
          const double *ud = u[d].begin();
          for (std::size_t i = 0; i < n_local; ++i)
            deformed[dim * i + d] = (x[i][d] - xc[d]) + ud[i];
        }
    // Without a finite s0 nothing is ever critical (and s0 is the same on
    // every rank).
    if ((n_evaluations++ % prm.check_interval == 0) && std::isfinite(s0) &&
        (!active_wls_rows.empty() || Utilities::MPI::n_mpi_processes(disc.get_mpi_communicator()) > 1))
      switch_critical(u);
    seconds[0] += (cpu_seconds() - start);

    // Omega_s: the nonlinear PMB force (3.1) with breaking (2.34), as in
    // BondBasedOperator: force k (l - r) y / l, break when l - r > s0 r.
    start = cpu_seconds();
    if (sweep_on)
      {
        op_stale = (half_on ? sweep_half_rows(force) : sweep_standard_rows(force)) || op_stale;
        seconds[1] += (cpu_seconds() - start);
        start = cpu_seconds();
        sweep_wls_rows(force);
      }
    const auto   &nb    = disc.neighborhood;
    auto         &flags = broken_flag;
    bool          broke = false;
    const double *p     = deformed.data();
    const double *coef  = op.bond_coefficients().data();
    for (const unsigned int i : sweep_on ? std::vector<unsigned int>() : standard_rows)
      {
        const double       *pi = p + std::size_t(dim) * i;
        const double       *k  = coef + nb.table_start[i];
        const double       *r  = nb.bond_length.data() + nb.table_start[i];
        const auto          begin = nb.row_start[i];
        const unsigned int  n     = nb.row_start[i + 1] - begin;
        const std::int32_t *col   = nb.col.data() + begin;
        std::uint8_t       *br    = flags.data() + begin;
        double             f[dim] = {};
        const unsigned int n_break = pmb_row<dim>(p, pi, col, k, r, br, n, s0, f);
        broke = broke || n_break > 0;
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
    op_stale = op_stale || broke;
    if (!sweep_on)
      {
        seconds[1] += (cpu_seconds() - start);
        start = cpu_seconds();
      }

    // Omega_w rows with their own weights: F_i = sum_c W_ic u_c, dim x dim
    // blocks (row-major).
    std::array<const double *, dim> ud;
    for (unsigned int d = 0; d < dim; ++d)
      ud[d] = u[d].begin();
    constexpr unsigned int c2 = dim * dim;
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
    if constexpr (dim == 2)
      {
        // Packed rows: 8 collocation nodes per chunk, two gathers, four FMAs.
        for (const unsigned int i : own_weight_rows)
          {
            const unsigned int k  = wls_row[i];
            __m512d            a0 = _mm512_setzero_pd(), a1 = _mm512_setzero_pd();
            for (auto c = packed_start[k]; c < packed_start[k + 1]; ++c)
              {
                const __m256i j  = _mm256_loadu_si256(
                  reinterpret_cast<const __m256i *>(packed_col.data() + 8 * c));
                const __m512d u0 = _mm512_i32gather_pd(j, ud[0], 8);
                const __m512d u1 = _mm512_i32gather_pd(j, ud[1], 8);
                const double *W  = packed_weight.data() + 32 * c;
                a0 = _mm512_fmadd_pd(_mm512_loadu_pd(W), u0, a0);
                a0 = _mm512_fmadd_pd(_mm512_loadu_pd(W + 8), u1, a0);
                a1 = _mm512_fmadd_pd(_mm512_loadu_pd(W + 16), u0, a1);
                a1 = _mm512_fmadd_pd(_mm512_loadu_pd(W + 24), u1, a1);
              }
            force[0].local_element(i) = _mm512_reduce_add_pd(a0);
            force[1].local_element(i) = _mm512_reduce_add_pd(a1);
          }
        seconds[2] += (cpu_seconds() - start);
        return;
      }
#endif
    for (const unsigned int i : own_weight_rows)
      {
        const unsigned int k = wls_row[i];
        double             f[dim] = {};
        for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
          {
            const double *W = wls->weight.data() + c2 * e;
            const auto    j = wls->col[e];
            for (unsigned int a = 0; a < dim; ++a)
              for (unsigned int b = 0; b < dim; ++b)
                f[a] += W[a * dim + b] * ud[b][j];
          }
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
    seconds[2] += (cpu_seconds() - start);
  }

  template <int dim>
  double
  HybridBondBasedModel<dim>::critical_time_step(const double rho) const
  {
    // Bound of lambda_max(-M) for the WLS rows: on a lattice the rows of
    // Omega_w are translates of a few collocation patterns, and on plane
    // waves u = a exp(i k.x) a pattern acts as the dim x dim symbol
    // M(k) = sum_c W_c exp(i k.(x_c - x_i)); rho(M(k)) <= ||M(k)||_inf is
    // maximized over a grid of k in the Brillouin zone [-pi/dx, pi/dx]^dim.
    // (A Gershgorin bound over the collocation nodes, sum_c ||W_c||, is
    // 2.5x too pessimistic for WLS-2 because of its negative weights.)
    // Verlet is stable for dt <= 2 / sqrt(lambda_max / rho).
    constexpr unsigned int   c2 = dim * dim;
    const double             dx = disc.parameters().dx;
    std::map<std::vector<long>, unsigned int> patterns; // offsets / (dx/8) -> first row
    for (unsigned int k = 0; k < wls->node.size(); ++k)
      {
        std::vector<long> key;
        for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
          for (unsigned int d = 0; d < dim; ++d)
            key.push_back(std::lround(8. * (disc.position[wls->col[e]][d] -
                                            disc.position[wls->node[k]][d]) / dx));
        patterns.emplace(key, k);
      }
    const unsigned int n_k = dim == 3 ? 17 : 41;
    double             lambda = 0.;
    for (const auto &[key, k] : patterns)
      {
        const unsigned int i = wls->node[k];
        unsigned int       n_total = 1;
        for (unsigned int d = 0; d < dim; ++d)
          n_total *= n_k;
        for (unsigned int q = 0; q < n_total; ++q)
          {
            Tensor<1, dim> wave;
            for (unsigned int d = 0, r = q; d < dim; ++d, r /= n_k)
              wave[d] = M_PI / dx * (-1. + 2. * double(r % n_k) / double(n_k - 1));
            std::complex<double> M[c2] = {};
            for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
              {
                const std::complex<double> phase =
                  std::exp(std::complex<double>(0., wave * (disc.position[wls->col[e]] -
                                                            disc.position[i])));
                for (unsigned int ab = 0; ab < c2; ++ab)
                  M[ab] += wls->weight[c2 * e + ab] * phase;
              }
            for (unsigned int a = 0; a < dim; ++a)
              {
                double row = 0.;
                for (unsigned int b = 0; b < dim; ++b)
                  row += std::abs(M[a * dim + b]);
                lambda = std::max(lambda, row);
              }
          }
      }
    lambda = Utilities::MPI::max(lambda, disc.get_mpi_communicator());
    const double dt_wls =
      lambda > 0. ? 2. * std::sqrt(rho / lambda) : std::numeric_limits<double>::max();
    return std::min(dt_wls, op.critical_time_step(rho));
  }

  template <int dim>
  std::string
  HybridBondBasedModel<dim>::description() const
  {
    std::ostringstream s;
    s << "adaptive hybrid (standard PMB on Omega_s, WLS-" << prm.wls.order << " with "
      << wls->n_collocation() << " collocation nodes on Omega_w, sigma = " << prm.sigma
      << ", c = " << op.micromodulus() << ", s0 = " << s0 << ")";
    return s.str();
  }

  template <int dim>
  types::global_dof_index
  HybridBondBasedModel<dim>::n_standard_nodes() const
  {
    types::global_dof_index n = 0;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      n += wls_flag.local_element(i) < 0.5 ? 1 : 0;
    return Utilities::MPI::sum(n, disc.get_mpi_communicator());
  }

  template <int dim>
  std::uint64_t
  HybridBondBasedModel<dim>::n_overstretched_bonds() const
  {
    return Utilities::MPI::sum(overstretched, disc.get_mpi_communicator());
  }

  template class HybridBondBasedModel<1>;
  template class HybridBondBasedModel<2>;
  template class HybridBondBasedModel<3>;
} // namespace PeriDEAL
