/*
 * Iterated function systems: the map lists (built-in presets, Fractint .ifs files), their checks,
 * the chaos game on either backend, and the flam3-style tone mapping of its histogram.
 */
#ifndef FB_IFS_H
#define FB_IFS_H

#include "fb.h"

#include <stdbool.h>
#include <stdint.h>

#define FB_IFS_MAX_MAPS 64
#define FB_IFS_PRESETS  "fern|sierpinski|maple|tree|spiral|population"

/* One affine map x' = a x + b y + e, y' = c x + d y + f with probability p (p < 0: not given). */
typedef struct fb_ifs_map {
    double a, b, c, d, e, f, p;
} fb_ifs_map;

typedef struct fb_ifs {
    int n;
    fb_ifs_map m[FB_IFS_MAX_MAPS];
} fb_ifs;

/* A preset by name (FB_IFS_PRESETS). `population` is the paper's plant population: its maps are
 * the row map w1(x, y) = (0.75x + 0.25, 0.75y); *cond receives the tree it condenses (may be NULL
 * for the other presets, which have no condensation set). */
fb_result fb_ifs_preset(const char *name, fb_ifs *out, fb_ifs *cond, bool *has_cond);

/* Reads entry `entry` (NULL: the first) of a Fractint .ifs file. Errors name path:line:column. */
fb_result fb_ifs_read_file(const char *path, const char *entry, fb_ifs *out);

/* The same from text (for tests); `origin` names it in messages. */
fb_result fb_ifs_parse_text(const char *text, const char *origin, const char *entry, fb_ifs *out);

/* Checks a map list: 1..64 maps, finite coefficients, every map contractive (largest singular value
 * < 1), probabilities all given or all missing, none negative, not summing to 0. On a problem:
 * false, *bad the map at fault (-1: the list as a whole) and the reason in msg. */
bool fb_ifs_valid(const fb_ifs *ifs, int *bad, char *msg, size_t n);

/* The probabilities actually used, normalised to sum 1: as given, or |det| weighting with a floor
 * of 1% of the largest weight (equal weights when every map is singular). */
void fb_ifs_probabilities(const fb_ifs *ifs, double *p);

/* Largest singular value of map k's linear part. */
double fb_ifs_contraction(const fb_ifs_map *m);

/* Transient steps that bring a start in [-1, 1]^2 within 2^-24 of the attractor's scale: from the
 * mean log contraction sum p_k ln s_k, clamped to 20..10000. */
int fb_ifs_auto_skip(const fb_ifs *ifs);

/* What a chaos-game run did. points = hits + outside + discarded, exactly. */
typedef struct fb_ifs_stats {
    uint64_t points, hits, outside, discarded, restarts, saturated;
    uint32_t chains, skip;
    double bounds[4];    /* the frame used: xmin, xmax, ymin, ymax */
    double seconds;      /* the whole prepare: chaos game, reduction to pixels, tone reference */
    double game_seconds; /* the chaos game alone (dispatches, or native tasks) */
    double gpu_seconds;  /* dispatch timestamps (vulkan), else -1 */
} fb_ifs_stats;

/* Tone mapping (after flam3): alpha from the log density, a gamma curve with a linear part below
 * the threshold, vibrancy between gamma on alpha and gamma per channel, highlight handling. */
typedef struct fb_ifs_tone {
    double brightness, gamma, threshold, vibrancy, highlight;
    double dref; /* the density that maps to alpha = brightness (fb_ifs_density_ref) */
    float palette[256][4];
} fb_ifs_tone;

/* The 99.5th percentile of the positive densities (1 when there are none). */
double fb_ifs_density_ref(const float *density, size_t n);

/* R, G, B (premultiplied) and A of n pixels from their density and mean colour coordinate. */
void fb_ifs_tonemap_row(const fb_ifs_tone *t, const float *density, const float *colour, size_t n, float *R, float *G,
                        float *B, float *A);

#endif
