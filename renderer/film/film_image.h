/* film_image.h — a film's accumulated state as an image for the encoders, and back.
 *
 * Design note: the CLI, the server and the farm nodes all turn films into EXR/PNG, so the
 * channel layout lives here, once. TS_FILM_IMAGE_RGB gives the resolved colour (Σw·L/Σw);
 * TS_FILM_IMAGE_STATS adds what a user computing with the image wants: per-pixel variance
 * of the mean ("R.var", "G.var", "B.var") and sample count ("count"). Pixels are the
 * film's crop window. Metadata is the caller's. Thread-safety: reads the film without
 * locking; the caller guarantees no worker writes it meanwhile (or uses a snapshot).
 *
 * TS_FILM_IMAGE_SHARD carries the film's raw sums so films can be rebuilt and merged
 * (farm shards, checkpoints; normative description: proto/shard-exr.md). EXR pixels are
 * 32-bit floats and an image holds at most 16 channels, so the nine per-pixel sums are
 * split across exactly 16 float channels:
 *
 *   R, G, B              the resolved colour m = Σw·L / Σw (viewable as it is); it is also
 *                        the high part of Σw·L: Σw·L = (double)m · W + lo
 *   sum.R.lo …           lo = Σw·L − (double)m · W, rounded to float
 *   sq.R.hi, sq.R.lo …   Σw·L² as an unevaluated float pair hi + lo (hi = (float)x,
 *                        lo = (float)(x − hi))
 *   weight.hi, weight.lo Σw as a float pair; W above is (double)hi + (double)lo
 *   weight_sq            Σw² rounded to float (it only feeds the variance estimate)
 *   count                the sample count (exact: counts above 2^24 are refused)
 *
 * A pixel with W = 0 (no samples, or filter weights of both signs cancelling) stores its
 * Σw·L as the pair (R, sum.lo) instead. Round trip: Σw·L, Σw·L² and Σw come back with a
 * relative error below 2^-47 (two float roundings of the residual plus one double
 * addition; a pair loses at most the last bit when lo is subnormal), Σw² below 2^-24,
 * count exactly. Values outside float range (|x| > 3.4e38) cannot be stored: such a film
 * is refused with TS_ERR_LIMIT. */
#ifndef TS_FILM_IMAGE_H
#define TS_FILM_IMAGE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "film/film.h"
#include "image/image.h"

typedef enum ts_film_image_layout {
    TS_FILM_IMAGE_RGB,   /* R, G, B */
    TS_FILM_IMAGE_STATS, /* R, G, B, R.var, G.var, B.var, count */
    TS_FILM_IMAGE_SHARD, /* the 16 channels above: raw sums, mergeable */
} ts_film_image_layout;

/* Fills img (initialised here; the caller finis it). TS_ERR_LIMIT for a SHARD image of a
 * film whose sums leave float range or whose count exceeds 2^24 (the sentence names the
 * pixel). */
ts_status ts_film_to_image(const ts_film *f, ts_film_image_layout layout, ts_image *img, ts_error *err);

/* True when img has every channel of the SHARD layout. */
bool ts_film_image_is_shard(const ts_image *img);

/* Rebuilds a film from a SHARD image: a new film of img's size for the window (x0, y0) of
 * a full_width × full_height image (NULL with err filled if the window does not fit, a
 * channel is missing — TS_ERR_INVALID naming it — or memory runs out). Counts must be
 * whole non-negative numbers. Free with ts_film_destroy. */
ts_film *ts_film_from_image(const ts_image *img, int full_width, int full_height, int x0, int y0, ts_error *err);

/* What a rendered image says about its render (EXR attributes): the one description that
 * `tessera render` and the server's image answers both write. */
typedef struct ts_render_info {
    const char *scene;          /* scene name ("scene" when NULL or empty) */
    const char *integrator;     /* integrator name */
    uint32_t spp;               /* samples per pixel the image holds */
    bool has_seed;
    uint32_t seed;
    double render_time_s;
    double error_estimate;      /* < 0: not written (a tile) */
    double nonfinite_samples;   /* samples dropped for NaN/∞/negative radiance */
    const char *job;            /* job id, or NULL */
    double film_scale;          /* the output factor the pixels carry (film.h); 0: not written */
    /* A scene with media (the media effect): volpath's tracking steps and walks cut short
     * (integrators/counters.h); not written when false. */
    bool media;
    double medium_steps, walks_truncated;
} ts_render_info;

/* Sets software ("tessera VERSION"), tessera_scene, tessera_integrator, tessera_spp,
 * tessera_seed, tessera_render_time_s, tessera_error_estimate, tessera_nonfinite_samples,
 * tessera_job, tessera_film_scale and, for media, tessera_medium_steps and
 * tessera_walks_truncated on img. */
ts_status ts_image_set_render_info(ts_image *img, const ts_render_info *info, ts_error *err);

#endif
