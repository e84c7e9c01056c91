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

#  include <deal.II/base/exceptions.h>

#  include <array>
#  include <cstddef>
#  include <cstdint>
#  include <vector>

#  define PERIDEAL_LATTICE_SWEEP_AVX512 1

namespace PeriDEAL
{
  namespace internal
  {
    namespace LatticeSweep
    {
      /**
       * Places the nodes in the sweep box: position[i] is the linear box index
       * of node i (lattice index minus lower, times stride), node[L] the node at
       * box index L or -1 (n_box entries).
       */
      template <int dim>
      inline void
      map_box_positions(const std::vector<std::array<int, dim>> &lattice_index,
                        const std::array<int, dim>              &lower,
                        const std::array<std::int64_t, dim>     &stride,
                        const std::size_t                        n_box,
                        std::vector<std::uint32_t>              &position,
                        std::vector<std::int32_t>               &node)
      {
        position.resize(lattice_index.size());
        node.assign(n_box, -1);
        for (std::size_t i = 0; i < lattice_index.size(); ++i)
          {
            std::int64_t L = 0;
            for (unsigned int d = 0; d < dim; ++d)
              L += std::int64_t(lattice_index[i][d] - lower[d]) * stride[d];
            AssertThrow(node[L] < 0, dealii::ExcMessage("Two nodes share a lattice position."));
            position[i] = L;
            node[L]     = i;
          }
      }

      /**
       * The live bits of a lattice sweep: bit L % 8 of byte
       * live[slot(h) * slot_stride + (L / 8) * group_stride] is set if bond
       * (L, L + o_h) exists and is not broken; slot(h) = slot[h], or h if
       * @p slot is null. One bit array per offset is {live, n_bytes, 1,
       * nullptr}; the operator's layout puts the bytes of all offsets of a
       * group of eight positions next to each other (slot_stride 1), so that
       * a chunk's bits are one sequential stream.
       */
      struct LiveBits
      {
        std::uint8_t       *live;
        std::size_t         slot_stride;
        std::size_t         group_stride;
        const unsigned int *slot;
      };

      /**
       * The PMB bond of eight lanes given l2 = |y|^2, the stiffnesses kb,
       * kr = kb rb (rb the lengths) and t2 = (rb + s0 rb)^2: sets brk to the
       * alive lanes with l > (1 + s0) r, i.e. l2 > t2 (2.34), and returns
       * k (l - r) / l = k - kr / l for the alive, unbroken lanes (0 for the
       * others). The breaking test needs no square root, so it is off the
       * critical path; the force is one fused k - kr inv after the inverse
       * length. 1/l: vrsqrt14pd (relative error e0 < 2^-14) and one
       * fourth-order step inv (1 + e/2 + 3e^2/8 + 5e^3/16), e = 1 - l2 inv^2
       * (truncation 35/128 e^4 < 1e-16; measured max relative error 1.6e-16
       * over 1.6e7 random l2, the two Newton steps it replaces 2.7e-16):
       * the divider is the bottleneck of sqrt + div (doc/benchmarks.md).
       * Every PMB loop (full list, half list, ghost list, lattice sweeps)
       * calls this, so all of them see bitwise the same stretch of a bond
       * and break it together. The unbroken lanes come from a second
       * comparison rather than alive & ~brk, which would round-trip the
       * mask through a general register on the critical path.
       */
      inline __m512d
      pmb_scale_of_length2(const __m512d  l2,
                           const __mmask8 keep,
                           const __m512d  kb,
                           const __m512d  kr)
      {
        const __m512d y = _mm512_rsqrt14_pd(l2);
        const __m512d e = _mm512_fnmadd_pd(_mm512_mul_pd(l2, y), y, _mm512_set1_pd(1.));
        __m512d       c = _mm512_fmadd_pd(e, _mm512_set1_pd(5. / 16.), _mm512_set1_pd(3. / 8.));
        c               = _mm512_fmadd_pd(c, e, _mm512_set1_pd(0.5));
        const __m512d inv = _mm512_fmadd_pd(_mm512_mul_pd(y, e), c, y);
        return _mm512_maskz_fnmadd_pd(keep, kr, inv, kb);
      }

      /**
       * With @p blend_dead_lanes = false the lanes outside @p alive are not
       * blended to l2 = 1 (one instruction less per bond): they may compute
       * inf or NaN internally but return 0 like the others, and the alive
       * lanes get bitwise the same scale. Only for loops in which a dead lane
       * never traps (the default floating-point environment).
       */
      template <bool blend_dead_lanes = true>
      inline __m512d
      pmb_bond_scale_kr(__m512d        l2,
                        const __mmask8 alive,
                        const __m512d  kb,
                        const __m512d  kr,
                        const __m512d  t2,
                        __mmask8      &brk)
      {
        brk                 = _mm512_mask_cmp_pd_mask(alive, l2, t2, _CMP_GT_OQ);
        const __mmask8 keep = _mm512_mask_cmp_pd_mask(alive, l2, t2, _CMP_LE_OQ);
        // Masked-off and broken lanes get l2 = 1 to keep inv finite.
        if constexpr (blend_dead_lanes)
          l2 = _mm512_mask_blend_pd(alive, _mm512_set1_pd(1.), l2);
        return pmb_scale_of_length2(l2, keep, kb, kr);
      }

      /**
       * The per-offset constants of pmb_bond_scale_kr() for the length rb:
       * kr = kb rb and t2 = (rb + s0 rb)^2, by the operations of
       * pmb_bond_scale() and sweep_offsets() (bitwise the same values).
       */
      inline void
      pmb_offset_constants(const double rb, const double kb, const double s0, double &kr, double &t2)
      {
        const __m512d vr = _mm512_set1_pd(rb);
        const __m512d t  = _mm512_add_pd(vr, _mm512_mul_pd(_mm512_set1_pd(s0), vr));
        kr               = _mm512_cvtsd_f64(_mm512_mul_pd(_mm512_set1_pd(kb), vr));
        t2               = _mm512_cvtsd_f64(_mm512_mul_pd(t, t));
      }

      /**
       * pmb_bond_scale_kr() given the lengths rb and s0r = s0 rb instead of
       * kr and t2 (computed here by the same operations as the sweep's
       * per-offset constants, so the results are bitwise the same).
       */
      inline __m512d
      pmb_bond_scale(const __m512d  l2,
                     const __mmask8 alive,
                     const __m512d  rb,
                     const __m512d  kb,
                     const __m512d  s0r,
                     __mmask8      &brk)
      {
        const __m512d t = _mm512_add_pd(rb, s0r);
        return pmb_bond_scale_kr(l2, alive, kb, _mm512_mul_pd(kb, rb), _mm512_mul_pd(t, t), brk);
      }

      /**
       * The stream pointers of a sweep over the chunk at c0 (P: positions,
       * Rb: reactions, both from c0; A: the chunk's force accumulator) and,
       * per offset hs[q], its bit slot offset and the constants of
       * pmb_bond_scale_kr() (k, k r, (r + s0 r)^2), shared by
       * sweep_offsets() and sweep_offset_pairs().
       */
      template <int dim, int n_offsets>
      inline __attribute__((always_inline)) void
      sweep_setup(const double       *p,
                  double             *reaction,
                  double             *acc,
                  const LiveBits     &bits,
                  const std::size_t   N,
                  const unsigned int  C,
                  const std::size_t   c0,
                  const unsigned int *hs,
                  const double       *k,
                  const double       *r,
                  const double        s0,
                  const double       *(&P)[dim],
                  double             *(&Rb)[dim],
                  double             *(&A)[dim],
                  std::size_t (&bq)[n_offsets],
                  double (&cst)[n_offsets][3])
      {
        for (unsigned int d = 0; d < dim; ++d)
          {
            P[d]  = p + d * N + c0;
            Rb[d] = reaction + d * N + c0;
            A[d]  = acc + d * C;
          }
        for (int q = 0; q < n_offsets; ++q)
          {
            bq[q] = std::size_t(bits.slot ? bits.slot[hs[q]] : hs[q]) * bits.slot_stride;
            pmb_offset_constants(r[hs[q]], k[hs[q]], s0, cst[q][1], cst[q][2]);
            cst[q][0] = k[hs[q]];
          }
      }

      /**
       * pmb_bond_scale_kr() without the dead-lane blend, the constants c of
       * sweep_setup() read as embedded broadcasts.
       */
      inline __attribute__((always_inline)) __m512d
      sweep_bond_scale(const __m512d l2, const __mmask8 alive, const double *c, __mmask8 &brk)
      {
        return pmb_bond_scale_kr<false>(
          l2, alive, _mm512_set1_pd(c[0]), _mm512_set1_pd(c[1]), _mm512_set1_pd(c[2]), brk);
      }

      /**
       * NO positive stencil offsets hs[0], ... of a lattice sweep over the
       * groups of eight box positions of one chunk starting at c0 (a
       * multiple of 8): the groups c0 + 8 g for g = groups[0 .. n_groups)
       * (the chunk's groups with a live bit), or for g = 0 .. n_groups - 1
       * if @p groups is null. Bond (L, L + o_q) for every live bit
       * (hs[q], L) of the bit array @p bits (see LiveBits). p and
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
      // Not inlined: inlined into the caller's chunk loop, GCC spilled the
      // stream pointers and masks (the same code ran 10 % slower, CPU time
      // of pmb_benchmark --chunks, doc/benchmarks.md session 7).
      template <int dim, int NO, typename Broken>
      __attribute__((noinline)) void
      sweep_offsets(const double        *p,
                    double              *reaction,
                    double              *acc,
                    const LiveBits      &bits,
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
        // One base pointer per component and stream (p_L, reaction, acc,
        // bits) and the offsets as indices: 4 offsets x 3 components of
        // precomputed p_{L+o} and reaction pointers did not fit the general
        // registers, and their spills cost 6-7 % (doc/benchmarks.md,
        // session 7). The empty asm keeps GCC from hoisting base + offset
        // out of the loop again. Per offset: k, k r and (r + s0 r)^2.
        // The per-offset constants are read from memory as embedded
        // broadcasts (8-byte loads) through a base pointer that the loop
        // cannot hoist: as 3 NO zmm values GCC spilled them, and reloaded
        // each as a 64-byte vector per bond vector (4 of the ~16 loads).
        const std::size_t   gs = bits.group_stride;
        std::uint8_t *const B  = bits.live + c0 / 8 * gs;
        std::size_t         bq[NO];
        std::int64_t        oq[NO];
        double              cst[NO][3]; // k, k r, (r + s0 r)^2
        const double       *P[dim];
        double             *Rb[dim], *A[dim];
        sweep_setup<dim, NO>(p, reaction, acc, bits, N, C, c0, hs, k, r, s0, P, Rb, A, bq, cst);
        for (int q = 0; q < NO; ++q)
          oq[q] = o[hs[q]];
        const auto group = [&](const std::size_t v) {
          __mmask8      alive[NO], any = 0;
          std::uint8_t *const Bv = B + v / 8 * gs;
#  pragma GCC unroll 4
          for (int q = 0; q < NO; ++q)
            any |= alive[q] = Bv[bq[q]];
          if (any == 0)
            return;
          const double(*c)[3] = cst;
          asm("" : "+r"(c));
          __m512d pi[dim], f[dim];
          for (unsigned int d = 0; d < dim; ++d)
            {
              pi[d] = _mm512_loadu_pd(P[d] + v);
              f[d]  = _mm512_load_pd(A[d] + v);
            }
          // Unrolled: the per-offset constants stay in registers (a rolled
          // loop reloads them from the stack per vector).
#  pragma GCC unroll 4
          for (int q = 0; q < NO; ++q)
            {
              if (alive[q] == 0)
                continue;
              std::int64_t j = std::int64_t(v) + oq[q];
              asm("" : "+r"(j));
              __m512d y[dim];
              for (unsigned int d = 0; d < dim; ++d)
                y[d] = _mm512_sub_pd(_mm512_loadu_pd(P[d] + j), pi[d]);
              __m512d l2 = _mm512_mul_pd(y[0], y[0]);
              for (unsigned int d = 1; d < dim; ++d)
                l2 = _mm512_fmadd_pd(y[d], y[d], l2);
              __mmask8      brk;
              // Dead lanes need no blend: they may compute inf or NaN, but
              // return 0 (the default floating-point environment).
              const __m512d scale = sweep_bond_scale(l2, alive[q], c[q], brk);
              for (unsigned int d = 0; d < dim; ++d)
                {
                  double *rd = Rb[d] + j;
                  f[d]       = _mm512_fmadd_pd(scale, y[d], f[d]);
                  _mm512_storeu_pd(rd, _mm512_fmadd_pd(scale, y[d], _mm512_loadu_pd(rd)));
                }
              if (__builtin_expect(brk != 0, 0))
                {
                  Bv[bq[q]] = alive[q] & ~brk;
                  for (unsigned int l = 0; l < 8; ++l)
                    if ((brk >> l) & 1u)
                      broken.emplace_back(hs[q], Position(c0 + v + l));
                }
            }
          for (unsigned int d = 0; d < dim; ++d)
            _mm512_store_pd(A[d] + v, f[d]);
        };
        if (groups != nullptr)
          for (unsigned int g = 0; g < n_groups; ++g)
            group(8 * groups[g]);
        else
          for (unsigned int g = 0; g < n_groups; ++g)
            group(8 * g);
      }

      /**
       * The body of a paired pass of a lattice sweep: the NO offset pairs
       * (hs[q], hs[NO + q]) with o[hs[NO + q]] = o[hs[q]] + @p delta
       * (@p delta > 0 a multiple of 8) over the groups g = g_begin ..
       * g_end - 1 of the chunk at c0 (g_begin >= delta / 8): offset hs[q]
       * from the group's positions v = 8 g, offset hs[NO + q] from
       * v - delta. Both bonds of a pair end at the same positions v + o_q,
       * so their reactions are summed in registers and stored once (one
       * unaligned read-modify-write per two bond vectors instead of one
       * per vector, and two force updates per 2 NO vectors); the groups
       * below g_begin (first offsets) and the last delta / 8 groups (second
       * offsets) are the caller's, e.g. sweep_offsets() on either half. The
       * arguments and the arithmetic of a bond are those of sweep_offsets()
       * (bitwise the same stretch, scale and breaking); only the order in
       * which the forces and reactions of different offsets are summed
       * differs. All bonds of a group pair are evaluated when any of its
       * bits is set (the dead lanes contribute 0).
       */
      template <int dim, int NO, typename Broken>
      __attribute__((noinline)) void
      sweep_offset_pairs(const double        *p,
                         double              *reaction,
                         double              *acc,
                         const LiveBits      &bits,
                         const std::size_t    N,
                         const unsigned int   C,
                         const std::size_t    c0,
                         const unsigned int   g_begin,
                         const unsigned int   g_end,
                         const std::int64_t  *o,
                         const unsigned int  *hs,
                         const std::int64_t   delta,
                         const double        *k,
                         const double        *r,
                         const double         s0,
                         Broken              &broken)
      {
        using Position = typename Broken::value_type::second_type;
        Assert(delta > 0 && delta % 8 == 0 && std::int64_t(g_begin) >= delta / 8,
               dealii::ExcInternalError());
        // The layout of sweep_offsets() (one base pointer per stream, the
        // constants as embedded broadcasts through an opaque pointer).
        const std::size_t   gs = bits.group_stride;
        std::uint8_t *const B  = bits.live + c0 / 8 * gs;
        std::size_t         bq[2 * NO];
        std::int64_t        oq[NO];
        double              cst[2 * NO][3]; // k, k r, (r + s0 r)^2
        const double       *P[dim];
        double             *Rb[dim], *A[dim];
        sweep_setup<dim, 2 * NO>(p, reaction, acc, bits, N, C, c0, hs, k, r, s0, P, Rb, A, bq, cst);
        for (int q = 0; q < NO; ++q)
          {
            oq[q] = o[hs[q]];
            Assert(o[hs[NO + q]] == oq[q] + delta, dealii::ExcInternalError());
          }
        const std::size_t dbits = delta / 8 * gs;
        for (std::size_t g = g_begin; g < g_end; ++g)
          {
            const std::size_t   v  = 8 * g;
            std::uint8_t *const Ba = B + g * gs, *const Bb = Ba - dbits;
            __mmask8            alive[2 * NO], any = 0;
#  pragma GCC unroll 4
            for (int q = 0; q < NO; ++q)
              {
                any |= alive[q] = Ba[bq[q]];
                any |= alive[NO + q] = Bb[bq[NO + q]];
              }
            if (any == 0)
              continue;
            const double(*c)[3] = cst;
            asm("" : "+r"(c));
            __m512d pa[dim], fa[dim], pb[dim], fb[dim];
            for (unsigned int d = 0; d < dim; ++d)
              {
                pa[d] = _mm512_loadu_pd(P[d] + v);
                fa[d] = _mm512_load_pd(A[d] + v);
                pb[d] = _mm512_loadu_pd(P[d] + v - delta);
                fb[d] = _mm512_load_pd(A[d] + v - delta);
              }
#  pragma GCC unroll 4
            for (int q = 0; q < NO; ++q)
              {
                if ((alive[q] | alive[NO + q]) == 0)
                  continue;
                std::int64_t j = std::int64_t(v) + oq[q];
                asm("" : "+r"(j));
                __m512d ya[dim], yb[dim];
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    const __m512d pj = _mm512_loadu_pd(P[d] + j);
                    ya[d]            = _mm512_sub_pd(pj, pa[d]);
                    yb[d]            = _mm512_sub_pd(pj, pb[d]);
                  }
                __m512d la = _mm512_mul_pd(ya[0], ya[0]), lb = _mm512_mul_pd(yb[0], yb[0]);
                for (unsigned int d = 1; d < dim; ++d)
                  {
                    la = _mm512_fmadd_pd(ya[d], ya[d], la);
                    lb = _mm512_fmadd_pd(yb[d], yb[d], lb);
                  }
                __mmask8      brka, brkb;
                const __m512d sa = sweep_bond_scale(la, alive[q], c[q], brka);
                const __m512d sb = sweep_bond_scale(lb, alive[NO + q], c[NO + q], brkb);
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    double *rd = Rb[d] + j;
                    fa[d]      = _mm512_fmadd_pd(sa, ya[d], fa[d]);
                    fb[d]      = _mm512_fmadd_pd(sb, yb[d], fb[d]);
                    _mm512_storeu_pd(rd,
                                     _mm512_fmadd_pd(sb,
                                                     yb[d],
                                                     _mm512_fmadd_pd(sa, ya[d], _mm512_loadu_pd(rd))));
                  }
                if (__builtin_expect((brka | brkb) != 0, 0))
                  {
                    Ba[bq[q]]      = alive[q] & ~brka;
                    Bb[bq[NO + q]] = alive[NO + q] & ~brkb;
                    for (unsigned int l = 0; l < 8; ++l)
                      {
                        if ((brka >> l) & 1u)
                          broken.emplace_back(hs[q], Position(c0 + v + l));
                        if ((brkb >> l) & 1u)
                          broken.emplace_back(hs[NO + q], Position(c0 + v - delta + l));
                      }
                  }
              }
            for (unsigned int d = 0; d < dim; ++d)
              {
                _mm512_store_pd(A[d] + v, fa[d]);
                _mm512_store_pd(A[d] + v - delta, fb[d]);
              }
          }
      }
    } // namespace LatticeSweep
  }   // namespace internal
} // namespace PeriDEAL

#endif
#endif
