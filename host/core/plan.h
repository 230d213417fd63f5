/*
 * Splitting a bake over N tasks (fractalbake plan, render --task K/N, merge).
 *
 * Each layer's cost comes from a per-generator model in seconds of one core of the reference machine
 * (docs/scenes.md, "Splitting a bake"): pixels x octaves for fBm, iterations for Julia (counted by a
 * pre-pass at 64 pixels wide), points for the chaos game, insertions and pixels for terrain. Layers
 * are grouped into units: the layers that refer to each other are one unit. A unit of per-pixel
 * layers (fbm, julia, op) is cut into horizontal bands; a lone chaos-game layer (ifs) into points
 * parts; any other unit (terrain, constrain, lsystem, a layer that writes a heightmap, or one that
 * uses them) is computed whole by one task, because its cost does not shrink with a band.
 *
 * A task holds either a band of every banded layer, or whole-image layers and points parts. Tasks
 * are numbered from 0 (like SLURM_ARRAY_TASK_ID): the bands first, top to bottom, then the others.
 * The plan uses the fewest tasks that keep the split's total within 10% of one bake (each task pays
 * a start-up), and of those the split whose longest task is shortest; tasks past the last it uses
 * have nothing to do. The plan depends only on the scene and N, so every task computes the same one.
 */
#ifndef FB_PLAN_H
#define FB_PLAN_H

#include "gen.h"
#include "scene.h"

#define FB_PLAN_MAX_TASKS 1024

typedef struct fb_task {
    bool band;        /* rows [y0, y1) of the banded layers; else whole-image layers and points parts */
    int y0, y1;       /* band: the rows */
    uint32_t layers;  /* the scene's layers it computes (bit i: layer i) */
    uint32_t points;  /* of them, the chaos games it computes a points part of */
    int part, nparts; /* that points part, 1-based (render --points-part), when points != 0 */
    double seconds;   /* the model's cost, its start-up included */
} fb_task;

typedef struct fb_plan {
    int ntasks;                    /* N */
    int nactive;                   /* tasks 0 .. nactive-1 have work; the others none */
    int nbands, nparts;            /* bands of the banded layers; points parts of the chaos games (0: whole) */
    fb_share share[FB_MAX_LAYERS]; /* how each layer is split */
    double layer_seconds[FB_MAX_LAYERS];
    double startup;                   /* the model's start-up of one task */
    double one;                       /* one bake: every layer and one start-up */
    double total;                     /* the tasks together */
    double longest;                   /* the longest task */
    fb_task tasks[FB_PLAN_MAX_TASKS]; /* nactive of them */
} fb_plan;

/* The model's start-up of a task, in seconds (measured on the reference machine: the process, the
 * scene and a Vulkan instance on lavapipe). */
#define FB_PLAN_STARTUP 0.07

/* Plans scene s over ntasks tasks (1 .. FB_PLAN_MAX_TASKS); startup: each task's start-up in seconds
 * (< 0: FB_PLAN_STARTUP; 0 uses every task that shortens the longest). */
fb_result fb_plan_make(const fb_scene *s, int ntasks, double startup, fb_plan *p);

/* The plan as JSON text (malloc'd; compact unless pretty): what render --task stores in each task's
 * file and merge reads back with fb_plan_parse. */
char *fb_plan_json(const fb_scene *s, const fb_plan *p, bool pretty);

/* "bands", "points parts" or "whole": how a layer is shared, for tables. */
const char *fb_plan_share_name(fb_share share);

/* Reads fb_plan_json's text for scene s. */
fb_result fb_plan_parse(const char *text, const fb_scene *s, fb_plan *p);

/* "rows 0-127 of sky, ops", "whole terrain" or "whole terrain; points part 1/2 of plants": task t's
 * share, for messages. */
void fb_plan_describe(const fb_scene *s, const fb_task *t, char *out, size_t size);

/* The scene of the layers in `mask` only, in the same order, their references renumbered; every
 * other field as in s (its json is a copy of s's: the whole scene, as a task's file stores it). */
fb_result fb_scene_subset(const fb_scene *s, uint32_t mask, fb_scene *out);

#endif
