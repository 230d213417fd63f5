/* compare's FLIP per layer (compare_int.h): the units, their maps, the picture, the verdicts. */
#include "compare_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const CMP_FLIP_STATS[5] = {"mean", "median", "q1", "q3", "max"};

/* The FLIP units among the compared channels: per layer, R G B, or else Y. */
fb_result cmp_find_flip_units(cmp *k)
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

/* A unit's planes: the whole planes, or when a value is not finite in either file a copy with
 * those values 0 for the filters, and the pixels where the files disagree marked bad (error 1). */
static fb_result flip_planes(cmp *k, flip_unit *u, const float *pa[3], const float *pb[3])
{
    size_t n = (size_t)k->W * k->H;
    int nq = u->grey ? 1 : 3;
    bool finite = true;
    for (int q = 0; q < 3; q++) {
        pa[q] = k->pa[k->st[u->ch[q]].ia], pb[q] = k->pb[k->st[u->ch[q]].ib];
        for (size_t i = 0; i < n && finite && q < nq; i++) finite = isfinite(pa[q][i]) && isfinite(pb[q][i]);
    }
    if (finite) return FB_OK;
    if (!(u->own = malloc(n * 2 * (size_t)nq * sizeof(float))) || !(u->bad = calloc(n ? n : 1, 1)))
        return fb_fail(FB_ERR_NOMEM, "out of memory for FLIP of %s (%d x %d)", u->name, k->W, k->H);
    for (int q = 0; q < nq; q++) {
        float *x = u->own + (size_t)(2 * q) * n, *y = x + n;
        for (size_t i = 0; i < n; i++) {
            float va = pa[q][i], vb = pb[q][i];
            if (!isfinite(va) || !isfinite(vb)) {
                if (!((isnan(va) && isnan(vb)) || va == vb)) u->bad[i] = 1;
                va = isfinite(va) ? va : 0, vb = isfinite(vb) ? vb : 0;
            }
            x[i] = va, y[i] = vb;
        }
    }
    for (int q = 0; q < 3; q++) pa[q] = u->own + (size_t)(2 * (u->grey ? 0 : q)) * n, pb[q] = pa[q] + n;
    return FB_OK;
}

/* One unit's job: its planes, its map, its exposures (a task per unit). */
static void flip_prepare_task(void *ctx, int t)
{
    cmp *k = ctx;
    flip_unit *u = &k->fu[t];
    const float *pa[3], *pb[3];
    size_t n = (size_t)k->W * k->H;
    u->rc = flip_planes(k, u, pa, pb);
    if (!u->rc && !(u->map = fb_malloc_large((n ? n : 1) * sizeof(float))))
        u->rc = fb_fail(FB_ERR_NOMEM, "out of memory for FLIP of %s (%d x %d)", u->name, k->W, k->H);
    if (!u->rc) u->rc = fb_flip_job_create(pa, pb, k->W, k->H, u->hdr, fb_flip_default_ppd(), u->map, &u->job);
}

/* Every unit's bands, as one list of tasks. */
static void flip_band_task(void *ctx, int t)
{
    cmp *k = ctx;
    for (int u = 0; u < k->nfu; u++) {
        int nb = k->fu[u].job ? fb_flip_job_bands(k->fu[u].job) : 0;
        if (t < nb) {
            fb_flip_job_band(k->fu[u].job, t);
            return;
        }
        t -= nb;
    }
}

/* A unit's statistics, its bad pixels at error 1 included (a task per unit). */
static void flip_finish_task(void *ctx, int t)
{
    cmp *k = ctx;
    flip_unit *u = &k->fu[t];
    size_t n = (size_t)k->W * k->H;
    if (!u->job) return;
    fb_result rc = fb_flip_job_finish(&u->job, &u->r);
    for (size_t i = 0; i < n && !rc && u->bad; i++)
        if (u->bad[i]) u->map[i] = 1.0f, u->nonfinite++;
    if (!rc && u->nonfinite) {
        fb_flip_result keep = u->r;
        rc = fb_flip_pool(u->map, n, &u->r);
        u->r.start_exposure = keep.start_exposure, u->r.stop_exposure = keep.stop_exposure;
        u->r.nexp = keep.nexp, u->r.zero_median = keep.zero_median;
    }
    if (!u->rc) u->rc = rc;
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
    if (!rc) cmp_say(k->d, "%-16s %s: the FLIP error of %s, black 0, white 1", "", k->d->flip_png, k->fu[best].name);
    return rc;
}

/* Every unit's FLIP on the threads: the jobs, every band of every unit, the statistics. */
fb_result cmp_compute_flip(cmp *k)
{
    if (k->nfu == 0) return FB_OK;
    fb_pool_run(k->pool, k->nfu, flip_prepare_task, k);
    int bands = 0;
    for (int u = 0; u < k->nfu; u++) bands += k->fu[u].job ? fb_flip_job_bands(k->fu[u].job) : 0;
    fb_pool_run(k->pool, bands, flip_band_task, k);
    fb_pool_run(k->pool, k->nfu, flip_finish_task, k);
    for (int u = 0; u < k->nfu; u++)
        if (k->fu[u].rc) return k->fu[u].rc;
    return write_flip_png(k);
}

void cmp_flip_verdict(cmp *k, flip_unit *u)
{
    const fb_compare_desc *d = k->d;
    double v = cmp_flip_stat(u, d->flip_stat);
    const char *stat = CMP_FLIP_STATS[d->flip_stat];
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
    cmp_say(d, "%-16s FLIP %s%s  mean %.6f  weighted median %.6f  quartiles %.6f %.6f  max %.6f%s  %s", u->name,
            u->hdr ? "HDR" : "LDR", u->grey ? " (Y)" : "", u->r.mean, u->r.median, u->r.q1, u->r.q3, u->r.max, ex,
            u->verdict == FB_VERDICT_PASS   ? "ok"
            : u->verdict == FB_VERDICT_WARN ? "WARN"
                                            : "FAIL");
    if (u->verdict != FB_VERDICT_PASS) cmp_say(d, "%-16s %s", "", u->why);
    if (u->nonfinite)
        cmp_say(d, "%-16s %llu pixels non-finite in one file only: FLIP error 1", "", (unsigned long long)u->nonfinite);
}
