/* api.h — the routes of HTTP API v1 (docs/design.md §5, proto/openapi.yaml).
 *
 * Design note: one function picks the route (a template, for metrics) from the URL and
 * one answers a complete request. Handlers only read the store and the scheduler's
 * snapshots under short locks, parse posted scenes (bounded by the body cap), and defer
 * image encoding to the offload pool; SSE streams go to events.c. */
#ifndef SRV_API_H
#define SRV_API_H

#include <stdatomic.h>
#include <stdint.h>

#include "http.h"

struct srv_store;
struct srv_metrics;
struct srv_events_limits;
struct srv_persist_stats;
struct srv_offload;
struct ts_scheduler;

/* The loads of posted scenes (JSON and bundles): counters for /metrics. */
typedef struct srv_load_stats {
    atomic_ullong started;   /* loads begun on a loader thread */
    atomic_ullong timed_out; /* stopped at --max-load-seconds, or whose time ran out while queued */
    atomic_ullong cancelled; /* stopped by the server's shutdown */
} srv_load_stats;

/* How long a pool's task may run before /healthz calls the pool stuck: an encoder's (an
 * image of the largest film takes a few seconds), a loader's beyond --max-load-seconds
 * (what a load may take between two polls of its ts_cancel). */
#define SRV_ENCODE_BOUND_S 60.0
#define SRV_LOAD_GRACE_S 5.0

/* What the routes read: the server's parts and the settings that concern them. Owned by
 * the caller; must outlive the HTTP daemon that uses it. */
typedef struct srv_api {
    const char *token;        /* NULL = no auth; never printed or logged */
    const char *data_dir;     /* --data, or NULL: accepted jobs are written there */
    const char *cors_origin;  /* NULL = no CORS preflight answers */
    const char *bind;         /* the address the server listens on: the Host names it answers */
    const char *allowed_hosts; /* --allowed-hosts: more Host names, comma-separated; or NULL */
    struct srv_store *store;
    struct ts_scheduler *sched;
    struct srv_metrics *metrics;
    struct srv_events_limits *sse_limits; /* event-stream subscriber caps */
    struct srv_persist_stats *persist;    /* checkpoint counters (--data), or NULL */
    /* Bundles (POST of a tar, bundle.h): their limits, and the folder under which jobs'
     * files go (incoming/ while unpacking, jobs/<id>/files after): --data, or the server's
     * temporary folder. NULL: bundles are refused (415). */
    const struct srv_bundle_limits *bundle;
    struct srv_bundle_root *files_root;
    /* Loading posted scenes, off the HTTP threads: the loader pool, each load's bound
     * (--max-load-seconds, from the request's arrival; queueing counts), the flag the
     * shutdown sets to stop every load, and the counters. The encoder pool, for /healthz. */
    struct srv_offload *loaders, *encoders;
    double max_load_s;
    const atomic_bool *loads_stop;
    srv_load_stats *loads;
    /* What GET /api/v1/limits answers (v1.4): the limits a posted job is checked against,
     * so a client (the web UI's form) can say them before posting. */
    struct srv_api_limits {
        uint32_t max_spp, max_resolution;
        uint64_t max_pixels, max_body, max_bundle_bytes;
        double max_work; /* 0: none */
    } limits;
    struct srv_farm *farm;    /* --farm (farm.h), or NULL: a farm job is 422 */
} srv_api;

/* The handler table of API v1 over api (srv_http_start takes it). */
srv_http_handlers srv_api_handlers(srv_api *api);

/* The route template a URL falls under (for metrics and the fuzz harness). */
srv_route srv_api_route(const char *url);

#endif
