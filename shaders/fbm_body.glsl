// fBm noise: one invocation per pixel of a strip of rows (fbm.comp: the plane; fbm_env.comp:
// environment maps). The math is kernels/fbm.h.

// The noise kind and style flags, fixed per pipeline so that the compiler folds the dispatch.
layout(constant_id = 0) const uint NOISE = 0u;
layout(constant_id = 1) const uint FLAGS = 0u;
// 1: every lattice index of every octave stays under 2^24 cells (the host bounds the coordinates):
// the wrap's huge-coordinate path folds away (kernels/noise.h).
layout(constant_id = 2) const uint SMALL = 0u;
// The mapping (rect; latlong or cube in fbm_env.comp, which alone carries the 3D noise), fixed per
// pipeline.
layout(constant_id = 3) const uint MAPPING = 0u;

#define K_GLSL       1
#define K_WRAP_SMALL (SMALL != 0u)
#include "../kernels/fbm.h"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform Push
{
    K_FbmParams p;
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
    K_FbmParams p = pc.p;
    p.noise = NOISE;
    p.flags = FLAGS;
    p.mapping = MAPPING;
    dst.v[r * p.width + x] = k_fbm_map_pixel(p, x, pc.y0 + r);
}
