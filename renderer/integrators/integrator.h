/* integrator.h — radiance along a camera ray: the integrators of scene format v1.
 *
 * Design note: one entry point switches on the scene's integrator type (no function
 * pointers on the hot path). Random numbers come only from the sample stream, whose
 * dimensions 0 and 1 the camera has used, so a sample's value depends only on (seed,
 * pixel, index, dimension). Nothing here allocates or locks; counters are per worker.
 * `ao` and `normals` are debugging views that need no lights. */
#ifndef TS_INTEGRATOR_H
#define TS_INTEGRATOR_H

#include <stdbool.h>
#include <stdint.h>

#include "sampling/sampler.h"
#include "scene/scene.h"

/* Per-worker counters, summed by the renderer after a pass. */
typedef struct ts_counters {
    uint64_t camera_rays, other_rays;
    uint64_t samples;
    uint64_t nonfinite; /* samples dropped for NaN, ∞ or negative radiance */
} ts_counters;

/* The scene-format name of an integrator type ("path", "direct", "ao", "normals"). */
const char *ts_integrator_name(ts_integrator_type type);

/* True when the integrator type is implemented in this build. */
bool ts_integrator_available(ts_integrator_type type);

/* Radiance arriving along ray (from the camera), simulating the effects in `effects`
 * (effects.h: the scene's own set, or all of them; never more than the scene has). */
ts_rgb ts_integrator_li(const ts_scene *s, ts_integrator_type type, uint32_t effects, const ts_ray *ray,
                        ts_sample_stream *st, ts_counters *c);

#endif
