/*
 * Benchmarks, the part shared by every generator's: timing a bake or a function, and the rows a
 * measurement produces. Each generator's benchmarks live in its folder (struct fb_gen_class.bench);
 * the bench command (cli/bench.c) parses the options and prints the rows, as text or JSON lines.
 *
 * Each measurement is a warm-up run (shader compilation, page faults) followed by three timed runs,
 * of which the median is reported. Every figure of one generator comes from the same run, so that
 * ratios between backends are meaningful on a noisy machine.
 */
#ifndef FB_BENCHKIT_H
#define FB_BENCHKIT_H

#include "engine.h"
#include "scene.h"

/* One measured figure. */
typedef struct fb_bench_row {
    const char *generator, *backend, *device, *mode, *unit;
    double rate;     /* units per second */
    double gpu_rate; /* from the GPU's timestamps, or <= 0 */
    int threads;     /* 0: not a thread count (a GPU) */
    bool size;       /* the figure is for an image of the bench's size */
    int nextra;      /* further JSON figures, after the size */
    struct {
        const char *name;
        double value;
        int decimals;
    } extra[4];
    char note[96]; /* for people: "(1000000 inserts in 0.846 s)", or "" */
} fb_bench_row;

typedef struct fb_bench {
    int width, height; /* the image of per-pixel benchmarks */
    double points;     /* chaos-game steps per run */
    int threads;       /* 0: one per core */
    bool vulkan, native;
    const char *device;
    vkc_desc vk_options; /* the Vulkan engines' other options (from the command line's environment) */
    const char *out;     /* a scratch EXR path for the end-to-end runs */
    bool json;
    /* the sink: a heading line for people (not in JSON), and each row */
    void (*heading)(const struct fb_bench *b, const char *text);
    void (*row)(const struct fb_bench *b, const fb_bench_row *r);
    void *user; /* the sink's */
} fb_bench;

/* A per-pixel generator's benchmark: its one-layer scene's work and unit. */
typedef struct fb_bench_case {
    const char *generator; /* "fbm", "julia" */
    const char *unit;      /* "Mpix/s", "Giter/s" */
    double work;           /* units of work in one image (pixels, iterations) */
    double unit_scale;     /* work per unit: 1e6 for Mpix, 1e9 for Giter */
    const char *extra;     /* a second figure's JSON name, or NULL */
    double extra_per_work; /* its work per unit of `work`, in millions */
} fb_bench_case;

void fb_bench_heading(const fb_bench *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* The median of three values (sorted in place). */
double fb_bench_median3(double t[3]);

/* Median wall seconds (and GPU seconds) of three bakes after one warm-up. out NULL: no file. */
fb_result fb_bench_timed(fb_engine *e, const fb_scene *s, const char *out, double *wall, double *gpu);

/* Median seconds (and device seconds) of three prepares of the scene's first layer after a warm-up
 * (a pipeline's compilation): the part of a bake that `read` reports from each prepared generator's
 * own stats (a chaos game alone: no reduction, tone map or file). */
struct fb_gen;
fb_result fb_bench_prepared(fb_engine *e, const fb_scene *s,
                            void (*read)(const struct fb_gen *g, double *sec, double *gpu), double *sec, double *gpu);

/* Opens the Vulkan engine; *have is false (and the result FB_OK) when there is no device and the
 * native backend is benchmarked anyway. */
fb_result fb_bench_open_vulkan(const fb_bench *b, fb_engine *e, bool *have);

/* Reports one timing of a case: work / seconds. */
void fb_bench_report(const fb_bench *b, const fb_bench_case *bc, const char *device, const char *backend,
                     const char *mode, int threads, double seconds, double gpu_seconds);

/* The encoder alone: the file the last bake wrote (b->out) read into memory, then written again
 * through the EXR writer with the same channels, types and compression on every core (or the
 * bench's --threads), median of three: an "encode-only-COMPRESSION" row in the case's unit, with
 * bake_vs_encode, the bake's `bake_seconds` over the encoder's (1: the bake as fast as encoding). */
fb_result fb_bench_encode(const fb_bench *b, const fb_bench_case *bc, const char *compression, double bake_seconds);

/* A per-pixel layer on every backend: generate-only and end-to-end (none, zip, piz) bakes, the
 * reference (seconds tref > 0, from the caller: a hand-vectorised loop) and the scalar kernel on one
 * thread. */
fb_result fb_bench_layer(const fb_bench *b, const fb_bench_case *bc, fb_scene *s, double tref);

/* The whole bake as a user's default gets it: --backend auto, ZIP, the file written ("auto",
 * "end-to-end-zip"). Nothing unless both backends are benchmarked. */
fb_result fb_bench_auto_zip(const fb_bench *b, const fb_bench_case *bc, fb_scene *s);

/* The layer alone (no file) on each backend, under another mode name. */
fb_result fb_bench_variant(const fb_bench *b, const fb_bench_case *bc, fb_scene *s, const char *mode);

/* A minimal shader of a layer's formula: the simplest fast GLSL a GPU programmer would write for
 * the bench's scene (bench/peers/), without the layer's generality, its values the layer's to the
 * bit where practical. Its interface: bindings 0..planes-1, planes of 4-byte values; binding
 * `planes`, the layer's input where `input` (a uniform buffer where the layer reads it as one); the
 * layer's push constants ({params; y0; rows}). */
typedef struct fb_bench_peer {
    const char *name; /* for people: "minimal GLSL (bench/peers/fbm_peer.comp)" */
    const char *mode; /* the rows' suffix: "kernel" MODE and "peer" MODE ("-simplex"; NULL: none) */
    const uint32_t *spv;
    size_t spv_size;
    const uint32_t *spec; /* its specialisation constants 0..nspec-1 */
    uint32_t nspec;
    int plane;          /* the layer's first plane its output must equal */
    int planes;         /* its planes, compared with the layer's plane, plane + 1, ... (0: 1) */
    int per_invocation; /* pixels an invocation along a row, in groups 64 wide (0: 1) */
    bool input;         /* it reads the layer's input (binding 1) */
} fb_bench_peer;

/* The layer of s (its one layer) by its own shader as a bake dispatches it, beside `peer`, on the
 * Vulkan device, in dispatches as large as a storage buffer allows (the whole image where it fits:
 * a GPU's dispatch, not a lavapipe strip); a warm-up pass, then three, the two alternating; rates
 * by the host clock and the device's timestamps. Rows "kernel" MODE, with vs_peer (its rate over
 * the peer's, by the timestamps where the device has them), same_bits (1: the peer's plane is the
 * layer's to the bit) and differing (pixels), and "peer" MODE. Nothing without a device. */
fb_result fb_bench_peer_layer(const fb_bench *b, const fb_bench_case *bc, const fb_scene *s, const fb_bench_peer *peer);

/* The two rows of a kernel beside its peer, from three timed runs of each (side 0 the layer's, 1
 * the peer's; seconds by the host clock and the device's timestamps, 0 where it has none) of
 * `work` units of `unit` (rates in work / seconds / unit_scale): "kernel" MODE on `device`, with
 * vs_peer, same_bits and differing (`diff` values unlike the layer's), and "peer" MODE on
 * `peer_name`, noted by `peer_note` (the seconds are sorted in place). */
void fb_bench_peer_rows(const fb_bench *b, const char *generator, const char *device, const char *peer_name,
                        const char *mode, const char *unit, double work, double unit_scale, double wall[2][3],
                        double gpu[2][3], uint64_t diff, const char *peer_note);

/* Median seconds of three runs after a warm-up of rows(ctx, y0, n, task) over `height` rows cut into
 * tasks on a pool of `threads`; *ntasks (optional) the number of tasks. -1 on failure. */
double fb_bench_rows(int threads, int height, void (*rows)(void *ctx, int y0, int n, int task), void *ctx, int *ntasks);

/* splitmix64 and a uniform double in [0, 1) from it: the benchmarks' inputs, which the peers in bench/
 * generate the same way. */
uint64_t fb_bench_splitmix64(uint64_t *s);
double fb_bench_unit(uint64_t *s);

#endif
