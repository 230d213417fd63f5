/*
 * Hull edges in the refinement: encroachment, exact midpoints, kriged heights (terrain_hull.h).
 */
#include "terrain_hull.h"

#include "predicates.h"

#include <math.h>

size_t fb_terrain_neighbourhood(const fb_dt *d, uint32_t tr, uint32_t list[16])
{
    size_t n = 0, head = 0;
    list[n++] = tr;
    for (int ring = 0; ring < 2; ring++)
        for (size_t end = n; head < end; head++)
            for (int i = 0; i < 3; i++) {
                uint32_t nb = d->tn[3 * (size_t)list[head] + i];
                bool seen = fb_dt_is_ghost(d, nb);
                for (size_t k = 0; k < n && !seen; k++) seen = list[k] == nb;
                if (!seen && n < 16) list[n++] = nb;
            }
    return n;
}

int fb_terrain_encroached(const fb_dt *d, uint32_t tr, const double *p, uint32_t *owner)
{
    uint32_t list[16];
    size_t n = fb_terrain_neighbourhood(d, tr, list);
    int best = -1;
    double best_l2 = 0;
    for (size_t k = 0; k < n; k++)
        for (int i = 0; i < 3; i++) {
            if (!fb_dt_is_ghost(d, d->tn[3 * (size_t)list[k] + i])) continue;
            const uint32_t *v = d->tv + 3 * (size_t)list[k];
            const double *a = d->xy + 2 * (size_t)v[(i + 1) % 3], *b = d->xy + 2 * (size_t)v[(i + 2) % 3];
            double l2 = (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]);
            double mx = p[0] - 0.5 * (a[0] + b[0]), my = p[1] - 0.5 * (a[1] + b[1]);
            if (4 * (mx * mx + my * my) < l2 && l2 > best_l2) best_l2 = l2, best = i, *owner = list[k];
        }
    return best;
}

bool fb_terrain_hull_midpoint(const fb_dt *d, uint32_t owner, const double *a, const double *b, double m[2])
{
    const double mx = 0.5 * (a[0] + b[0]), my = 0.5 * (a[1] + b[1]);
    bool on = false;
    for (int k = 0; k < 9 && !on; k++) {
        m[0] = k % 3 == 0 ? mx : nextafter(mx, k % 3 == 1 ? -INFINITY : INFINITY);
        m[1] = k / 3 == 0 ? my : nextafter(my, k / 3 == 1 ? -INFINITY : INFINITY);
        on = fb_orient2d(a, b, m) == 0;
    }
    if (!on) return false;
    double near2 = 1e-12 * ((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]));
    uint32_t list[16];
    size_t n = fb_terrain_neighbourhood(d, owner, list);
    for (size_t j = 0; j < n; j++)
        for (int c = 0; c < 3; c++) {
            uint32_t v = d->tv[3 * (size_t)list[j] + c];
            double dx = d->xy[2 * (size_t)v] - m[0], dy = d->xy[2 * (size_t)v + 1] - m[1];
            if (dx * dx + dy * dy <= near2) return false;
        }
    return true;
}

/* Solves the n x n system a x = a[.][n] in place by Gaussian elimination with partial pivoting
 * (Gauss-Jordan: the solution ends in a[i][n] / a[i][i]); false on a pivot below tol times the
 * largest entry of its column at the start. */
#define KN (FB_HULL_KRIGE_MAX + 3)
static bool solve(double a[KN][KN + 1], int n)
{
    for (int c = 0; c < n; c++) {
        int piv = c;
        double big = 0;
        for (int r = 0; r < n; r++) big = fmax(big, fabs(a[r][c]));
        for (int r = c + 1; r < n; r++)
            if (fabs(a[r][c]) > fabs(a[piv][c])) piv = r;
        if (!(fabs(a[piv][c]) > 1e-12 * big)) return false;
        for (int k = 0; k <= n; k++) {
            double t = a[c][k];
            a[c][k] = a[piv][k], a[piv][k] = t;
        }
        for (int r = 0; r < n; r++) {
            if (r == c || a[r][c] == 0) continue;
            double f = a[r][c] / a[c][c];
            for (int k = c; k <= n; k++) a[r][k] -= f * a[c][k];
        }
    }
    return true;
}

/* The system [G F; F' 0] [w; mu] = [g; f0] in units of a length L (the neighbourhood's extent), for
 * conditioning: G_jk = (|x_j - x_k| / L)^(2H), g_j = (|x_j - p| / L)^(2H), the rows of F
 * (1, (x_j - p) / L), f0 = (1, 0, 0); the kriging variance is L^(2H) (w'g + mu_0). */
bool fb_terrain_hull_krige(const fb_dt *d, uint32_t owner, const double *p, double H, fb_hull_weights *out)
{
    uint32_t list[16];
    size_t nt = fb_terrain_neighbourhood(d, owner, list);
    int n = 0;
    double L2 = 0;
    for (size_t j = 0; j < nt; j++)
        for (int c = 0; c < 3; c++) {
            uint32_t v = d->tv[3 * (size_t)list[j] + c];
            bool seen = false;
            for (int k = 0; k < n && !seen; k++) seen = out->v[k] == v;
            if (seen || n == FB_HULL_KRIGE_MAX) continue;
            out->v[n++] = v;
            double dx = d->xy[2 * (size_t)v] - p[0], dy = d->xy[2 * (size_t)v + 1] - p[1];
            L2 = fmax(L2, dx * dx + dy * dy);
        }
    if (n < 3 || !(L2 > 0)) return false;
    static double a[KN][KN + 1]; /* not on the stack: 4 KiB; the refinement runs on one thread */
    double g[FB_HULL_KRIGE_MAX];
    const int N = n + 3;
    for (int j = 0; j < n; j++) {
        const double *xj = d->xy + 2 * (size_t)out->v[j];
        for (int k = 0; k < n; k++) {
            const double *xk = d->xy + 2 * (size_t)out->v[k];
            double dx = xj[0] - xk[0], dy = xj[1] - xk[1];
            a[j][k] = j == k ? 0 : pow((dx * dx + dy * dy) / L2, H);
        }
        double dx = xj[0] - p[0], dy = xj[1] - p[1], s = sqrt(L2);
        a[j][n] = a[n][j] = 1, a[j][n + 1] = a[n + 1][j] = dx / s, a[j][n + 2] = a[n + 2][j] = dy / s;
        a[j][N] = g[j] = pow((dx * dx + dy * dy) / L2, H);
    }
    for (int r = n; r < N; r++) {
        for (int k = n; k < N; k++) a[r][k] = 0;
        a[r][N] = r == n ? 1 : 0;
    }
    if (!solve(a, N)) return false;
    double kv = 0;
    for (int j = 0; j < n; j++) out->w[j] = a[j][N] / a[j][j], kv += out->w[j] * g[j];
    kv += a[n][N] / a[n][n];
    out->n = n;
    out->kvar = kv * pow(L2, H);
    bool finite = isfinite(out->kvar);
    for (int j = 0; j < n; j++) finite = finite && isfinite(out->w[j]);
    return finite;
}
