/*
 * The ZIP compression of EXR chunks, as the format defines it (and OpenEXR writes it): the bytes
 * split into even and odd halves, each byte replaced by its difference from the previous one plus
 * 128 (mod 256), then a zlib stream; a chunk that would not shrink is stored raw. libdeflate does
 * the zlib part, several times faster than zlib at the same ratio. For exrio's writer and reader.
 */
#ifndef FB_EXRZIP_H
#define FB_EXRZIP_H

#include "fb.h"

#include <openexr.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* A compression thread's ZIP state, made at its first ZIP chunk and kept for its life. */
typedef struct exrzip_state {
    struct libdeflate_compressor *dc;
    uint8_t *split, *pred; /* the halves, then the predicted bytes */
    size_t cap;
} exrzip_state;

/* Makes the compressor at `level` (1 to 12) unless made; false when out of memory. */
bool exrzip_start(exrzip_state *z, int level);
void exrzip_state_free(exrzip_state *z);

/* The bytes exrzip_deflate may write for n packed bytes (the state started). */
size_t exrzip_bound(const exrzip_state *z, size_t n);

/* Compresses n packed bytes into out (cap bytes, at least exrzip_bound): *size their count (n: stored
 * raw). */
fb_result exrzip_deflate(exrzip_state *z, int level, const uint8_t *packed, size_t n, uint8_t *out, size_t cap,
                         uint64_t *size);

/* A reader's ZIP state: the decompressor and its buffer. */
typedef struct exrzip_inflater {
    struct libdeflate_decompressor *d;
    uint8_t *buf;
    size_t cap;
} exrzip_inflater;

/* A chunk of `packed` bytes back to its n unpacked bytes; EXR_ERR_CORRUPT_CHUNK when it does not
 * inflate to exactly n. */
exr_result_t exrzip_inflate(exrzip_inflater *r, const void *packed, size_t packed_size, void *unpacked, size_t n);
void exrzip_inflater_free(exrzip_inflater *r);

#endif
