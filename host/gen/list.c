/*
 * The generators, in the order the help lists them. A new generator is a folder host/gen/NAME/
 * whose layer.c defines `const fb_gen_class fb_gen_NAME`, and its name on a line here
 * (docs/architecture.md).
 */
#include "gen.h"

#define FB_GENERATORS(X)                                                                                               \
    X(fbm)                                                                                                             \
    X(julia)                                                                                                           \
    X(stars)                                                                                                           \
    X(ifs)                                                                                                             \
    X(flame)                                                                                                           \
    X(lsystem)                                                                                                         \
    X(terrain)                                                                                                         \
    X(constrain)                                                                                                       \
    X(erode)                                                                                                           \
    X(rivers)                                                                                                          \
    X(op)

#define DECLARE(name) extern const fb_gen_class fb_gen_##name;
#define ENTRY(name)   &fb_gen_##name,
FB_GENERATORS(DECLARE)
const fb_gen_class *const fb_gen_list[] = {FB_GENERATORS(ENTRY) NULL};
