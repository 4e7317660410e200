/* bxdf.c — see bxdf.h. Mathematics of pbrt-v3 ch. 8 (Lambertian, Oren–Nayar, Torrance–
 * Sparrow microfacet reflection, Walter et al.'s microfacet transmission, Ashikhmin–
 * Shirley FresnelBlend, specular reflection / transmission / FresnelSpecular) and §8.6
 * for the Fourier lobe; the code is this project's own. */
#include "materials/bxdf.h"

#include "materials/fourier_bsdf.h"
#include "sampling/sampling.h"

/* ---------------------------------------------------------------- helpers ---- */

bool ts_refract(ts_vec3 wi, ts_vec3 n, float eta, ts_vec3 *wt)
{
    float cos_i = ts_vec3_dot(n, wi);
    float sin2_i = ts_maxf(0, 1 - cos_i * cos_i);
    float sin2_t = eta * eta * sin2_i;
    if (sin2_t >= 1) return false;
    float cos_t = sqrtf(1 - sin2_t);
    *wt = ts_vec3_add(ts_vec3_scale(ts_vec3_neg(wi), eta), ts_vec3_scale(n, eta * cos_i - cos_t));
    return true;
}

static inline ts_rgb black(void) { return (ts_rgb){0, 0, 0}; }
static inline float pow5(float v) { return (v * v) * (v * v) * v; }
static inline ts_rgb rgb_finite(ts_rgb c)
{
    if (!ts_rgb_is_finite(c)) return black();
    return (ts_rgb){ts_maxf(c.r, 0), ts_maxf(c.g, 0), ts_maxf(c.b, 0)};
}

/* ----------------------------------------------------------- constructors ---- */

ts_bxdf ts_bxdf_lambertian(ts_rgb r)
{
    return (ts_bxdf){.type = TS_BXDF_LAMBERTIAN, .flags = TS_BXDF_REFLECTION | TS_BXDF_DIFFUSE, .r = r};
}

ts_bxdf ts_bxdf_lambertian_coupled(ts_rgb r, ts_rgb ks, ts_fresnel fr)
{
    return (ts_bxdf){.type = TS_BXDF_LAMBERTIAN, .flags = TS_BXDF_REFLECTION | TS_BXDF_DIFFUSE, .r = r, .rs = ks,
                     .fresnel = fr, .diffuse_coupled = true};
}

ts_bxdf ts_bxdf_oren_nayar(ts_rgb r, float sigma_deg)
{
    float s = ts_radians(sigma_deg), s2 = s * s;
    return (ts_bxdf){.type = TS_BXDF_OREN_NAYAR, .flags = TS_BXDF_REFLECTION | TS_BXDF_DIFFUSE, .r = r,
                     .on_a = 1 - s2 / (2 * (s2 + 0.33f)), .on_b = 0.45f * s2 / (s2 + 0.09f)};
}

ts_bxdf ts_bxdf_microfacet_reflection(ts_rgb r, ts_microfacet dist, ts_fresnel fresnel)
{
    return (ts_bxdf){.type = TS_BXDF_MICROFACET_REFLECTION, .flags = TS_BXDF_REFLECTION | TS_BXDF_GLOSSY,
                     .r = r, .dist = ts_microfacet_make(dist.type, dist.alpha_x, dist.alpha_y), .fresnel = fresnel};
}

/* Indices this close make refraction a straight pass-through (wi = −wo): a delta. */
static bool index_matched(float eta_a, float eta_b) { return fabsf(eta_a - eta_b) <= 1e-5f * fabsf(eta_a); }

ts_bxdf ts_bxdf_microfacet_transmission(ts_rgb t, ts_microfacet dist, float eta_a, float eta_b)
{
    uint32_t kind = index_matched(eta_a, eta_b) ? TS_BXDF_SPECULAR : TS_BXDF_GLOSSY;
    return (ts_bxdf){.type = TS_BXDF_MICROFACET_TRANSMISSION, .flags = TS_BXDF_TRANSMISSION | kind,
                     .t = t, .dist = ts_microfacet_make(dist.type, dist.alpha_x, dist.alpha_y), .eta_a = eta_a,
                     .eta_b = eta_b};
}

ts_bxdf ts_bxdf_fresnel_blend(ts_rgb rd, ts_rgb rs, ts_microfacet dist)
{
    return (ts_bxdf){.type = TS_BXDF_FRESNEL_BLEND, .flags = TS_BXDF_REFLECTION | TS_BXDF_GLOSSY, .r = rd, .rs = rs,
                     .blend_glossy = true, .dist = ts_microfacet_make(dist.type, dist.alpha_x, dist.alpha_y)};
}

ts_bxdf ts_bxdf_fresnel_blend_diffuse(ts_rgb rd, ts_rgb rs)
{
    return (ts_bxdf){.type = TS_BXDF_FRESNEL_BLEND, .flags = TS_BXDF_REFLECTION | TS_BXDF_DIFFUSE, .r = rd, .rs = rs,
                     .blend_glossy = false};
}

ts_bxdf ts_bxdf_specular_reflection(ts_rgb r, ts_fresnel fresnel)
{
    return (ts_bxdf){.type = TS_BXDF_SPECULAR_REFLECTION, .flags = TS_BXDF_REFLECTION | TS_BXDF_SPECULAR, .r = r,
                     .fresnel = fresnel};
}

ts_bxdf ts_bxdf_specular_transmission(ts_rgb t, float eta_a, float eta_b)
{
    return (ts_bxdf){.type = TS_BXDF_SPECULAR_TRANSMISSION, .flags = TS_BXDF_TRANSMISSION | TS_BXDF_SPECULAR,
                     .t = t, .eta_a = eta_a, .eta_b = eta_b};
}

ts_bxdf ts_bxdf_fresnel_specular(ts_rgb r, ts_rgb t, float eta_a, float eta_b)
{
    return (ts_bxdf){.type = TS_BXDF_FRESNEL_SPECULAR,
                     .flags = TS_BXDF_REFLECTION | TS_BXDF_TRANSMISSION | TS_BXDF_SPECULAR, .r = r, .t = t,
                     .eta_a = eta_a, .eta_b = eta_b};
}

ts_bxdf ts_bxdf_lambertian_transmission(ts_rgb t)
{
    return (ts_bxdf){.type = TS_BXDF_LAMBERTIAN_TRANSMISSION, .flags = TS_BXDF_TRANSMISSION | TS_BXDF_DIFFUSE,
                     .t = t};
}

ts_bxdf ts_bxdf_scaled(ts_bxdf b, ts_rgb s)
{
    b.scale = b.scaled ? ts_rgb_mul(b.scale, s) : s;
    b.scaled = true;
    return b;
}

ts_bxdf ts_bxdf_fourier(const struct ts_fourier_table *table)
{
    return (ts_bxdf){.type = TS_BXDF_FOURIER, .flags = TS_BXDF_REFLECTION | TS_BXDF_TRANSMISSION | TS_BXDF_GLOSSY,
                     .fourier = table};
}

/* --------------------------------------------------------------- lobes: f ---- */

static ts_rgb oren_nayar_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    float sin_i = ts_sin_theta(wi), sin_o = ts_sin_theta(wo);
    float max_cos = 0;
    if (sin_i > 1e-4f && sin_o > 1e-4f) {
        float d_cos = ts_cos_phi(wi) * ts_cos_phi(wo) + ts_sin_phi(wi) * ts_sin_phi(wo);
        max_cos = ts_maxf(0, d_cos);
    }
    float sin_alpha, tan_beta;
    if (ts_abs_cos_theta(wi) > ts_abs_cos_theta(wo)) {
        sin_alpha = sin_o;
        tan_beta = sin_i / ts_abs_cos_theta(wi);
    } else {
        sin_alpha = sin_i;
        tan_beta = sin_o / ts_abs_cos_theta(wo);
    }
    float v = TS_INV_PI * (b->on_a + b->on_b * max_cos * sin_alpha * tan_beta);
    return ts_rgb_scale(b->r, isfinite(v) ? v : TS_INV_PI * b->on_a);
}

static ts_rgb microfacet_reflection_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    float cos_o = fabsf(wo.z), cos_i = fabsf(wi.z);
    if (cos_i == 0 || cos_o == 0) return black();
    ts_vec3 wh = ts_vec3_add(wi, wo);
    if (wh.x == 0 && wh.y == 0 && wh.z == 0) return black();
    wh = ts_vec3_normalize(wh);
    /* wi·wh = wo·wh exactly; the average keeps f reciprocal under float rounding. */
    ts_vec3 whf = ts_vec3_faceforward(wh, (ts_vec3){0, 0, 1});
    ts_rgb f = ts_fresnel_eval(&b->fresnel, 0.5f * (ts_vec3_dot(wi, whf) + ts_vec3_dot(wo, whf)));
    float s = ts_microfacet_d(&b->dist, wh) * ts_microfacet_g(&b->dist, wo, wi) / (4 * cos_i * cos_o);
    return rgb_finite(ts_rgb_scale(ts_rgb_mul(b->r, f), s));
}

/* Generalised half vector of a refraction pair, oriented to +z, with the checks that the
 * configuration is one a visible microfacet can produce (wo in front of it, wi behind).
 * *eta gets η(wi side) / η(wo side). False if impossible. */
static bool transmission_half(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi, ts_vec3 *wh, float *eta)
{
    if (wo.z == 0 || wi.z == 0 || ts_same_hemisphere(wo, wi)) return false;
    *eta = wo.z > 0 ? b->eta_b / b->eta_a : b->eta_a / b->eta_b;
    ts_vec3 h = ts_vec3_add(wo, ts_vec3_scale(wi, *eta));
    float len = ts_vec3_length(h);
    if (!(len > 0)) return false;
    h = ts_vec3_scale(h, 1 / len);
    if (h.z < 0) h = ts_vec3_neg(h);
    float dot_o = ts_vec3_dot(wo, h), dot_i = ts_vec3_dot(wi, h);
    /* wo sees the microfacet from its own side, wi leaves through its back. */
    if (!(dot_o * wo.z > 0) || !(dot_i * wo.z < 0)) return false;
    *wh = h;
    return true;
}

static ts_rgb microfacet_transmission_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    ts_vec3 wh;
    float eta;
    if (!transmission_half(b, wo, wi, &wh, &eta)) return black();
    float dot_o = ts_vec3_dot(wo, wh), dot_i = ts_vec3_dot(wi, wh);
    float fr = ts_fresnel_dielectric(dot_o, b->eta_a, b->eta_b);
    float denom = dot_o + eta * dot_i;
    /* Radiance transport: Walter et al.'s η_o² cancels against the (1/η)² of the
     * adjoint, leaving the (η_i/η_t)² scaling of radiance in the Jacobian. */
    float s = ts_microfacet_d(&b->dist, wh) * ts_microfacet_g(&b->dist, wo, wi) * fabsf(dot_i) * fabsf(dot_o) /
              (fabsf(wi.z) * fabsf(wo.z) * denom * denom);
    return rgb_finite(ts_rgb_scale(b->t, (1 - fr) * s));
}

static ts_rgb schlick(ts_rgb rs, float cos_theta)
{
    float m = pow5(1 - ts_clampf(fabsf(cos_theta), 0, 1));
    return ts_rgb_add(rs, ts_rgb_scale(ts_rgb_sub(ts_rgb_gray(1), rs), m));
}

static ts_rgb fresnel_blend_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    float ci = fabsf(wi.z), co = fabsf(wo.z);
    float k = (28.0f / (23.0f * TS_PI)) * (1 - pow5(1 - 0.5f * ci)) * (1 - pow5(1 - 0.5f * co));
    ts_rgb diffuse = ts_rgb_scale(ts_rgb_mul(b->r, ts_rgb_sub(ts_rgb_gray(1), b->rs)), k);
    if (!b->blend_glossy) return rgb_finite(diffuse);
    ts_vec3 wh = ts_vec3_add(wi, wo);
    if (wh.x == 0 && wh.y == 0 && wh.z == 0) return rgb_finite(diffuse);
    wh = ts_vec3_normalize(wh);
    float dot_ih = 0.5f * (fabsf(ts_vec3_dot(wi, wh)) + fabsf(ts_vec3_dot(wo, wh))); /* symmetric in wo, wi */
    float denom = 4 * dot_ih * ts_maxf(ci, co);
    if (!(denom > 0)) return rgb_finite(diffuse);
    ts_rgb spec = ts_rgb_scale(schlick(b->rs, dot_ih), ts_microfacet_d(&b->dist, wh) / denom);
    return rgb_finite(ts_rgb_add(diffuse, spec));
}

/* Lambertian under a coat: light crossing the coat twice loses what the coat's specular
 * lobe reflects at each crossing (|cos| so both sides of the surface agree). */
static ts_rgb coupled_diffuse_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    ts_rgb fo = ts_fresnel_eval(&b->fresnel, fabsf(wo.z)), fi = ts_fresnel_eval(&b->fresnel, fabsf(wi.z));
    ts_rgb t = {(1 - b->rs.r * fo.r) * (1 - b->rs.r * fi.r), (1 - b->rs.g * fo.g) * (1 - b->rs.g * fi.g),
                (1 - b->rs.b * fo.b) * (1 - b->rs.b * fi.b)};
    return rgb_finite(ts_rgb_scale(ts_rgb_mul(b->r, t), TS_INV_PI));
}

/* f of the lobe without its ScaledBxDF factor. */
static ts_rgb lobe_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    if (wo.z == 0 || !ts_vec3_is_finite(wo) || !ts_vec3_is_finite(wi)) return black();
    switch (b->type) {
    case TS_BXDF_LAMBERTIAN: return b->diffuse_coupled ? coupled_diffuse_f(b, wo, wi) : ts_rgb_scale(b->r, TS_INV_PI);
    case TS_BXDF_LAMBERTIAN_TRANSMISSION: return ts_rgb_scale(b->t, TS_INV_PI); /* the BSDF picks the side pair */
    case TS_BXDF_OREN_NAYAR: return oren_nayar_f(b, wo, wi);
    case TS_BXDF_MICROFACET_REFLECTION: return microfacet_reflection_f(b, wo, wi);
    case TS_BXDF_MICROFACET_TRANSMISSION:
        if (b->flags & TS_BXDF_SPECULAR) return black();
        return microfacet_transmission_f(b, wo, wi);
    case TS_BXDF_FRESNEL_BLEND: return fresnel_blend_f(b, wo, wi);
    case TS_BXDF_FOURIER: return rgb_finite(ts_fourier_f(b->fourier, wo, wi));
    case TS_BXDF_SPECULAR_REFLECTION:
    case TS_BXDF_SPECULAR_TRANSMISSION:
    case TS_BXDF_FRESNEL_SPECULAR: return black();
    }
    return black();
}

ts_rgb ts_bxdf_f(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    ts_rgb f = lobe_f(b, wo, wi);
    return b->scaled ? rgb_finite(ts_rgb_mul(f, b->scale)) : f;
}

/* ------------------------------------------------------------- lobes: pdf ---- */

static float cosine_pdf(ts_vec3 wo, ts_vec3 wi) { return ts_same_hemisphere(wo, wi) ? fabsf(wi.z) * TS_INV_PI : 0; }
/* The cosine density on the hemisphere opposite wo (diffuse transmission). */
static float cosine_pdf_opposite(ts_vec3 wo, ts_vec3 wi)
{
    return ts_same_hemisphere(wo, wi) || wi.z == 0 ? 0 : fabsf(wi.z) * TS_INV_PI;
}

static float microfacet_reflection_pdf(const ts_microfacet *d, ts_vec3 wo, ts_vec3 wi)
{
    if (!ts_same_hemisphere(wo, wi)) return 0;
    ts_vec3 wh = ts_vec3_add(wo, wi);
    if (wh.x == 0 && wh.y == 0 && wh.z == 0) return 0;
    wh = ts_vec3_normalize(wh);
    float dot = fabsf(ts_vec3_dot(wo, wh));
    if (!(dot > 0)) return 0;
    float p = ts_microfacet_pdf(d, wo, wh) / (4 * dot);
    return isfinite(p) ? p : 0;
}

static float microfacet_transmission_pdf(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    ts_vec3 wh;
    float eta;
    if (!transmission_half(b, wo, wi, &wh, &eta)) return 0;
    float dot_o = ts_vec3_dot(wo, wh), dot_i = ts_vec3_dot(wi, wh);
    float denom = dot_o + eta * dot_i;
    float dwh_dwi = fabsf(eta * eta * dot_i / (denom * denom));
    float p = ts_microfacet_pdf(&b->dist, wo, wh) * dwh_dwi;
    return isfinite(p) ? p : 0;
}

float ts_bxdf_pdf(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi)
{
    if (wo.z == 0 || !ts_vec3_is_finite(wo) || !ts_vec3_is_finite(wi)) return 0;
    switch (b->type) {
    case TS_BXDF_LAMBERTIAN:
    case TS_BXDF_OREN_NAYAR: return cosine_pdf(wo, wi);
    case TS_BXDF_LAMBERTIAN_TRANSMISSION: return cosine_pdf_opposite(wo, wi);
    case TS_BXDF_MICROFACET_REFLECTION: return microfacet_reflection_pdf(&b->dist, wo, wi);
    case TS_BXDF_MICROFACET_TRANSMISSION:
        if (b->flags & TS_BXDF_SPECULAR) return 0;
        return microfacet_transmission_pdf(b, wo, wi);
    case TS_BXDF_FRESNEL_BLEND:
        if (!b->blend_glossy) return cosine_pdf(wo, wi);
        return 0.5f * (cosine_pdf(wo, wi) + microfacet_reflection_pdf(&b->dist, wo, wi));
    case TS_BXDF_FOURIER: {
        float p = ts_fourier_pdf(b->fourier, wo, wi);
        return isfinite(p) && p > 0 ? p : 0;
    }
    case TS_BXDF_SPECULAR_REFLECTION:
    case TS_BXDF_SPECULAR_TRANSMISSION:
    case TS_BXDF_FRESNEL_SPECULAR: return 0;
    }
    return 0;
}

/* ---------------------------------------------------------- lobes: sample ---- */

static ts_vec3 cosine_sample(ts_vec3 wo, ts_vec2 u)
{
    ts_vec3 wi = ts_sample_cosine_hemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    return wi;
}

/* Fills out from f(wo, wi) and pdf(wo, wi) of a non-specular lobe; false if the pdf is 0. */
static bool finish_sample(const ts_bxdf *b, ts_vec3 wo, ts_vec3 wi, uint32_t flags, float eta,
                          ts_bxdf_sample *out)
{
    if (!ts_vec3_is_finite(wi) || wi.z == 0) return false;
    out->wi = wi;
    out->pdf = ts_bxdf_pdf(b, wo, wi);
    if (!(out->pdf > 0)) return false;
    out->f = lobe_f(b, wo, wi);
    out->flags = flags;
    out->eta = eta;
    return true;
}

static bool sample_reflected_wh(const ts_microfacet *d, ts_vec3 wo, ts_vec2 u, ts_vec3 *wi)
{
    ts_vec3 wh = ts_microfacet_sample_wh(d, wo, u);
    if (!(ts_vec3_dot(wo, wh) > 0)) return false;
    *wi = ts_reflect(wo, wh);
    return ts_same_hemisphere(wo, *wi);
}

/* A sample of the lobe, its f without the ScaledBxDF factor. */
static bool sample_lobe(const ts_bxdf *b, ts_vec3 wo, ts_vec2 u, ts_bxdf_sample *out)
{
    if (wo.z == 0 || !ts_vec3_is_finite(wo)) return false;
    u.x = ts_clampf(u.x, 0, TS_ONE_MINUS_EPSILON);
    u.y = ts_clampf(u.y, 0, TS_ONE_MINUS_EPSILON);
    switch (b->type) {
    case TS_BXDF_LAMBERTIAN:
    case TS_BXDF_OREN_NAYAR: return finish_sample(b, wo, cosine_sample(wo, u), b->flags, 1, out);
    case TS_BXDF_LAMBERTIAN_TRANSMISSION: {
        ts_vec3 wi = cosine_sample(wo, u);
        wi.z = -wi.z;
        return finish_sample(b, wo, wi, b->flags, 1, out);
    }
    case TS_BXDF_MICROFACET_REFLECTION: {
        ts_vec3 wi;
        if (!sample_reflected_wh(&b->dist, wo, u, &wi)) return false;
        return finish_sample(b, wo, wi, b->flags, 1, out);
    }
    case TS_BXDF_MICROFACET_TRANSMISSION: {
        if (b->flags & TS_BXDF_SPECULAR) { /* matched indices: straight through, no Fresnel */
            out->wi = ts_vec3_neg(wo);
            out->pdf = 1;
            out->f = rgb_finite(ts_rgb_scale(b->t, 1 / fabsf(wo.z)));
            out->flags = b->flags;
            out->eta = 1;
            return true;
        }
        ts_vec3 wh = ts_microfacet_sample_wh(&b->dist, wo, u), wi;
        if (!(ts_vec3_dot(wo, wh) > 0)) return false;
        float eta_io = wo.z > 0 ? b->eta_a / b->eta_b : b->eta_b / b->eta_a; /* η_i / η_t */
        if (!ts_refract(wo, wh, eta_io, &wi)) return false; /* total internal reflection */
        if (ts_same_hemisphere(wo, wi)) return false;
        return finish_sample(b, wo, ts_vec3_normalize(wi), b->flags, 1 / eta_io, out);
    }
    case TS_BXDF_FRESNEL_BLEND: {
        ts_vec3 wi;
        if (!b->blend_glossy) return finish_sample(b, wo, cosine_sample(wo, u), b->flags, 1, out);
        if (u.x < 0.5f) {
            wi = cosine_sample(wo, (ts_vec2){ts_minf(2 * u.x, TS_ONE_MINUS_EPSILON), u.y});
            return finish_sample(b, wo, wi, TS_BXDF_REFLECTION | TS_BXDF_DIFFUSE, 1, out);
        }
        if (!sample_reflected_wh(&b->dist, wo, (ts_vec2){ts_minf(2 * (u.x - 0.5f), TS_ONE_MINUS_EPSILON), u.y}, &wi))
            return false;
        return finish_sample(b, wo, wi, TS_BXDF_REFLECTION | TS_BXDF_GLOSSY, 1, out);
    }
    case TS_BXDF_FOURIER: {
        ts_vec3 wi;
        float pdf;
        ts_rgb f = ts_fourier_sample(b->fourier, wo, u, &wi, &pdf);
        if (!(pdf > 0) || !ts_vec3_is_finite(wi) || wi.z == 0) return false;
        bool refl = ts_same_hemisphere(wo, wi);
        float eta = ts_maxf(b->fourier->eta, 1e-6f);
        out->wi = wi;
        out->f = rgb_finite(f);
        out->pdf = pdf;
        out->flags = TS_BXDF_GLOSSY | (refl ? TS_BXDF_REFLECTION : TS_BXDF_TRANSMISSION);
        out->eta = refl ? 1 : (wo.z > 0 ? eta : 1 / eta);
        return true;
    }
    case TS_BXDF_SPECULAR_REFLECTION: {
        ts_vec3 wi = {-wo.x, -wo.y, wo.z};
        out->wi = wi;
        out->pdf = 1;
        out->f = rgb_finite(ts_rgb_scale(ts_rgb_mul(b->r, ts_fresnel_eval(&b->fresnel, wi.z)), 1 / fabsf(wi.z)));
        out->flags = b->flags;
        out->eta = 1;
        return true;
    }
    case TS_BXDF_SPECULAR_TRANSMISSION:
    case TS_BXDF_FRESNEL_SPECULAR: {
        float fr = ts_fresnel_dielectric(wo.z, b->eta_a, b->eta_b);
        if (b->type == TS_BXDF_FRESNEL_SPECULAR && u.x < fr) {
            ts_vec3 wi = {-wo.x, -wo.y, wo.z};
            out->wi = wi;
            out->pdf = fr;
            out->f = rgb_finite(ts_rgb_scale(b->r, fr / fabsf(wi.z)));
            out->flags = TS_BXDF_REFLECTION | TS_BXDF_SPECULAR;
            out->eta = 1;
            return true;
        }
        bool entering = wo.z > 0;
        float eta_i = entering ? b->eta_a : b->eta_b, eta_t = entering ? b->eta_b : b->eta_a;
        ts_vec3 wi;
        if (!ts_refract(wo, ts_vec3_faceforward((ts_vec3){0, 0, 1}, wo), eta_i / eta_t, &wi)) return false;
        if (wi.z == 0 || ts_same_hemisphere(wo, wi)) return false;
        float ft = (1 - fr) * (eta_i * eta_i) / (eta_t * eta_t);
        out->wi = wi;
        out->pdf = b->type == TS_BXDF_FRESNEL_SPECULAR ? 1 - fr : 1;
        if (!(out->pdf > 0)) return false;
        out->f = rgb_finite(ts_rgb_scale(b->t, ft / fabsf(wi.z)));
        out->flags = TS_BXDF_TRANSMISSION | TS_BXDF_SPECULAR;
        out->eta = eta_t / eta_i;
        return true;
    }
    }
    return false;
}

bool ts_bxdf_sample_f(const ts_bxdf *b, ts_vec3 wo, ts_vec2 u, ts_bxdf_sample *out)
{
    if (!sample_lobe(b, wo, u, out)) return false;
    if (b->scaled) out->f = rgb_finite(ts_rgb_mul(out->f, b->scale));
    return true;
}

/* ------------------------------------------------------------ reflectance ---- */

ts_rgb ts_bxdf_rho_hd(const ts_bxdf *b, ts_vec3 wo, int n, const ts_vec2 *u)
{
    double r = 0, g = 0, bl = 0;
    for (int i = 0; i < n; i++) {
        ts_bxdf_sample s;
        if (!ts_bxdf_sample_f(b, wo, u[i], &s) || !(s.pdf > 0)) continue;
        double w = fabsf(s.wi.z) / s.pdf;
        r += s.f.r * w;
        g += s.f.g * w;
        bl += s.f.b * w;
    }
    return n > 0 ? (ts_rgb){(float)(r / n), (float)(g / n), (float)(bl / n)} : black();
}

ts_rgb ts_bxdf_rho_hh(const ts_bxdf *b, int n, const ts_vec2 *u_wo, const ts_vec2 *u_wi)
{
    double r = 0, g = 0, bl = 0;
    for (int i = 0; i < n; i++) {
        ts_vec3 wo = ts_sample_uniform_hemisphere(u_wo[i]);
        ts_bxdf_sample s;
        if (!ts_bxdf_sample_f(b, wo, u_wi[i], &s) || !(s.pdf > 0)) continue;
        double w = fabsf(s.wi.z) * fabsf(wo.z) / (s.pdf * ts_uniform_hemisphere_pdf());
        r += s.f.r * w;
        g += s.f.g * w;
        bl += s.f.b * w;
    }
    double k = n > 0 ? 1.0 / (TS_PI_D * n) : 0;
    return (ts_rgb){(float)(r * k), (float)(g * k), (float)(bl * k)};
}
