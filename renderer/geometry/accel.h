/* accel.h — the scene's ray-intersection structure, built with Embree 3.
 *
 * Design note: one Embree device and scene per ts_accel. Shape i is attached with geometry
 * ID i, so a hit's geomID is the index into the scene's shapes. Meshes are native Embree
 * triangles; analytic shapes are user geometry calling ts_shape_intersect. A ray naming a
 * triangle in skip_shape/skip_prim never reports it (see interaction.h). Built once;
 * ts_accel_intersect and ts_accel_occluded are thread-safe and allocate nothing. */
#ifndef TS_ACCEL_H
#define TS_ACCEL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "geometry/interaction.h"
#include "geometry/shape.h"

typedef struct ts_accel ts_accel;

/* Builds over shapes[0..n) (the array must outlive the accel). NULL and err filled on
 * failure (Embree error text included). */
ts_accel *ts_accel_create(const ts_shape *shapes, uint32_t n_shapes, ts_error *err);
void ts_accel_destroy(ts_accel *a);

/* Nearest hit in (0, ray.tmax): fills si fully and returns true; false on a miss. */
bool ts_accel_intersect(const ts_accel *a, const ts_ray *ray, ts_interaction *si);
/* True if anything is hit in (0, ray.tmax). */
bool ts_accel_occluded(const ts_accel *a, const ts_ray *ray);
/* World bounds of everything. */
ts_bounds3 ts_accel_bounds(const ts_accel *a);

/* A record of the rays an accel is asked about, for benchmarks (bench/throughput replays
 * them against raw Embree). Caller-owned storage. Every query that reaches Embree takes
 * the next slot with an atomic increment of n and, while slots remain, stores its ray
 * and kind there, so any number of threads may log at once; with one rendering thread the
 * log is in query order. Queries beyond the capacity only count in n. */
typedef struct ts_ray_log {
    ts_ray *rays;     /* capacity entries */
    uint8_t *kinds;   /* capacity entries: TS_RAY_LOG_INTERSECT or TS_RAY_LOG_OCCLUDED */
    size_t capacity;
    atomic_size_t n;  /* queries offered so far (may exceed capacity) */
} ts_ray_log;

enum { TS_RAY_LOG_INTERSECT = 0, TS_RAY_LOG_OCCLUDED = 1 };

/* Starts (log non-NULL) or stops (NULL) logging a's queries. The one mutable field of an
 * accel: set it only while no query runs (between renders). Off, a query pays one
 * predictable branch. */
void ts_accel_set_ray_log(ts_accel *a, ts_ray_log *log);

#endif
