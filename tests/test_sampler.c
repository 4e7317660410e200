/* test_sampler.c — Owen-scrambled Sobol and independent samplers: net property of every
 * power-of-two prefix and aligned block, determinism, decorrelation, range, uniformity. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
/* cmocka.h needs the three headers above first. */
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "core/hash.h"
#include "sampling/sampler.h"

#define MAX_M 12

static const uint32_t k_seeds[] = {0u, 1u, 0xdeadbeefu};
static const uint32_t k_pixels[][2] = {{0, 0}, {1, 0}, {37, 511}, {4095, 3000}};
static const uint32_t k_dims[] = {0u, 1u, 2u, 7u};

/* Upper χ² quantile with tail probability p via Wilson–Hilferty (z = the normal quantile
 * of p); accurate to well under 1% for hundreds of degrees of freedom. */
static double chi2_upper(double dof, double z)
{
    double h = 2.0 / (9.0 * dof), t = 1 - h + z * sqrt(h);
    return dof * t * t * t;
}
#define Z_1E6 4.753 /* upper normal quantile for p = 1e-6 */

/* True when the n = 2^m points put exactly one point in every elementary interval
 * [i/2^a, (i+1)/2^a) × [j/2^b, (j+1)/2^b) with a + b = m: a (0,m,2)-net. */
static int is_net(const ts_vec2 *pts, int m)
{
    static unsigned char hits[1 << MAX_M];
    uint32_t n = 1u << m;
    for (int a = 0; a <= m; a++) {
        int b = m - a;
        memset(hits, 0, n);
        for (uint32_t i = 0; i < n; i++) {
            /* Values are multiples of 2^-24, so scaling by 2^a and truncating is exact. */
            uint32_t cx = (uint32_t)(pts[i].x * (float)(1u << a)),
                     cy = (uint32_t)(pts[i].y * (float)(1u << b));
            if (cx >= (1u << a) || cy >= (1u << b)) return 0;
            if (hits[cx + (cy << a)]++) return 0;
        }
    }
    return 1;
}

static void test_sobol_nets(void **state)
{
    (void)state;
    static ts_vec2 pts[1 << MAX_M];
    /* What holds: for every m, every aligned block of 2^m sample indices [k·2^m, (k+1)·2^m)
     * — the first 2^m samples being k = 0 — is a (0,m,2)-net in every dimension. Checked
     * for blocks k = 0, 1, 3, 1000; unaligned windows are not nets in general. */
    static const uint32_t blocks[] = {0, 1, 3, 1000};
    int checked = 0;
    for (size_t si = 0; si < sizeof k_seeds / sizeof *k_seeds; si++)
        for (size_t pi = 0; pi < sizeof k_pixels / sizeof *k_pixels; pi++)
            for (size_t di = 0; di < sizeof k_dims / sizeof *k_dims; di++) {
                ts_sampler s = {TS_SAMPLER_SOBOL, k_seeds[si]};
                for (int m = 0; m <= MAX_M; m++)
                    for (size_t bi = 0; bi < sizeof blocks / sizeof *blocks; bi++) {
                        uint32_t n = 1u << m, base = blocks[bi] << m;
                        for (uint32_t i = 0; i < n; i++)
                            pts[i] = ts_sampler_value_2d(&s, k_pixels[pi][0], k_pixels[pi][1], base + i,
                                                         k_dims[di]);
                        if (!is_net(pts, m))
                            fail_msg("not a (0,%d,2)-net: seed %u pixel (%u,%u) dim %u block %u", m,
                                     k_seeds[si], k_pixels[pi][0], k_pixels[pi][1], k_dims[di], blocks[bi]);
                        checked++;
                    }
            }
    assert_int_equal(checked, 3 * 4 * 4 * 13 * 4);
}

/* A window that is not aligned is generally not a net: a sanity check that is_net can fail
 * (so the test above is not vacuous). Samples 5..20 (16 samples straddling two aligned
 * blocks) fail to be a (0,4,2)-net for at least one of 16 seeds. */
static void test_sobol_unaligned_not_net(void **state)
{
    (void)state;
    ts_vec2 pts[16];
    int failures = 0;
    for (uint32_t seed = 0; seed < 16; seed++) {
        ts_sampler s = {TS_SAMPLER_SOBOL, seed};
        for (uint32_t i = 0; i < 16; i++)
            pts[i] = ts_sampler_value_2d(&s, 3, 4, 5 + i, 0);
        failures += !is_net(pts, 4);
    }
    assert_true(failures > 0);
}

static void check_order_independent(ts_sampler_type type)
{
    enum { DIMS = 24 };
    ts_sampler s = {type, 12345u};
    ts_vec2 forward[DIMS];
    float forward_1d[DIMS];
    /* Draw in increasing dimension order, alternating 1-D and 2-D draws. */
    for (uint32_t index = 0; index < 64; index++) {
        ts_sample_stream st;
        ts_sampler_begin(&s, 17, 29, index, &st);
        assert_int_equal(st.dim, 0);
        for (int d = 0; d < DIMS; d++) {
            if (d % 3 == 1)
                forward_1d[d] = ts_sample_1d(&st);
            else
                forward[d] = ts_sample_2d(&st);
        }
        assert_int_equal(st.dim, DIMS);
        /* Other pixels' and indices' streams in between change nothing. */
        ts_sample_stream other;
        ts_sampler_begin(&s, 18, 29, index + 1, &other);
        for (int d = 0; d < 5; d++)
            (void)ts_sample_2d(&other);
        /* Now the pure function, dimensions in reverse order: bit-identical. */
        for (int d = DIMS - 1; d >= 0; d--) {
            ts_vec2 v = ts_sampler_value_2d(&s, 17, 29, index, (uint32_t)d);
            if (d % 3 == 1) {
                assert_true(v.x == forward_1d[d]);
                assert_true(ts_sampler_value_1d(&s, 17, 29, index, (uint32_t)d) == forward_1d[d]);
            } else {
                assert_true(v.x == forward[d].x && v.y == forward[d].y);
            }
        }
    }
}

/* Streams begun in a pixel's seed cache draw exactly what ts_sampler_begin's draw, whatever
 * dimensions earlier samples reached or skipped, past the cache's end too, in any index
 * order; the independent sampler (which shares nothing) the same. */
static void check_pixel_cache(ts_sampler_type type)
{
    enum { DIMS = TS_SAMPLER_PIXEL_DIMS + 9 };
    ts_sampler s = {type, 777u};
    ts_sampler_pixel pixel;
    ts_sampler_pixel_init(&s, 40, 3, &pixel);
    const uint32_t indices[] = {5, 0, 1, 63, 2, 2, 1000000u, 7};
    for (size_t k = 0; k < sizeof indices / sizeof indices[0]; k++) {
        uint32_t index = indices[k];
        ts_sample_stream a, b;
        ts_sampler_begin(&s, 40, 3, index, &a);
        ts_sampler_begin_in_pixel(&pixel, index, &b);
        /* A pattern that differs per sample: how far it goes, what it skips, 1-D or 2-D. */
        uint32_t n = (uint32_t)(3 + (k * 11) % DIMS);
        for (uint32_t d = 0; d < n; d++) {
            uint32_t kind = (uint32_t)(d + k) % 4;
            if (kind == 0) {
                a.dim++, b.dim++; /* a dimension not drawn */
            } else if (kind == 1) {
                assert_true(ts_sample_1d(&a) == ts_sample_1d(&b));
            } else {
                ts_vec2 va = ts_sample_2d(&a), vb = ts_sample_2d(&b);
                assert_true(va.x == vb.x && va.y == vb.y);
            }
        }
        assert_int_equal(a.dim, b.dim);
    }
    if (type == TS_SAMPLER_SOBOL) assert_true(pixel.filled != 0);
}

static void test_pixel_cache_sobol(void **state)
{
    (void)state;
    check_pixel_cache(TS_SAMPLER_SOBOL);
}

static void test_pixel_cache_independent(void **state)
{
    (void)state;
    check_pixel_cache(TS_SAMPLER_INDEPENDENT);
}

/* A dimension's seeds taken once (ts_sampler_dim) give the pure values bit for bit: both
 * samplers, pixels, dimensions in and past the pixel cache's range, indices up to 2^32−1
 * (the arrays' index st·n + j). Deterministic, exact. */
static void test_dim_arrays(void **state)
{
    (void)state;
    for (int type = 0; type < 2; type++) {
        ts_sampler s = {type ? TS_SAMPLER_INDEPENDENT : TS_SAMPLER_SOBOL, 0x9e3779b9u * (uint32_t)(type + 1)};
        for (uint32_t p = 0; p < 12; p++)
            for (uint32_t dim = 0; dim < 70; dim += 3) {
                uint32_t px = ts_hash_u32(p) % 4096, py = ts_hash_u32(p + 77) % 4096;
                ts_sampler_dim d;
                ts_sampler_dim_init(&s, px, py, dim, &d);
                for (uint32_t k = 0; k < 600; k++) {
                    uint32_t index = k < 512 ? k : ts_hash_u32(k * 31 + dim);
                    if (k == 599) index = UINT32_MAX;
                    ts_vec2 a = ts_sampler_dim_value_2d(&d, index), b = ts_sampler_value_2d(&s, px, py, index, dim);
                    float x = ts_sampler_dim_value_1d(&d, index);
                    if (memcmp(&a, &b, sizeof a) != 0 || memcmp(&x, &b.x, sizeof x) != 0)
                        fail_msg("%s (%u, %u) dim %u index %u: (%a, %a) != (%a, %a)", ts_sampler_type_name(s.type), px,
                                 py, dim, index, (double)a.x, (double)a.y, (double)b.x, (double)b.y);
                }
            }
    }
}

static void test_sobol_order_independent(void **state)
{
    (void)state;
    check_order_independent(TS_SAMPLER_SOBOL);
}

static void test_independent_deterministic(void **state)
{
    (void)state;
    check_order_independent(TS_SAMPLER_INDEPENDENT);
    /* And a fixed value, so a change of the hash (which would change every image) is seen. */
    ts_sampler s = {TS_SAMPLER_INDEPENDENT, 0};
    ts_vec2 a = ts_sampler_value_2d(&s, 1, 2, 3, 4), b = ts_sampler_value_2d(&s, 1, 2, 3, 4);
    assert_true(a.x == b.x && a.y == b.y);
    ts_vec2 c = ts_sampler_value_2d(&s, 1, 2, 4, 4);
    assert_false(a.x == c.x && a.y == c.y);
}

/* Pearson correlation of two sequences. */
static double correlation(const double *a, const double *b, int n)
{
    double ma = 0, mb = 0;
    for (int i = 0; i < n; i++)
        ma += a[i], mb += b[i];
    ma /= n;
    mb /= n;
    double sab = 0, saa = 0, sbb = 0;
    for (int i = 0; i < n; i++) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / sqrt(saa * sbb);
}

/* Points of two pixels (or two dimensions) at the same sample index must be unrelated. */
static void test_sobol_decorrelated(void **state)
{
    (void)state;
    enum { N = 4096 };
    /* (px, py, dim) pairs compared index by index: neighbouring pixels, distant pixels,
     * neighbouring dimensions of one pixel, and one pixel under two seeds. */
    static const struct {
        uint32_t seed_a, pxa, pya, da, seed_b, pxb, pyb, db;
    } pairs[] = {
        {0, 0, 0, 0, 0, 1, 0, 0},         {0, 0, 0, 0, 0, 0, 1, 0}, {0, 5, 7, 0, 0, 6, 7, 0},
        {0, 100, 200, 2, 0, 300, 400, 2}, {0, 5, 7, 0, 0, 5, 7, 1}, {0, 5, 7, 2, 0, 5, 7, 3},
        {0, 5, 7, 0, 1, 5, 7, 0},
    };
    static double xa[N], ya[N], xb[N], yb[N];
    /* Under independence the correlation of N pairs has standard deviation ≈ 1/√N = 1/64;
     * stratified marginals only shrink it. 5σ two-sided: false failure < 6e-7 per pair. */
    const double bound = 5.0 / sqrt((double)N);
    double worst = 0;
    for (size_t k = 0; k < sizeof pairs / sizeof *pairs; k++) {
        ts_sampler sa = {TS_SAMPLER_SOBOL, pairs[k].seed_a}, sb = {TS_SAMPLER_SOBOL, pairs[k].seed_b};
        int equal = 0;
        for (int i = 0; i < N; i++) {
            ts_vec2 a = ts_sampler_value_2d(&sa, pairs[k].pxa, pairs[k].pya, (uint32_t)i, pairs[k].da);
            ts_vec2 b = ts_sampler_value_2d(&sb, pairs[k].pxb, pairs[k].pyb, (uint32_t)i, pairs[k].db);
            xa[i] = a.x, ya[i] = a.y, xb[i] = b.x, yb[i] = b.y;
            equal += a.x == b.x && a.y == b.y;
        }
        /* Equal points at the same index: chance 2^-48 each if unrelated. */
        assert_int_equal(equal, 0);
        double r[4] = {correlation(xa, xb, N), correlation(ya, yb, N), correlation(xa, yb, N),
                       correlation(ya, xb, N)};
        for (int j = 0; j < 4; j++) {
            if (fabs(r[j]) > bound) fail_msg("pair %zu: correlation %g exceeds %g", k, r[j], bound);
            if (fabs(r[j]) > worst) worst = fabs(r[j]);
        }
    }
    printf("    sobol decorrelation: max |rho| = %.4f (bound %.4f)\n", worst, bound);
}

/* Joint uniformity across two dimensions of one pixel (x of dim 2 against x of dim 3, the
 * pair an integrator would use for, say, a BSDF and a light choice): χ² over 16×16 cells. */
static void test_sobol_cross_dimension_uniform(void **state)
{
    (void)state;
    enum { N = 1 << 14, G = 16 };
    ts_sampler s = {TS_SAMPLER_SOBOL, 99};
    static int cells[G * G];
    memset(cells, 0, sizeof cells);
    for (uint32_t i = 0; i < N; i++) {
        float a = ts_sampler_value_1d(&s, 40, 41, i, 2), b = ts_sampler_value_1d(&s, 40, 41, i, 3);
        cells[(int)(a * G) + G * (int)(b * G)]++;
    }
    double expected = (double)N / (G * G), chi2 = 0;
    for (int c = 0; c < G * G; c++)
        chi2 += (cells[c] - expected) * (cells[c] - expected) / expected;
    /* 255 degrees of freedom; the 1e-6 upper quantile (≈ 375) is the bound: false failure
     * 1e-6 for independent points (stratified marginals make it rarer still). */
    double bound = chi2_upper(G * G - 1, Z_1E6);
    printf("    sobol dims 2×3 chi2 = %.1f (dof 255, bound %.1f)\n", chi2, bound);
    assert_true(chi2 < bound);
}

static void test_values_in_range(void **state)
{
    (void)state;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 1);
    for (int t = 0; t < 2; t++) {
        ts_sampler s = {t ? TS_SAMPLER_INDEPENDENT : TS_SAMPLER_SOBOL, 0};
        for (int i = 0; i < 400000; i++) {
            uint32_t px = ts_pcg32_next(&rng), py = ts_pcg32_next(&rng), index = ts_pcg32_next(&rng),
                     dim = ts_pcg32_next(&rng) & 0xff;
            if (i < 4) { /* the extremes of index and dimension */
                index = i < 2 ? 0xffffffffu : 0u;
                dim = (i & 1) ? 0xffffffffu : 0u;
            }
            s.seed = ts_pcg32_next(&rng);
            ts_vec2 v = ts_sampler_value_2d(&s, px, py, index, dim);
            if (!(v.x >= 0 && v.x <= TS_ONE_MINUS_EPSILON && v.y >= 0 && v.y <= TS_ONE_MINUS_EPSILON))
                fail_msg("value (%a, %a) out of [0, 1)", v.x, v.y);
        }
        /* The full first 2^16 of one Sobol pixel, too (every sequence index pattern of 16 bits). */
        for (uint32_t i = 0; i < (1u << 16); i++) {
            ts_vec2 v = ts_sampler_value_2d(&s, 0, 0, i, 0);
            assert_true(v.x >= 0 && v.x < 1 && v.y >= 0 && v.y < 1);
        }
    }
}

/* χ² of N points in a G×G grid; returns the statistic. */
static double chi2_grid(const ts_vec2 *pts, int n, int g)
{
    static int cells[64 * 64];
    memset(cells, 0, sizeof cells);
    for (int i = 0; i < n; i++)
        cells[(int)(pts[i].x * g) + g * (int)(pts[i].y * g)]++;
    double expected = (double)n / (g * g), chi2 = 0;
    for (int c = 0; c < g * g; c++)
        chi2 += (cells[c] - expected) * (cells[c] - expected) / expected;
    return chi2;
}

static void test_independent_uniform(void **state)
{
    (void)state;
    enum { N = 1 << 17, G = 32 };
    static ts_vec2 pts[N];
    ts_sampler s = {TS_SAMPLER_INDEPENDENT, 2024};
    /* 1023 degrees of freedom, 128 expected per cell (the χ² approximation is excellent).
     * Bound = the 1e-6 upper quantile: a correct generator fails with probability 1e-6 per
     * statistic; with the fixed seed the outcome is fixed. */
    double bound = chi2_upper(G * G - 1, Z_1E6);
    /* Along the sample index of one pixel and dimension. */
    for (int i = 0; i < N; i++)
        pts[i] = ts_sampler_value_2d(&s, 3, 5, (uint32_t)i, 2);
    double c1 = chi2_grid(pts, N, G);
    /* Across pixels at a fixed index and dimension (512 × 256 pixels). */
    for (int i = 0; i < N; i++)
        pts[i] = ts_sampler_value_2d(&s, (uint32_t)(i & 511), (uint32_t)(i >> 9), 0, 0);
    double c2 = chi2_grid(pts, N, G);
    /* Across dimensions of one sample (x of dim d against x of dim d + 1). */
    for (int i = 0; i < N; i++) {
        uint32_t index = (uint32_t)i >> 6, d = (uint32_t)(i & 63);
        pts[i] =
            (ts_vec2){ts_sampler_value_1d(&s, 9, 9, index, d), ts_sampler_value_1d(&s, 9, 9, index, d + 64)};
    }
    double c3 = chi2_grid(pts, N, G);
    printf("    independent chi2 = %.1f / %.1f / %.1f (dof 1023, bound %.1f)\n", c1, c2, c3, bound);
    assert_true(c1 < bound);
    assert_true(c2 < bound);
    assert_true(c3 < bound);
}

/* The point of the nets: a smooth integrand converges far faster than with independent
 * samples. ∫∫ x·e^y over [0,1]² = (e − 1)/2. */
static void test_sobol_beats_independent(void **state)
{
    (void)state;
    enum { N = 1024, PIXELS = 64 };
    const double exact = (exp(1.0) - 1) / 2;
    double err2[2] = {0, 0};
    for (int t = 0; t < 2; t++) {
        ts_sampler s = {t ? TS_SAMPLER_INDEPENDENT : TS_SAMPLER_SOBOL, 5};
        for (uint32_t p = 0; p < PIXELS; p++) {
            double sum = 0;
            for (uint32_t i = 0; i < N; i++) {
                ts_vec2 u = ts_sampler_value_2d(&s, p, 0, i, 0);
                sum += u.x * exp(u.y);
            }
            err2[t] += (sum / N - exact) * (sum / N - exact);
        }
    }
    double rms_sobol = sqrt(err2[0] / PIXELS), rms_indep = sqrt(err2[1] / PIXELS);
    printf("    rms error, 1024 spp: sobol %.3g, independent %.3g\n", rms_sobol, rms_indep);
    /* Independent: σ/√N ≈ 0.49/32 ≈ 0.015. Owen-scrambled nets: O(N^-1.5) for smooth
     * integrands, about 1e-4 here; a factor 10 is a very loose requirement. */
    assert_true(rms_sobol * 10 < rms_indep);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sobol_nets),
        cmocka_unit_test(test_sobol_unaligned_not_net),
        cmocka_unit_test(test_sobol_order_independent),
        cmocka_unit_test(test_pixel_cache_sobol),
        cmocka_unit_test(test_pixel_cache_independent),
        cmocka_unit_test(test_dim_arrays),
        cmocka_unit_test(test_independent_deterministic),
        cmocka_unit_test(test_sobol_decorrelated),
        cmocka_unit_test(test_sobol_cross_dimension_uniform),
        cmocka_unit_test(test_values_in_range),
        cmocka_unit_test(test_independent_uniform),
        cmocka_unit_test(test_sobol_beats_independent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
