/* shape.c — exact ray–shape intersection with error bounds; see shape.h.
 *
 * Design note. Analytic shapes (sphere, disk, cylinder) are solved in object space in
 * double precision: the float ray goes through the double inverse transform, the roots
 * come from numerically stable formulas (the quadratic's discriminant from the distance
 * of the line to the axis/centre, as in "Precision Improvements for Ray/Sphere
 * Intersection", Ray Tracing Gems ch. 7), the hit is reprojected onto the surface and
 * mapped back to world space in double, then rounded once to float. A triangle hit that
 * Embree found is evaluated in float from Embree's barycentrics with pbrt-v3's kind of
 * bound ("the accelerator's hits" below); ts_shape_interaction recomputes one from the
 * ray in double (Möller–Trumbore on the float vertices), the reference of the tests.
 *
 * The error bound of a world-space hit point, per component, is the sum of
 *   - the final rounding to float: 2^-22·|p| (four times the half ulp 2^-24·|p|);
 *     for triangles in double pbrt-v3's gamma(7)·Σ|b_i·p_i|, which contains it;
 *   - the double arithmetic of the object→world transform and of the reprojection:
 *     MAG_SLACK·(Σ_j |M_ij·p_obj_j| + |M_i3|), MAG_SLACK = 2^-40 being 8192 unit
 *     roundoffs of double — tiny against the float term except in components that
 *     cancel to near zero, and large enough that the spawn offset it produces always
 *     dwarfs the double error of re-intersecting the surface (see below);
 *   - the displacement of the hit *along* the surface caused by the double round-off of
 *     the object-space ray and of the solve. That round-off moves the ray's line by at
 *     most δ = DBL_SLACK·(|o| + t·|d| + size) plus the transform's error; the hit then
 *     moves by at most δ·(1 + 2/cosθ) (θ between ray and normal), and for a curved
 *     surface never more than δ + 4·sqrt(r·δ) (the sagitta bound near tangency). It is
 *     negligible except for grazing rays, where it is what keeps the bound honest.
 *
 * Self-intersection. A ray spawned from a hit starts at least p_error·|n| off the
 * surface, i.e. at least ~2^-40 of the shape's size in object space, which is 2^13 times
 * the double error of the re-solve. So the root of the point it left is computed with
 * the right sign: for a sphere outside/moving away both roots are negative, inside one is
 * negative and one positive (their product c/a has a robust sign); for a disk
 * t = −o_z/d_z has the sign of the offset. In addition roots closer than T_GUARD·(|o| +
 * size) to the origin, which no double computation can tell from 0, are rejected.
 *
 * Everything here is pure and thread-safe. */
#include "geometry/shape.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Double-precision round-off slack of the object-space solve (32 unit roundoffs). */
#define DBL_SLACK 0x1p-48
/* Bound on the error of one 3-term dot product plus translation in double: γ_d(4) < 2^-50. */
#define XFORM_SLACK 0x1p-50
/* See the design note: transform/reprojection term of p_error. */
#define MAG_SLACK 0x1p-40
/* Float rounding term of p_error: four half-ulps. */
#define FLOAT_SLACK 0x1p-22
/* Roots nearer than this fraction of the problem's magnitude are indistinguishable from 0. */
#define T_GUARD 0x1p-45

#define TWO_PI_D (2.0 * TS_PI_D)

/* ---- small helpers ---- */

static inline double dmax(double a, double b) { return a > b ? a : b; }
static inline double dmin(double a, double b) { return a < b ? a : b; }

/* Smallest float ≥ x (x ≥ 0). When the rounded f is below x it is finite and ≥ +0, and
 * the next float up is its bit pattern plus one (ts_next_float_up for such f); added
 * without a branch, because which way the rounding went is a coin toss. */
static float round_up_f(double x)
{
    float f = (float)x;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    u += (uint32_t)((double)f < x);
    memcpy(&f, &u, sizeof f);
    return f;
}

static ts_vec3 round_up_v(ts_dvec3 e) { return (ts_vec3){round_up_f(e.x), round_up_f(e.y), round_up_f(e.z)}; }

static ts_vec3 to_unit_f(ts_dvec3 v)
{
    ts_dvec3 u = ts_dvec3_normalize(v);
    return ts_dvec3_to_vec3(u);
}

static double det3(const ts_mat4 *m)
{
    const double(*a)[4] = m->m;
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

/* ---- the ray in object space ---- */

typedef struct obj_ray {
    ts_dvec3 o, d;  /* object-space origin and direction (double) */
    double o_err;   /* bound on |o − exact| (sum of components) */
    double d_err;   /* bound on |d − exact| */
    double d_len;   /* |d| */
    double o_len;   /* |o| */
} obj_ray;

static obj_ray to_object(const ts_shape *s, const ts_ray *ray)
{
    const double(*mi)[4] = s->to_world.m_inv.m;
    double ow[3] = {ray->o.x, ray->o.y, ray->o.z}, dw[3] = {ray->d.x, ray->d.y, ray->d.z};
    double o[3], d[3], oe = 0, de = 0;
    for (int i = 0; i < 3; i++) {
        o[i] = mi[i][0] * ow[0] + mi[i][1] * ow[1] + mi[i][2] * ow[2] + mi[i][3];
        d[i] = mi[i][0] * dw[0] + mi[i][1] * dw[1] + mi[i][2] * dw[2];
        oe += XFORM_SLACK * (fabs(mi[i][0] * ow[0]) + fabs(mi[i][1] * ow[1]) + fabs(mi[i][2] * ow[2]) + fabs(mi[i][3]));
        de += XFORM_SLACK * (fabs(mi[i][0] * dw[0]) + fabs(mi[i][1] * dw[1]) + fabs(mi[i][2] * dw[2]));
    }
    obj_ray r;
    r.o = (ts_dvec3){o[0], o[1], o[2]};
    r.d = (ts_dvec3){d[0], d[1], d[2]};
    r.o_err = oe;
    r.d_err = de;
    r.d_len = ts_dvec3_length(r.d);
    r.o_len = ts_dvec3_length(r.o);
    return r;
}

/* An analytic hit in object space: p on the surface, err bounds |p − exact hit|. */
typedef struct obj_hit {
    double t;
    ts_dvec3 p;
    double err;
} obj_hit;

static inline bool root_ok(double t, double t_lo, float tmax) { return t > t_lo && (float)t < tmax; }

/* Perturbation of the object-space line at parameter t (see the design note). */
static inline double line_delta(const obj_ray *r, double t, double size)
{
    return DBL_SLACK * (r->o_len + t * r->d_len + size) + r->o_err + t * r->d_err;
}

/* Displacement of the hit along the surface for a line moved by delta; cos_theta is the
 * cosine between the ray and the normal; curv_bound the tangency (sagitta) bound, or
 * INFINITY for a flat surface. */
static inline double slide_bound(double delta, double cos_theta, double curv_bound)
{
    double b = cos_theta > 0 ? delta * (1 + 2 / cos_theta) : INFINITY;
    return dmin(b, curv_bound);
}

/* Two roots of a·t² + 2·b·t + c = 0 given a, b, c and the quarter discriminant over a,
 * disc_a = b²/a − c ≥ 0 computed accurately by the caller. Stable form: q = −(b ± √(a·disc_a)). */
static bool solve_roots(double a, double b, double c, double disc_a, double *t0, double *t1)
{
    double root = sqrt(a * disc_a);
    double q = -(b + copysign(root, b));
    if (q == 0) return false;
    double r0 = q / a, r1 = c / q;
    *t0 = dmin(r0, r1);
    *t1 = dmax(r0, r1);
    return true;
}

/* φ of an object-space point in [0, 2π) (0 on the z axis, where pbrt-v3 nudges x). */
static inline double point_phi(ts_dvec3 p)
{
    double phi = atan2(p.y, p.x);
    if (phi < 0) phi += TWO_PI_D;
    return phi;
}

/* A partial shape's cut (shape.h): a point p on the full surface belongs to s. pbrt-v3's
 * tests: φ > phi_max is out; of a sphere, z below z_min (when z_min > −r) or above z_max
 * (when z_max < r). */
static inline bool in_cut(const ts_shape *s, ts_dvec3 p)
{
    if (!s->partial) return true;
    if (s->type == TS_SHAPE_SPHERE) {
        double r = s->sphere.radius;
        if ((s->sphere.z_min > -r && p.z < s->sphere.z_min) || (s->sphere.z_max < r && p.z > s->sphere.z_max))
            return false;
    }
    return point_phi(p) <= s->phi_max;
}

static bool sphere_hit(const ts_shape *s, const obj_ray *R, float tmax, obj_hit *h)
{
    double radius = s->sphere.radius;
    ts_dvec3 o = R->o, d = R->d;
    double a = ts_dvec3_dot(d, d);
    if (!(a > 0)) return false;
    double b = ts_dvec3_dot(o, d);
    /* f: foot of the perpendicular from the centre to the line; b²/a − c = r² − |f|². */
    ts_dvec3 f = ts_dvec3_sub(o, ts_dvec3_scale(d, b / a));
    double f_len = ts_dvec3_length(f);
    double disc_a = (radius - f_len) * (radius + f_len);
    if (disc_a < 0) return false;
    double c = ts_dvec3_dot(o, o) - radius * radius;
    double t0, t1;
    if (!solve_roots(a, b, c, disc_a, &t0, &t1)) return false;
    double t_lo = T_GUARD * (R->o_len + radius) / R->d_len;
    /* The nearer root, else the farther (a partial sphere's cut may remove the nearer). */
    double roots[2] = {t0, t1};
    for (int k = 0; k < 2; k++) {
        double t = roots[k];
        if (!root_ok(t, t_lo, tmax)) continue;
        ts_dvec3 p = ts_dvec3_add(o, ts_dvec3_scale(d, t));
        double p_len = ts_dvec3_length(p);
        if (!(p_len > 0)) return false;
        p = ts_dvec3_scale(p, radius / p_len);
        if (!in_cut(s, p)) continue;
        double delta = line_delta(R, t, radius);
        double cos_theta = fabs(ts_dvec3_dot(p, d)) / (radius * R->d_len);
        double slide = slide_bound(delta, cos_theta, delta + 4 * sqrt(radius * delta));
        h->t = t;
        h->p = p;
        h->err = slide + DBL_SLACK * radius;
        return true;
    }
    return false;
}

static bool disk_hit(const ts_shape *s, const obj_ray *R, float tmax, obj_hit *h)
{
    double radius = s->disk.radius, inner = s->disk.inner_radius;
    ts_dvec3 o = R->o, d = R->d;
    if (d.z == 0) return false;
    double t = -o.z / d.z;
    double t_lo = T_GUARD * (R->o_len + radius) / R->d_len;
    if (!root_ok(t, t_lo, tmax)) return false;
    ts_dvec3 p = {o.x + t * d.x, o.y + t * d.y, 0};
    double dist2 = p.x * p.x + p.y * p.y;
    if (dist2 > radius * radius || dist2 < inner * inner) return false;
    if (!in_cut(s, p)) return false;
    double delta = line_delta(R, t, radius);
    double cos_theta = fabs(d.z) / R->d_len;
    h->t = t;
    h->p = p;
    h->err = slide_bound(delta, cos_theta, INFINITY) + DBL_SLACK * radius;
    return true;
}

static bool cylinder_hit(const ts_shape *s, const obj_ray *R, float tmax, obj_hit *h)
{
    double radius = s->cylinder.radius, height = s->cylinder.height;
    ts_dvec3 o = R->o, d = R->d;
    double a = d.x * d.x + d.y * d.y;
    if (!(a > 0)) return false;
    double b = o.x * d.x + o.y * d.y;
    double fx = o.x - (b / a) * d.x, fy = o.y - (b / a) * d.y;
    double f_len = hypot(fx, fy);
    double disc_a = (radius - f_len) * (radius + f_len);
    if (disc_a < 0) return false;
    double c = o.x * o.x + o.y * o.y - radius * radius;
    double t0, t1;
    if (!solve_roots(a, b, c, disc_a, &t0, &t1)) return false;
    double size = radius + height;
    double t_lo = T_GUARD * (R->o_len + size) / R->d_len;
    double roots[2] = {t0, t1};
    for (int k = 0; k < 2; k++) {
        double t = roots[k];
        if (!root_ok(t, t_lo, tmax)) continue;
        double z = o.z + t * d.z;
        if (z < 0 || z > height) continue;
        double x = o.x + t * d.x, y = o.y + t * d.y;
        double rh = hypot(x, y);
        if (!(rh > 0)) continue;
        ts_dvec3 p = {x * (radius / rh), y * (radius / rh), z};
        if (!in_cut(s, p)) continue;
        double delta = line_delta(R, t, size);
        double cos_theta = fabs(p.x * d.x + p.y * d.y) / (radius * R->d_len);
        /* Tangency in the xy projection, stretched back to 3D by |d|/|d_xy|. */
        double curv = delta + (delta + 4 * sqrt(radius * delta)) * (R->d_len / sqrt(a));
        h->t = t;
        h->p = p;
        h->err = slide_bound(delta, cos_theta, curv) + DBL_SLACK * size;
        return true;
    }
    return false;
}

static bool analytic_hit(const ts_shape *s, const ts_ray *ray, float tmax, obj_hit *h)
{
    if (!(tmax > 0)) return false;
    obj_ray R = to_object(s, ray);
    if (!(R.d_len > 0)) return false;
    switch (s->type) {
    case TS_SHAPE_SPHERE: return sphere_hit(s, &R, tmax, h);
    case TS_SHAPE_DISK: return disk_hit(s, &R, tmax, h);
    case TS_SHAPE_CYLINDER: return cylinder_hit(s, &R, tmax, h);
    case TS_SHAPE_MESH:
    case TS_SHAPE_CURVE: break;
    }
    return false;
}

/* ---- triangles ---- */

typedef struct tri_d {
    ts_dvec3 p0, p1, p2;
    uint32_t i0, i1, i2;
} tri_d;

static tri_d tri_load(const ts_mesh *m, uint32_t prim)
{
    tri_d t;
    t.i0 = m->index[3 * prim];
    t.i1 = m->index[3 * prim + 1];
    t.i2 = m->index[3 * prim + 2];
    const float *a = m->p + 3 * t.i0, *b = m->p + 3 * t.i1, *c = m->p + 3 * t.i2;
    t.p0 = (ts_dvec3){a[0], a[1], a[2]};
    t.p1 = (ts_dvec3){b[0], b[1], b[2]};
    t.p2 = (ts_dvec3){c[0], c[1], c[2]};
    return t;
}

/* Möller–Trumbore in double. Returns false only if the ray is parallel to the plane (or the
 * triangle degenerate); u, v (barycentrics of p1, p2) and t are not range-checked.
 * num = e2·((o − p0) × e1) = t·det is |e1 × e2| times the signed distance of o from the
 * plane; tri_num_noise bounds its round-off. */
typedef struct tri_solve {
    double u, v, t, det, num;
    ts_dvec3 e1, e2, tvec;
} tri_solve;

static bool tri_mt(const tri_d *tr, ts_dvec3 o, ts_dvec3 d, tri_solve *s)
{
    s->e1 = ts_dvec3_sub(tr->p1, tr->p0);
    s->e2 = ts_dvec3_sub(tr->p2, tr->p0);
    ts_dvec3 pvec = ts_dvec3_cross(d, s->e2);
    s->det = ts_dvec3_dot(s->e1, pvec);
    if (s->det == 0 || !isfinite(s->det)) return false;
    s->tvec = ts_dvec3_sub(o, tr->p0);
    double inv = 1.0 / s->det;
    s->u = ts_dvec3_dot(s->tvec, pvec) * inv;
    ts_dvec3 qvec = ts_dvec3_cross(s->tvec, s->e1);
    s->v = ts_dvec3_dot(d, qvec) * inv;
    s->num = ts_dvec3_dot(s->e2, qvec);
    s->t = s->num * inv;
    return true;
}

/* e2·(tvec × e1) is a triple product: its round-off is a few units of |e1|·|e2|·|tvec|;
 * T_GUARD leaves a wide margin. Computed only where it is compared (three square roots). */
static inline double tri_num_noise(const tri_solve *s)
{
    return T_GUARD * ts_dvec3_length(s->e1) * ts_dvec3_length(s->e2) * ts_dvec3_length(s->tvec);
}

bool ts_shape_triangle_intersect(const ts_shape *s, uint32_t prim, const ts_ray *ray, float tmax, float *t_hit)
{
    if (s->type != TS_SHAPE_MESH || prim >= s->mesh.n_triangles || !(tmax > 0)) return false;
    tri_d tr = tri_load(&s->mesh, prim);
    tri_solve m;
    if (!tri_mt(&tr, ts_dvec3_from(ray->o), ts_dvec3_from(ray->d), &m)) return false;
    if (m.u < 0 || m.v < 0 || m.u + m.v > 1) return false;
    if (!root_ok(m.t, 0, tmax) || fabs(m.num) <= tri_num_noise(&m)) return false;
    *t_hit = (float)m.t;
    return true;
}

/* tri_mt without the barycentrics, which this test does not need; e1_len and e2_len are
 * |e1| and |e2| (tri_num_noise's first two factors). */
static inline bool triangle_ahead(const tri_d *tr, const ts_ray *ray, double e1_len, double e2_len)
{
    ts_dvec3 o = ts_dvec3_from(ray->o), d = ts_dvec3_from(ray->d);
    ts_dvec3 e1 = ts_dvec3_sub(tr->p1, tr->p0), e2 = ts_dvec3_sub(tr->p2, tr->p0);
    double det = ts_dvec3_dot(e1, ts_dvec3_cross(d, e2));
    if (det == 0 || !isfinite(det)) return false;
    ts_dvec3 tvec = ts_dvec3_sub(o, tr->p0);
    double num = ts_dvec3_dot(e2, ts_dvec3_cross(tvec, e1));
    double t = num * (1.0 / det);
    return t > 0 && fabs(num) > T_GUARD * e1_len * e2_len * ts_dvec3_length(tvec);
}

bool ts_shape_triangle_ahead(const ts_shape *s, uint32_t prim, const ts_ray *ray)
{
    if (s->type != TS_SHAPE_MESH || prim >= s->mesh.n_triangles) return false;
    tri_d tr = tri_load(&s->mesh, prim);
    return triangle_ahead(&tr, ray, ts_dvec3_length(ts_dvec3_sub(tr.p1, tr.p0)),
                          ts_dvec3_length(ts_dvec3_sub(tr.p2, tr.p0)));
}

/* triangle_ahead's "yes" where it is clear by a wide margin, from p0 and the cache's float
 * unit normal n alone; -1 where it is not clear (then triangle_ahead decides).
 *
 * With n̂ = N/|N| (N = e1 × e2), triangle_ahead's num = e2·(tvec × e1) is tvec·N and its
 * det = e1·(d × e2) is −d·N, each up to a few double roundoffs of |tvec|·|e1|·|e2| and
 * |d|·|e1|·|e2|; it answers yes iff num·det > 0 and |num| > T_GUARD·|e1|·|e2|·|tvec|.
 * Here a = tvec·n and b = d·n, in double. n is n̂ rounded to float: |n − n̂| ≤ 2^-24·√3
 * < 1.1e-7, so |a − num/|N|| < 1.2e-7·|tvec|·k and |b + det/|N|| < 1.2e-7·|d|·k with
 * k = |e1|·|e2|/|N| ≥ 1 (inv_sin; the double roundoffs of num and det are inside that).
 * If |a| > AHEAD_CLEAR·k·|tvec| and |b| > AHEAD_CLEAR·k·|d|, AHEAD_CLEAR = 2^-20
 * (9.5e-7, eight times the error), then num has a's sign and |num| > 8.3e-7·|e1|·|e2|·|tvec|
 * — 3·10^7 times T_GUARD's threshold — and det has −b's sign and is not 0, so the exact
 * test says yes iff a·b < 0; t = num/det cannot underflow to 0 for float input (|t| ≥
 * 8e-7·|tvec|/|d| ≥ 1e-90). The comparisons are of squares (no square root) and fail for
 * NaN, ∞ (a degenerate triangle's k) and tvec = 0, which all go to the exact test. So the
 * answer is triangle_ahead's, bit for bit; what it saves is the two other vertices' loads,
 * two cross products, a division and a square root for all but the hits near the ray's
 * origin plane (a neighbour of the triangle it leaves) or along the triangle's plane. */
#define AHEAD_CLEAR 0x1p-20
static inline bool triangle_ahead_clear(const ts_mesh *m, const ts_tri_cache *c, uint32_t prim, const ts_ray *ray,
                                        bool *ahead)
{
    const float *p0 = m->p + 3 * (size_t)m->index[3 * prim];
    ts_dvec3 tvec = {(double)ray->o.x - p0[0], (double)ray->o.y - p0[1], (double)ray->o.z - p0[2]};
    ts_dvec3 n = ts_dvec3_from(c->n), d = ts_dvec3_from(ray->d);
    double a = ts_dvec3_dot(tvec, n), b = ts_dvec3_dot(d, n);
    double k2 = AHEAD_CLEAR * AHEAD_CLEAR * c->inv_sin * c->inv_sin;
    if (!(a * a > k2 * ts_dvec3_dot(tvec, tvec)) || !(b * b > k2 * ts_dvec3_dot(d, d))) return false;
    *ahead = (a < 0) != (b < 0);
    return true;
}

bool ts_shape_triangle_ahead_cached(const ts_shape *s, const ts_tri_cache *c, uint32_t prim, const ts_ray *ray)
{
    if (s->type != TS_SHAPE_MESH || prim >= s->mesh.n_triangles) return false;
    bool ahead;
    if (triangle_ahead_clear(&s->mesh, c, prim, ray, &ahead)) return ahead;
    tri_d tr = tri_load(&s->mesh, prim);
    return triangle_ahead(&tr, ray, c->e1_len, c->e2_len);
}

/* ---- public: intersection ---- */

bool ts_shape_intersect(const ts_shape *s, const ts_ray *ray, float tmax, float *t_hit)
{
    if (s->type == TS_SHAPE_CURVE) return false; /* Embree's curves only (geometry/curve.h) */
    if (s->type == TS_SHAPE_MESH) {
        /* Brute force over the triangles (tests and tools; traversal uses Embree). */
        bool hit = false;
        for (uint32_t i = 0; i < s->mesh.n_triangles; i++) {
            float t;
            if (ts_shape_triangle_intersect(s, i, ray, tmax, &t)) {
                hit = true;
                tmax = t;
                *t_hit = t;
            }
        }
        return hit;
    }
    obj_hit h;
    if (!analytic_hit(s, ray, tmax, &h)) return false;
    *t_hit = (float)h.t;
    return true;
}

/* ---- public: interaction ---- */

/* pbrt-v3's Weingarten equations: ∂N/∂u, ∂N/∂v of the unit normal N of a surface with
 * first derivatives dpdu, dpdv and second derivatives d2uu, d2uv, d2vv (object space).
 * A degenerate first fundamental form gives 0. */
static void weingarten(ts_dvec3 N, ts_dvec3 dpdu, ts_dvec3 dpdv, ts_dvec3 d2uu, ts_dvec3 d2uv, ts_dvec3 d2vv,
                       ts_dvec3 *dndu, ts_dvec3 *dndv)
{
    double E = ts_dvec3_dot(dpdu, dpdu), F = ts_dvec3_dot(dpdu, dpdv), G = ts_dvec3_dot(dpdv, dpdv);
    double e = ts_dvec3_dot(N, d2uu), f = ts_dvec3_dot(N, d2uv), g = ts_dvec3_dot(N, d2vv);
    double det = E * G - F * F;
    *dndu = *dndv = (ts_dvec3){0, 0, 0};
    if (!(fabs(det) > 0) || !isfinite(det)) return;
    double inv = 1 / det;
    *dndu = ts_dvec3_add(ts_dvec3_scale(dpdu, (f * F - e * G) * inv), ts_dvec3_scale(dpdv, (e * F - f * E) * inv));
    *dndv = ts_dvec3_add(ts_dvec3_scale(dpdu, (g * F - f * G) * inv), ts_dvec3_scale(dpdv, (f * F - g * E) * inv));
}

/* The derivative of the world normal n_w = M^-T·N / |M^-T·N| given ∂N/∂u in object space. */
static ts_dvec3 world_normal_derivative(const ts_xform *X, ts_dvec3 N, ts_dvec3 n_w, ts_dvec3 dN)
{
    double len = ts_dvec3_length(ts_xform_normal(X, N));
    ts_dvec3 dm = ts_xform_normal(X, dN);
    ts_dvec3 d = ts_dvec3_sub(dm, ts_dvec3_scale(n_w, ts_dvec3_dot(n_w, dm)));
    return len > 0 ? ts_dvec3_scale(d, 1 / len) : (ts_dvec3){0, 0, 0};
}

static void analytic_interaction(const ts_shape *s, const ts_ray *ray, const obj_hit *h, ts_interaction *si)
{
    ts_dvec3 d2uu = {0, 0, 0}, d2uv = {0, 0, 0}, d2vv = {0, 0, 0}; /* ∂²p/∂u², ∂²p/∂u∂v, ∂²p/∂v² */
    const ts_xform *X = &s->to_world;
    const double(*m)[4] = X->m.m;
    ts_dvec3 p = h->p, n_obj, dpdu, dpdv;
    double u, v;
    /* pbrt-v3's parameterisation (shape.h); the whole shape's φ_max is 2π. */
    double phi_max = s->partial ? s->phi_max : TWO_PI_D;
    switch (s->type) {
    case TS_SHAPE_SPHERE: {
        double r = s->sphere.radius;
        double phi = point_phi(p);
        u = phi / phi_max;
        double cos_theta = fmax(-1.0, fmin(1.0, p.z / r));
        double theta = acos(cos_theta);
        /* v = (θ − θ_min)/(θ_max − θ_min); the whole sphere's θ_min = π, θ_max = 0. */
        double th_min = TS_PI_D, th_range = -TS_PI_D;
        if (s->partial) th_min = s->sphere.theta_min, th_range = s->sphere.theta_max - s->sphere.theta_min;
        v = (theta - th_min) / th_range;
        double z_radius = hypot(p.x, p.y);
        double cos_phi = 1, sin_phi = 0;
        if (z_radius > 0) {
            cos_phi = p.x / z_radius;
            sin_phi = p.y / z_radius;
            dpdu = (ts_dvec3){-phi_max * p.y, phi_max * p.x, 0};
        } else {
            /* At a pole ∂p/∂u vanishes; use its limit direction at φ = 0 (pbrt-v3 nudges
             * the point instead, which would break the error bound). */
            dpdu = (ts_dvec3){0, phi_max * 1e-5 * r, 0};
        }
        double sin_theta = sqrt(fmax(0.0, 1 - cos_theta * cos_theta));
        dpdv = ts_dvec3_scale((ts_dvec3){p.z * cos_phi, p.z * sin_phi, -r * sin_theta}, th_range);
        d2uu = ts_dvec3_scale((ts_dvec3){p.x, p.y, 0}, -phi_max * phi_max);
        d2uv = ts_dvec3_scale((ts_dvec3){-sin_phi, cos_phi, 0}, th_range * p.z * phi_max);
        d2vv = ts_dvec3_scale(p, -th_range * th_range);
        n_obj = p;
        break;
    }
    case TS_SHAPE_DISK: {
        double r = s->disk.radius, ri = s->disk.inner_radius;
        double phi = point_phi(p);
        u = phi / phi_max;
        double r_hit = hypot(p.x, p.y);
        v = (r - r_hit) / (r - ri);
        if (r_hit > 0) {
            dpdu = (ts_dvec3){-phi_max * p.y, phi_max * p.x, 0};
            dpdv = ts_dvec3_scale((ts_dvec3){p.x, p.y, 0}, (ri - r) / r_hit);
        } else {
            dpdu = (ts_dvec3){0, phi_max * 1e-5 * r, 0};
            dpdv = (ts_dvec3){ri - r, 0, 0};
        }
        n_obj = (ts_dvec3){0, 0, 1};
        break;
    }
    case TS_SHAPE_CYLINDER:
    default: {
        double hgt = s->cylinder.height;
        double phi = point_phi(p);
        u = phi / phi_max;
        v = p.z / hgt;
        dpdu = (ts_dvec3){-phi_max * p.y, phi_max * p.x, 0};
        dpdv = (ts_dvec3){0, 0, hgt};
        d2uu = ts_dvec3_scale((ts_dvec3){p.x, p.y, 0}, -phi_max * phi_max);
        n_obj = (ts_dvec3){p.x, p.y, 0};
        break;
    }
    }

    /* World point and its error bound (see the design note). */
    double pw[3], err[3], pv[3] = {p.x, p.y, p.z};
    for (int i = 0; i < 3; i++) {
        double mag = fabs(m[i][3]), row = 0;
        pw[i] = m[i][3];
        for (int j = 0; j < 3; j++) {
            pw[i] += m[i][j] * pv[j];
            mag += fabs(m[i][j] * pv[j]);
            row += fabs(m[i][j]);
        }
        err[i] = FLOAT_SLACK * fabs(pw[i]) + MAG_SLACK * mag + row * h->err;
    }
    si->p = (ts_vec3){(float)pw[0], (float)pw[1], (float)pw[2]};
    si->p_error = round_up_v((ts_dvec3){err[0], err[1], err[2]});

    /* n_obj points along ∂p/∂u × ∂p/∂v in object space; in world space that cross product
     * is det(M)·M^-T·n_obj. pbrt-v3 takes it and flips it when the transform swaps
     * handedness, so the result is M^-T·n_obj, the front side of docs/design.md §4
     * (outwards, or the disk's +z side), flipped again by ReverseOrientation. */
    ts_dvec3 n_w = ts_dvec3_normalize(ts_xform_normal(X, n_obj));
    /* ∂n/∂u, ∂n/∂v (a disk's second derivatives are 0, so are its): of the unit object
     * normal, then of the world normal, turned with it. */
    ts_dvec3 dndu = {0, 0, 0}, dndv = {0, 0, 0};
    if (!s->no_normal_derivatives) {
        ts_dvec3 N = ts_dvec3_normalize(n_obj);
        weingarten(N, dpdu, dpdv, d2uu, d2uv, d2vv, &dndu, &dndv);
        dndu = world_normal_derivative(X, N, n_w, dndu);
        dndv = world_normal_derivative(X, N, n_w, dndv);
    }
    double sign = s->reverse_orientation ? -1 : 1;
    if (s->reverse_orientation) n_w = ts_dvec3_scale(n_w, -1);
    si->n = ts_dvec3_to_vec3(n_w);
    si->ns = si->n;
    si->dpdu = ts_dvec3_to_vec3(ts_xform_vector(X, dpdu));
    si->dpdv = ts_dvec3_to_vec3(ts_xform_vector(X, dpdv));
    si->dndu = ts_dvec3_to_vec3(ts_dvec3_scale(dndu, sign));
    si->dndv = ts_dvec3_to_vec3(ts_dvec3_scale(dndv, sign));
    si->mesh_normals = false;
    si->uv = (ts_vec2){(float)u, (float)v};
    si->wo = to_unit_f(ts_dvec3_scale(ts_dvec3_from(ray->d), -1));
    si->t = (float)h->t;
    si->prim = 0;
}

/* The ray-independent part of a triangle's interaction (shape.h, ts_tri_cache): computed
 * per hit by ts_shape_interaction, once per triangle by the accelerator. One routine for
 * both, so a cached value is the very value the per-hit path would compute. */
void ts_shape_triangle_cache_init(const ts_shape *s, uint32_t prim, ts_tri_cache *c)
{
    const ts_mesh *mesh = &s->mesh;
    tri_d tr = tri_load(mesh, prim);
    ts_dvec3 e1 = ts_dvec3_sub(tr.p1, tr.p0), e2 = ts_dvec3_sub(tr.p2, tr.p0);
    ts_dvec3 N = ts_dvec3_cross(e1, e2);
    double N_len = ts_dvec3_length(N);
    c->n_len = N_len;
    c->e1_len = ts_dvec3_length(e1);
    c->e2_len = ts_dvec3_length(e2);
    c->inv_sin = N_len > 0 ? c->e1_len * c->e2_len / N_len : INFINITY;
    ts_dvec3 n_d = N_len > 0 ? ts_dvec3_scale(N, 1 / N_len) : (ts_dvec3){0, 0, 1};
    c->n = ts_dvec3_to_vec3(n_d);

    /* ∂p/∂u, ∂p/∂v as pbrt-v3 (default uvs (0,0), (1,0), (1,1)). */
    double uv[3][2] = {{0, 0}, {1, 0}, {1, 1}};
    if (mesh->uv) {
        uint32_t ids[3] = {tr.i0, tr.i1, tr.i2};
        for (int k = 0; k < 3; k++) {
            uv[k][0] = mesh->uv[2 * ids[k]];
            uv[k][1] = mesh->uv[2 * ids[k] + 1];
        }
    }
    double du02 = uv[0][0] - uv[2][0], dv02 = uv[0][1] - uv[2][1];
    double du12 = uv[1][0] - uv[2][0], dv12 = uv[1][1] - uv[2][1];
    ts_dvec3 dp02 = ts_dvec3_sub(tr.p0, tr.p2), dp12 = ts_dvec3_sub(tr.p1, tr.p2);
    double uv_det = du02 * dv12 - dv02 * du12;
    bool degenerate = fabs(uv_det) < 1e-8;
    ts_dvec3 dpdu = {0, 0, 0}, dpdv = {0, 0, 0};
    if (!degenerate) {
        double inv = 1 / uv_det;
        dpdu = ts_dvec3_scale(ts_dvec3_sub(ts_dvec3_scale(dp02, dv12), ts_dvec3_scale(dp12, dv02)), inv);
        dpdv = ts_dvec3_scale(ts_dvec3_sub(ts_dvec3_scale(dp12, du02), ts_dvec3_scale(dp02, du12)), inv);
    }
    if (degenerate || ts_dvec3_length(ts_dvec3_cross(dpdu, dpdv)) == 0) {
        ts_coordinate_system(c->n, &c->dpdu, &c->dpdv);
    } else {
        c->dpdu = ts_dvec3_to_vec3(dpdu);
        c->dpdv = ts_dvec3_to_vec3(dpdv);
    }
}

/* The barycentrics (b1, b2 of p1, p2) and t of the hit of ray on triangle tr, in double
 * (Möller–Trumbore); for a ray in the triangle's plane (traversal should not report that)
 * those of the point at t_hint projected onto the plane. */
static void tri_bary(const tri_d *tr, ts_dvec3 o, ts_dvec3 d, float t_hint, double *b1_out, double *b2_out,
                     double *t_out)
{
    double b1, b2, t;
    tri_solve ms;
    if (tri_mt(tr, o, d, &ms)) {
        b1 = ms.u;
        b2 = ms.v;
        t = ms.t;
    } else {
        ts_dvec3 e1 = ts_dvec3_sub(tr->p1, tr->p0), e2 = ts_dvec3_sub(tr->p2, tr->p0);
        t = t_hint;
        ts_dvec3 q = ts_dvec3_sub(ts_dvec3_add(o, ts_dvec3_scale(d, t)), tr->p0);
        double d00 = ts_dvec3_dot(e1, e1), d01 = ts_dvec3_dot(e1, e2), d11 = ts_dvec3_dot(e2, e2);
        double d20 = ts_dvec3_dot(q, e1), d21 = ts_dvec3_dot(q, e2), den = d00 * d11 - d01 * d01;
        b1 = den != 0 ? (d11 * d20 - d01 * d21) / den : 0;
        b2 = den != 0 ? (d00 * d21 - d01 * d20) / den : 0;
    }
    *b1_out = b1;
    *b2_out = b2;
    *t_out = t;
}

/* The hit point b0·p0 + b1·p1 + b2·p2 (double). */
static inline ts_dvec3 tri_point(const tri_d *tr, double b0, double b1, double b2)
{
    return ts_dvec3_add(ts_dvec3_add(ts_dvec3_scale(tr->p0, b0), ts_dvec3_scale(tr->p1, b1)),
                        ts_dvec3_scale(tr->p2, b2));
}

/* (u, v) as pbrt-v3 interpolates it (default uvs (0,0), (1,0), (1,1)), into *uv (stored
 * through the pointer: the interaction's hot path then compiles as it did before). */
static inline void tri_uv(const ts_mesh *mesh, const tri_d *tr, double b0, double b1, double b2, ts_vec2 *uv)
{
    if (mesh->uv) {
        const float *uv0 = mesh->uv + 2 * tr->i0, *uv1 = mesh->uv + 2 * tr->i1, *uv2 = mesh->uv + 2 * tr->i2;
        *uv = (ts_vec2){(float)(b0 * (double)uv0[0] + b1 * (double)uv1[0] + b2 * (double)uv2[0]),
                        (float)(b0 * (double)uv0[1] + b1 * (double)uv1[1] + b2 * (double)uv2[1])};
    } else {
        *uv = (ts_vec2){(float)(b0 * 0.0 + b1 * 1.0 + b2 * 1.0), (float)(b0 * 0.0 + b1 * 0.0 + b2 * 1.0)};
    }
}

/* ∂n/∂u, ∂n/∂v as pbrt-v3's Triangle::Intersect: of the interpolated normal, from the
 * vertex normals' and the uvs' differences (default uvs (0,0), (1,0), (1,1)), turned with
 * ns (sign); left as they are when the uvs are degenerate. */
static void tri_normal_derivatives(const ts_mesh *mesh, uint32_t i0, uint32_t i1, uint32_t i2, double sign,
                                   ts_interaction *si)
{
    const float *n0 = mesh->n + 3 * i0, *n1 = mesh->n + 3 * i1, *n2 = mesh->n + 3 * i2;
    double uv[3][2] = {{0, 0}, {1, 0}, {1, 1}};
    if (mesh->uv) {
        uint32_t ids[3] = {i0, i1, i2};
        for (int k = 0; k < 3; k++)
            uv[k][0] = mesh->uv[2 * ids[k]], uv[k][1] = mesh->uv[2 * ids[k] + 1];
    }
    double du02 = uv[0][0] - uv[2][0], dv02 = uv[0][1] - uv[2][1];
    double du12 = uv[1][0] - uv[2][0], dv12 = uv[1][1] - uv[2][1];
    double det = du02 * dv12 - dv02 * du12;
    if (det == 0) return;
    ts_dvec3 dn1 = {(double)n0[0] - n2[0], (double)n0[1] - n2[1], (double)n0[2] - n2[2]};
    ts_dvec3 dn2 = {(double)n1[0] - n2[0], (double)n1[1] - n2[1], (double)n1[2] - n2[2]};
    double inv = sign / det;
    si->dndu = ts_dvec3_to_vec3(ts_dvec3_scale(ts_dvec3_sub(ts_dvec3_scale(dn1, dv12), ts_dvec3_scale(dn2, dv02)), inv));
    si->dndv = ts_dvec3_to_vec3(ts_dvec3_scale(ts_dvec3_sub(ts_dvec3_scale(dn2, du02), ts_dvec3_scale(dn1, du12)), inv));
}

/* ---- the accelerator's hits: float refinement from Embree's barycentrics ----
 *
 * A hit found by Embree comes with its barycentrics (b1, b2) of p1 and p2. The point is
 * evaluated from them in float as p0 + b1·e1 + b2·e2 (e1 = p1 − p0, e2 = p2 − p0), and its
 * bound by pbrt-v3's method (§3.9.1–3.9.5: each float operation contributes (1 ± ε_m), the
 * product of n of them is within γ_n): e_k = (p_k − p0)(1 ± ε_m), b_k·e_k one more
 * rounding, the two sums one each, so
 *   |p − (p0 + b1·(p1 − p0) + b2·(p2 − p0))| ≤ γ_4·(|p0| + |b1·e1| + |b2·e2|)
 * per component; γ_5 is taken, which also covers the float evaluation of the bound (three
 * more roundings of a sum of non-negative terms) and |b_k·e_k| read from the rounded
 * product. Whatever b1 and b2 are, p0 + b1·(p1 − p0) + b2·(p2 − p0) lies exactly in the
 * plane of the float triangle, so p is within p_error of that plane and an origin offset
 * by |n|·p_error along n (interaction.h) is on the side it is sent to: what the offset
 * needs. Embree's own rounding of (b1, b2) moves p within the plane only, as pbrt-v3's
 * float barycentrics do (so, unlike the double path above, p_error does not bound the
 * distance to the exact ray's hit along the plane). pbrt-v3's own form, γ_7·Σ|b_i·p_i|
 * with b0 = 1 − b1 − b2, is not used: it assumes each b_i has a small relative error,
 * which b0 computed as 1 − b1 − b2 has not where b0 is near 0.
 *
 * Each component of the bound also gets TRI_NUDGE of the triangle's edge lengths. A
 * triangle lying in a coordinate plane (x, y or z = 0, as the floors and walls of many
 * scenes) has an exact p there and a bound of 0 along its normal, so its rays would start
 * on its plane; Embree's float test then finds the triangle a ray leaves at t ≈ 0, and the
 * skip filter (accel.c) has to reject it: on the Cornell box, without the nudge, 205 k more
 * filter calls (669 k against 463 k) and 1.5% more instructions. 2^-40 of the size is far below
 * the γ_5 term wherever that is not 0 (γ_5 ≈ 2^-21.7 of the coordinates). */
#define TRI_NUDGE 0x1p-40f
static inline ts_vec3 fabs_v(ts_vec3 a) { return (ts_vec3){fabsf(a.x), fabsf(a.y), fabsf(a.z)}; }

static inline void tri_eval_f(const ts_mesh *m, uint32_t i0, uint32_t i1, uint32_t i2, float b1, float b2,
                              float nudge, ts_vec3 *p, ts_vec3 *p_error, ts_vec2 *uv)
{
    const float *a = m->p + 3 * i0, *b = m->p + 3 * i1, *c = m->p + 3 * i2;
    ts_vec3 p0 = {a[0], a[1], a[2]};
    ts_vec3 e1 = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2 = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    ts_vec3 s1 = ts_vec3_scale(e1, b1), s2 = ts_vec3_scale(e2, b2);
    *p = ts_vec3_add(ts_vec3_add(p0, s1), s2);
    if (p_error) {
        ts_vec3 e = ts_vec3_scale(ts_vec3_add(ts_vec3_add(fabs_v(p0), fabs_v(s1)), fabs_v(s2)), ts_gamma(5));
        *p_error = (ts_vec3){e.x + nudge, e.y + nudge, e.z + nudge};
    }
    float b0 = 1 - b1 - b2;
    if (m->uv) {
        const float *uv0 = m->uv + 2 * i0, *uv1 = m->uv + 2 * i1, *uv2 = m->uv + 2 * i2;
        *uv = (ts_vec2){b0 * uv0[0] + b1 * uv1[0] + b2 * uv2[0], b0 * uv0[1] + b1 * uv1[1] + b2 * uv2[1]};
    } else {
        *uv = (ts_vec2){b1 + b2, b2}; /* default uvs (0,0), (1,0), (1,1) */
    }
}

void ts_shape_triangle_point_uv(const ts_shape *s, uint32_t prim, float b1, float b2, ts_vec3 *p, ts_vec2 *uv)
{
    const uint32_t *ix = s->mesh.index + 3 * prim;
    tri_eval_f(&s->mesh, ix[0], ix[1], ix[2], b1, b2, 0, p, NULL, uv);
}

static void triangle_interaction(const ts_shape *s, const ts_tri_cache *c, uint32_t prim, const ts_ray *ray,
                                 float t_hint, ts_interaction *si)
{
    const ts_mesh *mesh = &s->mesh;
    tri_d tr = tri_load(mesh, prim);
    ts_dvec3 o = ts_dvec3_from(ray->o), d = ts_dvec3_from(ray->d);
    double b1, b2, t;
    tri_bary(&tr, o, d, t_hint, &b1, &b2, &t);
    double b0 = 1 - b1 - b2;
    ts_dvec3 p = tri_point(&tr, b0, b1, b2);

    /* pbrt-v3's bound gamma(7)·Σ|b_i·p_i| (it contains the rounding of the double sum to
     * float), plus the slide of the hit in the plane from double round-off: a line moved
     * by δ slides δ/cosθ, and barycentrics of a sliver are 1/sin(angle) worse. */
    double g7 = ts_gamma(7);
    ts_dvec3 ab = {fabs(b0 * tr.p0.x) + fabs(b1 * tr.p1.x) + fabs(b2 * tr.p2.x),
                   fabs(b0 * tr.p0.y) + fabs(b1 * tr.p1.y) + fabs(b2 * tr.p2.y),
                   fabs(b0 * tr.p0.z) + fabs(b1 * tr.p1.z) + fabs(b2 * tr.p2.z)};
    double d_len = ts_dvec3_length(d);
    double N_len = c->n_len;
    double delta =
        DBL_SLACK * (ts_dvec3_length(ts_dvec3_sub(o, tr.p0)) + fabs(t) * d_len + c->e1_len + c->e2_len) * c->inv_sin;
    ts_dvec3 N = ts_dvec3_cross(ts_dvec3_sub(tr.p1, tr.p0), ts_dvec3_sub(tr.p2, tr.p0));
    double cos_theta = N_len > 0 && d_len > 0 ? fabs(ts_dvec3_dot(N, d)) / (N_len * d_len) : 0;
    double slide = slide_bound(delta, cos_theta, INFINITY);
    si->p = ts_dvec3_to_vec3(p);
    si->p_error = round_up_v((ts_dvec3){g7 * ab.x + slide, g7 * ab.y + slide, g7 * ab.z + slide});
    si->n = c->n;

    /* Shading normal: interpolated vertex normals, on n's side; ∂n/∂u, ∂n/∂v as pbrt-v3's
     * Triangle::Intersect: of the interpolated normal, from the vertex normals' and the
     * uvs' differences (default uvs (0,0), (1,0), (1,1)), turned with ns. */
    si->ns = si->n;
    si->dndu = si->dndv = (ts_vec3){0, 0, 0};
    si->mesh_normals = mesh->n != NULL;
    if (mesh->n) {
        ts_dvec3 n_d = N_len > 0 ? ts_dvec3_scale(N, 1 / N_len) : (ts_dvec3){0, 0, 1};
        const float *n0 = mesh->n + 3 * tr.i0, *n1 = mesh->n + 3 * tr.i1, *n2 = mesh->n + 3 * tr.i2;
        ts_dvec3 ns = {b0 * n0[0] + b1 * n1[0] + b2 * n2[0], b0 * n0[1] + b1 * n1[1] + b2 * n2[1],
                       b0 * n0[2] + b1 * n1[2] + b2 * n2[2]};
        double sign = 1;
        if (ts_dvec3_length(ns) > 0) {
            ns = ts_dvec3_normalize(ns);
            if (ts_dvec3_dot(ns, n_d) < 0) ns = ts_dvec3_scale(ns, -1), sign = -1;
            si->ns = ts_dvec3_to_vec3(ns);
        }
        if (!s->no_normal_derivatives) tri_normal_derivatives(mesh, tr.i0, tr.i1, tr.i2, sign, si);
    }

    tri_uv(mesh, &tr, b0, b1, b2, &si->uv);
    si->dpdu = c->dpdu;
    si->dpdv = c->dpdv;
    /* to_unit_f(−d), whose length is d_len bit for bit ((−x)² = x²). */
    ts_dvec3 wo = ts_dvec3_scale(d, -1);
    si->wo = ts_dvec3_to_vec3(d_len > 0 ? ts_dvec3_scale(wo, 1.0 / d_len) : wo);
    si->t = (float)t;
    si->prim = prim;
}

void ts_shape_interaction(const ts_shape *s, uint32_t shape_index, uint32_t prim, const ts_ray *ray, float t,
                          ts_interaction *si)
{
    si->shape = shape_index;
    si->inst = 0;
    si->time = ray->time;
    if (s->type == TS_SHAPE_MESH) {
        ts_tri_cache c;
        ts_shape_triangle_cache_init(s, prim, &c);
        triangle_interaction(s, &c, prim, ray, t, si);
        return;
    }
    if (s->type == TS_SHAPE_CURVE) {
        ts_curve_interaction_at(&s->curve, s->reverse_orientation, shape_index, prim, ray, t, si);
        return;
    }
    /* Re-solve: the same computation with tmax just above t finds the same root. */
    obj_hit h;
    if (!analytic_hit(s, ray, ts_next_float_up(t), &h) && !analytic_hit(s, ray, INFINITY, &h)) {
        /* Not a hit of this shape (caller error): reproject the point at t. */
        obj_ray R = to_object(s, ray);
        ts_dvec3 p = ts_dvec3_add(R.o, ts_dvec3_scale(R.d, t));
        switch (s->type) {
        case TS_SHAPE_SPHERE: p = ts_dvec3_scale(p, s->sphere.radius / fmax(ts_dvec3_length(p), DBL_MIN)); break;
        case TS_SHAPE_DISK: p.z = 0; break;
        default: {
            double rh = fmax(hypot(p.x, p.y), DBL_MIN);
            p.x *= s->cylinder.radius / rh;
            p.y *= s->cylinder.radius / rh;
            break;
        }
        }
        h.t = t;
        h.p = p;
        h.err = ts_dvec3_length(ts_dvec3_sub(p, ts_dvec3_add(R.o, ts_dvec3_scale(R.d, t))));
    }
    analytic_interaction(s, ray, &h, si);
}

void ts_shape_triangle_interaction_cached(const ts_shape *s, const ts_tri_cache *c, uint32_t shape_index,
                                          uint32_t prim, const ts_ray *ray, float t, float b1, float b2,
                                          ts_interaction *si)
{
    const ts_mesh *mesh = &s->mesh;
    const uint32_t *ix = mesh->index + 3 * prim;
    uint32_t i0 = ix[0], i1 = ix[1], i2 = ix[2];
    si->shape = shape_index;
    si->inst = 0;
    si->time = ray->time;
    tri_eval_f(mesh, i0, i1, i2, b1, b2, TRI_NUDGE * (float)(c->e1_len + c->e2_len), &si->p, &si->p_error, &si->uv);
    si->n = c->n;
    si->ns = si->n;
    si->dndu = si->dndv = (ts_vec3){0, 0, 0};
    si->mesh_normals = mesh->n != NULL;
    if (mesh->n) {
        /* As triangle_interaction, the interpolation in float. */
        float b0 = 1 - b1 - b2;
        const float *n0 = mesh->n + 3 * i0, *n1 = mesh->n + 3 * i1, *n2 = mesh->n + 3 * i2;
        ts_vec3 ns = {b0 * n0[0] + b1 * n1[0] + b2 * n2[0], b0 * n0[1] + b1 * n1[1] + b2 * n2[1],
                      b0 * n0[2] + b1 * n1[2] + b2 * n2[2]};
        double sign = 1;
        float len = ts_vec3_length(ns);
        if (len > 0 && isfinite(len)) {
            ns = ts_vec3_scale(ns, 1 / len);
            if (ts_vec3_dot(ns, c->n) < 0) ns = ts_vec3_neg(ns), sign = -1;
            si->ns = ns;
        }
        if (!s->no_normal_derivatives) tri_normal_derivatives(mesh, i0, i1, i2, sign, si);
    }
    si->dpdu = c->dpdu;
    si->dpdv = c->dpdv;
    /* −d/|d| in double, as triangle_interaction. */
    ts_dvec3 d = ts_dvec3_from(ray->d);
    double d_len = ts_dvec3_length(d);
    ts_dvec3 wo = ts_dvec3_scale(d, -1);
    si->wo = ts_dvec3_to_vec3(d_len > 0 ? ts_dvec3_scale(wo, 1.0 / d_len) : wo);
    si->t = t;
    si->prim = prim;
}

/* ---- bounds and area ---- */

static ts_bounds3 round_out(const double lo[3], const double hi[3])
{
    ts_bounds3 b;
    float l[3], u[3];
    for (int i = 0; i < 3; i++) {
        l[i] = (float)lo[i];
        if ((double)l[i] > lo[i]) l[i] = ts_next_float_down(l[i]);
        l[i] = ts_next_float_down(l[i]); /* covers the double round-off of the transform */
        u[i] = (float)hi[i];
        if ((double)u[i] < hi[i]) u[i] = ts_next_float_up(u[i]);
        u[i] = ts_next_float_up(u[i]);
    }
    b.lo = (ts_vec3){l[0], l[1], l[2]};
    b.hi = (ts_vec3){u[0], u[1], u[2]};
    return b;
}

ts_bounds3 ts_shape_triangle_bounds(const ts_shape *s, uint32_t prim)
{
    ts_bounds3 b = ts_bounds3_empty();
    if (s->type != TS_SHAPE_MESH || prim >= s->mesh.n_triangles) return b;
    for (int k = 0; k < 3; k++) {
        const float *v = s->mesh.p + 3 * s->mesh.index[3 * prim + k];
        b = ts_bounds3_extend(b, (ts_vec3){v[0], v[1], v[2]});
    }
    return b;
}

ts_bounds3 ts_shape_bounds(const ts_shape *s)
{
    if (s->type == TS_SHAPE_CURVE) return ts_curve_bounds(&s->curve);
    if (s->type == TS_SHAPE_MESH) {
        ts_bounds3 b = ts_bounds3_empty();
        for (uint32_t i = 0; i < s->mesh.n_triangles; i++) b = ts_bounds3_union(b, ts_shape_triangle_bounds(s, i));
        return b;
    }
    double lo_o[3], hi_o[3];
    switch (s->type) {
    case TS_SHAPE_SPHERE: {
        double r = s->sphere.radius;
        lo_o[0] = lo_o[1] = lo_o[2] = -r;
        hi_o[0] = hi_o[1] = hi_o[2] = r;
        if (s->partial) lo_o[2] = s->sphere.z_min, hi_o[2] = s->sphere.z_max; /* pbrt-v3's bound */
        break;
    }
    case TS_SHAPE_DISK: {
        double r = s->disk.radius;
        lo_o[0] = lo_o[1] = -r;
        hi_o[0] = hi_o[1] = r;
        lo_o[2] = hi_o[2] = 0;
        break;
    }
    default: {
        double r = s->cylinder.radius;
        lo_o[0] = lo_o[1] = -r;
        hi_o[0] = hi_o[1] = r;
        lo_o[2] = 0;
        hi_o[2] = s->cylinder.height;
        break;
    }
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; c++) {
        ts_dvec3 q = {(c & 1) ? hi_o[0] : lo_o[0], (c & 2) ? hi_o[1] : lo_o[1], (c & 4) ? hi_o[2] : lo_o[2]};
        ts_dvec3 w = ts_xform_point(&s->to_world, q);
        double wv[3] = {w.x, w.y, w.z};
        for (int i = 0; i < 3; i++) {
            lo[i] = dmin(lo[i], wv[i]);
            hi[i] = dmax(hi[i], wv[i]);
        }
    }
    return round_out(lo, hi);
}

/* Perimeter of an ellipse with semi-axes a, b (Ramanujan's second approximation:
 * exact for circles, relative error < 4e-5 at any eccentricity). */
static double ellipse_perimeter(double a, double b)
{
    if (a + b == 0) return 0;
    double h = (a - b) / (a + b);
    h *= h;
    return TS_PI_D * (a + b) * (1 + 3 * h / (10 + sqrt(4 - 3 * h)));
}

/* Eigenvalues of a symmetric 3×3 matrix (closed form, Smith 1961), descending. */
static void sym3_eigenvalues(const double A[3][3], double ev[3])
{
    double p1 = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
    double q = (A[0][0] + A[1][1] + A[2][2]) / 3;
    if (p1 == 0) {
        ev[0] = A[0][0], ev[1] = A[1][1], ev[2] = A[2][2];
    } else {
        double p2 = (A[0][0] - q) * (A[0][0] - q) + (A[1][1] - q) * (A[1][1] - q) + (A[2][2] - q) * (A[2][2] - q) + 2 * p1;
        double p = sqrt(p2 / 6);
        double B[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) B[i][j] = (A[i][j] - (i == j ? q : 0)) / p;
        double r = (B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) - B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
                    B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0])) / 2;
        double phi = r <= -1 ? TS_PI_D / 3 : (r >= 1 ? 0 : acos(r) / 3);
        ev[0] = q + 2 * p * cos(phi);
        ev[2] = q + 2 * p * cos(phi + 2 * TS_PI_D / 3);
        ev[1] = 3 * q - ev[0] - ev[2];
    }
    for (int i = 0; i < 3; i++) ev[i] = fmax(ev[i], 0.0);
}

double ts_shape_object_area(const ts_shape *s)
{
    double phi_max = s->partial ? s->phi_max : TWO_PI_D;
    switch (s->type) {
    case TS_SHAPE_SPHERE:
        if (s->partial) return phi_max * s->sphere.radius * (s->sphere.z_max - s->sphere.z_min);
        return 4.0 * TS_PI_D * s->sphere.radius * s->sphere.radius;
    case TS_SHAPE_DISK:
        if (s->partial)
            return phi_max * 0.5 * (s->disk.radius * s->disk.radius - s->disk.inner_radius * s->disk.inner_radius);
        return TS_PI_D * (s->disk.radius * s->disk.radius - s->disk.inner_radius * s->disk.inner_radius);
    case TS_SHAPE_CYLINDER:
        if (s->partial) return phi_max * s->cylinder.radius * s->cylinder.height;
        return 2.0 * TS_PI_D * s->cylinder.radius * s->cylinder.height;
    case TS_SHAPE_MESH:
    case TS_SHAPE_CURVE: break;
    }
    return 0;
}

bool ts_shape_is_similarity(const ts_shape *s)
{
    const ts_mat4 *m = &s->to_world.m;
    ts_dvec3 c[3];
    for (int j = 0; j < 3; j++) c[j] = (ts_dvec3){m->m[0][j], m->m[1][j], m->m[2][j]};
    double l0 = ts_dvec3_length(c[0]), l1 = ts_dvec3_length(c[1]), l2 = ts_dvec3_length(c[2]);
    double tol = 1e-9 * l0 * l0;
    return fabs(l0 - l1) <= 1e-9 * l0 && fabs(l0 - l2) <= 1e-9 * l0 && fabs(ts_dvec3_dot(c[0], c[1])) <= tol &&
           fabs(ts_dvec3_dot(c[0], c[2])) <= tol && fabs(ts_dvec3_dot(c[1], c[2])) <= tol;
}

/* World area of a partial sphere or cylinder: the object area times the scale² under a
 * similarity; else the midpoint rule over pbrt-v3's parameter domain of the area
 * Jacobian |det M|·|M^-T n_obj| (Nanson), smooth on the domain: relative error below
 * 1e-6 at 256 × 512 points for any transform whose singular values are within a factor
 * 10 of each other (checked against 4× the points in tests/test_shape.c). */
static double partial_area(const ts_shape *s)
{
    const ts_xform *X = &s->to_world;
    double a_obj = ts_shape_object_area(s);
    if (ts_shape_is_similarity(s)) {
        double l0 = ts_dvec3_length((ts_dvec3){X->m.m[0][0], X->m.m[1][0], X->m.m[2][0]});
        return a_obj * l0 * l0;
    }
    double det = fabs(det3(&X->m));
    const int nz = s->type == TS_SHAPE_SPHERE ? 256 : 1, np = 512;
    double sum = 0, r = s->sphere.radius;
    for (int i = 0; i < nz; i++) {
        ts_dvec3 n = {0, 0, 0};
        double ring = 1;
        if (s->type == TS_SHAPE_SPHERE) {
            /* dA = r dz dφ on the sphere: uniform in z. */
            double z = s->sphere.z_min + (i + 0.5) * (s->sphere.z_max - s->sphere.z_min) / nz;
            n.z = z / r;
            ring = sqrt(fmax(0.0, 1 - n.z * n.z));
        }
        for (int k = 0; k < np; k++) {
            double ph = (k + 0.5) * s->phi_max / np;
            ts_dvec3 nk = {ring * cos(ph), ring * sin(ph), n.z};
            sum += det * ts_dvec3_length(ts_xform_normal(X, nk));
        }
    }
    return a_obj * sum / ((double)nz * np);
}

/* World-space area. Meshes and disks: exact. Spheres and cylinders: exact under any
 * similarity (rotation, uniform scale, translation) and, for cylinders, also under a scale
 * along the axis; under other non-uniform scales the ellipsoid's area by Thomsen's formula
 * (≤ 1.1% off) and the elliptic tube's by Ramanujan's perimeter (≤ 4e-5 off). Partial
 * spheres and cylinders: partial_area. */
double ts_shape_area(const ts_shape *s, uint32_t prim)
{
    if (s->type == TS_SHAPE_CURVE) return ts_curve_area(&s->curve);
    if (s->type == TS_SHAPE_MESH) {
        if (prim >= s->mesh.n_triangles) return 0;
        tri_d tr = tri_load(&s->mesh, prim);
        return 0.5 * ts_dvec3_length(ts_dvec3_cross(ts_dvec3_sub(tr.p1, tr.p0), ts_dvec3_sub(tr.p2, tr.p0)));
    }
    const ts_xform *X = &s->to_world;
    const double(*m)[4] = X->m.m;
    double det = fabs(det3(&X->m));
    if (s->partial && s->type != TS_SHAPE_DISK) return partial_area(s);
    switch (s->type) {
    case TS_SHAPE_SPHERE: {
        /* Ellipsoid with semi-axes r·σ_i (σ_i the singular values of M): Knud Thomsen's
         * formula, exact for a sphere (any similarity), within 1.1% otherwise. */
        double A[3][3], ev[3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) A[i][j] = m[0][i] * m[0][j] + m[1][i] * m[1][j] + m[2][i] * m[2][j];
        sym3_eigenvalues(A, ev);
        double r = s->sphere.radius, pw = 1.6075;
        double a = pow(r * r * ev[0], pw / 2), b = pow(r * r * ev[1], pw / 2), c = pow(r * r * ev[2], pw / 2);
        if (ev[0] == ev[1] && ev[1] == ev[2]) return 4 * TS_PI_D * r * r * ev[0];
        return 4 * TS_PI_D * pow((a * b + a * c + b * c) / 3, 1 / pw);
    }
    case TS_SHAPE_DISK: {
        /* Exact for any affine map: area scales by |det M|·|M^-T·e_z|. */
        double r = s->disk.radius, ri = s->disk.inner_radius;
        double scale = det * ts_dvec3_length(ts_xform_normal(X, (ts_dvec3){0, 0, 1}));
        if (s->partial) return ts_shape_object_area(s) * scale;
        return TS_PI_D * (r * r - ri * ri) * scale;
    }
    default: {
        /* ∂p/∂φ × ∂p/∂z = |det M|·r·|M^-T·(cos φ, sin φ, 0)|: the integral over φ is the
         * perimeter of the ellipse with semi-axes the singular values of the 3×2 matrix
         * [M^-T e_x, M^-T e_y]. Exact when the world cross-section is a circle (uniform
         * scale, or any scale along the axis), Ramanujan's approximation otherwise. */
        ts_dvec3 cx = ts_xform_normal(X, (ts_dvec3){1, 0, 0}), cy = ts_xform_normal(X, (ts_dvec3){0, 1, 0});
        double g11 = ts_dvec3_dot(cx, cx), g22 = ts_dvec3_dot(cy, cy), g12 = ts_dvec3_dot(cx, cy);
        double mean = 0.5 * (g11 + g22), diff = sqrt(0.25 * (g11 - g22) * (g11 - g22) + g12 * g12);
        double s1 = sqrt(fmax(mean + diff, 0.0)), s2 = sqrt(fmax(mean - diff, 0.0));
        return det * s->cylinder.radius * s->cylinder.height * ellipse_perimeter(s1, s2);
    }
    }
}

/* ---- ray spawning ---- */

ts_ray ts_spawn_ray(const ts_interaction *si, const ts_shape *shapes, ts_vec3 d)
{
    bool mesh = shapes && shapes[si->shape].type == TS_SHAPE_MESH;
    ts_ray r = ts_spawn_ray_ex(si->p, si->p_error, si->n, d, mesh ? si->shape : TS_NONE, mesh ? si->prim : TS_NONE,
                               mesh ? si->inst : 0);
    r.time = si->time;
    return r;
}

ts_ray ts_spawn_ray_to(const ts_interaction *si, const ts_shape *shapes, ts_vec3 p_to, ts_vec3 p_to_error,
                       ts_vec3 n_to)
{
    bool mesh = shapes && shapes[si->shape].type == TS_SHAPE_MESH;
    ts_vec3 o = ts_offset_ray_origin(si->p, si->p_error, si->n, ts_vec3_sub(p_to, si->p));
    ts_vec3 pt = ts_offset_ray_origin(p_to, p_to_error, n_to, ts_vec3_sub(o, p_to));
    ts_ray r = {o, ts_vec3_sub(pt, o), 1 - TS_SHADOW_EPSILON, mesh ? si->shape : TS_NONE, mesh ? si->prim : TS_NONE,
                mesh ? si->inst : 0, si->time};
    return r;
}
