/*
 * The fBm generator: kernels/fbm.h, driven natively or by shaders/fbm.comp.
 */
#include "fbm3_avx2.h"
#include "fbm_avx2.h"
#include "gen_fbm.h"

#include "kernels/fbm.h"
#include "fbm_comp.h"
#include "fbm_env_comp.h"

#include "heightmap.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec fbm_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"fbm\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"fbm\"", "layer name; the channel is NAME.Y (flag: --layer)", FB_CORE},
    {"noise", FB_K_ENUM, 0, 0, false, "gradient|value|simplex|cellular|cellular-f2|sine", "\"gradient\"", "base noise",
     FB_FIELD(fb_fbm_params, noise)},
    {"hurst", FB_K_NUM, 0, 1, false, NULL, "1.0", "Hurst exponent H; gain G = 2^-H", 0, NULL, "gain",
     FB_FIELD(fb_fbm_params, hurst)},
    {"gain", FB_K_NUM, 0, 2, true, NULL, NULL, "octave gain G, instead of hurst", FB_FIELD(fb_fbm_params, gain)},
    {"octaves", FB_K_INT, 1, 32, false, NULL, "8", "number of octaves", FB_FIELD(fb_fbm_params, octaves)},
    {"lacunarity", FB_K_NUM, 1.01, 8, false, NULL, "2.0", "frequency ratio between octaves",
     FB_FIELD(fb_fbm_params, lacunarity)},
    {"rotation", FB_K_NUM, -180, 180, false, NULL, "36.87", "rotation between octaves, degrees",
     FB_FIELD(fb_fbm_params, rotation)},
    {"frequency", FB_K_NUM, 0, 1e6, true, NULL, "4.0",
     "cycles of the first octave across the image width (latlong, cube: round the equator)",
     FB_FIELD(fb_fbm_params, frequency)},
    {"offset", FB_K_VEC2, -1e6, 1e6, false, NULL, "[0.0, 0.0]", "domain offset, in first-octave cells (X,Y)",
     FB_FIELD(fb_fbm_params, offset)},
    {"ridged", FB_K_BOOL, 0, 0, false, NULL, "false", "ridged octaves (1 - |n|)^2", FB_FIELD(fb_fbm_params, ridged)},
    {"billow", FB_K_BOOL, 0, 0, false, NULL, "false", "billow octaves 2|n| - 1", FB_FIELD(fb_fbm_params, billow)},
    {"warp", FB_K_NUM, 0, 100, false, NULL, "0.0", "domain-warp strength, in first-octave cells",
     FB_FIELD(fb_fbm_params, warp)},
    {"tileable", FB_K_BOOL, 0, 0, false, NULL, "false", "periodic in x and y: the image wraps without a seam",
     FB_FIELD(fb_fbm_params, tileable)},
    {"mapping", FB_K_ENUM, 0, 0, false, "rect|latlong|cube", "\"rect\"",
     "the plane, or an environment map of the sphere, latlong (2N x N) or cube (N x 6N): 3D fBm at each "
     "pixel's direction, no seam and no pinch (docs/sky.md)",
     FB_FIELD(fb_fbm_params, mapping)},
    {"heightmap", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write the heights for engines: OUT.png (16-bit grey) or OUT.r16 (16-bit raw, little-endian)", FB_CORE},
    FB_HEIGHTMAP_KEYS,
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store as half instead of float (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_fbm(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    char sub[256];
    fb_fbm_params *f = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, fbm_keys, FB_NKEYS(fbm_keys), "an fbm layer", f);
    if (rc) return rc;
    if (json_object_get(obj, "hurst") && json_object_get(obj, "gain")) {
        snprintf(sub, sizeof sub, "%s.gain", path);
        return fb_schema_error(v, sub, "give hurst or gain, not both");
    }
    /* the noise and mapping names are in the order of K_NOISE_* and K_ENV_*: their index is the kind */
    f->gain_given = json_object_get(obj, "gain") != NULL;
    if (f->gain_given)
        f->hurst = -log2(f->gain);
    else
        f->gain = exp2(-f->hurst);
    _Static_assert(K_NOISE_VALUE == 1u && K_NOISE_SINE == 5u && K_ENV_LATLONG == 1u && K_ENV_CUBE == 2u,
                   "the keys' names in the order of the kinds");
    if (f->tileable && f->mapping != K_ENV_RECT) {
        snprintf(sub, sizeof sub, "%s.tileable", path);
        return fb_schema_error(v, sub,
                               "an environment map has no edges to tile: drop \"tileable\" (the sphere "
                               "has no seam)");
    }
    if (f->ridged && f->billow) {
        snprintf(sub, sizeof sub, "%s.billow", path);
        return fb_schema_error(v, sub, "ridged and billow cannot both be set");
    }
    if (f->tileable && f->noise == K_NOISE_SIMPLEX) {
        snprintf(sub, sizeof sub, "%s.tileable", path);
        return fb_schema_error(v, sub,
                               "simplex noise lives on a skewed lattice that does not tile a rectangle; use gradient, "
                               "value, cellular, cellular-f2 or sine noise for tileable fBm");
    }
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

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
_Static_assert(offsetof(K_FbmParams, mapping) == 76 && offsetof(K_FbmParams, pad1) == 80, "std430 offset");
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
                out[(size_t)r * p.width + x] = k_fbm_map_pixel(p, x, (uint32_t)(y0 + r));                              \
    }
FBM_ROWS(K_NOISE_GRADIENT)
FBM_ROWS(K_NOISE_VALUE)
FBM_ROWS(K_NOISE_SIMPLEX)
FBM_ROWS(K_NOISE_CELLULAR)
FBM_ROWS(K_NOISE_CELLULAR_F2)
FBM_ROWS(K_NOISE_SINE)

/* The plane's AVX2 loop (gradient noise, plain shape, no warp). */
static bool avx2_applies(const K_FbmParams *p)
{
    return p->mapping == K_ENV_RECT && fb_fbm_avx2_supported(p);
}

/* The sphere's AVX2 lanes (environment maps: every noise kind and shape, warp or not). */
static bool avx2_env_applies(const K_FbmParams *p)
{
    return p->mapping != K_ENV_RECT && fb_fbm3_avx2_supported(p);
}

static void fbm_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const K_FbmParams *p = params(g);
    float *out = planes[0];
    /* Both bit-exact with the kernel (tests/test_avx2.c), so using them changes no result. */
    if (!g->run.scalar && avx2_applies(p)) {
        fb_fbm_avx2_rows(p, y0, n, out);
        return;
    }
    if (!g->run.scalar && avx2_env_applies(p)) {
        fb_fbm3_avx2_rows(p, y0, n, out);
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

/* The frame fields of *p for a width x height image: the size, its reciprocals and those of the
 * frequencies (freq_x, freq_y already set). */
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
    const fb_fbm_params *f = fb_layer_params(L);
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
    p->mapping = f->mapping;
    fb_fbm_params_frame(p, s->width, s->height);
}

double fb_fbm_lattice_bound(const K_FbmParams *p)
{
    double amp_sum = 0, amp = 1;
    for (uint32_t i = 0; i < p->octaves; i++, amp *= fabs((double)p->gain)) amp_sum += amp;
    /* |u|, |v| < 1, then the warp: u' = u + warp fbm(u, v) / fx with |fbm| <= amp_sum (every shape is in [-1, 1]) */
    double um = 1 + fabs((double)p->warp) * amp_sum * fabs((double)p->inv_freq_x);
    double vm = 1 + fabs((double)p->warp) * amp_sum * fabs((double)p->inv_freq_y);
    double lac = fabs((double)p->lacunarity), rc = fabs((double)p->rot_c), rs = fabs((double)p->rot_s);
    double x = fabs((double)p->freq_x) * um + fabs((double)p->offset_x);
    double y = fabs((double)p->freq_y) * vm + fabs((double)p->offset_y);
    double cx = fabs((double)p->freq_x), cy = fabs((double)p->freq_y), bound = 0;
    for (uint32_t i = 0; i < p->octaves; i++) {
        double m = x > y ? x : y;
        if ((p->flags & K_FBM_TILEABLE) != 0u) { /* u round(cells) + an offset under 256 */
            double tx = um * (cx + 1) + 255 + fabs((double)p->offset_x),
                   ty = vm * (cy + 1) + 255 + fabs((double)p->offset_y);
            m = tx > ty ? tx : ty;
        }
        /* simplex skews by (x + y)(sqrt(3) - 1)/2; cellular looks 2 cells away; 1e-5: float rounding */
        m = (m * (1 + 0.7320508) + 3) * (1 + 1e-5);
        if (isnan(m)) return INFINITY;
        if (m > bound) bound = m;
        double nx = lac * (rc * x + rs * y) * (1 + 1e-5) + 64, ny = lac * (rs * x + rc * y) * (1 + 1e-5) + 64;
        x = nx, y = ny, cx *= lac, cy *= lac;
    }
    return isfinite(bound) ? bound : INFINITY;
}

static fb_result fbm_init(fb_gen *g)
{
    fb_fbm_params_fill(g->scene, g->layer, (K_FbmParams *)(void *)g->params);
    g->store.nchannels = 1;
    snprintf(g->store.channel_names[0], sizeof g->store.channel_names[0], "%s.Y", g->layer->name);
    g->store.channel_types[0] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    g->compute.native_rows = fbm_rows;
    /* the AVX2 loops beat lavapipe (the plane's 1.6x; the sphere's, lat-long 2048 x 1024 x 8 octaves:
     * gradient 0.2 s of CPU against 0.9 s, cellular 1.8 s against 4.3 s); the scalar C does not */
    g->compute.lavapipe_faster = !avx2_applies(params(g)) && !avx2_env_applies(params(g));
    bool env = params(g)->mapping != K_ENV_RECT; /* only the sphere's shader carries 3D noise */
    g->compute.shader.spv = env ? fbm_env_comp : fbm_comp;
    g->compute.shader.spv_size = env ? sizeof fbm_env_comp : sizeof fbm_comp;
    g->compute.shader.params_size = sizeof(K_FbmParams);
    g->compute.shader.push_size = sizeof(fbm_push);
    g->compute.shader.spec[0] = params(g)->noise;
    g->compute.shader.spec[1] = params(g)->flags;
    g->compute.shader.spec[2] = fb_fbm_lattice_bound(params(g)) < 16777216.0 ? 1u : 0u;
    g->compute.shader.spec[3] = params(g)->mapping;
    g->compute.shader.nspec = 4;
    return FB_OK;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). */
static fb_result fbm_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_fbm_params *f = fb_layer_params(&s->layers[layer]);
    /* an octave of one pixel (3D noise on the sphere: twice the lattice corners), its frame and channel */
    double octave = f->mapping == K_ENV_RECT ? 3.0e-9 : 6.0e-9;
    double row = (double)s->width * (f->octaves * octave + 9.0e-9);
    *total = 0;
    for (int y = 0; y < s->height; y++) rows[y] = row, *total += row;
    return FB_OK;
}

const fb_gen_class fb_gen_fbm = {
    .name = "fbm",
    .synopsis = "fbm [options] -o OUT.exr",
    .summary = "fBm noise, one layer (fractalbake fbm --help lists the options)",
    .what = "an fbm layer",
    .keys = fbm_keys,
    .nkeys = FB_NKEYS(fbm_keys),
    .params_size = sizeof(fb_fbm_params),
    .parse = parse_fbm,
    .init = fbm_init,
    .share = FB_SHARE_BAND,
    .cost = fbm_cost,
    .tolerance = {0, 0}, /* exact arithmetic (kernels/exact.h): the same bits on every backend */
    .bench = fb_fbm_bench,
};
