/*
 * Fractional Brownian motion (SPEC.md section 1, seed 002):
 *
 *     fbm(x) = sum_{i=0}^{n-1} G^i * noise(R^i (L^i x) + o_i),   G = 2^-H
 *
 * The parameter block is shared with the shader's push constants (std430: scalars only, so the C
 * and GLSL offsets agree; host/gen/fbm/layer.c asserts every offset).
 */
#ifndef FB_KERNELS_FBM_H
#define FB_KERNELS_FBM_H

#include "noise.h"
#if K_WITH_ENVMAP
#include "noise3.h"
#include "sincos.h"
#endif

#define K_FBM_RIDGED   1u
#define K_FBM_BILLOW   2u
#define K_FBM_TILEABLE 4u

K_STRUCT(K_FbmParams)
{
    uint seed;
    uint noise;   /* K_NOISE_* */
    uint octaves; /* 1..32 */
    uint flags;   /* K_FBM_* */
    float gain;   /* G = 2^-H */
    float lacunarity;
    float rot_c; /* per-octave rotation R, as cos and sin (computed once on the host) */
    float rot_s;
    float freq_x; /* octave-0 cells across the image width / height */
    float freq_y;
    float offset_x; /* domain offset, in octave-0 cells */
    float offset_y;
    float warp; /* domain-warp strength, in octave-0 cells; 0 disables */
    uint width;
    uint height;
    float inv_width;  /* 1/W, 1/H, 1/fx, 1/fy: computed once on the host, because a shader division */
    float inv_height; /* may differ from C's by 2.5 ULP while a multiplication rounds the same */
    float inv_freq_x;
    float inv_freq_y;
    uint mapping; /* K_ENV_RECT (the plane), K_ENV_LATLONG or K_ENV_CUBE (kernels/envmap.h) */
    uint pad1;
}
K_END(K_FbmParams)

/* Shapes one octave's noise value: ridged (1 - |n|)^2 in [0, 1], billow 2|n| - 1 in [-1, 1]. */
K_FN float k_fbm_shape(float n, uint flags)
{
    if ((flags & K_FBM_RIDGED) != 0u) {
        float r = 1.0f - k_abs(n);
        return r * r;
    }
    if ((flags & K_FBM_BILLOW) != 0u) return 2.0f * k_abs(n) - 1.0f;
    return n;
}

/*
 * The fBm sum at texture coordinates (u, v) for one random stream (0: the field itself, 1 and 2:
 * the two domain-warp displacement fields). Ordinary fBm iterates x_{i+1} = L R x_i + o_{i+1} from
 * x_0 = (u fx, v fy) + offset. Tileable fBm instead uses an integral number of cells per octave,
 * P_i = round(fx L^i), with the lattice period set to P_i, and no rotation (a rotated square
 * lattice is not periodic on the image rectangle): every octave, and so the sum, wraps exactly.
 */
K_FN float k_fbm_uv(K_FbmParams p, uint stream, float u, float v)
{
    /* One hash per pixel for the stream, one per octave for its noise seed and offsets. */
    uint seed = k_hash3(p.seed, stream, 0x0fb0u);
    bool tileable = (p.flags & K_FBM_TILEABLE) != 0u;
    float x = u * p.freq_x + p.offset_x;
    float y = v * p.freq_y + p.offset_y;
    float cells_x = p.freq_x, cells_y = p.freq_y;
    float amp = 1.0f, sum = 0.0f;
    for (uint i = 0u; i < p.octaves; i++) {
        uint h = k_hash(seed + i * 0x9e3779b9u);
        uint per_x = K_NOISE_PERIOD, per_y = K_NOISE_PERIOD;
        float qx = x, qy = y;
        if (tileable) {
            float rx = k_max(k_floor(cells_x + 0.5f), 1.0f);
            float ry = k_max(k_floor(cells_y + 0.5f), 1.0f);
            per_x = K_U(K_I(k_min(rx, 16777216.0f)));
            per_y = K_U(K_I(k_min(ry, 16777216.0f)));
            /* integral offsets keep every octave periodic */
            qx = u * rx + K_F(h & 255u) + p.offset_x;
            qy = v * ry + K_F((h >> 8) & 255u) + p.offset_y;
        }
        sum += amp * k_fbm_shape(k_noise(p.noise, h, qx, qy, per_x, per_y), p.flags);
        amp *= p.gain;
        cells_x *= p.lacunarity;
        cells_y *= p.lacunarity;
        /* next octave's domain: scale, rotate, offset by a fraction of a cell */
        float nx = p.lacunarity * (p.rot_c * x - p.rot_s * y);
        float ny = p.lacunarity * (p.rot_s * x + p.rot_c * y);
        uint ho = k_hash(h ^ 0x5bd1e995u);
        x = nx + K_F(ho & 0xffffu) * (64.0f / 65536.0f);
        y = ny + K_F(ho >> 16) * (64.0f / 65536.0f);
    }
    return sum;
}

/* The fBm value of pixel (px, py): texture coordinates u = (x + 0.5)/W, v = 1 - (y + 0.5)/H, then
 * an optional domain warp u' = u + w fbm_1(u, v) / fx, v' = v + w fbm_2(u, v) / fy. */
K_FN float k_fbm_pixel(K_FbmParams p, uint px, uint py)
{
    float u = (K_F(px) + 0.5f) * p.inv_width;
    float v = 1.0f - (K_F(py) + 0.5f) * p.inv_height;
    if (p.warp != 0.0f) {
        float du = k_fbm_uv(p, 1u, u, v);
        float dv = k_fbm_uv(p, 2u, u, v);
        u = u + p.warp * du * p.inv_freq_x;
        v = v + p.warp * dv * p.inv_freq_y;
    }
    return k_fbm_uv(p, 0u, u, v);
}

#if K_WITH_ENVMAP
/*
 * fBm on the unit sphere (environment maps), for one random stream: the octaves of 3D noise
 * (noise3.h) at x_0 = d fx / (2 pi) + offset, so that fx octave-0 cells go round the equator as
 * they go across a rect image's width, then x_{i+1} = L R3 x_i + o_{i+1}, R3 the per-octave
 * rotation (rot_c, rot_s) about z and then about x, o a hashed fraction of a cell as in 2D. A
 * direction has no edge, so there is no seam and no pinch; the tileable flag does not apply.
 */
K_FN float k_fbm3(K_FbmParams p, uint stream, k_vec3 d)
{
    uint seed = k_hash3(p.seed, stream, 0x0fb3u);
    float k = p.freq_x * (1.0f / K_TAU);
    float x = d.x * k + p.offset_x, y = d.y * k + p.offset_y, z = d.z * k;
    float amp = 1.0f, sum = 0.0f;
    for (uint i = 0u; i < p.octaves; i++) {
        uint h = k_hash(seed + i * 0x9e3779b9u);
        sum += amp * k_fbm_shape(k_noise3(p.noise, h, k_vec3(x, y, z)), p.flags);
        amp *= p.gain;
        float ax = p.rot_c * x - p.rot_s * y;
        float ay = p.rot_s * x + p.rot_c * y;
        float by = p.rot_c * ay - p.rot_s * z;
        float bz = p.rot_s * ay + p.rot_c * z;
        uint ho = k_hash(h ^ 0x5bd1e995u), ho2 = k_hash(ho);
        x = p.lacunarity * ax + K_F(ho & 0xffffu) * (64.0f / 65536.0f);
        y = p.lacunarity * by + K_F(ho >> 16) * (64.0f / 65536.0f);
        z = p.lacunarity * bz + K_F(ho2 & 0xffffu) * (64.0f / 65536.0f);
    }
    return sum;
}

/* The fBm value at direction d (any length but zero) with the optional domain warp: d' = d + w
 * (fbm_1, fbm_2, fbm_3)(d) / k, k = fx / (2 pi) cells per unit, then fbm_0(d'). */
K_FN float k_fbm_dir(K_FbmParams p, k_vec3 d)
{
    float len = kx_sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    k_vec3 u = k_vec3(kx_div(d.x, len), kx_div(d.y, len), kx_div(d.z, len));
    if (p.warp != 0.0f) {
        float s = kx_div(p.warp * K_TAU, p.freq_x);
        u = k_vec3(u.x + s * k_fbm3(p, 1u, u), u.y + s * k_fbm3(p, 2u, u), u.z + s * k_fbm3(p, 3u, u));
    }
    return k_fbm3(p, 0u, u);
}

/* The fBm value of pixel (px, py) of the layer's mapping: the plane (k_fbm_pixel) or the direction
 * through the pixel's centre of a lat-long or cube environment map (envmap.h). */
K_FN float k_fbm_map_pixel(K_FbmParams p, uint px, uint py)
{
    if (p.mapping == K_ENV_RECT) return k_fbm_pixel(p, px, py);
    return k_fbm_dir(p, k_env_dir_exact(p.mapping, K_F(px), K_F(py), p.width, p.height));
}

#else
K_FN float k_fbm_map_pixel(K_FbmParams p, uint px, uint py)
{
    return k_fbm_pixel(p, px, py);
}
#endif

#endif
