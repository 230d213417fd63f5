/* 3D fBm on eight AVX2 lanes (see fbm3_avx2.c): kernels/fbm.h's k_fbm3 and the lat-long and cube
 * rows of k_fbm_map_pixel, bit-exact with the kernel (tests/test_avx2.c compares every pixel with the
 * scalar loop). The fbm layer's native path for environment maps and the Julia layer's turbulence on
 * the sphere. */
#ifndef FB_FBM3_AVX2_H
#define FB_FBM3_AVX2_H

#include "kernels/fbm.h"

#include <stdbool.h>

/* True when this CPU has AVX2 (the lanes implement every noise kind, every shape, warp or not). */
bool fb_fbm3_avx2_supported(const K_FbmParams *p);

/* out[k] = k_fbm3(*p, stream, (d[0][k], d[1][k], d[2][k])) for the eight lanes k. */
void fb_fbm3_avx2_lanes(const K_FbmParams *p, uint32_t stream, const float d[3][8], float out[8]);

/* Rows [y0, y0 + n) of a lat-long or cube fbm layer (n * width floats): k_fbm_map_pixel, warp
 * included. */
void fb_fbm3_avx2_rows(const K_FbmParams *p, int y0, int n, float *out);

#endif
