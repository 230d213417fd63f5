/*
 * Scenes and flags reach the kernel: every fBm key and flag changes the parameters it names
 * (a flag parsed and ignored would fail here), defaults are filled in, and the stored scene is
 * canonical.
 */
#include "../kernels/fbm.h"
#include "gen.h"
#include "scene.h"

#include "testhelp.h"

#include <math.h>
#include <string.h>

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
    CHECK(g.nchannels == 1 && !strcmp(g.channel_names[0], "h.Y") && g.channel_types[0] == EXRIO_HALF);
    CHECK(g.nspec == 2 && g.spec[0] == K_NOISE_CELLULAR_F2 && g.spec[1] == K_FBM_RIDGED);
    fb_scene_fini(&s);

    /* defaults, filled into the stored scene */
    p = params_of("{\"layers\": [{\"type\": \"fbm\"}]}", &s, &g);
    CHECK(s.width == 1024 && s.height == 1024 && s.seed == 1 && s.compression == EXRIO_ZIP);
    CHECK(p.octaves == 8 && p.gain == 0.5f && p.lacunarity == 2.0f && p.noise == K_NOISE_GRADIENT && p.flags == 0);
    CHECK(g.channel_types[0] == EXRIO_FLOAT && !strcmp(g.channel_names[0], "fbm.Y"));
    CHECK(strstr(s.json, "\"octaves\": 8") && strstr(s.json, "\"hurst\": 1.0") && strstr(s.json, "\"seed\": 1"));
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

int main(void)
{
    test_keys();
    test_flags();
    test_canonical();
    TEST_REPORT();
}
