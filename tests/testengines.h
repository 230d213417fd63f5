/*
 * The engines a determinism test compares: native on 2, 1 and 3 threads, then, when the test runs
 * with --gpu (its CTest entry NAME-gpu, label gpu), lavapipe (or whichever Vulkan device exists)
 * with the validation layer. With --gpu and no device the test exits 77 (not run); without --gpu it
 * runs the native engines only, so no comparison is reported as passed that did not run.
 */
#ifndef FB_TESTENGINES_H
#define FB_TESTENGINES_H

#include "bake.h"
#include "env.h"

#include "testhelp.h"

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Opens up to 4 engines into engines[]; returns how many. *have_gpu: the last one is Vulkan (only with
 * --gpu among the arguments; exits 77 when there is no device then). */
static int th_open_engines(int argc, char **argv, fb_engine engines[4], bool *have_gpu)
{
    bool gpu = false;
    for (int i = 1; i < argc; i++) gpu = gpu || !strcmp(argv[i], "--gpu");
    int n = 0;
    const int threads[3] = {2, 1, 3};
    for (int i = 0; i < 3; i++)
        if (fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = threads[i]}, &engines[n]) ==
            FB_OK)
            n++;
    CHECK(n == 3);
    fb_env env; /* the pipeline cache's folder, as the command line has it */
    fb_env_read(&env);
    *have_gpu =
        gpu && fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .validation = true, .vk_options = env.vk},
                              &engines[n]) == FB_OK;
    if (*have_gpu) {
        n++;
    } else if (gpu) {
        printf("no Vulkan device: not run\n");
        exit(77);
    }
    return n;
}

#endif
