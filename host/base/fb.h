/*
 * fractalbake: the types every host module shares: the result code, the logger, small helpers.
 *
 * Library code (every folder of host/ below host/cli, and kernels/) never prints, never exits and
 * never reads the environment: it returns an fb_result, hands its text to the logger and its
 * progress to the progress sink of the calling thread's scope (fb_scope, which its caller sets:
 * main() for the command line, a library context for one call), and takes its settings in
 * descriptors. It writes nothing on standard output or standard error (no printf, puts, perror,
 * stdout or stderr); the files a run names it writes through output.h, where "-" is standard
 * output as one of those files. host/cli is the user interface: its commands print their results
 * and messages, and cli/env.c alone reads the environment. tests/rules.py checks these rules.
 */
#ifndef FB_H
#define FB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define FB_VERSION "0.1.0"

/* The largest image side anything reads or writes. */
#define FB_MAX_DIM 65536

typedef int32_t fb_result;

enum {
    FB_OK = 0,
    FB_ERR_USAGE = 1,     /* bad flag or argument (exit 2) */
    FB_ERR_INPUT = 2,     /* bad input data: scene, file contents, values (exit 2) */
    FB_ERR_IO = 3,        /* file system: cannot open, write, rename (exit 3) */
    FB_ERR_NOMEM = 4,     /* allocation failed (exit 3) */
    FB_ERR_VULKAN = 5,    /* a Vulkan call failed (exit 3) */
    FB_ERR_NODEVICE = 6,  /* no Vulkan loader or no device (exit 3 when vulkan was asked for) */
    FB_ERR_EXR = 7,       /* OpenEXRCore reported an error (exit 3) */
    FB_ERR_INTERNAL = 8,  /* an impossible state was reached (exit 3) */
    FB_ERR_CANCELLED = 9, /* the caller cancelled the work (a library's progress callback; exit 3) */
};

/* A short name for a result code ("bad input", "vulkan error", ...). */
const char *fb_result_string(fb_result r);

/* The process exit code of a result (docs/usage.md): 0, 2 (usage, input) or 3 (runtime). */
int fb_result_exit_code(fb_result r);

/* Log levels. Errors are the one line a user sees when a command fails. */
enum { FB_LOG_ERROR = 0, FB_LOG_WARN = 1, FB_LOG_INFO = 2, FB_LOG_DEBUG = 3 };

typedef void (*fb_log_fn)(int level, const char *msg, void *user);

/* Where log text goes: fn(level, msg, user). */
typedef struct fb_logger {
    fb_log_fn fn;
    void *user;
} fb_logger;

/*
 * What a piece of work runs in: where its log goes, the output transaction its files join
 * (output.h), where its progress is shown (progress.h). There is no process-wide setting of any of
 * them: each thread has a scope, which a caller (the command line's main, a library context for
 * the length of one call) sets on the thread it works on, and which the threads started for that
 * work take from the thread that starts them (the pool's workers take the scope of the thread that
 * hands them a job, the EXR writer's the scope of the thread that creates it). Two contexts working
 * at once on two threads never see each other's messages, files or progress. NULL fields: the log
 * goes nowhere, outputs go to the thread's own transaction (output.h), progress is shown nowhere.
 */
struct fb_outputs;
struct fb_progress_sink;
typedef struct fb_scope {
    const fb_logger *log; /* must outlive the scope's use */
    struct fb_outputs *outputs;
    const struct fb_progress_sink *progress;
} fb_scope;

/* The calling thread's scope. */
fb_scope fb_scope_get(void);

/* Sets the calling thread's scope; returns the one it replaces, for the caller to set back. */
fb_scope fb_scope_set(fb_scope s);

/* The calling thread's scope with its transaction named even where it is the thread's own (output.h):
 * what a thread started for this thread's work sets as its scope. */
fb_scope fb_scope_capture(void);

/* Routes the calling thread's log text to fn (NULL: nothing): its scope's logger, held by the
 * thread (for programs and tests that log on one thread; a library call sets a scope instead). */
void fb_log_set_sink(fb_log_fn fn, void *user);

/* Formats a message and hands it to the sink. Returns `r` so that callers can write
 * `return fb_fail(FB_ERR_INPUT, "size: expected ...")`. */
fb_result fb_fail(fb_result r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void fb_log(int level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Sets what the calling thread is doing, "layer sky" or "layer sky, rows 512-767" (printf-style;
 * NULL clears it): its errors and warnings then begin with it, so that a module's message needs
 * not say which layer or rows it was about. A message that already begins with the same subject
 * ("layer sky: ...") gets only the rest ("layer sky, rows 512-767: ..."). */
void fb_log_context(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* SQLite's defensive-check idiom: conditions that must never happen. In debug builds they abort;
 * in release builds they still evaluate and let the caller take the error path. */
#ifdef NDEBUG
#define ALWAYS(x) (x)
#define NEVER(x)  (x)
#else
#include <assert.h>
#define ALWAYS(x) ((x) ? 1 : (assert(0), 0))
#define NEVER(x)  ((x) ? (assert(0), 1) : 0)
#endif

/* Seconds on a monotonic clock. */
double fb_now(void);

/* Number of online CPU cores (at least 1). */
int fb_cpu_count(void);

/* Physical memory, or the container's (cgroup v2 memory.max) where that is less. */
uint64_t fb_physical_memory(void);

/* The memory a run may use, carried in the descriptors of the work that allocates it (a bake's,
 * a merge's, a layer's fb_gen): limit, --max-memory's bytes, 0 for the default, 80% of
 * fb_physical_memory() and at most the address-space limit (RLIMIT_AS, ulimit -v) less overhead,
 * the address space the process maps for itself beyond the data a bake predicts (code, thread
 * stacks, malloc arenas, a Vulkan driver's mappings: the engine that runs the bake knows it; 0: 256
 * MiB). A NULL fb_memory is {0, 0}: the default limit. */
typedef struct fb_memory {
    uint64_t limit, overhead;
} fb_memory;
uint64_t fb_memory_limit(const fb_memory *m);

/* RLIMIT_AS's soft limit in bytes, UINT64_MAX where there is none. */
uint64_t fb_address_space_limit(void);

/* "" when the limit is --max-memory's or 80% of the memory; else " (the default: the address-space
 * limit ...)" in buf, for messages that name the limit. */
const char *fb_memory_limit_note(const fb_memory *m, char *buf, size_t size);

/* "512M", "8G", "8GiB", "1.5T", "12345678" (bytes), "50%" (of physical memory): at least 1 MiB.
 * False for anything else. */
bool fb_parse_memory(const char *s, uint64_t *out);

/* FB_ERR_INPUT "WHO needs about X, more than --max-memory Y" when bytes exceed fb_memory_limit(m). */
fb_result fb_memory_check(const fb_memory *m, uint64_t bytes, const char *who);

/* "12.3 MiB" / "1.25 GiB" */
void fb_format_bytes(uint64_t bytes, char *out, size_t size);

/* The shortest %g text of v that strtod reads back as the same double ("0.3", not
 * "0.29999999999999999"); "inf", "-inf" or "nan" for those. */
void fb_format_shortest(double v, char *out, size_t size);

/* What a file of this st_mode is, for "PATH: is KIND" messages ("a FIFO", "a character device"): the
 * output transaction's and the text inputs' (output.c, textin.c). */
const char *fb_file_kind(unsigned mode);

/* The candidate nearest to a misspelt word by edit distance (at most 1 edit for words of up to 4
 * letters, 2 beyond), for "did you mean" hints; NULL when none is that near. */
const char *fb_closest(const char *word, const char *const *cands, int n);

/* malloc for arrays of hundreds of MiB: 2 MiB-aligned and marked for transparent huge pages, so the
 * first touch costs a fault per 2 MiB instead of per 4 KiB (the kernel may decline). Free with free(). */
void *fb_malloc_large(size_t size);

/* Gives the allocator's free memory back to the system (glibc: malloc_trim), after a phase that
 * freed much (a CPU device's shader compiler), so that it does not stay resident beside what comes
 * next. Nothing elsewhere. */
void fb_release_free_memory(void);

#endif
