/* scene.h — the immutable scene every render thread reads, and its teardown.
 *
 * Design note: a scene is made by the scene builder (scene_builder.h), which a front end
 * drives — the JSON loader of scene format v1 (scene_json.h, docs/design.md §4) or another
 * format's importer — and which checks everything before building anything expensive. All
 * of a scene's memory comes from its arena (plus the accelerator, Fourier tables and
 * environment maps, which the scene owns), so ts_scene_destroy is the whole teardown. Once
 * built, the scene is immutable and may be shared by any number of threads. */
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
#include "media/medium.h"
#include "sampling/sampler.h"

typedef enum ts_integrator_type {
    TS_INTEGRATOR_PATH,
    TS_INTEGRATOR_DIRECT,
    TS_INTEGRATOR_AO,      /* debugging view: ambient occlusion, needs no lights */
    TS_INTEGRATOR_NORMALS, /* debugging view: shading normals as colour */
    TS_INTEGRATOR_VOLPATH, /* pbrt-v3's VolPathIntegrator: path with participating media */
} ts_integrator_type;

typedef enum ts_light_strategy { TS_LIGHTS_ALL, TS_LIGHTS_ONE } ts_light_strategy;
typedef enum ts_light_selection {
    TS_LIGHT_SELECT_UNIFORM,
    TS_LIGHT_SELECT_POWER,
    TS_LIGHT_SELECT_SPATIAL, /* pbrt-v3's per-voxel distributions (lights/light.h) */
    TS_LIGHT_SELECT_BVH,     /* pbrt-v4's light hierarchy (lights/light_bvh.h) */
    TS_LIGHT_SELECT_AUTO,    /* path, unnamed in JSON: the builder picks bvh for two or more
                                lights, power for one (docs/design.md §4); the built scene holds
                                the one it picked */
} ts_light_selection;
/* How direct light is estimated at a vertex: both strategies combined by the power
 * heuristic, light sampling only, or BSDF sampling only (delta lights are always light
 * sampled: no BSDF sample can hit them). The last two exist to compare strategies. */
typedef enum ts_direct_sampling { TS_SAMPLING_MIS, TS_SAMPLING_LIGHT, TS_SAMPLING_BSDF } ts_direct_sampling;

typedef struct ts_integrator_desc {
    ts_integrator_type type;
    int max_depth, rr_depth;            /* path, volpath; direct: max_depth of specular recursion */
    ts_light_selection light_sampling;  /* path, volpath; direct's strategy one (uniform, power or bvh) */
    ts_light_strategy strategy;         /* direct */
    ts_direct_sampling sampling;        /* path, direct */
    int samples_per_light;              /* direct, all */
    float ao_distance;                  /* ao: occluders farther than this are ignored (inf = any) */
} ts_integrator_desc;

/* The ranges of the integrator's and the lights' counts, stated once for every front end
 * and the builder (build/scene_builder.c checks them; json/ and pbrt3/ name them in their
 * errors). The path loop is iterative, so depth costs no stack; `direct` recurses on
 * specular chains and keeps a lower cap. */
#define TS_PATH_DEPTH_MAX 65535    /* path and volpath: max_depth and rr_depth, in [0, this] */
#define TS_DIRECT_DEPTH_MAX 1000   /* direct: max_depth, in [0, this] */
#define TS_LIGHT_SAMPLES_MAX 4096  /* samples per light (integrator, shape, infinite light), in [1, this] */

/* The optional top-level "job" object: halt conditions and bookkeeping. */
typedef struct ts_job_desc {
    const char *name;     /* or NULL */
    uint32_t effects_off; /* effects switched off on purpose (job.effects), effects.h bits */
    int priority;         /* higher first; default 0 */
    uint32_t spp;         /* 0 = the sampler's spp */
    double time_limit_s;  /* 0 = none */
    double target_error;  /* 0 = none */
    /* Adaptive sampling (render/adaptive.h): after the first passes, samples go to the
     * pixels whose error estimate is still above their share of the target. */
    bool adaptive;
    /* "HOST:PORT" of a tev display server to stream the render to (job.display_server), or
     * NULL: a string of 1–255 characters here; its syntax, and whether a server honours it,
     * are for the program rendering the scene (server/display.h, docs/security.md). */
    const char *display_server;
} ts_job_desc;

typedef struct ts_scene {
    ts_arena arena;
    const char *name;      /* scene name: the document's "name", else the file name */
    const char *base_dir;  /* folder that relative file paths resolve against, or NULL */
    char digest[65];       /* the front end's identity of its document, 64 hex digits (JSON: SHA-256 of
                              the canonical document, scene_digest.h) */

    ts_camera camera;
    int width, height;                         /* full film */
    int crop_x0, crop_y0, crop_x1, crop_y1;    /* pixel window [x0,x1) × [y0,y1) */
    ts_filter filter;
    /* pbrt-v3's ImageFilm: every pixel value is multiplied by film_scale at output (the
     * film's scale, film.h; never in the sums), and a sample's RGB is scaled to luminance
     * max_sample_luminance at most before the film weighs it in (INFINITY: never). */
    float film_scale, max_sample_luminance;
    ts_sampler sampler;
    uint32_t spp;
    ts_integrator_desc integrator;
    ts_job_desc job;

    ts_material *materials;
    const char **material_names; /* NULL for a material added without a name */
    uint32_t n_materials;
    ts_shape *shapes;
    uint32_t n_shapes;
    ts_light *lights;
    uint32_t n_lights;
    uint64_t n_triangles;

    /* Object instancing (geometry/accel.h): objects are ranges of shapes (in_object set). */
    ts_object *objects;
    uint32_t n_objects;
    ts_instance *instances;
    uint32_t n_instances;

    ts_accel *accel;
    ts_bounds3 bounds;
    /* What the scene calls for (effects.h), less what the job switched off; the
     * integrators simulate only these. */
    uint32_t effects;
    /* Some material has a texture (or bump map): camera rays carry ray differentials
     * (integrators/differential.h); else none are made. */
    bool textured;
    /* The most texture evaluations one ray's hit may cost: the costliest material's
     * (ts_material.cost) plus the costliest alpha cut-out's. ts_scene_ray_weight turns it
     * into the work a ray stands for (the server's --max-work). */
    uint32_t shading_cost;
    /* Light selection for next-event estimation: integrator.light_sampling for `path` and
     * `direct` (used by its strategy one), power for the others. */
    ts_light_distribution light_distribution;
    uint32_t *infinite_lights; /* indices of the infinite lights, added to escaping rays */
    uint32_t n_infinite_lights;

    /* Participating media (media/medium.h; docs/design.md §4): shapes name theirs by index
     * (ts_shape's medium interface), camera rays start in camera_medium (TS_NONE: vacuum). */
    ts_medium *media;
    uint32_t n_media;
    uint32_t camera_medium;

    /* Owned resources released by ts_scene_destroy. */
    struct ts_fourier_table **fourier_tables;
    uint32_t n_fourier_tables;
    struct ts_envmap **envmaps;
    uint32_t n_envmaps;
    /* The image maps of the scene's textures (textures live in the arena); NULL: none. */
    struct ts_texture_cache *texture_cache;
} ts_scene;

/* Frees the scene and everything it owns (its arena, accelerator, Fourier tables,
 * environment maps and texture images). NULL is fine. Not while any thread still reads the scene. */
void ts_scene_destroy(ts_scene *s);

/* Texture evaluations a ray's work is worth: a ray with a hit is counted as
 * 1 + shading_cost / TS_LOOKUPS_PER_RAY rays, so a scene whose textures cost many lookups
 * a hit asks more of --max-work (docs/design.md §5b). */
#define TS_LOOKUPS_PER_RAY 16
double ts_scene_ray_weight(const ts_scene *s);

#endif
