/*
 * The output transaction (host/base/output.c): exclusive temporary files, all-or-nothing renames, nesting,
 * refusal of non-regular targets and of one path named twice, names too long for the folder, the
 * signal handler's clean-up; outputs that would replace an input; anonymous (O_TMPFILE) files that nothing sees and
 * SIGKILL leaves nothing of; signals during a commit taken after the whole set is in place.
 */
#define _GNU_SOURCE /* syscall */
#include "output.h"
#include "testhelp.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <glob.h>
#include <sys/syscall.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <time.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char g_dir[256];

/* Files in the scratch folder whose name contains `part`. */
static int count_files(const char *part)
{
    DIR *d = opendir(g_dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) n += strstr(e->d_name, part) != NULL;
    if (d) closedir(d);
    return n;
}

static const char *at(const char *name)
{
    static char buf[4][512];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", g_dir, name);
    return buf[k];
}

/* name, spelled through the folder's "." */
static const char *alias_of(const char *name)
{
    static char buf[512];
    snprintf(buf, sizeof buf, "%s/./%s", g_dir, name);
    return buf;
}

static bool has(const char *name, const char *text)
{
    char got[64] = {0};
    FILE *f = fopen(at(name), "rb");
    if (!f) return false;
    size_t n = fread(got, 1, sizeof got - 1, f);
    fclose(f);
    return n == strlen(text) && !memcmp(got, text, n);
}

static fb_result write_text(const char *name, const char *what, const char *text)
{
    int fd = -1;
    fb_result rc = fb_output_open(at(name), what, &fd);
    if (rc) return rc;
    rc = write(fd, text, strlen(text)) == (ssize_t)strlen(text) ? FB_OK : FB_ERR_IO;
    close(fd);
    return fb_output_done(at(name), rc);
}

/* Files in the scratch folder, all names. */
static int count_all(void)
{
    DIR *d = opendir(g_dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    if (d) closedir(d);
    return n;
}

/* The warnings logged, and the last one, for the sweep's lines: the last "removed" line and the
 * first four "left" lines of a sweep (sorted: those of other owners, by pid, then those whose lock
 * cannot be seen). */
static int g_warnings, g_nleft;
static char g_last_warning[1024], g_removed_warning[1024], g_left_warning[4][1024];
static void count_warnings(int level, const char *msg, void *user)
{
    (void)user;
    if (level != FB_LOG_WARN) return;
    if (g_warnings++ == 0) g_nleft = 0;
    snprintf(g_last_warning, sizeof g_last_warning, "%s", msg);
    if (!strncmp(msg, "removed ", 8)) snprintf(g_removed_warning, sizeof g_removed_warning, "%s", msg);
    if (!strncmp(msg, "left ", 5) && g_nleft < 4)
        snprintf(g_left_warning[g_nleft++], sizeof g_left_warning[0], "%s", msg);
}

/* flock as the C library's, or failing with g_flock_err: a file system whose locks cannot be seen
 * (NFS mounted without a lock manager). The sweep's calls come here too (the test links it). */
static int g_flock_err;
int flock(int fd, int op)
{
    if (g_flock_err) return errno = g_flock_err, -1;
    return (int)syscall(SYS_flock, fd, op);
}

/* The signal handler of a run, as main's: outside a commit it ends the process. */
static void on_term(int sig)
{
    if (fb_outputs_signal(sig)) _exit(128 + sig);
}

/* A child that commits generation after generation of one set of 24 files ("set00".."set23", each
 * holding its generation's number) until it is killed. */
static void commit_forever(int ready)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_term;
    sigfillset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGTERM, &sa, NULL);
    if (write(ready, "r", 1) != 1) _exit(1); /* the handler is in place: the parent may signal */
    for (int g = 1;; g++) {
        char text[32], name[32];
        snprintf(text, sizeof text, "%d", g);
        fb_outputs_begin();
        for (int k = 0; k < 24; k++) {
            snprintf(name, sizeof name, "set%02d", k);
            if (write_text(name, "output", text)) _exit(1);
        }
        if (fb_outputs_end(FB_OK)) _exit(1);
    }
}

/* The generation every file of the set holds; -1 when they differ (or one is missing). */
static int set_generation(void)
{
    int gen = -2;
    for (int k = 0; k < 24; k++) {
        char name[32], got[32] = {0};
        snprintf(name, sizeof name, "set%02d", k);
        FILE *f = fopen(at(name), "rb");
        if (!f) return -1;
        size_t n = fread(got, 1, sizeof got - 1, f);
        fclose(f);
        int g = n ? atoi(got) : -1;
        if (gen == -2) gen = g;
        if (g != gen) return -1;
    }
    return gen;
}

int main(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/fb-test-output-XXXXXX");
    REQUIRE(mkdtemp(g_dir) != NULL);

    /* First the hidden named temporary files (a file system without O_TMPFILE), which these checks
     * can see; the anonymous ones after. */
    fb_outputs_use_tmpfile(false);

    /* Outside a transaction an output is its own: renamed when done. */
    REQUIRE(write_text("a.txt", "output", "one") == FB_OK);
    CHECK(has("a.txt", "one") && count_files(".tmp") == 0);

    /* Inside one, nothing is renamed before the outermost end; then everything is. */
    fb_outputs_begin();
    CHECK(write_text("a.txt", "output", "two") == FB_OK);
    fb_outputs_begin(); /* nested, as fb_bake inside main */
    CHECK(write_text("b.txt", "preview", "three") == FB_OK);
    CHECK(fb_outputs_end(FB_OK) == FB_OK);
    CHECK(has("a.txt", "one") && access(at("b.txt"), F_OK) != 0);
    CHECK(count_files(".tmp") == 2);
    CHECK(fb_outputs_end(FB_OK) == FB_OK);
    CHECK(has("a.txt", "two") && has("b.txt", "three") && count_files(".tmp") == 0);

    /* A failure at any depth removes every temporary file and renames nothing. */
    fb_outputs_begin();
    CHECK(write_text("a.txt", "output", "four") == FB_OK);
    fb_outputs_begin();
    CHECK(write_text("c.txt", "mesh", "five") == FB_OK);
    CHECK(fb_outputs_end(FB_ERR_IO) == FB_ERR_IO);
    CHECK(fb_outputs_end(FB_OK) == FB_OK); /* the outer level has nothing left to commit */
    CHECK(has("a.txt", "two") && access(at("c.txt"), F_OK) != 0 && count_files(".tmp") == 0);

    /* The temporary name: hidden, beside the target, ".fractalbake-tmp.HOST.OWNER.PID.SET.RAND.NAME.tmp":
     * this host's name (to its first dot), 16 hex digits of the owner's digest (host, boot, pid
     * namespace), this process, the set's 16 random hex digits (one for the transaction), 8 more
     * random ones of its own. */
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("d.txt"), "output") == FB_OK);
    CHECK(fb_output_reserve(at("e.txt"), "output") == FB_OK);
    char names[2][256] = {{0}};
    DIR *d = opendir(g_dir);
    int k = 0;
    for (struct dirent *e; d && (e = readdir(d));)
        if (strstr(e->d_name, ".tmp") && k < 2) snprintf(names[k++], sizeof names[k], "%s", e->d_name);
    if (d) closedir(d);
    CHECK(k == 2);
    char sets[2][17] = {{0}}, rands[2][9] = {{0}}, owners[2][17] = {{0}}, host[256] = "";
    REQUIRE(gethostname(host, sizeof host - 1) == 0);
    host[strcspn(host, ".")] = 0;
    for (int i = 0; i < k; i++) {
        const char *n = names[i];
        char tail[64] = "", who[64] = "";
        int pid = 0, used = 0;
        bool form = !strncmp(n, ".fractalbake-tmp.", 17) &&
                    sscanf(n + 17, "%63[-_0-9A-Za-z].%16[0-9a-f].%d.%16[0-9a-f].%8[0-9a-f].%n", who, owners[i], &pid,
                           sets[i], rands[i], &used) == 5 &&
                    used > 0 && pid == (int)getpid() && strlen(owners[i]) == 16 && strlen(sets[i]) == 16 &&
                    strlen(rands[i]) == 8 && !strncmp(who, host, 32) &&
                    snprintf(tail, sizeof tail, "%s", n + 17 + used) > 0 &&
                    (!strcmp(tail, "d.txt.tmp") || !strcmp(tail, "e.txt.tmp"));
        CHECKF(form, "temporary name %s", n);
    }
    CHECK(!strcmp(owners[0], owners[1]));
    CHECK(!strcmp(sets[0], sets[1]) && strcmp(rands[0], rands[1]) != 0);
    /* Reserved but never written is an internal error at commit, and leaves nothing. */
    CHECK(fb_outputs_end(FB_OK) == FB_ERR_INTERNAL);
    CHECK(count_files(".tmp") == 0 && access(at("d.txt"), F_OK) != 0);

    /* One path named twice, in two spellings, is refused; so is a non-regular target. */
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("f.txt"), "output") == FB_OK);
    char alias[512];
    snprintf(alias, sizeof alias, "%s/./f.txt", g_dir);
    CHECK(fb_output_reserve(alias, "preview") == FB_ERR_USAGE);
    int fd = -1;
    CHECK(fb_output_open(alias, "preview", &fd) == FB_OK); /* taking its own reservation is fine */
    CHECK(fb_output_open(at("f.txt"), "mesh", &fd) == FB_ERR_USAGE || (close(fd), 0));
    mkdir(at("g.dir"), 0777);
    CHECK(symlink("a.txt", at("h.lnk")) == 0);
    CHECK(fb_output_reserve(at("g.dir"), "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(at("h.lnk"), "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve("/dev/null", "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(at("no/such/folder.txt"), "output") == FB_ERR_USAGE);
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    CHECK(count_files(".tmp") == 0);

    /* No output replaces an input: noted first (by device and inode, through another spelling or a
     * hard link) or reserved first, the second of the two is refused; and a target that becomes an
     * input's hard link after it was reserved is refused at the commit, the input untouched. */
    REQUIRE(write_text("in.txt", "output", "input") == FB_OK);
    REQUIRE(link(at("in.txt"), at("in-link.txt")) == 0);
    fb_outputs_begin();
    CHECK(fb_input_note(at("in.txt"), "scene", -1) == FB_OK);
    CHECK(fb_input_note(at("in.txt"), "scene", -1) == FB_OK); /* the same input twice is one */
    CHECK(fb_output_reserve(at("in.txt"), "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(alias_of("in.txt"), "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(at("in-link.txt"), "preview") == FB_ERR_USAGE);
    CHECK(fb_input_note(at("not-yet.txt"), "points", -1) == FB_OK); /* by its resolved path */
    CHECK(fb_output_reserve(alias_of("not-yet.txt"), "mesh") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(at("out.txt"), "output") == FB_OK);
    CHECK(fb_input_note(at("out.txt"), "EXR", -1) == FB_ERR_USAGE); /* reserved first */
    CHECK(fb_input_note("-", "scene", -1) == FB_OK);                /* standard input is no file */
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    fb_outputs_begin(); /* the inputs went with the outermost end */
    CHECK(fb_output_reserve(at("in.txt"), "output") == FB_OK);
    fb_output_discard(at("in.txt"));
    CHECK(fb_input_note(at("in.txt"), "scene", -1) == FB_OK);
    fd = -1;
    CHECK(fb_output_open(at("late.txt"), "output", &fd) == FB_OK && write(fd, "x", 1) == 1);
    if (fd >= 0) close(fd);
    CHECK(fb_output_done(at("late.txt"), FB_OK) == FB_OK);
    CHECK(link(at("in.txt"), at("late.txt")) == 0); /* the target turns into the input since */
    CHECK(fb_outputs_end(FB_OK) == FB_ERR_USAGE);
    CHECK(has("in.txt", "input") && has("late.txt", "input") && count_files(".tmp") == 0);
    unlink(at("in.txt")), unlink(at("in-link.txt")), unlink(at("late.txt"));

    /* Standard output carries one document: a claim (--json) and "-" exclude each other, either
     * order; the claim goes with the transaction. (Not where standard output is a terminal, which
     * "-" refuses anyway.) */
    if (!isatty(STDOUT_FILENO)) {
        fb_outputs_begin();
        CHECK(fb_output_claim_stdout("--json") == FB_OK);
        CHECK(fb_output_reserve("-", "JUnit report") == FB_ERR_USAGE);
        CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
        fb_outputs_begin();
        CHECK(fb_output_reserve("-", "output") == FB_OK);
        CHECK(fb_output_claim_stdout("--json") == FB_ERR_USAGE);
        CHECK(fb_output_reserve("-", "preview") == FB_ERR_USAGE);
        CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
        fb_outputs_begin();
        CHECK(fb_output_reserve("-", "output") == FB_OK);
        fb_output_discard("-");
        CHECK(fb_outputs_end(FB_OK) == FB_OK);
    }

    /* The signal handler's clean-up removes every temporary file. */
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("i.txt"), "output") == FB_OK);
    CHECK(write_text("j.txt", "preview", "six") == FB_OK);
    CHECK(count_files(".tmp") == 2);
    fb_outputs_unlink_all();
    CHECK(count_files(".tmp") == 0);
    fb_outputs_end(FB_ERR_INTERNAL);
    CHECK(access(at("j.txt"), F_OK) != 0);

    /* A dead run's temporary files are removed by the next run that writes into their folder, with
     * one line naming the set; a live run's are not, nor a file its name calls dead that someone holds
     * locked (a reused pid, another pid namespace). */
    int up[2];
    REQUIRE(pipe(up) == 0);
    pid_t child = fork();
    if (child == 0) {
        fb_outputs_begin();
        if (fb_output_reserve(at("s1.txt"), "output") || fb_output_reserve(at("s2.txt"), "preview")) _exit(1);
        if (write(up[1], "r", 1) != 1) _exit(1);
        pause();
        _exit(0);
    }
    char r1;
    REQUIRE(child > 0 && read(up[0], &r1, 1) == 1);
    close(up[0]), close(up[1]);
    fb_log_set_sink(count_warnings, NULL);
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("t1.txt"), "output") == FB_OK);
    CHECK(count_files(".s1.txt.") == 1 && count_files(".s2.txt.") == 1 && g_warnings == 0); /* alive: kept */
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    int cst = 0;
    CHECK(kill(child, SIGKILL) == 0 && waitpid(child, &cst, 0) == child);
    char set[17] = {0}, owner[17] = {0}, who[64] = {0}, planted[512];
    d = opendir(g_dir);
    for (struct dirent *e; d && (e = readdir(d));)
        if (strstr(e->d_name, ".s1.txt.tmp"))
            sscanf(e->d_name, ".fractalbake-tmp.%63[^.].%16[0-9a-f].%*d.%16[0-9a-f]", who, owner, set);
    if (d) closedir(d);
    REQUIRE(strlen(set) == 16 && strlen(owner) == 16);
    /* a file whose name says the dead child, held locked by this process (as by a live run) */
    snprintf(planted, sizeof planted, "%s/.fractalbake-tmp.%s.%s.%d.%s.0badcafe.held.txt.tmp", g_dir, who, owner,
             (int)child, set);
    int held = open(planted, O_WRONLY | O_CREAT | O_EXCL, 0666);
    CHECK(held >= 0 && flock(held, LOCK_EX) == 0);
    /* Files the sweep cannot prove dead: its pid dead here, but another host's (a live run on another
     * node of a cluster, its lock not seen through NFS), or this host's name with another owner
     * (another boot, another pid namespace), or another host's with a live pid; and files that merely
     * look like temporary files (the form of earlier versions, a dead pid in it; the prefix and
     * another form; a name ending .tmp): none is removed. */
    const char *foreign[] = {".fractalbake-tmp.node17.0123456789abcdef.%d.00000000000000aa.00000001.far.txt.tmp",
                             ".fractalbake-tmp.%s.fedcba9876543210.%d.00000000000000bb.00000002.boot.txt.tmp",
                             ".fractalbake-tmp.node17.0123456789abcdef.1.00000000000000cc.00000003.init.txt.tmp",
                             ".user.txt.%d.0123456789abcdef.0badcafe.tmp",
                             ".fractalbake-tmp.notes.txt",
                             ".fractalbake-tmp.%s.%s.%d.%s.0badcafe..tmp",
                             "user.txt.tmp"};
    char fpath[7][512];
    for (int i = 0; i < 7; i++) {
        char name[256];
        if (i == 1)
            snprintf(name, sizeof name, foreign[i], who, (int)child);
        else if (i == 5)
            snprintf(name, sizeof name, foreign[i], who, owner, (int)child, set);
        else
            snprintf(name, sizeof name, foreign[i], (int)child);
        snprintf(fpath[i], sizeof fpath[i], "%s/%s", g_dir, name);
        FILE *f = fopen(fpath[i], "w");
        CHECK(f && fputs("user's", f) >= 0 && fclose(f) == 0);
    }
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("t2.txt"), "output") == FB_OK);
    CHECK(count_files(".s1.txt.") == 0 && count_files(".s2.txt.") == 0 && count_files(".t2.txt.") == 1);
    for (int i = 0; i < 7; i++) CHECKF(has(strrchr(fpath[i], '/') + 1, "user's"), "%s was removed", fpath[i]);
    /* one line for the removed set, one for each run left (three), each with a command that removes
     * its files and no other */
    CHECKF(g_warnings == 4, "%d warnings: %s", g_warnings, g_last_warning);
    CHECKF(strstr(g_removed_warning, set) && strstr(g_removed_warning, "s1.txt, s2.txt") &&
               strstr(g_removed_warning, "removed 2 temporary files of an incomplete set"),
           "%s", g_removed_warning);
    for (int i = 0; i < 3; i++) {
        const char *line = g_left_warning[i], *rm = strstr(line, "rm -- ");
        static const char *const order[3] = {"init.txt", "far.txt", "boot.txt"}; /* by pid, then set */
        char target[32], file[32];
        snprintf(target, sizeof target, "for %s)", order[i]);
        snprintf(file, sizeof file, ".%s.tmp", order[i]);
        CHECKF(rm && strstr(line, "left 1 temporary file in ") && strstr(line, target) &&
                   strstr(line, "made on another host, boot or pid namespace"),
               "left line %d: %s", i, line);
        glob_t g = {0};
        CHECKF(rm && glob(rm + 6, 0, NULL, &g) == 0 && g.gl_pathc == 1 && strstr(g.gl_pathv[0], file),
               "%s matches %zu files", rm ? rm + 6 : "(none)", g.gl_pathc);
        if (rm) globfree(&g);
    }
    CHECK(access(planted, F_OK) == 0); /* locked: alive, whatever its name says */
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    close(held);
    /* A run whose lock cannot be seen (flock fails: NFS without a lock manager): left, and said. */
    g_warnings = 0;
    g_flock_err = ENOLCK;
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("t3.txt"), "output") == FB_OK);
    g_flock_err = 0;
    CHECK(access(planted, F_OK) == 0);
    CHECKF(g_warnings == 4 && strstr(g_left_warning[3], "held.txt") &&
               strstr(g_left_warning[3], "its lock cannot be seen here (flock: No locks available)"),
           "%d warnings: %s", g_warnings, g_left_warning[3]);
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    /* Unlocked now, its pid dead, this host's and boot's: removed. */
    g_warnings = 0;
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("t4.txt"), "output") == FB_OK);
    CHECK(access(planted, F_OK) != 0 && g_warnings == 4 && strstr(g_removed_warning, "held.txt was not replaced"));
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    fb_log_set_sink(NULL, NULL);
    for (int i = 0; i < 7; i++) CHECK(has(strrchr(fpath[i], '/') + 1, "user's") && unlink(fpath[i]) == 0);
    CHECK(count_files(".tmp") == 0);

    /* A name longer than the folder allows is refused when reserved, before any work (not at the
     * rename after it). */
    char longname[300];
    memset(longname, 'n', 299);
    longname[299] = 0;
    fb_outputs_begin();
    CHECK(fb_output_reserve(at(longname), "heightmap") == FB_ERR_USAGE);
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    CHECK(count_files("nnnnnnnn") == 0);

    /* Standard output's data waits in the folder the command line names ($TMPDIR, fb_outputs_tmpdir):
     * one that does not exist fails the reservation, a real one takes it (where standard output is
     * not a terminal, which "-" refuses). */
    if (!isatty(STDOUT_FILENO)) {
        fb_outputs_begin();
        fb_outputs_tmpdir(at("no/such/folder"));
        CHECK(fb_output_reserve("-", "output") == FB_ERR_IO);
        fb_outputs_tmpdir(g_dir);
        CHECK(fb_output_reserve("-", "output") == FB_OK);
        fb_output_discard("-");
        CHECK(fb_outputs_end(FB_OK) == FB_OK);
        fb_outputs_tmpdir(NULL);
    }

    /* Anonymous files (O_TMPFILE, tmpfs has it): nothing in the folder until the commit, then the
     * targets alone. */
    fb_outputs_use_tmpfile(true);
    int before = count_all();
    fb_outputs_begin();
    CHECK(write_text("k.txt", "output", "seven") == FB_OK);
    CHECK(write_text("l.txt", "preview", "eight") == FB_OK);
    CHECK(fb_output_reserve(at("m.txt"), "mesh") == FB_OK);
    CHECK(count_all() == before); /* nothing visible while the run works */
    fb_output_discard(at("m.txt"));
    CHECK(fb_outputs_end(FB_OK) == FB_OK);
    CHECK(has("k.txt", "seven") && has("l.txt", "eight") && count_all() == before + 2);
    /* the mode is 0666 less the umask, as for the named files */
    mode_t old_mask = umask(027);
    CHECK(write_text("n.txt", "output", "nine") == FB_OK);
    umask(old_mask);
    struct stat st;
    CHECK(stat(at("n.txt"), &st) == 0 && (st.st_mode & 0777) == 0640);
    /* a symbolic link planted at every hidden name is never written through (linkat never replaces) */

    /* SIGKILL in the middle of a run: nothing at all is left of its outputs. */
    before = count_all();
    pid_t pid = fork();
    if (pid == 0) {
        fb_outputs_begin();
        int fd1 = -1;
        if (fb_output_open(at("o.txt"), "output", &fd1) || write(fd1, "x", 1) != 1) _exit(1);
        if (fb_output_reserve(at("p.txt"), "preview")) _exit(1);
        raise(SIGKILL);
        _exit(2);
    }
    int status = 0;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    CHECK(count_all() == before);

    /* SIGTERM at random moments of runs that commit one set of 24 files again and again: the set is
     * always one generation's, never half of two (a signal during the commit waits for its end). */
    int mixed = 0, rounds = 0, committed = 0;
    th_rng = (uint64_t)time(NULL) | 1;
    for (int r = 0; r < 60; r++) {
        int ready[2];
        REQUIRE(pipe(ready) == 0);
        pid = fork();
        if (pid == 0) commit_forever(ready[1]);
        char r1;
        bool up = read(ready[0], &r1, 1) == 1;
        close(ready[0]);
        close(ready[1]);
        if (!up) break;
        struct timespec ts = {0, (long)(2e6 + th_unif() * 20e6)}; /* 2 to 22 ms */
        nanosleep(&ts, NULL);
        kill(pid, SIGTERM);
        if (waitpid(pid, &status, 0) != pid) break;
        rounds++;
        committed += WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM;
        int g = set_generation();
        mixed += g == -1 && access(at("set00"), F_OK) == 0;
    }
    CHECKF(rounds == 60 && committed == 60, "%d rounds, %d ended with 143", rounds, committed);
    CHECKF(mixed == 0, "%d of %d rounds left a set of two generations", mixed, rounds);
    CHECK(count_files(".tmp") == 0);

    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
    CHECK(system(cmd) == 0);
    TEST_REPORT();
}
