/* events.c — SSE hubs; see events.h. */
#include "events.h"

#include <microhttpd.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

typedef struct sub {
    struct srv_events *hub;      /* immutable */
    struct MHD_Connection *conn; /* immutable */
    int fd;                      /* immutable: conn's socket, or -1; open while the sub is
                                  * listed (libmicrohttpd frees the response, and the sub
                                  * with it, before it closes the socket) */
    srv_events_limits *limits;   /* immutable */
    srv_events_source src;       /* immutable */
    /* guarded by hub->mu */
    int cursor;                  /* next backlog item; src.n_items: the tail; beyond: backlog sent */
    char *buf;
    size_t len, off, cap;
    bool suspended, ended, dropped;
    struct sub *next;
} sub;

struct srv_events {
    pthread_mutex_t mu;
    char **items;        /* guarded by mu: the latest event of each item, or NULL */
    int n_items;         /* set once */
    sub *subs;           /* guarded by mu */
    int n_subs;          /* guarded by mu */
    bool closed, shut;   /* guarded by mu */
};

srv_events *srv_events_create(void)
{
    srv_events *h = calloc(1, sizeof *h);
    if (h) pthread_mutex_init(&h->mu, NULL);
    return h;
}

void srv_events_destroy(srv_events *h)
{
    if (!h) return;
    for (int i = 0; h->items && i < h->n_items; i++) free(h->items[i]);
    free(h->items);
    pthread_mutex_destroy(&h->mu);
    free(h);
}

void srv_events_set_items(srv_events *h, int n_items)
{
    pthread_mutex_lock(&h->mu);
    if (!h->items && n_items > 0 && (h->items = calloc((size_t)n_items, sizeof *h->items))) h->n_items = n_items;
    pthread_mutex_unlock(&h->mu);
}

static bool backlog_done(const sub *s) { return s->cursor > s->src.n_items; }

/* Drops a subscriber that is too far behind (or out of memory): nothing more is sent and
 * its connection is aborted now; hub->mu held, s listed or being subscribed (so s->fd is
 * still its socket). libmicrohttpd alone would end the response only when it next asks
 * sub_read for data, i.e. once the socket takes more: for a client that stopped reading,
 * not before the idle timeout; and even after that close the kernel sends the FIN only
 * behind the events still queued for the client. So the socket is shut down (the next
 * send fails and libmicrohttpd closes the connection at once, as for the request deadline
 * in http.c) with a zero linger time, which makes the close a reset: the stale events
 * queued are discarded and the client learns at once, whether or not it reads. */
static void drop(sub *s)
{
    atomic_fetch_add(&s->limits->dropped, 1);
    s->ended = s->dropped = true;
    free(s->buf);
    s->buf = NULL;
    s->len = s->off = s->cap = 0;
    if (s->fd >= 0) {
        struct linger abort_on_close = {1, 0};
        setsockopt(s->fd, SOL_SOCKET, SO_LINGER, &abort_on_close, sizeof abort_on_close);
        shutdown(s->fd, SHUT_RDWR);
    }
}

static void sub_append(sub *s, const char *text, size_t n)
{
    if (s->ended) return;
    if (s->off == s->len) s->off = s->len = 0;
    if (s->len + n > s->cap) {
        size_t pending = s->len - s->off;
        if (pending + n > SRV_EVENTS_BUFFER_CAP) {
            drop(s);
            return;
        }
        if (s->off) { /* make room at the front first */
            memmove(s->buf, s->buf + s->off, pending);
            s->len = pending, s->off = 0;
        }
        if (s->len + n > s->cap) {
            size_t cap = s->cap ? s->cap : 4096;
            while (cap < s->len + n) cap *= 2;
            char *b = realloc(s->buf, cap);
            if (!b) {
                drop(s);
                return;
            }
            s->buf = b;
            s->cap = cap;
        }
    }
    memcpy(s->buf + s->len, text, n);
    s->len += n;
}

/* Pulls backlog items (then the tail) until `want` bytes are buffered or it is all sent;
 * hub->mu held. */
static void pull_backlog(srv_events *h, sub *s, size_t want)
{
    while (!backlog_done(s) && !s->ended && s->len - s->off < want) {
        int i = s->cursor++;
        if (i < s->src.n_items) {
            bool kept = i < h->n_items;
            char *e = kept && h->items[i] ? h->items[i] : s->src.item(s->src.arg, i);
            if (!e) continue;
            sub_append(s, e, strlen(e));
            if (kept) h->items[i] = e;
            else free(e);
        } else {
            char *e = s->src.tail(s->src.arg);
            if (e) sub_append(s, e, strlen(e));
            free(e);
        }
    }
}

static void wake(sub *s)
{
    if (s->suspended) {
        s->suspended = false;
        MHD_resume_connection(s->conn);
    }
}

char *srv_events_format(const char *name, const char *json)
{
    /* A line break inside the data (CR, LF or CR LF; never in cJSON's unformatted output)
     * would end the field: each line goes on a `data:` line of its own, which the client
     * joins with LF (the SSE framing of the HTML standard). */
    size_t lines = 1, len = strlen(json);
    for (size_t i = 0; i < len; i++)
        if (json[i] == '\n' || (json[i] == '\r' && json[i + 1] != '\n')) lines++;
    size_t n = strlen(name) + len + 6 * lines + 16;
    char *t = malloc(n);
    if (!t) return NULL;
    size_t at = (size_t)snprintf(t, n, "event: %s\ndata: ", name);
    for (size_t i = 0; i < len; i++) {
        if (json[i] == '\r' || json[i] == '\n') {
            if (json[i] == '\r' && json[i + 1] == '\n') i++;
            memcpy(t + at, "\ndata: ", 7);
            at += 7;
        } else {
            t[at++] = json[i];
        }
    }
    memcpy(t + at, "\n\n", 3);
    return t;
}

void srv_events_publish(srv_events *h, const char *name, const char *json, int item)
{
    char *t = srv_events_format(name, json);
    if (t) srv_events_publish_frame(h, t, item);
    free(t);
}

void srv_events_publish_frame(srv_events *h, const char *t, int item)
{
    size_t n = strlen(t);
    char *keep = item >= 0 && item < h->n_items ? strdup(t) : NULL;
    pthread_mutex_lock(&h->mu);
    if (keep) {
        free(h->items[item]);
        h->items[item] = keep;
    }
    for (sub *s = h->subs; s; s = s->next) {
        /* During the backlog, what it has yet to read is left to it (events.h). */
        if (!backlog_done(s) && !(item >= 0 && item < s->cursor)) continue;
        sub_append(s, t, n);
        wake(s);
    }
    pthread_mutex_unlock(&h->mu);
}

void srv_events_keepalive(srv_events *h)
{
    pthread_mutex_lock(&h->mu);
    for (sub *s = h->subs; s; s = s->next) {
        sub_append(s, ": keep-alive\n\n", 14);
        wake(s);
    }
    pthread_mutex_unlock(&h->mu);
}

void srv_events_close(srv_events *h)
{
    pthread_mutex_lock(&h->mu);
    h->closed = true;
    for (sub *s = h->subs; s; s = s->next) wake(s);
    pthread_mutex_unlock(&h->mu);
}

void srv_events_shutdown(srv_events *h)
{
    pthread_mutex_lock(&h->mu);
    h->closed = h->shut = true;
    for (sub *s = h->subs; s; s = s->next) {
        s->ended = true;
        wake(s);
    }
    pthread_mutex_unlock(&h->mu);
}

int srv_events_subscribers(srv_events *h)
{
    pthread_mutex_lock(&h->mu);
    int n = h->n_subs;
    pthread_mutex_unlock(&h->mu);
    return n;
}

/* libmicrohttpd's content reader: runs on a daemon thread, must not block. */
static ssize_t sub_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    sub *s = cls;
    srv_events *h = s->hub;
    pthread_mutex_lock(&h->mu);
    if (s->dropped) {
        pthread_mutex_unlock(&h->mu);
        return MHD_CONTENT_READER_END_WITH_ERROR; /* close the connection */
    }
    if (s->len == s->off && !(s->ended && h->shut)) pull_backlog(h, s, max);
    if (s->len > s->off && !(s->ended && h->shut)) {
        size_t n = s->len - s->off < max ? s->len - s->off : max;
        memcpy(buf, s->buf + s->off, n);
        s->off += n;
        pthread_mutex_unlock(&h->mu);
        return (ssize_t)n;
    }
    if (s->ended || (h->closed && backlog_done(s))) {
        pthread_mutex_unlock(&h->mu);
        return MHD_CONTENT_READER_END_OF_STREAM;
    }
    s->suspended = true;
    MHD_suspend_connection(s->conn);
    pthread_mutex_unlock(&h->mu);
    return 0;
}

static void sub_free(void *cls)
{
    sub *s = cls;
    srv_events *h = s->hub;
    pthread_mutex_lock(&h->mu);
    for (sub **pp = &h->subs; *pp; pp = &(*pp)->next)
        if (*pp == s) {
            *pp = s->next;
            h->n_subs--;
            break;
        }
    pthread_mutex_unlock(&h->mu);
    atomic_fetch_sub(&s->limits->total, 1);
    free(s->buf);
    srv_events_source src = s->src;
    free(s);
    if (src.release) src.release(src.arg); /* last: it may free the hub */
}

struct MHD_Response *srv_events_subscribe(srv_events *h, struct MHD_Connection *conn, const srv_events_source *src,
                                          srv_events_limits *limits, unsigned *http_status, char *msg,
                                          size_t msg_len)
{
    *http_status = 503;
    if (limits->max_total > 0 && atomic_fetch_add(&limits->total, 1) >= limits->max_total) {
        atomic_fetch_sub(&limits->total, 1);
        snprintf(msg, msg_len, "this server already streams events to %d clients, its limit; try again later",
                 limits->max_total);
        return NULL;
    }
    if (limits->max_total <= 0) atomic_fetch_add(&limits->total, 1);
    sub *s = calloc(1, sizeof *s);
    struct MHD_Response *r = s ? MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, sub_read, s, sub_free) : NULL;
    if (!r) {
        free(s);
        atomic_fetch_sub(&limits->total, 1);
        *http_status = 500;
        snprintf(msg, msg_len, "out of memory");
        return NULL;
    }
    s->hub = h;
    s->conn = conn;
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    s->fd = ci ? ci->connect_fd : -1;
    s->limits = limits;
    s->src = *src;
    pthread_mutex_lock(&h->mu);
    if (limits->max_per_job > 0 && h->n_subs >= limits->max_per_job) {
        pthread_mutex_unlock(&h->mu);
        s->src.release = NULL; /* never retained */
        MHD_destroy_response(r); /* frees s through sub_free, which gives back the place */
        snprintf(msg, msg_len, "this job already streams events to %d clients, its limit; try again later",
                 limits->max_per_job);
        return NULL;
    }
    if (src->retain) src->retain(src->arg);
    sub_append(s, "retry: 2000\n\n", 13);
    if (h->shut) s->ended = true;
    s->next = h->subs;
    h->subs = s;
    h->n_subs++;
    pthread_mutex_unlock(&h->mu);
    return r;
}
