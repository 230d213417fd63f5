/*
 * The command line's standard streams and signals. See cliout.h.
 */
#include "cliout.h"

#include "output.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char *g_after; /* the held lines, each ending in '\n' */
static size_t g_after_len;

void cli_after(const char *fmt, ...)
{
    char line[4096];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line, sizeof line - 1, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    size_t len = strlen(line);
    line[len++] = '\n';
    char *grown = realloc(g_after, g_after_len + len + 1);
    if (!grown) return;
    memcpy(grown + g_after_len, line, len);
    g_after = grown;
    g_after_len += len;
    g_after[g_after_len] = 0;
}

void cli_after_flush(bool show)
{
    if (show && g_after) fputs(g_after, stderr);
    free(g_after);
    g_after = NULL;
    g_after_len = 0;
}

fb_result cli_stdout_finish(void)
{
    errno = 0;
    int flushed = fflush(stdout);
    int err = errno;
    if (flushed == 0 && !ferror(stdout)) return FB_OK;
    clearerr(stdout);
    /* errno is the flush's; a write that failed earlier (a large text written through) left none */
    return fb_fail(FB_ERR_IO, "standard output: cannot write: %s", err ? strerror(err) : "a write to it failed");
}

/* The signals that end a process by default and can be caught. */
static const int k_ending[] = {SIGHUP,  SIGINT,  SIGQUIT,   SIGTERM, SIGPIPE, SIGXFSZ, SIGXCPU,  SIGALRM,
                               SIGUSR1, SIGUSR2, SIGVTALRM, SIGPROF, SIGPOLL, SIGPWR,  SIGSTKFLT};
static const int k_faults[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS};

static void on_signal(int sig)
{
    if (fb_outputs_signal(sig)) _exit(128 + sig);
}

static void on_fault(int sig)
{
    fb_outputs_unlink_all();
    signal(sig, SIG_DFL);
    raise(sig);
}

static void install(const int *sigs, size_t n, void (*fn)(int), int flags)
{
    for (size_t i = 0; i < n; i++) {
        struct sigaction old, sa;
        /* Kept ignored where the parent chose so: SIGHUP under nohup; SIGPIPE and SIGXFSZ, which then come
         * back as write errors (exit 3). SIGINT and SIGQUIT are not: a shell ignores them for every
         * background job, and a bake started with & must still stop cleanly on kill -INT. */
        bool keep_ignored = sigs[i] == SIGHUP || sigs[i] == SIGPIPE || sigs[i] == SIGXFSZ;
        if (keep_ignored && sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = fn;
        sa.sa_flags = flags;
        if (fn == on_signal)
            sigfillset(&sa.sa_mask); /* no second signal inside the handler */
        else
            sigemptyset(&sa.sa_mask); /* the fault raised again inside it ends the process */
        sigaction(sigs[i], &sa, NULL);
    }
}

void cli_start(void)
{
    for (int fd = 0; fd < 3; fd++) {
        if (fcntl(fd, F_GETFD) >= 0 || errno != EBADF) continue;
        int got = open("/dev/null", fd == 2 ? O_WRONLY : O_RDONLY);
        if (got >= 0 && got != fd) {
            dup2(got, fd);
            close(got);
        }
    }
    install(k_ending, sizeof k_ending / sizeof k_ending[0], on_signal, SA_RESTART);
    install(k_faults, sizeof k_faults / sizeof k_faults[0], on_fault, SA_RESETHAND | SA_NODEFER);
}

fb_result cli_check_quiet_json(bool quiet, bool json)
{
    if (quiet && json)
        return fb_fail(FB_ERR_USAGE,
                       "--quiet: not with --json (the JSON summary replaces the line --quiet leaves out)");
    return FB_OK;
}
