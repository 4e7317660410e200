/* fourier_bsdf.h — tabulated BSDFs in pbrt-v3's Fourier basis ("SCATFUN" v1 .bsdf files).
 *
 * Design note (pbrt-v3 §8.6): the BSDF times |cosθi| is stored, for every pair of nodes
 * (μi, μo) of a grid of cosines, as a truncated cosine series in the azimuth difference
 * φ. Evaluation interpolates the coefficients with Catmull-Rom weights over μi and μo
 * and sums the series; sampling draws μi from the 2D Catmull-Rom spline of the series'
 * constant term (with the stored CDF) and then φ from the interpolated series. Directions
 * are in the shading frame; by the file convention μi is the cosine of −wi.
 *
 * A table is immutable after loading and may be shared by any number of threads. The
 * loader reads every table pbrt-v3's FourierBSDFTable::Read reads — repeated cosine nodes
 * (μ = 0 twice in the pbrt-v3-scenes collection's tables), bytes after the coefficients
 * (the header's nMetadataBytes of description) left unread — and checks everything a
 * malformed file could break (magic, flags, counts, non-decreasing nodes with a non-empty
 * last interval, offsets and lengths inside the coefficient array, mMax × channels ≤ 4096
 * — the evaluator's stack scratch) so evaluation never reads out of bounds or silently
 * drops terms; errors name the file, the problem and its byte. */
#ifndef TS_FOURIER_BSDF_H
#define TS_FOURIER_BSDF_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/vecmath.h"

typedef struct ts_fourier_table {
    float eta;            /* relative index of refraction (inside / outside) */
    int m_max;            /* most coefficients of any series */
    int n_channels;       /* 1 (luminance Y) or 3 (Y, R, B) */
    int n_mu;             /* number of cosine nodes */
    float *mu;            /* [n_mu] ascending cosines */
    int *m;               /* [n_mu²] series length at (o, i): m[o·n_mu + i] */
    int *a_offset;        /* [n_mu²] offset of that series in a */
    float *a;             /* [n_coeffs] coefficients; channel c of a series of length m at offset + c·m */
    float *a0;            /* [n_mu²] constant term of the luminance series (0 if empty) */
    float *cdf;           /* [n_mu²] running integral over μi of a0 for each μo row */
    float *recip;         /* [m_max] 1/k */
    int n_coeffs;
} ts_fourier_table;

/* Reads a pbrt-v3 .bsdf file. On success *out owns the table (free with
 * ts_fourier_table_destroy). On failure returns TS_ERR_IO (cannot open/read, truncated)
 * or TS_ERR_INVALID / TS_ERR_UNSUPPORTED (bad content) with a sentence naming the file;
 * *out is left NULL. Thread-safe. */
ts_status ts_fourier_table_load(const char *path, struct ts_fourier_table **out, ts_error *err);

/* The same from an in-memory file image of size bytes (only read); path names it in
 * messages (NULL: "(memory)"). Errors as ts_fourier_table_load except TS_ERR_IO. */
ts_status ts_fourier_table_load_memory(const unsigned char *buf, size_t size, const char *path,
                                       struct ts_fourier_table **out, ts_error *err);

/* Frees a table from ts_fourier_table_load; NULL is accepted. */
void ts_fourier_table_destroy(struct ts_fourier_table *t);

/* ---- evaluation (used by bxdf.c; local shading frame, +z the normal) ---- */

/* BSDF value f(wo, wi) (not multiplied by |cosθi|) for radiance transport. */
ts_rgb ts_fourier_f(const ts_fourier_table *t, ts_vec3 wo, ts_vec3 wi);
/* Solid-angle pdf of ts_fourier_sample. */
float ts_fourier_pdf(const ts_fourier_table *t, ts_vec3 wo, ts_vec3 wi);
/* Samples wi given wo; returns f and sets *pdf (0 when no sample could be drawn). */
ts_rgb ts_fourier_sample(const ts_fourier_table *t, ts_vec3 wo, ts_vec2 u, ts_vec3 *wi, float *pdf);

/* ---- Catmull-Rom and Fourier helpers (pbrt-v3 §8.6, appendix A.4), exposed for tests ---- */

/* Spline weights of x among nodes[0..n): *offset is the index of the first of four
 * consecutive nodes (weights of nodes outside [0, n) are 0). False if x is outside
 * [nodes[0], nodes[n−1]]. */
bool ts_catmull_rom_weights(int n, const float *nodes, float x, int *offset, float weights[4]);
/* Σ_k a[k] cos(kφ) given cos φ (Chebyshev recurrence, double accumulation). */
float ts_fourier_eval(const float *a, int m, double cos_phi);
/* Integral over x of the Catmull-Rom spline through (x[i], values[i]); cdf[i] gets the
 * running integral up to x[i] (cdf[0] = 0); returns the total. */
float ts_catmull_rom_integrate(int n, const float *x, const float *values, float *cdf);

#endif
