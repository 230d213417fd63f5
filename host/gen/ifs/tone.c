/*
 * Re-toning an ifs layer (fractalbake tonemap) and merging its points parts (fractalbake merge): the
 * class hooks of gen.h (fb_tone_ops, fb_points_ops) over the layer's stored channels.
 */
#include "gen_ifs.h"
#include "ifs.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The keys that only change the tone mapping. */
static const char *const k_tone_keys[] = {"brightness", "gamma",  "gamma-threshold", "vibrancy", "highlight-power",
                                          "palette",    "cosine", "stops",           NULL};

typedef struct ifs_retone {
    fb_ifs_tone tone;
    int idx[6]; /* the file's density, colour, R, G, B, A channels */
    size_t width;
} ifs_retone;

/* Pass 1: the reference density over the whole image, and the layer's new tone parameters. */
static fb_result retone_begin(const fb_layer *L, exrio_reader *r, const char *path, void **state)
{
    static const char *const suffix[6] = {"density", "colour", "R", "G", "B", "A"};
    ifs_retone *t = calloc(1, sizeof *t);
    if (!t) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_result rc = FB_OK;
    for (int k = 0; k < 6 && !rc; k++) {
        char name[96];
        snprintf(name, sizeof name, "%s.%s", L->name, suffix[k]);
        if ((t->idx[k] = exrio_find_channel(r, name)) < 0)
            rc = fb_fail(FB_ERR_INPUT, "%s: channel %s is missing", path, name);
    }
    int width = exrio_width(r), height = exrio_height(r), nch = exrio_nchannels(r);
    size_t n = (size_t)width * height;
    t->width = (size_t)width;
    char who[4200];
    snprintf(who, sizeof who, "tonemap %s (%d x %d)", path, width, height);
    float *density = NULL;
    void **one = NULL;
    if (!rc) rc = fb_memory_check(NULL, (uint64_t)n * 4, who);
    if (!rc && (!(density = malloc(n * 4)) || !(one = calloc((size_t)nch, sizeof *one))))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int y = 0; y < height && !rc; y += 256) {
        int rows = y + 256 <= height ? 256 : height - y;
        one[t->idx[0]] = density + (size_t)y * width;
        rc = exrio_read_rows(r, y, rows, one);
    }
    if (!rc) {
        const fb_ifs_params *f = fb_layer_params(L);
        t->tone = (fb_ifs_tone){.brightness = f->brightness,
                                .gamma = f->gamma,
                                .threshold = f->gamma_threshold,
                                .vibrancy = f->vibrancy,
                                .highlight = f->highlight_power,
                                .dref = fb_ifs_density_ref(density, n)};
        fb_palette_build(&f->palette, t->tone.palette);
    }
    free(one);
    free(density);
    if (rc) {
        free(t);
        return rc;
    }
    *state = t;
    return FB_OK;
}

static void retone_rows(const void *state, int m, void *const *planes)
{
    const ifs_retone *t = state;
    const int *i = t->idx;
    fb_ifs_tonemap_row(&t->tone, planes[i[0]], planes[i[1]], (size_t)m * t->width, planes[i[2]], planes[i[3]],
                       planes[i[4]], planes[i[5]]);
}

static void retone_end(void *state)
{
    free(state);
}

const fb_tone_ops fb_ifs_tone_ops = {
    .keys = k_tone_keys,
    .begin = retone_begin,
    .rows = retone_rows,
    .end = retone_end,
};

static fb_result merge_from_sums(fb_gen *g, const uint64_t *const *sums, uint64_t outside)
{
    return fb_gen_ifs_from_sums(g, sums[0], sums[1], outside);
}

static int merge_nsums(const fb_gen *g)
{
    (void)g;
    return 2;
}

/* A points part stores the hit count and each pixel's 64-bit colour sum as two uint channels. */
static bool merge_sum(const fb_gen *g, int k, char *suffix, size_t size)
{
    (void)g;
    snprintf(suffix, size, "%s", k == 0 ? "count" : "colour_sum");
    return k == 1;
}

const fb_points_ops fb_ifs_points_ops = {
    .nsums = merge_nsums,
    .sum = merge_sum,
    .from_sums = merge_from_sums,
};
