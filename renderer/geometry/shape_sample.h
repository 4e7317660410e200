/* shape_sample.h — sampling points on shapes, by area and by solid angle, with pdfs.
 *
 * Design note (pbrt-v3 §14.2.2, pbrt-v4 §6.5): an area light samples a point on its shape
 * as seen from a reference point. Every shape can be sampled uniformly by area (sphere,
 * cylinder and disk in object space, then mapped to world with the exact area Jacobian
 * of to_world, so non-uniform scales stay unbiased; triangles by uniform barycentrics)
 * and its density converted to solid angle, p_ω = p_A · r² / |cos θ_o|. Better strategies
 * where they exist: the sphere samples the cone of directions it subtends from outside
 * (stable for tiny spheres through the small-angle form of 1 − cos θ_max), and triangles
 * may use Arvo's uniform spherical-triangle sampling (behind ts_triangle_sampling).
 * Two triangles of a mesh that form a rectangle (ts_shape_triangles_rectangle) can be one
 * emitter, sampled uniformly in the solid angle of the whole rectangle by Ureña, Fajardo
 * and King's area-preserving parametrisation of spherical rectangles (2013), under the
 * same ts_triangle_sampling policy and limits as a triangle (AUTO's size test takes half
 * the rectangle's area: where its triangles would have been sampled spherically).
 *
 * Densities are those of the FIRST surface point along a direction: ts_shape_pdf_solid_
 * angle(ref, wi) intersects the shape and evaluates the density of the sampler at the
 * nearest hit; 0 if wi misses. A sampled point that is not the first hit along its
 * direction (the far side of an ellipsoid or tube) is still returned — for a one-sided
 * emitter it faces away, and the integrator's shadow ray rejects it in any case.
 *
 * A reference point on the plane of a disk or triangle (within its error bound) sees
 * the shape edge-on: no sample, pdf 0, so a coplanar receiver gets exactly no light.
 *
 * ts_shape_sample_info holds what ts_shape_sample_info_init precomputes once per shape
 * (or triangle); everything else is pure, allocation-free and thread-safe. */
#ifndef TS_SHAPE_SAMPLE_H
#define TS_SHAPE_SAMPLE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "core/vecmath.h"
#include "geometry/interaction.h"
#include "geometry/shape.h"

/* How triangles are sampled from a reference point. AUTO (the zero value): spherical when
 * the solid angle is between 3e-4 sr (below it the triangle is small and area sampling is
 * as good and cheaper) and 6.22 sr (near a hemisphere, where Arvo's construction loses
 * precision), area sampling otherwise — pbrt-v4's thresholds. */
typedef enum ts_triangle_sampling {
    TS_TRIANGLE_SAMPLING_AUTO = 0,
    TS_TRIANGLE_SAMPLING_AREA,
    TS_TRIANGLE_SAMPLING_SPHERICAL,
} ts_triangle_sampling;

typedef struct ts_shape_sample_info {
    double area;              /* world-space area (mesh: of triangle prim); 0 for degenerate */
    bool similarity;          /* to_world = uniform scale · rotation (+ translation) */
    ts_dvec3 center;          /* sphere: world centre */
    double radius;            /* sphere: world radius when similarity */
    double det_abs;           /* |det| of to_world's linear part */
    ts_triangle_sampling triangle_mode;
    ts_dvec3 tri_p[3];        /* mesh: triangle prim's vertices (the float positions, in double) */
    ts_dvec3 tri_n;           /* mesh: its unit normal, normalize((p1 − p0) × (p2 − p0)) in double */
    float tri_pdf_area;       /* mesh: (float)(1 / area) */
    /* Rectangle of two triangles (ts_shape_sample_info_init_rect): tri_p[0] is its corner c,
     * tri_p[1] = c + rect_x·rect_w, tri_p[2] = c + rect_y·rect_h (triangle rect_prim[0]
     * exactly), tri_n the triangles' front normal; area = rect_w·rect_h. */
    bool rect;
    uint32_t rect_prim[2];    /* the two triangles */
    ts_dvec3 rect_x, rect_y;  /* orthonormal edge directions in the rectangle's plane */
    double rect_w, rect_h;    /* edge lengths along rect_x, rect_y */
    ts_vec3 rect_defect;      /* |fourth corner of the mesh − c − w·x − h·y| per component, added to p_error */
} ts_shape_sample_info;

/* A point on a shape: world position with its error bound, unit normal on the shape's
 * front side (docs/design.md §4), and its density (per area or per solid angle, as named by
 * the function that produced it). */
typedef struct ts_shape_point {
    ts_vec3 p, p_error, n;
    float pdf;
} ts_shape_point;

/* Precomputes area and sampling data of shape s (triangle prim for meshes). For spheres
 * under a non-uniform scale the area is integrated numerically (relative error < 1e-5).
 * TS_ERR_INVALID for a prim out of range. Not hot-path. The sampling and pdf functions
 * below take the info of the same shape and prim (a triangle's vertices and normal are
 * read from it). */
ts_status ts_shape_sample_info_init(const ts_shape *s, uint32_t prim, ts_triangle_sampling triangle_mode,
                                    ts_shape_sample_info *info, ts_error *err);

/* Whether triangles a and b of mesh s form one rectangle: they share an edge (two vertex
 * positions, bit for bit), which is the rectangle's diagonal, face the same way, and their
 * other vertices o_a, o_b complete a parallelogram with a right angle: with s0, s1 the
 * shared vertices, M the largest |coordinate| of the four and D = o_a + o_b − s0 − s1,
 * max|D_k| ≤ 2^-21·M (each of the four float vertices is within 2^-24·M of an exact
 * parallelogram's, 2^-22·M for the sum, and twice that for a transform applied in float)
 * and |D| ≤ 2^-16 of the shorter edge, and the edges at o_a meet at a cosine of at most
 * 2^-20. The rectangle sampled (corner o_a, edges towards s0 and s1, the second made
 * orthogonal to the first) then differs from the two triangles by a fraction of its area
 * of at most |D|/min edge + 2^-20 < 1.6e-5, the bias bound of treating them as one (the
 * exact rectangles of the shipped scenes have D = 0 and cosine 0). False for anything
 * else, degenerate triangles included. Not hot-path. */
bool ts_shape_triangles_rectangle(const ts_shape *s, uint32_t a, uint32_t b);
/* Like ts_shape_sample_info_init for the rectangle of triangles a and b (a first: the
 * corner and the front side are its); TS_ERR_INVALID if ts_shape_triangles_rectangle is
 * false. */
ts_status ts_shape_sample_info_init_rect(const ts_shape *s, uint32_t a, uint32_t b,
                                         ts_triangle_sampling triangle_mode, ts_shape_sample_info *info,
                                         ts_error *err);

/* Uniform-by-area sample; pdf per unit world area. False if the shape has no area. */
bool ts_shape_sample_area(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info, ts_vec2 u,
                          ts_shape_point *out);
/* Density per unit area of ts_shape_sample_area at point p with front normal n on the shape. */
float ts_shape_pdf_area(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info, ts_vec3 p);

/* Sample as seen from ref (ref->p, ref->p_error used); pdf per unit solid angle at ref.
 * False (and no light) when no valid direction results: ref on the shape's plane, on the
 * sampled point itself, or the shape degenerate. */
bool ts_shape_sample_solid_angle(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info,
                                 const ts_interaction *ref, ts_vec2 u, ts_shape_point *out);
/* Density per solid angle with which ts_shape_sample_solid_angle produces the first point
 * of the shape along the ray (ref->p, wi); 0 if it misses. wi need not be unit. */
float ts_shape_pdf_solid_angle(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info,
                               const ts_interaction *ref, ts_vec3 wi);
/* The same density when the caller already knows the point p_hit of the shape hit along
 * wi (e.g. from the accelerator): no second intersection. */
float ts_shape_pdf_solid_angle_at(const ts_shape *s, uint32_t prim, const ts_shape_sample_info *info,
                                  const ts_interaction *ref, ts_vec3 p_hit);

/* Nearest hit of the ray (o, d) with the shape for t in (tmin, tmax), in double precision,
 * without any offsetting: *t, and the front-side unit normal there if n is not NULL.
 * Meshes test only triangle prim. */
bool ts_shape_sample_intersect(const ts_shape *s, uint32_t prim, ts_vec3 o, ts_vec3 d, double tmin, double tmax,
                               double *t, ts_vec3 *n);

/* Solid angle (sr) that triangle (a, b, c) subtends at p (Van Oosterom & Strackee). */
double ts_spherical_triangle_area(ts_dvec3 a, ts_dvec3 b, ts_dvec3 c, ts_dvec3 p);

/* Solid angle (sr) that the rectangle of info (init_rect) subtends at p, as the spherical
 * rectangle sampler computes it (the sum of its four angles − 2π); 0 on its plane. */
double ts_spherical_rectangle_area(const ts_shape_sample_info *info, ts_dvec3 p);
/* Ureña et al.'s map of u ∈ [0,1)² onto the rectangle of info as seen from p: a point on the
 * rectangle whose direction from p is uniform in its solid angle (*omega, as above). False
 * where the solid angle is 0 or the set-up degenerates (p on the plane or a corner). */
bool ts_spherical_rectangle_sample(const ts_shape_sample_info *info, ts_dvec3 p, ts_vec2 u, ts_dvec3 *p_rect,
                                   double *omega);

#endif
