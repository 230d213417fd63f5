/* Progress, through the sink of the calling thread's scope (fb.h: the command line's writes to stderr). On a
 * terminal, a bar redrawn five times a second by a thread of its own once the work has lasted half a
 * second, with the rate and the time left; for a log, a line after 10 s and then one a minute, so that
 * short runs and logs stay clean and long ones are never silent. Workers report from any thread
 * (fb_progress_add); only the progress thread writes. Library code never prints: without a sink,
 * nothing is shown. */
#ifndef FB_PROGRESS_H
#define FB_PROGRESS_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

typedef struct fb_progress_sink {
    bool terminal;                               /* redraw a bar in place ("\r"), else write log lines */
    void (*write)(const char *text, void *user); /* shows text as it is (NULL: nothing shown) */
    /* Asked by fb_progress_poll with the fraction done (0 to 1): non-zero stops the work (a library
     * caller's progress callback). NULL: the work never stops early. */
    int (*poll)(double fraction, void *user);
    void *user;
} fb_progress_sink;

typedef struct fb_progress {
    fb_progress_sink sink; /* the scope's when it started */
    bool enabled, tty, steps;
    double start;
    double scale; /* units shown per unit counted (1 unless fb_progress_set_scale) */
    const char *label;
    const char *unit;
    char detail[96]; /* shown after the bar (fb_progress_detail) */
    _Atomic uint64_t done, total;
    _Atomic bool stop;
    bool running, drawn;
    double last_line;
    pthread_t thread;
    pthread_mutex_t mu; /* guards detail */
} fb_progress;

/* Installs the sink (copied; NULL: none) as the calling thread's scope's (fb.h), for progress started
 * on this thread from now on. */
void fb_progress_set_sink(const fb_progress_sink *sink);

/* Starts the progress of `total` units of `unit` (pixels, points): nothing at all unless enabled. */
void fb_progress_init(fb_progress *p, bool enabled, const char *label, const char *unit);
/* The same for a count of steps ("3 of 14") with no rate and no time left (steps of uneven cost): a benchmark's
 * generators. */
void fb_progress_init_steps(fb_progress *p, bool enabled, const char *label);
/* done of total work units, from the thread that knows them */
void fb_progress_update(fb_progress *p, uint64_t done, uint64_t total);
/* The units counted are `per` of the units shown (a bake counts pixels of each layer and shows
 * pixels: per = the layer count). */
void fb_progress_set_scale(fb_progress *p, double per);
/* n more units done, from any thread */
void fb_progress_add(fb_progress *p, uint64_t n);
/* A short text after the bar (the benchmark's current case). */
void fb_progress_detail(fb_progress *p, const char *text);
/* Whether the work should stop: the sink's poll, asked with the fraction done, on the calling thread
 * (the one that drives the work, between its steps). false without a poll or when not enabled. */
bool fb_progress_poll(fb_progress *p);
/* Stops the progress thread and clears the bar. */
void fb_progress_finish(fb_progress *p);

/* "12.3 Mpix/s", "456 kpts/s", "7.89 pix/s": a rate with its SI prefix. */
void fb_format_rate(double per_second, const char *unit, char *out, int size);

#endif
