/* curve.h — pbrt-v3's curve shape (src/shapes/curve.{h,cpp}): its control points, its
 * hit quantities, and how it is handed to Embree.
 *
 * Design note. pbrt-v3 turns a "curve" of any basis (bezier, bspline) and degree (2, 3)
 * into cubic Bézier segments (degree 2 elevated exactly, uniform B-splines blossomed) and
 * intersects each as a ray-facing strip: the points within width/2 of the curve, measured
 * in the plane perpendicular to the ray, cut square at the segment's ends. The width is
 * linear along each segment (width0 → width1 over the whole curve, sampled at the
 * segment ends). tessera gives the same segments to Embree as
 * RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE, Embree's ray-facing curve, whose radius (the fourth
 * control-point coordinate) is interpolated with the Bézier basis: radii r_i = w(i/3)/2
 * reproduce a linear width exactly. Embree tests `tessellation` (4, 8 or at most 16) straight
 * ray-facing quads per primitive, so a segment that bends sharply for its width is cut into
 * 2^k exact pieces first (blossoms, as pbrt-v3's splitdepth pieces) until 16 quads meet the
 * flatness TS_CURVE_FLATNESS; the departure left is measured in docs/design.md (Decisions,
 * curves).
 *
 * The three kinds (pbrt-v3's CurveType):
 *   - flat: the strip; ∂p/∂v = w·normalize(d × ∂p/∂u) across it (d the ray's unit
 *     direction), n = normalize(∂p/∂u × ∂p/∂v) — facing away from the ray, as pbrt-v3's.
 *   - cylinder: the same strip; ∂p/∂v turned about ∂p/∂u by −θ, θ = 180°·(v − 1/2), so the
 *     normal sweeps a half turn across it: a tube's look, not a tube (pbrt-v3 bends the
 *     geometric normal too, and so does tessera).
 *   - ribbon: the strip whose width seen along d is w·|n_u·d|, n_u pbrt-v3's slerp of the
 *     segment's two end normals (its angle clamped to [0, 90°] as pbrt-v3 clamps the dot
 *     product; equal normals: that normal, where pbrt-v3's 1/sin 0 gives NaN); Embree's
 *     flat curve at the full width with a filter that keeps only hits within it;
 *     ∂p/∂v = w_hit·normalize(n_u × ∂p/∂u).
 * (u, v): u is pbrt-v3's, the parameter within the hit's Bézier segment (each segment of
 * a multi-segment curve runs 0 → 1, as pbrt-v3's per-segment CurveCommon); v runs 0 → 1
 * across the width (1/2 on the curve). ∂n/∂u = ∂n/∂v = 0, the shading normal is n, the
 * point error 2·w_hit per axis (pbrt-v3's) plus the float ray's rounding. Under a mirroring
 * transform ∂p/∂v is negated (pbrt-v3 builds it in object space, tessera in world space).
 *
 * Curves are stored in world space (their object's space within an object); their width
 * is scaled by the cube root of the transform's |det| (exact for similarities; a
 * non-uniform scale is warned by the front ends). Pure functions, thread-safe. */
#ifndef TS_CURVE_H
#define TS_CURVE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/vecmath.h"
#include "geometry/interaction.h"

/* pbrt-v3's three curve kinds (its CurveType): ray-facing strips; a ribbon's width seen
 * along a ray is scaled by |n·d| for its normal n slerped along the segment; a cylinder's
 * normal is bent across the strip (geometry/curve.h). */
typedef enum ts_curve_type { TS_CURVE_FLAT, TS_CURVE_RIBBON, TS_CURVE_CYLINDER } ts_curve_type;

/* A curve: pbrt-v3's cubic Bézier segments (what the builder made of any basis and
 * degree), each cut into 2^k pieces where it bends sharply for its width (curve.h), in
 * world space, or in its object's space when the shape is part of an object. Piece i is
 * Embree's primitive i. */
typedef struct ts_curve {
    ts_curve_type type;
    uint32_t n_segments;   /* pbrt-v3's segments */
    uint32_t n_pieces;     /* Embree's primitives */
    const float *cp;       /* 16·n_pieces: each piece's 4 Bézier control points as x, y, z, radius
                              (half the width, linear along it: Embree's float4 layout) */
    const float *u_range;  /* 2·n_pieces: the piece's [u0, u1] within its segment (pbrt-v3's u) */
    const uint32_t *segment; /* n_pieces: the piece's segment */
    const float *n;        /* ribbon: 3·(n_segments + 1) unit normals at the segments' ends; else NULL */
    bool mirrored;         /* the placing transform swapped handedness (curve.h: dpdv's sign) */
    uint32_t tessellation; /* ray-facing pieces per piece Embree tests (geometry/curve.h) */
} ts_curve;

typedef enum ts_curve_basis { TS_CURVE_BEZIER, TS_CURVE_BSPLINE } ts_curve_basis;

/* The flatness tessera asks of Embree's straight pieces, as a fraction of the width.
 * pbrt-v3 refines its pieces to width/20 but then measures the distance to the curve
 * itself at the piece's nearest parameter, which is near exact; Embree measures it to
 * the straight piece, so its chordal error shows at the strip's edges directly: width/200
 * keeps it under 0.5% of the width (measured against pbrt-v3's intersection in
 * tests/test_curve.c). */
#define TS_CURVE_FLATNESS (1.0 / 200)

/* Embree's largest tessellation rate for flat curves (higher rates give the same hits). */
#define TS_CURVE_MAX_TESSELLATION 16u

/* pbrt-v3's segment count of n_points control points (degree 2 or 3): bezier needs
 * degree + 1 + k·degree points (k ≥ 0) for (n − 1)/degree segments, bspline at least
 * degree + 1 for n − degree segments. false when pbrt-v3 refuses the count (it also takes
 * a single Bézier point, as 0 segments: *n_segments 0 and true). */
bool ts_curve_segment_count(ts_curve_basis basis, int degree, uint64_t n_points, uint32_t *n_segments);

/* Segment seg's cubic Bézier control points from P (3·n_points floats), as pbrt-v3's
 * CreateCurveShape computes them in float. seg < the segment count. */
void ts_curve_bezier_segment(ts_curve_basis basis, int degree, const float *P, uint32_t seg, float out[4][3]);

/* pbrt-v3's splitdepth, as tessera needs it: the pieces (a power of two, at most
 * TS_CURVE_MAX_SPLIT) a segment with control points cp and largest width is cut into so
 * that each needs at most TS_CURVE_MAX_TESSELLATION straight pieces for the flatness
 * width·TS_CURVE_FLATNESS (pbrt-v3's refinement rule: √(√2·6·L0 / (8·flatness)) pieces, L0
 * the largest second difference of the control points). */
#define TS_CURVE_MAX_SPLIT 1024u
uint32_t ts_curve_split(const double cp[4][3], double width);

/* The cubic Bézier control points of the part [u0, u1] of the segment cp (blossoms, as
 * pbrt-v3's Curve pieces). */
void ts_curve_piece(const double cp[4][3], double u0, double u1, double out[4][3]);

/* Embree's tessellation rate for the curve: 4 (its default), 8 or 16, the least that gives
 * every piece that flatness. */
uint32_t ts_curve_tessellation(const ts_curve *c);

/* World bounds of the curve: its control points' box grown by the largest radius. */
ts_bounds3 ts_curve_bounds(const ts_curve *c);

/* pbrt-v3's Curve::Area: each segment's control-polygon length times its mean width. */
double ts_curve_area(const ts_curve *c);

/* pbrt-v3's ribbon normal of segment seg at u (its slerp of the end normals, not
 * renormalised). */
ts_dvec3 ts_curve_ribbon_normal(const ts_curve *c, uint32_t seg, double u);

/* Whether a hit that Embree's flat curve reports at (u, v) (v ∈ [−1, 1] across the full
 * width) on ribbon piece `piece` for a ray of direction d lies within pbrt-v3's ribbon
 * width: |v| ≤ |n_u·d| / |d|. */
bool ts_curve_ribbon_covers(const ts_curve *c, uint32_t piece, float u, float v, ts_vec3 d);

/* The interaction of a hit on piece seg of curve c (reverse_orientation: its shape's,
 * pbrt-v3's ReverseOrientation) at parameter t along ray, from
 * Embree's hit coordinates u (along the piece) and v (in [−1, 1] across the full width,
 * its sign pbrt-v3's edge function's): every field of ts_shape_interaction (uv.u the
 * segment's u, ∂p/∂u with respect to it, prim the piece), in c's space (the ray in that
 * space). */
void ts_curve_interaction(const ts_curve *c, bool reverse_orientation, uint32_t shape_index, uint32_t seg,
                          const ts_ray *ray, float t, float u, float v, ts_interaction *si);

/* ts_curve_interaction for a hit at t without Embree's (u, v) (tools and tests): u of the
 * curve point nearest the ray among 256 along the piece, refined, and v from the ray's
 * signed distance to it. */
void ts_curve_interaction_at(const ts_curve *c, bool reverse_orientation, uint32_t shape_index, uint32_t seg,
                             const ts_ray *ray, float t, ts_interaction *si);

#endif
