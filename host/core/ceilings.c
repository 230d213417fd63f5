/* The machine's ceilings: see ceilings.h. */
#include "ceilings.h"

#include "ceiling_copy_comp.h"
#include "ceiling_fma_comp.h"
#include "vkc_bench.h"

#include <immintrin.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FMA_GROUPS 4096u                /* 262144 invocations */
#define FMA_ITERS  4096u                /* 16 FLOP each: 17 GFLOP a dispatch */
#define COPY_BYTES ((uint64_t)64 << 20) /* under lavapipe's 128 MiB storage buffer range */
#define COPY_ROW   ((uint64_t)32 << 20) /* ceiling_copy.comp: a row of workgroups copies 32 MiB */

static double best3(double t[3])
{
    double b = t[0];
    for (int i = 1; i < 3; i++) b = t[i] < b ? t[i] : b;
    return b;
}

/* One dispatch of `pipe` over `bufs`: the fastest of three after a warm-up by the host clock
 * (submission to fence) and by the device's timestamps (*gpu 0 where the queue has none). Device
 * buffers: nothing is copied back to the host. */
static fb_result timed_dispatch(vkc_context *vk, vkc_pipeline *pipe, vkc_buffer *const *bufs, uint32_t nbufs,
                                const void *push, const uint32_t groups[3], double *wall, double *gpu)
{
    vkc_job *job = NULL;
    fb_result rc = vkc_job_create(vk, pipe, &job);
    double t[3] = {0}, g[3] = {0};
    for (int run = -1; run < 3 && !rc; run++) { /* a warm-up, then three */
        double t0 = fb_now(), s = -1;
        rc = vkc_job_submit(vk, job, bufs, nbufs, push, groups);
        if (!rc) rc = vkc_job_wait(vk, job, &s);
        if (run >= 0) t[run] = fb_now() - t0;
        if (run >= 0) g[run] = s;
    }
    vkc_job_destroy(vk, &job);
    if (!rc) *wall = best3(t);
    if (!rc) *gpu = best3(g) > 0 ? best3(g) : 0;
    return rc;
}

/* The bytes of each copy: 64 MiB on a CPU device (its storage buffers are host memory, at most
 * 128 MiB each on lavapipe), 256 MiB elsewhere where a storage buffer may be that large (a 64 MiB
 * copy is 30 us on an H200: too short to read its memory's rate through a dispatch's ramp). */
static uint64_t copy_bytes(const vkc_device_info *info)
{
    uint64_t big = (uint64_t)256 << 20;
    return strcmp(info->type, "cpu") && info->max_storage_buffer_range >= big ? big : COPY_BYTES;
}

static fb_result measure_vulkan(vkc_context *vk, fb_ceilings *c)
{
    vkc_pipeline *fma = NULL, *copy = NULL;
    vkc_buffer *out = NULL, *src = NULL, *dst = NULL;
    uint64_t bytes = copy_bytes(vkc_info(vk));
    fb_result rc = vkc_pipeline_create(
        vk, &(vkc_pipeline_desc){FB_SPV(ceiling_fma_comp), .push_size = 12, .buffers = 1, .name = "ceiling_fma"}, &fma);
    if (!rc) rc = vkc_buffer_create_kind(vk, (uint64_t)FMA_GROUPS * 64 * 4, VKC_BUFFER_DEVICE, &out);
    struct {
        uint32_t iters;
        float a, b;
    } push = {FMA_ITERS, 0.999f, 0.001f};
    double s = 0, g = 0;
    if (!rc) rc = timed_dispatch(vk, fma, &out, 1, &push, (const uint32_t[3]){FMA_GROUPS, 1, 1}, &s, &g);
    if (!rc) c->vk_gflops = (double)FMA_GROUPS * 64 * FMA_ITERS * 16 / (g > 0 ? g : s) * 1e-9;
    if (!rc)
        rc = vkc_pipeline_create(
            vk, &(vkc_pipeline_desc){FB_SPV(ceiling_copy_comp), .buffers = 2, .name = "ceiling_copy"}, &copy);
    /* Device buffers: a shared buffer on a discrete GPU is copied back to the host after every job,
     * and that copy (over PCIe) is what this figure measured before (issue 41); the contents do not
     * matter to a copy. */
    if (!rc) rc = vkc_buffer_create_kind(vk, bytes, VKC_BUFFER_DEVICE, &dst);
    if (!rc) rc = vkc_buffer_create_kind(vk, bytes, VKC_BUFFER_DEVICE, &src);
    vkc_buffer *pair[2] = {dst, src};
    /* 64 invocations a group, a vec4 each: rows of 32 MiB (2^21 vec4) */
    uint32_t gx = (uint32_t)(COPY_ROW / 16 / 64), rows = (uint32_t)(bytes / COPY_ROW);
    if (!rc) rc = timed_dispatch(vk, copy, pair, 2, NULL, (const uint32_t[3]){gx, rows, 1}, &s, &g);
    if (!rc) c->vk_gbps_wall = 2.0 * (double)bytes / s * 1e-9;
    if (!rc) c->vk_gbps = g > 0 ? 2.0 * (double)bytes / g * 1e-9 : 0;
    vkc_buffer_destroy(vk, &out);
    vkc_buffer_destroy(vk, &src);
    vkc_buffer_destroy(vk, &dst);
    vkc_pipeline_destroy(vk, &fma);
    vkc_pipeline_destroy(vk, &copy);
    vkc_copy_rates r;
    if (!rc) rc = vkc_bench_copies(vk, bytes, 3, &r);
    if (!rc) {
        c->vk_copy_bytes = r.bytes;
        c->vk_copy_gbps = r.device;
        c->vk_upload_gbps = r.upload;
        c->vk_download_gbps = r.download;
    }
    return rc;
}

/* ---- native: FMA chains in AVX2 registers, and memcpy ------------------------------------------ */

typedef struct native_job {
    int ntasks;
    float sink[64];
    uint8_t *src, *dst;
} native_job;

__attribute__((target("avx2,fma"))) static void fma_task(void *ctx, int task)
{
    native_job *j = ctx;
    __m256 a = _mm256_set1_ps(0.999f), b = _mm256_set1_ps(0.001f);
    __m256 x[8];
    for (int k = 0; k < 8; k++) x[k] = _mm256_set1_ps(0.1f * (float)(k + task));
    for (uint32_t it = 0; it < FMA_ITERS * 64; it++)
        for (int k = 0; k < 8; k++) x[k] = _mm256_fmadd_ps(x[k], a, b);
    __m256 s = x[0];
    for (int k = 1; k < 8; k++) s = _mm256_add_ps(s, x[k]);
    float v[8];
    _mm256_storeu_ps(v, s);
    j->sink[task % 64] = v[0];
}

static void copy_task(void *ctx, int task)
{
    native_job *j = ctx;
    uint64_t per = COPY_BYTES / (uint64_t)j->ntasks, at = per * (uint64_t)task;
    memcpy(j->dst + at, j->src + at, per);
}

/* Each of `ntasks` tasks runs 8 x 8 lanes x 64 * FMA_ITERS FMAs (2 FLOP each). */
static double native_flop(int ntasks)
{
    return (double)ntasks * 8 * 8 * 64.0 * FMA_ITERS * 2;
}

static fb_result measure_native(fb_engine *e, fb_ceilings *c)
{
    native_job j = {.ntasks = e->threads > 0 ? e->threads : 1};
    c->threads = j.ntasks;
    double t[3];
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
        for (int run = -1; run < 3; run++) {
            double t0 = fb_now();
            fb_pool_run(e->pool, j.ntasks, fma_task, &j);
            if (run >= 0) t[run] = fb_now() - t0;
        }
        c->native_gflops = native_flop(j.ntasks) / best3(t) * 1e-9;
    }
    j.src = malloc(COPY_BYTES);
    j.dst = malloc(COPY_BYTES);
    if (!j.src || !j.dst) {
        free(j.src);
        free(j.dst);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    memset(j.src, 1, COPY_BYTES);
    memset(j.dst, 0, COPY_BYTES);
    for (int run = -1; run < 3; run++) {
        double t0 = fb_now();
        fb_pool_run(e->pool, j.ntasks, copy_task, &j);
        if (run >= 0) t[run] = fb_now() - t0;
    }
    c->native_gbps = 2.0 * (double)COPY_BYTES / best3(t) * 1e-9;
    free(j.src);
    free(j.dst);
    return FB_OK;
}

static void cpu_name(char *out, size_t size)
{
    out[0] = 0;
    FILE *f = fopen("/proc/cpuinfo", "r");
    char line[512];
    while (f && fgets(line, sizeof line, f)) {
        if (strncmp(line, "model name", 10)) continue;
        const char *v = strchr(line, ':');
        if (!v) continue;
        v += 1 + (v[1] == ' ');
        snprintf(out, size, "%.*s", (int)strcspn(v, "\n"), v);
        break;
    }
    if (f) fclose(f);
}

fb_result fb_ceilings_measure(fb_engine *vk, fb_engine *native, fb_ceilings *out)
{
    memset(out, 0, sizeof *out);
    cpu_name(out->cpu, sizeof out->cpu);
    fb_result rc = FB_OK;
    if (vk && vk->vk) {
        const vkc_device_info *info = vkc_info(vk->vk);
        snprintf(out->device, sizeof out->device, "%s", info->name);
        snprintf(out->driver, sizeof out->driver, "%s", info->driver);
        rc = measure_vulkan(vk->vk, out);
    }
    if (!rc && native) rc = measure_native(native, out);
    return rc;
}
