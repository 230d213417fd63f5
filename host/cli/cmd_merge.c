/* `fractalbake merge PARTS... -o OUT.exr`: region files, points parts or task files joined (merge.h). */
#include "cmd_bake.h"

#include "cliout.h"
#include "exrio.h"
#include "merge.h"

#include <string.h>

typedef struct merge_opts {
    fb_arg_list parts;
    const char *out;
    int threads, zip_level;
    uint64_t max_memory;
    bool quiet, json, help;
} merge_opts;

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake merge PART.exr... -o OUT.exr [--threads N] [--zip-level N] [--max-memory SIZE] "
           "[--quiet] [--json]\n"
           "Joins the region files of `fractalbake render --region X,Y,W,H` into the whole image: regions\n"
           "of one bake (same size, channels and scene) that cover it with no overlap. Or adds the N points\n"
           "parts of `render --points-part K/N` (chaos games split by points) into the whole game.\n");
}

static fb_result run(const fb_cli *cli, void *opts)
{
    merge_opts *m = opts;
    if (!m->out) return fb_fail(FB_ERR_USAGE, "merge: -o OUT.exr is required (fractalbake merge PARTS... -o OUT.exr)");
    if (!m->parts.n)
        return fb_fail(FB_ERR_USAGE, "merge: no region files given (fractalbake merge PARTS... -o OUT.exr)");
    if (cli_check_quiet_json(m->quiet, m->json)) return FB_ERR_USAGE;
    double t0 = fb_now();
    fb_result rc = fb_merge(&(fb_merge_desc){.paths = m->parts.v,
                                             .n = m->parts.n,
                                             .out = m->out,
                                             .threads = m->threads,
                                             .zip_level = m->zip_level,
                                             .max_memory = m->max_memory});
    if (!rc && m->json) {
        json_t *sum = fb_cli_summary(cli, "merge"), *in = json_array();
        for (int i = 0; i < m->parts.n; i++) json_array_append_new(in, json_string(m->parts.v[i]));
        json_object_set_new(sum, "parts", in);
        json_object_set_new(sum, "seconds", json_real(fb_now() - t0));
    } else if (!rc && !m->quiet) {
        cli_after("fractalbake: merged %d part%s into %s in %.2f s", m->parts.n, m->parts.n == 1 ? "" : "s", m->out,
                  fb_now() - t0);
    }
    return rc;
}

#define M(f) offsetof(merge_opts, f)
static const fb_arg flags[] = {
    {FB_ARG_OUTPUT, "--output", "-o", M(out), .ext = ".exr"},
    {FB_ARG_INT, "--threads", NULL, M(threads), 1, 1024},
    {FB_ARG_INT, "--zip-level", NULL, M(zip_level), 1, EXRIO_ZIP_LEVEL_MAX},
    {FB_ARG_VALUE, "--max-memory", NULL, M(max_memory), .parse = fb_arg_memory},
    {FB_ARG_BOOL, "--quiet", NULL, M(quiet)},
    {FB_ARG_DOCUMENT, "--json", NULL, M(json)},
    {FB_ARG_BOOL, "--help", "-h", M(help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables, .files_off = M(parts), .max_files = 1 << 30};
#undef M

const fb_command fb_cmd_merge = {
    .name = "merge",
    .usage = "  merge PARTS... -o OUT.exr          join task files (--task), region files (--region) or points\n"
             "                                     parts (--points-part) into the whole bake\n",
    .opts_size = sizeof(merge_opts),
    .args = &spec,
    .help = help,
    .help_off = offsetof(merge_opts, help),
    .run = run};
