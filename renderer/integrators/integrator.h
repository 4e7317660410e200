/* integrator.h — radiance along a camera ray: the integrators of scene format v1.
 *
 * Design note: one entry point switches on the scene's integrator type (no function
 * pointers on the hot path). Random numbers come only from the sample stream, whose
 * dimensions 0 and 1 the camera has used, so a sample's value depends only on (seed,
 * pixel, index, dimension). Nothing here allocates or locks; counters are per worker.
 * `ao` and `normals` are debugging views that need no lights.
 *
 * Sample dimensions (sampler.h: every dimension is 2-D; a 1-D draw uses its x and leaves
 * its y unused). A dimension is consumed whether or not its value is computed (effects.h
 * skips what nothing reads), so each has a fixed place:
 *   camera (render.c)          0 film position, 1 lens
 *   path, vertex k ≥ 0 from 2 + 5k:
 *     +0 light selection       x: the alias-table bin, y: the bin's coin (distribution.h)
 *     +1 light sample          the point or direction on the chosen light
 *     +2 lobe choice           x (y free)
 *     +3 BSDF sample           the continuation direction (MIS's BSDF half)
 *     +4 Russian roulette      x (y free)
 *   direct, strategy one, at each vertex: +0 selection (x bin, y coin), +1 light sample,
 *     +2 lobe choice (x), +3 BSDF sample; then, for a specular bounce, +4 lobe choice and
 *     +5 BSDF sample of the specular continuation, and the next vertex after those.
 *   direct, strategy all: per light +0 light sample, +1 lobe choice (x), +2 BSDF sample,
 *     drawn at samples_per_light consecutive sequence indices (an array); then the
 *     specular continuation's +0 lobe choice, +1 BSDF sample.
 * The selection's coin lives in the y of the selection's own dimension, so it is
 * independent of the bin and stratified with it, at no extra dimension. */
#ifndef TS_INTEGRATOR_H
#define TS_INTEGRATOR_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "integrators/counters.h"
#include "integrators/differential.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

/* Per-worker state of the integrator: counters (summed by the renderer after a pass) and
 * an optional stop flag, integrators/counters.h. */

/* The scene-format name of an integrator type ("path", "direct", "ao", "normals"). */
const char *ts_integrator_name(ts_integrator_type type);

/* An upper bound on the rays one camera sample of this integrator traces in scene s with
 * these effects (the camera ray included): path 1 + 2·max_depth (a continuation and a
 * shadow ray a bounce), direct (1 + shadow and BSDF rays of its light sampling) at each
 * of up to max_depth specular vertices, ao 2, normals 1. What a request asks of the
 * renderer is this × spp × pixels (the server's --max-work, docs/security.md). */
double ts_integrator_rays_per_sample(const ts_scene *s, ts_integrator_type type, uint32_t effects);

/* What a scene with media (the media effect) rendered by an integrator other than volpath
 * does, for the user at load time: true with one sentence in buf, headed by its JSON path
 * (integrator.type), else false. pbrt-v3's integrators are the reference: rays pass through
 * the shapes without a surface, shadow (and occlusion) rays are blocked by them. */
bool ts_integrator_media_warning(const ts_scene *s, char *buf, size_t n);

/* Radiance arriving along ray (from the camera), simulating the effects in `effects`
 * (effects.h: the scene's own set, or all of them; never more than the scene has). rd:
 * the camera ray's differential (differential.h), or NULL for none. */
ts_rgb ts_integrator_li(const ts_scene *s, ts_integrator_type type, uint32_t effects, const ts_ray *ray,
                        const ts_ray_differential *rd, ts_sample_stream *st, ts_counters *c);

#endif
