/* png_decode.h — PNG decoding through libpng, for image textures.
 *
 * Design note: decoded as pbrt-v3 decodes PNG textures (lodepng's 24-bit RGB): palette
 * and grey expanded to RGB, alpha and tRNS dropped, 16-bit channels cut to their high
 * byte, no gamma or colour-profile chunk applied; values are the 8-bit codes over 255,
 * still sRGB-encoded (the texture layer decodes gamma, textures/texture_image.h).
 * Interlaced files are deinterlaced. libpng's messages go into the error sentence, never
 * to stderr. Checked before the pixels are allocated: the signature, a size beyond
 * TS_IMAGE_MAX_PIXELS, and a header that promises more raw scanline bytes than deflate
 * could expand the whole file into (its ratio is at most 1032:1): a decompression bomb.
 * Thread-safe (libpng state is per call). */
#ifndef TS_PNG_DECODE_H
#define TS_PNG_DECODE_H

#include <stddef.h>

#include "core/error.h"
#include "image/image.h"

/* Decodes buf[0, len) into *out with channels R, G, B, row 0 at the top (caller calls
 * ts_image_fini). name prefixes messages. Errors: TS_ERR_INVALID (not a PNG, corrupt or
 * truncated), TS_ERR_LIMIT, TS_ERR_NOMEM. On failure *out is empty. */
ts_status ts_png_decode(const unsigned char *buf, size_t len, const char *name, ts_image *out, ts_error *err);

#endif
