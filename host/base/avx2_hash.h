/* k_hash (kernels/hash.h, lowbias32) on eight lanes, for the hand-vectorised AVX2 loops. Include
 * only where <immintrin.h> is available (x86). */
#ifndef FB_AVX2_HASH_H
#define FB_AVX2_HASH_H

#include <immintrin.h>

#define AVX2 __attribute__((target("avx2")))

AVX2 static inline __m256i hash8(__m256i x)
{
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
    x = _mm256_mullo_epi32(x, _mm256_set1_epi32(0x7feb352d));
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 15));
    x = _mm256_mullo_epi32(x, _mm256_set1_epi32((int)0x846ca68bu));
    x = _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
    return x;
}

#endif
