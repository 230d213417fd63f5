/* compare's images (compare_int.h): an EXR read in blocks of rows, or a PNG held whole. */
#include "compare_int.h"
#include "textin.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const uint8_t PNG_SIG[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

/* Standard input made seekable, so that its first bytes can be looked at and then read again by the
 * reader of the format they name: a file as it is, a pipe copied to an unlinked temporary file that
 * becomes file descriptor 0. */
static fb_result stdin_seekable(void)
{
    struct stat st;
    if (fstat(STDIN_FILENO, &st) == 0 && S_ISREG(st.st_mode) && lseek(STDIN_FILENO, 0, SEEK_CUR) >= 0) return FB_OK;
    FILE *t = tmpfile();
    if (!t) return fb_fail(FB_ERR_IO, "-: cannot make a temporary file for standard input: %s", strerror(errno));
    char buf[1 << 16];
    ssize_t n;
    fb_result rc = FB_OK;
    while (!rc && (n = read(STDIN_FILENO, buf, sizeof buf)) != 0) {
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) rc = fb_fail(FB_ERR_INPUT, "-: cannot read standard input: %s", strerror(errno));
        if (!rc && fwrite(buf, 1, (size_t)n, t) != (size_t)n)
            rc = fb_fail(FB_ERR_IO, "-: cannot keep standard input in a temporary file: %s", strerror(errno));
    }
    if (!rc && (fflush(t) || dup2(fileno(t), STDIN_FILENO) < 0 || lseek(STDIN_FILENO, 0, SEEK_SET) != 0))
        rc = fb_fail(FB_ERR_IO, "-: cannot keep standard input in a temporary file: %s", strerror(errno));
    fclose(t); /* descriptor 0 keeps the file */
    return rc;
}

/* Whether path holds a PNG (else an EXR is read); "-", standard input made seekable, is looked at
 * from where it stands. */
static fb_result probe_png(const char *path, bool *png)
{
    uint8_t b[8];
    *png = false;
    if (!strcmp(path, "-")) {
        fb_result rc = stdin_seekable();
        off_t at = rc ? 0 : lseek(STDIN_FILENO, 0, SEEK_CUR);
        if (!rc) *png = pread(STDIN_FILENO, b, 8, at) == 8 && !memcmp(b, PNG_SIG, 8);
        return rc;
    }
    FILE *f = NULL;
    fb_result rc = fb_input_open_seekable(path, "EXR or PNG image", &f); /* read twice: here, then by its reader */
    if (rc) return rc;
    *png = fread(b, 1, 8, f) == 8 && !memcmp(b, PNG_SIG, 8);
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
        if (!(k->pa[c->ia] = fb_malloc_large(n ? n * 4 : 1)) || !(k->pb[c->ib] = fb_malloc_large(n ? n * 4 : 1)))
            return fb_fail(FB_ERR_NOMEM,
                           "out of memory for the compared channels whole (%d of %d x %d, for FLIP or the report)",
                           k->nst, k->W, k->H);
    }
    k->whole = true;
    whole_job j = {.k = k};
    fb_pool_run(k->pool, 2, whole_task, &j); /* both files at once */
    return j.rc[0] ? j.rc[0] : j.rc[1];
}
