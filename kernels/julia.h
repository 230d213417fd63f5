/*
 * Warped Julia sets for night skies (SPEC.md section 2, seed 003).
 *
 *   (7)  rectangular: p = s_u (u - 0.5) + i s_v (v - 0.5)      (then rotated and centred)
 *   (8)  polar:       p = r v exp(i 2 pi u)                     t(0, v) = t(1, v): seamless
 *   (11) z_0 = A(p^-1) = (p - conj(a)) / (1 - a p),  z_{n+1} = z_n^2 + c
 *
 * Per pixel: the escape count at the user's bailout R (`iter`), a smooth count that does not depend
 * on R, whether the orbit stayed bounded for max_iter steps, and a distance estimate in pixels.
 */
#ifndef FB_KERNELS_JULIA_H
#define FB_KERNELS_JULIA_H

#include "fbm.h"
#include "hash.h"

#define K_JULIA_RECT  0u
#define K_JULIA_POLAR 1u

/* Orbits continue past R until |z| > 2^16 for the smooth count and the distance estimate, where
 * ln|z_{n+1}| = 2 ln|z_n| holds to 1e-9 and the smooth value no longer depends on the radius. */
#define K_JULIA_BIG_RADIUS2 4294967296.0f
#define K_JULIA_EXTRA_ITER  64u

K_STRUCT(K_JuliaParams)
{
    uint width;
    uint height;
    uint mapping;  /* K_JULIA_RECT or K_JULIA_POLAR */
    uint max_iter; /* >= 1 */
    float c_re, c_im;
    float a_re, a_im;       /* allpass alpha; 0 is the plain Julia set */
    float scale_u, scale_v; /* rect: s_u, s_v */
    float radius;           /* polar: r */
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

/* An orbit's state: z and its derivative z' with respect to the pixel coordinate. */
K_STRUCT(K_JuliaZ)
{
    float zr, zi, dzr, dzi;
}
K_END(K_JuliaZ)

/* One step: z' <- 2 z z', z <- z^2 + c. precise: an orbit is chaotic, so one fused rounding would
 * change the escape count of boundary pixels between a device and C. */
K_FN K_JuliaZ k_julia_step(K_JuliaZ o, float c_re, float c_im)
{
    K_PRECISE K_JuliaZ r;
    r.dzr = 2.0f * (o.zr * o.dzr - o.zi * o.dzi);
    r.dzi = 2.0f * (o.zr * o.dzi + o.zi * o.dzr);
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
        x = rr * k_cos(ang);
        y = rr * k_sin(ang);
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
        dx = -k * k_sin(ang);
        dy = k * k_cos(ang);
    } else {
        dx = p.scale_u * p.inv_width;
        dy = 0.0f;
    }
    return k_vec2(p.rot_c * dx - p.rot_s * dy, p.rot_s * dx + p.rot_c * dy);
}

/* (tw_re, tw_im): the turbulence term lambda W(p) added to z0 (eq. 13); 0 for none. */
K_FN K_JuliaResult k_julia_orbit(K_JuliaParams p, float px, float py, float dpx, float dpy, float tw_re, float tw_im)
{
    K_JuliaResult res;
    res.iter = 0u;
    res.inside = 0u;
    res.nsmooth = 0.0f;
    res.de = 0.0f;
    /* z0 = (p - conj(a)) / (1 - a p); dz0/dx = (1 - |a|^2) / (1 - a p)^2 * dp/dx */
    K_PRECISE float nr = px - p.a_re;
    K_PRECISE float ni = py + p.a_im;
    K_PRECISE float dr = 1.0f - (p.a_re * px - p.a_im * py);
    K_PRECISE float di = -(p.a_re * py + p.a_im * px);
    K_PRECISE float den = dr * dr + di * di;
    /* The pole p = 1/a sends z0 to infinity, which lies outside every filled Julia set: the pixel
     * escapes before the first iteration. Nothing non-finite reaches the output. */
    if (!(den > 1.0e-30f)) return res;
    float inv = 1.0f / den;
    /* precise: an orbit is chaotic, so one fused rounding would change the escape count of
     * boundary pixels between a device and C. */
    K_PRECISE float zr = (nr * dr + ni * di) * inv + tw_re;
    K_PRECISE float zi = (ni * dr - nr * di) * inv + tw_im;
    float k = 1.0f - (p.a_re * p.a_re + p.a_im * p.a_im);
    float sr = (dr * dr - di * di) * inv * inv, si = -2.0f * dr * di * inv * inv; /* 1 / (1 - a p)^2 */
    float wr = k * sr, wi = k * si;
    K_PRECISE K_JuliaZ o;
    o.zr = zr;
    o.zi = zi;
    o.dzr = wr * dpx - wi * dpy;
    o.dzi = wr * dpy + wi * dpx;
    if (!(zr * zr + zi * zi < 1.0e30f)) return res;

    uint n = 0u;
    bool escaped = false;
    for (uint i = 0u; i < p.max_iter; i++) {
        if (o.zr * o.zr + o.zi * o.zi >= p.bailout2) {
            escaped = true;
            break;
        }
        o = k_julia_step(o, p.c_re, p.c_im);
        n++;
    }
    if (!escaped && o.zr * o.zr + o.zi * o.zi >= p.bailout2) escaped = true;
    res.iter = n;
    if (!escaped) {
        res.inside = 1u;
        res.nsmooth = K_F(p.max_iter);
        return res;
    }
    /* Continue to the big radius (at most K_JULIA_EXTRA_ITER steps; from |z| >= 2 the orbit grows
     * doubly exponentially, so a handful suffice). */
    uint m = n;
    for (uint j = 0u; j < K_JULIA_EXTRA_ITER; j++) {
        if (o.zr * o.zr + o.zi * o.zi > K_JULIA_BIG_RADIUS2) break;
        o = k_julia_step(o, p.c_re, p.c_im);
        m++;
    }
    float r2 = o.zr * o.zr + o.zi * o.zi;
    float lnr = 0.5f * k_log2(r2) * 0.69314718f; /* ln |z| */
    res.nsmooth = K_F(m) + 1.0f - k_log2(lnr);
    float dz = k_sqrt(o.dzr * o.dzr + o.dzi * o.dzi);
    /* an overflowed derivative (inf or NaN) gives 0, never a non-finite value */
    res.de = (dz > 0.0f && dz < 3.0e38f) ? k_sqrt(r2) * lnr / dz : 0.0f;
    return res;
}

/* W(p) in [0, 1]^2 scaled by lambda: two decorrelated streams of the shared fBm over (u, v); the
 * host makes it tileable for polar grids, so that the sky still wraps (t(0, v) = t(1, v)). */
K_FN k_vec2 k_julia_turbulence(K_JuliaParams p, K_FbmParams t, float u, float v)
{
    if (p.lambda == 0.0f) return k_vec2(0.0f, 0.0f);
    float wr = k_clamp(0.5f + 0.5f * p.turb_norm * k_fbm_uv(t, 1u, u, v), 0.0f, 1.0f);
    float wi = k_clamp(0.5f + 0.5f * p.turb_norm * k_fbm_uv(t, 2u, u, v), 0.0f, 1.0f);
    return k_vec2(p.lambda * wr, p.lambda * wi);
}

/* The orbit of the point at continuous pixel coordinates (fx, fy) (pixel centres at +0.5). */
K_FN K_JuliaResult k_julia_at(K_JuliaParams p, K_FbmParams turb, float fx, float fy)
{
    K_PRECISE float u = fx * p.inv_width;
    K_PRECISE float v = 1.0f - fy * p.inv_height;
    k_vec2 s = k_julia_start(p, u, v);
    k_vec2 d = k_julia_dstart(p, u, v);
    k_vec2 w = k_julia_turbulence(p, turb, u, v);
    return k_julia_orbit(p, s.x, s.y, d.x, d.y, w.x, w.y);
}

/* Pixel (x, y) at its centre: u = (x + 0.5)/W, v = 1 - (y + 0.5)/H. */
K_FN K_JuliaResult k_julia_pixel(K_JuliaParams p, K_FbmParams turb, uint x, uint y)
{
    return k_julia_at(p, turb, K_F(x) + 0.5f, K_F(y) + 0.5f);
}

/* Sample k of pixel (x, y) for anti-aliasing: sample 0 is the centre, the others jittered uniformly
 * over the pixel by the counter-based hash of (seed, sample, absolute pixel index), so a sample is
 * the same whatever strip, thread or device computes it. */
K_FN K_JuliaResult k_julia_sample(K_JuliaParams p, K_FbmParams turb, uint seed, uint x, uint y, uint k)
{
    if (k == 0u) return k_julia_pixel(p, turb, x, y);
    uint idx = y * p.width + x;
    float jx = k_rand01(seed, 0x5a00u + 2u * k, idx), jy = k_rand01(seed, 0x5a01u + 2u * k, idx);
    return k_julia_at(p, turb, K_F(x) + jx, K_F(y) + jy);
}

#endif
