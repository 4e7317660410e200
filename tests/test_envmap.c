/* test_envmap.c — lat-long environment maps (envmap.h): χ² of importance sampling on a
 * constant map, a 3×2 map and a map black but for one texel; continuity of lookups at the
 * poles and across the seam; pdf 0 (not ∞) at sinθ = 0; bounded L/pdf on a sparse map;
 * loading from an EXR file. χ² significance: the project-wide family of
 * TS_CHI2_FAMILY_SIZE tests fails with probability ≤ 0.01; fixed seeds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "chi2.h"
#include "core/hash.h"
#include "image/exr.h"
#include "image/image.h"
#include "lights/envmap.h"

static void assert_close(double a, double b, double tol, const char *what)
{
    if (!(fabs(a - b) <= tol)) fail_msg("%s: %.9g != %.9g (tolerance %g)", what, a, b, tol);
}

static ts_envmap *make_map(const ts_rgb *tx, uint32_t w, uint32_t h)
{
    ts_envmap *m = NULL;
    ts_error err = {0};
    if (ts_envmap_create(tx, w, h, &m, &err)) fail_msg("%s", err.message);
    return m;
}

static ts_chi2_outcome chi2_sample(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    const ts_envmap *m = ctx;
    float a = ts_pcg32_float(rng);
    ts_vec2 u = {a, ts_pcg32_float(rng)};
    float pdf;
    if (!ts_envmap_sample(m, u, w, &pdf)) return TS_CHI2_NONE;
    *w = ts_vec3_normalize(*w);
    return TS_CHI2_DIRECTION;
}

static double chi2_pdf(void *ctx, ts_vec3 w) { return ts_envmap_pdf(ctx, w); }

/* The pdf is piecewise constant over texels whose borders are lines of constant θ
 * (not of constant cosθ, chi2's rows) and constant φ: chi2's quadrature handles the φ
 * borders when they fall on its columns (42 columns: maps 3, 6, 14, 21 or 42 wide) and
 * refines along the θ borders. */
static void run_chi2(const char *name, ts_envmap *m, uint64_t seed)
{
    ts_chi2_params p;
    ts_chi2_params_default(&p);
    p.seed = seed;
    p.sample_count = 400000;
    p.max_node_evals = 40000;
    ts_chi2_result r;
    bool ok = ts_chi2_test(&p, chi2_sample, chi2_pdf, m, &r);
    print_message("chi2 %-28s p=%.4f ∫pdf=%.6f none=%llu, %d cells over budget %s\n", name, r.p_value,
                  r.pdf_integral, (unsigned long long)r.none, r.unconverged, ok ? "" : r.message);
    if (!ok) fail_msg("%s: %s", name, r.message);
    /* Every sample is a direction (sinθ = 0 has probability 0) and the pdf integrates to 1
     * within chi2's own quadrature error on the θ borders (≤ 2e-3 measured). */
    assert_true(r.none == 0);
    assert_close(r.pdf_integral, 1.0, 5e-3, "∫pdf");
}

static void test_chi2(void **state)
{
    (void)state;
    ts_rgb c[16 * 8];
    for (int i = 0; i < 16 * 8; i++) c[i] = ts_rgb_make(0.5f, 0.7f, 0.9f);
    ts_envmap *m = make_map(c, 14, 8);
    run_chi2("constant 14×8", m, 1);
    ts_envmap_destroy(m);
    ts_rgb c32[6] = {{1, 2, 3}, {0.1f, 0.1f, 0.1f}, {5, 0, 0}, {0, 0, 0}, {0.3f, 0.2f, 0.1f}, {2, 2, 2}};
    m = make_map(c32, 3, 2);
    run_chi2("3×2", m, 2);
    ts_envmap_destroy(m);
    ts_rgb one[21 * 10] = {{0}};
    one[4 * 21 + 7] = ts_rgb_make(100, 50, 10);
    m = make_map(one, 21, 10);
    run_chi2("one texel of 21×10", m, 3);
    ts_envmap_destroy(m);
}

/* Lookups are continuous: across the seam φ = 0 and at the poles, directions 1e-5 rad
 * apart have radiance within 1e-3 of each other (the map's largest texel difference is
 * 10, the bilinear slope at most 10·w/(2π) = 25 per radian: 2.5e-4 for 1e-5 rad; 1e-3
 * leaves room for float rounding). Values at θ = 0 and π equal the row means. */
static void test_continuity(void **state)
{
    (void)state;
    enum { W = 16, H = 8 };
    ts_rgb tx[W * H];
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 8, 8);
    for (int i = 0; i < W * H; i++) tx[i] = ts_rgb_make(10 * ts_pcg32_float(&rng), ts_pcg32_float(&rng), 0.5f);
    ts_envmap *m = make_map(tx, W, H);
    double eps = 1e-5;
    for (int k = 0; k < 200; k++) {
        double theta = (k + 0.5) * TS_PI_D / 200;
        ts_vec3 a = {(float)(sin(theta) * cos(eps)), (float)(sin(theta) * sin(eps)), (float)cos(theta)};
        ts_vec3 b = {(float)(sin(theta) * cos(-eps)), (float)(sin(theta) * sin(-eps)), (float)cos(theta)};
        ts_rgb la = ts_envmap_lookup(m, a), lb = ts_envmap_lookup(m, b);
        assert_close(la.r, lb.r, 1e-3, "seam continuity");
        assert_close(la.g, lb.g, 1e-3, "seam continuity");
    }
    ts_rgb north = ts_envmap_lookup(m, (ts_vec3){0, 0, 1}), south = ts_envmap_lookup(m, (ts_vec3){0, 0, -1});
    assert_close(north.r, m->pole_mean[0].r, 1e-6, "north pole = mean of row 0");
    assert_close(south.r, m->pole_mean[1].r, 1e-6, "south pole = mean of last row");
    for (int k = 0; k < 64; k++) {
        double phi = k * 2 * TS_PI_D / 64;
        ts_vec3 n = {(float)(sin(eps) * cos(phi)), (float)(sin(eps) * sin(phi)), (float)cos(eps)};
        ts_vec3 s = {(float)(sin(eps) * cos(phi)), (float)(sin(eps) * sin(phi)), (float)-cos(eps)};
        assert_close(ts_envmap_lookup(m, n).r, north.r, 1e-3, "north pole continuity");
        assert_close(ts_envmap_lookup(m, s).r, south.r, 1e-3, "south pole continuity");
    }
    /* Texel centres return the texel. */
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            ts_rgb l = ts_envmap_lookup_uv(m, (ts_vec2){(i + 0.5f) / W, (j + 0.5f) / H});
            assert_close(l.r, tx[j * W + i].r, 1e-5, "texel centre");
        }
    /* The pdf at the poles is 0, not ∞; everywhere else it is finite and positive. */
    assert_true(ts_envmap_pdf(m, (ts_vec3){0, 0, 1}) == 0);
    assert_true(ts_envmap_pdf(m, (ts_vec3){0, 0, -1}) == 0);
    float p = ts_envmap_pdf(m, ts_vec3_normalize((ts_vec3){1e-20f, 0, 1}));
    assert_true(isfinite(p) && p >= 0);
    /* Direction ↔ (u, v) round trip. */
    for (int k = 0; k < 100; k++) {
        ts_vec2 uv = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
        ts_vec2 back = ts_envmap_dir_to_uv(ts_envmap_uv_to_dir(uv));
        double du = fabs(back.x - uv.x);
        du = fmin(du, 1 - du);
        assert_close(du, 0, 1e-5, "u round trip");
        assert_close(back.y, uv.y, 1e-5, "v round trip");
    }
    ts_envmap_destroy(m);
}

/* Sparse map: L/pdf (per channel average) stays below the bound 4π²·I of envmap.c, I the
 * mean sampling weight, for every one of 10^5 samples; and the estimator of ∫L dω by
 * L/pdf converges to the map's integral (5σ). */
static void test_sparse_weight(void **state)
{
    (void)state;
    enum { W = 64, H = 32 };
    static ts_rgb tx[W * H];
    memset(tx, 0, sizeof tx);
    tx[0 * W + 5] = ts_rgb_make(1000, 1000, 1000); /* in the polar row */
    tx[17 * W + 40] = ts_rgb_make(3, 2, 1);
    ts_envmap *m = make_map(tx, W, H);
    double bound = 4 * TS_PI_D * TS_PI_D * ts_distribution2d_integral(&m->distrib);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 6, 6);
    double worst = 0, sum = 0, sum2 = 0;
    int n = 100000;
    for (int i = 0; i < n; i++) {
        ts_vec3 w;
        float pdf;
        ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
        double x = 0;
        if (ts_envmap_sample(m, u, &w, &pdf)) {
            assert_true(isfinite(pdf) && pdf > 0);
            ts_rgb l = ts_envmap_lookup(m, w);
            x = ts_rgb_average(l) / pdf;
            assert_true(isfinite(x));
            worst = fmax(worst, x);
        }
        sum += x, sum2 += x * x;
    }
    print_message("sparse map: largest avg(L)/pdf %.4g, bound %.4g\n", worst, bound);
    assert_true(worst <= bound);
    /* Reference ∫ avg(L) dω by a fine midpoint rule in (θ, φ) on the lookup. */
    double ref = 0;
    int kt = 2048, kp = 4096;
    for (int i = 0; i < kt; i++) {
        double th = (i + 0.5) * TS_PI_D / kt;
        for (int j = 0; j < kp; j++) {
            double ph = (j + 0.5) * 2 * TS_PI_D / kp;
            ts_rgb l = ts_envmap_lookup_uv(m, (ts_vec2){(float)(ph / (2 * TS_PI_D)), (float)(th / TS_PI_D)});
            ref += ts_rgb_average(l) * sin(th);
        }
    }
    ref *= (TS_PI_D / kt) * (2 * TS_PI_D / kp);
    double mean = sum / n, sd = sqrt(fmax(0, sum2 / n - mean * mean) / n);
    print_message("sparse map: ∫L dω estimate %.5g ± %.2g, quadrature %.5g\n", mean, sd, ref);
    assert_close(mean, ref, 5 * sd + 1e-4 * ref, "∫L dω");
    ts_envmap_destroy(m);

    /* A black map samples nothing and has pdf 0. */
    ts_rgb black[4] = {{0}};
    m = make_map(black, 2, 2);
    ts_vec3 w;
    float pdf;
    assert_false(ts_envmap_sample(m, (ts_vec2){0.3f, 0.6f}, &w, &pdf));
    assert_true(ts_envmap_pdf(m, (ts_vec3){1, 0, 0}) == 0);
    ts_envmap_destroy(m);
}

static void test_load_exr(void **state)
{
    (void)state;
    char dir[] = "/tmp/ts_envmap_XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/sky.exr", dir);
    const char *names[3] = {"R", "G", "B"};
    ts_image img = {0};
    ts_error err = {0};
    assert_int_equal(ts_image_init(&img, 4, 2, 3, names, &err), TS_OK);
    for (int k = 0; k < 8 * 3; k++) img.data[k] = 0.25f * (float)k;
    assert_int_equal(ts_exr_write(path, &img, &err), TS_OK);
    ts_envmap *m = NULL;
    if (ts_envmap_load(path, &m, &err)) fail_msg("%s", err.message);
    assert_int_equal(m->width, 4);
    assert_int_equal(m->height, 2);
    int rc = ts_image_channel(&img, "R"), gc = ts_image_channel(&img, "G"), bc = ts_image_channel(&img, "B");
    for (int k = 0; k < 8; k++) {
        assert_close(m->texels[k].c.r, img.data[k * 3 + rc], 0, "R");
        assert_close(m->texels[k].c.g, img.data[k * 3 + gc], 0, "G");
        assert_close(m->texels[k].c.b, img.data[k * 3 + bc], 0, "B");
    }
    /* Each texel's weight is its cell's value in the distribution, bit for bit. */
    for (uint32_t k = 0; k < 8; k++) assert_true(m->texels[k].weight == m->distrib.conditional[k / 4].func[k % 4]);
    ts_envmap_destroy(m);
    ts_image_fini(&img);
    /* A missing file is an error naming it, not a crash. */
    snprintf(path, sizeof path, "%s/missing.exr", dir);
    m = (ts_envmap *)1;
    assert_int_not_equal(ts_envmap_load(path, &m, &err), TS_OK);
    assert_null(m);
    /* Negative texels are refused. */
    ts_rgb bad[2] = {{1, 1, 1}, {-1, 0, 0}};
    assert_int_equal(ts_envmap_create(bad, 2, 1, &m, &err), TS_ERR_INVALID);
    assert_null(m);
    snprintf(path, sizeof path, "%s/sky.exr", dir);
    unlink(path);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2),
        cmocka_unit_test(test_continuity),
        cmocka_unit_test(test_sparse_weight),
        cmocka_unit_test(test_load_exr),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
