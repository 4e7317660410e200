/* scheduler.c — the shared render pool; see scheduler.h for the design.
 *
 * Locking: s->mu guards every field marked "guarded" below, in the scheduler and in every
 * job. Workers hold it only to pick work and to publish results. A job's working film is
 * written without the lock by the one worker that holds a tile (tile.busy), and read
 * without the lock only while the job is "closing" a pass (no tile in flight, none handed
 * out until closing is cleared).
 *
 * Stopping inside a tile: each worker has an interrupt flag that the tile it renders
 * watches (ts_render_request.stop, checked at every sample and, through the integrator, at
 * every bounce and light). Cancelling a job, its time limit (the timer thread below wakes
 * at the earliest deadline) and ts_scheduler_stop set the flags of the workers rendering
 * it, under s->mu; a worker clears its flag under s->mu when it takes a tile. An
 * interrupted tile is rolled back to its last snapshot (or to zero before its first),
 * nothing of it is published or counted, and its spp stays: snapshots, and so every film,
 * checkpoint and image, only ever hold whole tile passes. */
#include "render/scheduler.h"

#include "render/adaptive.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct worker {
    struct ts_scheduler *s;  /* immutable */
    atomic_bool interrupt;   /* set (under s->mu) to stop the tile being rendered */
    struct ts_sched_job *job; /* guarded: the job whose tile it renders, or NULL */
} worker;

typedef struct tile_state {
    int tx, ty, x, y, w, h; /* immutable */
    uint32_t spp;           /* guarded: samples in the published snapshot (and the film) */
    ts_tile_snapshot *snap; /* guarded: latest snapshot, or NULL */
} tile_state;

struct ts_sched_job {
    atomic_int refs;
    ts_scheduler *s;            /* immutable; the job holds a reference on its memory */
    /* immutable after submit */
    ts_scene *scene;
    ts_job_settings settings;
    uint32_t sample_begin;
    double max_pass_s;
    uint32_t done_before;       /* spp every tile held at submission (a resume) */
    bool external;              /* rendered elsewhere: fed by ts_sched_job_publish, never listed */
    uint64_t seq;
    ts_job_callbacks cb;
    int full_w, full_h, x0, y0, w, h, nx, ny, n_tiles;
    tile_state *tiles;
    int *order;                 /* tile indices, centre outwards */
    ts_film *film;              /* working film: see the locking note */
    double t_submit;
    /* guarded by s->mu */
    ts_job_state state;
    ts_halt_reason halt;
    bool cancel, closing, in_list;
    bool out_of_time;           /* the time limit passed: nothing more is dispatched */
    double deadline;            /* ts_now_seconds() when the time limit passes; 0 = none */
    uint32_t pass_end;
    int cursor, outstanding;
    uint64_t last_dispatch;
    double t_start, t_end, elapsed_before;
    uint64_t samples, nonfinite, camera_rays, other_rays;
    uint64_t medium_steps, walks_truncated; /* volpath's (counters.h) */
    double error;               /* the last error estimate, at error_spp; < 0 unknown */
    uint32_t error_spp;
    double prev_error;          /* the one before, at prev_error_spp (the convergence slope) */
    uint32_t prev_error_spp;
    double spp_before;          /* pixel-samples ÷ pixels held at submission */
    /* Adaptive jobs (render/adaptive.h; NULL otherwise): the pixels that take samples
     * (w·h bytes, row-major over the window), chosen at check point active_spp (0: every
     * pixel, before the first check). The pointer and active_spp are guarded; the bytes
     * are written only while closing a pass (no tile in flight), by swapping in
     * active_next, which with adaptive_scratch belongs to the closing worker. */
    uint8_t *active, *active_next;
    float *adaptive_scratch;
    uint32_t active_spp;
    struct ts_sched_job *next;  /* s->jobs list (unfinished jobs, in priority order) */
};

struct ts_scheduler {
    atomic_int refs;            /* the owner's + one per job */
    pthread_mutex_t mu;
    pthread_cond_t work;        /* signalled when there may be work or on stop */
    pthread_cond_t timer_cv;    /* (CLOCK_MONOTONIC) signalled when a deadline is set or on stop */
    int n_threads, max_running;
    pthread_t *threads;         /* immutable after create */
    worker *workers;            /* immutable after create (each worker's fields: see worker) */
    pthread_t timer;
    int started;
    bool timer_started;
    /* guarded by mu */
    bool stopping, joined;
    ts_sched_job *jobs;
    uint64_t next_seq, dispatch_clock;
    uint64_t samples_total;
};

const char *ts_job_state_name(ts_job_state s)
{
    switch (s) {
    case TS_JOB_QUEUED: return "queued";
    case TS_JOB_RUNNING: return "running";
    case TS_JOB_DONE: return "done";
    case TS_JOB_CANCELLED: return "cancelled";
    case TS_JOB_FAILED: return "failed";
    }
    return "unknown";
}

/* ---------------------------------------------------------------- references */

static void scheduler_unref(ts_scheduler *s)
{
    if (atomic_fetch_sub(&s->refs, 1) != 1) return;
    pthread_mutex_destroy(&s->mu);
    pthread_cond_destroy(&s->work);
    pthread_cond_destroy(&s->timer_cv);
    free(s->threads);
    free(s->workers);
    free(s);
}

void ts_tile_snapshot_release(ts_tile_snapshot *t)
{
    if (t && atomic_fetch_sub(&t->refs, 1) == 1) free(t);
}

void ts_sched_job_retain(ts_sched_job *j) { atomic_fetch_add(&j->refs, 1); }

static void job_free(ts_sched_job *j)
{
    for (int i = 0; j->tiles && i < j->n_tiles; i++) ts_tile_snapshot_release(j->tiles[i].snap);
    free(j->tiles);
    free(j->order);
    free(j->active);
    free(j->active_next);
    free(j->adaptive_scratch);
    ts_film_destroy(j->film);
    ts_scene_destroy(j->scene);
    if (j->s) scheduler_unref(j->s);
    free(j);
}

void ts_sched_job_release(ts_sched_job *j)
{
    if (j && atomic_fetch_sub(&j->refs, 1) == 1) job_free(j);
}

/* ---------------------------------------------------------------- helpers (s->mu held) */

static double job_elapsed(const ts_sched_job *j, double now)
{
    if (j->t_start <= 0) return j->elapsed_before;
    return j->elapsed_before + ((j->t_end > 0 ? j->t_end : now) - j->t_start);
}

static uint32_t job_spp_done(const ts_sched_job *j)
{
    uint32_t m = UINT32_MAX;
    for (int i = 0; i < j->n_tiles; i++)
        if (j->tiles[i].spp < m) m = j->tiles[i].spp;
    return j->n_tiles ? m : 0;
}

static void fill_progress(const ts_sched_job *j, ts_job_progress *p)
{
    double now = ts_now_seconds();
    memset(p, 0, sizeof *p);
    p->state = j->state;
    p->halt = j->halt;
    p->spp_done = job_spp_done(j);
    p->spp_target = j->settings.spp;
    p->pass_end = j->pass_end;
    p->tiles = j->n_tiles;
    for (int i = 0; i < j->n_tiles; i++)
        if (j->tiles[i].spp >= j->pass_end) p->tiles_at_pass_end++;
    p->elapsed_s = job_elapsed(j, now);
    p->queued_s = j->t_start > 0 ? j->t_start - j->t_submit : 0;
    p->samples = j->samples;
    p->nonfinite = j->nonfinite;
    p->camera_rays = j->camera_rays;
    p->other_rays = j->other_rays;
    p->medium_steps = j->medium_steps;
    p->walks_truncated = j->walks_truncated;
    p->samples_per_s = p->elapsed_s > 0 ? (double)j->samples / p->elapsed_s : 0;
    p->error_estimate = j->error;
    uint64_t px_samples = 0;
    for (int i = 0; i < j->n_tiles; i++) px_samples += (uint64_t)j->tiles[i].spp * (uint64_t)(j->tiles[i].w * j->tiles[i].h);
    uint64_t pixels = (uint64_t)j->w * (uint64_t)j->h;
    p->spp_fraction = pixels ? (double)px_samples / (double)pixels : 0;
    ts_progress_in in = {p->spp_fraction, j->spp_before, p->elapsed_s, j->elapsed_before, j->error, j->error_spp,
                         j->prev_error, j->prev_error_spp, ts_job_state_finished(j->state)};
    ts_progressive_estimate(&j->settings, &in, &p->progress, &p->eta_s);
    p->cancelling = j->cancel && !ts_job_state_finished(j->state);
}

/* Index (into tiles) of the job's next tile needing the current pass, advancing the cursor
 * past tiles already there; -1 when none is left. */
static int next_tile(ts_sched_job *j)
{
    while (j->cursor < j->n_tiles && j->tiles[j->order[j->cursor]].spp >= j->pass_end) j->cursor++;
    return j->cursor < j->n_tiles ? j->order[j->cursor] : -1;
}

static bool needs_close(ts_sched_job *j)
{
    return !j->closing && j->outstanding == 0 && !ts_job_state_finished(j->state) &&
           (j->cancel || j->out_of_time || next_tile(j) < 0);
}

/* Stops every tile of j being rendered (their workers roll them back). */
static void interrupt_job(ts_scheduler *s, const ts_sched_job *j)
{
    for (int i = 0; i < s->started; i++)
        if (s->workers[i].job == j) atomic_store(&s->workers[i].interrupt, true);
}

/* Marks j out of time once its deadline has passed (now: ts_now_seconds()); true then. */
static bool check_deadline(ts_scheduler *s, ts_sched_job *j, double now)
{
    if (j->deadline <= 0 || j->out_of_time || now < j->deadline || ts_job_state_finished(j->state)) return j->out_of_time;
    j->out_of_time = true;
    interrupt_job(s, j);
    pthread_cond_broadcast(&s->work); /* an idle worker may have to close it */
    return true;
}

static void list_remove(ts_scheduler *s, ts_sched_job *j)
{
    for (ts_sched_job **pp = &s->jobs; *pp; pp = &(*pp)->next)
        if (*pp == j) {
            *pp = j->next;
            j->next = NULL;
            j->in_list = false;
            return;
        }
}

/* ---------------------------------------------------------------- workers */

static ts_tile_snapshot *snapshot_from_film(const ts_film *f, const tile_state *t, uint32_t spp)
{
    ts_tile_snapshot *snap = malloc(sizeof *snap + sizeof(ts_film_pixel) * (size_t)t->w * (size_t)t->h);
    if (!snap) return NULL;
    atomic_init(&snap->refs, 1);
    snap->tx = t->tx, snap->ty = t->ty, snap->x = t->x, snap->y = t->y, snap->w = t->w, snap->h = t->h;
    snap->spp = spp;
    for (int y = 0; y < t->h; y++)
        memcpy(&snap->pixels[(size_t)y * t->w], ts_film_pixel_at(f, t->x, t->y + y), sizeof(ts_film_pixel) * (size_t)t->w);
    return snap;
}


/* Ends the job's current pass: estimate the error, then halt or start the next pass.
 * Called with s->mu held and j->closing set; drops and retakes the lock. */
static void close_pass(ts_scheduler *s, ts_sched_job *j)
{
    uint32_t done = job_spp_done(j);
    /* An adaptive job at a check point it has not chosen at yet: choose the pixels that go
     * on (every tile holds `done` then: passes end at check points, adaptive.h). */
    bool choose = j->active && !j->cancel && !j->out_of_time && done < j->settings.spp && ts_adaptive_is_check(done) &&
                  j->active_spp < done;
    pthread_mutex_unlock(&s->mu);
    /* One sample gives no variance: the estimate means something from two on. */
    double error = done >= 2 && j->film ? ts_film_relative_error(j->film) : -1;
    if (choose) {
        memcpy(j->active_next, j->active, (size_t)j->w * (size_t)j->h);
        ts_adaptive_select(j->film, ts_job_adaptive_target(&j->settings), j->active_next, j->adaptive_scratch);
    }
    pthread_mutex_lock(&s->mu);
    if (choose) {
        uint8_t *t = j->active;
        j->active = j->active_next, j->active_next = t;
        j->active_spp = done;
    }
    if (error >= 0 && done != j->error_spp) {
        j->prev_error = j->error, j->prev_error_spp = j->error_spp;
        j->error = error, j->error_spp = done;
    }
    double now = ts_now_seconds();
    ts_pass_state ps = {done, j->done_before, job_elapsed(j, now), j->elapsed_before, error, j->cancel, j->out_of_time};
    ts_halt_reason halt = ts_progressive_halt(&j->settings, &ps);
    bool finished = halt != TS_HALT_NONE;
    if (finished) {
        j->halt = halt;
        j->state = halt == TS_HALT_CANCELLED ? TS_JOB_CANCELLED : TS_JOB_DONE;
        if (j->t_start > 0) j->t_end = now;
        list_remove(s, j);
    } else {
        /* After a restore tiles may differ: the first pass brings all to the furthest. */
        uint32_t max = 0;
        for (int i = 0; i < j->n_tiles; i++)
            if (j->tiles[i].spp > max) max = j->tiles[i].spp;
        uint32_t cap = j->settings.spp;
        j->pass_end = max > done ? (max < cap ? max : cap) : ts_progressive_next_pass_end(&j->settings, &ps, j->max_pass_s);
        j->cursor = 0;
    }
    ts_job_progress p;
    fill_progress(j, &p);
    if (!finished && done > 0 && j->cb.on_pass) {
        /* Still closing: no tile of the next pass starts until on_pass returns. */
        pthread_mutex_unlock(&s->mu);
        j->cb.on_pass(j->cb.user, j, &p);
        pthread_mutex_lock(&s->mu);
    }
    j->closing = false;
    pthread_cond_broadcast(&s->work);
    pthread_mutex_unlock(&s->mu);
    if (finished) {
        if (j->cb.on_done) j->cb.on_done(j->cb.user, j, &p);
        ts_sched_job_release(j); /* the list's reference */
    }
    pthread_mutex_lock(&s->mu);
}

/* Picks work under s->mu: a job to close (*tile = -1) or a tile of an active job. */
static ts_sched_job *pick(ts_scheduler *s, int *tile)
{
    for (ts_sched_job *j = s->jobs; j; j = j->next)
        if (needs_close(j) && (j->cancel || j->state == TS_JOB_RUNNING || j->pass_end == 0)) {
            *tile = -1;
            return j;
        }
    ts_sched_job *best = NULL;
    int active = 0;
    double now = ts_now_seconds();
    for (ts_sched_job *j = s->jobs; j && active < s->max_running; j = j->next) {
        active++;
        if (j->closing || j->cancel || check_deadline(s, j, now) || next_tile(j) < 0) continue;
        if (!best || j->outstanding < best->outstanding ||
            (j->outstanding == best->outstanding && j->last_dispatch < best->last_dispatch))
            best = j;
    }
    if (!best) return NULL;
    *tile = next_tile(best);
    best->cursor++;
    best->outstanding++;
    best->last_dispatch = ++s->dispatch_clock;
    if (best->state == TS_JOB_QUEUED) {
        best->state = TS_JOB_RUNNING;
        best->t_start = now;
        if (best->settings.time_limit_s > 0) {
            best->deadline = now + (best->settings.time_limit_s - best->elapsed_before);
            pthread_cond_signal(&s->timer_cv);
        }
    }
    return best;
}

/* Puts tile t of the film back as `base` holds it (NULL: empty, before its first pass). */
static void roll_back(ts_film *f, const tile_state *t, const ts_tile_snapshot *base)
{
    for (int y = 0; y < t->h; y++) {
        ts_film_pixel *row = ts_film_pixel_at(f, t->x, t->y + y);
        if (base) memcpy(row, &base->pixels[(size_t)y * t->w], sizeof(ts_film_pixel) * (size_t)t->w);
        else memset(row, 0, sizeof(ts_film_pixel) * (size_t)t->w);
    }
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    ts_scheduler *s = w->s;
    pthread_mutex_lock(&s->mu);
    while (!s->stopping) {
        int ti;
        ts_sched_job *j = pick(s, &ti);
        if (!j) {
            pthread_cond_wait(&s->work, &s->mu);
            continue;
        }
        if (ti < 0) {
            j->closing = true;
            close_pass(s, j);
            continue;
        }
        tile_state *t = &j->tiles[ti];
        ts_render_request req = {j->scene, j->settings.integrator, j->film, j->sample_begin + t->spp,
                                 j->sample_begin + j->pass_end, 1, NULL, NULL, NULL};
        req.active = j->active;
        /* What an interrupted tile goes back to: its snapshot, or nothing before its first
         * pass. Only after a snapshot could not be allocated (the film then holds more than
         * it) is there none to go back to: that tile pass runs to its end. */
        ts_tile_snapshot *base = t->snap && t->snap->spp == t->spp ? t->snap : NULL;
        if (base) atomic_fetch_add(&base->refs, 1);
        if (base || t->spp == 0) req.stop = &w->interrupt;
        w->job = j;
        atomic_store(&w->interrupt, false);
        ts_sched_job_retain(j);
        pthread_mutex_unlock(&s->mu);

        ts_counters c = {0};
        bool complete = ts_render_tile(&req, t->x, t->y, t->w, t->h, &c);
        if (!complete) {
            roll_back(j->film, t, base);
            ts_tile_snapshot_release(base);
            pthread_mutex_lock(&s->mu);
            w->job = NULL;
            j->outstanding--;
            /* Stopped by a cancel or the time limit: close the job; by a shutdown: leave
             * it as it is (its tiles all hold whole passes). */
            if (!s->stopping && needs_close(j)) {
                j->closing = true;
                close_pass(s, j);
            } else if (j->outstanding == 0) {
                pthread_cond_broadcast(&s->work);
            }
            pthread_mutex_unlock(&s->mu);
            ts_sched_job_release(j);
            pthread_mutex_lock(&s->mu);
            continue;
        }
        ts_tile_snapshot_release(base);
        ts_tile_snapshot *snap = snapshot_from_film(j->film, t, j->pass_end);
        ts_tile_event ev = {t->tx, t->ty, t->x, t->y, t->w, t->h, j->pass_end};

        pthread_mutex_lock(&s->mu);
        w->job = NULL;
        ts_tile_snapshot *old = NULL;
        if (snap) { /* out of memory: the film has the samples; the old snapshot stays */
            old = t->snap;
            t->snap = snap;
        }
        t->spp = j->pass_end;
        j->samples += c.samples;
        j->nonfinite += c.nonfinite;
        j->camera_rays += c.camera_rays;
        j->other_rays += c.other_rays;
        j->medium_steps += c.medium_steps;
        j->walks_truncated += c.walks_truncated;
        s->samples_total += c.samples;
        pthread_mutex_unlock(&s->mu);
        ts_tile_snapshot_release(old);
        if (j->cb.on_tile) j->cb.on_tile(j->cb.user, j, &ev);
        pthread_mutex_lock(&s->mu);
        j->outstanding--;
        if (needs_close(j)) {
            j->closing = true;
            close_pass(s, j);
        } else if (j->outstanding == 0 || j->cancel) {
            pthread_cond_broadcast(&s->work);
        }
        pthread_mutex_unlock(&s->mu);
        ts_sched_job_release(j);
        pthread_mutex_lock(&s->mu);
    }
    pthread_mutex_unlock(&s->mu);
    return NULL;
}

/* Marks jobs out of time at their deadlines, so a time limit stops the tiles being
 * rendered within one sample (the workers only see it through their interrupt flags).
 * Sleeps on timer_cv until the earliest deadline. */
static void *timer_main(void *arg)
{
    ts_scheduler *s = arg;
    pthread_mutex_lock(&s->mu);
    while (!s->stopping) {
        double now = ts_now_seconds(), next = 0;
        for (ts_sched_job *j = s->jobs; j; j = j->next)
            if (!check_deadline(s, j, now) && j->deadline > 0 && (next == 0 || j->deadline < next)) next = j->deadline;
        if (next == 0) {
            pthread_cond_wait(&s->timer_cv, &s->mu);
            continue;
        }
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        double wait = next - now, whole = floor(wait);
        ts.tv_sec += (time_t)whole;
        ts.tv_nsec += (long)((wait - whole) * 1e9);
        if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
        pthread_cond_timedwait(&s->timer_cv, &s->mu, &ts);
    }
    pthread_mutex_unlock(&s->mu);
    return NULL;
}

/* ---------------------------------------------------------------- scheduler */

ts_scheduler *ts_scheduler_create(int threads, int max_running, ts_error *err)
{
    if (threads < 1) threads = 1;
    if (max_running < 1) max_running = 1;
    ts_scheduler *s = calloc(1, sizeof *s);
    if (!s) {
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for the scheduler");
        return NULL;
    }
    atomic_init(&s->refs, 1);
    s->n_threads = threads;
    s->max_running = max_running;
    pthread_mutex_init(&s->mu, NULL);
    pthread_cond_init(&s->work, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC); /* the clock of ts_now_seconds */
    pthread_cond_init(&s->timer_cv, &ca);
    pthread_condattr_destroy(&ca);
    s->threads = calloc((size_t)threads, sizeof *s->threads);
    s->workers = calloc((size_t)threads, sizeof *s->workers);
    if (!s->threads || !s->workers) {
        scheduler_unref(s);
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for %d threads", threads);
        return NULL;
    }
    if (pthread_create(&s->timer, NULL, timer_main, s) != 0) {
        scheduler_unref(s);
        ts_error_set(err, TS_ERR_INTERNAL, "could not start the scheduler's timer thread");
        return NULL;
    }
    s->timer_started = true;
    for (int i = 0; i < threads; i++) {
        s->workers[i].s = s;
        atomic_init(&s->workers[i].interrupt, false);
    }
    /* s->started only grows before any job exists, so interrupt_job never sees a worker
     * that is not running. */
    while (s->started < threads &&
           pthread_create(&s->threads[s->started], NULL, worker_main, &s->workers[s->started]) == 0)
        s->started++;
    if (s->started == 0) {
        ts_scheduler_stop(s);
        scheduler_unref(s);
        ts_error_set(err, TS_ERR_INTERNAL, "could not start any render thread");
        return NULL;
    }
    s->n_threads = s->started;
    return s;
}

int ts_scheduler_threads(const ts_scheduler *s) { return s->n_threads; }

uint64_t ts_scheduler_samples(ts_scheduler *s)
{
    pthread_mutex_lock(&s->mu);
    uint64_t n = s->samples_total;
    pthread_mutex_unlock(&s->mu);
    return n;
}

void ts_scheduler_stop(ts_scheduler *s)
{
    pthread_mutex_lock(&s->mu);
    bool join = !s->joined;
    s->stopping = true;
    s->joined = true;
    for (int i = 0; i < s->started; i++) atomic_store(&s->workers[i].interrupt, true);
    pthread_cond_broadcast(&s->work);
    pthread_cond_broadcast(&s->timer_cv);
    pthread_mutex_unlock(&s->mu);
    if (!join) return;
    for (int i = 0; i < s->started; i++) pthread_join(s->threads[i], NULL);
    if (s->timer_started) pthread_join(s->timer, NULL);
}

void ts_scheduler_destroy(ts_scheduler *s)
{
    if (!s) return;
    ts_scheduler_stop(s);
    pthread_mutex_lock(&s->mu);
    ts_sched_job *list = s->jobs;
    s->jobs = NULL;
    for (ts_sched_job *j = list; j; j = j->next) j->in_list = false;
    pthread_mutex_unlock(&s->mu);
    while (list) {
        ts_sched_job *next = list->next;
        list->next = NULL;
        ts_sched_job_release(list);
        list = next;
    }
    scheduler_unref(s);
}

ts_sched_job *ts_scheduler_submit(ts_scheduler *s, const ts_sched_job_desc *d, ts_error *err)
{
    bool finished = ts_job_state_finished(d->finished);
    if (!d->scene && !(finished && d->film)) {
        ts_error_set(err, TS_ERR_INVALID, "a job needs a scene (or a film when restored finished)");
        return NULL;
    }
    if (d->settings.spp < 1 && !finished) {
        ts_error_set(err, TS_ERR_INVALID, "a job needs at least 1 sample per pixel");
        return NULL;
    }
    ts_sched_job *j = calloc(1, sizeof *j);
    if (!j) {
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job");
        return NULL;
    }
    atomic_init(&j->refs, 1);
    j->settings = d->settings;
    j->sample_begin = d->sample_begin;
    j->max_pass_s = d->max_pass_s;
    j->external = d->external;
    j->cb = d->callbacks;
    j->error = j->prev_error = -1;
    if (d->scene) {
        const ts_scene *sc = d->scene;
        j->full_w = sc->width, j->full_h = sc->height;
        j->x0 = sc->crop_x0, j->y0 = sc->crop_y0, j->w = sc->crop_x1 - sc->crop_x0, j->h = sc->crop_y1 - sc->crop_y0;
    } else {
        j->full_w = d->full_width, j->full_h = d->full_height;
        j->x0 = d->film->x0, j->y0 = d->film->y0, j->w = d->film->width, j->h = d->film->height;
    }
    if (d->film && (d->film->x0 != j->x0 || d->film->y0 != j->y0 || d->film->width != j->w ||
                    d->film->height != j->h || d->film->full_width != j->full_w || d->film->full_height != j->full_h)) {
        ts_error_set(err, TS_ERR_INVALID, "the film to resume does not match the scene's film window");
        free(j);
        return NULL;
    }
    ts_tile_grid_size(j->w, j->h, &j->nx, &j->ny);
    j->n_tiles = j->nx * j->ny;
    bool adaptive = j->settings.adaptive && d->scene && !finished && !d->external;
    if (adaptive && d->film) {
        /* A resumed adaptive job: its tiles must lie within the stretch its active pixels
         * were chosen for (from the check point they were chosen at to the next one). */
        uint32_t least = UINT32_MAX, most = 0, at = d->active ? d->active_spp : 0;
        for (int i = 0; i < j->n_tiles; i++) {
            uint32_t t = d->tile_spp ? d->tile_spp[i] : 0;
            if (t < least) least = t;
            if (t > most) most = t;
        }
        if ((at && !ts_adaptive_is_check(at)) || at > least || most > ts_adaptive_next_check(at)) {
            ts_error_set(err, TS_ERR_INVALID,
                         "the film to resume holds %u to %u samples per pixel, but its active pixels were chosen at "
                         "%u: an adaptive job resumes only with the active pixels of the film's samples",
                         least, most, at);
            free(j);
            return NULL;
        }
    }
    size_t n_px = (size_t)j->w * (size_t)j->h;
    j->tiles = calloc((size_t)j->n_tiles, sizeof *j->tiles);
    j->order = malloc(sizeof *j->order * (size_t)j->n_tiles);
    if (adaptive) {
        j->active = malloc(n_px);
        j->active_next = malloc(n_px);
        j->adaptive_scratch = malloc(n_px * sizeof *j->adaptive_scratch);
    }
    bool adaptive_ok = !adaptive || (j->active && j->active_next && j->adaptive_scratch);
    ts_film *film = d->film ? d->film : ts_film_create(j->full_w, j->full_h, j->x0, j->y0, j->w, j->h, err);
    if (film && d->scene) film->scale = d->scene->film_scale; /* the output factor; a film of its own else */
    if (!j->tiles || !j->order || !film || !adaptive_ok) {
        if (film && film != d->film) ts_film_destroy(film);
        free(j->tiles);
        free(j->order);
        free(j->active);
        free(j->active_next);
        free(j->adaptive_scratch);
        free(j);
        if (film) ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job's tiles");
        return NULL;
    }
    if (adaptive) {
        if (d->film && d->active) memcpy(j->active, d->active, n_px);
        else memset(j->active, 1, n_px);
        j->active_spp = d->film && d->active ? d->active_spp : 0;
    }
    for (int ty = 0; ty < j->ny; ty++)
        for (int tx = 0; tx < j->nx; tx++) {
            int i = ty * j->nx + tx;
            tile_state *t = &j->tiles[i];
            ts_tile_rect r = ts_tile_grid_rect(j->x0, j->y0, j->w, j->h, tx, ty);
            t->tx = tx, t->ty = ty, t->x = r.x, t->y = r.y, t->w = r.w, t->h = r.h;
            t->spp = d->tile_spp ? d->tile_spp[i] : 0;
            if (d->film && t->spp > 0) t->snap = snapshot_from_film(film, t, t->spp);
        }
    ts_tile_grid_order(j->x0, j->y0, j->w, j->h, j->full_w, j->full_h, j->order);
    j->film = film;
    j->scene = d->scene;
    j->elapsed_before = d->elapsed_s;
    j->samples = d->samples;
    j->nonfinite = d->nonfinite;
    j->medium_steps = d->medium_steps;
    j->walks_truncated = d->walks_truncated;
    j->t_submit = ts_now_seconds();
    j->cursor = j->n_tiles; /* pass_end 0: the first close starts pass 1 */
    j->done_before = job_spp_done(j);
    for (int i = 0; i < j->n_tiles; i++)
        j->spp_before += (double)j->tiles[i].spp * j->tiles[i].w * j->tiles[i].h / ((double)j->w * j->h);
    if (d->film && !finished && j->done_before >= 2) j->error = ts_film_relative_error(film), j->error_spp = j->done_before;

    atomic_fetch_add(&s->refs, 1);
    j->s = s;
    pthread_mutex_lock(&s->mu);
    j->seq = s->next_seq++;
    if (finished) {
        j->state = d->finished;
        j->halt = TS_HALT_RESTORED;
        j->pass_end = job_spp_done(j);
        pthread_mutex_unlock(&s->mu);
        if (j->film && j->pass_end >= 2) j->error = ts_film_relative_error(j->film), j->error_spp = j->pass_end;
        return j;
    }
    j->state = TS_JOB_QUEUED;
    if (d->external) {
        /* Not in the workers' list: ts_sched_job_publish and _finish drive it. */
        pthread_mutex_unlock(&s->mu);
        return j;
    }
    ts_sched_job **pp = &s->jobs;
    int prio = j->settings.priority;
    while (*pp && ((*pp)->settings.priority > prio || ((*pp)->settings.priority == prio && (*pp)->seq < j->seq)))
        pp = &(*pp)->next;
    j->next = *pp;
    *pp = j;
    j->in_list = true;
    ts_sched_job_retain(j); /* the list's reference */
    pthread_cond_broadcast(&s->work);
    pthread_mutex_unlock(&s->mu);
    return j;
}

bool ts_sched_job_cancel(ts_sched_job *j)
{
    ts_scheduler *s = j->s;
    if (!s) return false;
    pthread_mutex_lock(&s->mu);
    if (ts_job_state_finished(j->state) || j->cancel) {
        bool was = !ts_job_state_finished(j->state);
        pthread_mutex_unlock(&s->mu);
        return was;
    }
    j->cancel = true;
    if (j->external) { /* cancelling until its owner has stopped it elsewhere (ts_sched_job_finish) */
        pthread_mutex_unlock(&s->mu);
        return true;
    }
    interrupt_job(s, j);
    if ((s->stopping || j->state == TS_JOB_QUEUED) && j->outstanding == 0 && !j->closing) {
        /* No workers left to close it, or it has not started (no tile to wait for): finish
         * here (no new error estimate), so the answer to a cancel of a queued job is the
         * state it is in, "cancelled", whatever the workers are busy with. */
        j->state = TS_JOB_CANCELLED;
        j->halt = TS_HALT_CANCELLED;
        if (j->t_start > 0) j->t_end = ts_now_seconds();
        bool listed = j->in_list;
        list_remove(s, j);
        ts_job_progress p;
        fill_progress(j, &p);
        pthread_mutex_unlock(&s->mu);
        if (j->cb.on_done) j->cb.on_done(j->cb.user, j, &p);
        if (listed) ts_sched_job_release(j);
        return true;
    }
    pthread_cond_broadcast(&s->work); /* a worker closes it once its tiles are in */
    pthread_mutex_unlock(&s->mu);
    return true;
}

void ts_sched_job_progress(ts_sched_job *j, ts_job_progress *out)
{
    pthread_mutex_lock(&j->s->mu);
    fill_progress(j, out);
    pthread_mutex_unlock(&j->s->mu);
}

const ts_scene *ts_sched_job_scene(const ts_sched_job *j) { return j->scene; }

void ts_sched_job_window(const ts_sched_job *j, int *full_w, int *full_h, int *x0, int *y0, int *w, int *h)
{
    if (full_w) *full_w = j->full_w;
    if (full_h) *full_h = j->full_h;
    if (x0) *x0 = j->x0;
    if (y0) *y0 = j->y0;
    if (w) *w = j->w;
    if (h) *h = j->h;
}

void ts_sched_job_grid(const ts_sched_job *j, int *nx, int *ny)
{
    *nx = j->nx;
    *ny = j->ny;
}

ts_tile_snapshot *ts_sched_job_tile(ts_sched_job *j, int tx, int ty)
{
    if (tx < 0 || ty < 0 || tx >= j->nx || ty >= j->ny) return NULL;
    pthread_mutex_lock(&j->s->mu);
    ts_tile_snapshot *t = j->tiles[ty * j->nx + tx].snap;
    if (t) atomic_fetch_add(&t->refs, 1);
    pthread_mutex_unlock(&j->s->mu);
    return t;
}

ts_film *ts_sched_job_film(ts_sched_job *j, uint32_t *tile_spp, ts_error *err)
{
    return ts_sched_job_film_adaptive(j, tile_spp, NULL, NULL, err);
}

bool ts_sched_job_adaptive(const ts_sched_job *j) { return j->active != NULL; }

ts_film *ts_sched_job_film_adaptive(ts_sched_job *j, uint32_t *tile_spp, uint8_t *active, uint32_t *active_spp,
                                    ts_error *err)
{
    ts_tile_snapshot **snaps = calloc((size_t)j->n_tiles, sizeof *snaps);
    ts_film *f = ts_film_create(j->full_w, j->full_h, j->x0, j->y0, j->w, j->h, err);
    if (f) f->scale = j->film->scale;
    if (!snaps || !f) {
        free(snaps);
        ts_film_destroy(f);
        if (f) ts_error_set(err, TS_ERR_NOMEM, "out of memory for a film snapshot");
        return NULL;
    }
    pthread_mutex_lock(&j->s->mu);
    for (int i = 0; i < j->n_tiles; i++) {
        snaps[i] = j->tiles[i].snap;
        if (snaps[i]) atomic_fetch_add(&snaps[i]->refs, 1);
    }
    /* The active pixels the snapshots were rendered with: the bytes change only while a
     * pass closes, under this lock (the swap), so they go with the snapshots taken here. */
    if (active && j->active) memcpy(active, j->active, (size_t)j->w * (size_t)j->h);
    else if (active) memset(active, 1, (size_t)j->w * (size_t)j->h);
    if (active_spp) *active_spp = j->active ? j->active_spp : 0;
    pthread_mutex_unlock(&j->s->mu);
    for (int i = 0; i < j->n_tiles; i++) {
        const ts_tile_snapshot *t = snaps[i];
        if (tile_spp) tile_spp[i] = t ? t->spp : 0;
        if (!t) continue;
        for (int y = 0; y < t->h; y++)
            memcpy(ts_film_pixel_at(f, t->x, t->y + y), &t->pixels[(size_t)y * t->w], sizeof(ts_film_pixel) * (size_t)t->w);
        ts_tile_snapshot_release(snaps[i]);
    }
    free(snaps);
    return f;
}

/* ---------------------------------------------------------------- external jobs */

/* j->mu held. */
static void external_start(ts_sched_job *j)
{
    if (j->state != TS_JOB_QUEUED) return;
    j->state = TS_JOB_RUNNING;
    j->t_start = ts_now_seconds();
}

void ts_sched_job_start(ts_sched_job *j)
{
    if (!j->external) return;
    pthread_mutex_lock(&j->s->mu);
    external_start(j);
    pthread_mutex_unlock(&j->s->mu);
}

/* The fewest samples a pixel of tile t of film holds. */
static uint32_t tile_min_count(const ts_film *f, const tile_state *t)
{
    uint64_t m = UINT64_MAX;
    for (int y = 0; y < t->h; y++) {
        const ts_film_pixel *row = ts_film_pixel_at(f, t->x, t->y + y);
        for (int x = 0; x < t->w; x++)
            if (row[x].count < m) m = row[x].count;
    }
    return m > UINT32_MAX ? UINT32_MAX : (uint32_t)m;
}

ts_status ts_sched_job_publish(ts_sched_job *j, const ts_film *film, uint64_t samples, ts_error *err)
{
    if (!j->external) return ts_error_set(err, TS_ERR_INVALID, "only an external job takes published pixels");
    if (film->x0 != j->x0 || film->y0 != j->y0 || film->width != j->w || film->height != j->h ||
        film->full_width != j->full_w || film->full_height != j->full_h)
        return ts_error_set(err, TS_ERR_INVALID, "the published film does not match the job's film window");
    ts_tile_snapshot **fresh = calloc((size_t)j->n_tiles, sizeof *fresh), **old = calloc((size_t)j->n_tiles, sizeof *old);
    if (!fresh || !old) {
        free(fresh), free(old);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job's tiles");
    }
    ts_scheduler *s = j->s;
    pthread_mutex_lock(&s->mu);
    for (int i = 0; i < j->n_tiles; i++)
        if ((old[i] = j->tiles[i].snap)) atomic_fetch_add(&old[i]->refs, 1);
    pthread_mutex_unlock(&s->mu);
    ts_status st = TS_OK;
    uint32_t least = UINT32_MAX; /* the spp every pixel of film holds */
    for (int i = 0; i < j->n_tiles && !st; i++) {
        const tile_state *t = &j->tiles[i];
        uint32_t spp = tile_min_count(film, t);
        if (spp < least) least = spp;
        ts_tile_snapshot *n = snapshot_from_film(film, t, spp);
        if (!n) st = ts_error_set(err, TS_ERR_NOMEM, "out of memory for a tile snapshot");
        else if (old[i] && old[i]->spp == spp &&
                 !memcmp(old[i]->pixels, n->pixels, sizeof(ts_film_pixel) * (size_t)t->w * (size_t)t->h))
            ts_tile_snapshot_release(n); /* unchanged */
        else
            fresh[i] = n;
    }
    for (int i = 0; i < j->n_tiles; i++) ts_tile_snapshot_release(old[i]), old[i] = NULL;
    /* One sample gives no variance: the estimate means something from two on. */
    double error = !st && j->n_tiles && least >= 2 ? ts_film_relative_error(film) : -1;
    pthread_mutex_lock(&s->mu);
    if (!st && ts_job_state_finished(j->state))
        st = ts_error_set(err, TS_ERR_INVALID, "the job has ended: it takes no more pixels");
    ts_job_progress p;
    if (!st) {
        for (int i = 0; i < j->n_tiles; i++) {
            if (!fresh[i]) continue;
            old[i] = j->tiles[i].snap; /* released below, outside the lock */
            j->tiles[i].snap = fresh[i];
            j->tiles[i].spp = fresh[i]->spp;
        }
        external_start(j);
        j->samples = samples;
        uint32_t done = job_spp_done(j);
        j->pass_end = done;
        if (error >= 0 && done != j->error_spp) {
            j->prev_error = j->error, j->prev_error_spp = j->error_spp;
            j->error = error, j->error_spp = done;
        }
        fill_progress(j, &p);
    }
    pthread_mutex_unlock(&s->mu);
    if (st) {
        for (int i = 0; i < j->n_tiles; i++) ts_tile_snapshot_release(fresh[i]);
        free(fresh), free(old);
        return st;
    }
    for (int i = 0; i < j->n_tiles; i++) {
        if (!fresh[i]) continue;
        ts_tile_snapshot_release(old[i]);
        const tile_state *t = &j->tiles[i];
        ts_tile_event ev = {t->tx, t->ty, t->x, t->y, t->w, t->h, fresh[i]->spp};
        if (j->cb.on_tile) j->cb.on_tile(j->cb.user, j, &ev);
    }
    if (j->cb.on_pass) j->cb.on_pass(j->cb.user, j, &p);
    free(fresh), free(old);
    return TS_OK;
}

bool ts_sched_job_finish(ts_sched_job *j, ts_job_state state, ts_halt_reason halt)
{
    if (!j->external || !ts_job_state_finished(state)) return false;
    ts_scheduler *s = j->s;
    pthread_mutex_lock(&s->mu);
    if (ts_job_state_finished(j->state)) {
        pthread_mutex_unlock(&s->mu);
        return false;
    }
    j->state = state;
    j->halt = halt;
    if (j->t_start > 0) j->t_end = ts_now_seconds();
    ts_job_progress p;
    fill_progress(j, &p);
    pthread_mutex_unlock(&s->mu);
    if (j->cb.on_done) j->cb.on_done(j->cb.user, j, &p);
    return true;
}

ts_film *ts_tile_snapshot_film(const ts_tile_snapshot *t, int full_w, int full_h, ts_error *err)
{
    ts_film *f = ts_film_create(full_w, full_h, t->x, t->y, t->w, t->h, err);
    if (f) memcpy(f->pixels, t->pixels, sizeof(ts_film_pixel) * (size_t)t->w * (size_t)t->h);
    return f;
}
