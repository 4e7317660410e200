/* adaptive.h — adaptive sampling: which pixels still take samples (docs/design.md §8,
 * "Adaptive sampling").
 *
 * Design note: an adaptive job renders its first TS_ADAPTIVE_MIN_SPP samples in every
 * pixel, as any job. From then on it checks at fixed sample counts, the check points
 * (TS_ADAPTIVE_MIN_SPP, then steps of a quarter of an octave: 16, 20, 24, 28, 32, 40, 48,
 * …); at each one the scheduler chooses, from the whole film, the pixels that go on to the
 * next check point, and the others keep the samples they hold. A pixel once stopped stays
 * stopped, so every pixel holds the samples 0 … n−1 of its own sequence, its count n is a
 * check point (or the cap), and its value is the mean of its own samples (film.h).
 *
 * The choice minimises the cost of reaching the target of the film's error estimate
 * E = sqrt(mean over pixels of r_p) (proto/error-estimate.md), r_p the relative variance of
 * pixel p's mean. With v_p = r_p · n_p the relative variance of one sample and n_p the
 * pixel's count, n_p samples give r_p = v_p / n_p; the fewest samples that make
 * mean(v_p / n_p) = t² are n*_p = K · √v_p with K = mean(√v) / t² (a Lagrange multiplier:
 * samples go as the square root of the variance, not as the variance, which equalising the
 * per-pixel errors would do at the cost of a uniform render). A pixel stays active while
 * n_p < n*_p. v_p is the mean over the pixel's 3×3 neighbourhood (a steadier estimate than
 * one pixel's, and less tied to that pixel's own samples), and the active set is dilated by
 * one pixel (a pixel next to an active one stays active, as Cycles does), both within the
 * set active until now. When no pixel would stay active the set is kept as it was: the
 * render never stalls short of its halting bounds.
 *
 * Determinism: the choice is a function of the film at a check point alone, computed by
 * one thread in a fixed order, and it is made only at check points (a pass may end between
 * them: a checkpoint interval, a time limit), so the pixels are bit-identical whatever the
 * thread count, tile order or split into passes. */
#ifndef TS_ADAPTIVE_H
#define TS_ADAPTIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "film/film.h"

/* Samples every pixel takes before the first check. */
#define TS_ADAPTIVE_MIN_SPP 16
/* The per-pixel share's target when the job has no target error (Cycles' default noise
 * threshold); such a job still halts only on its spp cap or time limit. */
#define TS_ADAPTIVE_DEFAULT_ERROR 0.01

/* The first check point above n. */
uint32_t ts_adaptive_next_check(uint32_t n);
/* Whether n is a check point. */
bool ts_adaptive_is_check(uint32_t n);

/* Chooses the pixels that take samples until the next check point: active holds
 * film->width · film->height bytes (row-major over the film's window), 1 for the pixels
 * active until now; on return 1 for those that stay active (a subset). target: the error
 * the render aims at (> 0). scratch: film->width · film->height floats, overwritten.
 * Returns the number of pixels active on return. Pure; reads the film only. */
size_t ts_adaptive_select(const ts_film *film, double target, uint8_t *active, float *scratch);

#endif
