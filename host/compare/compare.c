/*
 * `fractalbake compare`: two EXR (or PNG) files, channel by channel, streaming in blocks of rows.
 *
 * compare speaks idiff's vocabulary (OpenImageIO's image comparison): a pixel fails beyond --fail
 * (our --max-abs), a channel fails when more than --failpercent of its pixels do or any is beyond
 * --hardfail, and the same for warnings. It adds RMSE, PSNR and SSIM (Wang, Bovik, Sheikh and
 * Simoncelli, "Image quality assessment: from error visibility to structural similarity", IEEE
 * Transactions on Image Processing 13(4), 2004) as thresholds, per channel or layer.
 */
#include "compare_int.h"
#include "output.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static bool in_layer(const char *name, const char *layer)
{
    if (!layer) return true;
    size_t n = strlen(layer);
    return !strncmp(name, layer, n) && name[n] == '.';
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
        cmp_say(d, "%s", k->reason);
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
        cmp_say(d, "%s", k->reason);
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
            cmp_say(d, "%s: only in %s", name, x->path);
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
        cmp_thresholds(d, c);
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

/* The verdicts; the reason: the first channel (or FLIP layer) with the worst one. */
static void verdicts(cmp *k)
{
    char worst[200] = "";
    fb_verdict v = FB_VERDICT_PASS;
    for (int s = 0; s < k->nst; s++) {
        chan_stats *c = &k->st[s];
        cmp_channel_verdict(k, c);
        cmp_channel_lines(k, c);
        if (c->verdict > v) v = c->verdict, snprintf(worst, sizeof worst, "%s: %s", c->name, c->why);
    }
    for (int u = 0; u < k->nfu; u++) {
        cmp_flip_verdict(k, &k->fu[u]);
        if (k->fu[u].verdict > v)
            v = k->fu[u].verdict, snprintf(worst, sizeof worst, "%s: %s", k->fu[u].name, k->fu[u].why);
    }
    if (v > k->verdict) k->verdict = v;
    if (!k->reason[0]) snprintf(k->reason, sizeof k->reason, "%s", worst);
    if (k->over) cmp_idiff_lines(k);
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
        free(k->st[s].over);
    }
    for (int u = 0; u < k->nfu; u++) free(k->fu[u].map), free(k->fu[u].own), free(k->fu[u].bad);
    fb_pool_destroy(&k->pool);
    free(k->ba);
    free(k->bb);
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
    if (!rc && k.nst > 0) rc = cmp_find_flip_units(&k);
    if (!rc && k.nst > 0) rc = cmp_check_rules(&k);
    if (!rc && k.nst > 0) rc = fb_pool_create(d->threads > 0 ? d->threads : fb_cpu_count(), &k.pool);
    if (!rc && k.nst > 0 && (d->flip || d->report)) rc = cmp_read_whole(&k);
    if (!rc && k.nst > 0) rc = cmp_compute_flip(&k);
    if (!rc && k.nst > 0) rc = open_outputs(&k);
    if (!rc && k.nst > 0) rc = cmp_stream_blocks(&k);
    if (!rc) verdicts(&k);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (!rc && d->report) rc = cmp_write_html(&k);
    if (!rc && d->junit)
        rc = cmp_write_junit(&k, (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    if (!rc) { /* nothing to write when nothing was compared: the reservations go */
        if (d->diff && !k.dch) fb_output_discard(d->diff);
        if (d->diff_png && !k.pic[0]) fb_output_discard(d->diff_png);
        if (d->flip_png && k.nfu == 0) fb_output_discard(d->flip_png);
        cmp_print_result(&k);
    }
    *verdict = k.verdict;
    cmp_free(&k);
    return rc;
}
