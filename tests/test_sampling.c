/* test_sampling.c — the warps of sampling.h against their densities (χ²), the MIS
 * weights' guards, and the χ² machinery of chi2.h testing itself. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "chi2.h"
#include "core/hash.h"
#include "sampling/sampling.h"

static void assert_close(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%.17g != %.17g (tolerance %g)", a, b, tol);
}

static void run_chi2(const char *name, ts_chi2_sample_fn s, ts_chi2_pdf_fn pdf, void *ctx, bool expect_pass)
{
    ts_chi2_params p;
    ts_chi2_params_default(&p);
    ts_chi2_result r;
    bool ok = ts_chi2_test(&p, s, pdf, ctx, &r);
    print_message("chi2 %-28s %s (p=%.4f, ∫pdf=%.7f ± %.1e, %llu pdf calls, %d unconverged)\n", name, r.message,
                  r.p_value, r.pdf_integral, r.quadrature_error, (unsigned long long)r.pdf_evals, r.unconverged);
    if (ok != expect_pass) fail_msg("%s: expected %s, got: %s", name, expect_pass ? "pass" : "failure", r.message);
    if (expect_pass) assert_int_equal(r.unconverged, 0);
}

static ts_vec2 u2(ts_pcg32 *rng)
{
    float a = ts_pcg32_float(rng);
    return (ts_vec2){a, ts_pcg32_float(rng)};
}

/* ---- warps ---- */
static ts_chi2_outcome s_cos(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    (void)ctx;
    *w = ts_sample_cosine_hemisphere(u2(rng));
    return TS_CHI2_DIRECTION;
}
static double p_cos(void *ctx, ts_vec3 w)
{
    (void)ctx;
    return ts_cosine_hemisphere_pdf(w.z);
}
static ts_chi2_outcome s_uhemi(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    (void)ctx;
    *w = ts_sample_uniform_hemisphere(u2(rng));
    return TS_CHI2_DIRECTION;
}
static double p_uhemi(void *ctx, ts_vec3 w)
{
    (void)ctx;
    return w.z >= 0 ? ts_uniform_hemisphere_pdf() : 0;
}
static ts_chi2_outcome s_sphere(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    (void)ctx;
    *w = ts_sample_uniform_sphere(u2(rng));
    return TS_CHI2_DIRECTION;
}
static double p_sphere(void *ctx, ts_vec3 w)
{
    (void)ctx;
    (void)w;
    return ts_uniform_sphere_pdf();
}
static ts_chi2_outcome s_cone(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    *w = ts_sample_uniform_cone(u2(rng), *(float *)ctx);
    return TS_CHI2_DIRECTION;
}
static double p_cone(void *ctx, ts_vec3 w)
{
    float c = *(float *)ctx;
    return w.z >= c ? ts_uniform_cone_pdf(c) : 0;
}

static void test_warps_chi2(void **state)
{
    (void)state;
    run_chi2("cosine hemisphere", s_cos, p_cos, NULL, true);
    run_chi2("uniform hemisphere", s_uhemi, p_uhemi, NULL, true);
    run_chi2("uniform sphere", s_sphere, p_sphere, NULL, true);
    float c = 0.3f; /* a cone edge inside a row: exercises refinement at a discontinuity */
    run_chi2("uniform cone cos=0.3", s_cone, p_cone, &c, true);
    c = 0.999f; /* narrow cone, about 2.6° */
    run_chi2("uniform cone cos=0.999", s_cone, p_cone, &c, true);
}

/* Uniform triangle barycentrics: histogram over an n×n grid of the (b0, b1) square,
 * cells clipped to the triangle (diagonal cells are exact half squares). */
static void test_triangle_uniform(void **state)
{
    (void)state;
    enum { n = 20, samples = 1000000 };
    static double count[n][n];
    memset(count, 0, sizeof count);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 1);
    for (int i = 0; i < samples; i++) {
        ts_vec2 b = ts_sample_uniform_triangle(u2(&rng));
        assert_true(b.x >= 0 && b.y >= 0 && b.x + b.y <= 1 + 1e-6f);
        int x = (int)(b.x * n), y = (int)(b.y * n);
        x = x >= n ? n - 1 : x;
        y = y >= n ? n - 1 : y;
        if (x + y >= n) { /* float rounding on the diagonal: put it in the diagonal cell */
            if (x > y) x = n - 1 - y;
            else y = n - 1 - x;
        }
        count[x][y] += 1;
    }
    double chi2 = 0;
    int bins = 0;
    for (int x = 0; x < n; x++)
        for (int y = 0; x + y < n; y++) {
            double area = (x + y == n - 1) ? 0.5 : 1.0; /* in units of one square */
            double e = samples * area / (0.5 * n * n);
            chi2 += (count[x][y] - e) * (count[x][y] - e) / e;
            bins++;
        }
    double pv = ts_chi2_upper_tail(chi2, bins - 1);
    print_message("triangle: χ²=%.1f dof=%d p=%.4f\n", chi2, bins - 1, pv);
    assert_true(pv >= ts_chi2_sidak(0.01, TS_CHI2_FAMILY_SIZE));
}

static void test_concentric_disk(void **state)
{
    (void)state;
    /* Corners and centre map inside the closed unit disk; the map is area preserving, so
     * the fraction of 10^6 points within radius 0.5 is 1/4 (binomial σ = 4.3e-4; 5σ). */
    ts_vec2 corners[] = {{0, 0}, {1, 1}, {0.5f, 0.5f}, {TS_ONE_MINUS_EPSILON, 0}, {0, TS_ONE_MINUS_EPSILON}};
    for (size_t i = 0; i < sizeof corners / sizeof corners[0]; i++) {
        ts_vec2 d = ts_sample_concentric_disk(corners[i]);
        assert_true(d.x * d.x + d.y * d.y <= 1 + 1e-6f);
    }
    ts_vec2 c = ts_sample_concentric_disk((ts_vec2){0.5f, 0.5f});
    assert_close(c.x, 0, 0);
    assert_close(c.y, 0, 0);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 3);
    int inside = 0, total = 1000000;
    for (int i = 0; i < total; i++) {
        ts_vec2 d = ts_sample_concentric_disk(u2(&rng));
        if (d.x * d.x + d.y * d.y < 0.25f) inside++;
    }
    assert_close((double)inside / total, 0.25, 5 * 4.33e-4);
}

static void test_pdfs_and_edges(void **state)
{
    (void)state;
    assert_close(ts_cosine_hemisphere_pdf(1), 1 / TS_PI_D, 1e-7);
    assert_close(ts_cosine_hemisphere_pdf(-0.5f), 0, 0);
    assert_close(ts_uniform_cone_pdf(0), 1 / (2 * TS_PI_D), 1e-7);
    assert_true(isinf(ts_uniform_cone_pdf(1)));
    ts_vec3 w = ts_sample_uniform_cone((ts_vec2){0.7f, 0.2f}, 1.0f);
    assert_close(w.z, 1, 0);
    /* Extreme u give finite, unit directions. */
    float us[] = {0, 0.5f, TS_ONE_MINUS_EPSILON, 1};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            ts_vec2 u = {us[i], us[j]};
            ts_vec3 ws[4] = {ts_sample_cosine_hemisphere(u), ts_sample_uniform_hemisphere(u),
                             ts_sample_uniform_sphere(u), ts_sample_uniform_cone(u, 0.5f)};
            for (int k = 0; k < 4; k++) {
                assert_true(ts_vec3_is_finite(ws[k]));
                assert_close(ts_vec3_length(ws[k]), 1, 1e-6);
            }
            ts_vec2 b = ts_sample_uniform_triangle(u);
            assert_true(b.x >= 0 && b.y >= 0 && b.x + b.y <= 1 + 1e-6f);
        }
}

static void test_power_heuristic(void **state)
{
    (void)state;
    assert_close(ts_power_heuristic(1, 1, 1, 1), 0.5, 1e-7);
    assert_close(ts_power_heuristic(1, 3, 1, 1), 0.9, 1e-6);
    assert_close(ts_balance_heuristic(1, 3, 1, 1), 0.75, 1e-6);
    float v[] = {0, 1e-38f, 1e-30f, 0.5f, 1, 1e30f, FLT_MAX, INFINITY, NAN, -1};
    int nv = (int)(sizeof v / sizeof v[0]);
    for (int i = 0; i < nv; i++)
        for (int j = 0; j < nv; j++) {
            float w = ts_power_heuristic(1, v[i], 1, v[j]);
            float wb = ts_balance_heuristic(1, v[i], 1, v[j]);
            if (!(w >= 0 && w <= 1) || !(wb >= 0 && wb <= 1))
                fail_msg("heuristic(%g, %g) = %g / %g", v[i], v[j], w, wb);
        }
    assert_close(ts_power_heuristic(1, INFINITY, 1, 5), 1, 0);
    assert_close(ts_power_heuristic(1, 5, 1, INFINITY), 0, 0);
    assert_close(ts_power_heuristic(1, 0, 1, 0), 0, 0);
    assert_close(ts_power_heuristic(1, 5, 1, 0), 1, 0);
    assert_close(ts_power_heuristic(1, FLT_MAX, 1, FLT_MAX), 0.5, 1e-7);
    /* Weights of the two strategies sum to 1 wherever one can produce the sample. */
    assert_close(ts_power_heuristic(1, 1e30f, 4, 3e29f) + ts_power_heuristic(4, 3e29f, 1, 1e30f), 1, 1e-6);
}

/* ---- the χ² machinery tests itself ---- */
static void test_chi2_tail(void **state)
{
    (void)state;
    /* dof 2: P(X ≥ x) = exp(−x/2) exactly; dof 1 at x = 3.841459 is 0.05; dof 100 at
     * 135.807 is 0.01 (tabulated values, 6 digits). */
    for (double x = 0.1; x < 60; x *= 1.7) assert_close(ts_chi2_upper_tail(x, 2), exp(-x / 2), 1e-12);
    assert_close(ts_chi2_upper_tail(3.841459, 1), 0.05, 1e-6);
    assert_close(ts_chi2_upper_tail(135.807, 100), 0.01, 1e-5);
    assert_close(ts_chi2_upper_tail(0, 5), 1, 0);
    assert_close(ts_chi2_sidak(0.01, 1), 0.01, 0);
    assert_close(ts_chi2_sidak(0.01, 10), 1 - pow(0.99, 0.1), 1e-15);
}

static ts_chi2_outcome s_half_cos(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    (void)ctx;
    if (ts_pcg32_float(rng) < 0.5f) return TS_CHI2_DISCRETE;
    *w = ts_sample_cosine_hemisphere(u2(rng));
    return TS_CHI2_DIRECTION;
}
static double p_half_cos(void *ctx, ts_vec3 w)
{
    (void)ctx;
    return 0.5 * ts_cosine_hemisphere_pdf(w.z);
}
static double p_bad_lobe(void *ctx, ts_vec3 w)
{
    /* The cosine pdf with a narrow bump (0.5% of the mass moved into a 1° cap around a
     * tilted axis): a sampler ignoring the bump must fail. */
    (void)ctx;
    ts_vec3 axis = {0.6f, 0, 0.8f};
    double c = ts_vec3_dot(w, axis), cmax = cos(1.0 * TS_PI_D / 180);
    double bump = c >= cmax ? 0.005 / (2 * TS_PI_D * (1 - cmax)) : 0;
    return 0.995 * ts_cosine_hemisphere_pdf(w.z) + bump;
}

static void test_chi2_self(void **state)
{
    (void)state;
    /* A correct pair passes; uniform sampling against the cosine pdf fails (same support,
     * wrong shape), as do the wrong mass of a partly discrete sampler, a sampler covering
     * a zero-pdf region, and a pdf with a narrow extra lobe the sampler never produces. */
    run_chi2("self: cosine/cosine", s_cos, p_cos, NULL, true);
    run_chi2("self: uniform/cosine", s_uhemi, p_cos, NULL, false);
    run_chi2("self: half discrete", s_half_cos, p_half_cos, NULL, true);
    run_chi2("self: half discrete/full pdf", s_half_cos, p_cos, NULL, false);
    run_chi2("self: sphere/hemisphere pdf", s_sphere, p_uhemi, NULL, false);
    run_chi2("self: missing narrow lobe", s_cos, p_bad_lobe, NULL, false);
    /* Even rows are refused. */
    ts_chi2_params p;
    ts_chi2_params_default(&p);
    p.cos_theta_res = 20;
    ts_chi2_result r;
    assert_false(ts_chi2_test(&p, s_cos, p_cos, NULL, &r));
    /* The quadrature integrates a normalised pdf to 1 (relative 1e-6). */
    assert_close(ts_chi2_integrate(p_cos, NULL, 21, 42, 1e-8), 1, 1e-6);
    float cone = 0.95f;
    assert_close(ts_chi2_integrate(p_cone, &cone, 21, 42, 1e-8), 1, 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_tail),      cmocka_unit_test(test_chi2_self),
        cmocka_unit_test(test_warps_chi2),     cmocka_unit_test(test_triangle_uniform),
        cmocka_unit_test(test_concentric_disk), cmocka_unit_test(test_pdfs_and_edges),
        cmocka_unit_test(test_power_heuristic),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
