/*
 * The checker generator: the example of docs/architecture.md, "Adding a generator". Its keys, its
 * parser, its layer driver and its class; the math is kernels/checker.h.
 */
#include "gen_checker.h"

#include "kernels/checker.h"
#include "checker_comp.h"

#include <stdio.h>
#include <string.h>

static const fb_keyspec checker_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"checker\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"checker\"", "layer name; the channel is NAME.Y (flag: --layer)", FB_CORE},
    {"cells", FB_K_INT, 1, 65536, false, NULL, "8", "squares across each side of the image",
     FB_FIELD(fb_checker_params, cells)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store as half instead of float (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_checker(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    fb_checker_params *c = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, checker_keys, FB_NKEYS(checker_keys), "a checker layer", c);
    if (rc) return rc;
    if (c->cells > s->width || c->cells > s->height) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.cells", path);
        return fb_schema_error(v, sub, "%d squares do not fit a %d x %d image", c->cells, s->width, s->height);
    }
    return FB_OK;
}

typedef struct {
    K_CheckerParams p;
    uint32_t y0, rows;
} checker_push;

static void checker_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_CheckerParams *p = (const void *)g->params;
    float *out = planes[0];
    for (int r = 0; r < n; r++)
        for (uint32_t x = 0; x < p->width; x++)
            out[(size_t)r * p->width + x] = k_checker_pixel(*p, x, (uint32_t)(y0 + r));
}

static fb_result checker_init(fb_gen *g)
{
    const fb_checker_params *c = fb_layer_params(g->layer);
    K_CheckerParams *p = (void *)g->params;
    *p = (K_CheckerParams){(uint32_t)g->scene->width, (uint32_t)g->scene->height, (uint32_t)c->cells, 0};
    g->store.nchannels = 1;
    snprintf(g->store.channel_names[0], sizeof g->store.channel_names[0], "%s.Y", g->layer->name);
    g->store.channel_types[0] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    g->compute.native_rows = checker_rows;
    g->compute.shader.spv = checker_comp;
    g->compute.shader.spv_size = sizeof checker_comp;
    g->compute.shader.params_size = sizeof(K_CheckerParams);
    g->compute.shader.push_size = sizeof(checker_push);
    return FB_OK;
}

/* The plan's cost: seconds of one core per row (a checker pixel costs about as much as an op's). */
static fb_result checker_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    *total = 0;
    for (int y = 0; y < s->height; y++) rows[y] = s->width * 4e-9, *total += rows[y];
    return FB_OK;
}

const fb_gen_class fb_gen_checker = {
    .name = "checker",
    .synopsis = "checker [options] -o OUT.exr",
    .summary = "a checkerboard (the example generator of docs/architecture.md)",
    .what = "a checker layer",
    .keys = checker_keys,
    .nkeys = FB_NKEYS(checker_keys),
    .params_size = sizeof(fb_checker_params),
    .parse = parse_checker,
    .init = checker_init,
    .share = FB_SHARE_BAND, /* a function of the pixel: a plan cuts it into bands */
    .cost = checker_cost,
};
