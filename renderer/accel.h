/* accel.h — the scene's ray-intersection structure, built with Embree 3.
 *
 * Design note: one Embree device and scene per ts_accel. Shape i is attached with geometry
 * ID i, so a hit's geomID is the index into the scene's shapes. Meshes are native Embree
 * triangles; analytic shapes are user geometry calling ts_shape_intersect. A ray naming a
 * triangle in skip_shape/skip_prim never reports it (see interaction.h). Built once;
 * ts_accel_intersect and ts_accel_occluded are thread-safe and allocate nothing. */
#ifndef TS_ACCEL_H
#define TS_ACCEL_H

#include <stdbool.h>
#include <stdint.h>

#include "error.h"
#include "interaction.h"
#include "shape.h"

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

#endif
