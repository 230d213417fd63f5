/*
 * fractalbake generators [--json]: every generator class of host/gen/list.c with its command, what
 * it makes, how a plan shares it between tasks, its keys (type, range, default, flag), a small
 * example scene's layers and its stated Vulkan-against-native tolerance. The conformance test
 * (tests/conformance.py) reads the JSON form, so it covers a new generator with no other edit.
 */
#include "command.h"

#include "gen.h"
#include "jsonout.h"
#include "plan.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static json_t *class_json(const fb_gen_class *c)
{
    json_t *keys = json_array();
    for (int i = 0; i < c->nkeys; i++) {
        const fb_keyspec *k = &c->keys[i];
        json_t *o = json_pack("{ssssssss}", "key", k->key, "flag", fb_key_flag(k), "type", fb_ktype_name(k), "help",
                              k->help ? k->help : "");
        if (k->type == FB_K_INT || k->type == FB_K_NUM) {
            json_object_set_new(o, "lo", json_real(k->lo));
            json_object_set_new(o, "hi", json_real(k->hi));
            json_object_set_new(o, "lo_open", json_boolean(k->lo_open));
        }
        if (k->enums) json_object_set_new(o, "enums", json_string(k->enums));
        if (k->def) json_object_set_new(o, "default", json_loads(k->def, JSON_DECODE_ANY, NULL));
        json_array_append_new(keys, o);
    }
    char dflt[128];
    snprintf(dflt, sizeof dflt, "[{\"type\": \"%s\"}]", c->name);
    json_t *example = json_loads(c->example ? c->example : dflt, 0, NULL);
    return json_pack("{sssbsssssosos{sfsf}sb}", "name", c->name, "command", c->synopsis != NULL, "summary",
                     c->summary ? c->summary : "", "share", fb_plan_share_name(c->share), "keys", keys, "example",
                     example ? example : json_null(), "tolerance", "max_abs", c->tolerance.max_abs, "fail_percent",
                     c->tolerance.fail_percent, "tonemap", c->tone != NULL);
}

typedef struct generators_opts {
    fb_arg_list files;
    bool json, help;
} generators_opts;

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake generators [--json]\n"
           "Lists every generator: its command, what it makes and how `fractalbake plan` shares its\n"
           "layers between tasks (bands, points parts or whole); --json adds each one's keys (type,\n"
           "range, default, flag), a small example scene's layers and its Vulkan tolerance.\n");
}

static fb_result run(const fb_cli *cli, void *opts)
{
    (void)cli;
    bool json = ((const generators_opts *)opts)->json;
    if (json) {
        json_t *arr = json_array();
        for (const fb_gen_class *const *c = fb_gen_list; *c; c++) json_array_append_new(arr, class_json(*c));
        char *text = fb_json_dumps(arr, 0);
        json_decref(arr);
        if (!text) return fb_fail(FB_ERR_NOMEM, "out of memory");
        printf("%s\n", text);
        free(text);
        return FB_OK;
    }
    printf("%-12s %-8s %-13s %s\n", "generator", "command", "plan", "makes (- : in scenes only)");
    for (const fb_gen_class *const *c = fb_gen_list; *c; c++)
        printf("%-12s %-8s %-13s %s\n", (*c)->name, (*c)->synopsis ? "yes" : "-", fb_plan_share_name((*c)->share),
               (*c)->summary ? (*c)->summary : "");
    return FB_OK;
}

static const fb_arg flags[] = {
    {FB_ARG_DOCUMENT, "--json", NULL, offsetof(generators_opts, json)},
    {FB_ARG_BOOL, "--help", "-h", offsetof(generators_opts, help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables, .files_off = offsetof(generators_opts, files)};

const fb_command fb_cmd_generators = {
    .name = "generators",
    .usage = "  generators [--json]                the generators, their keys and how a plan shares them\n",
    .opts_size = sizeof(generators_opts),
    .args = &spec,
    .help = help,
    .help_off = offsetof(generators_opts, help),
    .run = run};
