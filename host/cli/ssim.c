/* SSIM, streamed (ssim.h). */
#include "ssim.h"

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
    if (!(s->ring = calloc((size_t)SSIM_N * 5 * (size_t)s->vw, sizeof *s->ring)))
        return fb_fail(FB_ERR_NOMEM, "out of memory for SSIM");
    return FB_OK;
}

/* One image row of both channels (doubles). */
void ssim_row(ssim_acc *s, const double *a, const double *b)
{
    double *h = s->ring + (size_t)(s->rows_in % SSIM_N) * 5 * s->vw;
    for (int x = 0; x < s->vw; x++) {
        double ma = 0, mb = 0, aa = 0, bb = 0, ab = 0;
        for (int k = 0; k < SSIM_N; k++) {
            double w = s->w[k], va = a[x + k], vb = b[x + k];
            ma += w * va, mb += w * vb, aa += w * va * va, bb += w * vb * vb, ab += w * va * vb;
        }
        h[x] = ma, h[s->vw + x] = mb, h[2 * s->vw + x] = aa, h[3 * s->vw + x] = bb, h[4 * s->vw + x] = ab;
    }
    s->rows_in++;
    if (s->rows_in < SSIM_N) return;
    for (int x = 0; x < s->vw; x++) { /* the window centred SSIM_R rows back */
        double st[5] = {0, 0, 0, 0, 0};
        for (int k = 0; k < SSIM_N; k++) {
            const double *r = s->ring + (size_t)((s->rows_in - SSIM_N + k) % SSIM_N) * 5 * s->vw;
            for (int q = 0; q < 5; q++) st[q] += s->w[k] * r[q * s->vw + x];
        }
        double mu_a = st[0], mu_b = st[1];
        double va = st[2] - mu_a * mu_a, vb = st[3] - mu_b * mu_b, cov = st[4] - mu_a * mu_b;
        s->sum +=
            ((2 * mu_a * mu_b + s->c1) * (2 * cov + s->c2)) / ((mu_a * mu_a + mu_b * mu_b + s->c1) * (va + vb + s->c2));
        s->count++;
    }
}

void ssim_fini(ssim_acc *s)
{
    free(s->ring);
    s->ring = NULL;
}

double ssim_mean(const ssim_acc *s)
{
    return s->count ? s->sum / (double)s->count : 1.0;
}
