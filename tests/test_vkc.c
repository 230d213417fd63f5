/*
 * The Vulkan context's buffer kinds and jobs (host/io/vkc.h): a dispatch into device buffers read
 * back by a job's copies into a host buffer at given offsets (a bake's staging ring) gives the bits
 * a shared buffer gives; a job of copies alone, a device-to-device copy timed with timestamps, an
 * upload into a device buffer, and the bounds a kind refuses. Run on lavapipe (direct-mapped shared buffers) and, as
 * its -staging twin, on the discrete GPU's path (under the layer's synchronization checks: the
 * subnormal probe's buffer is uploaded and then written by its shader, the shape of erosion's). 77
 * where there is no Vulkan device.
 */
#include "env.h"
#include "gen.h"
#include "probe.h"
#include "scene.h"
#include "vkc.h"

#include "testhelp.h"

#include <stdlib.h>
#include <string.h>

enum { W = 300, H = 40 };

/* The fbm layer's shader over rows [y0, y0 + n) into `buf` (device or shared), then `copies`. */
static fb_result fbm_job(vkc_context *vk, vkc_pipeline *pipe, const fb_gen *g, int y0, int n, vkc_buffer *buf,
                         const vkc_copy *copies, uint32_t ncopies, double *gpu)
{
    uint8_t push[FB_GEN_MAX_PUSH];
    uint32_t groups[3];
    fb_gen_push(g, y0, n, push);
    fb_gen_groups(g, n, groups);
    vkc_job *job = NULL;
    fb_result rc = vkc_job_create(vk, pipe, &job);
    if (!rc)
        rc = vkc_job_run(vk, job,
                         &(vkc_submit){.bufs = &buf,
                                       .nbufs = 1,
                                       .push = push,
                                       .groups = {groups[0], groups[1], groups[2]},
                                       .copies = copies,
                                       .ncopies = ncopies});
    if (!rc) rc = vkc_job_wait(vk, job, gpu);
    vkc_job_destroy(vk, &job);
    return rc;
}

int main(void)
{
    vkc_context *vk = NULL;
    fb_env env; /* FB_VK_STAGING: the discrete-GPU path */
    fb_env_read(&env);
    env.vk.validation = env.vk.no_pipeline_cache = true;
    if (vkc_create(&env.vk, &vk)) return 77;
    const vkc_device_info *info = vkc_info(vk);
    CHECK(info->max_workgroup_count[0] >= 65535 && info->max_workgroup_count[1] >= 65535);
    CHECK(info->max_allocation >= info->max_storage_buffer_range || info->max_allocation >= (1u << 30));
    CHECK(info->heap > 0 && info->heap <= info->memory);
    CHECK(info->staging == (env.vk.staging || !info->unified));

    fb_scene s;
    fb_gen g;
    REQUIRE(fb_scene_parse("{\"size\": [300, 40], \"layers\": [{\"type\": \"fbm\", \"octaves\": 5}]}", NULL, &s) ==
            FB_OK);
    REQUIRE(fb_gen_init(&g, &s, &s.layers[0]) == FB_OK);
    vkc_pipeline *pipe = NULL;
    REQUIRE(vkc_pipeline_create(vk,
                                &(vkc_pipeline_desc){.spv = g.compute.shader.spv,
                                                     .spv_size = g.compute.shader.spv_size,
                                                     .push_size = g.compute.shader.push_size,
                                                     .buffers = 1,
                                                     .spec = g.compute.shader.spec,
                                                     .nspec = g.compute.shader.nspec,
                                                     .name = "fbm"},
                                &pipe) == FB_OK);
    const uint64_t bytes = (uint64_t)W * H * 4, half = bytes / 2;
    vkc_buffer *shared = NULL, *dev = NULL, *dev2 = NULL, *host = NULL;
    REQUIRE(vkc_buffer_create(vk, bytes, &shared) == FB_OK);
    REQUIRE(vkc_buffer_create_kind(vk, bytes, VKC_BUFFER_DEVICE, &dev) == FB_OK);
    REQUIRE(vkc_buffer_create_kind(vk, bytes, VKC_BUFFER_DEVICE, &dev2) == FB_OK);
    REQUIRE(vkc_buffer_create_kind(vk, 3 * bytes, VKC_BUFFER_HOST, &host) == FB_OK);
    CHECK(vkc_buffer_data(dev) == NULL && vkc_buffer_data(host) != NULL && vkc_buffer_size(host) == 3 * bytes);

    /* the reference: the whole image in a shared buffer */
    double gpu = 0;
    CHECK(fbm_job(vk, pipe, &g, 0, H, shared, NULL, 0, &gpu) == FB_OK);
    uint8_t *want = malloc(bytes);
    REQUIRE(want);
    memcpy(want, vkc_buffer_data(shared), bytes);
    uint32_t nonzero = 0;
    for (uint64_t i = 0; i < bytes / 4; i++) nonzero += ((const uint32_t *)(const void *)want)[i] != 0;
    CHECKF(nonzero > W * H / 2, "only %u of %d values set", nonzero, W * H);

    /* rows 20-39 into the device buffer, read back at an offset of the host buffer, in two copies of
     * its halves swapped in place */
    const uint64_t rows = half;
    vkc_copy copies[2] = {{.src = dev, .dst = host, .src_offset = 0, .dst_offset = bytes + rows / 2, .size = rows / 2},
                          {.src = dev, .dst = host, .src_offset = rows / 2, .dst_offset = bytes, .size = rows / 2}};
    memset((void *)vkc_buffer_data(host), 0xff, 3 * bytes);
    CHECK(fbm_job(vk, pipe, &g, H / 2, H / 2, dev, copies, 2, NULL) == FB_OK);
    const uint8_t *got = vkc_buffer_data(host);
    CHECK(!memcmp(got + bytes + rows / 2, want + half, rows / 2) &&
          !memcmp(got + bytes, want + half + rows / 2, rows / 2));
    CHECK(got[0] == 0xff && got[bytes - 1] == 0xff && got[2 * bytes] == 0xff); /* nothing else written */

    /* a copy between device buffers with its device time, then a job of copies alone to the host */
    CHECK(fbm_job(vk, pipe, &g, 0, H, dev, NULL, 0, NULL) == FB_OK);
    double copy = 0;
    CHECK(vkc_copy_timed(vk, dev, dev2, bytes, &copy) == FB_OK);
    CHECKF(copy > 0 && copy < 1, "copy time %g s", copy);
    vkc_job *job = NULL;
    REQUIRE(vkc_job_create(vk, NULL, &job) == FB_OK);
    CHECK(vkc_job_run(
              vk, job,
              &(vkc_submit){.copies = &(vkc_copy){.src = dev2, .dst = host, .dst_offset = 2 * bytes, .size = bytes},
                            .ncopies = 1}) == FB_OK);
    double none = 0;
    CHECK(vkc_job_wait(vk, job, &none) == FB_OK);
    CHECK(none == -1 && vkc_job_copy_seconds(job) > 0);
    CHECK(!memcmp(got + 2 * bytes, want, bytes));
    vkc_job_destroy(vk, &job);

    /* an upload into a device buffer (through a host buffer), read back by a job's copy */
    CHECK(vkc_buffer_upload(vk, dev2, want + 8, bytes - 8) == FB_OK);
    REQUIRE(vkc_job_create(vk, NULL, &job) == FB_OK);
    CHECK(vkc_job_run(vk, job,
                      &(vkc_submit){.copies = &(vkc_copy){.src = dev2, .dst = host, .size = bytes - 8},
                                    .ncopies = 1}) == FB_OK);
    CHECK(vkc_job_wait(vk, job, NULL) == FB_OK);
    CHECK(!memcmp(got, want + 8, bytes - 8));
    vkc_job_destroy(vk, &job);

    /* the bounds of each kind: a device buffer over maxStorageBufferRange is refused, a host one may
     * be larger (up to maxMemoryAllocationSize) */
    vkc_buffer *big = NULL;
    CHECK(vkc_buffer_create_kind(vk, info->max_storage_buffer_range + 1, VKC_BUFFER_DEVICE, &big) != FB_OK && !big);
    CHECK(vkc_buffer_create_kind(vk, 0, VKC_BUFFER_HOST, &big) != FB_OK && !big);

    /* the subnormal probe (probe.h): its verdicts, and lavapipe, whose LLVM code multiplies with the
     * CPU's SSE instructions (MXCSR's default: nothing flushed), keeps both */
    CHECK(!strcmp(fb_denormals_verdict(0x00400000u, 0x03800000u), "kept"));
    CHECK(!strcmp(fb_denormals_verdict(0, 0), "flushed"));
    CHECK(!strcmp(fb_denormals_verdict(0, 0x03800000u), "results flushed"));
    CHECK(!strcmp(fb_denormals_verdict(0x00400000u, 0), "operands flushed"));
    CHECK(!strcmp(fb_denormals_verdict(0x00400001u, 0x03800000u), "unexpected"));
    fb_denormals dn;
    CHECK(fb_denormals_probe(vk, &dn) == FB_OK);
    if (!strcmp(info->type, "cpu"))
        CHECKF(dn.product == 0x00400000u && dn.operand == 0x03800000u, "lavapipe's subnormals: %08x %08x", dn.product,
               dn.operand);
    else
        CHECKF(strcmp(dn.verdict, "unexpected"), "the probe's results: %08x %08x", dn.product, dn.operand);

    vkc_buffer_destroy(vk, &shared);
    vkc_buffer_destroy(vk, &dev);
    vkc_buffer_destroy(vk, &dev2);
    vkc_buffer_destroy(vk, &host);
    vkc_pipeline_destroy(vk, &pipe);
    free(want);
    fb_gen_fini(&g);
    fb_scene_fini(&s);
    CHECKF(vkc_validation_messages(vk) == 0, "%u validation messages", vkc_validation_messages(vk));
    vkc_destroy(&vk);
    TEST_REPORT();
}
