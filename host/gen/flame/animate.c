/*
 * Interpolation of flame keyframes, after flam3 3.1.1's flam3_interpolate, flam3_align and
 * flam3_interpolate_n (interpolation.c, flam3.c) and its temporal filter (filters.c); the rules
 * are flam3's, the code is this project's.
 */
#include "animate.h"

#include "kernels/flame_var.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

typedef fb_flame_genome genome;

#define EPS 1e-10 /* flam3's tolerance at a half turn */

void fb_flame_rgb2hsv(const double *rgb, double *hsv);
void fb_flame_hsv2rgb(const double *hsv, double *rgb);

/* ---- which variation each parameter belongs to (flam3_copy_params) ----------------------------- */

static const char *const param_names[FB_FP_COUNT] = {
#define FB_FLAME_PARAM_NAME(e, name, def) name,
    FB_FLAME_PARAMS(FB_FLAME_PARAM_NAME)
#undef FB_FLAME_PARAM_NAME
};
static int param_owner[FB_FP_COUNT];
static pthread_once_t owner_once = PTHREAD_ONCE_INIT;

/* The variation whose name, then '_', begins the parameter's name (the longest: wedge_sph_angle
 * belongs to wedge_sph, not wedge). */
static void find_owners(void)
{
    for (int p = 0; p < FB_FP_COUNT; p++) {
        size_t best = 0;
        param_owner[p] = -1;
        for (int v = 0; v < (int)K_V_COUNT; v++) {
            const char *vn = fb_flame_variation_name(v);
            size_t l = strlen(vn);
            if (l > best && !strncmp(param_names[p], vn, l) && param_names[p][l] == '_') best = l, param_owner[p] = v;
        }
    }
}

static void copy_params(fb_flame_xform *dst, const fb_flame_xform *src, int v)
{
    for (int p = 0; p < FB_FP_COUNT; p++)
        if (param_owner[p] == v) dst->par[p] = src->par[p];
}

/* ---- flam3_align ------------------------------------------------------------------------------ */

static void pad_xform(fb_flame_xform *x, int index)
{
    fb_flame_xform_init(x, index);
    x->var[K_V_LINEAR] = 1.0;
    x->padding = true;
}

/* flam3_copyx: src with nx ordinary xforms (the missing ones padding) and a final xform where fx
 * (a padding one, still and keeping the colour, where src has none). */
static void copyx(genome *dst, const genome *src, int nx, bool fx)
{
    *dst = *src;
    for (int i = 0; i < src->nxforms; i++) {
        dst->xf[i].padding = false;
        for (int j = src->nxforms; j < FB_FLAME_MAX_XFORMS; j++) dst->xf[i].chaos[j] = 1.0;
    }
    for (int i = src->nxforms; i < nx; i++) pad_xform(&dst->xf[i], i);
    dst->nxforms = nx;
    dst->has_final = fx;
    if (fx && src->has_final) {
        dst->xf[nx] = src->xf[src->nxforms];
        dst->xf[nx].padding = false;
    } else if (fx) {
        pad_xform(&dst->xf[nx], nx);
        dst->xf[nx].animate = 0.0, dst->xf[nx].color_speed = 0.0;
    }
}

static bool neighbour(const genome *dst, int nsrc, int i, int ii, int xf)
{
    return i + ii >= 0 && i + ii < nsrc && !dst[i + ii].xf[xf].padding;
}

/* A padding xform's better identity, from the variations its neighbours' xform uses (flam3_align):
 * a half turn with linear -1 against spherical-like ones (log interpolation only), a zero-parameter
 * form of the parametric ones, or a swap of x and y against fan and rings; else linear. */
static void better_identity(genome *dst, int nsrc, int i, int xf)
{
    fb_flame_xform *x = &dst[i].xf[xf];
    x->var[K_V_LINEAR] = 0.0;
    int fnd = 0;
    static const unsigned holes[] = {K_V_SPHERICAL, K_V_NGON,      K_V_JULIAN,     K_V_JULIASCOPE,
                                     K_V_POLAR,     K_V_WEDGE_SPH, K_V_WEDGE_JULIA};
    if ((i == 0 && dst[i].interpolation_type == FB_FLAME_ITYPE_LOG) ||
        (i > 0 && dst[i - 1].interpolation_type == FB_FLAME_ITYPE_LOG))
        for (int ii = -1; ii <= 1; ii += 2) {
            if (!neighbour(dst, nsrc, i, ii, xf)) continue;
            const fb_flame_xform *o = &dst[i + ii].xf[xf];
            bool any = false;
            for (size_t k = 0; k < sizeof holes / sizeof holes[0]; k++) any |= o->var[holes[k]] > 0;
            if (any) {
                x->var[K_V_LINEAR] = -1.0;
                memset(x->c, 0, sizeof x->c);
                x->c[0][0] = x->c[1][1] = -1.0;
                fnd = -1;
            }
        }
    if (fnd == 0)
        for (int ii = -1; ii <= 1; ii += 2) {
            if (!neighbour(dst, nsrc, i, ii, xf)) continue;
            const fb_flame_xform *o = &dst[i + ii].xf[xf];
            if (o->var[K_V_RECTANGLES] > 0)
                x->var[K_V_RECTANGLES] = 1, x->par[FB_FP_RECTANGLES_X] = x->par[FB_FP_RECTANGLES_Y] = 0, fnd++;
            if (o->var[K_V_RINGS2] > 0) x->var[K_V_RINGS2] = 1, x->par[FB_FP_RINGS2_VAL] = 0, fnd++;
            if (o->var[K_V_FAN2] > 0) x->var[K_V_FAN2] = 1, x->par[FB_FP_FAN2_X] = x->par[FB_FP_FAN2_Y] = 0, fnd++;
            if (o->var[K_V_BLOB] > 0) {
                x->var[K_V_BLOB] = 1, fnd++;
                x->par[FB_FP_BLOB_LOW] = x->par[FB_FP_BLOB_HIGH] = x->par[FB_FP_BLOB_WAVES] = 1;
            }
            if (o->var[K_V_PERSPECTIVE] > 0) x->var[K_V_PERSPECTIVE] = 1, x->par[FB_FP_PERSPECTIVE_ANGLE] = 0, fnd++;
            if (o->var[K_V_CURL] > 0) x->var[K_V_CURL] = 1, x->par[FB_FP_CURL_C1] = x->par[FB_FP_CURL_C2] = 0, fnd++;
            if (o->var[K_V_SUPER_SHAPE] > 0) {
                x->var[K_V_SUPER_SHAPE] = 1, fnd++;
                x->par[FB_FP_SUPER_SHAPE_N1] = x->par[FB_FP_SUPER_SHAPE_N2] = x->par[FB_FP_SUPER_SHAPE_N3] = 2;
                x->par[FB_FP_SUPER_SHAPE_RND] = x->par[FB_FP_SUPER_SHAPE_HOLES] = 0;
            }
        }
    if (fnd == 0) {
        for (int ii = -1; ii <= 1; ii += 2) {
            if (!neighbour(dst, nsrc, i, ii, xf)) continue;
            const fb_flame_xform *o = &dst[i + ii].xf[xf];
            if (o->var[K_V_FAN] > 0) x->var[K_V_FAN] = 1, fnd++;
            if (o->var[K_V_RINGS] > 0) x->var[K_V_RINGS] = 1, fnd++;
        }
        if (fnd > 0) {
            memset(x->c, 0, sizeof x->c);
            x->c[0][1] = x->c[1][0] = 1.0;
        }
    }
    if (fnd == 0) {
        x->var[K_V_LINEAR] = 1.0;
    } else if (fnd > 0) {
        double normed = 0;
        for (int v = 0; v < (int)K_V_COUNT; v++) normed += x->var[v];
        for (int v = 0; v < (int)K_V_COUNT; v++) x->var[v] /= normed;
    }
}

/* flam3_align: dst[0 .. nsrc) as src with the same xforms, padded; unless the genome in the middle
 * interpolates old or older, a variation's parameters taken from the neighbouring keyframe where
 * this one lacks it, and the padding xforms given a better identity. */
static void align(genome *dst, const genome *src, int nsrc)
{
    int max_nx = src[0].nxforms;
    bool max_fx = src[0].has_final, aligned = true;
    for (int i = 1; i < nsrc; i++) {
        if (src[i].nxforms != max_nx) aligned = false;
        if (src[i].nxforms > max_nx) max_nx = src[i].nxforms;
        if (src[i].has_final != max_fx) aligned = false;
        max_fx |= src[i].has_final;
    }
    for (int i = 0; i < nsrc; i++) copyx(&dst[i], &src[i], max_nx, max_fx);
    fb_flame_itype it = dst[nsrc / 2 - 1].interpolation_type;
    if (it == FB_FLAME_ITYPE_OLD || it == FB_FLAME_ITYPE_OLDER) return;
    pthread_once(&owner_once, find_owners);
    for (int i = 0; i < nsrc; i++)
        for (int xf = 0; xf < max_nx + max_fx; xf++) {
            for (int v = (int)K_V_BLOB; v < (int)K_V_COUNT; v++) {
                if (dst[i].xf[xf].var[v] != 0) continue;
                if (i > 0) {
                    if (dst[i - 1].xf[xf].var[v] != 0) copy_params(&dst[i].xf[xf], &dst[i - 1].xf[xf], v);
                } else if (i < nsrc - 1) {
                    if (dst[i + 1].xf[xf].var[v] != 0) copy_params(&dst[i].xf[xf], &dst[i + 1].xf[xf], v);
                }
            }
            if (dst[i].xf[xf].padding && !aligned) better_identity(dst, nsrc, i, xf);
        }
}

/* ---- flam3_interpolate_n ---------------------------------------------------------------------- */

static void interp_palette(genome *r, int ncp, const genome *cp, const double *c)
{
    if (cp[0].palette_interpolation == FB_FLAME_PALINT_SWEEP) {
        for (int i = 0; i < 256; i++) {
            int j = i < 256 * c[0] ? 0 : 1;
            memcpy(r->palette[i], cp[j].palette[i], sizeof r->palette[i]);
        }
        return;
    }
    double rgb_fraction = cp[0].palette_interpolation == FB_FLAME_PALINT_RGB            ? 1.0
                          : cp[0].palette_interpolation == FB_FLAME_PALINT_HSV_CIRCULAR ? cp[0].hsv_rgb_palette_blend
                                                                                        : 0.0;
    for (int i = 0; i < 256; i++) {
        double new_rgb[3] = {0, 0, 0}, new_hsv[3] = {0, 0, 0}, count = 0;
        bool alpha1 = true;
        for (int k = 0; k < ncp; k++) {
            double hsv[3];
            fb_flame_rgb2hsv(cp[k].palette[i], hsv);
            if (ncp == 2 && k == 0 && cp[0].palette_interpolation == FB_FLAME_PALINT_HSV_CIRCULAR) {
                double second[3];
                fb_flame_rgb2hsv(cp[1].palette[i], second);
                if (second[0] - hsv[0] > 3.0)
                    hsv[0] += 6.0;
                else if (second[0] - hsv[0] < -3.0)
                    hsv[0] -= 6.0;
            }
            for (int j = 0; j < 3; j++) new_rgb[j] += c[k] * cp[k].palette[i][j], new_hsv[j] += c[k] * hsv[j];
            count += c[k] * cp[k].palette[i][3];
            if (cp[k].palette[i][3] != 1.0) alpha1 = false;
        }
        double back[3];
        fb_flame_hsv2rgb(new_hsv, back);
        for (int l = 0; l < 3; l++) r->palette[i][l] = rgb_fraction * new_rgb[l] + (1.0 - rgb_fraction) * back[l];
        r->palette[i][3] = alpha1 ? 1.0 : count;
        for (int j = 0; j < 4; j++) r->palette[i][j] = fmin(fmax(r->palette[i][j], 0.0), 1.0);
    }
}

static bool id_matrix(const double m[3][2])
{
    return m[0][0] == 1.0 && m[0][1] == 0.0 && m[1][0] == 0.0 && m[1][1] == 1.0 && m[2][0] == 0.0 && m[2][1] == 0.0;
}

/* The log-polar blend of xform xi's coefficients (post: its post transform): each column's angle
 * and log magnitude blended (the magnitude linearly where some is under e^-10), the angles first
 * brought to the shorter way round; the translation linearly (convert_linear_to_polar,
 * interp_and_convert_back). */
static void interp_polar(int ncp, const genome *cp, const double *c, int xi, bool post, double out[3][2])
{
    double ang[4][2], mag[4][2], trn[4][2];
    for (int k = 0; k < ncp; k++) {
        const double(*m)[2] = post ? cp[k].xf[xi].post : cp[k].xf[xi].c;
        bool zero[2];
        for (int col = 0; col < 2; col++) {
            ang[k][col] = atan2(m[col][1], m[col][0]);
            mag[k][col] = sqrt(m[col][0] * m[col][0] + m[col][1] * m[col][1]);
            zero[col] = mag[k][col] == 0.0;
            trn[k][col] = m[2][col];
        }
        if (zero[0] && !zero[1])
            ang[k][0] = ang[k][1];
        else if (!zero[0] && zero[1])
            ang[k][1] = ang[k][0];
    }
    for (int col = 0; col < 2; col++)
        for (int k = 1; k < ncp; k++) {
            double d = ang[k][col] - ang[k - 1][col];
            if (d > M_PI + EPS)
                ang[k][col] -= 2 * M_PI;
            else if (d < -(M_PI - EPS))
                ang[k][col] += 2 * M_PI;
        }
    memset(out, 0, sizeof(double[3][2]));
    for (int col = 0; col < 2; col++) {
        bool lin = false;
        for (int k = 0; k < ncp; k++) lin |= log(mag[k][col]) < -10;
        double a = 0, m = 0;
        for (int k = 0; k < ncp; k++) {
            a += c[k] * ang[k][col];
            m += c[k] * (lin ? mag[k][col] : log(mag[k][col]));
            out[2][col] += c[k] * trn[k][col];
        }
        double e = lin ? m : exp(m);
        out[col][0] = e * cos(a);
        out[col][1] = e * sin(a);
    }
}

#define BLEND(field)                                                                                                   \
    do {                                                                                                               \
        double s_ = 0;                                                                                                 \
        for (int k_ = 0; k_ < ncp; k_++) s_ += c[k_] * cp[k_].field;                                                   \
        r->field = s_;                                                                                                 \
    } while (0)
#define BLENDI(field)                                                                                                  \
    do {                                                                                                               \
        double s_ = 0;                                                                                                 \
        for (int k_ = 0; k_ < ncp; k_++) s_ += c[k_] * cp[k_].field;                                                   \
        r->field = (int)rint(s_);                                                                                      \
    } while (0)

static void interp_xform(genome *r, int ncp, const genome *cp, const double *c, int i)
{
    fb_flame_xform *x = &r->xf[i];
    BLEND(xf[i].weight);
    x->weight = fmax(x->weight, 0.0);
    BLEND(xf[i].color);
    x->color = fmin(fmax(x->color, 0.0), 1.0);
    BLEND(xf[i].color_speed);
    x->color_speed = fmin(fmax(x->color_speed, 0.0), 1.0);
    BLEND(xf[i].opacity);
    BLEND(xf[i].animate);
    for (int p = 0; p < FB_FP_COUNT; p++) BLEND(xf[i].par[p]);
    for (int v = 0; v < (int)K_V_COUNT; v++) BLEND(xf[i].var[v]);
    bool all_id = true;
    for (int k = 0; k < ncp; k++) all_id &= id_matrix(cp[k].xf[i].post);
    if (cp[0].interpolation_type == FB_FLAME_ITYPE_LOG) {
        interp_polar(ncp, cp, c, i, false, x->c);
        if (!all_id) interp_polar(ncp, cp, c, i, true, x->post);
    } else {
        memset(x->c, 0, sizeof x->c);
        memset(x->post, 0, sizeof x->post);
        for (int k = 0; k < ncp; k++)
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 2; b++)
                    x->c[a][b] += c[k] * cp[k].xf[i].c[a][b], x->post[a][b] += c[k] * cp[k].xf[i].post[a][b];
    }
    if (all_id) {
        memset(x->post, 0, sizeof x->post);
        x->post[0][0] = x->post[1][1] = 1.0;
    }
    x->padding = false;
}

/* r from the aligned genomes cp[0 .. ncp) with coefficients c (flam3_interpolate_n, no stagger). */
static void interpolate_n(genome *r, int ncp, const genome *cp, const double *c)
{
    *r = cp[0];
    interp_palette(r, ncp, cp, c);
    r->symmetry = false;
    BLEND(brightness);
    BLEND(highlight_power);
    BLEND(gamma);
    BLEND(vibrancy);
    BLENDI(width);
    BLENDI(height);
    BLENDI(supersample);
    BLEND(center[0]);
    BLEND(center[1]);
    for (int k = 0; k < 3; k++) BLEND(background[k]);
    BLEND(scale);
    BLEND(filter);
    BLEND(temporal_filter_exp);
    BLEND(temporal_filter_width);
    BLEND(quality);
    BLEND(zoom);
    BLEND(rotate);
    BLENDI(temporal_samples);
    BLEND(estimator);
    BLEND(estimator_minimum);
    BLEND(estimator_curve);
    BLEND(gamma_threshold);
    int nstd = cp[0].nxforms;
    r->chaos = false;
    for (int i = 0; i < nstd; i++)
        for (int j = 0; j < nstd; j++) {
            BLEND(xf[i].chaos[j]);
            if (r->xf[i].chaos[j] < 0) r->xf[i].chaos[j] = 0;
            if (fabs(r->xf[i].chaos[j] - 1.0) > 1e-10) r->chaos = true;
        }
    for (int i = 0; i < nstd + cp[0].has_final; i++) interp_xform(r, ncp, cp, c, i);
}

/* ---- flam3_interpolate ------------------------------------------------------------------------ */

fb_result fb_flame_interpolate(const fb_flame_genome *keys, int n, double time, fb_flame_genome *out)
{
    if (n == 1) {
        *out = keys[0];
        return FB_OK;
    }
    int i1, i2;
    if (keys[0].time >= time) {
        i1 = 0, i2 = 1;
    } else if (keys[n - 1].time <= time) {
        i1 = n - 2, i2 = n - 1;
    } else {
        i1 = 0;
        while (keys[i1].time < time) i1++;
        i1--, i2 = i1 + 1;
    }
    double c[2];
    c[0] = (keys[i2].time - time) / (keys[i2].time - keys[i1].time);
    c[1] = 1.0 - c[0];
    /* fb_flame_read_keys leaves no smooth segment first or last: i1 - 1 and i1 + 2 are keyframes */
    bool smooth = keys[i1].interpolation == FB_FLAME_INTERP_SMOOTH && i1 > 0 && i2 < n - 1;
    genome *cpi = malloc(4 * sizeof *cpi);
    if (!cpi) return fb_fail(FB_ERR_NOMEM, "out of memory interpolating keyframes");
    if (!smooth) {
        align(cpi, &keys[i1], 2);
        interpolate_n(out, 2, cpi, c);
    } else {
        align(cpi, &keys[i1 - 1], 4);
        double t = c[1], t2 = t * t, t3 = t2 * t;
        double cmc[4] = {(2 * t2 - t - t3) / 2, (3 * t3 - 5 * t2 + 2) / 2, (4 * t2 - 3 * t3 + t) / 2, (t3 - t2) / 2};
        interpolate_n(out, 4, cpi, cmc);
    }
    free(cpi);
    out->time = time;
    out->has_time = true;
    out->interpolation = FB_FLAME_INTERP_LINEAR;
    return FB_OK;
}

/* ---- the temporal filter ---------------------------------------------------------------------- */

double fb_flame_temporal_filter(int n, fb_flame_tfilter type, double fexp, double width, double *delta, double *weight)
{
    if (n == 1) {
        delta[0] = 0, weight[0] = 1;
        return 1.0;
    }
    double maxfilt = 0, sumfilt = 0;
    for (int i = 0; i < n; i++) {
        delta[i] = ((double)i / (double)(n - 1) - 0.5) * width;
        if (type == FB_FLAME_TFILTER_EXP) {
            double slpx = fexp >= 0 ? (i + 1.0) / n : (double)(n - i) / n;
            weight[i] = pow(slpx, fabs(fexp));
        } else if (type == FB_FLAME_TFILTER_GAUSSIAN) {
            /* flam3's gaussian spatial kernel at its support 1.5 times the distance from the middle */
            double half = n / 2.0, x = 1.5 * fabs(i - half) / half;
            weight[i] = exp(-2.0 * x * x) * sqrt(2.0 / M_PI);
        } else {
            weight[i] = 1.0;
        }
        if (weight[i] > maxfilt) maxfilt = weight[i];
    }
    for (int i = 0; i < n; i++) weight[i] /= maxfilt, sumfilt += weight[i];
    return sumfilt / n;
}

/* ---- a frame ---------------------------------------------------------------------------------- */

fb_result fb_flame_frame_init(const fb_flame_genome *keys, int n, double time, int samples, fb_flame_frame *f)
{
    memset(f, 0, sizeof *f);
    fb_result rc = fb_flame_interpolate(keys, n, time, &f->frame);
    if (rc) return rc;
    f->n = samples > 0 ? samples : f->frame.temporal_samples;
    if (f->n < 1) f->n = 1;
    f->delta = malloc((size_t)f->n * sizeof *f->delta);
    f->weight = malloc((size_t)f->n * sizeof *f->weight);
    genome *g = malloc(sizeof *g);
    if (!f->delta || !f->weight || !g) {
        free(g);
        fb_flame_frame_fini(f);
        return fb_fail(FB_ERR_NOMEM, "out of memory for %d temporal samples", samples);
    }
    f->sumfilt = fb_flame_temporal_filter(f->n, f->frame.temporal_filter_type, f->frame.temporal_filter_exp,
                                          f->frame.temporal_filter_width, f->delta, f->weight);
    for (int t = 0; t < f->n && !rc; t++) {
        rc = fb_flame_interpolate(keys, n, time + f->delta[t], g);
        if (rc) break;
        if (t == 0) {
            f->frame.estimator = g->estimator;
            f->frame.estimator_minimum = g->estimator_minimum;
            f->frame.estimator_curve = g->estimator_curve;
        }
        f->gamma += g->gamma, f->vibrancy += g->vibrancy; /* sums, then means, as flam3 does: n ones make 1 */
        for (int k = 0; k < 3; k++) f->background[k] += g->background[k];
        f->brightness = g->brightness, f->gamma_threshold = g->gamma_threshold;
        f->highlight_power = g->highlight_power;
    }
    free(g);
    f->gamma /= f->n, f->vibrancy /= f->n;
    for (int k = 0; k < 3; k++) f->background[k] /= f->n;
    if (rc) fb_flame_frame_fini(f);
    return rc;
}

void fb_flame_frame_fini(fb_flame_frame *f)
{
    if (!f) return;
    free(f->delta);
    free(f->weight);
    memset(f, 0, sizeof *f);
}
