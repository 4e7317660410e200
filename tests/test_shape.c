/* test_shape.c — exact ray–shape intersection: known hits, grazing rays, error bounds
 * checked against an independent long double reference, and self-intersection of spawned
 * rays.
 *
 * The reference. A shape is defined by to_world (m) and its stored inverse (m_inv): the
 * exact hit of a float ray is m·(first hit of m_inv·ray with the object-space surface).
 * The reference evaluates that in long double (64-bit mantissa, 2^11 times finer than
 * double) with the same stable formulas, so its own error is far below the bounds it
 * checks. Where a hit/miss decision of the exact ray is within a relative AMBIGUOUS of a
 * boundary (tangency, rim, tube end, triangle edge, origin on the surface), the reference
 * says so and the two answers may differ; such rays are counted, and must stay rare.
 *
 * Random streams are PCG32 with fixed seeds: every run tests the same rays. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/hash.h"
#include "core/transform.h"
#include "geometry/shape.h"

/* Relative closeness to a boundary below which the exact decision is "ambiguous": 1e-10 is
 * ~10^6 double roundoffs (the implementation decides correctly well inside it) and ~10^-3
 * float ulps (so it hardly ever catches a random float ray). */
#define AMBIGUOUS 1e-10L

typedef long double ld;
typedef struct lv3 { ld x, y, z; } lv3;

static lv3 lv_add(lv3 a, lv3 b) { return (lv3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static lv3 lv_sub(lv3 a, lv3 b) { return (lv3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static lv3 lv_scale(lv3 a, ld s) { return (lv3){a.x * s, a.y * s, a.z * s}; }
static ld lv_dot(lv3 a, lv3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static lv3 lv_cross(lv3 a, lv3 b) { return (lv3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
static ld lv_len(lv3 a) { return sqrtl(lv_dot(a, a)); }
static lv3 lv_norm(lv3 a) { return lv_scale(a, 1 / lv_len(a)); }
static lv3 lv_from(ts_vec3 a) { return (lv3){a.x, a.y, a.z}; }
static ld lv_get(lv3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
static float vget(ts_vec3 a, int i) { return ts_vec3_get(a, i); }

static lv3 m_point(const ts_mat4 *m, lv3 p)
{
    const double(*a)[4] = m->m;
    return (lv3){(ld)a[0][0] * p.x + (ld)a[0][1] * p.y + (ld)a[0][2] * p.z + (ld)a[0][3],
                 (ld)a[1][0] * p.x + (ld)a[1][1] * p.y + (ld)a[1][2] * p.z + (ld)a[1][3],
                 (ld)a[2][0] * p.x + (ld)a[2][1] * p.y + (ld)a[2][2] * p.z + (ld)a[2][3]};
}
static lv3 m_vector(const ts_mat4 *m, lv3 v)
{
    const double(*a)[4] = m->m;
    return (lv3){(ld)a[0][0] * v.x + (ld)a[0][1] * v.y + (ld)a[0][2] * v.z,
                 (ld)a[1][0] * v.x + (ld)a[1][1] * v.y + (ld)a[1][2] * v.z,
                 (ld)a[2][0] * v.x + (ld)a[2][1] * v.y + (ld)a[2][2] * v.z};
}
/* Normal: by the transpose of m_inv. */
static lv3 m_normal(const ts_mat4 *mi, lv3 n)
{
    const double(*a)[4] = mi->m;
    return (lv3){(ld)a[0][0] * n.x + (ld)a[1][0] * n.y + (ld)a[2][0] * n.z,
                 (ld)a[0][1] * n.x + (ld)a[1][1] * n.y + (ld)a[2][1] * n.z,
                 (ld)a[0][2] * n.x + (ld)a[1][2] * n.y + (ld)a[2][2] * n.z};
}

typedef struct ref_hit {
    bool hit, ambiguous;
    ld t;
    lv3 p;  /* world */
    lv3 n;  /* world, unit, front side */
} ref_hit;

static ld sgnl(ld v) { return v < 0 ? -1 : 1; }

/* Both roots of the quadratic a·t² + 2·b·t + c (b, c about the centre line), from the
 * distance f of the line to the axis; false if none. Sets *amb near tangency. */
static bool ref_roots(ld a, ld b, ld c, ld f2, ld r, ld *t0, ld *t1, bool *amb)
{
    ld disc = r * r - f2;
    if (fabsl(disc) <= AMBIGUOUS * r * r) *amb = true;
    if (disc < 0) return false;
    ld q = -(b + sgnl(b) * sqrtl(a * disc));
    if (q == 0) return false;
    ld r0 = q / a, r1 = c / q;
    *t0 = fminl(r0, r1);
    *t1 = fmaxl(r0, r1);
    return true;
}

static ref_hit ref_intersect(const ts_shape *s, ts_vec3 of, ts_vec3 df)
{
    ref_hit R = {0};
    if (s->type == TS_SHAPE_MESH) {
        const ts_mesh *m = &s->mesh;
        lv3 p0 = lv_from(*(const ts_vec3 *)(m->p + 3 * m->index[0]));
        lv3 p1 = lv_from(*(const ts_vec3 *)(m->p + 3 * m->index[1]));
        lv3 p2 = lv_from(*(const ts_vec3 *)(m->p + 3 * m->index[2]));
        lv3 o = lv_from(of), d = lv_from(df), e1 = lv_sub(p1, p0), e2 = lv_sub(p2, p0), N = lv_cross(e1, e2);
        ld nd = lv_dot(N, d);
        if (nd == 0) return R;
        ld t = lv_dot(N, lv_sub(p0, o)) / nd;
        lv3 p = lv_add(o, lv_scale(d, t));
        /* Barycentrics by sub-areas along N. */
        ld nn = lv_dot(N, N);
        ld b1 = lv_dot(N, lv_cross(lv_sub(p, p0), e2)) / nn;
        ld b2 = lv_dot(N, lv_cross(e1, lv_sub(p, p0))) / nn;
        ld b0 = 1 - b1 - b2;
        if (fabsl(b0) < AMBIGUOUS || fabsl(b1) < AMBIGUOUS || fabsl(b2) < AMBIGUOUS) R.ambiguous = true;
        ld scale = lv_len(lv_sub(o, p0)) + lv_len(e1) + lv_len(e2);
        if (fabsl(t) * lv_len(d) <= AMBIGUOUS * scale) R.ambiguous = true;
        if (t > 0 && b0 >= 0 && b1 >= 0 && b2 >= 0) {
            R.hit = true;
            R.t = t;
            R.p = p;
            R.n = lv_norm(N);
        }
        return R;
    }
    const ts_mat4 *m = &s->to_world.m, *mi = &s->to_world.m_inv;
    lv3 o = m_point(mi, lv_from(of)), d = m_vector(mi, lv_from(df));
    ld dl = lv_len(d), ol = lv_len(o);
    lv3 p_obj = {0, 0, 0}, n_obj = {0, 0, 1};
    ld t_hit = 0;
    bool hit = false;
    switch (s->type) {
    case TS_SHAPE_SPHERE: {
        ld r = s->sphere.radius, a = lv_dot(d, d), b = lv_dot(o, d);
        lv3 f = lv_sub(o, lv_scale(d, b / a));
        ld t0, t1;
        if (!ref_roots(a, b, lv_dot(o, o) - r * r, lv_dot(f, f), r, &t0, &t1, &R.ambiguous)) break;
        ld ts[2] = {t0, t1};
        for (int k = 0; k < 2 && !hit; k++) {
            if (fabsl(ts[k]) * dl <= AMBIGUOUS * (ol + r)) R.ambiguous = true;
            if (ts[k] > 0) {
                hit = true;
                t_hit = ts[k];
                p_obj = lv_add(o, lv_scale(d, t_hit));
                n_obj = p_obj;
            }
        }
        break;
    }
    case TS_SHAPE_DISK: {
        ld r = s->disk.radius, ri = s->disk.inner_radius;
        if (d.z == 0) break;
        ld t = -o.z / d.z;
        if (fabsl(t) * dl <= AMBIGUOUS * (ol + r)) R.ambiguous = true;
        lv3 p = lv_add(o, lv_scale(d, t));
        p.z = 0;
        ld dist = sqrtl(p.x * p.x + p.y * p.y);
        if (fabsl(dist - r) <= AMBIGUOUS * r || fabsl(dist - ri) <= AMBIGUOUS * r) R.ambiguous = true;
        if (t > 0 && dist <= r && dist >= ri) {
            hit = true;
            t_hit = t;
            p_obj = p;
        }
        break;
    }
    case TS_SHAPE_CYLINDER: {
        ld r = s->cylinder.radius, h = s->cylinder.height, a = d.x * d.x + d.y * d.y;
        if (a == 0) break;
        ld b = o.x * d.x + o.y * d.y, fx = o.x - (b / a) * d.x, fy = o.y - (b / a) * d.y, t0, t1;
        if (!ref_roots(a, b, o.x * o.x + o.y * o.y - r * r, fx * fx + fy * fy, r, &t0, &t1, &R.ambiguous)) break;
        ld ts[2] = {t0, t1};
        for (int k = 0; k < 2 && !hit; k++) {
            if (fabsl(ts[k]) * dl <= AMBIGUOUS * (ol + r + h)) R.ambiguous = true;
            if (!(ts[k] > 0)) continue;
            ld z = o.z + ts[k] * d.z;
            if (fabsl(z) <= AMBIGUOUS * (r + h) || fabsl(z - h) <= AMBIGUOUS * (r + h)) R.ambiguous = true;
            if (z < 0 || z > h) continue;
            hit = true;
            t_hit = ts[k];
            p_obj = lv_add(o, lv_scale(d, t_hit));
            n_obj = (lv3){p_obj.x, p_obj.y, 0};
        }
        break;
    }
    case TS_SHAPE_MESH:
    case TS_SHAPE_CURVE: break;
    }
    if (!hit) return R;
    R.hit = true;
    R.t = t_hit;
    R.p = m_point(m, p_obj);
    R.n = lv_norm(m_normal(mi, n_obj)); /* outward / +z side, whatever the handedness */
    return R;
}

/* ---- building shapes ---- */

static double rnd(ts_pcg32 *g) { return ts_pcg32_double(g); }
static double rnd_range(ts_pcg32 *g, double a, double b) { return a + (b - a) * rnd(g); }
static ts_dvec3 rnd_unit(ts_pcg32 *g)
{
    double z = 1 - 2 * rnd(g), phi = 2 * TS_PI_D * rnd(g), r = sqrt(fmax(0, 1 - z * z));
    return (ts_dvec3){r * cos(phi), r * sin(phi), z};
}

static ts_shape make_analytic(ts_shape_type type, double r, double ri_or_h, ts_xform x)
{
    ts_shape s;
    memset(&s, 0, sizeof s);
    s.type = type;
    s.to_world = x;
    if (type == TS_SHAPE_SPHERE) s.sphere.radius = r;
    else if (type == TS_SHAPE_DISK) s.disk.radius = r, s.disk.inner_radius = ri_or_h;
    else s.cylinder.radius = r, s.cylinder.height = ri_or_h;
    return s;
}

/* A one-triangle mesh over caller storage. */
typedef struct tri_store {
    float p[9], n[9], uv[6];
    uint32_t idx[3];
} tri_store;

static ts_shape make_triangle(tri_store *st, ts_vec3 a, ts_vec3 b, ts_vec3 c)
{
    ts_vec3 v[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        st->p[3 * k] = v[k].x, st->p[3 * k + 1] = v[k].y, st->p[3 * k + 2] = v[k].z;
        st->idx[k] = (uint32_t)k;
    }
    ts_shape s;
    memset(&s, 0, sizeof s);
    s.type = TS_SHAPE_MESH;
    s.to_world = ts_xform_identity();
    s.mesh.n_vertices = 3;
    s.mesh.n_triangles = 1;
    s.mesh.p = st->p;
    s.mesh.index = st->idx;
    return s;
}

/* Random placement: T·R·S with |T| log-uniform in [1e-4, max_offset] (or 0), a random
 * rotation and per-axis scales in [2^-smax, 2^smax]. */
static ts_xform rnd_xform(ts_pcg32 *g, double max_offset, double smax)
{
    ts_dvec3 sc = {exp2(rnd_range(g, -smax, smax)), exp2(rnd_range(g, -smax, smax)), exp2(rnd_range(g, -smax, smax))};
    ts_xform S = ts_xform_scale(sc);
    ts_xform R = ts_xform_rotate(rnd_range(g, 0, 360), rnd_unit(g));
    double mag = rnd(g) < 0.1 ? 0 : exp(rnd_range(g, log(1e-4), log(max_offset)));
    ts_xform T = ts_xform_translate(ts_dvec3_scale(rnd_unit(g), mag));
    ts_xform RS = ts_xform_compose(&R, &S);
    return ts_xform_compose(&T, &RS);
}

static ts_vec3 to_f(ts_dvec3 v) { return ts_dvec3_to_vec3(v); }

/* Object-space size and centre of an analytic shape. */
static double shape_size(const ts_shape *s, ts_dvec3 *centre)
{
    *centre = (ts_dvec3){0, 0, 0};
    if (s->type == TS_SHAPE_SPHERE) return s->sphere.radius;
    if (s->type == TS_SHAPE_DISK) return s->disk.radius;
    centre->z = 0.5 * s->cylinder.height;
    return fmax(s->cylinder.radius, 0.5 * s->cylinder.height);
}

/* A random float ray towards an analytic shape; one in ten grazes it. */
static ts_ray rnd_ray_analytic(ts_pcg32 *g, const ts_shape *s)
{
    ts_dvec3 c;
    double size = shape_size(s, &c);
    ts_dvec3 o, target;
    /* Origins 1.5 to 20 sizes away, one in ten up to 10^4 sizes away. */
    double R = size * (rnd(g) < 0.1 ? exp(rnd_range(g, log(20), log(1e4))) : rnd_range(g, 1.5, 20));
    if (rnd(g) < 0.1) {
        ts_dvec3 d = rnd_unit(g);
        if (s->type == TS_SHAPE_SPHERE) {
            ts_dvec3 u = ts_dvec3_normalize(ts_dvec3_cross(d, rnd_unit(g)));
            target = ts_dvec3_scale(u, s->sphere.radius);
        } else if (s->type == TS_SHAPE_CYLINDER) {
            double dl = hypot(d.x, d.y);
            target = (ts_dvec3){-d.y / dl * s->cylinder.radius, d.x / dl * s->cylinder.radius,
                                rnd(g) * s->cylinder.height};
        } else {
            double phi = rnd_range(g, 0, 2 * TS_PI_D), ang = rnd_range(g, 0, 2 * TS_PI_D);
            double rr = rnd_range(g, s->disk.inner_radius, s->disk.radius);
            double dz = (rnd(g) < 0.5 ? -1 : 1) * exp(rnd_range(g, log(1e-6), log(1e-1)));
            d = ts_dvec3_normalize((ts_dvec3){cos(ang), sin(ang), dz});
            target = (ts_dvec3){rr * cos(phi), rr * sin(phi), 0};
        }
        o = ts_dvec3_sub(target, ts_dvec3_scale(d, R));
    } else {
        o = ts_dvec3_add(c, ts_dvec3_scale(rnd_unit(g), R));
        ts_dvec3 box = {1.2 * size, 1.2 * size, 1.2 * size};
        target = (ts_dvec3){c.x + box.x * rnd_range(g, -1, 1), c.y + box.y * rnd_range(g, -1, 1),
                            c.z + box.z * rnd_range(g, -1, 1)};
    }
    ts_dvec3 ow = ts_xform_point(&s->to_world, o), tw = ts_xform_point(&s->to_world, target);
    ts_vec3 of = to_f(ow);
    ts_vec3 df = to_f(ts_dvec3_sub(tw, ts_dvec3_from(of)));
    return ts_ray_make(of, df, INFINITY);
}

static ts_shape rnd_analytic(ts_pcg32 *g, ts_shape_type type, double r, double max_offset, double smax)
{
    ts_xform x = rnd_xform(g, max_offset, smax);
    double extra = 0;
    if (type == TS_SHAPE_DISK) extra = rnd(g) < 0.5 ? 0 : r * rnd_range(g, 0.05, 0.8);
    if (type == TS_SHAPE_CYLINDER) extra = r * exp2(rnd_range(g, -2, 2));
    return make_analytic(type, r, extra, x);
}

/* A random triangle of size ~L around a point |c| ≤ max_offset; one in five is a sliver. */
static ts_shape rnd_triangle(ts_pcg32 *g, tri_store *st, double L, double max_offset)
{
    double mag = rnd(g) < 0.1 ? 0 : exp(rnd_range(g, log(1e-4), log(max_offset)));
    ts_dvec3 c = ts_dvec3_scale(rnd_unit(g), mag);
    ts_dvec3 a = ts_dvec3_add(c, ts_dvec3_scale(rnd_unit(g), L));
    ts_dvec3 b = ts_dvec3_add(c, ts_dvec3_scale(rnd_unit(g), L));
    ts_dvec3 e = ts_dvec3_add(c, ts_dvec3_scale(rnd_unit(g), L));
    if (rnd(g) < 0.2) { /* sliver: third vertex near the middle of the first edge */
        ts_dvec3 mid = ts_dvec3_scale(ts_dvec3_add(a, b), 0.5);
        e = ts_dvec3_add(mid, ts_dvec3_scale(rnd_unit(g), L * 1e-3));
    }
    return make_triangle(st, to_f(a), to_f(b), to_f(e));
}

static ts_ray rnd_ray_triangle(ts_pcg32 *g, const ts_shape *s)
{
    const float *p = s->mesh.p;
    ts_dvec3 v[3];
    for (int k = 0; k < 3; k++) v[k] = (ts_dvec3){p[3 * k], p[3 * k + 1], p[3 * k + 2]};
    double b1 = rnd_range(g, -0.1, 1.1), b2 = rnd_range(g, -0.1, 1.1);
    if (b1 + b2 > 1.2) b1 = 1.1 - b1, b2 = 1.1 - b2;
    ts_dvec3 target = ts_dvec3_add(v[0], ts_dvec3_add(ts_dvec3_scale(ts_dvec3_sub(v[1], v[0]), b1),
                                                      ts_dvec3_scale(ts_dvec3_sub(v[2], v[0]), b2)));
    double L = ts_dvec3_length(ts_dvec3_sub(v[1], v[0])) + ts_dvec3_length(ts_dvec3_sub(v[2], v[0]));
    ts_dvec3 d;
    if (rnd(g) < 0.1) { /* grazing: nearly in the plane */
        ts_dvec3 N = ts_dvec3_normalize(ts_dvec3_cross(ts_dvec3_sub(v[1], v[0]), ts_dvec3_sub(v[2], v[0])));
        ts_dvec3 u = ts_dvec3_normalize(ts_dvec3_cross(N, rnd_unit(g)));
        double dz = (rnd(g) < 0.5 ? -1 : 1) * exp(rnd_range(g, log(1e-6), log(1e-1)));
        d = ts_dvec3_normalize(ts_dvec3_add(u, ts_dvec3_scale(N, dz)));
    } else {
        d = rnd_unit(g);
    }
    ts_dvec3 o = ts_dvec3_sub(target, ts_dvec3_scale(d, L * rnd_range(g, 1, 10)));
    ts_vec3 of = to_f(o);
    return ts_ray_make(of, to_f(ts_dvec3_sub(target, ts_dvec3_from(of))), INFINITY);
}

static bool shape_hit(const ts_shape *s, const ts_ray *r, float *t)
{
    if (s->type == TS_SHAPE_MESH) return ts_shape_triangle_intersect(s, 0, r, r->tmax, t);
    return ts_shape_intersect(s, r, r->tmax, t);
}

static void assert_close(double a, double b, double tol, const char *what)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%s: %.9g != %.9g (tolerance %g)", what, a, b, tol);
}
static void assert_vec_close(ts_vec3 a, ts_vec3 b, double tol, const char *what)
{
    for (int i = 0; i < 3; i++)
        if (!(fabs(vget(a, i) - vget(b, i)) <= tol))
            fail_msg("%s: (%.9g %.9g %.9g) != (%.9g %.9g %.9g) (tolerance %g)", what, a.x, a.y, a.z, b.x, b.y, b.z,
                     tol);
}

/* The bound contains the exact point; returns max_i |p_i − exact_i| / p_error_i. */
static double bound_ratio(const ts_interaction *si, lv3 exact)
{
    double worst = 0;
    for (int i = 0; i < 3; i++) {
        ld diff = fabsl((ld)vget(si->p, i) - lv_get(exact, i));
        double e = vget(si->p_error, i);
        double ratio = e > 0 ? (double)(diff / e) : (diff > 0 ? INFINITY : 0);
        if (ratio > worst) worst = ratio;
    }
    return worst;
}

/* Float results of exact values: 1e-6 relative is a few float ulps. */
#define FTOL 1e-6

/* ---- known hits ---- */

static void test_sphere_known(void **state)
{
    (void)state;
    ts_shape s = make_analytic(TS_SHAPE_SPHERE, 2, 0, ts_xform_translate((ts_dvec3){1, 2, 3}));
    ts_ray r = ts_ray_make((ts_vec3){-10, 2, 3}, (ts_vec3){1, 0, 0}, INFINITY);
    float t;
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    assert_close(t, 9, 0, "t"); /* exact in double and float */
    ts_interaction si;
    ts_shape_interaction(&s, 7, 0, &r, t, &si);
    assert_int_equal(si.shape, 7);
    assert_vec_close(si.p, (ts_vec3){-1, 2, 3}, 0, "p");
    assert_vec_close(si.n, (ts_vec3){-1, 0, 0}, FTOL, "n");
    assert_vec_close(si.wo, (ts_vec3){-1, 0, 0}, FTOL, "wo");
    assert_close(si.uv.x, 0.5, FTOL, "u");
    assert_close(si.uv.y, 0.5, FTOL, "v");
    /* pbrt-v3: ∂p/∂u = 2π(−y, x, 0) = (0, −4π, 0); ∂p/∂v = −π(z cos φ, z sin φ, −r sin θ) = (0, 0, 2π). */
    assert_vec_close(si.dpdu, (ts_vec3){0, -4 * TS_PI, 0}, 1e-5, "dpdu");
    assert_vec_close(si.dpdv, (ts_vec3){0, 0, 2 * TS_PI}, 1e-5, "dpdv");
    /* tmax respected: the hit at 9 is not in (0, 9). */
    assert_false(ts_shape_intersect(&s, &r, 9, &t));
    /* From inside: the far side, normal still outwards. */
    r = ts_ray_make((ts_vec3){1, 2, 3}, (ts_vec3){0, 0, 2}, INFINITY);
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    assert_close(t, 1, 0, "t inside");
    ts_shape_interaction(&s, 0, 0, &r, t, &si);
    assert_vec_close(si.p, (ts_vec3){1, 2, 5}, 0, "p inside");
    assert_vec_close(si.n, (ts_vec3){0, 0, 1}, FTOL, "n inside");
    /* Misses: beside it, and pointing away. */
    r = ts_ray_make((ts_vec3){-10, 4.5f, 3}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){-10, 2, 3}, (ts_vec3){-1, 0, 0}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    /* A mirroring transform keeps the normal outwards (shape.h, Orientation). */
    ts_shape m = make_analytic(TS_SHAPE_SPHERE, 1, 0, ts_xform_scale((ts_dvec3){-1, 1, 1}));
    assert_true(ts_xform_swaps_handedness(&m.to_world));
    r = ts_ray_make((ts_vec3){-5, 0, 0}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_true(ts_shape_intersect(&m, &r, INFINITY, &t));
    ts_shape_interaction(&m, 0, 0, &r, t, &si);
    assert_vec_close(si.n, (ts_vec3){-1, 0, 0}, FTOL, "mirrored n");
    /* Area: 4πr², times s² under a uniform scale. */
    assert_close(ts_shape_area(&s, 0), 16 * TS_PI_D, 1e-12, "area");
    ts_shape big = make_analytic(TS_SHAPE_SPHERE, 1, 0, ts_xform_scale((ts_dvec3){3, 3, 3}));
    assert_close(ts_shape_area(&big, 0), 36 * TS_PI_D, 1e-9, "scaled area");
    ts_xform rot = ts_xform_rotate(37, (ts_dvec3){1, 2, 3});
    ts_xform rot_big = ts_xform_compose(&rot, &big.to_world);
    ts_shape rb = make_analytic(TS_SHAPE_SPHERE, 1, 0, rot_big);
    assert_close(ts_shape_area(&rb, 0), 36 * TS_PI_D, 1e-9, "rotated, scaled area"); /* double round-off */
    /* Non-uniform: the ellipsoid's area by Thomsen's formula, within its 1.1% of the truth
     * (the prolate spheroid a = 1, c = 2 has area 2π(1 + 2·asin(e)/e), e = √3/2). */
    ts_shape ell = make_analytic(TS_SHAPE_SPHERE, 1, 0, ts_xform_scale((ts_dvec3){1, 1, 2}));
    double e = sqrt(3.0) / 2, exact = 2 * TS_PI_D * (1 + 2 * asin(e) / e);
    assert_close(ts_shape_area(&ell, 0), exact, 0.011 * exact, "ellipsoid area");
    ts_bounds3 b = ts_shape_bounds(&s);
    assert_true(b.lo.x <= -1 && b.lo.y <= 0 && b.lo.z <= 1 && b.hi.x >= 3 && b.hi.y >= 4 && b.hi.z >= 5);
    assert_true(b.lo.x > -1.001f && b.hi.z < 5.001f);
}

static void test_disk_known(void **state)
{
    (void)state;
    ts_shape s = make_analytic(TS_SHAPE_DISK, 1, 0.5, ts_xform_identity());
    ts_ray r = ts_ray_make((ts_vec3){0.75f, 0, 5}, (ts_vec3){0, 0, -1}, INFINITY);
    float t;
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    assert_close(t, 5, 0, "t");
    ts_interaction si;
    ts_shape_interaction(&s, 0, 0, &r, t, &si);
    assert_vec_close(si.p, (ts_vec3){0.75f, 0, 0}, 0, "p");
    assert_vec_close(si.n, (ts_vec3){0, 0, 1}, 0, "n");
    assert_close(si.uv.x, 0, FTOL, "u");
    assert_close(si.uv.y, 0.5, FTOL, "v = (r − r_hit)/(r − r_i)");
    assert_vec_close(si.dpdu, (ts_vec3){0, 2 * TS_PI * 0.75f, 0}, 1e-5, "dpdu");
    assert_vec_close(si.dpdv, (ts_vec3){-0.5f, 0, 0}, 1e-6, "dpdv = (x, y, 0)(r_i − r)/r_hit");
    /* From below: same hit, same (+z) normal. */
    r = ts_ray_make((ts_vec3){0, -0.75f, -2}, (ts_vec3){0, 0, 1}, INFINITY);
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    ts_shape_interaction(&s, 0, 0, &r, t, &si);
    assert_vec_close(si.n, (ts_vec3){0, 0, 1}, 0, "n from below");
    assert_close(si.uv.x, 0.75, FTOL, "u at φ = 3π/2");
    /* Inside the inner radius, outside the radius, parallel: misses. */
    r = ts_ray_make((ts_vec3){0.25f, 0, 5}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){0, 0, 5}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){1.5f, 0, 5}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){-5, 0.75f, 0}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    /* Placed by a frame (centre, normal): faces along the normal. */
    ts_shape f = make_analytic(TS_SHAPE_DISK, 2, 0, ts_xform_frame((ts_dvec3){0, 1, 0}, (ts_dvec3){0, -1, 0}));
    r = ts_ray_make((ts_vec3){0.5f, 5, 0.5f}, (ts_vec3){0, -1, 0}, INFINITY);
    assert_true(ts_shape_intersect(&f, &r, INFINITY, &t));
    assert_close(t, 4, 0, "t framed");
    ts_shape_interaction(&f, 0, 0, &r, t, &si);
    assert_vec_close(si.n, (ts_vec3){0, -1, 0}, FTOL, "n framed");
    /* Area π(r² − r_i²), exact under any linear map (here a 2×3 stretch of the plane). */
    assert_close(ts_shape_area(&s, 0), TS_PI_D * 0.75, 1e-12, "area");
    ts_shape st = make_analytic(TS_SHAPE_DISK, 1, 0, ts_xform_scale((ts_dvec3){2, 3, 7}));
    assert_close(ts_shape_area(&st, 0), TS_PI_D * 6, 1e-12, "stretched area");
}

static void test_cylinder_known(void **state)
{
    (void)state;
    ts_shape s = make_analytic(TS_SHAPE_CYLINDER, 1, 2, ts_xform_identity());
    float t;
    ts_interaction si;
    /* From outside. */
    ts_ray r = ts_ray_make((ts_vec3){-5, 0, 1}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    assert_close(t, 4, 0, "t");
    ts_shape_interaction(&s, 0, 0, &r, t, &si);
    assert_vec_close(si.p, (ts_vec3){-1, 0, 1}, 0, "p");
    assert_vec_close(si.n, (ts_vec3){-1, 0, 0}, FTOL, "n");
    assert_close(si.uv.x, 0.5, FTOL, "u");
    assert_close(si.uv.y, 0.5, FTOL, "v");
    assert_vec_close(si.dpdu, (ts_vec3){0, -2 * TS_PI, 0}, 1e-5, "dpdu");
    assert_vec_close(si.dpdv, (ts_vec3){0, 0, 2}, 0, "dpdv");
    /* From inside the tube: the wall ahead, normal still outwards. */
    r = ts_ray_make((ts_vec3){0, 0, 1}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    assert_close(t, 1, 0, "t inside");
    ts_shape_interaction(&s, 0, 0, &r, t, &si);
    assert_vec_close(si.n, (ts_vec3){1, 0, 0}, FTOL, "n inside");
    /* In through the open end, onto the inner wall at z = 1. */
    r = ts_ray_make((ts_vec3){0, 0, -1}, (ts_vec3){0.5f, 0, 1}, INFINITY);
    assert_true(ts_shape_intersect(&s, &r, INFINITY, &t));
    assert_close(t, 2, 0, "t through the end");
    /* Misses: above the end, along the axis, straight through both open ends. */
    r = ts_ray_make((ts_vec3){-5, 0, 3}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){0, 0, -5}, (ts_vec3){0, 0, 1}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){0, 0, -1}, (ts_vec3){0.1f, 0, 1}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    /* Near wall below z = 0, far wall above z = h: the tube is missed although the
     * infinite cylinder is hit twice. */
    r = ts_ray_make((ts_vec3){-2, 0, -4}, (ts_vec3){1, 0, 3}, INFINITY);
    assert_false(ts_shape_intersect(&s, &r, INFINITY, &t));
    /* Area 2πrh; with a scale along the axis and a uniform one across, still exact. */
    assert_close(ts_shape_area(&s, 0), 4 * TS_PI_D, 1e-12, "area");
    ts_shape sc = make_analytic(TS_SHAPE_CYLINDER, 1, 2, ts_xform_scale((ts_dvec3){3, 3, 5}));
    assert_close(ts_shape_area(&sc, 0), 2 * TS_PI_D * 3 * 10, 1e-9, "scaled area");
    /* Elliptic cross-section (semi-axes 1 and 3): perimeter 13.3648932…, Ramanujan's
     * formula is good to 1e-5 relative there. */
    ts_shape el = make_analytic(TS_SHAPE_CYLINDER, 1, 1, ts_xform_scale((ts_dvec3){1, 3, 1}));
    assert_close(ts_shape_area(&el, 0), 13.3648932, 13.37e-5, "elliptic area");
}

static void test_triangle_known(void **state)
{
    (void)state;
    tri_store st;
    ts_shape s = make_triangle(&st, (ts_vec3){0, 0, 0}, (ts_vec3){1, 0, 0}, (ts_vec3){0, 1, 0});
    ts_ray r = ts_ray_make((ts_vec3){0.25f, 0.25f, 1}, (ts_vec3){0, 0, -1}, INFINITY);
    float t;
    assert_true(ts_shape_triangle_intersect(&s, 0, &r, INFINITY, &t));
    assert_close(t, 1, 0, "t");
    ts_interaction si;
    ts_shape_interaction(&s, 3, 0, &r, t, &si);
    assert_int_equal(si.shape, 3);
    assert_int_equal(si.prim, 0);
    assert_vec_close(si.p, (ts_vec3){0.25f, 0.25f, 0}, 0, "p");
    assert_vec_close(si.n, (ts_vec3){0, 0, 1}, 0, "n");
    assert_vec_close(si.ns, si.n, 0, "ns without vertex normals");
    /* Default uvs (0,0), (1,0), (1,1) with b = (0.5, 0.25, 0.25). */
    assert_close(si.uv.x, 0.5, FTOL, "u");
    assert_close(si.uv.y, 0.25, FTOL, "v");
    assert_vec_close(si.dpdu, (ts_vec3){1, 0, 0}, FTOL, "dpdu");
    assert_vec_close(si.dpdv, (ts_vec3){-1, 1, 0}, FTOL, "dpdv");
    /* From behind: hit, same normal. */
    r = ts_ray_make((ts_vec3){0.25f, 0.25f, -1}, (ts_vec3){0, 0, 2}, INFINITY);
    assert_true(ts_shape_triangle_intersect(&s, 0, &r, INFINITY, &t));
    assert_close(t, 0.5, 0, "t behind");
    ts_shape_interaction(&s, 0, 0, &r, t, &si);
    assert_vec_close(si.n, (ts_vec3){0, 0, 1}, 0, "n behind");
    /* Misses: beyond the hypotenuse, pointing away, tmax short of it. */
    r = ts_ray_make((ts_vec3){0.75f, 0.75f, 1}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_false(ts_shape_triangle_intersect(&s, 0, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){0.25f, 0.25f, 1}, (ts_vec3){0, 0, 1}, INFINITY);
    assert_false(ts_shape_triangle_intersect(&s, 0, &r, INFINITY, &t));
    r = ts_ray_make((ts_vec3){0.25f, 0.25f, 1}, (ts_vec3){0, 0, -1}, 1);
    assert_false(ts_shape_triangle_intersect(&s, 0, &r, 1, &t));
    /* Vertex normals facing −z: the shading normal is flipped to n's side. */
    for (int k = 0; k < 3; k++) st.n[3 * k] = 0, st.n[3 * k + 1] = 0, st.n[3 * k + 2] = -1;
    s.mesh.n = st.n;
    r = ts_ray_make((ts_vec3){0.25f, 0.25f, 1}, (ts_vec3){0, 0, -1}, INFINITY);
    ts_shape_interaction(&s, 0, 0, &r, 1, &si);
    assert_vec_close(si.ns, (ts_vec3){0, 0, 1}, 0, "ns flipped");
    /* Tilted vertex normals interpolate: b = (0.5, 0.25, 0.25), n1 tilted to +x. */
    st.n[2] = st.n[8] = 1;
    st.n[3] = 1, st.n[5] = 0;
    ts_shape_interaction(&s, 0, 0, &r, 1, &si);
    ts_vec3 want = ts_vec3_normalize((ts_vec3){0.25f, 0, 0.75f});
    assert_vec_close(si.ns, want, FTOL, "ns interpolated");
    /* Vertex uvs: the hit's uv and ∂p/∂u, ∂p/∂v follow them (u along y, v along x). */
    float uvs[6] = {0, 0, 0, 1, 1, 0};
    memcpy(st.uv, uvs, sizeof uvs);
    s.mesh.uv = st.uv;
    ts_shape_interaction(&s, 0, 0, &r, 1, &si);
    assert_close(si.uv.x, 0.25, FTOL, "u from vertex uvs");
    assert_close(si.uv.y, 0.25, FTOL, "v from vertex uvs");
    assert_vec_close(si.dpdu, (ts_vec3){0, 1, 0}, FTOL, "dpdu from uvs");
    assert_vec_close(si.dpdv, (ts_vec3){1, 0, 0}, FTOL, "dpdv from uvs");
    /* Degenerate uvs: an orthonormal frame around n. */
    memset(st.uv, 0, sizeof st.uv);
    ts_shape_interaction(&s, 0, 0, &r, 1, &si);
    assert_close(ts_vec3_dot(si.dpdu, si.n), 0, FTOL, "dpdu ⟂ n");
    assert_close(ts_vec3_dot(si.dpdv, si.n), 0, FTOL, "dpdv ⟂ n");
    assert_close(ts_vec3_length(si.dpdu), 1, FTOL, "|dpdu|");
    /* Orientation (p1 − p0) × (p2 − p0), area ½|e1 × e2|, bounds of the vertices. */
    ts_shape cw = make_triangle(&st, (ts_vec3){0, 0, 0}, (ts_vec3){0, 2, 0}, (ts_vec3){3, 0, 0});
    ts_shape_interaction(&cw, 0, 0, &(ts_ray){{0.5f, 0.5f, 1}, {0, 0, -1}, INFINITY, TS_NONE, TS_NONE}, 1, &si);
    assert_vec_close(si.n, (ts_vec3){0, 0, -1}, 0, "clockwise n");
    assert_close(ts_shape_area(&cw, 0), 3, 0, "area");
    ts_bounds3 b = ts_shape_triangle_bounds(&cw, 0);
    assert_vec_close(b.lo, (ts_vec3){0, 0, 0}, 0, "bounds lo");
    assert_vec_close(b.hi, (ts_vec3){3, 2, 0}, 0, "bounds hi");
}

/* ---- the filter's test with the cache: the same answer as without ---- */

/* ts_shape_triangle_ahead_cached answers most queries from the cached float normal and
 * leaves the unclear ones to the exact test (shape.c, triangle_ahead_clear); its answer
 * must be ts_shape_triangle_ahead's for every ray. The rays are chosen around both of
 * the shortcut's boundaries, where a shortcut taken too eagerly answers differently:
 * origins at log-uniform distances 0 and 1e-16…1e-1 (relative to the triangle's size)
 * off its plane, on either side, at up to 3 sizes from it, and directions random or
 * within 1e-12…1e-1 of the plane. A deterministic check (fixed seed): it fails on any
 * single disagreement, and the counts below show that both answers occur where the
 * exact test is close to its threshold (origin within 1e-12 of the plane). */
static void test_triangle_ahead_cached(void **state)
{
    (void)state;
    ts_pcg32 g;
    ts_pcg32_seed(&g, 0x5eedu, 7);
    int n = 0, disagree = 0, near_yes = 0, near_no = 0, yes = 0;
    for (int tri = 0; tri < 400; tri++) {
        tri_store st;
        double L = exp(rnd_range(&g, log(1e-3), log(1e3)));
        ts_shape s = rnd_triangle(&g, &st, L, 1e4);
        ts_tri_cache c;
        ts_shape_triangle_cache_init(&s, 0, &c);
        ts_dvec3 v[3];
        for (int k = 0; k < 3; k++) v[k] = (ts_dvec3){st.p[3 * k], st.p[3 * k + 1], st.p[3 * k + 2]};
        ts_dvec3 e1 = ts_dvec3_sub(v[1], v[0]), e2 = ts_dvec3_sub(v[2], v[0]);
        ts_dvec3 N = ts_dvec3_cross(e1, e2);
        if (!(ts_dvec3_length(N) > 0)) continue;
        N = ts_dvec3_normalize(N);
        double size = ts_dvec3_length(e1) + ts_dvec3_length(e2);
        for (int i = 0; i < 500; i++) {
            ts_ray r;
            double rel = 1;
            if (i < 100) {
                r = rnd_ray_triangle(&g, &s);
            } else {
                double b1 = rnd_range(&g, -3, 3), b2 = rnd_range(&g, -3, 3);
                rel = rnd(&g) < 0.1 ? 0 : exp(rnd_range(&g, log(1e-16), log(1e-1)));
                double off = (rnd(&g) < 0.5 ? -1 : 1) * rel * size;
                ts_dvec3 o = ts_dvec3_add(ts_dvec3_add(v[0], ts_dvec3_add(ts_dvec3_scale(e1, b1), ts_dvec3_scale(e2, b2))),
                                          ts_dvec3_scale(N, off));
                ts_dvec3 d = rnd_unit(&g);
                if (rnd(&g) < 0.5) { /* nearly along the plane */
                    ts_dvec3 u = ts_dvec3_normalize(ts_dvec3_cross(N, d));
                    double dz = (rnd(&g) < 0.5 ? -1 : 1) * exp(rnd_range(&g, log(1e-12), log(1e-1)));
                    d = ts_dvec3_add(u, ts_dvec3_scale(N, dz));
                }
                r = ts_ray_make(to_f(o), to_f(d), INFINITY);
            }
            bool want = ts_shape_triangle_ahead(&s, 0, &r);
            bool got = ts_shape_triangle_ahead_cached(&s, &c, 0, &r);
            n++;
            if (want != got) {
                if (disagree < 5) fprintf(stderr, "triangle %d ray %d: ahead %d, cached %d\n", tri, i, want, got);
                disagree++;
            }
            yes += want;
            if (i >= 100 && rel < 1e-12) {
                if (want) near_yes++;
                else near_no++;
            }
        }
    }
    printf("triangle_ahead_cached: %d rays, %d ahead; origin within 1e-12: %d ahead, %d not; %d disagree\n", n, yes,
           near_yes, near_no, disagree);
    assert_int_equal(disagree, 0);
    assert_true(near_yes > 100 && near_no > 100); /* both answers near the threshold */
    assert_true(yes > n / 10 && yes < n - n / 10);
}

/* ---- grazing and just-missing rays (values exact in float and double) ---- */

static void test_grazing(void **state)
{
    (void)state;
    float t;
    ts_interaction si;
    const float below = nextafterf(1, 0), above = nextafterf(1, 2);
    /* Sphere r = 1: the line y = 1 − 2^-24 hits, y = 1 + 2^-23 misses; y = 1 exactly touches. */
    ts_shape sp = make_analytic(TS_SHAPE_SPHERE, 1, 0, ts_xform_identity());
    ts_ray r = ts_ray_make((ts_vec3){-10, below, 0}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_true(ts_shape_intersect(&sp, &r, INFINITY, &t));
    ts_shape_interaction(&sp, 0, 0, &r, t, &si);
    lv3 exact = {-sqrtl(1 - (ld)below * below), below, 0};
    assert_true(bound_ratio(&si, exact) <= 1);
    r.o.y = above;
    assert_false(ts_shape_intersect(&sp, &r, INFINITY, &t));
    r.o.y = 1;
    if (ts_shape_intersect(&sp, &r, INFINITY, &t)) {
        ts_shape_interaction(&sp, 0, 0, &r, t, &si);
        assert_true(bound_ratio(&si, (lv3){0, 1, 0}) <= 1);
    }
    /* Cylinder r = 1, h = 2: the same about its wall. */
    ts_shape cy = make_analytic(TS_SHAPE_CYLINDER, 1, 2, ts_xform_identity());
    r = ts_ray_make((ts_vec3){-10, below, 1}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_true(ts_shape_intersect(&cy, &r, INFINITY, &t));
    ts_shape_interaction(&cy, 0, 0, &r, t, &si);
    assert_true(bound_ratio(&si, (lv3){-sqrtl(1 - (ld)below * below), below, 1}) <= 1);
    r.o.y = above;
    assert_false(ts_shape_intersect(&cy, &r, INFINITY, &t));
    /* ... and about its ends: z = 2 is on the tube, one ulp above is not. */
    r = ts_ray_make((ts_vec3){-10, 0, 2}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_true(ts_shape_intersect(&cy, &r, INFINITY, &t));
    r.o.z = nextafterf(2, 3);
    assert_false(ts_shape_intersect(&cy, &r, INFINITY, &t));
    r.o.z = 0;
    assert_true(ts_shape_intersect(&cy, &r, INFINITY, &t));
    r.o.z = -FLT_TRUE_MIN;
    assert_false(ts_shape_intersect(&cy, &r, INFINITY, &t));
    /* Disk rims: r = 1 and r_i = 0.5 belong to it, one ulp beyond does not. */
    ts_shape dk = make_analytic(TS_SHAPE_DISK, 1, 0.5, ts_xform_identity());
    r = ts_ray_make((ts_vec3){1, 0, 1}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_true(ts_shape_intersect(&dk, &r, INFINITY, &t));
    r.o.x = above;
    assert_false(ts_shape_intersect(&dk, &r, INFINITY, &t));
    r.o.x = 0.5f;
    assert_true(ts_shape_intersect(&dk, &r, INFINITY, &t));
    r.o.x = nextafterf(0.5f, 0);
    assert_false(ts_shape_intersect(&dk, &r, INFINITY, &t));
    /* A ray in the disk's plane never hits it. */
    r = ts_ray_make((ts_vec3){-5, 0.75f, 0}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_false(ts_shape_intersect(&dk, &r, INFINITY, &t));
    /* Triangle edges: on the hypotenuse x + y = 1 hits, one ulp outside misses; the same
     * on the edge y = 0. */
    tri_store st;
    ts_shape tr = make_triangle(&st, (ts_vec3){0, 0, 0}, (ts_vec3){1, 0, 0}, (ts_vec3){0, 1, 0});
    r = ts_ray_make((ts_vec3){0.5f, 0.5f, 1}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_true(ts_shape_triangle_intersect(&tr, 0, &r, INFINITY, &t));
    r.o.y = nextafterf(0.5f, 1);
    assert_false(ts_shape_triangle_intersect(&tr, 0, &r, INFINITY, &t));
    r.o = (ts_vec3){0.5f, 0, 1};
    assert_true(ts_shape_triangle_intersect(&tr, 0, &r, INFINITY, &t));
    r.o.y = -FLT_TRUE_MIN;
    assert_false(ts_shape_triangle_intersect(&tr, 0, &r, INFINITY, &t));
    /* A ray in the triangle's plane never hits it. */
    r = ts_ray_make((ts_vec3){-1, 0.25f, 0}, (ts_vec3){1, 0, 0}, INFINITY);
    assert_false(ts_shape_triangle_intersect(&tr, 0, &r, INFINITY, &t));
}

/* ---- the error bound contains the exact hit ---- */

typedef struct bound_stats {
    long rays, hits, both, ambiguous, mismatched;
    double worst, worst_n;
} bound_stats;

static void check_bound_ray(const ts_shape *s, const ts_ray *r, bound_stats *st)
{
    float t;
    bool hit = shape_hit(s, r, &t);
    ref_hit ex = ref_intersect(s, r->o, r->d);
    st->rays++;
    st->hits += hit;
    if (ex.ambiguous) {
        st->ambiguous++;
        return;
    }
    if (hit != ex.hit) {
        st->mismatched++;
        fail_msg("hit %d but exact %d: ray o=(%.9g %.9g %.9g) d=(%.9g %.9g %.9g), type %d", hit, ex.hit, r->o.x, r->o.y,
                 r->o.z, r->d.x, r->d.y, r->d.z, s->type);
    }
    if (!hit) return;
    st->both++;
    ts_interaction si;
    ts_shape_interaction(s, 0, 0, r, t, &si);
    /* The hit lies in the shape's (conservative) world bounds. */
    ts_bounds3 b = ts_shape_bounds(s);
    for (int i = 0; i < 3; i++)
        if (!(vget(si.p, i) >= vget(b.lo, i) && vget(si.p, i) <= vget(b.hi, i)))
            fail_msg("hit outside the bounds on axis %d: %.9g not in [%.9g, %.9g]", i, vget(si.p, i), vget(b.lo, i),
                     vget(b.hi, i));
    double ratio = bound_ratio(&si, ex.p);
    if (ratio > st->worst) st->worst = ratio;
    if (!(ratio <= 1))
        fail_msg("bound violated (ratio %g): p=(%.9g %.9g %.9g) exact=(%.12Lg %.12Lg %.12Lg) err=(%g %g %g) type %d",
                 ratio, si.p.x, si.p.y, si.p.z, ex.p.x, ex.p.y, ex.p.z, si.p_error.x, si.p_error.y, si.p_error.z,
                 s->type);
    /* The geometric normal: a unit float vector within a few ulps of the exact one. */
    double dn = 1 - (double)lv_dot(lv_from(si.n), ex.n);
    if (dn > st->worst_n) st->worst_n = dn;
    assert_true(dn < 1e-6);
    /* t: float rounding of the double root (relative 2^-24), plus the slide of grazing hits. */
    double tol = 1e-6 * (double)ex.t + 2 * ts_vec3_max_component(si.p_error) / ts_vec3_length(r->d);
    assert_close(t, (double)ex.t, tol, "t");
}

static void report(const char *name, const bound_stats *st)
{
    print_message("  %-9s %ld rays, %ld hits, %ld compared, %ld ambiguous; worst |p − exact|/p_error = %.3g, "
                  "worst 1 − n·n_exact = %.2g\n",
                  name, st->rays, st->hits, st->both, st->ambiguous, st->worst, st->worst_n);
}

/* 10^5 rays per shape: 3 sizes × 50 placements × 667 rays. */
#define BOUND_PLACEMENTS 50
#define BOUND_RAYS 667

static void bound_test_analytic(ts_shape_type type, const char *name, uint64_t seed)
{
    ts_pcg32 g;
    ts_pcg32_seed(&g, seed, 1);
    bound_stats st = {0};
    const double radii[3] = {1e-4, 1, 1e4};
    for (int ri = 0; ri < 3; ri++)
        for (int k = 0; k < BOUND_PLACEMENTS; k++) {
            ts_shape s = rnd_analytic(&g, type, radii[ri], 1e3, 2);
            for (int i = 0; i < BOUND_RAYS; i++) {
                ts_ray r = rnd_ray_analytic(&g, &s);
                check_bound_ray(&s, &r, &st);
            }
        }
    report(name, &st);
    assert_true(st.worst <= 1);
    /* Ambiguity needs a float ray within 1e-10 of a boundary: a handful at most. */
    assert_true(st.ambiguous <= st.rays / 10000);
    assert_true(st.both > st.rays / 10);
}

static void test_bound_sphere(void **state) { (void)state; bound_test_analytic(TS_SHAPE_SPHERE, "sphere", 11); }
static void test_bound_disk(void **state) { (void)state; bound_test_analytic(TS_SHAPE_DISK, "disk", 12); }
static void test_bound_cylinder(void **state) { (void)state; bound_test_analytic(TS_SHAPE_CYLINDER, "cylinder", 13); }

static void test_bound_triangle(void **state)
{
    (void)state;
    ts_pcg32 g;
    ts_pcg32_seed(&g, 14, 1);
    bound_stats st = {0};
    const double sizes[3] = {1e-4, 1, 1e4};
    for (int si = 0; si < 3; si++)
        for (int k = 0; k < BOUND_PLACEMENTS; k++) {
            tri_store store;
            ts_shape s = rnd_triangle(&g, &store, sizes[si], 1e3);
            for (int i = 0; i < BOUND_RAYS; i++) {
                ts_ray r = rnd_ray_triangle(&g, &s);
                check_bound_ray(&s, &r, &st);
            }
        }
    report("triangle", &st);
    assert_true(st.worst <= 1);
    assert_true(st.ambiguous <= st.rays / 10000);
    assert_true(st.both > st.rays / 10);
}

/* ---- spawned rays never re-hit the surface they leave ---- */

#define SPAWN_DIRS 10000

typedef struct spawn_stats {
    long rays, hits_front, hits_back, ambiguous;
    double min_hit_dist; /* cylinder: nearest legitimate hit, in radii */
} spawn_stats;

/* Uniform direction in the hemisphere of n (side > 0) or of −n. */
static ts_vec3 rnd_hemisphere(ts_pcg32 *g, ts_vec3 n, float side)
{
    ts_vec3 a, b;
    ts_coordinate_system(n, &a, &b);
    float z = ts_pcg32_float(g), phi = 2 * TS_PI * ts_pcg32_float(g), r = sqrtf(fmaxf(0, 1 - z * z));
    ts_vec3 d = ts_vec3_add(ts_vec3_add(ts_vec3_scale(a, r * cosf(phi)), ts_vec3_scale(b, r * sinf(phi))),
                            ts_vec3_scale(n, side * z));
    return d;
}

/* Spawns SPAWN_DIRS rays on each side of the hit si (exact normal n_exact) and checks
 * each against the exact intersection of that float ray: a hit the exact ray does not
 * have is a re-hit of the surface left behind. */
static void spawn_from(const ts_shape *s, const ts_interaction *si, lv3 n_exact, double size, ts_pcg32 *g,
                       spawn_stats *st)
{
    float front = ts_vec3_dot(si->wo, si->n) >= 0 ? 1.0f : -1.0f;
    for (int side = 0; side < 2; side++) {
        float sgn = side == 0 ? front : -front; /* 0: back towards wo (reflection); 1: through (transmission) */
        for (int i = 0; i < SPAWN_DIRS; i++) {
            ts_vec3 d = rnd_hemisphere(g, si->n, sgn);
            ts_ray r = ts_spawn_ray(si, s, d);
            float t;
            bool hit = shape_hit(s, &r, &t);
            ref_hit ex = ref_intersect(s, r.o, r.d);
            st->rays++;
            if (ex.ambiguous) {
                st->ambiguous++;
                continue;
            }
            if (hit && !ex.hit)
                fail_msg("re-hit: type %d, size %g, side %d, t = %g, p = (%.9g %.9g %.9g), o = (%.9g %.9g %.9g)",
                         s->type, size, side, t, si->p.x, si->p.y, si->p.z, r.o.x, r.o.y, r.o.z);
            if (!hit && ex.hit)
                fail_msg("missed the far side: type %d, size %g, side %d, exact t = %Lg", s->type, size, side, ex.t);
            if (!hit) continue;
            /* A legitimate hit is the exact one: t to float rounding plus the bounds' slack. */
            double dl = ts_vec3_length(r.d);
            assert_close(t, (double)ex.t, 1e-6 * (double)ex.t + 4 * ts_vec3_length(si->p_error) / dl, "spawned t");
            double dist = (double)ex.t * dl;
            if (dist / size < st->min_hit_dist) st->min_hit_dist = dist / size;
            /* Directions clearly off the tangent plane (|cos| > 1e-6, far beyond the float
             * rounding of d and n) cannot hit a flat shape, nor a sphere on the wo side. */
            double cosn = (double)(lv_dot(lv_from(d), n_exact) / lv_len(lv_from(d)));
            bool flat = s->type == TS_SHAPE_DISK || s->type == TS_SHAPE_MESH;
            if ((flat || (s->type == TS_SHAPE_SPHERE && side == 0)) && fabs(cosn) > 1e-6)
                fail_msg("hit a shape that the ray leaves: type %d side %d cos %g", s->type, side, cosn);
            if (side == 0) st->hits_front++;
            else st->hits_back++;
        }
    }
}

static void spawn_test(ts_shape_type type, const char *name, uint64_t seed, int hits_per_placement)
{
    ts_pcg32 g;
    ts_pcg32_seed(&g, seed, 2);
    spawn_stats st = {0, 0, 0, 0, INFINITY};
    const double radii[5] = {1e-4, 1e-2, 1, 1e2, 1e4};
    long n_hits = 0;
    for (int ri = 0; ri < 5; ri++)
        for (int k = 0; k < 2; k++) {
            /* Placements keep the shape within 100 radii of the origin (at most 1e3): a
             * shape a few float ulps across (r = 1e-4 at 1e3) has no room for an offset. */
            double r = radii[ri];
            tri_store store;
            ts_shape s = type == TS_SHAPE_MESH ? rnd_triangle(&g, &store, r, fmin(1e3, 100 * r))
                                               : rnd_analytic(&g, type, r, fmin(1e3, 100 * r), 1);
            for (int h = 0; h < hits_per_placement;) {
                ts_ray ray;
                if (type == TS_SHAPE_MESH) {
                    ray = rnd_ray_triangle(&g, &s);
                } else if (type == TS_SHAPE_CYLINDER && h % 2 == 1) {
                    /* From inside the tube onto its inner wall. */
                    double a = rnd_range(&g, 0, 2 * TS_PI_D), rr = 0.9 * r * sqrt(rnd(&g));
                    ts_dvec3 o = {rr * cos(a), rr * sin(a), rnd(&g) * s.cylinder.height};
                    ts_vec3 of = to_f(ts_xform_point(&s.to_world, o));
                    ts_dvec3 dw = ts_xform_vector(&s.to_world, rnd_unit(&g));
                    ray = ts_ray_make(of, to_f(dw), INFINITY);
                } else {
                    ray = rnd_ray_analytic(&g, &s);
                }
                float t;
                if (!shape_hit(&s, &ray, &t)) continue;
                ref_hit ex = ref_intersect(&s, ray.o, ray.d);
                if (!ex.hit || ex.ambiguous) continue;
                ts_interaction si;
                ts_shape_interaction(&s, 0, 0, &ray, t, &si);
                spawn_from(&s, &si, ex.n, r, &g, &st);
                h++;
                n_hits++;
            }
        }
    print_message("  %-9s %ld hits × 2×%d directions: %ld rays, %ld/%ld legitimate hits (wo side/through), "
                  "%ld ambiguous, nearest hit %.3g radii\n",
                  name, n_hits, SPAWN_DIRS, st.rays, st.hits_front, st.hits_back, st.ambiguous, st.min_hit_dist);
    if (type == TS_SHAPE_SPHERE) assert_true(st.hits_back > 0 && st.hits_front == 0);
    if (type == TS_SHAPE_DISK || type == TS_SHAPE_MESH) assert_true(st.hits_front == 0 && st.hits_back == 0);
    if (type == TS_SHAPE_CYLINDER) assert_true(st.hits_front > 0 && st.hits_back > 0);
    assert_true(st.ambiguous <= st.rays / 10000);
}

/* 5 radii × 2 placements × 10 hits = 100 hits per shape. */
static void test_spawn_sphere(void **state) { (void)state; spawn_test(TS_SHAPE_SPHERE, "sphere", 21, 10); }
static void test_spawn_disk(void **state) { (void)state; spawn_test(TS_SHAPE_DISK, "disk", 22, 10); }
static void test_spawn_cylinder(void **state) { (void)state; spawn_test(TS_SHAPE_CYLINDER, "cylinder", 23, 10); }
static void test_spawn_triangle(void **state) { (void)state; spawn_test(TS_SHAPE_MESH, "triangle", 24, 10); }

/* Two coplanar triangles sharing an edge: rays leaving one close to the shared edge never
 * hit the other (tested with the double-precision triangle test, no skip ids involved). */
static void test_spawn_quad(void **state)
{
    (void)state;
    ts_pcg32 g;
    ts_pcg32_seed(&g, 25, 3);
    long rays = 0;
    for (int q = 0; q < 20; q++) {
        double L = exp(rnd_range(&g, log(1e-3), log(1e3)));
        ts_dvec3 c = ts_dvec3_scale(rnd_unit(&g), fmin(1e3, 100 * L) * rnd(&g));
        ts_dvec3 eu = ts_dvec3_normalize(rnd_unit(&g));
        ts_dvec3 ev = ts_dvec3_normalize(ts_dvec3_cross(eu, rnd_unit(&g)));
        eu = ts_dvec3_scale(eu, L), ev = ts_dvec3_scale(ev, L);
        ts_vec3 q0 = to_f(ts_dvec3_sub(ts_dvec3_sub(c, eu), ev)), q1 = to_f(ts_dvec3_sub(ts_dvec3_add(c, eu), ev));
        ts_vec3 q2 = to_f(ts_dvec3_add(ts_dvec3_add(c, eu), ev)), q3 = to_f(ts_dvec3_add(ts_dvec3_sub(c, eu), ev));
        tri_store sa, sb;
        ts_shape A = make_triangle(&sa, q0, q1, q2), B = make_triangle(&sb, q0, q2, q3);
        for (int h = 0; h < 5; h++) {
            /* A point of A at distance 10^[-7, -2]·L from the diagonal q0–q2. */
            double along = rnd_range(&g, 0.05, 0.95), off = exp(rnd_range(&g, log(1e-7), log(1e-2)));
            ts_dvec3 P = ts_dvec3_add(ts_dvec3_from(q0),
                                      ts_dvec3_scale(ts_dvec3_sub(ts_dvec3_from(q2), ts_dvec3_from(q0)), along));
            P = ts_dvec3_add(P, ts_dvec3_scale(ts_dvec3_normalize(ts_dvec3_sub(eu, ev)), off * L));
            ts_dvec3 from = ts_dvec3_add(P, ts_dvec3_scale(rnd_unit(&g), 3 * L));
            ts_vec3 of = to_f(from);
            ts_ray r = ts_ray_make(of, to_f(ts_dvec3_sub(P, ts_dvec3_from(of))), INFINITY);
            float t;
            if (!ts_shape_triangle_intersect(&A, 0, &r, INFINITY, &t)) continue;
            ts_interaction si;
            ts_shape_interaction(&A, 0, 0, &r, t, &si);
            for (int i = 0; i < 2 * SPAWN_DIRS; i++) {
                ts_vec3 d = rnd_hemisphere(&g, si.n, i % 2 ? 1.0f : -1.0f);
                ts_ray sr = ts_spawn_ray(&si, &A, d);
                rays++;
                if (ts_shape_triangle_intersect(&B, 0, &sr, INFINITY, &t))
                    fail_msg("ray leaving A hit its neighbour B at t = %g (L = %g, offset %g)", t, L, off);
                if (ts_shape_triangle_intersect(&A, 0, &sr, INFINITY, &t)) fail_msg("ray leaving A hit A");
            }
        }
    }
    print_message("  quad      %ld rays leaving one triangle near the shared edge: no hit on either\n", rays);
    assert_true(rays > 0);
}

/* ---- spawn_ray_to ---- */

static void test_spawn_ray_to(void **state)
{
    (void)state;
    ts_shape shapes[2];
    tri_store st;
    shapes[0] = make_analytic(TS_SHAPE_SPHERE, 1, 0, ts_xform_identity());
    shapes[1] = make_triangle(&st, (ts_vec3){-5, -5, 5}, (ts_vec3){5, -5, 5}, (ts_vec3){0, 5, 5});
    ts_ray r = ts_ray_make((ts_vec3){0.1f, 0.2f, 10}, (ts_vec3){0, 0, -1}, INFINITY);
    float t;
    assert_true(ts_shape_intersect(&shapes[0], &r, INFINITY, &t));
    ts_interaction a, b;
    ts_shape_interaction(&shapes[0], 0, 0, &r, t, &a);
    r = ts_ray_make((ts_vec3){0.3f, 3, 10}, (ts_vec3){0, 0, -1}, INFINITY);
    assert_true(ts_shape_triangle_intersect(&shapes[1], 0, &r, INFINITY, &t));
    ts_shape_interaction(&shapes[1], 1, 0, &r, t, &b);
    /* From the sphere to the triangle: no skip ids, both ends offset, tmax 1 − ε. */
    ts_ray s = ts_spawn_ray_to(&a, shapes, b.p, b.p_error, b.n);
    assert_int_equal(s.skip_shape, TS_NONE);
    assert_close(s.tmax, 1 - TS_SHADOW_EPSILON, 0, "tmax");
    ts_vec3 end = ts_vec3_add(s.o, s.d);
    assert_true(ts_vec3_distance(s.o, a.p) > 0 && ts_vec3_distance(s.o, a.p) < 1e-5f);
    assert_true(ts_vec3_distance(end, b.p) > 0 && ts_vec3_distance(end, b.p) < 1e-5f);
    assert_false(ts_shape_intersect(&shapes[0], &s, s.tmax, &t));
    assert_false(ts_shape_triangle_intersect(&shapes[1], 0, &s, s.tmax, &t));
    /* From the triangle: its ids are named; towards a point light (no normal, no error). */
    s = ts_spawn_ray_to(&b, shapes, (ts_vec3){0, 0, 8}, (ts_vec3){0, 0, 0}, (ts_vec3){0, 0, 0});
    assert_int_equal(s.skip_shape, 1);
    assert_int_equal(s.skip_prim, 0);
    assert_vec_close(ts_vec3_add(s.o, s.d), (ts_vec3){0, 0, 8}, 1e-6, "target");
    /* ts_spawn_ray from the sphere: no ids; from the triangle: ids. */
    assert_int_equal(ts_spawn_ray(&a, shapes, a.n).skip_shape, TS_NONE);
    ts_ray sb = ts_spawn_ray(&b, shapes, b.n);
    assert_int_equal(sb.skip_shape, 1);
    assert_true(isinf(sb.tmax));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_known),   cmocka_unit_test(test_disk_known),
        cmocka_unit_test(test_cylinder_known), cmocka_unit_test(test_triangle_known),
        cmocka_unit_test(test_grazing),        cmocka_unit_test(test_bound_sphere),
        cmocka_unit_test(test_bound_disk),     cmocka_unit_test(test_bound_cylinder),
        cmocka_unit_test(test_bound_triangle), cmocka_unit_test(test_spawn_sphere),
        cmocka_unit_test(test_spawn_disk),     cmocka_unit_test(test_spawn_cylinder),
        cmocka_unit_test(test_spawn_triangle), cmocka_unit_test(test_spawn_quad),
        cmocka_unit_test(test_spawn_ray_to),   cmocka_unit_test(test_triangle_ahead_cached),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
