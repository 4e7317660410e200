/* film.c — film allocation, pixel estimates and merging; see film.h. */
#include "film/film.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

ts_film *ts_film_create(int full_width, int full_height, int x0, int y0, int width, int height, ts_error *err)
{
    if (full_width <= 0 || full_height <= 0) {
        ts_error_set(err, TS_ERR_INVALID, "film: expected a positive image size, got %d x %d", full_width,
                     full_height);
        return NULL;
    }
    if (width <= 0 || height <= 0 || x0 < 0 || y0 < 0 || x0 > full_width - width ||
        y0 > full_height - height) {
        ts_error_set(err, TS_ERR_INVALID,
                     "film: crop window %d x %d at (%d, %d) is empty or outside the %d x %d image", width,
                     height, x0, y0, full_width, full_height);
        return NULL;
    }
    size_t n = (size_t)width * (size_t)height;
    if (n > SIZE_MAX / sizeof(ts_film_pixel)) {
        ts_error_set(err, TS_ERR_LIMIT, "film: %d x %d pixels do not fit in memory", width, height);
        return NULL;
    }
    ts_film *f = malloc(sizeof *f);
    if (!f) goto fail_film;
    f->pixels = calloc(n, sizeof(ts_film_pixel));
    if (!f->pixels) goto fail_pixels;
    f->full_width = full_width;
    f->full_height = full_height;
    f->x0 = x0;
    f->y0 = y0;
    f->width = width;
    f->height = height;
    f->scale = 1;
    return f;

fail_pixels:
    free(f);
fail_film:
    ts_error_set(err, TS_ERR_NOMEM, "film: out of memory for %d x %d pixels", width, height);
    return NULL;
}

void ts_film_destroy(ts_film *f)
{
    if (!f) return;
    free(f->pixels);
    free(f);
}

/* v as a float, held to ±FLT_MAX: a large film scale (or a tiny filter weight sum) cannot
 * make a pixel value infinite; values in range are converted as they are. */
static float finite_float(double v) { return (float)(v > FLT_MAX ? FLT_MAX : (v < -FLT_MAX ? -FLT_MAX : v)); }

static ts_rgb pixel_mean(const ts_film_pixel *p, float scale)
{
    if (p->weight == 0) return (ts_rgb){0, 0, 0};
    double inv = scale / p->weight;
    return (ts_rgb){finite_float(p->sum[0] * inv), finite_float(p->sum[1] * inv), finite_float(p->sum[2] * inv)};
}

ts_rgb ts_film_pixel_rgb(const ts_film *f, int x, int y)
{
    const ts_film_pixel *p = ts_film_pixel_at(f, x, y);
    return p ? pixel_mean(p, f->scale) : (ts_rgb){0, 0, 0};
}

ts_rgb ts_film_pixel_variance(const ts_film *f, int x, int y)
{
    const ts_film_pixel *p = ts_film_pixel_at(f, x, y);
    if (!p || p->weight == 0 || p->weight_sq == 0) return (ts_rgb){0, 0, 0};
    double n_eff = p->weight * p->weight / p->weight_sq;
    if (!(n_eff > 1)) return (ts_rgb){0, 0, 0};
    double v[3];
    for (int c = 0; c < 3; c++) {
        double mean = p->sum[c] / p->weight;
        /* (Σ w·L² − mean·Σ w·L)/Σ w: the weighted sample variance, clamped against
         * cancellation (it is exactly 0 for a constant only up to rounding). */
        double s2 = (p->sum_sq[c] - mean * p->sum[c]) / p->weight;
        v[c] = s2 > 0 ? (double)f->scale * f->scale * s2 / (n_eff - 1) : 0;
        /* Samples are at most TS_FILM_SAMPLE_MAX, so s2 fits a float; n_eff − 1 below 1
         * (negative filter weights) or a scale above 1 could still lift it beyond: the
         * largest float then. */
        if (!(v[c] <= FLT_MAX)) v[c] = FLT_MAX;
    }
    return (ts_rgb){(float)v[0], (float)v[1], (float)v[2]};
}

void ts_film_resolve(const ts_film *f, float *rgb)
{
    size_t n = (size_t)f->width * (size_t)f->height;
    for (size_t i = 0; i < n; i++) {
        ts_rgb m = pixel_mean(&f->pixels[i], f->scale);
        rgb[3 * i + 0] = m.r;
        rgb[3 * i + 1] = m.g;
        rgb[3 * i + 2] = m.b;
    }
}

void ts_film_merge(ts_film *dst, const ts_film *src)
{
    int xa = dst->x0 > src->x0 ? dst->x0 : src->x0, ya = dst->y0 > src->y0 ? dst->y0 : src->y0;
    int xb = dst->x0 + dst->width < src->x0 + src->width ? dst->x0 + dst->width : src->x0 + src->width;
    int yb = dst->y0 + dst->height < src->y0 + src->height ? dst->y0 + dst->height : src->y0 + src->height;
    for (int y = ya; y < yb; y++)
        for (int x = xa; x < xb; x++) {
            ts_film_pixel *d = ts_film_pixel_at(dst, x, y);
            const ts_film_pixel *s = ts_film_pixel_at(src, x, y);
            for (int c = 0; c < 3; c++) {
                d->sum[c] += s->sum[c];
                d->sum_sq[c] += s->sum_sq[c];
            }
            d->weight += s->weight;
            d->weight_sq += s->weight_sq;
            d->count += s->count;
        }
}

void ts_film_clear(ts_film *f)
{
    memset(f->pixels, 0, (size_t)f->width * (size_t)f->height * sizeof(ts_film_pixel));
}
