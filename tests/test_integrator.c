/* test_integrator.c — the `path` and `direct` integrators against closed-form answers
 * (pbrt-v3 §14.4.2 and friends). Each case renders a tiny film and compares the mean over
 * its pixels with the analytic value.
 *
 * Several cases have zero-variance estimators, which makes their tolerances tight:
 * inside a uniformly emitting sphere of radius R the light-sampling estimate of the
 * reflected radiance is (ρ/π)·Le·cosθi·cosθl/r²·A = (ρ/π)·Le·π = ρ·Le for every sampled
 * point (cosθi = cosθl = r/2R on a sphere), and cosine-weighted BSDF sampling gives ρ·Le
 * too, so MIS of the two is exact at every vertex; a point light at the centre of a sphere
 * likewise gives (ρ/π)·I/R² at every point. Those renders must match to float rounding
 * (relative 1e-4 covers the float sums of up to ~1000 terms). Cases with variance are
 * K = 16 renders with 16 different seeds (render_stats.h): their standard error comes
 * from the spread of the 16 image means — not from one render's per-pixel variance, which
 * overstates a Sobol render's error many times over — and each must be within its
 * Student-t bound (15 dof) at the significance written beside it, and within the 1% of
 * docs/design.md §8 where it applies. The strategy comparisons are in
 * test_integrator_strategies.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "materials/fresnel.h"
#include "render/render.h"
#include "render_stats.h"
#include "json/scene_json.h"

typedef struct result { double mean, se; uint64_t nonfinite; int k; } result;

/* One render at the scene's own seed: for the zero-variance cases (se 0). */
static result render_doc(const char *doc, int spp)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text(doc, strlen(doc), NULL, "test", NULL, &s, &err);
    if (st) fail_msg("scene: %s\n%s", err.message, doc);
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    assert_non_null(f);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, (uint32_t)spp, 2, NULL, NULL, NULL};
    assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
    result r = {0, 0, stats.counters.nonfinite, 1};
    int n = s->width * s->height;
    for (int y = 0; y < s->height; y++)
        for (int x = 0; x < s->width; x++) r.mean += ts_film_pixel_rgb(f, x, y).g / n;
    ts_film_destroy(f);
    ts_scene_destroy(s);
    return r;
}

/* K = 16 renders of spp/16 samples each, seeds seed0.. (independent scrambles): the mean
 * of their image means and its standard error from their spread (grey scenes: the channel
 * average is the green channel's value). */
enum { K_RENDERS = 16 };
static result render_k(const char *doc, int spp, uint32_t seed0)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "test", NULL, &s, &err)) fail_msg("scene: %s\n%s", err.message, doc);
    ts_rs_blocks b;
    ts_rs_render(s, s->sampler.type, seed0, K_RENDERS, spp / K_RENDERS, 4, &b);
    ts_scene_destroy(s);
    return (result){b.image_mean, b.image_se, b.nonfinite, K_RENDERS};
}

/* Passes when the mean is within rel_tol of expected (float rounding of a zero-variance
 * case) or, for k > 1 renders, when Student's t of (mean − expected)/se on k − 1 degrees
 * of freedom has a two-sided p ≥ alpha — alpha is then the check's false-failure rate. */
static void check(const char *what, result r, double expected, double rel_tol, double alpha)
{
    double d = r.mean - expected, t = r.se > 0 ? d / r.se : 0;
    double p = r.k > 1 && r.se > 0 ? ts_rs_student_two_sided(t, r.k - 1) : 0;
    bool ok = fabs(d) <= rel_tol * fabs(expected) || (r.k > 1 && p >= alpha);
    print_message("%-48s %.6f expected %.6f (se %.2e from %d renders, t %+.2f, p %.2g)\n", what, r.mean, expected,
                  r.se, r.k, t, p);
    if (r.nonfinite) fail_msg("%s: %llu non-finite samples", what, (unsigned long long)r.nonfinite);
    if (!ok) fail_msg("%s: %.7f, expected %.7f (t %.2f, p %.2g < %.2g)", what, r.mean, expected, t, p, alpha);
}

/* A camera at the centre of a closed, two-sided emitting diffuse sphere. */
static void emitting_sphere_doc(char *buf, size_t n, double rho, double le, const char *integrator, int size)
{
    snprintf(buf, n,
             "{\"tessera\":1,\"camera\":{\"from\":[0,0,0],\"to\":[0,0,-1],\"fov\":60},"
             "\"film\":{\"width\":%d,\"height\":%d,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"seed\":3},"
             "\"integrator\":%s,\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":%.17g}},"
             "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\",\"emission\":%.17g,\"two_sided\":true}]}",
             size, size, integrator, rho, le);
}

static void test_emitting_sphere_fixed_depth(void **state)
{
    (void)state;
    char doc[2048], integ[256], what[128];
    const double le = 0.75;
    double rhos[] = {0.5, 0.9, 0.99};
    for (int k = 0; k < 3; k++) {
        double rho = rhos[k];
        /* direct: emission plus one bounce of direct light, Le (1 + ρ). */
        emitting_sphere_doc(doc, sizeof doc, rho, le, "{\"type\":\"direct\",\"strategy\":\"all\"}", 8);
        snprintf(what, sizeof what, "direct, rho %.2f", rho);
        check(what, render_doc(doc, 4), le * (1 + rho), 1e-4, 0);
        emitting_sphere_doc(doc, sizeof doc, rho, le, "{\"type\":\"direct\",\"strategy\":\"one\"}", 8);
        snprintf(what, sizeof what, "direct one, rho %.2f", rho);
        check(what, render_doc(doc, 4), le * (1 + rho), 1e-4, 0);
        /* path, max_depth D, no roulette: Le Σ_{i=0..D} ρ^i. */
        int depths[] = {0, 1, 2, 5, 20};
        for (int d = 0; d < 5; d++) {
            snprintf(integ, sizeof integ, "{\"type\":\"path\",\"max_depth\":%d,\"rr_depth\":1000}", depths[d]);
            emitting_sphere_doc(doc, sizeof doc, rho, le, integ, 8);
            double sum = 0, p = 1;
            for (int i = 0; i <= depths[d]; i++, p *= rho) sum += p;
            snprintf(what, sizeof what, "path depth %d, rho %.2f", depths[d], rho);
            check(what, render_doc(doc, 4), le * sum, 1e-4, 0);
        }
    }
}

static void test_emitting_sphere_roulette(void **state)
{
    (void)state;
    /* path to (practically) infinite depth with roulette after 3 bounces: Le/(1−ρ) within
     * 1% (docs/design.md §8) and within Student's t at p ≥ 1e-4 (a false failure per case
     * 1e-4, so 3e-4 for the three). Each vertex's estimate is exact, so all variance
     * comes from the roulette's random path length: its relative standard deviation per
     * sample is about 1 at ρ = 0.99 (a geometric length with mean 100), so 16×16 pixels ×
     * 512 spp give se ≈ 0.28% before stratification — 1% is then 3.5 se; the spread of the
     * 16 renders measures what Sobol's stratification of the roulette leaves. */
    char doc[2048];
    const double le = 0.75;
    struct { double rho; int spp; } cases[] = {{0.5, 16}, {0.9, 64}, {0.99, 512}};
    for (int k = 0; k < 3; k++) {
        emitting_sphere_doc(doc, sizeof doc, cases[k].rho, le,
                            "{\"type\":\"path\",\"max_depth\":60000,\"rr_depth\":3}", 16);
        char what[64];
        snprintf(what, sizeof what, "path roulette, rho %.2f", cases[k].rho);
        result r = render_k(doc, cases[k].spp, 40 + 20 * (uint32_t)k);
        double expected = le / (1 - cases[k].rho);
        check(what, r, expected, 0, 1e-4);
        if (!(fabs(r.mean - expected) < 0.01 * expected)) fail_msg("%s: not within 1%%", what);
    }
}

static void test_point_light_in_sphere(void **state)
{
    (void)state;
    /* A point light of intensity π at the centre of a diffuse sphere of albedo 1/2 and
     * radius 1, camera beside it: direct 1/2; path with max_depth D and no roulette
     * Σ_{k=1..D} 2^-k = 1 − 2^-D. */
    const char *fmt = "{\"tessera\":1,\"camera\":{\"from\":[0,0,0.01],\"to\":[0,0,-1],\"fov\":60},"
                      "\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\"}},"
                      "\"integrator\":%s,\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
                      "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}],"
                      "\"lights\":[{\"type\":\"point\",\"position\":[0,0,0],\"intensity\":3.14159265358979}]}";
    char doc[2048], integ[256], what[64];
    snprintf(doc, sizeof doc, fmt, "{\"type\":\"direct\"}");
    check("point light, direct", render_doc(doc, 4), 0.5, 1e-4, 0);
    int depths[] = {1, 2, 3, 8};
    for (int d = 0; d < 4; d++) {
        snprintf(integ, sizeof integ, "{\"type\":\"path\",\"max_depth\":%d,\"rr_depth\":1000}", depths[d]);
        snprintf(doc, sizeof doc, fmt, integ);
        snprintf(what, sizeof what, "point light, path depth %d", depths[d]);
        /* Indirect bounces are estimated (cosine-sampled points see the light at their own
         * distance 1 from it): still exact, since every point of the sphere is lit alike. */
        check(what, render_doc(doc, 4), 1 - ldexp(1, -depths[d]), 1e-4, 0);
    }
}


/* Hard case 4: a sphere light of radius r and radiance L whose centre is at distance D
 * from a point of a diffuse plane of albedo ρ, at angle θ from its normal: the reflected
 * radiance there is ρ·L·(r/D)²·cosθ (irradiance πL(r/D)²cosθ from a sphere entirely
 * above the horizon). The light sits at (1.5, 2, 0)·scale so that D = 2.5, cosθ = 0.8 at
 * the origin and the camera above the origin does not see it. An
 * orthographic camera looks at a tiny patch around that point; the irradiance varies over
 * the patch by at most 1.5·(x/d)² ≈ 1e-4 relative for the patches below. Tolerance: the
 * 1% of docs/design.md §8 and Student's t at p ≥ 1e-4 per case (6e-4 for the six; cone
 * sampling of the light varies only with cosθ). */
static void sphere_over_plane(char *doc, size_t n, double scale, double shift, double r, double L, double view_deg,
                              double patch)
{
    double d = 2 * scale, dx = 1.5 * scale, c = shift;
    double th = view_deg * 3.14159265358979323846 / 180, dist = 3 * scale;
    snprintf(doc, n,
             "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[%.17g,%.17g,%.17g],\"to\":[%.17g,%.17g,%.17g],\"up\":[0,0,1],"
             "\"height\":%.17g},\"film\":{\"width\":4,\"height\":4,\"filter\":{\"type\":\"box\"}},"
             "\"integrator\":{\"type\":\"path\",\"max_depth\":1},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":0.5},"
             "\"black\":{\"type\":\"diffuse\",\"reflectance\":0}},\"shapes\":[{\"type\":\"disk\",\"center\":[%.17g,%.17g,%.17g],"
             "\"normal\":[0,1,0],\"radius\":%.17g,\"material\":\"m\"},{\"type\":\"sphere\",\"center\":[%.17g,%.17g,%.17g],"
             "\"radius\":%.17g,\"material\":\"black\",\"emission\":%.17g}]}",
             c - dist * sin(th), c + dist * cos(th), c, c, c, c, patch * scale, c, c, c, 10 * scale, c + dx, c + d, c,
             r * scale, L);
}

static void test_sphere_light_over_plane(void **state)
{
    (void)state;
    char doc[4096], what[96];
    struct { const char *name; double scale, shift, r, L, view, patch; int spp; } cases[] = {
        {"at the origin", 1, 0, 0.5, 32, 0, 1e-3, 64},
        {"translated by 1e5", 1, 1e5, 0.5, 32, 0, 2e-2, 64},
        {"scaled by 1e-3", 1e-3, 0, 0.5, 32, 0, 1e-3, 64},
        {"scaled by 1e3", 1e3, 0, 0.5, 32, 0, 1e-3, 64},
        {"light radius 1e-3, radiance 9e6", 1, 0, 1e-3, 9e6, 0, 1e-3, 64},
        {"viewed at 89.9 degrees", 1, 0, 0.5, 32, 89.9, 1e-6, 64},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        sphere_over_plane(doc, sizeof doc, cases[i].scale, cases[i].shift, cases[i].r, cases[i].L, cases[i].view,
                          cases[i].patch);
        double expected = 0.5 * cases[i].L * (cases[i].r / 2.5) * (cases[i].r / 2.5) * 0.8;
        snprintf(what, sizeof what, "sphere light over a plane, %s", cases[i].name);
        result res = render_k(doc, cases[i].spp, 60 + 20 * (uint32_t)i);
        check(what, res, expected, 0, 1e-4);
        if (!(fabs(res.mean - expected) < 0.01 * expected)) fail_msg("%s: not within 1%%", what);
    }
}

/* Hard case 3: white furnace. Under a constant environment of radiance 1, a sphere of an
 * energy-conserving material (Lambertian with albedo 1, a perfect mirror, smooth glass
 * with unit reflectance and transmittance) is invisible: every pixel is 1. A camera
 * inside a smooth glass sphere (η = 1.5) sees η² = 2.25: radiance inside a denser medium
 * is higher by η², and the 4% reflected at normal incidence returns the same value
 * (L = T·η²/(1 − R) = η²). Tolerance: the 1% of docs/design.md §8 and Student's t at p ≥ 1e-4 per
 * case, with a 1e-5 floor for the float rounding of the noiseless specular cases. */
static void test_white_furnace(void **state)
{
    (void)state;
    const char *fmt = "{\"tessera\":1,\"camera\":{\"from\":%s,\"to\":[0,0,0],\"fov\":%s},"
                      "\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"seed\":5},"
                      "\"integrator\":{\"type\":\"path\",\"max_depth\":200,\"rr_depth\":20},"
                      "\"materials\":{\"m\":%s},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}],"
                      "\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}";
    struct { const char *name, *material, *from, *fov; double expected; int spp; } cases[] = {
        {"furnace: Lambertian, albedo 1", "{\"type\":\"diffuse\",\"reflectance\":1}", "[0,0,4]", "20", 1, 256},
        {"furnace: mirror", "{\"type\":\"mirror\",\"reflectance\":1}", "[0,0,4]", "20", 1, 16},
        {"furnace: smooth glass", "{\"type\":\"dielectric\",\"eta\":1.5}", "[0,0,4]", "20", 1, 64},
        {"camera inside smooth glass (eta^2)", "{\"type\":\"dielectric\",\"eta\":1.5}", "[0,0,0.001]", "20", 2.25, 64},
    };
    char doc[2048];
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        snprintf(doc, sizeof doc, fmt, cases[i].from, cases[i].fov, cases[i].material);
        result r = render_k(doc, cases[i].spp, 80 + 20 * (uint32_t)i);
        /* Specular cases have (near) zero variance: a 1e-5 floor covers float rounding. */
        check(cases[i].name, r, cases[i].expected, 1e-5, 1e-4);
        if (!(fabs(r.mean - cases[i].expected) < 0.01 * cases[i].expected)) fail_msg("%s: not within 1%%", cases[i].name);
    }
}

/* The white furnace seen from behind: an orthographic camera below a large
 * disk that faces up looks at its back at cosθo = −0.7, under a constant environment of
 * radiance 1, max_depth 1. Every ray leaving the disk escapes, so a pixel is the
 * material's directional albedo at that wo: 1 for a white Lambertian and a perfect
 * conductor; for kd = ks = 1 smooth plastic ks·F + kd(1 − ks·F)(1 − ks·F̄) = 0.9128 with F
 * from 1 into 1.5 at |cosθo| — the coat is two-sided — where a coat whose Fresnel swapped
 * the indices below the normal gave 1.86; rough plastic, substrate, rough conductor and Oren–Nayar must
 * stay ≤ 1.01 (rough plastic at α = 0.1 gave 1.66). The same from the front for plastic.
 * 16 renders of 16 spp over 4×4 pixels: se ≈ 0.5%.
 * Tolerance: Student's t at p ≥ 1e-4 per case around the closed form (1e-5 for float
 * rounding), or the one-sided bound 1.01 + t·se with the same t. */
static void test_furnace_from_behind(void **state)
{
    (void)state;
    const char *fmt = "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[%.17g,%.17g,0],\"to\":[0,0,0],"
                      "\"up\":[0,0,1],\"height\":0.01},\"film\":{\"width\":4,\"height\":4,\"filter\":{\"type\":\"box\"}},"
                      "\"integrator\":{\"type\":\"path\",\"max_depth\":1},\"materials\":{\"m\":%s},"
                      "\"shapes\":[{\"type\":\"disk\",\"normal\":[0,1,0],\"radius\":10,\"material\":\"m\"}],"
                      "\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}";
    /* 2∫₀¹ F(μ)μ dμ (Simpson, 2000 intervals) and the smooth plastic's closed form. */
    double fbar = 0;
    for (int i = 0; i <= 2000; i++) {
        double mu = i / 2000.0, w = (i == 0 || i == 2000) ? 1 : (i % 2 ? 4 : 2);
        fbar += w * ts_fresnel_dielectric((float)mu, 1, 1.5f) * mu;
    }
    fbar = 2 * fbar / 6000;
    double f = ts_fresnel_dielectric(0.7f, 1, 1.5f), plastic = f + (1 - f) * (1 - fbar);
    struct { const char *name, *material; int side; double expected; } cases[] = {
        {"behind: Lambertian, albedo 1", "{\"type\":\"diffuse\",\"reflectance\":1}", -1, 1},
        {"behind: mirror", "{\"type\":\"mirror\",\"reflectance\":1}", -1, 1},
        {"behind: smooth plastic kd=ks=1", "{\"type\":\"plastic\",\"diffuse\":1,\"specular\":1}", -1, plastic},
        {"front: smooth plastic kd=ks=1", "{\"type\":\"plastic\",\"diffuse\":1,\"specular\":1}", 1, plastic},
        {"behind: plastic kd=ks=1 alpha 0.1", "{\"type\":\"plastic\",\"diffuse\":1,\"specular\":1,\"roughness\":0.1}", -1, NAN},
        {"behind: substrate kd=ks=1 alpha 0.1", "{\"type\":\"substrate\",\"diffuse\":1,\"specular\":1,\"roughness\":0.1}", -1, NAN},
        {"behind: conductor F=1 ggx alpha 0.2", "{\"type\":\"conductor\",\"eta\":0,\"k\":0,\"roughness\":0.2}", -1, NAN},
        {"behind: diffuse sigma 20", "{\"type\":\"diffuse\",\"reflectance\":1,\"sigma\":20}", -1, NAN},
    };
    char doc[2048];
    const double c = 0.7, sn = sqrt(1 - c * c);
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        snprintf(doc, sizeof doc, fmt, -3 * sn, 3 * c * cases[i].side, cases[i].material);
        result r = render_k(doc, 256, 500 + 20 * (uint32_t)i);
        if (!isnan(cases[i].expected)) {
            check(cases[i].name, r, cases[i].expected, 1e-5, 1e-4);
            continue;
        }
        /* One-sided bound: t of (mean − 1.01) must not exceed the 1e-4 one-sided point. */
        double t = r.se > 0 ? (r.mean - 1.01) / r.se : (r.mean > 1.01 ? INFINITY : -INFINITY);
        double p = t > 0 ? 0.5 * ts_rs_student_two_sided(t, r.k - 1) : 1;
        print_message("%-48s %.6f ≤ 1.01 (se %.2e from %d renders, p %.2g)\n", cases[i].name, r.mean, r.se, r.k, p);
        if (r.nonfinite) fail_msg("%s: %llu non-finite samples", cases[i].name, (unsigned long long)r.nonfinite);
        if (!(p >= 1e-4)) fail_msg("%s: albedo %.5f exceeds 1.01", cases[i].name, r.mean);
    }
}

/* Hard case 5a: total internal reflection. A camera inside a wide glass slab (η = 1.5,
 * 1 unit thick) looks up at 60° from the vertical, beyond the critical angle of 41.8°:
 * the ray is reflected between the faces and never leaves within max_depth, so the
 * emitter above the slab contributes exactly nothing. At 30° it refracts out and sees it. */
static void test_total_internal_reflection(void **state)
{
    (void)state;
    const char *fmt =
        "{\"tessera\":1,\"camera\":{\"type\":\"orthographic\",\"from\":[0,0,0],\"to\":[%.17g,%.17g,0],\"up\":[0,0,1],"
        "\"height\":0.01},\"film\":{\"width\":4,\"height\":4,\"filter\":{\"type\":\"box\"}},"
        "\"integrator\":{\"type\":\"path\",\"max_depth\":20,\"rr_depth\":100},"
        "\"materials\":{\"glass\":{\"type\":\"dielectric\",\"eta\":1.5},\"k\":{\"type\":\"diffuse\",\"reflectance\":0}},"
        "\"shapes\":[{\"type\":\"mesh\",\"material\":\"glass\",\"positions\":[-100,-0.5,-100, 100,-0.5,-100, 100,-0.5,100,"
        " -100,-0.5,100, -100,0.5,-100, 100,0.5,-100, 100,0.5,100, -100,0.5,100],"
        "\"indices\":[0,1,2, 0,2,3, 4,6,5, 4,7,6, 0,4,5, 0,5,1, 1,5,6, 1,6,2, 2,6,7, 2,7,3, 3,7,4, 3,4,0]},"
        "{\"type\":\"disk\",\"center\":[0,30,0],\"normal\":[0,-1,0],\"radius\":1000,\"material\":\"k\",\"emission\":1}]}";
    char doc[4096];
    double a = 60 * 3.14159265358979 / 180;
    snprintf(doc, sizeof doc, fmt, sin(a), cos(a));
    result tir = render_doc(doc, 4);
    print_message("%-48s %.6f (expected exactly 0)\n", "TIR at 60 degrees inside a glass slab", tir.mean);
    assert_int_equal(tir.nonfinite, 0);
    assert_true(tir.mean == 0);
    a = 30 * 3.14159265358979 / 180;
    snprintf(doc, sizeof doc, fmt, sin(a), cos(a));
    result out = render_doc(doc, 4);
    print_message("%-48s %.6f (expected > 0)\n", "refraction at 30 degrees", out.mean);
    assert_true(out.mean > 0.5);
}

/* Hard case 5b: an emissive mesh with a zero-area triangle (collinear vertices) and a
 * sliver (height 1e-7 of its length) renders no non-finite sample and the same light as
 * the mesh without them (the sliver emits a negligible 1e-7 of the quad's power): 16
 * renders of each with seeds the other does not use, compared block by block with
 * Welch's t, Bonferroni over the 6 blocks at a false-failure rate of 1e-4. */
static void test_degenerate_emitter_triangles(void **state)
{
    (void)state;
    const char *fmt =
        "{\"tessera\":1,\"camera\":{\"from\":[0,3,4],\"to\":[0,0,0],\"fov\":40},\"film\":{\"width\":12,\"height\":8},"
        "\"integrator\":{\"type\":\"path\",\"max_depth\":3},\"materials\":{\"w\":{\"type\":\"diffuse\",\"reflectance\":0.6},"
        "\"k\":{\"type\":\"diffuse\",\"reflectance\":0}},\"shapes\":[{\"type\":\"disk\",\"normal\":[0,1,0],\"radius\":5,"
        "\"material\":\"w\"},{\"type\":\"mesh\",\"material\":\"k\",\"emission\":5,\"positions\":[-0.5,2,-0.5, 0.5,2,-0.5,"
        " 0.5,2,0.5, -0.5,2,0.5, 0,2,0, 1,2,1, 2,2,2, 0.2,2.1,0, 0.7,2.1,1e-7]%s}]}";
    char with[4096], without[4096];
    snprintf(with, sizeof with, fmt, ",\"indices\":[0,2,1, 0,3,2, 4,6,5, 7,8,1, 4,4,4]");
    snprintf(without, sizeof without, fmt, ",\"indices\":[0,2,1, 0,3,2]");
    ts_rs_blocks a, b;
    ts_error err = {0};
    ts_scene *s = NULL;
    if (ts_scene_load_text(with, strlen(with), NULL, "with", NULL, &s, &err)) fail_msg("%s", err.message);
    ts_rs_render(s, TS_SAMPLER_SOBOL, 200, K_RENDERS, 4, 4, &a);
    ts_scene_destroy(s);
    if (ts_scene_load_text(without, strlen(without), NULL, "without", NULL, &s, &err)) fail_msg("%s", err.message);
    ts_rs_render(s, TS_SAMPLER_SOBOL, 300, K_RENDERS, 4, 4, &b);
    ts_scene_destroy(s);
    ts_rs_result c = ts_rs_compare(&a, &b, 0);
    print_message("%-48s %.6f vs %.6f without them (image t %+.2f; worst block t %+.2f, p %.2g)\n",
                  "emitter with zero-area and sliver triangles", a.image_mean, b.image_mean, c.image_t, c.t, c.p);
    assert_int_equal(a.nonfinite, 0);
    assert_true(a.image_mean > 0);
    assert_true(ts_rs_passes(&c, a.n, 1e-4));
}

/* pbrt-v3's per-light nSamples under direct's strategy all (a light's "samples", an
 * emitter's "light_samples"): each light is estimated from its own count of samples,
 * averaged. A white-ish diffuse disk of radius 100 seen from 1 above, under a constant
 * environment of radiance 1, reflects exactly ρ·L = 0.5 (its whole hemisphere is open),
 * whatever the count. The light's 16 samples must (1) keep that mean — Student's t over
 * K = 16 renders at p ≥ 1e-4, as check() — where summing them would give 8, and (2) cut
 * the variance of a render's mean: 16 averaged samples have at most 1/16 of one sample's
 * variance (less with the stratified arrays), so the observed ratio of the two sample
 * variances (15 dof each) is below 1/2 unless F(15, 15) > 8, p = 1.2e-4 — the false-failure
 * rate; a count that is not honoured gives a ratio near 1. Inside a two-sided emitting
 * sphere the light estimate is exact for any count (the zero-variance case above), so an
 * emitter's light_samples 8 must give Le (1 + ρ) to float rounding, not 8 Le ρ + Le. */
static void test_light_samples(void **state)
{
    (void)state;
    const char *fmt = "{\"tessera\":1,\"camera\":{\"from\":[0,0,1],\"to\":[0,0,0],\"up\":[0,1,0],\"fov\":20},"
                      "\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\"}},"
                      "\"integrator\":{\"type\":\"direct\",\"strategy\":\"all\",\"max_depth\":1},"
                      "\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":0.5}},"
                      "\"shapes\":[{\"type\":\"disk\",\"center\":[0,0,0],\"normal\":[0,0,1],\"radius\":100,"
                      "\"material\":\"m\"}],\"lights\":[{\"type\":\"infinite\",\"radiance\":1%s}]}";
    char doc[2048];
    snprintf(doc, sizeof doc, fmt, "");
    result one = render_k(doc, 64, 300);
    check("environment, 1 sample per light", one, 0.5, 1e-5, 1e-4);
    snprintf(doc, sizeof doc, fmt, ",\"samples\":16");
    result many = render_k(doc, 64, 400);
    check("environment, 16 samples per light", many, 0.5, 1e-5, 1e-4);
    double ratio = (many.se * many.se) / (one.se * one.se);
    print_message("variance of a render's mean, 16 samples / 1 sample: %.4f (at most 1/16 = 0.0625 expected)\n", ratio);
    if (!(ratio < 0.5)) fail_msg("16 samples per light did not reduce the variance: ratio %.3f", ratio);

    char integ[] = "{\"type\":\"direct\",\"strategy\":\"all\"}";
    const double rho = 0.5, le = 0.75;
    snprintf(doc, sizeof doc,
             "{\"tessera\":1,\"camera\":{\"from\":[0,0,0],\"to\":[0,0,-1],\"fov\":60},"
             "\"film\":{\"width\":8,\"height\":8,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"seed\":3},"
             "\"integrator\":%s,\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":%g}},"
             "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\",\"emission\":%g,\"two_sided\":true,"
             "\"light_samples\":8}]}",
             integ, rho, le);
    check("emitting sphere, light_samples 8", render_doc(doc, 4), le * (1 + rho), 1e-4, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_emitting_sphere_fixed_depth),
        cmocka_unit_test(test_point_light_in_sphere),
        cmocka_unit_test(test_emitting_sphere_roulette),
        cmocka_unit_test(test_sphere_light_over_plane),
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_furnace_from_behind),
        cmocka_unit_test(test_total_internal_reflection),
        cmocka_unit_test(test_degenerate_emitter_triangles),
        cmocka_unit_test(test_light_samples),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
