/* adaptive.c — the check points and the choice of active pixels; see adaptive.h. */
#include "render/adaptive.h"

#include <math.h>

#include "render/render.h"

uint32_t ts_adaptive_next_check(uint32_t n)
{
    if (n < TS_ADAPTIVE_MIN_SPP) return TS_ADAPTIVE_MIN_SPP;
    /* Steps of a quarter of the octave n lies in: 2^(⌊log2 n⌋ − 2), at least 4. The grid is
     * the same from any n, since each octave [2^k, 2^(k+1)) from 16 on holds exactly the
     * multiples of its step. */
    uint32_t octave = 1;
    while (octave <= n / 2) octave *= 2; /* the largest power of two ≤ n */
    uint32_t step = octave / 4 < 4 ? 4 : octave / 4;
    uint64_t next = ((uint64_t)n / step + 1) * step;
    return next > UINT32_MAX ? UINT32_MAX : (uint32_t)next;
}

bool ts_adaptive_is_check(uint32_t n)
{
    return n >= TS_ADAPTIVE_MIN_SPP && ts_adaptive_next_check(n - 1) == n;
}

/* The mean of scratch over the 3×3 neighbourhood of (x, y) inside the w × h window. */
static double pooled(const float *v, int w, int h, int x, int y)
{
    double sum = 0;
    int n = 0;
    for (int yy = y - 1; yy <= y + 1; yy++)
        for (int xx = x - 1; xx <= x + 1; xx++)
            if (xx >= 0 && yy >= 0 && xx < w && yy < h) sum += v[(size_t)yy * w + xx], n++;
    return sum / n;
}

enum { WAS_ACTIVE = 1, NEEDS = 2, STAYS = 4 };

size_t ts_adaptive_select(const ts_film *film, double target, uint8_t *active, float *scratch)
{
    const int w = film->width, h = film->height;
    /* v_p: the relative variance of one sample, r_p · n_p (0 where a pixel has fewer than
     * two samples: it stays active, below). */
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const ts_film_pixel *p = &film->pixels[(size_t)y * w + x];
            double r = ts_film_pixel_relative_variance(film, film->x0 + x, film->y0 + y);
            scratch[(size_t)y * w + x] = p->count >= 2 ? (float)(r * (double)p->count) : 0.0f;
        }
    double sum_sqrt = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) sum_sqrt += sqrt(pooled(scratch, w, h, x, y));
    double k = sum_sqrt / ((double)w * h) / (target * target);
    /* Which active pixels hold fewer samples than their share n* = K·√v. */
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            active[i] = active[i] ? WAS_ACTIVE : 0;
            uint64_t n = film->pixels[i].count;
            if (active[i] && (n < 2 || (double)n < k * sqrt(pooled(scratch, w, h, x, y)))) active[i] |= NEEDS;
        }
    /* Dilated by one pixel, within the pixels active until now. */
    size_t stays = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            if (!(active[i] & WAS_ACTIVE)) continue;
            bool near = false;
            for (int yy = y - 1; yy <= y + 1 && !near; yy++)
                for (int xx = x - 1; xx <= x + 1 && !near; xx++)
                    near = xx >= 0 && yy >= 0 && xx < w && yy < h && (active[(size_t)yy * w + xx] & NEEDS);
            if (near) active[i] |= STAYS, stays++;
        }
    /* None would stay: keep the set as it was, so the render goes on to its halting bounds. */
    for (size_t i = 0; i < (size_t)w * h; i++)
        active[i] = stays ? (active[i] & STAYS) != 0 : (active[i] & WAS_ACTIVE) != 0;
    if (stays) return stays;
    size_t n = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) n += active[i];
    return n;
}
