/* test_exr.c — ts_image container and EXR read/write: bit-exact round trips (file and
 * memory), HALF/UINT/tiled/offset files written with the core API, errors on missing,
 * truncated, random and corrupted input, atomic replacement of files. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "image/exr.h"
#include "image/image.h"

/* ---- helpers ---- */

static char g_dir[256]; /* per-run scratch directory, made by the group setup */

static void path_in_dir(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", g_dir, name); }

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static uint64_t g_rng = 0x9E3779B97F4A7C15ull;
static uint64_t rng_next(void) /* xorshift64*: fixed seed, deterministic test data */
{
    g_rng ^= g_rng >> 12;
    g_rng ^= g_rng << 25;
    g_rng ^= g_rng >> 27;
    return g_rng * 0x2545F4914F6CDD1Dull;
}

static unsigned char *read_whole(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return buf;
}

static void write_whole(const char *path, const void *buf, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(buf, 1, len, f), len);
    fclose(f);
}

/* Number of entries in g_dir whose name contains ".tmp." (leftover temporary files). */
static int count_tmp_files(void)
{
    DIR *d = opendir(g_dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, ".tmp.")) n++;
    closedir(d);
    return n;
}

static void assert_failed_cleanly(ts_status st, ts_status want, const ts_error *err, const ts_image *img)
{
    if (st != want) fail_msg("status %d (%s), want %d: %s", st, ts_status_name(st), want, err->message);
    assert_true(strlen(err->message) > 10);
    assert_null(img->data);
    assert_int_equal(img->n_channels, 0);
}

/* Channels given out of EXR's sorted order; "R2" etc. are the film's extra moments. */
static const char *const k_names[] = {"R", "G", "B", "weight", "count", "R2", "G2", "B2", "Z_depth"};
enum { K_W = 37, K_H = 29, K_N = 9 }; /* 29 rows: one full ZIP block of 16 and a partial one */

/* Awkward floats that a lossy or converting path would change. */
static const uint32_t k_special_bits[] = {
    0x00000000u, 0x80000000u,             /* +0, -0 */
    0x3f800000u, 0xbf800000u, 0x3f000000u, /* 1, -1, 0.5 */
    0x00000001u, 0x80000001u,             /* smallest denormals */
    0x000b2a7cu, 0x807fffffu,             /* denormals (≈1e-39, largest negative one) */
    0x00800000u,                          /* FLT_MIN */
    0x7f7fffffu, 0xff7fffffu,             /* ±FLT_MAX */
    0x7e967699u,                          /* 1e38 */
    0x477fe000u,                          /* 65504: largest half, exact in float */
    0x7f800000u, 0xff800000u,             /* ±inf */
    0x7fc12345u, 0xffc00001u,             /* quiet NaNs with payloads */
    0x3dcccccdu, 0xc2f6e979u,             /* 0.1, -123.456 */
};
enum { K_N_SPECIAL = sizeof k_special_bits / sizeof k_special_bits[0] };

static void make_test_image(ts_image *img)
{
    ts_error err = {0};
    assert_int_equal(ts_image_init(img, K_W, K_H, K_N, k_names, &err), TS_OK);
    size_t count = (size_t)K_W * K_H * K_N;
    for (size_t k = 0; k < count; k++) {
        uint32_t u = k < K_N_SPECIAL * 4 ? k_special_bits[k % K_N_SPECIAL] : (uint32_t)(rng_next() >> 32);
        /* Random patterns may be signalling NaNs; keep them quiet so a plain float copy in the
         * library could not be blamed for a change the format itself does not promise. */
        if ((u & 0x7f800000u) == 0x7f800000u && (u & 0x007fffffu)) u |= 0x00400000u;
        img->data[k] = bits_float(u);
    }
    char digest[65];
    for (int k = 0; k < 64; k++) digest[k] = "0123456789abcdef"[(k * 7 + 3) % 16];
    digest[64] = '\0';
    char longest[256];
    memset(longest, 'x', 255);
    longest[255] = '\0';
    assert_int_equal(ts_image_set_string(img, "tessera.scene_digest", digest, &err), TS_OK);
    assert_int_equal(ts_image_set_int(img, "tessera.seed", -123456789, &err), TS_OK);
    assert_int_equal(ts_image_set_int(img, "tessera.spp_end", INT32_MAX, &err), TS_OK);
    assert_int_equal(ts_image_set_double(img, "tessera.exposure", 0.1, &err), TS_OK);
    assert_int_equal(ts_image_set_double(img, "tessera.tiny", 4.9406564584124654e-324, &err), TS_OK);
    assert_int_equal(ts_image_set_string(img, "comments", longest, &err), TS_OK);
    assert_int_equal(ts_image_set_string(img, "tessera.empty", "", &err), TS_OK);
    /* > 31 bytes: needs EXR long-name support */
    assert_int_equal(ts_image_set_string(img, "tessera.a_rather_long_attribute_name", "v", &err), TS_OK);
    assert_int_equal(ts_image_set_string(img, "tessera.version", "0.1.0", &err), TS_OK);
}

/* Same size, same channel names (any order), every float bit-identical, same attributes. */
static void assert_images_identical(const ts_image *a, const ts_image *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->n_channels, b->n_channels);
    for (int c = 0; c < a->n_channels; c++) {
        int cb = ts_image_channel(b, a->channel_names[c]);
        if (cb < 0) fail_msg("channel '%s' missing", a->channel_names[c]);
        for (size_t p = 0; p < (size_t)a->width * a->height; p++) {
            uint32_t ua = float_bits(a->data[p * a->n_channels + c]);
            uint32_t ub = float_bits(b->data[p * b->n_channels + cb]);
            if (ua != ub) fail_msg("channel %s pixel %zu: 0x%08x != 0x%08x", a->channel_names[c], p, ua, ub);
        }
    }
    assert_int_equal(a->n_attrs, b->n_attrs);
    for (int k = 0; k < a->n_attrs; k++) {
        const ts_image_attr *x = &a->attrs[k], *y = ts_image_attr_find(b, x->name);
        if (!y) fail_msg("attribute '%s' missing", x->name);
        assert_int_equal(x->type, y->type);
        switch (x->type) {
        case TS_ATTR_STRING: assert_string_equal(x->s, y->s); break;
        case TS_ATTR_INT: assert_int_equal(x->i, y->i); break;
        case TS_ATTR_DOUBLE: assert_memory_equal(&x->d, &y->d, sizeof x->d); break;
        }
    }
}

/* ---- core-API fixture writer: files our writer never makes (HALF, UINT, tiled, offset) ---- */

typedef struct fixture {
    exr_storage_t storage;
    int x0, y0, w, h;          /* data window origin and size */
    int tile_w, tile_h;        /* tiled only */
    exr_tile_level_mode_t levels;
    exr_compression_t compression;
    int n;
    const char *names[4];
    exr_pixel_type_t types[4];
    const void *planes[4]; /* level-0 data, planar, w*h elements of the channel's type */
} fixture;

static void write_fixture(const char *path, const fixture *fx)
{
    exr_context_t ctxt;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, NULL), EXR_ERR_SUCCESS);
    int part;
    assert_int_equal(exr_add_part(ctxt, NULL, fx->storage, &part), EXR_ERR_SUCCESS);
    exr_attr_box2i_t dw = {.min = {.x = fx->x0, .y = fx->y0}, .max = {.x = fx->x0 + fx->w - 1, .y = fx->y0 + fx->h - 1}};
    exr_attr_v2f_t swc = {.x = 0, .y = 0};
    assert_int_equal(exr_initialize_required_attr(ctxt, part, &dw, &dw, 1.f, &swc, 1.f, EXR_LINEORDER_INCREASING_Y,
                                                  fx->compression),
                     EXR_ERR_SUCCESS);
    for (int c = 0; c < fx->n; c++)
        assert_int_equal(exr_add_channel(ctxt, part, fx->names[c], fx->types[c], EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                         EXR_ERR_SUCCESS);
    if (fx->storage == EXR_STORAGE_TILED)
        assert_int_equal(exr_set_tile_descriptor(ctxt, part, (uint32_t)fx->tile_w, (uint32_t)fx->tile_h, fx->levels,
                                                 EXR_TILE_ROUND_DOWN),
                         EXR_ERR_SUCCESS);
    assert_int_equal(exr_attr_set_float(ctxt, part, "fixture.gain", 0.75f), EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctxt), EXR_ERR_SUCCESS);

    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int live = 0;
    static const uint8_t zeros[64 * 64 * 4];
    if (fx->storage == EXR_STORAGE_SCANLINE) {
        int lpc;
        assert_int_equal(exr_get_scanlines_per_chunk(ctxt, part, &lpc), EXR_ERR_SUCCESS);
        for (int y = fx->y0; y < fx->y0 + fx->h; y += lpc) {
            exr_chunk_info_t ci;
            assert_int_equal(exr_write_scanline_chunk_info(ctxt, part, y, &ci), EXR_ERR_SUCCESS);
            assert_int_equal(live ? exr_encoding_update(ctxt, part, &ci, &enc) : exr_encoding_initialize(ctxt, part, &ci, &enc),
                             EXR_ERR_SUCCESS);
            live = 1;
            for (int c = 0; c < enc.channel_count; c++) {
                exr_coding_channel_info_t *ch = &enc.channels[c];
                int k = 0;
                while (strcmp(fx->names[k], ch->channel_name) != 0) k++;
                int bpe = fx->types[k] == EXR_PIXEL_HALF ? 2 : 4;
                ch->encode_from_ptr = (const uint8_t *)fx->planes[k] + (size_t)(ci.start_y - fx->y0) * fx->w * bpe;
                ch->user_pixel_stride = bpe;
                ch->user_line_stride = fx->w * bpe;
                ch->user_data_type = (uint16_t)fx->types[k];
                ch->user_bytes_per_element = (int16_t)bpe;
            }
            assert_int_equal(exr_encoding_choose_default_routines(ctxt, part, &enc), EXR_ERR_SUCCESS);
            assert_int_equal(exr_encoding_run(ctxt, part, &enc), EXR_ERR_SUCCESS);
        }
    } else {
        int32_t levels_x = 1, levels_y = 1;
        assert_int_equal(exr_get_tile_levels(ctxt, part, &levels_x, &levels_y), EXR_ERR_SUCCESS);
        for (int level = 0; level < levels_x; level++) {
            int32_t lw, lh;
            assert_int_equal(exr_get_level_sizes(ctxt, part, level, level, &lw, &lh), EXR_ERR_SUCCESS);
            for (int ty = 0; ty * fx->tile_h < lh; ty++)
                for (int tx = 0; tx * fx->tile_w < lw; tx++) {
                    exr_chunk_info_t ci;
                    assert_int_equal(exr_write_tile_chunk_info(ctxt, part, tx, ty, level, level, &ci), EXR_ERR_SUCCESS);
                    assert_int_equal(live ? exr_encoding_update(ctxt, part, &ci, &enc)
                                          : exr_encoding_initialize(ctxt, part, &ci, &enc),
                                     EXR_ERR_SUCCESS);
                    live = 1;
                    for (int c = 0; c < enc.channel_count; c++) {
                        exr_coding_channel_info_t *ch = &enc.channels[c];
                        int k = 0;
                        while (strcmp(fx->names[k], ch->channel_name) != 0) k++;
                        int bpe = fx->types[k] == EXR_PIXEL_HALF ? 2 : 4;
                        if (level == 0) { /* real data; lower mip levels are zeros */
                            ch->encode_from_ptr = (const uint8_t *)fx->planes[k] +
                                                  ((size_t)ty * fx->tile_h * fx->w + (size_t)tx * fx->tile_w) * bpe;
                            ch->user_line_stride = fx->w * bpe;
                        } else {
                            assert_true(fx->tile_w * fx->tile_h <= 64 * 64);
                            ch->encode_from_ptr = zeros;
                            ch->user_line_stride = fx->tile_w * bpe;
                        }
                        ch->user_pixel_stride = bpe;
                        ch->user_data_type = (uint16_t)fx->types[k];
                        ch->user_bytes_per_element = (int16_t)bpe;
                    }
                    assert_int_equal(exr_encoding_choose_default_routines(ctxt, part, &enc), EXR_ERR_SUCCESS);
                    assert_int_equal(exr_encoding_run(ctxt, part, &enc), EXR_ERR_SUCCESS);
                }
        }
    }
    if (live) exr_encoding_destroy(ctxt, &enc);
    assert_int_equal(exr_finish(&ctxt), EXR_ERR_SUCCESS);
}

/* IEEE half → float by the definition (independent of OpenEXR's converter). */
static float half_value(uint16_t h)
{
    int sign = h >> 15, e = (h >> 10) & 31, m = h & 1023;
    double v;
    if (e == 0) v = ldexp(m, -24);
    else if (e == 31) v = m ? NAN : INFINITY;
    else v = ldexp(1024 + m, e - 25);
    return (float)(sign ? -v : v);
}

/* ---- tests: the container ---- */

static void test_image_container(void **state)
{
    (void)state;
    ts_image img;
    ts_error err = {0};
    const char *names[] = {"R", "G", "B"};
    assert_int_equal(ts_image_init(&img, 4, 3, 3, names, &err), TS_OK);
    for (int k = 0; k < 4 * 3 * 3; k++) assert_true(img.data[k] == 0.0f);
    assert_int_equal(ts_image_channel(&img, "G"), 1);
    assert_int_equal(ts_image_channel(&img, "A"), -1);
    assert_int_equal(ts_image_set_int(&img, "spp", 16, &err), TS_OK);
    assert_int_equal(ts_image_set_string(&img, "spp", "sixteen", &err), TS_OK); /* replaces, type changes */
    assert_int_equal(img.n_attrs, 1);
    const ts_image_attr *a = ts_image_attr_find(&img, "spp");
    assert_non_null(a);
    assert_int_equal(a->type, TS_ATTR_STRING);
    assert_string_equal(a->s, "sixteen");
    assert_null(ts_image_attr_find(&img, "seed"));
    char name[80];
    for (int k = 1; k < TS_IMAGE_MAX_ATTRS; k++) {
        snprintf(name, sizeof name, "a%d", k);
        assert_int_equal(ts_image_set_double(&img, name, k, &err), TS_OK);
    }
    assert_int_equal(ts_image_set_double(&img, "one_too_many", 1, &err), TS_ERR_LIMIT);
    assert_non_null(strstr(err.message, "one_too_many"));
    memset(name, 'n', 64);
    name[64] = '\0';
    assert_int_equal(ts_image_set_int(&img, name, 1, &err), TS_ERR_LIMIT);
    ts_image_fini(&img);
    assert_null(img.data);
    ts_image_fini(&img); /* idempotent */

    const char *dup[] = {"R", "R"};
    assert_int_equal(ts_image_init(&img, 2, 2, 2, dup, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "twice"));
    assert_null(img.data);
    assert_int_equal(ts_image_init(&img, 0, 2, 3, names, &err), TS_ERR_INVALID);
    assert_int_equal(ts_image_init(&img, 2, 2, 17, names, &err), TS_ERR_LIMIT);
    assert_int_equal(ts_image_init(&img, 1 << 15, 1 << 15, 3, names, &err), TS_ERR_LIMIT); /* 2^30 > 2^28 pixels */
}

/* ---- tests: EXR ---- */

static void test_round_trip_file(void **state)
{
    (void)state;
    ts_image img, back;
    ts_error err = {0};
    make_test_image(&img);
    char path[512];
    path_in_dir(path, sizeof path, "round_trip.exr");
    if (ts_exr_write(path, &img, &err)) fail_msg("%s", err.message);
    if (ts_exr_read(path, &back, &err)) fail_msg("%s", err.message);
    assert_images_identical(&img, &back);
    /* The file lists channels sorted (ASCII: upper case first); the reader keeps that order. */
    const char *sorted[] = {"B", "B2", "G", "G2", "R", "R2", "Z_depth", "count", "weight"};
    for (int c = 0; c < K_N; c++) assert_string_equal(back.channel_names[c], sorted[c]);
    assert_int_equal(count_tmp_files(), 0);
    ts_image_fini(&back);
    ts_image_fini(&img);
}

static void test_round_trip_memory(void **state)
{
    (void)state;
    ts_image img, from_file, from_mem;
    ts_error err = {0};
    make_test_image(&img);
    char path[512];
    path_in_dir(path, sizeof path, "memory.exr");
    assert_int_equal(ts_exr_write(path, &img, &err), TS_OK);
    unsigned char *buf, *buf2;
    size_t len, len2, file_len;
    if (ts_exr_write_memory(&img, &buf, &len, &err)) fail_msg("%s", err.message);
    unsigned char *file = read_whole(path, &file_len);
    assert_int_equal(len, file_len); /* the same bytes as the file */
    assert_memory_equal(buf, file, len);
    assert_int_equal(ts_exr_write_memory(&img, &buf2, &len2, &err), TS_OK); /* deterministic */
    assert_int_equal(len2, len);
    assert_memory_equal(buf2, buf, len);
    assert_int_equal(ts_exr_read(path, &from_file, &err), TS_OK);
    if (ts_exr_read_memory(buf, len, &from_mem, &err)) fail_msg("%s", err.message);
    assert_images_identical(&from_file, &from_mem);
    assert_images_identical(&img, &from_mem);
    for (int c = 0; c < K_N; c++) assert_string_equal(from_file.channel_names[c], from_mem.channel_names[c]);
    free(file);
    free(buf);
    free(buf2);
    ts_image_fini(&from_file);
    ts_image_fini(&from_mem);
    ts_image_fini(&img);
}

static void test_read_half_uint_offset_scanline(void **state)
{
    (void)state;
    /* 5×19 scanline file, data window origin (-3, 7), ZIP (16-line blocks): HALF, UINT, FLOAT. */
    enum { W = 5, H = 19 };
    static const uint16_t half_set[] = {0x0000, 0x8000, 0x3c00, 0x3800, 0xc000, 0x7bff, 0x0001,
                                        0x03ff, 0x3555, 0x7c00, 0xfc00, 0x1234, 0xabcd};
    static const uint32_t uint_set[] = {0, 1, 65535, 16777216, 16777217, 4294967295u};
    uint16_t half[W * H];
    uint32_t uints[W * H];
    float floats[W * H];
    for (int k = 0; k < W * H; k++) {
        half[k] = half_set[k % (sizeof half_set / sizeof half_set[0])];
        uints[k] = uint_set[k % (sizeof uint_set / sizeof uint_set[0])];
        floats[k] = (float)k * 0.25f - 3.0f;
    }
    fixture fx = {.storage = EXR_STORAGE_SCANLINE, .x0 = -3, .y0 = 7, .w = W, .h = H,
                  .compression = EXR_COMPRESSION_ZIP, .n = 3, .names = {"Y", "id", "Z"},
                  .types = {EXR_PIXEL_HALF, EXR_PIXEL_UINT, EXR_PIXEL_FLOAT}, .planes = {half, uints, floats}};
    char path[512];
    path_in_dir(path, sizeof path, "half.exr");
    write_fixture(path, &fx);

    ts_image img;
    ts_error err = {0};
    if (ts_exr_read(path, &img, &err)) fail_msg("%s", err.message);
    assert_int_equal(img.width, W);
    assert_int_equal(img.height, H);
    assert_int_equal(img.n_channels, 3);
    int cy = ts_image_channel(&img, "Y"), ci = ts_image_channel(&img, "id"), cz = ts_image_channel(&img, "Z");
    assert_true(cy >= 0 && ci >= 0 && cz >= 0);
    for (int k = 0; k < W * H; k++) {
        /* Every half and the float of a uint are exact in float: compare bit patterns. */
        assert_int_equal(float_bits(img.data[k * 3 + cy]), float_bits(half_value(half[k])));
        assert_int_equal(float_bits(img.data[k * 3 + ci]), float_bits((float)uints[k]));
        assert_int_equal(float_bits(img.data[k * 3 + cz]), float_bits(floats[k]));
    }
    assert_true(img.data[2 * 3 + cy] == 1.0f && img.data[3 * 3 + cy] == 0.5f && img.data[4 * 3 + cy] == -2.0f);
    assert_true(img.data[5 * 3 + cy] == 65504.0f && img.data[6 * 3 + cy] == ldexpf(1, -24));
    assert_true(img.data[5 * 3 + ci] == 4294967296.0f); /* 2^32 − 1 rounds to 2^32 in float */
    const ts_image_attr *gain = ts_image_attr_find(&img, "fixture.gain");
    assert_non_null(gain);
    assert_int_equal(gain->type, TS_ATTR_DOUBLE);
    assert_true(gain->d == 0.75);
    assert_null(ts_image_attr_find(&img, "pixelAspectRatio")); /* standard attributes are not copied */
    assert_null(ts_image_attr_find(&img, "screenWindowWidth"));
    ts_image_fini(&img);
}

static void test_read_tiled(void **state)
{
    (void)state;
    /* 37×23 with 16×8 tiles: partial tiles on the right and bottom; origin (10, -4). */
    enum { W = 37, H = 23 };
    static float r[W * H], g[W * H];
    static uint16_t a[W * H];
    for (int k = 0; k < W * H; k++) {
        r[k] = (float)k;
        g[k] = -1.0f / (float)(k + 1);
        a[k] = (uint16_t)(0x3c00 + (k % 7)); /* 1 + k·2^-10 */
    }
    exr_compression_t comps[] = {EXR_COMPRESSION_NONE, EXR_COMPRESSION_ZIP, EXR_COMPRESSION_PIZ};
    exr_tile_level_mode_t modes[] = {EXR_TILE_ONE_LEVEL, EXR_TILE_MIPMAP_LEVELS, EXR_TILE_ONE_LEVEL};
    for (int t = 0; t < 3; t++) {
        fixture fx = {.storage = EXR_STORAGE_TILED, .x0 = 10, .y0 = -4, .w = W, .h = H, .tile_w = 16, .tile_h = 8,
                      .levels = modes[t], .compression = comps[t], .n = 3, .names = {"R", "G", "A"},
                      .types = {EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_HALF}, .planes = {r, g, a}};
        char path[512];
        path_in_dir(path, sizeof path, "tiled.exr");
        write_fixture(path, &fx);
        ts_image img;
        ts_error err = {0};
        if (ts_exr_read(path, &img, &err)) fail_msg("case %d: %s", t, err.message);
        assert_int_equal(img.width, W);
        assert_int_equal(img.height, H);
        int cr = ts_image_channel(&img, "R"), cg = ts_image_channel(&img, "G"), ca = ts_image_channel(&img, "A");
        for (int k = 0; k < W * H; k++) {
            assert_int_equal(float_bits(img.data[k * 3 + cr]), float_bits(r[k]));
            assert_int_equal(float_bits(img.data[k * 3 + cg]), float_bits(g[k]));
            assert_true(img.data[k * 3 + ca] == 1.0f + ldexpf((float)(k % 7), -10)); /* exact in half and float */
        }
        ts_image_fini(&img);
    }
}

/* All-HALF files of 3 and 4 channels (RGBA textures are usually stored so): OpenEXR 3.1's
 * fast half→float path for four interleaved channels reversed them (A,B,G,R read as
 * R,G,B,A; pbrt-v3 scene f10-1ac's lines.exr turned its red into alpha = 1). Every channel
 * and pixel holds a different value, so any permutation or misplaced block fails. */
static void test_read_all_half_channel_order(void **state)
{
    (void)state;
    enum { W = 21, H = 19 };
    static uint16_t planes[4][W * H];
    for (int c = 0; c < 4; c++)
        for (int k = 0; k < W * H; k++) planes[c][k] = (uint16_t)(0x3c00 + c * 0x400 + k); /* 2^c·(1 + k·2^-10) */
    const char *names[4] = {"R", "G", "B", "A"};
    exr_storage_t storages[] = {EXR_STORAGE_SCANLINE, EXR_STORAGE_SCANLINE, EXR_STORAGE_TILED};
    exr_compression_t comps[] = {EXR_COMPRESSION_ZIP, EXR_COMPRESSION_NONE, EXR_COMPRESSION_PIZ};
    for (int n = 3; n <= 4; n++)
        for (int t = 0; t < 3; t++) {
            fixture fx = {.storage = storages[t], .x0 = 2, .y0 = -5, .w = W, .h = H, .tile_w = 16, .tile_h = 8,
                          .levels = EXR_TILE_ONE_LEVEL, .compression = comps[t], .n = n,
                          .names = {names[0], names[1], names[2], names[3]},
                          .types = {EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF, EXR_PIXEL_HALF},
                          .planes = {planes[0], planes[1], planes[2], planes[3]}};
            char path[512];
            path_in_dir(path, sizeof path, "allhalf.exr");
            write_fixture(path, &fx);
            ts_image img;
            ts_error err = {0};
            if (ts_exr_read(path, &img, &err)) fail_msg("%d channels, case %d: %s", n, t, err.message);
            assert_int_equal(img.width, W);
            assert_int_equal(img.height, H);
            assert_int_equal(img.n_channels, n);
            for (int c = 0; c < n; c++) {
                int ci = ts_image_channel(&img, names[c]);
                assert_true(ci >= 0);
                for (int k = 0; k < W * H; k++)
                    if (float_bits(img.data[k * n + ci]) != float_bits(half_value(planes[c][k])))
                        fail_msg("%d channels, case %d: channel %s pixel %d reads %g, wrote %g", n, t, names[c], k,
                                 (double)img.data[k * n + ci], (double)half_value(planes[c][k]));
            }
            ts_image_fini(&img);
        }
}

static void test_unsupported_multipart(void **state)
{
    (void)state;
    char path[512];
    path_in_dir(path, sizeof path, "multipart.exr");
    exr_context_t ctxt;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, NULL), EXR_ERR_SUCCESS);
    float plane[4 * 4] = {0};
    for (int p = 0; p < 2; p++) {
        int part;
        assert_int_equal(exr_add_part(ctxt, p ? "right" : "left", EXR_STORAGE_SCANLINE, &part), EXR_ERR_SUCCESS);
        assert_int_equal(exr_initialize_required_attr_simple(ctxt, part, 4, 4, EXR_COMPRESSION_NONE), EXR_ERR_SUCCESS);
        assert_int_equal(exr_add_channel(ctxt, part, "Y", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                         EXR_ERR_SUCCESS);
    }
    assert_int_equal(exr_write_header(ctxt), EXR_ERR_SUCCESS);
    for (int p = 0; p < 2; p++) {
        exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
        exr_chunk_info_t ci;
        assert_int_equal(exr_write_scanline_chunk_info(ctxt, p, 0, &ci), EXR_ERR_SUCCESS);
        assert_int_equal(exr_encoding_initialize(ctxt, p, &ci, &enc), EXR_ERR_SUCCESS);
        for (int y = 0; y < 4; y++) {
            if (y) {
                assert_int_equal(exr_write_scanline_chunk_info(ctxt, p, y, &ci), EXR_ERR_SUCCESS);
                assert_int_equal(exr_encoding_update(ctxt, p, &ci, &enc), EXR_ERR_SUCCESS);
            }
            enc.channels[0].encode_from_ptr = (const uint8_t *)(plane + 4 * y);
            enc.channels[0].user_pixel_stride = 4;
            enc.channels[0].user_line_stride = 16;
            enc.channels[0].user_data_type = EXR_PIXEL_FLOAT;
            enc.channels[0].user_bytes_per_element = 4;
            assert_int_equal(exr_encoding_choose_default_routines(ctxt, p, &enc), EXR_ERR_SUCCESS);
            assert_int_equal(exr_encoding_run(ctxt, p, &enc), EXR_ERR_SUCCESS);
        }
        exr_encoding_destroy(ctxt, &enc);
    }
    assert_int_equal(exr_finish(&ctxt), EXR_ERR_SUCCESS);

    ts_image img;
    ts_error err = {0};
    ts_status st = ts_exr_read(path, &img, &err);
    assert_failed_cleanly(st, TS_ERR_UNSUPPORTED, &err, &img);
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, "2 parts"));
}

static void test_unsupported_deep(void **state)
{
    (void)state;
    /* A 4×2 deep scanline file with no samples, uncompressed (one line per chunk). */
    char path[512];
    path_in_dir(path, sizeof path, "deep.exr");
    exr_context_t ctxt;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, NULL), EXR_ERR_SUCCESS);
    int part;
    assert_int_equal(exr_add_part(ctxt, NULL, EXR_STORAGE_DEEP_SCANLINE, &part), EXR_ERR_SUCCESS);
    assert_int_equal(exr_initialize_required_attr_simple(ctxt, part, 4, 2, EXR_COMPRESSION_NONE), EXR_ERR_SUCCESS);
    assert_int_equal(exr_add_channel(ctxt, part, "Z", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                     EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctxt), EXR_ERR_SUCCESS);
    int32_t counts[4] = {0, 0, 0, 0}; /* cumulative sample counts of one line */
    for (int y = 0; y < 2; y++)
        assert_int_equal(exr_write_deep_scanline_chunk(ctxt, part, y, NULL, 0, 0, counts, sizeof counts), EXR_ERR_SUCCESS);
    assert_int_equal(exr_finish(&ctxt), EXR_ERR_SUCCESS);

    ts_image img;
    ts_error err = {0};
    assert_failed_cleanly(ts_exr_read(path, &img, &err), TS_ERR_UNSUPPORTED, &err, &img);
    assert_non_null(strstr(err.message, "deep"));
}

static void test_error_missing_file(void **state)
{
    (void)state;
    char path[512];
    path_in_dir(path, sizeof path, "does_not_exist.exr");
    ts_image img;
    ts_error err = {0};
    assert_failed_cleanly(ts_exr_read(path, &img, &err), TS_ERR_IO, &err, &img);
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, "No such file"));
    assert_failed_cleanly(ts_exr_read(g_dir, &img, &err), TS_ERR_IO, &err, &img); /* a directory */
}

/* A small valid file: 8×8, 3 channels, ZIP, attributes. */
static unsigned char *small_exr(size_t *len)
{
    ts_image img;
    ts_error err = {0};
    const char *names[] = {"R", "G", "B"};
    assert_int_equal(ts_image_init(&img, 8, 8, 3, names, &err), TS_OK);
    for (int k = 0; k < 8 * 8 * 3; k++) img.data[k] = (float)(rng_next() >> 40) / 65536.0f;
    assert_int_equal(ts_image_set_string(&img, "tessera.scene_digest", "abc", &err), TS_OK);
    assert_int_equal(ts_image_set_int(&img, "tessera.seed", 7, &err), TS_OK);
    unsigned char *buf;
    assert_int_equal(ts_exr_write_memory(&img, &buf, len, &err), TS_OK);
    ts_image_fini(&img);
    return buf;
}

static void test_error_truncated(void **state)
{
    (void)state;
    size_t len;
    unsigned char *good = small_exr(&len);
    ts_image img;
    ts_error err = {0};
    assert_int_equal(ts_exr_read_memory(good, len, &img, &err), TS_OK);
    ts_image_fini(&img);
    /* Every cut fails: the last bytes of a file always belong to its last chunk. A copy of
     * exactly cut bytes so a read past the end is visible to ASan. */
    for (size_t cut = 0; cut < len; cut++) {
        unsigned char *part = malloc(cut ? cut : 1);
        memcpy(part, good, cut);
        ts_status st = ts_exr_read_memory(part, cut, &img, &err);
        if (st == TS_OK) fail_msg("a file cut at %zu of %zu bytes was accepted", cut, len);
        assert_failed_cleanly(st, TS_ERR_INVALID, &err, &img);
        free(part);
    }
    /* File variant at a few lengths: in the magic, in the header, in the offsets, in the data. */
    size_t cuts[] = {0, 3, 4, 8, 40, len / 4, len / 2, len - 20, len - 1};
    char path[512];
    path_in_dir(path, sizeof path, "truncated.exr");
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        write_whole(path, good, cuts[k]);
        ts_status st = ts_exr_read(path, &img, &err);
        assert_failed_cleanly(st, TS_ERR_INVALID, &err, &img);
        assert_non_null(strstr(err.message, path));
    }
    write_whole(path, good, len / 2);
    assert_int_equal(ts_exr_read(path, &img, &err), TS_ERR_INVALID);
    print_message("  cut at %zu of %zu bytes: %s\n", len / 2, len, err.message);
    free(good);
}

static void test_error_garbage(void **state)
{
    (void)state;
    ts_image img;
    ts_error err = {0};
    unsigned char buf[4096];
    /* 300 buffers of random bytes, 300 with the EXR magic and version 2 then random bytes. */
    for (int k = 0; k < 600; k++) {
        size_t len = (size_t)(rng_next() % sizeof buf);
        for (size_t i = 0; i < len; i++) buf[i] = (unsigned char)(rng_next() >> 56);
        if (k >= 300 && len >= 8) memcpy(buf, "\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
        unsigned char *copy = malloc(len ? len : 1);
        memcpy(copy, buf, len);
        ts_status st = ts_exr_read_memory(copy, len, &img, &err);
        assert_failed_cleanly(st, TS_ERR_INVALID, &err, &img);
        if (k < 300) assert_non_null(strstr(err.message, "not an OpenEXR file")); /* no magic number */
        free(copy);
    }
    print_message("  magic + garbage: %s\n", err.message);
    for (const char *p = err.message; *p; p++) assert_true(*p >= 0x20 && *p <= 0x7e); /* printable ASCII */
    char path[512];
    path_in_dir(path, sizeof path, "garbage.exr");
    memcpy(buf, "\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    write_whole(path, buf, 1000);
    assert_failed_cleanly(ts_exr_read(path, &img, &err), TS_ERR_INVALID, &err, &img);
    assert_non_null(strstr(err.message, path));
}

static void test_error_bit_flips(void **state)
{
    (void)state;
    /* Corrupt a valid file in 1..4 random bytes, 2000 times: no crash, no leak (run under
     * ASan), and either a clean failure or a well-formed image. */
    size_t len;
    unsigned char *good = small_exr(&len);
    unsigned char *buf = malloc(len);
    int failures = 0;
    for (int k = 0; k < 2000; k++) {
        memcpy(buf, good, len);
        int flips = 1 + (int)(rng_next() % 4);
        for (int f = 0; f < flips; f++) buf[rng_next() % len] ^= (unsigned char)(1 + rng_next() % 255);
        ts_image img;
        ts_error err = {0};
        ts_status st = ts_exr_read_memory(buf, len, &img, &err);
        if (st == TS_OK) {
            assert_non_null(img.data);
            assert_true(img.width >= 1 && img.height >= 1 && img.n_channels >= 1);
            ts_image_fini(&img);
        } else {
            failures++;
            assert_true(st == TS_ERR_INVALID || st == TS_ERR_UNSUPPORTED || st == TS_ERR_LIMIT || st == TS_ERR_NOMEM);
            assert_true(strlen(err.message) > 10);
            assert_null(img.data);
        }
    }
    print_message("  bit flips: %d of 2000 corrupted files refused\n", failures);
    free(buf);
    free(good);
}

static void test_atomic_write(void **state)
{
    (void)state;
    ts_image a, b, back;
    ts_error err = {0};
    const char *names[] = {"R", "G", "B"};
    assert_int_equal(ts_image_init(&a, 3, 2, 3, names, &err), TS_OK);
    assert_int_equal(ts_image_init(&b, 5, 4, 3, names, &err), TS_OK);
    for (int k = 0; k < 3 * 2 * 3; k++) a.data[k] = 1.0f;
    for (int k = 0; k < 5 * 4 * 3; k++) b.data[k] = 2.0f;

    /* Into a directory that does not exist: a sentence, nothing left anywhere. */
    char path[512];
    path_in_dir(path, sizeof path, "no_such_dir/out.exr");
    assert_int_equal(ts_exr_write(path, &a, &err), TS_ERR_IO);
    assert_non_null(strstr(err.message, path));
    assert_non_null(strstr(err.message, "No such file"));
    assert_int_equal(count_tmp_files(), 0);

    /* The rename fails (the target is a directory): the temporary file is removed. */
    path_in_dir(path, sizeof path, "a_directory");
    assert_int_equal(mkdir(path, 0700), 0);
    assert_int_equal(ts_exr_write(path, &a, &err), TS_ERR_IO);
    assert_non_null(strstr(err.message, "renaming"));
    assert_int_equal(count_tmp_files(), 0);
    rmdir(path);

    /* Overwriting replaces the file. */
    path_in_dir(path, sizeof path, "replace.exr");
    assert_int_equal(ts_exr_write(path, &a, &err), TS_OK);
    assert_int_equal(ts_exr_write(path, &b, &err), TS_OK);
    assert_int_equal(ts_exr_read(path, &back, &err), TS_OK);
    assert_images_identical(&b, &back);
    assert_int_equal(count_tmp_files(), 0);
    ts_image_fini(&back);

    /* A row too long for the library's int32 byte stride (2^25 pixels × 16 channels × 4 B =
     * 2^31): refused before encoding. Only the struct is faked; no pixels are touched. */
    ts_image wide = a;
    wide.width = 1 << 25;
    wide.height = 1;
    wide.n_channels = 16;
    for (int c = 0; c < 16; c++) snprintf(wide.channel_names[c], sizeof wide.channel_names[c], "c%d", c);
    unsigned char *wbuf;
    size_t wlen;
    assert_int_equal(ts_exr_write_memory(&wide, &wbuf, &wlen, &err), TS_ERR_LIMIT);
    assert_null(wbuf);

    /* An attribute that would clash with the header: refused before any file exists. */
    path_in_dir(path, sizeof path, "refused.exr");
    assert_int_equal(ts_image_set_string(&a, "channels", "RGB", &err), TS_OK);
    assert_int_equal(ts_exr_write(path, &a, &err), TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "'channels'"));
    struct stat sb;
    assert_int_not_equal(stat(path, &sb), 0);
    assert_int_equal(count_tmp_files(), 0);
    ts_image_fini(&a);
    ts_image_fini(&b);
}

static int group_setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "%s/ts_test_exr.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int group_teardown(void **state)
{
    (void)state;
    DIR *d = opendir(g_dir);
    if (!d) return 0;
    struct dirent *e;
    char path[512];
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            path_in_dir(path, sizeof path, e->d_name);
            unlink(path);
        }
    closedir(d);
    rmdir(g_dir);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_image_container),
        cmocka_unit_test(test_round_trip_file),
        cmocka_unit_test(test_round_trip_memory),
        cmocka_unit_test(test_read_half_uint_offset_scanline),
        cmocka_unit_test(test_read_all_half_channel_order),
        cmocka_unit_test(test_read_tiled),
        cmocka_unit_test(test_unsupported_multipart),
        cmocka_unit_test(test_unsupported_deep),
        cmocka_unit_test(test_error_missing_file),
        cmocka_unit_test(test_error_truncated),
        cmocka_unit_test(test_error_garbage),
        cmocka_unit_test(test_error_bit_flips),
        cmocka_unit_test(test_atomic_write),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
