/* api.h — the routes of HTTP API v1 (docs/design.md §5, proto/openapi.yaml).
 *
 * Design note: one function picks the route (a template, for metrics) from the URL and
 * one answers a complete request. Handlers only read the store and the scheduler's
 * snapshots under short locks, parse posted scenes (bounded by the body cap), and defer
 * image encoding to the offload pool; SSE streams go to events.c. */
#ifndef SRV_API_H
#define SRV_API_H

#include "http.h"

struct srv_store;
struct srv_metrics;
struct srv_events_limits;
struct srv_persist_stats;
struct ts_scheduler;

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
} srv_api;

/* The handler table of API v1 over api (srv_http_start takes it). */
srv_http_handlers srv_api_handlers(srv_api *api);

/* The route template a URL falls under (for metrics and the fuzz harness). */
srv_route srv_api_route(const char *url);

#endif
