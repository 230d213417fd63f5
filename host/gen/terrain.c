/*
 * The terrain generator: survey points (a file, the scene, or a sampled height field) are
 * triangulated and refined on the CPU (host/terrain.c), then the refined TIN is rasterised into
 * the layer strip by strip: each pixel centre takes the height of the triangle that contains it,
 * interpolated linearly. Triangles are binned into bands of BAND rows in slot order, and where
 * two triangles claim a pixel (a shared edge) the later one in that order wins, so the image does
 * not depend on the strip height or the thread count.
 *
 * Channels: NAME.Y (height; float unless half), NAME.A (1 inside the hull, 0 outside, where Y
 * holds the lowest input height) and NAME.slope (the slope of the pixel's triangle in degrees, 0 to
 * 90, from its plane in world units: exact for the TIN, no neighbouring pixels needed; 0 outside).
 */
#include "../gen.h"
#include "../terrain.h"
#include "../progress.h"
#include "../terrain_io.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define BAND 16

typedef struct terrain_state {
    double *xyz; /* the input points, until prepare */
    size_t n;
    fb_terrain_center *centers;
    int ncenters;
    fb_terrain t;
    fb_terrain_stats st;
    double bounds[4], fill;
    uint32_t nbands;
    uint32_t *band_start; /* nbands + 1 */
    uint32_t *band_tris;
} terrain_state;

static terrain_state *state(const fb_gen *g)
{
    return (terrain_state *)g->owned;
}

static void terrain_fini(fb_gen *g)
{
    terrain_state *s = state(g);
    if (!s) return;
    free(s->xyz);
    free(s->centers);
    free(s->band_start);
    free(s->band_tris);
    fb_terrain_free(&s->t);
}

/* ---- rasterisation ----------------------------------------------------------------------------- */

static void terrain_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const terrain_state *s = state(g);
    const fb_dt *d = &s->t.dt;
    const int W = g->scene->width, H = g->scene->height;
    float *Y = planes[0], *A = planes[1], *S = planes[2];
    for (size_t i = 0; i < (size_t)n * W; i++) Y[i] = (float)s->fill, A[i] = 0, S[i] = 0;
    const double sx = (s->bounds[1] - s->bounds[0]) / W, sy = (s->bounds[3] - s->bounds[2]) / H;
    for (uint32_t b = (uint32_t)y0 / BAND; b <= (uint32_t)(y0 + n - 1) / BAND && b < s->nbands; b++) {
        int r0 = (int)b * BAND > y0 ? (int)b * BAND : y0;
        int r1 = (int)(b + 1) * BAND < y0 + n ? (int)(b + 1) * BAND : y0 + n; /* rows [r0, r1) */
        for (uint32_t k = s->band_start[b]; k < s->band_start[b + 1]; k++) {
            const uint32_t *v = d->tv + 3 * (size_t)s->band_tris[k];
            /* pixel-space vertices: px = (x - xmin) / sx, py = (ymax - y) / sy */
            double px[3], py[3], z[3];
            for (int c = 0; c < 3; c++) {
                px[c] = (d->xy[2 * (size_t)v[c]] - s->bounds[0]) / sx;
                py[c] = (s->bounds[3] - d->xy[2 * (size_t)v[c] + 1]) / sy;
                z[c] = s->t.z[v[c]];
            }
            double area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
            if (area == 0) continue;
            /* the slope of the triangle's plane in world units: the angle of its normal from vertical */
            double ax = d->xy[2 * (size_t)v[1]] - d->xy[2 * (size_t)v[0]],
                   ay = d->xy[2 * (size_t)v[1] + 1] - d->xy[2 * (size_t)v[0] + 1];
            double bx = d->xy[2 * (size_t)v[2]] - d->xy[2 * (size_t)v[0]],
                   by = d->xy[2 * (size_t)v[2] + 1] - d->xy[2 * (size_t)v[0] + 1];
            double az = z[1] - z[0], bz = z[2] - z[0];
            double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
            float slope = (float)(atan2(sqrt(nx * nx + ny * ny), fabs(nz)) * (180.0 / M_PI));
            double ylo = fmin(py[0], fmin(py[1], py[2])), yhi = fmax(py[0], fmax(py[1], py[2]));
            double xlo = fmin(px[0], fmin(px[1], px[2])), xhi = fmax(px[0], fmax(px[1], px[2]));
            int ya = (int)ceil(ylo - 0.5), yb = (int)floor(yhi - 0.5), xa = (int)ceil(xlo - 0.5),
                xb = (int)floor(xhi - 0.5);
            if (ya < r0) ya = r0;
            if (yb > r1 - 1) yb = r1 - 1;
            if (xa < 0) xa = 0;
            if (xb > W - 1) xb = W - 1;
            const double tol = -1e-9 * fabs(area);
            for (int y = ya; y <= yb; y++) {
                double cy = y + 0.5;
                for (int x = xa; x <= xb; x++) {
                    double cx = x + 0.5;
                    /* barycentric weights (edge functions), inclusive of the edges */
                    double w0 = (px[1] - cx) * (py[2] - cy) - (py[1] - cy) * (px[2] - cx);
                    double w1 = (px[2] - cx) * (py[0] - cy) - (py[2] - cy) * (px[0] - cx);
                    double w2 = (px[0] - cx) * (py[1] - cy) - (py[0] - cy) * (px[1] - cx);
                    if (area < 0) w0 = -w0, w1 = -w1, w2 = -w2;
                    if (w0 < tol || w1 < tol || w2 < tol) continue;
                    double sum = w0 + w1 + w2;
                    size_t i = (size_t)(y - y0) * W + x;
                    Y[i] = (float)((w0 * z[0] + w1 * z[1] + w2 * z[2]) / sum);
                    A[i] = 1;
                    S[i] = slope;
                }
            }
        }
    }
}

/* Bins the finite triangles into row bands, in slot order. */
static fb_result bin_triangles(fb_gen *g)
{
    terrain_state *s = state(g);
    const fb_dt *d = &s->t.dt;
    const int H = g->scene->height;
    const double sy = (s->bounds[3] - s->bounds[2]) / H;
    s->nbands = (uint32_t)((H + BAND - 1) / BAND);
    s->band_start = calloc((size_t)s->nbands + 1, sizeof *s->band_start);
    if (!s->band_start) return fb_fail(FB_ERR_NOMEM, "out of memory");
    uint64_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t t = 0; t < d->nt; t++) {
            if (fb_dt_is_ghost(d, t)) continue;
            const uint32_t *v = d->tv + 3 * (size_t)t;
            double lo = INFINITY, hi = -INFINITY;
            for (int c = 0; c < 3; c++) {
                double py = (s->bounds[3] - d->xy[2 * (size_t)v[c] + 1]) / sy;
                lo = fmin(lo, py), hi = fmax(hi, py);
            }
            /* rows whose centre may be covered: ceil(lo - 0.5) .. floor(hi - 0.5) */
            double ra = ceil(lo - 0.5), rb = floor(hi - 0.5);
            if (rb < 0 || ra > H - 1 || ra > rb) continue;
            uint32_t b0 = (uint32_t)(ra < 0 ? 0 : ra) / BAND, b1 = (uint32_t)(rb > H - 1 ? H - 1 : rb) / BAND;
            for (uint32_t b = b0; b <= b1; b++) {
                if (pass == 0)
                    s->band_start[b + 1]++;
                else
                    s->band_tris[s->band_start[b]++] = t;
            }
        }
        if (pass == 0) {
            for (uint32_t b = 0; b < s->nbands; b++) s->band_start[b + 1] += s->band_start[b];
            total = s->band_start[s->nbands];
            if (total > UINT32_MAX)
                return fb_fail(FB_ERR_INPUT, "layer %s: too many triangles to rasterise", g->layer->name);
            s->band_tris = malloc((total ? total : 1) * sizeof *s->band_tris);
            if (!s->band_tris)
                return fb_fail(FB_ERR_NOMEM, "out of memory binning %llu triangles", (unsigned long long)total);
        } else {
            for (uint32_t b = s->nbands; b > 0; b--) s->band_start[b] = s->band_start[b - 1];
            s->band_start[0] = 0;
        }
    }
    return FB_OK;
}

/* ---- prepare: triangulate, refine, bin, write the mesh ------------------------------------------- */

static void on_progress(void *user, uint64_t done, uint64_t total)
{
    fb_progress_update(user, done, total);
}

static fb_result terrain_prepare(fb_gen *g, struct fb_engine *e, bool progress)
{
    (void)e;
    terrain_state *s = state(g);
    const fb_terrain_layer_params *P = &g->layer->terrain;
    char who[96];
    snprintf(who, sizeof who, "layer %s", g->layer->name);
    fb_result rc = fb_terrain_build(&s->t, s->xyz, s->n, who, &s->st);
    free(s->xyz);
    s->xyz = NULL;
    if (rc) return rc;
    if (P->sigma < 0 && P->insert > 0) {
        bool flat = true;
        for (uint32_t v = 1; v < s->t.ninput && flat; v++) flat = s->t.z[v] == s->t.z[0];
        if (flat)
            return fb_fail(FB_ERR_INPUT,
                           "layer %s: the input heights are all equal, so sigma cannot be estimated from them; give "
                           "sigma",
                           g->layer->name);
    }
    fb_progress bar;
    fb_progress_init(&bar, progress, "refine", "pts");
    fb_terrain_opts o = {
        .insert = P->insert,
        .hurst = P->hurst,
        .sigma = P->sigma,
        .sweep = P->sweep,
        .local_variance = P->local_variance,
        .seed = g->scene->seed,
        .centers = s->centers,
        .ncenters = s->ncenters,
        .progress = on_progress,
        .user = &bar,
    };
    rc = fb_terrain_refine(&s->t, &o, who, &s->st);
    fb_progress_finish(&bar);
    if (rc) return rc;

    double zmin = INFINITY;
    for (uint32_t v = 0; v < s->t.ninput; v++) zmin = fmin(zmin, s->t.z[v]);
    s->fill = zmin;
    if (P->auto_bounds) {
        memcpy(s->bounds, s->t.bbox, sizeof s->bounds);
        /* a degenerate extent cannot happen: the points are not collinear */
    } else {
        memcpy(s->bounds, P->bounds, sizeof s->bounds);
    }
    g->preview_shade[0] = (s->bounds[1] - s->bounds[0]) / g->scene->width;
    g->preview_shade[1] = (s->bounds[3] - s->bounds[2]) / g->scene->height;
    double t0 = fb_now();
    if ((rc = bin_triangles(g))) return rc;
    if (P->mesh[0] && (rc = fb_terrain_write_mesh(&s->t, P->mesh))) return rc; /* renamed with the EXR */
    double t_out = fb_now() - t0;
    const fb_terrain_stats *st = &s->st;
    snprintf(g->summary, sizeof g->summary,
             "%s: %u input points (%llu duplicates left out), %llu inserted, %llu variances clamped to 0, %u "
             "triangles; sigma %.6g; triangulate %.3f s, refine %.3f s, bin%s %.3f s",
             g->layer->name, st->input, (unsigned long long)st->duplicates, (unsigned long long)st->inserted,
             (unsigned long long)st->clamped, s->t.dt.nfinite, st->sigma, st->build_seconds, st->refine_seconds,
             P->mesh[0] ? " and mesh" : "", t_out);
    snprintf(g->summary_json, sizeof g->summary_json,
             "{\"layer\": \"%s\", \"generator\": \"terrain\", \"input_points\": %u, \"duplicates\": %llu, "
             "\"inserted\": %llu, \"clamped_variances\": %llu, \"rejected_sites\": %llu, \"variance_stages\": %u, "
             "\"vertices\": %u, \"triangles\": %u, \"sigma\": %.17g, \"triangulate_seconds\": %.6f, "
             "\"refine_seconds\": %.6f, \"output_seconds\": %.6f}",
             g->layer->name, st->input, (unsigned long long)st->duplicates, (unsigned long long)st->inserted,
             (unsigned long long)st->clamped, (unsigned long long)st->rejected, st->stages, s->t.dt.nv, s->t.dt.nfinite,
             st->sigma, st->build_seconds, st->refine_seconds, t_out);
    return FB_OK;
}

/* ---- init: read every input now, so that bad input fails before anything is written ------------- */

static fb_result inline_points(fb_gen *g, terrain_state *s)
{
    /* The layer's "points" array, from the canonical scene. */
    json_t *root = json_loads(g->scene->json, 0, NULL);
    const json_t *pts = json_object_get(
        json_array_get(json_object_get(root, "layers"), (size_t)(g->layer - g->scene->layers)), "points");
    size_t n = json_array_size(pts);
    s->xyz = malloc((n ? n : 1) * 3 * sizeof *s->xyz);
    if (!root || !s->xyz) {
        json_decref(root);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    for (size_t i = 0; i < n; i++)
        for (size_t c = 0; c < 3; c++) s->xyz[3 * i + c] = json_number_value(json_array_get(json_array_get(pts, i), c));
    s->n = n;
    json_decref(root);
    return FB_OK;
}

/* The refined mesh: per vertex its position, height and links (32 bytes), two triangles of
 * corners and neighbours (2 x 28), the triangles' band lists and the refinement's hint grid (about
 * 12 more); the input points (24 bytes each) are freed once triangulated. */
static uint64_t terrain_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    (void)e;
    const terrain_state *s = state(g);
    uint64_t v = (uint64_t)s->n + (uint64_t)g->layer->terrain.insert;
    *hold = 100 * v;
    return 24 * (uint64_t)s->n + *hold;
}

fb_result fb_gen_terrain_init(fb_gen *g)
{
    const fb_terrain_layer_params *P = &g->layer->terrain;
    terrain_state *s = calloc(1, sizeof *s);
    if (!s) return fb_fail(FB_ERR_NOMEM, "out of memory");
    g->owned = s;
    g->fini = terrain_fini;
    fb_result rc;
    if (P->points_inline)
        rc = inline_points(g, s);
    else if (P->points[0])
        rc = fb_terrain_read_points(P->points, &s->xyz, &s->n);
    else
        rc = fb_terrain_read_heightfield(P->heightfield, P->sample, &s->xyz, &s->n);
    if (!rc && P->centers[0]) rc = fb_terrain_read_centers(P->centers, &s->centers, &s->ncenters);
    if (rc) return rc;

    static const char *const suffix[3] = {"Y", "A", "slope"};
    g->nchannels = 3;
    for (int c = 0; c < 3; c++)
        snprintf(g->channel_names[c], sizeof g->channel_names[c], "%s.%s", g->layer->name, suffix[c]);
    g->channel_types[0] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    g->channel_types[1] = EXRIO_HALF;
    g->channel_types[2] = g->channel_types[0];
    g->preview_channel = 0;
    g->native_rows = terrain_rows;
    g->prepare = terrain_prepare;
    g->memory = terrain_memory;
    g->prepare_gpu_seconds = -1;
    return FB_OK;
}
