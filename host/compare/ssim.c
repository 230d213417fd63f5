/* SSIM, streamed (ssim.h). */
#include "ssim.h"

#include "clones.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

fb_result ssim_init(ssim_acc *s, int width, double range)
{
    memset(s, 0, sizeof *s);
    double t = 0;
    for (int i = 0; i < SSIM_N; i++) t += s->w[i] = exp(-(double)((i - SSIM_R) * (i - SSIM_R)) / (2 * 1.5 * 1.5));
    for (int i = 0; i < SSIM_N; i++) s->w[i] /= t;
    double L = range > 0 ? range : 1.0;
    s->c1 = (0.01 * L) * (0.01 * L);
    s->c2 = (0.03 * L) * (0.03 * L);
    s->width = width;
    s->vw = width - 2 * SSIM_R;
    if (!(s->ring = calloc((size_t)SSIM_N * 5 * (size_t)s->vw, sizeof *s->ring)) ||
        !(s->tmp = calloc(6 * (size_t)s->vw + 3 * (size_t)width, sizeof *s->tmp)))
        return fb_fail(FB_ERR_NOMEM, "out of memory for SSIM");
    return FB_OK;
}

/* out = the window w (symmetric: w[k] = w[N - 1 - k]) over rows r[0..N) at each of n positions:
 * the centre's term, then each pair's, in that order. */
static inline __attribute__((always_inline)) void window(const double *w, const double *const r[SSIM_N], int n,
                                                         double *restrict out)
{
    for (int x = 0; x < n; x++) out[x] = w[SSIM_R] * r[SSIM_R][x];
    for (int k = 0; k < SSIM_R; k++) {
        const double *p = r[k], *q = r[SSIM_N - 1 - k];
        double wk = w[k];
        for (int x = 0; x < n; x++) out[x] += wk * (p[x] + q[x]);
    }
}

/* One image row of both channels (doubles). Each loop runs along the row (it vectorises), and each
 * sum is taken in the same order whatever the clone: the same bits. */
FB_CLONES void ssim_row(ssim_acc *s, const double *a, const double *b)
{
    int vw = s->vw, wd = s->width;
    double *sq = s->tmp + 6 * (size_t)vw, *aa = sq, *bb = sq + wd, *ab = sq + 2 * wd;
    for (int x = 0; x < wd; x++) aa[x] = a[x] * a[x], bb[x] = b[x] * b[x], ab[x] = a[x] * b[x];
    double *h = s->ring + (size_t)(s->rows_in % SSIM_N) * 5 * vw;
    const double *in[5] = {a, b, aa, bb, ab};
    for (int q = 0; q < 5; q++) { /* along the row: the window's taps are the row shifted */
        const double *r[SSIM_N];
        for (int k = 0; k < SSIM_N; k++) r[k] = in[q] + k;
        window(s->w, r, vw, h + (size_t)q * vw);
    }
    s->rows_in++;
    if (s->rows_in < SSIM_N) return;
    double *st = s->tmp, *m = s->tmp + 5 * vw; /* down the rows: the window centred SSIM_R rows back */
    const double *r[SSIM_N];
    for (int k = 0; k < SSIM_N; k++) r[k] = s->ring + (size_t)((s->rows_in - SSIM_N + k) % SSIM_N) * 5 * vw;
    window(s->w, r, 5 * vw, st);
    for (int x = 0; x < vw; x++) {
        double mu_a = st[x], mu_b = st[vw + x];
        double va = st[2 * vw + x] - mu_a * mu_a, vb = st[3 * vw + x] - mu_b * mu_b, cov = st[4 * vw + x] - mu_a * mu_b;
        m[x] =
            ((2 * mu_a * mu_b + s->c1) * (2 * cov + s->c2)) / ((mu_a * mu_a + mu_b * mu_b + s->c1) * (va + vb + s->c2));
    }
    for (int x = 0; x < vw; x++) s->sum += m[x];
    s->count += (uint64_t)vw;
}

void ssim_fini(ssim_acc *s)
{
    free(s->ring);
    free(s->tmp);
    s->ring = s->tmp = NULL;
}

double ssim_mean(const ssim_acc *s)
{
    return s->count ? s->sum / (double)s->count : 1.0;
}
