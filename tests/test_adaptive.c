/* test_adaptive.c — adaptive sampling (render/adaptive.h, docs/design.md §8 "Adaptive
 * sampling"): the check points and the pass ends they impose; the choice of pixels on a
 * film of known variances; on a 64×64 Cornell box: bit-identical pixels whatever the
 * threads and the split into passes, the target reached with fewer samples than a uniform
 * render, samples concentrated where the error is, each pixel the mean of its own samples, and the bias the stopping rule adds within its bound; resuming from a
 * film and its active pixels gives the uninterrupted pixels bit for bit. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json/scene_json.h"
#include "render/adaptive.h"
#include "render/scheduler.h"

/* ---------------------------------------------------------------- the schedule */

static void test_check_points(void **state)
{
    (void)state;
    uint32_t want[] = {16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96, 112, 128, 160};
    uint32_t n = 0;
    for (size_t i = 0; i < sizeof want / sizeof *want; i++) {
        n = ts_adaptive_next_check(n);
        assert_int_equal(n, want[i]);
        assert_true(ts_adaptive_is_check(n));
        assert_false(ts_adaptive_is_check(n + 1));
    }
    assert_int_equal(ts_adaptive_next_check(5), 16);
    assert_int_equal(ts_adaptive_next_check(33), 40);
    assert_false(ts_adaptive_is_check(8));
    assert_int_equal(ts_adaptive_next_check(1u << 20), (1u << 20) + (1u << 18));
    assert_int_equal(ts_adaptive_next_check(UINT32_MAX - 1), UINT32_MAX);
}

/* Pass ends: doubling to 16, then check point to check point, capped; a pass shrunk by
 * max_pass_s never runs past a check point. */
static void test_pass_ends(void **state)
{
    (void)state;
    ts_job_settings js = {TS_INTEGRATOR_PATH, 100, 0, 0, 0.05, true};
    uint32_t want[] = {1, 2, 4, 8, 16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96, 100}, n = 0;
    ts_pass_state st = {0};
    st.error = 1;
    while (ts_progressive_halt(&js, &st) == TS_HALT_NONE) {
        assert_true(n < sizeof want / sizeof *want);
        st.done = ts_progressive_next_pass_end(&js, &st, 0);
        assert_int_equal(st.done, want[n++]);
    }
    assert_int_equal(n, sizeof want / sizeof *want);
    /* 1 s per spp and passes of at most 3 s: 16 → 19 → 20 (not 22). */
    st = (ts_pass_state){16, 0, 16, 0, 1, false};
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 3), 19);
    st = (ts_pass_state){19, 0, 19, 0, 1, false};
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 3), 20);
    js.adaptive = false;
    st = (ts_pass_state){16, 0, 16, 0, 1, false};
    assert_int_equal(ts_progressive_next_pass_end(&js, &st, 0), 32);
}

/* A 16 × 8 film, 16 samples a pixel: the left half alternates 0 and 2 (variance 1 about
 * a mean of 1), the right half is 1 in every sample (no variance). With t = 0.1 the left
 * half's share is K·√v ≈ 50 samples (K = mean √v̄ / t²): it stays active; the right half
 * stops, but for its first column (its 3×3 mean of v holds the left half's) and the one
 * after it (the dilation). */
static void test_select(void **state)
{
    (void)state;
    ts_error err = {0};
    int w = 16, h = 8;
    ts_film *f = ts_film_create(w, h, 0, 0, w, h, &err);
    assert_non_null(f);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int i = 0; i < 16; i++) {
                float v = x < w / 2 ? (float)(2 * (i & 1)) : 1.0f;
                ts_film_add_sample(f, x, y, (ts_rgb){v, v, v}, 1);
            }
    uint8_t active[16 * 8];
    float scratch[16 * 8];
    memset(active, 1, sizeof active);
    active[0] = 0; /* stopped earlier: stays stopped */
    size_t n = ts_adaptive_select(f, 0.1, active, scratch);
    size_t count = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            bool want = x <= w / 2 + 1 && !(x == 0 && y == 0);
            assert_int_equal(active[y * w + x], want);
            count += want;
        }
    assert_int_equal(n, count);
    /* Every pixel past its share (a loose target): none would stay, so the set is kept. */
    size_t before = n;
    n = ts_adaptive_select(f, 0.9, active, scratch);
    assert_int_equal(n, before);
    ts_film_destroy(f);
}

/* ---------------------------------------------------------------- renders */

/* The Cornell box at 64 × 64 (scenes/cornell-box.json, its film made smaller). */
static ts_scene *cornell64(void)
{
    size_t len = 0;
    const char *text = ts_scene_builtin_text(&len);
    char *t = malloc(len + 1);
    assert_non_null(t);
    memcpy(t, text, len);
    t[len] = '\0';
    char *w = strstr(t, "\"width\": 512"), *h = strstr(t, "\"height\": 512");
    assert_non_null(w);
    assert_non_null(h);
    memcpy(w, "\"width\":  64", 12);
    memcpy(h, "\"height\":  64", 13);
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_text(t, len, NULL, "cornell-box", NULL, &s, &err), TS_OK);
    free(t);
    return s;
}

typedef struct waiter {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool done;
    ts_job_progress final;
    /* Optional: at this pass end (every tile holds it), keep the film and its active pixels. */
    uint32_t keep_at;
    ts_film *kept;
    uint8_t *kept_active;
    uint32_t kept_active_spp;
} waiter;

static void on_pass(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    waiter *w = user;
    if (!w->keep_at || p->spp_done != w->keep_at || w->kept) return;
    ts_error err = {0};
    int nx, ny;
    ts_sched_job_grid(j, &nx, &ny);
    uint32_t *tile_spp = calloc((size_t)nx * ny, sizeof *tile_spp);
    int fw, fh;
    ts_sched_job_window(j, NULL, NULL, NULL, NULL, &fw, &fh);
    w->kept_active = malloc((size_t)fw * fh);
    w->kept = ts_sched_job_film_adaptive(j, tile_spp, w->kept_active, &w->kept_active_spp, &err);
    free(tile_spp);
}

static void on_done(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    (void)j;
    waiter *w = user;
    pthread_mutex_lock(&w->mu);
    w->done = true;
    w->final = *p;
    pthread_cond_signal(&w->cv);
    pthread_mutex_unlock(&w->mu);
}

typedef struct run_opts {
    int threads;
    uint32_t spp;
    double target_error, max_pass_s;
    bool adaptive;
    uint32_t keep_at; /* see waiter */
    /* Resume from these (all optional). */
    ts_film *film;
    const uint8_t *active;
    uint32_t active_spp;
} run_opts;

/* Renders the 64 × 64 Cornell box as one job of a pool of its own; returns its film and
 * fills *final (and *w's kept film when asked). */
static ts_film *run(const run_opts *o, ts_job_progress *final, waiter *w)
{
    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(o->threads, 1, &err);
    assert_non_null(sch);
    ts_scene *s = cornell64();
    pthread_mutex_init(&w->mu, NULL);
    pthread_cond_init(&w->cv, NULL);
    w->done = false;
    w->keep_at = o->keep_at;
    ts_sched_job_desc d = {0};
    d.scene = s;
    ts_job_settings_from_scene(s, &d.settings);
    d.settings.spp = o->spp;
    d.settings.target_error = o->target_error;
    d.settings.adaptive = o->adaptive;
    d.max_pass_s = o->max_pass_s;
    d.callbacks = (ts_job_callbacks){NULL, on_pass, on_done, w};
    uint32_t tile_spp[4];
    if (o->film) {
        for (int i = 0; i < 4; i++) tile_spp[i] = o->active_spp ? o->active_spp : 16;
        d.film = o->film;
        d.tile_spp = tile_spp;
        d.active = o->active;
        d.active_spp = o->active_spp;
    }
    ts_sched_job *j = ts_scheduler_submit(sch, &d, &err);
    assert_non_null(j);
    pthread_mutex_lock(&w->mu);
    while (!w->done) pthread_cond_wait(&w->cv, &w->mu);
    pthread_mutex_unlock(&w->mu);
    *final = w->final;
    ts_film *f = ts_sched_job_film(j, NULL, &err);
    assert_non_null(f);
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
    pthread_cond_destroy(&w->cv);
    pthread_mutex_destroy(&w->mu);
    return f;
}

static bool same_pixels(const ts_film *a, const ts_film *b)
{
    return a->width == b->width && a->height == b->height &&
           !memcmp(a->pixels, b->pixels, sizeof *a->pixels * (size_t)a->width * a->height);
}

/* The target of the render tests: 5%, reached at about 100 spp uniformly on this film. */
#define TARGET 0.05
#define CAP 1024

static ts_film *g_adaptive;         /* 2 threads, target TARGET */
static ts_job_progress g_adaptive_p;
static waiter g_adaptive_w;         /* with the film kept at 32 spp */

static int setup_adaptive(void **state)
{
    (void)state;
    run_opts o = {2, CAP, TARGET, 0, true, 32, NULL, NULL, 0};
    g_adaptive = run(&o, &g_adaptive_p, &g_adaptive_w);
    return 0;
}

static int teardown_adaptive(void **state)
{
    (void)state;
    ts_film_destroy(g_adaptive);
    ts_film_destroy(g_adaptive_w.kept);
    free(g_adaptive_w.kept_active);
    return 0;
}

/* One thread, and passes split to about a millisecond (so pass ends fall between check
 * points): the same pixels, bit for bit. */
static void test_deterministic(void **state)
{
    (void)state;
    waiter w = {0};
    ts_job_progress p;
    run_opts o = {1, CAP, TARGET, 0, true, 0, NULL, NULL, 0};
    ts_film *one = run(&o, &p, &w);
    assert_true(same_pixels(one, g_adaptive));
    assert_int_equal(p.spp_done, g_adaptive_p.spp_done);
    o = (run_opts){2, CAP, TARGET, 1e-3, true, 0, NULL, NULL, 0};
    ts_film *split = run(&o, &p, &w);
    assert_true(same_pixels(split, g_adaptive));
    ts_film_destroy(one);
    ts_film_destroy(split);
}

/* Resuming at 32 spp from the film and active pixels ts_sched_job_film_adaptive gave then:
 * the uninterrupted pixels. Without the active pixels (a film past the first check) the
 * job is refused. */
static void test_resume(void **state)
{
    (void)state;
    assert_non_null(g_adaptive_w.kept);
    assert_int_equal(g_adaptive_w.kept_active_spp, 32);
    waiter w = {0};
    ts_job_progress p;
    run_opts o = {2, CAP, TARGET, 0, true, 0, g_adaptive_w.kept, g_adaptive_w.kept_active, 32};
    ts_film *resumed = run(&o, &p, &w);
    g_adaptive_w.kept = NULL; /* the job's */
    assert_true(same_pixels(resumed, g_adaptive));
    ts_film_destroy(resumed);

    ts_error err = {0};
    ts_scheduler *sch = ts_scheduler_create(1, 1, &err);
    ts_scene *s = cornell64();
    ts_film *f = ts_film_create(64, 64, 0, 0, 64, 64, &err);
    uint32_t tile_spp[4] = {32, 32, 32, 32};
    ts_sched_job_desc d = {0};
    d.scene = s;
    ts_job_settings_from_scene(s, &d.settings);
    d.settings.adaptive = true;
    d.film = f;
    d.tile_spp = tile_spp;
    assert_null(ts_scheduler_submit(sch, &d, &err));
    assert_int_equal(err.status, TS_ERR_INVALID);
    assert_non_null(strstr(err.message, "active pixels"));
    ts_film_destroy(f);
    ts_scene_destroy(s);
    ts_scheduler_destroy(sch);
}

/* Mean sample count of the film's pixels in [x0, x1) × [y0, y1). */
static double mean_count(const ts_film *f, int x0, int x1, int y0, int y1)
{
    double sum = 0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) sum += (double)ts_film_pixel_at(f, x, y)->count;
    return sum / ((double)(x1 - x0) * (y1 - y0));
}

/* The target is reached, with fewer samples than a uniform render of the same target
 * (deterministic: fixed seed), and the counts follow the error. */
static void test_concentrates(void **state)
{
    (void)state;
    assert_int_equal(g_adaptive_p.halt, TS_HALT_ERROR);
    assert_true(ts_film_relative_error(g_adaptive) <= TARGET);
    waiter w = {0};
    ts_job_progress up;
    run_opts o = {2, CAP, TARGET, 0, false, 0, NULL, NULL, 0};
    ts_film *uniform = run(&o, &up, &w);
    assert_int_equal(up.halt, TS_HALT_ERROR);
    print_message("adaptive: %llu samples to %.4f at %u spp; uniform: %llu samples to %.4f at %u spp\n",
                  (unsigned long long)g_adaptive_p.samples, ts_film_relative_error(g_adaptive), g_adaptive_p.spp_done,
                  (unsigned long long)up.samples, ts_film_relative_error(uniform), up.spp_done);
    /* The uniform render overshoots (passes double); its samples for the adaptive one's
     * error by the 1/n law of a uniform render's error² (exact in expectation). */
    double ea = ts_film_relative_error(g_adaptive), eu = ts_film_relative_error(uniform);
    double uniform_samples = (double)up.samples * (eu / ea) * (eu / ea);
    print_message("uniform samples for the same error: %.0f; adaptive ÷ uniform %.3f\n", uniform_samples,
                  (double)g_adaptive_p.samples / uniform_samples);
    assert_true((double)g_adaptive_p.samples < 0.95 * uniform_samples);
    uint64_t least = UINT64_MAX, most = 0;
    for (int i = 0; i < 64 * 64; i++) {
        uint64_t c = g_adaptive->pixels[i].count;
        least = c < least ? c : least;
        most = c > most ? c : most;
    }
    /* Counts against the error each pixel has per sample (v_p = r_p · n_p of the uniform
     * render): the quarter of the pixels with the largest v takes more than 1.5 times the
     * samples of the quarter with the smallest (√ of their v's ratio, adaptive.h, but
     * for the cap). Named regions: the ceiling (lit from below
     * only, noisy) against the floor in front of the boxes (lit by the light directly). */
    static double key[64 * 64];
    static int idx[64 * 64];
    for (int i = 0; i < 64 * 64; i++) {
        key[i] = ts_film_pixel_relative_variance(uniform, i % 64, i / 64) * (double)uniform->pixels[i].count;
        idx[i] = i;
    }
    for (int i = 1; i < 64 * 64; i++) /* insertion sort by key, ties by index: deterministic */
        for (int k = i; k > 0 && key[idx[k]] < key[idx[k - 1]]; k--) {
            int t = idx[k];
            idx[k] = idx[k - 1], idx[k - 1] = t;
        }
    double low = 0, high = 0;
    for (int i = 0; i < 1024; i++) {
        low += (double)g_adaptive->pixels[idx[i]].count / 1024;
        high += (double)g_adaptive->pixels[idx[64 * 64 - 1 - i]].count / 1024;
    }
    double ceiling = mean_count(g_adaptive, 16, 48, 0, 6), floor = mean_count(g_adaptive, 8, 56, 58, 64);
    print_message("counts %llu to %llu; by v: lowest quarter %.1f, highest %.1f; ceiling %.1f, floor %.1f\n",
                  (unsigned long long)least, (unsigned long long)most, low, high, ceiling, floor);
    assert_true(least >= TS_ADAPTIVE_MIN_SPP);
    assert_int_equal(most, g_adaptive_p.spp_done);
    assert_true(high > 1.5 * low);
    assert_true(ceiling > 1.3 * floor);
    ts_film_destroy(uniform);
}

/* The bias the stopping rule adds (docs/design.md §8 "Adaptive sampling"). The uniform
 * render at the adaptive one's final spp with the same seed holds every pixel's first
 * n_p samples and more, so D_p = (Ŷ_adaptive − Ŷ_uniform) / sqrt(Ŷ_uniform² + ε) has the
 * stopping rule's bias for its expectation, and about the stopped pixel's relative error
 * for its spread. The mean of D over the 4096 pixels must lie within the bound of the
 * design (t/9: a pixel's own samples are 1/9 of the estimate its stop depends on) plus 4
 * standard errors of that mean (from the
 * D_p themselves): a false failure rate of 6e-5 for a normal mean, given the bound holds.
 * Each pixel's value is the mean of its own samples: the test fails (mean D = −0.34) when
 * the stopped pixels' sums are divided by the pass's count instead. */
static void test_bias(void **state)
{
    (void)state;
    waiter w = {0};
    ts_job_progress up;
    run_opts o = {2, g_adaptive_p.spp_done, 0, 0, false, 0, NULL, NULL, 0};
    ts_film *uniform = run(&o, &up, &w);
    double sum = 0, sum_sq = 0, eps = 1e-3;
    int n = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            double ya = ts_rgb_luminance(ts_film_pixel_rgb(g_adaptive, x, y));
            double yu = ts_rgb_luminance(ts_film_pixel_rgb(uniform, x, y));
            double d = (ya - yu) / sqrt(yu * yu + eps);
            sum += d, sum_sq += d * d, n++;
        }
    double mean = sum / n, sd = sqrt((sum_sq / n - mean * mean) / (n - 1));
    double bound = TARGET / 9;
    print_message("mean relative deviation %.5f ± %.5f (bound %.4f)\n", mean, sd, bound);
    assert_true(fabs(mean) <= bound + 4 * sd);
    ts_film_destroy(uniform);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_check_points), cmocka_unit_test(test_pass_ends), cmocka_unit_test(test_select),
        cmocka_unit_test(test_deterministic), cmocka_unit_test(test_resume), cmocka_unit_test(test_concentrates),
        cmocka_unit_test(test_bias),
    };
    return cmocka_run_group_tests(tests, setup_adaptive, teardown_adaptive);
}
