#define _GNU_SOURCE /* O_TMPFILE */
/*
 * The output transaction. See output.h.
 */
#include "output.h"

#include <errno.h>
#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <stdatomic.h>
#include <sys/file.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

enum { FREE = 0, RESERVED = 1, TAKEN = 2 };

typedef struct entry {
    volatile sig_atomic_t live; /* the temporary file exists: the signal handler removes it */
    int state;
    int fd;       /* RESERVED: the open temporary file, until taken */
    int keepfd;   /* the temporary file (or standard output's), kept open and locked until dropped */
    bool std;     /* "-": copied to standard output at the commit */
    bool anon;    /* an O_TMPFILE file in the target's folder: linked to a hidden name at the commit */
    uint64_t set; /* the set of outputs it belongs to, named in its hidden temporary file with the pid */
    bool has_id;  /* the target existed when reserved: its device and inode, checked against the inputs */
    dev_t dev;
    ino_t ino;
    char what[32];
    char path[PATH_MAX]; /* as the user gave it */
    char key[PATH_MAX];  /* the folder resolved, then the name: two spellings of one file compare equal */
    char tmp[PATH_MAX];
} entry;

/* The signal hand-off (fb_outputs_signal): IDLE, COMMITTING (a signal waits for the commit's end),
 * DYING (a handler is removing the temporary files; the commit must not start). */
enum { IDLE = 0, COMMITTING = 1, DYING = 2 };

/* The inputs of the run (fb_input_note): no output may name one. */
typedef struct input {
    char *path; /* as the user gave it */
    char *key;  /* resolved: realpath, or the folder resolved and the name where it does not exist */
    char what[32];
    bool has_id; /* it exists: its device and inode */
    dev_t dev;
    ino_t ino;
} input;

/* What a commit put in place (fb_outputs_written). */
typedef struct done_entry {
    char path[PATH_MAX], what[32];
    uint64_t bytes;
} done_entry;

struct fb_outputs {
    pthread_mutex_t mu;
    entry *out;                  /* FB_MAX_OUTPUTS of them */
    volatile sig_atomic_t count; /* entries in use are below it */
    done_entry *done;            /* FB_MAX_OUTPUTS of them */
    int ndone;
    int depth;
    bool tmpfile;          /* fb_outputs_use_tmpfile */
    char tmpdir[PATH_MAX]; /* fb_outputs_tmpdir: "" is /tmp */
    atomic_int phase;
    volatile sig_atomic_t deferred; /* the signal that came during the commit */
    input *in;
    int nin, capin;
    char stdout_claim[32]; /* a document the run prints on standard output itself: no "-" output then */
    bool stdout_watch;     /* fb_outputs_stdout_watch: standard output is an output of every run */
    /* the set of the outermost transaction (0: none drawn yet), and the folders swept of dead runs'
     * temporary files in it (sweep_locked) */
    uint64_t set;
    char *swept[FB_MAX_OUTPUTS];
    int nswept;
    int slot; /* in g_live */
};

/* Every transaction that exists, for the signal handler alone (fb_outputs_signal, which must remove
 * the temporary files of all of them): no transaction reads another's entries. */
#define MAX_TRANSACTIONS 64
static fb_outputs *_Atomic g_live[MAX_TRANSACTIONS];

/* The thread's own transaction (where its scope names none), made when first needed and freed when
 * the thread ends. */
static _Thread_local fb_outputs *t_own;
static pthread_key_t g_own_key;
static pthread_once_t g_own_once = PTHREAD_ONCE_INIT;

static void own_free(void *o)
{
    fb_outputs_destroy((fb_outputs **)&o);
}

static void own_key(void)
{
    pthread_key_create(&g_own_key, own_free);
}

fb_result fb_outputs_create(fb_outputs **out)
{
    fb_outputs *o = calloc(1, sizeof *o);
    if (o) o->out = calloc(FB_MAX_OUTPUTS, sizeof *o->out), o->done = calloc(FB_MAX_OUTPUTS, sizeof *o->done);
    if (!o || !o->out || !o->done) {
        if (o) free(o->out), free(o->done);
        free(o);
        return fb_fail(FB_ERR_NOMEM, "out of memory for the output transaction");
    }
    pthread_mutex_init(&o->mu, NULL);
    o->tmpfile = true;
    o->slot = -1;
    for (int i = 0; i < MAX_TRANSACTIONS && o->slot < 0; i++) {
        fb_outputs *none = NULL;
        if (atomic_compare_exchange_strong(&g_live[i], &none, o)) o->slot = i;
    }
    if (o->slot < 0) {
        fb_outputs_destroy(&o);
        return fb_fail(FB_ERR_INTERNAL, "more than %d output transactions at once", MAX_TRANSACTIONS);
    }
    *out = o;
    return FB_OK;
}

/* The calling thread's transaction: its scope's, or its own (made now when `make` and it has none).
 * NULL only when it has none and make is false, or when making one failed (logged). */
static fb_outputs *current(bool make)
{
    fb_outputs *o = fb_scope_get().outputs;
    if (o) return o;
    if (!t_own && make && fb_outputs_create(&t_own) == FB_OK) {
        pthread_once(&g_own_once, own_key);
        pthread_setspecific(g_own_key, t_own);
    }
    return t_own;
}

fb_scope fb_scope_capture(void)
{
    fb_scope s = fb_scope_get();
    if (!s.outputs) s.outputs = t_own;
    return s;
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
        static _Atomic uint64_t n;
        r = ((uint64_t)getpid() << 32) ^ (uint64_t)(fb_now() * 1e9) ^
            ((atomic_fetch_add(&n, 1) + 1) * 0x9E3779B97F4A7C15ull);
    }
    return r;
}

static entry *find(fb_outputs *o, const char *key)
{
    for (int i = 0; i < o->count; i++)
        if (o->out[i].state != FREE && !strcmp(o->out[i].key, key)) return &o->out[i];
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

/* The input that names `key`, or is the file st describes (NULL: it does not exist), or NULL. Called
 * locked. */
static const input *input_named(const fb_outputs *o, const char *key, const struct stat *st)
{
    for (int i = 0; i < o->nin; i++) {
        const input *in = &o->in[i];
        if ((st && in->has_id && in->dev == st->st_dev && in->ino == st->st_ino) || !strcmp(in->key, key)) return in;
    }
    return NULL;
}

/* An output that would replace an input: refused, with how to do it on purpose. */
static fb_result clash(const char *path, const char *what, const char *in_path, const char *in_what)
{
    const char *how = !strcmp(what, "output") ? "write the output under another name, then mv it over the input"
                                              : "name another file";
    if (!strcmp(path, in_path))
        return fb_fail(FB_ERR_USAGE, "%s: is an input of this run (read as the %s) and cannot also be the %s: %s", path,
                       in_what, what, how);
    return fb_fail(FB_ERR_USAGE,
                   "%s: is the same file as %s, an input of this run (read as the %s), and cannot also be the %s: %s",
                   path, in_path, in_what, what, how);
}

/* Whether standard output is an output of the run: watched (the command line's), named "-", or
 * claimed for a document. Called locked. */
static bool stdout_is_output(const fb_outputs *o)
{
    return o->stdout_watch || o->stdout_claim[0] || find((fb_outputs *)o, "-");
}

/* Standard output written into an input (`1<> in.exr`, `>> in.exr`): refused. */
static fb_result stdout_clash(const char *in_path, const char *in_what)
{
    return fb_fail(FB_ERR_USAGE,
                   "%s: is an input of this run (read as the %s) and also its standard output (redirected into it "
                   "with >> or 1<>), which would change it: redirect standard output to another file",
                   in_path, in_what);
}

/* The input that standard output is (a regular file: the same device and inode), or NULL. Called
 * locked. */
static const input *stdout_input(const fb_outputs *o)
{
    struct stat st;
    if (fstat(STDOUT_FILENO, &st) != 0 || !S_ISREG(st.st_mode)) return NULL;
    for (int i = 0; i < o->nin; i++)
        if (o->in[i].has_id && o->in[i].dev == st.st_dev && o->in[i].ino == st.st_ino) return &o->in[i];
    return NULL;
}

static entry *free_entry(fb_outputs *o)
{
    for (int i = 0; i < o->count; i++)
        if (o->out[i].state == FREE && !o->out[i].live) return &o->out[i];
    return o->count < FB_MAX_OUTPUTS ? &o->out[o->count] : NULL;
}

/* "-": standard output. The data goes to an anonymous temporary file (gone when closed: nothing for
 * a signal to leave behind) and is copied to standard output at the commit, so that a failed run
 * writes nothing there either. Refused when standard output is a terminal. Called locked. */
static fb_result reserve_stdout(fb_outputs *o, const char *what, entry **out)
{
    if (find(o, "-"))
        return fb_fail(FB_ERR_USAGE,
                       "-: standard output named for two outputs (the %s and the %s): it carries one document; "
                       "name a file for one of them",
                       find(o, "-")->what, what);
    if (o->stdout_claim[0])
        return fb_fail(FB_ERR_USAGE,
                       "-: standard output carries what %s prints: name a file for the %s (standard output "
                       "carries one document)",
                       o->stdout_claim, what);
    if (isatty(STDOUT_FILENO))
        return fb_fail(FB_ERR_USAGE, "-: the %s would go to a terminal: redirect standard output to a file or a pipe",
                       what);
    const input *in = stdout_input(o);
    if (in) return stdout_clash(in->path, in->what);
    entry *e = free_entry(o);
    if (!e) return fb_fail(FB_ERR_USAGE, "-: more than %d outputs", FB_MAX_OUTPUTS);
    const char *tmpdir = o->tmpdir[0] ? o->tmpdir : "/tmp";
    int fd = open(tmpdir, O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd < 0) {
        char tmp[PATH_MAX];
        snprintf(tmp, sizeof tmp, "%s/fractalbake-stdout.XXXXXX", tmpdir);
        if ((fd = mkstemp(tmp)) >= 0) unlink(tmp);
    }
    int keep = fd >= 0 ? dup(fd) : -1;
    if (keep < 0) {
        int err = errno;
        if (fd >= 0) close(fd);
        return fb_fail(FB_ERR_IO, "-: cannot create a temporary file for the %s: %s", what, strerror(err));
    }
    *e = (entry){.live = 0, .state = RESERVED, .fd = fd, .keepfd = keep, .std = true};
    snprintf(e->what, sizeof e->what, "%s", what);
    snprintf(e->path, sizeof e->path, "-");
    snprintf(e->key, sizeof e->key, "-");
    if (e == &o->out[o->count]) o->count = o->count + 1;
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

/* Every temporary file's name starts with this, and the sweep touches no other name. */
#define TEMP_PREFIX ".fractalbake-tmp."

/* Who owns a temporary file: the host's name (to its first dot, letters, digits, '-' and '_', for
 * people to read) and a digest of what a process is known by: the full host name, the boot
 * (/proc/sys/kernel/random/boot_id) and the pid namespace (/proc/self/ns/pid). A sweep removes a
 * file only when its digest is this process's: the pid then names a process of this kernel's and
 * namespace's, which kill(pid, 0) can see. proven is false where the boot or the namespace cannot
 * be read: no sweep then removes anything. */
static struct {
    char host[33];
    uint64_t digest;
    bool proven;
} g_me;
static pthread_once_t g_me_once = PTHREAD_ONCE_INIT;

static uint64_t fnv1a(uint64_t h, const char *s)
{
    for (; *s; s++) h = (h ^ (unsigned char)*s) * 0x100000001b3ull;
    return (h ^ 0xff) * 0x100000001b3ull; /* a separator: ("ab", "c") and ("a", "bc") differ */
}

static void me_init(void)
{
    char name[256] = "", boot[64] = "", ns[64] = "";
    if (gethostname(name, sizeof name - 1) != 0) name[0] = 0;
    int fd = open("/proc/sys/kernel/random/boot_id", O_RDONLY | O_CLOEXEC);
    ssize_t n = fd >= 0 ? read(fd, boot, sizeof boot - 1) : -1;
    if (fd >= 0) close(fd);
    boot[n > 0 ? n : 0] = 0;
    ssize_t m = readlink("/proc/self/ns/pid", ns, sizeof ns - 1);
    ns[m > 0 ? m : 0] = 0;
    g_me.proven = n >= 32 && m > 0;
    g_me.digest = fnv1a(fnv1a(fnv1a(0xcbf29ce484222325ull, name), boot), ns);
    size_t k = 0;
    for (const char *c = name; *c && *c != '.' && k < sizeof g_me.host - 1; c++)
        g_me.host[k++] =
            (strchr("-_", *c) || (*c >= '0' && *c <= '9') || ((*c | 32) >= 'a' && (*c | 32) <= 'z')) ? *c : '-';
    if (!k) g_me.host[k++] = '-';
    g_me.host[k] = 0;
}

/* A hidden temporary name beside the target, TEMP_PREFIX "HOST.OWNER.PID.SET.RAND.NAME.tmp": the host
 * and the owner's digest (g_me), the process, the set of outputs it belongs to (16 hex digits,
 * random) and 32 more random bits; what a later run needs to recognise the files of a dead run's set
 * (sweep_locked), and more than anyone can predict. NAME is the target's (its first 140 bytes). */
static void temp_name(char *out, size_t size, const char *dir, const char *base, uint64_t set)
{
    pthread_once(&g_me_once, me_init);
    snprintf(out, size, "%s/" TEMP_PREFIX "%s.%016llx.%ld.%016llx.%08x.%.140s.tmp", dir, g_me.host,
             (unsigned long long)g_me.digest, (long)getpid(), (unsigned long long)set, (unsigned)random64(), base);
}

/* A temporary file a sweep found: its owner, its run, its set and its target's name. */
typedef struct owned {
    char host[33];
    uint64_t digest;
    long pid;
    uint64_t set;
    char base[NAME_MAX + 1];
} owned;

/* One field of a temporary's name, up to the next '.': n characters of set (n == 0: 1 to max). */
static const char *field(const char *s, const char *set, size_t n, size_t max, char *out, size_t osize)
{
    const char *dot = s ? strchr(s, '.') : NULL;
    size_t m = dot ? (size_t)(dot - s) : 0;
    if (!dot || (n ? m != n : m == 0 || m > max) || strspn(s, set) < m || m >= osize) return NULL;
    memcpy(out, s, m);
    out[m] = 0;
    return dot + 1;
}

/* The parts of a temporary name of temp_name's form; false for any other name. */
static bool temp_parts(const char *name, owned *t)
{
    static const char hex[] = "0123456789abcdef", dec[] = "0123456789",
                      host[] = "-_0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ";
    size_t n = strlen(name), p = strlen(TEMP_PREFIX);
    char digest[17], pid[11], set[17], rnd[9];
    if (n < p + 5 || strncmp(name, TEMP_PREFIX, p) || strcmp(name + n - 4, ".tmp")) return false;
    const char *s = field(name + p, host, 0, 32, t->host, sizeof t->host);
    s = field(s, hex, 16, 16, digest, sizeof digest);
    s = field(s, dec, 0, 10, pid, sizeof pid);
    s = field(s, hex, 16, 16, set, sizeof set);
    s = field(s, hex, 8, 8, rnd, sizeof rnd);
    if (!s || s >= name + n - 4) return false;
    snprintf(t->base, sizeof t->base, "%.*s", (int)(name + n - 4 - s), s);
    t->digest = strtoull(digest, NULL, 16);
    t->pid = strtol(pid, NULL, 10);
    t->set = strtoull(set, NULL, 16);
    return true;
}

/* Holds the temporary file locked (flock, exclusive) for as long as the entry keeps it open: a later
 * run's sweep leaves a locked file alone whatever its name says (a pid reused, another pid
 * namespace). The kernel drops the lock with the process. Where the file system has no flock, the
 * pid alone tells. */
static void lock_temp(int fd)
{
    while (flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EINTR) {
    }
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* What a sweep did with a temporary file of another run. */
enum { REMOVED = 0, NOT_OURS = 1, LOCK_UNSEEN = 2 };

typedef struct found {
    int what; /* REMOVED, NOT_OURS, LOCK_UNSEEN */
    int err;  /* LOCK_UNSEEN: flock's errno */
    owned t;
} found;

static int cmp_found(const void *a, const void *b)
{
    const found *x = a, *y = b;
    if (x->what != y->what) return x->what < y->what ? -1 : 1;
    if (x->t.pid != y->t.pid) return x->t.pid < y->t.pid ? -1 : 1;
    if (x->t.set != y->t.set) return x->t.set < y->t.set ? -1 : 1;
    if (x->t.digest != y->t.digest) return x->t.digest < y->t.digest ? -1 : 1;
    return strcmp(x->t.base, y->t.base);
}

static bool same_run(const found *x, const found *y)
{
    return x->what == y->what && x->t.pid == y->t.pid && x->t.set == y->t.set && x->t.digest == y->t.digest;
}

/* One warning line for each run's files among the n found (sorted): the removed ones and the targets
 * they left as they were; the ones left, with how to remove them by hand. */
static void say_found(const char *shown, const found *f, size_t n)
{
    for (size_t i = 0, j; i < n; i = j) {
        char targets[512] = "";
        for (j = i; j < n && same_run(&f[j], &f[i]); j++)
            snprintf(targets + strlen(targets), sizeof targets - strlen(targets), "%s%s", j > i ? ", " : "",
                     f[j].t.base);
        const owned *t = &f[i].t;
        size_t k = j - i;
        if (f[i].what == REMOVED)
            fb_log(FB_LOG_WARN,
                   "removed %zu temporary file%s of an incomplete set of outputs in %s (set %016llx of process %ld, "
                   "which died before its commit was done): %s %s not replaced by that run",
                   k, k == 1 ? "" : "s", shown, (unsigned long long)t->set, t->pid, targets, k == 1 ? "was" : "were");
        else
            fb_log(FB_LOG_WARN,
                   "left %zu temporary file%s in %s of process %ld on host %s (set %016llx, for %s): %s%s%s, so "
                   "that run may still be working; once it is not, remove %s by hand: rm -- %s/" TEMP_PREFIX
                   "%s.%016llx.%ld.%016llx.*",
                   k, k == 1 ? "" : "s", shown, t->pid, t->host, (unsigned long long)t->set, targets,
                   f[i].what == NOT_OURS ? "made on another host, boot or pid namespace"
                                         : "its lock cannot be seen here (flock: ",
                   f[i].what == NOT_OURS ? "" : strerror(f[i].err), f[i].what == NOT_OURS ? "" : ")",
                   k == 1 ? "it" : "them", shown, t->host, (unsigned long long)t->digest, t->pid,
                   (unsigned long long)t->set);
    }
}

/* What to do with the temporary file `name` of another run (t): REMOVED when it is proven dead and
 * was removed (the same owner's digest as this process's, its pid gone, and no lock on the file,
 * checked on the file itself before its name is removed); NOT_OURS or LOCK_UNSEEN when it is left
 * for the user; -1 when it is left unsaid (a live process's, one held locked, or gone meanwhile). */
static int sweep_one(int dfd, const char *name, const owned *t, int *err)
{
    if (!g_me.proven || t->digest != g_me.digest) return NOT_OURS;
    if (t->pid <= 0 || t->pid == (long)getpid() || kill((pid_t)t->pid, 0) == 0 || errno != ESRCH) return -1;
    int fd = openat(dfd, name, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return -1;
    struct stat a, b;
    int rc = -1;
    if (fstat(fd, &a) == 0 && S_ISREG(a.st_mode)) {
        if (flock(fd, LOCK_EX | LOCK_NB) != 0)
            rc = errno == EWOULDBLOCK || errno == EINTR ? -1 : (*err = errno, LOCK_UNSEEN); /* held: alive */
        else if (fstatat(dfd, name, &b, AT_SYMLINK_NOFOLLOW) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino &&
                 unlinkat(dfd, name, 0) == 0)
            rc = REMOVED;
    }
    close(fd);
    return rc;
}

/* Sweeps dir (shown: the folder as the user spelled it) of the temporary files dead runs left, once
 * per folder and transaction: only names of temp_name's form are looked at (sweep_one); one warning
 * line per run whose files were removed, and one per run whose files are left because this process
 * cannot prove it dead. Called locked. */
static void sweep_locked(fb_outputs *o, const char *shown, const char *dir)
{
    for (int i = 0; i < o->nswept; i++)
        if (!strcmp(o->swept[i], dir)) return;
    if (o->nswept < FB_MAX_OUTPUTS && (o->swept[o->nswept] = strdup(dir))) o->nswept++;
    DIR *d = opendir(dir);
    if (!d) return;
    pthread_once(&g_me_once, me_init);
    found *f = NULL;
    size_t n = 0, cap = 0;
    for (struct dirent *de; (de = readdir(d));) {
        found one = {0};
        if (!temp_parts(de->d_name, &one.t)) continue;
        one.what = sweep_one(dirfd(d), de->d_name, &one.t, &one.err);
        if (one.what < 0) continue;
        if (n == cap) { /* out of memory: a removed file is gone all the same, its line shorter */
            found *grown = realloc(f, (cap ? 2 * cap : 16) * sizeof *f);
            if (grown) f = grown, cap = cap ? 2 * cap : 16;
        }
        if (n < cap) f[n++] = one;
    }
    closedir(d);
    if (n) qsort(f, n, sizeof *f, cmp_found); /* f is NULL when nothing was found */
    say_found(shown, f, n);
    free(f);
}

static void forget_swept_locked(fb_outputs *o)
{
    for (int i = 0; i < o->nswept; i++) free(o->swept[i]);
    o->nswept = 0;
}

/* Creates the hidden named temporary file beside the target (temp_name), exclusively: the fallback
 * where the folder's file system has no O_TMPFILE. Returns the fd or -1 (errno). */
static int create_named(entry *e, const char *dir, const char *base)
{
    int fd = -1;
    for (int tries = 0; tries < 16 && fd < 0; tries++) {
        char tmp[PATH_MAX];
        temp_name(tmp, sizeof tmp, dir, base, e->set);
        /* The name is written before the file exists, so that a signal between the two removes
         * nothing else: unlink of a name that does not exist yet is harmless. */
        memcpy(e->tmp, tmp, sizeof tmp);
        fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0666);
        if (fd < 0 && errno != EEXIST) break;
        if (fd >= 0) e->live = 1;
    }
    return fd;
}

/* An O_TMPFILE file in dir (nothing visible, nothing left by any end of the process), linkable at the
 * commit through /proc/self/fd. -1 where the file system or the kernel cannot (errno EOPNOTSUPP,
 * EISDIR, EINVAL), or without /proc. */
static int create_anonymous(const fb_outputs *o, const char *dir)
{
    if (!o->tmpfile || access("/proc/self/fd", X_OK) != 0) {
        errno = EOPNOTSUPP;
        return -1;
    }
    return open(dir, O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
}

/* Resolves path to its key; checks the target and its name; creates the temporary file. Called
 * locked. */
static fb_result reserve_locked(fb_outputs *o, const char *path, const char *what, entry **out)
{
    char dir[PATH_MAX], key[PATH_MAX];
    const char *base;
    if (!path || !*path) return fb_fail(FB_ERR_USAGE, "%s: an empty file name", what);
    if (!strcmp(path, "-")) return reserve_stdout(o, what, out);
    if (strlen(path) >= PATH_MAX - 64) return fb_fail(FB_ERR_USAGE, "%s: path too long for the %s", path, what);
    split(path, dir, sizeof dir, &base);
    if (!*base || !strcmp(base, ".") || !strcmp(base, ".."))
        return fb_fail(FB_ERR_USAGE, "%s: names a folder, not a file for the %s", path, what);
    if (!key_of(path, key))
        return fb_fail(FB_ERR_USAGE, "%s: cannot create the %s: folder %s: %s", path, what, dir, strerror(errno));
    /* The name must fit the folder's file system now, not at the commit after the work. */
    long name_max = pathconf(dir, _PC_NAME_MAX);
    if (name_max <= 0) name_max = NAME_MAX;
    if ((long)strlen(base) > name_max)
        return fb_fail(FB_ERR_USAGE, "%.60s...: the %s's file name has %zu bytes, more than the %ld its folder allows",
                       path, what, strlen(base), name_max);
    if (strlen(key) >= PATH_MAX - 32) return fb_fail(FB_ERR_USAGE, "%.60s...: path too long for the %s", path, what);
    entry *twice = find(o, key);
    if (twice)
        return fb_fail(FB_ERR_USAGE, "%s: named as the %s and as the %s: two outputs cannot share one path", path,
                       twice->what, what);
    struct stat st;
    bool exists = lstat(path, &st) == 0;
    if (exists && !S_ISREG(st.st_mode))
        return fb_fail(FB_ERR_USAGE, "%s: exists and is %s: the %s replaces only regular files", path,
                       fb_file_kind(st.st_mode), what);
    const input *in = input_named(o, key, exists ? &st : NULL);
    if (in) return clash(path, what, in->path, in->what);
    entry *e = free_entry(o);
    if (!e) return fb_fail(FB_ERR_USAGE, "%s: more than %d outputs", path, FB_MAX_OUTPUTS);
    char kdir[PATH_MAX];
    snprintf(kdir, sizeof kdir, "%.*s", strrchr(key, '/') == key ? 1 : (int)(strrchr(key, '/') - key), key);
    sweep_locked(o, dir, kdir);
    if (!o->set || o->depth == 0) o->set = random64() | 1; /* outside a transaction an output is its own set */
    e->live = 0;
    e->tmp[0] = 0;
    e->set = o->set;
    int fd = create_anonymous(o, dir), keep = -1;
    bool anon = fd >= 0;
    if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL || errno == ENOENT))
        fd = create_named(e, dir, base);
    if (fd >= 0) lock_temp(fd); /* the lock goes with the file's description: dup'ed below, it stays */
    if (fd >= 0 && (keep = dup(fd)) < 0) {
        close(fd);
        fd = -1;
        if (!anon) unlink(e->tmp), e->live = 0;
    }
    if (fd < 0) {
        int err = errno;
        return fb_fail(err == EACCES || err == EROFS || err == ENOENT || err == ENOTDIR ? FB_ERR_USAGE : FB_ERR_IO,
                       "%s: cannot create the %s: %s", path, what, strerror(err));
    }
    e->fd = fd;
    e->keepfd = keep;
    e->anon = anon;
    e->has_id = exists;
    e->dev = exists ? st.st_dev : 0;
    e->ino = exists ? st.st_ino : 0;
    e->std = false;
    e->state = RESERVED;
    snprintf(e->what, sizeof e->what, "%s", what);
    snprintf(e->path, sizeof e->path, "%s", path);
    memcpy(e->key, key, sizeof key);
    if (e == &o->out[o->count]) o->count = o->count + 1;
    *out = e;
    return FB_OK;
}

void fb_outputs_begin(void)
{
    fb_outputs *o = current(true);
    if (!o) return; /* no memory for one: the first output says so */
    pthread_mutex_lock(&o->mu);
    if (o->depth++ == 0) o->ndone = 0, o->set = 0;
    pthread_mutex_unlock(&o->mu);
}

static void abort_locked(fb_outputs *o)
{
    for (int i = 0; i < o->count; i++) drop(&o->out[i]);
    o->count = 0;
}

/* The folder of a file entry's key, for the commit lock. */
static void key_dir(const entry *e, char *dir, size_t size)
{
    const char *slash = strrchr(e->key, '/');
    snprintf(dir, size, "%.*s", slash == e->key ? 1 : (int)(slash - e->key), e->key);
}

/* Locks every folder the entries write into (flock, exclusive, in the folders' sorted order so that
 * two runs never wait for each other crosswise): concurrent runs committing into the same folders
 * put their sets in place one whole set at a time. Returns how many fds it opened in fds. A folder
 * that cannot be locked (a file system without flock) is committed unlocked, with a warning. */
static int lock_folders(entry **list, int n, int *fds)
{
    char(*dirs)[PATH_MAX] = malloc((size_t)(n > 0 ? n : 1) * sizeof *dirs);
    const char *sorted[FB_MAX_OUTPUTS];
    int nd = 0, nfd = 0;
    if (!dirs) { /* no memory to sort the folders: committed unlocked, as on a file system without flock */
        fb_log(FB_LOG_WARN, "out of memory to lock the folders for the commit: committing unlocked");
        return 0;
    }
    for (int i = 0; i < n; i++) {
        if (list[i]->std) continue;
        key_dir(list[i], dirs[nd], sizeof dirs[nd]);
        sorted[nd] = dirs[nd];
        nd++;
    }
    qsort(sorted, (size_t)nd, sizeof sorted[0], cmp_str);
    for (int i = 0; i < nd; i++) {
        if (i > 0 && !strcmp(sorted[i], sorted[i - 1])) continue;
        int fd = open(sorted[i], O_RDONLY | O_DIRECTORY | O_CLOEXEC), rc;
        if (fd < 0) continue;
        while ((rc = flock(fd, LOCK_EX)) != 0 && errno == EINTR) {
        }
        if (rc != 0) /* a file system without flock (NFS with no lock manager: ENOLCK) */
            fb_log(FB_LOG_WARN,
                   "%s: cannot lock the folder for the commit (flock: %s): committing unlocked, so runs writing "
                   "the same files into it at once may leave files of different runs",
                   sorted[i], strerror(errno));
        fds[nfd++] = fd;
    }
    free(dirs);
    return nfd;
}

/* Gives the anonymous file a hidden name beside its target (linkat through /proc/self/fd, which
 * never replaces an existing name: a planted one makes it try another). */
static fb_result link_hidden(entry *e)
{
    char proc[64], dir[PATH_MAX];
    const char *base;
    snprintf(proc, sizeof proc, "/proc/self/fd/%d", e->keepfd);
    split(e->path, dir, sizeof dir, &base);
    for (int tries = 0; tries < 16; tries++) {
        temp_name(e->tmp, sizeof e->tmp, dir, base, e->set);
        e->live = 1; /* before the name exists: a signal then removes nothing else */
        if (linkat(AT_FDCWD, proc, AT_FDCWD, e->tmp, AT_SYMLINK_FOLLOW) == 0) return FB_OK;
        e->live = 0;
        if (errno != EEXIST) break;
    }
    return fb_fail(FB_ERR_IO, "%s: cannot give the %s a name in its folder: %s", e->path, e->what, strerror(errno));
}

/* Puts the n taken entries in place, as one set: names and targets checked again, the folders
 * locked, signals held off (fb_outputs_signal), every anonymous file given its hidden name, standard
 * output written (it cannot be taken back), then the renames. Records what was written. On a
 * failure, nothing more is renamed and the rest are removed by the caller. Called locked. */
static fb_result commit_locked(fb_outputs *o, entry **list, int n)
{
    fb_result rc = FB_OK;
    struct stat st;
    /* Checked again just before the renames: a target that became a non-regular file, or an input,
     * since. */
    for (int i = 0; i < n && !rc; i++) {
        const input *in;
        if (list[i]->std || lstat(list[i]->path, &st) != 0) continue;
        if (!S_ISREG(st.st_mode))
            rc = fb_fail(FB_ERR_USAGE, "%s: exists and is %s: the %s replaces only regular files", list[i]->path,
                         fb_file_kind(st.st_mode), list[i]->what);
        else if ((in = input_named(o, list[i]->key, &st)))
            rc = clash(list[i]->path, list[i]->what, in->path, in->what);
    }
    const input *in = n > 0 && stdout_is_output(o) ? stdout_input(o) : NULL;
    if (!rc && in) rc = stdout_clash(in->path, in->what);
    if (rc) return rc;
    int lockfds[FB_MAX_OUTPUTS], nlock = lock_folders(list, n, lockfds);
    int idle = IDLE;
    while (!atomic_compare_exchange_strong(&o->phase, &idle, COMMITTING)) { /* a handler is ending the run */
        idle = IDLE;
        pause();
    }
    uint64_t bytes[FB_MAX_OUTPUTS];
    for (int i = 0; i < n; i++) {
        entry *e = list[i];
        bytes[i] = e->keepfd >= 0 ? (fstat(e->keepfd, &st) == 0 ? (uint64_t)st.st_size : 0)
                                  : (lstat(e->tmp, &st) == 0 ? (uint64_t)st.st_size : 0);
    }
    if (o->deferred) rc = FB_ERR_INTERNAL; /* a signal came before the first rename: nothing is put in place */
    for (int i = 0; i < n && !rc; i++)
        if (list[i]->anon) rc = link_hidden(list[i]);
    for (int i = 0; i < n && !rc; i++)
        if (list[i]->std) rc = copy_to_stdout(list[i]);
    for (int i = 0; i < n && !rc; i++) {
        entry *e = list[i];
        if (!e->std && rename(e->tmp, e->path) != 0) {
            rc = fb_fail(FB_ERR_IO, "%s: cannot move the %s into place: %s", e->path, e->what, strerror(errno));
            break;
        }
        e->live = 0; /* in place: the handler must not remove it any more */
        if (o->ndone < FB_MAX_OUTPUTS) {
            snprintf(o->done[o->ndone].path, sizeof o->done[0].path, "%s", e->path);
            snprintf(o->done[o->ndone].what, sizeof o->done[0].what, "%s", e->what);
            o->done[o->ndone++].bytes = bytes[i];
        }
    }
    for (int i = 0; i < nlock; i++) close(lockfds[i]); /* the locks go with the fds */
    if (rc) /* the hidden names given so far go too (drop unlinks what is live) */
        for (int i = 0; i < n; i++)
            if (list[i]->live && list[i]->anon) unlink(list[i]->tmp), list[i]->live = 0;
    atomic_store(&o->phase, IDLE);
    return rc;
}

/* A signal that came during the commit: taken now, as if it had come after (its handler ends the
 * run). */
static void deliver_deferred(fb_outputs *o)
{
    int sig = o->deferred;
    if (sig) {
        o->deferred = 0;
        raise(sig);
    }
}

/* The inputs noted go with the run's outermost transaction. Called locked. */
static void forget_inputs_locked(fb_outputs *o)
{
    for (int i = 0; i < o->nin; i++) free(o->in[i].path), free(o->in[i].key);
    free(o->in);
    o->in = NULL;
    o->nin = o->capin = 0;
}

fb_result fb_outputs_end(fb_result rc)
{
    fb_outputs *o = current(false);
    if (!o) return rc ? rc : fb_fail(FB_ERR_NOMEM, "out of memory for the output transaction");
    pthread_mutex_lock(&o->mu);
    if (o->depth > 0) o->depth--;
    if (rc) {
        abort_locked(o);
    } else if (o->depth == 0) {
        entry *list[FB_MAX_OUTPUTS];
        int n = 0;
        for (int i = 0; i < o->count && !rc; i++)
            if (o->out[i].state == RESERVED)
                rc = fb_fail(FB_ERR_INTERNAL, "%s: the %s was reserved but never written", o->out[i].path,
                             o->out[i].what);
            else if (o->out[i].state == TAKEN)
                list[n++] = &o->out[i];
        if (!rc) rc = commit_locked(o, list, n);
        abort_locked(o); /* after a failed rename: the rest are removed */
    }
    if (o->depth == 0) forget_inputs_locked(o), forget_swept_locked(o), o->stdout_claim[0] = 0;
    pthread_mutex_unlock(&o->mu);
    deliver_deferred(o);
    return rc;
}

/* The calling thread's transaction, or an error for the output at path. */
static fb_result current_for(const char *path, fb_outputs **o)
{
    *o = current(true);
    return *o ? FB_OK : fb_fail(FB_ERR_NOMEM, "%s: out of memory for the output transaction", path ? path : "-");
}

fb_result fb_output_reserve(const char *path, const char *what)
{
    entry *e;
    fb_outputs *o;
    fb_result rc = current_for(path, &o);
    if (rc) return rc;
    pthread_mutex_lock(&o->mu);
    rc = reserve_locked(o, path, what, &e);
    pthread_mutex_unlock(&o->mu);
    return rc;
}

fb_result fb_output_open(const char *path, const char *what, int *fd)
{
    char key[PATH_MAX];
    entry *e = NULL;
    fb_outputs *o;
    fb_result rc = current_for(path, &o);
    if (rc) return rc;
    pthread_mutex_lock(&o->mu);
    if (path && *path && key_of(path, key) && (e = find(o, key))) {
        if (e->state != RESERVED)
            rc = fb_fail(FB_ERR_USAGE, "%s: named as the %s and as the %s: two outputs cannot share one path", path,
                         e->what, what);
    } else {
        rc = reserve_locked(o, path, what, &e);
    }
    if (!rc) {
        *fd = e->fd;
        e->fd = -1;
        e->state = TAKEN;
    }
    pthread_mutex_unlock(&o->mu);
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
        snprintf(tmp, sizeof tmp, "%s/" TEMP_PREFIX "spool.%.180s.XXXXXX", dir, base);
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
    fb_outputs *o = current(false);
    if (!o) return fb_fail(FB_ERR_INTERNAL, "%s: finished but never opened as an output", path);
    pthread_mutex_lock(&o->mu);
    entry *e = key_of(path, key) ? find(o, key) : NULL;
    if (!e || e->state != TAKEN) {
        rc = fb_fail(FB_ERR_INTERNAL, "%s: finished but never opened as an output", path);
    } else if (o->depth == 0) {
        o->ndone = 0;
        rc = commit_locked(o, &e, 1);
        drop(e);
        forget_swept_locked(o);
    }
    pthread_mutex_unlock(&o->mu);
    deliver_deferred(o);
    return rc;
}

void fb_output_discard(const char *path)
{
    char key[PATH_MAX];
    fb_outputs *o = current(false);
    if (!o) return;
    pthread_mutex_lock(&o->mu);
    entry *e = path && key_of(path, key) ? find(o, key) : NULL;
    if (e) drop(e);
    pthread_mutex_unlock(&o->mu);
}

fb_result fb_output_claim_stdout(const char *what)
{
    fb_result rc = FB_OK;
    fb_outputs *o = current(false);
    if (!o) return FB_OK; /* outside any transaction: no effect */
    pthread_mutex_lock(&o->mu);
    const entry *e = find(o, "-");
    const input *in;
    if (e)
        rc = fb_fail(FB_ERR_USAGE,
                     "%s: standard output carries the %s (-): name a file for it (standard output carries one "
                     "document)",
                     what, e->what);
    else if (o->depth > 0 && (in = stdout_input(o)))
        rc = stdout_clash(in->path, in->what);
    else if (o->depth > 0)
        snprintf(o->stdout_claim, sizeof o->stdout_claim, "%s", what);
    pthread_mutex_unlock(&o->mu);
    return rc;
}

fb_result fb_input_note(const char *path, const char *what, int fd)
{
    if (!path || !*path || !strcmp(path, "-")) return FB_OK; /* standard input is no file an output can name */
    struct stat st;
    bool has = (fd >= 0 ? fstat(fd, &st) : stat(path, &st)) == 0;
    char key[PATH_MAX];
    if (!realpath(path, key) && !key_of(path, key)) snprintf(key, sizeof key, "%s", path);
    fb_outputs *o = current(false);
    if (!o) return FB_OK; /* no transaction on this thread: no run to belong to, no output to clash with */
    fb_result rc = FB_OK;
    pthread_mutex_lock(&o->mu);
    struct stat so;
    if (has && stdout_is_output(o) && o->depth > 0 && fstat(STDOUT_FILENO, &so) == 0 && S_ISREG(so.st_mode) &&
        so.st_dev == st.st_dev && so.st_ino == st.st_ino)
        rc = stdout_clash(path, what);
    for (int i = 0; i < o->count && !rc; i++) { /* an output reserved before the input was opened */
        const entry *e = &o->out[i];
        if (e->state != FREE && !e->std &&
            ((has && e->has_id && e->dev == st.st_dev && e->ino == st.st_ino) || !strcmp(e->key, key)))
            rc = clash(e->path, e->what, path, what);
    }
    /* outside a transaction there is no run for it to belong to (a library caller's reads between its
     * bakes): nothing to remember */
    bool known = !rc && (o->depth == 0 || input_named(o, key, has ? &st : NULL));
    if (!rc && !known && o->nin == o->capin) {
        int cap = o->capin ? 2 * o->capin : 16;
        input *grown = realloc(o->in, (size_t)cap * sizeof *o->in);
        if (grown)
            o->in = grown, o->capin = cap;
        else
            rc = fb_fail(FB_ERR_NOMEM, "out of memory for the inputs' names");
    }
    if (!rc && !known) {
        input *in = &o->in[o->nin];
        *in = (input){.path = strdup(path), .key = strdup(key), .has_id = has};
        snprintf(in->what, sizeof in->what, "%s", what);
        in->dev = has ? st.st_dev : 0;
        in->ino = has ? st.st_ino : 0;
        if (in->path && in->key)
            o->nin++;
        else
            free(in->path), free(in->key), rc = fb_fail(FB_ERR_NOMEM, "out of memory for the inputs' names");
    }
    pthread_mutex_unlock(&o->mu);
    return rc;
}

/* Removes every temporary file of o (async-signal-safe). */
static void unlink_all(fb_outputs *o)
{
    for (int i = 0; i < o->count; i++)
        if (o->out[i].live) unlink(o->out[i].tmp);
}

void fb_outputs_unlink_all(void)
{
    for (int i = 0; i < MAX_TRANSACTIONS; i++) {
        fb_outputs *o = atomic_load(&g_live[i]);
        if (o) unlink_all(o);
    }
}

bool fb_outputs_signal(int sig)
{
    bool end = true;
    for (int i = 0; i < MAX_TRANSACTIONS; i++) {
        fb_outputs *o = atomic_load(&g_live[i]);
        int idle = IDLE;
        if (!o) continue;
        if (atomic_compare_exchange_strong(&o->phase, &idle, DYING)) {
            unlink_all(o);
            continue;
        }
        if (idle == COMMITTING && !o->deferred) o->deferred = sig;
        end = false; /* COMMITTING: taken when the commit ends; DYING: another thread is ending the run */
    }
    return end;
}

void fb_outputs_stdout_watch(bool on)
{
    fb_outputs *o = current(true);
    if (!o) return;
    pthread_mutex_lock(&o->mu);
    o->stdout_watch = on;
    pthread_mutex_unlock(&o->mu);
}

void fb_outputs_use_tmpfile(bool on)
{
    fb_outputs *o = current(true);
    if (!o) return;
    pthread_mutex_lock(&o->mu);
    o->tmpfile = on;
    pthread_mutex_unlock(&o->mu);
}

void fb_outputs_tmpdir(const char *dir)
{
    fb_outputs *o = current(true);
    if (!o) return;
    pthread_mutex_lock(&o->mu);
    snprintf(o->tmpdir, sizeof o->tmpdir, "%s", dir ? dir : "");
    pthread_mutex_unlock(&o->mu);
}

void fb_outputs_destroy(fb_outputs **po)
{
    fb_outputs *o = po ? *po : NULL;
    if (!o) return;
    if (o->slot >= 0) atomic_store(&g_live[o->slot], NULL); /* first: a signal handler then leaves it alone */
    pthread_mutex_lock(&o->mu);
    abort_locked(o);
    forget_inputs_locked(o);
    forget_swept_locked(o);
    pthread_mutex_unlock(&o->mu);
    if (t_own == o) t_own = NULL;
    pthread_mutex_destroy(&o->mu);
    free(o->out);
    free(o->done);
    memset(o, 0, sizeof *o);
    free(o);
    *po = NULL;
}

fb_result fb_output_format(const char *flag, const char *path, const char *ext)
{
    static const struct {
        const char *ext, *format;
    } formats[] = {{".exr", "OpenEXR"}, {".png", "PNG"}, {".html", "HTML"}, {".xml", "XML"}};
    size_t n = strlen(path), e = strlen(ext);
    if (!strcmp(path, "-") || (n > e && !strcasecmp(path + n - e, ext) && path[n - e - 1] != '/')) return FB_OK;
    const char *format = ext;
    for (size_t i = 0; i < sizeof formats / sizeof formats[0]; i++)
        if (!strcmp(ext, formats[i].ext)) format = formats[i].format;
    const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
    if (dot && (!slash || dot > slash) && dot[1])
        return fb_fail(FB_ERR_USAGE, "%s %s: this writes %s (%s), not %s: name the file %s", flag, path, format, ext,
                       dot, ext);
    return fb_fail(FB_ERR_USAGE, "%s %s: this writes %s: name the file %s (or - for standard output)", flag, path,
                   format, ext);
}

int fb_outputs_written(const char **paths, const char **whats, uint64_t *bytes, int max)
{
    int n = 0;
    fb_outputs *o = current(false);
    if (!o) return 0;
    pthread_mutex_lock(&o->mu);
    for (; n < o->ndone && n < max; n++) {
        paths[n] = o->done[n].path;
        whats[n] = o->done[n].what;
        bytes[n] = o->done[n].bytes;
    }
    pthread_mutex_unlock(&o->mu);
    return n;
}

int fb_inputs_noted(const char **paths, const char **whats, int max)
{
    int n = 0;
    fb_outputs *o = current(false);
    if (!o) return 0;
    pthread_mutex_lock(&o->mu);
    for (; n < o->nin && n < max; n++) {
        paths[n] = o->in[n].path;
        whats[n] = o->in[n].what;
    }
    pthread_mutex_unlock(&o->mu);
    return n;
}
