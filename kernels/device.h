/*
 * The shape of the device a shader runs on, for kernels whose fastest form differs between a CPU's
 * SIMD lanes and a GPU's SIMT warps (the same bits either way: only the order of independent work
 * changes).
 *
 * On lavapipe an invocation is one lane of an AVX2 register and a thread runs one workgroup's lanes
 * at a time: floating-point latency is exposed, so two independent dependency chains in one
 * invocation pay (two Julia orbits in one loop: 1.86x, bench/RESULTS.md). On a GPU latency is hidden
 * by other warps, and a warp runs a loop until its slowest lane is done: two orbits in one loop then
 * run as long as the slowest of 64 pixels, where one after the other each runs as long as the slowest
 * of its 32.
 *
 * The host (host/io/vkc_work.c) sets the specialisation constant K_SPEC_CPU_DEVICE on every pipeline:
 * true on a CPU device whose memory is mapped directly (lavapipe as it runs by default), false on a
 * GPU, and false on lavapipe under FB_VK_STAGING=1, which takes a discrete GPU's path there so that the
 * tests run the GPU's forms too. In C (the native path) the kernels do not ask.
 */
#ifndef FB_KERNELS_DEVICE_H
#define FB_KERNELS_DEVICE_H

#define K_SPEC_CPU_DEVICE 126

#ifdef K_GLSL
layout(constant_id = K_SPEC_CPU_DEVICE) const bool K_CPU_DEVICE = false;
#endif

#endif
