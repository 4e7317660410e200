/* tga.c — TGA decoding (see tga.h). */
#include "textures/tga.h"

#include <stdint.h>
#include <string.h>

static const char *const rgb_names[3] = {"R", "G", "B"};

static unsigned le16(const unsigned char *p) { return (unsigned)p[0] | (unsigned)p[1] << 8; }

/* One stored colour of `bits` bits (15, 16, 24, 32; 8 for grey, grey_pair for 16-bit grey
 * and alpha) at p to RGB in [0, 1]. */
static void color_of(const unsigned char *p, int bits, int grey, float rgb[3])
{
    if (grey) {
        rgb[0] = rgb[1] = rgb[2] = (float)p[0] / 255.f; /* 16-bit grey: p[1] is alpha */
    } else if (bits == 15 || bits == 16) {
        unsigned v = le16(p);
        rgb[0] = (float)((v >> 10) & 31) / 31.f;
        rgb[1] = (float)((v >> 5) & 31) / 31.f;
        rgb[2] = (float)(v & 31) / 31.f;
    } else { /* B, G, R[, A] */
        rgb[0] = (float)p[2] / 255.f;
        rgb[1] = (float)p[1] / 255.f;
        rgb[2] = (float)p[0] / 255.f;
    }
}

typedef struct tga {
    const char *name;
    int base_type; /* 1 colour-mapped, 2 true-colour, 3 grey */
    int depth, bpp;
    const unsigned char *map;
    unsigned map_first, map_len;
    int map_bits, map_bpp;
    int width, height, top_down, right_to_left;
    ts_image *img;
} tga;

/* The pixel stored at p, written to file position i (in file order). */
static ts_status put_pixel(const tga *t, const unsigned char *p, int64_t i, float rgb[3], int reuse,
                           ts_error *err)
{
    if (!reuse) {
        if (t->base_type == 1) {
            unsigned index = t->bpp == 1 ? p[0] : le16(p);
            if (index < t->map_first || index - t->map_first >= t->map_len)
                return ts_error_set(err, TS_ERR_INVALID,
                                    "%s: colour index %u is outside the colour map (entries %u … %u)",
                                    t->name, index, t->map_first, t->map_first + t->map_len - 1);
            color_of(t->map + (size_t)(index - t->map_first) * (size_t)t->map_bpp, t->map_bits, 0, rgb);
        } else {
            color_of(p, t->depth, t->base_type == 3, rgb);
        }
    }
    int64_t row = i / t->width, col = i % t->width;
    int64_t y = t->top_down ? row : t->height - 1 - row;
    int64_t x = t->right_to_left ? t->width - 1 - col : col;
    float *dst = t->img->data + ((size_t)y * (size_t)t->width + (size_t)x) * 3;
    dst[0] = rgb[0], dst[1] = rgb[1], dst[2] = rgb[2];
    return TS_OK;
}

ts_status ts_tga_decode(const unsigned char *buf, size_t len, const char *name, ts_image *out, ts_error *err)
{
    memset(out, 0, sizeof *out);
    if (!name) name = "TGA image";
    if (len < 18)
        return ts_error_set(err, TS_ERR_INVALID, "%s: %zu bytes are too few for a TGA header", name, len);
    unsigned id_len = buf[0], cmap_type = buf[1], type = buf[2];
    tga t = {.name = name, .img = out};
    t.map_first = le16(buf + 3);
    t.map_len = le16(buf + 5);
    t.map_bits = buf[7];
    t.width = (int)le16(buf + 12), t.height = (int)le16(buf + 14);
    t.depth = buf[16];
    t.right_to_left = (buf[17] >> 4) & 1;
    t.top_down = (buf[17] >> 5) & 1;
    if (cmap_type > 1)
        return ts_error_set(err, TS_ERR_INVALID, "%s: not a TGA file (colour-map type %u)", name, cmap_type);
    if (type == 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the TGA file holds no image data (type 0)", name);
    int rle = (type & 8) != 0;
    t.base_type = (int)(type & ~8u);
    if ((type & ~11u) != 0 || t.base_type < 1 || t.base_type > 3)
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "%s: TGA image type %u is not supported (1, 2, 3, 9, 10, 11 are)", name, type);
    if (t.base_type == 1 && cmap_type != 1)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the TGA image is colour-mapped but has no colour map",
                            name);
    int depth_ok = t.base_type == 1   ? (t.depth == 8 || t.depth == 16)
                   : t.base_type == 2 ? (t.depth == 15 || t.depth == 16 || t.depth == 24 || t.depth == 32)
                                      : (t.depth == 8 || t.depth == 16);
    if (!depth_ok)
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "%s: %d-bit pixels are not supported for TGA image type %u", name, t.depth, type);
    if (t.base_type == 1 && t.map_bits != 15 && t.map_bits != 16 && t.map_bits != 24 && t.map_bits != 32)
        return ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: %d-bit colour-map entries are not supported", name,
                            t.map_bits);
    if (t.base_type == 1 && t.map_len == 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the TGA colour map is empty", name);
    if (t.width == 0 || t.height == 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the image has a zero size (%d × %d)", name, t.width,
                            t.height);
    int64_t npix = (int64_t)t.width * t.height;
    if (npix > TS_IMAGE_MAX_PIXELS)
        return ts_error_set(err, TS_ERR_LIMIT, "%s: the image is %d × %d pixels, more than the limit of %lld",
                            name, t.width, t.height, (long long)TS_IMAGE_MAX_PIXELS);
    size_t pos = 18 + (size_t)id_len;
    t.map_bpp = (t.map_bits + 7) / 8;
    size_t map_bytes = cmap_type == 1 ? (size_t)t.map_len * (size_t)t.map_bpp : 0;
    if (pos > len || len - pos < map_bytes)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the file is truncated (in its image ID or colour map)",
                            name);
    t.map = buf + pos;
    pos += map_bytes;
    t.bpp = (t.depth + 7) / 8;
    size_t avail = len - pos;
    if (!rle && (uint64_t)avail < (uint64_t)npix * (uint64_t)t.bpp)
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: the file is truncated (%zu bytes of pixels, %llu expected)", name, avail,
                            (unsigned long long)((uint64_t)npix * (uint64_t)t.bpp));
    /* A run-length packet is at least 2 bytes and covers at most 128 pixels. */
    if (rle && (uint64_t)npix > 64 * (uint64_t)avail)
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: the file is truncated (%zu bytes cannot encode %lld pixels)", name, avail,
                            (long long)npix);

    ts_status st = ts_image_init(out, t.width, t.height, 3, rgb_names, err);
    if (st) {
        ts_error_prefix(err, "%s", name);
        return st;
    }
    float rgb[3];
    int64_t i = 0;
    if (!rle) {
        for (; i < npix; i++, pos += (size_t)t.bpp)
            if ((st = put_pixel(&t, buf + pos, i, rgb, 0, err))) goto fail;
    } else {
        while (i < npix) {
            if (pos >= len) goto truncated;
            unsigned h = buf[pos++];
            int64_t count = (int64_t)(h & 127) + 1;
            if (i + count > npix) {
                st = ts_error_set(err, TS_ERR_INVALID,
                                  "%s: a run-length packet runs past the image's last pixel", name);
                goto fail;
            }
            if (h & 128) { /* one pixel, repeated */
                if (len - pos < (size_t)t.bpp) goto truncated;
                for (int64_t k = 0; k < count; k++, i++)
                    if ((st = put_pixel(&t, buf + pos, i, rgb, k > 0, err))) goto fail;
                pos += (size_t)t.bpp;
            } else {
                if ((uint64_t)(len - pos) < (uint64_t)count * (uint64_t)t.bpp) goto truncated;
                for (int64_t k = 0; k < count; k++, i++, pos += (size_t)t.bpp)
                    if ((st = put_pixel(&t, buf + pos, i, rgb, 0, err))) goto fail;
            }
        }
    }
    return TS_OK;
truncated:
    st = ts_error_set(err, TS_ERR_INVALID,
                      "%s: the file is truncated (its run-length data ends at pixel %lld of %lld)", name,
                      (long long)i, (long long)npix);
fail:
    ts_image_fini(out);
    return st;
}
