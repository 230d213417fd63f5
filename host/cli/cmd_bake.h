/* What the baking commands (render and each generator's command) share: their options and the bake. */
#ifndef FB_CMD_BAKE_H
#define FB_CMD_BAKE_H

#include "args.h"
#include "command.h"
#include "engine.h"
#include "scene.h"

/* Options every baking command shares (the table fb_bake_flags reads them). */
typedef struct fb_bake_opts {
    const char *out, *preview, *preview_layer, *device, *cube_faces;
    fb_backend backend;
    int threads, strip_rows, zip_level;
    int region[4];       /* x, y, w, h; w == 0: none */
    int points_part[2];  /* K, N; N == 0: none */
    int task[2];         /* render --task K/N (K from 0); N == 0: none */
    double task_startup; /* --task-startup S; < 0: not given */
    bool quiet, validation, help, json, dry_run;
    bool backend_from;       /* render --from chose the backend (the one the file was baked on) */
    const char *layer_kinds; /* render --from an auto file: where each layer ran (fb_bake_desc) */
    uint64_t max_memory;     /* 0: the default (80% of physical memory) */
} fb_bake_opts;

/* The shared flags, for a command's table list; fb_bake_opts_init gives their defaults. */
extern const fb_arg fb_bake_flags[];
void fb_bake_opts_init(fb_bake_opts *o);

/* Value readers other commands use for the same flags (plan's --task-startup, merge's --max-memory). */
fb_result fb_arg_seconds(const char *flag, const char *value, void *field);
fb_result fb_arg_memory(const char *flag, const char *value, void *field);
bool fb_parse_region(const char *s, int r[4]);
bool fb_parse_points_part(const char *s, int pp[2]);

/* Bakes the scene as the options say (a task's share, a region, a points part), with the summary
 * (--json or the lines after the commit). */
fb_result fb_cli_bake(const fb_cli *cli, const char *command, fb_scene *scene, const fb_bake_opts *o);

#endif
