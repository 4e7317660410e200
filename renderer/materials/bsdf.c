/* bsdf.c — see bsdf.h (pbrt-v3 §9.1 BSDF, §14.1.6 sampling of the mixture). */
#include "materials/bsdf.h"

#include <string.h>

#include "sampling/sampling.h"

void ts_bsdf_init(ts_bsdf *b, ts_vec3 ng, ts_vec3 ns, ts_vec3 dpdu, float eta)
{
    b->ng = ts_vec3_normalize(ng);
    /* Without shading normals ns is ng, bit for bit: its normalisation is b->ng's. */
    b->ns = memcmp(&ns, &ng, sizeof ns) == 0 ? b->ng : ts_vec3_normalize(ns);
    if (!(ts_vec3_length_sq(b->ns) > 0.5f) || !ts_vec3_is_finite(b->ns)) b->ns = b->ng;
    /* Gram–Schmidt dpdu against ns; fall back to an arbitrary tangent. */
    ts_vec3 s = ts_vec3_sub(dpdu, ts_vec3_scale(b->ns, ts_vec3_dot(b->ns, dpdu)));
    float len = ts_vec3_length(s);
    if (len > 1e-12f && isfinite(len)) {
        b->ss = ts_vec3_scale(s, 1 / len);
        b->ts = ts_vec3_cross(b->ns, b->ss);
    } else {
        ts_coordinate_system(b->ns, &b->ss, &b->ts);
    }
    b->eta = eta;
    b->n_bxdfs = 0;
}

bool ts_bsdf_add(ts_bsdf *b, ts_bxdf bxdf)
{
    if (b->n_bxdfs >= TS_BSDF_MAX_BXDFS) return false;
    b->bxdfs[b->n_bxdfs++] = bxdf;
    return true;
}

ts_vec3 ts_bsdf_world_to_local(const ts_bsdf *b, ts_vec3 v)
{
    return (ts_vec3){ts_vec3_dot(v, b->ss), ts_vec3_dot(v, b->ts), ts_vec3_dot(v, b->ns)};
}

ts_vec3 ts_bsdf_local_to_world(const ts_bsdf *b, ts_vec3 v)
{
    return ts_vec3_add(ts_vec3_add(ts_vec3_scale(b->ss, v.x), ts_vec3_scale(b->ts, v.y)), ts_vec3_scale(b->ns, v.z));
}

static ts_rgb sum_f(const ts_bsdf *b, ts_vec3 wo, ts_vec3 wi, bool reflect)
{
    ts_rgb f = {0, 0, 0};
    uint32_t want = reflect ? TS_BXDF_REFLECTION : TS_BXDF_TRANSMISSION;
    for (int i = 0; i < b->n_bxdfs; i++) {
        const ts_bxdf *x = &b->bxdfs[i];
        if ((x->flags & TS_BXDF_SPECULAR) || !(x->flags & want)) continue;
        f = ts_rgb_add(f, ts_bxdf_f(x, wo, wi));
    }
    return f;
}

ts_rgb ts_bsdf_f(const ts_bsdf *b, ts_vec3 wo_world, ts_vec3 wi_world)
{
    ts_vec3 wo = ts_bsdf_world_to_local(b, wo_world), wi = ts_bsdf_world_to_local(b, wi_world);
    if (wo.z == 0) return (ts_rgb){0, 0, 0};
    bool reflect = ts_vec3_dot(wi_world, b->ng) * ts_vec3_dot(wo_world, b->ng) > 0;
    return sum_f(b, wo, wi, reflect);
}

float ts_bsdf_pdf(const ts_bsdf *b, ts_vec3 wo_world, ts_vec3 wi_world)
{
    if (b->n_bxdfs == 0) return 0;
    ts_vec3 wo = ts_bsdf_world_to_local(b, wo_world), wi = ts_bsdf_world_to_local(b, wi_world);
    if (wo.z == 0) return 0;
    float pdf = 0;
    for (int i = 0; i < b->n_bxdfs; i++) pdf += ts_bxdf_pdf(&b->bxdfs[i], wo, wi);
    return pdf / (float)b->n_bxdfs;
}

bool ts_bsdf_sample_f(const ts_bsdf *b, ts_vec3 wo_world, float u_lobe, ts_vec2 u, ts_bsdf_sample *out)
{
    int n = b->n_bxdfs;
    if (n == 0) return false;
    int comp = (int)(ts_clampf(u_lobe, 0, 1) * (float)n);
    if (comp >= n) comp = n - 1;
    if (comp < 0) comp = 0;
    ts_vec3 wo = ts_bsdf_world_to_local(b, wo_world);
    if (wo.z == 0 || !ts_vec3_is_finite(wo)) return false;
    const ts_bxdf *x = &b->bxdfs[comp];
    ts_bxdf_sample s;
    if (!ts_bxdf_sample_f(x, wo, u, &s) || !(s.pdf > 0)) return false;
    ts_vec3 wi_world = ts_bsdf_local_to_world(b, s.wi);
    out->wi = wi_world;
    out->flags = s.flags;
    out->eta = s.eta;
    if (x->flags & TS_BXDF_SPECULAR) {
        out->f = s.f;
        out->pdf = s.pdf / (float)n;
    } else {
        float pdf = s.pdf;
        for (int i = 0; i < n; i++)
            if (i != comp) pdf += ts_bxdf_pdf(&b->bxdfs[i], wo, s.wi);
        out->pdf = pdf / (float)n;
        bool reflect = ts_vec3_dot(wi_world, b->ng) * ts_vec3_dot(wo_world, b->ng) > 0;
        /* sum_f of a single lobe is its ts_bxdf_f(wo, wi), which s.f is already (bxdf.h's
         * sampling contract; exactly so for every lobe but the tabulated Fourier one,
         * whose sampled f comes from its own inversion). */
        if (n == 1 && x->type != TS_BXDF_FOURIER)
            out->f = (x->flags & (reflect ? TS_BXDF_REFLECTION : TS_BXDF_TRANSMISSION)) ? s.f : (ts_rgb){0, 0, 0};
        else
            out->f = sum_f(b, wo, s.wi, reflect);
    }
    if (!(out->pdf > 0) || !isfinite(out->pdf) || ts_rgb_is_black(out->f) || !ts_rgb_is_finite(out->f)) return false;
    return true;
}

uint32_t ts_bsdf_flags(const ts_bsdf *b)
{
    uint32_t f = 0;
    for (int i = 0; i < b->n_bxdfs; i++) f |= b->bxdfs[i].flags;
    return f;
}

int ts_bsdf_num_non_specular(const ts_bsdf *b)
{
    int c = 0;
    for (int i = 0; i < b->n_bxdfs; i++)
        if (!(b->bxdfs[i].flags & TS_BXDF_SPECULAR)) c++;
    return c;
}

ts_rgb ts_bsdf_rho_hd(const ts_bsdf *b, ts_vec3 wo_world, int n, const float *u_lobe, const ts_vec2 *u)
{
    double r = 0, g = 0, bl = 0;
    for (int i = 0; i < n; i++) {
        ts_bsdf_sample s;
        if (!ts_bsdf_sample_f(b, wo_world, u_lobe[i], u[i], &s)) continue;
        double w = ts_vec3_absdot(s.wi, b->ns) / s.pdf;
        r += s.f.r * w;
        g += s.f.g * w;
        bl += s.f.b * w;
    }
    return n > 0 ? (ts_rgb){(float)(r / n), (float)(g / n), (float)(bl / n)} : (ts_rgb){0, 0, 0};
}

ts_rgb ts_bsdf_rho_hh(const ts_bsdf *b, int n, const ts_vec2 *u_wo, const float *u_lobe, const ts_vec2 *u_wi)
{
    double r = 0, g = 0, bl = 0;
    for (int i = 0; i < n; i++) {
        ts_vec3 wo = ts_bsdf_local_to_world(b, ts_sample_uniform_hemisphere(u_wo[i]));
        ts_bsdf_sample s;
        if (!ts_bsdf_sample_f(b, wo, u_lobe[i], u_wi[i], &s)) continue;
        double w = ts_vec3_absdot(s.wi, b->ns) * ts_vec3_absdot(wo, b->ns) / (s.pdf * ts_uniform_hemisphere_pdf());
        r += s.f.r * w;
        g += s.f.g * w;
        bl += s.f.b * w;
    }
    double k = n > 0 ? 1.0 / (TS_PI_D * n) : 0;
    return (ts_rgb){(float)(r * k), (float)(g * k), (float)(bl * k)};
}
