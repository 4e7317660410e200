/* material.h — the materials of scene format v1 (docs/design.md §4) as parameters, and the
 * mapping from a material at a hit to its BSDF.
 *
 * Design note: a material is plain data filled by the scene loader (which validates every
 * value); ts_material_bsdf builds the BSDF for one shading point into caller storage with
 * no allocation (the hot path). `roughness` is the microfacet α, no remapping (pbrt-v3
 * meaning). Materials are immutable after scene build and shared by all threads.
 *
 * Parameters (docs/design.md §4d). Every parameter pbrt-v3 lets be a texture is a
 * ts_material_rgb or ts_material_float: a constant `value` and an optional texture `tex`
 * (textures/texture.h, made in the scene's arena). With no texture the value is used as
 * it is — the constant path costs one predictable branch per parameter read and gives the
 * same bits as before parameters could be textured. With one, the texture is evaluated
 * at the hit's ts_texture_context and the result clamped into the range the builder
 * demands of the constant (ts_material_eval_*: reflectances to [0, 1], σ to [0, 90],
 * α ≥ 0, η > 0; pbrt-v3 clamps colours only at 0 — a **Decision** so that a texture
 * cannot break the energy rule of §8 or make a BxDF divide by zero). `value` is ignored
 * when `tex` is set. `textured` is set by the builder (ts_material_uses_textures) and
 * tells the integrators whether to fill a texture context at all. */
#ifndef TS_MATERIAL_H
#define TS_MATERIAL_H

#include <stdbool.h>
#include <stddef.h>

#include "core/vecmath.h"
#include "geometry/interaction.h"
#include "materials/microfacet.h" /* ts_microfacet_type */

typedef enum ts_material_type {
    TS_MATERIAL_DIFFUSE,    /* reflectance, sigma (degrees; Oren–Nayar if > 0) */
    TS_MATERIAL_MIRROR,     /* reflectance */
    TS_MATERIAL_DIELECTRIC, /* eta, reflectance, transmittance, roughness (0 = smooth) */
    TS_MATERIAL_CONDUCTOR,  /* eta[rgb], k[rgb], roughness, distribution */
    TS_MATERIAL_PLASTIC,    /* diffuse, specular, roughness */
    TS_MATERIAL_SUBSTRATE,  /* diffuse, specular, roughness, vroughness (FresnelBlend) */
    TS_MATERIAL_FOURIER,    /* file: pbrt-v3 .bsdf */
    /* pbrt-v3's own materials, its parameters under tessera's field names (pbrt-v3's name
     * and default in brackets; the builder takes the values as given, the defaults are for
     * the front ends): */
    TS_MATERIAL_PLASTIC_PBRT3, /* PlasticMaterial: diffuse [Kd 0.25], specular [Ks 0.25],
                                * roughness [0.1], remap_roughness [true] */
    TS_MATERIAL_UBER,          /* UberMaterial: diffuse [Kd 0.25], specular [Ks 0.25],
                                * reflectance [Kr 0], transmittance [Kt 0], roughness [0.1]
                                * (vroughness [uroughness]), eta [index 1.5], opacity [1],
                                * remap_roughness [true] */
    TS_MATERIAL_TRANSLUCENT,   /* TranslucentMaterial: diffuse [Kd 0.25], specular [Ks 0.25],
                                * reflectance [reflect 0.5], transmittance [transmit 0.5],
                                * roughness [0.1], remap_roughness [true]; η = 1.5 */
    TS_MATERIAL_MIX,           /* MixMaterial: mix[0] [namedmaterial1] weighted by amount
                                * [0.5], mix[1] [namedmaterial2] by 1 − amount */
} ts_material_type;

struct ts_fourier_table; /* fourier_bsdf.h */
struct ts_texture;       /* textures/texture.h */
struct ts_texture_context; /* textures/texture_mapping.h */

/* A colour parameter: value, or tex (an RGB texture, or a float one read as grey). */
typedef struct ts_material_rgb {
    ts_rgb value;
    const struct ts_texture *tex; /* NULL: the constant value; else owned by the scene */
} ts_material_rgb;

/* A float parameter: value, or tex (a float texture; an RGB one gives its red channel). */
typedef struct ts_material_float {
    float value;
    const struct ts_texture *tex; /* NULL: the constant value; else owned by the scene */
} ts_material_float;

static inline ts_material_rgb ts_material_rgb_const(ts_rgb v) { return (ts_material_rgb){v, NULL}; }
static inline ts_material_rgb ts_material_rgb_gray(float v) { return (ts_material_rgb){ts_rgb_gray(v), NULL}; }
static inline ts_material_float ts_material_float_const(float v) { return (ts_material_float){v, NULL}; }

typedef struct ts_material {
    ts_material_type type;
    ts_material_rgb reflectance;              /* diffuse, mirror, dielectric */
    ts_material_rgb transmittance;            /* dielectric */
    ts_material_float sigma_deg;              /* diffuse: Oren–Nayar σ in degrees */
    ts_material_float eta;                    /* dielectric: interior / exterior index */
    ts_material_rgb conductor_eta, conductor_k; /* conductor: complex index per channel */
    ts_material_float roughness;              /* microfacet α (dielectric, conductor, plastic, substrate) */
    ts_microfacet_type distribution;          /* conductor (plastic/substrate/dielectric: GGX) */
    ts_material_rgb diffuse, specular;        /* plastic, substrate */
    const struct ts_fourier_table *fourier;   /* fourier: owned by the scene */
    /* Anisotropic roughness (pbrt-v3's uroughness / vroughness): roughness is along dpdu
     * (the shading frame's s axis), vroughness along the other when has_vroughness (else
     * it is roughness). Conductor, dielectric, substrate, uber. */
    bool has_vroughness;
    ts_material_float vroughness;
    /* pbrt-v3's remaproughness: roughness and vroughness pass through
     * ts_microfacet_roughness_to_alpha before use (conductor, dielectric, plastic,
     * substrate, and pbrt-v3's plastic, uber, translucent). false: they are α. pbrt-v3's
     * default is true (the pbrt-v3 importer's); scene format v1's is false (§4). */
    bool remap_roughness;
    ts_material_rgb opacity;               /* uber: [0, 1]; below 1 adds a pass-through lobe */
    ts_material_rgb amount;                /* mix: mix[0]'s weight per channel, [0, 1] */
    uint32_t mix_id[2];                    /* mix: builder ids of earlier materials */
    const struct ts_material *mix[2];      /* mix: set by the builder from mix_id (the scene's) */
    /* Any type: pbrt-v3's bump map, a float texture of displacement along the shading
     * normal (NULL: none; ts_material_bump). */
    const struct ts_texture *bump;
    bool textured; /* a parameter or the bump map has a texture: set by the builder (ts_material_uses_textures) */
    /* Textured colours clamped at 0 only, as pbrt-v3's Spectrum::Clamp(), not into [0, 1]
     * (the Decision above): set for every material of a .pbrt file, JSON "texture_clamp":
     * "nonnegative". The coupled `plastic`, whose 1 − ks·F needs ks ≤ 1, keeps [0, 1]. */
    bool texture_clamp_nonneg;
    /* Set by the builder, from the materials a mix names (so counting is linear in the
     * scene): the lobes of its flattened BSDF at most (ts_material_max_lobes; a mix the sum
     * of its two, at most TS_BSDF_MAX_BXDFS), and the textures one shading of it evaluates
     * at most (ts_material_texture_cost; a mix adds its two, at most TS_MATERIAL_MAX_COST). */
    uint8_t lobes;
    uint32_t cost;
} ts_material;

/* The most texture evaluations one shading of a material may take (its parameters', its
 * bump map's three, and a mix's two materials'): the builder refuses beyond. Each texture
 * counts its own cost (textures/texture.h, TS_TEXTURE_MAX_COST a lookup). */
#define TS_MATERIAL_MAX_COST 4096

/* pbrt-v3's Material::Bump: with displacement d = m->bump at c, and du = ½(|∂u/∂x| +
 * |∂u/∂y|) of c's footprint (0.0005 without one), likewise dv, the displaced tangents are
 *   ∂p'/∂u = ∂p/∂u + (d(u + du) − d(u))/du · ns + d(u)·∂ns/∂u,  ∂p'/∂v likewise,
 * (d(u + du) read at p + du·∂p/∂u, uv + (du, 0)), and si->ns becomes normalize(∂p'/∂u ×
 * ∂p'/∂v) turned into si->n's hemisphere — pbrt-v3's SetShadingGeometry with the geometric
 * orientation authoritative, which makes its ReverseOrientation/handedness flip moot.
 * ∂p/∂u, ∂p/∂v are the shading tangents: si's, or with vertex normals (si->mesh_normals)
 * pbrt-v3's unit frame about ns (ss = ∂p/∂u made orthogonal to ns, ts = ns × ss);
 * ∂ns/∂u, ∂ns/∂v are si's (geometry/shape.h). A degenerate result (zero cross product)
 * leaves si->ns. A mix then bumps with its first material (recursively), as pbrt-v3's
 * MixMaterial does: the second bumps a copy of the frame the mixed BSDF does not use.
 * Nothing when no bump map applies. */
void ts_material_bump(const ts_material *m, ts_interaction *si, const struct ts_texture_context *c);

/* Textured values are clamped into these: η of a dielectric below the minimum is raised
 * to it (a constant η must be > 0; 1e-3 keeps every Fresnel and refraction term finite). */
#define TS_MATERIAL_ETA_MIN 1e-3f

/* Out of line: a texture's value at c clamped to [0, 1] per channel; to [0, FLT_MAX]; to
 * [lo, hi] (NaN, which textures never give, to lo). */
ts_rgb ts_material_texture_unit_rgb(const struct ts_texture *t, const struct ts_texture_context *c);
ts_rgb ts_material_texture_nonneg_rgb(const struct ts_texture *t, const struct ts_texture_context *c);
float ts_material_texture_float(const struct ts_texture *t, const struct ts_texture_context *c, float lo, float hi);

/* A parameter's value at texture context c (which may be NULL when p has no texture):
 * the constant, or the texture's value clamped as the design note says. */
static inline ts_rgb ts_material_eval_unit_rgb(const ts_material_rgb *p, const struct ts_texture_context *c)
{
    return p->tex ? ts_material_texture_unit_rgb(p->tex, c) : p->value;
}
static inline ts_rgb ts_material_eval_nonneg_rgb(const ts_material_rgb *p, const struct ts_texture_context *c)
{
    return p->tex ? ts_material_texture_nonneg_rgb(p->tex, c) : p->value;
}
static inline float ts_material_eval_float(const ts_material_float *p, const struct ts_texture_context *c, float lo,
                                           float hi)
{
    return p->tex ? ts_material_texture_float(p->tex, c, lo, hi) : p->value;
}

/* The texture context of hit si with no footprint (no ray differentials): p, uv, dpdu,
 * dpdv from si. */
void ts_material_texture_context(const ts_interaction *si, struct ts_texture_context *c);

struct ts_bsdf; /* bsdf.h */

/* Builds the BSDF of material m at hit si into *out (no allocation; pbrt-v3 §9.2), with
 * textured parameters evaluated at tc: the hit's texture context with its footprint,
 * which the caller fills when m->textured (ts_material_texture_context, then the ray
 * differentials) and may pass as NULL otherwise (a textured material given NULL reads
 * its textures at an all-zero context — a caller's error, never a crash):
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
 *   substrate  FresnelBlend(diffuse, specular, GGX(roughness, vroughness)); when smooth,
 *              its diffuse part + a specular reflection with Schlick's Fresnel(specular)
 *   fourier    the tabulated lobe (out->eta from the table)
 *   plastic_pbrt3  pbrt-v3's PlasticMaterial: Lambertian(diffuse) + microfacet (GGX)
 *              reflection(specular) with pbrt-v3's FresnelDielectric(1.5, 1) — its
 *              indices as its code has them (docs/design.md §9, #1), uncoupled, so it
 *              reflects more than 1 where pbrt-v3's does (material.c quantifies it)
 *   uber       pbrt-v3's UberMaterial: with op = opacity, a pass-through specular
 *              transmission(1 − op) (then the BSDF's η is 1, else eta), Lambertian
 *              (op·diffuse), microfacet reflection(op·specular, Fresnel 1 → eta), specular
 *              reflection(op·reflectance, Fresnel 1 → eta), specular transmission
 *              (op·transmittance, 1 → eta): up to 5 lobes
 *   translucent pbrt-v3's TranslucentMaterial: Lambertian reflection(reflectance·diffuse)
 *              and transmission(transmittance·diffuse), microfacet reflection
 *              (reflectance·specular, Fresnel 1 → 1.5) and transmission(transmittance·
 *              specular, 1 → 1.5); η 1.5
 *   mix        mix[0]'s lobes each scaled by amount and mix[1]'s by 1 − amount
 *              (pbrt-v3's ScaledBxDF; in mix[0]'s shading frame, with its η)
 * A microfacet lobe whose α (after remapping) is below TS_MICROFACET_SPECULAR_ALPHA on
 * both axes is a specular lobe instead; below it on one axis only, that α is raised to it.
 * A dielectric with both roughnesses exactly 0 is smooth before remapping (pbrt-v3's
 * glass). Lobes with black scale are left out. Pure and thread-safe. */
void ts_material_bsdf(const ts_material *m, const ts_interaction *si, const struct ts_texture_context *tc,
                      struct ts_bsdf *out);

#endif
