/* offload.c — the encoder and loader threads; see offload.h. */
#include "offload.h"

#include <pthread.h>
#include <stdlib.h>
#include <time.h>

typedef struct task {
    void (*fn)(void *);
    void *arg;
    double queued_at; /* monotonic seconds */
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

bool srv_offload_submit(srv_offload *o, void (*fn)(void *arg), void *arg)
{
    task *t = malloc(sizeof *t);
    if (!t) return false;
    t->fn = fn, t->arg = arg, t->next = NULL;
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
    pthread_mutex_unlock(&o->mu);
    return true;
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
    bool join = !o->joined;
    o->joined = true;
    pthread_mutex_unlock(&o->mu);
    if (join)
        for (int i = 0; i < o->n; i++) pthread_join(o->w[i].th, NULL);
}

void srv_offload_destroy(srv_offload *o)
{
    if (!o) return;
    srv_offload_drain(o);
    pthread_mutex_destroy(&o->mu);
    pthread_cond_destroy(&o->cv);
    free(o->w);
    free(o);
}
