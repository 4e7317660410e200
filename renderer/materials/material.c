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
 * front side's (test_material's furnace sweeps both sides of every material).
 *
 * pbrt-v3's own materials (plastic_pbrt3, uber, translucent, mix) are pbrt-v3's exactly,
 * including what the coupled plastic departs from: plastic_pbrt3's Fresnel is pbrt-v3's
 * code's FresnelDielectric(1.5, 1), whose swapped indices reflect totally from the front
 * beyond 41.8° (docs/design.md §9, #1), and nothing couples its lobes, so unit parameters
 * reflect up to 2 (translucent and uber up to 3); test_material_pbrt3 measures it and
 * holds them to the energy rule where their parameters sum to at most 1. */
#include "materials/material.h"

#include <float.h>
#include <math.h>

#include "materials/bsdf.h"
#include "materials/fourier_bsdf.h"
#include "materials/microfacet.h"
#include "textures/texture.h"

static bool nonblack(ts_rgb c) { return c.r > 0 || c.g > 0 || c.b > 0; }

/* ---------------------------------------------------------------- parameters */

static float clampf(float v, float lo, float hi) { return v > lo ? (v < hi ? v : hi) : lo; } /* NaN → lo */

/* A caller's error (material.h): a textured parameter read without a context is read at
 * a zero one rather than through a null pointer. */
static const ts_texture_context *context(const ts_texture_context *c)
{
    static const ts_texture_context zero;
    return c ? c : &zero;
}

ts_rgb ts_material_texture_unit_rgb(const ts_texture *t, const ts_texture_context *c)
{
    ts_rgb v = ts_texture_eval_rgb(t, context(c));
    return (ts_rgb){clampf(v.r, 0, 1), clampf(v.g, 0, 1), clampf(v.b, 0, 1)};
}

ts_rgb ts_material_texture_nonneg_rgb(const ts_texture *t, const ts_texture_context *c)
{
    ts_rgb v = ts_texture_eval_rgb(t, context(c));
    return (ts_rgb){clampf(v.r, 0, FLT_MAX), clampf(v.g, 0, FLT_MAX), clampf(v.b, 0, FLT_MAX)};
}

float ts_material_texture_float(const ts_texture *t, const ts_texture_context *c, float lo, float hi)
{
    return clampf(ts_texture_eval_float(t, context(c)), lo, hi);
}

/* pbrt-v3's Material::Bump of displacement texture d on si's shading frame. */
static void bump(const ts_texture *d, ts_interaction *si, const ts_texture_context *c)
{
    float du = .5f * (fabsf(c->dudx) + fabsf(c->dudy));
    if (du == 0) du = .0005f;
    float dv = .5f * (fabsf(c->dvdx) + fabsf(c->dvdy));
    if (dv == 0) dv = .0005f;
    /* The shading tangents: ∂p/∂u, ∂p/∂v, or with vertex normals the unit frame about ns
     * (pbrt-v3's Triangle: ss along ∂p/∂u made orthogonal to ns, ts = ns × ss). */
    ts_vec3 dpdu = si->dpdu, dpdv = si->dpdv;
    if (si->mesh_normals) {
        ts_vec3 ts = ts_vec3_cross(si->ns, dpdu);
        float len = ts_vec3_length(ts);
        if (len > 0 && isfinite(len)) {
            ts = ts_vec3_scale(ts, 1 / len);
            dpdu = ts_vec3_cross(ts, si->ns);
            dpdv = ts;
        } else {
            ts_coordinate_system(si->ns, &dpdu, &dpdv);
        }
    }
    ts_texture_context e = *c;
    e.p = ts_vec3_add(c->p, ts_vec3_scale(dpdu, du));
    e.uv = (ts_vec2){c->uv.x + du, c->uv.y};
    float u_displace = ts_texture_eval_float(d, &e);
    e.p = ts_vec3_add(c->p, ts_vec3_scale(dpdv, dv));
    e.uv = (ts_vec2){c->uv.x, c->uv.y + dv};
    float v_displace = ts_texture_eval_float(d, &e);
    float displace = ts_texture_eval_float(d, c);
    /* ∂/∂u of p + d·ns: the tangent, the displacement's slope along ns, and d·∂ns/∂u. */
    ts_vec3 bu = ts_vec3_add(ts_vec3_add(dpdu, ts_vec3_scale(si->ns, (u_displace - displace) / du)),
                             ts_vec3_scale(si->dndu, displace));
    ts_vec3 bv = ts_vec3_add(ts_vec3_add(dpdv, ts_vec3_scale(si->ns, (v_displace - displace) / dv)),
                             ts_vec3_scale(si->dndv, displace));
    ts_vec3 n = ts_vec3_cross(bu, bv);
    float len = ts_vec3_length(n);
    if (!(len > 0) || !isfinite(len)) return;
    si->ns = ts_vec3_faceforward(ts_vec3_scale(n, 1 / len), si->n);
}

void ts_material_bump(const ts_material *m, ts_interaction *si, const ts_texture_context *c)
{
    c = context(c);
    if (m->bump) bump(m->bump, si, c);
    /* pbrt-v3's MixMaterial: the first material computes on the interaction itself, the
     * second on a copy; the mixed BSDF keeps the first's frame (mix_bsdf), so the first's
     * bump maps (a mix's, recursively) make the shading normal and the second's cannot
     * show. */
    if (m->type == TS_MATERIAL_MIX && m->mix[0]) ts_material_bump(m->mix[0], si, c);
}

void ts_material_texture_context(const ts_interaction *si, ts_texture_context *c)
{
    c->p = si->p;
    c->uv = si->uv;
    c->dpdu = si->dpdu;
    c->dpdv = si->dpdv;
    ts_texture_context_clear_differentials(c);
}

/* ---------------------------------------------------------------- BSDFs */

/* α along u and v after vroughness and pbrt-v3's remapping (u_raw, v_raw as given), and
 * whether the lobe is specular: both α below TS_MICROFACET_SPECULAR_ALPHA, or a
 * dielectric whose roughnesses are exactly 0 before remapping (pbrt-v3's glass); a rough
 * lobe has each α raised to at least that threshold. Isotropic and unremapped this is the
 * rule every material had before (both α the same). */
static void roughness_uv(const ts_material *m, float u_raw, float v_raw, float *au, float *av, bool *smooth)
{
    float u = u_raw, v = v_raw;
    if (m->remap_roughness) {
        u = ts_microfacet_roughness_to_alpha(u_raw);
        v = m->has_vroughness ? ts_microfacet_roughness_to_alpha(v_raw) : u;
    }
    *smooth = (!(u >= TS_MICROFACET_SPECULAR_ALPHA) && !(v >= TS_MICROFACET_SPECULAR_ALPHA)) ||
              (m->type == TS_MATERIAL_DIELECTRIC && u_raw == 0 && v_raw == 0);
    if (!*smooth) {
        if (!(u >= TS_MICROFACET_SPECULAR_ALPHA)) u = TS_MICROFACET_SPECULAR_ALPHA;
        if (!(v >= TS_MICROFACET_SPECULAR_ALPHA)) v = TS_MICROFACET_SPECULAR_ALPHA;
    }
    *au = u;
    *av = v;
}

/* Appends b's lobes to out, each scaled by s (pbrt-v3's ScaledBxDF); lobes the scale makes
 * black are left out (they would add nothing to f, only take samples). */
static void add_scaled(ts_bsdf *out, const ts_bsdf *b, ts_rgb s)
{
    if (!nonblack(s)) return;
    for (int i = 0; i < b->n_bxdfs; i++) ts_bsdf_add(out, ts_bxdf_scaled(b->bxdfs[i], s));
}

/* pbrt-v3's MixMaterial: mix[0]'s BSDF (its frame and η) with its lobes scaled by amount,
 * then mix[1]'s lobes scaled by 1 − amount. The builder has bounded the lobe count. */
static void mix_bsdf(const ts_material *m, const ts_interaction *si, const ts_texture_context *tc, ts_rgb amount,
                     ts_bsdf *out)
{
    ts_bsdf b0, b1;
    ts_rgb rest = {clampf(1 - amount.r, 0, 1), clampf(1 - amount.g, 0, 1), clampf(1 - amount.b, 0, 1)};
    if (!m->mix[0] || !m->mix[1]) return;
    ts_material_bsdf(m->mix[0], si, tc, &b0);
    ts_material_bsdf(m->mix[1], si, tc, &b1);
    out->eta = b0.eta;
    out->ng = b0.ng;
    out->ns = b0.ns;
    out->ss = b0.ss;
    out->ts = b0.ts;
    add_scaled(out, &b0, amount);
    add_scaled(out, &b1, rest);
}

/* The BSDF, with the parameter reads of a textured material (textured) or of a constant
 * one, whose reads the compiler reduces to the plain values: ts_material_bsdf calls it
 * with the constant true or false, so a constant-only material runs the code it ran
 * before parameters could be textured (docs/design.md §4d measures it). */
#define RGB(p) (textured ? (nonneg ? ts_material_eval_nonneg_rgb(&(p), tc) : ts_material_eval_unit_rgb(&(p), tc)) \
                         : (p).value)
#define NONNEG_RGB(p) (textured ? ts_material_eval_nonneg_rgb(&(p), tc) : (p).value)
#define FLOAT(p, lo, hi) (textured ? ts_material_eval_float(&(p), tc, lo, hi) : (p).value)
/* The dielectric's η, evaluated once when textured; a constant one read again, as the
 * constant path always has (no register held across calls). */
#define ETA (textured ? eta : m->eta.value)
static inline __attribute__((always_inline)) void bsdf(const ts_material *m, const ts_interaction *si,
                                                       const ts_texture_context *tc, ts_bsdf *out, bool textured)
{
    /* Colours clamped at 0 only (pbrt-v3's), but for the coupled plastic (material.h). */
    const bool nonneg = textured && m->texture_clamp_nonneg && m->type != TS_MATERIAL_PLASTIC;
    float eta = 1;
    if (m->type == TS_MATERIAL_DIELECTRIC) eta = FLOAT(m->eta, TS_MATERIAL_ETA_MIN, FLT_MAX);
    if (m->type == TS_MATERIAL_FOURIER && m->fourier) eta = m->fourier->eta;
    ts_bsdf_init(out, si->n, si->ns, si->dpdu, eta);

    float alpha = FLOAT(m->roughness, 0, FLT_MAX), alpha_v = alpha;
    bool smooth = ts_microfacet_is_specular(alpha, alpha);
    if (m->has_vroughness | m->remap_roughness)
        roughness_uv(m, alpha, m->has_vroughness ? FLOAT(m->vroughness, 0, FLT_MAX) : alpha, &alpha, &alpha_v, &smooth);
    switch (m->type) {
    case TS_MATERIAL_DIFFUSE: {
        ts_rgb r = RGB(m->reflectance);
        if (!nonblack(r)) break;
        float sigma = FLOAT(m->sigma_deg, 0, 90);
        if (sigma > 0) ts_bsdf_add(out, ts_bxdf_oren_nayar(r, sigma));
        else ts_bsdf_add(out, ts_bxdf_lambertian(r));
        break;
    }
    case TS_MATERIAL_MIRROR: {
        ts_rgb r = RGB(m->reflectance);
        if (nonblack(r)) ts_bsdf_add(out, ts_bxdf_specular_reflection(r, ts_fresnel_one()));
        break;
    }
    case TS_MATERIAL_DIELECTRIC: {
        ts_rgb r = RGB(m->reflectance);
        ts_rgb t = RGB(m->transmittance);
        if (!nonblack(r) && !nonblack(t)) break;
        if (smooth) {
            ts_bsdf_add(out, ts_bxdf_fresnel_specular(r, t, 1, ETA));
            break;
        }
        ts_microfacet d = ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha_v);
        if (nonblack(r)) ts_bsdf_add(out, ts_bxdf_microfacet_reflection(r, d, ts_fresnel_make_dielectric(1, ETA)));
        if (nonblack(t)) ts_bsdf_add(out, ts_bxdf_microfacet_transmission(t, d, 1, ETA));
        break;
    }
    case TS_MATERIAL_CONDUCTOR: {
        ts_fresnel fr = ts_fresnel_make_conductor(1, NONNEG_RGB(m->conductor_eta),
                                                  NONNEG_RGB(m->conductor_k));
        if (smooth) ts_bsdf_add(out, ts_bxdf_specular_reflection(ts_rgb_gray(1), fr));
        else
            ts_bsdf_add(out, ts_bxdf_microfacet_reflection(ts_rgb_gray(1), ts_microfacet_make(m->distribution, alpha, alpha_v),
                                                           fr));
        break;
    }
    case TS_MATERIAL_PLASTIC: {
        ts_rgb kd = RGB(m->diffuse), ks = RGB(m->specular);
        ts_fresnel fr = ts_fresnel_make_dielectric_two_sided(1, 1.5f);
        if (nonblack(kd)) ts_bsdf_add(out, ts_bxdf_lambertian_coupled(kd, ks, fr));
        if (!nonblack(ks)) break;
        if (smooth) ts_bsdf_add(out, ts_bxdf_specular_reflection(ks, fr));
        else
            ts_bsdf_add(out, ts_bxdf_microfacet_reflection(ks, ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha_v), fr));
        break;
    }
    case TS_MATERIAL_SUBSTRATE: {
        ts_rgb kd = RGB(m->diffuse), ks = RGB(m->specular);
        if (smooth) {
            ts_bsdf_add(out, ts_bxdf_fresnel_blend_diffuse(kd, ks));
            ts_bsdf_add(out, ts_bxdf_specular_reflection(ts_rgb_gray(1), ts_fresnel_make_schlick(ks)));
        } else {
            ts_bsdf_add(out, ts_bxdf_fresnel_blend(kd, ks, ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha_v)));
        }
        break;
    }
    case TS_MATERIAL_FOURIER:
        if (m->fourier) ts_bsdf_add(out, ts_bxdf_fourier(m->fourier));
        break;
    case TS_MATERIAL_PLASTIC_PBRT3: {
        ts_rgb kd = RGB(m->diffuse), ks = RGB(m->specular);
        if (nonblack(kd)) ts_bsdf_add(out, ts_bxdf_lambertian(kd));
        if (!nonblack(ks)) break;
        ts_fresnel fr = ts_fresnel_make_dielectric(1.5f, 1); /* pbrt-v3's indices, material.c's note */
        if (smooth) ts_bsdf_add(out, ts_bxdf_specular_reflection(ks, fr));
        else ts_bsdf_add(out, ts_bxdf_microfacet_reflection(ks, ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha_v), fr));
        break;
    }
    case TS_MATERIAL_UBER: {
        float e = FLOAT(m->eta, TS_MATERIAL_ETA_MIN, FLT_MAX);
        ts_rgb op = RGB(m->opacity), pass = {ts_maxf(0, 1 - op.r), ts_maxf(0, 1 - op.g), ts_maxf(0, 1 - op.b)};
        out->eta = e;
        if (nonblack(pass)) {
            ts_bsdf_add(out, ts_bxdf_specular_transmission(pass, 1, 1));
            out->eta = 1;
        }
        ts_rgb kd = ts_rgb_mul(op, RGB(m->diffuse)), ks = ts_rgb_mul(op, RGB(m->specular));
        ts_rgb kr = ts_rgb_mul(op, RGB(m->reflectance)), kt = ts_rgb_mul(op, RGB(m->transmittance));
        ts_fresnel fr = ts_fresnel_make_dielectric(1, e);
        if (nonblack(kd)) ts_bsdf_add(out, ts_bxdf_lambertian(kd));
        if (nonblack(ks)) {
            if (smooth) ts_bsdf_add(out, ts_bxdf_specular_reflection(ks, fr));
            else ts_bsdf_add(out, ts_bxdf_microfacet_reflection(ks, ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha_v), fr));
        }
        if (nonblack(kr)) ts_bsdf_add(out, ts_bxdf_specular_reflection(kr, fr));
        if (nonblack(kt)) ts_bsdf_add(out, ts_bxdf_specular_transmission(kt, 1, e));
        break;
    }
    case TS_MATERIAL_TRANSLUCENT: {
        ts_rgb r = RGB(m->reflectance), t = RGB(m->transmittance);
        out->eta = 1.5f;
        if (!nonblack(r) && !nonblack(t)) break;
        ts_rgb kd = RGB(m->diffuse), ks = RGB(m->specular);
        if (nonblack(kd)) {
            if (nonblack(r)) ts_bsdf_add(out, ts_bxdf_lambertian(ts_rgb_mul(r, kd)));
            if (nonblack(t)) ts_bsdf_add(out, ts_bxdf_lambertian_transmission(ts_rgb_mul(t, kd)));
        }
        if (!nonblack(ks)) break;
        ts_microfacet d = ts_microfacet_make(TS_MICROFACET_GGX, alpha, alpha_v);
        ts_fresnel fr = ts_fresnel_make_dielectric(1, 1.5f);
        if (nonblack(r)) {
            ts_rgb rs = ts_rgb_mul(r, ks);
            ts_bsdf_add(out, smooth ? ts_bxdf_specular_reflection(rs, fr) : ts_bxdf_microfacet_reflection(rs, d, fr));
        }
        if (nonblack(t)) {
            ts_rgb ts = ts_rgb_mul(t, ks);
            ts_bsdf_add(out, smooth ? ts_bxdf_specular_transmission(ts, 1, 1.5f)
                                    : ts_bxdf_microfacet_transmission(ts, d, 1, 1.5f));
        }
        break;
    }
    case TS_MATERIAL_MIX: mix_bsdf(m, si, tc, RGB(m->amount), out); break;
    }
}
#undef RGB
#undef NONNEG_RGB
#undef FLOAT
#undef ETA

/* The textured instance is a call of its own, so its registers and stack do not weigh on
 * the constant path (measured: Cornell box, callgrind, docs/design.md §4d). */
static __attribute__((noinline)) void bsdf_textured(const ts_material *m, const ts_interaction *si,
                                                    const ts_texture_context *tc, ts_bsdf *out)
{
    bsdf(m, si, tc, out, true);
}

void ts_material_bsdf(const ts_material *m, const ts_interaction *si, const ts_texture_context *tc, ts_bsdf *out)
{
    if (m->textured) bsdf_textured(m, si, tc, out);
    else bsdf(m, si, NULL, out, false);
}
