/* filter.h — pixel reconstruction filters, used by filter importance sampling.
 *
 * Design note: instead of splatting each sample into every pixel under the filter's
 * footprint, a pixel's sample is placed at an offset d from the pixel centre drawn with a
 * density p(d) close to |f(d)|, and is added to that pixel only, with weight f(d)/p(d)
 * (pbrt-v4's approach). Tiles therefore never write outside themselves and pixels have
 * one writer each.
 *
 * Every filter f is normalised to unit integral over its square support [-r, r]^2 and is
 * separable, f(x, y) = f1(x)·f1(y), with f1 integrating to 1 over [-r, r]:
 *   box       f1 = 1/(2r)                                  sampled uniformly, weight 1
 *   triangle  f1 = (r − |x|)/r²                              sampled exactly,   weight 1
 *   gaussian  f1 ∝ exp(−x²/2σ²) − exp(−r²/2σ²), σ = r/3        tabulated
 *   mitchell  f1 = (2/r)·M(2x/r), Mitchell–Netravali B = C = 1/3 tabulated
 * ts_filter_init_params sets the gaussian's α = 1/(2σ²) (pbrt-v3's `alpha`; its profile is
 * exp(−α x²) − exp(−α r²)) and Mitchell's B and C instead of those defaults.
 * For gaussian and mitchell, |f1| is tabulated over [-r, r] in TS_FILTER_TABLE_CELLS
 * cells (cell value = mean of |f1| over the cell) and sampled by inverting the CDF of
 * that piecewise-constant density, so f/p stays near ±∫|f|.
 *
 * Expected value of the weight: E[f(d)/p(d)] = ∫f = 1 for all four filters (exactly, for
 * the density actually sampled). Box and triangle weights are exactly 1; gaussian
 * weights are close to 1 (standard deviation ≈ 0.02; only the outermost cells, where f
 * falls linearly to 0, give weights spread over (0, 2)); mitchell weights are negative
 * where f is (its negative lobes), with E[w] = 1 and E[|w|] = (∫|f1|)² ≈ 1.07² ≈ 1.14.
 * The film divides Σ w·L by Σ w, so the normalisation cancels in the pixel value.
 *
 * A ts_filter is immutable after ts_filter_init and may be shared by threads. The
 * sampling and evaluation functions are pure and thread-safe and allocate nothing. */
#ifndef TS_FILTER_H
#define TS_FILTER_H

#include "core/error.h"
#include "core/vecmath.h"

typedef enum ts_filter_type {
    TS_FILTER_BOX,
    TS_FILTER_TRIANGLE,
    TS_FILTER_GAUSSIAN,
    TS_FILTER_MITCHELL
} ts_filter_type;

/* Cells of the tabulated 1-D density over [-r, r] (64 per radius). */
#define TS_FILTER_TABLE_CELLS 128

/* Caller storage; fixed-size tables inside, no heap. Fields are private to filter.c. */
typedef struct ts_filter {
    ts_filter_type type;
    float radius;                          /* r, pixels */
    float profile_scale;                   /* gaussian: 1/∫ of the unnormalised profile; mitchell: 2/r */
    double mitchell_b, mitchell_c;         /* mitchell: B and C */
    float gaussian_alpha, gaussian_floor;  /* gaussian: 1/(2σ²) and exp(−r²/2σ²) */
    float cdf[TS_FILTER_TABLE_CELLS + 1];  /* tabulated filters: CDF, cdf[0] = 0, last = 1 */
    float cell_pdf[TS_FILTER_TABLE_CELLS]; /* density of x in each cell (per pixel) */
} ts_filter;

/* Fills f for `type` with `radius` > 0 (pixels, finite). TS_ERR_INVALID for a bad radius
 * or type. Thread-safe (touches only f and err). */
ts_status ts_filter_init(ts_filter *f, ts_filter_type type, float radius, ts_error *err);

/* Parameters beyond the radius (pbrt-v3's). */
typedef struct ts_filter_params {
    float gaussian_alpha;     /* gaussian: α > 0, finite; 0: σ = radius/3 (α = 4.5/radius²) */
    bool mitchell_custom;     /* mitchell: use b and c below (else B = C = 1/3) */
    float mitchell_b, mitchell_c; /* finite */
} ts_filter_params;

/* ts_filter_init with params (NULL: the defaults above). TS_ERR_INVALID for a bad α, B or C. */
ts_status ts_filter_init_params(ts_filter *f, ts_filter_type type, float radius, const ts_filter_params *params,
                                ts_error *err);

/* Offset from the pixel centre, in pixels with |dx|, |dy| <= radius, for u in [0,1)^2, and
 * in *weight (not NULL) the sample's weight f(d)/p(d) (negative in Mitchell's negative
 * lobes). Monotone in each component of u, so stratified u give stratified offsets. */
ts_vec2 ts_filter_sample(const ts_filter *f, ts_vec2 u, float *weight);

/* f(offset), normalised to unit integral; 0 outside [-r, r]^2. */
float ts_filter_eval(const ts_filter *f, ts_vec2 offset);

/* Name used in the scene format ("box", "triangle", "gaussian", "mitchell"). */
const char *ts_filter_type_name(ts_filter_type type);

#endif
