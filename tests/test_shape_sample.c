/* test_shape_sample.c — sampling points on shapes by area and solid angle (shape_sample.h).
 *
 * χ² (tests/chi2.h): the directions of every shape's solid-angle sampler, seen from points
 * outside, near (distance ≪ size) and, for spheres and tubes, inside, against
 * ts_shape_pdf_solid_angle. A sample counts as a direction only when its point is the
 * first hit along its direction (that is the density the pdf describes); the others go
 * to the χ² "none" bin, whose expected count N(1 − ∫pdf) is checked too. Significance:
 * the project-wide family of TS_CHI2_FAMILY_SIZE tests fails with probability ≤ 0.01.
 * Fixed seeds, so the run is deterministic. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chi2.h"
#include "core/hash.h"
#include "geometry/shape_sample.h"

static void assert_close(double a, double b, double tol, const char *what)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%s: %.9g != %.9g (tolerance %g)", what, a, b, tol);
}

static ts_vec2 u2(ts_pcg32 *rng)
{
    float a = ts_pcg32_float(rng);
    return (ts_vec2){a, ts_pcg32_float(rng)};
}

/* ---- shapes ---- */

static ts_shape sphere(ts_vec3 c, double r)
{
    ts_shape s = {0};
    s.type = TS_SHAPE_SPHERE;
    s.sphere.radius = r;
    s.to_world = ts_xform_translate(ts_dvec3_from(c));
    return s;
}

static ts_shape disk(ts_vec3 c, ts_vec3 n, double r, double ri)
{
    ts_shape s = {0};
    s.type = TS_SHAPE_DISK;
    s.disk.radius = r;
    s.disk.inner_radius = ri;
    s.to_world = ts_xform_frame(ts_dvec3_from(c), ts_dvec3_from(n));
    return s;
}

static ts_shape cylinder(ts_vec3 p0, ts_vec3 p1, double r)
{
    ts_shape s = {0};
    s.type = TS_SHAPE_CYLINDER;
    s.cylinder.radius = r;
    s.cylinder.height = ts_vec3_distance(p0, p1);
    s.to_world = ts_xform_frame(ts_dvec3_from(p0), ts_dvec3_from(ts_vec3_sub(p1, p0)));
    return s;
}

static ts_shape triangle(float *p /* 9 floats */, uint32_t *ix)
{
    ts_shape s = {0};
    s.type = TS_SHAPE_MESH;
    s.to_world = ts_xform_identity();
    s.mesh.n_vertices = 3;
    s.mesh.n_triangles = 1;
    s.mesh.p = p;
    s.mesh.index = ix;
    return s;
}

static ts_interaction ref_at(ts_vec3 p)
{
    ts_interaction r = {0};
    r.p = p;
    r.n = (ts_vec3){0, 0, 1};
    r.shape = TS_NONE;
    return r;
}

typedef struct ctx {
    const ts_shape *s;
    ts_shape_sample_info info;
    ts_interaction ref;
} ctx;

static void ctx_init(ctx *c, const ts_shape *s, ts_triangle_sampling mode, ts_vec3 ref)
{
    c->s = s;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init(s, 0, mode, &c->info, &err), TS_OK);
    c->ref = ref_at(ref);
}

/* Is p the first point of the shape along the ray from ref through it? The ray is aimed
 * at p in double, and an earlier hit must be 0.1% nearer to count: near a silhouette the
 * two roots of a grazing ray merge and p's float rounding (1e-7) moves them apart by up
 * to ~sqrt(2·r·1e-7·d) ≈ 5e-4·d. Far-side points within that band of the silhouette are
 * miscounted as first hits: a fraction ≲ 1e-3 of the samples, inside the integral
 * check's tolerance below. */
static bool first_hit(const ctx *c, ts_vec3 p, ts_vec3 wi)
{
    (void)wi;
    ts_dvec3 d = ts_dvec3_sub(ts_dvec3_from(p), ts_dvec3_from(c->ref.p));
    double dist = ts_dvec3_length(d), t;
    ts_vec3 dir = ts_dvec3_to_vec3(ts_dvec3_scale(d, 1 / dist));
    if (!ts_shape_sample_intersect(c->s, 0, c->ref.p, dir, 1e-6 * dist, INFINITY, &t, NULL)) return true;
    return t >= dist * (1 - 1e-3);
}

static ts_chi2_outcome chi2_sample(void *vc, ts_pcg32 *rng, ts_vec3 *w)
{
    ctx *c = vc;
    ts_shape_point pt;
    if (!ts_shape_sample_solid_angle(c->s, 0, &c->info, &c->ref, u2(rng), &pt)) return TS_CHI2_NONE;
    *w = ts_vec3_normalize(ts_vec3_sub(pt.p, c->ref.p));
    return first_hit(c, pt.p, *w) ? TS_CHI2_DIRECTION : TS_CHI2_NONE;
}

static double chi2_pdf(void *vc, ts_vec3 w)
{
    ctx *c = vc;
    return ts_shape_pdf_solid_angle(c->s, 0, &c->info, &c->ref, w);
}

/* ∫ pdf dω over the sphere by a stratified midpoint rule in (z, φ) — independent of chi2's
 * quadrature. K² = 2.25·10^6 nodes; for a pdf that is smooth but for silhouette curves
 * the error is about (fraction of nodes cut by the curves) × jump ≲ 3e-4 (measured:
 * ≤ 1e-4 on these shapes). */
static double integrate_pdf(ctx *c)
{
    const int k = 1500;
    /* The grid is turned by a fixed, arbitrary rotation so that no silhouette circle about a
     * coordinate axis runs along a grid row (that would make the midpoint error systematic). */
    ts_xform rot = ts_xform_rotate(37.3, (ts_dvec3){0.3, 0.8, 0.5});
    double sum = 0;
    for (int i = 0; i < k; i++) {
        double z = -1 + (i + 0.5) * 2.0 / k, sz = sqrt(fmax(0, 1 - z * z));
        for (int j = 0; j < k; j++) {
            double phi = (j + 0.5) * 2 * TS_PI_D / k;
            ts_dvec3 w = ts_xform_vector(&rot, (ts_dvec3){sz * cos(phi), sz * sin(phi), z});
            sum += chi2_pdf(c, ts_dvec3_to_vec3(w));
        }
    }
    return sum * 4 * TS_PI_D / ((double)k * k);
}

/* Runs chi2 (400 000 samples, project-wide family significance 0.01) and checks the
 * pdf's total against the fraction of first-hit samples.
 *
 * About chi2's quadrature here: a light's solid-angle pdf has silhouettes, curved
 * discontinuities across cells, and (through float directions) ~1e-7 relative noise;
 * chi2's per-cell target of 0.001 counts is out of reach there, cells end "over budget"
 * and chi2 widens those bins' variance by the error bound (less power in silhouette
 * cells, none lost elsewhere). aligned marks configurations whose silhouettes lie on
 * chi2's row borders, where its expected counts are accurate. The independent check:
 * ∫pdf by a rotated midpoint grid (error ≲ 4e-4, measured) equals the first-hit fraction
 * within 5 binomial σ + 1e-3 (grid error plus the silhouette miscount above). */
static void run_chi2(const char *name, ctx *c, uint64_t seed, bool aligned)
{
    ts_chi2_params p;
    ts_chi2_params_default(&p);
    p.seed = seed;
    p.sample_count = 400000;
    p.max_node_evals = 40000;
    ts_chi2_result r;
    bool ok = ts_chi2_test(&p, chi2_sample, chi2_pdf, c, &r);
    double n = (double)p.sample_count, frac = (double)r.binned / n;
    double integral = integrate_pdf(c);
    print_message("chi2 %-34s p=%.4f ∫pdf=%.6f (chi2 %.6f) first-hit fraction %.6f; %d cells over budget%s %s\n",
                  name, r.p_value, integral, r.pdf_integral, frac, r.unconverged, aligned ? " (aligned)" : "",
                  ok ? "" : r.message);
    if (!ok) fail_msg("%s: %s", name, r.message);
    assert_close(integral, frac, 5 * sqrt(fmax(frac * (1 - frac), 1e-12) / n) + 1e-3, "∫pdf vs first-hit fraction");
}

/* Sample_Li-style consistency: for every sample whose point is the first hit, the pdf it
 * returns equals ts_shape_pdf_solid_angle(wi) and ts_shape_pdf_solid_angle_at(p) to a
 * relative 1e-3 (both are the same formula evaluated from float wi / p; the bound leaves
 * room for the float rounding of wi at grazing angles, measured ≤ 2e-5). */
static void check_consistency(const char *name, ctx *c, int n)
{
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 3);
    int checked = 0;
    double worst = 0;
    for (int i = 0; i < n; i++) {
        ts_shape_point pt;
        if (!ts_shape_sample_solid_angle(c->s, 0, &c->info, &c->ref, u2(&rng), &pt)) continue;
        assert_true(isfinite(pt.pdf) && pt.pdf > 0);
        assert_true(ts_vec3_is_finite(pt.p) && ts_vec3_is_finite(pt.n));
        ts_vec3 wi = ts_vec3_normalize(ts_vec3_sub(pt.p, c->ref.p));
        if (!first_hit(c, pt.p, wi)) continue;
        /* Skip the grazing band |cos θ_light| < 0.02: there pdf(wi) = p_A d²/cos is ill-
         * conditioned — one ulp of wi moves the hit along a curved surface and changes the
         * pdf by ≈ (d/r)·6e-8/cos² relative, > 1e-3 below cos ≈ 0.015 for d/r = 3. */
        if (fabsf(ts_vec3_dot(pt.n, wi)) < 0.02f) continue;
        double p1 = ts_shape_pdf_solid_angle(c->s, 0, &c->info, &c->ref, wi);
        double p2 = ts_shape_pdf_solid_angle_at(c->s, 0, &c->info, &c->ref, pt.p);
        double e1 = fabs(p1 - pt.pdf) / pt.pdf, e2 = fabs(p2 - pt.pdf) / pt.pdf;
        if (e1 > 1e-3 || e2 > 1e-3)
            fail_msg("%s: sample pdf %.9g, pdf(wi) %.9g, pdf(p) %.9g at p=(%g,%g,%g)", name, pt.pdf, p1, p2, pt.p.x,
                     pt.p.y, pt.p.z);
        worst = fmax(worst, fmax(e1, e2));
        checked++;
    }
    print_message("consistency %-28s %d first-hit samples, worst relative difference %.2e\n", name, checked, worst);
    assert_true(checked >= 200); /* from near a tube only ~5% of its area is visible, mostly grazing */
}

static void check_case(const char *name, const ts_shape *s, ts_triangle_sampling mode, ts_vec3 ref, uint64_t seed,
                       bool aligned)
{
    ctx c;
    ctx_init(&c, s, mode, ref);
    run_chi2(name, &c, seed, aligned);
    check_consistency(name, &c, 20000);
}

/* ---- tests ---- */

static void test_sphere(void **state)
{
    (void)state;
    ts_shape s = sphere((ts_vec3){0.2f, -0.1f, 0.3f}, 1.0);
    check_case("sphere outside (d = 3r)", &s, 0, (ts_vec3){0.2f, -0.1f, 3.3f}, 11, false);
    check_case("sphere near (gap 0.03r)", &s, 0, (ts_vec3){1.23f, -0.1f, 0.3f}, 12, false);
    check_case("sphere inside", &s, 0, (ts_vec3){0.5f, 0.1f, 0.0f}, 13, true); /* pdf continuous */
    /* Ellipsoid: non-uniform scale, area sampling through the exact Jacobian; far-side
     * points are "none". */
    ts_xform sc = ts_xform_scale((ts_dvec3){1.0, 2.0, 0.5});
    ts_xform rot = ts_xform_rotate(30, (ts_dvec3){1, 1, 0});
    s.to_world = ts_xform_compose(&rot, &sc);
    check_case("ellipsoid outside", &s, 0, (ts_vec3){0.3f, 0.4f, 2.0f}, 14, false);
    check_case("ellipsoid inside", &s, 0, (ts_vec3){0.1f, 0.2f, 0.0f}, 15, true); /* pdf continuous */
}

/* Configurations whose silhouettes fall on chi2's row borders z = −1 + 2i/21: circles of
 * direction cosine c = k/21 (k odd) about ∓z, seen from a point on the z axis. Radii are
 * derived in double from the float reference point so the borders are hit to ~1e-16. */
static double edge_cos(int k) { return k / 21.0; }
static double tan_of(double c) { return sqrt(1 - c * c) / c; }

static void test_aligned(void **state)
{
    (void)state;
    /* Sphere below ref = (0,0,d): cosθ_max = c ⇒ r = d·sin θ_max. */
    int ks[2] = {19, 3};
    const char *names[2] = {"sphere outside, aligned", "sphere near, aligned (gap 0.01r)"};
    for (int k = 0; k < 2; k++) {
        float d = 2.5f;
        ts_shape s = sphere((ts_vec3){0, 0, 0}, d * sqrt(1 - edge_cos(ks[k]) * edge_cos(ks[k])));
        check_case(names[k], &s, 0, (ts_vec3){0, 0, d}, 41 + k, true);
    }
    /* Annulus in z = 0 seen from (0,0,h): outer rim at c_o, inner at c_i > c_o. */
    int ko[2] = {17, 1}, ki[2] = {19, 3};
    const char *dn[2] = {"annulus on axis, aligned", "annulus near, aligned"};
    for (int k = 0; k < 2; k++) {
        float h = k == 0 ? 2.0f : 0.05f;
        ts_shape d = disk((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, h * tan_of(edge_cos(ko[k])), h * tan_of(edge_cos(ki[k])));
        check_case(dn[k], &d, 0, (ts_vec3){0, 0, h}, 43 + k, true);
    }
    /* Tube along z from 0 to H, radius r. From (0,0,2) beyond its top end: rims at
     * c = 13/21 (top) and 19/21 (bottom). From (0,0,1) inside: ends at 5/21 up, 7/21 down. */
    {
        float zr = 2.0f;
        double r = zr / tan_of(edge_cos(19)) / 1.0;
        r = zr * sqrt(1 - edge_cos(19) * edge_cos(19)) / edge_cos(19);
        double a = r / tan_of(edge_cos(13));
        ts_shape c = cylinder((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, r);
        c.cylinder.height = zr - a;
        check_case("tube from beyond an end, aligned", &c, 0, (ts_vec3){0, 0, zr}, 45, true);
    }
    {
        float zr = 1.0f;
        double r = zr * tan_of(edge_cos(7));
        double up = r / tan_of(edge_cos(5));
        ts_shape c = cylinder((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, r);
        c.cylinder.height = zr + up;
        check_case("tube inside, aligned", &c, 0, (ts_vec3){0, 0, zr}, 46, true);
    }
}

static void test_disk_cylinder(void **state)
{
    (void)state;
    ts_vec3 n = ts_vec3_normalize((ts_vec3){0.3f, -0.2f, 1.0f});
    ts_shape d = disk((ts_vec3){0, 0, 0}, n, 1.0, 0.4);
    check_case("annulus outside", &d, 0, (ts_vec3){0.5f, 0.7f, 1.5f}, 21, false);
    check_case("annulus near (0.02 over it)", &d, 0, ts_vec3_add((ts_vec3){0.6f, 0, 0}, ts_vec3_scale(n, 0.02f)), 22, false);
    check_case("annulus from below", &d, 0, (ts_vec3){0.1f, 0.2f, -0.8f}, 23, false);
    ts_shape c = cylinder((ts_vec3){0, 0, -1}, (ts_vec3){0.2f, 0.1f, 1}, 0.5);
    check_case("tube outside", &c, 0, (ts_vec3){1.5f, 0.3f, 0.2f}, 24, false);
    check_case("tube near (gap 0.02)", &c, 0, (ts_vec3){0.62f, 0.05f, 0.1f}, 25, false);
    check_case("tube inside", &c, 0, (ts_vec3){0.1f, 0.0f, 0.5f}, 26, false);
    check_case("tube beyond an end", &c, 0, (ts_vec3){0.3f, 0.2f, 2.0f}, 27, false);
}

static float tri_p[9] = {-1, -0.5f, 0, 1.2f, -0.7f, 0.1f, 0.1f, 1.1f, -0.2f};
static uint32_t tri_ix[3] = {0, 1, 2};

static void test_triangle(void **state)
{
    (void)state;
    ts_shape t = triangle(tri_p, tri_ix);
    ts_vec3 far = {0.2f, 0.3f, 2.5f}, near = {0.15f, 0.0f, 0.04f}, below = {-0.3f, 0.2f, -0.5f};
    check_case("triangle area, outside", &t, TS_TRIANGLE_SAMPLING_AREA, far, 31, false);
    check_case("triangle area, near", &t, TS_TRIANGLE_SAMPLING_AREA, near, 32, false);
    check_case("triangle spherical, outside", &t, TS_TRIANGLE_SAMPLING_SPHERICAL, far, 33, false);
    check_case("triangle spherical, near", &t, TS_TRIANGLE_SAMPLING_SPHERICAL, near, 34, false);
    check_case("triangle spherical, below", &t, TS_TRIANGLE_SAMPLING_SPHERICAL, below, 35, false);
    check_case("triangle auto, near", &t, TS_TRIANGLE_SAMPLING_AUTO, near, 36, false);
}

/* Arvo's sampler against a closed form: the octant triangle seen from the origin is a
 * spherical triangle of area π/2; its samples are uniform there, so each coordinate of
 * the direction has mean ∫_octant x dω / (π/2) = (π/4)/(π/2) = 1/2. 10^5 samples of a
 * variable with sd ≤ 0.3: 5σ = 0.005. */
static void test_spherical_triangle_closed_form(void **state)
{
    (void)state;
    static float p[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    ts_shape t = triangle(p, tri_ix);
    double omega = ts_spherical_triangle_area((ts_dvec3){1, 0, 0}, (ts_dvec3){0, 1, 0}, (ts_dvec3){0, 0, 1},
                                              (ts_dvec3){0, 0, 0});
    assert_close(omega, TS_PI_D / 2, 1e-12, "octant solid angle");
    ctx c;
    ctx_init(&c, &t, TS_TRIANGLE_SAMPLING_SPHERICAL, (ts_vec3){0, 0, 0});
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 5, 5);
    double mean[3] = {0};
    int n = 100000;
    for (int i = 0; i < n; i++) {
        ts_shape_point pt;
        assert_true(ts_shape_sample_solid_angle(&t, 0, &c.info, &c.ref, u2(&rng), &pt));
        assert_close(pt.pdf, 2 / TS_PI_D, 1e-6, "pdf 1/Ω");
        /* On the triangle: x + y + z = 1, all ≥ 0. */
        assert_close(pt.p.x + pt.p.y + pt.p.z, 1, 1e-6, "on the plane");
        assert_true(pt.p.x >= 0 && pt.p.y >= 0 && pt.p.z >= 0);
        ts_vec3 w = ts_vec3_normalize(pt.p);
        mean[0] += w.x, mean[1] += w.y, mean[2] += w.z;
    }
    for (int k = 0; k < 3; k++) assert_close(mean[k] / n, 0.5, 0.005, "mean direction");
}

/* Area sampling: E[1/pdf_A] = area exactly for any density that is the sampler's own, so
 * the mean of 1/pdf over 2·10^5 samples must match info.area (and the closed form where
 * there is one). Tolerance 5σ of that mean (σ measured from the same samples). */
static void check_area(const char *name, const ts_shape *s, double expect)
{
    ts_shape_sample_info info;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init(s, 0, 0, &info, &err), TS_OK);
    if (expect > 0) assert_close(info.area, expect, 1e-5 * expect, name);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 9, 1);
    int n = 200000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; i++) {
        ts_shape_point pt;
        assert_true(ts_shape_sample_area(s, 0, &info, u2(&rng), &pt));
        double pdf_at = ts_shape_pdf_area(s, 0, &info, pt.p);
        assert_close(pdf_at, pt.pdf, 1e-4 * pt.pdf, "pdf_area at the sample");
        double x = 1.0 / pt.pdf;
        sum += x, sum2 += x * x;
    }
    double mean = sum / n, sd = sqrt(fmax(0, sum2 / n - mean * mean) / n);
    print_message("area %-20s info %.7g, E[1/pdf] %.7g ± %.1e\n", name, info.area, mean, sd);
    assert_close(mean, info.area, 5 * sd + 1e-6 * info.area, name);
}

static void test_area_sampling(void **state)
{
    (void)state;
    ts_shape s = sphere((ts_vec3){1, 2, 3}, 0.7);
    check_area("sphere", &s, 4 * TS_PI_D * 0.49);
    ts_xform sc = ts_xform_scale((ts_dvec3){1.0, 2.0, 0.5});
    s.to_world = sc;
    /* Ellipsoid (0.7, 1.4, 0.35): no elementary closed form; info.area is checked
     * against the unbiased estimate alone. */
    check_area("ellipsoid", &s, 0);
    ts_shape d = disk((ts_vec3){0, 1, 0}, (ts_vec3){0, 1, 0}, 2.0, 0.5);
    check_area("annulus", &d, TS_PI_D * (4 - 0.25));
    d.to_world = ts_xform_compose(&sc, &d.to_world);
    check_area("scaled annulus", &d, 0);
    ts_shape c = cylinder((ts_vec3){0, 0, 0}, (ts_vec3){0, 3, 0}, 0.5);
    check_area("tube", &c, 2 * TS_PI_D * 0.5 * 3);
    c.to_world = ts_xform_compose(&sc, &c.to_world);
    check_area("scaled tube", &c, 0);
    ts_shape t = triangle(tri_p, tri_ix);
    check_area("triangle", &t, 0);

    /* The annulus sampler honours the inner radius: r² uniform on [ri², R²]. */
    ts_shape_sample_info info;
    ts_error err = {0};
    ts_shape a = disk((ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, 2.0, 0.5);
    assert_int_equal(ts_shape_sample_info_init(&a, 0, 0, &info, &err), TS_OK);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 4, 4);
    double m = 0;
    int n = 100000;
    for (int i = 0; i < n; i++) {
        ts_shape_point pt;
        assert_true(ts_shape_sample_area(&a, 0, &info, u2(&rng), &pt));
        double r2 = (double)pt.p.x * pt.p.x + (double)pt.p.y * pt.p.y;
        assert_true(r2 >= 0.25 * (1 - 1e-6) && r2 <= 4 * (1 + 1e-6));
        assert_close(pt.p.z, 0, 0, "in the plane");
        m += r2;
    }
    /* mean of r² = (0.25 + 4)/2, sd of r² = 3.75/√12 ≈ 1.08: 5σ/√n = 0.017. */
    assert_close(m / n, 2.125, 0.017, "annulus mean r²");
}

/* Tiny spheres: 1 − cos θ_max must come from the small-angle form: the pdf is
 * 1/(2π(1 − cosθ_max)) with 1 − cosθ_max = s/2 + s²/8 + …, s = (r/d)². */
static void test_tiny_sphere(void **state)
{
    (void)state;
    double radii[] = {1e-2, 1e-4, 1e-6};
    for (int k = 0; k < 3; k++) {
        ts_shape s = sphere((ts_vec3){0, 0, 0}, radii[k]);
        ctx c;
        ctx_init(&c, &s, 0, (ts_vec3){0, 0, 1});
        double s2 = radii[k] * radii[k];
        double omc = s2 / 2 + s2 * s2 / 8 + s2 * s2 * s2 / 16;
        double expect = 1 / (2 * TS_PI_D * omc);
        ts_pcg32 rng;
        ts_pcg32_seed(&rng, 2, 2);
        for (int i = 0; i < 1000; i++) {
            ts_shape_point pt;
            assert_true(ts_shape_sample_solid_angle(&s, 0, &c.info, &c.ref, u2(&rng), &pt));
            assert_true(isfinite(pt.pdf));
            assert_close(pt.pdf, expect, 1e-6 * expect, "tiny sphere pdf");
            /* The point is on the sphere, on the side facing ref. */
            assert_close(ts_vec3_length(pt.p), radii[k], 1e-5 * radii[k], "on the sphere");
            assert_true(pt.p.z >= -1e-7 * radii[k] || pt.n.z >= -1e-3);
            ts_vec3 wi = ts_vec3_normalize(ts_vec3_sub(pt.p, c.ref.p));
            double p = ts_shape_pdf_solid_angle(&s, 0, &c.info, &c.ref, wi);
            assert_close(p, expect, 1e-6 * expect, "tiny sphere pdf(wi)");
        }
        /* A direction well outside the cone has pdf 0. */
        assert_close(ts_shape_pdf_solid_angle(&s, 0, &c.info, &c.ref, (ts_vec3){0.05f, 0, -1}), 0, 0, "outside cone");
    }
}

/* Degenerate configurations stay finite: a reference point on the sphere itself, at a
 * triangle's vertex, coplanar with a disk or a triangle (no sample, pdf 0), a zero-area
 * triangle (no sample). */
static void test_edge_cases(void **state)
{
    (void)state;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 3);
    ts_shape s = sphere((ts_vec3){0, 0, 0}, 1.0);
    ts_vec3 on = ts_vec3_normalize((ts_vec3){0.3f, 0.4f, 0.5f});
    ctx c;
    ctx_init(&c, &s, 0, on);
    int produced = 0;
    for (int i = 0; i < 10000; i++) {
        ts_shape_point pt;
        if (!ts_shape_sample_solid_angle(&s, 0, &c.info, &c.ref, u2(&rng), &pt)) continue;
        produced++;
        assert_true(isfinite(pt.pdf) && pt.pdf > 0 && ts_vec3_is_finite(pt.p));
        ts_vec3 wi = ts_vec3_normalize(ts_vec3_sub(pt.p, on));
        float p = ts_shape_pdf_solid_angle(&s, 0, &c.info, &c.ref, wi);
        assert_true(isfinite(p) && p >= 0);
    }
    /* Samples whose point rounds onto ref are dropped (no light); most survive. */
    assert_true(produced > 5000);

    ts_shape t = triangle(tri_p, tri_ix);
    for (int v = 0; v < 3; v++) {
        ctx_init(&c, &t, TS_TRIANGLE_SAMPLING_SPHERICAL, (ts_vec3){tri_p[3 * v], tri_p[3 * v + 1], tri_p[3 * v + 2]});
        for (int i = 0; i < 1000; i++) {
            ts_shape_point pt;
            if (ts_shape_sample_solid_angle(&t, 0, &c.info, &c.ref, u2(&rng), &pt))
                assert_true(isfinite(pt.pdf) && pt.pdf > 0);
        }
    }
    /* Coplanar with the triangle, outside and inside it. */
    ts_vec3 a = {tri_p[0], tri_p[1], tri_p[2]}, b = {tri_p[3], tri_p[4], tri_p[5]}, cc = {tri_p[6], tri_p[7], tri_p[8]};
    ts_vec3 outside = ts_vec3_add(a, ts_vec3_scale(ts_vec3_sub(a, b), 0.7f));
    ts_vec3 inside = ts_vec3_scale(ts_vec3_add(a, ts_vec3_add(b, cc)), 1.0f / 3);
    ts_vec3 refs[2] = {outside, inside};
    for (int m = 0; m < 3; m++)
        for (int k = 0; k < 2; k++) {
            ctx_init(&c, &t, (ts_triangle_sampling)m, refs[k]);
            ts_shape_point pt;
            for (int i = 0; i < 100; i++) assert_false(ts_shape_sample_solid_angle(&t, 0, &c.info, &c.ref, u2(&rng), &pt));
            assert_true(ts_shape_pdf_solid_angle(&t, 0, &c.info, &c.ref, ts_vec3_sub(b, refs[k])) == 0);
            assert_true(ts_shape_pdf_solid_angle(&t, 0, &c.info, &c.ref, (ts_vec3){0, 0, 1}) == 0);
        }
    ts_shape d = disk((ts_vec3){0, 0, 0}, ts_vec3_normalize((ts_vec3){1, 1, 1}), 1.0, 0.0);
    ctx_init(&c, &d, 0, (ts_vec3){2, -1, -1});
    ts_shape_point pt;
    for (int i = 0; i < 100; i++) assert_false(ts_shape_sample_solid_angle(&d, 0, &c.info, &c.ref, u2(&rng), &pt));
    /* Zero-area triangle: area 0, never a sample, pdf 0. */
    static float zp[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    ts_shape z = triangle(zp, tri_ix);
    ctx_init(&c, &z, 0, (ts_vec3){0, 1, 0});
    assert_true(c.info.area == 0);
    for (int i = 0; i < 100; i++) {
        assert_false(ts_shape_sample_solid_angle(&z, 0, &c.info, &c.ref, u2(&rng), &pt));
        assert_false(ts_shape_sample_area(&z, 0, &c.info, u2(&rng), &pt));
    }
    assert_true(ts_shape_pdf_solid_angle(&z, 0, &c.info, &c.ref, (ts_vec3){1, 0, 1}) == 0);
}

/* ---- rectangles of two triangles (Ureña et al.'s spherical rectangles) ---- */

/* A w × h rectangle with corner c and edges along unit vectors ex, ey (orthogonal), as two
 * triangles (c, c+ex·w, c+ey·h) and (c+ex·w, c+ex·w+ey·h, c+ey·h) wound the same way: the
 * diagonal is shared, the builder's pairing. Vertices rounded to float. */
typedef struct rect_mesh {
    float p[12];
    uint32_t ix[6];
    ts_shape s;
} rect_mesh;

static void rect_mesh_make(rect_mesh *m, ts_dvec3 c, ts_dvec3 ex, ts_dvec3 ey, double w, double h)
{
    ts_dvec3 v[4] = {c, ts_dvec3_add(c, ts_dvec3_scale(ex, w)),
                     ts_dvec3_add(c, ts_dvec3_add(ts_dvec3_scale(ex, w), ts_dvec3_scale(ey, h))),
                     ts_dvec3_add(c, ts_dvec3_scale(ey, h))};
    for (int k = 0; k < 4; k++) {
        m->p[3 * k] = (float)v[k].x;
        m->p[3 * k + 1] = (float)v[k].y;
        m->p[3 * k + 2] = (float)v[k].z;
    }
    static const uint32_t ix[6] = {0, 1, 3, 1, 2, 3};
    memcpy(m->ix, ix, sizeof ix);
    m->s = (ts_shape){0};
    m->s.type = TS_SHAPE_MESH;
    m->s.to_world = ts_xform_identity();
    m->s.mesh.n_vertices = 4;
    m->s.mesh.n_triangles = 2;
    m->s.mesh.p = m->p;
    m->s.mesh.index = m->ix;
}

static ts_dvec3 vtx(const rect_mesh *m, int k) { return (ts_dvec3){m->p[3 * k], m->p[3 * k + 1], m->p[3 * k + 2]}; }

static void ctx_init_rect(ctx *c, const ts_shape *s, ts_triangle_sampling mode, ts_vec3 ref)
{
    c->s = s;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init_rect(s, 0, 1, mode, &c->info, &err), TS_OK);
    c->ref = ref_at(ref);
}

/* Solid angle of the part [s0, s1] × [t0, t1] (fractions of the edges) of the rectangle
 * from p: two Van Oosterom–Strackee triangles, a formula independent of the sampler's. */
static double sub_rect_omega(const ts_shape_sample_info *in, ts_dvec3 p, double s0, double s1, double t0, double t1)
{
    ts_dvec3 q[4];
    double ss[4] = {s0, s1, s1, s0}, tt[4] = {t0, t0, t1, t1};
    for (int k = 0; k < 4; k++)
        q[k] = ts_dvec3_add(in->tri_p[0], ts_dvec3_add(ts_dvec3_scale(in->rect_x, ss[k] * in->rect_w),
                                                       ts_dvec3_scale(in->rect_y, tt[k] * in->rect_h)));
    return ts_spherical_triangle_area(q[0], q[1], q[2], p) + ts_spherical_triangle_area(q[0], q[2], q[3], p);
}

/* χ² over a G × G grid of the rectangle's area: the samples' points binned by their edge
 * fractions, expected counts N·Ω(cell)/Ω with Ω(cell) by sub_rect_omega. Uniform in solid
 * angle is exactly this. G = 8 (64 cells, 63 dof), N = 10^6: the smallest expected count
 * at these receivers is 24 (close over a corner, whose far cells subtend little) and
 * > 1000 elsewhere, where Pearson's statistic is χ²-distributed well into the tail used. Each case is one test of the project's χ² family (tests/chi2.h: the
 * Šidák threshold of TS_CHI2_FAMILY_SIZE tests, whole-suite false-failure rate ≤ 0.01);
 * seeds fixed. Also: each pdf is 1/Ω with Ω = Σ Ω(cell) to 1e-9 relative. */
static void rect_grid_chi2(const char *name, const rect_mesh *m, ts_vec3 ref, uint64_t seed)
{
    enum { G = 8 };
    ctx c;
    ctx_init_rect(&c, &m->s, TS_TRIANGLE_SAMPLING_SPHERICAL, ref);
    ts_dvec3 p = ts_dvec3_from(ref);
    double cell[G * G], omega = 0;
    for (int i = 0; i < G; i++)
        for (int j = 0; j < G; j++) {
            cell[i * G + j] = sub_rect_omega(&c.info, p, (double)i / G, (double)(i + 1) / G, (double)j / G,
                                             (double)(j + 1) / G);
            omega += cell[i * G + j];
        }
    assert_close(ts_spherical_rectangle_area(&c.info, p), omega, 1e-9 * omega, "Ω by Ureña's angles vs cells");
    uint64_t count[G * G] = {0};
    const uint64_t n = 1000000;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, seed, 1);
    for (uint64_t i = 0; i < n; i++) {
        ts_shape_point pt;
        if (!ts_shape_sample_solid_angle(&m->s, 0, &c.info, &c.ref, u2(&rng), &pt))
            fail_msg("%s: no sample", name);
        assert_true(isfinite(pt.pdf));
        if (!(fabs(pt.pdf * omega - 1) <= 1e-6)) fail_msg("%s: pdf %.9g, 1/Ω %.9g", name, pt.pdf, 1 / omega);
        ts_dvec3 d = ts_dvec3_sub(ts_dvec3_from(pt.p), c.info.tri_p[0]);
        double fs = ts_dvec3_dot(d, c.info.rect_x) / c.info.rect_w, ft = ts_dvec3_dot(d, c.info.rect_y) / c.info.rect_h;
        int bi = (int)floor(fs * G), bj = (int)floor(ft * G);
        /* a point on the far edge (float rounding) belongs to the last cell */
        if (bi == G && fs < 1 + 1e-6) bi = G - 1;
        if (bj == G && ft < 1 + 1e-6) bj = G - 1;
        if (bi == -1 && fs > -1e-6) bi = 0;
        if (bj == -1 && ft > -1e-6) bj = 0;
        if (bi < 0 || bi >= G || bj < 0 || bj >= G) fail_msg("%s: sample off the rectangle (%g, %g)", name, fs, ft);
        count[bi * G + bj]++;
    }
    double chi2 = 0, emin = INFINITY;
    for (int k = 0; k < G * G; k++) {
        double e = (double)n * cell[k] / omega;
        emin = fmin(emin, e);
        chi2 += ((double)count[k] - e) * ((double)count[k] - e) / e;
    }
    double pv = ts_chi2_upper_tail(chi2, G * G - 1), th = ts_chi2_sidak(0.01, TS_CHI2_FAMILY_SIZE);
    print_message("rect grid chi2 %-30s Ω %.6g sr, χ² %.1f (63 dof), p %.4f (threshold %.2e), smallest expected %.0f\n",
                  name, omega, chi2, pv, th, emin);
    assert_true(emin >= 5);
    if (!(pv >= th)) fail_msg("%s: χ² %.1f, p %.3g < %.3g", name, chi2, pv, th);
}

/* The rectangle of these tests: 1.5 × 0.8, turned out of the axes, corner off the origin. */
static void test_rect(rect_mesh *m)
{
    ts_dvec3 ex = ts_dvec3_normalize((ts_dvec3){0.8, 0.6, 0}), ey = ts_dvec3_normalize((ts_dvec3){-0.36, 0.48, 0.8});
    rect_mesh_make(m, (ts_dvec3){0.3, -0.2, 0.5}, ex, ey, 1.5, 0.8);
}

/* Receivers, in the rectangle's edge fractions (s, t) and height above it (along
 * ex × ey; negative: behind): over the centre, off to the side, near the plane beside it,
 * grazing (far out, little above), close over a corner, behind. */
static ts_vec3 rect_receiver(const ctx *c, double s, double t, double z)
{
    ts_dvec3 n = ts_dvec3_cross(c->info.rect_x, c->info.rect_y);
    ts_dvec3 p = ts_dvec3_add(c->info.tri_p[0], ts_dvec3_add(ts_dvec3_scale(c->info.rect_x, s * c->info.rect_w),
                                                             ts_dvec3_scale(c->info.rect_y, t * c->info.rect_h)));
    return ts_dvec3_to_vec3(ts_dvec3_add(p, ts_dvec3_scale(n, z)));
}

static const double rect_refs[6][3] = {{0.5, 0.5, 0.7}, {1.8, 0.4, 0.6}, {1.2, 0.5, 0.05},
                                       {4.0, 2.5, 0.1}, {0.02, 0.03, 0.02}, {0.3, 0.6, -0.9}};
static const char *rect_ref_names[6] = {"over the centre", "off to the side", "near the plane", "grazing",
                                        "close over a corner", "behind"};

static void test_rectangle_grid_chi2(void **state)
{
    (void)state;
    rect_mesh m;
    test_rect(&m);
    ctx c;
    ctx_init_rect(&c, &m.s, TS_TRIANGLE_SAMPLING_SPHERICAL, (ts_vec3){0, 0, 0});
    for (int k = 0; k < 6; k++)
        rect_grid_chi2(rect_ref_names[k], &m, rect_receiver(&c, rect_refs[k][0], rect_refs[k][1], rect_refs[k][2]),
                       61 + (uint64_t)k);
}

/* The direction χ² of every shape (tests/chi2.h over the sphere), ∫pdf against the first-
 * hit fraction, and sample pdf = pdf(wi) = pdf(p) (the MIS side, which intersects both
 * triangles), for the rectangle light in each mode. */
static void test_rectangle(void **state)
{
    (void)state;
    rect_mesh m;
    test_rect(&m);
    ctx c;
    ctx_init_rect(&c, &m.s, TS_TRIANGLE_SAMPLING_SPHERICAL, (ts_vec3){0, 0, 0});
    ts_vec3 centre = rect_receiver(&c, 0.5, 0.5, 0.7), side = rect_receiver(&c, 1.8, 0.4, 0.6);
    ts_vec3 corner = rect_receiver(&c, 0.02, 0.03, 0.02);
    const struct {
        const char *name;
        ts_triangle_sampling mode;
        ts_vec3 ref;
    } cases[] = {
        {"rectangle spherical, over it", TS_TRIANGLE_SAMPLING_SPHERICAL, centre},
        {"rectangle spherical, to the side", TS_TRIANGLE_SAMPLING_SPHERICAL, side},
        {"rectangle spherical, at a corner", TS_TRIANGLE_SAMPLING_SPHERICAL, corner},
        {"rectangle area, over it", TS_TRIANGLE_SAMPLING_AREA, centre},
        {"rectangle auto, to the side", TS_TRIANGLE_SAMPLING_AUTO, side},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        ctx_init_rect(&c, &m.s, cases[k].mode, cases[k].ref);
        run_chi2(cases[k].name, &c, 71 + k, false);
        check_consistency(cases[k].name, &c, 20000);
    }
    /* A hit on either triangle has the whole rectangle's pdf 1/Ω. */
    ctx_init_rect(&c, &m.s, TS_TRIANGLE_SAMPLING_SPHERICAL, centre);
    double omega = ts_spherical_rectangle_area(&c.info, ts_dvec3_from(centre));
    ts_dvec3 in_a = ts_dvec3_scale(ts_dvec3_add(ts_dvec3_add(vtx(&m, 0), vtx(&m, 1)), vtx(&m, 3)), 1.0 / 3);
    ts_dvec3 in_b = ts_dvec3_scale(ts_dvec3_add(ts_dvec3_add(vtx(&m, 1), vtx(&m, 2)), vtx(&m, 3)), 1.0 / 3);
    ts_dvec3 hits[2] = {in_a, in_b};
    for (int k = 0; k < 2; k++) {
        float pa = ts_shape_pdf_solid_angle_at(&m.s, 0, &c.info, &c.ref, ts_dvec3_to_vec3(hits[k]));
        float pw = ts_shape_pdf_solid_angle(&m.s, 0, &c.info, &c.ref,
                                            ts_dvec3_to_vec3(ts_dvec3_sub(hits[k], ts_dvec3_from(centre))));
        assert_close(pa * omega, 1, 1e-6, "pdf at a hit = 1/Ω");
        assert_close(pw * omega, 1, 1e-6, "pdf along a ray = 1/Ω");
    }
}

/* Ω of a rectangle a × b seen from a point at height c over one corner has the closed
 * form atan(ab / (c√(a² + b² + c²))); by superposition of four such rectangles, any point
 * over the rectangle. */
static double corner_omega(double a, double b, double c) { return atan(a * b / (c * sqrt(a * a + b * b + c * c))); }

static void test_rectangle_solid_angle(void **state)
{
    (void)state;
    rect_mesh m;
    rect_mesh_make(&m, (ts_dvec3){0, 0, 0}, (ts_dvec3){1, 0, 0}, (ts_dvec3){0, 1, 0}, 1.5, 0.75);
    ts_shape_sample_info in;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init_rect(&m.s, 0, 1, 0, &in, &err), TS_OK);
    assert_close(in.area, 1.125, 1e-12, "area");
    double hs[4] = {1e-3, 0.1, 1, 100};
    for (int k = 0; k < 4; k++) {
        double h = hs[k];
        /* over the corner, and over (0.5, 0.25) (four corner rectangles), from either side */
        assert_close(ts_spherical_rectangle_area(&in, (ts_dvec3){0, 0, h}), corner_omega(1.5, 0.75, h),
                     1e-12 * corner_omega(1.5, 0.75, h) + 4e-15, "Ω over a corner");
        double inner = corner_omega(0.5, 0.25, h) + corner_omega(1.0, 0.25, h) + corner_omega(0.5, 0.5, h) +
                       corner_omega(1.0, 0.5, h);
        assert_close(ts_spherical_rectangle_area(&in, (ts_dvec3){0.5, 0.25, -h}), inner, 1e-12 * inner + 4e-15,
                     "Ω over an inner point");
    }
}

/* Which pairs are rectangles (ts_shape_triangles_rectangle). */
static void test_rectangle_detection(void **state)
{
    (void)state;
    rect_mesh m;
    test_rect(&m); /* turned, vertices rounded to float: within the rounding tolerance */
    assert_true(ts_shape_triangles_rectangle(&m.s, 0, 1));
    assert_true(ts_shape_triangles_rectangle(&m.s, 1, 0));
    /* The Cornell box's light, as the shipped scene writes it (indices 0 1 2, 0 2 3). */
    static float cb[12] = {343, 548.8f, 227, 343, 548.8f, 332, 213, 548.8f, 332, 213, 548.8f, 227};
    static uint32_t cbi[6] = {0, 1, 2, 0, 2, 3};
    ts_shape s = m.s;
    s.mesh.p = cb;
    s.mesh.index = cbi;
    assert_true(ts_shape_triangles_rectangle(&s, 0, 1));
    ts_shape_sample_info in;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init_rect(&s, 0, 1, 0, &in, &err), TS_OK);
    assert_close(in.area, 130.0 * 105.0, 1e-9, "Cornell light area");
    assert_true(in.rect_defect.x == 0 && in.rect_defect.y == 0 && in.rect_defect.z == 0);
    /* Not rectangles: a parallelogram with a 60° corner, a trapezoid, a bent pair (fourth
     * vertex 1e-3 out of the plane), the second triangle wound the other way, two triangles
     * without a shared edge; the unit square's fourth corner moved by 2^-20 (beyond the
     * rounding allowance 2^-21·M, M = 1) but not by 2^-22; a 2^-10 square at x = 100 whose
     * fourth corner is one float ulp (2^-17) off: within 2^-21·M but beyond 2^-16 of its
     * edge. */
    float p[12];
    uint32_t ix[6];
    s.mesh.p = p;
    s.mesh.index = ix;
    static const float base[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    static const uint32_t bix[6] = {0, 1, 2, 0, 2, 3};
    struct {
        const char *name;
        int vertex;
        float dx, dy, dz;
        bool flip, expect;
    } cases[] = {
        {"square", 0, 0, 0, 0, false, true},
        {"parallelogram 60°", 2, 0.57735f, 0, 0, false, false},
        {"trapezoid", 2, 0.25f, 0, 0, false, false},
        {"bent", 2, 0, 0, 1e-3f, false, false},
        {"opposite windings", 0, 0, 0, 0, true, false},
        {"fourth corner off by 2^-20", 3, 0x1p-20f, 0, 0, false, false},
        {"fourth corner off by 2^-22", 3, 0x1p-22f, 0, 0, false, true},
        {"small square far out, 1 ulp", 3, 0x1p-17f, 0, 0, false, false},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        memcpy(p, base, sizeof p);
        memcpy(ix, bix, sizeof ix);
        if (k == 1) p[3 * 3] += 0.57735f; /* the parallelogram: both far vertices shift */
        if (k == 7) /* 2^-10 square at x = 100 */
            for (int v = 0; v < 4; v++) {
                p[3 * v] = 100 + p[3 * v] * 0x1p-10f;
                p[3 * v + 1] *= 0x1p-10f;
            }
        p[3 * cases[k].vertex] += cases[k].dx;
        p[3 * cases[k].vertex + 1] += cases[k].dy;
        p[3 * cases[k].vertex + 2] += cases[k].dz;
        if (cases[k].flip) ix[4] = 3, ix[5] = 2;
        bool got = ts_shape_triangles_rectangle(&s, 0, 1);
        print_message("rectangle detection: %-28s %s\n", cases[k].name, got ? "rectangle" : "two triangles");
        if (got != cases[k].expect) fail_msg("%s: detected %d, expected %d", cases[k].name, got, cases[k].expect);
        if (!got) assert_int_equal(ts_shape_sample_info_init_rect(&s, 0, 1, 0, &in, &err), TS_ERR_INVALID);
    }
    memcpy(p, base, sizeof p);
    static const uint32_t apart[6] = {0, 1, 2, 0, 3, 1}; /* share 0–1 and… only an edge that is not a diagonal */
    memcpy(ix, apart, sizeof ix);
    assert_false(ts_shape_triangles_rectangle(&s, 0, 1));
    static const uint32_t same[6] = {0, 1, 2, 0, 1, 2};
    memcpy(ix, same, sizeof ix);
    assert_false(ts_shape_triangles_rectangle(&s, 0, 1));
}

/* Degenerate views stay finite: on the plane (inside and outside the rectangle: no sample,
 * pdf 0), at a corner and on an edge, from very far (Ω ~ 1e-10: area sampling), almost on
 * it (Ω → 2π: area sampling past 6.22 sr), and at u on the square's edges; every point
 * returned is on the rectangle (edge fractions in [0, 1]). */
static void test_rectangle_edge_cases(void **state)
{
    (void)state;
    rect_mesh m;
    test_rect(&m);
    ctx c;
    ctx_init_rect(&c, &m.s, TS_TRIANGLE_SAMPLING_SPHERICAL, (ts_vec3){0, 0, 0});
    const double r[][3] = {{0.5, 0.5, 0},    {2, 0.5, 0},      {0, 0, 0},        {1, 1, 0},       {0.5, 0, 1e-7},
                           {0.5, 0.5, 1e-6}, {0.5, 0.5, 1e-3}, {0, 0, 1e-4},     {3e4, 2e4, 1e3}, {0.5, 0.5, 1e5},
                           {1, 0.5, 1e-5},   {-1e-4, 0.5, 0.3}, {0.5, 1, -1e-6}, {1e3, 0.5, 1e-3}};
    const float us[] = {0, 1e-7f, 0.5f, 0x1.fffffep-1f};
    int produced = 0;
    for (size_t k = 0; k < sizeof r / sizeof *r; k++)
        for (int mode = 0; mode < 3; mode++) {
            ts_vec3 ref = rect_receiver(&c, r[k][0], r[k][1], r[k][2]);
            ctx e;
            ctx_init_rect(&e, &m.s, (ts_triangle_sampling)mode, ref);
            double om = ts_spherical_rectangle_area(&e.info, ts_dvec3_from(ref));
            assert_true(isfinite(om) && om >= 0 && om <= 2 * TS_PI_D + 1e-12);
            for (int i = 0; i < 4; i++)
                for (int j = 0; j < 4; j++) {
                    ts_shape_point pt;
                    if (!ts_shape_sample_solid_angle(&m.s, 0, &e.info, &e.ref, (ts_vec2){us[i], us[j]}, &pt)) continue;
                    produced++;
                    assert_true(isfinite(pt.pdf) && pt.pdf > 0 && ts_vec3_is_finite(pt.p) && ts_vec3_is_finite(pt.p_error));
                    ts_dvec3 d = ts_dvec3_sub(ts_dvec3_from(pt.p), e.info.tri_p[0]);
                    double fs = ts_dvec3_dot(d, e.info.rect_x) / e.info.rect_w;
                    double ft = ts_dvec3_dot(d, e.info.rect_y) / e.info.rect_h;
                    assert_true(fs >= -1e-6 && fs <= 1 + 1e-6 && ft >= -1e-6 && ft <= 1 + 1e-6);
                    float pw = ts_shape_pdf_solid_angle(&m.s, 0, &e.info, &e.ref, ts_vec3_sub(pt.p, ref));
                    float ph = ts_shape_pdf_solid_angle_at(&m.s, 0, &e.info, &e.ref, pt.p);
                    assert_true(isfinite(pw) && pw >= 0 && isfinite(ph) && ph >= 0);
                }
            if (r[k][2] == 0) { /* on the plane */
                assert_true(ts_shape_pdf_solid_angle(&m.s, 0, &e.info, &e.ref, (ts_vec3){0, 0, 1}) == 0);
                ts_shape_point pt;
                assert_false(ts_shape_sample_solid_angle(&m.s, 0, &e.info, &e.ref, (ts_vec2){0.3f, 0.6f}, &pt));
            }
        }
    assert_true(produced > 300);
    /* The sampler itself, straight: u over a 64² grid with its edges from a point 1e-9
     * over the centre and one 1e-9 beside an edge; finite and on the rectangle. */
    ts_vec3 near[2] = {rect_receiver(&c, 0.5, 0.5, 1e-9), rect_receiver(&c, 1 + 1e-9, 0.5, 0.2)};
    for (int k = 0; k < 2; k++)
        for (int i = 0; i <= 64; i++)
            for (int j = 0; j <= 64; j++) {
                ts_vec2 u = {fminf(i / 64.0f, 0x1.fffffep-1f), fminf(j / 64.0f, 0x1.fffffep-1f)};
                ts_dvec3 q;
                double om;
                if (!ts_spherical_rectangle_sample(&c.info, ts_dvec3_from(near[k]), u, &q, &om)) continue;
                assert_true(isfinite(q.x) && isfinite(q.y) && isfinite(q.z) && om > 0 && isfinite(om));
            }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere),
        cmocka_unit_test(test_aligned),
        cmocka_unit_test(test_disk_cylinder),
        cmocka_unit_test(test_triangle),
        cmocka_unit_test(test_spherical_triangle_closed_form),
        cmocka_unit_test(test_area_sampling),
        cmocka_unit_test(test_tiny_sphere),
        cmocka_unit_test(test_edge_cases),
        cmocka_unit_test(test_rectangle_detection),
        cmocka_unit_test(test_rectangle_solid_angle),
        cmocka_unit_test(test_rectangle_grid_chi2),
        cmocka_unit_test(test_rectangle),
        cmocka_unit_test(test_rectangle_edge_cases),
    };
    if (getenv("TS_TEST_FILTER")) cmocka_set_test_filter(getenv("TS_TEST_FILTER")); /* e.g. "test_rectangle*" */
    return cmocka_run_group_tests(tests, NULL, NULL);
}
