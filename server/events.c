/* events.c — SSE hubs; see events.h. */
#include "events.h"

#include <microhttpd.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SUB_BUFFER_CAP (16u << 20) /* a client this far behind is cut off */

typedef struct sub {
    struct srv_events *hub;
    struct MHD_Connection *conn;
    char *buf;          /* guarded by hub->mu */
    size_t len, off, cap;
    bool suspended, ended;
    struct sub *next;
} sub;

struct srv_events {
    pthread_mutex_t mu;
    sub *subs;           /* guarded by mu */
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
    pthread_mutex_destroy(&h->mu);
    free(h);
}

static void sub_append(sub *s, const char *text, size_t n)
{
    if (s->ended) return;
    if (s->off == s->len) s->off = s->len = 0;
    if (s->len + n > s->cap) {
        size_t cap = s->cap ? s->cap : 4096;
        while (cap < s->len + n) cap *= 2;
        char *b = cap <= SUB_BUFFER_CAP ? realloc(s->buf, cap) : NULL;
        if (!b) {
            s->ended = true; /* too far behind or out of memory: end the stream */
            return;
        }
        s->buf = b;
        s->cap = cap;
    }
    memcpy(s->buf + s->len, text, n);
    s->len += n;
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

void srv_events_publish(srv_events *h, const char *name, const char *json)
{
    char *t = srv_events_format(name, json);
    if (!t) return;
    size_t n = strlen(t);
    pthread_mutex_lock(&h->mu);
    for (sub *s = h->subs; s; s = s->next) {
        sub_append(s, t, n);
        wake(s);
    }
    pthread_mutex_unlock(&h->mu);
    free(t);
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

/* libmicrohttpd's content reader: runs on a daemon thread, must not block. */
static ssize_t sub_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    sub *s = cls;
    srv_events *h = s->hub;
    pthread_mutex_lock(&h->mu);
    if (s->len > s->off && !(s->ended && h->shut)) {
        size_t n = s->len - s->off < max ? s->len - s->off : max;
        memcpy(buf, s->buf + s->off, n);
        s->off += n;
        pthread_mutex_unlock(&h->mu);
        return (ssize_t)n;
    }
    if (s->ended || h->closed) {
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
            break;
        }
    pthread_mutex_unlock(&h->mu);
    free(s->buf);
    free(s);
}

static void append_cb(void *ctx, const char *text) { sub_append(ctx, text, strlen(text)); }

struct MHD_Response *srv_events_subscribe(srv_events *h, struct MHD_Connection *conn,
                                          void (*initial)(void *arg, srv_events_append_fn append, void *ctx),
                                          void *arg)
{
    sub *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->hub = h;
    s->conn = conn;
    struct MHD_Response *r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, sub_read, s, sub_free);
    if (!r) {
        free(s);
        return NULL;
    }
    pthread_mutex_lock(&h->mu);
    sub_append(s, "retry: 2000\n\n", 13);
    if (initial && !h->shut) initial(arg, append_cb, s);
    if (h->shut) s->ended = true;
    s->next = h->subs;
    h->subs = s;
    pthread_mutex_unlock(&h->mu);
    return r;
}
