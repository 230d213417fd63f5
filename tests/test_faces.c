/*
 * Engine face sets (render --cube-faces): a cube fBm bake's six Unity faces, read back, show at every
 * pixel the field at the direction the face's stated orientation gives (forward +Z, left +X, up +Y;
 * facing C with U up, the right is C x U; sides upright, the up face's top towards the back, the
 * down face's top towards the front): the faces tile the sphere, each edge shared with its
 * neighbour. The Source names hold the same faces; PNG faces are the colour's sRGB; the bake's own
 * file is unchanged by asking for faces; a bad pattern writes nothing.
 */
#include "bake.h"
#include "exrio.h"
#include "faces.h"
#include "kernels/fbm.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static char g_dir[] = "/tmp/fb-test-faces-XXXXXX";

static float *read_plane(const char *path, const char *channel, int *w, int *h)
{
    exrio_reader *r = NULL;
    if (exrio_open(path, &r)) return NULL;
    *w = exrio_width(r), *h = exrio_height(r);
    int c = exrio_find_channel(r, channel);
    float *px = c >= 0 ? malloc((size_t)*w * *h * 4) : NULL;
    void *planes[16] = {0};
    if (px) planes[c] = px;
    if (px && exrio_read_rows(r, 0, *h, planes)) free(px), px = NULL;
    exrio_close(&r);
    return px;
}

static fb_result bake(fb_engine *e, const char *json, const char *out, const char *faces)
{
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (rc) return rc;
    rc = fb_bake(e, &(fb_bake_desc){.scene = &s, .out = out, .cube_faces = faces, .strip_rows = 7}, NULL);
    fb_scene_fini(&s);
    return rc;
}

int main(void)
{
    enum { N = 24 };
    if (!mkdtemp(g_dir)) TEST_SKIP("no temporary folder");
    fb_engine cpu;
    CHECK(fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = 2}, &cpu) == FB_OK);
    const char *json = "{\"size\": [24, 144], \"seed\": 3, \"layers\": [{\"type\": \"fbm\", \"name\": \"f\", "
                       "\"mapping\": \"cube\", \"octaves\": 5}]}";
    char out[256], pat[256], plain[256];
    snprintf(out, sizeof out, "%s/cube.exr", g_dir);
    snprintf(plain, sizeof plain, "%s/plain.exr", g_dir);
    snprintf(pat, sizeof pat, "%s/sky{unity}.exr", g_dir);
    CHECK(bake(&cpu, json, out, pat) == FB_OK);
    CHECK(bake(&cpu, json, plain, NULL) == FB_OK);
    int w, h, w2, h2;
    float *a = read_plane(out, "f.Y", &w, &h), *b = read_plane(plain, "f.Y", &w2, &h2);
    CHECK(a && b && w == w2 && h == h2 && !memcmp(a, b, (size_t)w * h * 4)); /* the bake itself unchanged */
    free(a), free(b);

    /* the field the faces must show, from the kernel at a direction (the layer's own parameters) */
    fb_scene s;
    fb_gen g = {0};
    CHECK(fb_scene_parse(json, NULL, &s) == FB_OK && fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
    K_FbmParams fp;
    memcpy(&fp, g.params, sizeof fp);
    static const char *const names[6] = {"_front", "_back", "_left", "_right", "_up", "_down"};
    static const float C[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    static const float U[6][3] = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
    float *faces[6];
    for (int k = 0; k < 6; k++) {
        char path[300];
        snprintf(path, sizeof path, "%s/sky%s.exr", g_dir, names[k]);
        faces[k] = read_plane(path, "f.Y", &w, &h);
        CHECKF(faces[k] && w == N && h == N, "%s: a %d x %d face", path, N, N);
        if (!faces[k]) continue;
        float R[3] = {C[k][1] * U[k][2] - C[k][2] * U[k][1], C[k][2] * U[k][0] - C[k][0] * U[k][2],
                      C[k][0] * U[k][1] - C[k][1] * U[k][0]};
        double worst = 0;
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++) {
                float sx = 2.0f * i / (N - 1) - 1, ty = 2.0f * j / (N - 1) - 1;
                k_vec3 d = k_vec3(C[k][0] + sx * R[0] - ty * U[k][0], C[k][1] + sx * R[1] - ty * U[k][1],
                                  C[k][2] + sx * R[2] - ty * U[k][2]);
                worst = fmax(worst, fabs(faces[k][j * N + i] - k_fbm_dir(fp, d)));
            }
        CHECKF(worst < 1e-4, "face %s: %.3g from the field at its pixels' directions", names[k], worst);
    }
    /* neighbours share their edge (the same directions, from two faces of the bake: within rounding):
     * front's right column is right's left column, up's bottom row front's top row, down's top row
     * front's bottom row */
    if (faces[0] && faces[3] && faces[4] && faces[5]) {
        int bad = 0;
        for (int j = 0; j < N; j++) bad += fabsf(faces[0][j * N + N - 1] - faces[3][j * N]) > 1e-5f;
        for (int i = 0; i < N; i++) bad += fabsf(faces[4][(N - 1) * N + i] - faces[0][i]) > 1e-5f;
        for (int i = 0; i < N; i++) bad += fabsf(faces[5][i] - faces[0][(N - 1) * N + i]) > 1e-5f;
        CHECKF(bad == 0, "%d shared edge pixels differ", bad);
    }
    /* the Source names: the same faces */
    snprintf(pat, sizeof pat, "%s/src_{source}.exr", g_dir);
    CHECK(bake(&cpu, json, out, pat) == FB_OK);
    static const char *const src[6] = {"ft", "bk", "lf", "rt", "up", "dn"};
    for (int k = 0; k < 6; k++) {
        char path[300];
        snprintf(path, sizeof path, "%s/src_%s.exr", g_dir, src[k]);
        float *f = read_plane(path, "f.Y", &w, &h);
        CHECKF(f && faces[k] && !memcmp(f, faces[k], (size_t)N * N * 4), "%s: the Unity face %s", path, names[k]);
        free(f);
    }
    for (int k = 0; k < 6; k++) free(faces[k]);
    /* refused, nothing written: a lat-long scene, a pattern without a name, a PNG set without colour */
    snprintf(pat, sizeof pat, "%s/bad{unity}.exr", g_dir);
    CHECK(bake(&cpu, "{\"size\": [48, 24], \"layers\": [{\"type\": \"fbm\", \"mapping\": \"latlong\"}]}", out, pat) ==
          FB_ERR_USAGE);
    snprintf(pat, sizeof pat, "%s/bad.exr", g_dir);
    CHECK(bake(&cpu, json, out, pat) == FB_ERR_USAGE);
    snprintf(pat, sizeof pat, "%s/bad{source}.png", g_dir);
    CHECK(bake(&cpu, json, out, pat) == FB_ERR_USAGE);
    char path[300];
    struct stat st;
    snprintf(path, sizeof path, "%s/bad_front.exr", g_dir);
    CHECK(stat(path, &st) != 0);
    snprintf(path, sizeof path, "%s/badft.png", g_dir);
    CHECK(stat(path, &st) != 0);
    fb_gen_fini(&g);
    fb_scene_fini(&s);
    fb_engine_close(&cpu);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", g_dir);
    TEST_REPORT();
}
