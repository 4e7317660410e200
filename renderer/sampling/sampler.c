/* sampler.c — Owen-scrambled (0,2)-sequence and independent sampling; see sampler.h.
 *
 * Nested-uniform scrambling (Owen 1995) permutes [0,1) hierarchically: the first bit is
 * flipped at random, the second bit by a random choice that depends on the first, and so
 * on. Burley (2020) obtains such a permutation from a hash: reverse the bits, apply a
 * Laine–Karras style permutation (each output bit depends only on the input bits at or
 * below it, and the map is a bijection), reverse back. Because it only permutes within
 * the dyadic hierarchy it maps elementary intervals onto elementary intervals, which
 * keeps a (0,m,2)-net a (0,m,2)-net. Applied to a sample index it is a shuffle that
 * keeps every aligned block of 2^m indices an aligned block of 2^m. */
#include "sampling/sampler.h"

#include <stddef.h>

#include "core/hash.h"

static inline uint32_t reverse_bits(uint32_t v)
{
    v = __builtin_bswap32(v); /* bytes; then nibbles, pairs and bits within each byte */
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    return ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
}

/* A bijection of 32-bit words in which output bit k depends only on input bits 0..k
 * (adding a constant carries upwards; x ^= x·even only adds higher-bit terms). Constants
 * from Burley 2020, §3. */
static inline uint32_t lk_permute(uint32_t x, uint32_t seed)
{
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

/* Nested-uniform scramble of a 0.32 fixed-point value x (bit 31 is the first binary
 * digit) is reverse_bits(lk_permute(reverse_bits(x), seed)). The code below applies it
 * in that form with the reversals that cancel left out. */

/* Second Sobol dimension, bit-reversed: the (0,2)-sequence's generator columns are
 * v_0 = 1<<31, v_k = v_{k-1} ^ (v_{k-1} >> 1) (Pascal's triangle mod 2), so bit 31−j of
 * Σ_k i_k·v_k is Σ_k i_k·C(k, j) mod 2, and by Lucas' theorem C(k, j) is odd exactly when
 * the bits of j are a subset of those of k. The XOR over all supersets k of j is the
 * GF(2) superset-sum transform: five butterfly stages on the bits of i. Returns
 * reverse_bits(sobol_dim1(i)), bit j holding that sum. The first dimension is van der
 * Corput, reverse_bits(i). */
static inline uint32_t sobol_dim1_reversed(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= (i >> 16) & 0x0000ffffu;
    return i;
}

/* Top 24 bits as a float in [0, 1): exact, so no rounding up to 1 or across strata. */
static inline float bits_to_unit(uint32_t bits) { return (float)(bits >> 8) * 0x1p-24f; }

/* h = ts_hash4(seed, px, py, dim); the three scramble seeds of that dimension. */
static inline void dim_seeds(uint32_t h, uint32_t seeds[3])
{
    seeds[0] = ts_hash_combine(h, 0x01u);
    seeds[1] = ts_hash_combine(h, 0x02u);
    seeds[2] = ts_hash_combine(h, 0x03u);
}

/* The index is shuffled by a nested-uniform scramble (seeds[0]), x = scramble(
 * reverse_bits(shuffled)) and y = scramble(sobol_dim1(shuffled)) (seeds[1], seeds[2]),
 * each written out with the double reversals cancelled; the index comes reversed
 * (index_reversed = reverse_bits(index)), as the shuffle's first step takes it. */
static inline ts_vec2 sobol_value_reversed(const uint32_t seeds[3], uint32_t index_reversed)
{
    uint32_t shuffled = reverse_bits(lk_permute(index_reversed, seeds[0]));
    uint32_t x = reverse_bits(lk_permute(shuffled, seeds[1]));
    uint32_t y = reverse_bits(lk_permute(sobol_dim1_reversed(shuffled), seeds[2]));
    return (ts_vec2){bits_to_unit(x), bits_to_unit(y)};
}

/* index_reversed = reverse_bits(index): a stream reverses its index once for all its
 * dimensions (ts_sampler_begin). */
static inline ts_vec2 sobol_value_hashed(uint32_t h, uint32_t index_reversed)
{
    uint32_t seeds[3];
    dim_seeds(h, seeds);
    return sobol_value_reversed(seeds, index_reversed);
}

/* Hash of (seed, px, py): ts_hash4(seed, px, py, d) = ts_hash_combine(pixel_hash, d). */
static inline uint32_t pixel_hash(uint32_t seed, uint32_t px, uint32_t py)
{
    return ts_hash_combine(ts_hash_combine(ts_hash_u32(seed), px), py);
}

static ts_vec2 sobol_value(uint32_t seed, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    return sobol_value_hashed(ts_hash_combine(pixel_hash(seed, px, py), dim), reverse_bits(index));
}

static ts_vec2 independent_value(uint32_t seed, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    uint32_t h = ts_hash_combine(ts_hash4(seed, px, py, index), dim);
    return (ts_vec2){bits_to_unit(h), bits_to_unit(ts_hash_u32(h ^ 0x68e31da4u))};
}

static ts_vec2 value_2d(ts_sampler_type type, uint32_t seed, uint32_t px, uint32_t py, uint32_t index,
                        uint32_t dim)
{
    switch (type) {
    case TS_SAMPLER_INDEPENDENT:
        return independent_value(seed, px, py, index, dim);
    case TS_SAMPLER_SOBOL:
        break;
    }
    return sobol_value(seed, px, py, index, dim);
}

void ts_sampler_begin(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, ts_sample_stream *out)
{
    uint32_t h = pixel_hash(s->seed, px, py);
    /* The stream caches what every dimension of this sample shares: for sobol the pixel's
     * hash, for independent that combined with the index (see independent_value). */
    if (s->type == TS_SAMPLER_INDEPENDENT) h = ts_hash_combine(h, index);
    *out = (ts_sample_stream){s->type, s->seed, px, py, index, 0, h, reverse_bits(index), NULL};
}

void ts_sampler_pixel_init(const ts_sampler *s, uint32_t px, uint32_t py, ts_sampler_pixel *pixel)
{
    pixel->type = s->type;
    pixel->seed = s->seed;
    pixel->px = px;
    pixel->py = py;
    pixel->hash = pixel_hash(s->seed, px, py);
    pixel->filled = 0;
}

void ts_sampler_begin_in_pixel(ts_sampler_pixel *pixel, uint32_t index, ts_sample_stream *out)
{
    if (pixel->type == TS_SAMPLER_INDEPENDENT) { /* per-sample hashes only: nothing to share */
        ts_sampler sampler = {pixel->type, pixel->seed};
        ts_sampler_begin(&sampler, pixel->px, pixel->py, index, out);
        return;
    }
    *out = (ts_sample_stream){pixel->type, pixel->seed, pixel->px, pixel->py, index, 0, pixel->hash,
                              reverse_bits(index), pixel};
}

/* The seeds of dimension dim (< TS_SAMPLER_PIXEL_DIMS) of a stream's pixel, from its
 * cache (computed there first if no sample of the pixel has drawn that dimension yet). */
static inline const uint32_t *cached_seeds(ts_sampler_pixel *p, uint32_t dim)
{
    uint64_t bit = (uint64_t)1 << dim;
    if (!(p->filled & bit)) {
        dim_seeds(ts_hash_combine(p->hash, dim), p->seeds[dim]);
        p->filled |= bit;
    }
    return p->seeds[dim];
}

/* One dimension of a stream: value_2d(...) of its sample, from the cached hash. */
static inline ts_vec2 stream_value(const ts_sample_stream *st, uint32_t dim)
{
    if (st->type == TS_SAMPLER_INDEPENDENT) {
        uint32_t h = ts_hash_combine(st->hash, dim);
        return (ts_vec2){bits_to_unit(h), bits_to_unit(ts_hash_u32(h ^ 0x68e31da4u))};
    }
    if (st->pixel && dim < TS_SAMPLER_PIXEL_DIMS)
        return sobol_value_reversed(cached_seeds(st->pixel, dim), st->index_reversed);
    return sobol_value_hashed(ts_hash_combine(st->hash, dim), st->index_reversed);
}

float ts_sample_1d(ts_sample_stream *st)
{
    return stream_value(st, st->dim++).x;
}

ts_vec2 ts_sample_2d(ts_sample_stream *st)
{
    return stream_value(st, st->dim++);
}

ts_vec2 ts_sampler_value_2d(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    return value_2d(s->type, s->seed, px, py, index, dim);
}

float ts_sampler_value_1d(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    return value_2d(s->type, s->seed, px, py, index, dim).x;
}

void ts_sampler_dim_init(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t dim, ts_sampler_dim *out)
{
    *out = (ts_sampler_dim){s->type, s->seed, px, py, dim, {0, 0, 0}};
    if (s->type == TS_SAMPLER_SOBOL) dim_seeds(ts_hash_combine(pixel_hash(s->seed, px, py), dim), out->seeds);
}

ts_vec2 ts_sampler_dim_value_2d(const ts_sampler_dim *d, uint32_t index)
{
    if (d->type == TS_SAMPLER_INDEPENDENT) return independent_value(d->seed, d->px, d->py, index, d->dim);
    return sobol_value_reversed(d->seeds, reverse_bits(index));
}

float ts_sampler_dim_value_1d(const ts_sampler_dim *d, uint32_t index)
{
    if (d->type == TS_SAMPLER_INDEPENDENT) return independent_value(d->seed, d->px, d->py, index, d->dim).x;
    uint32_t shuffled = reverse_bits(lk_permute(reverse_bits(index), d->seeds[0]));
    return bits_to_unit(reverse_bits(lk_permute(shuffled, d->seeds[1])));
}

const char *ts_sampler_type_name(ts_sampler_type type)
{
    switch (type) {
    case TS_SAMPLER_SOBOL:
        return "sobol";
    case TS_SAMPLER_INDEPENDENT:
        return "independent";
    }
    return "unknown";
}
