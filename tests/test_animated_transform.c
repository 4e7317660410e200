/* test_animated_transform.c — pbrt's AnimatedTransform (core/animated_transform.h):
 * interpolated matrices against closed forms, the decomposition's round trip, the shorter
 * arc, the clamping at the ends, and motion bounds that contain a rotating box. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>

#include "core/animated_transform.h"
#include "core/hash.h"

static void assert_close(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%.17g != %.17g (tolerance %g)", a, b, tol);
}

static void assert_mat_close(const ts_mat4 *a, const ts_mat4 *b, double tol)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!(fabs(a->m[i][j] - b->m[i][j]) <= tol))
                fail_msg("m[%d][%d]: %.17g != %.17g (tolerance %g)", i, j, a->m[i][j], b->m[i][j], tol);
}

static ts_xform compose3(ts_xform a, ts_xform b, ts_xform c)
{
    ts_xform ab = ts_xform_compose(&a, &b);
    return ts_xform_compose(&ab, &c);
}

/* Translation (0,0,0) → (2,4,0), rotation 0° → 90° about z, scale 1 → 3 along x over
 * [1, 3]: at t = 2 the book's T·R·S with the halves: (1,2,0), 45°, 2. */
static void test_interpolated_matrix(void **state)
{
    (void)state;
    ts_xform a = ts_xform_identity();
    ts_xform b = compose3(ts_xform_translate((ts_dvec3){2, 4, 0}), ts_xform_rotate(90, (ts_dvec3){0, 0, 1}),
                          ts_xform_scale((ts_dvec3){3, 1, 1}));
    ts_anim_xform x;
    assert_true(ts_anim_xform_init(&x, &a, 1, &b, 3));
    assert_true(x.animated);
    ts_mat4 m = ts_anim_xform_matrix(&x, 2);
    ts_xform want = compose3(ts_xform_translate((ts_dvec3){1, 2, 0}), ts_xform_rotate(45, (ts_dvec3){0, 0, 1}),
                             ts_xform_scale((ts_dvec3){2, 1, 1}));
    assert_mat_close(&m, &want.m, 1e-14);
    /* A quarter of the way: 22.5°, (0.5, 1, 0), 1.5. */
    m = ts_anim_xform_matrix(&x, 1.5);
    want = compose3(ts_xform_translate((ts_dvec3){0.5, 1, 0}), ts_xform_rotate(22.5, (ts_dvec3){0, 0, 1}),
                    ts_xform_scale((ts_dvec3){1.5, 1, 1}));
    assert_mat_close(&m, &want.m, 1e-14);
    /* With its inverse. */
    ts_xform xi;
    assert_true(ts_anim_xform_at(&x, 1.5, &xi));
    ts_mat4 id = ts_mat4_mul(&xi.m, &xi.m_inv), I = ts_mat4_identity();
    assert_mat_close(&id, &I, 1e-14);
}

/* At and beyond the ends the keyframes themselves, bit for bit; equal keyframes are static
 * at every time, even with times that could not animate. */
static void test_ends_and_static(void **state)
{
    (void)state;
    ts_xform a = compose3(ts_xform_translate((ts_dvec3){0.1, 0.2, 0.3}), ts_xform_rotate(33, (ts_dvec3){1, 2, 3}),
                          ts_xform_scale((ts_dvec3){0.7, 1.3, 2.9}));
    ts_xform b = compose3(ts_xform_translate((ts_dvec3){-1, 5, 2}), ts_xform_rotate(-71, (ts_dvec3){0, 1, 0}),
                          ts_xform_scale((ts_dvec3){1, 1, 1}));
    ts_anim_xform x;
    assert_true(ts_anim_xform_init(&x, &a, 0, &b, 1));
    double times[] = {-5, 0, 1, 7};
    for (int k = 0; k < 4; k++) {
        ts_xform got;
        assert_true(ts_anim_xform_at(&x, times[k], &got));
        const ts_xform *want = times[k] <= 0 ? &a : &b;
        assert_memory_equal(&got, want, sizeof got);
    }
    ts_anim_xform s;
    assert_true(ts_anim_xform_init(&s, &a, 3, &a, 3)); /* equal: static, any times */
    assert_false(s.animated);
    ts_xform got;
    assert_true(ts_anim_xform_at(&s, 3.5, &got));
    assert_memory_equal(&got, &a, sizeof got);
    /* Different keyframes need t1 > t0. */
    assert_false(ts_anim_xform_init(&x, &a, 1, &b, 1));
    assert_false(ts_anim_xform_init(&x, &a, 2, &b, 1));
    /* A singular keyframe cannot be decomposed. */
    ts_xform flat = ts_xform_scale((ts_dvec3){1, 0, 1});
    flat.m_inv = ts_mat4_identity();
    assert_false(ts_anim_xform_init(&x, &a, 0, &flat, 1));
}

/* M = T·R·S recomposes to M for random proper and mirroring matrices; R is a rotation
 * (orthonormal, det +1), S symmetric. */
static void test_decompose_round_trip(void **state)
{
    (void)state;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 11);
    for (int n = 0; n < 2000; n++) {
        double u[10];
        for (int i = 0; i < 10; i++) u[i] = ts_pcg32_float(&rng);
        ts_dvec3 axis = {u[0] - 0.5, u[1] - 0.5, u[2] - 0.5 + 1e-3};
        ts_dvec3 sc = {0.2 + 3 * u[3], 0.2 + 3 * u[4], 0.2 + 3 * u[5]};
        if (n % 3 == 1) sc.y = -sc.y; /* a mirror */
        ts_xform inner = ts_xform_rotate(360 * u[6], (ts_dvec3){u[7] - 0.5, 0.3, u[8] - 0.5});
        /* T · R · (R2 · D · R2ᵀ)·…: a general (sheared) linear part. */
        ts_xform r2 = ts_xform_inverse(&inner);
        ts_xform m = compose3(ts_xform_translate((ts_dvec3){10 * u[9], -3, 2}), ts_xform_rotate(400 * u[6], axis),
                              compose3(inner, ts_xform_scale(sc), r2));
        ts_dvec3 t;
        ts_quat q;
        ts_mat4 s;
        assert_true(ts_mat4_decompose(&m.m, &t, &q, &s));
        assert_close(ts_quat_dot(q, q), 1, 1e-14);
        ts_mat4 r = ts_quat_to_mat4(q), rt = ts_mat4_transpose(&r), rrt = ts_mat4_mul(&r, &rt), I = ts_mat4_identity();
        assert_mat_close(&rrt, &I, 1e-13);
        double det = r.m[0][0] * (r.m[1][1] * r.m[2][2] - r.m[1][2] * r.m[2][1]) -
                     r.m[0][1] * (r.m[1][0] * r.m[2][2] - r.m[1][2] * r.m[2][0]) +
                     r.m[0][2] * (r.m[1][0] * r.m[2][1] - r.m[1][1] * r.m[2][0]);
        assert_close(det, 1, 1e-13);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) assert_close(s.m[i][j], s.m[j][i], 1e-12);
        ts_mat4 rs = ts_mat4_mul(&r, &s);
        rs.m[0][3] = t.x, rs.m[1][3] = t.y, rs.m[2][3] = t.z;
        assert_mat_close(&rs, &m.m, 1e-12);
    }
}

/* Rotations 0° → 270° about z: pbrt takes the shorter arc, −90°, so halfway is −45°. */
static void test_shorter_arc(void **state)
{
    (void)state;
    ts_xform a = ts_xform_identity(), b = ts_xform_rotate(270, (ts_dvec3){0, 0, 1});
    ts_anim_xform x;
    assert_true(ts_anim_xform_init(&x, &a, 0, &b, 1));
    assert_true(ts_quat_dot(x.r[0], x.r[1]) >= 0);
    ts_mat4 m = ts_anim_xform_matrix(&x, 0.5);
    ts_xform want = ts_xform_rotate(-45, (ts_dvec3){0, 0, 1});
    assert_mat_close(&m, &want.m, 1e-14);
    /* Constant angular speed: at 0.2 of the way, −18°. */
    m = ts_anim_xform_matrix(&x, 0.2);
    want = ts_xform_rotate(-18, (ts_dvec3){0, 0, 1});
    assert_mat_close(&m, &want.m, 1e-14);
    /* 0° → 190°: the end's quaternion (trace < 0 branch) is more than 90° from the start's
     * on the sphere, so it is negated: the arc is −170°, halfway −85°. */
    b = ts_xform_rotate(190, (ts_dvec3){0, 0, 1});
    assert_true(ts_anim_xform_init(&x, &a, 0, &b, 1));
    m = ts_anim_xform_matrix(&x, 0.5);
    want = ts_xform_rotate(-85, (ts_dvec3){0, 0, 1});
    assert_mat_close(&m, &want.m, 1e-14);
    /* Within acos(0.9995) pbrt's normalised lerp: 2° → 1° halfway to float-free accuracy. */
    b = ts_xform_rotate(2, (ts_dvec3){1, 0, 0});
    assert_true(ts_anim_xform_init(&x, &a, 0, &b, 1));
    assert_false(x.has_rotation);
    m = ts_anim_xform_matrix(&x, 0.5);
    want = ts_xform_rotate(1, (ts_dvec3){1, 0, 0});
    assert_mat_close(&m, &want.m, 1e-15);
}

/* A mirroring keyframe (Decision in the header): the interpolation starts at the mirror
 * and moves continuously — halfway between mirror-x and mirror-x turned 90° about z is the
 * mirror turned 45°. */
static void test_mirror(void **state)
{
    (void)state;
    ts_xform a = ts_xform_scale((ts_dvec3){-1, 1, 1});
    ts_xform rz = ts_xform_rotate(90, (ts_dvec3){0, 0, 1});
    ts_xform b = ts_xform_compose(&rz, &a);
    ts_anim_xform x;
    assert_true(ts_anim_xform_init(&x, &a, 0, &b, 1));
    ts_mat4 m = ts_anim_xform_matrix(&x, 0.5);
    ts_xform r45 = ts_xform_rotate(45, (ts_dvec3){0, 0, 1});
    ts_xform want = ts_xform_compose(&r45, &a);
    assert_mat_close(&m, &want.m, 1e-14);
    m = ts_anim_xform_matrix(&x, 1e-9);
    assert_mat_close(&m, &a.m, 1e-8);
}

/* A box spinning 300° about a tilted axis while it moves and grows: the motion bounds hold
 * every corner at 10⁵ random times, and are not loose by more than the margin's share
 * (the step margin is θ·r/128 ≈ 4% of the radius here; allow 10% of the extent). */
static void test_motion_bounds(void **state)
{
    (void)state;
    ts_bounds3 box = {{-1, -0.5f, -0.25f}, {1, 0.5f, 0.25f}};
    ts_xform a = ts_xform_translate((ts_dvec3){3, 0, 0});
    ts_xform b = compose3(ts_xform_translate((ts_dvec3){3, 2, 1}), ts_xform_rotate(300, (ts_dvec3){0.2, 1, 0.3}),
                          ts_xform_scale((ts_dvec3){1.5, 1, 2}));
    ts_anim_xform x;
    assert_true(ts_anim_xform_init(&x, &a, 0, &b, 2));
    ts_bounds3 mb = ts_anim_xform_motion_bounds(&x, box);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 5);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int n = 0; n < 100000; n++) {
        double t = 2.0 * ts_pcg32_float(&rng);
        ts_mat4 m = ts_anim_xform_matrix(&x, t);
        for (int c = 0; c < 8; c++) {
            double p[3] = {(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y, (c & 4) ? box.hi.z : box.lo.z};
            for (int i = 0; i < 3; i++) {
                double v = m.m[i][0] * p[0] + m.m[i][1] * p[1] + m.m[i][2] * p[2] + m.m[i][3];
                lo[i] = fmin(lo[i], v), hi[i] = fmax(hi[i], v);
            }
        }
    }
    double mlo[3] = {mb.lo.x, mb.lo.y, mb.lo.z}, mhi[3] = {mb.hi.x, mb.hi.y, mb.hi.z};
    for (int i = 0; i < 3; i++) {
        assert_true(mlo[i] <= lo[i] && mhi[i] >= hi[i]);
        double ext = hi[i] - lo[i];
        assert_true(lo[i] - mlo[i] <= 0.1 * ext && mhi[i] - hi[i] <= 0.1 * ext);
    }
    /* Without rotation the union of the keyframes' boxes, exactly. */
    ts_xform c = ts_xform_compose(&a, &(ts_xform){ts_xform_scale((ts_dvec3){2, 2, 2}).m, ts_xform_scale((ts_dvec3){0.5, 0.5, 0.5}).m});
    assert_true(ts_anim_xform_init(&x, &a, 0, &c, 1));
    mb = ts_anim_xform_motion_bounds(&x, box);
    assert_true(mb.lo.x == 1 && mb.hi.x == 5 && mb.lo.y == -1 && mb.hi.y == 1 && mb.lo.z == -0.5f && mb.hi.z == 0.5f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_interpolated_matrix), cmocka_unit_test(test_ends_and_static),
        cmocka_unit_test(test_decompose_round_trip), cmocka_unit_test(test_shorter_arc),
        cmocka_unit_test(test_mirror), cmocka_unit_test(test_motion_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
