/* http.h — libmicrohttpd glue: the daemon, the per-request context, replies.
 *
 * Design note (STYLE.md's handler contract): the access handler allocates a srv_request
 * on its first call, consumes the body in chunks (up to cfg.max_body; beyond it the
 * request is answered 413), dispatches to api.c on the last call, and the completion
 * callback frees the context and counts the request for /metrics. Work a handler must not
 * do (encoding images) goes to the offload pool: srv_http_defer suspends the connection,
 * the task fills the reply and srv_http_complete resumes it; the handler, called again,
 * queues that reply. The daemon uses an internal polling thread pool (epoll/poll) with
 * suspend/resume. */
#ifndef SRV_HTTP_H
#define SRV_HTTP_H

#include <stdbool.h>
#include <stddef.h>

#include "metrics.h"
#include "serve.h"

struct MHD_Connection;
struct MHD_Response;

typedef struct srv_request {
    srv_server *srv;
    struct MHD_Connection *conn;
    const char *method, *url; /* valid during handler calls */
    char *body;
    size_t body_len, body_cap;
    bool body_too_large;
    srv_route route;
    unsigned status;          /* answered status, for metrics */
    /* deferred work: set by the task before srv_http_complete */
    bool deferred, completed;
    unsigned reply_status;
    const char *reply_type;
    unsigned char *reply_body; /* malloc'd; ownership passes to the response */
    size_t reply_len;
    char reply_disposition[128];
    void *task;               /* api.c's task state */
} srv_request;

typedef struct srv_http srv_http;

/* Starts the daemon on cfg.bind:cfg.port; *port_out gets the bound port. NULL with a
 * message in err on failure. */
srv_http *srv_http_start(srv_server *srv, int *port_out, char *err, size_t err_len);
/* Stops accepting connections (existing ones continue). */
void srv_http_quiesce(srv_http *h);
void srv_http_stop(srv_http *h);
/* Connections the daemon holds now (a request's completion callback has run once its
 * connection is no longer counted): for tests. */
unsigned srv_http_connections(srv_http *h);

/* Replies (from a handler). body is copied. Adds CORS headers when configured. */
int srv_http_reply(srv_request *r, unsigned status, const char *type, const void *body, size_t len);
/* Replies with a JSON document ({"error": message} for srv_http_error). */
int srv_http_reply_json(srv_request *r, unsigned status, const char *json);
int srv_http_error(srv_request *r, unsigned status, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* 405 with Allow. */
int srv_http_method_not_allowed(srv_request *r, const char *allow);
/* Queues a prepared response (takes ownership). */
int srv_http_queue(srv_request *r, unsigned status, struct MHD_Response *resp);

/* Suspends the connection and runs fn(r) on the offload pool; fn must end with
 * srv_http_complete(r). Returns the MHD result for the handler; answers 503 when the
 * pool refuses (shutting down). */
int srv_http_defer(srv_request *r, void (*fn)(void *r));
/* Marks the deferred reply ready and resumes the connection (from the task). */
void srv_http_complete(srv_request *r);

#endif
