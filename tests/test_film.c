/* test_film.c — pixel filters (importance sampling, weights, evaluation) and the film
 * (exact accumulation, variance estimate, crop windows, merge, clear). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
/* cmocka.h needs the three headers above first. */
#include <cmocka.h>

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/hash.h"
#include "film/film.h"
#include "film/filter.h"

static void assert_close(double a, double b, double tol)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%.17g != %.17g (tolerance %g)", a, b, tol);
}

/* ---- filters ---------------------------------------------------------------------- */

static const ts_filter_type k_types[] = {TS_FILTER_BOX, TS_FILTER_TRIANGLE, TS_FILTER_GAUSSIAN,
                                         TS_FILTER_MITCHELL};
static const float k_radii[] = {0.5f, 1.5f, 2.0f};

/* The filters' 1-D profiles written from their definitions (unnormalised), independently
 * of filter.c. */
static double ref_profile(ts_filter_type type, double r, double x)
{
    x = fabs(x);
    if (x > r) return 0;
    switch (type) {
    case TS_FILTER_BOX:
        return 1;
    case TS_FILTER_TRIANGLE:
        return r - x;
    case TS_FILTER_GAUSSIAN: {
        double s = r / 3;
        return exp(-x * x / (2 * s * s)) - exp(-r * r / (2 * s * s));
    }
    case TS_FILTER_MITCHELL: {
        double t = 2 * x / r; /* B = C = 1/3 expanded */
        if (t < 1) return (7 * t * t * t - 12 * t * t + 16.0 / 3) / 6;
        return (-7.0 / 3 * t * t * t + 12 * t * t - 20 * t + 32.0 / 3) / 6;
    }
    }
    return 0;
}

/* A smooth, non-separable test integrand over the filter footprint. */
static double test_g(double x, double y)
{
    return 1 + 0.5 * sin(2 * x + 0.3) + 0.25 * cos(1.5 * y) + 0.3 * x * y + 0.2 * x * x;
}

/* ∫∫ f·g / ∫∫ f by the midpoint rule on Q×Q points with the reference profile. For these
 * smooth integrands the error is O(h²) ≈ 1e-6, far below the Monte Carlo tolerance. */
static double reference_mean(ts_filter_type type, double r)
{
    enum { Q = 1024 };
    static double fx[Q], xs[Q];
    double h = 2 * r / Q, num = 0, den = 0;
    for (int i = 0; i < Q; i++)
        xs[i] = -r + (i + 0.5) * h, fx[i] = ref_profile(type, r, xs[i]);
    for (int j = 0; j < Q; j++)
        for (int i = 0; i < Q; i++) {
            double f = fx[i] * fx[j];
            num += f * test_g(xs[i], xs[j]);
            den += f;
        }
    return num / den;
}

static void test_filter_init_errors(void **state)
{
    (void)state;
    ts_filter f;
    ts_error err;
    const float bad[] = {0.0f, -1.0f, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        ts_error_clear(&err);
        assert_int_equal(ts_filter_init(&f, TS_FILTER_GAUSSIAN, bad[i], &err), TS_ERR_INVALID);
        assert_int_equal(err.status, TS_ERR_INVALID);
        assert_non_null(strstr(err.message, "radius"));
    }
    assert_int_equal(ts_filter_init(&f, (ts_filter_type)42, 1.0f, &err), TS_ERR_INVALID);
    assert_int_equal(ts_filter_init(&f, TS_FILTER_MITCHELL, 2.0f, NULL), TS_OK);
    assert_string_equal(ts_filter_type_name(TS_FILTER_MITCHELL), "mitchell");
}

/* ts_filter_eval is the reference profile, normalised to unit integral. */
static void test_filter_eval(void **state)
{
    (void)state;
    for (size_t t = 0; t < 4; t++)
        for (size_t k = 0; k < 3; k++) {
            ts_filter f;
            double r = k_radii[k];
            assert_int_equal(ts_filter_init(&f, k_types[t], k_radii[k], NULL), TS_OK);
            /* Integral over a grid finer than the profile's curvature: midpoint error O(h²),
             * h = 2r/2000, below 1e-5; float evaluation adds ~1e-7. */
            enum { Q = 2000 };
            double h = 2 * r / Q, integral = 0, ref_int = 0;
            for (int i = 0; i < Q; i++) {
                double x = -r + (i + 0.5) * h;
                integral += ts_filter_eval(&f, (ts_vec2){(float)x, 0}) * h;
                ref_int += ref_profile(k_types[t], r, x) * h;
            }
            /* ∫ f(x, 0) dx = f1(0), and f1 = profile/∫profile. */
            double f1_0 = ref_profile(k_types[t], r, 0) / ref_int;
            assert_close(integral, f1_0, 1e-5 * f1_0);
            /* Pointwise against the reference, relative to the peak (float arithmetic). */
            for (int i = 0; i <= 40; i++)
                for (int j = 0; j <= 40; j++) {
                    double x = -1.1 * r + 2.2 * r * i / 40, y = -1.1 * r + 2.2 * r * j / 40;
                    double want =
                        ref_profile(k_types[t], r, x) * ref_profile(k_types[t], r, y) / (ref_int * ref_int);
                    assert_close(ts_filter_eval(&f, (ts_vec2){(float)x, (float)y}), want, 1e-5 * f1_0 * f1_0);
                }
        }
}

/* Offsets stay within the radius for all u, including the extremes, and move monotonically
 * with u (so stratified u stay stratified). Box and triangle weights are exactly 1. */
static void test_filter_sample_bounds(void **state)
{
    (void)state;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 11, 3);
    for (size_t t = 0; t < 4; t++)
        for (size_t k = 0; k < 3; k++) {
            ts_filter f;
            float r = k_radii[k];
            assert_int_equal(ts_filter_init(&f, k_types[t], r, NULL), TS_OK);
            float prev = -INFINITY;
            for (int i = 0; i <= 200000; i++) {
                float u = i == 200000 ? TS_ONE_MINUS_EPSILON : (float)i / 200000;
                float w;
                ts_vec2 d = ts_filter_sample(&f, (ts_vec2){u, ts_pcg32_float(&rng)}, &w);
                if (!(fabsf(d.x) <= r && fabsf(d.y) <= r))
                    fail_msg("offset (%g, %g) beyond radius %g", d.x, d.y, r);
                if (d.x < prev) fail_msg("offset not monotone at u = %g", u);
                prev = d.x;
                assert_true(isfinite(w));
                if (k_types[t] == TS_FILTER_BOX || k_types[t] == TS_FILTER_TRIANGLE) assert_true(w == 1.0f);
                /* The weight's sign is the filter's sign there (pdf > 0 everywhere sampled). */
                float fv = ts_filter_eval(&f, d);
                if (fv != 0 && w != 0) assert_true((fv > 0) == (w > 0));
            }
            /* Both extremes reach (almost) the edge of the support. */
            float w;
            assert_true(ts_filter_sample(&f, (ts_vec2){0, 0}, &w).x <= -0.9f * r);
            assert_true(ts_filter_sample(&f, (ts_vec2){TS_ONE_MINUS_EPSILON, 0}, &w).x >= 0.9f * r);
        }
}

/* The weighted mean Σ w·g / Σ w of N filter-sampled points converges to ∫f·g / ∫f, and
 * the mean weight to ∫f = 1. */
static void test_filter_importance_sampling(void **state)
{
    (void)state;
    enum { N = 1 << 20 };
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 2718, 28);
    for (size_t t = 0; t < 4; t++)
        for (size_t k = 0; k < 3; k++) {
            ts_filter f;
            assert_int_equal(ts_filter_init(&f, k_types[t], k_radii[k], NULL), TS_OK);
            static double ws[N], gs[N];
            double sw = 0, swg = 0, sw2 = 0, wmin = INFINITY, wmax = -INFINITY;
            for (int i = 0; i < N; i++) {
                ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
                float w;
                ts_vec2 d = ts_filter_sample(&f, u, &w);
                ws[i] = w;
                gs[i] = test_g(d.x, d.y);
                sw += w, swg += w * gs[i], sw2 += (double)w * w;
                wmin = fmin(wmin, w), wmax = fmax(wmax, w);
            }
            double est = swg / sw, mean_w = sw / N;
            /* Delta-method variance of the ratio estimator: Σ w²(g − est)² / (Σ w)². */
            double v = 0;
            for (int i = 0; i < N; i++)
                v += ws[i] * ws[i] * (gs[i] - est) * (gs[i] - est);
            double sigma = sqrt(v) / fabs(sw), sigma_w = sqrt(sw2 / N - mean_w * mean_w) / sqrt((double)N);
            double want = reference_mean(k_types[t], k_radii[k]);
            printf("    %-8s r=%.1f: mean %.6f want %.6f (%+.2f sigma), E[w] %.6f (%+.2f sigma), w in [%.4f, "
                   "%.4f], sd %.4f\n",
                   ts_filter_type_name(k_types[t]), (double)k_radii[k], est, want, (est - want) / sigma,
                   mean_w, sigma_w > 0 ? (mean_w - 1) / sigma_w : 0.0, wmin, wmax, sigma_w * sqrt((double)N));
            /* 5σ two-sided: a correct sampler fails with probability ≈ 6e-7 per case for a
             * random seed (the estimates are sums of 2^20 terms: normal). Plus 1e-5 for the
             * quadrature of the reference and float rounding of the sums' terms. */
            assert_close(est, want, 5 * sigma + 1e-5);
            /* E[w] = ∫f = 1 exactly for the density sampled (box/triangle: σ_w = 0, and float
             * rounding of the tabulated density is ~1e-7). */
            assert_close(mean_w, 1, 5 * sigma_w + 1e-5);
            if (k_types[t] == TS_FILTER_GAUSSIAN) {
                /* f/p is nearly constant: the piecewise-constant density tracks |f| to within
                 * a cell (1/64 of the radius); only the two end cells, where f → 0 linearly,
                 * range over (0, 2). The spread of weights stays small. */
                assert_true(sqrt(sw2 / N - mean_w * mean_w) < 0.05);
            }
            if (k_types[t] == TS_FILTER_MITCHELL) assert_true(wmin < 0); /* negative lobes are sampled */
        }
}

/* ---- film ------------------------------------------------------------------------- */

static void test_film_create_errors(void **state)
{
    (void)state;
    ts_error err;
    struct {
        int fw, fh, x0, y0, w, h;
    } bad[] = {
        {0, 10, 0, 0, 1, 1},   {10, -1, 0, 0, 1, 1}, {10, 10, 0, 0, 0, 5}, {10, 10, 0, 0, 5, 0},
        {10, 10, -1, 0, 5, 5}, {10, 10, 6, 0, 5, 5}, {10, 10, 0, 6, 5, 5}, {10, 10, 0, 0, 11, 1},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        ts_error_clear(&err);
        assert_null(ts_film_create(bad[i].fw, bad[i].fh, bad[i].x0, bad[i].y0, bad[i].w, bad[i].h, &err));
        assert_int_equal(err.status, TS_ERR_INVALID);
        assert_true(strlen(err.message) > 0);
    }
    ts_film *f = ts_film_create(10, 10, 5, 5, 5, 5, &err);
    assert_non_null(f);
    ts_film_destroy(f);
    ts_film_destroy(NULL);
}

/* 10^7 samples of a constant: the stored mean is the constant to 1e-12 relative. */
static void test_film_constant_exact(void **state)
{
    (void)state;
    enum { N = 10000000 };
    ts_film *f = ts_film_create(4, 4, 0, 0, 4, 4, NULL);
    assert_non_null(f);
    const ts_rgb L = {0.3f, 1.7f, 123.456f};
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 5, 5);
    for (int i = 0; i < N; i++) {
        ts_film_add_sample(f, 1, 2, L, 1.0f);
        /* Pixel (3,3): varying filter weights, as a gaussian filter gives. */
        ts_film_add_sample(f, 3, 3, L, 0.5f + ts_pcg32_float(&rng));
    }
    const ts_film_pixel *p = ts_film_pixel_at(f, 1, 2), *q = ts_film_pixel_at(f, 3, 3);
    assert_true(p->count == N && q->count == N);
    double worst = 0;
    const double want[3] = {L.r, L.g, L.b};
    for (int c = 0; c < 3; c++) {
        /* Weight 1: w·L and Σ are exact in double below 2^29 samples, so equality. */
        assert_true(p->sum[c] / p->weight == want[c]);
        /* Varying weights: each Σ rounds like a random walk, ~√N·2^-53 ≈ 4e-13 relative. */
        double rel = fabs(q->sum[c] / q->weight - want[c]) / want[c];
        worst = fmax(worst, rel);
        assert_true(rel <= 1e-12);
    }
    printf("    constant radiance, 1e7 varying-weight samples: relative error %.2g\n", worst);
    ts_rgb m = ts_film_pixel_rgb(f, 1, 2);
    assert_true(m.r == L.r && m.g == L.g && m.b == L.b);
    /* A constant has zero variance. Σ w·L² is not exact (L² has 48 bits, times w 72), so the
     * cancellation in Σw·L²/Σw − mean² leaves up to N·2^-53 ≈ 1e-9 relative of L², divided
     * by n_eff − 1 ≈ N: the estimate must be below 1e-9·L²/N. */
    ts_rgb v = ts_film_pixel_variance(f, 1, 2), vq = ts_film_pixel_variance(f, 3, 3);
    printf("    constant radiance: variance estimate %.3g (weight 1), %.3g (varying), L^2/N = %.3g\n", v.b,
           vq.b, L.b * L.b / N);
    assert_true(v.r <= 1e-9 * L.r * L.r / N && v.g <= 1e-9 * L.g * L.g / N && v.b <= 1e-9 * L.b * L.b / N);
    assert_true(vq.r <= 1e-9 * L.r * L.r / N && vq.g <= 1e-9 * L.g * L.g / N && vq.b <= 1e-9 * L.b * L.b / N);
    /* Untouched pixels and pixels outside the window read as 0. */
    ts_rgb z = ts_film_pixel_rgb(f, 0, 0), zo = ts_film_pixel_rgb(f, 9, 9);
    assert_true(z.r == 0 && z.g == 0 && z.b == 0 && zo.r == 0);
    ts_film_destroy(f);
}

/* Exponential(1) variate: mean 1, variance 1. */
static double exponential(ts_pcg32 *rng) { return -log(1 - ts_pcg32_double(rng)); }

/* The variance of each pixel's mean is estimated right: per channel a source of known
 * variance (uniform: 1/12; constant 2: 0; exponential: 1), N samples per pixel, many
 * pixels. Checked against the truth and against the observed spread of the pixel means. */
static void check_variance(int weighted)
{
    enum { W = 64, H = 64, N = 1000, P = W * H };
    ts_film *f = ts_film_create(W, H, 0, 0, W, H, NULL);
    assert_non_null(f);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, weighted ? 77 : 76, 1);
    static double inv_neff[P];
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double sw = 0, sw2 = 0;
            for (int i = 0; i < N; i++) {
                /* Weighted: weights in [0.5, 1.5) independent of L, the case where the
                 * estimator s²/(n_eff − 1) is unbiased. */
                float w = weighted ? 0.5f + ts_pcg32_float(&rng) : 1.0f;
                ts_rgb L = {ts_pcg32_float(&rng), 2.0f, (float)exponential(&rng)};
                ts_film_add_sample(f, x, y, L, w);
                sw += w, sw2 += (double)w * w;
            }
            inv_neff[x + y * W] = sw2 / (sw * sw);
        }
    const double sigma2[3] = {1.0 / 12, 0, 1}, mean[3] = {0.5, 2, 1};
    /* Relative standard deviation of one pixel's s²: √((κ − 1)/N) with kurtosis κ = 1.8
     * (uniform) and 9 (exponential); averaged over P = 4096 pixels, /64. 5σ bounds (false
     * failure ≈ 6e-7 each, the average of 4096 terms being normal): */
    const double rel_tol[3] = {5 * sqrt(0.8 / N) / sqrt(P), 0, 5 * sqrt(8.0 / N) / sqrt(P)};
    for (int c = 0; c < 3; c++) {
        double est = 0, truth = 0, m = 0;
        for (int i = 0; i < P; i++) {
            ts_rgb v = ts_film_pixel_variance(f, i % W, i / W), mu = ts_film_pixel_rgb(f, i % W, i / W);
            double vc = c == 0 ? v.r : c == 1 ? v.g : v.b, mc = c == 0 ? mu.r : c == 1 ? mu.g : mu.b;
            est += vc;
            truth += sigma2[c] * inv_neff[i]; /* Var(Σ w·L / Σ w) = σ²·Σw²/(Σw)² */
            m += (mc - mean[c]) * (mc - mean[c]);
        }
        est /= P, truth /= P, m /= P;
        printf("    %s channel %d: mean estimated variance %.6g, true %.6g, observed spread %.6g\n",
               weighted ? "weighted" : "unweighted", c, est, truth, m);
        if (c == 1) {
            /* Constant: exactly zero unweighted; weighted, cancellation leaves ≲ 1e-15·4/N. */
            assert_true(est <= 1e-17);
            continue;
        }
        assert_close(est, truth, rel_tol[c] * truth);
        /* The observed mean squared deviation of the pixel means from the true mean is an
         * average of P squared, nearly normal deviations: relative sd √(2/P) ≈ 2.2%,
         * 5σ ≈ 11%. */
        assert_close(m, truth, 5 * sqrt(2.0 / P) * truth);
    }
    ts_film_destroy(f);
}

static void test_film_variance(void **state)
{
    (void)state;
    check_variance(0);
    check_variance(1);
    /* One sample: variance unknown, reported as 0. */
    ts_film *f = ts_film_create(1, 1, 0, 0, 1, 1, NULL);
    ts_film_add_sample(f, 0, 0, (ts_rgb){1, 2, 3}, 1);
    ts_rgb v = ts_film_pixel_variance(f, 0, 0);
    assert_true(v.r == 0 && v.g == 0 && v.b == 0);
    /* Two samples 0 and 2: unbiased sample variance 2, variance of the mean 1. */
    ts_film_add_sample(f, 0, 0, (ts_rgb){3, 2, 1}, 1);
    v = ts_film_pixel_variance(f, 0, 0);
    assert_close(v.r, 1, 0);
    assert_close(v.g, 0, 0);
    assert_close(v.b, 1, 0);
    ts_film_destroy(f);
}

/* A crop window addresses full-image pixels: (x, y) lands in (x − x0) + (y − y0)·width,
 * and samples outside the window are dropped. */
static void test_film_crop(void **state)
{
    (void)state;
    enum { FW = 100, FH = 80, X0 = 10, Y0 = 20, CW = 30, CH = 15 };
    ts_film *f = ts_film_create(FW, FH, X0, Y0, CW, CH, NULL);
    assert_non_null(f);
    assert_true(f->full_width == FW && f->full_height == FH && f->x0 == X0 && f->y0 == Y0);
    for (int y = -2; y < FH + 2; y++)
        for (int x = -2; x < FW + 2; x++)
            ts_film_add_sample(f, x, y, (ts_rgb){(float)x, (float)y, 1}, 2.0f);
    float *rgb = malloc(sizeof(float) * 3 * CW * CH);
    assert_non_null(rgb);
    ts_film_resolve(f, rgb);
    uint64_t total = 0;
    for (int j = 0; j < CH; j++)
        for (int i = 0; i < CW; i++) {
            const float *px = rgb + 3 * (i + j * CW);
            assert_true(px[0] == X0 + i && px[1] == Y0 + j && px[2] == 1);
            total += f->pixels[i + j * CW].count;
            assert_true(f->pixels[i + j * CW].weight == 2.0);
        }
    assert_true(total == CW * CH); /* nothing outside the window was counted */
    assert_true(ts_film_contains(f, X0, Y0) && ts_film_contains(f, X0 + CW - 1, Y0 + CH - 1));
    assert_false(ts_film_contains(f, X0 - 1, Y0) || ts_film_contains(f, X0 + CW, Y0) ||
                 ts_film_contains(f, X0, Y0 + CH) || ts_film_contains(f, X0, Y0 - 1));
    assert_null(ts_film_pixel_at(f, 0, 0));
    ts_rgb c = ts_film_pixel_rgb(f, X0 + 3, Y0 + 4);
    assert_true(c.r == X0 + 3 && c.g == Y0 + 4);
    ts_film_clear(f);
    ts_film_resolve(f, rgb);
    for (int i = 0; i < 3 * CW * CH; i++)
        assert_true(rgb[i] == 0);
    assert_true(f->pixels[0].count == 0 && f->pixels[0].weight == 0);
    free(rgb);
    ts_film_destroy(f);
}

/* Two films with half the samples each, merged, equal one film with all of them: counts
 * exactly, sums to a few ulps (double addition in a different order). */
static void test_film_merge(void **state)
{
    (void)state;
    enum { W = 16, H = 8, N = 64 };
    ts_film *all = ts_film_create(40, 40, 4, 4, W, H, NULL), *a = ts_film_create(40, 40, 4, 4, W, H, NULL),
            *b = ts_film_create(40, 40, 4, 4, W, H, NULL);
    assert_true(all && a && b);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 9, 9);
    for (int y = 4; y < 4 + H; y++)
        for (int x = 4; x < 4 + W; x++)
            for (int i = 0; i < N; i++) {
                ts_rgb L = {ts_pcg32_float(&rng), 3 * ts_pcg32_float(&rng), (float)exponential(&rng)};
                float w = i % 5 == 4 ? -0.2f : 0.5f + ts_pcg32_float(&rng); /* incl. negative (Mitchell) */
                ts_film_add_sample(all, x, y, L, w);
                ts_film_add_sample(i < N / 2 ? a : b, x, y, L, w);
            }
    ts_film_merge(a, b);
    for (int i = 0; i < W * H; i++) {
        const ts_film_pixel *p = &all->pixels[i], *q = &a->pixels[i];
        assert_true(p->count == q->count);
        /* Sums of 64 terms of magnitude ≲ 10 in two orders: differences ≲ 64·2^-53·10. */
        for (int c = 0; c < 3; c++) {
            assert_close(q->sum[c], p->sum[c], 1e-13);
            assert_close(q->sum_sq[c], p->sum_sq[c], 1e-12);
        }
        assert_close(q->weight, p->weight, 1e-13);
        assert_close(q->weight_sq, p->weight_sq, 1e-13);
    }
    /* Merging a film of another window adds only the overlap. */
    ts_film *c = ts_film_create(40, 40, 0, 0, 6, 6, NULL);
    assert_non_null(c);
    ts_film_merge(c, all);
    for (int y = 0; y < 6; y++)
        for (int x = 0; x < 6; x++) {
            const ts_film_pixel *p = ts_film_pixel_at(c, x, y);
            if (x >= 4 && y >= 4)
                assert_true(p->count == N && p->sum[0] == ts_film_pixel_at(all, x, y)->sum[0]);
            else
                assert_true(p->count == 0 && p->weight == 0);
        }
    ts_film_destroy(c);
    ts_film_destroy(all);
    ts_film_destroy(a);
    ts_film_destroy(b);
}

/* Film "scale" is an output factor: the sums are those of scale 1, the values scale times
 * theirs and the variances scale² times; merges keep the destination's scale. pbrt-v3's
 * maxsampleluminance: a sample above the luminance is scaled to it (pbrt-v3's Y weights),
 * one at or below it passes bit for bit. */
static void test_film_scale_and_clamp(void **state)
{
    (void)state;
    ts_film *a = ts_film_create(8, 8, 0, 0, 8, 8, NULL), *b = ts_film_create(8, 8, 0, 0, 8, 8, NULL);
    assert_true(a && b);
    assert_true(a->scale == 1);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 3);
    for (int i = 0; i < 40; i++) {
        ts_rgb L = {ts_pcg32_float(&rng), 2 * ts_pcg32_float(&rng), 0.5f + ts_pcg32_float(&rng)};
        float w = 0.25f + ts_pcg32_float(&rng);
        ts_film_add_sample(a, 3, 4, L, w);
        ts_film_add_sample(b, 3, 4, L, w);
    }
    b->scale = 1.5f;
    assert_memory_equal(ts_film_pixel_at(a, 3, 4), ts_film_pixel_at(b, 3, 4), sizeof(ts_film_pixel));
    ts_rgb m = ts_film_pixel_rgb(a, 3, 4), ms = ts_film_pixel_rgb(b, 3, 4);
    ts_rgb v = ts_film_pixel_variance(a, 3, 4), vs = ts_film_pixel_variance(b, 3, 4);
    assert_close(ms.r, 1.5 * m.r, 1e-6 * m.r);
    assert_close(ms.g, 1.5 * m.g, 1e-6 * m.g);
    assert_close(ms.b, 1.5 * m.b, 1e-6 * m.b);
    assert_true(v.g > 0);
    assert_close(vs.g, 2.25 * v.g, 1e-6 * v.g);
    float rgb[8 * 8 * 3];
    ts_film_resolve(b, rgb);
    assert_true(rgb[(4 * 8 + 3) * 3 + 1] == ms.g);
    b->scale = FLT_MAX; /* values beyond float range give the largest float, not ∞ */
    ts_rgb big = ts_film_pixel_rgb(b, 3, 4);
    assert_true(isfinite(big.r) && isfinite(big.g) && isfinite(big.b) && (big.g == FLT_MAX || big.b == FLT_MAX));
    assert_true(ts_film_pixel_variance(b, 3, 4).g == FLT_MAX);
    b->scale = 1.5f;
    ts_film_merge(b, a); /* adds a's sums; b keeps its scale */
    assert_true(b->scale == 1.5f);
    assert_close(ts_film_pixel_rgb(b, 3, 4).g, ms.g, 1e-6 * ms.g);
    ts_film_destroy(a);
    ts_film_destroy(b);

    ts_rgb bright = {100, 40, 2}, dim = {1, 2, 3};
    ts_rgb c = ts_film_clamp_luminance(bright, 10);
    double y = 0.212671 * c.r + 0.715160 * c.g + 0.072169 * c.b;
    assert_close(y, 10, 1e-5);
    assert_close(c.g / c.r, 0.4, 1e-6); /* the colour's ratios stay */
    ts_rgb d = ts_film_clamp_luminance(dim, 10);
    assert_memory_equal(&d, &dim, sizeof d);
    d = ts_film_clamp_luminance(bright, INFINITY);
    assert_memory_equal(&d, &bright, sizeof d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_filter_init_errors),   cmocka_unit_test(test_filter_eval),
        cmocka_unit_test(test_filter_sample_bounds), cmocka_unit_test(test_filter_importance_sampling),
        cmocka_unit_test(test_film_create_errors),   cmocka_unit_test(test_film_constant_exact),
        cmocka_unit_test(test_film_variance),        cmocka_unit_test(test_film_crop),
        cmocka_unit_test(test_film_merge),           cmocka_unit_test(test_film_scale_and_clamp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
