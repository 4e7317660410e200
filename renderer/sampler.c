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
#include "sampler.h"

#include "hash.h"

static uint32_t reverse_bits(uint32_t v)
{
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
    return (v >> 16) | (v << 16);
}

/* A bijection of 32-bit words in which output bit k depends only on input bits 0..k
 * (adding a constant carries upwards; x ^= x·even only adds higher-bit terms). Constants
 * from Burley 2020, §3. */
static uint32_t lk_permute(uint32_t x, uint32_t seed)
{
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

/* Nested-uniform scramble of a 0.32 fixed-point value (bit 31 is the first binary digit). */
static uint32_t nested_uniform_scramble(uint32_t x, uint32_t seed)
{
    return reverse_bits(lk_permute(reverse_bits(x), seed));
}

/* Second Sobol dimension: generator columns v_0 = 1<<31, v_k = v_{k-1} ^ (v_{k-1} >> 1)
 * (Pascal's triangle mod 2). The first dimension is van der Corput, reverse_bits(i). */
static uint32_t sobol_dim1(uint32_t i)
{
    uint32_t r = 0;
    for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
        if (i & 1u) r ^= v;
    return r;
}

/* Top 24 bits as a float in [0, 1): exact, so no rounding up to 1 or across strata. */
static inline float bits_to_unit(uint32_t bits) { return (float)(bits >> 8) * 0x1p-24f; }

static ts_vec2 sobol_value(uint32_t seed, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    uint32_t h = ts_hash4(seed, px, py, dim);
    uint32_t shuffled = nested_uniform_scramble(index, ts_hash_combine(h, 0x01u));
    uint32_t x = nested_uniform_scramble(reverse_bits(shuffled), ts_hash_combine(h, 0x02u));
    uint32_t y = nested_uniform_scramble(sobol_dim1(shuffled), ts_hash_combine(h, 0x03u));
    return (ts_vec2){bits_to_unit(x), bits_to_unit(y)};
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
    *out = (ts_sample_stream){s->type, s->seed, px, py, index, 0};
}

float ts_sample_1d(ts_sample_stream *st)
{
    return value_2d(st->type, st->seed, st->px, st->py, st->index, st->dim++).x;
}

ts_vec2 ts_sample_2d(ts_sample_stream *st)
{
    return value_2d(st->type, st->seed, st->px, st->py, st->index, st->dim++);
}

ts_vec2 ts_sampler_value_2d(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    return value_2d(s->type, s->seed, px, py, index, dim);
}

float ts_sampler_value_1d(const ts_sampler *s, uint32_t px, uint32_t py, uint32_t index, uint32_t dim)
{
    return value_2d(s->type, s->seed, px, py, index, dim).x;
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
