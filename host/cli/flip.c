/*
 * FLIP and HDR-FLIP (flip.h). The pipeline, per the papers:
 *  1. sRGB to linear RGB to CIE XYZ (D65) to YCxCz, the opponent space of the contrast
 *     sensitivity functions;
 *  2. the colour pipeline: each of Y, Cx, Cz filtered by its CSF (Gaussians in the papers' a, b
 *     form; Cz's a sum of two, filtered as two separable parts), clamped to [0, 1] in linear RGB,
 *     to CIELAB with the Hunt adjustment, the HyAB distance raised to 0.7 and mapped to [0, 1]
 *     (0.95 at 0.4 of the green-blue distance);
 *  3. the feature pipeline: edges and points of Y/116 + 16/116 by the first and second derivative of
 *     a Gaussian of 0.5 * 0.082 degrees, the larger difference over sqrt 2, raised to 0.5;
 *  4. the error color^(1 - feature).
 * Every step in float, in the order of the published implementation; borders clamp to the edge.
 * HDR-FLIP exposes both images by 2^e for each exposure e, tone maps by ACES (Narkowicz's fit,
 * its 0.6 pre-exposure cancelled), clamps, encodes as sRGB and keeps the largest LDR-FLIP.
 */
#include "flip.h"

#include "pool.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FPI 3.14159265358979f

static const float ILL[3] = {0.950428545f, 1.000000000f, 1.088900371f};
static const float INV_ILL[3] = {1.052156925f, 1.000000000f, 0.918357670f};

/* ACES (Narkowicz) as a rational (c0 x^2 + c1 x + c2) / (c3 x^2 + c4 x + c5), the pre-exposure 0.6 folded in. */
static const float ACES[6] = {0.6f * 0.6f * 2.51f, 0.6f * 0.03f, 0.0f, 0.6f * 0.6f * 2.43f, 0.6f * 0.59f, 0.14f};

float fb_flip_default_ppd(void)
{
    return 0.7f * (3840.0f / 0.7f) * (FPI / 180.0f);
}

static float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

static float linear_to_srgb(float c)
{
    return c <= 0.0031308f ? c * 12.92f : 1.055f * powf(c, 1.0f / 2.4f) - 0.055f;
}

static void rgb_to_xyz(const float c[3], float o[3])
{
    const float a11 = 10135552.0f / 24577794.0f, a12 = 8788810.0f / 24577794.0f, a13 = 4435075.0f / 24577794.0f;
    const float a21 = 2613072.0f / 12288897.0f, a22 = 8788810.0f / 12288897.0f, a23 = 887015.0f / 12288897.0f;
    const float a31 = 1425312.0f / 73733382.0f, a32 = 8788810.0f / 73733382.0f, a33 = 70074185.0f / 73733382.0f;
    float x = a11 * c[0] + a12 * c[1] + a13 * c[2];
    float y = a21 * c[0] + a22 * c[1] + a23 * c[2];
    float z = a31 * c[0] + a32 * c[1] + a33 * c[2];
    o[0] = x, o[1] = y, o[2] = z;
}

static void xyz_to_rgb(const float c[3], float o[3])
{
    float r = 3.241003275f * c[0] + -1.537398934f * c[1] + -0.498615861f * c[2];
    float g = -0.969224334f * c[0] + 1.875930071f * c[1] + 0.041554224f * c[2];
    float b = 0.055639423f * c[0] + -0.204011202f * c[1] + 1.057148933f * c[2];
    o[0] = r, o[1] = g, o[2] = b;
}

static float lab_f(float t)
{
    const float delta = 6.0f / 29.0f, d2 = delta * delta, d3 = delta * d2;
    const float factor = 1.0f / (3.0f * d2), term = 4.0f / 29.0f;
    return t > d3 ? powf(t, 1.0f / 3.0f) : factor * t + term;
}

static void xyz_to_lab(const float c[3], float o[3])
{
    float x = lab_f(c[0] * INV_ILL[0]), y = lab_f(c[1] * INV_ILL[1]), z = lab_f(c[2] * INV_ILL[2]);
    o[0] = 116.0f * y - 16.0f, o[1] = 500.0f * (x - y), o[2] = 200.0f * (y - z);
}

static void xyz_to_ycxcz(const float c[3], float o[3])
{
    float x = c[0] * INV_ILL[0], y = c[1] * INV_ILL[1], z = c[2] * INV_ILL[2];
    o[0] = 116.0f * y - 16.0f, o[1] = 500.0f * (x - y), o[2] = 200.0f * (y - z);
}

static void ycxcz_to_xyz(const float c[3], float o[3])
{
    float y = (c[0] + 16.0f) / 116.0f, cx = c[1] / 500.0f, cz = c[2] / 200.0f;
    o[0] = (y + cx) * ILL[0], o[1] = y * ILL[1], o[2] = (y - cz) * ILL[2];
}

static float hyab(const float a[3], const float b[3])
{
    float dl = fabsf(a[0] - b[0]);
    return dl + sqrtf((a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static void hunt(float lab[3])
{
    lab[1] = 0.01f * lab[0] * lab[1];
    lab[2] = 0.01f * lab[0] * lab[2];
}

/* The HyAB distance of green and blue, Hunt-adjusted, to the power 0.7: the largest colour error. */
static float max_distance(void)
{
    float g[3] = {0, 1, 0}, b[3] = {0, 0, 1}, t[3];
    rgb_to_xyz(g, t);
    xyz_to_lab(t, g);
    rgb_to_xyz(b, t);
    xyz_to_lab(t, b);
    hunt(g);
    hunt(b);
    return powf(hyab(g, b), 0.7f);
}

/* ---- filters --------------------------------------------------------------------------------- */

static float gauss_ab(float x2, float a, float b)
{
    const float pi_sq = FPI * FPI;
    return a * sqrtf(FPI / b) * expf(-pi_sq * x2 / b);
}

static float gauss_ab_sqrt(float x2, float a, float b) /* half of a 2D Gaussian of a sum, separated */
{
    const float pi_sq = FPI * FPI;
    return sqrtf(a * sqrtf(FPI / b)) * expf(-pi_sq * x2 / b);
}

static int spatial_radius(float ppd)
{
    const float pi_sq = FPI * FPI;
    return (int)ceilf(3.0f * sqrtf(0.04f / (2.0f * pi_sq)) * ppd); /* the largest b: Cz's 0.04 */
}

/* yc: (Y, Cx) weights per tap, cz: Cz's two Gaussians per tap; 2r + 1 taps each. */
static void spatial_filters(float ppd, int r, float (*yc)[2], float (*cz)[2])
{
    float dx = 1.0f / ppd, s[4] = {0, 0, 0, 0};
    for (int i = 0; i < 2 * r + 1; i++) {
        float x = (float)(i - r) * dx, x2 = x * x;
        yc[i][0] = gauss_ab(x2, 1.0f, 0.0047f);
        yc[i][1] = gauss_ab(x2, 1.0f, 0.0053f);
        cz[i][0] = gauss_ab_sqrt(x2, 34.1f, 0.04f);
        cz[i][1] = gauss_ab_sqrt(x2, 13.5f, 0.025f);
        s[0] += yc[i][0], s[1] += yc[i][1], s[2] += cz[i][0], s[3] += cz[i][1];
    }
    float ny = 1.0f / s[0], nx = 1.0f / s[1], nz = 1.0f / sqrtf(s[2] * s[2] + s[3] * s[3]);
    for (int i = 0; i < 2 * r + 1; i++) yc[i][0] *= ny, yc[i][1] *= nx, cz[i][0] *= nz, cz[i][1] *= nz;
}

/* f: (Gaussian, first derivative, second derivative) per tap, 2r + 1 taps; returns r. */
static int feature_radius(float ppd)
{
    return (int)ceilf(3.0f * (0.5f * 0.082f * ppd));
}

static void feature_filter(float ppd, int r, float (*f)[3])
{
    float sd = 0.5f * 0.082f * ppd, gs = 0, dn = 0, dp = 0, ddn = 0, ddp = 0;
    for (int i = 0; i < 2 * r + 1; i++) {
        float x = (float)(i - r);
        float g = expf(-(x * x) / (2.0f * sd * sd));
        float dg = -x * g;
        float ddg = (x * x / (sd * sd) - 1.0f) * g;
        gs += g;
        if (dg > 0.0f)
            dp += dg;
        else
            dn -= dg;
        if (ddg > 0.0f)
            ddp += ddg;
        else
            ddn -= ddg;
        f[i][0] = g, f[i][1] = dg, f[i][2] = ddg;
    }
    for (int i = 0; i < 2 * r + 1; i++) {
        f[i][0] /= gs;
        f[i][1] /= f[i][1] > 0.0f ? dp : dn;
        f[i][2] /= f[i][2] > 0.0f ? ddp : ddn;
    }
}

static inline int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* ---- LDR-FLIP -------------------------------------------------------------------------------- */

typedef struct flip_work {
    int w, h, rs, rf;
    float (*yc)[2], (*cz)[2], (*ff)[3];
    float cmax, pccmax;
    float *ycc[2]; /* YCxCz of ref and test, 3 per pixel */
    float *tmp[2]; /* the first pass: 4 per pixel (Y, Cx, Cz1, Cz2) or 3 (dx, ddx, g) */
    float *color;  /* the colour difference */
    fb_pool *pool; /* rows in bands over the cores: every row computed alone, the same bits */
    /* the pass being run over bands of rows, and its operands */
    void (*pass)(struct flip_work *k, int y0, int y1);
    const float *const *src3;
    float *dst, *err, **dst3, m;
    int side;
} flip_work;

#define FLIP_BAND 16

static int g_threads; /* fb_flip_set_threads; 0: one per core */

void fb_flip_set_threads(int n)
{
    g_threads = n;
}

static void band_task(void *ctx, int t)
{
    flip_work *k = ctx;
    int y0 = t * FLIP_BAND, y1 = y0 + FLIP_BAND < k->h ? y0 + FLIP_BAND : k->h;
    k->pass(k, y0, y1);
}

static void run_bands(flip_work *k, void (*pass)(flip_work *, int, int))
{
    k->pass = pass;
    fb_pool_run(k->pool, (k->h + FLIP_BAND - 1) / FLIP_BAND, band_task, k);
}

static void to_ycxcz_rows(flip_work *k, int y0, int y1)
{
    const float *const *src = k->src3;
    float *o = k->dst;
    for (size_t i = (size_t)y0 * k->w; i < (size_t)y1 * k->w; i++) {
        float c[3] = {srgb_to_linear(src[0][i]), srgb_to_linear(src[1][i]), srgb_to_linear(src[2][i])}, t[3];
        rgb_to_xyz(c, t);
        xyz_to_ycxcz(t, o + 3 * i);
    }
}

static void color_pass_x(flip_work *k, int y0, int y1)
{
    int r = k->rs;
    const float *src = k->ycc[k->side];
    float *dst = k->tmp[k->side];
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < k->w; x++) {
            float s0 = 0, s1 = 0, s2 = 0, s3 = 0;
            for (int i = -r; i <= r; i++) {
                const float *p = src + 3 * ((size_t)y * k->w + clampi(x + i, 0, k->w - 1));
                s0 += k->yc[i + r][0] * p[0];
                s1 += k->yc[i + r][1] * p[1];
                s2 += k->cz[i + r][0] * p[2];
                s3 += k->cz[i + r][1] * p[2];
            }
            float *o = dst + 4 * ((size_t)y * k->w + x);
            o[0] = s0, o[1] = s1, o[2] = s2, o[3] = s3;
        }
}

/* The filtered colour at (x, y) from the first pass: to linear RGB, clamped, to Hunt-adjusted CIELAB. */
static void color_at(const flip_work *k, const float *t, int x, int y, float lab[3])
{
    int r = k->rs;
    float s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (int i = -r; i <= r; i++) {
        const float *p = t + 4 * ((size_t)clampi(y + i, 0, k->h - 1) * k->w + x);
        s0 += k->yc[i + r][0] * p[0];
        s1 += k->yc[i + r][1] * p[1];
        s2 += k->cz[i + r][0] * p[2];
        s3 += k->cz[i + r][1] * p[3];
    }
    float c[3] = {s0, s1, s2 + s3}, xyz[3], rgb[3];
    ycxcz_to_xyz(c, xyz);
    xyz_to_rgb(xyz, rgb);
    for (int q = 0; q < 3; q++) rgb[q] = fminf(fmaxf(rgb[q], 0.0f), 1.0f);
    rgb_to_xyz(rgb, xyz);
    xyz_to_lab(xyz, lab);
    hunt(lab);
}

static void color_rows(flip_work *k, int y0, int y1)
{
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < k->w; x++) {
            float a[3], b[3];
            color_at(k, k->tmp[0], x, y, a);
            color_at(k, k->tmp[1], x, y, b);
            float d = powf(hyab(a, b), 0.7f);
            if (d < k->pccmax)
                d *= 0.95f / k->pccmax;
            else
                d = 0.95f + ((d - k->pccmax) / (k->cmax - k->pccmax)) * (1.0f - 0.95f);
            k->color[(size_t)y * k->w + x] = d;
        }
}

static void color_difference(flip_work *k)
{
    for (k->side = 0; k->side < 2; k->side++) run_bands(k, color_pass_x);
    run_bands(k, color_rows);
}

static void feature_pass_x(flip_work *k, int y0, int y1)
{
    int r = k->rf;
    const float o116 = 1.0f / 116.0f, s116 = 16.0f / 116.0f;
    const float *src = k->ycc[k->side];
    float *dst = k->tmp[k->side];
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < k->w; x++) {
            float dx = 0, ddx = 0, g = 0;
            for (int i = -r; i <= r; i++) {
                float v = src[3 * ((size_t)y * k->w + clampi(x + i, 0, k->w - 1))] * o116 + s116;
                dx += k->ff[i + r][1] * v;
                ddx += k->ff[i + r][2] * v;
                g += k->ff[i + r][0] * v;
            }
            float *o = dst + 3 * ((size_t)y * k->w + x);
            o[0] = dx, o[1] = ddx, o[2] = g;
        }
}

static void features_at(const flip_work *k, const float *t, int x, int y, float *edge, float *point)
{
    int r = k->rf;
    float dx = 0, ddx = 0, dy = 0, ddy = 0;
    for (int i = -r; i <= r; i++) {
        const float *p = t + 3 * ((size_t)clampi(y + i, 0, k->h - 1) * k->w + x);
        dx += k->ff[i + r][0] * p[0];
        ddx += k->ff[i + r][0] * p[1];
        dy += k->ff[i + r][1] * p[2];
        ddy += k->ff[i + r][2] * p[2];
    }
    *edge = sqrtf(dx * dx + dy * dy);
    *point = sqrtf(ddx * ddx + ddy * ddy);
}

static void final_rows(flip_work *k, int y0, int y1)
{
    const float norm = 1.0f / sqrtf(2.0f);
    float *err = k->err;
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < k->w; x++) {
            float ea, pa, eb, pb;
            features_at(k, k->tmp[0], x, y, &ea, &pa);
            features_at(k, k->tmp[1], x, y, &eb, &pb);
            float f = powf(norm * fmaxf(fabsf(ea - eb), fabsf(pa - pb)), 0.5f);
            size_t i = (size_t)y * k->w + x;
            err[i] = powf(k->color[i], 1.0f - f);
        }
}

static void final_error(flip_work *k, float *err)
{
    for (k->side = 0; k->side < 2; k->side++) run_bands(k, feature_pass_x);
    k->err = err;
    run_bands(k, final_rows);
}

static fb_result work_init(flip_work *k, int w, int h, float ppd)
{
    memset(k, 0, sizeof *k);
    k->w = w, k->h = h;
    k->rs = spatial_radius(ppd);
    k->rf = feature_radius(ppd);
    size_t n = (size_t)w * h;
    k->yc = malloc(sizeof *k->yc * (size_t)(2 * k->rs + 1));
    k->cz = malloc(sizeof *k->cz * (size_t)(2 * k->rs + 1));
    k->ff = malloc(sizeof *k->ff * (size_t)(2 * k->rf + 1));
    for (int s = 0; s < 2; s++) k->ycc[s] = malloc(n * 3 * sizeof(float)), k->tmp[s] = malloc(n * 4 * sizeof(float));
    k->color = malloc(n * sizeof(float));
    if (!k->yc || !k->cz || !k->ff || !k->ycc[0] || !k->ycc[1] || !k->tmp[0] || !k->tmp[1] || !k->color)
        return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP (%d x %d)", w, h);
    spatial_filters(ppd, k->rs, k->yc, k->cz);
    feature_filter(ppd, k->rf, k->ff);
    k->cmax = max_distance();
    k->pccmax = 0.4f * k->cmax;
    return fb_pool_create(g_threads > 0 ? g_threads : fb_cpu_count(), &k->pool);
}

static void work_fini(flip_work *k)
{
    free(k->yc);
    free(k->cz);
    free(k->ff);
    for (int s = 0; s < 2; s++) free(k->ycc[s]), free(k->tmp[s]);
    free(k->color);
    fb_pool_destroy(&k->pool);
}

/* LDR-FLIP of two sRGB images into err. */
static void ldr_flip(flip_work *k, const float *const ref[3], const float *const test[3], float *err)
{
    k->src3 = ref, k->dst = k->ycc[0];
    run_bands(k, to_ycxcz_rows);
    k->src3 = test, k->dst = k->ycc[1];
    run_bands(k, to_ycxcz_rows);
    color_difference(k);
    final_error(k, err);
}

/* ---- HDR-FLIP -------------------------------------------------------------------------------- */

static float luminance(float r, float g, float b)
{
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

void fb_flip_exposures(const float *const ref[3], size_t n, float *start, float *stop, int *nexp, bool *zero_median)
{
    /* the larger root of (c0 - t c3) x^2 + (c1 - t c4) x + (c2 - t c5) = 0: where ACES reaches t = 0.85 */
    float t = 0.85f, a = ACES[0] - t * ACES[3], b = ACES[1] - t * ACES[4], c = ACES[2] - t * ACES[5];
    float d1 = -0.5f * (b / a), d2 = sqrtf(d1 * d1 - c / a), xmax = d1 + d2;
    float *lum = malloc(n * sizeof *lum);
    float ymax = -1e30f, ymed = 0;
    *zero_median = false;
    if (lum && n > 0) {
        for (size_t i = 0; i < n; i++) {
            lum[i] = luminance(ref[0][i], ref[1][i], ref[2][i]);
            if (isnan(lum[i])) lum[i] = 0; /* non-finite pixels count as black for the range */
            ymax = fmaxf(ymax, lum[i]);
        }
        qsort(lum, n, sizeof *lum, cmp_float);
        size_t m = n >= 2 ? n / 2 - 1 : 0;
        ymed = n >= 2 ? (lum[m] + lum[m + 1]) * 0.5f : lum[0];
        if (!(ymed > 0)) { /* the published tool's stop exposure would be +inf here: take the positive ones' median */
            *zero_median = true;
            size_t p = 0;
            while (p < n && !(lum[p] > 0)) p++;
            size_t np = n - p;
            ymed = np == 0 ? 0 : np >= 2 ? (lum[p + np / 2 - 1] + lum[p + np / 2]) * 0.5f : lum[p];
        }
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
}

static void expose_rows(flip_work *k, int y0, int y1)
{
    const float *const *src = k->src3;
    float **dst = k->dst3, m = k->m;
    for (int q = 0; q < 3; q++)
        for (size_t i = (size_t)y0 * k->w; i < (size_t)y1 * k->w; i++) {
            float v = src[q][i] * m;
            v = (v * v * ACES[0] + v * ACES[1] + ACES[2]) / (v * v * ACES[3] + v * ACES[4] + ACES[5]);
            v = fminf(fmaxf(v, 0.0f), 1.0f);
            dst[q][i] = linear_to_srgb(v);
        }
}

static fb_result hdr_flip(flip_work *k, const float *const ref[3], const float *const test[3], float *err,
                          fb_flip_result *out)
{
    size_t n = (size_t)k->w * k->h;
    fb_flip_exposures(ref, n, &out->start_exposure, &out->stop_exposure, &out->nexp, &out->zero_median);
    float *buf = malloc(n * 7 * sizeof(float));
    if (!buf) return fb_fail(FB_ERR_NOMEM, "out of memory for HDR-FLIP");
    float *r[3] = {buf, buf + n, buf + 2 * n}, *t[3] = {buf + 3 * n, buf + 4 * n, buf + 5 * n}, *e = buf + 6 * n;
    float step = (out->stop_exposure - out->start_exposure) / (float)(out->nexp - 1);
    memset(err, 0, n * sizeof *err);
    for (int i = 0; i < out->nexp; i++) {
        float m = powf(2.0f, out->start_exposure + (float)i * step);
        k->m = m, k->src3 = ref, k->dst3 = r;
        run_bands(k, expose_rows);
        k->src3 = test, k->dst3 = t;
        run_bands(k, expose_rows);
        ldr_flip(k, (const float *const *)r, (const float *const *)t, e);
        for (size_t p = 0; p < n; p++)
            if (e[p] > err[p]) err[p] = e[p];
    }
    free(buf);
    return FB_OK;
}

/* ---- pooling --------------------------------------------------------------------------------- */

fb_result fb_flip_pool(const float *map, size_t n, fb_flip_result *out)
{
    float *v = malloc((n ? n : 1) * sizeof *v);
    if (!v) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's statistics");
    double sum = 0;
    for (size_t i = 0; i < n; i++) v[i] = map[i], sum += map[i];
    qsort(v, n, sizeof *v, cmp_float);
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

fb_result fb_flip(const float *const ref[3], const float *const test[3], int width, int height, bool hdr, float ppd,
                  float *map, fb_flip_result *out)
{
    memset(out, 0, sizeof *out);
    size_t n = (size_t)width * height;
    flip_work k;
    fb_result rc = work_init(&k, width, height, ppd);
    float *err = map ? map : malloc((n ? n : 1) * sizeof *err);
    if (!rc && !err) rc = fb_fail(FB_ERR_NOMEM, "out of memory for FLIP");
    if (!rc) {
        if (hdr)
            rc = hdr_flip(&k, ref, test, err, out);
        else
            ldr_flip(&k, ref, test, err);
    }
    if (!rc) {
        fb_flip_result keep = *out;
        rc = fb_flip_pool(err, n, out);
        out->start_exposure = keep.start_exposure, out->stop_exposure = keep.stop_exposure;
        out->nexp = keep.nexp, out->zero_median = keep.zero_median;
    }
    if (!map) free(err);
    work_fini(&k);
    return rc;
}
