/*
 * The checker generator's kernel (docs/architecture.md, "Adding a generator"): a board of
 * cells x cells squares over the image, 1 on the squares whose row and column add to an odd number.
 * Compiles as C11 (the native path) and GLSL 450 (shaders/checker.comp).
 */
#ifndef FB_KERNELS_CHECKER_H
#define FB_KERNELS_CHECKER_H

#include "common.h"

K_STRUCT(K_CheckerParams)
{
    uint width, height; /* the image */
    uint cells;         /* squares across each side */
    uint pad;
}
K_END(K_CheckerParams)

#ifndef K_GLSL
_Static_assert(sizeof(K_CheckerParams) == 16, "K_CheckerParams must match the std430 push block");
#endif

K_FN float k_checker_pixel(K_CheckerParams p, uint x, uint y)
{
    uint cx = x * p.cells / p.width, cy = y * p.cells / p.height;
    return ((cx + cy) & 1u) != 0u ? 1.0 : 0.0;
}

#endif
