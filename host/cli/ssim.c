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
        !(s->tmp = calloc(6 * (size_t)s->vw, sizeof *s->tmp)))
        return fb_fail(FB_ERR_NOMEM, "out of memory for SSIM");
    return FB_OK;
}

/* One image row of both channels (doubles). Each loop runs along the row (it vectorises); each
 * value's sums are taken in the window's order, so the bits are those of a plain loop per pixel. */
FB_CLONES void ssim_row(ssim_acc *s, const double *a, const double *b)
{
    int vw = s->vw;
    double *h = s->ring + (size_t)(s->rows_in % SSIM_N) * 5 * vw;
    double *ma = h, *mb = h + vw, *aa = h + 2 * vw, *bb = h + 3 * vw, *ab = h + 4 * vw;
    for (int x = 0; x < 5 * vw; x++) h[x] = 0;
    for (int k = 0; k < SSIM_N; k++) {
        double w = s->w[k];
        const double *pa = a + k, *pb = b + k;
        for (int x = 0; x < vw; x++) {
            double va = pa[x], vb = pb[x];
            ma[x] += w * va, mb[x] += w * vb, aa[x] += w * va * va, bb[x] += w * vb * vb, ab[x] += w * va * vb;
        }
    }
    s->rows_in++;
    if (s->rows_in < SSIM_N) return;
    double *st = s->tmp, *m = s->tmp + 5 * vw; /* the window centred SSIM_R rows back */
    for (int x = 0; x < 5 * vw; x++) st[x] = 0;
    for (int k = 0; k < SSIM_N; k++) {
        const double *r = s->ring + (size_t)((s->rows_in - SSIM_N + k) % SSIM_N) * 5 * vw;
        double w = s->w[k];
        for (int x = 0; x < 5 * vw; x++) st[x] += w * r[x];
    }
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
