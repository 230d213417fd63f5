/* Image comparison and file description, for `fractalbake compare` and `fractalbake info`. */
#ifndef FB_COMPARE_H
#define FB_COMPARE_H

#include "fb.h"

#include <stdarg.h>
#include <stdbool.h>

typedef struct fb_compare_desc {
    const char *a, *b;
    const char *layer; /* restrict to channels "layer.*" */
    bool has_max_abs, has_rmse, has_psnr, has_fail_percent;
    double max_abs, rmse, psnr, fail_percent;
    bool ignore_missing;
    const char *diff;     /* write |A - B| per common channel here */
    const char *diff_png; /* and a picture: red where any channel is beyond --max-abs, A's grey elsewhere */
    void (*print)(const char *line, void *user);
    void *user;
} fb_compare_desc;

/* Compares two EXR files channel by channel. *pass is false when a threshold is exceeded (with no
 * threshold: when any pixel differs), when the sizes differ, or when a channel is missing from one
 * file (unless ignore_missing). An error reading either file is a failed result, not *pass. */
fb_result fb_compare(const fb_compare_desc *d, bool *pass);

/* Prints size, compression, layers and channels with types, attributes and the stored scene. */
fb_result fb_info(const char *path, void (*print)(const char *line, void *user), void *user);

#endif
