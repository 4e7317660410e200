/* texture_image.c — image files of image textures (see texture_image.h). */
#include "textures/texture_image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "image/exr.h"
#include "textures/mipmap.h"
#include "textures/pfm.h"
#include "textures/png_decode.h"
#include "textures/tga.h"

static const char *extension(const char *filename)
{
    const char *slash = strrchr(filename, '/');
    const char *dot = strrchr(filename, '.');
    return dot && (!slash || dot > slash) ? dot : NULL;
}

ts_texture_image_format ts_texture_image_format_of(const char *filename)
{
    const char *ext = filename ? extension(filename) : NULL;
    if (!ext) return TS_TEXTURE_IMAGE_UNKNOWN;
    if (strcasecmp(ext, ".exr") == 0) return TS_TEXTURE_IMAGE_EXR;
    if (strcasecmp(ext, ".png") == 0) return TS_TEXTURE_IMAGE_PNG;
    if (strcasecmp(ext, ".tga") == 0) return TS_TEXTURE_IMAGE_TGA;
    if (strcasecmp(ext, ".pfm") == 0) return TS_TEXTURE_IMAGE_PFM;
    return TS_TEXTURE_IMAGE_UNKNOWN;
}

bool ts_texture_image_default_gamma(const char *filename)
{
    ts_texture_image_format f = ts_texture_image_format_of(filename);
    return f == TS_TEXTURE_IMAGE_PNG || f == TS_TEXTURE_IMAGE_TGA;
}

float ts_texture_srgb_to_linear(float v)
{
    /* pbrt-v3 writes v * 1.f / 12.92f: a division, as here. */
    if (v <= 0.04045f) return v / 12.92f;
    return powf((v + 0.055f) / 1.055f, 2.4f);
}

static uint32_t be32(const unsigned char *p) { return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]; }

bool ts_texture_image_size(const char *filename, const unsigned char *buf, size_t len, int64_t *width,
                           int64_t *height, int *channels)
{
    *width = *height = 0;
    *channels = 3;
    if (!buf) return false;
    switch (ts_texture_image_format_of(filename)) {
    case TS_TEXTURE_IMAGE_PNG: /* the signature, then IHDR (libpng requires it first) */
        if (len < 24 || memcmp(buf, "\x89PNG\r\n\x1a\n", 8) != 0 || memcmp(buf + 12, "IHDR", 4) != 0) return false;
        *width = be32(buf + 16), *height = be32(buf + 20);
        break;
    case TS_TEXTURE_IMAGE_TGA:
        if (len < 18) return false;
        *width = buf[12] | buf[13] << 8, *height = buf[14] | buf[15] << 8;
        break;
    case TS_TEXTURE_IMAGE_PFM:
        if (!ts_pfm_size(buf, len, width, height)) return false;
        break;
    case TS_TEXTURE_IMAGE_EXR:
        if (!ts_exr_size_memory(buf, len, width, height, channels)) return false;
        break;
    case TS_TEXTURE_IMAGE_UNKNOWN: return false;
    }
    return *width > 0 && *height > 0;
}

ts_status ts_texture_image_decode(const char *filename, const unsigned char *buf, size_t len, ts_image *out,
                                  ts_error *err)
{
    memset(out, 0, sizeof *out);
    char name[300];
    snprintf(name, sizeof name, "texture image '%s'", filename ? filename : "");
    ts_status st;
    switch (ts_texture_image_format_of(filename)) {
    case TS_TEXTURE_IMAGE_PNG:
        return ts_png_decode(buf, len, name, out, err);
    case TS_TEXTURE_IMAGE_TGA:
        return ts_tga_decode(buf, len, name, out, err);
    case TS_TEXTURE_IMAGE_PFM:
        return ts_pfm_decode(buf, len, name, out, err);
    case TS_TEXTURE_IMAGE_EXR:
        st = ts_exr_read_memory(buf, len, out, err);
        if (st) ts_error_prefix(err, "%s", name);
        return st;
    case TS_TEXTURE_IMAGE_UNKNOWN:
        break;
    }
    const char *ext = filename ? extension(filename) : NULL;
    if (!ext)
        return ts_error_set(
            err, TS_ERR_UNSUPPORTED,
            "%s: the file name has no extension to tell its format (.exr, .png, .tga and .pfm are read)",
            name);
    return ts_error_set(err, TS_ERR_UNSUPPORTED,
                        "%s: unsupported image format \"%s\" (.exr, .png, .tga and .pfm are read)", name,
                        ext);
}

ts_status ts_texture_image_texels(const ts_image *img, const char *filename, int n_channels, bool gamma,
                                  float scale, float **texels, ts_error *err)
{
    *texels = NULL;
    if (n_channels != 1 && n_channels != 3)
        return ts_error_set(err, TS_ERR_INVALID, "texture image '%s': %d channels asked for (1 or 3)",
                            filename, n_channels);
    int ch[3] = {ts_image_channel(img, "R"), ts_image_channel(img, "G"), ts_image_channel(img, "B")};
    int y_ch = ts_image_channel(img, "Y");
    bool grey = ch[0] < 0 && ch[1] < 0 && ch[2] < 0;
    if (grey && y_ch < 0)
        return ts_error_set(err, TS_ERR_INVALID,
                            "texture image '%s': the image has none of the channels R, G, B and Y", filename);
    if (grey) ch[0] = ch[1] = ch[2] = y_ch;
    size_t w = (size_t)img->width, h = (size_t)img->height, nc = (size_t)img->n_channels;
    float *out = malloc(sizeof *out * w * h * (size_t)n_channels);
    if (!out)
        return ts_error_set(err, TS_ERR_NOMEM, "texture image '%s': out of memory for its texels", filename);
    for (size_t y = 0; y < h; y++) {
        const float *src = img->data + y * w * nc;
        float *dst = out + (h - 1 - y) * w * (size_t)n_channels; /* t = 0 is the bottom row */
        for (size_t x = 0; x < w; x++) {
            float rgb[3];
            for (int c = 0; c < 3; c++)
                rgb[c] = ch[c] >= 0 ? src[x * nc + (size_t)ch[c]] : 0.0f;
            bool finite = true; /* and within ±TS_MIPMAP_MAX_TEXEL: checked on the results */
            if (n_channels == 3) {
                for (int c = 0; c < 3; c++) {
                    float v = gamma ? ts_texture_srgb_to_linear(rgb[c]) : rgb[c];
                    dst[x * 3 + (size_t)c] = scale * v;
                    finite = finite && fabsf(dst[x * 3 + (size_t)c]) <= TS_MIPMAP_MAX_TEXEL;
                }
            } else {
                float lum = 0.212671f * rgb[0] + 0.715160f * rgb[1] + 0.072169f * rgb[2];
                dst[x] = scale * (gamma ? ts_texture_srgb_to_linear(lum) : lum);
                finite = finite && fabsf(dst[x]) <= TS_MIPMAP_MAX_TEXEL;
            }
            if (!finite) {
                free(out);
                return ts_error_set(err, TS_ERR_INVALID,
                                    "texture image '%s': pixel (%zu, %zu) is not finite or beyond ±1e30 (%g, "
                                    "%g, %g, scale %g)",
                                    filename, x, y, (double)rgb[0], (double)rgb[1], (double)rgb[2],
                                    (double)scale);
            }
        }
    }
    *texels = out;
    return TS_OK;
}
