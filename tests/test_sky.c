/*
 * Skies as environment maps, the kernels against references written here in double precision:
 * kernels/sincos.h against libm; the Julia layer's lat-long and cube grids (every pixel's escape
 * count and distance estimate) against the stereographic projection of the pixel's direction
 * (envmap.h's directions, which tests/test_envmap.cpp checks against OpenEXR's), warped and iterated
 * in double; the poles' rows hold one value each and the lat-long seam's two columns agree. fBm on
 * the sphere: 3D cellular noise against a brute-force search, each pole row one value for every
 * noise kind and the seam's columns one meridian (their difference under 2% of neighbours'), the six cube faces alike
 * in variance and variogram over angular distance (over seeds, within 4 standard errors), and neighbours across the
 * lat-long seam and every cube edge no farther apart than neighbours inside a face.
 */
#include "../kernels/fbm.h"
#include "../kernels/julia.h"
#include "../kernels/sincos.h"

#include "testhelp.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static K_FbmParams g_turb; /* unused while lambda = 0 */

/* Within 2 ulp of 1 (2.4e-7) everywhere on [-4 pi, 4 pi]: Cephes' bound for its polynomials. */
static void test_sincos(void)
{
    double worst = 0;
    for (int i = -2000000; i <= 2000000; i++) {
        float x = (float)(i * (4.0 * M_PI / 2000000.0));
        k_vec2 sc = k_sincos(x);
        worst = fmax(worst, fmax(fabs(sc.x - sin((double)x)), fabs(sc.y - cos((double)x))));
    }
    CHECKF(worst <= 2.4e-7, "k_sincos: %.3g from libm's double sin and cos", worst);
}

static K_JuliaParams sky(uint mapping, int w, int h)
{
    K_JuliaParams p;
    memset(&p, 0, sizeof p);
    p.width = (uint)w, p.height = (uint)h;
    p.mapping = mapping;
    p.max_iter = 200;
    p.c_re = -0.76f, p.c_im = 0.2f;
    p.a_re = -0.3f, p.a_im = 0.1f;
    p.radius = 1.3f;
    p.center_re = 0.05f, p.center_im = -0.02f;
    double rot = 0.4;
    p.rot_c = (float)cos(rot), p.rot_s = (float)sin(rot);
    p.bailout2 = 4.0f;
    p.inv_width = 1.0f / (float)w, p.inv_height = 1.0f / (float)h;
    return p;
}

/* The reference: the direction of position (ex, ey) in double (the lat-long formulas of OpenEXR's
 * ImfEnvmap.h; a cube face's point on its plane), then p = r (d.x + i d.z) / (1 + d.y). */
static double complex ref_p(const K_JuliaParams *p, double ex, double ey)
{
    double d[3];
    if (p->mapping == K_JULIA_LATLONG) {
        double lat = -M_PI * (ey / (p->height - 1) - 0.5), lon = -2 * M_PI * (ex / (p->width - 1) - 0.5);
        d[0] = sin(lon) * cos(lat), d[1] = sin(lat), d[2] = cos(lon) * cos(lat);
    } else {
        /* the face's plane is linear in the position: c(ey) = c0 + (ey - y0) (c1 - c0) */
        double y0 = floor(ey + 0.5);
        uint face = k_env_cube_face((float)y0, p->width);
        k_vec3 c0 = k_env_cube_dir_face((float)ex, (float)y0, face, p->width);
        k_vec3 c1 = k_env_cube_dir_face((float)ex, (float)y0 + 1.0f, face, p->width);
        double t = ey - y0;
        d[0] = c0.x + t * (c1.x - c0.x), d[1] = c0.y + t * (c1.y - c0.y), d[2] = c0.z + t * (c1.z - c0.z);
        double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int k = 0; k < 3; k++) d[k] /= len;
    }
    return p->radius * (d[0] + I * d[2]) / (1 + d[1]);
}

static double complex ref_z0(const K_JuliaParams *p, double ex, double ey)
{
    double complex q = ref_p(p, ex, ey), a = p->a_re + I * p->a_im;
    q = (p->center_re + I * p->center_im) + (p->rot_c + I * p->rot_s) * q;
    return (q - conj(a)) / (1 - a * q);
}

typedef struct ref_result {
    int iter;
    double de; /* in pixels along the column; 0 inside */
} ref_result;

/* The orbit in double, dz0/dy by a central difference of z0, continued to |z| = 2^16 as the kernel. */
static ref_result ref_orbit(const K_JuliaParams *p, double ex, double ey)
{
    const double h = 1e-4;
    double complex z = ref_z0(p, ex, ey), c = p->c_re + I * p->c_im;
    double complex dz = (ref_z0(p, ex, ey + h) - ref_z0(p, ex, ey - h)) / (2 * h);
    ref_result r = {0, 0};
    while (r.iter < (int)p->max_iter && cabs(z) * cabs(z) < p->bailout2) {
        dz = 2 * z * dz;
        z = z * z + c;
        r.iter++;
    }
    if (cabs(z) * cabs(z) < p->bailout2) return r;
    for (int j = 0; j < 64 && cabs(z) * cabs(z) <= 4294967296.0; j++) {
        dz = 2 * z * dz;
        z = z * z + c;
    }
    r.de = cabs(z) * log(cabs(z)) / cabs(dz);
    return r;
}

/* Every pixel's escape count as the reference's but on the boundary (float and double orbits part
 * there: 1% allowed), and the distance estimate within 1% where both escaped with the same count
 * and the distance is over a tenth of a pixel (nearer, the first-order estimate's own error). */
static void test_julia_map(uint mapping, int w, int h)
{
    K_JuliaParams p = sky(mapping, w, h);
    int n = 0, iter_bad = 0, de_n = 0, de_bad = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++, n++) {
            K_JuliaResult k = k_julia_pixel(p, g_turb, (uint)x, (uint)y);
            ref_result r = ref_orbit(&p, x, y);
            if ((int)k.iter != r.iter) {
                iter_bad++;
                continue;
            }
            if (k.inside || r.de < 0.1) continue;
            de_n++;
            de_bad += fabs(k.de - r.de) > 0.01 * r.de;
        }
    CHECKF(iter_bad <= n / 100, "%s %dx%d: %d of %d escape counts differ from the reference",
           mapping == K_JULIA_CUBE ? "cube" : "latlong", w, h, iter_bad, n);
    CHECKF(de_n > n / 4 && de_bad <= de_n / 100, "%s %dx%d: %d of %d distances beyond 1%% of the reference",
           mapping == K_JULIA_CUBE ? "cube" : "latlong", w, h, de_bad, de_n);
}

/* The lat-long map's top row is the zenith, the point p = centre; its bottom row the nadir, the point
 * at infinity, z0 = -1/a: each row one orbit. Its first and last columns are the same meridian. */
static void test_poles_seam(void)
{
    enum { W = 256, H = 128 };
    K_JuliaParams p = sky(K_JULIA_LATLONG, W, H);
    K_JuliaResult top = k_julia_pixel(p, g_turb, 0, 0), bottom = k_julia_pixel(p, g_turb, 0, H - 1);
    int row_bad = 0, seam_bad = 0;
    for (int x = 1; x < W; x++) {
        K_JuliaResult t = k_julia_pixel(p, g_turb, (uint)x, 0), b = k_julia_pixel(p, g_turb, (uint)x, H - 1);
        row_bad += t.iter != top.iter || fabsf(t.nsmooth - top.nsmooth) > 1e-4f;
        row_bad += b.iter != bottom.iter || fabsf(b.nsmooth - bottom.nsmooth) > 1e-4f;
    }
    CHECKF(row_bad == 0, "%d pole-row pixels differ from their row's first", row_bad);
    ref_result zt = ref_orbit(&p, 0, 0);
    CHECKF((int)top.iter == zt.iter, "zenith: %u iterations, the centre's orbit %d", top.iter, zt.iter);
    /* the nadir: z0 = -1/a exactly, so its count is that of the orbit of -1/a */
    double complex z = -1 / (p.a_re + I * p.a_im), c = p.c_re + I * p.c_im;
    int it = 0;
    while (it < (int)p.max_iter && cabs(z) * cabs(z) < 4) z = z * z + c, it++;
    CHECKF((int)bottom.iter == it, "nadir: %u iterations, -1/a's orbit %d", bottom.iter, it);
    for (int y = 0; y < H; y++) {
        K_JuliaResult l = k_julia_pixel(p, g_turb, 0, (uint)y), r = k_julia_pixel(p, g_turb, W - 1, (uint)y);
        seam_bad += l.iter != r.iter;
    }
    CHECKF(seam_bad <= 1, "the seam: %d of %d rows differ between the first and last columns", seam_bad, H);
}

/* ---- fBm on the sphere ---------------------------------------------------------------------- */

static K_FbmParams fbm_env(uint mapping, int w, int h, uint noise, uint seed)
{
    K_FbmParams p;
    memset(&p, 0, sizeof p);
    p.seed = seed, p.noise = noise, p.octaves = 6, p.gain = 0.5f, p.lacunarity = 2.0f;
    p.rot_c = 0.8f, p.rot_s = 0.6f;
    p.freq_x = p.freq_y = 6.0f;
    p.width = (uint)w, p.height = (uint)h, p.mapping = mapping;
    p.inv_width = 1.0f / (float)w, p.inv_height = 1.0f / (float)h;
    p.inv_freq_x = p.inv_freq_y = 1.0f / p.freq_x;
    return p;
}

/* F1 and F2 of the 5 x 5 x 5 search with skipping against every point of the 7 x 7 x 7 block. */
static void test_cellular3(void)
{
    int bad = 0;
    uint32_t st = 1;
    for (int i = 0; i < 200000; i++) {
        float q[3];
        for (int k = 0; k < 3; k++) st = st * 1664525u + 1013904223u, q[k] = (float)(st >> 8) / 16777216.0f * 40 - 20;
        k_vec2 f = k_cellular3(77u, k_vec3(q[0], q[1], q[2]));
        double f1 = 1e9, f2 = 1e9;
        float fl[3] = {floorf(q[0]), floorf(q[1]), floorf(q[2])};
        for (int dz = -3; dz <= 3; dz++)
            for (int dy = -3; dy <= 3; dy++)
                for (int dx = -3; dx <= 3; dx++) {
                    uint P = K_NOISE_PERIOD;
                    uint h =
                        k_hash3i(77u, k_cell_add(k_wrap_cell(fl[0], P), dx, P),
                                 k_cell_add(k_wrap_cell(fl[1], P), dy, P), k_cell_add(k_wrap_cell(fl[2], P), dz, P));
                    uint h2 = k_hash(h);
                    double ox = dx + (double)k_u01(h) - (q[0] - fl[0]), oy = dy + (double)k_u01(h2) - (q[1] - fl[1]);
                    double oz = dz + (double)k_u01(k_hash(h2)) - (q[2] - fl[2]);
                    double d2 = ox * ox + oy * oy + oz * oz;
                    if (d2 < f1)
                        f2 = f1, f1 = d2;
                    else if (d2 < f2)
                        f2 = d2;
                }
        bad += fabs(f.x - sqrt(f1)) > 1e-5 || fabs(f.y - sqrt(f2)) > 1e-5;
    }
    CHECKF(bad == 0, "3D cellular: %d of 200000 queries miss the nearest points", bad);
}

/* Each pole row of a lat-long fBm is one point: its spread is below 1e-4 while the image's standard
 * deviation is above 0.05, for every noise kind; the seam's two columns are one meridian. */
static void test_fbm_poles(void)
{
    enum { W = 256, H = 128 };
    for (uint kind = 0; kind < K_NOISE_COUNT; kind++) {
        K_FbmParams p = fbm_env(K_ENV_LATLONG, W, H, kind, 5u);
        double s = 0, s2 = 0, spread = 0, seam = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double v = k_fbm_map_pixel(p, (uint)x, (uint)y);
                s += v, s2 += v * v;
            }
        double sd = sqrt(s2 / (W * H) - (s / (W * H)) * (s / (W * H)));
        for (int row = 0; row < H; row += H - 1) {
            float lo = 1e9f, hi = -1e9f;
            for (int x = 0; x < W; x++) {
                float v = k_fbm_map_pixel(p, (uint)x, (uint)row);
                lo = fminf(lo, v), hi = fmaxf(hi, v);
            }
            spread = fmax(spread, hi - lo);
        }
        double step = 0; /* the mean difference between neighbours along a row */
        for (int y = 0; y < H; y++) {
            seam = fmax(seam, fabsf(k_fbm_map_pixel(p, 0, (uint)y) - k_fbm_map_pixel(p, W - 1, (uint)y)));
            for (int x = 0; x + 1 < W; x++)
                step += fabsf(k_fbm_map_pixel(p, (uint)x + 1, (uint)y) - k_fbm_map_pixel(p, (uint)x, (uint)y));
        }
        step /= (double)H * (W - 1);
        CHECKF(sd > 0.05 && spread < 1e-4 && seam < 0.02 * step,
               "noise %u: pole rows spread %g, seam %g (neighbours %g), image sd %g", kind, spread, seam, step, sd);
    }
}

static double angle_between(k_vec3 a, k_vec3 b)
{
    double cx = (double)a.y * b.z - (double)a.z * b.y, cy = (double)a.z * b.x - (double)a.x * b.z;
    double cz = (double)a.x * b.y - (double)a.y * b.x;
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z);
}

/* The six faces of a cube fBm, over S seeds: each face's mean square and its variogram in four bins of
 * angular distance (pairs 1 to 4 pixels apart along a row of the face) against the other faces'
 * mean, within 4 standard errors of the seeds' spread. */
static void test_fbm_faces(void)
{
    enum { N = 40, S = 16, NB = 4 };
    static const double edges[NB + 1] = {0.015, 0.03, 0.06, 0.12, 0.2};
    static double stat[S][6][NB + 1];
    memset(stat, 0, sizeof stat);
    for (int sd = 0; sd < S; sd++) {
        K_FbmParams p = fbm_env(K_ENV_CUBE, N, 6 * N, K_NOISE_GRADIENT, 100u + (uint)sd);
        static float img[6 * N][N];
        for (int y = 0; y < 6 * N; y++)
            for (int x = 0; x < N; x++) img[y][x] = k_fbm_map_pixel(p, (uint)x, (uint)y);
        for (int f = 0; f < 6; f++) {
            double sum[NB] = {0}, cnt[NB] = {0}, sq = 0;
            for (int y = f * N; y < f * N + N; y++)
                for (int x = 0; x < N; x++) {
                    sq += (double)img[y][x] * img[y][x];
                    k_vec3 a = k_env_cube_dir((float)x, (float)y, N);
                    for (int k = 1; k <= 4 && x + k < N; k++) {
                        double t = angle_between(a, k_env_cube_dir((float)(x + k), (float)y, N));
                        for (int b = 0; b < NB; b++)
                            if (t >= edges[b] && t < edges[b + 1]) {
                                double d = (double)img[y][x + k] - img[y][x];
                                sum[b] += d * d, cnt[b]++;
                            }
                    }
                }
            stat[sd][f][0] = sq / (N * N);
            for (int b = 0; b < NB; b++) stat[sd][f][b + 1] = cnt[b] > 0 ? 0.5 * sum[b] / cnt[b] : 0;
        }
    }
    int worst_face = -1;
    double worst = 0;
    for (int m = 0; m <= NB; m++)
        for (int f = 0; f < 6; f++) {
            /* the seed-wise difference between this face and the mean of the other five */
            double s = 0, s2 = 0;
            for (int sd = 0; sd < S; sd++) {
                double others = 0;
                for (int g = 0; g < 6; g++) others += g == f ? 0 : stat[sd][g][m] / 5;
                double d = stat[sd][f][m] - others;
                s += d, s2 += d * d;
            }
            double mean = s / S, se = sqrt(fmax(s2 / S - mean * mean, 1e-300) / (S - 1));
            double z = fabs(mean) / se;
            if (z > worst) worst = z, worst_face = f * 10 + m;
        }
    CHECKF(worst <= 4.0, "cube faces: face %d statistic %d is %.2f standard errors from the others", worst_face / 10,
           worst_face % 10, worst);
}

/* Neighbours across every cube edge (a face's edge pixel and the pixel one step beyond it, found on
 * the neighbouring face) differ by no more per radian than neighbours inside the faces: the edges'
 * mean |difference| / angle within 4 standard errors above the interior's. */
static void test_fbm_edges(void)
{
    enum { N = 64 };
    K_FbmParams p = fbm_env(K_ENV_CUBE, N, 6 * N, K_NOISE_GRADIENT, 9u);
    double in_s = 0, in_n = 0, e_s = 0, e_s2 = 0, e_n = 0;
    for (int f = 0; f < 6; f++)
        for (int y = f * N; y < f * N + N; y++)
            for (int x = 0; x < N; x++) {
                float v = k_fbm_map_pixel(p, (uint)x, (uint)y);
                k_vec3 a = k_env_cube_dir((float)x, (float)y, N);
                if (x + 1 < N) {
                    float w = k_fbm_map_pixel(p, (uint)x + 1, (uint)y);
                    in_s += fabs((double)w - v) / angle_between(a, k_env_cube_dir((float)x + 1, (float)y, N)), in_n++;
                }
                bool edge = x == 0 || x == N - 1 || y == f * N || y == f * N + N - 1;
                if (!edge) continue;
                /* one pixel outward, continuing the face's plane, lands on the neighbouring face */
                float ox = x == 0 ? -1.0f : x == N - 1 ? (float)N : (float)x;
                float oy = y == f * N ? (float)y - 1.0f : y == f * N + N - 1 ? (float)y + 1.0f : (float)y;
                k_vec3 out = k_env_cube_dir_face(ox, oy, (uint)f, N);
                k_vec2 q = k_env_cube_pos(out, N);
                int qx = (int)lroundf(q.x), qy = (int)lroundf(q.y);
                if (qy / N == f) continue;
                k_vec3 b = k_env_cube_dir((float)qx, (float)qy, N);
                double t = angle_between(a, b);
                if (t < 1e-6) continue;
                double r = fabs((double)k_fbm_map_pixel(p, (uint)qx, (uint)qy) - v) / t;
                e_s += r, e_s2 += r * r, e_n++;
            }
    double in_mean = in_s / in_n, e_mean = e_s / e_n, e_se = sqrt((e_s2 / e_n - e_mean * e_mean) / (e_n - 1));
    CHECKF(e_n > 12 * (N - 2) && e_mean <= in_mean + 4 * e_se,
           "cube edges: %.0f pairs, mean |d|/angle %.4g against %.4g inside (se %.3g)", e_n, e_mean, in_mean, e_se);
}

/* A lat-long map resampled from the cube bake of the same fBm (bilinear within the face that each
 * direction falls on) against the lat-long bake itself: the RMS difference under half the cube's
 * RMS difference between neighbouring pixels (what bilinear resampling at the cube's spacing leaves;
 * a face turned or mirrored gives about the field's deviation), for every noise kind but sine. */
static void test_resample(void)
{
    enum { N = 96, W = 256, H = 128 };
    static float cube[6 * N][N];
    for (uint kind = 0; kind < K_NOISE_SINE; kind++) {
        K_FbmParams pc = fbm_env(K_ENV_CUBE, N, 6 * N, kind, 3u), pl = fbm_env(K_ENV_LATLONG, W, H, kind, 3u);
        double nb = 0, nbn = 0, err = 0;
        for (int y = 0; y < 6 * N; y++)
            for (int x = 0; x < N; x++) cube[y][x] = k_fbm_map_pixel(pc, (uint)x, (uint)y);
        for (int y = 0; y < 6 * N; y++)
            for (int x = 0; x + 1 < N; x++) nb += (cube[y][x + 1] - cube[y][x]) * (cube[y][x + 1] - cube[y][x]), nbn++;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                k_vec2 q = k_env_cube_pos(k_env_latlong_dir((float)x, (float)y, W, H), N);
                int f = (int)k_env_cube_face(q.y, N);
                float fx = fminf(fmaxf(q.x, 0.0f), N - 1.0f), fy = fminf(fmaxf(q.y, (float)(f * N)), f * N + N - 1.0f);
                int x0 = (int)fminf(floorf(fx), N - 2.0f), y0 = (int)fminf(floorf(fy), f * N + N - 2.0f);
                float tx = fx - x0, ty = fy - y0;
                double v = (1 - ty) * ((1 - tx) * cube[y0][x0] + tx * cube[y0][x0 + 1]) +
                           ty * ((1 - tx) * cube[y0 + 1][x0] + tx * cube[y0 + 1][x0 + 1]);
                double d = v - k_fbm_map_pixel(pl, (uint)x, (uint)y);
                err += d * d;
            }
        double rms = sqrt(err / (W * H)), step = sqrt(nb / nbn);
        CHECKF(rms <= 0.5 * step, "noise %u: lat-long from the cube %.3g RMS from the lat-long bake (neighbours %.3g)",
               kind, rms, step);
    }
}

int main(void)
{
    test_sincos();
    test_julia_map(K_JULIA_LATLONG, 240, 120);
    test_julia_map(K_JULIA_LATLONG, 130, 65);
    test_julia_map(K_JULIA_CUBE, 48, 288);
    test_poles_seam();
    test_cellular3();
    test_fbm_poles();
    test_fbm_faces();
    test_fbm_edges();
    test_resample();
    TEST_REPORT();
}
