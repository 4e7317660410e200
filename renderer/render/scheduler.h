/* scheduler.h — one persistent render pool shared by every job, with progressive passes.
 *
 * Design note: a scheduler owns N worker threads, created once. Jobs are submitted with a
 * scene (whose ownership passes to the job) and halt conditions. The film of a job is cut
 * into TS_TILE_SIZE tiles (the grid of render.h), ordered from the image centre outwards.
 * A job renders in passes: the pass ends are 1, 2, 4, 8, … spp (passes of 1, 1, 2, 4, …
 * samples), capped at the target; every tile of a job reaches the end of pass k before any
 * tile starts pass k+1 (a barrier per job, never across jobs). The unit of work is one
 * tile of one pass, so jobs share the pool at tile granularity.
 *
 * Which jobs run: unfinished jobs are ordered by priority (higher first), then arrival.
 * The first `max_running` of them are active; a worker takes the next tile of the active
 * job that has had the fewest tiles so far (round robin, so active jobs share the pool
 * fairly). A job is "queued" until its first tile is taken.
 *
 * Snapshots: each tile's pixels are written only by the worker rendering it, in the job's
 * working film. After each tile pass the worker copies the tile into a new immutable,
 * reference-counted ts_tile_snapshot and publishes it; readers (HTTP, checkpoints) take
 * references to snapshots and never touch the working film, so they never stop workers.
 *
 * Passes and halting follow progressive.h, the one policy of every render: the spp target;
 * time_limit_s (rendering wall time; the last pass is shrunk to what the measured speed
 * says still fits, and a timer stops the tiles still rendering when the limit passes);
 * target_error (ts_film_relative_error, checked at pass ends from
 * TS_PROGRESSIVE_ERROR_MIN_SPP on; proto/error-estimate.md); cancellation (nothing new
 * starts, pixels of whole tile passes stay).
 *
 * Stopping inside a tile: cancellation, the time limit and ts_scheduler_stop take effect
 * within one sample, and the integrator checks at every bounce and light, so a stop takes
 * about one bounce's time whatever the scene. The tile pass that was interrupted is rolled
 * back to its last snapshot (its samples are neither published nor counted), so snapshots
 * and every film read from them hold whole tile passes; after a stop part-way through a
 * pass tiles may be one pass apart (each pixel's count says how many samples it holds).
 * A job may render a sample range that
 * starts past 0 (a farm shard): its tiles' sample counts are relative to sample_begin.
 * Samples of a pixel are added in index order by one thread, so a job's film is
 * bit-identical to ts_render of the same sample range.
 *
 * Threads: every function here is thread-safe. One mutex guards all scheduling state;
 * it is held only for bookkeeping, never while rendering, copying a film or calling back.
 * Workers wait on a condition variable when there is no work. Callbacks run on worker
 * threads (or the thread calling ts_sched_job_cancel) with no lock held; they must be
 * quick and must not call ts_scheduler_destroy. For one job, every on_tile call of a pass
 * returns before the pass's on_pass and the final on_done, and no tile of the next pass
 * starts before on_pass returns: during on_pass every tile holds exactly pass_end samples
 * (ts_sched_job_film then gives a consistent film, e.g. for a checkpoint). */
#ifndef TS_SCHEDULER_H
#define TS_SCHEDULER_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "film/film.h"
#include "integrators/integrator.h"
#include "render/progressive.h"
#include "render/render.h"
#include "scene/scene.h"

typedef struct ts_scheduler ts_scheduler;
typedef struct ts_sched_job ts_sched_job;

typedef enum ts_job_state {
    TS_JOB_QUEUED,
    TS_JOB_RUNNING,
    TS_JOB_DONE,
    TS_JOB_CANCELLED,
    TS_JOB_FAILED,
} ts_job_state;

/* "queued", "running", "done", "cancelled", "failed". */
const char *ts_job_state_name(ts_job_state s);
static inline bool ts_job_state_finished(ts_job_state s) { return s >= TS_JOB_DONE; }

/* One tile as it stood after a tile pass: immutable once published. Pixels are the
 * film's accumulators for the tile rectangle, row-major, w·h of them. */
typedef struct ts_tile_snapshot {
    atomic_int refs;   /* private: reference count */
    int tx, ty;        /* grid position (tiles of the film window) */
    int x, y, w, h;    /* full-image pixels */
    uint32_t spp;      /* samples per pixel in it */
    ts_film_pixel pixels[]; /* w·h */
} ts_tile_snapshot;

/* Callbacks (all optional). `info` is only valid during the call. */
typedef struct ts_tile_event { int tx, ty, x, y, w, h; uint32_t spp; } ts_tile_event;

typedef struct ts_job_progress {
    ts_job_state state;
    ts_halt_reason halt;
    uint32_t spp_done;      /* every tile has at least this many samples per pixel */
    uint32_t spp_target;
    uint32_t pass_end;      /* the pass under way renders up to this spp */
    int tiles, tiles_at_pass_end; /* tiles in the film; of them, at pass_end */
    double elapsed_s;       /* rendering wall time (including time before a restore) */
    double queued_s;        /* time from submission to the first tile (0 while queued) */
    uint64_t samples;       /* camera samples taken (this process + before a restore) */
    uint64_t nonfinite;     /* of them, dropped for NaN/∞/negative radiance */
    uint64_t camera_rays, other_rays;
    /* volpath in media (counters.h): tracking steps taken and walks cut short (a step or
     * crossing bound), including those before a restore */
    uint64_t medium_steps, walks_truncated;
    double samples_per_s;   /* samples / elapsed_s */
    double error_estimate;  /* at the last pass end; < 0 when not yet known (fewer than 2 spp) */
    double spp_fraction;    /* pixel-samples held ÷ pixels: grows as tiles finish, within a pass */
    double progress;        /* 0–1 towards the first halting bound (progressive.h); 1 when finished */
    double eta_s;           /* seconds still to go; < 0 while it cannot be estimated */
    bool cancelling;        /* cancelled, and tiles still finishing */
} ts_job_progress;

typedef struct ts_job_callbacks {
    void (*on_tile)(void *user, ts_sched_job *job, const ts_tile_event *ev);
    void (*on_pass)(void *user, ts_sched_job *job, const ts_job_progress *p);
    void (*on_done)(void *user, ts_sched_job *job, const ts_job_progress *p);
    void *user;
} ts_job_callbacks;

typedef struct ts_sched_job_desc {
    ts_scene *scene;            /* ownership passes to the job on success (destroyed with it);
                                 * may be NULL only with `finished` set */
    ts_job_settings settings;   /* integrator, spp target (≥ 1), priority, halting bounds */
    uint32_t sample_begin;      /* the job renders sample indices [sample_begin, sample_begin + spp) */
    double max_pass_s;          /* a pass is shrunk to about this long (e.g. a checkpoint interval); 0 = no bound */
    ts_job_callbacks callbacks;
    /* Resuming (all optional): a film of the scene's crop window with samples already in it
     * (ownership passes to the job on success) and, per tile (row-major over the grid),
     * the samples per pixel it holds. `elapsed_s`, `samples`, `nonfinite`,
     * `medium_steps`, `walks_truncated` carry the counters of the earlier run. */
    ts_film *film;
    const uint32_t *tile_spp;
    /* An adaptive job resumed (settings.adaptive, render/adaptive.h): the active pixels the
     * film was rendered with (width·height bytes of the window, row-major; copied) and the
     * check point they were chosen at (ts_sched_job_film_adaptive gives both). NULL: every
     * pixel, which fits a film of at most TS_ADAPTIVE_MIN_SPP samples per pixel. A film
     * whose tiles lie outside [active_spp, the next check point] is refused (TS_ERR_INVALID):
     * its stopped pixels could not be told from the others. */
    const uint8_t *active;
    uint32_t active_spp;
    double elapsed_s;
    uint64_t samples, nonfinite, medium_steps, walks_truncated;
    /* Restoring a finished job: it is registered in this state (TS_JOB_DONE, _CANCELLED or
     * _FAILED) and never rendered; `film` is required then, with width/height below. */
    ts_job_state finished;      /* 0 (TS_JOB_QUEUED) = render it */
    int full_width, full_height; /* only when scene is NULL */
    /* Rendered elsewhere (a farm, docs/design.md §7): never given to the workers. The caller
     * feeds its pixels with ts_sched_job_publish and ends it with ts_sched_job_finish; a
     * cancel only marks it cancelling until then. Snapshots, progress and callbacks are
     * those of a rendered job. */
    bool external;
} ts_sched_job_desc;

/* Starts `threads` workers (≥ 1); at most `max_running` jobs (≥ 1) are active at once.
 * NULL with err filled when threads cannot be started. */
ts_scheduler *ts_scheduler_create(int threads, int max_running, ts_error *err);

/* Stops the workers within one sample (the tiles they were rendering are rolled back to
 * their snapshots), without changing any job's state: used before a final checkpoint.
 * Idempotent. Jobs submitted afterwards are kept but never rendered. */
void ts_scheduler_stop(ts_scheduler *s);

/* Stops (if needed) and frees the scheduler; drops its references to jobs. Jobs the
 * caller still references stay readable. */
void ts_scheduler_destroy(ts_scheduler *s);

/* Total samples rendered by this scheduler, all jobs (for metrics). */
uint64_t ts_scheduler_samples(ts_scheduler *s);
int ts_scheduler_threads(const ts_scheduler *s);

/* Submits a job; returns it with one reference for the caller (ts_sched_job_release).
 * NULL with err filled (TS_ERR_INVALID for a bad description, TS_ERR_NOMEM); then the
 * scene and film still belong to the caller. */
ts_sched_job *ts_scheduler_submit(ts_scheduler *s, const ts_sched_job_desc *desc, ts_error *err);

void ts_sched_job_retain(ts_sched_job *j);
void ts_sched_job_release(ts_sched_job *j); /* NULL is fine */

/* Asks the job to stop; tiles being rendered stop within one sample and are rolled back
 * (the whole tile passes before them stay). Returns true if the job was unfinished.
 * on_done may run on the calling thread. */
bool ts_sched_job_cancel(ts_sched_job *j);

void ts_sched_job_progress(ts_sched_job *j, ts_job_progress *out);

/* The job's scene (NULL for a restored finished job); immutable, valid while j is held. */
const ts_scene *ts_sched_job_scene(const ts_sched_job *j);

/* Film geometry of the job: full image size and the window (crop) the film covers. */
void ts_sched_job_window(const ts_sched_job *j, int *full_w, int *full_h, int *x0, int *y0, int *w, int *h);
/* Tiles across and down the film window. */
void ts_sched_job_grid(const ts_sched_job *j, int *nx, int *ny);

/* A reference to tile (tx, ty)'s latest snapshot, or NULL when out of range or not yet
 * rendered. Release with ts_tile_snapshot_release. */
ts_tile_snapshot *ts_sched_job_tile(ts_sched_job *j, int tx, int ty);
void ts_tile_snapshot_release(ts_tile_snapshot *t); /* NULL is fine */

/* A new film (caller destroys) of the job's window holding every tile's latest snapshot
 * (with the scene's output scale, film.h), and optionally (tile_spp: nx·ny entries, caller-allocated) each tile's spp. Tiles not
 * rendered yet are empty. Consistent per tile; reads no working state. */
ts_film *ts_sched_job_film(ts_sched_job *j, uint32_t *tile_spp, ts_error *err);

/* Whether the job samples adaptively (render/adaptive.h). */
bool ts_sched_job_adaptive(const ts_sched_job *j);

/* ts_sched_job_film, and for an adaptive job the active pixels its snapshots were
 * rendered with, consistent with them: active (optional, width·height bytes of the
 * window; all 1 for a job that is not adaptive) and the check point they were chosen at
 * (optional; 0 before the first check and for a job that is not adaptive). What a
 * checkpoint saves to resume the job (ts_sched_job_desc.active). */
ts_film *ts_sched_job_film_adaptive(ts_sched_job *j, uint32_t *tile_spp, uint8_t *active, uint32_t *active_spp,
                                    ts_error *err);

/* External jobs (desc.external): marks the job running (its first samples are being
 * rendered elsewhere; elapsed time counts from here). Idempotent; no effect on a finished
 * or rendered job. */
void ts_sched_job_start(ts_sched_job *j);

/* External jobs: replaces the job's pixels with film (its window; e.g. an exact merge of
 * shards) and `samples` camera samples in all. Each tile whose pixels changed gets a new
 * snapshot, its spp the fewest samples a pixel of it holds, and an on_tile call; then the
 * error estimate is taken (from 2 spp on) and on_pass reports the progress. The job is
 * marked running. TS_ERR_INVALID for a rendered or finished job or a film of another
 * window, TS_ERR_NOMEM. */
ts_status ts_sched_job_publish(ts_sched_job *j, const ts_film *film, uint64_t samples, ts_error *err);

/* External jobs: ends the job in `state` (TS_JOB_DONE, _CANCELLED or _FAILED) with `halt`,
 * keeping the pixels published so far, and calls on_done. False (nothing done) when it
 * had ended already or is not external. */
bool ts_sched_job_finish(ts_sched_job *j, ts_job_state state, ts_halt_reason halt);

/* A new film (caller destroys) covering just one snapshot's tile (scale 1: the caller sets
 * the scene's). */
ts_film *ts_tile_snapshot_film(const ts_tile_snapshot *t, int full_w, int full_h, ts_error *err);

#endif
