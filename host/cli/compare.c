/*
 * `fractalbake compare` and `fractalbake info`: EXR (and PNG) consumers, streaming in blocks of rows.
 *
 * compare speaks idiff's vocabulary (OpenImageIO's image comparison): a pixel fails beyond --fail
 * (our --max-abs), a channel fails when more than --failpercent of its pixels do or any is beyond
 * --hardfail, and the same for warnings. It adds RMSE, PSNR and SSIM (Wang, Bovik, Sheikh and
 * Simoncelli, "Image quality assessment: from error visibility to structural similarity", IEEE
 * Transactions on Image Processing 13(4), 2004) as thresholds, per channel or layer.
 */
#include "compare.h"

#include "exrio.h"
#include "jsonout.h"
#include "pngio.h"
#include "preview.h"

#include <jansson.h>

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BLOCK_ROWS 64 /* a multiple of every scanline chunk height we read (1, 16, 32) */

/* ---- thresholds ------------------------------------------------------------------------------ */

static bool parse_value(const char *s, size_t n, double *out)
{
    char buf[64], *end;
    if (n == 0 || n >= sizeof buf) return false;
    memcpy(buf, s, n);
    buf[n] = 0;
    errno = 0;
    *out = strtod(buf, &end);
    return !*end && errno == 0 && isfinite(*out) && *out >= 0;
}

fb_result fb_limit_parse(const char *flag, const char *text, fb_limit *l)
{
    l->flag = flag;
    const char *p = text;
    if (!*p) return fb_fail(FB_ERR_USAGE, "%s: missing value", flag);
    while (*p) {
        const char *end = strchr(p, ',');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        const char *eq = memchr(p, '=', n);
        double v;
        if (!eq) {
            if (!parse_value(p, n, &v))
                return fb_fail(FB_ERR_USAGE, "%s: expected a finite number >= 0 or CHANNEL=VALUE, found \"%.*s\"", flag,
                               (int)n, p);
            l->has_all = true, l->all = v;
        } else {
            size_t kn = (size_t)(eq - p);
            if (kn == 0 || kn >= sizeof l->name[0] || !parse_value(eq + 1, n - kn - 1, &v))
                return fb_fail(FB_ERR_USAGE,
                               "%s: expected CHANNEL=VALUE (sky.R=1e-3) or LAYER=VALUE with a finite value >= 0, "
                               "found \"%.*s\"",
                               flag, (int)n, p);
            if (l->n >= FB_LIMIT_RULES)
                return fb_fail(FB_ERR_USAGE, "%s: at most %d CHANNEL=VALUE rules", flag, FB_LIMIT_RULES);
            memcpy(l->name[l->n], p, kn);
            l->name[l->n][kn] = 0;
            l->v[l->n++] = v;
        }
        l->set = true;
        p = end ? end + 1 : p + n;
        if (end && !*p) return fb_fail(FB_ERR_USAGE, "%s: a trailing comma in \"%s\"", flag, text);
    }
    return FB_OK;
}

/* 2: the rule names the channel; 1: its layer; 0: neither */
static int rule_match(const char *rule, const char *channel)
{
    if (!strcmp(rule, channel)) return 2;
    size_t n = strlen(rule);
    return !strncmp(channel, rule, n) && channel[n] == '.' ? 1 : 0;
}

bool fb_limit_get(const fb_limit *l, const char *channel, double *v)
{
    int best = 0;
    for (int i = 0; i < l->n; i++) {
        int m = rule_match(l->name[i], channel);
        if (m > best) best = m, *v = l->v[i];
    }
    if (best) return true;
    if (l->has_all) *v = l->all;
    return l->has_all;
}

/* ---- images: an EXR read in blocks of rows, or a PNG held whole ------------------------------ */

typedef struct image {
    const char *path;
    exrio_reader *exr;
    fb_png png;
    bool is_png;
} image;

static bool has_png_signature(const char *path)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    uint8_t b[8];
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    bool png = fread(b, 1, 8, f) == 8 && !memcmp(b, sig, 8);
    fclose(f);
    return png;
}

static fb_result image_open(const char *path, image *im)
{
    memset(im, 0, sizeof *im);
    im->path = path;
    if (has_png_signature(path)) {
        im->is_png = true;
        return fb_png_read(path, &im->png);
    }
    return exrio_open(path, &im->exr);
}

static void image_close(image *im)
{
    exrio_close(&im->exr);
    fb_png_fini(&im->png);
}

static int image_width(const image *im)
{
    return im->is_png ? im->png.width : exrio_width(im->exr);
}

static int image_height(const image *im)
{
    return im->is_png ? im->png.height : exrio_height(im->exr);
}

static void image_window(const image *im, int w[4])
{
    if (im->is_png)
        w[0] = w[1] = 0, w[2] = im->png.width, w[3] = im->png.height;
    else
        exrio_window(im->exr, &w[0], &w[1], &w[2], &w[3]);
}

static int image_nchannels(const image *im)
{
    return im->is_png ? im->png.channels : exrio_nchannels(im->exr);
}

static const char *image_channel(const image *im, int c)
{
    return im->is_png ? im->png.names[c] : exrio_channel_name(im->exr, c);
}

static bool image_uint(const image *im, int c)
{
    return !im->is_png && exrio_channel_type(im->exr, c) == EXRIO_UINT;
}

static int image_find(const image *im, const char *name)
{
    for (int c = 0; c < image_nchannels(im); c++)
        if (!strcmp(image_channel(im, c), name)) return c;
    return -1;
}

static fb_result image_read_rows(image *im, int y0, int n, void *const *planes)
{
    if (!im->is_png) return exrio_read_rows(im->exr, y0, n, planes);
    size_t w = (size_t)im->png.width;
    for (int c = 0; c < im->png.channels; c++)
        if (planes[c]) memcpy(planes[c], im->png.plane[c] + (size_t)y0 * w, (size_t)n * w * sizeof(float));
    return FB_OK;
}

/* ---- SSIM, streamed ------------------------------------------------------------------------- */

/* The paper's local statistics: an 11 x 11 circular-symmetric Gaussian window of standard
 * deviation 1.5, normalised to sum 1, applied separably (horizontally per row, then vertically over
 * a ring of 11 rows); K1 = 0.01, K2 = 0.03, L the channel's dynamic range; the mean of the SSIM map
 * over every position where the window lies inside the image (MSSIM, eq. 17). */
#define SSIM_R 5
#define SSIM_N (2 * SSIM_R + 1)

typedef struct ssim_acc {
    double w[SSIM_N];
    double c1, c2;
    int width, vw; /* image width, valid width (width - 10) */
    double *ring;  /* SSIM_N rows x 5 statistics x vw, the horizontally filtered rows */
    int rows_in;   /* rows added so far */
    double sum;    /* of the SSIM map */
    uint64_t count;
} ssim_acc;

static fb_result ssim_init(ssim_acc *s, int width, double range)
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
static void ssim_row(ssim_acc *s, const double *a, const double *b)
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

static void ssim_fini(ssim_acc *s)
{
    free(s->ring);
    s->ring = NULL;
}

/* ---- the comparison -------------------------------------------------------------------------- */

typedef struct chan_stats {
    int ia, ib; /* channel index in A and B */
    const char *name;
    bool uint_a, uint_b;
    double fail, warn, hardfail, hardwarn, failpct, warnpct, rmse_max, psnr_min, ssim_min;
    bool abs_test, has_warn, has_hardfail, has_hardwarn, has_warnpct, has_rmse, has_psnr, has_ssim;
    double max_abs;
    int max_x, max_y;
    double sum_sq;
    uint64_t n; /* finite pairs */
    uint64_t beyond, beyond_warn;
    uint64_t nonfinite_mismatch; /* NaN/Inf in one file and not the same in the other */
    uint64_t nonfinite_same;
    double a_lo, a_hi;
    ssim_acc ssim;
    double *ra, *rb; /* one row of each as doubles, for SSIM */
    fb_verdict verdict;
    char why[160];
} chan_stats;

static double value(const void *plane, bool is_uint, size_t i)
{
    return is_uint ? (double)((const uint32_t *)plane)[i] : (double)((const float *)plane)[i];
}

static bool in_layer(const char *name, const char *layer)
{
    if (!layer) return true;
    size_t n = strlen(layer);
    return !strncmp(name, layer, n) && name[n] == '.';
}

static void say(const fb_compare_desc *d, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say(const fb_compare_desc *d, const char *fmt, ...)
{
    if (d->json) return; /* the JSON object carries the same */
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    d->print(buf, d->user);
}

/* Every CHANNEL=VALUE rule of every threshold must name a compared channel or layer: a typo would
 * otherwise leave a channel unchecked. */
static fb_result check_rules(const fb_compare_desc *d, const chan_stats *st, int nst)
{
    const fb_limit *all[] = {&d->fail,     &d->failpercent, &d->hardfail, &d->warn, &d->warnpercent,
                             &d->hardwarn, &d->rmse,        &d->psnr,     &d->ssim};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
        for (int i = 0; i < all[k]->n; i++) {
            bool hit = false;
            for (int s = 0; s < nst && !hit; s++) hit = rule_match(all[k]->name[i], st[s].name) > 0;
            if (!hit) {
                char names[512] = "";
                for (int s = 0; s < nst && strlen(names) < 400; s++)
                    snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", s ? ", " : "", st[s].name);
                return fb_fail(FB_ERR_USAGE, "%s %s=...: no compared channel is %s or in layer %s (compared: %s)",
                               all[k]->flag, all[k]->name[i], all[k]->name[i], all[k]->name[i],
                               names[0] ? names : "none");
            }
        }
    return FB_OK;
}

/* A channel's thresholds from the limits. */
static void thresholds(const fb_compare_desc *d, chan_stats *c)
{
    const char *n = c->name;
    c->has_rmse = fb_limit_get(&d->rmse, n, &c->rmse_max);
    c->has_psnr = fb_limit_get(&d->psnr, n, &c->psnr_min);
    c->has_ssim = fb_limit_get(&d->ssim, n, &c->ssim_min);
    bool has_fail = fb_limit_get(&d->fail, n, &c->fail);
    bool has_failpct = fb_limit_get(&d->failpercent, n, &c->failpct);
    c->has_hardfail = fb_limit_get(&d->hardfail, n, &c->hardfail);
    c->has_warn = fb_limit_get(&d->warn, n, &c->warn);
    c->has_warnpct = fb_limit_get(&d->warnpercent, n, &c->warnpct);
    c->has_hardwarn = fb_limit_get(&d->hardwarn, n, &c->hardwarn);
    if (!has_fail) c->fail = 0;
    if (!has_failpct) c->failpct = 0;
    if (!c->has_warnpct) c->warnpct = 0;
    /* with no threshold at all every pixel must be equal; with only statistics, they decide */
    c->abs_test = has_fail || has_failpct || !(c->has_rmse || c->has_psnr || c->has_ssim || c->has_hardfail);
    if (!c->has_warn && (c->has_warnpct || c->has_hardwarn)) c->warn = 0, c->has_warn = c->has_warnpct;
}

/* A heat colour for t in [0, 1]: black, blue, red, yellow, white. */
static void heat(double t, float rgb[3])
{
    static const float stops[5][3] = {{0, 0, 0}, {0.1f, 0.15f, 1}, {1, 0.1f, 0.05f}, {1, 0.9f, 0.1f}, {1, 1, 1}};
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double x = t * 4;
    int i = x >= 4 ? 3 : (int)x;
    double f = x - i;
    for (int k = 0; k < 3; k++) rgb[k] = (float)(stops[i][k] + f * (stops[i + 1][k] - stops[i][k]));
}

/* The heat map's scale: |A - B| from 1e-8 (black) to 1 and more (white), a decade per eighth. */
static double heat_t(double ad)
{
    if (!(ad > 0)) return 0;
    if (isinf(ad)) return 1;
    return (log10(ad) + 8) / 8;
}

static const char *verdict_name(fb_verdict v)
{
    return v == FB_VERDICT_PASS ? "pass" : v == FB_VERDICT_WARN ? "warn" : "fail";
}

static void add_limit(json_t *o, const char *key, bool has, double v)
{
    if (has) json_object_set_new(o, key, json_real(v));
}

/* The end of the report: the verdict line, or the JSON object. */
static void report(const fb_compare_desc *d, fb_verdict v, const char *reason, int W, int H, chan_stats *st, int nst,
                   json_t *missing)
{
    if (!d->json) {
        char line[600];
        snprintf(line, sizeof line, "result: %s%s%s",
                 v == FB_VERDICT_PASS   ? "PASS"
                 : v == FB_VERDICT_WARN ? "WARN"
                                        : "FAIL",
                 reason[0] ? ": " : "", reason);
        d->print(line, d->user);
        return;
    }
    json_t *o = json_object(), *chans = json_array();
    json_object_set_new(o, "a", json_string(d->a));
    json_object_set_new(o, "b", json_string(d->b));
    if (W > 0) json_object_set_new(o, "size", json_pack("[ii]", W, H));
    json_object_set_new(o, "result", json_string(verdict_name(v)));
    if (reason[0]) json_object_set_new(o, "reason", json_string(reason));
    uint64_t total = (uint64_t)W * H;
    for (int s = 0; s < nst; s++) {
        chan_stats *c = &st[s];
        double rmse = c->n ? sqrt(c->sum_sq / (double)c->n) : 0;
        double peak = c->a_hi > c->a_lo ? c->a_hi - c->a_lo : (c->a_hi > 0 ? c->a_hi : 1.0);
        json_t *j = json_object(), *lim = json_object();
        json_object_set_new(j, "name", json_string(c->name));
        json_object_set_new(j, "result", json_string(verdict_name(c->verdict)));
        if (c->why[0]) json_object_set_new(j, "reason", json_string(c->why));
        json_object_set_new(j, "max_abs", isfinite(c->max_abs) ? json_real(c->max_abs) : json_null());
        if (c->max_x >= 0) json_object_set_new(j, "max_at", json_pack("[ii]", c->max_x, c->max_y));
        json_object_set_new(j, "rmse", json_real(rmse));
        json_object_set_new(j, "psnr_db", rmse > 0 ? json_real(20 * log10(peak / rmse)) : json_null());
        json_object_set_new(j, "beyond_fail_pixels", json_integer((json_int_t)c->beyond));
        json_object_set_new(j, "beyond_fail_percent", json_real(total ? 100.0 * (double)c->beyond / (double)total : 0));
        if (c->has_warn)
            json_object_set_new(j, "beyond_warn_percent",
                                json_real(total ? 100.0 * (double)c->beyond_warn / (double)total : 0));
        if (c->has_ssim) json_object_set_new(j, "ssim", json_real(c->ssim.count ? c->ssim.sum / c->ssim.count : 1));
        json_object_set_new(j, "nonfinite_differ", json_integer((json_int_t)c->nonfinite_mismatch));
        add_limit(lim, "fail", c->abs_test, c->fail);
        add_limit(lim, "failpercent", c->abs_test, c->failpct);
        add_limit(lim, "hardfail", c->has_hardfail, c->hardfail);
        add_limit(lim, "warn", c->has_warn, c->warn);
        add_limit(lim, "warnpercent", c->has_warn, c->warnpct);
        add_limit(lim, "hardwarn", c->has_hardwarn, c->hardwarn);
        add_limit(lim, "rmse", c->has_rmse, c->rmse_max);
        add_limit(lim, "psnr", c->has_psnr, c->psnr_min);
        add_limit(lim, "ssim", c->has_ssim, c->ssim_min);
        json_object_set_new(j, "thresholds", lim);
        json_array_append_new(chans, j);
    }
    json_object_set_new(o, "channels", chans);
    if (missing && json_array_size(missing)) json_object_set(o, "missing", missing);
    char *text = fb_json_dumps(o, 0);
    d->print(text ? text : "{}", d->user);
    free(text);
    json_decref(o);
}

fb_result fb_compare(const fb_compare_desc *d, fb_verdict *verdict)
{
    fb_result rc = FB_OK;
    image A, B;
    bool a_open = false, b_open = false;
    exrio_writer *diff = NULL;
    fb_preview *png = NULL;
    chan_stats *st = NULL;
    void **pa = NULL, **pb = NULL;
    float **pd = NULL;
    exrio_channel *dch = NULL;
    json_t *missing = json_array();
    float *pic[3] = {NULL, NULL, NULL};
    int nst = 0, W = 0, H = 0;
    char reason[512] = "";
    *verdict = FB_VERDICT_PASS;

    if (!(rc = image_open(d->a, &A))) a_open = true;
    if (!rc && !(rc = image_open(d->b, &B))) b_open = true;
    if (rc) goto out;
    W = image_width(&A), H = image_height(&A);
    if (W != image_width(&B) || H != image_height(&B)) {
        snprintf(reason, sizeof reason, "the sizes differ: %s is %d x %d, %s is %d x %d", d->a, W, H, d->b,
                 image_width(&B), image_height(&B));
        say(d, "%s", reason);
        *verdict = FB_VERDICT_FAIL;
        W = H = 0;
        goto out;
    }
    int wa[4], wb[4];
    image_window(&A, wa);
    image_window(&B, wb);
    if (memcmp(wa, wb, sizeof wa)) {
        snprintf(reason, sizeof reason,
                 "the regions differ: %s holds %d,%d,%d,%d of %d x %d, %s holds %d,%d,%d,%d of %d x %d", d->a, wa[0],
                 wa[1], W, H, wa[2], wa[3], d->b, wb[0], wb[1], W, H, wb[2], wb[3]);
        say(d, "%s", reason);
        *verdict = FB_VERDICT_FAIL;
        goto out;
    }
    int na = image_nchannels(&A), nb = image_nchannels(&B);
    st = calloc((size_t)na + 1, sizeof *st);
    pa = calloc((size_t)na + 1, sizeof *pa);
    pb = calloc((size_t)nb + 1, sizeof *pb);
    if (!st || !pa || !pb || !missing) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto out;
    }
    char only[400] = "";
    int nmissing = 0;
    for (int pass = 0; pass < 2; pass++) { /* A's channels missing from B, then B's from A */
        image *x = pass ? &B : &A, *y = pass ? &A : &B;
        for (int i = 0; i < image_nchannels(x); i++) {
            const char *name = image_channel(x, i);
            if (!in_layer(name, d->layer) || image_find(y, name) >= 0) continue;
            say(d, "%s: only in %s", name, x->path);
            json_array_append_new(missing, json_pack("{ssss}", "channel", name, "only_in", x->path));
            if (nmissing++ < 4)
                snprintf(only + strlen(only), sizeof only - strlen(only), "%s%s only in %s", nmissing > 1 ? ", " : "",
                         name, x->path);
        }
    }
    for (int i = 0; i < na; i++) {
        const char *name = image_channel(&A, i);
        int j = image_find(&B, name);
        if (!in_layer(name, d->layer) || j < 0) continue;
        st[nst] =
            (chan_stats){.ia = i, .ib = j, .name = name, .a_lo = INFINITY, .a_hi = -INFINITY, .max_x = -1, .max_y = -1};
        st[nst].uint_a = image_uint(&A, i);
        st[nst].uint_b = image_uint(&B, j);
        thresholds(d, &st[nst]);
        nst++;
    }
    if (d->layer && nst == 0 && nmissing == 0) {
        rc = fb_fail(FB_ERR_USAGE, "--layer: no channel %s.* in either file", d->layer);
        goto out;
    }
    if ((rc = check_rules(d, st, nst))) goto out;
    if (nmissing && !d->ignore_missing) {
        snprintf(reason, sizeof reason, "the channel sets differ: %s%s (--ignore-missing compares the common ones)",
                 only, nmissing > 4 ? ", ..." : "");
        *verdict = FB_VERDICT_FAIL;
    }
    if (nst == 0 && !reason[0]) {
        snprintf(reason, sizeof reason, "no channel in common to compare");
        *verdict = FB_VERDICT_FAIL;
    }

    size_t block = (size_t)W * BLOCK_ROWS;
    for (int s = 0; s < nst; s++) {
        if (!(pa[st[s].ia] = malloc(block * 4)) || !(pb[st[s].ib] = malloc(block * 4))) {
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            goto out;
        }
    }
    /* SSIM needs each channel's dynamic range first (A's; a PNG's is its full scale, 1) */
    bool want_ssim = false;
    for (int s = 0; s < nst; s++) want_ssim = want_ssim || st[s].has_ssim;
    if (want_ssim && (W < SSIM_N || H < SSIM_N)) {
        rc = fb_fail(FB_ERR_USAGE, "--ssim: the images are %d x %d, and SSIM's window needs at least %d x %d", W, H,
                     SSIM_N, SSIM_N);
        goto out;
    }
    if (want_ssim && !A.is_png) {
        double lo[256], hi[256];
        for (int s = 0; s < nst && s < 256; s++) lo[s] = INFINITY, hi[s] = -INFINITY;
        for (int y0 = 0; y0 < H && !rc; y0 += BLOCK_ROWS) {
            int n = y0 + BLOCK_ROWS <= H ? BLOCK_ROWS : H - y0;
            if ((rc = image_read_rows(&A, y0, n, pa))) goto out;
            for (int s = 0; s < nst && s < 256; s++)
                for (size_t i = 0; i < (size_t)W * n; i++) {
                    double v = value(pa[st[s].ia], st[s].uint_a, i);
                    if (isfinite(v)) lo[s] = v < lo[s] ? v : lo[s], hi[s] = v > hi[s] ? v : hi[s];
                }
        }
        for (int s = 0; s < nst; s++)
            if (st[s].has_ssim && (rc = ssim_init(&st[s].ssim, W, s < 256 && hi[s] > lo[s] ? hi[s] - lo[s] : 1.0)))
                goto out;
    } else if (want_ssim) {
        for (int s = 0; s < nst; s++)
            if (st[s].has_ssim && (rc = ssim_init(&st[s].ssim, W, 1.0))) goto out;
    }
    for (int s = 0; s < nst; s++)
        if (st[s].has_ssim &&
            (!(st[s].ra = malloc((size_t)W * sizeof(double))) || !(st[s].rb = malloc((size_t)W * sizeof(double))))) {
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            goto out;
        }
    if (d->diff && nst > 0) {
        dch = calloc((size_t)nst, sizeof *dch);
        pd = calloc((size_t)nst, sizeof *pd);
        if (!dch || !pd) {
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            goto out;
        }
        for (int s = 0; s < nst; s++) {
            dch[s] = (exrio_channel){st[s].name, EXRIO_FLOAT};
            if (!(pd[s] = malloc(block * 4))) {
                rc = fb_fail(FB_ERR_NOMEM, "out of memory");
                goto out;
            }
        }
        exrio_attr attrs[] = {{"fractalbake/diff", "absolute difference |A - B| of each common channel"}};
        rc = exrio_writer_create(&(exrio_writer_desc){.path = d->diff,
                                                      .what = "diff",
                                                      .width = W,
                                                      .height = H,
                                                      .compression = EXRIO_ZIP,
                                                      .channels = dch,
                                                      .nchannels = nst,
                                                      .attrs = attrs,
                                                      .nattrs = 1},
                                 &diff);
        if (rc) goto out;
    }
    if (d->diff_png && nst > 0) {
        if ((rc = fb_preview_create(W, H, 2048, 3, &png))) goto out;
        for (int k = 0; k < 3; k++)
            if (!(pic[k] = malloc(block * 4))) {
                rc = fb_fail(FB_ERR_NOMEM, "out of memory");
                goto out;
            }
    }
    for (int y0 = 0; y0 < H && nst > 0; y0 += BLOCK_ROWS) {
        int n = y0 + BLOCK_ROWS <= H ? BLOCK_ROWS : H - y0;
        if ((rc = image_read_rows(&A, y0, n, pa)) || (rc = image_read_rows(&B, y0, n, pb))) goto out;
        if (png && !d->heat) { /* the background: A's first compared channel, grey over its block range, dimmed */
            double lo = INFINITY, hi = -INFINITY;
            for (size_t i = 0; i < (size_t)W * n; i++) {
                double v = value(pa[st[0].ia], st[0].uint_a, i);
                if (isfinite(v)) lo = v < lo ? v : lo, hi = v > hi ? v : hi;
            }
            for (size_t i = 0; i < (size_t)W * n; i++) {
                double v = value(pa[st[0].ia], st[0].uint_a, i);
                float g = isfinite(v) && hi > lo ? (float)(0.25 * (v - lo) / (hi - lo)) : 0.0f;
                pic[0][i] = pic[1][i] = pic[2][i] = g;
            }
        } else if (png) {
            memset(pic[0], 0, (size_t)W * n * 4); /* pic[0]: the largest |A - B| so far, then colours */
        }
        for (int s = 0; s < nst; s++) {
            chan_stats *c = &st[s];
            const void *pA = pa[c->ia], *pB = pb[c->ib];
            for (size_t i = 0; i < (size_t)W * n; i++) {
                double va = value(pA, c->uint_a, i), vb = value(pB, c->uint_b, i);
                double ad;
                if (!isfinite(va) || !isfinite(vb)) {
                    bool same = (isnan(va) && isnan(vb)) || va == vb;
                    if (same) {
                        c->nonfinite_same++;
                        ad = 0;
                    } else {
                        c->nonfinite_mismatch++;
                        c->beyond++;
                        c->beyond_warn++;
                        c->max_abs = INFINITY;
                        ad = INFINITY;
                    }
                } else {
                    ad = fabs(va - vb);
                    c->n++;
                    c->sum_sq += ad * ad;
                    if (va < c->a_lo) c->a_lo = va;
                    if (va > c->a_hi) c->a_hi = va;
                    if (ad > c->max_abs || (c->max_x < 0 && ad > 0)) {
                        c->max_abs = ad;
                        c->max_x = (int)(i % (size_t)W);
                        c->max_y = y0 + (int)(i / (size_t)W);
                    }
                    if (ad > c->fail) c->beyond++;
                    if (c->has_warn && ad > c->warn) c->beyond_warn++;
                }
                if (pd) pd[s][i] = (float)ad;
                if (png && d->heat) {
                    if (ad > pic[0][i]) pic[0][i] = (float)(isinf(ad) ? 1e30 : ad);
                } else if (png && c->abs_test && ad > c->fail) {
                    pic[0][i] = 1.0f, pic[1][i] = pic[2][i] = 0.0f;
                }
            }
            if (c->has_ssim)
                for (int r = 0; r < n; r++) {
                    for (int x = 0; x < W; x++) {
                        size_t i = (size_t)r * W + x;
                        double va = value(pA, c->uint_a, i), vb = value(pB, c->uint_b, i);
                        c->ra[x] = isfinite(va) ? va : 0, c->rb[x] = isfinite(vb) ? vb : 0;
                    }
                    ssim_row(&c->ssim, c->ra, c->rb);
                }
        }
        if (png && d->heat)
            for (size_t i = 0; i < (size_t)W * n; i++) {
                float rgb[3];
                heat(heat_t(pic[0][i]), rgb);
                pic[0][i] = rgb[0], pic[1][i] = rgb[1], pic[2][i] = rgb[2];
            }
        if (png) fb_preview_add_rows(png, y0, n, (const float *const *)pic);
        if (diff && (rc = exrio_writer_rows(diff, y0, n, (const void *const *)pd))) goto out;
    }
    if (png && (rc = fb_preview_write_png(png, d->diff_png, "diff picture"))) goto out;

    uint64_t total = (uint64_t)W * H;
    char worst[200] = "";
    for (int s = 0; s < nst; s++) {
        chan_stats *c = &st[s];
        double rmse = c->n ? sqrt(c->sum_sq / (double)c->n) : 0;
        double peak = c->a_hi > c->a_lo ? c->a_hi - c->a_lo : (c->a_hi > 0 ? c->a_hi : 1.0);
        double psnr = rmse > 0 ? 20 * log10(peak / rmse) : INFINITY;
        double pct = total ? 100.0 * (double)c->beyond / (double)total : 0;
        double wpct = total ? 100.0 * (double)c->beyond_warn / (double)total : 0;
        double ssim = c->has_ssim ? (c->ssim.count ? c->ssim.sum / (double)c->ssim.count : 1.0) : NAN;
        c->verdict = FB_VERDICT_PASS;
#define FAIL_IF(cond, ...)                                                                                             \
    if (c->verdict != FB_VERDICT_FAIL && (cond))                                                                       \
    c->verdict = FB_VERDICT_FAIL, snprintf(c->why, sizeof c->why, __VA_ARGS__)
        FAIL_IF(c->abs_test && pct > c->failpct, "%.4g%% of pixels beyond %g (allowed %g%%)", pct, c->fail, c->failpct);
        FAIL_IF(c->has_hardfail && c->max_abs > c->hardfail, "max |A - B| %g beyond --hardfail %g", c->max_abs,
                c->hardfail);
        FAIL_IF(c->has_rmse && rmse > c->rmse_max, "RMSE %g beyond %g", rmse, c->rmse_max);
        FAIL_IF(c->has_psnr && psnr < c->psnr_min, "PSNR %.2f dB below %g", psnr, c->psnr_min);
        FAIL_IF(c->has_ssim && ssim < c->ssim_min, "SSIM %.6f below %g", ssim, c->ssim_min);
#undef FAIL_IF
        if (c->verdict == FB_VERDICT_PASS && c->has_warn && wpct > c->warnpct)
            c->verdict = FB_VERDICT_WARN,
            snprintf(c->why, sizeof c->why, "%.4g%% of pixels beyond the warning %g (allowed %g%%)", wpct, c->warn,
                     c->warnpct);
        if (c->verdict == FB_VERDICT_PASS && c->has_hardwarn && c->max_abs > c->hardwarn)
            c->verdict = FB_VERDICT_WARN,
            snprintf(c->why, sizeof c->why, "max |A - B| %g beyond --hardwarn %g", c->max_abs, c->hardwarn);
        if (c->verdict > *verdict) { /* the reason: the first channel with the worst verdict */
            *verdict = c->verdict;
            snprintf(worst, sizeof worst, "%s: %s", c->name, c->why);
        }
        char where[64] = "", ss[32] = "";
        if (c->max_x >= 0) snprintf(where, sizeof where, " at pixel (%d, %d)", c->max_x, c->max_y);
        if (c->has_ssim) snprintf(ss, sizeof ss, "  ssim %.6f", ssim);
        say(d, "%-16s max_abs %.6g%s  rmse %.6g  psnr %s%.2f dB  beyond %.4f%% (%llu px)%s  %s", c->name, c->max_abs,
            where, rmse, isinf(psnr) ? "+" : "", isinf(psnr) ? INFINITY : psnr, pct, (unsigned long long)c->beyond, ss,
            c->verdict == FB_VERDICT_PASS   ? "ok"
            : c->verdict == FB_VERDICT_WARN ? "WARN"
                                            : "FAIL");
        if (c->verdict != FB_VERDICT_PASS) say(d, "%-16s %s", "", c->why);
        if (c->nonfinite_mismatch || c->nonfinite_same)
            say(d, "%-16s non-finite pixels: %llu differ between the files, %llu identical in both", "",
                (unsigned long long)c->nonfinite_mismatch, (unsigned long long)c->nonfinite_same);
        if (c->n && c->a_lo == 0 && c->a_hi == 0) say(d, "%-16s all-zero in %s", "", d->a);
    }
    if (!reason[0]) snprintf(reason, sizeof reason, "%s", worst);
    if (png && d->heat)
        say(d,
            "%-16s %s: max |A - B| over the channels, black 1e-8, blue 1e-6, red 1e-4, yellow 0.01, "
            "white 1 and beyond",
            "", d->diff_png);
    if (diff) rc = exrio_writer_finish(&diff);
out:
    if (!rc) report(d, *verdict, reason, W, H, st, nst, missing);
    for (int k = 0; k < 3; k++) free(pic[k]);
    fb_preview_destroy(&png);
    exrio_writer_abort(&diff);
    if (st)
        for (int s = 0; s < nst; s++) {
            free(pa[st[s].ia]);
            free(pb[st[s].ib]);
            if (pd) free(pd[s]);
            ssim_fini(&st[s].ssim);
            free(st[s].ra);
            free(st[s].rb);
        }
    json_decref(missing);
    free(pd);
    free(dch);
    free(pa);
    free(pb);
    free(st);
    if (a_open) image_close(&A);
    if (b_open) image_close(&B);
    return rc;
}

/* ---- info ------------------------------------------------------------------------------------ */

/* The layer of a channel: the text before its last dot ("" for none). */
static int layer_len(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot ? (int)(dot - name) : 0;
}

fb_result fb_info(const char *path, bool json, void (*print)(const char *line, void *user), void *user)
{
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    json_t *o = json_object(), *layers = json_array(), *attrs = json_object(), *parts = json_array();
    char line[4096];
#define P(...)                                                                                                         \
    do {                                                                                                               \
        if (!json) {                                                                                                   \
            snprintf(line, sizeof line, __VA_ARGS__);                                                                  \
            print(line, user);                                                                                         \
        }                                                                                                              \
    } while (0)
    P("file:        %s", path);
    json_object_set_new(o, "file", json_string(path));
    int win[4];
    exrio_window(r, &win[0], &win[1], &win[2], &win[3]);
    json_object_set_new(o, "size", json_pack("[ii]", exrio_width(r), exrio_height(r)));
    if (win[0] || win[1] || win[2] != exrio_width(r) || win[3] != exrio_height(r)) {
        P("size:        %d x %d: the region %d,%d,%d,%d of a %d x %d image", exrio_width(r), exrio_height(r), win[0],
          win[1], exrio_width(r), exrio_height(r), win[2], win[3]);
        json_object_set_new(o, "region", json_pack("[iiii]", win[0], win[1], exrio_width(r), exrio_height(r)));
        json_object_set_new(o, "full_size", json_pack("[ii]", win[2], win[3]));
    } else {
        P("size:        %d x %d", exrio_width(r), exrio_height(r));
    }
    int np = exrio_nparts(r);
    if (np > 1) {
        P("parts:       %d", np);
        for (int p = 0; p < np; p++) {
            P("  part %-2d %-12s compression %s", p, exrio_part_name(r, p), exrio_part_compression(r, p));
            json_array_append_new(
                parts, json_pack("{ssss}", "name", exrio_part_name(r, p), "compression", exrio_part_compression(r, p)));
        }
        json_object_set_new(o, "parts", parts);
        parts = NULL;
    } else {
        P("compression: %s", exrio_compression_of(r));
        json_object_set_new(o, "compression", json_string(exrio_compression_of(r)));
    }
    P("channels:    %d", exrio_nchannels(r));
    /* Channels grouped by layer (the text before the last dot) within each part; the layer is named
     * in full, and a part's channels without a dot are its part's (a multi-part file) or "(no
     * layer)". */
    for (int c = 0; c < exrio_nchannels(r); c++) {
        const char *name = exrio_channel_name(r, c);
        int part = exrio_channel_part(r, c), llen = layer_len(name);
        bool first = true;
        for (int k = 0; k < c && first; k++) {
            const char *q = exrio_channel_name(r, k);
            first = !(exrio_channel_part(r, k) == part && layer_len(q) == llen && !strncmp(q, name, (size_t)llen));
        }
        if (!first) continue;
        char lname[300];
        if (llen)
            snprintf(lname, sizeof lname, "%.*s", llen, name);
        else
            snprintf(lname, sizeof lname, "%s",
                     np > 1 && exrio_part_name(r, part)[0] ? exrio_part_name(r, part) : "(no layer)");
        char chans[2048] = "";
        json_t *jl = json_object(), *jc = json_array();
        for (int k = c; k < exrio_nchannels(r); k++) {
            const char *q = exrio_channel_name(r, k);
            if (exrio_channel_part(r, k) != part || layer_len(q) != llen || strncmp(q, name, (size_t)llen)) continue;
            const char *short_name = llen ? q + llen + 1 : q, *type = exrio_type_name(exrio_channel_type(r, k));
            snprintf(chans + strlen(chans), sizeof chans - strlen(chans), "%s%s (%s)", chans[0] ? ", " : "", short_name,
                     type);
            json_array_append_new(jc, json_pack("{ssssss}", "name", q, "channel", short_name, "type", type));
        }
        P("  layer %-10s %s", lname, chans);
        json_object_set_new(jl, "layer", json_string(llen ? lname : ""));
        if (np > 1) json_object_set_new(jl, "part", json_integer(part));
        json_object_set_new(jl, "channels", jc);
        json_array_append_new(layers, jl);
    }
    json_object_set_new(o, "layers", layers);
    P("attributes:");
    for (int i = 0; i < exrio_attr_count(r); i++) {
        const char *name, *type;
        exrio_attr_at(r, i, &name, &type);
        if (!strcmp(name, "fractalbake/scene")) continue;
        char val[2048];
        exrio_attr_text(r, i, val, sizeof val);
        json_object_set_new(attrs, name, json_pack("{ssss}", "type", type, "value", val));
        char shown[2048], *o = shown; /* one line each: control characters as \n, \t, ? */
        for (const char *c = val; *c && o < shown + sizeof shown - 3; c++)
            if ((unsigned char)*c >= 0x20)
                *o++ = *c;
            else
                *o++ = '\\', *o++ = *c == '\n' ? 'n' : *c == '\t' ? 't' : '?';
        *o = 0;
        P("  %-26s %-12s %s", name, type, shown);
    }
    json_object_set_new(o, "attributes", attrs);
    const char *scene = exrio_attr_string(r, "fractalbake/scene");
    json_t *sj = scene ? json_loads(scene, 0, NULL) : NULL;
    if (scene) {
        P("stored scene:");
        char *pretty = sj ? fb_json_dumps(sj, 2) : NULL;
        if (!json) print(pretty ? pretty : scene, user);
        free(pretty);
        json_object_set_new(o, "scene", sj ? sj : json_string(scene));
    } else {
        P("stored scene: none (not written by fractalbake)");
        json_object_set_new(o, "scene", json_null());
    }
#undef P
    if (json) {
        char *text = fb_json_dumps(o, 0);
        print(text ? text : "{}", user);
        free(text);
    }
    json_decref(o);
    json_decref(parts);
    exrio_close(&r);
    return FB_OK;
}
