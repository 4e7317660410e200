/* accel.h — the scene's ray-intersection structure, built with Embree 3.
 *
 * Design note: one Embree device and scene per ts_accel. Shape i is attached with geometry
 * ID i, so a hit's geomID is the index into the scene's shapes. Meshes are native Embree
 * triangles, curves Embree's flat Bézier curves (geometry/curve.h); analytic shapes are
 * user geometry calling ts_shape_intersect. A ray naming a
 * triangle in skip_shape/skip_prim never reports it (see interaction.h). Built once;
 * ts_accel_intersect and ts_accel_occluded are thread-safe and allocate nothing. */
#ifndef TS_ACCEL_H
#define TS_ACCEL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/animated_transform.h"
#include "core/cancel.h"
#include "core/error.h"
#include "geometry/interaction.h"
#include "geometry/shape.h"

typedef struct ts_accel ts_accel;

/* Object instancing (pbrt-v3's ObjectBegin/End and ObjectInstance). An object is the
 * shapes [first_shape, first_shape + n_shapes) of the scene's array, all with in_object
 * set and in the object's own space; it becomes one Embree scene, built once, and every
 * instance is an Embree instance of it under its to_world, so its geometry exists once
 * however many instances there are. A hit through instance k is resolved (instID) to the
 * object's shape: its interaction is that shape's, computed in the object's space from the
 * ray taken there in double, then mapped to world space — p by to_world with its error
 * bound carried through (pbrt-v3's transformed pError), n and ns by the inverse transpose,
 * ∂p/∂u, ∂p/∂v by to_world, uv as they are — with shape the object's shape index and inst
 * k + 1. Analytic shapes are solved directly in world space under the composed transform
 * (bit for bit what the same shape placed directly with that transform gives). Instances
 * do not nest (Embree here is built with one instance level; pbrt-v3 refuses it too). */
/* Motion (pbrt-v3's TransformedPrimitive with an AnimatedTransform): an instance with a
 * motion is an Embree instance with time steps, its transform at each step given as
 * Embree's quaternion decomposition (translation, rotation, upper-triangular scale and
 * shear), which Embree interpolates between steps as pbrt interpolates its T, R, S.
 * Where that is pbrt's interpolation exactly — the keyframes' S diagonal with the same
 * signs and the motion's times the scene's motion interval — two steps are given; else
 * (shear in S, or a motion over part of the interval, whose clamped ends Embree cannot
 * follow) TS_ACCEL_MOTION_STEPS steps, and traversal follows pbrt's motion within the
 * measured bound of tests/test_instance.c. Embree's ray time is the ray's, mapped from the
 * scene's motion interval (the union of the instances' [start, end]) to [0, 1] and clamped.
 * Either way Embree only finds the candidate: the hit itself (and every filter's test) is
 * computed in double under pbrt's transform at the ray's time, ts_anim_xform_at. */
#define TS_ACCEL_MOTION_STEPS 129
/* All moving instances' time steps together at most (else TS_ERR_LIMIT at create). */
#define TS_ACCEL_MOTION_STEP_LIMIT (1u << 20)

typedef struct ts_object {
    uint32_t first_shape, n_shapes;
} ts_object;

typedef struct ts_instance {
    uint32_t object;   /* index into the objects */
    ts_xform to_world; /* object space → world, invertible (the motion's start keyframe when moving) */
    /* NULL, or the instance's motion (core/animated_transform.h; owned by the scene): a ray
     * of time t sees the object under motion(t). See "Motion" below. */
    const ts_anim_xform *motion;
} ts_instance;

/* Builds over shapes[0..n) (the array must outlive the accel). NULL and err filled on
 * failure (Embree error text included). */
ts_accel *ts_accel_create(const ts_shape *shapes, uint32_t n_shapes, ts_error *err);
/* The same with object instances (the arrays, like shapes, must outlive the accel; shapes
 * in objects are attached only through instances). The build polls cancel (NULL: never
 * stops; Embree's progress monitor): once it says stop, NULL with TS_ERR_CANCELLED. */
ts_accel *ts_accel_create_instanced(const ts_shape *shapes, uint32_t n_shapes, const ts_object *objects,
                                    uint32_t n_objects, const ts_instance *instances, uint32_t n_instances,
                                    ts_cancel *cancel, ts_error *err);
void ts_accel_destroy(ts_accel *a);

/* Nearest hit in (0, ray.tmax): fills si fully and returns true; false on a miss. */
bool ts_accel_intersect(const ts_accel *a, const ts_ray *ray, ts_interaction *si);
/* ts_accel_intersect for a shadow ray that must find every shape on its way, not only the
 * first opaque one (volpath's transmittance through surface-less shapes): a mesh's hit is
 * cut out where alpha or shadow_alpha is 0, as ts_accel_occluded's. */
bool ts_accel_intersect_shadow(const ts_accel *a, const ts_ray *ray, ts_interaction *si);
/* True if anything is hit in (0, ray.tmax). */
bool ts_accel_occluded(const ts_accel *a, const ts_ray *ray);
/* World bounds of everything. */
ts_bounds3 ts_accel_bounds(const ts_accel *a);

/* What the accel holds in memory, for the memory benchmark (bench/memory.c): its
 * per-triangle caches (ts_tri_cache), and the bytes Embree's device allocated for it as
 * its memory monitor reports them (BVHs, primitive blocks, the copied vertex buffers):
 * still held now, and at most while building. Any field pointer may be NULL. */
typedef struct ts_accel_memory {
    size_t tri_cache_bytes;
    size_t embree_bytes, embree_peak_bytes;
} ts_accel_memory;
void ts_accel_memory_get(const ts_accel *a, ts_accel_memory *m);

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
