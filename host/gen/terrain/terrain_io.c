/*
 * Terrain input and output (see terrain_io.h).
 */
#include "terrain_io.h"

#include "exrio.h"
#include "output.h"
#include "textin.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

fb_result fb_terrain_read_points(const char *path, double **xyz, size_t *n)
{
    *xyz = NULL;
    *n = 0;
    fb_lines in;
    fb_result rc = fb_lines_open(&in, path, "points");
    if (rc) return rc;
    char *fld[4];
    size_t count = 0, alloc = 0;
    double *p = NULL;
    int nf, got;
    while (!rc && (got = fb_lines_next(&in, fld, 3, &nf)) > 0) {
        double v[3];
        if (nf != 3 || !fb_text_number(fld[0], &v[0]) || !fb_text_number(fld[1], &v[1]) ||
            !fb_text_number(fld[2], &v[2])) {
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: expected three numbers x y z (or x,y,z)", path, in.lineno);
        } else if (!isfinite(v[0]) || !isfinite(v[1]) || !isfinite(v[2])) {
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: coordinate is not a finite number", path, in.lineno);
        } else if (fabs(v[0]) > FB_TERRAIN_MAX_COORD || fabs(v[1]) > FB_TERRAIN_MAX_COORD ||
                   fabs(v[2]) > FB_TERRAIN_MAX_COORD) {
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: coordinate beyond +-%g (heights and squared distances must stay finite)",
                         path, in.lineno, FB_TERRAIN_MAX_COORD);
        } else if (count == FB_TERRAIN_MAX_POINTS) {
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: more than %llu points", path, in.lineno, FB_TERRAIN_MAX_POINTS);
        } else {
            if (count == alloc) {
                alloc = alloc ? 2 * alloc : 1024;
                double *q = realloc(p, alloc * 3 * sizeof *q);
                if (!q) {
                    rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory for %zu points", path, count);
                    break;
                }
                p = q;
            }
            memcpy(p + 3 * count++, v, sizeof v);
        }
    }
    if (!rc && got < 0) rc = FB_ERR_INPUT;
    if (!rc && !count) rc = fb_fail(FB_ERR_INPUT, "%s: no points (expected lines of x y z)", path);
    fb_lines_close(&in);
    if (rc) {
        free(p);
        return rc;
    }
    *xyz = p;
    *n = count;
    return FB_OK;
}

fb_result fb_terrain_read_heightfield(const char *spec, int step, double **xyz, size_t *n)
{
    *xyz = NULL;
    *n = 0;
    char path[4096];
    snprintf(path, sizeof path, "%s", spec);
    /* IN.exr:layer.channel: the first colon right after ".exr" */
    char *chan = NULL;
    for (char *colon = strchr(path, ':'); colon; colon = strchr(colon + 1, ':'))
        if (colon - path >= 4 && !strncasecmp(colon - 4, ".exr", 4)) {
            *colon = 0, chan = colon + 1;
            break;
        }
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    int c = -1, nc = exrio_nchannels(r);
    if (chan) {
        c = exrio_find_channel(r, chan);
        if (c < 0) rc = fb_fail(FB_ERR_INPUT, "%s: no channel %s", path, chan);
    } else if (nc == 1) {
        c = 0;
    } else {
        for (int k = 0; k < nc; k++) {
            const char *nm = exrio_channel_name(r, k);
            size_t l = strlen(nm);
            if (!strcmp(nm, "Y") || (l > 2 && !strcmp(nm + l - 2, ".Y"))) {
                if (c >= 0) {
                    c = -2;
                    break;
                }
                c = k;
            }
        }
        if (c < 0) rc = fb_fail(FB_ERR_INPUT, "%s: %d channels; name one as %s:layer.channel", path, nc, path);
    }
    if (!rc && exrio_channel_type(r, c) == EXRIO_UINT)
        rc = fb_fail(FB_ERR_INPUT, "%s: channel %s holds integers, not heights", path, exrio_channel_name(r, c));
    int W = exrio_width(r), H = exrio_height(r);
    size_t nx = (size_t)(W - 1) / step + 1 + ((W - 1) % step != 0);
    size_t ny = (size_t)(H - 1) / step + 1 + ((H - 1) % step != 0);
    double *p = NULL;
    float *row = NULL;
    void *planes[64] = {0};
    if (!rc && nc > 64) rc = fb_fail(FB_ERR_INPUT, "%s: more than 64 channels", path);
    if (!rc && (!(p = malloc(nx * ny * 3 * sizeof *p)) || !(row = malloc((size_t)W * sizeof *row))))
        rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory", path);
    size_t count = 0;
    for (size_t j = 0; j < ny && !rc; j++) {
        int y = j + 1 == ny ? H - 1 : (int)(j * (size_t)step);
        planes[c] = row;
        rc = exrio_read_rows(r, y, 1, planes);
        for (size_t i = 0; i < nx && !rc; i++) {
            int x = i + 1 == nx ? W - 1 : (int)(i * (size_t)step);
            if (!isfinite(row[x]) || fabs(row[x]) > FB_TERRAIN_MAX_COORD) {
                rc = fb_fail(FB_ERR_INPUT, "%s: pixel (%d, %d) of %s is %s", path, x, y, exrio_channel_name(r, c),
                             isfinite(row[x]) ? "beyond +-1e15" : "not a finite number");
                break;
            }
            p[3 * count] = x, p[3 * count + 1] = H - 1 - y, p[3 * count + 2] = row[x];
            count++;
        }
    }
    free(row);
    exrio_close(&r);
    if (rc) {
        free(p);
        return rc;
    }
    *xyz = p;
    *n = count;
    return FB_OK;
}

fb_result fb_terrain_read_centers(const char *path, fb_terrain_center **out, int *n)
{
    *out = NULL;
    *n = 0;
    fb_lines in;
    fb_result rc = fb_lines_open(&in, path, "centres");
    if (rc) return rc;
    fb_terrain_center *c = calloc(FB_TERRAIN_MAX_CENTERS, sizeof *c);
    char *fld[5];
    int count = 0, nf, got = 0;
    if (!c) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    while (!rc && (got = fb_lines_next(&in, fld, 4, &nf)) > 0) {
        double v[4] = {0, 0, 0, -1};
        bool ok = (nf == 3 || nf == 4) && fb_text_number(fld[0], &v[0]) && fb_text_number(fld[1], &v[1]) &&
                  fb_text_number(fld[2], &v[2]) && (nf == 3 || !*fld[3] || fb_text_number(fld[3], &v[3]));
        if (!ok)
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: expected x,y,D or x,y,D,sigma", path, in.lineno);
        else if (!isfinite(v[0]) || !isfinite(v[1]) || !isfinite(v[3]))
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: not a finite number", path, in.lineno);
        else if (fabs(v[0]) > FB_TERRAIN_MAX_COORD || fabs(v[1]) > FB_TERRAIN_MAX_COORD || v[3] > FB_TERRAIN_MAX_COORD)
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: beyond +-%g", path, in.lineno, FB_TERRAIN_MAX_COORD);
        else if (!(v[2] > 2 && v[2] < 3))
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: fractal dimension D = %g is outside (2, 3)", path, in.lineno, v[2]);
        else if (nf == 4 && *fld[3] && !(v[3] >= 0))
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: sigma %g is negative", path, in.lineno, v[3]);
        else if (count == FB_TERRAIN_MAX_CENTERS)
            rc = fb_fail(FB_ERR_INPUT, "%s:%d: more than %d centres", path, in.lineno, FB_TERRAIN_MAX_CENTERS);
        else
            c[count++] = (fb_terrain_center){v[0], v[1], 3 - v[2], v[3]};
    }
    if (!rc && got < 0) rc = FB_ERR_INPUT;
    if (!rc && !count) rc = fb_fail(FB_ERR_INPUT, "%s: no centres (expected lines of x,y,D,sigma)", path);
    fb_lines_close(&in);
    if (rc) {
        free(c);
        return rc;
    }
    *out = c;
    *n = count;
    return FB_OK;
}

bool fb_terrain_mesh_format_ok(const char *path)
{
    const char *dot = strrchr(path, '.');
    return dot && (!strcasecmp(dot, ".ply") || !strcasecmp(dot, ".obj"));
}

static void put_u32(unsigned char *b, uint32_t v)
{
    for (int i = 0; i < 4; i++) b[i] = (unsigned char)(v >> (8 * i));
}

static void put_f32(unsigned char *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}

/* Per-vertex unit normals: the sum of the cross products of the vertex's triangles (so each weighted
 * by its area), normalised; (0, 0, 1) for a vertex of no finite triangle. */
static float *vertex_normals(const fb_terrain *t)
{
    const fb_dt *d = &t->dt;
    double *acc = calloc((size_t)d->nv * 3, sizeof *acc);
    float *n = malloc((size_t)d->nv * 3 * sizeof *n);
    if (!acc || !n) {
        free(acc), free(n);
        return NULL;
    }
    for (uint32_t tr = 0; tr < d->nt; tr++) {
        if (fb_dt_is_ghost(d, tr)) continue;
        const uint32_t *v = d->tv + 3 * (size_t)tr;
        double p[3][3];
        for (int k = 0; k < 3; k++)
            p[k][0] = d->xy[2 * (size_t)v[k]], p[k][1] = d->xy[2 * (size_t)v[k] + 1], p[k][2] = t->z[v[k]];
        double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        if (c[2] < 0) c[0] = -c[0], c[1] = -c[1], c[2] = -c[2]; /* up, whatever the triangle's order */
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++) acc[3 * (size_t)v[k] + j] += c[j];
    }
    for (uint32_t i = 0; i < d->nv; i++) {
        double *a = acc + 3 * (size_t)i, len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int j = 0; j < 3; j++) n[3 * (size_t)i + j] = len > 0 ? (float)(a[j] / len) : j == 2 ? 1.0f : 0.0f;
    }
    free(acc);
    return n;
}

fb_result fb_terrain_write_mesh(const fb_terrain *t, const double bounds[4], const char *path)
{
    const fb_dt *d = &t->dt;
    const char *dot = strrchr(path, '.');
    bool ply = dot && !strcasecmp(dot, ".ply");
    float *nrm = vertex_normals(t);
    if (!nrm) return fb_fail(FB_ERR_NOMEM, "out of memory for the mesh's normals");
    /* texture coordinates: the vertex's place in the image's frame, u right, v up (0 at the bottom
     * row), so that the baked layers map onto the mesh */
    const double u0 = bounds[0], us = 1.0 / (bounds[1] - bounds[0]), v0 = bounds[2], vs = 1.0 / (bounds[3] - bounds[2]);
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, "mesh", (void **)&f);
    if (rc) {
        free(nrm);
        return rc;
    }
    if (ply) {
        fprintf(f,
                "ply\nformat binary_little_endian 1.0\ncomment fractalbake terrain\nelement vertex %u\n"
                "property double x\nproperty double y\nproperty double z\nproperty float nx\nproperty float ny\n"
                "property float nz\nproperty float u\nproperty float v\nelement face %u\n"
                "property list uchar int vertex_indices\nend_header\n",
                d->nv, d->nfinite);
        for (uint32_t v = 0; v < d->nv; v++) {
            double xyz[3] = {d->xy[2 * (size_t)v], d->xy[2 * (size_t)v + 1], t->z[v]};
            unsigned char b[44];
            for (int k = 0; k < 3; k++) {
                uint64_t u;
                memcpy(&u, &xyz[k], 8);
                put_u32(b + 8 * k, (uint32_t)u);
                put_u32(b + 8 * k + 4, (uint32_t)(u >> 32));
            }
            for (int k = 0; k < 3; k++) put_f32(b + 24 + 4 * k, nrm[3 * (size_t)v + k]);
            put_f32(b + 36, (float)((xyz[0] - u0) * us));
            put_f32(b + 40, (float)((xyz[1] - v0) * vs));
            fwrite(b, 1, 44, f);
        }
        for (uint32_t tr = 0; tr < d->nt; tr++) {
            if (fb_dt_is_ghost(d, tr)) continue;
            unsigned char b[13];
            b[0] = 3;
            for (int k = 0; k < 3; k++) put_u32(b + 1 + 4 * k, d->tv[3 * (size_t)tr + k]);
            fwrite(b, 1, 13, f);
        }
    } else {
        fprintf(f, "# fractalbake terrain: %u vertices, %u triangles; normals and texture coordinates per vertex\n",
                d->nv, d->nfinite);
        for (uint32_t v = 0; v < d->nv; v++) {
            double x = d->xy[2 * (size_t)v], y = d->xy[2 * (size_t)v + 1];
            fprintf(f, "v %.17g %.17g %.17g\nvn %.9g %.9g %.9g\nvt %.9g %.9g\n", x, y, t->z[v], nrm[3 * (size_t)v],
                    nrm[3 * (size_t)v + 1], nrm[3 * (size_t)v + 2], (x - u0) * us, (y - v0) * vs);
        }
        for (uint32_t tr = 0; tr < d->nt; tr++) {
            if (fb_dt_is_ghost(d, tr)) continue;
            const uint32_t *v = d->tv + 3 * (size_t)tr;
            fprintf(f, "f %u/%u/%u %u/%u/%u %u/%u/%u\n", v[0] + 1, v[0] + 1, v[0] + 1, v[1] + 1, v[1] + 1, v[1] + 1,
                    v[2] + 1, v[2] + 1, v[2] + 1);
        }
    }
    free(nrm);
    bool bad = ferror(f) != 0;
    if (fclose(f) != 0) bad = true;
    if (bad) rc = fb_fail(FB_ERR_IO, "%s: cannot write the mesh: %s", path, strerror(errno));
    return fb_output_done(path, rc);
}
