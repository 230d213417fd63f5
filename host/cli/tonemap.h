/* `fractalbake tonemap`: the tone mapping of an ifs layer, re-run from a baked file. */
#ifndef FB_TONEMAP_H
#define FB_TONEMAP_H

#include "fb.h"

#include <stdbool.h>

/* Runs the command; *quiet and *json are set when --quiet and --json were given. */
fb_result fb_tonemap_main(int argc, char **argv, bool *quiet, bool *json);

#endif
