/* pfm.h — Portable Float Map (.pfm) decoding, for image textures.
 *
 * Design note: the format (netpbm's PFM, which pbrt-v3 reads) is a text header and raw
 * float32 pixels: "PF" (RGB) or "Pf" (grey), whitespace, the width and the height as
 * decimal integers, whitespace, the scale as a decimal real, exactly one whitespace byte,
 * then width·height·channels floats, rows from the bottom of the image to its top. The
 * scale's sign gives the byte order (negative: little-endian); its magnitude, when it is
 * not 1, multiplies every value, as pbrt-v3 does. Whitespace is space, tab, CR or LF.
 * Everything is checked against the buffer before it is read or allocated: a header that
 * is malformed, a size of 0 or beyond TS_IMAGE_MAX_PIXELS, a scale that is 0 or not
 * finite, or fewer pixel bytes than the header promises is refused with a sentence naming
 * the file; bytes after the pixels are ignored (as pbrt-v3 ignores them). The result is
 * an image with channels R, G, B (grey repeated in all three), row 0 at the top, values
 * as stored (non-finite ones included: the caller decides). Thread-safe, no state. */
#ifndef TS_PFM_H
#define TS_PFM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "image/image.h"

/* Decodes buf[0, len) into *out (caller calls ts_image_fini). name prefixes messages
 * ("texture image 'a.pfm'"). Errors: TS_ERR_INVALID (malformed, truncated, zero size),
 * TS_ERR_LIMIT (too many pixels), TS_ERR_NOMEM. On failure *out is empty. */
ts_status ts_pfm_decode(const unsigned char *buf, size_t len, const char *name, ts_image *out, ts_error *err);
/* The width and height the header gives, without decoding: false when it cannot be read. */
bool ts_pfm_size(const unsigned char *buf, size_t len, int64_t *width, int64_t *height);

#endif
