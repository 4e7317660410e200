/* sampling.h — warps from the unit square to disks, hemispheres, spheres, cones and
 * triangles, with their densities, and the multiple-importance weights.
 *
 * Design note: every warp takes its random numbers as a parameter u ∈ [0,1)² (docs/style.md:
 * random numbers are parameters, never drawn inside) and is paired with its pdf, so a
 * caller (or tests/chi2.h) can check one against the other. Directions are in a local
 * frame whose +z is the pole (the normal, or the cone axis). Densities are per unit solid
 * angle for directions and per unit area for the disk; a sample outside the support has
 * pdf 0. All functions are pure, allocation-free and thread-safe (pbrt-v3 §13.6). */
#ifndef TS_SAMPLING_H
#define TS_SAMPLING_H

#include "core/vecmath.h"

/* Point on the unit disk, area-preserving concentric map (Shirley–Chiu); pdf 1/π. */
ts_vec2 ts_sample_concentric_disk(ts_vec2 u);

/* Cosine-weighted direction on the +z hemisphere (Malley's method); pdf cosθ/π. */
ts_vec3 ts_sample_cosine_hemisphere(ts_vec2 u);
/* cosθ/π for cos_theta > 0, else 0. */
static inline float ts_cosine_hemisphere_pdf(float cos_theta) { return cos_theta > 0 ? cos_theta * TS_INV_PI : 0; }

/* Uniform direction on the +z hemisphere; pdf 1/(2π) for z ≥ 0. */
ts_vec3 ts_sample_uniform_hemisphere(ts_vec2 u);
static inline float ts_uniform_hemisphere_pdf(void) { return TS_INV_2PI; }

/* Uniform direction on the unit sphere; pdf 1/(4π). */
ts_vec3 ts_sample_uniform_sphere(ts_vec2 u);
static inline float ts_uniform_sphere_pdf(void) { return TS_INV_4PI; }

/* Uniform direction in the cone around +z of half-angle acos(cos_theta_max);
 * pdf 1/(2π(1 − cos_theta_max)) inside the cone. cos_theta_max = 1 (a degenerate cone)
 * returns +z; its pdf is then a delta and ts_uniform_cone_pdf returns +∞ — callers that
 * can meet a zero-angle cone treat it as a delta distribution. */
ts_vec3 ts_sample_uniform_cone(ts_vec2 u, float cos_theta_max);
float ts_uniform_cone_pdf(float cos_theta_max);

/* Barycentrics (b0, b1) of a uniform point in a triangle (b2 = 1 − b0 − b1); the area
 * density is 1/area. Uses the square-root warp of pbrt-v3 §13.6.5. */
ts_vec2 ts_sample_uniform_triangle(ts_vec2 u);

/* Power heuristic (β = 2) weight of strategy f (nf samples, pdf f_pdf) against g:
 * (nf·f_pdf)² / ((nf·f_pdf)² + (ng·g_pdf)²). Never NaN: a pdf of +∞ (a delta strategy)
 * gets weight 1 against a finite one, 0 when f_pdf = 0, and when both are 0 the weight
 * is 0; very large finite pdfs are handled without overflow. */
float ts_power_heuristic(int nf, float f_pdf, int ng, float g_pdf);

/* Balance heuristic nf·f_pdf / (nf·f_pdf + ng·g_pdf), with the same guarantees. */
float ts_balance_heuristic(int nf, float f_pdf, int ng, float g_pdf);

/* ---- spherical coordinates in the local frame (pbrt-v3 §5.5) ---- */
static inline float ts_cos_theta(ts_vec3 w) { return w.z; }
static inline float ts_cos2_theta(ts_vec3 w) { return w.z * w.z; }
static inline float ts_abs_cos_theta(ts_vec3 w) { return fabsf(w.z); }
static inline float ts_sin2_theta(ts_vec3 w) { return ts_maxf(0.0f, 1.0f - w.z * w.z); }
static inline float ts_sin_theta(ts_vec3 w) { return sqrtf(ts_sin2_theta(w)); }
static inline float ts_tan_theta(ts_vec3 w) { return ts_sin_theta(w) / w.z; }
static inline float ts_tan2_theta(ts_vec3 w) { return ts_sin2_theta(w) / (w.z * w.z); }
static inline float ts_cos_phi(ts_vec3 w)
{
    float s = ts_sin_theta(w);
    return s == 0 ? 1.0f : ts_clampf(w.x / s, -1, 1);
}
static inline float ts_sin_phi(ts_vec3 w)
{
    float s = ts_sin_theta(w);
    return s == 0 ? 0.0f : ts_clampf(w.y / s, -1, 1);
}
static inline bool ts_same_hemisphere(ts_vec3 a, ts_vec3 b) { return a.z * b.z > 0; }
static inline ts_vec3 ts_spherical_direction(float sin_theta, float cos_theta, float phi)
{
    return (ts_vec3){ts_clampf(sin_theta, -1, 1) * cosf(phi), ts_clampf(sin_theta, -1, 1) * sinf(phi),
                     ts_clampf(cos_theta, -1, 1)};
}

#endif
