/* cancel.h — a long operation (loading a scene, building its BVH) asked to stop.
 *
 * Design note: the caller owns a ts_cancel and hands a pointer down (ts_scene_limits.cancel,
 * ts_pbrt_limits.cancel, ts_mesh_limits.cancel); the loops of the work poll it with
 * ts_cancel_check, which costs one clock read and two atomic loads, at least every few
 * milliseconds of work. It stops when any thread sets `cancelled`, when the flag `stop`
 * that many operations share (a server shutting down) is set, or when the monotonic clock
 * (ts_cancel_now) passes `deadline`. The first check that finds the deadline passed sets
 * `timed_out`, so the owner can tell a time-out from a cancellation. A NULL ts_cancel
 * never stops. Thread-safe: polled from any thread (Embree's build threads too). */
#ifndef TS_CANCEL_H
#define TS_CANCEL_H

#include <stdatomic.h>
#include <stdbool.h>

#include "core/error.h"

typedef struct ts_cancel {
    atomic_bool cancelled;   /* set by any thread: stop now */
    const atomic_bool *stop; /* a flag shared with other operations (shutdown), or NULL */
    double deadline;         /* ts_cancel_now() seconds after which the work stops; 0: none */
    double bound_s;          /* the time it was given (for the sentence); 0: none */
    atomic_bool timed_out;   /* set by the check that found the deadline passed */
} ts_cancel;

/* Monotonic seconds (CLOCK_MONOTONIC). Thread-safe. */
double ts_cancel_now(void);

/* A ts_cancel that stops `bound_s` seconds from now (0: never by time), or when *stop is
 * set (stop may be NULL). */
void ts_cancel_init(ts_cancel *c, const atomic_bool *stop, double bound_s);

/* True when c says stop (NULL: false); records a time-out in c->timed_out. */
bool ts_cancel_requested(ts_cancel *c);

/* TS_OK, or TS_ERR_CANCELLED with a sentence in err ("the load took more than its 30 s",
 * or "cancelled"). */
ts_status ts_cancel_check(ts_cancel *c, ts_error *err);

#endif
