/* envmap.c — lat-long environment maps (see envmap.h).
 *
 * Bound on L/pdf: the sampling weight of texel (i,j) is M_ij·sinθ_j, where M_ij is at
 * least the largest channel average the filtered lookup reaches inside the texel and θ_j
 * is the texel centre. With I the mean weight, the pdf inside the texel is
 * M_ij sinθ_j / (I · 2π² sinθ), so avg(L)/pdf ≤ 2π² I · sinθ/sinθ_j ≤ 4π² I, because
 * sinθ ≤ 2 sinθ_j within any texel row (the polar rows are the worst case). */
#include "lights/envmap.h"

#include <stdlib.h>
#include <string.h>

#include "image/exr.h"
#include "image/image.h"

static float texel_value(ts_rgb c) { return (c.r + c.g + c.b) * (1.0f / 3.0f); }

static ts_rgb texel(const ts_envmap *m, int64_t i, int64_t j)
{
    int64_t w = m->width;
    i %= w;
    if (i < 0) i += w;
    if (j < 0) j = 0;
    if (j >= (int64_t)m->height) j = m->height - 1;
    return m->texels[(size_t)j * m->width + (size_t)i].c;
}

static ts_rgb rgb_lerp(float t, ts_rgb a, ts_rgb b)
{
    return (ts_rgb){ts_lerpf(t, a.r, b.r), ts_lerpf(t, a.g, b.g), ts_lerpf(t, a.b, b.b)};
}

/* Row j (in [0, height)) interpolated linearly in x (texel-centre coordinates), wrapping
 * in φ: texel(m, i0, j) and texel(m, i0 + 1, j), their columns wrapped without a
 * division where x is in [−1, width) (every lookup's: x = u·width − ½ with u in [0,1)). */
static ts_rgb row_lookup(const ts_envmap *m, int64_t j, double x)
{
    double x0 = floor(x);
    float fx = (float)(x - x0);
    int64_t w = m->width, i0 = (int64_t)x0;
    if (i0 < 0 || i0 >= w) {
        i0 %= w;
        if (i0 < 0) i0 += w;
    }
    int64_t i1 = i0 + 1 < w ? i0 + 1 : 0;
    const ts_envmap_texel *row = m->texels + (size_t)j * m->width;
    return rgb_lerp(fx, row[i0].c, row[i1].c);
}

ts_rgb ts_envmap_lookup_uv(const ts_envmap *m, ts_vec2 uv)
{
    double u = uv.x - floor(uv.x);
    double v = ts_clampf(uv.y, 0.0f, 1.0f);
    double x = u * m->width - 0.5, y = v * m->height - 0.5;
    int64_t h = m->height;
    if (y < 0) /* between the north pole and the first row's centres */
        return rgb_lerp((float)(2 * v * h), m->pole_mean[0], row_lookup(m, 0, x));
    if (y > h - 1) /* between the last row's centres and the south pole */
        return rgb_lerp((float)(2 * (1 - v) * h), m->pole_mean[1], row_lookup(m, h - 1, x));
    double y0 = floor(y);
    int64_t j0 = (int64_t)y0;
    int64_t j1 = j0 + 1 < h ? j0 + 1 : h - 1;
    return rgb_lerp((float)(y - y0), row_lookup(m, j0, x), row_lookup(m, j1, x));
}

ts_vec2 ts_envmap_dir_to_uv(ts_vec3 w)
{
    double x = w.x, y = w.y, z = w.z;
    double theta = atan2(sqrt(x * x + y * y), z);
    double phi = atan2(y, x);
    if (phi < 0) phi += 2 * TS_PI_D;
    float u = (float)(phi / (2 * TS_PI_D)), v = (float)(theta / TS_PI_D);
    return (ts_vec2){u < 1.0f ? u : 0.0f, ts_clampf(v, 0.0f, 1.0f)};
}

ts_vec3 ts_envmap_uv_to_dir(ts_vec2 uv)
{
    double theta = uv.y * TS_PI_D, phi = uv.x * 2 * TS_PI_D;
    double st = sin(theta);
    return (ts_vec3){(float)(st * cos(phi)), (float)(st * sin(phi)), (float)cos(theta)};
}

ts_rgb ts_envmap_lookup(const ts_envmap *m, ts_vec3 w) { return ts_envmap_lookup_uv(m, ts_envmap_dir_to_uv(w)); }

/* uv_out: the sampled (u, v) (set when true is returned). */
static bool sample_uv(const ts_envmap *m, ts_vec2 u, ts_vec3 *w, float *pdf, ts_vec2 *uv_out)
{
    *pdf = 0;
    if (!(ts_distribution2d_integral(&m->distrib) > 0)) return false;
    uint32_t iu, iv;
    ts_vec2 uv = ts_distribution2d_sample_cell(&m->distrib, u, &iu, &iv);
    float pdf_uv = ts_distribution2d_pdf_cell(&m->distrib, iv, m->texels[(size_t)iv * m->width + iu].weight);
    double theta = uv.y * TS_PI_D, phi = uv.x * 2 * TS_PI_D;
    double st = sin(theta);
    if (!(st > 0) || !(pdf_uv > 0)) return false;
    *w = (ts_vec3){(float)(st * cos(phi)), (float)(st * sin(phi)), (float)cos(theta)};
    double p = pdf_uv / (2 * TS_PI_D * TS_PI_D * st);
    if (!(p < FLT_MAX)) return false;
    *pdf = (float)p;
    *uv_out = uv;
    return true;
}

bool ts_envmap_sample(const ts_envmap *m, ts_vec2 u, ts_vec3 *w, float *pdf)
{
    ts_vec2 uv;
    return sample_uv(m, u, w, pdf, &uv);
}

bool ts_envmap_sample_li(const ts_envmap *m, ts_vec2 u, ts_vec3 *w, float *pdf, ts_rgb *L)
{
    ts_vec2 uv;
    *L = ts_rgb_gray(0);
    if (!sample_uv(m, u, w, pdf, &uv)) return false;
    *L = ts_envmap_lookup_uv(m, uv);
    return true;
}

/* ts_envmap_pdf of w, whose lat-long coordinates are uv. */
static float pdf_at(const ts_envmap *m, ts_vec3 w, ts_vec2 uv)
{
    if (!(ts_distribution2d_integral(&m->distrib) > 0)) return 0;
    double st = sqrt((double)w.x * w.x + (double)w.y * w.y);
    if (!(st > 0)) return 0;
    double len = sqrt(st * st + (double)w.z * w.z);
    st /= len;
    uint32_t iu, iv;
    if (!ts_distribution2d_cell(&m->distrib, uv, &iu, &iv)) return 0;
    float pdf_uv = ts_distribution2d_pdf_cell(&m->distrib, iv, m->texels[(size_t)iv * m->width + iu].weight);
    double p = pdf_uv / (2 * TS_PI_D * TS_PI_D * st);
    return p < FLT_MAX ? (float)p : 0.0f;
}

float ts_envmap_pdf(const ts_envmap *m, ts_vec3 w) { return pdf_at(m, w, ts_envmap_dir_to_uv(w)); }

void ts_envmap_query_begin(const ts_envmap *m, ts_vec3 w, ts_envmap_query *q)
{
    q->w = w;
    q->uv = ts_envmap_dir_to_uv(w);
    /* The texel of the pdf's cell and its row neighbour towards (u, v), which with the
     * column neighbours in their cache lines are what the bilinear lookup reads. Only a
     * hint: nothing depends on it but the time. */
    float x = q->uv.x * m->width, y = q->uv.y * m->height;
    uint32_t i = x < m->width ? (uint32_t)x : m->width - 1, j = y < m->height ? (uint32_t)y : m->height - 1;
    uint32_t j2 = y - j >= 0.5f ? (j + 1 < m->height ? j + 1 : j) : (j > 0 ? j - 1 : j);
    __builtin_prefetch(m->texels + (size_t)j * m->width + i);
    __builtin_prefetch(m->texels + (size_t)j2 * m->width + i);
}

ts_rgb ts_envmap_query_lookup_pdf(const ts_envmap *m, const ts_envmap_query *q, float *pdf)
{
    *pdf = pdf_at(m, q->w, q->uv);
    return ts_envmap_lookup_uv(m, q->uv);
}

ts_rgb ts_envmap_lookup_pdf(const ts_envmap *m, ts_vec3 w, float *pdf)
{
    ts_envmap_query q;
    ts_envmap_query_begin(m, w, &q);
    return ts_envmap_query_lookup_pdf(m, &q, pdf);
}

ts_status ts_envmap_create(const ts_rgb *texels, uint32_t width, uint32_t height, ts_envmap **out, ts_error *err)
{
    *out = NULL;
    if (width == 0 || height == 0 || (uint64_t)width * height > ((uint64_t)1 << 28))
        return ts_error_set(err, TS_ERR_INVALID, "environment map: bad size %u×%u", width, height);
    ts_envmap *m = calloc(1, sizeof *m);
    if (!m) return ts_error_set(err, TS_ERR_NOMEM, "environment map: out of memory");
    ts_arena_init(&m->arena, 0);
    ts_status st = TS_OK;
    size_t n = (size_t)width * height;
    ts_envmap_texel *tx = ts_arena_calloc(&m->arena, n, sizeof *tx);
    float *weight = malloc(n * sizeof *weight);
    if (!tx || !weight) {
        st = ts_error_set(err, TS_ERR_NOMEM, "environment map: out of memory for %u×%u texels", width, height);
        goto fail;
    }
    for (size_t k = 0; k < n; k++) {
        ts_rgb c = texels[k];
        if (!ts_rgb_is_finite(c) || c.r < 0 || c.g < 0 || c.b < 0) {
            st = ts_error_set(err, TS_ERR_INVALID,
                              "environment map: texel (%zu, %zu) is (%g, %g, %g), expected finite values ≥ 0",
                              k % width, k / width, c.r, c.g, c.b);
            goto fail;
        }
        tx[k].c = c;
    }
    m->width = width;
    m->height = height;
    m->texels = tx;
    /* Pole means and the solid-angle-weighted mean radiance, in double. */
    double pole[2][3] = {{0}}, mean[3] = {0};
    for (uint32_t j = 0; j < height; j++) {
        double d_omega = (2 * TS_PI_D / width) * (cos(j * TS_PI_D / height) - cos((j + 1) * TS_PI_D / height));
        for (uint32_t i = 0; i < width; i++) {
            ts_rgb c = tx[(size_t)j * width + i].c;
            mean[0] += c.r * d_omega, mean[1] += c.g * d_omega, mean[2] += c.b * d_omega;
            if (j == 0) pole[0][0] += c.r, pole[0][1] += c.g, pole[0][2] += c.b;
            if (j == height - 1) pole[1][0] += c.r, pole[1][1] += c.g, pole[1][2] += c.b;
        }
    }
    for (int k = 0; k < 2; k++)
        m->pole_mean[k] = (ts_rgb){(float)(pole[k][0] / width), (float)(pole[k][1] / width), (float)(pole[k][2] / width)};
    m->mean_radiance = (ts_rgb){(float)(mean[0] / (4 * TS_PI_D)), (float)(mean[1] / (4 * TS_PI_D)),
                                (float)(mean[2] / (4 * TS_PI_D))};
    /* Sampling weights: the largest value the bilinear lookup can take in the texel — it
     * is a convex combination of the 3×3 neighbourhood (and of the pole mean at the end
     * rows) — times sinθ at the texel centre. */
    for (uint32_t j = 0; j < height; j++) {
        double s = sin((j + 0.5) * TS_PI_D / height);
        for (uint32_t i = 0; i < width; i++) {
            float mx = 0;
            for (int dj = -1; dj <= 1; dj++)
                for (int di = -1; di <= 1; di++) mx = ts_maxf(mx, texel_value(texel(m, (int64_t)i + di, (int64_t)j + dj)));
            if (j == 0) mx = ts_maxf(mx, texel_value(m->pole_mean[0]));
            if (j == height - 1) mx = ts_maxf(mx, texel_value(m->pole_mean[1]));
            /* ≥ 0, so it is the distribution's |f| of the cell too */
            weight[(size_t)j * width + i] = tx[(size_t)j * width + i].weight = (float)(mx * s);
        }
    }
    st = ts_distribution2d_init(&m->distrib, weight, width, height, &m->arena, err);
    if (st) goto fail;
    free(weight);
    *out = m;
    return TS_OK;
fail:
    free(weight);
    ts_arena_fini(&m->arena);
    free(m);
    return st;
}

ts_status ts_envmap_from_image(const ts_image *img, const char *name, ts_envmap **out, ts_error *err)
{
    *out = NULL;
    int ch[3] = {ts_image_channel(img, "R"), ts_image_channel(img, "G"), ts_image_channel(img, "B")};
    if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s: environment map needs channels R, G and B", name);
    size_t n = (size_t)img->width * (size_t)img->height;
    ts_rgb *tx = malloc(n * sizeof *tx);
    if (!tx)
        return ts_error_set(err, TS_ERR_NOMEM, "%s: out of memory for %d×%d texels", name, img->width, img->height);
    for (size_t k = 0; k < n; k++) {
        const float *px = img->data + k * (size_t)img->n_channels;
        tx[k] = (ts_rgb){px[ch[0]], px[ch[1]], px[ch[2]]};
    }
    ts_status st = ts_envmap_create(tx, (uint32_t)img->width, (uint32_t)img->height, out, err);
    if (st) ts_error_prefix(err, "%s", name);
    free(tx);
    return st;
}

ts_status ts_envmap_load(const char *path, ts_envmap **out, ts_error *err)
{
    *out = NULL;
    ts_image img = {0};
    ts_status st = ts_exr_read(path, &img, err);
    if (st) return st;
    st = ts_envmap_from_image(&img, path, out, err);
    ts_image_fini(&img);
    return st;
}

void ts_envmap_destroy(ts_envmap *m)
{
    if (!m) return;
    ts_arena_fini(&m->arena);
    free(m);
}
