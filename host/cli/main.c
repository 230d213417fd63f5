/*
 * fractalbake: the command line's entry. It finds the command in the table (command.h), reads its
 * argv with the command's flag table (args.h), runs it, commits every file it wrote together
 * (output.h), prints the --json summary and exits: 0 ok, 1 comparison beyond threshold, 2 bad usage
 * or input, 3 runtime failure. The log sink and the signals (cliout.h) are installed here.
 */
#include "command.h"

#include "cliout.h"
#include "env.h"
#include "exrio.h"
#include "gen.h"
#include "jsonout.h"
#include "output.h"
#include "progress.h"

#include <jansson.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The first error is the one line the user sees; warnings are shown as they come. */
static char g_first_error[2048];
static bool g_quiet_warnings;

/* --json: the command's summary, printed on standard output by main() once its outputs are in
 * place, with what was written ("outputs": path, what, bytes) added. */
static json_t *g_summary;
/* The environment, read once when the program starts (env.h), for every engine a command opens. */
static fb_env g_env;

/* The commands, in the order `fractalbake --help` lists them; a generator's command comes from its
 * class (fb_cmd_generator with the class as data), after render. */
static const fb_command *const k_commands[] = {&fb_cmd_render,  &fb_cmd_tonemap, &fb_cmd_compare,    &fb_cmd_plan,
                                               &fb_cmd_merge,   &fb_cmd_info,    &fb_cmd_generators, &fb_cmd_scene,
                                               &fb_cmd_devices, &fb_cmd_bench};

json_t *fb_cli_summary(const fb_cli *cli, const char *command)
{
    json_decref(*cli->summary);
    *cli->summary = json_object();
    json_object_set_new(*cli->summary, "command", json_string(command));
    return *cli->summary;
}

void fb_cli_print_line(const char *line, void *user)
{
    fprintf(user ? (FILE *)user : stdout, "%s\n", line);
}

static void sink(int level, const char *msg, void *user)
{
    (void)user;
    if (level == FB_LOG_ERROR) {
        if (!g_first_error[0]) snprintf(g_first_error, sizeof g_first_error, "%s", msg);
    } else if (level == FB_LOG_WARN && !g_quiet_warnings) {
        fprintf(stderr, "fractalbake: warning: %s\n", msg);
    }
}

static void clear_error(void)
{
    g_first_error[0] = 0;
}

/* Progress lines and bars (progress.h) go to stderr. */
static void progress_sink(const char *text, void *user)
{
    (void)user;
    fputs(text, stderr);
    fflush(stderr);
}

static int finish(fb_result rc)
{
    if (rc) fprintf(stderr, "fractalbake: %s\n", g_first_error[0] ? g_first_error : fb_result_string(rc));
    return fb_result_exit_code(rc);
}

_Static_assert(EXRIO_ZIP_LEVEL_MAX == 12, "the usage's --zip-level line says 1..12");

static const char *const k_usage =
    "usage: fractalbake COMMAND [options]\n"
    "\n"
    "commands:\n"
    "%s" /* a line or two per command */
    "\n"
    "common options:\n"
    "  -o, --output FILE     output EXR (written to a temporary file, renamed when complete)\n"
    "  --preview FILE.png    also write a PNG preview (grey, colour or hillshade, as the layer suits)\n"
    "  --preview-layer L     the layer it shows; `all`: a contact sheet, a labelled tile per layer; or\n"
    "                        `over`: every layer composited back to front by its coverage A (the\n"
    "                        default for scenes of several layers)\n"
    "  --cube-faces PATTERN  a cube environment map's six faces also as files for engines' six-sided\n"
    "                        skyboxes: PATTERN holds {unity} (_front _back _left _right _up _down) or\n"
    "                        {source} (ft bk lf rt up dn) and ends in .exr (every channel) or .png\n"
    "                        (colour); sky{unity}.exr -> sky_front.exr ... (docs/sky.md)\n"
    "  --backend B           auto | vulkan | native (default auto: a GPU when there is one; on lavapipe,\n"
    "                        each layer where it is faster (see `fractalbake devices`); else native)\n"
    "  --device D            Vulkan device index or name substring (see `fractalbake devices`)\n"
    "  --threads N           native threads, EXR compression threads and lavapipe's own compute\n"
    "                        threads (LP_NUM_THREADS) (default: all cores)\n"
    "  --strip-rows N        rows of a piece (default: sized for the device; no effect on the result)\n"
    "  --region X,Y,W,H      bake only these pixels (the same as in the full bake) into a region file;\n"
    "                        `fractalbake merge` joins region files into the whole image\n"
    "  --points-part K/N     bake the K-th of N shares of every chaos game's points (the other\n"
    "                        layers whole); `fractalbake merge` adds the N parts' hits exactly\n"
    "  --task K/N            bake task K (from 0, like SLURM_ARRAY_TASK_ID) of the N of `fractalbake plan`:\n"
    "                        only its share (a band, points parts or whole layers); merge joins the N\n"
    "  --task-startup S      the start-up of a task the plan assumes (default 0.07 s; 0: use every task\n"
    "                        that shortens the longest); give the same to plan, every task and merge\n"
    "  --zip-level N         deflate level of ZIP compression, 1 (fastest) to 12 (smallest) (default 1)\n"
    "  --dry-run             print the predicted peak memory per layer, bake nothing, write nothing\n"
    "  --max-memory SIZE     stop before allocating when the predicted peak is larger (8G, 512M, 50%;\n"
    "                        default 80% of this machine's memory)\n"
    "  --validation          enable VK_LAYER_KHRONOS_validation (also FB_VK_VALIDATION=1)\n"
    "  -q, --quiet           no progress bar, no warnings, no summary line\n"
    "  --json                one JSON object on stdout when done: what was written (paths, sizes),\n"
    "                        the time, each layer's backend and summary (terrain: points, stages)\n"
    "  --help, --version\n"
    "\n"
    "exit codes: 0 success, 1 comparison beyond threshold, 2 bad usage or input, 3 runtime failure\n";

/* The top-level help: the commands' lines (a generator's after render), then the common options. */
static void print_usage(FILE *f)
{
    const char *at = strstr(k_usage, "%s");
    fwrite(k_usage, 1, (size_t)(at - k_usage), f);
    for (size_t c = 0; c < sizeof k_commands / sizeof k_commands[0]; c++) {
        if (k_commands[c]->usage) fputs(k_commands[c]->usage, f);
        for (int i = 0; c == 0 && fb_gen_list[i]; i++)
            if (fb_gen_list[i]->synopsis) fprintf(f, "  %-34s %s\n", fb_gen_list[i]->synopsis, fb_gen_list[i]->summary);
    }
    fputs(at + 2, f);
}

/* Finds the command, reads its argv, runs it; the exit code. */
static int run_command(int argc, char **argv)
{
    if (argc < 2) {
        print_usage(stderr);
        return 2;
    }
    const char *name = argv[1];
    if (!strcmp(name, "--help") || !strcmp(name, "-h") || !strcmp(name, "help")) {
        print_usage(stdout);
        return 0;
    }
    if (!strcmp(name, "--version")) {
        printf("fractalbake %s\n", FB_VERSION);
        return 0;
    }
    const fb_command *cmd = NULL;
    const void *data = NULL;
    for (size_t c = 0; c < sizeof k_commands / sizeof k_commands[0] && !cmd; c++)
        if (!strcmp(name, k_commands[c]->name)) cmd = k_commands[c];
    const fb_gen_class *gen = cmd ? NULL : fb_gen_find(name);
    if (gen && gen->synopsis) cmd = &fb_cmd_generator, data = gen;
    if (!cmd) { /* "; did you mean render?" from the table and the generators with a command */
        const char *cands[sizeof k_commands / sizeof k_commands[0] + 64];
        int n = 0;
        for (size_t c = 0; c < sizeof k_commands / sizeof k_commands[0]; c++) cands[n++] = k_commands[c]->name;
        for (int i = 0; fb_gen_list[i] && n < (int)(sizeof cands / sizeof cands[0]); i++)
            if (fb_gen_list[i]->synopsis) cands[n++] = fb_gen_list[i]->name;
        const char *near = fb_closest(name, cands, n);
        fprintf(stderr, "fractalbake: %s: unknown command%s%s%s (see fractalbake --help)\n", name,
                near ? "; did you mean " : "", near ? near : "", near ? "?" : "");
        return 2;
    }
    fb_cli cli = {.env = &g_env,
                  .self = cmd,
                  .data = data,
                  .summary = &g_summary,
                  .quiet_warnings = &g_quiet_warnings,
                  .first_error = g_first_error,
                  .clear_error = clear_error};
    void *opts = calloc(1, cmd->opts_size);
    if (!opts) return finish(fb_fail(FB_ERR_NOMEM, "out of memory"));
    if (cmd->init) cmd->init(opts);
    fb_result rc = fb_args_parse(cmd->args, name, data, argc - 2, argv + 2, opts);
    int code;
    if (!rc && *(bool *)((char *)opts + cmd->help_off)) {
        cmd->help(&cli);
        code = 0;
    } else {
        if (!rc) rc = cmd->run(&cli, opts);
        code = rc ? finish(rc) : cmd->exit_code ? cmd->exit_code(opts) : 0;
    }
    fb_args_free(cmd->args, opts);
    free(opts);
    return code;
}

static bool own_outputs(int argc, char **argv)
{
    for (size_t c = 0; argc >= 2 && c < sizeof k_commands / sizeof k_commands[0]; c++)
        if (!strcmp(argv[1], k_commands[c]->name)) return k_commands[c]->own_outputs;
    return false;
}

/* The habits of other command lines, spelled the one way the commands read: --flag=value becomes
 * --flag value (the value may hold '='s: --set=layers.sky.c=0,1), -q is --quiet, `help CMD` is
 * CMD --help. A new argv; the strings are argv's own or the split copies (kept for the process). */
static char **g_args;  /* the normalised argv, freed when main returns */
static char **g_split; /* the "--flag" halves it allocated */
static int g_nsplit;

static void free_args(void)
{
    for (int i = 0; i < g_nsplit; i++) free(g_split[i]);
    free(g_split);
    free(g_args);
}

static char **normalise_args(int *argc, char **argv)
{
    char **out = g_args = calloc((size_t)*argc * 2 + 2, sizeof *out);
    g_split = calloc((size_t)*argc + 1, sizeof *g_split);
    if (!out || !g_split) {
        free(out), free(g_split);
        g_args = g_split = NULL;
        return argv;
    }
    int n = 0;
    for (int i = 0; i < *argc; i++) {
        const char *a = argv[i], *eq = strchr(a, '=');
        if (i == 1 && !strcmp(a, "help") && *argc > 2) { /* help CMD */
            out[n++] = argv[2];
            out[n++] = "--help";
            i = 2;
            continue;
        }
        if (i > 0 && !strcmp(a, "-q")) {
            out[n++] = "--quiet";
        } else if (i > 0 && !strncmp(a, "--", 2) && eq && eq > a + 2 && (out[n] = strndup(a, (size_t)(eq - a)))) {
            g_split[g_nsplit++] = out[n++];
            out[n++] = (char *)eq + 1;
        } else {
            out[n++] = argv[i];
        }
    }
    *argc = n;
    return out;
}

int main(int argc, char **argv)
{
    cli_start();
    fb_log_set_sink(sink, NULL);
    fb_progress_set_sink(&(fb_progress_sink){.terminal = isatty(STDERR_FILENO), .write = progress_sink});
    fb_env_read(&g_env);
    fb_outputs_tmpdir(g_env.tmpdir);
    fb_outputs_stdout_watch(true); /* every command prints there: no input may be standard output's file */
    argv = normalise_args(&argc, argv);
    if (own_outputs(argc, argv)) {
        int code = run_command(argc, argv);
        fb_result out = cli_stdout_finish();
        if (out && code == 0) code = finish(out);
        free_args();
        return code;
    }
    /* Every file the command writes is renamed into place here, together, or none is (output.h).
     * A comparison beyond threshold (1) still writes its diff pictures. */
    fb_outputs_begin();
    int code = run_command(argc, argv);
    g_first_error[0] = 0;
    fb_result rc = fb_outputs_end(code == 0 || code == 1 ? FB_OK : FB_ERR_INTERNAL);
    if (rc && (code == 0 || code == 1)) code = finish(rc);
    cli_after_flush(code == 0 || code == 1); /* "wrote ...": now that it is true */
    if (g_summary && code == 0) {            /* --json: the summary, now that the outputs are in place */
        const char *paths[FB_MAX_OUTPUTS], *whats[FB_MAX_OUTPUTS];
        uint64_t bytes[FB_MAX_OUTPUTS];
        int n = fb_outputs_written(paths, whats, bytes, FB_MAX_OUTPUTS);
        json_t *outs = json_array();
        for (int i = 0; i < n; i++)
            json_array_append_new(
                outs, json_pack("{sssssI}", "path", paths[i], "what", whats[i], "bytes", (json_int_t)bytes[i]));
        json_object_set_new(g_summary, "outputs", outs);
        char *text = fb_json_dumps(g_summary, 0);
        if (text) printf("%s\n", text);
        free(text);
    }
    json_decref(g_summary);
    g_first_error[0] = 0;
    fb_result out = cli_stdout_finish();
    if (out && (code == 0 || code == 1)) code = finish(out);
    free_args();
    return code;
}
