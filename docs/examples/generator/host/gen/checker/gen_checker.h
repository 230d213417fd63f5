/*
 * The checker generator's parameters (a layer's, as parsed from the scene) and its class.
 */
#ifndef FB_GEN_CHECKER_H
#define FB_GEN_CHECKER_H

#include "gen.h"

typedef struct fb_checker_params {
    int cells; /* squares across each side */
} fb_checker_params;

extern const fb_gen_class fb_gen_checker;

#endif
