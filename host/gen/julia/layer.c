/*
 * The Julia sky generator: kernels/julia.h, driven natively or by shaders/julia.comp.
 * Channels: NAME.iter (uint), NAME.n (smooth count), NAME.inside (0/1), NAME.de (pixels), NAME.R/G/B;
 * the layer's `channels` stores a subset, and what no stored channel needs is not computed.
 */
#include "gen_fbm.h"
#include "gen_julia.h"

#include "kernels/julia.h"
#include "kernels/palette.h"
#include "palette.h"
#include "julia64_comp.h"
#include "julia_comp.h"
#include "julia_env_comp.h"
#include "layer_avx2.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec julia_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"julia\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"sky\"",
     "layer name; channels NAME.iter, .n, .inside, .de, .R, .G, .B (flag: --layer)", FB_CORE},
    {"mapping", FB_K_ENUM, 0, 0, false, "rect|polar|latlong|cube", "\"rect\"",
     "starting grid: rect (eq. 7), polar (eq. 8, seamless left/right), or an environment map of the sphere, "
     "latlong (2N x N) or cube (N x 6N), through p = r (d.x + i d.z) / (1 + d.y) (docs/sky.md)",
     FB_FIELD(fb_julia_params, mapping)},
    {"scale", FB_K_VEC2, 0, 1e6, false, NULL, NULL,
     "rect: width and height of the grid (default 3 wide, square pixels)", FB_FIELD(fb_julia_params, scale)},
    {"radius", FB_K_NUM, 0, 1e6, true, NULL, "1.5",
     "polar: radius r of p = r v exp(i 2 pi u); latlong, cube: the horizon's |p|", FB_FIELD(fb_julia_params, radius)},
    {"center", FB_K_VEC2, -1e6, 1e6, false, NULL, "[0.0, 0.0]", "centre of the starting grid (RE,IM)",
     FB_FIELD(fb_julia_params, center)},
    {"rotation", FB_K_NUM, -360, 360, false, NULL, "0.0", "rotation of the starting grid, degrees",
     FB_FIELD(fb_julia_params, rotation)},
    {"alpha", FB_K_VEC2, -1e6, 1e6, false, NULL, "[0.0, 0.0]", "allpass warp coefficient a (RE,IM); 0: plain Julia set",
     FB_FIELD(fb_julia_params, alpha)},
    {"c", FB_K_VEC2, -1e6, 1e6, false, NULL, "[-0.8, 0.156]", "Julia constant c (RE,IM)", FB_FIELD(fb_julia_params, c)},
    {"max-iter", FB_K_INT, 1, 1000000, false, NULL, "256", "iteration limit", FB_FIELD(fb_julia_params, max_iter)},
    {"bailout", FB_K_NUM, 2, 1e6, false, NULL, "2.0", "escape radius R (iter counts steps until |z| >= R)",
     FB_FIELD(fb_julia_params, bailout)},
    {"turbulence", FB_K_NUM, 0, 10, false, NULL, "0.0", "lambda of eq. 13: z0 = A(1/p) + lambda W(p), W fBm in [0, 1]",
     FB_FIELD(fb_julia_params, turbulence)},
    {"turbulence-hurst", FB_K_NUM, 0, 1, false, NULL, "0.8", "Hurst exponent of W",
     FB_FIELD(fb_julia_params, turb_hurst)},
    {"turbulence-octaves", FB_K_INT, 1, 32, false, NULL, "6", "octaves of W", FB_FIELD(fb_julia_params, turb_octaves)},
    {"turbulence-frequency", FB_K_NUM, 0, 1e4, true, NULL, "4.0", "cycles of W's first octave across the image",
     FB_FIELD(fb_julia_params, turb_frequency)},
    {"samples", FB_K_INT, 1, 1024, false, NULL, "1", "jittered colour samples per pixel (iter, n, inside, de: centre)",
     FB_FIELD(fb_julia_params, samples)},
    {"precision", FB_K_ENUM, 0, 0, false, "float|double", "\"float\"",
     "the grid and orbits in float, or double (escape counts as a double reference has them; Vulkan "
     "devices need shaderFloat64)",
     FB_FIELD(fb_julia_params, double_precision)},
    {"channels", FB_K_NAMES, 0, 0, false, "iter|n|inside|de|R|G|B",
     "[\"iter\", \"n\", \"inside\", \"de\", \"R\", \"G\", \"B\"]",
     "channels to store; what none of them needs is not computed (R, G, B go together)",
     FB_FIELD(fb_julia_params, channels)},
    {"palette", FB_K_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"night\"", "named colour map", 0, NULL, "cosine|stops",
     FB_CORE},
    {"cosine", FB_K_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12, FB_CORE},
    {"stops", FB_K_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")", FB_CORE},
    {"period", FB_K_NUM, 0, 1e6, true, NULL, "24.0", "smooth-count units per palette sweep",
     FB_FIELD(fb_julia_params, period)},
    {"palette-offset", FB_K_NUM, -1e6, 1e6, false, NULL, "0.0", "palette position at count 0, in sweeps",
     FB_FIELD(fb_julia_params, palette_offset)},
    {"brightness", FB_K_NUM, 0, 1e3, false, NULL, "1.0", "linear colour scale", FB_FIELD(fb_julia_params, brightness)},
    {"gamma", FB_K_NUM, 0, 10, true, NULL, "1.0", "exponent on the colour", FB_FIELD(fb_julia_params, gamma)},
    {"density", FB_K_NUM, 0, 16, false, NULL, "1.5", "contrast: larger keeps only pixels near the set bright",
     FB_FIELD(fb_julia_params, density)},
    {"density-count", FB_K_NUM, 1, 1e6, false, NULL, "48.0", "smooth count at which brightness is full",
     FB_FIELD(fb_julia_params, density_count)},
    {"inside-color", FB_K_NUMLIST, 0, 1e3, false, NULL, "[0.0, 0.0, 0.0]", "colour of points inside the set (R,G,B)", 3,
     FB_FIELD(fb_julia_params, inside_color)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "true", "store R, G, B as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

/* The keys that shape only R, G and B. */
static const char *const k_colour_keys[] = {"palette",        "cosine",       "stops",   "period",
                                            "palette-offset", "brightness",   "gamma",   "density",
                                            "density-count",  "inside-color", "samples", NULL};

/* A colour key the user gave on the command line or by --set (a file's may be a stored default). */
static const char *given_colour_key(const fb_vctx *v, const char *path, const json_t *obj)
{
    for (int i = 0; k_colour_keys[i]; i++) {
        if (!json_object_get(obj, k_colour_keys[i])) continue;
        if (!v->origin) return k_colour_keys[i];
        char sub[256];
        snprintf(sub, sizeof sub, "%s.%s", path, k_colour_keys[i]);
        for (int k = 0; k < v->nsets; k++)
            if (!strcmp(v->set_paths[k], sub)) return k_colour_keys[i];
    }
    return NULL;
}

static fb_result parse_julia(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    /* The default grid is 3 units wide with square pixels, so it depends on the image size. */
    if (!json_object_get(obj, "scale") && s->width > 0)
        json_object_set_new(obj, "scale", json_pack("[ff]", 3.0, 3.0 * s->height / s->width));
    const char *colour = given_colour_key(v, path, obj); /* before the defaults fill them in */
    fb_julia_params *j = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, julia_keys, FB_NKEYS(julia_keys), "a julia layer", j);
    if (rc) return rc;
    /* the mapping's names in the order of K_JULIA_*; the channels' bits in the order of their names */
    _Static_assert(K_JULIA_POLAR == 1u && K_JULIA_LATLONG == 2u && K_JULIA_CUBE == 3u, "mapping names");
    if ((rc = fb_schema_palette(v, path, obj, &j->palette))) return rc;
    if (j->double_precision && j->mapping >= K_JULIA_LATLONG) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.precision", path);
        return fb_schema_error(v, sub,
                               "\"double\" is for the rect and polar grids; an environment map's directions "
                               "are float (use \"float\")");
    }
    unsigned rgb = j->channels & 0x70u;
    if (rgb && rgb != 0x70u) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.channels", path);
        return fb_schema_error(v, sub, "R, G and B go together: list all three or none");
    }
    if (!rgb && colour) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.%s", path, colour);
        return fb_schema_error(v, sub,
                               "shapes only R, G and B, which the layer does not store (add them to its channels)");
    }
    if (!(j->scale[0] > 0 && j->scale[1] > 0)) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.scale", path);
        return fb_schema_error(v, sub, "both sides of the grid must be positive");
    }
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

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
    K_JuliaD dp; /* the double-precision shader's parameters and constants */
} julia_palette;
_Static_assert(sizeof(K_SkyColour) == 48 && offsetof(julia_palette, turb) == 48, "std430 offset");
_Static_assert(sizeof(K_FbmParams) == 84 && offsetof(julia_palette, entries) == 144, "std430: vec4 array at 144");
_Static_assert(FB_PALETTE_ENTRIES == K_PALETTE_SIZE, "palette size");
_Static_assert(offsetof(julia_palette, dp) == 144 + 16 * K_PALETTE_SIZE && sizeof(K_JuliaD) == 29 * 8, "std430");
/* a uniform buffer (julia_body.glsl): std140 gives the same offsets (turb rounds up to 96 bytes, the
 * entries at 144 without the pad), within the 16 KiB every Vulkan device binds */
_Static_assert(48 + 96 == 144 && sizeof(julia_palette) <= 16384, "std140 uniform buffer");

static const K_JuliaParams *params(const fb_gen *g)
{
    return (const K_JuliaParams *)(const void *)g->params;
}

/* The same table lookup as shaders/julia.comp. */
/* The palette lookup of kernels/palette.h (k_sky_rgb), the entries fetched from the table. */
static void sky_colour(const julia_palette *pal, K_JuliaResult res, float rgb[3])
{
    uint32_t i0 = k_sky_i0(pal->colour, res.nsmooth), i1 = k_sky_i1(i0);
    const float *a = pal->entries[i0], *b = pal->entries[i1];
    k_vec3 v = k_sky_rgb(pal->colour, res.inside, res.nsmooth, (k_vec4){a[0], a[1], a[2], a[3]},
                         (k_vec4){b[0], b[1], b[2], b[3]});
    rgb[0] = v.x, rgb[1] = v.y, rgb[2] = v.z;
}

/* Kernel planes: iter, n, inside, de, R, G, B (bit k of the stored mask: plane k stored). */
enum { P_ITER, P_N, P_INSIDE, P_DE, P_R, P_G, P_B, NPLANES };

/* What the orbits must compute for the stored planes. */
static uint32_t want_of(uint32_t stored)
{
    uint32_t smooth = (1u << P_N) | (1u << P_R) | (1u << P_G) | (1u << P_B);
    return ((stored & smooth) ? K_JULIA_WANT_SMOOTH : 0u) | ((stored & (1u << P_DE)) ? K_JULIA_WANT_DE : 0u);
}

static void store(void *const *planes, size_t i, K_JuliaResult res)
{
    if (planes[P_ITER]) ((uint32_t *)planes[P_ITER])[i] = res.iter;
    if (planes[P_N]) ((float *)planes[P_N])[i] = res.nsmooth;
    if (planes[P_INSIDE]) ((float *)planes[P_INSIDE])[i] = (float)res.inside;
    if (planes[P_DE]) ((float *)planes[P_DE])[i] = res.de;
}

static void store_colour(void *const *planes, size_t i, const julia_palette *pal, const float sum[3])
{
    float s = pal->colour.samples == 1 ? 1.0f : pal->colour.inv_samples;
    for (int ch = 0; ch < 3; ch++) ((float *)planes[P_R + ch])[i] = pal->colour.samples == 1 ? sum[ch] : sum[ch] * s;
}

/* One pixel at a time: the shader's pairs give the same results to the bit (their point is two
 * dependency chains per SIMD lane; scalar C ran slower with them). */
static void julia_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_JuliaParams *p = params(g);
    const julia_palette *pal = g->compute.shader.input;
    const uint32_t want = want_of(g->compute.shader.spec[4]);
    const bool colour = planes[P_R] != NULL, dbl = g->compute.shader.needs_float64;
    /* Every channel bit-exact with the loop below (tests/test_avx2.c), so using it changes no result. */
    if (!g->run.scalar && !dbl && fb_julia_avx2_layer_supported(p)) {
        fb_julia_avx2_layer_rows(&(fb_julia_avx2_ctx){p, &pal->colour, pal->entries, &pal->turb, want}, y0, n, planes);
        return;
    }
    for (int r = 0; r < n; r++)
        for (uint32_t x = 0; x < p->width; x++) {
            uint32_t y = (uint32_t)(y0 + r);
            K_JuliaResult res =
                dbl ? k_julia_run_d(*p, pal->dp, pal->turb, x + 0.5, y + 0.5, want)
                    : k_julia_run(*p, k_julia_start_at(*p, pal->turb, (float)x + 0.5f, (float)y + 0.5f), want);
            size_t i = (size_t)r * p->width + x;
            store(planes, i, res);
            if (!colour) continue;
            /* the average of `samples` jittered samples in linear colour (sample 0 is the centre) */
            float sum[3], c[3];
            sky_colour(pal, res, sum);
            for (uint32_t k = 1; k < pal->colour.samples; k++) {
                k_vec2 f = k_julia_sample_xy(*p, pal->colour.seed, x, y, k);
                sky_colour(pal,
                           dbl ? k_julia_run_d(*p, pal->dp, pal->turb, f.x, f.y, K_JULIA_WANT_SMOOTH)
                               : k_julia_run(*p, k_julia_start_at(*p, pal->turb, f.x, f.y), K_JULIA_WANT_SMOOTH),
                           c);
                for (int ch = 0; ch < 3; ch++) sum[ch] += c[ch];
            }
            store_colour(planes, i, pal, sum);
        }
}

static fb_result julia_init(fb_gen *g)
{
    const fb_scene *s = g->scene;
    const fb_julia_params *j = fb_layer_params(g->layer);
    K_JuliaParams *p = (K_JuliaParams *)(void *)g->params;
    memset(p, 0, sizeof *p);
    p->width = (uint32_t)s->width;
    p->height = (uint32_t)s->height;
    p->mapping = j->mapping;
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
    /* double precision: the parameters unrounded, and the constants of k_julia_sincos_d */
    pal->dp = (K_JuliaD){
        .c_re = j->c[0],
        .c_im = j->c[1],
        .a_re = j->alpha[0],
        .a_im = j->alpha[1],
        .scale_u = j->scale[0],
        .scale_v = j->scale[1],
        .radius = j->radius,
        .center_re = j->center[0],
        .center_im = j->center[1],
        .rot_c = cos(a),
        .rot_s = sin(a),
        .bailout2 = j->bailout * j->bailout,
    };
    k_julia_d_constants(&pal->dp);
    /* Turbulence W: fBm over (u, v) with the layer's own parameters; tileable for polar grids; on
     * the sphere for environment maps (k_fbm3: the frequency's cells round the equator). */
    bool polar = j->mapping == K_JULIA_POLAR;
    K_FbmParams *t = &pal->turb;
    t->seed = s->seed;
    t->noise = K_NOISE_GRADIENT;
    t->octaves = (uint32_t)j->turb_octaves;
    t->gain = (float)exp2(-j->turb_hurst);
    t->lacunarity = 2.0f;
    t->rot_c = 0.8f; /* the paper's rotation (0.8, 0.6) between octaves */
    t->rot_s = 0.6f;
    t->flags = polar ? K_FBM_TILEABLE : 0u;
    t->freq_x = (float)j->turb_frequency;
    t->freq_y =
        (float)(polar || j->mapping >= K_JULIA_LATLONG ? j->turb_frequency : j->turb_frequency * s->height / s->width);
    fb_fbm_params_frame(t, s->width, s->height);
    double gsum = 0, amp = 1;
    for (int i = 0; i < j->turb_octaves; i++, amp *= t->gain) gsum += amp;
    p->lambda = (float)j->turbulence;
    p->turb_norm = (float)(1.0 / gsum);
    g->owned = pal;
    g->compute.shader.input = pal;
    g->compute.shader.input_size = sizeof *pal;
    g->compute.shader.input_uniform = true; /* julia_body.glsl: the palette's lanes gather from a uniform buffer */

    static const char *const suffix[NPLANES] = {"iter", "n", "inside", "de", "R", "G", "B"};
    exrio_type colour = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    const exrio_type types[NPLANES] = {EXRIO_UINT, EXRIO_FLOAT, EXRIO_HALF, EXRIO_FLOAT, colour, colour, colour};
    uint32_t stored = (uint32_t)j->channels & ((1u << NPLANES) - 1);
    g->compute.nkernel = NPLANES;
    g->store.nchannels = 0;
    for (int k = 0; k < NPLANES; k++) {
        if (!(stored & (1u << k))) continue;
        int c = g->store.nchannels++;
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[k]);
        g->store.channel_types[c] = types[k];
        g->compute.kernel_of[c] = k;
    }
    /* the preview: colour if stored, else the first float channel (n, inside, de), else iter */
    g->store.preview_rgb = -1;
    g->store.preview_channel = 0;
    for (int c = g->store.nchannels - 1; c >= 0; c--) {
        if (g->compute.kernel_of[c] == P_R) g->store.preview_rgb = c;
        if (g->compute.kernel_of[c] != P_ITER && g->compute.kernel_of[c] != P_R && g->compute.kernel_of[c] != P_G &&
            g->compute.kernel_of[c] != P_B)
            g->store.preview_channel = c;
    }
    g->compute.native_rows = julia_rows;
    g->compute.shader.needs_float64 = j->double_precision;
    /* the plane's shader carries no environment-map code (kernels/common.h, K_WITH_ENVMAP) */
    bool env = p->mapping >= K_JULIA_LATLONG;
    g->compute.shader.spv = j->double_precision ? julia64_comp : env ? julia_env_comp : julia_comp;
    g->compute.shader.spv_size = j->double_precision ? sizeof julia64_comp
                                 : env               ? sizeof julia_env_comp
                                                     : sizeof julia_comp;
    g->compute.shader.params_size = sizeof(K_JuliaParams);
    g->compute.shader.push_size = sizeof(julia_push);
    g->compute.shader.spec[0] = p->mapping;
    g->compute.shader.spec[1] = p->lambda != 0.0f;
    g->compute.shader.spec[2] = (uint32_t)j->samples;
    g->compute.shader.spec[3] = (pal->colour.gamma != 1.0f ? 1u : 0u) | (pal->colour.density > 0.0f ? 2u : 0u);
    g->compute.shader.spec[4] = stored;
    g->compute.shader.spec[5] = p->width % 2u == 0u; /* each invocation's pair stored as one vec2 (julia_body.glsl) */
    g->compute.shader.nspec = 6;
    g->compute.shader.per_invocation = 2;
    /* The AVX2 path (float grids on a CPU with AVX2) beats lavapipe's shader at every size, with or
     * without turbulence. The scalar loop (double precision, no AVX2): the shader beats it by 1.27x
     * once the work outweighs compiling it (measured crossover: about 8 million samples), but its
     * turbulence (fBm per pixel) runs 7x slower there (bench/RESULTS.md). */
    g->compute.lavapipe_faster = (j->double_precision || !fb_julia_avx2_layer_supported(p)) && j->turbulence == 0 &&
                                 (double)s->width * s->height * j->samples >= 8e6;
    return FB_OK;
}

/* ---- planning -------------------------------------------------------------------------------- */

/* Seconds of one core of the reference machine (docs/scenes.md, "Splitting a bake"). */
#define C_JULIA_ITER   1.9e-9 /* a Julia iteration of one sample */
#define C_JULIA_SAMPLE 8.0e-8 /* a Julia sample: the warp, palette and 7 channels */
#define C_JULIA_TURB   7.7e-8 /* an octave of a Julia sample's turbulence */
#define PREPASS_WIDTH  64     /* the pre-pass's width */

/* The iterations of each row, per pixel and sample, from a pre-pass at PREPASS_WIDTH pixels wide
 * without turbulence (it moves the starting grid a little: a row's iterations hardly change, and it
 * would be most of the pre-pass's time, which each idle task of a plan pays too), one sample, and
 * only the iteration count computed; then the model's seconds per row. */
static fb_result julia_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_layer *L = &s->layers[layer];
    const fb_julia_params *j = fb_layer_params(L);
    int w = s->width < PREPASS_WIDTH ? s->width : PREPASS_WIDTH;
    int h = (int)((double)s->height * w / s->width + 0.5);
    if (h < 1) h = 1;
    if (h > s->height) h = s->height;
    fb_julia_params small_params = *j;
    small_params.channels = 1u; /* iter */
    small_params.samples = 1;
    small_params.turbulence = 0;
    fb_layer small_layer = *L;
    small_layer.params = &small_params;
    fb_scene small = *s; /* shares s's storage: only read here */
    small.width = w, small.height = h;
    fb_gen g = {0};
    uint32_t *it = malloc((size_t)w * h * sizeof *it);
    fb_result rc = it ? fb_gen_init(&g, &small, &small_layer) : fb_fail(FB_ERR_NOMEM, "out of memory");
    if (!rc && (!g.compute.native_rows || fb_gen_nplanes(&g) > FB_GEN_MAX_CHANNELS))
        rc = fb_fail(FB_ERR_INTERNAL, "the Julia pre-pass has no native kernel");
    if (!rc) {
        void *planes[FB_GEN_MAX_CHANNELS] = {0};
        planes[fb_gen_plane_of(&g, 0)] = it;
        g.compute.native_rows(&g, 0, h, planes);
        double turb = j->turbulence != 0 ? j->turb_octaves * C_JULIA_TURB : 0;
        *total = 0;
        for (int y = 0; y < s->height; y++) {
            int ys = (int)((int64_t)y * h / s->height);
            double sum = 0;
            for (int x = 0; x < w; x++) sum += it[(size_t)ys * w + x];
            rows[y] = (double)s->width * j->samples * (sum / w * C_JULIA_ITER + C_JULIA_SAMPLE + turb);
            *total += rows[y];
        }
    }
    fb_gen_fini(&g);
    free(it);
    return rc;
}

const fb_gen_class fb_gen_julia = {
    .name = "julia",
    .synopsis = "julia [options] -o OUT.exr",
    .summary = "a warped Julia set (night skies), one layer",
    .what = "a julia layer",
    .keys = julia_keys,
    .nkeys = FB_NKEYS(julia_keys),
    .params_size = sizeof(fb_julia_params),
    .parse = parse_julia,
    .init = julia_init,
    .share = FB_SHARE_BAND,
    .cost = julia_cost,
    .tolerance = {0, 0}, /* exact arithmetic (kernels/exact.h): the same bits on every backend */
    .bench = fb_julia_bench,
};
