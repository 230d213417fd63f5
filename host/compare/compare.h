/* Image comparison, for `fractalbake compare` and anything else that compares two images. */
#ifndef FB_COMPARE_H
#define FB_COMPARE_H

#include "fb.h"

#include <stdarg.h>
#include <stdbool.h>

#define FB_LIMIT_RULES 32

/* A threshold: one value for every channel, and values for some channels or layers ("sky.R=1e-3"
 * names a channel, "sky=1e-3" every channel of a layer; the channel's own value wins, then its
 * layer's, then the value for all). */
typedef struct fb_limit {
    const char *flag; /* as the user wrote it, for messages */
    bool set, has_all;
    double all;
    int n;
    char name[FB_LIMIT_RULES][128];
    double v[FB_LIMIT_RULES];
} fb_limit;

/* Parses "1e-4", "sky.R=1e-3,terrain=1e-5" or both ("1e-4,sky=0.01") into *l (added to what it holds:
 * a flag may be given twice). Values must be finite and >= 0. A usage error names the flag. */
fb_result fb_limit_parse(const char *flag, const char *text, fb_limit *l);

/* The limit for `channel`: its own rule, its layer's, or the value for all; false when none. */
bool fb_limit_get(const fb_limit *l, const char *channel, double *v);

typedef enum fb_verdict { FB_VERDICT_PASS, FB_VERDICT_WARN, FB_VERDICT_FAIL } fb_verdict;

typedef enum fb_flip_mode { FB_FLIP_AUTO, FB_FLIP_LDR, FB_FLIP_HDR } fb_flip_mode;

typedef struct fb_compare_desc {
    const char *a, *b;
    const char *layer; /* restrict to channels "layer.*" */
    /* idiff's vocabulary: a pixel fails beyond `fail` (--max-abs); the channel fails when more than
     * `failpercent` percent of its pixels do (default 0), or any pixel is beyond `hardfail`; the same
     * with warn for a warning. Then the statistics: RMSE at most, PSNR and SSIM at least. */
    fb_limit fail, failpercent, hardfail, warn, warnpercent, hardwarn, rmse, psnr, ssim;
    /* idiff's --allowfailures: a channel fails on its failing pixels (beyond fail, and beyond
     * failrelative * (|A| + |B|) / 2 when that is set) or on hardfail only when more than
     * allowfailures of its pixels fail; warnrelative likewise for warnings */
    long long allowfailures;
    double failrelative, warnrelative;
    /* idiff's statistics over all compared channels together (peak: max(1, the largest value)),
     * the failing and warning counts per pixel (any channel over) */
    bool idiff_stats;
    bool ignore_missing;
    const char *diff;     /* write |A - B| per common channel here */
    const char *diff_png; /* and a picture: red where a channel fails, A's grey elsewhere; or `heat` */
    bool heat;            /* the picture as a heat map of max |A - B| over the channels, log scale */
    bool json;            /* the report as one JSON object instead of lines */
    const char *report;   /* an HTML page: every layer's pictures, statistics and verdict, failing first */
    const char *junit;    /* JUnit XML: a test case per channel (or FLIP layer) and threshold */
    /* FLIP (flip.h) per layer of R, G, B float channels (or Y as grey): LDR-FLIP for PNGs, HDR-FLIP
     * for EXRs unless flip_mode says; a layer fails (warns) when its statistic flip_stat (0 mean,
     * 1 weighted median, 2 first, 3 third weighted quartile, 4 max) is beyond flip_fail (flip_warn),
     * rules naming layers ("RGB" or "Y" for channels without a layer) */
    bool flip;
    fb_flip_mode flip_mode;
    int flip_stat;
    fb_limit flip_fail, flip_warn;
    const char *flip_png; /* the FLIP error of the layer with the largest mean, grey */
    int threads;          /* the threads to run on (0: one per core); the results are the same bits for any */
    void (*print)(const char *line, void *user);
    void *user;
} fb_compare_desc;

/* Compares two images (EXR or PNG) channel by channel and prints the report (lines, or one JSON
 * object), ending with the verdict. A comparison that cannot be made (different sizes or regions,
 * channels missing from one file unless ignore_missing) is FB_VERDICT_FAIL with its reason. An
 * error reading either file, or a threshold naming no channel, is a failed result. */
fb_result fb_compare(const fb_compare_desc *d, fb_verdict *verdict);

#endif
