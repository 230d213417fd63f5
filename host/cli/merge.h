/*
 * Joining region files: `fractalbake render --region X,Y,W,H` bakes part of an image into a file
 * whose data window is that region; fb_merge writes the whole image from parts that tile it exactly
 * (same image, channels and stored scene; no gap, no overlap). The merged pixels are those of the
 * whole-image bake, and so are the file's bytes when the parts came from one fractalbake build.
 */
#ifndef FB_MERGE_H
#define FB_MERGE_H

#include "fb.h"

#define FB_MERGE_MAX_CHANNELS 128

/* Writes `out` (atomically) from the n region files `paths`; threads: compression workers (0: all
 * cores); zip_level: the deflate level of ZIP chunks (0: EXRIO_ZIP_LEVEL). */
fb_result fb_merge(const char *const *paths, int n, const char *out, int threads, int zip_level);

#endif
