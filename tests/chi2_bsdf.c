/* chi2_bsdf.c — χ² adapters for BxDFs and BSDFs; see chi2_bsdf.h. */
#include "chi2_bsdf.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

/* A non-specular sample's f and pdf against evaluation at its direction. */
static void check_contract(ts_rgb f_sample, float pdf_sample, ts_rgb f, float pdf)
{
    if (fabsf(pdf - pdf_sample) > 1e-4f * pdf || fabsf(f.r - f_sample.r) > 1e-4f * f.r + 1e-7f ||
        fabsf(f.g - f_sample.g) > 1e-4f * f.g + 1e-7f || fabsf(f.b - f_sample.b) > 1e-4f * f.b + 1e-7f)
        fail_msg("sample/eval mismatch: pdf %g vs %g, f (%g %g %g) vs (%g %g %g)", pdf_sample, pdf, f_sample.r,
                 f_sample.g, f_sample.b, f.r, f.g, f.b);
}

ts_chi2_outcome ts_chi2_bxdf_sample(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    const ts_chi2_bxdf *c = ctx;
    ts_vec2 u;
    u.x = ts_pcg32_float(rng);
    u.y = ts_pcg32_float(rng);
    ts_bxdf_sample s;
    if (!ts_bxdf_sample_f(&c->b, c->wo, u, &s)) return TS_CHI2_NONE;
    if (s.flags & TS_BXDF_SPECULAR) return TS_CHI2_DISCRETE;
    check_contract(s.f, s.pdf, ts_bxdf_f(&c->b, c->wo, s.wi), ts_bxdf_pdf(&c->b, c->wo, s.wi));
    *w = s.wi;
    return TS_CHI2_DIRECTION;
}

double ts_chi2_bxdf_pdf(void *ctx, ts_vec3 w)
{
    const ts_chi2_bxdf *c = ctx;
    return ts_bxdf_pdf(&c->b, c->wo, w);
}

ts_chi2_outcome ts_chi2_bsdf_sample(void *ctx, ts_pcg32 *rng, ts_vec3 *w)
{
    const ts_chi2_bsdf *c = ctx;
    float u_lobe = ts_pcg32_float(rng);
    ts_vec2 u = {ts_pcg32_float(rng), ts_pcg32_float(rng)};
    ts_bsdf_sample s;
    if (!ts_bsdf_sample_f(&c->b, c->wo, u_lobe, u, &s)) return TS_CHI2_NONE;
    if (s.flags & TS_BXDF_SPECULAR) return TS_CHI2_DISCRETE;
    check_contract(s.f, s.pdf, ts_bsdf_f(&c->b, c->wo, s.wi), ts_bsdf_pdf(&c->b, c->wo, s.wi));
    *w = s.wi;
    return TS_CHI2_DIRECTION;
}

double ts_chi2_bsdf_pdf(void *ctx, ts_vec3 w)
{
    const ts_chi2_bsdf *c = ctx;
    return ts_bsdf_pdf(&c->b, c->wo, w);
}

bool ts_chi2_pdf_normalised(const ts_chi2_params *p, const ts_chi2_result *r, double *frac)
{
    *frac = (double)r->binned / (double)p->sample_count;
    double sigma = sqrt(*frac * (1 - *frac) / (double)p->sample_count);
    return fabs(r->pdf_integral - *frac) <= 1e-3 + 4 * sigma;
}
