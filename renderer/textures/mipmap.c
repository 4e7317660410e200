/* mipmap.c — pbrt-v3's MIPMap (see mipmap.h).
 *
 * Every level is a power of two wide and high (level 0 is resampled to one when the
 * source is not), so the repeat wrap is a mask. Texel coordinates are int64 so that
 * pbrt-v3's int conversions of large (s, t) are never out of range here. */
#include "textures/mipmap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SOURCE_PIXELS ((int64_t)1 << 28)

static const float zero3[3] = {0, 0, 0};

/* pbrt-v3's Log2 (log(x)·1/ln 2), in float. */
static inline float log2_pbrt(float x) { return logf(x) * 1.442695040888963387004650940071f; }

/* floor(x) as an int64, saturating far beyond any texture (and NaN to the low end). */
static inline int64_t floor_i64(float x)
{
    float f = floorf(x);
    if (!(f > -0x1p62f)) return -((int64_t)1 << 62);
    if (!(f < 0x1p62f)) return (int64_t)1 << 62;
    return (int64_t)f;
}

static inline int64_t ceil_i64(float x)
{
    float f = ceilf(x);
    if (!(f > -0x1p62f)) return -((int64_t)1 << 62);
    if (!(f < 0x1p62f)) return (int64_t)1 << 62;
    return (int64_t)f;
}

static int32_t round_up_pow2(int32_t v)
{
    int32_t p = 1;
    while (p < v)
        p <<= 1;
    return p;
}

static int log2_int(int32_t v)
{
    int l = 0;
    while (v > 1)
        v >>= 1, l++;
    return l;
}

/* Texel (s, t) of a level under the wrap mode (pbrt-v3's MIPMap::Texel); levels are
 * powers of two, so repeat is a mask (also right for negative s in two's complement). */
static inline const float *texel_ptr(const ts_mipmap *m, const ts_mipmap_level *l, int64_t s, int64_t t)
{
    int64_t w = l->width, h = l->height;
    switch (m->wrap) {
    case TS_TEXTURE_WRAP_REPEAT:
        s &= w - 1;
        t &= h - 1;
        break;
    case TS_TEXTURE_WRAP_CLAMP:
        s = s < 0 ? 0 : (s >= w ? w - 1 : s);
        t = t < 0 ? 0 : (t >= h ? h - 1 : t);
        break;
    case TS_TEXTURE_WRAP_BLACK:
        if (s < 0 || s >= w || t < 0 || t >= h) return zero3;
        break;
    }
    return l->texels + ((size_t)t * (size_t)w + (size_t)s) * (size_t)m->n_channels;
}

static inline ts_rgb to_rgb(const ts_mipmap *m, const float *v)
{
    return m->n_channels == 1 ? ts_rgb_gray(v[0]) : (ts_rgb){v[0], v[1], v[2]};
}

static inline ts_rgb rgb_lerp(float t, ts_rgb a, ts_rgb b)
{
    return (ts_rgb){ts_lerpf(t, a.r, b.r), ts_lerpf(t, a.g, b.g), ts_lerpf(t, a.b, b.b)};
}

ts_rgb ts_mipmap_texel(const ts_mipmap *m, int level, int64_t s, int64_t t)
{
    if (level < 0) level = 0;
    if (level >= m->n_levels) level = m->n_levels - 1;
    return to_rgb(m, texel_ptr(m, &m->levels[level], s, t));
}

static inline ts_vec2 finite_st(ts_vec2 st)
{
    return (isfinite(st.x) && isfinite(st.y)) ? st : (ts_vec2){0, 0};
}

static ts_rgb bilinear(const ts_mipmap *m, int level, ts_vec2 st)
{
    if (level < 0) level = 0;
    if (level >= m->n_levels) level = m->n_levels - 1;
    const ts_mipmap_level *l = &m->levels[level];
    float s = st.x * (float)l->width - 0.5f, t = st.y * (float)l->height - 0.5f;
    float fs = floorf(s), ft = floorf(t);
    int64_t s0 = floor_i64(s), t0 = floor_i64(t);
    float ds = s - fs, dt = t - ft;
    float w00 = (1 - ds) * (1 - dt), w01 = (1 - ds) * dt, w10 = ds * (1 - dt), w11 = ds * dt;
    const float *a = texel_ptr(m, l, s0, t0), *b = texel_ptr(m, l, s0, t0 + 1);
    const float *c = texel_ptr(m, l, s0 + 1, t0), *d = texel_ptr(m, l, s0 + 1, t0 + 1);
    float v[3];
    for (int k = 0; k < m->n_channels; k++)
        v[k] = w00 * a[k] + w01 * b[k] + w10 * c[k] + w11 * d[k];
    return to_rgb(m, v);
}

ts_rgb ts_mipmap_bilinear(const ts_mipmap *m, int level, ts_vec2 st)
{
    return bilinear(m, level, finite_st(st));
}

ts_rgb ts_mipmap_trilinear(const ts_mipmap *m, ts_vec2 st, float width)
{
    st = finite_st(st);
    if (!(width >= 0)) width = 0; /* NaN or negative: the finest level, as pbrt-v3 for w < 1e-8 */
    float level = (float)(m->n_levels - 1) + log2_pbrt(ts_maxf(width, 1e-8f));
    if (level < 0) return bilinear(m, 0, st);
    if (level >= (float)(m->n_levels - 1)) return ts_mipmap_texel(m, m->n_levels - 1, 0, 0);
    int il = (int)floorf(level);
    float delta = level - (float)il;
    return rgb_lerp(delta, bilinear(m, il, st), bilinear(m, il + 1, st));
}

/* One level of pbrt-v3's MIPMap::EWA. */
static ts_rgb ewa_level(const ts_mipmap *m, int level, ts_vec2 st, ts_vec2 dst0, ts_vec2 dst1)
{
    if (level >= m->n_levels) return ts_mipmap_texel(m, m->n_levels - 1, 0, 0);
    const ts_mipmap_level *l = &m->levels[level];
    float w = (float)l->width, h = (float)l->height;
    float s = st.x * w - 0.5f, t = st.y * h - 0.5f;
    dst0.x *= w, dst0.y *= h, dst1.x *= w, dst1.y *= h;

    /* The ellipse's implicit form A s² + B s t + C t² < 1 (with the filter widened by one
     * texel in each direction), and its bounding box. */
    float a = dst0.y * dst0.y + dst1.y * dst1.y + 1;
    float b = -2 * (dst0.x * dst0.y + dst1.x * dst1.y);
    float c = dst0.x * dst0.x + dst1.x * dst1.x + 1;
    float inv_f = 1 / (a * c - b * b * 0.25f);
    a *= inv_f, b *= inv_f, c *= inv_f;
    float det = -b * b + 4 * a * c;
    float inv_det = 1 / det;
    float u_sqrt = sqrtf(det * c), v_sqrt = sqrtf(a * det);
    int64_t s0 = ceil_i64(s - 2 * inv_det * u_sqrt), s1 = floor_i64(s + 2 * inv_det * u_sqrt);
    int64_t t0 = ceil_i64(t - 2 * inv_det * v_sqrt), t1 = floor_i64(t + 2 * inv_det * v_sqrt);
    /* Unreachable with the bounded anisotropy (mipmap.h); a guard against a degenerate
     * ellipse from rounding. */
    if (!(s1 - s0 <= 4096 && t1 - t0 <= 4096)) return bilinear(m, level, st);

    float sum[3] = {0, 0, 0}, sum_w = 0;
    for (int64_t it = t0; it <= t1; ++it) {
        float tt = (float)it - t;
        for (int64_t is = s0; is <= s1; ++is) {
            float ss = (float)is - s;
            float r2 = a * ss * ss + b * ss * tt + c * tt * tt;
            if (r2 < 1) {
                int index = (int)(r2 * TS_MIPMAP_EWA_LUT_SIZE);
                if (index > TS_MIPMAP_EWA_LUT_SIZE - 1) index = TS_MIPMAP_EWA_LUT_SIZE - 1;
                if (index < 0) index = 0;
                float weight = m->ewa_weights[index];
                const float *v = texel_ptr(m, l, is, it);
                for (int k = 0; k < m->n_channels; k++)
                    sum[k] += v[k] * weight;
                sum_w += weight;
            }
        }
    }
    if (!(sum_w > 0)) return bilinear(m, level, st);
    for (int k = 0; k < m->n_channels; k++)
        sum[k] = sum[k] / sum_w;
    return to_rgb(m, sum);
}

static inline bool finite2(ts_vec2 v) { return isfinite(v.x) && isfinite(v.y); }

ts_rgb ts_mipmap_ewa(const ts_mipmap *m, ts_vec2 st, ts_vec2 dst0, ts_vec2 dst1, float max_anisotropy)
{
    st = finite_st(st);
    if (!finite2(dst0) || !finite2(dst1)) dst0 = dst1 = (ts_vec2){0, 0};
    if (!(max_anisotropy > 0)) max_anisotropy = 1;
    if (max_anisotropy > TS_MIPMAP_MAX_ANISOTROPY) max_anisotropy = TS_MIPMAP_MAX_ANISOTROPY;
    if (dst0.x * dst0.x + dst0.y * dst0.y < dst1.x * dst1.x + dst1.y * dst1.y) {
        ts_vec2 tmp = dst0;
        dst0 = dst1, dst1 = tmp;
    }
    float major = sqrtf(dst0.x * dst0.x + dst0.y * dst0.y);
    float minor = sqrtf(dst1.x * dst1.x + dst1.y * dst1.y);
    /* Clamp the eccentricity by growing the minor axis. */
    if (minor * max_anisotropy < major && minor > 0) {
        float scale = major / (minor * max_anisotropy);
        dst1.x *= scale, dst1.y *= scale;
        minor *= scale;
    }
    if (minor == 0) return bilinear(m, 0, st);
    float lod = ts_maxf(0, (float)(m->n_levels - 1) + log2_pbrt(minor));
    if (lod > (float)m->n_levels) lod = (float)m->n_levels; /* both levels are the 1 × 1 texel */
    int ilod = (int)floorf(lod);
    return rgb_lerp(lod - (float)ilod, ewa_level(m, ilod, st, dst0, dst1),
                    ewa_level(m, ilod + 1, st, dst0, dst1));
}

ts_rgb ts_mipmap_lookup(const ts_mipmap *m, ts_vec2 st, ts_vec2 dstdx, ts_vec2 dstdy, bool trilinear,
                        float max_anisotropy)
{
    if (trilinear) {
        float width =
            ts_maxf(ts_maxf(fabsf(dstdx.x), fabsf(dstdx.y)), ts_maxf(fabsf(dstdy.x), fabsf(dstdy.y)));
        return ts_mipmap_trilinear(m, st, 2 * width);
    }
    return ts_mipmap_ewa(m, st, dstdx, dstdy, max_anisotropy);
}

/* ---- building ---- */

size_t ts_mipmap_bytes_for(int32_t width, int32_t height, int32_t n_channels)
{
    if (width < 1 || height < 1 || width > TS_MIPMAP_MAX_SIZE || height > TS_MIPMAP_MAX_SIZE) return 0;
    if (n_channels != 1 && n_channels != 3) return 0;
    size_t w = (size_t)round_up_pow2(width), h = (size_t)round_up_pow2(height), total = 0;
    for (;;) {
        total += w * h * (size_t)n_channels * sizeof(float);
        if (w == 1 && h == 1) break;
        w = w > 1 ? w / 2 : 1;
        h = h > 1 ? h / 2 : 1;
    }
    return total;
}

/* pbrt-v3's windowed sinc: sinc(x·τ)·sinc(x) on |x| ≤ 1, τ = 2. */
static float lanczos(float x)
{
    const float tau = 2;
    x = fabsf(x);
    if (x < 1e-5f) return 1;
    if (x > 1.0f) return 0;
    x *= TS_PI;
    float s = sinf(x * tau) / (x * tau);
    float l = sinf(x) / x;
    return s * l;
}

typedef struct resample_weight {
    int32_t first;
    float w[4];
} resample_weight;

/* pbrt-v3's MIPMap::resampleWeights(old_res, new_res), new_res ≥ old_res. */
static void resample_weights(int32_t old_res, int32_t new_res, resample_weight *wt)
{
    const float filter_width = 2;
    for (int32_t i = 0; i < new_res; ++i) {
        float center = ((float)i + 0.5f) * (float)old_res / (float)new_res;
        wt[i].first = (int32_t)floorf((center - filter_width) + 0.5f);
        for (int j = 0; j < 4; ++j) {
            float pos = (float)(wt[i].first + j) + 0.5f;
            wt[i].w[j] = lanczos((pos - center) / filter_width);
        }
        float inv_sum = 1 / (wt[i].w[0] + wt[i].w[1] + wt[i].w[2] + wt[i].w[3]);
        for (int j = 0; j < 4; ++j)
            wt[i].w[j] *= inv_sum;
    }
}

/* A tap of the resampling filter under the wrap mode; -1 for black outside. */
static int32_t resample_tap(int32_t i, int32_t n, ts_texture_wrap wrap)
{
    if (wrap == TS_TEXTURE_WRAP_REPEAT) {
        i %= n;
        if (i < 0) i += n;
    } else if (wrap == TS_TEXTURE_WRAP_CLAMP) {
        i = i < 0 ? 0 : (i >= n ? n - 1 : i);
    }
    return i >= 0 && i < n ? i : -1;
}

/* Level 0 (w2 × h2) from the w × h source: the s pass into the first h rows, then the t
 * pass column by column through a work buffer, clamping at 0. */
static ts_status resample(const float *src, int32_t w, int32_t h, int32_t nc, ts_texture_wrap wrap,
                          float *dst, int32_t w2, int32_t h2, ts_error *err)
{
    resample_weight *sw = malloc(sizeof *sw * (size_t)w2), *tw = malloc(sizeof *tw * (size_t)h2);
    float *work = malloc(sizeof *work * (size_t)h2 * (size_t)nc);
    if (!sw || !tw || !work) {
        free(sw), free(tw), free(work);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory resampling a %d × %d texture", w, h);
    }
    resample_weights(w, w2, sw);
    for (int32_t t = 0; t < h; ++t) {
        for (int32_t s = 0; s < w2; ++s) {
            float *o = dst + ((size_t)t * (size_t)w2 + (size_t)s) * (size_t)nc;
            for (int k = 0; k < nc; k++)
                o[k] = 0;
            for (int j = 0; j < 4; ++j) {
                int32_t os = resample_tap(sw[s].first + j, w, wrap);
                if (os < 0) continue;
                const float *in = src + ((size_t)t * (size_t)w + (size_t)os) * (size_t)nc;
                for (int k = 0; k < nc; k++)
                    o[k] += sw[s].w[j] * in[k];
            }
        }
    }
    resample_weights(h, h2, tw);
    for (int32_t s = 0; s < w2; ++s) {
        for (int32_t t = 0; t < h2; ++t) {
            float *o = work + (size_t)t * (size_t)nc;
            for (int k = 0; k < nc; k++)
                o[k] = 0;
            for (int j = 0; j < 4; ++j) {
                int32_t ot = resample_tap(tw[t].first + j, h, wrap);
                if (ot < 0) continue;
                const float *in = dst + ((size_t)ot * (size_t)w2 + (size_t)s) * (size_t)nc;
                for (int k = 0; k < nc; k++)
                    o[k] += tw[t].w[j] * in[k];
            }
        }
        for (int32_t t = 0; t < h2; ++t)
            for (int k = 0; k < nc; k++) {
                float v = work[(size_t)t * (size_t)nc + (size_t)k];
                dst[((size_t)t * (size_t)w2 + (size_t)s) * (size_t)nc + (size_t)k] = v < 0 ? 0 : v;
            }
    }
    free(sw), free(tw), free(work);
    return TS_OK;
}

ts_status ts_mipmap_create(const float *texels, int32_t width, int32_t height, int32_t n_channels,
                           ts_texture_wrap wrap, size_t max_bytes, ts_mipmap **out, ts_error *err)
{
    *out = NULL;
    if (n_channels != 1 && n_channels != 3)
        return ts_error_set(err, TS_ERR_INVALID, "a MIP map has 1 or 3 channels, not %d", n_channels);
    if (width < 1 || height < 1)
        return ts_error_set(err, TS_ERR_INVALID, "the image is empty (%d × %d texels)", width, height);
    if (width > TS_MIPMAP_MAX_SIZE || height > TS_MIPMAP_MAX_SIZE ||
        (int64_t)width * height > MAX_SOURCE_PIXELS)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "the image is %d × %d texels, more than the limit of %d per side and %lld in all",
                            width, height, TS_MIPMAP_MAX_SIZE, (long long)MAX_SOURCE_PIXELS);
    if (wrap != TS_TEXTURE_WRAP_REPEAT && wrap != TS_TEXTURE_WRAP_BLACK && wrap != TS_TEXTURE_WRAP_CLAMP)
        return ts_error_set(err, TS_ERR_INVALID, "unknown wrap mode %d", (int)wrap);
    size_t n = (size_t)width * (size_t)height * (size_t)n_channels;
    for (size_t i = 0; i < n; i++)
        if (!(fabsf(texels[i]) <= TS_MIPMAP_MAX_TEXEL)) {
            size_t px = i / (size_t)n_channels;
            return ts_error_set(err, TS_ERR_INVALID,
                                "texel (%zu, %zu) is %g, not a finite number within ±1e30",
                                px % (size_t)width, px / (size_t)width, (double)texels[i]);
        }
    size_t bytes = ts_mipmap_bytes_for(width, height, n_channels);
    if (max_bytes && bytes > max_bytes)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "the MIP map of a %d × %d image needs %zu bytes, more than the %zu left", width,
                            height, bytes, max_bytes);

    ts_mipmap *m = calloc(1, sizeof *m);
    float *block = malloc(bytes);
    if (!m || !block) {
        free(m), free(block);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for the MIP map of a %d × %d image", width,
                            height);
    }
    m->n_channels = n_channels;
    m->wrap = wrap;
    m->source_width = width, m->source_height = height;
    m->block = block;
    m->bytes = bytes;

    int32_t w2 = round_up_pow2(width), h2 = round_up_pow2(height);
    m->n_levels = 1 + log2_int(w2 > h2 ? w2 : h2);
    float *p = block;
    for (int i = 0; i < m->n_levels; i++) {
        int32_t lw = i == 0 ? w2 : (m->levels[i - 1].width / 2 > 1 ? m->levels[i - 1].width / 2 : 1);
        int32_t lh = i == 0 ? h2 : (m->levels[i - 1].height / 2 > 1 ? m->levels[i - 1].height / 2 : 1);
        m->levels[i] = (ts_mipmap_level){lw, lh, p};
        p += (size_t)lw * (size_t)lh * (size_t)n_channels;
    }

    float *l0 = block;
    if (w2 == width && h2 == height) {
        memcpy(l0, texels, n * sizeof(float));
    } else {
        ts_status st = resample(texels, width, height, n_channels, wrap, l0, w2, h2, err);
        if (st) {
            ts_mipmap_destroy(m);
            return st;
        }
    }
    for (int i = 1; i < m->n_levels; i++) {
        const ts_mipmap_level *fine = &m->levels[i - 1];
        float *o = (float *)m->levels[i].texels;
        for (int32_t t = 0; t < m->levels[i].height; ++t)
            for (int32_t s = 0; s < m->levels[i].width; ++s) {
                const float *a = texel_ptr(m, fine, 2 * s, 2 * t), *b = texel_ptr(m, fine, 2 * s + 1, 2 * t);
                const float *c = texel_ptr(m, fine, 2 * s, 2 * t + 1),
                            *d = texel_ptr(m, fine, 2 * s + 1, 2 * t + 1);
                float *v = o + ((size_t)t * (size_t)m->levels[i].width + (size_t)s) * (size_t)n_channels;
                for (int k = 0; k < n_channels; k++)
                    v[k] = 0.25f * (a[k] + b[k] + c[k] + d[k]);
            }
    }
    /* pbrt-v3's EWA weights: a Gaussian of r², α = 2, shifted to reach 0 at r = 1. */
    for (int i = 0; i < TS_MIPMAP_EWA_LUT_SIZE; ++i) {
        const float alpha = 2;
        float r2 = (float)i / (float)(TS_MIPMAP_EWA_LUT_SIZE - 1);
        m->ewa_weights[i] = expf(-alpha * r2) - expf(-alpha);
    }
    *out = m;
    return TS_OK;
}

void ts_mipmap_destroy(ts_mipmap *m)
{
    if (!m) return;
    free(m->block);
    free(m);
}
