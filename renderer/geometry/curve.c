/* curve.c — pbrt-v3's curve shape; see curve.h.
 *
 * Design note. The segment conversion follows pbrt-v3's CreateCurveShape step for step in
 * float (so a .pbrt curve has pbrt-v3's control points to the bit); the hit quantities are
 * computed in double from Embree's (t, u, v) and the ray, with pbrt-v3's formulas written
 * frame-free: pbrt-v3's ray space has z along the ray and a right-handed (x, y), so its
 * (−y, x, 0) of ∂p/∂u is d × ∂p/∂u and its 2-D edge function is ((c − o) × ∂c/∂u)·d. */
#include "geometry/curve.h"

#include <math.h>
#include <stddef.h>

static inline float lerpf(float t, float a, float b) { return (1 - t) * a + t * b; }

static void lerp3(float t, const float *a, const float *b, float *out)
{
    for (int k = 0; k < 3; k++) out[k] = lerpf(t, a[k], b[k]);
}

bool ts_curve_segment_count(ts_curve_basis basis, int degree, uint64_t n_points, uint32_t *n_segments)
{
    *n_segments = 0;
    if (degree != 2 && degree != 3) return false;
    if (n_points > UINT32_MAX) return false;
    if (basis == TS_CURVE_BEZIER) {
        /* pbrt-v3: ((ncp − 1 − degree) % degree) != 0 refuses, with C's remainder: one point
         * passes as (−degree) % degree == 0 and makes no segment. */
        int64_t r = ((int64_t)n_points - 1 - degree) % degree;
        if (r != 0 || n_points == 0) return false;
        *n_segments = (uint32_t)((n_points - 1) / (uint64_t)degree);
        return true;
    }
    if (n_points < (uint64_t)degree + 1) return false;
    *n_segments = (uint32_t)(n_points - (uint64_t)degree);
    return true;
}

void ts_curve_bezier_segment(ts_curve_basis basis, int degree, const float *P, uint32_t seg, float out[4][3])
{
    if (basis == TS_CURVE_BEZIER) {
        const float *b = P + 3 * (size_t)seg * (size_t)degree;
        if (degree == 2) { /* elevated to degree 3 */
            for (int k = 0; k < 3; k++) out[0][k] = b[k], out[3][k] = b[6 + k];
            lerp3(2.f / 3.f, b, b + 3, out[1]);
            lerp3(1.f / 3.f, b + 3, b + 6, out[2]);
        } else {
            for (int i = 0; i < 4; i++)
                for (int k = 0; k < 3; k++) out[i][k] = b[3 * i + k];
        }
        return;
    }
    const float *b = P + 3 * (size_t)seg; /* uniform B-spline: one point per segment */
    if (degree == 2) {
        /* Blossoms p01, p12, p23 → Bézier p11, p12, p22, then elevated. */
        float p11[3], p22[3];
        lerp3(0.5f, b, b + 3, p11);
        lerp3(0.5f, b + 3, b + 6, p22);
        for (int k = 0; k < 3; k++) out[0][k] = p11[k], out[3][k] = p22[k];
        lerp3(2.f / 3.f, p11, b + 3, out[1]);
        lerp3(1.f / 3.f, b + 3, p22, out[2]);
        return;
    }
    /* p012, p123, p234, p345 → p222, p223, p233, p333 */
    float p122[3], p223[3], p233[3], p334[3];
    lerp3(2.f / 3.f, b, b + 3, p122);
    lerp3(1.f / 3.f, b + 3, b + 6, p223);
    lerp3(2.f / 3.f, b + 3, b + 6, p233);
    lerp3(1.f / 3.f, b + 6, b + 9, p334);
    lerp3(0.5f, p122, p223, out[0]);
    for (int k = 0; k < 3; k++) out[1][k] = p223[k], out[2][k] = p233[k];
    lerp3(0.5f, p233, p334, out[3]);
}

static inline ts_dvec3 cpt(const ts_curve *c, uint32_t seg, int i)
{
    const float *q = c->cp + 16 * (size_t)seg + 4 * i;
    return (ts_dvec3){q[0], q[1], q[2]};
}

static inline double radius(const ts_curve *c, uint32_t seg, int i) { return c->cp[16 * (size_t)seg + 4 * i + 3]; }

/* pbrt-v3's refinement measure: straight pieces a cubic with control points cp needs for a
 * flatness of width·TS_CURVE_FLATNESS (√(√2·6·L0 / (8·flatness)), L0 its largest second
 * difference; the chord's distance from the cubic is at most that flatness). */
static double pieces_needed(const ts_dvec3 cp[4], double width)
{
    double L0 = 0;
    for (int i = 0; i < 2; i++) {
        ts_dvec3 a = cp[i], b = cp[i + 1], d = cp[i + 2];
        L0 = fmax(L0, fmax(fabs(a.x - 2 * b.x + d.x), fmax(fabs(a.y - 2 * b.y + d.y), fabs(a.z - 2 * b.z + d.z))));
    }
    double eps = width * TS_CURVE_FLATNESS;
    double n = eps > 0 ? sqrt(1.41421356237 * 6 * L0 / (8 * eps)) : INFINITY;
    return isnan(n) ? INFINITY : n;
}

uint32_t ts_curve_split(const double cp[4][3], double width)
{
    ts_dvec3 p[4];
    for (int i = 0; i < 4; i++) p[i] = (ts_dvec3){cp[i][0], cp[i][1], cp[i][2]};
    double n = pieces_needed(p, width);
    uint32_t k = 1; /* halving a piece quarters its second differences: halves the pieces it needs */
    while (k < TS_CURVE_MAX_SPLIT && n / k > TS_CURVE_MAX_TESSELLATION) k *= 2;
    return k;
}

void ts_curve_piece(const double cp[4][3], double u0, double u1, double out[4][3])
{
    const double us[4][3] = {{u0, u0, u0}, {u0, u0, u1}, {u0, u1, u1}, {u1, u1, u1}};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++) {
            double a[3], b[2];
            for (int j = 0; j < 3; j++) a[j] = (1 - us[i][0]) * cp[j][k] + us[i][0] * cp[j + 1][k];
            for (int j = 0; j < 2; j++) b[j] = (1 - us[i][1]) * a[j] + us[i][1] * a[j + 1];
            out[i][k] = (1 - us[i][2]) * b[0] + us[i][2] * b[1];
        }
}

uint32_t ts_curve_tessellation(const ts_curve *c)
{
    double worst = 4;
    for (uint32_t s = 0; s < c->n_pieces; s++) {
        ts_dvec3 p[4];
        for (int i = 0; i < 4; i++) p[i] = cpt(c, s, i);
        double n = pieces_needed(p, 2 * fmax(radius(c, s, 0), radius(c, s, 3)));
        if (n > worst) worst = fmin(n, TS_CURVE_MAX_TESSELLATION);
    }
    /* Embree's rates 4, 8, 16 (a power of two: its pieces then meet at pbrt-v3's split points). */
    return worst <= 4 ? 4 : worst <= 8 ? 8 : TS_CURVE_MAX_TESSELLATION;
}

ts_bounds3 ts_curve_bounds(const ts_curve *c)
{
    ts_bounds3 b = ts_bounds3_empty();
    float r = 0;
    for (uint32_t s = 0; s < c->n_pieces; s++)
        for (int i = 0; i < 4; i++) {
            const float *q = c->cp + 16 * (size_t)s + 4 * i;
            b = ts_bounds3_extend(b, (ts_vec3){q[0], q[1], q[2]});
            r = fmaxf(r, q[3]);
        }
    if (ts_bounds3_is_empty(b)) return b;
    b.lo = (ts_vec3){ts_next_float_down(b.lo.x - r), ts_next_float_down(b.lo.y - r), ts_next_float_down(b.lo.z - r)};
    b.hi = (ts_vec3){ts_next_float_up(b.hi.x + r), ts_next_float_up(b.hi.y + r), ts_next_float_up(b.hi.z + r)};
    return b;
}

double ts_curve_area(const ts_curve *c)
{
    double a = 0;
    for (uint32_t s = 0; s < c->n_pieces; s++) {
        double len = 0;
        for (int i = 0; i < 3; i++) len += ts_dvec3_length(ts_dvec3_sub(cpt(c, s, i + 1), cpt(c, s, i)));
        a += len * (radius(c, s, 0) + radius(c, s, 3)); /* mean width = r0 + r3 */
    }
    return a;
}

ts_dvec3 ts_curve_ribbon_normal(const ts_curve *c, uint32_t seg, double u)
{
    const float *a = c->n + 3 * (size_t)seg, *b = a + 3;
    ts_dvec3 n0 = {a[0], a[1], a[2]}, n1 = {b[0], b[1], b[2]};
    double cosang = ts_dvec3_dot(n0, n1);
    double angle = acos(cosang < 0 ? 0 : cosang > 1 ? 1 : cosang); /* pbrt-v3's Clamp(·, 0, 1) */
    double sa = sin(angle);
    if (!(sa > 0)) return n0; /* equal normals (pbrt-v3: 0·∞) */
    double s0 = sin((1 - u) * angle) / sa, s1 = sin(u * angle) / sa;
    return ts_dvec3_add(ts_dvec3_scale(n0, s0), ts_dvec3_scale(n1, s1));
}

/* Piece i's u in its segment for Embree's u along the piece. */
static inline double segment_u(const ts_curve *c, uint32_t i, double u_piece)
{
    double u0 = c->u_range[2 * (size_t)i], u1 = c->u_range[2 * (size_t)i + 1];
    return u0 + (u1 - u0) * u_piece;
}

bool ts_curve_ribbon_covers(const ts_curve *c, uint32_t piece, float u, float v, ts_vec3 d)
{
    ts_dvec3 D = ts_dvec3_from(d);
    double len = ts_dvec3_length(D);
    if (!(len > 0) || piece >= c->n_pieces) return false;
    double u01 = u < 0 ? 0 : u > 1 ? 1 : u;
    double k = fabs(ts_dvec3_dot(ts_curve_ribbon_normal(c, c->segment[piece], segment_u(c, piece, u01)), D)) / len;
    return fabs((double)v) <= k;
}

/* The Bézier derivative at u of segment seg, pbrt-v3's EvalBezier: 3·(b1 − b0) of the last
 * de Casteljau step, or cp3 − cp0 where that vanishes. */
static ts_dvec3 bezier_derivative(const ts_curve *c, uint32_t seg, double u, ts_dvec3 *point)
{
    ts_dvec3 p[4];
    for (int i = 0; i < 4; i++) p[i] = cpt(c, seg, i);
    ts_dvec3 a[3], b[2];
    for (int i = 0; i < 3; i++) a[i] = ts_dvec3_add(ts_dvec3_scale(p[i], 1 - u), ts_dvec3_scale(p[i + 1], u));
    for (int i = 0; i < 2; i++) b[i] = ts_dvec3_add(ts_dvec3_scale(a[i], 1 - u), ts_dvec3_scale(a[i + 1], u));
    if (point) *point = ts_dvec3_add(ts_dvec3_scale(b[0], 1 - u), ts_dvec3_scale(b[1], u));
    ts_dvec3 d = ts_dvec3_sub(b[1], b[0]);
    if (ts_dvec3_dot(d, d) > 0) return ts_dvec3_scale(d, 3);
    return ts_dvec3_sub(p[3], p[0]);
}

/* A unit vector perpendicular to unit a (for degenerate crosses). */
static ts_dvec3 any_perpendicular(ts_dvec3 a)
{
    ts_dvec3 t = fabs(a.x) > fabs(a.z) ? (ts_dvec3){-a.y, a.x, 0} : (ts_dvec3){0, -a.z, a.y};
    double l = ts_dvec3_length(t);
    return l > 0 ? ts_dvec3_scale(t, 1 / l) : (ts_dvec3){1, 0, 0};
}

static ts_dvec3 unit_or(ts_dvec3 v, ts_dvec3 fallback)
{
    double l = ts_dvec3_length(v);
    return l > 0 && isfinite(l) ? ts_dvec3_scale(v, 1 / l) : fallback;
}

void ts_curve_interaction(const ts_curve *c, bool reverse_orientation, uint32_t shape_index, uint32_t seg,
                          const ts_ray *ray, float t, float u_hit, float v_hit, ts_interaction *si)
{
    if (seg >= c->n_pieces) seg = c->n_pieces ? c->n_pieces - 1 : 0;
    double u = u_hit < 0 ? 0 : u_hit > 1 ? 1 : (double)u_hit; /* along the piece */
    double du = c->u_range[2 * (size_t)seg + 1] - c->u_range[2 * (size_t)seg];
    double u_seg = segment_u(c, seg, u);
    double ve = v_hit < -1 ? -1 : v_hit > 1 ? 1 : (double)v_hit;
    ts_dvec3 D = ts_dvec3_from(ray->d), O = ts_dvec3_from(ray->o);
    double len = ts_dvec3_length(D);
    ts_dvec3 dir = len > 0 ? ts_dvec3_scale(D, 1 / len) : (ts_dvec3){0, 0, 1};
    ts_dvec3 dpdu = ts_dvec3_scale(bezier_derivative(c, seg, u, NULL), du > 0 ? 1 / du : 1); /* ∂p/∂u_seg */
    ts_dvec3 a = unit_or(dpdu, any_perpendicular(dir));
    double w = 2 * ((1 - u) * radius(c, seg, 0) + u * radius(c, seg, 3)); /* lerp(u, w0, w1) */
    double sigma = c->mirrored ? -1 : 1;
    double hit_w = w, v;
    ts_dvec3 dpdv;
    if (c->type == TS_CURVE_RIBBON) {
        ts_dvec3 nh = ts_curve_ribbon_normal(c, c->segment[seg], u_seg);
        double k = fabs(ts_dvec3_dot(nh, dir));
        hit_w = w * k;
        v = 0.5 + 0.5 * ve / (k > 0 ? k : 1);
        dpdv = ts_dvec3_scale(unit_or(ts_dvec3_cross(nh, dpdu), any_perpendicular(a)), sigma * hit_w);
    } else {
        v = 0.5 + 0.5 * ve;
        ts_dvec3 across = unit_or(ts_dvec3_cross(dir, dpdu), any_perpendicular(a));
        dpdv = ts_dvec3_scale(across, sigma * hit_w);
        if (c->type == TS_CURVE_CYLINDER) {
            /* pbrt-v3's Rotate(−θ, ∂p/∂u), θ = lerp(v, −90°, 90°); mirrored, the turn's sense
             * flips with the space. dpdv ⊥ a, so R·dpdv = dpdv·cos φ + (a × dpdv)·sin φ. */
            double phi = -sigma * (v - 0.5) * TS_PI_D;
            dpdv = ts_dvec3_add(ts_dvec3_scale(dpdv, cos(phi)), ts_dvec3_scale(ts_dvec3_cross(a, dpdv), sin(phi)));
        }
    }
    if (v < 0) v = 0;
    if (v > 1) v = 1;
    ts_dvec3 n = unit_or(ts_dvec3_cross(dpdu, dpdv), ts_dvec3_scale(dir, -1));
    if (reverse_orientation) n = ts_dvec3_scale(n, -1);

    ts_dvec3 p = ts_dvec3_add(O, ts_dvec3_scale(D, t));
    *si = (ts_interaction){0};
    si->p = ts_dvec3_to_vec3(p);
    /* pbrt-v3's 2·hitWidth, plus the float rounding of Embree's t and of p. */
    double e_w = 2 * hit_w;
    si->p_error = (ts_vec3){(float)(e_w + 0x1p-20 * (fabs(O.x) + fabs(t * D.x))),
                            (float)(e_w + 0x1p-20 * (fabs(O.y) + fabs(t * D.y))),
                            (float)(e_w + 0x1p-20 * (fabs(O.z) + fabs(t * D.z)))};
    si->p_error = (ts_vec3){ts_next_float_up(si->p_error.x), ts_next_float_up(si->p_error.y),
                            ts_next_float_up(si->p_error.z)};
    si->n = si->ns = ts_dvec3_to_vec3(n);
    si->dpdu = ts_dvec3_to_vec3(dpdu);
    si->dpdv = ts_dvec3_to_vec3(dpdv);
    si->uv = (ts_vec2){(float)u_seg, (float)v};
    si->wo = ts_dvec3_to_vec3(ts_dvec3_scale(dir, -1));
    si->t = t;
    si->time = ray->time;
    si->shape = shape_index;
    si->prim = seg;
}

void ts_curve_interaction_at(const ts_curve *c, bool reverse_orientation, uint32_t shape_index, uint32_t seg,
                             const ts_ray *ray, float t, ts_interaction *si)
{
    if (seg >= c->n_pieces) seg = c->n_pieces ? c->n_pieces - 1 : 0;
    ts_dvec3 D = ts_dvec3_from(ray->d), O = ts_dvec3_from(ray->o);
    double len = ts_dvec3_length(D);
    ts_dvec3 dir = len > 0 ? ts_dvec3_scale(D, 1 / len) : (ts_dvec3){0, 0, 1};
    /* The distance from the ray's line to the curve point at u, in the plane ⊥ dir. */
    double best = INFINITY, u_best = 0.5;
    double lo = 0, hi = 1;
    for (int pass = 0; pass < 3; pass++) {
        double u0 = lo, du = (hi - lo) / 256;
        for (int k = 0; k <= 256; k++) {
            double u = u0 + k * du;
            ts_dvec3 q;
            bezier_derivative(c, seg, u, &q);
            ts_dvec3 r = ts_dvec3_sub(q, O);
            r = ts_dvec3_sub(r, ts_dvec3_scale(dir, ts_dvec3_dot(r, dir)));
            double d2 = ts_dvec3_dot(r, r);
            if (d2 < best) best = d2, u_best = u;
        }
        lo = fmax(0, u_best - du), hi = fmin(1, u_best + du);
    }
    ts_dvec3 q;
    ts_dvec3 dq = bezier_derivative(c, seg, u_best, &q);
    ts_dvec3 r = ts_dvec3_sub(q, O);
    double edge = ts_dvec3_dot(ts_dvec3_cross(r, dq), dir); /* pbrt-v3's edge function */
    double w = 2 * ((1 - u_best) * radius(c, seg, 0) + u_best * radius(c, seg, 3));
    double ve = w > 0 ? 2 * sqrt(best) / w : 0;
    ts_curve_interaction(c, reverse_orientation, shape_index, seg, ray, t, (float)u_best, (float)(edge > 0 ? ve : -ve),
                         si);
}
