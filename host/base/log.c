#include "fb.h"

#include <errno.h>
#include <math.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* The calling thread's scope (fb.h), and the logger fb_log_set_sink keeps for it. */
static _Thread_local fb_scope t_scope;
static _Thread_local fb_logger t_logger;

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
    case FB_ERR_CANCELLED:
        return "cancelled";
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

fb_scope fb_scope_get(void)
{
    return t_scope;
}

fb_scope fb_scope_set(fb_scope s)
{
    fb_scope old = t_scope;
    t_scope = s;
    return old;
}

void fb_log_set_sink(fb_log_fn fn, void *user)
{
    t_logger = (fb_logger){fn, user};
    t_scope.log = fn ? &t_logger : NULL;
}

/* What the calling thread is doing ("layer sky, rows 512-767"), put before its errors and warnings. */
static _Thread_local char t_context[160];

void fb_log_context(const char *fmt, ...)
{
    if (!fmt) {
        t_context[0] = 0;
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(t_context, sizeof t_context, fmt, ap);
    va_end(ap);
}

static void vlog(int level, const char *fmt, va_list ap)
{
    const fb_logger *log = t_scope.log;
    if (!log || !log->fn) return;
    char buf[2048], msg[2048 + 192];
    vsnprintf(buf, sizeof buf, fmt, ap);
    const char *out = buf;
    if (t_context[0] && level <= FB_LOG_WARN) {
        /* A message that already names the context's subject ("layer sky: ...") keeps its words;
         * the context adds what it lacks (the rows). */
        size_t subject = strcspn(t_context, ",");
        if (!strncmp(buf, t_context, subject) && (buf[subject] == ':' || buf[subject] == ',')) {
            if (t_context[subject] && buf[subject] == ':')
                snprintf(msg, sizeof msg, "%s%s", t_context, buf + subject);
            else
                snprintf(msg, sizeof msg, "%s", buf);
        } else {
            snprintf(msg, sizeof msg, "%s: %s", t_context, buf);
        }
        out = msg;
    }
    log->fn(level, out, log->user);
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

void fb_release_free_memory(void)
{
#ifdef __GLIBC__
    malloc_trim(0);
#endif
}

uint64_t fb_physical_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    uint64_t phys = pages > 0 && page > 0 ? (uint64_t)pages * (uint64_t)page : (uint64_t)8 << 30;
    /* A container's limit (cgroup v2) is the machine a run really has. */
    FILE *f = fopen("/sys/fs/cgroup/memory.max", "r");
    unsigned long long lim = 0;
    if (f) {
        if (fscanf(f, "%llu", &lim) == 1 && lim > 0 && lim < phys) phys = lim;
        fclose(f);
    }
    return phys;
}

uint64_t fb_address_space_limit(void)
{
    struct rlimit r;
    if (getrlimit(RLIMIT_AS, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return UINT64_MAX;
    return (uint64_t)r.rlim_cur;
}

/* The default: 80% of the memory, and no more than the address space (ulimit -v) leaves beyond what
 * the process and its backend map for themselves (code, thread stacks and malloc arenas, a Vulkan
 * driver). */
static uint64_t overhead_of(const fb_memory *m)
{
    return m && m->overhead ? m->overhead : (uint64_t)256 << 20;
}

static uint64_t default_limit(const fb_memory *m, bool *from_as)
{
    uint64_t over = overhead_of(m);
    uint64_t phys = fb_physical_memory() / 10 * 8, as = fb_address_space_limit();
    uint64_t room = as == UINT64_MAX ? UINT64_MAX : as > over + ((uint64_t)1 << 20) ? as - over : 1 << 20;
    *from_as = room < phys;
    return room < phys ? room : phys;
}

uint64_t fb_memory_limit(const fb_memory *m)
{
    bool as;
    return m && m->limit ? m->limit : default_limit(m, &as);
}

bool fb_parse_memory(const char *s, uint64_t *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || errno || !(v > 0) || !isfinite(v)) return false;
    double scale = 1;
    if (*end == '%') {
        if (v > 100) return false;
        scale = (double)fb_physical_memory() / 100.0;
        end++;
    } else if (*end) {
        const char *units = "KMGT";
        const char *u = strchr(units, *end);
        if (!u) return false;
        scale = (double)(1ull << (10 * (u - units + 1)));
        end++;
        if (*end == 'i') end++;
        if (*end == 'B') end++;
    }
    if (*end || v * scale < 1 << 20 || v * scale > 9.0e18) return false;
    *out = (uint64_t)(v * scale);
    return true;
}

void fb_format_bytes(uint64_t bytes, char *out, size_t size)
{
    if (bytes >= (1ull << 30))
        snprintf(out, size, "%.2f GiB", (double)bytes / (double)(1ull << 30));
    else
        snprintf(out, size, "%.1f MiB", (double)bytes / (double)(1ull << 20));
}

fb_result fb_memory_check(const fb_memory *m, uint64_t bytes, const char *who)
{
    if (bytes <= fb_memory_limit(m)) return FB_OK;
    char need[32], lim[32], note[160];
    fb_format_bytes(bytes, need, sizeof need);
    fb_format_bytes(fb_memory_limit(m), lim, sizeof lim);
    return fb_fail(FB_ERR_INPUT, "%s needs about %s, more than --max-memory %s%s", who, need, lim,
                   fb_memory_limit_note(m, note, sizeof note));
}

const char *fb_memory_limit_note(const fb_memory *m, char *buf, size_t size)
{
    bool as = false;
    buf[0] = 0;
    if (!(m && m->limit)) default_limit(m, &as);
    if (!as) return buf;
    char total[32], over[32];
    fb_format_bytes(fb_address_space_limit(), total, sizeof total);
    fb_format_bytes(overhead_of(m), over, sizeof over);
    snprintf(buf, size, " (the default: the address-space limit, ulimit -v, %s, less about %s the process maps)", total,
             over);
    return buf;
}

const char *fb_file_kind(unsigned mode)
{
    return S_ISDIR(mode)    ? "a directory"
           : S_ISLNK(mode)  ? "a symbolic link"
           : S_ISCHR(mode)  ? "a character device"
           : S_ISBLK(mode)  ? "a block device"
           : S_ISFIFO(mode) ? "a FIFO"
           : S_ISSOCK(mode) ? "a socket"
                            : "not a regular file";
}

const char *fb_closest(const char *word, const char *const *cands, int n)
{
    size_t lw = strlen(word);
    if (lw == 0 || lw > 63) return NULL;
    const char *best = NULL;
    size_t best_d = lw <= 4 ? 1 : 2; /* at most one edit for short words, two for the rest */
    for (int c = 0; c < n; c++) {
        size_t lc = strlen(cands[c]);
        if (lc > 63 || (lc > lw ? lc - lw : lw - lc) > best_d) continue;
        size_t row[64], prev_diag, tmp; /* Levenshtein distance, one row */
        for (size_t j = 0; j <= lc; j++) row[j] = j;
        for (size_t i = 1; i <= lw; i++) {
            prev_diag = row[0];
            row[0] = i;
            for (size_t j = 1; j <= lc; j++) {
                tmp = row[j];
                size_t sub = prev_diag + (word[i - 1] != cands[c][j - 1]);
                size_t del = row[j] + 1, ins = row[j - 1] + 1;
                row[j] = sub < del ? (sub < ins ? sub : ins) : (del < ins ? del : ins);
                prev_diag = tmp;
            }
        }
        if (row[lc] > 0 && row[lc] <= best_d && (!best || row[lc] < best_d)) best = cands[c], best_d = row[lc];
    }
    return best;
}

void fb_format_shortest(double v, char *out, size_t size)
{
    for (int p = 1; p <= 17; p++) {
        snprintf(out, size, "%.*g", p, v);
        if (strtod(out, NULL) == v) return;
    }
}
