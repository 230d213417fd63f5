/*
 * The commands of the command line, one fb_command each, one file each under host/cli/ (cmd_*.c and
 * the commands with files of their own: generators.c, bench.c). main.c only finds the
 * command, parses its argv with the command's table (args.h) into the command's options struct,
 * runs it, and then commits the outputs, prints the summary and exits.
 */
#ifndef FB_COMMAND_H
#define FB_COMMAND_H

#include "args.h"
#include "env.h"
#include "fb.h"

#include <jansson.h>

typedef struct fb_command fb_command;

/* What main() gives every command. */
typedef struct fb_cli {
    const fb_env *env;       /* read once at start (env.h) */
    const fb_command *self;  /* the command being run */
    const void *data;        /* the command's data (a generator command: its class) */
    json_t **summary;        /* --json: a command sets it (fb_cli_summary); main prints it after the commit */
    bool *quiet_warnings;    /* --quiet: warnings are not shown */
    const char *first_error; /* the first error logged, for commands that report it as data (devices) */
    void (*clear_error)(void);
} fb_cli;

struct fb_command {
    const char *name;
    const char *usage;        /* its lines in `fractalbake --help` (NULL: not listed there) */
    size_t opts_size;         /* the options struct, zeroed, then init() */
    void (*init)(void *opts); /* defaults other than zero, or NULL */
    const fb_argspec *args;
    void (*help)(const fb_cli *cli); /* --help: what to print on stdout */
    size_t help_off;                 /* the options struct's bool set by --help */
    fb_result (*run)(const fb_cli *cli, void *opts);
    /* The exit code of a run that succeeded: 0, or 1 for a comparison beyond its threshold. NULL: 0. */
    int (*exit_code)(const void *opts);
    /* A command that makes many transactions of its own (bench bakes again and again): main does
     * not wrap it in one. */
    bool own_outputs;
};

/* The commands (main.c's table; each defined in its file). */
extern const fb_command fb_cmd_render, fb_cmd_generator, fb_cmd_tonemap, fb_cmd_compare, fb_cmd_plan, fb_cmd_merge,
    fb_cmd_info, fb_cmd_generators, fb_cmd_scene, fb_cmd_devices, fb_cmd_bench;

/* A new --json summary object for `command` (the previous one dropped), owned by main. */
json_t *fb_cli_summary(const fb_cli *cli, const char *command);

/* print callback for text reports: the line and a newline on user (a FILE *) or stdout. */
void fb_cli_print_line(const char *line, void *user);

#endif
