/*
 * The fbm shader's small-coordinate specialisation (constant 2: the wrap's huge-coordinate path
 * folded away). fb_fbm_lattice_bound must bound every lattice index the kernel forms: checked
 * against the indexes of a replica of the kernel's domain recursion over a grid of pixels, for
 * random parameter blocks. And the specialised shader must give the same bits as the general one
 * on lavapipe wherever the host chooses it. Returns 77 (not run) for the second part only when
 * there is no Vulkan device.
 */
#include "gen.h"
#include "gen_fbm.h"
#include "kernels/fbm.h"
#include "scene.h"
#include "env.h"
#include "vkc.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The largest |floor| of a lattice coordinate the kernel forms at (u, v) for one stream: the domain
 * recursion of k_fbm_uv, written out again (the simplex skew and the cellular neighbours included). */
static double observed_index(const K_FbmParams *p, float u, float v)
{
    if (p->warp != 0.0f) {
        float du = k_fbm_uv(*p, 1u, u, v), dv = k_fbm_uv(*p, 2u, u, v);
        u = u + p->warp * du * p->inv_freq_x;
        v = v + p->warp * dv * p->inv_freq_y;
    }
    uint seed = k_hash3(p->seed, 0u, 0x0fb0u);
    float x = u * p->freq_x + p->offset_x, y = v * p->freq_y + p->offset_y;
    float cx = p->freq_x, cy = p->freq_y;
    double m = 0;
    for (uint i = 0; i < p->octaves; i++) {
        uint h = k_hash(seed + i * 0x9e3779b9u);
        float qx = x, qy = y;
        if ((p->flags & K_FBM_TILEABLE) != 0u) {
            qx = u * fmaxf(floorf(cx + 0.5f), 1.0f) + (float)(h & 255u) + p->offset_x;
            qy = v * fmaxf(floorf(cy + 0.5f), 1.0f) + (float)((h >> 8) & 255u) + p->offset_y;
        }
        float s = (qx + qy) * 0.36602540378f; /* simplex's skewed cell */
        double c[4] = {fabs(floor(qx)) + 2, fabs(floor(qy)) + 2, fabs(floor(qx + s)) + 1, fabs(floor(qy + s)) + 1};
        for (int k = 0; k < 4; k++) m = c[k] > m ? c[k] : m;
        cx *= p->lacunarity;
        cy *= p->lacunarity;
        float nx = p->lacunarity * (p->rot_c * x - p->rot_s * y);
        float ny = p->lacunarity * (p->rot_s * x + p->rot_c * y);
        uint ho = k_hash(h ^ 0x5bd1e995u);
        x = nx + (float)(ho & 0xffffu) * (64.0f / 65536.0f);
        y = ny + (float)(ho >> 16) * (64.0f / 65536.0f);
    }
    return m;
}

static void test_bound(void)
{
    int tight = 0;
    for (int t = 0; t < 300; t++) {
        K_FbmParams p = {0};
        p.seed = (uint)th_next();
        p.octaves = 1 + (uint)(th_next() % 12);
        p.flags = (uint)(th_next() % 8);
        p.gain = (float)(0.2 + 0.8 * th_unif());
        p.lacunarity = (float)(1.1 + 2.9 * th_unif());
        double a = 6.283185307179586 * th_unif();
        p.rot_c = (float)cos(a);
        p.rot_s = (float)sin(a);
        p.freq_x = (float)exp(log(0.5) + (log(3000.0) - log(0.5)) * th_unif());
        p.freq_y = p.freq_x * (float)(0.5 + th_unif());
        p.offset_x = (float)(2000 * th_unif() - 1000);
        p.offset_y = (float)(2000 * th_unif() - 1000);
        p.warp = t % 3 == 0 ? 0.0f : (float)(5 * th_unif());
        fb_fbm_params_frame(&p, 97, 61);
        double bound = fb_fbm_lattice_bound(&p), seen = 0;
        for (int j = 0; j <= 16; j++)
            for (int i = 0; i <= 16; i++) {
                /* pixel centres from edge to edge: u = (x + 0.5)/W, v = 1 - (y + 0.5)/H */
                float u = ((float)(i * 96 / 16) + 0.5f) * p.inv_width,
                      v = 1.0f - ((float)(j * 60 / 16) + 0.5f) * p.inv_height;
                double o = observed_index(&p, u, v);
                seen = o > seen ? o : seen;
            }
        CHECKF(seen <= bound, "parameter block %d: lattice index %g above the bound %g", t, seen, bound);
        tight += bound < 64 * seen + 1e4; /* not so loose that it never specialises */
    }
    CHECKF(tight > 250, "the bound is within 64x (+1e4) of the indexes seen in only %d of 300 blocks", tight);
    K_FbmParams nan = {.octaves = 4, .lacunarity = 2, .rot_c = 1, .freq_x = NAN, .freq_y = 1, .gain = 0.5f};
    CHECK(isinf(fb_fbm_lattice_bound(&nan)));
}

/* Runs the layer's shader over the whole image with specialisation constant 2 set to `small`. */
static float *dispatch(vkc_context *vk, const fb_gen *g, uint32_t small)
{
    uint32_t spec[3] = {g->compute.shader.spec[0], g->compute.shader.spec[1], small};
    vkc_pipeline *pipe = NULL;
    vkc_job *job = NULL;
    vkc_buffer *buf = NULL;
    int w = g->scene->width, h = g->scene->height;
    float *out = NULL;
    uint8_t push[FB_GEN_MAX_PUSH];
    uint32_t groups[3];
    fb_gen_push(g, 0, h, push);
    fb_gen_groups(g, h, groups);
    fb_result rc = vkc_pipeline_create(vk,
                                       &(vkc_pipeline_desc){.spv = g->compute.shader.spv,
                                                            .spv_size = g->compute.shader.spv_size,
                                                            .push_size = g->compute.shader.push_size,
                                                            .buffers = 1,
                                                            .spec = spec,
                                                            .nspec = 3,
                                                            .name = "fbm"},
                                       &pipe);
    if (!rc) rc = vkc_job_create(vk, pipe, &job);
    if (!rc) rc = vkc_buffer_create(vk, (uint64_t)w * h * 4, &buf);
    if (!rc) rc = vkc_job_submit(vk, job, &buf, 1, push, groups);
    if (!rc) rc = vkc_job_wait(vk, job, NULL);
    if (!rc && (out = malloc((size_t)w * h * 4))) memcpy(out, vkc_buffer_data(buf), (size_t)w * h * 4);
    vkc_buffer_destroy(vk, &buf);
    vkc_job_destroy(vk, &job);
    vkc_pipeline_destroy(vk, &pipe);
    return out;
}

static int test_shader(void)
{
    vkc_context *vk = NULL;
    fb_env env; /* FB_VK_STAGING: the discrete-GPU path */
    fb_env_read(&env);
    env.vk.validation = env.vk.no_pipeline_cache = true;
    if (vkc_create(&env.vk, &vk)) return 77;
    static const char *noises[] = {"gradient", "value", "simplex", "cellular", "cellular-f2", "sine"};
    static const char *styles[] = {"",
                                   ", \"ridged\": true",
                                   ", \"billow\": true, \"warp\": 0.8",
                                   ", \"tileable\": true, \"warp\": 0.5",
                                   ", \"frequency\": 700, \"rotation\": 31",
                                   ", \"frequency\": 3000, \"lacunarity\": 3.5"};
    int specialised = 0, general = 0;
    for (int n = 0; n < 6; n++)
        for (int st = 0; st < 6; st++) {
            if (st == 3 && n == 2) continue; /* simplex is not tileable */
            char json[512];
            snprintf(json, sizeof json,
                     "{\"size\": [193, 77], \"seed\": %d, \"layers\": [{\"type\": \"fbm\", \"noise\": \"%s\", "
                     "\"octaves\": 9, \"hurst\": 0.6, \"offset\": [-321.5, 77.25]%s}]}",
                     3 + n, noises[n], styles[st]);
            fb_scene s;
            fb_gen g;
            REQUIRE(fb_scene_parse(json, NULL, &s) == FB_OK);
            REQUIRE(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
            REQUIRE(g.compute.shader.nspec == 4);
            bool small = fb_fbm_lattice_bound((const K_FbmParams *)(const void *)g.params) < 16777216.0;
            CHECKF(g.compute.shader.spec[2] == (small ? 1u : 0u), "%s: spec 2 is %u", json, g.compute.shader.spec[2]);
            if (small) {
                float *a = dispatch(vk, &g, 0), *b = dispatch(vk, &g, 1);
                CHECKF(a && b && !memcmp(a, b, 193 * 77 * 4), "%s: the specialised shader changes bits", json);
                free(a);
                free(b);
            }
            specialised += small;
            general += !small;
            fb_gen_fini(&g);
            fb_scene_fini(&s);
        }
    /* 3000 cells x 3.5^8 is beyond 2^24: those scenes keep the general path */
    CHECKF(specialised >= 25 && general == 6, "%d specialised, %d general", specialised, general);
    CHECKF(vkc_validation_messages(vk) == 0, "%u validation messages", vkc_validation_messages(vk));
    vkc_destroy(&vk);
    return 0;
}

int main(void)
{
    test_bound();
    if (test_shader() == 77) {
        printf("%d passed, %d failed (no Vulkan device: the shader part not run)\n", th_passed, th_failed);
        return th_failed ? 1 : 77;
    }
    TEST_REPORT();
}
