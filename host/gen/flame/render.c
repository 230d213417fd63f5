/*
 * A flame's render after (and around) the chaos game, as flam3 3.1.1's render_rectangle: camera,
 * kernel tables, density estimation, spatial filter and tone map. The formulas are flam3's, from
 * Draves and Reckase, "The Fractal Flame Algorithm" (2008), and flam3's filters.c and rect.c.
 */
#include "render.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define PREFILTER_WHITE 255.0
#define DE_THRESH       100

/* ---- spatial filters (flam3's filters.c, after Graphics Gems III and ImageMagick) ------------- */

static const double support[14] = {1.5, 1.0, 0.5, 1.0, 1.5, 2.0, 2.0, 1.0, 2.0, 1.0, 1.0, 3.0, 2.0, 1.5};

static double sinc(double x)
{
    x *= M_PI;
    return x != 0 ? sin(x) / x : 1.0;
}

static double filter_at(int k, double t)
{
    double a = fabs(t), tt;
    switch (k) {
    case 0:
        return exp(-2.0 * t * t) * sqrt(2.0 / M_PI);
    case 1:
        return a < 1.0 ? (2.0 * a - 3.0) * a * a + 1.0 : 0.0;
    case 2:
        return t > -0.5 && t <= 0.5 ? 1.0 : 0.0;
    case 3:
        return a < 1.0 ? 1.0 - a : 0.0;
    case 4:
        if (a < .5) return .75 - a * a;
        if (a < 1.5) return .5 * (a - 1.5) * (a - 1.5);
        return 0.0;
    case 5:
        if (a < 1) return .5 * a * a * a - a * a + 2.0 / 3.0;
        if (a < 2) return (2 - a) * (2 - a) * (2 - a) / 6.0;
        return 0.0;
    case 6: {
        const double B = 1.0 / 3.0, C = 1.0 / 3.0;
        tt = t * t; /* flam3 squares t before taking its absolute value: the same */
        if (a < 1.0)
            return (((12.0 - 9.0 * B - 6.0 * C) * (a * tt)) + ((-18.0 + 12.0 * B + 6.0 * C) * tt) + (6.0 - 2 * B)) /
                   6.0;
        if (a < 2.0)
            return (((-1.0 * B - 6.0 * C) * (a * tt)) + ((6.0 * B + 30.0 * C) * tt) + ((-12.0 * B - 48.0 * C) * a) +
                    (8.0 * B + 24 * C)) /
                   6.0;
        return 0.0;
    }
    case 7:
        return sinc(t) * (0.42 + 0.5 * cos(M_PI * t) + 0.08 * cos(2 * M_PI * t));
    case 8:
        if (t < -2.0) return 0.0;
        if (t < -1.0) return 0.5 * (4.0 + t * (8.0 + t * (5.0 + t)));
        if (t < 0.0) return 0.5 * (2.0 + t * t * (-5.0 - 3.0 * t));
        if (t < 1.0) return 0.5 * (2.0 + t * t * (-5.0 + 3.0 * t));
        if (t < 2.0) return 0.5 * (4.0 + t * (-8.0 + t * (5.0 - t)));
        return 0.0;
    case 9:
        return sinc(t) * (0.5 + 0.5 * cos(M_PI * t));
    case 10:
        return sinc(t) * (0.54 + 0.46 * cos(M_PI * t));
    case 11:
        return (a < 3.0 ? sinc(a) * sinc(a / 3.0) : 0.0) * sinc(t / 3.0);
    case 12:
        return (a < 2.0 ? sinc(a) * sinc(a / 2.0) : 0.0) * sinc(t / 2.0);
    default:
        if (t < -1.5) return 0.0;
        if (t < -0.5) return 0.5 * (t + 1.5) * (t + 1.5);
        if (t < 0.5) return 0.75 - t * t;
        if (t < 1.5) return 0.5 * (t - 1.5) * (t - 1.5);
        return 0.0;
    }
}

/* flam3_create_spatial_filter (pixel aspect 1, no fields). */
static fb_result spatial_filter(int shape, int ss, double radius, double **out, int *width)
{
    double supp = support[shape], fw = 2.0 * supp * ss * radius;
    int n = (int)fw + 1;
    if ((n ^ ss) & 1) n++;
    double adjust = fw > 0.0 ? supp * n / fw : 1.0;
    double *f = calloc((size_t)n * n, sizeof *f);
    if (!f) return fb_fail(FB_ERR_NOMEM, "out of memory");
    double sum = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double ii = ((2.0 * i + 1.0) / n - 1.0) * adjust, jj = ((2.0 * j + 1.0) / n - 1.0) * adjust;
            f[i + j * n] = filter_at(shape, ii) * filter_at(shape, jj);
            sum += f[i + j * n];
        }
    if (sum == 0.0) {
        free(f);
        return fb_fail(FB_ERR_INPUT, "the spatial filter (radius %g) is too small", radius);
    }
    for (int i = 0; i < n * n; i++) f[i] *= 1.0 / sum;
    *out = f;
    *width = n;
    return FB_OK;
}

/* flam3_create_de_filters. */
static fb_result de_filters(double max_rad, double min_rad, double curve, int ss, fb_flame_setup *s)
{
    if (max_rad < min_rad)
        return fb_fail(FB_ERR_INPUT, "estimator_radius %g is smaller than estimator_minimum %g", max_rad, min_rad);
    double cmax = max_rad * ss + 1, cmin = min_rad * ss + 1;
    double nd = pow(cmax / cmin, 1.0 / curve);
    if (nd > 1e7) return fb_fail(FB_ERR_INPUT, "density estimation would need %g filters (estimator_curve)", nd);
    int nf = (int)ceil(nd), max_ind, keep = 100;
    if (nf > keep) {
        max_ind = (int)ceil(DE_THRESH + pow(nf - DE_THRESH, curve)) + 1;
        s->de_max_counts = (int)pow((double)(max_ind - DE_THRESH), 1.0 / curve) + DE_THRESH;
    } else {
        max_ind = nf;
        s->de_max_counts = max_ind;
    }
    int row = (int)(2 * ceil(cmax) - 1), half = (row - 1) / 2;
    s->de_kernel_size = (half + 1) * (2 + half) / 2;
    s->de_coefs = calloc((size_t)max_ind * s->de_kernel_size, sizeof *s->de_coefs);
    s->de_widths = calloc((size_t)max_ind, sizeof *s->de_widths);
    if (!s->de_coefs || !s->de_widths) return fb_fail(FB_ERR_NOMEM, "out of memory");
    s->de_max_index = 0;
    for (int fl = 0; fl < max_ind; fl++) {
        double h = fl < keep ? cmax / pow(fl + 1, curve) : cmax / pow(pow(fl - keep, 1.0 / curve) + keep + 1, curve);
        if (h <= cmin) {
            h = cmin;
            s->de_max_index = fl;
        }
        s->de_widths[fl] = h;
        double sum = 0;
        for (int j = -half; j <= half; j++)
            for (int k = -half; k <= half; k++) {
                double d = sqrt((double)(j * j + k * k)) / h;
                if (d <= 1.0) sum += filter_at(0, support[0] * d);
            }
        int at = fl * s->de_kernel_size;
        for (int j = 0; j <= half; j++)
            for (int k = 0; k <= j; k++) {
                double d = sqrt((double)(j * j + k * k)) / h;
                s->de_coefs[at++] = d > 1.0 ? 0.0 : filter_at(0, support[0] * d) / sum;
            }
        if (s->de_max_index > 0) break;
    }
    if (s->de_max_index == 0) s->de_max_index = max_ind - 1;
    return FB_OK;
}

/* ---- the kernel's tables --------------------------------------------------------------------- */

/* The parameters of variations 0 .. 54 as kernels/flame_var.h reads them (its comments say which). */
static void params_classic(const fb_flame_xform *x, int v, double q[8])
{
    const double *P = x->par, EPS = 1e-10;
    switch (v) {
    case K_V_WAVES:
        q[0] = x->c[1][0], q[1] = x->c[1][1];
        q[2] = 1.0 / (x->c[2][0] * x->c[2][0] + EPS), q[3] = 1.0 / (x->c[2][1] * x->c[2][1] + EPS);
        break;
    case K_V_POPCORN:
        q[0] = x->c[2][0], q[1] = x->c[2][1];
        break;
    case K_V_RINGS:
        q[0] = x->c[2][0] * x->c[2][0] + EPS;
        break;
    case K_V_FAN:
        q[0] = M_PI * (x->c[2][0] * x->c[2][0] + EPS), q[1] = x->c[2][1];
        break;
    case K_V_BLOB:
        q[0] = P[FB_FP_BLOB_LOW], q[1] = P[FB_FP_BLOB_HIGH] - P[FB_FP_BLOB_LOW], q[2] = P[FB_FP_BLOB_WAVES];
        break;
    case K_V_PDJ:
        q[0] = P[FB_FP_PDJ_A], q[1] = P[FB_FP_PDJ_B], q[2] = P[FB_FP_PDJ_C], q[3] = P[FB_FP_PDJ_D];
        break;
    case K_V_FAN2:
        q[0] = M_PI * (P[FB_FP_FAN2_X] * P[FB_FP_FAN2_X] + EPS), q[1] = P[FB_FP_FAN2_Y];
        break;
    case K_V_RINGS2:
        q[0] = P[FB_FP_RINGS2_VAL] * P[FB_FP_RINGS2_VAL] + EPS;
        break;
    case K_V_PERSPECTIVE: {
        double ang = P[FB_FP_PERSPECTIVE_ANGLE] * M_PI / 2.0;
        q[0] = P[FB_FP_PERSPECTIVE_DIST], q[1] = sin(ang), q[2] = P[FB_FP_PERSPECTIVE_DIST] * cos(ang);
        break;
    }
    case K_V_JULIAN:
    case K_V_JULIASCOPE: {
        double pw = v == K_V_JULIAN ? P[FB_FP_JULIAN_POWER] : P[FB_FP_JULIASCOPE_POWER];
        double ds = v == K_V_JULIAN ? P[FB_FP_JULIAN_DIST] : P[FB_FP_JULIASCOPE_DIST];
        q[0] = pw, q[1] = ds / pw / 2.0, q[2] = fabs(pw);
        break;
    }
    case K_V_RADIAL_BLUR:
        q[0] = sin(P[FB_FP_RADIAL_BLUR_ANGLE] * M_PI / 2.0), q[1] = cos(P[FB_FP_RADIAL_BLUR_ANGLE] * M_PI / 2.0);
        break;
    case K_V_PIE:
        q[0] = P[FB_FP_PIE_SLICES], q[1] = P[FB_FP_PIE_ROTATION], q[2] = P[FB_FP_PIE_THICKNESS];
        break;
    case K_V_NGON:
        q[0] = P[FB_FP_NGON_POWER] / 2.0, q[1] = 2 * M_PI / P[FB_FP_NGON_SIDES];
        q[2] = P[FB_FP_NGON_CORNERS], q[3] = P[FB_FP_NGON_CIRCLE];
        break;
    case K_V_CURL:
        q[0] = P[FB_FP_CURL_C1], q[1] = P[FB_FP_CURL_C2];
        break;
    case K_V_RECTANGLES:
        q[0] = P[FB_FP_RECTANGLES_X], q[1] = P[FB_FP_RECTANGLES_Y];
        break;
    case K_V_DISC2: {
        double add = P[FB_FP_DISC2_TWIST], sa = sin(add), ca = cos(add) - 1;
        if (add > 2 * M_PI) sa *= 1 + add - 2 * M_PI, ca *= 1 + add - 2 * M_PI;
        if (add < -2 * M_PI) sa *= 1 + add + 2 * M_PI, ca *= 1 + add + 2 * M_PI;
        q[0] = P[FB_FP_DISC2_ROT] * M_PI, q[1] = sa, q[2] = ca;
        break;
    }
    case K_V_SUPER_SHAPE:
        q[0] = P[FB_FP_SUPER_SHAPE_M] / 4.0, q[1] = P[FB_FP_SUPER_SHAPE_N2], q[2] = P[FB_FP_SUPER_SHAPE_N3];
        q[3] = P[FB_FP_SUPER_SHAPE_RND], q[4] = P[FB_FP_SUPER_SHAPE_HOLES], q[5] = -1.0 / P[FB_FP_SUPER_SHAPE_N1];
        break;
    case K_V_FLOWER:
        q[0] = P[FB_FP_FLOWER_PETALS], q[1] = P[FB_FP_FLOWER_HOLES];
        break;
    case K_V_CONIC:
        q[0] = P[FB_FP_CONIC_ECCENTRICITY], q[1] = P[FB_FP_CONIC_HOLES];
        break;
    case K_V_PARABOLA:
        q[0] = P[FB_FP_PARABOLA_HEIGHT], q[1] = P[FB_FP_PARABOLA_WIDTH];
        break;
    case K_V_BENT2:
        q[0] = P[FB_FP_BENT2_X], q[1] = P[FB_FP_BENT2_Y];
        break;
    default:
        break;
    }
}

/* ... and of variations 55 .. 98, combined as flam3's precalc functions and variations do in double
 * (the weight's own combinations included: scry's 1 / (w + EPS) ...). */
static void params_plugin(const fb_flame_xform *x, int v, double q[8])
{
    const double *P = x->par, w = x->var[v], EPS = 1e-10;
    switch (v) {
    case K_V_BIPOLAR:
        q[0] = -M_PI_2 * P[FB_FP_BIPOLAR_SHIFT];
        break;
    case K_V_CELL:
        q[0] = P[FB_FP_CELL_SIZE], q[1] = 1.0 / P[FB_FP_CELL_SIZE];
        break;
    case K_V_CPOW: {
        double pw = P[FB_FP_CPOW_POWER];
        q[0] = 2.0 * M_PI / pw, q[1] = P[FB_FP_CPOW_R] / pw, q[2] = P[FB_FP_CPOW_I] / pw, q[3] = pw;
        break;
    }
    case K_V_CURVE:
        q[0] = P[FB_FP_CURVE_XAMP], q[1] = P[FB_FP_CURVE_YAMP];
        q[2] = 1.0 / fmax(P[FB_FP_CURVE_XLENGTH] * P[FB_FP_CURVE_XLENGTH], 1e-20);
        q[3] = 1.0 / fmax(P[FB_FP_CURVE_YLENGTH] * P[FB_FP_CURVE_YLENGTH], 1e-20);
        break;
    case K_V_EDISC:
        q[0] = w / 11.57034632;
        break;
    case K_V_ELLIPTIC:
        q[0] = w / M_PI_2;
        break;
    case K_V_ESCHER:
        q[0] = 0.5 * (1.0 + cos(P[FB_FP_ESCHER_BETA])), q[1] = 0.5 * sin(P[FB_FP_ESCHER_BETA]);
        break;
    case K_V_LAZYSUSAN:
        q[0] = P[FB_FP_LAZYSUSAN_X], q[1] = P[FB_FP_LAZYSUSAN_Y], q[2] = P[FB_FP_LAZYSUSAN_SPIN];
        q[3] = P[FB_FP_LAZYSUSAN_SPACE], q[4] = P[FB_FP_LAZYSUSAN_TWIST];
        break;
    case K_V_MODULUS:
        q[0] = P[FB_FP_MODULUS_X], q[1] = P[FB_FP_MODULUS_Y];
        break;
    case K_V_OSCILLOSCOPE:
        q[0] = 2 * M_PI * P[FB_FP_OSCOPE_FREQUENCY], q[1] = P[FB_FP_OSCOPE_AMPLITUDE];
        q[2] = P[FB_FP_OSCOPE_DAMPING], q[3] = P[FB_FP_OSCOPE_SEPARATION];
        break;
    case K_V_POLAR2:
        q[0] = w / M_PI;
        break;
    case K_V_POPCORN2:
        q[0] = P[FB_FP_POPCORN2_X], q[1] = P[FB_FP_POPCORN2_Y], q[2] = P[FB_FP_POPCORN2_C];
        break;
    case K_V_SCRY:
        q[0] = 1.0 / (w + EPS);
        break;
    case K_V_SEPARATION:
        q[0] = P[FB_FP_SEPARATION_X] * P[FB_FP_SEPARATION_X], q[1] = P[FB_FP_SEPARATION_XINSIDE];
        q[2] = P[FB_FP_SEPARATION_Y] * P[FB_FP_SEPARATION_Y], q[3] = P[FB_FP_SEPARATION_YINSIDE];
        break;
    case K_V_SPLIT:
        q[0] = P[FB_FP_SPLIT_XSIZE], q[1] = P[FB_FP_SPLIT_YSIZE];
        break;
    case K_V_SPLITS:
        q[0] = P[FB_FP_SPLITS_X], q[1] = P[FB_FP_SPLITS_Y];
        break;
    case K_V_STRIPES:
        q[0] = 1.0 - P[FB_FP_STRIPES_SPACE], q[1] = P[FB_FP_STRIPES_WARP];
        break;
    case K_V_WEDGE:
    case K_V_WEDGE_SPH: {
        int o = v == K_V_WEDGE ? 0 : FB_FP_WEDGE_SPH_ANGLE - FB_FP_WEDGE_ANGLE;
        q[0] = P[FB_FP_WEDGE_ANGLE + o], q[1] = P[FB_FP_WEDGE_HOLE + o], q[2] = P[FB_FP_WEDGE_COUNT + o];
        q[3] = P[FB_FP_WEDGE_SWIRL + o], q[4] = 1 - q[0] * q[2] * M_1_PI * 0.5;
        break;
    }
    case K_V_WEDGE_JULIA: {
        double pw = P[FB_FP_WEDGE_JULIA_POWER], cnt = P[FB_FP_WEDGE_JULIA_COUNT], ang = P[FB_FP_WEDGE_JULIA_ANGLE];
        q[0] = pw, q[1] = P[FB_FP_WEDGE_JULIA_DIST] / pw / 2.0, q[2] = fabs(pw);
        q[3] = cnt, q[4] = ang, q[5] = 1.0 - ang * cnt * M_1_PI * 0.5;
        break;
    }
    case K_V_WHORL:
        q[0] = P[FB_FP_WHORL_INSIDE], q[1] = P[FB_FP_WHORL_OUTSIDE];
        break;
    case K_V_WAVES2:
        q[0] = P[FB_FP_WAVES2_SCALEX], q[1] = P[FB_FP_WAVES2_SCALEY];
        q[2] = P[FB_FP_WAVES2_FREQX], q[3] = P[FB_FP_WAVES2_FREQY];
        break;
    case K_V_AUGER:
        q[0] = P[FB_FP_AUGER_FREQ], q[1] = P[FB_FP_AUGER_WEIGHT], q[2] = P[FB_FP_AUGER_SYM];
        q[3] = P[FB_FP_AUGER_SCALE];
        break;
    case K_V_FLUX:
        q[0] = 2 + P[FB_FP_FLUX_SPREAD];
        break;
    case K_V_MOBIUS:
        for (int k = 0; k < 8; k++) q[k] = P[FB_FP_MOBIUS_RE_A + k];
        break;
    default:
        break;
    }
}

K_FlameVar fb_flame_var_params(const fb_flame_xform *x, int v)
{
    double q[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    if (v < (int)K_V_BIPOLAR)
        params_classic(x, v, q);
    else
        params_plugin(x, v, q);
    return (K_FlameVar){(uint32_t)v, (float)x->var[v], (float)q[0], (float)q[1], (float)q[2], (float)q[3],
                        (float)q[4], (float)q[5],      (float)q[6], (float)q[7], 0,           0};
}

/* What each variation reads of flam3's precalcs (prepare_precalc_flags, and precalc_sqrt where the
 * variation reads it). */
static uint32_t var_flags(int v)
{
    enum { XY = K_FLAME_ATAN_XY, YX = K_FLAME_ATAN_YX, SQ = K_FLAME_SQRT, AN = K_FLAME_ANGLES | K_FLAME_SQRT };
    static const uint8_t flags[K_V_COUNT] = {
        [K_V_HORSESHOE] = SQ,      [K_V_POLAR] = XY | SQ, [K_V_HANDKERCHIEF] = XY | SQ,
        [K_V_HEART] = XY | SQ,     [K_V_DISC] = XY | SQ,  [K_V_SPIRAL] = AN,
        [K_V_HYPERBOLIC] = AN,     [K_V_DIAMOND] = AN,    [K_V_EX] = XY | SQ,
        [K_V_JULIA] = XY | SQ,     [K_V_FISHEYE] = SQ,    [K_V_POWER] = AN,
        [K_V_RINGS] = AN,          [K_V_FAN] = XY | SQ,   [K_V_BLOB] = XY | AN,
        [K_V_FAN2] = XY | SQ,      [K_V_RINGS2] = AN,     [K_V_EYEFISH] = SQ,
        [K_V_JULIAN] = YX,         [K_V_JULIASCOPE] = YX, [K_V_RADIAL_BLUR] = YX | SQ,
        [K_V_NGON] = YX,           [K_V_BLADE] = SQ,      [K_V_SECANT2] = SQ,
        [K_V_TWINTRIAN] = SQ,      [K_V_DISC2] = XY,      [K_V_SUPER_SHAPE] = YX | SQ,
        [K_V_FLOWER] = YX | SQ,    [K_V_CONIC] = YX | SQ, [K_V_PARABOLA] = SQ,
        [K_V_CPOW] = YX,           [K_V_ESCHER] = YX,     [K_V_POLAR2] = XY,
        [K_V_SCRY] = SQ,           [K_V_WEDGE] = YX | SQ, [K_V_WEDGE_JULIA] = YX,
        [K_V_WEDGE_SPH] = YX | SQ, [K_V_WHORL] = YX | SQ, [K_V_LOG] = YX,
    };
    return flags[v];
}

static void xform_table(fb_flame_setup *s, const fb_flame_xform *x, K_FlameXform *out)
{
    double vis = x->opacity == 0.0 ? 0.0 : pow(10.0, -log(1.0 / x->opacity) / log(2)); /* flam3's adjust_percentage */
    bool post = !(x->post[0][0] == 1 && x->post[0][1] == 0 && x->post[1][0] == 0 && x->post[1][1] == 1 &&
                  x->post[2][0] == 0 && x->post[2][1] == 0);
    *out = (K_FlameXform){.ax = (float)x->c[0][0],
                          .bx = (float)x->c[1][0],
                          .cx = (float)x->c[2][0],
                          .ay = (float)x->c[0][1],
                          .by = (float)x->c[1][1],
                          .cy = (float)x->c[2][1],
                          .pax = (float)x->post[0][0],
                          .pbx = (float)x->post[1][0],
                          .pcx = (float)x->post[2][0],
                          .pay = (float)x->post[0][1],
                          .pby = (float)x->post[1][1],
                          .pcy = (float)x->post[2][1],
                          .color = (float)x->color,
                          .speed = (float)x->color_speed,
                          .vis = (float)vis,
                          .var0 = s->nvar,
                          .flags = post ? K_FLAME_HAS_POST : 0u,
                          .visq = (uint32_t)llround(fmin(fmax(vis, 0), 1) * 32768.0),
                          .preblur = (float)x->var[K_V_PRE_BLUR]};
    for (int v = 0; v < (int)K_V_COUNT; v++) {
        if (x->var[v] == 0.0 || v == (int)K_V_PRE_BLUR) continue;
        s->var[s->nvar++] = fb_flame_var_params(x, v);
        out->nvar++;
        out->flags |= var_flags(v);
    }
}

/* flam3_create_chaos_distrib: row `from` (-1: the plain weights) of the xform choice table. */
static void choice_row(const fb_flame_genome *g, int from, uint32_t *row)
{
    double dr = 0;
    for (int i = 0; i < g->nxforms; i++) dr += g->xf[i].weight * (from >= 0 ? g->xf[from].chaos[i] : 1.0);
    dr /= K_FLAME_GRAIN;
    int j = 0;
    double t = g->xf[0].weight * (from >= 0 ? g->xf[from].chaos[0] : 1.0), r = 0;
    for (uint32_t i = 0; i < K_FLAME_GRAIN; i++) {
        while (r >= t && j < g->nxforms - 1) {
            j++;
            t += g->xf[j].weight * (from >= 0 ? g->xf[from].chaos[j] : 1.0);
        }
        row[i] = (uint32_t)j;
        r += dr;
    }
}

/* The chaos game's part of s for genome g, on the frame s already holds (size, supersample, gutter,
 * histogram): the camera, the points (share of density x pixels), the xform and choice tables and
 * the palette (times scalar: a temporal sample's weight), k1, k2 and the tone map. */
static fb_result setup_game(const fb_flame_genome *g, double quality, uint32_t seed, double share, double scalar,
                            fb_flame_setup *s)
{
    K_FlameParams *p = &s->p;
    int width = s->width, height = s->height, ss = s->ss, gutter = s->gutter;
    double zoom = pow(2.0, g->zoom), q = quality > 0 ? quality : g->quality;
    double density = q * zoom * zoom;
    double ppux = g->scale * zoom * ((double)width / g->width), ppuy = ppux;
    double t0 = gutter / (ss * ppux), t1 = gutter / (ss * ppuy);
    double corner0 = g->center[0] - width / ppux / 2.0, corner1 = g->center[1] - height / ppuy / 2.0;
    double b[4] = {corner0 - t0, corner1 - t1, corner0 + width / ppux + t0, corner1 + height / ppuy + t1};
    double ws0 = p->hist_w / (b[2] - b[0]), hs1 = p->hist_h / (b[3] - b[1]);
    p->b0 = (float)b[0], p->b1 = (float)b[1], p->b2 = (float)b[2], p->b3 = (float)b[3];
    p->ws0 = (float)ws0, p->wb0s0 = (float)(ws0 * b[0]), p->hs1 = (float)hs1, p->hb1s1 = (float)(hs1 * b[1]);
    double th = g->rotate * 2 * M_PI / 360.0;
    p->rotate = g->rotate != 0.0;
    p->rot00 = (float)cos(th), p->rot01 = (float)-sin(th), p->rot10 = (float)sin(th), p->rot11 = (float)cos(th);
    p->rcx = (float)g->center[0], p->rcy = (float)g->center[1];
    s->samples = density * width * height * share;
    double area = width * height / (ppux * ppuy);
    s->k1 = (1.0 * 1.0 * PREFILTER_WHITE * 268.0 * 1.0) / 256; /* brightness 1: the tone map scales by it */
    s->k2 = (ss * ss * 1.0) / (1.0 * area * PREFILTER_WHITE * density * 1.0);

    p->seed = seed;
    p->nxf = (uint32_t)g->nxforms;
    p->chaos = g->chaos;
    p->fuse = 15;   /* flam3's FUSE_27 */
    p->len = 10000; /* flam3's sub-batch */
    double chains = ceil(s->samples / p->len);
    if (chains > 4e9) return fb_fail(FB_ERR_INPUT, "%.3g points are more than this renderer counts", s->samples);
    p->chains = (uint32_t)(chains < 1 ? 1 : chains);
    double last = s->samples - (double)(p->chains - 1) * p->len;
    p->last_len = (uint32_t)(last < 1 ? 1 : last > p->len ? p->len : last);
    for (int i = 0; i < g->nxforms; i++) xform_table(s, &g->xf[i], &s->xf[i]);
    p->final_xf = K_FLAME_NONE;
    if (g->has_final) {
        xform_table(s, &g->xf[g->nxforms], &s->xf[g->nxforms]);
        p->final_xf = (uint32_t)g->nxforms;
        p->final_always = g->xf[g->nxforms].opacity == 1.0;
        p->final_opacity = (float)g->xf[g->nxforms].opacity;
    }
    s->ndist = (uint32_t)(g->chaos ? g->nxforms + 1 : 1) * K_FLAME_GRAIN;
    s->dist = malloc(s->ndist * sizeof *s->dist);
    if (!s->dist) return fb_fail(FB_ERR_NOMEM, "out of memory");
    choice_row(g, -1, s->dist);
    for (int i = 0; g->chaos && i < g->nxforms; i++) choice_row(g, i, s->dist + (size_t)(i + 1) * K_FLAME_GRAIN);
    s->linear_palette = g->palette_mode == FB_FLAME_PALETTE_LINEAR;
    for (int i = 0; i < 256; i++)
        for (int k = 0; k < 4; k++) {
            double v = g->palette[i][k] * 255.0;
            s->palq[i][k] = (uint32_t)llround(fmin(fmax(v, 0), 255.0) * 16.0 * scalar);
        }
    s->tone =
        (fb_flame_tone){g->brightness, g->gamma,           g->gamma_threshold,
                        g->vibrancy,   g->highlight_power, {g->background[0], g->background[1], g->background[2]}};
    return FB_OK;
}

fb_result fb_flame_setup_init(const fb_flame_genome *g, int width, int height, double quality, uint32_t seed,
                              fb_flame_setup *s)
{
    memset(s, 0, sizeof *s);
    K_FlameParams *p = &s->p;
    s->width = width, s->height = height, s->ss = g->supersample;
    int ss = g->supersample;
    fb_result rc = spatial_filter(g->filter_shape, ss, g->filter, &s->filter, &s->fwidth);
    if (rc) return rc;
    int gutter = (s->fwidth - ss) / 2, de_fw = (int)ceil(g->estimator) * ss;
    if (de_fw > 0) de_fw += ss - 1;
    s->de_offset = de_fw > gutter ? de_fw - gutter : 0;
    if (de_fw > gutter) gutter = de_fw;
    s->gutter = gutter;
    p->hist_w = (uint32_t)(ss * width + 2 * gutter);
    p->hist_h = (uint32_t)(ss * height + 2 * gutter);
    if ((uint64_t)p->hist_w * p->hist_h > (1ull << 30))
        return fb_fail(FB_ERR_INPUT, "the flame's histogram would have %llu cells (size x supersample^2); at most 2^30",
                       (unsigned long long)p->hist_w * p->hist_h);
    if (g->estimator > 0) {
        s->estimator_curve = g->estimator_curve;
        if ((rc = de_filters(g->estimator, g->estimator_minimum, g->estimator_curve, ss, s))) return rc;
    }
    return setup_game(g, quality, seed, 1.0, 1.0, s);
}

fb_result fb_flame_setup_sample(const fb_flame_genome *g, const fb_flame_setup *frame, double quality, uint32_t seed,
                                double share, double scalar, fb_flame_setup *s)
{
    memset(s, 0, sizeof *s);
    s->width = frame->width, s->height = frame->height, s->ss = frame->ss;
    s->gutter = frame->gutter, s->de_offset = frame->de_offset;
    s->p.hist_w = frame->p.hist_w, s->p.hist_h = frame->p.hist_h;
    return setup_game(g, quality, seed, share, scalar, s);
}

void fb_flame_setup_fini(fb_flame_setup *s)
{
    if (!s) return;
    free(s->dist);
    free(s->filter);
    free(s->de_coefs);
    free(s->de_widths);
    memset(s, 0, sizeof *s);
}

void fb_flame_spill(fb_flame_cell *total, fb_flame_cell32 *h)
{
    for (int k = 0; k < 5; k++)
        atomic_fetch_add_explicit((_Atomic uint64_t *)&total->c[k], h->c[k], memory_order_relaxed);
    atomic_fetch_add_explicit((_Atomic uint64_t *)&total->hits, h->hits, memory_order_relaxed);
    memset(h, 0, sizeof *h);
}

typedef struct zero_job {
    uint8_t *p;
    size_t n;
} zero_job;

#define ZERO_CHUNK ((size_t)2 << 20)

static void zero_task(void *ctx, int t)
{
    const zero_job *J = ctx;
    size_t a = (size_t)t * ZERO_CHUNK, b = a + ZERO_CHUNK < J->n ? a + ZERO_CHUNK : J->n;
    memset(J->p + a, 0, b - a);
}

void *fb_flame_zalloc(size_t n, fb_pool *pool)
{
    uint8_t *p = fb_malloc_large(n);
    if (!p) return NULL;
    zero_job J = {p, n};
    size_t chunks = (n + ZERO_CHUNK - 1) / ZERO_CHUNK;
    if (pool && chunks > 1 && chunks < (size_t)1 << 30)
        fb_pool_run(pool, (int)chunks, zero_task, &J);
    else
        memset(p, 0, n);
    return p;
}

void fb_flame_hist_fold(fb_flame_cell *a, const fb_flame_cell32 *b, size_t c0, size_t c1)
{
    for (size_t i = c0; i < c1; i++) {
        for (int k = 0; k < 5; k++) a[i].c[k] += b[i].c[k];
        a[i].hits += b[i].hits;
    }
}

/* ---- density estimation and the spatial filter ------------------------------------------------ */

/* Density estimation and the filter compiled for AVX2 too, chosen when the program loads
 * (host/compare/clones.h's way: no contraction, no reassociation, so the same operations on each
 * value in the same order, the same bits): a cell's four doubles in one 256-bit add. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FILTER_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FILTER_CLONES
#endif

static inline void add_at(double (*acc)[4], int x, int y, int w, int y0, int y1, const double *c)
{
    if (x < 0 || y < y0 || x >= w || y >= y1) return;
    double *a = acc[(size_t)y * w + x];
    a[0] += c[0], a[1] += c[1], a[2] += c[2], a[3] += c[3];
}

/* Density estimation and the filter on the pool: the accumulation's rows in bands, each band
 * visiting every source cell whose kernel can reach it, in the one order of the whole image's
 * pass (rows, then columns, then the kernel's taps), adding only into its own rows. So every
 * accumulation cell receives the same terms in the same order for any banding, and the doubles
 * are the same bits as one thread's. */
typedef struct filter_job {
    const fb_flame_setup *S;
    const fb_flame_cell *hist;
    double (*acc)[4];
    float *const *out;
    uint32_t *count;
    int W, H, reach, nbands, nrows;
} filter_job;

/* Band `task` of the accumulation's rows: density estimation (or the plain log scale without it). */
FILTER_CLONES static void de_band(void *ctx, int task)
{
    const filter_job *J = ctx;
    const fb_flame_setup *S = J->S;
    const fb_flame_cell *hist = J->hist;
    double(*acc)[4] = J->acc;
    int W = J->W, H = J->H, os = S->ss;
    int y0 = (int)((int64_t)H * task / J->nbands), y1 = (int)((int64_t)H * (task + 1) / J->nbands);
    const double k1 = S->k1, k2 = S->k2, q = 1.0 / 16.0;
    if (S->de_max_index == 0) {
        for (size_t i = (size_t)y0 * W; i < (size_t)y1 * W; i++) {
            double c3 = hist[i].c[3] * q;
            if (c3 == 0.0) continue;
            double ls = k1 * log(1.0 + c3 * k2) / c3;
            for (int k = 0; k < 4; k++) acc[i][k] = hist[i].c[k] * q * ls;
        }
        return;
    }
    int half = os / 2, scf = !(os & 1);
    double scfact = pow(os / (os + 1.0), 2.0), curve = S->estimator_curve;
    int j0 = y0 - J->reach, j1 = y1 + J->reach;
    if (j0 < os - 1) j0 = os - 1;
    if (j1 > H - (os - 1)) j1 = H - (os - 1);
    for (int j = j0; j < j1; j++)
        for (int i = os - 1; i < W - (os - 1); i++) {
            const fb_flame_cell *b = &hist[(size_t)j * W + i];
            if (b->c[4] == 0 || b->c[3] == 0) continue;
            double fs = 0;
            for (int ii = -half; ii <= half; ii++)
                for (int jj = -half; jj <= half; jj++) {
                    int x = i + ii, y = j + jj;
                    if (x >= 0 && y >= 0 && x < W && y < H) fs += hist[(size_t)y * W + x].c[4] * q / 255.0;
                }
            if (scf) fs *= scfact;
            int fi;
            if (fs > S->de_max_counts)
                fi = S->de_max_index;
            else if (fs <= DE_THRESH)
                fi = (int)ceil(fs) - 1;
            else
                fi = DE_THRESH + (int)floor(pow(fs - DE_THRESH, curve));
            if (fi > S->de_max_index) fi = S->de_max_index;
            if (fi < 0) fi = 0;
            int at = fi * S->de_kernel_size, fw = (int)ceil(S->de_widths[fi]) - 1;
            if (j + fw < y0 || j - fw >= y1) continue; /* its kernel reaches none of the band's rows */
            double c[4], cb[4] = {b->c[0] * q, b->c[1] * q, b->c[2] * q, b->c[3] * q};
            double ls0 = k1 * log(1.0 + cb[3] * k2) / cb[3];
            for (int jj = 0; jj <= fw; jj++)
                for (int ii = 0; ii <= jj; ii++, at++) {
                    double f = S->de_coefs[at];
                    if (f == 0.0) continue;
                    double ls = f * ls0;
                    for (int k = 0; k < 4; k++) c[k] = cb[k] * ls;
                    if (jj == 0 && ii == 0) {
                        add_at(acc, i, j, W, y0, y1, c);
                    } else if (ii == 0) {
                        add_at(acc, i + jj, j, W, y0, y1, c);
                        add_at(acc, i - jj, j, W, y0, y1, c);
                        add_at(acc, i, j + jj, W, y0, y1, c);
                        add_at(acc, i, j - jj, W, y0, y1, c);
                    } else if (jj == ii) {
                        add_at(acc, i + ii, j + jj, W, y0, y1, c);
                        add_at(acc, i - ii, j + jj, W, y0, y1, c);
                        add_at(acc, i + ii, j - jj, W, y0, y1, c);
                        add_at(acc, i - ii, j - jj, W, y0, y1, c);
                    } else {
                        add_at(acc, i + ii, j + jj, W, y0, y1, c);
                        add_at(acc, i - ii, j + jj, W, y0, y1, c);
                        add_at(acc, i + ii, j - jj, W, y0, y1, c);
                        add_at(acc, i - ii, j - jj, W, y0, y1, c);
                        add_at(acc, i + jj, j + ii, W, y0, y1, c);
                        add_at(acc, i - jj, j + ii, W, y0, y1, c);
                        add_at(acc, i + jj, j - ii, W, y0, y1, c);
                        add_at(acc, i - jj, j - ii, W, y0, y1, c);
                    }
                }
        }
}

/* Band `task` of the image's rows: the spatial filter, one output pixel per os x os block (flam3
 * keeps de_offset cells of gutter), and the pixel's hits. */
FILTER_CLONES static void filter_band(void *ctx, int task)
{
    const filter_job *J = ctx;
    const fb_flame_setup *S = J->S;
    int W = J->W, os = S->ss, fw = S->fwidth;
    int r0 = (int)((int64_t)S->height * task / J->nrows), r1 = (int)((int64_t)S->height * (task + 1) / J->nrows);
    for (int j = r0; j < r1; j++)
        for (int i = 0; i < S->width; i++) {
            int x = S->de_offset + i * os, y = S->de_offset + j * os;
            double t[4] = {0, 0, 0, 0};
            for (int jj = 0; jj < fw; jj++)
                for (int ii = 0; ii < fw; ii++) {
                    double k = S->filter[ii + jj * fw];
                    const double *a = J->acc[(size_t)(y + jj) * W + x + ii];
                    t[0] += k * a[0], t[1] += k * a[1], t[2] += k * a[2], t[3] += k * a[3];
                }
            size_t o = (size_t)j * S->width + i;
            for (int k = 0; k < 4; k++) J->out[k][o] = (float)t[k];
            /* the hits of the pixel's own os x os cells (inside the gutter) */
            uint64_t n = 0;
            for (int jj = 0; jj < os; jj++)
                for (int ii = 0; ii < os; ii++)
                    n += J->hist[(size_t)(S->gutter + j * os + jj) * W + S->gutter + i * os + ii].hits;
            J->count[o] = n > 0xffffffffu ? 0xffffffffu : (uint32_t)n;
        }
}

fb_result fb_flame_filter(const fb_flame_setup *S, const fb_flame_cell *hist, float *const acc_out[4], uint32_t *count,
                          fb_pool *pool)
{
    int W = (int)S->p.hist_w, H = (int)S->p.hist_h;
    double(*acc)[4] = fb_flame_zalloc((size_t)W * H * sizeof *acc, pool);
    if (!acc) return fb_fail(FB_ERR_NOMEM, "out of memory for the flame's density estimation");
    int threads = pool ? fb_pool_threads(pool) : 1, reach = 0;
    for (int fi = 0; S->de_max_index > 0 && fi <= S->de_max_index; fi++) {
        int fw = (int)ceil(S->de_widths[fi]) - 1;
        if (fw > reach) reach = fw;
    }
    /* a few bands a thread (the cost of a row varies with its density), each at least 4 reaches tall
     * so that the kernels its halo rows spill in are a small part of its work */
    int nbands = threads < 2 ? 1 : 4 * threads, min_rows = 4 * (reach + 1);
    while (nbands > 1 && H / nbands < min_rows) nbands--;
    int nrows = threads < 2 ? 1 : 4 * threads;
    if (nrows > S->height) nrows = S->height > 0 ? S->height : 1;
    filter_job J = {S, hist, acc, acc_out, count, W, H, reach, nbands, nrows};
    if (pool && nbands > 1)
        fb_pool_run(pool, nbands, de_band, &J);
    else
        for (int t = 0; t < nbands; t++) de_band(&J, t);
    if (pool && nrows > 1)
        fb_pool_run(pool, nrows, filter_band, &J);
    else
        for (int t = 0; t < nrows; t++) filter_band(&J, t);
    free(acc);
    return FB_OK;
}

/* ---- the tone map (flam3's calc_alpha and calc_newrgb) ------------------------------------------- */

void fb_flame_rgb2hsv(const double *rgb, double *hsv);
void fb_flame_hsv2rgb(const double *hsv, double *rgb);

static double calc_alpha(double density, double gamma, double linrange)
{
    if (!(density > 0)) return 0;
    if (density < linrange) {
        double frac = density / linrange;
        return (1.0 - frac) * density * (pow(linrange, gamma) / linrange) + frac * pow(density, gamma);
    }
    return pow(density, gamma);
}

static void calc_newrgb(const double *c, double ls, double highpow, double *out)
{
    if (ls == 0.0 || (c[0] == 0.0 && c[1] == 0.0 && c[2] == 0.0)) {
        out[0] = out[1] = out[2] = 0;
        return;
    }
    double maxa = -1.0, maxc = 0;
    for (int k = 0; k < 3; k++) {
        double a = ls * (c[k] / PREFILTER_WHITE);
        if (a > maxa) maxa = a, maxc = c[k] / PREFILTER_WHITE;
    }
    if (maxa > 255 && highpow >= 0.0) {
        double newls = 255.0 / maxc, ratio = pow(newls / ls, highpow), hsv[3];
        for (int k = 0; k < 3; k++) out[k] = newls * (c[k] / PREFILTER_WHITE) / 255.0;
        fb_flame_rgb2hsv(out, hsv);
        hsv[1] *= ratio;
        fb_flame_hsv2rgb(hsv, out);
        for (int k = 0; k < 3; k++) out[k] *= 255.0;
    } else {
        double newls = 255.0 / maxc, adj = -highpow;
        if (adj > 1) adj = 1;
        if (maxa <= 255) adj = 1.0;
        for (int k = 0; k < 3; k++) out[k] = ((1.0 - adj) * newls + adj * ls) * (c[k] / PREFILTER_WHITE);
    }
}

static float srgb_decode(double v)
{
    return (float)(v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4));
}

void fb_flame_tone_row(const fb_flame_tone *t, size_t n, const float *const acc[4], float *R, float *G, float *B,
                       float *A)
{
    double g = 1.0 / t->gamma, bg[3];
    for (int k = 0; k < 3; k++) bg[k] = t->background[k] * 256.0;
    for (size_t i = 0; i < n; i++) {
        double c[4];
        for (int k = 0; k < 4; k++) c[k] = acc[k][i] * t->brightness;
        double alpha = 0, ls = 0, tmp = c[3] / PREFILTER_WHITE, rgb[3], out[3];
        if (c[3] > 0) {
            alpha = calc_alpha(tmp, g, t->gamma_threshold);
            ls = t->vibrancy * 256.0 * alpha / tmp;
            alpha = alpha < 0 ? 0 : alpha > 1 ? 1 : alpha;
        }
        calc_newrgb(c, ls, t->highlight_power, rgb);
        for (int k = 0; k < 3; k++) {
            double a = rgb[k];
            if (t->vibrancy != 1.0) a += (1.0 - t->vibrancy) * 256.0 * pow(c[k] / PREFILTER_WHITE, g);
            a += (1.0 - alpha) * bg[k];
            a = a > 255 ? 255 : a < 0 ? 0 : a;
            out[k] = a / 255.0;
        }
        R[i] = srgb_decode(out[0]), G[i] = srgb_decode(out[1]), B[i] = srgb_decode(out[2]);
        A[i] = (float)alpha;
    }
}
