/* interaction.h — rays, surface interactions and robust ray spawning.
 *
 * Design note: a hit point carries a conservative per-component bound on its floating-
 * point error (p_error). A ray leaving the surface starts at p pushed along the geometric
 * normal just past that bound, then rounded away from the surface (pbrt-v3 §3.9.5), never
 * by a fixed epsilon, so scenes behave the same at any scale or distance from the origin.
 * Embree's float triangle test is not conservative, so a ray spawned from a triangle also
 * names that triangle (skip_shape, skip_prim) and the accelerator ignores it: a planar
 * triangle can never be hit again by a ray leaving it. All functions are pure. */
#ifndef TS_INTERACTION_H
#define TS_INTERACTION_H

#include <stdint.h>

#include "core/vecmath.h"

#define TS_NONE 0xffffffffu

typedef struct ts_ray {
    ts_vec3 o, d;        /* world space; d need not be unit */
    float tmax;          /* hits with t in (0, tmax) count */
    uint32_t skip_shape; /* TS_NONE, or the triangle this ray leaves (shape index) */
    uint32_t skip_prim;
    uint32_t skip_inst;  /* with skip_shape: 0 for a triangle of the scene itself, k + 1 for
                            one seen through object instance k (accel.h) */
    float time;          /* the scene time the ray samples (motion blur, accel.h): the camera
                            ray's, inherited by every ray spawned from its path; 0 without motion */
} ts_ray;

typedef struct ts_interaction {
    ts_vec3 p;         /* world-space hit point */
    ts_vec3 p_error;   /* |p − exact hit| ≤ p_error, per component (a triangle hit of the
                          accelerator: of a point of its plane, shape.c) */
    ts_vec3 n;         /* unit geometric normal on the shape's front side (docs/design.md §4) */
    ts_vec3 ns;        /* unit shading normal, in n's hemisphere */
    ts_vec3 dpdu, dpdv;
    ts_vec3 dndu, dndv; /* ∂ns/∂u, ∂ns/∂v, world space (pbrt-v3's shading.dndu, dndv; shape.h) */
    ts_vec2 uv;
    ts_vec3 wo;        /* unit direction back towards the ray origin */
    float t;           /* ray parameter of the hit */
    uint32_t shape;    /* index into the scene's shapes */
    uint32_t prim;     /* triangle index for meshes, 0 otherwise */
    uint32_t inst;     /* 0, or k + 1 when the hit is on a shape of object instance k (accel.h):
                          everything above is then in world space all the same */
    bool mesh_normals; /* ns interpolates a mesh's vertex normals: a bump map then uses pbrt-v3's
                          unit shading tangents (materials/material.h, ts_material_bump) */
    float time;        /* the time of the ray that found it (ts_ray.time): rays spawned here keep it */
} ts_interaction;

static inline ts_vec3 ts_ray_at(const ts_ray *r, float t) { return ts_vec3_add(r->o, ts_vec3_scale(r->d, t)); }

static inline ts_ray ts_ray_make(ts_vec3 o, ts_vec3 d, float tmax)
{
    ts_ray r = {o, d, tmax, TS_NONE, TS_NONE, 0, 0};
    return r;
}

/* p moved along n, to w's side, by the error bound, then rounded away (pbrt-v3's
 * OffsetRayOrigin). */
static inline ts_vec3 ts_offset_ray_origin(ts_vec3 p, ts_vec3 p_error, ts_vec3 n, ts_vec3 w)
{
    float d = ts_vec3_dot(ts_vec3_abs(n), p_error);
    ts_vec3 offset = ts_vec3_scale(n, d);
    if (ts_vec3_dot(w, n) < 0) offset = ts_vec3_neg(offset);
    ts_vec3 po = ts_vec3_add(p, offset);
    if (offset.x > 0) po.x = ts_next_float_up(po.x);
    else if (offset.x < 0) po.x = ts_next_float_down(po.x);
    if (offset.y > 0) po.y = ts_next_float_up(po.y);
    else if (offset.y < 0) po.y = ts_next_float_down(po.y);
    if (offset.z > 0) po.z = ts_next_float_up(po.z);
    else if (offset.z < 0) po.z = ts_next_float_down(po.z);
    return po;
}

/* Set by the accelerator for shapes that are triangle meshes (see accel.h). */
static inline ts_ray ts_spawn_ray_ex(ts_vec3 p, ts_vec3 p_error, ts_vec3 n, ts_vec3 d, uint32_t skip_shape,
                                     uint32_t skip_prim, uint32_t skip_inst)
{
    ts_ray r = {ts_offset_ray_origin(p, p_error, n, d), d, INFINITY, skip_shape, skip_prim, skip_inst, 0};
    return r;
}

/* Shadow rays stop this fraction short of their target (pbrt's ShadowEpsilon), relative to
 * the segment, after both ends have been offset by their error bounds. */
#define TS_SHADOW_EPSILON 1e-4f

#endif
