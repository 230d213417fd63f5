/* Progress on stderr: a bar redrawn every 0.1 s when stderr is a terminal and the work has lasted a
 * second; for a log, a line after 10 s and then one a minute (rate and time left), so that short
 * runs and logs stay clean and long ones are never silent. */
#ifndef FB_PROGRESS_H
#define FB_PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

typedef struct fb_progress {
    bool enabled, drawn, tty;
    double start, last;
    const char *label;
    const char *unit;
} fb_progress;

void fb_progress_init(fb_progress *p, bool enabled, const char *label, const char *unit);
/* done of total work units (pixels, points...) */
void fb_progress_update(fb_progress *p, uint64_t done, uint64_t total);
void fb_progress_finish(fb_progress *p);

#endif
