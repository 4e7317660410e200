/* test_shape_partial.c — pbrt-v3's partial quadrics (geometry/shape.h): their areas, their
 * intersection at the cut edges with pbrt-v3's (u, v) and ∂p/∂u, ∂p/∂v, their sampling as
 * area lights, and the builder's clamping and refusals.
 *
 * Statistics. Both Monte Carlo checks use independent samples (PCG32, fixed seeds), so the
 * standard error of a mean is the sample standard deviation over √N, and every bound is
 * 4 standard errors: a correct implementation fails one comparison with probability
 * 6.3e-5 (two-sided normal tail; N ≥ 2^19 makes the mean normal to far better than that),
 * i.e. about 1e-3 for the 15 comparisons of this file together.
 *   - Area by hit-testing (Cauchy–Crofton): isotropic uniform lines meeting a ball of
 *     radius R cross a surface of area A inside it A / (2πR²) times on average, so
 *     A = 2πR²·E[crossings]. Crossings are counted with ts_shape_intersect along the line.
 *   - Irradiance E = ∫ L cosθ dω from a partial emitter through ts_light_sample_li, against
 *     a tensor Gauss–Legendre quadrature of L cosθ_ref cosθ_o / d² dA over the shape's
 *     parameter domain (smooth, no singularity: the reference point is off the surface),
 *     whose error is below 1e-12 relative (it agrees with twice the order to that). Each
 *     case is chosen so that every point of the emitter is seen from its front side and
 *     unoccluded, so no shadow ray is needed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/hash.h"
#include "geometry/shape.h"
#include "geometry/shape_sample.h"
#include "lights/light.h"
#include "geometry/accel.h"
#include "build/scene_builder.h"

static double rnd(ts_pcg32 *g) { return ts_pcg32_double(g); }

/* A partial analytic shape as the builder stores it (scene_builder.c, place_analytic). */
static ts_shape sphere_cut(double r, double z0, double z1, double phi_deg, ts_xform x)
{
    ts_shape s;
    memset(&s, 0, sizeof s);
    s.type = TS_SHAPE_SPHERE;
    s.to_world = x;
    s.sphere.radius = r;
    s.partial = true;
    s.phi_max = phi_deg * TS_PI_D / 180;
    s.sphere.z_min = z0, s.sphere.z_max = z1;
    s.sphere.theta_min = acos(z0 / r), s.sphere.theta_max = acos(z1 / r);
    return s;
}

static ts_shape disk_cut(double r, double ri, double phi_deg, ts_xform x)
{
    ts_shape s;
    memset(&s, 0, sizeof s);
    s.type = TS_SHAPE_DISK;
    s.to_world = x;
    s.disk.radius = r, s.disk.inner_radius = ri;
    s.partial = true;
    s.phi_max = phi_deg * TS_PI_D / 180;
    return s;
}

static ts_shape cylinder_cut(double r, double h, double phi_deg, ts_xform x)
{
    ts_shape s;
    memset(&s, 0, sizeof s);
    s.type = TS_SHAPE_CYLINDER;
    s.to_world = x;
    s.cylinder.radius = r, s.cylinder.height = h;
    s.partial = true;
    s.phi_max = phi_deg * TS_PI_D / 180;
    return s;
}

static ts_xform rot_scale(double s, ts_dvec3 t)
{
    ts_xform a = ts_xform_translate(t), b = ts_xform_rotate(37, (ts_dvec3){1, 2, 3}), c = ts_xform_scale((ts_dvec3){s, s, s});
    ts_xform ab = ts_xform_compose(&a, &b);
    return ts_xform_compose(&ab, &c);
}

static ts_xform aniso(void)
{
    ts_xform a = ts_xform_rotate(20, (ts_dvec3){0, 1, 1}), b = ts_xform_scale((ts_dvec3){1.5, 0.8, 1.2});
    return ts_xform_compose(&a, &b);
}

/* ---- area by Cauchy–Crofton ---- */

static int crossings(const ts_shape *s, ts_ray r)
{
    int n = 0;
    for (int k = 0; k < 8; k++) {
        float t;
        if (!ts_shape_intersect(s, &r, INFINITY, &t)) break;
        ts_interaction si;
        ts_shape_interaction(s, 0, 0, &r, t, &si);
        n++;
        r = ts_spawn_ray(&si, NULL, r.d);
    }
    return n;
}

/* Mean crossings·2πR² and its standard error over n isotropic lines meeting the ball
 * (centre c, radius R) around the shape. */
static void crofton(const ts_shape *s, ts_dvec3 c, double R, int n, uint64_t seed, double *mean, double *se)
{
    ts_pcg32 g;
    ts_pcg32_seed(&g, seed, 7);
    double sum = 0, sum2 = 0, k = 2 * TS_PI_D * R * R;
    for (int i = 0; i < n; i++) {
        double z = 1 - 2 * rnd(&g), ph = 2 * TS_PI_D * rnd(&g), sr = sqrt(fmax(0, 1 - z * z));
        ts_dvec3 d = {sr * cos(ph), sr * sin(ph), z}, a, b;
        ts_vec3 af, bf;
        ts_coordinate_system(ts_dvec3_to_vec3(d), &af, &bf);
        a = ts_dvec3_from(af), b = ts_dvec3_from(bf);
        double rr = R * sqrt(rnd(&g)), pa = 2 * TS_PI_D * rnd(&g);
        ts_dvec3 o = ts_dvec3_add(c, ts_dvec3_add(ts_dvec3_scale(a, rr * cos(pa)), ts_dvec3_scale(b, rr * sin(pa))));
        o = ts_dvec3_sub(o, ts_dvec3_scale(d, 2 * R));
        double x = k * crossings(s, ts_ray_make(ts_dvec3_to_vec3(o), ts_dvec3_to_vec3(d), INFINITY));
        sum += x, sum2 += x * x;
    }
    *mean = sum / n;
    *se = sqrt(fmax(0, sum2 / n - *mean * *mean) / (n - 1));
}

static void check_area(const char *what, const ts_shape *s, ts_dvec3 c, double R, double exact, uint64_t seed)
{
    double mean, se;
    crofton(s, c, R, 1 << 19, seed, &mean, &se);
    double a = ts_shape_area(s, 0);
    ts_shape_sample_info info;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init(s, 0, TS_TRIANGLE_SAMPLING_AUTO, &info, &err), TS_OK);
    if (!(fabs(mean - a) <= 4 * se))
        fail_msg("%s: hit-testing area %.6g ± %.2g, ts_shape_area %.6g (%.1f standard errors)", what, mean, se, a,
                 (mean - a) / se);
    if (!(fabs(info.area - a) <= 1e-9 * a)) fail_msg("%s: sample info area %.12g, shape area %.12g", what, info.area, a);
    if (exact > 0 && !(fabs(a - exact) <= 1e-9 * exact))
        fail_msg("%s: area %.12g, pbrt-v3's formula %.12g", what, a, exact);
}

static void test_area_by_hit_testing(void **state)
{
    (void)state;
    ts_xform id = ts_xform_identity(), sim = rot_scale(1.7, (ts_dvec3){0.3, -0.2, 0.5}), an = aniso();
    /* pbrt-v3: sphere φmax·r·(zmax − zmin), disk φmax/2·(r² − ri²), cylinder φmax·r·h. */
    double ph = 250 * TS_PI_D / 180;
    ts_shape s = sphere_cut(1, -0.4, 0.7, 250, id);
    check_area("sphere", &s, (ts_dvec3){0, 0, 0}, 1.05, ph * 1 * 1.1, 11);
    s = sphere_cut(1, -0.4, 0.7, 250, sim);
    check_area("sphere, similarity", &s, ts_xform_point(&sim, (ts_dvec3){0, 0, 0}), 1.8, ph * 1.1 * 1.7 * 1.7, 12);
    s = sphere_cut(1, -0.4, 0.7, 250, an);
    check_area("sphere, non-uniform scale", &s, (ts_dvec3){0, 0, 0}, 1.6, 0, 13);
    ts_shape d = disk_cut(1, 0.35, 200, id);
    double pd = 200 * TS_PI_D / 180;
    check_area("disk", &d, (ts_dvec3){0, 0, 0}, 1.05, pd / 2 * (1 - 0.35 * 0.35), 14);
    d = disk_cut(1, 0.35, 200, an);
    check_area("disk, non-uniform scale", &d, (ts_dvec3){0, 0, 0}, 1.6, 0, 15);
    double pc = 120 * TS_PI_D / 180;
    ts_shape c = cylinder_cut(0.6, 1.5, 120, id);
    check_area("cylinder", &c, (ts_dvec3){0, 0, 0.75}, 1.0, pc * 0.6 * 1.5, 16);
    c = cylinder_cut(0.6, 1.5, 120, an);
    check_area("cylinder, non-uniform scale", &c, ts_xform_point(&an, (ts_dvec3){0, 0, 0.75}), 1.6, 0, 17);
}

/* The midpoint rule of shape.c's partial_area against a 4× finer one, under a non-uniform
 * scale (its stated 1e-6). */
static void test_area_quadrature(void **state)
{
    (void)state;
    ts_shape s = sphere_cut(1, -0.4, 0.7, 250, aniso());
    double a = ts_shape_area(&s, 0);
    const int nz = 1024, np = 2048;
    double sum = 0;
    const double(*m)[4] = s.to_world.m.m;
    double d3 = fabs(m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]));
    for (int i = 0; i < nz; i++) {
        double z = -0.4 + (i + 0.5) * 1.1 / nz, ring = sqrt(1 - z * z);
        for (int k = 0; k < np; k++) {
            double ph = (k + 0.5) * s.phi_max / np;
            sum += d3 * ts_dvec3_length(ts_xform_normal(&s.to_world, (ts_dvec3){ring * cos(ph), ring * sin(ph), z}));
        }
    }
    double fine = ts_shape_object_area(&s) * sum / ((double)nz * np);
    if (!(fabs(a - fine) <= 1e-6 * fine)) fail_msg("partial sphere area %.12g, finer quadrature %.12g", a, fine);
}

/* ---- intersection at the cut edges ---- */

static void hit(const ts_shape *s, ts_vec3 o, ts_vec3 d, bool expect, double t_expect, const char *what)
{
    ts_ray r = ts_ray_make(o, d, INFINITY);
    float t;
    bool h = ts_shape_intersect(s, &r, INFINITY, &t);
    if (h != expect) fail_msg("%s: %s", what, h ? "hit, expected a miss" : "missed, expected a hit");
    if (h && !(fabs(t - t_expect) <= 1e-5 * fabs(t_expect)))
        fail_msg("%s: t = %.9g, expected %.9g", what, t, t_expect);
}

static void test_cut_edges(void **state)
{
    (void)state;
    ts_xform id = ts_xform_identity();
    const double e = 1e-4;
    /* Sphere r = 1, z ∈ [−0.5, 0.6], φ ∈ [0, 270°]. A ray along −x at height z, y = 0
     * meets x = +√(1−z²) (φ = 0) first, then x = −√(1−z²) (φ = 180°). */
    ts_shape s = sphere_cut(1, -0.5, 0.6, 270, id);
    for (int k = 0; k < 2; k++) {
        double z = k ? 0.6 - e : -0.5 + e, x = sqrt(1 - z * z);
        hit(&s, (ts_vec3){5, 0, (float)z}, (ts_vec3){-1, 0, 0}, true, 5 - x, "sphere just inside the z cut");
        z = k ? 0.6 + e : -0.5 - e;
        hit(&s, (ts_vec3){5, 0, (float)z}, (ts_vec3){-1, 0, 0}, false, 0, "sphere just outside the z cut");
    }
    /* φ cut (270°): a ray along +y at x = cos(270° ± δ), from y = −5. Its near root is at
     * y = −√(1−x²), φ = 270° ± δ: kept below 270°; beyond, the far root (φ near 90°). */
    for (int k = 0; k < 2; k++) {
        double phi = 1.5 * TS_PI_D + (k ? e : -e), x = cos(phi), y = -sqrt(1 - x * x);
        hit(&s, (ts_vec3){(float)x, -5, 0}, (ts_vec3){0, 1, 0}, true, k ? 5 - y : 5 + y,
            k ? "sphere beyond phi_max: the far root" : "sphere within phi_max: the near root");
    }
    /* Ray from inside the bowl (the second root is the only one ahead). */
    hit(&s, (ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 1}, false, 0, "sphere: up through the cut top");
    hit(&s, (ts_vec3){0, 0, 0}, (ts_vec3){1, 0, 0}, true, 1, "sphere: from the centre outwards");

    /* Disk r = 1, ri = 0.3, φ ∈ [0, 90°]: rays down −z. */
    ts_shape d = disk_cut(1, 0.3, 90, id);
    double a_in = (90 - 0.01) * TS_PI_D / 180, a_out = (90 + 0.01) * TS_PI_D / 180;
    hit(&d, (ts_vec3){(float)(0.6 * cos(a_in)), (float)(0.6 * sin(a_in)), 2}, (ts_vec3){0, 0, -1}, true, 2, "disk within phi_max");
    hit(&d, (ts_vec3){(float)(0.6 * cos(a_out)), (float)(0.6 * sin(a_out)), 2}, (ts_vec3){0, 0, -1}, false, 0, "disk beyond phi_max");
    hit(&d, (ts_vec3){0.6f, (float)-e, 2}, (ts_vec3){0, 0, -1}, false, 0, "disk below phi = 0");
    hit(&d, (ts_vec3){0.6f, (float)e, 2}, (ts_vec3){0, 0, -1}, true, 2, "disk above phi = 0");

    /* Cylinder r = 1, h = 2, φ ∈ [0, 120°]: a ray along −x at y = sin φ meets φ then 180° − φ. */
    ts_shape c = cylinder_cut(1, 2, 120, id);
    double p1 = 30 * TS_PI_D / 180; /* 30° and 150°: near kept, far cut away */
    hit(&c, (ts_vec3){5, (float)sin(p1), 1}, (ts_vec3){-1, 0, 0}, true, 5 - cos(p1), "cylinder: near root kept");
    double p2 = (60 + 0.01) * TS_PI_D / 180; /* 60.01° and 119.99°: both kept */
    hit(&c, (ts_vec3){-5, (float)sin(p2), 1}, (ts_vec3){1, 0, 0}, true, 5 + cos(M_PI - p2), "cylinder: near root 119.99°");
    double p3 = (60 - 0.01) * TS_PI_D / 180; /* from −x: first 120.01° (cut), then 59.99° (kept) */
    hit(&c, (ts_vec3){-5, (float)sin(p3), 1}, (ts_vec3){1, 0, 0}, true, 5 + cos(p3), "cylinder: near root cut, far root");
    hit(&c, (ts_vec3){5, -0.5f, 1}, (ts_vec3){-1, 0, 0}, false, 0, "cylinder: both roots cut");
}

/* pbrt-v3's (u, v) and ∂p/∂u, ∂p/∂v at hits, against the parameterisation differenced
 * numerically: P(u, v) in object space, mapped by the shape's transform. */
static ts_dvec3 param_point(const ts_shape *s, double u, double v)
{
    double phi = u * s->phi_max;
    ts_dvec3 p;
    switch (s->type) {
    case TS_SHAPE_SPHERE: {
        double th = s->sphere.theta_min + v * (s->sphere.theta_max - s->sphere.theta_min), r = s->sphere.radius;
        p = (ts_dvec3){r * sin(th) * cos(phi), r * sin(th) * sin(phi), r * cos(th)};
        break;
    }
    case TS_SHAPE_DISK: {
        double rr = s->disk.radius - v * (s->disk.radius - s->disk.inner_radius);
        p = (ts_dvec3){rr * cos(phi), rr * sin(phi), 0};
        break;
    }
    default: p = (ts_dvec3){s->cylinder.radius * cos(phi), s->cylinder.radius * sin(phi), v * s->cylinder.height};
    }
    return ts_xform_point(&s->to_world, p);
}

static void check_param(const ts_shape *s, uint64_t seed, const char *what)
{
    ts_pcg32 g;
    ts_pcg32_seed(&g, seed, 3);
    ts_shape_sample_info info;
    ts_error err = {0};
    assert_int_equal(ts_shape_sample_info_init(s, 0, TS_TRIANGLE_SAMPLING_AUTO, &info, &err), TS_OK);
    for (int i = 0; i < 200; i++) {
        ts_shape_point pt;
        ts_vec2 u = {(float)(0.02 + 0.96 * rnd(&g)), (float)(0.02 + 0.96 * rnd(&g))};
        assert_true(ts_shape_sample_area(s, 0, &info, u, &pt));
        /* Shoot at the sampled point along its normal, from outside. */
        ts_vec3 o = ts_vec3_add(pt.p, ts_vec3_scale(pt.n, 0.01f));
        ts_ray r = ts_ray_make(o, ts_vec3_neg(pt.n), INFINITY);
        float t;
        assert_true(ts_shape_intersect(s, &r, INFINITY, &t));
        ts_interaction si;
        ts_shape_interaction(s, 0, 0, &r, t, &si);
        if (!(ts_vec3_distance_sq(si.p, pt.p) < 1e-10f)) fail_msg("%s: hit far from the sampled point", what);
        assert_true(si.uv.x >= 0 && si.uv.x <= 1 && si.uv.y >= 0 && si.uv.y <= 1);
        ts_dvec3 p = param_point(s, si.uv.x, si.uv.y);
        if (!(ts_dvec3_length(ts_dvec3_sub(p, ts_dvec3_from(si.p))) < 1e-5))
            fail_msg("%s: P(u, v) = (%g %g %g) is not the hit (%g %g %g)", what, p.x, p.y, p.z, si.p.x, si.p.y, si.p.z);
        const double h = 1e-6;
        ts_dvec3 du = ts_dvec3_scale(ts_dvec3_sub(param_point(s, si.uv.x + h, si.uv.y), param_point(s, si.uv.x - h, si.uv.y)), 0.5 / h);
        ts_dvec3 dv = ts_dvec3_scale(ts_dvec3_sub(param_point(s, si.uv.x, si.uv.y + h), param_point(s, si.uv.x, si.uv.y - h)), 0.5 / h);
        double eu = ts_dvec3_length(ts_dvec3_sub(du, ts_dvec3_from(si.dpdu))), ev = ts_dvec3_length(ts_dvec3_sub(dv, ts_dvec3_from(si.dpdv)));
        if (!(eu <= 1e-4 * ts_dvec3_length(du) && ev <= 1e-4 * ts_dvec3_length(dv)))
            fail_msg("%s: dp/du off by %g, dp/dv off by %g", what, eu, ev);
        /* The front side is ∂p/∂u × ∂p/∂v (shape.h). */
        if (!(ts_vec3_dot(ts_vec3_cross(si.dpdu, si.dpdv), si.n) > 0)) fail_msg("%s: n is not along dp/du × dp/dv", what);
    }
}

static void test_parameterisation(void **state)
{
    (void)state;
    ts_xform sim = rot_scale(1.3, (ts_dvec3){1, 2, 3});
    ts_shape s = sphere_cut(1, -0.5, 0.6, 270, sim);
    check_param(&s, 1, "sphere");
    ts_shape d = disk_cut(1, 0.3, 200, sim);
    check_param(&d, 2, "disk");
    ts_shape c = cylinder_cut(0.7, 2, 120, sim);
    check_param(&c, 3, "cylinder");
}

/* ---- irradiance from partial emitters ---- */

/* Gauss–Legendre nodes and weights on [0, 1] (Newton on the Legendre recurrence). */
static void gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < n; i++) {
        double z = cos(TS_PI_D * (i + 0.75) / (n + 0.5)), pp = 0;
        for (int it = 0; it < 100; it++) {
            double p1 = 1, p2 = 0;
            for (int j = 1; j <= n; j++) {
                double p3 = p2;
                p2 = p1;
                p1 = ((2 * j - 1) * z * p2 - (j - 1) * p3) / j;
            }
            pp = n * (z * p1 - p2) / (z * z - 1);
            double dz = p1 / pp;
            z -= dz;
            if (fabs(dz) < 1e-15) break;
        }
        x[i] = 0.5 * (1 - z);
        w[i] = 1 / ((1 - z * z) * pp * pp);
    }
}

/* ∫ cosθ_ref⁺ cosθ_o⁺ / d² dA_world over the shape's (u, v) domain, order n per axis in each
 * of m × m panels. */
static double irradiance_exact(const ts_shape *s, ts_dvec3 p_ref, ts_dvec3 n_ref, int n, int m)
{
    double x[64], w[64];
    gauss_legendre(n, x, w);
    const double(*M)[4] = s->to_world.m.m;
    double det = fabs(M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
                      M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]));
    double sum = 0;
    for (int a = 0; a < m * n; a++)
        for (int b = 0; b < m * n; b++) {
            double u = (a / n + x[a % n]) / m, v = (b / n + x[b % n]) / m, wt = w[a % n] * w[b % n] / (m * m);
            double phi = u * s->phi_max, dA;
            ts_dvec3 p, n_obj;
            switch (s->type) {
            case TS_SHAPE_SPHERE: {
                double r = s->sphere.radius, z = s->sphere.z_min + v * (s->sphere.z_max - s->sphere.z_min);
                double ring = sqrt(r * r - z * z);
                p = (ts_dvec3){ring * cos(phi), ring * sin(phi), z};
                n_obj = ts_dvec3_scale(p, 1 / r);
                dA = s->phi_max * r * (s->sphere.z_max - s->sphere.z_min); /* r dz dφ */
                break;
            }
            case TS_SHAPE_DISK: {
                double ri = s->disk.inner_radius, ro = s->disk.radius, rr = ri + v * (ro - ri);
                p = (ts_dvec3){rr * cos(phi), rr * sin(phi), 0};
                n_obj = (ts_dvec3){0, 0, 1};
                dA = s->phi_max * (ro - ri) * rr;
                break;
            }
            default: {
                double r = s->cylinder.radius;
                p = (ts_dvec3){r * cos(phi), r * sin(phi), v * s->cylinder.height};
                n_obj = (ts_dvec3){cos(phi), sin(phi), 0};
                dA = s->phi_max * r * s->cylinder.height;
            }
            }
            ts_dvec3 X = ts_xform_point(&s->to_world, p), Nw = ts_xform_normal(&s->to_world, n_obj);
            double J = det * ts_dvec3_length(Nw);
            Nw = ts_dvec3_normalize(Nw);
            ts_dvec3 dd = ts_dvec3_sub(X, p_ref);
            double d2 = ts_dvec3_dot(dd, dd), dl = sqrt(d2);
            double ci = ts_dvec3_dot(n_ref, dd) / dl, co = -ts_dvec3_dot(Nw, dd) / dl;
            if (ci > 0 && co > 0) sum += wt * dA * J * ci * co / d2;
        }
    return sum;
}

static void check_irradiance(const char *what, const ts_shape *shape, ts_vec3 p_ref, ts_vec3 n_ref, uint64_t seed)
{
    ts_light l = {0};
    l.type = TS_LIGHT_AREA;
    l.color = ts_rgb_gray(1);
    l.shape = 0, l.prim = 0;
    l.to_world = ts_xform_identity();
    ts_error err = {0};
    ts_bounds3 b = {{-4, -4, -4}, {4, 4, 4}};
    if (ts_lights_prepare(&l, 1, shape, b, &err)) fail_msg("%s", err.message);
    ts_interaction ref = {0};
    ref.p = p_ref, ref.n = ref.ns = ts_vec3_normalize(n_ref), ref.shape = TS_NONE;
    double exact = irradiance_exact(shape, ts_dvec3_from(ref.p), ts_dvec3_from(ref.n), 24, 4);
    double finer = irradiance_exact(shape, ts_dvec3_from(ref.p), ts_dvec3_from(ref.n), 48, 4);
    if (!(fabs(exact - finer) <= 1e-12 * finer)) fail_msg("%s: quadrature %.15g vs %.15g", what, exact, finer);
    ts_pcg32 g;
    ts_pcg32_seed(&g, seed, 5);
    const int n = 1 << 20;
    double sum = 0, sum2 = 0;
    int misses = 0;
    for (int i = 0; i < n; i++) {
        ts_vec2 u = {ts_pcg32_float(&g), ts_pcg32_float(&g)};
        ts_light_sample ls;
        double x = 0;
        if (ts_light_sample_li(&l, shape, &ref, u, &ls)) {
            x = ls.L.g * fmax(0.0, ts_vec3_dot(ls.wi, ref.n)) / ls.pdf;
            /* The pdf of the direction agrees with the sample's (light.h) — except where
             * the float direction, re-intersected, misses the shape: within about
             * 2^-23·d/cosθ_o of a cut edge (like a mesh's edges), a fraction ~1e-5 of
             * the samples here; more than 1e-4 fails. */
            float pdf = ts_light_pdf_li(&l, shape, &ref, ls.wi);
            if (pdf == 0) misses++;
            else if (!(fabs(pdf - ls.pdf) <= 1e-3 * ls.pdf))
                fail_msg("%s: pdf_li %.7g, sample pdf %.7g", what, pdf, ls.pdf);
        }
        assert_true(isfinite(x));
        sum += x, sum2 += x * x;
    }
    if (misses > n / 10000) fail_msg("%s: %d of %d sampled directions miss the shape", what, misses, n);
    double mean = sum / n, se = sqrt(fmax(0, sum2 / n - mean * mean) / (n - 1));
    print_message("%s: E = %.7g ± %.2g (exact %.7g), %d edge misses\n", what, mean, se, exact, misses);
    if (!(fabs(mean - exact) <= 4 * se))
        fail_msg("%s: irradiance %.7g ± %.2g, exact %.7g (%.1f standard errors)", what, mean, se, exact, (mean - exact) / se);
}

static void test_irradiance(void **state)
{
    (void)state;
    ts_xform id = ts_xform_identity();
    /* A cap z ∈ [0.3, 1], φ ≤ 270°, seen from (0, 0, 4) looking down: every point faces
     * the reference point (n·(p_ref − p) = 4z − 1 > 0). Cone sampling of the whole sphere
     * would count the cut-away part too. */
    ts_shape s = sphere_cut(1, 0.3, 1, 270, id);
    check_irradiance("sphere cap", &s, (ts_vec3){0, 0, 4}, (ts_vec3){0, 0, -1}, 21);
    ts_xform an = aniso();
    ts_shape s2 = sphere_cut(1, 0.3, 1, 270, an);
    ts_dvec3 top = ts_xform_point(&an, (ts_dvec3){0, 0, 5});
    ts_dvec3 down = ts_dvec3_scale(ts_xform_normal(&an, (ts_dvec3){0, 0, 1}), -1);
    check_irradiance("sphere cap, non-uniform scale", &s2, ts_dvec3_to_vec3(top), ts_dvec3_to_vec3(down), 22);
    /* An annulus sector seen from above, off-centre and tilted. */
    ts_shape d = disk_cut(1, 0.35, 200, id);
    check_irradiance("disk sector", &d, (ts_vec3){0.4f, 0.2f, 1.1f}, (ts_vec3){0.2f, -0.1f, -1}, 23);
    ts_shape d2 = disk_cut(1, 0.35, 200, rot_scale(1.5, (ts_dvec3){0, 0, 0}));
    ts_dvec3 dn = ts_xform_normal(&d2.to_world, (ts_dvec3){0, 0, 1});
    ts_dvec3 dp = ts_dvec3_scale(ts_dvec3_normalize(dn), 1.3);
    check_irradiance("disk sector, similarity", &d2, ts_dvec3_to_vec3(dp), ts_dvec3_to_vec3(ts_dvec3_scale(dn, -1)), 24);
    /* A tube sector φ ∈ [0, 120°] seen from outside at φ = 60°, distance 3: every point
     * faces it (3 cos(φ − 60°) > 1). */
    ts_shape c = cylinder_cut(1, 1.5, 120, id);
    double a = TS_PI_D / 3;
    check_irradiance("cylinder sector", &c, (ts_vec3){(float)(3 * cos(a)), (float)(3 * sin(a)), 0.5f},
                     (ts_vec3){(float)-cos(a), (float)-sin(a), 0.1f}, 25);
}

/* ---- the builder ---- */

static ts_scene_builder *builder(void)
{
    ts_scene_builder *b;
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_create(NULL, NULL, &b, &err), TS_OK);
    ts_material m = {.type = TS_MATERIAL_DIFFUSE, .reflectance = {{0.5f, 0.5f, 0.5f}}};
    assert_int_equal(ts_scene_builder_add_material(b, "m", &m, NULL, &err), TS_OK);
    return b;
}

static void expect_refused(ts_shape_desc d, const char *msg)
{
    ts_scene_builder *b = builder();
    ts_error err = {0};
    assert_int_not_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_OK);
    if (!strstr(err.message, msg)) fail_msg("got '%s', expected '%s'", err.message, msg);
    ts_scene_builder_destroy(b);
}

static void test_builder_cut(void **state)
{
    (void)state;
    ts_xform id = ts_xform_identity();
    /* Clamping: pbrt-v3's defaults (±r, 360) and anything beyond are the whole shape. */
    ts_shape_desc d = {.type = TS_SHAPE_SPHERE, .to_world = id, .sphere = {2}, .cut = {true, -5, 7, 400}};
    ts_scene_builder *b = builder();
    ts_error err = {0};
    assert_int_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_OK);
    /* zmin > zmax is pbrt-v3's either order; the cut is stored sorted with θ. */
    d.cut = (ts_shape_cut){true, 1, -0.5, 180};
    assert_int_equal(ts_scene_builder_add_shape(b, &d, NULL, &err), TS_OK);
    /* A cylinder's z range and a disk's height go into the transform. */
    ts_shape_desc c = {.type = TS_SHAPE_CYLINDER, .to_world = id, .cylinder = {1, 0}, .cut = {true, 3, -1, 360}};
    assert_int_equal(ts_scene_builder_add_shape(b, &c, NULL, &err), TS_OK);
    ts_shape_desc k = {.type = TS_SHAPE_DISK, .to_world = id, .disk = {1, 0, 0.25}};
    assert_int_equal(ts_scene_builder_add_shape(b, &k, NULL, &err), TS_OK);
    ts_film_desc film = {8, 8, {0, 1, 0, 1}, TS_FILTER_BOX, 0.5f};
    ts_camera_desc cam = {.type = TS_CAMERA_PERSPECTIVE, .from = {0, 0, 10}, .to = {0, 0, 0}, .up = {0, 1, 0}, .fov_deg = 40, .focus_distance = 1};
    ts_sampler smp = {.type = TS_SAMPLER_SOBOL};
    ts_integrator_desc in = {.type = TS_INTEGRATOR_NORMALS};
    assert_int_equal(ts_scene_builder_set_film(b, &film, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_camera(b, &cam, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_sampler(b, &smp, 1, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_integrator(b, &in, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_digest(b, "0000000000000000000000000000000000000000000000000000000000000000", &err), TS_OK);
    ts_scene *s;
    if (ts_scene_builder_finish(b, &s, &err)) fail_msg("%s", err.message);
    ts_scene_builder_destroy(b);
    assert_false(s->shapes[0].partial);
    assert_true(s->shapes[1].partial);
    assert_true(s->shapes[1].sphere.z_min == -0.5 && s->shapes[1].sphere.z_max == 1);
    assert_true(fabs(s->shapes[1].phi_max - TS_PI_D) < 1e-15);
    assert_true(fabs(s->shapes[1].sphere.theta_min - acos(-0.25)) < 1e-15 && fabs(s->shapes[1].sphere.theta_max - acos(0.5)) < 1e-15);
    assert_false(s->shapes[2].partial);
    assert_true(s->shapes[2].cylinder.height == 4);
    assert_true(s->shapes[2].to_world.m.m[2][3] == -1);
    assert_true(s->shapes[3].to_world.m.m[2][3] == 0.25);
    ts_scene_destroy(s);

    expect_refused((ts_shape_desc){.type = TS_SHAPE_SPHERE, .to_world = id, .sphere = {1}, .cut = {true, -1, 1, 0}},
                   "phimax: 0 degrees leaves the shape no area");
    expect_refused((ts_shape_desc){.type = TS_SHAPE_SPHERE, .to_world = id, .sphere = {1}, .cut = {true, 2, 3, 90}},
                   "zmin, zmax: 2 and 3 clamp to the same height on a sphere of radius 1");
    expect_refused((ts_shape_desc){.type = TS_SHAPE_CYLINDER, .to_world = id, .cylinder = {1, 1}, .cut = {true, 1, 1, 90}},
                   "zmin, zmax: both 1, which leaves the cylinder no area");
    expect_refused((ts_shape_desc){.type = TS_SHAPE_SPHERE, .to_world = id, .sphere = {1}, .cut = {true, -1, 1, NAN}},
                   "phimax: expected an angle in degrees, got nan");
}

/* ---- ReverseOrientation ---- */

/* A scene of one emitter (radiance 1) from the builder. */
static ts_scene *one_emitter(ts_shape_desc d)
{
    ts_scene_builder *b = builder();
    ts_error err = {0};
    d.emission = ts_rgb_gray(1);
    if (ts_scene_builder_add_shape(b, &d, NULL, &err)) fail_msg("%s", err.message);
    ts_film_desc film = {8, 8, {0, 1, 0, 1}, TS_FILTER_BOX, 0.5f};
    ts_camera_desc cam = {.type = TS_CAMERA_PERSPECTIVE, .from = {0, 3, 10}, .to = {0, 0, 0}, .up = {0, 1, 0}, .fov_deg = 40, .focus_distance = 1};
    ts_sampler smp = {.type = TS_SAMPLER_SOBOL};
    ts_integrator_desc in = {.type = TS_INTEGRATOR_PATH, .max_depth = 1, .samples_per_light = 1};
    assert_int_equal(ts_scene_builder_set_film(b, &film, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_camera(b, &cam, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_sampler(b, &smp, 1, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_integrator(b, &in, &err), TS_OK);
    assert_int_equal(ts_scene_builder_set_digest(b, "0000000000000000000000000000000000000000000000000000000000000000", &err), TS_OK);
    ts_scene *s;
    if (ts_scene_builder_finish(b, &s, &err)) fail_msg("%s", err.message);
    ts_scene_builder_destroy(b);
    return s;
}

/* Irradiance at p (normal n) from every light of s, N independent samples each: mean and
 * standard error. */
static void scene_irradiance(const ts_scene *s, ts_vec3 p, ts_vec3 n, double *mean, double *se)
{
    ts_interaction ref = {0};
    ref.p = p, ref.n = ref.ns = ts_vec3_normalize(n), ref.shape = TS_NONE;
    ts_pcg32 g;
    ts_pcg32_seed(&g, 99, 1);
    const int N = 1 << 18;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < N; i++) {
        double x = 0;
        for (uint32_t li = 0; li < s->n_lights; li++) {
            ts_vec2 u = {ts_pcg32_float(&g), ts_pcg32_float(&g)};
            ts_light_sample ls;
            if (ts_light_sample_li(&s->lights[li], s->shapes, &ref, u, &ls))
                x += ls.L.g * fmax(0.0, ts_vec3_dot(ls.wi, ref.n)) / ls.pdf;
        }
        sum += x, sum2 += x * x;
    }
    *mean = sum / N;
    *se = sqrt(fmax(0, sum2 / N - *mean * *mean) / (N - 1));
}

/* Radiance leaving the first hit of the ray towards its origin (0 on a miss). */
static double seen(const ts_scene *s, ts_vec3 o, ts_vec3 d)
{
    ts_ray r = ts_ray_make(o, d, INFINITY);
    ts_interaction si;
    if (!ts_accel_intersect(s->accel, &r, &si)) return -1;
    const ts_shape *sh = &s->shapes[si.shape];
    const ts_light *l = &s->lights[ts_area_light_index(sh, si.prim)];
    return ts_area_light_l(l, &si, si.wo).g;
}

/* A unit disk (or a quad of the same plane, or a partial sphere's cap) emitting one-sided at
 * z = 0, seen from z = ±1 on its axis. Reversed, it lights −z and not +z; mirrored by
 * scale(1, 1, −1) and reversed, +z again (pbrt-v3's ReverseOrientation XOR the handedness,
 * which the builder applies: scene_builder.h). Disk closed form: E = πR²/(h² + R²). */
static void test_reverse_orientation(void **state)
{
    (void)state;
    static const float qp[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    static const uint32_t qi[] = {0, 1, 2, 0, 2, 3}; /* faces +z */
    const double disk_e = TS_PI_D / 2;
    ts_xform id = ts_xform_identity(), mirror = ts_xform_scale((ts_dvec3){1, 1, -1});
    for (int shape = 0; shape < 3; shape++)
        for (int c = 0; c < 4; c++) {
            bool rev = c & 1, mir = c & 2;
            ts_shape_desc d = {.type = TS_SHAPE_DISK, .to_world = mir ? mirror : id, .reverse_orientation = rev, .disk = {1, 0, 0}};
            if (shape == 1) {
                d.type = TS_SHAPE_MESH;
                d.mesh = (ts_mesh){4, 2, qp, NULL, NULL, qi};
            } else if (shape == 2) {
                /* The cap z ∈ [0.5, 1] of a unit sphere moved down by 1: faces +z at the top. */
                d.type = TS_SHAPE_SPHERE;
                d.sphere.radius = 1;
                d.cut = (ts_shape_cut){true, 0.5, 1, 360};
                ts_xform down = ts_xform_translate((ts_dvec3){0, 0, -1});
                d.to_world = ts_xform_compose(&down, mir ? &mirror : &id);
                if (mir) d.to_world = ts_xform_compose(&mirror, &down);
            }
            ts_scene *s = one_emitter(d);
            bool lights_up = rev == mir; /* the front is +z unless exactly one of them */
            double up, up_se, dn, dn_se;
            ts_vec3 p_up = {0, 0, 1}, p_dn = {0, 0, shape == 2 ? -0.75f : -1};
            if (shape == 2 && mir) p_up.z = 0.75f, p_dn.z = -1;
            scene_irradiance(s, p_up, (ts_vec3){0, 0, -1}, &up, &up_se);
            scene_irradiance(s, p_dn, (ts_vec3){0, 0, 1}, &dn, &dn_se);
            double lit = lights_up ? up : dn, dark = lights_up ? dn : up, lit_se = lights_up ? up_se : dn_se;
            if (dark != 0) fail_msg("shape %d case %d: the back side receives %g", shape, c, dark);
            if (!(lit > 0.1)) fail_msg("shape %d case %d: the front side receives %g", shape, c, lit);
            if (shape == 0 && !(fabs(lit - disk_e) <= 4 * lit_se))
                fail_msg("disk case %d: E = %.6g ± %.2g, closed form %.6g", c, lit, lit_se, disk_e);
            /* Seen by a ray: emits towards the lit side only. */
            double from_up = seen(s, (ts_vec3){0.1f, 0.2f, 3}, (ts_vec3){0, 0, -1});
            double from_dn = seen(s, (ts_vec3){0.1f, 0.2f, -3}, (ts_vec3){0, 0, 1});
            if (shape != 2) {
                assert_true(from_up == (lights_up ? 1 : 0));
                assert_true(from_dn == (lights_up ? 0 : 1));
            } else {
                /* The cap is seen from its own side only (its inside from below is behind it). */
                assert_true(lights_up ? from_up == 1 : from_up == 0);
            }
            ts_scene_destroy(s);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_area_by_hit_testing),
        cmocka_unit_test(test_area_quadrature),
        cmocka_unit_test(test_cut_edges),
        cmocka_unit_test(test_parameterisation),
        cmocka_unit_test(test_irradiance),
        cmocka_unit_test(test_builder_cut),
        cmocka_unit_test(test_reverse_orientation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
