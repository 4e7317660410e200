/* fuzz_teximage.c — libFuzzer harness: the image decoders of image textures
 * (renderer/textures/): every input goes through the PFM, TGA and PNG decoders
 * (ts_pfm_decode, ts_tga_decode, ts_png_decode); an image that decodes is made into
 * texels (1 and 3 channels, with and without gamma, ts_texture_image_texels) and, when
 * small enough to stay fast, into a MIP map under a wrap mode picked from the input,
 * which is then looked up (bilinear, trilinear, EWA) at points derived from the input.
 * Invariants (FUZZ_CHECK): a failure leaves no image and a sentence with the status; an
 * image is as large as it says, within the pixel limit, with channels R, G, B, and every
 * value readable; PNG and TGA values lie in [0, 1]; a map of the texels accepted (finite,
 * within ±1e30) gives finite lookups. */
#include "fuzz_common.h"

#include <math.h>

#include "image/image.h"
#include "textures/mipmap.h"
#include "textures/pfm.h"
#include "textures/png_decode.h"
#include "textures/texture_image.h"
#include "textures/tga.h"

static void use_map(const float *texels, int w, int h, int nc, uint64_t state)
{
    ts_mipmap *m = NULL;
    ts_error err = {0};
    ts_texture_wrap wrap = (ts_texture_wrap)(state % 3);
    if (ts_mipmap_create(texels, w, h, nc, wrap, 0, &m, &err) != TS_OK) {
        FUZZ_CHECK(m == NULL && err.message[0] != '\0');
        return;
    }
    FUZZ_CHECK(m->n_levels >= 1 && m->levels[m->n_levels - 1].width == 1 &&
               m->levels[m->n_levels - 1].height == 1);
    for (int k = 0; k < 6; k++) {
        ts_vec2 st = {fuzz_unit(&state) * 3 - 1, fuzz_unit(&state) * 3 - 1};
        ts_vec2 d0 = {(fuzz_unit(&state) - 0.5f) * 0.2f, (fuzz_unit(&state) - 0.5f) * 0.2f};
        ts_vec2 d1 = {(fuzz_unit(&state) - 0.5f) * 0.02f, (fuzz_unit(&state) - 0.5f) * 0.02f};
        ts_rgb a = ts_mipmap_bilinear(m, k % m->n_levels, st);
        ts_rgb b = ts_mipmap_trilinear(m, st, fuzz_unit(&state));
        ts_rgb c = ts_mipmap_ewa(m, st, d0, d1, 1 + 63 * fuzz_unit(&state));
        FUZZ_CHECK(ts_rgb_is_finite(a) && ts_rgb_is_finite(b) && ts_rgb_is_finite(c));
    }
    ts_mipmap_destroy(m);
}

static void use_image(const ts_image *img, int unit_range, uint64_t state)
{
    FUZZ_CHECK(img->width >= 1 && img->height >= 1 && img->data);
    FUZZ_CHECK((int64_t)img->width * img->height <= TS_IMAGE_MAX_PIXELS);
    FUZZ_CHECK(img->n_channels == 3 && ts_image_channel(img, "R") == 0 && ts_image_channel(img, "B") == 2);
    size_t n = (size_t)img->width * (size_t)img->height * 3;
    for (size_t i = 0; i < n; i++)
        if (unit_range) FUZZ_CHECK(img->data[i] >= 0 && img->data[i] <= 1);
    volatile float last = img->data[n - 1];
    (void)last;
    for (int nc = 1; nc <= 3; nc += 2) {
        float *texels = NULL;
        ts_error err = {0};
        ts_status st = ts_texture_image_texels(img, "fuzz", nc, (state >> 8) & 1, 1, &texels, &err);
        if (st != TS_OK) {
            FUZZ_CHECK(texels == NULL && err.message[0] != '\0');
            continue;
        }
        if ((int64_t)img->width * img->height <= 64 * 64)
            use_map(texels, img->width, img->height, nc, state + nc);
        free(texels);
    }
}

typedef ts_status (*decoder)(const unsigned char *, size_t, const char *, ts_image *, ts_error *);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const decoder decoders[3] = {ts_pfm_decode, ts_tga_decode, ts_png_decode};
    uint64_t state = fuzz_hash(data, size);
    for (int d = 0; d < 3; d++) {
        ts_image img = {0};
        ts_error err = {0};
        ts_status st = decoders[d](data, size, "fuzz", &img, &err);
        if (st != TS_OK) {
            FUZZ_CHECK(img.data == NULL && err.status == st && err.message[0] != '\0');
            continue;
        }
        use_image(&img, d != 0, state);
        ts_image_fini(&img);
    }
    return 0;
}
