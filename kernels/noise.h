/*
 * Band-limited 2D base noises for fBm (SPEC.md section 1): gradient (Perlin), value, simplex,
 * cellular (Worley F1, F2) and sine. Every lattice noise takes a period (px, py) in cells: the
 * lattice hash wraps at that period, so the noise is exactly periodic. Tileable fBm passes the
 * image's cell count; ordinary fBm passes K_NOISE_PERIOD, which is far beyond any visible scale
 * and keeps every float-to-int conversion in range however large the coordinate grows.
 */
#ifndef FB_KERNELS_NOISE_H
#define FB_KERNELS_NOISE_H

#include "exact.h"
#include "hash.h"
#include "sincos.h"

#define K_NOISE_PERIOD 4096u

/* 1 / 0.0221089, the largest simplex sum over every assignment of the 8 gradients to the three
 * corners (found by exhaustive search over a 0.0005-cell grid, tests/test_kernels.c re-checks it). */
#define K_SIMPLEX_SCALE 45.22f

#define K_NOISE_GRADIENT    0u
#define K_NOISE_VALUE       1u
#define K_NOISE_SIMPLEX     2u
#define K_NOISE_CELLULAR    3u
#define K_NOISE_CELLULAR_F2 4u
#define K_NOISE_SINE        5u
#define K_NOISE_COUNT       6u

/* Wraps an integral lattice index i (a float, possibly huge) into [0, p). Integer arithmetic while
 * i is exact in binary32 (|i| < 2^24), so that C and GLSL agree bit for bit: Vulkan lets a float
 * division be off by 2.5 ULP, so no kernel divides. Beyond 2^24 cells (octaves finer than any
 * pixel) the float path only has to stay in range. GLSL leaves % of negative operands undefined,
 * hence the shift to a non-negative value first. */
/* A shader whose every lattice index is known on the host to stay under 2^24 cells (fBm's scenes
 * but for huge frequencies: host/gen/fbm/layer.c) defines K_WRAP_SMALL as true, a specialisation
 * constant, before including this file: the float path then folds away. On lavapipe both sides of
 * the test run in every lane, and that path cost fBm a tenth of its time (bench/RESULTS.md). Where
 * |i| < 2^24 both paths give the same cell, so the result is the same bits. */
#ifndef K_WRAP_SMALL
#define K_WRAP_SMALL false
#endif

K_FN uint k_wrap_cell(float i, uint p)
{
    if (K_WRAP_SMALL || k_abs(i) < 16777216.0f) {
        int ii = K_I(i);
        /* A power-of-two period (every non-tileable lattice) is a mask, also for negative ii in two's
         * complement. Integer division has no SIMD instruction: on lavapipe, where one invocation is
         * one AVX2 lane, a % per lattice lookup made fBm 20 times slower. */
        if ((p & (p - 1u)) == 0u) return K_U(ii) & (p - 1u);
        int ip = K_I(p);
        if (ii < 0) ii += ((-ii) / ip + 1) * ip;
        return K_U(ii) % p;
    }
    float fp = K_F(p);
    float r = k_clamp(i - fp * k_floor(i * kx_div(1.0f, fp)), 0.0f, fp - 1.0f);
    return K_U(K_I(r)) % p;
}

/* (c + d) mod p for a cell c in [0, p) and a small offset d >= -2p. */
K_FN uint k_cell_add(uint c, int d, uint p)
{
    if ((p & (p - 1u)) == 0u) return K_U(K_I(c) + d) & (p - 1u);
    return K_U(K_I(c) + d + 2 * K_I(p)) % p;
}

/* One of 8 gradients of length sqrt(5), (+-1, +-2) and (+-2, +-1), dotted with (x, y). Bit
 * operations only, so both languages agree exactly (Perlin's reference 2D gradient set). */
K_FN float k_grad2(uint h, float x, float y)
{
    uint b = h & 7u;
    float u = b < 4u ? x : y;
    float v = b < 4u ? y : x;
    return ((b & 1u) != 0u ? -u : u) + ((b & 2u) != 0u ? -2.0f * v : 2.0f * v);
}

/* Gradient noise in [-1, 1]; exactly 0 at lattice points. The largest value of 2D gradient noise
 * with unit gradients is sqrt(2)/2; ours are sqrt(5) long, so the scale is 1 / (sqrt(5) sqrt(2)/2). */
K_FN float k_gradient_noise(uint seed, float x, float y, uint px, uint py)
{
    float fx = k_floor(x), fy = k_floor(y);
    float tx = x - fx, ty = y - fy;
    uint ix0 = k_wrap_cell(fx, px), iy0 = k_wrap_cell(fy, py);
    uint ix1 = k_cell_add(ix0, 1, px), iy1 = k_cell_add(iy0, 1, py);
    float n00 = k_grad2(k_hash2i(seed, ix0, iy0), tx, ty);
    float n10 = k_grad2(k_hash2i(seed, ix1, iy0), tx - 1.0f, ty);
    float n01 = k_grad2(k_hash2i(seed, ix0, iy1), tx, ty - 1.0f);
    float n11 = k_grad2(k_hash2i(seed, ix1, iy1), tx - 1.0f, ty - 1.0f);
    float u = k_fade(tx), v = k_fade(ty);
    return 0.6324555f * k_mix(k_mix(n00, n10, u), k_mix(n01, n11, u), v);
}

/* Value noise in [-1, 1]: random lattice values, quintic interpolation. */
K_FN float k_value_noise(uint seed, float x, float y, uint px, uint py)
{
    float fx = k_floor(x), fy = k_floor(y);
    float tx = x - fx, ty = y - fy;
    uint ix0 = k_wrap_cell(fx, px), iy0 = k_wrap_cell(fy, py);
    uint ix1 = k_cell_add(ix0, 1, px), iy1 = k_cell_add(iy0, 1, py);
    float n00 = k_u01(k_hash2i(seed, ix0, iy0));
    float n10 = k_u01(k_hash2i(seed, ix1, iy0));
    float n01 = k_u01(k_hash2i(seed, ix0, iy1));
    float n11 = k_u01(k_hash2i(seed, ix1, iy1));
    float u = k_fade(tx), v = k_fade(ty);
    return 2.0f * k_mix(k_mix(n00, n10, u), k_mix(n01, n11, u), v) - 1.0f;
}

/* One simplex corner's contribution: (0.5 - r^2)^4 (g . d). */
K_FN float k_simplex_corner(uint h, float x, float y)
{
    float t = 0.5f - x * x - y * y;
    if (t <= 0.0f) return 0.0f;
    t = t * t;
    return t * t * k_grad2(h, x, y);
}

/* Simplex noise in [-1, 1] (Gustavson's 2D formulation on a skewed triangular lattice). The
 * lattice hash wraps at K_NOISE_PERIOD in skewed coordinates; simplex noise is not tileable. */
K_FN float k_simplex_noise(uint seed, float x, float y)
{
    float F2 = 0.36602540378f; /* (sqrt(3) - 1) / 2 */
    float G2 = 0.21132486540f; /* (3 - sqrt(3)) / 6 */
    float s = (x + y) * F2;
    float fi = k_floor(x + s), fj = k_floor(y + s);
    float t = (fi + fj) * G2;
    float x0 = x - (fi - t), y0 = y - (fj - t);
    int i1 = x0 > y0 ? 1 : 0;
    int j1 = 1 - i1;
    float x1 = x0 - K_F(i1) + G2, y1 = y0 - K_F(j1) + G2;
    float x2 = x0 - 1.0f + 2.0f * G2, y2 = y0 - 1.0f + 2.0f * G2;
    uint ii = k_wrap_cell(fi, K_NOISE_PERIOD), jj = k_wrap_cell(fj, K_NOISE_PERIOD);
    float n0 = k_simplex_corner(k_hash2i(seed, ii, jj), x0, y0);
    float n1 = k_simplex_corner(k_hash2i(seed, k_cell_add(ii, i1, K_NOISE_PERIOD), k_cell_add(jj, j1, K_NOISE_PERIOD)),
                                x1, y1);
    float n2 =
        k_simplex_corner(k_hash2i(seed, k_cell_add(ii, 1, K_NOISE_PERIOD), k_cell_add(jj, 1, K_NOISE_PERIOD)), x2, y2);
    return K_SIMPLEX_SCALE * (n0 + n1 + n2);
}

/* Cellular (Worley) noise: distances to the nearest (F1) and second nearest (F2) feature point,
 * one uniformly jittered point per cell, searched over the 5 x 5 neighbourhood (a 3 x 3 search
 * misses the true nearest point when the query sits near a cell edge). */
K_FN k_vec2 k_cellular(uint seed, float x, float y, uint px, uint py)
{
    float fx = k_floor(x), fy = k_floor(y);
    float tx = x - fx, ty = y - fy;
    uint cx = k_wrap_cell(fx, px), cy = k_wrap_cell(fy, py);
    float f1 = 1.0e9f, f2 = 1.0e9f;
    for (int dy = -2; dy <= 2; dy++) {
        uint gy = k_cell_add(cy, dy, py);
        for (int dx = -2; dx <= 2; dx++) {
            uint h = k_hash2i(seed, k_cell_add(cx, dx, px), gy);
            float ox = K_F(dx) + k_u01(h) - tx;
            float oy = K_F(dy) + k_u01(k_hash(h)) - ty;
            float d2 = ox * ox + oy * oy;
            if (d2 < f1) {
                f2 = f1;
                f1 = d2;
            } else if (d2 < f2) {
                f2 = d2;
            }
        }
    }
    return k_vec2(kx_sqrt(f1), kx_sqrt(f2));
}

/* Sine noise in [-1, 1]: sin(2 pi x) sin(2 pi y), period 1 cell. Fastest and periodic; fBm's
 * per-octave offsets and rotations break its regularity. The coordinate is first reduced modulo
 * the period (without dividing) so that sin() sees a small argument. */
K_FN float k_sine_noise(float x, float y, uint px, uint py)
{
    float fx = k_floor(x), fy = k_floor(y);
    float xr = K_F(k_wrap_cell(fx, px)) + (x - fx);
    float yr = K_F(k_wrap_cell(fy, py)) + (y - fy);
    return k_sincos(K_TAU * xr).x * k_sincos(K_TAU * yr).x;
}

/* Dispatch on the noise kind. Cellular F1 is mapped from [0, sqrt(2)] to [-1, 1]; "cellular-f2"
 * is the edge distance F2 - F1, mapped from [0, 1] (clamped) to [-1, 1]. */
K_FN float k_noise(uint kind, uint seed, float x, float y, uint px, uint py)
{
    if (kind == K_NOISE_VALUE) return k_value_noise(seed, x, y, px, py);
    if (kind == K_NOISE_SIMPLEX) return k_simplex_noise(seed, x, y);
    if (kind == K_NOISE_CELLULAR) {
        k_vec2 f = k_cellular(seed, x, y, px, py);
        return k_min(f.x * 1.41421356f - 1.0f, 1.0f);
    }
    if (kind == K_NOISE_CELLULAR_F2) {
        k_vec2 f = k_cellular(seed, x, y, px, py);
        return 2.0f * k_min(f.y - f.x, 1.0f) - 1.0f;
    }
    if (kind == K_NOISE_SINE) return k_sine_noise(x, y, px, py);
    return k_gradient_noise(seed, x, y, px, py);
}

#endif
