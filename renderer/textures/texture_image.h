/* texture_image.h — image files of image textures: the format, decoding, texels.
 *
 * Design note (pbrt-v3 §10.4.1, its ImageTexture). The format is the file name's
 * extension, case-insensitive, as pbrt-v3 picks it: .exr (OpenEXR, image/exr.h), .png
 * (textures/png_decode.h), .tga (textures/tga.h), .pfm (textures/pfm.h); anything else
 * is refused. Texels are made the way pbrt-v3's convertIn makes them:
 *   - from the image's R, G, B (EXR: whichever of R, G, B exist, the others 0 as
 *     OpenEXR's RGBA interface fills them; a file with Y and none of R, G, B is grey);
 *   - RGB textures: each channel v → scale·(gamma ? sRGB⁻¹(v) : v);
 *     float textures: the luminance of the stored values y = 0.212671 R + 0.715160 G +
 *     0.072169 B (pbrt-v3's weights), then y → scale·(gamma ? sRGB⁻¹(y) : y) — pbrt-v3
 *     decodes gamma after taking luminance, and so does this;
 *   - sRGB⁻¹ is pbrt-v3's InverseGammaCorrect: v/12.92 up to 0.04045, else
 *     ((v + 0.055)/1.055)^2.4;
 *   - `gamma` defaults to true for .png and .tga (8-bit files hold sRGB codes), false for
 *     .exr and .pfm;
 *   - rows are turned over so that t = 0 is the image's bottom row (pbrt-v3 flips every
 *     image it reads for a texture).
 * pbrt-v3 reads EXR through OpenEXR's half-float RGBA interface; FLOAT channels here keep
 * their precision (a difference of at most 2^-11 relative). A texel that is not finite
 * (in the file, or after scaling) is refused, naming it in image coordinates (x from
 * the left, y from the top). Thread-safe, no state. */
#ifndef TS_TEXTURE_IMAGE_H
#define TS_TEXTURE_IMAGE_H

#include <stdbool.h>
#include <stddef.h>

#include "core/error.h"
#include "image/image.h"

typedef enum ts_texture_image_format {
    TS_TEXTURE_IMAGE_UNKNOWN,
    TS_TEXTURE_IMAGE_EXR,
    TS_TEXTURE_IMAGE_PNG,
    TS_TEXTURE_IMAGE_TGA,
    TS_TEXTURE_IMAGE_PFM,
} ts_texture_image_format;

/* The format of a file name by its extension (case-insensitive); UNKNOWN otherwise. */
ts_texture_image_format ts_texture_image_format_of(const char *filename);

/* pbrt-v3's default of `gamma` for the file: true for .png and .tga. */
bool ts_texture_image_default_gamma(const char *filename);

/* The image's size and its decoded channels as the file's header says (PNG's IHDR, TGA's
 * header, PFM's, EXR's data window and channel list), read without decoding anything:
 * false when there is no such header (the decoder then says why). For a memory budget
 * checked before any pixel is allocated (texture_cache.h). */
bool ts_texture_image_size(const char *filename, const unsigned char *buf, size_t len, int64_t *width,
                           int64_t *height, int *channels);

/* Decodes buf[0, len) in the format of filename's extension into *out (caller calls
 * ts_image_fini). Messages start "texture image '<filename>': ". An unknown extension
 * is TS_ERR_UNSUPPORTED ("… unsupported image format \".jpg\" (.exr, .png, .tga and
 * .pfm are read)"). On failure *out is empty. */
ts_status ts_texture_image_decode(const char *filename, const unsigned char *buf, size_t len, ts_image *out,
                                  ts_error *err);

/* The texels of a decoded image as described above: n_channels 3 (RGB) or 1 (float),
 * width·height·n_channels floats, row t = 0 (the image's bottom row) first, in a malloc'd
 * array the caller frees (*texels NULL on failure). filename names the file in messages. */
ts_status ts_texture_image_texels(const ts_image *img, const char *filename, int n_channels, bool gamma,
                                  float scale, float **texels, ts_error *err);

/* pbrt-v3's InverseGammaCorrect (the sRGB decoding curve). */
float ts_texture_srgb_to_linear(float v);

#endif
