/* distribution.h — piecewise-constant 1D and 2D distributions and an alias table.
 *
 * Design note: these are the tables behind importance sampling (pbrt-v3 §13.3.1 and
 * §14.2.4): a 1D piecewise-constant density on [0,1) with its CDF, a 2D one built as a
 * marginal over rows and one conditional per row, and Walker's alias table for O(1)
 * discrete selection with exactly stored probabilities (used for light selection).
 * Every sampler comes with its pdf and, for the continuous ones, its inverse.
 *
 * Memory: tables are allocated from a caller's arena (per-scene memory, docs/design.md §6)
 * and are immutable after init, so all query functions are pure and thread-safe.
 * Construction is done in double precision; stored values are float. */
#ifndef TS_DISTRIBUTION_H
#define TS_DISTRIBUTION_H

#include <stdbool.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/error.h"
#include "core/vecmath.h"

/* Piecewise-constant density on [0,1) with n equal pieces. */
typedef struct ts_distribution1d {
    uint32_t n;
    const float *func; /* n: |f| as given (negative values are taken as absolute) */
    const float *cdf;  /* n + 1: cdf[0] = 0, cdf[n] = 1 */
    float func_int;    /* ∫ f over [0,1) = Σ f / n; 0 if f ≡ 0 (then the cdf is uniform) */
    /* Guide table (the cutpoint method): n_guide, the smallest power of two ≥ ⌊n/4⌋
     * (so at most n/2 for n ≥ 2), and guide[k] for k = 0..n_guide the largest i < n with cdf[i] ≤ k/n_guide.
     * A u in [k, k+1)/n_guide has its piece in [guide[k], guide[k+1]], so sampling
     * searches those few pieces instead of all n: the same piece, bit for bit, as a
     * binary search over the whole cdf, from one or two cache lines. */
    uint32_t n_guide;
    const uint32_t *guide;
} ts_distribution1d;

/* Builds from f[0..n) (copied), n ≥ 1. All-zero (or non-finite-free zero) input gives a
 * uniform cdf with func_int = 0, so sampling still works and pdfs are the uniform ones;
 * callers that must not sample zero functions check func_int. TS_ERR_INVALID for n = 0
 * or a non-finite value, TS_ERR_NOMEM when the arena is exhausted. */
ts_status ts_distribution1d_init(ts_distribution1d *d, const float *f, uint32_t n, ts_arena *arena,
                                 ts_error *err);

/* Continuous sample x in [0,1) for u in [0,1); *pdf (density in x) and *offset (piece
 * index) if not NULL. */
float ts_distribution1d_sample_continuous(const ts_distribution1d *d, float u, float *pdf, uint32_t *offset);
/* Density at x in [0,1] (x = 1 belongs to the last piece). */
float ts_distribution1d_pdf(const ts_distribution1d *d, float x);
/* u such that sample_continuous(u) = x (the CDF at x); x in [0,1]. */
float ts_distribution1d_invert(const ts_distribution1d *d, float x);
/* Discrete sample: piece index with probability f[i] / Σ f; *pmf, and *u_remapped (u
 * stretched back to [0,1) within the piece) if not NULL. */
uint32_t ts_distribution1d_sample_discrete(const ts_distribution1d *d, float u, float *pmf, float *u_remapped);
float ts_distribution1d_discrete_pmf(const ts_distribution1d *d, uint32_t i);

/* Piecewise-constant density on [0,1)² from f[v][u] (nu columns, nv rows, row-major). */
typedef struct ts_distribution2d {
    uint32_t nu, nv;
    const ts_distribution1d *conditional; /* nv rows, each over u */
    ts_distribution1d marginal;           /* over v, of the row integrals */
} ts_distribution2d;

ts_status ts_distribution2d_init(ts_distribution2d *d, const float *f, uint32_t nu, uint32_t nv, ts_arena *arena,
                                 ts_error *err);
/* Sample (u, v) in [0,1)² with density *pdf (if not NULL). */
ts_vec2 ts_distribution2d_sample(const ts_distribution2d *d, ts_vec2 u, float *pdf);
/* Density at p in [0,1]². */
float ts_distribution2d_pdf(const ts_distribution2d *d, ts_vec2 p);
/* The same two for callers that keep f next to data they read anyway (the environment
 * map's texels), so the table's own copy of f is not read: ts_distribution2d_sample's
 * value with its cell (column *iu, row *iv) instead of its density, and the density of
 * the cell in row iv whose value is f_cell (f[iv][iu] as given to init):
 * ts_distribution2d_pdf_cell(d, iv, |f[iv][iu]|) is bit for bit the density
 * ts_distribution2d_sample returns, and with the cell of p the one ts_distribution2d_pdf
 * returns (ts_distribution2d_cell). */
ts_vec2 ts_distribution2d_sample_cell(const ts_distribution2d *d, ts_vec2 u, uint32_t *iu, uint32_t *iv);
float ts_distribution2d_pdf_cell(const ts_distribution2d *d, uint32_t iv, float f_cell);
/* The cell of p in [0,1]² whose density ts_distribution2d_pdf gives (false, and 0, 0,
 * where that density is 0 because p is outside). */
bool ts_distribution2d_cell(const ts_distribution2d *d, ts_vec2 p, uint32_t *iu, uint32_t *iv);
/* Inverse of ts_distribution2d_sample. */
ts_vec2 ts_distribution2d_invert(const ts_distribution2d *d, ts_vec2 p);
/* Integral of f over [0,1)² (mean of f). */
static inline float ts_distribution2d_integral(const ts_distribution2d *d) { return d->marginal.func_int; }

/* Walker/Vose alias table over 1 ≤ n ≤ 2^24 non-negative weights. pmf[i] = w[i] / Σ w,
 * computed in double; if every weight is 0 the table is uniform (total_weight = 0 tells
 * you). The table has n_bins = the power of two ≥ n bins (the n_bins − n extra ones hold
 * no outcome of their own: keep probability 0, always their alias), so a sampler value —
 * a multiple of 2^-24 — picks a bin from its top log2(n_bins) bits with exactly equal
 * probability for every bin; with n bins, 10^6 lights got 16 or 17 of the 2^24 values
 * each, their probabilities off by −4.6% to +1.3%. */
typedef struct ts_alias_table {
    uint32_t n;             /* outcomes */
    uint32_t n_bins;        /* power of two ≥ n */
    const float *pmf;       /* n exact probabilities */
    const float *q;         /* n_bins: probability of keeping bin i */
    const uint32_t *alias;  /* n_bins: the other outcome of bin i */
    double total_weight;    /* Σ w */
} ts_alias_table;

/* TS_ERR_INVALID for n = 0, n > 2^24 or a negative or non-finite weight; TS_ERR_NOMEM. */
ts_status ts_alias_table_init(ts_alias_table *t, const double *w, uint32_t n, ts_arena *arena, ts_error *err);
/* Index with probability pmf[index]; *pmf if not NULL. Never returns an index whose pmf
 * is 0 (unless all are 0 and the table is uniform). u.x picks the bin, u.y is the coin
 * that keeps it or takes its alias: two independent values — in the integrators the two
 * components of one 2-D sampler dimension, which the (0,2)-sequence stratifies jointly
 * (integrator.h). The coin must not be frac(u.x·n_bins) of the same value: sampler values
 * are multiples of 2^-24, so a bin holds only 2^24/n_bins of them and the coin would take
 * that few values; with 10^6 lights of uneven power the real probabilities were off the
 * pmf by up to 8.6× and 18% of the lights were never chosen (test_distribution's χ²). */
uint32_t ts_alias_table_sample(const ts_alias_table *t, ts_vec2 u, float *pmf);
static inline float ts_alias_table_pmf(const ts_alias_table *t, uint32_t i) { return i < t->n ? t->pmf[i] : 0.0f; }

#endif
