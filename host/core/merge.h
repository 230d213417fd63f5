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

typedef struct fb_merge_desc {
    const char *const *paths; /* the n part files */
    int n;
    const char *out;     /* the whole file, written through the output transaction */
    int threads;         /* compression workers; 0: all cores */
    int zip_level;       /* the deflate level of ZIP chunks; 0: EXRIO_ZIP_LEVEL */
    uint64_t max_memory; /* --max-memory; 0: the default (fb_memory_limit) */
} fb_merge_desc;

/* Writes d->out from the parts: region files, points parts or task files (see above). */
fb_result fb_merge(const fb_merge_desc *d);

#endif
