/* cancel.c — see cancel.h. */
#include "core/cancel.h"

#include <time.h>

double ts_cancel_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void ts_cancel_init(ts_cancel *c, const atomic_bool *stop, double bound_s)
{
    atomic_init(&c->cancelled, false);
    atomic_init(&c->timed_out, false);
    c->stop = stop;
    c->bound_s = bound_s > 0 ? bound_s : 0;
    c->deadline = bound_s > 0 ? ts_cancel_now() + bound_s : 0;
}

bool ts_cancel_requested(ts_cancel *c)
{
    if (!c) return false;
    if (atomic_load_explicit(&c->cancelled, memory_order_relaxed)) return true;
    if (c->stop && atomic_load_explicit(c->stop, memory_order_relaxed)) return true;
    if (c->deadline > 0 && ts_cancel_now() > c->deadline) {
        atomic_store(&c->timed_out, true);
        return true;
    }
    return false;
}

ts_status ts_cancel_check(ts_cancel *c, ts_error *err)
{
    if (!ts_cancel_requested(c)) return TS_OK;
    if (atomic_load(&c->timed_out))
        return ts_error_set(err, TS_ERR_CANCELLED, "the scene took more than its %g s to load (stopped)", c->bound_s);
    return ts_error_set(err, TS_ERR_CANCELLED, "loading was cancelled");
}
