/* scene.h — scene format v1 (docs/design.md §4, proto/scene.schema.json): loading, validation
 * and the immutable Scene every render thread reads.
 *
 * Design note: loading is two phases. Phase one walks the whole JSON document and checks
 * every value (types, ranges, unknown keys, references to materials, mesh files), so a
 * bad document is refused with one sentence naming its JSON path before anything is
 * built. Phase two builds: transforms, shapes, lights, the Embree accelerator. All of a
 * scene's memory comes from its arena (plus the accel, Fourier tables and environment
 * maps, which the scene owns), so ts_scene_destroy is the whole teardown. After a
 * ts_scene_load_* function returns, the scene is immutable and may be shared by any number of
 * threads. */
#ifndef TS_SCENE_H
#define TS_SCENE_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "core/arena.h"
#include "core/error.h"
#include "film/filter.h"
#include "geometry/accel.h"
#include "geometry/shape.h"
#include "lights/light.h"
#include "materials/material.h"
#include "sampling/sampler.h"

/* Resource limits checked while loading, before any large allocation. */
typedef struct ts_scene_limits {
    uint32_t max_width, max_height; /* film */
    uint64_t max_pixels;
    uint32_t max_spp;
    uint64_t max_triangles; /* all meshes together */
    uint32_t max_shapes, max_lights, max_materials;
    uint64_t max_file_bytes; /* each referenced file */
    uint64_t max_memory;     /* the scene arena */
} ts_scene_limits;

/* Generous defaults for the CLI (a server sets its own). */
void ts_scene_limits_default(ts_scene_limits *l);

typedef enum ts_integrator_type {
    TS_INTEGRATOR_PATH,
    TS_INTEGRATOR_DIRECT,
    TS_INTEGRATOR_AO,      /* debugging view: ambient occlusion, needs no lights */
    TS_INTEGRATOR_NORMALS, /* debugging view: shading normals as colour */
} ts_integrator_type;

typedef enum ts_light_strategy { TS_LIGHTS_ALL, TS_LIGHTS_ONE } ts_light_strategy;
typedef enum ts_light_selection { TS_LIGHT_SELECT_UNIFORM, TS_LIGHT_SELECT_POWER } ts_light_selection;
/* How direct light is estimated at a vertex: both strategies combined by the power
 * heuristic, light sampling only, or BSDF sampling only (delta lights are always light
 * sampled: no BSDF sample can hit them). The last two exist to compare strategies. */
typedef enum ts_direct_sampling { TS_SAMPLING_MIS, TS_SAMPLING_LIGHT, TS_SAMPLING_BSDF } ts_direct_sampling;

typedef struct ts_integrator_desc {
    ts_integrator_type type;
    int max_depth, rr_depth;            /* path; direct: max_depth of specular recursion */
    ts_light_selection light_sampling;  /* path */
    ts_light_strategy strategy;         /* direct */
    ts_direct_sampling sampling;        /* path, direct */
    int samples_per_light;              /* direct, all */
    float ao_distance;                  /* ao: occluders farther than this are ignored (inf = any) */
} ts_integrator_desc;

/* The optional top-level "job" object: halt conditions and bookkeeping. */
typedef struct ts_job_desc {
    const char *name;     /* or NULL */
    uint32_t effects_off; /* effects switched off on purpose (job.effects), effects.h bits */
    int priority;         /* higher first; default 0 */
    uint32_t spp;         /* 0 = the sampler's spp */
    double time_limit_s;  /* 0 = none */
    double target_error;  /* 0 = none */
} ts_job_desc;

typedef struct ts_scene {
    ts_arena arena;
    const char *name;      /* scene name: the document's "name", else the file name */
    const char *base_dir;  /* folder that relative file paths resolve against, or NULL */
    char digest[65];       /* SHA-256 (hex) of the canonical document, set at load (scene_digest.h) */

    ts_camera camera;
    int width, height;                         /* full film */
    int crop_x0, crop_y0, crop_x1, crop_y1;    /* pixel window [x0,x1) × [y0,y1) */
    ts_filter filter;
    ts_sampler sampler;
    uint32_t spp;
    ts_integrator_desc integrator;
    ts_job_desc job;

    ts_material *materials;
    const char **material_names;
    uint32_t n_materials;
    ts_shape *shapes;
    uint32_t n_shapes;
    ts_light *lights;
    uint32_t n_lights;
    uint64_t n_triangles;

    ts_accel *accel;
    ts_bounds3 bounds;
    /* What the scene calls for (effects.h), less what the job switched off; the
     * integrators simulate only these. */
    uint32_t effects;
    /* Light selection for next-event estimation: integrator.light_sampling for `path`,
     * power for `direct`. */
    ts_light_distribution light_distribution;
    uint32_t *infinite_lights; /* indices of the infinite lights, added to escaping rays */
    uint32_t n_infinite_lights;

    /* Owned resources released by ts_scene_destroy. */
    struct ts_fourier_table **fourier_tables;
    uint32_t n_fourier_tables;
    struct ts_envmap **envmaps;
    uint32_t n_envmaps;
} ts_scene;

/* Loads a scene file (JSON). Relative paths inside it resolve against its folder and may
 * not leave it. On failure: NULL *out, err holds the sentence (JSON path first for
 * content errors), nothing leaks. */
ts_status ts_scene_load_file(const char *path, const ts_scene_limits *limits, ts_scene **out, ts_error *err);

/* Loads a scene from text. base_dir: folder for relative file paths, or NULL to refuse
 * every file reference. name: used when the document has no "name". */
ts_status ts_scene_load_text(const char *text, size_t len, const char *base_dir, const char *name,
                             const ts_scene_limits *limits, ts_scene **out, ts_error *err);

/* The built-in default scene (the classic Cornell box, scenes/cornell-box.json). */
ts_status ts_scene_load_builtin(const ts_scene_limits *limits, ts_scene **out, ts_error *err);
const char *ts_scene_builtin_text(size_t *len);

void ts_scene_destroy(ts_scene *s);

#endif
