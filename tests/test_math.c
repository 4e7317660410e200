/* test_math.c — vectors, 4×4 matrices and transforms: inverse, composition, normals. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "core/hash.h"
#include "core/transform.h"
#include "core/vecmath.h"

static void assert_close(double a, double b, double tol)
{
    if (fabs(a - b) > tol) fail_msg("%.17g != %.17g (tolerance %g)", a, b, tol);
}

static void test_vec3_basics(void **state)
{
    (void)state;
    ts_vec3 a = {1, 2, 3}, b = {4, 5, 6};
    assert_close(ts_vec3_dot(a, b), 32, 0);
    ts_vec3 c = ts_vec3_cross(a, b);
    assert_close(c.x, -3, 0);
    assert_close(c.y, 6, 0);
    assert_close(c.z, -3, 0);
    assert_close(ts_vec3_length(ts_vec3_normalize(b)), 1, 1e-6);
    /* The orthonormal basis is orthonormal for every normal, including near −z. */
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 1, 2);
    for (int i = 0; i < 10000; i++) {
        float z = 1 - 2 * ts_pcg32_float(&rng), phi = 2 * TS_PI * ts_pcg32_float(&rng);
        float r = sqrtf(fmaxf(0, 1 - z * z));
        ts_vec3 n = {r * cosf(phi), r * sinf(phi), z}, s, t;
        if (i == 0) n = (ts_vec3){0, 0, -1};
        ts_coordinate_system(n, &s, &t);
        /* Single-precision products of unit vectors: a few ulps of 1. */
        assert_close(ts_vec3_dot(s, t), 0, 1e-6);
        assert_close(ts_vec3_dot(s, n), 0, 1e-6);
        assert_close(ts_vec3_dot(t, n), 0, 1e-6);
        assert_close(ts_vec3_length(s), 1, 1e-6);
        assert_close(ts_vec3_length(t), 1, 1e-6);
    }
}

static void test_next_float(void **state)
{
    (void)state;
    assert_true(ts_next_float_up(1.0f) > 1.0f);
    assert_true(ts_next_float_down(1.0f) < 1.0f);
    assert_true(ts_next_float_up(0.0f) > 0.0f);
    assert_true(ts_next_float_down(0.0f) < 0.0f);
    assert_true(ts_next_float_up(-0.0f) > 0.0f);
    assert_close(ts_next_float_up(1.0f) - 1.0f, FLT_EPSILON, 0);
}

static void assert_mat_identity(const ts_mat4 *m, double tol)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) assert_close(m->m[i][j], i == j ? 1 : 0, tol);
}

static void test_matrix_inverse(void **state)
{
    (void)state;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 3);
    for (int k = 0; k < 1000; k++) {
        ts_mat4 m;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) m.m[i][j] = 2 * ts_pcg32_double(&rng) - 1;
        ts_mat4 inv;
        assert_true(ts_mat4_invert(&m, &inv));
        ts_mat4 p = ts_mat4_mul(&m, &inv);
        /* Random matrices are usually well conditioned; 1e-9 leaves room for the odd
         * condition number of 1e6 at double precision. */
        assert_mat_identity(&p, 1e-9);
    }
    ts_mat4 singular = ts_mat4_identity(), inv;
    singular.m[2][2] = 0;
    assert_false(ts_mat4_invert(&singular, &inv));
}

static void test_transforms(void **state)
{
    (void)state;
    ts_xform t = ts_xform_translate((ts_dvec3){1, 2, 3});
    ts_dvec3 p = ts_xform_point(&t, (ts_dvec3){1, 1, 1});
    assert_close(p.x, 2, 0), assert_close(p.y, 3, 0), assert_close(p.z, 4, 0);
    ts_dvec3 v = ts_xform_vector(&t, (ts_dvec3){1, 1, 1});
    assert_close(v.x, 1, 0), assert_close(v.y, 1, 0), assert_close(v.z, 1, 0);

    /* Rotation by 90° about z maps x to y. */
    ts_xform r = ts_xform_rotate(90, (ts_dvec3){0, 0, 1});
    ts_dvec3 q = ts_xform_vector(&r, (ts_dvec3){1, 0, 0});
    assert_close(q.x, 0, 1e-15), assert_close(q.y, 1, 1e-15), assert_close(q.z, 0, 1e-15);

    /* compose applies the right operand first; the stored inverse really is the inverse. */
    ts_xform s = ts_xform_scale((ts_dvec3){2, 3, 4});
    ts_xform rs = ts_xform_compose(&r, &s);
    ts_dvec3 a = ts_xform_point(&rs, (ts_dvec3){1, 1, 1});
    assert_close(a.x, -3, 1e-14), assert_close(a.y, 2, 1e-14), assert_close(a.z, 4, 1e-14);
    ts_mat4 id = ts_mat4_mul(&rs.m, &rs.m_inv);
    assert_mat_identity(&id, 1e-14);
    ts_dvec3 back = ts_xform_point_inv(&rs, a);
    assert_close(back.x, 1, 1e-14), assert_close(back.y, 1, 1e-14), assert_close(back.z, 1, 1e-14);

    /* Normals stay perpendicular to transformed tangents under non-uniform scale. */
    ts_dvec3 n = {1, 1, 0}, tangent = {1, -1, 0};
    ts_dvec3 tn = ts_xform_normal(&rs, n), tt = ts_xform_vector(&rs, tangent);
    assert_close(ts_dvec3_dot(tn, tt), 0, 1e-14);

    /* A frame maps z to the normal and is orthonormal. */
    ts_dvec3 nn = ts_dvec3_normalize((ts_dvec3){0.3, -0.5, 0.8});
    ts_xform f = ts_xform_frame((ts_dvec3){5, 6, 7}, nn);
    ts_dvec3 z = ts_xform_vector(&f, (ts_dvec3){0, 0, 1});
    assert_close(z.x, nn.x, 1e-15), assert_close(z.y, nn.y, 1e-15), assert_close(z.z, nn.z, 1e-15);
    ts_mat4 fid = ts_mat4_mul(&f.m, &f.m_inv);
    assert_mat_identity(&fid, 1e-14);
    assert_false(ts_xform_swaps_handedness(&f));
    ts_xform mirror = ts_xform_scale((ts_dvec3){-1, 1, 1});
    assert_true(ts_xform_swaps_handedness(&mirror));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vec3_basics),
        cmocka_unit_test(test_next_float),
        cmocka_unit_test(test_matrix_inverse),
        cmocka_unit_test(test_transforms),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
