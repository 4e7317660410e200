/* serve.h — `tessera serve`: the render server of docs/design.md §5 (proto/openapi.yaml).
 *
 * Design note: one srv_server value holds everything the server shares between threads
 * (docs/design.md §6: no global mutable state outside the job store): the configuration
 * (immutable after start), the render scheduler, the job store, metrics, the encoder
 * pool and the HTTP daemon. srv_serve_main blocks SIGINT/SIGTERM and waits for them
 * with sigwait; a maintenance thread checkpoints (--data) and sends SSE keep-alives and, once a second,
 * running jobs' progress events and history points, on a
 * condition variable's timed wait. */
#ifndef SRV_SERVE_H
#define SRV_SERVE_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "api.h"
#include "bundle.h"
#include "farm.h"
#include "http.h"
#include "job_store.h"
#include "log.h"
#include "metrics.h"
#include "offload.h"
#include "persist.h"
#include "tessera.h"

typedef struct srv_config {
    const char *bind;            /* "127.0.0.1" */
    int port;                    /* 8080; 0 = any free port */
    int threads;                 /* render threads */
    int max_running;             /* jobs rendering at once */
    int http_threads;            /* libmicrohttpd thread pool */
    unsigned client_timeout_s;   /* a connection idle this long is closed */
    unsigned request_timeout_s;  /* a request's headers and body must arrive within this long */
    unsigned max_client_conns;   /* connections from one IP address at once; more are refused */
    const char *data_dir;        /* NULL = no persistence */
    const char *token;           /* NULL = no auth; never printed or logged */
    const char *assets_dir;      /* --assets: the only folder posted scenes may read; NULL = none */
    int max_jobs;                /* jobs held in the store (any state); a POST beyond: 503 */
    double max_work;             /* rays one job may ask for; a POST beyond: 422 */
    int max_subscribers;         /* event streams at once, all jobs; beyond: 503 */
    int max_job_subscribers;     /* event streams of one job at once; beyond: 503 */
    const char *cors_origin;     /* NULL = no CORS headers */
    const char *allowed_hosts;   /* Host names answered besides the bind address; comma-separated; NULL = none */
    size_t max_body;             /* request body cap, bytes */
    double checkpoint_interval_s;
    ts_scene_limits limits;      /* resolution, spp, scene size; max_file_bytes: --max-asset-bytes */
    bool queue_builtin;          /* queue the Cornell box at start (make run) */
    const char *display_server;  /* --display-server HOST:PORT: every job streams to tev there; NULL = none */
    bool allow_job_display_server; /* --allow-job-display-server: a job's job.display_server may name any address */
    srv_log_format log_format;   /* --log-format text|json */
    srv_log_level log_level;     /* --log-level: info (job events) by default, debug adds requests */
    srv_bundle_limits bundle;    /* --max-bundle-*: posted tar bundles (bundle.h) */
    double max_load_s;           /* --max-load-seconds: a posted scene's load, from its arrival */
    srv_farm_options farm;       /* --farm, --farm-*, --max-shards (farm.h) */
} srv_config;

typedef struct srv_server {
    srv_config cfg;                 /* immutable after start */
    ts_scheduler *sched;
    srv_store *store;
    srv_metrics *metrics;
    srv_offload *offload;           /* the encoders (images, tiles) */
    srv_offload *loaders;           /* posted scenes and bundles (offload.h) */
    atomic_bool loads_stop;         /* set first at shutdown: every load stops (core/cancel.h) */
    srv_load_stats loads;           /* their counters (atomics) */
    srv_http *http;
    srv_api api;                    /* what the routes read; immutable after start */
    srv_log log;                    /* job events and (at debug) requests, to stderr */
    char builtin_job[24];           /* the id of the queued built-in scene (--queue-builtin), or "" */
    srv_events_limits sse_limits;   /* caps from cfg; its count is atomic */
    srv_persist_stats persist;      /* checkpoint and restore counters (atomics) */
    srv_bundle_root files_root;     /* where bundles' files go (bundle.h); thread-safe itself */
    srv_farm *farm;                 /* --farm: farm jobs on Slurm (farm.h), or NULL */
    bool files_root_made;           /* files_root initialised (start) */
    /* maintenance thread */
    pthread_t maint;
    bool maint_started;
    pthread_mutex_t mu;
    pthread_cond_t cv;              /* kicks: stop, or a job finished (checkpoint soon) */
    bool stopping, kick;            /* guarded by mu */
} srv_server;

/* Starts a server whose cfg is filled in (the rest of *srv zeroed): the render scheduler,
 * the job store (restoring --data, queueing the built-in scene if asked), the encoder
 * pool, the maintenance thread and the HTTP daemon; *port_out gets the bound port. Start-up
 * notes go to stderr. On failure returns false with a sentence in err, and whatever was
 * started is stopped again (srv_server_stop is not needed then). */
bool srv_server_start(srv_server *srv, int *port_out, char *err, size_t err_len);

/* Stops a started server in order: no new connections, the maintenance thread, the render
 * workers after their current tiles, a final checkpoint of every changed job when
 * `checkpoint` (and --data), the event streams, the encoders, the daemon; then frees it. */
void srv_server_stop(srv_server *srv, bool checkpoint);

/* `tessera serve [options]`: runs until SIGINT/SIGTERM; returns the exit status. */
int srv_serve_main(int argc, char **argv);

#endif
