/* fresnel.h — Fresnel reflectance of dielectric and conductor interfaces (pbrt-v3 §8.2).
 *
 * Design note: a ts_fresnel is a tagged value (docs/style.md: dispatch by switch, no function
 * pointers) evaluated at the cosine of the angle between the incident direction and the
 * (micro)surface normal. Results are always in [0, 1] and finite, for any cosine in
 * [−1, 1] (clamped) and any positive indices. Pure and thread-safe. */
#ifndef TS_FRESNEL_H
#define TS_FRESNEL_H

#include "core/vecmath.h"

typedef enum ts_fresnel_type {
    TS_FRESNEL_ONE,        /* F = 1 (perfect mirror) */
    TS_FRESNEL_DIELECTRIC, /* eta_i: index on the normal's side, eta_t: the other side */
    TS_FRESNEL_DIELECTRIC_TWO_SIDED, /* a coat seen from outside on either side: eta_i → eta_t at |cosθ| */
    TS_FRESNEL_CONDUCTOR,  /* complex index eta + i·k of the conductor, per channel, from eta_i */
    TS_FRESNEL_SCHLICK,    /* Schlick's approximation with normal-incidence reflectance r0 */
} ts_fresnel_type;

typedef struct ts_fresnel {
    ts_fresnel_type type;
    float eta_i, eta_t; /* dielectric; conductor: eta_i is the outside medium */
    ts_rgb eta, k;      /* conductor */
    ts_rgb r0;          /* Schlick */
} ts_fresnel;

/* Unpolarised dielectric reflectance for light arriving at cos_theta_i from the eta_i
 * side (cos_theta_i < 0: from the eta_t side; the indices swap). 1 under total internal
 * reflection; 0 when eta_i = eta_t. */
float ts_fresnel_dielectric(float cos_theta_i, float eta_i, float eta_t);

/* Reflectance of a conductor with complex index (eta + i k) relative to a dielectric
 * eta_i, at |cos_theta_i|, per channel. */
ts_rgb ts_fresnel_conductor(float cos_theta_i, float eta_i, ts_rgb eta, ts_rgb k);

/* Evaluates f at cos_theta_i. */
ts_rgb ts_fresnel_eval(const ts_fresnel *f, float cos_theta_i);

static inline ts_fresnel ts_fresnel_one(void) { return (ts_fresnel){.type = TS_FRESNEL_ONE}; }
static inline ts_fresnel ts_fresnel_make_dielectric(float eta_i, float eta_t)
{
    return (ts_fresnel){.type = TS_FRESNEL_DIELECTRIC, .eta_i = eta_i, .eta_t = eta_t};
}
/* The Fresnel term of a dielectric coat that has its outside (eta_i) on both faces, as
 * plastic's: light arriving on either side goes from eta_i into eta_t, so there is no
 * total internal reflection whatever the sign of the cosine (pbrt-v3's FresnelDielectric
 * would swap the indices for a cosine below the normal's side). */
static inline ts_fresnel ts_fresnel_make_dielectric_two_sided(float eta_i, float eta_t)
{
    return (ts_fresnel){.type = TS_FRESNEL_DIELECTRIC_TWO_SIDED, .eta_i = eta_i, .eta_t = eta_t};
}
static inline ts_fresnel ts_fresnel_make_conductor(float eta_i, ts_rgb eta, ts_rgb k)
{
    return (ts_fresnel){.type = TS_FRESNEL_CONDUCTOR, .eta_i = eta_i, .eta = eta, .k = k};
}
static inline ts_fresnel ts_fresnel_make_schlick(ts_rgb r0) { return (ts_fresnel){.type = TS_FRESNEL_SCHLICK, .r0 = r0}; }

#endif
