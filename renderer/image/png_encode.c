/* png_encode.c — 8-bit sRGB PNG encoding with libpng's simplified write API; see png_encode.h. */
#include "image/png_encode.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* libpng itself (this module is png_encode.h, so <png.h> is unambiguous). */
#include <png.h>

uint8_t ts_srgb8_from_linear(float v)
{
    /* Double precision so the result is the correctly rounded code for every float input. */
    double x = (double)v;
    if (!(x > 0)) return 0; /* also NaN */
    if (x >= 1) return 255;
    double s = x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
    long code = lround(s * 255.0);
    return (uint8_t)(code < 0 ? 0 : code > 255 ? 255 : code);
}

/* t[k] = the smallest float x with ts_srgb8_from_linear(x) > k, k = 0..254: bisection over
 * the bit patterns of floats in [0, 1], which are ordered like the floats. About 8000 calls
 * of the reference function per encode instead of one per sample. */
static void srgb8_thresholds(float t[255])
{
    for (int k = 0; k < 255; k++) {
        uint32_t lo = 0x00000000u, hi = 0x3f800000u; /* code(0) = 0 ≤ k < 255 = code(1) */
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            float x;
            memcpy(&x, &mid, sizeof x);
            if (ts_srgb8_from_linear(x) > k) hi = mid;
            else lo = mid;
        }
        memcpy(&t[k], &hi, sizeof t[k]);
    }
}

/* The number of thresholds ≤ x: equals ts_srgb8_from_linear(x) because that function is
 * non-decreasing (tests/test_png.c checks the two agree, boundaries included). */
static uint8_t srgb8_lookup(const float t[255], float x)
{
    if (!(x > 0)) return 0; /* also NaN */
    int lo = 0, hi = 255;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (t[mid] <= x) lo = mid + 1;
        else hi = mid;
    }
    return (uint8_t)lo;
}

ts_status ts_png_encode(const ts_image *img, float exposure_stops, unsigned char **buf, size_t *len, ts_error *err)
{
    *buf = NULL;
    *len = 0;
    if (!img || !img->data || img->width < 1 || img->height < 1 || img->n_channels < 1)
        return ts_error_set(err, TS_ERR_INVALID, "cannot encode PNG: the image is empty or not initialised");
    int rgb[3] = {ts_image_channel(img, "R"), ts_image_channel(img, "G"), ts_image_channel(img, "B")};
    for (int k = 0; k < 3; k++)
        if (rgb[k] < 0)
            return ts_error_set(err, TS_ERR_INVALID, "cannot encode PNG: the image has no channel '%s'",
                                k == 0 ? "R" : k == 1 ? "G" : "B");
    if (!isfinite(exposure_stops))
        return ts_error_set(err, TS_ERR_INVALID, "cannot encode PNG: exposure %g is not a finite number",
                            (double)exposure_stops);

    size_t w = (size_t)img->width, h = (size_t)img->height, n = (size_t)img->n_channels;
    unsigned char *pixels = malloc(w * h * 3);
    if (!pixels) return ts_error_set(err, TS_ERR_NOMEM, "cannot encode PNG: out of memory");
    float scale = exp2f(exposure_stops), thresholds[255];
    srgb8_thresholds(thresholds);
    for (size_t p = 0; p < w * h; p++) {
        const float *src = img->data + p * n;
        for (int k = 0; k < 3; k++) pixels[p * 3 + (size_t)k] = srgb8_lookup(thresholds, src[rgb[k]] * scale);
    }

    ts_status st = TS_OK;
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    image.width = (png_uint_32)w;
    image.height = (png_uint_32)h;
    image.format = PNG_FORMAT_RGB; /* 8-bit, non-linear (sRGB): written with an sRGB chunk */
    png_alloc_size_t cap = PNG_IMAGE_PNG_SIZE_MAX(image);
    unsigned char *out = malloc(cap);
    if (!out) {
        st = ts_error_set(err, TS_ERR_NOMEM, "cannot encode PNG: out of memory");
        goto fail_pixels;
    }
    png_alloc_size_t size = cap;
    if (!png_image_write_to_memory(&image, out, &size, 0, pixels, (png_int_32)(w * 3), NULL)) {
        st = ts_error_set(err, TS_ERR_INTERNAL, "cannot encode PNG: libpng: %s", image.message);
        png_image_free(&image);
        goto fail_out;
    }
    unsigned char *shrunk = realloc(out, size ? size : 1);
    *buf = shrunk ? shrunk : out;
    *len = size;
    free(pixels);
    return TS_OK;

fail_out:
    free(out);
fail_pixels:
    free(pixels);
    return st;
}

ts_status ts_png_write(const char *path, const ts_image *img, float exposure_stops, ts_error *err)
{
    unsigned char *buf = NULL;
    size_t len = 0;
    ts_status st = ts_png_encode(img, exposure_stops, &buf, &len, err);
    if (st) {
        ts_error_prefix(err, "cannot write PNG file '%s'", path ? path : "");
        return st;
    }
    st = ts_image_write_file_atomic(path, buf, len, err);
    free(buf);
    return st;
}
