/* `fractalbake plan`: how render --task K/N splits a bake (plan.h). */
#include "cmd_bake.h"

#include "gen.h"
#include "plan.h"
#include "sequence.h"

#include <stdlib.h>
#include <string.h>

typedef struct plan_opts {
    fb_arg_list files, sets;
    int ntasks;
    double startup; /* < 0: the default */
    bool json, help;
} plan_opts;

static void init(void *opts)
{
    ((plan_opts *)opts)->startup = -1;
}

static void help(const fb_cli *cli)
{
    (void)cli;
    char by_share[3][256];
    for (int k = 0; k < 3; k++) by_share[k][0] = 0;
    for (const fb_gen_class *const *c = fb_gen_list; *c; c++) {
        char *o = by_share[(*c)->share];
        snprintf(o + strlen(o), 256 - strlen(o), "%s%s", *o ? ", " : "", (*c)->name);
    }
    printf("usage: fractalbake plan [SCENE.json|-] --tasks N [--set KEY.PATH=VALUE ...] [--task-startup S]\n"
           "                        [--json]\n"
           "Splits a bake into N tasks of about equal cost: per-pixel layers (%s) into bands of rows,\n"
           "chaos games (%s) into points parts, and layers whose cost does not shrink with a band\n"
           "(%s, a layer writing a heightmap, and the layers using them) whole, each in one task.\n"
           "Costs come from a model of each generator (seconds of one core).\n"
           "Tasks count from 0, like SLURM_ARRAY_TASK_ID; the plan uses the fewest that keep the tasks'\n"
           "total within 10%% of one bake, so with small bakes the last tasks may have nothing to do.\n"
           "--task-startup S: each task's start-up the plan assumes (default 0.07 s, measured with\n"
           "lavapipe; 0: every task that shortens the longest); give the same to each render --task.\n"
           "Each task: fractalbake render SCENE.json --task K/N -o part-K.exr; then\n"
           "fractalbake merge part-*.exr -o OUT.exr checks the set is complete and joins it.\n"
           "Without SCENE.json, the embedded default scene.\n",
           by_share[FB_SHARE_BAND], by_share[FB_SHARE_POINTS], by_share[FB_SHARE_WHOLE]);
}

/* A sequence's plan: each task's frames (render --task K/N bakes them, whole, in order). */
static fb_result print_frames(const fb_scene *sc, const fb_frames *fr, int ntasks, bool json)
{
    json_t *tasks = json ? json_array() : NULL;
    if (!json)
        printf("plan: a sequence of %ld frames (%ld to %ld by %ld), %d x %d, over %d task%s (numbered from 0, like "
               "SLURM_ARRAY_TASK_ID)\n\n%-6s %s\n",
               fb_frames_count(fr), fr->first, fr->last, fr->step, sc->width, sc->height, ntasks,
               ntasks == 1 ? "" : "s", "task", "frames");
    for (int k = 0; k < ntasks; k++) {
        long i0, i1;
        fb_frames_share(fr, k, ntasks, &i0, &i1);
        long a = fr->first + i0 * fr->step, b = fr->first + (i1 - 1) * fr->step;
        if (json)
            json_array_append_new(tasks, i1 > i0 ? json_pack("{sisIsIsI}", "task", k, "first", (json_int_t)a, "last",
                                                             (json_int_t)b, "frames", (json_int_t)(i1 - i0))
                                                 : json_pack("{sisI}", "task", k, "frames", (json_int_t)0));
        else if (i1 > i0)
            printf("%-6d %ld to %ld (%ld frame%s)\n", k, a, b, i1 - i0, i1 - i0 == 1 ? "" : "s");
        else
            printf("%-6d nothing: fewer frames than tasks\n", k);
    }
    if (json) {
        json_t *doc = json_pack("{sIsIsIso}", "first", (json_int_t)fr->first, "last", (json_int_t)fr->last, "step",
                                (json_int_t)fr->step, "tasks", tasks);
        char *text = doc ? json_dumps(doc, JSON_COMPACT) : NULL;
        json_decref(doc);
        if (!text) return fb_fail(FB_ERR_NOMEM, "out of memory");
        printf("%s\n", text);
        free(text);
    }
    return FB_OK;
}

static fb_result run(const fb_cli *cli, void *opts)
{
    (void)cli;
    const plan_opts *o = opts;
    if (o->ntasks == 0)
        return fb_fail(FB_ERR_USAGE, "plan: --tasks N is required (fractalbake plan SCENE.json --tasks 8)");
    fb_scene *sc = calloc(1, sizeof *sc);
    fb_plan *p = malloc(sizeof *p);
    fb_result rc = !sc || !p ? fb_fail(FB_ERR_NOMEM, "out of memory")
                   : o->files.n
                       ? fb_scene_load_sets(o->files.v[0], o->sets.v, o->sets.n, sc)
                       : fb_scene_parse_sets(fb_scene_default_json(), "(default scene)", o->sets.v, o->sets.n, sc);
    bool seq = false;
    fb_frames fr;
    if (!rc) rc = fb_scene_frames(sc, &seq, &fr);
    if (!rc && seq) {
        rc = print_frames(sc, &fr, o->ntasks, o->json);
    } else if (!rc && !(rc = fb_plan_make(sc, o->ntasks, o->startup, p)) && o->json) {
        char *text = fb_plan_json(sc, p, true);
        if (text)
            printf("%s\n", text);
        else
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        free(text);
    } else if (!rc) {
        printf("plan: %d x %d, %d layer%s over %d task%s (numbered from 0, like SLURM_ARRAY_TASK_ID)\n", sc->width,
               sc->height, sc->nlayers, sc->nlayers == 1 ? "" : "s", o->ntasks, o->ntasks == 1 ? "" : "s");
        printf("\n%-20s %-10s %-13s %10s\n", "layer", "type", "split", "model s");
        for (int i = 0; i < sc->nlayers; i++)
            printf("%-20s %-10s %-13s %10.3f\n", sc->layers[i].name, sc->layers[i].cls->name,
                   fb_plan_share_name(p->share[i]), p->layer_seconds[i]);
        printf("\n%-6s %-56s %10s\n", "task", "share", "model s");
        for (int k = 0; k < p->nactive; k++) {
            char d[2048];
            fb_plan_describe(sc, &p->tasks[k], d, sizeof d);
            printf("%-6d %-56s %10.3f\n", k, d, p->tasks[k].seconds);
        }
        if (p->nactive < o->ntasks)
            printf("%d-%-4d nothing: more tasks would not shorten the longest within 10%% of one bake's cost\n",
                   p->nactive, o->ntasks - 1);
        printf("\none bake %.2f s; the %d task%s %.2f s in all (%.2fx), the longest %.2f s (%.1fx sooner)\n", p->one,
               p->nactive, p->nactive == 1 ? "" : "s", p->total, p->total / p->one, p->longest, p->one / p->longest);
        printf("(model seconds of one core of the reference machine; docs/scenes.md)\n");
    }
    if (sc) fb_scene_fini(sc);
    free(sc);
    free(p);
    return rc;
}

static const fb_arg flags[] = {
    {FB_ARG_LIST, "--set", NULL, offsetof(plan_opts, sets)},
    {FB_ARG_INT, "--tasks", NULL, offsetof(plan_opts, ntasks), 1, FB_PLAN_MAX_TASKS},
    {FB_ARG_VALUE, "--task-startup", NULL, offsetof(plan_opts, startup), .parse = fb_arg_seconds},
    {FB_ARG_DOCUMENT, "--json", NULL, offsetof(plan_opts, json)},
    {FB_ARG_IGNORED, "--quiet"}, /* it prints the plan and nothing else */
    {FB_ARG_BOOL, "--help", "-h", offsetof(plan_opts, help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = offsetof(plan_opts, files),
                                .max_files = 1,
                                .too_many = "%s: only one scene file may be given"};

const fb_command fb_cmd_plan = {
    .name = "plan",
    .usage = "  plan [SCENE.json] --tasks N        split a bake into N tasks of about equal cost (render --task)\n",
    .opts_size = sizeof(plan_opts),
    .init = init,
    .args = &spec,
    .help = help,
    .help_off = offsetof(plan_opts, help),
    .run = run};
