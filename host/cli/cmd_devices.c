/* `fractalbake devices`: the Vulkan devices found, and which one a bake chooses. */
#include "command.h"

#include "jsonout.h"
#include "probe.h"
#include "vkc.h"

#include <stdlib.h>
#include <string.h>

typedef struct devices_opts {
    fb_arg_list files;
    const char *device;
    bool json, help;
} devices_opts;

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake devices [--device D] [--json]\n"
           "Lists the Vulkan devices (index, name, type, memory, subgroup size, driver), marks the one\n"
           "fractalbake chooses (with --device D: the one D names), and says what --backend auto does.\n"
           "On the chosen device, a probe shader says whether fp32 subnormals are kept or flushed; with\n"
           "FB_VK_VALIDATION=1 the validation layer watches it, and a message (or a layer that is not\n"
           "installed) fails the command (exit 3).\n"
           "--json: the same as one JSON object.\n");
}

/* The chosen device opened as a bake opens it (the environment's options), the subnormal probe run
 * on it; *validation says what the validation layer did: "off" (not asked for), "silent", or
 * FB_ERR_VULKAN when it is asked for and missing or has spoken. */
static fb_result probe(const fb_cli *cli, const char *device, fb_denormals *dn, const char **validation)
{
    vkc_desc desc = cli->env->vk;
    desc.device = device;
    vkc_context *vk = NULL;
    fb_result rc = vkc_create(&desc, &vk);
    if (rc) return rc;
    rc = fb_denormals_probe(vk, dn);
    *validation = desc.validation ? "silent" : "off";
    if (!rc && desc.validation && !vkc_validation_enabled(vk))
        rc = fb_fail(FB_ERR_VULKAN, "FB_VK_VALIDATION=1 but VK_LAYER_KHRONOS_validation is not installed");
    else if (!rc && vkc_validation_messages(vk))
        rc = fb_fail(FB_ERR_VULKAN, "vulkan validation reported %u message(s) on the probe (see above)",
                     vkc_validation_messages(vk));
    vkc_destroy(&vk);
    return rc;
}

static fb_result run(const fb_cli *cli, void *opts)
{
    const devices_opts *d = opts;
    vkc_device_info *infos = NULL;
    int n = 0;
    fb_result rc = vkc_enumerate(d->device, &infos, &n);
    if (rc == FB_ERR_NODEVICE) {
        if (d->json) {
            json_t *o = json_pack("{s[]sssisssi}", "devices", "reason", cli->first_error, "native_threads",
                                  fb_cpu_count(), "auto", "native", "chosen", -1);
            char *t = fb_json_dumps(o, 0);
            printf("%s\n", t ? t : "{}");
            free(t);
            json_decref(o);
        } else {
            printf("no Vulkan device: %s\nfractalbake will use the native backend (%d threads).\n", cli->first_error,
                   fb_cpu_count());
        }
        cli->clear_error();
        return FB_OK;
    }
    if (rc) return rc;
    fb_denormals dn = {0};
    const char *validation = "off";
    rc = probe(cli, d->device, &dn, &validation);
    if (rc) {
        free(infos);
        return rc;
    }
    if (d->json) {
        json_t *o = json_object(), *list = json_array();
        int chosen = -1;
        for (int i = 0; i < n; i++) {
            json_array_append_new(list,
                                  json_pack("{sisssssIsiss}", "index", i, "name", infos[i].name, "type", infos[i].type,
                                            "memory_bytes", (json_int_t)infos[i].memory, "subgroup_size",
                                            (int)infos[i].subgroup_size, "driver", infos[i].driver));
            char arith[256];
            vkc_arith_describe(&infos[i], arith, sizeof arith);
            json_object_set_new(json_array_get(list, (size_t)i), "arithmetic", json_string(arith));
            if (infos[i].chosen) chosen = i;
        }
        json_object_set_new(o, "devices", list);
        json_object_set_new(o, "chosen", json_integer(chosen));
        if (chosen >= 0)
            json_object_set_new(json_array_get(list, (size_t)chosen), "subnormals",
                                json_pack("{sssIsI}", "fp32", dn.verdict, "product_bits", (json_int_t)dn.product,
                                          "operand_bits", (json_int_t)dn.operand));
        json_object_set_new(o, "validation", json_string(validation));
        json_object_set_new(o, "native_threads", json_integer(fb_cpu_count()));
        /* what --backend auto does with the chosen device */
        json_object_set_new(o, "auto",
                            json_string(chosen < 0                           ? "native"
                                        : !strcmp(infos[chosen].type, "cpu") ? "per layer"
                                                                             : "device"));
        char *t = fb_json_dumps(o, 0);
        printf("%s\n", t ? t : "{}");
        free(t);
        json_decref(o);
        free(infos);
        return FB_OK;
    }
    printf("%-3s %-3s %-34s %-10s %-10s %-8s %s\n", "#", "use", "name", "type", "memory", "subgroup", "driver");
    for (int i = 0; i < n; i++)
        printf("%-3d %-3s %-34s %-10s %-10.0f %-8u %s\n", i, infos[i].chosen ? "*" : "", infos[i].name, infos[i].type,
               (double)infos[i].memory / (1024.0 * 1024.0), infos[i].subgroup_size, infos[i].driver);
    printf("(memory in MiB; * marks the device fractalbake chooses%s)\n", d->device ? " for --device" : "");
    for (int i = 0; i < n; i++) {
        if (!infos[i].chosen) continue;
        char arith[256];
        vkc_arith_describe(&infos[i], arith, sizeof arith);
        printf("arithmetic on %s: %s\n", infos[i].name, arith);
        printf("fp32 subnormals on %s, measured: %s (2^-126 * 0.5 = 0x%08x, 2^-140 * 2^20 = 0x%08x; kept: "
               "0x00400000, 0x03800000)\n",
               infos[i].name, dn.verdict, dn.product, dn.operand);
        printf("validation layer: %s\n",
               !strcmp(validation, "off") ? "off (FB_VK_VALIDATION=1 turns it on)" : "on, silent");
        if (!strcmp(infos[i].type, "cpu"))
            printf("--backend auto (the default): %s is a CPU implementation of Vulkan, so each layer runs where it\n"
                   "is faster on this machine: the native C path (fBm with its AVX2 loop, float Julia sets with\n"
                   "AVX2, other Julia sets below about 8 million samples or with turbulence, the chaos game,\n"
                   "L-systems, terrain, constraints), the device for the rest. --backend vulkan runs every layer\n"
                   "on it.\n",
                   infos[i].name);
        else
            printf("--backend auto (the default): every layer runs on %s.\n", infos[i].name);
    }
    free(infos);
    return FB_OK;
}

static const fb_arg flags[] = {
    {FB_ARG_STRING, "--device", NULL, offsetof(devices_opts, device)},
    {FB_ARG_DOCUMENT, "--json", NULL, offsetof(devices_opts, json)},
    {FB_ARG_IGNORED, "--quiet"}, /* nothing to leave out: the list is the output */
    {FB_ARG_BOOL, "--help", "-h", offsetof(devices_opts, help)},
    {FB_ARG_END},
};
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables, .files_off = offsetof(devices_opts, files)};

const fb_command fb_cmd_devices = {
    .name = "devices",
    .usage = "  devices                            the Vulkan devices found, and which one is chosen\n",
    .opts_size = sizeof(devices_opts),
    .args = &spec,
    .help = help,
    .help_off = offsetof(devices_opts, help),
    .run = run};
