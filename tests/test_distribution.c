/* test_distribution.c — piecewise-constant 1D/2D distributions and the alias table
 * (distribution.h). Mostly deterministic: samples are taken on fine u grids, so
 * frequencies are compared with exact cdf widths, and tolerances are float rounding of the
 * tables; the many-lights case is a χ² test of sampler values (its false-failure rate
 * beside it). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>

#include "chi2.h"
#include "core/hash.h"
#include "sampling/distribution.h"
#include "sampling/sampler.h"

static void assert_close(double a, double b, double tol, const char *what)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%s: %.9g != %.9g (tolerance %g)", what, a, b, tol);
}

static void test_1d(void **state)
{
    (void)state;
    ts_arena arena;
    ts_arena_init(&arena, 0);
    ts_error err = {0};
    float f[5] = {1, 0, 3, 0.5f, 0};
    ts_distribution1d d;
    assert_int_equal(ts_distribution1d_init(&d, f, 5, &arena, &err), TS_OK);
    assert_close(d.func_int, 4.5 / 5, 1e-7, "∫f");
    /* pdf = f/∫f; sample ↔ invert; zero pieces never sampled; pdf integrates to 1. */
    double integral = 0;
    for (int i = 0; i < 5; i++) integral += ts_distribution1d_pdf(&d, (i + 0.5f) / 5) / 5;
    assert_close(integral, 1, 1e-6, "∫pdf");
    int count[5] = {0};
    const int n = 100000;
    for (int k = 0; k < n; k++) {
        float u = (k + 0.5f) / n, pdf;
        uint32_t off;
        float x = ts_distribution1d_sample_continuous(&d, u, &pdf, &off);
        assert_true(x >= 0 && x < 1);
        assert_int_equal(off, (uint32_t)(x * 5));
        assert_close(pdf, f[off] / d.func_int, 1e-6, "pdf of the sample");
        assert_close(ts_distribution1d_invert(&d, x), u, 1e-5, "invert");
        float pmf;
        uint32_t i = ts_distribution1d_sample_discrete(&d, u, &pmf, NULL);
        count[i]++;
        assert_close(pmf, f[i] / 4.5, 1e-6, "discrete pmf");
    }
    for (int i = 0; i < 5; i++) assert_close((double)count[i] / n, f[i] / 4.5, 2.0 / n, "discrete frequency");
    /* All zeros: uniform, func_int 0. */
    float z[3] = {0, 0, 0};
    assert_int_equal(ts_distribution1d_init(&d, z, 3, &arena, &err), TS_OK);
    assert_true(d.func_int == 0);
    assert_close(ts_distribution1d_discrete_pmf(&d, 1), 1.0 / 3, 1e-7, "uniform fallback");
    /* Invalid input. */
    float bad[2] = {1, NAN};
    assert_int_equal(ts_distribution1d_init(&d, bad, 2, &arena, &err), TS_ERR_INVALID);
    assert_int_equal(ts_distribution1d_init(&d, f, 0, &arena, &err), TS_ERR_INVALID);
    ts_arena_fini(&arena);
}

static void test_2d(void **state)
{
    (void)state;
    ts_arena arena;
    ts_arena_init(&arena, 0);
    ts_error err = {0};
    float f[4 * 3] = {1, 2, 0, 4, 0, 0, 0, 0, 0.5f, 0.25f, 3, 1};
    ts_distribution2d d;
    assert_int_equal(ts_distribution2d_init(&d, f, 4, 3, &arena, &err), TS_OK);
    double integral = 0;
    for (int v = 0; v < 3; v++)
        for (int u = 0; u < 4; u++) {
            float p = ts_distribution2d_pdf(&d, (ts_vec2){(u + 0.5f) / 4, (v + 0.5f) / 3});
            assert_close(p, f[v * 4 + u] / ts_distribution2d_integral(&d), 1e-5, "2D pdf ∝ f");
            integral += p / 12;
        }
    assert_close(integral, 1, 1e-6, "∫pdf");
    for (int i = 0; i < 200; i++)
        for (int j = 0; j < 200; j++) {
            ts_vec2 u = {(i + 0.5f) / 200, (j + 0.5f) / 200};
            float pdf;
            ts_vec2 x = ts_distribution2d_sample(&d, u, &pdf);
            assert_true(pdf > 0);
            assert_close(pdf, ts_distribution2d_pdf(&d, x), 1e-5 * pdf, "sample pdf = pdf");
            /* The cell form gives the same value and, from the cell's own f, the same
             * density, bit for bit. */
            uint32_t iu, iv;
            ts_vec2 xc = ts_distribution2d_sample_cell(&d, u, &iu, &iv);
            assert_true(xc.x == x.x && xc.y == x.y && iu < 4 && iv < 3);
            assert_true(ts_distribution2d_pdf_cell(&d, iv, f[iv * 4 + iu]) == pdf);
            ts_vec2 back = ts_distribution2d_invert(&d, x);
            assert_close(back.x, u.x, 1e-4, "invert u");
            assert_close(back.y, u.y, 1e-4, "invert v");
        }
    ts_arena_fini(&arena);
}

static void test_alias(void **state)
{
    (void)state;
    ts_arena arena;
    ts_arena_init(&arena, 0);
    ts_error err = {0};
    double w[7] = {1, 0, 1e-6, 100, 3, 0, 7};
    double sum = 1 + 1e-6 + 100 + 3 + 7;
    ts_alias_table t;
    assert_int_equal(ts_alias_table_init(&t, w, 7, &arena, &err), TS_OK);
    double psum = 0;
    for (int i = 0; i < 7; i++) {
        assert_close(ts_alias_table_pmf(&t, (uint32_t)i), w[i] / sum, 1e-7 * w[i] / sum, "exact pmf");
        psum += t.pmf[i];
    }
    assert_close(psum, 1, 1e-6, "Σ pmf");
    /* A grid over u: u.x at 512 points per bin of the table (exactly 1/512 of the bin each),
     * u.y, the coin, at 2048 points: each bin's share is resolved to 1/2048 of 1/7, and an
     * outcome gathers at most 7 such shares. */
    int count[7] = {0};
    const int nx = 7 * 512, ny = 2048;
    for (int a = 0; a < nx; a++)
        for (int b = 0; b < ny; b++) {
            float pmf;
            uint32_t i = ts_alias_table_sample(&t, (ts_vec2){(a + 0.5f) / nx, (b + 0.5f) / ny}, &pmf);
            assert_true(pmf == t.pmf[i]);
            count[i]++;
        }
    const double n = (double)nx * ny;
    for (int i = 0; i < 7; i++) assert_close(count[i] / n, w[i] / sum, 1.0 / ny + 1e-6, "frequency");
    assert_int_equal(count[1], 0);
    assert_int_equal(count[5], 0);
    double neg[2] = {1, -1};
    assert_int_equal(ts_alias_table_init(&t, neg, 2, &arena, &err), TS_ERR_INVALID);
    ts_arena_fini(&arena);
}

/* Light selection with many lights: 10^6 weights spread log-uniformly over
 * three decades (powers 1 to 1000), sampled N = 2^24 times with the values the renderer
 * feeds the table — one 2-D dimension of the independent sampler per draw, multiples of
 * 2^-24 — and the counts compared with the returned pmfs by Pearson's χ² over bins of
 * lights (consecutive lights pooled until a bin expects ≥ 10 draws: ~870,000 bins). The
 * counts are multinomial, so with the χ² approximation (≥ 10 per bin) the test fails
 * correct code with probability 1e-3 (its significance) for a random seed. Taking the
 * coin as frac(u·n) of the bin's own value (the defect this guards against) puts
 * χ² − dof at ~150 standard deviations: 18% of the lights are then never chosen and
 * others are chosen up to 8.6× their pmf. */
/* The guide table (distribution.h) must give the piece a search of the whole cdf gives:
 * the largest i < n with cdf[i] ≤ u. Checked against a linear scan on distributions with
 * runs of zero pieces, a single spike and all zeros, at every cdf value, the floats next
 * to it on both sides, and a grid of 2^16 values: deterministic, no tolerance. */
static uint32_t piece_by_scan(const ts_distribution1d *d, float u)
{
    uint32_t i = 0;
    while (i + 1 < d->n && d->cdf[i + 1] <= u) i++;
    return i;
}

static void check_pieces(const ts_distribution1d *d, float u, uint32_t *checked)
{
    if (!(u >= 0.0f && u < 1.0f)) return;
    uint32_t off;
    float pdf;
    ts_distribution1d_sample_continuous(d, u, &pdf, &off);
    uint32_t want = piece_by_scan(d, u);
    if (off != want) fail_msg("n = %u, u = %a: piece %u, the whole cdf says %u", d->n, (double)u, off, want);
    if (d->func_int > 0 && !(d->func[off] > 0)) fail_msg("n = %u, u = %a: zero piece %u sampled", d->n, (double)u, off);
    uint32_t i = ts_distribution1d_sample_discrete(d, u, NULL, NULL);
    if (i != want) fail_msg("n = %u, u = %a: discrete piece %u, the whole cdf says %u", d->n, (double)u, i, want);
    (*checked)++;
}

static void test_guide_table(void **state)
{
    (void)state;
    static const uint32_t sizes[] = {1, 2, 3, 4, 5, 7, 8, 9, 13, 100, 1000, 4097};
    uint32_t checked = 0;
    for (size_t s = 0; s < sizeof sizes / sizeof *sizes; s++)
        for (int kind = 0; kind < 3; kind++) {
            uint32_t n = sizes[s];
            float *f = malloc(n * sizeof *f);
            assert_non_null(f);
            for (uint32_t i = 0; i < n; i++) {
                uint32_t h = ts_hash4(n, (uint32_t)kind, i, 7);
                /* kind 0: uneven values (exponents over 2^±12), a third zero, in runs;
                 * kind 1: one spike among tiny values; kind 2: all zero. */
                if (kind == 0) f[i] = (h % 3 == 0 || (i / 5) % 4 == 1) ? 0.0f : ldexpf(1.0f + (h >> 8) * 0x1p-24f, (int)(h % 25) - 12);
                else if (kind == 1) f[i] = i == n / 3 ? 1e6f : (h & 1 ? 1e-6f : 0.0f);
                else f[i] = 0;
            }
            ts_arena arena;
            ts_arena_init(&arena, 0);
            ts_error err = {0};
            ts_distribution1d d;
            assert_int_equal(ts_distribution1d_init(&d, f, n, &arena, &err), TS_OK);
            for (uint32_t i = 0; i <= n; i++) {
                check_pieces(&d, d.cdf[i], &checked);
                check_pieces(&d, nextafterf(d.cdf[i], 0.0f), &checked);
                check_pieces(&d, nextafterf(d.cdf[i], 1.0f), &checked);
            }
            for (uint32_t k = 0; k < (1u << 16); k++) check_pieces(&d, (float)k * 0x1p-16f, &checked);
            check_pieces(&d, TS_ONE_MINUS_EPSILON, &checked);
            ts_arena_fini(&arena);
            free(f);
        }
    assert_true(checked > 36 * 65536);
}

static void test_alias_many_lights(void **state)
{
    (void)state;
    enum { N_LIGHTS = 1000000 };
    const uint32_t n_draws = 1u << 24;
    ts_arena arena;
    ts_arena_init(&arena, 0);
    ts_error err = {0};
    double *w = malloc(N_LIGHTS * sizeof *w);
    uint32_t *count = calloc(N_LIGHTS, sizeof *count);
    assert_non_null(w);
    assert_non_null(count);
    for (uint32_t i = 0; i < N_LIGHTS; i++) w[i] = exp(log(1000.0) * (ts_hash_u32(i * 2654435761u + 7) * 0x1p-32));
    ts_alias_table t;
    assert_int_equal(ts_alias_table_init(&t, w, N_LIGHTS, &arena, &err), TS_OK);
    ts_sampler sampler = {TS_SAMPLER_INDEPENDENT, 17};
    for (uint32_t k = 0; k < n_draws; k++) {
        float pmf;
        uint32_t i = ts_alias_table_sample(&t, ts_sampler_value_2d(&sampler, 3, 5, k, 2), &pmf);
        assert_true(i < N_LIGHTS);
        count[i]++;
    }
    double psum = 0;
    for (uint32_t i = 0; i < N_LIGHTS; i++) psum += t.pmf[i];
    double chi2 = 0, e = 0, o = 0, worst = 0, never_expected = 0;
    int bins = 0;
    uint32_t never = 0;
    for (uint32_t i = 0; i < N_LIGHTS; i++) {
        double ei = n_draws * (t.pmf[i] / psum);
        e += ei;
        o += count[i];
        never_expected += exp(-ei);
        if (count[i] == 0) never++;
        if (e >= 10 || i + 1 == N_LIGHTS) {
            chi2 += (o - e) * (o - e) / e;
            worst = fmax(worst, fabs(o - e) / sqrt(e));
            bins++;
            e = o = 0;
        }
    }
    int dof = bins - 1;
    double p = ts_chi2_upper_tail(chi2, dof), z = (chi2 - dof) / sqrt(2.0 * dof);
    print_message("10^6 lights, 2^24 draws: χ² %.0f over %d dof (%+.2f σ), p = %.3f; largest bin deviation %.2f σ; "
                  "%u lights never drawn (%.0f expected)\n",
                  chi2, dof, z, p, worst, never, never_expected);
    assert_true(p >= 1e-3);
    free(count);
    free(w);
    ts_arena_fini(&arena);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_1d),
        cmocka_unit_test(test_2d),
        cmocka_unit_test(test_guide_table),
        cmocka_unit_test(test_alias),
        cmocka_unit_test(test_alias_many_lights),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
