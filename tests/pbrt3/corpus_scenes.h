/* corpus_scenes.h — the shared pbrt-v3 collection as the corpus tests see it: its scenes
 * with the spp each is rendered at, pbrt-v3's reference entry (REFERENCES.md), and the one
 * way a scene is loaded and rendered. pbrt3_corpus (tests/pbrt3/corpus.c) renders every
 * scene K times this way and compares with pbrt-v3; pbrt3_corpus_http
 * (tests/pbrt3/corpus_http.c) checks that a bundle posted to `tessera serve` renders to the
 * same pixels as render k = 0, so the comparison holds for the HTTP path too. */
#ifndef TS_TESTS_PBRT3_CORPUS_SCENES_H
#define TS_TESTS_PBRT3_CORPUS_SCENES_H

#include <stdbool.h>
#include <stdint.h>

#include "render/render.h"
#include "load/scene_load.h"

typedef struct corpus_scene {
    const char *name;     /* DIR/NAME/NAME.pbrt, NAME-pbrt3.exr */
    int spp;              /* per render of pbrt3_corpus (K renders, seeds 0 … K − 1) */
    const char *expected; /* the missing feature it needs, or NULL: must pass */
    uint32_t light_cap;   /* the K renders' samples per light at most (0: 1), ts_corpus_cap_lights */
    bool refused;         /* expected is a refusal at load: pbrt3_corpus_http and pbrt3_convert
                           * expect the scene refused too (and fail loudly when it loads) */
} corpus_scene;

/* The scenes of the collection in DIR, known by DIR's last name: "pbrt-v3" (the scenes
 * by others) or "pbrt-v3-next" (the next steps' scenes, ../shared/scenes/pbrt-v3-next);
 * *count their number. NULL (and a sentence on stdout) for any other folder. */
const corpus_scene *ts_corpus_scenes_of(const char *dir, int *count);

/* The entry named name in DIR's table, or NULL. */
const corpus_scene *ts_corpus_scene_named(const char *dir, const char *name);

/* True when DIR holds the collection (its REFERENCES.md); else prints "SKIPPED: …" (the
 * test then exits 77, ctest's SKIP_RETURN_CODE). */
bool ts_corpus_present(const char *dir);

/* pbrt-v3's spp and seconds for name from DIR/REFERENCES.md ("- NAME: … reference: pbrt-v3
 * 13d871f, 1024 spp, 133 s …"); false when there is no such entry. */
bool ts_corpus_reference_entry(const char *dir, const char *name, int *spp, double *seconds);

/* Loads DIR/NAME/NAME.pbrt and sets its sampler's spp to pbrt-v3's reference spp ref_spp:
 * textured scenes carry ray differentials scaled by 1/√(sampler spp) as pbrt-v3 does
 * (renderer/render/render.c), so each render filters its textures as the reference was
 * filtered, whatever its own spp (the request's sample range). */
ts_status ts_corpus_load(const char *dir, const char *name, int ref_spp, ts_warning_fn warn, void *warn_ctx,
                         ts_scene **out, ts_error *err);

/* Caps every light's samples (pbrt-v3's nsamples) at cs->light_cap (0: 1), as the K
 * renders take them. */
void ts_corpus_cap_lights(ts_scene *s, const corpus_scene *cs);

/* The process's CPU time so far (user + system, every thread), seconds. */
double ts_corpus_cpu_seconds(void);

/* Renders s with seed and spp samples per pixel (samples 0 … spp − 1) on 2 threads into a
 * new film (the caller destroys it); adds the render's wall time to *seconds and the
 * process's CPU time (user + system, every thread) over it to *cpu_seconds. NULL with err
 * filled on failure. */
ts_film *ts_corpus_render(ts_scene *s, uint32_t seed, uint32_t spp, double *seconds, double *cpu_seconds,
                          ts_error *err);

#endif
