/* light.h — the lights of scene format v1 and their sampling (pbrt-v3 ch. 12, §14.2).
 *
 * Design note: a light is plain data tagged by type; every operation is a switch on the
 * tag (no function pointers on the hot path). The scene loader fills the public fields,
 * then calls ts_lights_prepare once, which validates them, normalises directions, sets
 * the scene's bounding sphere for distant and infinite lights and precomputes what
 * sampling needs (shape areas etc., in the fields marked "prepare"). After that lights
 * are immutable and shared read-only by all threads; every query below is pure,
 * allocation-free and thread-safe.
 *
 * Conventions (docs/design.md §4): a mesh's emitting triangles are one TS_LIGHT_AREA each
 * (zero-area ones get power 0 and are never selected by the power distribution, and
 * sample nothing), except that two consecutive triangles forming a rectangle
 * (ts_shape_triangles_rectangle) are one light, `rect`, sampled uniformly in the solid
 * angle of the whole rectangle; ts_area_light_index maps a hit to its light. Area lights emit `color` on the shape's front side unless two_sided.
 * Infinite lights: radiance `color` (constant), or color × map (color holds the scale),
 * the map's own space taken to world by to_world (see envmap.h for the lat-long axes).
 *
 * Sampling returns radiance and a pdf; it does no visibility test: the integrator traces
 * a shadow ray to p_light (ts_spawn_ray_to(ref, shapes, p_light, p_light_error, n_light)).
 * For distant and infinite lights p_light is a proxy outside the scene's bounding sphere.
 * n_light and p_light_error are 0 for every light but area lights. */
#ifndef TS_LIGHT_H
#define TS_LIGHT_H

#include <stdbool.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/error.h"
#include "core/transform.h"
#include "core/vecmath.h"
#include "geometry/interaction.h"
#include "geometry/shape.h"
#include "geometry/shape_sample.h"
#include "lights/envmap.h"
#include "lights/light_bvh.h"
#include "sampling/distribution.h"

struct ts_envmap; /* envmap.h */

typedef enum ts_light_type {
    TS_LIGHT_POINT,
    TS_LIGHT_SPOT,
    TS_LIGHT_DISTANT,
    TS_LIGHT_AREA,
    TS_LIGHT_INFINITE,
} ts_light_type;

typedef struct ts_light {
    ts_light_type type;
    ts_rgb color;          /* point/spot: intensity I; distant: irradiance E; area: emitted radiance L;
                              infinite: radiance (or scale×map) */
    ts_vec3 position;      /* point, spot */
    ts_vec3 direction;     /* spot: unit axis from→to; distant: unit direction the light travels (from→to) */
    float cos_total, cos_falloff_start; /* spot: cos(cone_angle), cos(cone_angle − cone_delta) (pbrt-v3) */
    uint32_t shape, prim;  /* area: the emitting shape and triangle (prim 0 for analytic shapes) */
    bool rect;             /* area, mesh: the rectangle of triangles prim and prim_b, one light */
    uint32_t prim_b;
    bool two_sided;        /* area */
    uint32_t samples;      /* samples of this light per camera sample under direct's strategy all
                              (pbrt-v3's nSamples); 0: the integrator's samples_per_light */
    const struct ts_envmap *map; /* infinite: map or NULL for constant */
    ts_xform to_world;     /* infinite: map space → world */
    ts_vec3 scene_center;  /* distant/infinite: filled by ts_lights_prepare */
    float scene_radius;
    /* area: how triangles are sampled (loader leaves 0 = AUTO; ts_lights_set_triangle_sampling forces one) */
    ts_triangle_sampling triangle_sampling;
    /* prepare: area sampling data (area, sphere centre/radius, …) */
    ts_shape_sample_info geom;
} ts_light;

/* After loading: validates (TS_ERR_INVALID, sentence starting "lights[i]: "), normalises
 * direction, sets scene_center/scene_radius for distant/infinite lights from scene_bounds
 * (empty or degenerate bounds give radius 1), and precomputes area-light data. shapes is
 * the scene's shape array (indexed by ts_light.shape). Not thread-safe; call once. */
ts_status ts_lights_prepare(ts_light *lights, uint32_t n, const ts_shape *shapes, ts_bounds3 scene_bounds,
                            ts_error *err);

/* Forces how the area lights on mesh triangles are sampled, after ts_lights_prepare (sets
 * triangle_sampling and the prepared geom's mode; AUTO restores the loader's default).
 * Returns how many lights it changed. The accuracy benchmark's switch (bench/accuracy/);
 * scene files have no key for it. Not thread-safe: call before rendering. */
uint32_t ts_lights_set_triangle_sampling(ts_light *lights, uint32_t n, const ts_shape *shapes,
                                         ts_triangle_sampling mode);

/* The area light of a hit on emissive shape sh (triangle prim of a mesh): the builder's
 * per-triangle table where it made one (a rectangle's two triangles share a light), else
 * one light per triangle from first_light. */
static inline uint32_t ts_area_light_index(const ts_shape *sh, uint32_t prim)
{
    if (sh->type != TS_SHAPE_MESH) return sh->first_light;
    return sh->prim_light ? sh->prim_light[prim] : sh->first_light + prim;
}

typedef struct ts_light_sample {
    ts_rgb L;            /* radiance arriving at ref along −wi (before visibility) */
    ts_vec3 wi;          /* unit, from ref towards the light */
    float pdf;           /* per solid angle, or 1 for delta lights */
    ts_vec3 p_light, p_light_error, n_light;
    bool is_delta;       /* point, spot, distant */
    bool is_infinite;    /* distant, infinite: p_light is a far proxy */
} ts_light_sample;

/* Samples incident light at ref with the 2D sample u. Returns false — and out->L black,
 * out->pdf 0 — when the sample carries no light (ref behind a one-sided emitter, ref on
 * or coplanar with the emitter, outside a spot's cone, a zero-area triangle, …); the
 * caller then adds nothing. On true, L is non-black, pdf > 0 and everything is finite. */
bool ts_light_sample_li(const ts_light *l, const ts_shape *shapes, const ts_interaction *ref, ts_vec2 u,
                        ts_light_sample *out);

/* Density per solid angle with which ts_light_sample_li picks direction wi from ref: 0 for
 * delta lights and for directions that miss the light. For area lights the point is the
 * first hit of the ray (ref->p, wi) on the light's shape (triangle). */
float ts_light_pdf_li(const ts_light *l, const ts_shape *shapes, const ts_interaction *ref, ts_vec3 wi);
/* Area lights, when the caller already found the light's point p_hit along the ray (the
 * path tracer's BSDF-sampled ray hit the emitter): the same density, no re-intersection. */
float ts_light_pdf_li_hit(const ts_light *l, const ts_shape *shapes, const ts_interaction *ref, ts_vec3 p_hit);

/* Infinite lights: radiance along an escaping ray (black for every other type). */
ts_rgb ts_light_le(const ts_light *l, const ts_ray *ray);
/* Infinite lights: ts_light_le along direction wi with *pdf = ts_light_pdf_li(l, …, wi),
 * bit for bit, the map's coordinates of wi found once; black and 0 for other types. */
ts_rgb ts_light_le_pdf(const ts_light *l, ts_vec3 wi, float *pdf);
/* The same in two halves (envmap.h's ts_envmap_query): ts_light_query_begin before the ray
 * along wi is traced starts fetching the map's texels; ts_light_query_le_pdf after it
 * escaped is ts_light_le_pdf(l, wi, pdf), bit for bit. */
typedef struct ts_light_query {
    ts_vec3 wi;
    double jac;
    ts_envmap_query map;
} ts_light_query;
void ts_light_query_begin(const ts_light *l, ts_vec3 wi, ts_light_query *q);
ts_rgb ts_light_query_le_pdf(const ts_light *l, const ts_light_query *q, float *pdf);
/* Area lights: emitted radiance from a hit si on its shape towards w (black behind a
 * one-sided emitter). */
ts_rgb ts_area_light_l(const ts_light *l, const ts_interaction *si, ts_vec3 w);
/* Total emitted power Φ (needs ts_lights_prepare for area, distant, infinite lights). */
ts_rgb ts_light_power(const ts_light *l, const ts_shape *shapes);

/* The bounds of a prepared light for the light hierarchy (light_bvh.h): phi 0 for lights with
 * no bounds (distant, infinite) or no power. */
ts_light_bounds ts_light_bounds_of(const ts_light *l, const ts_shape *shapes);

/* Light selection for the integrators (docs/design.md §4 `light_sampling`). */
typedef enum ts_light_sampling {
    TS_LIGHT_SAMPLING_UNIFORM,
    TS_LIGHT_SAMPLING_POWER,   /* ∝ luminance of ts_light_power; uniform if all powers are 0 */
    TS_LIGHT_SAMPLING_SPATIAL, /* pbrt-v3's SpatialLightDistribution, below */
    TS_LIGHT_SAMPLING_BVH,     /* pbrt-v4's BVHLightSampler (light_bvh.h): by the point and its normal */
} ts_light_sampling;

/* Spatial selection (pbrt-v3's default for `path`): the scene's bounds are cut into voxels,
 * TS_LIGHT_SPATIAL_VOXELS along the longest axis and round(extent / longest · that) (≥ 1)
 * along the others. Each voxel has its own distribution, ∝ max(c_j, 10⁻³ · mean c) where
 * c_j sums luminance(L)/pdf of light j's ts_light_sample_li from 128 Halton points of the
 * voxel (bases 2, 3, 5 for the point, 7 and 11 for the light sample; no visibility, no
 * normal), and all lights get 1 when every c_j is 0. A voxel's distribution is made the first
 * time a point in it is looked up, by whichever thread gets there first, and never changes:
 * it depends on the voxel alone, so images are the same whatever the thread count. Its
 * state word is atomic (0 empty, 1 being made, 2 ready; a thread finding 1 waits on it —
 * rare, and as short as making one voxel's distribution); the cdf words are written
 * before the release store of 2 and read after an acquire load of it. Memory: one state
 * word and n + 1 floats a voxel, calloc'd (pages only touched voxels use); when the grid
 * would need more than TS_LIGHT_SPATIAL_MAX_BYTES the voxel count along the longest axis
 * is halved until it fits (many-light scenes; pbrt-v3 keeps 64 and allocates per voxel). */
#define TS_LIGHT_SPATIAL_VOXELS 64
#define TS_LIGHT_SPATIAL_SAMPLES 128
#define TS_LIGHT_SPATIAL_MAX_BYTES ((size_t)64 << 20)

typedef struct ts_light_distribution {
    uint32_t n;            /* number of lights (0: nothing to sample) */
    ts_alias_table table;  /* uniform/power: table.pmf[i] is the exact probability of light i */
    /* spatial (n > 0): immutable but for the per-voxel cache (state, cdf) described above */
    bool spatial;
    const ts_light *lights;
    const ts_shape *shapes;
    ts_bounds3 bounds;
    int voxels[3];
    _Atomic uint32_t *state; /* per voxel, x fastest */
    float *cdf;              /* (n + 1) per voxel: cdf[0] = 0 ≤ … ≤ cdf[n] = 1 */
    /* bvh (n > 0): the hierarchy, in the arena */
    bool bvh;
    ts_light_bvh tree;
} ts_light_distribution;

/* Builds over lights[0..n) (prepared), memory from arena (the spatial cache from calloc:
 * ts_light_distribution_fini frees it). bounds: the scene's (spatial only). n = 0 is
 * allowed. lights and shapes must outlive d when spatial. */
ts_status ts_light_distribution_init(ts_light_distribution *d, const ts_light *lights, uint32_t n,
                                     const ts_shape *shapes, ts_light_sampling mode, ts_bounds3 bounds,
                                     ts_arena *arena, ts_error *err);
/* Frees the spatial cache; safe on a zeroed or non-spatial distribution. */
void ts_light_distribution_fini(ts_light_distribution *d);
/* Index of a light with probability *pmf for a shading point p (spatial: its voxel's
 * distribution; else p is unused); TS_NONE (pmf 0) when there are no lights. u is one 2-D
 * sample (uniform/power: ts_alias_table_sample, u.x the bin, u.y the coin; spatial: u.x
 * inverts the voxel's cdf). Thread-safe. */
uint32_t ts_light_distribution_sample(const ts_light_distribution *d, ts_vec3 p, ts_vec2 u, float *pmf);
/* Probability of selecting light i at p (0 if out of range). Thread-safe. */
float ts_light_distribution_pmf(const ts_light_distribution *d, ts_vec3 p, uint32_t i);
/* The same for a point p with shading normal n (zero: none; only bvh reads it): the
 * integrators' calls at surface vertices, the pmf at the same (p, n) as the sample. */
uint32_t ts_light_distribution_sample_at(const ts_light_distribution *d, ts_vec3 p, ts_vec3 n, ts_vec2 u, float *pmf);
float ts_light_distribution_pmf_at(const ts_light_distribution *d, ts_vec3 p, ts_vec3 n, uint32_t i);

#endif
