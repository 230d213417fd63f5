/* compare's HTML page and JUnit file (compare_int.h, report.h). */
#include "compare_int.h"
#include "report.h"

#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the HTML and JUnit reports -------------------------------------------------------------- */

static uint8_t to8(double v)
{
    return (uint8_t)(v <= 0 || !(v == v) ? 0 : v >= 1 ? 255 : v * 255 + 0.5);
}

static double srgb(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    return v <= 0.0031308 ? v * 12.92 : 1.055 * pow(v, 1 / 2.4) - 0.055;
}

typedef struct shown {
    int w, h, step;
} shown;

static fb_result add_picture(fb_report_layer *L, const char *label, const uint8_t *pix, int ch, shown s)
{
    fb_report_image *im = &L->img[L->nimg];
    im->label = label, im->width = s.w, im->height = s.h;
    fb_result rc = fb_png_encode(s.w, s.h, ch, pix, &im->png, &im->size);
    if (!rc) L->nimg++;
    return rc;
}

/* Channels idx[0..n) of the layer from A and B, as doubles. */
static fb_result read_layer(cmp *k, const int *idx, int n, double **va, double **vb)
{
    size_t np = (size_t)k->W * k->H;
    for (int q = 0; q < n; q++) {
        const chan_stats *c = &k->st[idx[q]];
        if (!(va[q] = malloc(np * 8)) || !(vb[q] = malloc(np * 8)))
            return fb_fail(FB_ERR_NOMEM, "out of memory for the report");
        for (size_t i = 0; i < np; i++) /* the channels were read whole (cmp_read_whole) */
            va[q][i] = cmp_value(k->pa[c->ia], c->uint_a, i), vb[q][i] = cmp_value(k->pb[c->ib], c->uint_b, i);
    }
    return FB_OK;
}

/* The layer's four pictures: A and B (colour, or its Y or first channel in grey over A's range),
 * the largest |A - B| over its channels as a heat map, and its FLIP error. */
static fb_result layer_pictures(cmp *k, fb_report_layer *L, const int *idx, int n, const int rgb[3], const flip_unit *u,
                                shown s)
{
    double *va[FB_LIMIT_RULES * 8] = {0}, *vb[FB_LIMIT_RULES * 8] = {0};
    if (n > (int)(sizeof va / sizeof va[0])) n = (int)(sizeof va / sizeof va[0]);
    fb_result rc = read_layer(k, idx, n, va, vb);
    size_t ns = (size_t)s.w * s.h;
    uint8_t *pix = rc ? NULL : malloc(ns * 3);
    if (!rc && !pix) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the report");
    int g = 0; /* the grey channel: Y, or the first */
    for (int q = 0; q < n; q++)
        if (!strcmp(strrchr(k->st[idx[q]].name, '.') ? strrchr(k->st[idx[q]].name, '.') + 1 : k->st[idx[q]].name, "Y"))
            g = q;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; !rc && i < (size_t)k->W * k->H; i++)
        if (isfinite(va[g][i])) lo = fmin(lo, va[g][i]), hi = fmax(hi, va[g][i]);
    for (int side = 0; side < 2 && !rc; side++) {
        double **v = side ? vb : va;
        for (size_t j = 0; j < ns; j++) {
            size_t i = (j / s.w) * s.step * (size_t)k->W + (j % s.w) * s.step;
            for (int q = 0; q < 3; q++)
                pix[3 * j + q] = rgb[0] >= 0 ? to8(k->A.is_png ? v[rgb[q]][i] : srgb(v[rgb[q]][i]))
                                             : to8(hi > lo ? (v[g][i] - lo) / (hi - lo) : 0);
        }
        rc = add_picture(L, side ? "test (B)" : "reference (A)", pix, 3, s);
    }
    for (size_t j = 0; j < ns && !rc; j++) {
        size_t i = (j / s.w) * s.step * (size_t)k->W + (j % s.w) * s.step;
        double m = 0;
        for (int q = 0; q < n; q++) {
            double d = fabs(va[q][i] - vb[q][i]);
            if (!(d <= m)) m = isnan(d) && !(isnan(va[q][i]) && isnan(vb[q][i])) ? INFINITY : isnan(d) ? m : d;
        }
        float c[3];
        cmp_heat(cmp_heat_t(m), c);
        for (int q = 0; q < 3; q++) pix[3 * j + q] = to8(c[q]);
    }
    if (!rc) rc = add_picture(L, "|A - B| (heat: black 1e-8 .. white 1)", pix, 3, s);
    for (size_t j = 0; u && j < ns && !rc; j++) {
        size_t i = (j / s.w) * s.step * (size_t)k->W + (j % s.w) * s.step;
        pix[3 * j] = pix[3 * j + 1] = pix[3 * j + 2] = to8(u->map[i]);
    }
    if (u && !rc) rc = add_picture(L, "FLIP error (black 0, white 1)", pix, 3, s);
    free(pix);
    for (int q = 0; q < n; q++) free(va[q]), free(vb[q]);
    return rc;
}

static void layer_rows(cmp *k, fb_report_layer *L, const int *idx, int n, const flip_unit *u)
{
    L->rows = calloc((size_t)n + 1, sizeof *L->rows);
    if (!L->rows) return;
    for (int q = 0; q < n; q++) {
        const chan_stats *c = &k->st[idx[q]];
        fb_report_row *r = &L->rows[L->nrows++];
        snprintf(r->name, sizeof r->name, "%s", c->name);
        snprintf(r->stats, sizeof r->stats, "max |A - B| %.6g, RMSE %.6g, PSNR %.2f dB, beyond %.4f%%%s", c->max_abs,
                 c->rmse, c->psnr, c->pct, c->has_ssim ? ", SSIM" : "");
        if (c->has_ssim) snprintf(r->stats + strlen(r->stats), sizeof r->stats - strlen(r->stats), " %.6f", c->ssim_v);
        snprintf(r->why, sizeof r->why, "%s", c->why);
        r->verdict = c->verdict;
        if (c->verdict > L->verdict) L->verdict = c->verdict;
    }
    if (u) {
        fb_report_row *r = &L->rows[L->nrows++];
        snprintf(r->name, sizeof r->name, "FLIP (%s%s)", u->hdr ? "HDR" : "LDR", u->grey ? ", Y" : "");
        snprintf(r->stats, sizeof r->stats, "mean %.6f, weighted median %.6f, quartiles %.6f %.6f, max %.6f", u->r.mean,
                 u->r.median, u->r.q1, u->r.q3, u->r.max);
        snprintf(r->why, sizeof r->why, "%s", u->why);
        r->verdict = u->verdict;
        if (u->verdict > L->verdict) L->verdict = u->verdict;
    }
}

/* One layer of the report: its channels (those of st with the prefix `name`). */
static fb_result report_layer(cmp *k, fb_report_layer *L, const char *name, shown s)
{
    int *idx = calloc((size_t)k->nst, sizeof *idx), n = 0, rgb[3] = {-1, -1, -1};
    if (!idx) return fb_fail(FB_ERR_NOMEM, "out of memory for the report");
    size_t ll = strlen(name);
    for (int q = 0; q < k->nst; q++) {
        const char *c = k->st[q].name, *dot = strrchr(c, '.');
        if ((size_t)(dot ? dot - c : 0) != ll || strncmp(c, name, ll)) continue;
        const char *last = dot ? dot + 1 : c;
        for (int j = 0; j < 3; j++)
            if (!strcmp(last, (const char *[]){"R", "G", "B"}[j]) && !k->st[q].uint_a) rgb[j] = n;
        idx[n++] = q;
    }
    if (rgb[0] < 0 || rgb[1] < 0 || rgb[2] < 0) rgb[0] = -1;
    const flip_unit *u = NULL;
    for (int f = 0; f < k->nfu; f++) {
        bool plain = !strcmp(k->fu[f].name, "RGB") || !strcmp(k->fu[f].name, "Y");
        if (plain ? ll == 0 : !strcmp(k->fu[f].name, name)) u = &k->fu[f];
    }
    snprintf(L->name, sizeof L->name, "%s", name);
    layer_rows(k, L, idx, n, u);
    fb_result rc = layer_pictures(k, L, idx, n, rgb, u, s);
    free(idx);
    return rc;
}

static int layer_order(const void *a, const void *b)
{
    const fb_report_layer *x = a, *y = b;
    if (x->verdict != y->verdict) return x->verdict > y->verdict ? -1 : 1;
    return strcmp(x->name, y->name);
}

fb_result cmp_write_html(cmp *k)
{
    const fb_compare_desc *d = k->d;
    fb_report r = {.a = d->a, .b = d->b, .reason = k->reason, .verdict = k->verdict, .width = k->W, .height = k->H};
    shown s = {.step = 1 + (k->W > k->H ? k->W - 1 : k->H - 1) / 1024};
    s.w = (k->W + s.step - 1) / s.step, s.h = (k->H + s.step - 1) / s.step;
    r.shown_width = s.w, r.shown_height = s.h;
    fb_result rc = FB_OK;
    r.layers = calloc((size_t)k->nst + 1, sizeof *r.layers);
    if (!r.layers) return fb_fail(FB_ERR_NOMEM, "out of memory for the report");
    for (int q = 0; q < k->nst && !rc; q++) { /* each layer once, at its first channel */
        const char *c = k->st[q].name, *dot = strrchr(c, '.');
        char name[128];
        snprintf(name, sizeof name, "%.*s", dot ? (int)(dot - c) : 0, c);
        bool seen = false;
        for (int j = 0; j < r.nlayers && !seen; j++) seen = !strcmp(r.layers[j].name, name);
        if (!seen) rc = report_layer(k, &r.layers[r.nlayers++], name, s);
    }
    qsort(r.layers, (size_t)r.nlayers, sizeof *r.layers, layer_order);
    const char *sa = k->A.is_png ? NULL : exrio_attr_string(k->A.exr, "fractalbake/scene");
    const char *sb = k->B.is_png ? NULL : exrio_attr_string(k->B.exr, "fractalbake/scene");
    if (!sa || !sb)
        r.scene_note = "not compared: a file holds no stored scene (not written by fractalbake)";
    else
        fb_report_scene_diff(sa, sb, &r.scene_diffs, &r.ndiffs);
    if (!rc) rc = fb_report_html(d->report, &r);
    for (int j = 0; j < r.nlayers; j++) {
        for (int i = 0; i < r.layers[j].nimg; i++) free(r.layers[j].img[i].png);
        free(r.layers[j].rows);
    }
    for (int j = 0; j < r.ndiffs; j++) free(r.scene_diffs[j]);
    free(r.scene_diffs);
    free(r.layers);
    return rc;
}

static void add_case(fb_junit_case *cs, int *n, const char *cls, bool failed, bool warned, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
static void add_case(fb_junit_case *cs, int *n, const char *cls, bool failed, bool warned, const char *fmt, ...)
{
    fb_junit_case *c = &cs[(*n)++];
    memset(c, 0, sizeof *c);
    snprintf(c->classname, sizeof c->classname, "%s", cls);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->name, sizeof c->name, fmt, ap);
    va_end(ap);
    c->failed = failed, c->warned = warned;
}

fb_result cmp_write_junit(cmp *k, double seconds)
{
    fb_junit_case *cs = calloc((size_t)(k->nst * 7 + k->nfu * 2 + 1), sizeof *cs);
    if (!cs) return fb_fail(FB_ERR_NOMEM, "out of memory for the JUnit report");
    int n = 0;
    for (int q = 0; q < k->nst; q++) {
        const chan_stats *c = &k->st[q];
        bool allowed = cmp_allowed(k, c);
        if (c->abs_test)
            add_case(cs, &n, c->name, !allowed && c->pct > c->failpct, false, "at most %g%% of pixels beyond %g",
                     c->failpct, c->fail);
        if (c->has_hardfail)
            add_case(cs, &n, c->name, !allowed && c->max_abs > c->hardfail, false, "no pixel beyond %g", c->hardfail);
        if (c->has_rmse) add_case(cs, &n, c->name, !(c->rmse <= c->rmse_max), false, "RMSE at most %g", c->rmse_max);
        if (c->has_psnr)
            add_case(cs, &n, c->name, !(c->psnr >= c->psnr_min), false, "PSNR at least %g dB", c->psnr_min);
        if (c->has_ssim) add_case(cs, &n, c->name, !(c->ssim_v >= c->ssim_min), false, "SSIM at least %g", c->ssim_min);
        if (c->has_warn || c->has_hardwarn)
            add_case(cs, &n, c->name, false, c->verdict == FB_VERDICT_WARN, "no warning (beyond %g)", c->warn);
        if (n > 0 && !strcmp(cs[n - 1].classname, c->name))
            for (int j = n - 1; j >= 0 && !strcmp(cs[j].classname, c->name); j--)
                snprintf(cs[j].message, sizeof cs[j].message, "%s", c->why[0] ? c->why : "ok");
    }
    for (int f = 0; f < k->nfu; f++) {
        const flip_unit *u = &k->fu[f];
        const char *stat = CMP_FLIP_STATS[k->d->flip_stat];
        if (u->has_fail)
            add_case(cs, &n, u->name, u->verdict == FB_VERDICT_FAIL, false, "FLIP %s at most %g", stat, u->limit_fail);
        if (u->has_warn)
            add_case(cs, &n, u->name, false, u->verdict == FB_VERDICT_WARN, "FLIP %s at most %g (warning)", stat,
                     u->limit_warn);
        for (int j = n - 1; j >= 0 && !strcmp(cs[j].classname, u->name) && (u->has_fail || u->has_warn); j--)
            snprintf(cs[j].message, sizeof cs[j].message, "%s", u->why[0] ? u->why : "ok");
    }
    char suite[600];
    snprintf(suite, sizeof suite, "fractalbake compare %s %s", k->d->a, k->d->b);
    fb_result rc = fb_report_junit(k->d->junit, suite, cs, n, seconds);
    free(cs);
    return rc;
}
