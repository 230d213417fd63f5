/* `fractalbake info FILE.exr`: what a file holds (info.h). */
#include "command.h"

#include "info.h"

typedef struct info_opts {
    fb_arg_list files;
    bool json, help;
} info_opts;

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake info FILE.exr [--json]\n"
           "Size, compression, layers and channels with their types, every attribute with its value,\n"
           "and the stored scene (what `render --from FILE.exr` bakes). --json: all of it as one JSON\n"
           "object.\n");
}

static fb_result run(const fb_cli *cli, void *opts)
{
    (void)cli;
    const info_opts *o = opts;
    if (!o->files.n) return fb_fail(FB_ERR_USAGE, "info: expected one EXR file: fractalbake info FILE.exr");
    return fb_info(o->files.v[0], o->json, fb_cli_print_line, stdout);
}

static const fb_arg flags[] = {
    {FB_ARG_DOCUMENT, "--json", NULL, offsetof(info_opts, json)},
    {FB_ARG_IGNORED, "--quiet"}, /* nothing to leave out: the description is the output */
    {FB_ARG_BOOL, "--help", "-h", offsetof(info_opts, help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = offsetof(info_opts, files),
                                .max_files = 1,
                                .too_many = "%s: info takes one EXR file"};

const fb_command fb_cmd_info = {
    .name = "info",
    .usage = "  info FILE.exr                      layers, channels, types, attributes and the stored scene\n",
    .opts_size = sizeof(info_opts),
    .args = &spec,
    .help = help,
    .help_off = offsetof(info_opts, help),
    .run = run};
