/*
 * fractalbake tonemap: a stored layer re-toned with new tone parameters, given as flags (the work:
 * core/tonemap.h).
 */
#include "command.h"

#include "cliout.h"
#include "flags.h"
#include "gen.h"
#include "tonemap.h"

#include <jansson.h>
#include <stdio.h>
#include <string.h>

/* How many values flag `flag` takes for some re-tonable class (fb_scene_flag_arity), -1 for none. */
static int tone_flag_arity(const char *flag)
{
    for (const fb_gen_class *const *c = fb_gen_list; *c; c++) {
        int a = (*c)->tone ? fb_scene_flag_arity((*c)->name, flag) : -1;
        if (a >= 0) return a;
    }
    return -1;
}

typedef struct tonemap_opts {
    fb_arg_list files, flags; /* flags: the tone flags and their values */
    const char *out, *layer, *preview;
    bool quiet, json, help;
} tonemap_opts;

static void help(const fb_cli *cli)
{
    (void)cli;
    char classes[256];
    fb_tone_classes(classes, sizeof classes);
    printf(
        "usage: fractalbake tonemap IN.exr -o OUT.exr [--preview P.png] [--layer NAME] [--brightness B] [--gamma G]\n"
        "          [--gamma-threshold T] [--vibrancy V] [--highlight-power P] [--palette NAME |\n"
        "          --cosine ... | --stops ...]\n"
        "Recomputes the tone-mapped channels of a layer that stores what its tone map reads (%s\n"
        "layers: R, G, B, A from the density and colour channels) with new tone parameters; the\n"
        "other channels keep their stored values and the layer is not computed again.\n"
        "--layer NAME: which layer (default: the first that can be re-toned).\n"
        "--preview P.png: also a PNG of the re-toned layer, as the bake's --preview draws it alone.\n"
        "--quiet: no summary line; --json: a JSON summary on standard output.\n",
        classes);
}

/* The tone flags read as class c's scene keys (fb_tonemap_desc.tone). */
static fb_result tone_from_flags(const fb_gen_class *c, void *user, char **json)
{
    const tonemap_opts *o = user;
    return fb_scene_from_flags(c->name, o->flags.n, (char **)o->flags.v, json);
}

static fb_result run(const fb_cli *cli, void *opts)
{
    const tonemap_opts *o = opts;
    if (!o->files.n)
        return fb_fail(FB_ERR_USAGE, "tonemap: expected an input EXR (fractalbake tonemap IN.exr -o OUT.exr)");
    if (!o->out) return fb_fail(FB_ERR_USAGE, "-o: missing output file (fractalbake tonemap IN.exr -o OUT.exr)");
    if (cli_check_quiet_json(o->quiet, o->json)) return FB_ERR_USAGE;
    double t0 = fb_now();
    fb_result rc = fb_tonemap(&(fb_tonemap_desc){.in = o->files.v[0],
                                                 .out = o->out,
                                                 .layer = o->layer,
                                                 .preview = o->preview,
                                                 .tone = tone_from_flags,
                                                 .user = (void *)o});
    if (!rc && o->json)
        json_object_set_new(fb_cli_summary(cli, "tonemap"), "seconds", json_real(fb_now() - t0));
    else if (!rc && !o->quiet)
        cli_after("fractalbake: wrote %s (tone-mapped)%s%s in %.2f s", o->out, o->preview ? " and " : "",
                  o->preview ? o->preview : "", fb_now() - t0);
    return rc;
}

static int flag_arity(const void *data, const char *flag)
{
    (void)data;
    return tone_flag_arity(flag);
}

#define T(f) offsetof(tonemap_opts, f)
static const fb_arg flags[] = {
    {FB_ARG_OUTPUT, "--output", "-o", T(out), .ext = ".exr"},
    {FB_ARG_OUTPUT, "--preview", NULL, T(preview), .ext = ".png"},
    {FB_ARG_STRING, "--layer", NULL, T(layer)},
    {FB_ARG_BOOL, "--quiet", NULL, T(quiet)},
    {FB_ARG_DOCUMENT, "--json", NULL, T(json)},
    {FB_ARG_BOOL, "--help", "-h", T(help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = T(files),
                                .max_files = 1,
                                .too_many = "%s: tonemap takes one input file",
                                .arity = flag_arity,
                                .pass_off = T(flags)};

const fb_command fb_cmd_tonemap = {
    .name = "tonemap",
    .usage = "  tonemap IN.exr -o OUT.exr [tone]   re-run a chaos game's tone mapping (no new game)\n",
    .opts_size = sizeof(tonemap_opts),
    .args = &spec,
    .help = help,
    .help_off = T(help),
    .run = run};
#undef T
