#include "pngio.h"

#include "output.h"
#include "textin.h"

#include <png.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* libpng reports through these, not on stderr: the message goes into the one error line. */
static _Thread_local char t_png_msg[200];

static void png_error_cb(png_structp png, png_const_charp msg)
{
    snprintf(t_png_msg, sizeof t_png_msg, "%s", msg ? msg : "");
    png_longjmp(png, 1);
}

static void png_warning_cb(png_structp png, png_const_charp msg)
{
    (void)png, (void)msg;
}

void fb_png_fini(fb_png *png)
{
    if (!png) return;
    for (int c = 0; c < 4; c++) free(png->plane[c]);
    memset(png, 0, sizeof *png);
}

fb_result fb_png_read(const char *path, fb_png *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = NULL;
    fb_result rc = fb_input_open(path, "PNG file", &f);
    if (rc) return rc;
    uint8_t sig[8];
    if (fread(sig, 1, 8, f) != 8 || png_sig_cmp(sig, 0, 8)) {
        fclose(f);
        return fb_fail(FB_ERR_INPUT, "%s: not a PNG file (no PNG signature)", path);
    }
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, png_error_cb, png_warning_cb);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    uint8_t *volatile img = NULL; /* volatile: survive libpng's longjmp */
    png_bytep *volatile rows = NULL;
    fb_png *volatile o = out;
    if (!png || !info) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory reading %s", path);
    } else if (setjmp(png_jmpbuf(png))) {
        rc = fb_fail(FB_ERR_INPUT, "%s: a damaged or truncated PNG file (%s)", path, t_png_msg);
    } else {
        png_set_user_limits(png, FB_MAX_DIM, FB_MAX_DIM);
        png_init_io(png, f);
        png_set_sig_bytes(png, 8);
        png_read_info(png, info);
        png_uint_32 w, h;
        int depth, type;
        png_get_IHDR(png, info, &w, &h, &depth, &type, NULL, NULL, NULL);
        o->depth = depth;
        /* palette -> RGB, grey below 8 bits -> 8 bits, tRNS -> alpha; 16-bit samples stay 16 */
        if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
        if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
        if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
        png_set_interlace_handling(png);
        png_read_update_info(png, info);
        int nc = png_get_channels(png, info), bits = png_get_bit_depth(png, info);
        static const char *const names[5][4] = {{0}, {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
        if (nc < 1 || nc > 4) {
            rc = fb_fail(FB_ERR_INPUT, "%s: a PNG with %d channels", path, nc);
        } else if ((rc = fb_memory_check(NULL, (uint64_t)w * h * (uint64_t)nc * 6, path)) == FB_OK) { /* planes, rows */
            o->width = (int)w, o->height = (int)h, o->channels = nc;
            for (int c = 0; c < nc; c++) {
                o->names[c] = names[nc][c];
                if (!(o->plane[c] = malloc((size_t)w * h * sizeof(float)))) rc = FB_ERR_NOMEM;
            }
            size_t rb = png_get_rowbytes(png, info);
            /* the whole image as rows (png_read_image combines an interlaced file's passes) */
            if (!rc) rows = calloc(h, sizeof *rows);
            if (!rc && (!rows || !(img = malloc(rb * h)))) rc = FB_ERR_NOMEM;
            if (rc) {
                rc = fb_fail(FB_ERR_NOMEM, "out of memory reading %s", path);
            } else {
                for (png_uint_32 y = 0; y < h; y++) rows[y] = img + y * rb;
                png_read_image(png, rows);
                double scale = bits == 16 ? 1.0 / 65535.0 : 1.0 / 255.0;
                for (png_uint_32 y = 0; y < h; y++)
                    for (png_uint_32 x = 0; x < w; x++)
                        for (int c = 0; c < nc; c++) {
                            const uint8_t *s = rows[y] + (size_t)(x * nc + c) * (bits == 16 ? 2 : 1);
                            unsigned u = bits == 16 ? (unsigned)s[0] << 8 | s[1] : s[0];
                            o->plane[c][(size_t)y * w + x] = (float)(u * scale);
                        }
                png_read_end(png, NULL);
            }
        }
    }
    png_destroy_read_struct(png ? &png : NULL, info ? &info : NULL, NULL);
    free((void *)img);
    free((void *)rows);
    fclose(f);
    if (rc) fb_png_fini(out);
    return rc;
}

/* The PNG into f; `name` names the destination in messages. */
static fb_result png_to(FILE *f, const char *name, const char *what, int width, int height, int channels, int bits,
                        const void *pix, const char *const (*kv)[2], int nkv)
{
    volatile fb_result rc = FB_OK;
    int bpp = channels * bits / 8;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, png_error_cb, png_warning_cb);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    uint8_t *volatile row = malloc((size_t)width * bpp);
    if (!png || !info || !row) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory writing %s", name);
    } else if (setjmp(png_jmpbuf(png))) {
        rc = fb_fail(FB_ERR_IO, "%s: cannot write %s (%s)", name, what, t_png_msg);
    } else {
        png_init_io(png, f);
        png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, bits,
                     channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
                     PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_text text[8];
        int nt = nkv < 8 ? nkv : 8;
        for (int i = 0; i < nt; i++)
            text[i] =
                (png_text){.compression = PNG_TEXT_COMPRESSION_NONE, .key = (char *)kv[i][0], .text = (char *)kv[i][1]};
        if (nt) png_set_text(png, info, text, nt);
        png_write_info(png, info);
        for (int y = 0; y < height; y++) {
            if (bits == 16) { /* PNG samples are big-endian */
                const uint16_t *src = (const uint16_t *)pix + (size_t)y * width * channels;
                for (int x = 0; x < width * channels; x++)
                    row[2 * x] = (uint8_t)(src[x] >> 8), row[2 * x + 1] = (uint8_t)src[x];
                png_write_row(png, row);
            } else {
                png_write_row(png, (png_const_bytep)pix + (size_t)y * width * bpp);
            }
        }
        png_write_end(png, NULL);
    }
    png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
    free((void *)row);
    return rc;
}

fb_result fb_png_write(const char *path, const char *what, int width, int height, int channels, int bits,
                       const void *pix, const char *const (*kv)[2], int nkv)
{
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, what, (void **)&f);
    if (rc) return rc;
    rc = png_to(f, path, what, width, height, channels, bits, pix, kv, nkv);
    if (fclose(f) != 0 && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write %s: %s", path, what, strerror(errno));
    return fb_output_done(path, rc);
}

fb_result fb_png_encode(int width, int height, int channels, const uint8_t *pix, uint8_t **out, size_t *size)
{
    char *buf = NULL;
    size_t n = 0;
    FILE *f = open_memstream(&buf, &n);
    if (!f) return fb_fail(FB_ERR_NOMEM, "out of memory encoding a PNG");
    fb_result rc = png_to(f, "a picture in memory", "PNG", width, height, channels, 8, pix, NULL, 0);
    if (fclose(f) != 0 && !rc) rc = fb_fail(FB_ERR_NOMEM, "out of memory encoding a PNG");
    if (rc) {
        free(buf);
        return rc;
    }
    *out = (uint8_t *)buf, *size = n;
    return FB_OK;
}
