/* `fractalbake scene default|FILE.json|-` [--set K=V ...] [--pretty]: the scene with every default
 * filled in, as a bake stores it; what `render --from` and the docs' examples start from. */
#include "command.h"

#include "jsonout.h"
#include "scene.h"

#include <stdlib.h>
#include <string.h>

typedef struct scene_opts {
    fb_arg_list files, sets;
    bool pretty, help;
} scene_opts;

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake scene default|SCENE.json|- [--set KEY.PATH=VALUE ...] [--pretty]\n"
           "Prints the scene with every default filled in, keys sorted, numbers in their shortest form:\n"
           "what a bake stores in its file and `render --from` bakes again. `default` is the embedded\n"
           "default scene, `-` a scene on standard input. One line of JSON, or indented with --pretty:\n"
           "  fractalbake scene default > scene.json\n");
}

static fb_result run(const fb_cli *cli, void *opts)
{
    (void)cli;
    const scene_opts *o = opts;
    if (!o->files.n)
        return fb_fail(FB_ERR_USAGE,
                       "scene: expected default, a scene file or - (fractalbake scene default > scene.json)");
    const char *which = o->files.v[0];
    fb_scene sc = {0};
    fb_result rc = !strcmp(which, "default")
                       ? fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", o->sets.v, o->sets.n, &sc)
                       : fb_scene_load_sets(which, o->sets.v, o->sets.n, &sc);
    if (!rc) {
        json_t *j = json_loads(sc.json, 0, NULL);
        char *text = j ? fb_json_dumps(j, o->pretty ? 2 : 0) : NULL;
        if (text)
            printf("%s\n", text);
        else
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        free(text);
        json_decref(j);
    }
    fb_scene_fini(&sc);
    return rc;
}

static const fb_arg flags[] = {
    {FB_ARG_LIST, "--set", NULL, offsetof(scene_opts, sets)},
    {FB_ARG_BOOL, "--pretty", NULL, offsetof(scene_opts, pretty)},
    {FB_ARG_IGNORED, "--json"},  /* the output is JSON already, */
    {FB_ARG_IGNORED, "--quiet"}, /* and nothing else */
    {FB_ARG_BOOL, "--help", "-h", offsetof(scene_opts, help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = offsetof(scene_opts, files),
                                .max_files = 1,
                                .too_many = "%s: scene takes one scene (default, a file or -)"};

const fb_command fb_cmd_scene = {
    .name = "scene",
    .usage = "  scene default|SCENE.json           a scene with every default filled in (scene default > s.json)\n",
    .opts_size = sizeof(scene_opts),
    .args = &spec,
    .help = help,
    .help_off = offsetof(scene_opts, help),
    .run = run};
