/*
 * The one way every command reads its argv: a table of flags per command, each naming the field of
 * the command's options struct it fills (offsetof) and how its value is read and checked. The
 * parser gives every command the same spellings (`--flag value`; main() has already turned
 * `--flag=value` into that and `-q` into `--quiet`), the same messages ("--threads: expected an
 * integer in 1..1024, found \"x\"", "--octavs: unknown flag for `fractalbake fbm`; did you mean
 * --octaves?", "--set: missing value") and the same treatment of file arguments.
 */
#ifndef FB_ARGS_H
#define FB_ARGS_H

#include "fb.h"

#include <stddef.h>

/* A flag given several times, or the file arguments, in order (the strings are argv's). */
typedef struct fb_arg_list {
    const char **v;
    int n;
} fb_arg_list;

typedef enum fb_arg_kind {
    FB_ARG_END = 0,  /* ends a table */
    FB_ARG_BOOL,     /* a switch: bool at off set true */
    FB_ARG_STRING,   /* const char * at off */
    FB_ARG_OUTPUT,   /* const char * at off: a file this run writes, its extension checked (ext) */
    FB_ARG_INT,      /* int at off: an integer in lo..hi (decimal, or exponent notation with a whole value) */
    FB_ARG_LIST,     /* fb_arg_list at off: every value of the flag, in order */
    FB_ARG_VALUE,    /* value read by parse(flag, value, field at off) */
    FB_ARG_IGNORED,  /* a switch accepted for uniformity that changes nothing for this command (why: a comment) */
    FB_ARG_DOCUMENT, /* a switch (bool at off) for a document printed on standard output (--json): it claims
                      * standard output (output.h), so that no output "-" goes there too */
} fb_arg_kind;

typedef struct fb_arg {
    fb_arg_kind kind;
    const char *name;  /* "--threads" */
    const char *alias; /* another spelling ("-o", "--failpercent"), or NULL */
    size_t off;        /* offsetof the field in the command's options struct */
    long lo, hi;       /* FB_ARG_INT's range */
    const char *ext;   /* FB_ARG_OUTPUT's extension (".exr") */
    /* FB_ARG_VALUE: reads `value` into `field`; logs one line and returns FB_ERR_USAGE when it is bad */
    fb_result (*parse)(const char *flag, const char *value, void *field);
} fb_arg;

/* What a command's argv may hold. */
typedef struct fb_argspec {
    const fb_arg *const *flags; /* the tables of flags, NULL-terminated (a command's own and shared ones) */
    size_t files_off;           /* fb_arg_list of the arguments that are not flags ("-" is one) */
    int max_files;              /* more are refused with too_many ("%s: info takes one EXR file") */
    const char *too_many;
    /* Flags the command hands on whole (a generator's keys), into the fb_arg_list at pass_off: the
     * flag and its value when arity(data, "octaves") is 1, the flag alone when 0; -1: not one. */
    int (*arity)(const void *data, const char *flag);
    int (*names)(const void *data, const char **out, int max); /* their names, for "did you mean" */
    size_t pass_off;
    /* Another tool's spelling turned into this one's (idiff's -fail as --fail) into buf; NULL when the
     * argument is refused (the error logged). */
    const char *(*rewrite)(const char *arg, char *buf, size_t size);
} fb_argspec;

/* Reads argv into opts as spec says; FB_ERR_USAGE with one line logged on the first bad argument.
 * The lists point into arrays allocated for argc entries: fb_args_free releases them. */
/* command: its name, for messages ("fbm"); data: what the spec's hooks are given. */
fb_result fb_args_parse(const fb_argspec *spec, const char *command, const void *data, int argc, char **argv,
                        void *opts);
void fb_args_free(const fb_argspec *spec, void *opts);

/* The integer reading of FB_ARG_INT, for values read elsewhere (stored attributes). */
bool fb_args_int(const char *s, long lo, long hi, int *out);

#endif
