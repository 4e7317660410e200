/* vecmath.h — small value types of the renderer: 2- and 3-vectors, RGB, bounds.
 *
 * Design note: everything here is a plain struct passed by value with static inline
 * operations, so the hot path has no calls and no aliasing. Geometry that needs more
 * than float precision (analytic shape intersection, transforms) uses ts_dvec3.
 * Names follow docs/style.md: ts_<type>_<verb>. All functions are pure and thread-safe. */
#ifndef TS_VECMATH_H
#define TS_VECMATH_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#define TS_PI 3.14159265358979323846f
#define TS_INV_PI 0.31830988618379067154f
#define TS_INV_2PI 0.15915494309189533577f
#define TS_INV_4PI 0.07957747154594766788f
#define TS_PI_D 3.14159265358979323846
/* Largest float below 1: what a sample value is clamped to (pbrt's OneMinusEpsilon). */
#define TS_ONE_MINUS_EPSILON 0x1.fffffep-1f
/* Unit roundoff of float and pbrt's gamma(n) = n·u / (1 − n·u) for error bounds. */
#define TS_MACHINE_EPSILON (FLT_EPSILON * 0.5f)
static inline float ts_gamma(int n) { return (n * TS_MACHINE_EPSILON) / (1 - n * TS_MACHINE_EPSILON); }

typedef struct ts_vec2 { float x, y; } ts_vec2;
typedef struct ts_vec3 { float x, y, z; } ts_vec3;
typedef struct ts_dvec3 { double x, y, z; } ts_dvec3;
typedef struct ts_rgb { float r, g, b; } ts_rgb;
typedef struct ts_bounds3 { ts_vec3 lo, hi; } ts_bounds3;

/* ---- scalar helpers ---- */
static inline float ts_clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }
static inline float ts_minf(float a, float b) { return a < b ? a : b; }
static inline float ts_maxf(float a, float b) { return a > b ? a : b; }
static inline float ts_lerpf(float t, float a, float b) { return (1 - t) * a + t * b; }
static inline float ts_radians(float deg) { return deg * (TS_PI / 180.0f); }
static inline float ts_safe_sqrtf(float v) { return sqrtf(v > 0 ? v : 0); }
static inline float ts_safe_acosf(float v) { return acosf(ts_clampf(v, -1, 1)); }
static inline float ts_safe_asinf(float v) { return asinf(ts_clampf(v, -1, 1)); }
static inline float ts_sqr(float v) { return v * v; }

/* Next representable float towards +inf / -inf (pbrt's NextFloatUp/Down). */
static inline float ts_next_float_up(float v)
{
    if (isinf(v) && v > 0) return v;
    if (v == -0.0f) v = 0.0f;
    union { float f; uint32_t u; } b = {v};
    b.u = v >= 0 ? b.u + 1 : b.u - 1;
    return b.f;
}
static inline float ts_next_float_down(float v)
{
    if (isinf(v) && v < 0) return v;
    if (v == 0.0f) v = -0.0f;
    union { float f; uint32_t u; } b = {v};
    b.u = v > 0 ? b.u - 1 : b.u + 1;
    return b.f;
}

/* ---- ts_vec2 ---- */
static inline ts_vec2 ts_vec2_make(float x, float y) { return (ts_vec2){x, y}; }

/* ---- ts_vec3 ---- */
static inline ts_vec3 ts_vec3_make(float x, float y, float z) { return (ts_vec3){x, y, z}; }
static inline ts_vec3 ts_vec3_add(ts_vec3 a, ts_vec3 b) { return (ts_vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline ts_vec3 ts_vec3_sub(ts_vec3 a, ts_vec3 b) { return (ts_vec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline ts_vec3 ts_vec3_mul(ts_vec3 a, ts_vec3 b) { return (ts_vec3){a.x * b.x, a.y * b.y, a.z * b.z}; }
static inline ts_vec3 ts_vec3_scale(ts_vec3 a, float s) { return (ts_vec3){a.x * s, a.y * s, a.z * s}; }
static inline ts_vec3 ts_vec3_neg(ts_vec3 a) { return (ts_vec3){-a.x, -a.y, -a.z}; }
static inline ts_vec3 ts_vec3_abs(ts_vec3 a) { return (ts_vec3){fabsf(a.x), fabsf(a.y), fabsf(a.z)}; }
static inline float ts_vec3_dot(ts_vec3 a, ts_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline float ts_vec3_absdot(ts_vec3 a, ts_vec3 b) { return fabsf(ts_vec3_dot(a, b)); }
static inline ts_vec3 ts_vec3_cross(ts_vec3 a, ts_vec3 b)
{
    /* Products in double so the cross of nearly parallel vectors does not cancel badly
     * (pbrt-v3 does the same). */
    double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
    return (ts_vec3){(float)(ay * bz - az * by), (float)(az * bx - ax * bz), (float)(ax * by - ay * bx)};
}
static inline float ts_vec3_length_sq(ts_vec3 a) { return ts_vec3_dot(a, a); }
static inline float ts_vec3_length(ts_vec3 a) { return sqrtf(ts_vec3_dot(a, a)); }
static inline ts_vec3 ts_vec3_normalize(ts_vec3 a)
{
    float len = ts_vec3_length(a);
    return len > 0 ? ts_vec3_scale(a, 1.0f / len) : a;
}
static inline float ts_vec3_distance(ts_vec3 a, ts_vec3 b) { return ts_vec3_length(ts_vec3_sub(a, b)); }
static inline float ts_vec3_distance_sq(ts_vec3 a, ts_vec3 b) { return ts_vec3_length_sq(ts_vec3_sub(a, b)); }
static inline float ts_vec3_max_component(ts_vec3 a) { return ts_maxf(a.x, ts_maxf(a.y, a.z)); }
static inline float ts_vec3_get(ts_vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
static inline ts_vec3 ts_vec3_min(ts_vec3 a, ts_vec3 b) { return (ts_vec3){fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)}; }
static inline ts_vec3 ts_vec3_max(ts_vec3 a, ts_vec3 b) { return (ts_vec3){fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)}; }
/* n flipped, if needed, to lie in the hemisphere of v (pbrt's Faceforward). */
static inline ts_vec3 ts_vec3_faceforward(ts_vec3 n, ts_vec3 v) { return ts_vec3_dot(n, v) < 0 ? ts_vec3_neg(n) : n; }
static inline bool ts_vec3_is_finite(ts_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

/* Orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited"). */
static inline void ts_coordinate_system(ts_vec3 n, ts_vec3 *s, ts_vec3 *t)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    *s = (ts_vec3){1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    *t = (ts_vec3){b, sign + n.y * n.y * a, -n.y};
}

/* ---- ts_dvec3 ---- */
static inline ts_dvec3 ts_dvec3_from(ts_vec3 a) { return (ts_dvec3){a.x, a.y, a.z}; }
static inline ts_vec3 ts_dvec3_to_vec3(ts_dvec3 a) { return (ts_vec3){(float)a.x, (float)a.y, (float)a.z}; }
static inline ts_dvec3 ts_dvec3_add(ts_dvec3 a, ts_dvec3 b) { return (ts_dvec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline ts_dvec3 ts_dvec3_sub(ts_dvec3 a, ts_dvec3 b) { return (ts_dvec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline ts_dvec3 ts_dvec3_scale(ts_dvec3 a, double s) { return (ts_dvec3){a.x * s, a.y * s, a.z * s}; }
static inline double ts_dvec3_dot(ts_dvec3 a, ts_dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline ts_dvec3 ts_dvec3_cross(ts_dvec3 a, ts_dvec3 b)
{
    return (ts_dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline double ts_dvec3_length(ts_dvec3 a) { return sqrt(ts_dvec3_dot(a, a)); }
static inline ts_dvec3 ts_dvec3_normalize(ts_dvec3 a)
{
    double len = ts_dvec3_length(a);
    return len > 0 ? ts_dvec3_scale(a, 1.0 / len) : a;
}

/* ---- ts_rgb ---- */
static inline ts_rgb ts_rgb_make(float r, float g, float b) { return (ts_rgb){r, g, b}; }
static inline ts_rgb ts_rgb_gray(float v) { return (ts_rgb){v, v, v}; }
static inline ts_rgb ts_rgb_add(ts_rgb a, ts_rgb b) { return (ts_rgb){a.r + b.r, a.g + b.g, a.b + b.b}; }
static inline ts_rgb ts_rgb_sub(ts_rgb a, ts_rgb b) { return (ts_rgb){a.r - b.r, a.g - b.g, a.b - b.b}; }
static inline ts_rgb ts_rgb_mul(ts_rgb a, ts_rgb b) { return (ts_rgb){a.r * b.r, a.g * b.g, a.b * b.b}; }
static inline ts_rgb ts_rgb_scale(ts_rgb a, float s) { return (ts_rgb){a.r * s, a.g * s, a.b * s}; }
static inline ts_rgb ts_rgb_div(ts_rgb a, ts_rgb b)
{
    return (ts_rgb){b.r != 0 ? a.r / b.r : 0, b.g != 0 ? a.g / b.g : 0, b.b != 0 ? a.b / b.b : 0};
}
static inline bool ts_rgb_is_black(ts_rgb a) { return a.r == 0 && a.g == 0 && a.b == 0; }
static inline float ts_rgb_max(ts_rgb a) { return ts_maxf(a.r, ts_maxf(a.g, a.b)); }
static inline float ts_rgb_average(ts_rgb a) { return (a.r + a.g + a.b) * (1.0f / 3.0f); }
/* Rec. 709 luminance of linear RGB. */
static inline float ts_rgb_luminance(ts_rgb a) { return 0.2126f * a.r + 0.7152f * a.g + 0.0722f * a.b; }
static inline bool ts_rgb_is_finite(ts_rgb a) { return isfinite(a.r) && isfinite(a.g) && isfinite(a.b); }

/* ---- ts_bounds3 ---- */
static inline ts_bounds3 ts_bounds3_empty(void)
{
    return (ts_bounds3){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
}
static inline ts_bounds3 ts_bounds3_extend(ts_bounds3 b, ts_vec3 p)
{
    return (ts_bounds3){ts_vec3_min(b.lo, p), ts_vec3_max(b.hi, p)};
}
static inline ts_bounds3 ts_bounds3_union(ts_bounds3 a, ts_bounds3 b)
{
    return (ts_bounds3){ts_vec3_min(a.lo, b.lo), ts_vec3_max(a.hi, b.hi)};
}
static inline bool ts_bounds3_is_empty(ts_bounds3 b) { return b.lo.x > b.hi.x || b.lo.y > b.hi.y || b.lo.z > b.hi.z; }

#endif
