/* Float-controls execution modes added to a SPIR-V module (spvpatch.h). */
#include "spvpatch.h"

#include <stdlib.h>
#include <string.h>

enum {
    OP_EXTENSION = 10,
    OP_ENTRY_POINT = 15,
    OP_EXECUTION_MODE = 16,
    OP_CAPABILITY = 17,
    OP_EXECUTION_MODE_ID = 331,
    CAP_FLOAT64 = 10,
    CAP_DENORM_PRESERVE = 4464,
    CAP_SZINP = 4466,
    CAP_RTE = 4467,
    MODE_DENORM_PRESERVE = 4459,
    MODE_SZINP = 4461,
    MODE_RTE = 4462,
};

static const char ext_name[] = "SPV_KHR_float_controls"; /* 23 bytes with its NUL: 6 words */
#define EXT_WORDS 6u

/* Walks the instructions; false on a malformed stream. */
static bool scan(const uint32_t *w, size_t n, size_t *cap_end, size_t *mode_end, bool *f64, bool *has_ext,
                 uint32_t *entries, int *nentries)
{
    *cap_end = *mode_end = 0;
    *f64 = *has_ext = false;
    *nentries = 0;
    for (size_t i = 5; i < n;) {
        uint32_t len = w[i] >> 16, op = w[i] & 0xffffu;
        if (len == 0 || i + len > n) return false;
        if (op == OP_CAPABILITY && len == 2) {
            if (w[i + 1] == CAP_FLOAT64) *f64 = true;
            *cap_end = i + len;
        }
        if (op == OP_EXTENSION && len == 1 + EXT_WORDS && !memcmp(&w[i + 1], ext_name, sizeof ext_name))
            *has_ext = true;
        if (op == OP_ENTRY_POINT && len >= 3) {
            if (*nentries < 8) entries[(*nentries)++] = w[i + 2];
            *mode_end = i + len;
        }
        if (op == OP_EXECUTION_MODE || op == OP_EXECUTION_MODE_ID) *mode_end = i + len;
        i += len;
    }
    return *cap_end && *mode_end && *nentries > 0;
}

const uint32_t *spv_variant(const uint32_t *spv, size_t words, bool native, size_t *out_words)
{
    *out_words = words;
    if (words < 12 || spv[words - 1] != SPV_VARIANTS_MAGIC || spv[words - 2] < 5 || spv[words - 2] > words - 7)
        return spv;
    size_t portable = spv[words - 2];
    *out_words = native ? words - 2 - portable : portable;
    return native ? spv + portable : spv;
}

bool spv_uses_float64(const uint32_t *spv, size_t words)
{
    size_t ce, me;
    bool f64 = false, ext;
    uint32_t entries[8];
    int ne;
    return words > 5 && scan(spv, words, &ce, &me, &f64, &ext, entries, &ne) && f64;
}

fb_result spv_add_float_controls(const uint32_t *spv, size_t words, spv_float_modes m32, spv_float_modes m64,
                                 uint32_t **out, size_t *out_words)
{
    size_t cap_end, mode_end;
    bool f64, has_ext;
    uint32_t entries[8];
    int ne;
    if (words < 5 || spv[0] != 0x07230203u || !scan(spv, words, &cap_end, &mode_end, &f64, &has_ext, entries, &ne))
        return fb_fail(FB_ERR_INTERNAL, "vulkan: a shader module is malformed (spvpatch)");
    if (!f64) m64 = (spv_float_modes){0};
    /* the capabilities and modes, width by width */
    uint32_t caps[3], modes[6][2];
    int nc = 0, nm = 0;
    const struct {
        bool on32, on64;
        uint32_t cap, mode;
    } want[] = {
        {m32.rte, m64.rte, CAP_RTE, MODE_RTE},
        {m32.denorm_preserve, m64.denorm_preserve, CAP_DENORM_PRESERVE, MODE_DENORM_PRESERVE},
        {m32.szinp, m64.szinp, CAP_SZINP, MODE_SZINP},
    };
    for (int k = 0; k < 3; k++) {
        if (!want[k].on32 && !want[k].on64) continue;
        caps[nc++] = want[k].cap;
        if (want[k].on32) modes[nm][0] = want[k].mode, modes[nm++][1] = 32;
        if (want[k].on64) modes[nm][0] = want[k].mode, modes[nm++][1] = 64;
    }
    bool add_ext = nc > 0 && !has_ext && spv[1] < 0x00010400u; /* core from SPIR-V 1.4 */
    size_t extra = 2u * (size_t)nc + (add_ext ? 1u + EXT_WORDS : 0u) + 4u * (size_t)nm * (size_t)ne;
    uint32_t *o = malloc((words + extra) * sizeof *o);
    if (!o) return fb_fail(FB_ERR_NOMEM, "out of memory");
    size_t k = 0;
    memcpy(o, spv, cap_end * sizeof *o);
    k = cap_end;
    for (int i = 0; i < nc; i++) {
        o[k++] = (2u << 16) | OP_CAPABILITY;
        o[k++] = caps[i];
    }
    if (add_ext) {
        o[k++] = ((1u + EXT_WORDS) << 16) | OP_EXTENSION;
        memset(&o[k], 0, EXT_WORDS * sizeof *o);
        memcpy(&o[k], ext_name, sizeof ext_name);
        k += EXT_WORDS;
    }
    memcpy(&o[k], &spv[cap_end], (mode_end - cap_end) * sizeof *o);
    k += mode_end - cap_end;
    for (int e = 0; e < ne; e++)
        for (int i = 0; i < nm; i++) {
            o[k++] = (4u << 16) | OP_EXECUTION_MODE;
            o[k++] = entries[e];
            o[k++] = modes[i][0];
            o[k++] = modes[i][1];
        }
    memcpy(&o[k], &spv[mode_end], (words - mode_end) * sizeof *o);
    k += words - mode_end;
    *out = o;
    *out_words = k;
    return FB_OK;
}
