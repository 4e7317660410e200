/* sampler.h — deterministic sample values for pixel samples.
 *
 * Design note: a sample value is a pure function of (seed, pixel, sample index,
 * dimension) (docs/design.md §6), so no generator state travels with a thread and any tile
 * order gives bit-identical images. Dimensions are 2-D: dimension 0 is the film position,
 * 1 the lens, 2.. belong to the integrator. A 1-D draw takes the first component of its
 * dimension's 2-D value and consumes the whole dimension.
 *
 * TS_SAMPLER_SOBOL: the 2-D (0,2)-sequence (the first two Sobol dimensions) per
 * dimension, with Burley's hash-based nested-uniform Owen scramble of each coordinate and
 * a nested-uniform shuffle of the sample index ("Practical Hash-based Owen Scrambling",
 * JCGT 2020), all seeded by a hash of (seed, px, py, dim). The index shuffle maps every
 * aligned block [k·2^m, (k+1)·2^m) of sample indices onto an aligned block of 2^m
 * sequence indices, so the first 2^m samples of a pixel — and every later aligned block
 * of 2^m — form a (0,m,2)-net in every dimension: progressive rendering in passes of
 * 1, 2, 4, … samples stays stratified. Different dimensions and pixels get independent
 * scrambles and shuffles, so dimensions are mutually decorrelated.
 *
 * TS_SAMPLER_INDEPENDENT: a hash of (seed, px, py, index, dim) gives two uniform values.
 *
 * Values are multiples of 2^-24 in [0, TS_ONE_MINUS_EPSILON]: the top 24 bits, truncated,
 * so a value never rounds up across a stratum boundary and never reaches 1.
 * Everything here is pure and thread-safe; a ts_sample_stream belongs to its caller. */
#ifndef TS_SAMPLER_H
#define TS_SAMPLER_H

#include <stdint.h>

#include "core/vecmath.h"

typedef enum ts_sampler_type { TS_SAMPLER_SOBOL, TS_SAMPLER_INDEPENDENT } ts_sampler_type;

/* Immutable configuration, shared read-only by all threads. */
typedef struct ts_sampler {
    ts_sampler_type type;
    uint32_t seed;
} ts_sampler;

/* What all samples of one pixel share (sobol): the scramble seeds of its first
 * TS_SAMPLER_PIXEL_DIMS dimensions, three hashes each that depend on (seed, px, py, dim)
 * but not on the sample index. Filled lazily, a dimension when a stream begun from it
 * first draws it, so a pixel's later samples skip those hashes; the values drawn are bit
 * for bit those of ts_sampler_begin's streams. Caller storage; one thread's, one pixel at
 * a time (its streams write to it). */
#define TS_SAMPLER_PIXEL_DIMS 48 /* ≤ 64: one bit of `filled` each */
typedef struct ts_sampler_pixel {
    ts_sampler_type type;
    uint32_t seed, px, py;
    uint32_t hash;   /* the pixel's hash (ts_sampler_begin's for sobol) */
    uint64_t filled; /* bit d: seeds[d] is computed */
    uint32_t seeds[TS_SAMPLER_PIXEL_DIMS][3];
} ts_sampler_pixel;

/* One pixel sample's sequence of dimensions; caller storage (e.g. on the stack). */
typedef struct ts_sample_stream {
    ts_sampler_type type;
    uint32_t seed, px, py, index, dim; /* dim = next dimension to be drawn */
    uint32_t hash; /* set by ts_sampler_begin: hash of what all dimensions share */
    uint32_t index_reversed; /* sobol: index with its bits reversed, shared by all dimensions */
    ts_sampler_pixel *pixel; /* NULL, or the pixel's seed cache (ts_sampler_begin_in_pixel) */
} ts_sample_stream;

/* Starts sample `index` of pixel (px, py) at dimension 0. */
void ts_sampler_begin(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, ts_sample_stream *out);

/* Starts the seed cache of pixel (px, py), empty. */
void ts_sampler_pixel_init(const ts_sampler *s, uint32_t px, uint32_t py, ts_sampler_pixel *pixel);

/* ts_sampler_begin for the cache's pixel, drawing through (and filling) the cache. */
void ts_sampler_begin_in_pixel(ts_sampler_pixel *pixel, uint32_t index, ts_sample_stream *out);

/* In [0, 1); consumes one dimension (the value is the x of that dimension's 2-D value). */
float ts_sample_1d(ts_sample_stream *st);

/* In [0, 1)^2; consumes one dimension. */
ts_vec2 ts_sample_2d(ts_sample_stream *st);

/* Pure: value of dimension `dim` of sample `index` of pixel (px, py). ts_sample_2d returns
 * exactly this, whatever was drawn before. */
ts_vec2 ts_sampler_value_2d(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, uint32_t dim);

/* Pure: the 1-D value of that dimension, ts_sampler_value_2d(...).x. */
float ts_sampler_value_1d(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, uint32_t dim);

/* One dimension of one pixel, for arrays of sample values of that dimension (pbrt-v3's
 * sample arrays: the integrator's many light samples of one camera sample): what
 * ts_sampler_value_2d computes before it looks at the sample index — for sobol the
 * pixel's and the dimension's hashes and the three scramble seeds — done once, so each
 * value costs only its index's shuffle and scrambles. Caller storage, immutable after
 * init. */
typedef struct ts_sampler_dim {
    ts_sampler_type type;
    uint32_t seed, px, py, dim;
    uint32_t seeds[3]; /* sobol */
} ts_sampler_dim;

void ts_sampler_dim_init(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t dim, ts_sampler_dim *out);

/* Pure: ts_sampler_value_2d(s, px, py, index, dim) of d's sampler, pixel and dimension,
 * bit for bit. */
ts_vec2 ts_sampler_dim_value_2d(const ts_sampler_dim *d, uint32_t index);
/* Pure: its x alone, ts_sampler_dim_value_2d(d, index).x bit for bit (the y's scramble
 * is not computed). */
float ts_sampler_dim_value_1d(const ts_sampler_dim *d, uint32_t index);

/* Name used in the scene format ("sobol", "independent"). */
const char *ts_sampler_type_name(ts_sampler_type type);

#endif
