/*
 * A flame between its keyframes, as flam3-animate (flam3 3.1.1) renders it: the genome at any time
 * (flam3_interpolate: xforms aligned and padded by flam3_align's rules, linear or Catmull-Rom
 * blends, matrices in log-polar or linear form, palettes in HSV, RGB or swept), and the temporal
 * filter whose samples make a frame's motion blur.
 */
#ifndef FB_FLAME_ANIMATE_H
#define FB_FLAME_ANIMATE_H

#include "genome.h"

/* The genome of keyframes keys[0 .. n) (times increasing, fb_flame_read_keys) at `time`, into *out:
 * the segment holding time (the first or last beyond the ends, extrapolated as flam3 does), blended
 * linearly or, where the segment's first keyframe says smooth, by Catmull-Rom over four keyframes.
 * Errors: FB_ERR_NOMEM. */
fb_result fb_flame_interpolate(const fb_flame_genome *keys, int n, double time, fb_flame_genome *out);

/* flam3's temporal filter of n samples (flam3_create_temporal_filter): delta[i], the sample's time
 * offset from the frame's, and weight[i], its colour's scale (the largest 1). Returns the mean
 * weight (flam3's sumfilt, which divides the tone map's k2). */
double fb_flame_temporal_filter(int n, fb_flame_tfilter type, double fexp, double width, double *delta, double *weight);

/* A frame at `time` as flam3's renderer takes it from the keyframes (rect.c): the genome at the
 * frame's time (its size, filters, supersample, temporal filter and number of samples), with the
 * density estimator of the first temporal sample's; the temporal samples' time offsets and weights
 * and their mean weight; the tone map's brightness, highlight power and gamma threshold of the last
 * sample and its gamma, vibrancy and background averaged over them all. */
typedef struct fb_flame_frame {
    fb_flame_genome frame;
    int n;                  /* temporal samples */
    double *delta, *weight; /* n each */
    double sumfilt;
    double brightness, gamma, gamma_threshold, vibrancy, highlight_power, background[3];
} fb_flame_frame;

/* Fills *f for keyframes keys[0 .. n) at `time`, with `samples` temporal samples (0: the frame
 * genome's temporal_samples). Owns delta and weight: fb_flame_frame_fini. Errors: FB_ERR_NOMEM. */
fb_result fb_flame_frame_init(const fb_flame_genome *keys, int n, double time, int samples, fb_flame_frame *f);
void fb_flame_frame_fini(fb_flame_frame *f);

#endif
