/*
 * A hand-vectorised AVX2 loop of the same fBm as kernels/fbm.h (gradient noise, standard shape, no
 * warp, not tileable), eight pixels of a row per step. It is the benchmark's reference for what a
 * CPU can do with this algorithm, and it is bit-exact with the kernel: the same operations in the
 * same order, no FMA (tests/test_avx2.c checks every pixel).
 */
#include "fbm_avx2.h"

#include "kernels/fbm.h"

#include <stdbool.h>

#if defined(__x86_64__) || defined(__i386__)
#include "fbm_avx2_ops.h"

AVX2 static inline __m256 grad8(__m256i h, __m256 x, __m256 y)
{
    __m256i b = _mm256_and_si256(h, _mm256_set1_epi32(7));
    __m256 lt4 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), b));
    __m256 u = _mm256_blendv_ps(y, x, lt4);
    __m256 v = _mm256_blendv_ps(x, y, lt4);
    /* bit 0 of b is the sign of u, bit 1 that of 2v: shifted into the sign bit (a negation is a
     * sign flip, exact) */
    __m256 su = _mm256_xor_ps(u, _mm256_castsi256_ps(_mm256_slli_epi32(b, 31)));
    __m256 v2 = _mm256_mul_ps(_mm256_set1_ps(2.0f), v);
    __m256 sv = _mm256_xor_ps(v2, _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_srli_epi32(b, 1), 31)));
    return _mm256_add_ps(su, sv);
}

AVX2 static inline __m256 gradient8(uint32_t seed, __m256 x, __m256 y)
{
    __m256 fx = _mm256_floor_ps(x), fy = _mm256_floor_ps(y);
    __m256 tx = _mm256_sub_ps(x, fx), ty = _mm256_sub_ps(y, fy);
    __m256i ix0 = wrap8(fx), iy0 = wrap8(fy);
    __m256i ix1 = next8(ix0), iy1 = next8(iy0);
    __m256i s = _mm256_set1_epi32((int)(seed ^ 0x632be5abu));
    __m256i r0 = hash8(_mm256_xor_si256(iy0, s)), r1 = hash8(_mm256_xor_si256(iy1, s));
    __m256 onef = _mm256_set1_ps(1.0f);
    __m256 tx1 = _mm256_sub_ps(tx, onef), ty1 = _mm256_sub_ps(ty, onef);
    __m256 n00 = grad8(cell_hash8(ix0, r0), tx, ty);
    __m256 n10 = grad8(cell_hash8(ix1, r0), tx1, ty);
    __m256 n01 = grad8(cell_hash8(ix0, r1), tx, ty1);
    __m256 n11 = grad8(cell_hash8(ix1, r1), tx1, ty1);
    __m256 u = fade8(tx), v = fade8(ty);
    return _mm256_mul_ps(_mm256_set1_ps(0.6324555f), mix8(mix8(n00, n10, u), mix8(n01, n11, u), v));
}

AVX2 static void rows_avx2(const K_FbmParams *p, int y0, int n, float *out)
{
    uint32_t seed = k_hash3(p->seed, 0u, 0x0fb0u);
    /* the per-octave constants, once: each octave's noise seed, amplitude and offset */
    uint32_t oct_seed[32];
    float oct_amp[32], oct_ox[32], oct_oy[32], amp = 1.0f;
    const uint32_t octaves = p->octaves < 32 ? p->octaves : 32;
    for (uint32_t i = 0; i < octaves; i++) {
        uint32_t h = k_hash(seed + i * 0x9e3779b9u), ho = k_hash(h ^ 0x5bd1e995u);
        oct_seed[i] = h, oct_amp[i] = amp;
        oct_ox[i] = (float)(ho & 0xffffu) * (64.0f / 65536.0f);
        oct_oy[i] = (float)(ho >> 16) * (64.0f / 65536.0f);
        amp *= p->gain;
    }
    const __m256 L = _mm256_set1_ps(p->lacunarity), c = _mm256_set1_ps(p->rot_c), s = _mm256_set1_ps(p->rot_s);
    for (int r = 0; r < n; r++) {
        float v = 1.0f - ((float)(y0 + r) + 0.5f) * p->inv_height;
        float *row = out + (size_t)r * p->width;
        uint32_t x0 = 0;
        for (; x0 + 8 <= p->width; x0 += 8) {
            __m256 px = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32((int)x0),
                                                                          _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7))),
                                      _mm256_set1_ps(0.5f));
            __m256 u = _mm256_mul_ps(px, _mm256_set1_ps(p->inv_width));
            __m256 x = _mm256_add_ps(_mm256_mul_ps(u, _mm256_set1_ps(p->freq_x)), _mm256_set1_ps(p->offset_x));
            __m256 y = _mm256_set1_ps(v * p->freq_y + p->offset_y);
            __m256 sum = _mm256_setzero_ps();
            for (uint32_t i = 0; i < octaves; i++) {
                sum = _mm256_add_ps(sum, _mm256_mul_ps(_mm256_set1_ps(oct_amp[i]), gradient8(oct_seed[i], x, y)));
                __m256 nx = _mm256_mul_ps(L, _mm256_sub_ps(_mm256_mul_ps(c, x), _mm256_mul_ps(s, y)));
                __m256 ny = _mm256_mul_ps(L, _mm256_add_ps(_mm256_mul_ps(s, x), _mm256_mul_ps(c, y)));
                x = _mm256_add_ps(nx, _mm256_set1_ps(oct_ox[i]));
                y = _mm256_add_ps(ny, _mm256_set1_ps(oct_oy[i]));
            }
            _mm256_storeu_ps(row + x0, sum);
        }
        for (; x0 < p->width; x0++) row[x0] = k_fbm_pixel(*p, x0, (uint32_t)(y0 + r));
    }
}

bool fb_fbm_avx2_supported(const void *params)
{
    const K_FbmParams *p = params;
    return __builtin_cpu_supports("avx2") && p->noise == K_NOISE_GRADIENT && p->flags == 0u && p->warp == 0.0f;
}

void fb_fbm_avx2_rows(const void *params, int y0, int n, float *out)
{
    rows_avx2(params, y0, n, out);
}

#else

bool fb_fbm_avx2_supported(const void *params)
{
    (void)params;
    return false;
}

void fb_fbm_avx2_rows(const void *params, int y0, int n, float *out)
{
    (void)params, (void)y0, (void)n, (void)out;
}

#endif
