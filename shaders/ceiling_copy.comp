#version 450
// The machine's memory ceiling (fractalbake bench): a copy of one storage buffer into another, a
// vec4 per invocation; the bytes moved are twice the buffer's size.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) writeonly buffer Dst
{
    vec4 v[];
}
dst;

layout(std430, set = 0, binding = 1) readonly buffer Src
{
    vec4 v[];
}
src;

void main()
{
    uint i = gl_GlobalInvocationID.y * 2097152u + gl_GlobalInvocationID.x;
    dst.v[i] = src.v[i];
}
