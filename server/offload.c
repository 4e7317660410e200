/* offload.c — the encoder threads; see offload.h. */
#include "offload.h"

#include <pthread.h>
#include <stdlib.h>

typedef struct task {
    void (*fn)(void *);
    void *arg;
    struct task *next;
} task;

struct srv_offload {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    task *head, *tail; /* guarded by mu */
    bool stopping;     /* guarded by mu */
    bool joined;
    int n;
    pthread_t *th;
};

static void *run(void *arg)
{
    srv_offload *o = arg;
    pthread_mutex_lock(&o->mu);
    for (;;) {
        while (!o->head && !o->stopping) pthread_cond_wait(&o->cv, &o->mu);
        task *t = o->head;
        if (!t) break; /* stopping and drained */
        o->head = t->next;
        if (!o->head) o->tail = NULL;
        pthread_mutex_unlock(&o->mu);
        t->fn(t->arg);
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
    o->th = calloc((size_t)threads, sizeof *o->th);
    if (!o->th) {
        free(o);
        return NULL;
    }
    pthread_mutex_init(&o->mu, NULL);
    pthread_cond_init(&o->cv, NULL);
    while (o->n < threads && pthread_create(&o->th[o->n], NULL, run, o) == 0) o->n++;
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
    pthread_mutex_lock(&o->mu);
    if (o->stopping) {
        pthread_mutex_unlock(&o->mu);
        free(t);
        return false;
    }
    if (o->tail) o->tail->next = t;
    else o->head = t;
    o->tail = t;
    pthread_cond_signal(&o->cv);
    pthread_mutex_unlock(&o->mu);
    return true;
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
        for (int i = 0; i < o->n; i++) pthread_join(o->th[i], NULL);
}

void srv_offload_destroy(srv_offload *o)
{
    if (!o) return;
    srv_offload_drain(o);
    pthread_mutex_destroy(&o->mu);
    pthread_cond_destroy(&o->cv);
    free(o->th);
    free(o);
}
