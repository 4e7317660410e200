/* test_bxdf.c — every BxDF: χ² of its sampling against its pdf, sample/eval consistency,
 * pdf normalisation, energy, reciprocity, and finiteness at the limits (docs/design.md §8). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>

#include "chi2_bsdf.h"
#include "core/hash.h"
#include "materials/bxdf.h"
#include "sampling/sampling.h"

static ts_vec3 dir_deg(float theta_deg, float phi_deg)
{
    float t = ts_radians(theta_deg), p = ts_radians(phi_deg);
    return (ts_vec3){sinf(t) * cosf(p), sinf(t) * sinf(p), cosf(t)};
}
static ts_vec3 dir_cos(float cos_theta, float phi_deg)
{
    float s = sqrtf(fmaxf(0, 1 - cos_theta * cos_theta)), p = ts_radians(phi_deg);
    return (ts_vec3){s * cosf(p), s * sinf(p), cos_theta};
}

static int chi2_failures;
static double p_min = 1, p_max = 0;

static void run_case(const char *name, ts_bxdf b, ts_vec3 wo)
{
    ts_chi2_bxdf c = {b, ts_vec3_normalize(wo)};
    ts_chi2_params p;
    ts_chi2_params_default(&p);
    ts_chi2_result r;
    bool ok = ts_chi2_test(&p, ts_chi2_bxdf_sample, ts_chi2_bxdf_pdf, &c, &r);
    double frac;
    bool norm_ok = ts_chi2_pdf_normalised(&p, &r, &frac);
    print_message("%-44s p=%.4f ∫pdf=%.6f frac=%.6f unconv=%d evals=%llu %s\n", name, r.p_value, r.pdf_integral, frac,
                  r.unconverged, (unsigned long long)r.pdf_evals, ok ? "" : r.message);
    if (r.dof >= 1) {
        if (r.p_value < p_min) p_min = r.p_value;
        if (r.p_value > p_max) p_max = r.p_value;
    }
    if (!ok || !norm_ok) chi2_failures++;
}

static ts_microfacet mf(int type, float ax, float ay) { return ts_microfacet_make((ts_microfacet_type)type, ax, ay); }

static void test_chi2_all(void **state)
{
    (void)state;
    char name[128];
    ts_rgb one = ts_rgb_gray(1);
    run_case("lambertian θo=30°", ts_bxdf_lambertian(one), dir_deg(30, 20));
    run_case("lambertian from below θo=150°", ts_bxdf_lambertian(one), dir_deg(150, 20));
    run_case("oren-nayar σ=20° θo=60°", ts_bxdf_oren_nayar(one, 20), dir_deg(60, 10));
    float alphas[] = {0.001f, 0.05f, 0.2f, 0.5f, 1.0f};
    for (int t = 0; t < 2; t++) {
        const char *dn = t ? "beckmann" : "ggx";
        for (int i = 0; i < 5; i++) {
            if (t == 1 && i == 0) continue; /* Beckmann α = 0.001: see test_sharp_beckmann */
            snprintf(name, sizeof name, "%s reflection α=%g θo=40°", dn, alphas[i]);
            run_case(name, ts_bxdf_microfacet_reflection(one, mf(t, alphas[i], alphas[i]), ts_fresnel_one()),
                     dir_deg(40, 30));
        }
        snprintf(name, sizeof name, "%s reflection α=(0.05,0.3) θo=60°", dn);
        run_case(name, ts_bxdf_microfacet_reflection(one, mf(t, 0.05f, 0.3f), ts_fresnel_one()), dir_deg(60, 50));
        snprintf(name, sizeof name, "%s reflection α=(0.5,0.1) θo=70°", dn);
        run_case(name, ts_bxdf_microfacet_reflection(one, mf(t, 0.5f, 0.1f), ts_fresnel_one()), dir_deg(70, 120));
        snprintf(name, sizeof name, "%s reflection α=0.2 normal incidence", dn);
        run_case(name, ts_bxdf_microfacet_reflection(one, mf(t, 0.2f, 0.2f), ts_fresnel_one()), dir_deg(0, 0));
    }
    /* Transmission: outside/inside, both η, total internal reflection, grazing. */
    struct {
        const char *what;
        float eta;
        ts_vec3 wo;
    } tr[] = {
        {"η=1.5 from outside θo=40°", 1.5f, dir_deg(40, 30)},
        {"η=1/1.5 from outside θo=40°", 1 / 1.5f, dir_deg(40, 30)},
        {"η=1.5 from inside θo=140°", 1.5f, dir_deg(140, 30)},
        {"η=1.5 from inside beyond critical θo=120°", 1.5f, dir_deg(120, 30)},
        {"η=1.5 grazing cosθo=0.05", 1.5f, dir_cos(0.05f, 30)},
        {"η=1.5 grazing cosθo=0.001", 1.5f, dir_cos(0.001f, 30)},
    };
    for (int t = 0; t < 2; t++)
        for (size_t i = 0; i < sizeof tr / sizeof tr[0]; i++) {
            snprintf(name, sizeof name, "%s transmission α=0.3 %s", t ? "beckmann" : "ggx", tr[i].what);
            run_case(name, ts_bxdf_microfacet_transmission(one, mf(t, 0.3f, 0.3f), 1, tr[i].eta), tr[i].wo);
        }
    run_case("ggx transmission α=0.05 η=1.5 θo=30°", ts_bxdf_microfacet_transmission(one, mf(0, 0.05f, 0.05f), 1, 1.5f),
             dir_deg(30, 0));
    /* Anisotropic transmission (rough glass with uroughness ≠ vroughness), both sides.
     * Beckmann's at (0.05, 0.4) is a lobe the harness's quadrature does not resolve
     * (∫pdf 0.997 with 8 unconverged cells, as test_sharp_beckmann's isotropic α = 0.001),
     * so its cases are milder. */
    run_case("ggx transmission α=(0.05,0.4) η=1.5 θo=50°", ts_bxdf_microfacet_transmission(one, mf(0, 0.05f, 0.4f), 1, 1.5f),
             dir_deg(50, 60));
    run_case("ggx transmission α=(0.6,0.1) η=1.5 inside θo=150°",
             ts_bxdf_microfacet_transmission(one, mf(0, 0.6f, 0.1f), 1, 1.5f), dir_deg(150, 20));
    run_case("beckmann transmission α=(0.15,0.45) η=1.5 θo=50°",
             ts_bxdf_microfacet_transmission(one, mf(1, 0.15f, 0.45f), 1, 1.5f), dir_deg(50, 60));
    run_case("beckmann transmission α=(0.6,0.2) η=1.5 inside θo=150°",
             ts_bxdf_microfacet_transmission(one, mf(1, 0.6f, 0.2f), 1, 1.5f), dir_deg(150, 20));
    run_case("lambertian transmission θo=30°", ts_bxdf_lambertian_transmission(one), dir_deg(30, 20));
    run_case("lambertian transmission from below θo=120°", ts_bxdf_lambertian_transmission(one), dir_deg(120, 20));
    /* A scaled lobe samples as its lobe; its f and pdf are the harness's consistency check. */
    run_case("scaled(0.3,0.6,0.9) ggx reflection α=0.3 θo=45°",
             ts_bxdf_scaled(ts_bxdf_microfacet_reflection(one, mf(0, 0.3f, 0.3f), ts_fresnel_make_dielectric(1, 1.5f)),
                            (ts_rgb){0.3f, 0.6f, 0.9f}),
             dir_deg(45, 10));
    run_case("ggx transmission η=1 θo=30°", ts_bxdf_microfacet_transmission(one, mf(0, 0.3f, 0.3f), 1, 1),
             dir_deg(30, 0));
    run_case("fresnel blend α=0.2 θo=50°", ts_bxdf_fresnel_blend(ts_rgb_gray(0.5f), ts_rgb_gray(0.2f), mf(0, 0.2f, 0.2f)),
             dir_deg(50, 70));
    run_case("fresnel blend α=(0.05,0.4) θo=20°",
             ts_bxdf_fresnel_blend(ts_rgb_gray(0.5f), ts_rgb_gray(0.2f), mf(0, 0.05f, 0.4f)), dir_deg(20, 70));
    run_case("fresnel blend diffuse part θo=50°", ts_bxdf_fresnel_blend_diffuse(one, ts_rgb_gray(0.2f)),
             dir_deg(50, 70));
    /* Specular lobes: everything discrete, nothing continuous (∫pdf = 0). */
    run_case("specular reflection", ts_bxdf_specular_reflection(one, ts_fresnel_one()), dir_deg(30, 0));
    run_case("specular transmission", ts_bxdf_specular_transmission(one, 1, 1.5f), dir_deg(30, 0));
    run_case("fresnel specular", ts_bxdf_fresnel_specular(one, one, 1, 1.5f), dir_deg(30, 0));
    print_message("χ² p-values over the cases: min %.4f max %.4f\n", p_min, p_max);
    assert_int_equal(chi2_failures, 0);
}

/* Beckmann at α = 0.001: the Gaussian lobe is ~1/1000 of a χ² cell and the harness's
 * sample-guided quadrature does not yet resolve it (it under-reports its error; the GGX
 * lobe, with its heavy tails, is resolved). Until it does, the pdf's normalisation is
 * checked by a direct integral over a patch of ±0.2 rad around the mirror direction on
 * a grid of α/40 (Gaussian tails beyond 200α are < e^-40000), and the sampler's
 * distribution by its first two moments about the mirror direction: with 10^6 samples
 * the mean offset has σ ≈ 1.3e-6 (α/1000), so the 1e-5 bound is ~7σ (false failure
 * < 1e-11); the second moments have relative σ ≈ 0.2%, bounded at 2% (10σ). */
static void test_sharp_beckmann(void **state)
{
    (void)state;
    float a = 0.001f;
    ts_bxdf b = ts_bxdf_microfacet_reflection(ts_rgb_gray(1), mf(1, a, a), ts_fresnel_one());
    ts_vec3 wo = ts_vec3_normalize(dir_deg(40, 30)), m = {-wo.x, -wo.y, wo.z}, s, t;
    ts_coordinate_system(m, &s, &t);
    double h = a / 40, sum = 0;
    int n = (int)(0.2 / h);
    for (int i = -n; i <= n; i++)
        for (int j = -n; j <= n; j++) {
            double x = i * h, y = j * h;
            if (x * x + y * y > 0.04) continue;
            double z = sqrt(1 - x * x - y * y);
            ts_vec3 w = {(float)(s.x * x + t.x * y + m.x * z), (float)(s.y * x + t.y * y + m.y * z),
                         (float)(s.z * x + t.z * y + m.z * z)};
            sum += ts_bxdf_pdf(&b, wo, w) * h * h / z;
        }
    print_message("beckmann α=0.001: ∫pdf over the lobe patch %.6f\n", sum);
    assert_true(fabs(sum - 1) < 1e-3);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 17, 2);
    double mx = 0, my = 0, mxx = 0, myy = 0;
    int cnt = 0;
    for (int i = 0; i < 1000000; i++) {
        ts_bxdf_sample smp;
        if (!ts_bxdf_sample_f(&b, wo, (ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)}, &smp)) continue;
        double x = ts_vec3_dot(smp.wi, s), y = ts_vec3_dot(smp.wi, t);
        mx += x;
        my += y;
        mxx += x * x;
        myy += y * y;
        cnt++;
    }
    mx /= cnt;
    my /= cnt;
    mxx /= cnt;
    myy /= cnt;
    /* The same moments of the pdf on the patch grid. */
    double ex = 0, ey = 0, exx = 0, eyy = 0;
    for (int i = -n / 10; i <= n / 10; i++)
        for (int j = -n / 10; j <= n / 10; j++) {
            double x = i * h, y = j * h, z = sqrt(1 - x * x - y * y);
            ts_vec3 w = {(float)(s.x * x + t.x * y + m.x * z), (float)(s.y * x + t.y * y + m.y * z),
                         (float)(s.z * x + t.z * y + m.z * z)};
            double p = ts_bxdf_pdf(&b, wo, w) * h * h / z;
            ex += p * x;
            ey += p * y;
            exx += p * x * x;
            eyy += p * y * y;
        }
    print_message("beckmann α=0.001 moments: sampled (%.3g, %.3g, %.3g, %.3g) pdf (%.3g, %.3g, %.3g, %.3g)\n", mx, my,
                  mxx, myy, ex, ey, exx, eyy);
    assert_true(cnt == 1000000);
    assert_true(fabs(mx - ex) < 1e-5 && fabs(my - ey) < 1e-5);
    assert_true(fabs(mxx - exx) < 0.02 * exx && fabs(myy - eyy) < 0.02 * eyy);
}

/* ---- the list of BxDFs the other tests iterate ---- */
static int make_all(ts_bxdf *out, int cap)
{
    int n = 0;
    ts_rgb one = ts_rgb_gray(1);
    out[n++] = ts_bxdf_lambertian(one);
    out[n++] = ts_bxdf_oren_nayar(one, 20);
    float alphas[] = {0.001f, 0.05f, 0.2f, 0.5f, 1.0f};
    for (int t = 0; t < 2; t++) {
        for (int i = 0; i < 5; i++) {
            out[n++] = ts_bxdf_microfacet_reflection(one, mf(t, alphas[i], alphas[i]),
                                                     ts_fresnel_make_conductor(1, ts_rgb_gray(0.2f), ts_rgb_gray(3)));
            out[n++] = ts_bxdf_microfacet_transmission(one, mf(t, alphas[i], alphas[i]), 1, 1.5f);
        }
        out[n++] = ts_bxdf_microfacet_reflection(one, mf(t, 0.05f, 0.3f), ts_fresnel_make_dielectric(1, 1.5f));
        out[n++] = ts_bxdf_microfacet_transmission(one, mf(t, 0.5f, 0.1f), 1, 1 / 1.5f);
    }
    out[n++] = ts_bxdf_fresnel_blend(ts_rgb_gray(0.5f), ts_rgb_gray(0.3f), mf(0, 0.2f, 0.2f));
    out[n++] = ts_bxdf_fresnel_blend_diffuse(ts_rgb_gray(0.5f), ts_rgb_gray(0.3f));
    out[n++] = ts_bxdf_lambertian_transmission(ts_rgb_gray(0.7f));
    out[n++] = ts_bxdf_microfacet_transmission(one, mf(0, 0.05f, 0.4f), 1, 1.5f);
    out[n++] = ts_bxdf_scaled(ts_bxdf_microfacet_reflection(one, mf(0, 0.4f, 0.1f), ts_fresnel_make_dielectric(1.5f, 1)),
                              (ts_rgb){0.2f, 0.5f, 0.8f});
    out[n++] = ts_bxdf_scaled(ts_bxdf_scaled(ts_bxdf_fresnel_blend(ts_rgb_gray(0.5f), ts_rgb_gray(0.3f), mf(0, 0.2f, 0.2f)),
                                             ts_rgb_gray(0.5f)),
                              (ts_rgb){0.9f, 0.5f, 0.1f});
    out[n++] = ts_bxdf_specular_reflection(one, ts_fresnel_make_dielectric(1, 1.5f));
    out[n++] = ts_bxdf_specular_transmission(one, 1, 1.5f);
    out[n++] = ts_bxdf_fresnel_specular(one, one, 1, 1.5f);
    assert_true(n <= cap);
    return n;
}

static bool rel_close(double a, double b, double rel) { return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-30; }

static void test_consistency(void **state)
{
    (void)state;
    ts_bxdf all[64];
    int n = make_all(all, 64);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 11, 5);
    double worst = 0;
    for (int k = 0; k < n; k++) {
        /* 10^5 random (wo, u) per BxDF. f and pdf of a sample are computed by the same
         * functions as f()/pdf() at the returned wi, so agreement is to float rounding:
         * relative 1e-4 (docs/design.md §8) is loose by orders of magnitude. */
        for (int i = 0; i < 100000; i++) {
            ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
            ts_bxdf_sample s;
            if (!ts_bxdf_sample_f(&all[k], wo, u, &s)) continue;
            if (!ts_rgb_is_finite(s.f) || !(s.pdf > 0) || !isfinite(s.pdf) || s.f.r < 0 || s.f.g < 0 || s.f.b < 0)
                fail_msg("bxdf %d: sample f=(%g,%g,%g) pdf=%g", k, s.f.r, s.f.g, s.f.b, s.pdf);
            if (s.flags & TS_BXDF_SPECULAR) continue;
            float pdf = ts_bxdf_pdf(&all[k], wo, s.wi);
            ts_rgb f = ts_bxdf_f(&all[k], wo, s.wi);
            double e = fmax(fabs(pdf - s.pdf) / fmax(pdf, s.pdf), fabs(f.r - s.f.r) / fmax(fmax(f.r, s.f.r), 1e-30));
            if (e > worst) worst = e;
            if (!rel_close(pdf, s.pdf, 1e-4) || !rel_close(f.r, s.f.r, 1e-4) || !rel_close(f.b, s.f.b, 1e-4))
                fail_msg("bxdf %d: sample pdf %g f %g vs pdf() %g f() %g", k, s.pdf, s.f.r, pdf, f.r);
        }
    }
    print_message("worst relative sample/eval mismatch: %.3g\n", worst);
}

static void test_energy(void **state)
{
    (void)state;
    /* Lambertian R = 1: every weight f|cosθi|/pdf is exactly 1 (float: 1e-6). */
    ts_bxdf lam = ts_bxdf_lambertian(ts_rgb_gray(1));
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 9);
    for (int i = 0; i < 100000; i++) {
        ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
        ts_bxdf_sample s;
        if (!ts_bxdf_sample_f(&lam, wo, (ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)}, &s)) continue;
        double w = s.f.r * fabsf(s.wi.z) / s.pdf;
        if (fabs(w - 1) > 1e-6) fail_msg("lambertian weight %.9g", w);
    }
    /* Oren–Nayar at normal incidence: f = R/π · A exactly, so every weight is A (1e-6). */
    for (float sigma = 5; sigma <= 60; sigma += 11) {
        ts_bxdf on = ts_bxdf_oren_nayar(ts_rgb_gray(1), sigma);
        float s2 = ts_sqr(ts_radians(sigma)), a = 1 - s2 / (2 * (s2 + 0.33f));
        ts_vec2 us[4096];
        for (int i = 0; i < 4096; i++) us[i] = (ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
        ts_rgb rho = ts_bxdf_rho_hd(&on, (ts_vec3){0, 0, 1}, 4096, us);
        if (fabs(rho.r - a) > 1e-5) fail_msg("oren-nayar σ=%g: albedo %.7f, expected %.7f", sigma, rho.r, a);
    }
    /* VNDF: weight = F · G(wo,wi)/G1(wo) ≤ 1 for reflection with F ≤ 1; for transmission
     * the radiance scale 1/η² is undone first: (1 − F) G/G1 ≤ 1. 1e-4 covers float
     * rounding of G and G1 computed separately. */
    float alphas[] = {0.001f, 0.05f, 0.2f, 0.5f, 1.0f, 2.0f};
    for (int t = 0; t < 2; t++)
        for (int a = 0; a < 6; a++) {
            ts_bxdf r = ts_bxdf_microfacet_reflection(ts_rgb_gray(1), mf(t, alphas[a], alphas[a]), ts_fresnel_one());
            ts_bxdf tr = ts_bxdf_microfacet_transmission(ts_rgb_gray(1), mf(t, alphas[a], alphas[a]), 1, 1.5f);
            for (int i = 0; i < 20000; i++) {
                ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
                ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
                ts_bxdf_sample s;
                if (ts_bxdf_sample_f(&r, wo, u, &s)) {
                    double w = s.f.r * fabsf(s.wi.z) / s.pdf;
                    if (!(w >= 0 && w <= 1 + 1e-4)) fail_msg("reflection weight %.9g (type %d α=%g)", w, t, alphas[a]);
                }
                if (ts_bxdf_sample_f(&tr, wo, u, &s)) {
                    double w = s.f.r * fabsf(s.wi.z) / s.pdf * s.eta * s.eta;
                    if (!(w >= 0 && w <= 1 + 1e-4)) fail_msg("transmission weight %.9g (type %d α=%g)", w, t, alphas[a]);
                }
            }
        }
}

static void test_reciprocity(void **state)
{
    (void)state;
    ts_bxdf all[64];
    int n = make_all(all, 64);
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 5, 1);
    for (int k = 0; k < n; k++) {
        if (!(all[k].flags & TS_BXDF_REFLECTION) || (all[k].flags & (TS_BXDF_TRANSMISSION | TS_BXDF_SPECULAR))) continue;
        for (int i = 0; i < 20000; i++) {
            ts_vec3 a = ts_sample_uniform_hemisphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec3 b = ts_sample_uniform_hemisphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_rgb fab = ts_bxdf_f(&all[k], a, b), fba = ts_bxdf_f(&all[k], b, a);
            /* Same formula with the roles swapped: only float rounding differs (1e-5). */
            if (!rel_close(fab.r, fba.r, 1e-5) || !rel_close(fab.g, fba.g, 1e-5))
                fail_msg("bxdf %d not reciprocal: %.9g vs %.9g", k, fab.r, fba.r);
        }
    }
}

static void test_no_nan(void **state)
{
    (void)state;
    ts_bxdf all[96];
    int n = make_all(all, 96);
    float limits[] = {0, 1e-7f, 1e-4f};
    for (int t = 0; t < 2; t++)
        for (int a = 0; a < 3; a++) {
            all[n++] = ts_bxdf_microfacet_reflection(ts_rgb_gray(1), mf(t, limits[a], limits[a]), ts_fresnel_one());
            all[n++] = ts_bxdf_microfacet_transmission(ts_rgb_gray(1), mf(t, limits[a], limits[a]), 1, 1.5f);
            all[n++] = ts_bxdf_microfacet_transmission(ts_rgb_gray(1), mf(t, limits[a], limits[a]), 1, 1);
            all[n++] = ts_bxdf_fresnel_blend(ts_rgb_gray(1), ts_rgb_gray(1), mf(t, limits[a], limits[a]));
        }
    all[n++] = ts_bxdf_fresnel_specular(ts_rgb_gray(1), ts_rgb_gray(1), 1, 1);
    all[n++] = ts_bxdf_specular_transmission(ts_rgb_gray(1), 1, 1);
    all[n++] = ts_bxdf_oren_nayar(ts_rgb_gray(1), 90);
    ts_vec3 dirs[] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0.6f, 0.8f, 0}, {0.8f, 0, 0.6f}, {0.8f, 0, -0.6f},
                      {0.9999995f, 0, 0.001f}, {0.9999995f, 0, -0.001f}, {1e-4f, 0, 0.99999999f}};
    int nd = (int)(sizeof dirs / sizeof dirs[0]);
    float us[] = {0, 0.25f, 0.5f, TS_ONE_MINUS_EPSILON, 1};
    for (int k = 0; k < n; k++)
        for (int i = 0; i < nd; i++)
            for (int j = 0; j < nd; j++) {
                ts_rgb f = ts_bxdf_f(&all[k], dirs[i], dirs[j]);
                float p = ts_bxdf_pdf(&all[k], dirs[i], dirs[j]);
                if (!ts_rgb_is_finite(f) || !isfinite(p) || p < 0 || f.r < 0)
                    fail_msg("bxdf %d f/pdf (%g, %g) at dirs %d %d", k, f.r, p, i, j);
                if (dirs[i].z == 0 && (f.r != 0 || p != 0)) fail_msg("bxdf %d: wo.z = 0 gives f %g pdf %g", k, f.r, p);
                for (int a = 0; a < 5; a++) {
                    ts_bxdf_sample s;
                    ts_vec2 u = {us[a], us[(a + j) % 5]};
                    if (!ts_bxdf_sample_f(&all[k], dirs[i], u, &s)) continue;
                    if (dirs[i].z == 0) fail_msg("bxdf %d sampled at wo.z = 0", k);
                    if (!ts_rgb_is_finite(s.f) || !isfinite(s.pdf) || !(s.pdf > 0) || !ts_vec3_is_finite(s.wi))
                        fail_msg("bxdf %d sample at dir %d u (%g,%g): f %g pdf %g", k, i, u.x, u.y, s.f.r, s.pdf);
                }
            }
}

/* A scaled lobe is its lobe's f times the scale, exactly (one float multiply; a scaled
 * scaled lobe multiplies the scales first, so 1 ulp of rounding is allowed there), with
 * the same pdf and the same sampled direction; a scaled specular lobe's sample weight is
 * scaled too. Lambertian transmission: f = t/π, its weight f|cosθi|/pdf exactly t
 * (float: 1e-6), every sample on the side opposite wo. */
static void test_scaled_and_transmission(void **state)
{
    (void)state;
    ts_rgb s = {0.25f, 0.5f, 0.75f};
    ts_bxdf base[] = {
        ts_bxdf_lambertian(ts_rgb_gray(0.8f)),
        ts_bxdf_microfacet_reflection(ts_rgb_gray(1), mf(0, 0.2f, 0.5f), ts_fresnel_make_dielectric(1, 1.5f)),
        ts_bxdf_microfacet_transmission(ts_rgb_gray(1), mf(1, 0.3f, 0.3f), 1, 1.5f),
        ts_bxdf_fresnel_specular(ts_rgb_gray(1), ts_rgb_gray(1), 1, 1.5f),
        ts_bxdf_lambertian_transmission(ts_rgb_gray(0.6f)),
    };
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 21, 4);
    for (size_t k = 0; k < sizeof base / sizeof base[0]; k++) {
        ts_bxdf sc = ts_bxdf_scaled(base[k], s);
        for (int i = 0; i < 20000; i++) {
            ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec3 wi = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
            ts_rgb f0 = ts_bxdf_f(&base[k], wo, wi), f1 = ts_bxdf_f(&sc, wo, wi);
            if (f1.r != f0.r * s.r || f1.g != f0.g * s.g || f1.b != f0.b * s.b)
                fail_msg("lobe %zu: scaled f (%g,%g,%g) against f·s (%g,%g,%g)", k, f1.r, f1.g, f1.b, f0.r * s.r,
                         f0.g * s.g, f0.b * s.b);
            assert_true(ts_bxdf_pdf(&base[k], wo, wi) == ts_bxdf_pdf(&sc, wo, wi));
            ts_bxdf_sample a, b;
            bool oka = ts_bxdf_sample_f(&base[k], wo, u, &a), okb = ts_bxdf_sample_f(&sc, wo, u, &b);
            assert_true(oka == okb);
            if (!oka) continue;
            assert_true(a.wi.x == b.wi.x && a.wi.y == b.wi.y && a.wi.z == b.wi.z && a.pdf == b.pdf &&
                        a.flags == b.flags);
            assert_true(b.f.r == a.f.r * s.r && b.f.g == a.f.g * s.g && b.f.b == a.f.b * s.b);
            if (base[k].type == TS_BXDF_LAMBERTIAN_TRANSMISSION) {
                assert_true(a.wi.z * wo.z < 0 && (a.flags & TS_BXDF_TRANSMISSION));
                double w = a.f.r * fabsf(a.wi.z) / a.pdf;
                if (fabs(w - 0.6) > 1e-6) fail_msg("lambertian transmission weight %.9g, expected 0.6", w);
            }
        }
    }
    ts_bxdf twice = ts_bxdf_scaled(ts_bxdf_scaled(base[0], s), ts_rgb_gray(0.5f));
    ts_rgb f = ts_bxdf_f(&twice, (ts_vec3){0, 0, 1}, (ts_vec3){0, 0.6f, 0.8f});
    assert_true(rel_close(f.g, 0.8 / TS_PI_D * 0.5 * 0.5, 2e-7));
    /* Lambertian transmission is 0 in pdf on wo's own side. */
    assert_true(ts_bxdf_pdf(&base[4], (ts_vec3){0, 0, 1}, (ts_vec3){0, 0.6f, 0.8f}) == 0);
    assert_true(ts_bxdf_pdf(&base[4], (ts_vec3){0, 0, 1}, (ts_vec3){0, 0.6f, -0.8f}) > 0);
}

/* pbrt-v3's RoughnessToAlpha against the same quartic evaluated in double (relative 1e-5:
 * a few float roundings of terms up to ~8 that cancel to ~0.05, at worst ~2e-6 here), and
 * the α of the roughness values docs/design.md §9 quotes (to its 3 decimals). Below 1e-3
 * and for NaN it is the value at 1e-3. */
static void test_roughness_to_alpha(void **state)
{
    (void)state;
    const double rs[] = {1e-3, 2e-3, 0.01, 0.05, 0.1, 0.3, 0.5, 1, 2, 10};
    for (size_t i = 0; i < sizeof rs / sizeof rs[0]; i++) {
        double x = log(rs[i]);
        double want = 1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x;
        float got = ts_microfacet_roughness_to_alpha((float)rs[i]);
        print_message("RoughnessToAlpha(%g) = %.7f (double %.7f)\n", rs[i], got, want);
        if (!rel_close(got, want, 1e-5)) fail_msg("RoughnessToAlpha(%g) = %.9g, expected %.9g", rs[i], got, want);
    }
    const float quoted[][2] = {{0.001f, 0.047f}, {0.01f, 0.139f}, {0.1f, 0.462f}, {0.5f, 1.131f}};
    for (size_t i = 0; i < 4; i++)
        assert_true(fabsf(ts_microfacet_roughness_to_alpha(quoted[i][0]) - quoted[i][1]) < 5e-4f);
    float lo = ts_microfacet_roughness_to_alpha(1e-3f);
    assert_true(ts_microfacet_roughness_to_alpha(0) == lo && ts_microfacet_roughness_to_alpha(-1) == lo &&
                ts_microfacet_roughness_to_alpha(NAN) == lo);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_consistency), cmocka_unit_test(test_energy), cmocka_unit_test(test_reciprocity),
        cmocka_unit_test(test_no_nan),      cmocka_unit_test(test_chi2_all), cmocka_unit_test(test_sharp_beckmann),
        cmocka_unit_test(test_scaled_and_transmission), cmocka_unit_test(test_roughness_to_alpha),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
