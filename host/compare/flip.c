/*
 * FLIP and HDR-FLIP (flip.h). The pipeline, per the papers:
 *  1. sRGB to linear RGB to CIE XYZ (D65) to YCxCz, the opponent space of the contrast
 *     sensitivity functions;
 *  2. the colour pipeline: each of Y, Cx, Cz filtered by its CSF (Gaussians in the papers' a, b
 *     form; Cz's a sum of two, filtered as two separable parts), clamped to [0, 1] in linear RGB,
 *     to CIELAB with the Hunt adjustment, the HyAB distance raised to 0.7 and mapped to [0, 1]
 *     (0.95 at 0.4 of the green-blue distance);
 *  3. the feature pipeline: edges and points of Y/116 + 16/116 (the linear luminance) by the first
 *     and second derivative of a Gaussian of 0.5 * 0.082 degrees, the larger difference over
 *     sqrt 2, raised to 0.5;
 *  4. the error color^(1 - feature).
 * HDR-FLIP exposes both images by 2^e for each exposure e, tone maps by ACES (Narkowicz's fit,
 * its 0.6 pre-exposure cancelled), clamps, and keeps the largest LDR-FLIP. The published tool then
 * encodes sRGB and LDR-FLIP decodes it again; that round trip is the identity and is skipped.
 *
 * How it is fast (the published tool's order, in single precision, but rearranged):
 *  - the work is cut in bands of rows; a band's rows are filtered horizontally once per exposure
 *    into a ring of 2r + 1 rows, from which each output row is filtered vertically;
 *  - every filter is symmetric or antisymmetric, so each pair of taps costs one multiply;
 *  - every loop runs along a row of planes, and is compiled three times (AVX-512, AVX2 and the SSE2
 *    baseline: clones.h), the same operations per pixel in each, so the same bits;
 *  - powers and exponentials are float log2/exp2 polynomials (a few 1e-7 relative), cube roots
 *    Newton's steps from the bits (1e-7), which vectorise where libm's powf and cbrtf do not;
 *  - a grey image (one plane passed three times) has Cx = Cz = 0: only Y is filtered, and CIELAB's
 *    a, b are 0 (the published tool gets a few 1e-5 of rounding there: 2e-5 in a quartile at most).
 * Bands are independent, so the result is the same bits for any thread count.
 */
#include "flip.h"

#include "clones.h"
#include "pool.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define FPI       3.14159265358979f
#define FLIP_BAND 128 /* rows a band: its first and last r rows are filtered for it alone */

static const float ILL[3] = {0.950428545f, 1.000000000f, 1.088900371f};
static const float INV_ILL[3] = {1.052156925f, 1.000000000f, 0.918357670f};

/* ACES (Narkowicz) as a rational (c0 x^2 + c1 x + c2) / (c3 x^2 + c4 x + c5), the pre-exposure 0.6 folded in. */
static const float ACES[6] = {0.6f * 0.6f * 2.51f, 0.6f * 0.03f, 0.0f, 0.6f * 0.6f * 2.43f, 0.6f * 0.59f, 0.14f};

/* linear RGB to XYZ and back (D65) */
#define A11 (10135552.0f / 24577794.0f)
#define A12 (8788810.0f / 24577794.0f)
#define A13 (4435075.0f / 24577794.0f)
#define A21 (2613072.0f / 12288897.0f)
#define A22 (8788810.0f / 12288897.0f)
#define A23 (887015.0f / 12288897.0f)
#define A31 (1425312.0f / 73733382.0f)
#define A32 (8788810.0f / 73733382.0f)
#define A33 (70074185.0f / 73733382.0f)

float fb_flip_default_ppd(void)
{
    return 0.7f * (3840.0f / 0.7f) * (FPI / 180.0f);
}

/* ---- float math that vectorises -------------------------------------------------------------- */

/* log2 of x > 0 (normal): the exponent, and ln of the mantissa in [sqrt 1/2, sqrt 2) by atanh's series. */
static inline __attribute__((always_inline)) float flog2(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    float e = (float)((int32_t)(u >> 23) - 127);
    u = (u & 0x007fffffu) | 0x3f800000u;
    float m;
    memcpy(&m, &u, sizeof m);
    bool big = m > 1.41421356f;
    m = big ? m * 0.5f : m;
    e = big ? e + 1.0f : e;
    float t = (m - 1.0f) / (m + 1.0f), t2 = t * t;
    float ln = t * (2.0f + t2 * (0.666666667f + t2 * (0.4f + t2 * (0.285714286f + t2 * 0.222222222f))));
    return e + ln * 1.44269504f;
}

/* 2^x: the integer part in the exponent, the rest in [-1/2, 1/2) by e^y's series to y^7. */
static inline __attribute__((always_inline)) float fexp2(float x)
{
    x = x < -125.0f ? -125.0f : x > 127.0f ? 127.0f : x;
    int32_t n = (int32_t)(x + 127.5f) - 127;
    float y = (x - (float)n) * 0.693147181f;
    float p =
        1.0f + y * (1.0f + y * (0.5f + y * (0.166666667f +
                                            y * (0.0416666667f +
                                                 y * (0.00833333333f + y * (0.00138888889f + y * 0.000198412698f))))));
    uint32_t u = (uint32_t)(n + 127) << 23;
    float s;
    memcpy(&s, &u, sizeof s);
    return p * s;
}

/* x^a for x >= 0, a > 0 */
static inline __attribute__((always_inline)) float fpow(float x, float a)
{
    float r = fexp2(a * flog2(x > 1e-30f ? x : 1e-30f));
    return x > 0.0f ? r : 0.0f;
}

static inline __attribute__((always_inline)) float clamp01(float v)
{
    v = v > 0.0f ? v : 0.0f;
    return v < 1.0f ? v : 1.0f;
}

/* The cube root of x > 0 (normal) without log2 and exp2: x^(-1/3) from the bits (3.9% at most), two
 * of Newton's steps on it, division-free (4e-5), then one on the root itself, with that inverse for
 * the derivative. Within 9.8e-8 relative of the true root over [216/24389, 2), every float there
 * tried (fexp2(flog2(x) / 3): 2.3e-7). */
static inline __attribute__((always_inline)) float fcbrt(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    u = 0x54a2fa8cu - u / 3u;
    float r;
    memcpy(&r, &u, sizeof r);
    for (int k = 0; k < 2; k++) {
        float e = 1.0f - x * (r * r * r);
        r = r + r * e * (1.0f / 3.0f);
    }
    float y = x * r * r;
    return y + (x - y * y * y) * (r * r) * (1.0f / 3.0f);
}

/* CIELAB's f of t >= 0 */
static inline __attribute__((always_inline)) float lab_f(float t)
{
    const float delta = 6.0f / 29.0f, d2 = delta * delta, d3 = delta * d2;
    const float factor = 1.0f / (3.0f * d2), term = 4.0f / 29.0f;
    float c = fcbrt(t > d3 ? t : d3);
    return t > d3 ? c : factor * t + term;
}

/* ---- the filters ----------------------------------------------------------------------------- */

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

static int feature_radius(float ppd)
{
    return (int)ceilf(3.0f * (0.5f * 0.082f * ppd));
}

/* The taps from the centre out (0..r): Y's, Cx's and Cz's two CSFs; the feature Gaussian, its first
 * derivative (antisymmetric: the tap at +i, minus it at -i) and second. */
enum { F_Y, F_CX, F_CZ1, F_CZ2, F_G, F_DG, F_DDG, F_N };

typedef struct flip_filters {
    int rs, rf, r; /* spatial, feature, the larger */
    float *tap[F_N];
} flip_filters;

static void spatial_taps(float ppd, int r, float *const *t)
{
    float dx = 1.0f / ppd, s[4] = {0, 0, 0, 0};
    for (int i = -r; i <= r; i++) {
        float x = (float)i * dx, x2 = x * x;
        float v[4] = {gauss_ab(x2, 1.0f, 0.0047f), gauss_ab(x2, 1.0f, 0.0053f), gauss_ab_sqrt(x2, 34.1f, 0.04f),
                      gauss_ab_sqrt(x2, 13.5f, 0.025f)};
        for (int q = 0; q < 4; q++) {
            s[q] += v[q];
            if (i >= 0) t[F_Y + q][i] = v[q];
        }
    }
    float ny = 1.0f / s[0], nx = 1.0f / s[1], nz = 1.0f / sqrtf(s[2] * s[2] + s[3] * s[3]);
    for (int i = 0; i <= r; i++) t[F_Y][i] *= ny, t[F_CX][i] *= nx, t[F_CZ1][i] *= nz, t[F_CZ2][i] *= nz;
}

static void feature_taps(float ppd, int r, float *const *t)
{
    float sd = 0.5f * 0.082f * ppd, gs = 0, dp = 0, ddp = 0, ddn = 0;
    for (int i = -r; i <= r; i++) {
        float x = (float)i, g = expf(-(x * x) / (2.0f * sd * sd)), ddg = (x * x / (sd * sd) - 1.0f) * g;
        gs += g;
        if (i < 0) dp += x * g * -1.0f; /* -x g > 0 on the left; the right's negatives sum to the same */
        if (ddg > 0.0f)
            ddp += ddg;
        else
            ddn -= ddg;
        if (i >= 0) t[F_G][i] = g, t[F_DG][i] = -x * g, t[F_DDG][i] = ddg;
    }
    for (int i = 0; i <= r; i++) {
        t[F_G][i] /= gs;
        t[F_DG][i] /= dp;
        t[F_DDG][i] /= t[F_DDG][i] > 0.0f ? ddp : ddn;
    }
}

static fb_result filters_init(flip_filters *f, float ppd)
{
    memset(f, 0, sizeof *f);
    f->rs = spatial_radius(ppd), f->rf = feature_radius(ppd);
    f->r = f->rs > f->rf ? f->rs : f->rf;
    for (int q = 0; q < F_N; q++)
        if (!(f->tap[q] = calloc((size_t)f->r + 1, sizeof(float))))
            return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP's filters");
    spatial_taps(ppd, f->rs, f->tap);
    feature_taps(ppd, f->rf, f->tap);
    return FB_OK;
}

static void filters_fini(flip_filters *f)
{
    for (int q = 0; q < F_N; q++) free(f->tap[q]);
}

#pragma GCC diagnostic ignored "-Wpsabi" /* v8f passed between inlined helpers only */
typedef float v8f __attribute__((vector_size(32)));

static inline __attribute__((always_inline)) v8f ld8(const float *p)
{
    v8f v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* The four filters of one row at once, 8 pixels at a time with the sums in registers: o[0] the
 * symmetric c[0] (radius r0), o[1] and o[3] the symmetric c[1], c[3], o[2] the antisymmetric c[2]
 * (radius r1 <= r0). Each sum is taken in hfilter's order: the same bits. */
FB_CLONES static void hfilter4(const float *p, const float *const c[4], int r0, int r1, int w, float *const o[4])
{
    int x = 0;
    for (; x + 8 <= w; x += 8) {
        const float *q = p + x;
        v8f m = ld8(q), a0 = c[0][0] * m, a1 = c[1][0] * m, a2 = {0}, a3 = c[3][0] * m;
        for (int i = 1; i <= r1; i++) {
            v8f u = ld8(q + i), v = ld8(q - i), sum = u + v, dif = u - v;
            a0 += c[0][i] * sum, a1 += c[1][i] * sum, a2 += c[2][i] * dif, a3 += c[3][i] * sum;
        }
        for (int i = r1 + 1; i <= r0; i++) a0 += c[0][i] * (ld8(q + i) + ld8(q - i));
        memcpy(o[0] + x, &a0, sizeof a0), memcpy(o[1] + x, &a1, sizeof a1);
        memcpy(o[2] + x, &a2, sizeof a2), memcpy(o[3] + x, &a3, sizeof a3);
    }
    for (; x < w; x++) { /* the last few, one at a time */
        const float *q = p + x;
        float m = q[0], a0 = c[0][0] * m, a1 = c[1][0] * m, a2 = 0.0f, a3 = c[3][0] * m;
        for (int i = 1; i <= r1; i++) {
            float u = q[i], v = q[-i], sum = u + v, dif = u - v;
            a0 += c[0][i] * sum, a1 += c[1][i] * sum, a2 += c[2][i] * dif, a3 += c[3][i] * sum;
        }
        for (int i = r1 + 1; i <= r0; i++) a0 += c[0][i] * (q[i] + q[-i]);
        o[0][x] = a0, o[1][x] = a1, o[2][x] = a2, o[3][x] = a3;
    }
}

/* Down the rows, five filters at once the same way: o[0] the symmetric c[0] over the rows Ry (radius
 * r0), o[1] the symmetric c[1] over Rx and o[4] the same over Rd, o[2] the antisymmetric c[2] and
 * o[3] the symmetric c[3], both over Rg (radius r1 <= r0); vfilter's order, the same bits. */
FB_CLONES static void vfilter5(const float *const *Ry, const float *const *Rx, const float *const *Rg,
                               const float *const *Rd, const float *const c[4], int r0, int r1, int w,
                               float *const o[5])
{
    int x = 0;
    for (; x + 16 <= w; x += 16) { /* two vectors a sum: the rows' pointers and the taps loaded once for both */
        int y = x + 8;
        v8f a0 = c[0][0] * ld8(Ry[0] + x), a1 = c[1][0] * ld8(Rx[0] + x), a2 = {0}, a3 = c[3][0] * ld8(Rg[0] + x);
        v8f b0 = c[0][0] * ld8(Ry[0] + y), b1 = c[1][0] * ld8(Rx[0] + y), b2 = {0}, b3 = c[3][0] * ld8(Rg[0] + y);
        v8f a4 = c[1][0] * ld8(Rd[0] + x), b4 = c[1][0] * ld8(Rd[0] + y);
        for (int i = 1; i <= r1; i++) {
            const float *yp = Ry[i], *ym = Ry[-i], *xp = Rx[i], *xm = Rx[-i], *gp = Rg[i], *gm = Rg[-i];
            const float *dp = Rd[i], *dm = Rd[-i];
            float c0 = c[0][i], c1 = c[1][i], c2 = c[2][i], c3 = c[3][i];
            v8f u = ld8(gp + x), v = ld8(gm + x), uu = ld8(gp + y), vv = ld8(gm + y);
            a0 += c0 * (ld8(yp + x) + ld8(ym + x)), b0 += c0 * (ld8(yp + y) + ld8(ym + y));
            a1 += c1 * (ld8(xp + x) + ld8(xm + x)), b1 += c1 * (ld8(xp + y) + ld8(xm + y));
            a2 += c2 * (u - v), b2 += c2 * (uu - vv), a3 += c3 * (u + v), b3 += c3 * (uu + vv);
            a4 += c1 * (ld8(dp + x) + ld8(dm + x)), b4 += c1 * (ld8(dp + y) + ld8(dm + y));
        }
        for (int i = r1 + 1; i <= r0; i++) {
            a0 += c[0][i] * (ld8(Ry[i] + x) + ld8(Ry[-i] + x));
            b0 += c[0][i] * (ld8(Ry[i] + y) + ld8(Ry[-i] + y));
        }
        memcpy(o[0] + x, &a0, sizeof a0), memcpy(o[1] + x, &a1, sizeof a1);
        memcpy(o[2] + x, &a2, sizeof a2), memcpy(o[3] + x, &a3, sizeof a3);
        memcpy(o[0] + y, &b0, sizeof b0), memcpy(o[1] + y, &b1, sizeof b1);
        memcpy(o[2] + y, &b2, sizeof b2), memcpy(o[3] + y, &b3, sizeof b3);
        memcpy(o[4] + x, &a4, sizeof a4), memcpy(o[4] + y, &b4, sizeof b4);
    }
    for (; x + 8 <= w; x += 8) {
        v8f m = ld8(Rg[0] + x), a0 = c[0][0] * ld8(Ry[0] + x), a1 = c[1][0] * ld8(Rx[0] + x), a2 = {0};
        v8f a3 = c[3][0] * m, a4 = c[1][0] * ld8(Rd[0] + x);
        for (int i = 1; i <= r1; i++) {
            v8f u = ld8(Rg[i] + x), v = ld8(Rg[-i] + x);
            a0 += c[0][i] * (ld8(Ry[i] + x) + ld8(Ry[-i] + x));
            a1 += c[1][i] * (ld8(Rx[i] + x) + ld8(Rx[-i] + x));
            a2 += c[2][i] * (u - v), a3 += c[3][i] * (u + v);
            a4 += c[1][i] * (ld8(Rd[i] + x) + ld8(Rd[-i] + x));
        }
        for (int i = r1 + 1; i <= r0; i++) a0 += c[0][i] * (ld8(Ry[i] + x) + ld8(Ry[-i] + x));
        memcpy(o[0] + x, &a0, sizeof a0), memcpy(o[1] + x, &a1, sizeof a1);
        memcpy(o[2] + x, &a2, sizeof a2), memcpy(o[3] + x, &a3, sizeof a3);
        memcpy(o[4] + x, &a4, sizeof a4);
    }
    for (; x < w; x++) { /* the last few, one at a time */
        float a0 = c[0][0] * Ry[0][x], a1 = c[1][0] * Rx[0][x], a2 = 0.0f, a3 = c[3][0] * Rg[0][x];
        float a4 = c[1][0] * Rd[0][x];
        for (int i = 1; i <= r1; i++) {
            float u = Rg[i][x], v = Rg[-i][x];
            a0 += c[0][i] * (Ry[i][x] + Ry[-i][x]), a1 += c[1][i] * (Rx[i][x] + Rx[-i][x]);
            a2 += c[2][i] * (u - v), a3 += c[3][i] * (u + v), a4 += c[1][i] * (Rd[i][x] + Rd[-i][x]);
        }
        for (int i = r1 + 1; i <= r0; i++) a0 += c[0][i] * (Ry[i][x] + Ry[-i][x]);
        o[0][x] = a0, o[1][x] = a1, o[2][x] = a2, o[3][x] = a3, o[4][x] = a4;
    }
}

/* out = the filter c down the rows rows[-r..r] (rows points at the centre's pointer) */
FB_CLONES static void vfilter(const float *const *rows, const float *c, int r, bool anti, int w, float *out)
{
    const float *m = rows[0];
    if (anti)
        for (int x = 0; x < w; x++) out[x] = 0.0f;
    else
        for (int x = 0; x < w; x++) out[x] = c[0] * m[x];
    for (int i = 1; i <= r; i++) {
        float ci = c[i];
        const float *a = rows[i], *b = rows[-i];
        if (anti)
            for (int x = 0; x < w; x++) out[x] += ci * (a[x] - b[x]);
        else
            for (int x = 0; x < w; x++) out[x] += ci * (a[x] + b[x]);
    }
}

/* out = the filter c (taps 0..r) along a row p, read from p[-r] to p[w - 1 + r]: vfilter over the
 * row shifted by each tap */
static void hfilter(const float *p, const float *c, int r, bool anti, int w, float *out)
{
    const float *rows[2 * 64 + 1];
    for (int i = -r; i <= r; i++) rows[64 + i] = p + i;
    vfilter(rows + 64, c, r, anti, w, out);
}

/* ---- one row to linear YCxCz ----------------------------------------------------------------- */

static inline __attribute__((always_inline)) float srgb_to_linear(float c)
{
    float p = fpow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
    return c <= 0.04045f ? c / 12.92f : p;
}

static inline __attribute__((always_inline)) float tone(float v, float m)
{
    v *= m;
    v = (v * v * ACES[0] + v * ACES[1] + ACES[2]) / (v * v * ACES[3] + v * ACES[4] + ACES[5]);
    return clamp01(v);
}

/* w values of plane s to linear: exposed by m and tone mapped (hdr), or decoded from sRGB */
static inline __attribute__((always_inline)) void linear_plane(const float *s, int w, bool hdr, float m, float *o)
{
    if (hdr)
        for (int x = 0; x < w; x++) o[x] = tone(s[x], m);
    else
        for (int x = 0; x < w; x++) o[x] = srgb_to_linear(s[x]);
}

/* y (the linear luminance, which is both Y/116 + 16/116 and what the CSF of Y filters) and, in
 * colour, Cx and Cz, of w pixels of the planes s (exposed by m and tone mapped when hdr). */
FB_CLONES static void linear_row(const float *const s[3], int w, bool hdr, float m, bool grey, float *y, float *cx,
                                 float *cz)
{
    linear_plane(s[0], w, hdr, m, y);
    if (grey) return;
    linear_plane(s[1], w, hdr, m, cx);
    linear_plane(s[2], w, hdr, m, cz);
    for (int x = 0; x < w; x++) {
        float r = y[x], g = cx[x], b = cz[x];
        float X = A11 * r + A12 * g + A13 * b, Y = A21 * r + A22 * g + A23 * b, Z = A31 * r + A32 * g + A33 * b;
        y[x] = Y;
        cx[x] = 500.0f * (X * INV_ILL[0] - Y);
        cz[x] = 200.0f * (Y - Z * INV_ILL[2]);
    }
}

/* ---- the error of one row from the filtered planes ------------------------------------------- */

/* the filtered planes of one output row of one image */
enum { V_Y, V_CX, V_CZ, V_DX, V_DDX, V_DY, V_DDY, V_T, V_N }; /* V_T: Cz's second part */

/* Hunt-adjusted CIELAB of the filtered (y, cx, cz): to XYZ, linear RGB clamped, back */
static inline __attribute__((always_inline)) void filtered_lab(float fy, float fcx, float fcz, bool grey, float lab[3])
{
    if (grey) {
        float l = 116.0f * lab_f(clamp01(fy)) - 16.0f;
        lab[0] = l, lab[1] = lab[2] = 0.0f;
        return;
    }
    float X = (fy + fcx * (1.0f / 500.0f)) * ILL[0], Y = fy, Z = (fy - fcz * (1.0f / 200.0f)) * ILL[2];
    float r = clamp01(3.241003275f * X + -1.537398934f * Y + -0.498615861f * Z);
    float g = clamp01(-0.969224334f * X + 1.875930071f * Y + 0.041554224f * Z);
    float b = clamp01(0.055639423f * X + -0.204011202f * Y + 1.057148933f * Z);
    X = A11 * r + A12 * g + A13 * b, Y = A21 * r + A22 * g + A23 * b, Z = A31 * r + A32 * g + A33 * b;
    float fx = lab_f(X * INV_ILL[0]), fyy = lab_f(Y), fz = lab_f(Z * INV_ILL[2]);
    float l = 116.0f * fyy - 16.0f;
    lab[0] = l, lab[1] = 0.01f * l * (500.0f * (fx - fyy)), lab[2] = 0.01f * l * (200.0f * (fyy - fz));
}

typedef struct row_consts {
    float cmax, pccmax;
    float lc;  /* log2(0.95 / pccmax): the colour error's scale below pccmax, in the exponent */
    float hyt; /* a little below the HyAB distance whose 0.7th power is pccmax */
} row_consts;

/* The colour distance (HyAB of the Hunt-adjusted CIELAB) and the feature difference of pixel x. */
static inline __attribute__((always_inline)) void pixel_parts(const float *const *a, const float *const *b, int x,
                                                              bool grey, float *hy, float *f)
{
    float la[3], lb[3];
    filtered_lab(a[V_Y][x], grey ? 0.0f : a[V_CX][x], grey ? 0.0f : a[V_CZ][x], grey, la);
    filtered_lab(b[V_Y][x], grey ? 0.0f : b[V_CX][x], grey ? 0.0f : b[V_CZ][x], grey, lb);
    float da = la[1] - lb[1], db = la[2] - lb[2];
    *hy = fabsf(la[0] - lb[0]) + sqrtf(da * da + db * db);
    float ea = sqrtf(a[V_DX][x] * a[V_DX][x] + a[V_DY][x] * a[V_DY][x]);
    float pa = sqrtf(a[V_DDX][x] * a[V_DDX][x] + a[V_DDY][x] * a[V_DDY][x]);
    float eb = sqrtf(b[V_DX][x] * b[V_DX][x] + b[V_DY][x] * b[V_DY][x]);
    float pb = sqrtf(b[V_DDX][x] * b[V_DDX][x] + b[V_DDY][x] * b[V_DDY][x]);
    float de = fabsf(ea - eb), dp = fabsf(pa - pb);
    *f = sqrtf(0.707106781f * (de > dp ? de : dp));
}

/* The error color^(1 - f) where color = hy^0.7 mapped to [0, 1]: below 0.95 (most pixels) the map is
 * a scale, taken in the exponent: 2^((1 - f) (0.7 log2 hy + lc)). */
static inline __attribute__((always_inline)) float error_low(float hy, float f, row_consts k)
{
    float e = fexp2((1.0f - f) * (0.7f * flog2(hy > 1e-30f ? hy : 1e-30f) + k.lc));
    return hy > 0.0f ? e : f >= 1.0f ? 1.0f : 0.0f; /* 0^0 = 1, as powf */
}

/* The same in full, for any hy. */
static float error_full(float hy, float f, row_consts k)
{
    float d = fpow(hy, 0.7f);
    d = d < k.pccmax ? d * (0.95f / k.pccmax) : 0.95f + ((d - k.pccmax) / (k.cmax - k.pccmax)) * (1.0f - 0.95f);
    float e = fexp2((1.0f - f) * flog2(d > 1e-30f ? d : 1e-30f));
    return d > 0.0f ? e : f >= 1.0f ? 1.0f : 0.0f;
}

FB_CLONES static void parts_row_grey(const float *const *a, const float *const *b, int w, row_consts k,
                                     float *restrict hy, float *restrict f, float *restrict e)
{
    for (int x = 0; x < w; x++) pixel_parts(a, b, x, true, &hy[x], &f[x]), e[x] = error_low(hy[x], f[x], k);
}

FB_CLONES static void parts_row_colour(const float *const *a, const float *const *b, int w, row_consts k,
                                       float *restrict hy, float *restrict f, float *restrict e)
{
    for (int x = 0; x < w; x++) pixel_parts(a, b, x, false, &hy[x], &f[x]), e[x] = error_low(hy[x], f[x], k);
}

/* One output row's error: the parts along the row, the few pixels of large colour error again in
 * full, then the largest over the exposures so far. */
static void error_row(const float *const *a, const float *const *b, int w, bool grey, row_consts k, bool first,
                      float *const t[3], float *err)
{
    float *hy = t[0], *f = t[1], *e = t[2];
    if (grey)
        parts_row_grey(a, b, w, k, hy, f, e);
    else
        parts_row_colour(a, b, w, k, hy, f, e);
    for (int x = 0; x < w; x++)
        if (hy[x] >= k.hyt) e[x] = error_full(hy[x], f[x], k);
    for (int x = 0; x < w; x++) {
        float o = first ? 0.0f : err[x];
        err[x] = e[x] > o ? e[x] : o;
    }
}

/* ---- jobs and bands -------------------------------------------------------------------------- */

/* the horizontally filtered planes kept in the ring, per image */
enum { H_Y, H_CX, H_CZ1, H_CZ2, H_G, H_DX, H_DDX, H_N };

struct fb_flip_job {
    const float *src[2][3]; /* ref, test */
    int w, h, nexp;
    bool hdr, grey;
    float start, step;
    flip_filters f;
    row_consts k;
    float *map;
    int nomem; /* a band found no memory (written atomically) */
    fb_flip_result r;
};

/* the largest colour error: HyAB of green and blue, Hunt-adjusted, to the power 0.7 (libm here: once) */
static float max_distance(void)
{
    float lab[2][3];
    for (int s = 0; s < 2; s++) {
        float c[3] = {0, s == 0 ? 1.0f : 0.0f, s == 1 ? 1.0f : 0.0f};
        float X = A11 * c[0] + A12 * c[1] + A13 * c[2], Y = A21 * c[0] + A22 * c[1] + A23 * c[2];
        float Z = A31 * c[0] + A32 * c[1] + A33 * c[2], v[3] = {X * INV_ILL[0], Y, Z * INV_ILL[2]}, f[3];
        for (int q = 0; q < 3; q++)
            f[q] = v[q] > 216.0f / 24389.0f ? cbrtf(v[q]) : v[q] * (841.0f / 108.0f) + 4.0f / 29.0f;
        float l = 116.0f * f[1] - 16.0f;
        lab[s][0] = l, lab[s][1] = 0.01f * l * 500.0f * (f[0] - f[1]), lab[s][2] = 0.01f * l * 200.0f * (f[1] - f[2]);
    }
    float da = lab[0][1] - lab[1][1], db = lab[0][2] - lab[1][2];
    return powf(fabsf(lab[0][0] - lab[1][0]) + sqrtf(da * da + db * db), 0.7f);
}

fb_result fb_flip_job_create(const float *const ref[3], const float *const test[3], int width, int height, bool hdr,
                             float ppd, float *map, fb_flip_job **out)
{
    *out = NULL;
    fb_flip_job *j = calloc(1, sizeof *j);
    if (!j) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP");
    size_t n = (size_t)width * height;
    for (int q = 0; q < 3; q++) j->src[0][q] = ref[q], j->src[1][q] = test[q];
    j->w = width, j->h = height, j->hdr = hdr, j->map = map, j->nexp = 1;
    j->grey = ref[0] == ref[1] && ref[1] == ref[2] && test[0] == test[1] && test[1] == test[2];
    j->k.cmax = max_distance();
    j->k.pccmax = 0.4f * j->k.cmax;
    j->k.lc = (float)log2(0.95 / j->k.pccmax);
    j->k.hyt = (float)(pow(j->k.pccmax, 1 / 0.7) * (1 - 1e-5));
    fb_result rc = filters_init(&j->f, ppd);
    if (!rc && hdr) {
        fb_flip_result *r = &j->r;
        rc = fb_flip_exposures(ref, n, map, &r->start_exposure, &r->stop_exposure, &r->nexp, &r->zero_median);
        j->nexp = r->nexp, j->start = r->start_exposure;
        j->step = (r->stop_exposure - r->start_exposure) / (float)(r->nexp - 1);
    }
    if (rc) {
        filters_fini(&j->f);
        free(j);
        return rc;
    }
    *out = j;
    return FB_OK;
}

int fb_flip_job_bands(const fb_flip_job *j)
{
    return (j->h + FLIP_BAND - 1) / FLIP_BAND;
}

/* A band's memory: per image, the padded linear rows and a ring of 2r + 1 rows of each horizontally
 * filtered plane; per output row, the vertically filtered planes. */
typedef struct band {
    int w, r, nring, nh, stride;
    float *mem;
    float *lin[2][3];    /* y, cx, cz, each w + 2r with r of clamped edge each side */
    float *ring[2][H_N]; /* nring rows of w each */
    float *v[2][V_N];    /* one row each */
    float *t[3];         /* an output row's colour distance, feature difference and error */
} band;

static bool band_init(band *b, const fb_flip_job *j)
{
    memset(b, 0, sizeof *b);
    b->w = j->w, b->r = j->f.r, b->nring = 2 * b->r + 1, b->nh = j->grey ? 4 : H_N;
    /* a ring row's stride: a cache line more than the row, rounded, so that the rows a filter reads
     * at once do not all fall in the same sets of the cache (4 KiB apart for 1024 pixels) */
    b->stride = ((b->w + 15) & ~15) + 16;
    size_t pad = (size_t)b->w + 2 * (size_t)b->r;
    size_t per = 3 * pad + (size_t)H_N * b->nring * b->stride + (size_t)(V_N + 2) * b->stride;
    if (!(b->mem = malloc(2 * per * sizeof(float)))) return false;
    for (int s = 0; s < 2; s++) {
        float *m = b->mem + s * per;
        for (int q = 0; q < 3; q++) b->lin[s][q] = m, m += pad;
        for (int q = 0; q < H_N; q++) b->ring[s][q] = m, m += (size_t)b->nring * b->stride;
        for (int q = 0; q < V_N; q++) b->v[s][q] = m, m += b->stride;
        for (int q = 0; q < 2 && s == 0; q++) b->t[q] = m, m += b->stride;
        if (s == 1) b->t[2] = m;
    }
    return true;
}

/* Row yy (clamped into the image) of image s, exposed by m, into the ring at slot. */
static void band_hrow(band *b, const fb_flip_job *j, int s, int yy, float m, int slot)
{
    int w = b->w, r = b->r;
    yy = yy < 0 ? 0 : yy >= j->h ? j->h - 1 : yy;
    const float *src[3];
    for (int q = 0; q < 3; q++) src[q] = j->src[s][q] + (size_t)yy * w;
    float *y = b->lin[s][0] + r, *cx = b->lin[s][1] + r, *cz = b->lin[s][2] + r;
    linear_row(src, w, j->hdr, m, j->grey, y, cx, cz);
    for (int q = 0; q < (j->grey ? 1 : 3); q++) {
        float *p = b->lin[s][q] + r;
        for (int i = 1; i <= r; i++) p[-i] = p[0], p[w - 1 + i] = p[w - 1];
    }
    const flip_filters *f = &j->f;
    float *const *rg = b->ring[s];
    size_t o = (size_t)slot * b->stride;
    if (f->rf <= f->rs) {
        hfilter4(y, (const float *const[4]){f->tap[F_Y], f->tap[F_G], f->tap[F_DG], f->tap[F_DDG]}, f->rs, f->rf, w,
                 (float *const[4]){rg[H_Y] + o, rg[H_G] + o, rg[H_DX] + o, rg[H_DDX] + o});
    } else {
        hfilter(y, f->tap[F_Y], f->rs, false, w, rg[H_Y] + o);
        hfilter(y, f->tap[F_G], f->rf, false, w, rg[H_G] + o);
        hfilter(y, f->tap[F_DG], f->rf, true, w, rg[H_DX] + o);
        hfilter(y, f->tap[F_DDG], f->rf, false, w, rg[H_DDX] + o);
    }
    if (j->grey) return;
    hfilter(cx, f->tap[F_CX], f->rs, false, w, rg[H_CX] + o);
    hfilter(cz, f->tap[F_CZ1], f->rs, false, w, rg[H_CZ1] + o);
    hfilter(cz, f->tap[F_CZ2], f->rs, false, w, rg[H_CZ2] + o);
}

/* The vertically filtered planes of output row y of image s (its ring holds rows y - r .. y + r). */
static void band_vrow(band *b, const fb_flip_job *j, int s, int y)
{
    const flip_filters *f = &j->f;
    int w = b->w, r = b->r;
    const float *rows[H_N][64 * 2 + 1], **c[H_N];
    size_t off[64 * 2 + 1]; /* the ring's rows y - r .. y + r: the slots from y - r's on, wrapping */
    for (int i = 0, slot = ((y - r) % b->nring + b->nring) % b->nring; i < b->nring; i++) {
        off[i] = (size_t)slot * b->stride;
        slot = slot + 1 == b->nring ? 0 : slot + 1;
    }
    for (int q = 0; q < H_N; q++) {
        c[q] = rows[q] + r;
        for (int i = 0; i < b->nring; i++) rows[q][i] = b->ring[s][q] + off[i];
    }
    float *const *v = b->v[s];
    if (f->rf <= f->rs) {
        vfilter5(c[H_Y], c[H_DX], c[H_G], c[H_DDX],
                 (const float *const[4]){f->tap[F_Y], f->tap[F_G], f->tap[F_DG], f->tap[F_DDG]}, f->rs, f->rf, w,
                 (float *const[5]){v[V_Y], v[V_DX], v[V_DY], v[V_DDY], v[V_DDX]});
    } else {
        vfilter(c[H_Y], f->tap[F_Y], f->rs, false, w, v[V_Y]);
        vfilter(c[H_DX], f->tap[F_G], f->rf, false, w, v[V_DX]);
        vfilter(c[H_G], f->tap[F_DG], f->rf, true, w, v[V_DY]);
        vfilter(c[H_G], f->tap[F_DDG], f->rf, false, w, v[V_DDY]);
        vfilter(c[H_DDX], f->tap[F_G], f->rf, false, w, v[V_DDX]);
    }
    if (j->grey) return;
    vfilter(c[H_CX], f->tap[F_CX], f->rs, false, w, v[V_CX]);
    vfilter(c[H_CZ1], f->tap[F_CZ1], f->rs, false, w, v[V_CZ]);
    vfilter(c[H_CZ2], f->tap[F_CZ2], f->rs, false, w, v[V_T]);
    for (int x = 0; x < w; x++) v[V_CZ][x] += v[V_T][x];
}

void fb_flip_job_band(fb_flip_job *j, int t)
{
    band b;
    if (j->f.r > 64 || !band_init(&b, j)) {
        __atomic_store_n(&j->nomem, 1, __ATOMIC_RELAXED);
        return;
    }
    int y0 = t * FLIP_BAND, y1 = y0 + FLIP_BAND < j->h ? y0 + FLIP_BAND : j->h, r = b.r;
    for (int e = 0; e < j->nexp; e++) {
        float m = j->hdr ? powf(2.0f, j->start + (float)e * j->step) : 1.0f;
        for (int yy = y0 - r; yy < y1 + r; yy++) {
            int slot = ((yy % b.nring) + b.nring) % b.nring;
            for (int s = 0; s < 2; s++) band_hrow(&b, j, s, yy, m, slot);
            int y = yy - r;
            if (y < y0) continue;
            for (int s = 0; s < 2; s++) band_vrow(&b, j, s, y);
            const float *va[V_N], *vb[V_N];
            for (int q = 0; q < V_N; q++) va[q] = b.v[0][q], vb[q] = b.v[1][q];
            float *err = j->map + (size_t)y * j->w;
            error_row(va, vb, j->w, j->grey, j->k, e == 0, b.t, err);
        }
    }
    free(b.mem);
}

fb_result fb_flip_job_finish(fb_flip_job **jp, fb_flip_result *out)
{
    fb_flip_job *j = *jp;
    *jp = NULL;
    memset(out, 0, sizeof *out);
    if (!j) return FB_OK;
    fb_result rc = j->nomem ? fb_fail(FB_ERR_NOMEM, "out of memory for FLIP (%d x %d)", j->w, j->h)
                            : fb_flip_pool(j->map, (size_t)j->w * j->h, out);
    out->start_exposure = j->r.start_exposure, out->stop_exposure = j->r.stop_exposure;
    out->nexp = j->r.nexp, out->zero_median = j->r.zero_median;
    filters_fini(&j->f);
    free(j);
    return rc;
}

/* ---- the whole, on a pool of its own --------------------------------------------------------- */

static int g_threads; /* fb_flip_set_threads; 0: one per core */

void fb_flip_set_threads(int n)
{
    g_threads = n;
}

static void band_task(void *ctx, int t)
{
    fb_flip_job_band(ctx, t);
}

fb_result fb_flip(const float *const ref[3], const float *const test[3], int width, int height, bool hdr, float ppd,
                  float *map, fb_flip_result *out)
{
    memset(out, 0, sizeof *out);
    size_t n = (size_t)width * height;
    float *err = map ? map : malloc((n ? n : 1) * sizeof *err);
    if (!err) return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP");
    fb_flip_job *j = NULL;
    fb_pool *pool = NULL;
    fb_result rc = fb_flip_job_create(ref, test, width, height, hdr, ppd, err, &j);
    if (!rc) rc = fb_pool_create(g_threads > 0 ? g_threads : fb_cpu_count(), &pool);
    if (!rc) fb_pool_run(pool, fb_flip_job_bands(j), band_task, j);
    fb_result rf = fb_flip_job_finish(&j, out);
    fb_pool_destroy(&pool);
    if (!map) free(err);
    return rc ? rc : rf;
}
