#include "fb.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

static fb_log_fn g_sink;
static void *g_sink_user;

const char *fb_result_string(fb_result r)
{
    switch (r) {
    case FB_OK:
        return "ok";
    case FB_ERR_USAGE:
        return "bad usage";
    case FB_ERR_INPUT:
        return "bad input";
    case FB_ERR_IO:
        return "i/o error";
    case FB_ERR_NOMEM:
        return "out of memory";
    case FB_ERR_VULKAN:
        return "vulkan error";
    case FB_ERR_NODEVICE:
        return "no vulkan device";
    case FB_ERR_EXR:
        return "openexr error";
    case FB_ERR_INTERNAL:
        return "internal error";
    default:
        return "unknown error";
    }
}

int fb_result_exit_code(fb_result r)
{
    if (r == FB_OK) return 0;
    if (r == FB_ERR_USAGE || r == FB_ERR_INPUT) return 2;
    return 3;
}

void fb_log_set_sink(fb_log_fn fn, void *user)
{
    g_sink = fn;
    g_sink_user = user;
}

static void vlog(int level, const char *fmt, va_list ap)
{
    if (!g_sink) return;
    char buf[2048];
    vsnprintf(buf, sizeof buf, fmt, ap);
    g_sink(level, buf, g_sink_user);
}

fb_result fb_fail(fb_result r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(FB_LOG_ERROR, fmt, ap);
    va_end(ap);
    return r;
}

void fb_log(int level, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(level, fmt, ap);
    va_end(ap);
}

double fb_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int fb_cpu_count(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

void *fb_malloc_large(size_t size)
{
    const size_t huge = (size_t)2 << 20;
    if (size < huge) return malloc(size);
    void *p = NULL;
    if (posix_memalign(&p, huge, size)) return NULL;
#ifdef MADV_HUGEPAGE
    madvise(p, size & ~(size_t)4095, MADV_HUGEPAGE); /* advice only: failure changes nothing */
#endif
    return p;
}
