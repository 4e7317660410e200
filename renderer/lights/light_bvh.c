/* light_bvh.c — light selection by a hierarchy of light bounds (light_bvh.h). */
#include "lights/light_bvh.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>


#define BUCKETS 12
#define COUNT_SPLIT_DEPTH 32 /* from here on, splits at the middle of the list (depth ≤ 32 + log2 n ≤ 64) */

static double clamp1(double x) { return x < -1 ? -1 : x > 1 ? 1 : x; }

static ts_light_bounds unbounded(void)
{
    ts_light_bounds lb;
    memset(&lb, 0, sizeof lb);
    lb.box = ts_bounds3_empty();
    return lb;
}

/* ---------------------------------------------------------------- importance */

/* Importance (float: the margin of the angles covers its rounding; the hierarchy's choices
 * are ratios of these, computed alike by sample and pmf). q: the bounds in the form the
 * walk reads (ts_light_bvh_node). */
static float importance_q(const ts_light_bvh_node *q, ts_vec3 p, ts_vec3 n)
{
    if (!(q->phi > 0)) return 0;
    ts_vec3 v = ts_vec3_sub(p, q->center);
    float d2_true = ts_vec3_dot(v, v), d2 = fmaxf(d2_true, q->r2);
    if (!(d2 > 0)) d2 = 1e-30f;
    /* the directions from the bounding sphere to p: within θ_b of the centre's (all from inside) */
    float cos_b = -1, sin_b = 0;
    if (d2_true > q->r2) {
        float sin2 = q->r2 / d2_true;
        cos_b = sqrtf(fmaxf(0, 1 - sin2));
        sin_b = sqrtf(fmaxf(0, sin2));
    }
    ts_vec3 wi = d2_true > 0 ? ts_vec3_scale(v, 1 / sqrtf(d2_true)) : (ts_vec3){0, 0, 1};
    float cos_w = ts_vec3_dot(q->w, wi);
    if (q->two_sided) cos_w = fabsf(cos_w);
    cos_w = fminf(1, fmaxf(-1, cos_w));
    float sin_w = sqrtf(fmaxf(0, 1 - cos_w * cos_w));
    /* θ_x = max(0, θ_w − θ_o), then θ' = max(0, θ_x − θ_b) */
    float cos_x = q->cos_o < cos_w ? 1 : cos_w * q->cos_o + sin_w * q->sin_o;
    float sin_x = q->cos_o < cos_w ? 0 : sin_w * q->cos_o - cos_w * q->sin_o;
    float cos_p = cos_b < cos_x ? 1 : cos_x * cos_b + sin_x * sin_b;
    if (cos_p <= q->cos_e) return 0;
    float imp = q->phi * cos_p / d2;
    if (n.x != 0 || n.y != 0 || n.z != 0) {
        float cos_i = fminf(1, fabsf(ts_vec3_dot(wi, n)));
        float sin_i = sqrtf(fmaxf(0, 1 - cos_i * cos_i));
        imp *= cos_b < cos_i ? 1 : cos_i * cos_b + sin_i * sin_b;
    }
    return imp > 0 ? imp : 0; /* also NaN */
}

static void node_set(ts_light_bvh_node *q, const ts_light_bounds *lb)
{
    q->lb = *lb;
    q->phi = lb->phi;
    q->center = ts_vec3_scale(ts_vec3_add(lb->box.lo, lb->box.hi), 0.5f);
    ts_vec3 half = ts_vec3_scale(ts_vec3_sub(lb->box.hi, lb->box.lo), 0.5f);
    /* rounded up: the sphere must hold the box */
    q->r2 = nextafterf(ts_vec3_dot(half, half) * (1 + 4 * FLT_EPSILON), INFINITY);
    q->w = lb->w;
    q->cos_o = lb->cos_o;
    q->sin_o = sqrtf(fmaxf(0, 1 - lb->cos_o * lb->cos_o));
    q->cos_e = lb->cos_e;
    q->two_sided = lb->two_sided;
}

static double importance(const ts_light_bounds *lb, ts_vec3 p, ts_vec3 n)
{
    ts_light_bvh_node q;
    node_set(&q, lb);
    return importance_q(&q, p, n);
}

float ts_light_bounds_importance(const ts_light_bounds *lb, ts_vec3 p, ts_vec3 n) { return (float)importance(lb, p, n); }

/* ---------------------------------------------------------------- union and cost */

/* The smallest cone holding cones (wa, θa) and (wb, θb) (pbrt-v4's DirectionCone Union). */
static void cone_union(ts_vec3 wa, double ta, ts_vec3 wb, double tb, ts_vec3 *w, double *t)
{
    ts_dvec3 a = ts_dvec3_normalize(ts_dvec3_from(wa)), b = ts_dvec3_normalize(ts_dvec3_from(wb));
    double td = acos(clamp1(ts_dvec3_dot(a, b)));
    if (fmin(td + tb, TS_PI_D) <= ta) { *w = wa, *t = ta; return; }
    if (fmin(td + ta, TS_PI_D) <= tb) { *w = wb, *t = tb; return; }
    double to = (ta + td + tb) / 2;
    ts_dvec3 axis = ts_dvec3_cross(a, b);
    double al = ts_dvec3_length(axis);
    if (to >= TS_PI_D || !(al > 0)) { *w = wa, *t = TS_PI_D; return; }
    /* a rotated by to − ta about a × b (Rodrigues; a ⟂ axis) */
    axis = ts_dvec3_scale(axis, 1 / al);
    double tr = to - ta;
    ts_dvec3 r = ts_dvec3_add(ts_dvec3_scale(a, cos(tr)), ts_dvec3_scale(ts_dvec3_cross(axis, a), sin(tr)));
    *w = ts_dvec3_to_vec3(ts_dvec3_normalize(r));
    *t = fmin(to + 1e-9, TS_PI_D);
}

static ts_light_bounds bounds_union(const ts_light_bounds *a, const ts_light_bounds *b)
{
    if (!(a->phi > 0)) return *b;
    if (!(b->phi > 0)) return *a;
    ts_light_bounds u;
    u.box = ts_bounds3_union(a->box, b->box);
    u.phi = a->phi + b->phi;
    double t;
    cone_union(a->w, acos(clamp1(a->cos_o)), b->w, acos(clamp1(b->cos_o)), &u.w, &t);
    /* a float cosine a little below the double's: never narrower than the union */
    u.cos_o = nextafterf((float)cos(t), -2.0f);
    if (u.cos_o < -1) u.cos_o = -1;
    u.cos_e = fminf(a->cos_e, b->cos_e);
    u.two_sided = a->two_sided || b->two_sided;
    return u;
}

/* pbrt-v4's EvaluateCost: φ · M_Ω · (longest extent / extent along dim) · surface area. */
static double cost(const ts_light_bounds *b, ts_bounds3 all, int dim)
{
    if (!(b->phi > 0)) return 0;
    double to = acos(clamp1(b->cos_o)), te = acos(clamp1(b->cos_e));
    double tw = fmin(to + te, TS_PI_D), so = sin(to);
    double m = 2 * TS_PI_D * (1 - b->cos_o) +
               TS_PI_D / 2 * (2 * tw * so - cos(to - 2 * tw) - 2 * to * so + b->cos_o);
    ts_vec3 d = ts_vec3_sub(all.hi, all.lo);
    double dk = dim == 0 ? d.x : dim == 1 ? d.y : d.z, dmax = fmax(d.x, fmax(d.y, d.z));
    double kr = dk > 0 ? dmax / dk : 1;
    ts_vec3 e = ts_vec3_sub(b->box.hi, b->box.lo);
    double area = 2 * ((double)e.x * e.y + (double)e.y * e.z + (double)e.z * e.x);
    return b->phi * m * kr * area;
}

/* ---------------------------------------------------------------- build */

typedef struct item {
    uint32_t light;
    ts_light_bounds lb;
    ts_vec3 centroid;
} item;

typedef struct builder {
    ts_light_bvh *bvh;
    item *scratch;
} builder;

static float axis_of(ts_vec3 v, int k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }

/* Node for items[0..n) at depth with path trail; returns its index. */
static uint32_t build(builder *bd, item *items, uint32_t n, uint64_t trail, int depth)
{
    ts_light_bvh *bvh = bd->bvh;
    uint32_t at = bvh->n_nodes++;
    ts_light_bvh_node *node = &bvh->nodes[at];
    if (n == 1) {
        node->leaf = true;
        node->index = items[0].light;
        node_set(node, &items[0].lb);
        bvh->trail[items[0].light] = trail;
        return at;
    }
    ts_bounds3 all = ts_bounds3_empty(), cent = ts_bounds3_empty();
    for (uint32_t i = 0; i < n; i++) {
        all = ts_bounds3_union(all, items[i].lb.box);
        cent = ts_bounds3_extend(cent, items[i].centroid);
    }
    uint32_t mid = n / 2;
    if (depth < COUNT_SPLIT_DEPTH) {
        double best = INFINITY;
        int best_dim = -1, best_bucket = -1;
        for (int dim = 0; dim < 3; dim++) {
            float c0 = axis_of(cent.lo, dim), c1 = axis_of(cent.hi, dim);
            if (!(c1 > c0)) continue;
            ts_light_bounds bucket[BUCKETS];
            for (int k = 0; k < BUCKETS; k++)
                bucket[k] = unbounded();
            for (uint32_t i = 0; i < n; i++) {
                int k = (int)(BUCKETS * ((axis_of(items[i].centroid, dim) - c0) / (c1 - c0)));
                k = k < 0 ? 0 : k >= BUCKETS ? BUCKETS - 1 : k;
                bucket[k] = bounds_union(&bucket[k], &items[i].lb);
            }
            for (int s = 0; s < BUCKETS - 1; s++) {
                ts_light_bounds below = unbounded(), above = unbounded();
                for (int k = 0; k <= s; k++)
                    below = bounds_union(&below, &bucket[k]);
                for (int k = s + 1; k < BUCKETS; k++)
                    above = bounds_union(&above, &bucket[k]);
                double c = cost(&below, all, dim) + cost(&above, all, dim);
                if (c > 0 && c < best) best = c, best_dim = dim, best_bucket = s;
            }
        }
        if (best_dim >= 0) {
            /* stable partition: bucket ≤ best_bucket first */
            float c0 = axis_of(cent.lo, best_dim), c1 = axis_of(cent.hi, best_dim);
            uint32_t lo_n = 0, hi_n = 0;
            for (uint32_t i = 0; i < n; i++) {
                int k = (int)(BUCKETS * ((axis_of(items[i].centroid, best_dim) - c0) / (c1 - c0)));
                k = k < 0 ? 0 : k >= BUCKETS ? BUCKETS - 1 : k;
                if (k <= best_bucket) items[lo_n++] = items[i];
                else bd->scratch[hi_n++] = items[i];
            }
            memcpy(items + lo_n, bd->scratch, hi_n * sizeof *items);
            if (lo_n > 0 && lo_n < n) mid = lo_n;
        }
    }
    uint64_t bit = depth < 64 ? (uint64_t)1 << depth : 0;
    build(bd, items, mid, trail, depth + 1);
    uint32_t second = build(bd, items + mid, n - mid, trail | bit, depth + 1);
    node = &bvh->nodes[at]; /* (the array does not move: sized up front) */
    node->leaf = false;
    node->index = second;
    ts_light_bounds u = bounds_union(&bvh->nodes[at + 1].lb, &bvh->nodes[second].lb);
    node_set(node, &u);
    return at;
}

ts_status ts_light_bvh_build(ts_light_bvh *bvh, const ts_light_bounds *bounds, const bool *unbounded_light,
                             uint32_t n, ts_arena *arena, ts_error *err)
{
    memset(bvh, 0, sizeof *bvh);
    bvh->n_lights = n;
    if (n == 0) return TS_OK;
    bvh->trail = ts_arena_calloc(arena, n, sizeof *bvh->trail);
    bvh->in_tree = ts_arena_calloc(arena, n, sizeof *bvh->in_tree);
    bvh->unbounded = ts_arena_calloc(arena, n, sizeof *bvh->unbounded);
    item *items = malloc((size_t)n * sizeof *items), *scratch = malloc((size_t)n * sizeof *scratch);
    if (!bvh->trail || !bvh->in_tree || !bvh->unbounded || !items || !scratch) {
        free(items);
        free(scratch);
        return ts_error_set(err, TS_ERR_NOMEM, "light hierarchy: out of memory for %u lights", n);
    }
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (unbounded_light[i]) {
            bvh->unbounded[bvh->n_unbounded++] = i;
            bvh->in_tree[i] = 2;
            continue;
        }
        const ts_light_bounds *lb = &bounds[i];
        if (!(lb->phi > 0) || !isfinite(lb->phi)) continue;
        items[m].light = i;
        items[m].lb = *lb;
        items[m].centroid = ts_vec3_scale(ts_vec3_add(lb->box.lo, lb->box.hi), 0.5f);
        bvh->in_tree[i] = 1;
        m++;
    }
    if (m > 0) {
        bvh->nodes = ts_arena_calloc(arena, 2 * (size_t)m - 1, sizeof *bvh->nodes);
        if (!bvh->nodes) {
            free(items);
            free(scratch);
            return ts_error_set(err, TS_ERR_NOMEM, "light hierarchy: out of memory for %u lights", n);
        }
        builder bd = {bvh, scratch};
        build(&bd, items, m, 0, 0);
    }
    free(items);
    free(scratch);
    return TS_OK;
}

/* ---------------------------------------------------------------- queries */

static double p_unbounded(const ts_light_bvh *bvh)
{
    uint32_t k = bvh->n_unbounded;
    return k ? (double)k / (double)(k + (bvh->n_nodes ? 1 : 0)) : 0;
}

uint32_t ts_light_bvh_sample(const ts_light_bvh *bvh, ts_vec3 p, ts_vec3 n, float u_f, float *pmf)
{
    *pmf = 0;
    double u = u_f >= 0 && u_f < 1 ? u_f : 0, pu = p_unbounded(bvh);
    if (u < pu) {
        uint32_t k = (uint32_t)(u / pu * bvh->n_unbounded);
        if (k >= bvh->n_unbounded) k = bvh->n_unbounded - 1;
        *pmf = (float)(pu / bvh->n_unbounded);
        return bvh->unbounded[k];
    }
    if (!bvh->n_nodes) return TS_NONE;
    u = fmin((u - pu) / (1 - pu), 0x1.fffffffffffffp-1);
    double prob = 1 - pu;
    uint32_t at = 0;
    for (;;) {
        const ts_light_bvh_node *node = &bvh->nodes[at];
        if (node->leaf) {
            if (at > 0 || importance_q(node, p, n) > 0) {
                *pmf = (float)prob;
                return node->index;
            }
            return TS_NONE;
        }
        double c0 = importance_q(&bvh->nodes[at + 1], p, n), c1 = importance_q(&bvh->nodes[node->index], p, n);
        if (!(c0 + c1 > 0)) return TS_NONE;
        double p0 = c0 / (c0 + c1);
        if (u < p0) {
            prob *= c0 / (c0 + c1);
            u = fmin(u / p0, 0x1.fffffffffffffp-1);
            at = at + 1;
        } else {
            prob *= c1 / (c0 + c1);
            u = fmin((u - p0) / (1 - p0), 0x1.fffffffffffffp-1);
            at = node->index;
        }
    }
}

float ts_light_bvh_pmf(const ts_light_bvh *bvh, ts_vec3 p, ts_vec3 n, uint32_t i)
{
    if (i >= bvh->n_lights || !bvh->in_tree[i]) return 0;
    double pu = p_unbounded(bvh);
    if (bvh->in_tree[i] == 2) return (float)(pu / bvh->n_unbounded);
    double prob = 1 - pu;
    uint64_t trail = bvh->trail[i];
    uint32_t at = 0;
    for (int depth = 0;; depth++) {
        const ts_light_bvh_node *node = &bvh->nodes[at];
        if (node->leaf) return at > 0 || importance_q(node, p, n) > 0 ? (float)prob : 0;
        double c0 = importance_q(&bvh->nodes[at + 1], p, n), c1 = importance_q(&bvh->nodes[node->index], p, n);
        if (!(c0 + c1 > 0)) return 0;
        bool second = depth < 64 && (trail >> depth & 1);
        prob *= (second ? c1 : c0) / (c0 + c1);
        at = second ? node->index : at + 1;
    }
}
