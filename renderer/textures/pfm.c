/* pfm.c — Portable Float Map decoding (see pfm.h). */
#include "textures/pfm.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const char *const rgb_names[3] = {"R", "G", "B"};

static int is_space(unsigned char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

/* The next whitespace-separated token of buf from *pos (after skipping whitespace):
 * [*start, *pos). False at the end of the buffer. */
static int next_token(const unsigned char *buf, size_t len, size_t *pos, size_t *start)
{
    size_t i = *pos;
    while (i < len && is_space(buf[i]))
        i++;
    if (i == len) return 0;
    *start = i;
    while (i < len && !is_space(buf[i]))
        i++;
    *pos = i;
    return 1;
}

/* A positive decimal integer of at most 9 digits. */
static int parse_size(const unsigned char *s, size_t n, int64_t *out)
{
    if (n == 0 || n > 9) return 0;
    int64_t v = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        v = v * 10 + (s[i] - '0');
    }
    *out = v;
    return 1;
}

static float read_f32(const unsigned char *p, int little_endian)
{
    uint32_t u = little_endian
                     ? (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24
                     : (uint32_t)p[3] | (uint32_t)p[2] << 8 | (uint32_t)p[1] << 16 | (uint32_t)p[0] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

bool ts_pfm_size(const unsigned char *buf, size_t len, int64_t *width, int64_t *height)
{
    *width = *height = 0;
    size_t pos = 2, start = 0;
    return len >= 3 && buf[0] == 'P' && (buf[1] == 'F' || buf[1] == 'f') && is_space(buf[2]) &&
           next_token(buf, len, &pos, &start) && parse_size(buf + start, pos - start, width) &&
           next_token(buf, len, &pos, &start) && parse_size(buf + start, pos - start, height);
}

ts_status ts_pfm_decode(const unsigned char *buf, size_t len, const char *name, ts_image *out, ts_error *err)
{
    memset(out, 0, sizeof *out);
    if (!name) name = "PFM image";
    if (len < 3 || buf[0] != 'P' || (buf[1] != 'F' && buf[1] != 'f') || !is_space(buf[2]))
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: not a PFM file (it does not start with \"PF\" or \"Pf\")", name);
    int nc = buf[1] == 'F' ? 3 : 1;
    size_t pos = 2, start = 0;
    int64_t width = 0, height = 0;
    if (!next_token(buf, len, &pos, &start) || !parse_size(buf + start, pos - start, &width))
        return ts_error_set(err, TS_ERR_INVALID, "%s: the PFM header has no valid width", name);
    if (!next_token(buf, len, &pos, &start) || !parse_size(buf + start, pos - start, &height))
        return ts_error_set(err, TS_ERR_INVALID, "%s: the PFM header has no valid height", name);
    if (!next_token(buf, len, &pos, &start) || pos - start > 63)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the PFM header has no valid scale", name);
    char text[64];
    memcpy(text, buf + start, pos - start);
    text[pos - start] = '\0';
    char *end = NULL;
    double scale = strtod(text, &end);
    if (end == text || *end != '\0' || !isfinite(scale) || scale == 0 || !isfinite((float)scale) ||
        (float)scale == 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the PFM scale \"%s\" is not a finite non-zero number",
                            name, text);
    /* Exactly one whitespace byte separates the header from the pixels. */
    if (pos == len) return ts_error_set(err, TS_ERR_INVALID, "%s: the PFM file ends after its header", name);
    pos++;
    if (width == 0 || height == 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the image has a zero size (%lld × %lld)", name,
                            (long long)width, (long long)height);
    if (width * height > TS_IMAGE_MAX_PIXELS)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "%s: the image is %lld × %lld pixels, more than the limit of %lld", name,
                            (long long)width, (long long)height, (long long)TS_IMAGE_MAX_PIXELS);
    uint64_t need = (uint64_t)width * (uint64_t)height * (uint64_t)nc * 4u;
    if ((uint64_t)(len - pos) < need)
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: the file is truncated (%zu bytes of pixels, %llu expected)", name, len - pos,
                            (unsigned long long)need);

    ts_status st = ts_image_init(out, (int)width, (int)height, 3, rgb_names, err);
    if (st) {
        ts_error_prefix(err, "%s", name);
        return st;
    }
    int little = (float)scale < 0;
    float mag = fabsf((float)scale);
    const unsigned char *px = buf + pos;
    for (int64_t row = 0; row < height; row++) {
        /* File rows go from the bottom up. */
        float *dst = out->data + (size_t)(height - 1 - row) * (size_t)width * 3;
        for (int64_t x = 0; x < width; x++, px += 4 * (size_t)nc) {
            for (int c = 0; c < 3; c++) {
                float v = read_f32(px + 4 * (nc == 3 ? c : 0), little);
                if (mag != 1.0f) v *= mag;
                dst[x * 3 + c] = v;
            }
        }
    }
    return TS_OK;
}
