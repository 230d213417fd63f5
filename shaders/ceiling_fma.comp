#version 450
// The machine's arithmetic ceiling (fractalbake bench): each invocation runs 8 independent chains
// of fused multiply-adds for `iters` rounds (16 FLOP a round), so the dispatch is bound by FMA
// throughput and not by latency or memory. The result is written so that nothing is optimised away.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    uint iters;
    float a, b;
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Out
{
    float v[];
}
dst;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    float x0 = float(i & 255u) * 1e-3, x1 = x0 + 0.1, x2 = x0 + 0.2, x3 = x0 + 0.3;
    float x4 = x0 + 0.4, x5 = x0 + 0.5, x6 = x0 + 0.6, x7 = x0 + 0.7;
    for (uint k = 0u; k < pc.iters; k++) {
        x0 = fma(x0, pc.a, pc.b);
        x1 = fma(x1, pc.a, pc.b);
        x2 = fma(x2, pc.a, pc.b);
        x3 = fma(x3, pc.a, pc.b);
        x4 = fma(x4, pc.a, pc.b);
        x5 = fma(x5, pc.a, pc.b);
        x6 = fma(x6, pc.a, pc.b);
        x7 = fma(x7, pc.a, pc.b);
    }
    dst.v[i] = x0 + x1 + x2 + x3 + x4 + x5 + x6 + x7;
}
