/*
 * `fractalbake compare` and `fractalbake info`: EXR consumers, streaming in blocks of rows.
 */
#include "compare.h"

#include "exrio.h"
#include "preview.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BLOCK_ROWS 64 /* a multiple of every scanline chunk height we read (1, 16, 32) */

typedef struct chan_stats {
    int ia, ib; /* channel index in A and B */
    bool uint_a, uint_b;
    double max_abs;
    int max_x, max_y;
    double sum_sq;
    uint64_t n; /* finite pairs */
    uint64_t beyond;
    uint64_t nonfinite_mismatch; /* NaN/Inf in one file and not the same in the other */
    uint64_t nonfinite_same;
    double a_lo, a_hi;
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
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    d->print(buf, d->user);
}

fb_result fb_compare(const fb_compare_desc *d, bool *pass)
{
    fb_result rc = FB_OK;
    exrio_reader *a = NULL, *b = NULL;
    exrio_writer *diff = NULL;
    fb_preview *png = NULL;
    chan_stats *st = NULL;
    void **pa = NULL, **pb = NULL;
    float **pd = NULL;
    exrio_channel *dch = NULL;
    int nst = 0;
    *pass = true;

    if ((rc = exrio_open(d->a, &a)) || (rc = exrio_open(d->b, &b))) goto out;
    int W = exrio_width(a), H = exrio_height(a);
    if (W != exrio_width(b) || H != exrio_height(b)) {
        say(d, "size differs: %s is %d x %d, %s is %d x %d", d->a, W, H, d->b, exrio_width(b), exrio_height(b));
        *pass = false;
        goto out;
    }
    int wa[4], wb[4];
    exrio_window(a, &wa[0], &wa[1], &wa[2], &wa[3]);
    exrio_window(b, &wb[0], &wb[1], &wb[2], &wb[3]);
    if (memcmp(wa, wb, sizeof wa)) {
        say(d, "region differs: %s holds %d,%d,%d,%d of %d x %d, %s holds %d,%d,%d,%d of %d x %d", d->a, wa[0], wa[1],
            W, H, wa[2], wa[3], d->b, wb[0], wb[1], W, H, wb[2], wb[3]);
        *pass = false;
        goto out;
    }
    int na = exrio_nchannels(a), nb = exrio_nchannels(b);
    st = calloc((size_t)na + 1, sizeof *st);
    pa = calloc((size_t)na + 1, sizeof *pa);
    pb = calloc((size_t)nb + 1, sizeof *pb);
    if (!st || !pa || !pb) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto out;
    }
    int missing = 0;
    for (int i = 0; i < na; i++) {
        const char *name = exrio_channel_name(a, i);
        if (!in_layer(name, d->layer)) continue;
        int j = exrio_find_channel(b, name);
        if (j < 0) {
            say(d, "%s: only in %s", name, d->a);
            missing++;
            continue;
        }
        st[nst] = (chan_stats){.ia = i, .ib = j, .a_lo = INFINITY, .a_hi = -INFINITY, .max_x = -1, .max_y = -1};
        st[nst].uint_a = exrio_channel_type(a, i) == EXRIO_UINT;
        st[nst].uint_b = exrio_channel_type(b, j) == EXRIO_UINT;
        nst++;
    }
    for (int j = 0; j < nb; j++) {
        const char *name = exrio_channel_name(b, j);
        if (in_layer(name, d->layer) && exrio_find_channel(a, name) < 0) {
            say(d, "%s: only in %s", name, d->b);
            missing++;
        }
    }
    if (d->layer && nst == 0 && missing == 0) {
        rc = fb_fail(FB_ERR_USAGE, "--layer: no channel %s.* in either file", d->layer);
        goto out;
    }
    if (missing && !d->ignore_missing) *pass = false;

    size_t block = (size_t)W * BLOCK_ROWS;
    for (int s = 0; s < nst; s++) {
        if (!(pa[st[s].ia] = malloc(block * 4)) || !(pb[st[s].ib] = malloc(block * 4))) {
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            goto out;
        }
    }
    if (d->diff && nst > 0) {
        dch = calloc((size_t)nst, sizeof *dch);
        pd = calloc((size_t)nst, sizeof *pd);
        if (!dch || !pd) {
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            goto out;
        }
        for (int s = 0; s < nst; s++) {
            dch[s] = (exrio_channel){exrio_channel_name(a, st[s].ia), EXRIO_FLOAT};
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

    double tol = d->has_max_abs ? d->max_abs : 0.0;
    float *pic[3] = {NULL, NULL, NULL};
    if (d->diff_png && nst > 0) {
        if ((rc = fb_preview_create(W, H, 2048, 3, &png))) goto out;
        for (int k = 0; k < 3; k++)
            if (!(pic[k] = malloc(block * 4))) {
                rc = fb_fail(FB_ERR_NOMEM, "out of memory");
                goto out_pic;
            }
    }
    for (int y0 = 0; y0 < H; y0 += BLOCK_ROWS) {
        int n = y0 + BLOCK_ROWS <= H ? BLOCK_ROWS : H - y0;
        if ((rc = exrio_read_rows(a, y0, n, pa)) || (rc = exrio_read_rows(b, y0, n, pb))) goto out_pic;
        if (png) { /* the background: A's first compared channel, grey over its block range, dimmed */
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
        }
        for (int s = 0; s < nst; s++) {
            chan_stats *c = &st[s];
            const void *A = pa[c->ia], *B = pb[c->ib];
            for (size_t i = 0; i < (size_t)W * n; i++) {
                double va = value(A, c->uint_a, i), vb = value(B, c->uint_b, i);
                double ad;
                if (!isfinite(va) || !isfinite(vb)) {
                    bool same = (isnan(va) && isnan(vb)) || va == vb;
                    if (same) {
                        c->nonfinite_same++;
                        ad = 0;
                    } else {
                        c->nonfinite_mismatch++;
                        c->beyond++;
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
                    if (ad > tol) c->beyond++;
                }
                if (pd) pd[s][i] = (float)ad;
                if (png && ad > tol) pic[0][i] = 1.0f, pic[1][i] = pic[2][i] = 0.0f;
            }
        }
        if (png) fb_preview_add_rows(png, y0, n, (const float *const *)pic);
        if (diff && (rc = exrio_writer_rows(diff, y0, n, (const void *const *)pd))) goto out_pic;
    }
    if (png) rc = fb_preview_write_png(png, d->diff_png, "diff picture");
out_pic:
    for (int k = 0; k < 3; k++) free(pic[k]);
    if (rc) goto out;

    uint64_t total = (uint64_t)W * H;
    for (int s = 0; s < nst; s++) {
        chan_stats *c = &st[s];
        double rmse = c->n ? sqrt(c->sum_sq / (double)c->n) : 0;
        double peak = c->a_hi > c->a_lo ? c->a_hi - c->a_lo : (c->a_hi > 0 ? c->a_hi : 1.0);
        double psnr = rmse > 0 ? 20 * log10(peak / rmse) : INFINITY;
        double pct = total ? 100.0 * (double)c->beyond / (double)total : 0;
        bool ok = true;
        if (d->has_fail_percent)
            ok = ok && pct <= d->fail_percent;
        else if (d->has_max_abs || (!d->has_rmse && !d->has_psnr))
            ok = ok && c->beyond == 0;
        if (d->has_rmse) ok = ok && rmse <= d->rmse;
        if (d->has_psnr) ok = ok && psnr >= d->psnr;
        if (!d->has_fail_percent) ok = ok && c->nonfinite_mismatch == 0;
        *pass = *pass && ok;
        char where[64] = "";
        if (c->max_x >= 0) snprintf(where, sizeof where, " at pixel (%d, %d)", c->max_x, c->max_y);
        say(d, "%-16s max_abs %.6g%s  rmse %.6g  psnr %s%.2f dB  beyond %.4f%% (%llu px)%s  %s",
            exrio_channel_name(a, c->ia), c->max_abs, where, rmse, isinf(psnr) ? "+" : "",
            isinf(psnr) ? INFINITY : psnr, pct, (unsigned long long)c->beyond, "", ok ? "ok" : "FAIL");
        if (c->nonfinite_mismatch || c->nonfinite_same)
            say(d, "%-16s non-finite pixels: %llu differ between the files, %llu identical in both", "",
                (unsigned long long)c->nonfinite_mismatch, (unsigned long long)c->nonfinite_same);
        if (c->n && c->a_lo == 0 && c->a_hi == 0) say(d, "%-16s all-zero in %s", "", d->a);
    }
    if (diff) rc = exrio_writer_finish(&diff);
out:
    fb_preview_destroy(&png);
    exrio_writer_abort(&diff);
    if (st)
        for (int s = 0; s < nst; s++) {
            free(pa[st[s].ia]);
            free(pb[st[s].ib]);
            if (pd) free(pd[s]);
        }
    free(pd);
    free(dch);
    free(pa);
    free(pb);
    free(st);
    exrio_close(&a);
    exrio_close(&b);
    return rc;
}

fb_result fb_info(const char *path, void (*print)(const char *line, void *user), void *user)
{
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    char line[1024];
#define P(...)                                                                                                         \
    do {                                                                                                               \
        snprintf(line, sizeof line, __VA_ARGS__);                                                                      \
        print(line, user);                                                                                             \
    } while (0)
    P("file:        %s", path);
    int win[4];
    exrio_window(r, &win[0], &win[1], &win[2], &win[3]);
    if (win[0] || win[1] || win[2] != exrio_width(r) || win[3] != exrio_height(r))
        P("size:        %d x %d: the region %d,%d,%d,%d of a %d x %d image", exrio_width(r), exrio_height(r), win[0],
          win[1], exrio_width(r), exrio_height(r), win[2], win[3]);
    else
        P("size:        %d x %d", exrio_width(r), exrio_height(r));
    if (exrio_nparts(r) > 1) {
        P("parts:       %d", exrio_nparts(r));
        for (int p = 0; p < exrio_nparts(r); p++)
            P("  part %-2d %-12s compression %s", p, exrio_part_name(r, p), exrio_part_compression(r, p));
    } else {
        P("compression: %s", exrio_compression_of(r));
    }
    P("channels:    %d", exrio_nchannels(r));
    /* Group channels by layer (the text before the last dot). */
    for (int c = 0; c < exrio_nchannels(r); c++) {
        const char *name = exrio_channel_name(r, c);
        const char *dot = strrchr(name, '.');
        int llen = dot ? (int)(dot - name) : 0;
        bool first = true;
        for (int k = 0; k < c && first; k++) {
            const char *o = exrio_channel_name(r, k), *od = strrchr(o, '.');
            int olen = od ? (int)(od - o) : 0;
            first = !(olen == llen && !strncmp(o, name, (size_t)llen));
        }
        if (!first) continue;
        char chans[512] = "";
        for (int k = c; k < exrio_nchannels(r); k++) {
            const char *o = exrio_channel_name(r, k), *od = strrchr(o, '.');
            int olen = od ? (int)(od - o) : 0;
            if (olen == llen && !strncmp(o, name, (size_t)llen))
                snprintf(chans + strlen(chans), sizeof chans - strlen(chans), "%s%s (%s)", chans[0] ? ", " : "",
                         od ? od + 1 : o, exrio_type_name(exrio_channel_type(r, k)));
        }
        P("  layer %-10.*s %s", llen ? llen : 9, llen ? name : "(no layer)", chans);
    }
    P("attributes:");
    for (int i = 0; i < exrio_attr_count(r); i++) {
        const char *name, *type;
        exrio_attr_at(r, i, &name, &type);
        const char *sv = !strcmp(type, "string") ? exrio_attr_string(r, name) : NULL;
        if (sv && !strcmp(name, "fractalbake/scene")) continue;
        if (sv)
            P("  %-22s %-8s %s", name, type, sv);
        else
            P("  %-22s %s", name, type);
    }
    const char *scene = exrio_attr_string(r, "fractalbake/scene");
    if (scene) {
        P("stored scene:");
        print(scene, user);
    } else {
        P("stored scene: none (not written by fractalbake)");
    }
#undef P
    exrio_close(&r);
    return FB_OK;
}
