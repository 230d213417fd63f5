/*
 * Band-limited 3D base noises, for fields on the unit sphere (environment maps: a direction is a
 * point in space, so a 3D noise has no seam and no pinch anywhere on the sphere). The same six
 * kinds as noise.h, each its 3D form:
 *   gradient   Perlin's improved noise (Perlin, "Improving Noise", SIGGRAPH 2002): 12 edge gradients
 *   value      random lattice values, quintic interpolation on the cube
 *   simplex    Gustavson's 3D formulation ("Simplex noise demystified", 2005) on the skewed lattice
 *   cellular   Worley's F1 and F2 ("A Cellular Texture Basis Function", SIGGRAPH 1996), searched
 *              over the 5 x 5 x 5 neighbourhood, cells farther than the current F2 skipped
 *   sine       sin(2 pi x) sin(2 pi y) sin(2 pi z)
 * Each lattice wraps at K_NOISE_PERIOD cells (a mask), far beyond any scale on the unit sphere.
 * Written in the common C/GLSL subset (common.h); every operation the same in both languages.
 */
#ifndef FB_KERNELS_NOISE3_H
#define FB_KERNELS_NOISE3_H

#include "noise.h"
#include "sincos.h"

/* Hash of 3D lattice coordinates under an (already hashed) seed: the 2D hash of (ix, iy) under a
 * seed that depends on the layer iz. */
K_FN uint k_hash3i(uint seed, uint ix, uint iy, uint iz)
{
    return k_hash2i(k_hash(iz ^ seed ^ 0x2545f491u), ix, iy);
}

/* Perlin's 12 gradients (the cube's edge midpoints, four repeated to make 16) dotted with (x, y, z). */
K_FN float k_grad3(uint h, float x, float y, float z)
{
    uint b = h & 15u;
    float u = b < 8u ? x : y;
    float v = b < 4u ? y : ((b == 12u || b == 14u) ? x : z);
    return ((b & 1u) != 0u ? -u : u) + ((b & 2u) != 0u ? -v : v);
}

/* Gradient noise, clamped to [-1, 1] (its extremes are near +-1 with these gradients); 0 at
 * lattice points. */
K_FN float k_gradient_noise3(uint seed, k_vec3 q)
{
    float fx = k_floor(q.x), fy = k_floor(q.y), fz = k_floor(q.z);
    float tx = q.x - fx, ty = q.y - fy, tz = q.z - fz;
    uint P = K_NOISE_PERIOD;
    uint x0 = k_wrap_cell(fx, P), y0 = k_wrap_cell(fy, P), z0 = k_wrap_cell(fz, P);
    uint x1 = k_cell_add(x0, 1, P), y1 = k_cell_add(y0, 1, P), z1 = k_cell_add(z0, 1, P);
    float u = k_fade(tx), v = k_fade(ty), w = k_fade(tz);
    float a0 = k_mix(k_grad3(k_hash3i(seed, x0, y0, z0), tx, ty, tz),
                     k_grad3(k_hash3i(seed, x1, y0, z0), tx - 1.0f, ty, tz), u);
    float b0 = k_mix(k_grad3(k_hash3i(seed, x0, y1, z0), tx, ty - 1.0f, tz),
                     k_grad3(k_hash3i(seed, x1, y1, z0), tx - 1.0f, ty - 1.0f, tz), u);
    float a1 = k_mix(k_grad3(k_hash3i(seed, x0, y0, z1), tx, ty, tz - 1.0f),
                     k_grad3(k_hash3i(seed, x1, y0, z1), tx - 1.0f, ty, tz - 1.0f), u);
    float b1 = k_mix(k_grad3(k_hash3i(seed, x0, y1, z1), tx, ty - 1.0f, tz - 1.0f),
                     k_grad3(k_hash3i(seed, x1, y1, z1), tx - 1.0f, ty - 1.0f, tz - 1.0f), u);
    return k_clamp(k_mix(k_mix(a0, b0, v), k_mix(a1, b1, v), w), -1.0f, 1.0f);
}

/* Value noise in [-1, 1]. */
K_FN float k_value_noise3(uint seed, k_vec3 q)
{
    float fx = k_floor(q.x), fy = k_floor(q.y), fz = k_floor(q.z);
    uint P = K_NOISE_PERIOD;
    uint x0 = k_wrap_cell(fx, P), y0 = k_wrap_cell(fy, P), z0 = k_wrap_cell(fz, P);
    uint x1 = k_cell_add(x0, 1, P), y1 = k_cell_add(y0, 1, P), z1 = k_cell_add(z0, 1, P);
    float u = k_fade(q.x - fx), v = k_fade(q.y - fy), w = k_fade(q.z - fz);
    float a0 = k_mix(k_u01(k_hash3i(seed, x0, y0, z0)), k_u01(k_hash3i(seed, x1, y0, z0)), u);
    float b0 = k_mix(k_u01(k_hash3i(seed, x0, y1, z0)), k_u01(k_hash3i(seed, x1, y1, z0)), u);
    float a1 = k_mix(k_u01(k_hash3i(seed, x0, y0, z1)), k_u01(k_hash3i(seed, x1, y0, z1)), u);
    float b1 = k_mix(k_u01(k_hash3i(seed, x0, y1, z1)), k_u01(k_hash3i(seed, x1, y1, z1)), u);
    return 2.0f * k_mix(k_mix(a0, b0, v), k_mix(a1, b1, v), w) - 1.0f;
}

/* One 3D simplex corner's contribution: (0.6 - r^2)^4 (g . d). */
K_FN float k_simplex3_corner(uint h, float x, float y, float z)
{
    float t = 0.6f - x * x - y * y - z * z;
    if (t <= 0.0f) return 0.0f;
    t = t * t;
    return t * t * k_grad3(h, x, y, z);
}

/* Simplex noise, scaled by Gustavson's 32 and clamped to [-1, 1]. */
K_FN float k_simplex_noise3(uint seed, k_vec3 q)
{
    float F3 = 1.0f / 3.0f, G3 = 1.0f / 6.0f;
    float s = (q.x + q.y + q.z) * F3;
    float fi = k_floor(q.x + s), fj = k_floor(q.y + s), fk = k_floor(q.z + s);
    float t = (fi + fj + fk) * G3;
    float x0 = q.x - (fi - t), y0 = q.y - (fj - t), z0 = q.z - (fk - t);
    /* the simplex: the order of the offsets' sizes */
    int i1 = 0, j1 = 0, k1 = 0, i2 = 0, j2 = 0, k2 = 0;
    if (x0 >= y0) {
        if (y0 >= z0) {
            i1 = 1, i2 = 1, j2 = 1;
        } else if (x0 >= z0) {
            i1 = 1, i2 = 1, k2 = 1;
        } else {
            k1 = 1, i2 = 1, k2 = 1;
        }
    } else {
        if (y0 < z0) {
            k1 = 1, j2 = 1, k2 = 1;
        } else if (x0 < z0) {
            j1 = 1, j2 = 1, k2 = 1;
        } else {
            j1 = 1, i2 = 1, j2 = 1;
        }
    }
    uint P = K_NOISE_PERIOD;
    uint ii = k_wrap_cell(fi, P), jj = k_wrap_cell(fj, P), kk = k_wrap_cell(fk, P);
    float n0 = k_simplex3_corner(k_hash3i(seed, ii, jj, kk), x0, y0, z0);
    float n1 = k_simplex3_corner(k_hash3i(seed, k_cell_add(ii, i1, P), k_cell_add(jj, j1, P), k_cell_add(kk, k1, P)),
                                 x0 - K_F(i1) + G3, y0 - K_F(j1) + G3, z0 - K_F(k1) + G3);
    float n2 = k_simplex3_corner(k_hash3i(seed, k_cell_add(ii, i2, P), k_cell_add(jj, j2, P), k_cell_add(kk, k2, P)),
                                 x0 - K_F(i2) + 2.0f * G3, y0 - K_F(j2) + 2.0f * G3, z0 - K_F(k2) + 2.0f * G3);
    float n3 = k_simplex3_corner(k_hash3i(seed, k_cell_add(ii, 1, P), k_cell_add(jj, 1, P), k_cell_add(kk, 1, P)),
                                 x0 - 1.0f + 3.0f * G3, y0 - 1.0f + 3.0f * G3, z0 - 1.0f + 3.0f * G3);
    return k_clamp(32.0f * (n0 + n1 + n2 + n3), -1.0f, 1.0f);
}

/* The squared distance from offset t in [0, 1) to cell d (-2..2) along one axis (0 inside it). */
K_FN float k_cell_gap2(int d, float t)
{
    float g = d > 0 ? K_F(d) - t : (d < 0 ? t - K_F(d + 1) : 0.0f);
    return g * g;
}

/* Cellular noise: F1 and F2, one uniformly jittered feature point per cell, searched over the
 * 5 x 5 x 5 neighbourhood with the cells whose nearest face is beyond the current F2 skipped. A cell
 * three away is at least 2 away, while F2 exceeds 2 only if the query's own cell and all 26
 * neighbours hold at most one point within 2: in none of tests/test_sky.c's 200,000 queries. */
K_FN k_vec2 k_cellular3(uint seed, k_vec3 q)
{
    float fx = k_floor(q.x), fy = k_floor(q.y), fz = k_floor(q.z);
    float tx = q.x - fx, ty = q.y - fy, tz = q.z - fz;
    uint P = K_NOISE_PERIOD;
    uint cx = k_wrap_cell(fx, P), cy = k_wrap_cell(fy, P), cz = k_wrap_cell(fz, P);
    float f1 = 1.0e9f, f2 = 1.0e9f;
    for (int dz = -2; dz <= 2; dz++) {
        float gz = k_cell_gap2(dz, tz);
        for (int dy = -2; dy <= 2; dy++) {
            float gyz = gz + k_cell_gap2(dy, ty);
            if (gyz >= f2) continue;
            for (int dx = -2; dx <= 2; dx++) {
                if (gyz + k_cell_gap2(dx, tx) >= f2) continue;
                uint h = k_hash3i(seed, k_cell_add(cx, dx, P), k_cell_add(cy, dy, P), k_cell_add(cz, dz, P));
                uint h2 = k_hash(h);
                float ox = K_F(dx) + k_u01(h) - tx;
                float oy = K_F(dy) + k_u01(h2) - ty;
                float oz = K_F(dz) + k_u01(k_hash(h2)) - tz;
                float d2 = ox * ox + oy * oy + oz * oz;
                if (d2 < f1) {
                    f2 = f1;
                    f1 = d2;
                } else if (d2 < f2) {
                    f2 = d2;
                }
            }
        }
    }
    return k_vec2(kx_sqrt(f1), kx_sqrt(f2));
}

/* Sine noise in [-1, 1], period 1 cell, the coordinate reduced first as in 2D; sin from sincos.h,
 * the same bits on every device. */
K_FN float k_sine_noise3(k_vec3 q)
{
    float fx = k_floor(q.x), fy = k_floor(q.y), fz = k_floor(q.z);
    uint P = K_NOISE_PERIOD;
    float xr = K_F(k_wrap_cell(fx, P)) + (q.x - fx);
    float yr = K_F(k_wrap_cell(fy, P)) + (q.y - fy);
    float zr = K_F(k_wrap_cell(fz, P)) + (q.z - fz);
    return k_sincos(K_TAU * xr).x * k_sincos(K_TAU * yr).x * k_sincos(K_TAU * zr).x;
}

/* Dispatch on the noise kind, with noise.h's mappings of cellular F1 (from [0, sqrt(3)]) and of
 * the edge distance F2 - F1 (from [0, 1], clamped) to [-1, 1]. */
K_FN float k_noise3(uint kind, uint seed, k_vec3 q)
{
    if (kind == K_NOISE_VALUE) return k_value_noise3(seed, q);
    if (kind == K_NOISE_SIMPLEX) return k_simplex_noise3(seed, q);
    if (kind == K_NOISE_CELLULAR) {
        k_vec2 f = k_cellular3(seed, q);
        return k_min(f.x * 1.15470054f - 1.0f, 1.0f);
    }
    if (kind == K_NOISE_CELLULAR_F2) {
        k_vec2 f = k_cellular3(seed, q);
        return 2.0f * k_min(f.y - f.x, 1.0f) - 1.0f;
    }
    if (kind == K_NOISE_SINE) return k_sine_noise3(q);
    return k_gradient_noise3(seed, q);
}

#endif
