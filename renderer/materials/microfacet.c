/* microfacet.c — see microfacet.h. */
#include "materials/microfacet.h"

#include "sampling/sampling.h"

ts_microfacet ts_microfacet_make(ts_microfacet_type type, float alpha_x, float alpha_y)
{
    ts_microfacet m = {type, alpha_x, alpha_y};
    if (!(m.alpha_x >= TS_MICROFACET_MIN_ALPHA)) m.alpha_x = TS_MICROFACET_MIN_ALPHA;
    if (!(m.alpha_y >= TS_MICROFACET_MIN_ALPHA)) m.alpha_y = TS_MICROFACET_MIN_ALPHA;
    if (m.alpha_x > 1e4f) m.alpha_x = 1e4f;
    if (m.alpha_y > 1e4f) m.alpha_y = 1e4f;
    return m;
}

float ts_microfacet_roughness_to_alpha(float roughness)
{
    if (!(roughness >= 1e-3f)) roughness = 1e-3f; /* max(roughness, 1e-3), NaN included */
    if (roughness > 1e30f) roughness = 1e30f;      /* ln stays finite */
    float x = logf(roughness);
    return 1.62142f + 0.819955f * x + 0.1734f * x * x + 0.0171201f * x * x * x + 0.000640711f * x * x * x * x;
}

/* sin²θ from x, y (accurate near the pole) and the azimuthal terms. */
static inline float sin2_xy(ts_vec3 w) { return w.x * w.x + w.y * w.y; }

/* tan²θ · (cos²φ/αx² + sin²φ/αy²) = (x²/αx² + y²/αy²) / z². */
static inline float stretched_tan2(const ts_microfacet *m, ts_vec3 w)
{
    float ex = w.x / m->alpha_x, ey = w.y / m->alpha_y;
    return (ex * ex + ey * ey) / (w.z * w.z);
}

float ts_microfacet_d(const ts_microfacet *m, ts_vec3 wh)
{
    float z2 = wh.z * wh.z;
    if (z2 == 0) return 0;
    float e = stretched_tan2(m, wh);
    if (!isfinite(e)) return 0;
    float cos4 = z2 * z2;
    float d;
    if (m->type == TS_MICROFACET_BECKMANN) {
        d = expf(-e) / (TS_PI * m->alpha_x * m->alpha_y * cos4);
    } else {
        float t = 1 + e;
        d = 1 / (TS_PI * m->alpha_x * m->alpha_y * cos4 * t * t);
    }
    return isfinite(d) ? d : 0;
}

float ts_microfacet_lambda(const ts_microfacet *m, ts_vec3 w)
{
    float s2 = sin2_xy(w);
    if (s2 == 0) return 0;
    if (w.z == 0) return INFINITY;
    /* α² tan²θ along w's azimuth: (αx² x² + αy² y²) / z². */
    double ax = (double)m->alpha_x * w.x, ay = (double)m->alpha_y * w.y;
    double a2tan2 = (ax * ax + ay * ay) / ((double)w.z * w.z);
    if (m->type == TS_MICROFACET_BECKMANN) {
        double a = 1 / sqrt(a2tan2);
        if (a > 26) return 0; /* both terms below double precision */
        return (float)(0.5 * (exp(-a * a) / (a * 1.7724538509055160273) - erfc(a)));
    }
    /* (√(1 + x) − 1) / 2 written without cancellation. */
    return (float)(a2tan2 / (2 * (1 + sqrt(1 + a2tan2))));
}

float ts_microfacet_g1(const ts_microfacet *m, ts_vec3 w) { return 1 / (1 + ts_microfacet_lambda(m, w)); }

float ts_microfacet_g(const ts_microfacet *m, ts_vec3 wo, ts_vec3 wi)
{
    return 1 / (1 + ts_microfacet_lambda(m, wo) + ts_microfacet_lambda(m, wi));
}

/* ---- visible-normal sampling ---- */

/* GGX: Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (wo.z > 0). */
static ts_vec3 sample_ggx(const ts_microfacet *m, ts_vec3 wo, ts_vec2 u)
{
    ts_vec3 vh = ts_vec3_normalize((ts_vec3){m->alpha_x * wo.x, m->alpha_y * wo.y, wo.z});
    float lensq = vh.x * vh.x + vh.y * vh.y;
    ts_vec3 t1 = lensq > 0 ? ts_vec3_scale((ts_vec3){-vh.y, vh.x, 0}, 1 / sqrtf(lensq)) : (ts_vec3){1, 0, 0};
    ts_vec3 t2 = ts_vec3_cross(vh, t1);
    float r = sqrtf(u.x), phi = 2 * TS_PI * u.y;
    float p1 = r * cosf(phi), p2 = r * sinf(phi);
    float s = 0.5f * (1 + vh.z);
    p2 = (1 - s) * ts_safe_sqrtf(1 - p1 * p1) + s * p2;
    ts_vec3 nh = ts_vec3_add(ts_vec3_add(ts_vec3_scale(t1, p1), ts_vec3_scale(t2, p2)),
                             ts_vec3_scale(vh, ts_safe_sqrtf(1 - p1 * p1 - p2 * p2)));
    ts_vec3 ne = {m->alpha_x * nh.x, m->alpha_y * nh.y, ts_maxf(0, nh.z)};
    float len = ts_vec3_length(ne);
    return len > 0 ? ts_vec3_scale(ne, 1 / len) : (ts_vec3){0, 0, 1};
}

/* Inverse error function in double: a rational first guess (Giles 2010) polished by
 * Newton steps on erf / erfc. */
static double erfinv_d(double y)
{
    if (y <= -1) y = -1 + 1e-16;
    if (y >= 1) y = 1 - 1e-16;
    double w = -log((1 - y) * (1 + y)), x;
    if (w < 5) {
        w -= 2.5;
        double p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
        x = p * y;
    } else {
        w = sqrt(w) - 3;
        double p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
        x = p * y;
    }
    for (int i = 0; i < 3; i++) {
        double d = 1.1283791670955125739 * exp(-x * x); /* erf'(x) */
        if (!(d > 0)) break;
        double err = fabs(y) < 0.5 ? erf(x) - y : (y > 0 ? (1 - y) - erfc(x) : erfc(-x) - (1 + y));
        x -= err / d;
    }
    return x;
}

/* Beckmann visible slopes for unit roughness, view at cosθ in the xz plane (Heitz &
 * d'Eon 2014): x̃ by Newton–bisection on its exact CDF expressed in b = erf(x̃), ỹ
 * Gaussian. */
static void beckmann_slopes(double cos_theta, double u1, double u2, double *sx, double *sy)
{
    double sin_theta = sqrt(fmax(0.0, 1 - cos_theta * cos_theta));
    double tan_theta = sin_theta / cos_theta;
    const double inv_sqrt_pi = 0.56418958354775628695;
    if (!(tan_theta > 1e-8)) {
        *sx = erfinv_d(2 * u1 - 1);
    } else {
        double cot = 1 / tan_theta;
        double c = erf(cot);
        double norm = 1 / (1 + c + inv_sqrt_pi * tan_theta * exp(-cot * cot));
        double lo = -1, hi = c;
        double theta = acos(cos_theta);
        double fit = 1 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
        double b = c - (1 + c) * pow(1 - u1, fit);
        for (int it = 0; it < 100; it++) {
            if (!(b >= lo && b <= hi)) b = 0.5 * (lo + hi);
            double x = erfinv_d(b);
            double value = norm * (1 + b + inv_sqrt_pi * tan_theta * exp(-x * x)) - u1;
            if (fabs(value) < 1e-13 || hi - lo < 1e-15) break;
            if (value > 0) hi = b;
            else lo = b;
            double deriv = norm * (1 - x * tan_theta);
            b = deriv > 0 ? b - value / deriv : 0.5 * (lo + hi);
        }
        *sx = erfinv_d(b);
    }
    *sy = erfinv_d(2 * u2 - 1);
}

static ts_vec3 sample_beckmann(const ts_microfacet *m, ts_vec3 wo, ts_vec2 u)
{
    /* Stretch to unit roughness, sample slopes, rotate to wo's azimuth, unstretch. */
    double wx = (double)m->alpha_x * wo.x, wy = (double)m->alpha_y * wo.y, wz = wo.z;
    double len = sqrt(wx * wx + wy * wy + wz * wz);
    wx /= len;
    wy /= len;
    wz /= len;
    double s = sqrt(wx * wx + wy * wy);
    double cphi = s > 0 ? wx / s : 1, sphi = s > 0 ? wy / s : 0;
    /* A float u of 0 stands for [0, 2^-24): map the ends of the square to the middle of
     * their float intervals, so u = 0 does not become an infinitely steep facet whose
     * density no evaluation can represent. */
    double u1 = fmin(fmax((double)u.x, 0x1p-25), 1 - 0x1p-25), u2 = fmin(fmax((double)u.y, 0x1p-25), 1 - 0x1p-25);
    double sx, sy;
    beckmann_slopes(wz, u1, u2, &sx, &sy);
    double rx = cphi * sx - sphi * sy, ry = sphi * sx + cphi * sy;
    rx *= m->alpha_x;
    ry *= m->alpha_y;
    double n = sqrt(rx * rx + ry * ry + 1);
    ts_vec3 wh = {(float)(-rx / n), (float)(-ry / n), (float)(1 / n)};
    return ts_vec3_is_finite(wh) ? wh : (ts_vec3){0, 0, 1};
}

ts_vec3 ts_microfacet_sample_wh(const ts_microfacet *m, ts_vec3 wo, ts_vec2 u)
{
    if (wo.z == 0) return (ts_vec3){0, 0, 1};
    bool flip = wo.z < 0;
    if (flip) wo = ts_vec3_neg(wo);
    ts_vec3 wh = m->type == TS_MICROFACET_BECKMANN ? sample_beckmann(m, wo, u) : sample_ggx(m, wo, u);
    return flip ? ts_vec3_neg(wh) : wh;
}

float ts_microfacet_pdf(const ts_microfacet *m, ts_vec3 wo, ts_vec3 wh)
{
    if (wo.z == 0) return 0;
    float p = ts_microfacet_d(m, wh) * ts_microfacet_g1(m, wo) * fabsf(ts_vec3_dot(wo, wh)) / fabsf(wo.z);
    return isfinite(p) ? p : 0;
}
