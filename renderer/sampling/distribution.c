/* distribution.c — piecewise-constant distributions and the alias table (see
 * distribution.h). Tables are built in double and stored in float; the CDF is
 * renormalised so cdf[n] is exactly 1. */
#include "sampling/distribution.h"

#include <stdlib.h>
#include <string.h>

ts_status ts_distribution1d_init(ts_distribution1d *d, const float *f, uint32_t n, ts_arena *arena, ts_error *err)
{
    memset(d, 0, sizeof *d);
    if (n == 0) return ts_error_set(err, TS_ERR_INVALID, "distribution: no values");
    float *func = ts_arena_calloc(arena, n, sizeof *func);
    float *cdf = ts_arena_calloc(arena, (size_t)n + 1, sizeof *cdf);
    if (!func || !cdf) return ts_error_set(err, TS_ERR_NOMEM, "distribution: out of memory for %u values", n);
    double sum = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (!isfinite(f[i])) return ts_error_set(err, TS_ERR_INVALID, "distribution: value %u is not finite", i);
        func[i] = fabsf(f[i]);
        sum += func[i];
    }
    /* cdf[i] = Σ_{j<i} f_j / Σ f, accumulated in double. */
    double acc = 0;
    cdf[0] = 0;
    for (uint32_t i = 0; i < n; i++) {
        acc += sum > 0 ? func[i] : 1.0;
        cdf[i + 1] = (float)(acc / (sum > 0 ? sum : (double)n));
    }
    cdf[n] = 1.0f;
    /* The guide table: k/n_guide is exact in float (n_guide ≤ 2^30 is a power of two),
     * and the cdf is non-decreasing, so one pass fills it. */
    uint32_t n_guide = 1;
    while (n_guide < n / 4) n_guide <<= 1;
    uint32_t *guide = ts_arena_calloc(arena, (size_t)n_guide + 1, sizeof *guide);
    if (!guide) return ts_error_set(err, TS_ERR_NOMEM, "distribution: out of memory for %u values", n);
    const float inv_guide = 1.0f / (float)n_guide;
    uint32_t i = 0;
    for (uint32_t k = 0; k <= n_guide; k++) {
        float t = (float)k * inv_guide;
        while (i + 1 < n && cdf[i + 1] <= t) i++;
        guide[k] = i;
    }
    d->n = n;
    d->func = func;
    d->cdf = cdf;
    d->func_int = (float)(sum / n);
    d->n_guide = n_guide;
    d->guide = guide;
    return TS_OK;
}

/* Largest i < n with cdf[i] ≤ u, or 0 if there is none (u < 0 or NaN): the guide table
 * narrows the binary search to [guide[k], guide[k+1]]. For u ≥ 0, k = ⌊u·n_guide⌋ is
 * exact, so k/n_guide ≤ u < (k+1)/n_guide: cdf[guide[k]] ≤ k/n_guide ≤ u puts the answer
 * at guide[k] or above, and the answer's cdf ≤ u < (k+1)/n_guide puts it at guide[k+1]
 * or below (u ≥ 1 takes the last bucket, whose guide[n_guide] is n − 1). The search
 * inside is the plain one, so the result is the same as over the whole table. */
static uint32_t find_interval(const ts_distribution1d *d, float u)
{
    if (!(u >= 0.0f)) return 0;
    float x = u * (float)d->n_guide;
    uint32_t k = x < (float)d->n_guide ? (uint32_t)x : d->n_guide - 1;
    uint32_t lo = d->guide[k], hi = d->guide[k + 1] + 1; /* cdf[lo] ≤ u, answer in [lo, hi) */
    const float *cdf = d->cdf;
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= u) lo = mid;
        else hi = mid;
    }
    return lo;
}

/* Density of piece i (in x) — uniform when the function is zero. */
static float piece_pdf(const ts_distribution1d *d, uint32_t i)
{
    return d->func_int > 0 ? d->func[i] / d->func_int : 1.0f;
}

float ts_distribution1d_sample_continuous(const ts_distribution1d *d, float u, float *pdf, uint32_t *offset)
{
    uint32_t i = find_interval(d, u);
    /* Skip pieces of zero width (zero function value), which cannot be landed in. */
    while (i + 1 < d->n && d->cdf[i + 1] <= u) i++;
    if (offset) *offset = i;
    float width = d->cdf[i + 1] - d->cdf[i];
    float du = u - d->cdf[i];
    if (width > 0) du /= width;
    du = ts_clampf(du, 0.0f, TS_ONE_MINUS_EPSILON);
    if (pdf) *pdf = piece_pdf(d, i);
    float x = (i + du) / d->n;
    return x < 1.0f ? x : TS_ONE_MINUS_EPSILON;
}

/* The piece of x in [0,1] of ts_distribution1d_pdf. */
static uint32_t piece_of(const ts_distribution1d *d, float x)
{
    uint32_t i = (uint32_t)(x * d->n);
    return i < d->n ? i : d->n - 1;
}

float ts_distribution1d_pdf(const ts_distribution1d *d, float x)
{
    if (!(x >= 0.0f && x <= 1.0f)) return 0.0f;
    return piece_pdf(d, piece_of(d, x));
}

float ts_distribution1d_invert(const ts_distribution1d *d, float x)
{
    x = ts_clampf(x, 0.0f, 1.0f);
    float fx = x * d->n;
    uint32_t i = (uint32_t)fx;
    if (i >= d->n) return 1.0f;
    float frac = fx - (float)i;
    return ts_lerpf(frac, d->cdf[i], d->cdf[i + 1]);
}

uint32_t ts_distribution1d_sample_discrete(const ts_distribution1d *d, float u, float *pmf, float *u_remapped)
{
    uint32_t i = find_interval(d, u);
    while (i + 1 < d->n && d->cdf[i + 1] <= u) i++;
    float width = d->cdf[i + 1] - d->cdf[i];
    if (pmf) *pmf = ts_distribution1d_discrete_pmf(d, i);
    if (u_remapped) *u_remapped = width > 0 ? ts_clampf((u - d->cdf[i]) / width, 0.0f, TS_ONE_MINUS_EPSILON) : 0.0f;
    return i;
}

float ts_distribution1d_discrete_pmf(const ts_distribution1d *d, uint32_t i)
{
    if (i >= d->n) return 0.0f;
    return d->func_int > 0 ? d->func[i] / (d->func_int * d->n) : 1.0f / d->n;
}

/* ---- 2D ---- */

ts_status ts_distribution2d_init(ts_distribution2d *d, const float *f, uint32_t nu, uint32_t nv, ts_arena *arena,
                                 ts_error *err)
{
    memset(d, 0, sizeof *d);
    if (nu == 0 || nv == 0) return ts_error_set(err, TS_ERR_INVALID, "distribution: empty %u×%u table", nu, nv);
    ts_distribution1d *rows = ts_arena_calloc(arena, nv, sizeof *rows);
    float *row_int = ts_arena_calloc(arena, nv, sizeof *row_int);
    if (!rows || !row_int) return ts_error_set(err, TS_ERR_NOMEM, "distribution: out of memory for %u rows", nv);
    for (uint32_t v = 0; v < nv; v++) {
        ts_status st = ts_distribution1d_init(&rows[v], f + (size_t)v * nu, nu, arena, err);
        if (st) return st;
        row_int[v] = rows[v].func_int;
    }
    ts_status st = ts_distribution1d_init(&d->marginal, row_int, nv, arena, err);
    if (st) return st;
    d->nu = nu;
    d->nv = nv;
    d->conditional = rows;
    return TS_OK;
}

ts_vec2 ts_distribution2d_sample_cell(const ts_distribution2d *d, ts_vec2 u, uint32_t *iu, uint32_t *iv)
{
    float y = ts_distribution1d_sample_continuous(&d->marginal, u.y, NULL, iv);
    float x = ts_distribution1d_sample_continuous(&d->conditional[*iv], u.x, NULL, iu);
    return (ts_vec2){x, y};
}

/* Density of piece i of a 1D distribution whose function value there is f: piece_pdf. */
static float piece_pdf_of(const ts_distribution1d *d, float f) { return d->func_int > 0 ? f / d->func_int : 1.0f; }

float ts_distribution2d_pdf_cell(const ts_distribution2d *d, uint32_t iv, float f_cell)
{
    return piece_pdf(&d->marginal, iv) * piece_pdf_of(&d->conditional[iv], f_cell);
}

ts_vec2 ts_distribution2d_sample(const ts_distribution2d *d, ts_vec2 u, float *pdf)
{
    uint32_t iu, iv;
    ts_vec2 x = ts_distribution2d_sample_cell(d, u, &iu, &iv);
    if (pdf) *pdf = ts_distribution2d_pdf_cell(d, iv, d->conditional[iv].func[iu]);
    return x;
}

bool ts_distribution2d_cell(const ts_distribution2d *d, ts_vec2 p, uint32_t *iu, uint32_t *iv)
{
    *iu = *iv = 0;
    if (!(p.x >= 0.0f && p.x <= 1.0f && p.y >= 0.0f && p.y <= 1.0f)) return false;
    *iv = piece_of(&d->marginal, p.y);
    *iu = piece_of(&d->conditional[*iv], p.x);
    return true;
}

float ts_distribution2d_pdf(const ts_distribution2d *d, ts_vec2 p)
{
    uint32_t iu, iv;
    if (!ts_distribution2d_cell(d, p, &iu, &iv)) return 0.0f;
    return ts_distribution2d_pdf_cell(d, iv, d->conditional[iv].func[iu]);
}

ts_vec2 ts_distribution2d_invert(const ts_distribution2d *d, ts_vec2 p)
{
    uint32_t iv = (uint32_t)(ts_clampf(p.y, 0.0f, 1.0f) * d->nv);
    if (iv >= d->nv) iv = d->nv - 1;
    return (ts_vec2){ts_distribution1d_invert(&d->conditional[iv], p.x), ts_distribution1d_invert(&d->marginal, p.y)};
}

/* ---- alias table (Vose's algorithm, in double) ---- */

ts_status ts_alias_table_init(ts_alias_table *t, const double *w, uint32_t n, ts_arena *arena, ts_error *err)
{
    memset(t, 0, sizeof *t);
    if (n == 0) return ts_error_set(err, TS_ERR_INVALID, "alias table: no weights");
    if (n > (1u << 24)) return ts_error_set(err, TS_ERR_INVALID, "alias table: %u weights, at most 2^24", n);
    uint32_t nb = 1;
    while (nb < n) nb <<= 1;
    float *pmf = ts_arena_calloc(arena, n, sizeof *pmf);
    float *q = ts_arena_calloc(arena, nb, sizeof *q);
    uint32_t *alias = ts_arena_calloc(arena, nb, sizeof *alias);
    double *scaled = malloc((size_t)nb * sizeof *scaled);
    uint32_t *work = malloc((size_t)nb * sizeof *work);
    ts_status st = TS_OK;
    if (!pmf || !q || !alias || !scaled || !work) {
        st = ts_error_set(err, TS_ERR_NOMEM, "alias table: out of memory for %u weights", n);
        goto fail_free;
    }
    double sum = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (!(w[i] >= 0) || !isfinite(w[i])) {
            st = ts_error_set(err, TS_ERR_INVALID, "alias table: weight %u is %g, expected a finite value ≥ 0", i, w[i]);
            goto fail_free;
        }
        sum += w[i];
    }
    for (uint32_t i = 0; i < nb; i++) {
        double p = i >= n ? 0 : (sum > 0 ? w[i] / sum : 1.0 / n);
        if (i < n) pmf[i] = (float)p;
        scaled[i] = p * nb;
        alias[i] = i < n ? i : 0;
    }
    /* work holds small indices from the front and large ones from the back. */
    uint32_t n_small = 0, n_large = 0;
    for (uint32_t i = 0; i < nb; i++) {
        if (scaled[i] < 1.0) work[n_small++] = i;
        else work[nb - 1 - n_large++] = i;
    }
    while (n_small > 0 && n_large > 0) {
        uint32_t s = work[--n_small];
        uint32_t l = work[nb - n_large]; /* most recently pushed large */
        q[s] = (float)scaled[s];
        alias[s] = l;
        scaled[l] = (scaled[l] + scaled[s]) - 1.0;
        if (scaled[l] < 1.0) {
            n_large--;
            work[n_small++] = l;
        }
    }
    /* Leftovers are 1 up to rounding (an extra bin, of mass exactly 0, is never one). */
    for (uint32_t k = 0; k < n_small; k++) q[work[k]] = work[k] < n ? 1.0f : 0.0f;
    for (uint32_t k = 0; k < n_large; k++) q[work[nb - 1 - k]] = 1.0f;
    /* An outcome of probability 0 must never be returned, even through rounding: send its
     * bin wholly to its alias (or to any positive outcome); the extra bins likewise. */
    uint32_t any_positive = 0;
    while (any_positive < n && pmf[any_positive] == 0) any_positive++;
    if (any_positive == n) any_positive = 0;
    for (uint32_t i = 0; i < nb; i++) {
        if (i >= n || pmf[i] == 0) q[i] = 0.0f;
        if (q[i] < 1.0f && (alias[i] >= n || pmf[alias[i]] == 0)) alias[i] = any_positive;
    }
    t->n = n;
    t->n_bins = nb;
    t->pmf = pmf;
    t->q = q;
    t->alias = alias;
    t->total_weight = sum;
fail_free:
    free(work);
    free(scaled);
    return st;
}

uint32_t ts_alias_table_sample(const ts_alias_table *t, ts_vec2 u, float *pmf)
{
    /* n_bins is a power of two ≤ 2^24, so this product is exact for sampler values. */
    float x = u.x * (float)t->n_bins;
    uint32_t i = x < (float)t->n_bins ? (uint32_t)x : t->n_bins - 1;
    uint32_t k = u.y < t->q[i] ? i : t->alias[i];
    if (pmf) *pmf = t->pmf[k];
    return k;
}
