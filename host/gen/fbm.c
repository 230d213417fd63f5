/*
 * The fBm generator: kernels/fbm.h, driven natively or by shaders/fbm.comp.
 */
#include "../fbm_avx2.h"
#include "../gen.h"

#include "../../kernels/fbm.h"
#include "fbm_comp.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* The push-constant block of shaders/fbm.comp. std430 with scalars only: offsets are the C ones. */
typedef struct fbm_push {
    K_FbmParams p;
    uint32_t y0;
    uint32_t rows;
} fbm_push;

_Static_assert(offsetof(K_FbmParams, seed) == 0, "std430 offset");
_Static_assert(offsetof(K_FbmParams, noise) == 4, "std430 offset");
_Static_assert(offsetof(K_FbmParams, octaves) == 8, "std430 offset");
_Static_assert(offsetof(K_FbmParams, flags) == 12, "std430 offset");
_Static_assert(offsetof(K_FbmParams, gain) == 16, "std430 offset");
_Static_assert(offsetof(K_FbmParams, lacunarity) == 20, "std430 offset");
_Static_assert(offsetof(K_FbmParams, rot_c) == 24, "std430 offset");
_Static_assert(offsetof(K_FbmParams, rot_s) == 28, "std430 offset");
_Static_assert(offsetof(K_FbmParams, freq_x) == 32, "std430 offset");
_Static_assert(offsetof(K_FbmParams, freq_y) == 36, "std430 offset");
_Static_assert(offsetof(K_FbmParams, offset_x) == 40, "std430 offset");
_Static_assert(offsetof(K_FbmParams, offset_y) == 44, "std430 offset");
_Static_assert(offsetof(K_FbmParams, warp) == 48, "std430 offset");
_Static_assert(offsetof(K_FbmParams, width) == 52, "std430 offset");
_Static_assert(offsetof(K_FbmParams, height) == 56, "std430 offset");
_Static_assert(offsetof(K_FbmParams, inv_width) == 60, "std430 offset");
_Static_assert(offsetof(K_FbmParams, inv_height) == 64, "std430 offset");
_Static_assert(offsetof(K_FbmParams, inv_freq_x) == 68, "std430 offset");
_Static_assert(offsetof(K_FbmParams, inv_freq_y) == 72, "std430 offset");
_Static_assert(offsetof(K_FbmParams, pad0) == 76 && offsetof(K_FbmParams, pad1) == 80, "std430 offset");
_Static_assert(offsetof(fbm_push, y0) == 84 && offsetof(fbm_push, rows) == 88, "std430 offset");
_Static_assert(sizeof(fbm_push) == 92 && sizeof(fbm_push) <= FB_GEN_MAX_PUSH, "push constants");
_Static_assert(sizeof(K_FbmParams) <= sizeof(((fb_gen *)0)->params), "params fit");

static const K_FbmParams *params(const fb_gen *g)
{
    return (const K_FbmParams *)(const void *)g->params;
}

/* The native loop, cloned per noise kind with the kind a compile-time constant (the C counterpart of
 * the shader's specialization constant), so that the dispatch in k_noise folds away. */
#define FBM_ROWS(KIND)                                                                                                 \
    static void fbm_rows_##KIND(K_FbmParams p, int y0, int n, float *out)                                              \
    {                                                                                                                  \
        p.noise = KIND;                                                                                                \
        for (int r = 0; r < n; r++)                                                                                    \
            for (uint32_t x = 0; x < p.width; x++)                                                                     \
                out[(size_t)r * p.width + x] = k_fbm_pixel(p, x, (uint32_t)(y0 + r));                                  \
    }
FBM_ROWS(K_NOISE_GRADIENT)
FBM_ROWS(K_NOISE_VALUE)
FBM_ROWS(K_NOISE_SIMPLEX)
FBM_ROWS(K_NOISE_CELLULAR)
FBM_ROWS(K_NOISE_CELLULAR_F2)
FBM_ROWS(K_NOISE_SINE)

static void fbm_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_FbmParams *p = params(g);
    float *out = planes[0];
    /* Bit-exact with the kernel (tests/test_avx2.c), so using it changes no result. */
    if (!g->scalar && fb_fbm_avx2_supported(p)) {
        fb_fbm_avx2_rows(p, y0, n, out);
        return;
    }
    switch (p->noise) {
    case K_NOISE_VALUE:
        fbm_rows_K_NOISE_VALUE(*p, y0, n, out);
        break;
    case K_NOISE_SIMPLEX:
        fbm_rows_K_NOISE_SIMPLEX(*p, y0, n, out);
        break;
    case K_NOISE_CELLULAR:
        fbm_rows_K_NOISE_CELLULAR(*p, y0, n, out);
        break;
    case K_NOISE_CELLULAR_F2:
        fbm_rows_K_NOISE_CELLULAR_F2(*p, y0, n, out);
        break;
    case K_NOISE_SINE:
        fbm_rows_K_NOISE_SINE(*p, y0, n, out);
        break;
    default:
        fbm_rows_K_NOISE_GRADIENT(*p, y0, n, out);
        break;
    }
}

/* Fills K_FbmParams from a validated layer. */
void fb_fbm_params_frame(K_FbmParams *p, int width, int height)
{
    p->width = (uint32_t)width;
    p->height = (uint32_t)height;
    p->inv_width = 1.0f / (float)width;
    p->inv_height = 1.0f / (float)height;
    p->inv_freq_x = 1.0f / p->freq_x;
    p->inv_freq_y = 1.0f / p->freq_y;
}

static void fb_fbm_params_fill(const fb_scene *s, const fb_layer *L, K_FbmParams *p)
{
    const fb_fbm_params *f = &L->fbm;
    memset(p, 0, sizeof *p);
    p->seed = s->seed;
    p->noise = f->noise;
    p->octaves = (uint32_t)f->octaves;
    p->flags = (f->ridged ? K_FBM_RIDGED : 0u) | (f->billow ? K_FBM_BILLOW : 0u) | (f->tileable ? K_FBM_TILEABLE : 0u);
    p->gain = (float)f->gain;
    p->lacunarity = (float)f->lacunarity;
    double a = f->rotation * 3.14159265358979323846 / 180.0;
    p->rot_c = (float)cos(a);
    p->rot_s = (float)sin(a);
    p->freq_x = (float)f->frequency;
    p->freq_y = (float)(f->frequency * s->height / s->width); /* square cells */
    p->offset_x = (float)f->offset[0];
    p->offset_y = (float)f->offset[1];
    p->warp = (float)f->warp;
    fb_fbm_params_frame(p, s->width, s->height);
}

fb_result fb_gen_fbm_init(fb_gen *g)
{
    fb_fbm_params_fill(g->scene, g->layer, (K_FbmParams *)(void *)g->params);
    g->nchannels = 1;
    snprintf(g->channel_names[0], sizeof g->channel_names[0], "%s.Y", g->layer->name);
    g->channel_types[0] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    g->native_rows = fbm_rows;
    g->spv = fbm_comp;
    g->spv_size = sizeof fbm_comp;
    g->params_size = sizeof(K_FbmParams);
    g->push_size = sizeof(fbm_push);
    g->spec[0] = params(g)->noise;
    g->spec[1] = params(g)->flags;
    g->nspec = 2;
    return FB_OK;
}
