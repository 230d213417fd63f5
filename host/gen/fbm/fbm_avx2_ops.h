/* The lattice steps the hand-vectorised fBm loops share (fbm_avx2.c in the plane, fbm3_avx2.c on the
 * sphere), eight lanes at a time and bit-exact with kernels/noise.h: the same operations in the same
 * order, no FMA. Include only where <immintrin.h> is available (x86), after avx2_hash.h. */
#ifndef FB_FBM_AVX2_OPS_H
#define FB_FBM_AVX2_OPS_H

#include "avx2_hash.h"

#include "kernels/noise.h"

/* k_wrap_cell(i, K_NOISE_PERIOD) for 8 lanes: integer path below 2^24, the float path above, blended. */
AVX2 static inline __m256i wrap8(__m256 i)
{
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 small = _mm256_cmp_ps(_mm256_and_ps(i, absmask), _mm256_set1_ps(16777216.0f), _CMP_LT_OQ);
    __m256i mask = _mm256_set1_epi32((int)(K_NOISE_PERIOD - 1u));
    __m256i a = _mm256_and_si256(_mm256_cvttps_epi32(i), mask);
    /* every lane's lattice index is exact (an image's coarse octaves): the integer path alone */
    if (__builtin_expect(_mm256_movemask_ps(small) == 0xff, 1)) return a;
    __m256 fp = _mm256_set1_ps((float)K_NOISE_PERIOD);
    __m256 r = _mm256_sub_ps(
        i, _mm256_mul_ps(fp, _mm256_floor_ps(_mm256_mul_ps(i, _mm256_set1_ps(1.0f / (float)K_NOISE_PERIOD)))));
    r = _mm256_min_ps(_mm256_max_ps(r, _mm256_setzero_ps()), _mm256_set1_ps((float)K_NOISE_PERIOD - 1.0f));
    __m256i b = _mm256_and_si256(_mm256_cvttps_epi32(r), mask);
    return _mm256_blendv_epi8(b, a, _mm256_castps_si256(small));
}

/* k_cell_add(c, 1, K_NOISE_PERIOD) */
AVX2 static inline __m256i next8(__m256i c)
{
    return _mm256_and_si256(_mm256_add_epi32(c, _mm256_set1_epi32(1)), _mm256_set1_epi32((int)(K_NOISE_PERIOD - 1u)));
}

/* k_hash2i(seed, ix, iy) = hash((ix * 0x9e3779b1) ^ row), row = hash(iy ^ seed ^ 0x632be5ab) given */
AVX2 static inline __m256i cell_hash8(__m256i ix, __m256i row)
{
    return hash8(_mm256_xor_si256(_mm256_mullo_epi32(ix, _mm256_set1_epi32((int)0x9e3779b1u)), row));
}

/* k_fade */
AVX2 static inline __m256 fade8(__m256 t)
{
    __m256 inner =
        _mm256_add_ps(_mm256_mul_ps(t, _mm256_sub_ps(_mm256_mul_ps(t, _mm256_set1_ps(6.0f)), _mm256_set1_ps(15.0f))),
                      _mm256_set1_ps(10.0f));
    return _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(t, t), t), inner);
}

/* k_mix */
AVX2 static inline __m256 mix8(__m256 a, __m256 b, __m256 t)
{
    return _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), t));
}

/* k_clamp(x, lo, hi) = fminf(fmaxf(x, lo), hi): maxps and minps return the second operand for a
 * NaN, as fmaxf and fminf return the number */
AVX2 static inline __m256 clamp8(__m256 x, float lo, float hi)
{
    return _mm256_min_ps(_mm256_max_ps(x, _mm256_set1_ps(lo)), _mm256_set1_ps(hi));
}

/* k_u01: the top 24 bits as a float in [0, 1) */
AVX2 static inline __m256 u01_8(__m256i h)
{
    return _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(h, 8)), _mm256_set1_ps(1.0f / 16777216.0f));
}

#endif
