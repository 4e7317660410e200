/* test_render.c — the tile renderer: the film is bit-identical whatever the thread count
 * and however the sample range is split into passes (DESIGN.md §6). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <string.h>

#include "render.h"

static ts_film *render(const ts_scene *s, int threads, const uint32_t *passes, int n_passes)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                s->crop_y1 - s->crop_y0, &err);
    assert_non_null(f);
    ts_render_stats stats = {0};
    uint32_t begin = 0;
    for (int i = 0; i < n_passes; i++) {
        ts_render_request req = {s, TS_INTEGRATOR_AO, f, begin, begin + passes[i], threads, NULL, NULL, NULL};
        assert_int_equal(ts_render(&req, &stats, &err), TS_OK);
        begin += passes[i];
    }
    assert_int_equal(stats.counters.nonfinite, 0);
    assert_int_equal(stats.counters.samples, (uint64_t)f->width * f->height * begin);
    return f;
}

static void test_thread_count_and_passes_do_not_change_pixels(void **state)
{
    (void)state;
    ts_scene *s = NULL;
    ts_error err = {0};
    assert_int_equal(ts_scene_load_builtin(NULL, &s, &err), TS_OK);
    /* A smaller film keeps the test quick; crop a window off-centre to exercise offsets. */
    s->crop_x0 = 100, s->crop_x1 = 230, s->crop_y0 = 200, s->crop_y1 = 290;
    uint32_t one[] = {8}, split[] = {1, 1, 2, 4};
    ts_film *a = render(s, 1, one, 1);
    ts_film *b = render(s, 2, one, 1);
    ts_film *c = render(s, 3, split, 4);
    size_t bytes = sizeof *a->pixels * (size_t)a->width * a->height;
    assert_memory_equal(a->pixels, b->pixels, bytes);
    assert_memory_equal(a->pixels, c->pixels, bytes);
    /* And the image is not trivially empty: the room is mostly unoccluded. */
    ts_rgb m = ts_film_pixel_rgb(a, 160, 250);
    assert_true(m.r > 0.05f && m.r <= 1.0f);
    ts_film_destroy(a);
    ts_film_destroy(b);
    ts_film_destroy(c);
    ts_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_count_and_passes_do_not_change_pixels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
