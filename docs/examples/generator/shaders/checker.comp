#version 450
// The checker generator: one invocation per pixel of a strip of rows. The math is kernels/checker.h.
#extension GL_GOOGLE_include_directive : require
#define K_GLSL 1
#include "../kernels/checker.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_CheckerParams p;
    uint y0;   // first image row of this strip
    uint rows; // rows in this strip
}
pc;

layout(std430, set = 0, binding = 0) writeonly buffer Out
{
    float v[];
}
dst;

void main()
{
    uint x = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (x >= pc.p.width || r >= pc.rows) return;
    dst.v[r * pc.p.width + x] = k_checker_pixel(pc.p, x, pc.y0 + r);
}
