/* fresnel.c — see fresnel.h. Formulas of pbrt-v3 §8.2.1 (dielectric) and the conductor
 * expression of §8.2 (after Lagarde), with guards so degenerate input stays in [0, 1]. */
#include "materials/fresnel.h"

float ts_fresnel_dielectric(float cos_theta_i, float eta_i, float eta_t)
{
    cos_theta_i = ts_clampf(cos_theta_i, -1, 1);
    if (cos_theta_i < 0) { /* arriving from the eta_t side */
        float t = eta_i;
        eta_i = eta_t;
        eta_t = t;
        cos_theta_i = -cos_theta_i;
    }
    if (!(eta_i > 0) || !(eta_t > 0) || eta_i == eta_t) return 0.0f;
    float sin_theta_i = ts_safe_sqrtf(1 - cos_theta_i * cos_theta_i);
    float sin_theta_t = eta_i / eta_t * sin_theta_i;
    if (sin_theta_t >= 1) return 1.0f; /* total internal reflection */
    float cos_theta_t = ts_safe_sqrtf(1 - sin_theta_t * sin_theta_t);
    float para_num = eta_t * cos_theta_i - eta_i * cos_theta_t, para_den = eta_t * cos_theta_i + eta_i * cos_theta_t;
    float perp_num = eta_i * cos_theta_i - eta_t * cos_theta_t, perp_den = eta_i * cos_theta_i + eta_t * cos_theta_t;
    if (!(para_den > 0) || !(perp_den > 0)) return 1.0f; /* exactly grazing: both cosines 0 */
    float r_para = para_num / para_den, r_perp = perp_num / perp_den;
    return ts_clampf(0.5f * (r_para * r_para + r_perp * r_perp), 0, 1);
}

static float conductor1(float cos_theta_i, float eta_i, float eta_t, float k_t)
{
    float c = ts_clampf(fabsf(cos_theta_i), 0, 1);
    if (!(eta_i > 0)) eta_i = 1;
    float eta = eta_t / eta_i, etak = k_t / eta_i;
    float cos2 = c * c, sin2 = 1 - cos2, eta2 = eta * eta, etak2 = etak * etak;
    float t0 = eta2 - etak2 - sin2;
    float a2plusb2 = sqrtf(t0 * t0 + 4 * eta2 * etak2);
    float t1 = a2plusb2 + cos2;
    float a = ts_safe_sqrtf(0.5f * (a2plusb2 + t0));
    float t2 = 2 * c * a;
    if (!(t1 + t2 > 0)) return 1.0f; /* grazing on a matched index: the limit is 1 */
    float rs = (t1 - t2) / (t1 + t2);
    float t3 = cos2 * a2plusb2 + sin2 * sin2, t4 = t2 * sin2;
    float rp = t3 + t4 > 0 ? rs * (t3 - t4) / (t3 + t4) : rs;
    float r = 0.5f * (rp + rs);
    return isfinite(r) ? ts_clampf(r, 0, 1) : 1.0f;
}

ts_rgb ts_fresnel_conductor(float cos_theta_i, float eta_i, ts_rgb eta, ts_rgb k)
{
    return (ts_rgb){conductor1(cos_theta_i, eta_i, eta.r, k.r), conductor1(cos_theta_i, eta_i, eta.g, k.g),
                    conductor1(cos_theta_i, eta_i, eta.b, k.b)};
}

ts_rgb ts_fresnel_eval(const ts_fresnel *f, float cos_theta_i)
{
    switch (f->type) {
    case TS_FRESNEL_ONE: return ts_rgb_gray(1);
    case TS_FRESNEL_DIELECTRIC: return ts_rgb_gray(ts_fresnel_dielectric(cos_theta_i, f->eta_i, f->eta_t));
    case TS_FRESNEL_DIELECTRIC_TWO_SIDED:
        return ts_rgb_gray(ts_fresnel_dielectric(fabsf(cos_theta_i), f->eta_i, f->eta_t));
    case TS_FRESNEL_CONDUCTOR: return ts_fresnel_conductor(cos_theta_i, f->eta_i, f->eta, f->k);
    case TS_FRESNEL_SCHLICK: {
        float m = 1 - ts_clampf(fabsf(cos_theta_i), 0, 1), m5 = (m * m) * (m * m) * m;
        return ts_rgb_add(f->r0, ts_rgb_scale(ts_rgb_sub(ts_rgb_gray(1), f->r0), m5));
    }
    }
    return ts_rgb_gray(0);
}
