#version 450
// Warped Julia sets: one invocation per pixel of a strip. The math is kernels/julia.h.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../kernels/julia.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// The mapping, fixed per pipeline so that the compiler folds the other one away.
layout(constant_id = 0) const uint MAPPING = 0u;

layout(push_constant) uniform Push
{
    K_JuliaParams p;
    uint y0;   // first image row of this strip
    uint rows; // rows in this strip
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Iter { uint v[]; } o_iter;
layout(std430, set = 0, binding = 1) writeonly buffer Smooth { float v[]; } o_n;
layout(std430, set = 0, binding = 2) writeonly buffer Inside { float v[]; } o_inside;
layout(std430, set = 0, binding = 3) writeonly buffer De { float v[]; } o_de;

void main()
{
    uint x = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    K_JuliaParams p = pc.p;
    p.mapping = MAPPING;
    K_JuliaResult res = k_julia_pixel(p, x, pc.y0 + r);
    uint i = r * p.width + x;
    o_iter.v[i] = res.iter;
    o_n.v[i] = res.nsmooth;
    o_inside.v[i] = float(res.inside);
    o_de.v[i] = res.de;
}
