/* chi2.c — the χ² test of chi2.h: histogram, adaptive per-cell quadrature, pooling,
 * incomplete-gamma tail and Šidák threshold. */
#include "chi2.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define KEEP_PER_CELL 8      /* samples kept per cell to guide refinement */
#define NEAR_MAX (9 * KEEP_PER_CELL) /* a cell's and its 8 neighbours' */
#define ZERO_EXPECTED 1e-8   /* a cell this empty should never see a sample */
#define NOISE_FRACTION 0.03  /* quadrature error target: 0.03 √E counts per cell ... */
#define MAX_COUNT_ERROR 1e-3 /* ... and at most 0.001 counts */
#define FLOAT_NOISE 1e-6     /* relative error floor: float pdf evaluations */

void ts_chi2_params_default(ts_chi2_params *p)
{
    p->sample_count = 1000000;
    p->cos_theta_res = 21;
    p->phi_res = 42;
    p->significance = 0.01;
    p->test_count = TS_CHI2_FAMILY_SIZE;
    p->min_expected = 5;
    p->seed = 1;
    p->max_node_evals = 2000000;
}

/* ---------------------------------------------------------------- quadrature ---- */

typedef struct kept_point {
    double z, phi; /* where the sample fell */
    double pdf;    /* pdf there */
} kept_point;

typedef struct quad {
    ts_chi2_pdf_fn pdf;
    void *ctx;
    uint64_t evals;     /* total pdf calls */
    uint64_t cell_evals;
    uint64_t budget;    /* per cell */
    bool over_budget;
    struct rect *heap;  /* scratch for the adaptive quadrature */
    int heap_cap;
    bool bad_value;     /* a negative or non-finite pdf was seen */
    ts_vec3 bad_w;
    double bad_pdf;
} quad;

static const double gl_x[4] = {-0.86113631159405257522, -0.33998104358485626480, 0.33998104358485626480,
                               0.86113631159405257522};
static const double gl_w[4] = {0.34785484513745385737, 0.65214515486254614263, 0.65214515486254614263,
                               0.34785484513745385737};

static ts_vec3 direction_of(double z, double phi)
{
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return (ts_vec3){(float)(s * cos(phi)), (float)(s * sin(phi)), (float)z};
}

static double eval_pdf(quad *q, double z, double phi)
{
    ts_vec3 w = direction_of(z, phi);
    double v = q->pdf(q->ctx, w);
    q->evals++;
    q->cell_evals++;
    if (!(v >= 0) || !isfinite(v)) {
        if (!q->bad_value) {
            q->bad_value = true;
            q->bad_w = w;
            q->bad_pdf = v;
        }
        return 0;
    }
    return v;
}

/* 4×4 Gauss–Legendre rule on [z0,z1]×[p0,p1]; *maxv gets the largest node value. */
static double gl_rect(quad *q, double z0, double z1, double p0, double p1, double *maxv)
{
    double hz = 0.5 * (z1 - z0), cz = 0.5 * (z1 + z0);
    double hp = 0.5 * (p1 - p0), cp = 0.5 * (p1 + p0);
    double sum = 0;
    for (int i = 0; i < 4; i++) {
        double z = cz + hz * gl_x[i];
        for (int j = 0; j < 4; j++) {
            double v = eval_pdf(q, z, cp + hp * gl_x[j]);
            if (v > *maxv) *maxv = v;
            sum += gl_w[i] * gl_w[j] * v;
        }
    }
    return sum * hz * hp;
}

/* 5-point Gauss–Lobatto rule (degree 7, like the 4-point Gauss rule, but with nodes on
 * the rectangle's edges): a step just inside an edge, invisible to the interior Gauss
 * nodes of the rectangle and of its halves, shows up as a disagreement of the two rules.
 * *var_z / *var_p get the summed jumps between opposite edges, to choose a split. */
static const double lob_x[5] = {-1.0, -0.65465367070797714380, 0.0, 0.65465367070797714380, 1.0};
static const double lob_w[5] = {0.1, 0.54444444444444444444, 0.71111111111111111111, 0.54444444444444444444, 0.1};

static double lobatto_rect(quad *q, double z0, double z1, double p0, double p1, double *maxv, double *var_z,
                           double *var_p)
{
    double hz = 0.5 * (z1 - z0), cz = 0.5 * (z1 + z0);
    double hp = 0.5 * (p1 - p0), cp = 0.5 * (p1 + p0);
    double v[5][5], sum = 0;
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < 5; j++) {
            double z = i == 0 ? z0 : (i == 4 ? z1 : cz + hz * lob_x[i]);
            double p = j == 0 ? p0 : (j == 4 ? p1 : cp + hp * lob_x[j]);
            v[i][j] = eval_pdf(q, z, p);
            if (v[i][j] > *maxv) *maxv = v[i][j];
            sum += lob_w[i] * lob_w[j] * v[i][j];
        }
    *var_z = *var_p = 0;
    for (int k = 0; k < 5; k++) {
        *var_z += fabs(v[4][k] - v[0][k]);
        *var_p += fabs(v[k][4] - v[k][0]);
    }
    return sum * hz * hp;
}

/* Angular lengths of the rectangle's sides, to choose a split when the error estimates
 * say nothing (an unresolved peak): near the pole a cosθ interval is long in angle. */
static bool split_z_by_geometry(double z0, double z1, double p0, double p1)
{
    double zm = 0.5 * (z0 + z1);
    double s_mid = sqrt(fmax(1e-300, 1.0 - zm * zm));
    double s_max = sqrt(fmax(0.0, 1.0 - fmin(z0 * z0, z1 * z1)));
    if (z0 < 0 && z1 > 0) s_max = 1;
    double len_z = (z1 - z0) / s_mid;
    double len_p = (p1 - p0) * s_max;
    return len_z >= len_p;
}

/* Kept samples within one rectangle size of [z0,z1]×[p0,p1] (the 3×3 neighbourhood):
 * a peak there may spill into the rectangle without touching its nodes. */
static int near_points(double z0, double z1, double p0, double p1, const kept_point *const *pts, int n,
                       const kept_point **out)
{
    double hz = z1 - z0, hp = p1 - p0;
    int m = 0;
    for (int i = 0; i < n; i++)
        if (pts[i]->z >= z0 - hz && pts[i]->z <= z1 + hz && pts[i]->phi >= p0 - hp && pts[i]->phi <= p1 + hp)
            out[m++] = pts[i];
    return m;
}

/* One rectangle of the adaptive quadrature: its estimate, error estimate, and how it
 * would be split (with the children's one-rule estimates already computed). */
typedef struct rect {
    double z0, z1, p0, p1;
    double whole;       /* one-rule estimate (from the parent's split) */
    double best, err;   /* refined estimate and its error estimate */
    double child[2];    /* one-rule estimates of the two halves along the chosen axis */
    bool split_z;
    bool unresolved;    /* a kept sample nearby has a pdf the nodes never approached */
} rect;

static void evaluate_rect(quad *q, rect *r, const kept_point *const *pts, int n)
{
    double z0 = r->z0, z1 = r->z1, p0 = r->p0, p1 = r->p1;
    double zm = 0.5 * (z0 + z1), pm = 0.5 * (p0 + p1);
    double maxv = 0;
    double za = gl_rect(q, z0, zm, p0, p1, &maxv), zb = gl_rect(q, zm, z1, p0, p1, &maxv);
    double pa = gl_rect(q, z0, z1, p0, pm, &maxv), pb = gl_rect(q, z0, z1, pm, p1, &maxv);
    double var_z, var_p;
    double lob = lobatto_rect(q, z0, z1, p0, p1, &maxv, &var_z, &var_p);
    double ez = fabs(za + zb - r->whole), ep = fabs(pa + pb - r->whole), el = fabs(lob - r->whole);
    r->best = 0.5 * (za + zb + pa + pb);
    r->err = fmax(el, fmax(ez, ep));
    const kept_point *near[NEAR_MAX] = {0};
    int m = near_points(z0, z1, p0, p1, pts, n, near);
    r->unresolved = false;
    for (int i = 0; i < m; i++)
        if (near[i]->pdf > 2.0 * maxv) r->unresolved = true;
    if ((z1 - z0) < 1e-13 || (p1 - p0) < 1e-13) r->unresolved = false; /* cannot resolve further */
    if (fmax(ez, ep) >= el && fabs(ez - ep) > 1e-3 * fmax(ez, ep))
        r->split_z = ez > ep; /* the halves say where the variation is */
    else if (el > 0 && fabs(var_z - var_p) > 1e-3 * fmax(var_z, var_p))
        r->split_z = var_z > var_p; /* a step near an edge: split across it */
    else
        r->split_z = split_z_by_geometry(z0, z1, p0, p1);
    r->child[0] = r->split_z ? za : pa;
    r->child[1] = r->split_z ? zb : pb;
}

static double priority(const rect *r) { return r->unresolved ? INFINITY : r->err; }

static void heap_push(rect *h, int *n, rect r)
{
    int i = (*n)++;
    h[i] = r;
    while (i > 0) {
        int parent = (i - 1) / 2;
        if (priority(&h[parent]) >= priority(&h[i])) break;
        rect t = h[parent];
        h[parent] = h[i];
        h[i] = t;
        i = parent;
    }
}

static rect heap_pop(rect *h, int *n)
{
    rect top = h[0];
    h[0] = h[--(*n)];
    int i = 0;
    for (;;) {
        int l = 2 * i + 1, r = l + 1, m = i;
        if (l < *n && priority(&h[l]) > priority(&h[m])) m = l;
        if (r < *n && priority(&h[r]) > priority(&h[m])) m = r;
        if (m == i) break;
        rect t = h[m];
        h[m] = h[i];
        h[i] = t;
        i = m;
    }
    return top;
}

/* Globally adaptive integration of one rectangle: always split the piece with the
 * largest error (or an unresolved peak) until the summed error estimate is below tol or
 * the budget is spent — so running out of budget degrades gracefully. */
static double adaptive(quad *q, double z0, double z1, double p0, double p1, double tol, const kept_point *const *pts,
                       int n, double *err_out)
{
    int cap = (int)(q->budget / 89) + 2;
    if (cap > q->heap_cap) cap = q->heap_cap;
    rect *h = q->heap;
    int nh = 0;
    /* Kept samples bunched in a small part of the rectangle mark a sharp lobe: cut the
     * rectangle along their bounding box, widened by twice its size, so the refinement
     * starts at the lobe's scale instead of searching for it from the cell's. */
    double zc[4] = {z0, z0, z1, z1}, pc[4] = {p0, p0, p1, p1};
    int nzc = 1, npc = 1;
    {
        double blo_z = INFINITY, bhi_z = -INFINITY, blo_p = INFINITY, bhi_p = -INFINITY;
        int inside = 0;
        for (int i = 0; i < n; i++) {
            const kept_point *k = pts[i];
            if (!(k->pdf > 0) || k->z < z0 || k->z > z1 || k->phi < p0 || k->phi > p1) continue;
            inside++;
            blo_z = fmin(blo_z, k->z);
            bhi_z = fmax(bhi_z, k->z);
            blo_p = fmin(blo_p, k->phi);
            bhi_p = fmax(bhi_p, k->phi);
        }
        if (inside >= 2) {
            double wz = fmax(bhi_z - blo_z, 1e-9 * (z1 - z0)), wp = fmax(bhi_p - blo_p, 1e-9 * (p1 - p0));
            double a = blo_z - 2 * wz, b = bhi_z + 2 * wz;
            if (b - a < 0.25 * (z1 - z0)) {
                zc[1] = fmax(z0, a);
                zc[2] = fmin(z1, b);
                nzc = 3;
            }
            a = blo_p - 2 * wp;
            b = bhi_p + 2 * wp;
            if (b - a < 0.25 * (p1 - p0)) {
                pc[1] = fmax(p0, a);
                pc[2] = fmin(p1, b);
                npc = 3;
            }
        }
    }
    if (nzc == 1) zc[1] = z1;
    if (npc == 1) pc[1] = p1;
    double total_err = 0;
    for (int i = 0; i < nzc; i++)
        for (int j = 0; j < npc; j++) {
            double a0 = zc[i], a1 = nzc == 1 ? z1 : zc[i + 1], b0 = pc[j], b1 = npc == 1 ? p1 : pc[j + 1];
            if (!(a1 > a0) || !(b1 > b0)) continue;
            double maxv = 0;
            rect root = {a0, a1, b0, b1, gl_rect(q, a0, a1, b0, b1, &maxv), 0, 0, {0, 0}, false, false};
            evaluate_rect(q, &root, pts, n);
            heap_push(h, &nh, root);
            total_err += root.err;
        }
    while (nh > 0 && nh + 1 < cap) {
        if (!h[0].unresolved && total_err <= tol) break;
        rect r = heap_pop(h, &nh);
        total_err -= r.err;
        double zm = 0.5 * (r.z0 + r.z1), pm = 0.5 * (r.p0 + r.p1);
        for (int k = 0; k < 2; k++) {
            rect c = r;
            if (r.split_z) {
                if (k == 0) c.z1 = zm;
                else c.z0 = zm;
            } else {
                if (k == 0) c.p1 = pm;
                else c.p0 = pm;
            }
            c.whole = r.child[k];
            evaluate_rect(q, &c, pts, n);
            total_err += c.err;
            heap_push(h, &nh, c);
        }
    }
    double sum = 0, e = 0;
    for (int i = 0; i < nh; i++) {
        sum += h[i].best;
        e += h[i].err;
    }
    *err_out = e;
    if (e > 10 * tol) q->over_budget = true; /* did not converge: reported */
    return sum;
}

/* ∫ over cell [z0,z1]×[p0,p1], split at the horizon. pts are the kept samples of this
 * cell and its neighbours (φ already unwrapped to be near this cell). With n_samples > 0
 * the tolerance follows the cell's statistical noise, else it is abs_tol. */
static double integrate_cell(quad *q, double z0, double z1, double p0, double p1, const kept_point *const *pts,
                             int n, double n_samples, double abs_tol, double *err)
{
    double bounds[3] = {z0, z1, z1};
    int parts = 1;
    if (z0 < 0 && z1 > 0) {
        bounds[1] = 0;
        parts = 2;
    }
    q->over_budget = false;
    double total = 0;
    for (int k = 0; k < parts; k++) {
        double a = bounds[k], b = bounds[k + 1];
        double maxv = 0, coarse = gl_rect(q, a, b, p0, p1, &maxv);
        double tol = abs_tol / parts;
        if (n_samples > 0) {
            /* Target |ΔE| ≤ min(0.03 √E, 0.001) counts: negligible in the cell's term
             * and, summed over all cells, in the no-direction bin's. */
            double e = fmax(coarse * n_samples, 1.0);
            tol = fmin(NOISE_FRACTION * sqrt(e), MAX_COUNT_ERROR) / n_samples / parts;
        }
        /* The pdf is evaluated in float at float directions: differences of the rules
         * below ~1e-6 of the value are rounding noise, not quadrature error. */
        tol = fmax(tol, FLOAT_NOISE * fabs(coarse));
        double e = 0;
        total += adaptive(q, a, b, p0, p1, tol, pts, n, &e);
        *err += e;
    }
    return total;
}

double ts_chi2_integrate(ts_chi2_pdf_fn pdf, void *ctx, int cos_theta_res, int phi_res, double abs_tol)
{
    quad q = {.pdf = pdf, .ctx = ctx, .budget = 200000};
    q.heap_cap = (int)(q.budget / 89) + 2;
    q.heap = malloc(sizeof(rect) * (size_t)q.heap_cap);
    if (!q.heap) return NAN;
    double cells = (double)cos_theta_res * phi_res;
    double total = 0;
    for (int i = 0; i < cos_theta_res; i++) {
        double z0 = -1.0 + 2.0 * i / cos_theta_res, z1 = -1.0 + 2.0 * (i + 1) / cos_theta_res;
        if (i == cos_theta_res - 1) z1 = 1.0;
        for (int j = 0; j < phi_res; j++) {
            double p0 = 2.0 * TS_PI_D * j / phi_res, p1 = 2.0 * TS_PI_D * (j + 1) / phi_res;
            double err = 0;
            total += integrate_cell(&q, z0, z1, p0, p1, NULL, 0, 0, abs_tol / cells, &err);
        }
    }
    free(q.heap);
    return total;
}

/* ------------------------------------------------------------- statistics ---- */

double ts_chi2_upper_tail(double x, int dof)
{
    if (dof <= 0) return 1.0;
    if (!(x > 0)) return 1.0;
    double a = 0.5 * dof, y = 0.5 * x;
    double lg = lgamma(a);
    if (y < a + 1) {
        /* Series for the lower regularised gamma P(a, y). */
        double ap = a, del = 1.0 / a, sum = del;
        for (int n = 0; n < 100000; n++) {
            ap += 1;
            del *= y / ap;
            sum += del;
            if (fabs(del) < fabs(sum) * 1e-16) break;
        }
        double p = sum * exp(-y + a * log(y) - lg);
        return fmax(0.0, 1.0 - p);
    }
    /* Continued fraction for Q(a, y) (modified Lentz). */
    const double tiny = 1e-300;
    double b = y + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; i++) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1) < 1e-16) break;
    }
    return exp(-y + a * log(y) - lg) * h;
}

double ts_chi2_sidak(double alpha, int tests)
{
    if (tests <= 1) return alpha;
    return -expm1(log1p(-alpha) / tests);
}

typedef struct bin {
    double expected;
    double observed;
    int cell;      /* −1: the no-direction bin; −2: pooled */
    double sigma;  /* error bound of `expected` from the quadrature (counts) */
} bin;

static int bin_cmp(const void *a, const void *b)
{
    double ea = ((const bin *)a)->expected, eb = ((const bin *)b)->expected;
    return (ea > eb) - (ea < eb);
}

static void describe_cell(const ts_chi2_params *p, int cell, char *buf, size_t size)
{
    if (cell == -1) {
        snprintf(buf, size, "no-direction bin");
        return;
    }
    if (cell == -2) {
        snprintf(buf, size, "pooled bin");
        return;
    }
    int i = cell / p->phi_res, j = cell % p->phi_res;
    snprintf(buf, size, "cell cosθ∈[%.3f,%.3f] φ∈[%.1f°,%.1f°]", -1.0 + 2.0 * i / p->cos_theta_res,
             -1.0 + 2.0 * (i + 1) / p->cos_theta_res, 360.0 * j / p->phi_res, 360.0 * (j + 1) / p->phi_res);
}

bool ts_chi2_test(const ts_chi2_params *p, ts_chi2_sample_fn sample, ts_chi2_pdf_fn pdf, void *ctx,
                  ts_chi2_result *r)
{
    memset(r, 0, sizeof *r);
    if (p->cos_theta_res < 1 || p->cos_theta_res % 2 == 0 || p->phi_res < 1 || p->sample_count == 0 ||
        p->test_count < 1 || !(p->significance > 0 && p->significance < 1)) {
        snprintf(r->message, sizeof r->message,
                 "invalid parameters (cos_theta_res must be odd and ≥ 1, phi_res ≥ 1, samples > 0, "
                 "test_count ≥ 1, 0 < significance < 1)");
        return false;
    }
    int nz = p->cos_theta_res, np = p->phi_res, ncells = nz * np;
    double *observed = calloc((size_t)ncells, sizeof *observed);
    kept_point *kept = calloc((size_t)ncells * KEEP_PER_CELL, sizeof *kept);
    int *nkept = calloc((size_t)ncells, sizeof *nkept);
    bin *bins = calloc((size_t)ncells + 1, sizeof *bins);
    if (!observed || !kept || !nkept || !bins) {
        snprintf(r->message, sizeof r->message, "out of memory");
        goto fail;
    }
    r->threshold = ts_chi2_sidak(p->significance, p->test_count);

    /* 1. Histogram. */
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, p->seed, 0x5eed);
    for (uint64_t s = 0; s < p->sample_count; s++) {
        ts_vec3 w = {0, 0, 0};
        ts_chi2_outcome o = sample(ctx, &rng, &w);
        if (o == TS_CHI2_NONE) {
            r->none++;
            continue;
        }
        if (o == TS_CHI2_DISCRETE) {
            r->discrete++;
            continue;
        }
        double x = w.x, y = w.y, z = w.z, len = sqrt(x * x + y * y + z * z);
        if (!ts_vec3_is_finite(w) || fabs(len - 1) > 1e-3) {
            snprintf(r->message, sizeof r->message, "sample %llu is not a unit direction: (%g, %g, %g)",
                     (unsigned long long)s, x, y, z);
            goto fail;
        }
        z /= len;
        double phi = atan2(y, x);
        if (phi < 0) phi += 2 * TS_PI_D;
        int iz = (int)floor((z + 1) * 0.5 * nz), ip = (int)floor(phi * np / (2 * TS_PI_D));
        iz = iz < 0 ? 0 : (iz >= nz ? nz - 1 : iz);
        ip = ip < 0 ? 0 : (ip >= np ? np - 1 : ip);
        int c = iz * np + ip;
        observed[c] += 1;
        r->binned++;
        if (nkept[c] < KEEP_PER_CELL) {
            kept_point *k = &kept[(size_t)c * KEEP_PER_CELL + nkept[c]];
            k->z = z;
            k->phi = phi;
            k->pdf = pdf(ctx, w);
            if (!(k->pdf >= 0) || !isfinite(k->pdf)) {
                snprintf(r->message, sizeof r->message, "pdf(%g, %g, %g) = %g at a sampled direction", x, y, z,
                         k->pdf);
                goto fail;
            }
            nkept[c]++;
        }
    }

    /* 2. Expected counts. */
    double n = (double)p->sample_count;
    quad q = {.pdf = pdf, .ctx = ctx, .budget = (uint64_t)p->max_node_evals};
    q.heap_cap = (int)(q.budget / 89) + 2;
    q.heap = malloc(sizeof(rect) * (size_t)q.heap_cap);
    if (!q.heap) {
        snprintf(r->message, sizeof r->message, "out of memory");
        goto fail;
    }
    double total = 0, total_err = 0;
    for (int i = 0; i < nz; i++) {
        double z0 = -1.0 + 2.0 * i / nz, z1 = i == nz - 1 ? 1.0 : -1.0 + 2.0 * (i + 1) / nz;
        for (int j = 0; j < np; j++) {
            int c = i * np + j;
            double p0 = 2.0 * TS_PI_D * j / np, p1 = 2.0 * TS_PI_D * (j + 1) / np;
            double err = 0;
            /* Kept samples of this cell and its neighbours, φ unwrapped across 0/2π. */
            kept_point local[NEAR_MAX];
            const kept_point *ptrs[NEAR_MAX];
            int m = 0;
            for (int di = -1; di <= 1; di++) {
                int ii = i + di;
                if (ii < 0 || ii >= nz) continue;
                for (int dj = -1; dj <= 1; dj++) {
                    int jj = j + dj;
                    double shift = 0;
                    if (jj < 0) {
                        jj += np;
                        shift = -2 * TS_PI_D;
                    } else if (jj >= np) {
                        jj -= np;
                        shift = 2 * TS_PI_D;
                    }
                    int cc = ii * np + jj;
                    for (int k = 0; k < nkept[cc]; k++) {
                        local[m] = kept[(size_t)cc * KEEP_PER_CELL + k];
                        local[m].phi += shift;
                        ptrs[m] = &local[m];
                        m++;
                    }
                }
            }
            double integral = integrate_cell(&q, z0, z1, p0, p1, ptrs, m, n, 0, &err);
            if (q.over_budget) r->unconverged++;
            total += integral;
            total_err += err;
            bins[c] = (bin){integral * n, observed[c], c, err * n};
        }
    }
    r->pdf_evals = q.evals;
    free(q.heap);
    r->pdf_integral = total;
    if (q.bad_value) {
        snprintf(r->message, sizeof r->message, "pdf(%g, %g, %g) = %g: negative or not finite", q.bad_w.x,
                 q.bad_w.y, q.bad_w.z, q.bad_pdf);
        goto fail;
    }
    double missing_expected = fmax(0.0, n * (1.0 - total));
    bins[ncells] = (bin){missing_expected, (double)(r->none + r->discrete), -1, total_err * n};
    r->quadrature_error = total_err;

    /* 3. Samples where none can be. */
    for (int c = 0; c <= ncells; c++) {
        if (bins[c].observed > 0 && bins[c].expected < ZERO_EXPECTED) {
            char where[128];
            describe_cell(p, bins[c].cell, where, sizeof where);
            snprintf(r->message, sizeof r->message,
                     "%.0f sample(s) in the %s whose expected count is %.3g (pdf integral over the sphere %.6f)",
                     bins[c].observed, where, bins[c].expected, total);
            goto fail;
        }
    }

    /* 4. Pool and sum. Bins that cannot receive samples (checked above) carry nothing. */
    int nb = 0;
    for (int c = 0; c <= ncells; c++)
        if (bins[c].expected >= ZERO_EXPECTED) bins[nb++] = bins[c];
    qsort(bins, (size_t)nb, sizeof *bins, bin_cmp);
    bin pooled = {0, 0, -2, 0};
    int first = 0;
    while (first < nb && (bins[first].expected < p->min_expected || (first > 0 && pooled.expected < p->min_expected))) {
        pooled.expected += bins[first].expected;
        pooled.observed += bins[first].observed;
        pooled.sigma += bins[first].sigma;
        first++;
    }
    int used = nb - first + (first > 0 ? 1 : 0);
    double chi2 = 0;
    double worst[3] = {0, 0, 0};
    int worst_cell[3] = {-3, -3, -3};
    for (int b = first > 0 ? first - 1 : 0; b < nb; b++) {
        const bin *bb = (first > 0 && b == first - 1) ? &pooled : &bins[b];
        /* The quadrature's error bound adds to the variance of O − E (it is ≪ √E except
         * where the quadrature ran out of budget, e.g. at a curved discontinuity). */
        double d = bb->observed - bb->expected, term = d * d / (bb->expected + bb->sigma * bb->sigma);
        chi2 += term;
        for (int k = 0; k < 3; k++)
            if (term > worst[k]) {
                for (int m = 2; m > k; m--) {
                    worst[m] = worst[m - 1];
                    worst_cell[m] = worst_cell[m - 1];
                }
                worst[k] = term;
                worst_cell[k] = bb->cell;
                break;
            }
    }
    r->statistic = chi2;
    r->dof = used - 1;
    r->p_value = ts_chi2_upper_tail(chi2, r->dof);
    r->passed = r->dof < 1 || r->p_value >= r->threshold;
    if (r->passed) {
        snprintf(r->message, sizeof r->message,
                 "passed: χ²=%.1f dof=%d p=%.4f (threshold %.2e), ∫pdf=%.6f, %llu binned, %llu discrete, %llu none",
                 chi2, r->dof, r->p_value, r->threshold, total, (unsigned long long)r->binned,
                 (unsigned long long)r->discrete, (unsigned long long)r->none);
    } else {
        int len = snprintf(r->message, sizeof r->message,
                           "χ²=%.1f dof=%d p=%.3g < %.2e, ∫pdf=%.6f; largest terms:", chi2, r->dof, r->p_value,
                           r->threshold, total);
        for (int k = 0; k < 3 && worst_cell[k] != -3 && len < (int)sizeof r->message; k++) {
            char where[128];
            describe_cell(p, worst_cell[k], where, sizeof where);
            double e = 0, o = 0;
            for (int b = 0; b < nb; b++)
                if (bins[b].cell == worst_cell[k]) {
                    e = bins[b].expected;
                    o = bins[b].observed;
                }
            if (worst_cell[k] == -2) {
                e = pooled.expected;
                o = pooled.observed;
            }
            len += snprintf(r->message + len, sizeof r->message - (size_t)len, " [%s: observed %.0f expected %.1f]",
                            where, o, e);
        }
    }
    free(observed);
    free(kept);
    free(nkept);
    free(bins);
    return r->passed;

fail:
    free(observed);
    free(kept);
    free(nkept);
    free(bins);
    r->passed = false;
    return false;
}
