/* render_stats.h — statistics of independent renders, for tests whose tolerance must come
 * from the estimator's real error (docs/design.md §8).
 *
 * Design note: a scene is rendered K times with K different seeds (independent Owen
 * scrambles for the Sobol sampler, independent hashes for the independent one); each
 * render's film is cut into square blocks of pixels and each block's mean (the mean of
 * its pixels' channel average) recorded. The K block means of a block are independent,
 * identically distributed estimates, so their spread gives the block's standard error —
 * unlike a single render's per-pixel variance, which for a stratified (Sobol) render
 * is the variance of an *independent* sample and overstates the real error many times.
 * Two strategies are compared block by block and as whole images with Welch's t (its
 * Welch–Satterthwaite degrees of freedom), an estimate against a reference with
 * Student's t; the smallest p-value over the blocks and the image is held to
 * α / (blocks + 1) (Bonferroni), so a comparison fails
 * correct code with probability at most α, as far as block means are normal (each is the
 * average of hundreds of pixel samples or more: the central limit theorem) — a test
 * names its α. Deterministic for given seeds. Not thread-safe (renders with 2 threads
 * and modifies the scene's sampler settings). */
#ifndef TS_TESTS_RENDER_STATS_H
#define TS_TESTS_RENDER_STATS_H

#include <stdint.h>

#include "render/render.h"

#define TS_RS_MAX_BLOCKS 256

typedef struct ts_rs_blocks {
    int nx, ny, n;                 /* blocks across, down, in all */
    int k;                         /* renders */
    double mean[TS_RS_MAX_BLOCKS]; /* per block: mean over the K renders */
    double se[TS_RS_MAX_BLOCKS];   /* its standard error, from the spread of the K */
    double image_mean, image_se;   /* the same for the whole image */
    uint64_t nonfinite;            /* samples the renderer dropped, over all renders */
    double seconds;                /* render time, all K */
} ts_rs_blocks;

/* Renders s (its integrator, at spp) K ≥ 2 times with sampler `type` and seeds seed0,
 * seed0 + 1, …, seed0 + K − 1, in blocks of block × block pixels (the film's size must be
 * a multiple of block in both directions, at most TS_RS_MAX_BLOCKS blocks). Fails the
 * cmocka test on a render error. */
void ts_rs_render(ts_scene *s, ts_sampler_type type, uint32_t seed0, int k, int spp, int block,
                  ts_rs_blocks *out);

/* Two-sided tail P(|T| ≥ |t|) of Student's t with dof > 0 degrees of freedom (dof may be
 * fractional, as Welch's are). */
double ts_rs_student_two_sided(double t, double dof);

typedef struct ts_rs_result {
    double p;       /* smallest two-sided p-value over the blocks */
    int block;      /* where (−1 if every block agrees exactly) */
    double t, dof;  /* that block's statistic and degrees of freedom */
    double diff;    /* that block's difference a − b (or a − reference) */
    double image_t; /* the whole image's statistic, difference and p-value */
    double image_diff;
    double image_p;
} ts_rs_result;

/* Welch's comparison of two independent sets of renders of the same scene and film.
 * Block differences below floor (absolute) pass whatever their standard error: the
 * resolution the caller asks for. It keeps rare-event blocks out — where an estimator
 * finds a faint contribution only through events too rare for K renders to see (a BSDF
 * sample reaching a light through the far tail of a glossy lobe), so its K estimates are
 * all 0 and their spread says nothing. Pass 0 to test every difference. */
ts_rs_result ts_rs_compare(const ts_rs_blocks *a, const ts_rs_blocks *b, double floor);
/* a against reference block values ref[i] ± ref_se[i] (ref_se NULL: exact values), the
 * reference's standard errors with ref_dof degrees of freedom (ignored when exact). */
ts_rs_result ts_rs_compare_reference(const ts_rs_blocks *a, const double *ref, const double *ref_se,
                                     double ref_dof, double floor);

/* Bonferroni over the blocks and the whole image: true when the smallest block p and the
 * image's p are both ≥ alpha / (blocks + 1). */
int ts_rs_passes(const ts_rs_result *r, int blocks, double alpha);

#endif
