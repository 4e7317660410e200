/* light.c — lights, their sampling and the light-selection distributions (see light.h).
 *
 * Infinite lights with a transform: a light-space direction w maps to the world direction
 * A w / |A w| (A the linear part of to_world). For a rotation this is the identity on
 * densities; for any other linear map the solid-angle Jacobian |det A| / |A w|³ is applied,
 * so Sample_Li and Pdf_Li stay consistent whatever transform the scene gives. */
#include "lights/light.h"

#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "lights/envmap.h"
#include "sampling/sampling.h"

static bool rgb_valid(ts_rgb c) { return ts_rgb_is_finite(c) && c.r >= 0 && c.g >= 0 && c.b >= 0; }

static double linear_det(const ts_xform *t)
{
    const double(*m)[4] = t->m.m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

ts_status ts_lights_prepare(ts_light *lights, uint32_t n, const ts_shape *shapes, ts_bounds3 scene_bounds,
                            ts_error *err)
{
    ts_vec3 center = {0, 0, 0};
    float radius = 1;
    if (!ts_bounds3_is_empty(scene_bounds) && ts_vec3_is_finite(scene_bounds.lo) && ts_vec3_is_finite(scene_bounds.hi)) {
        center = ts_vec3_scale(ts_vec3_add(scene_bounds.lo, scene_bounds.hi), 0.5f);
        float r = ts_vec3_distance(center, scene_bounds.hi);
        if (r > 0 && isfinite(r)) radius = r;
    }
    for (uint32_t i = 0; i < n; i++) {
        ts_light *l = &lights[i];
        if (!rgb_valid(l->color))
            return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: color (%g, %g, %g) must be finite and ≥ 0", i,
                                l->color.r, l->color.g, l->color.b);
        switch (l->type) {
        case TS_LIGHT_POINT:
            if (!ts_vec3_is_finite(l->position))
                return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: position is not finite", i);
            break;
        case TS_LIGHT_SPOT:
            if (!ts_vec3_is_finite(l->position))
                return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: position is not finite", i);
            __attribute__((fallthrough)); /* spots have a direction too */
        case TS_LIGHT_DISTANT: {
            float len = ts_vec3_length(l->direction);
            if (!(len > 0) || !isfinite(len))
                return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: direction must be a non-zero vector", i);
            l->direction = ts_vec3_scale(l->direction, 1 / len);
            if (l->type == TS_LIGHT_SPOT &&
                !(l->cos_total >= -1 && l->cos_total <= l->cos_falloff_start && l->cos_falloff_start <= 1))
                return ts_error_set(err, TS_ERR_INVALID,
                                    "lights[%u]: spot cosines must satisfy -1 ≤ cos_total (%g) ≤ cos_falloff_start (%g) ≤ 1",
                                    i, l->cos_total, l->cos_falloff_start);
            break;
        }
        case TS_LIGHT_AREA: {
            if (!shapes) return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: area light without shapes", i);
            ts_status st = l->rect ? ts_shape_sample_info_init_rect(&shapes[l->shape], l->prim, l->prim_b,
                                                                     l->triangle_sampling, &l->geom, err)
                                   : ts_shape_sample_info_init(&shapes[l->shape], l->prim, l->triangle_sampling,
                                                               &l->geom, err);
            if (st) {
                ts_error_prefix(err, "lights[%u] (shape %u)", i, l->shape);
                return st;
            }
            break;
        }
        case TS_LIGHT_INFINITE:
            if (!(fabs(linear_det(&l->to_world)) > 0))
                return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: transform is singular", i);
            break;
        default: return ts_error_set(err, TS_ERR_INVALID, "lights[%u]: unknown type %d", i, (int)l->type);
        }
        l->scene_center = center;
        l->scene_radius = radius;
    }
    return TS_OK;
}

/* pbrt-v3's smooth spot falloff: 1 inside the inner cone, 0 outside the outer, quartic
 * in cosθ between. */
static float spot_falloff(const ts_light *l, float cos_theta)
{
    if (cos_theta < l->cos_total) return 0;
    if (cos_theta >= l->cos_falloff_start) return 1;
    float delta = (cos_theta - l->cos_total) / (l->cos_falloff_start - l->cos_total);
    return (delta * delta) * (delta * delta);
}

/* A point standing in for "at infinity" along wi from p: outside the scene's sphere. */
static ts_vec3 far_point(const ts_light *l, ts_vec3 p, ts_vec3 wi)
{
    float dist = 2 * l->scene_radius + ts_vec3_distance(p, l->scene_center);
    return ts_vec3_add(p, ts_vec3_scale(wi, dist));
}

/* Map-space direction of a world direction, and the solid-angle density factor
 * dω_map/dω_world = |A w_map|³ / |det A| (1 for rotations). */
static ts_vec3 world_to_map(const ts_light *l, ts_vec3 w_world, double *jac)
{
    ts_dvec3 wm = ts_xform_vector_inv(&l->to_world, ts_dvec3_normalize(ts_dvec3_from(w_world)));
    double len = ts_dvec3_length(wm);
    if (jac) *jac = 1 / (len * len * len * fabs(linear_det(&l->to_world)));
    return ts_dvec3_to_vec3(ts_dvec3_scale(wm, 1 / len));
}

ts_rgb ts_area_light_l(const ts_light *l, const ts_interaction *si, ts_vec3 w)
{
    if (l->type != TS_LIGHT_AREA) return ts_rgb_gray(0);
    return l->two_sided || ts_vec3_dot(si->n, w) > 0 ? l->color : ts_rgb_gray(0);
}

bool ts_light_sample_li(const ts_light *l, const ts_shape *shapes, const ts_interaction *ref, ts_vec2 u,
                        ts_light_sample *out)
{
    memset(out, 0, sizeof *out);
    switch (l->type) {
    case TS_LIGHT_POINT:
    case TS_LIGHT_SPOT: {
        ts_vec3 d = ts_vec3_sub(l->position, ref->p);
        float d2 = ts_vec3_length_sq(d);
        if (!(d2 > 0)) return false;
        out->wi = ts_vec3_scale(d, 1 / sqrtf(d2));
        float scale = 1 / d2;
        if (l->type == TS_LIGHT_SPOT) scale *= spot_falloff(l, -ts_vec3_dot(out->wi, l->direction));
        out->L = ts_rgb_scale(l->color, scale);
        out->pdf = 1;
        out->p_light = l->position;
        out->is_delta = true;
        break;
    }
    case TS_LIGHT_DISTANT:
        out->wi = ts_vec3_neg(l->direction);
        out->L = l->color;
        out->pdf = 1;
        out->p_light = far_point(l, ref->p, out->wi);
        out->is_delta = true;
        out->is_infinite = true;
        break;
    case TS_LIGHT_AREA: {
        ts_shape_point pt;
        if (!ts_shape_sample_solid_angle(&shapes[l->shape], l->prim, &l->geom, ref, u, &pt)) return false;
        ts_vec3 d = ts_vec3_sub(pt.p, ref->p);
        float len = ts_vec3_length(d);
        if (!(len > 0)) return false;
        out->wi = ts_vec3_scale(d, 1 / len);
        if (l->two_sided || ts_vec3_dot(pt.n, out->wi) < 0) out->L = l->color;
        out->pdf = pt.pdf;
        out->p_light = pt.p;
        out->p_light_error = pt.p_error;
        out->n_light = pt.n;
        break;
    }
    case TS_LIGHT_INFINITE: {
        if (l->map) {
            ts_vec3 wm;
            float pdf_map;
            ts_rgb L_map;
            if (!ts_envmap_sample_li(l->map, u, &wm, &pdf_map, &L_map)) return false;
            ts_dvec3 ww = ts_xform_vector(&l->to_world, ts_dvec3_from(wm));
            double len = ts_dvec3_length(ww);
            double pdf = pdf_map * len * len * len / fabs(linear_det(&l->to_world));
            if (!(pdf > 0) || !(pdf < FLT_MAX)) return false;
            out->wi = ts_dvec3_to_vec3(ts_dvec3_scale(ww, 1 / len));
            out->pdf = (float)pdf;
            out->L = ts_rgb_mul(l->color, L_map);
        } else {
            out->wi = ts_sample_uniform_sphere(u);
            out->pdf = ts_uniform_sphere_pdf();
            out->L = l->color;
        }
        out->p_light = far_point(l, ref->p, out->wi);
        out->is_infinite = true;
        break;
    }
    }
    if (ts_rgb_is_black(out->L) || !(out->pdf > 0) || !ts_rgb_is_finite(out->L) || !ts_vec3_is_finite(out->wi) ||
        !ts_vec3_is_finite(out->p_light)) {
        memset(out, 0, sizeof *out);
        return false;
    }
    return true;
}

float ts_light_pdf_li(const ts_light *l, const ts_shape *shapes, const ts_interaction *ref, ts_vec3 wi)
{
    switch (l->type) {
    case TS_LIGHT_AREA: return ts_shape_pdf_solid_angle(&shapes[l->shape], l->prim, &l->geom, ref, wi);
    case TS_LIGHT_INFINITE: {
        if (!l->map) return ts_uniform_sphere_pdf();
        double jac;
        ts_vec3 wm = world_to_map(l, wi, &jac);
        double pdf = ts_envmap_pdf(l->map, wm) * jac;
        return pdf < FLT_MAX ? (float)pdf : 0.0f;
    }
    default: return 0;
    }
}

float ts_light_pdf_li_hit(const ts_light *l, const ts_shape *shapes, const ts_interaction *ref, ts_vec3 p_hit)
{
    if (l->type != TS_LIGHT_AREA) return 0;
    return ts_shape_pdf_solid_angle_at(&shapes[l->shape], l->prim, &l->geom, ref, p_hit);
}

ts_rgb ts_light_le(const ts_light *l, const ts_ray *ray)
{
    if (l->type != TS_LIGHT_INFINITE) return ts_rgb_gray(0);
    if (!l->map) return l->color;
    return ts_rgb_mul(l->color, ts_envmap_lookup(l->map, world_to_map(l, ray->d, NULL)));
}

void ts_light_query_begin(const ts_light *l, ts_vec3 wi, ts_light_query *q)
{
    q->wi = wi;
    q->jac = 0;
    if (l->type == TS_LIGHT_INFINITE && l->map) ts_envmap_query_begin(l->map, world_to_map(l, wi, &q->jac), &q->map);
}

ts_rgb ts_light_query_le_pdf(const ts_light *l, const ts_light_query *q, float *pdf)
{
    *pdf = 0;
    if (l->type != TS_LIGHT_INFINITE) return ts_rgb_gray(0);
    if (!l->map) {
        *pdf = ts_uniform_sphere_pdf();
        return l->color;
    }
    float pdf_map;
    ts_rgb L = ts_envmap_query_lookup_pdf(l->map, &q->map, &pdf_map);
    double p = pdf_map * q->jac;
    *pdf = p < FLT_MAX ? (float)p : 0.0f;
    return ts_rgb_mul(l->color, L);
}

ts_rgb ts_light_le_pdf(const ts_light *l, ts_vec3 wi, float *pdf)
{
    ts_light_query q;
    ts_light_query_begin(l, wi, &q);
    return ts_light_query_le_pdf(l, &q, pdf);
}

ts_rgb ts_light_power(const ts_light *l, const ts_shape *shapes)
{
    (void)shapes;
    switch (l->type) {
    case TS_LIGHT_POINT: return ts_rgb_scale(l->color, 4 * TS_PI);
    case TS_LIGHT_SPOT: {
        /* 2π ∫ falloff d(cosθ): 1 − cos_start inside, (cos_start − cos_total)/5 in the band. */
        float band = (l->cos_falloff_start - l->cos_total) / 5;
        return ts_rgb_scale(l->color, 2 * TS_PI * ((1 - l->cos_falloff_start) + band));
    }
    case TS_LIGHT_DISTANT: return ts_rgb_scale(l->color, TS_PI * l->scene_radius * l->scene_radius);
    case TS_LIGHT_AREA: return ts_rgb_scale(l->color, (float)(TS_PI_D * l->geom.area * (l->two_sided ? 2 : 1)));
    case TS_LIGHT_INFINITE: {
        ts_rgb mean = l->map ? ts_rgb_mul(l->color, l->map->mean_radiance) : l->color;
        return ts_rgb_scale(mean, 4 * TS_PI * TS_PI * l->scene_radius * l->scene_radius);
    }
    }
    return ts_rgb_gray(0);
}

/* ---------------------------------------------------------------- a light's bounds for the hierarchy (light_bvh.h) */

static ts_light_bounds no_bounds(void)
{
    ts_light_bounds lb;
    memset(&lb, 0, sizeof lb);
    lb.box = ts_bounds3_empty();
    return lb;
}

/* Emits into every direction from every point of box. */
static ts_light_bounds everywhere(ts_bounds3 box, float phi)
{
    ts_light_bounds lb = {.box = box, .phi = phi, .w = {0, 0, 1}, .cos_o = -1, .cos_e = 0, .two_sided = false};
    lb.cos_e = (float)cos(TS_PI_D / 2 + TS_LIGHT_BVH_MARGIN);
    return lb;
}

/* A flat emitter with front normal n: the hemisphere around n (both sides if two_sided). */
static ts_light_bounds flat(ts_bounds3 box, float phi, ts_vec3 n, bool two_sided)
{
    ts_light_bounds lb = everywhere(box, phi);
    lb.w = n;
    lb.cos_o = 1;
    lb.two_sided = two_sided;
    return lb;
}

ts_light_bounds ts_light_bounds_of(const ts_light *l, const ts_shape *shapes)
{
    ts_rgb power = ts_light_power(l, shapes);
    double lum = ts_rgb_luminance(power);
    float phi = ts_rgb_is_finite(power) && ts_rgb_max(power) > 0 && lum > 0 ? (float)lum : 0;
    if (!(phi > 0) || !isfinite(phi)) return no_bounds();
    switch (l->type) {
    case TS_LIGHT_POINT: return everywhere((ts_bounds3){l->position, l->position}, phi);
    case TS_LIGHT_SPOT: {
        ts_light_bounds lb = everywhere((ts_bounds3){l->position, l->position}, phi);
        double theta = acos(fmax(-1.0, fmin(1.0, (double)l->cos_total))) + TS_LIGHT_BVH_MARGIN;
        lb.w = l->direction;
        lb.cos_o = (float)cos(theta < TS_PI_D ? theta : TS_PI_D);
        lb.cos_e = (float)cos((double)TS_LIGHT_BVH_MARGIN);
        return lb;
    }
    case TS_LIGHT_AREA: {
        const ts_shape *sh = &shapes[l->shape];
        if (sh->type == TS_SHAPE_MESH) {
            ts_bounds3 box = ts_shape_triangle_bounds(sh, l->prim);
            if (l->rect) box = ts_bounds3_union(box, ts_shape_triangle_bounds(sh, l->prim_b));
            ts_vec3 n = ts_dvec3_to_vec3(l->geom.tri_n);
            if (!ts_vec3_is_finite(n) || !(ts_vec3_length_sq(n) > 0)) return everywhere(box, phi);
            return flat(box, phi, n, l->two_sided);
        }
        ts_bounds3 box = ts_shape_bounds(sh);
        if (sh->type == TS_SHAPE_DISK) {
            ts_shape_point pt;
            if (ts_shape_sample_area(sh, 0, &l->geom, (ts_vec2){0.5f, 0.5f}, &pt) && ts_vec3_is_finite(pt.n) &&
                ts_vec3_length_sq(pt.n) > 0)
                return flat(box, phi, ts_vec3_normalize(pt.n), l->two_sided);
        }
        return everywhere(box, phi); /* spheres and cylinders: normals in every direction */
    }
    case TS_LIGHT_DISTANT:
    case TS_LIGHT_INFINITE: return no_bounds();
    }
    return no_bounds();
}

/* ---------------------------------------------------------------- light selection */

/* Radical inverse of i in the prime base of dimension dim (2, 3, 5, 7, 11): the Halton
 * sequence pbrt-v3's SpatialLightDistribution places its points and light samples with. */
static float radical_inverse(int dim, uint32_t i)
{
    static const uint32_t primes[5] = {2, 3, 5, 7, 11};
    uint32_t b = primes[dim];
    double inv = 1.0 / b, f = inv, r = 0;
    for (; i; i /= b, f *= inv)
        r += (double)(i % b) * f;
    return fminf((float)r, 0x1.fffffep-1f);
}

static float axis(ts_vec3 v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

/* Makes voxel (ix, iy, iz)'s cdf (n + 1 floats) from the lights' estimated contributions. */
static void spatial_make(const ts_light_distribution *d, const int vi[3], float *cdf)
{
    uint32_t n = d->n;
    float lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        float b0 = axis(d->bounds.lo, k), b1 = axis(d->bounds.hi, k);
        float t0 = (float)vi[k] / (float)d->voxels[k], t1 = (float)(vi[k] + 1) / (float)d->voxels[k];
        lo[k] = (1 - t0) * b0 + t0 * b1;
        hi[k] = (1 - t1) * b0 + t1 * b1;
    }
    for (uint32_t j = 0; j <= n; j++)
        cdf[j] = 0;
    for (uint32_t i = 0; i < TS_LIGHT_SPATIAL_SAMPLES; i++) {
        ts_interaction ref;
        memset(&ref, 0, sizeof ref);
        float t[3] = {radical_inverse(0, i), radical_inverse(1, i), radical_inverse(2, i)};
        ref.p = (ts_vec3){(1 - t[0]) * lo[0] + t[0] * hi[0], (1 - t[1]) * lo[1] + t[1] * hi[1],
                          (1 - t[2]) * lo[2] + t[2] * hi[2]};
        ref.shape = ref.prim = TS_NONE;
        ts_vec2 u = {radical_inverse(3, i), radical_inverse(4, i)};
        for (uint32_t j = 0; j < n; j++) {
            ts_light_sample ls;
            if (ts_light_sample_li(&d->lights[j], d->shapes, &ref, u, &ls) && ls.pdf > 0)
                cdf[j + 1] += ts_rgb_luminance(ls.L) / ls.pdf;
        }
    }
    /* No light may get probability 0: it may light points of the voxel the 128 missed. */
    double sum = 0;
    for (uint32_t j = 1; j <= n; j++)
        sum += cdf[j];
    double avg = sum / ((double)TS_LIGHT_SPATIAL_SAMPLES * n), min_c = avg > 0 ? 1e-3 * avg : 1;
    double total = 0;
    for (uint32_t j = 1; j <= n; j++) {
        double c = cdf[j];
        if (!(c >= min_c)) c = min_c; /* also a NaN or infinite sum's */
        total += c;
        cdf[j] = (float)c;
    }
    double run = 0;
    for (uint32_t j = 1; j <= n; j++) {
        run += cdf[j];
        cdf[j] = (float)(run / total);
    }
    cdf[n] = 1;
}

/* The voxel of p (pbrt-v3's: the offset in the bounds, clamped to the grid). */
static size_t spatial_voxel(const ts_light_distribution *d, ts_vec3 p, int vi[3])
{
    for (int k = 0; k < 3; k++) {
        float b0 = axis(d->bounds.lo, k), b1 = axis(d->bounds.hi, k), o = axis(p, k) - b0;
        if (b1 > b0) o /= b1 - b0;
        float x = o * (float)d->voxels[k];
        vi[k] = x >= 0 ? (x < (float)d->voxels[k] ? (int)x : d->voxels[k] - 1) : 0; /* NaN: 0 */
    }
    return ((size_t)vi[2] * (size_t)d->voxels[1] + (size_t)vi[1]) * (size_t)d->voxels[0] + (size_t)vi[0];
}

/* p's voxel's cdf, made on first use (light.h: the state word's protocol). */
static const float *spatial_cdf(const ts_light_distribution *d, ts_vec3 p)
{
    int vi[3];
    size_t v = spatial_voxel(d, p, vi);
    float *cdf = d->cdf + v * ((size_t)d->n + 1);
    uint32_t st = atomic_load_explicit(&d->state[v], memory_order_acquire);
    if (st == 2) return cdf;
    uint32_t empty = 0;
    if (st == 0 && atomic_compare_exchange_strong_explicit(&d->state[v], &empty, 1, memory_order_acq_rel,
                                                           memory_order_acquire)) {
        spatial_make(d, vi, cdf);
        atomic_store_explicit(&d->state[v], 2, memory_order_release);
        return cdf;
    }
    while (atomic_load_explicit(&d->state[v], memory_order_acquire) != 2)
        sched_yield(); /* another thread is making it: 128 × n light samples */
    return cdf;
}

ts_status ts_light_distribution_init(ts_light_distribution *d, const ts_light *lights, uint32_t n,
                                     const ts_shape *shapes, ts_light_sampling mode, ts_bounds3 bounds,
                                     ts_arena *arena, ts_error *err)
{
    memset(d, 0, sizeof *d);
    if (n == 0) return TS_OK;
    if (mode == TS_LIGHT_SAMPLING_BVH) {
        ts_light_bounds *lb = malloc((size_t)n * sizeof *lb);
        bool *far = malloc((size_t)n * sizeof *far);
        if (!lb || !far) {
            free(lb);
            free(far);
            return ts_error_set(err, TS_ERR_NOMEM, "light distribution: out of memory for %u lights", n);
        }
        for (uint32_t i = 0; i < n; i++) {
            lb[i] = ts_light_bounds_of(&lights[i], shapes);
            ts_rgb phi = ts_light_power(&lights[i], shapes);
            far[i] = (lights[i].type == TS_LIGHT_DISTANT || lights[i].type == TS_LIGHT_INFINITE) &&
                     ts_rgb_is_finite(phi) && ts_rgb_max(phi) > 0;
        }
        ts_status st = ts_light_bvh_build(&d->tree, lb, far, n, arena, err);
        free(lb);
        free(far);
        if (st) return st;
        d->bvh = true;
        d->n = n;
        return TS_OK;
    }
    if (mode == TS_LIGHT_SAMPLING_SPATIAL) {
        ts_vec3 diag = ts_vec3_sub(bounds.hi, bounds.lo);
        float bmax = fmaxf(diag.x, fmaxf(diag.y, diag.z));
        bool usable = !ts_bounds3_is_empty(bounds) && ts_vec3_is_finite(diag) && bmax > 0;
        size_t per_voxel = sizeof(uint32_t) + ((size_t)n + 1) * sizeof(float), count = 1;
        for (int along = TS_LIGHT_SPATIAL_VOXELS; along >= 1; along /= 2) {
            count = 1;
            for (int k = 0; k < 3; k++) {
                int m = usable ? (int)roundf(axis(diag, k) / bmax * (float)along) : 1;
                d->voxels[k] = m > 1 ? m : 1;
                count *= (size_t)d->voxels[k];
            }
            if (count * per_voxel <= TS_LIGHT_SPATIAL_MAX_BYTES) break;
        }
        if (count * per_voxel > TS_LIGHT_SPATIAL_MAX_BYTES)
            return ts_error_set(err, TS_ERR_LIMIT, "light distribution: %u lights are too many for spatial selection",
                                n);
        d->state = calloc(count, sizeof *d->state);
        d->cdf = calloc(count * ((size_t)n + 1), sizeof *d->cdf);
        if (!d->state || !d->cdf) {
            ts_light_distribution_fini(d);
            return ts_error_set(err, TS_ERR_NOMEM, "light distribution: out of memory for %zu voxels of %u lights",
                                count, n);
        }
        d->spatial = true;
        d->lights = lights;
        d->shapes = shapes;
        d->bounds = bounds;
        d->n = n;
        return TS_OK;
    }
    double *w = malloc((size_t)n * sizeof *w);
    if (!w) return ts_error_set(err, TS_ERR_NOMEM, "light distribution: out of memory for %u lights", n);
    for (uint32_t i = 0; i < n; i++) {
        ts_rgb phi = ts_light_power(&lights[i], shapes);
        bool emits = ts_rgb_is_finite(phi) && ts_rgb_max(phi) > 0;
        double lum = ts_rgb_luminance(phi);
        if (mode == TS_LIGHT_SAMPLING_POWER) w[i] = emits && lum > 0 ? lum : 0;
        else w[i] = emits ? 1 : 0;
    }
    ts_status st = ts_alias_table_init(&d->table, w, n, arena, err);
    free(w);
    if (st) return st;
    d->n = n;
    return TS_OK;
}

void ts_light_distribution_fini(ts_light_distribution *d)
{
    free((void *)d->state);
    free(d->cdf);
    d->state = NULL;
    d->cdf = NULL;
}

uint32_t ts_light_distribution_sample(const ts_light_distribution *d, ts_vec3 p, ts_vec2 u, float *pmf)
{
    return ts_light_distribution_sample_at(d, p, (ts_vec3){0, 0, 0}, u, pmf);
}

float ts_light_distribution_pmf(const ts_light_distribution *d, ts_vec3 p, uint32_t i)
{
    return ts_light_distribution_pmf_at(d, p, (ts_vec3){0, 0, 0}, i);
}

uint32_t ts_light_distribution_sample_at(const ts_light_distribution *d, ts_vec3 p, ts_vec3 n, ts_vec2 u, float *pmf)
{
    if (d->n == 0) {
        if (pmf) *pmf = 0;
        return TS_NONE;
    }
    if (d->bvh) {
        float pm;
        uint32_t i = ts_light_bvh_sample(&d->tree, p, n, u.x, &pm);
        if (pmf) *pmf = pm;
        return i;
    }
    if (!d->spatial) return ts_alias_table_sample(&d->table, u, pmf);
    const float *cdf = spatial_cdf(d, p);
    /* the first i with cdf[i + 1] > u.x: cdf[i] ≤ u.x < cdf[i + 1], so its pmf is > 0 */
    uint32_t lo = 0, hi = d->n - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid + 1] > u.x) hi = mid;
        else lo = mid + 1;
    }
    if (pmf) *pmf = cdf[lo + 1] - cdf[lo];
    return lo;
}

float ts_light_distribution_pmf_at(const ts_light_distribution *d, ts_vec3 p, ts_vec3 n, uint32_t i)
{
    if (d->n == 0 || i >= d->n) return 0.0f;
    if (d->bvh) return ts_light_bvh_pmf(&d->tree, p, n, i);
    if (!d->spatial) return ts_alias_table_pmf(&d->table, i);
    const float *cdf = spatial_cdf(d, p);
    return cdf[i + 1] - cdf[i];
}

uint32_t ts_lights_set_triangle_sampling(ts_light *lights, uint32_t n, const ts_shape *shapes,
                                         ts_triangle_sampling mode)
{
    uint32_t changed = 0;
    for (uint32_t i = 0; i < n; i++) {
        ts_light *l = &lights[i];
        if (l->type != TS_LIGHT_AREA || shapes[l->shape].type != TS_SHAPE_MESH) continue;
        l->triangle_sampling = mode;
        l->geom.triangle_mode = mode;
        changed++;
    }
    return changed;
}
