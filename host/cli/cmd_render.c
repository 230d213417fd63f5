/* `fractalbake render`: every layer of a scene (a file, standard input, the embedded default or the
 * scene a file stored) in one EXR. */
#include "cmd_bake.h"

#include "exrio.h"
#include "plan.h"

#include <stdlib.h>
#include <string.h>

typedef struct render_opts {
    fb_bake_opts bake;
    fb_arg_list files, sets, from;
    char *layer_kinds; /* --from an auto file: where its layers ran (bake.layer_kinds) */
} render_opts;
_Static_assert(offsetof(render_opts, bake) == 0, "fb_bake_flags' offsets are into fb_bake_opts");

/* The scene stored in a file fractalbake wrote, its backend (for auto, where each layer ran, in
 * *kinds), and what part of a bake the file is: a region, a points part, or task[0]/task[1] of a plan
 * with *startup (render --task). */
static fb_result stored_scene(const char *path, char **json, fb_backend *backend, char **kinds, int region[4],
                              int points_part[2], int task[2], double *startup)
{
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return rc;
    const char *tk = exrio_attr_string(r, "fractalbake/task"), *plan = exrio_attr_string(r, "fractalbake/plan");
    if (tk) {
        json_t *pj = plan ? json_loads(plan, 0, NULL) : NULL;
        char *end;
        long k = strtol(tk, &end, 10), n = *end == '/' ? strtol(end + 1, &end, 10) : 0;
        if (*end || k < 0 || n < 1 || k >= n || n > FB_PLAN_MAX_TASKS ||
            !json_is_number(json_object_get(pj, "startup")))
            rc =
                fb_fail(FB_ERR_INPUT, "%s: malformed attributes fractalbake/task \"%s\" or fractalbake/plan", path, tk);
        else
            task[0] = (int)k, task[1] = (int)n, *startup = json_number_value(json_object_get(pj, "startup"));
        json_decref(pj);
        exrio_close(&r);
        if (rc) return rc;
        if ((rc = exrio_open(path, &r))) return rc;
    }
    const char *text = exrio_attr_string(r, "fractalbake/scene");
    const char *be = exrio_attr_string(r, "fractalbake/backend");
    const char *reg = tk ? NULL : exrio_attr_string(r, "fractalbake/region"); /* a task's come from its plan */
    const char *pp = tk ? NULL : exrio_attr_string(r, "fractalbake/points-part");
    if (pp && !fb_parse_points_part(pp, points_part))
        rc = fb_fail(FB_ERR_INPUT, "%s: malformed attribute fractalbake/points-part \"%s\"", path, pp);
    if (reg && !fb_parse_region(reg, region))
        rc = fb_fail(FB_ERR_INPUT, "%s: malformed attribute fractalbake/region \"%s\"", path, reg);
    if (rc)
        ;
    else if (!text)
        rc = fb_fail(FB_ERR_INPUT, "%s: no stored scene (attribute fractalbake/scene): not baked by fractalbake", path);
    else if (!(*json = strdup(text)))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    *backend = be && !strcmp(be, "native")   ? FB_BACKEND_NATIVE
               : be && !strcmp(be, "vulkan") ? FB_BACKEND_VULKAN
                                             : FB_BACKEND_AUTO;
    const char *per_layer = exrio_attr_string(r, "fractalbake/layer-backends");
    if (!rc && *backend == FB_BACKEND_AUTO && per_layer && !(*kinds = strdup(per_layer)))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    exrio_close(&r);
    return rc;
}

/* --from OLD.exr: the stored scene with --set applied, the part of a bake the file was, its backend. */
static fb_result from_file(render_opts *r, fb_scene *scene)
{
    fb_bake_opts *o = &r->bake;
    char *json = NULL, origin[1100];
    fb_backend stored = FB_BACKEND_AUTO;
    int region[4] = {0}, part[2] = {0}, task[2] = {0};
    double startup = 0;
    const char *from = r->from.v[0];
    fb_result rc = stored_scene(from, &json, &stored, &r->layer_kinds, region, part, task, &startup);
    if (!rc && o->region[2] == 0 && o->points_part[1] == 0 && o->task[1] == 0) {
        memcpy(o->region, region, sizeof region);
        memcpy(o->points_part, part, sizeof part);
        memcpy(o->task, task, sizeof task);
        if (task[1]) o->task_startup = startup;
    }
    snprintf(origin, sizeof origin, "%s (stored scene)", from);
    /* A file from elsewhere must not choose what this run writes: its layers' output paths go, and
     * --set puts back the ones the user names. */
    char *kept = NULL, dropped[2048];
    if (!rc) rc = fb_scene_drop_outputs(json, &kept, dropped, sizeof dropped);
    if (!rc && dropped[0])
        fb_log(FB_LOG_WARN, "--from %s: not writing the stored scene's outputs (%s); name them with --set", from,
               dropped);
    if (!rc) rc = fb_scene_parse_sets(kept, origin, r->sets.v, r->sets.n, scene);
    free(kept);
    if (o->backend == FB_BACKEND_AUTO) { /* the file's backend; for auto, each layer where it ran */
        o->backend = stored, o->backend_from = stored != FB_BACKEND_AUTO;
        o->layer_kinds = r->layer_kinds;
    }
    free(json);
    return rc;
}

static fb_result run(const fb_cli *cli, void *opts)
{
    render_opts *r = opts;
    *cli->quiet_warnings = r->bake.quiet;
    const char *scene_path = r->files.n ? r->files.v[0] : NULL;
    if (!r->bake.out) r->bake.out = "fractalbake.exr";
    fb_scene scene = {0};
    fb_result rc;
    const char *from = r->from.n ? r->from.v[0] : NULL;
    if (r->from.n > 1)
        rc = fb_fail(FB_ERR_USAGE, "--from: only one --from may be given");
    else if (from && scene_path)
        rc = fb_fail(FB_ERR_USAGE, "--from %s: give either a scene file or --from, not both", from);
    else if (from)
        rc = from_file(r, &scene);
    else if (scene_path)
        rc = fb_scene_load_sets(scene_path, r->sets.v, r->sets.n, &scene);
    else
        rc = fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", r->sets.v, r->sets.n, &scene);
    if (!rc) rc = fb_cli_bake(cli, "render", &scene, &r->bake);
    fb_scene_fini(&scene);
    free(r->layer_kinds);
    return rc;
}

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake render [SCENE.json | --from OLD.exr] [--set KEY.PATH=VALUE ...] [-o OUT.exr]\n"
           "                          [--preview OUT.png [--preview-layer NAME|over]]\n"
           "Bakes every layer of the scene into one EXR. Without SCENE.json, bakes the embedded default scene\n"
           "(a night sky, a refined terrain and a plant population). --from bakes the scene stored in a file\n"
           "fractalbake wrote, on the backend that wrote it unless --backend is given: the same pixels.\n"
           "--set overrides one key before validation: size=2048x1024, seed=9, layers.sky.c=-0.8,0.156,\n"
           "layers.1.insert=5000 (a list element by index or by layer name; lists comma-separated).\n"
           "Default output: fractalbake.exr in the current folder.\n");
}

static void init(void *opts)
{
    fb_bake_opts_init(&((render_opts *)opts)->bake);
}

static const fb_arg render_flags[] = {
    {FB_ARG_LIST, "--set", NULL, offsetof(render_opts, sets)},
    {FB_ARG_LIST, "--from", NULL, offsetof(render_opts, from)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {fb_bake_flags, render_flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = offsetof(render_opts, files),
                                .max_files = 1,
                                .too_many = "%s: only one scene file may be given"};

const fb_command fb_cmd_render = {
    .name = "render",
    .usage = "  render [SCENE.json] [-o OUT.exr]   bake every layer of a scene (no scene: the embedded default);\n"
             "         [--from OLD.exr] [--set K=V]  or the scene stored in a file; override keys\n",
    .opts_size = sizeof(render_opts),
    .init = init,
    .args = &spec,
    .help = help,
    .help_off = offsetof(render_opts, bake.help),
    .run = run};
