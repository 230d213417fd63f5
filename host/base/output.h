/*
 * The files a run writes, as one transaction.
 *
 * Every output (the EXR, its preview, a terrain mesh, a CSV, a plot, a diff image) is written to a
 * temporary file in the target's folder, mode 0666 less the umask: an anonymous one (O_TMPFILE)
 * where the file system allows, which nothing can see and no end of the process (SIGKILL, a crash,
 * a power cut) leaves behind; elsewhere a hidden one created exclusively (O_CREAT | O_EXCL), named
 * ".fractalbake-tmp.HOST.OWNER.PID.SET.RAND.NAME.tmp" (OWNER: a digest of the host name, the boot id
 * and the pid namespace; 96 random bits). The first reservation in a folder sweeps it of the files of
 * that form a dead run left: removed when proven dead (this process's OWNER, no such pid, no lock on
 * the file), else named in a warning (another host, boot or namespace; a lock that cannot be seen);
 * no other name is touched. Names, folders and targets are checked when an output is reserved,
 * before any work. Nothing is put in place until the whole run has succeeded; then, at the commit, the
 * folders are locked (flock: runs committing into the same folders do it one whole set at a time),
 * signals are held off (fb_outputs_signal), each anonymous file is linked to a hidden name, and every
 * file is renamed over its target. On any failure, and on a signal before the commit, every
 * temporary file is removed and no target is touched.
 *
 * Only regular files are replaced: a target that exists and is anything else (a directory, a device
 * node, a symbolic link, a FIFO) is refused before anything is computed, as is one path named twice.
 *
 * No output replaces an input of the run: every file a run reads is noted as it is opened
 * (fb_input_note, called by textin.h's readers, which every reader of the program goes through), and
 * an output that names one (the same device and inode, or the same resolved path) is refused, whatever
 * its extension and whichever comes first: reserving an output checks the inputs noted, noting an
 * input checks the outputs reserved, and the commit checks the targets once more.
 *
 * The path "-" is standard output: its data goes to an anonymous temporary file (in the folder of
 * fb_outputs_tmpdir) and is copied to standard output at the commit (so a failed run writes nothing
 * there either); it is refused when standard output is a terminal. Standard output carries one
 * document: a second "-" is refused, and so is one beside a document the run prints there itself (a
 * --json summary, fb_output_claim_stdout).
 *
 * Transactions nest: fb_outputs_begin() / fb_outputs_end() pairs may be called inside one another
 * (main() around a command, fb_bake() around a bake); only the outermost end commits, and any
 * failed end aborts everything.
 *
 * Every function below works on the calling thread's transaction: the one its scope names (fb.h: the
 * command line's, a library context's for one call; the threads a bake starts take it from the
 * thread that starts them), else the thread's own, made when first needed. A transaction is
 * thread-safe; no transaction sees another's outputs or inputs. The signal functions alone reach
 * every transaction that exists (a signal ends the whole process).
 */
#ifndef FB_OUTPUT_H
#define FB_OUTPUT_H

#include "fb.h"

#include <stdbool.h>
#include <stdint.h>

#define FB_MAX_OUTPUTS 300 /* room for a heightmap in 16 x 16 tiles beside the other outputs */

typedef struct fb_outputs fb_outputs;

/* A transaction of its own, for a scope (fb.h) to name: anonymous temporary files where the file system
 * allows, standard output's data waiting in /tmp (fb_outputs_use_tmpfile, fb_outputs_tmpdir change
 * them while it is the calling thread's). FB_ERR_NOMEM, or FB_ERR_INTERNAL with 64 transactions in
 * the process already. */
fb_result fb_outputs_create(fb_outputs **out);

/* Removes every temporary file the transaction still holds and frees it. Null-safe; sets *o to NULL. */
void fb_outputs_destroy(fb_outputs **o);

/* Opens a transaction (or a nested level of one). */
void fb_outputs_begin(void);

/* Closes a level. rc != FB_OK aborts the whole transaction (every temporary file removed) and is
 * returned. At the outermost level with rc == FB_OK, renames every output into place; returns
 * FB_ERR_IO (logged) when a rename fails, or FB_ERR_INTERNAL when an output was reserved but never
 * written. */
fb_result fb_outputs_end(fb_result rc);

/* Reserves `path` (what: "output", "preview", "mesh"... for messages) before any work is done: checks
 * that it is not named twice and is not an existing non-regular file, and creates its temporary file.
 * Failures are FB_ERR_USAGE (the command line named a bad target) or FB_ERR_IO (cannot create). */
fb_result fb_output_reserve(const char *path, const char *what);

/* A file descriptor open for writing on path's temporary file, to be written and closed by the caller.
 * Takes a reservation, or reserves the path now. Taking one path twice is FB_ERR_USAGE. */
fb_result fb_output_open(const char *path, const char *what, int *fd);

/* Called by a writer when it has written and closed path's file: rc != FB_OK discards it (and is
 * returned). Inside a transaction the file then waits for fb_outputs_end; outside any, it is its
 * own transaction and is renamed into place now. */
fb_result fb_output_done(const char *path, fb_result rc);

/* fopen-style: fb_output_open and fdopen. */
fb_result fb_output_fopen(const char *path, const char *what, void **file);

/* An anonymous scratch file (no name: gone when closed) in path's folder, open for reading and
 * writing: for data too large for memory that ends up in the output (an EXR's later parts). */
fb_result fb_output_spool(const char *path, void **file);

/* Drops one output from the transaction: its temporary file is removed. Safe on unknown paths. */
void fb_output_discard(const char *path);

/* After the outermost fb_outputs_end succeeded, until the next outermost begin: the outputs it put
 * in place, in order, with what they are and their sizes in bytes. Returns how many (at most max). */
int fb_outputs_written(const char **paths, const char **whats, uint64_t *bytes, int max);

/* The inputs noted so far in the calling thread's open transaction (fb_input_note): their paths and
 * what they were read as, valid until the outermost fb_outputs_end. For a caller that reads in one
 * call and writes in another (the library: a scene loaded, then baked), which notes them again in the
 * second. Returns how many (at most max). */
int fb_inputs_noted(const char **paths, const char **whats, int max);

/* For a signal handler: removes every temporary file of every transaction. Async-signal-safe. */
void fb_outputs_unlink_all(void);

/* For a handler of a signal that ends the run (async-signal-safe, any thread). Outside a commit (of
 * every transaction): removes every temporary file and returns true (the handler then ends the
 * process). During a commit: records the signal and returns false; the commit finishes the whole set (or, when the
 * signal came before its first rename, puts nothing in place) and then raises the signal again,
 * which ends the run like one that came after. */
bool fb_outputs_signal(int sig);

/* Whether the calling thread's transaction's outputs may be anonymous (O_TMPFILE) files (default true).
 * false: always the hidden named temporary file, as on a file system without O_TMPFILE (for tests of
 * that path). */
void fb_outputs_use_tmpfile(bool on);

/* Whether standard output is an output of every run of the calling thread's transaction (default
 * false: only when "-" is reserved or a document claims it): the command line's, whose commands print
 * there. While it is one, an input that is the same file as standard output (`1<> in.exr`,
 * `>> in.exr`) is refused (FB_ERR_USAGE), whichever comes first. */
void fb_outputs_stdout_watch(bool on);

/* The folder where the calling thread's transaction keeps standard output's data ("-") until the
 * commit (the command line passes $TMPDIR); NULL or "": /tmp. A folder that cannot hold it fails the
 * reservation (FB_ERR_IO). */
void fb_outputs_tmpdir(const char *dir);

/* A file the flag writes in one format (ext, ".exr") must be named so (any case), or be "-": any other
 * name (x.png, g.flame, out, /dev/null) is FB_ERR_USAGE naming the flag. */
fb_result fb_output_format(const char *flag, const char *path, const char *ext);

/* Claims standard output for a document the run prints there itself (what: the flag, "--json"), for
 * the transaction: an output "-" is then refused, and the claim is refused (FB_ERR_USAGE, logged)
 * when one was reserved. Outside any transaction it has no effect. */
fb_result fb_output_claim_stdout(const char *what);

/* Notes path as an input of the run (what: its role in messages, "scene", "points"; fd: the open file,
 * or -1 to look the path up): from now until the outermost fb_outputs_end, an output that names the
 * same file (the same device and inode, or the same resolved path where it does not exist) is refused.
 * An output already reserved that names it makes this fail. FB_ERR_USAGE (logged) on a clash. "-",
 * standard input, is no file. Outside any transaction nothing is remembered (there is no run). */
fb_result fb_input_note(const char *path, const char *what, int fd);

#endif
