/* test_light.c — lights (light.h): closed-form irradiance through Sample_Li, Sample_Li vs
 * Pdf_Li, light selection, power, edge cases.
 *
 * Irradiance E = ∫ L cosθ dω is estimated as the mean of L·max(0, n·wi)/pdf over a
 * jittered K×K grid of u (K = 512, fixed seed). Every integrand here is smooth in u (the
 * samplers are smooth maps of the square), so the stratified error is O(K^-2) to
 * O(K^-1.5) relative, ≤ 2e-5 measured; the 1e-3 bound of docs/design.md §8 is therefore
 * a bound on bias, not on noise. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "core/arena.h"
#include "core/hash.h"
#include "lights/envmap.h"
#include "lights/light.h"
#include "integrators/integrator.h"
#include "json/scene_json.h"
#include "sampling/sampling.h"

static void assert_rel(double a, double b, double rel, const char *what)
{
    if (!(fabs(a - b) <= rel * fabs(b))) fail_msg("%s: %.9g != %.9g (relative %g, off by %.2e)", what, a, b, rel, fabs(a - b) / fabs(b));
}

static ts_interaction ref_at(ts_vec3 p, ts_vec3 n)
{
    ts_interaction r = {0};
    r.p = p;
    r.n = ts_vec3_normalize(n);
    r.ns = r.n;
    r.shape = TS_NONE;
    return r;
}

static void prepare(ts_light *l, uint32_t n, const ts_shape *shapes)
{
    ts_error err = {0};
    ts_bounds3 b = {{-1, -1, -1}, {1, 1, 1}};
    if (ts_lights_prepare(l, n, shapes, b, &err)) fail_msg("%s", err.message);
}

/* Irradiance (green channel) at ref from lights[0..n), each sampled K² times. Also
 * checks every sample is finite and, where the light is not delta, that pdf_li agrees. */
static double irradiance(const ts_light *lights, uint32_t n, const ts_shape *shapes, const ts_interaction *ref, int k)
{
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 1234, 1);
    double total = 0;
    for (uint32_t li = 0; li < n; li++) {
        double sum = 0;
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++) {
                ts_vec2 u = {(i + ts_pcg32_float(&rng)) / k, (j + ts_pcg32_float(&rng)) / k};
                ts_light_sample s;
                if (!ts_light_sample_li(&lights[li], shapes, ref, u, &s)) {
                    assert_true(ts_rgb_is_black(s.L) && s.pdf == 0);
                    continue;
                }
                assert_true(ts_rgb_is_finite(s.L) && isfinite(s.pdf) && s.pdf > 0);
                assert_true(fabsf(ts_vec3_length(s.wi) - 1) < 1e-5f);
                double c = ts_vec3_dot(ref->n, s.wi);
                if (c > 0) sum += s.L.g * c / s.pdf;
            }
        total += sum / ((double)k * k);
    }
    return total;
}

static ts_shape sphere_shape(ts_vec3 c, double r)
{
    ts_shape s = {0};
    s.type = TS_SHAPE_SPHERE;
    s.sphere.radius = r;
    s.to_world = ts_xform_translate(ts_dvec3_from(c));
    s.emissive = true;
    return s;
}

static ts_light area_light(uint32_t shape, uint32_t prim, float L)
{
    ts_light l = {0};
    l.type = TS_LIGHT_AREA;
    l.color = ts_rgb_gray(L);
    l.shape = shape;
    l.prim = prim;
    l.to_world = ts_xform_identity();
    return l;
}

static void test_delta_lights(void **state)
{
    (void)state;
    ts_light l = {0};
    l.type = TS_LIGHT_POINT;
    l.position = (ts_vec3){1, 2, 3};
    l.color = ts_rgb_make(4, 5, 6);
    prepare(&l, 1, NULL);
    ts_interaction r = ref_at((ts_vec3){1, 2, 1}, (ts_vec3){0, 0, 1});
    assert_rel(irradiance(&l, 1, NULL, &r, 1), 5.0 / 4, 1e-6, "point I/d²");
    assert_true(ts_light_pdf_li(&l, NULL, &r, (ts_vec3){0, 0, 1}) == 0);

    /* Spot along −z from (0,0,2), cone 30°, delta 10°: falloff starts at 20°. */
    l.type = TS_LIGHT_SPOT;
    l.position = (ts_vec3){0, 0, 2};
    l.direction = (ts_vec3){0, 0, -1};
    l.cos_total = cosf(ts_radians(30));
    l.cos_falloff_start = cosf(ts_radians(20));
    prepare(&l, 1, NULL);
    double angles[3] = {10, 25, 35};
    for (int k = 0; k < 3; k++) {
        double a = angles[k] * TS_PI_D / 180;
        ts_vec3 p = {(float)(2 * tan(a)), 0, 0};
        ts_interaction rr = ref_at(p, ts_vec3_sub(l.position, p)); /* facing the light: cos = 1 */
        double d2 = 4 + p.x * (double)p.x, expect;
        double ct = cos(a);
        if (ct >= l.cos_falloff_start) expect = 5 / d2;
        else if (ct < l.cos_total) expect = 0;
        else {
            double delta = (ct - l.cos_total) / (l.cos_falloff_start - l.cos_total);
            expect = 5 / d2 * delta * delta * delta * delta;
        }
        double e = irradiance(&l, 1, NULL, &rr, 1);
        print_message("spot at %2.0f°: E = %.7g, expected %.7g\n", angles[k], e, expect);
        if (expect == 0) assert_true(e == 0);
        else assert_rel(e, expect, 1e-5, "spot");
    }
    /* Spot power: Φ = 2πI[(1 − cos δ_start) + (cos δ_start − cos δ_total)/5], checked
     * against ∫ I·falloff dω by a 10^6-point midpoint rule in cosθ (error < 1e-6). */
    double integral = 0;
    int nq = 1000000;
    for (int i = 0; i < nq; i++) {
        double c = -1 + (i + 0.5) * 2.0 / nq;
        double f = c >= l.cos_falloff_start ? 1 : (c < l.cos_total ? 0 : pow((c - l.cos_total) / (l.cos_falloff_start - l.cos_total), 4));
        integral += f * 2.0 / nq;
    }
    assert_rel(ts_light_power(&l, NULL).g, 2 * TS_PI_D * 5 * integral, 1e-4, "spot power");
    l.type = TS_LIGHT_POINT;
    assert_rel(ts_light_power(&l, NULL).g, 4 * TS_PI_D * 5, 1e-6, "point power");

    /* Distant: E cosθ, and the shadow-ray target lies outside the scene sphere. */
    l.type = TS_LIGHT_DISTANT;
    l.direction = ts_vec3_normalize((ts_vec3){1, 0, -1});
    prepare(&l, 1, NULL);
    r = ref_at((ts_vec3){0.5f, 0.2f, 0}, (ts_vec3){0, 0, 1});
    assert_rel(irradiance(&l, 1, NULL, &r, 1), 5 * cos(TS_PI_D / 4), 1e-6, "distant E cosθ");
    ts_light_sample s;
    assert_true(ts_light_sample_li(&l, NULL, &r, (ts_vec2){0.5f, 0.5f}, &s));
    assert_true(s.is_delta && s.is_infinite);
    assert_true(ts_vec3_distance(s.p_light, l.scene_center) > l.scene_radius);
    assert_rel(ts_light_power(&l, NULL).g, 5 * TS_PI_D * 3, 1e-6, "distant power π r² E"); /* r² = 3 */
}

static void test_area_irradiance(void **state)
{
    (void)state;
    const int k = 512;
    /* Sphere: E = πL (r/d)² for a receiver facing its centre. */
    ts_shape sph = sphere_shape((ts_vec3){0, 0, 0}, 0.5);
    ts_light l = area_light(0, 0, 2);
    prepare(&l, 1, &sph);
    ts_interaction r = ref_at((ts_vec3){0, 0, 3}, (ts_vec3){0, 0, -1});
    double e = irradiance(&l, 1, &sph, &r, k);
    print_message("sphere: E = %.9g, expected %.9g\n", e, TS_PI_D * 2 * 0.25 / 9);
    assert_rel(e, TS_PI_D * 2 * 0.25 / 9, 1e-3, "sphere πL(r/d)²");
    /* Tiny sphere r = 1e-4 at distance 1: E = π·1e-8·L, finite and non-zero. */
    ts_shape tiny = sphere_shape((ts_vec3){0, 0, 0}, 1e-4);
    prepare(&l, 1, &tiny);
    r = ref_at((ts_vec3){0, 0, 1}, (ts_vec3){0, 0, -1});
    e = irradiance(&l, 1, &tiny, &r, 64);
    print_message("tiny sphere: E = %.9g, expected %.9g\n", e, TS_PI_D * 1e-8 * 2);
    assert_rel(e, TS_PI_D * 1e-8 * 2, 1e-3, "tiny sphere");

    /* Disk of radius 0.7 on axis at height h = 1.3: E = πL r²/(r² + h²). */
    ts_shape dk = {0};
    dk.type = TS_SHAPE_DISK;
    dk.disk.radius = 0.7;
    dk.to_world = ts_xform_frame((ts_dvec3){0, 0, 0}, (ts_dvec3){0, 0, 1});
    prepare(&l, 1, &dk);
    r = ref_at((ts_vec3){0, 0, 1.3f}, (ts_vec3){0, 0, -1});
    e = irradiance(&l, 1, &dk, &r, k);
    double expect = TS_PI_D * 2 * 0.49 / (0.49 + 1.69);
    print_message("disk: E = %.9g, expected %.9g\n", e, expect);
    assert_rel(e, expect, 1e-3, "disk on axis");
    /* One-sided: from below, nothing. */
    r = ref_at((ts_vec3){0, 0, -1.3f}, (ts_vec3){0, 0, 1});
    assert_true(irradiance(&l, 1, &dk, &r, 8) == 0);

    /* Rectangle a × b at height c, receiver under a corner facing it: the point-to-
     * parallel-rectangle form factor F = 1/(2π)[A/√(1+A²)·atan(B/√(1+A²)) + B/√(1+B²)·
     * atan(A/√(1+B²))], A = a/c, B = b/c; E = πLF. Two triangles, two lights, facing −z. */
    static float quad[12] = {0, 0, 1, 1.5f, 0, 1, 1.5f, 0.8f, 1, 0, 0.8f, 1};
    static uint32_t qix[6] = {0, 2, 1, 0, 3, 2};
    ts_shape q = {0};
    q.type = TS_SHAPE_MESH;
    q.to_world = ts_xform_identity();
    q.mesh.n_vertices = 4;
    q.mesh.n_triangles = 2;
    q.mesh.p = quad;
    q.mesh.index = qix;
    double A = 1.5, B = 0.8;
    double F = (A / sqrt(1 + A * A) * atan(B / sqrt(1 + A * A)) + B / sqrt(1 + B * B) * atan(A / sqrt(1 + B * B))) /
               (2 * TS_PI_D);
    ts_triangle_sampling modes[3] = {TS_TRIANGLE_SAMPLING_AREA, TS_TRIANGLE_SAMPLING_SPHERICAL, TS_TRIANGLE_SAMPLING_AUTO};
    const char *mn[3] = {"area", "spherical", "auto"};
    for (int m = 0; m < 3; m++) {
        ts_light ql[2] = {area_light(0, 0, 2), area_light(0, 1, 2)};
        ql[0].triangle_sampling = ql[1].triangle_sampling = modes[m];
        prepare(ql, 2, &q);
        r = ref_at((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1});
        e = irradiance(ql, 2, &q, &r, k);
        print_message("rectangle (%s): E = %.9g, expected %.9g\n", mn[m], e, TS_PI_D * 2 * F);
        assert_rel(e, TS_PI_D * 2 * F, 1e-3, "rectangle form factor");
        /* Receiver in the rectangle's plane: exactly no light. */
        r = ref_at((ts_vec3){3, 0.4f, 1}, (ts_vec3){-1, 0, 0});
        assert_true(irradiance(ql, 2, &q, &r, 16) == 0);
    }
    /* The accuracy benchmark's switch: prepared as AUTO, then forced; same irradiance. */
    for (int m = 0; m < 2; m++) {
        ts_light ql[2] = {area_light(0, 0, 2), area_light(0, 1, 2)};
        prepare(ql, 2, &q);
        assert_int_equal(ts_lights_set_triangle_sampling(ql, 2, &q, modes[m]), 2);
        assert_int_equal(ql[0].triangle_sampling, modes[m]);
        assert_int_equal(ql[1].geom.triangle_mode, modes[m]);
        r = ref_at((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1});
        e = irradiance(ql, 2, &q, &r, k);
        assert_rel(e, TS_PI_D * 2 * F, 1e-3, "rectangle form factor, forced sampling");
    }

    /* Cylinder vs a finely tessellated mesh of it, the mesh's irradiance by Lambert's
     * exact polygon formula E = L/2 Σ_edges θ_e (n · û_e) over the triangles facing the
     * receiver. The tessellation (2048 segments) differs from the tube by O((π/2048)²)
     * ≈ 2e-6 relative. Tube: axis z, radius 0.5, z ∈ [−1, 1]; receiver at x = 2 facing
     * −x, so the whole tube is above its horizon. */
    ts_shape cy = {0};
    cy.type = TS_SHAPE_CYLINDER;
    cy.cylinder.radius = 0.5;
    cy.cylinder.height = 2;
    cy.to_world = ts_xform_translate((ts_dvec3){0, 0, -1});
    prepare(&l, 1, &cy);
    r = ref_at((ts_vec3){2, 0.3f, 0.2f}, (ts_vec3){-1, 0, 0});
    e = irradiance(&l, 1, &cy, &r, k);
    const int seg = 2048;
    double lambert = 0;
    ts_dvec3 rp = ts_dvec3_from(r.p), rn = ts_dvec3_from(r.n);
    for (int i = 0; i < seg; i++) {
        double a0 = 2 * TS_PI_D * i / seg, a1 = 2 * TS_PI_D * (i + 1) / seg;
        ts_dvec3 v[4] = {{0.5 * cos(a0), 0.5 * sin(a0), -1}, {0.5 * cos(a1), 0.5 * sin(a1), -1},
                         {0.5 * cos(a1), 0.5 * sin(a1), 1}, {0.5 * cos(a0), 0.5 * sin(a0), 1}};
        /* The quad (v0 v1 v2 v3) faces outwards (counter-clockwise seen from outside). */
        ts_dvec3 nq = ts_dvec3_cross(ts_dvec3_sub(v[1], v[0]), ts_dvec3_sub(v[3], v[0]));
        if (ts_dvec3_dot(nq, ts_dvec3_sub(rp, v[0])) <= 0) continue;
        ts_dvec3 phi = {0, 0, 0};
        for (int k2 = 0; k2 < 4; k2++) {
            ts_dvec3 a = ts_dvec3_normalize(ts_dvec3_sub(v[k2], rp)), b = ts_dvec3_normalize(ts_dvec3_sub(v[(k2 + 1) % 4], rp));
            double theta = acos(fmax(-1.0, fmin(1.0, ts_dvec3_dot(a, b))));
            phi = ts_dvec3_add(phi, ts_dvec3_scale(ts_dvec3_normalize(ts_dvec3_cross(a, b)), theta));
        }
        lambert += 0.5 * fabs(ts_dvec3_dot(phi, rn));
    }
    lambert *= 2;
    print_message("cylinder: E = %.9g, tessellated mesh (Lambert) %.9g\n", e, lambert);
    assert_rel(e, lambert, 1e-3, "cylinder vs mesh");
    /* Only triangle emitters are switched. */
    assert_int_equal(ts_lights_set_triangle_sampling(&l, 1, &cy, TS_TRIANGLE_SAMPLING_AREA), 0);
}

static void test_infinite(void **state)
{
    (void)state;
    /* Constant environment: E = πL for any receiver (uniform-sphere sampling). */
    ts_light l = {0};
    l.type = TS_LIGHT_INFINITE;
    l.color = ts_rgb_make(0.2f, 0.4f, 0.6f);
    l.to_world = ts_xform_identity();
    prepare(&l, 1, NULL);
    ts_interaction r = ref_at((ts_vec3){0, 0, 0}, (ts_vec3){0.3f, 1, 0.2f});
    double e = irradiance(&l, 1, NULL, &r, 1024);
    print_message("constant environment: E = %.9g, expected %.9g\n", e, TS_PI_D * 0.4);
    assert_rel(e, TS_PI_D * 0.4, 1e-3, "constant environment πL");
    assert_rel(ts_light_pdf_li(&l, NULL, &r, (ts_vec3){0, 1, 0}), 1 / (4 * TS_PI_D), 1e-6, "uniform pdf");
    ts_ray ray = ts_ray_make((ts_vec3){0, 0, 0}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_rel(ts_light_le(&l, &ray).g, 0.4, 1e-6, "Le constant");
    assert_rel(ts_light_power(&l, NULL).g, 4 * TS_PI_D * TS_PI_D * 3 * 0.4, 1e-5, "infinite power");

    /* A constant map with scale 2 under a rotation and a non-uniform scale: still E = πL·2
     * (the transform's solid-angle Jacobian is accounted for), and Sample_Li agrees with
     * Pdf_Li and Le. */
    ts_rgb tx[8 * 4];
    for (int i = 0; i < 32; i++) tx[i] = ts_rgb_gray(0.4f);
    ts_envmap *m = NULL;
    ts_error err = {0};
    assert_int_equal(ts_envmap_create(tx, 8, 4, &m, &err), TS_OK);
    l.map = m;
    l.color = ts_rgb_gray(2);
    ts_xform rot = ts_xform_rotate(-90, (ts_dvec3){1, 0, 0}), sc = ts_xform_scale((ts_dvec3){1, 3, 0.5});
    l.to_world = ts_xform_compose(&rot, &sc);
    prepare(&l, 1, NULL);
    e = irradiance(&l, 1, NULL, &r, 1024);
    print_message("constant map, scaled & rotated: E = %.9g, expected %.9g\n", e, TS_PI_D * 0.8);
    assert_rel(e, TS_PI_D * 0.8, 1e-3, "constant map πL");
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 77, 7);
    for (int i = 0; i < 20000; i++) {
        ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
        ts_light_sample s;
        if (!ts_light_sample_li(&l, NULL, &r, u, &s)) continue;
        float p = ts_light_pdf_li(&l, NULL, &r, s.wi);
        assert_rel(p, s.pdf, 1e-3, "infinite: Sample_Li pdf = Pdf_Li");
        ts_ray ry = ts_ray_make(r.p, s.wi, INFINITY);
        assert_rel(ts_light_le(&l, &ry).g, s.L.g, 1e-3, "infinite: Sample_Li L = Le");
        assert_true(s.is_infinite && !s.is_delta);
    }
    ts_envmap_destroy(m);
}

/* ts_light_le_pdf is ts_light_le and ts_light_pdf_li together, bit for bit: a varying
 * 64×32 map under a rotation and a non-uniform scale, 20 000 random directions, the poles
 * and the seam φ = 0; the map-less light too. Deterministic, exact. */
static void test_le_pdf(void **state)
{
    (void)state;
    ts_rgb tx[64 * 32];
    for (uint32_t i = 0; i < 64 * 32; i++)
        tx[i] = ts_rgb_make((ts_hash_u32(i) >> 8) * 0x1p-20f, (ts_hash_u32(i + 9999) >> 8) * 0x1p-24f, i % 7 ? 0.5f : 0);
    ts_envmap *m = NULL;
    ts_error err = {0};
    assert_int_equal(ts_envmap_create(tx, 64, 32, &m, &err), TS_OK);
    ts_light l = {0};
    l.type = TS_LIGHT_INFINITE;
    l.color = ts_rgb_make(2, 3, 4);
    ts_xform rot = ts_xform_rotate(-70, (ts_dvec3){1, 0.2, 0}), sc = ts_xform_scale((ts_dvec3){1, 3, 0.5});
    l.to_world = ts_xform_compose(&rot, &sc);
    ts_interaction r = ref_at((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1});
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 5, 11);
    for (int with_map = 0; with_map < 2; with_map++) {
        l.map = with_map ? m : NULL;
        prepare(&l, 1, NULL);
        for (int i = 0; i < 20003; i++) {
            ts_vec3 w = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            if (i == 20000) w = (ts_vec3){0, 0, 1};
            if (i == 20001) w = (ts_vec3){0, 0, -1};
            if (i == 20002) w = (ts_vec3){1, 0, 0};
            float pdf;
            ts_rgb L = ts_light_le_pdf(&l, w, &pdf);
            ts_ray ray = ts_ray_make(r.p, w, INFINITY);
            ts_rgb L_want = ts_light_le(&l, &ray);
            float pdf_want = ts_light_pdf_li(&l, NULL, &r, w);
            if (memcmp(&L, &L_want, sizeof L) != 0 || memcmp(&pdf, &pdf_want, sizeof pdf) != 0)
                fail_msg("direction %d (%a, %a, %a): L (%a, %a, %a) pdf %a, expected (%a, %a, %a) %a", i, (double)w.x,
                         (double)w.y, (double)w.z, (double)L.r, (double)L.g, (double)L.b, (double)pdf,
                         (double)L_want.r, (double)L_want.g, (double)L_want.b, (double)pdf_want);
        }
    }
    ts_envmap_destroy(m);
}

/* Sample_Li vs Pdf_Li for area lights of every shape (analytic first-hit check), and
 * Pdf_Li = 0 for directions that miss. */
static void test_sample_vs_pdf(void **state)
{
    (void)state;
    static float tp[9] = {-1, -1, 1, 1, -1, 1.2f, 0, 1, 0.8f};
    static uint32_t tix[3] = {0, 1, 2};
    ts_shape shapes[4] = {0};
    shapes[0] = sphere_shape((ts_vec3){0, 0, 0}, 0.6);
    shapes[1].type = TS_SHAPE_DISK;
    shapes[1].disk.radius = 1;
    shapes[1].disk.inner_radius = 0.3;
    shapes[1].to_world = ts_xform_frame((ts_dvec3){0, 0, 1.5}, (ts_dvec3){0.2, 0.1, -1});
    shapes[2].type = TS_SHAPE_CYLINDER;
    shapes[2].cylinder.radius = 0.3;
    shapes[2].cylinder.height = 1;
    shapes[2].to_world = ts_xform_frame((ts_dvec3){1.5, 0, -0.5}, (ts_dvec3){0, 0, 1});
    shapes[3].type = TS_SHAPE_MESH;
    shapes[3].to_world = ts_xform_identity();
    shapes[3].mesh.n_vertices = 3;
    shapes[3].mesh.n_triangles = 1;
    shapes[3].mesh.p = tp;
    shapes[3].mesh.index = tix;
    ts_light lights[4];
    for (int i = 0; i < 4; i++) {
        lights[i] = area_light((uint32_t)i, 0, 1);
        lights[i].two_sided = true;
    }
    prepare(lights, 4, shapes);
    ts_interaction refs[3] = {ref_at((ts_vec3){0.1f, -0.2f, 0.9f}, (ts_vec3){0, 0, 1}),
                              ref_at((ts_vec3){-1.5f, 0.5f, 0.2f}, (ts_vec3){1, 0, 0}),
                              ref_at((ts_vec3){0.2f, 0.1f, 0.3f}, (ts_vec3){0, 1, 0})};
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 9);
    for (int li = 0; li < 4; li++)
        for (int ri = 0; ri < 3; ri++) {
            int checked = 0;
            double worst = 0;
            for (int i = 0; i < 5000; i++) {
                ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
                ts_light_sample s;
                if (!ts_light_sample_li(&lights[li], shapes, &refs[ri], u, &s)) continue;
                assert_true(ts_vec3_is_finite(s.p_light) && ts_vec3_is_finite(s.n_light));
                /* First hit along wi (aimed at p_light in double)? */
                ts_dvec3 d = ts_dvec3_sub(ts_dvec3_from(s.p_light), ts_dvec3_from(refs[ri].p));
                double dist = ts_dvec3_length(d), t;
                ts_vec3 dir = ts_dvec3_to_vec3(ts_dvec3_scale(d, 1 / dist));
                if (ts_shape_sample_intersect(&shapes[li], 0, refs[ri].p, dir, 1e-6 * dist, INFINITY, &t, NULL) &&
                    t < dist * (1 - 1e-3))
                    continue;
                if (fabsf(ts_vec3_dot(s.n_light, s.wi)) < 0.02f) continue; /* grazing: see test_shape_sample */
                float p = ts_light_pdf_li(&lights[li], shapes, &refs[ri], s.wi);
                float ph = ts_light_pdf_li_hit(&lights[li], shapes, &refs[ri], s.p_light);
                double err = fmax(fabs(p - s.pdf), fabs(ph - s.pdf)) / s.pdf;
                if (err > 1e-3) fail_msg("light %d ref %d: sample pdf %g, Pdf_Li %g, at hit %g", li, ri, s.pdf, p, ph);
                worst = fmax(worst, err);
                checked++;
            }
            print_message("light %d ref %d: %d first-hit samples, worst relative pdf difference %.2e\n", li, ri,
                          checked, worst);
            assert_true(checked > 100);
            /* A direction away from the light misses: pdf 0. */
            ts_vec3 away = ts_vec3_normalize(ts_vec3_sub(refs[ri].p, (ts_vec3){(float)shapes[li].to_world.m.m[0][3],
                                                                               (float)shapes[li].to_world.m.m[1][3],
                                                                               (float)shapes[li].to_world.m.m[2][3]}));
            if (li == 3) away = ts_vec3_normalize(ts_vec3_sub(refs[ri].p, (ts_vec3){0, -1.0f / 3, 3.0f / 3}));
            if (li != 0 || ri != 2) /* ref 2 is inside the sphere: every direction hits */
                assert_true(ts_light_pdf_li(&lights[li], shapes, &refs[ri], away) == 0);
        }
}

/* Light selection: pmfs exact and summing to 1, emitting lights > 0, the returned pmf is
 * the distribution's, frequencies over a fine grid of u (bin × coin) match the pmfs
 * (within the grid's resolution of the coin), a zero-area triangle is never chosen. */
static void test_selection(void **state)
{
    (void)state;
    static float mp[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 2, 0};
    static uint32_t mix[6] = {0, 1, 2, 0, 3, 3}; /* triangle 1 is degenerate */
    ts_shape shapes[2] = {0};
    shapes[0] = sphere_shape((ts_vec3){0, 0, 3}, 0.5);
    shapes[1].type = TS_SHAPE_MESH;
    shapes[1].to_world = ts_xform_identity();
    shapes[1].mesh.n_vertices = 4;
    shapes[1].mesh.n_triangles = 2;
    shapes[1].mesh.p = mp;
    shapes[1].mesh.index = mix;
    ts_light lights[5] = {0};
    lights[0].type = TS_LIGHT_POINT;
    lights[0].color = ts_rgb_make(1, 2, 3);
    lights[1] = area_light(0, 0, 5);
    lights[2] = area_light(1, 0, 1);
    lights[3] = area_light(1, 1, 1);
    lights[4].type = TS_LIGHT_INFINITE;
    lights[4].color = ts_rgb_gray(0.01f);
    lights[4].to_world = ts_xform_identity();
    prepare(lights, 5, shapes);
    /* The zero-area triangle: power 0, no sample, nothing non-finite. */
    assert_true(ts_rgb_is_black(ts_light_power(&lights[3], shapes)));
    ts_interaction r = ref_at((ts_vec3){0.2f, 0.2f, 1}, (ts_vec3){0, 0, -1});
    ts_light_sample s;
    assert_false(ts_light_sample_li(&lights[3], shapes, &r, (ts_vec2){0.3f, 0.3f}, &s));
    assert_true(ts_light_pdf_li(&lights[3], shapes, &r, (ts_vec3){0, 0, -1}) == 0);
    assert_rel(ts_light_power(&lights[1], shapes).g, 5 * TS_PI_D * 4 * TS_PI_D * 0.25, 1e-6, "area power LπA");
    /* A two-sided emitter emits from both faces: twice the power. */
    ts_light two = lights[1];
    two.two_sided = true;
    assert_rel(ts_light_power(&two, shapes).g, 2 * 5 * TS_PI_D * 4 * TS_PI_D * 0.25, 1e-6, "two-sided area power 2LπA");
    ts_arena arena;
    ts_arena_init(&arena, 0);
    for (int mode = 0; mode < 2; mode++) {
        ts_light_distribution d;
        ts_error err = {0};
        assert_int_equal(ts_light_distribution_init(&d, lights, 5, shapes, (ts_light_sampling)mode, (ts_bounds3){{0, 0, 0}, {1, 1, 1}}, &arena, &err), TS_OK);
        double sum = 0, wsum = 0, w[5];
        for (int i = 0; i < 5; i++) {
            w[i] = mode == TS_LIGHT_SAMPLING_POWER ? ts_rgb_luminance(ts_light_power(&lights[i], shapes))
                                                   : (i == 3 ? 0 : 1);
            wsum += w[i];
        }
        for (int i = 0; i < 5; i++) {
            float p = ts_light_distribution_pmf(&d, (ts_vec3){0, 0, 0}, (uint32_t)i);
            sum += p;
            assert_rel(p + 1e-30, w[i] / wsum + 1e-30, 1e-6, "pmf exact");
            if (i != 3) assert_true(p > 0);
            else assert_true(p == 0);
        }
        assert_rel(sum, 1, 1e-6, "pmfs sum to 1");
        /* u.x at 256 points per alias bin, u.y (the coin) at 1024: an outcome gathers at
         * most 5 bins' shares, each resolved to 1/1024 of 1/5. */
        int count[5] = {0};
        const int nx = 5 * 256, ny = 1024;
        for (int a = 0; a < nx; a++)
            for (int b = 0; b < ny; b++) {
                float pmf;
                uint32_t i = ts_light_distribution_sample(&d, (ts_vec3){0, 0, 0}, (ts_vec2){(a + 0.5f) / nx, (b + 0.5f) / ny}, &pmf);
                assert_true(i < 5);
                assert_true(pmf == ts_light_distribution_pmf(&d, (ts_vec3){0, 0, 0}, i));
                count[i]++;
            }
        const double n = (double)nx * ny;
        for (int i = 0; i < 5; i++)
            if (fabs(count[i] / n - w[i] / wsum) > 1.0 / ny)
                fail_msg("mode %d light %d: frequency %g, pmf %g", mode, i, (double)count[i] / n, w[i] / wsum);
        assert_int_equal(count[3], 0);
    }
    ts_light_distribution empty;
    ts_error err = {0};
    assert_int_equal(ts_light_distribution_init(&empty, lights, 0, shapes, TS_LIGHT_SAMPLING_POWER, (ts_bounds3){{0, 0, 0}, {1, 1, 1}}, &arena, &err), TS_OK);
    float pmf = 1;
    assert_true(ts_light_distribution_sample(&empty, (ts_vec3){0, 0, 0}, (ts_vec2){0.5f, 0.5f}, &pmf) == TS_NONE && pmf == 0);
    ts_arena_fini(&arena);
}

/* Edge cases stay finite: reference on the light's own surface, at the point light's
 * position and 1e-20 away from it, coplanar receivers (exactly 0). */
static void test_edge_cases(void **state)
{
    (void)state;
    ts_shape shapes[2] = {0};
    shapes[0] = sphere_shape((ts_vec3){0, 0, 0}, 1);
    shapes[1].type = TS_SHAPE_DISK;
    shapes[1].disk.radius = 1;
    shapes[1].to_world = ts_xform_frame((ts_dvec3){0, 0, 0}, (ts_dvec3){0, 1, 0});
    ts_light lights[3] = {area_light(0, 0, 1), area_light(1, 0, 1), {0}};
    lights[1].two_sided = true;
    lights[2].type = TS_LIGHT_POINT;
    lights[2].color = ts_rgb_gray(1);
    prepare(lights, 3, shapes);
    ts_vec3 on_sphere = ts_vec3_normalize((ts_vec3){0.2f, 0.5f, -0.7f});
    ts_interaction refs[5] = {ref_at(on_sphere, on_sphere), ref_at((ts_vec3){0.3f, 0, 0.2f}, (ts_vec3){0, 1, 0}),
                              ref_at((ts_vec3){0, 0, 0}, (ts_vec3){0, 1, 0}),
                              ref_at((ts_vec3){1e-20f, 0, 0}, (ts_vec3){1, 0, 0}),
                              ref_at((ts_vec3){5, 0, 3}, (ts_vec3){0, 1, 0})};
    for (int li = 0; li < 3; li++)
        for (int ri = 0; ri < 5; ri++) {
            double e = irradiance(&lights[li], 1, shapes, &refs[ri], 32);
            assert_true(isfinite(e));
            ts_pcg32 rng;
            ts_pcg32_seed(&rng, 1, 1);
            for (int i = 0; i < 100; i++) {
                ts_vec3 w = ts_vec3_normalize((ts_vec3){ts_pcg32_float(&rng) - 0.5f, ts_pcg32_float(&rng) - 0.5f,
                                                        ts_pcg32_float(&rng) - 0.5f});
                float p = ts_light_pdf_li(&lights[li], shapes, &refs[ri], w);
                assert_true(isfinite(p) && p >= 0);
            }
        }
    /* The disk lies in y = 0: receivers in that plane (on it, and beside it) get exactly 0. */
    assert_true(irradiance(&lights[1], 1, shapes, &refs[1], 32) == 0);
    assert_true(irradiance(&lights[1], 1, shapes, &refs[4], 32) == 0);
    /* The point light at the reference point gives no sample. */
    ts_light_sample s;
    assert_false(ts_light_sample_li(&lights[2], shapes, &refs[2], (ts_vec2){0.5f, 0.5f}, &s));
}

/* Spatial selection (pbrt-v3's SpatialLightDistribution, lights/light.h): in the bounds
 * [0, 1]³ (64³ voxels), a voxel's pmf is ∝ each light's Σ luminance(L)/pdf over 128 points,
 * here with closed forms: a distant light E (E per point), a point light I at distance d
 * (I/d²), a sphere light L of radius r at distance d (cone sampling: L·2π(1 − √(1 − r²/d²)),
 * whatever the sample), and a spot pointing away (0, so pbrt-v3's floor). The voxels are 1/64 wide: 1/d² varies by ±0.03 % (point) and the
 * sphere's solid angle by ±0.5 % across one, linearly to first order, and the 128 Halton
 * points average it to well within 2e-3 of the value at the voxel's centre. */
static void test_spatial_selection(void **state)
{
    (void)state;
    ts_shape shapes[1] = {0};
    shapes[0] = sphere_shape((ts_vec3){0.5f, 0.5f, -3}, 0.5);
    ts_light lights[4] = {0};
    lights[0].type = TS_LIGHT_DISTANT;
    lights[0].color = ts_rgb_gray(1);
    lights[0].direction = (ts_vec3){0, 0, -1};
    lights[1].type = TS_LIGHT_POINT;
    lights[1].color = ts_rgb_gray(2500);
    lights[1].position = (ts_vec3){0.5f, 0.5f, 50};
    lights[2] = area_light(0, 0, 4);
    lights[3].type = TS_LIGHT_SPOT;
    lights[3].color = ts_rgb_gray(100);
    lights[3].position = (ts_vec3){0.5f, 0.5f, 5};
    lights[3].direction = (ts_vec3){0, 0, 1};
    lights[3].cos_total = cosf(ts_radians(30)), lights[3].cos_falloff_start = cosf(ts_radians(25));
    prepare(lights, 4, shapes);
    ts_arena arena;
    ts_arena_init(&arena, 0);
    ts_light_distribution d;
    ts_error err = {0};
    ts_bounds3 b = {{0, 0, 0}, {1, 1, 1}};
    assert_int_equal(ts_light_distribution_init(&d, lights, 4, shapes, TS_LIGHT_SAMPLING_SPATIAL, b, &arena, &err),
                     TS_OK);
    assert_true(d.spatial && d.voxels[0] == 64 && d.voxels[1] == 64 && d.voxels[2] == 64);
    /* voxels apart along one axis each (the sphere's solid angle tells x and y apart by
     * ~2 %, the point light's distance z by 4 %), so a cache slot shared by two voxels fails */
    const ts_vec3 at[5] = {
        {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.99f}, {0.5f, 0.99f, 0.5f}, {0.01f, 0.5f, 0.5f}, {0.7f, 0.2f, 0.999f}};
    for (int k = 0; k < 5; k++) {
        /* the voxel's centre */
        ts_vec3 c = {(floorf(at[k].x * 64) + 0.5f) / 64, (floorf(at[k].y * 64) + 0.5f) / 64,
                     (floorf(at[k].z * 64) + 0.5f) / 64};
        double d_point = ts_vec3_distance(c, lights[1].position), d_sphere = ts_vec3_distance(c, (ts_vec3){0.5f, 0.5f, -3});
        double w[4] = {1, 2500 / (d_point * d_point),
                       4 * 2 * TS_PI_D * (1 - sqrt(1 - 0.25 / (d_sphere * d_sphere))), 0};
        /* pbrt-v3's floor is 10⁻³ of the mean per point and light, set against sums over
         * the 128 points: 10⁻³/128 of the mean in these per-point units */
        w[3] = 1e-3 * (w[0] + w[1] + w[2]) / (4 * 128.0);
        double wsum = w[0] + w[1] + w[2] + w[3], sum = 0;
        float pmf[4];
        for (uint32_t i = 0; i < 4; i++) {
            pmf[i] = ts_light_distribution_pmf(&d, at[k], i);
            sum += pmf[i];
            /* a pmf is a difference of the float cdf, exact to 2^-23 (two of its steps
             * below 1), which is 6 % of the spot's floor: that much more absolute slack */
            if (!(fabs(pmf[i] - w[i] / wsum) <= 2e-3 * w[i] / wsum + 0x1p-23))
                fail_msg("point %d light %u: spatial pmf %.9g, expected %.9g", k, i, (double)pmf[i], w[i] / wsum);
        }
        assert_rel(sum, 1, 1e-6, "pmfs sum to 1");
        assert_true(ts_light_distribution_pmf(&d, at[k], 4) == 0);
        /* inverting the cdf: frequencies of u.x on a grid of 10⁶ match the pmf to 1e-6 */
        int count[4] = {0};
        const int nu = 1000000;
        for (int a = 0; a < nu; a++) {
            float p;
            uint32_t i = ts_light_distribution_sample(&d, at[k], (ts_vec2){(a + 0.5f) / nu, 0.5f}, &p);
            assert_true(i < 4 && p == pmf[i]);
            count[i]++;
        }
        for (int i = 0; i < 4; i++)
            if (fabs(count[i] / (double)nu - pmf[i]) > 2e-6)
                fail_msg("point %d light %d: frequency %g, pmf %g", k, i, count[i] / (double)nu, (double)pmf[i]);
    }
    /* Points outside the bounds (and NaN) fall into the nearest voxel (pbrt-v3's clamp). */
    assert_true(ts_light_distribution_pmf(&d, (ts_vec3){-5, 0.5f, 0.5f}, 1) ==
                ts_light_distribution_pmf(&d, (ts_vec3){0, 0.5f, 0.5f}, 1));
    assert_true(ts_light_distribution_pmf(&d, (ts_vec3){NAN, 2, 0.5f}, 1) ==
                ts_light_distribution_pmf(&d, (ts_vec3){0, 1, 0.5f}, 1));
    ts_light_distribution_fini(&d);
    /* 100 lights: 64³ voxels of 101 floats and a state word (106 MB) exceed
     * TS_LIGHT_SPATIAL_MAX_BYTES (64 MB), 32³ (13 MB) do not. Equal point lights at equal
     * distances from a voxel's centre share it equally. */
    static ts_light many[100];
    for (int i = 0; i < 100; i++) {
        many[i] = (ts_light){0};
        many[i].type = TS_LIGHT_POINT;
        many[i].color = ts_rgb_gray(1);
        float a = 2 * TS_PI * (float)i / 100;
        many[i].position = (ts_vec3){0.5f / 32 + 40 * cosf(a), 0.5f / 32 + 40 * sinf(a), 0.5f / 32};
    }
    prepare(many, 100, shapes);
    assert_int_equal(ts_light_distribution_init(&d, many, 100, shapes, TS_LIGHT_SAMPLING_SPATIAL, b, &arena, &err),
                     TS_OK);
    assert_true(d.voxels[0] == 32 && d.voxels[1] == 32 && d.voxels[2] == 32);
    for (uint32_t i = 0; i < 100; i++)
        if (!(fabs(ts_light_distribution_pmf(&d, (ts_vec3){0.01f, 0.01f, 0.01f}, i) - 0.01) <= 2e-5))
            fail_msg("light %u of 100: pmf %g", i, (double)ts_light_distribution_pmf(&d, (ts_vec3){0.01f, 0.01f, 0.01f}, i));
    ts_light_distribution_fini(&d);
    ts_arena_fini(&arena);
}

/* ---------------------------------------------------------------- rectangle lights */

/* Irradiance from a polygon of radiance L at p with unit normal n, the part above p's
 * horizon: Lambert's contour formula E = L/2 |Σ_edges θ_e (n · û_e)| (θ_e the angle the
 * edge subtends at p, û_e the unit normal of the plane through p and the edge; e.g. Baum,
 * Rushmeier and Winget 1989, eq. 3 — the form factor of a differential area to a polygon),
 * after clipping the polygon by the plane through p normal to n (Sutherland–Hodgman), so
 * it is exact for any receiver orientation. */
static double polygon_irradiance(const ts_dvec3 *v, int nv, ts_dvec3 p, ts_dvec3 n, double L)
{
    ts_dvec3 c[16];
    int nc = 0;
    for (int i = 0; i < nv; i++) {
        ts_dvec3 a = v[i], b = v[(i + 1) % nv];
        double da = ts_dvec3_dot(ts_dvec3_sub(a, p), n), db = ts_dvec3_dot(ts_dvec3_sub(b, p), n);
        if (da >= 0) c[nc++] = a;
        if ((da >= 0) != (db >= 0)) c[nc++] = ts_dvec3_add(a, ts_dvec3_scale(ts_dvec3_sub(b, a), da / (da - db)));
    }
    double sum = 0;
    for (int i = 0; i < nc; i++) {
        ts_dvec3 a = ts_dvec3_normalize(ts_dvec3_sub(c[i], p)), b = ts_dvec3_normalize(ts_dvec3_sub(c[(i + 1) % nc], p));
        ts_dvec3 x = ts_dvec3_cross(a, b);
        double s = ts_dvec3_length(x);
        if (!(s > 0)) continue;
        sum += atan2(s, ts_dvec3_dot(a, b)) * ts_dvec3_dot(ts_dvec3_scale(x, 1 / s), n);
    }
    return 0.5 * L * fabs(sum);
}

/* A rectangle light of two triangles, one light: irradiance at receivers under it, off to
 * the side, near its plane and grazing (its horizon cutting the rectangle) within 1e-3 of
 * Lambert's formula in every sampling mode, and, under a corner, of the parallel-rectangle
 * form factor; every sample's pdf equals the MIS side's (ts_light_pdf_li_hit at the sample,
 * ts_light_pdf_li along it) and, where spherical, 1/Ω with Ω from two Van Oosterom–
 * Strackee triangles of the mesh (1e-6 relative: both in double, rounded to float). The
 * irradiance estimator is the file's K² = 512² stratified one: an integrand smooth in u,
 * stratified error O(K^-2), far below the 1e-3 bias bound. */
static void test_rect_light(void **state)
{
    (void)state;
    static float quad[12] = {0, 0, 1, 1.5f, 0, 1, 1.5f, 0.8f, 1, 0, 0.8f, 1};
    static uint32_t qix[6] = {0, 2, 1, 0, 3, 2}; /* faces −z; shares the diagonal 0–2 */
    ts_shape q = {0};
    q.type = TS_SHAPE_MESH;
    q.to_world = ts_xform_identity();
    q.mesh.n_vertices = 4;
    q.mesh.n_triangles = 2;
    q.mesh.p = quad;
    q.mesh.index = qix;
    assert_true(ts_shape_triangles_rectangle(&q, 0, 1));
    ts_dvec3 v[4];
    for (int k = 0; k < 4; k++) v[k] = (ts_dvec3){quad[3 * k], quad[3 * k + 1], quad[3 * k + 2]};
    const struct {
        const char *name;
        ts_vec3 p, n;
    } recv[] = {
        {"under a corner", {0, 0, 0}, {0, 0, 1}},
        {"under it, tilted", {0.6f, 0.3f, 0.2f}, {0.3f, -0.2f, 1}},
        {"off to the side", {2.6f, -0.7f, 0.4f}, {-0.6f, 0.3f, 0.7f}},
        {"near its plane", {1.9f, 0.4f, 0.97f}, {-1, 0, 0.1f}},
        {"grazing (horizon cuts it)", {0.7f, -0.9f, 0.3f}, {0, 1, -0.15f}},
    };
    double A = 1.5, B = (double)0.8f; /* the float vertex's value */
    double F = (A / sqrt(1 + A * A) * atan(B / sqrt(1 + A * A)) + B / sqrt(1 + B * B) * atan(A / sqrt(1 + B * B))) /
               (2 * TS_PI_D);
    ts_triangle_sampling modes[3] = {TS_TRIANGLE_SAMPLING_AREA, TS_TRIANGLE_SAMPLING_SPHERICAL, TS_TRIANGLE_SAMPLING_AUTO};
    const char *mn[3] = {"area", "spherical", "auto"};
    for (int m = 0; m < 3; m++) {
        ts_light l = area_light(0, 0, 2);
        l.rect = true;
        l.prim_b = 1;
        l.triangle_sampling = modes[m];
        prepare(&l, 1, &q);
        assert_true(l.geom.rect);
        assert_rel(ts_light_power(&l, &q).g, TS_PI_D * 2 * 1.5 * B, 1e-6, "rectangle power πLA");
        for (size_t k = 0; k < sizeof recv / sizeof *recv; k++) {
            ts_interaction r = ref_at(recv[k].p, recv[k].n);
            double e = irradiance(&l, 1, &q, &r, 512);
            double expect = polygon_irradiance(v, 4, ts_dvec3_from(r.p), ts_dvec3_from(r.n), 2);
            print_message("rectangle light (%s) %-26s E = %.9g, Lambert %.9g\n", mn[m], recv[k].name, e, expect);
            assert_rel(e, expect, 1e-3, recv[k].name);
            if (k == 0) assert_rel(expect, TS_PI_D * 2 * F, 1e-12, "Lambert vs the corner form factor");
            /* pdfs */
            ts_dvec3 p = ts_dvec3_from(r.p);
            double omega = ts_spherical_triangle_area(v[0], v[2], v[1], p) + ts_spherical_triangle_area(v[0], v[3], v[2], p);
            ts_pcg32 rng;
            ts_pcg32_seed(&rng, 17, (uint64_t)k);
            for (int i = 0; i < 2000; i++) {
                ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
                ts_light_sample s;
                if (!ts_light_sample_li(&l, &q, &r, u, &s)) continue;
                float ph = ts_light_pdf_li_hit(&l, &q, &r, s.p_light), pw = ts_light_pdf_li(&l, &q, &r, s.wi);
                if (!(fabs(ph - s.pdf) <= 1e-6 * s.pdf) || !(fabs(pw - s.pdf) <= 1e-3 * s.pdf))
                    fail_msg("%s: sample pdf %.9g, at the hit %.9g, along wi %.9g", recv[k].name, s.pdf, ph, pw);
                if (m == 1 && !(fabs(s.pdf * omega - 1) <= 1e-6))
                    fail_msg("%s: pdf %.9g, 1/Ω %.9g", recv[k].name, s.pdf, 1 / omega);
            }
        }
    }
}

static ts_scene *load_doc(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "test", NULL, &s, &err)) fail_msg("scene: %s", err.message);
    return s;
}

/* The builder's light list: an emitting mesh of a rectangle (two triangles sharing the
 * diagonal) is one light, both triangles map to it, the MIS pdf of a hit on either is the
 * selection pmf × 1/Ω (what path_emission computes), and direct's strategy all and the
 * max-work bound count one light; a trapezoid, a rectangle split into triangles that do not
 * share its diagonal, and the rectangle's triangles in opposite windings stay two lights;
 * in a mesh of three, the rectangle pairs and the third stays alone. */
static void test_rect_lights_in_scene(void **state)
{
    (void)state;
    static const char *fmt =
        "{\"tessera\":1,\"camera\":{\"from\":[0,0,3],\"to\":[0,0,0],\"fov\":40},"
        "\"film\":{\"width\":8,\"height\":8},\"integrator\":{\"type\":\"direct\",\"strategy\":\"all\"},"
        "\"materials\":{\"w\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
        "\"shapes\":[{\"type\":\"mesh\",\"material\":\"w\",\"emission\":3,"
        "\"positions\":[%s],\"indices\":[%s]}]}";
    const struct {
        const char *name, *pos, *idx;
        uint32_t lights;
        bool rect;
    } cases[] = {
        {"rectangle", "-1,1,-1, 1,1,-1, 1,1,1, -1,1,1", "0,2,1, 0,3,2", 1, true},
        {"rectangle, other diagonal", "-1,1,-1, 1,1,-1, 1,1,1, -1,1,1", "1,0,3, 1,3,2", 1, true},
        {"trapezoid", "-1,1,-1, 1,1,-1, 0.5,1,1, -1,1,1", "0,2,1, 0,3,2", 2, false},
        {"rectangle cut by no diagonal", "-1,1,-1, 1,1,-1, 1,1,1, -1,1,1, 0,1,0", "0,4,1, 1,4,2", 2, false},
        {"opposite windings", "-1,1,-1, 1,1,-1, 1,1,1, -1,1,1", "0,2,1, 0,2,3", 2, false},
        {"rectangle and a triangle", "-1,1,-1, 1,1,-1, 1,1,1, -1,1,1, 2,1,2", "0,2,1, 0,3,2, 1,2,4", 2, true},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char doc[2048];
        snprintf(doc, sizeof doc, fmt, cases[k].pos, cases[k].idx);
        ts_scene *s = load_doc(doc);
        print_message("scene lights: %-30s %u light(s)\n", cases[k].name, s->n_lights);
        assert_int_equal(s->n_lights, cases[k].lights);
        assert_int_equal(s->lights[0].rect, cases[k].rect);
        const ts_shape *sh = &s->shapes[0];
        uint32_t l0 = ts_area_light_index(sh, 0), l1 = ts_area_light_index(sh, 1);
        assert_true(cases[k].rect ? l0 == l1 : l0 != l1);
        if (k == 5) assert_int_equal(ts_area_light_index(sh, 2), 1);
        /* direct, strategy all: 1 + 2·(samples per light) rays per light and vertex */
        double rays = ts_integrator_rays_per_sample(s, TS_INTEGRATOR_DIRECT, s->effects);
        assert_true(rays == 1 + 2.0 * cases[k].lights);
        if (cases[k].rect) {
            /* what the path tracer's MIS weight of a BSDF-found hit uses, on both triangles */
            ts_interaction ref = ref_at((ts_vec3){0.2f, -0.3f, 0.1f}, (ts_vec3){0, 1, 0});
            ts_dvec3 p = ts_dvec3_from(ref.p);
            ts_dvec3 c[4] = {{-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}};
            double omega = ts_spherical_triangle_area(c[0], c[1], c[2], p) + ts_spherical_triangle_area(c[0], c[2], c[3], p);
            ts_vec3 hits[2] = {{0.5f, 1, -0.2f}, {-0.5f, 1, 0.2f}}; /* one in each triangle of either split */
            for (int h = 0; h < 2; h++) {
                ts_interaction hit = {0};
                hit.p = hits[h];
                float pmf = ts_light_distribution_pmf(&s->light_distribution, ref.p, l0);
                float pdf = ts_light_pdf_li_hit(&s->lights[l0], s->shapes, &ref, hit.p);
                /* power selection: the rectangle's area 4 against the triangle's 1 */
                assert_rel(pmf, cases[k].lights == 1 ? 1 : 0.8, 1e-6, "selection pmf");
                assert_rel(pdf * omega, 1, 1e-6, "MIS pdf of a hit = 1/Ω");
            }
        }
        ts_scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_delta_lights),  cmocka_unit_test(test_area_irradiance),
        cmocka_unit_test(test_infinite),
        cmocka_unit_test(test_le_pdf),      cmocka_unit_test(test_sample_vs_pdf),
        cmocka_unit_test(test_selection),     cmocka_unit_test(test_edge_cases),
        cmocka_unit_test(test_spatial_selection), cmocka_unit_test(test_rect_light),
        cmocka_unit_test(test_rect_lights_in_scene),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
