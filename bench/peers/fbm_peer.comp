#version 450
// The fbm layer's formula as plainly as GLSL allows, one pixel an invocation: the minimal shader
// the layer's own (shaders/fbm.comp, fbm_env.comp) is measured against in `fractalbake bench`
// (host/gen/fbm/bench.c). The same hashes (one per pixel, two per octave, the lattice's), the same
// rotation and offsets per octave, each noise kind written out for a lattice that wraps at 4096
// cells (a mask), with none of the layer's generality: no styles, tiling, warp or huge-coordinate
// path, and one noise kind and mapping per pipeline (constants 0 and 1). Where every lattice index
// stays under 2^24 cells (the bench's scenes) its values are the layer's to the bit: the bench
// checks it. The sphere's directions, sin and cos and the square roots use the exact helpers of
// kernels/ (any device), as every shader of the project must.
#extension GL_GOOGLE_include_directive : require
layout(constant_id = 0) const uint NOISE = 0u;   // kernels/noise.h: gradient, value, simplex, cellular, cellular-f2, sine
layout(constant_id = 1) const uint MAPPING = 0u; // rect (2D noise), latlong or cube (gradient noise on the sphere)
#define K_GLSL   1
#define K_ENVMAP 1
#include "../../kernels/sincos.h"
#include "../../kernels/hash.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// The layer's push block (kernels/fbm.h K_FbmParams, then y0 and rows), read member by member.
layout(push_constant) uniform Push
{
    uint seed, noise, octaves, flags;
    float gain, lacunarity, rot_c, rot_s, freq_x, freq_y, offset_x, offset_y, warp;
    uint width, height;
    float inv_width, inv_height, inv_freq_x, inv_freq_y;
    uint mapping, pad1, y0, rows;
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Out
{
    float v[];
}
dst;

uint cell(float f)
{
    return uint(int(f)) & 4095u;
}

uint corner(uint seed, uint ix, uint iy)
{
    return k_hash((ix * 0x9e3779b1u) ^ k_hash(iy ^ seed ^ 0x632be5abu));
}

float fade(float t)
{
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

float grad2(uint h, float x, float y)
{
    uint b = h & 7u;
    float u = b < 4u ? x : y;
    float v = b < 4u ? y : x;
    return ((b & 1u) != 0u ? -u : u) + ((b & 2u) != 0u ? -2.0 * v : 2.0 * v);
}

float u01(uint h)
{
    return float(h >> 8) * (1.0 / 16777216.0);
}

float gradient(uint seed, float x, float y)
{
    float fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
    uint ix0 = cell(fx), iy0 = cell(fy), ix1 = (ix0 + 1u) & 4095u, iy1 = (iy0 + 1u) & 4095u;
    float n00 = grad2(corner(seed, ix0, iy0), tx, ty), n10 = grad2(corner(seed, ix1, iy0), tx - 1.0, ty);
    float n01 = grad2(corner(seed, ix0, iy1), tx, ty - 1.0), n11 = grad2(corner(seed, ix1, iy1), tx - 1.0, ty - 1.0);
    float fu = fade(tx), fv = fade(ty);
    float a = n00 + (n10 - n00) * fu, b = n01 + (n11 - n01) * fu;
    return 0.6324555 * (a + (b - a) * fv);
}

float value(uint seed, float x, float y)
{
    float fx = floor(x), fy = floor(y);
    uint ix0 = cell(fx), iy0 = cell(fy), ix1 = (ix0 + 1u) & 4095u, iy1 = (iy0 + 1u) & 4095u;
    float n00 = u01(corner(seed, ix0, iy0)), n10 = u01(corner(seed, ix1, iy0));
    float n01 = u01(corner(seed, ix0, iy1)), n11 = u01(corner(seed, ix1, iy1));
    float fu = fade(x - fx), fv = fade(y - fy);
    float a = n00 + (n10 - n00) * fu, b = n01 + (n11 - n01) * fu;
    return 2.0 * (a + (b - a) * fv) - 1.0;
}

float simplex_corner(uint h, float x, float y)
{
    float t = 0.5 - x * x - y * y;
    if (t <= 0.0) return 0.0;
    t = t * t;
    return t * t * grad2(h, x, y);
}

float simplex(uint seed, float x, float y)
{
    float F2 = 0.36602540378, G2 = 0.21132486540;
    float s = (x + y) * F2;
    float fi = floor(x + s), fj = floor(y + s);
    float t = (fi + fj) * G2;
    float x0 = x - (fi - t), y0 = y - (fj - t);
    uint i1 = x0 > y0 ? 1u : 0u, j1 = 1u - i1;
    uint ii = cell(fi), jj = cell(fj);
    float n0 = simplex_corner(corner(seed, ii, jj), x0, y0);
    float n1 = simplex_corner(corner(seed, (ii + i1) & 4095u, (jj + j1) & 4095u), x0 - float(i1) + G2,
                              y0 - float(j1) + G2);
    float n2 = simplex_corner(corner(seed, (ii + 1u) & 4095u, (jj + 1u) & 4095u), x0 - 1.0 + 2.0 * G2,
                              y0 - 1.0 + 2.0 * G2);
    return 45.22 * (n0 + n1 + n2);
}

// F1 and F2, squared, over the 5 x 5 cells around (x, y)
vec2 cellular(uint seed, float x, float y)
{
    float fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
    uint cx = cell(fx), cy = cell(fy);
    float f1 = 1.0e9, f2 = 1.0e9;
    for (int dy = -2; dy <= 2; dy++)
        for (int dx = -2; dx <= 2; dx++) {
            uint h = corner(seed, uint(int(cx) + dx) & 4095u, uint(int(cy) + dy) & 4095u);
            float ox = float(dx) + u01(h) - tx, oy = float(dy) + u01(k_hash(h)) - ty;
            float d2 = ox * ox + oy * oy;
            f2 = d2 < f1 ? f1 : min(f2, d2);
            f1 = min(f1, d2);
        }
    return vec2(kx_sqrt(f1), kx_sqrt(f2));
}

float sine(float x, float y)
{
    float fx = floor(x), fy = floor(y);
    float xr = float(cell(fx)) + (x - fx), yr = float(cell(fy)) + (y - fy);
    return k_sincos(K_TAU * xr).x * k_sincos(K_TAU * yr).x;
}

float noise2(uint seed, float x, float y)
{
    if (NOISE == 1u) return value(seed, x, y);
    if (NOISE == 2u) return simplex(seed, x, y);
    if (NOISE == 3u) return min(cellular(seed, x, y).x * 1.41421356 - 1.0, 1.0);
    if (NOISE == 4u) {
        vec2 f = cellular(seed, x, y);
        return 2.0 * min(f.y - f.x, 1.0) - 1.0;
    }
    if (NOISE == 5u) return sine(x, y);
    return gradient(seed, x, y);
}

float plane(uint px, uint py)
{
    float u = (float(px) + 0.5) * pc.inv_width;
    float v = 1.0 - (float(py) + 0.5) * pc.inv_height;
    uint seed = k_hash(0x0fb0u ^ k_hash(0u ^ k_hash(pc.seed ^ 0x9e3779b9u)));
    float x = u * pc.freq_x + pc.offset_x, y = v * pc.freq_y + pc.offset_y;
    float amp = 1.0, sum = 0.0;
    for (uint i = 0u; i < pc.octaves; i++) {
        uint h = k_hash(seed + i * 0x9e3779b9u);
        sum += amp * noise2(h, x, y);
        amp *= pc.gain;
        float nx = pc.lacunarity * (pc.rot_c * x - pc.rot_s * y);
        float ny = pc.lacunarity * (pc.rot_s * x + pc.rot_c * y);
        uint ho = k_hash(h ^ 0x5bd1e995u);
        x = nx + float(ho & 0xffffu) * (64.0 / 65536.0);
        y = ny + float(ho >> 16) * (64.0 / 65536.0);
    }
    return sum;
}

float grad3(uint h, float x, float y, float z)
{
    uint b = h & 15u;
    float u = b < 8u ? x : y;
    float v = b < 4u ? y : ((b == 12u || b == 14u) ? x : z);
    return ((b & 1u) != 0u ? -u : u) + ((b & 2u) != 0u ? -v : v);
}

// gradient noise in 3D: the lattice hash of (ix, iy) under a hash of iz and the seed
float gradient3(uint seed, float x, float y, float z)
{
    float fx = floor(x), fy = floor(y), fz = floor(z), tx = x - fx, ty = y - fy, tz = z - fz;
    uint x0 = cell(fx), y0 = cell(fy), x1 = (x0 + 1u) & 4095u, y1 = (y0 + 1u) & 4095u;
    uint s0 = k_hash(cell(fz) ^ seed ^ 0x2545f491u), s1 = k_hash(((cell(fz) + 1u) & 4095u) ^ seed ^ 0x2545f491u);
    float u = fade(tx), v = fade(ty), w = fade(tz);
    float g000 = grad3(corner(s0, x0, y0), tx, ty, tz), g100 = grad3(corner(s0, x1, y0), tx - 1.0, ty, tz);
    float g010 = grad3(corner(s0, x0, y1), tx, ty - 1.0, tz);
    float g110 = grad3(corner(s0, x1, y1), tx - 1.0, ty - 1.0, tz);
    float g001 = grad3(corner(s1, x0, y0), tx, ty, tz - 1.0);
    float g101 = grad3(corner(s1, x1, y0), tx - 1.0, ty, tz - 1.0);
    float g011 = grad3(corner(s1, x0, y1), tx, ty - 1.0, tz - 1.0);
    float g111 = grad3(corner(s1, x1, y1), tx - 1.0, ty - 1.0, tz - 1.0);
    float a0 = g000 + (g100 - g000) * u, b0 = g010 + (g110 - g010) * u;
    float a1 = g001 + (g101 - g001) * u, b1 = g011 + (g111 - g011) * u;
    float c0 = a0 + (b0 - a0) * v, c1 = a1 + (b1 - a1) * v;
    return clamp(c0 + (c1 - c0) * w, -1.0, 1.0);
}

float sphere(uint px, uint py)
{
    vec3 d = k_env_dir_exact(MAPPING, float(px), float(py), pc.width, pc.height);
    float len = kx_sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    d = vec3(kx_div(d.x, len), kx_div(d.y, len), kx_div(d.z, len));
    uint seed = k_hash(0x0fb3u ^ k_hash(0u ^ k_hash(pc.seed ^ 0x9e3779b9u)));
    float k = pc.freq_x * (1.0 / K_TAU);
    float x = d.x * k + pc.offset_x, y = d.y * k + pc.offset_y, z = d.z * k;
    float amp = 1.0, sum = 0.0;
    for (uint i = 0u; i < pc.octaves; i++) {
        uint h = k_hash(seed + i * 0x9e3779b9u);
        sum += amp * gradient3(h, x, y, z);
        amp *= pc.gain;
        float ax = pc.rot_c * x - pc.rot_s * y, ay = pc.rot_s * x + pc.rot_c * y;
        float by = pc.rot_c * ay - pc.rot_s * z, bz = pc.rot_s * ay + pc.rot_c * z;
        uint ho = k_hash(h ^ 0x5bd1e995u), ho2 = k_hash(ho);
        x = pc.lacunarity * ax + float(ho & 0xffffu) * (64.0 / 65536.0);
        y = pc.lacunarity * by + float(ho >> 16) * (64.0 / 65536.0);
        z = pc.lacunarity * bz + float(ho2 & 0xffffu) * (64.0 / 65536.0);
    }
    return sum;
}

void main()
{
    uint px = gl_GlobalInvocationID.x, r = gl_GlobalInvocationID.y;
    if (px >= pc.width || r >= pc.rows) return;
    dst.v[r * pc.width + px] = MAPPING == 0u ? plane(px, pc.y0 + r) : sphere(px, pc.y0 + r);
}
