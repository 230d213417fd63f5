/*
 * The erosion model's drivers: the native passes over row bands of a thread pool, and the Vulkan
 * passes (shaders/erode.comp). Both gather a cell's neighbours the same way and call the same
 * kernels (kernels/erode.h), so they compute the same bits.
 */
#include "erode.h"

#include "erode_comp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

K_ErodeParams fb_erode_params(const fb_erode_desc *d)
{
    double l = d->cell, dt = d->duration / d->iterations;
    double kt = d->thermal * dt;
    return (K_ErodeParams){.width = (uint)d->width,
                           .height = (uint)d->height,
                           .rain = (float)(d->rain * dt),
                           .pipe = (float)(dt * d->gravity * l),
                           .vol = (float)(l * l / dt),
                           .dt_area = (float)(dt / (l * l)),
                           .inv_l = (float)(1 / l),
                           .half_inv_l = (float)(0.5 / l),
                           .kc = (float)d->capacity,
                           .ks = (float)fmin(1.0, d->dissolve * dt),
                           .kd = (float)fmin(1.0, d->deposit * dt),
                           .keep = (float)fmax(0.0, 1 - d->evaporate * dt),
                           .dmin = (float)(d->min_depth > 0 ? d->min_depth : 1e-4),
                           .talus = (float)(tan(d->talus * M_PI / 180) * l),
                           /* above 1/2 the explicit exchange between four neighbours overshoots */
                           .kt = (float)fmin(0.5, kt),
                           .flow_w = (float)(dt / d->duration),
                           .inv_depth = (float)(1 / d->depth)};
}

const char *fb_erode_check(const fb_erode_desc *d)
{
    if (d->width < 1 || d->height < 1) return "the grid is empty";
    if (!(d->cell > 0) || !isfinite(d->cell)) return "the cell size must be a positive number";
    if (d->iterations < 1) return "at least one iteration";
    if (!(d->duration > 0)) return "the duration must be positive";
    if (!(d->depth > 0)) return "the full-capacity depth must be positive";
    if (!(d->talus >= 0 && d->talus < 90)) return "the talus angle is in [0, 90) degrees";
    return NULL;
}

/* S, T, F, M: 16 bytes a cell each; the result: 6 floats a cell */
uint64_t fb_erode_memory(int width, int height)
{
    return (uint64_t)width * height * (4 * 16 + 6 * 4);
}

void fb_erode_out_free(fb_erode_out *o)
{
    if (!o) return;
    free(o->bed), free(o->water), free(o->sediment), free(o->flow), free(o->wear), free(o->deposit);
    memset(o, 0, sizeof *o);
}

static fb_result out_alloc(size_t n, fb_erode_out *o)
{
    memset(o, 0, sizeof *o);
    float **p[6] = {&o->bed, &o->water, &o->sediment, &o->flow, &o->wear, &o->deposit};
    for (int k = 0; k < 6; k++)
        if (!(*p[k] = malloc(n * sizeof(float)))) {
            fb_erode_out_free(o);
            return fb_fail(FB_ERR_NOMEM, "erode: out of memory for the result");
        }
    o->gpu_seconds = -1;
    return FB_OK;
}

/* The four grids as the shader sees them, and what one pool task does. */
typedef struct grids {
    k_vec4 *S, *T, *F, *M;
    K_ErodeParams p;
    int rows_per_task;
} grids;

/* One cell of each pass; l, r, t, b: whether the neighbour on that side is in the grid (constants
 * for the interior, so that the compiler drops the tests there). */
static inline __attribute__((always_inline)) void flux_cell(const K_ErodeParams p, k_vec4 *restrict F,
                                                            const k_vec4 *restrict S, uint i, uint w, bool l, bool r,
                                                            bool t, bool b)
{
    k_vec4 c = S[i];
    float hc = k_erode_surface(p, c);
    k_vec4 hn = k_vec4(l ? k_erode_surface(p, S[i - 1]) : hc, r ? k_erode_surface(p, S[i + 1]) : hc,
                       t ? k_erode_surface(p, S[i - w]) : hc, b ? k_erode_surface(p, S[i + w]) : hc);
    k_vec4 inside = k_vec4(l ? 1.0f : 0.0f, r ? 1.0f : 0.0f, t ? 1.0f : 0.0f, b ? 1.0f : 0.0f);
    float d1 = c.y + p.rain;
    F[i] = k_erode_flux(p, F[i], d1, hc, hn, inside);
}

static inline __attribute__((always_inline)) void water_cell(const K_ErodeParams p, const k_vec4 *restrict S,
                                                             const k_vec4 *restrict F, k_vec4 *restrict T,
                                                             k_vec4 *restrict M, uint i, uint w, bool l, bool r, bool t,
                                                             bool b)
{
    k_vec4 c = S[i];
    k_vec4 fin = k_vec4(l ? F[i - 1].y : 0.0f, r ? F[i + 1].x : 0.0f, t ? F[i - w].w : 0.0f, b ? F[i + w].z : 0.0f);
    k_vec4 bn = k_vec4(l ? S[i - 1].x : c.x, r ? S[i + 1].x : c.x, t ? S[i - w].x : c.x, b ? S[i + w].x : c.x);
    float d1 = c.y + p.rain;
    k_vec4 o = k_erode_water(p, c.x, d1, c.z, F[i], fin, bn);
    T[i] = k_vec4(o.x, o.y, o.z, d1);
    M[i] = k_erode_masks(p, M[i], c.x, o.x, o.w);
}

static inline __attribute__((always_inline)) void settle_cell(const K_ErodeParams p, const k_vec4 *restrict T,
                                                              const k_vec4 *restrict F, k_vec4 *restrict S,
                                                              k_vec4 *restrict M, uint i, uint w, bool l, bool r,
                                                              bool t, bool b)
{
    k_vec4 c = T[i], wall = k_vec4(c.x, 0.0f, 0.0f, 0.0f);
    k_vec4 fin = k_vec4(l ? F[i - 1].y : 0.0f, r ? F[i + 1].x : 0.0f, t ? F[i - w].w : 0.0f, b ? F[i + w].z : 0.0f);
    k_vec4 cl = l ? T[i - 1] : wall, cr = r ? T[i + 1] : wall;
    k_vec4 ct = t ? T[i - w] : wall, cb = b ? T[i + w] : wall;
    float s = k_erode_sediment(p, c.z, c.w, F[i], k_vec4(cl.z, cr.z, ct.z, cb.z), k_vec4(cl.w, cr.w, ct.w, cb.w), fin);
    float nb = k_erode_thermal(p, c.x, k_vec4(cl.x, cr.x, ct.x, cb.x));
    S[i] = k_vec4(nb, c.y, s, 0.0f);
    M[i] = k_erode_masks(p, M[i], c.x, nb, 0.0f);
}

/* A pass over rows [y0, y1): the first and last cells of a row, and the rows at the grid's top and
 * bottom, test their neighbours; the rest do not. */
#define PASS_ROWS(CELL, ...)                                                                                           \
    for (uint y = (uint)y0; y < (uint)y1; y++) {                                                                       \
        bool t = y > 0, b = y + 1 < h;                                                                                 \
        uint row = y * w;                                                                                              \
        if (w == 1) {                                                                                                  \
            CELL(p, __VA_ARGS__, row, w, false, false, t, b);                                                          \
            continue;                                                                                                  \
        }                                                                                                              \
        CELL(p, __VA_ARGS__, row, w, false, true, t, b);                                                               \
        if (t && b)                                                                                                    \
            for (uint x = 1; x + 1 < w; x++) CELL(p, __VA_ARGS__, row + x, w, true, true, true, true);                 \
        else                                                                                                           \
            for (uint x = 1; x + 1 < w; x++) CELL(p, __VA_ARGS__, row + x, w, true, true, t, b);                       \
        CELL(p, __VA_ARGS__, row + w - 1, w, true, false, t, b);                                                       \
    }

static void pass_rows(grids *g, int y0, int y1)
{
    const K_ErodeParams p = g->p;
    const uint w = p.width, h = p.height;
    if (p.pass == K_ERODE_PASS_FLUX)
        PASS_ROWS(flux_cell, g->F, g->S)
    else if (p.pass == K_ERODE_PASS_WATER)
        PASS_ROWS(water_cell, g->S, g->F, g->T, g->M)
    else
        PASS_ROWS(settle_cell, g->T, g->F, g->S, g->M)
}

static void pass_task(void *ctx, int task)
{
    grids *g = ctx;
    int y0 = task * g->rows_per_task, y1 = y0 + g->rows_per_task;
    pass_rows(g, y0, y1 < (int)g->p.height ? y1 : (int)g->p.height);
}

static void unpack(const k_vec4 *S, const k_vec4 *M, size_t n, fb_erode_out *o)
{
    for (size_t i = 0; i < n; i++) {
        o->bed[i] = S[i].x, o->water[i] = S[i].y, o->sediment[i] = S[i].z;
        o->flow[i] = M[i].x, o->wear[i] = M[i].y, o->deposit[i] = M[i].z;
    }
}

fb_result fb_erode_run_native(const fb_erode_desc *d, fb_pool *pool, fb_progress *prog, fb_erode_out *out)
{
    const char *bad = fb_erode_check(d);
    if (bad) return fb_fail(FB_ERR_INPUT, "erode: %s", bad);
    size_t n = (size_t)d->width * d->height;
    grids g = {.p = fb_erode_params(d)};
    k_vec4 *all = calloc(4 * n, sizeof *all);
    if (!all) return fb_fail(FB_ERR_NOMEM, "erode: out of memory for %zu cells", n);
    g.S = all, g.T = all + n, g.F = all + 2 * n, g.M = all + 3 * n;
    for (size_t i = 0; i < n; i++) g.S[i].x = d->bed[i];
    /* bands of rows: a few per thread, so that uneven cores even out */
    int threads = pool ? fb_pool_threads(pool) : 1, tasks = threads == 1 ? 1 : 4 * threads;
    if (tasks > d->height) tasks = d->height;
    g.rows_per_task = (d->height + tasks - 1) / tasks;
    tasks = (d->height + g.rows_per_task - 1) / g.rows_per_task;
    for (int it = 0; it < d->iterations; it++) {
        for (uint pass = 0; pass < 3; pass++) {
            g.p.pass = pass;
            if (pool)
                fb_pool_run(pool, tasks, pass_task, &g);
            else
                pass_rows(&g, 0, d->height);
        }
        if (prog) fb_progress_update(prog, (uint64_t)(it + 1) * n, (uint64_t)d->iterations * n);
    }
    fb_result rc = out_alloc(n, out);
    if (!rc) unpack(g.S, g.M, n, out);
    free(all);
    return rc;
}

enum { B_S, B_T, B_F, B_M, NBUF };

fb_result fb_erode_run_vulkan(const fb_erode_desc *d, vkc_context *vk, fb_progress *prog, fb_erode_out *out)
{
    const char *bad = fb_erode_check(d);
    if (bad) return fb_fail(FB_ERR_INPUT, "erode: %s", bad);
    size_t n = (size_t)d->width * d->height;
    uint64_t range = vkc_info(vk)->max_storage_buffer_range;
    if ((uint64_t)n * 16 > range)
        return fb_fail(FB_ERR_INPUT,
                       "erode: a grid of %zu cells needs %llu MiB per buffer; this device allows %llu MiB (lower the "
                       "size, or use --backend native)",
                       n, (unsigned long long)((uint64_t)n * 16 >> 20), (unsigned long long)(range >> 20));
    /* a pipeline and a job a pass (shaders/erode.comp's specialization constant) */
    vkc_pipeline *pipe[3] = {0};
    vkc_job *job[3] = {0};
    vkc_buffer *buf[NBUF] = {0};
    fb_result rc = FB_OK;
    for (uint32_t pass = 0; pass < 3 && !rc; pass++) {
        rc = vkc_pipeline_create(vk,
                                 &(vkc_pipeline_desc){FB_SPV(erode_comp), .push_size = sizeof(K_ErodeParams),
                                                      .buffers = NBUF, .spec = &pass, .nspec = 1, .name = "erode"},
                                 &pipe[pass]);
        if (!rc) rc = vkc_job_create(vk, pipe[pass], &job[pass]);
    }
    for (int b = 0; b < NBUF && !rc; b++) rc = vkc_buffer_create(vk, (uint64_t)n * 16, &buf[b]);
    k_vec4 *init = rc ? NULL : calloc(n, sizeof *init);
    if (!rc && !init) rc = fb_fail(FB_ERR_NOMEM, "erode: out of memory for %zu cells", n);
    for (int b = NBUF - 1; b >= 0 && !rc; b--) { /* zeros for T, F, M; then S, the heights */
        if (b == B_S)
            for (size_t i = 0; i < n; i++) init[i].x = d->bed[i];
        rc = vkc_buffer_upload(vk, buf[b], init, (uint64_t)n * 16);
    }
    free(init);
    K_ErodeParams p = fb_erode_params(d);
    uint32_t groups[3] = {((uint32_t)d->width + 15) / 16, ((uint32_t)d->height + 15) / 16, 1};
    double gpu = 0;
    for (int it = 0; it < d->iterations && !rc; it++) {
        for (uint pass = 0; pass < 3 && !rc; pass++) {
            p.pass = pass;
            double t = -1;
            rc = vkc_job_submit(vk, job[pass], buf, NBUF, &p, groups);
            if (!rc) rc = vkc_job_wait(vk, job[pass], &t);
            if (t > 0) gpu += t;
        }
        if (prog) fb_progress_update(prog, (uint64_t)(it + 1) * n, (uint64_t)d->iterations * n);
    }
    if (!rc) rc = out_alloc(n, out);
    if (!rc) {
        unpack(vkc_buffer_data(buf[B_S]), vkc_buffer_data(buf[B_M]), n, out);
        out->gpu_seconds = gpu;
    }
    for (int k = 0; k < 3; k++) vkc_job_destroy(vk, &job[k]), vkc_pipeline_destroy(vk, &pipe[k]);
    for (int b = 0; b < NBUF; b++) vkc_buffer_destroy(vk, &buf[b]);
    return rc;
}
