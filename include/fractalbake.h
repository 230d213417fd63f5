/*
 * libfractalbake: fractalbake's bakes in your own program.
 *
 * A context holds a compute backend (a Vulkan device, or native C on a thread pool) and everything a
 * bake needs; contexts share nothing, so two of them may work at once on two threads, on different
 * backends. A scene is read from JSON text or a file (or is the embedded default scene), with
 * "KEY.PATH=VALUE" overrides as `fractalbake render --set` takes them. A bake writes an EXR file
 * (and the other files the scene names) exactly as `fractalbake render` does, or hands its channels
 * to planes the caller owns: the same bits either way.
 *
 * Every function that can fail returns 0 on success, else one of FRACTALBAKE_ERR_*; the context's
 * fractalbake_error() is then the one line the command line prints for the same failure. The library
 * never prints, never exits, never reads the environment and installs no signal handler.
 *
 * Link with `pkg-config --cflags --libs fractalbake`.
 */
#ifndef FRACTALBAKE_H
#define FRACTALBAKE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The API this header describes: a context desc names it, and a library that does not offer it
 * refuses the context (FRACTALBAKE_ERR_USAGE). */
#define FRACTALBAKE_API 1

enum {
    FRACTALBAKE_OK = 0,
    FRACTALBAKE_ERR_USAGE = 1,     /* a bad argument (the command line's exit 2) */
    FRACTALBAKE_ERR_INPUT = 2,     /* a bad scene or input file (exit 2) */
    FRACTALBAKE_ERR_IO = 3,        /* a file could not be read or written (exit 3) */
    FRACTALBAKE_ERR_NOMEM = 4,     /* out of memory (exit 3) */
    FRACTALBAKE_ERR_VULKAN = 5,    /* the Vulkan device failed (exit 3) */
    FRACTALBAKE_ERR_NODEVICE = 6,  /* no Vulkan device where vulkan was asked for (exit 3) */
    FRACTALBAKE_ERR_EXR = 7,       /* OpenEXR failed (exit 3) */
    FRACTALBAKE_ERR_INTERNAL = 8,  /* an impossible state (exit 3) */
    FRACTALBAKE_ERR_CANCELLED = 9, /* the progress callback asked to stop */
};

/* The channels' sample types, as in the EXR file: 32-bit unsigned, 16-bit half, 32-bit float. */
enum { FRACTALBAKE_UINT = 0, FRACTALBAKE_HALF = 1, FRACTALBAKE_FLOAT = 2 };

typedef struct fractalbake_context fractalbake_context;
typedef struct fractalbake_scene fractalbake_scene;
typedef struct fractalbake_image fractalbake_image;

/* Called between strips of rows with the fraction of the bake done (0 to 1); a non-zero return
 * stops the bake: it then fails with FRACTALBAKE_ERR_CANCELLED and leaves no file behind. */
typedef int (*fractalbake_progress_fn)(double fraction, void *user);

typedef struct fractalbake_context_desc {
    int api;             /* FRACTALBAKE_API */
    const char *backend; /* "auto" (NULL), "vulkan" or "native", as --backend */
    const char *device;  /* a Vulkan device's index or a substring of its name (NULL: the best) */
    int threads;         /* native threads and EXR compression threads (0: one per core) */
    uint64_t max_memory; /* bytes a bake may use at its peak (0: 80% of physical memory) */
    const char *tmpdir;  /* where a bake into planes keeps its file until read (NULL: /tmp) */
} fractalbake_context_desc;

/* The API version (FRACTALBAKE_API of the library) and the library's version ("0.1.0"). */
int fractalbake_api(void);
const char *fractalbake_version(void);

/* Makes a context and opens its backend. On failure *out is still a context (NULL only when out of
 * memory) whose fractalbake_error() says why, for the caller to read and destroy. */
int fractalbake_context_create(const fractalbake_context_desc *desc, fractalbake_context **out);
void fractalbake_context_destroy(fractalbake_context *ctx); /* NULL-safe */

/* The line of the context's last failure ("fractalbake: ..."), "" after a success. */
const char *fractalbake_error(const fractalbake_context *ctx);

/* Where the context's bakes run: "vulkan" or "native", and the device ("llvmpipe (LLVM 15.0.7, 256
 * bits)", "native C, 8 threads"). */
const char *fractalbake_backend(const fractalbake_context *ctx);
const char *fractalbake_device(const fractalbake_context *ctx);

/* The progress callback of the context's bakes (NULL: none). */
void fractalbake_set_progress(fractalbake_context *ctx, fractalbake_progress_fn fn, void *user);

/* A scene from JSON text (text), else a file (path), else the embedded default scene; sets[0..nsets)
 * applied first, as --set. */
int fractalbake_scene_load(fractalbake_context *ctx, const char *text, const char *path, const char *const *sets,
                           int nsets, fractalbake_scene **out);
void fractalbake_scene_destroy(fractalbake_scene *scene); /* NULL-safe */
void fractalbake_scene_size(const fractalbake_scene *scene, int *width, int *height);
/* The scene with every default filled in, as the file stores it (valid while the scene lives). */
const char *fractalbake_scene_json(const fractalbake_scene *scene);

/* Bakes the scene into an EXR file at path (and the other files the scene names), all put in place
 * together at the end or none: `fractalbake render SCENE -o PATH`. region: x, y, w, h of the pixels
 * to bake (the same as in the full bake), or NULL: the whole image. */
int fractalbake_bake(fractalbake_context *ctx, const fractalbake_scene *scene, const char *path, const int *region);

/* Bakes the scene (region as above) and keeps the result, to be read into planes: *out lists the
 * channels with the names, types and order the EXR file has. */
int fractalbake_render(fractalbake_context *ctx, const fractalbake_scene *scene, const int *region,
                       fractalbake_image **out);

/* An EXR file (one fractalbake or another program wrote), to be read into planes the same way. */
int fractalbake_open(fractalbake_context *ctx, const char *path, fractalbake_image **out);

/* The image's pixels: width x height, at (x, y) of a full image of full_width x full_height (a
 * region's data window; 0, 0 and the same size for a whole image). */
void fractalbake_image_window(const fractalbake_image *img, int *x, int *y, int *width, int *height, int *full_width,
                              int *full_height);
int fractalbake_image_channels(const fractalbake_image *img);
const char *fractalbake_image_channel(const fractalbake_image *img, int c); /* "sky.R", "Y" */
int fractalbake_image_type(const fractalbake_image *img, int c);            /* FRACTALBAKE_UINT, _HALF, _FLOAT */
/* A string attribute of the file ("fractalbake/scene"), or NULL. */
const char *fractalbake_image_attribute(const fractalbake_image *img, const char *name);

/* Reads the channels into planes[c] (NULL: skipped), each width x height samples, row after row:
 * uint32_t for FRACTALBAKE_UINT, float for the others (a half converts exactly). */
int fractalbake_image_read(fractalbake_context *ctx, fractalbake_image *img, void *const *planes);
void fractalbake_image_destroy(fractalbake_image *img); /* NULL-safe */

/* What fractalbake_compare checks: thresholds as `fractalbake compare` takes them ("0.01",
 * "sky.R=0.01,0.1"; NULL: none), and FLIP per layer when flip is non-zero. */
typedef struct fractalbake_compare_desc {
    const char *layer;                  /* only the channels "layer.*" (NULL: all) */
    const char *max_abs, *fail_percent; /* --max-abs, --fail-percent */
    const char *warn, *warn_percent;    /* --warn, --warn-percent */
    const char *rmse, *psnr, *ssim;     /* --rmse (at most), --psnr, --ssim (at least) */
    int flip;
    int ignore_missing; /* channels in one file only are left out rather than failing */
} fractalbake_compare_desc;

/* Compares two images (EXR or PNG files) channel by channel: *json (malloc'd: free it with
 * fractalbake_free) is the object `fractalbake compare --json A B` prints, statistics and verdicts
 * per channel; *passed is 1 when no channel fails. desc may be NULL (no thresholds: the statistics). */
int fractalbake_compare(fractalbake_context *ctx, const char *a, const char *b, const fractalbake_compare_desc *desc,
                        char **json, int *passed);

/* Frees what the library allocated for the caller (fractalbake_compare's text). */
void fractalbake_free(void *p);

#ifdef __cplusplus
}
#endif

#endif
