/* test_png.c — linear → 8-bit sRGB conversion and PNG encoding, decoded back with libpng's
 * low-level reader (no transforms) so the bytes checked are the bytes in the file. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* libpng's own header: the renderer's encoder is image/png_encode.h, so <png.h> is libpng's. */
#include <png.h>

#include "image/image.h"
#include "image/png_encode.h"

/* ---- a minimal PNG decoder on libpng: RGB8 rows as stored ---- */

typedef struct mem_reader {
    const unsigned char *p;
    size_t left;
} mem_reader;

static void read_mem(png_structp png, png_bytep out, png_size_t n)
{
    mem_reader *r = png_get_io_ptr(png);
    if (n > r->left) png_error(png, "read past the end");
    memcpy(out, r->p, n);
    r->p += n;
    r->left -= n;
}

typedef struct decoded {
    uint32_t width, height;
    int bit_depth, color_type, interlace, has_srgb;
    unsigned char *rgb; /* width*height*3 */
} decoded;

/* Decodes buf; returns 0 on success. No transforms are set, so rows are the stored samples. */
static int decode_png(const unsigned char *buf, size_t len, decoded *d)
{
    memset(d, 0, sizeof *d);
    if (len < 8 || png_sig_cmp(buf, 0, 8)) return -1;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    png_bytep *rows = NULL;
    mem_reader r = {buf, len};
    if (setjmp(png_jmpbuf(png))) {
        free(rows);
        free(d->rgb);
        d->rgb = NULL;
        png_destroy_read_struct(&png, &info, NULL);
        return -1;
    }
    png_set_read_fn(png, &r, read_mem);
    png_read_info(png, info);
    d->width = png_get_image_width(png, info);
    d->height = png_get_image_height(png, info);
    d->bit_depth = png_get_bit_depth(png, info);
    d->color_type = png_get_color_type(png, info);
    d->interlace = png_get_interlace_type(png, info);
    d->has_srgb = png_get_valid(png, info, PNG_INFO_sRGB) != 0;
    if (d->bit_depth != 8 || d->color_type != PNG_COLOR_TYPE_RGB) png_error(png, "not RGB8");
    d->rgb = malloc((size_t)d->width * d->height * 3);
    rows = malloc(sizeof *rows * d->height);
    for (uint32_t y = 0; y < d->height; y++) rows[y] = d->rgb + (size_t)y * d->width * 3;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    free(rows);
    png_destroy_read_struct(&png, &info, NULL);
    return 0;
}

/* sRGB code value → linear, by the standard's formula (the inverse of what is tested). */
static double srgb_to_linear(double s) { return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4); }

/* ---- tests ---- */

static void test_srgb8_values(void **state)
{
    (void)state;
    assert_int_equal(ts_srgb8_from_linear(0.0f), 0);
    assert_int_equal(ts_srgb8_from_linear(-0.0f), 0);
    assert_int_equal(ts_srgb8_from_linear(1.0f), 255);
    assert_int_equal(ts_srgb8_from_linear(0.5f), 188); /* 1.055·0.5^(1/2.4) − 0.055 = 0.73536 → 187.52 */
    assert_int_equal(ts_srgb8_from_linear(0.18f), 118); /* 18 % grey */
    assert_int_equal(ts_srgb8_from_linear(0.001f), 3);  /* linear segment: 12.92·0.001·255 = 3.29 */
    assert_int_equal(ts_srgb8_from_linear(2.0f), 255);
    assert_int_equal(ts_srgb8_from_linear(1e30f), 255);
    assert_int_equal(ts_srgb8_from_linear(INFINITY), 255);
    assert_int_equal(ts_srgb8_from_linear(-1.0f), 0);
    assert_int_equal(ts_srgb8_from_linear(-INFINITY), 0);
    assert_int_equal(ts_srgb8_from_linear(NAN), 0);
    assert_int_equal(ts_srgb8_from_linear(-NAN), 0);
    assert_int_equal(ts_srgb8_from_linear(1e-45f), 0); /* smallest denormal */

    /* Every code survives code → linear (standard formula) → code. Exact: rounding the
     * linear value to float moves it by ≤ 2^-24 relative, far less than the half-code
     * margin to the next rounding boundary. */
    for (int k = 0; k < 256; k++) {
        float lin = (float)srgb_to_linear(k / 255.0);
        if (ts_srgb8_from_linear(lin) != k) fail_msg("code %d → linear %.9g → %d", k, lin, ts_srgb8_from_linear(lin));
    }
    /* Monotonic over [0, 1.01] in 2^17 steps. */
    int prev = 0;
    for (int k = 0; k <= (1 << 17); k++) {
        int code = ts_srgb8_from_linear(1.01f * (float)k / (float)(1 << 17));
        assert_true(code >= prev);
        prev = code;
    }
    assert_int_equal(prev, 255);
}

/* Row 0 of R: the values the brief names; G and B carry other cases. */
enum { W = 8, H = 2 };
static const float k_r[W] = {0.0f, 1.0f, 0.5f, 2.0f, -1.0f, NAN, 0.25f, 0.18f};
static const uint8_t k_r_codes[W] = {0, 255, 188, 255, 0, 0, 137, 118}; /* 0.25 → 136.96 */
static const uint8_t k_r_codes_plus1[W] = {0, 255, 255, 255, 0, 0, 188, 162}; /* ×2: 0.36 → 161.7 */

static void make_image(ts_image *img)
{
    /* Channels out of order, plus one the PNG ignores. */
    const char *names[] = {"B", "weight", "R", "G"};
    ts_error err = {0};
    assert_int_equal(ts_image_init(img, W, H, 4, names, &err), TS_OK);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *p = img->data + ((size_t)y * W + x) * 4;
            p[0] = y == 0 ? 1.0f : INFINITY;      /* B */
            p[1] = 1e9f;                          /* weight: ignored */
            p[2] = y == 0 ? k_r[x] : 0.0f;        /* R */
            p[3] = y == 0 ? 0.0031308f : -0.0f;   /* G: the curve's knee (12.92·0.0031308·255 = 10.3) */
        }
}

static void check_decoded(const decoded *d, const uint8_t *r_codes)
{
    assert_int_equal(d->width, W);
    assert_int_equal(d->height, H);
    assert_int_equal(d->bit_depth, 8);
    assert_int_equal(d->color_type, PNG_COLOR_TYPE_RGB);
    assert_int_equal(d->interlace, PNG_INTERLACE_NONE);
    assert_true(d->has_srgb);
    for (int x = 0; x < W; x++) {
        const unsigned char *p0 = d->rgb + x * 3, *p1 = d->rgb + (W + x) * 3;
        if (p0[0] != r_codes[x]) fail_msg("R[%d] = %d, want %d", x, p0[0], r_codes[x]);
        assert_int_equal(p0[2], 255);
        assert_int_equal(p1[0], 0);
        assert_int_equal(p1[1], 0);
        assert_int_equal(p1[2], 255);
    }
}

static void test_png_encode_values(void **state)
{
    (void)state;
    ts_image img;
    make_image(&img);
    ts_error err = {0};
    unsigned char *buf;
    size_t len;
    decoded d;

    if (ts_png_encode(&img, 0.0f, &buf, &len, &err)) fail_msg("%s", err.message);
    assert_int_equal(decode_png(buf, len, &d), 0);
    check_decoded(&d, k_r_codes);
    for (int x = 0; x < W; x++) assert_int_equal(d.rgb[x * 3 + 1], 10);
    free(d.rgb);
    free(buf);

    /* +1 stop doubles the linear values before the curve. */
    assert_int_equal(ts_png_encode(&img, 1.0f, &buf, &len, &err), TS_OK);
    assert_int_equal(decode_png(buf, len, &d), 0);
    check_decoded(&d, k_r_codes_plus1);
    for (int x = 0; x < W; x++) assert_int_equal(d.rgb[x * 3 + 1], 18); /* 0.0062616 is past the knee: power segment, 18.46 */
    free(d.rgb);
    free(buf);

    /* −1 stop: 1 → 0.5 → 188. */
    assert_int_equal(ts_png_encode(&img, -1.0f, &buf, &len, &err), TS_OK);
    assert_int_equal(decode_png(buf, len, &d), 0);
    assert_int_equal(d.rgb[1 * 3 + 0], 188);
    assert_int_equal(d.rgb[0 * 3 + 2], 188);
    free(d.rgb);
    free(buf);
    ts_image_fini(&img);
}

static void test_png_errors(void **state)
{
    (void)state;
    ts_image img;
    ts_error err = {0};
    const char *names[] = {"R", "G", "weight"};
    assert_int_equal(ts_image_init(&img, 2, 2, 3, names, &err), TS_OK);
    unsigned char *buf = (unsigned char *)&img; /* must be reset to NULL */
    size_t len = 99;
    assert_int_equal(ts_png_encode(&img, 0.0f, &buf, &len, &err), TS_ERR_INVALID);
    assert_null(buf);
    assert_int_equal(len, 0);
    assert_non_null(strstr(err.message, "'B'"));
    ts_image_fini(&img);
    ts_image empty = {0};
    assert_int_equal(ts_png_encode(&empty, 0.0f, &buf, &len, &err), TS_ERR_INVALID);
    assert_true(strlen(err.message) > 10);
}

static void test_png_matches_reference(void **state)
{
    (void)state;
    /* The encoder's fast path must give ts_srgb8_from_linear(v·2^stops) for every sample:
     * each rounding boundary (found here by bisection) and its float neighbours, plus random
     * bit patterns in [0, 1.25) and special values, at three exposures. */
    enum { N = 255 * 3 + 4095 }; /* a multiple of 3: one RGB row */
    static float v[N];
    int n = 0;
    for (int k = 0; k < 255; k++) {
        float lo = 0.0f, hi = 1.0f;
        while (nextafterf(lo, 2.0f) < hi) {
            float mid = lo + (hi - lo) / 2;
            if (mid <= lo || mid >= hi) mid = nextafterf(lo, 2.0f);
            if (ts_srgb8_from_linear(mid) > k) hi = mid;
            else lo = mid;
        }
        v[n++] = lo;
        v[n++] = hi;
        v[n++] = nextafterf(hi, 2.0f);
    }
    uint64_t s = 12345;
    while (n < N) {
        s = s * 6364136223846793005ull + 1442695040888963407ull; /* LCG, fixed seed */
        uint32_t u = (uint32_t)(s >> 33) % 0x3fa00000u;          /* bit patterns below 1.25f */
        memcpy(&v[n++], &u, sizeof u);
    }
    v[0] = NAN, v[1] = INFINITY, v[2] = -INFINITY, v[3] = -0.0f;
    const char *names[] = {"R", "G", "B"};
    ts_image img;
    ts_error err = {0};
    assert_int_equal(N % 3, 0);
    assert_int_equal(ts_image_init(&img, N / 3, 1, 3, names, &err), TS_OK);
    memcpy(img.data, v, sizeof v);
    const float stops[] = {0.0f, 1.0f, -2.5f};
    for (int e = 0; e < 3; e++) {
        unsigned char *buf;
        size_t len;
        decoded d;
        assert_int_equal(ts_png_encode(&img, stops[e], &buf, &len, &err), TS_OK);
        assert_int_equal(decode_png(buf, len, &d), 0);
        float scale = exp2f(stops[e]);
        for (int k = 0; k < N; k++)
            if (d.rgb[k] != ts_srgb8_from_linear(v[k] * scale))
                fail_msg("stops %g, value %.9g: %d != %d", stops[e], v[k], d.rgb[k], ts_srgb8_from_linear(v[k] * scale));
        free(d.rgb);
        free(buf);
    }
    ts_image_fini(&img);
}

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
    closedir(d);
    return n;
}

static void test_png_write_file(void **state)
{
    (void)state;
    char dir[256], path[512];
    snprintf(dir, sizeof dir, "%s/ts_test_png.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    assert_non_null(mkdtemp(dir));
    ts_image img;
    make_image(&img);
    ts_error err = {0};

    snprintf(path, sizeof path, "%s/missing/out.png", dir);
    assert_int_equal(ts_png_write(path, &img, 0.0f, &err), TS_ERR_IO);
    assert_non_null(strstr(err.message, path));
    assert_int_equal(count_entries(dir), 0); /* no temporary file anywhere */

    snprintf(path, sizeof path, "%s/out.png", dir);
    assert_int_equal(ts_png_write(path, &img, 5.0f, &err), TS_OK); /* then overwritten */
    if (ts_png_write(path, &img, 0.0f, &err)) fail_msg("%s", err.message);
    assert_int_equal(count_entries(dir), 1);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    unsigned char file[4096];
    size_t n = fread(file, 1, sizeof file, f);
    fclose(f);
    unsigned char *buf;
    size_t len;
    assert_int_equal(ts_png_encode(&img, 0.0f, &buf, &len, &err), TS_OK);
    assert_int_equal(n, len); /* the file holds exactly the encoded bytes */
    assert_memory_equal(file, buf, len);
    decoded d;
    assert_int_equal(decode_png(file, n, &d), 0);
    check_decoded(&d, k_r_codes);
    free(d.rgb);
    free(buf);
    unlink(path);
    rmdir(dir);
    ts_image_fini(&img);
}

static void test_png_full_hd_time(void **state)
{
    (void)state;
    /* A 1920×1080 preview: a gradient, decoded and spot-checked; the time is reported. */
    const char *names[] = {"R", "G", "B"};
    ts_image img;
    ts_error err = {0};
    assert_int_equal(ts_image_init(&img, 1920, 1080, 3, names, &err), TS_OK);
    for (size_t p = 0; p < (size_t)1920 * 1080; p++) {
        img.data[p * 3 + 0] = (float)(p % 1920) / 1919.0f;
        img.data[p * 3 + 1] = 0.5f;
        img.data[p * 3 + 2] = (float)(p / 1920) / 1079.0f;
    }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    unsigned char *buf;
    size_t len;
    assert_int_equal(ts_png_encode(&img, 0.0f, &buf, &len, &err), TS_OK);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    print_message("  1920x1080 PNG: %zu bytes in %.1f ms\n", len,
                  (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) * 1e-6);
    decoded d;
    assert_int_equal(decode_png(buf, len, &d), 0);
    assert_int_equal(d.rgb[1919 * 3 + 0], 255);
    assert_int_equal(d.rgb[1], 188);
    assert_int_equal(d.rgb[((size_t)1079 * 1920) * 3 + 2], 255);
    free(d.rgb);
    free(buf);
    ts_image_fini(&img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb8_values),
        cmocka_unit_test(test_png_encode_values),
        cmocka_unit_test(test_png_errors),
        cmocka_unit_test(test_png_matches_reference),
        cmocka_unit_test(test_png_write_file),
        cmocka_unit_test(test_png_full_hd_time),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
