/* `fractalbake compare A B`: two images channel by channel against thresholds (compare.h), in
 * idiff's vocabulary too. */
#include "cliout.h"
#include "command.h"

#include "compare.h"
#include "output.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct compare_opts {
    fb_compare_desc d;
    fb_arg_list files;
    bool quiet, help;
    int flip_mode, flip_stat; /* -1: not given; either implies --flip */
    fb_verdict verdict;
} compare_opts;

static void init(void *opts)
{
    compare_opts *c = opts;
    c->flip_mode = c->flip_stat = -1;
}

/* compare --quiet: the verdict line alone */
static void print_result_only(const char *line, void *user)
{
    if (!strncmp(line, "result: ", 8)) fb_cli_print_line(line, user);
}

/* idiff's single-dash spelling of a flag compare shares, as ours (in buf); its other flags answered
 * with ours (NULL, the error logged); any other argument as it is. */
static const char *idiff_flag(const char *a, char *buf, size_t size)
{
    /* idiff's own single-dash spellings of the flags that mean the same here; its others answered */
    static const char *const idiff_same[] = {"fail", "failrelative", "failpercent", "hardfail", "allowfailures",
                                             "warn", "warnrelative", "warnpercent", "hardwarn"};
    static const char *const idiff_other[][2] = {
        {"-o", "the difference image: --diff OUT.exr (|A - B|; idiff -o writes A - B)"},
        {"-od", "--diff writes its file whatever the difference"},
        {"-abs", "--diff writes |A - B| already"},
        {"-scale", "--diff writes |A - B| unscaled"},
        {"-p", "a perceptual comparison: --flip (idiff -p is Yee's metric)"},
        {"-a", "every part is compared: channels are matched by name"},
        {"-v", "compare prints its statistics already (--idiff-stats: idiff's)"},
        {"-q", "--quiet"}};
    for (size_t k = 0; a[0] == '-' && a[1] != '-' && k < sizeof idiff_same / sizeof idiff_same[0]; k++)
        if (!strcmp(a + 1, idiff_same[k])) return snprintf(buf, size, "-%s", a), buf;
    for (size_t k = 0; k < sizeof idiff_other / sizeof idiff_other[0]; k++)
        if (!strcmp(a, idiff_other[k][0])) {
            fb_fail(FB_ERR_USAGE, "%s: idiff's flag; fractalbake compare: %s", a, idiff_other[k][1]);
            return NULL;
        }
    return a;
}

static void help(const fb_cli *cli)
{
    (void)cli;
    printf("usage: fractalbake compare A B [thresholds] [--layer L] [--ignore-missing] [--diff OUT.exr]\n"
           "                          [--diff-png OUT.png [--heat]] [--json] [--quiet]\n"
           "A and B are EXR or PNG files (a PNG's channels are Y, Y A, R G B or R G B A, 0..1).\n"
           "Per channel: the largest |A - B| and where, RMSE, PSNR (peak: A's range), the share of pixels\n"
           "beyond the fail threshold, and with --ssim the mean SSIM (Wang et al. 2004, L: A's range).\n"
           "\n"
           "thresholds (idiff's names; each takes a value for every channel, CHANNEL=VALUE or\n"
           "LAYER=VALUE rules, or both: --max-abs 1e-4,sky.R=1e-3,terrain=1e-6):\n"
           "  --max-abs E, --fail E      a pixel fails when |A - B| > E (default 0: every pixel equal)\n"
           "  --fail-percent P           the channel fails when more than P%% of its pixels fail (default 0)\n"
           "  --hardfail E               ... or when any pixel's |A - B| > E, whatever --fail and P say\n"
           "  --warn E, --warn-percent P, --hardwarn E   the same for a warning\n"
           "  --rmse E, --psnr DB, --ssim S              fail beyond an RMSE, below a PSNR or an SSIM\n"
           "  (--failpercent and --warnpercent are accepted too)\n"
           "  --allowfailures N          a channel fails (on --fail-percent or --hardfail) only when more than\n"
           "                             N of its pixels fail: beyond --fail, or beyond --hardfail (idiff's\n"
           "                             rule, but idiff 2.4 counts only those beyond -fail, and so skips\n"
           "                             -hardfail while none is, against its own help)\n"
           "  --failrelative R, --warnrelative R   a pixel is beyond --fail (--warn) only when |A - B| is\n"
           "                             also beyond R * (|A| + |B|) / 2\n"
           "  idiff's single-dash spellings (-fail, -failpercent, -hardfail, -allowfailures, -warn, ...)\n"
           "  are taken too.\n"
           "--report OUT.html: one page that works offline: every layer's reference, test, difference\n"
           "and FLIP pictures (full size on click), statistics and verdict, failing layers first, and the\n"
           "stored scenes' keys that differ. --junit OUT.xml: a test case per channel and threshold.\n"
           "--idiff-stats adds idiff's statistics: over all compared channels together, RMS error and\n"
           "PSNR with peak max(1, the largest value), the pixels over --warn and --fail (any channel).\n"
           "\n"
           "FLIP (Andersson et al. 2020; HDR-FLIP 2021), per layer of R, G, B (or Y as grey):\n"
           "  --flip                     compute it: LDR-FLIP for PNGs, HDR-FLIP for EXRs (ACES, automatic\n"
           "                             exposures); the mean, weighted median and quartiles, max\n"
           "  --flip-fail E, --flip-warn E   fail (warn) when a layer's statistic is beyond E (LAYER=E rules)\n"
           "  --flip-stat mean|median|q1|q3|max   the statistic they test (default mean)\n"
           "  --flip-mode auto|ldr|hdr   LDR-FLIP takes sRGB values in [0, 1], HDR-FLIP linear ones\n"
           "  --flip-png OUT.png         the error of the layer with the largest mean, grey (255: error 1)\n"
           "  (each implies --flip; --diff then holds LAYER.FLIP too)\n"
           "\n"
           "--diff writes |A - B| per channel; --diff-png a picture: red where a channel fails, over A's\n"
           "first channel in dim grey; with --heat a heat map of the largest |A - B| over the channels,\n"
           "log scale (black 1e-8, blue 1e-6, red 1e-4, yellow 0.01, white 1). --json: the report as one\n"
           "JSON object. --quiet: only the result line. --threads N: the threads (default one per core;\n"
           "the same results for any N). FLIP and --report hold the compared channels of both files in\n"
           "memory; the other statistics read blocks of rows.\n"
           "\n"
           "exit: 0 pass or warn (the result line says WARN; --json: \"result\": \"warn\"), 1 fail (also\n"
           "different sizes or channel sets, with the reason), 2 bad usage or input, 3 runtime failure.\n"
           "idiff returns 1 for a warning and 2 for a failure: fractalbake keeps 2 for bad input, as\n"
           "every fractalbake command does, and lets a warning pass.\n");
}

static fb_result arg_limit(const char *flag, const char *value, void *field)
{
    return fb_limit_parse(flag, value, field);
}

static fb_result arg_flip_mode(const char *flag, const char *value, void *field)
{
    static const char *const modes[] = {"auto", "ldr", "hdr"};
    for (int k = 0; k < 3; k++)
        if (!strcmp(value, modes[k])) return *(int *)field = k, FB_OK;
    return fb_fail(FB_ERR_USAGE, "%s: expected auto|ldr|hdr, found \"%s\"", flag, value);
}

static fb_result arg_flip_stat(const char *flag, const char *value, void *field)
{
    static const char *const stats[] = {"mean", "median", "q1", "q3", "max"};
    for (int k = 0; k < 5; k++)
        if (!strcmp(value, stats[k])) return *(int *)field = k, FB_OK;
    return fb_fail(FB_ERR_USAGE, "%s: expected mean|median|q1|q3|max, found \"%s\"", flag, value);
}

/* a finite number >= 0 */
static fb_result arg_relative(const char *flag, const char *value, void *field)
{
    char *end;
    errno = 0;
    double v = strtod(value, &end);
    if (end == value || *end || errno || !isfinite(v) || v < 0)
        return fb_fail(FB_ERR_USAGE, "%s: expected a finite number >= 0, found \"%s\"", flag, value);
    *(double *)field = v;
    return FB_OK;
}

/* a whole number of pixels >= 0 */
static fb_result arg_count(const char *flag, const char *value, void *field)
{
    char *end;
    errno = 0;
    double v = strtod(value, &end);
    if (end == value || *end || errno || !isfinite(v) || v < 0 || v != floor(v) || v > 9e18)
        return fb_fail(FB_ERR_USAGE, "%s: expected a whole number of pixels >= 0, found \"%s\"", flag, value);
    *(long long *)field = (long long)v;
    return FB_OK;
}

static fb_result run(const fb_cli *cli, void *opts)
{
    (void)cli;
    compare_opts *c = opts;
    fb_compare_desc *d = &c->d;
    if (c->files.n != 2) return fb_fail(FB_ERR_USAGE, "compare: expected two images: fractalbake compare A.exr B.exr");
    if (c->flip_mode >= 0) d->flip_mode = (fb_flip_mode)c->flip_mode;
    if (c->flip_stat >= 0) d->flip_stat = c->flip_stat;
    if (d->flip_fail.set || d->flip_warn.set || d->flip_png || c->flip_mode >= 0 || c->flip_stat >= 0) d->flip = true;
    d->a = c->files.v[0];
    d->b = c->files.v[1];
    d->print = c->quiet && !d->json ? print_result_only : fb_cli_print_line;
    /* a document written to standard output (--junit -) is all it carries: the lines go to stderr */
    const char *outs[] = {d->diff, d->diff_png, d->flip_png, d->report, d->junit};
    for (size_t k = 0; k < sizeof outs / sizeof outs[0]; k++)
        if (outs[k] && !strcmp(outs[k], "-")) d->user = stderr;
    if (cli_check_quiet_json(c->quiet, d->json)) return FB_ERR_USAGE;
    if (d->heat && !d->diff_png)
        return fb_fail(FB_ERR_USAGE, "--heat: only with --diff-png OUT.png (it chooses that picture's colours)");
    return fb_compare(d, &c->verdict);
}

static int exit_code(const void *opts)
{
    return ((const compare_opts *)opts)->verdict == FB_VERDICT_FAIL ? 1 : 0;
}

#define D(f) offsetof(compare_opts, d.f)
static const fb_arg flags[] = {
    /* idiff's names beside ours: --fail is --max-abs, --failpercent --fail-percent */
    {FB_ARG_VALUE, "--max-abs", "--fail", D(fail), .parse = arg_limit},
    {FB_ARG_VALUE, "--fail-percent", "--failpercent", D(failpercent), .parse = arg_limit},
    {FB_ARG_VALUE, "--hardfail", NULL, D(hardfail), .parse = arg_limit},
    {FB_ARG_VALUE, "--warn", NULL, D(warn), .parse = arg_limit},
    {FB_ARG_VALUE, "--warn-percent", "--warnpercent", D(warnpercent), .parse = arg_limit},
    {FB_ARG_VALUE, "--hardwarn", NULL, D(hardwarn), .parse = arg_limit},
    {FB_ARG_VALUE, "--rmse", NULL, D(rmse), .parse = arg_limit},
    {FB_ARG_VALUE, "--psnr", NULL, D(psnr), .parse = arg_limit},
    {FB_ARG_VALUE, "--ssim", NULL, D(ssim), .parse = arg_limit},
    {FB_ARG_VALUE, "--flip-fail", NULL, D(flip_fail), .parse = arg_limit},
    {FB_ARG_VALUE, "--flip-warn", NULL, D(flip_warn), .parse = arg_limit},
    {FB_ARG_STRING, "--layer", NULL, D(layer)},
    {FB_ARG_OUTPUT, "--diff", NULL, D(diff), .ext = ".exr"},
    {FB_ARG_OUTPUT, "--diff-png", NULL, D(diff_png), .ext = ".png"},
    {FB_ARG_OUTPUT, "--report", NULL, D(report), .ext = ".html"},
    {FB_ARG_OUTPUT, "--junit", NULL, D(junit), .ext = ".xml"},
    {FB_ARG_OUTPUT, "--flip-png", NULL, D(flip_png), .ext = ".png"},
    {FB_ARG_VALUE, "--flip-mode", NULL, offsetof(compare_opts, flip_mode), .parse = arg_flip_mode},
    {FB_ARG_VALUE, "--flip-stat", NULL, offsetof(compare_opts, flip_stat), .parse = arg_flip_stat},
    {FB_ARG_BOOL, "--flip", NULL, D(flip)},
    {FB_ARG_BOOL, "--idiff-stats", NULL, D(idiff_stats)},
    {FB_ARG_VALUE, "--allowfailures", NULL, D(allowfailures), .parse = arg_count},
    {FB_ARG_VALUE, "--failrelative", NULL, D(failrelative), .parse = arg_relative},
    {FB_ARG_VALUE, "--warnrelative", NULL, D(warnrelative), .parse = arg_relative},
    {FB_ARG_BOOL, "--ignore-missing", NULL, D(ignore_missing)},
    {FB_ARG_BOOL, "--heat", NULL, D(heat)},
    {FB_ARG_DOCUMENT, "--json", NULL, D(json)},
    {FB_ARG_BOOL, "--quiet", NULL, offsetof(compare_opts, quiet)},
    {FB_ARG_INT, "--threads", NULL, D(threads), 1, 1024},
    {FB_ARG_BOOL, "--help", "-h", offsetof(compare_opts, help)},
    {FB_ARG_END},
};
#undef D
static const fb_arg *const tables[] = {flags, NULL};
static const fb_argspec spec = {.flags = tables,
                                .files_off = offsetof(compare_opts, files),
                                .max_files = 2,
                                .too_many = "%s: compare takes exactly two files",
                                .rewrite = idiff_flag};

const fb_command fb_cmd_compare = {
    .name = "compare",
    .usage = "  compare A.exr B.exr [thresholds]   exit 0 within thresholds, 1 beyond, 2 on error\n",
    .opts_size = sizeof(compare_opts),
    .init = init,
    .args = &spec,
    .help = help,
    .help_off = offsetof(compare_opts, help),
    .run = run,
    .exit_code = exit_code};
