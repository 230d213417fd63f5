/*
 * Text inputs. See textin.h.
 */
#include "textin.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
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
    /* O_NONBLOCK: a FIFO with no writer must not block the open (read, it then ends at once: nothing
     * to read); regular files and FIFOs (a shell's <(...)) are read, devices and sockets refused. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return fb_fail(FB_ERR_INPUT, "%s: cannot open %s: %s", path, what, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !(S_ISREG(st.st_mode) || S_ISFIFO(st.st_mode))) {
        int err = errno;
        bool known = err == 0 || !S_ISREG(st.st_mode);
        close(fd);
        if (known && S_ISDIR(st.st_mode))
            return fb_fail(FB_ERR_INPUT, "%s: is a directory (expected the %s file)", path, what);
        if (known)
            return fb_fail(FB_ERR_INPUT, "%s: is %s, not a regular file or a pipe (expected the %s file)", path,
                           S_ISFIFO(st.st_mode)   ? "a FIFO"
                           : S_ISCHR(st.st_mode)  ? "a character device"
                           : S_ISBLK(st.st_mode)  ? "a block device"
                           : S_ISSOCK(st.st_mode) ? "a socket"
                                                  : "not a regular file",
                           what);
        return fb_fail(FB_ERR_INPUT, "%s: cannot open %s: %s", path, what, strerror(err));
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
    struct stat st;
    l->fifo = !rc && fstat(fileno(l->f), &st) == 0 && S_ISFIFO(st.st_mode);
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
                fb_fail(FB_ERR_INPUT, "%s: a FIFO with nothing written to it (no writer): expected the %s file",
                        l->path, l->what);
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
