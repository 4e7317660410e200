/* material.c — scene materials to BSDFs (see material.h).
 *
 * Design note — plastic departs from pbrt-v3. pbrt-v3's PlasticMaterial adds a
 * Lambertian(kd) and a Fresnel-weighted specular lobe(ks) without coupling them, so with
 * kd = ks = 1 it reflects up to 1 + F: about 1.04 at normal incidence, ~2 at grazing.
 * The energy rule of docs/design.md §8 — no material with unit parameters reflects more
 * than 1.01 — wins over pbrt-v3 (a decision, docs/design.md §4), so the diffuse lobe is
 * the light that passes the coat twice:
 *     f_d(wo, wi) = kd/π · (1 − ks·F(|cosθo|)) · (1 − ks·F(|cosθi|)),
 * F the dielectric Fresnel from 1 into 1.5 the specular lobe uses (ts_bxdf_lambertian_
 * coupled). Why this form rather than 1 − the specular lobe's directional albedo E(wo):
 *  - reciprocity holds by construction (the factor is symmetric), while 1 − E(wo) alone
 *    is not reciprocal and its symmetric form (1 − E(o))(1 − E(i))/(1 − Ē) (Kelemen)
 *    needs an albedo table per roughness;
 *  - it is closed-form, costs two Fresnel evaluations, and keeps cosine sampling exact;
 *  - the bound is exact for the smooth coat: albedo = ks·F(o) + kd(1 − ks·F(o))(1 − ks·F̄)
 *    ≤ ks·F(o) + (1 − ks·F(o)) = 1, F̄ = 2∫F(μ)μ dμ, for kd, ks ≤ 1; for the rough coat
 *    the specular lobe reflects ≤ ks·F averaged over visible microfacets minus its
 *    shadowing loss, and test_material proves the 1.01 bound across roughness and wo.
 * It is not energy-*preserving*, which the energy rule does not ask for: light reflected back
 * down by the coat is not re-added, so kd = ks = 1 smooth plastic reflects 0.91 at normal
 * incidence rising to ~1 at grazing, and rough plastic (whose microfacet lobe also loses
 * its shadowed energy) at most 0.89 (α = 1) to 0.99 (α → 0) (test_material prints them).
 * Substrate (FresnelBlend) is already coupled in its own formula and is pbrt-v3's.
 *
 * The coat is two-sided: seen from behind (wo below the shading normal: a one-sided
 * surface's back, a leaf, an open box seen from inside) light still arrives at the coat
 * from the air, so its Fresnel term is F from 1 into 1.5 at |cosθ| on both sides
 * (ts_fresnel_make_dielectric_two_sided) — the coupled diffuse lobe's own |cos| rule.
 * A one-sided dielectric Fresnel swapped the indices below the normal and totally
 * reflected beyond 41.8° while the diffuse lobe still took (1 − F(|cos|)), so kd = ks = 1
 * reflected 1.86 at cosθo = −0.7 (smooth) and 1.66 (α = 0.1); now every albedo is the
 * front side's (test_material's furnace sweeps both sides of every material). */
#include "materials/material.h"

#include "materials/bsdf.h"
#include "materials/fourier_bsdf.h"
#include "materials/microfacet.h"

static bool nonblack(ts_rgb c) { return c.r > 0 || c.g > 0 || c.b > 0; }

void ts_material_bsdf(const ts_material *m, const ts_interaction *si, ts_bsdf *out)
{
    float eta = 1;
    if (m->type == TS_MATERIAL_DIELECTRIC) eta = m->eta;
    if (m->type == TS_MATERIAL_FOURIER && m->fourier) eta = m->fourier->eta;
    ts_bsdf_init(out, si->n, si->ns, si->dpdu, eta);

    float alpha = m->roughness;
    bool smooth = ts_microfacet_is_specular(alpha, alpha);
    switch (m->type) {
    case TS_MATERIAL_DIFFUSE:
        if (!nonblack(m->reflectance)) break;
        if (m->sigma_deg > 0) ts_bsdf_add(out, ts_bxdf_oren_nayar(m->reflectance, m->sigma_deg));
        else ts_bsdf_add(out, ts_bxdf_lambertian(m->reflectance));
        break;
    case TS_MATERIAL_MIRROR:
        if (nonblack(m->reflectance)) ts_bsdf_add(out, ts_bxdf_specular_reflection(m->reflectance, ts_fresnel_one()));
        break;
    case TS_MATERIAL_DIELECTRIC: {
        if (!nonblack(m->reflectance) && !nonblack(m->transmittance)) break;
        if (smooth) {
            ts_bsdf_add(out, ts_bxdf_fresnel_specular(m->reflectance, m->transmittance, 1, m->eta));
            break;
        }
        ts_microfacet d = ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha);
        if (nonblack(m->reflectance))
            ts_bsdf_add(out, ts_bxdf_microfacet_reflection(m->reflectance, d, ts_fresnel_make_dielectric(1, m->eta)));
        if (nonblack(m->transmittance))
            ts_bsdf_add(out, ts_bxdf_microfacet_transmission(m->transmittance, d, 1, m->eta));
        break;
    }
    case TS_MATERIAL_CONDUCTOR: {
        ts_fresnel fr = ts_fresnel_make_conductor(1, m->conductor_eta, m->conductor_k);
        if (smooth) ts_bsdf_add(out, ts_bxdf_specular_reflection(ts_rgb_gray(1), fr));
        else
            ts_bsdf_add(out, ts_bxdf_microfacet_reflection(ts_rgb_gray(1), ts_microfacet_make(m->distribution, alpha, alpha),
                                                           fr));
        break;
    }
    case TS_MATERIAL_PLASTIC: {
        ts_fresnel fr = ts_fresnel_make_dielectric_two_sided(1, 1.5f);
        if (nonblack(m->diffuse)) ts_bsdf_add(out, ts_bxdf_lambertian_coupled(m->diffuse, m->specular, fr));
        if (!nonblack(m->specular)) break;
        if (smooth) ts_bsdf_add(out, ts_bxdf_specular_reflection(m->specular, fr));
        else
            ts_bsdf_add(out, ts_bxdf_microfacet_reflection(m->specular, ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha),
                                                           fr));
        break;
    }
    case TS_MATERIAL_SUBSTRATE:
        if (smooth) {
            ts_bsdf_add(out, ts_bxdf_fresnel_blend_diffuse(m->diffuse, m->specular));
            ts_bsdf_add(out, ts_bxdf_specular_reflection(ts_rgb_gray(1), ts_fresnel_make_schlick(m->specular)));
        } else {
            ts_bsdf_add(out, ts_bxdf_fresnel_blend(m->diffuse, m->specular,
                                                   ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha)));
        }
        break;
    case TS_MATERIAL_FOURIER:
        if (m->fourier) ts_bsdf_add(out, ts_bxdf_fourier(m->fourier));
        break;
    }
}
