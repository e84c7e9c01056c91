#ifndef perideal_models_pmb_bond_h
#define perideal_models_pmb_bond_h

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__)
#  include <immintrin.h>

namespace PeriDEAL
{
  namespace internal
  {
    /**
     * The PMB bond of eight lanes (AVX-512) given l2 = |y|^2, the lengths
     * rb, the stiffnesses kb and s0r = s0 rb: sets brk to the alive lanes
     * with l - r > s0 r (2.34) and returns k (l - r) / l for the alive,
     * unbroken lanes (0 for the others). 1/l by vrsqrt14pd (relative error
     * < 2^-14) and two Newton steps inv <- inv (3/2 - l2/2 inv^2) (error
     * ~1e-16), l - r by one fused multiply-subtract: every loop that calls
     * this sees bitwise the same stretch of a bond and breaks it at the same
     * step. The same arithmetic as pmb_bond_scale() in bond_based.cc (which
     * can include this header instead of its copy).
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
      l2              = _mm512_mask_blend_pd(alive, _mm512_set1_pd(1.), l2);
      const __m512d h = _mm512_mul_pd(_mm512_set1_pd(0.5), l2);
      __m512d       inv = _mm512_rsqrt14_pd(l2);
      for (unsigned int it = 0; it < 2; ++it)
        inv = _mm512_mul_pd(inv,
                            _mm512_fnmadd_pd(h, _mm512_mul_pd(inv, inv), _mm512_set1_pd(1.5)));
      const __m512d  dl   = _mm512_fmsub_pd(l2, inv, rb);
      const __mmask8 keep = _mm512_mask_cmp_pd_mask(alive, dl, s0r, _CMP_LE_OQ);
      brk                 = _mm512_mask_cmp_pd_mask(alive, dl, s0r, _CMP_GT_OQ);
      return _mm512_maskz_mul_pd(keep, _mm512_mul_pd(kb, dl), inv);
    }
  } // namespace internal
} // namespace PeriDEAL
#endif

#endif
