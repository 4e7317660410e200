/* integrator.c — integrator dispatch and the debugging views; see integrator.h. */
#include "integrators/integrator.h"

#include <stdio.h>

#include "integrators/effects.h"
#include "integrators/volpath.h"
#include "lights/light.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "sampling/sampling.h"
#include "textures/texture_mapping.h"

const char *ts_integrator_name(ts_integrator_type type)
{
    switch (type) {
    case TS_INTEGRATOR_PATH: return "path";
    case TS_INTEGRATOR_DIRECT: return "direct";
    case TS_INTEGRATOR_AO: return "ao";
    case TS_INTEGRATOR_NORMALS: return "normals";
    case TS_INTEGRATOR_VOLPATH: return "volpath";
    }
    return "unknown";
}

/* The camera ray's first hit on a surface: shapes without one (material none, bounding a
 * medium) are passed through, as pbrt-v3's integrators skip a hit without a BSDF
 * (`ray = isect.SpawnRay(ray.d)`); false on a miss or past the crossing bound (counted). */
static bool first_surface(const ts_scene *s, uint32_t fx, const ts_ray *ray, ts_interaction *si, ts_counters *c)
{
    if (!ts_accel_intersect(s->accel, ray, si)) return false;
    if (!(fx & TS_EFFECT_MEDIA)) return true; /* no shape without a surface */
    for (uint32_t k = 0; s->shapes[si->shape].material == TS_NONE; k++) {
        if (k >= TS_VOLPATH_MAX_CROSSINGS) {
            c->walks_truncated++;
            return false;
        }
        ts_ray next = ts_spawn_ray(si, s->shapes, ray->d);
        c->other_rays++;
        if (!ts_accel_intersect(s->accel, &next, si)) return false;
    }
    return true;
}

/* Ambient occlusion: the cosine-weighted fraction of the hemisphere around the shading
 * normal (turned to face the viewer) that is open within ao_distance. One shadow ray per
 * sample, so the estimate is 0 or 1 and its mean is the occlusion integral ∫V cosθ/π.
 * As pbrt-v3's AOIntegrator, the camera ray passes shapes without a surface and the
 * occlusion ray (its IntersectP) is blocked by them. */
static ts_rgb li_ao(const ts_scene *s, uint32_t fx, const ts_ray *ray, ts_sample_stream *st, ts_counters *c)
{
    ts_interaction si;
    if (!first_surface(s, fx, ray, &si, c)) return ts_rgb_gray(0);
    ts_vec3 n = ts_vec3_faceforward(si.n, si.wo);
    ts_vec3 ns = ts_vec3_faceforward(si.ns, n);
    ts_vec3 a, b;
    ts_coordinate_system(ns, &a, &b);
    ts_vec3 w_local = ts_sample_cosine_hemisphere(ts_sample_2d(st));
    ts_vec3 w = ts_vec3_add(ts_vec3_add(ts_vec3_scale(a, w_local.x), ts_vec3_scale(b, w_local.y)),
                            ts_vec3_scale(ns, w_local.z));
    if (ts_vec3_dot(w, n) <= 0) return ts_rgb_gray(0); /* below the geometric surface */
    ts_ray shadow = ts_spawn_ray(&si, s->shapes, w);
    shadow.tmax = s->integrator.ao_distance;
    c->other_rays++;
    return ts_accel_occluded(s->accel, &shadow) ? ts_rgb_gray(0) : ts_rgb_gray(1);
}

/* The shading normal of the first surface (shapes without one passed, as ao's). */
static ts_rgb li_normals(const ts_scene *s, uint32_t fx, const ts_ray *ray, ts_counters *c)
{
    ts_interaction si;
    if (!first_surface(s, fx, ray, &si, c)) return ts_rgb_gray(0);
    return (ts_rgb){0.5f * (si.ns.x + 1), 0.5f * (si.ns.y + 1), 0.5f * (si.ns.z + 1)};
}

/* ---------------------------------------------------------------- shared light transport */

/* Emitted radiance leaving hit si towards w, if its shape emits. */
static ts_rgb emitted(const ts_scene *s, const ts_interaction *si, ts_vec3 w)
{
    const ts_shape *sh = &s->shapes[si->shape];
    if (!sh->emissive) return ts_rgb_gray(0);
    const ts_light *l = &s->lights[ts_area_light_index(sh, si->prim)];
    return ts_area_light_l(l, si, w);
}

/* Radiance of every infinite light along an escaping ray. */
static ts_rgb escaped(const ts_scene *s, const ts_ray *ray)
{
    ts_rgb L = ts_rgb_gray(0);
    for (uint32_t i = 0; i < s->n_infinite_lights; i++)
        L = ts_rgb_add(L, ts_light_le(&s->lights[s->infinite_lights[i]], ray));
    return L;
}

/* A textured material's BSDF, its parameters read at si's texture context with rd's
 * footprint: a call of its own, so the context's storage does not weigh on the constant
 * path. */
static __attribute__((noinline)) void textured_bsdf(const ts_material *m, ts_interaction *si,
                                                    const ts_ray_differential *rd, ts_bsdf *bsdf)
{
    ts_texture_context tc;
    ts_ray_differential_context(si, rd, &tc);
    ts_material_bump(m, si, &tc);
    ts_material_bsdf(m, si, &tc, bsdf);
}

/* The BSDF at hit si, reached by a ray with differential rd (or NULL); a bump map
 * replaces si's shading normal first (ts_material_bump), as pbrt-v3's does. */
static inline void material_bsdf(const ts_scene *s, ts_interaction *si, const ts_ray_differential *rd,
                                 ts_bsdf *bsdf)
{
    const ts_material *m = &s->materials[s->shapes[si->shape].material];
    if (m->textured) textured_bsdf(m, si, rd, bsdf);
    else ts_material_bsdf(m, si, NULL, bsdf);
}

static float power_heuristic(float f_pdf, float g_pdf) { return ts_power_heuristic(1, f_pdf, 1, g_pdf); }

/* A shape that only bounds a medium (material none). */
static bool no_surface(const ts_scene *s, const ts_interaction *si) { return s->shapes[si->shape].material == TS_NONE; }

/* Whether the sample should end now (ts_counters.stop). */
static bool stopped(const ts_counters *c) { return c->stop && atomic_load_explicit(c->stop, memory_order_relaxed); }

static bool is_delta_light(const ts_light *light)
{
    return light->type == TS_LIGHT_POINT || light->type == TS_LIGHT_SPOT || light->type == TS_LIGHT_DISTANT;
}

/* EstimateDirect's light sample (u_light), if it takes one: false if it does not or the
 * sample is empty. Pure, so it may run ahead of the rest of its estimate. */
static bool direct_light_sample(const ts_scene *s, const ts_interaction *si, const ts_light *light, ts_vec2 u_light,
                                ts_light_sample *ls)
{
    if (!is_delta_light(light) && s->integrator.sampling == TS_SAMPLING_BSDF) {
        *ls = (ts_light_sample){0};
        return false;
    }
    return ts_light_sample_li(light, s->shapes, si, u_light, ls);
}

/* pbrt's EstimateDirect: light `li` sampled with u_light, the BSDF with (u_lobe, u_bsdf),
 * combined by the power heuristic; delta lights get light sampling only. The BSDF here
 * samples all its lobes; a specular pick adds nothing (specular transport is handled by
 * the caller), which stays unbiased because the returned pdf includes the lobe choice.
 * The light sample comes made (direct_light_sample: sampled, and ls): sample_all_lights
 * makes a batch of them first. */
static ts_rgb estimate_direct_sampled(const ts_scene *s, const ts_interaction *si, const ts_bsdf *bsdf, uint32_t li,
                                      bool sampled, const ts_light_sample *ls_made, float u_lobe, ts_vec2 u_bsdf,
                                      ts_counters *c)
{
    const ts_light *light = &s->lights[li];
    const ts_direct_sampling sampling = s->integrator.sampling;
    bool delta = is_delta_light(light);
    ts_rgb Ld = ts_rgb_gray(0);
    const ts_light_sample ls = *ls_made;
    if (sampled) {
        ts_rgb f = ts_rgb_scale(ts_bsdf_f(bsdf, si->wo, ls.wi), ts_vec3_absdot(ls.wi, si->ns));
        if (!ts_rgb_is_black(f)) {
            ts_ray shadow = ts_spawn_ray_to(si, s->shapes, ls.p_light, ls.p_light_error, ls.n_light);
            c->other_rays++;
            if (!ts_accel_occluded(s->accel, &shadow)) {
                if (ls.is_delta || sampling == TS_SAMPLING_LIGHT) Ld = ts_rgb_scale(ts_rgb_mul(f, ls.L), 1.0f / ls.pdf);
                else {
                    float w = power_heuristic(ls.pdf, ts_bsdf_pdf(bsdf, si->wo, ls.wi));
                    Ld = ts_rgb_scale(ts_rgb_mul(f, ls.L), w / ls.pdf);
                }
            }
        }
    }
    if (delta || sampling == TS_SAMPLING_LIGHT) return Ld;
    ts_bsdf_sample bs;
    if (!ts_bsdf_sample_f(bsdf, si->wo, u_lobe, u_bsdf, &bs) || (bs.flags & TS_BXDF_SPECULAR) || !(bs.pdf > 0))
        return Ld;
    ts_rgb f = ts_rgb_scale(bs.f, ts_vec3_absdot(bs.wi, si->ns));
    if (ts_rgb_is_black(f)) return Ld;
    ts_ray ray = ts_spawn_ray(si, s->shapes, bs.wi);
    ts_interaction hit;
    c->other_rays++;
    ts_light_query query; /* an environment map's texels are fetched while the ray is traced */
    if (light->type == TS_LIGHT_INFINITE) ts_light_query_begin(light, bs.wi, &query);
    ts_rgb Li = ts_rgb_gray(0);
    float light_pdf = 0;
    if (ts_accel_intersect(s->accel, &ray, &hit)) {
        const ts_shape *sh = &s->shapes[hit.shape];
        if (light->type == TS_LIGHT_AREA && sh->emissive &&
            ts_area_light_index(sh, hit.prim) == li) {
            light_pdf = ts_light_pdf_li_hit(light, s->shapes, si, hit.p);
            Li = ts_area_light_l(light, &hit, ts_vec3_neg(bs.wi));
        }
    } else if (light->type == TS_LIGHT_INFINITE) {
        Li = ts_light_query_le_pdf(light, &query, &light_pdf); /* the ray's direction is bs.wi */
    }
    if (ts_rgb_is_black(Li) || !(light_pdf > 0)) return Ld;
    float w = sampling == TS_SAMPLING_BSDF ? 1.0f : power_heuristic(bs.pdf, light_pdf);
    return ts_rgb_add(Ld, ts_rgb_scale(ts_rgb_mul(f, Li), w / bs.pdf));
}

static ts_rgb estimate_direct(const ts_scene *s, const ts_interaction *si, const ts_bsdf *bsdf, uint32_t li,
                              ts_vec2 u_light, float u_lobe, ts_vec2 u_bsdf, ts_counters *c)
{
    ts_light_sample ls;
    bool sampled = direct_light_sample(s, si, &s->lights[li], u_light, &ls);
    return estimate_direct_sampled(s, si, bsdf, li, sampled, &ls, u_lobe, u_bsdf, c);
}

/* The random numbers of what the effects rule out are not computed; their dimensions are
 * still consumed, so every later value is the same as without the specialisation. */

/* Lobe choice: ts_bsdf_sample_f never reads it from a BSDF of one lobe. */
static float lobe_u(uint32_t fx, ts_sample_stream *st)
{
    if (fx & TS_EFFECT_LOBE_CHOICE) return ts_sample_1d(st);
    st->dim++;
    return 0;
}

/* Whether next-event estimation samples the BSDF too: only towards lights that are not
 * delta lights (estimate_direct). */
static bool nee_samples_bsdf(uint32_t fx) { return (fx & (TS_EFFECT_AREA_LIGHTS | TS_EFFECT_ENVIRONMENT)) != 0; }

/* pbrt's UniformSampleOneLight: one light from the distribution, divided by its pmf. */
static ts_rgb sample_one_light(const ts_scene *s, uint32_t fx, const ts_interaction *si, const ts_bsdf *bsdf,
                               ts_sample_stream *st, ts_counters *c)
{
    ts_vec2 u_select = ts_sample_2d(st); /* x: the alias bin, y: its coin (integrator.h) */
    ts_vec2 u_light = ts_sample_2d(st);
    float u_lobe = 0;
    ts_vec2 u_bsdf = {0, 0};
    if (nee_samples_bsdf(fx)) {
        u_lobe = lobe_u(fx, st);
        u_bsdf = ts_sample_2d(st);
    } else {
        st->dim += 2;
    }
    float pmf;
    uint32_t li = ts_light_distribution_sample_at(&s->light_distribution, si->p, si->ns, u_select, &pmf);
    if (li == TS_NONE || !(pmf > 0)) return ts_rgb_gray(0);
    return ts_rgb_scale(estimate_direct(s, si, bsdf, li, u_light, u_lobe, u_bsdf, c), 1.0f / pmf);
}

/* The samples a light takes under strategy all: its own count (pbrt-v3's nSamples) or the
 * integrator's samples_per_light. */
static uint32_t light_samples(const ts_scene *s, uint32_t li)
{
    uint32_t n = s->lights[li].samples;
    return n ? n : (uint32_t)s->integrator.samples_per_light;
}

#define LIGHT_BATCH 8 /* light samples made ahead in sample_all_lights */

/* pbrt's UniformSampleAllLights: each light's samples (light_samples), drawn as arrays
 * (consecutive sequence indices of one dimension) so that they are stratified together. */
static ts_rgb sample_all_lights(const ts_scene *s, uint32_t fx, const ts_interaction *si, const ts_bsdf *bsdf,
                                ts_sample_stream *st, ts_counters *c)
{
    ts_rgb L = ts_rgb_gray(0);
    ts_sampler sampler = {st->type, st->seed};
    for (uint32_t li = 0; li < s->n_lights && !stopped(c); li++) {
        uint32_t n = light_samples(s, li), dim = st->dim;
        st->dim += 3;
        /* The three dimensions' seeds once for the light's n samples (sampler.h). */
        ts_sampler_dim d_light, d_lobe, d_bsdf;
        ts_sampler_dim_init(&sampler, st->px, st->py, dim, &d_light);
        ts_sampler_dim_init(&sampler, st->px, st->py, dim + 1, &d_lobe);
        ts_sampler_dim_init(&sampler, st->px, st->py, dim + 2, &d_bsdf);
        ts_rgb Ll = ts_rgb_gray(0);
        /* The light samples of a batch are made first, then their estimates in order: the
         * same values and sum, but a batch's environment-map searches, independent of each
         * other, overlap their cache misses. */
        for (uint32_t j0 = 0; j0 < n; j0 += LIGHT_BATCH) {
            uint32_t nb = n - j0 < LIGHT_BATCH ? n - j0 : LIGHT_BATCH;
            ts_light_sample ls[LIGHT_BATCH];
            bool sampled[LIGHT_BATCH];
            for (uint32_t k = 0; k < nb; k++) {
                ts_vec2 u_light = ts_sampler_dim_value_2d(&d_light, st->index * n + j0 + k);
                sampled[k] = direct_light_sample(s, si, &s->lights[li], u_light, &ls[k]);
            }
            for (uint32_t k = 0; k < nb; k++) {
                uint32_t index = st->index * n + j0 + k;
                float u_lobe = 0;
                ts_vec2 u_bsdf = {0, 0};
                if (nee_samples_bsdf(fx)) {
                    if (fx & TS_EFFECT_LOBE_CHOICE) u_lobe = ts_sampler_dim_value_1d(&d_lobe, index);
                    u_bsdf = ts_sampler_dim_value_2d(&d_bsdf, index);
                }
                Ll = ts_rgb_add(Ll, estimate_direct_sampled(s, si, bsdf, li, sampled[k], &ls[k], u_lobe, u_bsdf, c));
            }
        }
        L = ts_rgb_add(L, ts_rgb_scale(Ll, 1.0f / (float)n));
    }
    return L;
}

/* ---------------------------------------------------------------- path */

/* Next-event estimation of the path integrator (pbrt-v4's SampleLd): one light from the
 * distribution, one light sample. Its MIS partner is the path's own next BSDF sample,
 * whose hit adds the emission it finds weighted by the power heuristic (li_path), so no
 * extra BSDF ray is traced here. Both pdfs include the light's selection pmf. */
static ts_rgb path_nee(const ts_scene *s, const ts_interaction *si, const ts_bsdf *bsdf, ts_vec2 u_select,
                       ts_vec2 u_light, ts_counters *c)
{
    float pmf;
    uint32_t li = ts_light_distribution_sample_at(&s->light_distribution, si->p, si->ns, u_select, &pmf);
    if (li == TS_NONE || !(pmf > 0)) return ts_rgb_gray(0);
    ts_light_sample ls = {0};
    if (!ts_light_sample_li(&s->lights[li], s->shapes, si, u_light, &ls) || !(ls.pdf > 0)) return ts_rgb_gray(0);
    /* BSDF-only sampling still light-samples delta lights, which no BSDF ray can hit. */
    if (!ls.is_delta && s->integrator.sampling == TS_SAMPLING_BSDF) return ts_rgb_gray(0);
    ts_rgb f = ts_rgb_scale(ts_bsdf_f(bsdf, si->wo, ls.wi), ts_vec3_absdot(ls.wi, si->ns));
    if (ts_rgb_is_black(f) || ts_rgb_is_black(ls.L)) return ts_rgb_gray(0);
    ts_ray shadow = ts_spawn_ray_to(si, s->shapes, ls.p_light, ls.p_light_error, ls.n_light);
    c->other_rays++;
    if (ts_accel_occluded(s->accel, &shadow)) return ts_rgb_gray(0);
    float light_pdf = ls.pdf * pmf;
    float w = 1;
    if (!ls.is_delta && s->integrator.sampling == TS_SAMPLING_MIS)
        w = power_heuristic(light_pdf, ts_bsdf_pdf(bsdf, si->wo, ls.wi));
    return ts_rgb_scale(ts_rgb_mul(f, ls.L), w / light_pdf);
}

/* Emission a path ray finds: at the camera and after specular bounces (and for BSDF-only
 * sampling) in full; after a non-specular bounce weighted against next-event estimation
 * at the vertex it left (prev, whose BSDF sampled the ray with pdf prev_pdf). */
static ts_rgb path_emission(const ts_scene *s, uint32_t fx, const ts_ray *ray, bool found, const ts_interaction *si,
                            bool full, const ts_interaction *prev, float prev_pdf)
{
    const ts_light_distribution *d = &s->light_distribution;
    ts_rgb L = ts_rgb_gray(0);
    if (found) {
        const ts_shape *sh = &s->shapes[si->shape];
        if (!(fx & TS_EFFECT_AREA_LIGHTS) || !sh->emissive) return L;
        uint32_t li = ts_area_light_index(sh, si->prim);
        const ts_light *l = &s->lights[li];
        L = ts_area_light_l(l, si, si->wo);
        if (full || ts_rgb_is_black(L)) return L;
        float light_pdf =
            ts_light_distribution_pmf_at(d, prev->p, prev->ns, li) * ts_light_pdf_li_hit(l, s->shapes, prev, si->p);
        return ts_rgb_scale(L, power_heuristic(prev_pdf, light_pdf));
    }
    if (!(fx & TS_EFFECT_ENVIRONMENT)) return L;
    for (uint32_t i = 0; i < s->n_infinite_lights; i++) {
        uint32_t li = s->infinite_lights[i];
        const ts_light *l = &s->lights[li];
        ts_rgb Le = ts_light_le(l, ray);
        if (!full && !ts_rgb_is_black(Le)) {
            float light_pdf =
                ts_light_distribution_pmf_at(d, prev->p, prev->ns, li) * ts_light_pdf_li(l, s->shapes, prev, ray->d);
            Le = ts_rgb_scale(Le, power_heuristic(prev_pdf, light_pdf));
        }
        L = ts_rgb_add(L, Le);
    }
    return L;
}

/* The path integrator: incremental path construction from the camera (pbrt's
 * PathIntegrator), next-event estimation with MIS at every vertex with a non-specular
 * lobe, the BSDF-sampled continuation ray doubling as MIS's BSDF sample (as pbrt-v4: two
 * rays a vertex, not pbrt-v3's three), Russian roulette after rr_depth on β·η-scale.
 * max_depth counts scattering events as pbrt: the emission found by the BSDF ray leaving
 * the last vertex is light after max_depth bounces and counts. */
static ts_rgb li_path(const ts_scene *s, uint32_t fx, ts_ray ray, const ts_ray_differential *rd,
                      ts_sample_stream *st, ts_counters *c)
{
    ts_rgb L = ts_rgb_gray(0), beta = ts_rgb_gray(1);
    bool specular_bounce = false;
    float eta_scale = 1;
    const int rr_depth = s->integrator.rr_depth;
    const ts_direct_sampling sampling = s->integrator.sampling;
    /* Depth cap where further bounces cannot carry light: nothing emits → nothing to see;
     * nothing scatters → only emission seen directly; no indirect → direct light only. */
    if (!(fx & TS_EFFECTS_LIGHTS)) return L;
    int max_depth = s->integrator.max_depth;
    if (!(fx & TS_EFFECTS_SCATTERING) && !(fx & TS_EFFECT_MEDIA)) max_depth = 0; /* rays pass shapes without a surface */
    else if (!(fx & TS_EFFECT_INDIRECT) && max_depth > 1) max_depth = 1;
    const bool emitters = (fx & (TS_EFFECT_AREA_LIGHTS | TS_EFFECT_ENVIRONMENT)) != 0;
    /* Under a film that clamps samples (max_sample_luminance) the image's expectation
     * depends on how each sample's value is distributed, not only on its mean: direct
     * light is then estimated as pbrt-v3's PathIntegrator does (UniformSampleOneLight: its
     * own BSDF ray towards the chosen light, all divided by the light's pmf; the
     * continuation's emission counts only at the camera and after specular bounces), so
     * the clamp cuts what pbrt-v3's cuts. Unclamped, both estimators have the same mean. */
    const bool v3_direct = s->max_sample_luminance < INFINITY;
    ts_interaction prev = {0};
    float prev_pdf = 0;
    uint32_t crossings = 0;
    bool crossed = false; /* the ray left its vertex through a shape without a surface */
    for (int bounces = 0;; bounces++) {
        /* Emission found by this ray counts at the camera, after a specular bounce, and
         * (MIS-weighted, or in full for BSDF-only sampling) unless light sampling alone
         * is asked for. A ray whose hit can add nothing — the last one, when nothing
         * emits or its emission does not count — is not traced; it draws no sample
         * dimensions, so nothing else changes. Past a shape without a surface only the
         * first two count: pbrt-v3's light sample is blocked by it (Unoccluded) and so is
         * its BSDF sample (Intersect finds the shape, not the light), so light behind a
         * medium boundary reaches a diffuse or glossy vertex through neither strategy. */
        bool counts = emitters && (bounces == 0 || specular_bounce ||
                                   (!v3_direct && sampling != TS_SAMPLING_LIGHT && !crossed));
        if ((bounces > 0 && bounces >= max_depth && !counts) || stopped(c)) break;
        ts_interaction si;
        bool found = ts_accel_intersect(s->accel, &ray, &si);
        if (bounces > 0) c->other_rays++;
        if (counts) {
            bool full = bounces == 0 || specular_bounce || sampling == TS_SAMPLING_BSDF;
            L = ts_rgb_add(L, ts_rgb_mul(beta, path_emission(s, fx, &ray, found, &si, full, &prev, prev_pdf)));
        }
        if (!found || bounces >= max_depth) break;
        if ((fx & TS_EFFECT_MEDIA) && no_surface(s, &si)) { /* pbrt-v3: on through it, no bounce */
            if (++crossings > TS_VOLPATH_MAX_CROSSINGS) {
                c->walks_truncated++;
                break;
            }
            ray = ts_spawn_ray(&si, s->shapes, ray.d);
            crossed = bounces > 0;
            bounces--;
            continue;
        }
        crossed = false;
        ts_bsdf bsdf;
        /* The camera ray's differentials only, as pbrt-v3's PathIntegrator (differential.h). */
        material_bsdf(s, &si, bounces == 0 ? rd : NULL, &bsdf);
        uint32_t flags = ts_bsdf_flags(&bsdf);
        if ((flags & ~TS_BXDF_SPECULAR & (TS_BXDF_DIFFUSE | TS_BXDF_GLOSSY)) && v3_direct) {
            L = ts_rgb_add(L, ts_rgb_mul(beta, sample_one_light(s, fx, &si, &bsdf, st, c)));
        } else if (flags & ~TS_BXDF_SPECULAR & (TS_BXDF_DIFFUSE | TS_BXDF_GLOSSY)) {
            ts_vec2 u_select = ts_sample_2d(st); /* x: the alias bin, y: its coin */
            ts_vec2 u_light = ts_sample_2d(st);
            L = ts_rgb_add(L, ts_rgb_mul(beta, path_nee(s, &si, &bsdf, u_select, u_light, c)));
        } else {
            st->dim += 2; /* keep later dimensions where they would be */
        }
        float u_lobe = lobe_u(fx, st);
        ts_vec2 u = ts_sample_2d(st);
        /* Roulette's value is computed only where roulette can happen. */
        float u_rr = 0;
        if (bounces > rr_depth) u_rr = ts_sample_1d(st);
        else st->dim++;
        ts_bsdf_sample bs;
        if (!ts_bsdf_sample_f(&bsdf, si.wo, u_lobe, u, &bs) || !(bs.pdf > 0) || ts_rgb_is_black(bs.f)) break;
        beta = ts_rgb_mul(beta, ts_rgb_scale(bs.f, ts_vec3_absdot(bs.wi, si.ns) / bs.pdf));
        specular_bounce = (bs.flags & TS_BXDF_SPECULAR) != 0;
        /* bs.eta is η(wi side)/η(wo side): entering glass it is 1.5 and the BTDF scaled
         * radiance by 1/1.5², which this undoes for roulette (pbrt's etaScale). */
        if ((fx & TS_EFFECT_SPECULAR_TRANSMISSION) && specular_bounce && (bs.flags & TS_BXDF_TRANSMISSION))
            eta_scale *= bs.eta * bs.eta;
        if (emitters) {
            prev = si;
            prev_pdf = bs.pdf;
        }
        ray = ts_spawn_ray(&si, s->shapes, bs.wi);
        if (!ts_russian_roulette(&beta, eta_scale, bounces, rr_depth, u_rr) || !ts_rgb_is_finite(beta)) break;
    }
    return L;
}

/* ---------------------------------------------------------------- direct */

/* pbrt-v3's DirectLightingIntegrator: emission at the hit, direct light from all lights
 * or one, and specular reflection/transmission followed up to max_depth. */
static ts_rgb li_direct(const ts_scene *s, uint32_t fx, ts_ray ray, const ts_ray_differential *rd,
                        ts_sample_stream *st, ts_counters *c, int depth)
{
    ts_interaction si;
    if (!(fx & TS_EFFECTS_LIGHTS) || stopped(c)) return ts_rgb_gray(0); /* nothing emits: nothing to see */
    if (depth > 0) c->other_rays++;
    bool found = ts_accel_intersect(s->accel, &ray, &si);
    /* pbrt-v3: a shape without a surface is passed through (media are not simulated here). */
    for (uint32_t k = 0; found && (fx & TS_EFFECT_MEDIA) && no_surface(s, &si); k++) {
        if (k >= TS_VOLPATH_MAX_CROSSINGS) {
            c->walks_truncated++;
            return ts_rgb_gray(0);
        }
        ray = ts_spawn_ray(&si, s->shapes, ray.d);
        found = ts_accel_intersect(s->accel, &ray, &si);
        c->other_rays++;
    }
    if (!found) return (fx & TS_EFFECT_ENVIRONMENT) ? escaped(s, &ray) : ts_rgb_gray(0);
    ts_rgb L = (fx & TS_EFFECT_AREA_LIGHTS) ? emitted(s, &si, si.wo) : ts_rgb_gray(0);
    if (!(fx & TS_EFFECTS_SCATTERING)) return L;
    ts_bsdf bsdf;
    /* With differentials, the footprint is needed for the specular rules too. */
    ts_texture_context tc;
    const bool diff = rd && rd->has;
    if (diff) {
        const ts_material *m = &s->materials[s->shapes[si.shape].material];
        ts_ray_differential_context(&si, rd, &tc);
        ts_material_bump(m, &si, &tc);
        ts_material_bsdf(m, &si, &tc, &bsdf);
    } else {
        material_bsdf(s, &si, NULL, &bsdf);
    }
    uint32_t flags = ts_bsdf_flags(&bsdf);
    if (s->n_lights > 0 && (flags & (TS_BXDF_DIFFUSE | TS_BXDF_GLOSSY))) {
        if (s->integrator.strategy == TS_LIGHTS_ALL) L = ts_rgb_add(L, sample_all_lights(s, fx, &si, &bsdf, st, c));
        else L = ts_rgb_add(L, sample_one_light(s, fx, &si, &bsdf, st, c));
    }
    if ((fx & TS_EFFECT_INDIRECT) && depth + 1 < s->integrator.max_depth && (flags & TS_BXDF_SPECULAR)) {
        float u_lobe = lobe_u(fx, st);
        ts_vec2 u = ts_sample_2d(st);
        ts_bsdf_sample bs;
        if (ts_bsdf_sample_f(&bsdf, si.wo, u_lobe, u, &bs) && (bs.flags & TS_BXDF_SPECULAR) && bs.pdf > 0 &&
            !ts_rgb_is_black(bs.f)) {
            float cos = ts_vec3_absdot(bs.wi, si.ns);
            ts_ray_differential next = {.has = false};
            if (diff && (bs.flags & TS_BXDF_REFLECTION)) ts_ray_differential_reflect(rd, &si, &tc, bs.wi, &next);
            else if (diff) ts_ray_differential_transmit(rd, &si, &tc, bs.wi, bsdf.eta, &next);
            ts_rgb Li = li_direct(s, fx, ts_spawn_ray(&si, s->shapes, bs.wi), diff ? &next : NULL, st, c, depth + 1);
            L = ts_rgb_add(L, ts_rgb_scale(ts_rgb_mul(bs.f, Li), cos / bs.pdf));
        }
    }
    return L;
}

/* ---------------------------------------------------------------- dispatch */

double ts_integrator_rays_per_sample(const ts_scene *s, ts_integrator_type type, uint32_t fx)
{
    switch (type) {
    case TS_INTEGRATOR_AO: return 2;
    case TS_INTEGRATOR_NORMALS: return 1;
    case TS_INTEGRATOR_VOLPATH: return ts_volpath_rays_per_sample(s, fx);
    case TS_INTEGRATOR_PATH: {
        /* The depth caps of li_path. */
        double depth = s->integrator.max_depth;
        if (!(fx & TS_EFFECTS_LIGHTS)) depth = 0;
        else if (!(fx & TS_EFFECTS_SCATTERING) && !(fx & TS_EFFECT_MEDIA)) depth = 0;
        else if (!(fx & TS_EFFECT_INDIRECT) && depth > 1) depth = 1;
        return 1 + 2 * depth;
    }
    case TS_INTEGRATOR_DIRECT: {
        double vertices = (fx & TS_EFFECT_INDIRECT) && s->integrator.max_depth > 1 ? s->integrator.max_depth : 1;
        double nee = 2.0;
        if (s->integrator.strategy == TS_LIGHTS_ALL) {
            nee = 0;
            for (uint32_t li = 0; li < s->n_lights; li++) nee += 2.0 * (double)light_samples(s, li);
        }
        return vertices * (1 + nee);
    }
    }
    return 1;
}

ts_rgb ts_integrator_li(const ts_scene *s, ts_integrator_type type, uint32_t fx, const ts_ray *ray,
                        const ts_ray_differential *rd, ts_sample_stream *st, ts_counters *c)
{
    c->camera_rays++;
    switch (type) {
    case TS_INTEGRATOR_AO: return li_ao(s, fx, ray, st, c);
    case TS_INTEGRATOR_NORMALS: return li_normals(s, fx, ray, c);
    case TS_INTEGRATOR_PATH: return li_path(s, fx, *ray, rd, st, c);
    case TS_INTEGRATOR_DIRECT: return li_direct(s, fx, *ray, rd, st, c, 0);
    case TS_INTEGRATOR_VOLPATH: return ts_volpath_li(s, fx, *ray, rd, st, c);
    }
    return ts_rgb_gray(0);
}

bool ts_integrator_media_warning(const ts_scene *s, char *buf, size_t n)
{
    if (!(s->effects & TS_EFFECT_MEDIA) || s->integrator.type == TS_INTEGRATOR_VOLPATH) return false;
    const char *name = ts_integrator_name(s->integrator.type);
    switch (s->integrator.type) {
    case TS_INTEGRATOR_AO:
        snprintf(buf, n,
                 "integrator.type: \"%s\" does not simulate the scene's participating media, as pbrt-v3's ambient "
                 "occlusion does not: camera rays pass through the shapes without a surface, occlusion rays are "
                 "blocked by them; use volpath",
                 name);
        break;
    case TS_INTEGRATOR_NORMALS:
        snprintf(buf, n,
                 "integrator.type: \"%s\" shows the first surface a camera ray meets, through the shapes without a "
                 "surface that bound the scene's media",
                 name);
        break;
    default:
        snprintf(buf, n,
                 "integrator.type: \"%s\" does not simulate the scene's participating media, as pbrt-v3's does not: "
                 "rays pass through the shapes that bound them, shadow rays are blocked by them, and light behind "
                 "such a shape reaches a surface only after a specular bounce; use volpath",
                 name);
        break;
    }
    return true;
}
