/* hash.h — integer hashing and a small PCG32 generator.
 *
 * Design note: sample values must depend only on (seed, pixel, sample index, dimension)
 * (docs/design.md §6), so randomness is derived by hashing those numbers, never from a
 * generator whose state travels with a thread. PCG32 (O'Neill 2014) is used where a
 * stream is natural (tests, table building). Everything here is pure and thread-safe. */
#ifndef TS_HASH_H
#define TS_HASH_H

#include <stdint.h>

/* A 32-bit finaliser with good avalanche (the "lowbias32" constants of Wellons' hash
 * prospector). */
static inline uint32_t ts_hash_u32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* Hash of several 32-bit words: each is mixed in and the state re-finalised. */
static inline uint32_t ts_hash_combine(uint32_t h, uint32_t v) { return ts_hash_u32(h ^ (v + 0x9e3779b9u + (h << 6) + (h >> 2))); }
static inline uint32_t ts_hash4(uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    return ts_hash_combine(ts_hash_combine(ts_hash_combine(ts_hash_u32(a), b), c), d);
}

typedef struct ts_pcg32 { uint64_t state, inc; } ts_pcg32;

static inline uint32_t ts_pcg32_next(ts_pcg32 *r)
{
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ull + r->inc;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
}

static inline void ts_pcg32_seed(ts_pcg32 *r, uint64_t seed, uint64_t stream)
{
    r->state = 0u;
    r->inc = (stream << 1u) | 1u;
    ts_pcg32_next(r);
    r->state += seed;
    ts_pcg32_next(r);
}

/* Uniform float in [0, 1): 24 random bits, so 1 is never returned. */
static inline float ts_pcg32_float(ts_pcg32 *r) { return (float)(ts_pcg32_next(r) >> 8) * 0x1p-24f; }
static inline double ts_pcg32_double(ts_pcg32 *r)
{
    uint64_t hi = ts_pcg32_next(r), lo = ts_pcg32_next(r);
    return (double)(((hi << 32) | lo) >> 11) * 0x1p-53;
}

#endif
