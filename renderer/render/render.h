/* render.h — rendering a range of samples of a scene into a film with a pool of threads.
 *
 * Design note: the image is cut into square tiles, ordered from the centre outwards (so a
 * preview fills in where people look first). Worker threads take tiles from an atomic
 * counter; each pixel's samples are added in sample-index order by the one thread that
 * owns its tile, and every sample value depends only on (seed, pixel, index, dimension),
 * so the film is bit-identical whatever the thread count, tile order or the split of the
 * sample range into passes. Radiance that is NaN, infinite or negative is dropped and
 * counted, never added. The scene is only read. */
#ifndef TS_RENDER_H
#define TS_RENDER_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "film/film.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

#define TS_TILE_SIZE 32

/* The tile grid of a film window of w × h pixels whose top-left pixel is (x0, y0) in a
 * full_w × full_h image: TS_TILE_SIZE squares from the window's corner, the last column
 * and row cut to fit. The one grid of the renderer, the scheduler and the server. */
typedef struct ts_tile_rect { int tx, ty, x, y, w, h; } ts_tile_rect;

/* Tiles across and down a w × h window. */
void ts_tile_grid_size(int w, int h, int *nx, int *ny);
/* Tile (tx, ty) of the window (full-image pixels). */
ts_tile_rect ts_tile_grid_rect(int x0, int y0, int w, int h, int tx, int ty);
/* The grid's tile indices (ty · nx + tx) from the image centre outwards (distance² of a
 * tile's centre from the image centre, ties by row then column) into order[nx · ny]. */
void ts_tile_grid_order(int x0, int y0, int w, int h, int full_w, int full_h, int *order);

typedef struct ts_render_request {
    const ts_scene *scene;
    ts_integrator_type integrator; /* usually scene->integrator.type */
    ts_film *film;                 /* covers the scene's crop window */
    uint32_t sample_begin, sample_end; /* sample indices [begin, end) of every pixel */
    int threads;                   /* ≥ 1 */
    atomic_bool *cancel;           /* optional: set to stop early (tiles already started finish) */
    /* Optional, called by a worker after each finished tile (x, y, w, h in full-image
     * pixels); must be thread-safe and quick. */
    void (*on_tile)(void *user, int x, int y, int w, int h);
    void *user;
    /* true: simulate every effect whatever the scene calls for (the specialisation off;
     * same estimate, for tests and benchmarks). Job switches (job.effects) still apply. */
    bool generic;
    /* Optional: once set, ts_render_tile stops within one sample (the integrator checks it
     * at every bounce and light, ts_counters.stop) and returns false; the rectangle then
     * holds part of its samples and the caller must restore it (the scheduler does).
     * ts_render leaves such tiles as they are. */
    const atomic_bool *stop;
    /* Optional (adaptive sampling, render/adaptive.h): film->width · film->height bytes,
     * row-major over the film's window; pixels whose byte is 0 take no samples. NULL: all
     * pixels do. Read only. */
    const uint8_t *active;
} ts_render_request;

typedef struct ts_render_stats {
    ts_counters counters;
    double seconds;
    bool cancelled;
} ts_render_stats;

/* Renders the request; adds its counters to *stats (which the caller zeroes once). Fails
 * only when the tile list cannot be allocated (TS_ERR_NOMEM); when fewer worker threads
 * (or none) can be started, those started, or the calling thread, render every tile. */
ts_status ts_render(const ts_render_request *req, ts_render_stats *stats, ts_error *err);

/* Renders sample indices [req->sample_begin, req->sample_end) of every pixel of the
 * rectangle (x0, y0, w, h) (full-image pixels, inside the film's window) into req->film,
 * adding its counters to *c. The one tile loop: ts_render and the scheduler (scheduler.h)
 * both use it. Only req's scene, integrator, film, sample range and stop flag are read.
 * The caller must be the only writer of those pixels meanwhile. Returns false when
 * req->stop ended it early (the pixels are then partly rendered), else true. */
bool ts_render_tile(const ts_render_request *req, int x0, int y0, int w, int h, ts_counters *c);

/* Relative RMS error estimate of the film's image: sqrt(mean over pixels of
 * Var[Y] / (Y² + 1e-3)) on luminance Y, from the per-pixel sample variance (definition:
 * proto/error-estimate.md). */
double ts_film_relative_error(const ts_film *f);

/* One pixel's term of it: Var[Y] / (Y² + 1e-3), the relative variance of the pixel's mean
 * (0 with fewer than two effective samples). */
double ts_film_pixel_relative_variance(const ts_film *f, int x, int y);

/* Seconds on a monotonic clock. */
double ts_now_seconds(void);

#endif
