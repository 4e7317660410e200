/* scene_support.h — loading scenes from text and rendering them, for tests.
 *
 * Design note: the few steps every scene test repeats, each failing the calling cmocka
 * test with the loader's sentence: a JSON document or pbrt-v3 text (called "t" / "t.pbrt"
 * in messages, no base folder) loaded, or refused with an exact sentence; a scene
 * rendered into a film of its size at its spp on a given number of threads, no sample
 * dropped as non-finite. pbrt-v3 warnings are counted, the last kept. Not thread-safe. */
#ifndef TS_TESTS_SCENE_SUPPORT_H
#define TS_TESTS_SCENE_SUPPORT_H

#include "core/error.h"
#include "film/film.h"
#include "scene/scene.h"

typedef struct ts_test_warnings {
    int n;
    char last[TS_ERROR_MAX + 64];
} ts_test_warnings;

/* The scene of a JSON document; fails the test with the sentence and the document. */
ts_scene *ts_test_load_json(const char *doc);
/* Fails the test unless doc is refused with exactly the sentence want. */
void ts_test_json_refused(const char *doc, const char *want);
/* The scene of pbrt-v3 text, its warnings into *w (may be NULL). */
ts_scene *ts_test_load_pbrt(const char *text, ts_test_warnings *w);
/* Fails the test unless text is refused with exactly the sentence want. */
void ts_test_pbrt_refused(const char *text, const char *want);
/* s rendered with its integrator at its spp on `threads` threads; the caller destroys it. */
ts_film *ts_test_render(const ts_scene *s, int threads);

#endif
