/*
 * The engines a determinism test compares: native on 2, 1 and 3 threads, then lavapipe (or whichever
 * Vulkan device exists) with the validation layer, when there is one.
 */
#ifndef FB_TESTENGINES_H
#define FB_TESTENGINES_H

#include "bake.h"

#include "testhelp.h"

#include <stdbool.h>
#include <stdio.h>

/* Opens up to 4 engines into engines[]; returns how many. *have_gpu: the last one is Vulkan. */
static int th_open_engines(fb_engine engines[4], bool *have_gpu)
{
    int n = 0;
    const int threads[3] = {2, 1, 3};
    for (int i = 0; i < 3; i++)
        if (fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_NATIVE, .threads = threads[i]}, &engines[n]) ==
            FB_OK)
            n++;
    CHECK(n == 3);
    *have_gpu =
        fb_engine_open(&(fb_engine_desc){.backend = FB_BACKEND_VULKAN, .validation = true}, &engines[n]) == FB_OK;
    if (*have_gpu)
        n++;
    else
        printf("no Vulkan device: the lavapipe comparisons are not run\n");
    return n;
}

#endif
