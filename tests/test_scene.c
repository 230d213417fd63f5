/*
 * Scenes and flags reach the kernel: every fBm key and flag changes the parameters it names
 * (a flag parsed and ignored would fail here), defaults are filled in, and the stored scene is
 * canonical.
 */
#include "../kernels/fbm.h"
#include "../kernels/julia.h"
#include "../kernels/palette.h"
#include "gen_fbm.h"
#include "gen_ifs.h"
#include "gen_julia.h"
#include "gen_op.h"
#include "gen_terrain.h"
#include "jsonout.h"
#include "flags.h"
#include "scene.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A layer's parameters as its generator's type. */
#define P(T, L) ((const T *)fb_layer_params(&(L)))

static K_FbmParams params_of(const char *json, fb_scene *s, fb_gen *g)
{
    K_FbmParams p;
    memset(&p, 0, sizeof p);
    CHECKF(fb_scene_parse(json, NULL, s) == FB_OK, "%s", json);
    CHECK(fb_gen_init(g, s, &s->layers[0]) == FB_OK);
    memcpy(&p, g->params, sizeof p);
    return p;
}

static void test_keys(void)
{
    fb_scene s;
    fb_gen g;
    K_FbmParams p = params_of("{\"size\": [200, 100], \"seed\": 99, \"compression\": \"piz\", \"layers\": [{\"type\": "
                              "\"fbm\", \"name\": \"h\", \"noise\": \"cellular-f2\", \"hurst\": 0.5, \"octaves\": 13, "
                              "\"lacunarity\": 1.99, \"rotation\": 90, \"frequency\": 6, \"offset\": [1.5, -2], "
                              "\"ridged\": true, \"warp\": 0.25, \"half\": true}]}",
                              &s, &g);
    CHECK(s.width == 200 && s.height == 100 && s.seed == 99 && s.compression == EXRIO_PIZ);
    CHECK(p.seed == 99 && p.noise == K_NOISE_CELLULAR_F2 && p.octaves == 13);
    CHECK(fabsf(p.gain - 0.70710678f) < 1e-7f);
    CHECK(p.lacunarity == 1.99f);
    CHECK(fabsf(p.rot_c) < 1e-7f && fabsf(p.rot_s - 1.0f) < 1e-7f);
    CHECK(p.freq_x == 6.0f && p.freq_y == 3.0f); /* square cells on a 2:1 image */
    CHECK(p.offset_x == 1.5f && p.offset_y == -2.0f);
    CHECK(p.flags == K_FBM_RIDGED && p.warp == 0.25f);
    CHECK(p.width == 200 && p.height == 100 && p.inv_width == 1.0f / 200.0f);
    CHECK(g.store.nchannels == 1 && !strcmp(g.store.channel_names[0], "h.Y") && g.store.channel_types[0] == EXRIO_HALF);
    /* 6 cells x 1.99^12 at the finest octave: far under 2^24, so the small-coordinate shader */
    CHECK(g.compute.shader.nspec == 4 && g.compute.shader.spec[0] == K_NOISE_CELLULAR_F2 &&
          g.compute.shader.spec[1] == K_FBM_RIDGED && g.compute.shader.spec[2] == 1u &&
          g.compute.shader.spec[3] == K_ENV_RECT);
    fb_scene_fini(&s);

    /* defaults, filled into the stored scene */
    p = params_of("{\"layers\": [{\"type\": \"fbm\"}]}", &s, &g);
    CHECK(s.width == 1024 && s.height == 1024 && s.seed == 1 && s.compression == EXRIO_ZIP);
    CHECK(p.octaves == 8 && p.gain == 0.5f && p.lacunarity == 2.0f && p.noise == K_NOISE_GRADIENT && p.flags == 0);
    CHECK(g.store.channel_types[0] == EXRIO_FLOAT && !strcmp(g.store.channel_names[0], "fbm.Y"));
    CHECK(strstr(s.json, "\"octaves\":8,") && strstr(s.json, "\"hurst\":1.0,") && strstr(s.json, "\"seed\":1,"));
    /* compact, numbers in their shortest round-trip form (0.08, not 0.080000000000000002) */
    CHECK(!strchr(s.json, '\n') && !strstr(s.json, ": ") && strstr(s.json, "\"rotation\":36.87,"));
    fb_scene_fini(&s);

    /* gain given directly; tileable and billow */
    p = params_of("{\"layers\": [{\"type\": \"fbm\", \"gain\": 0.3, \"tileable\": true, \"billow\": true}]}", &s, &g);
    CHECK(p.gain == 0.3f && p.flags == (K_FBM_TILEABLE | K_FBM_BILLOW));
    CHECK(strstr(s.json, "\"gain\"") && !strstr(s.json, "\"hurst\""));
    fb_scene_fini(&s);
}

/* Flags become the scene keys of the same name. */
static void test_flags(void)
{
    char *argv[] = {"--size",    "64x32", "--seed",     "5",      "--layer",       "foo",
                    "--octaves", "3",     "--hurst",    "0.25",   "--noise",       "sine",
                    "--offset",  "1,2",   "--tileable", "--half", "--compression", "none"};
    char *json = NULL;
    CHECK(fb_scene_from_flags("fbm", (int)(sizeof argv / sizeof argv[0]), argv, &json) == FB_OK);
    fb_scene s;
    fb_gen g;
    K_FbmParams p = params_of(json, &s, &g);
    CHECK(s.width == 64 && s.height == 32 && s.seed == 5 && s.compression == EXRIO_NONE);
    CHECK(!strcmp(s.layers[0].name, "foo") && s.layers[0].half);
    CHECK(p.octaves == 3 && fabsf(p.gain - 0.84089642f) < 1e-7f && p.noise == K_NOISE_SINE);
    CHECK(p.offset_x == 1.0f && p.offset_y == 2.0f && p.flags == K_FBM_TILEABLE);
    fb_scene_fini(&s);
    free(json);

    char *bad[] = {"--octaves"};
    CHECK(fb_scene_from_flags("fbm", 1, bad, &json) == FB_ERR_USAGE);
    char *unknown[] = {"--nope", "1"};
    CHECK(fb_scene_from_flags("fbm", 2, unknown, &json) == FB_ERR_USAGE);
    CHECK(fb_scene_flag_arity("fbm", "tileable") == 0 && fb_scene_flag_arity("fbm", "octaves") == 1 &&
          fb_scene_flag_arity("fbm", "size") == 1 && fb_scene_flag_arity("fbm", "nope") == -1);
}

/* The stored scene is canonical: a file and the equivalent flags store the same text. */
static void test_canonical(void)
{
    fb_scene a, b;
    CHECK(fb_scene_parse("{\"layers\": [{\"octaves\": 3, \"type\": \"fbm\"}], \"size\": [64, 32]}", "x.json", &a) ==
          FB_OK);
    char *argv[] = {"--size", "64x32", "--octaves", "3"};
    char *json = NULL;
    CHECK(fb_scene_from_flags("fbm", 4, argv, &json) == FB_OK);
    CHECK(fb_scene_parse(json, NULL, &b) == FB_OK);
    CHECK(a.json && b.json && !strcmp(a.json, b.json));
    /* and it parses back to itself */
    fb_scene c;
    CHECK(fb_scene_parse(a.json, "stored", &c) == FB_OK && !strcmp(c.json, a.json));
    fb_scene_fini(&a);
    fb_scene_fini(&b);
    fb_scene_fini(&c);
    free(json);
}

/* Every julia key reaches what it names: the kernel block, the colour and turbulence parameters at
 * the head of the input buffer (K_SkyColour at 0, K_FbmParams at 48: asserted in host/gen/julia/layer.c), the
 * palette table, the specialization constants and the channel types. */
static void test_julia_keys(void)
{
    const char *json =
        "{\"size\": [300, 100], \"seed\": 8, \"layers\": [{\"type\": \"julia\", \"name\": \"night\", \"mapping\": "
        "\"polar\", \"scale\": [2, 1], \"radius\": 1.25, \"center\": [0.5, -0.25], \"rotation\": 90, \"alpha\": "
        "[-0.3, 0.1], \"c\": [-0.4, 0.6], \"max-iter\": 777, \"bailout\": 4, \"turbulence\": 0.2, "
        "\"turbulence-hurst\": "
        "0.5, \"turbulence-octaves\": 3, \"turbulence-frequency\": 5, \"samples\": 6, \"stops\": [[0, 0, 0, 0], [1, 1, "
        "0.5, 0.25]], \"period\": 8, \"palette-offset\": 0.5, \"brightness\": 2, \"gamma\": 2.2, \"density\": 3, "
        "\"density-count\": 16, \"inside-color\": [0.1, 0.2, 0.3], \"half\": false}]}";
    fb_scene s;
    CHECK(fb_scene_parse(json, NULL, &s) == FB_OK);
    fb_gen g;
    CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
    K_JuliaParams p;
    memcpy(&p, g.params, sizeof p);
    CHECK(p.mapping == K_JULIA_POLAR && p.max_iter == 777 && p.bailout2 == 16.0f);
    CHECK(p.scale_u == 2.0f && p.scale_v == 1.0f && p.radius == 1.25f);
    CHECK(p.center_re == 0.5f && p.center_im == -0.25f);
    CHECK(fabsf(p.rot_c) < 1e-7f && fabsf(p.rot_s - 1.0f) < 1e-7f);
    CHECK(p.a_re == -0.3f && p.a_im == 0.1f && p.c_re == -0.4f && p.c_im == 0.6f);
    CHECK(p.lambda == 0.2f && fabsf(p.turb_norm - 1.0f / (1.0f + 0.70710678f + 0.5f)) < 1e-6f);
    const K_SkyColour *c = g.compute.shader.input;
    K_FbmParams t;
    memcpy(&t, (const char *)g.compute.shader.input + 48, sizeof t);
    CHECK(c->inv_period == 0.125f && c->offset == 0.5f && c->brightness == 2.0f && c->gamma == 2.2f);
    CHECK(c->density == 3.0f && c->inv_n_ref == 1.0f / 16.0f && c->samples == 6 && c->seed == 8);
    CHECK(c->inside_r == 0.1f && c->inside_g == 0.2f && c->inside_b == 0.3f);
    CHECK(t.octaves == 3 && fabsf(t.gain - 0.70710678f) < 1e-7f && t.freq_x == 5.0f && t.flags == K_FBM_TILEABLE);
    CHECK(t.seed == 8 && t.width == 300 && t.inv_freq_x == 0.2f);
    /* the gradient's last stop is the table's last entry */
    const float *last = (const float *)((const char *)g.compute.shader.input + 144) + 4 * (K_PALETTE_SIZE - 1);
    CHECK(last[0] == 1.0f && last[1] == 0.5f && last[2] == 0.25f);
    CHECK(g.compute.shader.nspec == 6 && g.compute.shader.spec[0] == K_JULIA_POLAR && g.compute.shader.spec[1] == 1 &&
          g.compute.shader.spec[2] == 6 && g.compute.shader.spec[3] == 3);
    CHECK(g.compute.shader.spec[4] == 127 && g.compute.nkernel == 7 &&
          g.compute.shader.per_invocation == 2); /* every channel by default */
    CHECK(g.compute.shader.spec[5] == 1);        /* width 300: even, each invocation's pair stored as one vec2 */
    CHECK(g.store.nchannels == 7 && !strcmp(g.store.channel_names[0], "night.iter") &&
          g.store.channel_types[0] == EXRIO_UINT);
    CHECK(!strcmp(g.store.channel_names[4], "night.R") && g.store.channel_types[4] == EXRIO_FLOAT); /* half: false */
    fb_gen_fini(&g);
    fb_scene_fini(&s);

    /* defaults: square-pixel scale from the size, night palette, half colour, no turbulence */
    CHECK(fb_scene_parse("{\"size\": [300, 100], \"layers\": [{\"type\": \"julia\"}]}", NULL, &s) == FB_OK);
    CHECK(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
    memcpy(&p, g.params, sizeof p);
    CHECK(p.scale_u == 3.0f && p.scale_v == 1.0f && p.mapping == K_JULIA_RECT && p.max_iter == 256);
    CHECK(p.c_re == -0.8f && p.c_im == 0.156f && p.lambda == 0.0f && g.compute.shader.spec[1] == 0 &&
          g.compute.shader.spec[2] == 1);
    CHECK(g.store.channel_types[4] == EXRIO_HALF && !strcmp(g.store.channel_names[0], "sky.iter"));
    fb_gen_fini(&g);
    fb_scene_fini(&s);
}

/* --set: values by their form, list elements by index or (default) layer name, objects created on the
 * way, later overrides win; and the default scene's layers are the ones the README promises. */
static void test_sets(void)
{
    fb_scene s;
    const char *base = "{\"size\": [64, 32], \"layers\": [{\"type\": \"fbm\"}, {\"type\": \"julia\"}]}";
    const char *sets[] = {"size=300x100",           "seed=12",
                          "layers.fbm.octaves=3",   "layers.sky.c=-0.5,0.25",
                          "layers.1.palette=ember", "layers.0.hurst=0.25",
                          "layers.fbm.hurst=0.75",  "compression=piz"};
    CHECK(fb_scene_parse_sets(base, "t", sets, 8, &s) == FB_OK);
    CHECK(s.width == 300 && s.height == 100 && s.seed == 12 && s.compression == EXRIO_PIZ);
    CHECK(P(fb_fbm_params, s.layers[0])->octaves == 3 &&
          P(fb_fbm_params, s.layers[0])->hurst == 0.75); /* the later override wins */
    CHECK(P(fb_julia_params, s.layers[1])->c[0] == -0.5 && P(fb_julia_params, s.layers[1])->c[1] == 0.25);
    CHECK(strstr(s.json, "\"ember\"") != NULL);
    fb_scene_fini(&s);
    /* a string that looks like nothing else stays a string; a nested object is created */
    const char *cond[] = {"layers.0.condensation.preset=tree", "layers.0.maps=[[0.75,0,0,0.75,0.25,0]]"};
    CHECK(fb_scene_parse_sets("{\"layers\": [{\"type\": \"ifs\"}]}", "t", cond, 2, &s) == FB_OK);
    CHECK(P(fb_ifs_params, s.layers[0])->has_cond && P(fb_ifs_params, s.layers[0])->cond_lsys);
    fb_scene_fini(&s);
    const char *bad[] = {"layers.fbm.octaves=many"};
    CHECK(fb_scene_parse_sets(base, "t", bad, 1, &s) != FB_OK);

    /* the showcase: the fBm detail behind a polar, warped, turbulent Julia sky; a terrain from inline
     * points, smooth, lit and coloured; the masks; the plant population in front */
    CHECK(fb_scene_parse(fb_scene_default_json(), "(default)", &s) == FB_OK);
    static const char *const names[7] = {"detail", "sky", "terrain", "ground", "snow", "gentle", "plants"};
    CHECK(s.nlayers == 7);
    for (int i = 0; i < 7 && i < s.nlayers; i++) CHECKF(!strcmp(s.layers[i].name, names[i]), "layer %d", i);
    CHECK(s.layers[0].cls == &fb_gen_fbm && s.layers[3].cls == &fb_gen_op && s.layers[4].cls == &fb_gen_op &&
          s.layers[5].cls == &fb_gen_op);
    CHECK(s.layers[1].cls == &fb_gen_julia && P(fb_julia_params, s.layers[1])->mapping == K_JULIA_POLAR &&
          P(fb_julia_params, s.layers[1])->turbulence > 0 &&
          (P(fb_julia_params, s.layers[1])->alpha[0] != 0 || P(fb_julia_params, s.layers[1])->alpha[1] != 0));
    CHECK(s.layers[2].cls == &fb_gen_terrain && P(fb_terrain_layer_params, s.layers[2])->points_inline &&
          P(fb_terrain_layer_params, s.layers[2])->smooth && P(fb_terrain_layer_params, s.layers[2])->relief.colour);
    CHECK(s.layers[6].cls == &fb_gen_ifs && P(fb_ifs_params, s.layers[6])->has_cond);
    fb_scene_fini(&s);
}

static char g_last_error[1024];

static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR) snprintf(g_last_error, sizeof g_last_error, "%s", msg);
}

/* The declaration check refuses a key nobody reads, a field its values do not fit, and one outside the
 * parameters; a table of fields fills them from a scene's values. */
typedef struct decl_params {
    double x;
    int n;
    bool b;
    double v[2];
    char s[8];
    unsigned bits;
} decl_params;

static void test_declared(void)
{
    char why[256];
    const fb_keyspec good[] = {
        {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "t", FB_CORE},
        {"x", FB_K_NUM, 0, 10, false, NULL, "2.5", "x", FB_FIELD(decl_params, x)},
        {"n", FB_K_INT, 0, 10, false, NULL, NULL, "n", FB_FIELD(decl_params, n)},
        {"b", FB_K_ENUM, 0, 0, false, "off|on", NULL, "b", FB_FIELD(decl_params, b)},
        {"v", FB_K_VEC2, -9, 9, false, NULL, NULL, "v", FB_FIELD(decl_params, v)},
        {"s", FB_K_STRING, 0, 0, false, NULL, NULL, "s", FB_FIELD(decl_params, s)},
        {"bits", FB_K_NAMES, 0, 0, false, "a|b|c", NULL, "bits", FB_FIELD(decl_params, bits)},
    };
    CHECKF(fb_schema_declared(good, FB_NKEYS(good), sizeof(decl_params), why, sizeof why), "%s", why);
    const fb_keyspec unread[] = {{"x", FB_K_NUM, 0, 10, false, NULL, NULL, "x"}};
    CHECK(!fb_schema_declared(unread, 1, sizeof(decl_params), why, sizeof why) && strstr(why, "\"x\""));
    const fb_keyspec misfit[] = {{"v", FB_K_VEC2, 0, 10, false, NULL, NULL, "v", FB_FIELD(decl_params, x)}};
    CHECK(!fb_schema_declared(misfit, 1, sizeof(decl_params), why, sizeof why) && strstr(why, "do not fit"));
    CHECK(!fb_schema_declared(good, FB_NKEYS(good), offsetof(decl_params, bits), why, sizeof why) &&
          strstr(why, "outside"));
    fb_vctx v = {.origin = "decl", .text = ""};
    json_t *obj = json_pack("{sis[ff]sssss[ss]}", "n", 7, "v", -1.5, 3.0, "b", "on", "s", "abc", "bits", "c", "a");
    decl_params p = {.n = -1};
    CHECK(fb_schema_check(&v, "", obj, good, FB_NKEYS(good), "a test", &p) == FB_OK);
    CHECK(p.x == 2.5 && p.n == 7 && p.b && p.v[0] == -1.5 && p.v[1] == 3.0 && !strcmp(p.s, "abc") && p.bits == 5u);
    json_object_set_new(obj, "s", json_string("12345678")); /* no room for it in s[8] */
    fb_log_set_sink(sink, NULL);
    CHECK(fb_schema_check(&v, "", obj, good, FB_NKEYS(good), "a test", &p) == FB_ERR_INPUT);
    CHECKF(strstr(g_last_error, "s: longer than 7 characters"), "%s", g_last_error);
    fb_log_set_sink(NULL, NULL);
    json_decref(obj);
}

/* The registry: every generator is found by its name, its table starts and ends like the others,
 * its flags are distinct, every default is a valid value of its own key, and its parameters fit. */
static void test_registry(void)
{
    int n = 0;
    fb_vctx v = {.origin = "registry", .text = ""};
    for (int i = 0; fb_gen_list[i]; i++, n++) {
        const fb_gen_class *c = fb_gen_list[i];
        CHECKF(fb_gen_find(c->name) == c, "%s: found by name", c->name);
        CHECKF(c->parse && c->init && c->keys && c->nkeys >= 4 && c->what, "%s: complete", c->name);
        CHECKF(c->params_size > 0, "%s: has parameters", c->name);
        char why[256] = "";
        CHECKF(fb_schema_declared(c->keys, c->nkeys, c->params_size, why, sizeof why), "%s: every key is read: %s",
               c->name, why);
        CHECKF(!strcmp(c->keys[0].key, "type") && !strcmp(c->keys[1].key, "name") &&
                   !strcmp(c->keys[c->nkeys - 2].key, "half") && !strcmp(c->keys[c->nkeys - 1].key, "compression"),
               "%s: type, name first; half, compression last", c->name);
        for (int k = 0; k < c->nkeys; k++) {
            const fb_keyspec *a = &c->keys[k];
            const char *fa = a->flag ? a->flag : !strcmp(a->key, "name") ? "layer" : a->key;
            for (int m = k + 1; m < c->nkeys; m++) {
                const fb_keyspec *b = &c->keys[m];
                const char *fb = b->flag ? b->flag : !strcmp(b->key, "name") ? "layer" : b->key;
                CHECKF(strcmp(a->key, b->key) && strcmp(fa, fb), "%s: keys %s and %s are distinct, as flags too",
                       c->name, a->key, b->key);
            }
            if (!a->def) continue;
            json_t *d = json_loads(a->def, JSON_DECODE_ANY, NULL);
            CHECKF(d && fb_schema_check_value(&v, a->key, a, d) == FB_OK, "%s.%s: default %s is valid", c->name, a->key,
                   a->def);
            json_decref(d);
        }
    }
    CHECK(n >= 7 && fb_gen_find("nope") == NULL);
    /* an unknown type lists every generator */
    fb_scene s;
    fb_log_set_sink(sink, NULL);
    CHECK(fb_scene_parse("{\"layers\": [{\"type\": \"nope\"}]}", "t.json", &s) == FB_ERR_INPUT);
    for (int i = 0; fb_gen_list[i]; i++)
        CHECKF(strstr(g_last_error, fb_gen_list[i]->name), "%s listed", fb_gen_list[i]->name);
}

/* fb_json_number: the shortest text that strtod reads back as the same double, a real kept real */
static void json_numbers(void)
{
    static const struct {
        double v;
        const char *want;
    } cases[] = {{0.1, "0.1"},
                 {-0.3, "-0.3"},
                 {1.0, "1.0"},
                 {-0.0, "-0.0"},
                 {36.87, "36.87"},
                 {1e300, "1e+300"},
                 {5e-324, "5e-324"},
                 {0.2f, "0.20000000298023224"},
                 {123456789.0, "123456789.0"},
                 {2.5e-7, "2.5e-07"},
                 {NAN, "null"},
                 {INFINITY, "null"}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char out[40];
        fb_json_number(cases[i].v, out);
        CHECKF(!strcmp(out, cases[i].want), "%.17g: \"%s\", wanted \"%s\"", cases[i].v, out, cases[i].want);
        if (isfinite(cases[i].v)) CHECK(strtod(out, NULL) == cases[i].v);
    }
    json_t *j = json_loads(
        "{\"b\": [1, 2.5, \"x\\\"y\"], \"a\": {\"c\": null, \"d\": true}, \"e\": -0.29999999999999999}", 0, NULL);
    char *t = fb_json_dumps(j, 0);
    CHECKF(t && !strcmp(t, "{\"a\":{\"c\":null,\"d\":true},\"b\":[1,2.5,\"x\\\"y\"],\"e\":-0.3}"), "%s", t);
    free(t);
    t = fb_json_dumps(j, 2);
    CHECKF(t && !strcmp(t, "{\n  \"a\": {\n    \"c\": null,\n    \"d\": true\n  },\n  \"b\": [\n    1,\n    2.5,\n    "
                           "\"x\\\"y\"\n  ],\n  \"e\": -0.3\n}"),
           "%s", t);
    free(t);
    json_decref(j);
}

/* The nearest environment-map size by search (the message must name it). */
static void nearest_env(bool latlong, int w, int h, char *out, size_t size)
{
    long best = -1;
    double bd = 1e300;
    for (long n = 1; n <= 20000; n++) {
        double a = latlong ? w - 2.0 * n : w - (double)n, b = latlong ? h - (double)n : h - 6.0 * n;
        if (a * a + b * b < bd) bd = a * a + b * b, best = n;
    }
    snprintf(out, size, "the nearest is %ld x %ld", latlong ? 2 * best : best, latlong ? best : 6 * best);
}

/* Environment maps: the mapping key sets the layer's and the file's envmap; op layers take their
 * inputs'; layers that disagree, an op over both kinds, and a wrong size are refused, naming the
 * key and (for the size) the nearest valid one. */
static void test_envmaps(void)
{
    fb_scene s;
    char want[64], json[512];
    fb_log_set_sink(sink, NULL);
    CHECK(
        fb_scene_parse("{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"mapping\": \"latlong\"}, {\"type\": "
                       "\"op\", \"op\": \"remap\", \"inputs\": [\"sky.n\"], \"from\": [0, 10]}]}",
                       "t.json", &s) == FB_OK);
    CHECK(s.envmap == EXRIO_ENVMAP_LATLONG && s.layers[0].envmap == EXRIO_ENVMAP_LATLONG &&
          s.layers[1].envmap == EXRIO_ENVMAP_LATLONG);
    fb_scene_fini(&s);
    CHECK(fb_scene_parse("{\"size\": [16, 96], \"layers\": [{\"type\": \"julia\", \"mapping\": \"cube\"}]}", "t.json",
                         &s) == FB_OK);
    CHECK(s.envmap == EXRIO_ENVMAP_CUBE);
    fb_scene_fini(&s);
    CHECK(fb_scene_parse("{\"size\": [64, 40], \"layers\": [{\"type\": \"julia\", \"mapping\": \"polar\"}]}", "t.json",
                         &s) == FB_OK);
    CHECK(s.envmap == EXRIO_ENVMAP_NONE);
    fb_scene_fini(&s);
    static const int sizes[][3] = {{1, 100, 60}, {1, 64, 33}, {1, 7, 1}, {0, 20, 100}, {0, 16, 97}, {0, 100, 10}};
    for (int k = 0; k < 6; k++) {
        bool ll = sizes[k][0];
        snprintf(json, sizeof json, "{\"size\": [%d, %d], \"layers\": [{\"type\": \"julia\", \"mapping\": \"%s\"}]}",
                 sizes[k][1], sizes[k][2], ll ? "latlong" : "cube");
        g_last_error[0] = 0;
        CHECKF(fb_scene_parse(json, "t.json", &s) == FB_ERR_INPUT, "%s refused", json);
        nearest_env(ll, sizes[k][1], sizes[k][2], want, sizeof want);
        CHECKF(strstr(g_last_error, want) && strstr(g_last_error, "size") &&
                   strstr(g_last_error, ll ? "2N x N" : "N x 6N"),
               "%s: \"%s\" names %s", json, g_last_error, want);
    }
    g_last_error[0] = 0;
    CHECK(
        fb_scene_parse("{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"mapping\": \"latlong\"}, {\"type\": "
                       "\"fbm\"}]}",
                       "t.json", &s) == FB_ERR_INPUT);
    CHECKF(strstr(g_last_error, "layers[1]") && strstr(g_last_error, "separate files"), "mixed: %s", g_last_error);
    g_last_error[0] = 0;
    CHECK(fb_scene_parse("{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"mapping\": \"cube\"}, {\"type\": "
                         "\"julia\", \"name\": \"b\", \"mapping\": \"latlong\"}]}",
                         "t.json", &s) == FB_ERR_INPUT);
    CHECKF(strstr(g_last_error, "layers[1].mapping") && strstr(g_last_error, "lat-long"), "cube+latlong: %s",
           g_last_error);
    g_last_error[0] = 0;
    CHECK(fb_scene_parse(
              "{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"mapping\": \"latlong\"}, {\"type\": "
              "\"fbm\", \"name\": \"f\"}, {\"type\": \"op\", \"op\": \"add\", \"inputs\": [\"sky.n\", \"f\"]}]}",
              "t.json", &s) == FB_ERR_INPUT);
    CHECKF(strstr(g_last_error, "inputs[1]") && strstr(g_last_error, "combines"), "op over both: %s", g_last_error);
    g_last_error[0] = 0;
    CHECK(fb_scene_parse("{\"size\": [64, 32], \"layers\": [{\"type\": \"julia\", \"mapping\": \"latlong\", "
                         "\"precision\": \"double\"}]}",
                         "t.json", &s) == FB_ERR_INPUT);
    CHECKF(strstr(g_last_error, "precision"), "double: %s", g_last_error);
    fb_log_set_sink(NULL, NULL);
}

int main(void)
{
    test_declared();
    json_numbers();
    test_registry();
    test_sets();
    test_julia_keys();
    test_keys();
    test_flags();
    test_canonical();
    test_envmaps();
    TEST_REPORT();
}
