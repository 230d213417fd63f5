/*
 * The flame generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_FLAME_H
#define FB_GEN_FLAME_H

#include "gen.h"
#include "genome.h"
#include "render.h"

typedef struct fb_flame_params {
    fb_flame_genome genome; /* read from the file at parse time */
    double quality;         /* samples per pixel; 0: the genome's */
    fb_flame_tone tone;     /* the genome's tone map, with the layer's tone keys applied */
} fb_flame_params;

extern const fb_gen_class fb_gen_flame;
extern const fb_tone_ops fb_flame_tone_ops; /* tone.c: fractalbake tonemap */

#endif
