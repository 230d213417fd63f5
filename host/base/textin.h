/*
 * Reading the text files users give (survey points, centres, constraint points and regions, CSV
 * profiles): one rule for every reader.
 *
 * - The file must be a readable file: a missing or unreadable path, a directory, or a read error is
 *   bad input (FB_ERR_INPUT, exit 2) naming the path.
 * - A line's content ends at '#' (a comment); blank lines are skipped. Fields are separated by
 *   commas and/or blanks; two commas in a row make an empty field.
 * - The first content line is a header when its first field does not begin like a number ("x,y,z",
 *   "easting northing height"): whatever strtod can start reading (a sign, digits, a point, "0x",
 *   "inf", "nan") makes the line data, even when its value overflows ("1e400", "0x1p99999") or the
 *   rest is not a number, so that the error is reported like anywhere else, never swallowed.
 * - Regular files and pipes are read ("-" is standard input; a FIFO or a shell's <(...) too), and
 *   nothing waits on a FIFO that has no writer: it reads as nothing, which is bad input naming it.
 *   Devices and sockets (/dev/zero) are refused. A line too long for memory is bad input too.
 *
 * The same rule holds for every file a run reads (scenes, .ifs and .flame files, bench rows, EXR and
 * PNG images), with one message form, "PATH: is WHAT IT IS ... (expected the ROLE file)":
 * - a device, socket or directory: "is a character device, not a regular file or a pipe";
 * - a FIFO where the reader seeks (an EXR is read by offsets): "is a FIFO, which cannot be read by
 *   offsets" (those readers take "-" for standard input instead);
 * - a FIFO that gives nothing (no writer, or an empty pipe): "is a FIFO with nothing written to it".
 *
 * Every file opened here is noted as an input of the run (fb_input_note, output.h): no output of the
 * run may then replace it.
 */
#ifndef FB_TEXTIN_H
#define FB_TEXTIN_H

#include "fb.h"

#include <stdbool.h>
#include <stdio.h>

/* fopen(path, "rb") for an input (never blocking on a FIFO without a writer), refusing a directory,
 * a device or a socket; failures logged as FB_ERR_INPUT.
 * "-" is standard input, which one run reads once (a second "-" is FB_ERR_USAGE). */
fb_result fb_input_open(const char *path, const char *what, FILE **out);

/* fb_input_open for a reader that seeks or reads a file twice: a FIFO is refused too. */
fb_result fb_input_open_seekable(const char *path, const char *what, FILE **out);

/* The whole of an input (fb_input_open's rule) as *len bytes and a NUL, malloc'ed into *text; larger
 * than limit bytes, or a FIFO that gives nothing, is bad input naming it. */
fb_result fb_input_slurp(const char *path, const char *what, size_t limit, char **text, size_t *len);

/* Whether f, opened from path, is a FIFO or pipe that is not standard input. */
bool fb_input_is_fifo(const char *path, FILE *f);

/* Logs "PATH: is a FIFO with nothing written to it" for a reader that found f empty. */
fb_result fb_input_fifo_empty(const char *path, const char *what);

typedef struct fb_lines {
    FILE *f;
    const char *path, *what;
    char *buf;
    size_t cap;
    int lineno;   /* of the line last returned */
    int contents; /* content lines seen, the header included */
    bool header;  /* the first content line was a header */
    bool fifo;    /* a FIFO or pipe: empty means no writer */
} fb_lines;

/* Opens path for fb_lines_next; `what` names the file's role in messages ("points", "centres"). */
fb_result fb_lines_open(fb_lines *l, const char *path, const char *what);

/* The next data line split into at most max fields (a line with more gives *nf = max + 1). Returns 1
 * with a line, 0 at the end, or -1 on a read error (logged). The header line is skipped. */
int fb_lines_next(fb_lines *l, char **fields, int max, int *nf);

void fb_lines_close(fb_lines *l);

/* A decimal integer in lo..hi, for metadata: digits with an optional sign, no blanks, no overflow
 * (4294967302 is not 6). end NULL: the whole of s; else *end is set after the digits. */
bool fb_text_int(const char *s, long long lo, long long hi, const char **end, long long *out);

/* Whether s is valid UTF-8 (what a JSON string holds: a value that is not cannot enter a scene). */
bool fb_text_utf8(const char *s);

/* Whether s begins like a number (the header rule above). */
bool fb_text_starts_number(const char *s);

/* A whole field as a finite or infinite double ("nan" and "inf" parse; overflow does not). */
bool fb_text_number(const char *s, double *out);

#endif
