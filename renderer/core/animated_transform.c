/* animated_transform.c — pbrt's AnimatedTransform in double; see animated_transform.h. */
#include "core/animated_transform.h"

#include <math.h>
#include <string.h>

double ts_quat_dot(ts_quat a, ts_quat b) { return a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w; }

static ts_quat quat_normalize(ts_quat q)
{
    double l = sqrt(ts_quat_dot(q, q));
    return (ts_quat){q.x / l, q.y / l, q.z / l, q.w / l};
}

ts_mat4 ts_quat_to_mat4(ts_quat q)
{
    double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    double wx = q.x * q.w, wy = q.y * q.w, wz = q.z * q.w;
    ts_mat4 m = ts_mat4_identity();
    m.m[0][0] = 1 - 2 * (yy + zz);
    m.m[0][1] = 2 * (xy - wz);
    m.m[0][2] = 2 * (xz + wy);
    m.m[1][0] = 2 * (xy + wz);
    m.m[1][1] = 1 - 2 * (xx + zz);
    m.m[1][2] = 2 * (yz - wx);
    m.m[2][0] = 2 * (xz - wy);
    m.m[2][1] = 2 * (yz + wx);
    m.m[2][2] = 1 - 2 * (xx + yy);
    return m;
}

ts_quat ts_quat_from_mat4(const ts_mat4 *r)
{
    const double(*m)[4] = r->m;
    double trace = m[0][0] + m[1][1] + m[2][2];
    ts_quat q;
    if (trace > 0) {
        double s = sqrt(trace + 1);
        q.w = s / 2;
        s = 0.5 / s;
        q.x = (m[2][1] - m[1][2]) * s;
        q.y = (m[0][2] - m[2][0]) * s;
        q.z = (m[1][0] - m[0][1]) * s;
    } else {
        /* The largest diagonal element's axis first (pbrt's branch). */
        static const int next[3] = {1, 2, 0};
        int i = 0;
        if (m[1][1] > m[0][0]) i = 1;
        if (m[2][2] > m[i][i]) i = 2;
        int j = next[i], k = next[j];
        double v[3];
        double s = sqrt((m[i][i] - (m[j][j] + m[k][k])) + 1);
        v[i] = s * 0.5;
        if (s != 0) s = 0.5 / s;
        q.w = (m[k][j] - m[j][k]) * s;
        v[j] = (m[j][i] + m[i][j]) * s;
        v[k] = (m[k][i] + m[i][k]) * s;
        q.x = v[0], q.y = v[1], q.z = v[2];
    }
    return quat_normalize(q);
}

ts_quat ts_quat_slerp(double t, ts_quat a, ts_quat b)
{
    double c = ts_quat_dot(a, b);
    if (c > 0.9995)
        return quat_normalize((ts_quat){(1 - t) * a.x + t * b.x, (1 - t) * a.y + t * b.y, (1 - t) * a.z + t * b.z,
                                        (1 - t) * a.w + t * b.w});
    double theta = acos(c < -1 ? -1 : c > 1 ? 1 : c), thetap = theta * t;
    ts_quat perp = quat_normalize((ts_quat){b.x - a.x * c, b.y - a.y * c, b.z - a.z * c, b.w - a.w * c});
    double ct = cos(thetap), st = sin(thetap);
    return (ts_quat){a.x * ct + perp.x * st, a.y * ct + perp.y * st, a.z * ct + perp.z * st,
                     a.w * ct + perp.w * st};
}

static double det3(const ts_mat4 *a)
{
    const double(*m)[4] = a->m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

bool ts_mat4_decompose(const ts_mat4 *m, ts_dvec3 *t, ts_quat *r, ts_mat4 *s)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(m->m[i][j])) return false;
    if (m->m[3][0] != 0 || m->m[3][1] != 0 || m->m[3][2] != 0 || m->m[3][3] != 1) return false;
    ts_mat4 lin = *m;
    for (int i = 0; i < 3; i++) lin.m[i][3] = lin.m[3][i] = 0;
    lin.m[3][3] = 1;
    double det = det3(&lin);
    if (!(det != 0) || !isfinite(det)) return false;
    /* Polar decomposition: R ← (R + R^-T)/2 converges (quadratically) to the orthogonal
     * factor; pbrt-v3 stops at a change of 1e-4 in float, here at 1e-15 in double. */
    ts_mat4 R = lin;
    for (int it = 0; it < 100; it++) {
        ts_mat4 rt = ts_mat4_transpose(&R), rit;
        if (!ts_mat4_invert(&rt, &rit)) return false;
        ts_mat4 next = R;
        double norm = 0;
        for (int i = 0; i < 3; i++) {
            double n = 0;
            for (int j = 0; j < 3; j++) {
                next.m[i][j] = 0.5 * (R.m[i][j] + rit.m[i][j]);
                n += fabs(R.m[i][j] - next.m[i][j]);
            }
            norm = fmax(norm, n);
        }
        R = next;
        if (norm <= 1e-15) break;
    }
    if (det < 0) /* Decision (header): the mirror goes into S, R stays a rotation */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) R.m[i][j] = -R.m[i][j];
    /* S = R^-1·M = Rᵀ·M (R orthogonal to rounding; the transpose keeps R·S = M to it). */
    ts_mat4 Rt = ts_mat4_transpose(&R);
    *s = ts_mat4_mul(&Rt, &lin);
    *r = ts_quat_from_mat4(&R);
    *t = (ts_dvec3){m->m[0][3], m->m[1][3], m->m[2][3]};
    return true;
}

void ts_anim_xform_static(ts_anim_xform *a, const ts_xform *x)
{
    memset(a, 0, sizeof *a);
    a->start = a->end = *x;
    a->start_time = 0;
    a->end_time = 1;
}

bool ts_anim_xform_init(ts_anim_xform *a, const ts_xform *start, double t0, const ts_xform *end, double t1)
{
    ts_anim_xform_static(a, start);
    a->end = *end;
    a->start_time = t0;
    a->end_time = t1;
    a->animated = memcmp(&start->m, &end->m, sizeof start->m) != 0;
    if (!a->animated) return true;
    if (!(t1 > t0) || !isfinite(t0) || !isfinite(t1)) return false;
    if (!ts_mat4_decompose(&start->m, &a->t[0], &a->r[0], &a->s[0]) ||
        !ts_mat4_decompose(&end->m, &a->t[1], &a->r[1], &a->s[1]))
        return false;
    if (ts_quat_dot(a->r[0], a->r[1]) < 0) /* the shorter arc (pbrt-v3's constructor) */
        a->r[1] = (ts_quat){-a->r[1].x, -a->r[1].y, -a->r[1].z, -a->r[1].w};
    a->has_rotation = ts_quat_dot(a->r[0], a->r[1]) < 0.9995;
    return true;
}

/* The interpolated matrix at dt in (0, 1) of the interval. */
static ts_mat4 interpolate(const ts_anim_xform *a, double dt)
{
    ts_dvec3 tr = {(1 - dt) * a->t[0].x + dt * a->t[1].x, (1 - dt) * a->t[0].y + dt * a->t[1].y,
                   (1 - dt) * a->t[0].z + dt * a->t[1].z};
    ts_mat4 r = ts_quat_to_mat4(ts_quat_slerp(dt, a->r[0], a->r[1]));
    ts_mat4 s = ts_mat4_identity();
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) s.m[i][j] = (1 - dt) * a->s[0].m[i][j] + dt * a->s[1].m[i][j];
    ts_mat4 m = ts_mat4_mul(&r, &s);
    m.m[0][3] = tr.x, m.m[1][3] = tr.y, m.m[2][3] = tr.z;
    return m;
}

ts_mat4 ts_anim_xform_matrix(const ts_anim_xform *a, double time)
{
    if (!a->animated || time <= a->start_time) return a->start.m;
    if (time >= a->end_time) return a->end.m;
    return interpolate(a, (time - a->start_time) / (a->end_time - a->start_time));
}

bool ts_anim_xform_at(const ts_anim_xform *a, double time, ts_xform *out)
{
    if (!a->animated || time <= a->start_time) {
        *out = a->start;
        return true;
    }
    if (time >= a->end_time) {
        *out = a->end;
        return true;
    }
    ts_mat4 m = interpolate(a, (time - a->start_time) / (a->end_time - a->start_time));
    return ts_xform_from_matrix(&m, out);
}

static ts_dvec3 mat_point(const ts_mat4 *m, ts_dvec3 p)
{
    return (ts_dvec3){m->m[0][0] * p.x + m->m[0][1] * p.y + m->m[0][2] * p.z + m->m[0][3],
                      m->m[1][0] * p.x + m->m[1][1] * p.y + m->m[1][2] * p.z + m->m[1][3],
                      m->m[2][0] * p.x + m->m[2][1] * p.y + m->m[2][2] * p.z + m->m[2][3]};
}

static ts_dvec3 mat_vector(const ts_mat4 *m, ts_dvec3 v)
{
    return (ts_dvec3){m->m[0][0] * v.x + m->m[0][1] * v.y + m->m[0][2] * v.z,
                      m->m[1][0] * v.x + m->m[1][1] * v.y + m->m[1][2] * v.z,
                      m->m[2][0] * v.x + m->m[2][1] * v.y + m->m[2][2] * v.z};
}

#define MOTION_BOUND_STEPS 64

ts_bounds3 ts_anim_xform_motion_bounds(const ts_anim_xform *a, ts_bounds3 b)
{
    ts_bounds3 w = ts_bounds3_empty();
    if (ts_bounds3_is_empty(b)) return w;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    /* Any rotation at all (not pbrt-v3's 0.9995 test: the normalised lerp it uses below that
     * angle is no straight line either). */
    bool rotates = a->animated && (a->r[0].x != a->r[1].x || a->r[0].y != a->r[1].y || a->r[0].z != a->r[1].z ||
                                   a->r[0].w != a->r[1].w);
    int steps = rotates ? MOTION_BOUND_STEPS : 1;
    double theta = 0;
    if (steps > 1) {
        double c = fabs(ts_quat_dot(a->r[0], a->r[1]));
        theta = 2 * acos(c > 1 ? 1 : c); /* the rotation's angle between the keyframes */
    }
    ts_mat4 ds;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) ds.m[i][j] = a->s[1].m[i][j] - a->s[0].m[i][j];
    ts_dvec3 dt = ts_dvec3_sub(a->t[1], a->t[0]);
    for (int c = 0; c < 8; c++) {
        ts_dvec3 p = {(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z};
        double margin = 0;
        if (steps > 1) {
            double s0 = ts_dvec3_length(mat_vector(&a->s[0], p)), s1 = ts_dvec3_length(mat_vector(&a->s[1], p));
            double speed = ts_dvec3_length(dt) + theta * fmax(s0, s1) + ts_dvec3_length(mat_vector(&ds, p));
            /* 1.01: the normalised lerp of nearby rotations turns up to 1.0003× faster than
             * constant speed at mid-interval. */
            margin = speed * (0.5 / steps) * 1.01;
        }
        for (int k = 0; k <= steps; k++) {
            ts_mat4 m;
            if (steps == 1) m = k == 0 ? a->start.m : a->end.m;
            else m = k == 0 ? a->start.m : k == steps ? a->end.m : interpolate(a, (double)k / steps);
            ts_dvec3 q = mat_point(&m, p);
            double v[3] = {q.x, q.y, q.z};
            for (int i = 0; i < 3; i++) {
                lo[i] = fmin(lo[i], v[i] - margin);
                hi[i] = fmax(hi[i], v[i] + margin);
            }
        }
    }
    /* Round outwards: the float next below/above the double. */
    float flo[3], fhi[3];
    for (int i = 0; i < 3; i++) {
        flo[i] = (float)lo[i];
        if ((double)flo[i] > lo[i]) flo[i] = nextafterf(flo[i], -INFINITY);
        fhi[i] = (float)hi[i];
        if ((double)fhi[i] < hi[i]) fhi[i] = nextafterf(fhi[i], INFINITY);
    }
    w.lo = (ts_vec3){flo[0], flo[1], flo[2]};
    w.hi = (ts_vec3){fhi[0], fhi[1], fhi[2]};
    return w;
}
