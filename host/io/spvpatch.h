/*
 * spvpatch: the float-controls execution modes a device offers, added to a SPIR-V module before it
 * becomes a pipeline (VK_KHR_shader_float_controls).
 *
 * Without them a device rounds "correctly with an implementation-defined rounding mode" (to
 * nearest or toward zero), may flush denormals, and may assume no infinity or NaN ever appears;
 * RoundingModeRTE, DenormPreserve and SignedZeroInfNanPreserve pin what the native C path does.
 * The modes go in only where the device says it supports them (VkPhysicalDeviceFloatControls-
 * Properties), for the widths the module uses, within the device's independence rules.
 */
#ifndef FB_SPVPATCH_H
#define FB_SPVPATCH_H

#include "fb.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* What to declare for one float width. */
typedef struct spv_float_modes {
    bool rte;             /* RoundingModeRTE */
    bool denorm_preserve; /* DenormPreserve */
    bool szinp;           /* SignedZeroInfNanPreserve */
} spv_float_modes;

/* A copy of the module `spv` (`words` 32-bit words) with the modes of m32 for 32-bit floats, and of
 * m64 for 64-bit floats where the module declares the Float64 capability: the capabilities, the
 * SPV_KHR_float_controls extension (modules before SPIR-V 1.4), and one OpExecutionMode per mode and
 * entry point. *out is malloc'd (the caller frees it); *out_words its length. FB_ERR_INTERNAL with
 * one logged line on a malformed module. */
fb_result spv_add_float_controls(const uint32_t *spv, size_t words, spv_float_modes m32, spv_float_modes m64,
                                 uint32_t **out, size_t *out_words);

/* The build embeds each shader as two modules in one array (cmake/spvexact.c): the portable one,
 * then a native one in which K_EXACT_NATIVE (kernels/exact.h) is the constant true and the portable
 * division's code is gone, then two words: the portable module's length and SPV_VARIANTS_MAGIC.
 * The module to use (native: the device's own division is exact) and its length in *out_words; an
 * array without the trailer (SPIR-V from a file) is returned whole. */
#define SPV_VARIANTS_MAGIC 0x564e4246u /* "FBNV" */
const uint32_t *spv_variant(const uint32_t *spv, size_t words, bool native, size_t *out_words);

/* True where the module declares the Float64 capability (it computes in double). */
bool spv_uses_float64(const uint32_t *spv, size_t words);

#endif
