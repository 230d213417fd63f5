/*
 * Re-toning a stored layer (`fractalbake tonemap`): the tone mapping of a layer whose class can
 * re-tone it (gen.h: fb_tone_ops; an ifs layer from the density and colour channels a bake stored)
 * run again with new tone parameters, without computing the layer again. The output is the input
 * file with that layer's tone-mapped channels recomputed and the scene updated; with the parameters
 * unchanged it reproduces the bake bit for bit (tests/cli/ifs.sh).
 */
#ifndef FB_TONEMAP_H
#define FB_TONEMAP_H

#include "fb.h"

#include <stddef.h>

struct fb_gen_class;

typedef struct fb_tonemap_desc {
    const char *in;      /* the baked EXR */
    const char *out;     /* the EXR written, through the output transaction */
    const char *layer;   /* the layer to re-tone; NULL: the first whose class can */
    const char *preview; /* also this PNG: the re-toned layer's R, G, B, as a bake's preview of it alone; NULL: none */
    /* The new tone parameters once the layer's class c is known: *json, a scene (malloc'd, freed
     * here) whose one layer holds them as c's scene keys, as the command line reads them from its
     * flags (fb_scene_from_flags). A key that is not one of c's tone keys is a usage error naming
     * it; a colour map given replaces the stored one of whatever kind. */
    fb_result (*tone)(const struct fb_gen_class *c, void *user, char **json);
    void *user;
} fb_tonemap_desc;

/* Writes d->out: d->in with the layer re-toned. Input errors (no stored scene, no layer that can be
 * re-toned, a size that does not match) name the file. */
fb_result fb_tonemap(const fb_tonemap_desc *d);

/* The classes that can re-tone a layer, "ifs, ..." into out (for messages and help); how many. */
int fb_tone_classes(char *out, size_t size);

#endif
