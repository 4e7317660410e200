/* volpath.h — pbrt-v3's VolPathIntegrator: path tracing with participating media.
 *
 * Design note: the path integrator's loop (integrator.c) with pbrt-v3's volumetric steps
 * (pbrt-v3 §15.3, VolPathIntegrator::Li): along each ray segment in a medium the medium
 * samples a scattering distance (media/medium.h: the homogeneous closed form, delta
 * tracking in a grid); a medium vertex gets next-event estimation from one light with its
 * phase function as the other MIS strategy and continues by sampling the phase function;
 * a surface vertex as pbrt-v3's path tracer, but with its EstimateDirect (three rays a
 * vertex: the light sample's shadow ray, the BSDF sample's ray towards the light, the
 * continuation; emission found by the continuation counts only at the camera and after
 * specular bounces). Shadow rays and the MIS rays carry the transmittance of every medium
 * they cross, stepping through shapes without a surface (pbrt-v3's VisibilityTester::Tr
 * and Scene::IntersectTr; a shape with a surface blocks); the grid's transmittance is
 * ratio tracking. A ray's medium changes where it crosses a shape that is a medium
 * transition (geometry/shape.h); it starts in the scene's camera medium. Russian roulette
 * after rr_depth bounces on β·η-scale (pbrt-v3's: q = max(0.05, 1 − max β)). max_depth
 * (capped at 1 when the job switches `indirect` off, as path's)
 * counts scattering events in media and at surfaces, as pbrt-v3; crossing a shape without
 * a surface is no event.
 *
 * Bounds: a path crosses at most TS_VOLPATH_MAX_CROSSINGS surface-less shapes, a shadow
 * ray as many; each medium walk is bounded by medium.h's step bound; the stop flag is read
 * at every bounce and inside long walks. What is cut is counted (ts_counters). In a scene
 * without media (effects.h: no TS_EFFECT_MEDIA) no medium code runs at all.
 *
 * Sample dimensions, vertex k ≥ 0 from 2 + 7k (each 2-D; a 1-D draw uses x):
 *   +0 medium distance     x the channel, y the distance (homogeneous media; the trackers
 *                          draw from the walk's own stream, seeded from the pixel sample)
 *   +1 light selection     x the alias bin, y its coin
 *   +2 light sample
 *   +3 lobe choices        x the direct estimate's BSDF lobe, y the continuation's lobe
 *   +4 direct estimate's BSDF or phase sample (MIS's other half)
 *   +5 continuation        BSDF or phase sample
 *   +6 Russian roulette    x */
#ifndef TS_VOLPATH_H
#define TS_VOLPATH_H

#include "integrators/counters.h"
#include "integrators/differential.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

#define TS_VOLPATH_MAX_CROSSINGS 4096

/* pbrt-v3's Russian roulette after rr_depth bounces (path and volpath): with β·η-scale's
 * largest channel m below 1 the path ends with probability q = max(0.05, 1 − m) (u < q:
 * false) and survives with β / (1 − q). */
static inline bool ts_russian_roulette(ts_rgb *beta, float eta_scale, int bounces, int rr_depth, float u)
{
    float m = ts_rgb_max(ts_rgb_scale(*beta, eta_scale));
    if (m < 1 && bounces > rr_depth) {
        float q = ts_maxf(0.05f, 1 - m);
        if (u < q) return false;
        *beta = ts_rgb_scale(*beta, 1.0f / (1 - q));
    }
    return true;
}

/* Radiance along the camera ray, simulating the effects in fx (effects.h). */
ts_rgb ts_volpath_li(const ts_scene *s, uint32_t fx, ts_ray ray, const ts_ray_differential *rd,
                     ts_sample_stream *st, ts_counters *c);

/* Rays one camera sample traces at most, without boundary crossings and tracking steps:
 * 1 + 3·max_depth (max_depth 1 with indirect switched off; 1 without lights). */
double ts_volpath_rays_per_sample(const ts_scene *s, uint32_t fx);

#endif
