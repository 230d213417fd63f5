/*
 * The EXR reader (exrio.h), the format's names, and OpenEXRCore's context set-up shared with the
 * writer (exrio_int.h). ZIP chunks are inflated by exrzip.c.
 */
#include "exrio.h"
#include "exrio_int.h"
#include "exrzip.h"

#include "textin.h"

#include <openexr.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* OpenEXRCore reports details through a callback; keep the last message of this thread so that
 * the error line we log can carry it. The library itself never prints. */
static _Thread_local char t_exr_msg[512];

static void exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    snprintf(t_exr_msg, sizeof t_exr_msg, "%s (%s)", msg ? msg : "", exr_get_default_error_message(code));
}

exr_context_initializer_t exrio_initializer(void)
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

const char *exrio_exr_msg(void)
{
    return t_exr_msg;
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
        int first;          /* its first channel's flat index */
        int chunk_rows;     /* scanlines per chunk, or a tile's height */
        int tile_w;         /* tiled parts: a tile's width (0: scanlines); level (0, 0), the top, is read */
        char storage[96];   /* "scanline", or the tiles and their levels */
        int buf_rows;       /* rows of chunk_buf per channel: chunk_rows, or the image's height if less */
        uint8_t *chunk_buf; /* one decoded chunk, all channels of the part */
    } parts[EXRIO_MAX_PARTS];
    exrzip_inflater inflater; /* ZIP chunks (zip_decompress) */
    uint8_t *mem;             /* a file read from standard input, whole */
    size_t mem_size;
};

/* OpenEXRCore's decompress step for ZIP chunks: exrzip_inflate, libdeflate's. */
static exr_result_t zip_decompress(exr_decode_pipeline_t *dec)
{
    exrio_reader *r = dec->decoding_user_data;
    return exrzip_inflate(&r->inflater, dec->packed_buffer, dec->chunk.packed_size, dec->unpacked_buffer,
                          dec->chunk.unpacked_size);
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

/* Standard input, whole, into r->mem (within --max-memory). */
static fb_result slurp_stdin(exrio_reader *r)
{
    size_t cap = 1 << 20;
    if (!(r->mem = malloc(cap))) return fb_fail(FB_ERR_NOMEM, "out of memory reading standard input");
    for (;;) {
        if (r->mem_size == cap) {
            if (fb_memory_check(NULL, (uint64_t)cap * 2, "an EXR on standard input")) return FB_ERR_INPUT;
            uint8_t *b = realloc(r->mem, cap * 2);
            if (!b) return fb_fail(FB_ERR_NOMEM, "out of memory reading standard input");
            r->mem = b, cap *= 2;
        }
        size_t got = fread(r->mem + r->mem_size, 1, cap - r->mem_size, stdin);
        r->mem_size += got;
        if (got == 0) break;
    }
    if (ferror(stdin)) return fb_fail(FB_ERR_IO, "standard input: %s", strerror(errno));
    if (r->mem_size == 0) return fb_fail(FB_ERR_INPUT, "standard input: empty, not an OpenEXR file");
    return FB_OK;
}

static int64_t mem_read(exr_const_context_t ctxt, void *user, void *buf, uint64_t sz, uint64_t offset,
                        exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt, (void)error_cb;
    const exrio_reader *r = user;
    if (offset >= r->mem_size) return 0;
    uint64_t n = r->mem_size - offset < sz ? r->mem_size - offset : sz;
    memcpy(buf, r->mem + offset, n);
    return (int64_t)n;
}

static int64_t mem_size(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return (int64_t)((const exrio_reader *)user)->mem_size;
}

fb_result exrio_open(const char *path, exrio_reader **out)
{
    fb_result rc = FB_OK;
    FILE *probe = NULL;
    bool std_in = !strcmp(path, "-");
    uint64_t file_size = UINT64_MAX;
    if (!std_in) {
        if ((rc = fb_input_open_seekable(path, "EXR", &probe))) return rc; /* OpenEXR reads by offsets */
        struct stat fst;
        if (fstat(fileno(probe), &fst) == 0) file_size = (uint64_t)fst.st_size;
        fclose(probe);
    }
    exrio_reader *r = calloc(1, sizeof *r);
    if (!r) return fb_fail(FB_ERR_NOMEM, "out of memory");
    snprintf(r->path, sizeof r->path, "%s", std_in ? "standard input" : path);
    exr_context_initializer_t init = exrio_initializer();
    if (std_in) { /* OpenEXR reads by offsets: standard input is read whole first */
        if ((rc = slurp_stdin(r))) goto fail;
        file_size = r->mem_size;
        init.user_data = r;
        init.read_fn = mem_read;
        init.size_fn = mem_size;
    }
    exr_result_t er = exr_start_read(&r->ctx, std_in ? "-" : path, &init);
    if (er != EXR_ERR_SUCCESS) {
        r->ctx = NULL;
        rc = fb_fail(FB_ERR_INPUT, "%s: not a readable OpenEXR file: %s", r->path, exrio_exr_msg());
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
        if (exr_get_storage(r->ctx, p, &st) != EXR_ERR_SUCCESS ||
            (st != EXR_STORAGE_SCANLINE && st != EXR_STORAGE_TILED)) {
            rc = fb_fail(FB_ERR_INPUT, "%s: part %d holds deep data; fractalbake reads scanline and tiled parts",
                         r->path, p);
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
        if (st == EXR_STORAGE_TILED) {
            uint32_t tx = 0, ty = 0;
            exr_tile_level_mode_t lm;
            exr_tile_round_mode_t rm;
            if (exr_get_tile_descriptor(r->ctx, p, &tx, &ty, &lm, &rm) != EXR_ERR_SUCCESS || tx < 1 || ty < 1 ||
                tx > EXRIO_MAX_DIM || ty > EXRIO_MAX_DIM) {
                rc = fb_fail(FB_ERR_INPUT, "%s: part %d is tiled without a usable tile size", r->path, p);
                goto fail;
            }
            rp->tile_w = (int)tx, spc = (int32_t)ty;
            snprintf(rp->storage, sizeof rp->storage, "tiled %u x %u%s", tx, ty,
                     lm == EXR_TILE_MIPMAP_LEVELS   ? ", mip-mapped: the top level read"
                     : lm == EXR_TILE_RIPMAP_LEVELS ? ", rip-mapped: the top level read"
                                                    : "");
        } else {
            snprintf(rp->storage, sizeof rp->storage, "scanline");
            exr_get_scanlines_per_chunk(r->ctx, p, &spc);
        }
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
    exrzip_inflater_free(&r->inflater);
    free(r->mem);
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

const char *exrio_part_storage(const exrio_reader *r, int p)
{
    return p >= 0 && p < r->nparts ? r->parts[p].storage : "";
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

exrio_envmap exrio_envmap_of(const exrio_reader *r)
{
    exr_envmap_t e = EXR_ENVMAP_LAST_TYPE;
    if (exr_attr_get_envmap(r->ctx, 0, "envmap", &e) != EXR_ERR_SUCCESS) return EXRIO_ENVMAP_NONE;
    return e == EXR_ENVMAP_LATLONG ? EXRIO_ENVMAP_LATLONG
           : e == EXR_ENVMAP_CUBE  ? EXRIO_ENVMAP_CUBE
                                   : EXRIO_ENVMAP_NONE;
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
        int ntx = rp->tile_w ? (r->width + rp->tile_w - 1) / rp->tile_w : 1;
        while (y < y0 + nrows) {
            int cy0 = 0, ch = 0;
            for (int tx = 0; tx < ntx; tx++) { /* a scanline chunk, or each tile of a row of tiles */
                exr_chunk_info_t cinfo;
                exr_result_t er = rp->tile_w ? exr_read_tile_chunk_info(r->ctx, p, tx, y / rp->chunk_rows, 0, 0, &cinfo)
                                             : exr_read_scanline_chunk_info(r->ctx, p, y + r->dw_y, &cinfo);
                if (er == EXR_ERR_SUCCESS)
                    er = init ? exr_decoding_update(r->ctx, p, &cinfo, &dec)
                              : exr_decoding_initialize(r->ctx, p, &cinfo, &dec);
                if (er != EXR_ERR_SUCCESS) goto exr_fail;
                init = true;
                cy0 = rp->tile_w ? y / rp->chunk_rows * rp->chunk_rows : cinfo.start_y - r->dw_y, ch = cinfo.height;
                size_t xoff = (size_t)tx * (size_t)rp->tile_w * 4;
                if (ch < 1 || ch > rp->buf_rows || cy0 < 0 ||
                    (rp->tile_w && (int)cinfo.width > r->width - tx * rp->tile_w)) {
                    rc = fb_fail(FB_ERR_INPUT, "%s: a chunk of %d rows at row %d does not fit the image", r->path, ch,
                                 cy0);
                    break;
                }
                for (int c = 0; c < dec.channel_count; c++) {
                    int idx = -1;
                    for (int k = 0; k < rp->chlist->num_channels; k++)
                        if (!strcmp(rp->chlist->entries[k].name.str, dec.channels[c].channel_name)) idx = k;
                    dec.channels[c].decode_to_ptr = rp->chunk_buf + (size_t)idx * rb * (size_t)rp->buf_rows + xoff;
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
                continue;
            exr_fail:
                rc = fb_fail(FB_ERR_INPUT, "%s: cannot decode rows from %d: %s", r->path, y, exrio_exr_msg());
                break;
            }
            if (rc) break;
            int from = y > cy0 ? y : cy0;
            int to = (y0 + nrows < cy0 + ch) ? y0 + nrows : cy0 + ch;
            for (int c = 0; c < rp->chlist->num_channels; c++) {
                void *dst = planes[rp->first + c];
                if (!dst) continue;
                const uint8_t *src = rp->chunk_buf + (size_t)c * rb * (size_t)rp->buf_rows + (size_t)(from - cy0) * rb;
                memcpy((uint8_t *)dst + (size_t)(from - y0) * rb, src, (size_t)(to - from) * rb);
            }
            y = to;
        }
        if (init) exr_decoding_destroy(r->ctx, &dec);
    }
    return rc;
}
