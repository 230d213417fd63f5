/* The fp32 subnormal probe: see probe.h. */
#include "probe.h"

#include "denormal_probe_comp.h"

#include <string.h>

#define KEPT_PRODUCT 0x00400000u /* 2^-127 */
#define KEPT_OPERAND 0x03800000u /* 2^-120 */

const char *fb_denormals_verdict(uint32_t product, uint32_t operand)
{
    bool pk = product == KEPT_PRODUCT, pf = product == 0, ok = operand == KEPT_OPERAND, of = operand == 0;
    if (pk && ok) return "kept";
    if (pf && of) return "flushed";
    if (pf && ok) return "results flushed";
    if (pk && of) return "operands flushed";
    return "unexpected";
}

fb_result fb_denormals_probe(vkc_context *vk, fb_denormals *out)
{
    vkc_pipeline *pipe = NULL;
    vkc_buffer *buf = NULL;
    vkc_job *job = NULL;
    /* 2^-126, 0.5, 2^-140, 2^20; the two results */
    const uint32_t in[6] = {0x00800000u, 0x3f000000u, 0x00000200u, 0x49800000u, 0xffffffffu, 0xffffffffu};
    fb_result rc = vkc_pipeline_create(
        vk, &(vkc_pipeline_desc){FB_SPV(denormal_probe_comp), .buffers = 1, .name = "denormal_probe"}, &pipe);
    if (!rc) rc = vkc_buffer_create(vk, sizeof in, &buf);
    if (!rc) rc = vkc_buffer_upload(vk, buf, in, sizeof in);
    if (!rc) rc = vkc_job_create(vk, pipe, &job);
    if (!rc) rc = vkc_job_submit(vk, job, &buf, 1, NULL, (const uint32_t[3]){1, 1, 1});
    if (!rc) rc = vkc_job_wait(vk, job, NULL);
    if (!rc) {
        uint32_t r[6];
        memcpy(r, vkc_buffer_data(buf), sizeof r);
        *out = (fb_denormals){.product = r[4], .operand = r[5], .verdict = fb_denormals_verdict(r[4], r[5])};
    }
    vkc_job_destroy(vk, &job);
    vkc_buffer_destroy(vk, &buf);
    vkc_pipeline_destroy(vk, &pipe);
    return rc;
}
