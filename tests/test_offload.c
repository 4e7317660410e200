/* test_offload.c — the encoder/loader pools (server/offload.h): tasks run in order, the
 * status /healthz reads tells a task running past its bound (stuck) from a busy pool, and
 * a task that waited in the queue past its deadline is answered by the watchdog. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <time.h>

#include "offload.h"

typedef struct gate {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool open;
    atomic_int ran;
} gate;

static void wait_gate(void *arg)
{
    gate *g = arg;
    pthread_mutex_lock(&g->mu);
    while (!g->open) pthread_cond_wait(&g->cv, &g->mu);
    pthread_mutex_unlock(&g->mu);
    atomic_fetch_add(&g->ran, 1);
}

static void sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

/* One thread held by a task: busy 1, the next task queued; the held task counts as stuck
 * only once it has run longer than the bound asked about; once released, all ran. */
static void test_stuck_task(void **state)
{
    (void)state;
    gate g = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, false, 0};
    srv_offload *o = srv_offload_create(1);
    assert_non_null(o);
    assert_true(srv_offload_submit(o, wait_gate, &g));
    assert_true(srv_offload_submit(o, wait_gate, &g));
    sleep_ms(150);
    srv_offload_status st;
    srv_offload_get_status(o, 10.0, &st);
    assert_int_equal(st.threads, 1);
    assert_int_equal(st.busy, 1);
    assert_int_equal(st.queued, 1);
    assert_int_equal(st.stuck, 0); /* 0.15 s of a 10 s bound */
    assert_true(st.oldest_task_s >= 0.1 && st.oldest_queued_s >= 0.1);
    srv_offload_get_status(o, 0.05, &st);
    assert_int_equal(st.stuck, 1);
    pthread_mutex_lock(&g.mu);
    g.open = true;
    pthread_cond_broadcast(&g.cv);
    pthread_mutex_unlock(&g.mu);
    srv_offload_drain(o);
    assert_int_equal(atomic_load(&g.ran), 2);
    srv_offload_get_status(o, 0.05, &st);
    assert_int_equal(st.busy, 0);
    assert_int_equal(st.queued, 0);
    assert_int_equal(st.stuck, 0);
    assert_false(srv_offload_submit(o, wait_gate, &g)); /* drained: refused */
    srv_offload_destroy(o);
}

static atomic_int g_ran_fn, g_ran_expired;
static void count_fn(void *arg) { (void)arg, atomic_fetch_add(&g_ran_fn, 1); }
static void count_expired(void *arg) { (void)arg, atomic_fetch_add(&g_ran_expired, 1); }

static double mono_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A bounded task queued behind a held thread is answered by the watchdog at its deadline
 * (expired runs, not fn), within the scheduling of one thread (0.5 s allowed on a loaded
 * machine; the deadline is 0.1 s); one whose deadline has not come runs fn. */
static void test_deadline_in_queue(void **state)
{
    (void)state;
    gate g = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, false, 0};
    srv_offload *o = srv_offload_create(1);
    assert_true(srv_offload_submit(o, wait_gate, &g));
    double t0 = mono_s();
    assert_true(srv_offload_submit_bounded(o, count_fn, count_expired, NULL, t0 + 0.1));
    assert_true(srv_offload_submit_bounded(o, count_fn, count_expired, NULL, t0 + 60));
    while (atomic_load(&g_ran_expired) == 0 && mono_s() - t0 < 5) sleep_ms(5);
    double took = mono_s() - t0;
    assert_int_equal(atomic_load(&g_ran_expired), 1);
    assert_true(took >= 0.1 && took < 0.5);
    srv_offload_status st;
    srv_offload_get_status(o, 10, &st);
    assert_int_equal(st.queued, 1);
    pthread_mutex_lock(&g.mu);
    g.open = true;
    pthread_cond_broadcast(&g.cv);
    pthread_mutex_unlock(&g.mu);
    srv_offload_drain(o);
    assert_int_equal(atomic_load(&g_ran_fn), 1);
    assert_int_equal(atomic_load(&g_ran_expired), 1);
    srv_offload_destroy(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_stuck_task), cmocka_unit_test(test_deadline_in_queue)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
