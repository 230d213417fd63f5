/*
 * `fractalbake compare`: two EXR (or PNG) files, channel by channel, streaming in blocks of rows.
 *
 * compare speaks idiff's vocabulary (OpenImageIO's image comparison): a pixel fails beyond --fail
 * (our --max-abs), a channel fails when more than --failpercent of its pixels do or any is beyond
 * --hardfail, and the same for warnings. It adds RMSE, PSNR and SSIM (Wang, Bovik, Sheikh and
 * Simoncelli, "Image quality assessment: from error visibility to structural similarity", IEEE
 * Transactions on Image Processing 13(4), 2004) as thresholds, per channel or layer.
 */
#include "textin.h"
#include "compare.h"
#include "flip.h"
#include "output.h"
#include "report.h"
#include "ssim.h"

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
#include <time.h>

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
    bool seen_all = false;
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
            if (seen_all)
                return fb_fail(FB_ERR_USAGE,
                               "%s: two values for every channel in \"%s\"; give one, and CHANNEL=VALUE or LAYER=VALUE "
                               "for the others",
                               flag, text);
            seen_all = true;
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

/* Whether path holds a PNG (else an EXR is read); "-" is an EXR on standard input. */
static fb_result probe_png(const char *path, bool *png)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    *png = false;
    if (!strcmp(path, "-")) return FB_OK;
    FILE *f = NULL;
    fb_result rc = fb_input_open_seekable(path, "EXR or PNG image", &f); /* read twice: here, then by its reader */
    if (rc) return rc;
    uint8_t b[8];
    *png = fread(b, 1, 8, f) == 8 && !memcmp(b, sig, 8);
    fclose(f);
    return FB_OK;
}

static fb_result image_open(const char *path, image *im)
{
    memset(im, 0, sizeof *im);
    im->path = path;
    fb_result rc = probe_png(path, &im->is_png);
    if (rc) return rc;
    if (im->is_png) return fb_png_read(path, &im->png);
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
    /* the statistics, once every row is in; a non-finite pixel that differs makes RMSE +inf, PSNR
     * -inf and SSIM -1 (the worst each can be), so no statistic passes it */
    double rmse, psnr, pct, wpct, ssim_v;
    fb_verdict verdict;
    char why[160];
} chan_stats;

/* A FLIP unit: a layer's R, G and B (or its Y as grey), compared as one picture. */
typedef struct flip_unit {
    char name[128]; /* the layer, "RGB" or "Y" for channels without one */
    int ch[3];      /* indices into the channel stats */
    bool hdr, grey;
    float *map;
    fb_flip_result r;
    uint64_t nonfinite; /* pixels where a non-finite value differs: error 1 */
    double limit_fail, limit_warn;
    bool has_fail, has_warn;
    fb_verdict verdict;
    char why[160];
} flip_unit;

typedef struct cmp {
    const fb_compare_desc *d;
    image A, B;
    bool a_open, b_open;
    int W, H, nst, nfu;
    chan_stats *st;
    flip_unit *fu;
    void **pa, **pb;
    exrio_writer *diff;
    float **pd; /* the diff's rows: one plane per channel, then one per FLIP unit */
    exrio_channel *dch;
    char (*dnames)[160];
    fb_preview *png;
    float *pic[3];
    json_t *missing;
    fb_verdict verdict;
    char reason[512];
    /* --idiff-stats: over every compared value */
    uint8_t *over;         /* per pixel of a block: 1 over the warning, 2 over the failure */
    double i_warn, i_fail; /* the thresholds of the two counts (idiff's default 1e-6) */
    double i_sum, i_sq, i_peak, i_max;
    int i_mx, i_my;
    const char *i_mc;
    uint64_t i_nvals, i_nwarn, i_nfail;
} cmp;

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

static fb_result rule_names_none(const fb_limit *l, int i, const char *const *names, int n)
{
    char list[512] = "";
    for (int s = 0; s < n && strlen(list) < 400; s++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", s ? ", " : "", names[s]);
    return fb_fail(FB_ERR_USAGE, "%s %s=...: no compared %s is %s or in layer %s (compared: %s)", l->flag, l->name[i],
                   l->flag && strstr(l->flag, "flip") ? "FLIP layer" : "channel", l->name[i], l->name[i],
                   list[0] ? list : "none");
}

/* Every CHANNEL=VALUE rule of every threshold must name a compared channel or layer (and a FLIP
 * rule a FLIP layer): a typo would otherwise leave a channel unchecked. */
static fb_result check_rules(const cmp *c)
{
    const fb_compare_desc *d = c->d;
    const fb_limit *all[] = {&d->fail,     &d->failpercent, &d->hardfail, &d->warn, &d->warnpercent,
                             &d->hardwarn, &d->rmse,        &d->psnr,     &d->ssim};
    const char **names = calloc((size_t)(c->nst + c->nfu) + 1, sizeof *names);
    if (!names) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int s = 0; s < c->nst; s++) names[s] = c->st[s].name;
    for (int u = 0; u < c->nfu; u++) names[c->nst + u] = c->fu[u].name;
    fb_result rc = FB_OK;
    for (size_t k = 0; k < sizeof all / sizeof all[0] && !rc; k++)
        for (int i = 0; i < all[k]->n && !rc; i++) {
            bool hit = false;
            for (int s = 0; s < c->nst && !hit; s++) hit = rule_match(all[k]->name[i], names[s]) > 0;
            if (!hit) rc = rule_names_none(all[k], i, names, c->nst);
        }
    const fb_limit *fl[] = {&d->flip_fail, &d->flip_warn};
    for (size_t k = 0; k < 2 && !rc; k++)
        for (int i = 0; i < fl[k]->n && !rc; i++) {
            bool hit = false;
            for (int u = 0; u < c->nfu && !hit; u++) hit = !strcmp(fl[k]->name[i], c->fu[u].name);
            if (!hit) rc = rule_names_none(fl[k], i, names + c->nst, c->nfu);
        }
    free(names);
    return rc;
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
    /* with no threshold at all every pixel must be equal; with only statistics (FLIP's included), they decide */
    c->abs_test =
        has_fail || has_failpct || !(c->has_rmse || c->has_psnr || c->has_ssim || c->has_hardfail || d->flip_fail.set);
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

static json_t *json_num(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static json_t *channel_json(const cmp *k, const chan_stats *c)
{
    json_t *j = json_object(), *lim = json_object();
    json_object_set_new(j, "name", json_string(c->name));
    json_object_set_new(j, "result", json_string(verdict_name(c->verdict)));
    if (c->why[0]) json_object_set_new(j, "reason", json_string(c->why));
    json_object_set_new(j, "max_abs", json_num(c->max_abs));
    if (c->max_x >= 0) json_object_set_new(j, "max_at", json_pack("[ii]", c->max_x, c->max_y));
    json_object_set_new(j, "rmse", json_num(c->rmse));
    json_object_set_new(j, "psnr_db", json_num(c->psnr));
    json_object_set_new(j, "beyond_fail_pixels", json_integer((json_int_t)c->beyond));
    json_object_set_new(j, "beyond_fail_percent", json_real(c->pct));
    if (c->has_warn) json_object_set_new(j, "beyond_warn_percent", json_real(c->wpct));
    if (c->has_ssim) json_object_set_new(j, "ssim", json_real(c->ssim_v));
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
    (void)k;
    return j;
}

static const char *const FLIP_STATS[] = {"mean", "median", "q1", "q3", "max"};

static double flip_stat(const flip_unit *u, int stat)
{
    const double v[] = {u->r.mean, u->r.median, u->r.q1, u->r.q3, u->r.max};
    return v[stat >= 0 && stat < 5 ? stat : 0];
}

static json_t *flip_json(const cmp *k, const flip_unit *u)
{
    json_t *j = json_pack("{sssssssfsfsfsfsfsf}", "name", u->name, "mode", u->hdr ? "HDR" : "LDR", "result",
                          verdict_name(u->verdict), "mean", u->r.mean, "weighted_median", u->r.median, "weighted_q1",
                          u->r.q1, "weighted_q3", u->r.q3, "min", u->r.min, "max", u->r.max);
    json_object_set_new(j, "channels", json_string(u->grey ? "Y" : "R,G,B"));
    if (u->hdr) {
        json_object_set_new(j, "start_exposure", json_real(u->r.start_exposure));
        json_object_set_new(j, "stop_exposure", json_real(u->r.stop_exposure));
        json_object_set_new(j, "num_exposures", json_integer(u->r.nexp));
        json_object_set_new(j, "zero_median", json_boolean(u->r.zero_median));
    }
    json_object_set_new(j, "nonfinite_differ", json_integer((json_int_t)u->nonfinite));
    if (u->why[0]) json_object_set_new(j, "reason", json_string(u->why));
    json_t *lim = json_object();
    add_limit(lim, "flip_fail", u->has_fail, u->limit_fail);
    add_limit(lim, "flip_warn", u->has_warn, u->limit_warn);
    if (u->has_fail || u->has_warn) json_object_set_new(lim, "statistic", json_string(FLIP_STATS[k->d->flip_stat]));
    json_object_set_new(j, "thresholds", lim);
    return j;
}

static json_t *idiff_json(const cmp *k);

/* The end of the report: the verdict line, or the JSON object. */
static void report(const cmp *k)
{
    const fb_compare_desc *d = k->d;
    if (!d->json) {
        char line[600];
        snprintf(line, sizeof line, "result: %s%s%s",
                 k->verdict == FB_VERDICT_PASS   ? "PASS"
                 : k->verdict == FB_VERDICT_WARN ? "WARN"
                                                 : "FAIL",
                 k->reason[0] ? ": " : "", k->reason);
        d->print(line, d->user);
        return;
    }
    json_t *o = json_object(), *chans = json_array();
    json_object_set_new(o, "a", json_string(d->a));
    json_object_set_new(o, "b", json_string(d->b));
    if (k->W > 0) json_object_set_new(o, "size", json_pack("[ii]", k->W, k->H));
    json_object_set_new(o, "result", json_string(verdict_name(k->verdict)));
    if (k->reason[0]) json_object_set_new(o, "reason", json_string(k->reason));
    for (int s = 0; s < k->nst; s++) json_array_append_new(chans, channel_json(k, &k->st[s]));
    json_object_set_new(o, "channels", chans);
    if (d->flip) {
        json_t *f = json_array();
        for (int u = 0; u < k->nfu; u++) json_array_append_new(f, flip_json(k, &k->fu[u]));
        json_object_set_new(o, "flip", f);
    }
    if (k->over) json_object_set_new(o, "idiff", idiff_json(k));
    if (k->missing && json_array_size(k->missing)) json_object_set(o, "missing", k->missing);
    char *text = fb_json_dumps(o, 0);
    d->print(text ? text : "{}", d->user);
    free(text);
    json_decref(o);
}

/* ---- steps of fb_compare --------------------------------------------------------------------- */

/* Opens both files and checks their sizes and regions; a mismatch is the verdict FAIL. */
static fb_result open_both(cmp *k)
{
    const fb_compare_desc *d = k->d;
    fb_result rc;
    if ((rc = image_open(d->a, &k->A))) return rc;
    k->a_open = true;
    if ((rc = image_open(d->b, &k->B))) return rc;
    k->b_open = true;
    k->W = image_width(&k->A), k->H = image_height(&k->A);
    if (k->W != image_width(&k->B) || k->H != image_height(&k->B)) {
        snprintf(k->reason, sizeof k->reason, "the sizes differ: %s is %d x %d, %s is %d x %d", d->a, k->W, k->H, d->b,
                 image_width(&k->B), image_height(&k->B));
        say(d, "%s", k->reason);
        k->verdict = FB_VERDICT_FAIL;
        k->W = k->H = 0;
        return FB_OK;
    }
    int wa[4], wb[4];
    image_window(&k->A, wa);
    image_window(&k->B, wb);
    if (memcmp(wa, wb, sizeof wa)) {
        snprintf(k->reason, sizeof k->reason,
                 "the regions differ: %s holds %d,%d,%d,%d of %d x %d, %s holds %d,%d,%d,%d of %d x %d", d->a, wa[0],
                 wa[1], k->W, k->H, wa[2], wa[3], d->b, wb[0], wb[1], k->W, k->H, wb[2], wb[3]);
        say(d, "%s", k->reason);
        k->verdict = FB_VERDICT_FAIL;
    }
    return FB_OK;
}

/* The channels in both files (within --layer), and those in one only. */
static fb_result match_channels(cmp *k)
{
    const fb_compare_desc *d = k->d;
    int na = image_nchannels(&k->A), nb = image_nchannels(&k->B);
    k->st = calloc((size_t)na + 1, sizeof *k->st);
    k->pa = calloc((size_t)na + 1, sizeof *k->pa);
    k->pb = calloc((size_t)nb + 1, sizeof *k->pb);
    if (!k->st || !k->pa || !k->pb || !k->missing) return fb_fail(FB_ERR_NOMEM, "out of memory");
    char only[400] = "";
    int nmissing = 0;
    for (int pass = 0; pass < 2; pass++) { /* A's channels missing from B, then B's from A */
        image *x = pass ? &k->B : &k->A, *y = pass ? &k->A : &k->B;
        for (int i = 0; i < image_nchannels(x); i++) {
            const char *name = image_channel(x, i);
            if (!in_layer(name, d->layer) || image_find(y, name) >= 0) continue;
            say(d, "%s: only in %s", name, x->path);
            json_array_append_new(k->missing, json_pack("{ssss}", "channel", name, "only_in", x->path));
            if (nmissing++ < 4)
                snprintf(only + strlen(only), sizeof only - strlen(only), "%s%s only in %s", nmissing > 1 ? ", " : "",
                         name, x->path);
        }
    }
    for (int i = 0; i < na; i++) {
        const char *name = image_channel(&k->A, i);
        int j = image_find(&k->B, name);
        if (!in_layer(name, d->layer) || j < 0) continue;
        chan_stats *c = &k->st[k->nst++];
        *c =
            (chan_stats){.ia = i, .ib = j, .name = name, .a_lo = INFINITY, .a_hi = -INFINITY, .max_x = -1, .max_y = -1};
        c->uint_a = image_uint(&k->A, i);
        c->uint_b = image_uint(&k->B, j);
        thresholds(d, c);
    }
    if (d->layer && k->nst == 0 && nmissing == 0)
        return fb_fail(FB_ERR_USAGE, "--layer: no channel %s.* in either file", d->layer);
    if (nmissing && !d->ignore_missing) {
        snprintf(k->reason, sizeof k->reason,
                 "the channel sets differ: %s%s (--ignore-missing compares the common ones)", only,
                 nmissing > 4 ? ", ..." : "");
        k->verdict = FB_VERDICT_FAIL;
    }
    if (k->nst == 0 && !k->reason[0]) {
        snprintf(k->reason, sizeof k->reason, "no channel in common to compare");
        k->verdict = FB_VERDICT_FAIL;
    }
    return FB_OK;
}

/* SSIM needs each channel's dynamic range first (A's; a PNG's is its full scale, 1). */
static fb_result setup_ssim(cmp *k)
{
    bool want = false;
    for (int s = 0; s < k->nst; s++) want = want || k->st[s].has_ssim;
    if (!want) return FB_OK;
    if (k->W < SSIM_N || k->H < SSIM_N)
        return fb_fail(FB_ERR_USAGE, "--ssim: the images are %d x %d, and SSIM's window needs at least %d x %d", k->W,
                       k->H, SSIM_N, SSIM_N);
    fb_result rc;
    for (int s = 0; s < k->nst; s++) k->st[s].a_lo = INFINITY, k->st[s].a_hi = -INFINITY;
    for (int y0 = 0; y0 < k->H && !k->A.is_png; y0 += BLOCK_ROWS) {
        int n = y0 + BLOCK_ROWS <= k->H ? BLOCK_ROWS : k->H - y0;
        if ((rc = image_read_rows(&k->A, y0, n, k->pa))) return rc;
        for (int s = 0; s < k->nst; s++)
            for (size_t i = 0; i < (size_t)k->W * n; i++) {
                chan_stats *c = &k->st[s];
                double v = value(k->pa[c->ia], c->uint_a, i);
                if (isfinite(v)) c->a_lo = v < c->a_lo ? v : c->a_lo, c->a_hi = v > c->a_hi ? v : c->a_hi;
            }
    }
    for (int s = 0; s < k->nst; s++) {
        chan_stats *c = &k->st[s];
        double range = !k->A.is_png && c->a_hi > c->a_lo ? c->a_hi - c->a_lo : 1.0;
        c->a_lo = INFINITY, c->a_hi = -INFINITY; /* measured again with the statistics */
        if (!c->has_ssim) continue;
        if ((rc = ssim_init(&c->ssim, k->W, range))) return rc;
        if (!(c->ra = malloc((size_t)k->W * sizeof(double))) || !(c->rb = malloc((size_t)k->W * sizeof(double))))
            return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    return FB_OK;
}

/* The FLIP units among the compared channels: per layer, R G B, or else Y. */
static fb_result find_flip_units(cmp *k)
{
    const fb_compare_desc *d = k->d;
    if (!d->flip) return FB_OK;
    if (!(k->fu = calloc((size_t)k->nst + 1, sizeof *k->fu))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int s = 0; s < k->nst; s++) {
        const char *name = k->st[s].name, *dot = strrchr(name, '.');
        const char *last = dot ? dot + 1 : name;
        int ll = dot ? (int)(dot - name) : 0;
        bool grey = !strcmp(last, "Y");
        if (strcmp(last, "R") && !grey) continue; /* a unit starts at its R (or Y) */
        int ch[3] = {s, s, s};
        if (!grey) {
            const char *want[2] = {"G", "B"};
            for (int q = 0; q < 2; q++) {
                ch[q + 1] = -1;
                for (int t = 0; t < k->nst; t++) {
                    const char *o = k->st[t].name;
                    if ((int)strlen(o) == ll + (ll ? 2 : 1) && !strncmp(o, name, (size_t)ll) &&
                        !strcmp(o + ll + (ll ? 1 : 0), want[q]))
                        ch[q + 1] = t;
                }
            }
            if (ch[1] < 0 || ch[2] < 0) continue;
        } else { /* a Y beside R G B belongs to the colour unit */
            bool colour = false;
            for (int t = 0; t < k->nst; t++) {
                const char *o = k->st[t].name;
                colour = colour || ((int)strlen(o) == ll + (ll ? 2 : 1) && !strncmp(o, name, (size_t)ll) &&
                                    !strcmp(o + ll + (ll ? 1 : 0), "R"));
            }
            if (colour) continue;
        }
        bool uint = false;
        for (int q = 0; q < 3; q++) uint = uint || k->st[ch[q]].uint_a || k->st[ch[q]].uint_b;
        if (uint) continue;
        flip_unit *u = &k->fu[k->nfu++];
        if (ll)
            snprintf(u->name, sizeof u->name, "%.*s", ll, name);
        else
            snprintf(u->name, sizeof u->name, "%s", grey ? "Y" : "RGB");
        memcpy(u->ch, ch, sizeof ch);
        u->grey = grey;
        u->hdr = d->flip_mode == FB_FLIP_HDR || (d->flip_mode == FB_FLIP_AUTO && !k->A.is_png);
        u->has_fail = fb_limit_get(&d->flip_fail, u->name, &u->limit_fail);
        u->has_warn = fb_limit_get(&d->flip_warn, u->name, &u->limit_warn);
    }
    if (k->nfu == 0 && k->nst > 0)
        return fb_fail(FB_ERR_USAGE, "--flip: no compared layer has R, G and B (or Y) float channels%s%s",
                       d->layer ? " in layer " : "", d->layer ? d->layer : "");
    return FB_OK;
}

/* One unit's FLIP map: its six planes read whole, non-finite values replaced by 0 for the filters
 * and their pixels given the largest error, 1, where the files disagree. */
static fb_result flip_one(cmp *k, flip_unit *u)
{
    size_t n = (size_t)k->W * k->H;
    float *buf = malloc(n * 6 * sizeof(float));
    if (!buf || !(u->map = malloc(n * sizeof(float)))) {
        free(buf);
        return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP of %s (%d x %d)", u->name, k->W, k->H);
    }
    float *pa[3], *pb[3];
    int na = image_nchannels(&k->A), nb = image_nchannels(&k->B);
    void **va = calloc((size_t)na, sizeof *va), **vb = calloc((size_t)nb, sizeof *vb);
    fb_result rc = va && vb ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int q = 0; q < 3 && !rc; q++) {
        pa[q] = buf + (size_t)q * n, pb[q] = buf + (size_t)(3 + q) * n;
        if (q == 0 || !u->grey) va[k->st[u->ch[q]].ia] = pa[q], vb[k->st[u->ch[q]].ib] = pb[q];
    }
    if (!rc && !(rc = image_read_rows(&k->A, 0, k->H, va))) rc = image_read_rows(&k->B, 0, k->H, vb);
    if (u->grey && !rc)
        for (int q = 1; q < 3; q++) pa[q] = pa[0], pb[q] = pb[0];
    free(va);
    free(vb);
    uint8_t *bad = rc ? NULL : calloc(n, 1);
    if (!rc && !bad) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n && !rc; i++)
        for (int q = 0; q < 3; q++) {
            float x = pa[q][i], y = pb[q][i];
            if (isfinite(x) && isfinite(y)) continue;
            if (!((isnan(x) && isnan(y)) || x == y)) bad[i] = 1;
            if (!isfinite(x)) pa[q][i] = 0;
            if (!isfinite(y)) pb[q][i] = 0;
        }
    if (!rc)
        rc = fb_flip((const float *const *)pa, (const float *const *)pb, k->W, k->H, u->hdr, fb_flip_default_ppd(),
                     u->map, &u->r);
    for (size_t i = 0; i < n && !rc; i++)
        if (bad[i]) u->map[i] = 1.0f, u->nonfinite++;
    if (!rc && u->nonfinite) {
        fb_flip_result keep = u->r;
        rc = fb_flip_pool(u->map, n, &u->r);
        u->r.start_exposure = keep.start_exposure, u->r.stop_exposure = keep.stop_exposure;
        u->r.nexp = keep.nexp, u->r.zero_median = keep.zero_median;
    }
    free(bad);
    free(buf);
    return rc;
}

/* The FLIP picture: the unit of the largest mean error, grey, round(255 * error). */
static fb_result write_flip_png(cmp *k)
{
    if (!k->d->flip_png || k->nfu == 0) return FB_OK;
    int best = 0;
    for (int u = 1; u < k->nfu; u++)
        if (k->fu[u].r.mean > k->fu[best].r.mean) best = u;
    size_t n = (size_t)k->W * k->H;
    uint8_t *pix = malloc(n ? n : 1);
    if (!pix) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n; i++) pix[i] = (uint8_t)(255.0f * k->fu[best].map[i] + 0.5f);
    const char *kv[2][2] = {{"fractalbake/flip-layer", k->fu[best].name},
                            {"fractalbake/flip", "FLIP error, round(255 * error), Andersson et al. 2020"}};
    fb_result rc = fb_png_write(k->d->flip_png, "FLIP picture", k->W, k->H, 1, 8, pix, kv, 2);
    free(pix);
    if (!rc) say(k->d, "%-16s %s: the FLIP error of %s, black 0, white 1", "", k->d->flip_png, k->fu[best].name);
    return rc;
}

static fb_result compute_flip(cmp *k)
{
    fb_result rc = FB_OK;
    for (int u = 0; u < k->nfu && !rc; u++) rc = flip_one(k, &k->fu[u]);
    return rc ? rc : write_flip_png(k);
}

/* The diff EXR (|A - B| per channel, then each FLIP unit's error as LAYER.FLIP) and the picture. */
static fb_result open_outputs(cmp *k)
{
    const fb_compare_desc *d = k->d;
    size_t block = (size_t)k->W * BLOCK_ROWS;
    int nd = k->nst + k->nfu;
    if (d->diff) {
        k->dch = calloc((size_t)nd, sizeof *k->dch);
        k->pd = calloc((size_t)nd, sizeof *k->pd);
        k->dnames = calloc((size_t)k->nfu + 1, sizeof *k->dnames);
        if (!k->dch || !k->pd || !k->dnames) return fb_fail(FB_ERR_NOMEM, "out of memory");
        for (int s = 0; s < nd; s++) {
            const char *name = k->st[s < k->nst ? s : 0].name;
            if (s >= k->nst) {
                const flip_unit *u = &k->fu[s - k->nst];
                bool plain = !strcmp(u->name, "RGB") || !strcmp(u->name, "Y");
                snprintf(k->dnames[s - k->nst], sizeof k->dnames[0], "%s%sFLIP", plain ? "" : u->name,
                         plain ? "" : ".");
                name = k->dnames[s - k->nst];
            }
            k->dch[s] = (exrio_channel){name, EXRIO_FLOAT};
            if (s < k->nst && !(k->pd[s] = malloc(block * 4))) return fb_fail(FB_ERR_NOMEM, "out of memory");
        }
        exrio_attr attrs[] = {{"fractalbake/diff", "absolute difference |A - B| of each common channel; "
                                                   "LAYER.FLIP: the FLIP error of the layer's colour (or Y)"}};
        fb_result rc = exrio_writer_create(&(exrio_writer_desc){.path = d->diff,
                                                                .what = "diff",
                                                                .width = k->W,
                                                                .height = k->H,
                                                                .compression = EXRIO_ZIP,
                                                                .channels = k->dch,
                                                                .nchannels = nd,
                                                                .attrs = attrs,
                                                                .nattrs = 1},
                                           &k->diff);
        if (rc) return rc;
    }
    if (d->diff_png) {
        fb_result rc = fb_preview_create(k->W, k->H, 2048, 3, &k->png);
        if (rc) return rc;
        for (int q = 0; q < 3; q++)
            if (!(k->pic[q] = malloc(block * 4))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    return FB_OK;
}

/* The picture's background for a block: A's first compared channel, grey over its block range, dimmed. */
static void picture_background(cmp *k, size_t npix)
{
    const chan_stats *c = &k->st[0];
    if (k->d->heat) {
        memset(k->pic[0], 0, npix * 4); /* pic[0]: the largest |A - B| so far, then colours */
        return;
    }
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < npix; i++) {
        double v = value(k->pa[c->ia], c->uint_a, i);
        if (isfinite(v)) lo = v < lo ? v : lo, hi = v > hi ? v : hi;
    }
    for (size_t i = 0; i < npix; i++) {
        double v = value(k->pa[c->ia], c->uint_a, i);
        float g = isfinite(v) && hi > lo ? (float)(0.25 * (v - lo) / (hi - lo)) : 0.0f;
        k->pic[0][i] = k->pic[1][i] = k->pic[2][i] = g;
    }
}

/* --idiff-stats: one finite pair of values into the totals and the block's per-pixel flags. */
static void idiff_value(cmp *k, const chan_stats *c, double va, double vb, double ad, double avg, size_t i, int y0)
{
    k->i_sum += ad, k->i_sq += ad * ad, k->i_nvals++;
    if (va > k->i_peak) k->i_peak = va;
    if (vb > k->i_peak) k->i_peak = vb;
    if (ad > k->i_max || !k->i_mc)
        k->i_max = ad, k->i_mx = (int)(i % (size_t)k->W), k->i_my = y0 + (int)(i / (size_t)k->W), k->i_mc = c->name;
    if (ad > k->i_warn && ad > k->d->warnrelative * avg) k->over[i] |= 1;
    if (ad > k->i_fail && ad > k->d->failrelative * avg) k->over[i] |= 2;
}

/* One channel's share of a block: its statistics, its diff row and its marks on the picture. */
static void channel_block(cmp *k, int s, int y0, int n)
{
    chan_stats *c = &k->st[s];
    const void *pA = k->pa[c->ia], *pB = k->pb[c->ib];
    size_t W = (size_t)k->W, npix = W * n;
    for (size_t i = 0; i < npix; i++) {
        double va = value(pA, c->uint_a, i), vb = value(pB, c->uint_b, i), ad;
        if (!isfinite(va) || !isfinite(vb)) {
            if ((isnan(va) && isnan(vb)) || va == vb) {
                c->nonfinite_same++;
                ad = 0;
            } else {
                c->nonfinite_mismatch++, c->beyond++, c->beyond_warn++;
                c->max_abs = ad = INFINITY;
                if (k->over) k->over[i] |= 3;
            }
        } else {
            ad = fabs(va - vb);
            c->n++;
            c->sum_sq += ad * ad;
            if (va < c->a_lo) c->a_lo = va;
            if (va > c->a_hi) c->a_hi = va;
            if (ad > c->max_abs || (c->max_x < 0 && ad > 0))
                c->max_abs = ad, c->max_x = (int)(i % W), c->max_y = y0 + (int)(i / W);
            double avg = 0.5 * (fabs(va) + fabs(vb));
            bool over_fail = ad > c->fail && ad > k->d->failrelative * avg;
            bool over_warn = ad > c->warn && ad > k->d->warnrelative * avg;
            if (over_fail) c->beyond++;
            if (c->has_warn && over_warn) c->beyond_warn++;
            if (k->over) idiff_value(k, c, va, vb, ad, avg, i, y0);
        }
        if (k->pd) k->pd[s][i] = (float)ad;
        if (k->png && k->d->heat) {
            if (ad > k->pic[0][i]) k->pic[0][i] = (float)(isinf(ad) ? 1e30 : ad);
        } else if (k->png && c->abs_test && ad > c->fail) {
            k->pic[0][i] = 1.0f, k->pic[1][i] = k->pic[2][i] = 0.0f;
        }
    }
    for (int r = 0; r < n && c->has_ssim; r++) {
        for (size_t x = 0; x < W; x++) {
            double va = value(pA, c->uint_a, r * W + x), vb = value(pB, c->uint_b, r * W + x);
            c->ra[x] = isfinite(va) ? va : 0, c->rb[x] = isfinite(vb) ? vb : 0;
        }
        ssim_row(&c->ssim, c->ra, c->rb);
    }
}

/* Every block of rows through the statistics, the diff and the picture. */
static fb_result stream_blocks(cmp *k)
{
    fb_result rc;
    size_t block = (size_t)k->W * BLOCK_ROWS;
    for (int s = 0; s < k->nst; s++)
        if ((!k->pa[k->st[s].ia] && !(k->pa[k->st[s].ia] = malloc(block * 4))) ||
            (!k->pb[k->st[s].ib] && !(k->pb[k->st[s].ib] = malloc(block * 4))))
            return fb_fail(FB_ERR_NOMEM, "out of memory");
    if ((rc = setup_ssim(k))) return rc;
    if (k->d->idiff_stats) {
        if (!(k->over = malloc(block ? block : 1))) return fb_fail(FB_ERR_NOMEM, "out of memory");
        k->i_warn = k->d->warn.has_all ? k->d->warn.all : 1e-6;
        k->i_fail = k->d->fail.has_all ? k->d->fail.all : 1e-6;
        k->i_peak = 1.0;
    }
    for (int y0 = 0; y0 < k->H && k->nst > 0; y0 += BLOCK_ROWS) {
        int n = y0 + BLOCK_ROWS <= k->H ? BLOCK_ROWS : k->H - y0;
        size_t npix = (size_t)k->W * n;
        if ((rc = image_read_rows(&k->A, y0, n, k->pa)) || (rc = image_read_rows(&k->B, y0, n, k->pb))) return rc;
        if (k->png) picture_background(k, npix);
        if (k->over) memset(k->over, 0, npix);
        for (int s = 0; s < k->nst; s++) channel_block(k, s, y0, n);
        for (size_t i = 0; k->over && i < npix; i++) k->i_nwarn += k->over[i] & 1, k->i_nfail += k->over[i] >> 1;
        if (k->png && k->d->heat)
            for (size_t i = 0; i < npix; i++) {
                float rgb[3];
                heat(heat_t(k->pic[0][i]), rgb);
                k->pic[0][i] = rgb[0], k->pic[1][i] = rgb[1], k->pic[2][i] = rgb[2];
            }
        if (k->png) fb_preview_add_rows(k->png, y0, n, (const float *const *)k->pic);
        for (int u = 0; u < k->nfu && k->pd; u++) k->pd[k->nst + u] = k->fu[u].map + (size_t)y0 * k->W;
        if (k->diff && (rc = exrio_writer_rows(k->diff, y0, n, (const void *const *)k->pd))) return rc;
    }
    if (k->png && (rc = fb_preview_write_png(k->png, k->d->diff_png, "diff picture"))) return rc;
    if (k->png && k->d->heat)
        say(k->d,
            "%-16s %s: max |A - B| over the channels, black 1e-8, blue 1e-6, red 1e-4, yellow 0.01, "
            "white 1 and beyond",
            "", k->d->diff_png);
    return k->diff ? exrio_writer_finish(&k->diff) : FB_OK;
}

/* A channel's statistics and verdict. */
static void channel_verdict(cmp *k, chan_stats *c)
{
    uint64_t total = (uint64_t)k->W * k->H;
    double peak = c->a_hi > c->a_lo ? c->a_hi - c->a_lo : (c->a_hi > 0 ? c->a_hi : 1.0);
    c->rmse = c->nonfinite_mismatch ? INFINITY : c->n ? sqrt(c->sum_sq / (double)c->n) : 0;
    c->psnr = c->nonfinite_mismatch ? -INFINITY : c->rmse > 0 ? 20 * log10(peak / c->rmse) : INFINITY;
    c->pct = total ? 100.0 * (double)c->beyond / (double)total : 0;
    c->wpct = total ? 100.0 * (double)c->beyond_warn / (double)total : 0;
    c->ssim_v = !c->has_ssim ? NAN : c->nonfinite_mismatch ? -1.0 : ssim_mean(&c->ssim);
    c->verdict = FB_VERDICT_PASS;
#define FAIL_IF(cond, ...)                                                                                             \
    if (c->verdict != FB_VERDICT_FAIL && (cond))                                                                       \
    c->verdict = FB_VERDICT_FAIL, snprintf(c->why, sizeof c->why, __VA_ARGS__)
    bool allowed = (long long)c->beyond <= k->d->allowfailures && c->nonfinite_mismatch == 0;
    FAIL_IF(!allowed && c->abs_test && c->pct > c->failpct, "%.4g%% of pixels beyond %g (allowed %g%%%s)", c->pct,
            c->fail, c->failpct, k->d->allowfailures ? " or --allowfailures" : "");
    FAIL_IF(!allowed && c->has_hardfail && c->max_abs > c->hardfail, "max |A - B| %g beyond --hardfail %g", c->max_abs,
            c->hardfail);
    FAIL_IF(c->has_rmse && !(c->rmse <= c->rmse_max), "RMSE %g beyond %g", c->rmse, c->rmse_max);
    FAIL_IF(c->has_psnr && !(c->psnr >= c->psnr_min), "PSNR %.2f dB below %g", c->psnr, c->psnr_min);
    FAIL_IF(c->has_ssim && !(c->ssim_v >= c->ssim_min), "SSIM %.6f below %g", c->ssim_v, c->ssim_min);
#undef FAIL_IF
    if (c->verdict == FB_VERDICT_PASS && c->has_warn && c->wpct > c->warnpct)
        c->verdict = FB_VERDICT_WARN,
        snprintf(c->why, sizeof c->why, "%.4g%% of pixels beyond the warning %g (allowed %g%%)", c->wpct, c->warn,
                 c->warnpct);
    if (c->verdict == FB_VERDICT_PASS && c->has_hardwarn && c->max_abs > c->hardwarn)
        c->verdict = FB_VERDICT_WARN,
        snprintf(c->why, sizeof c->why, "max |A - B| %g beyond --hardwarn %g", c->max_abs, c->hardwarn);
}

static void channel_lines(const cmp *k, const chan_stats *c)
{
    const fb_compare_desc *d = k->d;
    char where[64] = "", ss[32] = "";
    if (c->max_x >= 0) snprintf(where, sizeof where, " at pixel (%d, %d)", c->max_x, c->max_y);
    if (c->has_ssim) snprintf(ss, sizeof ss, "  ssim %.6f", c->ssim_v);
    say(d, "%-16s max_abs %.6g%s  rmse %.6g  psnr %s%.2f dB  beyond %.4f%% (%llu px)%s  %s", c->name, c->max_abs, where,
        c->rmse, c->psnr > 0 && isinf(c->psnr) ? "+" : "", c->psnr, c->pct, (unsigned long long)c->beyond, ss,
        c->verdict == FB_VERDICT_PASS   ? "ok"
        : c->verdict == FB_VERDICT_WARN ? "WARN"
                                        : "FAIL");
    if (c->verdict != FB_VERDICT_PASS) say(d, "%-16s %s", "", c->why);
    if (c->nonfinite_mismatch || c->nonfinite_same)
        say(d,
            "%-16s non-finite pixels: %llu differ between the files (each a failing pixel; RMSE, PSNR and SSIM "
            "at their worst), %llu identical in both",
            "", (unsigned long long)c->nonfinite_mismatch, (unsigned long long)c->nonfinite_same);
    if (c->n && c->a_lo == 0 && c->a_hi == 0) say(d, "%-16s all-zero in %s", "", d->a);
}

static void flip_verdict(cmp *k, flip_unit *u)
{
    const fb_compare_desc *d = k->d;
    double v = flip_stat(u, d->flip_stat);
    const char *stat = FLIP_STATS[d->flip_stat];
    u->verdict = FB_VERDICT_PASS;
    if (u->has_fail && v > u->limit_fail) {
        u->verdict = FB_VERDICT_FAIL;
        snprintf(u->why, sizeof u->why, "FLIP %s %.6f beyond --flip-fail %g", stat, v, u->limit_fail);
    } else if (u->has_warn && v > u->limit_warn) {
        u->verdict = FB_VERDICT_WARN;
        snprintf(u->why, sizeof u->why, "FLIP %s %.6f beyond --flip-warn %g", stat, v, u->limit_warn);
    }
    char ex[96] = "";
    if (u->hdr)
        snprintf(ex, sizeof ex, "  exposures %.4f..%.4f (%d)%s", u->r.start_exposure, u->r.stop_exposure, u->r.nexp,
                 u->r.zero_median ? " from the positive luminances' median" : "");
    say(d, "%-16s FLIP %s%s  mean %.6f  weighted median %.6f  quartiles %.6f %.6f  max %.6f%s  %s", u->name,
        u->hdr ? "HDR" : "LDR", u->grey ? " (Y)" : "", u->r.mean, u->r.median, u->r.q1, u->r.q3, u->r.max, ex,
        u->verdict == FB_VERDICT_PASS   ? "ok"
        : u->verdict == FB_VERDICT_WARN ? "WARN"
                                        : "FAIL");
    if (u->verdict != FB_VERDICT_PASS) say(d, "%-16s %s", "", u->why);
    if (u->nonfinite)
        say(d, "%-16s %llu pixels non-finite in one file only: FLIP error 1", "", (unsigned long long)u->nonfinite);
}

static double idiff_rms(const cmp *k)
{
    return k->i_nvals ? sqrt(k->i_sq / (double)k->i_nvals) : 0;
}

/* --idiff-stats: idiff's block, its numbers by its definitions. */
static void idiff_lines(const cmp *k)
{
    const fb_compare_desc *d = k->d;
    double npels = (double)k->W * k->H, rms = idiff_rms(k);
    say(d, "idiff statistics over the %d compared channels:", k->nst);
    say(d, "  Mean error = %.6g", k->i_nvals ? k->i_sum / (double)k->i_nvals : 0);
    say(d, "  RMS error = %.6g", rms);
    say(d, "  Peak SNR = %.6g", rms > 0 ? 20 * log10(k->i_peak / rms) : INFINITY);
    say(d, "  Max error  = %.6g @ (%d, %d, %s)", k->i_max, k->i_mx, k->i_my, k->i_mc ? k->i_mc : "-");
    say(d, "  %llu pixels (%.3g%%) over %g", (unsigned long long)k->i_nwarn, npels ? 100 * k->i_nwarn / npels : 0,
        k->i_warn);
    say(d, "  %llu pixels (%.3g%%) over %g", (unsigned long long)k->i_nfail, npels ? 100 * k->i_nfail / npels : 0,
        k->i_fail);
}

static json_t *idiff_json(const cmp *k)
{
    double npels = (double)k->W * k->H, rms = idiff_rms(k);
    json_t *j = json_object();
    json_object_set_new(j, "mean_error", json_real(k->i_nvals ? k->i_sum / (double)k->i_nvals : 0));
    json_object_set_new(j, "rms_error", json_real(rms));
    json_object_set_new(j, "peak_snr", json_num(rms > 0 ? 20 * log10(k->i_peak / rms) : INFINITY));
    json_object_set_new(j, "peak", json_real(k->i_peak));
    json_object_set_new(j, "max_error", json_real(k->i_max));
    if (k->i_mc) json_object_set_new(j, "max_at", json_pack("[iis]", k->i_mx, k->i_my, k->i_mc));
    json_object_set_new(j, "warn_pixels", json_integer((json_int_t)k->i_nwarn));
    json_object_set_new(j, "warn_percent", json_real(npels ? 100 * k->i_nwarn / npels : 0));
    json_object_set_new(j, "warn_threshold", json_real(k->i_warn));
    json_object_set_new(j, "fail_pixels", json_integer((json_int_t)k->i_nfail));
    json_object_set_new(j, "fail_percent", json_real(npels ? 100 * k->i_nfail / npels : 0));
    json_object_set_new(j, "fail_threshold", json_real(k->i_fail));
    return j;
}

/* The verdicts; the reason: the first channel (or FLIP layer) with the worst one. */
static void verdicts(cmp *k)
{
    char worst[200] = "";
    fb_verdict v = FB_VERDICT_PASS;
    for (int s = 0; s < k->nst; s++) {
        chan_stats *c = &k->st[s];
        channel_verdict(k, c);
        channel_lines(k, c);
        if (c->verdict > v) v = c->verdict, snprintf(worst, sizeof worst, "%s: %s", c->name, c->why);
    }
    for (int u = 0; u < k->nfu; u++) {
        flip_verdict(k, &k->fu[u]);
        if (k->fu[u].verdict > v)
            v = k->fu[u].verdict, snprintf(worst, sizeof worst, "%s: %s", k->fu[u].name, k->fu[u].why);
    }
    if (v > k->verdict) k->verdict = v;
    if (!k->reason[0]) snprintf(k->reason, sizeof k->reason, "%s", worst);
    if (k->over) idiff_lines(k);
}

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

/* Reads channels idx[0..n) of the layer whole from A and B (as doubles). */
static fb_result read_layer(cmp *k, const int *idx, int n, double **va, double **vb)
{
    size_t np = (size_t)k->W * k->H;
    fb_result rc = FB_OK;
    int na = image_nchannels(&k->A), nb = image_nchannels(&k->B);
    void **pa = calloc((size_t)na, sizeof *pa), **pb = calloc((size_t)nb, sizeof *pb);
    if (!pa || !pb) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the report");
    for (int q = 0; q < n && !rc; q++) {
        const chan_stats *c = &k->st[idx[q]];
        if (!(pa[c->ia] = malloc(np * 4)) || !(pb[c->ib] = malloc(np * 4)) || !(va[q] = malloc(np * 8)) ||
            !(vb[q] = malloc(np * 8)))
            rc = fb_fail(FB_ERR_NOMEM, "out of memory for the report");
    }
    if (!rc) rc = image_read_rows(&k->A, 0, k->H, pa);
    if (!rc) rc = image_read_rows(&k->B, 0, k->H, pb);
    for (int q = 0; q < n && !rc; q++) {
        const chan_stats *c = &k->st[idx[q]];
        for (size_t i = 0; i < np; i++)
            va[q][i] = value(pa[c->ia], c->uint_a, i), vb[q][i] = value(pb[c->ib], c->uint_b, i);
    }
    for (int q = 0; q < n && pa && pb; q++) free(pa[k->st[idx[q]].ia]), free(pb[k->st[idx[q]].ib]);
    free(pa);
    free(pb);
    return rc;
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
        heat(heat_t(m), c);
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

static fb_result write_html(cmp *k)
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

static fb_result write_junit(cmp *k, double seconds)
{
    fb_junit_case *cs = calloc((size_t)(k->nst * 7 + k->nfu * 2 + 1), sizeof *cs);
    if (!cs) return fb_fail(FB_ERR_NOMEM, "out of memory for the JUnit report");
    int n = 0;
    for (int q = 0; q < k->nst; q++) {
        const chan_stats *c = &k->st[q];
        bool allowed = (long long)c->beyond <= k->d->allowfailures && c->nonfinite_mismatch == 0;
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
        const char *stat = FLIP_STATS[k->d->flip_stat];
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

static void cmp_free(cmp *k)
{
    for (int q = 0; q < 3; q++) free(k->pic[q]);
    fb_preview_destroy(&k->png);
    exrio_writer_abort(&k->diff);
    for (int s = 0; s < k->nst; s++) {
        free(k->pa[k->st[s].ia]);
        free(k->pb[k->st[s].ib]);
        if (k->pd) free(k->pd[s]);
        ssim_fini(&k->st[s].ssim);
        free(k->st[s].ra);
        free(k->st[s].rb);
    }
    for (int u = 0; u < k->nfu; u++) free(k->fu[u].map);
    json_decref(k->missing);
    free(k->fu);
    free(k->over);
    free(k->dnames);
    free(k->pd);
    free(k->dch);
    free(k->pa);
    free(k->pb);
    free(k->st);
    if (k->a_open) image_close(&k->A);
    if (k->b_open) image_close(&k->B);
}

fb_result fb_compare(const fb_compare_desc *d, fb_verdict *verdict)
{
    if (!strcmp(d->a, "-") && !strcmp(d->b, "-"))
        return fb_fail(FB_ERR_USAGE, "compare - -: standard input can be read once; give one of the files by name");
    cmp k = {.d = d, .missing = json_array(), .verdict = FB_VERDICT_PASS};
    fb_result rc = FB_OK;
    /* every named output is checked (and its temporary file made) before the work, whatever the files hold */
    if (d->diff) rc = fb_output_reserve(d->diff, "diff");
    if (!rc && d->diff_png) rc = fb_output_reserve(d->diff_png, "diff picture");
    if (!rc && d->flip_png) rc = fb_output_reserve(d->flip_png, "FLIP picture");
    if (!rc && d->report) rc = fb_output_reserve(d->report, "HTML report");
    if (!rc && d->junit) rc = fb_output_reserve(d->junit, "JUnit report");
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (!rc) rc = open_both(&k);
    if (!rc && k.verdict == FB_VERDICT_PASS) rc = match_channels(&k);
    if (!rc && k.nst > 0) rc = find_flip_units(&k);
    if (!rc && k.nst > 0) rc = check_rules(&k);
    if (!rc && k.nst > 0) rc = compute_flip(&k);
    if (!rc && k.nst > 0) rc = open_outputs(&k);
    if (!rc && k.nst > 0) rc = stream_blocks(&k);
    if (!rc) verdicts(&k);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (!rc && d->report) rc = write_html(&k);
    if (!rc && d->junit)
        rc = write_junit(&k, (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    if (!rc) { /* nothing to write when nothing was compared: the reservations go */
        if (d->diff && !k.dch) fb_output_discard(d->diff);
        if (d->diff_png && !k.pic[0]) fb_output_discard(d->diff_png);
        if (d->flip_png && k.nfu == 0) fb_output_discard(d->flip_png);
        report(&k);
    }
    *verdict = k.verdict;
    cmp_free(&k);
    return rc;
}
