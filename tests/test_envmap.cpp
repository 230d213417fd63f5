/*
 * kernels/envmap.h against OpenEXR's own environment-map functions (ImfEnvmap.h, the C++ library
 * libopenexr-dev ships): every pixel centre and sub-pixel sample of lat-long and cube maps of several
 * sizes gives the direction OpenEXR gives, every direction maps back to its position, and the
 * cube's edge pixels are shared between neighbouring faces as OpenEXR defines them.
 */
#include "kernels/envmap.h"

#include <ImfEnvmap.h>
#include <cmath>
#include <cstdio>

static int failures = 0;
#define CHECK(c)                                                                                                       \
    do {                                                                                                               \
        if (!(c)) {                                                                                                    \
            if (failures++ < 20) std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #c);            \
        }                                                                                                              \
    } while (0)

static double angle(Imath::V3f a, k_vec3 b)
{
    /* atan2(|a x b|, a . b) in double: accurate for small angles, where acos of a float dot is not */
    Imath::V3d x(a.x, a.y, a.z), y(b.x, b.y, b.z);
    return std::atan2((x % y).length(), x ^ y);
}

static void test_latlong(int w, int h)
{
    Imath::Box2i dw(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
    double worst = 0, worst_back = 0;
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++)
            for (int s = 0; s < 3; s++) {
                float px = i + (s - 1) * 0.37f, py = j + (s == 1 ? 0.0f : 0.29f);
                Imath::V3f ref = Imf::LatLongMap::direction(dw, Imath::V2f(px, py));
                k_vec3 d = k_env_latlong_dir(px, py, (uint)w, (uint)h);
                worst = std::fmax(worst, angle(ref, d));
                Imath::V2f rp = Imf::LatLongMap::pixelPosition(dw, ref);
                k_vec2 p = k_env_latlong_pos(d, (uint)w, (uint)h);
                if (j > 0 && j < h - 1) /* longitude is undefined at the poles */
                    worst_back = std::fmax(worst_back, std::fmax(std::fabs(p.x - rp.x), std::fabs(p.y - rp.y)));
            }
    CHECK(worst < 2e-6 * w);             /* float angles against float angles: a few ulp of 2 pi */
    CHECK(worst_back < 1e-5 * w + 1e-3); /* positions in pixels */
    /* The convention in words: top row +Y, longitude 0 (+Z) in the middle column, +pi/2 (+X) a
     * quarter in, +pi (-Z) at the left edge. */
    k_vec3 top = k_env_latlong_dir(0.3f * w, 0, w, h), mid = k_env_latlong_dir((w - 1) * 0.5f, (h - 1) * 0.5f, w, h);
    k_vec3 q = k_env_latlong_dir((w - 1) * 0.25f, (h - 1) * 0.5f, w, h),
           left = k_env_latlong_dir(0, (h - 1) * 0.5f, w, h);
    CHECK(h < 2 || top.y > 0.999999f);
    CHECK(mid.z > 0.999999f);
    CHECK(q.x > 0.999999f);
    CHECK(left.z < -0.999999f);
}

static void test_cube(int n)
{
    Imath::Box2i dw(Imath::V2i(0, 0), Imath::V2i(n - 1, 6 * n - 1));
    double worst = 0, worst_back = 0;
    int wrong_face = 0, shared = 0, edge = 0;
    for (int f = 0; f < 6; f++)
        for (int b = 0; b < n; b++)
            for (int a = 0; a < n; a++) {
                Imf::CubeMapFace face = (Imf::CubeMapFace)f;
                Imath::V2f pos = Imf::CubeMap::pixelPosition(face, dw, Imath::V2f(a, b));
                Imath::V3f ref = Imf::CubeMap::direction(face, dw, Imath::V2f(a, b));
                CHECK(k_env_cube_face(pos.y, (uint)n) == (uint)f);
                k_vec3 d = k_env_cube_dir(pos.x, pos.y, (uint)n);
                worst = std::fmax(worst, angle(ref, d));
                k_vec2 p = k_env_cube_pos_face(d, (uint)f, (uint)n);
                worst_back = std::fmax(worst_back, std::fmax(std::fabs(p.x - pos.x), std::fabs(p.y - pos.y)));
                Imf::CubeMapFace rf;
                Imath::V2f rpif;
                Imf::CubeMap::faceAndPixelPosition(ref, dw, rf, rpif);
                if (k_env_cube_face_of(d) != (uint)rf) wrong_face++;
                if (a == 0 || b == 0 || a == n - 1 || b == n - 1) {
                    /* an edge pixel's direction lies on the neighbouring face too, at one of its
                     * edge pixel centres */
                    edge++;
                    for (int g = 0; g < 6; g++) {
                        if (g == f || g / 2 == f / 2) continue;
                        k_vec2 q = k_env_cube_pos_face(d, (uint)g, (uint)n);
                        float m = g < 2 ? std::fabs(d.x) : g < 4 ? std::fabs(d.y) : std::fabs(d.z);
                        float sg = g < 2 ? d.x : g < 4 ? d.y : d.z;
                        if (m != 1.0f || (sg > 0) != (g % 2 == 0)) continue;
                        if (std::fabs(q.x - std::round(q.x)) < 1e-3 && std::fabs(q.y - std::round(q.y)) < 1e-3 &&
                            (int)std::round(q.y) / n == g)
                            shared++;
                    }
                }
            }
    CHECK(worst < 1e-6);
    CHECK(worst_back < 1e-4 * n);
    CHECK(wrong_face == 0);
    CHECK(n < 2 || shared >= edge); /* every edge pixel found on at least one neighbour */
    /* Sub-pixel samples beyond a face's edge continue its plane: the direction moves on smoothly */
    if (n > 2) {
        k_vec3 in = k_env_cube_dir_face(0.0f, 0.0f, K_CUBE_POS_X, (uint)n);
        k_vec3 out = k_env_cube_dir_face(-0.5f, -0.5f, K_CUBE_POS_X, (uint)n);
        CHECK(std::fabs(out.y) > std::fabs(in.y) - 1.0f / n && out.x == 1.0f);
    }
}

int main()
{
    for (int h : {1, 2, 3, 8, 31, 256}) test_latlong(2 * h, h);
    for (int n : {2, 3, 8, 33, 128}) test_cube(n);
    if (failures) std::fprintf(stderr, "%d failures\n", failures);
    return failures ? 1 : 0;
}
