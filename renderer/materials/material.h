/* material.h — the materials of scene format v1 (docs/design.md §4) as parameters, and the
 * mapping from a material at a hit to its BSDF.
 *
 * Design note: a material is plain data filled by the scene loader (which validates every
 * value); ts_material_bsdf builds the BSDF for one shading point into caller storage with
 * no allocation (the hot path). `roughness` is the microfacet α, no remapping (pbrt-v3
 * meaning). Materials are immutable after scene build and shared by all threads. */
#ifndef TS_MATERIAL_H
#define TS_MATERIAL_H

#include <stdbool.h>

#include "core/vecmath.h"
#include "geometry/interaction.h"
#include "materials/microfacet.h" /* ts_microfacet_type */

typedef enum ts_material_type {
    TS_MATERIAL_DIFFUSE,    /* reflectance, sigma (degrees; Oren–Nayar if > 0) */
    TS_MATERIAL_MIRROR,     /* reflectance */
    TS_MATERIAL_DIELECTRIC, /* eta, reflectance, transmittance, roughness (0 = smooth) */
    TS_MATERIAL_CONDUCTOR,  /* eta[rgb], k[rgb], roughness, distribution */
    TS_MATERIAL_PLASTIC,    /* diffuse, specular, roughness */
    TS_MATERIAL_SUBSTRATE,  /* diffuse, specular, roughness (FresnelBlend) */
    TS_MATERIAL_FOURIER,    /* file: pbrt-v3 .bsdf */
} ts_material_type;

struct ts_fourier_table; /* fourier_bsdf.h */

typedef struct ts_material {
    ts_material_type type;
    ts_rgb reflectance;                  /* diffuse, mirror, dielectric */
    ts_rgb transmittance;                /* dielectric */
    float sigma_deg;                     /* diffuse: Oren–Nayar σ in degrees */
    float eta;                           /* dielectric: interior / exterior index */
    ts_rgb conductor_eta, conductor_k;   /* conductor: complex index per channel */
    float roughness;                     /* microfacet α (dielectric, conductor, plastic, substrate) */
    ts_microfacet_type distribution;     /* conductor (plastic/substrate/dielectric: GGX) */
    ts_rgb diffuse, specular;            /* plastic, substrate */
    const struct ts_fourier_table *fourier; /* fourier: owned by the scene */
} ts_material;

struct ts_bsdf; /* bsdf.h */

/* Builds the BSDF of material m at hit si into *out (no allocation; pbrt-v3 §9.2):
 *   diffuse    Lambertian(reflectance), or Oren–Nayar(reflectance, sigma) when sigma > 0
 *   mirror     specular reflection(reflectance), Fresnel = 1
 *   dielectric smooth (roughness < TS_MICROFACET_SPECULAR_ALPHA): FresnelSpecular
 *              (reflectance, transmittance, 1, eta); rough: microfacet reflection with
 *              dielectric Fresnel + microfacet transmission, GGX(roughness)
 *   conductor  microfacet reflection (distribution, roughness) with conductor Fresnel
 *              (eta, k), or specular reflection when smooth
 *   plastic    microfacet (GGX) or specular reflection(specular) with dielectric
 *              Fresnel F from 1 into 1.5, over Lambertian(diffuse) scaled by
 *              (1 − specular·F(cosθo))(1 − specular·F(cosθi)) (a departure from
 *              pbrt-v3 so unit plastic conserves energy; material.c explains)
 *   substrate  FresnelBlend(diffuse, specular, GGX roughness); when smooth, its diffuse
 *              part + a specular reflection with Schlick's Fresnel(specular)
 *   fourier    the tabulated lobe (out->eta from the table)
 * Lobes with black scale are left out. Pure and thread-safe. */
void ts_material_bsdf(const ts_material *m, const ts_interaction *si, struct ts_bsdf *out);

#endif
