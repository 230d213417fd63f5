/*
 * The ZIP codec of EXR chunks (exrzip.h), through libdeflate.
 */
#include "exrzip.h"

#include <libdeflate.h>

#include <stdlib.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

bool exrzip_start(exrzip_state *z, int level)
{
    return z->dc || (z->dc = libdeflate_alloc_compressor(level));
}

void exrzip_state_free(exrzip_state *z)
{
    libdeflate_free_compressor(z->dc);
    free(z->split);
    free(z->pred);
    memset(z, 0, sizeof *z);
}

void exrzip_inflater_free(exrzip_inflater *r)
{
    if (r->d) libdeflate_free_decompressor(r->d);
    free(r->buf);
    memset(r, 0, sizeof *r);
}

/* The sample of a chunk deflated at level 1 to decide whether deflating the rest pays (deflate_chunk). */
#define ZIP_SAMPLE 16384

/* A compression thread's ZIP state, made at its first ZIP chunk and kept for its life. */
typedef struct zip_state_unused {
    struct libdeflate_compressor *dc;
    uint8_t *split, *pred; /* the halves, then the predicted bytes */
    size_t cap;
} zip_state;

/* The format's byte split and predictor: out[] is the even bytes then the odd bytes of p[0..n),
 * each (after the first) minus the one before it plus 128. tmp[] holds the split. SSE2 (every
 * x86-64) does 16 bytes a step: the scalar loops ran at 1.1 GB/s, this at about 15. */
static void zip_predict(const uint8_t *restrict p, uint8_t *restrict tmp, uint8_t *restrict out, size_t n)
{
    size_t half = (n + 1) / 2, j = 0, i = 1;
    uint8_t *e = tmp, *o = tmp + half;
#ifdef __SSE2__
    const __m128i lo = _mm_set1_epi16(0xff), k128 = _mm_set1_epi8((char)128);
    for (; j + 16 <= n / 2; j += 16) {
        __m128i a = _mm_loadu_si128((const __m128i *)(p + 2 * j));
        __m128i b = _mm_loadu_si128((const __m128i *)(p + 2 * j + 16));
        _mm_storeu_si128((__m128i *)(e + j), _mm_packus_epi16(_mm_and_si128(a, lo), _mm_and_si128(b, lo)));
        _mm_storeu_si128((__m128i *)(o + j), _mm_packus_epi16(_mm_srli_epi16(a, 8), _mm_srli_epi16(b, 8)));
    }
#endif
    for (; j < n / 2; j++) e[j] = p[2 * j], o[j] = p[2 * j + 1];
    if (n & 1) e[j] = p[2 * j];
    if (!n) return;
    out[0] = tmp[0];
#ifdef __SSE2__
    for (; i + 16 <= n; i += 16) {
        __m128i c = _mm_loadu_si128((const __m128i *)(tmp + i));
        __m128i q = _mm_loadu_si128((const __m128i *)(tmp + i - 1));
        _mm_storeu_si128((__m128i *)(out + i), _mm_add_epi8(_mm_sub_epi8(c, q), k128));
    }
#endif
    for (; i < n; i++) out[i] = (uint8_t)(tmp[i] - tmp[i - 1] + 128);
}

/* A ZIP chunk as the format defines it (and OpenEXR writes it): the bytes split into even and odd
 * halves, then each byte replaced by its difference from the previous one plus 128 (mod 256), then
 * a zlib stream; a chunk that would not shrink is stored raw. libdeflate writes the zlib stream
 * several times faster than zlib at the same ratio (OpenEXR moved to it in 3.2 for this reason).
 *
 * At level 1 (the fastest, the default) a chunk whose sample deflates by less than 1/16 is stored
 * raw without deflating the rest: float noise (fBm's low mantissa bytes) deflates by about 4% at
 * 80 MB/s a core, which made a float fBm bake cost 2.6 times its generation for that 4%. The sample
 * is the first ZIP_SAMPLE bytes of each half (the two halves compress differently: the even one
 * holds the noisiest bytes of a float); over the layers measured (bench/RESULTS.md), float fBm's
 * samples save 1.3 to 1.7% and every other kind's at least 23%, so the cut is far from both.
 * Levels 2 to 12 always deflate the whole chunk.
 * The caller's buffer receives the chunk: no allocation per chunk. */
size_t exrzip_bound(const exrzip_state *z, size_t n)
{
    size_t bound = libdeflate_zlib_compress_bound(z->dc, n);
    return bound > n ? bound : n > 0 ? n : 1;
}

fb_result exrzip_deflate(exrzip_state *z, int level, const uint8_t *packed, size_t n, uint8_t *out, size_t cap,
                         uint64_t *size)
{
    if (NEVER(cap < exrzip_bound(z, n))) return FB_ERR_INTERNAL;
    if (z->cap < n) {
        uint8_t *a = realloc(z->split, n), *b = a ? realloc(z->pred, n) : NULL;
        if (a) z->split = a;
        if (!b) return FB_ERR_NOMEM;
        z->pred = b, z->cap = n;
    }
    zip_predict(packed, z->split, z->pred, n);
    size_t half = (n + 1) / 2, zn = 0;
    bool worth = n > 0;
    if (level == 1 && half >= 4 * ZIP_SAMPLE) {
        size_t zs = libdeflate_zlib_compress(z->dc, z->pred, ZIP_SAMPLE, out, cap);
        zs += zs ? libdeflate_zlib_compress(z->dc, z->pred + half, ZIP_SAMPLE, out, cap) : 0;
        worth = zs > 0 && zs * 16 < (size_t)2 * ZIP_SAMPLE * 15;
    }
    if (worth) zn = libdeflate_zlib_compress(z->dc, z->pred, n, out, cap);
    if (zn == 0 || zn >= n) { /* stored raw: the size equal to the packed size tells readers so */
        memcpy(out, packed, n);
        zn = n;
    }
    *size = zn;
    return FB_OK;
}

/* A ZIP chunk's pixels, as OpenEXRCore's decompress step gives them (exrzip_deflate's predictor undone):
 * libdeflate inflates the zlib stream about twice as fast as zlib, which OpenEXRCore 3.1 uses, and
 * reading (merge, compare, --from) was mostly inflating. A chunk whose size equals its pixels' is
 * stored raw. */
exr_result_t exrzip_inflate(exrzip_inflater *r, const void *packed_buffer, size_t packed, void *unpacked_buffer,
                            size_t n)
{
    size_t got = 0;
    if (packed == 0) return EXR_ERR_SUCCESS;
    if (packed == n) {
        if (unpacked_buffer != packed_buffer) memcpy(unpacked_buffer, packed_buffer, n);
        return EXR_ERR_SUCCESS;
    }
    if (r->cap < n) {
        uint8_t *b = realloc(r->buf, n);
        if (!b) return EXR_ERR_OUT_OF_MEMORY;
        r->buf = b, r->cap = n;
    }
    if (!r->d && !(r->d = libdeflate_alloc_decompressor())) return EXR_ERR_OUT_OF_MEMORY;
    if (libdeflate_zlib_decompress(r->d, packed_buffer, packed, r->buf, n, &got) != LIBDEFLATE_SUCCESS || got != n)
        return EXR_ERR_CORRUPT_CHUNK;
    /* the predictor undone (each byte the previous plus it, less 128), then the even and odd halves
     * interleaved again */
    uint8_t *t = r->buf, *out = unpacked_buffer;
    for (size_t i = 1; i < n; i++) t[i] = (uint8_t)(t[i - 1] + t[i] - 128);
    size_t half = (n + 1) / 2, j = 0;
#ifdef __SSE2__
    for (; j + 16 <= n / 2; j += 16) {
        __m128i e = _mm_loadu_si128((const __m128i *)(t + j)), o = _mm_loadu_si128((const __m128i *)(t + half + j));
        _mm_storeu_si128((__m128i *)(out + 2 * j), _mm_unpacklo_epi8(e, o));
        _mm_storeu_si128((__m128i *)(out + 2 * j + 16), _mm_unpackhi_epi8(e, o));
    }
#endif
    for (; j < n / 2; j++) out[2 * j] = t[j], out[2 * j + 1] = t[half + j];
    if (n & 1) out[n - 1] = t[j];
    return EXR_ERR_SUCCESS;
}
