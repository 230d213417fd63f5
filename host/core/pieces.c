/*
 * The bake's pieces: a ring of slots between the producer and the sinks (bake_int.h, sink.h).
 *
 * The producer (the bake's thread) fills piece k into slot k mod slots: the GPU layers' dispatches
 * (submitted one piece ahead, so that the device computes the next piece while this one is
 * finished), the pool layers' rows on the host's pool, then the op layers from those planes. A
 * consumer thread hands each finished piece, in order, to every sink: first the sinks' bands (the
 * finite check, heightmaps, preview) on its own workers, then each sink's rows in turn (the EXR
 * writer, which keeps the piece until its workers have encoded it, and the cube faces). A slot is
 * filled again only when the consumer and every sink holding it have let it go, so at most `slots`
 * pieces exist at once whatever the speed of either side.
 *
 * Where the GPU's memory is its own (shape->staged), each slot has device buffers for the layer's
 * kernel planes and a host buffer its stored planes are copied into after the dispatch, in the same
 * submission; on a CPU device the shader writes mapped memory that the sinks read directly.
 */
#include "bake_int.h"

#include "progress.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_PLANES (FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS)

typedef struct slot {
    struct pieces *ring;
    int index, y0, n; /* the piece it holds */
    int refs;         /* holds (the consumer's, the EXR writer's batches), under ring->mu */
    bool ready;       /* produced and not yet taken by the consumer */
    void *mem[FB_MAX_LAYERS][FB_GEN_MAX_CHANNELS];       /* pool and op layers: their stored planes */
    vkc_job *job[FB_MAX_LAYERS];                         /* GPU layers */
    vkc_buffer *buf[FB_MAX_LAYERS][FB_GEN_MAX_CHANNELS]; /* a GPU layer's kernel planes */
    vkc_buffer *host[FB_MAX_LAYERS];                     /* staged: its stored planes, read back */
    const void *planes[MAX_PLANES];                      /* every stored channel, column 0 of row y0 */
} slot;

struct pieces {
    fb_engine *e;
    layer_run *runs;
    int nlayers;
    bake_shape shape;
    int width, npieces;
    size_t plane_bytes; /* a plane of a full piece */
    vkc_pipeline *pipe[FB_MAX_LAYERS];
    vkc_buffer *input[FB_MAX_LAYERS]; /* a GPU layer's input, shared by every slot's job */
    slot *slots;

    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool stop;      /* the producer or the consumer failed: the other stops */
    fb_result fail; /* the consumer's failure */
    fb_sink *const *sinks;
    int nsinks;
    fb_pool *bands; /* the consumer's band workers */
    fb_scope scope; /* the bake's thread's (fb.h): the consumer works in it */
    fb_progress prog;
};

static int stored_planes(const fb_gen *g)
{
    int n = 0;
    for (int k = 0; k < fb_gen_nplanes(g); k++) n += fb_gen_plane_stored(g, k);
    return n;
}

void pieces_slot_bytes(const fb_engine *e, const layer_run *runs, int nlayers, int width, int rows, bool staged,
                       uint64_t *host, uint64_t *device)
{
    uint64_t plane = (uint64_t)width * (uint64_t)rows * 4;
    *host = *device = 0;
    for (int i = 0; i < nlayers; i++) {
        uint64_t bytes = (uint64_t)stored_planes(&runs[i].gen) * plane;
        *host += bytes; /* planes, mapped shared buffers or host buffers */
        if (runs[i].where == RUN_GPU && staged) *device += bytes;
    }
    if (e->vk && vkc_info(e->vk)->unified) *host += *device, *device = 0; /* its device memory is ours */
}

/* ---- making the ring ------------------------------------------------------------------------ */

/* Layer i's pipeline and its input, shared by every slot. */
static fb_result gpu_layer(pieces *p, int i)
{
    const fb_gen *g = &p->runs[i].gen;
    const fb_gen_shader *sh = &g->compute.shader;
    vkc_context *vk = p->e->vk;
    int np = fb_gen_nplanes(g);
    if (sh->needs_float64 && !vkc_info(vk)->float64)
        return fb_fail(FB_ERR_INPUT,
                       "layer %s: precision \"double\" needs a Vulkan device with shaderFloat64, and %s has none "
                       "(use --backend native)",
                       g->layer->name, p->e->device);
    fb_result rc = vkc_pipeline_create(vk,
                                       &(vkc_pipeline_desc){.spv = sh->spv,
                                                            .spv_size = sh->spv_size,
                                                            .push_size = sh->push_size,
                                                            .buffers = (uint32_t)np + (sh->input ? 1u : 0u),
                                                            .uniform = sh->input && sh->input_uniform ? 1u << np : 0u,
                                                            .spec = sh->spec,
                                                            .nspec = sh->nspec,
                                                            .name = g->layer->name},
                                       &p->pipe[i]);
    /* read-only: in device memory where it is the GPU's own, so that no job copies it back */
    vkc_buffer_kind kind = p->shape.staged ? VKC_BUFFER_DEVICE : VKC_BUFFER_SHARED;
    if (!rc && sh->input) rc = vkc_buffer_create_kind(vk, sh->input_size, kind, &p->input[i]);
    if (!rc && sh->input) rc = vkc_buffer_upload(vk, p->input[i], sh->input, sh->input_size);
    return rc;
}

/* Slot t's buffers and planes for GPU layer i. A plane the layer does not store is never written: a
 * token buffer binds it. */
static fb_result slot_gpu(pieces *p, slot *sl, int i)
{
    const fb_gen *g = &p->runs[i].gen;
    vkc_context *vk = p->e->vk;
    fb_result rc = vkc_job_create(vk, p->pipe[i], &sl->job[i]);
    vkc_buffer_kind kind = p->shape.staged ? VKC_BUFFER_DEVICE : VKC_BUFFER_SHARED;
    for (int k = 0; k < fb_gen_nplanes(g) && !rc; k++)
        rc = vkc_buffer_create_kind(vk, fb_gen_plane_stored(g, k) ? p->plane_bytes : 16, kind, &sl->buf[i][k]);
    if (!rc && p->shape.staged)
        rc = vkc_buffer_create_kind(vk, (uint64_t)stored_planes(g) * p->plane_bytes, VKC_BUFFER_HOST, &sl->host[i]);
    for (int c = 0; c < g->store.nchannels && !rc; c++)
        sl->planes[p->runs[i].offset + c] = p->shape.staged
                                                ? (const uint8_t *)vkc_buffer_data(sl->host[i]) + c * p->plane_bytes
                                                : vkc_buffer_data(sl->buf[i][fb_gen_plane_of(g, c)]);
    return rc;
}

/* Slot t's host planes for pool or op layer i (an op layer has one). */
static fb_result slot_host(pieces *p, slot *sl, int i)
{
    const fb_gen *g = &p->runs[i].gen;
    for (int k = 0; k < fb_gen_nplanes(g); k++)
        if (fb_gen_plane_stored(g, k) && !(sl->mem[i][k] = malloc(p->plane_bytes)))
            return fb_fail(FB_ERR_NOMEM, "out of memory for a piece of rows");
    for (int c = 0; c < g->store.nchannels; c++) sl->planes[p->runs[i].offset + c] = sl->mem[i][fb_gen_plane_of(g, c)];
    return FB_OK;
}

fb_result pieces_create(fb_engine *e, layer_run *runs, int nlayers, const bake_shape *shape, pieces **out)
{
    pieces *p = calloc(1, sizeof *p);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->cv, NULL);
    p->e = e, p->runs = runs, p->nlayers = nlayers, p->shape = *shape;
    p->width = runs[0].gen.scene->width;
    p->npieces = (shape->region[3] + shape->rows - 1) / shape->rows;
    p->plane_bytes = (size_t)p->width * (size_t)shape->rows * 4;
    p->slots = calloc((size_t)shape->slots, sizeof *p->slots);
    fb_result rc = p->slots ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
    /* The pipelines first: a CPU device's compiler frees its memory before the pieces' buffers exist,
     * and that memory is given back to the system (it would otherwise stay in the allocator's heap,
     * beside the buffers, at the peak). */
    bool compiled = false;
    for (int i = 0; i < nlayers && !rc; i++) {
        fb_log_context("layer %s", runs[i].gen.layer->name);
        if (runs[i].where == RUN_GPU) rc = gpu_layer(p, i), compiled = true;
    }
    /* Only after a compiler ran: trimming the heap otherwise hands back the pages the last bake's
     * pieces left free, and this bake's pieces fault them in again (in a process that bakes again,
     * the bench's timed bakes among them: 11000 page faults a 4096 x 4096 Julia bake, 10% of it). */
    if (compiled) fb_release_free_memory();
    for (int i = 0; i < nlayers && !rc; i++) {
        fb_log_context("layer %s", runs[i].gen.layer->name);
        for (int t = 0; t < shape->slots && !rc; t++) {
            p->slots[t].ring = p;
            rc = runs[i].where == RUN_GPU ? slot_gpu(p, &p->slots[t], i) : slot_host(p, &p->slots[t], i);
        }
    }
    fb_log_context(NULL);
    if (rc) {
        pieces_destroy(&p);
        return rc;
    }
    *out = p;
    return FB_OK;
}

void pieces_destroy(pieces **pp)
{
    if (!pp || !*pp) return;
    pieces *p = *pp;
    vkc_context *vk = p->e->vk;
    for (int t = 0; p->slots && t < p->shape.slots; t++) {
        slot *sl = &p->slots[t];
        for (int i = 0; i < p->nlayers; i++) {
            if (vk) vkc_job_destroy(vk, &sl->job[i]); /* waits for one in flight */
            for (int k = 0; k < FB_GEN_MAX_CHANNELS; k++) {
                if (vk) vkc_buffer_destroy(vk, &sl->buf[i][k]);
                free(sl->mem[i][k]);
            }
            if (vk) vkc_buffer_destroy(vk, &sl->host[i]);
        }
    }
    for (int i = 0; i < p->nlayers && vk; i++) {
        vkc_buffer_destroy(vk, &p->input[i]);
        vkc_pipeline_destroy(vk, &p->pipe[i]);
    }
    free(p->slots);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->cv);
    free(p);
    *pp = NULL;
}

/* ---- holds ---------------------------------------------------------------------------------- */

void fb_piece_retain(void *owner)
{
    slot *sl = owner;
    pthread_mutex_lock(&sl->ring->mu);
    sl->refs++;
    pthread_mutex_unlock(&sl->ring->mu);
}

void fb_piece_release(void *owner)
{
    slot *sl = owner;
    pthread_mutex_lock(&sl->ring->mu);
    if (--sl->refs == 0) pthread_cond_broadcast(&sl->ring->cv);
    pthread_mutex_unlock(&sl->ring->mu);
}

/* Stops both sides: the producer at its next wait, the consumer at its next piece. */
static void ring_stop(pieces *p, fb_result rc)
{
    pthread_mutex_lock(&p->mu);
    p->stop = true;
    if (!p->fail) p->fail = rc;
    pthread_cond_broadcast(&p->cv);
    pthread_mutex_unlock(&p->mu);
}

/* ---- the producer --------------------------------------------------------------------------- */

/* Rows of one pool layer of a piece, cut into tasks. */
typedef struct native_task {
    const fb_gen *gen;
    int y0, n, rows_per_task;
    void *const *planes;
    fb_progress *prog; /* pixels done, counted per layer: each task adds its rows x `cols` */
    int cols;
} native_task;

/* One piece of every pool layer, as one pool job: its tasks are each layer's row blocks in turn. */
typedef struct piece_job {
    native_task t[FB_MAX_LAYERS];
    int first[FB_MAX_LAYERS + 1]; /* t[i]'s first task */
    int n;
} piece_job;

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

static void piece_task(void *ctx, int task)
{
    piece_job *j = ctx;
    int i = 0;
    while (task >= j->first[i + 1]) i++;
    native_task_fn(&j->t[i], task - j->first[i]);
}

/* The pool layers' rows of the piece in slot sl, on every core (the producer's thread included). */
static void run_pool(pieces *p, slot *sl)
{
    /* 16 tasks a thread: every piece ends on a barrier, where a core waits for the other's last task
     * (half a task on average); with 4 tasks a thread, that was 6% of a Julia bake's cores */
    int threads = fb_pool_threads(p->e->pool);
    int per = (sl->n + 16 * threads - 1) / (16 * threads);
    if (per < 1) per = 1;
    piece_job j = {.n = 0};
    for (int i = 0; i < p->nlayers; i++) {
        if (p->runs[i].where != RUN_POOL) continue;
        j.t[j.n] = (native_task){.gen = &p->runs[i].gen,
                                 .y0 = sl->y0,
                                 .n = sl->n,
                                 .rows_per_task = per,
                                 .planes = sl->mem[i],
                                 .prog = &p->prog,
                                 .cols = p->shape.region[2]};
        j.first[j.n + 1] = j.first[j.n] + (sl->n + per - 1) / per;
        j.n++;
    }
    if (j.n) fb_pool_run(p->e->pool, j.first[j.n], piece_task, &j);
}

/* Waits until slot k mod slots is free, makes it piece k's and submits its GPU layers' dispatches
 * (and, staged, the copies of their stored planes into the slot's host buffers). */
static fb_result slot_start(pieces *p, int k, slot **out)
{
    slot *sl = &p->slots[k % p->shape.slots];
    pthread_mutex_lock(&p->mu);
    while ((sl->refs > 0 || sl->ready) && !p->stop) pthread_cond_wait(&p->cv, &p->mu);
    bool stop = p->stop;
    pthread_mutex_unlock(&p->mu);
    if (stop) return FB_ERR_INTERNAL; /* the consumer failed: its error is the bake's */
    const int *region = p->shape.region;
    sl->index = k;
    sl->y0 = region[1] + k * p->shape.rows;
    sl->n = sl->y0 + p->shape.rows <= region[1] + region[3] ? p->shape.rows : region[1] + region[3] - sl->y0;
    *out = sl;
    fb_result rc = FB_OK;
    for (int i = 0; i < p->nlayers && !rc; i++) {
        if (p->runs[i].where != RUN_GPU) continue;
        const fb_gen *g = &p->runs[i].gen;
        fb_log_context("layer %s, rows %d-%d", g->layer->name, sl->y0, sl->y0 + sl->n - 1);
        uint8_t push[FB_GEN_MAX_PUSH];
        vkc_submit w = {.push = push};
        fb_gen_push(g, sl->y0, sl->n, push);
        fb_gen_groups(g, sl->n, w.groups);
        vkc_buffer *bufs[FB_GEN_MAX_CHANNELS + 1];
        int np = fb_gen_nplanes(g);
        memcpy(bufs, sl->buf[i], (size_t)np * sizeof *bufs);
        if (p->input[i]) bufs[np++] = p->input[i];
        w.bufs = bufs, w.nbufs = (uint32_t)np;
        vkc_copy copies[FB_GEN_MAX_CHANNELS];
        for (int c = 0; c < g->store.nchannels && p->shape.staged; c++)
            copies[c] = (vkc_copy){.src = sl->buf[i][fb_gen_plane_of(g, c)],
                                   .dst = sl->host[i],
                                   .dst_offset = c * p->plane_bytes,
                                   .size = (uint64_t)sl->n * p->width * 4};
        w.copies = copies, w.ncopies = p->shape.staged ? (uint32_t)g->store.nchannels : 0;
        rc = vkc_job_run(p->e->vk, sl->job[i], &w);
    }
    fb_log_context(NULL);
    return rc;
}

/* Completes the piece in slot sl: its pool layers, the GPU's results, its op layers; then hands it to
 * the consumer. */
static fb_result slot_finish(pieces *p, slot *sl, double *gpu_seconds)
{
    run_pool(p, sl);
    fb_result rc = FB_OK;
    uint64_t pixels = (uint64_t)sl->n * (uint64_t)p->shape.region[2];
    for (int i = 0; i < p->nlayers && !rc; i++) {
        if (p->runs[i].where != RUN_GPU) continue;
        fb_log_context("layer %s, rows %d-%d", p->runs[i].gen.layer->name, sl->y0, sl->y0 + sl->n - 1);
        double t = -1;
        rc = vkc_job_wait(p->e->vk, sl->job[i], &t);
        if (t > 0) *gpu_seconds += t;
        fb_progress_add(&p->prog, pixels);
    }
    fb_log_context(NULL);
    const fb_scene *s = p->runs[0].gen.scene;
    for (int j = 0; j < s->nlayers && !rc; j++) { /* op layers, after the layers they use */
        layer_run *lr = &p->runs[s->order[j]];
        if (lr->where != RUN_HOST) continue;
        lr->gen.compute.host_rows(&lr->gen, (size_t)sl->n * p->width, sl->planes, sl->mem[s->order[j]][0]);
        fb_progress_add(&p->prog, pixels);
    }
    if (rc) return rc;
    pthread_mutex_lock(&p->mu);
    sl->ready = true;
    sl->refs = 1; /* the consumer's */
    pthread_cond_broadcast(&p->cv);
    pthread_mutex_unlock(&p->mu);
    return FB_OK;
}

/* Every piece in order; with GPU layers, the next piece's dispatches are submitted before this one is
 * finished, so that the device never waits for the host's part of a piece. */
static fb_result produce(pieces *p, double *gpu_seconds)
{
    bool ahead = false;
    for (int i = 0; i < p->nlayers; i++) ahead = ahead || p->runs[i].where == RUN_GPU;
    slot *cur = NULL, *next = NULL;
    fb_result rc = slot_start(p, 0, &cur);
    for (int k = 0; k < p->npieces && !rc; k++) {
        if (ahead && k + 1 < p->npieces) rc = slot_start(p, k + 1, &next);
        if (!rc) rc = slot_finish(p, cur, gpu_seconds);
        if (!rc && fb_progress_poll(&p->prog))
            rc = fb_fail(FB_ERR_CANCELLED, "the bake was cancelled at rows %d-%d (by its progress callback)", cur->y0,
                         cur->y0 + cur->n - 1);
        if (!rc && !ahead && k + 1 < p->npieces) rc = slot_start(p, k + 1, &next);
        cur = next;
    }
    return rc;
}

/* ---- the consumer --------------------------------------------------------------------------- */

typedef struct band_job {
    pieces *p;
    const fb_piece *piece;
    int rows; /* a band: a multiple of every sink's band_rows, from the window's top */
    int first;
    fb_result rc[256];
} band_job;

static void band_task(void *ctx, int b)
{
    band_job *j = ctx;
    const fb_piece *pc = j->piece;
    int y0 = pc->top + (j->first + b) * j->rows, y1 = y0 + j->rows;
    y0 = y0 < pc->y0 ? pc->y0 : y0;
    y1 = y1 > pc->y0 + pc->n ? pc->y0 + pc->n : y1;
    j->rc[b] = FB_OK;
    for (int k = 0; k < j->p->nsinks && !j->rc[b]; k++)
        if (j->p->sinks[k]->band) j->rc[b] = j->p->sinks[k]->band(j->p->sinks[k]->self, pc, y0, y1 - y0);
}

static int gcd(int a, int b)
{
    return b ? gcd(b, a % b) : a;
}

/* The bands of a piece on the consumer's workers, then every sink's rows in turn. */
static fb_result feed(pieces *p, const fb_piece *pc)
{
    int unit = 1, threads = fb_pool_threads(p->bands);
    for (int k = 0; k < p->nsinks; k++)
        if (p->sinks[k]->band) unit = unit / gcd(unit, p->sinks[k]->band_rows) * p->sinks[k]->band_rows;
    band_job j = {.p = p, .piece = pc, .rows = unit};
    int want = threads > 1 ? 4 * threads : 1; /* bands a piece is cut into */
    while ((pc->n + j.rows - 1) / j.rows > want) j.rows += unit;
    j.first = (pc->y0 - pc->top) / j.rows;
    int nb = (pc->y0 + pc->n - 1 - pc->top) / j.rows - j.first + 1;
    if (nb > 256) return fb_fail(FB_ERR_INTERNAL, "a piece in %d bands", nb);
    fb_pool_run(p->bands, nb, band_task, &j);
    fb_result rc = FB_OK;
    for (int b = 0; b < nb && !rc; b++) rc = j.rc[b];
    fb_log_context("rows %d-%d", pc->y0, pc->y0 + pc->n - 1);
    for (int k = 0; k < p->nsinks && !rc; k++)
        if (p->sinks[k]->rows) rc = p->sinks[k]->rows(p->sinks[k]->self, pc);
    fb_log_context(NULL);
    return rc;
}

static void *consume(void *arg)
{
    pieces *p = arg;
    fb_scope_set(p->scope); /* the bake's log and output transaction */
    const int *region = p->shape.region;
    for (int k = 0; k < p->npieces; k++) {
        slot *sl = &p->slots[k % p->shape.slots];
        pthread_mutex_lock(&p->mu);
        while (!(sl->ready && sl->index == k) && !p->stop) pthread_cond_wait(&p->cv, &p->mu);
        bool stop = p->stop;
        sl->ready = false;
        pthread_mutex_unlock(&p->mu);
        if (stop) break;
        const void *planes[MAX_PLANES]; /* the window's columns */
        for (int c = 0; c < p->shape.nplanes; c++) planes[c] = (const uint8_t *)sl->planes[c] + (size_t)region[0] * 4;
        fb_piece pc = {.index = k,
                       .y0 = sl->y0,
                       .n = sl->n,
                       .x0 = region[0],
                       .width = region[2],
                       .top = region[1],
                       .stride = p->width,
                       .planes = planes,
                       .owner = sl};
        fb_result rc = feed(p, &pc);
        fb_piece_release(sl);
        if (rc) {
            ring_stop(p, rc);
            break;
        }
    }
    return NULL;
}

fb_result pieces_run(pieces *p, fb_sink *const *sinks, int nsinks, bool progress, double *gpu_seconds)
{
    fb_result rc = FB_OK;
    p->sinks = sinks, p->nsinks = nsinks;
    for (int k = 0; k < nsinks && !rc; k++)
        if (sinks[k]->begin) rc = sinks[k]->begin(sinks[k]->self);
    if (!rc) rc = fb_pool_create(p->shape.threads, &p->bands);
    if (rc) return rc;
    const fb_scene *s = p->runs[0].gen.scene;
    fb_progress_init(&p->prog, progress, "bake", "pix");
    fb_progress_update(&p->prog, 0, (uint64_t)p->shape.region[2] * p->shape.region[3] * (uint64_t)s->nlayers);
    fb_progress_set_scale(&p->prog, s->nlayers);
    p->scope = fb_scope_capture();
    pthread_t consumer;
    if (pthread_create(&consumer, NULL, consume, p) != 0) {
        fb_pool_destroy(&p->bands);
        return fb_fail(FB_ERR_INTERNAL, "cannot start the bake's consumer thread");
    }
    rc = produce(p, gpu_seconds);
    if (rc) ring_stop(p, FB_OK); /* the producer's own error: the consumer stops */
    pthread_join(consumer, NULL);
    fb_progress_finish(&p->prog);
    fb_pool_destroy(&p->bands);
    return p->fail ? p->fail : rc;
}
