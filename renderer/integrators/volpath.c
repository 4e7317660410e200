/* volpath.c — pbrt-v3's volumetric path tracer; see volpath.h. */
#include "integrators/volpath.h"

#include <math.h>

#include "integrators/effects.h"
#include "lights/light.h"
#include "materials/bsdf.h"
#include "materials/material.h"
#include "media/medium.h"
#include "sampling/sampling.h"

typedef struct vp {
    const ts_scene *s;
    uint32_t fx;
    ts_counters *c;
    ts_medium_walk walk;
} vp;

/* A scattering vertex: a surface hit with its BSDF, or a point in a medium (shape TS_NONE,
 * no normal) with the medium's phase function. wo is unit, back along the arriving ray. */
typedef struct vertex {
    ts_interaction it;
    const ts_bsdf *bsdf; /* NULL: a medium vertex */
    float g;
    uint32_t medium; /* a medium vertex's medium; a surface vertex's arriving ray's */
} vertex;

static bool stopped(const ts_counters *c) { return c->stop && atomic_load_explicit(c->stop, memory_order_relaxed); }

static bool is_delta_light(const ts_light *l)
{
    return l->type == TS_LIGHT_POINT || l->type == TS_LIGHT_SPOT || l->type == TS_LIGHT_DISTANT;
}

static bool has_surface(const ts_scene *s, const ts_interaction *si) { return s->shapes[si->shape].material != TS_NONE; }

/* The medium of a ray leaving hit si along w: the side's of a transition, else the
 * medium the ray was in (pbrt-v3's GetMedium with a primitive's MediumInterface). */
static uint32_t medium_towards(const ts_scene *s, const ts_interaction *si, ts_vec3 w, uint32_t current)
{
    const ts_shape *sh = &s->shapes[si->shape];
    if (!sh->medium_transition) return current;
    return ts_vec3_dot(w, si->n) > 0 ? sh->medium_outside : sh->medium_inside;
}

/* pbrt-v3's Scene::IntersectTr (to_point false) and VisibilityTester::Tr (to_point: the
 * ray ends at o + d, a shadow ray): from ray in `medium` through shapes without a surface,
 * *tr multiplied by each medium segment's transmittance, to the first surface (true,
 * *hit) or the ray's end (false). A black *tr ends the trace early (false). */
static bool trace_tr(vp *v, ts_ray ray, uint32_t medium, bool to_point, ts_interaction *hit, ts_rgb *tr)
{
    const ts_scene *s = v->s;
    const ts_vec3 target = ts_vec3_add(ray.o, ray.d), zero = {0, 0, 0};
    for (uint32_t k = 0;; k++) {
        /* A shadow ray sees cut-outs as ts_accel_occluded does (alpha and shadow_alpha). */
        bool found = to_point ? ts_accel_intersect_shadow(s->accel, &ray, hit) : ts_accel_intersect(s->accel, &ray, hit);
        v->c->other_rays++;
        if (medium != TS_NONE) {
            *tr = ts_rgb_mul(*tr, ts_medium_tr(&s->media[medium], &ray, found ? hit->t : ray.tmax, &v->walk));
            if (ts_rgb_is_black(*tr)) return false;
        }
        if (!found) return false;
        if (has_surface(s, hit)) return true;
        if (k >= TS_VOLPATH_MAX_CROSSINGS || stopped(v->c)) {
            v->c->walks_truncated++;
            *tr = ts_rgb_gray(0);
            return false;
        }
        medium = medium_towards(s, hit, ray.d, medium);
        ray = to_point ? ts_spawn_ray_to(hit, s->shapes, target, zero, zero) : ts_spawn_ray(hit, s->shapes, ray.d);
    }
}

/* The scattering function at x towards wi (the BSDF times |cos|, or the phase function)
 * and the density with which x samples wi. */
static ts_rgb scatter_f(const vertex *x, ts_vec3 wi, float *pdf)
{
    if (!x->bsdf) {
        float p = ts_hg_phase(-ts_vec3_dot(x->it.wo, wi), x->g);
        *pdf = p;
        return ts_rgb_gray(p);
    }
    *pdf = ts_bsdf_pdf(x->bsdf, x->it.wo, wi);
    return ts_rgb_scale(ts_bsdf_f(x->bsdf, x->it.wo, wi), ts_vec3_absdot(wi, x->it.ns));
}

/* Transmittance of the light sample's shadow ray from x (0: blocked by a surface). */
static ts_rgb shadow_tr(vp *v, const vertex *x, const ts_light_sample *ls)
{
    const ts_scene *s = v->s;
    ts_ray r = ts_spawn_ray_to(&x->it, x->bsdf ? s->shapes : NULL, ls->p_light, ls->p_light_error, ls->n_light);
    if (!(v->fx & TS_EFFECT_MEDIA)) {
        v->c->other_rays++;
        return ts_rgb_gray(ts_accel_occluded(s->accel, &r) ? 0 : 1);
    }
    uint32_t m = x->bsdf ? medium_towards(s, &x->it, r.d, x->medium) : x->medium;
    ts_interaction hit;
    ts_rgb tr = ts_rgb_gray(1);
    if (trace_tr(v, r, m, true, &hit, &tr)) return ts_rgb_gray(0);
    return tr;
}

/* pbrt-v3's EstimateDirect with media: light li sampled with u_light, x's BSDF (lobe
 * u_lobe) or phase function sampled with u_scatter, combined by the power heuristic;
 * delta lights by light sampling only; a specular BSDF pick adds nothing. */
static ts_rgb estimate_direct(vp *v, const vertex *x, uint32_t li, ts_vec2 u_light, float u_lobe, ts_vec2 u_scatter)
{
    const ts_scene *s = v->s;
    const ts_light *light = &s->lights[li];
    ts_rgb Ld = ts_rgb_gray(0);
    ts_light_sample ls;
    if (ts_light_sample_li(light, s->shapes, &x->it, u_light, &ls) && ls.pdf > 0) {
        float spdf;
        ts_rgb f = scatter_f(x, ls.wi, &spdf);
        if (!ts_rgb_is_black(f)) {
            ts_rgb Li = ts_rgb_mul(ls.L, shadow_tr(v, x, &ls));
            if (!ts_rgb_is_black(Li)) {
                float w = ls.is_delta ? 1 : ts_power_heuristic(1, ls.pdf, 1, spdf);
                Ld = ts_rgb_scale(ts_rgb_mul(f, Li), w / ls.pdf);
            }
        }
    }
    if (is_delta_light(light)) return Ld;
    ts_vec3 wi;
    ts_rgb f;
    float spdf;
    if (!x->bsdf) {
        wi = ts_hg_sample(ts_vec3_neg(x->it.wo), x->g, u_scatter, &spdf);
        f = ts_rgb_gray(spdf);
    } else {
        ts_bsdf_sample bs;
        if (!ts_bsdf_sample_f(x->bsdf, x->it.wo, u_lobe, u_scatter, &bs) || (bs.flags & TS_BXDF_SPECULAR)) return Ld;
        wi = bs.wi;
        spdf = bs.pdf;
        f = ts_rgb_scale(bs.f, ts_vec3_absdot(bs.wi, x->it.ns));
    }
    if (ts_rgb_is_black(f) || !(spdf > 0)) return Ld;
    ts_ray r = x->bsdf ? ts_spawn_ray(&x->it, s->shapes, wi) : ts_ray_make(x->it.p, wi, INFINITY);
    r.time = x->it.time;
    ts_interaction hit;
    ts_rgb tr = ts_rgb_gray(1);
    bool found;
    if (v->fx & TS_EFFECT_MEDIA) {
        uint32_t m = x->bsdf ? medium_towards(s, &x->it, wi, x->medium) : x->medium;
        found = trace_tr(v, r, m, false, &hit, &tr);
        if (ts_rgb_is_black(tr)) return Ld;
    } else {
        found = ts_accel_intersect(s->accel, &r, &hit);
        v->c->other_rays++;
    }
    ts_rgb Li = ts_rgb_gray(0);
    float light_pdf = 0;
    if (found) {
        const ts_shape *sh = &s->shapes[hit.shape];
        if (light->type == TS_LIGHT_AREA && sh->emissive && ts_area_light_index(sh, hit.prim) == li) {
            light_pdf = ts_light_pdf_li_hit(light, s->shapes, &x->it, hit.p);
            Li = ts_area_light_l(light, &hit, ts_vec3_neg(wi));
        }
    } else if (light->type == TS_LIGHT_INFINITE) {
        Li = ts_light_le_pdf(light, wi, &light_pdf);
    }
    if (ts_rgb_is_black(Li) || !(light_pdf > 0)) return Ld;
    float w = ts_power_heuristic(1, spdf, 1, light_pdf);
    return ts_rgb_add(Ld, ts_rgb_scale(ts_rgb_mul(ts_rgb_mul(f, Li), tr), w / spdf));
}

/* pbrt-v3's UniformSampleOneLight at x: one light from the distribution at x's point. */
static ts_rgb sample_one_light(vp *v, const vertex *x, ts_vec2 u_select, ts_vec2 u_light, float u_lobe,
                               ts_vec2 u_scatter)
{
    float pmf;
    uint32_t li = ts_light_distribution_sample_at(&v->s->light_distribution, x->it.p, x->it.ns, u_select, &pmf);
    if (li == TS_NONE || !(pmf > 0)) return ts_rgb_gray(0);
    return ts_rgb_scale(estimate_direct(v, x, li, u_light, u_lobe, u_scatter), 1 / pmf);
}

/* A textured material's BSDF with the ray's footprint (rd NULL: none). */
static void surface_bsdf(const ts_scene *s, ts_interaction *si, const ts_ray_differential *rd, ts_bsdf *bsdf)
{
    const ts_material *m = &s->materials[s->shapes[si->shape].material];
    if (!m->textured) {
        ts_material_bsdf(m, si, NULL, bsdf);
        return;
    }
    ts_texture_context tc;
    ts_ray_differential_context(si, rd, &tc);
    ts_material_bump(m, si, &tc);
    ts_material_bsdf(m, si, &tc, bsdf);
}

/* Radiance of the camera ray's first hit or of the infinite lights it escapes to. */
static ts_rgb emission(const ts_scene *s, uint32_t fx, bool found, const ts_interaction *si, const ts_ray *ray)
{
    ts_rgb L = ts_rgb_gray(0);
    if (found) {
        const ts_shape *sh = &s->shapes[si->shape];
        if ((fx & TS_EFFECT_AREA_LIGHTS) && sh->emissive)
            L = ts_area_light_l(&s->lights[ts_area_light_index(sh, si->prim)], si, si->wo);
        return L;
    }
    if (fx & TS_EFFECT_ENVIRONMENT)
        for (uint32_t i = 0; i < s->n_infinite_lights; i++)
            L = ts_rgb_add(L, ts_light_le(&s->lights[s->infinite_lights[i]], ray));
    return L;
}

ts_rgb ts_volpath_li(const ts_scene *s, uint32_t fx, ts_ray ray, const ts_ray_differential *rd,
                     ts_sample_stream *st, ts_counters *c)
{
    ts_rgb L = ts_rgb_gray(0), beta = ts_rgb_gray(1);
    if (!(fx & TS_EFFECTS_LIGHTS)) return L;
    vp v = {s, fx, c, {{0, 0}, 0, 0, NULL}};
    const bool media = (fx & TS_EFFECT_MEDIA) != 0;
    if (media) ts_medium_walk_init(&v.walk, st->seed, st->px, st->py, st->index, c->stop);
    uint32_t medium = media ? s->camera_medium : TS_NONE;
    const int rr_depth = s->integrator.rr_depth;
    int max_depth = s->integrator.max_depth;
    if (!(fx & TS_EFFECT_INDIRECT) && max_depth > 1) max_depth = 1; /* job.effects.indirect off */
    bool specular = false, crossed = false;
    float eta_scale = 1;
    uint32_t crossings = 0;
    for (int bounces = 0;; bounces++) {
        if (stopped(c)) break;
        ts_interaction si;
        bool found = ts_accel_intersect(s->accel, &ray, &si);
        if (bounces > 0 || crossings > 0) c->other_rays++;
        /* The vertex's medium sample value; a segment after a crossing draws its own. */
        ts_vec2 u_medium;
        if (!crossed) u_medium = ts_sample_2d(st);
        else u_medium = (ts_vec2){ts_pcg32_float(&v.walk.rng), ts_pcg32_float(&v.walk.rng)};
        crossed = false;
        bool scattered = false;
        float t_medium = 0;
        if (medium != TS_NONE) {
            beta = ts_rgb_mul(beta, ts_medium_sample(&s->media[medium], &ray, found ? si.t : ray.tmax, u_medium,
                                                     &v.walk, &scattered, &t_medium));
            if (ts_rgb_is_black(beta)) break;
        }
        vertex x;
        if (scattered) {
            if (bounces >= max_depth) break;
            x = (vertex){.bsdf = NULL, .g = s->media[medium].g, .medium = medium};
            x.it.p = ts_ray_at(&ray, t_medium);
            x.it.wo = ts_vec3_neg(ts_vec3_normalize(ray.d));
            x.it.shape = x.it.prim = TS_NONE;
            x.it.time = ray.time;
        } else {
            if (bounces == 0 || specular) L = ts_rgb_add(L, ts_rgb_mul(beta, emission(s, fx, found, &si, &ray)));
            if (!found || bounces >= max_depth) break;
            if (!has_surface(s, &si)) { /* only bounds a medium: go on through it, no event */
                if (++crossings > TS_VOLPATH_MAX_CROSSINGS) {
                    c->walks_truncated++;
                    break;
                }
                medium = medium_towards(s, &si, ray.d, medium);
                ray = ts_spawn_ray(&si, s->shapes, ray.d);
                crossed = true;
                bounces--;
                continue;
            }
            x = (vertex){.it = si, .medium = medium};
        }
        ts_vec2 u_select = ts_sample_2d(st), u_light = ts_sample_2d(st), u_lobes = ts_sample_2d(st);
        ts_vec2 u_direct = ts_sample_2d(st), u_cont = ts_sample_2d(st);
        float u_rr = ts_sample_1d(st);
        if (scattered) {
            L = ts_rgb_add(L, ts_rgb_mul(beta, sample_one_light(&v, &x, u_select, u_light, 0, u_direct)));
            float p;
            ts_vec3 wi = ts_hg_sample(ts_vec3_neg(x.it.wo), x.g, u_cont, &p);
            ray = ts_ray_make(x.it.p, wi, INFINITY); /* β·p/p: unchanged */
            ray.time = x.it.time;
            specular = false;
        } else {
            ts_bsdf bsdf;
            /* The camera ray's differentials only, as pbrt-v3. */
            surface_bsdf(s, &x.it, bounces == 0 && crossings == 0 ? rd : NULL, &bsdf);
            x.bsdf = &bsdf;
            if (ts_bsdf_flags(&bsdf) & (TS_BXDF_DIFFUSE | TS_BXDF_GLOSSY))
                L = ts_rgb_add(L, ts_rgb_mul(beta, sample_one_light(&v, &x, u_select, u_light, u_lobes.x, u_direct)));
            ts_bsdf_sample bs;
            if (!ts_bsdf_sample_f(&bsdf, x.it.wo, u_lobes.y, u_cont, &bs) || !(bs.pdf > 0) || ts_rgb_is_black(bs.f))
                break;
            beta = ts_rgb_mul(beta, ts_rgb_scale(bs.f, ts_vec3_absdot(bs.wi, x.it.ns) / bs.pdf));
            specular = (bs.flags & TS_BXDF_SPECULAR) != 0;
            if (specular && (bs.flags & TS_BXDF_TRANSMISSION)) eta_scale *= bs.eta * bs.eta;
            if (media) medium = medium_towards(s, &x.it, bs.wi, medium);
            ray = ts_spawn_ray(&x.it, s->shapes, bs.wi);
        }
        if (!ts_russian_roulette(&beta, eta_scale, bounces, rr_depth, u_rr) || !ts_rgb_is_finite(beta)) break;
    }
    c->medium_steps += v.walk.steps;
    c->walks_truncated += v.walk.truncated;
    return L;
}

double ts_volpath_rays_per_sample(const ts_scene *s, uint32_t fx)
{
    if (!(fx & TS_EFFECTS_LIGHTS)) return 1;
    double depth = s->integrator.max_depth;
    if (!(fx & TS_EFFECT_INDIRECT) && depth > 1) depth = 1;
    return 1 + 3.0 * depth;
}
