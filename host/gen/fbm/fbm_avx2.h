/* The hand-vectorised fBm loop (see fbm_avx2.c): the native backend's fast path for the case it
 * implements, bit-exact with k_fbm_pixel (tests/test_avx2.c compares every pixel with the scalar
 * kernel), and the benchmark's reference. `params` is a K_FbmParams. */
#ifndef FB_FBM_AVX2_H
#define FB_FBM_AVX2_H

#include <stdbool.h>

/* True when this CPU has AVX2 and the parameters are the case the loop implements (gradient
 * noise, standard shape, no warp, not tileable). */
bool fb_fbm_avx2_supported(const void *params);

/* Fills rows [y0, y0 + n) of the image (n * width floats), bit-exact with k_fbm_pixel. */
void fb_fbm_avx2_rows(const void *params, int y0, int n, float *out);

#endif
