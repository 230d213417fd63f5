/*
 * Warped Julia sets for night skies (SPEC.md section 2, seed 003).
 *
 *   (7)  rectangular: p = s_u (u - 0.5) + i s_v (v - 0.5)      (then rotated and centred)
 *   (8)  polar:       p = r v exp(i 2 pi u)                     t(0, v) = t(1, v): seamless
 *   (11) z_0 = A(p^-1) = (p - conj(a)) / (1 - a p),  z_{n+1} = z_n^2 + c
 * and on the sphere (environment maps, kernels/envmap.h), the direction d of a pixel through the
 * stereographic projection from the nadir: p = r (d.x + i d.z) / (1 + d.y), so that the allpass
 * warp stays a Moebius map, the upper hemisphere is the polar disc |p| <= r (zenith: the centre,
 * horizon: the rim), and the nadir is the point at infinity.
 *
 * Per pixel: the escape count at the user's bailout R (`iter`), a smooth count that does not depend
 * on R, whether the orbit stayed bounded for max_iter steps, and a distance estimate in pixels.
 */
#ifndef FB_KERNELS_JULIA_H
#define FB_KERNELS_JULIA_H

#include "explog.h"
#include "fbm.h"
#if K_WITH_ENVMAP
#include "sincos.h"
#endif
#include "hash.h"

#define K_JULIA_RECT    0u
#define K_JULIA_POLAR   1u
#define K_JULIA_LATLONG 2u /* environment maps: envmap.h's positions, each pixel a direction */
#define K_JULIA_CUBE    3u

/* Orbits continue past R until |z| > 2^16 for the smooth count and the distance estimate, where
 * ln|z_{n+1}| = 2 ln|z_n| holds to 1e-9 and the smooth value no longer depends on the radius. */
#define K_JULIA_BIG_RADIUS2 4294967296.0f
#define K_JULIA_EXTRA_ITER  64u

K_STRUCT(K_JuliaParams)
{
    uint width;
    uint height;
    uint mapping;  /* K_JULIA_RECT, _POLAR, _LATLONG or _CUBE */
    uint max_iter; /* >= 1 */
    float c_re, c_im;
    float a_re, a_im;       /* allpass alpha; 0 is the plain Julia set */
    float scale_u, scale_v; /* rect: s_u, s_v */
    float radius;           /* polar, latlong, cube: r */
    float center_re, center_im;
    float rot_c, rot_s; /* rotation of the starting grid (host-computed cos, sin) */
    float bailout2;     /* R^2, R >= 2 */
    float inv_width, inv_height;
    float lambda;    /* turbulence strength (eq. 13); 0 disables */
    float turb_norm; /* 1 / sum of the turbulence octaves' gains: maps fBm to [-1, 1] */
}
K_END(K_JuliaParams)

K_STRUCT(K_JuliaResult)
{
    uint iter;     /* iterations before |z| >= R; max_iter if it never did */
    uint inside;   /* 1 if the orbit stayed within R for max_iter iterations */
    float nsmooth; /* n + 1 - log2(ln |z_n|) at the big radius; max_iter for inside points */
    float de;      /* distance estimate |z| ln|z| / |z'| in pixels; 0 inside */
}
K_END(K_JuliaResult)

/* An orbit's state: z and the squared magnitude dz2 = |z'|^2 of its derivative z' with respect to
 * the pixel coordinate. The distance estimate needs only |z'|, and since z'_{k+1} = 2 z_k z'_k,
 * |z'_{k+1}|^2 = 4 |z_k|^2 |z'_k|^2: a real running product of the |z_k|^2 that the bailout test
 * computes anyway (two multiplies a step instead of a complex multiply).
 * Range: dz2 overflows to +inf where |z'| > 1.8e19, where the complex z' of before gave an
 * infinite |z'|^2 = dzr^2 + dzi^2 at the end; inf stays inf (or NaN from inf * 0 if z is exactly 0),
 * and the distance is then 0, never non-finite, as before. dz2 underflows where |z'| < 1.1e-19 (a
 * subnormal below that): the end's dzr^2 + dzi^2 did too, but now a minimum of |z'| along the orbit
 * counts as well, which takes an orbit within about 1e-8 of the critical point 0 (the distance
 * there is ill-conditioned anyway). */
K_STRUCT(K_JuliaZ)
{
    float zr, zi, dz2;
}
K_END(K_JuliaZ)

/* One step: |z'|^2 <- 4 |z|^2 |z'|^2, z <- z^2 + c, where r2 = |z|^2 = zr^2 + zi^2 of this z as the
 * bailout test computes it (so the step multiplies by |z_k|^2 of the z it squares). precise: an
 * orbit is chaotic, so one fused rounding would change the escape count of boundary pixels between
 * a device and C. */
K_FN K_JuliaZ k_julia_step(K_JuliaZ o, float r2, float c_re, float c_im)
{
    K_PRECISE K_JuliaZ r;
    r.dz2 = o.dz2 * (4.0f * r2);
    r.zr = o.zr * o.zr - o.zi * o.zi + c_re;
    r.zi = 2.0f * o.zr * o.zi + c_im;
    return r;
}

/* The starting point p for texture coordinates (u, v), and dp/dx (per pixel) as a complex number. */
K_FN k_vec2 k_julia_start(K_JuliaParams p, float u, float v)
{
    K_PRECISE float x, y;
    if (p.mapping == K_JULIA_POLAR) {
        float rr = p.radius * v;
        /* wrapping u first makes t(0, v) = t(1, v) exactly: 2 pi * 1.0f is not 2 pi in float */
        float ang = K_TAU * (u - k_floor(u));
        k_vec2 sc = k_sincos(ang); /* sincos.h: the same bits on every device */
        x = rr * sc.y;
        y = rr * sc.x;
    } else {
        x = p.scale_u * (u - 0.5f);
        y = p.scale_v * (v - 0.5f);
    }
    K_PRECISE float sx = p.center_re + (p.rot_c * x - p.rot_s * y);
    K_PRECISE float sy = p.center_im + (p.rot_s * x + p.rot_c * y);
    return k_vec2(sx, sy);
}

K_FN k_vec2 k_julia_dstart(K_JuliaParams p, float u, float v)
{
    float dx, dy;
    if (p.mapping == K_JULIA_POLAR) {
        /* d/dx of r v exp(i 2 pi u), u = (x + 0.5)/W: i 2 pi r v exp(i 2 pi u) / W */
        float k = K_TAU * p.radius * v * p.inv_width;
        float ang = K_TAU * (u - k_floor(u));
        k_vec2 sc = k_sincos(ang);
        dx = -k * sc.x;
        dy = k * sc.y;
    } else {
        dx = p.scale_u * p.inv_width;
        dy = 0.0f;
    }
    return k_vec2(p.rot_c * dx - p.rot_s * dy, p.rot_s * dx + p.rot_c * dy);
}

/* What an orbit must produce beyond the escape count: the smooth count (also what colour needs)
 * and the distance estimate. Channels a layer does not store are not computed; what is computed is
 * the same to the bit whatever else is. */
#define K_JULIA_WANT_SMOOTH 1u
#define K_JULIA_WANT_DE     2u
#define K_JULIA_WANT_ALL    3u

/* z without its derivative: the same z, to the bit, as k_julia_step. */
K_FN K_JuliaZ k_julia_step_z(K_JuliaZ o, float c_re, float c_im)
{
    K_PRECISE K_JuliaZ r = o;
    r.zr = o.zr * o.zr - o.zi * o.zi + c_re;
    r.zi = 2.0f * o.zr * o.zi + c_im;
    return r;
}

/* r2: |z|^2 of o, zr^2 + zi^2 (used only for the distance) */
K_FN K_JuliaZ k_julia_advance(K_JuliaZ o, float r2, float c_re, float c_im, uint want)
{
    return (want & K_JULIA_WANT_DE) != 0u ? k_julia_step(o, r2, c_re, c_im) : k_julia_step_z(o, c_re, c_im);
}

/* An orbit's start: z0 and |dz0/dx|^2; ok = 0 where it escapes before the first iteration. */
K_STRUCT(K_JuliaStart)
{
    K_JuliaZ o;
    uint ok;
}
K_END(K_JuliaStart)

/* z0 = (nr + i ni) / (dr + i di) + tw and dz0 = (1 - |a|^2) (qr + i qi) / (dr + i di)^2: the allpass
 * warp's value and derivative from its numerator and denominator (q: the derivative of its argument,
 * times what the form needs); the orbit keeps |dz0|^2. A zero denominator is the pole: the point at infinity, outside
 * every filled Julia set, so the pixel escapes before the first iteration and nothing non-finite reaches the output. */
K_FN K_JuliaStart k_julia_quotient(K_JuliaParams p, float nr, float ni, float dr, float di, float qr, float qi,
                                   float tw_re, float tw_im)
{
    K_PRECISE K_JuliaStart s;
    s.ok = 0u;
    s.o.zr = 0.0f;
    s.o.zi = 0.0f;
    s.o.dz2 = 0.0f;
    K_PRECISE float den = dr * dr + di * di;
    if (!(den > 1.0e-30f)) return s;
    float inv = kx_div(1.0f, den);
    /* precise: an orbit is chaotic, so one fused rounding would change the escape count of
     * boundary pixels between a device and C. */
    K_PRECISE float zr = (nr * dr + ni * di) * inv + tw_re;
    K_PRECISE float zi = (ni * dr - nr * di) * inv + tw_im;
    float k = 1.0f - (p.a_re * p.a_re + p.a_im * p.a_im);
    float sr = (dr * dr - di * di) * inv * inv, si = -2.0f * dr * di * inv * inv; /* 1 / den^2 */
    float wr = k * sr, wi = k * si;
    K_PRECISE float dzr = wr * qr - wi * qi;
    K_PRECISE float dzi = wr * qi + wi * qr;
    s.o.zr = zr;
    s.o.zi = zi;
    s.o.dz2 = dzr * dzr + dzi * dzi;
    s.ok = zr * zr + zi * zi < 1.0e30f ? 1u : 0u;
    return s;
}

/* (tw_re, tw_im): the turbulence term lambda W(p) added to z0 (eq. 13); 0 for none.
 * z0 = (p - conj(a)) / (1 - a p); dz0/dx = (1 - |a|^2) / (1 - a p)^2 * dp/dx */
K_FN K_JuliaStart k_julia_begin(K_JuliaParams p, float px, float py, float dpx, float dpy, float tw_re, float tw_im)
{
    K_PRECISE float nr = px - p.a_re;
    K_PRECISE float ni = py + p.a_im;
    K_PRECISE float dr = 1.0f - (p.a_re * px - p.a_im * py);
    K_PRECISE float di = -(p.a_re * py + p.a_im * px);
    return k_julia_quotient(p, nr, ni, dr, di, dpx, dpy, tw_re, tw_im);
}

/* lambda W from the turbulence's two fBm values f1, f2 (streams 1 and 2, each a sum of octaves
 * that turb_norm maps to [-1, 1]): W = clamp(0.5 + 0.5 turb_norm f, 0, 1) in each component. */
K_FN k_vec2 k_julia_turbulence_of(K_JuliaParams p, float f1, float f2)
{
    float wr = k_clamp(0.5f + 0.5f * p.turb_norm * f1, 0.0f, 1.0f);
    float wi = k_clamp(0.5f + 0.5f * p.turb_norm * f2, 0.0f, 1.0f);
    return k_vec2(p.lambda * wr, p.lambda * wi);
}

/* ---- environment maps: the grid from directions ---------------------------------------------- */

#if K_WITH_ENVMAP
/* A pixel's point of the plane in homogeneous form, p = N / D (D = 0: the point at infinity), with
 * G = N' D - N D' (the derivative along the image's columns, per pixel of y: p' = G / D^2), and its
 * unit direction d (for the turbulence). On a lat-long map the column is a meridian, whose pixels
 * are the same arc pi / (H - 1) apart everywhere (a row's pixels crowd towards the poles), so the
 * distance estimate in pixels is the smaller of the two; on a cube, the face's column. */
K_STRUCT(K_JuliaHom)
{
    float nr, ni, d, gr, gi;
    k_vec3 dir;
}
K_END(K_JuliaHom)

/* Lat-long: p = r e tan(b), e = sin(lon) + i cos(lon) (the direction of d.x + i d.z), b = pi/4 - lat/2
 * = (pi/2) y / (H - 1) from the zenith; N = r e sin(b), D = cos(b) = sin(pi/2 - b), both from
 * their own small arguments, so that D keeps its relative precision towards the nadir; then
 * G = r e db/dy. A sample beyond a pole (b < 0 or b > pi/2) continues over it. Cube: N = r (c.x + i
 * c.z), D = |c| + c.y for the face point c (D computed as (c.x^2 + c.z^2) / (|c| - c.y) below the
 * horizon, without cancellation), G from one pixel's step down the face. */
K_FN K_JuliaHom k_julia_env_point(K_JuliaParams p, float ex, float ey)
{
    K_PRECISE K_JuliaHom h;
    if (p.mapping == K_JULIA_LATLONG) {
        k_vec2 ll = k_env_latlong_angles(ex, ey, p.width, p.height);
        k_vec2 lon = k_sincos(ll.y), lat = k_sincos(ll.x);
        float so = lon.x, co = lon.y;
        float k = p.height > 1u ? kx_div(0.5f * K_PI, K_F(p.height - 1u)) : 0.0f; /* db/dy */
        K_PRECISE float b = k * ey, g = k * (K_F(p.height - 1u) - ey);
        K_PRECISE float sb = k_sincos(b).x;
        h.nr = p.radius * so * sb;
        h.ni = p.radius * co * sb;
        h.d = k_sincos(g).x;
        h.gr = p.radius * so * k;
        h.gi = p.radius * co * k;
        h.dir = k_vec3(so * lat.y, lat.x, co * lat.y);
        return h;
    }
    uint face = k_env_cube_face(ey, p.width);
    k_vec3 c = k_env_cube_dir_face(ex, ey, face, p.width);
    k_vec3 c1 = k_env_cube_dir_face(ex, ey + 1.0f, face, p.width);
    K_PRECISE float len = kx_sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    K_PRECISE float q = c.x * c.x + c.z * c.z;
    K_PRECISE float D = c.y >= 0.0f ? len + c.y : kx_div(q, len - c.y);
    K_PRECISE float gx = c1.x - c.x, gy = c1.y - c.y, gz = c1.z - c.z;
    K_PRECISE float dD = kx_div(c.x * gx + c.y * gy + c.z * gz, len) + gy; /* D' */
    h.nr = p.radius * c.x;
    h.ni = p.radius * c.z;
    h.d = D;
    h.gr = p.radius * (gx * D - c.x * dD);
    h.gi = p.radius * (gz * D - c.z * dD);
    h.dir = k_vec3(kx_div(c.x, len), kx_div(c.y, len), kx_div(c.z, len));
    return h;
}

/* The orbit's start at a pixel's point p = N / D: the rotation R and centre c, then z0 = A(p),
 * written homogeneously (times D) so that the nadir, D = 0, is the point at infinity without a
 * division by zero: z0 = num / den with
 *   num = R N + (c - conj(a)) D,   den = (1 - a c) D - a R N,
 * so the nadir gives z0 = -1/a (for a = 0: infinity, which escapes at once), and
 *   dz0/dy = A'(p) R p' = (1 - |a|^2) R G / den^2.
 * (tw_re, tw_im): the turbulence term added to z0. */
K_FN K_JuliaStart k_julia_env_begin(K_JuliaParams p, K_JuliaHom e, float tw_re, float tw_im)
{
    K_PRECISE float D = e.d;
    K_PRECISE float pr = p.rot_c * e.nr - p.rot_s * e.ni, pi = p.rot_s * e.nr + p.rot_c * e.ni; /* R N */
    K_PRECISE float nr = pr + (p.center_re - p.a_re) * D;
    K_PRECISE float ni = pi + (p.center_im + p.a_im) * D;
    K_PRECISE float acr = 1.0f - (p.a_re * p.center_re - p.a_im * p.center_im); /* 1 - a c */
    K_PRECISE float aci = -(p.a_re * p.center_im + p.a_im * p.center_re);
    K_PRECISE float dr = acr * D - (p.a_re * pr - p.a_im * pi);
    K_PRECISE float di = aci * D - (p.a_re * pi + p.a_im * pr);
    float qr = p.rot_c * e.gr - p.rot_s * e.gi, qi = p.rot_s * e.gr + p.rot_c * e.gi; /* R G */
    return k_julia_quotient(p, nr, ni, dr, di, qr, qi, tw_re, tw_im);
}

/* W on the sphere: the two streams of 3D fBm at the direction (fbm.h, k_fbm3), scaled by lambda. */
K_FN k_vec2 k_julia_turbulence3(K_JuliaParams p, K_FbmParams t, k_vec3 d)
{
    if (p.lambda == 0.0f) return k_vec2(0.0f, 0.0f);
    return k_julia_turbulence_of(p, k_fbm3(t, 1u, d), k_fbm3(t, 2u, d));
}

/* The start of the orbit at environment-map position (ex, ey) (envmap.h: pixel centres at integers). */
K_FN K_JuliaStart k_julia_env_start(K_JuliaParams p, K_FbmParams turb, float ex, float ey)
{
    K_JuliaHom e = k_julia_env_point(p, ex, ey);
    k_vec2 w = k_julia_turbulence3(p, turb, e.dir);
    return k_julia_env_begin(p, e, w.x, w.y);
}

#endif

/* The result of an orbit that took n steps (escaped: it reached the bailout; else it stayed
 * inside for max_iter steps). */
K_FN K_JuliaResult k_julia_end(K_JuliaParams p, K_JuliaZ o, uint n, bool escaped, uint want)
{
    K_JuliaResult res;
    res.iter = n;
    res.inside = 0u;
    res.nsmooth = 0.0f;
    res.de = 0.0f;
    if (!escaped) {
        res.inside = 1u;
        res.nsmooth = K_F(p.max_iter);
        return res;
    }
    if (want == 0u) return res;
    /* Continue to the big radius (at most K_JULIA_EXTRA_ITER steps; from |z| >= 2 the orbit grows
     * doubly exponentially, so a handful suffice). */
    uint m = n;
    for (uint j = 0u; j < K_JULIA_EXTRA_ITER; j++) {
        K_PRECISE float r2j = o.zr * o.zr + o.zi * o.zi;
        if (r2j > K_JULIA_BIG_RADIUS2) break;
        o = k_julia_advance(o, r2j, p.c_re, p.c_im, want);
        m++;
    }
    float r2 = o.zr * o.zr + o.zi * o.zi;
    /* log2 as kernels/explog.h computes it: the same bits in C, on AVX2 lanes and on a device */
    float lnr = 0.5f * k_log2_poly(r2) * 0.69314718f; /* ln |z| */
    if ((want & K_JULIA_WANT_SMOOTH) != 0u) res.nsmooth = K_F(m) + 1.0f - k_log2_poly(lnr);
    if ((want & K_JULIA_WANT_DE) != 0u) {
        float dz = kx_sqrt(o.dz2); /* |z'| */
        /* an overflowed derivative (inf or NaN) gives 0, never a non-finite value */
        res.de = (dz > 0.0f && dz < 3.0e38f) ? kx_div(kx_sqrt(r2) * lnr, dz) : 0.0f;
    }
    return res;
}

/* One orbit from its start to its result. */
K_FN K_JuliaResult k_julia_run(K_JuliaParams p, K_JuliaStart s, uint want)
{
    if (s.ok == 0u) return k_julia_end(p, s.o, 0u, true, 0u);
    K_JuliaZ o = s.o;
    uint n = 0u;
    bool escaped = false;
    for (uint i = 0u; i < p.max_iter; i++) {
        K_PRECISE float r2 = o.zr * o.zr + o.zi * o.zi;
        if (r2 >= p.bailout2) {
            escaped = true;
            break;
        }
        o = k_julia_advance(o, r2, p.c_re, p.c_im, want);
        n++;
    }
    if (!escaped && o.zr * o.zr + o.zi * o.zi >= p.bailout2) escaped = true;
    return k_julia_end(p, o, n, escaped, want);
}

K_FN K_JuliaResult k_julia_orbit(K_JuliaParams p, float px, float py, float dpx, float dpy, float tw_re, float tw_im)
{
    return k_julia_run(p, k_julia_begin(p, px, py, dpx, dpy, tw_re, tw_im), K_JULIA_WANT_ALL);
}

/* Two orbits in one loop: two independent dependency chains interleave in the pipeline (on a SIMD
 * CPU device each lane then carries two pixels). Each orbit runs exactly the steps it would alone,
 * so the results are those of k_julia_run to the bit. has_b = false: a alone. */
K_STRUCT(K_JuliaPair)
{
    K_JuliaResult a, b;
}
K_END(K_JuliaPair)

K_FN K_JuliaPair k_julia_orbit2(K_JuliaParams p, K_JuliaStart sa, K_JuliaStart sb, bool has_b, uint want)
{
    K_JuliaZ a = sa.o, b = sb.o;
    bool da = sa.ok == 0u, db = !has_b || sb.ok == 0u; /* done */
    bool ea = da, eb = db;                             /* escaped (the pole: before the first step) */
    uint na = 0u, nb = 0u;
    for (uint i = 0u; i < p.max_iter; i++) {
        K_PRECISE float ra = a.zr * a.zr + a.zi * a.zi, rb = b.zr * b.zr + b.zi * b.zi;
        if (!da && ra >= p.bailout2) {
            da = true;
            ea = true;
        }
        if (!db && rb >= p.bailout2) {
            db = true;
            eb = true;
        }
        if (da && db) break;
        if (!da) {
            a = k_julia_advance(a, ra, p.c_re, p.c_im, want);
            na++;
        }
        if (!db) {
            b = k_julia_advance(b, rb, p.c_re, p.c_im, want);
            nb++;
        }
    }
    if (!ea && a.zr * a.zr + a.zi * a.zi >= p.bailout2) ea = true;
    if (!eb && b.zr * b.zr + b.zi * b.zi >= p.bailout2) eb = true;
    K_JuliaPair r;
    r.a = k_julia_end(p, a, na, ea, sa.ok == 0u ? 0u : want);
    r.b = k_julia_end(p, b, nb, eb, sb.ok == 0u ? 0u : want);
    return r;
}

/* W(p) in [0, 1]^2 scaled by lambda: two decorrelated streams of the shared fBm over (u, v); the
 * host makes it tileable for polar grids, so that the sky still wraps (t(0, v) = t(1, v)). */
K_FN k_vec2 k_julia_turbulence(K_JuliaParams p, K_FbmParams t, float u, float v)
{
    if (p.lambda == 0.0f) return k_vec2(0.0f, 0.0f);
    return k_julia_turbulence_of(p, k_fbm_uv(t, 1u, u, v), k_fbm_uv(t, 2u, u, v));
}

/* The start of the orbit of the point at continuous pixel coordinates (fx, fy) (pixel centres at
 * +0.5), turbulence included. */
K_FN K_JuliaStart k_julia_start_at(K_JuliaParams p, K_FbmParams turb, float fx, float fy)
{
#if K_WITH_ENVMAP
    if (p.mapping >= K_JULIA_LATLONG) return k_julia_env_start(p, turb, fx - 0.5f, fy - 0.5f);
#endif
    K_PRECISE float u = fx * p.inv_width;
    K_PRECISE float v = 1.0f - fy * p.inv_height;
    k_vec2 s = k_julia_start(p, u, v);
    k_vec2 d = k_julia_dstart(p, u, v);
    k_vec2 w = k_julia_turbulence(p, turb, u, v);
    return k_julia_begin(p, s.x, s.y, d.x, d.y, w.x, w.y);
}

K_FN K_JuliaResult k_julia_at(K_JuliaParams p, K_FbmParams turb, float fx, float fy)
{
    return k_julia_run(p, k_julia_start_at(p, turb, fx, fy), K_JULIA_WANT_ALL);
}

/* Pixel (x, y) at its centre: u = (x + 0.5)/W, v = 1 - (y + 0.5)/H. */
K_FN K_JuliaResult k_julia_pixel(K_JuliaParams p, K_FbmParams turb, uint x, uint y)
{
    return k_julia_at(p, turb, K_F(x) + 0.5f, K_F(y) + 0.5f);
}

/* The continuous coordinates of sample k of pixel (x, y) for anti-aliasing: sample 0 is the centre,
 * the others jittered uniformly over the pixel by the counter-based hash of (seed, sample, absolute
 * pixel index), so a sample is the same whatever strip, thread or device computes it. */
K_FN k_vec2 k_julia_sample_xy(K_JuliaParams p, uint seed, uint x, uint y, uint k)
{
    if (k == 0u) return k_vec2(K_F(x) + 0.5f, K_F(y) + 0.5f);
    uint idx = y * p.width + x;
    float jx = k_rand01(seed, 0x5a00u + 2u * k, idx), jy = k_rand01(seed, 0x5a01u + 2u * k, idx);
    return k_vec2(K_F(x) + jx, K_F(y) + jy);
}

K_FN K_JuliaResult k_julia_sample(K_JuliaParams p, K_FbmParams turb, uint seed, uint x, uint y, uint k)
{
    k_vec2 f = k_julia_sample_xy(p, seed, x, y, k);
    return k_julia_at(p, turb, f.x, f.y);
}

/* Sample k of pixels (x, y) and (x + 1, y) together (has_b = false: the first only). */
K_FN K_JuliaPair k_julia_sample2(K_JuliaParams p, K_FbmParams turb, uint seed, uint x, uint y, uint k, bool has_b,
                                 uint want)
{
    k_vec2 fa = k_julia_sample_xy(p, seed, x, y, k);
    k_vec2 fb = k_julia_sample_xy(p, seed, has_b ? x + 1u : x, y, k);
    K_JuliaStart sa = k_julia_start_at(p, turb, fa.x, fa.y);
    K_JuliaStart sb = sa;
    if (has_b) sb = k_julia_start_at(p, turb, fb.x, fb.y);
    return k_julia_orbit2(p, sa, sb, has_b, want);
}

/* ---- double precision (a layer's "precision": "double") ------------------------------------------
 * The grid, the warp and the orbit in double, for escape counts that agree with a double reference
 * wherever float's 2^-24 would change them. Every constant that is not exact in float comes from the
 * host in K_JuliaD (GLSL has no suffix-free double literals), and sin/cos are computed here, so that
 * C and a device with shaderFloat64 run the same operations. The tail (smooth count, distance) is
 * float, as stored. Shaders define K_JULIA_F64 to compile this part. */
#if !defined(K_GLSL) || defined(K_JULIA_F64)

#ifdef K_GLSL
#define K_DF(x)      double(x)
#define K_DU(x)      uint(x)
#define k_floor_d(x) floor(x)
#else
#define K_DF(x)      ((double)(x))
#define K_DU(x)      ((uint)(x))
#define k_floor_d(x) floor(x)
#endif

K_STRUCT(K_JuliaD)
{
    double c_re, c_im, a_re, a_im;
    double scale_u, scale_v, radius, center_re, center_im, rot_c, rot_s;
    double bailout2, huge;                     /* R^2; (double)1e30f: beyond it z0 escapes at once */
    double two_pi, pio2_hi, pio2_lo, inv_pio2; /* pi/2 = pio2_hi + pio2_lo */
    double s1, s2, s3, s4, s5, s6;             /* fdlibm's __kernel_sin and __kernel_cos polynomials */
    double c1, c2, c3, c4, c5, c6;
}
K_END(K_JuliaD)

#ifndef K_GLSL
/* The constants of K_JuliaD (the host sets the parameters): pi/2 in two parts, and fdlibm's
 * polynomials for sin and cos on [-pi/4, pi/4]. */
static inline void k_julia_d_constants(K_JuliaD *d)
{
    d->huge = (double)1.0e30f;
    d->two_pi = 6.28318530717958647692;
    d->pio2_hi = 1.57079632673412561417e+00;
    d->pio2_lo = 6.07710050650619224932e-11;
    d->inv_pio2 = 6.36619772367581382433e-01;
    d->s1 = -1.66666666666666324348e-01;
    d->s2 = 8.33333333332248946124e-03;
    d->s3 = -1.98412698298579493134e-04;
    d->s4 = 2.75573137070700676789e-06;
    d->s5 = -2.50507602534068634195e-08;
    d->s6 = 1.58969099521155010221e-10;
    d->c1 = 4.16666666666666019037e-02;
    d->c2 = -1.38888888888741095749e-03;
    d->c3 = 2.48015872894767294178e-05;
    d->c4 = -2.75573143513906633035e-07;
    d->c5 = 2.08757232129817482790e-09;
    d->c6 = -1.13596475577881948265e-11;
}
#endif

K_STRUCT(K_JuliaSinCos)
{
    double s, c;
}
K_END(K_JuliaSinCos)

/* sin and cos of x >= 0 (a few turns at most): x - q pi/2 in two parts, then the polynomials on
 * [-pi/4, pi/4]; within 2 ulp of the libm values. */
K_FN K_JuliaSinCos k_julia_sincos_d(K_JuliaD d, double x)
{
    K_PRECISE double q = k_floor_d(x * d.inv_pio2 + 0.5);
    K_PRECISE double r = (x - q * d.pio2_hi) - q * d.pio2_lo;
    K_PRECISE double z = r * r;
    K_PRECISE double sn = r + r * z * (d.s1 + z * (d.s2 + z * (d.s3 + z * (d.s4 + z * (d.s5 + z * d.s6)))));
    K_PRECISE double cs = 1.0 - 0.5 * z + z * z * (d.c1 + z * (d.c2 + z * (d.c3 + z * (d.c4 + z * (d.c5 + z * d.c6)))));
    uint n = K_DU(q) & 3u;
    K_JuliaSinCos o;
    o.s = n == 0u ? sn : n == 1u ? cs : n == 2u ? -sn : -cs;
    o.c = n == 0u ? cs : n == 1u ? -sn : n == 2u ? -cs : sn;
    return o;
}

/* An orbit's state in double, and one step of it (|z'|^2 <- 4 |z|^2 |z'|^2, as K_JuliaZ, only when
 * the distance is wanted; r2 = |z|^2 of o as the bailout test computes it). In double dz2 overflows
 * where |z'| > 1.3e154, and the float |z'| of the end where |z'| > 3e38, as the complex z' did. */
K_STRUCT(K_JuliaZD)
{
    double zr, zi, dz2;
}
K_END(K_JuliaZD)

K_FN K_JuliaZD k_julia_step_d(K_JuliaZD o, double r2, K_JuliaD d, uint want)
{
    K_PRECISE K_JuliaZD r = o;
    if ((want & K_JULIA_WANT_DE) != 0u) r.dz2 = o.dz2 * (4.0 * r2);
    r.zr = o.zr * o.zr - o.zi * o.zi + d.c_re;
    r.zi = 2.0 * o.zr * o.zi + d.c_im;
    return r;
}

/* The orbit of the point at continuous pixel coordinates (fx, fy), in double. */
K_FN K_JuliaResult k_julia_run_d(K_JuliaParams p, K_JuliaD d, K_FbmParams turb, double fx, double fy, uint want)
{
    K_JuliaResult res;
    res.iter = 0u;
    res.inside = 0u;
    res.nsmooth = 0.0f;
    res.de = 0.0f;
    K_PRECISE double u = kx_ddiv(fx, K_DF(p.width));
    K_PRECISE double v = 1.0 - kx_ddiv(fy, K_DF(p.height));
    K_PRECISE double x, y, ddx, ddy;
    if (p.mapping == K_JULIA_POLAR) {
        K_PRECISE double rr = d.radius * v;
        K_PRECISE double ang = d.two_pi * (u - k_floor_d(u)); /* wrapped first: t(0, v) = t(1, v) */
        K_JuliaSinCos sc = k_julia_sincos_d(d, ang);
        K_PRECISE double k = kx_ddiv(d.two_pi * rr, K_DF(p.width));
        x = rr * sc.c;
        y = rr * sc.s;
        ddx = -k * sc.s;
        ddy = k * sc.c;
    } else {
        x = d.scale_u * (u - 0.5);
        y = d.scale_v * (v - 0.5);
        ddx = kx_ddiv(d.scale_u, K_DF(p.width));
        ddy = 0.0;
    }
    K_PRECISE double px = d.center_re + (d.rot_c * x - d.rot_s * y);
    K_PRECISE double py = d.center_im + (d.rot_s * x + d.rot_c * y);
    K_PRECISE double dpx = d.rot_c * ddx - d.rot_s * ddy;
    K_PRECISE double dpy = d.rot_s * ddx + d.rot_c * ddy;
    k_vec2 w = k_julia_turbulence(p, turb, K_F(u), K_F(v));
    /* z0 = (p - conj(a)) / (1 - a p), dz0/dx = (1 - |a|^2) / (1 - a p)^2 dp/dx, as in float */
    K_PRECISE double nr = px - d.a_re;
    K_PRECISE double ni = py + d.a_im;
    K_PRECISE double dr = 1.0 - (d.a_re * px - d.a_im * py);
    K_PRECISE double di = -(d.a_re * py + d.a_im * px);
    K_PRECISE double den = dr * dr + di * di;
    if (!(den > 0.0)) return res; /* the pole */
    K_PRECISE double inv = kx_ddiv(1.0, den);
    K_PRECISE double zr = (nr * dr + ni * di) * inv + K_DF(w.x);
    K_PRECISE double zi = (ni * dr - nr * di) * inv + K_DF(w.y);
    K_PRECISE double kk = 1.0 - (d.a_re * d.a_re + d.a_im * d.a_im);
    K_PRECISE double wr = kk * ((dr * dr - di * di) * inv * inv), wi = kk * (-2.0 * dr * di * inv * inv);
    K_PRECISE K_JuliaZD o;
    K_PRECISE double dzr = wr * dpx - wi * dpy;
    K_PRECISE double dzi = wr * dpy + wi * dpx;
    o.zr = zr;
    o.zi = zi;
    o.dz2 = dzr * dzr + dzi * dzi;
    if (!(zr * zr + zi * zi < d.huge)) return res;
    uint n = 0u;
    bool escaped = false;
    for (uint i = 0u; i < p.max_iter; i++) {
        K_PRECISE double r2 = o.zr * o.zr + o.zi * o.zi;
        if (r2 >= d.bailout2) {
            escaped = true;
            break;
        }
        o = k_julia_step_d(o, r2, d, want);
        n++;
    }
    if (!escaped && o.zr * o.zr + o.zi * o.zi >= d.bailout2) escaped = true;
    res.iter = n;
    if (!escaped) {
        res.inside = 1u;
        res.nsmooth = K_F(p.max_iter);
        return res;
    }
    if (want == 0u) return res;
    uint m = n;
    for (uint j = 0u; j < K_JULIA_EXTRA_ITER; j++) {
        K_PRECISE double r2j = o.zr * o.zr + o.zi * o.zi;
        if (r2j > 4294967296.0) break;
        o = k_julia_step_d(o, r2j, d, want);
        m++;
    }
    float r2 = K_F(o.zr * o.zr + o.zi * o.zi);
    float lnr = 0.5f * k_log2_poly(r2) * 0.69314718f;
    if ((want & K_JULIA_WANT_SMOOTH) != 0u) res.nsmooth = K_F(m) + 1.0f - k_log2_poly(lnr);
    if ((want & K_JULIA_WANT_DE) != 0u) {
        /* |z'| from dz2 rounded to float first (kx_sqrt: the same bits everywhere) */
        float dz = kx_sqrt(K_F(o.dz2));
        res.de = (dz > 0.0f && dz < 3.0e38f) ? kx_div(kx_sqrt(r2) * lnr, dz) : 0.0f;
    }
    return res;
}

#endif

#endif
