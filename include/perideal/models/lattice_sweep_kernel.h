// ---------------------------------------------------------------------
// The AVX-512 kernel of the lattice sweep of the nonlinear PMB force, shared
// by BondBasedOperator (source/models/bond_based.cc) and the two-grid
// solver's fine-grid loop (source/multigrid/multigrid_mechanics.cc). Internal:
// include it only from compilation units built with the native ISA.
// ---------------------------------------------------------------------
#ifndef perideal_models_lattice_sweep_kernel_h
#define perideal_models_lattice_sweep_kernel_h

#if defined(__AVX512F__) && defined(__AVX512VL__)
#  include <immintrin.h>

#  include <cstddef>
#  include <cstdint>

#  define PERIDEAL_LATTICE_SWEEP_AVX512 1

namespace PeriDEAL
{
  namespace internal
  {
    namespace LatticeSweep
    {
      /**
       * The PMB bond of eight lanes given l2 = |y|^2, the lengths rb and the
       * stiffnesses kb: sets brk to the alive lanes with l - r > s0 r (2.34)
       * and returns k (l - r) / l for the alive, unbroken lanes (0 for the
       * others). 1/l by vrsqrt14pd (relative error < 2^-14) and two Newton
       * steps inv <- inv (3/2 - l2/2 inv^2) (error ~1e-16): the divider is
       * the bottleneck of sqrt + div (doc/benchmarks.md); l - r by one
       * explicit fused multiply-subtract. Every PMB loop (full list, half
       * list, ghost list, lattice sweeps) calls this, so all of them see
       * bitwise the same stretch of a bond and break it together. @p s0r is
       * s0 r (the sweep passes it precomputed per offset: the same product).
       * The unbroken lanes come from a second comparison rather than
       * alive & ~brk, which would round-trip the mask through a general
       * register on the critical path.
       */
      inline __m512d
      pmb_bond_scale(__m512d        l2,
                     const __mmask8 alive,
                     const __m512d  rb,
                     const __m512d  kb,
                     const __m512d  s0r,
                     __mmask8      &brk)
      {
        // Masked-off and broken lanes get l2 = 1 to keep inv finite.
        l2                = _mm512_mask_blend_pd(alive, _mm512_set1_pd(1.), l2);
        const __m512d h   = _mm512_mul_pd(_mm512_set1_pd(0.5), l2);
        __m512d       inv = _mm512_rsqrt14_pd(l2);
        for (unsigned int it = 0; it < 2; ++it)
          inv = _mm512_mul_pd(inv, _mm512_fnmadd_pd(h, _mm512_mul_pd(inv, inv),
                                                    _mm512_set1_pd(1.5)));
        const __m512d  dl   = _mm512_fmsub_pd(l2, inv, rb);
        const __mmask8 keep = _mm512_mask_cmp_pd_mask(alive, dl, s0r, _CMP_LE_OQ);
        brk                 = _mm512_mask_cmp_pd_mask(alive, dl, s0r, _CMP_GT_OQ);
        return _mm512_maskz_mul_pd(keep, _mm512_mul_pd(kb, dl), inv);
      }

      /**
       * NO positive stencil offsets hs[0], ... of a lattice sweep over the
       * groups of eight box positions of one chunk starting at c0 (a
       * multiple of 8): the groups c0 + 8 g for g = groups[0 .. n_groups)
       * (the chunk's groups with a live bit), or for g = 0 .. n_groups - 1
       * if @p groups is null. Bond (L, L + o_q) for every live bit
       * (hs[q], L) of the bit array @p live (n_bytes bytes per offset). p and
       * reaction are dim arrays of stride N over the box positions; the
       * force on L is accumulated in acc (dim arrays of stride C, indexed
       * from c0), the reaction on L + o in reaction (F = acc - reaction).
       * The offsets share the loads of p_L and the update of acc; they must
       * lie more than 8 apart (else the reaction update of one partially
       * overlaps the other's, and the store cannot be forwarded). o, k, r:
       * linear box offset, stiffness c omega beta V / |xi| and length |xi|
       * per offset. Newly broken bonds clear their bit and are appended to
       * @p broken (a vector of pairs) as (h, L).
       */
      template <int dim, int NO, typename Broken>
      inline void
      sweep_offsets(const double        *p,
                    double              *reaction,
                    double              *acc,
                    std::uint8_t        *live,
                    const std::size_t    n_bytes,
                    const std::size_t    N,
                    const unsigned int   C,
                    const std::size_t    c0,
                    const std::uint8_t  *groups,
                    const unsigned int   n_groups,
                    const std::int64_t  *o,
                    const unsigned int  *hs,
                    const double        *k,
                    const double        *r,
                    const double         s0,
                    Broken              &broken)
      {
        using Position = typename Broken::value_type::second_type;
        // Everything loop-invariant in locals (pointers per offset and
        // component, s0 r per offset), so that nothing is reloaded per vector.
        std::uint8_t *bits[NO];
        __m512d       vk[NO], vr[NO], vs0r[NO];
        const double *pj[NO][dim];
        double       *rj[NO][dim];
        const double *pi_[dim];
        double       *ai[dim];
        for (unsigned int d = 0; d < dim; ++d)
          {
            pi_[d] = p + d * N + c0;
            ai[d]  = acc + d * C;
          }
        for (int q = 0; q < NO; ++q)
          {
            bits[q] = live + hs[q] * n_bytes + c0 / 8;
            vk[q]   = _mm512_set1_pd(k[hs[q]]);
            vr[q]   = _mm512_set1_pd(r[hs[q]]);
            vs0r[q] = _mm512_mul_pd(_mm512_set1_pd(s0), vr[q]);
            for (unsigned int d = 0; d < dim; ++d)
              {
                pj[q][d] = pi_[d] + o[hs[q]];
                rj[q][d] = reaction + d * N + c0 + o[hs[q]];
              }
          }
        const auto group = [&](const unsigned int v) {
          __mmask8 alive[NO], any = 0;
#  pragma GCC unroll 4
          for (int q = 0; q < NO; ++q)
            any |= alive[q] = bits[q][v / 8];
          if (any == 0)
            return;
          __m512d pi[dim], f[dim];
          for (unsigned int d = 0; d < dim; ++d)
            {
              pi[d] = _mm512_loadu_pd(pi_[d] + v);
              f[d]  = _mm512_load_pd(ai[d] + v);
            }
          // Unrolled: the per-offset constants and pointers stay in
          // registers (a rolled loop reloads them from the stack per vector).
#  pragma GCC unroll 4
          for (int q = 0; q < NO; ++q)
            {
              if (alive[q] == 0)
                continue;
              __m512d y[dim];
              for (unsigned int d = 0; d < dim; ++d)
                y[d] = _mm512_sub_pd(_mm512_loadu_pd(pj[q][d] + v), pi[d]);
              __m512d l2 = _mm512_mul_pd(y[0], y[0]);
              for (unsigned int d = 1; d < dim; ++d)
                l2 = _mm512_fmadd_pd(y[d], y[d], l2);
              __mmask8      brk;
              const __m512d scale = pmb_bond_scale(l2, alive[q], vr[q], vk[q], vs0r[q], brk);
              for (unsigned int d = 0; d < dim; ++d)
                {
                  double *rd = rj[q][d] + v;
                  f[d]       = _mm512_fmadd_pd(scale, y[d], f[d]);
                  _mm512_storeu_pd(rd, _mm512_fmadd_pd(scale, y[d], _mm512_loadu_pd(rd)));
                }
              if (__builtin_expect(brk != 0, 0))
                {
                  bits[q][v / 8] = alive[q] & ~brk;
                  for (unsigned int l = 0; l < 8; ++l)
                    if ((brk >> l) & 1u)
                      broken.emplace_back(hs[q], Position(c0 + v + l));
                }
            }
          for (unsigned int d = 0; d < dim; ++d)
            _mm512_store_pd(ai[d] + v, f[d]);
        };
        if (groups != nullptr)
          for (unsigned int g = 0; g < n_groups; ++g)
            group(8 * groups[g]);
        else
          for (unsigned int g = 0; g < n_groups; ++g)
            group(8 * g);
      }
    } // namespace LatticeSweep
  }   // namespace internal
} // namespace PeriDEAL

#endif
#endif
