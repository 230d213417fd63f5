#include "smooth.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

/* Solves the n x n system m x = r (n <= 5) by Gaussian elimination with partial pivoting; false when
 * a pivot is below tol times the largest diagonal entry (the points do not determine the fit). */
static bool solve(double m[5][5], double r[5], int n, double x[5])
{
    double big = 0;
    for (int i = 0; i < n; i++) big = fmax(big, fabs(m[i][i]));
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int i = c + 1; i < n; i++)
            if (fabs(m[i][c]) > fabs(m[piv][c])) piv = i;
        if (!(fabs(m[piv][c]) > 1e-12 * big)) return false;
        for (int j = 0; j < n; j++) {
            double t = m[c][j];
            m[c][j] = m[piv][j], m[piv][j] = t;
        }
        double t = r[c];
        r[c] = r[piv], r[piv] = t;
        for (int i = c + 1; i < n; i++) {
            double f = m[i][c] / m[c][c];
            for (int j = c; j < n; j++) m[i][j] -= f * m[c][j];
            r[i] -= f * r[c];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double acc = r[i];
        for (int j = i + 1; j < n; j++) acc -= m[i][j] * x[j];
        x[i] = acc / m[i][i];
    }
    return true;
}

double *fb_smooth_gradients(const fb_terrain *t)
{
    const fb_dt *d = &t->dt;
    /* each vertex's neighbours (the finite triangles' edges, both ways; duplicates are harmless to
     * the fit but removed), as compressed rows */
    uint32_t *cnt = calloc((size_t)d->nv + 1, sizeof *cnt), *adj = NULL;
    double *g = malloc((size_t)d->nv * 2 * sizeof *g), *acc = calloc((size_t)d->nv * 3, sizeof *acc);
    if (!cnt || !g || !acc) goto fail;
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t tr = 0; tr < d->nt; tr++) {
            if (fb_dt_is_ghost(d, tr)) continue;
            const uint32_t *v = d->tv + 3 * (size_t)tr;
            for (int k = 0; k < 3; k++)
                for (int j = 1; j < 3; j++) {
                    uint32_t a = v[k], b = v[(k + j) % 3];
                    if (pass == 0)
                        cnt[a + 1]++;
                    else
                        adj[cnt[a]++] = b;
                }
            if (pass == 1) continue;
            /* the area-weighted normal: the fallback where a fit is not determined */
            const double *p0 = d->xy + 2 * (size_t)v[0], *p1 = d->xy + 2 * (size_t)v[1], *p2 = d->xy + 2 * (size_t)v[2];
            double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], t->z[v[1]] - t->z[v[0]]};
            double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], t->z[v[2]] - t->z[v[0]]};
            double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
            if (n[2] < 0) n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
            for (int k = 0; k < 3; k++)
                for (int j = 0; j < 3; j++) acc[3 * (size_t)v[k] + j] += n[j];
        }
        if (pass == 0) {
            for (uint32_t i = 0; i < d->nv; i++) cnt[i + 1] += cnt[i];
            if (!(adj = malloc((size_t)cnt[d->nv] * sizeof *adj))) goto fail;
        } else { /* cnt[i] now ends row i: shift back so that row i is cnt[i] .. cnt[i + 1] */
            for (uint32_t i = d->nv; i > 0; i--) cnt[i] = cnt[i - 1];
            cnt[0] = 0;
        }
    }
    for (uint32_t i = 0; i < d->nv; i++) {
        /* a quadratic through the vertex, z - z_i = a dx + b dy + c dx^2 + e dx dy + f dy^2, fitted
         * by least squares to its neighbours weighted by 1 / distance^2: its slope at the vertex */
        const double *pi = d->xy + 2 * (size_t)i;
        double m[5][5] = {{0}}, r[5] = {0}, x[5];
        int n = 0;
        for (uint32_t k = cnt[i]; k < cnt[i + 1]; k++) {
            uint32_t j = adj[k];
            bool seen = false;
            for (uint32_t q = cnt[i]; q < k && !seen; q++) seen = adj[q] == j;
            if (seen) continue;
            double dx = d->xy[2 * (size_t)j] - pi[0], dy = d->xy[2 * (size_t)j + 1] - pi[1], dd = dx * dx + dy * dy;
            if (!(dd > 0)) continue;
            double w = 1 / dd, b[5] = {dx, dy, dx * dx, dx * dy, dy * dy}, dz = t->z[j] - t->z[i];
            for (int a = 0; a < 5; a++) {
                for (int c = 0; c < 5; c++) m[a][c] += w * b[a] * b[c];
                r[a] += w * b[a] * dz;
            }
            n++;
        }
        const double *nn = acc + 3 * (size_t)i;
        if (n >= 6 && solve(m, r, 5, x)) {
            g[2 * (size_t)i] = x[0], g[2 * (size_t)i + 1] = x[1];
        } else { /* too few neighbours (a hull corner): the plane of the mean normal */
            g[2 * (size_t)i] = nn[2] > 0 ? -nn[0] / nn[2] : 0;
            g[2 * (size_t)i + 1] = nn[2] > 0 ? -nn[1] / nn[2] : 0;
        }
    }
    free(cnt), free(adj), free(acc);
    return g;
fail:
    free(cnt), free(adj), free(acc), free(g);
    return NULL;
}

static double dot(const double a[2], const double b[2])
{
    return a[0] * b[0] + a[1] * b[1];
}

/*
 * The Bezier ordinates of the split triangle (indices mod 3; C the centroid):
 *
 *            V[i+2]
 *             /|\
 *            / | \            on edge V[i]V[i+1]: V[i], e[i][0], e[i][1], V[i+1]
 *           /  C  \           on the split edge V[i]C: V[i], pc[i], qc[i], C
 *          / .   . \          inside micro-triangle (V[i], V[i+1], C): m[i]
 *     V[i] --------- V[i+1]
 *
 * e and pc come from the vertex's value and gradient (the linear Taylor terms at a third of the
 * way); m[i] makes the derivative across edge i, in the direction of the edge's midpoint towards C,
 * the one whose normal part is linear along the edge; qc and zc are the C1 conditions across the
 * split edges: with C the centroid, qc[i] = (pc[i] + m[i] + m[i-1]) / 3 and zc = mean of qc.
 */
void fb_smooth_setup(fb_smooth_tri *s, const double p[3][2], const double z[3], const double g[3][2])
{
    for (int i = 0; i < 3; i++) s->p[i][0] = p[i][0], s->p[i][1] = p[i][1], s->z[i] = z[i];
    s->cen[0] = (p[0][0] + p[1][0] + p[2][0]) / 3, s->cen[1] = (p[0][1] + p[1][1] + p[2][1]) / 3;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3;
        double dij[2] = {p[j][0] - p[i][0], p[j][1] - p[i][1]}, dic[2] = {s->cen[0] - p[i][0], s->cen[1] - p[i][1]};
        s->e[i][0] = z[i] + dot(g[i], dij) / 3;
        s->e[i][1] = z[j] - dot(g[j], dij) / 3;
        s->pc[i] = z[i] + dot(g[i], dic) / 3;
    }
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3;
        double L = hypot(p[j][0] - p[i][0], p[j][1] - p[i][1]);
        double t[2] = {(p[j][0] - p[i][0]) / L, (p[j][1] - p[i][1]) / L}, n[2] = {-t[1], t[0]};
        double w[2] = {s->cen[0] - (p[i][0] + p[j][0]) / 2, s->cen[1] - (p[i][1] + p[j][1]) / 2};
        double dn = (dot(g[i], n) + dot(g[j], n)) / 2; /* the normal derivative at the edge's middle */
        double dt = 3 * (s->e[i][1] - s->e[i][0]) / L; /* the edge cubic's middle derivative ordinate */
        s->m[i] = (s->e[i][0] + s->e[i][1]) / 2 + (dot(w, n) * dn + dot(w, t) * dt) / 3;
    }
    for (int i = 0; i < 3; i++) s->qc[i] = (s->pc[i] + s->m[i] + s->m[(i + 2) % 3]) / 3;
    s->zc = (s->qc[0] + s->qc[1] + s->qc[2]) / 3;
}

/* Barycentric coordinates of (x, y) in triangle a, b, c. */
static void bary(const double a[2], const double b[2], const double c[2], double x, double y, double l[3])
{
    double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    l[1] = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
    l[2] = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
    l[0] = 1 - l[1] - l[2];
}

double fb_smooth_eval(const fb_smooth_tri *s, double x, double y, double grad[2])
{
    double L[3];
    bary(s->p[0], s->p[1], s->p[2], x, y, L);
    /* the micro-triangle: the one without the vertex of the smallest coordinate */
    int k = L[0] <= L[1] && L[0] <= L[2] ? 0 : L[1] <= L[2] ? 1 : 2;
    int i = (k + 1) % 3, j = (k + 2) % 3; /* micro-triangle (V[i], V[j], C); edge index of V[i]V[j] is i */
    double u[3];                          /* barycentric in (V[i], V[j], C) */
    bary(s->p[i], s->p[j], s->cen, x, y, u);
    /* the cubic's ordinates c[a][b] for u0^a u1^b uc^(3-a-b) */
    double c300 = s->z[i], c030 = s->z[j], c003 = s->zc;
    double c210 = s->e[i][0], c120 = s->e[i][1];
    double c201 = s->pc[i], c102 = s->qc[i], c021 = s->pc[j], c012 = s->qc[j], c111 = s->m[i];
    double a = u[0], b = u[1], c = u[2];
    double v = a * a * a * c300 + b * b * b * c030 + c * c * c * c003 + 3 * a * a * b * c210 + 3 * a * b * b * c120 +
               3 * a * a * c * c201 + 3 * a * c * c * c102 + 3 * b * b * c * c021 + 3 * b * c * c * c012 +
               6 * a * b * c * c111;
    if (grad) {
        /* partial derivatives in the three barycentric coordinates, then the chain rule */
        double da = 3 * a * a * c300 + 6 * a * b * c210 + 3 * b * b * c120 + 6 * a * c * c201 + 3 * c * c * c102 +
                    6 * b * c * c111;
        double db = 3 * b * b * c030 + 3 * a * a * c210 + 6 * a * b * c120 + 6 * b * c * c021 + 3 * c * c * c012 +
                    6 * a * c * c111;
        double dc = 3 * c * c * c003 + 3 * a * a * c201 + 6 * a * c * c102 + 3 * b * b * c021 + 6 * b * c * c012 +
                    6 * a * b * c111;
        const double *P = s->p[i], *Q = s->p[j], *R = s->cen;
        double det = (Q[0] - P[0]) * (R[1] - P[1]) - (R[0] - P[0]) * (Q[1] - P[1]);
        /* d(u1)/dx, d(u1)/dy, d(u2)/dx, d(u2)/dy; u0 = 1 - u1 - u2 */
        double b_x = (R[1] - P[1]) / det, b_y = -(R[0] - P[0]) / det;
        double c_x = -(Q[1] - P[1]) / det, c_y = (Q[0] - P[0]) / det;
        grad[0] = db * b_x + dc * c_x - da * (b_x + c_x);
        grad[1] = db * b_y + dc * c_y - da * (b_y + c_y);
    }
    return v;
}
