/* png_decode.c — PNG decoding through libpng (see png_decode.h).
 *
 * libpng reports errors by longjmp: the setjmp is in a function of its own whose only
 * locals are its unchanged parameters, and all state lives in a job struct, so nothing
 * is clobbered; whatever the job allocated is freed by the caller either way. */
#include "textures/png_decode.h"

#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const rgb_names[3] = {"R", "G", "B"};

typedef struct png_job {
    const unsigned char *buf;
    size_t len, pos;
    const char *name;
    char msg[256]; /* libpng's error message */
    ts_status st;  /* a refusal decided between libpng calls (TS_OK: none) */
    ts_error *err;
    unsigned char *pixels;
    png_bytep *rows;
    ts_image *out;
} png_job;

static void read_fn(png_structp png, png_bytep data, png_size_t n)
{
    png_job *j = png_get_io_ptr(png);
    if (n > j->len - j->pos) png_error(png, "the file is truncated");
    memcpy(data, j->buf + j->pos, n);
    j->pos += n;
}

static void error_fn(png_structp png, png_const_charp msg)
{
    png_job *j = png_get_error_ptr(png);
    snprintf(j->msg, sizeof j->msg, "%s", msg ? msg : "unknown error");
    png_longjmp(png, 1);
}

static void warning_fn(png_structp png, png_const_charp msg) { (void)png, (void)msg; }

static void decode_body(png_structp png, png_infop info, png_job *j)
{
    png_set_read_fn(png, j, read_fn);
    png_read_info(png, info);
    png_uint_32 w = 0, h = 0;
    int bit_depth = 0, color_type = 0, interlace = 0;
    png_get_IHDR(png, info, &w, &h, &bit_depth, &color_type, &interlace, NULL, NULL);
    if ((uint64_t)w * h > (uint64_t)TS_IMAGE_MAX_PIXELS) {
        j->st =
            ts_error_set(j->err, TS_ERR_LIMIT, "%s: the image is %u × %u pixels, more than the limit of %lld",
                         j->name, (unsigned)w, (unsigned)h, (long long)TS_IMAGE_MAX_PIXELS);
        return;
    }
    /* Raw scanlines (a filter byte each) inflate from at most 1032 times their
     * compressed size; the whole file bounds the compressed data. */
    uint64_t raw =
        (uint64_t)h * (((uint64_t)w * png_get_channels(png, info) * (uint64_t)bit_depth + 7) / 8 + 1);
    if (raw > 1032 * (uint64_t)j->len + 4096) {
        j->st = ts_error_set(
            j->err, TS_ERR_INVALID,
            "%s: the PNG header promises %u × %u pixels (%llu bytes of scanlines), more than its %zu "
            "bytes can hold",
            j->name, (unsigned)w, (unsigned)h, (unsigned long long)raw, j->len);
        return;
    }
    if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (bit_depth == 16) png_set_strip_16(png); /* the high byte, as pbrt-v3's lodepng */
    if (color_type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
    if (color_type == PNG_COLOR_TYPE_GRAY || color_type == PNG_COLOR_TYPE_GRAY_ALPHA)
        png_set_gray_to_rgb(png);
    if (interlace != PNG_INTERLACE_NONE) (void)png_set_interlace_handling(png);
    png_read_update_info(png, info);
    size_t rowbytes = png_get_rowbytes(png, info);
    if (rowbytes != (size_t)w * 3) {
        j->st = ts_error_set(j->err, TS_ERR_INTERNAL, "%s: libpng gave rows of %zu bytes, not %u × 3",
                             j->name, rowbytes, (unsigned)w);
        return;
    }
    j->pixels = malloc((size_t)w * (size_t)h * 3);
    j->rows = malloc(sizeof *j->rows * (size_t)h);
    if (!j->pixels || !j->rows) {
        j->st = ts_error_set(j->err, TS_ERR_NOMEM, "%s: out of memory for %u × %u pixels", j->name,
                             (unsigned)w, (unsigned)h);
        return;
    }
    for (png_uint_32 y = 0; y < h; y++)
        j->rows[y] = j->pixels + (size_t)y * rowbytes;
    png_read_image(png, j->rows);
    if ((j->st = ts_image_init(j->out, (int)w, (int)h, 3, rgb_names, j->err))) {
        ts_error_prefix(j->err, "%s", j->name);
        return;
    }
    size_t n = (size_t)w * (size_t)h * 3;
    for (size_t i = 0; i < n; i++)
        j->out->data[i] = (float)j->pixels[i] / 255.f;
}

/* Runs decode_body; false if libpng raised an error. */
static int decode_protected(png_structp png, png_infop info, png_job *j)
{
    if (setjmp(png_jmpbuf(png))) return 0;
    decode_body(png, info, j);
    return 1;
}

ts_status ts_png_decode(const unsigned char *buf, size_t len, const char *name, ts_image *out, ts_error *err)
{
    memset(out, 0, sizeof *out);
    if (!name) name = "PNG image";
    if (len < 8 || png_sig_cmp(buf, 0, 8) != 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: not a PNG file (no PNG signature)", name);
    png_job j = {.buf = buf, .len = len, .name = name, .err = err, .out = out};
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &j, error_fn, warning_fn);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_read_struct(png ? &png : NULL, NULL, NULL);
        return ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory starting libpng", name);
    }
    ts_status st = TS_OK;
    if (!decode_protected(png, info, &j))
        st = ts_error_set(err, TS_ERR_INVALID, "%s: the PNG file is corrupt or truncated (libpng: %s)", name,
                          j.msg);
    else
        st = j.st;
    png_destroy_read_struct(&png, &info, NULL);
    free(j.pixels);
    free(j.rows);
    if (st) ts_image_fini(out);
    return st;
}
