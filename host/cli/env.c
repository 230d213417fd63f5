/* The environment, read once: see env.h. */
#include "env.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool env_true(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

void fb_env_lavapipe_threads(int threads)
{
    if (threads <= 0) return;
    char n[16];
    snprintf(n, sizeof n, "%d", threads);
    setenv("LP_NUM_THREADS", n, 1);
}

void fb_env_read(fb_env *env)
{
    memset(env, 0, sizeof *env);
    env->vk.validation = env_true("FB_VK_VALIDATION");
    /* a discrete GPU's path on any device: its memory, and the portable exact arithmetic */
    env->vk.staging = env->vk.portable = env_true("FB_VK_STAGING");
    env->vk.portable = env->vk.portable || env_true("FB_VK_PORTABLE"); /* the arithmetic alone */
    env->vk.no_int64 = env_true("FB_VK_NO_INT64");
    env->vk.no_float64 = env_true("FB_VK_NO_FLOAT64");
    env->vk.no_pipeline_cache = env_true("FB_NO_PIPELINE_CACHE");
    const char *base = getenv("XDG_CACHE_HOME");
    if (base && *base)
        snprintf(env->cache_dir, sizeof env->cache_dir, "%s/fractalbake", base);
    else if ((base = getenv("HOME")) && *base)
        snprintf(env->cache_dir, sizeof env->cache_dir, "%s/.cache/fractalbake", base);
    env->vk.cache_dir = env->cache_dir[0] ? env->cache_dir : NULL;
    const char *lp = getenv("LP_NUM_THREADS");
    snprintf(env->lp_num_threads, sizeof env->lp_num_threads, "%s", lp ? lp : "");
    lp = getenv("LP_NATIVE_VECTOR_WIDTH");
    snprintf(env->lp_vector_width, sizeof env->lp_vector_width, "%s", lp ? lp : "");
    const char *tmp = getenv("TMPDIR");
    snprintf(env->tmpdir, sizeof env->tmpdir, "%s", tmp ? tmp : "");
}
