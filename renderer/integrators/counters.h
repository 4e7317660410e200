/* counters.h — what a render worker counts while it integrates, and its stop flag.
 *
 * Design note: one per worker, summed by the renderer after a pass (render.h); nothing
 * here is shared between threads while a pass runs but the stop flag, only read. */
#ifndef TS_COUNTERS_H
#define TS_COUNTERS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

typedef struct ts_counters {
    uint64_t camera_rays, other_rays;
    uint64_t samples;
    uint64_t nonfinite; /* samples dropped for NaN, ∞ or negative radiance */
    /* volpath: tracking steps taken in media, and walks cut short (the step bound of
     * media/medium.h, a path's bound on boundary crossings, or the stop flag). */
    uint64_t medium_steps, walks_truncated;
    /* Optional, only read (relaxed) here: once set, the integrator ends the sample at its
     * next bounce or light, so no sample outlives a stop by more than one step; the value
     * it returns then is meaningless and the caller discards the work (render.h). */
    const atomic_bool *stop;
} ts_counters;

#endif
