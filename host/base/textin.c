/*
 * Text inputs. See textin.h.
 */
#include "textin.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

fb_result fb_input_open(const char *path, const char *what, FILE **out)
{
    *out = NULL;
    if (!strcmp(path, "-")) { /* standard input, once: a second reader would find it empty */
        static bool taken;
        if (taken) return fb_fail(FB_ERR_USAGE, "-: standard input named twice (for the %s too)", what);
        int fd = dup(STDIN_FILENO);
        FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
        if (!f) {
            if (fd >= 0) close(fd);
            return fb_fail(FB_ERR_INPUT, "-: cannot read the %s from standard input: %s", what, strerror(errno));
        }
        taken = true;
        *out = f;
        return FB_OK;
    }
    FILE *f = fopen(path, "rb");
    if (!f) return fb_fail(FB_ERR_INPUT, "%s: cannot open %s: %s", path, what, strerror(errno));
    struct stat st;
    if (fstat(fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
        fclose(f);
        return fb_fail(FB_ERR_INPUT, "%s: is a directory (expected the %s file)", path, what);
    }
    *out = f;
    return FB_OK;
}

bool fb_text_number(const char *s, double *out)
{
    if (!*s) return false;
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return !*end && errno != ERANGE;
}

fb_result fb_lines_open(fb_lines *l, const char *path, const char *what)
{
    memset(l, 0, sizeof *l);
    l->path = path;
    l->what = what;
    return fb_input_open(path, what, &l->f);
}

/* Splits a line into at most `max` fields separated by commas and/or blanks; a comma between two
 * commas gives an empty field. Returns the field count (max + 1 when there are more). */
static int split_fields(char *line, char **f, int max)
{
    int n = 0;
    char *p = line;
    while (*p == ' ' || *p == '\t') p++;
    if (!*p) return 0;
    for (;;) {
        if (n == max) return max + 1;
        f[n++] = p;
        while (*p && *p != ',' && *p != ' ' && *p != '\t') p++;
        char *end = p;
        while (*p == ' ' || *p == '\t') p++;
        bool comma = *p == ',';
        if (comma) p++;
        *end = 0;
        while (*p == ' ' || *p == '\t') p++;
        if (!*p) {
            if (comma) {
                if (n == max) return max + 1;
                f[n++] = p; /* a trailing empty field */
            }
            return n;
        }
    }
}

int fb_lines_next(fb_lines *l, char **fields, int max, int *nf)
{
    for (;;) {
        errno = 0;
        ssize_t len = getline(&l->buf, &l->cap, l->f);
        if (len < 0) {
            if (!ferror(l->f)) return 0;
            fb_fail(FB_ERR_INPUT, "%s: cannot read the %s file: %s", l->path, l->what, strerror(errno ? errno : EIO));
            return -1;
        }
        l->lineno++;
        char *s = l->buf;
        if ((size_t)len != strlen(s)) {
            fb_fail(FB_ERR_INPUT, "%s:%d: a NUL byte: not a text file", l->path, l->lineno);
            return -1;
        }
        s[strcspn(s, "#\r\n")] = 0;
        int n = split_fields(s, fields, max);
        if (n == 0) continue;
        double v;
        if (l->contents++ == 0 && !fb_text_number(fields[0], &v)) { /* a header, by its form */
            l->header = true;
            continue;
        }
        *nf = n;
        return 1;
    }
}

void fb_lines_close(fb_lines *l)
{
    if (l->f) fclose(l->f);
    free(l->buf);
    memset(l, 0, sizeof *l);
}
