/* test_material_pbrt3.c — pbrt-v3's own materials through the whole BSDF (docs/design.md
 * §4, §8): pbrt-v3's uncoupled plastic, uber (with its opacity's pass-through lobe),
 * translucent and mix, anisotropic rough conductors, dielectrics and substrates (the
 * substrate's own closed forms are tests/test_substrate.c's), remapped roughness.
 * χ² of the BSDF's sampler against its pdf for every lobe combination (the harness also
 * holds each sample's f and pdf to f and pdf evaluated at its direction, 1e-4 relative:
 * tests/chi2_bsdf.h); the white furnace from both sides with the closed-form albedo of
 * every smooth case, the energy rule where pbrt-v3's model keeps it and the measured
 * excess where it does not; a mix is the amount-weighted sum of its materials; remapped
 * roughness is the α it remaps to; reciprocity; finiteness at the limits. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
/* cmocka needs the three above first */
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "chi2_bsdf.h"
#include "core/hash.h"
#include "material_frame.h"
#include "materials/bsdf.h"
#include "materials/fresnel.h"
#include "materials/material.h"
#include "materials/material_desc.h"
#include "materials/microfacet.h"
#include "sampling/sampling.h"
#include "scene/scene.h"
#include "json/scene_json.h"

static const ts_rgb gold_eta = {0.143f, 0.374f, 1.442f}, gold_k = {3.983f, 2.385f, 1.603f};

static ts_material_rgb gray(float v) { return ts_material_rgb_gray(v); }
static ts_material_float num(float v) { return ts_material_float_const(v); }

static ts_material plastic3(float kd, float ks, float r, bool remap)
{
    return (ts_material){.type = TS_MATERIAL_PLASTIC_PBRT3,
                         .diffuse = gray(kd),
                         .specular = gray(ks),
                         .roughness = num(r),
                         .remap_roughness = remap};
}
static ts_material uber(float kd, float ks, float kr, float kt, float op, float eta, float r)
{
    return (ts_material){.type = TS_MATERIAL_UBER,
                         .diffuse = gray(kd),
                         .specular = gray(ks),
                         .reflectance = gray(kr),
                         .transmittance = gray(kt),
                         .opacity = gray(op),
                         .eta = num(eta),
                         .roughness = num(r)};
}
static ts_material translucent(float kd, float ks, float refl, float trans, float r)
{
    return (ts_material){.type = TS_MATERIAL_TRANSLUCENT,
                         .diffuse = gray(kd),
                         .specular = gray(ks),
                         .reflectance = gray(refl),
                         .transmittance = gray(trans),
                         .roughness = num(r)};
}
static ts_material conductor_aniso(ts_rgb eta, ts_rgb k, float au, float av, ts_microfacet_type d)
{
    return (ts_material){.type = TS_MATERIAL_CONDUCTOR,
                         .conductor_eta = ts_material_rgb_const(eta),
                         .conductor_k = ts_material_rgb_const(k),
                         .roughness = num(au),
                         .has_vroughness = true,
                         .vroughness = num(av),
                         .distribution = d};
}
static ts_material dielectric_aniso(float eta, float au, float av)
{
    return (ts_material){.type = TS_MATERIAL_DIELECTRIC,
                         .eta = num(eta),
                         .reflectance = gray(1),
                         .transmittance = gray(1),
                         .roughness = num(au),
                         .has_vroughness = au != av,
                         .vroughness = num(av)};
}
static ts_material diffuse(float r)
{
    return (ts_material){.type = TS_MATERIAL_DIFFUSE, .reflectance = gray(r)};
}
/* A mix of a and b (pointers the caller keeps alive), amount the weight of a. */
static ts_material mix(const ts_material *a, const ts_material *b, float amount)
{
    return (ts_material){.type = TS_MATERIAL_MIX, .amount = gray(amount), .mix = {a, b}};
}

/* ------------------------------------------------------------------ χ² ---- */

/* Harness defaults (10⁶ samples, significance 0.01 Šidák-corrected over
 * TS_CHI2_FAMILY_SIZE), as test_material: ∫pdf equals the fraction of continuous samples
 * within 1e-3 plus 4σ of that binomial fraction. */
static void run_chi2(const char *name, ts_material m, ts_vec3 wo)
{
    ts_chi2_bsdf c;
    canonical_bsdf(&m, &c.b);
    c.wo = ts_vec3_normalize(wo);
    ts_chi2_params p;
    ts_chi2_params_default(&p);
    ts_chi2_result r;
    bool ok = ts_chi2_test(&p, ts_chi2_bsdf_sample, ts_chi2_bsdf_pdf, &c, &r);
    double frac;
    bool norm_ok = ts_chi2_pdf_normalised(&p, &r, &frac);
    print_message("%-52s lobes=%d p=%.4f dof=%3d ∫pdf=%.5f cont=%.5f %s\n", name, c.b.n_bxdfs, r.p_value,
                  r.dof, r.pdf_integral, frac, ok ? "" : r.message);
    assert_true(ok);
    assert_true(norm_ok);
}

static void test_chi2(void **state)
{
    (void)state;
    run_chi2("plastic_pbrt3 kd=0.5 ks=1 α=0.3 θo=40°", plastic3(0.5f, 1, 0.3f, false),
             dir_cos(cos(ts_radians(40)), 0.3));
    run_chi2("plastic_pbrt3 remapped r=0.1 from behind θo=120°", plastic3(0.5f, 1, 0.1f, true),
             dir_cos(cos(ts_radians(120)), 0.3));
    /* All five lobes: pass-through, Lambertian, microfacet, specular R and T. */
    ts_material u5 = uber(0.4f, 0.5f, 0.3f, 0.3f, 0.6f, 1.5f, 0.25f);
    run_chi2("uber 5 lobes op=0.6 α=0.25 θo=50°", u5, dir_cos(cos(ts_radians(50)), 1));
    run_chi2("uber 5 lobes inside θo=150°", u5, dir_cos(cos(ts_radians(150)), 1));
    u5.has_vroughness = true;
    u5.vroughness = num(0.05f);
    run_chi2("uber anisotropic α=(0.25,0.05) θo=60°", u5, dir_cos(cos(ts_radians(60)), 0.7));
    run_chi2("translucent kd=0.5 ks=0.5 α=0.2 θo=35°", translucent(0.5f, 0.5f, 0.6f, 0.4f, 0.2f),
             dir_cos(cos(ts_radians(35)), 0.5));
    run_chi2("translucent from behind θo=140°", translucent(0.5f, 0.5f, 0.6f, 0.4f, 0.2f),
             dir_cos(cos(ts_radians(140)), 0.5));
    ts_material ga = conductor_aniso(gold_eta, gold_k, 0.3f, 0.1f, TS_MICROFACET_GGX);
    ts_material tr = translucent(0.7f, 0.3f, 0.5f, 0.5f, 0.3f);
    run_chi2("mix 0.4·gold ggx α=(0.3,0.1) + 0.6·translucent θo=45°", mix(&ga, &tr, 0.4f),
             dir_cos(cos(ts_radians(45)), 2));
    run_chi2("conductor gold ggx α=(0.05,0.4) θo=60°",
             conductor_aniso(gold_eta, gold_k, 0.05f, 0.4f, TS_MICROFACET_GGX),
             dir_cos(cos(ts_radians(60)), 0.8));
    run_chi2("conductor gold beckmann α=(0.4,0.1) θo=30°",
             conductor_aniso(gold_eta, gold_k, 0.4f, 0.1f, TS_MICROFACET_BECKMANN),
             dir_cos(cos(ts_radians(30)), 0.8));
    run_chi2("dielectric η=1.5 α=(0.1,0.4) θo=40°", dielectric_aniso(1.5f, 0.1f, 0.4f),
             dir_cos(cos(ts_radians(40)), 1.2));
    run_chi2("dielectric η=1.5 α=(0.4,0.1) inside θo=145°", dielectric_aniso(1.5f, 0.4f, 0.1f),
             dir_cos(cos(ts_radians(145)), 1.2));
    run_chi2("substrate kd=.5 ks=.3 α=(0.05,0.4) θo=45°", substrate_aniso(0.5f, 0.3f, 0.05f, 0.4f),
             dir_cos(cos(ts_radians(45)), 0.7));
    run_chi2("substrate kd=.3 ks=.8 α=(0.5,0.08) θo=70°", substrate_aniso(0.3f, 0.8f, 0.5f, 0.08f),
             dir_cos(cos(ts_radians(70)), 2.2));
    ts_material sub = substrate_aniso(0.4f, 0.5f, 0.02f, 0.3f); /* α ≈ (0.19, 0.86) */
    sub.remap_roughness = true;
    run_chi2("substrate remapped r=(0.02,0.3) behind θo=130°", sub, dir_cos(cos(ts_radians(130)), 0.3));
}

/* ------------------------------------------------------------ furnace ---- */

typedef struct albedo {
    double mean, stderr_;
} albedo;

/* f of sample s for flux (green channel): radiance transport's (η_wo/η_wi)² taken back
 * out of every refracting lobe. A specular sample is one lobe (× s.eta² when it
 * refracts); a non-specular one sums the lobes of its kind, and translucent's diffuse
 * transmission (η 1) shares that sum with its microfacet transmission (η 1.5), so each
 * microfacet transmission lobe's f is re-evaluated and scaled by its own η². */
static double flux_f(const ts_bsdf *b, ts_vec3 wo, const ts_bsdf_sample *s)
{
    if (s->flags & TS_BXDF_SPECULAR)
        return s->f.g * ((s->flags & TS_BXDF_TRANSMISSION) ? (double)s->eta * s->eta : 1.0);
    if (!(s->flags & TS_BXDF_TRANSMISSION)) return s->f.g;
    ts_vec3 wol = ts_bsdf_world_to_local(b, wo), wil = ts_bsdf_world_to_local(b, s->wi);
    double f = s->f.g;
    for (int i = 0; i < b->n_bxdfs; i++) {
        const ts_bxdf *x = &b->bxdfs[i];
        if (x->type != TS_BXDF_MICROFACET_TRANSMISSION || (x->flags & TS_BXDF_SPECULAR)) continue;
        double e = wol.z > 0 ? x->eta_b / x->eta_a : x->eta_a / x->eta_b;
        f += ts_bxdf_f(x, wol, wil).g * (e * e - 1);
    }
    return f;
}

/* Directional albedo for flux at wo, channel 1: the mean of f·|cosθi|/pdf with f for flux
 * (flux_f). The lobe pick is
 * jittered-stratified within each of 32 batches of 1024 samples; the standard error is
 * the spread of the 32 independent batch means (Student t, 31 dof). As test_material. */
static albedo flux_albedo(const ts_bsdf *b, ts_vec3 wo, uint64_t seed)
{
    enum { BATCHES = 32, PER = 1024 };
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, seed, 11);
    double sum = 0, sum2 = 0;
    for (int j = 0; j < BATCHES; j++) {
        double bsum = 0;
        for (int i = 0; i < PER; i++) {
            float ul = ((float)i + ts_pcg32_float(&rng)) / PER;
            ts_vec2 u = {ts_pcg32_float(&rng), ts_pcg32_float(&rng)};
            ts_bsdf_sample s;
            if (!ts_bsdf_sample_f(b, wo, ul, u, &s)) continue;
            bsum += flux_f(b, wo, &s) * fabs(ts_vec3_dot(s.wi, b->ns)) / s.pdf;
        }
        bsum /= PER;
        sum += bsum;
        sum2 += bsum * bsum;
    }
    double mean = sum / BATCHES, var = fmax(0, sum2 / BATCHES - mean * mean) / (BATCHES - 1);
    return (albedo){mean, sqrt(var)};
}

/* Closed forms of smooth materials (α = 0, no remapping) at signed cosθo μ, F the one-
 * sided dielectric Fresnel pbrt-v3 uses (ts_fresnel_dielectric: the indices swap below
 * the normal, total internal reflection gives 1):
 *   plastic_pbrt3  kd + ks·F(μ; 1.5 → 1)  (pbrt-v3's swapped indices: F = 1 from the front
 *                  beyond 41.8°, so unit plastic reflects 2 there)
 *   uber           (1 − op) + op·(kd + (ks + kr)·F(μ; 1 → η) + kt·(1 − F))
 *   translucent    kd·(r + t) + ks·(r·F(μ; 1 → 1.5) + t·(1 − F))
 * (flux: refraction's radiance scale taken out; the pass-through lobe carries all). */
static double closed_albedo(const ts_material *m, double mu)
{
    switch (m->type) {
    case TS_MATERIAL_PLASTIC_PBRT3:
        return m->diffuse.value.g + m->specular.value.g * ts_fresnel_dielectric((float)mu, 1.5f, 1);
    case TS_MATERIAL_UBER: {
        double op = m->opacity.value.g, f = ts_fresnel_dielectric((float)mu, 1, m->eta.value);
        return (1 - op) + op * (m->diffuse.value.g + (m->specular.value.g + m->reflectance.value.g) * f +
                                m->transmittance.value.g * (1 - f));
    }
    case TS_MATERIAL_TRANSLUCENT: {
        double f = ts_fresnel_dielectric((float)mu, 1, 1.5f), r = m->reflectance.value.g,
               t = m->transmittance.value.g;
        return m->diffuse.value.g * (r + t) + m->specular.value.g * (r * f + t * (1 - f));
    }
    default:
        return NAN;
    }
}

static const double sweep[] = {1, 0.9, 0.7, 0.5, 0.3, 0.15, 0.05, 0.01};

/* ρ_hd over the sweep of wo on both sides. With closed (a closed form exists): |mean −
 * closed| ≤ 4.5·stderr + 1e-4 (two-sided false failure ~8e-5 per estimate with noise,
 * plus float rounding; 16 estimates per material). With bound > 0: mean ≤ bound +
 * 4.5·stderr (one-sided ~4e-5 per estimate at the bound). Returns the largest mean. */
static double furnace(const char *name, ts_material m, double bound, bool closed)
{
    ts_bsdf b;
    canonical_bsdf(&m, &b);
    double worst = 0, worst_cos = 0;
    for (int side = 0; side < 2; side++)
        for (size_t k = 0; k < sizeof sweep / sizeof sweep[0]; k++) {
            double ct = side ? -sweep[k] : sweep[k];
            albedo a = flux_albedo(&b, dir_cos(ct, 0.4 + (double)k), 300 + k + 20 * (uint64_t)side);
            if (a.mean > worst) {
                worst = a.mean;
                worst_cos = ct;
            }
            if (bound > 0 && !(a.mean <= bound + 4.5 * a.stderr_))
                print_error("%s: albedo %.5f ± %.5f at cosθo=%g exceeds %g\n", name, a.mean, a.stderr_, ct,
                            bound);
            if (bound > 0) assert_true(a.mean <= bound + 4.5 * a.stderr_);
            if (!closed) continue;
            double want = closed_albedo(&m, ct);
            if (!(fabs(a.mean - want) <= 4.5 * a.stderr_ + 1e-4))
                print_error("%s: albedo %.6f ± %.6f at cosθo=%g, closed form %.6f\n", name, a.mean, a.stderr_,
                            ct, want);
            assert_true(fabs(a.mean - want) <= 4.5 * a.stderr_ + 1e-4);
        }
    print_message("%-50s max ρ_hd %.4f at cosθo=%g%s\n", name, worst, worst_cos,
                  closed ? " (= closed form)" : "");
    return worst;
}

/* pbrt-v3's materials are uncoupled sums of lobes, so they keep the energy rule of §8 only
 * where their parameters sum to at most 1 (pbrt-v3's model, kept exactly); with unit
 * parameters they exceed it, and the test measures by how much (docs/design.md §4
 * quotes these maxima). The coupled plastic's ≤ 1 is test_material's. */
static void test_furnace(void **state)
{
    (void)state;
    char name[96];
    /* Smooth closed forms, both sides. */
    furnace("plastic_pbrt3 kd=ks=1 smooth", plastic3(1, 1, 0, false), 0, true);
    furnace("plastic_pbrt3 kd=0.5 ks=0.5 smooth", plastic3(0.5f, 0.5f, 0, false), 1.01, true);
    furnace("uber smooth kd=.2 ks=.3 kr=.25 kt=.25 op=.7", uber(0.2f, 0.3f, 0.25f, 0.25f, 0.7f, 1.5f, 0),
            1.01, true);
    furnace("uber smooth η=1.33 kt=1 op=1", uber(0, 0, 0, 1, 1, 1.33f, 0), 1.01, true);
    furnace("translucent smooth kd=.5 ks=.5 r=.6 t=.4", translucent(0.5f, 0.5f, 0.6f, 0.4f, 0), 1.01, true);
    /* Rough: the rule where the parameters sum to ≤ 1, the excess measured with unit ones. */
    const float rs[] = {0.01f, 0.1f, 0.3f, 1.0f};
    double mx = 0;
    for (size_t i = 0; i < 4; i++) {
        snprintf(name, sizeof name, "plastic_pbrt3 kd=0.6 ks=0.4 α=%g", rs[i]);
        furnace(name, plastic3(0.6f, 0.4f, rs[i], false), 1.01, false);
        snprintf(name, sizeof name, "plastic_pbrt3 kd=ks=1 α=%g", rs[i]);
        mx = fmax(mx, furnace(name, plastic3(1, 1, rs[i], false), 0, false));
        snprintf(name, sizeof name, "uber kd=.3 ks=.3 kr=.2 kt=.2 op=.8 α=%g", rs[i]);
        furnace(name, uber(0.3f, 0.3f, 0.2f, 0.2f, 0.8f, 1.5f, rs[i]), 1.01, false);
        snprintf(name, sizeof name, "translucent kd=.5 ks=.5 r=.5 t=.5 α=%g", rs[i]);
        furnace(name, translucent(0.5f, 0.5f, 0.5f, 0.5f, rs[i]), 1.01, false);
    }
    print_message("=> plastic_pbrt3 kd=ks=1 rough: max %.4f (pbrt-v3's model)\n", mx);
    mx = furnace("translucent kd=ks=1 r=t=1 α=0.1", translucent(1, 1, 1, 1, 0.1f), 0, false);
    mx = fmax(mx, furnace("uber kd=ks=kr=kt=1 α=0.1", uber(1, 1, 1, 1, 1, 1.5f, 0.1f), 0, false));
    print_message("=> translucent and uber with unit parameters: max %.4f (pbrt-v3's model)\n", mx);
    /* Anisotropic lobes with F = 1 (conductor η = k = 0) or a dielectric keep the rule. */
    furnace("conductor F=1 ggx α=(0.05,0.5)",
            conductor_aniso(ts_rgb_gray(0), ts_rgb_gray(0), 0.05f, 0.5f, TS_MICROFACET_GGX), 1.01, false);
    furnace("conductor F=1 beckmann α=(0.6,0.02)",
            conductor_aniso(ts_rgb_gray(0), ts_rgb_gray(0), 0.6f, 0.02f, TS_MICROFACET_BECKMANN), 1.01,
            false);
    furnace("dielectric η=1.5 α=(0.02,0.6)", dielectric_aniso(1.5f, 0.02f, 0.6f), 1.01, false);
    /* The anisotropic substrate with white Kd reflects at most 1 (stricter than the rule):
     * Ks = 1 (all glossy, (1 − Ks) removes the diffuse term) and Ks = 0.04; 96 estimates,
     * false failure ≤ 4e-3 even at the bound, measured maxima 0.79 and 0.97. */
    const float sa[][2] = {{0.05f, 0.5f}, {0.5f, 0.05f}, {0.01f, 1.0f}};
    mx = 0;
    for (size_t i = 0; i < 3; i++) {
        snprintf(name, sizeof name, "substrate kd=ks=1 α=(%g,%g)", sa[i][0], sa[i][1]);
        mx = fmax(mx, furnace(name, substrate_aniso(1, 1, sa[i][0], sa[i][1]), 1, false));
        snprintf(name, sizeof name, "substrate kd=1 ks=0.04 α=(%g,%g)", sa[i][0], sa[i][1]);
        mx = fmax(mx, furnace(name, substrate_aniso(1, 0.04f, sa[i][0], sa[i][1]), 1, false));
    }
    print_message("=> anisotropic substrate with white Kd: max %.4f\n", mx);
}

/* A mix's albedo is the amount-weighted sum of its two materials' (each lobe scaled,
 * none re-weighted in the sampling): smooth glass (albedo 1) and Lambertian 0.6 at amount
 * 0.3 → 0.3 + 0.7·0.6 = 0.72 at every wo, both sides (the Lambertian reflects behind too).
 * Tolerance as the furnace's closed forms. And amount 1 / 0 is exactly the first / second
 * material: the same f and pdf (the other material's lobes scaled to black are left out). */
static void test_mix(void **state)
{
    (void)state;
    ts_material glass = dielectric_aniso(1.5f, 0, 0), lam = diffuse(0.6f);
    ts_material mx = mix(&glass, &lam, 0.3f);
    ts_bsdf b;
    canonical_bsdf(&mx, &b);
    assert_int_equal(b.n_bxdfs, 2);
    for (int side = 0; side < 2; side++)
        for (size_t k = 0; k < sizeof sweep / sizeof sweep[0]; k++) {
            double ct = side ? -sweep[k] : sweep[k];
            albedo a = flux_albedo(&b, dir_cos(ct, 1 + (double)k), 900 + k + 20 * (uint64_t)side);
            if (!(fabs(a.mean - 0.72) <= 4.5 * a.stderr_ + 1e-4))
                print_error("mix: albedo %.6f ± %.6f at cosθo=%g, expected 0.72\n", a.mean, a.stderr_, ct);
            assert_true(fabs(a.mean - 0.72) <= 4.5 * a.stderr_ + 1e-4);
        }
    ts_material pl = plastic3(0.5f, 0.5f, 0.2f, false), tr = translucent(0.5f, 0.5f, 0.5f, 0.5f, 0.3f);
    for (int which = 0; which < 2; which++) {
        ts_material m = mix(&pl, &tr, which ? 0.0f : 1.0f);
        ts_bsdf bm, bo;
        canonical_bsdf(&m, &bm);
        canonical_bsdf(which ? &tr : &pl, &bo);
        assert_int_equal(bm.n_bxdfs, bo.n_bxdfs);
        ts_pcg32 rng;
        ts_pcg32_seed(&rng, 4, 4);
        for (int i = 0; i < 5000; i++) {
            ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec3 wi = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_rgb f1 = ts_bsdf_f(&bm, wo, wi), f2 = ts_bsdf_f(&bo, wo, wi);
            assert_true(f1.r == f2.r && f1.g == f2.g && f1.b == f2.b);
            assert_true(ts_bsdf_pdf(&bm, wo, wi) == ts_bsdf_pdf(&bo, wo, wi));
        }
    }
    /* The lobe bound the builder enforces: uber 5 + translucent 4 = 9 > 8. */
    ts_material u = uber(1, 1, 1, 1, 0.5f, 1.5f, 0.1f);
    ts_material big = mix(&u, &tr, 0.5f), inner = mix(&pl, &tr, 0.5f), nested = mix(&inner, &pl, 0.5f);
    assert_int_equal(ts_material_max_lobes(&big), 9);
    assert_int_equal(ts_material_max_lobes(&nested), 8);
    canonical_bsdf(&nested, &b);
    assert_int_equal(b.n_bxdfs, 8);
}

/* remap_roughness: the BSDF is the one built from α = RoughnessToAlpha(r) directly, bit
 * for bit (the same float α reaches the same code), on every material that has it and on
 * both axes; glass with both roughnesses 0 stays smooth (pbrt-v3's isSpecular before the
 * remapping), metal with roughness 0 becomes α = 0.0473 (pbrt-v3 has no such exception). */
static void test_remap(void **state)
{
    (void)state;
    const float r = 0.2f, rv = 0.05f;
    float a = ts_microfacet_roughness_to_alpha(r), av = ts_microfacet_roughness_to_alpha(rv);
    ts_material pairs[][2] = {
        {plastic3(0.5f, 0.5f, r, true), plastic3(0.5f, 0.5f, a, false)},
        {uber(0.3f, 0.4f, 0.1f, 0.1f, 0.9f, 1.5f, r), uber(0.3f, 0.4f, 0.1f, 0.1f, 0.9f, 1.5f, a)},
        {translucent(0.5f, 0.5f, 0.5f, 0.5f, r), translucent(0.5f, 0.5f, 0.5f, 0.5f, a)},
        {conductor_aniso(gold_eta, gold_k, r, rv, TS_MICROFACET_GGX),
         conductor_aniso(gold_eta, gold_k, a, av, TS_MICROFACET_GGX)},
        {dielectric_aniso(1.5f, r, rv), dielectric_aniso(1.5f, a, av)},
        {(ts_material){.type = TS_MATERIAL_SUBSTRATE,
                       .diffuse = gray(0.5f),
                       .specular = gray(0.1f),
                       .roughness = num(r)},
         (ts_material){.type = TS_MATERIAL_SUBSTRATE,
                       .diffuse = gray(0.5f),
                       .specular = gray(0.1f),
                       .roughness = num(a)}},
        {(ts_material){
             .type = TS_MATERIAL_PLASTIC, .diffuse = gray(0.5f), .specular = gray(0.5f), .roughness = num(r)},
         (ts_material){.type = TS_MATERIAL_PLASTIC,
                       .diffuse = gray(0.5f),
                       .specular = gray(0.5f),
                       .roughness = num(a)}},
    };
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 8, 8);
    for (size_t k = 0; k < sizeof pairs / sizeof pairs[0]; k++) {
        pairs[k][0].remap_roughness = true;
        ts_bsdf b0, b1;
        canonical_bsdf(&pairs[k][0], &b0);
        canonical_bsdf(&pairs[k][1], &b1);
        for (int i = 0; i < 5000; i++) {
            ts_vec3 wo = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec3 wi = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_rgb f0 = ts_bsdf_f(&b0, wo, wi), f1 = ts_bsdf_f(&b1, wo, wi);
            if (!(f0.r == f1.r && f0.g == f1.g && f0.b == f1.b &&
                  ts_bsdf_pdf(&b0, wo, wi) == ts_bsdf_pdf(&b1, wo, wi)))
                fail_msg("material %zu: remapped f %g against α-given %g", k, f0.g, f1.g);
        }
    }
    ts_material g = dielectric_aniso(1.5f, 0, 0);
    g.remap_roughness = true;
    ts_bsdf b;
    canonical_bsdf(&g, &b);
    assert_int_equal(b.n_bxdfs, 1);
    assert_true(b.bxdfs[0].type == TS_BXDF_FRESNEL_SPECULAR);
    ts_material metal = conductor_aniso(gold_eta, gold_k, 0, 0, TS_MICROFACET_GGX);
    metal.remap_roughness = true;
    canonical_bsdf(&metal, &b);
    assert_true(b.bxdfs[0].type == TS_BXDF_MICROFACET_REFLECTION &&
                fabsf(b.bxdfs[0].dist.alpha_x - 0.04727f) < 1e-4f);
    /* Anisotropic with one axis below the specular threshold: that axis is raised to it. */
    ts_material c1 = conductor_aniso(gold_eta, gold_k, 0.3f, 0, TS_MICROFACET_GGX);
    canonical_bsdf(&c1, &b);
    assert_true(b.bxdfs[0].type == TS_BXDF_MICROFACET_REFLECTION &&
                b.bxdfs[0].dist.alpha_y == TS_MICROFACET_SPECULAR_ALPHA && b.bxdfs[0].dist.alpha_x == 0.3f);
}

/* f(wo, wi) = f(wi, wo) for reflection pairs of the new materials and the anisotropic
 * lobes (relative 1e-5: the same terms in another order), and for translucent's diffuse
 * transmission (t/π both ways; its microfacet transmission is not symmetric in radiance
 * transport and is left out by giving it no specular). 10⁴ random pairs each. */
static void test_reciprocity(void **state)
{
    (void)state;
    ts_material ms[] = {
        plastic3(0.8f, 0.6f, 0.2f, true),
        uber(0.3f, 0.5f, 0, 0, 1, 1.5f, 0.3f),
        conductor_aniso(gold_eta, gold_k, 0.05f, 0.5f, TS_MICROFACET_GGX),
        conductor_aniso(gold_eta, gold_k, 0.4f, 0.1f, TS_MICROFACET_BECKMANN),
        translucent(0.7f, 0, 0.4f, 0.6f, 0.2f),
        substrate_aniso(0.7f, 0.3f, 0.05f, 0.5f),
        substrate_aniso(1, 1, 0.6f, 0.02f),
    };
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 3, 3);
    for (size_t k = 0; k < sizeof ms / sizeof ms[0]; k++) {
        ts_bsdf b;
        canonical_bsdf(&ms[k], &b);
        for (int i = 0; i < 10000; i++) {
            ts_vec3 a = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_vec3 c = ts_sample_uniform_sphere((ts_vec2){ts_pcg32_float(&rng), ts_pcg32_float(&rng)});
            ts_rgb f1 = ts_bsdf_f(&b, a, c), f2 = ts_bsdf_f(&b, c, a);
            float m = fmaxf(fmaxf(f1.r, f1.g), f1.b);
            if (!(fabsf(f1.r - f2.r) <= 1e-5f * m + 1e-12f && fabsf(f1.g - f2.g) <= 1e-5f * m + 1e-12f &&
                  fabsf(f1.b - f2.b) <= 1e-5f * m + 1e-12f))
                fail_msg("material %zu not reciprocal: %.9g vs %.9g", k, f1.g, f2.g);
        }
    }
}

/* Finiteness at the limits (docs/design.md §8): every new material and the anisotropic
 * ones at roughness 0, 1e-8 and 1, remapped and not, η = 1 for uber, wo and wi on and
 * below the horizon and at the poles, u at 0 and 1 − 2⁻²⁴: f, pdf and samples finite and
 * ≥ 0, and wo on the horizon gives no sample. */
static void test_no_nan(void **state)
{
    (void)state;
    const float rs[] = {0, 1e-8f, 1};
    const ts_vec3 dirs[] = {{0, 0, 1},       {0, 0, -1},       {1, 0, 0},     {0.6f, 0.8f, 0},
                            {0.6f, 0, 0.8f}, {0.6f, 0, -0.8f}, {1, 0, 1e-7f}, {0, 1, -1e-7f}};
    const float us[] = {0, 0.5f, 1 - 0x1p-24f};
    for (size_t a = 0; a < 3; a++)
        for (int remap = 0; remap < 2; remap++) {
            float r = rs[a];
            ts_material tr = translucent(1, 1, 1, 1, r), pl = plastic3(1, 1, r, remap);
            ts_material ms[] = {
                pl,
                uber(1, 1, 1, 1, 0.5f, 1.5f, r),
                uber(1, 1, 1, 1, 0.5f, 1, r),
                tr,
                conductor_aniso(gold_eta, gold_k, r, 0.3f, TS_MICROFACET_GGX),
                conductor_aniso(gold_eta, gold_k, 0.3f, r, TS_MICROFACET_BECKMANN),
                dielectric_aniso(1.5f, r, 0.2f),
                dielectric_aniso(1, r, r),
                mix(&pl, &tr, 0.5f),
                substrate_aniso(1, 1, r, 0.3f),
                substrate_aniso(0.5f, 0.04f, 0.3f, r),
            };
            for (size_t k = 0; k < sizeof ms / sizeof ms[0]; k++) {
                ms[k].remap_roughness = remap;
                ts_bsdf b;
                canonical_bsdf(&ms[k], &b);
                for (size_t i = 0; i < sizeof dirs / sizeof dirs[0]; i++) {
                    ts_vec3 wo = ts_vec3_normalize(dirs[i]);
                    for (size_t j = 0; j < sizeof dirs / sizeof dirs[0]; j++) {
                        ts_vec3 wi = ts_vec3_normalize(dirs[j]);
                        ts_rgb f = ts_bsdf_f(&b, wo, wi);
                        float p = ts_bsdf_pdf(&b, wo, wi);
                        if (!(ts_rgb_is_finite(f) && f.r >= 0 && f.g >= 0 && f.b >= 0 && isfinite(p) &&
                              p >= 0))
                            fail_msg("material %zu r=%g remap=%d: f %g pdf %g at dirs %zu %zu", k, r, remap,
                                     f.g, p, i, j);
                    }
                    for (size_t x = 0; x < 3; x++)
                        for (size_t y = 0; y < 3; y++)
                            for (size_t z = 0; z < 3; z++) {
                                ts_bsdf_sample s;
                                if (!ts_bsdf_sample_f(&b, wo, us[x], (ts_vec2){us[y], us[z]}, &s)) continue;
                                if (wo.z == 0) fail_msg("material %zu sampled at wo on the horizon", k);
                                if (!(ts_vec3_is_finite(s.wi) && isfinite(s.pdf) && s.pdf > 0 &&
                                      ts_rgb_is_finite(s.f) && s.f.r >= 0 && s.f.g >= 0 && s.f.b >= 0))
                                    fail_msg("material %zu r=%g: sample f %g pdf %g", k, r, s.f.g, s.pdf);
                            }
                }
            }
        }
}

/* Scene format v1 to the builder's fields: pbrt-v3's defaults (but remap_roughness false),
 * uroughness / vroughness each defaulting to roughness (anisotropic only when they differ),
 * mix's names resolved to the scene's materials in order, amount per channel. */
static void test_json(void **state)
{
    (void)state;
    const char *doc =
        "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{"
        "\"p\":{\"type\":\"plastic_pbrt3\"},"
        "\"u\":{\"type\":\"uber\",\"roughness\":0.3,\"vroughness\":0.05,\"remap_roughness\":true},"
        "\"t\":{\"type\":\"translucent\",\"transmittance\":0.7},"
        "\"c\":{\"type\":\"conductor\",\"eta\":0.2,\"k\":3,\"uroughness\":0.2},"
        "\"g\":{\"type\":\"dielectric\",\"uroughness\":0.1,\"vroughness\":0.1},"
        "\"m\":{\"type\":\"mix\",\"materials\":[\"t\",\"p\"],\"amount\":[0.2,0.4,0.6]}}}";
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    assert_int_equal(s->n_materials, 6);
    const ts_material *p = &s->materials[0], *u = &s->materials[1], *t = &s->materials[2],
                      *c = &s->materials[3], *g = &s->materials[4], *m = &s->materials[5];
    assert_true(p->type == TS_MATERIAL_PLASTIC_PBRT3 && p->diffuse.value.g == 0.25f &&
                p->specular.value.g == 0.25f && p->roughness.value == 0.1f && !p->remap_roughness &&
                !p->has_vroughness);
    assert_true(u->type == TS_MATERIAL_UBER && u->remap_roughness && u->roughness.value == 0.3f &&
                u->has_vroughness && u->vroughness.value == 0.05f && u->eta.value == 1.5f &&
                u->opacity.value.g == 1 && u->reflectance.value.g == 0 && u->transmittance.value.g == 0);
    assert_true(t->type == TS_MATERIAL_TRANSLUCENT && t->reflectance.value.g == 0.5f &&
                t->transmittance.value.g == 0.7f);
    /* uroughness alone: u = 0.2, v = roughness's default 0.01. */
    assert_true(c->roughness.value == 0.2f && c->has_vroughness && c->vroughness.value == 0.01f);
    assert_true(g->roughness.value == 0.1f && !g->has_vroughness);
    assert_true(m->type == TS_MATERIAL_MIX && m->mix[0] == t && m->mix[1] == p && m->amount.value.r == 0.2f &&
                m->amount.value.b == 0.6f);
    ts_scene_destroy(s);

    /* Textured: a roughness texture survives the absent uroughness / vroughness, a mix
     * whose amount (or whose material) is textured is textured. */
    const char *tdoc = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},"
                       "\"textures\":{\"r\":{\"type\":\"checkerboard\",\"kind\":\"float\",\"tex1\":0.1,"
                       "\"tex2\":0.3}},\"materials\":{"
                       "\"c\":{\"type\":\"conductor\",\"eta\":0.2,\"k\":3,\"roughness\":\"r\"},"
                       "\"d\":{\"type\":\"diffuse\"},"
                       "\"m1\":{\"type\":\"mix\",\"materials\":[\"d\",\"d\"],\"amount\":\"r\"},"
                       "\"m2\":{\"type\":\"mix\",\"materials\":[\"d\",\"c\"]}}}";
    if (ts_scene_load_text(tdoc, strlen(tdoc), NULL, "t", NULL, &s, &err)) fail_msg("%s", err.message);
    assert_true(s->materials[0].roughness.tex && !s->materials[0].has_vroughness && s->materials[0].textured);
    assert_true(!s->materials[1].textured && s->materials[2].textured && s->materials[3].textured);
    ts_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json),        cmocka_unit_test(test_mix),    cmocka_unit_test(test_remap),
        cmocka_unit_test(test_reciprocity), cmocka_unit_test(test_no_nan), cmocka_unit_test(test_furnace),
        cmocka_unit_test(test_chi2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
