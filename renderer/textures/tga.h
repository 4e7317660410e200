/* tga.h — Truevision TGA (.tga) decoding, for image textures.
 *
 * Design note: pbrt-v3 reads TGA textures, so tessera does. The decoder is ours (the
 * format is small, and a decoder that checks every count against the buffer is simpler
 * to keep safe than to wrap one that zero-fills truncated files and sniffs a dozen other
 * formats): image types 1, 2, 3 (colour-mapped, true-colour, grey) and their run-length
 * encoded forms 9, 10, 11; true-colour pixels of 15, 16 (5-5-5, the top bit ignored), 24
 * or 32 bits (B, G, R[, A]); grey of 8 bits (16 bits: grey and alpha); colour-map
 * indices of 8 or 16 bits into a map of 15-, 16-, 24- or 32-bit entries, offset by the
 * header's first entry index. Rows run bottom to top unless descriptor bit 5 says top to
 * bottom; bit 4 mirrors columns. Alpha is dropped (pbrt-v3 ignores it); values are the
 * stored codes over 255 (over 31 for 5-bit channels), still sRGB-encoded: the texture
 * layer decodes gamma (textures/texture_image.h).
 *
 * Checked before anything is read or allocated: the header's fields, the image ID and
 * colour map lying inside the buffer, a size of 0 or beyond TS_IMAGE_MAX_PIXELS, and
 * pixels the data cannot hold (uncompressed: exactly; RLE: at most 128 pixels per 2
 * bytes); while decoding: every run inside the buffer and the image, every colour index
 * inside the map. Failures are sentences naming the file; bytes after the pixels (a TGA
 * 2.0 footer) are ignored. The result has channels R, G, B, row 0 at the top.
 * Thread-safe, no state. */
#ifndef TS_TGA_H
#define TS_TGA_H

#include <stddef.h>

#include "core/error.h"
#include "image/image.h"

/* Decodes buf[0, len) into *out (caller calls ts_image_fini). name prefixes messages.
 * Errors: TS_ERR_INVALID (malformed, truncated, zero size), TS_ERR_UNSUPPORTED (an
 * image type or pixel depth outside the list above), TS_ERR_LIMIT, TS_ERR_NOMEM. On
 * failure *out is empty. */
ts_status ts_tga_decode(const unsigned char *buf, size_t len, const char *name, ts_image *out, ts_error *err);

#endif
