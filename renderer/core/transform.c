/* transform.c — 4×4 transforms in double; see transform.h. */
#include "core/transform.h"

#include <math.h>
#include <string.h>

ts_mat4 ts_mat4_identity(void)
{
    ts_mat4 r;
    memset(&r, 0, sizeof r);
    for (int i = 0; i < 4; i++) r.m[i][i] = 1;
    return r;
}

ts_mat4 ts_mat4_mul(const ts_mat4 *a, const ts_mat4 *b)
{
    ts_mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a->m[i][k] * b->m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

ts_mat4 ts_mat4_transpose(const ts_mat4 *a)
{
    ts_mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) r.m[i][j] = a->m[j][i];
    return r;
}

bool ts_mat4_invert(const ts_mat4 *a, ts_mat4 *inv)
{
    /* Gauss–Jordan with full pivoting, as in Numerical Recipes' gaussj. */
    int indxc[4], indxr[4], ipiv[4] = {0, 0, 0, 0};
    ts_mat4 r = *a;
    for (int i = 0; i < 4; i++) {
        int irow = 0, icol = 0;
        double big = 0;
        for (int j = 0; j < 4; j++) {
            if (ipiv[j] == 1) continue;
            for (int k = 0; k < 4; k++) {
                if (ipiv[k] == 0) {
                    if (fabs(r.m[j][k]) >= big) {
                        big = fabs(r.m[j][k]);
                        irow = j;
                        icol = k;
                    }
                } else if (ipiv[k] > 1) {
                    return false;
                }
            }
        }
        ++ipiv[icol];
        if (irow != icol)
            for (int k = 0; k < 4; ++k) {
                double tmp = r.m[irow][k];
                r.m[irow][k] = r.m[icol][k];
                r.m[icol][k] = tmp;
            }
        indxr[i] = irow;
        indxc[i] = icol;
        if (r.m[icol][icol] == 0 || !isfinite(r.m[icol][icol])) return false;
        double pivinv = 1.0 / r.m[icol][icol];
        r.m[icol][icol] = 1;
        for (int j = 0; j < 4; j++) r.m[icol][j] *= pivinv;
        for (int j = 0; j < 4; j++) {
            if (j == icol) continue;
            double save = r.m[j][icol];
            r.m[j][icol] = 0;
            for (int k = 0; k < 4; k++) r.m[j][k] -= r.m[icol][k] * save;
        }
    }
    for (int j = 3; j >= 0; j--) {
        if (indxr[j] == indxc[j]) continue;
        for (int k = 0; k < 4; k++) {
            double tmp = r.m[k][indxr[j]];
            r.m[k][indxr[j]] = r.m[k][indxc[j]];
            r.m[k][indxc[j]] = tmp;
        }
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(r.m[i][j])) return false;
    *inv = r;
    return true;
}

ts_xform ts_xform_identity(void)
{
    ts_xform t = {ts_mat4_identity(), ts_mat4_identity()};
    return t;
}

bool ts_xform_from_matrix(const ts_mat4 *m, ts_xform *out)
{
    ts_mat4 inv;
    if (!ts_mat4_invert(m, &inv)) return false;
    out->m = *m;
    out->m_inv = inv;
    return true;
}

ts_xform ts_xform_translate(ts_dvec3 d)
{
    ts_xform t = ts_xform_identity();
    t.m.m[0][3] = d.x;
    t.m.m[1][3] = d.y;
    t.m.m[2][3] = d.z;
    t.m_inv.m[0][3] = -d.x;
    t.m_inv.m[1][3] = -d.y;
    t.m_inv.m[2][3] = -d.z;
    return t;
}

ts_xform ts_xform_scale(ts_dvec3 s)
{
    ts_xform t = ts_xform_identity();
    t.m.m[0][0] = s.x;
    t.m.m[1][1] = s.y;
    t.m.m[2][2] = s.z;
    t.m_inv.m[0][0] = 1 / s.x;
    t.m_inv.m[1][1] = 1 / s.y;
    t.m_inv.m[2][2] = 1 / s.z;
    return t;
}

ts_xform ts_xform_rotate(double angle_deg, ts_dvec3 axis)
{
    ts_dvec3 a = ts_dvec3_normalize(axis);
    double theta = angle_deg * (TS_PI_D / 180.0);
    double s = sin(theta), c = cos(theta);
    ts_xform t = ts_xform_identity();
    ts_mat4 *m = &t.m;
    m->m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
    m->m[0][1] = a.x * a.y * (1 - c) - a.z * s;
    m->m[0][2] = a.x * a.z * (1 - c) + a.y * s;
    m->m[1][0] = a.x * a.y * (1 - c) + a.z * s;
    m->m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
    m->m[1][2] = a.y * a.z * (1 - c) - a.x * s;
    m->m[2][0] = a.x * a.z * (1 - c) - a.y * s;
    m->m[2][1] = a.y * a.z * (1 - c) + a.x * s;
    m->m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
    t.m_inv = ts_mat4_transpose(m); /* rotations are orthogonal */
    return t;
}

ts_xform ts_xform_frame(ts_dvec3 o, ts_dvec3 n)
{
    n = ts_dvec3_normalize(n);
    /* Duff et al.'s branchless basis, in double. */
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double b = n.x * n.y * a;
    ts_dvec3 s = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    ts_dvec3 t = {b, sign + n.y * n.y * a, -n.y};
    ts_mat4 m = ts_mat4_identity();
    m.m[0][0] = s.x, m.m[1][0] = s.y, m.m[2][0] = s.z;
    m.m[0][1] = t.x, m.m[1][1] = t.y, m.m[2][1] = t.z;
    m.m[0][2] = n.x, m.m[1][2] = n.y, m.m[2][2] = n.z;
    m.m[0][3] = o.x, m.m[1][3] = o.y, m.m[2][3] = o.z;
    ts_xform x;
    x.m = m;
    /* Inverse of [R | o] is [Rᵀ | −Rᵀo]. */
    ts_mat4 inv = ts_mat4_identity();
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) inv.m[i][j] = m.m[j][i];
    for (int i = 0; i < 3; i++) inv.m[i][3] = -(inv.m[i][0] * o.x + inv.m[i][1] * o.y + inv.m[i][2] * o.z);
    x.m_inv = inv;
    return x;
}

ts_xform ts_xform_compose(const ts_xform *a, const ts_xform *b)
{
    ts_xform r;
    r.m = ts_mat4_mul(&a->m, &b->m);
    r.m_inv = ts_mat4_mul(&b->m_inv, &a->m_inv);
    return r;
}

ts_xform ts_xform_inverse(const ts_xform *a)
{
    ts_xform r = {a->m_inv, a->m};
    return r;
}

bool ts_xform_swaps_handedness(const ts_xform *a)
{
    const double(*m)[4] = a->m.m;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    return det < 0;
}

bool ts_xform_is_identity(const ts_xform *a)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (a->m.m[i][j] != (i == j ? 1.0 : 0.0)) return false;
    return true;
}

static ts_dvec3 apply_point(const ts_mat4 *m, ts_dvec3 p)
{
    double x = m->m[0][0] * p.x + m->m[0][1] * p.y + m->m[0][2] * p.z + m->m[0][3];
    double y = m->m[1][0] * p.x + m->m[1][1] * p.y + m->m[1][2] * p.z + m->m[1][3];
    double z = m->m[2][0] * p.x + m->m[2][1] * p.y + m->m[2][2] * p.z + m->m[2][3];
    double w = m->m[3][0] * p.x + m->m[3][1] * p.y + m->m[3][2] * p.z + m->m[3][3];
    if (w == 1) return (ts_dvec3){x, y, z};
    return (ts_dvec3){x / w, y / w, z / w};
}

static ts_dvec3 apply_vector(const ts_mat4 *m, ts_dvec3 v)
{
    return (ts_dvec3){m->m[0][0] * v.x + m->m[0][1] * v.y + m->m[0][2] * v.z,
                      m->m[1][0] * v.x + m->m[1][1] * v.y + m->m[1][2] * v.z,
                      m->m[2][0] * v.x + m->m[2][1] * v.y + m->m[2][2] * v.z};
}

ts_dvec3 ts_xform_point(const ts_xform *t, ts_dvec3 p) { return apply_point(&t->m, p); }
ts_dvec3 ts_xform_vector(const ts_xform *t, ts_dvec3 v) { return apply_vector(&t->m, v); }
ts_dvec3 ts_xform_point_inv(const ts_xform *t, ts_dvec3 p) { return apply_point(&t->m_inv, p); }
ts_dvec3 ts_xform_vector_inv(const ts_xform *t, ts_dvec3 v) { return apply_vector(&t->m_inv, v); }

ts_dvec3 ts_xform_normal(const ts_xform *t, ts_dvec3 n)
{
    const ts_mat4 *mi = &t->m_inv;
    return (ts_dvec3){mi->m[0][0] * n.x + mi->m[1][0] * n.y + mi->m[2][0] * n.z,
                      mi->m[0][1] * n.x + mi->m[1][1] * n.y + mi->m[2][1] * n.z,
                      mi->m[0][2] * n.x + mi->m[1][2] * n.y + mi->m[2][2] * n.z};
}
