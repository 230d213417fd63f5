#include "progress.h"

#include "fb.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* The sink fb_progress_set_sink keeps for the calling thread's scope. */
static _Thread_local fb_progress_sink t_sink;

void fb_progress_set_sink(const fb_progress_sink *sink)
{
    t_sink = sink ? *sink : (fb_progress_sink){0};
    fb_scope s = fb_scope_get();
    s.progress = sink ? &t_sink : NULL;
    fb_scope_set(s);
}

static void emit(const fb_progress *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void emit(const fb_progress *p, const char *fmt, ...)
{
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (p->sink.write) p->sink.write(text, p->sink.user);
}

void fb_format_rate(double r, const char *unit, char *out, int size)
{
    const char *pre = r >= 1e9 ? "G" : r >= 1e6 ? "M" : r >= 1e3 ? "k" : "";
    double v = r >= 1e9 ? r * 1e-9 : r >= 1e6 ? r * 1e-6 : r >= 1e3 ? r * 1e-3 : r;
    snprintf(out, (size_t)size, "%.3g %s%s/s", v, pre, unit);
}

static void format_time(double s, char *out, size_t size)
{
    if (s >= 7200)
        snprintf(out, size, "%.1f h", s / 3600);
    else if (s >= 120)
        snprintf(out, size, "%.0f min", s / 60);
    else
        snprintf(out, size, "%.0f s", s);
}

static void draw(fb_progress *p, bool final)
{
    uint64_t done = atomic_load(&p->done), total = atomic_load(&p->total);
    double now = fb_now(), el = now - p->start;
    if (total == 0) return;
    double f = (double)done / (double)total;
    if (f > 1) f = 1;
    /* The time left from the rate so far: for units of even cost (pixels, points), not for steps, whose costs differ
     * (a benchmark's generators: the estimate would grow fourfold as the slow ones come); none before a rate. */
    char rate[48] = "", left[48] = "", time[32], detail[96];
    double r = el > 0 ? (double)done / el : 0, shown = p->scale > 0 ? p->scale : 1.0;
    if (!p->steps) fb_format_rate(r * shown, p->unit, rate, sizeof rate);
    if (r > 0 && !p->steps) {
        format_time((double)(total - (done < total ? done : total)) / r, time, sizeof time);
        snprintf(left, sizeof left, p->tty ? "  %s left" : ", about %s left", time);
    }
    format_time(el, time, sizeof time);
    pthread_mutex_lock(&p->mu);
    snprintf(detail, sizeof detail, "%s", p->detail);
    pthread_mutex_unlock(&p->mu);
    if (!p->tty) {
        if (p->steps)
            emit(p, "fractalbake: %s: %llu of %llu%s%s, %s so far\n", p->label, (unsigned long long)done,
                 (unsigned long long)total, detail[0] ? ": " : "", detail, time);
        else
            emit(p, "fractalbake: %s: %.1f%% (%.4g of %.4g %s, %s, %s so far%s)\n", p->label, 100 * f,
                 (double)done * shown, (double)total * shown, p->unit, rate, time, left);
        return;
    }
    (void) final;
    int w = 30, fill = (int)(f * w);
    char bar[64];
    for (int i = 0; i < w; i++) bar[i] = i < fill ? '#' : '.';
    bar[w] = 0;
    if (p->steps)
        emit(p, "\r%s [%s] %llu of %llu  %s so far  %-40.40s", p->label, bar, (unsigned long long)done,
             (unsigned long long)total, time, detail);
    else
        emit(p, "\r%s [%s] %3d%%  %s%s   ", p->label, bar, (int)(100 * f), rate, left);
    p->drawn = true;
}

static void *ticker(void *arg)
{
    fb_progress *p = arg;
    while (!atomic_load(&p->stop)) {
        struct timespec ts = {0, 50 * 1000 * 1000};
        nanosleep(&ts, NULL);
        double now = fb_now(), el = now - p->start;
        if (p->tty) {
            /* five times a second once the work has lasted half a second */
            if (el >= 0.5 && now - p->last_line >= 0.2) {
                p->last_line = now;
                draw(p, false);
            }
        } else if (el >= 10.0 && (p->last_line == 0 || now - p->last_line >= 60.0)) {
            p->last_line = now;
            draw(p, false);
        }
    }
    return NULL;
}

static void start(fb_progress *p, bool enabled, const char *label, const char *unit, bool steps)
{
    memset(p, 0, sizeof *p);
    const fb_progress_sink *sink = fb_scope_get().progress;
    if (sink) p->sink = *sink;
    p->tty = p->sink.terminal;
    p->enabled = enabled && (p->sink.write || p->sink.poll);
    p->steps = steps;
    p->start = fb_now();
    p->label = label;
    p->unit = unit;
    pthread_mutex_init(&p->mu, NULL);
    if (p->enabled && p->sink.write) p->running = pthread_create(&p->thread, NULL, ticker, p) == 0;
}

void fb_progress_init(fb_progress *p, bool enabled, const char *label, const char *unit)
{
    start(p, enabled, label, unit, false);
}

void fb_progress_init_steps(fb_progress *p, bool enabled, const char *label)
{
    start(p, enabled, label, "", true);
}

void fb_progress_update(fb_progress *p, uint64_t done, uint64_t total)
{
    atomic_store(&p->total, total);
    atomic_store(&p->done, done);
}

void fb_progress_set_scale(fb_progress *p, double per)
{
    p->scale = per > 0 ? 1.0 / per : 1.0;
}

void fb_progress_add(fb_progress *p, uint64_t n)
{
    atomic_fetch_add(&p->done, n);
}

void fb_progress_detail(fb_progress *p, const char *text)
{
    pthread_mutex_lock(&p->mu);
    snprintf(p->detail, sizeof p->detail, "%s", text);
    pthread_mutex_unlock(&p->mu);
}

bool fb_progress_poll(fb_progress *p)
{
    if (!p->enabled || !p->sink.poll) return false;
    uint64_t done = atomic_load(&p->done), total = atomic_load(&p->total);
    double f = total ? (double)done / (double)total : 0;
    return p->sink.poll(f > 1 ? 1 : f, p->sink.user) != 0;
}

void fb_progress_finish(fb_progress *p)
{
    if (p->running) {
        atomic_store(&p->stop, true);
        pthread_join(p->thread, NULL);
        p->running = false;
    }
    if (p->drawn && p->tty) {
        emit(p, "\r%*s\r", 110, "");
    }
    p->drawn = false;
    pthread_mutex_destroy(&p->mu);
    p->enabled = false;
}
