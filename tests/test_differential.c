/* test_differential.c — ray differentials (renderer/integrators/differential.h): the
 * camera's offset rays and their footprint on a plane against finite differences of the
 * camera, pbrt-v3's SpecularReflect rule against the exact mirror image of the offset ray
 * (which it equals for a flat mirror), its SpecularTransmit rule against Snell's law
 * applied to the offset ray (equal to first order), and a grazing checkerboard rendered
 * with its footprint against the box-filtered checkerboard of each pixel, bit-identical
 * across thread counts.
 *
 * No check here is statistical: the closed-form checkerboard at one sample a pixel is a
 * deterministic function of the footprint, and the reference is a deterministic quadrature,
 * so every tolerance is a bound on rounding, on a linearisation or on a quadrature's error,
 * derived where it is used. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
// clang-format off
#include <cmocka.h>
// clang-format on

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "geometry/accel.h"
#include "integrators/differential.h"
#include "render/render.h"
#include "scene/scene.h"
#include "json/scene_json.h"

static void near3(ts_vec3 got, ts_vec3 want, float tol, const char *what)
{
    if (!(fabsf(got.x - want.x) <= tol && fabsf(got.y - want.y) <= tol && fabsf(got.z - want.z) <= tol))
        fail_msg("%s: (%.9g, %.9g, %.9g), want (%.9g, %.9g, %.9g)", what, got.x, got.y, got.z, want.x, want.y,
                 want.z);
}

/* The hit of ray (o, d) on the plane z = 0, parameterised u = x, v = y. */
static ts_interaction plane_hit(ts_vec3 o, ts_vec3 d)
{
    ts_interaction si = {0};
    float t = -o.z / d.z;
    si.p = ts_vec3_add(o, ts_vec3_scale(d, t));
    si.n = si.ns = (ts_vec3){0, 0, 1};
    si.dpdu = (ts_vec3){1, 0, 0};
    si.dpdv = (ts_vec3){0, 1, 0};
    si.uv = (ts_vec2){si.p.x, si.p.y};
    si.wo = ts_vec3_normalize(ts_vec3_neg(d));
    si.t = t;
    return si;
}

static ts_vec3 plane_point(ts_vec3 o, ts_vec3 d) { return ts_vec3_add(o, ts_vec3_scale(d, -o.z / d.z)); }

/* The footprint of a camera ray's differential on a plane: the offset rays are the rays
 * one pixel over with their directions moved towards the main ray's by the scale (pbrt-v3's
 * ScaleDifferentials), so dpdx is where such a ray meets the plane, less p (to rounding,
 * 1e-5 relative), and, since moving unit directions is not moving raster points, within a
 * second-order term of the scaled finite difference of the camera's hits one pixel over
 * (measured 0.8 % here, the ray at 53° from the plane's normal; bound 3 %; a wrong scale,
 * 1 or 1/4, misses by 50 % or more). */
static void test_camera_footprint(void **state)
{
    (void)state;
    ts_camera cam;
    ts_camera_desc d = {TS_CAMERA_PERSPECTIVE, {0.3f, -2, 1.5f}, {0, 0, 0}, {0, 0, 1}, 40, 1, 0, 1};
    ts_error err = {0};
    assert_int_equal(ts_camera_init(&cam, &d, 64, 48, &err), TS_OK);
    ts_vec2 p = {20.3f, 30.7f}, u = {0, 0};
    ts_ray ray = ts_camera_ray(&cam, p, u);
    ts_ray_differential rd;
    ts_ray_differential_camera(&cam, p, u, &ray, 0.5f, &rd);
    assert_true(rd.has);
    ts_interaction si = plane_hit(ray.o, ray.d);
    ts_texture_context c;
    ts_ray_differential_context(&si, &rd, &c);
    ts_ray rx = ts_camera_ray(&cam, (ts_vec2){p.x + 1, p.y}, u),
           ry = ts_camera_ray(&cam, (ts_vec2){p.x, p.y + 1}, u);
    ts_vec3 fx = ts_vec3_scale(ts_vec3_sub(plane_point(rx.o, rx.d), si.p), 0.5f);
    ts_vec3 fy = ts_vec3_scale(ts_vec3_sub(plane_point(ry.o, ry.d), si.p), 0.5f);
    ts_vec3 hx = ts_vec3_sub(
        plane_point(ray.o, ts_vec3_add(ray.d, ts_vec3_scale(ts_vec3_sub(rx.d, ray.d), 0.5f))), si.p);
    ts_vec3 hy = ts_vec3_sub(
        plane_point(ray.o, ts_vec3_add(ray.d, ts_vec3_scale(ts_vec3_sub(ry.d, ray.d), 0.5f))), si.p);
    near3(c.dpdx, hx, 1e-5f * ts_vec3_length(hx), "dpdx");
    near3(c.dpdy, hy, 1e-5f * ts_vec3_length(hy), "dpdy");
    near3(c.dpdx, fx, 0.03f * ts_vec3_length(fx), "dpdx against the camera");
    near3(c.dpdy, fy, 0.03f * ts_vec3_length(fy), "dpdy against the camera");
    assert_true(fabsf(c.dudx - c.dpdx.x) <= 1e-6f && fabsf(c.dvdy - c.dpdy.y) <= 1e-6f);
    /* Without a differential the context has no footprint. */
    ts_ray_differential_context(&si, NULL, &c);
    assert_true(c.dudx == 0 && c.dvdy == 0 && ts_vec3_length(c.dpdx) == 0);
}

/* A flat mirror: pbrt-v3's rule gives exactly the mirror image of the offset ray from
 * where the offset ray meets the mirror (∂n = 0, and the rule is then exact algebra, so
 * only rounding remains: 1e-6 on unit-sized values). */
static void test_mirror_rule(void **state)
{
    (void)state;
    ts_vec3 o = {0, -1, 1}, p = {0.1f, 0.2f, 0};
    ts_vec3 d = ts_vec3_normalize(ts_vec3_sub(p, o));
    ts_ray_differential rd = {true, ts_vec3_add(o, (ts_vec3){0.01f, 0, 0}),
                              ts_vec3_normalize(ts_vec3_add(d, (ts_vec3){0.003f, 0.002f, 0})),
                              ts_vec3_add(o, (ts_vec3){0, 0.01f, 0.005f}),
                              ts_vec3_normalize(ts_vec3_add(d, (ts_vec3){-0.001f, 0.004f, 0.001f}))};
    ts_interaction si = plane_hit(o, d);
    ts_texture_context c;
    ts_ray_differential_context(&si, &rd, &c);
    ts_vec3 n = si.ns, wi = ts_vec3_sub(ts_vec3_scale(n, 2 * ts_vec3_dot(si.wo, n)), si.wo);
    ts_ray_differential out;
    ts_ray_differential_reflect(&rd, &si, &c, wi, &out);
    assert_true(out.has);
    near3(out.rx_o, plane_point(rd.rx_o, rd.rx_d), 1e-6f, "rx origin");
    near3(out.ry_o, plane_point(rd.ry_o, rd.ry_d), 1e-6f, "ry origin");
    ts_vec3 mx = ts_vec3_sub(rd.rx_d, ts_vec3_scale(n, 2 * ts_vec3_dot(rd.rx_d, n)));
    ts_vec3 my = ts_vec3_sub(rd.ry_d, ts_vec3_scale(n, 2 * ts_vec3_dot(rd.ry_d, n)));
    near3(out.rx_d, mx, 1e-6f, "rx direction");
    near3(out.ry_d, my, 1e-6f, "ry direction");
}

/* A curved mirror (a sphere of radius 1, textured: differentials come with textures): pbrt-v3's rule with ∂n/∂x = ∂n/∂u·∂u/∂x + …
 * is the first-order expansion of reflecting the offset ray at its own hit, so it
 * matches that exact reflection to second order in the offset (|Δp| ≈ 0.02 here: error
 * ≲ |Δp|²/r ≈ 4e-4, bound 2e-3); with ∂n taken as 0 it misses by the first-order term,
 * 2·|Δn| ≈ 0.04, which the test also asserts. */
static void test_curved_mirror_rule(void **state)
{
    (void)state;
    const char *doc = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"film\":{\"width\":4,"
                      "\"height\":4},\"textures\":{\"t\":{\"type\":\"constant\",\"value\":0.9}},"
                      "\"materials\":{\"m\":{\"type\":\"mirror\",\"reflectance\":\"t\"}},\"shapes\":[{\"type\":"
                      "\"sphere\",\"radius\":1,\"material\":\"m\"}]}";
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "mirror", NULL, &s, &err)) fail_msg("%s", err.message);
    ts_vec3 o = {0.3f, -0.2f, 4};
    ts_vec3 d = ts_vec3_normalize(ts_vec3_sub((ts_vec3){0.2f, 0.1f, 0}, o));
    ts_ray_differential rd = {true, ts_vec3_add(o, (ts_vec3){0.01f, 0, 0}),
                              ts_vec3_normalize(ts_vec3_add(d, (ts_vec3){0.003f, 0.002f, 0})),
                              ts_vec3_add(o, (ts_vec3){0, 0.01f, 0.005f}),
                              ts_vec3_normalize(ts_vec3_add(d, (ts_vec3){-0.001f, 0.004f, 0.001f}))};
    ts_ray ray = ts_ray_make(o, d, INFINITY);
    ts_interaction si;
    assert_true(ts_accel_intersect(s->accel, &ray, &si));
    ts_texture_context c;
    ts_ray_differential_context(&si, &rd, &c);
    ts_vec3 n = si.ns, wi = ts_vec3_sub(ts_vec3_scale(n, 2 * ts_vec3_dot(si.wo, n)), si.wo);
    ts_ray_differential out;
    ts_ray_differential_reflect(&rd, &si, &c, wi, &out);
    ts_interaction flat = si;
    flat.dndu = flat.dndv = (ts_vec3){0, 0, 0};
    ts_ray_differential out0;
    ts_ray_differential_reflect(&rd, &flat, &c, wi, &out0);
    const ts_vec3 od[2][2] = {{rd.rx_o, rd.rx_d}, {rd.ry_o, rd.ry_d}};
    const ts_vec3 got[2] = {out.rx_d, out.ry_d}, got0[2] = {out0.rx_d, out0.ry_d};
    for (int k = 0; k < 2; k++) {
        ts_ray r = ts_ray_make(od[k][0], od[k][1], INFINITY);
        ts_interaction sk;
        assert_true(ts_accel_intersect(s->accel, &r, &sk));
        ts_vec3 dk = ts_vec3_normalize(od[k][1]);
        ts_vec3 exact = ts_vec3_sub(dk, ts_vec3_scale(sk.n, 2 * ts_vec3_dot(dk, sk.n)));
        float e = ts_vec3_length(ts_vec3_sub(ts_vec3_normalize(got[k]), exact));
        float e0 = ts_vec3_length(ts_vec3_sub(ts_vec3_normalize(got0[k]), exact));
        printf("curved mirror, offset ray %d: %.2g off the exact reflection (%.2g with dn/du taken as 0)\n", k, e, e0);
        if (!(e < 2e-3f && e0 > 0.02f))
            fail_msg("offset ray %d: off the exact reflection by %g with dn/du, %g without", k, e, e0);
    }
    ts_scene_destroy(s);
}

/* Snell's law for incident direction d (unit) through the plane z = 0 with relative index
 * eta_rel (wo's side over wi's side). */
static ts_vec3 refract(ts_vec3 d, float eta_rel)
{
    ts_vec3 n = d.z < 0 ? (ts_vec3){0, 0, 1} : (ts_vec3){0, 0, -1}; /* towards the incident side */
    ts_vec3 wo = ts_vec3_neg(d);
    float cos_i = ts_vec3_dot(wo, n), sin2_t = eta_rel * eta_rel * (1 - cos_i * cos_i);
    float cos_t = sqrtf(1 - sin2_t);
    return ts_vec3_add(ts_vec3_scale(wo, -eta_rel), ts_vec3_scale(n, eta_rel * cos_i - cos_t));
}

/* A flat interface of η = 1.5, entered from above and left from below: the rule is the
 * first-order expansion of Snell's law, so it matches the refracted offset ray to second
 * order in the offset (|Δd| ≈ 4e-3: error ≲ 1e-4, while the offset itself changes the
 * direction by ≳ 1e-3, which the test also asserts, so it cannot pass by ignoring it). */
static void test_transmit_rule(void **state)
{
    (void)state;
    for (int side = 0; side < 2; side++) {
        ts_vec3 o = side == 0 ? (ts_vec3){0, -1, 1} : (ts_vec3){0, -0.4f, -1};
        ts_vec3 p = {0.1f, 0.2f, 0}, d = ts_vec3_normalize(ts_vec3_sub(p, o));
        float eta_rel = side == 0 ? 1 / 1.5f : 1.5f;
        ts_ray_differential rd = {true, ts_vec3_add(o, (ts_vec3){0.01f, 0, 0}),
                                  ts_vec3_normalize(ts_vec3_add(d, (ts_vec3){0.003f, 0.002f, 0})),
                                  ts_vec3_add(o, (ts_vec3){0, 0.01f, 0}),
                                  ts_vec3_normalize(ts_vec3_add(d, (ts_vec3){-0.001f, 0.004f, 0}))};
        ts_interaction si = plane_hit(o, d);
        ts_texture_context c;
        ts_ray_differential_context(&si, &rd, &c);
        ts_vec3 wi = refract(d, eta_rel);
        ts_ray_differential out;
        ts_ray_differential_transmit(&rd, &si, &c, wi, 1.5f, &out);
        near3(out.rx_o, plane_point(rd.rx_o, rd.rx_d), 1e-6f, "rx origin");
        ts_vec3 ex = refract(rd.rx_d, eta_rel), ey = refract(rd.ry_d, eta_rel);
        near3(ts_vec3_normalize(out.rx_d), ex, 1e-4f, side ? "rx direction (leaving)" : "rx direction");
        near3(ts_vec3_normalize(out.ry_d), ey, 1e-4f, side ? "ry direction (leaving)" : "ry direction");
        assert_true(ts_vec3_length(ts_vec3_sub(ex, wi)) > 1e-3f);
    }
}

/* A checkerboard seen at 10° above its plane through an orthographic camera, one sample a
 * pixel. Each pixel's footprint spans ≈ 0.75 checks across and ≈ 4.3 checks along the
 * view, so the closed-form checkerboard (aamode closedform, the default) returns pbrt-v3's
 * ½(tex1 + tex2) there, while a point sample would return tex1 or tex2: an aliased image.
 * The reference is the box-filtered checkerboard of each pixel (the pixel filter is a box
 * of one pixel), integrated by a 64 × 64 midpoint rule through the same camera: it differs
 * from ½ by the part of a check the pixel's 4.3 checks along the view leave unbalanced, at
 * most about ½·(1/4.3)·(tex1 − tex2) ≈ 0.09 here; the bound is 0.15 (aliased pixels miss by
 * 0.35 or more). Threads 1 and 2 give the same bits. */
static void test_grazing_checkerboard(void **state)
{
    (void)state;
    const float e = 10.0f * (float)M_PI / 180;
    char doc[2048];
    snprintf(
        doc, sizeof doc,
        "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,%.9g,%.9g],\"to\":[0,0,0],"
        "\"up\":[0,0,1],\"height\":0.3},\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\"}},"
        "\"sampler\":{\"spp\":1},\"integrator\":{\"type\":\"direct\"},"
        "\"lights\":[{\"type\":\"distant\",\"from\":[0,0,1],\"to\":[0,0,0],\"irradiance\":3.14159265358979}],"
        "\"textures\":{\"c\":{\"type\":\"checkerboard\",\"mapping\":{\"uscale\":40,\"vscale\":40},"
        "\"tex1\":0.9,\"tex2\":0.1}},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"c\"}},"
        "\"shapes\":[{\"type\":\"mesh\",\"positions\":[-1,-1,0,1,-1,0,1,1,0,-1,1,0],\"indices\":[0,1,2,0,2,3]"
        ","
        "\"uvs\":[0,0,1,0,1,1,0,1],\"material\":\"m\"}]}",
        -5 * cos(e), 5 * sin(e));
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    assert_true(s->textured);
    ts_film *f[2];
    for (int k = 0; k < 2; k++) {
        f[k] = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
        ts_render_stats stats = {0};
        ts_render_request req = {s, s->integrator.type, f[k], 0, 1, k + 1, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    }
    double worst = 0;
    for (int y = 0; y < 8; y++)
        for (int x = 0; x < 8; x++) {
            ts_rgb a = ts_film_pixel_rgb(f[0], x, y), b = ts_film_pixel_rgb(f[1], x, y);
            assert_memory_equal(&a, &b, sizeof a);
            double ref = 0;
            const int n = 64;
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    ts_ray r = ts_camera_ray(&s->camera, (ts_vec2){x + (i + 0.5f) / n, y + (j + 0.5f) / n},
                                             (ts_vec2){0, 0});
                    ts_vec3 q = plane_point(r.o, r.d);
                    double su = floor(40 * (q.x + 1) / 2), tv = floor(40 * (q.y + 1) / 2);
                    ref += fmod(su + tv, 2) != 0 ? 0.1 : 0.9;
                }
            ref /= n * n;
            double dev = fabs(a.g - ref);
            if (dev > worst) worst = dev;
            if (dev > 0.15) fail_msg("pixel (%d, %d): %g, box-filtered %g", x, y, a.g, ref);
        }
    print_message("grazing checkerboard: worst pixel %.3f from its box-filtered value\n", worst);
    ts_film_destroy(f[0]);
    ts_film_destroy(f[1]);
    ts_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_footprint),
        cmocka_unit_test(test_mirror_rule),
        cmocka_unit_test(test_curved_mirror_rule),
        cmocka_unit_test(test_transmit_rule),
        cmocka_unit_test(test_grazing_checkerboard),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
