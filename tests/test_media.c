/* test_media.c — participating media and the volpath integrator against closed forms.
 *
 * Statistical checks compare a Monte Carlo mean with its exact value within K standard
 * errors, the standard error estimated from the same samples (independent sampler, fixed
 * seeds, so each run is deterministic). K = 4.5: a correct estimator (near-normal means of
 * ≥ 10^4 samples) lands outside with probability 6.8e-6 per check; this file makes about
 * 60 such checks, so correct code fails it with probability ≤ 4e-4 over seeds. The χ²
 * tests of the Henyey–Greenstein sampler use tests/chi2.h's family-wise significance.
 * Each test names the closed form it checks. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stdlib.h>
#include <unistd.h>

#include "chi2.h"
#include "integrators/effects.h"
#include "integrators/integrator.h"
#include "json/scene_json.h"
#include "load/scene_load.h"
#include "media/medium.h"

#define K_SIGMA 4.5

static ts_scene *load(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err)) fail_msg("%s\n%s", err.message, doc);
    return s;
}

static void load_fails(const char *doc, const char *expected)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err);
    if (st == TS_OK) {
        ts_scene_destroy(s);
        fail_msg("loaded, expected an error containing '%s'", expected);
    }
    if (!strstr(err.message, expected)) fail_msg("error '%s' lacks '%s'", err.message, expected);
}

typedef struct estimate {
    double mean[3], se[3];
    uint64_t nonfinite, truncated;
} estimate;

/* n independent samples of ts_integrator_li along the ray (o, d) with the scene's own
 * effects, integrator `type`. */
static estimate run(const ts_scene *s, ts_integrator_type type, ts_vec3 o, ts_vec3 d, uint32_t n)
{
    estimate e = {0};
    double sum[3] = {0}, sq[3] = {0};
    ts_counters c = {0};
    for (uint32_t i = 0; i < n; i++) {
        ts_sample_stream st;
        ts_sampler_begin(&s->sampler, 3, 5, i, &st);
        st.dim = 2;
        ts_ray ray = ts_ray_make(o, ts_vec3_normalize(d), INFINITY);
        ts_rgb L = ts_integrator_li(s, type, s->effects, &ray, NULL, &st, &c);
        const float v[3] = {L.r, L.g, L.b};
        if (!ts_rgb_is_finite(L) || L.r < 0 || L.g < 0 || L.b < 0) {
            e.nonfinite++;
            continue;
        }
        for (int k = 0; k < 3; k++) {
            sum[k] += v[k];
            sq[k] += (double)v[k] * v[k];
        }
    }
    for (int k = 0; k < 3; k++) {
        e.mean[k] = sum[k] / n;
        double var = sq[k] / n - e.mean[k] * e.mean[k];
        e.se[k] = sqrt(var > 0 ? var / (n - 1) : 0);
    }
    e.truncated = c.walks_truncated;
    return e;
}

/* |mean − exact| ≤ K_SIGMA·se (+ an absolute floor for zero-variance estimators). */
static void expect_close(const char *what, double mean, double se, double exact)
{
    double tol = K_SIGMA * se + 1e-6 * fabs(exact) + 1e-12;
    if (!(fabs(mean - exact) <= tol))
        fail_msg("%s: %.7g, expected %.7g (tolerance %.3g = %.1f × se %.3g)", what, mean, exact, tol, K_SIGMA, se);
}

/* ---------------------------------------------------------------- Henyey–Greenstein */

static const float hg_g[] = {-0.99f, -0.9f, -0.5f, -0.1f, 0, 0.0005f, 0.3f, 0.7f, 0.9f, 0.99f};
static const ts_vec3 hg_din = {0.3f, -0.5f, 0.8124038f};

typedef struct hg_ctx { float g; ts_vec3 d_in; } hg_ctx;

static ts_chi2_outcome hg_sample(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    const hg_ctx *h = ctx;
    ts_vec2 u = {ts_pcg32_float(rng), ts_pcg32_float(rng)};
    float pdf;
    *w = ts_hg_sample(h->d_in, h->g, u, &pdf);
    return TS_CHI2_DIRECTION;
}

static double hg_pdf(void *ctx, ts_vec3 w)
{
    const hg_ctx *h = ctx;
    return ts_hg_phase(ts_vec3_dot(h->d_in, w), h->g);
}

/* χ² of ts_hg_sample against ts_hg_phase, g from −0.99 to 0.99. */
static void test_hg_chi2(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof hg_g / sizeof *hg_g; i++) {
        hg_ctx h = {hg_g[i], ts_vec3_normalize(hg_din)};
        ts_chi2_params p;
        ts_chi2_params_default(&p);
        p.sample_count = 200000;
        p.seed = 7 + i;
        ts_chi2_result r;
        if (!ts_chi2_test(&p, hg_sample, hg_pdf, &h, &r)) fail_msg("g = %g: %s", h.g, r.message);
        if (fabs(r.pdf_integral - 1) > 1e-3) fail_msg("g = %g: ∫p = %.6f", h.g, r.pdf_integral);
    }
}

/* The sampler's pdf is the phase function at the direction drawn, and it is finite. */
static void test_hg_pdf_matches(void **state)
{
    (void)state;
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 4);
    ts_vec3 d = ts_vec3_normalize(hg_din);
    for (size_t i = 0; i < sizeof hg_g / sizeof *hg_g; i++)
        for (int k = 0; k < 1000; k++) {
            ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
            if (k == 0) u = (ts_vec2){0, 0};
            float pdf;
            ts_vec3 w = ts_hg_sample(d, hg_g[i], u, &pdf);
            float p = ts_hg_phase(ts_vec3_dot(d, w), hg_g[i]);
            assert_true(isfinite(pdf) && pdf > 0);
            assert_true(fabsf(ts_vec3_length(w) - 1) < 1e-5f);
            if (!(fabsf(pdf - p) <= 1e-6f * p)) fail_msg("g %g: pdf %g, phase %g", hg_g[i], pdf, p);
        }
}

/* ---------------------------------------------------------------- media directly */

#define HEAD                                                                                                      \
    "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0],\"fov\":30%s},\"film\":{\"width\":4,\"height\":4}," \
    "\"sampler\":{\"type\":\"independent\",\"seed\":%d},\"integrator\":{\"type\":\"%s\",\"max_depth\":%d},"

/* A scene of only the media of `media` (the inside of "media": {…}), volpath. */
static ts_scene *media_scene(const char *media)
{
    char doc[4096];
    snprintf(doc, sizeof doc, HEAD "\"media\":{%s}}", "", 1, "volpath", 5, media);
    return load(doc);
}

/* Beer–Lambert, exactly: ts_medium_tr of a homogeneous medium is exp(−σt·d) per channel,
 * 1 where σt is 0 whatever d (also ∞). */
static void test_homogeneous_tr(void **state)
{
    (void)state;
    ts_scene *s = media_scene("\"m\":{\"type\":\"homogeneous\",\"sigma_a\":[0.5,0,2],\"sigma_s\":[0.25,0,1]}");
    assert_int_equal(s->n_media, 1);
    const ts_medium *m = &s->media[0];
    ts_medium_walk w;
    ts_medium_walk_init(&w, 1, 0, 0, 0, NULL);
    ts_ray r = ts_ray_make((ts_vec3){1, 2, 3}, (ts_vec3){0, 2, 0}, INFINITY);
    ts_rgb t = ts_medium_tr(m, &r, 0.75f, &w); /* 1.5 units */
    assert_float_equal(t.r, expf(-0.75f * 1.5f), 1e-6);
    assert_float_equal(t.g, 1, 0);
    assert_float_equal(t.b, expf(-3 * 1.5f), 1e-6);
    t = ts_medium_tr(m, &r, INFINITY, &w);
    assert_float_equal(t.r, 0, 0);
    assert_float_equal(t.g, 1, 0);
    ts_scene_destroy(s);
}

/* Ratio tracking's mean and delta tracking's chance of passing along segments of the grid's
 * x axis (local y = z = 0.4) from x = −1 to each x_end, against exp(−τ), τ = σt ∫ density
 * by the midpoint rule over the interpolated density (piecewise linear along the ray;
 * 2·10^5 steps, error < 1e-7). */
static void tracking_case(const ts_medium *m, const ts_xform *xf, const double *x_end, int n_end)
{
    const ts_xform to_world = *xf;
    for (int k = 0; k < n_end; k++) {
        ts_dvec3 a = ts_xform_point(&to_world, (ts_dvec3){-1, 0.4, 0.4});
        ts_dvec3 b = ts_xform_point(&to_world, (ts_dvec3){x_end[k], 0.4, 0.4});
        ts_ray r = ts_ray_make((ts_vec3){(float)a.x, (float)a.y, (float)a.z},
                               (ts_vec3){(float)(b.x - a.x), (float)(b.y - a.y), (float)(b.z - a.z)}, 1);
        double len = ts_vec3_length(r.d), tau = 0;
        const int steps = 200000;
        for (int i = 0; i < steps; i++) {
            ts_vec3 p = ts_ray_at(&r, (float)((i + 0.5) / steps));
            tau += ts_medium_density(m, p);
        }
        tau *= 3.0 * len / steps;
        double exact = exp(-tau);
        ts_medium_walk w;
        ts_medium_walk_init(&w, 11, (uint32_t)k, 0, 0, NULL);
        const int n = 40000;
        double sum = 0, sq = 0, pass = 0;
        for (int i = 0; i < n; i++) {
            float t = ts_medium_tr(m, &r, 1, &w).r;
            sum += t;
            sq += (double)t * t;
            bool scattered;
            float th;
            ts_rgb f = ts_medium_sample(m, &r, 1, (ts_vec2){0, 0}, &w, &scattered, &th);
            if (!scattered) pass++, assert_float_equal(f.r, 1, 0);
            else assert_float_equal(f.g, 2.0f / 3.0f, 1e-6); /* σs/σt */
        }
        double mean = sum / n, se = sqrt((sq / n - mean * mean) / (n - 1));
        char what[64];
        snprintf(what, sizeof what, "ratio tracking to x = %g", x_end[k]);
        expect_close(what, mean, se, exact);
        snprintf(what, sizeof what, "delta tracking to x = %g", x_end[k]);
        expect_close(what, pass / n, sqrt(exact * (1 - exact) / n), exact);
        assert_int_equal(w.truncated, 0);
    }
}

/* A 4 × 1 × 1 grid of densities {0.5, 2, 0, 1} over [0,4]×[0,1]×[0,1], rotated and moved:
 * ratio tracking's mean and delta tracking's chance of passing equal exp(−τ), τ = σt ∫
 * density along the segment, integrated by the midpoint rule over the interpolated
 * density (piecewise linear along the ray; 2·10^5 steps, error < 1e-7). */
static void test_tracking(void **state)
{
    (void)state;
    ts_scene *s = media_scene("\"g\":{\"type\":\"grid\",\"sigma_a\":[1,1,1],\"sigma_s\":[2,2,2],\"nx\":4,\"ny\":1,"
                              "\"nz\":1,\"density\":[0.5,2,0,1],\"p0\":[0,0,0],\"p1\":[4,1,1],"
                              "\"transform\":[{\"rotate\":{\"angle\":30,\"axis\":[0,0,1]}},{\"translate\":[1,-2,0.5]}]}");
    const ts_medium *m = &s->media[0];
    assert_int_equal(m->type, TS_MEDIUM_GRID);
    assert_float_equal(m->max_density, 2, 0);
    /* Centre values and the half-cell ramp to 0 outside (pbrt-v3's lookup). */
    ts_xform rot = ts_xform_rotate(30, (ts_dvec3){0, 0, 1}), mv = ts_xform_translate((ts_dvec3){1, -2, 0.5});
    ts_xform to_world = ts_xform_compose(&mv, &rot);
    const double cx[] = {0.5, 1.5, 2.5, 3.5, 1.0, 0.25};
    const float dv[] = {0.5f, 2, 0, 1, 1.25f, 0.375f}; /* centres, between two, the ramp to 0 */
    for (int k = 0; k < 6; k++) {
        ts_dvec3 p = ts_xform_point(&to_world, (ts_dvec3){cx[k], 0.5, 0.5});
        assert_float_equal(ts_medium_density(m, (ts_vec3){(float)p.x, (float)p.y, (float)p.z}), dv[k], 1e-4);
    }
    /* Segments along the grid's x axis, from outside, ending inside. */
    const double x_end[] = {0.8, 1.7, 2.9, 5.0};
    tracking_case(m, &to_world, x_end, 4);
    ts_scene_destroy(s);
}

/* The majorant grid (media/medium.h): a 32 × 1 × 1 grid spans four of its cells along x,
 * with densities that jump at the cells' faces (0 | 1 | 0.2 | 3, eight samples each), so a
 * cell's bound must hold the interpolation's ramp into its neighbour's first sample (a
 * bound of the cell's own samples only is 0 in the first cell); the trackers against
 * exp(−τ) as above, over segments ending in each cell and past the grid. */
static void test_tracking_majorant_cells(void **state)
{
    (void)state;
    char media[1024], dens[512] = "";
    for (int i = 0; i < 32; i++) {
        const char *v[] = {"0", "1", "0.2", "3"};
        strcat(dens, v[i / 8]);
        if (i < 31) strcat(dens, ",");
    }
    snprintf(media, sizeof media,
             "\"g\":{\"type\":\"grid\",\"sigma_a\":[1,1,1],\"sigma_s\":[2,2,2],\"nx\":32,\"ny\":1,\"nz\":1,"
             "\"density\":[%s],\"p0\":[0,0,0],\"p1\":[4,1,1]}",
             dens);
    ts_scene *s = media_scene(media);
    const ts_medium *m = &s->media[0];
    assert_int_equal(m->mx, 4);
    assert_true(m->majorant[0] >= 1); /* the ramp into the second cell's first sample */
    ts_xform id = ts_xform_identity();
    const double x_end[] = {0.99, 1.05, 1.5, 2.2, 3.1, 5.0};
    tracking_case(m, &id, x_end, 6);
    ts_scene_destroy(s);
}

/* A walk is bounded: a majorant of 3e9 over a unit stops at the step bound, counted, and
 * the path carries nothing; a set stop flag ends it within 1024 steps. */
static void test_walk_bounded(void **state)
{
    (void)state;
    ts_scene *s = media_scene("\"g\":{\"type\":\"grid\",\"sigma_a\":[1e9,1e9,1e9],\"sigma_s\":[0,0,0],\"nx\":2,"
                              "\"ny\":1,\"nz\":1,\"density\":[1,3]}");
    const ts_medium *m = &s->media[0];
    ts_medium_walk w;
    ts_medium_walk_init(&w, 1, 0, 0, 0, NULL);
    ts_ray r = ts_ray_make((ts_vec3){-1, 0.5f, 0.5f}, (ts_vec3){1.4f, 0, 0}, 1);
    ts_rgb t = ts_medium_tr(m, &r, 1, &w);
    assert_float_equal(t.r, 0, 0);
    assert_int_equal(w.truncated, 1);
    assert_true(w.steps == TS_MEDIUM_MAX_STEPS);
    /* σs = 0: delta tracking's collisions are all absorptions; a cut walk carries 0 too. */
    atomic_bool stop = true;
    ts_medium_walk_init(&w, 1, 0, 0, 0, &stop);
    bool scattered;
    float th;
    ts_rgb f = ts_medium_sample(m, &r, 1, (ts_vec2){0, 0}, &w, &scattered, &th);
    assert_true(ts_rgb_is_finite(f));
    assert_true(w.steps <= 1024);
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- volpath, closed forms */

/* A sphere of radius 1 at the origin bounding medium "m" (no surface), a black emitter of
 * radiance 1 behind it facing the camera; rays through the centre cross 2 units. */
#define ABSORBER_SCENE                                                                                         \
    "\"materials\":{\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},"                                     \
    "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":null,\"medium\":{\"inside\":\"m\"}},"         \
    "{\"type\":\"disk\",\"center\":[0,0,-3],\"normal\":[0,0,1],\"radius\":50,\"material\":\"black\",\"emission\":1}]}"

/* Beer–Lambert through the sphere: volpath's mean is exp(−σt·2) per channel (σs = 0:
 * each sample is 0 or 1 in a grey medium); `path` ignores the medium as pbrt-v3 does and
 * sees the emitter through the surface-less sphere: exactly 1. */
static void test_beer_lambert(void **state)
{
    (void)state;
    char doc[4096];
    snprintf(doc, sizeof doc,
             HEAD "\"media\":{\"m\":{\"type\":\"homogeneous\",\"sigma_a\":[0.3,0.65,1.5],\"sigma_s\":[0,0,0]}}," ABSORBER_SCENE,
             "", 2, "volpath", 5);
    ts_scene *s = load(doc);
    assert_true(s->effects & TS_EFFECT_MEDIA);
    estimate e = run(s, TS_INTEGRATOR_VOLPATH, (ts_vec3){0, 0, 5}, (ts_vec3){0, 0, -1}, 40000);
    assert_int_equal(e.nonfinite, 0);
    const double sig[3] = {0.3, 0.65, 1.5};
    for (int k = 0; k < 3; k++) expect_close("Beer–Lambert", e.mean[k], e.se[k], exp(-2 * sig[k]));
    e = run(s, TS_INTEGRATOR_PATH, (ts_vec3){0, 0, 5}, (ts_vec3){0, 0, -1}, 100);
    for (int k = 0; k < 3; k++) assert_float_equal(e.mean[k], 1, 1e-6);
    ts_scene_destroy(s);
}

/* An all-zero grid transmits everything: exactly 1, every sample. */
static void test_zero_grid(void **state)
{
    (void)state;
    char doc[4096];
    snprintf(doc, sizeof doc,
             HEAD "\"media\":{\"m\":{\"type\":\"grid\",\"sigma_a\":[1,1,1],\"sigma_s\":[1,1,1],\"nx\":2,\"ny\":2,"
                  "\"nz\":2,\"density\":[0,0,0,0,0,0,0,0],\"p0\":[-1,-1,-1],\"p1\":[1,1,1]}}," ABSORBER_SCENE,
             "", 2, "volpath", 5);
    ts_scene *s = load(doc);
    estimate e = run(s, TS_INTEGRATOR_VOLPATH, (ts_vec3){0, 0, 5}, (ts_vec3){0.01f, 0, -1}, 200);
    for (int k = 0; k < 3; k++) assert_float_equal(e.mean[k], 1, 1e-6);
    assert_float_equal(e.se[0], 0, 1e-9);
    ts_scene_destroy(s);
}

/* The slab 0 ≤ z ≤ h between two surface-less disks (radius 1000), lit by a distant light
 * of irradiance E from the direction at angle α from +z, seen from above along −z with
 * max_depth 1 (single scattering): L = σs E p(−cos α) (1 − e^{−σt h k}) / (σt k),
 * k = 1 + 1/cos α. */
static double single_scatter(double ss, double st, double h, double g, double alpha, double E)
{
    double k = 1 + 1 / cos(alpha);
    return ss * E * ts_hg_phase((float)-cos(alpha), (float)g) * -expm1(-st * h * k) / (st * k);
}

static void slab_case(const char *medium_json, double ss, double st, double h, double g, uint32_t n)
{
    const double alpha = 30 * M_PI / 180, E = 2;
    char doc[4096];
    snprintf(doc, sizeof doc,
             HEAD "\"media\":{\"m\":%s},\"materials\":{},"
                  "\"shapes\":[{\"type\":\"disk\",\"center\":[0,0,%.9g],\"normal\":[0,0,1],\"radius\":1000,"
                  "\"material\":null,\"medium\":{\"inside\":\"m\",\"outside\":null}},"
                  "{\"type\":\"disk\",\"center\":[0,0,0],\"normal\":[0,0,-1],\"radius\":1000,\"material\":null,"
                  "\"medium\":{\"inside\":\"m\"}}],"
                  "\"lights\":[{\"type\":\"distant\",\"from\":[0,%.9g,%.9g],\"to\":[0,0,0],\"irradiance\":%g}]}",
             "", 5, "volpath", 1, medium_json, h, sin(alpha), cos(alpha), E);
    ts_scene *s = load(doc);
    estimate e = run(s, TS_INTEGRATOR_VOLPATH, (ts_vec3){0.3f, -0.2f, 5}, (ts_vec3){0, 0, -1}, n);
    assert_int_equal(e.nonfinite, 0);
    double exact = single_scatter(ss, st, h, g, alpha, E);
    char what[128];
    snprintf(what, sizeof what, "single scattering, σs %g σt %g h %g g %g", ss, st, h, g);
    for (int k = 0; k < 3; k++) expect_close(what, e.mean[k], e.se[k], exact);
    ts_scene_destroy(s);
}

static void test_single_scattering(void **state)
{
    (void)state;
    slab_case("{\"type\":\"homogeneous\",\"sigma_a\":[0.4,0.4,0.4],\"sigma_s\":[0.8,0.8,0.8],\"g\":0.3}", 0.8, 1.2,
              1, 0.3, 40000);
    slab_case("{\"type\":\"homogeneous\",\"sigma_a\":[0.1,0.1,0.1],\"sigma_s\":[2,2,2],\"g\":-0.6}", 2, 2.1, 0.5,
              -0.6, 40000);
    /* Hard cases: σt = 1e6 in a slab 1e-3 thick (optical depth 1000), and σt → 0. */
    slab_case("{\"type\":\"homogeneous\",\"sigma_a\":[5e5,5e5,5e5],\"sigma_s\":[5e5,5e5,5e5],\"g\":0.99}", 5e5, 1e6,
              1e-3, 0.99, 20000);
    slab_case("{\"type\":\"homogeneous\",\"sigma_a\":[0,0,0],\"sigma_s\":[1e-30,1e-30,1e-30],\"g\":-0.99}", 1e-30,
              1e-30, 1, -0.99, 2000);
}

/* A grid of constant density 1 (3 cells an axis over a box that holds the slab between
 * the first and last cell centres, where trilinear interpolation is exactly 1) with the
 * homogeneous medium's σ: the same closed form, by delta and ratio tracking; also the hard
 * cases of test_single_scattering in a grid. */
static void test_constant_grid(void **state)
{
    (void)state;
    char m[1024];
    snprintf(m, sizeof m,
             "{\"type\":\"grid\",\"sigma_a\":[0.4,0.4,0.4],\"sigma_s\":[0.8,0.8,0.8],\"g\":0.3,\"nx\":3,\"ny\":3,"
             "\"nz\":3,\"p0\":[-2000,-2000,-1],\"p1\":[2000,2000,2],\"density\":[%s]}",
             "1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1");
    slab_case(m, 0.8, 1.2, 1, 0.3, 40000);
    /* The hard cases through the trackers: σt = 1e6 in a slab 1e-3 thick (optical depth
     * 1000, g 0.99), and σt = 2e-30 (g −0.99), the box made to hold the slab likewise. */
    const char *ones = "1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1";
    snprintf(m, sizeof m,
             "{\"type\":\"grid\",\"sigma_a\":[5e5,5e5,5e5],\"sigma_s\":[5e5,5e5,5e5],\"g\":0.99,\"nx\":3,"
             "\"ny\":3,\"nz\":3,\"p0\":[-2000,-2000,-1e-3],\"p1\":[2000,2000,2e-3],\"density\":[%s]}",
             ones);
    slab_case(m, 5e5, 1e6, 1e-3, 0.99, 20000);
    snprintf(m, sizeof m,
             "{\"type\":\"grid\",\"sigma_a\":[1e-30,1e-30,1e-30],\"sigma_s\":[1e-30,1e-30,1e-30],\"g\":-0.99,"
             "\"nx\":3,\"ny\":3,\"nz\":3,\"p0\":[-2000,-2000,-1],\"p1\":[2000,2000,2],\"density\":[%s]}",
             ones);
    slab_case(m, 1e-30, 2e-30, 1, -0.99, 2000);
}

/* Furnaces: albedo-1 media under a uniform environment of radiance 1 with no surface:
 * every path escapes, so L = 1 for any ray, with any phase function; β stays 1 (no
 * roulette), max_depth 10000 is never reached (optical radius ≤ 4). Also with the camera
 * inside the medium, and nested media (a sphere of one inside a sphere of another). */
#define FURNACE_LIGHT "\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}"

static void furnace_case(const char *camera, const char *media, const char *shapes, ts_vec3 o, uint32_t n)
{
    char doc[4096];
    snprintf(doc, sizeof doc, HEAD "\"media\":{%s},\"materials\":{},\"shapes\":[%s]," FURNACE_LIGHT, camera, 9,
             "volpath", 10000, media, shapes);
    ts_scene *s = load(doc);
    estimate e = run(s, TS_INTEGRATOR_VOLPATH, o, (ts_vec3){0.1f, 0.05f, -1}, n);
    assert_int_equal(e.nonfinite, 0);
    assert_int_equal(e.truncated, 0);
    for (int k = 0; k < 3; k++) expect_close(media, e.mean[k], e.se[k], 1);
    ts_scene_destroy(s);
}

#define SPHERE(r, in, out)                                                                                      \
    "{\"type\":\"sphere\",\"radius\":" r ",\"material\":null,\"medium\":{\"inside\":" in ",\"outside\":" out "}}"

static void test_furnace(void **state)
{
    (void)state;
    const char *gs[] = {"0", "0.9", "-0.9", "0.99", "-0.99"};
    for (int i = 0; i < 5; i++) {
        char media[256];
        snprintf(media, sizeof media, "\"a\":{\"type\":\"homogeneous\",\"sigma_a\":[0,0,0],\"sigma_s\":[3,3,3],\"g\":%s}",
                 gs[i]);
        furnace_case("", media, SPHERE("1", "\"a\"", "null"), (ts_vec3){0, 0, 5}, 20000);
    }
    /* A grid of varying density (albedo 1). */
    furnace_case("",
                 "\"a\":{\"type\":\"grid\",\"sigma_a\":[0,0,0],\"sigma_s\":[4,4,4],\"g\":0.5,\"nx\":2,\"ny\":2,\"nz\":2,"
                 "\"density\":[0,1,0.5,1,1,0.2,0,1],\"p0\":[-1,-1,-1],\"p1\":[1,1,1]}",
                 SPHERE("1", "\"a\"", "null"), (ts_vec3){0, 0, 5}, 20000);
    /* The camera inside the medium. */
    furnace_case(",\"medium\":\"a\"",
                 "\"a\":{\"type\":\"homogeneous\",\"sigma_a\":[0,0,0],\"sigma_s\":[2,2,2],\"g\":0.7}",
                 SPHERE("1", "\"a\"", "null"), (ts_vec3){0.2f, 0, 0.1f}, 20000);
    /* Nested media. */
    furnace_case("",
                 "\"a\":{\"type\":\"homogeneous\",\"sigma_a\":[0,0,0],\"sigma_s\":[4,4,4],\"g\":0.5},"
                 "\"b\":{\"type\":\"homogeneous\",\"sigma_a\":[0,0,0],\"sigma_s\":[1,1,1],\"g\":-0.3}",
                 SPHERE("1", "\"a\"", "\"b\"") "," SPHERE("2", "\"b\"", "null"), (ts_vec3){0, 0, 5}, 20000);
}

/* ---------------------------------------------------------------- other integrators */

/* A surface-less dome (radius 10, no medium) over a diffuse floor disk, under a uniform
 * environment of radiance 1, seen from outside. pbrt-v3's integrators other than volpath
 * skip a hit without a BSDF and go on along the ray, while its shadow rays (Unoccluded,
 * IntersectP) and its BSDF-sampled light rays (Intersect) stop at the dome: so the floor
 * receives nothing, by either strategy — exactly 0 for path, direct and ao — while a
 * camera ray that escapes through the dome sees the environment, exactly 1; normals shows
 * the floor's. Also the load-time warning of each (ts_integrator_media_warning, and through
 * ts_scene_load_path's warning callback). */
#define DOME_SCENE                                                                                              \
    "\"materials\":{\"grey\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"                                    \
    "\"shapes\":[{\"type\":\"sphere\",\"radius\":10,\"material\":null},"                                      \
    "{\"type\":\"disk\",\"center\":[0,0,0],\"normal\":[0,0,1],\"radius\":5,\"material\":\"grey\"}],"          \
    "\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}"

static void warned(void *ctx, const char *msg) { snprintf(ctx, 1024, "%s", msg); }

static void test_surface_less_other_integrators(void **state)
{
    (void)state;
    const char *names[] = {"path", "direct", "ao", "normals"};
    const ts_integrator_type types[] = {TS_INTEGRATOR_PATH, TS_INTEGRATOR_DIRECT, TS_INTEGRATOR_AO,
                                        TS_INTEGRATOR_NORMALS};
    const ts_vec3 o = {20, 0, 3}, to_floor = {-18, 0, -3}, escape = {-1, 0, 0.05f};
    for (int i = 0; i < 4; i++) {
        char doc[4096];
        snprintf(doc, sizeof doc, HEAD DOME_SCENE, "", 3, names[i], 5);
        if (i >= 2) { /* ao and normals take no max_depth */
            char *md = strstr(doc, ",\"max_depth\":5");
            memmove(md, md + strlen(",\"max_depth\":5"), strlen(md + strlen(",\"max_depth\":5")) + 1);
        }
        ts_scene *s = load(doc);
        assert_true(s->effects & TS_EFFECT_MEDIA);
        estimate e = run(s, types[i], o, to_floor, 2000);
        assert_int_equal(e.nonfinite, 0);
        const float floor_value[3] = {types[i] == TS_INTEGRATOR_NORMALS ? 0.5f : 0,
                                      types[i] == TS_INTEGRATOR_NORMALS ? 0.5f : 0,
                                      types[i] == TS_INTEGRATOR_NORMALS ? 1.0f : 0};
        for (int k = 0; k < 3; k++)
            if (fabs(e.mean[k] - floor_value[k]) > 1e-6)
                fail_msg("%s: the floor under the dome is %g in channel %d, expected %g", names[i], e.mean[k], k,
                         floor_value[k]);
        if (types[i] == TS_INTEGRATOR_PATH || types[i] == TS_INTEGRATOR_DIRECT) {
            e = run(s, types[i], o, escape, 100);
            for (int k = 0; k < 3; k++) assert_float_equal(e.mean[k], 1, 1e-6);
        }
        char msg[600];
        assert_true(ts_integrator_media_warning(s, msg, sizeof msg));
        char want[64];
        snprintf(want, sizeof want, "integrator.type: \"%s\" ", names[i]);
        if (strncmp(msg, want, strlen(want)) != 0) fail_msg("warning: %s", msg);
        if (i == 0) { /* the CLI's loader says it at load time, with the file */
            char path[] = "/tmp/tessera-media-XXXXXX.json";
            int fd = mkstemps(path, 5);
            assert_true(fd >= 0);
            assert_true(write(fd, doc, strlen(doc)) == (ssize_t)strlen(doc));
            close(fd);
            char got[1024] = "";
            ts_scene *t = NULL;
            ts_error err = {0};
            if (ts_scene_load_path(path, NULL, warned, got, &t, &err)) fail_msg("%s", err.message);
            unlink(path);
            ts_scene_destroy(t);
            if (!strstr(got, path) || !strstr(got, msg)) fail_msg("load-time warning: '%s'", got);
        }
        ts_scene_destroy(s);
    }
    /* volpath: no warning. */
    char doc[4096];
    snprintf(doc, sizeof doc, HEAD DOME_SCENE, "", 3, "volpath", 5);
    ts_scene *s = load(doc);
    char msg[600];
    assert_false(ts_integrator_media_warning(s, msg, sizeof msg));
    ts_scene_destroy(s);
}

/* ---------------------------------------------------------------- input */

static void test_presets(void **state)
{
    (void)state;
    ts_scene *s = media_scene("\"k\":{\"type\":\"homogeneous\",\"preset\":\"Ketchup\",\"scale\":2},"
                              "\"d\":{\"type\":\"homogeneous\"},\"o\":{\"type\":\"homogeneous\",\"preset\":\"Skin1\","
                              "\"sigma_s\":[1,2,3]}");
    assert_float_equal(s->media[0].sigma_s.r, 0.36f, 1e-6); /* Ketchup σ′s 0.18 × 2 */
    assert_float_equal(s->media[0].sigma_a.b, 2.9f, 1e-6);  /* σa 1.45 × 2 */
    assert_float_equal(s->media[1].sigma_s.g, 3.21f, 1e-6); /* pbrt-v3's default: whole milk */
    assert_float_equal(s->media[1].sigma_a.r, 0.0011f, 1e-7);
    assert_float_equal(s->media[2].sigma_s.b, 3, 0);       /* given σs over the preset's */
    assert_float_equal(s->media[2].sigma_a.g, 0.17f, 1e-6); /* the preset's σa */
    /* No scattering anywhere a ray goes: media absent from the effects (nothing refers to them). */
    assert_false(s->effects & TS_EFFECT_MEDIA);
    ts_scene_destroy(s);
    for (uint32_t i = 0; ts_medium_preset_name(i); i++) {
        ts_rgb a, b;
        assert_true(ts_medium_preset(ts_medium_preset_name(i), &a, &b));
    }
}

static void test_bad_input(void **state)
{
    (void)state;
    char doc[2048];
    struct { const char *media, *camera, *shapes, *expected; } cases[] = {
        {"\"s\":{\"type\":\"grid\",\"nx\":2,\"ny\":2,\"nz\":2,\"density\":[1,1,1,1,1,1,1]}", "", "",
         "media.s: density: 7 values, expected nx·ny·nz = 2·2·2 = 8"},
        {"\"f\":{\"type\":\"homogeneous\",\"sigma_a\":[1,-1,1]}", "", "", "media.f: sigma_a:"},
        {"\"f\":{\"type\":\"homogeneous\",\"sigma_s\":[1,1,1],\"scale\":-1}", "", "", "media.f: scale:"},
        {"\"f\":{\"type\":\"homogeneous\",\"preset\":\"Jam\"}", "", "", "media.f: preset: unknown medium preset \"Jam\""},
        {"\"f\":{\"type\":\"homogeneous\",\"g\":1}", "", "", "media.f: g:"},
        {"\"s\":{\"type\":\"grid\",\"sigma_a\":[1,1,1],\"sigma_s\":[1,1,1],\"nx\":1,\"ny\":1,\"nz\":1,\"density\":[-1]}", "", "",
         "media.s: density[0]:"},
        {"\"s\":{\"type\":\"grid\",\"sigma_a\":[1,2,3],\"nx\":1,\"ny\":1,\"nz\":1,\"density\":[1]}", "", "",
         "media.s: sigma_a, sigma_s: a grid's σa + σs must be the same in every channel"},
        {"\"s\":{\"type\":\"grid\",\"nx\":1,\"ny\":1,\"nz\":1,\"density\":[1],\"p0\":[0,0,1],\"p1\":[1,1,1]}", "", "",
         "media.s: p0, p1:"},
        {"\"s\":{\"type\":\"grid\",\"sigma_a\":[1e30,1e30,1e30],\"sigma_s\":[0,0,0],\"nx\":1,\"ny\":1,\"nz\":1,"
         "\"density\":[1e30]}", "", "", "media.s: density: σa + σs (1e+30) times the largest density (1e+30) is beyond"},
        {"\"f\":{\"type\":\"homogeneous\"}", ",\"medium\":\"fog\"", "", "camera.medium: no medium named \"fog\""},
        {"\"f\":{\"type\":\"homogeneous\"}", "",
         "{\"type\":\"sphere\",\"radius\":1,\"material\":null,\"medium\":{\"inside\":\"smoke\"}}",
         "shapes[0].medium.inside: no medium named \"smoke\""},
        {"\"f\":{\"type\":\"homogeneous\"}", "",
         "{\"type\":\"sphere\",\"radius\":1,\"material\":null,\"emission\":1}",
         "shapes[0]: emission: a shape without a surface"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        snprintf(doc, sizeof doc, HEAD "\"media\":{%s},\"shapes\":[%s]}", cases[i].camera, 1, "volpath", 5,
                 cases[i].media, cases[i].shapes);
        load_fails(doc, cases[i].expected);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hg_chi2),       cmocka_unit_test(test_hg_pdf_matches),
        cmocka_unit_test(test_homogeneous_tr), cmocka_unit_test(test_tracking),
        cmocka_unit_test(test_tracking_majorant_cells),
        cmocka_unit_test(test_walk_bounded),  cmocka_unit_test(test_beer_lambert),
        cmocka_unit_test(test_zero_grid),     cmocka_unit_test(test_single_scattering),
        cmocka_unit_test(test_constant_grid), cmocka_unit_test(test_furnace),
        cmocka_unit_test(test_presets),       cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_surface_less_other_integrators),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
