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

#include "exrio.h"

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
 * is byte for byte the whole-image bake); the region attribute is left out. */
static const char *const k_attrs[] = {"fractalbake/scene", "fractalbake/seed", "fractalbake/backend",
                                      "fractalbake/device", "fractalbake/version"};

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

fb_result fb_merge(const char *const *paths, int n, const char *out, int threads)
{
    if (n < 1) return fb_fail(FB_ERR_USAGE, "merge: no parts given");
    fb_result rc = FB_OK;
    part *p = calloc((size_t)n, sizeof *p);
    void *full[FB_MERGE_MAX_CHANNELS] = {0};
    exrio_channel ch[FB_MERGE_MAX_CHANNELS];
    exrio_writer *w = NULL;
    int W = 0, H = 0, nch = 0;
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n && !rc; i++) rc = exrio_open(paths[i], &p[i].r);
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

    exrio_attr attrs[sizeof k_attrs / sizeof k_attrs[0]];
    int nattrs = 0;
    for (size_t a = 0; a < sizeof k_attrs / sizeof k_attrs[0]; a++) {
        const char *v = exrio_attr_string(p[0].r, k_attrs[a]);
        if (v) attrs[nattrs++] = (exrio_attr){k_attrs[a], v};
    }
    /* the parts' structure (names, compressions) as in the first region file */
    int nparts = exrio_nparts(p[0].r);
    const char *part_names[EXRIO_MAX_PARTS];
    exrio_compression part_comp[EXRIO_MAX_PARTS];
    for (int k = 0; k < nparts; k++) {
        int c = exrio_compression_parse(exrio_part_compression(p[0].r, k));
        part_names[k] = exrio_part_name(p[0].r, k);
        part_comp[k] = c < 0 ? EXRIO_ZIP : (exrio_compression)c;
    }
    int comp = exrio_compression_parse(exrio_compression_of(p[0].r));
    rc = exrio_writer_create(&(exrio_writer_desc){.path = out,
                                                  .width = W,
                                                  .height = H,
                                                  .compression = comp < 0 ? EXRIO_ZIP : (exrio_compression)comp,
                                                  .channels = ch,
                                                  .nchannels = nch,
                                                  .attrs = attrs,
                                                  .nattrs = nattrs,
                                                  .threads = threads,
                                                  .nparts = nparts,
                                                  .part_names = part_names,
                                                  .part_compression = part_comp},
                             &w);
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
