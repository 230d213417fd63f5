/*
 * The terrain generator: survey points (a file, the scene, or a sampled height field) are
 * triangulated and refined on the CPU (terrain.c), then the refined TIN is rasterised into
 * the layer strip by strip: each pixel centre takes the height of the triangle that contains it,
 * interpolated linearly. Triangles are binned into bands of BAND rows in slot order, and where
 * two triangles claim a pixel (a shared edge) the later one in that order wins, so the image does
 * not depend on the strip height or the thread count.
 *
 * Channels: NAME.Y (height; float unless half), NAME.A (1 inside the hull, 0 outside, where Y
 * holds the lowest input height) and NAME.slope (the slope of the pixel's triangle in degrees, 0 to
 * 90, from its plane in world units: exact for the TIN, no neighbouring pixels needed; 0 outside).
 */
#include "gen_terrain.h"
#include "terrain.h"
#include "progress.h"
#include "smooth.h"
#include "terrain_io.h"

#include "heightmap.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

/* Survey points: a file path, or an inline list [[x, y, z], ...] of finite numbers in lo..hi. */
static fb_result check_points(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j)
{
    char shown[64];
    fb_json_show(j, shown, sizeof shown);
    if (json_is_string(j) && *json_string_value(j) && strlen(json_string_value(j)) < 1024) return FB_OK;
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    if (!n)
        return fb_schema_error(v, path, "expected a file name or a list of points [[x, y, z], ...], found %s", shown);
    for (size_t i = 0; i < n; i++) {
        const json_t *pt = json_array_get(j, i);
        bool good = json_is_array(pt) && json_array_size(pt) == 3;
        for (size_t c = 0; good && c < 3; c++) {
            const json_t *e = json_array_get(pt, c);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(x) && x >= k->lo && x <= k->hi;
        }
        if (!good) {
            char sub[256];
            snprintf(sub, sizeof sub, "%s[%zu]", path, i);
            fb_json_show(pt, shown, sizeof shown);
            return fb_schema_error(v, sub, "expected a point [x, y, z] of finite numbers, found %s", shown);
        }
    }
    return FB_OK;
}

static const fb_kvalue points_value = {.check = check_points, .names_file = fb_string_names_file};

static const fb_keyspec terrain_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"terrain\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"terrain\"",
     "layer name; channels NAME.Y (height) and NAME.A (in the hull)", FB_CORE},
    {"points", FB_K_CUSTOM, -1e15, 1e15, false, NULL, NULL,
     "survey points: an XYZ / CSV file (x y z per line) or a list [[x, y, z], ...]", .value = &points_value,
     FB_FIELD(fb_terrain_layer_params, points)},
    {"from-heightfield", FB_K_PATH, 0, 0, false, NULL, NULL, "instead of points: IN.exr[:layer.channel] sampled",
     FB_FIELD(fb_terrain_layer_params, heightfield)},
    {"sample", FB_K_INT, 1, 65536, false, NULL, NULL, "with from-heightfield: every N-th pixel (default 16)",
     FB_FIELD(fb_terrain_layer_params, sample)},
    {"insert", FB_K_INT, 0, 1e8, false, NULL, "40000", "points inserted by random midpoint displacement",
     FB_FIELD(fb_terrain_layer_params, insert)},
    {"hurst", FB_K_NUM, 0, 1, true, NULL, "0.85", "Hurst exponent H in (0, 1); D = 3 - H", 0, NULL, "dimension",
     FB_FIELD(fb_terrain_layer_params, hurst)},
    {"dimension", FB_K_NUM, 2, 3, true, NULL, NULL, "fractal dimension D in (2, 3), instead of hurst",
     FB_FIELD(fb_terrain_layer_params, dimension)},
    {"sigma", FB_K_NUM, 0, 1e15, false, NULL, NULL,
     "standard deviation of height increments at unit distance (default: estimated from the points)",
     FB_FIELD(fb_terrain_layer_params, sigma)},
    {"order", FB_K_ENUM, 0, 0, false, "random|sweep", "\"random\"",
     "insertion triangles: random (by area) or an ordered sweep", FB_FIELD(fb_terrain_layer_params, sweep)},
    {"variance", FB_K_ENUM, 0, 0, false, "stage|local|additions", "\"stage\"",
     "the displacements: the paper's, var(z_abc - z_*) over the mesh per doubling (stage) or the triangle's "
     "neighbourhood (local); or additions, an fBm field of the asked H added to the survey's interpolated "
     "residual",
     FB_FIELD(fb_terrain_layer_params, variance)},
    {"centers", FB_K_PATH, 0, 0, false, NULL, NULL, "CSV of centres x,y,D,sigma: regions of their own D and sigma",
     FB_FIELD(fb_terrain_layer_params, centers)},
    {"interpolation", FB_K_ENUM, 0, 0, false, "linear|smooth", "\"linear\"",
     "the surface between the vertices: each triangle's plane, or a C1 surface (Clough-Tocher) without facets",
     FB_FIELD(fb_terrain_layer_params, smooth)},
    {"bounds", FB_K_BOUNDS, -1e15, 1e15, false, NULL, "\"auto\"",
     "area rasterised: \"auto\" (the points' bounding box) or [xmin, xmax, ymin, ymax]",
     FB_FIELD(fb_terrain_layer_params, bounds)},
    {"mesh", FB_K_OUTPUT, 0, 0, false, NULL, NULL, "also write the refined mesh: OUT.ply (binary) or OUT.obj",
     FB_FIELD(fb_terrain_layer_params, mesh)},
    {"heightmap", FB_K_OUTPUT, 0, 0, false, NULL, NULL,
     "also write the heights for engines: OUT.png (16-bit grey) or OUT.r16 (16-bit raw, little-endian), or OUT.tif "
     "(float GeoTIFF with the geotransform; pixels outside the hull are NoData, -3.4028234663852886e+38)",
     FB_CORE},
    FB_HEIGHTMAP_KEYS,
    {"crs", FB_K_STRING, 0, 0, false, NULL, NULL,
     "the points' projected CRS, EPSG:N (a GeoTIFF heightmap records it; default: not stated)",
     FB_FIELD(fb_terrain_layer_params, crs)},
    FB_RELIEF_KEYS,
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store Y (and R, G, B) as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_terrain(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    char sub[256];
    bool h_given = json_object_get(obj, "hurst") != NULL, d_given = json_object_get(obj, "dimension") != NULL;
    fb_terrain_layer_params *t = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, terrain_keys, FB_NKEYS(terrain_keys), "a terrain layer", t);
    if (rc) return rc;
    json_t *pts = json_object_get(obj, "points");
    bool hf = json_object_get(obj, "from-heightfield") != NULL;
    if (!pts == !hf) {
        snprintf(sub, sizeof sub, "%s.points", path);
        return fb_schema_error(v, sub,
                               "give the survey points (points) or a height field to sample (from-heightfield)%s",
                               pts ? ", not both" : "");
    }
    if (json_object_get(obj, "sample") && !hf) {
        snprintf(sub, sizeof sub, "%s.sample", path);
        return fb_schema_error(v, sub, "sample is the step of from-heightfield, which is not given");
    }
    if (h_given && d_given) {
        snprintf(sub, sizeof sub, "%s.dimension", path);
        return fb_schema_error(v, sub, "give hurst or dimension, not both");
    }
    if (json_object_get(obj, "centers") && (h_given || d_given)) {
        snprintf(sub, sizeof sub, "%s.%s", path, h_given ? "hurst" : "dimension");
        return fb_schema_error(v, sub, "the centres file gives each region its own D; drop %s",
                               h_given ? "hurst" : "dimension");
    }
    t->points_inline = json_is_array(pts);
    if (!json_object_get(obj, "sample")) t->sample = 16;
    if (d_given) t->hurst = 3 - t->dimension;
    if (!(t->hurst > 0 && t->hurst < 1)) {
        snprintf(sub, sizeof sub, "%s.%s", path, d_given ? "dimension" : "hurst");
        return fb_schema_error(v, sub, "%s must lie strictly inside %s", d_given ? "D" : "H",
                               d_given ? "(2, 3)" : "(0, 1)");
    }
    if (!json_object_get(obj, "sigma")) t->sigma = -1;
    t->local_variance = t->variance == 1; /* stage|local|additions */
    t->additions = t->variance == 2;
    if ((rc = fb_schema_relief(v, path, obj, &t->relief))) return rc;
    t->auto_bounds = json_is_string(json_object_get(obj, "bounds"));
    const char *too_long = strlen(t->heightfield) >= sizeof t->heightfield - 1              ? "from-heightfield"
                           : strlen(t->centers) >= sizeof t->centers - 1                    ? "centers"
                           : strlen(t->mesh) >= sizeof t->mesh - 1                          ? "mesh"
                           : !t->points_inline && strlen(t->points) >= sizeof t->points - 1 ? "points"
                                                                                            : NULL;
    if (too_long) {
        snprintf(sub, sizeof sub, "%s.%s", path, too_long);
        return fb_schema_error(v, sub, "file name longer than %zu characters", sizeof t->mesh - 2);
    }
    const char *crs = t->crs;
    if (crs[0]) {
        /* EPSG's geographic 2D systems (degrees: 4326 and its kind) are codes 4000 to 4999; the
         * refinement needs x, y in the units of z (a projected system, in metres) */
        unsigned code = 0;
        int used = 0;
        snprintf(sub, sizeof sub, "%s.crs", path);
        if (sscanf(crs, "EPSG:%u%n", &code, &used) != 1 || crs[used] || code < 1024 || code > 32766)
            return fb_schema_error(v, sub,
                                   "expected EPSG:N, a projected coordinate system's code (EPSG:32633 for "
                                   "UTM zone 33N), found \"%s\"",
                                   crs);
        if (code >= 4000 && code <= 4999)
            return fb_schema_error(v, sub,
                                   "%s is a geographic system (degrees): give the points in a projected one "
                                   "(metres, like their heights), such as a UTM zone",
                                   crs);
        t->epsg = (int)code;
        const char *hm = json_string_value(json_object_get(obj, "heightmap")), *dot = hm ? strrchr(hm, '.') : NULL;
        if (!dot || (strcasecmp(dot, ".tif") && strcasecmp(dot, ".tiff")))
            return fb_schema_error(v, sub, "%s is recorded only in a GeoTIFF heightmap (heightmap NAME.tif): %s", crs,
                                   hm ? "this heightmap is not one" : "no heightmap is written");
    }
    if (t->mesh[0]) {
        const char *dot = strrchr(t->mesh, '.');
        if (!dot || (strcasecmp(dot, ".ply") && strcasecmp(dot, ".obj"))) {
            snprintf(sub, sizeof sub, "%s.mesh", path);
            return fb_schema_error(v, sub, "\"%s\": the mesh format comes from the extension, .ply or .obj", t->mesh);
        }
    }
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

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
    double *grad;     /* "smooth": each vertex's gradient (smooth.h), else NULL */
    fb_relief relief; /* colour by height (fb_terrain_layer_params.relief) */
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
    free(s->grad);
    fb_terrain_free(&s->t);
}

/* ---- rasterisation ----------------------------------------------------------------------------- */

static void terrain_rows(const fb_gen *g, int y0, int n, void *const *planes)
{
    const terrain_state *s = state(g);
    const fb_dt *d = &s->t.dt;
    const int W = g->scene->width, H = g->scene->height;
    float *Y = planes[0], *A = planes[1], *S = planes[2];
    float *R = g->store.nchannels > 3 ? planes[3] : NULL, *G = R ? planes[4] : NULL, *B = R ? planes[5] : NULL;
    for (size_t i = 0; i < (size_t)n * W; i++) Y[i] = (float)s->fill, A[i] = 0, S[i] = 0;
    for (size_t i = 0; R && i < (size_t)n * W; i++) R[i] = G[i] = B[i] = 0;
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
            fb_smooth_tri ct;
            if (s->grad) {
                double wp[3][2], wg[3][2];
                for (int c = 0; c < 3; c++) {
                    wp[c][0] = d->xy[2 * (size_t)v[c]], wp[c][1] = d->xy[2 * (size_t)v[c] + 1];
                    wg[c][0] = s->grad[2 * (size_t)v[c]], wg[c][1] = s->grad[2 * (size_t)v[c] + 1];
                }
                fb_smooth_setup(&ct, wp, z, wg);
            }
            /* the slope of the triangle's plane in world units: the angle of its normal from vertical */
            double ax = d->xy[2 * (size_t)v[1]] - d->xy[2 * (size_t)v[0]],
                   ay = d->xy[2 * (size_t)v[1] + 1] - d->xy[2 * (size_t)v[0] + 1];
            double bx = d->xy[2 * (size_t)v[2]] - d->xy[2 * (size_t)v[0]],
                   by = d->xy[2 * (size_t)v[2] + 1] - d->xy[2 * (size_t)v[0] + 1];
            double az = z[1] - z[0], bz = z[2] - z[0];
            double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
            float slope = (float)(atan2(sqrt(nx * nx + ny * ny), fabs(nz)) * (180.0 / M_PI));
            double pgx = nz != 0 ? -nx / nz : 0, pgy = nz != 0 ? -ny / nz : 0; /* the plane's dz/dx, dz/dy */
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
                    A[i] = 1;
                    if (s->grad) { /* the C1 surface at the pixel's centre, and its own slope */
                        double gr[2];
                        Y[i] = (float)fb_smooth_eval(&ct, s->bounds[0] + cx * sx, s->bounds[3] - cy * sy, gr);
                        S[i] = (float)(atan(hypot(gr[0], gr[1])) * (180.0 / M_PI));
                        if (R) {
                            float c[3];
                            fb_relief_colour(&s->relief, Y[i], gr[0], gr[1], c);
                            R[i] = c[0], G[i] = c[1], B[i] = c[2];
                        }
                        continue;
                    }
                    Y[i] = (float)((w0 * z[0] + w1 * z[1] + w2 * z[2]) / sum);
                    S[i] = slope;
                    if (R) {
                        float c[3];
                        fb_relief_colour(&s->relief, Y[i], pgx, pgy, c);
                        R[i] = c[0], G[i] = c[1], B[i] = c[2];
                    }
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
    const fb_terrain_layer_params *P = fb_layer_params(g->layer);
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
        .additions = P->additions,
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
    if (P->relief.colour) { /* colour-range, else the refined surface's own range */
        double zlo = INFINITY, zhi = -INFINITY;
        for (uint32_t v = 0; v < s->t.dt.nv; v++)
            if (isfinite(s->t.z[v])) zlo = fmin(zlo, s->t.z[v]), zhi = fmax(zhi, s->t.z[v]);
        fb_relief_init(&s->relief, &P->relief, zlo, zhi);
    }
    if (P->auto_bounds) {
        memcpy(s->bounds, s->t.bbox, sizeof s->bounds);
        /* a degenerate extent cannot happen: the points are not collinear */
    } else {
        memcpy(s->bounds, P->bounds, sizeof s->bounds);
    }
    g->store.preview_shade[0] = (s->bounds[1] - s->bounds[0]) / g->scene->width;
    g->store.preview_shade[1] = (s->bounds[3] - s->bounds[2]) / g->scene->height;
    memcpy(g->prepared.world, s->bounds, sizeof g->prepared.world); /* the image's frame, for a GeoTIFF heightmap */
    g->prepared.has_world = true;
    g->prepared.epsg = P->epsg;
    double t0 = fb_now();
    if (P->smooth && !(s->grad = fb_smooth_gradients(&s->t)))
        return fb_fail(FB_ERR_NOMEM, "layer %s: out of memory for the vertex gradients", g->layer->name);
    if ((rc = bin_triangles(g))) return rc;
    if (P->mesh[0] && (rc = fb_terrain_write_mesh(&s->t, s->bounds, P->mesh))) return rc; /* renamed with the EXR */
    double t_out = fb_now() - t0;
    const fb_terrain_stats *st = &s->st;
    snprintf(g->prepared.summary, sizeof g->prepared.summary,
             "layer %s (terrain): %u input points (%llu duplicates left out), %llu inserted, %llu variances clamped "
             "to 0, %u triangles; sigma %.6g; triangulate %.3f s, refine %.3f s, bin%s %.3f s%s%.200s",
             g->layer->name, st->input, (unsigned long long)st->duplicates, (unsigned long long)st->inserted,
             (unsigned long long)st->clamped, s->t.dt.nfinite, st->sigma, st->build_seconds, st->refine_seconds,
             P->mesh[0] ? " and mesh" : "", t_out, P->mesh[0] ? "; mesh " : "", P->mesh);
    snprintf(g->prepared.summary_json, sizeof g->prepared.summary_json,
             "{\"layer\": \"%s\", \"generator\": \"terrain\", \"input_points\": %u, \"duplicates\": %llu, "
             "\"inserted\": %llu, \"hull_splits\": %llu, \"clamped_variances\": %llu, \"rejected_sites\": %llu, "
             "\"variance_stages\": %u, "
             "\"vertices\": %u, \"triangles\": %u, \"sigma\": %.17g, \"triangulate_seconds\": %.6f, "
             "\"refine_seconds\": %.6f, \"output_seconds\": %.6f}",
             g->layer->name, st->input, (unsigned long long)st->duplicates, (unsigned long long)st->inserted,
             (unsigned long long)st->hull_splits, (unsigned long long)st->clamped, (unsigned long long)st->rejected,
             st->stages, s->t.dt.nv, s->t.dt.nfinite, st->sigma, st->build_seconds, st->refine_seconds, t_out);
    return FB_OK;
}

/* ---- init: read every input now, so that bad input fails before anything is written ------------- */

static fb_result inline_points(fb_gen *g, terrain_state *s)
{
    /* The layer's "points" array, from the canonical scene: found by the layer's name, since a task's
     * scene (render --task) holds some of the stored scene's layers only. */
    json_t *root = json_loads(g->scene->json, 0, NULL);
    const json_t *pts = NULL, *lj;
    size_t k;
    json_array_foreach(json_object_get(root, "layers"), k,
                       lj) if (!strcmp(json_string_value(json_object_get(lj, "name"))
                                           ? json_string_value(json_object_get(lj, "name"))
                                           : "",
                                       g->layer->name)) pts = json_object_get(lj, "points");
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
 * 12 more); the input points (24 bytes each) are freed once triangulated. Additions' residuals (8
 * bytes a vertex) are freed before the band lists are made, so they do not raise the peak (measured:
 * 306 and 308 MiB for 3 * 10^6 insertions, stage and additions). */
static uint64_t terrain_memory(const fb_gen *g, const struct fb_engine *e, uint64_t *hold)
{
    (void)e;
    const terrain_state *s = state(g);
    uint64_t v = (uint64_t)s->n + (uint64_t)((const fb_terrain_layer_params *)fb_layer_params(g->layer))->insert;
    *hold = 100 * v + (((const fb_terrain_layer_params *)fb_layer_params(g->layer))->smooth ? 16 * v : 0);
    return 24 * (uint64_t)s->n + *hold;
}

static fb_result terrain_init(fb_gen *g)
{
    const fb_terrain_layer_params *P = fb_layer_params(g->layer);
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

    static const char *const suffix[6] = {"Y", "A", "slope", "R", "G", "B"};
    g->store.nchannels = P->relief.colour ? 6 : 3;
    for (int c = 0; c < g->store.nchannels; c++) {
        snprintf(g->store.channel_names[c], sizeof g->store.channel_names[c], "%s.%s", g->layer->name, suffix[c]);
        g->store.channel_types[c] = g->layer->half ? EXRIO_HALF : EXRIO_FLOAT;
    }
    g->store.channel_types[1] = EXRIO_HALF;
    g->store.preview_channel = 0;
    if (P->relief.colour) g->store.preview_rgb = 3; /* the preview shows the lit colour */
    g->compute.native_rows = terrain_rows;
    g->prepare = terrain_prepare;
    g->memory = terrain_memory;
    g->prepared.gpu_seconds = -1;
    return FB_OK;
}

static int terrain_outputs(const fb_layer *L, const char **paths, const char **what, int max)
{
    const fb_terrain_layer_params *P = fb_layer_params(L);
    if (!P->mesh[0] || max < 1) return 0;
    paths[0] = P->mesh, what[0] = "mesh";
    return 1;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). */
static fb_result terrain_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    const fb_terrain_layer_params *t = fb_layer_params(&s->layers[layer]);
    *total = (double)t->insert * 4.0e-6 /* an insertion: refinement and Delaunay */ +
             (double)s->width * s->height * 4.8e-8 /* a pixel: rasterising, slope, channels */;
    return FB_OK;
}

const fb_gen_class fb_gen_terrain = {
    .name = "terrain",
    .synopsis = "terrain --points F.xyz -o OUT.exr",
    .summary = "survey points refined by Delaunay midpoint displacement, one layer",
    .what = "a terrain layer",
    .keys = terrain_keys,
    .nkeys = FB_NKEYS(terrain_keys),
    .params_size = sizeof(fb_terrain_layer_params),
    .parse = parse_terrain,
    .outputs = terrain_outputs,
    .init = terrain_init,
    .share = FB_SHARE_WHOLE,
    .cost = terrain_cost,
    .example = "[{\"type\": \"terrain\", \"insert\": 500, \"points\": [[0, 0, 0], [100, 0, 10], [0, 50, 20], "
               "[100, 50, 40], [50, 25, 80]]}]",
    .bench = fb_terrain_bench,
};
