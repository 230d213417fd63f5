#include "progress.h"

#include "fb.h"

#include <stdio.h>
#include <unistd.h>

void fb_progress_init(fb_progress *p, bool enabled, const char *label, const char *unit)
{
    p->tty = isatty(STDERR_FILENO);
    p->enabled = enabled;
    p->drawn = false;
    p->start = fb_now();
    p->last = 0;
    p->label = label;
    p->unit = unit;
}

void fb_progress_update(fb_progress *p, uint64_t done, uint64_t total)
{
    if (!p->enabled || total == 0) return;
    double now = fb_now(), el = now - p->start;
    /* A log (stderr not a terminal) gets a line after 10 s and then every minute: a long run is never
     * silent, a short one leaves the log clean. */
    if (p->tty ? el < 1.0 || now - p->last < 0.1 : el < 10.0 || (p->last > 0 && now - p->last < 60.0)) return;
    p->last = now;
    double f = (double)done / (double)total;
    if (!p->tty) {
        double rate = (double)done / el, eta = rate > 0 ? (double)(total - done) / rate : 0;
        fprintf(stderr, "fractalbake: %s: %.1f%% (%.4g of %.4g %s, %.4g M%s/s, %.0f s so far, about %.3g %s left)\n",
                p->label, 100 * f, (double)done, (double)total, p->unit, rate * 1e-6, p->unit, el,
                eta > 7200  ? eta / 3600
                : eta > 120 ? eta / 60
                            : eta,
                eta > 7200  ? "h"
                : eta > 120 ? "min"
                            : "s");
        fflush(stderr);
        return;
    }
    int w = 30, fill = (int)(f * w);
    char bar[64];
    for (int i = 0; i < w; i++) bar[i] = i < fill ? '#' : '.';
    bar[w] = 0;
    double rate = el > 0 ? (double)done / el : 0;
    double eta = rate > 0 ? (double)(total - done) / rate : 0;
    fprintf(stderr, "\r%s [%s] %3d%%  %.1f M%s/s  eta %.0fs  ", p->label, bar, (int)(100 * f), rate * 1e-6, p->unit,
            eta);
    fflush(stderr);
    p->drawn = true;
}

void fb_progress_finish(fb_progress *p)
{
    if (p->drawn && p->tty) {
        fprintf(stderr, "\r%*s\r", 100, "");
        fflush(stderr);
    }
    p->drawn = false;
}
