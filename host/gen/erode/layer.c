/*
 * The erode layer: another layer's heights eroded by water (virtual pipes) and by slides above the
 * talus angle (erode.h), computed whole in prepare on the engine's backend; strips are copied out.
 *
 * Channels: NAME.Y (the settled height: bed plus the sediment still suspended), NAME.flow (the
 * time-averaged discharge per unit width), NAME.wear (material removed), NAME.deposition (material
 * laid down), NAME.sediment (suspended at the end), NAME.water (depth at the end).
 */
#include "engine.h"
#include "erode.h"
#include "exrio.h"
#include "gen_erode.h"

#include "heightmap.h"
#include "pngio.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec erode_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"erode\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"eroded\"",
     "layer name; channels NAME.Y, .flow, .wear, .deposition, .sediment, .water", FB_CORE},
    {"input", FB_K_REF, 0, 0, false, NULL, NULL, "the heights to erode: another layer's channel (\"layer\": its Y)",
     FB_FIELD(fb_erode_layer_params, input)},
    {"extent", FB_K_NUM, 0, 1e12, true, NULL, NULL,
     "the image's width in world units (the heights' unit); default: the input's world width, else 1024",
     FB_FIELD(fb_erode_layer_params, extent)},
    {"iterations", FB_K_INT, 1, 1000000, false, NULL, "200",
     "time steps over the duration (more: a smaller step; double them with the size)",
     FB_FIELD(fb_erode_layer_params, iterations)},
    {"duration", FB_K_NUM, 0, 1e9, true, NULL, "60", "simulated time, in time units",
     FB_FIELD(fb_erode_layer_params, duration)},
    {"rain", FB_K_NUM, 0, 1e6, false, NULL, "0.005", "water added everywhere, height per time unit",
     FB_FIELD(fb_erode_layer_params, rain)},
    {"gravity", FB_K_NUM, 0, 1e6, true, NULL, "9.81", "the acceleration that drives water down the pipes",
     FB_FIELD(fb_erode_layer_params, gravity)},
    {"capacity", FB_K_NUM, 0, 1e6, false, NULL, "0.05", "Kc: sediment carried per unit sin(slope) and unit speed",
     FB_FIELD(fb_erode_layer_params, capacity)},
    {"dissolve", FB_K_NUM, 0, 1e6, false, NULL, "0.5", "Ks: rate at which water takes up its capacity, per time unit",
     FB_FIELD(fb_erode_layer_params, dissolve)},
    {"deposit", FB_K_NUM, 0, 1e6, false, NULL, "1.0", "Kd: rate at which water drops sediment above it, per time unit",
     FB_FIELD(fb_erode_layer_params, deposit)},
    {"evaporation", FB_K_NUM, 0, 1e6, false, NULL, "0.2", "Ke: water lost, fraction per time unit",
     FB_FIELD(fb_erode_layer_params, evaporate)},
    {"depth", FB_K_NUM, 0, 1e6, true, NULL, "0.05",
     "the water depth that carries the full capacity; shallower water carries proportionally less",
     FB_FIELD(fb_erode_layer_params, depth)},
    {"talus", FB_K_NUM, 0, 89.9, false, NULL, "35", "thermal erosion: slopes steeper than this angle (degrees) slide",
     FB_FIELD(fb_erode_layer_params, talus)},
    {"thermal", FB_K_NUM, 0, 1e6, false, NULL, "0.5", "thermal erosion rate, per time unit (0: none)",
     FB_FIELD(fb_erode_layer_params, thermal)},
    {"heightmap", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write the eroded heights (Y) for engines: OUT.png (16-bit grey) or OUT.r16 (16-bit raw, little-endian)",
     FB_CORE},
    FB_HEIGHTMAP_KEYS,
    {"masks", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write the masks for texturing as grey PNGs: PREFIX.flow.png, PREFIX.wear.png, PREFIX.deposition.png, "
     "PREFIX.sediment.png, each from 0 to its own maximum (kept in the text chunk fractalbake/mask-max)",
     FB_FIELD(fb_erode_layer_params, prefix)},
    {"mask-bits", FB_K_INT, 8, 16, false, NULL, "16", "the masks' PNG depth: 8 or 16 bits",
     FB_FIELD(fb_erode_layer_params, mask_bits)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store the channels as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_erode(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    (void)s;
    fb_erode_layer_params *P = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, erode_keys, FB_NKEYS(erode_keys), "an erode layer", P);
    if (rc) return rc;
    char sub[256];
    const json_t *in = json_object_get(obj, "input");
    if (!in || json_is_number(in)) {
        snprintf(sub, sizeof sub, "%s.input", path);
        return fb_schema_error(v, sub,
                               in ? "expected another layer's heights (\"layer\" or \"layer.channel\"), not a number"
                                  : "required for an erode layer (the layer whose heights it erodes)");
    }
    if (P->mask_bits != 8 && P->mask_bits != 16) {
        snprintf(sub, sizeof sub, "%s.mask-bits", path);
        return fb_schema_error(v, sub, "a PNG's depth: expected 8 or 16, found %d", P->mask_bits);
    }
    const char *masks = P->prefix;
    if (masks[0]) {
        static const char *const names[4] = {"flow", "wear", "deposition", "sediment"};
        snprintf(sub, sizeof sub, "%s.masks", path);
        if (strlen(masks) >= sizeof P->masks[0] - 16)
            return fb_schema_error(v, sub, "file name longer than %zu characters", sizeof P->masks[0] - 16);
        for (int k = 0; k < 4; k++) snprintf(P->masks[k], sizeof P->masks[k], "%s.%s.png", masks, names[k]);
    } else if (json_object_get(obj, "mask-bits") && P->mask_bits != 16) {
        snprintf(sub, sizeof sub, "%s.mask-bits", path);
        return fb_schema_error(v, sub, "the masks' depth, and no \"masks\" are written");
    }
    return FB_OK;
}

/* The masks an erode layer writes (reserved with the other outputs before any work). */
static int erode_outputs(const fb_layer *L, const char **paths, const char **what, int max)
{
    const fb_erode_layer_params *P = fb_layer_params(L);
    int n = 0;
    for (int k = 0; k < 4 && P->masks[k][0] && n < max; k++) paths[n] = P->masks[k], what[n++] = "mask";
    return n;
}

/* ---- the layer --------------------------------------------------------------------------------- */

typedef struct erode_state {
    fb_source src; /* the input layer's channel (resolve) */
    float *height; /* bed + sediment */
    fb_erode_out out;
} erode_state;

static erode_state *state(const fb_gen *g)
{
    return g->owned;
}

static void erode_fini(fb_gen *g)
{
    erode_state *s = state(g);
    if (!s) return;
    free(s->height);
    fb_erode_out_free(&s->out);
}

static double extent_of(const fb_gen *g)
{
    const fb_erode_layer_params *P = fb_layer_params(g->layer);
    const erode_state *s = state(g);
    if (P->extent > 0) return P->extent;
    const fb_gen *src = s ? s->src.gen : NULL;
    if (src && src->prepared.has_world) return src->prepared.world[1] - src->prepared.world[0];
    return 1024;
}

/* The four masks as grey PNGs of P->mask_bits, each 0 at 0 and full scale at its own maximum. */
static fb_result write_masks(const fb_gen *g, const fb_erode_layer_params *P)
{
    const erode_state *s = state(g);
    const int w = g->scene->width, h = g->scene->height, full = P->mask_bits == 16 ? 65535 : 255;
    const size_t n = (size_t)w * h;
    const float *planes[4] = {s->out.flow, s->out.wear, s->out.deposit, s->out.sediment};
    void *pix = malloc(n * (P->mask_bits / 8));
    if (!pix) return fb_fail(FB_ERR_NOMEM, "layer %s: out of memory for its masks", g->layer->name);
    fb_result rc = FB_OK;
    for (int k = 0; k < 4 && !rc; k++) {
        float top = 0;
        for (size_t i = 0; i < n; i++) top = planes[k][i] > top ? planes[k][i] : top;
        for (size_t i = 0; i < n; i++) {
            double q = top > 0 && planes[k][i] > 0 ? (double)planes[k][i] / top * full + 0.5 : 0;
            unsigned v = q >= full ? (unsigned)full : (unsigned)q;
            if (P->mask_bits == 16)
                ((uint16_t *)pix)[i] = (uint16_t)v;
            else
                ((uint8_t *)pix)[i] = (uint8_t)v;
        }
        char mx[40];
        fb_format_shortest(top, mx, sizeof mx);
        const char *kv[2][2] = {{"fractalbake/mask-max", mx},
                                {"Description", "0 at 0, full scale at mask-max, linear between"}};
        rc = fb_png_write(P->masks[k], "mask", w, h, 1, P->mask_bits, pix, (const char *const(*)[2])kv, 2);
    }
    free(pix);
    return rc;
}

static fb_result erode_prepare(fb_gen *g, struct fb_engine *e, bool progress)
{
    erode_state *s = state(g);
    const fb_erode_layer_params *P = fb_layer_params(g->layer);
    const fb_scene *sc = g->scene;
    size_t n = (size_t)sc->width * sc->height;
    float *bed = malloc(n * sizeof *bed);
    if (!bed) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_result rc = fb_source_read(&s->src, g, "input", bed);
    double extent = extent_of(g);
    fb_erode_desc d = {.width = sc->width,
                       .height = sc->height,
                       .cell = extent / sc->width,
                       .iterations = P->iterations,
                       .duration = P->duration,
                       .rain = P->rain,
                       .gravity = P->gravity,
                       .capacity = P->capacity,
                       .dissolve = P->dissolve,
                       .deposit = P->deposit,
                       .evaporate = P->evaporate,
                       .depth = P->depth,
                       .talus = P->talus,
                       .thermal = P->thermal,
                       .bed = bed};
    fb_progress prog;
    char label[96];
    snprintf(label, sizeof label, "%s: erosion", g->layer->name);
    fb_progress_init(&prog, progress, label, "cells");
    double t0 = fb_now();
    if (!rc)
        rc = e->kind == FB_BACKEND_VULKAN ? fb_erode_run_vulkan(&d, e->vk, &prog, &s->out)
                                          : fb_erode_run_native(&d, e->pool, &prog, &s->out);
    fb_progress_finish(&prog);
    double secs = fb_now() - t0;
    if (!rc && !(s->height = malloc(n * sizeof *s->height))) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (rc) {
        free(bed);
        return rc;
    }
    double moved = 0, total0 = 0, total1 = 0;
    for (size_t i = 0; i < n; i++) {
        s->height[i] = s->out.bed[i] + s->out.sediment[i];
        moved += s->out.wear[i];
        total0 += bed[i];
        total1 += (double)s->out.bed[i] + s->out.sediment[i];
    }
    free(bed);
    free(s->out.bed), s->out.bed = NULL;                       /* the strips need only the settled height */
    if (P->masks[0][0] && (rc = write_masks(g, P))) return rc; /* committed with the EXR */
    g->prepared.gpu_seconds = s->out.gpu_seconds;
    if (s->src.gen->prepared.has_world) {
        g->prepared.has_world = true;
        memcpy(g->prepared.world, s->src.gen->prepared.world, sizeof g->prepared.world);
        g->prepared.epsg = s->src.gen->prepared.epsg;
    }
    if (sc->height > 1) g->store.preview_shade[0] = g->store.preview_shade[1] = extent / sc->width;
    double cell_iters = (double)n * P->iterations;
    snprintf(g->prepared.summary, sizeof g->prepared.summary,
             "%s: %d x %d cells of %.4g, %d iterations over %.4g; material moved %.6g, mass change %.3g (relative); "
             "%.3f s, %.3g Mcell-iterations/s",
             g->layer->name, sc->width, sc->height, d.cell, P->iterations, P->duration, moved,
             total0 != 0 ? (total1 - total0) / fabs(total0) : total1 - total0, secs, cell_iters / secs * 1e-6);
    snprintf(g->prepared.summary_json, sizeof g->prepared.summary_json,
             "{\"layer\": \"%s\", \"generator\": \"erode\", \"width\": %d, \"height\": %d, \"cell\": %.9g, "
             "\"iterations\": %d, \"moved\": %.9g, \"seconds\": %.6f}",
             g->layer->name, sc->width, sc->height, d.cell, P->iterations, moved, secs);
    return FB_OK;
}

static void erode_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const erode_state *s = state(g);
    size_t at = (size_t)y0 * g->scene->width, len = (size_t)n * g->scene->width * 4;
    const float *src[6] = {s->height, s->out.flow, s->out.wear, s->out.deposit, s->out.sediment, s->out.water};
    for (int c = 0; c < 6; c++)
        if (planes[c]) memcpy(planes[c], src[c] + at, len);
}

/* The model's grids (4 x 16 bytes a cell) and its result (6 floats), plus the input (4): all at the
 * peak; five channels kept for the strips. */
static uint64_t erode_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    (void)e;
    uint64_t npx = (uint64_t)g->scene->width * g->scene->height;
    *hold = 5 * 4 * npx;
    return fb_erode_memory(g->scene->width, g->scene->height) + 4 * npx + 4 * npx;
}

static fb_result erode_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset);

static fb_result erode_init(fb_gen *g)
{
    uint64_t hold, peak = erode_memory(g, NULL, &hold);
    char who[96];
    snprintf(who, sizeof who, "erosion of %d x %d cells", g->scene->width, g->scene->height);
    fb_result rc = fb_memory_check(&g->run.budget, peak, who);
    if (rc) return rc;
    erode_state *s = calloc(1, sizeof *s);
    if (!s) return fb_fail(FB_ERR_NOMEM, "out of memory");
    g->owned = s;
    g->fini = erode_fini;
    static const char *const suffix[6] = {"Y", "flow", "wear", "deposition", "sediment", "water"};
    g->store.nchannels = 6;
    for (int c = 0; c < g->store.nchannels; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    }
    g->store.preview_channel = 0;
    if (g->scene->height > 1) g->store.preview_shade[0] = g->store.preview_shade[1] = extent_of(g) / g->scene->width;
    g->compute.native_rows = erode_rows;
    g->prepare = erode_prepare;
    g->memory = erode_memory;
    g->resolve = erode_resolve;
    g->prepared.gpu_seconds = -1;
    return FB_OK;
}

static fb_result erode_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset)
{
    (void)plane_offset;
    const fb_erode_layer_params *P = fb_layer_params(g->layer);
    return fb_source_find(&state(g)->src, g, gens, &P->input, "input", NULL);
}

static int erode_refs(fb_layer *L, fb_ref_slot *out)
{
    fb_erode_layer_params *P = (void *)L->params;
    out[0] = (fb_ref_slot){&P->input, "input", NULL};
    return 1;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). Memory-bound
 * passes: 1024 x 1024 x 50 iterations ran at 1.8 Mcell-iterations/s on one loaded core beside the
 * peer's 1.84 (bench/RESULTS.md); 100 ns a cell-iteration is its unloaded rate. */
static fb_result erode_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    (void)rows;
    const fb_erode_layer_params *P = fb_layer_params(&s->layers[layer]);
    *total = (double)s->width * s->height * (P->iterations * 1.0e-7 /* a cell-iteration */ + 2.0e-8 /* a pixel */);
    return FB_OK;
}

const fb_gen_class fb_gen_erode = {
    .name = "erode",
    .synopsis = NULL,
    .summary = "another layer's heights eroded by water (virtual pipes) and by slides (talus angle), with masks",
    .what = "an erode layer",
    .keys = erode_keys,
    .nkeys = FB_NKEYS(erode_keys),
    .params_size = sizeof(fb_erode_layer_params),
    .parse = parse_erode,
    .refs = erode_refs,
    .outputs = erode_outputs,
    .init = erode_init,
    .share = FB_SHARE_WHOLE,
    .cost = erode_cost,
    .example = "[{\"type\": \"fbm\", \"name\": \"h\", \"octaves\": 5}, {\"type\": \"erode\", \"name\": \"e\", "
               "\"input\": \"h\", \"extent\": 8, \"iterations\": 20, \"duration\": 10}]",
    .tolerance = {0, 0}, /* exact arithmetic (kernels/exact.h): the same bits on every backend */
    .bench = fb_erode_bench,
};
