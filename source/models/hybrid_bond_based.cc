#include <perideal/base/exceptions.h>
#include <perideal/models/hybrid_bond_based.h>

#include <ctime>
#include <immintrin.h>
#include <complex>
#include <map>
#include <cmath>
#include <limits>
#include <sstream>

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
    constexpr unsigned int max_classes = 3;

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

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
    /** y = p_j - p_i of bonds b..b+7 (masked lanes read p_i itself). */
    inline void
    gather_y2(const double *p, const double *pi, const std::int32_t *col, const unsigned int b,
              const __mmask8 m, __m512d &y0, __m512d &y1)
    {
      const __m256i j2 = _mm256_slli_epi32(_mm256_maskz_loadu_epi32(m, col + b), 1);
      const __m512d x0 = _mm512_set1_pd(pi[0]), x1 = _mm512_set1_pd(pi[1]);
      y0 = _mm512_sub_pd(_mm512_mask_i32gather_pd(x0, m, j2, p, 8), x0);
      y1 = _mm512_sub_pd(_mm512_mask_i32gather_pd(x1, m, j2, p + 1, 8), x1);
    }

    /** pmb_row<2> with AVX-512: the same expressions, eight bonds at a time. */
    unsigned int
    pmb_row_avx512(const double       *p,
                   const double       *pi,
                   const std::int32_t *col,
                   const double       *k,
                   const double       *r,
                   std::uint8_t       *br,
                   const unsigned int  n,
                   const double        s0,
                   double             *f)
    {
      __m512d       a0 = _mm512_setzero_pd(), a1 = _mm512_setzero_pd();
      const __m512d vs0     = _mm512_set1_pd(s0);
      unsigned int  n_break = 0;
      for (unsigned int b = 0; b < n; b += 8)
        {
          const __mmask8 m = n - b >= 8 ? __mmask8(0xFF) : __mmask8((1u << (n - b)) - 1u);
          const __mmask8 alive =
            _mm_mask_cmpeq_epi8_mask(m, _mm_maskz_loadu_epi8(m, br + b), _mm_setzero_si128());
          if (alive == 0)
            continue;
          __m512d y0, y1;
          gather_y2(p, pi, col, b, alive, y0, y1);
          const __m512d l2 =
            _mm512_mask_blend_pd(alive, _mm512_set1_pd(1.),
                                 _mm512_fmadd_pd(y1, y1, _mm512_mul_pd(y0, y0)));
          const __m512d  l   = _mm512_sqrt_pd(l2);
          const __m512d  rb  = _mm512_maskz_loadu_pd(alive, r + b);
          const __m512d  dl  = _mm512_sub_pd(l, rb);
          const __mmask8 brk = _mm512_mask_cmp_pd_mask(alive, dl, _mm512_mul_pd(vs0, rb), _CMP_GT_OQ);
          const __mmask8 live = alive & ~brk;
          const __m512d  scale =
            _mm512_maskz_div_pd(live, _mm512_mul_pd(_mm512_maskz_loadu_pd(live, k + b), dl), l);
          a0 = _mm512_fmadd_pd(scale, y0, a0);
          a1 = _mm512_fmadd_pd(scale, y1, a1);
          if (brk)
            {
              _mm_mask_storeu_epi8(br + b, brk, _mm_set1_epi8(1));
              n_break += __builtin_popcount(brk);
            }
        }
      f[0] += _mm512_reduce_add_pd(a0);
      f[1] += _mm512_reduce_add_pd(a1);
      return n_break;
    }

    /** test_row<2> with AVX-512: the same expressions, eight bonds at a time. */
    unsigned int
    test_row_avx512(const double       *p,
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
      __m512d      qmax[max_classes];
      for (unsigned int k = 0; k < max_classes; ++k)
        qmax[k] = _mm512_setzero_pd();
      for (unsigned int b = 0; b < n; b += 8)
        {
          const __mmask8 m = n - b >= 8 ? __mmask8(0xFF) : __mmask8((1u << (n - b)) - 1u);
          const __mmask8 alive =
            _mm_mask_cmpeq_epi8_mask(m, _mm_maskz_loadu_epi8(m, br + b), _mm_setzero_si128());
          if (alive == 0)
            continue;
          __m512d y0, y1;
          gather_y2(p, pi, col, b, alive, y0, y1);
          const __m512d l2 = _mm512_fmadd_pd(y1, y1, _mm512_mul_pd(y0, y0));
          count += __builtin_popcount(
            _mm512_mask_cmp_pd_mask(alive, l2, _mm512_maskz_loadu_pd(alive, L2 + b), _CMP_GE_OQ));
          const __m512d ratio = _mm512_mul_pd(l2, _mm512_maskz_loadu_pd(alive, iL2 + b));
          const __m512d rb    = _mm512_maskz_loadu_pd(alive, r + b);
          __mmask8      rest  = alive;
          for (unsigned int k = 0; k < n_classes; ++k)
            {
              const __mmask8 in =
                k + 1 < n_classes ?
                  __mmask8(rest & _mm512_cmp_pd_mask(rb, _mm512_set1_pd(bound[k]), _CMP_LE_OQ)) :
                  rest;
              qmax[k] = _mm512_mask_max_pd(qmax[k], in, qmax[k], ratio);
              rest &= ~in;
            }
        }
      for (unsigned int k = 0; k < n_classes; ++k)
        q[k] = _mm512_reduce_max_pd(qmax[k]);
      return count;
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
    for (unsigned int k = 0; k < max_classes && (k == 0 || class_bound.back() < r_max); ++k)
      class_bound.push_back(k + 1 < max_classes ? r_min * std::pow(2., k + 1) * (1. + 1e-9) :
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
    update_row_lists();
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
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const bool w = wls_flag.local_element(i) > 0.5;
        (w ? active_wls_rows : standard_rows).push_back(i);
      }
  }

  template <int dim>
  bool
  HybridBondBasedModel<dim>::switch_critical(const VectorField &u)
  {
    const auto        &nb      = disc.neighborhood;
    double            *crit    = critical.begin();
    const double      *p       = deformed.data();
    const std::int32_t *wf     = wls_mask.data();
    if (prm.switching_bound)
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
        unsigned int        count;
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
        if constexpr (dim == 2)
          count = test_row_avx512(p, pi, col, L2, iL2, r, class_bound.data(), n_classes, br, n, q);
        else
#endif
          count = test_row<dim>(p, pi, col, L2, iL2, r, class_bound.data(), n_classes, br, n, q);
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
    // One global sum per step; the ghost exchanges only when needed.
    if (Utilities::MPI::sum(n_critical, disc.get_mpi_communicator()) == 0)
      return false;
    critical.compress(VectorOperation::add); // marks of ghost end points to their owners
    critical.update_ghost_values();
    bool changed = false;
    for (const unsigned int i : active_wls_rows)
      {
        bool hit = crit[i] > 0.;
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1] && !hit; ++b)
          hit = crit[nb.col[b]] > 0.;
        if (hit)
          {
            wls_flag.local_element(i) = 0.;
            switched_at[i]            = int(n_evaluations) - 1;
            changed                   = true;
          }
      }
    critical = 0.;
    critical.zero_out_ghost_values();
    wls_flag.update_ghost_values();
    update_row_lists();
    ++switch_events;
    return changed;
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
    start               = cpu_seconds();
    const auto   &nb    = disc.neighborhood;
    auto         &flags = broken_flag;
    bool          broke = false;
    const double *p     = deformed.data();
    const double *coef  = op.bond_coefficients().data();
    for (const unsigned int i : standard_rows)
      {
        const double       *pi = p + std::size_t(dim) * i;
        const double       *k  = coef + nb.table_start[i];
        const double       *r  = nb.bond_length.data() + nb.table_start[i];
        const auto          begin = nb.row_start[i];
        const unsigned int  n     = nb.row_start[i + 1] - begin;
        const std::int32_t *col   = nb.col.data() + begin;
        std::uint8_t       *br    = flags.data() + begin;
        double             f[dim] = {};
        unsigned int       n_break;
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
        if constexpr (dim == 2)
          n_break = pmb_row_avx512(p, pi, col, k, r, br, n, s0, f);
        else
#endif
          n_break = pmb_row<dim>(p, pi, col, k, r, br, n, s0, f);
        broke = broke || n_break > 0;
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
    op_stale = op_stale || broke;
    seconds[1] += (cpu_seconds() - start);

    // Omega_w: F_i = sum_c W_ic u_c, dim x dim blocks (row-major).
    start = cpu_seconds();
    std::array<const double *, dim> ud;
    for (unsigned int d = 0; d < dim; ++d)
      ud[d] = u[d].begin();
    constexpr unsigned int c2 = dim * dim;
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
    if constexpr (dim == 2)
      {
        // Packed rows: 8 collocation nodes per chunk, two gathers, four FMAs.
        for (const unsigned int i : active_wls_rows)
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
    for (const unsigned int i : active_wls_rows)
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
