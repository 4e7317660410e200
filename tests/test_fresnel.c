/* test_fresnel.c — dielectric and conductor Fresnel reflectance. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "materials/fresnel.h"

static void assert_close(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%.9g != %.9g (tolerance %g)", a, b, tol);
}

static void test_dielectric(void **state)
{
    (void)state;
    /* ((1 − 1.5) / (1 + 1.5))² = 0.04 exactly; float arithmetic: a few ulps. */
    assert_close(ts_fresnel_dielectric(1, 1, 1.5f), 0.04, 1e-6);
    assert_close(ts_fresnel_dielectric(-1, 1, 1.5f), 0.04, 1e-6); /* from inside, same at normal incidence */
    for (float c = -1; c <= 1; c += 0.01f) assert_close(ts_fresnel_dielectric(c, 1, 1), 0, 0);
    /* Total internal reflection from inside glass beyond the critical angle asin(1/1.5). */
    float crit = asinf(1 / 1.5f);
    assert_close(ts_fresnel_dielectric(-cosf(crit + 0.01f), 1, 1.5f), 1, 0);
    assert_close(ts_fresnel_dielectric(-cosf(1.2f), 1, 1.5f), 1, 0);
    assert_true(ts_fresnel_dielectric(-cosf(crit - 0.01f), 1, 1.5f) < 1);
    /* Grazing incidence from outside reflects everything; monotone in between. */
    assert_close(ts_fresnel_dielectric(0, 1, 1.5f), 1, 1e-6);
    float prev = 0;
    for (float c = 1; c >= 0; c -= 0.01f) {
        float f = ts_fresnel_dielectric(c, 1, 1.5f);
        assert_true(f >= prev - 1e-6f && f >= 0 && f <= 1);
        prev = f;
    }
    /* Reciprocity of the interface: F(θi) from outside = F(θt) from inside (Stokes).
     * Float: cosθt is recomputed from a rounded sine, and dF/dcos reaches ~10 near
     * grazing, so 2e-5. */
    for (float c = 0.05f; c <= 1; c += 0.05f) {
        float s = sqrtf(1 - c * c) / 1.5f, ct = sqrtf(1 - s * s);
        assert_close(ts_fresnel_dielectric(c, 1, 1.5f), ts_fresnel_dielectric(-ct, 1, 1.5f), 2e-5);
    }
}

static void test_conductor(void **state)
{
    (void)state;
    /* With k = 0 the conductor formula is the dielectric one (float, 1e-5). */
    for (float c = 0.0f; c <= 1; c += 0.02f)
        assert_close(ts_fresnel_conductor(c, 1, ts_rgb_gray(1.5f), ts_rgb_gray(0)).r,
                     ts_fresnel_dielectric(c, 1, 1.5f), 1e-5);
    /* Normal incidence: ((η−1)² + k²) / ((η+1)² + k²); gold-like (0.2, 3.5): 0.9286. */
    double eta = 0.2, k = 3.5, want = ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
    assert_close(ts_fresnel_conductor(1, 1, ts_rgb_gray(0.2f), ts_rgb_gray(3.5f)).g, want, 1e-5);
    /* Degenerate inputs stay in [0, 1]. */
    float vals[] = {0, 1e-6f, 1, 3, 1e6f};
    for (int a = 0; a < 5; a++)
        for (int b = 0; b < 5; b++)
            for (float c = -1; c <= 1; c += 0.25f) {
                float f = ts_fresnel_conductor(c, 1, ts_rgb_gray(vals[a]), ts_rgb_gray(vals[b])).r;
                assert_true(f >= 0 && f <= 1);
                float d = ts_fresnel_dielectric(c, vals[a] > 0 ? vals[a] : 1, vals[b]);
                assert_true(d >= 0 && d <= 1);
            }
    ts_fresnel s = ts_fresnel_make_schlick(ts_rgb_gray(0.04f));
    assert_close(ts_fresnel_eval(&s, 1).r, 0.04, 1e-7);
    assert_close(ts_fresnel_eval(&s, 0).r, 1, 1e-7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_dielectric), cmocka_unit_test(test_conductor)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
