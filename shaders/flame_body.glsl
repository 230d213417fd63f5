// The flame's chaos game (kernels/flame.h): one invocation per chain, steps [step0, step0 + nsteps)
// of it per dispatch (the first `fuse` not plotted), each plotted point added into the integer
// histogram with atomics (order-independent sums, the same as the native path's cell for cell).
// host/gen/flame/game.c runs the same chains natively. Included by flame.comp (32-bit atomics: a
// field a word, the atomics' results read for the carries) and flame64.comp (FB_FLAME_INT64: 64-bit
// words whose atomics' results nothing waits for, folded into totals by flame_fold.comp).
//
// flame.comp: a cell has F fields: opaque genomes (COMPACT) hits, red, green, blue (their alpha and
// opacity sums are 4080 x hits); others red, green, blue, alpha, opacity, hits. A word that passes
// 2^32 counts the carry in `carry`, one counter a field, so the host recovers the exact 64-bit sums
// (host/gen/flame/layer.c).
//
// flame64.comp: a cell has K_FLAME_WORDS(COMPACT) words: hits and red (hits in the low
// K_FLAME_HIT_BITS bits), green, blue, and for translucent genomes alpha and opacity, the sums since
// the last fold, exact while fewer than 2^K_FLAME_HIT_BITS points are played in between
// (kernels/flame.h).
#define K_GLSL 1
#include "../kernels/common.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// bit 0: opaque xforms and palette, step mode: 4 fields a cell (else 6); bit 1: flam3's linear
// palette mode (interpolated entries); bit 2: the genome has a final xform (without, its code is
// compiled out: lavapipe would run it under a mask)
layout(constant_id = 0) const uint FLAGS = 0u;
const uint COMPACT = FLAGS & 1u;
const uint LINEAR = (FLAGS >> 1) & 1u;
const uint FINAL = (FLAGS >> 2) & 1u;
// the genome's variations, bits of 0-31, 32-63, 64-95 and 96-98: only their code is compiled
// (kernels/flame_var.h)
layout(constant_id = 1) const uint VMASK0 = 0xffffffffu;
layout(constant_id = 2) const uint VMASK1 = 0xffffffffu;
layout(constant_id = 3) const uint VMASK2 = 0xffffffffu;
layout(constant_id = 4) const uint VMASK3 = 0x7u;
#define K_FLAME_FINAL  (FINAL != 0u)
#define K_FLAME_VMASK0 VMASK0
#define K_FLAME_VMASK1 VMASK1
#define K_FLAME_VMASK2 VMASK2
#define K_FLAME_VMASK3 VMASK3
// each of the genome's variations once a step, not once an xform's variation slot (kernels/flame.h)
#define K_FLAME_ONCE 1

// the xform and variation tables' entries (their uniform buffers' arrays are this long)
layout(constant_id = 5) const uint NXF = 1u;
layout(constant_id = 6) const uint NVAR = 1u;

// The xforms, variations and palette are uniform buffers: on lavapipe a read at an index that differs
// by lane is then a gather, where a storage buffer's is a loop over the 8 lanes with a branch each
// (a step reads some 20 fields of its xform and a few of each variation).
#define K_FLAME_BUFFERS                                                                                                \
    layout(std140, set = 0, binding = 1) uniform Xforms                                                                \
    {                                                                                                                  \
        K_FlameXform k_flame_xf[NXF];                                                                                  \
    };                                                                                                                 \
    layout(std140, set = 0, binding = 2) uniform Vars                                                                  \
    {                                                                                                                  \
        K_FlameVar k_flame_var[NVAR];                                                                                  \
    };                                                                                                                 \
    layout(std430, set = 0, binding = 3) readonly buffer Dist                                                          \
    {                                                                                                                  \
        uint k_flame_dist[];                                                                                           \
    };
#include "../kernels/flame.h"

layout(std140, set = 0, binding = 0) uniform Params
{
    K_FlameParams p;
}
params;
// the palette times 255 in 2^-4 units (r, g, b, a)
layout(std140, set = 0, binding = 4) uniform Palette
{
    uvec4 q[256];
}
pal;
// chain c0 + i's state between dispatches
layout(std430, set = 0, binding = 5) buffer Chains
{
    K_FlameChain s[];
}
chains;
#ifdef FB_FLAME_INT64
layout(std430, set = 0, binding = 6) buffer Hist
{
    uint64_t v[];
}
hist;
#else
layout(std430, set = 0, binding = 6) buffer Hist
{
    uint v[];
}
hist;
layout(std430, set = 0, binding = 7) buffer Carry
{
    uint v[];
}
carry;
#endif

layout(push_constant) uniform Push
{
    uint c0, c1;        // the chains of this run: [c0, c1)
    uint step0, nsteps; // this dispatch's steps of each chain
}
pc;

#ifdef FB_FLAME_INT64
// A point's sums into the words of its cell, W of them from word `at`: hits and red in word 0, then
// green, blue (and alpha, opacity: W = 5). The adds' results are unused: nothing waits for them (a
// GPU sends each off as a reduction), and the host's folds keep every field within its bits.
void add_words(uint at, uint W, uint r, uint g, uint b, uint a, uint o)
{
    atomicAdd(hist.v[at], (uint64_t(r) << K_FLAME_HIT_BITS) | uint64_t(1u));
    atomicAdd(hist.v[at + 1u], uint64_t(g));
    atomicAdd(hist.v[at + 2u], uint64_t(b));
    if (W > 3u) {
        atomicAdd(hist.v[at + 3u], uint64_t(a));
        atomicAdd(hist.v[at + 4u], uint64_t(o));
    }
}
#else
void add1(uint cell, uint f, uint v)
{
    uint F = COMPACT != 0u ? 4u : 6u;
    uint old = atomicAdd(hist.v[cell * F + f], v);
    if (old + v < old) atomicAdd(carry.v[cell * F + f], 1u);
}
#endif

void main()
{
    uint i = pc.c0 + gl_GlobalInvocationID.x;
    if (i >= pc.c1) return;
    K_FlameParams P = params.p;
    uint len = P.fuse + (i + 1u == P.chains ? P.last_len : P.len);
    uint end = min(len, pc.step0 + pc.nsteps);
    if (pc.step0 >= end) return;
    uint key = k_flame_key(P.seed, i);
    // (not a ?: between a local and a buffer struct: glslang stores the wrong type for that)
    K_FlameChain s;
    if (pc.step0 == 0u)
        s = k_flame_init(key);
    else
        s = chains.s[i - pc.c0];
    for (uint t = pc.step0; t < end; t++) {
        s = k_flame_step(P, s, key);
        if (t < P.fuse) continue;
        uint cell = k_flame_cell(P, s);
        uint visq = k_flame_xf[s.vis].visq;
        if (cell == K_FLAME_NONE || visq == 0u) continue;
        uvec4 q;
        if (LINEAR != 0u) {
            uint e = k_flame_lin_index(s.pc), fr = k_flame_lin_frac(s.pc);
            uvec4 a = pal.q[e], b = pal.q[e + 1u];
            q = uvec4(k_flame_lerp(a.x, b.x, fr), k_flame_lerp(a.y, b.y, fr), k_flame_lerp(a.z, b.z, fr),
                      k_flame_lerp(a.w, b.w, fr));
        } else {
            q = pal.q[k_flame_index(s.pc)];
        }
#ifdef FB_FLAME_INT64
        if (COMPACT != 0u) {
            add_words(cell * K_FLAME_WORDS(1u), 3u, q.x, q.y, q.z, 0u, 0u);
        } else {
            add_words(cell * K_FLAME_WORDS(0u), 5u, k_flame_vis(q.x, visq), k_flame_vis(q.y, visq),
                      k_flame_vis(q.z, visq), k_flame_vis(q.w, visq), k_flame_vis(K_FLAME_OPAQUE, visq));
        }
#else
        if (COMPACT != 0u) {
            add1(cell, 0u, 1u);
            add1(cell, 1u, q.x);
            add1(cell, 2u, q.y);
            add1(cell, 3u, q.z);
        } else {
            add1(cell, 0u, k_flame_vis(q.x, visq));
            add1(cell, 1u, k_flame_vis(q.y, visq));
            add1(cell, 2u, k_flame_vis(q.z, visq));
            add1(cell, 3u, k_flame_vis(q.w, visq));
            add1(cell, 4u, k_flame_vis(K_FLAME_OPAQUE, visq));
            add1(cell, 5u, 1u);
        }
#endif
    }
    chains.s[i - pc.c0] = s;
}
