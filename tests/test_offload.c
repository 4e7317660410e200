/* test_offload.c — the encoder/loader pools (server/offload.h): tasks run in order, and the
 * status /healthz reads tells a task running past its bound (stuck) from a busy pool. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_stuck_task)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
