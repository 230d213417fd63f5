/* compare's statistics per channel over blocks of rows, the diff and the picture, the verdicts (compare_int.h). */
#include "compare_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A heat colour for t in [0, 1]: black, blue, red, yellow, white. */
void cmp_heat(double t, float rgb[3])
{
    static const float stops[5][3] = {{0, 0, 0}, {0.1f, 0.15f, 1}, {1, 0.1f, 0.05f}, {1, 0.9f, 0.1f}, {1, 1, 1}};
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double x = t * 4;
    int i = x >= 4 ? 3 : (int)x;
    double f = x - i;
    for (int k = 0; k < 3; k++) rgb[k] = (float)(stops[i][k] + f * (stops[i + 1][k] - stops[i][k]));
}

/* The heat map's scale: |A - B| from 1e-8 (black) to 1 and more (white), a decade per eighth. */
double cmp_heat_t(double ad)
{
    if (!(ad > 0)) return 0;
    if (isinf(ad)) return 1;
    return (log10(ad) + 8) / 8;
}

/* The planes of rows y0 .. y0 + n of both files: pointers into the whole planes, or read. */
static fb_result block_planes(cmp *k, int y0, int n, void ***A, void ***B)
{
    if (!k->whole) {
        fb_result rc = image_read_rows(&k->A, y0, n, k->pa);
        if (!rc) rc = image_read_rows(&k->B, y0, n, k->pb);
        *A = k->pa, *B = k->pb;
        return rc;
    }
    size_t off = (size_t)y0 * k->W * 4; /* float and uint alike */
    for (int s = 0; s < k->nst; s++) {
        const chan_stats *c = &k->st[s];
        k->ba[c->ia] = (char *)k->pa[c->ia] + off, k->bb[c->ib] = (char *)k->pb[c->ib] + off;
    }
    *A = k->ba, *B = k->bb;
    return FB_OK;
}

/* a block's job for the threads: one task per channel */
typedef struct block_job {
    cmp *k;
    int y0, n;
    void **A, **B;
} block_job;

static void range_task(void *ctx, int s)
{
    block_job *j = ctx;
    chan_stats *c = &j->k->st[s];
    for (size_t i = 0; i < (size_t)j->k->W * j->n; i++) {
        double v = cmp_value(j->A[c->ia], c->uint_a, i);
        if (isfinite(v)) c->a_lo = v < c->a_lo ? v : c->a_lo, c->a_hi = v > c->a_hi ? v : c->a_hi;
    }
}

/* SSIM needs each channel's dynamic range first (A's; a PNG's is its full scale, 1). */
static fb_result setup_ssim(cmp *k)
{
    bool want = false;
    for (int s = 0; s < k->nst; s++) want = want || k->st[s].has_ssim;
    if (!want) return FB_OK;
    if (k->W < SSIM_N || k->H < SSIM_N)
        return fb_fail(FB_ERR_USAGE, "--ssim: the images are %d x %d, and SSIM's window needs at least %d x %d", k->W,
                       k->H, SSIM_N, SSIM_N);
    fb_result rc;
    for (int s = 0; s < k->nst; s++) k->st[s].a_lo = INFINITY, k->st[s].a_hi = -INFINITY;
    block_job j = {.k = k};
    for (int y0 = 0; y0 < k->H && !k->A.is_png; y0 += BLOCK_ROWS) {
        j.y0 = y0, j.n = y0 + BLOCK_ROWS <= k->H ? BLOCK_ROWS : k->H - y0;
        if (k->whole) { /* the whole planes as one block */
            j.n = k->H, y0 = k->H;
            if ((rc = block_planes(k, 0, k->H, &j.A, &j.B))) return rc;
        } else if ((rc = image_read_rows(&k->A, y0, j.n, k->pa))) {
            return rc;
        } else {
            j.A = k->pa;
        }
        fb_pool_run(k->pool, k->nst, range_task, &j);
    }
    for (int s = 0; s < k->nst; s++) {
        chan_stats *c = &k->st[s];
        double range = !k->A.is_png && c->a_hi > c->a_lo ? c->a_hi - c->a_lo : 1.0;
        c->a_lo = INFINITY, c->a_hi = -INFINITY; /* measured again with the statistics */
        if (!c->has_ssim) continue;
        if ((rc = ssim_init(&c->ssim, k->W, range))) return rc;
        if (!(c->ra = malloc((size_t)k->W * sizeof(double))) || !(c->rb = malloc((size_t)k->W * sizeof(double))))
            return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    return FB_OK;
}

/* The picture's background for a block: A's first compared channel, grey over its block range, dimmed. */
static void picture_background(cmp *k, void **A, size_t npix)
{
    const chan_stats *c = &k->st[0];
    if (k->d->heat) {
        memset(k->pic[0], 0, npix * 4); /* pic[0]: the largest |A - B| so far, then colours */
        return;
    }
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < npix; i++) {
        double v = cmp_value(A[c->ia], c->uint_a, i);
        if (isfinite(v)) lo = v < lo ? v : lo, hi = v > hi ? v : hi;
    }
    for (size_t i = 0; i < npix; i++) {
        double v = cmp_value(A[c->ia], c->uint_a, i);
        float g = isfinite(v) && hi > lo ? (float)(0.25 * (v - lo) / (hi - lo)) : 0.0f;
        k->pic[0][i] = k->pic[1][i] = k->pic[2][i] = g;
    }
}

/* The picture of a block: the background, then each channel's |A - B| (the heat's largest) or its
 * failing pixels in red, then the heat's colours. */
static void picture_block(cmp *k, void **A, void **B, size_t npix)
{
    picture_background(k, A, npix);
    for (int s = 0; s < k->nst; s++) {
        const chan_stats *c = &k->st[s];
        for (size_t i = 0; i < npix; i++) {
            double va = cmp_value(A[c->ia], c->uint_a, i), vb = cmp_value(B[c->ib], c->uint_b, i), ad;
            if (isfinite(va) && isfinite(vb))
                ad = fabs(va - vb);
            else
                ad = (isnan(va) && isnan(vb)) || va == vb ? 0 : INFINITY;
            if (k->d->heat) {
                if (ad > k->pic[0][i]) k->pic[0][i] = (float)(isinf(ad) ? 1e30 : ad);
            } else if (c->abs_test && ad > c->fail) {
                k->pic[0][i] = 1.0f, k->pic[1][i] = k->pic[2][i] = 0.0f;
            }
        }
    }
    if (k->d->heat)
        for (size_t i = 0; i < npix; i++) {
            float rgb[3];
            cmp_heat(cmp_heat_t(k->pic[0][i]), rgb);
            k->pic[0][i] = rgb[0], k->pic[1][i] = rgb[1], k->pic[2][i] = rgb[2];
        }
}

/* --idiff-stats: one pair of values into the channel's share of the block. A non-finite value
 * that differs is the largest error there is (inf), over both thresholds. */
static void idiff_value(cmp *k, chan_stats *c, double va, double vb, double ad, double avg, size_t i, int y0)
{
    bool finite = isfinite(ad);
    if (finite) {
        c->i_sum += ad, c->i_sq += ad * ad, c->i_nvals++;
        if (va > c->i_peak) c->i_peak = va;
        if (vb > c->i_peak) c->i_peak = vb;
    } else {
        c->i_nonfinite++;
    }
    if (ad > c->i_max || c->i_mx < 0)
        c->i_max = ad, c->i_mx = (int)(i % (size_t)k->W), c->i_my = y0 + (int)(i / (size_t)k->W);
    if (!finite || (ad > k->i_warn && ad > k->d->warnrelative * avg)) c->over[i] |= 1;
    if (!finite || (ad > k->i_fail && ad > k->d->failrelative * avg)) c->over[i] |= 2;
}

/* Whether every value of two float planes of npix values is finite. */
static bool all_finite(const float *a, const float *b, size_t npix)
{
    uint32_t bad = 0;
    for (size_t i = 0; i < npix; i++) {
        uint32_t u, v;
        memcpy(&u, a + i, sizeof u), memcpy(&v, b + i, sizeof v);
        bad |= ((u & 0x7f800000u) == 0x7f800000u) | ((v & 0x7f800000u) == 0x7f800000u);
    }
    return !bad;
}

/* channel_block's loop for two float planes without a non-finite value: the same operations in the
 * same order on each pair (the same bits), with the sums in locals instead of the channel's fields,
 * which the stores to the diff row and the idiff flags would otherwise make it load and store again
 * for each pixel. */
static void finite_block(cmp *k, chan_stats *c, float *pd, int y0, const float *a, const float *b, size_t npix)
{
    const double frel = k->d->failrelative, wrel = k->d->warnrelative, fail = c->fail, warn = c->warn;
    const double i_warn = k->i_warn, i_fail = k->i_fail, hard = c->has_hardfail ? c->hardfail : INFINITY;
    double sum_sq = c->sum_sq, a_lo = c->a_lo, a_hi = c->a_hi, max_abs = c->max_abs;
    double i_sum = 0, i_sq = 0, i_peak = 0, i_max = 0;
    uint64_t beyond = 0, beyond_warn = 0, failing = 0;
    size_t max_i = SIZE_MAX, i_maxi = SIZE_MAX;
    bool have = c->max_x >= 0, has_warn = c->has_warn;
    uint8_t *over = c->over;
    for (size_t i = 0; i < npix; i++) {
        double va = a[i], vb = b[i], ad = fabs(va - vb);
        sum_sq += ad * ad;
        if (va < a_lo) a_lo = va;
        if (va > a_hi) a_hi = va;
        if (ad > max_abs || (!have && ad > 0)) max_abs = ad, max_i = i, have = true;
        double avg = 0.5 * (fabs(va) + fabs(vb));
        bool over_fail = ad > fail && ad > frel * avg;
        beyond += over_fail;
        beyond_warn += has_warn && ad > warn && ad > wrel * avg;
        failing += over_fail || ad > hard;
        if (over) {
            i_sum += ad, i_sq += ad * ad;
            if (va > i_peak) i_peak = va;
            if (vb > i_peak) i_peak = vb;
            if (ad > i_max || i_maxi == SIZE_MAX) i_max = ad, i_maxi = i;
            over[i] = (uint8_t)((ad > i_warn && ad > wrel * avg) | (ad > i_fail && ad > frel * avg) << 1);
        }
        if (pd) pd[i] = (float)ad;
    }
    size_t W = (size_t)k->W;
    c->n += npix, c->sum_sq = sum_sq, c->a_lo = a_lo, c->a_hi = a_hi, c->max_abs = max_abs;
    c->beyond += beyond, c->beyond_warn += beyond_warn, c->failing += failing;
    if (max_i != SIZE_MAX) c->max_x = (int)(max_i % W), c->max_y = y0 + (int)(max_i / W);
    if (!over) return;
    c->i_sum = i_sum, c->i_sq = i_sq, c->i_peak = i_peak, c->i_nvals = npix;
    if (i_maxi != SIZE_MAX) c->i_max = i_max, c->i_mx = (int)(i_maxi % W), c->i_my = y0 + (int)(i_maxi / W);
}

/* One channel's share of a block: its statistics, its diff row, its idiff share and its SSIM rows. */
static void channel_block(cmp *k, int s, int y0, int n, void **A, void **B)
{
    chan_stats *c = &k->st[s];
    const void *pA = A[c->ia], *pB = B[c->ib];
    size_t W = (size_t)k->W, npix = W * n;
    if (c->over) {
        memset(c->over, 0, npix);
        c->i_sum = c->i_sq = c->i_peak = 0, c->i_nvals = c->i_nonfinite = 0;
        c->i_max = 0, c->i_mx = c->i_my = -1;
    }
    bool fast = !c->uint_a && !c->uint_b && all_finite(pA, pB, npix);
    if (fast) finite_block(k, c, k->pd ? k->pd[s] : NULL, y0, pA, pB, npix);
    for (size_t i = 0; i < npix && !fast; i++) {
        double va = cmp_value(pA, c->uint_a, i), vb = cmp_value(pB, c->uint_b, i), ad, avg = 0;
        if (!isfinite(va) || !isfinite(vb)) {
            if ((isnan(va) && isnan(vb)) || va == vb) {
                c->nonfinite_same++;
                if (k->pd) k->pd[s][i] = 0.0f;
                continue; /* the same in both: no error, and not in idiff's sums */
            }
            c->nonfinite_mismatch++, c->beyond++, c->beyond_warn++, c->failing++;
            c->max_abs = ad = INFINITY;
        } else {
            ad = fabs(va - vb);
            c->n++;
            c->sum_sq += ad * ad;
            if (va < c->a_lo) c->a_lo = va;
            if (va > c->a_hi) c->a_hi = va;
            if (ad > c->max_abs || (c->max_x < 0 && ad > 0))
                c->max_abs = ad, c->max_x = (int)(i % W), c->max_y = y0 + (int)(i / W);
            avg = 0.5 * (fabs(va) + fabs(vb));
            bool over_fail = ad > c->fail && ad > k->d->failrelative * avg;
            bool over_warn = ad > c->warn && ad > k->d->warnrelative * avg;
            if (over_fail) c->beyond++;
            if (c->has_warn && over_warn) c->beyond_warn++;
            if (over_fail || (c->has_hardfail && ad > c->hardfail)) c->failing++;
        }
        if (c->over) idiff_value(k, c, va, vb, ad, avg, i, y0);
        if (k->pd) k->pd[s][i] = (float)ad;
    }
    for (int r = 0; r < n && c->has_ssim; r++) {
        for (size_t x = 0; x < W; x++) {
            double va = cmp_value(pA, c->uint_a, r * W + x), vb = cmp_value(pB, c->uint_b, r * W + x);
            c->ra[x] = isfinite(va) ? va : 0, c->rb[x] = isfinite(vb) ? vb : 0;
        }
        ssim_row(&c->ssim, c->ra, c->rb);
    }
}

static void channel_task(void *ctx, int s)
{
    block_job *j = ctx;
    channel_block(j->k, s, j->y0, j->n, j->A, j->B);
}

/* The channels' idiff shares of a block into the totals, in the channels' order. */
static void idiff_add(cmp *k, size_t npix)
{
    memset(k->over, 0, npix);
    for (int s = 0; s < k->nst; s++) {
        const chan_stats *c = &k->st[s];
        k->i_sum += c->i_sum, k->i_sq += c->i_sq, k->i_nvals += c->i_nvals, k->i_nonfinite += c->i_nonfinite;
        if (c->i_peak > k->i_peak) k->i_peak = c->i_peak;
        if (c->i_mx >= 0 && (c->i_max > k->i_max || !k->i_mc))
            k->i_max = c->i_max, k->i_mx = c->i_mx, k->i_my = c->i_my, k->i_mc = c->name;
        for (size_t i = 0; i < npix; i++) k->over[i] |= c->over[i];
    }
    for (size_t i = 0; i < npix; i++) k->i_nwarn += k->over[i] & 1, k->i_nfail += k->over[i] >> 1;
}

/* The buffers: a block of each compared channel (unless whole), idiff's per-pixel flags. */
static fb_result stream_setup(cmp *k)
{
    size_t block = (size_t)k->W * BLOCK_ROWS;
    for (int s = 0; s < k->nst && !k->whole; s++)
        if ((!k->pa[k->st[s].ia] && !(k->pa[k->st[s].ia] = malloc(block * 4))) ||
            (!k->pb[k->st[s].ib] && !(k->pb[k->st[s].ib] = malloc(block * 4))))
            return fb_fail(FB_ERR_NOMEM, "out of memory");
    if (k->d->idiff_stats) {
        if (!(k->over = malloc(block ? block : 1))) return fb_fail(FB_ERR_NOMEM, "out of memory");
        for (int s = 0; s < k->nst; s++)
            if (!(k->st[s].over = malloc(block ? block : 1))) return fb_fail(FB_ERR_NOMEM, "out of memory");
        k->i_warn = k->d->warn.has_all ? k->d->warn.all : 1e-6;
        k->i_fail = k->d->fail.has_all ? k->d->fail.all : 1e-6;
        k->i_peak = 1.0;
    }
    return setup_ssim(k);
}

/* Every block of rows through the statistics (a task per channel), the diff and the picture. */
fb_result cmp_stream_blocks(cmp *k)
{
    fb_result rc = stream_setup(k);
    if (rc) return rc;
    block_job j = {.k = k};
    for (int y0 = 0; y0 < k->H && k->nst > 0; y0 += BLOCK_ROWS) {
        j.y0 = y0, j.n = y0 + BLOCK_ROWS <= k->H ? BLOCK_ROWS : k->H - y0;
        size_t npix = (size_t)k->W * j.n;
        if ((rc = block_planes(k, y0, j.n, &j.A, &j.B))) return rc;
        fb_pool_run(k->pool, k->nst, channel_task, &j);
        if (k->over) idiff_add(k, npix);
        if (k->png) {
            picture_block(k, j.A, j.B, npix);
            fb_preview_add_rows(k->png, y0, j.n, (const float *const *)k->pic);
        }
        for (int u = 0; u < k->nfu && k->pd; u++) k->pd[k->nst + u] = k->fu[u].map + (size_t)y0 * k->W;
        if (k->diff && (rc = exrio_writer_rows(k->diff, y0, j.n, (const void *const *)k->pd))) return rc;
    }
    if (k->png && (rc = fb_preview_write_png(k->png, k->d->diff_png, "diff picture"))) return rc;
    if (k->png && k->d->heat)
        cmp_say(k->d,
                "%-16s %s: max |A - B| over the channels, black 1e-8, blue 1e-6, red 1e-4, yellow 0.01, "
                "white 1 and beyond",
                "", k->d->diff_png);
    return k->diff ? exrio_writer_finish(&k->diff) : FB_OK;
}

/* A pixel fails beyond --fail, and beyond --hardfail whatever --fail says; --allowfailures N lets a
 * channel with at most N failing pixels pass, idiff's "OK for this number of pixels to fail by any
 * amount" (idiff 2.4 counts only the pixels beyond -fail, so that its -hardfail is skipped while none
 * is, against its own help: "Fail if any one pixel exceeds this error"). */
bool cmp_allowed(const cmp *k, const chan_stats *c)
{
    return (long long)c->failing <= k->d->allowfailures && c->nonfinite_mismatch == 0;
}

/* A channel's statistics and verdict. */
void cmp_channel_verdict(cmp *k, chan_stats *c)
{
    uint64_t total = (uint64_t)k->W * k->H;
    double peak = c->a_hi > c->a_lo ? c->a_hi - c->a_lo : (c->a_hi > 0 ? c->a_hi : 1.0);
    c->rmse = c->nonfinite_mismatch ? INFINITY : c->n ? sqrt(c->sum_sq / (double)c->n) : 0;
    c->psnr = c->nonfinite_mismatch ? -INFINITY : c->rmse > 0 ? 20 * log10(peak / c->rmse) : INFINITY;
    c->pct = total ? 100.0 * (double)c->beyond / (double)total : 0;
    c->wpct = total ? 100.0 * (double)c->beyond_warn / (double)total : 0;
    c->ssim_v = !c->has_ssim ? NAN : c->nonfinite_mismatch ? -1.0 : ssim_mean(&c->ssim);
    c->verdict = FB_VERDICT_PASS;
#define FAIL_IF(cond, ...)                                                                                             \
    if (c->verdict != FB_VERDICT_FAIL && (cond))                                                                       \
    c->verdict = FB_VERDICT_FAIL, snprintf(c->why, sizeof c->why, __VA_ARGS__)
    bool allowed = cmp_allowed(k, c);
    FAIL_IF(!allowed && c->abs_test && c->pct > c->failpct, "%.4g%% of pixels beyond %g (allowed %g%%%s)", c->pct,
            c->fail, c->failpct, k->d->allowfailures ? " or --allowfailures" : "");
    FAIL_IF(!allowed && c->has_hardfail && c->max_abs > c->hardfail, "max |A - B| %g beyond --hardfail %g", c->max_abs,
            c->hardfail);
    FAIL_IF(c->has_rmse && !(c->rmse <= c->rmse_max), "RMSE %g beyond %g", c->rmse, c->rmse_max);
    FAIL_IF(c->has_psnr && !(c->psnr >= c->psnr_min), "PSNR %.2f dB below %g", c->psnr, c->psnr_min);
    FAIL_IF(c->has_ssim && !(c->ssim_v >= c->ssim_min), "SSIM %.6f below %g", c->ssim_v, c->ssim_min);
#undef FAIL_IF
    if (c->verdict == FB_VERDICT_PASS && c->has_warn && c->wpct > c->warnpct)
        c->verdict = FB_VERDICT_WARN,
        snprintf(c->why, sizeof c->why, "%.4g%% of pixels beyond the warning %g (allowed %g%%)", c->wpct, c->warn,
                 c->warnpct);
    if (c->verdict == FB_VERDICT_PASS && c->has_hardwarn && c->max_abs > c->hardwarn)
        c->verdict = FB_VERDICT_WARN,
        snprintf(c->why, sizeof c->why, "max |A - B| %g beyond --hardwarn %g", c->max_abs, c->hardwarn);
}
