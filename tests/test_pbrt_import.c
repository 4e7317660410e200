/* test_pbrt_import.c — the pbrt-v3 front end's mapping (renderer/scene/pbrt_import.h,
 * scene_load.h, spectrum.h): small pbrt-v3 scenes written inline, each mapping checked
 * against pbrt-v3's definitions in closed form — camera rays against pbrt-v3's
 * raster → screen → camera chain, filters against their formulas, spectra against the
 * CIE's normalisation — or against the JSON v1 document it is equivalent to; and the
 * error sentences, exactly. */
// clang-format off
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>
// clang-format on

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_load.h"
#include "scene/spectrum.h"

typedef struct warnings {
    int n;
    char last[TS_ERROR_MAX + 64];
} warnings;

static void on_warning(void *ctx, const char *msg)
{
    warnings *w = ctx;
    w->n++;
    snprintf(w->last, sizeof w->last, "%s", msg);
}

static ts_scene *load(const char *text, warnings *w)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, w, &s, &err);
    if (st) fprintf(stderr, "load failed: %s\n", err.message);
    assert_int_equal(st, TS_OK);
    return s;
}

static void expect_error(const char *text, const char *sentence)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    warnings w = {0};
    ts_status st =
        ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, &w, &s, &err);
    assert_int_not_equal(st, TS_OK);
    assert_null(s);
    if (strcmp(err.message, sentence) != 0)
        fprintf(stderr, "got:      %s\nexpected: %s\n", err.message, sentence);
    assert_string_equal(err.message, sentence);
}

/* The direction of the camera ray through raster point (x, y), lens at its centre. */
static ts_vec3 ray_dir(const ts_scene *s, float x, float y)
{
    return ts_camera_ray(&s->camera, (ts_vec2){x, y}, (ts_vec2){0.5f, 0.5f}).d;
}

static void assert_vec_near(ts_vec3 a, double x, double y, double z, double tol)
{
    if (fabs(a.x - x) > tol || fabs(a.y - y) > tol || fabs(a.z - z) > tol)
        fprintf(stderr, "got (%.7f %.7f %.7f), expected (%.7f %.7f %.7f)\n", a.x, a.y, a.z, x, y, z);
    assert_true(fabs(a.x - x) <= tol && fabs(a.y - y) <= tol && fabs(a.z - z) <= tol);
}

#define WORLD "WorldBegin\nLightSource \"point\" \"point from\" [0 0 -1]\nShape \"sphere\"\nWorldEnd\n"

/* pbrt-v3: raster (0, 0) is screen (pMin.x, pMax.y); the screen window of a 2:1 film is
 * [-2, 2] × [-1, 1] in units of tan(fov/2); camera +x is image right, +y up, +z forward,
 * and LookAt's camera-to-world columns are (normalize(up × dir), dir × right, dir). */
static void camera_lookat_orientation(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 90\n"
                       "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
                       &w);
    double k = 1 / sqrt(6.0);
    assert_vec_near(ray_dir(s, 0, 0), -2 * k, k, k, 2e-6);   /* top left: −x, +y */
    assert_vec_near(ray_dir(s, 64, 32), 2 * k, -k, k, 2e-6); /* bottom right */
    assert_vec_near(ray_dir(s, 32, 16), 0, 0, 1, 2e-6);
    ts_scene_destroy(s);

    /* A mirroring transform before LookAt (as exporters write) turns the image around x. */
    s = load("Scale -1 1 1\nLookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 90\n"
             "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
             &w);
    assert_vec_near(ray_dir(s, 0, 0), 2 * k, k, k, 2e-6);
    ts_scene_destroy(s);
}

/* screenwindow and frameaspectratio replace the window; fov is along the shorter axis. */
static void camera_screen_window(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [-1 1 -1 1]\n"
                       "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
                       &w);
    double k = 1 / sqrt(3.0);
    assert_vec_near(ray_dir(s, 0, 0), -k, k, k, 2e-6);
    ts_scene_destroy(s);
    /* A portrait film: x spans [-1, 1], y [-2, 2] (fov along x). */
    s = load("Camera \"perspective\" \"float fov\" 90\n"
             "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 64\n" WORLD,
             &w);
    double q = 1 / sqrt(6.0);
    assert_vec_near(ray_dir(s, 0, 0), -q, 2 * q, q, 2e-6);
    ts_scene_destroy(s);
    /* An uneven window is off-centre. */
    s = load("Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [0 1 0 1]\n"
             "Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 32\n" WORLD,
             &w);
    assert_vec_near(ray_dir(s, 16, 16), 0.5 / sqrt(1.5), 0.5 / sqrt(1.5), 1 / sqrt(1.5),
                    2e-6); /* screen (0.5, 0.5) */
    ts_scene_destroy(s);
}

/* Orthographic: the window [-2, 2] × [-1, 1] in camera-space units, rays along +z. */
static void camera_orthographic(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\n"
                       "Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 32\n" WORLD,
                       &w);
    ts_ray r = ts_camera_ray(&s->camera, (ts_vec2){0, 0}, (ts_vec2){0.5f, 0.5f});
    assert_vec_near(r.o, -2, 1, -5, 2e-6);
    assert_vec_near(r.d, 0, 0, 1, 2e-6);
    ts_scene_destroy(s);
}

/* pbrt-v3's gaussian: f(x) = exp(−α x²) − exp(−α r²), α = 2, r = 2 by default. */
static void filter_gaussian(void **state)
{
    (void)state;
    warnings w = {0};
    ts_scene *s = load("PixelFilter \"gaussian\"\nFilm \"image\" \"integer xresolution\" 8 \"integer "
                       "yresolution\" 8\n" WORLD,
                       &w);
    assert_int_equal(s->filter.type, TS_FILTER_GAUSSIAN);
    assert_float_equal(s->filter.radius, 2, 0);
    double floor_v = exp(-8.0), integral = sqrt(TS_PI_D / 2) * erf(2 * sqrt(2.0)) - 4 * floor_v;
    double f1_0 = (1 - floor_v) / integral, f1_1 = (exp(-2.0) - floor_v) / integral;
    assert_float_equal(ts_filter_eval(&s->filter, (ts_vec2){0, 0}), f1_0 * f1_0, 1e-5 * f1_0 * f1_0);
    assert_float_equal(ts_filter_eval(&s->filter, (ts_vec2){1, 0}), f1_1 * f1_0, 1e-5 * f1_0 * f1_0);
    ts_scene_destroy(s);
    s = load("PixelFilter \"gaussian\" \"float alpha\" 0.5 \"float xwidth\" 3 \"float ywidth\" 3\n" WORLD,
             &w);
    floor_v = exp(-4.5);
    integral = sqrt(TS_PI_D / 0.5) * erf(3 * sqrt(0.5)) - 6 * floor_v;
    f1_0 = (1 - floor_v) / integral;
    assert_float_equal(s->filter.radius, 3, 0);
    assert_float_equal(ts_filter_eval(&s->filter, (ts_vec2){0, 0}), f1_0 * f1_0, 1e-5 * f1_0 * f1_0);
    ts_scene_destroy(s);
}

/* An equal-energy spectrum has x = y = z by the CIE's normalisation (∫x̄ = ∫ȳ = ∫z̄), so it
 * is the XYZ → sRGB matrix's row sums times pbrt-v3's Y of it, (830 − 360)/471 ∫ȳ/∫ȳ. */
static void spectrum_equal_energy(void **state)
{
    (void)state;
    float flat[4] = {300, 1, 900, 1};
    ts_rgb c = ts_spectrum_to_rgb(flat, 2);
    double y = 470.0 / 471.0;
    /* The 1 nm sums of x̄, z̄ differ from ȳ's by under 0.1 %. */
    assert_float_equal(c.r, 1.204794 * y, 2e-3);
    assert_float_equal(c.g, 0.948291 * y, 2e-3);
    assert_float_equal(c.b, 0.908916 * y, 2e-3);
    /* Unsorted pairs are sorted first. */
    float a[6] = {400, 0.2f, 500, 0.5f, 600, 0.9f}, b[6] = {600, 0.9f, 400, 0.2f, 500, 0.5f};
    ts_rgb ca = ts_spectrum_to_rgb(a, 3), cb = ts_spectrum_to_rgb(b, 3);
    assert_true(ca.r == cb.r && ca.g == cb.g && ca.b == cb.b);
}

static void error_sentences(void **state)
{
    (void)state;
    expect_error("WorldBegin\nShape \"sphere\" \"float radius\" [1 2]\nWorldEnd\n",
                 "t.pbrt:2:16: Shape \"sphere\": \"float radius\" expects 1 value, got 2");
    expect_error(
        "WorldBegin\nShape \"hyperboloid\"\nWorldEnd\n",
        "t.pbrt:2:1: Shape \"hyperboloid\" is not supported (sphere, disk, cylinder, trianglemesh and "
        "plymesh are)");
    expect_error("Camera \"environment\"\nWorldBegin\nWorldEnd\n",
                 "t.pbrt:1:1: Camera \"environment\" is not supported (perspective and orthographic are)");
    expect_error("WorldBegin\nMaterial \"disney\"\nShape \"sphere\"\nWorldEnd\n",
                 "t.pbrt:2:1: Material \"disney\" is not supported (the Disney BSDF is not implemented)");
    expect_error(
        "WorldBegin\nShape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n"
        "WorldEnd\n",
        "t.pbrt:2:52: Shape \"trianglemesh\": \"integer indices\" value 2 is 3, not a vertex index in [0, "
        "2]");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(camera_lookat_orientation), cmocka_unit_test(camera_screen_window),
        cmocka_unit_test(camera_orthographic),       cmocka_unit_test(filter_gaussian),
        cmocka_unit_test(spectrum_equal_energy),     cmocka_unit_test(error_sentences),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
