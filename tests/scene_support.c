/* scene_support.c — see scene_support.h. */
#include "scene_support.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
// clang-format off
#include <cmocka.h>
// clang-format on

#include <stdio.h>
#include <string.h>

#include "json/scene_json.h"
#include "load/scene_load.h"
#include "render/render.h"

ts_scene *ts_test_load_json(const char *doc)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err)) fail_msg("%s\n%s", err.message, doc);
    return s;
}

void ts_test_json_refused(const char *doc, const char *want)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_status st = ts_scene_load_text(doc, strlen(doc), NULL, "t", NULL, &s, &err);
    if (st == TS_OK) fail_msg("accepted, expected \"%s\"", want);
    if (strcmp(err.message, want) != 0) fail_msg("got      \"%s\"\nexpected \"%s\"", err.message, want);
    assert_null(s);
}

static void on_warning(void *ctx, const char *msg)
{
    ts_test_warnings *w = ctx;
    if (!w) return;
    w->n++;
    snprintf(w->last, sizeof w->last, "%s", msg);
}

ts_scene *ts_test_load_pbrt(const char *text, ts_test_warnings *w)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, w, &s, &err))
        fail_msg("%s", err.message);
    return s;
}

void ts_test_pbrt_refused(const char *text, const char *want)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    ts_test_warnings w = {0};
    ts_status st = ts_scene_load_pbrt_text(text, strlen(text), NULL, "t.pbrt", NULL, on_warning, &w, &s, &err);
    if (st == TS_OK) fail_msg("accepted, expected \"%s\"", want);
    if (strcmp(err.message, want) != 0) fail_msg("got      \"%s\"\nexpected \"%s\"", err.message, want);
    assert_null(s);
}

ts_film *ts_test_render(const ts_scene *s, int threads)
{
    ts_error err = {0};
    ts_film *f = ts_film_create(s->width, s->height, 0, 0, s->width, s->height, &err);
    if (!f) fail_msg("%s", err.message);
    ts_render_stats stats = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, s->spp, threads, NULL, NULL, NULL};
    if (ts_render(&req, &stats, &err)) fail_msg("%s", err.message);
    assert_int_equal(stats.counters.nonfinite, 0);
    return f;
}
