#version 450
// The flame's fold (host/gen/flame/layer.c): the 64-bit words of flame64.comp hold a cell's sums
// since the last fold (kernels/flame.h, K_FLAME_HIT_BITS: hits and red in word 0, then green, blue,
// and for translucent genomes alpha and opacity), exact while fewer than 2^K_FLAME_HIT_BITS points
// were played in between; the fold adds them to the run's 64-bit totals (hits, red, green, blue, and
// alpha, opacity) and clears the cell. Integer arithmetic only.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// 1: opaque genomes, 3 words and 4 totals a cell (else 5 and 6); K_FLAME_HIT_BITS
layout(constant_id = 0) const uint COMPACT = 0u;
layout(constant_id = 1) const uint HIT_BITS = 26u;

layout(push_constant) uniform Push
{
    uint cells;
    uint stride; // cells a row of workgroups covers
}
pc;

layout(std430, set = 0, binding = 0) buffer Packed { uint64_t v[]; } packed;
layout(std430, set = 0, binding = 1) buffer Totals { uint64_t v[]; } totals;

void main()
{
    uint i = gl_GlobalInvocationID.y * pc.stride + gl_GlobalInvocationID.x;
    if (i >= pc.cells) return;
    uint W = COMPACT != 0u ? 3u : 5u, at = i * W, t = i * (W + 1u);
    uint64_t x = packed.v[at];
    if (x == 0ul) return; // every point adds a hit to word 0: a cell without one has all words 0
    packed.v[at] = 0ul;
    totals.v[t] += x & ((uint64_t(1u) << HIT_BITS) - 1ul);
    totals.v[t + 1u] += x >> HIT_BITS;
    for (uint k = 1u; k < W; k++) {
        totals.v[t + 1u + k] += packed.v[at + k];
        packed.v[at + k] = 0ul;
    }
}
