/*
 * Skies as environment maps, the kernels against references written here in double precision:
 * kernels/sincos.h against libm; the Julia layer's lat-long and cube grids (every pixel's escape
 * count and distance estimate) against the stereographic projection of the pixel's direction
 * (envmap.h's directions, which tests/test_envmap.cpp checks against OpenEXR's), warped and iterated
 * in double; the poles' rows hold one value each and the lat-long seam's two columns agree.
 */
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

int main(void)
{
    test_sincos();
    test_julia_map(K_JULIA_LATLONG, 240, 120);
    test_julia_map(K_JULIA_LATLONG, 130, 65);
    test_julia_map(K_JULIA_CUBE, 48, 288);
    test_poles_seam();
    TEST_REPORT();
}
