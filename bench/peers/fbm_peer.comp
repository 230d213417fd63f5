#version 450
// The fbm layer's formula for gradient noise, written as plainly as GLSL allows: the same hashes
// (one per pixel, two per octave, the lattice's), the same rotation and offsets per octave, with
// none of the layer's generality (no noise kinds, styles, tiling, warp or huge-coordinate path).
// The speed the layer's shader is measured against (bench/lavapipe_peers.c). Where every lattice
// index stays under 2^24 cells (the bench's scene) its values are the layer's to the bit.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// The layer's push block (kernels/fbm.h K_FbmParams, then y0 and rows), read member by member.
layout(push_constant) uniform Push
{
    uint seed, noise, octaves, flags;
    float gain, lacunarity, rot_c, rot_s, freq_x, freq_y, offset_x, offset_y, warp;
    uint width, height;
    float inv_width, inv_height, inv_freq_x, inv_freq_y;
    uint pad0, pad1, y0, rows;
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Out
{
    float v[];
}
dst;

uint hash(uint x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

float grad(uint h, float x, float y)
{
    uint b = h & 7u;
    float u = b < 4u ? x : y;
    float v = b < 4u ? y : x;
    return ((b & 1u) != 0u ? -u : u) + ((b & 2u) != 0u ? -2.0 * v : 2.0 * v);
}

float fade(float t)
{
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

void main()
{
    uint px = gl_GlobalInvocationID.x, r = gl_GlobalInvocationID.y;
    if (px >= pc.width || r >= pc.rows) return;
    float u = (float(px) + 0.5) * pc.inv_width;
    float v = 1.0 - (float(pc.y0 + r) + 0.5) * pc.inv_height;
    uint seed = hash(0x0fb0u ^ hash(0u ^ hash(pc.seed ^ 0x9e3779b9u)));
    float x = u * pc.freq_x + pc.offset_x, y = v * pc.freq_y + pc.offset_y;
    float amp = 1.0, sum = 0.0;
    for (uint i = 0u; i < pc.octaves; i++) {
        uint h = hash(seed + i * 0x9e3779b9u);
        float fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
        uint ix0 = uint(int(fx)) & 4095u, iy0 = uint(int(fy)) & 4095u;
        uint ix1 = (ix0 + 1u) & 4095u, iy1 = (iy0 + 1u) & 4095u;
        uint r0 = hash(iy0 ^ h ^ 0x632be5abu), r1 = hash(iy1 ^ h ^ 0x632be5abu);
        float n00 = grad(hash((ix0 * 0x9e3779b1u) ^ r0), tx, ty);
        float n10 = grad(hash((ix1 * 0x9e3779b1u) ^ r0), tx - 1.0, ty);
        float n01 = grad(hash((ix0 * 0x9e3779b1u) ^ r1), tx, ty - 1.0);
        float n11 = grad(hash((ix1 * 0x9e3779b1u) ^ r1), tx - 1.0, ty - 1.0);
        float fu = fade(tx), fv = fade(ty);
        float a = n00 + (n10 - n00) * fu, b = n01 + (n11 - n01) * fu;
        sum += amp * (0.6324555 * (a + (b - a) * fv));
        amp *= pc.gain;
        float nx = pc.lacunarity * (pc.rot_c * x - pc.rot_s * y);
        float ny = pc.lacunarity * (pc.rot_s * x + pc.rot_c * y);
        uint ho = hash(h ^ 0x5bd1e995u);
        x = nx + float(ho & 0xffffu) * (64.0 / 65536.0);
        y = ny + float(ho >> 16) * (64.0 / 65536.0);
    }
    dst.v[r * pc.width + px] = sum;
}
