/*
 * Plant instances of an ifs population (docs/plants.md, "Plant instances"): the plants enumerated
 * from the maps, placed on a height layer, written as PLY or CSV through the output transaction.
 */
#include "instances.h"
#include "output.h"

#include "kernels/hash.h"

#include <errno.h>
#include <math.h>
#include <strings.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the population ----------------------------------------------------------------------------- */

/* A composed map W = w_i1 o ... o w_ik: x' = a x + b y + e, y' = c x + d y + f. */
typedef struct word {
    double a, b, c, d, e, f;
    int generation, next; /* next: the child to visit (the index of the map appended) */
} word;

/* Words visited at most (plants in and out of the frame, and their extensions). */
#define MAX_VISITS (4ull * FB_IFS_MAX_PLANTS)

static word extend(const word *w, const fb_ifs_map *m)
{
    return (word){w->a * m->a + w->b * m->c,
                  w->a * m->b + w->b * m->d,
                  w->c * m->a + w->d * m->c,
                  w->c * m->b + w->d * m->d,
                  w->a * m->e + w->b * m->f + w->e,
                  w->c * m->e + w->d * m->f + w->f,
                  w->generation + 1,
                  0};
}

static double word_size(const word *w, double cond_size)
{
    return cond_size * sqrt(fabs(w->a * w->d - w->b * w->c));
}

static bool in_frame(const word *w, const double frame[4])
{
    return w->e >= frame[0] && w->e <= frame[1] && w->f >= frame[2] && w->f <= frame[3];
}

static fb_result push(void **arr, size_t *cap, size_t n, size_t elem)
{
    if (n < *cap) return FB_OK;
    size_t nc = *cap ? 2 * *cap : 64;
    void *p = realloc(*arr, nc * elem);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    *arr = p, *cap = nc;
    return FB_OK;
}

fb_result fb_ifs_plants(const fb_ifs *maps, double cond_size, const double frame[4], double min_size,
                        fb_ifs_plant **out, size_t *n)
{
    word *stack = NULL;
    fb_ifs_plant *plants = NULL;
    size_t depth = 0, cap = 0, np = 0, pcap = 0;
    uint64_t visits = 0;
    fb_result rc = push((void **)&stack, &cap, 0, sizeof *stack);
    if (!rc) stack[depth++] = (word){1, 0, 0, 1, 0, 0, 0, 0};
    bool fresh = true; /* the top of the stack has not been emitted yet */
    while (!rc && depth) {
        word *w = &stack[depth - 1];
        if (fresh) {
            fresh = false;
            if (++visits > MAX_VISITS) {
                rc = fb_fail(FB_ERR_INPUT,
                             "the population has more than %llu plants taller than instances-min-size; raise it",
                             (unsigned long long)MAX_VISITS);
                break;
            }
            if (in_frame(w, frame)) {
                if (np == FB_IFS_MAX_PLANTS) {
                    rc = fb_fail(FB_ERR_INPUT,
                                 "the population has more than %u plants in the frame taller than "
                                 "instances-min-size; raise it",
                                 FB_IFS_MAX_PLANTS);
                    break;
                }
                if ((rc = push((void **)&plants, &pcap, np, sizeof *plants))) break;
                plants[np++] = (fb_ifs_plant){w->e, w->f, word_size(w, cond_size), w->generation};
            }
        }
        if (w->next >= maps->n) {
            depth--;
            continue;
        }
        word child = extend(w, &maps->m[w->next++]);
        if (!(word_size(&child, cond_size) >= min_size)) continue; /* it and every extension: smaller */
        if ((rc = push((void **)&stack, &cap, depth, sizeof *stack))) break;
        stack[depth++] = child;
        fresh = true;
    }
    free(stack);
    if (rc) {
        free(plants);
        return rc;
    }
    *out = plants, *n = np;
    return FB_OK;
}

double fb_ifs_cond_extent(const fb_ifs *cond, uint32_t seed)
{
    double p[FB_IFS_MAX_MAPS], x = 0, y = 0, x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    fb_ifs_probabilities(cond, p);
    const uint32_t skip = (uint32_t)fb_ifs_auto_skip(cond), steps = 1u << 18;
    for (uint32_t t = 0; t < skip + steps; t++) {
        double r = k_u01(k_hash3(seed, 0x636f6e64u /* "cond" */, t)), cum = 0;
        int k = 0;
        while (k < cond->n - 1 && r >= (cum += p[k])) k++;
        const fb_ifs_map *m = &cond->m[k];
        double nx = m->a * x + m->b * y + m->e, ny = m->c * x + m->d * y + m->f;
        x = nx, y = ny;
        if (t < skip) continue;
        x0 = fmin(x0, x), x1 = fmax(x1, x), y0 = fmin(y0, y), y1 = fmax(y1, y);
    }
    return fmax(x1 - x0, y1 - y0);
}

/* ---- placement ---------------------------------------------------------------------------------- */

typedef struct instance {
    float P[3], N[3], pscale, orient[4];
    int32_t id, variant;
} instance;

/* Heights of the source's plane on rows r and r + 1 (clamped to the image), from its native rows. */
typedef struct rows2 {
    const fb_ifs_place *pl;
    int r; /* the first row held, or INT32_MIN */
    float *buf[FB_GEN_MAX_CHANNELS];
} rows2;

static fb_result rows_at(rows2 *rw, int r)
{
    const fb_ifs_place *pl = rw->pl;
    if (rw->r == r) return FB_OK;
    int np = fb_gen_nplanes(pl->src), n = pl->height > 1 ? 2 : 1,
        y0 = r < 0                ? 0
             : r > pl->height - n ? pl->height - n
                                  : r;
    for (int k = 0; k < np; k++)
        if (!rw->buf[k] && !(rw->buf[k] = malloc((size_t)pl->width * 2 * sizeof(float))))
            return fb_fail(FB_ERR_NOMEM, "out of memory");
    void *planes[FB_GEN_MAX_CHANNELS] = {0};
    for (int k = 0; k < np; k++) planes[k] = rw->buf[k];
    pl->src->compute.native_rows(pl->src, y0, n, planes);
    rw->r = r;
    return FB_OK;
}

/* The height at row ry (clamped) and column cx (clamped) of what rows_at(r) holds. */
static double height_at(const rows2 *rw, int ry, int cx)
{
    const fb_ifs_place *pl = rw->pl;
    int n = pl->height > 1 ? 2 : 1, y0 = rw->r < 0 ? 0 : rw->r > pl->height - n ? pl->height - n : rw->r;
    ry = ry < 0 ? 0 : ry >= pl->height ? pl->height - 1 : ry;
    cx = cx < 0 ? 0 : cx >= pl->width ? pl->width - 1 : cx;
    return rw->buf[pl->plane][(size_t)(ry - y0) * pl->width + cx];
}

/* Bilinear height and its derivatives per pixel at pixel coordinates (u, v) (pixel i covers [i, i + 1),
 * row 0 at the top), between the four nearest pixel centres. */
static fb_result surface_at(rows2 *rw, double u, double v, double *h, double *hu, double *hv)
{
    double fu = u - 0.5, fv = v - 0.5;
    int i = (int)floor(fu), j = (int)floor(fv);
    double s = fu - i, t = fv - j;
    fb_result rc = rows_at(rw, j);
    if (rc) return rc;
    double h00 = height_at(rw, j, i), h10 = height_at(rw, j, i + 1), h01 = height_at(rw, j + 1, i),
           h11 = height_at(rw, j + 1, i + 1);
    *h = (1 - t) * ((1 - s) * h00 + s * h10) + t * ((1 - s) * h01 + s * h11);
    *hu = (1 - t) * (h10 - h00) + t * (h11 - h01);
    *hv = (1 - s) * (h01 - h00) + s * (h11 - h10);
    return FB_OK;
}

typedef struct by_row {
    int row;
    size_t idx;
} by_row;

static int cmp_row(const void *a, const void *b)
{
    const by_row *x = a, *y = b;
    return x->row != y->row ? (x->row > y->row) - (x->row < y->row) : (x->idx > y->idx) - (x->idx < y->idx);
}

/* One plant's instance: world X (east), Y (north), height and world normal, in the output's axes. */
static void fill(const fb_ifs_place *pl, size_t id, const fb_ifs_plant *p, double X, double Y, double h,
                 const double nw[3], double scale, instance *o)
{
    double theta = k_u01(k_hash3(pl->seed, 0x706c6e74u /* "plnt" */, (uint32_t)id)) * 2 * M_PI;
    double sh = sin(theta / 2), ch = cos(theta / 2);
    bool y_up = pl->up == 'y';
    double P[3] = {X, y_up ? h : Y, y_up ? -Y : h}, N[3] = {nw[0], y_up ? nw[2] : nw[1], y_up ? -nw[1] : nw[2]};
    for (int k = 0; k < 3; k++) o->P[k] = (float)P[k] + 0.0f, o->N[k] = (float)N[k] + 0.0f; /* no -0 */
    o->pscale = (float)(p->size * scale);
    o->orient[0] = 0, o->orient[1] = (float)(y_up ? sh : 0), o->orient[2] = (float)(y_up ? 0 : sh);
    o->orient[3] = (float)ch;
    o->id = (int32_t)id, o->variant = p->generation;
}

/* The mask plants keep away from, whole (its layer's native rows, band by band), or NULL with *rc. */
static float *read_mask(const fb_ifs_place *pl, fb_result *rc)
{
    const int band = 64, np = fb_gen_nplanes(pl->avoid);
    float *mask = malloc((size_t)pl->width * pl->height * sizeof *mask);
    void *planes[FB_GEN_MAX_CHANNELS] = {0};
    *rc = mask ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory for the instances' mask");
    for (int k = 0; k < np && !*rc; k++)
        if (fb_gen_plane_stored(pl->avoid, k) && !(planes[k] = malloc((size_t)pl->width * band * sizeof(float))))
            *rc = fb_fail(FB_ERR_NOMEM, "out of memory for the instances' mask");
    for (int y0 = 0; y0 < pl->height && !*rc; y0 += band) {
        int n = y0 + band <= pl->height ? band : pl->height - y0;
        pl->avoid->compute.native_rows(pl->avoid, y0, n, planes);
        memcpy(mask + (size_t)y0 * pl->width, planes[pl->avoid_plane], (size_t)n * pl->width * sizeof *mask);
    }
    for (int k = 0; k < FB_GEN_MAX_CHANNELS; k++) free(planes[k]);
    if (*rc) free(mask), mask = NULL;
    return mask;
}

/* Whether a pixel whose centre lies within r pixels of (u, v) is set in the mask (r = 0: the four
 * pixel centres around it, those the height is interpolated between). */
static bool near_mask(const fb_ifs_place *pl, const float *mask, double u, double v, double rx, double ry)
{
    int i0 = (int)floor(u - 0.5 - rx), i1 = (int)floor(u - 0.5 + rx) + 1;
    int j0 = (int)floor(v - 0.5 - ry), j1 = (int)floor(v - 0.5 + ry) + 1;
    for (int j = j0 < 0 ? 0 : j0; j <= j1 && j < pl->height; j++)
        for (int i = i0 < 0 ? 0 : i0; i <= i1 && i < pl->width; i++) {
            double du = rx > 0 ? (i + 0.5 - u) / rx : 0, dv = ry > 0 ? (j + 0.5 - v) / ry : 0;
            if ((rx > 0 || ry > 0) && du * du + dv * dv > 1) continue;
            if (mask[(size_t)j * pl->width + i] >= 0.5f) return true;
        }
    return false;
}

static fb_result place(const fb_ifs_place *pl, const fb_ifs_plant *plants, size_t n, instance *out, bool *ok,
                       size_t *avoided)
{
    const double *b = pl->frame, *w = pl->has_world ? pl->world : pl->frame;
    const double su = pl->width / (b[1] - b[0]), sv = pl->height / (b[3] - b[2]);
    const double cx = (w[1] - w[0]) / pl->width, cy = (w[3] - w[2]) / pl->height, scale = sqrt(cx * su * cy * sv);
    by_row *order = malloc((n ? n : 1) * sizeof *order);
    if (!order) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n; i++) order[i] = (by_row){(int)floor((b[3] - plants[i].y) * sv - 0.5), i};
    qsort(order, n, sizeof *order, cmp_row); /* each pair of rows computed once */
    rows2 rw = {pl, INT32_MIN, {0}};
    fb_result rc = FB_OK;
    float *mask = pl->avoid ? read_mask(pl, &rc) : NULL;
    const double min_up = cos(pl->max_slope * (M_PI / 180)) - 1e-12; /* 90: every slope */
    *avoided = 0;
    for (size_t k = 0; k < n && !rc; k++) {
        size_t i = order[k].idx;
        double u = (plants[i].x - b[0]) * su, v = (b[3] - plants[i].y) * sv, h = pl->constant, hu = 0, hv = 0;
        if (pl->src) rc = surface_at(&rw, u, v, &h, &hu, &hv);
        double hx = hu / cx, hy = -hv / cy, len = sqrt(hx * hx + hy * hy + 1); /* v grows southward */
        double nw[3] = {-hx / len, -hy / len, 1 / len};
        ok[i] = isfinite(h) && isfinite(len);
        if (ok[i] &&
            (nw[2] < min_up || (mask && near_mask(pl, mask, u, v, pl->avoid_distance / cx, pl->avoid_distance / cy))))
            ok[i] = false, ++*avoided;
        double X = pl->has_world ? w[0] + u * cx : plants[i].x, Y = pl->has_world ? w[3] - v * cy : plants[i].y;
        fill(pl, i, &plants[i], X, Y, h, nw, scale, &out[i]);
    }
    for (int k = 0; k < FB_GEN_MAX_CHANNELS; k++) free(rw.buf[k]);
    free(order);
    free(mask);
    return rc;
}

/* ---- the files ---------------------------------------------------------------------------------- */

static const char *const k_names[13] = {"id",     "x",        "y",        "z",        "nx",       "ny",     "nz",
                                        "pscale", "orient_x", "orient_y", "orient_z", "orient_w", "variant"};

static void put_u32(unsigned char *b, uint32_t v)
{
    for (int k = 0; k < 4; k++) b[k] = (unsigned char)(v >> (8 * k));
}

static void write_ply(FILE *f, const fb_ifs_place *pl, const instance *v, const bool *ok, size_t n, size_t count)
{
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\ncomment fractalbake plant instances: %s up; N the surface "
            "normal, pscale the plant's height, orient a quaternion (x y z w) about the up axis, variant the "
            "generation\nelement vertex %zu\n",
            pl->up == 'y' ? "Y (x east, z south)" : "Z (x east, y north)", count);
    for (int k = 0; k < 13; k++) fprintf(f, "property %s %s\n", k == 0 || k == 12 ? "int" : "float", k_names[k]);
    fputs("end_header\n", f);
    for (size_t i = 0; i < n; i++) {
        if (!ok[i]) continue;
        float fl[11] = {v[i].P[0],   v[i].P[1],      v[i].P[2],      v[i].N[0],      v[i].N[1],     v[i].N[2],
                        v[i].pscale, v[i].orient[0], v[i].orient[1], v[i].orient[2], v[i].orient[3]};
        unsigned char b[52];
        put_u32(b, (uint32_t)v[i].id);
        for (int k = 0; k < 11; k++) {
            uint32_t u;
            memcpy(&u, &fl[k], 4);
            put_u32(b + 4 + 4 * k, u);
        }
        put_u32(b + 48, (uint32_t)v[i].variant);
        fwrite(b, 1, sizeof b, f);
    }
}

static void write_csv(FILE *f, const instance *v, const bool *ok, size_t n)
{
    for (int k = 0; k < 13; k++) fprintf(f, "%s%s", k_names[k], k < 12 ? "," : "\n");
    for (size_t i = 0; i < n; i++) {
        if (!ok[i]) continue;
        const instance *o = &v[i];
        fprintf(f, "%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d\n", (int)o->id, o->P[0], o->P[1],
                o->P[2], o->N[0], o->N[1], o->N[2], o->pscale, o->orient[0], o->orient[1], o->orient[2], o->orient[3],
                (int)o->variant);
    }
}

fb_result fb_ifs_write_instances(const char *path, const fb_ifs_place *pl, const fb_ifs_plant *plants, size_t n,
                                 size_t *written, size_t *skipped, size_t *avoided)
{
    instance *v = malloc((n ? n : 1) * sizeof *v);
    bool *ok = malloc(n ? n : 1);
    *avoided = 0;
    fb_result rc = v && ok ? place(pl, plants, n, v, ok, avoided) : fb_fail(FB_ERR_NOMEM, "out of memory");
    size_t count = 0;
    for (size_t i = 0; !rc && i < n; i++) count += ok[i];
    FILE *f = NULL;
    if (!rc) rc = fb_output_fopen(path, "instances", (void **)&f);
    if (!rc) {
        const char *dot = strrchr(path, '.');
        if (dot && !strcasecmp(dot, ".csv"))
            write_csv(f, v, ok, n);
        else
            write_ply(f, pl, v, ok, n, count);
        bool bad = ferror(f) != 0;
        if (fclose(f) != 0) bad = true;
        if (bad) rc = fb_fail(FB_ERR_IO, "%s: cannot write the instances: %s", path, strerror(errno));
        rc = fb_output_done(path, rc);
    }
    free(v);
    free(ok);
    *written = count, *skipped = n - count - *avoided;
    return rc;
}
