/*
 * The stars benchmark: a lat-long sky to magnitude 8 (about 47,000 stars) with the Milky Way, on
 * every backend, in Mpix/s, against the simplest fast way to draw the same records: scattering each
 * record's tent into the rows it reaches (the reference; the same weights, summed in another order,
 * so not the same bits), then dividing by the solid angle, with the same catalogue and binning; and
 * on the device, the layer's shader beside a minimal one of the same formula (bench/peers/).
 */
#include "benchkit.h"
#include "gen_stars.h"

#include "kernels/stars.h"
/* after the headers of core: the SPIR-V array is a uint32_t[] */
#include "stars_peer_comp.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct scatter_job {
    const fb_gen *g;
    float *rgb; /* 3 planes */
} scatter_job;

/* Rows [y0, y0 + n): every record of the tiles these rows cross, added to the pixels of those rows
 * within its reach, then the rows divided by their pixels' solid angles. */
static void scatter_rows(void *ctx, int y0, int n, int task)
{
    const scatter_job *j = ctx;
    const K_StarsParams *p = (const K_StarsParams *)(const void *)j->g->params;
    const uint32_t *w = j->g->compute.shader.input;
    const K_StarsRec *rec = (const K_StarsRec *)(const void *)(w + p->rec_off);
    size_t plane = (size_t)p->width * p->height;
    float *R = j->rgb, *G = R + plane, *B = G + plane;
    memset(R + (size_t)y0 * p->width, 0, (size_t)n * p->width * 4);
    memset(G + (size_t)y0 * p->width, 0, (size_t)n * p->width * 4);
    memset(B + (size_t)y0 * p->width, 0, (size_t)n * p->width * 4);
    int reach = (int)p->radius + 1, y1 = y0 + n;
    for (uint32_t ty = (uint32_t)y0 >> p->tile_shift; ty <= (uint32_t)(y1 - 1) >> p->tile_shift; ty++) {
        int ta = (int)(ty << p->tile_shift), tb = ta + (1 << p->tile_shift);
        for (uint32_t tx = 0; tx < p->tiles_x; tx++) {
            uint32_t t = ty * p->tiles_x + tx;
            int xa = (int)(tx << p->tile_shift), xb = xa + (1 << p->tile_shift);
            for (uint32_t k = w[t]; k < w[t + 1]; k++) {
                K_StarsRec s = rec[k];
                int cx = (int)s.x, cy = (int)s.y;
                for (int y = cy - reach; y <= cy + reach + 1; y++) {
                    if (y < y0 || y >= y1 || y < ta || y >= tb) continue;
                    for (int x = cx - reach; x <= cx + reach + 1; x++) {
                        if (x < xa || x >= xb || x >= (int)p->width) continue;
                        float wt = k_stars_weight(*p, s.x, s.y, s.flags, (uint32_t)x, (uint32_t)y);
                        size_t i = (size_t)y * p->width + (size_t)x;
                        R[i] += s.r * wt, G[i] += s.g * wt, B[i] += s.b * wt;
                    }
                }
            }
        }
    }
    for (int y = y0; y < y1; y++) {
        float row_inv;
        memcpy(&row_inv, w + p->row_off + y, 4);
        for (uint32_t x = 0; x < p->width; x++) {
            float inv = row_inv * (x == 0 || x == p->width - 1 ? 2.0f : 1.0f);
            size_t i = (size_t)y * p->width + x;
            R[i] *= inv, G[i] *= inv, B[i] *= inv;
        }
    }
}

/* Median seconds of the layer's set-up (the catalogue and its binning, which the bake also pays) plus
 * the median of the scatter over the whole image. */
static double time_reference(const fb_scene *s, int threads)
{
    fb_gen g;
    double init[3];
    for (int i = 0; i < 3; i++) {
        double t0 = fb_now();
        if (fb_gen_init(&g, s, &s->layers[0])) return -1;
        init[i] = fb_now() - t0;
        if (i < 2) fb_gen_fini(&g);
    }
    scatter_job j = {&g, malloc((size_t)s->width * s->height * 12)};
    double t = j.rgb ? fb_bench_rows(threads, s->height, scatter_rows, &j, NULL) : -1;
    free(j.rgb);
    fb_gen_fini(&g);
    return t < 0 ? t : t + fb_bench_median3(init);
}

fb_result fb_stars_bench(fb_bench *b)
{
    int w = b->width, h = b->width / 2;
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"stars\", \"mapping\": \"latlong\", "
             "\"limit\": 8, \"milky-way\": 3}]}",
             w, h);
    fb_bench_heading(b,
                     "stars %d x %d lat-long, to magnitude 8 with the Milky Way; median of 3 runs after a warm-up; "
                     "reference: the same records scattered",
                     w, h);
    fb_bench_case bc = {"stars", "Mpix/s", (double)w * h, 1e6, NULL, 0};
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (!rc) rc = fb_bench_layer(b, &bc, &s, time_reference(&s, b->threads > 0 ? b->threads : fb_cpu_count()));
    fb_bench_peer peer = {
        .name = "minimal GLSL (bench/peers/stars_peer.comp)", FB_SPV(stars_peer_comp), .planes = 4, .input = true};
    if (!rc) rc = fb_bench_peer_layer(b, &bc, &s, &peer);
    fb_scene_fini(&s);
    return rc;
}
