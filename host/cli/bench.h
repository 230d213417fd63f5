/* `fractalbake bench`: throughput of every generator on each backend, measured in one run. */
#ifndef FB_BENCH_H
#define FB_BENCH_H

#include "fb.h"

struct fb_env;
/* Runs `fractalbake bench`; env: the environment's Vulkan options (env.h). */
fb_result fb_bench_main(int argc, char **argv, const struct fb_env *env);

#endif
