/* http.h — libmicrohttpd glue: the daemon, the per-request context, replies.
 *
 * Design note (docs/style.md's handler contract): the access handler allocates a srv_request
 * on its first call, consumes the body in chunks (up to cfg.max_body; beyond it the
 * request is answered 413), dispatches to the handler table it was started with (the
 * routes of api.c, in the server) on the last call, and the completion callback lets the
 * handlers free what they attached, frees the context and counts the request for
 * /metrics. The HTTP layer knows nothing of jobs or of the server around it: it takes its
 * own configuration and an opaque `app` pointer that it hands to the handlers. Work a handler must not
 * do (encoding images) goes to the offload pool: srv_http_defer suspends the connection,
 * the task fills the reply and srv_http_complete resumes it; the handler, called again,
 * queues that reply. The daemon uses an internal polling thread pool (epoll/poll) with
 * suspend/resume. Besides libmicrohttpd's idle timeout (client_timeout_s), a thread of
 * this layer holds every request to a deadline for its headers and body
 * (request_timeout_s), so a client that trickles bytes cannot keep a connection forever. */
#ifndef SRV_HTTP_H
#define SRV_HTTP_H

#include <stdbool.h>
#include <stddef.h>

#include "metrics.h"

struct MHD_Connection;
struct MHD_Response;
struct srv_offload;

typedef struct srv_http srv_http;

typedef struct srv_request {
    srv_http *http;           /* the daemon answering it */
    void *app;                /* the handler table's app pointer */
    struct MHD_Connection *conn;
    const char *method, *url; /* valid during handler calls */
    char *body;
    size_t body_len, body_cap;
    bool body_too_large;
    size_t max_body;          /* this request's body cap (config.max_body, or max_bundle_body) */
    srv_route route;
    unsigned status;          /* answered status, for metrics */
    double t_start;           /* monotonic seconds at its first call, for the log */
    char log_method[8];       /* kept for the completion log line */
    char log_url[160];
    /* deferred work: set by the task before srv_http_complete */
    bool deferred, completed;
    unsigned reply_status;
    const char *reply_type;
    unsigned char *reply_body; /* malloc'd; ownership passes to the response */
    size_t reply_len;
    char reply_disposition[128];
    char reply_location[96];  /* a Location header, or "" */
    void *task;               /* api.c's task state */
} srv_request;

/* What the daemon needs to know; copied at start (strings must outlive the daemon). */
typedef struct srv_http_config {
    const char *bind;            /* numeric IPv4 or IPv6 address */
    int port;                    /* 0 = any free port */
    int threads;                 /* libmicrohttpd's thread pool */
    unsigned client_timeout_s;   /* a connection idle this long is closed (0: 60 s) */
    unsigned request_timeout_s;  /* a request's headers and body must arrive within this long of the
                                  * connection's start or its previous answer, else it is closed (0: 60 s) */
    unsigned max_client_conns;   /* connections from one address at once */
    size_t max_body;             /* request body cap, bytes (413 beyond) */
    const char *cors_origin;     /* NULL = no CORS headers */
    struct srv_metrics *metrics; /* every answer is counted here */
    struct srv_offload *offload; /* the pool srv_http_defer runs tasks on */
    struct srv_log *log;         /* every request at debug level (method, URL, status, time); NULL: none */
    size_t max_bundle_body;      /* the cap of a body sent as a bundle (srv_bundle_media_type); 0: max_body */
} srv_http_config;

/* The routes: `route` names a URL's route (for metrics) on a request's first call,
 * `handle` answers a complete request (returns an MHD_Result), `done` frees what handle
 * attached (once the request is over; may be NULL). Called on the daemon's threads. */
typedef struct srv_http_handlers {
    srv_route (*route)(const char *url);
    int (*handle)(srv_request *r);
    void (*done)(srv_request *r);
    void *app; /* given to the handlers as r->app */
} srv_http_handlers;

/* Starts the daemon on cfg->bind:cfg->port; *port_out gets the bound port. NULL with a
 * message in err on failure. */
srv_http *srv_http_start(const srv_http_config *cfg, const srv_http_handlers *handlers, int *port_out, char *err,
                         size_t err_len);
/* Stops accepting connections (existing ones continue). */
void srv_http_quiesce(srv_http *h);
void srv_http_stop(srv_http *h);
/* Connections the daemon holds now (a request's completion callback has run once its
 * connection is no longer counted): for tests. */
unsigned srv_http_connections(srv_http *h);

/* The daemon's configuration (immutable while it runs). */
const srv_http_config *srv_http_config_of(const srv_http *h);

/* Replies (from a handler). body is copied. Adds CORS headers when configured. */
int srv_http_reply(srv_request *r, unsigned status, const char *type, const void *body, size_t len);
/* Replies with a JSON document. srv_http_error, srv_http_set_error and srv_http_error_header
 * write every error body of the server the one way: {"error": the message (valid UTF-8,
 * escaped by cJSON), "status": status}; out of memory, a 500 of the same shape. */
int srv_http_reply_json(srv_request *r, unsigned status, const char *json);
int srv_http_error(srv_request *r, unsigned status, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* For a deferred task: sets the reply to that error document (as srv_http_error's). */
void srv_http_set_error(srv_request *r, unsigned status, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* The error document with one more header (header: value), e.g. 401's WWW-Authenticate. */
int srv_http_error_header(srv_request *r, unsigned status, const char *header, const char *value, const char *fmt,
                          ...) __attribute__((format(printf, 5, 6)));
/* 405 with Allow. */
int srv_http_method_not_allowed(srv_request *r, const char *allow);
/* Queues a prepared response (takes ownership). */
int srv_http_queue(srv_request *r, unsigned status, struct MHD_Response *resp);

/* Suspends the connection and runs fn(r) on the offload pool; fn must end with
 * srv_http_complete(r). Returns the MHD result for the handler; answers 503 when the
 * pool refuses (shutting down). */
int srv_http_defer(srv_request *r, void (*fn)(void *r));
/* The same on another pool (the loaders, offload.h). */
int srv_http_defer_to(srv_request *r, struct srv_offload *pool, void (*fn)(void *r));
/* The same, and if the task still waits in the pool's queue at deadline (monotonic
 * seconds), expired(r) runs instead of fn (it too must end with srv_http_complete). */
int srv_http_defer_bounded(srv_request *r, struct srv_offload *pool, void (*fn)(void *r), void (*expired)(void *r),
                           double deadline);
/* Marks the deferred reply ready and resumes the connection (from the task). */
void srv_http_complete(srv_request *r);

#endif
