/*
 * OpenEXR writing and reading through OpenEXRCore. See exrio.h.
 */
#include "exrio.h"

#include "output.h"
#include "textin.h"

#include <libdeflate.h>
#include <openexr.h>

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

/* OpenEXRCore reports details through a callback; keep the last message of this thread so that
 * the error line we log can carry it. The library itself never prints. */
static _Thread_local char t_exr_msg[512];

static void exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    snprintf(t_exr_msg, sizeof t_exr_msg, "%s (%s)", msg ? msg : "", exr_get_default_error_message(code));
}

static exr_context_initializer_t initializer(void)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_error_cb;
    return init;
}

int exrio_compression_parse(const char *s)
{
    if (!strcmp(s, "none")) return EXRIO_NONE;
    if (!strcmp(s, "zip")) return EXRIO_ZIP;
    if (!strcmp(s, "piz")) return EXRIO_PIZ;
    return -1;
}

const char *exrio_compression_name(exrio_compression c)
{
    return c == EXRIO_ZIP ? "zip" : c == EXRIO_PIZ ? "piz" : "none";
}

const char *exrio_type_name(exrio_type t)
{
    return t == EXRIO_UINT ? "uint" : t == EXRIO_HALF ? "half" : "float";
}

static exr_pixel_type_t pixel_type(exrio_type t)
{
    return t == EXRIO_UINT ? EXR_PIXEL_UINT : t == EXRIO_HALF ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
}

/* ---- writer --------------------------------------------------------------------------------- */

/* One batch of whole chunks (of every part): the rows as given (4 bytes a value), then the
 * compressed chunks of each part. */
typedef struct batch {
    int y0, nrows;
    uint8_t *rows; /* nchannels planes of nrows * width values */
    int nchunks[EXRIO_MAX_PARTS];
    void **chunk_data[EXRIO_MAX_PARTS]; /* compressed bytes of each chunk, written in order */
    uint64_t *chunk_size[EXRIO_MAX_PARTS];
    bool done;
    struct batch *next; /* queue link */
} batch;

/* One part of the file. OpenEXRCore writes the parts one after the other, so the chunks of every
 * part but the first go to a spool file (unlinked, beside the output) and are copied in at the end:
 * memory stays bounded and each strip is computed once. */
typedef struct wpart {
    int chunk_rows;
    int nch;
    int *file_order; /* file_order[i]: index into the caller's channel list of the part's i-th channel */
    FILE *spool;
    bool zip; /* ZIP chunks: OpenEXRCore packs them, libdeflate compresses them (deflate_chunk) */
} wpart;

struct exrio_writer {
    exr_context_t ctx;
    char path[4096];
    int fd; /* the output transaction's temporary file (output.h) */
    int width, height, nchannels;
    int x0, y0, row_stride;
    exrio_type *types;
    int nparts;
    wpart parts[EXRIO_MAX_PARTS];
    int batch_rows;
    size_t plane_bytes_per_row;
    int zip_level;

    batch *filling; /* the batch receiving rows */
    int next_row;

    pthread_mutex_t mu;
    pthread_cond_t cv;
    batch *queue_head, *queue_tail; /* not yet taken by a worker */
    batch **order;                  /* every submitted batch by sequence, for in-order commit */
    int submitted, committed, in_flight, max_in_flight;
    bool stopping;
    fb_result error;
    char error_msg[600];
    pthread_t *threads;
    int nthreads;
};

static void batch_free(batch *b)
{
    if (!b) return;
    for (int p = 0; p < EXRIO_MAX_PARTS; p++) {
        for (int i = 0; i < b->nchunks[p] && b->chunk_data[p]; i++) free(b->chunk_data[p][i]);
        free(b->chunk_data[p]);
        free(b->chunk_size[p]);
    }
    free(b->rows);
    free(b);
}

static void set_error(exrio_writer *w, fb_result rc, const char *msg)
{
    if (w->error) return;
    w->error = rc;
    snprintf(w->error_msg, sizeof w->error_msg, "%s", msg);
}

uint64_t exrio_zip_state_bytes(int level)
{
    if (level <= 0) level = EXRIO_ZIP_LEVEL;
    return level <= 1 ? (uint64_t)200 << 10 : level <= 9 ? (uint64_t)656 << 10 : (uint64_t)8800 << 10;
}

/* OpenEXRCore packs a ZIP chunk and this compresses it: the pipeline's own step is a no-op. */
static exr_result_t pack_only(exr_encode_pipeline_t *enc)
{
    enc->compressed_bytes = enc->packed_bytes;
    return EXR_ERR_SUCCESS;
}

/* The sample of a chunk deflated at level 1 to decide whether deflating the rest pays (deflate_chunk). */
#define ZIP_SAMPLE 16384

/* A compression thread's ZIP state, made at its first ZIP chunk and kept for its life. */
typedef struct zip_state {
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
 * *out receives malloc'd bytes, *size their count. */
static fb_result deflate_chunk(zip_state *z, int level, const uint8_t *packed, size_t n, void **out, uint64_t *size)
{
    if (z->cap < n) {
        uint8_t *a = realloc(z->split, n), *b = a ? realloc(z->pred, n) : NULL;
        if (a) z->split = a;
        if (!b) return FB_ERR_NOMEM;
        z->pred = b, z->cap = n;
    }
    zip_predict(packed, z->split, z->pred, n);
    size_t bound = libdeflate_zlib_compress_bound(z->dc, n);
    uint8_t *c = malloc(bound ? bound : 1);
    if (!c) return FB_ERR_NOMEM;
    size_t half = (n + 1) / 2, zn = 0;
    bool worth = n > 0;
    if (level == 1 && half >= 4 * ZIP_SAMPLE) {
        size_t zs = libdeflate_zlib_compress(z->dc, z->pred, ZIP_SAMPLE, c, bound);
        zs += zs ? libdeflate_zlib_compress(z->dc, z->pred + half, ZIP_SAMPLE, c, bound) : 0;
        worth = zs > 0 && zs * 16 < (size_t)2 * ZIP_SAMPLE * 15;
    }
    if (worth) zn = libdeflate_zlib_compress(z->dc, z->pred, n, c, bound);
    if (zn == 0 || zn >= n) { /* stored raw: the size equal to the packed size tells readers so */
        memcpy(c, packed, n);
        zn = n;
    }
    *out = zn < bound ? realloc(c, zn ? zn : 1) : c;
    if (!*out) *out = c;
    *size = zn;
    return FB_OK;
}

/* Packs and compresses every chunk of a batch (no lock held: OpenEXRCore allows concurrent encoding
 * of different chunks; we clear yield/write so that nothing is written from here). */
static fb_result encode_batch(exrio_writer *w, batch *b, zip_state *z, char *msg, size_t msgsz)
{
    fb_result rc = FB_OK;
    for (int p = 0; p < w->nparts && !rc; p++) {
        const wpart *wp = &w->parts[p];
        if (wp->zip && !z->dc && !(z->dc = libdeflate_alloc_compressor(w->zip_level))) {
            snprintf(msg, msgsz, "out of memory starting the ZIP compressor");
            rc = FB_ERR_NOMEM;
            break;
        }
        exr_encode_pipeline_t enc = {0};
        bool init = false;
        for (int k = 0; k < b->nchunks[p]; k++) {
            int y = b->y0 + k * wp->chunk_rows;
            exr_chunk_info_t cinfo;
            exr_result_t er = exr_write_scanline_chunk_info(w->ctx, p, y + w->y0, &cinfo);
            if (er == EXR_ERR_SUCCESS)
                er = init ? exr_encoding_update(w->ctx, p, &cinfo, &enc)
                          : exr_encoding_initialize(w->ctx, p, &cinfo, &enc);
            if (er != EXR_ERR_SUCCESS) goto exr_fail;
            init = true;
            for (int c = 0; c < enc.channel_count; c++) {
                int src = wp->file_order[c];
                size_t row_bytes = (size_t)w->width * 4;
                enc.channels[c].encode_from_ptr =
                    b->rows + (size_t)src * b->nrows * row_bytes + (size_t)(y - b->y0) * row_bytes;
                enc.channels[c].user_pixel_stride = 4;
                enc.channels[c].user_line_stride = (int32_t)row_bytes;
                enc.channels[c].user_bytes_per_element = 4;
                enc.channels[c].user_data_type = w->types[src] == EXRIO_UINT ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
            }
            er = exr_encoding_choose_default_routines(w->ctx, p, &enc);
            if (er != EXR_ERR_SUCCESS) goto exr_fail;
            enc.yield_until_ready_fn = NULL;
            enc.write_fn = NULL;
            if (wp->zip) enc.compress_fn = pack_only;
            er = exr_encoding_run(w->ctx, p, &enc);
            if (er != EXR_ERR_SUCCESS) goto exr_fail;
            if (wp->zip) {
                rc = deflate_chunk(z, w->zip_level, enc.packed_buffer, enc.packed_bytes, &b->chunk_data[p][k],
                                   &b->chunk_size[p][k]);
                if (rc) {
                    snprintf(msg, msgsz, "out of memory compressing rows %d..%d", y, y + cinfo.height - 1);
                    break;
                }
                continue;
            }
            b->chunk_size[p][k] = enc.compressed_bytes;
            b->chunk_data[p][k] = malloc(enc.compressed_bytes ? enc.compressed_bytes : 1);
            if (!b->chunk_data[p][k]) {
                snprintf(msg, msgsz, "out of memory compressing rows %d..%d", y, y + cinfo.height - 1);
                rc = FB_ERR_NOMEM;
                break;
            }
            /* A chunk whose size equals its packed size is raw to every reader. OpenEXRCore 3.1.5
             * (Debian 12) falls back to the raw rows only when deflate's output is larger, so a chunk
             * that deflates to exactly its raw size was written compressed and read back as garbage
             * (a julia layer storing only `de` hit it). The packed rows are the raw data. */
            const void *bytes = enc.compressed_bytes == enc.packed_bytes ? enc.packed_buffer : enc.compressed_buffer;
            memcpy(b->chunk_data[p][k], bytes, enc.compressed_bytes);
            continue;
        exr_fail:
            snprintf(msg, msgsz, "%s: encoding rows from %d failed: %s", w->path, y, t_exr_msg);
            rc = FB_ERR_EXR;
            break;
        }
        if (init) exr_encoding_destroy(w->ctx, &enc);
    }
    free(b->rows); /* the raw rows are no longer needed: keep only compressed data in memory */
    b->rows = NULL;
    return rc;
}

/* Writes, in order, every finished batch at the head of the sequence. Called with w->mu held;
 * only one thread commits at a time because the lock is held throughout. */
static void commit_ready(exrio_writer *w)
{
    while (w->committed < w->submitted && w->order[w->committed] && w->order[w->committed]->done) {
        batch *b = w->order[w->committed];
        for (int k = 0; k < b->nchunks[0] && !w->error; k++) {
            int y = b->y0 + k * w->parts[0].chunk_rows;
            exr_result_t er = exr_write_scanline_chunk(w->ctx, 0, y + w->y0, b->chunk_data[0][k], b->chunk_size[0][k]);
            if (er != EXR_ERR_SUCCESS) {
                char m[600];
                snprintf(m, sizeof m, "%s: writing rows from %d failed: %s", w->path, y, t_exr_msg);
                set_error(w, er == EXR_ERR_WRITE_IO ? FB_ERR_IO : FB_ERR_EXR, m);
            }
        }
        for (int p = 1; p < w->nparts && !w->error; p++) /* spooled: size, then bytes */
            for (int k = 0; k < b->nchunks[p] && !w->error; k++)
                if (fwrite(&b->chunk_size[p][k], 8, 1, w->parts[p].spool) != 1 ||
                    fwrite(b->chunk_data[p][k], 1, b->chunk_size[p][k], w->parts[p].spool) != b->chunk_size[p][k]) {
                    char m[600];
                    snprintf(m, sizeof m, "%s: cannot spool part %d: %s", w->path, p, strerror(errno));
                    set_error(w, FB_ERR_IO, m);
                }
        w->order[w->committed] = NULL;
        batch_free(b);
        w->committed++;
        w->in_flight--;
        pthread_cond_broadcast(&w->cv);
    }
}

static void *worker_main(void *arg)
{
    exrio_writer *w = arg;
    zip_state z = {0};
    pthread_mutex_lock(&w->mu);
    for (;;) {
        while (!w->queue_head && !w->stopping) pthread_cond_wait(&w->cv, &w->mu);
        if (!w->queue_head) break;
        batch *b = w->queue_head;
        w->queue_head = b->next;
        if (!w->queue_head) w->queue_tail = NULL;
        bool skip = w->error != FB_OK;
        pthread_mutex_unlock(&w->mu);
        char msg[600] = "";
        fb_result rc = skip ? FB_OK : encode_batch(w, b, &z, msg, sizeof msg);
        pthread_mutex_lock(&w->mu);
        if (rc) set_error(w, rc, msg);
        b->done = true;
        commit_ready(w);
    }
    pthread_mutex_unlock(&w->mu);
    libdeflate_free_compressor(z.dc);
    free(z.split);
    free(z.pred);
    return NULL;
}

static batch *batch_new(exrio_writer *w, int y0)
{
    batch *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    b->y0 = y0;
    b->nrows = w->batch_rows;
    if (y0 + b->nrows > w->height) b->nrows = w->height - y0;
    b->rows = malloc(w->plane_bytes_per_row * (size_t)w->nchannels * (size_t)b->nrows);
    bool ok = b->rows != NULL;
    for (int p = 0; p < w->nparts; p++) {
        b->nchunks[p] = (b->nrows + w->parts[p].chunk_rows - 1) / w->parts[p].chunk_rows;
        b->chunk_data[p] = calloc((size_t)b->nchunks[p], sizeof *b->chunk_data[p]);
        b->chunk_size[p] = calloc((size_t)b->nchunks[p], sizeof *b->chunk_size[p]);
        ok = ok && b->chunk_data[p] && b->chunk_size[p];
    }
    if (!ok) {
        batch_free(b);
        return NULL;
    }
    return b;
}

/* OpenEXRCore's write callback: every write at its offset, into the transaction's file. */
static int64_t write_fd(exr_const_context_t ctxt, void *user, const void *buf, uint64_t size, uint64_t offset,
                        exr_stream_error_func_ptr_t error_cb)
{
    const exrio_writer *w = user;
    uint64_t done = 0;
    while (done < size) {
        ssize_t n = pwrite(w->fd, (const uint8_t *)buf + done, size - done, (off_t)(offset + done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            error_cb(ctxt, EXR_ERR_WRITE_IO, "%s", strerror(n < 0 ? errno : EIO));
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)size;
}

static void free_unstarted(exrio_writer *w)
{
    pthread_mutex_destroy(&w->mu);
    pthread_cond_destroy(&w->cv);
    free(w);
}

fb_result exrio_writer_create(const exrio_writer_desc *d, exrio_writer **out)
{
    fb_result rc = FB_OK;
    exrio_writer *w = calloc(1, sizeof *w);
    if (!w) return fb_fail(FB_ERR_NOMEM, "out of memory");
    pthread_mutex_init(&w->mu, NULL);
    pthread_cond_init(&w->cv, NULL);
    snprintf(w->path, sizeof w->path, "%s", d->path);
    w->width = d->width;
    w->height = d->height;
    w->nchannels = d->nchannels;
    w->plane_bytes_per_row = (size_t)d->width * 4;
    w->x0 = d->x0;
    w->y0 = d->y0;
    w->row_stride = d->row_stride > 0 ? d->row_stride : d->width;

    w->fd = -1;
    if ((rc = fb_output_open(d->path, d->what ? d->what : "output", &w->fd))) {
        free_unstarted(w);
        return rc;
    }

    exr_context_initializer_t init = initializer();
    init.user_data = w;
    init.write_fn = write_fd; /* OpenEXRCore opens nothing: the filename is for its messages */
    exr_result_t er = exr_start_write(&w->ctx, d->path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (er != EXR_ERR_SUCCESS) {
        w->ctx = NULL;
        rc = fb_fail(FB_ERR_EXR, "%s: cannot start the output file: %s", d->path, t_exr_msg);
        goto fail;
    }
    w->nparts = d->nparts > 0 ? d->nparts : 1;
    if (w->nparts > EXRIO_MAX_PARTS) {
        rc = fb_fail(FB_ERR_INTERNAL, "%s: %d parts (at most %d)", d->path, w->nparts, EXRIO_MAX_PARTS);
        goto fail;
    }
    for (int p = 0; p < w->nparts && er == EXR_ERR_SUCCESS; p++) {
        int part = 0;
        exrio_compression comp = d->part_compression ? d->part_compression[p] : d->compression;
        exr_compression_t ct = comp == EXRIO_ZIP   ? EXR_COMPRESSION_ZIP
                               : comp == EXRIO_PIZ ? EXR_COMPRESSION_PIZ
                                                   : EXR_COMPRESSION_NONE;
        w->parts[p].zip = ct == EXR_COMPRESSION_ZIP;
        er = exr_add_part(w->ctx, d->part_names ? d->part_names[p] : "fractalbake", EXR_STORAGE_SCANLINE, &part);
        if (er == EXR_ERR_SUCCESS) er = exr_initialize_required_attr_simple(w->ctx, part, d->width, d->height, ct);
        if (er == EXR_ERR_SUCCESS && d->full_width > 0) {
            exr_attr_box2i_t dw, disp;
            dw.min.x = d->x0, dw.min.y = d->y0, dw.max.x = d->x0 + d->width - 1, dw.max.y = d->y0 + d->height - 1;
            disp.min.x = 0, disp.min.y = 0, disp.max.x = d->full_width - 1, disp.max.y = d->full_height - 1;
            er = exr_set_display_window(w->ctx, part, &disp);
            if (er == EXR_ERR_SUCCESS) er = exr_set_data_window(w->ctx, part, &dw);
        }
        for (int c = 0; c < d->nchannels && er == EXR_ERR_SUCCESS; c++)
            if (d->channels[c].part == p)
                er = exr_add_channel(
                    w->ctx, part, d->channels[c].name, pixel_type(d->channels[c].type),
                    d->channels[c].type == EXRIO_UINT ? EXR_PERCEPTUALLY_LINEAR : EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        for (int a = 0; a < d->nattrs && er == EXR_ERR_SUCCESS && p == 0; a++)
            er = exr_attr_set_string(w->ctx, part, d->attrs[a].name, d->attrs[a].value);
    }
    if (er == EXR_ERR_SUCCESS) er = exr_write_header(w->ctx);
    if (er != EXR_ERR_SUCCESS) {
        rc = fb_fail(FB_ERR_EXR, "%s: cannot write the EXR header: %s", d->path, t_exr_msg);
        goto fail;
    }
    w->batch_rows = 64; /* a multiple of every scanline compression's chunk height used (1, 16, 32) */
    w->types = calloc((size_t)d->nchannels, sizeof *w->types);
    if (!w->types) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto fail;
    }
    for (int c = 0; c < d->nchannels; c++) w->types[c] = d->channels[c].type;
    int total = 0;
    for (int p = 0; p < w->nparts; p++) {
        wpart *wp = &w->parts[p];
        int32_t spc = 1;
        exr_get_scanlines_per_chunk(w->ctx, p, &spc);
        wp->chunk_rows = spc > 0 ? spc : 1;
        /* The file stores channels sorted by name; map each back to the caller's plane index. */
        const exr_attr_chlist_t *cl = NULL;
        exr_get_channels(w->ctx, p, &cl);
        wp->nch = cl ? cl->num_channels : 0;
        wp->file_order = calloc((size_t)wp->nch + 1, sizeof *wp->file_order);
        if (!wp->file_order || wp->nch == 0 || w->batch_rows % wp->chunk_rows) {
            rc = fb_fail(FB_ERR_INTERNAL, "%s: part %d has no channels or chunks of %d rows", d->path, p,
                         wp->chunk_rows);
            goto fail;
        }
        for (int i = 0; i < cl->num_channels; i++) {
            wp->file_order[i] = -1;
            for (int c = 0; c < d->nchannels; c++)
                if (d->channels[c].part == p && !strcmp(cl->entries[i].name.str, d->channels[c].name))
                    wp->file_order[i] = c;
            if (wp->file_order[i] < 0) {
                rc = fb_fail(FB_ERR_INTERNAL, "%s: channel %s lost", d->path, cl->entries[i].name.str);
                goto fail;
            }
        }
        total += wp->nch;
        if (p > 0) {
            if ((rc = fb_output_spool(d->path, (void **)&wp->spool))) goto fail;
        }
    }
    if (total != d->nchannels) {
        rc = fb_fail(FB_ERR_INTERNAL, "%s: channel list mismatch (duplicate channel names?)", d->path);
        goto fail;
    }

    int nbatches = (d->height + w->batch_rows - 1) / w->batch_rows;
    w->order = calloc((size_t)nbatches + 1, sizeof *w->order);
    w->zip_level = d->zip_level > 0 && d->zip_level <= EXRIO_ZIP_LEVEL_MAX ? d->zip_level : EXRIO_ZIP_LEVEL;
    w->nthreads = d->threads > 0 ? d->threads : fb_cpu_count();
    w->max_in_flight = 2 * w->nthreads + 2;
    w->threads = calloc((size_t)w->nthreads, sizeof *w->threads);
    if (!w->order || !w->threads) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto fail;
    }
    for (int t = 0; t < w->nthreads; t++) {
        if (pthread_create(&w->threads[t], NULL, worker_main, w) != 0) {
            w->nthreads = t;
            rc = fb_fail(FB_ERR_INTERNAL, "cannot start EXR compression threads");
            goto fail;
        }
    }
    *out = w;
    return FB_OK;
fail:
    exrio_writer_abort(&w);
    return rc;
}

/* Hands the filled batch to the workers, waiting while too many are in flight. */
static fb_result submit_filling(exrio_writer *w)
{
    batch *b = w->filling;
    w->filling = NULL;
    pthread_mutex_lock(&w->mu);
    while (w->in_flight >= w->max_in_flight && !w->error) pthread_cond_wait(&w->cv, &w->mu);
    w->order[w->submitted++] = b;
    w->in_flight++;
    if (w->queue_tail)
        w->queue_tail->next = b;
    else
        w->queue_head = b;
    w->queue_tail = b;
    pthread_cond_broadcast(&w->cv);
    fb_result rc = w->error;
    pthread_mutex_unlock(&w->mu);
    return rc;
}

fb_result exrio_writer_rows(exrio_writer *w, int y0, int nrows, const void *const *planes)
{
    if (y0 != w->next_row || nrows < 0 || y0 + nrows > w->height)
        return fb_fail(FB_ERR_INTERNAL, "%s: rows %d..%d given out of order (next is %d)", w->path, y0, y0 + nrows - 1,
                       w->next_row);
    size_t rb = w->plane_bytes_per_row;
    int done = 0;
    while (done < nrows) {
        if (!w->filling && !(w->filling = batch_new(w, w->next_row)))
            return fb_fail(FB_ERR_NOMEM, "out of memory buffering rows for %s", w->path);
        batch *b = w->filling;
        int at = w->next_row - b->y0;
        int n = b->nrows - at;
        if (n > nrows - done) n = nrows - done;
        size_t stride = (size_t)w->row_stride * 4;
        for (int c = 0; c < w->nchannels; c++) {
            const uint8_t *src = (const uint8_t *)planes[c] + (size_t)done * stride;
            if (stride == rb)
                memcpy(b->rows + ((size_t)c * b->nrows + at) * rb, src, (size_t)n * rb);
            else
                for (int r = 0; r < n; r++)
                    memcpy(b->rows + ((size_t)c * b->nrows + at + r) * rb, src + (size_t)r * stride, rb);
        }
        done += n;
        w->next_row += n;
        if (at + n == b->nrows) {
            fb_result rc = submit_filling(w);
            if (rc) {
                pthread_mutex_lock(&w->mu);
                fb_fail(rc, "%s", w->error_msg);
                pthread_mutex_unlock(&w->mu);
                return rc;
            }
        }
    }
    return FB_OK;
}

/* Stops the workers after the queue drains. */
static void stop_workers(exrio_writer *w)
{
    pthread_mutex_lock(&w->mu);
    w->stopping = true;
    pthread_cond_broadcast(&w->cv);
    pthread_mutex_unlock(&w->mu);
    for (int t = 0; t < w->nthreads; t++) pthread_join(w->threads[t], NULL);
    w->nthreads = 0;
}

static void writer_free(exrio_writer *w)
{
    for (int i = w->committed; i < w->submitted; i++) batch_free(w->order[i]);
    batch_free(w->filling);
    free(w->order);
    free(w->threads);
    free(w->types);
    for (int p = 0; p < EXRIO_MAX_PARTS; p++) {
        free(w->parts[p].file_order);
        if (w->parts[p].spool) fclose(w->parts[p].spool);
    }
    pthread_mutex_destroy(&w->mu);
    pthread_cond_destroy(&w->cv);
    memset(w, 0, sizeof *w);
    free(w);
}

/* Writes part p's spooled chunks into the file, in order. */
static fb_result copy_spool(exrio_writer *w, int p)
{
    wpart *wp = &w->parts[p];
    void *buf = NULL;
    size_t cap = 0;
    fb_result rc = FB_OK;
    if (fflush(wp->spool) != 0 || fseek(wp->spool, 0, SEEK_SET) != 0)
        return fb_fail(FB_ERR_IO, "%s: cannot read back the spool of part %d: %s", w->path, p, strerror(errno));
    for (int y = 0; y < w->height && !rc; y += wp->chunk_rows) {
        uint64_t size = 0;
        if (fread(&size, 8, 1, wp->spool) != 1 || size > (1ull << 31)) {
            rc = fb_fail(FB_ERR_IO, "%s: the spool of part %d is short", w->path, p);
            break;
        }
        if (size > cap) {
            void *nb = realloc(buf, size);
            if (!nb) {
                rc = fb_fail(FB_ERR_NOMEM, "out of memory");
                break;
            }
            buf = nb, cap = size;
        }
        if (fread(buf, 1, size, wp->spool) != size) {
            rc = fb_fail(FB_ERR_IO, "%s: the spool of part %d is short", w->path, p);
            break;
        }
        exr_result_t er = exr_write_scanline_chunk(w->ctx, p, y + w->y0, buf, size);
        if (er != EXR_ERR_SUCCESS)
            rc = fb_fail(er == EXR_ERR_WRITE_IO ? FB_ERR_IO : FB_ERR_EXR, "%s: writing part %d failed: %s", w->path, p,
                         t_exr_msg);
    }
    free(buf);
    return rc;
}

fb_result exrio_writer_finish(exrio_writer **pw)
{
    exrio_writer *w = *pw;
    *pw = NULL;
    fb_result rc = FB_OK;
    if (w->next_row != w->height) {
        rc = fb_fail(FB_ERR_INTERNAL, "%s: finished after %d of %d rows", w->path, w->next_row, w->height);
    } else if (w->filling) {
        rc = submit_filling(w);
        if (rc) fb_fail(rc, "%s", w->error_msg);
    }
    stop_workers(w);
    if (!rc && w->error) rc = fb_fail(w->error, "%s", w->error_msg);
    for (int p = 1; p < w->nparts && !rc; p++) rc = copy_spool(w, p);
    exr_result_t er = exr_finish(&w->ctx);
    if (!rc && er != EXR_ERR_SUCCESS)
        rc = fb_fail(er == EXR_ERR_WRITE_IO ? FB_ERR_IO : FB_ERR_EXR, "%s: cannot complete the file: %s", w->path,
                     t_exr_msg);
    if (close(w->fd) != 0 && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write: %s", w->path, strerror(errno));
    w->fd = -1;
    rc = fb_output_done(w->path, rc); /* renamed with the run's other outputs (output.h) */
    writer_free(w);
    return rc;
}

void exrio_writer_abort(exrio_writer **pw)
{
    if (!pw || !*pw) return;
    exrio_writer *w = *pw;
    *pw = NULL;
    pthread_mutex_lock(&w->mu);
    w->error = w->error ? w->error : FB_ERR_INTERNAL; /* workers skip what is left */
    pthread_mutex_unlock(&w->mu);
    stop_workers(w);
    if (w->ctx) exr_finish(&w->ctx);
    if (w->fd >= 0) {
        close(w->fd);
        fb_output_discard(w->path);
    }
    writer_free(w);
}

/* ---- reader --------------------------------------------------------------------------------- */

struct exrio_reader {
    exr_context_t ctx;
    char path[4096];
    int width, height, x0, y0, full_width, full_height;
    int dw_y;      /* the data window's first row in file coordinates */
    int nchannels; /* over every part: the parts' channels one after the other */
    int nparts;
    struct rpart {
        const exr_attr_chlist_t *chlist;
        int first; /* its first channel's flat index */
        int chunk_rows;
        int buf_rows;       /* rows of chunk_buf per channel: chunk_rows, or the image's height if less */
        uint8_t *chunk_buf; /* one decoded chunk, all channels of the part */
    } parts[EXRIO_MAX_PARTS];
    /* ZIP chunks are inflated by libdeflate (zip_decompress), into inflated[] */
    struct libdeflate_decompressor *inflater;
    uint8_t *inflated;
    size_t inflated_cap;
};

/* A ZIP chunk's pixels, as OpenEXRCore's decompress step gives them (zip_predict undone):
 * libdeflate inflates the zlib stream about twice as fast as zlib, which OpenEXRCore 3.1 uses, and
 * reading (merge, compare, --from) was mostly inflating. A chunk whose size equals its pixels' is
 * stored raw. */
static exr_result_t zip_decompress(exr_decode_pipeline_t *dec)
{
    exrio_reader *r = dec->decoding_user_data;
    size_t packed = dec->chunk.packed_size, n = dec->chunk.unpacked_size, got = 0;
    if (packed == 0) return EXR_ERR_SUCCESS;
    if (packed == n) {
        if (dec->unpacked_buffer != dec->packed_buffer) memcpy(dec->unpacked_buffer, dec->packed_buffer, n);
        return EXR_ERR_SUCCESS;
    }
    if (r->inflated_cap < n) {
        uint8_t *b = realloc(r->inflated, n);
        if (!b) return EXR_ERR_OUT_OF_MEMORY;
        r->inflated = b, r->inflated_cap = n;
    }
    if (!r->inflater && !(r->inflater = libdeflate_alloc_decompressor())) return EXR_ERR_OUT_OF_MEMORY;
    if (libdeflate_zlib_decompress(r->inflater, dec->packed_buffer, packed, r->inflated, n, &got) !=
            LIBDEFLATE_SUCCESS ||
        got != n)
        return EXR_ERR_CORRUPT_CHUNK;
    /* the predictor undone (each byte the previous plus it, less 128), then the even and odd halves
     * interleaved again */
    uint8_t *t = r->inflated, *out = dec->unpacked_buffer;
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

/* The part of flat channel c and c's index within it. */
static int part_of(const exrio_reader *r, int c, int *within)
{
    int p = r->nparts - 1;
    while (p > 0 && c < r->parts[p].first) p--;
    *within = c - r->parts[p].first;
    return p;
}

/* A window the reader can hold: non-empty, its sides within FB_MAX_DIM (the sizes fractalbake bakes),
 * computed without overflow. */
static fb_result check_window(const char *path, int part, const exr_attr_box2i_t *dw, const exr_attr_box2i_t *disp)
{
    int64_t w = (int64_t)dw->max.x - dw->min.x + 1, h = (int64_t)dw->max.y - dw->min.y + 1;
    int64_t fw = (int64_t)disp->max.x - disp->min.x + 1, fh = (int64_t)disp->max.y - disp->min.y + 1;
    if (w < 1 || h < 1 || w > EXRIO_MAX_DIM || h > EXRIO_MAX_DIM || fw < 1 || fh < 1 || fw > EXRIO_MAX_DIM ||
        fh > EXRIO_MAX_DIM)
        return fb_fail(FB_ERR_INPUT,
                       "%s: part %d: data window %lld x %lld, display window %lld x %lld: each side must be 1 to %d",
                       path, part, (long long)w, (long long)h, (long long)fw, (long long)fh, EXRIO_MAX_DIM);
    int64_t ox = (int64_t)dw->min.x - disp->min.x, oy = (int64_t)dw->min.y - disp->min.y;
    if (ox < INT32_MIN / 2 || ox > INT32_MAX / 2 || oy < INT32_MIN / 2 || oy > INT32_MAX / 2)
        return fb_fail(FB_ERR_INPUT, "%s: part %d: the data window lies %lld, %lld pixels from the display window",
                       path, part, (long long)ox, (long long)oy);
    return FB_OK;
}

/* Refuses, before anything is allocated for it, a header that claims more pixels than the file can
 * hold: every chunk needs its offset (8 bytes) and its own header (8), and a chunk's pixels cannot
 * be more than the compression's largest ratio times its bytes (deflate: 1032; RLE: 64; B44: 11;
 * PIZ and DWA, whose Huffman runs have no small bound: 4096). A 1 KB file asking for gigabytes is
 * damaged or hostile, and is bad input. */
static fb_result check_size(const char *path, int part, int w, int h, const struct rpart *rp, exr_compression_t comp,
                            uint64_t file_size)
{
    if (file_size == UINT64_MAX) return FB_OK; /* not a regular file: its size is unknown */
    uint64_t chunks = ((uint64_t)h + (uint64_t)rp->chunk_rows - 1) / (uint64_t)rp->chunk_rows;
    uint64_t bytes = 0;
    for (int c = 0; c < rp->chlist->num_channels; c++)
        bytes += (uint64_t)w * (uint64_t)h * (rp->chlist->entries[c].pixel_type == EXR_PIXEL_HALF ? 2u : 4u);
    double ratio = comp == EXR_COMPRESSION_NONE                                  ? 1
                   : comp == EXR_COMPRESSION_RLE                                 ? 64
                   : comp == EXR_COMPRESSION_ZIPS || comp == EXR_COMPRESSION_ZIP ? 1032
                   : comp == EXR_COMPRESSION_PXR24                               ? 1376
                   : comp == EXR_COMPRESSION_B44 || comp == EXR_COMPRESSION_B44A ? 11
                                                                                 : 4096;
    if (chunks * 16 > file_size || (double)bytes > ratio * (double)file_size + 4096.0)
        return fb_fail(FB_ERR_INPUT,
                       "%s: part %d claims %d x %d pixels in %d channels (%.3g MB of pixels in %llu chunks), more than "
                       "a file of %llu bytes can hold: damaged or not an EXR fractalbake can read",
                       path, part, w, h, rp->chlist->num_channels, (double)bytes * 1e-6, (unsigned long long)chunks,
                       (unsigned long long)file_size);
    return FB_OK;
}

fb_result exrio_open(const char *path, exrio_reader **out)
{
    fb_result rc = FB_OK;
    FILE *probe = NULL;
    if (!strcmp(path, "-")) /* OpenEXR reads by offsets: a pipe will not do */
        return fb_fail(FB_ERR_USAGE, "-: an EXR cannot be read from standard input: give its file");
    if ((rc = fb_input_open(path, "EXR", &probe))) return rc;
    struct stat fst;
    uint64_t file_size = fstat(fileno(probe), &fst) == 0 && S_ISREG(fst.st_mode) ? (uint64_t)fst.st_size : UINT64_MAX;
    fclose(probe);
    if (file_size == UINT64_MAX) /* a FIFO: OpenEXR reads by offsets, and would wait for a writer */
        return fb_fail(FB_ERR_INPUT, "%s: is a FIFO or pipe, not a regular file: an EXR is read by offsets", path);
    exrio_reader *r = calloc(1, sizeof *r);
    if (!r) return fb_fail(FB_ERR_NOMEM, "out of memory");
    snprintf(r->path, sizeof r->path, "%s", path);
    exr_context_initializer_t init = initializer();
    exr_result_t er = exr_start_read(&r->ctx, path, &init);
    if (er != EXR_ERR_SUCCESS) {
        r->ctx = NULL;
        rc = fb_fail(FB_ERR_INPUT, "%s: not a readable OpenEXR file: %s", path, t_exr_msg);
        goto fail;
    }
    int np = 0;
    if (exr_get_count(r->ctx, &np) != EXR_ERR_SUCCESS || np < 1 || np > EXRIO_MAX_PARTS) {
        rc = fb_fail(FB_ERR_INPUT, "%s: %d parts; fractalbake reads 1 to %d", path, np, EXRIO_MAX_PARTS);
        goto fail;
    }
    r->nparts = np;
    exr_attr_box2i_t dw0 = {0}, disp0 = {0};
    for (int p = 0; p < np; p++) {
        exr_storage_t st;
        exr_attr_box2i_t dw, disp;
        struct rpart *rp = &r->parts[p];
        if (exr_get_storage(r->ctx, p, &st) != EXR_ERR_SUCCESS || st != EXR_STORAGE_SCANLINE) {
            rc = fb_fail(FB_ERR_INPUT, "%s: only scanline (not tiled or deep) EXR files are supported", path);
            goto fail;
        }
        if (exr_get_data_window(r->ctx, p, &dw) != EXR_ERR_SUCCESS || exr_get_channels(r->ctx, p, &rp->chlist) ||
            !rp->chlist) {
            rc = fb_fail(FB_ERR_INPUT, "%s: missing data window or channel list", path);
            goto fail;
        }
        if (exr_get_display_window(r->ctx, p, &disp) != EXR_ERR_SUCCESS) disp = dw;
        if ((rc = check_window(path, p, &dw, &disp))) goto fail;
        if (p == 0) {
            dw0 = dw, disp0 = disp;
        } else if (memcmp(&dw, &dw0, sizeof dw) || memcmp(&disp, &disp0, sizeof disp)) {
            rc = fb_fail(FB_ERR_INPUT, "%s: part %d has another data or display window than part 0 (not supported)",
                         path, p);
            goto fail;
        }
        for (int c = 0; c < rp->chlist->num_channels; c++)
            if (rp->chlist->entries[c].x_sampling != 1 || rp->chlist->entries[c].y_sampling != 1) {
                rc = fb_fail(FB_ERR_INPUT, "%s: channel %s is subsampled, which is not supported", path,
                             rp->chlist->entries[c].name.str);
                goto fail;
            }
        rp->first = r->nchannels;
        r->nchannels += rp->chlist->num_channels;
        int32_t spc = 1;
        exr_get_scanlines_per_chunk(r->ctx, p, &spc);
        rp->chunk_rows = spc > 0 ? spc : 1;
        int w = dw.max.x - dw.min.x + 1, n = rp->chlist->num_channels;
        exr_compression_t comp = EXR_COMPRESSION_NONE;
        exr_get_compression(r->ctx, p, &comp);
        if ((rc = check_size(path, p, w, dw.max.y - dw.min.y + 1, rp, comp, file_size))) goto fail;
        rp->buf_rows = rp->chunk_rows < dw.max.y - dw.min.y + 1 ? rp->chunk_rows : dw.max.y - dw.min.y + 1;
        if (!(rp->chunk_buf = malloc((size_t)w * 4 * (size_t)rp->buf_rows * (size_t)(n ? n : 1)))) {
            rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory", path);
            goto fail;
        }
    }
    r->full_width = disp0.max.x - disp0.min.x + 1;
    r->full_height = disp0.max.y - disp0.min.y + 1;
    r->x0 = dw0.min.x - disp0.min.x;
    r->y0 = dw0.min.y - disp0.min.y;
    r->dw_y = dw0.min.y;
    r->width = dw0.max.x - dw0.min.x + 1;
    r->height = dw0.max.y - dw0.min.y + 1;
    *out = r;
    return FB_OK;
fail:
    exrio_close(&r);
    return rc;
}

void exrio_close(exrio_reader **pr)
{
    if (!pr || !*pr) return;
    exrio_reader *r = *pr;
    if (r->ctx) exr_finish(&r->ctx);
    for (int p = 0; p < EXRIO_MAX_PARTS; p++) free(r->parts[p].chunk_buf);
    if (r->inflater) libdeflate_free_decompressor(r->inflater);
    free(r->inflated);
    memset(r, 0, sizeof *r);
    free(r);
    *pr = NULL;
}

int exrio_width(const exrio_reader *r)
{
    return r->width;
}
int exrio_height(const exrio_reader *r)
{
    return r->height;
}
void exrio_window(const exrio_reader *r, int *x0, int *y0, int *full_width, int *full_height)
{
    *x0 = r->x0;
    *y0 = r->y0;
    *full_width = r->full_width;
    *full_height = r->full_height;
}
int exrio_nchannels(const exrio_reader *r)
{
    return r->nchannels;
}
const char *exrio_channel_name(const exrio_reader *r, int c)
{
    int k, p = part_of(r, c, &k);
    return r->parts[p].chlist->entries[k].name.str;
}
int exrio_channel_part(const exrio_reader *r, int c)
{
    int k;
    return part_of(r, c, &k);
}
int exrio_nparts(const exrio_reader *r)
{
    return r->nparts;
}
const char *exrio_part_name(const exrio_reader *r, int p)
{
    const char *name = NULL;
    int32_t len = 0;
    if (exr_attr_get_string(r->ctx, p, "name", &len, &name) != EXR_ERR_SUCCESS) return "";
    return name;
}
exrio_type exrio_channel_type(const exrio_reader *r, int c)
{
    int k, p = part_of(r, c, &k);
    exr_pixel_type_t t = r->parts[p].chlist->entries[k].pixel_type;
    return t == EXR_PIXEL_UINT ? EXRIO_UINT : t == EXR_PIXEL_HALF ? EXRIO_HALF : EXRIO_FLOAT;
}
int exrio_find_channel(const exrio_reader *r, const char *name)
{
    for (int c = 0; c < r->nchannels; c++)
        if (!strcmp(exrio_channel_name(r, c), name)) return c;
    return -1;
}

const char *exrio_compression_of(const exrio_reader *r)
{
    return exrio_part_compression(r, 0);
}

const char *exrio_part_compression(const exrio_reader *r, int p)
{
    exr_compression_t c = EXR_COMPRESSION_NONE;
    exr_get_compression(r->ctx, p, &c);
    static const char *names[] = {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"};
    return (unsigned)c < sizeof names / sizeof names[0] ? names[c] : "unknown";
}

const char *exrio_attr_string(const exrio_reader *r, const char *name)
{
    const char *s = NULL;
    int32_t len = 0;
    if (exr_attr_get_string(r->ctx, 0, name, &len, &s) != EXR_ERR_SUCCESS) return NULL;
    return s;
}

int exrio_attr_count(const exrio_reader *r)
{
    int32_t n = 0;
    exr_get_attribute_count(r->ctx, 0, &n);
    return n;
}

void exrio_attr_at(const exrio_reader *r, int i, const char **name, const char **type)
{
    const exr_attribute_t *a = NULL;
    *name = "?";
    *type = "?";
    if (exr_get_attribute_by_index(r->ctx, 0, EXR_ATTR_LIST_FILE_ORDER, i, &a) == EXR_ERR_SUCCESS && a) {
        *name = a->name;
        *type = a->type_name;
    }
}

static void put_numbers(char *out, size_t size, const double *v, int n)
{
    out[0] = 0;
    for (int i = 0; i < n; i++) {
        char num[40];
        fb_format_shortest(v[i], num, sizeof num);
        snprintf(out + strlen(out), size - strlen(out), "%s%s", i ? "," : "", num);
    }
}

void exrio_attr_text(const exrio_reader *r, int i, char *out, size_t size)
{
    const exr_attribute_t *a = NULL;
    snprintf(out, size, "?");
    if (exr_get_attribute_by_index(r->ctx, 0, EXR_ATTR_LIST_FILE_ORDER, i, &a) != EXR_ERR_SUCCESS || !a) return;
    double v[16];
    switch (a->type) {
    case EXR_ATTR_STRING:
        snprintf(out, size, "%.*s", a->string->length, a->string->str ? a->string->str : "");
        break;
    case EXR_ATTR_STRING_VECTOR:
        out[0] = 0;
        for (int k = 0; k < a->stringvector->n_strings; k++)
            snprintf(out + strlen(out), size - strlen(out), "%s\"%.*s\"", k ? ", " : "",
                     a->stringvector->strings[k].length, a->stringvector->strings[k].str);
        break;
    case EXR_ATTR_INT:
        snprintf(out, size, "%d", a->i);
        break;
    case EXR_ATTR_FLOAT:
        fb_format_shortest(a->f, out, size);
        break;
    case EXR_ATTR_DOUBLE:
        fb_format_shortest(a->d, out, size);
        break;
    case EXR_ATTR_BOX2I:
        snprintf(out, size, "%d,%d,%d,%d", a->box2i->min.x, a->box2i->min.y, a->box2i->max.x, a->box2i->max.y);
        break;
    case EXR_ATTR_BOX2F:
        v[0] = a->box2f->min.x, v[1] = a->box2f->min.y, v[2] = a->box2f->max.x, v[3] = a->box2f->max.y;
        put_numbers(out, size, v, 4);
        break;
    case EXR_ATTR_V2I:
        snprintf(out, size, "%d,%d", a->v2i->x, a->v2i->y);
        break;
    case EXR_ATTR_V3I:
        snprintf(out, size, "%d,%d,%d", a->v3i->x, a->v3i->y, a->v3i->z);
        break;
    case EXR_ATTR_V2F:
        v[0] = a->v2f->x, v[1] = a->v2f->y;
        put_numbers(out, size, v, 2);
        break;
    case EXR_ATTR_V2D:
        put_numbers(out, size, (double[]){a->v2d->x, a->v2d->y}, 2);
        break;
    case EXR_ATTR_V3F:
        v[0] = a->v3f->x, v[1] = a->v3f->y, v[2] = a->v3f->z;
        put_numbers(out, size, v, 3);
        break;
    case EXR_ATTR_V3D:
        put_numbers(out, size, (double[]){a->v3d->x, a->v3d->y, a->v3d->z}, 3);
        break;
    case EXR_ATTR_M33F:
        for (int k = 0; k < 9; k++) v[k] = a->m33f->m[k];
        put_numbers(out, size, v, 9);
        break;
    case EXR_ATTR_M33D:
        put_numbers(out, size, a->m33d->m, 9);
        break;
    case EXR_ATTR_M44F:
        for (int k = 0; k < 16; k++) v[k] = a->m44f->m[k];
        put_numbers(out, size, v, 16);
        break;
    case EXR_ATTR_M44D:
        put_numbers(out, size, a->m44d->m, 16);
        break;
    case EXR_ATTR_FLOAT_VECTOR:
        out[0] = 0;
        for (int k = 0; k < a->floatvector->length; k++) {
            char num[40];
            fb_format_shortest(a->floatvector->arr[k], num, sizeof num);
            snprintf(out + strlen(out), size - strlen(out), "%s%s", k ? "," : "", num);
        }
        break;
    case EXR_ATTR_RATIONAL:
        snprintf(out, size, "%d/%u", a->rational->num, a->rational->denom);
        break;
    case EXR_ATTR_CHROMATICITIES:
        v[0] = a->chromaticities->red_x, v[1] = a->chromaticities->red_y, v[2] = a->chromaticities->green_x;
        v[3] = a->chromaticities->green_y, v[4] = a->chromaticities->blue_x, v[5] = a->chromaticities->blue_y;
        v[6] = a->chromaticities->white_x, v[7] = a->chromaticities->white_y;
        put_numbers(out, size, v, 8);
        break;
    case EXR_ATTR_COMPRESSION: {
        static const char *names[] = {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"};
        snprintf(out, size, "%s", a->uc < sizeof names / sizeof names[0] ? names[a->uc] : "unknown");
        break;
    }
    case EXR_ATTR_LINEORDER: {
        static const char *names[] = {"increasing y", "decreasing y", "random y"};
        snprintf(out, size, "%s", a->uc < 3 ? names[a->uc] : "unknown");
        break;
    }
    case EXR_ATTR_ENVMAP:
        snprintf(out, size, "%s", a->uc == 0 ? "latlong" : a->uc == 1 ? "cube" : "unknown");
        break;
    case EXR_ATTR_CHLIST:
        out[0] = 0;
        for (int k = 0; k < a->chlist->num_channels; k++) {
            const exr_attr_chlist_entry_t *e = &a->chlist->entries[k];
            snprintf(out + strlen(out), size - strlen(out), "%s%.*s %s", k ? ", " : "", e->name.length, e->name.str,
                     e->pixel_type == EXR_PIXEL_UINT   ? "uint"
                     : e->pixel_type == EXR_PIXEL_HALF ? "half"
                                                       : "float");
        }
        break;
    case EXR_ATTR_TILEDESC:
        snprintf(out, size, "%u x %u", a->tiledesc->x_size, a->tiledesc->y_size);
        break;
    case EXR_ATTR_TIMECODE:
        snprintf(out, size, "time %u, user %u", a->timecode->time_and_flags, a->timecode->user_data);
        break;
    case EXR_ATTR_KEYCODE:
        snprintf(out, size, "film %d, prefix %d, count %d", a->keycode->film_mfc_code, a->keycode->prefix,
                 a->keycode->count);
        break;
    case EXR_ATTR_PREVIEW:
        snprintf(out, size, "a %u x %u preview image", a->preview->width, a->preview->height);
        break;
    default:
        snprintf(out, size, "(%d bytes of %s data)", a->opaque ? a->opaque->size : 0, a->type_name);
        break;
    }
}

fb_result exrio_read_rows(exrio_reader *r, int y0, int nrows, void *const *planes)
{
    if (y0 < 0 || nrows < 0 || y0 + nrows > r->height)
        return fb_fail(FB_ERR_INTERNAL, "%s: rows %d..%d out of range", r->path, y0, y0 + nrows - 1);
    fb_result rc = FB_OK;
    size_t rb = (size_t)r->width * 4;
    for (int p = 0; p < r->nparts && !rc; p++) {
        struct rpart *rp = &r->parts[p];
        bool wanted = false;
        for (int c = 0; c < rp->chlist->num_channels; c++) wanted = wanted || planes[rp->first + c];
        if (!wanted) continue;
        exr_decode_pipeline_t dec = {0};
        bool init = false;
        int y = y0;
        while (y < y0 + nrows) {
            exr_chunk_info_t cinfo;
            exr_result_t er = exr_read_scanline_chunk_info(r->ctx, p, y + r->dw_y, &cinfo);
            if (er == EXR_ERR_SUCCESS)
                er = init ? exr_decoding_update(r->ctx, p, &cinfo, &dec)
                          : exr_decoding_initialize(r->ctx, p, &cinfo, &dec);
            if (er != EXR_ERR_SUCCESS) goto exr_fail;
            init = true;
            int cy0 = cinfo.start_y - r->dw_y, ch = cinfo.height;
            for (int c = 0; c < dec.channel_count; c++) {
                int idx = -1;
                for (int k = 0; k < rp->chlist->num_channels; k++)
                    if (!strcmp(rp->chlist->entries[k].name.str, dec.channels[c].channel_name)) idx = k;
                dec.channels[c].decode_to_ptr = rp->chunk_buf + (size_t)idx * rb * (size_t)rp->buf_rows;
                dec.channels[c].user_pixel_stride = 4;
                dec.channels[c].user_line_stride = (int32_t)rb;
                dec.channels[c].user_bytes_per_element = 4;
                dec.channels[c].user_data_type =
                    dec.channels[c].data_type == EXR_PIXEL_UINT ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
            }
            er = exr_decoding_choose_default_routines(r->ctx, p, &dec);
            exr_compression_t comp = EXR_COMPRESSION_NONE;
            exr_get_compression(r->ctx, p, &comp);
            if (comp == EXR_COMPRESSION_ZIP || comp == EXR_COMPRESSION_ZIPS) {
                dec.decoding_user_data = r;
                dec.decompress_fn = zip_decompress;
            }
            if (er == EXR_ERR_SUCCESS) er = exr_decoding_run(r->ctx, p, &dec);
            if (er != EXR_ERR_SUCCESS) goto exr_fail;
            int from = y > cy0 ? y : cy0;
            int to = (y0 + nrows < cy0 + ch) ? y0 + nrows : cy0 + ch;
            for (int c = 0; c < rp->chlist->num_channels; c++) {
                void *dst = planes[rp->first + c];
                if (!dst) continue;
                const uint8_t *src = rp->chunk_buf + (size_t)c * rb * (size_t)rp->buf_rows + (size_t)(from - cy0) * rb;
                memcpy((uint8_t *)dst + (size_t)(from - y0) * rb, src, (size_t)(to - from) * rb);
            }
            y = to;
            continue;
        exr_fail:
            rc = fb_fail(FB_ERR_INPUT, "%s: cannot decode rows from %d: %s", r->path, y, t_exr_msg);
            break;
        }
        if (init) exr_decoding_destroy(r->ctx, &dec);
    }
    return rc;
}
