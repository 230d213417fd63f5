/*
 * SSIM, streamed row by row (Wang, Bovik, Sheikh and Simoncelli, "Image quality assessment: from
 * error visibility to structural similarity", IEEE Transactions on Image Processing 13(4), 2004).
 */
#ifndef FB_SSIM_H
#define FB_SSIM_H

#include "fb.h"

#include <stdint.h>

/* The paper's local statistics: an 11 x 11 circular-symmetric Gaussian window of standard
 * deviation 1.5, normalised to sum 1, applied separably (horizontally per row, then vertically over
 * a ring of 11 rows); K1 = 0.01, K2 = 0.03, L the channel's dynamic range; the mean of the SSIM map
 * over every position where the window lies inside the image (MSSIM, eq. 17). */
#define SSIM_R 5
#define SSIM_N (2 * SSIM_R + 1)

typedef struct ssim_acc {
    double w[SSIM_N];
    double c1, c2;
    int width, vw; /* image width, valid width (width - 10) */
    double *ring;  /* SSIM_N rows x 5 statistics x vw, the horizontally filtered rows */
    double *tmp;   /* 6 x vw: a row's 5 statistics filtered vertically, and its SSIM; 3 x width: the squares */
    int rows_in;   /* rows added so far */
    double sum;    /* of the SSIM map */
    uint64_t count;
} ssim_acc;

/* For rows of `width` values of a channel of dynamic range `range` (<= 0: 1). */
fb_result ssim_init(ssim_acc *s, int width, double range);
/* One image row of both channels. */
void ssim_row(ssim_acc *s, const double *a, const double *b);
/* The mean SSIM of the rows so far (1 before any window is complete). */
double ssim_mean(const ssim_acc *s);
void ssim_fini(ssim_acc *s);

#endif
