/* test_camera.c — primary rays against the geometry docs/design.md §4 gives the camera:
 * `fov` the full angle along the shorter image axis, raster (0,0) the top-left corner with
 * y down, right = forward × up; the orthographic window `height` scene units tall; the thin
 * lens focused on the plane at focus_distance along forward. Exact up to float rounding
 * (relative 1e-5 on angles and positions). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
/* cmocka needs the three above first */
#include <cmocka.h>

#include <math.h>

#include "camera/camera.h"

static void assert_near(double a, double b, double tol, const char *what)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%s: %.9g, expected %.9g", what, a, b);
}

static ts_camera make(ts_camera_type type, float fov, float ortho_h, float lens, float focus, int w, int h)
{
    ts_camera_desc d = {type, {0, 0, 0}, {0, 0, -1}, {0, 1, 0}, fov, ortho_h, lens, focus};
    ts_camera cam;
    ts_error err = {0};
    if (ts_camera_init(&cam, &d, w, h, &err) != TS_OK) fail_msg("camera: %s", err.message);
    return cam;
}

/* Angle between a ray direction and the view axis (−z). */
static double off_axis_deg(ts_vec3 d)
{
    return acos(-d.z / sqrt(d.x * d.x + d.y * d.y + d.z * d.z)) * 180 / M_PI;
}

static void test_perspective_fov(void **state)
{
    (void)state;
    const ts_vec2 lens = {0.5f, 0.5f};
    /* Landscape 200 × 100: the fov spans the height; the width sees atan(2 tan(fov/2)). */
    ts_camera c = make(TS_CAMERA_PERSPECTIVE, 40, 0, 0, 1, 200, 100);
    ts_ray top = ts_camera_ray(&c, (ts_vec2){100, 0}, lens),
           right = ts_camera_ray(&c, (ts_vec2){200, 50}, lens);
    assert_near(off_axis_deg(top.d), 20, 1e-4, "half the fov at the top edge");
    assert_true(top.d.y > 0 && fabsf(top.d.x) < 1e-6f); /* raster y = 0 is the top */
    assert_near(off_axis_deg(right.d), atan(2 * tan(20 * M_PI / 180)) * 180 / M_PI, 1e-4, "the wider axis");
    assert_true(right.d.x > 0); /* right = forward × up = +x for forward −z, up +y */
    ts_ray centre = ts_camera_ray(&c, (ts_vec2){100, 50}, lens);
    assert_near(off_axis_deg(centre.d), 0, 1e-3, "centre on the axis");
    /* Portrait 100 × 300: now the fov spans the width. */
    c = make(TS_CAMERA_PERSPECTIVE, 60, 0, 0, 1, 100, 300);
    ts_ray left = ts_camera_ray(&c, (ts_vec2){0, 150}, lens),
           bottom = ts_camera_ray(&c, (ts_vec2){50, 300}, lens);
    assert_near(off_axis_deg(left.d), 30, 1e-4, "half the fov at the left edge");
    assert_true(left.d.x < 0);
    assert_near(off_axis_deg(bottom.d), atan(3 * tan(30 * M_PI / 180)) * 180 / M_PI, 1e-4, "the taller axis");
    assert_true(bottom.d.y < 0);
}

static void test_orthographic_window(void **state)
{
    (void)state;
    ts_camera c = make(TS_CAMERA_ORTHOGRAPHIC, 0, 3, 0, 1, 40, 20);
    ts_ray a = ts_camera_ray(&c, (ts_vec2){0, 0}, (ts_vec2){0.5f, 0.5f});
    ts_ray b = ts_camera_ray(&c, (ts_vec2){40, 20}, (ts_vec2){0.5f, 0.5f});
    assert_near(a.o.x, -3, 1e-6, "left edge at −height·aspect/2");
    assert_near(a.o.y, 1.5, 1e-6, "top edge at +height/2");
    assert_near(b.o.x, 3, 1e-6, "right edge");
    assert_near(b.o.y, -1.5, 1e-6, "bottom edge");
    assert_near(a.d.z, -1, 1e-7, "parallel rays along forward");
}

/* Every lens sample of one raster point reaches the same point of the focus plane. */
static void test_thin_lens_focus(void **state)
{
    (void)state;
    ts_camera c = make(TS_CAMERA_PERSPECTIVE, 50, 0, 0.3f, 4, 64, 64);
    ts_camera pin = make(TS_CAMERA_PERSPECTIVE, 50, 0, 0, 4, 64, 64);
    ts_vec2 p = {10.5f, 50.25f};
    ts_ray r0 = ts_camera_ray(&pin, p, (ts_vec2){0.5f, 0.5f});
    double t0 = 4 / -r0.d.z;
    ts_vec3 focus = ts_vec3_add(r0.o, ts_vec3_scale(r0.d, (float)t0));
    const ts_vec2 us[] = {{0.1f, 0.2f}, {0.9f, 0.4f}, {0.5f, 0.99f}, {0.02f, 0.7f}};
    for (int i = 0; i < 4; i++) {
        ts_ray r = ts_camera_ray(&c, p, us[i]);
        assert_true(r.o.x * r.o.x + r.o.y * r.o.y <= 0.3f * 0.3f * (1 + 1e-5f) && fabsf(r.o.z) < 1e-6f);
        double t = (r.o.z + 4) / -r.d.z;
        assert_near(r.o.x + t * r.d.x, focus.x, 1e-5, "focus x");
        assert_near(r.o.y + t * r.d.y, focus.y, 1e-5, "focus y");
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_perspective_fov),
        cmocka_unit_test(test_orthographic_window),
        cmocka_unit_test(test_thin_lens_focus),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
