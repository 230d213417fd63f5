#version 450
// What the device does with fp32 subnormals (`fractalbake devices`): two products of values read at
// run time, so that no compiler folds them. v[0] * v[1] = 2^-126 * 0.5 is a subnormal result
// (2^-127, or 0 where results are flushed); v[2] * v[3] = 2^-140 * 2^20 has a subnormal operand and
// a normal result (2^-120, or 0 where operands are flushed). host/core/probe.c reads v[4] and v[5].
layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) buffer Probe
{
    float v[];
}
p;

void main()
{
    p.v[4] = p.v[0] * p.v[1];
    p.v[5] = p.v[2] * p.v[3];
}
