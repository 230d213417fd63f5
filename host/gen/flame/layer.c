/*
 * The flame generator: a .flame genome (flam3's XML) rendered as flam3 3.1.1 renders it, with the
 * chaos game of kernels/flame.h on the native thread pool (game.c) or in a Vulkan shader
 * (shaders/flame_body.glsl) into a fixed-point histogram, the same sums either way, then flam3's
 * density estimation, spatial filter and tone map on the host (render.c; docs/flames.md).
 *
 * Channels: NAME.R, .G, .B (linear: the sRGB decoding of flam3's 8-bit output, the background
 * composited under), NAME.A (flam3's alpha), NAME.acc_R, .acc_G, .acc_B, .acc_A (the filtered
 * accumulation at brightness 1: what the tone map reads) and NAME.count (hits).
 */
#include "animate.h"
#include "bake.h"
#include "gen_flame.h"
#include "game.h"

#include "flame64_comp.h"
#include "flame_comp.h"
#include "flame_fold_comp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FB_FLAME_PALETTES "/usr/share/flam3/flam3-palettes.xml"

static const fb_keyspec flame_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"flame\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"flame\"",
     "layer name; channels NAME.R, .G, .B, .A, .acc_R, .acc_G, .acc_B, .acc_A, .count (flag: --layer)", FB_CORE},
    {"file", FB_K_PATH, 0, 0, false, NULL, NULL, "a .flame file (flam3's XML genomes); required",
     FB_FIELD(fb_flame_params, file)},
    {"flame", FB_K_STRING, 0, 0, false, NULL, NULL,
     "the <flame> to render: its name attribute, or its index from 0 (default: the first)",
     FB_FIELD(fb_flame_params, pick)},
    {"quality", FB_K_NUM, 0, 1e6, false, NULL, "0", "samples per pixel (0: the genome's quality attribute)",
     FB_FIELD(fb_flame_params, quality)},
    {"time", FB_K_NUM, -1e9, 1e9, false, NULL, NULL,
     "render the file's flames as keyframes at this time, as flam3-animate does (default: a still of one flame)",
     FB_FIELD(fb_flame_params, time)},
    {"temporal-samples", FB_K_INT, 0, 100000, false, NULL, NULL,
     "with time: the chaos games a frame's motion blur is made of (default: the genome's temporal_samples)",
     FB_FIELD(fb_flame_params, temporal_samples)},
    {"palettes", FB_K_PATH, 0, 0, false, NULL, "\"" FB_FLAME_PALETTES "\"",
     "flam3's palette library, for genomes with palette=\"N\"", FB_FIELD(fb_flame_params, palettes)},
    {"brightness", FB_K_NUM, 0, 1e6, false, NULL, NULL, "the tone map's brightness (default: the genome's)",
     FB_FIELD(fb_flame_params, tone.brightness)},
    {"gamma", FB_K_NUM, 0, 100, true, NULL, NULL, "the tone map's gamma (default: the genome's)",
     FB_FIELD(fb_flame_params, tone.gamma)},
    {"gamma-threshold", FB_K_NUM, 0, 1e6, false, NULL, NULL,
     "below it the gamma curve is linear (default: the genome's)", FB_FIELD(fb_flame_params, tone.gamma_threshold)},
    {"vibrancy", FB_K_NUM, -10, 10, false, NULL, NULL, "1: gamma on alpha, 0: per channel (default: the genome's)",
     FB_FIELD(fb_flame_params, tone.vibrancy)},
    {"highlight-power", FB_K_NUM, -1e6, 1e6, false, NULL, NULL,
     "over-bright pixels: < 0 clip, 0 keep the hue, larger fade to white (default: the genome's)",
     FB_FIELD(fb_flame_params, tone.highlight_power)},
    {"background", FB_K_NUMLIST, 0, 1, false, NULL, NULL, "background R,G,B in [0, 1] (default: the genome's)", 3,
     FB_FIELD(fb_flame_params, tone.background)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "true", "store R, G, B, A as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

/* The file's keyframes (*keys, *n: malloc'd). */
static fb_result read_keys(const fb_flame_params *f, fb_flame_genome **keys, int *n)
{
    char *text = NULL;
    size_t len = 0;
    fb_result rc = fb_flame_slurp(f->file, &text, &len);
    if (!rc) rc = fb_flame_read_keys(text, len, f->file, f->palettes, keys, n);
    free(text);
    return rc;
}

/* The frame at f->time of the file's keyframes. */
static fb_result frame_of(const fb_flame_params *f, fb_flame_frame *fr)
{
    fb_flame_genome *keys = NULL;
    int n = 0;
    fb_result rc = read_keys(f, &keys, &n);
    if (!rc) rc = fb_flame_frame_init(keys, n, f->time, f->temporal_samples, fr);
    free(keys);
    return rc;
}

static fb_result parse_flame(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    char sub[256];
    fb_flame_params *f = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, flame_keys, FB_NKEYS(flame_keys), "a flame layer", f);
    if (rc) return rc;
    if (!f->file[0]) {
        snprintf(sub, sizeof sub, "%s.file", path);
        return fb_schema_error(v, sub, "a flame layer needs a .flame file");
    }
    f->animated = json_object_get(obj, "time") != NULL;
    if (f->animated && f->pick[0]) {
        snprintf(sub, sizeof sub, "%s.flame", path);
        return fb_schema_error(v, sub, "with a time every <flame> of the file is a keyframe: no flame picks one");
    }
    /* the tone map the genome (or the frame) gives */
    fb_flame_tone base;
    if (f->animated) {
        fb_flame_frame fr;
        if ((rc = frame_of(f, &fr))) return rc;
        f->genome = fr.frame;
        base =
            (fb_flame_tone){fr.brightness, fr.gamma,           fr.gamma_threshold,
                            fr.vibrancy,   fr.highlight_power, {fr.background[0], fr.background[1], fr.background[2]}};
        fb_flame_frame_fini(&fr);
    } else {
        char *text = NULL;
        size_t len = 0;
        if ((rc = fb_flame_slurp(f->file, &text, &len))) return rc;
        rc = fb_flame_read(text, len, f->file, f->pick[0] ? f->pick : NULL, f->palettes, &f->genome, NULL);
        free(text);
        if (rc) return rc;
        const fb_flame_genome *gn = &f->genome;
        base = (fb_flame_tone){gn->brightness,      gn->gamma,
                               gn->gamma_threshold, gn->vibrancy,
                               gn->highlight_power, {gn->background[0], gn->background[1], gn->background[2]}};
    }
    /* a tone key not given is the genome's (the frame's) */
    fb_flame_tone *t = &f->tone;
    if (!json_object_get(obj, "brightness")) t->brightness = base.brightness;
    if (!json_object_get(obj, "gamma")) t->gamma = base.gamma;
    if (!json_object_get(obj, "gamma-threshold")) t->gamma_threshold = base.gamma_threshold;
    if (!json_object_get(obj, "vibrancy")) t->vibrancy = base.vibrancy;
    if (!json_object_get(obj, "highlight-power")) t->highlight_power = base.highlight_power;
    for (int k = 0; k < 3 && !json_object_get(obj, "background"); k++) t->background[k] = base.background[k];
    (void)s;
    return FB_OK;
}

/* ---- the chaos game --------------------------------------------------------------------------- */

typedef struct flame_state {
    fb_flame_setup S;
    float *acc[4];
    uint32_t *count;
    uint64_t bad;
    double seconds;
    fb_flame_stats stats;  /* the last prepare's game: fb_gen_flame_stats */
    uint32_t cr0, cr1;     /* the chains this run plays: all, or a points part's share */
    int nsums;             /* a points part: the 64-bit sums its histogram is stored as (flame_sums) */
    fb_flame_cell *hist;   /* a points part: its histogram, kept for its sums channels */
    fb_flame_genome *keys; /* animated: the file's keyframes (else NULL) and the frame */
    int nkeys;
    fb_flame_frame frame;
} flame_state;

static flame_state *state(const fb_gen *g)
{
    return g->owned;
}

/* The points of the chains [cr0, cr1) of S (the last chain of all may be shorter). */
static double chain_points(const fb_flame_setup *S, uint32_t cr0, uint32_t cr1)
{
    const K_FlameParams *p = &S->p;
    double n = (double)(cr1 - cr0) * p->len;
    return cr1 == p->chains && cr1 > cr0 ? n - (p->len - p->last_len) : n;
}

/* The image planes the filter fills: the accumulations and the hit count. */
static fb_result alloc_image(flame_state *st, size_t npix)
{
    for (int k = 0; k < 4; k++)
        if (!(st->acc[k] = fb_malloc_large(npix * sizeof(float)))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!(st->count = fb_malloc_large(npix * sizeof(uint32_t)))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    return FB_OK;
}

/* Density estimation and the spatial filter of the total histogram (taken over: a points part keeps
 * it for its sums channels, else it is freed). */
static fb_result finish(flame_state *st, fb_flame_cell *total, fb_pool *pool)
{
    fb_result rc = fb_flame_filter(&st->S, total, st->acc, st->count, pool);
    if (st->nsums && !rc)
        st->hist = total;
    else
        free(total);
    return rc;
}

/* ---- the chaos game on Vulkan ------------------------------------------------------------------ */

_Static_assert(sizeof(K_FlameParams) == 108, "std430 struct of 27 words");
_Static_assert(sizeof(K_FlameXform) == 80, "std430 struct of 20 words");
_Static_assert(sizeof(K_FlameVar) == 48, "std140 array of structs of 12 words");
_Static_assert(sizeof(K_FlameChain) == 40, "std430 struct of 10 words");

/* Points per dispatch (all chains together): well under a second on lavapipe, so that the progress
 * bar moves and no submission runs long. */
#define FLAME_POINTS_PER_DISPATCH (1u << 22)
#define FLAME_MAX_GROUPS          65535u /* Vulkan's least maxComputeWorkGroupCount[0] */
/* lavapipe ends a loop nest after 65535 iterations in all (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS,
 * a guard against endless loops), silently: a dispatch's steps are kept under it (loop_steps). */
#define FLAME_LOOP_ITERATIONS 60000u

enum { FB_PARAMS, FB_XF, FB_VAR, FB_DIST, FB_PAL, FB_CHAINS, FB_HIST, FB_CARRY, FB_NBUF };

typedef struct flame_push {
    uint32_t c0, c1, step0, nsteps;
} flame_push;

/* Fields a histogram cell has on the device: hits, r, g, b for opaque genomes; else r, g, b, a,
 * opacity, hits (flame_body.glsl). */
static uint32_t device_fields(const fb_flame_setup *S)
{
    return fb_flame_cell_bytes(S) == 16 ? 4u : 6u;
}

/* Field f of cell i of the device's 32-bit histogram as its exact 64-bit sum: the word plus 2^32
 * for each carry out of it. */
static uint64_t device_field(const uint32_t *hist, const uint32_t *carry, size_t at)
{
    return ((uint64_t)carry[at] << 32) + hist[at];
}

/* The points one fold interval of the 64-bit histogram may take (kernels/flame.h). */
#define FOLD_POINTS ((1ull << K_FLAME_HIT_BITS) - 1)

/* The 64-bit histogram's words a cell (kernels/flame.h), and its totals' (shaders/flame_fold.comp):
 * hits, red, green, blue and for translucent genomes alpha, opacity. */
static uint32_t device_words(const fb_flame_setup *S)
{
    return K_FLAME_WORDS(device_fields(S) == 4);
}

/* Adds the device's histogram into total (64-bit cells). 32-bit atomics: hist and carry as
 * flame_body.glsl's flame.comp leaves them. 64-bit: the words since the last fold in hist64 and,
 * where the run folded, the totals before them in tot (else NULL). */
static void device_to_total(const fb_flame_setup *S, const uint32_t *hist, const uint32_t *carry,
                            const uint64_t *hist64, const uint64_t *tot, fb_flame_cell *total)
{
    size_t cells = (size_t)S->p.hist_w * S->p.hist_h;
    uint32_t F = device_fields(S), W = device_words(S);
    for (size_t i = 0; i < cells; i++) {
        size_t at = i * F;
        fb_flame_cell *c = &total[i];
        uint64_t v[6] = {0}; /* hits, red, green, blue, alpha, opacity */
        if (hist64) {
            const uint64_t *w = hist64 + i * W;
            v[0] = w[0] & ((1ull << K_FLAME_HIT_BITS) - 1), v[1] = w[0] >> K_FLAME_HIT_BITS;
            for (uint32_t k = 1; k < W; k++) v[1 + k] = w[k];
            for (uint32_t k = 0; tot && k <= W; k++) v[k] += tot[i * (W + 1) + k];
        } else if (F == 4) {
            for (int k = 0; k < 4; k++) v[k] = device_field(hist, carry, at + k);
        } else {
            v[0] = device_field(hist, carry, at + 5);
            for (int k = 0; k < 5; k++) v[1 + k] = device_field(hist, carry, at + k);
        }
        if (F == 4) v[4] = v[5] = K_FLAME_OPAQUE * v[0];
        for (int k = 0; k < 5; k++) c->c[k] += v[1 + k];
        c->hits += v[0];
    }
}

/* Whether the run folds the 64-bit histogram: it plays more steps (plotted or not) than a fold
 * interval holds points. */
static bool folds(const fb_flame_setup *S, uint32_t cr0, uint32_t cr1)
{
    return (uint64_t)(cr1 - cr0) * (S->p.fuse + S->p.len) > FOLD_POINTS;
}

/* The device's buffers: the histogram, its carries (32-bit atomics) or the totals it is folded into
 * (64-bit, where the run folds), and the chains' state of one batch. */
static void device_bytes(const fb_flame_setup *S, uint32_t cr0, uint32_t cr1, bool wide, uint64_t *hist,
                         uint64_t *extra, uint64_t *chains)
{
    uint64_t cells = (uint64_t)S->p.hist_w * S->p.hist_h, n = cr1 - cr0;
    uint64_t batch = (uint64_t)FLAME_MAX_GROUPS * 64u;
    uint32_t W = device_words(S);
    *hist = (wide ? 8ull * W : 4ull * device_fields(S)) * cells;
    *extra = wide ? (folds(S, cr0, cr1) ? 8ull * (W + 1) * cells : 0) : *hist;
    *chains = sizeof(K_FlameChain) * (n < batch ? (n ? n : 1) : batch);
}

/* The 64-bit histogram where the device has 64-bit atomics and its words, and the totals where the
 * run folds, fit a buffer each; else the 32-bit one with its carries. The sums are the same. */
static bool wide_histogram(const fb_flame_setup *S, uint32_t cr0, uint32_t cr1, vkc_context *vk)
{
    uint64_t hist, extra, chains, range = vkc_info(vk)->max_storage_buffer_range;
    device_bytes(S, cr0, cr1, true, &hist, &extra, &chains);
    return vkc_info(vk)->int64_atomics && hist <= range && extra <= range;
}

/* Adds the 64-bit words into the totals and clears them (shaders/flame_fold.comp). */
static fb_result fold(vkc_context *vk, vkc_pipeline *pipe, vkc_buffer *hist, vkc_buffer *tot, size_t cells, double *gpu)
{
    vkc_job *job = NULL;
    fb_result rc = vkc_job_create(vk, pipe, &job);
    uint64_t groups = (cells + 63) / 64, gx = groups < FLAME_MAX_GROUPS ? groups : FLAME_MAX_GROUPS;
    const uint32_t push[2] = {(uint32_t)cells, (uint32_t)gx * 64}; /* cells, cells a row of groups */
    double t = -1;
    if (!rc)
        rc = vkc_job_submit(vk, job, (vkc_buffer *[2]){hist, tot}, 2, push,
                            (const uint32_t[3]){(uint32_t)gx, (uint32_t)((groups + gx - 1) / gx), 1});
    if (!rc) rc = vkc_job_wait(vk, job, &t);
    if (t > 0) *gpu += t;
    vkc_job_destroy(vk, &job);
    return rc;
}

/* The steps a dispatch may run per chain within FLAME_LOOP_ITERATIONS (lavapipe ends a shader's
 * loops after 65535 iterations in all): a step is one iteration of the steps' loop, up to five tries
 * of an xform and the final xform. An xform (kernels/flame.h, K_FLAME_ONCE) is a pass over the
 * genome's g variations (g + 1 iterations, and at most g + 4 more finding each next one in the
 * masks) and the corrections of the portable division and square root (kernels/exact.h: at most 3
 * iterations each; at most 7 of them in the precalcs and 8 in a variation, `most` variations). */
static uint32_t loop_steps(const fb_flame_setup *S, const uint32_t mask[4])
{
    uint32_t most = 0, g = 0;
    for (uint32_t i = 0; i < S->p.nxf + (S->p.final_xf != K_FLAME_NONE); i++)
        if (S->xf[i].nvar > most) most = S->xf[i].nvar;
    for (int w = 0; w < 4; w++) g += (uint32_t)__builtin_popcount(mask[w]);
    uint32_t apply = (g + 1) + (g + 4) + 3 * (7 + 8 * most);
    return FLAME_LOOP_ITERATIONS / (1 + 5 * apply + (S->p.final_xf != K_FLAME_NONE ? apply : 0));
}

/* Steps a chain per dispatch of n chains: on a CPU device about FLAME_POINTS_PER_DISPATCH points (a
 * few hundred ms on lavapipe, so that the progress bar moves; fewer where lavapipe's loop limit
 * would cut a chain short); on a GPU as many as a fold interval holds (2^26 points: milliseconds),
 * since each job's end costs a round trip and, on a discrete GPU, vkc's copy of its buffers back to
 * the host. */
static uint32_t steps_per_dispatch(const fb_flame_setup *S, const vkc_context *vk, uint32_t n, const uint32_t mask[4])
{
    uint64_t per = FOLD_POINTS / n;
    if (!strcmp(vkc_info(vk)->type, "cpu")) {
        per = FLAME_POINTS_PER_DISPATCH / n;
        if (per > loop_steps(S, mask)) per = loop_steps(S, mask);
    }
    return per ? (uint32_t)per : 1;
}

/* Chains [cr0, cr1) in the shader, in batches of at most 65535 workgroups, each in dispatches of
 * steps_per_dispatch; the 64-bit histogram folded before a dispatch could take it past a fold
 * interval; then added into total. */
static fb_result play_vulkan(fb_gen *g, fb_engine *e, const fb_flame_setup *S, uint32_t cr0, uint32_t cr1,
                             fb_flame_cell *total, fb_progress *prog, double *gpu, uint64_t *bad)
{
    vkc_context *vk = e->vk;
    size_t cells = (size_t)S->p.hist_w * S->p.hist_h;
    bool wide = wide_histogram(S, cr0, cr1, vk), folding = wide && folds(S, cr0, cr1);
    uint64_t hist_bytes, extra_bytes, chain_bytes, range = vkc_info(vk)->max_storage_buffer_range;
    device_bytes(S, cr0, cr1, wide, &hist_bytes, &extra_bytes, &chain_bytes);
    if (hist_bytes > range || chain_bytes > range)
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: the flame's histogram (%u x %u cells) needs %llu MiB in one buffer; this device "
                       "allows %llu MiB (a smaller size or supersample, or --backend native)",
                       g->layer->name, S->p.hist_w, S->p.hist_h, (unsigned long long)(hist_bytes >> 20),
                       (unsigned long long)(range >> 20));
    vkc_pipeline *pipe = NULL, *fold_pipe = NULL;
    vkc_job *job = NULL;
    vkc_buffer *buf[FB_NBUF] = {0}, *tot = NULL;
    uint32_t nxf = S->p.nxf + (S->p.final_xf != K_FLAME_NONE), nvar = S->nvar ? S->nvar : 1;
    /* flame_body.glsl's specialisation: flags, the genome's variations as 4 masks, the tables' sizes */
    uint32_t spec[7] = {
        (device_fields(S) == 4) | S->linear_palette << 1 | (S->p.final_xf != K_FLAME_NONE) << 2, 0, 0, 0, 0, nxf, nvar};
    for (uint32_t v = 0; v < S->nvar; v++) spec[1 + S->var[v].id / 32] |= 1u << (S->var[v].id % 32);
    for (uint32_t f = 0; f < nxf; f++)
        if (S->xf[f].preblur != 0.0f) spec[1 + K_V_PRE_BLUR / 32] |= 1u << (K_V_PRE_BLUR % 32);
    /* the parameters, xforms, variations and palette: uniform buffers (flame_body.glsl), their sizes
     * in std140 (the parameters' block rounded up to 16 bytes); with 64-bit atomics the carries'
     * binding is not used */
    const uint64_t sizes[FB_NBUF] = {(sizeof S->p + 15) & ~(uint64_t)15,
                                     sizeof(K_FlameXform) * nxf,
                                     sizeof(K_FlameVar) * nvar,
                                     4ull * S->ndist,
                                     sizeof S->palq,
                                     chain_bytes,
                                     hist_bytes,
                                     wide ? 16 : extra_bytes};
    const uint32_t uniform = 1u << FB_PARAMS | 1u << FB_XF | 1u << FB_VAR | 1u << FB_PAL;
    for (int b = 0; b < FB_NBUF; b++)
        if ((uniform >> b & 1u) && sizes[b] > vkc_info(vk)->max_uniform_buffer_range)
            return fb_fail(FB_ERR_INPUT,
                           "layer %s: the flame's tables (%u xforms, %u variations) need %llu bytes in one uniform "
                           "buffer; this device allows %llu (--backend native)",
                           g->layer->name, nxf, S->nvar, (unsigned long long)sizes[b],
                           (unsigned long long)vkc_info(vk)->max_uniform_buffer_range);
    fb_result rc = vkc_pipeline_create(vk,
                                       &(vkc_pipeline_desc){.spv = wide ? flame64_comp : flame_comp,
                                                            .spv_size = wide ? sizeof flame64_comp : sizeof flame_comp,
                                                            .push_size = sizeof(flame_push),
                                                            .buffers = FB_NBUF,
                                                            .uniform = uniform,
                                                            .spec = spec,
                                                            .nspec = 7,
                                                            .name = g->layer->name},
                                       &pipe);
    const uint32_t fold_spec[2] = {device_fields(S) == 4, K_FLAME_HIT_BITS};
    if (!rc && folding)
        rc = vkc_pipeline_create(vk,
                                 &(vkc_pipeline_desc){FB_SPV(flame_fold_comp), .push_size = 8, .buffers = 2,
                                                      .spec = fold_spec, .nspec = 2, .name = g->layer->name},
                                 &fold_pipe);
    for (int b = 0; b < FB_NBUF && !rc; b++) rc = vkc_buffer_create(vk, sizes[b], &buf[b]);
    if (!rc && folding) rc = vkc_buffer_create(vk, extra_bytes, &tot);
    const void *data[FB_PAL + 1] = {&S->p, S->xf, S->var, S->dist, S->palq};
    for (int b = 0; b <= FB_PAL && !rc; b++)
        rc = vkc_buffer_upload(vk, buf[b], data[b], b == FB_PARAMS ? sizeof S->p : sizes[b]);
    void *zero = rc ? NULL : calloc(1, hist_bytes > extra_bytes ? hist_bytes : extra_bytes);
    if (!rc && !zero) rc = fb_fail(FB_ERR_NOMEM, "out of memory for the flame's histogram");
    for (int b = FB_HIST; b <= FB_CARRY && !rc; b++) rc = vkc_buffer_upload(vk, buf[b], zero, sizes[b]);
    if (!rc && folding) rc = vkc_buffer_upload(vk, tot, zero, extra_bytes);
    free(zero);
    if (!rc) rc = vkc_job_create(vk, pipe, &job);
    uint32_t steps = S->p.fuse + S->p.len, batch = FLAME_MAX_GROUPS * 64u;
    uint64_t since = 0; /* steps played since the last fold: a bound on the points any cell took */
    double all = chain_points(S, cr0, cr1);
    for (uint32_t b0 = cr0; b0 < cr1 && !rc; b0 += batch) {
        uint32_t b1 = cr1 - b0 > batch ? b0 + batch : cr1, n = b1 - b0;
        uint32_t per = steps_per_dispatch(S, vk, n, spec + 1);
        for (uint32_t t0 = 0; t0 < steps && !rc; t0 += per) {
            uint64_t played = (uint64_t)n * (steps - t0 < per ? steps - t0 : per);
            if (folding && since + played > FOLD_POINTS) {
                rc = fold(vk, fold_pipe, buf[FB_HIST], tot, cells, gpu);
                since = 0;
            }
            since += played;
            flame_push push = {b0, b1, t0, per};
            uint32_t groups[3] = {(n + 63) / 64, 1, 1};
            double t = -1;
            if (!rc) rc = vkc_job_submit(vk, job, buf, FB_NBUF, &push, groups);
            if (!rc) rc = vkc_job_wait(vk, job, &t);
            if (t > 0) *gpu += t;
            double done = (double)(b0 - cr0) * S->p.len + (double)n * fmin(t0 + per, steps) / steps * S->p.len;
            if (prog) fb_progress_update(prog, (uint64_t)fmin(done, all), (uint64_t)all);
        }
        const K_FlameChain *ch = rc ? NULL : vkc_buffer_data(buf[FB_CHAINS]);
        for (uint32_t i = 0; ch && i < n; i++) *bad += ch[i].bad;
    }
    if (!rc && wide)
        device_to_total(S, NULL, NULL, vkc_buffer_data(buf[FB_HIST]), folding ? vkc_buffer_data(tot) : NULL, total);
    else if (!rc)
        device_to_total(S, vkc_buffer_data(buf[FB_HIST]), vkc_buffer_data(buf[FB_CARRY]), NULL, NULL, total);
    vkc_job_destroy(vk, &job);
    for (int b = 0; b < FB_NBUF; b++) vkc_buffer_destroy(vk, &buf[b]);
    vkc_buffer_destroy(vk, &tot);
    vkc_pipeline_destroy(vk, &pipe);
    vkc_pipeline_destroy(vk, &fold_pipe);
    return rc;
}

/* Chains [cr0, cr1) of S into total, on the device or the pool. */
static fb_result play(fb_gen *g, fb_engine *e, const fb_flame_setup *S, uint32_t cr0, uint32_t cr1,
                      fb_flame_cell *total, fb_progress *prog, double *gpu)
{
    flame_state *st = state(g);
    if (e->kind == FB_BACKEND_VULKAN) {
        if (*gpu < 0) *gpu = 0;
        return play_vulkan(g, e, S, cr0, cr1, total, prog, gpu, &st->bad);
    }
    int threads = e->pool ? fb_pool_threads(e->pool) : 1;
    return fb_flame_play(S, e->pool, threads, g->run.scalar, cr0, cr1, total, &st->bad, prog);
}

/* A points part's share [*c0, *c1) of n chains (all of them in a whole bake): any split sums to
 * the whole histogram. */
static void part_chains(const fb_gen *g, uint32_t n, uint32_t *c0, uint32_t *c1)
{
    *c0 = 0, *c1 = n;
    if (g->run.points_part[1] > 0) {
        uint64_t k = (uint64_t)g->run.points_part[0], parts = (uint64_t)g->run.points_part[1];
        *c0 = (uint32_t)(n * (k - 1) / parts), *c1 = (uint32_t)(n * k / parts);
    }
}

/* The seed of temporal sample t: the scene's for the first, a hash of it and t for the rest, so that
 * no two samples play the same chains. */
static uint32_t sample_seed(uint32_t seed, int t)
{
    uint32_t h = seed ^ (uint32_t)t * 0x9E3779B9u;
    h ^= h >> 16, h *= 0x7feb352du, h ^= h >> 15, h *= 0x846ca68bu, h ^= h >> 16;
    return t ? h : seed;
}

/* Temporal sample t's game: the genome at its time, 1/n of the points, its palette times its weight
 * (rect.c's temporal sample loop); *c0, *c1 the chains this run plays. */
static fb_result sample_setup(fb_gen *g, int t, fb_flame_genome *at, fb_flame_setup *T, uint32_t *c0, uint32_t *c1)
{
    flame_state *st = state(g);
    const fb_flame_params *f = fb_layer_params(g->layer);
    const fb_flame_frame *fr = &st->frame;
    fb_result rc = fb_flame_interpolate(st->keys, st->nkeys, f->time + fr->delta[t], at);
    if (!rc)
        rc = fb_flame_setup_sample(at, &st->S, f->quality, sample_seed(g->scene->seed, t), 1.0 / fr->n, fr->weight[t],
                                   T);
    if (!rc) part_chains(g, T->p.chains, c0, c1);
    return rc;
}

/* An animated frame's temporal samples into total, in order: natively FB_FLAME_BATCH at a time into
 * the threads' histograms, which last the whole frame (a sample's share of the points is small: a
 * histogram or a wake-up of the pool each would cost more than its game); on Vulkan one after
 * another. The tone map's k2 is the last sample's over the mean weight. */
static fb_result play_samples(fb_gen *g, fb_engine *e, fb_flame_cell *total, fb_progress *prog, double *gpu,
                              double *points, uint32_t *chains)
{
    flame_state *st = state(g);
    const fb_flame_frame *fr = &st->frame;
    bool native = e->kind != FB_BACKEND_VULKAN;
    int nb = native ? FB_FLAME_BATCH : 1;
    fb_flame_genome *at = malloc(sizeof *at);
    fb_flame_setup *T = calloc((size_t)nb, sizeof *T);
    const fb_flame_setup *Tp[FB_FLAME_BATCH];
    uint32_t cr[FB_FLAME_BATCH][2];
    fb_flame_hists H = {0};
    fb_result rc = at && T ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc && native)
        rc = fb_flame_hists_init(&H, &st->S, false, e->pool, e->pool ? fb_pool_threads(e->pool) : 1, total);
    for (int t0 = 0; t0 < fr->n && !rc; t0 += nb) {
        int n = fr->n - t0 < nb ? fr->n - t0 : nb;
        for (int i = 0; i < n && !rc; i++) {
            rc = sample_setup(g, t0 + i, at, &T[i], &cr[i][0], &cr[i][1]);
            Tp[i] = &T[i];
            if (!rc) *points += chain_points(&T[i], cr[i][0], cr[i][1]), *chains += cr[i][1] - cr[i][0];
        }
        if (!rc && native) rc = fb_flame_hists_play_batch(&H, Tp, (const uint32_t(*)[2])cr, n, g->run.scalar);
        if (!rc && !native) rc = play(g, e, &T[0], cr[0][0], cr[0][1], total, NULL, gpu);
        if (!rc && t0 + n == fr->n) st->S.k2 = T[n - 1].k2 / fr->sumfilt;
        for (int i = 0; i < n; i++) fb_flame_setup_fini(&T[i]);
        fb_progress_update(prog, (uint64_t)(t0 + n), (uint64_t)fr->n);
    }
    if (!rc && native) fb_flame_hists_fold(&H, &st->bad);
    fb_flame_hists_fini(&H);
    free(T);
    free(at);
    return rc;
}

static fb_result flame_prepare(fb_gen *g, fb_engine *e, bool progress)
{
    flame_state *st = state(g);
    const fb_flame_setup *S = &st->S;
    size_t cells = (size_t)S->p.hist_w * S->p.hist_h, npix = (size_t)g->scene->width * g->scene->height;
    fb_flame_cell *total = fb_flame_zalloc(cells * sizeof *total, e->pool);
    fb_result rc = total ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory for the flame's histogram");
    if (!rc) rc = alloc_image(st, npix);
    fb_progress prog;
    char label[96];
    snprintf(label, sizeof label, "%s: chaos game", g->layer->name);
    if (st->keys)
        fb_progress_init(&prog, progress, label, "samples");
    else
        fb_progress_init(&prog, progress, label, "pts");
    double t0 = fb_now(), gpu = -1, points = 0;
    uint32_t chains = 0;
    if (!rc && st->keys) {
        rc = play_samples(g, e, total, &prog, &gpu, &points, &chains);
    } else if (!rc) {
        rc = play(g, e, S, st->cr0, st->cr1, total, &prog, &gpu);
        points = chain_points(S, st->cr0, st->cr1), chains = st->cr1 - st->cr0;
    }
    fb_progress_finish(&prog);
    double t1 = fb_now();
    if (!rc)
        rc = finish(st, total, e->pool);
    else
        free(total);
    st->seconds = fb_now() - t0;
    g->prepared.gpu_seconds = gpu;
    st->stats =
        (fb_flame_stats){.points = points, .game_seconds = t1 - t0, .gpu_seconds = gpu, .prepare_seconds = st->seconds};
    if (rc) return rc;
    fb_log(
        FB_LOG_INFO, "%s: %.0f points in %u chains, %.3g Mpts/s (chaos game %.2f s, filters %.2f s), %llu bad values",
        g->layer->name, points, chains, points / (t1 - t0) * 1e-6, t1 - t0, fb_now() - t1, (unsigned long long)st->bad);
    snprintf(g->prepared.summary, sizeof g->prepared.summary, "%s: flame %.0f points, %.3g Mpts/s", g->layer->name,
             points, points / (t1 - t0) * 1e-6);
    return FB_OK;
}

const fb_flame_stats *fb_gen_flame_stats(const fb_gen *g)
{
    return g->layer->cls == &fb_gen_flame && g->owned ? &state(g)->stats : NULL;
}

/* ---- points parts: the histogram as sums ------------------------------------------------------ */

/* A points part stores its whole histogram (hist_w x hist_h cells of six 64-bit sums, larger than
 * the image by the supersample and the filters' gutter) as the wide sums hist0, hist1, ...: value
 * v = k * width * height + pixel of sum k is field v % 6 of cell v / 6 (0 past the last cell). */
static int flame_nsums(const fb_gen *g)
{
    const flame_state *st = state(g);
    uint64_t values = 6ull * st->S.p.hist_w * st->S.p.hist_h, npix = (uint64_t)g->scene->width * g->scene->height;
    return (int)((values + npix - 1) / npix);
}

static bool flame_sum(const fb_gen *g, int k, char *suffix, size_t size)
{
    (void)g;
    snprintf(suffix, size, "hist%d", k);
    return true;
}

static uint64_t *cell_field(fb_flame_cell *c, int f)
{
    return f < 5 ? &c->c[f] : &c->hits;
}

/* Rows [y0, y0 + n) of the sums channels: planes[2k], planes[2k + 1] the low and high words of sum k. */
static void sums_rows(const flame_state *st, size_t npix, size_t at, size_t len, void *const *planes)
{
    size_t values = 6 * (size_t)st->S.p.hist_w * st->S.p.hist_h;
    for (int k = 0; k < st->nsums; k++) {
        uint32_t *lo = planes[2 * k], *hi = planes[2 * k + 1];
        for (size_t i = 0; i < len; i++) {
            size_t v = (size_t)k * npix + at + i;
            uint64_t x = v < values ? *cell_field(&st->hist[v / 6], (int)(v % 6)) : 0;
            lo[i] = (uint32_t)x, hi[i] = (uint32_t)(x >> 32);
        }
    }
}

/* The whole game's layer from the parts' sums: their histogram, filtered as a whole bake does. */
static fb_result flame_from_sums(fb_gen *g, const uint64_t *const *sums, uint64_t outside)
{
    flame_state *st = state(g);
    size_t cells = (size_t)st->S.p.hist_w * st->S.p.hist_h, npix = (size_t)g->scene->width * g->scene->height;
    (void)outside;
    fb_flame_cell *total = malloc(cells * sizeof *total);
    fb_result rc = total ? alloc_image(st, npix) : fb_fail(FB_ERR_NOMEM, "out of memory for the flame's histogram");
    for (size_t v = 0; v < 6 * cells && !rc; v++) *cell_field(&total[v / 6], (int)(v % 6)) = sums[v / npix][v % npix];
    if (rc) {
        free(total);
        return rc;
    }
    return finish(st, total, NULL);
}

static const fb_points_ops flame_points_ops = {
    .nsums = flame_nsums,
    .sum = flame_sum,
    .from_sums = flame_from_sums,
};

static void flame_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const flame_state *st = state(g);
    size_t w = (size_t)g->scene->width, at = (size_t)y0 * w, len = (size_t)n * w;
    const float *acc[4] = {st->acc[0] + at, st->acc[1] + at, st->acc[2] + at, st->acc[3] + at};
    fb_flame_tone_row(&st->S.tone, len, acc, planes[0], planes[1], planes[2], planes[3]);
    for (int k = 0; k < 4; k++) memcpy(planes[4 + k], acc[k], len * 4);
    memcpy(planes[8], st->count + at, len * 4);
    if (st->nsums) sums_rows(st, w * (size_t)g->scene->height, at, len, planes + 9);
}

static void flame_fini(fb_gen *g)
{
    flame_state *st = state(g);
    if (!st) return;
    fb_flame_setup_fini(&st->S);
    free(st->keys);
    fb_flame_frame_fini(&st->frame);
    for (int k = 0; k < 4; k++) free(st->acc[k]);
    free(st->count);
    free(st->hist);
}

/* The 32-bit histograms (one per thread), the 64-bit total, the density estimation's doubles, and the image-size planes
 * kept. */
static uint64_t flame_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    const flame_state *st = state(g);
    uint64_t cells = (uint64_t)st->S.p.hist_w * st->S.p.hist_h, n = (uint64_t)g->scene->width * g->scene->height;
    int threads = e->pool ? fb_pool_threads(e->pool) : 1;
    if (threads > 64) threads = 64;
    *hold = 20 * n + (st->nsums ? cells * sizeof(fb_flame_cell) : 0); /* a points part keeps its histogram */
    if (e->kind == FB_BACKEND_VULKAN) { /* the device's histogram, its carries or totals, chains, then the total */
        uint64_t hist, extra, chains;
        device_bytes(&st->S, st->cr0, st->cr1, e->vk && wide_histogram(&st->S, st->cr0, st->cr1, e->vk), &hist, &extra,
                     &chains);
        return hist + extra + chains + cells * sizeof(fb_flame_cell) + 32 * cells + 20 * n;
    }
    return (uint64_t)threads * cells * fb_flame_cell_bytes(&st->S) + cells * sizeof(fb_flame_cell) + 32 * cells +
           20 * n;
}

/* Seconds of one core of the reference machine: the chaos game per point (1.0 s of user time for
 * 13 Mpts at 512 x 512, bench/RESULTS.md) and density estimation, filter, tone map and the written
 * channels per pixel. */
#define FLAME_POINT_SECONDS 7.6e-8
#define FLAME_PIXEL_SECONDS 4e-7

static fb_result flame_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_flame_params *f = fb_layer_params(&s->layers[layer]);
    double q = f->quality > 0 ? f->quality : f->genome.quality, zoom = pow(2.0, f->genome.zoom);
    double pixels = (double)s->width * s->height;
    (void)rows;
    *total = q * zoom * zoom * pixels * FLAME_POINT_SECONDS + pixels * FLAME_PIXEL_SECONDS;
    return FB_OK;
}

static fb_result flame_init(fb_gen *g)
{
    const fb_scene *s = g->scene;
    const fb_flame_params *f = fb_layer_params(g->layer);
    flame_state *st = calloc(1, sizeof *st);
    if (!st) return fb_fail(FB_ERR_NOMEM, "out of memory");
    g->owned = st;
    g->fini = flame_fini;
    fb_result rc = FB_OK;
    if (f->animated && !(rc = read_keys(f, &st->keys, &st->nkeys)))
        rc = fb_flame_frame_init(st->keys, st->nkeys, f->time, f->temporal_samples, &st->frame);
    /* the frame: animated, at its time with the first temporal sample's density estimator */
    if (!rc) rc = fb_flame_setup_init(&f->genome, s->width, s->height, f->quality, s->seed, &st->S);
    if (rc) return rc;
    st->S.tone = f->tone;
    /* points part K of N: the K-th share of the chains (any split sums to the whole histogram) */
    part_chains(g, st->S.p.chains, &st->cr0, &st->cr1);
    if (g->run.points_part[1] > 0) {
        st->nsums = flame_nsums(g);
        if (9 + 2 * st->nsums > FB_GEN_MAX_CHANNELS)
            return fb_fail(FB_ERR_INPUT,
                           "layer %s: a points part stores the flame's histogram (%u x %u cells) in %d channels; at "
                           "most %d: bake it whole, larger, or with less supersample",
                           g->layer->name, st->S.p.hist_w, st->S.p.hist_h, 2 * st->nsums, FB_GEN_MAX_CHANNELS - 9);
    }
    static const char *const suffix[9] = {"R", "G", "B", "A", "acc_R", "acc_G", "acc_B", "acc_A", "count"};
    exrio_type colour = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    const exrio_type types[9] = {colour,      colour,      colour,      colour,    EXRIO_FLOAT,
                                 EXRIO_FLOAT, EXRIO_FLOAT, EXRIO_FLOAT, EXRIO_UINT};
    g->store.nchannels = 9 + 2 * st->nsums; /* a points part also carries its histogram */
    for (int c = 0; c < g->store.nchannels; c++) {
        if (c < 9)
            snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        else
            snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.hist%d_%s", g->layer->name,
                     (c - 9) / 2, (c - 9) % 2 ? "hi" : "lo");
        g->store.channel_types[c] = c < 9 ? types[c] : EXRIO_UINT;
    }
    g->prepared.points_split = true; /* merge reads an outside count: a flame's is 0 (its filter needs none) */
    g->store.preview_channel = 3;
    g->store.preview_rgb = 0;
    g->compute.native_rows = flame_rows;
    g->prepare = flame_prepare;
    g->memory = flame_memory;
    return FB_OK;
}

const fb_gen_class fb_gen_flame = {
    .name = "flame",
    .synopsis = "flame --file F.flame [options] -o OUT.exr",
    .summary = "a fractal flame from a .flame genome (flam3's XML), rendered as flam3 does",
    .what = "a flame layer",
    .keys = flame_keys,
    .nkeys = FB_NKEYS(flame_keys),
    .params_size = sizeof(fb_flame_params),
    .parse = parse_flame,
    .init = flame_init,
    .share = FB_SHARE_POINTS,
    .cost = flame_cost,
    .part_pixel_seconds = FLAME_PIXEL_SECONDS,
    .points = &flame_points_ops,
    .tone = &fb_flame_tone_ops,
    .example = "[{\"type\": \"flame\", \"file\": \"docs/examples/flames.flame\", \"flame\": \"gold\", \"quality\": 2}]",
    .bench = fb_flame_bench,
};
