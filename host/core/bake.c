/*
 * The bake driver. See bake.h.
 */
#include "bake.h"
#include "faces.h"

#include "output.h"
#include "preview.h"
#include "heightmap.h"
#include "progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- one layer's strip producer ------------------------------------------------------------- */

#define SLOTS 2 /* strips in flight per layer: one computing (GPU or pool) while one is consumed */

typedef struct layer_run {
    fb_gen gen;
    fb_engine e; /* the bake's engine as this layer uses it: its kind is the layer's backend */
    /* vulkan */
    vkc_pipeline *pipe;
    vkc_job *job[SLOTS];
    vkc_buffer *buf[SLOTS][FB_GEN_MAX_CHANNELS + 1]; /* the outputs, then the input (shared) */
    /* native (an op layer uses slot 0 only) */
    void *planes[SLOTS][FB_GEN_MAX_CHANNELS];
} layer_run;

/* The strips a layer's rows come from: the GPU, the host's pool, or (an op layer) the main thread
 * from other layers' strips. */
static bool run_on_gpu(const fb_engine *e, const layer_run *lr)
{
    return e->kind == FB_BACKEND_VULKAN && !lr->gen.prepare && !lr->gen.compute.host_rows;
}

static bool run_on_pool(const fb_engine *e, const layer_run *lr)
{
    return !run_on_gpu(e, lr) && !lr->gen.compute.host_rows;
}

typedef struct native_task {
    const fb_gen *gen;
    int y0, n, rows_per_task;
    void *const *planes;
    fb_progress *prog; /* pixels done, counted per layer: each task adds its rows x `cols` */
    int cols;
} native_task;

static void native_task_fn(void *ctx, int t)
{
    const native_task *nt = ctx;
    int r0 = t * nt->rows_per_task;
    int r1 = r0 + nt->rows_per_task < nt->n ? r0 + nt->rows_per_task : nt->n;
    size_t row_bytes = (size_t)nt->gen->scene->width * 4;
    void *planes[FB_GEN_MAX_CHANNELS];
    for (int k = 0; k < fb_gen_nplanes(nt->gen); k++)
        planes[k] = nt->planes[k] ? (uint8_t *)nt->planes[k] + (size_t)r0 * row_bytes : NULL;
    nt->gen->compute.native_rows(nt->gen, nt->y0 + r0, r1 - r0, planes);
    if (nt->prog) fb_progress_add(nt->prog, (uint64_t)(r1 - r0) * (uint64_t)nt->cols);
}

static fb_result run_init(fb_engine *e, layer_run *lr, int strip_rows)
{
    const fb_scene *s = lr->gen.scene;
    size_t bytes = (size_t)s->width * (size_t)strip_rows * 4;
    fb_result rc = FB_OK;
    const int np = fb_gen_nplanes(&lr->gen);
    if (run_on_gpu(e, lr)) {
        if (lr->gen.compute.shader.needs_float64 && !vkc_info(e->vk)->float64)
            return fb_fail(FB_ERR_INPUT,
                           "layer %s: precision \"double\" needs a Vulkan device with shaderFloat64, and %s has none "
                           "(use --backend native)",
                           lr->gen.layer->name, e->device);
        rc = vkc_pipeline_create(
            e->vk,
            &(vkc_pipeline_desc){
                .spv = lr->gen.compute.shader.spv,
                .spv_size = lr->gen.compute.shader.spv_size,
                .push_size = lr->gen.compute.shader.push_size,
                .buffers = (uint32_t)np + (lr->gen.compute.shader.input ? 1u : 0u),
                .uniform = lr->gen.compute.shader.input && lr->gen.compute.shader.input_uniform ? 1u << np : 0u,
                .spec = lr->gen.compute.shader.spec,
                .nspec = lr->gen.compute.shader.nspec,
                .name = lr->gen.layer->name},
            &lr->pipe);
        for (int k = 0; k < SLOTS && !rc; k++) {
            rc = vkc_job_create(e->vk, lr->pipe, &lr->job[k]);
            /* a plane the layer does not store is never written: a token buffer binds it */
            for (int c = 0; c < np && !rc; c++)
                rc = vkc_buffer_create(e->vk, fb_gen_plane_stored(&lr->gen, c) ? bytes : 16, &lr->buf[k][c]);
        }
        if (!rc && lr->gen.compute.shader.input) {
            int at = np;
            rc = vkc_buffer_create(e->vk, lr->gen.compute.shader.input_size, &lr->buf[0][at]);
            if (!rc)
                rc = vkc_buffer_upload(e->vk, lr->buf[0][at], lr->gen.compute.shader.input,
                                       lr->gen.compute.shader.input_size);
            for (int k = 1; k < SLOTS; k++) lr->buf[k][at] = lr->buf[0][at]; /* one input, both slots */
        }
        return rc;
    }
    for (int k = 0; k < (run_on_pool(e, lr) ? SLOTS : 1); k++)
        for (int c = 0; c < np; c++)
            if (fb_gen_plane_stored(&lr->gen, c) && !(lr->planes[k][c] = malloc(bytes)))
                return fb_fail(FB_ERR_NOMEM, "out of memory for a strip of rows");
    return FB_OK;
}

static void run_fini(fb_engine *e, layer_run *lr)
{
    for (int k = 1; k < SLOTS; k++) lr->buf[k][fb_gen_nplanes(&lr->gen)] = NULL; /* the shared input: freed once */
    for (int k = 0; k < SLOTS; k++) {
        if (e->vk) vkc_job_destroy(e->vk, &lr->job[k]);
        for (int c = 0; c <= FB_GEN_MAX_CHANNELS; c++) {
            if (e->vk) vkc_buffer_destroy(e->vk, &lr->buf[k][c]);
        }
    }
    fb_gen_fini(&lr->gen);
    if (e->vk) vkc_pipeline_destroy(e->vk, &lr->pipe);
    for (int k = 0; k < SLOTS; k++)
        for (int c = 0; c < FB_GEN_MAX_CHANNELS; c++) free(lr->planes[k][c]);
    memset(lr->planes, 0, sizeof lr->planes);
}

static fb_result run_submit(fb_engine *e, layer_run *lr, int slot, int y0, int n)
{
    if (!run_on_gpu(e, lr)) return FB_OK; /* host strips: strip_start */
    uint8_t push[FB_GEN_MAX_PUSH];
    uint32_t groups[3];
    fb_gen_push(&lr->gen, y0, n, push);
    fb_gen_groups(&lr->gen, n, groups);
    return vkc_job_submit(e->vk, lr->job[slot], lr->buf[slot],
                          (uint32_t)fb_gen_nplanes(&lr->gen) + (lr->gen.compute.shader.input ? 1u : 0u), push, groups);
}

/* Makes the strip [y0, y0+n) available in planes[]: waits for the GPU job, or points at the strip
 * the pool computed (strip_start, then fb_pool_wait). */
static fb_result run_collect(fb_engine *e, layer_run *lr, int slot, const void **planes, double *gpu_seconds)
{
    if (run_on_gpu(e, lr)) {
        double t = -1;
        fb_result rc = vkc_job_wait(e->vk, lr->job[slot], &t);
        if (rc) return rc;
        if (t > 0) *gpu_seconds += t;
        for (int c = 0; c < lr->gen.store.nchannels; c++)
            planes[c] = vkc_buffer_data(lr->buf[slot][fb_gen_plane_of(&lr->gen, c)]);
        return FB_OK;
    }
    for (int c = 0; c < lr->gen.store.nchannels; c++) planes[c] = lr->planes[slot][fb_gen_plane_of(&lr->gen, c)];
    return FB_OK;
}

/* One strip of every layer computed on the host's pool, as one pool job: its tasks are each
 * layer's row blocks in turn. */
typedef struct strip_job {
    native_task t[FB_MAX_LAYERS];
    int first[FB_MAX_LAYERS + 1]; /* t[i]'s first task */
    int n;
} strip_job;

static void strip_task(void *ctx, int task)
{
    strip_job *j = ctx;
    int i = 0;
    while (task >= j->first[i + 1]) i++;
    native_task_fn(&j->t[i], task - j->first[i]);
}

/* Starts the pool on rows [y0, y0+n) of every layer it computes, into their planes of `slot`, and
 * returns at once: the caller writes the strip before while the workers compute this one, then
 * fb_pool_wait. Every engine has a pool (engine.c): native layers and the host side of the others
 * use it. */
static void strip_start(fb_engine *e, layer_run *runs, int nlayers, strip_job *j, int slot, int y0, int n,
                        fb_progress *prog, int cols)
{
    int threads = fb_pool_threads(e->pool);
    int per = (n + 4 * threads - 1) / (4 * threads);
    if (per < 1) per = 1;
    j->n = 0;
    j->first[0] = 0;
    for (int i = 0; i < nlayers; i++) {
        if (!run_on_pool(&runs[i].e, &runs[i])) continue;
        j->t[j->n] = (native_task){.gen = &runs[i].gen,
                                   .y0 = y0,
                                   .n = n,
                                   .rows_per_task = per,
                                   .planes = runs[i].planes[slot],
                                   .prog = prog,
                                   .cols = cols};
        j->first[j->n + 1] = j->first[j->n] + (n + per - 1) / per;
        j->n++;
    }
    fb_pool_start(e->pool, j->first[j->n], strip_task, j);
}

/* ---- the PNG preview ------------------------------------------------------------------------ */

/* One layer's preview: its colour (3 channels from `first`) or scalar channel, and its coverage. */
typedef struct previews {
    int n;     /* 1: one layer shown alone; more: the over composite of every layer, or the sheet */
    bool over; /* composite (also with a single layer, when asked for by name "over") */
    bool all;  /* a contact sheet: every layer a tile of its own, labelled */
    char labels[FB_MAX_LAYERS][96];
    fb_preview *p[FB_MAX_LAYERS];
    int layer[FB_MAX_LAYERS], first[FB_MAX_LAYERS], alpha[FB_MAX_LAYERS]; /* channel indices; alpha -1: none */
    int offset[FB_MAX_LAYERS]; /* the layer's first plane among all planes of a strip */
    bool uint[FB_MAX_LAYERS];  /* a scalar uint channel (a julia layer's iter alone): shown as float */
    bool light[FB_MAX_LAYERS]; /* colour added in the composite (fb_gen.preview_light) */
    float *conv;               /* its rows as float: region width x strip rows */
    int width, stride;         /* the region's width; the planes' row stride */
} previews;

static int alpha_channel(const fb_gen *g)
{
    for (int c = 0; c < g->store.nchannels; c++) {
        size_t len = strlen(g->store.channel_names[c]);
        if (len >= 2 && !strcmp(g->store.channel_names[c] + len - 2, ".A")) return c;
    }
    return -1;
}

static fb_result previews_create(const fb_scene *s, const layer_run *runs, const char *which, const int region[4],
                                 previews *pv, char *note, size_t note_size)
{
    int only = 0;
    pv->all = which && !strcmp(which, "all");
    pv->over = which ? !strcmp(which, "over") : s->nlayers > 1;
    if (which && !pv->over && !pv->all) {
        only = -1;
        for (int i = 0; i < s->nlayers; i++)
            if (!strcmp(s->layers[i].name, which)) only = i;
        if (only < 0) {
            char names[FB_MAX_LAYERS * 66];
            fb_scene_layer_names(s, names, sizeof names);
            return fb_fail(FB_ERR_USAGE, "--preview-layer: no layer named \"%s\" (layers: %s; or \"over\" or \"all\")",
                           which, names);
        }
    }
    int at = 0;
    for (int i = 0; i < s->nlayers; i++) {
        const fb_gen *g = &runs[i].gen;
        /* op layers are data (masks, sums): shown by name, left out of the composite */
        bool shown = pv->all    ? true
                     : pv->over ? !g->compute.host_rows || (i == s->nlayers - 1 && pv->n == 0)
                                : i == only;
        if (shown) {
            int k = pv->n++, cols = 1;
            while (cols * cols < s->nlayers) cols++;
            pv->layer[k] = i;
            pv->offset[k] = at;
            pv->first[k] = g->store.preview_rgb >= 0 ? g->store.preview_rgb : g->store.preview_channel;
            pv->alpha[k] = pv->over ? alpha_channel(g) : -1;
            snprintf(pv->labels[k], sizeof pv->labels[k], "%s (%s)", s->layers[i].name, s->layers[i].cls->name);
            /* a sheet's tiles share about 2048 pixels across */
            int side = pv->all ? (2048 / cols > 256 ? 2048 / cols : 256) : 2048;
            fb_result rc = fb_preview_create_alpha(region[2], region[3], side, g->store.preview_rgb >= 0 ? 3 : 1,
                                                   pv->alpha[k] >= 0, &pv->p[k]);
            if (rc) return rc;
            fb_preview_set_row_stride(pv->p[k], s->width);
            pv->uint[k] = g->store.preview_rgb < 0 && g->store.channel_types[g->store.preview_channel] == EXRIO_UINT;
            if (g->store.preview_rgb < 0 && g->store.preview_shade[0] > 0)
                fb_preview_set_hillshade(pv->p[k], g->store.preview_shade[0], g->store.preview_shade[1]);
            pv->light[k] = pv->over && g->store.preview_rgb >= 0 && g->store.preview_light;
            if (pv->light[k]) fb_preview_set_light(pv->p[k]);
        }
        at += g->store.nchannels;
    }
    pv->width = region[2];
    pv->stride = s->width;
    /* One line for the user: what the picture shows, and what it leaves out. */
    char list[FB_MAX_LAYERS * 70] = "", left[FB_MAX_LAYERS * 70] = "", hid[FB_MAX_LAYERS * 140] = "";
    for (int k = 0; k < pv->n; k++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s",
                 !k              ? ""
                 : k < pv->n - 1 ? ", "
                                 : " and ",
                 s->layers[pv->layer[k]].name);
    if (pv->all) {
        snprintf(note, note_size, "a contact sheet of every layer (%s)", list);
    } else if (!pv->over) {
        snprintf(note, note_size, "layer %s alone", list);
    } else {
        for (int i = 0; i < s->nlayers; i++) {
            bool drawn = false;
            for (int k = 0; k < pv->n; k++) drawn = drawn || pv->layer[k] == i;
            if (!drawn)
                snprintf(left + strlen(left), sizeof left - strlen(left), "%s%s", left[0] ? ", " : "",
                         s->layers[i].name);
        }
        char added[FB_MAX_LAYERS * 70] = "";
        for (int k = 0; k < pv->n; k++)
            if (pv->light[k])
                snprintf(added + strlen(added), sizeof added - strlen(added), "%s%s", added[0] ? ", " : "",
                         s->layers[pv->layer[k]].name);
        for (int k = pv->n - 1; k > 0; k--) /* the frontmost opaque layer hides every layer behind it */
            if (pv->alpha[k] < 0 && !pv->light[k]) {
                char behind[FB_MAX_LAYERS * 70] = "";
                for (int j = 0; j < k; j++)
                    snprintf(behind + strlen(behind), sizeof behind - strlen(behind), "%s%s", j ? ", " : "",
                             s->layers[pv->layer[j]].name);
                snprintf(hid, sizeof hid, "; %s has no coverage (A) and hides %s", s->layers[pv->layer[k]].name,
                         behind);
                break;
            }
        snprintf(note, note_size, "%s composited back to front by their coverage%s%s%s%s%s%s%s", list,
                 added[0] ? " (light added: " : "", added, added[0] ? ")" : "", hid,
                 left[0] ? "; op layers not drawn: " : "", left,
                 pv->n > 1 || left[0] ? " (--preview-layer NAME shows one, all a sheet of every layer)" : "");
    }
    return FB_OK;
}

/* planes: the region's first column of each strip row, rows the image width apart; y0 in the region */
static fb_result previews_add(previews *pv, const layer_run *runs, int y0, int n, const void *const *planes)
{
    for (int k = 0; k < pv->n; k++) {
        const fb_gen *g = &runs[pv->layer[k]].gen;
        const void *const *lp = planes + pv->offset[k];
        int f = pv->first[k], three = g->store.preview_rgb >= 0;
        const float *rows[4] = {lp[f], lp[three ? f + 1 : f], lp[three ? f + 2 : f], NULL};
        if (pv->alpha[k] >= 0) rows[three ? 3 : 1] = lp[pv->alpha[k]];
        if (pv->uint[k]) { /* converted into rows of the same stride */
            float *conv = realloc(pv->conv, (size_t)n * pv->stride * sizeof *conv);
            if (!conv) return fb_fail(FB_ERR_NOMEM, "out of memory for the preview");
            pv->conv = conv;
            const uint32_t *src = lp[f];
            for (int r = 0; r < n; r++)
                for (int x = 0; x < pv->width; x++)
                    conv[(size_t)r * pv->stride + x] = (float)src[(size_t)r * pv->stride + x];
            rows[0] = conv;
        }
        fb_preview_add_rows(pv->p[k], y0, n, rows);
    }
    return FB_OK;
}

static fb_result previews_write(const previews *pv, const char *path)
{
    if (pv->all) {
        const char *labels[FB_MAX_LAYERS];
        for (int k = 0; k < pv->n; k++) labels[k] = pv->labels[k];
        return fb_preview_write_sheet((const fb_preview *const *)pv->p, labels, pv->n, path);
    }
    if (pv->over) return fb_preview_write_over((const fb_preview *const *)pv->p, pv->n, path);
    return fb_preview_write_png(pv->p[0], path, "preview");
}

/* ---- the bake ------------------------------------------------------------------------------- */

/* No stored float or half channel may hold a NaN or an infinity: every generator's inputs are checked
 * so that none can, and this cheap pass over each strip (one compare per value, next to generating
 * and compressing it) turns a breach into an error instead of a silently broken file. */
static fb_result check_finite(const layer_run *runs, int nlayers, const void *const *planes, int y0, int n, int x0,
                              int w, int stride)
{
    int at = 0;
    for (int i = 0; i < nlayers; i++) {
        const fb_gen *g = &runs[i].gen;
        for (int c = 0; c < g->store.nchannels; c++, at++) {
            if (g->store.channel_types[c] == EXRIO_UINT) continue;
            for (int r = 0; r < n; r++) {
                const uint32_t *row = (const uint32_t *)planes[at] + (size_t)r * stride;
                uint32_t any = 0;
                for (int x = 0; x < w; x++) any |= (row[x] & 0x7f800000u) == 0x7f800000u;
                if (!any) continue;
                for (int x = 0; x < w; x++) {
                    float v;
                    memcpy(&v, &row[x], 4);
                    if (isfinite(v)) continue;
                    fb_log_context("layer %s, rows %d-%d", g->layer->name, y0, y0 + n - 1);
                    if (g->compute.host_rows) /* the user's numbers: weights or constants too large for a float */
                        return fb_fail(FB_ERR_INPUT,
                                       "layer %s: the %s gives %s at pixel (%d, %d) of %s: its inputs, weights or "
                                       "ranges are too large for a float (at most 3.4e38)",
                                       g->layer->name, g->layer->cls->name, isnan(v) ? "NaN" : "an infinity", x0 + x,
                                       y0 + r, g->store.channel_names[c]);
                    return fb_fail(FB_ERR_INTERNAL,
                                   "layer %s: channel %s holds %s at pixel (%d, %d): an internal error, please "
                                   "report it with the scene",
                                   g->layer->name, g->store.channel_names[c], isnan(v) ? "NaN" : "an infinity", x0 + x,
                                   y0 + r);
                }
            }
        }
    }
    return FB_OK;
}

/* The bake's predicted peak: the process and its backend, every layer's own arrays (the largest
 * transient one at a time, as layers prepare one after another, on top of what every layer keeps),
 * its strip buffers (two slots a layer on Vulkan), then either the preparing or the writer's queue
 * (2 x threads + 3 batches of 64 rows, raw and compressed) and the preview's sums. Pages a layer
 * allocates but never touches (a chaos game's empty histogram cells) count: it is a bound. Fails naming the largest
 * layer when the peak is beyond the bake's limit (its max_memory, with the engine's overhead). */
static fb_result plan_memory(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs, int strip, int nch,
                             int rw, fb_bake_plan *plan)
{
    const fb_scene *s = d->scene;
    memset(plan, 0, sizeof *plan);
    plan->nlayers = s->nlayers;
    const fb_memory mem = {d->max_memory, e->overhead};
    plan->limit = fb_memory_limit(&mem);
    plan->base = e->kind == FB_BACKEND_VULKAN ? (uint64_t)96 << 20 : (uint64_t)12 << 20;
    uint64_t hold_sum = 0, extra_max = 0, strips_sum = 0;
    int largest = 0;
    for (int i = 0; i < s->nlayers; i++) {
        const fb_gen *g = &runs[i].gen;
        uint64_t hold = 0, peak = g->memory ? g->memory(g, &runs[i].e, &hold) : 0;
        if (s->layers[i].heightmap[0]) { /* its heights, kept for the heightmap written at the end */
            int rh = d->region[2] > 0 ? d->region[3] : s->height;
            uint64_t hm = (uint64_t)rw * rh * 4;
            hold += hm, peak += hm;
        }
        bool gpu = run_on_gpu(&runs[i].e, &runs[i]);
        uint64_t planes = 0;
        for (int c = 0; c < fb_gen_nplanes(g); c++) planes += fb_gen_plane_stored(g, c);
        uint64_t strips = (g->compute.host_rows ? 1 : SLOTS) * planes * (uint64_t)s->width * (uint64_t)strip * 4 +
                          (gpu && g->compute.shader.input ? g->compute.shader.input_size : 0);
        hold_sum += hold;
        strips_sum += strips;
        if (peak - hold > extra_max) extra_max = peak - hold;
        snprintf(plan->layers[i].name, sizeof plan->layers[i].name, "%s", s->layers[i].name);
        plan->layers[i].bytes = peak + strips;
        if (plan->layers[i].bytes > plan->layers[largest].bytes) largest = i;
    }
    /* the raw rows of every batch in flight, and their compressed chunks (a quarter of that, on
     * average over what the generators make) */
    if (d->out) plan->writer = (uint64_t)(2 * e->threads + 3) * 64 * (uint64_t)rw * 4 * (uint64_t)nch * 5 / 4;
    /* and each compression thread's deflate state with its three chunk buffers (16 rows: split,
     * predicted, deflated) */
    bool zip = s->compression == EXRIO_ZIP;
    for (int i = 0; i < s->nlayers; i++) zip = zip || (s->multipart && s->layers[i].compression == EXRIO_ZIP);
    if (d->out && zip)
        plan->writer +=
            (uint64_t)e->threads * (exrio_zip_state_bytes(d->zip_level) + 3 * 16 * (uint64_t)rw * 4 * (uint64_t)nch);
    if (d->preview) {
        int rh = d->region[2] > 0 ? d->region[3] : s->height; /* the preview shows the region */
        int side = rw > rh ? rw : rh, scale = (side + 2047) / 2048;
        uint64_t px = (uint64_t)((rw + scale - 1) / scale) * (uint64_t)((rh + scale - 1) / scale);
        plan->preview = px * (4 * 8 + 4) * (uint64_t)s->nlayers;
    }
    if (d->cube_faces) plan->preview += fb_faces_bytes(s->width, nch); /* one face of every channel */
    /* Layers prepare (chaos game, mesh, grid) before the writer and the preview exist: the peak is
     * the worse of the two phases. */
    uint64_t prepare = extra_max, strips = plan->writer + plan->preview;
    plan->peak = plan->base + strips_sum + hold_sum + (prepare > strips ? prepare : strips);
    if (plan->peak > plan->limit) {
        char need[32], lim[32], big[32], note[160];
        fb_format_bytes(plan->peak, need, sizeof need);
        fb_format_bytes(plan->limit, lim, sizeof lim);
        fb_format_bytes(plan->layers[largest].bytes, big, sizeof big);
        return fb_fail(FB_ERR_INPUT,
                       "the bake needs about %s, more than --max-memory %s%s; layer %s alone needs %s (lower its "
                       "size, points or insertions, or raise --max-memory)",
                       need, lim, fb_memory_limit_note(&mem, note, sizeof note), plan->layers[largest].name, big);
    }
    return FB_OK;
}

/* "on llvmpipe (...)", or per layer: "with sky on llvmpipe (...), terrain and plants on native C". */
static void ran_on(const fb_engine *e, const layer_run *runs, const fb_scene *s, char *out, size_t size)
{
    snprintf(out, size, "on %s", e->device);
    if (!e->per_layer) return;
    snprintf(out, size, "with");
    for (int kind = FB_BACKEND_VULKAN, groups = 0; kind <= FB_BACKEND_NATIVE; kind++) {
        int n = 0, total = 0;
        for (int i = 0; i < s->nlayers; i++) total += runs[i].e.kind == (fb_backend)kind;
        for (int i = 0; i < s->nlayers; i++) {
            if (runs[i].e.kind != (fb_backend)kind) continue;
            n++;
            snprintf(out + strlen(out), size - strlen(out), "%s%s",
                     n == 1       ? (groups ? ", " : " ")
                     : n == total ? " and "
                                  : ", ",
                     s->layers[i].name);
        }
        if (n) {
            snprintf(out + strlen(out), size - strlen(out), " on %s",
                     kind == FB_BACKEND_VULKAN ? e->device : "native C");
            groups++;
        }
    }
}

static int auto_strip_rows(const fb_scene *s, int height)
{
    /* About 4 MiB per channel buffer: well inside lavapipe's 128 MiB maxStorageBufferRange and small
     * enough that the writer's queue keeps memory bounded at any image size. */
    long rows = (1L << 20) / s->width;
    if (rows >= 64) rows -= rows % 64;
    /* and at least 32 strips (of 16 rows or more): a strip is what a GPU layer's progress can see */
    long part = (height + 31) / 32;
    part = part < 16 ? 16 : (part + 15) / 16 * 16;
    if (rows > part) rows = part;
    if (rows < 1) rows = 1;
    if (rows > height) rows = height;
    return (int)rows;
}

/* ---- heightmaps: a layer's Y channel kept whole, written at the end ----------------------------- */

typedef struct heightmaps {
    float *z[FB_MAX_LAYERS];  /* region width x height, or NULL */
    int plane[FB_MAX_LAYERS]; /* the Y channel among all planes of a strip */
    int alpha[FB_MAX_LAYERS]; /* a GeoTIFF's: the A channel (0 outside a terrain's hull: no data), or -1 */
} heightmaps;

static fb_result heightmaps_create(const fb_scene *s, const layer_run *runs, const int *offset, const int *region,
                                   heightmaps *hm)
{
    int rw = region[2] > 0 ? region[2] : s->width, rh = region[2] > 0 ? region[3] : s->height;
    for (int i = 0; i < s->nlayers; i++) {
        if (!s->layers[i].heightmap[0]) continue;
        char msg[256];
        fb_heightmap_format f = FB_HEIGHTMAP_PNG16;
        fb_heightmap_format_of(s->layers[i].heightmap, &f);
        if (s->layers[i].tiles[0] && region[2] > 0)
            return fb_fail(FB_ERR_USAGE,
                           "layer %s: its heightmap's tiles (%dx%d) cut the whole image, and this bake is a region of "
                           "it: bake the whole image, or leave the tiles out",
                           s->layers[i].name, s->layers[i].tiles[0], s->layers[i].tiles[1]);
        if (!s->layers[i].tiles[0] && /* a region's size (the scene checked the whole image's, and the tiles') */
            !fb_heightmap_engine_check(s->layers[i].heightmap_engine, rw, rh, f, msg, sizeof msg))
            return fb_fail(FB_ERR_USAGE, "layer %s: %s (the region is %d x %d)", s->layers[i].name, msg, rw, rh);
        int c = fb_gen_channel_of(&runs[i].gen, "Y", s->layers[i].name, "heightmap");
        if (!ALWAYS(c >= 0)) return FB_ERR_INTERNAL;
        hm->plane[i] = offset[i] + c;
        char alpha[160];
        snprintf(alpha, sizeof alpha, "%s.A", s->layers[i].name);
        hm->alpha[i] = -1;
        for (int k = 0; k < runs[i].gen.store.nchannels && f == FB_HEIGHTMAP_GEOTIFF; k++)
            if (!strcmp(runs[i].gen.store.channel_names[k], alpha)) hm->alpha[i] = offset[i] + k;
        if (!(hm->z[i] = fb_malloc_large((size_t)rw * rh * sizeof(float))))
            return fb_fail(FB_ERR_NOMEM, "layer %s: out of memory for its heightmap", s->layers[i].name);
    }
    return FB_OK;
}

static void heightmaps_add(const fb_scene *s, heightmaps *hm, const void *const *planes, int y0, int n, int rw)
{
    for (int i = 0; i < s->nlayers; i++)
        if (hm->z[i])
            for (int r = 0; r < n; r++) {
                float *z = hm->z[i] + (size_t)(y0 + r) * rw;
                memcpy(z, (const float *)planes[hm->plane[i]] + (size_t)r * s->width, (size_t)rw * sizeof(float));
                const float *a = hm->alpha[i] >= 0 ? (const float *)planes[hm->alpha[i]] + (size_t)r * s->width : NULL;
                for (int x = 0; a && x < rw; x++)
                    if (a[x] < 0.5f) z[x] = FB_HEIGHTMAP_NODATA;
            }
}

static fb_result heightmaps_write(const fb_scene *s, const layer_run *runs, heightmaps *hm, const int region[4],
                                  fb_bake_stats *stats)
{
    fb_result rc = FB_OK;
    for (int i = 0; i < s->nlayers && !rc; i++) {
        const fb_layer *L = &s->layers[i];
        if (!hm->z[i]) continue;
        size_t n = (size_t)region[2] * region[3];
        double lo = L->heightmap_range[0], hi = L->heightmap_range[1];
        if (!L->heightmap_range_set) {
            lo = INFINITY, hi = -INFINITY;
            for (size_t k = 0; k < n; k++)
                lo = hm->z[i][k] < lo ? hm->z[i][k] : lo, hi = hm->z[i][k] > hi ? hm->z[i][k] : hi;
            if (!(hi > lo)) hi = lo + 1; /* a flat image: every height stored as 0 */
        }
        const fb_gen *g = &runs[i].gen;
        double world[4] = {0, 1, 0, 1};
        if (g->prepared.has_world) { /* the region's part of the layer's frame */
            double sx = (g->prepared.world[1] - g->prepared.world[0]) / s->width,
                   sy = (g->prepared.world[3] - g->prepared.world[2]) / s->height;
            world[0] = g->prepared.world[0] + region[0] * sx, world[1] = world[0] + region[2] * sx;
            world[3] = g->prepared.world[3] - region[1] * sy, world[2] = world[3] - region[3] * sy;
        }
        fb_log_context("layer %s", L->name);
        rc = fb_heightmap_write(&(fb_heightmap_desc){.path = L->heightmap,
                                                     .width = region[2],
                                                     .height = region[3],
                                                     .z = hm->z[i],
                                                     .lo = lo,
                                                     .hi = hi,
                                                     .world = world,
                                                     .epsg = g->prepared.epsg,
                                                     .engine = (fb_heightmap_engine)L->heightmap_engine,
                                                     .nodata = hm->alpha[i] >= 0,
                                                     .cols = L->tiles[0],
                                                     .rows = L->tiles[1]});
        if (!rc && stats && stats->nheightmaps < FB_MAX_LAYERS) {
            fb_bake_heightmap *h = &stats->heightmaps[stats->nheightmaps++];
            h->layer = L->name, h->path = L->heightmap, h->lo = lo, h->hi = hi;
            h->sidecar = L->heightmap_sidecar[0] ? L->heightmap_sidecar : NULL;
            h->engine = L->heightmap_engine, h->tiles[0] = L->tiles[0], h->tiles[1] = L->tiles[1];
            h->tile_paths = L->tile_paths;
            fb_heightmap_format f = FB_HEIGHTMAP_PNG16;
            fb_heightmap_format_of(L->heightmap, &f);
            h->format = (int)f;
        }
    }
    return rc;
}

static void heightmaps_free(const fb_scene *s, heightmaps *hm)
{
    for (int i = 0; i < s->nlayers; i++) free(hm->z[i]);
    memset(hm, 0, sizeof *hm);
}

/* Every output is reserved before any work: a bad target (named twice, a directory, a device node, a
 * folder that does not exist) fails now, not after minutes of computing. A dry run writes nothing. */
static fb_result reserve_outputs(const fb_bake_desc *d, const fb_scene *s)
{
    if (d->dry_run) return FB_OK;
    fb_result rc = FB_OK;
    if (d->out) rc = fb_output_reserve(d->out, "output");
    if (!rc && d->preview) rc = fb_output_reserve(d->preview, "preview");
    const char *side[FB_MAX_OUTPUTS + 1], *side_what[FB_MAX_OUTPUTS + 1]; /* one more: too many fail here */
    int nside = fb_scene_outputs(s, side, side_what, FB_MAX_OUTPUTS + 1);
    for (int i = 0; i < nside && !rc; i++) rc = fb_output_reserve(side[i], side_what[i]);
    return rc;
}

/* The pixels baked (region[] = x, y, w, h: the desc's region, or the whole image) and the rows of a
 * strip, which one storage buffer row of the device must hold. */
static fb_result bake_window(const fb_engine *e, const fb_bake_desc *d, int region[4], int *strip_out)
{
    const fb_scene *s = d->scene;
    region[0] = 0, region[1] = 0, region[2] = s->width, region[3] = s->height;
    if (d->region[2] > 0) {
        int rx = d->region[0], ry = d->region[1], rw = d->region[2], rh = d->region[3];
        if (rx < 0 || ry < 0 || rh <= 0 || (long)rx + rw > s->width || (long)ry + rh > s->height)
            return fb_fail(FB_ERR_USAGE, "--region %d,%d,%d,%d: not inside the %d x %d image", rx, ry, rw, rh, s->width,
                           s->height);
        memcpy(region, d->region, sizeof d->region);
    }
    int rh = region[3];
    int strip = d->strip_rows > 0 ? d->strip_rows : auto_strip_rows(s, rh);
    if (strip > rh) strip = rh;
    if (e->kind == FB_BACKEND_VULKAN && (uint64_t)strip * s->width * 4 > vkc_info(e->vk)->max_storage_buffer_range) {
        strip = (int)(vkc_info(e->vk)->max_storage_buffer_range / ((uint64_t)s->width * 4));
        if (strip < 1)
            return fb_fail(FB_ERR_INPUT, "image width %d is too wide for one storage buffer row on this device",
                           s->width);
    }
    *strip_out = strip;
    return FB_OK;
}

/* The file's backend: the one asked for (auto, vulkan, native); where each layer ran goes in
 * per_layer ("a=vulkan;b=native") for auto, where the layers ran on different ones (a layer with no
 * Vulkan path), or when d asks for the list. Returns how many layers ran on Vulkan. */
static int file_backend(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs, char backend[16],
                        char *per_layer, size_t size)
{
    const fb_scene *s = d->scene;
    int nvk = 0;
    for (int i = 0; i < s->nlayers; i++) nvk += runs[i].e.kind == FB_BACKEND_VULKAN;
    snprintf(backend, 16, "%s", fb_backend_name(e->asked));
    per_layer[0] = 0;
    bool list = d->layer_backends || e->asked == FB_BACKEND_AUTO || (nvk > 0 && nvk < s->nlayers);
    for (int i = 0; i < s->nlayers && list; i++)
        snprintf(per_layer + strlen(per_layer), size - strlen(per_layer), "%s%s=%s", i ? ";" : "", s->layers[i].name,
                 fb_backend_name(runs[i].e.kind));
    return nvk;
}

/* The EXR writer for the window, with the attributes that let `render --from` and merge read the
 * file back: the scene, seed, backend, device, version, region, a task's or points part's own. */
static fb_result open_writer(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs,
                             const exrio_channel *channels, int nch, const int region[4], exrio_writer **w)
{
    const fb_scene *s = d->scene;
    char backend[16], per_layer[FB_MAX_LAYERS * 80], seed[16], reg[64];
    int nvk = file_backend(e, d, runs, backend, per_layer, sizeof per_layer);
    snprintf(seed, sizeof seed, "%u", s->seed);
    snprintf(reg, sizeof reg, "%d,%d,%d,%d", region[0], region[1], region[2], region[3]);
    bool partial = d->region[2] > 0;
    exrio_attr attrs[16] = {
        {"fractalbake/scene", s->json},      {"fractalbake/seed", seed},
        {"fractalbake/backend", backend},    {"fractalbake/device", nvk ? e->device : "native C"},
        {"fractalbake/version", FB_VERSION},
    };
    int nattrs = 5;
    if (partial) attrs[nattrs++] = (exrio_attr){"fractalbake/region", reg};
    if (per_layer[0]) attrs[nattrs++] = (exrio_attr){"fractalbake/layer-backends", per_layer};
    for (int a = 0; a < d->nattrs && nattrs < 14; a++) attrs[nattrs++] = d->attrs[a];
    /* a points part: which, and each chaos-game layer's points outside the frame (merge needs them
     * for the density; merge also reads the attribute's first name, fractalbake/ifs-outside) */
    char part[32], outside[FB_MAX_LAYERS * 90] = "";
    if (d->points_part[1] > 0) {
        snprintf(part, sizeof part, "%d/%d", d->points_part[0], d->points_part[1]);
        for (int i = 0; i < s->nlayers; i++)
            if (runs[i].gen.prepared.points_split)
                snprintf(outside + strlen(outside), sizeof outside - strlen(outside), "%s%s=%llu",
                         outside[0] ? ";" : "", s->layers[i].name,
                         (unsigned long long)runs[i].gen.prepared.points_outside);
        attrs[nattrs++] = (exrio_attr){"fractalbake/points-part", part};
        attrs[nattrs++] = (exrio_attr){"fractalbake/points-outside", outside};
    }
    const char *part_names[FB_MAX_LAYERS];
    exrio_compression part_comp[FB_MAX_LAYERS];
    for (int i = 0; i < s->nlayers; i++) part_names[i] = s->layers[i].name, part_comp[i] = s->layers[i].compression;
    return exrio_writer_create(&(exrio_writer_desc){.path = d->out,
                                                    .width = region[2],
                                                    .height = region[3],
                                                    .x0 = region[0],
                                                    .y0 = region[1],
                                                    .full_width = partial ? s->width : 0,
                                                    .full_height = partial ? s->height : 0,
                                                    .row_stride = s->width,
                                                    .nparts = s->multipart ? s->nlayers : 1,
                                                    .part_names = s->multipart ? part_names : NULL,
                                                    .part_compression = s->multipart ? part_comp : NULL,
                                                    .compression = s->compression,
                                                    .channels = channels,
                                                    .nchannels = nch,
                                                    .attrs = attrs,
                                                    .nattrs = nattrs,
                                                    .threads = e->threads,
                                                    .zip_level = d->zip_level,
                                                    .envmap = s->envmap},
                               w);
}

/* The strips: each strip of each per-pixel layer dispatched (or queued on the pool) while the last
 * one is collected, op layers computed from it, checked, and handed to the heightmaps, the previews
 * and the writer. */
static fb_result run_strips(fb_engine *e, const fb_bake_desc *d, layer_run *runs, const int *offset,
                            const int region[4], int strip, exrio_writer *w, heightmaps *hm, previews *pv,
                            fb_faces *faces, double *gpu)
{
    const fb_scene *s = d->scene;
    int rx = region[0], ry = region[1], rw = region[2], rh = region[3];
    fb_result rc = FB_OK;
    fb_progress prog;
    fb_progress_init(&prog, d->progress, "bake", "pix");
    fb_progress_update(&prog, 0, (uint64_t)rh * rw * (uint64_t)s->nlayers); /* pixels of each layer */
    fb_progress_set_scale(&prog, s->nlayers);
    int nstrips = (rh + strip - 1) / strip;
    bool gpu_path = e->kind == FB_BACKEND_VULKAN;
    strip_job job;
    for (int i = 0; i < s->nlayers && gpu_path && !rc; i++) {
        fb_log_context("layer %s, rows %d-%d", s->layers[i].name, ry, ry + (strip < rh ? strip : rh) - 1);
        rc = run_submit(&runs[i].e, &runs[i], 0, ry, strip < rh ? strip : rh);
    }
    if (!rc) strip_start(e, runs, s->nlayers, &job, 0, ry, strip < rh ? strip : rh, &prog, rw);
    for (int k = 0; k < nstrips && !rc; k++) {
        int y0 = ry + k * strip, n = y0 + strip <= ry + rh ? strip : ry + rh - y0;
        /* Start the next strip before consuming this one, so the device and the pool work while
         * this one is checked, previewed and handed to the writer. */
        fb_pool_wait(e->pool); /* this strip's host rows */
        if (k + 1 < nstrips) {
            int y1 = y0 + strip, n1 = y1 + strip <= ry + rh ? strip : ry + rh - y1;
            for (int i = 0; i < s->nlayers && gpu_path && !rc; i++) {
                fb_log_context("layer %s, rows %d-%d", s->layers[i].name, y1, y1 + n1 - 1);
                rc = run_submit(&runs[i].e, &runs[i], (k + 1) % SLOTS, y1, n1);
            }
            if (!rc) strip_start(e, runs, s->nlayers, &job, (k + 1) % SLOTS, y1, n1, &prog, rw);
        }
        const void *planes[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS];
        int at = 0;
        for (int i = 0; i < s->nlayers && !rc; i++) {
            fb_log_context("layer %s, rows %d-%d", s->layers[i].name, y0, y0 + n - 1);
            if (!runs[i].gen.compute.host_rows) rc = run_collect(&runs[i].e, &runs[i], k % SLOTS, planes + at, gpu);
            if (!rc && run_on_gpu(&runs[i].e, &runs[i])) fb_progress_add(&prog, (uint64_t)n * rw);
            at += runs[i].gen.store.nchannels;
        }
        for (int j = 0; j < s->nlayers && !rc; j++) { /* op layers, after the layers they use */
            layer_run *lr = &runs[s->order[j]];
            if (!lr->gen.compute.host_rows) continue;
            lr->gen.compute.host_rows(&lr->gen, (size_t)n * s->width, planes, lr->planes[0][0]);
            planes[offset[s->order[j]]] = lr->planes[0][0];
            fb_progress_add(&prog, (uint64_t)n * rw);
        }
        if (rc) break;
        for (int c = 0; c < at; c++) planes[c] = (const uint8_t *)planes[c] + (size_t)rx * 4; /* the region's columns */
        rc = check_finite(runs, s->nlayers, planes, y0, n, rx, rw, s->width);
        if (!rc) heightmaps_add(s, hm, planes, y0 - ry, n, rw);
        if (!rc && d->preview) rc = previews_add(pv, runs, y0 - ry, n, planes);
        fb_log_context("rows %d-%d", y0, y0 + n - 1);
        if (!rc && w) rc = exrio_writer_rows(w, y0 - ry, n, planes);
        if (!rc && faces) rc = fb_faces_rows(faces, y0, n, planes, s->width);
        fb_log_context(NULL);
    }
    fb_progress_finish(&prog);
    return rc;
}

/* The engine face sets of a cube bake (faces.h): the whole cube, every channel; PNG faces show the
 * first colour layer. */
static fb_result faces_create(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs,
                              const exrio_channel *channels, int nch, fb_faces **out)
{
    const fb_scene *s = d->scene;
    if (s->envmap != EXRIO_ENVMAP_CUBE || d->region[2] > 0)
        return fb_fail(FB_ERR_USAGE,
                       "--cube-faces: needs the whole of a cube environment map (mapping cube, no --region)");
    int rgb = -1;
    for (int i = 0, at = 0; i < s->nlayers && rgb < 0; at += runs[i].gen.store.nchannels, i++)
        if (runs[i].gen.store.preview_rgb >= 0) rgb = at + runs[i].gen.store.preview_rgb;
    return fb_faces_create(&(fb_faces_desc){.pattern = d->cube_faces,
                                            .n = s->width,
                                            .channels = channels,
                                            .nchannels = nch,
                                            .rgb = rgb,
                                            .compression = s->compression,
                                            .threads = e->threads,
                                            .zip_level = d->zip_level},
                           out);
}

fb_result fb_bake(fb_engine *e, const fb_bake_desc *d, fb_bake_stats *stats)
{
    if (stats) stats->ran_on[0] = stats->preview[0] = 0, stats->nheightmaps = 0;
    heightmaps hm = {0};
    const fb_scene *s = d->scene;
    layer_run *runs = calloc((size_t)s->nlayers, sizeof *runs);
    exrio_channel channels[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS];
    int nch = 0, region[4] = {0, 0, s->width, s->height}, strip = 1;
    exrio_writer *w = NULL;
    previews pv = {0};
    fb_faces *faces = NULL;
    double t0 = fb_now(), gpu = 0;
    if (!runs) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_outputs_begin();
    fb_result rc = reserve_outputs(d, s);
    if (!rc) rc = bake_window(e, d, region, &strip);
    for (int i = 0; i < s->nlayers && !rc; i++) {
        fb_log_context("layer %s", s->layers[i].name);
        rc = fb_gen_init_run(
            &runs[i].gen, s, &s->layers[i],
            &(fb_gen_run){{d->points_part[0], d->points_part[1]}, {d->max_memory, e->overhead}, e->scalar});
        runs[i].e = *e;
        if (e->per_layer) /* auto on a CPU device: each layer where it runs faster (engine.h) */
            runs[i].e.kind = runs[i].gen.compute.lavapipe_faster ? FB_BACKEND_VULKAN : FB_BACKEND_NATIVE;
        fb_backend was;
        if (fb_layer_backend_of(d->layer_kinds, s->layers[i].name, &was) && (was == FB_BACKEND_NATIVE || e->vk))
            runs[i].e.kind = was; /* where it ran in the file baked again */
        for (int c = 0; c < runs[i].gen.store.nchannels && !rc; c++)
            channels[nch++] = (exrio_channel){runs[i].gen.store.channel_names[c], runs[i].gen.store.channel_types[c],
                                              s->multipart ? i : 0};
    }
    /* Memory is predicted, not discovered: the whole bake's peak, before anything large exists. */
    fb_bake_plan plan_local, *plan = d->plan ? d->plan : &plan_local;
    if (!rc) rc = plan_memory(e, d, runs, strip, nch, region[2], plan);
    fb_log_context(NULL);
    if (!rc) fb_engine_say_fallback(e); /* only now: a refused bake gives one line */
    if (!rc && d->dry_run) goto out;
    if (!rc && d->cube_faces) rc = faces_create(e, d, runs, channels, nch, &faces);
    for (int i = 0; i < s->nlayers && !rc; i++) {
        fb_log_context("layer %s", s->layers[i].name);
        rc = run_init(&runs[i].e, &runs[i], strip);
    }
    /* Layers that use others (op inputs, a macro shape) find them among every layer's generator. */
    int offset[FB_MAX_LAYERS];
    const fb_gen *gens[FB_MAX_LAYERS];
    for (int i = 0, at = 0; i < s->nlayers; at += runs[i].gen.store.nchannels, i++)
        offset[i] = at, gens[i] = &runs[i].gen;
    for (int i = 0; i < s->nlayers && !rc; i++)
        if (runs[i].gen.resolve) rc = runs[i].gen.resolve(&runs[i].gen, gens, offset);
    if (!rc) rc = heightmaps_create(s, runs, offset, d->region, &hm);
    /* Layers computed as a whole (the chaos game) run before the first strip. */
    for (int j = 0; j < s->nlayers && !rc; j++) { /* in dependency order: a macro's source first */
        int i = s->order[j];
        if (!runs[i].gen.prepare) continue;
        fb_log_context("layer %s", s->layers[i].name);
        rc = runs[i].gen.prepare(&runs[i].gen, &runs[i].e, d->progress);
        if (runs[i].gen.prepared.gpu_seconds > 0) gpu += runs[i].gen.prepared.gpu_seconds;
    }
    if (rc) goto out;
    if (stats) {
        ran_on(e, runs, s, stats->ran_on, sizeof stats->ran_on);
        for (int i = 0; i < s->nlayers; i++) stats->layer_backend[i] = runs[i].e.kind;
    }
    if (d->out && (rc = open_writer(e, d, runs, channels, nch, region, &w))) goto out;
    if (d->preview && (rc = previews_create(s, runs, d->preview_layer, region, &pv, stats ? stats->preview : NULL,
                                            stats ? sizeof stats->preview : 0)))
        goto out;
    rc = run_strips(e, d, runs, offset, region, strip, w, &hm, &pv, faces, &gpu);
    /* Checked before the file is renamed into place: a validated run that broke a rule is a failure. */
    if (!rc && e->vk && vkc_validation_messages(e->vk))
        rc = fb_fail(FB_ERR_VULKAN, "vulkan validation reported %u message(s) (see above)",
                     vkc_validation_messages(e->vk));
    if (!rc && w) rc = exrio_writer_finish(&w);
    if (!rc && d->preview) rc = previews_write(&pv, d->preview);
    if (!rc) rc = heightmaps_write(s, runs, &hm, region, stats);
    for (int i = 0; i < s->nlayers && !rc && d->report; i++)
        if (runs[i].gen.prepared.summary[0])
            d->report(runs[i].gen.layer->name, runs[i].gen.prepared.summary, runs[i].gen.prepared.summary_json,
                      d->user);
out:
    fb_log_context(NULL);
    fb_pool_wait(e->pool); /* a strip still computing when an error stopped the loop */
    exrio_writer_abort(&w);
    rc = fb_outputs_end(rc); /* every output renamed into place now, or none */
    for (int k = 0; k < pv.n; k++) fb_preview_destroy(&pv.p[k]);
    free(pv.conv);
    fb_faces_destroy(&faces);
    heightmaps_free(s, &hm);
    for (int i = 0; i < s->nlayers; i++) run_fini(&runs[i].e, &runs[i]);
    free(runs);
    if (stats) {
        stats->seconds = fb_now() - t0;
        stats->gpu_seconds = e->kind == FB_BACKEND_VULKAN ? gpu : -1;
        stats->pixels = (uint64_t)region[2] * region[3];
    }
    return rc;
}
