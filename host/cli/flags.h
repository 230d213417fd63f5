/* The command line's flags as scene keys (flags.c). */
#ifndef FB_FLAGS_H
#define FB_FLAGS_H

#include "fb.h"

/* converts `--flag value` of a single-generator command into the JSON scene
 * it stands for. `kind` is the generator ("fbm"; fb_gen_find). argv holds only the generator's flags. Returns
 * malloc'd JSON text in *json. Global flags (--size, --seed, --compression) become scene keys. */
fb_result fb_scene_from_flags(const char *kind, int argc, char **argv, char **json);

/* how many values flag `flag` (without the dashes) of generator `kind` takes:
 * 0 for a switch (--tileable), 1 for a valued flag (--octaves 8), -1 when it is not a flag of
 * `kind` or of the scene. */
int fb_scene_flag_arity(const char *kind, const char *flag);

/* The flags of generator `kind` and of the scene, without dashes (for "did you mean" hints). */
int fb_scene_flags(const char *kind, const char **out, int max);

/* Prints the keys of a generator with their types, ranges and defaults (for --help). */
void fb_scene_print_keys(const char *kind, void (*print)(const char *line, void *user), void *user);

#endif
