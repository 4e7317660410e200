/* integrator.c — integrator dispatch and the debugging views; see integrator.h. */
#include "integrator.h"

#include "sampling.h"

bool ts_integrator_available(ts_integrator_type type)
{
    return type == TS_INTEGRATOR_AO || type == TS_INTEGRATOR_NORMALS;
}

/* Ambient occlusion: the cosine-weighted fraction of the hemisphere around the shading
 * normal (turned to face the viewer) that is open within ao_distance. One shadow ray per
 * sample, so the estimate is 0 or 1 and its mean is the occlusion integral ∫V cosθ/π. */
static ts_rgb li_ao(const ts_scene *s, const ts_ray *ray, ts_sample_stream *st, ts_counters *c)
{
    ts_interaction si;
    if (!ts_accel_intersect(s->accel, ray, &si)) return ts_rgb_gray(0);
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

static ts_rgb li_normals(const ts_scene *s, const ts_ray *ray)
{
    ts_interaction si;
    if (!ts_accel_intersect(s->accel, ray, &si)) return ts_rgb_gray(0);
    return (ts_rgb){0.5f * (si.ns.x + 1), 0.5f * (si.ns.y + 1), 0.5f * (si.ns.z + 1)};
}

ts_rgb ts_integrator_li(const ts_scene *s, ts_integrator_type type, const ts_ray *ray, ts_sample_stream *st,
                        ts_counters *c)
{
    c->camera_rays++;
    switch (type) {
    case TS_INTEGRATOR_AO: return li_ao(s, ray, st, c);
    case TS_INTEGRATOR_NORMALS: return li_normals(s, ray);
    case TS_INTEGRATOR_PATH:
    case TS_INTEGRATOR_DIRECT: break;
    }
    return ts_rgb_gray(0);
}
