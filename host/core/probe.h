/*
 * What a Vulkan device does with fp32 subnormals, measured rather than read from its declarations: a
 * device may report shaderDenormPreserveFloat32 = false (NVIDIA's driver has been seen to), and its
 * shaders then follow the driver's default, which may flush subnormal results to zero, subnormal
 * operands, or both. The native path keeps them (and the goldens hold under FTZ/DAZ too:
 * tests/cli/ftz.sh), so a device that flushes may differ from it on values below 1.2e-38.
 *
 * The probe is a one-invocation shader (shaders/denormal_probe.comp) that multiplies values it reads
 * from a buffer at run time, through the same pipeline path as every kernel (the float-controls modes
 * the device offers declared).
 */
#ifndef FB_PROBE_H
#define FB_PROBE_H

#include "vkc.h"

#include <stdint.h>

typedef struct fb_denormals {
    uint32_t product; /* the bits of 2^-126 * 0.5: 0x00400000 kept, 0 flushed */
    uint32_t operand; /* the bits of 2^-140 * 2^20: 0x03800000 kept, 0 flushed */
    const char *verdict;
} fb_denormals;

/* The verdict on the two results' bits: "kept", "flushed" (results and operands), "results flushed"
 * (operands kept), "operands flushed" (results kept), or "unexpected" (neither value). */
const char *fb_denormals_verdict(uint32_t product, uint32_t operand);

/* Runs the probe on the context's device. */
fb_result fb_denormals_probe(vkc_context *vk, fb_denormals *out);

#endif
