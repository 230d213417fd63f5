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
#define FB_FLAME_NPARAMS 28

/* The parametric variations' parameters, by index into fb_flame_xform.par. */
enum {
    FB_FP_BLOB_LOW,
    FB_FP_BLOB_HIGH,
    FB_FP_BLOB_WAVES,
    FB_FP_PDJ_A,
    FB_FP_PDJ_B,
    FB_FP_PDJ_C,
    FB_FP_PDJ_D,
    FB_FP_FAN2_X,
    FB_FP_FAN2_Y,
    FB_FP_RINGS2_VAL,
    FB_FP_PERSPECTIVE_ANGLE,
    FB_FP_PERSPECTIVE_DIST,
    FB_FP_JULIAN_POWER,
    FB_FP_JULIAN_DIST,
    FB_FP_JULIASCOPE_POWER,
    FB_FP_JULIASCOPE_DIST,
    FB_FP_RADIAL_BLUR_ANGLE,
    FB_FP_PIE_SLICES,
    FB_FP_PIE_ROTATION,
    FB_FP_PIE_THICKNESS,
    FB_FP_NGON_SIDES,
    FB_FP_NGON_POWER,
    FB_FP_NGON_CIRCLE,
    FB_FP_NGON_CORNERS,
    FB_FP_CURL_C1,
    FB_FP_CURL_C2,
    FB_FP_RECTANGLES_X,
    FB_FP_RECTANGLES_Y,
};
/* ... and those of variations 49 to 54, after them */
enum {
    FB_FP_DISC2_ROT = FB_FLAME_NPARAMS,
    FB_FP_DISC2_TWIST,
    FB_FP_SUPER_SHAPE_RND,
    FB_FP_SUPER_SHAPE_M,
    FB_FP_SUPER_SHAPE_N1,
    FB_FP_SUPER_SHAPE_N2,
    FB_FP_SUPER_SHAPE_N3,
    FB_FP_SUPER_SHAPE_HOLES,
    FB_FP_FLOWER_PETALS,
    FB_FP_FLOWER_HOLES,
    FB_FP_CONIC_ECCENTRICITY,
    FB_FP_CONIC_HOLES,
    FB_FP_PARABOLA_HEIGHT,
    FB_FP_PARABOLA_WIDTH,
    FB_FP_BENT2_X,
    FB_FP_BENT2_Y,
    FB_FP_COUNT
};

typedef struct fb_flame_xform {
    double weight, color, color_speed, opacity;
    double c[3][2];    /* coefs: tx = c00 x + c10 y + c20, ty = c01 x + c11 y + c21 */
    double post[3][2]; /* the post transform, the same way */
    double var[K_V_COUNT];
    double par[FB_FP_COUNT];
    double chaos[FB_FLAME_MAX_XFORMS]; /* xaos: the weight of going to xform j after this one (1: none) */
} fb_flame_xform;

typedef enum {
    FB_FLAME_PALETTE_STEP,
    FB_FLAME_PALETTE_LINEAR,
} fb_flame_palette_mode;

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
    fb_flame_xform xf[FB_FLAME_MAX_XFORMS + 1];
} fb_flame_genome;

/* Reads the <flame> named `pick` (its name attribute, or a decimal index from 0; NULL: the first) of
 * the XML text `xml` (`len` bytes; `what` names it in messages: a file path). A palette="N" reads
 * flam3's palette library `palettes`. The text is checked as fb_flame_slurp checks a file before its
 * tree is built. Errors: FB_ERR_INPUT with one line naming the file, the flame, the xform and the
 * attribute (an unknown variation names the variation), or the line libxml2 stopped at. */
fb_result fb_flame_read(const char *xml, size_t len, const char *what, const char *pick, const char *palettes,
                        fb_flame_genome *out, char **element);

/* Reads a whole .flame file into memory (NUL-terminated), refusing it by its counts as it streams in
 * (scan.h: xforms, palette entries, attributes, sizes, entities), before anything large is built. */
fb_result fb_flame_slurp(const char *path, char **text, size_t *len);

/* Variation number of a flam3 variation name (all 99 of flam3 3.1.1), or -1. */
int fb_flame_variation_of(const char *name);

/* The name of flam3 variation number v. */
const char *fb_flame_variation_name(int v);

#endif
