/* offload.h — a few threads that do what HTTP handlers must not: encode images.
 *
 * Design note: a handler suspends its connection, submits a task, and returns; the task
 * runs here and resumes the connection (http.h). Tasks run in submission order on
 * `threads` threads waiting on a condition variable. srv_offload_destroy runs every task
 * already submitted, then joins; submissions after it started are refused. */
#ifndef SRV_OFFLOAD_H
#define SRV_OFFLOAD_H

#include <stdbool.h>

typedef struct srv_offload srv_offload;

srv_offload *srv_offload_create(int threads);
/* False (the task is not run) when shutting down or out of memory. Thread-safe. */
bool srv_offload_submit(srv_offload *o, void (*fn)(void *arg), void *arg);
/* Stops accepting, drains the queue, joins. */
void srv_offload_drain(srv_offload *o);
void srv_offload_destroy(srv_offload *o);

#endif
