/*
 * FLIP's statistics (flip.h): the automatic exposure range of HDR-FLIP from the reference's
 * luminances, and the pooled error (mean, weighted median and quartiles). Both want a few order
 * statistics of a million values per image, so they bucket the values by the top 16 bits of their
 * keys (the floats' bits made unsigned-monotone: the order of the values) and sort, by radix, only
 * the buckets that hold what is asked.
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

#define NBUCKET 65536

/* Values bucketed by the top 16 bits of their keys: how many in each, and (weighted) their sums. */
typedef struct buckets {
    uint32_t *count;
    double *sum;
} buckets;

static fb_result buckets_fill(buckets *b, const float *v, size_t n, bool sums)
{
    b->count = calloc(NBUCKET, sizeof *b->count);
    b->sum = sums ? calloc(NBUCKET, sizeof *b->sum) : NULL;
    if (!b->count || (sums && !b->sum)) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
    for (size_t i = 0; i < n; i++) {
        uint32_t d = float_key(v[i]) >> 16;
        b->count[d]++;
        if (sums) b->sum[d] += v[i];
    }
    return FB_OK;
}

static void buckets_fini(buckets *b)
{
    free(b->count);
    free(b->sum);
}

/* The values of bucket d, sorted, into out (count[d] of them). */
static fb_result bucket_sorted(const float *v, size_t n, uint32_t d, float *out)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (float_key(v[i]) >> 16 == d) out[m++] = v[i];
    return sort_floats(out, m);
}

/* The k-th smallest of v (0-based, k < n). */
static fb_result kth_value(const float *v, size_t n, const buckets *b, size_t k, float *out)
{
    uint32_t d = 0;
    size_t before = 0;
    while (before + b->count[d] <= k) before += b->count[d++];
    float *in = malloc((size_t)b->count[d] * sizeof *in);
    if (!in) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
    fb_result rc = bucket_sorted(v, n, d, in);
    if (!rc) *out = in[k - before];
    free(in);
    return rc;
}

/* The median of the values from the p-th smallest on (the mean of the middle two when there is an even
 * number), as the published tool takes it; 0 when none. */
static fb_result median_from(const float *v, size_t n, const buckets *b, size_t p, float *med)
{
    size_t m = n - p;
    float lo = 0, hi = 0;
    fb_result rc = FB_OK;
    if (m == 0) return *med = 0, FB_OK;
    if (m == 1) return kth_value(v, n, b, p, med);
    if (!(rc = kth_value(v, n, b, p + m / 2 - 1, &lo))) rc = kth_value(v, n, b, p + m / 2, &hi);
    *med = (lo + hi) * 0.5f;
    return rc;
}

static float luminance(float r, float g, float b)
{
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

fb_result fb_flip_exposures(const float *const ref[3], size_t n, float *scratch, float *start, float *stop, int *nexp,
                            bool *zero_median)
{
    /* the larger root of (c0 - t c3) x^2 + (c1 - t c4) x + (c2 - t c5) = 0: where ACES reaches t = 0.85 */
    float t = 0.85f, a = ACES[0] - t * ACES[3], b = ACES[1] - t * ACES[4], c = ACES[2] - t * ACES[5];
    float d1 = -0.5f * (b / a), d2 = sqrtf(d1 * d1 - c / a), xmax = d1 + d2;
    float *lum = scratch ? scratch : malloc((n ? n : 1) * sizeof *lum);
    if (!lum) return fb_fail(FB_ERR_NOMEM, "out of memory for HDR-FLIP's exposures");
    float ymax = -1e30f, ymed = 0;
    size_t nonpos = 0;
    *zero_median = false;
    for (size_t i = 0; i < n; i++) {
        lum[i] = luminance(ref[0][i], ref[1][i], ref[2][i]);
        if (isnan(lum[i])) lum[i] = 0; /* non-finite pixels count as black for the range */
        ymax = fmaxf(ymax, lum[i]);
        nonpos += !(lum[i] > 0);
    }
    buckets bk = {0};
    fb_result rc = buckets_fill(&bk, lum, n, false);
    if (!rc) rc = median_from(lum, n, &bk, 0, &ymed);
    if (!rc && n > 0 && !(ymed > 0)) { /* the published tool's stop exposure would be +inf: the positive ones' median */
        *zero_median = true;
        rc = median_from(lum, n, &bk, nonpos, &ymed);
    }
    buckets_fini(&bk);
    if (lum != scratch) free(lum);
    if (rc) return rc;
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
    bool nan = false; /* a NaN counts as 1: in a copy, where there is one */
    for (size_t i = 0; i < n; i++) nan = nan || isnan(map[i]);
    float *own = nan ? malloc(n * sizeof *own) : NULL;
    if (nan && !own) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
    for (size_t i = 0; i < n && own; i++) own[i] = isnan(map[i]) ? 1.0f : map[i];
    const float *v = own ? own : map;
    double sum = 0;
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) sum += v[i], lo = v[i] < lo ? v[i] : lo, hi = v[i] > hi ? v[i] : hi;
    out->mean = n ? sum / (double)n : 0;
    out->min = n ? lo : 0;
    out->max = n ? hi : 0;
    /* the weighted percentile p: the first value, in sorted order, at which the running sum of the values
     * exceeds p of the total (whole buckets first, then the sorted values of the bucket where it does) */
    const double p[3] = {0.25, 0.5, 0.75};
    double *dst[3] = {&out->q1, &out->median, &out->q3}, run = 0;
    for (int j = 0; j < 3; j++) *dst[j] = 0;
    buckets b = {0};
    fb_result rc = buckets_fill(&b, v, n, true);
    float *in = NULL;
    for (uint32_t d = 0, k = 0; d < NBUCKET && k < 3 && !rc; d++) {
        if (!b.count[d] || !(run + b.sum[d] > p[k] * sum)) {
            run += b.sum[d];
            continue;
        }
        if (!(in = malloc((size_t)b.count[d] * sizeof *in)) || (rc = bucket_sorted(v, n, d, in))) {
            rc = rc ? rc : fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
            break;
        }
        for (uint32_t i = 0; i < b.count[d] && k < 3; i++) {
            run += in[i];
            while (k < 3 && run > p[k] * sum) *dst[k++] = in[i];
        }
        free(in), in = NULL;
    }
    buckets_fini(&b);
    free(own);
    return rc;
}
