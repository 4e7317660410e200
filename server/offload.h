/* offload.h — a few threads that do what HTTP handlers must not: encode images, load scenes.
 *
 * Design note: a handler suspends its connection, submits a task, and returns; the task
 * runs here and resumes the connection (http.h). Tasks run in submission order on
 * `threads` threads waiting on a condition variable. The server has two pools: the
 * encoders (images and tiles) and the loaders (posted scenes and bundles), so a load that
 * takes its whole --max-load-seconds never delays an image. Each thread records when its
 * current task started, so /healthz can tell a pool whose task is older than its bound
 * (srv_offload_status); a task may carry a deadline past which, still queued, it is answered
 * by a watchdog thread instead. srv_offload_destroy runs every task already submitted, then
 * joins; submissions after it started are refused. */
#ifndef SRV_OFFLOAD_H
#define SRV_OFFLOAD_H

#include <stdbool.h>

typedef struct srv_offload srv_offload;

srv_offload *srv_offload_create(int threads);
/* False (the task is not run) when shutting down or out of memory. Thread-safe. */
bool srv_offload_submit(srv_offload *o, void (*fn)(void *arg), void *arg);
/* The same with a deadline (monotonic seconds, CLOCK_MONOTONIC): if the task is still
 * queued then, the pool's watchdog thread takes it out and runs expired(arg) instead of
 * fn (so a request waiting behind busy threads is answered at its bound). At shutdown the
 * queued tasks run fn as usual. */
bool srv_offload_submit_bounded(srv_offload *o, void (*fn)(void *arg), void (*expired)(void *arg), void *arg,
                                double deadline);

/* What a pool is doing now. */
typedef struct srv_offload_status {
    int threads, busy, queued;
    double oldest_task_s;   /* how long the longest-running task has run; 0 when idle */
    double oldest_queued_s; /* how long the first waiting task has waited; 0 when none */
    int stuck;              /* tasks running for longer than the bound asked about */
} srv_offload_status;
/* Thread-safe; a short lock (never held while a task runs). */
void srv_offload_get_status(srv_offload *o, double bound_s, srv_offload_status *out);

/* Stops accepting, drains the queue, joins. */
void srv_offload_drain(srv_offload *o);
void srv_offload_destroy(srv_offload *o);

#endif
