/* chi2_bsdf.h — χ² adapters (chi2.h) for one BxDF and for a whole BSDF.
 *
 * Design note: the tests of BxDFs, Fourier BSDFs and materials all check a sampler the
 * same way: draw (u_lobe,) u from the χ² harness's generator, call sample_f, report a
 * specular pick as discrete, and hold every other sample to the sampling contract — its f
 * and pdf equal f and pdf evaluated at the sampled direction (relative 1e-4: the same
 * float expressions on both paths); the pdf callback is the lobe's pdf. And each checks
 * that ∫pdf equals the fraction of samples that were directions. These helpers are that
 * code, once. */
#ifndef TS_TESTS_CHI2_BSDF_H
#define TS_TESTS_CHI2_BSDF_H

#include <stdbool.h>

#include "chi2.h"
#include "materials/bsdf.h"
#include "materials/bxdf.h"

typedef struct ts_chi2_bxdf {
    ts_bxdf b;
    ts_vec3 wo; /* unit, in the lobe's local frame */
} ts_chi2_bxdf;

typedef struct ts_chi2_bsdf {
    ts_bsdf b;
    ts_vec3 wo; /* unit, world space */
} ts_chi2_bsdf;

/* ts_chi2_sample_fn / ts_chi2_pdf_fn with a ts_chi2_bxdf or a ts_chi2_bsdf as context. */
ts_chi2_outcome ts_chi2_bxdf_sample(void *ctx, ts_pcg32 *rng, ts_vec3 *w);
double ts_chi2_bxdf_pdf(void *ctx, ts_vec3 w);
ts_chi2_outcome ts_chi2_bsdf_sample(void *ctx, ts_pcg32 *rng, ts_vec3 *w);
double ts_chi2_bsdf_pdf(void *ctx, ts_vec3 w);

/* ∫pdf against the fraction of samples that were directions (*frac): equal within 1e-3
 * (docs/design.md §8) plus 4σ of that binomial fraction (≤ 2e-3 at 10⁶ samples). */
bool ts_chi2_pdf_normalised(const ts_chi2_params *p, const ts_chi2_result *r, double *frac);

#endif
