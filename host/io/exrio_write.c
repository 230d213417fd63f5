/*
 * The EXR writer (exrio.h): rows in order, batches of chunks compressed by worker threads, written
 * in order under the output transaction's temporary name. ZIP chunks go through exrzip.c.
 */
#include "exrio.h"
#include "exrio_int.h"
#include "exrzip.h"

#include "output.h"

#include <openexr.h>

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static exr_pixel_type_t pixel_type(exrio_type t)
{
    return t == EXRIO_UINT ? EXR_PIXEL_UINT : t == EXRIO_HALF ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
}

/* ---- writer --------------------------------------------------------------------------------- */

/* One batch of whole chunks (of every part): the rows as given (4 bytes a value), then the
 * compressed chunks of each part. The rows are a copy the batch owns, or the caller's, read in place
 * and held (exrio_writer_rows_held) until they are encoded. */
typedef struct batch {
    int y0, nrows;
    uint8_t *rows;       /* the copy: nchannels planes of nrows * width values, or NULL */
    const uint8_t **src; /* channel c's first row (in `rows`, or the caller's) */
    size_t stride;       /* bytes from a row of src[c] to the next */
    exrio_hold hold;     /* the caller's rows: released once encoded (hold.release NULL: a copy) */
    int nchunks[EXRIO_MAX_PARTS];
    void **chunk_data[EXRIO_MAX_PARTS]; /* compressed bytes of each chunk, written in order */
    uint64_t *chunk_size[EXRIO_MAX_PARTS];
    size_t *chunk_cap[EXRIO_MAX_PARTS]; /* the capacity of its buffer */
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
    bool zip; /* ZIP chunks: OpenEXRCore packs them, exrzip_deflate compresses them */
} wpart;

struct exrio_writer {
    exr_context_t ctx;
    fb_scope scope; /* the creating thread's (fb.h), the workers' */
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
    /* Chunk buffers given back once written, taken again by the next chunks (under mu): a bake's
     * chunks need the same few buffers over and over, and a malloc and free of each (hundreds of KiB)
     * costs page faults wherever the allocator returns them to the system. */
    void **spare;
    size_t *spare_cap;
    int nspare, max_spare;
};

/* The batch no longer reads its rows: a copy is freed, the caller's rows are released. */
static void batch_drop_rows(batch *b)
{
    free(b->rows);
    b->rows = NULL;
    if (b->hold.release) b->hold.release(b->hold.ctx);
    b->hold.release = NULL;
}

static void batch_free(batch *b)
{
    if (!b) return;
    batch_drop_rows(b);
    free(b->src);
    for (int p = 0; p < EXRIO_MAX_PARTS; p++) {
        for (int i = 0; i < b->nchunks[p] && b->chunk_data[p]; i++) free(b->chunk_data[p][i]);
        free(b->chunk_data[p]);
        free(b->chunk_size[p]);
        free(b->chunk_cap[p]);
    }
    free(b);
}

/* A buffer of at least `need` bytes for a chunk: a spare one, or a new one. */
static void *chunk_get(exrio_writer *w, size_t need, size_t *cap)
{
    void *buf = NULL;
    pthread_mutex_lock(&w->mu);
    for (int i = w->nspare - 1; i >= 0 && !buf; i--)
        if (w->spare_cap[i] >= need) {
            buf = w->spare[i], *cap = w->spare_cap[i];
            w->spare[i] = w->spare[w->nspare - 1], w->spare_cap[i] = w->spare_cap[w->nspare - 1];
            w->nspare--;
        }
    pthread_mutex_unlock(&w->mu);
    if (!buf && (buf = malloc(need))) *cap = need;
    return buf;
}

/* A written chunk's buffer given back (w->mu held). */
static void chunk_put(exrio_writer *w, void *buf, size_t cap)
{
    if (w->nspare < w->max_spare)
        w->spare[w->nspare] = buf, w->spare_cap[w->nspare++] = cap;
    else
        free(buf);
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

/* Packs and compresses every chunk of a batch (no lock held: OpenEXRCore allows concurrent encoding
 * of different chunks; we clear yield/write so that nothing is written from here). */
static fb_result encode_batch(exrio_writer *w, batch *b, exrzip_state *z, char *msg, size_t msgsz)
{
    fb_result rc = FB_OK;
    for (int p = 0; p < w->nparts && !rc; p++) {
        const wpart *wp = &w->parts[p];
        if (wp->zip && !exrzip_start(z, w->zip_level)) {
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
                enc.channels[c].encode_from_ptr = b->src[src] + (size_t)(y - b->y0) * b->stride;
                enc.channels[c].user_pixel_stride = 4;
                enc.channels[c].user_line_stride = (int32_t)b->stride;
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
            size_t need = wp->zip ? exrzip_bound(z, enc.packed_bytes) : enc.compressed_bytes ? enc.compressed_bytes : 1;
            b->chunk_data[p][k] = chunk_get(w, need, &b->chunk_cap[p][k]);
            if (b->chunk_data[p][k] && wp->zip) {
                rc = exrzip_deflate(z, w->zip_level, enc.packed_buffer, enc.packed_bytes, b->chunk_data[p][k],
                                    b->chunk_cap[p][k], &b->chunk_size[p][k]);
                if (rc) {
                    snprintf(msg, msgsz, "out of memory compressing rows %d..%d", y, y + cinfo.height - 1);
                    break;
                }
                continue;
            }
            b->chunk_size[p][k] = enc.compressed_bytes;
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
            snprintf(msg, msgsz, "%s: encoding rows from %d failed: %s", w->path, y, exrio_exr_msg());
            rc = FB_ERR_EXR;
            break;
        }
        if (init) exr_encoding_destroy(w->ctx, &enc);
    }
    batch_drop_rows(b); /* the raw rows are no longer needed: keep only compressed data in memory */
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
                snprintf(m, sizeof m, "%s: writing rows from %d failed: %s", w->path, y, exrio_exr_msg());
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
        for (int p = 0; p < w->nparts; p++) /* the chunk buffers, for the next batches */
            for (int k = 0; k < b->nchunks[p]; k++)
                if (b->chunk_data[p][k])
                    chunk_put(w, b->chunk_data[p][k], b->chunk_cap[p][k]), b->chunk_data[p][k] = NULL;
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
    exrzip_state z = {0};
    fb_scope_set(w->scope); /* the creating thread's: its log and its transaction */
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
    exrzip_state_free(&z);
    return NULL;
}

/* A batch of the rows from y0: a copy of them to fill (planes NULL), or the caller's planes (row y0
 * `offset` bytes into each, `stride` bytes a row), held. */
static batch *batch_new(exrio_writer *w, int y0, const void *const *planes, size_t offset, size_t stride,
                        const exrio_hold *hold)
{
    batch *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    b->y0 = y0;
    b->nrows = w->batch_rows;
    if (y0 + b->nrows > w->height) b->nrows = w->height - y0;
    b->src = calloc((size_t)w->nchannels, sizeof *b->src);
    bool ok = b->src != NULL;
    if (ok && planes) {
        for (int c = 0; c < w->nchannels; c++) b->src[c] = (const uint8_t *)planes[c] + offset;
        b->stride = stride;
        b->hold = *hold;
        if (hold->retain) hold->retain(hold->ctx);
    } else if (ok) {
        b->rows = malloc(w->plane_bytes_per_row * (size_t)w->nchannels * (size_t)b->nrows);
        ok = b->rows != NULL;
        b->stride = w->plane_bytes_per_row;
        for (int c = 0; c < w->nchannels && ok; c++) b->src[c] = b->rows + (size_t)c * b->nrows * b->stride;
    }
    for (int p = 0; p < w->nparts; p++) {
        b->nchunks[p] = (b->nrows + w->parts[p].chunk_rows - 1) / w->parts[p].chunk_rows;
        b->chunk_data[p] = calloc((size_t)b->nchunks[p], sizeof *b->chunk_data[p]);
        b->chunk_size[p] = calloc((size_t)b->nchunks[p], sizeof *b->chunk_size[p]);
        b->chunk_cap[p] = calloc((size_t)b->nchunks[p], sizeof *b->chunk_cap[p]);
        ok = ok && b->chunk_data[p] && b->chunk_size[p] && b->chunk_cap[p];
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

/* True where a channel is colour: R, G or B, alone or as LAYER.R (OpenEXR's naming). */
static bool file_has_colour(const exrio_writer_desc *d)
{
    for (int c = 0; c < d->nchannels; c++) {
        const char *n = d->channels[c].name, *dot = strrchr(n, '.');
        const char *last = dot ? dot + 1 : n;
        if (!strcmp(last, "R") || !strcmp(last, "G") || !strcmp(last, "B")) return true;
    }
    return false;
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

    exr_context_initializer_t init = exrio_initializer();
    init.user_data = w;
    init.write_fn = write_fd; /* OpenEXRCore opens nothing: the filename is for its messages */
    exr_result_t er = exr_start_write(&w->ctx, d->path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (er != EXR_ERR_SUCCESS) {
        w->ctx = NULL;
        rc = fb_fail(FB_ERR_EXR, "%s: cannot start the output file: %s", d->path, exrio_exr_msg());
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
        /* a file that holds colour says which: scene-linear Rec. 709 primaries, D65 white (ITU-R
         * BT.709), so that a colour-managed tool need not guess. OpenEXR makes chromaticities a shared
         * attribute of a multi-part file (every part the same value, or none: "non-conforming shared
         * attributes" otherwise), so every part carries it when any part has colour. */
        if (er == EXR_ERR_SUCCESS && file_has_colour(d)) {
            const exr_attr_chromaticities_t rec709 = {0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f};
            er = exr_attr_set_chromaticities(w->ctx, part, "chromaticities", &rec709);
        }
        /* every part is an image of the same sphere, so each says so (OpenEXR: 0 latlong, 1 cube) */
        if (er == EXR_ERR_SUCCESS && d->envmap != EXRIO_ENVMAP_NONE)
            er = exr_attr_set_envmap(w->ctx, part, "envmap",
                                     d->envmap == EXRIO_ENVMAP_CUBE ? EXR_ENVMAP_CUBE : EXR_ENVMAP_LATLONG);
        for (int a = 0; a < d->nattrs && er == EXR_ERR_SUCCESS && p == 0; a++)
            er = exr_attr_set_string(w->ctx, part, d->attrs[a].name, d->attrs[a].value);
    }
    if (er == EXR_ERR_SUCCESS) er = exr_write_header(w->ctx);
    if (er != EXR_ERR_SUCCESS) {
        rc = fb_fail(FB_ERR_EXR, "%s: cannot write the EXR header: %s", d->path, exrio_exr_msg());
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
    int most = 0; /* chunks of a batch, in its part of most */
    for (int p = 0; p < w->nparts; p++) most += w->batch_rows / w->parts[p].chunk_rows;
    w->max_spare = (w->max_in_flight + 1) * most;
    w->spare = calloc((size_t)w->max_spare, sizeof *w->spare);
    w->spare_cap = calloc((size_t)w->max_spare, sizeof *w->spare_cap);
    if (!w->order || !w->threads || !w->spare || !w->spare_cap) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto fail;
    }
    w->scope = fb_scope_capture();
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

/* The error the workers met, logged (one line) and returned. */
static fb_result worker_error(exrio_writer *w, fb_result rc)
{
    pthread_mutex_lock(&w->mu);
    fb_fail(rc, "%s", w->error_msg);
    pthread_mutex_unlock(&w->mu);
    return rc;
}

/* Copies rows [first, nrows) of the planes (the next rows of the image) into batches. */
static fb_result copy_rows(exrio_writer *w, const void *const *planes, int first, int nrows)
{
    size_t rb = w->plane_bytes_per_row;
    int done = first;
    while (done < nrows) {
        if (!w->filling && !(w->filling = batch_new(w, w->next_row, NULL, 0, 0, NULL)))
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
            if (rc) return worker_error(w, rc);
        }
    }
    return FB_OK;
}

static fb_result check_order(const exrio_writer *w, int y0, int nrows)
{
    if (y0 != w->next_row || nrows < 0 || y0 + nrows > w->height)
        return fb_fail(FB_ERR_INTERNAL, "%s: rows %d..%d given out of order (next is %d)", w->path, y0, y0 + nrows - 1,
                       w->next_row);
    return FB_OK;
}

fb_result exrio_writer_rows(exrio_writer *w, int y0, int nrows, const void *const *planes)
{
    fb_result rc = check_order(w, y0, nrows);
    return rc ? rc : copy_rows(w, planes, 0, nrows);
}

int exrio_writer_batch_rows(const exrio_writer *w)
{
    return w->batch_rows;
}

fb_result exrio_writer_rows_held(exrio_writer *w, int y0, int nrows, const void *const *planes, const exrio_hold *hold)
{
    fb_result rc = check_order(w, y0, nrows);
    if (rc) return rc;
    size_t stride = (size_t)w->row_stride * 4;
    int done = 0;
    /* whole batches read in place, while the rows start a batch (nothing half-filled before) */
    while (!w->filling && (y0 + done) % w->batch_rows == 0 && done < nrows &&
           (nrows - done >= w->batch_rows || y0 + nrows == w->height)) {
        if (!(w->filling = batch_new(w, y0 + done, planes, (size_t)done * stride, stride, hold)))
            return fb_fail(FB_ERR_NOMEM, "out of memory queueing rows for %s", w->path);
        done += w->filling->nrows;
        w->next_row += w->filling->nrows;
        if ((rc = submit_filling(w))) return worker_error(w, rc);
    }
    return copy_rows(w, planes, done, nrows);
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
    for (int i = 0; i < w->nspare; i++) free(w->spare[i]);
    free(w->spare);
    free(w->spare_cap);
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
                         exrio_exr_msg());
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
                     exrio_exr_msg());
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
