/* light_bvh.h — light selection by a bounding volume hierarchy over the lights (pbrt-v4's
 * BVHLightSampler, after Conty Estevez and Kulla 2018): each node bounds its lights' positions
 * (a box), their power and the directions they emit into (a cone of normals θ_o around w,
 * widened by the emission spread θ_e), and a shading point walks from the root choosing a
 * child with probability ∝ the child's importance there — a conservative bound of what the
 * child's lights can give the point — until it reaches one light.
 *
 * Design note. Exactness: the importance of a node is 0 only where none of its lights can
 * light the point (behind every one-sided emitter of the node, outside every spot cone, by
 * more than a small margin; the node's box is seen through its bounding sphere), so every light that can contribute at p has pmf > 0, and
 * ts_light_bvh_pmf(p, n, i) walks light i's path from the root with the same float
 * operations as ts_light_bvh_sample, so the two agree bit for bit (MIS needs that). Lights
 * without bounds (distant, infinite) are chosen apart, uniformly, with probability
 * n_inf / (n_inf + 1) (1 when the hierarchy is empty), as pbrt-v4; lights that emit nothing
 * are never chosen.
 *
 * The bounds of a light: point lights emit everywhere (θ_o = π); a spot around its axis
 * within its total cone angle; a flat one-sided emitter (a mesh triangle, a rectangle of two,
 * a disk) into the hemisphere of its front normal (θ_o = 0, θ_e = π/2); spheres, cylinders
 * and two-sided emitters everywhere. φ is the luminance of ts_light_power. Departures from
 * pbrt-v4's heuristics (unbiased either way, docs/design.md §9): the distance is clamped
 * below by the squared half-diagonal of the node's box (pbrt-v4 takes the half-diagonal's
 * length, not squared), and the angles carry a margin of TS_LIGHT_BVH_MARGIN radians so
 * that float rounding can never zero a light that contributes.
 *
 * Build: pbrt-v4's top-down split over 12 buckets per axis by its cost (power × the solid
 * angle measure M_Ω of the cone × the box's area × the axis' aspect), one light per leaf, a
 * stable partition so the tree is a function of the light list alone; beyond depth 32 a
 * split at the middle of the list bounds the depth (the path of a light is kept as 64
 * bits). Immutable after build; every query is pure and thread-safe. */
#ifndef TS_LIGHT_BVH_H
#define TS_LIGHT_BVH_H

#include <stdbool.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/error.h"
#include "core/vecmath.h"
#include "geometry/interaction.h" /* TS_NONE */

#define TS_LIGHT_BVH_MARGIN 1e-3f /* radians added to the cones' angles */
#define TS_LIGHT_BVH_MAX_DEPTH 60

/* pbrt-v4's LightBounds. */
typedef struct ts_light_bounds {
    ts_bounds3 box;
    float phi;             /* power (luminance); 0: not bounded (never selected) */
    ts_vec3 w;             /* unit axis of the emitting normals */
    float cos_o, cos_e;    /* cos θ_o: normals within θ_o of w; cos θ_e: emission spread */
    bool two_sided;
} ts_light_bounds;

typedef struct ts_light_bvh_node {
    /* what the walk reads: the bounds' sphere (centre, radius² rounded up), cone and power */
    ts_vec3 center, w;
    float r2, phi, cos_o, sin_o, cos_e;
    bool two_sided;
    bool leaf;
    uint32_t index; /* leaf: the light; interior: the second child (the first is the next node) */
    ts_light_bounds lb; /* the bounds themselves (the build's unions) */
} ts_light_bvh_node;

typedef struct ts_light_bvh {
    ts_light_bvh_node *nodes;
    uint32_t n_nodes;
    uint32_t n_lights;
    uint32_t *unbounded; /* distant and infinite lights that emit */
    uint32_t n_unbounded;
    uint64_t *trail; /* per light: its path from the root, bit k the choice at depth k */
    uint8_t *in_tree; /* per light: 1 in the hierarchy, 2 among the unbounded, 0 never chosen */
} ts_light_bvh;

/* Importance of bounds lb for a point p with normal n (n zero: no cosine at p). */
float ts_light_bounds_importance(const ts_light_bounds *lb, ts_vec3 p, ts_vec3 n);

/* Builds the hierarchy over n lights: light i has bounds[i] (phi 0: never chosen, unless
 * unbounded[i]: a distant or infinite light that emits, chosen apart). Memory from arena;
 * the lights' bounds come from light.h's ts_light_bounds_of. */
ts_status ts_light_bvh_build(ts_light_bvh *bvh, const ts_light_bounds *bounds, const bool *unbounded, uint32_t n,
                             ts_arena *arena, ts_error *err);

/* A light for point p with shading normal n (zero for none), from the 1-D sample u in [0, 1),
 * with its probability; TS_NONE (pmf 0) when no light can light p. */
uint32_t ts_light_bvh_sample(const ts_light_bvh *bvh, ts_vec3 p, ts_vec3 n, float u, float *pmf);

/* The probability that ts_light_bvh_sample(p, n, ·) returns light i. */
float ts_light_bvh_pmf(const ts_light_bvh *bvh, ts_vec3 p, ts_vec3 n, uint32_t i);

#endif
