/* animated_transform.h — pbrt's AnimatedTransform: a transform that moves between two
 * keyframes over a time interval (motion blur; docs/design.md §4, "motion").
 *
 * Design note: as pbrt-v3's (book §2.9.3–2.9.4), each keyframe matrix M is decomposed as
 * M = T·R·S — T the translation (M's last column), R a rotation found by polar
 * decomposition of M's linear part (the iteration R ← (R + R^-T)/2 until it settles) and
 * held as a unit quaternion, S = R^-1·M the rest (scale and shear, symmetric) — and the
 * transform at time t between the keyframes is T, S interpolated linearly and R by
 * spherical linear interpolation (Slerp) on the shorter arc (the end quaternion is
 * negated when the two are more than 90° apart on the sphere of quaternions, i.e. the
 * rotation by more than 180°). At or before the start time it is the start matrix itself,
 * at or after the end time the end matrix itself, and when the two matrices are equal it
 * is that matrix at every time: a keyframe pair that does not move is bit for bit the
 * static transform.
 *
 * **Decision — a mirroring keyframe** (negative determinant) is decomposed with R := −R
 * and S := −S, so R is a proper rotation and the mirror lives in S. pbrt-v3 makes a
 * quaternion of the improper polar factor, which is no rotation; its interpolated matrix
 * then jumps away from the keyframe as soon as t leaves it (a mirrored object or camera
 * during the shutter). The pbrt-v3 importer warns when it meets one.
 *
 * Everything in double; pure functions, thread-safe. */
#ifndef TS_ANIMATED_TRANSFORM_H
#define TS_ANIMATED_TRANSFORM_H

#include <stdbool.h>

#include "core/transform.h"
#include "core/vecmath.h"

/* A unit quaternion w + xi + yj + zk. */
typedef struct ts_quat {
    double x, y, z, w;
} ts_quat;

double ts_quat_dot(ts_quat a, ts_quat b);
/* The rotation matrix of unit q (the upper 3×3; the rest of the identity). */
ts_mat4 ts_quat_to_mat4(ts_quat q);
/* The unit quaternion of a proper rotation matrix (its upper 3×3). */
ts_quat ts_quat_from_mat4(const ts_mat4 *r);
/* pbrt's Slerp: from a (t = 0) to b (t = 1) at constant angular speed; normalised linear
 * interpolation where the two are within acos(0.9995) of each other. No sign flip: the
 * caller picks the arc. */
ts_quat ts_quat_slerp(double t, ts_quat a, ts_quat b);

/* M = T·R·S as above; false (nothing written) if M's linear part is singular or not finite
 * or M is projective. */
bool ts_mat4_decompose(const ts_mat4 *m, ts_dvec3 *t, ts_quat *r, ts_mat4 *s);

typedef struct ts_anim_xform {
    ts_xform start, end;          /* keyframes, object → world */
    double start_time, end_time;  /* start_time < end_time when animated */
    bool animated;                /* the matrices differ */
    bool has_rotation;            /* pbrt-v3's hasRotation: dot(r[0], r[1]) < 0.9995 */
    ts_dvec3 t[2];
    ts_quat r[2]; /* dot(r[0], r[1]) ≥ 0: the shorter arc */
    ts_mat4 s[2];
} ts_anim_xform;

/* Keyframes start at t0 and end at t1. Fails (false) when the matrices differ and
 * t1 ≤ t0 or either cannot be decomposed; equal matrices are a static transform whatever
 * the times. */
bool ts_anim_xform_init(ts_anim_xform *a, const ts_xform *start, double t0, const ts_xform *end, double t1);
/* A static transform (animated false) at every time. */
void ts_anim_xform_static(ts_anim_xform *a, const ts_xform *x);

/* The matrix at time (pbrt's AnimatedTransform::Interpolate). */
ts_mat4 ts_anim_xform_matrix(const ts_anim_xform *a, double time);
/* The same with its inverse: the keyframes' own xforms at and beyond the ends (so the
 * inverse is the keyframe's, bit for bit), else the interpolated matrix and its
 * Gauss–Jordan inverse; false if that is singular (a motion between a keyframe and its
 * mirror passes through a flat transform). */
bool ts_anim_xform_at(const ts_anim_xform *a, double time, ts_xform *out);

/* Bounds of b (object space) under the transform at every time of [start_time,
 * end_time]: the union of the keyframes' bounds when the rotations are equal (the motion
 * of each point is then linear in t); else the corners at 65 times, widened by the most a corner
 * can move in half a step (|ΔT| + θ·max(|S₀p|, |S₁p|) + |ΔS·p|, θ the rotation angle, per
 * unit of the interval) — conservative, where pbrt-v3 solves for the extrema. Rounded
 * outwards to float. */
ts_bounds3 ts_anim_xform_motion_bounds(const ts_anim_xform *a, ts_bounds3 b);

#endif
