/* chi2.h — Pearson χ² goodness-of-fit test of a direction sampler against its own pdf.
 *
 * Design note: the sphere is cut into equal-solid-angle cells, uniform in cosθ (rows,
 * an odd number so the horizon z = 0 runs through the middle of a row rather than along
 * a cell border — the quadrature splits that row at z = 0 exactly) and uniform in φ.
 * The sampler is run N times and its directions histogrammed; the expected count of a
 * cell is N ∫_cell pdf dω, integrated in double precision by an adaptive tensor Gauss–
 * Legendre rule that splits rectangles of the (cosθ, φ) cell along the axis with the
 * larger error estimate (so a discontinuity along a row edge costs O(depth) work), with a
 * per-rectangle tolerance tied to the statistical noise √E of the cell. A sharp lobe that
 * falls between quadrature nodes is found through the samples themselves: the first few
 * samples of every cell are kept, and a rectangle holding one whose pdf exceeds the
 * largest pdf the rectangle's nodes saw is split until the nodes resolve it. The samples
 * only decide where to refine, never what the integral is.
 *
 * Samples the sampler reports as "none" (no sample) or "discrete" (a delta lobe: not a
 * density) go into one extra bin whose expected count is N (1 − ∫_sphere pdf): the test
 * therefore also checks that the pdf integrates to the fraction of continuous samples.
 * Cells (and that bin) with expected count < min_expected are pooled into one bin; if the
 * pooled bin is still short it absorbs the smallest other bins. A sample in a cell whose
 * expected count is below 1e-8 (the pdf integrates to ~0 there) fails at once.
 * Where the quadrature could not reach its target (budget exhausted, e.g. along a curved
 * discontinuity), its error estimate σ is added to the variance: a bin contributes
 * (O − E)² / (E + σ²). The statistic is compared with the χ² distribution of (bins − 1) degrees of freedom;
 * the test passes when p ≥ 1 − (1 − significance)^(1/test_count) (Šidák correction, so
 * that a family of test_count independent tests of correct code fails with probability
 * `significance`).
 *
 * Independent of what is sampled: BSDFs, lights and shapes all plug in through the two
 * callbacks and a context pointer. Deterministic for a given seed. Not thread-safe per
 * call only in that the callbacks must be; uses no global state. */
#ifndef TS_TESTS_CHI2_H
#define TS_TESTS_CHI2_H

#include <stdbool.h>
#include <stdint.h>

#include "core/hash.h"
#include "core/vecmath.h"

/* Upper bound on the number of χ² tests in the whole project's suite (BSDFs, lights,
 * shapes, warps), the default Šidák family size: with it, correct code fails some χ²
 * test of `make test` with probability ≤ 0.01 (for a random choice of seeds). */
#define TS_CHI2_FAMILY_SIZE 256

typedef enum ts_chi2_outcome {
    TS_CHI2_NONE,      /* the sampler produced nothing (e.g. the direction fell below the horizon) */
    TS_CHI2_DIRECTION, /* *w_out is a unit direction drawn from the density the pdf callback gives */
    TS_CHI2_DISCRETE,  /* a delta (specular) sample: not part of the density */
} ts_chi2_outcome;

/* Draws one sample with random numbers taken from rng (as many as it needs). */
typedef ts_chi2_outcome (*ts_chi2_sample_fn)(void *ctx, ts_pcg32 *rng, ts_vec3 *w_out);
/* Solid-angle density of the continuous part at unit direction w (≥ 0, finite). */
typedef double (*ts_chi2_pdf_fn)(void *ctx, ts_vec3 w);

typedef struct ts_chi2_params {
    uint64_t sample_count; /* N; default 10^6 */
    int cos_theta_res;     /* rows in cosθ; must be odd; default 21 */
    int phi_res;           /* columns in φ; default 2 · cos_theta_res */
    double significance;   /* family-wise false-failure rate; default 0.01 */
    int test_count;        /* number of χ² tests in the family (Šidák); default TS_CHI2_FAMILY_SIZE */
    double min_expected;   /* pooling threshold; default 5 */
    uint64_t seed;         /* PCG32 seed of the sample stream; default 1 */
    int max_node_evals;    /* quadrature budget per cell (pdf calls); default 2 000 000 */
} ts_chi2_params;

typedef struct ts_chi2_result {
    bool passed;
    double statistic;     /* Pearson χ² */
    int dof;              /* bins after pooling − 1 */
    double p_value;       /* P(χ²_dof ≥ statistic) */
    double threshold;     /* per-test significance after Šidák */
    double pdf_integral;  /* ∫_sphere pdf dω by the same quadrature */
    double quadrature_error; /* bound on the error of pdf_integral (sum of the cells' estimates) */
    uint64_t binned;      /* TS_CHI2_DIRECTION samples */
    uint64_t discrete;    /* TS_CHI2_DISCRETE samples */
    uint64_t none;        /* TS_CHI2_NONE samples */
    uint64_t pdf_evals;   /* pdf callback calls made by the quadrature */
    int unconverged;      /* cells whose quadrature hit max_node_evals (should be 0) */
    char message[768];    /* why it failed, or a one-line summary when it passed */
} ts_chi2_result;

/* Fills p with the defaults above. */
void ts_chi2_params_default(ts_chi2_params *p);

/* Runs the test. Returns result->passed. Fails (with a message) on invalid parameters,
 * a non-finite or non-unit sample, a sample in a zero-pdf cell, a negative or non-finite
 * pdf value, or p < threshold. Allocates O(cells) memory, freed before returning. */
bool ts_chi2_test(const ts_chi2_params *p, ts_chi2_sample_fn sample, ts_chi2_pdf_fn pdf, void *ctx,
                  ts_chi2_result *result);

/* ∫_sphere pdf dω by the same adaptive quadrature (no samples, so no sample-guided
 * refinement: only for pdfs without lobes narrower than a cell / 4^6). */
double ts_chi2_integrate(ts_chi2_pdf_fn pdf, void *ctx, int cos_theta_res, int phi_res, double abs_tol);

/* Upper tail of the χ² distribution, P(X ≥ x) for dof degrees of freedom (regularised
 * incomplete gamma Q(dof/2, x/2)); exposed so tests can check it. */
double ts_chi2_upper_tail(double x, int dof);

/* 1 − (1 − alpha)^(1/tests). */
double ts_chi2_sidak(double alpha, int tests);

#endif
