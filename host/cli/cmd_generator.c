/* `fractalbake fbm|julia|...`: a scene of one layer from a generator's flags, baked (one command per
 * generator class that has a synopsis; the class is the command's data). */
#include "cmd_bake.h"

#include "flags.h"
#include "gen.h"

#include <stdlib.h>

typedef struct gen_opts {
    fb_bake_opts bake;
    fb_arg_list files, keys; /* keys: the generator's flags and their values, for fb_scene_from_flags */
} gen_opts;
_Static_assert(offsetof(gen_opts, bake) == 0, "fb_bake_flags' offsets are into fb_bake_opts");

static int key_arity(const void *data, const char *flag)
{
    return fb_scene_flag_arity(((const fb_gen_class *)data)->name, flag);
}

static int key_names(const void *data, const char **out, int max)
{
    return fb_scene_flags(((const fb_gen_class *)data)->name, out, max);
}

static void init(void *opts)
{
    fb_bake_opts_init(&((gen_opts *)opts)->bake);
}

static void help(const fb_cli *cli)
{
    const char *kind = ((const fb_gen_class *)cli->data)->name;
    printf("usage: fractalbake %s [options] -o OUT.exr [--preview OUT.png]\n\noptions (each is also a scene key of "
           "the same name):\n",
           kind);
    fb_scene_print_keys(kind, fb_cli_print_line, stdout);
    printf("\nand the common options of `fractalbake --help`.\n");
}

static fb_result run(const fb_cli *cli, void *opts)
{
    gen_opts *g = opts;
    *cli->quiet_warnings = g->bake.quiet;
    const char *kind = ((const fb_gen_class *)cli->data)->name;
    char *json = NULL;
    fb_scene scene = {0};
    fb_result rc = fb_scene_from_flags(kind, g->keys.n, (char **)g->keys.v, &json);
    if (!rc) rc = fb_scene_parse(json, NULL, &scene);
    if (!rc && !g->bake.out && !g->bake.dry_run)
        rc = fb_fail(FB_ERR_USAGE, "-o: missing output file (fractalbake %s ... -o OUT.exr)", kind);
    if (!rc) rc = fb_cli_bake(cli, kind, &scene, &g->bake);
    fb_scene_fini(&scene);
    free(json);
    return rc;
}

static const fb_arg *const tables[] = {fb_bake_flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = offsetof(gen_opts, files),
                                .arity = key_arity,
                                .names = key_names,
                                .pass_off = offsetof(gen_opts, keys)};

const fb_command fb_cmd_generator = {.name = "(generator)",
                                     .opts_size = sizeof(gen_opts),
                                     .init = init,
                                     .args = &spec,
                                     .help = help,
                                     .help_off = offsetof(gen_opts, bake.help),
                                     .run = run};
