/* test_scheduler.c — the shared render pool: same pixels as ts_render whatever the
 * threads and passes, progressive pass order, priorities, cancellation, time limit, and
 * resuming from a partial film (docs/design.md §6, scheduler.h); cancel, time limit and
 * stop take effect inside a tile, even inside one sample of a mirror sphere seen from
 * within (65535 bounces a sample), and an interrupted tile publishes nothing: every
 * tile's pixels hold whole passes, and resuming gives the uninterrupted film bit for bit. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/scheduler.h"
#include "json/scene_json.h"

static ts_scene *load(int x0, int x1, int y0, int y1)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_builtin(NULL, &s, &err), TS_OK);
    s->crop_x0 = x0, s->crop_x1 = x1, s->crop_y0 = y0, s->crop_y1 = y1;
    return s;
}

static ts_film *reference(uint32_t spp)
{
    ts_scene *s = load(100, 230, 200, 290);
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                s->crop_y1 - s->crop_y0, &err);
    ts_render_stats st = {0};
    ts_render_request req = {s, TS_INTEGRATOR_AO, f, 0, spp, 2, NULL, NULL, NULL};
    assert_int_equal(ts_render(&req, &st, &err), TS_OK);
    ts_scene_destroy(s);
    return f;
}

/* Records events; done is signalled through a condition variable (no polling). */
typedef struct recorder {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    uint32_t last_spp; /* spp of the previous tile event */
    bool order_ok;
    int tiles, passes, done;
    int tag;
} recorder;

typedef struct start_order {
    pthread_mutex_t mu;
    int n;
    int order[8];
} start_order;
static start_order g_start = {PTHREAD_MUTEX_INITIALIZER, 0, {0}};

static void rec_init(recorder *r)
{
    memset(r, 0, sizeof *r);
    pthread_mutex_init(&r->mu, NULL);
    pthread_cond_init(&r->cv, NULL);
    r->order_ok = true;
}

static void on_tile(void *user, ts_sched_job *j, const ts_tile_event *ev)
{
    (void)j;
    recorder *r = user;
    pthread_mutex_lock(&r->mu);
    if (ev->spp < r->last_spp) r->order_ok = false; /* a tile of pass k after one of pass k+1 */
    r->last_spp = ev->spp;
    bool first = r->tiles++ == 0;
    pthread_mutex_unlock(&r->mu);
    if (first) { /* start order: a job's first tile comes after the previous job's last */
        pthread_mutex_lock(&g_start.mu);
        if (g_start.n < 8) g_start.order[g_start.n++] = r->tag;
        pthread_mutex_unlock(&g_start.mu);
    }
}

static void on_pass(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    (void)j, (void)p;
    recorder *r = user;
    pthread_mutex_lock(&r->mu);
    r->passes++;
    pthread_mutex_unlock(&r->mu);
}

static void on_done(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    (void)j, (void)p;
    recorder *r = user;
    pthread_mutex_lock(&r->mu);
    r->done = 1;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
}

static void wait_done(recorder *r)
{
    pthread_mutex_lock(&r->mu);
    while (!r->done) pthread_cond_wait(&r->cv, &r->mu);
    pthread_mutex_unlock(&r->mu);
}

static ts_sched_job *submit(ts_scheduler *sch, ts_scene *s, uint32_t spp, int priority, recorder *r)
{
    ts_error err = {0};
    ts_sched_job_desc d = {0};
    d.scene = s;
    d.settings.integrator = TS_INTEGRATOR_AO;
    d.settings.spp = spp;
    d.settings.priority = priority;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, r};
    ts_sched_job *j = ts_scheduler_submit(sch, &d, &err);
    assert_non_null(j);
    return j;
}

static void assert_same_film(const ts_film *a, const ts_film *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_memory_equal(a->pixels, b->pixels, sizeof *a->pixels * (size_t)a->width * a->height);
}

static void test_same_pixels_as_ts_render_and_pass_order(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(3, 2, &err);
    assert_non_null(sch);
    recorder r;
    rec_init(&r);
    ts_sched_job *j = submit(sch, load(100, 230, 200, 290), 12, 0, &r);
    wait_done(&r);
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_DONE);
    assert_int_equal(p.halt, TS_HALT_SPP);
    assert_int_equal(p.spp_done, 12);
    assert_int_equal(p.samples, 130ull * 90 * 12);
    /* Passes end at 1, 2, 4, 8, 12: five passes of 5×3 tiles, in pass order. */
    assert_true(r.order_ok);
    assert_int_equal(r.tiles, 5 * 3 * 5);
    assert_int_equal(r.passes, 4); /* the fifth pass ends the job: on_done instead */
    ts_film *f = ts_sched_job_film(j, NULL, &err);
    ts_film *ref = reference(12);
    assert_same_film(f, ref);
    ts_film_destroy(f);
    ts_film_destroy(ref);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

static void test_priority_then_arrival(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 1, &err);
    recorder r[4];
    ts_sched_job *j[4];
    pthread_mutex_lock(&g_start.mu);
    g_start.n = 0;
    pthread_mutex_unlock(&g_start.mu);
    for (int i = 0; i < 4; i++) {
        rec_init(&r[i]);
        r[i].tag = i;
    }
    /* Job 0 (priority 9) occupies the only running slot; then 1 (prio 0), 2 (prio 5) and
     * 3 (prio 5) queue: the order must be 0, 2, 3, 1. */
    j[0] = submit(sch, load(0, 160, 0, 160), 16, 9, &r[0]);
    j[1] = submit(sch, load(0, 40, 0, 40), 2, 0, &r[1]);
    j[2] = submit(sch, load(0, 40, 0, 40), 2, 5, &r[2]);
    j[3] = submit(sch, load(0, 40, 0, 40), 2, 5, &r[3]);
    for (int i = 0; i < 4; i++) wait_done(&r[i]);
    int expect[4] = {0, 2, 3, 1};
    for (int i = 0; i < 4; i++) assert_int_equal(g_start.order[i], expect[i]);
    for (int i = 0; i < 4; i++) ts_sched_job_release(j[i]);
    ts_scheduler_destroy(sch);
}

static void test_cancel_keeps_pixels(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    ts_sched_job *j = submit(sch, load(0, 256, 0, 256), 1u << 20, 0, &r);
    /* Wait for the first pass, then cancel. */
    for (;;) {
        ts_job_progress p;
        ts_sched_job_progress(j, &p);
        if (p.spp_done >= 1) break;
        pthread_mutex_lock(&r.mu);
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += 5000000;
        if (ts.tv_nsec >= 1000000000) ts.tv_sec++, ts.tv_nsec -= 1000000000;
        pthread_cond_timedwait(&r.cv, &r.mu, &ts);
        pthread_mutex_unlock(&r.mu);
    }
    assert_true(ts_sched_job_cancel(j));
    wait_done(&r);
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_CANCELLED);
    assert_true(p.spp_done >= 1 && p.spp_done < (1u << 20));
    ts_tile_snapshot *t = ts_sched_job_tile(j, 3, 3);
    assert_non_null(t);
    assert_true(t->spp >= 1 && t->pixels[0].count == t->spp);
    ts_tile_snapshot_release(t);
    assert_false(ts_sched_job_cancel(j));
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

/* An external job (a farm's): never rendered by the workers; published films become its
 * snapshots (only changed tiles get events), its progress and its error estimate; a cancel
 * leaves it cancelling until ts_sched_job_finish, which keeps the pixels. */
static void test_external_job(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    ts_sched_job_desc d = {0};
    d.scene = load(100, 230, 200, 290);
    d.settings.integrator = TS_INTEGRATOR_AO;
    d.settings.spp = 8;
    d.external = true;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, &r};
    ts_sched_job *j = ts_scheduler_submit(sch, &d, &err);
    assert_non_null(j);
    struct timespec nap = {0, 50 * 1000 * 1000};
    nanosleep(&nap, NULL);
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_QUEUED); /* no worker took it */
    assert_int_equal(r.tiles, 0);
    assert_int_equal(ts_scheduler_samples(sch), 0);
    int nx, ny;
    ts_sched_job_grid(j, &nx, &ny);
    ts_film *four = reference(4), *eight = reference(8);
    uint64_t samples = (uint64_t)four->width * four->height * 4;
    assert_int_equal(ts_sched_job_publish(j, four, samples, &err), TS_OK);
    assert_int_equal(r.tiles, nx * ny);
    assert_int_equal(r.passes, 1);
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_RUNNING);
    assert_int_equal(p.spp_done, 4);
    assert_int_equal(p.samples, samples);
    assert_true(p.error_estimate > 0);
    ts_film *got = ts_sched_job_film(j, NULL, &err);
    assert_same_film(got, four);
    ts_film_destroy(got);
    /* The same pixels again: no tile event, one progress. */
    assert_int_equal(ts_sched_job_publish(j, four, samples, &err), TS_OK);
    assert_int_equal(r.tiles, nx * ny);
    assert_int_equal(r.passes, 2);
    /* Cancel: cancelling until its owner ends it; the next publish still lands. */
    assert_true(ts_sched_job_cancel(j));
    ts_sched_job_progress(j, &p);
    assert_true(p.cancelling);
    assert_int_equal(p.state, TS_JOB_RUNNING);
    assert_int_equal(ts_sched_job_publish(j, eight, samples * 2, &err), TS_OK);
    assert_int_equal(r.tiles, 2 * nx * ny);
    assert_true(ts_sched_job_finish(j, TS_JOB_CANCELLED, TS_HALT_CANCELLED));
    assert_int_equal(r.done, 1);
    assert_false(ts_sched_job_finish(j, TS_JOB_DONE, TS_HALT_SPP));
    assert_int_equal(ts_sched_job_publish(j, eight, samples * 2, &err), TS_ERR_INVALID); /* ended */
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_CANCELLED);
    assert_int_equal(p.spp_done, 8);
    got = ts_sched_job_film(j, NULL, &err);
    assert_same_film(got, eight);
    ts_film_destroy(got);
    /* A film of another window is refused. */
    ts_film *other = ts_film_create(four->full_width, four->full_height, 0, 0, 16, 16, &err);
    assert_int_equal(ts_sched_job_publish(j, other, 0, &err), TS_ERR_INVALID);
    ts_film_destroy(other);
    ts_film_destroy(four);
    ts_film_destroy(eight);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

static void test_time_limit(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    ts_error e2 = {0};
    ts_sched_job_desc d = {0};
    d.scene = load(0, 128, 0, 128);
    d.settings.integrator = TS_INTEGRATOR_AO;
    d.settings.spp = 1u << 22;
    d.settings.time_limit_s = 0.5;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, &r};
    double t0 = ts_now_seconds();
    ts_sched_job *j = ts_scheduler_submit(sch, &d, &e2);
    wait_done(&r);
    double took = ts_now_seconds() - t0;
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.halt, TS_HALT_TIME);
    /* The last pass is shrunk to the measured speed, so the overshoot is a fraction of
     * the limit (generous bound for a loaded machine). */
    assert_true(took >= 0.5 && took < 1.5);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

/* A two-sided mirror sphere with the camera inside: every sample bounces max_depth (65535)
 * times, about 0.1 s of one core per sample here — a tile pass of it takes minutes. */
static ts_scene *mirror_sphere(void)
{
    static const char doc[] =
        "{\"tessera\":1,\"camera\":{\"from\":[0,0,0],\"to\":[0,0,-1],\"fov\":60},"
        "\"film\":{\"width\":16,\"height\":16},\"sampler\":{\"spp\":16},"
        "\"integrator\":{\"type\":\"path\",\"max_depth\":65535,\"rr_depth\":65535},"
        "\"materials\":{\"m\":{\"type\":\"mirror\"}},"
        "\"shapes\":[{\"type\":\"sphere\",\"radius\":10,\"material\":\"m\",\"two_sided\":true}],"
        "\"lights\":[{\"type\":\"point\",\"position\":[0,1,0],\"intensity\":1}]}";
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, sizeof doc - 1, NULL, "mirror", NULL, &s, &err)) fail_msg("%s", err.message);
    return s;
}

static ts_sched_job *submit_mirror(ts_scheduler *sch, double time_limit_s, recorder *r)
{
    ts_error err = {0};
    ts_sched_job_desc d = {0};
    d.scene = mirror_sphere();
    ts_job_settings_from_scene(d.scene, &d.settings);
    d.settings.time_limit_s = time_limit_s;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, r};
    ts_sched_job *j = ts_scheduler_submit(sch, &d, &err);
    assert_non_null(j);
    return j;
}

/* Waits until the job's first tile is being rendered (it is "running") plus 50 ms. */
static void wait_running(ts_sched_job *j)
{
    for (;;) {
        ts_job_progress p;
        ts_sched_job_progress(j, &p);
        if (p.state == TS_JOB_RUNNING) break;
        struct timespec t = {0, 1000000};
        nanosleep(&t, NULL);
    }
    struct timespec t = {0, 50000000};
    nanosleep(&t, NULL);
}

/* Nothing of an interrupted tile pass is visible: no snapshot, an empty film. */
static void assert_nothing_published(ts_sched_job *j)
{
    ts_error err = {0};
    assert_null(ts_sched_job_tile(j, 0, 0));
    uint32_t spp = 99;
    ts_film *f = ts_sched_job_film(j, &spp, &err);
    assert_non_null(f);
    assert_int_equal(spp, 0);
    for (int i = 0; i < f->width * f->height; i++) assert_int_equal(f->pixels[i].count, 0);
    ts_film_destroy(f);
}

/* The bound on how long a stop may take: the target is 100 ms; the assertion allows 1 s for
 * a loaded 2-core machine (without stops inside tiles it takes minutes). */
#define STOP_BOUND_S 1.0

static void test_cancel_inside_a_sample(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    ts_sched_job *j = submit_mirror(sch, 0, &r);
    wait_running(j);
    double t0 = ts_now_seconds();
    assert_true(ts_sched_job_cancel(j));
    wait_done(&r);
    double took = ts_now_seconds() - t0;
    if (took > STOP_BOUND_S) fail_msg("cancel took %.3f s", took);
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_CANCELLED);
    assert_int_equal(p.spp_done, 0);
    assert_int_equal(p.samples, 0); /* an interrupted tile's samples do not count */
    assert_int_equal(r.tiles, 0);
    assert_nothing_published(j);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

static void test_time_limit_inside_a_sample(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    double t0 = ts_now_seconds();
    ts_sched_job *j = submit_mirror(sch, 0.3, &r);
    wait_done(&r);
    double took = ts_now_seconds() - t0;
    if (took < 0.3 || took > 0.3 + STOP_BOUND_S) fail_msg("a 0.3 s time limit stopped after %.3f s", took);
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_DONE);
    assert_int_equal(p.halt, TS_HALT_TIME);
    assert_int_equal(p.spp_done, 0);
    assert_nothing_published(j);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

static void test_stop_inside_a_sample(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    ts_sched_job *j = submit_mirror(sch, 0, &r);
    wait_running(j);
    double t0 = ts_now_seconds();
    ts_scheduler_stop(sch);
    double took = ts_now_seconds() - t0;
    if (took > STOP_BOUND_S) fail_msg("stopping the scheduler took %.3f s", took);
    ts_job_progress p;
    ts_sched_job_progress(j, &p);
    assert_int_equal(p.state, TS_JOB_RUNNING); /* a stop changes no job's state */
    assert_int_equal(r.done, 0);
    assert_nothing_published(j);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

/* Cancelling mid-pass interrupts tiles; what is left is whole passes per tile (each pixel's
 * count is its tile's spp), and resuming from it gives the film of an uninterrupted render
 * bit for bit. Cancelled at several moments, so some cancel lands inside tile passes. */
static void test_interrupted_tiles_resume_bit_identical(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    const uint32_t target = 16;
    ts_film *ref = reference(target);
    for (int k = 0; k < 4; k++) {
        recorder r;
        rec_init(&r);
        ts_sched_job *j = submit(sch, load(100, 230, 200, 290), target, 0, &r);
        struct timespec t = {0, 1000000L + 2500000L * k};
        nanosleep(&t, NULL);
        ts_sched_job_cancel(j);
        wait_done(&r);
        int nx, ny;
        ts_sched_job_grid(j, &nx, &ny);
        uint32_t *tile_spp = calloc((size_t)(nx * ny), sizeof *tile_spp);
        ts_film *partial = ts_sched_job_film(j, tile_spp, &err);
        for (int ty = 0; ty < ny; ty++)
            for (int tx = 0; tx < nx; tx++) {
                ts_tile_rect tr = ts_tile_grid_rect(100, 200, 130, 90, tx, ty);
                for (int y = tr.y; y < tr.y + tr.h; y++)
                    for (int x = tr.x; x < tr.x + tr.w; x++)
                        assert_int_equal(ts_film_pixel_at(partial, x, y)->count, tile_spp[ty * nx + tx]);
            }
        ts_sched_job_release(j);
        recorder r2;
        rec_init(&r2);
        ts_sched_job_desc d = {0};
        d.scene = load(100, 230, 200, 290);
        d.settings.integrator = TS_INTEGRATOR_AO;
        d.settings.spp = target;
        d.film = partial;
        d.tile_spp = tile_spp;
        d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, &r2};
        j = ts_scheduler_submit(sch, &d, &err);
        assert_non_null(j);
        wait_done(&r2);
        ts_film *f = ts_sched_job_film(j, NULL, &err);
        assert_same_film(f, ref);
        ts_film_destroy(f);
        free(tile_spp);
        ts_sched_job_release(j);
    }
    ts_film_destroy(ref);
    ts_scheduler_destroy(sch);
}

static void test_resume_from_partial_film(void **state)
{
    (void)state;
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(2, 2, &err);
    recorder r;
    rec_init(&r);
    ts_sched_job *j = submit(sch, load(100, 230, 200, 290), 5, 0, &r);
    wait_done(&r);
    int nx, ny;
    ts_sched_job_grid(j, &nx, &ny);
    uint32_t *tile_spp = calloc((size_t)(nx * ny), sizeof *tile_spp);
    ts_film *partial = ts_sched_job_film(j, tile_spp, &err);
    ts_sched_job_release(j);
    /* Pretend one tile got ahead (as after a kill mid-pass): re-render it to 8 spp. */
    ts_scene *s = load(100, 230, 200, 290);
    ts_render_request req = {s, TS_INTEGRATOR_AO, partial, 5, 8, 1, NULL, NULL, NULL};
    ts_counters c = {0};
    ts_render_tile(&req, 100, 200, 32, 32, &c);
    tile_spp[0] = 8;
    recorder r2;
    rec_init(&r2);
    ts_sched_job_desc d = {0};
    d.scene = s;
    d.settings.integrator = TS_INTEGRATOR_AO;
    d.settings.spp = 12;
    d.film = partial;
    d.tile_spp = tile_spp;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, &r2};
    j = ts_scheduler_submit(sch, &d, &err);
    assert_non_null(j);
    wait_done(&r2);
    ts_film *f = ts_sched_job_film(j, NULL, &err);
    ts_film *ref = reference(12);
    assert_same_film(f, ref);
    ts_film_destroy(f);
    ts_film_destroy(ref);
    free(tile_spp);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_pixels_as_ts_render_and_pass_order),
        cmocka_unit_test(test_priority_then_arrival),
        cmocka_unit_test(test_cancel_keeps_pixels),
        cmocka_unit_test(test_external_job),
        cmocka_unit_test(test_time_limit),
        cmocka_unit_test(test_resume_from_partial_film),
        cmocka_unit_test(test_cancel_inside_a_sample),
        cmocka_unit_test(test_time_limit_inside_a_sample),
        cmocka_unit_test(test_stop_inside_a_sample),
        cmocka_unit_test(test_interrupted_tiles_resume_bit_identical),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
