/* offload.c — the encoder and loader threads; see offload.h. */
#include "offload.h"

#include <pthread.h>
#include <stdlib.h>
#include <time.h>

typedef struct task {
    void (*fn)(void *);
    void (*expired)(void *); /* run instead of fn once deadline passes in the queue, or NULL */
    void *arg;
    double queued_at; /* monotonic seconds */
    double deadline;  /* monotonic seconds; 0: none */
    struct task *next;
} task;

typedef struct worker {
    struct srv_offload *o;
    pthread_t th;
    double since; /* when its current task started, 0 idle; guarded by o->mu */
} worker;

struct srv_offload {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    pthread_cond_t wcv;  /* the watchdog's: a bounded task queued, or stopping (CLOCK_MONOTONIC) */
    pthread_t watchdog;
    bool watchdog_started;
    task *head, *tail; /* guarded by mu */
    int queued;        /* guarded by mu */
    bool stopping;     /* guarded by mu */
    bool joined;
    int n;
    worker *w;
};

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void *run(void *arg)
{
    worker *w = arg;
    srv_offload *o = w->o;
    pthread_mutex_lock(&o->mu);
    for (;;) {
        while (!o->head && !o->stopping) pthread_cond_wait(&o->cv, &o->mu);
        task *t = o->head;
        if (!t) break; /* stopping and drained */
        o->head = t->next;
        if (!o->head) o->tail = NULL;
        o->queued--;
        w->since = now_s();
        pthread_mutex_unlock(&o->mu);
        t->fn(t->arg);
        free(t);
        pthread_mutex_lock(&o->mu);
        w->since = 0;
    }
    pthread_mutex_unlock(&o->mu);
    return NULL;
}

/* The earliest deadline of a queued task (0: none). Under mu. */
static double first_deadline(const srv_offload *o)
{
    double d = 0;
    for (const task *t = o->head; t; t = t->next)
        if (t->deadline > 0 && (d == 0 || t->deadline < d)) d = t->deadline;
    return d;
}

/* Takes the queued tasks whose deadline has passed out of the queue and runs their
 * `expired` (which answers the request), so a request waiting for a busy pool is answered
 * at its bound, not when a thread frees up. */
static void *watch(void *arg)
{
    srv_offload *o = arg;
    pthread_mutex_lock(&o->mu);
    while (!o->stopping) {
        double d = first_deadline(o), now = now_s();
        if (d == 0 || d > now) {
            if (d == 0) {
                pthread_cond_wait(&o->wcv, &o->mu);
            } else {
                struct timespec ts;
                double whole = (double)(long long)d;
                ts.tv_sec = (time_t)whole;
                ts.tv_nsec = (long)((d - whole) * 1e9);
                pthread_cond_timedwait(&o->wcv, &o->mu, &ts);
            }
            continue;
        }
        task **at = &o->head, *prev = NULL;
        while (*at && !((*at)->deadline > 0 && (*at)->deadline <= now)) prev = *at, at = &(*at)->next;
        task *t = *at;
        *at = t->next;
        if (o->tail == t) o->tail = prev;
        o->queued--;
        pthread_mutex_unlock(&o->mu);
        t->expired(t->arg);
        free(t);
        pthread_mutex_lock(&o->mu);
    }
    pthread_mutex_unlock(&o->mu);
    return NULL;
}

srv_offload *srv_offload_create(int threads)
{
    srv_offload *o = calloc(1, sizeof *o);
    if (!o) return NULL;
    o->w = calloc((size_t)threads, sizeof *o->w);
    if (!o->w) {
        free(o);
        return NULL;
    }
    pthread_mutex_init(&o->mu, NULL);
    pthread_cond_init(&o->cv, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&o->wcv, &ca);
    pthread_condattr_destroy(&ca);
    o->watchdog_started = pthread_create(&o->watchdog, NULL, watch, o) == 0;
    while (o->n < threads) {
        o->w[o->n].o = o;
        if (pthread_create(&o->w[o->n].th, NULL, run, &o->w[o->n]) != 0) break;
        o->n++;
    }
    if (o->n == 0) {
        srv_offload_destroy(o);
        return NULL;
    }
    return o;
}

bool srv_offload_submit_bounded(srv_offload *o, void (*fn)(void *arg), void (*expired)(void *arg), void *arg,
                               double deadline)
{
    task *t = malloc(sizeof *t);
    if (!t) return false;
    t->fn = fn, t->arg = arg, t->next = NULL;
    t->expired = expired;
    t->deadline = expired && o->watchdog_started ? deadline : 0;
    t->queued_at = now_s();
    pthread_mutex_lock(&o->mu);
    if (o->stopping) {
        pthread_mutex_unlock(&o->mu);
        free(t);
        return false;
    }
    if (o->tail) o->tail->next = t;
    else o->head = t;
    o->tail = t;
    o->queued++;
    pthread_cond_signal(&o->cv);
    if (t->deadline > 0) pthread_cond_signal(&o->wcv);
    pthread_mutex_unlock(&o->mu);
    return true;
}

bool srv_offload_submit(srv_offload *o, void (*fn)(void *arg), void *arg)
{
    return srv_offload_submit_bounded(o, fn, NULL, arg, 0);
}

void srv_offload_get_status(srv_offload *o, double bound_s, srv_offload_status *out)
{
    double now = now_s();
    *out = (srv_offload_status){0};
    pthread_mutex_lock(&o->mu);
    out->threads = o->n;
    out->queued = o->queued;
    for (int i = 0; i < o->n; i++)
        if (o->w[i].since > 0) {
            out->busy++;
            if (now - o->w[i].since > bound_s) out->stuck++;
            if (now - o->w[i].since > out->oldest_task_s) out->oldest_task_s = now - o->w[i].since;
        }
    if (o->head) out->oldest_queued_s = now - o->head->queued_at;
    pthread_mutex_unlock(&o->mu);
}

void srv_offload_drain(srv_offload *o)
{
    pthread_mutex_lock(&o->mu);
    o->stopping = true;
    pthread_cond_broadcast(&o->cv);
    pthread_cond_broadcast(&o->wcv);
    bool join = !o->joined;
    o->joined = true;
    pthread_mutex_unlock(&o->mu);
    if (join) {
        if (o->watchdog_started) pthread_join(o->watchdog, NULL);
        for (int i = 0; i < o->n; i++) pthread_join(o->w[i].th, NULL);
    }
}

void srv_offload_destroy(srv_offload *o)
{
    if (!o) return;
    srv_offload_drain(o);
    pthread_mutex_destroy(&o->mu);
    pthread_cond_destroy(&o->cv);
    pthread_cond_destroy(&o->wcv);
    free(o->w);
    free(o);
}
