/* bxdf.h — the BxDFs of pbrt-v3 ch. 8 as one tagged struct, in the local shading frame.
 *
 * Design note (docs/style.md, Cycles' closures): a ts_bxdf is a plain value with a type tag;
 * f / pdf / sample dispatch with a switch, so a BSDF is a fixed array of them with no
 * allocation and no function pointers. Directions are unit vectors in the shading frame
 * (+z the shading normal), both pointing away from the surface; wo is towards the viewer.
 * Transport is radiance transport (camera paths): refraction scales radiance by
 * (η_i/η_t)². Every function returns finite, non-negative values for any input,
 * including directions on or below the horizon and wo.z == 0 (then f = pdf = 0 and no
 * sample). Reflection lobes evaluate f with |cosθ| and leave the reflection/transmission
 * decision to the BSDF (which uses the geometric normal, pbrt-v3 §9.1); pdf and sample
 * stay on wo's side. Pure and thread-safe.
 *
 * Sampling contract: ts_bxdf_sample draws wi from u ∈ [0,1]² and reports f(wo, wi),
 * the solid-angle pdf (for specular lobes: the discrete probability of the event, with f
 * carrying the matching delta weight, so f·|cosθi|/pdf is the sample weight either way),
 * the lobe flags of the event and eta = η(wi side) / η(wo side) (1 for reflection). For
 * non-specular lobes f and pdf equal ts_bxdf_f / ts_bxdf_pdf at (wo, wi). */
#ifndef TS_BXDF_H
#define TS_BXDF_H

#include <stdbool.h>
#include <stdint.h>

#include "core/vecmath.h"
#include "materials/fresnel.h"
#include "materials/microfacet.h"

struct ts_fourier_table;

enum {
    TS_BXDF_REFLECTION = 1u << 0,
    TS_BXDF_TRANSMISSION = 1u << 1,
    TS_BXDF_DIFFUSE = 1u << 2,
    TS_BXDF_GLOSSY = 1u << 3,
    TS_BXDF_SPECULAR = 1u << 4,
    TS_BXDF_ALL = 0x1fu,
};

typedef enum ts_bxdf_type {
    TS_BXDF_LAMBERTIAN,             /* r: reflectance; diffuse_coupled: × (1 − rs·F(|cosθo|))(1 − rs·F(|cosθi|)) */
    TS_BXDF_LAMBERTIAN_TRANSMISSION,/* t: f = t/π between opposite hemispheres (pbrt-v3 §8.3) */
    TS_BXDF_OREN_NAYAR,             /* r, on_a, on_b */
    TS_BXDF_MICROFACET_REFLECTION,  /* r, dist, fresnel */
    TS_BXDF_MICROFACET_TRANSMISSION,/* t, dist, eta_a (outside, +z side), eta_b (inside) */
    TS_BXDF_FRESNEL_BLEND,          /* rd = r, rs, dist (α < specular threshold: diffuse part only) */
    TS_BXDF_SPECULAR_REFLECTION,    /* r, fresnel */
    TS_BXDF_SPECULAR_TRANSMISSION,  /* t, eta_a, eta_b */
    TS_BXDF_FRESNEL_SPECULAR,       /* r, t, eta_a, eta_b */
    TS_BXDF_FOURIER,                /* fourier */
} ts_bxdf_type;

typedef struct ts_bxdf {
    ts_bxdf_type type;
    uint32_t flags;     /* TS_BXDF_* of the lobe(s) */
    ts_rgb r, t;        /* reflectance / transmittance scale */
    ts_rgb rs;          /* FresnelBlend specular reflectance at normal incidence */
    float on_a, on_b;   /* Oren–Nayar A and B */
    float eta_a, eta_b; /* indices outside (+z side) and inside */
    bool blend_glossy;  /* FresnelBlend has its glossy term */
    bool diffuse_coupled; /* Lambertian under a specular coat (plastic): see ts_bxdf_lambertian_coupled */
    bool scaled;        /* f (and a sample's f) multiplied by scale: pbrt-v3's ScaledBxDF (mix) */
    ts_rgb scale;
    ts_microfacet dist;
    ts_fresnel fresnel;
    const struct ts_fourier_table *fourier;
} ts_bxdf;

typedef struct ts_bxdf_sample {
    ts_vec3 wi;     /* local frame */
    ts_rgb f;
    float pdf;
    uint32_t flags; /* lobe flags of the sampled event */
    float eta;      /* η on wi's side / η on wo's side; 1 for reflection */
} ts_bxdf_sample;

/* ---- constructors (validate nothing: the scene loader has) ---- */
ts_bxdf ts_bxdf_lambertian(ts_rgb r);
/* Lambertian(r) under a specular coat of scale ks and Fresnel fr (the plastic material):
 * f = r/π · (1 − ks·F(|cosθo|)) · (1 − ks·F(|cosθi|)), per channel. Symmetric in wo and
 * wi (reciprocal); sampled like the Lambertian (cosine-weighted). material.c explains why. */
ts_bxdf ts_bxdf_lambertian_coupled(ts_rgb r, ts_rgb ks, ts_fresnel fr);
ts_bxdf ts_bxdf_oren_nayar(ts_rgb r, float sigma_deg);
ts_bxdf ts_bxdf_microfacet_reflection(ts_rgb r, ts_microfacet dist, ts_fresnel fresnel);
ts_bxdf ts_bxdf_microfacet_transmission(ts_rgb t, ts_microfacet dist, float eta_a, float eta_b);
ts_bxdf ts_bxdf_fresnel_blend(ts_rgb rd, ts_rgb rs, ts_microfacet dist);
/* FresnelBlend without its glossy term (the substrate at α → 0 pairs it with a specular
 * Schlick reflection). */
ts_bxdf ts_bxdf_fresnel_blend_diffuse(ts_rgb rd, ts_rgb rs);
ts_bxdf ts_bxdf_specular_reflection(ts_rgb r, ts_fresnel fresnel);
ts_bxdf ts_bxdf_specular_transmission(ts_rgb t, float eta_a, float eta_b);
ts_bxdf ts_bxdf_fresnel_specular(ts_rgb r, ts_rgb t, float eta_a, float eta_b);
ts_bxdf ts_bxdf_fourier(const struct ts_fourier_table *table);
/* Lambertian transmission (pbrt-v3's LambertianTransmission): f = t/π for wo and wi on
 * opposite sides, cosine-weighted sampling of wo's opposite hemisphere. */
ts_bxdf ts_bxdf_lambertian_transmission(ts_rgb t);
/* b with its f multiplied by s (pdf and sampling unchanged): pbrt-v3's ScaledBxDF, which
 * its MixMaterial wraps around every lobe. Scaling a scaled lobe multiplies the scales. */
ts_bxdf ts_bxdf_scaled(ts_bxdf b, ts_rgb s);

/* ---- evaluation ---- */
ts_rgb ts_bxdf_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi);   /* 0 for specular lobes */
float ts_bxdf_pdf(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi);  /* 0 for specular lobes */
bool ts_bxdf_sample_f(const ts_bxdf *b, ts_vec3 wo, ts_vec2 u, ts_bxdf_sample *out); /* false: no sample */

/* ---- reflectance (pbrt-v3 §8.1.1, §14.1.5), Monte Carlo with caller-given samples ---- */
/* ρ_hd(wo) = ∫ f |cosθi| dωi ≈ (1/n) Σ f |cosθi| / pdf over n samples u[i]. */
ts_rgb ts_bxdf_rho_hd(const ts_bxdf *b, ts_vec3 wo, int n, const ts_vec2 *u);
/* ρ_hh = (1/π) ∫∫ f |cosθo cosθi| dωo dωi, wo uniform on the hemisphere from u_wo[i]. */
ts_rgb ts_bxdf_rho_hh(const ts_bxdf *b, int n, const ts_vec2 *u_wo, const ts_vec2 *u_wi);

/* Refraction of wi about unit n (n on wi's side) with eta = η_i/η_t; false under total
 * internal reflection. */
bool ts_refract(ts_vec3 wi, ts_vec3 n, float eta, ts_vec3 *wt);
static inline ts_vec3 ts_reflect(ts_vec3 wo, ts_vec3 n)
{
    return ts_vec3_sub(ts_vec3_scale(n, 2 * ts_vec3_dot(wo, n)), wo);
}

#endif
