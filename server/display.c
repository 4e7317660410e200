/* display.c — tev display-server streaming (display.h has the design note and the format).
 *
 * State: the fields marked "guarded" are under `mu`; the socket itself is used only by the
 * display thread (destroy shuts it down, under mu, to interrupt a send). The tile queue is
 * lock-free, so a worker's on_tile never waits for the display thread (on a loaded machine
 * waiting for a mutex means sleeping, and a woken thread may wait a time slice for a CPU):
 * per tile a `pending` flag (set by on_tile, cleared by the thread before it reads the tile's
 * snapshot, so a later state sets it again) and a stamp ordering tiles by their last
 * change; `queued` counts set flags. The thread takes every pending tile in stamp order
 * (the order they finished). Workers never signal the thread: waking a thread is a system
 * call after which, on a loaded machine, the worker can lose its CPU for a time slice
 * (measured here under load 13 on 2 cores: FUTEX_WAKE calls from workers returning after
 * ~20 ms, 3 % of the workers' time). So the thread looks at `queued` on a timed wait
 * instead, every 20 ms while tiles come (a display refresh rate, like a viewer's frame
 * rate), backing off to every 0.2 s when none do, and for the first tile every 50 ms; its
 * condition variable is signalled only by finish and stop. */
#define _GNU_SOURCE
#include "display.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

const char *const srv_display_channel_names[SRV_DISPLAY_CHANNELS] = {"R", "G", "B", "error"};

#define BACKOFF_MIN_S 0.1
#define BACKOFF_MAX_S 5.0
#define CONNECT_TIMEOUT_MS 2000
#define IDLE_CHECK_S 0.2  /* how often an idle thread looks for a closed connection */
#define FIRST_TILE_CHECK_S 0.05 /* how often a display without a job yet looks for one */
#define DUTY 0.02         /* the display thread's CPU budget while a job renders: 2 % of one core */
#define BATCH_S 0.02      /* the queue is looked at this often while tiles come (≤ 50 wake-ups/s) */
#define SEND_TIMEOUT_S 10 /* a viewer that accepts nothing for this long is dropped */

struct srv_display {
    char host[SRV_DISPLAY_ADDRESS_MAX + 1], port[8];
    char name[SRV_DISPLAY_NAME_MAX];
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cv;       /* work arrived, or stop */
    pthread_cond_t idle_cv;  /* a flush may have completed */
    /* guarded by mu */
    bool stop;
    int fd;                  /* -1 when not connected (written by the thread only) */
    bool sending;            /* the thread is sending tiles it took off the queue */
    bool ended;              /* the thread has returned */
    bool hurry;              /* a flush waits: no pacing rests */
    bool finishing;          /* srv_display_finish: end once the queue is sent (or now, unconnected) */
    srv_display_stats stats;
    /* set once under mu by the first srv_display_tile, then immutable; published by `ready` */
    ts_sched_job *job;       /* the display's job (a reference), NULL until the first tile */
    int nx, ny, full_w, full_h, x0, y0, w, h;
    atomic_uchar *pending;   /* per tile: changed since the thread last took it */
    atomic_uint_fast64_t *stamp; /* per tile: when it was last marked pending */
    int *order;              /* the thread's scratch: pending tiles in stamp order */
    atomic_bool ready;
    /* lock-free */
    atomic_int queued;       /* pending flags set (transiently −1 while a worker is between steps) */
    atomic_uint_fast64_t seq;
};

static double thread_cpu_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static struct timespec deadline_in(double s)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    double ns = (double)t.tv_nsec + s * 1e9;
    t.tv_sec += (time_t)(ns / 1e9);
    t.tv_nsec = (long)fmod(ns, 1e9);
    return t;
}

/* ---------------------------------------------------------------- address */

static bool host_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '_';
}

ts_status srv_display_parse_address(const char *address, char *host, char *port, ts_error *err)
{
    if (!address || !*address)
        return ts_error_set(err, TS_ERR_INVALID, "display server: expected HOST:PORT, got an empty address");
    size_t n = strnlen(address, SRV_DISPLAY_ADDRESS_MAX + 1);
    if (n > SRV_DISPLAY_ADDRESS_MAX)
        return ts_error_set(err, TS_ERR_INVALID, "display server: the address is longer than %d characters",
                            SRV_DISPLAY_ADDRESS_MAX);
    const char *colon = strrchr(address, ':');
    if (!colon) return ts_error_set(err, TS_ERR_INVALID, "display server '%s': expected HOST:PORT", address);
    const char *h0 = address, *h1 = colon;
    if (*address == '[') { /* [IPv6]:port */
        if (colon == address || colon[-1] != ']')
            return ts_error_set(err, TS_ERR_INVALID, "display server '%s': an IPv6 address is written [ADDRESS]:PORT", address);
        h0 = address + 1, h1 = colon - 1;
        for (const char *c = h0; c < h1; c++)
            if (!(*c == ':' || *c == '.' || (*c >= '0' && *c <= '9') || (*c >= 'a' && *c <= 'f') || (*c >= 'A' && *c <= 'F')))
                return ts_error_set(err, TS_ERR_INVALID, "display server '%s': '%c' in an IPv6 address", address, *c);
    } else {
        for (const char *c = h0; c < h1; c++)
            if (!host_char(*c))
                return ts_error_set(err, TS_ERR_INVALID,
                                    "display server '%s': the host may hold letters, digits, '.', '-' and '_', not '%c'",
                                    address, *c);
    }
    if (h1 == h0) return ts_error_set(err, TS_ERR_INVALID, "display server '%s': the host is missing", address);
    const char *p = colon + 1;
    unsigned long v = 0;
    size_t digits = 0;
    for (; p[digits]; digits++) {
        if (p[digits] < '0' || p[digits] > '9' || digits >= 5) {
            digits = 0;
            break;
        }
        v = v * 10 + (unsigned long)(p[digits] - '0');
    }
    if (digits == 0 || v < 1 || v > 65535)
        return ts_error_set(err, TS_ERR_INVALID, "display server '%s': the port must be a number from 1 to 65535", address);
    if (host) {
        memcpy(host, h0, (size_t)(h1 - h0));
        host[h1 - h0] = 0;
    }
    if (port) snprintf(port, 6, "%lu", v);
    return TS_OK;
}

/* ---------------------------------------------------------------- packets */

typedef struct buf {
    uint8_t *p;
    size_t n, cap;
    bool failed;
} buf;

/* Room for n more bytes; false (and b->failed) when memory runs out. */
static bool reserve(buf *b, size_t n)
{
    if (b->failed) return false;
    if (b->n + n <= b->cap) return true;
    size_t cap = b->cap ? b->cap : 256;
    while (cap < b->n + n) cap *= 2;
    uint8_t *p = realloc(b->p, cap);
    if (!p) return !(b->failed = true);
    b->p = p, b->cap = cap;
    return true;
}
static void put(buf *b, const void *src, size_t n)
{
    if (!reserve(b, n)) return;
    memcpy(b->p + b->n, src, n);
    b->n += n;
}
static void put_u8(buf *b, uint8_t v) { put(b, &v, 1); }
static void put_le(buf *b, uint64_t v, int bytes)
{
    uint8_t o[8];
    for (int i = 0; i < bytes; i++) o[i] = (uint8_t)(v >> (8 * i));
    put(b, o, (size_t)bytes);
}
static void put_i32(buf *b, int32_t v) { put_le(b, (uint32_t)v, 4); }
static void put_i64(buf *b, int64_t v) { put_le(b, (uint64_t)v, 8); }
static void put_str(buf *b, const char *s) { put(b, s, strlen(s) + 1); }
/* n floats, src[0], src[stride], …, little-endian. */
static void put_f32s(buf *b, const float *src, size_t n, size_t stride)
{
    if (!reserve(b, 4 * n)) return;
    uint8_t *o = b->p + b->n;
    for (size_t i = 0; i < n; i++, o += 4) {
        uint32_t u;
        memcpy(&u, &src[i * stride], 4);
        o[0] = (uint8_t)u, o[1] = (uint8_t)(u >> 8), o[2] = (uint8_t)(u >> 16), o[3] = (uint8_t)(u >> 24);
    }
    b->n += 4 * n;
}

static void begin_packet(buf *b, srv_display_packet type)
{
    b->n = 0, b->failed = false;
    put_le(b, 0, 4); /* the length, patched by end_packet */
    put_u8(b, (uint8_t)type);
}
static bool end_packet(buf *b)
{
    if (b->failed || b->n > UINT32_MAX) return false;
    for (int i = 0; i < 4; i++) b->p[i] = (uint8_t)(b->n >> (8 * i));
    return true;
}

static bool encode_create(buf *b, const char *name, int w, int h)
{
    begin_packet(b, SRV_DISPLAY_CREATE_IMAGE);
    put_u8(b, 1); /* grab focus: show the new render */
    put_str(b, name);
    put_i32(b, w);
    put_i32(b, h);
    put_i32(b, SRV_DISPLAY_CHANNELS);
    for (int c = 0; c < SRV_DISPLAY_CHANNELS; c++) put_str(b, srv_display_channel_names[c]);
    return end_packet(b);
}

float srv_display_relative_error(const float rgb[3], const float var[3])
{
    double y = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
    double v = 0.2126 * 0.2126 * var[0] + 0.7152 * 0.7152 * var[1] + 0.0722 * 0.0722 * var[2];
    double e = v > 0 ? sqrt(v / (y * y + 1e-3)) : 0;
    return (float)e;
}

/* UpdateImageV3 of one snapshot, at window coordinates (x, y), planar channels. */
static bool encode_tile(buf *b, const char *name, const ts_tile_snapshot *t, int full_w, int full_h, int x, int y,
                        float scale)
{
    /* The snapshot read in place as a film of its tile (it is immutable and only read), so
     * the floats are those of the EXR encoder's ts_film_to_image, with no copy. */
    ts_film view = {full_w, full_h, t->x, t->y, t->w, t->h, (ts_film_pixel *)t->pixels, scale};
    ts_error err = {0};
    ts_image img;
    if (ts_film_to_image(&view, TS_FILM_IMAGE_STATS, &img, &err)) return false;
    int64_t npx = (int64_t)t->w * t->h;
    begin_packet(b, SRV_DISPLAY_UPDATE_IMAGE_V3);
    put_u8(b, 0);
    put_str(b, name);
    put_i32(b, SRV_DISPLAY_CHANNELS);
    for (int c = 0; c < SRV_DISPLAY_CHANNELS; c++) put_str(b, srv_display_channel_names[c]);
    put_i32(b, x);
    put_i32(b, y);
    put_i32(b, t->w);
    put_i32(b, t->h);
    for (int c = 0; c < SRV_DISPLAY_CHANNELS; c++) put_i64(b, c * npx); /* offsets */
    for (int c = 0; c < SRV_DISPLAY_CHANNELS; c++) put_i64(b, 1);       /* strides */
    const int nc = img.n_channels;                                        /* R G B R.var G.var B.var count */
    for (int c = 0; c < 3; c++) put_f32s(b, img.data + c, (size_t)npx, (size_t)nc);
    /* The error channel, computed into the image's count channel (not sent) in place. */
    for (int64_t i = 0; i < npx; i++) img.data[i * nc + 6] = srv_display_relative_error(&img.data[i * nc], &img.data[i * nc + 3]);
    put_f32s(b, img.data + 6, (size_t)npx, (size_t)nc);
    ts_image_fini(&img);
    return end_packet(b);
}

/* ---------------------------------------------------------------- the connection */

static int connect_to(const char *host, const char *port)
{
    struct addrinfo hints = {0}, *ai = NULL;
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    if (getaddrinfo(host, port, &hints, &ai) != 0) return -1;
    int fd = -1;
    for (struct addrinfo *a = ai; a && fd < 0; a = a->ai_next) {
        fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
        if (fd < 0) continue;
        int r = connect(fd, a->ai_addr, a->ai_addrlen);
        if (r < 0 && errno == EINPROGRESS) {
            struct pollfd pfd = {fd, POLLOUT, 0};
            int e = 0;
            socklen_t len = sizeof e;
            r = poll(&pfd, 1, CONNECT_TIMEOUT_MS) == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &e, &len) == 0 && e == 0 ? 0 : -1;
        }
        if (r < 0) {
            close(fd);
            fd = -1;
        }
    }
    freeaddrinfo(ai);
    if (fd < 0) return -1;
    /* Blocking from here on (this thread has nothing else to do), with a send timeout. */
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    struct timeval tv = {SEND_TIMEOUT_S, 0};
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return fd;
}

static bool send_all(int fd, const uint8_t *p, size_t n)
{
    while (n) {
        ssize_t r = send(fd, p, n, MSG_NOSIGNAL);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return false;
        p += r, n -= (size_t)r;
    }
    return true;
}

/* tev never writes to us: a readable socket means the viewer closed it (or failed). */
static bool peer_closed(int fd)
{
    char c;
    ssize_t r = recv(fd, &c, 1, MSG_PEEK | MSG_DONTWAIT);
    return r == 0 || (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

/* Marks tile i pending (any thread); true when it was not. */
static bool mark(srv_display *d, int i)
{
    if (atomic_exchange(&d->pending[i], 1)) return false;
    atomic_store_explicit(&d->stamp[i], atomic_fetch_add(&d->seq, 1), memory_order_relaxed);
    atomic_fetch_add(&d->queued, 1);
    return true;
}

/* Marks every tile (after a new connection: the viewer has none of them). */
static void queue_all(srv_display *d)
{
    for (int i = 0; i < d->nx * d->ny; i++) mark(d, i);
}

static int by_stamp(const void *a, const void *b, void *arg)
{
    const srv_display *d = arg;
    uint_fast64_t x = atomic_load_explicit(&d->stamp[*(const int *)a], memory_order_relaxed);
    uint_fast64_t y = atomic_load_explicit(&d->stamp[*(const int *)b], memory_order_relaxed);
    return (x > y) - (x < y);
}

static void disconnect(srv_display *d)
{
    pthread_mutex_lock(&d->mu);
    int fd = d->fd;
    d->fd = -1;
    d->stats.disconnects++;
    pthread_cond_broadcast(&d->idle_cv);
    pthread_mutex_unlock(&d->mu);
    close(fd);
}

static void *display_thread(void *arg)
{
    srv_display *d = arg;
    buf b = {0};
    double backoff = BACKOFF_MIN_S, next_attempt = 0;
    bool created = false; /* CreateImage sent on this connection */
    double poll_s = BATCH_S; /* how long to wait before looking at the queue again */
    double rest_until = 0;   /* pacing: no batch before this (now_s) */
    /* A batch thread is not let preempt a worker when it wakes up. */
    struct sched_param sp = {0};
    pthread_setschedparam(pthread_self(), SCHED_BATCH, &sp);
    pthread_mutex_lock(&d->mu);
    while (!d->stop) {
        /* Finishing: done once everything is sent; when not connected, done unless the first
         * attempt to connect is still to come (a job quicker than that is still shown). */
        if (d->finishing && (d->fd < 0 ? !d->job || d->stats.failed_connects + d->stats.connects > 0
                                       : created && atomic_load(&d->queued) <= 0 && !d->sending))
            break;
        if (d->fd < 0) {
            double wait = next_attempt - now_s();
            if (wait > 0 || !d->job) { /* backing off, or nothing to show yet (looked for every 50 ms) */
                struct timespec t = deadline_in(wait > 0 ? wait : FIRST_TILE_CHECK_S);
                pthread_cond_timedwait(&d->cv, &d->mu, &t);
                continue;
            }
            pthread_mutex_unlock(&d->mu);
            int fd = connect_to(d->host, d->port);
            pthread_mutex_lock(&d->mu);
            if (fd < 0) {
                d->stats.failed_connects++;
                pthread_cond_broadcast(&d->idle_cv); /* a flush may give up */
                next_attempt = now_s() + backoff;
                backoff = backoff * 2 < BACKOFF_MAX_S ? backoff * 2 : BACKOFF_MAX_S;
                continue;
            }
            if (d->stop) {
                close(fd);
                break;
            }
            d->fd = fd;
            d->stats.connects++;
            backoff = BACKOFF_MIN_S;
            created = false;
            queue_all(d);
        }
        int fd = d->fd;
        if (!created) {
            int w = d->w, h = d->h;
            pthread_mutex_unlock(&d->mu);
            bool ok = encode_create(&b, d->name, w, h) && send_all(fd, b.p, b.n);
            if (!ok) {
                disconnect(d);
                pthread_mutex_lock(&d->mu);
                next_attempt = now_s() + backoff;
                continue;
            }
            pthread_mutex_lock(&d->mu);
            d->stats.bytes_sent += b.n;
            created = true;
            continue;
        }
        if (atomic_load(&d->queued) <= 0) {
            /* Nothing pending: look again in a moment (see the note at the top: workers
             * never wake this thread). 20 ms while tiles keep coming, backing off to 0.2 s. */
            pthread_cond_broadcast(&d->idle_cv);
            struct timespec t = deadline_in(poll_s);
            int r = pthread_cond_timedwait(&d->cv, &d->mu, &t);
            poll_s = poll_s * 2 < IDLE_CHECK_S ? poll_s * 2 : IDLE_CHECK_S;
            if (r == ETIMEDOUT && atomic_load(&d->queued) <= 0 && peer_closed(fd)) {
                pthread_mutex_unlock(&d->mu);
                disconnect(d);
                pthread_mutex_lock(&d->mu);
            }
            continue;
        }
        poll_s = BATCH_S;
        /* Pacing: this thread uses at most DUTY of one core while the job renders (its
         * batches are followed by rests 1/DUTY as long as their CPU time); never once the
         * job is finished or someone waits in flush. */
        double wait = rest_until - now_s();
        if (wait > 0 && !d->finishing && !d->hurry) {
            struct timespec t = deadline_in(wait);
            pthread_cond_timedwait(&d->cv, &d->mu, &t);
            continue;
        }
        d->sending = true;
        pthread_mutex_unlock(&d->mu);
        double batch_start = now_s(), cpu_start = thread_cpu_s();
        int n = 0;
        for (int i = 0; i < d->nx * d->ny; i++)
            if (atomic_load(&d->pending[i])) d->order[n++] = i;
        qsort_r(d->order, (size_t)n, sizeof *d->order, by_stamp, d);
        bool ok = true;
        uint64_t sent = 0, bytes = 0;
        const ts_scene *scene = ts_sched_job_scene(d->job);
        float scale = scene ? scene->film_scale : 1; /* the output factor (film.h) */
        for (int k = 0; k < n && ok; k++) {
            int i = d->order[k];
            if (!atomic_exchange(&d->pending[i], 0)) continue;
            atomic_fetch_sub(&d->queued, 1);
            ts_tile_snapshot *t = ts_sched_job_tile(d->job, i % d->nx, i / d->nx);
            if (!t) continue; /* not rendered yet */
            /* An encoding failure (out of memory) skips this state of the tile only. */
            bool encoded = encode_tile(&b, d->name, t, d->full_w, d->full_h, t->x - d->x0, t->y - d->y0, scale);
            ts_tile_snapshot_release(t);
            if (encoded && (ok = send_all(fd, b.p, b.n))) sent++, bytes += b.n;
        }
        if (!ok) disconnect(d); /* the next connection re-sends every tile */
        pthread_mutex_lock(&d->mu);
        d->sending = false;
        d->stats.tiles_sent += sent;
        d->stats.bytes_sent += bytes;
        d->stats.thread_cpu_s = thread_cpu_s();
        rest_until = batch_start + (d->stats.thread_cpu_s - cpu_start) / DUTY;
        if (!ok) next_attempt = now_s() + backoff;
    }
    int fd = d->fd;
    d->fd = -1;
    d->ended = true;
    pthread_cond_broadcast(&d->idle_cv);
    pthread_mutex_unlock(&d->mu);
    if (fd >= 0) close(fd);
    free(b.p);
    return NULL;
}

/* ---------------------------------------------------------------- the public side */

srv_display *srv_display_create(const char *address, const char *name, ts_error *err)
{
    char host[SRV_DISPLAY_ADDRESS_MAX + 1], port[8];
    if (srv_display_parse_address(address, host, port, err)) return NULL;
    srv_display *d = calloc(1, sizeof *d);
    if (!d) {
        ts_error_set(err, TS_ERR_NOMEM, "display server: out of memory");
        return NULL;
    }
    memcpy(d->host, host, sizeof host);
    memcpy(d->port, port, sizeof port);
    snprintf(d->name, sizeof d->name, "%s", name && *name ? name : "tessera");
    d->fd = -1;
    pthread_mutex_init(&d->mu, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&d->cv, &ca);
    pthread_cond_init(&d->idle_cv, &ca);
    pthread_condattr_destroy(&ca);
    if (pthread_create(&d->thread, NULL, display_thread, d) != 0) {
        ts_error_set(err, TS_ERR_NOMEM, "display server: could not start its thread");
        pthread_cond_destroy(&d->cv);
        pthread_cond_destroy(&d->idle_cv);
        pthread_mutex_destroy(&d->mu);
        free(d);
        return NULL;
    }
    return d;
}

/* The first tile: the job's geometry and the queue (once; under mu). */
static void first_tile(srv_display *d, ts_sched_job *job)
{
    pthread_mutex_lock(&d->mu);
    if (!atomic_load(&d->ready) && !d->stop) {
        int nx, ny;
        ts_sched_job_grid(job, &nx, &ny);
        size_t n = nx > 0 && ny > 0 ? (size_t)nx * (size_t)ny : 0;
        d->pending = n ? calloc(n, sizeof *d->pending) : NULL;
        d->stamp = n ? calloc(n, sizeof *d->stamp) : NULL;
        d->order = n ? malloc(n * sizeof *d->order) : NULL;
        if (d->pending && d->stamp && d->order) {
            ts_sched_job_retain(job);
            d->job = job;
            d->nx = nx, d->ny = ny;
            ts_sched_job_window(job, &d->full_w, &d->full_h, &d->x0, &d->y0, &d->w, &d->h);
            atomic_store(&d->ready, true);
        } else { /* out of memory: this display shows nothing (rendering is unaffected) */
            d->stop = true;
        }
        /* No signal: the thread looks for the job every 50 ms (no system call here). */
    }
    pthread_mutex_unlock(&d->mu);
}

void srv_display_tile(srv_display *d, ts_sched_job *job, const ts_tile_event *ev)
{
    if (!atomic_load(&d->ready)) {
        first_tile(d, job);
        if (!atomic_load(&d->ready)) return;
    }
    if (d->job != job || ev->tx < 0 || ev->tx >= d->nx || ev->ty < 0 || ev->ty >= d->ny) return;
    mark(d, ev->ty * d->nx + ev->tx);
}

void srv_display_on_tile(void *user, ts_sched_job *job, const ts_tile_event *ev) { srv_display_tile(user, job, ev); }

void srv_display_finish(srv_display *d)
{
    pthread_mutex_lock(&d->mu);
    d->finishing = true;
    pthread_cond_broadcast(&d->cv);
    pthread_mutex_unlock(&d->mu);
}

bool srv_display_connected(srv_display *d)
{
    pthread_mutex_lock(&d->mu);
    bool c = d->fd >= 0;
    pthread_mutex_unlock(&d->mu);
    return c;
}

bool srv_display_flush(srv_display *d, double timeout_s)
{
    struct timespec t = deadline_in(timeout_s);
    pthread_mutex_lock(&d->mu);
    bool done;
    uint64_t failed0 = d->stats.failed_connects;
    d->hurry = true;
    pthread_cond_broadcast(&d->cv);
    /* The fd stays open while mu is held and fd >= 0 (disconnect clears it first). A viewer
     * that closed the connection has received nothing of late: not done. */
    while (!(done = d->job && d->fd >= 0 && atomic_load(&d->queued) <= 0 && !d->sending && !peer_closed(d->fd)) && !d->stop &&
           !d->ended) {
        /* Not connected and known unreachable: give up now rather than wait for a retry. */
        if (d->fd < 0 && d->job && (failed0 > 0 || d->stats.failed_connects > failed0)) break;
        if (pthread_cond_timedwait(&d->idle_cv, &d->mu, &t) == ETIMEDOUT) break;
    }
    d->hurry = false;
    if (!d->job && !d->stop && !d->ended) done = true; /* nothing was ever rendered: nothing to send */
    pthread_mutex_unlock(&d->mu);
    return done;
}

void srv_display_get_stats(srv_display *d, srv_display_stats *out)
{
    pthread_mutex_lock(&d->mu);
    *out = d->stats;
    pthread_mutex_unlock(&d->mu);
}

void srv_display_destroy(srv_display *d)
{
    if (!d) return;
    pthread_mutex_lock(&d->mu);
    d->stop = true;
    if (d->fd >= 0) shutdown(d->fd, SHUT_RDWR); /* interrupts a send under way */
    pthread_cond_broadcast(&d->cv);
    pthread_mutex_unlock(&d->mu);
    pthread_join(d->thread, NULL);
    ts_sched_job_release(d->job);
    free(d->pending);
    free(d->stamp);
    free(d->order);
    pthread_cond_destroy(&d->cv);
    pthread_cond_destroy(&d->idle_cv);
    pthread_mutex_destroy(&d->mu);
    free(d);
}
