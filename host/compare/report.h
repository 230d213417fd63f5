/*
 * compare's report for people and for CI systems: one self-contained HTML page (every picture
 * inside it as a PNG data URI, no script or style from elsewhere) and a JUnit XML file.
 */
#ifndef FB_REPORT_H
#define FB_REPORT_H

#include "compare.h"

#include <stddef.h>
#include <stdint.h>

typedef struct fb_report_image {
    const char *label; /* "reference", "test", "|A - B|", "FLIP" */
    uint8_t *png;      /* PNG bytes (malloc'd) */
    size_t size;
    int width, height;
} fb_report_image;

typedef struct fb_report_row { /* one line of a layer's statistics */
    char name[128], stats[400], why[200];
    fb_verdict verdict;
} fb_report_row;

typedef struct fb_report_layer {
    char name[128];
    fb_verdict verdict;
    fb_report_image img[4];
    int nimg;
    fb_report_row *rows;
    int nrows;
} fb_report_layer;

typedef struct fb_report {
    const char *a, *b, *reason;
    fb_verdict verdict;
    int width, height, shown_width, shown_height; /* the pictures may be reduced */
    fb_report_layer *layers;                      /* failing first, then warning, then passing */
    int nlayers;
    char **scene_diffs; /* "layers.sky.octaves: 6 in A, 5 in B" */
    int ndiffs;
    const char *scene_note; /* why no scene keys are listed (NULL: they were compared) */
} fb_report;

/* Writes the page through the output transaction. */
fb_result fb_report_html(const char *path, const fb_report *r);

/* The keys of two stored scenes (JSON text, either may be NULL) whose values differ, as lines. */
fb_result fb_report_scene_diff(const char *a, const char *b, char ***lines, int *n);

/* One test case per (channel or FLIP layer, threshold): name, whether it failed and why. */
typedef struct fb_junit_case {
    char classname[128], name[200], message[300];
    bool failed, warned;
} fb_junit_case;

fb_result fb_report_junit(const char *path, const char *suite, const fb_junit_case *cases, int n, double seconds);

#endif
