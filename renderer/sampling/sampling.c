/* sampling.c — warps and MIS weights (see sampling.h). Mathematics of pbrt-v3 §13.6 and
 * §13.10; the code guards every sqrt and division so u on the closed square [0,1]² and
 * degenerate parameters give finite results. */
#include "sampling/sampling.h"

ts_vec2 ts_sample_concentric_disk(ts_vec2 u)
{
    float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
    if (ox == 0 && oy == 0) return (ts_vec2){0, 0};
    float r, theta;
    if (fabsf(ox) > fabsf(oy)) {
        r = ox;
        theta = (TS_PI / 4.0f) * (oy / ox);
    } else {
        r = oy;
        theta = (TS_PI / 2.0f) - (TS_PI / 4.0f) * (ox / oy);
    }
    return (ts_vec2){r * cosf(theta), r * sinf(theta)};
}

ts_vec3 ts_sample_cosine_hemisphere(ts_vec2 u)
{
    ts_vec2 d = ts_sample_concentric_disk(u);
    float z = ts_safe_sqrtf(1.0f - d.x * d.x - d.y * d.y);
    return (ts_vec3){d.x, d.y, z};
}

ts_vec3 ts_sample_uniform_hemisphere(ts_vec2 u)
{
    float z = u.x;
    float r = ts_safe_sqrtf(1.0f - z * z);
    float phi = 2.0f * TS_PI * u.y;
    return (ts_vec3){r * cosf(phi), r * sinf(phi), z};
}

ts_vec3 ts_sample_uniform_sphere(ts_vec2 u)
{
    float z = 1.0f - 2.0f * u.x;
    float r = ts_safe_sqrtf(1.0f - z * z);
    float phi = 2.0f * TS_PI * u.y;
    return (ts_vec3){r * cosf(phi), r * sinf(phi), z};
}

ts_vec3 ts_sample_uniform_cone(ts_vec2 u, float cos_theta_max)
{
    /* cosθ = 1 − u(1 − cosθmax) rather than the lerp form: exact at u = 0 and keeps full
     * precision for narrow cones, where 1 − cosθmax is tiny. */
    float one_minus = 1.0f - cos_theta_max;
    float cos_theta = 1.0f - u.x * one_minus;
    /* sin²θ = (1 − cosθ)(1 + cosθ), computed from (1 − cosθ) directly to avoid the
     * cancellation of 1 − cos²θ for small cones. */
    float omc = u.x * one_minus;
    float sin_theta = ts_safe_sqrtf(omc * (2.0f - omc));
    float phi = 2.0f * TS_PI * u.y;
    return (ts_vec3){sin_theta * cosf(phi), sin_theta * sinf(phi), cos_theta};
}

float ts_uniform_cone_pdf(float cos_theta_max)
{
    float one_minus = 1.0f - cos_theta_max;
    if (!(one_minus > 0)) return INFINITY;
    return 1.0f / (2.0f * TS_PI * one_minus);
}

ts_vec2 ts_sample_uniform_triangle(ts_vec2 u)
{
    float su0 = sqrtf(ts_maxf(u.x, 0.0f));
    return (ts_vec2){1.0f - su0, u.y * su0};
}

float ts_power_heuristic(int nf, float f_pdf, int ng, float g_pdf)
{
    float f = (float)nf * f_pdf, g = (float)ng * g_pdf;
    if (!(f > 0)) return 0.0f; /* 0, negative or NaN: this strategy cannot produce the sample */
    if (isinf(f)) return isinf(g) ? 0.5f : 1.0f;
    if (!(g > 0)) return 1.0f;
    if (isinf(g)) return 0.0f;
    /* 1 / (1 + (g/f)²): no overflow of f² or g² for huge pdfs; (g/f)² → ∞ gives 0. */
    float r = g / f;
    return 1.0f / (1.0f + r * r);
}

float ts_balance_heuristic(int nf, float f_pdf, int ng, float g_pdf)
{
    float f = (float)nf * f_pdf, g = (float)ng * g_pdf;
    if (!(f > 0)) return 0.0f;
    if (isinf(f)) return isinf(g) ? 0.5f : 1.0f;
    if (!(g > 0)) return 1.0f;
    if (isinf(g)) return 0.0f;
    return 1.0f / (1.0f + g / f);
}
