/*
 * Benchmarks: a layer's shader beside a minimal shader of its formula on the Vulkan device (see
 * benchkit.h, fb_bench_peer_layer).
 */
#include "benchkit.h"

#include "gen.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PASSES 3

/* One side of the comparison: a pipeline, its job and buffers, and its timings. */
typedef struct side {
    vkc_pipeline *pipe;
    vkc_job *job;
    vkc_buffer *buf[FB_GEN_MAX_CHANNELS + 1];
    uint32_t nbufs;
    uint32_t per; /* pixels an invocation along the row */
    double wall[PASSES], gpu[PASSES];
} side;

static void side_fini(vkc_context *vk, side *sd)
{
    for (uint32_t k = 0; k < sd->nbufs; k++) vkc_buffer_destroy(vk, &sd->buf[k]);
    vkc_job_destroy(vk, &sd->job);
    vkc_pipeline_destroy(vk, &sd->pipe);
}

/* The layer's side: its shader as a bake dispatches it (host/core/bake.c), strips of `rows`. */
static fb_result layer_init(vkc_context *vk, const fb_gen *g, int rows, side *sd)
{
    int np = fb_gen_nplanes(g);
    uint64_t bytes = (uint64_t)g->scene->width * (uint64_t)rows * 4;
    fb_result rc = vkc_pipeline_create(
        vk,
        &(vkc_pipeline_desc){.spv = g->compute.shader.spv,
                             .spv_size = g->compute.shader.spv_size,
                             .push_size = g->compute.shader.push_size,
                             .buffers = (uint32_t)np + (g->compute.shader.input ? 1u : 0u),
                             .uniform = g->compute.shader.input && g->compute.shader.input_uniform ? 1u << np : 0u,
                             .spec = g->compute.shader.spec,
                             .nspec = g->compute.shader.nspec,
                             .name = g->layer->name},
        &sd->pipe);
    sd->per = g->compute.shader.per_invocation > 1 ? (uint32_t)g->compute.shader.per_invocation : 1u;
    if (!rc) rc = vkc_job_create(vk, sd->pipe, &sd->job);
    for (int c = 0; c < np && !rc; c++, sd->nbufs++)
        rc = vkc_buffer_create(vk, fb_gen_plane_stored(g, c) ? bytes : 16, &sd->buf[c]);
    if (!rc && g->compute.shader.input) rc = vkc_buffer_create(vk, g->compute.shader.input_size, &sd->buf[sd->nbufs++]);
    if (!rc && g->compute.shader.input)
        rc = vkc_buffer_upload(vk, sd->buf[np], g->compute.shader.input, g->compute.shader.input_size);
    return rc;
}

/* The peer's side: its output planes, then the layer's input where it reads it. */
static fb_result peer_init(vkc_context *vk, const fb_gen *g, const fb_bench_peer *peer, int rows, side *sd)
{
    bool input = peer->input && g->compute.shader.input;
    uint32_t np = peer->planes > 1 ? (uint32_t)peer->planes : 1u;
    fb_result rc =
        vkc_pipeline_create(vk,
                            &(vkc_pipeline_desc){.spv = peer->spv,
                                                 .spv_size = peer->spv_size,
                                                 .push_size = g->compute.shader.push_size,
                                                 .buffers = np + (input ? 1u : 0u),
                                                 .uniform = input && g->compute.shader.input_uniform ? 1u << np : 0u,
                                                 .spec = peer->spec,
                                                 .nspec = peer->nspec,
                                                 .name = peer->name},
                            &sd->pipe);
    sd->per = peer->per_invocation > 1 ? (uint32_t)peer->per_invocation : 1u;
    if (!rc) rc = vkc_job_create(vk, sd->pipe, &sd->job);
    for (uint32_t k = 0; k < np && !rc; k++)
        rc = vkc_buffer_create(vk, (uint64_t)g->scene->width * (uint64_t)rows * 4, &sd->buf[sd->nbufs++]);
    if (!rc && input) rc = vkc_buffer_create(vk, g->compute.shader.input_size, &sd->buf[sd->nbufs++]);
    if (!rc && input) rc = vkc_buffer_upload(vk, sd->buf[np], g->compute.shader.input, g->compute.shader.input_size);
    return rc;
}

/* One strip [y0, y0 + n) on one side; adds its host-clock and timestamp seconds to the pass's. */
static fb_result side_strip(vkc_context *vk, const fb_gen *g, side *sd, int pass, int y0, int n)
{
    uint8_t push[FB_GEN_MAX_PUSH];
    fb_gen_push(g, y0, n, push);
    uint32_t w = (uint32_t)g->scene->width, groups[3] = {(w + 64 * sd->per - 1) / (64 * sd->per), (uint32_t)n, 1};
    double t0 = fb_now(), gpu = -1;
    fb_result rc = vkc_job_submit(vk, sd->job, sd->buf, sd->nbufs, push, groups);
    if (!rc) rc = vkc_job_wait(vk, sd->job, &gpu);
    if (!rc && pass >= 0) {
        sd->wall[pass] += fb_now() - t0;
        sd->gpu[pass] += gpu;
    }
    return rc;
}

/* The pixels of a strip where the peer's planes differ from the layer's, from its plane k on. */
static uint64_t differing(const side *layer, int k, const side *peer, int planes, size_t values)
{
    uint64_t n = 0;
    for (int j = 0; j < planes; j++) {
        const uint32_t *a = vkc_buffer_data(layer->buf[k + j]), *b = vkc_buffer_data(peer->buf[j]);
        for (size_t i = 0; i < values; i++) n += a[i] != b[i];
    }
    return n;
}

/* The rows of one dispatch: the whole image where a plane of it fits one storage buffer. */
static int strip_rows(vkc_context *vk, const fb_scene *s)
{
    uint64_t fit = vkc_info(vk)->max_storage_buffer_range / ((uint64_t)s->width * 4);
    return fit >= (uint64_t)s->height ? s->height : fit > 0 ? (int)fit : 1;
}

fb_result fb_bench_peer_layer(const fb_bench *b, const fb_bench_case *bc, const fb_scene *s, const fb_bench_peer *peer)
{
    if (!b->vulkan) return FB_OK;
    fb_engine e;
    bool have = false;
    fb_result rc = fb_bench_open_vulkan(b, &e, &have);
    if (rc || !have) return rc;
    vkc_context *vk = e.vk;
    fb_gen g;
    side sides[2] = {0}; /* the layer's, the peer's */
    uint64_t diff = 0;
    rc = fb_gen_init(&g, s, &s->layers[0]);
    bool gen_ok = rc == FB_OK;
    int planes = peer->planes > 1 ? peer->planes : 1;
    for (int k = peer->plane; k < peer->plane + planes && !rc; k++)
        if (k >= fb_gen_nplanes(&g) || !fb_gen_plane_stored(&g, k))
            rc = fb_fail(FB_ERR_INTERNAL, "bench: peer %s compares plane %d, which the layer does not store",
                         peer->name, k);
    int rows = rc ? 0 : strip_rows(vk, s);
    if (!rc) rc = layer_init(vk, &g, rows, &sides[0]);
    if (!rc) rc = peer_init(vk, &g, peer, rows, &sides[1]);
    /* a warm-up pass (pipelines compiled, pages touched), then PASSES, the two sides alternating
     * strip by strip and starting with the other each pass; the planes compared on the last */
    for (int pass = -1; pass < PASSES && !rc; pass++)
        for (int y0 = 0; y0 < s->height && !rc; y0 += rows) {
            int n = s->height - y0 < rows ? s->height - y0 : rows, first = (pass + 2) % 2;
            rc = side_strip(vk, &g, &sides[first], pass, y0, n);
            if (!rc) rc = side_strip(vk, &g, &sides[1 - first], pass, y0, n);
            if (!rc && pass == PASSES - 1)
                diff += differing(&sides[0], peer->plane, &sides[1], planes, (size_t)n * s->width);
        }
    if (!rc) {
        double wall[2][PASSES], gpu[2][PASSES];
        for (int k = 0; k < 2; k++)
            memcpy(wall[k], sides[k].wall, sizeof wall[k]), memcpy(gpu[k], sides[k].gpu, sizeof gpu[k]);
        char note[64];
        snprintf(note, sizeof note, "(one dispatch of %d rows)", rows);
        fb_bench_peer_rows(b, bc->generator, e.device, peer->name, peer->mode, bc->unit, bc->work, bc->unit_scale, wall,
                           gpu, diff, note);
    }
    for (int k = 0; k < 2; k++) side_fini(vk, &sides[k]);
    if (gen_ok) fb_gen_fini(&g);
    fb_engine_close(&e);
    return rc;
}

void fb_bench_peer_rows(const fb_bench *b, const char *generator, const char *device, const char *peer_name,
                        const char *mode, const char *unit, double work, double unit_scale, double wall[2][3],
                        double gpu[2][3], uint64_t diff, const char *peer_note)
{
    double rate[2], grate[2];
    for (int k = 0; k < 2; k++) {
        rate[k] = work / fb_bench_median3(wall[k]) / unit_scale;
        double gs = fb_bench_median3(gpu[k]);
        grate[k] = gs > 0 ? work / gs / unit_scale : 0;
    }
    /* the ratio by the device's clock where it has one: the host clock counts the readback */
    double vs = grate[0] > 0 && grate[1] > 0 ? grate[0] / grate[1] : rate[0] / rate[1];
    char modes[2][64];
    snprintf(modes[0], sizeof modes[0], "kernel%s", mode ? mode : "");
    snprintf(modes[1], sizeof modes[1], "peer%s", mode ? mode : "");
    fb_bench_row r = {.generator = generator,
                      .backend = "vulkan",
                      .device = device,
                      .mode = modes[0],
                      .unit = unit,
                      .rate = rate[0],
                      .gpu_rate = grate[0],
                      .size = true,
                      .nextra = 3,
                      .extra = {{"vs_peer", vs, 3}, {"same_bits", diff == 0, 0}, {"differing", (double)diff, 0}}};
    if (diff)
        snprintf(r.note, sizeof r.note, "x%.3f of its peer; %llu values differ", vs, (unsigned long long)diff);
    else
        snprintf(r.note, sizeof r.note, "x%.3f of its peer, the same bits", vs);
    b->row(b, &r);
    r = (fb_bench_row){.generator = generator,
                       .backend = "vulkan",
                       .device = peer_name,
                       .mode = modes[1],
                       .unit = unit,
                       .rate = rate[1],
                       .gpu_rate = grate[1],
                       .size = true};
    snprintf(r.note, sizeof r.note, "%s", peer_note ? peer_note : "");
    b->row(b, &r);
}
