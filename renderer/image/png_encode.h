/* png_encode.h — 8-bit sRGB PNG previews from linear R,G,B channels, through libpng.
 *
 * Design note: a PNG is a view, not data: linear value × 2^exposure_stops, the sRGB
 * transfer curve, clamp to [0,1], round to nearest, NaN → 0; 8-bit RGB, no alpha, tagged
 * sRGB. Encoding goes to memory (the HTTP body); ts_png_write adds the atomic file
 * replacement of ts_image_write_file_atomic. Thread-safe: no shared state. */
#ifndef TS_PNG_ENCODE_H
#define TS_PNG_ENCODE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "image/image.h"

/* One linear value to an 8-bit sRGB code: sRGB curve (IEC 61966-2-1), clamp to [0,1],
 * round to nearest; NaN and values ≤ 0 → 0, ≥ 1 (and +inf) → 255. 0.5 → 188. */
uint8_t ts_srgb8_from_linear(float v);

/* Encodes channels R, G, B of img (TS_ERR_INVALID if one is missing) as an 8-bit sRGB PNG
 * in a malloc'd buffer the caller frees. On failure *buf is NULL and *len 0. */
ts_status ts_png_encode(const ts_image *img, float exposure_stops, unsigned char **buf, size_t *len, ts_error *err);

/* ts_png_encode written atomically to path ("<path>.tmp.<pid>" then rename(2); on failure
 * nothing is left behind). */
ts_status ts_png_write(const char *path, const ts_image *img, float exposure_stops, ts_error *err);

#endif
