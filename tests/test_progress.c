/*
 * Progress (host/base/progress.c) as a sink sees it: the time left only from a rate of units of even
 * cost, never "?" before there is one, and none for steps of uneven cost (a benchmark's generators,
 * whose estimate grew fourfold as the slow ones came).
 */
#include "progress.h"
#include "testhelp.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

static char g_text[8192];

static void sink_write(const char *text, void *user)
{
    (void)user;
    snprintf(g_text + strlen(g_text), sizeof g_text - strlen(g_text), "%s", text);
}

static void wait_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

/* The text drawn on a terminal sink while `done` of `total` stays still for 0.65 s (the bar is drawn
 * from 0.5 s on, five times a second). */
static void drawn(bool steps, uint64_t done, uint64_t total)
{
    g_text[0] = 0;
    fb_progress_set_sink(&(fb_progress_sink){.terminal = true, .write = sink_write});
    fb_progress p;
    if (steps)
        fb_progress_init_steps(&p, true, "bench");
    else
        fb_progress_init(&p, true, "bake", "pix");
    fb_progress_update(&p, done, total);
    if (steps) fb_progress_detail(&p, "julia");
    wait_ms(650);
    fb_progress_finish(&p);
    fb_progress_set_sink(NULL);
}

int main(void)
{
    drawn(true, 0, 14);
    CHECKF(strstr(g_text, "0 of 14") && strstr(g_text, "so far") && strstr(g_text, "julia"), "%s", g_text);
    CHECKF(!strchr(g_text, '?') && !strstr(g_text, "left"), "steps: no time left, no \"?\": %s", g_text);
    drawn(false, 0, 1000);
    CHECKF(strstr(g_text, "bake [") && !strchr(g_text, '?') && !strstr(g_text, "left"),
           "no rate yet: no time left and no \"?\": %s", g_text);
    drawn(false, 500, 1000); /* half in 0.65 s: about 1 s left */
    CHECKF(strstr(g_text, " 50%") && strstr(g_text, " s left") && !strchr(g_text, '?'), "%s", g_text);
    TEST_REPORT();
}
