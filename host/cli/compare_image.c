/* compare's images (compare_int.h): an EXR read in blocks of rows, or a PNG held whole. */
#include "compare_int.h"
#include "textin.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Whether path holds a PNG (else an EXR is read); "-" is an EXR on standard input. */
static fb_result probe_png(const char *path, bool *png)
{
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    *png = false;
    if (!strcmp(path, "-")) return FB_OK;
    FILE *f = NULL;
    fb_result rc = fb_input_open_seekable(path, "EXR or PNG image", &f); /* read twice: here, then by its reader */
    if (rc) return rc;
    uint8_t b[8];
    *png = fread(b, 1, 8, f) == 8 && !memcmp(b, sig, 8);
    fclose(f);
    return FB_OK;
}

fb_result image_open(const char *path, image *im)
{
    memset(im, 0, sizeof *im);
    im->path = path;
    fb_result rc = probe_png(path, &im->is_png);
    if (rc) return rc;
    if (im->is_png) return fb_png_read(path, &im->png);
    return exrio_open(path, &im->exr);
}

void image_close(image *im)
{
    exrio_close(&im->exr);
    fb_png_fini(&im->png);
}

int image_width(const image *im)
{
    return im->is_png ? im->png.width : exrio_width(im->exr);
}

int image_height(const image *im)
{
    return im->is_png ? im->png.height : exrio_height(im->exr);
}

void image_window(const image *im, int w[4])
{
    if (im->is_png)
        w[0] = w[1] = 0, w[2] = im->png.width, w[3] = im->png.height;
    else
        exrio_window(im->exr, &w[0], &w[1], &w[2], &w[3]);
}

int image_nchannels(const image *im)
{
    return im->is_png ? im->png.channels : exrio_nchannels(im->exr);
}

const char *image_channel(const image *im, int c)
{
    return im->is_png ? im->png.names[c] : exrio_channel_name(im->exr, c);
}

bool image_uint(const image *im, int c)
{
    return !im->is_png && exrio_channel_type(im->exr, c) == EXRIO_UINT;
}

int image_find(const image *im, const char *name)
{
    for (int c = 0; c < image_nchannels(im); c++)
        if (!strcmp(image_channel(im, c), name)) return c;
    return -1;
}

fb_result image_read_rows(image *im, int y0, int n, void *const *planes)
{
    if (!im->is_png) return exrio_read_rows(im->exr, y0, n, planes);
    size_t w = (size_t)im->png.width;
    for (int c = 0; c < im->png.channels; c++)
        if (planes[c]) memcpy(planes[c], im->png.plane[c] + (size_t)y0 * w, (size_t)n * w * sizeof(float));
    return FB_OK;
}

/* ---- the compared channels whole ------------------------------------------------------------- */

typedef struct whole_job {
    cmp *k;
    fb_result rc[2];
} whole_job;

static void whole_task(void *ctx, int side)
{
    whole_job *j = ctx;
    cmp *k = j->k;
    j->rc[side] = image_read_rows(side ? &k->B : &k->A, 0, k->H, side ? k->pb : k->pa);
}

fb_result cmp_read_whole(cmp *k)
{
    size_t n = (size_t)k->W * k->H;
    k->ba = calloc((size_t)image_nchannels(&k->A) + 1, sizeof *k->ba);
    k->bb = calloc((size_t)image_nchannels(&k->B) + 1, sizeof *k->bb);
    if (!k->ba || !k->bb) return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int s = 0; s < k->nst; s++) {
        const chan_stats *c = &k->st[s];
        if (!(k->pa[c->ia] = malloc(n ? n * 4 : 1)) || !(k->pb[c->ib] = malloc(n ? n * 4 : 1)))
            return fb_fail(FB_ERR_NOMEM,
                           "out of memory for the compared channels whole (%d of %d x %d, for FLIP or the report)",
                           k->nst, k->W, k->H);
    }
    k->whole = true;
    whole_job j = {.k = k};
    fb_pool_run(k->pool, 2, whole_task, &j); /* both files at once */
    return j.rc[0] ? j.rc[0] : j.rc[1];
}
