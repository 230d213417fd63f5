/*
 * Reading the text files users give (survey points, centres, constraint points and regions, CSV
 * profiles): one rule for every reader.
 *
 * - The file must be a readable file: a missing or unreadable path, a directory, or a read error is
 *   bad input (FB_ERR_INPUT, exit 2) naming the path.
 * - A line's content ends at '#' (a comment); blank lines are skipped. Fields are separated by
 *   commas and/or blanks; two commas in a row make an empty field.
 * - The first content line is a header when its first field is not a number (by its form: "x,y,z"
 *   or "easting northing height"), never because the line failed to parse: "10.5,10" on line 1 is
 *   data, and an error there is reported like anywhere else.
 */
#ifndef FB_TEXTIN_H
#define FB_TEXTIN_H

#include "fb.h"

#include <stdbool.h>
#include <stdio.h>

/* fopen(path, "rb") for an input, refusing a directory; failures logged as FB_ERR_INPUT. "-" is
 * standard input, which one run reads once (a second "-" is FB_ERR_USAGE). */
fb_result fb_input_open(const char *path, const char *what, FILE **out);

typedef struct fb_lines {
    FILE *f;
    const char *path, *what;
    char *buf;
    size_t cap;
    int lineno;   /* of the line last returned */
    int contents; /* content lines seen, the header included */
    bool header;  /* the first content line was a header */
} fb_lines;

/* Opens path for fb_lines_next; `what` names the file's role in messages ("points", "centres"). */
fb_result fb_lines_open(fb_lines *l, const char *path, const char *what);

/* The next data line split into at most max fields (a line with more gives *nf = max + 1). Returns 1
 * with a line, 0 at the end, or -1 on a read error (logged). The header line is skipped. */
int fb_lines_next(fb_lines *l, char **fields, int max, int *nf);

void fb_lines_close(fb_lines *l);

/* A whole field as a finite or infinite double ("nan" and "inf" parse; overflow does not). */
bool fb_text_number(const char *s, double *out);

#endif
