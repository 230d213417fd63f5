/*
 * Re-toning a flame layer (fractalbake tonemap): the class hook of gen.h (fb_tone_ops) over the
 * layer's stored accumulations (NAME.acc_R, .acc_G, .acc_B, .acc_A, at brightness 1), with the
 * layer's tone keys, no new chaos game.
 */
#include "gen_flame.h"

#include <stdio.h>
#include <stdlib.h>

static const char *const k_tone_keys[] = {"brightness", "gamma", "gamma-threshold", "vibrancy", "highlight-power",
                                          "background", NULL};

typedef struct flame_retone {
    fb_flame_tone tone;
    int idx[8]; /* the file's acc_R, acc_G, acc_B, acc_A, R, G, B, A channels */
    size_t width;
} flame_retone;

static fb_result retone_begin(const fb_layer *L, exrio_reader *r, const char *path, void **state)
{
    static const char *const suffix[8] = {"acc_R", "acc_G", "acc_B", "acc_A", "R", "G", "B", "A"};
    flame_retone *t = calloc(1, sizeof *t);
    if (!t) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int k = 0; k < 8; k++) {
        char name[96];
        snprintf(name, sizeof name, "%s.%s", L->name, suffix[k]);
        if ((t->idx[k] = exrio_find_channel(r, name)) < 0) {
            free(t);
            return fb_fail(FB_ERR_INPUT, "%s: channel %s is missing", path, name);
        }
    }
    t->width = (size_t)exrio_width(r);
    t->tone = ((const fb_flame_params *)fb_layer_params(L))->tone;
    *state = t;
    return FB_OK;
}

static void retone_rows(const void *state, int m, void *const *planes)
{
    const flame_retone *t = state;
    const int *i = t->idx;
    const float *acc[4] = {planes[i[0]], planes[i[1]], planes[i[2]], planes[i[3]]};
    fb_flame_tone_row(&t->tone, (size_t)m * t->width, acc, planes[i[4]], planes[i[5]], planes[i[6]], planes[i[7]]);
}

static void retone_end(void *state)
{
    free(state);
}

const fb_tone_ops fb_flame_tone_ops = {
    .keys = k_tone_keys,
    .begin = retone_begin,
    .rows = retone_rows,
    .end = retone_end,
};
