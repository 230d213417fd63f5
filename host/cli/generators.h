/* `fractalbake generators`: the registered generator classes, their keys and how they are planned. */
#ifndef FB_GENERATORS_H
#define FB_GENERATORS_H

#include "fb.h"

/* Prints the list (text, or JSON with --json) on standard output. */
fb_result fb_generators_main(int argc, char **argv);

#endif
