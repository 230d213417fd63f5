#version 450
// The chaos game's fold (host/gen/ifs/layer.c): the 64-bit cells of ifs64.comp hold the hits (low
// K_IFS_HIT_BITS bits) and the colour sum (the rest) added since the last fold, exact while fewer
// than 2^K_IFS_HIT_BITS points were played in between; the fold adds them to the run's totals (hits,
// and the colour sum in two words) and clears the cell. Integer arithmetic only.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define K_GLSL 1
#include "../kernels/common.h"
// (the map table kernels/ifs.h declares: not used here, nor bound)
#define K_IFS_MAPS_BUFFER                                                                                              \
    layout(std430, set = 0, binding = 5) readonly buffer Maps                                                          \
    {                                                                                                                  \
        K_IfsMap m[];                                                                                                  \
    }                                                                                                                  \
    maps;
#define k_ifs_maps maps.m
#include "../kernels/ifs.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    uint cells;
    uint stride; // cells a row of workgroups covers
}
pc;

layout(std430, set = 0, binding = 0) buffer Packed { uint64_t v[]; } packed;
layout(std430, set = 0, binding = 1) buffer Hits { uint v[]; } hits;
layout(std430, set = 0, binding = 2) buffer SumLo { uint v[]; } sum_lo;
layout(std430, set = 0, binding = 3) buffer SumHi { uint v[]; } sum_hi;
// [0] != 0: some cell's hits passed 2^32 - 1 (its total then stays there: saturated, as natively)
layout(std430, set = 0, binding = 4) buffer Flags { uint v[]; } flags;

void main()
{
    uint i = gl_GlobalInvocationID.y * pc.stride + gl_GlobalInvocationID.x;
    if (i >= pc.cells) return;
    uint64_t x = packed.v[i];
    if (x == 0ul) return;
    packed.v[i] = 0ul;
    uint h = uint(x) & K_IFS_HIT_MASK, t = hits.v[i] + h;
    if (t < h) {
        atomicOr(flags.v[0], 1u);
        t = 0xffffffffu;
    }
    hits.v[i] = t;
    uint64_t s = ((uint64_t(sum_hi.v[i]) << 32) | uint64_t(sum_lo.v[i])) + (x >> K_IFS_HIT_BITS);
    sum_lo.v[i] = uint(s);
    sum_hi.v[i] = uint(s >> 32);
}
