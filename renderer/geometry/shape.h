/* shape.h — the shapes of scene format v1 and their exact intersection.
 *
 * Design note: triangle meshes go to Embree as native triangles (vertices pre-transformed
 * to world space); spheres, disks and cylinders are Embree user geometry whose intersect
 * callbacks run the analytic test here. Analytic tests work in object space in double
 * precision: the float ray is transformed with the double inverse transform, the root is
 * found in double and the hit reprojected onto the surface, so the world-space point,
 * rounded once to float, is within about one ulp of the exact hit and p_error bounds it
 * conservatively. The same routine rebuilds the full interaction after traversal; a
 * triangle hit's is evaluated in float from Embree's barycentrics (shape.c).
 *
 * Object spaces: sphere centred at the origin; disk in the plane z = 0 facing +z with
 * inner_radius ≤ r ≤ radius; cylinder an open tube around the z axis from z = 0 to
 * z = height facing outwards. to_world maps object to world (the scene's transform list
 * composed with the placement from center/normal/p0,p1). Triangles face along
 * (p1 − p0) × (p2 − p0) in world space.
 *
 * Partial quadrics (pbrt-v3's Sphere, Disk, Cylinder): with `partial` set, only the points
 * with φ = atan2(y, x) ∈ [0, phi_max] belong to the shape, and of a sphere only those with
 * z ∈ [z_min, z_max]; a ray whose nearer root falls outside tries the farther one. The
 * parameterisation is pbrt-v3's: u = φ/phi_max; sphere v = (θ − θ_min)/(θ_max − θ_min)
 * with θ_min = acos(z_min/r), θ_max = acos(z_max/r); disk v = (radius − r)/(radius −
 * inner_radius); cylinder v = z/height; ∂p/∂u = phi_max·(−y, x, 0), ∂p/∂v as pbrt-v3.
 * A whole shape (partial false, the zero value) is the same with phi_max = 2π, z_min =
 * −radius, z_max = radius, and takes none of the cut tests (pbrt-v3's zmin/zmax/phimax
 * defaults give exactly the whole shape, which the builder stores as not partial).
 * A cylinder's pbrt-v3 z range and a disk's height are the builder's to fold into
 * to_world (scene_builder.h), so here the tube always starts at z = 0 and the disk lies
 * in z = 0.
 *
 * Orientation (docs/design.md §4): the front side of an analytic shape is pbrt-v3's
 * normalize(∂p/∂u × ∂p/∂v) mapped by to_world's inverse transpose — outwards, or the
 * disk's +z — whatever to_world's handedness (pbrt-v3 flips the world cross product when
 * the transform swaps handedness, which comes to the same); reverse_orientation flips it
 * (pbrt-v3's ReverseOrientation). Meshes carry their orientation in their winding (the
 * builder reverses the winding of a reversed or mirrored mesh).
 *
 * Alpha cut-outs (pbrt-v3's TriangleMesh alphaMask / shadowAlphaMask; docs/design.md §4):
 * a mesh may carry a float texture `alpha` and one `shadow_alpha`. The accelerator
 * (geometry/accel.c) evaluates them in its Embree filters at the hit's point and (u, v)
 * (ts_shape_triangle_point_uv at Embree's barycentrics: the interaction's own values) with no footprint, and a hit
 * where alpha is exactly 0 is no hit for any ray; one where shadow_alpha is 0 is none for
 * shadow rays (pbrt-v3's Triangle::Intersect and IntersectP). Analytic shapes have none
 * (pbrt-v3 reads alpha on trianglemesh and plymesh only).
 *
 * Shapes are immutable after scene build and read by all threads. */
#ifndef TS_SHAPE_H
#define TS_SHAPE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/transform.h"
#include "core/vecmath.h"
#include "geometry/curve.h"
#include "geometry/interaction.h"

struct ts_texture;

typedef enum ts_shape_type {
    TS_SHAPE_SPHERE,
    TS_SHAPE_DISK,
    TS_SHAPE_CYLINDER,
    TS_SHAPE_MESH,
    TS_SHAPE_CURVE, /* pbrt-v3's curve: cubic Bézier segments (geometry/curve.h) */
} ts_shape_type;

typedef struct ts_mesh {
    uint32_t n_vertices, n_triangles;
    const float *p;        /* 3·n_vertices, world space */
    const float *n;        /* 3·n_vertices world-space shading normals (lengths weight them), or NULL */
    const float *uv;       /* 2·n_vertices, or NULL */
    const uint32_t *index; /* 3·n_triangles, validated < n_vertices */
} ts_mesh;

typedef struct ts_shape {
    ts_shape_type type;
    uint32_t material;    /* index into the scene's materials; TS_NONE: no surface (the shape only
                             bounds a medium: rays pass through it, pbrt-v3's Material "none") */
    /* pbrt-v3's MediumInterface where it is a transition (inside ≠ outside): a ray leaving
     * the shape towards its front side (dot(w, n) > 0) is in medium_outside, else in
     * medium_inside (indices into the scene's media, TS_NONE: vacuum). false (the zero
     * value): crossing the shape keeps the ray's medium. */
    bool medium_transition;
    uint32_t medium_inside, medium_outside;
    bool emissive;        /* emission set and non-black: a diffuse area light */
    bool two_sided;       /* emits on both sides */
    ts_rgb emission;      /* radiance leaving the front side (both sides if two_sided) */
    uint32_t light_samples; /* emitters: samples per light under direct's strategy all (0: the integrator's) */
    uint32_t first_light; /* index of this shape's first area light (meshes: + triangle) */
    const uint32_t *prim_light; /* emissive meshes: each triangle's area light, in the scene's arena (two
                                   triangles of a rectangle share one); NULL: first_light + triangle */
    ts_xform to_world;    /* object → world (identity for meshes) */
    bool reverse_orientation; /* analytic shapes: the front side is the inside (disk: −z) */
    bool partial;         /* analytic shapes: cut by phi_max (and a sphere by z_min, z_max) */
    double phi_max;       /* partial: radians in (0, 2π] */
    /* Part of object definition `object` (accel.h): in that object's space (a mesh's vertices
     * too), seen only through its instances; otherwise (false, the zero value) in the scene. */
    bool in_object;
    uint32_t object;
    /* Leave the interaction's dndu, dndv 0: the builder sets it in scenes without textures,
     * where nothing reads them (bump maps and ray differentials come with textures), so
     * their hits do not pay for them. */
    bool no_normal_derivatives;
    /* Meshes: the alpha cut-out textures (float textures owned by the scene; NULL, the zero
     * value: opaque, the filter's one test is not even installed). */
    const struct ts_texture *alpha, *shadow_alpha;
    union {
        /* z_min < z_max within [−radius, radius], theta_min = acos(z_min/radius) >
         * theta_max = acos(z_max/radius): read only when partial */
        struct { double radius, z_min, z_max, theta_min, theta_max; } sphere;
        struct { double radius, inner_radius; } disk;
        struct { double radius, height; } cylinder;
        ts_mesh mesh;
        ts_curve curve;
    };
} ts_shape;

/* World-space bounds of the whole shape (meshes: all triangles). */
ts_bounds3 ts_shape_bounds(const ts_shape *s);
/* World-space bounds of one triangle of a mesh. */
ts_bounds3 ts_shape_triangle_bounds(const ts_shape *s, uint32_t prim);

/* Analytic shapes: nearest hit with t in (0, tmax) of the world ray, in double precision
 * and conservative (a ray leaving the surface from a spawned origin does not report the
 * point it left). Returns false on a miss. */
bool ts_shape_intersect(const ts_shape *s, const ts_ray *ray, float tmax, float *t_hit);

/* The full interaction of a hit found by traversal: shape s, primitive prim, parameter t
 * along ray (triangles: recomputed in double from the ray — the reference for tests and
 * tools; the accelerator's hits take ts_shape_triangle_interaction_cached, in float from
 * Embree's barycentrics).
 * Fills p, p_error, n, ns, dpdu, dpdv, dndu, dndv, uv, wo, t, shape index (shape_index),
 * prim, mesh_normals. ∂ns/∂u, ∂ns/∂v are pbrt-v3's: spheres and cylinders by the
 * Weingarten equations of their parameterisation (in object space; then the derivative
 * of the world normal, so a scaled shape's are its world curvature's), disks 0; triangles
 * of a mesh with normals the derivatives of the interpolated (unnormalised) vertex normal
 * in (u, v) (0 when the uvs are degenerate), without normals 0. Each is the derivative of
 * ns as it faces: turned with it by ReverseOrientation or a flipped vertex normal. */
void ts_shape_interaction(const ts_shape *s, uint32_t shape_index, uint32_t prim, const ts_ray *ray, float t,
                          ts_interaction *si);

/* Ray-independent data of one mesh triangle that ts_shape_interaction and
 * ts_shape_triangle_ahead otherwise recompute at every hit (three square roots, the
 * normal's division, the ∂p/∂u solve). The accelerator keeps one per triangle; the
 * functions taking it return bit for bit what the ones without it return. */
typedef struct ts_tri_cache {
    double n_len, e1_len, e2_len; /* |(p1 − p0) × (p2 − p0)|, |p1 − p0|, |p2 − p0| (double) */
    double inv_sin;               /* e1_len·e2_len / n_len, ∞ for a degenerate triangle */
    ts_vec3 n;                    /* the interaction's n */
    ts_vec3 dpdu, dpdv;           /* the interaction's dpdu, dpdv */
} ts_tri_cache;

/* Fills c for triangle prim of mesh s. */
void ts_shape_triangle_cache_init(const ts_shape *s, uint32_t prim, ts_tri_cache *c);

/* The interaction of a hit that Embree found on triangle prim of mesh s, with its cache (c
 * from ts_shape_triangle_cache_init of the same s and prim), Embree's t and its
 * barycentrics b1, b2 of p1 and p2 (RTCHit's u, v): what ts_shape_interaction fills, in
 * float from the barycentrics (shape.c, "the accelerator's hits"): p within p_error of the
 * triangle's plane (not of the exact ray's hit along it), n, dpdu, dpdv from the cache, ns
 * and uv interpolated in float, ∂n/∂u, ∂n/∂v and wo as ts_shape_interaction. */
void ts_shape_triangle_interaction_cached(const ts_shape *s, const ts_tri_cache *c, uint32_t shape_index,
                                          uint32_t prim, const ts_ray *ray, float t, float b1, float b2,
                                          ts_interaction *si);

/* ts_shape_triangle_ahead with the triangle's cache: the same answer. */
bool ts_shape_triangle_ahead_cached(const ts_shape *s, const ts_tri_cache *c, uint32_t prim, const ts_ray *ray);

/* The point p and (u, v) at barycentrics b1, b2 (of p1, p2) of triangle prim of mesh s:
 * the p and uv that ts_shape_triangle_interaction_cached fills for that hit, bit for bit,
 * without the rest. Embree's filters test the alpha textures there. */
void ts_shape_triangle_point_uv(const ts_shape *s, uint32_t prim, float b1, float b2, ts_vec3 *p, ts_vec2 *uv);

/* Surface area in world space (meshes: of one triangle prim; other shapes ignore prim). */
double ts_shape_area(const ts_shape *s, uint32_t prim);
/* pbrt-v3's Area() of an analytic shape in object space: a sphere φ_max·r·(z_max − z_min),
 * a disk φ_max/2·(r² − r_i²), a cylinder φ_max·r·height (φ_max = 2π, z = ±r when whole);
 * 0 for meshes. */
double ts_shape_object_area(const ts_shape *s);
/* True if to_world's linear part is a rotation times a uniform scale (to 1e-9 relative). */
bool ts_shape_is_similarity(const ts_shape *s);

/* Ray leaving si in direction d (skips si's own triangle when si is on a mesh). */
ts_ray ts_spawn_ray(const ts_interaction *si, const ts_shape *shapes, ts_vec3 d);
/* Shadow ray from si towards the point p_to (with its own error p_to_error and normal n_to,
 * both offset), stopping TS_SHADOW_EPSILON short of it. */
ts_ray ts_spawn_ray_to(const ts_interaction *si, const ts_shape *shapes, ts_vec3 p_to, ts_vec3 p_to_error,
                       ts_vec3 n_to);

/* One triangle prim of a mesh: nearest hit with t in (0, tmax), computed in double
 * precision (Möller–Trumbore on the float vertices) and conservative like
 * ts_shape_intersect: a ray whose origin lies on the triangle's plane within double
 * round-off does not hit it. The ray's skip ids are not consulted. */
bool ts_shape_triangle_intersect(const ts_shape *s, uint32_t prim, const ts_ray *ray, float tmax, float *t_hit);
/* True if the ray crosses the plane of triangle prim at a t > 0 that double precision can
 * tell from 0 (false for a ray leaving that plane, lying in it or moving away from it).
 * The accelerator's check, for rays leaving a mesh, that a hit of Embree's float test is
 * not the surface the ray leaves (e.g. the coplanar neighbour of its triangle). */
bool ts_shape_triangle_ahead(const ts_shape *s, uint32_t prim, const ts_ray *ray);

#endif
