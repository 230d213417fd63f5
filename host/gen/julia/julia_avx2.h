/* The AVX2 escape-time loop for the Julia benchmark (see julia_avx2.c). `params` is a K_JuliaParams. */
#ifndef FB_JULIA_AVX2_H
#define FB_JULIA_AVX2_H

#include <stdbool.h>
#include <stdint.h>

/* True when this CPU has AVX2 and the parameters are the case the loop implements (rect grid, no
 * turbulence). */
bool fb_julia_avx2_supported(const void *params);

/* Escape counts of rows [y0, y0 + n) (n * width values), bit-exact with the kernel's `iter`; adds
 * their sum (the iterations executed) to *total when total is not NULL. */
void fb_julia_avx2_rows(const void *params, int y0, int n, uint32_t *iter, uint64_t *total);

#endif
