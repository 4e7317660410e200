/* http.c — libmicrohttpd glue; see http.h. */
#include "http.h"
#include "bundle.h"

#include <arpa/inet.h>
#include <cjson/cJSON.h>
#include <math.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "log.h"
#include "offload.h"

/* One open connection, for the request deadline: while a request's headers and body are
 * arriving it must be complete by `deadline`, however the bytes trickle in (libmicrohttpd's
 * own timeout is an idle timer, which a byte every few seconds resets). */
typedef struct conn_entry {
    int fd;                      /* immutable; valid until the CLOSED notification */
    double deadline;             /* monotonic seconds; 0 while answering; guarded by conns_mu */
    bool cut;                    /* guarded by conns_mu */
    struct conn_entry *prev, *next; /* guarded by conns_mu */
} conn_entry;

struct srv_http {
    struct MHD_Daemon *d;
    srv_http_config cfg;         /* immutable */
    srv_http_handlers handlers;  /* immutable */
    /* The deadline thread: cuts connections whose request is late (shutdown(2) of the
     * socket; libmicrohttpd then closes it). An entry leaves the list in the CLOSED
     * notification, which libmicrohttpd sends before it closes the descriptor, so under
     * conns_mu every listed fd is still the connection's. */
    pthread_mutex_t conns_mu;
    pthread_cond_t conns_cv;
    conn_entry *conns;           /* guarded by conns_mu */
    bool stopping;               /* guarded by conns_mu */
    pthread_t deadline_thread;
    bool deadline_started;
    MHD_socket quiesced_fd;      /* the listen socket after srv_http_quiesce, closed at stop */
};

static double mono_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double request_timeout(const srv_http *h) { return h->cfg.request_timeout_s ? h->cfg.request_timeout_s : 60.0; }

/* Sets the deadline of conn's current request (0: none, its answer is being sent). */
static void set_deadline(srv_http *h, struct MHD_Connection *conn, double deadline)
{
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    conn_entry *c = ci ? ci->socket_context : NULL;
    if (!c) return;
    pthread_mutex_lock(&h->conns_mu);
    c->deadline = deadline;
    pthread_mutex_unlock(&h->conns_mu);
}

static void notify_connection(void *cls, struct MHD_Connection *conn, void **socket_context,
                              enum MHD_ConnectionNotificationCode code)
{
    srv_http *h = cls;
    if (code == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
        conn_entry *c = ci ? calloc(1, sizeof *c) : NULL;
        if (!c) return; /* not tracked: only the idle timeout applies */
        c->fd = ci->connect_fd;
        pthread_mutex_lock(&h->conns_mu);
        c->deadline = mono_now() + request_timeout(h);
        c->next = h->conns;
        if (h->conns) h->conns->prev = c;
        h->conns = c;
        pthread_mutex_unlock(&h->conns_mu);
        *socket_context = c;
    } else if (code == MHD_CONNECTION_NOTIFY_CLOSED && *socket_context) {
        conn_entry *c = *socket_context;
        pthread_mutex_lock(&h->conns_mu);
        if (c->prev) c->prev->next = c->next;
        else h->conns = c->next;
        if (c->next) c->next->prev = c->prev;
        pthread_mutex_unlock(&h->conns_mu);
        free(c);
        *socket_context = NULL;
    }
}

static void *deadline_main(void *arg)
{
    srv_http *h = arg;
    pthread_mutex_lock(&h->conns_mu);
    while (!h->stopping) {
        double now = mono_now(), next = now + 1.0;
        for (conn_entry *c = h->conns; c; c = c->next) {
            if (c->deadline <= 0 || c->cut) continue;
            if (c->deadline <= now) {
                shutdown(c->fd, SHUT_RDWR);
                c->cut = true;
                srv_metrics_count_deadline_cut(h->cfg.metrics);
            } else if (c->deadline < next) {
                next = c->deadline;
            }
        }
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        double wait = next - now, whole = floor(wait);
        ts.tv_sec += (time_t)whole;
        ts.tv_nsec += (long)((wait - whole) * 1e9);
        if (ts.tv_nsec >= 1000000000L) ts.tv_sec++, ts.tv_nsec -= 1000000000L;
        pthread_cond_timedwait(&h->conns_cv, &h->conns_mu, &ts);
    }
    pthread_mutex_unlock(&h->conns_mu);
    return NULL;
}

const srv_http_config *srv_http_config_of(const srv_http *h) { return &h->cfg; }

static void add_common_headers(srv_request *r, struct MHD_Response *resp)
{
    const srv_http_config *cfg = &r->http->cfg;
    if (cfg->cors_origin) {
        MHD_add_response_header(resp, "Access-Control-Allow-Origin", cfg->cors_origin);
        MHD_add_response_header(resp, "Vary", "Origin");
    }
    MHD_add_response_header(resp, "Cache-Control", "no-store");
}

int srv_http_queue(srv_request *r, unsigned status, struct MHD_Response *resp)
{
    if (!resp) return MHD_NO;
    add_common_headers(r, resp);
    r->status = status;
    /* Counted when queued, so a client's next request already sees it in /metrics. */
    srv_metrics_count(r->http->cfg.metrics, r->route, status);
    enum MHD_Result ret = MHD_queue_response(r->conn, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

int srv_http_reply(srv_request *r, unsigned status, const char *type, const void *body, size_t len)
{
    struct MHD_Response *resp = MHD_create_response_from_buffer(len, (void *)body, MHD_RESPMEM_MUST_COPY);
    if (!resp) return MHD_NO;
    if (type) MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, type);
    return srv_http_queue(r, status, resp);
}

int srv_http_reply_json(srv_request *r, unsigned status, const char *json)
{
    return srv_http_reply(r, status, "application/json", json, strlen(json));
}

/* Copies s into out (out_len > 0) as valid UTF-8: each byte that does not start a
 * complete, shortest-form sequence becomes U+FFFD; stops at a character boundary when out
 * is full. Error sentences quote the client's URL and scene text and are cut to fit
 * buffers, possibly inside a character; JSON must be UTF-8 (RFC 8259). */
static void utf8_clean(const char *s, char *out, size_t out_len)
{
    const unsigned char *u = (const unsigned char *)s;
    size_t at = 0;
    while (*u) {
        unsigned c = u[0];
        size_t n = c < 0x80 ? 1 : c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : 0;
        if (c >= 0xf0 && c <= 0xf4) n = 4;
        for (size_t i = 1; i < n; i++)
            if ((u[i] & 0xc0) != 0x80) n = 0;
        /* overlong forms, UTF-16 surrogates, beyond U+10FFFF */
        if ((n == 3 && ((c == 0xe0 && u[1] < 0xa0) || (c == 0xed && u[1] >= 0xa0))) ||
            (n == 4 && ((c == 0xf0 && u[1] < 0x90) || (c == 0xf4 && u[1] >= 0x90))))
            n = 0;
        const char *src = n ? (const char *)u : "\xef\xbf\xbd";
        size_t len = n ? n : 3;
        if (at + len >= out_len) break;
        memcpy(out + at, src, len);
        at += len;
        u += n ? n : 1;
    }
    out[at] = '\0';
}

/* The one error body of every reply: {"error": the message as valid UTF-8, "status": status},
 * malloc'd; NULL when out of memory (the caller then answers 500 with OOM_BODY). */
#define OOM_BODY "{\"error\":\"out of memory\",\"status\":500}"
static char *error_body(unsigned status, const char *fmt, va_list ap)
{
    char text[1024], msg[1024];
    vsnprintf(text, sizeof text, fmt, ap);
    utf8_clean(text, msg, sizeof msg);
    cJSON *o = cJSON_CreateObject();
    char *s = NULL;
    if (o && cJSON_AddStringToObject(o, "error", msg) && cJSON_AddNumberToObject(o, "status", status))
        s = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    return s;
}

/* Sets r's reply to body (taken), or to the out-of-memory 500 when body is NULL. */
static void set_json_reply(srv_request *r, unsigned status, char *body)
{
    free(r->reply_body);
    r->reply_status = body ? status : 500;
    r->reply_type = "application/json";
    r->reply_body = (unsigned char *)(body ? body : strdup(OOM_BODY));
    r->reply_len = r->reply_body ? strlen((char *)r->reply_body) : 0;
}

void srv_http_set_error(srv_request *r, unsigned status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *s = error_body(status, fmt, ap);
    va_end(ap);
    set_json_reply(r, status, s);
}

int srv_http_error(srv_request *r, unsigned status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *s = error_body(status, fmt, ap);
    va_end(ap);
    int ret = srv_http_reply_json(r, s ? status : 500, s ? s : OOM_BODY);
    free(s);
    return ret;
}

int srv_http_error_header(srv_request *r, unsigned status, const char *header, const char *value, const char *fmt,
                          ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *msg = error_body(status, fmt, ap);
    va_end(ap);
    if (!msg) return MHD_NO;
    struct MHD_Response *resp = MHD_create_response_from_buffer(strlen(msg), msg, MHD_RESPMEM_MUST_FREE);
    if (!resp) {
        free(msg);
        return MHD_NO;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "application/json");
    MHD_add_response_header(resp, header, value);
    return srv_http_queue(r, status, resp);
}

int srv_http_method_not_allowed(srv_request *r, const char *allow)
{
    /* The method is the client's: through cJSON, so quotes and backslashes in it are escaped
     * (found by tests/fuzz/fuzz_http.c). */
    return srv_http_error_header(r, 405, MHD_HTTP_HEADER_ALLOW, allow, "method %s is not allowed here; allowed: %s",
                                 r->method, allow);
}


typedef struct deferred { srv_request *r; void (*fn)(void *), (*expired)(void *); } deferred;

static void run_deferred(void *arg)
{
    deferred *d = arg;
    d->fn(d->r);
    free(d);
}

static void run_expired(void *arg)
{
    deferred *d = arg;
    d->expired(d->r);
    free(d);
}

int srv_http_defer(srv_request *r, void (*fn)(void *r)) { return srv_http_defer_to(r, r->http->cfg.offload, fn); }

int srv_http_defer_to(srv_request *r, struct srv_offload *pool, void (*fn)(void *r))
{
    return srv_http_defer_bounded(r, pool, fn, NULL, 0);
}

int srv_http_defer_bounded(srv_request *r, struct srv_offload *pool, void (*fn)(void *r), void (*expired)(void *r),
                           double deadline)
{
    deferred *d = malloc(sizeof *d);
    if (!d) return srv_http_error(r, 500, "out of memory");
    d->r = r;
    d->fn = fn;
    d->expired = expired;
    r->deferred = true;
    r->completed = false;
    MHD_suspend_connection(r->conn);
    if (!srv_offload_submit_bounded(pool, run_deferred, expired ? run_expired : NULL, d, deadline)) {
        free(d);
        srv_http_set_error(r, 503, "the server is shutting down");
        srv_http_complete(r);
    }
    return MHD_YES;
}

void srv_http_complete(srv_request *r)
{
    r->completed = true;
    MHD_resume_connection(r->conn);
}

static int reply_deferred(srv_request *r)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(r->reply_len, r->reply_body ? r->reply_body : (void *)"", r->reply_body ? MHD_RESPMEM_MUST_FREE : MHD_RESPMEM_PERSISTENT);
    if (!resp) return MHD_NO;
    r->reply_body = NULL; /* the response frees it */
    if (r->reply_type) MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, r->reply_type);
    if (r->reply_disposition[0]) MHD_add_response_header(resp, "Content-Disposition", r->reply_disposition);
    if (r->reply_location[0]) MHD_add_response_header(resp, MHD_HTTP_HEADER_LOCATION, r->reply_location);
    return srv_http_queue(r, r->reply_status, resp);
}

/* libmicrohttpd would percent-decode the path and the query arguments before the handler
 * sees them, so "%2f" became a '/' and "%00" cut a string short before routing: the URL
 * is kept as sent, and what needs decoding (the access_token argument) is decoded by the
 * code that reads it, with its length. */
static size_t keep_escaped(void *cls, struct MHD_Connection *conn, char *s)
{
    (void)cls, (void)conn;
    return strlen(s);
}

static enum MHD_Result count_content_length(void *cls, enum MHD_ValueKind kind, const char *key, const char *value)
{
    (void)kind, (void)value;
    if (key && !strcasecmp(key, MHD_HTTP_HEADER_CONTENT_LENGTH)) ++*(int *)cls;
    return MHD_YES;
}

/* tessera's own limits on a request's head, answered with JSON 414/431 (docs/security.md):
 * well inside libmicrohttpd's per-connection memory (HTTP_CONNECTION_MEMORY), which a
 * request line plus headers must fit in; only a head larger than that gets the library's
 * own HTML answer, sent before tessera sees the request. */
#define HTTP_MAX_URI 8192
#define HTTP_MAX_HEADERS 8192
#define HTTP_CONNECTION_MEMORY 32768

static enum MHD_Result add_value_bytes(void *cls, enum MHD_ValueKind kind, const char *key, const char *value)
{
    (void)kind;
    /* "key: value\r\n" for a header, "key=value&" for a query argument */
    *(size_t *)cls += (key ? strlen(key) : 0) + (value ? strlen(value) : 0) + 4;
    return MHD_YES;
}

static enum MHD_Result handler(void *cls, struct MHD_Connection *conn, const char *url, const char *method,
                               const char *version, const char *upload, size_t *upload_size, void **con_cls)
{
    (void)version;
    srv_http *h = cls;
    srv_request *r = *con_cls;
    if (!r) {
        r = calloc(1, sizeof *r);
        if (!r) return MHD_NO;
        r->http = h;
        r->app = h->handlers.app;
        r->conn = conn;
        if (srv_log_enabled(h->cfg.log, SRV_LOG_DEBUG)) {
            struct timespec t;
            clock_gettime(CLOCK_MONOTONIC, &t);
            r->t_start = (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
            snprintf(r->log_method, sizeof r->log_method, "%s", method);
            snprintf(r->log_url, sizeof r->log_url, "%s", url);
        }
        r->route = h->handlers.route(url);
        *con_cls = r;
        size_t uri_bytes = strlen(url), header_bytes = 0;
        MHD_get_connection_values(conn, MHD_GET_ARGUMENT_KIND, add_value_bytes, &uri_bytes);
        MHD_get_connection_values(conn, MHD_HEADER_KIND, add_value_bytes, &header_bytes);
        if (uri_bytes > HTTP_MAX_URI || header_bytes > HTTP_MAX_HEADERS) {
            r->method = method, r->url = "";
            r->body_too_large = true; /* discard the body */
            if (uri_bytes > HTTP_MAX_URI)
                return (enum MHD_Result)srv_http_error(r, 414, "the request's URL (about %zu bytes) is longer than the limit of %d bytes",
                                                       uri_bytes, HTTP_MAX_URI);
            return (enum MHD_Result)srv_http_error(r, 431, "the request's headers (about %zu bytes) are larger than the limit of %d bytes",
                                                   header_bytes, HTTP_MAX_HEADERS);
        }
        int n_cl = 0;
        MHD_get_connection_values(conn, MHD_HEADER_KIND, count_content_length, &n_cl);
        if (n_cl > 1) { /* which one frames the body? (request smuggling) */
            r->method = method, r->url = url;
            r->body_too_large = true; /* discard the body */
            return (enum MHD_Result)srv_http_error(r, 400, "the request has %d Content-Length headers; send one", n_cl);
        }
        /* A bundle (a tar of a scene with its files, bundle.h) has a cap of its own. */
        r->max_body = h->cfg.max_body;
        if (h->cfg.max_bundle_body &&
            srv_bundle_media_type(MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE)))
            r->max_body = h->cfg.max_bundle_body;
        const char *cl = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
        if (cl && strtoull(cl, NULL, 10) > r->max_body) {
            r->method = method, r->url = url;
            r->body_too_large = true;
            return (enum MHD_Result)srv_http_error(r, 413, "the request body (%s bytes) is larger than the limit of %zu bytes",
                                                   cl, r->max_body);
        }
        return MHD_YES;
    }
    r->method = method;
    r->url = url;
    if (r->deferred) {
        if (!r->completed) return MHD_YES;
        return (enum MHD_Result)reply_deferred(r);
    }
    if (*upload_size) {
        size_t n = *upload_size;
        *upload_size = 0;
        if (r->body_too_large || r->body_len + n > r->max_body) {
            r->body_too_large = true;
            return MHD_YES; /* keep reading, discard */
        }
        if (r->body_len + n + 1 > r->body_cap) {
            size_t cap = r->body_cap ? r->body_cap : 16384;
            while (cap < r->body_len + n + 1) cap *= 2;
            char *b = realloc(r->body, cap);
            if (!b) return MHD_NO;
            r->body = b;
            r->body_cap = cap;
        }
        memcpy(r->body + r->body_len, upload, n);
        r->body_len += n;
        r->body[r->body_len] = '\0';
        return MHD_YES;
    }
    set_deadline(h, conn, 0); /* the whole request is in: from here only the idle timeout */
    if (r->body_too_large)
        return (enum MHD_Result)srv_http_error(r, 413, "the request body is larger than the limit of %zu bytes",
                                               r->max_body);
    return (enum MHD_Result)h->handlers.handle(r);
}

static void completed(void *cls, struct MHD_Connection *conn, void **con_cls, enum MHD_RequestTerminationCode toe)
{
    srv_http *h = cls;
    /* A kept-alive connection's next request has the deadline from now. */
    set_deadline(h, conn, mono_now() + request_timeout(h));
    srv_request *r = *con_cls;
    if (!r) return;
    if (h->handlers.done) h->handlers.done(r);
    if (srv_log_enabled(h->cfg.log, SRV_LOG_DEBUG)) {
        struct timespec t;
        clock_gettime(CLOCK_MONOTONIC, &t);
        double ms = 1e3 * ((double)t.tv_sec + 1e-9 * (double)t.tv_nsec - r->t_start);
        srv_log_field f[] = {SRV_LOG_STR("method", r->log_method), SRV_LOG_STR("url", r->log_url),
                             SRV_LOG_NUM("status", r->status), SRV_LOG_NUM("ms", ms),
                             SRV_LOG_STR("end", toe == MHD_REQUEST_TERMINATED_COMPLETED_OK ? "ok" : "aborted")};
        srv_log_event(h->cfg.log, SRV_LOG_DEBUG, "http.request", f, sizeof f / sizeof *f);
    }
    free(r->body);
    free(r->reply_body);
    free(r);
    *con_cls = NULL;
}

srv_http *srv_http_start(const srv_http_config *cfg, const srv_http_handlers *handlers, int *port_out, char *err,
                         size_t err_len)
{
    srv_http *h = calloc(1, sizeof *h);
    if (!h) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    h->cfg = *cfg;
    h->handlers = *handlers;
    h->quiesced_fd = MHD_INVALID_SOCKET;
    pthread_mutex_init(&h->conns_mu, NULL);
    pthread_cond_init(&h->conns_cv, NULL);
    struct sockaddr_storage ss;
    memset(&ss, 0, sizeof ss);
    const char *bind = h->cfg.bind;
    if (strchr(bind, ':')) {
        struct sockaddr_in6 *a = (struct sockaddr_in6 *)&ss;
        a->sin6_family = AF_INET6;
        a->sin6_port = htons((uint16_t)h->cfg.port);
        if (inet_pton(AF_INET6, bind, &a->sin6_addr) != 1) goto bad_addr;
    } else {
        struct sockaddr_in *a = (struct sockaddr_in *)&ss;
        a->sin_family = AF_INET;
        a->sin_port = htons((uint16_t)h->cfg.port);
        if (inet_pton(AF_INET, bind, &a->sin_addr) != 1) goto bad_addr;
    }
    /* poll(), not epoll (which MHD_USE_AUTO picks on Linux): libmicrohttpd 0.9.75's
     * MHD_quiesce_daemon removes the listen socket from each worker's epoll set while the
     * worker may be removing it too, and the loser's epoll_ctl(DEL) fails with ENOENT, which
     * it answers with MHD_PANIC, an abort ("Failed to remove listen FD from epoll set", seen
     * at shutdown: server_security, 1 run in ~20). With poll() quiescing only signals the
     * workers through their inter-thread channel (MHD_USE_ITC, which quiescing needs). */
    unsigned flags = MHD_USE_POLL | MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_ITC | MHD_ALLOW_SUSPEND_RESUME;
    if (strchr(bind, ':')) flags |= MHD_USE_IPv6;
    h->d = MHD_start_daemon(flags, (uint16_t)h->cfg.port, NULL, NULL, handler, h,
                            MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&ss,
                            MHD_OPTION_NOTIFY_COMPLETED, completed, h,
                            MHD_OPTION_NOTIFY_CONNECTION, notify_connection, h,
                            MHD_OPTION_UNESCAPE_CALLBACK, keep_escaped, NULL,
                            MHD_OPTION_THREAD_POOL_SIZE, (unsigned)(h->cfg.threads > 0 ? h->cfg.threads : 1),
                            MHD_OPTION_CONNECTION_LIMIT, (unsigned)4000,
                            MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)HTTP_CONNECTION_MEMORY,
                            /* Slow clients hold no thread (the pool polls); these bound
                             * what they hold: idle connections close, and one address may
                             * keep only so many open (more are refused at accept). */
                            MHD_OPTION_CONNECTION_TIMEOUT, h->cfg.client_timeout_s ? h->cfg.client_timeout_s : 60u,
                            MHD_OPTION_PER_IP_CONNECTION_LIMIT, h->cfg.max_client_conns,
                            MHD_OPTION_LISTEN_BACKLOG_SIZE, (unsigned)1024,
                            MHD_OPTION_END);
    if (!h->d) {
        snprintf(err, err_len, "cannot listen on %s port %d (in use, or not an address of this host)", bind, h->cfg.port);
        goto fail;
    }
    if (pthread_create(&h->deadline_thread, NULL, deadline_main, h) != 0) {
        snprintf(err, err_len, "cannot start the request deadline thread");
        MHD_stop_daemon(h->d);
        goto fail;
    }
    h->deadline_started = true;
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(h->d, MHD_DAEMON_INFO_BIND_PORT);
    *port_out = info ? info->port : h->cfg.port;
    return h;
bad_addr:
    snprintf(err, err_len, "--bind %s: not a numeric IPv4 or IPv6 address", bind);
fail:
    pthread_cond_destroy(&h->conns_cv);
    pthread_mutex_destroy(&h->conns_mu);
    free(h);
    return NULL;
}

void srv_http_quiesce(srv_http *h)
{
    if (!h || !h->d) return;
    if (h->quiesced_fd != MHD_INVALID_SOCKET) return;
    /* The socket stays open until MHD_stop_daemon has joined the workers: a worker that
     * has not yet seen the quiesce may still poll it, and a closed number could be reused
     * by a file meanwhile. Connections that arrive in between wait in the backlog and are
     * reset when it closes. */
    h->quiesced_fd = MHD_quiesce_daemon(h->d);
}

unsigned srv_http_connections(srv_http *h)
{
    const union MHD_DaemonInfo *info = h && h->d ? MHD_get_daemon_info(h->d, MHD_DAEMON_INFO_CURRENT_CONNECTIONS) : NULL;
    return info ? info->num_connections : 0;
}

void srv_http_stop(srv_http *h)
{
    if (!h) return;
    if (h->deadline_started) {
        pthread_mutex_lock(&h->conns_mu);
        h->stopping = true;
        pthread_cond_signal(&h->conns_cv);
        pthread_mutex_unlock(&h->conns_mu);
        pthread_join(h->deadline_thread, NULL);
    }
    if (h->d) MHD_stop_daemon(h->d); /* its CLOSED notifications empty the list */
    if (h->quiesced_fd != MHD_INVALID_SOCKET) close(h->quiesced_fd);
    pthread_cond_destroy(&h->conns_cv);
    pthread_mutex_destroy(&h->conns_mu);
    free(h);
}
