/*
 * FLIP, the perceptual difference of two images flipped back and forth (Andersson, Nilsson,
 * Akenine-Moller, Oskarsson, Astrom and Fairchild, "FLIP: A Difference Evaluator for Alternating
 * Images", HPG 2020), and HDR-FLIP (Andersson, Nilsson, Shirley and Akenine-Moller, "Visualizing
 * Errors in Rendered High Dynamic Range Images", Eurographics 2021; and "Visualizing and
 * Communicating Errors in Rendered Images", Ray Tracing Gems II, 2021), in single precision, with
 * the steps of NVIDIA's published implementation (version 1.6), so that its numbers come out
 * within 1e-4.
 */
#ifndef FB_FLIP_H
#define FB_FLIP_H

#include "fb.h"

#include <stdbool.h>
#include <stddef.h>

/* The papers' observer: 0.7 m from a 0.7 m wide monitor of 3840 pixels, 67.02 pixels per degree. */
float fb_flip_default_ppd(void);

typedef struct fb_flip_result {
    double mean, median, q1, q3, min, max; /* of the per-pixel error; median and quartiles weighted */
    /* HDR-FLIP: the exposures used (stops), start to stop in nexp equal steps */
    float start_exposure, stop_exposure;
    int nexp;
    /* HDR-FLIP: the reference's median luminance was <= 0 (at least half of it black), and the
     * stop exposure came from the median of its positive luminances instead (both 0 when it has
     * none) */
    bool zero_median;
} fb_flip_result;

/* The FLIP error of test against ref, both width x height, three planes each (R, G, B; a grey image
 * passes its one plane three times, which is faster). LDR-FLIP (hdr false) takes
 * sRGB-encoded values in [0, 1]; HDR-FLIP takes linear values and takes, per pixel, the largest
 * LDR-FLIP over the exposures, with ACES tone mapping and the exposure range chosen from the
 * reference. map (width * height, may be NULL) receives the per-pixel error in [0, 1]. */
fb_result fb_flip(const float *const ref[3], const float *const test[3], int width, int height, bool hdr, float ppd,
                  float *map, fb_flip_result *out);

/* The threads fb_flip runs on (0, the default: one per core). Bands of rows are computed
 * independently, so the result is the same bits whatever the count. */
void fb_flip_set_threads(int n);

/* fb_flip in three steps, for a caller that runs the bands of several images on its own threads:
 * create (the exposures; the planes and map must live until finish), every band 0..bands-1 once on
 * any thread, then finish (the statistics; it frees the job). */
typedef struct fb_flip_job fb_flip_job;
fb_result fb_flip_job_create(const float *const ref[3], const float *const test[3], int width, int height, bool hdr,
                             float ppd, float *map, fb_flip_job **out);
int fb_flip_job_bands(const fb_flip_job *j);
void fb_flip_job_band(fb_flip_job *j, int band);
fb_result fb_flip_job_finish(fb_flip_job **j, fb_flip_result *out);

/* The automatic exposure range from the reference's linear RGB (as fb_flip uses). scratch: room for
 * n floats that it may overwrite (the map, before the bands write it), or NULL to allocate its own. */
fb_result fb_flip_exposures(const float *const ref[3], size_t n, float *scratch, float *start, float *stop, int *nexp,
                            bool *zero_median);

/* The statistics of an error map of n values (mean, weighted median and quartiles, min, max). */
fb_result fb_flip_pool(const float *map, size_t n, fb_flip_result *out);

#endif
