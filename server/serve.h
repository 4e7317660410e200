/* serve.h — `tessera serve`: the render server of DESIGN.md §5 (proto/openapi.yaml).
 *
 * Design note: one srv_server value holds everything the server shares between threads
 * (DESIGN.md §6: no global mutable state outside the job store): the configuration
 * (immutable after start), the render scheduler, the job store, metrics, the encoder
 * pool and the HTTP daemon. main() blocks SIGINT/SIGTERM and waits for them with
 * sigwait; a maintenance thread checkpoints (--data) and sends SSE keep-alives on a
 * condition variable's timed wait. */
#ifndef SRV_SERVE_H
#define SRV_SERVE_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "tessera.h"

typedef struct srv_config {
    const char *bind;            /* "127.0.0.1" */
    int port;                    /* 8080; 0 = any free port */
    int threads;                 /* render threads */
    int max_running;             /* jobs rendering at once */
    int http_threads;            /* libmicrohttpd thread pool */
    unsigned client_timeout_s;   /* a connection idle this long is closed */
    unsigned max_client_conns;   /* connections from one IP address at once; more are refused */
    const char *data_dir;        /* NULL = no persistence */
    const char *token;           /* NULL = no auth; never printed or logged */
    const char *assets_dir;      /* --assets: the only folder posted scenes may read; NULL = none */
    int max_jobs;                /* jobs held in the store (any state); a POST beyond: 503 */
    const char *cors_origin;     /* NULL = no CORS headers */
    size_t max_body;             /* request body cap, bytes */
    double checkpoint_interval_s;
    ts_scene_limits limits;      /* resolution, spp, scene size; max_file_bytes: --max-asset-bytes */
    bool queue_builtin;          /* queue the Cornell box at start (make run) */
} srv_config;

struct srv_store;
struct srv_metrics;
struct srv_offload;
struct srv_http;
struct ts_scheduler;

typedef struct srv_server {
    srv_config cfg;                 /* immutable after start */
    struct ts_scheduler *sched;
    struct srv_store *store;
    struct srv_metrics *metrics;
    struct srv_offload *offload;
    struct srv_http *http;
    /* maintenance thread */
    pthread_mutex_t mu;
    pthread_cond_t cv;              /* kicks: stop, or a job finished (checkpoint soon) */
    bool stopping, kick;            /* guarded by mu */
} srv_server;

/* Wakes the maintenance thread to checkpoint now (a job finished). Thread-safe. */
void srv_server_kick(srv_server *srv);

/* `tessera serve [options]`: runs until SIGINT/SIGTERM; returns the exit status. */
int srv_serve_main(int argc, char **argv);

#endif
