/*
 * The fbm and Julia layers' shaders on a Vulkan device (lavapipe here) beside their peers, in one
 * run, the variants alternating within each pass:
 *   fbm:   the layer's shaders/fbm.comp against bench/peers/fbm_peer.comp, a minimal GLSL of the same
 *          formula (rotation, offsets and hashes), 8 octaves of gradient noise;
 *   julia: the layer's shaders/julia.comp with every channel against the same shader storing `iter`
 *          only (the escape loop alone), c = -0.8+0.156i, max-iter 256.
 * Each variant's rate is given in wall-clock time and in process CPU time (lavapipe's threads
 * included: what other processes on a shared machine move least), the median of --reps passes, and
 * its outputs are hashed: a variant is listed with "same bits" only where every stored plane is
 * the layer's to the bit.
 *
 * --spv NAME=FILE adds FILE (SPIR-V with the layer's interface, say the shader of an earlier build:
 * `glslangValidator -V --target-env vulkan1.1 -o old.spv shaders/fbm.comp`) as a variant of the
 * layer whose file name says which (fbm or julia in the name), so that before and after run side by side.
 * It reads the layer's input (julia: the palette) as a storage buffer, as shaders before 2026-12-03
 * did; --spv-ubo NAME=FILE for SPIR-V that reads it as a uniform buffer, as julia_body.glsl now does.
 *
 *     cmake --build build --target lavapipe_peers && build/lavapipe_peers [--size N] [--reps N]
 *         [--rows N] [--only fbm|julia] [--spv NAME=FILE ...]
 */
#include "gen.h"
/* after gen.h: the SPIR-V array is a uint32_t[] */
#include "fbm_peer_comp.h"
#include "scene.h"
#include "vkc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_VARIANTS 12
#define MAX_REPS     31

typedef struct variant {
    char name[64];
    const char *channels; /* the julia layer's channels (JSON), or NULL: the scene's default */
    uint32_t *spv;        /* NULL: the layer's own shader */
    size_t spv_size;
    bool spv_ubo; /* the SPIR-V reads the layer's input as a uniform buffer (--spv-ubo) */
    fb_gen g;
    fb_scene s;
    vkc_pipeline *pipe;
    vkc_job *job;
    vkc_buffer *buf[FB_GEN_MAX_CHANNELS + 1];
    double wall[MAX_REPS], cpu[MAX_REPS], gpu[MAX_REPS];
    uint64_t hash[FB_GEN_MAX_CHANNELS]; /* of each stored plane, the whole image */
    uint64_t iter_sum;                  /* julia: the sum of `iter` (iterations to the bailout) */
} variant;

typedef struct options {
    int size, reps, rows;
    const char *only;
    int nspv;
    char *spv_name[MAX_VARIANTS];
    char *spv_file[MAX_VARIANTS];
    bool spv_ubo[MAX_VARIANTS];
    int nchannels;
    const char *channels[MAX_VARIANTS]; /* --channels: more julia variants, the layer storing these */
    bool validation;
} options;

static double process_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double median(const double *v, int n)
{
    double t[MAX_REPS];
    memcpy(t, v, sizeof(double) * (size_t)n);
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && t[j] < t[j - 1]; j--) {
            double x = t[j];
            t[j] = t[j - 1];
            t[j - 1] = x;
        }
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

static uint64_t fnv(uint64_t h, const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

static uint32_t *read_spv(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint32_t *w = n > 0 && n % 4 == 0 ? malloc((size_t)n) : NULL;
    if (w && fread(w, 1, (size_t)n, f) != (size_t)n) {
        free(w);
        w = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return w;
}

static const char *scene_json(const char *kind, int size, const char *channels, char *out, size_t n)
{
    if (!strcmp(kind, "fbm"))
        snprintf(out, n,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"fbm\", \"noise\": \"gradient\", "
                 "\"octaves\": 8}]}",
                 size, size);
    else
        snprintf(out, n,
                 "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"julia\", \"c\": [-0.8, 0.156], "
                 "\"max-iter\": 256%s%s}]}",
                 size, size, channels ? ", \"channels\": " : "", channels ? channels : "");
    return out;
}

/* The variant's layer, pipeline, job and strip buffers. */
static fb_result variant_init(vkc_context *vk, variant *v, const char *kind, const options *o)
{
    char json[512];
    fb_result rc = fb_scene_parse(scene_json(kind, o->size, v->channels, json, sizeof json), NULL, &v->s);
    if (!rc) rc = fb_gen_init(&v->g, &v->s, &v->s.layers[0]);
    if (rc) return rc;
    int np = fb_gen_nplanes(&v->g);
    vkc_pipeline_desc d = {
        .spv = v->spv ? v->spv : v->g.compute.shader.spv,
        .spv_size = v->spv ? v->spv_size : v->g.compute.shader.spv_size,
        .push_size = v->g.compute.shader.push_size,
        .buffers = (uint32_t)np + (v->g.compute.shader.input ? 1u : 0u),
        /* an earlier build's SPIR-V reads its input as a storage buffer unless --spv-ubo */
        .uniform =
            v->g.compute.shader.input && (v->spv ? v->spv_ubo : v->g.compute.shader.input_uniform) ? 1u << np : 0u,
        .spec = v->g.compute.shader.spec,
        .nspec = v->g.compute.shader.nspec,
        .name = v->name};
    rc = vkc_pipeline_create(vk, &d, &v->pipe);
    if (!rc) rc = vkc_job_create(vk, v->pipe, &v->job);
    for (int k = 0; k < np && !rc; k++)
        rc = vkc_buffer_create(vk, (uint64_t)o->size * (uint64_t)o->rows * 4, &v->buf[k]);
    if (!rc && v->g.compute.shader.input) rc = vkc_buffer_create(vk, v->g.compute.shader.input_size, &v->buf[np]);
    if (!rc && v->g.compute.shader.input)
        rc = vkc_buffer_upload(vk, v->buf[np], v->g.compute.shader.input, v->g.compute.shader.input_size);
    return rc;
}

static void variant_fini(vkc_context *vk, variant *v)
{
    for (int k = 0; k <= FB_GEN_MAX_CHANNELS; k++) vkc_buffer_destroy(vk, &v->buf[k]);
    vkc_job_destroy(vk, &v->job);
    vkc_pipeline_destroy(vk, &v->pipe);
    fb_gen_fini(&v->g);
    fb_scene_fini(&v->s);
    free(v->spv);
}

/* One pass over the image in strips of o->rows: the clocks run only around submit and wait; the
 * strips' stored planes are hashed between them. */
static fb_result variant_pass(vkc_context *vk, variant *v, const options *o, int rep)
{
    int np = fb_gen_nplanes(&v->g), h = v->s.height;
    double wall = 0, cpu = 0, gpu = 0;
    for (int k = 0; k < np; k++) v->hash[k] = 0xcbf29ce484222325ull;
    v->iter_sum = 0;
    for (int y0 = 0; y0 < h; y0 += o->rows) {
        int n = y0 + o->rows <= h ? o->rows : h - y0;
        uint8_t push[FB_GEN_MAX_PUSH];
        uint32_t groups[3];
        fb_gen_push(&v->g, y0, n, push);
        fb_gen_groups(&v->g, n, groups);
        double t0 = fb_now(), c0 = process_cpu(), g = -1;
        fb_result rc =
            vkc_job_submit(vk, v->job, v->buf, (uint32_t)np + (v->g.compute.shader.input ? 1u : 0u), push, groups);
        if (!rc) rc = vkc_job_wait(vk, v->job, &g);
        if (rc) return rc;
        wall += fb_now() - t0;
        cpu += process_cpu() - c0;
        gpu += g;
        size_t bytes = (size_t)v->s.width * (size_t)n * 4;
        for (int k = 0; k < np; k++) {
            if (!fb_gen_plane_stored(&v->g, k)) continue;
            const uint8_t *d = vkc_buffer_data(v->buf[k]);
            v->hash[k] = fnv(v->hash[k], d, bytes);
            if (k == 0 && !strcmp(v->g.layer->cls->name, "julia"))
                for (size_t i = 0; i < bytes / 4; i++) v->iter_sum += ((const uint32_t *)(const void *)d)[i];
        }
    }
    v->wall[rep] = wall;
    v->cpu[rep] = cpu;
    v->gpu[rep] = gpu;
    return FB_OK;
}

/* The planes both variants store are the same bits. */
static bool same_bits(const variant *a, const variant *b)
{
    int n = fb_gen_nplanes(&a->g) < fb_gen_nplanes(&b->g) ? fb_gen_nplanes(&a->g) : fb_gen_nplanes(&b->g);
    for (int k = 0; k < n; k++)
        if (fb_gen_plane_stored(&a->g, k) && fb_gen_plane_stored(&b->g, k) && a->hash[k] != b->hash[k]) return false;
    return true;
}

static int add_variant(variant *vs, int n, const char *name, const char *channels, uint32_t *spv, size_t size)
{
    memset(&vs[n], 0, sizeof vs[n]);
    snprintf(vs[n].name, sizeof vs[n].name, "%s", name);
    vs[n].channels = channels;
    vs[n].spv = spv;
    vs[n].spv_size = size;
    return n + 1;
}

/* The case's variants: [0] the peer (fbm) or the iteration-only layer (julia), [1] the layer, then
 * the --spv files whose name names the case. */
static int make_variants(const char *kind, const options *o, variant *vs)
{
    static const char all[] = "[\"iter\", \"n\", \"inside\", \"de\", \"R\", \"G\", \"B\"]";
    bool fbm = !strcmp(kind, "fbm");
    int n = 0;
    if (fbm) {
        uint32_t *peer = malloc(sizeof fbm_peer_comp);
        memcpy(peer, fbm_peer_comp, sizeof fbm_peer_comp);
        n = add_variant(vs, n, "peer (bench/peers/fbm_peer.comp)", NULL, peer, sizeof fbm_peer_comp);
        n = add_variant(vs, n, "layer (shaders/fbm.comp)", NULL, NULL, 0);
    } else {
        n = add_variant(vs, n, "layer storing iter only", "[\"iter\"]", NULL, 0);
        n = add_variant(vs, n, "layer, all seven channels", all, NULL, 0);
        for (int i = 0; i < o->nchannels && n < MAX_VARIANTS - 1; i++)
            n = add_variant(vs, n, o->channels[i], o->channels[i], NULL, 0);
    }
    for (int i = 0; i < o->nspv && n < MAX_VARIANTS - 1; i++) {
        if (!strstr(o->spv_file[i], kind)) continue;
        size_t size = 0;
        uint32_t *w = read_spv(o->spv_file[i], &size);
        if (!w) {
            fprintf(stderr, "lavapipe_peers: --spv %s: cannot read a SPIR-V file there\n", o->spv_file[i]);
            exit(2);
        }
        char name[64];
        snprintf(name, sizeof name, "%s%s", o->spv_name[i], fbm ? "" : ", all seven channels");
        n = add_variant(vs, n, name, fbm ? NULL : all, w, size);
        vs[n - 1].spv_ubo = o->spv_ubo[i];
        if (!fbm) {
            uint32_t *w2 = malloc(size);
            memcpy(w2, w, size);
            snprintf(name, sizeof name, "%s, iter only", o->spv_name[i]);
            n = add_variant(vs, n, name, "[\"iter\"]", w2, size);
            vs[n - 1].spv_ubo = o->spv_ubo[i];
        }
    }
    return n;
}

static void report(const char *kind, const options *o, variant *vs, int n)
{
    bool fbm = !strcmp(kind, "fbm");
    double pix = (double)o->size * o->size;
    /* julia's rates are in iterations to the bailout (the iter plane's sum), the same for every variant */
    double work = fbm ? pix * 1e-6 : (double)vs[0].iter_sum * 1e-9;
    const char *unit = fbm ? "Mpix/s" : "Giter/s";
    if (fbm)
        printf("fBm %d x %d, 8 octaves of gradient noise, strips of %d rows; median of %d passes\n", o->size, o->size,
               o->rows, o->reps);
    else
        printf("Julia %d x %d, c = -0.8+0.156i, max-iter 256, %.1f iterations a pixel, strips of %d rows; median of %d "
               "passes\n",
               o->size, o->size, (double)vs[0].iter_sum / pix, o->rows, o->reps);
    printf("  %-44s %12s %12s %12s %9s  %s\n", "variant", "wall", "CPU time", "timestamps", "CPU ratio", "bits");
    double ref = work / median(vs[0].cpu, o->reps);
    for (int k = 0; k < n; k++) {
        double c = work / median(vs[k].cpu, o->reps);
        const variant *base = fbm || k == 0 ? &vs[fbm ? 1 : 0] : &vs[1];
        if (!fbm && strstr(vs[k].name, "iter only")) base = &vs[0];
        printf("  %-44s %8.3f %-3s %8.3f %-3s %8.3f %-3s %8.3fx  %s\n", vs[k].name, work / median(vs[k].wall, o->reps),
               unit, c, unit, work / median(vs[k].gpu, o->reps), unit, c / ref,
               base == &vs[k]            ? "(reference)"
               : same_bits(&vs[k], base) ? "same bits"
                                         : "DIFFERENT BITS");
    }
    printf("  (CPU ratio: CPU-time rate over the first row's; every process CPU second lavapipe's threads spend)\n");
}

static fb_result run_case(vkc_context *vk, const char *kind, const options *o)
{
    variant *vs = calloc(MAX_VARIANTS, sizeof *vs);
    int n = make_variants(kind, o, vs);
    fb_result rc = FB_OK;
    for (int k = 0; k < n && !rc; k++) rc = variant_init(vk, &vs[k], kind, o);
    for (int k = 0; k < n && !rc; k++) rc = variant_pass(vk, &vs[k], o, 0); /* warm-up */
    for (int rep = 0; rep < o->reps && !rc; rep++)
        for (int k = 0; k < n && !rc; k++) rc = variant_pass(vk, &vs[(k + rep) % n], o, rep);
    if (!rc) report(kind, o, vs, n);
    for (int k = 0; k < n; k++) variant_fini(vk, &vs[k]);
    free(vs);
    return rc;
}

static int usage(const char *why)
{
    fprintf(stderr, "lavapipe_peers: %s\n", why);
    fprintf(stderr, "usage: lavapipe_peers [--size N] [--reps N] [--rows N] [--only fbm|julia] [--spv NAME=FILE ...] "
                    "[--spv-ubo NAME=FILE ...]\n"
                    "       [--channels JSON-LIST ...]\n");
    return 2;
}

static int parse(int argc, char **argv, options *o)
{
    *o = (options){.size = 4096, .reps = 5, .rows = 256};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v) return usage("every option takes a value");
        i++;
        if (!strcmp(a, "--size"))
            o->size = atoi(v);
        else if (!strcmp(a, "--reps"))
            o->reps = atoi(v);
        else if (!strcmp(a, "--rows"))
            o->rows = atoi(v);
        else if (!strcmp(a, "--only"))
            o->only = v;
        else if ((!strcmp(a, "--spv") || !strcmp(a, "--spv-ubo")) && strchr(v, '=') && o->nspv < MAX_VARIANTS) {
            o->spv_ubo[o->nspv] = !strcmp(a, "--spv-ubo");
            o->spv_name[o->nspv] = strndup(v, (size_t)(strchr(v, '=') - v));
            o->spv_file[o->nspv++] = strchr(v, '=') + 1;
        } else if (!strcmp(a, "--channels") && o->nchannels < MAX_VARIANTS)
            o->channels[o->nchannels++] = v;
        else
            return usage("unknown option or bad value");
    }
    if (o->size < 64 || o->size > 8192) return usage("--size: 64 to 8192");
    if (o->reps < 1 || o->reps > MAX_REPS) return usage("--reps: 1 to 31");
    if (o->rows < 1 || o->rows > o->size) return usage("--rows: 1 to the size");
    if (o->only && strcmp(o->only, "fbm") && strcmp(o->only, "julia")) return usage("--only: fbm or julia");
    for (int i = 0; i < o->nspv; i++) {
        bool fbm = strstr(o->spv_file[i], "fbm") != NULL, julia = strstr(o->spv_file[i], "julia") != NULL;
        if (fbm == julia) return usage("--spv: the file's name must name one case, fbm or julia");
        if (o->only && strcmp(o->only, fbm ? "fbm" : "julia"))
            return usage("--spv: a file of the case --only leaves out");
    }
    if (o->nchannels && o->only && strcmp(o->only, "julia"))
        return usage("--channels: a julia variant, but --only fbm");
    const char *val = getenv("FB_VK_VALIDATION");
    o->validation = val && !strcmp(val, "1");
    return 0;
}

int main(int argc, char **argv)
{
    options o;
    int bad = parse(argc, argv, &o);
    if (bad) return bad;
    vkc_context *vk = NULL;
    if (vkc_create(&(vkc_desc){.validation = o.validation, .no_pipeline_cache = true}, &vk)) return 77;
    printf("device: %s (%s); LP_NUM_THREADS=%s\n", vkc_info(vk)->name, vkc_info(vk)->driver,
           getenv("LP_NUM_THREADS") ? getenv("LP_NUM_THREADS") : "(unset)");
    fb_result rc = FB_OK;
    if (!o.only || !strcmp(o.only, "fbm")) rc = run_case(vk, "fbm", &o);
    if (!rc && (!o.only || !strcmp(o.only, "julia"))) rc = run_case(vk, "julia", &o);
    uint32_t msgs = vkc_validation_messages(vk);
    vkc_destroy(&vk);
    if (msgs) fprintf(stderr, "lavapipe_peers: %u validation messages\n", msgs);
    return rc || msgs ? 1 : 0;
}
