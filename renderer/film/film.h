/* film.h — per-pixel accumulation of weighted radiance samples.
 *
 * Design note: with filter importance sampling (filter.h) every sample belongs to exactly
 * one pixel, so a pixel keeps running sums — Σ w·L, Σ w·L², Σ w, Σ w² and a count — and
 * its value is Σ w·L / Σ w. Sums are doubles: a float product w·L has at most 48
 * significant bits, so Σ w·L and Σ w of up to 2^29 samples of a constant (float) L and w
 * are exact, and in general the relative rounding error grows like √n·2^-53.
 *
 * A film covers a crop window (x0, y0, width, height) of the full image; coordinates
 * passed in are full-image pixels. Memory is one heap block owned by the film.
 *
 * Threads: the film holds no lock. Each pixel belongs to one writer at a time (the
 * renderer gives a tile to one thread, which adds its samples in sample-index order, so
 * sums are deterministic). Different pixels may be written concurrently by different
 * threads. Readers (ts_film_pixel_rgb, _variance, _resolve, _merge's src) must not run
 * concurrently with a writer of the pixels they read. */
#ifndef TS_FILM_H
#define TS_FILM_H

#include <stdint.h>

#include "core/error.h"
#include "core/vecmath.h"

typedef struct ts_film_pixel {
    double sum[3];    /* Σ w·L */
    double sum_sq[3]; /* Σ w·L² (second moment) */
    double weight;    /* Σ w */
    double weight_sq; /* Σ w² (effective sample count (Σw)²/Σw²) */
    uint64_t count;   /* samples added */
} ts_film_pixel;

typedef struct ts_film {
    int full_width, full_height; /* the whole image the camera sees */
    int x0, y0, width, height;   /* the pixels this film holds (crop window) */
    ts_film_pixel *pixels;       /* (x-x0) + (y-y0)*width; owned */
    /* The output factor of every pixel value (pbrt-v3's Film "scale", the scene's
     * film_scale): ts_film_pixel_rgb and _resolve multiply by it, _variance by its square.
     * It is never in the sums, so merges and shards stay exact; 1 at create. */
    float scale;
} ts_film;

/* A zeroed film for the window [x0, x0+width) × [y0, y0+height), which must lie inside the
 * full_width × full_height image and be non-empty. NULL with err filled (TS_ERR_INVALID
 * for a bad window, TS_ERR_NOMEM) on failure. Free with ts_film_destroy. */
ts_film *ts_film_create(int full_width, int full_height, int x0, int y0, int width, int height,
                        ts_error *err);
void ts_film_destroy(ts_film *f); /* NULL is fine */

/* True when full-image pixel (x, y) lies in the film's window. */
static inline int ts_film_contains(const ts_film *f, int x, int y)
{
    return x >= f->x0 && y >= f->y0 && x - f->x0 < f->width && y - f->y0 < f->height;
}

/* The accumulator of full-image pixel (x, y), or NULL outside the window. */
static inline ts_film_pixel *ts_film_pixel_at(const ts_film *f, int x, int y)
{
    if (!ts_film_contains(f, x, y)) return 0;
    return &f->pixels[(size_t)(x - f->x0) + (size_t)(y - f->y0) * (size_t)f->width];
}

/* The largest sample component the film takes: its square, which the pixel's variance
 * (R.var …, written as a float) is made of, must fit a float (√FLT_MAX ≈ 1.84e19).
 * Larger samples are dropped and counted with the non-finite ones (docs/design.md §6). */
#define TS_FILM_SAMPLE_MAX 1.8e19f

/* pbrt-v3's ImageFilm clamp ("maxsampleluminance"): L scaled so that its luminance (pbrt-v3's
 * weights 0.212671, 0.715160, 0.072169) is at most max_luminance; a sample is clamped before
 * its filter weight is applied. INFINITY: L as it is. */
static inline ts_rgb ts_film_clamp_luminance(ts_rgb L, float max_luminance)
{
    float y = 0.212671f * L.r + 0.715160f * L.g + 0.072169f * L.b;
    if (!(y > max_luminance)) return L;
    float k = max_luminance / y;
    return (ts_rgb){L.r * k, L.g * k, L.b * k};
}

/* Adds radiance L with filter weight `weight` to full-image pixel (x, y). Samples outside
 * the window are ignored. L and weight must be finite: the integrator rejects (and
 * counts) NaN/Inf before they reach the film (docs/design.md §6). Hot path: no allocation,
 * no lock; one writer per pixel (see above). */
static inline void ts_film_add_sample(ts_film *f, int x, int y, ts_rgb L, float weight)
{
    ts_film_pixel *p = ts_film_pixel_at(f, x, y);
    if (!p) return;
    double w = weight, l[3] = {L.r, L.g, L.b};
    for (int c = 0; c < 3; c++) {
        double wl = w * l[c]; /* exact: a product of two floats fits in a double */
        p->sum[c] += wl;
        p->sum_sq[c] += wl * l[c];
    }
    p->weight += w;
    p->weight_sq += w * w;
    p->count++;
}

/* scale · Σ w·L / Σ w of full-image pixel (x, y); 0 with no weight or outside the window. */
ts_rgb ts_film_pixel_rgb(const ts_film *f, int x, int y);

/* Estimated variance of that pixel's mean, per channel: scale² · s² / (n_eff − 1), where
 * s² = Σ w·L²/Σ w − mean² is the weighted sample variance and n_eff = (Σw)²/Σw². For
 * equal weights this is the usual unbiased s²/n of a mean of n samples; with unequal
 * weights it is unbiased when L is independent of w (exact for the box and triangle
 * filters, whose weights are 1, and an approximation for gaussian/mitchell). 0 when
 * n_eff <= 1 (fewer than two effective samples: unknown) or outside the window. */
ts_rgb ts_film_pixel_variance(const ts_film *f, int x, int y);

/* Writes the window's pixel values (scaled), 3·width·height floats, row-major RGB. */
void ts_film_resolve(const ts_film *f, float *rgb);

/* Adds src's sums to dst for every pixel in both windows (normally the same window); dst's
 * scale stays.
 * Sums in double are associative only up to rounding, so merging two halves equals one
 * film with all samples to about 2^-53 relative, not bit for bit. */
void ts_film_merge(ts_film *dst, const ts_film *src);

/* Zeroes every accumulator. */
void ts_film_clear(ts_film *f);

#endif
