/* The Julia layer's whole per-pixel path on eight AVX2 lanes (see layer_avx2.c): the native fast
 * path of layer.c, bit-exact with the portable kernel (tests/test_avx2.c). */
#ifndef FB_JULIA_LAYER_AVX2_H
#define FB_JULIA_LAYER_AVX2_H

#include "kernels/julia.h"
#include "kernels/palette.h"

#include <stdbool.h>

/* What the rows need besides the grid: the colour parameters, the palette table (K_PALETTE_SIZE
 * linear RGBA entries), the turbulence fBm, and what the orbits must compute (K_JULIA_WANT_*). */
typedef struct fb_julia_avx2_ctx {
    const K_JuliaParams *p;
    const K_SkyColour *colour;
    const float (*entries)[4];
    const K_FbmParams *turb;
    uint32_t want;
} fb_julia_avx2_ctx;

/* True when this CPU has AVX2 and the grid is one the lanes implement (rect and polar; lat-long and
 * cube with their starts from the portable kernel; float). */
bool fb_julia_avx2_layer_supported(const K_JuliaParams *p);

/* Rows [y0, y0 + n) into the kernel planes iter (uint32), n, inside, de, R, G, B (float; NULL: not
 * stored; R, G, B all or none), n * width values each, as layer.c's scalar loop writes them. */
void fb_julia_avx2_layer_rows(const fb_julia_avx2_ctx *c, int y0, int n, void *const *planes);

#endif
