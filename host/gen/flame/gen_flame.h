/*
 * The flame generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_FLAME_H
#define FB_GEN_FLAME_H

#include "gen.h"
#include "genome.h"
#include "render.h"

#define FB_FLAME_PATH 4096

typedef struct fb_flame_params {
    char file[FB_FLAME_PATH];     /* the .flame file */
    char pick[4096];              /* its <flame> by name or index; "": the first */
    char palettes[FB_FLAME_PATH]; /* flam3's palette library */
    fb_flame_genome genome;       /* read from the file at parse time; animated: the frame's (animate.h) */
    double quality;               /* samples per pixel; 0: the genome's */
    fb_flame_tone tone;           /* the genome's tone map, with the layer's tone keys applied */
    /* animated (the key time): the file's flames are keyframes, the frame is at `time`, made of
     * temporal_samples (0: the genome's) chaos games between them; the bake reads the file again */
    bool animated;
    double time;
    int temporal_samples;
} fb_flame_params;

/* The last prepare's chaos game: its points, wall seconds (the game alone: no density estimation,
 * filter or file), the device's seconds from its timestamps (<= 0: none, or native), and the whole
 * prepare's wall seconds (the game, density estimation and the spatial filter: no tone map or file). */
typedef struct fb_flame_stats {
    double points, game_seconds, gpu_seconds, prepare_seconds;
} fb_flame_stats;

extern const fb_gen_class fb_gen_flame;
extern const fb_tone_ops fb_flame_tone_ops; /* tone.c: fractalbake tonemap */

/* The stats of a flame layer's generator after prepare; NULL for another class. */
const fb_flame_stats *fb_gen_flame_stats(const fb_gen *g);

/* fractalbake bench's flame rows (bench.c). */
struct fb_bench;
fb_result fb_flame_bench(struct fb_bench *b);

#endif
