/* transform.h — affine/projective 4×4 transforms kept with their inverse, in double.
 *
 * Design note: transforms are built once at scene load, so they are stored in double
 * precision; applying them in double and rounding once to float is what lets the shape
 * code bound the error of a world-space hit point by a few ulps (see shape.h). Matrices
 * are row-major, points are column vectors: p' = M · p. Pure functions, thread-safe. */
#ifndef TS_TRANSFORM_H
#define TS_TRANSFORM_H

#include <stdbool.h>

#include "core/vecmath.h"

typedef struct ts_mat4 { double m[4][4]; } ts_mat4;

typedef struct ts_xform {
    ts_mat4 m;     /* object → world */
    ts_mat4 m_inv; /* world → object */
} ts_xform;

ts_mat4 ts_mat4_identity(void);
ts_mat4 ts_mat4_mul(const ts_mat4 *a, const ts_mat4 *b);
ts_mat4 ts_mat4_transpose(const ts_mat4 *a);
/* Inverse by Gauss–Jordan with full pivoting; false if (numerically) singular. */
bool ts_mat4_invert(const ts_mat4 *a, ts_mat4 *inv);

ts_xform ts_xform_identity(void);
/* From a matrix; false if it is singular. */
bool ts_xform_from_matrix(const ts_mat4 *m, ts_xform *out);
ts_xform ts_xform_translate(ts_dvec3 d);
ts_xform ts_xform_scale(ts_dvec3 s);
/* Rotation by angle_deg degrees about axis (normalised here; must be non-zero). */
ts_xform ts_xform_rotate(double angle_deg, ts_dvec3 axis);
/* Frame whose z axis is unit n and origin o: object (x,y,z) → o + x·s + y·t + z·n. */
ts_xform ts_xform_frame(ts_dvec3 o, ts_dvec3 n);
/* a ∘ b: apply b first, then a. */
ts_xform ts_xform_compose(const ts_xform *a, const ts_xform *b);
ts_xform ts_xform_inverse(const ts_xform *a);
/* True if the linear part has negative determinant (mirrors handedness). */
bool ts_xform_swaps_handedness(const ts_xform *a);
bool ts_xform_is_identity(const ts_xform *a);

ts_dvec3 ts_xform_point(const ts_xform *t, ts_dvec3 p);
ts_dvec3 ts_xform_vector(const ts_xform *t, ts_dvec3 v);
/* Normals transform by the inverse transpose; the result is not normalised. */
ts_dvec3 ts_xform_normal(const ts_xform *t, ts_dvec3 n);
ts_dvec3 ts_xform_point_inv(const ts_xform *t, ts_dvec3 p);
ts_dvec3 ts_xform_vector_inv(const ts_xform *t, ts_dvec3 v);

#endif
