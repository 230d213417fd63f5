/*
 * Text inputs. See textin.h.
 */
#include "textin.h"

#include "output.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static fb_result open_stdin(const char *what, FILE **out)
{
    static bool taken; /* standard input, once: a second reader would find it empty */
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

/* Opens path (never blocking on a FIFO without a writer) if its kind is a regular file, or a FIFO
 * where `fifo` allows one. */
static fb_result open_input(const char *path, const char *what, bool fifo, FILE **out)
{
    *out = NULL;
    if (!strcmp(path, "-")) return open_stdin(what, out);
    /* O_NONBLOCK: a FIFO with no writer must not block the open (read, it then ends at once) */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return fb_fail(FB_ERR_INPUT, "%s: cannot open %s: %s", path, what, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int err = errno;
        close(fd);
        return fb_fail(FB_ERR_INPUT, "%s: cannot open %s: %s", path, what, strerror(err));
    }
    if (!S_ISREG(st.st_mode) && !(S_ISFIFO(st.st_mode) && fifo)) {
        close(fd);
        if (S_ISFIFO(st.st_mode))
            return fb_fail(FB_ERR_INPUT,
                           "%s: is a FIFO, which cannot be read by offsets (expected the %s file; - reads "
                           "standard input)",
                           path, what);
        return fb_fail(FB_ERR_INPUT, "%s: is %s%s (expected the %s file)", path, fb_file_kind(st.st_mode),
                       S_ISDIR(st.st_mode) ? "" : ", not a regular file or a pipe", what);
    }
    fb_result rc = fb_input_note(path, what, fd); /* no output of the run may replace it */
    if (rc) {
        close(fd);
        return rc;
    }
    FILE *f = NULL;
    if (fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK) != 0 || !(f = fdopen(fd, "rb"))) {
        int err = errno;
        close(fd);
        return fb_fail(FB_ERR_INPUT, "%s: cannot open %s: %s", path, what, strerror(err));
    }
    *out = f;
    return FB_OK;
}

fb_result fb_input_open(const char *path, const char *what, FILE **out)
{
    return open_input(path, what, true, out);
}

fb_result fb_input_open_seekable(const char *path, const char *what, FILE **out)
{
    return open_input(path, what, false, out);
}

bool fb_input_is_fifo(const char *path, FILE *f)
{
    struct stat st;
    return strcmp(path, "-") && fstat(fileno(f), &st) == 0 && S_ISFIFO(st.st_mode);
}

fb_result fb_input_fifo_empty(const char *path, const char *what)
{
    return fb_fail(FB_ERR_INPUT, "%s: is a FIFO with nothing written to it (expected the %s file)", path, what);
}

fb_result fb_input_slurp(const char *path, const char *what, size_t limit, char **text, size_t *len)
{
    *text = NULL;
    *len = 0;
    FILE *f = NULL;
    fb_result rc = fb_input_open(path, what, &f);
    if (rc) return rc;
    char *buf = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (n + 4096 + 1 > cap) {
            size_t grown = cap ? 2 * cap : 65536;
            char *t = n <= limit ? realloc(buf, grown) : NULL;
            if (!t) {
                if (n <= limit) rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory reading the %s file", path, what);
                break;
            }
            buf = t;
            cap = grown;
        }
        size_t got = fread(buf + n, 1, 4096, f);
        n += got;
        if (got < 4096) break;
    }
    if (!rc && ferror(f)) rc = fb_fail(FB_ERR_INPUT, "%s: cannot read the %s file: %s", path, what, strerror(errno));
    if (!rc && n > limit)
        rc = fb_fail(FB_ERR_INPUT, "%s: larger than %zu MiB (expected the %s file)", path, limit >> 20, what);
    if (!rc && n == 0 && fb_input_is_fifo(path, f)) rc = fb_input_fifo_empty(path, what);
    fclose(f);
    if (rc) {
        free(buf);
        return rc;
    }
    buf[n] = 0;
    *text = buf;
    *len = n;
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

bool fb_text_int(const char *s, long long lo, long long hi, const char **end, long long *out)
{
    const char *p = s;
    if (*p == '-' || *p == '+') p++;
    if (*p < '0' || *p > '9') return false;
    errno = 0;
    char *e;
    long long v = strtoll(s, &e, 10);
    if (errno == ERANGE || v < lo || v > hi || (!end && *e)) return false;
    if (end) *end = e;
    *out = v;
    return true;
}

bool fb_text_utf8(const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    while (*p) {
        int n = *p < 0x80                           ? 0
                : (*p & 0xE0) == 0xC0 && *p >= 0xC2 ? 1
                : (*p & 0xF0) == 0xE0               ? 2
                : (*p & 0xF8) == 0xF0 && *p <= 0xF4 ? 3
                                                    : -1;
        if (n < 0) return false;
        uint32_t c = n == 0 ? *p : *p & (0x3Fu >> n);
        for (int k = 1; k <= n; k++) {
            if ((p[k] & 0xC0) != 0x80) return false;
            c = c << 6 | (p[k] & 0x3Fu);
        }
        if ((n == 2 && (c < 0x800 || (c >= 0xD800 && c <= 0xDFFF))) || (n == 3 && (c < 0x10000 || c > 0x10FFFF)))
            return false;
        p += n + 1;
    }
    return true;
}

bool fb_text_starts_number(const char *s)
{
    char *end;
    (void)strtod(s, &end); /* whatever the value: 1e400 and 0x1p99999 begin like numbers */
    return end > s;
}

fb_result fb_lines_open(fb_lines *l, const char *path, const char *what)
{
    memset(l, 0, sizeof *l);
    l->path = path;
    l->what = what;
    fb_result rc = fb_input_open(path, what, &l->f);
    l->fifo = !rc && fb_input_is_fifo(path, l->f);
    return rc;
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
            if (errno == ENOMEM || errno == EOVERFLOW) {
                fb_fail(FB_ERR_INPUT, "%s:%d: a line too long to hold in memory: not a %s file", l->path, l->lineno + 1,
                        l->what);
                return -1;
            }
            if (!ferror(l->f) && l->lineno == 0 && l->fifo) {
                fb_input_fifo_empty(l->path, l->what);
                return -1;
            }
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
        if (l->contents++ == 0 && !fb_text_starts_number(fields[0])) { /* a header, by its form */
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
