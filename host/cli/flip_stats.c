/*
 * FLIP's statistics (flip.h): the automatic exposure range of HDR-FLIP from the reference's
 * luminances, and the pooled error (mean, weighted median and quartiles). Both sort a million
 * values per image, so they sort by radix: the floats' bits made unsigned-monotone, three passes
 * of 11 bits, the same order as a comparison sort.
 */
#include "flip.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ACES (Narkowicz) as a rational (c0 x^2 + c1 x + c2) / (c3 x^2 + c4 x + c5), the pre-exposure 0.6 folded in
 * (as in flip.c). */
static const float ACES[6] = {0.6f * 0.6f * 2.51f, 0.6f * 0.03f, 0.0f, 0.6f * 0.6f * 2.43f, 0.6f * 0.59f, 0.14f};

static uint32_t float_key(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u & 0x80000000u ? ~u : u | 0x80000000u;
}

static float key_float(uint32_t k)
{
    uint32_t u = k & 0x80000000u ? k & 0x7fffffffu : ~k;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Sorts v (n values, no NaN) ascending. */
static fb_result sort_floats(float *v, size_t n)
{
    uint32_t *a = malloc((n ? n : 1) * sizeof *a), *b = malloc((n ? n : 1) * sizeof *b);
    if (!a || !b) {
        free(a);
        free(b);
        return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
    }
    for (size_t i = 0; i < n; i++) a[i] = float_key(v[i]);
    for (int shift = 0; shift < 32; shift += 11) {
        size_t count[2048] = {0}, at = 0;
        for (size_t i = 0; i < n; i++) count[(a[i] >> shift) & 2047]++;
        for (int d = 0; d < 2048; d++) {
            size_t c = count[d];
            count[d] = at, at += c;
        }
        for (size_t i = 0; i < n; i++) b[count[(a[i] >> shift) & 2047]++] = a[i];
        uint32_t *t = a;
        a = b, b = t;
    }
    for (size_t i = 0; i < n; i++) v[i] = key_float(a[i]);
    free(a);
    free(b);
    return FB_OK;
}

static float luminance(float r, float g, float b)
{
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

/* The median of sorted[0..n) (the mean of the middle two when n is even), as the published tool takes it. */
static float median_of(const float *sorted, size_t n)
{
    return n == 0 ? 0 : n >= 2 ? (sorted[n / 2 - 1] + sorted[n / 2]) * 0.5f : sorted[0];
}

fb_result fb_flip_exposures(const float *const ref[3], size_t n, float *start, float *stop, int *nexp,
                            bool *zero_median)
{
    /* the larger root of (c0 - t c3) x^2 + (c1 - t c4) x + (c2 - t c5) = 0: where ACES reaches t = 0.85 */
    float t = 0.85f, a = ACES[0] - t * ACES[3], b = ACES[1] - t * ACES[4], c = ACES[2] - t * ACES[5];
    float d1 = -0.5f * (b / a), d2 = sqrtf(d1 * d1 - c / a), xmax = d1 + d2;
    float *lum = malloc((n ? n : 1) * sizeof *lum);
    if (!lum) return fb_fail(FB_ERR_NOMEM, "out of memory for HDR-FLIP's exposures");
    float ymax = -1e30f, ymed = 0;
    *zero_median = false;
    for (size_t i = 0; i < n; i++) {
        lum[i] = luminance(ref[0][i], ref[1][i], ref[2][i]);
        if (isnan(lum[i])) lum[i] = 0; /* non-finite pixels count as black for the range */
        ymax = fmaxf(ymax, lum[i]);
    }
    fb_result rc = sort_floats(lum, n);
    if (rc) {
        free(lum);
        return rc;
    }
    ymed = median_of(lum, n);
    if (n > 0 &&
        !(ymed > 0)) { /* the published tool's stop exposure would be +inf here: take the positive ones' median */
        *zero_median = true;
        size_t p = 0;
        while (p < n && !(lum[p] > 0)) p++;
        ymed = median_of(lum + p, n - p);
    }
    free(lum);
    if (ymax > 0 && isfinite(ymax) && ymed > 0) {
        *start = log2f(xmax / ymax);
        *stop = log2f(xmax / ymed);
    } else { /* black (or unreadable): one exposure range of zero width */
        *start = *stop = 0;
    }
    float steps = ceilf(*stop - *start);
    *nexp = (int)(steps > 2.0f ? steps : 2.0f);
    return FB_OK;
}

fb_result fb_flip_pool(const float *map, size_t n, fb_flip_result *out)
{
    float *v = malloc((n ? n : 1) * sizeof *v);
    if (!v) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
    double sum = 0;
    for (size_t i = 0; i < n; i++) v[i] = isnan(map[i]) ? 1.0f : map[i], sum += v[i];
    fb_result rc = sort_floats(v, n);
    if (rc) {
        free(v);
        return rc;
    }
    out->mean = n ? sum / (double)n : 0;
    out->min = n ? v[0] : 0;
    out->max = n ? v[n - 1] : 0;
    /* the weighted percentile p: the first value at which the running sum of the sorted values exceeds p of the total
     */
    const double p[3] = {0.25, 0.5, 0.75};
    double *dst[3] = {&out->q1, &out->median, &out->q3}, run = 0;
    int k = 0;
    for (int j = 0; j < 3; j++) *dst[j] = 0;
    for (size_t i = 0; i < n && k < 3; i++) {
        run += v[i];
        while (k < 3 && run > p[k] * sum) *dst[k++] = v[i];
    }
    free(v);
    return FB_OK;
}
