/*
 * The Julia sky generator: kernels/julia.h, driven natively or by shaders/julia.comp.
 * Channels: NAME.iter (uint), NAME.n (smooth count), NAME.inside (0/1), NAME.de (pixels).
 */
#include "../gen.h"

#include "../../kernels/julia.h"
#include "../../kernels/palette.h"
#include "../palette.h"
#include "julia_comp.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct julia_push {
    K_JuliaParams p;
    uint32_t y0;
    uint32_t rows;
} julia_push;

_Static_assert(offsetof(K_JuliaParams, width) == 0 && offsetof(K_JuliaParams, height) == 4, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, mapping) == 8 && offsetof(K_JuliaParams, max_iter) == 12, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, c_re) == 16 && offsetof(K_JuliaParams, c_im) == 20, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, a_re) == 24 && offsetof(K_JuliaParams, a_im) == 28, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, scale_u) == 32 && offsetof(K_JuliaParams, scale_v) == 36, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, radius) == 40, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, center_re) == 44 && offsetof(K_JuliaParams, center_im) == 48, "std430");
_Static_assert(offsetof(K_JuliaParams, rot_c) == 52 && offsetof(K_JuliaParams, rot_s) == 56, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, bailout2) == 60, "std430 offset");
_Static_assert(offsetof(K_JuliaParams, inv_width) == 64 && offsetof(K_JuliaParams, inv_height) == 68, "std430");
_Static_assert(offsetof(K_JuliaParams, lambda) == 72 && offsetof(K_JuliaParams, turb_norm) == 76, "std430 offset");
_Static_assert(offsetof(julia_push, y0) == 80 && offsetof(julia_push, rows) == 84, "std430 offset");
_Static_assert(sizeof(julia_push) <= FB_GEN_MAX_PUSH, "push constants");
_Static_assert(sizeof(K_JuliaParams) <= sizeof(((fb_gen *)0)->params), "params fit");

/* The read-only buffer of shaders/julia.comp: colour parameters, then the palette table. */
typedef struct julia_palette {
    K_SkyColour colour;
    K_FbmParams turb;
    float pad[3];
    float entries[K_PALETTE_SIZE][4];
} julia_palette;
_Static_assert(sizeof(K_SkyColour) == 48 && offsetof(julia_palette, turb) == 48, "std430 offset");
_Static_assert(sizeof(K_FbmParams) == 84 && offsetof(julia_palette, entries) == 144, "std430: vec4 array at 144");
_Static_assert(FB_PALETTE_ENTRIES == K_PALETTE_SIZE, "palette size");

static const K_JuliaParams *params(const fb_gen *g)
{
    return (const K_JuliaParams *)(const void *)g->params;
}

/* The same table lookup as shaders/julia.comp. */
static void sky_colour(const julia_palette *pal, K_JuliaResult res, float rgb[3])
{
    const K_SkyColour c = pal->colour;
    if (res.inside) {
        rgb[0] = c.inside_r, rgb[1] = c.inside_g, rgb[2] = c.inside_b;
        return;
    }
    float pos = k_palette_pos(c, res.nsmooth);
    uint32_t i0 = (uint32_t)pos, i1 = i0 + 1 < K_PALETTE_SIZE ? i0 + 1 : i0;
    float f = pos - (float)i0, w = k_sky_weight(c, res.nsmooth);
    for (int ch = 0; ch < 3; ch++) rgb[ch] = k_sky_channel(c, k_mix(pal->entries[i0][ch], pal->entries[i1][ch], f), w);
}

static void julia_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_JuliaParams *p = params(g);
    const julia_palette *pal = g->input;
    uint32_t *iter = planes[0];
    float *sm = planes[1], *inside = planes[2], *de = planes[3], *R = planes[4], *G = planes[5], *B = planes[6];
    for (int r = 0; r < n; r++)
        for (uint32_t x = 0; x < p->width; x++) {
            uint32_t y = (uint32_t)(y0 + r);
            K_JuliaResult res = k_julia_pixel(*p, pal->turb, x, y);
            size_t i = (size_t)r * p->width + x;
            iter[i] = res.iter;
            sm[i] = res.nsmooth;
            inside[i] = (float)res.inside;
            de[i] = res.de;
            /* the average of `samples` jittered samples in linear colour (sample 0 is the centre) */
            float sum[3], c[3];
            sky_colour(pal, res, sum);
            for (uint32_t k = 1; k < pal->colour.samples; k++) {
                sky_colour(pal, k_julia_sample(*p, pal->turb, pal->colour.seed, x, y, k), c);
                for (int ch = 0; ch < 3; ch++) sum[ch] += c[ch];
            }
            float s = pal->colour.samples == 1 ? 1.0f : pal->colour.inv_samples;
            R[i] = pal->colour.samples == 1 ? sum[0] : sum[0] * s;
            G[i] = pal->colour.samples == 1 ? sum[1] : sum[1] * s;
            B[i] = pal->colour.samples == 1 ? sum[2] : sum[2] * s;
        }
}

fb_result fb_gen_julia_init(fb_gen *g)
{
    const fb_scene *s = g->scene;
    const fb_julia_params *j = &g->layer->julia;
    K_JuliaParams *p = (K_JuliaParams *)(void *)g->params;
    memset(p, 0, sizeof *p);
    p->width = (uint32_t)s->width;
    p->height = (uint32_t)s->height;
    p->mapping = j->polar ? K_JULIA_POLAR : K_JULIA_RECT;
    p->max_iter = (uint32_t)j->max_iter;
    p->c_re = (float)j->c[0];
    p->c_im = (float)j->c[1];
    p->a_re = (float)j->alpha[0];
    p->a_im = (float)j->alpha[1];
    p->scale_u = (float)j->scale[0];
    p->scale_v = (float)j->scale[1];
    p->radius = (float)j->radius;
    p->center_re = (float)j->center[0];
    p->center_im = (float)j->center[1];
    double a = j->rotation * 3.14159265358979323846 / 180.0;
    p->rot_c = (float)cos(a);
    p->rot_s = (float)sin(a);
    p->bailout2 = (float)(j->bailout * j->bailout);
    p->inv_width = 1.0f / (float)s->width;
    p->inv_height = 1.0f / (float)s->height;

    julia_palette *pal = calloc(1, sizeof *pal);
    if (!pal) return fb_fail(FB_ERR_NOMEM, "out of memory");
    pal->colour = (K_SkyColour){
        .inv_period = (float)(1.0 / j->period),
        .offset = (float)j->palette_offset,
        .brightness = (float)j->brightness,
        .gamma = (float)j->gamma,
        .density = (float)j->density,
        .inv_n_ref = (float)(1.0 / j->density_count),
        .inside_r = (float)j->inside_color[0],
        .inside_g = (float)j->inside_color[1],
        .inside_b = (float)j->inside_color[2],
        .samples = (uint32_t)j->samples,
        .seed = s->seed,
        .inv_samples = (float)(1.0 / j->samples),
    };
    fb_palette_build(&j->palette, pal->entries);
    /* Turbulence W: fBm over (u, v) with the layer's own parameters; tileable for polar grids. */
    K_FbmParams *t = &pal->turb;
    t->seed = s->seed;
    t->noise = K_NOISE_GRADIENT;
    t->octaves = (uint32_t)j->turb_octaves;
    t->gain = (float)exp2(-j->turb_hurst);
    t->lacunarity = 2.0f;
    t->rot_c = 0.8f; /* the paper's rotation (0.8, 0.6) between octaves */
    t->rot_s = 0.6f;
    t->flags = j->polar ? K_FBM_TILEABLE : 0u;
    t->freq_x = (float)j->turb_frequency;
    t->freq_y = (float)(j->polar ? j->turb_frequency : j->turb_frequency * s->height / s->width);
    fb_fbm_params_frame(t, s->width, s->height);
    double gsum = 0, amp = 1;
    for (int i = 0; i < j->turb_octaves; i++, amp *= t->gain) gsum += amp;
    p->lambda = (float)j->turbulence;
    p->turb_norm = (float)(1.0 / gsum);
    g->owned = pal;
    g->input = pal;
    g->input_size = sizeof *pal;

    static const char *const suffix[7] = {"iter", "n", "inside", "de", "R", "G", "B"};
    exrio_type colour = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    const exrio_type types[7] = {EXRIO_UINT, EXRIO_FLOAT, EXRIO_HALF, EXRIO_FLOAT, colour, colour, colour};
    g->nchannels = 7;
    for (int c = 0; c < 7; c++) {
        snprintf(g->channel_names[c], sizeof g->channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->channel_types[c] = types[c];
    }
    g->preview_channel = 1; /* the smooth count */
    g->preview_rgb = 4;     /* R, G, B */
    g->native_rows = julia_rows;
    g->spv = julia_comp;
    g->spv_size = sizeof julia_comp;
    g->params_size = sizeof(K_JuliaParams);
    g->push_size = sizeof(julia_push);
    g->spec[0] = p->mapping;
    g->spec[1] = p->lambda != 0.0f;
    g->spec[2] = (uint32_t)j->samples;
    g->spec[3] = (pal->colour.gamma != 1.0f ? 1u : 0u) | (pal->colour.density > 0.0f ? 2u : 0u);
    g->nspec = 4;
    return FB_OK;
}
