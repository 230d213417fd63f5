// The chaos game: one invocation per chain, `nsteps` steps per dispatch, every plotted point
// splatted into integer histograms with atomics (order-independent sums). The math is
// kernels/ifs.h; host/gen/ifs/layer.c runs the same loop natively. Included by ifs.comp (32-bit atomics:
// a hit and its colour are two adds, and a third for the colour word's carry) and ifs64.comp
// (FB_IFS_INT64: one 64-bit add per point, whose result nothing waits for).
#define K_GLSL 1
#include "../kernels/common.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Condensation on or off, fixed per pipeline: without it the second chain is folded away.
layout(constant_id = 0) const uint CONDENSATION = 0u;

#define K_IFS_MAPS_BUFFER                                                                                              \
    layout(std430, set = 0, binding = 0) readonly buffer Maps                                                          \
    {                                                                                                                  \
        K_IfsMap m[];                                                                                                  \
    }                                                                                                                  \
    maps;
#define k_ifs_maps maps.m
#include "../kernels/ifs.h"

layout(push_constant) uniform Push
{
    K_IfsParams p;
}
pc;

layout(std430, set = 0, binding = 1) buffer Chains
{
    K_IfsChain s[];
}
chains;
// per chain, this dispatch: points outside the frame, points discarded, restarts, (unused)
layout(std430, set = 0, binding = 2) writeonly buffer Counts
{
    uvec4 v[];
}
counts;
#ifdef FB_IFS_INT64
// per cell: hits and colour sum since the last fold (kernels/ifs.h, K_IFS_HIT_BITS); bindings 4 and 5
// are not used
layout(std430, set = 0, binding = 3) buffer Hits { uint64_t v[]; } hits;
#else
layout(std430, set = 0, binding = 3) buffer Hits { uint v[]; } hits;
layout(std430, set = 0, binding = 4) buffer SumLo { uint v[]; } sum_lo;
layout(std430, set = 0, binding = 5) buffer SumHi { uint v[]; } sum_hi;
#endif

void main()
{
    uint i = gl_GlobalInvocationID.x;
    K_IfsParams p = pc.p;
    if (i < p.chain0 || i >= p.chains) return;
    if (CONDENSATION == 0u) p.cmaps = 0u;
    uint total = k_ifs_total(p, i);
    uint end = min(total, p.step0 + p.nsteps);
    uvec4 n = uvec4(0u);
    if (p.step0 < end) {
        // (not a ?: between a local and a buffer struct: glslang stores the wrong type for that)
        K_IfsChain s;
        if (p.step0 == 0u)
            s = k_ifs_init(p, i);
        else
            s = chains.s[i];
        for (uint t = p.step0; t < end; t++) {
            s = k_ifs_step(p, s, i, t);
            uint cell = k_ifs_target(p, s);
            if (cell == K_IFS_NONE) { // the counters move only for points not plotted
                n.x += k_ifs_outside(s, cell);
                n.y += k_ifs_discarded(s);
                n.z += k_ifs_restarted(s);
            } else {
                uint q = k_ifs_quant(s.c);
#ifdef FB_IFS_INT64
                // its result unused: nothing waits for the add (a GPU sends it off as a reduction)
                atomicAdd(hits.v[cell], (uint64_t(q) << K_IFS_HIT_BITS) | uint64_t(1u));
#else
                atomicAdd(hits.v[cell], 1u);
                uint old = atomicAdd(sum_lo.v[cell], q);
                if (old + q < old) atomicAdd(sum_hi.v[cell], 1u); // the carry out of the low word
#endif
            }
        }
        chains.s[i] = s;
    }
    counts.v[i] = n;
}
