/* fourier_bsdf.c — pbrt-v3 Fourier BSDF tables: loading with full validation, Catmull-
 * Rom interpolation, Fourier evaluation and sampling (pbrt-v3 §8.6, appendix A). */
#include "materials/fourier_bsdf.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sampling/sampling.h"

#define HEADER_BYTES 64
#define MAX_MU 4096
/* Scratch for the interpolated coefficients of one lookup, on the stack (the hot path
 * allocates nothing): mMax × nChannels must fit. Real files use a few hundred
 * coefficients per channel; larger tables are refused at load time rather than rendered
 * black or truncated. */
#define AK_STACK 4096

/* ------------------------------------------------------------------ loading ---- */

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static int32_t le_i32(const unsigned char *p)
{
    uint32_t u = le32(p);
    int32_t v;
    memcpy(&v, &u, 4);
    return v;
}
static float le_f32(const unsigned char *p)
{
    uint32_t u = le32(p);
    float v;
    memcpy(&v, &u, 4);
    return v;
}

void ts_fourier_table_destroy(struct ts_fourier_table *t)
{
    if (!t) return;
    free(t->mu);
    free(t->m);
    free(t->a_offset);
    free(t->a);
    free(t->a0);
    free(t->cdf);
    free(t->recip);
    free(t);
}

ts_status ts_fourier_table_load(const char *path, struct ts_fourier_table **out, ts_error *err)
{
    *out = NULL;
    ts_status st = TS_OK;
    unsigned char *buf = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return ts_error_set(err, TS_ERR_IO, "%s: cannot open Fourier BSDF file: %s", path, strerror(errno));
    if (fseek(f, 0, SEEK_END) != 0) {
        st = ts_error_set(err, TS_ERR_IO, "%s: cannot read Fourier BSDF file: %s", path, strerror(errno));
        goto fail_file;
    }
    long size = ftell(f);
    rewind(f);
    if (size < 0) {
        st = ts_error_set(err, TS_ERR_IO, "%s: cannot read Fourier BSDF file", path);
        goto fail_file;
    }
    if (size < HEADER_BYTES) {
        st = ts_error_set(err, TS_ERR_INVALID, "%s: truncated Fourier BSDF file: %ld bytes, the header alone is %d",
                          path, size, HEADER_BYTES);
        goto fail_file;
    }
    buf = malloc((size_t)size);
    if (!buf) {
        st = ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory reading %ld bytes", path, size);
        goto fail_file;
    }
    if (fread(buf, 1, (size_t)size, f) != (size_t)size) {
        st = ts_error_set(err, TS_ERR_IO, "%s: read error", path);
        goto fail_buf;
    }
    st = ts_fourier_table_load_memory(buf, (size_t)size, path, out, err);
fail_buf:
    free(buf);
fail_file:
    fclose(f);
    return st;
}

ts_status ts_fourier_table_load_memory(const unsigned char *buf, size_t size, const char *path,
                                       struct ts_fourier_table **out, ts_error *err)
{
    *out = NULL;
    ts_status st = TS_OK;
    ts_fourier_table *t = NULL;
    if (!path) path = "(memory)";
    if (size < HEADER_BYTES)
        return ts_error_set(err, TS_ERR_INVALID, "%s: truncated Fourier BSDF file: %zu bytes, the header alone is %d",
                            path, size, HEADER_BYTES);
    static const unsigned char magic[8] = {'S', 'C', 'A', 'T', 'F', 'U', 'N', 0x01};
    if (memcmp(buf, magic, 8) != 0) {
        st = ts_error_set(err, TS_ERR_INVALID, "%s: not a pbrt-v3 Fourier BSDF file (bad magic, expected \"SCATFUN\\x01\")",
                          path);
        return st;
    }
    /* The header (pbrt-v3's FourierBSDFTable::Read): flags at byte 8, nMu 12, nCoeffs 16,
     * mMax 20, nChannels 24, nBases 28, nMetadataBytes 32 (what follows the coefficients:
     * a description pbrt-v3 never reads), two unused, eta 44, four unused. */
    int32_t flags = le_i32(buf + 8), n_mu = le_i32(buf + 12), n_coeffs = le_i32(buf + 16), m_max = le_i32(buf + 20),
            n_channels = le_i32(buf + 24), n_bases = le_i32(buf + 28);
    float eta = le_f32(buf + 44);
    if (flags != 1) {
        st = ts_error_set(err, TS_ERR_UNSUPPORTED,
                          "%s: unsupported flags %d at byte 8 (only 1, a uniform non-textured material, is supported, "
                          "as in pbrt-v3)",
                          path, (int)flags);
        return st;
    }
    if (n_channels != 1 && n_channels != 3) {
        st = ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: unsupported channel count %d at byte 24 (expected 1 or 3)", path,
                          (int)n_channels);
        return st;
    }
    if (n_bases != 1) {
        st = ts_error_set(err, TS_ERR_UNSUPPORTED, "%s: unsupported basis count %d at byte 28 (expected 1)", path,
                          (int)n_bases);
        return st;
    }
    if (n_mu < 2 || n_mu > MAX_MU || n_coeffs < 0 || m_max < 1) {
        st = ts_error_set(err, TS_ERR_INVALID, "%s: invalid sizes at bytes 12-23 (nMu %d, nCoeffs %d, mMax %d)", path,
                          (int)n_mu, (int)n_coeffs, (int)m_max);
        return st;
    }
    if ((int64_t)m_max * n_channels > AK_STACK) {
        st = ts_error_set(err, TS_ERR_UNSUPPORTED,
                          "%s: mMax %d (byte 20) with %d channel(s) exceeds the supported %d coefficients per lookup", path,
                          (int)m_max, (int)n_channels, AK_STACK);
        return st;
    }
    if (!(eta > 0) || !isfinite(eta)) {
        st = ts_error_set(err, TS_ERR_INVALID, "%s: invalid index of refraction %g at byte 44", path, eta);
        return st;
    }
    uint64_t nn = (uint64_t)n_mu * (uint64_t)n_mu;
    uint64_t expect = HEADER_BYTES + 4 * ((uint64_t)n_mu + nn + 2 * nn + (uint64_t)n_coeffs);
    /* What follows the coefficients (the nMetadataBytes of description the collection's
     * tables carry, or anything else) is not read, as pbrt-v3 reads none of it. */
    if ((uint64_t)size < expect) {
        st = ts_error_set(err, TS_ERR_INVALID,
                          "%s: truncated Fourier BSDF file: %zu bytes, the header announces tables up to byte %llu", path,
                          size, (unsigned long long)expect);
        return st;
    }
    t = calloc(1, sizeof *t);
    if (!t) goto fail_nomem;
    t->eta = eta;
    t->m_max = m_max;
    t->n_channels = n_channels;
    t->n_mu = n_mu;
    t->n_coeffs = n_coeffs;
    t->mu = malloc(sizeof(float) * (size_t)n_mu);
    t->cdf = malloc(sizeof(float) * nn);
    t->a0 = malloc(sizeof(float) * nn);
    t->m = malloc(sizeof(int) * nn);
    t->a_offset = malloc(sizeof(int) * nn);
    t->a = malloc(sizeof(float) * ((size_t)n_coeffs + 1));
    t->recip = malloc(sizeof(float) * (size_t)m_max);
    if (!t->mu || !t->cdf || !t->a0 || !t->m || !t->a_offset || !t->a || !t->recip) goto fail_nomem;

    /* The cosine nodes may repeat (the collection's tables hold μ = 0 twice, splitting
     * reflection from transmission): the spline's interval search never lands on an empty
     * interval but the last, so only decreasing nodes and an empty last interval (reached
     * at μ = its node) are refused. */
    const unsigned char *p = buf + HEADER_BYTES;
    for (int i = 0; i < n_mu; i++, p += 4) {
        t->mu[i] = le_f32(p);
        if (!isfinite(t->mu[i]) || (i > 0 && t->mu[i] < t->mu[i - 1])) {
            st = ts_error_set(err, TS_ERR_INVALID,
                              "%s: cosine node %d at byte %d (%g) is not finite or is below the node before it (the "
                              "nodes must not decrease)",
                              path, i, HEADER_BYTES + 4 * i, t->mu[i]);
            goto fail_table;
        }
    }
    if (!(t->mu[n_mu - 1] > t->mu[n_mu - 2])) {
        st = ts_error_set(err, TS_ERR_INVALID,
                          "%s: cosine node %d at byte %d (%g) equals the one before it: the last interval is empty", path,
                          n_mu - 1, HEADER_BYTES + 4 * (n_mu - 1), t->mu[n_mu - 1]);
        goto fail_table;
    }
    for (uint64_t i = 0; i < nn; i++, p += 4) {
        t->cdf[i] = le_f32(p);
        if (!isfinite(t->cdf[i])) {
            st = ts_error_set(err, TS_ERR_INVALID, "%s: CDF entry %llu at byte %llu is not finite", path,
                              (unsigned long long)i, (unsigned long long)(p - buf));
            goto fail_table;
        }
    }
    for (uint64_t i = 0; i < nn; i++, p += 8) {
        int32_t off = le_i32(p), len = le_i32(p + 4);
        if (off < 0 || len < 0 || len > m_max || (int64_t)off + (int64_t)len * n_channels > (int64_t)n_coeffs) {
            st = ts_error_set(err, TS_ERR_INVALID,
                              "%s: series %llu at byte %llu (offset %d, length %d, %d channel(s)) lies past the end of "
                              "the %d coefficients or exceeds mMax %d",
                              path, (unsigned long long)i, (unsigned long long)(p - buf), (int)off, (int)len,
                              (int)n_channels, (int)n_coeffs, (int)m_max);
            goto fail_table;
        }
        t->a_offset[i] = off;
        t->m[i] = len;
    }
    for (int i = 0; i < n_coeffs; i++, p += 4) {
        t->a[i] = le_f32(p);
        if (!isfinite(t->a[i])) {
            st = ts_error_set(err, TS_ERR_INVALID, "%s: coefficient %d at byte %llu is not finite", path, i,
                              (unsigned long long)(p - buf));
            goto fail_table;
        }
    }
    for (uint64_t i = 0; i < nn; i++) t->a0[i] = t->m[i] > 0 ? t->a[t->a_offset[i]] : 0;
    for (int i = 0; i < m_max; i++) t->recip[i] = i > 0 ? 1.0f / (float)i : 0;
    *out = t;
    return TS_OK;

fail_nomem:
    st = ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory for the Fourier BSDF table", path);
fail_table:
    ts_fourier_table_destroy(t);
    return st;
}

/* ------------------------------------------------------- spline and series ---- */

/* Largest i in [0, n−2] with nodes[i] ≤ x. */
static int find_interval(int n, const float *nodes, float x)
{
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (nodes[mid] <= x) lo = mid;
        else hi = mid;
    }
    return lo > n - 2 ? n - 2 : lo;
}

bool ts_catmull_rom_weights(int n, const float *nodes, float x, int *offset, float w[4])
{
    if (!(x >= nodes[0] && x <= nodes[n - 1])) return false;
    int idx = find_interval(n, nodes, x);
    *offset = idx - 1;
    float x0 = nodes[idx], x1 = nodes[idx + 1];
    float t = (x - x0) / (x1 - x0), t2 = t * t, t3 = t2 * t;
    w[1] = 2 * t3 - 3 * t2 + 1;
    w[2] = -2 * t3 + 3 * t2;
    if (idx > 0) {
        float w0 = (t3 - 2 * t2 + t) * (x1 - x0) / (x1 - nodes[idx - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        float w0 = t3 - 2 * t2 + t;
        w[0] = 0;
        w[1] -= w0;
        w[2] += w0;
    }
    if (idx + 2 < n) {
        float w3 = (t3 - t2) * (x1 - x0) / (nodes[idx + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        float w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
        w[3] = 0;
    }
    return true;
}

float ts_fourier_eval(const float *a, int m, double cos_phi)
{
    double value = 0, cos_prev = cos_phi, cos_cur = 1;
    for (int k = 0; k < m; k++) {
        value += a[k] * cos_cur;
        double cos_next = 2 * cos_phi * cos_cur - cos_prev;
        cos_prev = cos_cur;
        cos_cur = cos_next;
    }
    return (float)value;
}

float ts_catmull_rom_integrate(int n, const float *x, const float *v, float *cdf)
{
    double sum = 0;
    cdf[0] = 0;
    for (int i = 0; i < n - 1; i++) {
        double x0 = x[i], x1 = x[i + 1], f0 = v[i], f1 = v[i + 1], width = x1 - x0;
        double d0 = i > 0 ? width * (f1 - v[i - 1]) / (x1 - x[i - 1]) : f1 - f0;
        double d1 = i + 2 < n ? width * (v[i + 2] - f0) / (x[i + 2] - x0) : f1 - f0;
        sum += ((d0 - d1) * (1.0 / 12.0) + (f0 + f1) * 0.5) * width;
        cdf[i + 1] = (float)sum;
    }
    return (float)sum;
}

/* cos(φa − φb) of two directions' azimuths (1 when either is at the pole). */
static double cos_dphi(ts_vec3 a, ts_vec3 b)
{
    double axy = (double)a.x * a.x + (double)a.y * a.y, bxy = (double)b.x * b.x + (double)b.y * b.y;
    if (axy == 0 || bxy == 0) return 1;
    double c = ((double)a.x * b.x + (double)a.y * b.y) / sqrt(axy * bxy);
    return c < -1 ? -1 : (c > 1 ? 1 : c);
}

/* Interpolated coefficients at (mu_i, mu_o): ak[c·m_max + k]; returns the series length
 * (0 if outside the table). ak must hold n_channels·m_max floats. */
static int interpolate_ak(const ts_fourier_table *t, float mu_i, float mu_o, float *ak)
{
    int off_i, off_o;
    float wi[4], wo[4];
    if (!ts_catmull_rom_weights(t->n_mu, t->mu, mu_i, &off_i, wi) ||
        !ts_catmull_rom_weights(t->n_mu, t->mu, mu_o, &off_o, wo))
        return 0;
    memset(ak, 0, sizeof(float) * (size_t)t->m_max * (size_t)t->n_channels);
    int m_max = 0;
    for (int b = 0; b < 4; b++)
        for (int a = 0; a < 4; a++) {
            float w = wi[a] * wo[b];
            if (w == 0) continue;
            int idx = (off_o + b) * t->n_mu + (off_i + a);
            int m = t->m[idx];
            const float *ap = t->a + t->a_offset[idx];
            if (m > m_max) m_max = m;
            for (int c = 0; c < t->n_channels; c++)
                for (int k = 0; k < m; k++) ak[c * t->m_max + k] += w * ap[c * m + k];
        }
    return m_max;
}

/* Radiance scale: 1/|μi| for the stored f·|cosθi|, and (η_i/η_t)² across the interface. */
static float radiance_scale(const ts_fourier_table *t, float mu_i, float mu_o)
{
    float scale = mu_i != 0 ? 1 / fabsf(mu_i) : 0;
    if (mu_i * mu_o > 0) {
        float e = mu_i > 0 ? 1 / t->eta : t->eta;
        scale *= e * e;
    }
    return scale;
}

static ts_rgb to_rgb(const ts_fourier_table *t, const float *ak, int m, double cos_phi, float y, float scale)
{
    if (t->n_channels == 1) return ts_rgb_gray(ts_maxf(0, y) * scale);
    float r = ts_fourier_eval(ak + t->m_max, m, cos_phi), b = ts_fourier_eval(ak + 2 * t->m_max, m, cos_phi);
    float g = 1.39829f * y - 0.100913f * b - 0.297375f * r;
    return (ts_rgb){ts_maxf(0, r * scale), ts_maxf(0, g * scale), ts_maxf(0, b * scale)};
}

ts_rgb ts_fourier_f(const ts_fourier_table *t, ts_vec3 wo, ts_vec3 wi)
{
    if (!t || t->m_max * t->n_channels > AK_STACK) return ts_rgb_gray(0);
    float ak[AK_STACK];
    float mu_i = -wi.z, mu_o = wo.z;
    ts_vec3 nwi = ts_vec3_neg(wi);
    double cos_phi = cos_dphi(nwi, wo);
    int m = interpolate_ak(t, mu_i, mu_o, ak);
    if (m == 0) return ts_rgb_gray(0);
    float y = ts_maxf(0, ts_fourier_eval(ak, m, cos_phi));
    return to_rgb(t, ak, m, cos_phi, y, radiance_scale(t, mu_i, mu_o));
}

float ts_fourier_pdf(const ts_fourier_table *t, ts_vec3 wo, ts_vec3 wi)
{
    if (!t || t->m_max * t->n_channels > AK_STACK) return 0;
    float mu_i = -wi.z, mu_o = wo.z;
    double cos_phi = cos_dphi(ts_vec3_neg(wi), wo);
    int off_i, off_o;
    float w_i[4], w_o[4];
    if (!ts_catmull_rom_weights(t->n_mu, t->mu, mu_i, &off_i, w_i) ||
        !ts_catmull_rom_weights(t->n_mu, t->mu, mu_o, &off_o, w_o))
        return 0;
    /* Luminance series at (μi, μo) and the total mass of the μo row (2π ∫ a0 dμi). */
    float ak[AK_STACK];
    int m = interpolate_ak(t, mu_i, mu_o, ak);
    double rho = 0;
    for (int b = 0; b < 4; b++) {
        if (w_o[b] == 0) continue;
        rho += w_o[b] * t->cdf[(off_o + b) * t->n_mu + t->n_mu - 1] * 2 * TS_PI_D;
    }
    float y = ts_fourier_eval(ak, m, cos_phi);
    return (rho > 0 && y > 0) ? (float)(y / rho) : 0;
}

/* Value of row-interpolated array (rows offset..offset+3 weighted by w) at column idx. */
static double interp_row(const ts_fourier_table *t, const float *array, int offset, const float w[4], int idx)
{
    double v = 0;
    for (int k = 0; k < 4; k++)
        if (w[k] != 0) v += (double)array[(offset + k) * t->n_mu + idx] * w[k];
    return v;
}

/* Samples μi from the 2D Catmull-Rom spline of a0 at μo = alpha (pbrt-v3's
 * SampleCatmullRom2D, solved in double): returns μi, *pdf its density in μi. */
static float sample_mu(const ts_fourier_table *t, float alpha, float u, float *pdf)
{
    int n = t->n_mu, offset;
    float w[4];
    *pdf = 0;
    if (!ts_catmull_rom_weights(n, t->mu, alpha, &offset, w)) return 0;
    double maximum = interp_row(t, t->cdf, offset, w, n - 1);
    if (!(maximum > 0)) return 0;
    double uu = u * maximum;
    int lo = 0, hi = n - 1; /* largest interval whose running integral is ≤ uu */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (interp_row(t, t->cdf, offset, w, mid) <= uu) lo = mid;
        else hi = mid;
    }
    int idx = lo > n - 2 ? n - 2 : lo;
    double f0 = interp_row(t, t->a0, offset, w, idx), f1 = interp_row(t, t->a0, offset, w, idx + 1);
    double x0 = t->mu[idx], x1 = t->mu[idx + 1], width = x1 - x0;
    if (!(width > 0)) return 0; /* an empty interval (repeated node) whose CDF rises: no sample */
    double d0 = idx > 0 ? width * (f1 - interp_row(t, t->a0, offset, w, idx - 1)) / (x1 - t->mu[idx - 1]) : f1 - f0;
    double d1 = idx + 2 < n ? width * (interp_row(t, t->a0, offset, w, idx + 2) - f0) / (t->mu[idx + 2] - x0) : f1 - f0;
    uu = (uu - interp_row(t, t->cdf, offset, w, idx)) / width;
    /* Invert the cubic's integral F(τ) = uu by Newton–bisection on τ ∈ [0, 1]. */
    double tau;
    if (f0 != f1) tau = (f0 - sqrt(fmax(0.0, f0 * f0 + 2 * uu * (f1 - f0)))) / (f0 - f1);
    else tau = f0 != 0 ? uu / f0 : 0.5;
    double a = 0, b = 1, fhat = 0;
    for (int it = 0; it < 100; it++) {
        if (!(tau >= a && tau <= b)) tau = 0.5 * (a + b);
        double big_f = tau * (f0 + tau * (0.5 * d0 + tau * ((1.0 / 3.0) * (-2 * d0 - d1) + f1 - f0 +
                                                              tau * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
        fhat = f0 + tau * (d0 + tau * (-2 * d0 - d1 + 3 * (f1 - f0) + tau * (d0 + d1 + 2 * (f0 - f1))));
        double diff = big_f - uu;
        if (fabs(diff) < 1e-12 || b - a < 1e-12) break;
        if (diff < 0) a = tau;
        else b = tau;
        tau = fhat != 0 ? tau - diff / fhat : 0.5 * (a + b);
    }
    *pdf = (float)(fhat / maximum);
    return (float)(x0 + width * tau);
}

/* Samples φ ∈ [0, 2π) from the series ak (pbrt-v3's SampleFourier, in double): returns φ;
 * *value the series there, *pdf the density in φ. */
static double sample_phi(const float *ak, const float *recip, int m, float u, float *value, float *pdf)
{
    bool flip = u >= 0.5f;
    double uu = flip ? 1 - 2 * ((double)u - 0.5) : 2 * (double)u;
    double a = 0, b = TS_PI_D, phi = 0.5 * TS_PI_D, big_f = 0, f = ak[0];
    for (int it = 0; it < 100; it++) {
        double cos_phi = cos(phi), sin_phi = sqrt(fmax(0.0, 1 - cos_phi * cos_phi));
        double cos_prev = cos_phi, cos_cur = 1, sin_prev = -sin_phi, sin_cur = 0;
        big_f = ak[0] * phi;
        f = ak[0];
        for (int k = 1; k < m; k++) {
            double sin_next = 2 * cos_phi * sin_cur - sin_prev, cos_next = 2 * cos_phi * cos_cur - cos_prev;
            sin_prev = sin_cur;
            sin_cur = sin_next;
            cos_prev = cos_cur;
            cos_cur = cos_next;
            big_f += ak[k] * recip[k] * sin_next;
            f += ak[k] * cos_next;
        }
        big_f -= uu * ak[0] * TS_PI_D;
        if (big_f > 0) b = phi;
        else a = phi;
        if (fabs(big_f) < 1e-12 || b - a < 1e-12) break;
        phi -= f != 0 ? big_f / f : 0;
        if (!(phi > a && phi < b)) phi = 0.5 * (a + b);
    }
    if (flip) phi = 2 * TS_PI_D - phi;
    *value = (float)f;
    *pdf = (float)(f / (2 * TS_PI_D * ak[0]));
    return phi;
}

ts_rgb ts_fourier_sample(const ts_fourier_table *t, ts_vec3 wo, ts_vec2 u, ts_vec3 *wi, float *pdf)
{
    *pdf = 0;
    *wi = (ts_vec3){0, 0, 1};
    if (!t || t->m_max * t->n_channels > AK_STACK || wo.z == 0) return ts_rgb_gray(0);
    float mu_o = wo.z, pdf_mu;
    float mu_i = sample_mu(t, mu_o, u.y, &pdf_mu);
    if (!(pdf_mu > 0)) return ts_rgb_gray(0);
    float ak[AK_STACK];
    int m = interpolate_ak(t, mu_i, mu_o, ak);
    if (m == 0 || !(ak[0] > 0)) return ts_rgb_gray(0);
    float y, pdf_phi;
    double phi = sample_phi(ak, t->recip, m, u.x, &y, &pdf_phi);
    *pdf = ts_maxf(0, pdf_phi * pdf_mu);
    if (!(*pdf > 0) || !isfinite(*pdf)) {
        *pdf = 0;
        return ts_rgb_gray(0);
    }
    /* −wi has cosine μi and azimuth φ relative to wo's. */
    double sin_i = sqrt(fmax(0.0, 1 - (double)mu_i * mu_i));
    double oxy = sqrt((double)wo.x * wo.x + (double)wo.y * wo.y);
    double cx = oxy > 0 ? wo.x / oxy : 1, cy = oxy > 0 ? wo.y / oxy : 0;
    double cp = cos(phi), sp = sin(phi);
    ts_vec3 d = {(float)(sin_i * (cp * cx - sp * cy)), (float)(sin_i * (sp * cx + cp * cy)), mu_i};
    *wi = ts_vec3_normalize(ts_vec3_neg(d));
    double cos_phi = cos_dphi(ts_vec3_neg(*wi), wo);
    return to_rgb(t, ak, m, cos_phi, ts_maxf(0, y), radiance_scale(t, mu_i, mu_o));
}
