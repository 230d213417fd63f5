#define _GNU_SOURCE /* O_TMPFILE */
/*
 * The output transaction. See output.h.
 */
#include "output.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

enum { FREE = 0, RESERVED = 1, TAKEN = 2 };

typedef struct entry {
    volatile sig_atomic_t live; /* the temporary file exists: the signal handler removes it */
    int state;
    int fd;     /* RESERVED: the open temporary file, until taken */
    int keepfd; /* "-" (standard output): the anonymous temporary file, copied out at the commit */
    char what[32];
    char path[PATH_MAX]; /* as the user gave it */
    char key[PATH_MAX];  /* the folder resolved, then the name: two spellings of one file compare equal */
    char tmp[PATH_MAX];
} entry;

static entry g_out[FB_MAX_OUTPUTS];
static volatile sig_atomic_t g_count; /* entries in use are below it */
/* what the last commit put in place (fb_outputs_written) */
static struct {
    char path[PATH_MAX], what[32];
    uint64_t bytes;
} g_done[FB_MAX_OUTPUTS];
static int g_ndone;
static int g_depth;
static pthread_mutex_t g_mu = PTHREAD_MUTEX_INITIALIZER;

static const char *kind_of(mode_t m)
{
    return S_ISDIR(m)    ? "a directory"
           : S_ISLNK(m)  ? "a symbolic link"
           : S_ISCHR(m)  ? "a character device"
           : S_ISBLK(m)  ? "a block device"
           : S_ISFIFO(m) ? "a FIFO"
           : S_ISSOCK(m) ? "a socket"
                         : "not a regular file";
}

/* The folder and the name of path: "a/b.exr" -> "a", "b.exr"; "b.exr" -> ".", "b.exr". */
static void split(const char *path, char *dir, size_t dsize, const char **base)
{
    const char *slash = strrchr(path, '/');
    if (!slash) {
        snprintf(dir, dsize, ".");
        *base = path;
    } else {
        snprintf(dir, dsize, "%.*s", slash == path ? 1 : (int)(slash - path), path);
        *base = slash + 1;
    }
}

static uint64_t random64(void)
{
    uint64_t r = 0;
    if (getrandom(&r, sizeof r, 0) != (ssize_t)sizeof r) { /* no entropy source: still unique, less secret */
        static uint64_t n;
        r = ((uint64_t)getpid() << 32) ^ (uint64_t)(fb_now() * 1e9) ^ (++n * 0x9E3779B97F4A7C15ull);
    }
    return r;
}

static entry *find(const char *key)
{
    for (int i = 0; i < g_count; i++)
        if (g_out[i].state != FREE && !strcmp(g_out[i].key, key)) return &g_out[i];
    return NULL;
}

static void drop(entry *e)
{
    if (e->fd >= 0) close(e->fd);
    if (e->keepfd >= 0) close(e->keepfd);
    e->fd = e->keepfd = -1;
    if (e->live) unlink(e->tmp);
    e->live = 0;
    e->state = FREE;
}

/* The folder resolved, then the name: two spellings of one target give one key. False when the
 * folder does not resolve (errno says why). */
static bool key_of(const char *path, char *key)
{
    if (!strcmp(path, "-")) { /* standard output */
        strcpy(key, "-");
        return true;
    }
    char dir[PATH_MAX], real[PATH_MAX];
    const char *base;
    split(path, dir, sizeof dir, &base);
    if (!realpath(dir, real)) return false;
    snprintf(key, PATH_MAX, "%s/%s", strcmp(real, "/") ? real : "", base);
    return true;
}

static entry *free_entry(void)
{
    for (int i = 0; i < g_count; i++)
        if (g_out[i].state == FREE && !g_out[i].live) return &g_out[i];
    return g_count < FB_MAX_OUTPUTS ? &g_out[g_count] : NULL;
}

/* "-": standard output. The data goes to an anonymous temporary file (gone when closed: nothing for
 * a signal to leave behind) and is copied to standard output at the commit, so that a failed run
 * writes nothing there either. Refused when standard output is a terminal. Called locked. */
static fb_result reserve_stdout(const char *what, entry **out)
{
    if (find("-"))
        return fb_fail(FB_ERR_USAGE, "-: standard output named for two outputs (the %s and the %s)", find("-")->what,
                       what);
    if (isatty(STDOUT_FILENO))
        return fb_fail(FB_ERR_USAGE, "-: the %s would go to a terminal: redirect standard output to a file or a pipe",
                       what);
    entry *e = free_entry();
    if (!e) return fb_fail(FB_ERR_USAGE, "-: more than %d outputs", FB_MAX_OUTPUTS);
    const char *tmpdir = getenv("TMPDIR");
    int fd = open(tmpdir && *tmpdir ? tmpdir : "/tmp", O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd < 0) {
        char tmp[PATH_MAX];
        snprintf(tmp, sizeof tmp, "%s/fractalbake-stdout.XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
        if ((fd = mkstemp(tmp)) >= 0) unlink(tmp);
    }
    int keep = fd >= 0 ? dup(fd) : -1;
    if (keep < 0) {
        int err = errno;
        if (fd >= 0) close(fd);
        return fb_fail(FB_ERR_IO, "-: cannot create a temporary file for the %s: %s", what, strerror(err));
    }
    *e = (entry){.live = 0, .state = RESERVED, .fd = fd, .keepfd = keep};
    snprintf(e->what, sizeof e->what, "%s", what);
    snprintf(e->path, sizeof e->path, "-");
    snprintf(e->key, sizeof e->key, "-");
    if (e == &g_out[g_count]) g_count = g_count + 1;
    *out = e;
    return FB_OK;
}

/* Copies the standard-output entry's file to standard output. */
static fb_result copy_to_stdout(entry *e)
{
    char buf[1 << 16];
    off_t at = 0;
    for (;;) {
        ssize_t n = pread(e->keepfd, buf, sizeof buf, at);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return fb_fail(FB_ERR_IO, "-: cannot read back the %s: %s", e->what, strerror(errno));
        if (n == 0) return FB_OK;
        for (ssize_t done = 0; done < n;) {
            ssize_t w = write(STDOUT_FILENO, buf + done, (size_t)(n - done));
            if (w < 0 && errno == EINTR) continue;
            if (w <= 0)
                return fb_fail(FB_ERR_IO, "-: cannot write the %s to standard output: %s", e->what, strerror(errno));
            done += w;
        }
        at += n;
    }
}

/* Resolves path to its key; checks the target; creates the temporary file. Called locked. */
static fb_result reserve_locked(const char *path, const char *what, entry **out)
{
    char dir[PATH_MAX], key[PATH_MAX];
    const char *base;
    if (!path || !*path) return fb_fail(FB_ERR_USAGE, "%s: an empty file name", what);
    if (!strcmp(path, "-")) return reserve_stdout(what, out);
    if (strlen(path) >= PATH_MAX - 64) return fb_fail(FB_ERR_USAGE, "%s: path too long for the %s", path, what);
    split(path, dir, sizeof dir, &base);
    if (!*base || !strcmp(base, ".") || !strcmp(base, ".."))
        return fb_fail(FB_ERR_USAGE, "%s: names a folder, not a file for the %s", path, what);
    if (!key_of(path, key))
        return fb_fail(FB_ERR_USAGE, "%s: cannot create the %s: folder %s: %s", path, what, dir, strerror(errno));
    entry *dup = find(key);
    if (dup)
        return fb_fail(FB_ERR_USAGE, "%s: named as the %s and as the %s: two outputs cannot share one path", path,
                       dup->what, what);
    struct stat st;
    if (lstat(path, &st) == 0 && !S_ISREG(st.st_mode))
        return fb_fail(FB_ERR_USAGE, "%s: exists and is %s: the %s replaces only regular files", path,
                       kind_of(st.st_mode), what);
    entry *e = free_entry();
    if (!e) return fb_fail(FB_ERR_USAGE, "%s: more than %d outputs", path, FB_MAX_OUTPUTS);
    int fd = -1;
    for (int tries = 0; tries < 16 && fd < 0; tries++) {
        char tmp[PATH_MAX];
        snprintf(tmp, sizeof tmp, "%s/.%.180s.%016llx.tmp", dir, base, (unsigned long long)random64());
        /* The name is written before the file exists, so that a signal between the two removes
         * nothing else: unlink of a name that does not exist yet is harmless. */
        memcpy(e->tmp, tmp, sizeof tmp);
        fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0666);
        if (fd < 0 && errno != EEXIST) break;
    }
    if (fd < 0) {
        int err = errno;
        return fb_fail(err == EACCES || err == EROFS || err == ENOENT || err == ENOTDIR ? FB_ERR_USAGE : FB_ERR_IO,
                       "%s: cannot create the %s: %s", path, what, strerror(err));
    }
    e->fd = fd;
    e->keepfd = -1;
    e->state = RESERVED;
    snprintf(e->what, sizeof e->what, "%s", what);
    snprintf(e->path, sizeof e->path, "%s", path);
    memcpy(e->key, key, sizeof key);
    e->live = 1;
    if (e == &g_out[g_count]) g_count = g_count + 1;
    *out = e;
    return FB_OK;
}

void fb_outputs_begin(void)
{
    pthread_mutex_lock(&g_mu);
    if (g_depth++ == 0) g_ndone = 0;
    pthread_mutex_unlock(&g_mu);
}

static void abort_locked(void)
{
    for (int i = 0; i < g_count; i++) drop(&g_out[i]);
    g_count = 0;
}

fb_result fb_outputs_end(fb_result rc)
{
    pthread_mutex_lock(&g_mu);
    if (g_depth > 0) g_depth--;
    if (rc) {
        abort_locked();
    } else if (g_depth == 0) {
        for (int i = 0; i < g_count && !rc; i++)
            if (g_out[i].state == RESERVED)
                rc =
                    fb_fail(FB_ERR_INTERNAL, "%s: the %s was reserved but never written", g_out[i].path, g_out[i].what);
        /* Checked again just before the renames: a target that became a non-regular file since. */
        struct stat st;
        for (int i = 0; i < g_count && !rc; i++)
            if (g_out[i].state == TAKEN && g_out[i].keepfd < 0 && lstat(g_out[i].path, &st) == 0 &&
                !S_ISREG(st.st_mode))
                rc = fb_fail(FB_ERR_USAGE, "%s: exists and is %s: the %s replaces only regular files", g_out[i].path,
                             kind_of(st.st_mode), g_out[i].what);
        for (int i = 0; i < g_count && !rc; i++) {
            entry *e = &g_out[i];
            if (e->state != TAKEN) continue;
            struct stat fs;
            uint64_t bytes = e->keepfd >= 0 ? (fstat(e->keepfd, &fs) == 0 ? (uint64_t)fs.st_size : 0)
                                            : (lstat(e->tmp, &fs) == 0 ? (uint64_t)fs.st_size : 0);
            if (e->keepfd >= 0) {
                if ((rc = copy_to_stdout(e))) break;
            } else if (rename(e->tmp, e->path) != 0) {
                rc = fb_fail(FB_ERR_IO, "%s: cannot move the %s into place: %s", e->path, e->what, strerror(errno));
                break;
            }
            e->live = 0; /* renamed: the handler must not remove it any more */
            e->state = FREE;
            snprintf(g_done[g_ndone].path, sizeof g_done[0].path, "%s", e->path);
            snprintf(g_done[g_ndone].what, sizeof g_done[0].what, "%s", e->what);
            g_done[g_ndone++].bytes = bytes;
        }
        abort_locked(); /* after a failed rename: the rest are removed */
    }
    pthread_mutex_unlock(&g_mu);
    return rc;
}

fb_result fb_output_reserve(const char *path, const char *what)
{
    entry *e;
    pthread_mutex_lock(&g_mu);
    fb_result rc = reserve_locked(path, what, &e);
    pthread_mutex_unlock(&g_mu);
    return rc;
}

fb_result fb_output_open(const char *path, const char *what, int *fd)
{
    char key[PATH_MAX];
    fb_result rc = FB_OK;
    entry *e = NULL;
    pthread_mutex_lock(&g_mu);
    if (path && *path && key_of(path, key) && (e = find(key))) {
        if (e->state != RESERVED)
            rc = fb_fail(FB_ERR_USAGE, "%s: named as the %s and as the %s: two outputs cannot share one path", path,
                         e->what, what);
    } else {
        rc = reserve_locked(path, what, &e);
    }
    if (!rc) {
        *fd = e->fd;
        e->fd = -1;
        e->state = TAKEN;
    }
    pthread_mutex_unlock(&g_mu);
    return rc;
}

fb_result fb_output_fopen(const char *path, const char *what, void **file)
{
    int fd = -1;
    fb_result rc = fb_output_open(path, what, &fd);
    if (rc) return rc;
    FILE *f = fdopen(fd, "wb");
    if (!f) {
        close(fd);
        return fb_fail(FB_ERR_NOMEM, "%s: %s: %s", what, path, strerror(errno));
    }
    *file = f;
    return FB_OK;
}

fb_result fb_output_spool(const char *path, void **file)
{
    char dir[PATH_MAX];
    const char *base;
    split(path, dir, sizeof dir, &base);
    int fd = open(dir, O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) { /* no O_TMPFILE here */
        char tmp[PATH_MAX];
        snprintf(tmp, sizeof tmp, "%s/.%.180s.spool.XXXXXX", dir, base);
        fd = mkstemp(tmp);
        if (fd >= 0) unlink(tmp);
    }
    FILE *f = fd >= 0 ? fdopen(fd, "w+b") : NULL;
    if (!f) {
        int err = errno;
        if (fd >= 0) close(fd);
        return fb_fail(FB_ERR_IO, "%s: cannot create a spool file beside it: %s", path, strerror(err));
    }
    *file = f;
    return FB_OK;
}

fb_result fb_output_done(const char *path, fb_result rc)
{
    if (rc) {
        fb_output_discard(path);
        return rc;
    }
    char key[PATH_MAX];
    pthread_mutex_lock(&g_mu);
    entry *e = key_of(path, key) ? find(key) : NULL;
    if (!e || e->state != TAKEN) {
        rc = fb_fail(FB_ERR_INTERNAL, "%s: finished but never opened as an output", path);
    } else if (g_depth == 0) {
        struct stat st;
        if (e->keepfd >= 0)
            rc = copy_to_stdout(e);
        else if (lstat(e->path, &st) == 0 && !S_ISREG(st.st_mode))
            rc = fb_fail(FB_ERR_USAGE, "%s: exists and is %s: the %s replaces only regular files", e->path,
                         kind_of(st.st_mode), e->what);
        else if (rename(e->tmp, e->path) != 0)
            rc = fb_fail(FB_ERR_IO, "%s: cannot move the %s into place: %s", e->path, e->what, strerror(errno));
        else
            e->live = 0;
        drop(e);
    }
    pthread_mutex_unlock(&g_mu);
    return rc;
}

void fb_output_discard(const char *path)
{
    char key[PATH_MAX];
    pthread_mutex_lock(&g_mu);
    entry *e = path && key_of(path, key) ? find(key) : NULL;
    if (e) drop(e);
    pthread_mutex_unlock(&g_mu);
}

void fb_outputs_unlink_all(void)
{
    for (int i = 0; i < g_count; i++)
        if (g_out[i].live) unlink(g_out[i].tmp);
}

fb_result fb_output_format(const char *flag, const char *path, const char *ext)
{
    static const char *const images[] = {".exr", ".png", ".jpg",  ".jpeg", ".tif", ".tiff", ".bmp",
                                         ".gif", ".hdr", ".webp", ".tga",  ".ppm", ".dpx"};
    const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash) || !strcasecmp(dot, ext)) return FB_OK;
    for (size_t i = 0; i < sizeof images / sizeof images[0]; i++)
        if (!strcasecmp(dot, images[i]))
            return fb_fail(FB_ERR_USAGE, "%s %s: this writes %s (%s), not %s: name the file %s", flag, path,
                           !strcmp(ext, ".exr") ? "OpenEXR" : "PNG", ext, dot, ext);
    return FB_OK;
}

int fb_outputs_written(const char **paths, const char **whats, uint64_t *bytes, int max)
{
    int n = 0;
    pthread_mutex_lock(&g_mu);
    for (; n < g_ndone && n < max; n++) {
        paths[n] = g_done[n].path;
        whats[n] = g_done[n].what;
        bytes[n] = g_done[n].bytes;
    }
    pthread_mutex_unlock(&g_mu);
    return n;
}
