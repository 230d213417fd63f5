/*
 * The bake driver. See bake.h: every layer's generator set up, the memory predicted, the pieces sized
 * for the device, the prepares run, then the pieces produced and fed to the sinks (pieces.c, sinks.c).
 */
#include "bake_int.h"
#include "faces.h"

#include "output.h"
#include "spvpatch.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- sizes ---------------------------------------------------------------------------------- */

/* On a CPU (native, or lavapipe's shaders): about 4 MiB per channel buffer, well inside lavapipe's 128
 * MiB maxStorageBufferRange and small enough that the pieces in flight stay a small part of memory at
 * any image size; and at least 32 pieces (of 16 rows or more), which is what a GPU layer's progress
 * can see. */
static int auto_strip_rows(const fb_scene *s, int height)
{
    long rows = (1L << 20) / s->width;
    if (rows >= 64) rows -= rows % 64;
    long part = (height + 31) / 32;
    part = part < 16 ? 16 : (part + 15) / 16 * 16;
    if (rows > part) rows = part;
    if (rows < 1) rows = 1;
    if (rows > height) rows = height;
    return (int)rows;
}

/* `rows` at most `most`, a multiple of 64 when a whole number of the EXR writer's batches was asked
 * for (the writer then reads the pieces in place). */
static long cap_rows(long rows, long most, bool batches)
{
    if (rows <= most) return rows;
    return batches && most >= 64 ? most - most % 64 : most;
}

static bool any_gpu(const layer_run *runs, int n)
{
    for (int i = 0; i < n; i++)
        if (runs[i].where == RUN_GPU) return true;
    return false;
}

/* The rows of a piece: --strip-rows, or on a discrete GPU's path a dispatch of millions of
 * invocations (BAKE_GPU_PIECE_PIXELS), or a CPU's strip; within what one storage buffer and one
 * dispatch may hold, and on a GPU what its memory holds of the smallest ring. */
static fb_result piece_rows(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs, bool staged, int rh,
                            int *out)
{
    const fb_scene *s = d->scene;
    uint64_t row = (uint64_t)s->width * 4;
    long rows = d->strip_rows > 0 ? d->strip_rows
                : staged          ? (long)(BAKE_GPU_PIECE_PIXELS / (uint64_t)s->width)
                                  : auto_strip_rows(s, rh);
    bool batches = d->strip_rows <= 0 && staged;
    if (batches) rows = rows >= 64 ? rows - rows % 64 : 64;
    rows = rows > rh ? rh : rows;
    if (e->kind == FB_BACKEND_VULKAN) {
        const vkc_device_info *info = vkc_info(e->vk);
        if (row > info->max_storage_buffer_range)
            return fb_fail(FB_ERR_INPUT, "image width %d is too wide for one storage buffer row on this device",
                           s->width);
        rows = cap_rows(rows, (long)(info->max_storage_buffer_range / row), batches);
        if (any_gpu(runs, s->nlayers)) rows = cap_rows(rows, (long)info->max_workgroup_count[1], batches);
    }
    if (staged) {
        const vkc_device_info *info = vkc_info(e->vk);
        uint64_t host, device;
        pieces_slot_bytes(e, runs, s->nlayers, s->width, 1, true, &host, &device);
        uint64_t max_alloc = info->max_allocation ? info->max_allocation : (uint64_t)1 << 30;
        for (int i = 0; i < s->nlayers; i++) { /* a layer's host buffer is one allocation */
            int stored = 0;
            for (int k = 0; k < fb_gen_nplanes(&runs[i].gen); k++) stored += fb_gen_plane_stored(&runs[i].gen, k);
            if (runs[i].where == RUN_GPU && stored) rows = cap_rows(rows, (long)(max_alloc / (row * stored)), batches);
        }
        if (device) rows = cap_rows(rows, (long)(info->heap / 2 / 3 / device), batches); /* 3 slots in half the heap */
    }
    *out = rows < 1 ? 1 : (int)rows;
    return FB_OK;
}

/* The EXR writer's batches in flight (exrio_write.c: twice its workers and two, and the one filling). */
static int writer_batches(const fb_engine *e)
{
    return 2 * e->threads + 3;
}

/* The ring: the consumer's piece and the producer's (two with the GPU a piece ahead), and, when the
 * writer reads pieces in place, as many more as hold its batches in flight. */
static int full_slots(const fb_engine *e, const bake_shape *sh, bool ahead)
{
    int slots = ahead ? 3 : 2;
    if (sh->held) slots += (64 * (writer_batches(e) - 1) + sh->rows - 1) / sh->rows;
    return slots > 64 ? 64 : slots;
}

/* ---- memory --------------------------------------------------------------------------------- */

/* The bake's predicted peak for the shape: the process and its backend, every layer's own arrays (the
 * largest transient one at a time, as layers prepare one after another, on top of what every layer
 * keeps), the ring's pieces, then either the preparing or the writer's queue and the preview's sums.
 * Pages a layer allocates but never touches (a chaos game's empty histogram cells) count: it is a
 * bound. Device memory (a discrete GPU's) is counted apart. */
static void plan_fill(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs, const bake_shape *sh,
                      const exrio_channel *channels, int nch, fb_bake_plan *plan)
{
    uint64_t px = 0; /* bytes of a pixel in the file */
    for (int c = 0; c < nch; c++) px += channels[c].type == EXRIO_HALF ? 2 : 4;
    const fb_scene *s = d->scene;
    int rw = sh->region[2], rh = sh->region[3];
    uint64_t limit = plan->limit, planned = plan->planned;
    memset(plan, 0, sizeof *plan);
    plan->limit = limit, plan->planned = planned;
    plan->nlayers = s->nlayers;
    plan->piece_rows = sh->rows;
    plan->slots = sh->slots;
    plan->base = e->kind == FB_BACKEND_VULKAN ? (uint64_t)80 << 20 : (uint64_t)12 << 20;
    bool unified = e->vk && vkc_info(e->vk)->unified;
    /* A CPU device (lavapipe) compiles each pipeline with LLVM in this process, one at a time, before
     * the pieces' buffers exist (pieces.c gives the compiler's freed memory back to the system
     * then). For the module it compiles (the native variant where the device divides exactly,
     * spvpatch.h) of s bytes, about 600 s + s^2 / 232 bytes at the peak: one-layer bakes on Mesa
     * 22.3.6, 2026-12-04, peak RSS above `fractalbake devices` (61 MiB): lsys's 11.6 KB 10 MiB,
     * stars' 27 KB 20 MiB, fbm's 44 KB 38 MiB, julia's 102 KB 85 MiB, fbm_env's 96 KB 110 MiB,
     * julia_env's 162 KB 218 MiB. */
    for (int i = 0; i < s->nlayers && e->vk && !strcmp(vkc_info(e->vk)->type, "cpu"); i++) {
        const fb_gen_shader *sh = &runs[i].gen.compute.shader;
        size_t words = 0;
        if (runs[i].where == RUN_GPU) spv_variant(sh->spv, sh->spv_size / 4, vkc_info(e->vk)->exact_native, &words);
        uint64_t spv = (uint64_t)words * 4, bytes = 600 * spv + spv * spv / 232;
        if (bytes > plan->compile) plan->compile = bytes;
    }
    uint64_t hold_sum = 0, extra_max = 0;
    for (int i = 0; i < s->nlayers; i++) {
        const fb_gen *g = &runs[i].gen;
        uint64_t hold = 0, peak = g->memory ? g->memory(g, &runs[i].e, &hold) : 0;
        if (s->layers[i].heightmap[0]) { /* its heights, kept for the heightmap written at the end */
            uint64_t hm = (uint64_t)rw * rh * 4;
            hold += hm, peak += hm;
        }
        uint64_t host, device, input = runs[i].where == RUN_GPU ? g->compute.shader.input_size : 0;
        pieces_slot_bytes(e, &runs[i], 1, s->width, sh->rows, sh->staged, &host, &device);
        host = host * (uint64_t)sh->slots + (sh->staged && !unified ? 0 : input);
        device = device * (uint64_t)sh->slots + (sh->staged && !unified ? input : 0);
        hold_sum += hold;
        plan->pieces += host;
        plan->device += device;
        if (peak - hold > extra_max) extra_max = peak - hold;
        snprintf(plan->layers[i].name, sizeof plan->layers[i].name, "%s", s->layers[i].name);
        plan->layers[i].bytes = peak + host;
    }
    /* the writer: the compressed chunks of every batch in flight (a quarter of the raw rows, on average
     * over what the generators make), and their raw rows when it copies them */
    uint64_t batch = 64 * (uint64_t)rw * 4 * (uint64_t)nch, batches = (uint64_t)writer_batches(e);
    if (sh->held && batches > (uint64_t)sh->slots * ((sh->rows + 63) / 64))
        batches = (uint64_t)sh->slots * ((sh->rows + 63) / 64);
    if (d->out) plan->writer = batches * batch * (sh->held ? 1 : 5) / 4;
    /* and each compression thread's deflate state with its three chunk buffers of 16 rows as the file
     * stores them (half channels 2 bytes a value): packed, split, predicted (it deflates into the
     * chunk's own buffer) */
    bool zip = s->compression == EXRIO_ZIP;
    for (int i = 0; i < s->nlayers; i++) zip = zip || (s->multipart && s->layers[i].compression == EXRIO_ZIP);
    if (d->out && zip)
        plan->writer += (uint64_t)e->threads * (exrio_zip_state_bytes(d->zip_level) + 3 * 16 * (uint64_t)rw * px);
    if (d->preview) {
        int side = rw > rh ? rw : rh, scale = (side + 2047) / 2048;
        uint64_t px = (uint64_t)((rw + scale - 1) / scale) * (uint64_t)((rh + scale - 1) / scale);
        plan->preview = px * (4 * 8 + 4) * (uint64_t)s->nlayers;
    }
    if (d->cube_faces) plan->preview += fb_faces_bytes(s->width, nch); /* one face of every channel */
    /* Layers prepare (chaos game, mesh, grid) before the writer and the preview exist: the peak is
     * the worse of the two phases. */
    uint64_t streaming = plan->writer + plan->preview;
    uint64_t data = plan->pieces + hold_sum + (extra_max > streaming ? extra_max : streaming);
    plan->peak = plan->base + (plan->compile > data ? plan->compile : data);
}

/* Fails naming the largest layer when the peak is beyond the bake's limit (its max_memory, with the
 * engine's overhead), or the device's memory beyond what its heap holds. */
static fb_result plan_refuse(const fb_engine *e, const fb_bake_desc *d, const fb_bake_plan *plan)
{
    char need[32], lim[32], big[32], note[160];
    if (plan->peak <= plan->limit) {
        uint64_t heap = e->vk ? vkc_info(e->vk)->heap : 0;
        if (!plan->device || plan->device <= heap) return FB_OK;
        fb_format_bytes(plan->device, need, sizeof need);
        fb_format_bytes(heap, lim, sizeof lim);
        return fb_fail(FB_ERR_INPUT,
                       "the bake needs about %s of device memory, more than %s has (%s): use --strip-rows", need,
                       e->device, lim);
    }
    int largest = 0;
    for (int i = 1; i < plan->nlayers; i++)
        if (plan->layers[i].bytes > plan->layers[largest].bytes) largest = i;
    const fb_memory mem = {d->max_memory, e->overhead};
    fb_format_bytes(plan->limit, lim, sizeof lim);
    fb_format_bytes(plan->layers[largest].bytes, big, sizeof big);
    char least[80] = "";
    if (plan->planned > plan->peak) { /* the ring shrunk as far as it goes: still too much */
        char fewest[32];
        fb_format_bytes(plan->peak, fewest, sizeof fewest);
        snprintf(least, sizeof least, " (%s with the fewest pieces in flight)", fewest);
    }
    fb_format_bytes(plan->planned, need, sizeof need);
    return fb_fail(FB_ERR_INPUT,
                   "the bake needs about %s%s, more than --max-memory %s%s; layer %s alone needs %s (lower its size, "
                   "points or insertions, or raise --max-memory)",
                   need, least, lim, fb_memory_limit_note(&mem, note, sizeof note), plan->layers[largest].name, big);
}

/* The shape of the bake and its memory: memory is predicted, not discovered, the whole bake's peak
 * before anything large exists. The ring shrinks to what --max-memory holds (fewer pieces in flight,
 * then on a GPU smaller pieces) before the bake is refused. */
static fb_result bake_shape_plan(const fb_engine *e, const fb_bake_desc *d, const layer_run *runs,
                                 const exrio_channel *channels, int nch, bake_shape *sh, fb_bake_plan *plan)
{
    const fb_scene *s = d->scene;
    bool ahead = any_gpu(runs, s->nlayers);
    sh->staged = ahead && vkc_info(e->vk)->staging;
    sh->threads = sh->staged ? e->threads : 1; /* the sinks' bands: every core while a GPU computes */
    for (int i = 0; i < s->nlayers; i++) sh->nplanes += runs[i].gen.store.nchannels;
    fb_result rc = piece_rows(e, d, runs, sh->staged, sh->region[3], &sh->rows);
    if (rc) return rc;
    const fb_memory mem = {d->max_memory, e->overhead};
    plan->planned = 0;
    for (;;) {
        /* no file, no writer: the ring holds the producer's piece and the consumer's alone */
        sh->held = d->out && (sh->rows % 64 == 0 || sh->rows >= sh->region[3]);
        int npieces = (sh->region[3] + sh->rows - 1) / sh->rows, least = ahead ? 3 : 2;
        least = least < npieces ? least : npieces; /* no more slots than pieces */
        sh->slots = full_slots(e, sh, ahead);
        sh->slots = sh->slots < npieces ? sh->slots : npieces;
        for (;;) {
            plan->limit = fb_memory_limit(&mem);
            plan_fill(e, d, runs, sh, channels, nch, plan);
            if (!plan->planned) plan->planned = plan->peak; /* the shape before any shrinking */
            if (plan->peak <= plan->limit || sh->slots <= least) break;
            sh->slots--;
        }
        if (plan->peak <= plan->limit || !sh->staged || d->strip_rows > 0 || sh->rows <= 64) break;
        sh->rows = sh->rows / 2 >= 64 ? sh->rows / 2 - sh->rows / 2 % 64 : 64;
    }
    return d->dry_run ? FB_OK : plan_refuse(e, d, plan); /* a dry run shows the prediction, whatever it is */
}

/* ---- the bake ------------------------------------------------------------------------------- */

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

/* The pixels baked: region[] = x, y, w, h (the desc's region, or the whole image). */
static fb_result bake_window(const fb_bake_desc *d, int region[4])
{
    const fb_scene *s = d->scene;
    region[0] = 0, region[1] = 0, region[2] = s->width, region[3] = s->height;
    if (d->region[2] <= 0) return FB_OK;
    int rx = d->region[0], ry = d->region[1], rw = d->region[2], rh = d->region[3];
    if (rx < 0 || ry < 0 || rh <= 0 || (long)rx + rw > s->width || (long)ry + rh > s->height)
        return fb_fail(FB_ERR_USAGE, "--region %d,%d,%d,%d: not inside the %d x %d image", rx, ry, rw, rh, s->width,
                       s->height);
    memcpy(region, d->region, sizeof d->region);
    return FB_OK;
}

/* Layer i's generator, the backend it runs on and where its rows come from. */
static fb_result layer_init(fb_engine *e, const fb_bake_desc *d, layer_run *lr, int i)
{
    const fb_scene *s = d->scene;
    fb_log_context("layer %s", s->layers[i].name);
    fb_result rc = fb_gen_init_run(
        &lr->gen, s, &s->layers[i],
        &(fb_gen_run){{d->points_part[0], d->points_part[1]},
                      {d->dry_run ? UINT64_MAX : d->max_memory, e->overhead}, /* predicted, not refused */
                      e->scalar});
    lr->e = *e;
    if (e->per_layer) /* auto on a CPU device: each layer where it runs faster (engine.h) */
        lr->e.kind = lr->gen.compute.lavapipe_faster ? FB_BACKEND_VULKAN : FB_BACKEND_NATIVE;
    fb_backend was;
    if (fb_layer_backend_of(d->layer_kinds, s->layers[i].name, &was) && (was == FB_BACKEND_NATIVE || e->vk))
        lr->e.kind = was; /* where it ran in the file baked again */
    const fb_gen *g = &lr->gen;
    lr->where = g->compute.host_rows                                                      ? RUN_HOST
                : lr->e.kind == FB_BACKEND_VULKAN && !g->prepare && g->compute.shader.spv ? RUN_GPU
                                                                                          : RUN_POOL;
    return rc;
}

/* What the bake holds while it runs, freed by bake_free whatever happened. */
typedef struct bake_state {
    layer_run *runs;
    pieces *ring;
    fb_sink sinks[5];
    int nsinks;
    exrio_channel channels[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS];
    int nch;
    bake_shape shape;
    bake_view view;
} bake_state;

static void bake_free(bake_state *b, int nlayers)
{
    for (int k = b->nsinks - 1; k >= 0; k--) b->sinks[k].destroy(b->sinks[k].self);
    b->nsinks = 0;
    pieces_destroy(&b->ring);
    for (int i = 0; b->runs && i < nlayers; i++) fb_gen_fini(&b->runs[i].gen);
    free(b->runs);
    b->runs = NULL;
}

/* Counts the sink just made (when rc is FB_OK). */
static fb_result added(bake_state *b, fb_result rc)
{
    b->nsinks += !rc;
    return rc;
}

/* The layers set up and the shape planned (what --dry-run shows). */
static fb_result bake_setup(fb_engine *e, const fb_bake_desc *d, bake_state *b, fb_bake_plan *plan)
{
    const fb_scene *s = d->scene;
    fb_result rc = bake_window(d, b->shape.region);
    for (int i = 0, at = 0; i < s->nlayers && !rc; i++) {
        rc = layer_init(e, d, &b->runs[i], i);
        b->runs[i].offset = at;
        const fb_gen *g = &b->runs[i].gen;
        for (int c = 0; c < g->store.nchannels && !rc; c++, at++)
            b->channels[b->nch++] =
                (exrio_channel){g->store.channel_names[c], g->store.channel_types[c], s->multipart ? i : 0};
    }
    fb_log_context(NULL);
    if (!rc) rc = bake_shape_plan(e, d, b->runs, b->channels, b->nch, &b->shape, plan);
    b->view = (bake_view){.d = d, .s = s, .e = e, .runs = b->runs, .region = b->shape.region};
    return rc;
}

/* The ring, the sinks that check their outputs before any work, the layers' references and
 * preparation (in dependency order: a macro's source first). */
static fb_result bake_prepare(fb_engine *e, const fb_bake_desc *d, bake_state *b, fb_bake_stats *stats, double *gpu)
{
    const fb_scene *s = d->scene;
    fb_result rc = added(b, sink_check_create(&b->view, &b->sinks[b->nsinks]));
    if (!rc && d->cube_faces) rc = added(b, sink_faces_create(&b->view, b->channels, b->nch, &b->sinks[b->nsinks]));
    if (!rc) rc = pieces_create(e, b->runs, s->nlayers, &b->shape, &b->ring);
    const fb_gen *gens[FB_MAX_LAYERS];
    int offset[FB_MAX_LAYERS];
    for (int i = 0; i < s->nlayers; i++) offset[i] = b->runs[i].offset, gens[i] = &b->runs[i].gen;
    for (int i = 0; i < s->nlayers && !rc; i++)
        if (b->runs[i].gen.resolve) rc = b->runs[i].gen.resolve(&b->runs[i].gen, gens, offset);
    if (!rc) rc = added(b, sink_heightmaps_create(&b->view, stats, &b->sinks[b->nsinks]));
    for (int j = 0; j < s->nlayers && !rc; j++) {
        layer_run *lr = &b->runs[s->order[j]];
        if (!lr->gen.prepare) continue;
        fb_log_context("layer %s", lr->gen.layer->name);
        rc = lr->gen.prepare(&lr->gen, &lr->e, d->progress);
        if (lr->gen.prepared.gpu_seconds > 0) *gpu += lr->gen.prepared.gpu_seconds;
    }
    fb_log_context(NULL);
    return rc;
}

/* The pieces through the sinks, then every sink's end: a validated run that broke a rule fails before
 * anything is renamed into place. */
static fb_result bake_stream(fb_engine *e, const fb_bake_desc *d, bake_state *b, fb_bake_stats *stats, double *gpu)
{
    fb_result rc = FB_OK;
    if (d->out) rc = added(b, sink_exr_create(&b->view, &b->shape, b->channels, b->nch, &b->sinks[b->nsinks]));
    if (!rc && d->preview)
        rc = added(b, sink_previews_create(&b->view, stats ? stats->preview : NULL, stats ? sizeof stats->preview : 0,
                                           &b->sinks[b->nsinks]));
    fb_sink *list[5];
    for (int k = 0; k < b->nsinks; k++) list[k] = &b->sinks[k];
    if (!rc) rc = pieces_run(b->ring, list, b->nsinks, d->progress, gpu);
    if (!rc && e->vk && vkc_validation_messages(e->vk))
        rc = fb_fail(FB_ERR_VULKAN, "vulkan validation reported %u message(s) (see above)",
                     vkc_validation_messages(e->vk));
    for (int k = 0; k < b->nsinks && !rc; k++)
        if (b->sinks[k].end) rc = b->sinks[k].end(b->sinks[k].self);
    return rc;
}

fb_result fb_bake(fb_engine *e, const fb_bake_desc *d, fb_bake_stats *stats)
{
    if (stats) stats->ran_on[0] = stats->preview[0] = 0, stats->nheightmaps = 0;
    const fb_scene *s = d->scene;
    double t0 = fb_now(), gpu = 0;
    bake_state b = {.runs = calloc((size_t)s->nlayers, sizeof *b.runs)};
    if (!b.runs) return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_outputs_begin();
    fb_bake_plan plan_local, *plan = d->plan ? d->plan : &plan_local;
    fb_result rc = reserve_outputs(d, s);
    if (!rc) rc = bake_setup(e, d, &b, plan);
    if (!rc) fb_engine_say_fallback(e); /* only now: a refused bake gives one line */
    if (!rc && !d->dry_run) rc = bake_prepare(e, d, &b, stats, &gpu);
    if (!rc && !d->dry_run && stats) {
        ran_on(e, b.runs, s, stats->ran_on, sizeof stats->ran_on);
        for (int i = 0; i < s->nlayers; i++) stats->layer_backend[i] = b.runs[i].e.kind;
    }
    if (!rc && !d->dry_run) rc = bake_stream(e, d, &b, stats, &gpu);
    for (int i = 0; i < s->nlayers && !rc && !d->dry_run && d->report; i++)
        if (b.runs[i].gen.prepared.summary[0])
            d->report(b.runs[i].gen.layer->name, b.runs[i].gen.prepared.summary, b.runs[i].gen.prepared.summary_json,
                      d->user);
    fb_log_context(NULL);
    bake_free(&b, s->nlayers); /* the writer abandoned (its file removed) unless it finished */
    rc = fb_outputs_end(rc);   /* every output renamed into place now, or none */
    if (stats) {
        stats->seconds = fb_now() - t0;
        stats->gpu_seconds = e->kind == FB_BACKEND_VULKAN ? gpu : -1;
        stats->pixels = (uint64_t)b.shape.region[2] * b.shape.region[3];
    }
    return rc;
}
