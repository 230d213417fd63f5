/*
 * A fractal flame genome as flam3 3.1.1 reads it from a .flame file (XML): the camera, the filters,
 * the tone map, the xforms with their variations and the palette. Read with libxml2.
 */
#ifndef FB_FLAME_GENOME_H
#define FB_FLAME_GENOME_H

#include "fb.h"

#include "kernels/flame.h"

#define FB_FLAME_MAX_XFORMS                                                                                            \
    24 /* ordinary xforms (flam3 has no limit; <symmetry> adds up to 25), plus one final xform */
/* flam3 3.1.1's variation parameters: the enum's name, the attribute, flam3's default
 * (initialize_xforms). */
#define FB_FLAME_PARAMS(X)                                                                                             \
    X(BLOB_LOW, "blob_low", 0)                                                                                         \
    X(BLOB_HIGH, "blob_high", 1)                                                                                       \
    X(BLOB_WAVES, "blob_waves", 1)                                                                                     \
    X(PDJ_A, "pdj_a", 0)                                                                                               \
    X(PDJ_B, "pdj_b", 0)                                                                                               \
    X(PDJ_C, "pdj_c", 0)                                                                                               \
    X(PDJ_D, "pdj_d", 0)                                                                                               \
    X(FAN2_X, "fan2_x", 0)                                                                                             \
    X(FAN2_Y, "fan2_y", 0)                                                                                             \
    X(RINGS2_VAL, "rings2_val", 0)                                                                                     \
    X(PERSPECTIVE_ANGLE, "perspective_angle", 0)                                                                       \
    X(PERSPECTIVE_DIST, "perspective_dist", 0)                                                                         \
    X(JULIAN_POWER, "julian_power", 1)                                                                                 \
    X(JULIAN_DIST, "julian_dist", 1)                                                                                   \
    X(JULIASCOPE_POWER, "juliascope_power", 1)                                                                         \
    X(JULIASCOPE_DIST, "juliascope_dist", 1)                                                                           \
    X(RADIAL_BLUR_ANGLE, "radial_blur_angle", 0)                                                                       \
    X(PIE_SLICES, "pie_slices", 6)                                                                                     \
    X(PIE_ROTATION, "pie_rotation", 0)                                                                                 \
    X(PIE_THICKNESS, "pie_thickness", 0.5)                                                                             \
    X(NGON_SIDES, "ngon_sides", 5)                                                                                     \
    X(NGON_POWER, "ngon_power", 3)                                                                                     \
    X(NGON_CIRCLE, "ngon_circle", 1)                                                                                   \
    X(NGON_CORNERS, "ngon_corners", 2)                                                                                 \
    X(CURL_C1, "curl_c1", 1)                                                                                           \
    X(CURL_C2, "curl_c2", 0)                                                                                           \
    X(RECTANGLES_X, "rectangles_x", 1)                                                                                 \
    X(RECTANGLES_Y, "rectangles_y", 1)                                                                                 \
    X(DISC2_ROT, "disc2_rot", 0)                                                                                       \
    X(DISC2_TWIST, "disc2_twist", 0)                                                                                   \
    X(SUPER_SHAPE_RND, "super_shape_rnd", 0)                                                                           \
    X(SUPER_SHAPE_M, "super_shape_m", 0)                                                                               \
    X(SUPER_SHAPE_N1, "super_shape_n1", 1)                                                                             \
    X(SUPER_SHAPE_N2, "super_shape_n2", 1)                                                                             \
    X(SUPER_SHAPE_N3, "super_shape_n3", 1)                                                                             \
    X(SUPER_SHAPE_HOLES, "super_shape_holes", 0)                                                                       \
    X(FLOWER_PETALS, "flower_petals", 0)                                                                               \
    X(FLOWER_HOLES, "flower_holes", 0)                                                                                 \
    X(CONIC_ECCENTRICITY, "conic_eccentricity", 1)                                                                     \
    X(CONIC_HOLES, "conic_holes", 0)                                                                                   \
    X(PARABOLA_HEIGHT, "parabola_height", 0)                                                                           \
    X(PARABOLA_WIDTH, "parabola_width", 0)                                                                             \
    X(BENT2_X, "bent2_x", 1)                                                                                           \
    X(BENT2_Y, "bent2_y", 1)                                                                                           \
    X(BIPOLAR_SHIFT, "bipolar_shift", 0)                                                                               \
    X(CELL_SIZE, "cell_size", 1)                                                                                       \
    X(CPOW_R, "cpow_r", 1)                                                                                             \
    X(CPOW_I, "cpow_i", 0)                                                                                             \
    X(CPOW_POWER, "cpow_power", 1)                                                                                     \
    X(CURVE_XAMP, "curve_xamp", 0)                                                                                     \
    X(CURVE_YAMP, "curve_yamp", 0)                                                                                     \
    X(CURVE_XLENGTH, "curve_xlength", 1)                                                                               \
    X(CURVE_YLENGTH, "curve_ylength", 1)                                                                               \
    X(ESCHER_BETA, "escher_beta", 0)                                                                                   \
    X(LAZYSUSAN_SPACE, "lazysusan_space", 0)                                                                           \
    X(LAZYSUSAN_TWIST, "lazysusan_twist", 0)                                                                           \
    X(LAZYSUSAN_SPIN, "lazysusan_spin", 0)                                                                             \
    X(LAZYSUSAN_X, "lazysusan_x", 0)                                                                                   \
    X(LAZYSUSAN_Y, "lazysusan_y", 0)                                                                                   \
    X(MODULUS_X, "modulus_x", 0)                                                                                       \
    X(MODULUS_Y, "modulus_y", 0)                                                                                       \
    X(OSCOPE_SEPARATION, "oscilloscope_separation", 1)                                                                 \
    X(OSCOPE_FREQUENCY, "oscilloscope_frequency", M_PI)                                                                \
    X(OSCOPE_AMPLITUDE, "oscilloscope_amplitude", 1)                                                                   \
    X(OSCOPE_DAMPING, "oscilloscope_damping", 0)                                                                       \
    X(POPCORN2_X, "popcorn2_x", 0)                                                                                     \
    X(POPCORN2_Y, "popcorn2_y", 0)                                                                                     \
    X(POPCORN2_C, "popcorn2_c", 0)                                                                                     \
    X(SEPARATION_X, "separation_x", 0)                                                                                 \
    X(SEPARATION_XINSIDE, "separation_xinside", 0)                                                                     \
    X(SEPARATION_Y, "separation_y", 0)                                                                                 \
    X(SEPARATION_YINSIDE, "separation_yinside", 0)                                                                     \
    X(SPLIT_XSIZE, "split_xsize", 0)                                                                                   \
    X(SPLIT_YSIZE, "split_ysize", 0)                                                                                   \
    X(SPLITS_X, "splits_x", 0)                                                                                         \
    X(SPLITS_Y, "splits_y", 0)                                                                                         \
    X(STRIPES_SPACE, "stripes_space", 0)                                                                               \
    X(STRIPES_WARP, "stripes_warp", 0)                                                                                 \
    X(WEDGE_ANGLE, "wedge_angle", 0)                                                                                   \
    X(WEDGE_HOLE, "wedge_hole", 0)                                                                                     \
    X(WEDGE_COUNT, "wedge_count", 1)                                                                                   \
    X(WEDGE_SWIRL, "wedge_swirl", 0)                                                                                   \
    X(WEDGE_JULIA_ANGLE, "wedge_julia_angle", 0)                                                                       \
    X(WEDGE_JULIA_COUNT, "wedge_julia_count", 1)                                                                       \
    X(WEDGE_JULIA_POWER, "wedge_julia_power", 1)                                                                       \
    X(WEDGE_JULIA_DIST, "wedge_julia_dist", 0)                                                                         \
    X(WEDGE_SPH_ANGLE, "wedge_sph_angle", 0)                                                                           \
    X(WEDGE_SPH_HOLE, "wedge_sph_hole", 0)                                                                             \
    X(WEDGE_SPH_COUNT, "wedge_sph_count", 1)                                                                           \
    X(WEDGE_SPH_SWIRL, "wedge_sph_swirl", 0)                                                                           \
    X(WHORL_INSIDE, "whorl_inside", 0)                                                                                 \
    X(WHORL_OUTSIDE, "whorl_outside", 0)                                                                               \
    X(WAVES2_SCALEX, "waves2_scalex", 0)                                                                               \
    X(WAVES2_SCALEY, "waves2_scaley", 0)                                                                               \
    X(WAVES2_FREQX, "waves2_freqx", 0)                                                                                 \
    X(WAVES2_FREQY, "waves2_freqy", 0)                                                                                 \
    X(AUGER_FREQ, "auger_freq", 1)                                                                                     \
    X(AUGER_WEIGHT, "auger_weight", 0.5)                                                                               \
    X(AUGER_SYM, "auger_sym", 0)                                                                                       \
    X(AUGER_SCALE, "auger_scale", 1)                                                                                   \
    X(FLUX_SPREAD, "flux_spread", 0)                                                                                   \
    X(MOBIUS_RE_A, "mobius_re_a", 0)                                                                                   \
    X(MOBIUS_IM_A, "mobius_im_a", 0)                                                                                   \
    X(MOBIUS_RE_B, "mobius_re_b", 0)                                                                                   \
    X(MOBIUS_IM_B, "mobius_im_b", 0)                                                                                   \
    X(MOBIUS_RE_C, "mobius_re_c", 0)                                                                                   \
    X(MOBIUS_IM_C, "mobius_im_c", 0)                                                                                   \
    X(MOBIUS_RE_D, "mobius_re_d", 0)                                                                                   \
    X(MOBIUS_IM_D, "mobius_im_d", 0)

/* The parameters, by index into fb_flame_xform.par: FB_FP_BLOB_LOW ... */
#define FB_FLAME_PARAM_ENUM(e, name, def) FB_FP_##e,
enum { FB_FLAME_PARAMS(FB_FLAME_PARAM_ENUM) FB_FP_COUNT };
#undef FB_FLAME_PARAM_ENUM

typedef struct fb_flame_xform {
    double weight, color, color_speed, opacity;
    double c[3][2];    /* coefs: tx = c00 x + c10 y + c20, ty = c01 x + c11 y + c21 */
    double post[3][2]; /* the post transform, the same way */
    double var[K_V_COUNT];
    double par[FB_FP_COUNT];
    double chaos[FB_FLAME_MAX_XFORMS]; /* xaos: the weight of going to xform j after this one (1: none) */
    double animate;                    /* flam3's animate: 0 for a symmetry xform (flam3-genome's rotate) */
    bool padding;                      /* added by flam3_align's rules to match another keyframe (animate.c) */
} fb_flame_xform;

typedef enum {
    FB_FLAME_PALETTE_STEP,
    FB_FLAME_PALETTE_LINEAR,
} fb_flame_palette_mode;

/* How a keyframe moves to the next (flam3-animate: the <flame> attributes interpolation,
 * interpolation_type, palette_interpolation, temporal_filter_type). */
/* (each stored as an int: genome.c's table of attributes writes them so) */
typedef enum { FB_FLAME_INTERP_LINEAR, FB_FLAME_INTERP_SMOOTH } fb_flame_interp;
typedef enum { FB_FLAME_ITYPE_LOG, FB_FLAME_ITYPE_LINEAR, FB_FLAME_ITYPE_OLD, FB_FLAME_ITYPE_OLDER } fb_flame_itype;
typedef enum {
    FB_FLAME_PALINT_HSV_CIRCULAR,
    FB_FLAME_PALINT_HSV,
    FB_FLAME_PALINT_SWEEP,
    FB_FLAME_PALINT_RGB
} fb_flame_palint;
typedef enum { FB_FLAME_TFILTER_BOX, FB_FLAME_TFILTER_GAUSSIAN, FB_FLAME_TFILTER_EXP } fb_flame_tfilter;

typedef struct fb_flame_genome {
    char name[80];
    int width, height;
    double center[2];
    double scale; /* pixels per unit */
    double zoom, rotate;
    int supersample;
    double filter;    /* the spatial filter's radius */
    int filter_shape; /* flam3's spatial filter number (0 gaussian ... 13 quadratic) */
    double quality;   /* samples per pixel */
    double background[3];
    double brightness, gamma, highlight_power, vibrancy, gamma_threshold;
    double estimator, estimator_minimum, estimator_curve;
    fb_flame_palette_mode palette_mode;
    int nxforms;            /* ordinary xforms xf[0 .. nxforms) */
    bool has_final;         /* and the final xform, xf[nxforms] */
    bool chaos;             /* some xaos entry is not 1 */
    bool symmetry;          /* xforms were added by <symmetry> */
    char form[64];          /* how the palette was given, for messages: "<color> elements", ... */
    double palette[256][4]; /* r, g, b (premultiplied by a), a in [0, 1] */
    /* animation: the keyframe's time and how it is interpolated (flam3's defaults: time 0, linear,
     * log, hsv_circular, 1000 temporal samples of a box filter of width 1) */
    double time;
    bool has_time; /* the time attribute was given */
    fb_flame_interp interpolation;
    fb_flame_itype interpolation_type;
    fb_flame_palint palette_interpolation;
    double hsv_rgb_palette_blend;
    int temporal_samples;
    fb_flame_tfilter temporal_filter_type;
    double temporal_filter_width, temporal_filter_exp;
    fb_flame_xform xf[FB_FLAME_MAX_XFORMS + 1];
} fb_flame_genome;

/* Reads the <flame> named `pick` (its name attribute, or a decimal index from 0; NULL: the first) of
 * the XML text `xml` (`len` bytes; `what` names it in messages: a file path). A palette="N" reads
 * flam3's palette library `palettes`. The text is checked as fb_flame_slurp checks a file before its
 * tree is built. Errors: FB_ERR_INPUT with one line naming the file, the flame, the xform and the
 * attribute (an unknown variation names the variation), or the line libxml2 stopped at. */
fb_result fb_flame_read(const char *xml, size_t len, const char *what, const char *pick, const char *palettes,
                        fb_flame_genome *out, char **element);

/* Reads every <flame> of the XML text as the keyframes of an animation, as flam3-animate does:
 * *out (n of them, malloc'd) in the file's order, their times strictly increasing, each sized as
 * the first; smooth interpolation on the first or the last segment read as linear, and each
 * rotate brought within 180 degrees of the one before (flam3_parse_xml2). Errors: FB_ERR_INPUT,
 * one line naming the file and the flame. */
fb_result fb_flame_read_keys(const char *xml, size_t len, const char *what, const char *palettes, fb_flame_genome **out,
                             int *n);

/* Reads a whole .flame file into memory (NUL-terminated), refusing it by its counts as it streams in
 * (scan.h: xforms, palette entries, attributes, sizes, entities), before anything large is built. */
fb_result fb_flame_slurp(const char *path, char **text, size_t *len);

/* An xform as flam3 starts one, the `index`-th of its genome: no weight, identity coefficients,
 * colour index & 1, colour speed 0.5, opacity and animate 1, flam3's parameter defaults, no
 * variation, xaos 1 to every xform. */
void fb_flame_xform_init(fb_flame_xform *x, int index);

/* Variation number of a flam3 variation name (all 99 of flam3 3.1.1), or -1. */
int fb_flame_variation_of(const char *name);

/* The name of flam3 variation number v. */
const char *fb_flame_variation_name(int v);

#endif
