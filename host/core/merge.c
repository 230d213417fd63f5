/*
 * fractalbake merge: joins region files (render --region) into the whole image. See merge.h.
 *
 * The parts must be regions of one image: the same display window, the same channels with the same
 * types, and, when they carry one, the same stored scene. Together they must cover the image with
 * no overlap. The output is written strip by strip (bounded memory): for each strip, every part
 * that crosses it is decoded for those rows and copied into place. Rows pass through as 4-byte
 * values, so half channels round-trip exactly and the merged pixels are the full bake's.
 */
#include "merge.h"
#include "textin.h"

#include "exrio.h"
#include "engine.h"
#include "plan.h"
#include "scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MERGE_STRIP 64

typedef struct part {
    exrio_reader *r;
    int x0, y0, w, h;
    void *planes[FB_MERGE_MAX_CHANNELS]; /* MERGE_STRIP rows of the part, in the output's channel order */
} part;

/* The attributes a fractalbake file carries, in the order bake writes them (so that a merged file
 * is byte for byte the whole-image bake, whatever backend ran each layer); the region attribute is
 * left out. */
static const char *const k_attrs[] = {"fractalbake/scene",  "fractalbake/seed",    "fractalbake/backend",
                                      "fractalbake/device", "fractalbake/version", "fractalbake/layer-backends"};

/* The merged file, W x H: the channels given, the EXR parts (names, compressions) and the fractalbake
 * attributes of the first input. */
static fb_result open_output(const exrio_reader *first, const char *out, int W, int H, const exrio_channel *ch, int nch,
                             int threads, int zip_level, exrio_writer **w)
{
    exrio_attr attrs[sizeof k_attrs / sizeof k_attrs[0]];
    int nattrs = 0;
    for (size_t a = 0; a < sizeof k_attrs / sizeof k_attrs[0]; a++) {
        const char *v = exrio_attr_string(first, k_attrs[a]);
        if (v) attrs[nattrs++] = (exrio_attr){k_attrs[a], v};
    }
    int nparts = exrio_nparts(first);
    const char *part_names[EXRIO_MAX_PARTS];
    exrio_compression part_comp[EXRIO_MAX_PARTS];
    for (int k = 0; k < nparts; k++) {
        int c = exrio_compression_parse(exrio_part_compression(first, k));
        part_names[k] = exrio_part_name(first, k);
        part_comp[k] = c < 0 ? EXRIO_ZIP : (exrio_compression)c;
    }
    return exrio_writer_create(&(exrio_writer_desc){.path = out,
                                                    .width = W,
                                                    .height = H,
                                                    .compression = part_comp[0],
                                                    .channels = ch,
                                                    .nchannels = nch,
                                                    .attrs = attrs,
                                                    .nattrs = nattrs,
                                                    .threads = threads,
                                                    .zip_level = zip_level,
                                                    .nparts = nparts,
                                                    .part_names = part_names,
                                                    .part_compression = part_comp,
                                                    .envmap = exrio_envmap_of(first)},
                               w);
}

static fb_result check_parts(part *p, int n, const char *const *paths, int *W, int *H)
{
    int fw, fh, x, y;
    exrio_window(p[0].r, &x, &y, &fw, &fh);
    const char *scene0 = exrio_attr_string(p[0].r, "fractalbake/scene");
    uint64_t area = 0;
    for (int i = 0; i < n; i++) {
        int pw, ph;
        exrio_window(p[i].r, &p[i].x0, &p[i].y0, &pw, &ph);
        p[i].w = exrio_width(p[i].r);
        p[i].h = exrio_height(p[i].r);
        if (pw != fw || ph != fh)
            return fb_fail(FB_ERR_INPUT, "%s: a region of a %d x %d image, but %s is of a %d x %d image", paths[i], pw,
                           ph, paths[0], fw, fh);
        if (p[i].x0 < 0 || p[i].y0 < 0 || p[i].x0 + p[i].w > fw || p[i].y0 + p[i].h > fh)
            return fb_fail(FB_ERR_INPUT, "%s: its data window reaches outside the %d x %d image", paths[i], fw, fh);
        if (exrio_nchannels(p[i].r) != exrio_nchannels(p[0].r))
            return fb_fail(FB_ERR_INPUT, "%s: %d channels, but %s has %d", paths[i], exrio_nchannels(p[i].r), paths[0],
                           exrio_nchannels(p[0].r));
        for (int c = 0; c < exrio_nchannels(p[0].r); c++) {
            int k = exrio_find_channel(p[i].r, exrio_channel_name(p[0].r, c));
            if (k < 0 || exrio_channel_type(p[i].r, k) != exrio_channel_type(p[0].r, c))
                return fb_fail(FB_ERR_INPUT, "%s: channel %s is %s, unlike in %s", paths[i],
                               exrio_channel_name(p[0].r, c), k < 0 ? "missing" : "of another type", paths[0]);
        }
        bool same_parts = exrio_nparts(p[i].r) == exrio_nparts(p[0].r);
        for (int c = 0; c < exrio_nchannels(p[0].r) && same_parts; c++)
            same_parts = exrio_channel_part(p[i].r, c) == exrio_channel_part(p[0].r, c) &&
                         !strcmp(exrio_channel_name(p[i].r, c), exrio_channel_name(p[0].r, c));
        if (!same_parts) return fb_fail(FB_ERR_INPUT, "%s: its EXR parts differ from those of %s", paths[i], paths[0]);
        const char *scene = exrio_attr_string(p[i].r, "fractalbake/scene");
        if ((scene == NULL) != (scene0 == NULL) || (scene && strcmp(scene, scene0)))
            return fb_fail(FB_ERR_INPUT, "%s: baked from another scene than %s (attribute fractalbake/scene)", paths[i],
                           paths[0]);
        for (int j = 0; j < i; j++) {
            bool apart = p[i].x0 + p[i].w <= p[j].x0 || p[j].x0 + p[j].w <= p[i].x0 || p[i].y0 + p[i].h <= p[j].y0 ||
                         p[j].y0 + p[j].h <= p[i].y0;
            if (!apart)
                return fb_fail(FB_ERR_INPUT, "%s and %s overlap (regions %d,%d,%d,%d and %d,%d,%d,%d)", paths[j],
                               paths[i], p[j].x0, p[j].y0, p[j].w, p[j].h, p[i].x0, p[i].y0, p[i].w, p[i].h);
        }
        area += (uint64_t)p[i].w * p[i].h;
    }
    if (area != (uint64_t)fw * fh)
        return fb_fail(FB_ERR_INPUT, "the parts cover %llu of the %d x %d image's %llu pixels: a region is missing",
                       (unsigned long long)area, fw, fh, (unsigned long long)fw * fh);
    *W = fw;
    *H = fh;
    return FB_OK;
}

static fb_result merge_points(part *p, int n, const fb_merge_desc *d);

/* How many of the n files carry attribute `attr`: all or none, else an error ("3 of the 4 files are
 * WHAT"). */
static fb_result count_kind(const part *p, int n, const char *attr, const char *what, int *count)
{
    *count = 0;
    for (int i = 0; i < n; i++) *count += exrio_attr_string(p[i].r, attr) != NULL;
    if (*count > 0 && *count < n)
        return fb_fail(FB_ERR_INPUT, "merge: %d of the %d files are %s: merge one kind at a time", *count, n, what);
    return FB_OK;
}
static fb_result merge_tasks(part *p, int n, const fb_merge_desc *d);

/* --zip-level tunes zlib: refused where no part of the merged file (the first input's parts, as
 * open_output and the tasks' stored scene give them) is ZIP-compressed. */
static fb_result check_zip_level(const exrio_reader *first, const char *path, int level)
{
    for (int k = 0; k < exrio_nparts(first); k++) {
        int c = exrio_compression_parse(exrio_part_compression(first, k));
        if (c < 0 || c == EXRIO_ZIP) return FB_OK;
    }
    return fb_fail(FB_ERR_USAGE,
                   "--zip-level %d: no part of %s is ZIP-compressed (%s), nor is the merged file: the level would "
                   "change nothing",
                   level, path, exrio_part_compression(first, 0));
}

fb_result fb_merge(const fb_merge_desc *d)
{
    const char *const *paths = d->paths, *out = d->out;
    const int n = d->n, threads = d->threads, zip_level = d->zip_level;
    if (n < 1) return fb_fail(FB_ERR_USAGE, "merge: no parts given");
    fb_result rc = FB_OK;
    part *p = calloc((size_t)n, sizeof *p);
    void *full[FB_MERGE_MAX_CHANNELS] = {0};
    exrio_channel ch[FB_MERGE_MAX_CHANNELS];
    exrio_writer *w = NULL;
    int W = 0, H = 0, nch = 0;
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n && !rc; i++) rc = exrio_open(paths[i], &p[i].r);
    if (!rc && zip_level) rc = check_zip_level(p[0].r, paths[0], zip_level);
    int tasks = 0, points = 0;
    if (!rc) rc = count_kind(p, n, "fractalbake/task", "task files (render --task), the others not", &tasks);
    if (!rc && tasks) {
        rc = merge_tasks(p, n, d);
        goto out;
    }
    if (!rc)
        rc = count_kind(p, n, "fractalbake/points-part", "points parts (--points-part), the others regions", &points);
    if (!rc && points) {
        rc = merge_points(p, n, d);
        goto out;
    }
    if (!rc) rc = check_parts(p, n, paths, &W, &H);
    if (rc) goto out;
    nch = exrio_nchannels(p[0].r);
    if (nch > FB_MERGE_MAX_CHANNELS) {
        rc = fb_fail(FB_ERR_INPUT, "%s: %d channels; merge handles at most %d", paths[0], nch, FB_MERGE_MAX_CHANNELS);
        goto out;
    }
    for (int c = 0; c < nch; c++) {
        ch[c] = (exrio_channel){exrio_channel_name(p[0].r, c), exrio_channel_type(p[0].r, c),
                                exrio_channel_part(p[0].r, c)};
        if (!(full[c] = malloc((size_t)W * MERGE_STRIP * 4))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < n && !rc; i++)
        for (int c = 0; c < nch && !rc; c++)
            if (!(p[i].planes[c] = malloc((size_t)p[i].w * MERGE_STRIP * 4)))
                rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (rc) goto out;

    rc = open_output(p[0].r, out, W, H, ch, nch, threads, zip_level, &w);
    for (int y0 = 0; y0 < H && !rc; y0 += MERGE_STRIP) {
        int rows = y0 + MERGE_STRIP <= H ? MERGE_STRIP : H - y0;
        for (int i = 0; i < n && !rc; i++) {
            int from = y0 > p[i].y0 ? y0 : p[i].y0;
            int to = y0 + rows < p[i].y0 + p[i].h ? y0 + rows : p[i].y0 + p[i].h;
            if (from >= to) continue;
            /* exrio_read_rows fills planes in the part's own channel order */
            void *own[FB_MERGE_MAX_CHANNELS] = {0};
            for (int c = 0; c < nch; c++)
                own[exrio_find_channel(p[i].r, exrio_channel_name(p[0].r, c))] = p[i].planes[c];
            rc = exrio_read_rows(p[i].r, from - p[i].y0, to - from, own);
            for (int c = 0; c < nch && !rc; c++)
                for (int y = from; y < to; y++)
                    memcpy((uint8_t *)full[c] + ((size_t)(y - y0) * W + p[i].x0) * 4,
                           (uint8_t *)p[i].planes[c] + (size_t)(y - from) * p[i].w * 4, (size_t)p[i].w * 4);
        }
        if (!rc) rc = exrio_writer_rows(w, y0, rows, (const void *const *)full);
    }
    if (!rc) rc = exrio_writer_finish(&w);
out:
    exrio_writer_abort(&w);
    for (int c = 0; c < FB_MERGE_MAX_CHANNELS; c++) free(full[c]);
    for (int i = 0; i < n; i++) {
        for (int c = 0; c < FB_MERGE_MAX_CHANNELS; c++) free(p[i].planes[c]);
        exrio_close(&p[i].r);
    }
    free(p);
    return rc;
}

/* ---- points parts: chaos-game hits added ------------------------------------------------------ */

/* "K/N" of a part or task attribute: decimal integers, K >= k_lo, 1 <= N <= n_max, nothing else. */
static bool parse_kn(const char *s, int k_lo, int n_max, int *k, int *n)
{
    const char *end;
    long long a, b;
    if (!s || !fb_text_int(s, k_lo, n_max, &end, &a) || *end != '/' || !fb_text_int(end + 1, 1, n_max, NULL, &b))
        return false;
    *k = (int)a, *n = (int)b;
    return true;
}

/* The outside count of layer `name` in a part's "fractalbake/points-outside" ("a=12;b=0"). */
static bool outside_of(const char *attr, const char *name, uint64_t *out)
{
    size_t len = strlen(name);
    for (const char *q = attr; q && *q; q = strchr(q, ';') ? strchr(q, ';') + 1 : NULL)
        if (!strncmp(q, name, len) && q[len] == '=') {
            /* digits up to the next ';', at most the documented maximum of a chaos game's points */
            const char *end;
            long long v;
            if (!fb_text_int(q + len + 1, 0, 100000000000000ll, &end, &v) || (*end && *end != ';') || q[len + 1] == '+')
                return false;
            *out = (uint64_t)v;
            return true;
        }
    return false;
}

/* A layer split by points (its class's fb_points_ops): its sums added over the parts. */
typedef struct chaos_layer {
    fb_gen gen;
    const fb_points_ops *ops;
    int layer; /* its index in the scene */
    int nsums; /* its sums (as many as its class sizes for the layer) */
    int nch;   /* the parts' channels of its sums: 1 each, 2 for a wide one */
    char (*suffix)[40];
    bool *wide;
    int *idx;        /* the channels' indices in the part being read */
    uint32_t **rows; /* a strip of each */
    uint64_t **sum;  /* added over the parts */
    uint64_t outside;
} chaos_layer;

/* Bytes per pixel of a chaos layer's sums (its generator initialised). */
static uint64_t chaos_bytes(const chaos_layer *c)
{
    return 8u * (uint64_t)c->gen.layer->cls->points->nsums(&c->gen);
}

/* Whether channel `name` is one of a chaos layer's sums that the whole game's layer does not store
 * (a points part's colour sums). */
static bool chaos_sum_only(const chaos_layer *c, const char *name)
{
    const char *lname = c->gen.layer->name;
    size_t len = strlen(lname);
    if (strncmp(name, lname, len) || name[len] != '.') return false;
    for (int j = 0; j < c->gen.store.nchannels; j++)
        if (!strcmp(c->gen.store.channel_names[j], name)) return false;
    for (int k = 0; k < c->nsums; k++) {
        size_t sl = strlen(c->suffix[k]);
        const char *q = name + len + 1;
        if (!strncmp(q, c->suffix[k], sl) && (c->wide[k] ? !strcmp(q + sl, "_lo") || !strcmp(q + sl, "_hi") : !q[sl]))
            return true;
    }
    return false;
}

/* Rows [y0, y0 + n) of a chaos layer's channels from its summed game, into the output planes of
 * the same names (ch[0..nout)); every channel of the layer must be among them. */
static fb_result chaos_rows(const chaos_layer *c, const exrio_channel *ch, void *const *outp, int nout, int y0, int n,
                            const char *path)
{
    void *planes[FB_GEN_MAX_CHANNELS] = {0};
    for (int j = 0; j < c->gen.store.nchannels; j++) {
        for (int o = 0; o < nout; o++)
            if (!strcmp(ch[o].name, c->gen.store.channel_names[j])) planes[j] = outp[o];
        if (!planes[j])
            return fb_fail(FB_ERR_INPUT, "%s: layer %s lacks some of its channels", path, c->gen.layer->name);
    }
    c->gen.compute.native_rows(&c->gen, y0, n, planes);
    return FB_OK;
}

/* Frees the ncl chaos layers' generators and sums. */
static void chaos_free(chaos_layer *cl, int ncl)
{
    for (int k = 0; k < ncl; k++) {
        fb_gen_fini(&cl[k].gen);
        for (int j = 0; cl[k].sum && j < cl[k].nsums; j++) free(cl[k].sum[j]);
        for (int j = 0; cl[k].rows && j < 2 * cl[k].nsums; j++) free(cl[k].rows[j]);
        free(cl[k].sum), free(cl[k].rows), free(cl[k].idx), free(cl[k].suffix), free(cl[k].wide);
    }
}

/* A chaos layer's sums (its generator initialised): their names, strip rows and image of sums. */
static fb_result chaos_alloc(chaos_layer *c, int W, int H)
{
    const fb_layer *L = c->gen.layer;
    c->ops = L->cls->points;
    c->nch = 0;
    if (!ALWAYS(c->ops && c->ops->from_sums && c->ops->nsums && c->ops->sum))
        return fb_fail(FB_ERR_INTERNAL, "generator %s splits by points but has no sums to merge", L->cls->name);
    int n = c->nsums = c->ops->nsums(&c->gen);
    bool ok = n > 0 && (c->suffix = calloc((size_t)n, sizeof *c->suffix)) && (c->wide = calloc((size_t)n, 1)) &&
              (c->idx = calloc(2 * (size_t)n, sizeof *c->idx)) && (c->rows = calloc(2 * (size_t)n, sizeof *c->rows)) &&
              (c->sum = calloc((size_t)n, sizeof *c->sum));
    for (int k = 0; k < n && ok; k++) {
        c->wide[k] = c->ops->sum(&c->gen, k, c->suffix[k], sizeof c->suffix[k]);
        ok = ok && (c->sum[k] = calloc((size_t)W * H, sizeof *c->sum[k]));
        for (int h = 0; h < (c->wide[k] ? 2 : 1); h++)
            ok = ok && (c->rows[c->nch++] = malloc((size_t)W * MERGE_STRIP * 4));
    }
    return ok ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
}

/* Adds one points part's hits, colour sums and outside count to each of the ncl chaos layers. */
static fb_result chaos_add(chaos_layer *cl, int ncl, const fb_scene *sc, exrio_reader *r, const char *path, int W,
                           int H)
{
    void *in[FB_MERGE_MAX_CHANNELS] = {0};
    if (exrio_nchannels(r) > FB_MERGE_MAX_CHANNELS)
        return fb_fail(FB_ERR_INPUT, "%s: more than %d channels", path, FB_MERGE_MAX_CHANNELS);
    for (int k = 0; k < ncl; k++) {
        uint64_t o = 0;
        const char *name = sc->layers[cl[k].layer].name;
        const char *counts = exrio_attr_string(r, "fractalbake/points-outside");
        if (!counts) counts = exrio_attr_string(r, "fractalbake/ifs-outside"); /* its name before flames */
        if (!outside_of(counts, name, &o))
            return fb_fail(
                FB_ERR_INPUT,
                "%s: no outside count for layer %s, or a malformed one (attribute fractalbake/points-outside: "
                "NAME=COUNT;..., counts 0..1e14)",
                path, name);
        cl[k].outside += o;
        for (int s = 0, j = 0; s < cl[k].nsums; s++) /* the channels' indices in this file */
            for (int h = 0; h < (cl[k].wide[s] ? 2 : 1); h++, j++) {
                char cn[160];
                snprintf(cn, sizeof cn, "%s.%s%s", name, cl[k].suffix[s], !cl[k].wide[s] ? "" : h ? "_hi" : "_lo");
                if ((cl[k].idx[j] = exrio_find_channel(r, cn)) < 0)
                    return fb_fail(FB_ERR_INPUT, "%s: no channel %s (not a points part of this scene)", path, cn);
                in[cl[k].idx[j]] = cl[k].rows[j];
            }
    }
    for (int y0 = 0; y0 < H && ncl > 0; y0 += MERGE_STRIP) {
        int rowsn = y0 + MERGE_STRIP <= H ? MERGE_STRIP : H - y0;
        fb_result rc = exrio_read_rows(r, y0, rowsn, in);
        if (rc) return rc;
        for (int k = 0; k < ncl; k++) {
            chaos_layer *c = &cl[k];
            for (int s = 0, j = 0; s < c->nsums; s++) {
                uint64_t *sum = c->sum[s] + (size_t)y0 * W;
                const uint32_t *lo = c->rows[j++], *hi = c->wide[s] ? c->rows[j++] : NULL;
                for (size_t q = 0; q < (size_t)rowsn * W; q++) sum[q] += (hi ? (uint64_t)hi[q] << 32 : 0) | lo[q];
            }
        }
    }
    return FB_OK;
}

static fb_result merge_points(part *p, int n, const fb_merge_desc *d)
{
    const char *const *paths = d->paths, *out = d->out;
    const int threads = d->threads, zip_level = d->zip_level;
    const fb_memory mem = {d->max_memory, 0};
    fb_result rc = FB_OK;
    int N = 0, seen[4097] = {0};
    const char *scene_json = exrio_attr_string(p[0].r, "fractalbake/scene");
    int W = exrio_width(p[0].r), H = exrio_height(p[0].r), nch = exrio_nchannels(p[0].r);
    for (int i = 0; i < n; i++) {
        int k = 0, nn = 0;
        const char *pp = exrio_attr_string(p[i].r, "fractalbake/points-part");
        const char *scene = exrio_attr_string(p[i].r, "fractalbake/scene");
        if (!parse_kn(pp, 1, 4096, &k, &nn) || k < 1 || k > nn)
            return fb_fail(FB_ERR_INPUT, "%s: malformed attribute fractalbake/points-part \"%s\"", paths[i], pp);
        if (i == 0) N = nn;
        if (nn != N) return fb_fail(FB_ERR_INPUT, "%s: part %d of %d, but %s is of %d", paths[i], k, nn, paths[0], N);
        if (seen[k]++) return fb_fail(FB_ERR_INPUT, "%s: points part %d/%d is given twice", paths[i], k, N);
        if (!scene || !scene_json || strcmp(scene, scene_json))
            return fb_fail(FB_ERR_INPUT, "%s: baked from another scene than %s (attribute fractalbake/scene)", paths[i],
                           paths[0]);
        int a[4], b[4];
        exrio_window(p[i].r, &a[0], &a[1], &a[2], &a[3]);
        exrio_window(p[0].r, &b[0], &b[1], &b[2], &b[3]);
        bool same =
            !memcmp(a, b, sizeof a) && exrio_nchannels(p[i].r) == nch && exrio_nparts(p[i].r) == exrio_nparts(p[0].r);
        for (int c = 0; c < nch && same; c++)
            same = !strcmp(exrio_channel_name(p[i].r, c), exrio_channel_name(p[0].r, c)) &&
                   exrio_channel_type(p[i].r, c) == exrio_channel_type(p[0].r, c) &&
                   exrio_channel_part(p[i].r, c) == exrio_channel_part(p[0].r, c);
        if (!same)
            return fb_fail(FB_ERR_INPUT, "%s: its image, channels or parts differ from those of %s", paths[i],
                           paths[0]);
    }
    if (n != N) {
        for (int k = 1; k <= N; k++)
            if (!seen[k]) return fb_fail(FB_ERR_INPUT, "merge: points part %d/%d is missing", k, N);
    }
    fb_scene sc = {0};
    chaos_layer *cl = NULL;
    int ncl = 0;
    exrio_channel *ch = calloc((size_t)nch, sizeof *ch);
    int *src = calloc((size_t)nch, sizeof *src); /* output channel -> part channel index, or -1 - chaos layer */
    void **in = calloc((size_t)nch, sizeof *in), **cmp = calloc((size_t)nch, sizeof *cmp);
    void *outp[FB_MERGE_MAX_CHANNELS] = {0};
    exrio_writer *w = NULL;
    int nout = 0;
    if (!ch || !src || !in || !cmp) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) rc = fb_scene_parse(scene_json, paths[0], &sc);
    if (!rc && (sc.width != W || sc.height != H))
        rc = fb_fail(FB_ERR_INPUT, "%s: %d x %d, but its scene is %d x %d", paths[0], W, H, sc.width, sc.height);
    if (!rc && !(cl = calloc((size_t)sc.nlayers, sizeof *cl))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    /* the chaos-game layers: their hits and colour sums, added over the parts (each part read once) */
    size_t npx = (size_t)W * H;
    int nchaos = 0;
    uint64_t bytes_px = 0;
    for (int l = 0; l < sc.nlayers && !rc; l++) { /* the whole game's layers */
        if (sc.layers[l].cls->share != FB_SHARE_POINTS) continue;
        chaos_layer *c = &cl[ncl++];
        c->layer = l;
        rc = fb_gen_init(&c->gen, &sc, &sc.layers[l]);
        if (!rc) nchaos++, bytes_px += chaos_bytes(c);
    }
    char who[4200];
    snprintf(who, sizeof who, "merging the points parts of %s (%d x %d, %d chaos-game layers)", paths[0], W, H, nchaos);
    if (!rc) rc = fb_memory_check(&mem, (uint64_t)npx * bytes_px, who);
    for (int k = 0; k < ncl && !rc; k++) rc = chaos_alloc(&cl[k], W, H);
    for (int i = 0; i < n && !rc; i++) rc = chaos_add(cl, ncl, &sc, p[i].r, paths[i], W, H);
    for (int k = 0; k < ncl && !rc; k++) {
        chaos_layer *c = &cl[k];
        for (int j = 0; j < c->nch; j++) free(c->rows[j]), c->rows[j] = NULL;
        rc = c->ops->from_sums(&c->gen, (const uint64_t *const *)c->sum, c->outside);
    }
    /* the output: every channel but the colour sums; chaos layers' from their generator */
    for (int c = 0; c < nch && !rc; c++) {
        const char *name = exrio_channel_name(p[0].r, c);
        bool sum_only = false;
        for (int k = 0; k < ncl; k++) sum_only = sum_only || chaos_sum_only(&cl[k], name);
        if (sum_only) continue;
        src[nout] = c;
        for (int k = 0; k < ncl; k++)
            for (int j = 0; j < cl[k].gen.store.nchannels; j++)
                if (!strcmp(cl[k].gen.store.channel_names[j], name)) src[nout] = -1 - k;
        ch[nout] = (exrio_channel){name, exrio_channel_type(p[0].r, c), exrio_channel_part(p[0].r, c)};
        if (!(outp[nout] = malloc((size_t)W * MERGE_STRIP * 4))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        nout++;
    }
    if (!rc) rc = open_output(p[0].r, out, W, H, ch, nout, threads, zip_level, &w);
    for (int c = 0; c < nch && !rc; c++) /* buffers for every part channel: read, and compared */
        if (!(in[c] = malloc((size_t)W * MERGE_STRIP * 4)) || !(cmp[c] = malloc((size_t)W * MERGE_STRIP * 4)))
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int y0 = 0; y0 < H && !rc; y0 += MERGE_STRIP) {
        int rowsn = y0 + MERGE_STRIP <= H ? MERGE_STRIP : H - y0;
        size_t bytes = (size_t)W * rowsn * 4;
        rc = exrio_read_rows(p[0].r, y0, rowsn, in);
        /* the layers that are not chaos games are the same in every part: checked, not trusted */
        for (int i = 1; i < n && !rc; i++) {
            rc = exrio_read_rows(p[i].r, y0, rowsn, cmp);
            for (int o = 0; o < nout && !rc; o++)
                if (src[o] >= 0 && memcmp(in[src[o]], cmp[src[o]], bytes))
                    rc = fb_fail(FB_ERR_INPUT, "%s: channel %s differs from %s's near row %d: not parts of one bake",
                                 paths[i], ch[o].name, paths[0], y0);
        }
        for (int k = 0; k < ncl && !rc; k++) rc = chaos_rows(&cl[k], ch, outp, nout, y0, rowsn, paths[0]);
        for (int o = 0; o < nout && !rc; o++)
            if (src[o] >= 0) memcpy(outp[o], in[src[o]], bytes);
        if (!rc) rc = exrio_writer_rows(w, y0, rowsn, (const void *const *)outp);
    }
    if (!rc) rc = exrio_writer_finish(&w);
    exrio_writer_abort(&w);
    chaos_free(cl, ncl);
    for (int c = 0; c < nch && in; c++) free(in[c]), free(cmp[c]);
    for (int o = 0; o < FB_MERGE_MAX_CHANNELS; o++) free(outp[o]);
    free(cl);
    free(ch);
    free(src);
    free(in);
    free(cmp);
    fb_scene_fini(&sc);
    return rc;
}

/* ---- task files: render --task K/N ---------------------------------------------------------- */

/* The scene layer that channel c of file r belongs to: its part's name in a multi-part file, else
 * the longest layer name that prefixes "NAME."; -1 if none. */
static int layer_of_channel(const fb_scene *sc, const exrio_reader *r, int c)
{
    if (exrio_nparts(r) > 1) {
        const char *pn = exrio_part_name(r, exrio_channel_part(r, c));
        for (int i = 0; i < sc->nlayers; i++)
            if (pn && !strcmp(sc->layers[i].name, pn)) return i;
        return -1;
    }
    const char *name = exrio_channel_name(r, c);
    int best = -1;
    size_t best_len = 0;
    for (int i = 0; i < sc->nlayers; i++) {
        size_t len = strlen(sc->layers[i].name);
        if (len > best_len && !strncmp(name, sc->layers[i].name, len) && name[len] == '.') best = i, best_len = len;
    }
    return best;
}

/* The state of merging the task files of one plan. */
typedef struct task_merge {
    part *p;
    int n;
    const fb_merge_desc *d;
    fb_scene *sc;
    fb_plan *plan;
    int *file_of;    /* task k's file, -1 before it is found */
    chaos_layer *cl; /* the chaos games split by points */
    int ncl;
    int (*map)[FB_MERGE_MAX_CHANNELS]; /* file channel -> output channel, or -1 */
    exrio_channel ch[FB_MERGE_MAX_CHANNELS];
    int nout;
    void *outp[FB_MERGE_MAX_CHANNELS]; /* a strip of each output channel */
} task_merge;

/* Which file is which task, the set complete, each file's window its task's share. */
static fb_result tasks_assign(task_merge *m)
{
    part *p = m->p;
    const int n = m->n;
    const char *const *paths = m->d->paths;
    fb_scene *sc = m->sc;
    fb_plan *plan = m->plan;
    int *file_of = m->file_of;
    const int W = sc->width, H = sc->height;
    fb_result rc = FB_OK;
    for (int k = 0; k < FB_PLAN_MAX_TASKS && file_of; k++) file_of[k] = -1;
    for (int i = 0; i < n && !rc; i++) {
        int k = -1, nn = 0;
        const char *t = exrio_attr_string(p[i].r, "fractalbake/task");
        if (!parse_kn(t, 0, FB_PLAN_MAX_TASKS, &k, &nn) || nn != plan->ntasks || k >= plan->nactive)
            rc = fb_fail(FB_ERR_INPUT, "%s: task \"%s\" is not one of the plan's %d tasks with work", paths[i], t,
                         plan->nactive);
        else if (file_of[k] >= 0)
            rc = fb_fail(FB_ERR_INPUT, "%s and %s are both task %d/%d", paths[file_of[k]], paths[i], k, nn);
        else
            file_of[k] = i;
    }
    if (!rc) {
        char missing[2048] = "";
        int nmiss = 0;
        for (int k = 0; k < plan->nactive; k++) {
            if (file_of[k] >= 0) continue;
            char d[1024];
            fb_plan_describe(sc, &plan->tasks[k], d, sizeof d);
            if (nmiss++ < 8)
                snprintf(missing + strlen(missing), sizeof missing - strlen(missing), "%stask %d (%s)",
                         nmiss > 1 ? ", " : "", k, d);
        }
        if (nmiss)
            rc = fb_fail(FB_ERR_INPUT, "merge: %d of the plan's %d tasks %s missing: %s%s", nmiss, plan->nactive,
                         nmiss == 1 ? "is" : "are", missing, nmiss > 8 ? ", ..." : "");
    }
    /* each file's window is its task's share */
    for (int k = 0; k < plan->nactive && !rc && sc; k++) {
        const fb_task *t = &plan->tasks[k];
        int i = file_of[k], x0, y0, fw, fh;
        exrio_window(p[i].r, &x0, &y0, &fw, &fh);
        int ey0 = t->band ? t->y0 : 0, eh = t->band ? t->y1 - t->y0 : H;
        if (fw != W || fh != H || x0 != 0 || y0 != ey0 || exrio_width(p[i].r) != W || exrio_height(p[i].r) != eh)
            rc = fb_fail(FB_ERR_INPUT,
                         "%s: task %d's file holds rows %d-%d of a %d x %d image, but its plan gives it %d-%d",
                         paths[i], k, y0, y0 + exrio_height(p[i].r) - 1, fw, fh, ey0, ey0 + eh - 1);
        p[i].y0 = y0, p[i].h = exrio_height(p[i].r), p[i].w = W;
    }
    return rc;
}

/* The output's channels, layer by layer: a chaos game split by points from its generator, the
 * others as the files hold them (every band the same), and map[file][channel] their place. */
static fb_result tasks_channels(task_merge *m)
{
    part *p = m->p;
    const int n = m->n;
    const char *const *paths = m->d->paths;
    fb_scene *sc = m->sc;
    fb_plan *plan = m->plan;
    int *file_of = m->file_of;
    fb_result rc = FB_OK;
    for (int i = 0; i < n && m->map; i++)
        for (int c = 0; c < FB_MERGE_MAX_CHANNELS; c++) m->map[i][c] = -1;
    for (int l = 0; l < (sc ? sc->nlayers : 0) && !rc; l++) {
        if (plan->share[l] == FB_SHARE_POINTS) {
            chaos_layer *c = &m->cl[m->ncl];
            m->ncl++;
            c->layer = l;
            rc = fb_gen_init(&c->gen, sc, &sc->layers[l]);
            for (int j = 0; j < c->gen.store.nchannels && !rc; j++) {
                if (m->nout == FB_MERGE_MAX_CHANNELS)
                    rc = fb_fail(FB_ERR_INPUT, "merge handles at most %d channels", m->nout);
                else
                    m->ch[m->nout++] = (exrio_channel){c->gen.store.channel_names[j], c->gen.store.channel_types[j],
                                                       sc->multipart ? l : 0};
            }
            continue;
        }
        bool first = true;
        int at = m->nout;
        for (int k = 0; k < plan->nactive && !rc; k++) {
            if (!(plan->tasks[k].layers >> l & 1)) continue;
            const exrio_reader *r = p[file_of[k]].r;
            int count = 0;
            for (int c = 0; c < exrio_nchannels(r) && !rc && exrio_nchannels(r) <= FB_MERGE_MAX_CHANNELS; c++) {
                if (layer_of_channel(sc, r, c) != l) continue;
                int o = -1;
                if (first) {
                    if (m->nout == FB_MERGE_MAX_CHANNELS) {
                        rc = fb_fail(FB_ERR_INPUT, "merge handles at most %d channels", m->nout);
                        break;
                    }
                    o = m->nout;
                    m->ch[m->nout++] =
                        (exrio_channel){exrio_channel_name(r, c), exrio_channel_type(r, c), sc->multipart ? l : 0};
                } else {
                    for (int q = at; q < m->nout; q++)
                        if (!strcmp(m->ch[q].name, exrio_channel_name(r, c)) &&
                            m->ch[q].type == exrio_channel_type(r, c))
                            o = q;
                    if (o < 0)
                        rc = fb_fail(FB_ERR_INPUT, "%s: channel %s is not in the other bands of layer %s",
                                     paths[file_of[k]], exrio_channel_name(r, c), sc->layers[l].name);
                }
                m->map[file_of[k]][c] = o;
                count++;
            }
            if (!rc && exrio_nchannels(r) > FB_MERGE_MAX_CHANNELS)
                rc = fb_fail(FB_ERR_INPUT, "%s: more than %d channels", paths[file_of[k]], FB_MERGE_MAX_CHANNELS);
            if (!rc && (count == 0 || (!first && count != m->nout - at)))
                rc = fb_fail(FB_ERR_INPUT, "%s: task %d's file lacks channels of layer %s", paths[file_of[k]], k,
                             sc->layers[l].name);
            first = false;
        }
    }
    return rc;
}

/* The chaos games split by points: every part's hits added. */
static fb_result tasks_chaos(task_merge *m)
{
    part *p = m->p;
    const char *const *paths = m->d->paths;
    fb_scene *sc = m->sc;
    fb_plan *plan = m->plan;
    int *file_of = m->file_of;
    const int W = sc->width, H = sc->height;
    const fb_memory mem = {m->d->max_memory, 0};
    fb_result rc = FB_OK;
    size_t npx = (size_t)W * H;
    chaos_layer *cl = m->cl;
    const int ncl = m->ncl;
    if (ncl) {
        char who[4200];
        uint64_t bytes_px = 0;
        for (int k = 0; k < ncl; k++) bytes_px += chaos_bytes(&cl[k]);
        snprintf(who, sizeof who, "merging the points parts of %s (%d x %d, %d chaos-game layers)", paths[0], W, H,
                 ncl);
        rc = fb_memory_check(&mem, (uint64_t)npx * bytes_px, who);
    }
    for (int k = 0; k < ncl && !rc; k++) rc = chaos_alloc(&cl[k], W, H);
    for (int t = 0; t < plan->nactive && !rc && ncl; t++)
        if (plan->tasks[t].points) rc = chaos_add(cl, ncl, sc, p[file_of[t]].r, paths[file_of[t]], W, H);
    for (int k = 0; k < ncl && !rc; k++)
        rc = cl[k].ops->from_sums(&cl[k].gen, (const uint64_t *const *)cl[k].sum, cl[k].outside);
    return rc;
}

/* The output file, with the attributes a one-command bake writes: the backend the tasks were asked
 * for, where each layer ran, and the strip buffers. */
static fb_result tasks_open_output(task_merge *m, const char *scene_json, exrio_writer **wp)
{
    part *p = m->p;
    const char *const *paths = m->d->paths;
    fb_scene *sc = m->sc;
    fb_plan *plan = m->plan;
    int *file_of = m->file_of;
    const int W = sc->width, H = sc->height;
    fb_result rc = FB_OK;
    char backend[16], per_layer[FB_MAX_LAYERS * 80] = "", device[1024] = "native C", seed[16];
    int nvk = 0;
    for (int l = 0; l < sc->nlayers && !rc; l++) {
        fb_backend kind = FB_BACKEND_NATIVE;
        int holder = -1;
        for (int k = 0; k < plan->nactive && holder < 0; k++)
            if (plan->tasks[k].layers >> l & 1) holder = file_of[k];
        if (holder < 0) {
            rc = fb_fail(FB_ERR_INPUT, "%s: the stored plan gives layer %s to no task", paths[0], sc->layers[l].name);
            break;
        }
        if (!fb_layer_backend_of(exrio_attr_string(p[holder].r, "fractalbake/layer-backends"), sc->layers[l].name,
                                 &kind))
            rc = fb_fail(FB_ERR_INPUT, "%s: no backend for layer %s (attribute fractalbake/layer-backends)",
                         paths[holder], sc->layers[l].name);
        bool vk = kind == FB_BACKEND_VULKAN;
        nvk += vk;
        if (vk) snprintf(device, sizeof device, "%s", exrio_attr_string(p[holder].r, "fractalbake/device"));
        snprintf(per_layer + strlen(per_layer), sizeof per_layer - strlen(per_layer), "%s%s=%s", l ? ";" : "",
                 sc->layers[l].name, fb_backend_name(kind));
    }
    if (!rc) { /* what the tasks were asked for, as the one-command bake records it */
        const char *asked = exrio_attr_string(p[0].r, "fractalbake/backend");
        for (int i = 1; i < m->n && asked; i++) {
            const char *b = exrio_attr_string(p[i].r, "fractalbake/backend");
            if (!b || strcmp(b, asked)) asked = fb_backend_name(FB_BACKEND_AUTO);
        }
        snprintf(backend, sizeof backend, "%s", asked ? asked : fb_backend_name(FB_BACKEND_AUTO));
        snprintf(seed, sizeof seed, "%u", sc->seed);
        exrio_attr attrs[6] = {{"fractalbake/scene", scene_json},
                               {"fractalbake/seed", seed},
                               {"fractalbake/backend", backend},
                               {"fractalbake/device", device},
                               {"fractalbake/version", exrio_attr_string(p[0].r, "fractalbake/version")}};
        int nattrs = attrs[4].value ? 5 : 4;
        if ((nvk > 0 && nvk < sc->nlayers) || !strcmp(backend, fb_backend_name(FB_BACKEND_AUTO)))
            attrs[nattrs++] = (exrio_attr){"fractalbake/layer-backends", per_layer};
        const char *part_names[FB_MAX_LAYERS];
        exrio_compression part_comp[FB_MAX_LAYERS];
        for (int l = 0; l < sc->nlayers; l++)
            part_names[l] = sc->layers[l].name, part_comp[l] = sc->layers[l].compression;
        for (int o = 0; o < m->nout && !rc; o++)
            if (!(m->outp[o] = malloc((size_t)W * MERGE_STRIP * 4))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        if (!rc)
            rc = exrio_writer_create(&(exrio_writer_desc){.path = m->d->out,
                                                          .width = W,
                                                          .height = H,
                                                          .nparts = sc->multipart ? sc->nlayers : 1,
                                                          .part_names = sc->multipart ? part_names : NULL,
                                                          .part_compression = sc->multipart ? part_comp : NULL,
                                                          .compression = sc->compression,
                                                          .channels = m->ch,
                                                          .nchannels = m->nout,
                                                          .attrs = attrs,
                                                          .nattrs = nattrs,
                                                          .threads = m->d->threads,
                                                          .zip_level = m->d->zip_level,
                                                          .envmap = sc->envmap},
                                     wp);
    }
    return rc;
}

/* Task files of one plan (render --task K/N) joined into the bake they share. */
static fb_result merge_tasks(part *p, int n, const fb_merge_desc *d)
{
    const char *const *paths = d->paths;
    const char *scene_json = exrio_attr_string(p[0].r, "fractalbake/scene");
    const char *plan_text = exrio_attr_string(p[0].r, "fractalbake/plan");
    if (!scene_json || !plan_text)
        return fb_fail(FB_ERR_INPUT, "%s: a task file without its scene or plan (attributes fractalbake/scene, /plan)",
                       paths[0]);
    for (int i = 1; i < n; i++) {
        const char *sj = exrio_attr_string(p[i].r, "fractalbake/scene"),
                   *pj = exrio_attr_string(p[i].r, "fractalbake/plan");
        if (!sj || strcmp(sj, scene_json))
            return fb_fail(FB_ERR_INPUT, "%s: baked from another scene than %s (attribute fractalbake/scene)", paths[i],
                           paths[0]);
        if (!pj || strcmp(pj, plan_text))
            return fb_fail(FB_ERR_INPUT, "%s: a task of another plan than %s (attribute fractalbake/plan: another N?)",
                           paths[i], paths[0]);
    }
    task_merge m = {.p = p,
                    .n = n,
                    .d = d,
                    .sc = calloc(1, sizeof *m.sc),
                    .plan = malloc(sizeof *m.plan),
                    .file_of = calloc(FB_PLAN_MAX_TASKS, sizeof *m.file_of),
                    .cl = calloc(FB_MAX_LAYERS, sizeof *m.cl),
                    .map = calloc((size_t)n, sizeof *m.map)};
    exrio_writer *w = NULL;
    fb_result rc = FB_OK;
    if (!m.sc || !m.plan || !m.file_of || !m.cl || !m.map) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc) rc = fb_scene_parse(scene_json, paths[0], m.sc);
    if (!rc) rc = fb_plan_parse(plan_text, m.sc, m.plan);
    if (!rc) rc = tasks_assign(&m);
    if (!rc) rc = tasks_channels(&m);
    if (!rc) rc = tasks_chaos(&m);
    if (!rc) rc = tasks_open_output(&m, scene_json, &w);
    const int W = m.sc ? m.sc->width : 0, H = m.sc ? m.sc->height : 0;
    /* strip by strip: each file's rows in place, the chaos games' from their sums */
    for (int y0 = 0; y0 < H && !rc; y0 += MERGE_STRIP) {
        int rowsn = y0 + MERGE_STRIP <= H ? MERGE_STRIP : H - y0;
        for (int i = 0; i < n && !rc; i++) {
            int from = y0 > p[i].y0 ? y0 : p[i].y0;
            int to = y0 + rowsn < p[i].y0 + p[i].h ? y0 + rowsn : p[i].y0 + p[i].h;
            if (from >= to) continue;
            void *own[FB_MERGE_MAX_CHANNELS] = {0};
            bool any = false;
            for (int c = 0; c < exrio_nchannels(p[i].r); c++)
                if (m.map[i][c] >= 0) own[c] = (uint8_t *)m.outp[m.map[i][c]] + (size_t)(from - y0) * W * 4, any = true;
            if (any) rc = exrio_read_rows(p[i].r, from - p[i].y0, to - from, own);
        }
        for (int k = 0; k < m.ncl && !rc; k++) rc = chaos_rows(&m.cl[k], m.ch, m.outp, m.nout, y0, rowsn, paths[0]);
        if (!rc) rc = exrio_writer_rows(w, y0, rowsn, (const void *const *)m.outp);
    }
    if (!rc) rc = exrio_writer_finish(&w);
    exrio_writer_abort(&w);
    chaos_free(m.cl, m.ncl);
    for (int o = 0; o < FB_MERGE_MAX_CHANNELS; o++) free(m.outp[o]);
    if (m.sc) fb_scene_fini(m.sc);
    free(m.sc);
    free(m.plan);
    free(m.file_of);
    free(m.cl);
    free(m.map);
    return rc;
}
