/* spectrum.c — spectra to RGB as pbrt-v3 converts them; see spectrum.h. */
#include "spectrum/spectrum.h"

#include <math.h>
#include <stdlib.h>

/* pbrt-v3's ∫ȳ(λ) dλ over its 1 nm table. */
#define CIE_Y_INTEGRAL 106.856895

ts_rgb ts_spectrum_xyz_to_rgb(double x, double y, double z)
{
    return (ts_rgb){(float)(3.240479 * x - 1.537150 * y - 0.498535 * z),
                    (float)(-0.969256 * x + 1.875991 * y + 0.041556 * z),
                    (float)(0.055648 * x - 0.204043 * y + 1.057311 * z)};
}

/* Piecewise-linear interpolation of sorted samples, constant beyond the ends. */
static double interpolate(const double *lambda, const double *v, size_t n, double l)
{
    if (l <= lambda[0]) return v[0];
    if (l >= lambda[n - 1]) return v[n - 1];
    size_t lo = 0, hi = n - 1; /* lambda[lo] <= l < lambda[hi] */
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (lambda[mid] <= l)
            lo = mid;
        else
            hi = mid;
    }
    double t = (l - lambda[lo]) / (lambda[lo + 1] - lambda[lo]);
    return (1 - t) * v[lo] + t * v[lo + 1];
}

typedef struct pair {
    double lambda, value;
} pair;

static int by_lambda(const void *a, const void *b)
{
    double x = ((const pair *)a)->lambda, y = ((const pair *)b)->lambda;
    return (x > y) - (x < y);
}

static ts_rgb from_sorted(const double *lambda, const double *v, size_t n)
{
    double xyz[3] = {0, 0, 0};
    for (int i = 0; i < TS_CIE_SAMPLES; i++) {
        double val = interpolate(lambda, v, n, TS_CIE_LAMBDA_MIN + i);
        xyz[0] += val * ts_cie_x[i];
        xyz[1] += val * ts_cie_y[i];
        xyz[2] += val * ts_cie_z[i];
    }
    double scale = (double)(TS_CIE_SAMPLES - 1) / (CIE_Y_INTEGRAL * TS_CIE_SAMPLES);
    return ts_spectrum_xyz_to_rgb(xyz[0] * scale, xyz[1] * scale, xyz[2] * scale);
}

ts_rgb ts_spectrum_sampled_to_rgb(const double *lambda, const double *value, size_t n)
{
    if (n == 0) return ts_rgb_gray(0);
    bool sorted = true;
    for (size_t i = 1; i < n; i++)
        if (lambda[i] < lambda[i - 1]) sorted = false;
    if (sorted) return from_sorted(lambda, value, n);
    pair *p = malloc(n * sizeof *p);
    double *l = malloc(n * sizeof *l), *v = malloc(n * sizeof *v);
    ts_rgb out = ts_rgb_gray(0);
    if (p && l && v) {
        for (size_t i = 0; i < n; i++)
            p[i] = (pair){lambda[i], value[i]};
        qsort(p, n, sizeof *p, by_lambda);
        for (size_t i = 0; i < n; i++)
            l[i] = p[i].lambda, v[i] = p[i].value;
        out = from_sorted(l, v, n);
    }
    free(p);
    free(l);
    free(v);
    return out;
}

ts_rgb ts_spectrum_to_rgb(const float *pairs, size_t n)
{
    double *l = malloc((n ? n : 1) * sizeof *l), *v = malloc((n ? n : 1) * sizeof *v);
    ts_rgb out = ts_rgb_gray(0);
    if (l && v) {
        for (size_t i = 0; i < n; i++)
            l[i] = pairs[2 * i], v[i] = pairs[2 * i + 1];
        out = ts_spectrum_sampled_to_rgb(l, v, n);
    }
    free(l);
    free(v);
    return out;
}

/* Planck's law: spectral radiance at lambda_nm (W·sr⁻¹·m⁻³), pbrt-v3's constants. */
static double planck(double lambda_nm, double t)
{
    const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    double l = lambda_nm * 1e-9, l5 = (l * l) * (l * l) * l;
    return (2 * h * c * c) / (l5 * (exp((h * c) / (l * kb * t)) - 1));
}

ts_rgb ts_spectrum_blackbody_rgb(double temperature_k, double scale)
{
    if (!(temperature_k > 0) || !isfinite(temperature_k)) return ts_rgb_gray(0);
    double lambda[TS_CIE_SAMPLES], v[TS_CIE_SAMPLES];
    double peak = planck(2.8977721e-3 / temperature_k * 1e9, temperature_k);
    for (int i = 0; i < TS_CIE_SAMPLES; i++) {
        lambda[i] = TS_CIE_LAMBDA_MIN + i;
        v[i] = planck(lambda[i], temperature_k) / peak;
    }
    ts_rgb c = from_sorted(lambda, v, TS_CIE_SAMPLES);
    return (ts_rgb){(float)(c.r * scale), (float)(c.g * scale), (float)(c.b * scale)};
}

void ts_spectrum_copper(ts_rgb *eta, ts_rgb *k)
{
    double l[TS_COPPER_SAMPLES], n[TS_COPPER_SAMPLES], kk[TS_COPPER_SAMPLES];
    for (int i = 0; i < TS_COPPER_SAMPLES; i++) {
        l[i] = ts_copper_nk[i][0];
        n[i] = ts_copper_nk[i][1];
        kk[i] = ts_copper_nk[i][2];
    }
    *eta = from_sorted(l, n, TS_COPPER_SAMPLES);
    *k = from_sorted(l, kk, TS_COPPER_SAMPLES);
}
