/*
 * compare's parts (compare.h), shared by its files:
 *   compare.c         the steps of fb_compare: the files, the channels both hold, the outputs
 *   compare_limits.c  thresholds: parsing, which rule applies to a channel, every rule used
 *   compare_image.c   an EXR or PNG read in blocks of rows, or whole
 *   compare_stats.c   the per-channel statistics over blocks of rows, the diff, the picture, verdicts
 *   compare_flip.c    FLIP per layer, its map and picture, its verdict
 *   compare_print.c   the lines and the JSON object
 *   compare_report.c  the HTML page and the JUnit file
 */
#ifndef FB_COMPARE_INT_H
#define FB_COMPARE_INT_H

#include "compare.h"
#include "flip.h"
#include "ssim.h"

#include "exrio.h"
#include "pngio.h"
#include "pool.h"
#include "preview.h"

#include <jansson.h>

#include <stdbool.h>
#include <stdint.h>

#define BLOCK_ROWS 64 /* a multiple of every scanline chunk height we read (1, 16, 32) */

/* ---- images: an EXR read in blocks of rows, or a PNG held whole ------------------------------ */

typedef struct image {
    const char *path;
    exrio_reader *exr;
    fb_png png;
    bool is_png;
} image;

fb_result image_open(const char *path, image *im);
void image_close(image *im);
int image_width(const image *im);
int image_height(const image *im);
void image_window(const image *im, int w[4]);
int image_nchannels(const image *im);
const char *image_channel(const image *im, int c);
bool image_uint(const image *im, int c);
int image_find(const image *im, const char *name);
fb_result image_read_rows(image *im, int y0, int n, void *const *planes);

/* ---- the comparison -------------------------------------------------------------------------- */

typedef struct chan_stats {
    int ia, ib; /* channel index in A and B */
    const char *name;
    bool uint_a, uint_b;
    double fail, warn, hardfail, hardwarn, failpct, warnpct, rmse_max, psnr_min, ssim_min;
    bool abs_test, has_warn, has_hardfail, has_hardwarn, has_warnpct, has_rmse, has_psnr, has_ssim;
    double max_abs;
    int max_x, max_y;
    double sum_sq;
    uint64_t n; /* finite pairs */
    uint64_t beyond, beyond_warn;
    uint64_t failing; /* pixels beyond --fail or beyond --hardfail: the failing pixels --allowfailures counts */
    uint64_t nonfinite_mismatch; /* NaN/Inf in one file and not the same in the other */
    uint64_t nonfinite_same;
    double a_lo, a_hi;
    ssim_acc ssim;
    double *ra, *rb; /* one row of each as doubles, for SSIM */
    /* --idiff-stats, this channel's share of a block: its sums and largest error, and per pixel of
     * the block 1 over the warning, 2 over the failure (the channels' shares are then added in
     * their order, so that the totals do not depend on the threads) */
    uint8_t *over;
    double i_sum, i_sq, i_peak, i_max;
    int i_mx, i_my; /* -1: none yet */
    uint64_t i_nvals, i_nonfinite;
    /* the statistics, once every row is in; a non-finite pixel that differs makes RMSE +inf, PSNR
     * -inf and SSIM -1 (the worst each can be), so no statistic passes it */
    double rmse, psnr, pct, wpct, ssim_v;
    fb_verdict verdict;
    char why[160];
} chan_stats;

/* A FLIP unit: a layer's R, G and B (or its Y as grey), compared as one picture. */
typedef struct flip_unit {
    char name[128]; /* the layer, "RGB" or "Y" for channels without one */
    int ch[3];      /* indices into the channel stats */
    bool hdr, grey;
    float *map;
    float *own;   /* the unit's planes when they had non-finite values (replaced by 0), else NULL */
    uint8_t *bad; /* then: the pixels non-finite in one file only */
    fb_flip_job *job;
    fb_result rc;
    fb_flip_result r;
    uint64_t nonfinite; /* pixels where a non-finite value differs: error 1 */
    double limit_fail, limit_warn;
    bool has_fail, has_warn;
    fb_verdict verdict;
    char why[160];
} flip_unit;

typedef struct cmp {
    const fb_compare_desc *d;
    image A, B;
    bool a_open, b_open;
    int W, H, nst, nfu;
    chan_stats *st;
    flip_unit *fu;
    fb_pool *pool; /* the threads: channels of a block, FLIP's bands */
    /* per channel index of A and B: its plane, of a block of rows or (whole) of every row */
    void **pa, **pb;
    bool whole;      /* FLIP and the report read the compared channels whole, once */
    void **ba, **bb; /* whole: the block's rows within pa, pb */
    exrio_writer *diff;
    float **pd; /* the diff's rows: one plane per channel, then one per FLIP unit */
    exrio_channel *dch;
    char (*dnames)[160];
    fb_preview *png;
    float *pic[3];
    json_t *missing;
    fb_verdict verdict;
    char reason[512];
    /* --idiff-stats: over every compared value */
    uint8_t *over;         /* per pixel of a block: 1 over the warning, 2 over the failure */
    double i_warn, i_fail; /* the thresholds of the two counts (idiff's default 1e-6) */
    double i_sum, i_sq, i_peak, i_max;
    int i_mx, i_my;
    const char *i_mc;
    uint64_t i_nvals, i_nwarn, i_nfail;
    uint64_t i_nonfinite; /* values non-finite in one file only: mean, RMS and max error inf */
} cmp;

static inline double cmp_value(const void *plane, bool is_uint, size_t i)
{
    return is_uint ? (double)((const uint32_t *)plane)[i] : (double)((const float *)plane)[i];
}

/* compare_limits.c */
int cmp_rule_match(const char *rule, const char *channel); /* 2: names the channel; 1: its layer; 0 */
fb_result cmp_check_rules(const cmp *c);
void cmp_thresholds(const fb_compare_desc *d, chan_stats *c);

/* compare_image.c: every compared channel of both files whole into pa, pb (both files at once) */
fb_result cmp_read_whole(cmp *k);

/* compare_stats.c */
fb_result cmp_stream_blocks(cmp *k);
void cmp_channel_verdict(cmp *k, chan_stats *c);
/* Whether --allowfailures lets the channel's failing pixels pass (--fail-percent and --hardfail). */
bool cmp_allowed(const cmp *k, const chan_stats *c);
void cmp_heat(double t, float rgb[3]);
double cmp_heat_t(double ad);

/* compare_flip.c */
fb_result cmp_find_flip_units(cmp *k);
fb_result cmp_compute_flip(cmp *k);
void cmp_flip_verdict(cmp *k, flip_unit *u);
extern const char *const CMP_FLIP_STATS[5];
double cmp_flip_stat(const flip_unit *u, int stat);

/* compare_print.c */
void cmp_say(const fb_compare_desc *d, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
const char *cmp_verdict_name(fb_verdict v);
void cmp_channel_lines(const cmp *k, const chan_stats *c);
void cmp_idiff_lines(const cmp *k);
void cmp_print_result(const cmp *k);

/* compare_report.c */
fb_result cmp_write_html(cmp *k);
fb_result cmp_write_junit(cmp *k, double seconds);

#endif
