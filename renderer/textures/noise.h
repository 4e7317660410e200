/* noise.h — pbrt-v3's Perlin noise, fractional Brownian motion and turbulence.
 *
 * Design note (pbrt-v3 §10.6). Noise(x, y, z) is gradient noise on the integer lattice:
 * each lattice point hashes to one of sixteen gradients through Ken Perlin's published
 * 256-entry permutation (his reference "improved noise", 2002), h = P[P[P[x] + y] + z]
 * (indices mod 256); the gradient is chosen from h's low four bits as pbrt-v3 chooses it
 * (the twelve cube-edge directions (±1, ±1, 0), (±1, 0, ±1), (0, ±1, ±1) and four repeats,
 * (1, 1, 0), (−1, 1, 0), (0, 1, −1), (0, −1, −1) — the repeats differ from Perlin's
 * reference, and pbrt-v3's are the ones its images were made with). The eight weights
 * g·(p − corner) are blended with the quintic 6t⁵ − 15t⁴ + 10t³, so noise is 0 at every
 * lattice point and C² everywhere. Arithmetic is float, in pbrt-v3's order.
 *
 * FBm and turbulence sum octaves λ = 1.99^i with weights ω^i; the number of octaves is
 * pbrt-v3's antialiasing rule n = clamp(−1 − ½·log₂ max(|∂p/∂x|², |∂p/∂y|²), 0, max),
 * the last, fractional octave faded in by smoothstep(0.3, 0.7, frac n); turbulence adds
 * 0.2·ω^i for each octave the footprint clamped away (their average |noise|). With no
 * footprint (∂p/∂x = ∂p/∂y = 0, no ray differentials) every octave is summed.
 *
 * Guards pbrt-v3 does not need: a non-finite coordinate gives 0 (not undefined integer
 * conversion), a NaN footprint counts as none. All functions are pure and thread-safe. */
#ifndef TS_NOISE_H
#define TS_NOISE_H

#include <stdint.h>

#include "core/vecmath.h"

/* The largest octave count fbm and turbulence accept (pbrt-v3 takes any; the texture
 * builders refuse more, keeping a lookup's cost bounded). */
#define TS_NOISE_MAX_OCTAVES 32

/* Perlin's permutation of 0 … 255 (read-only; for tests and documentation). */
const uint8_t *ts_noise_permutation(void);

/* pbrt-v3's Noise(x, y, z), in [−1, 1]; 0 at integer points and for non-finite input. */
float ts_noise(float x, float y, float z);

/* pbrt-v3's SmoothStep: 0 below a, 1 above b, 3v² − 2v³ of v = (x − a)/(b − a) between. */
float ts_noise_smoothstep(float a, float b, float x);

/* The octave count of pbrt-v3's antialiasing rule for a footprint (before flooring). */
float ts_noise_octaves(ts_vec3 dpdx, ts_vec3 dpdy, int max_octaves);

/* pbrt-v3's FBm(p, dpdx, dpdy, omega, maxOctaves): Σ ω^i Noise(1.99^i p). max_octaves in
 * 0 … TS_NOISE_MAX_OCTAVES (clamped to it). */
float ts_noise_fbm(ts_vec3 p, ts_vec3 dpdx, ts_vec3 dpdy, float omega, int max_octaves);

/* pbrt-v3's Turbulence: Σ ω^i |Noise(1.99^i p)| plus 0.2·ω^i for each clamped octave. */
float ts_noise_turbulence(ts_vec3 p, ts_vec3 dpdx, ts_vec3 dpdy, float omega, int max_octaves);

#endif
