/* material.c — scene materials to BSDFs (see material.h). */
#include "material.h"

#include "bsdf.h"
#include "fourier_bsdf.h"
#include "microfacet.h"

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
        if (nonblack(m->diffuse)) ts_bsdf_add(out, ts_bxdf_lambertian(m->diffuse));
        if (!nonblack(m->specular)) break;
        ts_fresnel fr = ts_fresnel_make_dielectric(1, 1.5f);
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
