/*
 * A hand-vectorised AVX2 escape-time loop for the Julia benchmark: eight pixels of a row at a time,
 * the same per-iteration work as kernels/julia.h (z <- z^2 + c and |z'|^2 <- 4 |z|^2 |z'|^2),
 * the same start point and allpass warp, with the same operations in the same order, so the escape
 * counts are bit-identical to the kernel's (tests/test_avx2.c). The per-pixel tail (smooth count,
 * distance, colour) is left out: at hundreds of iterations per pixel it is a small share.
 */
#include "julia_avx2.h"

#include "kernels/julia.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

#define AVX2 __attribute__((target("avx2")))

AVX2 static void rows_avx2(const K_JuliaParams *p, int y0, int n, uint32_t *out, uint64_t *total)
{
    const __m256 two = _mm256_set1_ps(2.0f), one = _mm256_set1_ps(1.0f);
    const __m256 are = _mm256_set1_ps(p->a_re), aim = _mm256_set1_ps(p->a_im);
    const __m256 cre = _mm256_set1_ps(p->c_re), cim = _mm256_set1_ps(p->c_im);
    const __m256 bail2 = _mm256_set1_ps(p->bailout2);
    const __m256 rc = _mm256_set1_ps(p->rot_c), rs = _mm256_set1_ps(p->rot_s);
    const float kk = 1.0f - (p->a_re * p->a_re + p->a_im * p->a_im);
    const float dx = p->scale_u * p->inv_width, dpx = p->rot_c * dx - p->rot_s * 0.0f,
                dpy = p->rot_s * dx + p->rot_c * 0.0f;
    uint64_t sum = 0;
    for (int r = 0; r < n; r++) {
        float v = 1.0f - ((float)(y0 + r) + 0.5f) * p->inv_height;
        float yy = p->scale_v * (v - 0.5f);
        uint32_t *row = out + (size_t)r * p->width;
        uint32_t x0 = 0;
        for (; x0 + 8 <= p->width; x0 += 8) {
            __m256 fx = _mm256_add_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32((int)x0),
                                                                          _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7))),
                                      _mm256_set1_ps(0.5f));
            __m256 u = _mm256_mul_ps(fx, _mm256_set1_ps(p->inv_width));
            __m256 xx = _mm256_mul_ps(_mm256_set1_ps(p->scale_u), _mm256_sub_ps(u, _mm256_set1_ps(0.5f)));
            __m256 Y = _mm256_set1_ps(yy);
            __m256 px =
                _mm256_add_ps(_mm256_set1_ps(p->center_re), _mm256_sub_ps(_mm256_mul_ps(rc, xx), _mm256_mul_ps(rs, Y)));
            __m256 py =
                _mm256_add_ps(_mm256_set1_ps(p->center_im), _mm256_add_ps(_mm256_mul_ps(rs, xx), _mm256_mul_ps(rc, Y)));
            /* z0 = (p - conj(a)) / (1 - a p) and its derivative, as in k_julia_orbit */
            __m256 nr = _mm256_sub_ps(px, are), ni = _mm256_add_ps(py, aim);
            __m256 dr = _mm256_sub_ps(one, _mm256_sub_ps(_mm256_mul_ps(are, px), _mm256_mul_ps(aim, py)));
            __m256 di =
                _mm256_sub_ps(_mm256_setzero_ps(), _mm256_add_ps(_mm256_mul_ps(are, py), _mm256_mul_ps(aim, px)));
            __m256 den = _mm256_add_ps(_mm256_mul_ps(dr, dr), _mm256_mul_ps(di, di));
            __m256 ok = _mm256_cmp_ps(den, _mm256_set1_ps(1.0e-30f), _CMP_GT_OQ);
            __m256 inv = _mm256_div_ps(one, den);
            __m256 zr = _mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(nr, dr), _mm256_mul_ps(ni, di)), inv),
                                      _mm256_setzero_ps());
            __m256 zi = _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(ni, dr), _mm256_mul_ps(nr, di)), inv),
                                      _mm256_setzero_ps());
            __m256 inv2 = _mm256_mul_ps(inv, inv);
            __m256 sr = _mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(dr, dr), _mm256_mul_ps(di, di)), inv2);
            __m256 si = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(-2.0f), dr), di), inv2);
            __m256 wr = _mm256_mul_ps(_mm256_set1_ps(kk), sr), wi = _mm256_mul_ps(_mm256_set1_ps(kk), si);
            __m256 dzr = _mm256_sub_ps(_mm256_mul_ps(wr, _mm256_set1_ps(dpx)), _mm256_mul_ps(wi, _mm256_set1_ps(dpy)));
            __m256 dzi = _mm256_add_ps(_mm256_mul_ps(wr, _mm256_set1_ps(dpy)), _mm256_mul_ps(wi, _mm256_set1_ps(dpx)));
            __m256 dz2 = _mm256_add_ps(_mm256_mul_ps(dzr, dzr), _mm256_mul_ps(dzi, dzi));
            __m256 r2 = _mm256_add_ps(_mm256_mul_ps(zr, zr), _mm256_mul_ps(zi, zi));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(r2, _mm256_set1_ps(1.0e30f), _CMP_LT_OQ));
            /* lanes at the pole or beyond 1e30 escape before the first iteration */
            __m256 done = _mm256_xor_ps(ok, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
            __m256i cnt = _mm256_setzero_si256();
            for (uint32_t i = 0; i < p->max_iter; i++) {
                r2 = _mm256_add_ps(_mm256_mul_ps(zr, zr), _mm256_mul_ps(zi, zi));
                done = _mm256_or_ps(done, _mm256_cmp_ps(r2, bail2, _CMP_GE_OQ));
                if (_mm256_movemask_ps(done) == 0xff) break;
                cnt = _mm256_sub_epi32(
                    cnt, _mm256_castps_si256(_mm256_xor_ps(done, _mm256_castsi256_ps(_mm256_set1_epi32(-1)))));
                dz2 = _mm256_mul_ps(dz2, _mm256_mul_ps(_mm256_set1_ps(4.0f), r2));
                __m256 xr = _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(zr, zr), _mm256_mul_ps(zi, zi)), cre);
                zi = _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(two, zr), zi), cim);
                zr = xr;
            }
            _mm256_storeu_si256((__m256i *)(row + x0), cnt);
        }
        for (; x0 < p->width; x0++) {
            K_FbmParams none = {0};
            row[x0] = k_julia_pixel(*p, none, x0, (uint32_t)(y0 + r)).iter;
        }
        for (uint32_t x = 0; x < p->width; x++) sum += row[x];
    }
    if (total) *total += sum;
}

bool fb_julia_avx2_supported(const void *params)
{
    const K_JuliaParams *p = params;
    return __builtin_cpu_supports("avx2") && p->mapping == K_JULIA_RECT && p->lambda == 0.0f;
}

void fb_julia_avx2_rows(const void *params, int y0, int n, uint32_t *iter, uint64_t *total)
{
    rows_avx2(params, y0, n, iter, total);
}

#else

bool fb_julia_avx2_supported(const void *params)
{
    (void)params;
    return false;
}

void fb_julia_avx2_rows(const void *params, int y0, int n, uint32_t *iter, uint64_t *total)
{
    (void)params, (void)y0, (void)n, (void)iter, (void)total;
}

#endif
