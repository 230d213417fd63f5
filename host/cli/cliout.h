/*
 * What the command line writes on its own standard streams, and how it ends on a signal: one place
 * for every command.
 *
 * - Standard output is checked: every command's text goes through stdio, and cli_stdout_finish()
 *   flushes it and reports a write error (a full disk, a closed pipe whose SIGPIPE is ignored, a
 *   closed descriptor) as a runtime failure (exit 3) naming standard output.
 * - Lines that say what a run wrote ("wrote out.exr ...") are held by cli_after() and printed by
 *   cli_after_flush() once the outputs are in place: a failed commit prints none of them.
 * - Every signal that ends a process by default and can be caught ends the run like SIGINT: the
 *   temporary files go, no output is put in place, exit 128 + the signal; during the commit it waits
 *   for the commit's end (output.h). SIGHUP, SIGPIPE and SIGXFSZ stay ignored where the parent
 *   set them so (nohup, `trap '' XFSZ`: a write error then, exit 3). Faults (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT)
 * remove the temporary files and then end the process as they would have.
 */
#ifndef FB_CLIOUT_H
#define FB_CLIOUT_H

#include "fb.h"

/* Before anything else in main: a closed standard descriptor (0, 1 or 2) is opened on /dev/null, so
 * that no file the run opens becomes its standard output; a closed standard output is opened
 * read-only, so every write to it fails and cli_stdout_finish() reports it. Then the signal handlers
 * (see above). */
void cli_start(void);

/* A line (printf format, no newline) for standard error once the outputs are in place. */
void cli_after(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Prints the held lines (show) or drops them, and forgets them. */
void cli_after_flush(bool show);

/* Flushes standard output; FB_ERR_IO (logged, naming standard output) when anything written to it
 * was lost. */
fb_result cli_stdout_finish(void);

/* --quiet with --json, where --quiet only leaves out the summary line that --json replaces: the
 * combination is refused (it would change nothing). */
fb_result cli_check_quiet_json(bool quiet, bool json);

#endif
