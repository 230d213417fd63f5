/*
 * The op generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_OP_H
#define FB_GEN_OP_H

#include "gen.h"

#define FB_OP_MAX_INPUTS 8
typedef enum fb_op_kind { FB_OP_ADD = 0, FB_OP_MULTIPLY, FB_OP_MIX, FB_OP_REMAP, FB_OP_THRESHOLD } fb_op_kind;

/* A compositing layer: one channel NAME.Y computed per pixel from other layers' channels. */
typedef struct fb_op_params {
    fb_op_kind op;
    int ninputs;
    fb_ref inputs[FB_OP_MAX_INPUTS];
    double weights[FB_OP_MAX_INPUTS]; /* add: sum of w_i x_i */
    fb_ref mask;                      /* mix: a + (b - a) clamp(m, 0, 1) */
    double from[2], to[2];            /* remap: from[0]..from[1] -> to[0]..to[1] */
    bool clamp;                       /* remap: clamp to the target range */
    double level, width;              /* threshold: smoothstep over level -/+ width/2 (a step if 0) */
} fb_op_params;

extern const fb_gen_class fb_gen_op;

#endif
