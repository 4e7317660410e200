/* microfacet.h — Trowbridge–Reitz (GGX) and Beckmann microfacet distributions with the
 * Smith masking function and sampling of visible normals (pbrt-v3 §8.4, Heitz 2014/2018).
 *
 * Design note: a ts_microfacet is a tagged value (type, αx, αy) in the shading frame
 * (+z the macro normal). All angles are computed from the x and y components of the unit
 * vectors (sin²θ = x² + y²), which stay accurate for the near-normal half vectors of very
 * smooth surfaces, where 1 − z² would cancel. α below TS_MICROFACET_MIN_ALPHA is raised
 * to it so every function stays finite; materials treat α < TS_MICROFACET_SPECULAR_ALPHA
 * as a perfectly specular surface instead. Λ for Beckmann is the exact erfc form, so the
 * visible-normal sampling (exact inversion of the slope CDF) matches D_wo exactly.
 * Pure and thread-safe. */
#ifndef TS_MICROFACET_H
#define TS_MICROFACET_H

#include "core/vecmath.h"

#define TS_MICROFACET_MIN_ALPHA 1e-7f
#define TS_MICROFACET_SPECULAR_ALPHA 1e-4f

typedef enum ts_microfacet_type {
    TS_MICROFACET_GGX, /* Trowbridge–Reitz */
    TS_MICROFACET_BECKMANN,
} ts_microfacet_type;

typedef struct ts_microfacet {
    ts_microfacet_type type;
    float alpha_x, alpha_y;
} ts_microfacet;

/* α clamped to [TS_MICROFACET_MIN_ALPHA, 1e4]; NaN becomes the minimum. */
ts_microfacet ts_microfacet_make(ts_microfacet_type type, float alpha_x, float alpha_y);

/* True if the surface is smooth enough to be treated as a specular interface. */
static inline bool ts_microfacet_is_specular(float alpha_x, float alpha_y)
{
    return !(alpha_x >= TS_MICROFACET_SPECULAR_ALPHA) || !(alpha_y >= TS_MICROFACET_SPECULAR_ALPHA);
}

/* pbrt-v3's RoughnessToAlpha (TrowbridgeReitzDistribution's, which its Beckmann
 * distribution shares): α = 1.62142 + 0.819955x + 0.1734x² + 0.0171201x³ +
 * 0.000640711x⁴ with x = ln max(roughness, 1e-3), in float and in pbrt-v3's order of
 * operations, so the same roughness gives the same α bit for bit. Its minimum, at
 * roughness ≤ 1e-3, is α ≈ 0.0472; NaN gives that minimum too. The materials' `remap
 * roughness` flag (material.h) applies it. */
float ts_microfacet_roughness_to_alpha(float roughness);

/* Normal distribution D(wh) (per unit solid angle of wh, ∫ D cosθh dωh = 1). */
float ts_microfacet_d(const ts_microfacet *m, ts_vec3 wh);
/* Smith Λ(w), G1(w) = 1 / (1 + Λ(w)), and the height-correlated G(wo, wi). */
float ts_microfacet_lambda(const ts_microfacet *m, ts_vec3 w);
float ts_microfacet_g1(const ts_microfacet *m, ts_vec3 w);
float ts_microfacet_g(const ts_microfacet *m, ts_vec3 wo, ts_vec3 wi);

/* A microfacet normal from the distribution of normals visible from wo, D_wo(wh) =
 * G1(wo) max(0, wo·wh) D(wh) / |cosθo|, on wo's side of the surface (wo.z < 0 is
 * handled by symmetry). u ∈ [0,1]². Returns +z if wo.z == 0. */
ts_vec3 ts_microfacet_sample_wh(const ts_microfacet *m, ts_vec3 wo, ts_vec2 u);
/* D_wo(wh) = G1(wo) |wo·wh| D(wh) / |cosθo| (0 if wo.z == 0): the density of sample_wh
 * for wh on wo's side with wo·wh > 0. */
float ts_microfacet_pdf(const ts_microfacet *m, ts_vec3 wo, ts_vec3 wh);

#endif
