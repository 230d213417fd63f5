/*
 * Engine face sets of a cube environment map: see faces.h. Each engine face is the view from the
 * cube's centre towards C with R to the right and U up; its pixel (i, j) (j down) is the direction
 * C + s R - t U, s and t in [-1, 1] from the face's edge pixels to its edges, as the cube's own
 * faces lie (ImfEnvmap.h: edge pixels on the cube's edges), so every engine face pixel is exactly one
 * pixel of one face of the bake: the set is the bake's faces turned and mirrored, nothing resampled.
 */
#include "faces.h"

#include "gen.h"
#include "kernels/envmap.h"
#include "output.h"
#include "preview.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct face_spec {
    const char *unity, *source;
    float c[3], r[3], u[3];
} face_spec;

/* Forward +Z, left +X, up +Y; right-handed, so facing +Z the viewer's right is -X. In the bake's
 * face order (+X, -X, +Y, -Y, +Z, -Z): face f of the bake is engine face f. */
static const face_spec k_faces[6] = {
    {"_left", "lf", {1, 0, 0}, {0, 0, 1}, {0, 1, 0}},    /* facing +X, forward on its right */
    {"_right", "rt", {-1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, /* facing -X */
    {"_up", "up", {0, 1, 0}, {-1, 0, 0}, {0, 0, -1}},    /* looking up, forward along its bottom edge */
    {"_down", "dn", {0, -1, 0}, {-1, 0, 0}, {0, 0, 1}},  /* looking down, forward along its top edge */
    {"_front", "ft", {0, 0, 1}, {-1, 0, 0}, {0, 1, 0}},  /* facing +Z */
    {"_back", "bk", {0, 0, -1}, {1, 0, 0}, {0, 1, 0}},   /* facing -Z */
};

struct fb_faces {
    fb_faces_desc d;
    char paths[6][FB_FACES_PATH];
    exrio_channel ch[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS];
    uint32_t *face; /* the bake's face being received: nchannels planes of n x n values */
    uint32_t *row;  /* one output row of every channel */
    int *src;       /* for the face being written: output pixel -> its pixel of the bake's face */
    uint8_t *rgb;   /* a PNG face */
};

fb_result fb_faces_paths(const char *pattern, char names[6][FB_FACES_PATH])
{
    const char *tok = strstr(pattern, "{unity}") ? "{unity}" : strstr(pattern, "{source}") ? "{source}" : NULL;
    size_t len = strlen(pattern);
    bool png = len >= 4 && !strcasecmp(pattern + len - 4, ".png"),
         exr = len >= 4 && !strcasecmp(pattern + len - 4, ".exr");
    if (!tok)
        return fb_fail(FB_ERR_USAGE,
                       "--cube-faces %s: the pattern needs {unity} (_front, _back, _left, _right, _up, _down) or "
                       "{source} (ft, bk, lf, rt, up, dn), e.g. sky{unity}.exr",
                       pattern);
    if (!png && !exr)
        return fb_fail(FB_ERR_USAGE, "--cube-faces %s: the faces are .exr (every channel) or .png (colour, LDR)",
                       pattern);
    const char *at = strstr(pattern, tok);
    if (strstr(at + 1, "{unity}") || strstr(at + 1, "{source}"))
        return fb_fail(FB_ERR_USAGE, "--cube-faces %s: one {unity} or {source} in the pattern", pattern);
    if (len + 8 >= FB_FACES_PATH) return fb_fail(FB_ERR_USAGE, "--cube-faces: the pattern is too long");
    for (int k = 0; k < 6; k++) {
        const char *name = !strcmp(tok, "{unity}") ? k_faces[k].unity : k_faces[k].source;
        snprintf(names[k], FB_FACES_PATH, "%.*s%s%s", (int)(at - pattern), pattern, name, at + strlen(tok));
    }
    return FB_OK;
}

uint64_t fb_faces_bytes(int n, int nchannels)
{
    return (uint64_t)n * n * (nchannels * 4u + sizeof(int) + 3) + (uint64_t)n * nchannels * 4u;
}

fb_result fb_faces_create(const fb_faces_desc *d, fb_faces **out)
{
    char names[6][FB_FACES_PATH];
    fb_result rc = fb_faces_paths(d->pattern, names);
    if (rc) return rc;
    size_t len = strlen(d->pattern);
    bool png = !strcasecmp(d->pattern + len - 4, ".png");
    if (png && d->rgb < 0)
        return fb_fail(FB_ERR_USAGE,
                       "--cube-faces %s: a PNG face set shows colour, and no layer has R, G, B: write .exr",
                       d->pattern);
    if (d->nchannels > (int)(sizeof((fb_faces *)0)->ch / sizeof(exrio_channel)))
        return fb_fail(FB_ERR_INTERNAL, "--cube-faces: too many channels");
    fb_faces *f = calloc(1, sizeof *f);
    if (!f) return fb_fail(FB_ERR_NOMEM, "out of memory");
    f->d = *d;
    size_t nn = (size_t)d->n * d->n;
    f->face = malloc(nn * d->nchannels * 4);
    f->row = malloc((size_t)d->n * d->nchannels * 4);
    f->src = malloc(nn * sizeof *f->src);
    f->rgb = png ? malloc(nn * 3) : NULL;
    if (!f->face || !f->row || !f->src || (png && !f->rgb)) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int c = 0; c < d->nchannels; c++) f->ch[c] = (exrio_channel){d->channels[c].name, d->channels[c].type, 0};
    for (int k = 0; k < 6 && !rc; k++) {
        memcpy(f->paths[k], names[k], FB_FACES_PATH);
        rc = fb_output_reserve(f->paths[k], "cube face");
    }
    if (rc) {
        fb_faces_destroy(&f);
        return rc;
    }
    *out = f;
    return FB_OK;
}

/* src[j n + i]: the pixel of the bake's face `face` that engine face k's pixel (i, j) shows. */
static void face_map(const fb_faces *f, int k, int face)
{
    int n = f->d.n;
    const face_spec *e = &k_faces[k];
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            float s = n > 1 ? 2.0f * i / (n - 1) - 1.0f : 0.0f, t = n > 1 ? 2.0f * j / (n - 1) - 1.0f : 0.0f;
            k_vec3 dir = k_vec3(e->c[0] + s * e->r[0] - t * e->u[0], e->c[1] + s * e->r[1] - t * e->u[1],
                                e->c[2] + s * e->r[2] - t * e->u[2]);
            k_vec2 p = k_env_cube_pos_face(dir, (uint)face, (uint)n);
            long px = lroundf(p.x), py = lroundf(p.y) - (long)face * n;
            px = px < 0 ? 0 : px >= n ? n - 1 : px;
            py = py < 0 ? 0 : py >= n ? n - 1 : py;
            f->src[(size_t)j * n + i] = (int)(py * n + px);
        }
}

static fb_result write_exr(fb_faces *f, int k)
{
    int n = f->d.n, nc = f->d.nchannels;
    size_t nn = (size_t)n * n;
    exrio_writer *w = NULL;
    fb_result rc = exrio_writer_create(&(exrio_writer_desc){.path = f->paths[k],
                                                            .what = "cube face",
                                                            .width = n,
                                                            .height = n,
                                                            .compression = f->d.compression,
                                                            .channels = f->ch,
                                                            .nchannels = nc,
                                                            .threads = f->d.threads,
                                                            .zip_level = f->d.zip_level},
                                       &w);
    const void *planes[FB_MAX_LAYERS * FB_GEN_MAX_CHANNELS];
    for (int c = 0; c < nc; c++) planes[c] = f->row + (size_t)c * n;
    for (int j = 0; j < n && !rc; j++) {
        for (int c = 0; c < nc; c++)
            for (int i = 0; i < n; i++) f->row[(size_t)c * n + i] = f->face[c * nn + f->src[(size_t)j * n + i]];
        rc = exrio_writer_rows(w, j, 1, planes);
    }
    if (!rc) rc = exrio_writer_finish(&w);
    exrio_writer_abort(&w);
    return rc;
}

static fb_result write_png(fb_faces *f, int k)
{
    int n = f->d.n;
    size_t nn = (size_t)n * n;
    for (size_t p = 0; p < nn; p++)
        for (int c = 0; c < 3; c++) {
            float v;
            memcpy(&v, &f->face[(f->d.rgb + c) * nn + f->src[p]], 4);
            f->rgb[p * 3 + c] = fb_srgb8(v);
        }
    return fb_png_write_rgb(f->paths[k], "cube face", n, n, f->rgb);
}

fb_result fb_faces_rows(fb_faces *f, int y0, int n, const void *const *planes, int stride)
{
    int N = f->d.n, nc = f->d.nchannels;
    size_t nn = (size_t)N * N;
    for (int r = 0; r < n; r++) {
        int y = y0 + r, face = y / N, local = y % N;
        for (int c = 0; c < nc; c++)
            memcpy(f->face + c * nn + (size_t)local * N, (const uint32_t *)planes[c] + (size_t)r * stride,
                   (size_t)N * 4);
        if (local != N - 1) continue;
        face_map(f, face, face);
        fb_result rc = f->rgb ? write_png(f, face) : write_exr(f, face);
        if (rc) return rc;
    }
    return FB_OK;
}

void fb_faces_destroy(fb_faces **f)
{
    if (!f || !*f) return;
    free((*f)->face);
    free((*f)->row);
    free((*f)->src);
    free((*f)->rgb);
    free(*f);
    *f = NULL;
}
