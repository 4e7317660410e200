/* render_stats.c — see render_stats.h. The incomplete beta function behind Student's t is
 * evaluated by its continued fraction (modified Lentz), on the side of x where it
 * converges quickly. */
#include "render_stats.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
/* cmocka needs the three above first */
#include <cmocka.h>

#include <math.h>
#include <string.h>

void ts_rs_render(ts_scene *s, ts_sampler_type type, uint32_t seed0, int k, int spp, int block,
                  ts_rs_blocks *out)
{
    memset(out, 0, sizeof *out);
    int w = s->width, h = s->height;
    if (k < 2 || block < 1 || w % block || h % block || (w / block) * (h / block) > TS_RS_MAX_BLOCKS)
        fail_msg("ts_rs_render: %d renders of a %d×%d film in %d-pixel blocks", k, w, h, block);
    out->nx = w / block, out->ny = h / block, out->n = out->nx * out->ny, out->k = k;
    double sum[TS_RS_MAX_BLOCKS] = {0}, sum2[TS_RS_MAX_BLOCKS] = {0}, isum = 0, isum2 = 0;
    ts_sampler saved = s->sampler;
    ts_error err = {0};
    for (int r = 0; r < k; r++) {
        s->sampler.type = type;
        s->sampler.seed = seed0 + (uint32_t)r;
        ts_film *f = ts_film_create(w, h, 0, 0, w, h, &err);
        if (!f) fail_msg("film: %s", err.message);
        ts_render_stats stats = {0};
        ts_render_request req = {s, s->integrator.type, f, 0, (uint32_t)spp, 2, NULL, NULL, NULL};
        if (ts_render(&req, &stats, &err) != TS_OK) fail_msg("render: %s", err.message);
        out->nonfinite += stats.counters.nonfinite;
        out->seconds += stats.seconds;
        double bm[TS_RS_MAX_BLOCKS] = {0};
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                ts_rgb c = ts_film_pixel_rgb(f, x, y);
                bm[(y / block) * out->nx + x / block] += (c.r + c.g + c.b) / 3.0;
            }
        double im = 0;
        for (int b = 0; b < out->n; b++) {
            bm[b] /= (double)block * block;
            im += bm[b] / out->n;
            sum[b] += bm[b];
            sum2[b] += bm[b] * bm[b];
        }
        isum += im;
        isum2 += im * im;
        ts_film_destroy(f);
    }
    s->sampler = saved;
    for (int b = 0; b < out->n; b++) {
        out->mean[b] = sum[b] / k;
        out->se[b] = sqrt(fmax(0, (sum2[b] - k * out->mean[b] * out->mean[b]) / (k - 1)) / k);
    }
    out->image_mean = isum / k;
    out->image_se = sqrt(fmax(0, (isum2 - k * out->image_mean * out->image_mean) / (k - 1)) / k);
}

/* Continued fraction of the incomplete beta function I_x(a, b) (without its prefactor),
 * by the modified Lentz method. */
static double beta_fraction(double a, double b, double x)
{
    const double tiny = 1e-300;
    double c = 1, d = 1 - (a + b) * x / (a + 1);
    if (fabs(d) < tiny) d = tiny;
    d = 1 / d;
    double f = d;
    for (int m = 1; m <= 400; m++) {
        /* even step: d_{2m} = m(b − m)x / ((a + 2m − 1)(a + 2m)) */
        double num = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m));
        d = 1 + num * d;
        c = 1 + num / c;
        if (fabs(d) < tiny) d = tiny;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        f *= d * c;
        /* odd step: d_{2m+1} = −(a + m)(a + b + m)x / ((a + 2m)(a + 2m + 1)) */
        num = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
        d = 1 + num * d;
        c = 1 + num / c;
        if (fabs(d) < tiny) d = tiny;
        if (fabs(c) < tiny) c = tiny;
        d = 1 / d;
        double delta = d * c;
        f *= delta;
        if (fabs(delta - 1) < 1e-15) break;
    }
    return f;
}

/* Regularised incomplete beta I_x(a, b). */
static double incomplete_beta(double a, double b, double x)
{
    if (x <= 0) return 0;
    if (x >= 1) return 1;
    double front = exp(lgamma(a + b) - lgamma(a) - lgamma(b) + a * log(x) + b * log1p(-x));
    if (x < (a + 1) / (a + b + 2)) return front * beta_fraction(a, b, x) / a;
    return 1 - front * beta_fraction(b, a, 1 - x) / b;
}

double ts_rs_student_two_sided(double t, double dof)
{
    if (!(dof > 0) || isnan(t)) return 0;
    if (isinf(t)) return 0;
    return incomplete_beta(dof / 2, 0.5, dof / (dof + t * t));
}

/* One block's test: difference d with standard error se on dof degrees of freedom. A
 * difference within 1e-5 of the values (scale) is float rounding of the film's sums —
 * a noiseless estimator (se ≈ 0) agrees with its closed form only to that — and one
 * within the caller's floor is below the test's resolution; both pass. A larger one with
 * se = 0 fails. */
static double block_p(double d, double se, double dof, double scale, double floor, double *t)
{
    *t = se > 0 ? d / se : 0;
    if (fabs(d) <= 1e-5 * scale + 1e-12) *t = 0;
    if (fabs(d) <= 1e-5 * scale + 1e-12 || fabs(d) <= floor) return 1;
    if (!(se > 0)) return 0;
    return ts_rs_student_two_sided(*t, dof);
}

static void keep_worst(ts_rs_result *r, int b, double p, double t, double dof, double d)
{
    if (r->block < 0 || p < r->p) {
        r->p = p, r->block = b, r->t = t, r->dof = dof, r->diff = d;
    }
}

ts_rs_result ts_rs_compare(const ts_rs_blocks *a, const ts_rs_blocks *b, double floor)
{
    ts_rs_result r = {1, -1, 0, 0, 0, 0, 0, 1};
    if (a->n != b->n) fail_msg("ts_rs_compare: %d blocks against %d", a->n, b->n);
    for (int i = 0; i < a->n; i++) {
        double va = a->se[i] * a->se[i], vb = b->se[i] * b->se[i], v = va + vb;
        /* Welch–Satterthwaite */
        double dof = v > 0 ? v * v / (va * va / (a->k - 1) + vb * vb / (b->k - 1)) : 1;
        double t, d = a->mean[i] - b->mean[i];
        double p = block_p(d, sqrt(v), dof, fmax(fabs(a->mean[i]), fabs(b->mean[i])), floor, &t);
        keep_worst(&r, i, p, t, dof, d);
    }
    double va = a->image_se * a->image_se, vb = b->image_se * b->image_se, v = va + vb;
    double dof = v > 0 ? v * v / (va * va / (a->k - 1) + vb * vb / (b->k - 1)) : 1;
    r.image_diff = a->image_mean - b->image_mean;
    r.image_p = block_p(r.image_diff, sqrt(v), dof, fmax(fabs(a->image_mean), fabs(b->image_mean)), floor,
                        &r.image_t);
    return r;
}

ts_rs_result ts_rs_compare_reference(const ts_rs_blocks *a, const double *ref, const double *ref_se,
                                     double ref_dof, double floor)
{
    ts_rs_result r = {1, -1, 0, 0, 0, 0, 0, 1};
    double rsum = 0, rvar = 0;
    for (int i = 0; i < a->n; i++) {
        double va = a->se[i] * a->se[i], vr = ref_se ? ref_se[i] * ref_se[i] : 0, v = va + vr;
        double dof = a->k - 1;
        if (vr > 0) dof = v * v / (va * va / (a->k - 1) + vr * vr / ref_dof);
        double t, d = a->mean[i] - ref[i];
        double p = block_p(d, sqrt(v), dof, fmax(fabs(a->mean[i]), fabs(ref[i])), floor, &t);
        keep_worst(&r, i, p, t, dof, d);
        rsum += ref[i] / a->n;
        rvar += vr / ((double)a->n * a->n);
    }
    /* The reference's image mean: its blocks' mean, their errors taken as independent. */
    double va = a->image_se * a->image_se, v = va + rvar;
    double dof = rvar > 0 ? v * v / (va * va / (a->k - 1) + rvar * rvar / ref_dof) : a->k - 1;
    r.image_diff = a->image_mean - rsum;
    r.image_p = block_p(r.image_diff, sqrt(v), dof, fmax(fabs(a->image_mean), fabs(rsum)), floor, &r.image_t);
    return r;
}

int ts_rs_passes(const ts_rs_result *r, int blocks, double alpha)
{
    return r->p >= alpha / (blocks + 1) && r->image_p >= alpha / (blocks + 1);
}
