#version 450
// The chaos game as a GPU programmer writes it first: one invocation a chain, its point, colour and
// transient count in registers and kept in a buffer between dispatches, the counter-based RNG
// k_hash3(seed, chain, step) picking a map by its threshold, the affine map, and one 64-bit atomic
// add a point into the histogram (hits | colour sum << K_IFS_HIT_BITS), its result unused. The
// minimal shader the chaos game (shaders/ifs64.comp) is measured against in `fractalbake bench`
// (host/gen/ifs/bench.c): without the layer's condensation, restarts of escaped chains, counters or
// points parts, so its histogram is the layer's to the bit for a set whose maps never send a point
// out of range (the bench's fern): the bench checks it.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#define K_GLSL 1
#include "../../kernels/common.h"
#define K_IFS_MAPS_BUFFER                                                                                              \
    layout(std430, set = 0, binding = 0) readonly buffer Maps                                                          \
    {                                                                                                                  \
        K_IfsMap m[];                                                                                                  \
    }                                                                                                                  \
    maps;
#define k_ifs_maps maps.m
#include "../../kernels/ifs.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_IfsParams p;
}
pc;

// per chain: x, y, colour, and the transient steps left (as bits)
layout(std430, set = 0, binding = 1) buffer Chains { vec4 s[]; } chains;
layout(std430, set = 0, binding = 2) buffer Hist { uint64_t v[]; } hist;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.p.chains) return;
    uint end = min(pc.p.base + (i < pc.p.extra ? 1u : 0u), pc.p.step0 + pc.p.nsteps);
    if (pc.p.step0 >= end) return;
    float x, y, c;
    uint left;
    if (pc.p.step0 == 0u) { // a random start in [-1, 1)^2, as the layer's first
        uint h = k_hash3(pc.p.seed ^ 0xa511e9b3u, i, 0xffffffffu);
        x = k_u01(h) * 2.0 - 1.0;
        y = k_u01(k_hash(h ^ 0x3c6ef372u)) * 2.0 - 1.0;
        c = 0.5;
        left = pc.p.skip;
    } else {
        vec4 s = chains.s[i];
        x = s.x, y = s.y, c = s.z;
        left = floatBitsToUint(s.w);
    }
    uint n = pc.p.nmaps;
    float fw = float(pc.p.hist_w), fh = float(pc.p.hist_h);
    for (uint t = pc.p.step0; t < end; t++) {
        uint r = k_hash3(pc.p.seed, i, t), k = 0u;
        for (uint j = 1u; j < n; j++) k += r >= maps.m[j].thr ? 1u : 0u;
        K_IfsMap m = maps.m[k];
        float nx = m.a * x + m.b * y + m.e;
        y = m.c * x + m.d * y + m.f;
        x = nx;
        c = (c + m.colour) * 0.5;
        if (left > 0u) {
            left--;
            continue;
        }
        float px = (x - pc.p.x0) * pc.p.sx, py = (pc.p.y0 - y) * pc.p.sy;
        if (px >= 0.0 && py >= 0.0 && px < fw && py < fh) {
            uint q = uint(clamp(c, 0.0, 1.0) * 255.0 + 0.5);
            atomicAdd(hist.v[uint(py) * pc.p.hist_w + uint(px)], (uint64_t(q) << K_IFS_HIT_BITS) | 1ul);
        }
    }
    chains.s[i] = vec4(x, y, c, uintBitsToFloat(left));
}
