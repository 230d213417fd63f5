/*
 * Environment-map pixel positions and directions on the unit sphere, in OpenEXR's convention
 * (ImfEnvmap.h, what `envmap` = latlong | cube means to every reader of the attribute).
 *
 * Positions are pixel coordinates in the image: pixel (i, j) has its centre at (i, j), so an
 * anti-aliasing sample at (i + dx, j + dy) with |dx|, |dy| <= 0.5 lies in that pixel's footprint.
 *
 * Lat-long (W x H, W = 2H): latitude  = -pi   (y / (H - 1) - 0.5), +pi/2 on the top row,
 *                           longitude = -2 pi (x / (W - 1) - 0.5), +pi on the left column,
 *   direction = (sin lon cos lat, sin lat, cos lon cos lat): +Y up, longitude 0 at +Z, pi/2 at +X.
 *   The top and bottom rows are the poles; the left and right columns are the same meridian.
 *
 * Cube (N x 6N): faces +X, -X, +Y, -Y, +Z, -Z stacked top to bottom, face f in rows [f N, f N + N).
 *   Within a face a position (a, b) in [0, N - 1]^2 maps to (a, b) / (N - 1) * 2 - 1 on the cube's
 *   face; a face's edge pixels lie on the cube's edges (shared with the neighbouring face), as
 *   ImfEnvmap.h defines. Each face is laid out in the image as ImfEnvmap's pixelPosition says.
 *
 * Directions need not be unit length (cube directions are not); callers normalise where needed.
 * Written in the common C/GLSL subset (common.h).
 */
#ifndef FB_KERNELS_ENVMAP_H
#define FB_KERNELS_ENVMAP_H

#include "common.h"
#include "exact.h"

#ifdef K_GLSL
#define k_env_atan2(y, x) atan(y, x)
#define k_env_asin(x)     asin(x)
#define k_env_acos(x)     acos(x)
#else
#define k_env_atan2(y, x) atan2f(y, x)
#define k_env_asin(x)     asinf(x)
#define k_env_acos(x)     acosf(x)
#endif

#define K_ENV_RECT    0u /* not an environment map: the plane */
#define K_ENV_LATLONG 1u
#define K_ENV_CUBE    2u

#define K_CUBE_POS_X 0u
#define K_CUBE_NEG_X 1u
#define K_CUBE_POS_Y 2u
#define K_CUBE_NEG_Y 3u
#define K_CUBE_POS_Z 4u
#define K_CUBE_NEG_Z 5u

/* Latitude (x) and longitude (y) of lat-long position (px, py) in a w x h image. */
K_FN k_vec2 k_env_latlong_angles(float px, float py, uint w, uint h)
{
    float lat = h > 1u ? -K_PI * (kx_div(py, K_F(h - 1u)) - 0.5f) : 0.0f;
    float lon = w > 1u ? -K_TAU * (kx_div(px, K_F(w - 1u)) - 0.5f) : 0.0f;
    return k_vec2(lat, lon);
}

K_FN k_vec3 k_env_latlong_dir(float px, float py, uint w, uint h)
{
    k_vec2 ll = k_env_latlong_angles(px, py, w, h);
    float cl = k_cos(ll.x);
    return k_vec3(k_sin(ll.y) * cl, k_sin(ll.x), k_cos(ll.y) * cl);
}

/* The lat-long position of direction d (any length but zero), as ImfEnvmap's latLong: the pole
 * rows for a direction along +-Y, longitude 0 where x = z = 0. */
K_FN k_vec2 k_env_latlong_pos(k_vec3 d, uint w, uint h)
{
    float len = kx_sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    float r = kx_sqrt(d.z * d.z + d.x * d.x);
    float lat =
        r < k_abs(d.y) ? k_env_acos(kx_div(r, len)) * (d.y < 0.0f ? -1.0f : 1.0f) : k_env_asin(kx_div(d.y, len));
    float lon = (d.z == 0.0f && d.x == 0.0f) ? 0.0f : k_env_atan2(d.x, d.z);
    float x = kx_div(lon, -K_TAU) + 0.5f;
    float y = kx_div(lat, -K_PI) + 0.5f;
    return k_vec2(x * K_F(w - 1u), y * K_F(h - 1u));
}

/* The face of cube-map row py (rows beyond the last face belong to the last). */
K_FN uint k_env_cube_face(float py, uint n)
{
    float f = k_floor(kx_div(py + 0.5f, K_F(n)));
    return K_U(k_clamp(f, 0.0f, 5.0f));
}

/* The direction through cube-map position (px, py) of face `face` (n x n faces): the inverse of
 * ImfEnvmap's pixelPosition, then its direction(). Positions a little outside the face (samples of
 * an edge pixel) continue the face's plane, so footprints stay contiguous across edges. */
K_FN k_vec3 k_env_cube_dir_face(float px, float py, uint face, uint n)
{
    float last = K_F(n - 1u);
    float y0 = K_F(face * n);
    float a, b; /* ImfEnvmap's positionInFace */
    if (face == K_CUBE_POS_X) {
        b = px;
        a = y0 + last - py;
    } else if (face == K_CUBE_NEG_X) {
        b = last - px;
        a = y0 + last - py;
    } else if (face == K_CUBE_NEG_Y) {
        a = px;
        b = py - y0;
    } else if (face == K_CUBE_POS_Z) {
        a = last - px;
        b = y0 + last - py;
    } else { /* +Y, -Z */
        a = px;
        b = y0 + last - py;
    }
    float s = n > 1u ? kx_div(a, last) * 2.0f - 1.0f : 0.0f;
    float t = n > 1u ? kx_div(b, last) * 2.0f - 1.0f : 0.0f;
    if (face == K_CUBE_POS_X) return k_vec3(1.0f, s, t);
    if (face == K_CUBE_NEG_X) return k_vec3(-1.0f, s, t);
    if (face == K_CUBE_POS_Y) return k_vec3(s, 1.0f, t);
    if (face == K_CUBE_NEG_Y) return k_vec3(s, -1.0f, t);
    if (face == K_CUBE_POS_Z) return k_vec3(s, t, 1.0f);
    return k_vec3(s, t, -1.0f);
}

K_FN k_vec3 k_env_cube_dir(float px, float py, uint n)
{
    return k_env_cube_dir_face(px, py, k_env_cube_face(py, n), n);
}

/* The face that direction d (not zero) falls on, as ImfEnvmap's faceAndPixelPosition chooses it. */
K_FN uint k_env_cube_face_of(k_vec3 d)
{
    float ax = k_abs(d.x), ay = k_abs(d.y), az = k_abs(d.z);
    if (ax >= ay && ax >= az) return d.x > 0.0f ? K_CUBE_POS_X : K_CUBE_NEG_X;
    if (ay >= az) return d.y > 0.0f ? K_CUBE_POS_Y : K_CUBE_NEG_Y;
    return d.z > 0.0f ? K_CUBE_POS_Z : K_CUBE_NEG_Z;
}

/* The image position of direction d on face `face` (d's projection onto that face's plane; d must
 * point into the face's half-space): the inverse of k_env_cube_dir_face. */
K_FN k_vec2 k_env_cube_pos_face(k_vec3 d, uint face, uint n)
{
    float last = K_F(n - 1u);
    float y0 = K_F(face * n);
    float m, u, v; /* major axis, then the face's two coordinates as ImfEnvmap orders them */
    if (face <= K_CUBE_NEG_X) {
        m = k_abs(d.x);
        u = d.y;
        v = d.z;
    } else if (face <= K_CUBE_NEG_Y) {
        m = k_abs(d.y);
        u = d.x;
        v = d.z;
    } else {
        m = k_abs(d.z);
        u = d.x;
        v = d.y;
    }
    float a = (kx_div(u, m) + 1.0f) * 0.5f * last;
    float b = (kx_div(v, m) + 1.0f) * 0.5f * last;
    if (face == K_CUBE_POS_X) return k_vec2(b, y0 + last - a);
    if (face == K_CUBE_NEG_X) return k_vec2(last - b, y0 + last - a);
    if (face == K_CUBE_NEG_Y) return k_vec2(a, y0 + b);
    if (face == K_CUBE_POS_Z) return k_vec2(last - a, y0 + last - b);
    return k_vec2(a, y0 + last - b); /* +Y, -Z */
}

K_FN k_vec2 k_env_cube_pos(k_vec3 d, uint n)
{
    return k_env_cube_pos_face(d, k_env_cube_face_of(d), n);
}

/* The direction through position (px, py) of an environment map of `mapping` sized w x h. */
K_FN k_vec3 k_env_dir(uint mapping, float px, float py, uint w, uint h)
{
    if (mapping == K_ENV_CUBE) return k_env_cube_dir(px, py, w);
    return k_env_latlong_dir(px, py, w, h);
}

#endif
