/* job_store.h — the server's jobs: reference-counted, listed newest first.
 *
 * Design note: a srv_job wraps one scheduler job (ts_sched_job) with what the API adds:
 * an id, the scene document as posted (for checkpoints), the event hub of its SSE
 * streams, and a version counter that checkpoints compare. The scheduler's callbacks turn
 * into `tile`, `progress` and `done` events here. The store is the one piece of mutable
 * state shared across the server (docs/design.md §6); its list is guarded by one mutex, a
 * job's immutable fields need no lock, and everything else about a job is read through
 * the scheduler (which has its own lock) or is atomic. */
#ifndef SRV_JOB_STORE_H
#define SRV_JOB_STORE_H

#include <cjson/cJSON.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "display.h"
#include "events.h"
#include "log.h"
#include "tessera.h"

/* The warnings of a scene's import (the pbrt-v3 importer's: "Integrator \"bdpt\": rendered
 * with the path integrator…"), each one sentence; at most SRV_WARNINGS_MAX are kept, the
 * rest only counted. Filled by srv_warnings_collect (a ts_warning_fn) while the scene loads,
 * immutable once the job is in the store. */
#define SRV_WARNINGS_MAX 64
typedef struct srv_warnings {
    char **items;
    int n;
    int dropped; /* beyond SRV_WARNINGS_MAX, or not kept for want of memory */
} srv_warnings;
/* Appends msg to the srv_warnings ctx (a ts_warning_fn, for ts_scene_load_pbrt_text). */
void srv_warnings_collect(void *ctx, const char *msg);
void srv_warnings_fini(srv_warnings *w);

typedef struct srv_job {
    atomic_int refs;
    /* immutable once the job is in the store */
    char id[24];
    char *name;                  /* may be NULL */
    char *scene_text;            /* the posted document (a bundle's scene file) */
    size_t scene_len;
    char *files_dir;             /* a bundle's folder (ROOT/jobs/<id>/files, bundle.h), or NULL */
    bool scene_pbrt;             /* scene_text is pbrt-v3 text (a bundle's scene.pbrt) */
    bool external;               /* a farm job (farm.h): rendered elsewhere, its scheduler job external */
    srv_warnings warnings;       /* what the scene's import warned about (a bundle's scene.pbrt) */
    srv_display *display;        /* streaming to a tev display server, or NULL (thread-safe itself) */
    char integrator[16];
    char effects[256];           /* "diffuse, area_lights, …" */
    ts_job_settings settings;    /* what the job renders: integrator, spp target, priority, halting bounds */
    double created_unix;
    int full_w, full_h, x0, y0, w, h, nx, ny;
    ts_sched_job *sj;
    srv_events *events;
    struct srv_store *store;     /* the store it was created in */
    char failure[512];           /* why a restored job failed, or "" */
    /* The last checkpoint's failure ("" when it was written): set by the maintenance
     * thread, read by status requests; guarded by ckpt_mu. */
    pthread_mutex_t ckpt_mu;
    char checkpoint_error[512];
    /* Serialises the job's files under --data (checkpoints and removal); removed is set
     * under it when the job has been deleted, after which nothing writes them again. */
    pthread_mutex_t disk_mu;
    bool removed;
    /* atomic: bumped whenever the pixels or the state change */
    atomic_uint_fast64_t version;
    atomic_bool started_logged;  /* the job.started line is written once */
    atomic_bool sched_ref;       /* the scheduler's callbacks hold a reference (dropped by on_done) */
    uint64_t saved_version;      /* maintenance thread only */
    double ckpt_backoff_s, ckpt_retry_at; /* failing checkpoints' retry (persist.c); maintenance thread only */
    /* The convergence series (GET …/history): a point at every pass end, once a second
     * while the job renders (srv_job_tick) and at the end; guarded by hist_mu. */
    pthread_mutex_t hist_mu;
    struct srv_history_point *hist;
    int n_hist, cap_hist;
    struct srv_job *next;        /* guarded by the store's mutex */
} srv_job;

typedef struct srv_store srv_store;

/* What a store needs: copied at creation (assets_dir must outlive the store). */
typedef struct srv_store_config {
    ts_scene_limits limits;   /* posted scenes: resolution and spp → 422, scene size → 413 */
    const char *assets_dir;   /* the only folder posted scenes may read files from; NULL = none */
    int max_jobs;             /* jobs held at once (any state); 0 = no limit */
    double max_work;          /* rays a job may ask for (ts_integrator_rays_per_sample × spp ×
                               * pixels) → 422 beyond; 0 = no limit */
    ts_scheduler *sched;      /* where jobs render */
    /* Optional: called (on a render thread, no lock held) when a job has finished, so a
     * checkpoint can follow soon. Must be quick. */
    void (*on_job_finished)(void *user);
    void *user;
    srv_log *log;             /* job events (submitted, started, pass, finished, restored); NULL: none */
    /* tev display server (display.h): every job streams to display_server when set; a
     * job's own job.display_server is refused (403) unless it names that same address or
     * allow_job_display_server is set (docs/security.md: a job must not make the server
     * connect to addresses its operator did not choose). */
    const char *display_server;
    bool allow_job_display_server;
    /* Optional: adds to an external (farm) job's status document what its owner knows
     * (farm.h's srv_farm_describe). */
    void (*describe)(void *user, srv_job *j, cJSON *status);
    void *describe_user;
} srv_store_config;

/* NULL when out of memory. */
srv_store *srv_store_create(const srv_store_config *cfg);
/* Sets cfg.describe_user (the farm, made after the store), before any request is served. */
void srv_store_set_describe_user(srv_store *st, void *user);
/* Releases every job (after the scheduler and HTTP daemon stopped). */
void srv_store_destroy(srv_store *st);

/* Loads, checks and queues a posted scene; file references resolve inside config.assets_dir
 * (none without it). On failure NULL, *http_status (400, 403 for a job.display_server this
 * server does not allow, 413, 422, 500, or 503 when the
 * store already holds config.max_jobs jobs — checked before the document is parsed) and
 * err's sentence say why. The returned job carries a reference for the caller. */
srv_job *srv_store_submit(srv_store *st, const char *text, size_t len, int *http_status, ts_error *err);
/* The same, with the name of a scene that has none (its file's: "cornell-box" for the
 * built-in one; srv_store_submit's is "scene"). The job's name: job.name, else the scene's
 * "name", else this one (ts_job_name, as `tessera render` names it). */
srv_job *srv_store_submit_named(srv_store *st, const char *text, size_t len, const char *name, int *http_status,
                                ts_error *err);

/* A posted bundle's scene (api.c, bundle.h): its scene file's text is loaded with the
 * folder the bundle was unpacked in as the base of every file it names; once the scene
 * loaded, that folder is renamed to files_root/jobs/<id>/files (the job's files_dir,
 * removed with the job). On failure the unpacked folder is left to the caller. */
typedef struct srv_submit_files {
    bool pbrt;                /* the scene file is scene.pbrt; else scene.json */
    const char *staging_dir;  /* where the bundle was unpacked */
    const char *files_root;   /* --data DIR, or the server's temporary folder */
    uint32_t spp;             /* the job's spp target (POST …?spp=N, the job.spp a scene.pbrt
                               * cannot hold; the sampler's spp stays the scene's), 0: the scene's */
    const char *name;         /* the bundle's name (POST …?name=, the page sends its file or folder
                               * name): the job's when its scene has none; NULL: "scene" */
} srv_submit_files;
srv_job *srv_store_submit_files(srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                                int *http_status, ts_error *err);
/* Either of the above (files NULL: a posted JSON document), the load stopped by cancel
 * (core/cancel.h; NULL: never): once it says stop, NULL with *http_status 422 when its
 * deadline passed (err says how long it had), else 503. */
srv_job *srv_store_submit_cancellable(srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                                      ts_cancel *cancel, int *http_status, ts_error *err);
/* False when the store holds config.max_jobs jobs (a hint before unpacking a bundle; the
 * submission itself decides). */
bool srv_store_has_room(srv_store *st);
/* A farm job (farm.h): loaded and checked like any other (files may be NULL: a JSON
 * document), but its scheduler job is external — nothing renders it here. */
srv_job *srv_store_submit_external(srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                                   ts_cancel *cancel, int *http_status, ts_error *err);

/* Restores a checkpointed job (persist.c): takes ownership of scene (may be NULL when
 * finished) and film; tile_spp per tile. Returns a new reference or NULL. */
typedef struct srv_restore {
    const char *id, *name, *scene_text;
    size_t scene_len;
    double created_unix, elapsed_s;
    uint64_t nonfinite, medium_steps, walks_truncated;
    ts_job_state state;          /* QUEUED/RUNNING: resume; else finished */
    ts_scene *scene;
    ts_film *film;               /* may be NULL: start from scratch */
    const uint32_t *tile_spp;
    const uint8_t *active;       /* an adaptive job's active pixels with the film, or NULL (ts_sched_job_desc) */
    uint32_t active_spp;
    ts_job_settings settings;    /* integrator: the scene's, or AO when there is none */
    const char *failure;         /* non-NULL: register as failed with this message */
    const cJSON *history;        /* the checkpoint's "history" array, or NULL */
    const char *files_dir;       /* a bundle job's folder (copied), or NULL */
    bool scene_pbrt;             /* scene_text is a bundle's scene.pbrt */
    srv_warnings *warnings;      /* the reloaded scene's import warnings (moved into the job), or NULL */
    bool external;               /* a farm job (its folder holds farm.json): never rendered here */
} srv_restore;
srv_job *srv_store_restore(srv_store *st, const srv_restore *r, ts_error *err);

/* A new reference to the job with that id, or NULL. */
srv_job *srv_store_get(srv_store *st, const char *id);
/* Takes a finished job out of the store (DELETE of a done, cancelled or failed job):
 * false if it was not listed. Holders of a reference keep it until they release it. */
bool srv_store_remove(srv_store *st, srv_job *j);
/* New references to all jobs, newest first; *n of them (caller frees the array). */
srv_job **srv_store_list(srv_store *st, int *n);
void srv_job_retain(srv_job *j);
void srv_job_release(srv_job *j);

/* The job's status document (proto/job-status.schema.json). Caller deletes. */
cJSON *srv_job_status_json(srv_job *j);
/* The progress event document. Caller deletes. */
/* One point of a job's convergence series. */
typedef struct srv_history_point {
    double elapsed_s, spp, error_estimate, samples_per_s; /* error < 0: unknown */
    char kind;                   /* 'p' pass end, 't' tick, 'd' done */
} srv_history_point;

#define SRV_HISTORY_MAX 4096     /* beyond, every other tick point is dropped */

/* Publishes a `progress` event and records a tick point if the job is running (the
 * maintenance thread calls it once a second). */
void srv_job_tick(srv_job *j);
/* {"id", "points": [{"elapsed_s", "spp", "error_estimate", "samples_per_s", "kind"}]}. */
cJSON *srv_job_history_json(srv_job *j);

/* The state a client sees: "failed" for a failed job, "cancelling" while a cancelled job's
 * last tiles finish, else the scheduler's ("queued", "running", "done", "cancelled"). */
const char *srv_job_state_name(const srv_job *j, const ts_job_progress *p);
cJSON *srv_job_progress_json(srv_job *j, const ts_job_progress *p);
/* The tile event document ({tx, ty, x, y, w, h, spp, png, exr}). Caller deletes. */
cJSON *srv_job_tile_json(const srv_job *j, const ts_tile_event *ev);
/* The whole SSE frame of that document ("event: tile\ndata: …\n\n", malloc'd; NULL when
 * out of memory): the same bytes as srv_events_format("tile", cJSON_PrintUnformatted of
 * srv_job_tile_json), printed directly, since a late subscriber's backlog makes one per
 * tile. */
char *srv_job_tile_event(const srv_job *j, const ts_tile_event *ev);
ts_job_state srv_job_state(srv_job *j);
/* Records why the job's checkpoint failed (NULL: it was written); true when that changed
 * the recorded state. Shown as `checkpoint_error` in the status. Thread-safe. */
bool srv_job_set_checkpoint_error(srv_job *j, const char *message);

#endif
