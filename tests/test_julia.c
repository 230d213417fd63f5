/*
 * The Julia kernel against closed forms and an independent double-precision reference written
 * here (not the shared kernel): known points, the allpass warp's unit-circle property (eq. 10),
 * the pole, the bailout-independent smooth count, the distance estimate, the polar seam.
 */
#include "../kernels/julia.h"

#include "testhelp.h"

#include <complex.h>
#include <math.h>
#include <string.h>

static K_FbmParams g_turb; /* unused while lambda = 0 */

static K_JuliaParams base(double cre, double cim, double are, double aim, int max_iter)
{
    K_JuliaParams p;
    memset(&p, 0, sizeof p);
    p.width = p.height = 200;
    p.max_iter = (uint)max_iter;
    p.c_re = (float)cre, p.c_im = (float)cim;
    p.a_re = (float)are, p.a_im = (float)aim;
    p.scale_u = p.scale_v = 3.0f;
    p.radius = 1.5f;
    p.rot_c = 1.0f;
    p.bailout2 = 4.0f;
    p.inv_width = p.inv_height = 1.0f / 200.0f;
    return p;
}

static void test_known_points(void)
{
    /* c = -1: the origin's orbit 0, -1, 0, -1, ... stays bounded */
    K_JuliaResult r = k_julia_orbit(base(-1, 0, 0, 0, 1000), 0, 0, 1e-3f, 0, 0, 0);
    CHECK(r.inside == 1 && r.iter == 1000 && r.nsmooth == 1000.0f && r.de == 0.0f);
    /* c = 0, a = 0: z_n = p^(2^n); inside for |p| < 1, else the first n with |p|^(2^n) >= 2 */
    int bad = 0;
    for (int i = 0; i < 400; i++) {
        double m = 0.3 + 0.004 * i, ang = 0.7 * i;
        if (fabs(m - 1) < 0.01) continue;
        double n_exact = log2(log(2.0) / log(m));
        if (m > 1 && fabs(n_exact - round(n_exact)) < 0.01) continue; /* a rounding tie: skip */
        K_JuliaResult q =
            k_julia_orbit(base(0, 0, 0, 0, 100), (float)(m * cos(ang)), (float)(m * sin(ang)), 1e-3f, 0, 0, 0);
        if (m < 1)
            bad += !(q.inside == 1 && q.iter == 100);
        else
            bad += !(q.inside == 0 && (double)q.iter == (m >= 2 ? 0 : ceil(n_exact)));
    }
    CHECKF(bad == 0, "%d points disagree with the closed form", bad);
}

/* Eq. 10: the warp keeps the unit circle (|z0| = 1) and, for |a| < 1, maps |p| < 1 inside and |p| > 1
 * outside. Observed through the escape test at step 0 with R^2 = 1 -/+ 1e-4. */
static void test_warp_circle(void)
{
    int bad = 0;
    for (int i = 0; i < 500; i++) {
        double ang = 0.0137 * i * 97, am = 0.1 + 0.0017 * i, aa = 0.3 * i;
        K_JuliaParams p = base(0.3, 0.1, am * cos(aa), am * sin(aa), 1);
        float x = (float)cos(ang), y = (float)sin(ang);
        p.bailout2 = 1.0f - 1e-4f;
        bad += k_julia_orbit(p, x, y, 1e-3f, 0, 0, 0).iter != 0; /* |z0| >= R: escapes at step 0 */
        p.bailout2 = 1.0f + 1e-4f;
        bad += k_julia_orbit(p, x, y, 1e-3f, 0, 0, 0).iter != 1;
        p.bailout2 = 1.0f;
        bad += k_julia_orbit(p, 0.9f * x, 0.9f * y, 1e-3f, 0, 0, 0).iter != 1; /* inside stays inside */
        bad += k_julia_orbit(p, 1.1f * x, 1.1f * y, 1e-3f, 0, 0, 0).iter != 0; /* outside stays outside */
    }
    CHECKF(bad == 0, "%d violations of |A| = 1 on the circle", bad);
}

/* The pole p = 1/a: no NaN or Inf, the pixel escapes at once. */
static void test_pole(void)
{
    K_JuliaParams p = base(-0.8, 0.156, 0.5, 0, 256);
    K_JuliaResult r = k_julia_orbit(p, 2.0f, 0.0f, 1e-3f, 0, 0, 0);
    CHECK(r.iter == 0 && r.inside == 0 && r.nsmooth == 0.0f && r.de == 0.0f);
    for (int i = -50; i <= 50; i++) {
        K_JuliaResult q = k_julia_orbit(p, 2.0f + 1e-7f * (float)i, 1e-7f * (float)(i % 7), 1e-3f, 0, 0, 0);
        CHECK(isfinite(q.nsmooth) && isfinite(q.de));
    }
}

/* Independent reference: the whole pipeline in double, written from the paper's equations. */
static int reference_iter(double complex pt, double complex a, double complex c, int max_iter, double R)
{
    double complex z = (pt - conj(a)) / (1.0 - a * pt);
    for (int n = 0; n < max_iter; n++) {
        if (cabs(z) >= R) return n;
        z = z * z + c;
    }
    return cabs(z) >= R ? max_iter : max_iter;
}

static double lcg_noise(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return ((double)(*s >> 8) / 16777216.0 - 0.5) * 2.0 * 0x1p-23;
}

/* The reference with a float-sized rounding (2^-23 relative, a fixed pseudo-random sequence per
 * `seed`) applied to the start point and after every step: what float arithmetic may do. */
static int noisy_iter(double complex pt, double complex a, double complex c, int max_iter, uint32_t seed)
{
    uint32_t s = seed * 2654435761u + 1u;
#define NOISE() lcg_noise(&s)
    pt *= 1.0 + NOISE() + I * NOISE();
    double complex z = (pt - conj(a)) / (1.0 - a * pt);
    for (int n = 0; n < max_iter; n++) {
        if (cabs(z) >= 2.0) return n;
        z = (z * z + c) * (1.0 + NOISE() + I * NOISE());
    }
#undef NOISE
    return max_iter;
}

/* Numerically unstable: float-sized rounding can change the reference's count. */
static bool unstable(double complex pt, double complex a, double complex c, int max_iter, int ref)
{
    for (uint32_t k = 1; k <= 16; k++)
        if (noisy_iter(pt, a, c, max_iter, k) != ref) return true;
    return false;
}

/* The cases compared with the reference: c values, alpha values (each with both mappings). */
static const double cs[4][2] = {{-0.8, 0.156}, {-0.4, 0.6}, {0.285, 0.01}, {-1.0, 0.0}};
static const double as[3][2] = {{0, 0}, {0.5, 0.25}, {-0.3, 0}};

/* The reference cases' float parameters: c = cs[ci], alpha = as[ai], a 160 x 120 grid. */
static K_JuliaParams case_params(int mapping, int ci, int ai)
{
    K_JuliaParams p = base(cs[ci][0], cs[ci][1], as[ai][0], as[ai][1], 256);
    p.mapping = (uint)mapping;
    p.width = 160, p.height = 120;
    p.inv_width = 1.0f / 160, p.inv_height = 1.0f / 120;
    return p;
}

/* The same case's double-precision parameters (the rest of d as k_julia_d_constants left it). */
static void case_d(K_JuliaD *d, int ci, int ai)
{
    d->c_re = cs[ci][0], d->c_im = cs[ci][1], d->a_re = as[ai][0], d->a_im = as[ai][1];
    d->scale_u = d->scale_v = 3.0, d->radius = 1.5, d->rot_c = 1.0, d->rot_s = 0.0, d->bailout2 = 4.0;
}

/* The reference's starting point of pixel (x, y), in double: the rect grid 3 wide, or polar r = 1.5. */
static double complex reference_point(int mapping, uint x, uint y, uint W, uint H)
{
    double u = (x + 0.5) / W, v = 1.0 - (y + 0.5) / H;
    return mapping ? 1.5 * v * cexp(I * 2 * M_PI * u) : 3.0 * (u - 0.5) + I * 3.0 * (v - 0.5);
}

static void test_against_reference(void)
{
    for (int mapping = 0; mapping < 2; mapping++)
        for (int ci = 0; ci < 4; ci++)
            for (int ai = 0; ai < 3; ai++) {
                K_JuliaParams p = case_params(mapping, ci, ai);
                double complex a = as[ai][0] + I * as[ai][1], c = cs[ci][0] + I * cs[ci][1];
                int agree = 0, total = 0, stable = 0, stable_agree = 0;
                for (uint y = 0; y < p.height; y++)
                    for (uint x = 0; x < p.width; x++) {
                        double complex pt = reference_point(mapping, x, y, p.width, p.height);
                        int ref = reference_iter(pt, a, c, 256, 2.0);
                        bool same = (int)k_julia_pixel(p, g_turb, x, y).iter == ref;
                        agree += same;
                        total++;
                        if (same || !unstable(pt, a, c, 256, ref)) {
                            stable++;
                            stable_agree += same;
                        }
                    }
                /* Disagreements must be on unstable pixels. The classification is a sample of 16
                 * rounding sequences, so it misses some unstable pixels: allow 0.1% of the image. */
                CHECKF(stable - stable_agree <= total / 1000,
                       "mapping %d c %g%+gi alpha %g%+gi: %d stable pixels disagree", mapping, cs[ci][0], cs[ci][1],
                       as[ai][0], as[ai][1], stable - stable_agree);
                CHECKF(agree >= 0.96 * total, "mapping %d c %g%+gi alpha %g%+gi: %d of %d agree", mapping, cs[ci][0],
                       cs[ci][1], as[ai][0], as[ai][1], agree, total);
            }
}

/* The smooth count does not depend on the bailout (exactly: the orbit continues to a fixed big
 * radius), and it is continuous: for c = 0, a = 0 it is 1 - log2(ln |p|) in closed form, with no
 * step where the integer count steps (no banding). */
static void test_smooth(void)
{
    K_JuliaParams p2 = base(-0.8, 0.156, 0.5, 0.25, 256), p9 = p2;
    p9.bailout2 = 81.0f;
    int bad = 0;
    for (uint x = 0; x < 200; x++)
        for (uint y = 90; y < 110; y++) {
            K_JuliaResult a = k_julia_pixel(p2, g_turb, x, y), b = k_julia_pixel(p9, g_turb, x, y);
            bad += !a.inside && !b.inside && a.nsmooth != b.nsmooth; /* R = 9 may need more iterations */
        }
    CHECKF(bad == 0, "%d smooth counts depend on the bailout", bad);
    K_JuliaParams p0 = base(0, 0, 0, 0, 100);
    double worst = 0;
    for (int i = 0; i < 1000; i++) {
        double m = 1.02 + 0.0015 * i, ang = 0.37 * i;
        K_JuliaResult r = k_julia_orbit(p0, (float)(m * cos(ang)), (float)(m * sin(ang)), 1e-3f, 0, 0, 0);
        double want = 1.0 - log2(log(m));
        worst = fmax(worst, fabs(r.nsmooth - want));
    }
    /* float rounding of |p| (1e-7) moves log2(ln |p|) by 1e-7 / (|p| ln|p| ln 2) < 1e-4 here */
    CHECKF(worst < 1e-3, "smooth count off its closed form by %g", worst);
}

/* Distance estimate for c = 0, a = 0: exactly |p| ln|p| / (pixel size) for points outside. */
static void test_distance_estimate(void)
{
    K_JuliaParams p = base(0, 0, 0, 0, 100);
    float pix = p.scale_u * p.inv_width;
    int bad = 0;
    for (int i = 0; i < 200; i++) {
        double m = 1.01 + 0.005 * i, ang = 0.3 * i;
        K_JuliaResult r = k_julia_orbit(p, (float)(m * cos(ang)), (float)(m * sin(ang)), pix, 0, 0, 0);
        double want = m * log(m) / pix;
        bad += fabs(r.de - want) > 1e-3 * want;
    }
    CHECKF(bad == 0, "%d distance estimates off by more than 0.1%%", bad);
}

/* z'_0 = dz0/dx in double at texture coordinates (u, v) and grid point pt: dp/dx of the grid (rect
 * 3 / W; polar i 2 pi 1.5 v e^(i 2 pi u) / W), times the warp's A'(p) = (1 - |a|^2) / (1 - a p)^2. */
static double complex reference_dstart(int mapping, double u, double v, double complex pt, uint W, double complex a)
{
    double complex dp = mapping ? I * 2 * M_PI * 1.5 * v * cexp(I * 2 * M_PI * u) / W : 3.0 / W;
    double complex q = 1.0 - a * pt;
    return (1.0 - creal(a * conj(a))) / (q * q) * dp;
}

/* The distance estimate |z| ln|z| / |z'| against references of its own, for every c, alpha and
 * mapping of test_against_reference, with the derivative as a complex number in double,
 * z'_{k+1} = 2 z_k z'_k (the kernel keeps only |z'|^2, a float running product of 4 |z_k|^2).
 * Float: along the kernel's own float orbit (z stepped here with the same operations, so the same
 * escape count and the same z), the derivative in double from z'_0 in double. Every rounding of the
 * kernel's product is relative and nothing cancels (positive factors, |z|^2 a sum of squares): at
 * most 3 roundings a step (two squares and their sum; times 4 is exact; the product) and about 20
 * for |z'_0|^2 and the end (log2 within 1.31 ulp, sqrt, divide), so |z'| = sqrt(|z'|^2) and the
 * distance are within (1.5 m + 20) ulp after m steps: checked at (2 m + 32) * 2^-24 on every pixel
 * that escapes, where |z'| is in float's range; where it is beyond (|z'|^2 overflows), the distance
 * must be 0. Double precision: against an orbit all in double from the reference's grid point, on
 * the pixels where the orbit itself is well conditioned (2^-52 |z'_m| / |z'_0| < 1e-7: the two
 * orbits agree to that), at 1e-5. */
static void test_distance_reference(void)
{
    const double u = 0x1p-24;
    double worst = 0, worst_d = 0;
    int checked = 0, checked_d = 0, bad = 0, bad_zero = 0, bad_d = 0, mismatch = 0;
    K_JuliaD d;
    memset(&d, 0, sizeof d);
    k_julia_d_constants(&d);
    for (int mapping = 0; mapping < 2; mapping++)
        for (int ci = 0; ci < 4; ci++)
            for (int ai = 0; ai < 3; ai++) {
                K_JuliaParams p = case_params(mapping, ci, ai);
                case_d(&d, ci, ai);
                double complex a = as[ai][0] + I * as[ai][1], c = cs[ci][0] + I * cs[ci][1];
                for (uint y = 0; y < p.height; y++)
                    for (uint x = 0; x < p.width; x++) {
                        K_JuliaResult r = k_julia_pixel(p, g_turb, x, y);
                        K_JuliaStart s = k_julia_start_at(p, g_turb, (float)x + 0.5f, (float)y + 0.5f);
                        /* the orbit starts where the kernel's float grid puts it (v = 1 - y / H
                         * loses bits near v = 0); the derivative there is the reference's */
                        float uf = ((float)x + 0.5f) * p.inv_width, vf = 1.0f - ((float)y + 0.5f) * p.inv_height;
                        k_vec2 pf = k_julia_start(p, uf, vf);
                        double complex dz0 = reference_dstart(mapping, uf, vf, pf.x + I * (double)pf.y, p.width, a);
                        double complex dz = dz0;
                        /* float: the kernel's orbit, the derivative in double */
                        float zr = s.o.zr, zi = s.o.zi;
                        uint n = 0, m;
                        while (n < p.max_iter && zr * zr + zi * zi < p.bailout2) {
                            dz = 2.0 * ((double)zr + I * (double)zi) * dz;
                            float t = zr * zr - zi * zi + p.c_re;
                            zi = 2.0f * zr * zi + p.c_im;
                            zr = t;
                            n++;
                        }
                        bool escaped = zr * zr + zi * zi >= p.bailout2;
                        if (!s.ok || !escaped) {
                            mismatch += !s.ok ? r.iter != 0 : (r.inside != 1 || r.iter != n);
                            continue;
                        }
                        mismatch += r.inside != 0 || r.iter != n;
                        for (m = n; m < n + K_JULIA_EXTRA_ITER && zr * zr + zi * zi <= K_JULIA_BIG_RADIUS2; m++) {
                            dz = 2.0 * ((double)zr + I * (double)zi) * dz;
                            float t = zr * zr - zi * zi + p.c_re;
                            zi = 2.0f * zr * zi + p.c_im;
                            zr = t;
                        }
                        double r2 = (double)(zr * zr + zi * zi), adz = cabs(dz);
                        double want = sqrt(r2) * 0.5 * log(r2) / adz;
                        if (adz > 2e19) {
                            bad_zero += r.de != 0.0f; /* |z'|^2 beyond float: 0, never inf or NaN */
                        } else if (adz < 1e19 && adz > 1e-18) {
                            double e = fabs(r.de - want) / want;
                            checked++;
                            worst = fmax(worst, e / ((2.0 * m + 32) * u));
                            bad += !(e <= (2.0 * m + 32) * u);
                        }
                        /* double precision: the orbit in double too */
                        K_JuliaResult rd = k_julia_run_d(p, d, g_turb, x + 0.5, y + 0.5, K_JULIA_WANT_ALL);
                        double complex pt = reference_point(mapping, x, y, p.width, p.height);
                        double complex z = (pt - conj(a)) / (1.0 - a * pt);
                        dz = reference_dstart(mapping, (x + 0.5) / p.width, 1.0 - (y + 0.5) / p.height, pt, p.width, a);
                        dz0 = dz;
                        for (n = 0; n < p.max_iter && creal(z * conj(z)) < 4.0; n++) {
                            dz = 2.0 * z * dz;
                            z = z * z + c;
                        }
                        if (rd.inside || rd.iter != n || creal(z * conj(z)) < 4.0) continue;
                        for (m = n; m < n + K_JULIA_EXTRA_ITER && creal(z * conj(z)) <= 4294967296.0; m++) {
                            dz = 2.0 * z * dz;
                            z = z * z + c;
                        }
                        adz = cabs(dz);
                        if (!(0x1p-52 * adz / cabs(dz0) < 1e-7) || adz > 1e19) continue;
                        want = cabs(z) * log(cabs(z)) / adz;
                        double e = fabs(rd.de - want) / want;
                        checked_d++;
                        worst_d = fmax(worst_d, e);
                        bad_d += !(e <= 1e-5);
                    }
            }
    CHECKF(mismatch == 0, "%d pixels: the reference's float orbit is not the kernel's", mismatch);
    CHECKF(bad == 0, "%d of %d distance estimates beyond (2 m + 32) ulp of the reference", bad, checked);
    CHECKF(bad_zero == 0, "%d distance estimates not 0 where |z'|^2 overflows float", bad_zero);
    CHECKF(checked > 100000, "only %d distance estimates checked", checked);
    CHECKF(bad_d == 0, "double: %d of %d distance estimates beyond 1e-5 of the reference", bad_d, checked_d);
    CHECKF(checked_d > 50000, "double: only %d distance estimates checked", checked_d);
    printf("distance estimate: %d pixels within %.2f of their bound (2 m + 32) * 2^-24 of the double reference; "
           "double precision: %d within %.2g\n",
           checked, worst, checked_d, worst_d);
}

/* Polar mapping is exactly periodic in u: t(0, v) = t(1, v) bit for bit, and t(u, v) = t(u + 1, v)
 * to the rounding of u + 1. */
static void test_polar_seam(void)
{
    K_JuliaParams p = base(-0.8, 0.156, -0.3, 0, 256);
    p.mapping = K_JULIA_POLAR;
    int bad = 0;
    for (int i = 0; i < 200; i++) {
        float v = (i + 0.5f) / 200.0f, u = 0.25f / 200.0f;
        k_vec2 a = k_julia_start(p, u, v), b = k_julia_start(p, u + 1.0f, v);
        k_vec2 c = k_julia_start(p, 0.0f, v), d = k_julia_start(p, 1.0f, v);
        bad += c.x != d.x || c.y != d.y;                             /* exactly periodic */
        bad += fabsf(a.x - b.x) > 1e-6f || fabsf(a.y - b.y) > 1e-6f; /* u + 1 rounds in float */
    }
    CHECKF(bad == 0, "%d rows differ across the seam", bad);
}

/* Turbulence (eq. 13): lambda W with W in [0, 1]^2; tileable W keeps the polar sky's seam exact. */
static void test_turbulence(void)
{
    K_JuliaParams p = base(-0.8, 0.156, -0.3, 0, 256);
    p.mapping = K_JULIA_POLAR;
    p.lambda = 0.2f;
    K_FbmParams t;
    memset(&t, 0, sizeof t);
    t.seed = 5, t.octaves = 6, t.gain = 0.57f, t.lacunarity = 2.0f, t.rot_c = 0.8f, t.rot_s = 0.6f;
    t.flags = K_FBM_TILEABLE, t.freq_x = t.freq_y = 4.0f, t.width = t.height = 200;
    t.inv_width = t.inv_height = 1.0f / 200, t.inv_freq_x = t.inv_freq_y = 0.25f;
    double gsum = 0, g = 1;
    for (int i = 0; i < 6; i++, g *= 0.57) gsum += g;
    p.turb_norm = (float)(1 / gsum);
    int bad = 0, varied = 0;
    k_vec2 first = k_julia_turbulence(p, t, 0.1f, 0.5f);
    for (int i = 0; i < 400; i++) {
        float u = (i % 20) / 20.0f, v = (i / 20 + 0.5f) / 20.0f;
        k_vec2 w = k_julia_turbulence(p, t, u, v), w1 = k_julia_turbulence(p, t, u + 1.0f, v);
        bad += !(w.x >= 0 && w.x <= 0.2f && w.y >= 0 && w.y <= 0.2f);
        k_vec2 a = k_julia_turbulence(p, t, 0.0f, v), b = k_julia_turbulence(p, t, 1.0f, v);
        bad += a.x != b.x || a.y != b.y; /* t(0, v) = t(1, v) exactly */
        bad += fabsf(w.x - w1.x) > 2e-3f * 0.2f || fabsf(w.y - w1.y) > 2e-3f * 0.2f;
        varied += fabsf(w.x - first.x) > 0.01f;
    }
    CHECKF(bad == 0, "%d turbulence samples out of [0, lambda] or not periodic", bad);
    CHECKF(varied > 200, "turbulence barely varies (%d of 400 samples)", varied);
    /* lambda = 0 is exactly the unperturbed set */
    K_JuliaParams q = p;
    q.lambda = 0.0f;
    int diff = 0;
    for (uint x = 0; x < 200; x += 3) diff += k_julia_pixel(q, t, x, 77).iter != k_julia_pixel(q, g_turb, x, 77).iter;
    CHECK(diff == 0);
}

/* Double precision: sin/cos within 2 ulp-ish (4e-16) of libm over [0, 2 pi], and escape counts that
 * agree with the independent double reference on at least 99.9% of the pixels for every c, alpha
 * and mapping of test_against_reference (float reaches 96-99.8% there, limited by float's rounding). */
static void test_double(void)
{
    K_JuliaD d;
    memset(&d, 0, sizeof d);
    k_julia_d_constants(&d);
    double worst = 0;
    for (int i = 0; i <= 100000; i++) {
        double x = 6.283185307179586 * i / 100000;
        K_JuliaSinCos sc = k_julia_sincos_d(d, x);
        worst = fmax(worst, fmax(fabs(sc.s - sin(x)), fabs(sc.c - cos(x))));
    }
    CHECKF(worst < 4e-16, "sincos_d: max error %g", worst);
    double lowest = 1;
    for (int mapping = 0; mapping < 2; mapping++)
        for (int ci = 0; ci < 4; ci++)
            for (int ai = 0; ai < 3; ai++) {
                K_JuliaParams p = base(cs[ci][0], cs[ci][1], as[ai][0], as[ai][1], 256);
                p.mapping = (uint)mapping;
                p.width = 160, p.height = 120;
                case_d(&d, ci, ai);
                double complex a = as[ai][0] + I * as[ai][1], c = cs[ci][0] + I * cs[ci][1];
                int agree = 0, total = 0;
                for (uint y = 0; y < p.height; y++)
                    for (uint x = 0; x < p.width; x++) {
                        double complex pt = reference_point(mapping, x, y, p.width, p.height);
                        int ref = reference_iter(pt, a, c, 256, 2.0);
                        agree += (int)k_julia_run_d(p, d, g_turb, x + 0.5, y + 0.5, 0).iter == ref;
                        total++;
                    }
                lowest = fmin(lowest, (double)agree / total);
                CHECKF(agree >= 0.999 * total, "double: mapping %d c %g%+gi alpha %g%+gi: %d of %d agree", mapping,
                       cs[ci][0], cs[ci][1], as[ai][0], as[ai][1], agree, total);
            }
    printf("double precision: at least %.3f%% of escape counts agree with the reference\n", 100 * lowest);
}

static bool same_result(K_JuliaResult a, K_JuliaResult b, uint want)
{
    return a.iter == b.iter && a.inside == b.inside &&
           (!(want & K_JULIA_WANT_SMOOTH) || !memcmp(&a.nsmooth, &b.nsmooth, 4)) &&
           (!(want & K_JULIA_WANT_DE) || !memcmp(&a.de, &b.de, 4));
}

/* Two orbits in one loop (the shader's pairs) and orbits that skip the smooth count or the distance
 * give the single full orbit's values to the bit: escape counts of very different lengths side by
 * side, the pole, a lone last pixel, with turbulence, and a jittered sample. */
static void test_pairs(void)
{
    int bad = 0, checked = 0;
    for (int variant = 0; variant < 3; variant++) {
        K_JuliaParams p = base(-0.8, 0.156, variant == 1 ? 0.5 : 0.0, variant == 1 ? 0.25 : 0.0, 300);
        p.width = 97, p.height = 41;
        p.inv_width = 1.0f / 97, p.inv_height = 1.0f / 41;
        K_FbmParams t = g_turb;
        if (variant == 2) { /* polar with turbulence */
            p.mapping = K_JULIA_POLAR;
            p.lambda = 0.2f;
            p.turb_norm = 0.5f;
            t.octaves = 3;
        }
        for (uint y = 0; y < p.height; y++)
            for (uint x = 0; x < p.width; x += 2)
                for (uint want = 0; want <= K_JULIA_WANT_ALL; want++)
                    for (uint k = 0; k < 2; k++) {
                        bool has_b = x + 1 < p.width;
                        K_JuliaPair q = k_julia_sample2(p, t, 9, x, y, k, has_b, want);
                        K_JuliaResult a = k_julia_sample(p, t, 9, x, y, k);
                        bad += !same_result(q.a, a, want);
                        if (has_b) bad += !same_result(q.b, k_julia_sample(p, t, 9, x + 1, y, k), want);
                        checked += 1 + has_b;
                    }
    }
    /* the pole p = 1/a beside an ordinary pixel */
    K_JuliaParams p = base(-0.8, 0.156, 0.5, 0, 256);
    K_JuliaStart pole = k_julia_begin(p, 2.0f, 0.0f, 1e-3f, 0, 0, 0), ok = k_julia_begin(p, 0.1f, 0.2f, 1e-3f, 0, 0, 0);
    K_JuliaPair q = k_julia_orbit2(p, pole, ok, true, K_JULIA_WANT_ALL),
                r = k_julia_orbit2(p, ok, pole, true, K_JULIA_WANT_ALL);
    K_JuliaResult a = k_julia_orbit(p, 2.0f, 0.0f, 1e-3f, 0, 0, 0), b = k_julia_orbit(p, 0.1f, 0.2f, 1e-3f, 0, 0, 0);
    bad += !same_result(q.a, a, K_JULIA_WANT_ALL) + !same_result(q.b, b, K_JULIA_WANT_ALL);
    bad += !same_result(r.a, b, K_JULIA_WANT_ALL) + !same_result(r.b, a, K_JULIA_WANT_ALL);
    CHECKF(bad == 0 && checked > 20000, "%d of %d paired or partial orbits differ from the full single orbit", bad,
           checked);
}

int main(void)
{
    test_double();
    test_pairs();
    test_turbulence();
    test_known_points();
    test_warp_circle();
    test_pole();
    test_against_reference();
    test_smooth();
    test_distance_estimate();
    test_distance_reference();
    test_polar_seam();
    TEST_REPORT();
}
