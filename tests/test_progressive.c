/* test_progressive.c — the pass and halt policy and the progress estimate (render/progressive.h).
 * Pure functions: every case is an exact value. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>

#include "render/progressive.h"

static ts_job_settings settings(uint32_t spp, double time_limit, double target_error)
{
    ts_job_settings js = {TS_INTEGRATOR_PATH, spp, 0, time_limit, target_error};
    return js;
}

static void test_passes_double_and_cap(void **state)
{
    (void)state;
    ts_job_settings js = settings(100, 0, 0);
    uint32_t ends[16], n = 0;
    ts_pass_state st = {0};
    st.error = -1;
    while (ts_progressive_halt(&js, &st) == TS_HALT_NONE) {
        ends[n++] = st.done = ts_progressive_next_pass_end(&js, &st, 0);
        st.elapsed_s += 1;
    }
    uint32_t want[] = {1, 2, 4, 8, 16, 32, 64, 100};
    assert_int_equal(n, 8);
    for (uint32_t i = 0; i < n; i++) assert_int_equal(ends[i], want[i]);
    assert_int_equal(ts_progressive_halt(&js, &st), TS_HALT_SPP);
}

static void test_halt_order(void **state)
{
    (void)state;
    ts_job_settings js = settings(64, 10, 0.05);
    ts_pass_state st = {8, 0, 20, 0, 0.01, true};
    assert_int_equal(ts_progressive_halt(&js, &st), TS_HALT_CANCELLED);
    st.cancelled = false;
    assert_int_equal(ts_progressive_halt(&js, &st), TS_HALT_ERROR); /* error before time */
    st.error = 0.5;
    assert_int_equal(ts_progressive_halt(&js, &st), TS_HALT_TIME);
    /* The error is not trusted below TS_PROGRESSIVE_ERROR_MIN_SPP. */
    st = (ts_pass_state){2, 0, 1, 0, 0.001, false};
    assert_int_equal(ts_progressive_halt(&js, &st), TS_HALT_NONE);
    st.done = TS_PROGRESSIVE_ERROR_MIN_SPP;
    assert_int_equal(ts_progressive_halt(&js, &st), TS_HALT_ERROR);
}

/* The last pass is shrunk to the time left at this process's own speed (not counting a
 * resumed render's earlier time and samples), and to max_pass_s. */
static void test_time_fit(void **state)
{
    (void)state;
    ts_job_settings js = settings(1u << 20, 10, 0);
    ts_pass_state st = {64, 0, 8, 0, -1, false}; /* 8 s for 64 spp: 0.125 s/spp, 2 s left: 16 spp */
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 0), 64 + 16);
    st = (ts_pass_state){64, 32, 8, 4, -1, false}; /* here: 32 spp in 4 s, 2 s left: 16 spp */
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 0), 64 + 16);
    js.time_limit_s = 0;
    st = (ts_pass_state){64, 0, 8, 0, -1, false};
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 1.0), 64 + 8); /* 1 s at 0.125 s/spp */
    st.elapsed_s = 1e6;                                                     /* still one more sample */
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 1.0), 65);
}

static void test_estimate(void **state)
{
    (void)state;
    double p, eta;
    ts_job_settings js = settings(1000, 0, 0);
    ts_progress_in in = {100, 0, 10, 0, -1, 0, -1, 0, false}; /* 10 spp/s */
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(fabs(p - 0.1) < 1e-12 && fabs(eta - 90) < 1e-9);
    /* A time limit that comes first. */
    js.time_limit_s = 20;
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(fabs(p - 0.5) < 1e-12 && fabs(eta - 10) < 1e-9);
    /* A target error: 0.1 at 100 spp, 0.2 at 25 → slope −0.5; 0.05 needs 400 spp. */
    js = settings(1000, 0, 0.05);
    in = (ts_progress_in){100, 0, 10, 0, 0.1, 100, 0.2, 25, false};
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(fabs(p - 0.25) < 1e-9 && fabs(eta - 30) < 1e-6);
    /* A target error before its first estimate: the spp cap's 99.9 s is no estimate of
     * when the render ends; a time limit bounds it. */
    in = (ts_progress_in){1, 0, 0.1, 0, -1, 0, -1, 0, false};
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(fabs(p - 0.001) < 1e-12 && eta < 0);
    js.time_limit_s = 50;
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(fabs(p - 0.1 / 50) < 1e-12 && fabs(eta - 49.9) < 1e-9);
    js.time_limit_s = 0;
    /* No speed yet: progress known, ETA not. */
    in = (ts_progress_in){0, 0, 0, 0, -1, 0, -1, 0, false};
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(p == 0 && eta < 0);
    in.finished = true;
    ts_progressive_estimate(&js, &in, &p, &eta);
    assert_true(p == 1 && eta == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_passes_double_and_cap),
        cmocka_unit_test(test_halt_order),
        cmocka_unit_test(test_time_fit),
        cmocka_unit_test(test_estimate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
