/*
 * A star field's pixels: each star's flux spread over a tent point-spread function in the image's
 * own pixel coordinates, divided by the pixel's solid angle, so that a pixel holds radiance and the
 * sum over pixels of value times solid angle is the stars' total flux, at any size and mapping.
 *
 * The host (host/gen/stars) draws the stars from the sphere's fixed cells and bins them into
 * records of the image's tiles: a record is a star's centre in one face's (or the whole lat-long or
 * polar image's) pixel coordinates with its flux per channel. A pixel's footprint is its box
 * [x - 1/2, x + 1/2] x [y - 1/2, y + 1/2] clipped to its face (OpenEXR puts the edge pixels' centres
 * on the cube's edges and the lat-long's poles and seam, so those pixels are half or quarter
 * boxes); the tent's mass over a footprint is the product of two 1D masses, differences of the
 * tent's CDF, so that the footprints of a face tile its plane and the masses sum to one:
 *   - cube: mass beyond a face's edge goes to the neighbouring face through the cube's unfolding
 *     (the host adds the star to that face as a record beyond its edge), mass beyond two edges at
 *     once to the face's corner pixel (K_STARS_HOME_CUBE records);
 *   - lat-long and polar: mass beyond the left or right column wraps round (the host adds the star
 *     once more a period away), mass beyond the first or last row stays in that row
 *     (K_STARS_CLAMP_Y).
 *
 * A pixel's solid angle: lat-long and polar, a function of the row from the host (exact, in double,
 * rounded once); cube, the integral of (1 + s^2 + t^2)^(-3/2) over the footprint's face coordinates
 * by 3 x 3 Gauss-Legendre (relative error under 1e-7 at 24 pixels a face), in the kernel.
 *
 * Only adds, multiplies, min and max, all `precise`, except the cube's square roots and one
 * division a pixel (correctly rounded on lavapipe; a GPU may differ there by an ulp or two).
 */
#ifndef FB_KERNELS_STARS_H
#define FB_KERNELS_STARS_H

#include "envmap.h"

#define K_STARS_POLAR     3u /* a mapping of its own: the upper hemisphere as the Julia layer's polar grid */
#define K_STARS_REC_WORDS 8u /* x y r g b mag flags pad */

#define K_STARS_HOME_CUBE 1u    /* the star's own face: mass beyond two edges at once goes to the corner pixel */
#define K_STARS_CLAMP_Y   2u    /* mass beyond the first and last rows stays in them */
#define K_STARS_NONE_MAG  99.0f /* the magnitude channel where no star reaches */

/* The push constants. The input holds tile_start[tiles + 1] (offsets into the records, which are
 * stored tile by tile), the records at rec_off (K_STARS_REC_WORDS each), and for lat-long and polar
 * 1/solid angle of each row's full pixel at row_off. */
K_STRUCT(K_StarsParams)
{
    uint width, height;
    uint mapping;    /* K_ENV_LATLONG, K_ENV_CUBE, K_STARS_POLAR */
    uint n;          /* cube: the face's size */
    uint tiles_x;    /* tiles per row */
    uint tile_shift; /* tiles are (1 << tile_shift) pixels square */
    uint rec_off;
    uint row_off;
    float radius;  /* the tent's half width, pixels */
    float inv_2r2; /* 1 / (2 radius^2) */
    float x_lo;    /* the columns' footprints are clipped to [x_lo, x_hi] */
    float x_hi;
    float cube_h; /* cube: face coordinate per pixel, 2 / (n - 1) */
    uint pad0, pad1, pad2;
}
K_END(K_StarsParams)

K_STRUCT(K_StarsRec)
{
    float x, y;    /* the star's centre, image pixel coordinates (beyond the face for an unfolded one) */
    float r, g, b; /* its flux in each channel (luminance flux times its colour) */
    float mag;     /* its magnitude */
    uint flags;    /* K_STARS_* | face << 8 */
    uint pad;
}
K_END(K_StarsRec)

K_STRUCT(K_StarsAcc)
{
    float r, g, b, mag;
}
K_END(K_StarsAcc)

/* The tent's CDF at x for a centre c: 0 below c - r, 1 above c + r. */
K_FN float k_stars_cdf(float x, float c, float r, float k)
{
    K_PRECISE float t = k_clamp(x - c + r, 0.0f, r + r);
    K_PRECISE float u = r + r - t;
    K_PRECISE float lo = t * t * k;
    K_PRECISE float hi = 1.0f - u * u * k;
    return t <= r ? lo : hi;
}

/* The footprint of pixel row y: [lo, hi] (x: lo, y: hi) within the rows of its face, or out to the
 * poles' far side where the mass beyond stays in the row. */
K_FN k_vec2 k_stars_rows(K_StarsParams p, uint y, bool clamp)
{
    uint f = p.mapping == K_ENV_CUBE ? y / p.n : 0u;
    float first = K_F(f * (p.mapping == K_ENV_CUBE ? p.n : 0u));
    float last = p.mapping == K_ENV_CUBE ? first + K_F(p.n - 1u) : K_F(p.height - 1u);
    float fy = K_F(y);
    float lo = k_max(fy - 0.5f, first), hi = k_min(fy + 0.5f, last);
    if (clamp && fy == first) lo = -1.0e30f;
    if (clamp && fy == last) hi = 1.0e30f;
    return k_vec2(lo, hi);
}

/* What the share of a record depends on of pixel (x, y): its centre, its footprint's columns and
 * rows (without and with the pole rows' reach beyond), its face (cube) and row in it. The same for
 * every record a pixel reads: a shader works it out once, before the loop over its tile's records. */
K_STRUCT(K_StarsPixel)
{
    float fx, fy;
    float xlo, xhi;
    float ylo, yhi, ylo_c, yhi_c; /* _c: with K_STARS_CLAMP_Y */
    uint face, b;                 /* cube: y / n and y % n */
}
K_END(K_StarsPixel)

K_FN K_StarsPixel k_stars_pixel(K_StarsParams p, uint x, uint y)
{
    K_StarsPixel px;
    px.fx = K_F(x);
    px.fy = K_F(y);
    px.xlo = k_max(px.fx - 0.5f, p.x_lo);
    px.xhi = k_min(px.fx + 0.5f, p.x_hi);
    k_vec2 yr = k_stars_rows(p, y, false), yc = k_stars_rows(p, y, true);
    px.ylo = yr.x;
    px.yhi = yr.y;
    px.ylo_c = yc.x;
    px.yhi_c = yc.y;
    px.face = p.mapping == K_ENV_CUBE ? y / p.n : 0u;
    px.b = p.mapping == K_ENV_CUBE ? y % p.n : 0u;
    return px;
}

/* Whether a record centred at (rx, ry) is within the tent's reach of the pixel (beyond it the masses
 * below would be exactly 0; a pole row's or a corner's share comes from stars within reach of the
 * pixel's centre too). Only the centre is read: a shader reads a record's other words after it. */
K_FN bool k_stars_near(K_StarsParams p, K_StarsPixel px, float rx, float ry)
{
    float reach = p.radius + 0.5f;
    return !(k_abs(px.fx - rx) >= reach || k_abs(px.fy - ry) >= reach);
}

/* The share of a record (rx, ry, flags) near pixel px (k_stars_near). */
K_FN float k_stars_share(K_StarsParams p, K_StarsPixel px, float rx, float ry, uint flags)
{
    if (p.mapping == K_ENV_CUBE && (flags >> 8) != px.face) return 0.0f;
    bool clamp = (flags & K_STARS_CLAMP_Y) != 0u;
    float r = p.radius, k = p.inv_2r2;
    float cx0 = k_stars_cdf(px.xlo, rx, r, k), cx1 = k_stars_cdf(px.xhi, rx, r, k);
    float cy0 = k_stars_cdf(clamp ? px.ylo_c : px.ylo, ry, r, k),
          cy1 = k_stars_cdf(clamp ? px.yhi_c : px.yhi, ry, r, k);
    K_PRECISE float w = (cx1 - cx0) * (cy1 - cy0);
    if ((flags & K_STARS_HOME_CUBE) != 0u) {
        /* the mass beyond two edges at once: to the corner pixel */
        K_PRECISE float ex = (px.fx == p.x_lo ? cx0 : 0.0f) + (px.fx == p.x_hi ? 1.0f - cx1 : 0.0f);
        K_PRECISE float ey = (px.b == 0u ? cy0 : 0.0f) + (px.b == p.n - 1u ? 1.0f - cy1 : 0.0f);
        w = w + ex * ey;
    }
    return w;
}

/* The share of record (rx, ry, flags) that pixel (x, y) receives. */
K_FN float k_stars_weight(K_StarsParams p, float rx, float ry, uint flags, uint x, uint y)
{
    K_StarsPixel px = k_stars_pixel(p, x, y);
    return k_stars_near(p, px, rx, ry) ? k_stars_share(p, px, rx, ry, flags) : 0.0f;
}

/* (1 + s^2 + t^2)^(-3/2): the solid angle per unit area of a cube face at (s, t). */
K_FN float k_stars_jacobian(float s, float t)
{
    K_PRECISE float q = 1.0f + s * s + t * t;
    K_PRECISE float d = q * kx_sqrt(q);
    return kx_div(1.0f, d);
}

/* The solid angle of the cube-face rectangle [s0, s1] x [t0, t1], by 3 x 3 Gauss-Legendre. */
K_FN float k_stars_cube_solid_angle(float s0, float s1, float t0, float t1)
{
    float g = 0.774596669241483f; /* sqrt(3/5) */
    K_PRECISE float hs = 0.5f * (s1 - s0), ms = 0.5f * (s0 + s1);
    K_PRECISE float ht = 0.5f * (t1 - t0), mt = 0.5f * (t0 + t1);
    K_PRECISE float sum = 0.0f;
    for (int i = -1; i <= 1; i++) {
        K_PRECISE float s = ms + hs * g * K_F(i);
        float wi = i == 0 ? 0.888888888888889f : 0.555555555555556f;
        K_PRECISE float row = 0.0f;
        for (int j = -1; j <= 1; j++) {
            K_PRECISE float t = mt + ht * g * K_F(j);
            float wj = j == 0 ? 0.888888888888889f : 0.555555555555556f;
            row = row + wj * k_stars_jacobian(s, t);
        }
        sum = sum + wi * row;
    }
    K_PRECISE float omega = sum * hs * ht;
    return omega;
}

/* 1 / the solid angle of cube pixel (x, y). */
K_FN float k_stars_cube_inv_omega(K_StarsParams p, uint x, uint y)
{
    float last = K_F(p.n - 1u);
    float a = K_F(x), b = K_F(y % p.n);
    K_PRECISE float s0 = k_max(a - 0.5f, 0.0f) * p.cube_h - 1.0f;
    K_PRECISE float s1 = k_min(a + 0.5f, last) * p.cube_h - 1.0f;
    K_PRECISE float t0 = k_max(b - 0.5f, 0.0f) * p.cube_h - 1.0f;
    K_PRECISE float t1 = k_min(b + 0.5f, last) * p.cube_h - 1.0f;
    return kx_div(1.0f, k_stars_cube_solid_angle(s0, s1, t0, t1));
}

K_FN K_StarsAcc k_stars_init()
{
    K_StarsAcc a;
    a.r = 0.0f;
    a.g = 0.0f;
    a.b = 0.0f;
    a.mag = K_STARS_NONE_MAG;
    return a;
}

/* Adds a record's share w (flux r, g, b; magnitude mag) to a pixel's sums; the magnitude channel
 * keeps the brightest star that reaches the pixel. */
K_FN K_StarsAcc k_stars_accumulate(K_StarsAcc acc, float w, float sr, float sg, float sb, float mag)
{
    if (w > 0.0f) {
        K_PRECISE float r = acc.r + sr * w, g = acc.g + sg * w, b = acc.b + sb * w;
        acc.r = r;
        acc.g = g;
        acc.b = b;
        acc.mag = k_min(acc.mag, mag);
    }
    return acc;
}

/* Adds record s's share to pixel px's sums. */
K_FN K_StarsAcc k_stars_add(K_StarsAcc acc, K_StarsParams p, K_StarsPixel px, K_StarsRec s)
{
    if (!k_stars_near(p, px, s.x, s.y)) return acc;
    return k_stars_accumulate(acc, k_stars_share(p, px, s.x, s.y, s.flags), s.r, s.g, s.b, s.mag);
}

/* The sums as radiance: divided by the pixel's solid angle (row_inv: the row's 1/omega from the
 * host for lat-long and polar, whose first and last lat-long columns are half pixels). */
K_FN K_StarsAcc k_stars_finish(K_StarsAcc acc, K_StarsParams p, float row_inv, uint x, uint y)
{
    float inv = row_inv;
    if (p.mapping == K_ENV_CUBE) inv = k_stars_cube_inv_omega(p, x, y);
    if (p.mapping == K_ENV_LATLONG && (x == 0u || x == p.width - 1u)) inv = inv * 2.0f;
    K_PRECISE float r = acc.r * inv, g = acc.g * inv, b = acc.b * inv;
    acc.r = r;
    acc.g = g;
    acc.b = b;
    return acc;
}

#endif
