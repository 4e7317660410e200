/* noise.c — pbrt-v3's Perlin noise, fBm and turbulence (see noise.h). */
#include "textures/noise.h"

#include <math.h>

/* Ken Perlin's permutation of 0 … 255, as published with his reference implementation of
 * improved noise (2002); pbrt-v3 uses the same table. */
static const uint8_t perm[256] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,
    69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,  197, 62,
    94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174, 20,  125, 136,
    171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166, 77,  146, 158, 231, 83,  111, 229, 122,
    60,  211, 133, 230, 220, 105, 92,  41,  55,  46,  245, 40,  244, 102, 143, 54,  65,  25,  63,  161,
    1,   216, 80,  73,  209, 76,  132, 187, 208, 89,  18,  169, 200, 196, 135, 130, 116, 188, 159, 86,
    164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250, 124, 123, 5,   202, 38,  147, 118, 126,
    255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189, 28,  42,  223, 183, 170, 213,
    119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,   129, 22,  39,  253,
    19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,  242, 193,
    238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,
    181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,
    222, 114, 67,  29,  24,  72,  243, 141, 128, 195, 78,  66,  215, 61,  156, 180,
};

const uint8_t *ts_noise_permutation(void) { return perm; }

/* pbrt-v3's gradients by the low four bits h of the hash: u = dx if h < 8 or h is 12 or
 * 13, else dy; v = dy if h < 4 or h is 12 or 13, else dz; the weight is (h&1 ? −u : u) +
 * (h&2 ? −v : v). As a table of gradient vectors, so the lookup has no branches (the
 * branchy form mispredicts on most calls); g·d with one zero term gives pbrt-v3's sum
 * exactly (x + 0 = x), but for the sign of a zero result. */
static const float grad_table[16][3] = {
    {1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0}, /* h 0-3: ±dx ± dy */
    {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1}, /* h 4-7: ±dx ± dz */
    {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}, /* h 8-11: ±dy ± dz */
    {1, 1, 0}, {-1, 1, 0}, {0, 1, -1}, {0, -1, -1}, /* h 12, 13: ±dx + dy; 14, 15: ±dy − dz */
};

/* The weight of the lattice corner (x, y, z) (indices already reduced mod 256, each at
 * most 256) for the offset (dx, dy, dz) from it. */
static inline float grad(int x, int y, int z, float dx, float dy, float dz)
{
    int h = perm[(perm[(perm[x & 255] + y) & 255] + z) & 255] & 15;
    return grad_table[h][0] * dx + grad_table[h][1] * dy + grad_table[h][2] * dz;
}

static inline float noise_weight(float t)
{
    float t3 = t * t * t;
    float t4 = t3 * t;
    return 6 * t4 * t - 15 * t4 + 10 * t3;
}

/* floor(v) mod 256 without an out-of-range conversion: floats of magnitude 2^62 or more
 * are multiples of 256. */
static inline int cell(float f) { return fabsf(f) < 0x1p62f ? (int)((int64_t)f & 255) : 0; }

float ts_noise(float x, float y, float z)
{
    if (!(isfinite(x) && isfinite(y) && isfinite(z))) return 0;
    float fx = floorf(x), fy = floorf(y), fz = floorf(z);
    float dx = x - fx, dy = y - fy, dz = z - fz;
    int ix = cell(fx), iy = cell(fy), iz = cell(fz);

    float w000 = grad(ix, iy, iz, dx, dy, dz);
    float w100 = grad(ix + 1, iy, iz, dx - 1, dy, dz);
    float w010 = grad(ix, iy + 1, iz, dx, dy - 1, dz);
    float w110 = grad(ix + 1, iy + 1, iz, dx - 1, dy - 1, dz);
    float w001 = grad(ix, iy, iz + 1, dx, dy, dz - 1);
    float w101 = grad(ix + 1, iy, iz + 1, dx - 1, dy, dz - 1);
    float w011 = grad(ix, iy + 1, iz + 1, dx, dy - 1, dz - 1);
    float w111 = grad(ix + 1, iy + 1, iz + 1, dx - 1, dy - 1, dz - 1);

    float wx = noise_weight(dx), wy = noise_weight(dy), wz = noise_weight(dz);
    float x00 = ts_lerpf(wx, w000, w100);
    float x10 = ts_lerpf(wx, w010, w110);
    float x01 = ts_lerpf(wx, w001, w101);
    float x11 = ts_lerpf(wx, w011, w111);
    float y0 = ts_lerpf(wy, x00, x10);
    float y1 = ts_lerpf(wy, x01, x11);
    return ts_lerpf(wz, y0, y1);
}

float ts_noise_smoothstep(float a, float b, float x)
{
    if (a == b) return x < a ? 0.0f : 1.0f;
    float v = ts_clampf((x - a) / (b - a), 0, 1);
    return v * v * (-2 * v + 3);
}

float ts_noise_octaves(ts_vec3 dpdx, ts_vec3 dpdy, int max_octaves)
{
    if (max_octaves < 0) max_octaves = 0;
    if (max_octaves > TS_NOISE_MAX_OCTAVES) max_octaves = TS_NOISE_MAX_OCTAVES;
    float len2 = ts_maxf(ts_vec3_length_sq(dpdx), ts_vec3_length_sq(dpdy));
    /* pbrt-v3's Log2: log(x)·(1/ln 2). len2 = 0 gives +∞ octaves, clamped to the most. */
    float n = -1 - 0.5f * (logf(len2) * 1.442695040888963387004650940071f);
    if (isnan(n)) n = (float)max_octaves; /* a NaN footprint: as if there were none */
    return ts_clampf(n, 0, (float)max_octaves);
}

static inline float noise3(ts_vec3 p, float lambda)
{
    return ts_noise(lambda * p.x, lambda * p.y, lambda * p.z);
}

float ts_noise_fbm(ts_vec3 p, ts_vec3 dpdx, ts_vec3 dpdy, float omega, int max_octaves)
{
    float n = ts_noise_octaves(dpdx, dpdy, max_octaves);
    int n_int = (int)floorf(n);
    float sum = 0, lambda = 1, o = 1;
    for (int i = 0; i < n_int; ++i) {
        sum += o * noise3(p, lambda);
        lambda *= 1.99f;
        o *= omega;
    }
    float n_partial = n - (float)n_int;
    sum += o * ts_noise_smoothstep(0.3f, 0.7f, n_partial) * noise3(p, lambda);
    return sum;
}

float ts_noise_turbulence(ts_vec3 p, ts_vec3 dpdx, ts_vec3 dpdy, float omega, int max_octaves)
{
    if (max_octaves > TS_NOISE_MAX_OCTAVES) max_octaves = TS_NOISE_MAX_OCTAVES;
    float n = ts_noise_octaves(dpdx, dpdy, max_octaves);
    int n_int = (int)floorf(n);
    float sum = 0, lambda = 1, o = 1;
    for (int i = 0; i < n_int; ++i) {
        sum += o * fabsf(noise3(p, lambda));
        lambda *= 1.99f;
        o *= omega;
    }
    /* The fractional octave fades from the average |noise| (0.2) to its value; each octave
     * beyond counts as its average (pbrt-v3 keeps o unchanged before this loop). */
    float n_partial = n - (float)n_int;
    sum += o * ts_lerpf(ts_noise_smoothstep(0.3f, 0.7f, n_partial), 0.2f, fabsf(noise3(p, lambda)));
    for (int i = n_int; i < max_octaves; ++i) {
        sum += o * 0.2f;
        o *= omega;
    }
    return sum;
}
