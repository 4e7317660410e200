/* test_render.c — the tile renderer: the film is bit-identical whatever the thread count
 * and however the sample range is split into passes (docs/design.md §6), and each sample
 * lands in the pixel whose square it was drawn in. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "film/film_image.h"
#include "image/image.h"
#include "render/render.h"
#include "json/scene_json.h"

static ts_film *render(const ts_scene *s, int threads, const uint32_t *passes, int n_passes)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                s->crop_y1 - s->crop_y0, &err);
    assert_non_null(f);
    ts_render_stats stats = {0};
    uint32_t begin = 0;
    for (int i = 0; i < n_passes; i++) {
        ts_render_request req = {s, TS_INTEGRATOR_AO, f, begin, begin + passes[i], threads, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
        begin += passes[i];
    }
    assert_int_equal(stats.counters.nonfinite, 0);
    assert_int_equal(stats.counters.samples, (uint64_t)f->width * f->height * begin);
    return f;
}

static void test_thread_count_and_passes_do_not_change_pixels(void **state)
{
    (void)state;
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_builtin(NULL, &s, &err), TS_OK);
    /* A smaller film keeps the test quick; crop a window off-centre to exercise offsets. */
    s->crop_x0 = 100, s->crop_x1 = 230, s->crop_y0 = 200, s->crop_y1 = 290;
    uint32_t one[] = {8}, split[] = {1, 1, 2, 4};
    ts_film *a = render(s, 1, one, 1);
    ts_film *b = render(s, 2, one, 1);
    ts_film *c = render(s, 3, split, 4);
    size_t bytes = sizeof *a->pixels * (size_t)a->width * a->height;
    assert_memory_equal(a->pixels, b->pixels, bytes);
    assert_memory_equal(a->pixels, c->pixels, bytes);
    /* And the image is not trivially empty: the room is mostly unoccluded. */
    ts_rgb m = ts_film_pixel_rgb(a, 160, 250);
    assert_true(m.r > 0.05f && m.r <= 1.0f);
    ts_film_destroy(a);
    ts_film_destroy(b);
    ts_film_destroy(c);
    ts_scene_destroy(s);
}

/* The Cornell box (inline copy of its boxes and walls is the built-in scene) with a
 * transform applied to every shape and the camera moved along: translated by 1e5 and
 * scaled by 1e-3 and 1e3. AO with its distance scaled along is invariant under both, and every
 * sample uses the same random numbers, so the images differ only where floating-point
 * error flips an occlusion test or nudges a hit. Self-intersection (the failure this
 * catches) darkens large areas: tens of percent of the mean. */
static ts_film *render_transformed(const char *transform, double scale, double shift)
{
    size_t len;
    const char *base = ts_scene_builtin_text(&len);
    /* Rebuild the document with the transform on each shape and a moved camera. */
    char *doc = malloc(len + 16384);
    assert_non_null(doc);
    const char *shapes = strstr(base, "\"shapes\"");
    assert_non_null(shapes);
    int n = snprintf(doc, 4096,
                     "{\"tessera\":1,\"camera\":{\"from\":[%.17g,%.17g,%.17g],\"to\":[%.17g,%.17g,%.17g],"
                     "\"fov\":39.3077},\"film\":{\"width\":64,\"height\":64,\"filter\":{\"type\":\"box\"}},"
                     "\"sampler\":{\"spp\":4},\"integrator\":{\"type\":\"ao\",\"max_distance\":%.17g},"
                     "\"materials\":{\"black\":{\"type\":\"diffuse\"},\"white\":{\"type\":\"diffuse\"},"
                     "\"red\":{\"type\":\"diffuse\"},\"green\":{\"type\":\"diffuse\"}},",
                     278 * scale + shift, 273 * scale + shift, -800 * scale + shift, 278 * scale + shift,
                     273 * scale + shift, shift, 150 * scale);
    /* Copy the shapes array, inserting the transform after every "material": "...". */
    const char *end = strstr(shapes, "\"lights\"");
    assert_non_null(end);
    for (const char *p = shapes; p < end; p++) {
        doc[n++] = *p;
        if (strncmp(p, "\"material\": \"", 13) == 0) {
            const char *q = strchr(p + 13, '"');
            size_t k = (size_t)(q - p);
            memcpy(doc + n, p + 1, k);
            n += (int)k;
            p = q;
            n += sprintf(doc + n, ", \"transform\": %s", transform);
        }
    }
    n += sprintf(doc + n, "\"lights\": []}");
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text(doc, (size_t)n, NULL, "t", NULL, &s, &err);
    if (st) fail_msg("%s", err.message);
    free(doc);
    uint32_t one[] = {4};
    ts_film *f = render(s, 2, one, 1);
    ts_scene_destroy(s);
    return f;
}

static void test_translated_and_scaled_scenes_render_alike(void **state)
{
    (void)state;
    ts_film *ref = render_transformed("[]", 1, 0);
    struct { const char *t; double scale, shift; } cases[] = {
        {"[{\"translate\":[100000,100000,100000]}]", 1, 1e5},
        {"[{\"scale\":0.001}]", 1e-3, 0},
        {"[{\"scale\":1000}]", 1e3, 0},
    };
    double ref_mean = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) ref_mean += ts_film_pixel_rgb(ref, x, y).r / 4096.0;
    if (!(ref_mean > 0.3)) fail_msg("mean AO at the origin %.4f: the test scene is too dark to mean much", ref_mean);
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        ts_film *f = render_transformed(cases[c].t, cases[c].scale, cases[c].shift);
        double diff = 0, mean = 0;
        int differing = 0;
        for (int y = 0; y < 64; y++)
            for (int x = 0; x < 64; x++) {
                double a = ts_film_pixel_rgb(ref, x, y).r, b = ts_film_pixel_rgb(f, x, y).r;
                diff += fabs(a - b) / 4096.0;
                mean += b / 4096.0;
                differing += a != b;
            }
        /* The same random numbers drive both renders; allow rare flips: the mean absolute
         * difference below 1% of the mean (one flipped sample in 25 pixels of 4 spp would
         * be 1%), and the means within 0.5%. Self-intersection would cost tens of percent. */
        if (!(diff < 0.01 * ref_mean) || !(fabs(mean - ref_mean) < 0.005 * ref_mean))
            fail_msg("case %zu: mean %.6f vs %.6f at the origin, mean |difference| %.6f, %d pixels differ", c, mean,
                     ref_mean, diff, differing);
        print_message("case %zu: mean %.6f (origin %.6f), mean |difference| %.2e, %d of 4096 pixels differ\n", c, mean,
                      ref_mean, diff, differing);
        ts_film_destroy(f);
    }
    ts_film_destroy(ref);
}

/* Pixel (x, y) is the raster square [x, x+1) × [y, y+1), raster y downwards
 * (docs/design.md §4): an orthographic camera whose 8 × 8 film spans 8 × 8 scene units
 * looks at an emitting rectangle covering raster [0, 2.75) × [0, 5.5). With the box filter of radius
 * 0.5 each pixel is the covered fraction of its square, and 64 Sobol samples — a
 * (0,6,2)-net — hit a strip of a quarter or a half of the square exactly that often: 1,
 * 0.75, 0 across and 1, 0.5, 0 down, to 1/64 (a sample exactly on an edge). A sample put
 * in the wrong pixel, or a filter offset by a pixel, moves the edges by whole pixels. */
static void test_pixels_are_registered(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,5],\"to\":[0,0,0],\"up\":[0,1,0],"
        "\"height\":8},\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\",\"radius\":0.5}},"
        "\"integrator\":{\"type\":\"path\",\"max_depth\":0},\"materials\":{\"k\":{\"type\":\"diffuse\",\"reflectance\":0}},"
        "\"shapes\":[{\"type\":\"mesh\",\"material\":\"k\",\"emission\":1,"
        "\"positions\":[-4,-1.5,0, -1.25,-1.5,0, -1.25,4,0, -4,4,0],\"indices\":[0,1,2, 0,2,3]}]}";
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "registration", NULL, &s, &err)) fail_msg("%s", err.message);
    ts_film *f = ts_film_create(8, 8, 0, 0, 8, 8, &err);
    assert_non_null(f);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, 64, 2, NULL, NULL, NULL};
    assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    const double cx[8] = {1, 1, 0.75, 0, 0, 0, 0, 0}, cy[8] = {1, 1, 1, 1, 1, 0.5, 0, 0};
    for (int y = 0; y < 8; y++)
        for (int x = 0; x < 8; x++) {
            double v = ts_film_pixel_rgb(f, x, y).g, want = cx[x] * cy[y];
            if (!(fabs(v - want) <= 1.0 / 64 + 1e-6))
                fail_msg("pixel (%d, %d) is %.4f, expected %.4f (the covered fraction of its square)", x, y, v, want);
        }
    ts_film_destroy(f);
    ts_scene_destroy(s);
}

/* A sky of radiance 1e38 behind a black sphere: a pixel that sees both holds samples 0 and
 * 1e38, whose variance (≈ 1e76) no float holds — it was written as Inf into R.var with no
 * non-finite sample counted. Samples beyond TS_FILM_SAMPLE_MAX are now dropped and counted,
 * so every value of the image is finite; a sky of 1e18 (under the bound) is kept whole. */
static void test_huge_radiance_keeps_the_variance_finite(void **state)
{
    (void)state;
    static const char *const radiance[] = {"1e38", "1e18"};
    for (int k = 0; k < 2; k++) {
        char doc[1024];
        snprintf(doc, sizeof doc,
                 "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0],\"fov\":30},"
                 "\"film\":{\"width\":16,\"height\":16},\"sampler\":{\"spp\":8},\"integrator\":{\"type\":\"path\"},"
                 "\"materials\":{\"k\":{\"type\":\"diffuse\",\"reflectance\":0}},"
                 "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"k\"}],"
                 "\"lights\":[{\"type\":\"infinite\",\"radiance\":%s}]}",
                 radiance[k]);
        ts_scene *s = NULL;
        ts_error err = {0};
        if (ts_scene_load_text(doc, strlen(doc), NULL, "huge", NULL, &s, &err)) fail_msg("%s", err.message);
        ts_film *f = ts_film_create(16, 16, 0, 0, 16, 16, &err);
        assert_non_null(f);
        ts_render_stats stats = {0};
        ts_render_request req = {s, s->integrator.type, f, 0, 8, 2, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
        ts_image img;
        assert_int_equal(ts_film_to_image(f, TS_FILM_IMAGE_STATS, &img, &err), TS_OK);
        int n_inf = 0;
        for (int i = 0; i < img.width * img.height * img.n_channels; i++) n_inf += !isfinite(img.data[i]);
        printf("sky %s: %d non-finite image values, %llu of %llu samples dropped\n", radiance[k], n_inf,
               (unsigned long long)stats.counters.nonfinite, (unsigned long long)stats.counters.samples);
        assert_int_equal(n_inf, 0);
        /* 1e38: every sample that sees the sky is dropped (1118 of the 16×16×8: the sphere
         * covers the middle); 1e18: none. Deterministic (fixed seed), so no false failures. */
        if (k == 0) assert_true(stats.counters.nonfinite > stats.counters.samples / 2);
        else assert_int_equal(stats.counters.nonfinite, 0);
        ts_image_fini(&img);
        ts_film_destroy(f);
        ts_scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_count_and_passes_do_not_change_pixels),
        cmocka_unit_test(test_translated_and_scaled_scenes_render_alike),
        cmocka_unit_test(test_pixels_are_registered),
        cmocka_unit_test(test_huge_radiance_keeps_the_variance_finite),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
