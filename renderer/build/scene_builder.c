/* scene_builder.c — checking a scene's description and building the immutable scene; see
 * scene_builder.h.
 *
 * The scene under construction exists from create on (its arena takes names and mesh
 * arrays as they come); materials, shapes and lights wait in growable lists, so that finish
 * can lay them out in the arena at their final counts, with the area lights after the
 * lights added (in shape order). finish then does the expensive steps — accelerator, light
 * preparation and distribution — once, after everything has been accepted. */
#include "build/scene_builder.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "image/exr.h"
#include "image/image.h"
#include "integrators/effects.h"
#include "lights/envmap.h"
#include "core/name_map.h"
#include "materials/bsdf.h"
#include "materials/fourier_bsdf.h"
#include "materials/material_desc.h"
#include "mesh/mesh_file.h"
#include "mesh/mesh_subdiv.h"
#include "core/scene_path.h"

struct ts_scene_builder {
    ts_scene *s; /* the scene being built (arena, settings, name, digest); finish hands it over */
    ts_scene_limits lim;
    bool finished;
    bool has_film, has_camera, has_sampler, has_integrator, has_digest;
    ts_camera_desc camera; /* set up for the film's size at finish */

    /* Growable lists (malloc), copied into the arena by finish. */
    ts_material *materials;
    const char **material_names; /* arena strings; NULL for anonymous materials */
    ts_name_map material_index;  /* the named ones' ids: lookups in constant time */
    uint32_t n_materials;
    size_t cap_materials, cap_material_names;
    ts_shape *shapes;
    uint32_t n_shapes;
    size_t cap_shapes;
    ts_light *lights;
    uint32_t n_lights;
    size_t cap_lights;
    uint64_t n_triangles, n_area_lights;
    uint64_t n_curve_segments; /* counted with the triangles against limits.max_triangles */
    /* Object instancing: the objects' names (arena) and shape ranges, the instances; the
     * object being defined (TS_NONE outside ObjectBegin/End). */
    ts_object *objects;
    const char **object_names;
    ts_name_map object_index;
    uint32_t n_objects;
    size_t cap_objects, cap_object_names;
    ts_instance *instances;
    uint32_t n_instances;
    size_t cap_instances;
    uint32_t open_object;

    /* Owned until finish moves them into the scene. */
    struct ts_fourier_table **fourier_tables;
    uint32_t n_fourier_tables;
    size_t cap_fourier_tables;
    struct ts_envmap **envmaps;
    uint32_t n_envmaps;
    size_t cap_envmaps;

    /* Participating media (their densities in the arena), named or not. */
    ts_medium *media;
    const char **medium_names;
    uint32_t n_media;
    size_t cap_media, cap_medium_names;
    uint32_t camera_medium;
};

ts_integrator_desc ts_integrator_desc_default(void)
{
    return (ts_integrator_desc){.type = TS_INTEGRATOR_PATH,
                                .max_depth = 5,
                                .rr_depth = 3,
                                .light_sampling = TS_LIGHT_SELECT_POWER,
                                .strategy = TS_LIGHTS_ALL,
                                .sampling = TS_SAMPLING_MIS,
                                .samples_per_light = 1,
                                .ao_distance = INFINITY};
}

void ts_scene_limits_default(ts_scene_limits *l)
{
    l->max_width = 16384;
    l->max_height = 16384;
    l->max_pixels = 64ull << 20;
    l->max_spp = 1u << 24;
    l->max_triangles = 50ull << 20;
    l->max_shapes = 1u << 20;
    l->max_lights = 1u << 22;
    l->max_materials = 1u << 16;
    l->max_file_bytes = 4ull << 30;
    l->max_memory = 16ull << 30;
    l->cancel = NULL;
}

#define TRY(expr)                                                                                            \
    do {                                                                                                     \
        ts_status st_ = (expr);                                                                              \
        if (st_ != TS_OK) return st_;                                                                        \
    } while (0)

static ts_status nomem(ts_error *err, const char *what)
{
    return ts_error_set(err, TS_ERR_NOMEM, "out of memory (or past the scene memory limit) while building %s",
                        what);
}

/* Grows the malloc'd array *p (of *cap elements of size elem) to hold at least need. */
static bool grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return true;
    size_t nc = *cap ? *cap : 16;
    while (nc < need) {
        if (nc > SIZE_MAX / 2 / elem) return false;
        nc *= 2;
    }
    void *q = realloc(*p, nc * elem);
    if (!q) return false;
    *p = q;
    *cap = nc;
    return true;
}

static ts_status usable(const ts_scene_builder *b, ts_error *err)
{
    if (b->finished)
        return ts_error_set(err, TS_ERR_INVALID, "the scene builder has finished; it takes no more calls");
    return ts_cancel_check(b->lim.cancel, err);
}

/* Participating media (the section at the end of this file). */
static ts_status check_shape_media(const ts_scene_builder *b, const ts_shape_desc *d, ts_error *err);
static void set_shape_media(const ts_shape_desc *d, ts_shape *sh);
static ts_status lay_out_media(ts_scene_builder *b, ts_error *err);

static bool rgb_nonneg(ts_rgb c) { return c.r >= 0 && c.g >= 0 && c.b >= 0; } /* false for NaN */
static bool rgb_finite_nonneg(ts_rgb c)
{
    return rgb_nonneg(c) && isfinite(c.r) && isfinite(c.g) && isfinite(c.b);
}

/* ---------------------------------------------------------------- create, destroy */

ts_status ts_scene_builder_create(const ts_scene_limits *limits, const char *base_dir, ts_scene_builder **out,
                                  ts_error *err)
{
    *out = NULL;
    ts_scene_builder *b = calloc(1, sizeof *b);
    ts_scene *s = b ? calloc(1, sizeof *s) : NULL;
    if (!s) {
        free(b);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory while building the scene");
    }
    if (limits)
        b->lim = *limits;
    else
        ts_scene_limits_default(&b->lim);
    b->s = s;
    b->open_object = TS_NONE;
    b->camera_medium = TS_NONE;
    ts_arena_init(&s->arena, b->lim.max_memory);
    if (base_dir && !(s->base_dir = ts_arena_strdup(&s->arena, base_dir))) {
        ts_scene_builder_destroy(b);
        return nomem(err, "the scene");
    }
    *out = b;
    return TS_OK;
}

void ts_scene_builder_destroy(ts_scene_builder *b)
{
    if (!b) return;
    for (uint32_t i = 0; i < b->n_fourier_tables; i++)
        ts_fourier_table_destroy(b->fourier_tables[i]);
    for (uint32_t i = 0; i < b->n_envmaps; i++)
        ts_envmap_destroy(b->envmaps[i]);
    free(b->fourier_tables);
    free(b->envmaps);
    free(b->materials);
    free(b->material_names);
    ts_name_map_fini(&b->material_index);
    ts_name_map_fini(&b->object_index);
    free(b->shapes);
    free(b->lights);
    free(b->objects);
    free(b->object_names);
    free(b->instances);
    free(b->media);
    free(b->medium_names);
    ts_scene_destroy(b->s);
    free(b);
}

/* ---------------------------------------------------------------- settings */

ts_status ts_scene_builder_set_name(ts_scene_builder *b, const char *name, ts_error *err)
{
    TRY(usable(b, err));
    if (!name) return ts_error_set(err, TS_ERR_INVALID, "name: expected a string");
    const char *copy = ts_arena_strdup(&b->s->arena, name);
    if (!copy) return nomem(err, "the name");
    b->s->name = copy;
    return TS_OK;
}

ts_status ts_scene_builder_set_digest(ts_scene_builder *b, const char *hex, ts_error *err)
{
    TRY(usable(b, err));
    const size_t want = sizeof b->s->digest - 1;
    size_t n = 0;
    while (hex && n <= want && ((hex[n] >= '0' && hex[n] <= '9') || (hex[n] >= 'a' && hex[n] <= 'f')))
        n++;
    if (!hex || n != want || hex[n] != '\0')
        return ts_error_set(err, TS_ERR_INVALID, "digest: expected %zu lower-case hex digits", want);
    memcpy(b->s->digest, hex, want + 1);
    b->has_digest = true;
    return TS_OK;
}

ts_status ts_scene_builder_set_film(ts_scene_builder *b, const ts_film_desc *f, ts_error *err)
{
    TRY(usable(b, err));
    const ts_scene_limits *lim = &b->lim;
    if (f->width < 1 || f->width > lim->max_width || f->height < 1 || f->height > lim->max_height)
        return ts_error_set(err, TS_ERR_LIMIT, "film: %u × %u pixels, expected 1 to %u × 1 to %u", f->width,
                            f->height, lim->max_width, lim->max_height);
    if ((uint64_t)f->width * f->height > lim->max_pixels)
        return ts_error_set(err, TS_ERR_LIMIT, "film: %u × %u pixels is more than the limit of %llu",
                            f->width, f->height, (unsigned long long)lim->max_pixels);
    if (!(f->filter_radius <= 16))
        return ts_error_set(err, TS_ERR_INVALID, "film.filter.radius: expected at most 16 pixels, got %g",
                            f->filter_radius);
    const float *c = f->crop;
    if (!(c[0] >= 0 && c[0] < c[1] && c[1] <= 1 && c[2] >= 0 && c[2] < c[3] && c[3] <= 1))
        return ts_error_set(err, TS_ERR_INVALID,
                            "film.crop: expected [x0, x1, y0, y1] with 0 ≤ x0 < x1 ≤ 1 and 0 ≤ y0 < y1 ≤ 1");
    int width = (int)f->width, height = (int)f->height;
    /* pbrt's rule: the window's edges, scaled to pixels, rounded up. */
    int x0 = (int)ceilf(width * c[0]), x1 = (int)ceilf(width * c[1]);
    int y0 = (int)ceilf(height * c[2]), y1 = (int)ceilf(height * c[3]);
    if (x1 <= x0 || y1 <= y0)
        return ts_error_set(err, TS_ERR_INVALID, "film.crop: the window holds no pixel");
    if (!(f->scale >= 0 && f->scale <= FLT_MAX))
        return ts_error_set(err, TS_ERR_INVALID, "film.scale: expected a finite number > 0, got %g", f->scale);
    if (!(f->max_sample_luminance >= 0))
        return ts_error_set(err, TS_ERR_INVALID, "film.max_sample_luminance: expected a number > 0, got %g",
                            f->max_sample_luminance);
    ts_filter filter; /* its own checks: a radius > 0, a known type */
    TRY(ts_filter_init_params(&filter, f->filter, f->filter_radius, &f->filter_params, err));
    ts_scene *s = b->s;
    s->film_scale = f->scale > 0 ? f->scale : 1;
    s->max_sample_luminance = f->max_sample_luminance > 0 ? f->max_sample_luminance : INFINITY;
    s->width = width;
    s->height = height;
    s->crop_x0 = x0, s->crop_x1 = x1, s->crop_y0 = y0, s->crop_y1 = y1;
    s->filter = filter;
    b->has_film = true;
    return TS_OK;
}

ts_status ts_scene_builder_set_camera(ts_scene_builder *b, const ts_camera_desc *d, ts_error *err)
{
    TRY(usable(b, err));
    if (d->type != TS_CAMERA_PERSPECTIVE && d->type != TS_CAMERA_ORTHOGRAPHIC)
        return ts_error_set(err, TS_ERR_INVALID, "camera.type: unknown camera type %d", (int)d->type);
    /* Where the camera is, before its frame: beyond ±1e15 (the scene's extent, §4) the
     * view direction's length overflows a float and would read as "up is parallel". */
    static const char *const names[] = {"camera.from", "camera.to", "camera.up"};
    const ts_vec3 *pts[] = {&d->from, &d->to, &d->up};
    for (int k = 0; k < 3; k++)
        if (!(fabsf(pts[k]->x) <= 1e15f && fabsf(pts[k]->y) <= 1e15f && fabsf(pts[k]->z) <= 1e15f))
            return ts_error_set(err, TS_ERR_INVALID, "%s: %s ([%g, %g, %g])", names[k],
                                k < 2 ? "farther than 1e15 units from the origin" : "components beyond ±1e15",
                                pts[k]->x, pts[k]->y, pts[k]->z);
    /* ts_camera_init's checks do not depend on the film's size. */
    ts_camera probe;
    TRY(ts_camera_init(&probe, d, 1, 1, err));
    if (!(d->lens_radius >= 0 && isfinite(d->lens_radius)))
        return ts_error_set(err, TS_ERR_INVALID, "camera.lens_radius: expected a finite number ≥ 0, got %g",
                            d->lens_radius);
    if (!(d->focus_distance > 0 && isfinite(d->focus_distance)))
        return ts_error_set(err, TS_ERR_INVALID,
                            "camera.focus_distance: expected a finite number > 0, got %g", d->focus_distance);
    b->camera = *d;
    b->has_camera = true;
    return TS_OK;
}

ts_status ts_scene_builder_set_sampler(ts_scene_builder *b, const ts_sampler *sampler, uint32_t spp,
                                       ts_error *err)
{
    TRY(usable(b, err));
    if (sampler->type != TS_SAMPLER_SOBOL && sampler->type != TS_SAMPLER_INDEPENDENT)
        return ts_error_set(err, TS_ERR_INVALID, "sampler.type: unknown sampler type %d", (int)sampler->type);
    if (spp < 1 || spp > b->lim.max_spp)
        return ts_error_set(err, TS_ERR_INVALID, "sampler.spp: expected 1 to %u samples per pixel, got %u",
                            b->lim.max_spp, spp);
    b->s->sampler = *sampler;
    b->s->spp = spp;
    b->has_sampler = true;
    return TS_OK;
}

static ts_status int_in(int v, int lo, int hi, const char *what, ts_error *err)
{
    if (v < lo || v > hi)
        return ts_error_set(err, TS_ERR_INVALID, "integrator.%s: expected an integer in [%d, %d], got %d",
                            what, lo, hi, v);
    return TS_OK;
}

ts_status ts_scene_builder_set_integrator(ts_scene_builder *b, const ts_integrator_desc *in, ts_error *err)
{
    TRY(usable(b, err));
    bool sampling_ok = in->sampling == TS_SAMPLING_MIS || in->sampling == TS_SAMPLING_LIGHT ||
                       in->sampling == TS_SAMPLING_BSDF;
    switch (in->type) {
    case TS_INTEGRATOR_PATH:
    case TS_INTEGRATOR_VOLPATH:
        TRY(int_in(in->max_depth, 0, TS_PATH_DEPTH_MAX, "max_depth", err)); /* scene/scene.h */
        TRY(int_in(in->rr_depth, 0, TS_PATH_DEPTH_MAX, "rr_depth", err));
        if (in->light_sampling != TS_LIGHT_SELECT_UNIFORM && in->light_sampling != TS_LIGHT_SELECT_POWER &&
            in->light_sampling != TS_LIGHT_SELECT_SPATIAL && in->light_sampling != TS_LIGHT_SELECT_BVH &&
            in->light_sampling != TS_LIGHT_SELECT_AUTO)
            return ts_error_set(err, TS_ERR_INVALID, "integrator.light_sampling: unknown selection %d",
                                (int)in->light_sampling);
        if (!sampling_ok)
            return ts_error_set(err, TS_ERR_INVALID, "integrator.sampling: unknown strategy %d",
                                (int)in->sampling);
        break;
    case TS_INTEGRATOR_DIRECT:
        TRY(int_in(in->max_depth, 0, TS_DIRECT_DEPTH_MAX, "max_depth", err));
        TRY(int_in(in->samples_per_light, 1, TS_LIGHT_SAMPLES_MAX, "samples_per_light", err));
        if (in->strategy != TS_LIGHTS_ALL && in->strategy != TS_LIGHTS_ONE)
            return ts_error_set(err, TS_ERR_INVALID, "integrator.strategy: unknown strategy %d",
                                (int)in->strategy);
        /* Strategy one's selection: pbrt-v3's uniform, by power, or by the light hierarchy. */
        if (in->light_sampling != TS_LIGHT_SELECT_UNIFORM && in->light_sampling != TS_LIGHT_SELECT_POWER &&
            in->light_sampling != TS_LIGHT_SELECT_BVH)
            return ts_error_set(err, TS_ERR_INVALID,
                                "integrator.light_sampling: direct selects uniform, power or bvh, not %d",
                                (int)in->light_sampling);
        if (!sampling_ok)
            return ts_error_set(err, TS_ERR_INVALID, "integrator.sampling: unknown strategy %d",
                                (int)in->sampling);
        break;
    case TS_INTEGRATOR_AO:
        if (!(in->ao_distance > 0))
            return ts_error_set(err, TS_ERR_INVALID,
                                "integrator.max_distance: expected a positive number, got %g",
                                in->ao_distance);
        break;
    case TS_INTEGRATOR_NORMALS:
        break;
    default:
        return ts_error_set(err, TS_ERR_INVALID, "integrator.type: unknown integrator %d", (int)in->type);
    }
    b->s->integrator = *in;
    b->has_integrator = true;
    return TS_OK;
}

ts_status ts_scene_builder_set_job(ts_scene_builder *b, const ts_job_desc *job, ts_error *err)
{
    TRY(usable(b, err));
    /* Switching a light type or a lobe off consistently would need the light distribution
     * and materials rebuilt; these two are switched off exactly. */
    if (job->effects_off & ~(uint32_t)(TS_EFFECT_INDIRECT | TS_EFFECT_DEPTH_OF_FIELD))
        return ts_error_set(err, TS_ERR_INVALID,
                            "job.effects: only 'indirect' and 'depth_of_field' can be switched off");
    if (job->priority < -1000000 || job->priority > 1000000)
        return ts_error_set(err, TS_ERR_INVALID,
                            "job.priority: expected an integer in [-1000000, 1000000], got %d",
                            job->priority);
    if (job->spp > b->lim.max_spp)
        return ts_error_set(err, TS_ERR_INVALID, "job.spp: expected at most %u samples per pixel, got %u",
                            b->lim.max_spp, job->spp);
    if (!(job->time_limit_s >= 0 && isfinite(job->time_limit_s)))
        return ts_error_set(err, TS_ERR_INVALID, "job.time_limit_s: expected a finite number ≥ 0, got %g",
                            job->time_limit_s);
    if (!(job->target_error >= 0 && isfinite(job->target_error)))
        return ts_error_set(err, TS_ERR_INVALID, "job.target_error: expected a finite number ≥ 0, got %g",
                            job->target_error);
    if (job->display_server && (!job->display_server[0] || strlen(job->display_server) > 255))
        return ts_error_set(err, TS_ERR_INVALID, "job.display_server: expected HOST:PORT of 1 to 255 characters");
    ts_job_desc j = *job;
    if (job->name && !(j.name = ts_arena_strdup(&b->s->arena, job->name))) return nomem(err, "job.name");
    if (job->display_server && !(j.display_server = ts_arena_strdup(&b->s->arena, job->display_server)))
        return nomem(err, "job.display_server");
    b->s->job = j;
    return TS_OK;
}

/* ---------------------------------------------------------------- files */

ts_status ts_scene_builder_load_fourier(ts_scene_builder *b, const char *rel_path,
                                        const struct ts_fourier_table **out, ts_error *err)
{
    TRY(usable(b, err));
    if (!grow((void **)&b->fourier_tables, &b->cap_fourier_tables, (size_t)b->n_fourier_tables + 1,
              sizeof *b->fourier_tables))
        return nomem(err, "the Fourier tables");
    char *bytes = NULL;
    size_t n_bytes = 0;
    struct ts_fourier_table *t = NULL;
    ts_status st = ts_scene_path_read(b->s->base_dir, rel_path, "Fourier BSDF file", b->lim.max_file_bytes,
                                      &bytes, &n_bytes, err);
    if (!st) st = ts_fourier_table_load_memory((const unsigned char *)bytes, n_bytes, rel_path, &t, err);
    free(bytes);
    if (st) return st;
    b->fourier_tables[b->n_fourier_tables++] = t;
    *out = t;
    return TS_OK;
}

ts_status ts_scene_builder_load_envmap(ts_scene_builder *b, const char *rel_path,
                                       const struct ts_envmap **out, ts_error *err)
{
    TRY(usable(b, err));
    if (!grow((void **)&b->envmaps, &b->cap_envmaps, (size_t)b->n_envmaps + 1, sizeof *b->envmaps))
        return nomem(err, "the environment maps");
    char *bytes = NULL;
    size_t n_bytes = 0;
    struct ts_envmap *em = NULL;
    ts_status st = ts_scene_path_read(b->s->base_dir, rel_path, "environment map", b->lim.max_file_bytes,
                                      &bytes, &n_bytes, err);
    /* The header's size against the scene's memory before any pixel is decoded: the decoded
     * floats, then 16 bytes a texel (radiance and weight) and 8 of the distributions. */
    int64_t w = 0, h = 0;
    int ch = 0;
    if (!st && ts_exr_size_memory((const unsigned char *)bytes, n_bytes, &w, &h, &ch) && b->lim.max_memory &&
        (double)w * (double)h * (4.0 * ch + 24) > (double)b->lim.max_memory)
        st = ts_error_set(err, TS_ERR_LIMIT,
                          "environment map '%s': its %lld × %lld pixels of %d channels need about %.0f bytes, more "
                          "than the scene's memory limit of %llu",
                          rel_path, (long long)w, (long long)h, ch, (double)w * (double)h * (4.0 * ch + 24),
                          (unsigned long long)b->lim.max_memory);
    if (!st) {
        ts_image img = {0};
        st = ts_exr_read_memory((const unsigned char *)bytes, n_bytes, &img, err);
        if (st)
            ts_error_prefix(err, "environment map '%s'", rel_path);
        else
            st = ts_envmap_from_image(&img, rel_path, &em, err);
        ts_image_fini(&img);
    }
    free(bytes);
    if (st) return st;
    b->envmaps[b->n_envmaps++] = em;
    *out = em;
    return TS_OK;
}

ts_status ts_scene_builder_load_mesh(ts_scene_builder *b, const char *rel_path, ts_mesh_data *out,
                                     ts_error *err)
{
    *out = (ts_mesh_data){0};
    TRY(usable(b, err));
    const ts_scene_limits *lim = &b->lim;
    if (b->n_triangles >= lim->max_triangles)
        return ts_error_set(err, TS_ERR_LIMIT, "the scene's triangles exceed the limit of %llu",
                            (unsigned long long)lim->max_triangles);
    if (!b->s->base_dir)
        return ts_error_set(
            err, TS_ERR_INVALID,
            "mesh file '%s': this scene may not refer to files (no asset folder is configured)", rel_path);
    /* What is left of the scene's triangle budget (never 0, which would mean unlimited). */
    ts_mesh_limits ml = {lim->max_triangles * 3, lim->max_triangles - b->n_triangles, lim->max_file_bytes, lim->cancel};
    return ts_mesh_file_load(b->s->base_dir, rel_path, &ml, out, err);
}

/* ---------------------------------------------------------------- textures */

ts_arena *ts_scene_builder_texture_arena(ts_scene_builder *b) { return &b->s->arena; }

ts_status ts_scene_builder_texture_cache(ts_scene_builder *b, ts_texture_cache **out, ts_error *err)
{
    *out = NULL;
    TRY(usable(b, err));
    if (!b->s->texture_cache && !(b->s->texture_cache = ts_texture_cache_create((size_t)b->lim.max_memory)))
        return nomem(err, "the texture cache");
    *out = b->s->texture_cache;
    return TS_OK;
}

const char *ts_scene_builder_base_dir(const ts_scene_builder *b) { return b->s->base_dir; }

const ts_scene_limits *ts_scene_builder_limits(const ts_scene_builder *b) { return &b->lim; }

ts_status ts_scene_builder_add_texture(ts_scene_builder *b, const ts_texture *proto, const ts_texture **out,
                                       ts_error *err)
{
    *out = NULL;
    TRY(usable(b, err));
    return ts_texture_make(&b->s->arena, proto, out, err);
}

ts_status ts_scene_builder_load_texture_image(ts_scene_builder *b, const char *rel_path,
                                              const ts_texture_image_options *opt, const ts_mipmap **out,
                                              ts_error *err)
{
    *out = NULL;
    ts_texture_cache *cache;
    TRY(ts_scene_builder_texture_cache(b, &cache, err));
    return ts_texture_cache_get(cache, b->s->base_dir, rel_path, b->lim.max_file_bytes, opt, out, err);
}

/* ---------------------------------------------------------------- materials */

static ts_status bad_rgb(ts_error *err, const char *what, const char *expected, ts_rgb c)
{
    return ts_error_set(err, TS_ERR_INVALID, "%s: expected %s, got (%g, %g, %g)", what, expected, c.r, c.g,
                        c.b);
}

/* A float parameter: a float texture, or a constant (its range checked by the caller). */
static ts_status check_float_texture(const ts_material_float *p, const char *what, ts_error *err)
{
    if (p->tex && p->tex->is_rgb)
        return ts_error_set(err, TS_ERR_INVALID, "%s: expected a float texture, got an RGB one", what);
    return TS_OK;
}

/* m's lobes and texture cost (material.h), a mix's from the two materials it names. */
static void material_counts(const ts_scene_builder *b, const ts_material *m, uint64_t *lobes, uint64_t *cost)
{
    *cost = ts_material_texture_cost(m);
    if (m->type != TS_MATERIAL_MIX) {
        *lobes = (uint64_t)ts_material_max_lobes(m);
        return;
    }
    const ts_material *a = &b->materials[m->mix_id[0]], *c = &b->materials[m->mix_id[1]];
    *lobes = (uint64_t)a->lobes + c->lobes;
    *cost += (uint64_t)a->cost + c->cost;
}

/* A parameter of m's type against its row (materials/material_desc.h): a texture of the
 * right kind, or a constant in the row's range. */
static ts_status check_material_param(const ts_material *m, const ts_material_param *p, ts_error *err)
{
    switch (p->kind) {
    case TS_MPARAM_RGB: {
        const ts_material_rgb *v = ts_mparam_crgb(m, p);
        if (v->tex) return TS_OK;
        if (!ts_mrange_ok(p->range, v->value.r) || !ts_mrange_ok(p->range, v->value.g) ||
            !ts_mrange_ok(p->range, v->value.b))
            return bad_rgb(err, p->key, ts_mrange_words(p->range, true), v->value);
        return TS_OK;
    }
    case TS_MPARAM_FLOAT: {
        const ts_material_float *v = ts_mparam_cfloat(m, p);
        TRY(check_float_texture(v, p->key, err));
        if (!v->tex && !ts_mrange_ok(p->range, v->value))
            return ts_error_set(err, TS_ERR_INVALID, "%s: expected %s, got %g", p->key,
                                ts_mrange_words(p->range, false), v->value);
        return TS_OK;
    }
    case TS_MPARAM_ENUM: {
        int v = *(const int *)(const void *)((const char *)m + p->offset), count = 0;
        while (p->names[count])
            count++;
        if (v < 0 || v >= count)
            return ts_error_set(err, TS_ERR_INVALID, "%s: unknown value %d (%d are known)", p->key, v, count);
        return TS_OK;
    }
    }
    return TS_OK;
}

static ts_status check_roughness(const ts_material_float *r, const char *what, ts_error *err)
{
    TRY(check_float_texture(r, what, err));
    if (!r->tex && !ts_mrange_ok(TS_MRANGE_NONNEG, r->value))
        return ts_error_set(err, TS_ERR_INVALID, "%s: expected a finite number ≥ 0, got %g", what, r->value);
    return TS_OK;
}

/* Every range and kind from m's type's description; what no row says (a mix's materials,
 * a Fourier table, the lobe and texture counts) after. */
static ts_status check_material(const ts_scene_builder *b, const ts_material *m, ts_error *err)
{
    const ts_material_desc *d = ts_material_desc_of(m->type);
    if (!d) return ts_error_set(err, TS_ERR_INVALID, "type: unknown material type %d", (int)m->type);
    if (m->bump && m->bump->is_rgb)
        return ts_error_set(err, TS_ERR_INVALID, "bumpmap: expected a float texture, got an RGB one");
    for (int i = 0; i < d->n_params; i++)
        TRY(check_material_param(m, &d->params[i], err));
    if (d->flags & TS_MDESC_MIX)
        for (int k = 0; k < 2; k++)
            if (m->mix_id[k] >= b->n_materials)
                return ts_error_set(err, TS_ERR_INVALID, "materials[%d]: no material of id %u (%u were added)", k,
                                    m->mix_id[k], b->n_materials);
    if (d->flags & TS_MDESC_FILE) {
        uint32_t i = 0;
        while (i < b->n_fourier_tables && b->fourier_tables[i] != m->fourier)
            i++;
        if (!m->fourier || i == b->n_fourier_tables)
            return ts_error_set(err, TS_ERR_INVALID, "file: the Fourier table was not loaded by this scene builder");
    }
    if (d->flags & TS_MDESC_ROUGH) TRY(check_roughness(&m->roughness, "roughness", err));
    if (m->has_vroughness && !(d->flags & TS_MDESC_ANISO))
        return ts_error_set(err, TS_ERR_INVALID,
                            "vroughness: only conductor, dielectric, substrate and uber materials are anisotropic");
    if (m->has_vroughness) TRY(check_roughness(&m->vroughness, "vroughness", err));
    /* The flattened BSDF's lobes and one shading's texture evaluations, from the counts of
     * the materials a mix names (set when they were added): linear in the scene, however
     * often a material is mixed in. pbrt-v3's BSDF holds 8 lobes and aborts beyond; refuse
     * such a mix up front. */
    uint64_t lobes = 0, cost = 0;
    material_counts(b, m, &lobes, &cost);
    if (lobes > TS_BSDF_MAX_BXDFS)
        return ts_error_set(err, TS_ERR_INVALID,
                            "materials: the two materials mixed have up to %llu lobes together, more than a BSDF's %d",
                            (unsigned long long)lobes, TS_BSDF_MAX_BXDFS);
    if (cost > TS_MATERIAL_MAX_COST)
        return ts_error_set(err, TS_ERR_INVALID,
                            "one shading of this material evaluates up to %llu textures (its parameters', its bump "
                            "map's three%s), more than the limit of %d",
                            (unsigned long long)cost, m->type == TS_MATERIAL_MIX ? " and the two materials mixed" : "",
                            TS_MATERIAL_MAX_COST);
    return TS_OK;
}

uint32_t ts_scene_builder_find_material(const ts_scene_builder *b, const char *name)
{
    uint32_t k = name ? ts_name_map_get(&b->material_index, name) : TS_NAME_MAP_NONE;
    return k == TS_NAME_MAP_NONE ? TS_NONE : k;
}

ts_status ts_scene_builder_add_material(ts_scene_builder *b, const char *name, const ts_material *m,
                                        uint32_t *id, ts_error *err)
{
    TRY(usable(b, err));
    if (b->n_materials >= b->lim.max_materials)
        return ts_error_set(err, TS_ERR_LIMIT, "more than the limit of %u materials", b->lim.max_materials);
    if (name && ts_scene_builder_find_material(b, name) != TS_NONE)
        return ts_error_set(err, TS_ERR_INVALID, "a material named \"%s\" was added before", name);
    TRY(check_material(b, m, err));
    size_t need = (size_t)b->n_materials + 1;
    if (!grow((void **)&b->materials, &b->cap_materials, need, sizeof *b->materials) ||
        !grow((void **)&b->material_names, &b->cap_material_names, need, sizeof *b->material_names))
        return nomem(err, "the materials");
    const char *copy = NULL;
    if (name && (!(copy = ts_arena_strdup(&b->s->arena, name)) || !ts_name_map_put(&b->material_index, copy, b->n_materials)))
        return nomem(err, "the material names");
    b->materials[b->n_materials] = *m;
    ts_material *added = &b->materials[b->n_materials];
    added->textured = ts_material_uses_textures(m);
    if (m->type == TS_MATERIAL_MIX) { /* textured if either material mixed is; mix[] is set by finish */
        added->textured = added->textured || b->materials[m->mix_id[0]].textured || b->materials[m->mix_id[1]].textured;
        added->mix[0] = added->mix[1] = NULL;
    }
    uint64_t lobes, cost;
    material_counts(b, m, &lobes, &cost); /* within bounds: check_material */
    added->lobes = (uint8_t)lobes;
    added->cost = (uint32_t)cost;
    b->material_names[b->n_materials] = copy;
    if (id) *id = b->n_materials;
    b->n_materials++;
    return TS_OK;
}

/* ---------------------------------------------------------------- shapes */

static ts_status check_mesh(const ts_scene_builder *b, const ts_mesh *m, ts_error *err)
{
    if (m->n_vertices == 0 || m->n_triangles == 0 || !m->p || !m->index)
        return ts_error_set(err, TS_ERR_INVALID, "a mesh needs vertices and triangles (got %u and %u)",
                            m->n_vertices, m->n_triangles);
    if (b->n_triangles + m->n_triangles > b->lim.max_triangles)
        return ts_error_set(err, TS_ERR_LIMIT, "the scene's triangles exceed the limit of %llu",
                            (unsigned long long)b->lim.max_triangles);
    for (uint64_t k = 0; k < 3ull * m->n_vertices; k++)
        if (!isfinite(m->p[k]))
            return ts_error_set(err, TS_ERR_INVALID, "positions[%llu]: expected a finite number",
                                (unsigned long long)k);
    for (uint64_t k = 0; k < 3ull * m->n_triangles; k++)
        if (m->index[k] >= m->n_vertices)
            return ts_error_set(err, TS_ERR_INVALID, "indices[%llu]: %u is not a vertex index (%u vertices)",
                                (unsigned long long)k, m->index[k], m->n_vertices);
    for (uint32_t k = 0; m->n && k < m->n_vertices; k++) {
        const float *n = m->n + 3 * (size_t)k;
        if (!(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2])) || (n[0] == 0 && n[1] == 0 && n[2] == 0))
            return ts_error_set(err, TS_ERR_INVALID, "normals[%u]: expected a finite, non-zero normal", k);
    }
    for (uint64_t k = 0; m->uv && k < 2ull * m->n_vertices; k++)
        if (!isfinite(m->uv[k]))
            return ts_error_set(err, TS_ERR_INVALID, "uvs[%llu]: expected a finite number",
                                (unsigned long long)k);
    return TS_OK;
}

/* A curve's description (scene_builder.h): pbrt-v3's checks of CreateCurveShape, the
 * values finite, and no emission (pbrt-v3's Curve::Sample is not implemented: a render
 * with a curve area light stops at its first light sample). */
static ts_status check_curve(const ts_scene_builder *b, const ts_shape_desc *d, ts_error *err)
{
    static const char *const bases[] = {"bezier", "bspline"};
    if (!ts_rgb_is_black(d->emission))
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "emission: a curve cannot be an area light (pbrt-v3 cannot sample curves: its "
                            "Curve::Sample is not implemented and its render stops there)");
    if ((unsigned)d->curve.type > TS_CURVE_CYLINDER)
        return ts_error_set(err, TS_ERR_INVALID, "curve_type: unknown curve type %d", (int)d->curve.type);
    if ((unsigned)d->curve.basis > TS_CURVE_BSPLINE)
        return ts_error_set(err, TS_ERR_INVALID, "basis: unknown curve basis %d", (int)d->curve.basis);
    int deg = d->curve.degree;
    if (deg != 2 && deg != 3)
        return ts_error_set(err, TS_ERR_INVALID, "degree: %d is not 2 or 3 (pbrt-v3's curve degrees)", deg);
    uint32_t nseg;
    if (!ts_curve_segment_count(d->curve.basis, deg, d->curve.n_points, &nseg) || !d->curve.p) {
        if (d->curve.basis == TS_CURVE_BEZIER)
            return ts_error_set(err, TS_ERR_INVALID,
                                "points: %u control points do not make degree-%d Bézier segments (%d + n·%d are "
                                "needed, n ≥ 0)",
                                d->curve.n_points, deg, deg + 1, deg);
        return ts_error_set(err, TS_ERR_INVALID,
                            "points: %u control points are too few for a degree-%d B-spline (at least %d)",
                            d->curve.n_points, deg, deg + 1);
    }
    if (nseg == 0)
        return ts_error_set(err, TS_ERR_INVALID, "points: one control point makes no %s segment", bases[d->curve.basis]);
    if (b->n_triangles + b->n_curve_segments + nseg > b->lim.max_triangles)
        return ts_error_set(err, TS_ERR_LIMIT, "the scene's triangles and curve segments exceed the limit of %llu",
                            (unsigned long long)b->lim.max_triangles);
    for (uint64_t k = 0; k < 3ull * d->curve.n_points; k++)
        if (!isfinite(d->curve.p[k]))
            return ts_error_set(err, TS_ERR_INVALID, "points[%llu]: expected a finite number", (unsigned long long)k);
    const double w[2] = {d->curve.width0, d->curve.width1};
    for (int k = 0; k < 2; k++)
        if (!(w[k] > 0) || !(w[k] < 1e30))
            return ts_error_set(err, TS_ERR_INVALID, "width%d: expected a positive finite number, got %g", k, w[k]);
    if (d->curve.type == TS_CURVE_RIBBON) {
        if (!d->curve.n || d->curve.n_normals != nseg + 1)
            return ts_error_set(err, TS_ERR_INVALID,
                                "normals: a ribbon curve of %u segments needs %u normals (one at each segment end), "
                                "got %u",
                                nseg, nseg + 1, d->curve.n ? d->curve.n_normals : 0);
        for (uint32_t k = 0; k <= nseg; k++) {
            const float *n = d->curve.n + 3 * (size_t)k;
            if (!(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2])) || (n[0] == 0 && n[1] == 0 && n[2] == 0))
                return ts_error_set(err, TS_ERR_INVALID, "normals[%u]: expected a finite, non-zero normal", k);
        }
    } else if (d->curve.n && d->curve.n_normals) {
        return ts_error_set(err, TS_ERR_INVALID, "normals: only ribbon curves take normals");
    }
    return TS_OK;
}

/* The curve of d in world space (to_world), in the arena: pbrt-v3's Bézier segments
 * (curve.h) cut into the pieces ts_curve_split asks for, radii linear along each, normals
 * by the inverse transpose, normalised. */
static ts_status place_curve(ts_scene_builder *b, const ts_shape_desc *d, ts_curve *out, ts_error *err)
{
    ts_arena *arena = &b->s->arena;
    uint32_t nseg;
    ts_curve_segment_count(d->curve.basis, d->curve.degree, d->curve.n_points, &nseg);
    const ts_xform *xf = &d->to_world;
    const double(*m)[4] = xf->m.m;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    double scale = cbrt(fabs(det));
    float w0 = (float)d->curve.width0, w1 = (float)d->curve.width1;
    /* Each segment in world space with its end widths (pbrt-v3: Lerp(seg / nSegments,
     * width0, width1), in float), and its pieces. */
    double(*wcp)[4][3] = malloc(sizeof *wcp * (size_t)nseg);
    double(*wend)[2] = malloc(sizeof *wend * (size_t)nseg);
    uint32_t *split = malloc(sizeof *split * (size_t)nseg);
    ts_status st = TS_OK;
    if (!wcp || !wend || !split) {
        st = nomem(err, "a curve");
        goto done;
    }
    uint64_t n_pieces = 0;
    for (uint32_t sg = 0; sg < nseg; sg++) {
        float bz[4][3];
        ts_curve_bezier_segment(d->curve.basis, d->curve.degree, d->curve.p, sg, bz);
        float t0 = (float)sg / (float)nseg, t1 = (float)(sg + 1) / (float)nseg;
        wend[sg][0] = scale * ((1 - t0) * w0 + t0 * w1);
        wend[sg][1] = scale * ((1 - t1) * w0 + t1 * w1);
        for (int i = 0; i < 4; i++) {
            ts_dvec3 q = ts_xform_point(xf, (ts_dvec3){bz[i][0], bz[i][1], bz[i][2]});
            if (!(fabs(q.x) < 3e38 && fabs(q.y) < 3e38 && fabs(q.z) < 3e38)) {
                st = ts_error_set(err, TS_ERR_INVALID, "a transformed control point is not a finite float");
                goto done;
            }
            wcp[sg][i][0] = q.x, wcp[sg][i][1] = q.y, wcp[sg][i][2] = q.z;
        }
        if (!(wend[sg][0] > 0 && wend[sg][1] > 0 && wend[sg][0] < 3e38 && wend[sg][1] < 3e38)) {
            st = ts_error_set(err, TS_ERR_INVALID, "the transformed width is not a positive finite float");
            goto done;
        }
        split[sg] = ts_curve_split(wcp[sg], fmax(wend[sg][0], wend[sg][1]));
        n_pieces += split[sg];
    }
    if (n_pieces > UINT32_MAX || b->n_triangles + b->n_curve_segments + n_pieces > b->lim.max_triangles) {
        st = ts_error_set(err, TS_ERR_LIMIT,
                          "the curve's %llu pieces (its sharp bends cut for Embree) exceed the scene's limit of %llu "
                          "triangles and curve pieces",
                          (unsigned long long)n_pieces, (unsigned long long)b->lim.max_triangles);
        goto done;
    }
    float *cp = ts_arena_calloc(arena, 16 * (size_t)n_pieces, sizeof *cp);
    float *ur = ts_arena_calloc(arena, 2 * (size_t)n_pieces, sizeof *ur);
    uint32_t *segof = ts_arena_calloc(arena, (size_t)n_pieces, sizeof *segof);
    float *nw = d->curve.type == TS_CURVE_RIBBON ? ts_arena_calloc(arena, 3 * ((size_t)nseg + 1), sizeof *nw) : NULL;
    if (!cp || !ur || !segof || (d->curve.type == TS_CURVE_RIBBON && !nw)) {
        st = nomem(err, "a curve");
        goto done;
    }
    size_t k = 0;
    for (uint32_t sg = 0; sg < nseg; sg++)
        for (uint32_t j = 0; j < split[sg]; j++, k++) {
            double a = (double)j / split[sg], e = (double)(j + 1) / split[sg], pc[4][3];
            ts_curve_piece(wcp[sg], a, e, pc);
            for (int i = 0; i < 4; i++) {
                double u = a + (e - a) * (i / 3.0);
                float *o = cp + 16 * k + 4 * i;
                o[0] = (float)pc[i][0], o[1] = (float)pc[i][1], o[2] = (float)pc[i][2];
                o[3] = (float)(0.5 * (wend[sg][0] + (wend[sg][1] - wend[sg][0]) * u));
            }
            ur[2 * k] = (float)a, ur[2 * k + 1] = (float)e;
            segof[k] = sg;
        }
    for (uint32_t q = 0; nw && q <= nseg; q++) {
        const float *n = d->curve.n + 3 * (size_t)q;
        ts_dvec3 w = ts_xform_normal(xf, (ts_dvec3){n[0], n[1], n[2]});
        double len = ts_dvec3_length(w);
        if (!(len > 0) || !isfinite(len)) {
            st = ts_error_set(err, TS_ERR_INVALID, "normals[%u]: the transformed normal is not a finite non-zero vector", q);
            goto done;
        }
        nw[3 * q] = (float)(w.x / len), nw[3 * q + 1] = (float)(w.y / len), nw[3 * q + 2] = (float)(w.z / len);
    }
    *out = (ts_curve){d->curve.type, nseg, (uint32_t)n_pieces, cp, ur, segof, nw, det < 0, 0};
    out->tessellation = ts_curve_tessellation(out);
done:
    free(wcp);
    free(wend);
    free(split);
    return st;
}

/* The cut of a partial quadric (scene_builder.h, ts_shape_cut): finite values that leave
 * some area. */
static ts_status check_cut(const ts_shape_desc *d, ts_error *err)
{
    const ts_shape_cut *c = &d->cut;
    if (!c->partial) return TS_OK;
    if (isnan(c->phi_max))
        return ts_error_set(err, TS_ERR_INVALID, "phimax: expected an angle in degrees, got %g", c->phi_max);
    if (!(c->phi_max > 0))
        return ts_error_set(err, TS_ERR_INVALID, "phimax: %g degrees leaves the shape no area", c->phi_max);
    if (d->type == TS_SHAPE_DISK) return TS_OK;
    if (isnan(c->z_min) || isnan(c->z_max) || (d->type == TS_SHAPE_CYLINDER && !(isfinite(c->z_min) && isfinite(c->z_max))))
        return ts_error_set(err, TS_ERR_INVALID, "zmin, zmax: expected %s numbers, got %g and %g",
                            d->type == TS_SHAPE_CYLINDER ? "finite" : "", c->z_min, c->z_max);
    double lo = fmin(c->z_min, c->z_max), hi = fmax(c->z_min, c->z_max);
    if (d->type == TS_SHAPE_SPHERE) {
        double r = d->sphere.radius;
        lo = fmin(fmax(lo, -r), r), hi = fmin(fmax(hi, -r), r);
        if (!(lo < hi))
            return ts_error_set(err, TS_ERR_INVALID,
                                "zmin, zmax: %g and %g clamp to the same height on a sphere of radius %g, which "
                                "leaves it no area",
                                c->z_min, c->z_max, r);
    } else if (!(lo < hi)) {
        return ts_error_set(err, TS_ERR_INVALID, "zmin, zmax: both %g, which leaves the cylinder no area", lo);
    }
    return TS_OK;
}

/* The analytic part of shape sh from d (checked): sizes, the cut in pbrt-v3's terms with
 * its clamping, and to_world with a disk's height and a cylinder's z_min folded in (the
 * translation composed only when non-zero, so shapes without them keep their transform
 * bit for bit). A cut that keeps the whole shape is no cut. */
static void place_analytic(const ts_shape_desc *d, ts_shape *sh)
{
    const ts_shape_cut *c = &d->cut;
    double phi_max = c->partial ? fmin(c->phi_max, 360.0) * (TS_PI_D / 180.0) : 2 * TS_PI_D;
    bool phi_cut = c->partial && c->phi_max < 360;
    sh->to_world = d->to_world;
    double z_shift = 0;
    switch (d->type) {
    case TS_SHAPE_SPHERE: {
        double r = d->sphere.radius;
        sh->sphere.radius = r;
        double lo = fmin(c->z_min, c->z_max), hi = fmax(c->z_min, c->z_max);
        lo = fmin(fmax(lo, -r), r), hi = fmin(fmax(hi, -r), r);
        bool z_cut = c->partial && (lo > -r || hi < r);
        sh->partial = phi_cut || z_cut;
        if (sh->partial) {
            sh->sphere.z_min = lo;
            sh->sphere.z_max = hi;
            sh->sphere.theta_min = acos(fmin(fmax(lo / r, -1.0), 1.0));
            sh->sphere.theta_max = acos(fmin(fmax(hi / r, -1.0), 1.0));
        }
        break;
    }
    case TS_SHAPE_DISK:
        sh->disk.radius = d->disk.radius;
        sh->disk.inner_radius = d->disk.inner_radius;
        sh->partial = phi_cut;
        z_shift = d->disk.height;
        break;
    case TS_SHAPE_CYLINDER:
        sh->cylinder.radius = d->cylinder.radius;
        sh->cylinder.height = d->cylinder.height;
        if (c->partial) {
            double lo = fmin(c->z_min, c->z_max), hi = fmax(c->z_min, c->z_max);
            sh->cylinder.height = hi - lo;
            z_shift = lo;
        }
        sh->partial = phi_cut;
        break;
    case TS_SHAPE_MESH:
    case TS_SHAPE_CURVE: break;
    }
    sh->phi_max = sh->partial ? phi_max : 0;
    if (z_shift != 0) {
        ts_xform up = ts_xform_translate((ts_dvec3){0, 0, z_shift});
        sh->to_world = ts_xform_compose(&d->to_world, &up);
    }
}

static ts_status check_shape(const ts_scene_builder *b, const ts_shape_desc *d, ts_error *err)
{
    if (b->n_shapes >= b->lim.max_shapes)
        return ts_error_set(err, TS_ERR_LIMIT, "more than the limit of %u shapes", b->lim.max_shapes);
    if (d->material >= b->n_materials && d->material != TS_NONE)
        return ts_error_set(err, TS_ERR_INVALID, "material: no material of id %u (%u were added)",
                            d->material, b->n_materials);
    TRY(check_shape_media(b, d, err));
    /* Infinite channels are ts_lights_prepare's to refuse, as every light's colour. */
    if (!rgb_nonneg(d->emission)) return bad_rgb(err, "emission", "RGB ≥ 0", d->emission);
    if (d->light_samples > TS_LIGHT_SAMPLES_MAX)
        return ts_error_set(err, TS_ERR_INVALID, "light_samples: %u is not in [1, %d]", d->light_samples,
                            TS_LIGHT_SAMPLES_MAX);
    const ts_texture *cut_tex[2] = {d->alpha, d->shadow_alpha};
    for (int k = 0; k < 2; k++) {
        const char *what = k ? "shadow_alpha" : "alpha";
        if (cut_tex[k] && d->type != TS_SHAPE_MESH)
            return ts_error_set(err, TS_ERR_INVALID,
                                "%s: only meshes take alpha textures (as pbrt-v3's trianglemesh and plymesh)", what);
        if (cut_tex[k] && cut_tex[k]->is_rgb)
            return ts_error_set(err, TS_ERR_INVALID, "%s: expected a float texture, got an RGB one", what);
    }
    /* Sizes and transforms too large for float are refused at finish, with the scene's
     * bounds ("shapes: the scene reaches beyond ±1e15 units …"). */
    switch (d->type) {
    case TS_SHAPE_SPHERE:
        if (!(d->sphere.radius > 0))
            return ts_error_set(err, TS_ERR_INVALID, "radius: expected a positive number, got %g",
                                d->sphere.radius);
        break;
    case TS_SHAPE_DISK:
        if (!(d->disk.radius > 0))
            return ts_error_set(err, TS_ERR_INVALID, "radius: expected a positive number, got %g",
                                d->disk.radius);
        if (!(d->disk.inner_radius >= 0 && d->disk.inner_radius < d->disk.radius))
            return ts_error_set(err, TS_ERR_INVALID, "inner_radius: expected a number in [0, radius), got %g",
                                d->disk.inner_radius);
        if (!isfinite(d->disk.height))
            return ts_error_set(err, TS_ERR_INVALID, "height: expected a finite number, got %g", d->disk.height);
        break;
    case TS_SHAPE_CYLINDER:
        if (!(d->cylinder.radius > 0))
            return ts_error_set(err, TS_ERR_INVALID, "radius: expected a positive number, got %g",
                                d->cylinder.radius);
        if (!d->cut.partial && !(d->cylinder.height > 0))
            return ts_error_set(err, TS_ERR_INVALID, "height: expected a positive number, got %g",
                                d->cylinder.height);
        break;
    case TS_SHAPE_MESH:
        if (d->cut.partial)
            return ts_error_set(err, TS_ERR_INVALID, "a mesh takes no zmin, zmax or phimax (partial quadrics only)");
        return check_mesh(b, &d->mesh, err);
    case TS_SHAPE_CURVE:
        if (d->cut.partial)
            return ts_error_set(err, TS_ERR_INVALID, "a curve takes no zmin, zmax or phimax (partial quadrics only)");
        return check_curve(b, d, err);
    default:
        return ts_error_set(err, TS_ERR_INVALID, "type: unknown shape type %d", (int)d->type);
    }
    return check_cut(d, err);
}

/* Copies the object-space mesh m into the arena, in world space (xf). */
static ts_status place_mesh(ts_scene_builder *b, const ts_mesh *m, const ts_xform *xf, bool reverse, ts_mesh *out,
                            ts_error *err)
{
    ts_arena *arena = &b->s->arena;
    uint32_t nv = m->n_vertices, nt = m->n_triangles;
    float *p = ts_arena_calloc(arena, (size_t)nv * 3, sizeof *p);
    float *n = m->n ? ts_arena_calloc(arena, (size_t)nv * 3, sizeof *n) : NULL;
    float *uv = m->uv ? ts_arena_calloc(arena, (size_t)nv * 2, sizeof *uv) : NULL;
    uint32_t *idx = ts_arena_calloc(arena, (size_t)nt * 3, sizeof *idx);
    if (!p || (m->n && !n) || (m->uv && !uv) || !idx) return nomem(err, "a mesh");
    memcpy(p, m->p, (size_t)nv * 3 * sizeof *p);
    if (n) memcpy(n, m->n, (size_t)nv * 3 * sizeof *n);
    if (uv) memcpy(uv, m->uv, (size_t)nv * 2 * sizeof *uv);
    memcpy(idx, m->index, (size_t)nt * 3 * sizeof *idx);
    /* To world space. A mirroring transform reverses the winding so that triangles keep
     * facing the way they did in object space (what pbrt-v3's XOR of ReverseOrientation
     * with TransformSwapsHandedness does); ReverseOrientation reverses it (once more). */
    if (!ts_xform_is_identity(xf)) {
        for (uint32_t k = 0; k < nv; k++) {
            ts_dvec3 q = ts_xform_point(xf, (ts_dvec3){p[3 * k], p[3 * k + 1], p[3 * k + 2]});
            if (!(fabs(q.x) < 3e38 && fabs(q.y) < 3e38 && fabs(q.z) < 3e38))
                return ts_error_set(err, TS_ERR_INVALID, "a transformed vertex is not a finite float");
            p[3 * k] = (float)q.x, p[3 * k + 1] = (float)q.y, p[3 * k + 2] = (float)q.z;
        }
        /* Vertex normals keep their lengths, which weight their interpolation as in pbrt-v3
         * (docs/design.md §4, shapes): transformed by the inverse transpose, a linear map,
         * then all scaled by one power of two when the longest would leave float's range. */
        double n_max = 0;
        for (uint32_t k = 0; n && k < nv; k++)
            n_max = fmax(n_max, ts_dvec3_length(ts_xform_normal(xf, (ts_dvec3){n[3 * k], n[3 * k + 1], n[3 * k + 2]})));
        int e = 0;
        if (n_max > 0x1p64 || n_max < 0x1p-64) frexp(n_max, &e);
        for (uint32_t k = 0; n && k < nv; k++) {
            ts_dvec3 w = ts_dvec3_scale(ts_xform_normal(xf, (ts_dvec3){n[3 * k], n[3 * k + 1], n[3 * k + 2]}),
                                        ldexp(1, -e));
            n[3 * k] = (float)w.x, n[3 * k + 1] = (float)w.y, n[3 * k + 2] = (float)w.z;
        }
        if (ts_xform_swaps_handedness(xf)) reverse = !reverse;
    }
    if (reverse)
        for (uint32_t t = 0; t < nt; t++) {
            uint32_t tmp = idx[3 * t + 1];
            idx[3 * t + 1] = idx[3 * t + 2];
            idx[3 * t + 2] = tmp;
        }
    *out = (ts_mesh){nv, nt, p, n, uv, idx};
    return TS_OK;
}

ts_status ts_scene_builder_add_shape(ts_scene_builder *b, const ts_shape_desc *d, uint32_t *id, ts_error *err)
{
    TRY(usable(b, err));
    TRY(check_shape(b, d, err));
    if (b->open_object != TS_NONE && !ts_rgb_is_black(d->emission))
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "a shape of an object cannot emit (pbrt-v3 drops area lights inside ObjectBegin/End); "
                            "add it without emission");
    if (!grow((void **)&b->shapes, &b->cap_shapes, (size_t)b->n_shapes + 1, sizeof *b->shapes))
        return nomem(err, "the shapes");
    ts_shape sh = {0};
    if (b->open_object != TS_NONE) {
        sh.in_object = true;
        sh.object = b->open_object;
        b->objects[b->open_object].n_shapes++;
    }
    sh.type = d->type;
    sh.material = d->material;
    set_shape_media(d, &sh);
    sh.emission = d->emission;
    sh.emissive = !ts_rgb_is_black(d->emission);
    sh.two_sided = d->two_sided;
    sh.light_samples = d->light_samples;
    sh.alpha = d->alpha;
    sh.shadow_alpha = d->shadow_alpha;
    if (d->type == TS_SHAPE_MESH) {
        TRY(place_mesh(b, &d->mesh, &d->to_world, d->reverse_orientation, &sh.mesh, err));
        sh.to_world = ts_xform_identity();
    } else if (d->type == TS_SHAPE_CURVE) {
        TRY(place_curve(b, d, &sh.curve, err));
        sh.to_world = ts_xform_identity();
        sh.reverse_orientation = d->reverse_orientation;
        b->n_curve_segments += sh.curve.n_pieces;
    } else {
        place_analytic(d, &sh);
        sh.reverse_orientation = d->reverse_orientation;
    }
    if (d->type == TS_SHAPE_MESH) b->n_triangles += d->mesh.n_triangles;
    if (sh.emissive) b->n_area_lights += d->type == TS_SHAPE_MESH ? d->mesh.n_triangles : 1;
    b->shapes[b->n_shapes] = sh;
    if (id) *id = b->n_shapes;
    b->n_shapes++;
    return TS_OK;
}

ts_status ts_scene_builder_loop_subdivide(ts_scene_builder *b, const ts_mesh *control, uint32_t levels,
                                          ts_mesh_data *out, ts_error *err)
{
    *out = (ts_mesh_data){0};
    TRY(usable(b, err));
    uint64_t left = b->lim.max_triangles > b->n_triangles ? b->lim.max_triangles - b->n_triangles : 0;
    ts_status st = ts_mesh_loop_subdivide(control->p, control->n_vertices, control->index, control->n_triangles,
                                          levels, left ? left : 1, b->lim.cancel, out, err);
    if (st == TS_ERR_LIMIT)
        return ts_error_set(err, TS_ERR_LIMIT, "%u levels of subdivision exceed the scene's limit of %llu triangles",
                            levels, (unsigned long long)b->lim.max_triangles);
    return st;
}

/* ---------------------------------------------------------------- objects */

ts_status ts_scene_builder_begin_object(ts_scene_builder *b, const char *name, uint32_t *id, ts_error *err)
{
    TRY(usable(b, err));
    if (b->open_object != TS_NONE)
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "object \"%s\" begins inside object \"%s\": objects do not nest (nor do they in pbrt-v3)",
                            name ? name : "", b->object_names[b->open_object]);
    if (!name || !name[0]) return ts_error_set(err, TS_ERR_INVALID, "an object needs a name");
    if (ts_scene_builder_find_object(b, name) != TS_NONE)
        return ts_error_set(err, TS_ERR_INVALID, "object \"%s\" is defined twice", name);
    if (!grow((void **)&b->objects, &b->cap_objects, (size_t)b->n_objects + 1, sizeof *b->objects) ||
        !grow((void **)&b->object_names, &b->cap_object_names, (size_t)b->n_objects + 1, sizeof *b->object_names))
        return nomem(err, "the objects");
    const char *copy = ts_arena_strdup(&b->s->arena, name);
    if (!copy || !ts_name_map_put(&b->object_index, copy, b->n_objects)) return nomem(err, "the objects");
    b->objects[b->n_objects] = (ts_object){b->n_shapes, 0};
    b->object_names[b->n_objects] = copy;
    if (id) *id = b->n_objects;
    b->open_object = b->n_objects++;
    return TS_OK;
}

ts_status ts_scene_builder_end_object(ts_scene_builder *b, ts_error *err)
{
    TRY(usable(b, err));
    if (b->open_object == TS_NONE) return ts_error_set(err, TS_ERR_INVALID, "no object is being defined");
    b->open_object = TS_NONE;
    return TS_OK;
}

uint32_t ts_scene_builder_find_object(const ts_scene_builder *b, const char *name)
{
    uint32_t i = name ? ts_name_map_get(&b->object_index, name) : TS_NAME_MAP_NONE;
    return i == TS_NAME_MAP_NONE ? TS_NONE : i;
}

static bool finite_invertible(const ts_xform *x)
{
    const double(*m)[4] = x->m.m;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    bool finite = isfinite(det);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) finite = finite && isfinite(m[i][j]) && isfinite(x->m_inv.m[i][j]);
    return finite && det != 0;
}

/* An instance of object under to_world, moving (motion, in the arena) or not (NULL). */
static ts_status push_instance(ts_scene_builder *b, uint32_t object, const ts_xform *to_world,
                               const ts_anim_xform *motion, ts_error *err)
{
    if (b->open_object != TS_NONE)
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "an instance inside object \"%s\": instances do not nest (nor do they in pbrt-v3)",
                            b->object_names[b->open_object]);
    if (object >= b->n_objects)
        return ts_error_set(err, TS_ERR_INVALID, "object: no object of id %u (%u were defined)", object, b->n_objects);
    if (!finite_invertible(to_world))
        return ts_error_set(err, TS_ERR_INVALID, "transform: expected a finite, invertible transform");
    if ((uint64_t)b->n_instances + b->n_shapes >= b->lim.max_shapes)
        return ts_error_set(err, TS_ERR_LIMIT, "more than the limit of %u shapes and instances", b->lim.max_shapes);
    if (!grow((void **)&b->instances, &b->cap_instances, (size_t)b->n_instances + 1, sizeof *b->instances))
        return nomem(err, "the instances");
    b->instances[b->n_instances++] = (ts_instance){object, *to_world, motion};
    return TS_OK;
}

ts_status ts_scene_builder_add_instance(ts_scene_builder *b, uint32_t object, const ts_xform *to_world, ts_error *err)
{
    TRY(usable(b, err));
    return push_instance(b, object, to_world, NULL, err);
}

/* The motion of start → end over [t0, t1] into the arena (*out NULL when the two are equal:
 * no motion). */
static ts_status make_motion(ts_scene_builder *b, const ts_xform *start, const ts_xform *end, double t0, double t1,
                             const ts_anim_xform **out, ts_error *err)
{
    *out = NULL;
    if (!finite_invertible(start))
        return ts_error_set(err, TS_ERR_INVALID, "transform: expected a finite, invertible transform");
    if (!finite_invertible(end))
        return ts_error_set(err, TS_ERR_INVALID, "motion.transform: expected a finite, invertible transform");
    if (!isfinite(t0) || !isfinite(t1))
        return ts_error_set(err, TS_ERR_INVALID, "motion.times: expected finite times");
    ts_anim_xform m;
    if (!ts_anim_xform_init(&m, start, t0, end, t1)) {
        if (!(t1 > t0))
            return ts_error_set(err, TS_ERR_INVALID,
                                "motion.times: the end time %g must be after the start time %g", t1, t0);
        return ts_error_set(err, TS_ERR_INVALID, "motion.transform: an affine transform is needed to interpolate");
    }
    if (!m.animated) return TS_OK;
    ts_anim_xform *copy = ts_arena_alloc(&b->s->arena, sizeof *copy, 16);
    if (!copy) return nomem(err, "the motion");
    *copy = m;
    *out = copy;
    return TS_OK;
}

ts_status ts_scene_builder_add_moving_instance(ts_scene_builder *b, uint32_t object, const ts_xform *start,
                                               double t0, const ts_xform *end, double t1, ts_error *err)
{
    TRY(usable(b, err));
    const ts_anim_xform *m;
    TRY(make_motion(b, start, end, t0, t1, &m, err));
    return push_instance(b, object, start, m, err);
}

ts_status ts_scene_builder_add_moving_shape(ts_scene_builder *b, const ts_shape_desc *d, const ts_xform *start,
                                            double t0, const ts_xform *end, double t1, uint32_t *id, ts_error *err)
{
    TRY(usable(b, err));
    if (b->open_object != TS_NONE)
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "a moving shape inside object \"%s\": a moving shape is an instance of its own, "
                            "and instances do not nest",
                            b->object_names[b->open_object]);
    const ts_anim_xform *m;
    TRY(make_motion(b, start, end, t0, t1, &m, err));
    if (!m) { /* it does not move: a shape like any */
        ts_shape_desc placed_d = *d;
        placed_d.to_world = ts_xform_compose(start, &d->to_world);
        return ts_scene_builder_add_shape(b, &placed_d, id, err);
    }
    if (!ts_rgb_is_black(d->emission))
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "emission: a moving shape cannot emit (pbrt-v3 ignores the area light of an animated "
                            "shape)");
    /* An object of its own (no name: nothing can refer to it), the shape in it as pbrt-v3
     * makes an animated shape — in its own space (d->to_world) — and one moving instance. */
    if (!grow((void **)&b->objects, &b->cap_objects, (size_t)b->n_objects + 1, sizeof *b->objects) ||
        !grow((void **)&b->object_names, &b->cap_object_names, (size_t)b->n_objects + 1, sizeof *b->object_names))
        return nomem(err, "the objects");
    uint32_t obj = b->n_objects;
    b->objects[obj] = (ts_object){b->n_shapes, 0};
    b->object_names[obj] = "";
    b->open_object = obj;
    b->n_objects++;
    ts_status st = ts_scene_builder_add_shape(b, d, id, err);
    b->open_object = TS_NONE;
    if (st) {
        b->n_objects--; /* nothing was added to it */
        return st;
    }
    st = push_instance(b, obj, start, m, err);
    if (st) { /* take the shape back out: the call adds nothing when it fails */
        if (d->type == TS_SHAPE_MESH) b->n_triangles -= d->mesh.n_triangles;
        b->n_shapes--;
        b->n_objects--;
    }
    return st;
}

/* ---------------------------------------------------------------- lights */

/* The rows of d's type's description (build/light_desc.h): each angle in its range, a point
 * that must differ from "from" differing. */
static ts_status check_light_params(const ts_light_desc *d, ts_error *err)
{
    const ts_light_type_desc *t = NULL;
    for (int i = 0; i < TS_LIGHT_DESC_COUNT; i++)
        if (ts_light_descs[i].type == d->type) t = &ts_light_descs[i];
    for (int i = 0; t && i < t->n_params; i++) {
        const ts_light_param *p = &t->params[i];
        const char *at = (const char *)d + p->offset;
        if (p->kind == TS_LPARAM_ANGLE && !ts_lparam_angle_ok(p, *(const double *)(const void *)at, d->cone_angle_deg))
            return ts_error_set(err, TS_ERR_INVALID, "%s: expected an angle in %s degrees, got %g", p->key,
                                (p->flags & TS_LPARAM_UPTO_ANGLE) ? "[0, cone_angle]" : "(0, 180]",
                                *(const double *)(const void *)at);
        if (p->kind == TS_LPARAM_POINT && (p->flags & TS_LPARAM_NOT_FROM)) {
            const ts_vec3 *v = (const ts_vec3 *)(const void *)at;
            if (v->x == d->from.x && v->y == d->from.y && v->z == d->from.z)
                return ts_error_set(err, TS_ERR_INVALID, "%s: must differ from 'from'", p->key);
        }
    }
    return TS_OK;
}

ts_status ts_scene_builder_add_light(ts_scene_builder *b, const ts_light_desc *d, ts_error *err)
{
    TRY(usable(b, err));
    if ((uint64_t)b->n_lights + b->n_area_lights + 1 > b->lim.max_lights)
        return ts_error_set(err, TS_ERR_LIMIT, "more than the limit of %u lights (emitting shapes included)",
                            b->lim.max_lights);
    /* Finiteness of colours, positions, directions and transforms: ts_lights_prepare's. */
    if (!rgb_nonneg(d->color)) return bad_rgb(err, "color", "RGB ≥ 0", d->color);
    ts_light l = {0};
    l.type = d->type;
    l.color = d->color;
    l.shape = TS_NONE;
    l.prim = TS_NONE;
    l.to_world = ts_xform_identity();
    TRY(check_light_params(d, err));
    switch (d->type) {
    case TS_LIGHT_POINT:
        l.position = d->from;
        break;
    case TS_LIGHT_SPOT: {
        double angle = d->cone_angle_deg, delta = d->cone_delta_deg; /* in range: checked above */
        l.position = d->from;
        l.direction = ts_vec3_normalize(ts_vec3_sub(d->to, d->from));
        l.cos_total = cosf(ts_radians((float)angle));
        l.cos_falloff_start = cosf(ts_radians((float)(angle - delta)));
        break;
    }
    case TS_LIGHT_DISTANT:
        l.direction = ts_vec3_normalize(ts_vec3_sub(d->to, d->from));
        break;
    case TS_LIGHT_INFINITE:
        if (d->map) {
            uint32_t i = 0;
            while (i < b->n_envmaps && b->envmaps[i] != d->map)
                i++;
            if (i == b->n_envmaps)
                return ts_error_set(err, TS_ERR_INVALID, "map: the map was not loaded by this scene builder");
        }
        l.map = d->map;
        l.to_world = d->to_world;
        break;
    case TS_LIGHT_AREA:
        return ts_error_set(err, TS_ERR_INVALID, "type: area lights come from shapes with an emission");
    default:
        return ts_error_set(err, TS_ERR_INVALID, "type: unknown light type %d", (int)d->type);
    }
    if (d->samples > TS_LIGHT_SAMPLES_MAX)
        return ts_error_set(err, TS_ERR_INVALID, "samples: %u is not in [1, %d]", d->samples, TS_LIGHT_SAMPLES_MAX);
    l.samples = d->samples;
    if (!grow((void **)&b->lights, &b->cap_lights, (size_t)b->n_lights + 1, sizeof *b->lights))
        return nomem(err, "the lights");
    b->lights[b->n_lights++] = l;
    return TS_OK;
}

void ts_scene_builder_counts(const ts_scene_builder *b, ts_scene_counts *out)
{
    *out = (ts_scene_counts){b->n_materials, b->n_shapes, b->n_lights, b->n_triangles, b->n_area_lights,
                             b->n_objects, b->n_instances};
}

/* ---------------------------------------------------------------- finish */

/* The lists into the arena at their final sizes (+ 1: calloc of 0 may fail), the files'
 * tables and maps into the scene's keeping, and one area light per emitting shape or
 * triangle after the lights added. */
static ts_status lay_out(ts_scene_builder *b, ts_error *err)
{
    ts_scene *s = b->s;
    ts_arena *a = &s->arena;
    uint64_t n_lights = b->n_lights + b->n_area_lights;
    s->materials = ts_arena_calloc(a, (size_t)b->n_materials + 1, sizeof *s->materials);
    s->material_names = ts_arena_calloc(a, (size_t)b->n_materials + 1, sizeof *s->material_names);
    s->shapes = ts_arena_calloc(a, (size_t)b->n_shapes + 1, sizeof *s->shapes);
    s->lights = ts_arena_calloc(a, (size_t)n_lights + 1, sizeof *s->lights);
    s->fourier_tables = ts_arena_calloc(a, (size_t)b->n_fourier_tables + 1, sizeof *s->fourier_tables);
    s->objects = ts_arena_calloc(a, (size_t)b->n_objects + 1, sizeof *s->objects);
    s->instances = ts_arena_calloc(a, (size_t)b->n_instances + 1, sizeof *s->instances);
    if (!s->objects || !s->instances) return nomem(err, "the scene");
    if (b->n_objects) memcpy(s->objects, b->objects, b->n_objects * sizeof *b->objects);
    if (b->n_instances) memcpy(s->instances, b->instances, b->n_instances * sizeof *b->instances);
    s->n_objects = b->n_objects;
    s->n_instances = b->n_instances;
    s->envmaps = ts_arena_calloc(a, (size_t)b->n_envmaps + 1, sizeof *s->envmaps);
    if (!s->materials || !s->material_names || !s->shapes || !s->lights || !s->fourier_tables || !s->envmaps)
        return nomem(err, "the scene");
    if (b->n_fourier_tables)
        memcpy(s->fourier_tables, b->fourier_tables, b->n_fourier_tables * sizeof *b->fourier_tables);
    s->n_fourier_tables = b->n_fourier_tables;
    b->n_fourier_tables = 0;
    if (b->n_envmaps) memcpy(s->envmaps, b->envmaps, b->n_envmaps * sizeof *b->envmaps);
    s->n_envmaps = b->n_envmaps;
    b->n_envmaps = 0;
    if (b->n_materials) {
        memcpy(s->materials, b->materials, b->n_materials * sizeof *b->materials);
        memcpy(s->material_names, b->material_names, b->n_materials * sizeof *b->material_names);
        for (uint32_t k = 0; k < b->n_materials; k++)
            if (s->materials[k].type == TS_MATERIAL_MIX)
                for (int j = 0; j < 2; j++) s->materials[k].mix[j] = &s->materials[s->materials[k].mix_id[j]];
    }
    s->n_materials = b->n_materials;
    if (b->n_shapes) memcpy(s->shapes, b->shapes, b->n_shapes * sizeof *b->shapes);
    s->n_shapes = b->n_shapes;
    s->n_triangles = b->n_triangles;
    if (b->n_lights) memcpy(s->lights, b->lights, b->n_lights * sizeof *b->lights);
    s->n_lights = b->n_lights;
    TRY(lay_out_media(b, err));
    for (uint32_t k = 0; k < s->n_shapes; k++) {
        ts_shape *sh = &s->shapes[k];
        if (!sh->emissive) continue;
        sh->first_light = s->n_lights;
        uint32_t count = sh->type == TS_SHAPE_MESH ? sh->mesh.n_triangles : 1;
        /* Two consecutive triangles of a mesh that form a rectangle are one light
         * (docs/design.md §4, ts_shape_triangles_rectangle), so each triangle's light is
         * looked up in prim_light. */
        uint32_t *prim_light = NULL;
        if (sh->type == TS_SHAPE_MESH) {
            prim_light = ts_arena_calloc(a, (size_t)count, sizeof *prim_light);
            if (!prim_light) return nomem(err, "the lights");
            sh->prim_light = prim_light;
        }
        for (uint32_t t = 0; t < count; t++) {
            ts_light *l = &s->lights[s->n_lights];
            *l = (ts_light){0};
            l->type = TS_LIGHT_AREA;
            l->color = sh->emission;
            l->shape = k;
            l->prim = sh->type == TS_SHAPE_MESH ? t : 0;
            l->two_sided = sh->two_sided;
            l->samples = sh->light_samples;
            l->to_world = ts_xform_identity();
            if (prim_light) {
                prim_light[t] = s->n_lights;
                if (t + 1 < count && ts_shape_triangles_rectangle(sh, t, t + 1)) {
                    l->rect = true;
                    l->prim_b = ++t;
                    prim_light[t] = s->n_lights;
                }
            }
            s->n_lights++;
        }
    }
    return TS_OK;
}

static ts_status build(ts_scene_builder *b, ts_error *err)
{
    ts_scene *s = b->s;
    TRY(ts_cancel_check(b->lim.cancel, err));
    s->accel = ts_accel_create_instanced(s->shapes, s->n_shapes, s->objects, s->n_objects, s->instances,
                                         s->n_instances, b->lim.cancel, err);
    if (!s->accel) return err->status ? err->status : TS_ERR_INTERNAL;
    s->bounds = ts_accel_bounds(s->accel);
    /* Rays carry float coordinates and Embree refuses components beyond ~1.8e18; far before
     * that, float spacing makes geometry meaningless. Refuse scenes that reach beyond. */
    const float limit = 1e15f;
    if (!ts_bounds3_is_empty(s->bounds) &&
        !(fabsf(s->bounds.lo.x) <= limit && fabsf(s->bounds.lo.y) <= limit &&
          fabsf(s->bounds.lo.z) <= limit && fabsf(s->bounds.hi.x) <= limit &&
          fabsf(s->bounds.hi.y) <= limit && fabsf(s->bounds.hi.z) <= limit))
    {
        /* Bounds of a shape beyond the float range are not printed (they read "-nan"). */
        if (!ts_vec3_is_finite(s->bounds.lo) || !ts_vec3_is_finite(s->bounds.hi))
            return ts_error_set(err, TS_ERR_INVALID,
                                "shapes: the scene reaches beyond ±1e15 units from the origin (its bounds overflow "
                                "the float range); scale or move it");
        return ts_error_set(
            err, TS_ERR_INVALID,
            "shapes: the scene reaches beyond ±1e15 units from the origin (bounds [%g, %g, %g] to "
            "[%g, %g, %g]); scale or move it",
            s->bounds.lo.x, s->bounds.lo.y, s->bounds.lo.z, s->bounds.hi.x, s->bounds.hi.y, s->bounds.hi.z);
    }
    ts_vec3 from = s->camera.origin;
    if (!(fabsf(from.x) <= limit && fabsf(from.y) <= limit && fabsf(from.z) <= limit))
        return ts_error_set(err, TS_ERR_INVALID, "camera.from: farther than 1e15 units from the origin");
    TRY(ts_lights_prepare(s->lights, s->n_lights, s->shapes, s->bounds, err));
    ts_light_sampling mode = TS_LIGHT_SAMPLING_POWER;
    bool selects = s->integrator.type == TS_INTEGRATOR_PATH || s->integrator.type == TS_INTEGRATOR_DIRECT ||
                   s->integrator.type == TS_INTEGRATOR_VOLPATH;
    /* JSON path's default: the light hierarchy wherever there is a choice to make (measured
     * 1.2–3× power's efficiency on the shipped scenes of 2–5 lights, 1.1–12× on corridors of
     * 16–4800: docs/performance.md "Many lights"); for one light power's pmf 1 costs less. */
    if (s->integrator.light_sampling == TS_LIGHT_SELECT_AUTO)
        s->integrator.light_sampling = s->n_lights >= 2 ? TS_LIGHT_SELECT_BVH : TS_LIGHT_SELECT_POWER;
    if (selects && s->integrator.light_sampling == TS_LIGHT_SELECT_UNIFORM)
        mode = TS_LIGHT_SAMPLING_UNIFORM;
    else if (selects && s->integrator.light_sampling == TS_LIGHT_SELECT_SPATIAL)
        mode = TS_LIGHT_SAMPLING_SPATIAL;
    else if (selects && s->integrator.light_sampling == TS_LIGHT_SELECT_BVH)
        mode = TS_LIGHT_SAMPLING_BVH;
    TRY(ts_light_distribution_init(&s->light_distribution, s->lights, s->n_lights, s->shapes, mode, s->bounds,
                                   &s->arena, err));
    s->infinite_lights = ts_arena_calloc(&s->arena, (size_t)s->n_lights + 1, sizeof *s->infinite_lights);
    if (!s->infinite_lights) return nomem(err, "the lights");
    for (uint32_t i = 0; i < s->n_lights; i++)
        if (s->lights[i].type == TS_LIGHT_INFINITE) s->infinite_lights[s->n_infinite_lights++] = i;
    for (uint32_t i = 0; i < s->n_materials; i++) {
        if (s->materials[i].textured) s->textured = true;
        if (s->materials[i].cost > s->shading_cost) s->shading_cost = s->materials[i].cost;
    }
    uint32_t alpha_cost = 0; /* a hit's cut-out test, once for either kind of ray */
    for (uint32_t i = 0; i < s->n_shapes; i++) {
        const ts_shape *sh = &s->shapes[i];
        uint32_t c = sh->alpha ? sh->alpha->cost : 0, d = sh->shadow_alpha ? sh->shadow_alpha->cost : 0;
        if ((c > d ? c : d) > alpha_cost) alpha_cost = c > d ? c : d;
    }
    s->shading_cost += alpha_cost;
    for (uint32_t i = 0; i < s->n_shapes; i++) /* dn/du is for bump maps and differentials */
        s->shapes[i].no_normal_derivatives = !s->textured;
    s->effects = ts_effects_analyse(s) & ~s->job.effects_off;
    return TS_OK;
}

ts_status ts_scene_builder_finish(ts_scene_builder *b, ts_scene **out, ts_error *err)
{
    *out = NULL;
    TRY(usable(b, err));
    b->finished = true;
    const char *missing = !b->has_film         ? "film"
                          : !b->has_camera     ? "camera"
                          : !b->has_sampler    ? "sampler"
                          : !b->has_integrator ? "integrator"
                          : !b->has_digest     ? "digest"
                                               : NULL;
    if (missing)
        return ts_error_set(err, TS_ERR_INVALID, "%s: not set (the scene builder needs it)", missing);
    if (b->open_object != TS_NONE)
        return ts_error_set(err, TS_ERR_INVALID, "object \"%s\" is not ended", b->object_names[b->open_object]);
    if ((uint64_t)b->n_lights + b->n_area_lights > b->lim.max_lights)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "lights: %llu lights (with emitting triangles) is more than the limit of %u",
                            (unsigned long long)(b->n_lights + b->n_area_lights), b->lim.max_lights);
    ts_scene *s = b->s;
    if (!s->name && !(s->name = ts_arena_strdup(&s->arena, "untitled"))) return nomem(err, "the scene");
    TRY(lay_out(b, err));
    TRY(ts_camera_init(&s->camera, &b->camera, s->width, s->height, err));
    TRY(build(b, err));
    *out = s;
    b->s = NULL;
    return TS_OK;
}

/* ---------------------------------------------------------------- participating media */

#define MAX_MEDIA (1u << 16)

static bool finite_nonneg(double v) { return v >= 0 && isfinite(v); }

uint32_t ts_scene_builder_find_medium(const ts_scene_builder *b, const char *name)
{
    if (!name) return TS_NONE;
    for (uint32_t k = 0; k < b->n_media; k++)
        if (b->medium_names[k] && strcmp(b->medium_names[k], name) == 0) return k;
    return TS_NONE;
}

/* σa, σs of the desc: given, else the preset's, else pbrt-v3's default; times scale. */
static ts_status medium_sigmas(const ts_medium_desc *d, ts_rgb *sigma_a, ts_rgb *sigma_s, ts_error *err)
{
    ts_rgb a = {.0011f, .0024f, .014f}, sc = {2.55f, 3.21f, 3.77f};
    if (d->preset && !ts_medium_preset(d->preset, &a, &sc))
        return ts_error_set(err, TS_ERR_INVALID, "preset: unknown medium preset \"%s\" (pbrt-v3's names, e.g. "
                                                 "\"Wholemilk\", \"Ketchup\", \"Espresso\")",
                            d->preset);
    if (d->has_sigma_a) a = d->sigma_a;
    if (d->has_sigma_s) sc = d->sigma_s;
    if (!rgb_finite_nonneg(a)) return bad_rgb(err, "sigma_a", "finite RGB ≥ 0", a);
    if (!rgb_finite_nonneg(sc)) return bad_rgb(err, "sigma_s", "finite RGB ≥ 0", sc);
    if (!finite_nonneg(d->scale))
        return ts_error_set(err, TS_ERR_INVALID, "scale: expected a finite number ≥ 0, got %g", d->scale);
    float k = (float)d->scale;
    *sigma_a = ts_rgb_scale(a, k);
    *sigma_s = ts_rgb_scale(sc, k);
    if (!rgb_finite_nonneg(*sigma_a) || !rgb_finite_nonneg(*sigma_s))
        return ts_error_set(err, TS_ERR_INVALID, "scale: %g takes σ beyond the float range", d->scale);
    return TS_OK;
}

/* The grid's parts of m from d, its densities copied into the arena. */
static ts_status medium_grid(ts_scene_builder *b, const ts_medium_desc *d, ts_medium *m, ts_error *err)
{
    if (d->nx < 1 || d->ny < 1 || d->nz < 1)
        return ts_error_set(err, TS_ERR_INVALID, "nx, ny, nz: expected integers ≥ 1, got %u, %u, %u", d->nx, d->ny,
                            d->nz);
    uint64_t nxy = (uint64_t)d->nx * d->ny; /* < 2^64: each count is below 2^32 */
    if (nxy > UINT64_MAX / d->nz) /* no array holds that many (and the product must not wrap) */
        return ts_error_set(err, TS_ERR_INVALID, "density: %llu values, expected nx·ny·nz = %u·%u·%u",
                            (unsigned long long)d->n_density, d->nx, d->ny, d->nz);
    uint64_t n = nxy * d->nz;
    if (d->n_density != n)
        return ts_error_set(err, TS_ERR_INVALID, "density: %llu values, expected nx·ny·nz = %u·%u·%u = %llu",
                            (unsigned long long)d->n_density, d->nx, d->ny, d->nz, (unsigned long long)n);
    if (n > b->lim.max_memory / sizeof(float) && b->lim.max_memory)
        return ts_error_set(err, TS_ERR_LIMIT, "density: %llu values exceed the scene's memory limit",
                            (unsigned long long)n);
    const double p0[3] = {d->p0.x, d->p0.y, d->p0.z}, p1[3] = {d->p1.x, d->p1.y, d->p1.z};
    for (int k = 0; k < 3; k++)
        if (!(isfinite(p0[k]) && isfinite(p1[k]) && p0[k] < p1[k]))
            return ts_error_set(err, TS_ERR_INVALID, "p0, p1: expected finite corners with p0 < p1 on every axis, got "
                                                     "[%g, %g, %g] and [%g, %g, %g]",
                                p0[0], p0[1], p0[2], p1[0], p1[1], p1[2]);
    if (m->sigma_t.r != m->sigma_t.g || m->sigma_t.r != m->sigma_t.b)
        return ts_error_set(err, TS_ERR_INVALID,
                            "sigma_a, sigma_s: a grid's σa + σs must be the same in every channel (pbrt-v3's "
                            "heterogeneous medium), got [%g, %g, %g]",
                            m->sigma_t.r, m->sigma_t.g, m->sigma_t.b);
    float *den = ts_arena_alloc(&b->s->arena, (size_t)n * sizeof *den, _Alignof(float));
    if (!den) return nomem(err, "the medium's density grid");
    float mx = 0;
    for (uint64_t i = 0; i < n; i++) {
        float v = d->density[i];
        if (!(v >= 0 && isfinite(v)))
            return ts_error_set(err, TS_ERR_INVALID, "density[%llu]: expected a finite number ≥ 0, got %g",
                                (unsigned long long)i, v);
        den[i] = v;
        if (v > mx) mx = v;
    }
    if (!isfinite(m->sigma_t.r * mx))
        return ts_error_set(err, TS_ERR_INVALID,
                            "density: σa + σs (%g) times the largest density (%g) is beyond the float range",
                            m->sigma_t.r, mx);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(d->to_world.m.m[i][j]) || !isfinite(d->to_world.m_inv.m[i][j]))
                return ts_error_set(err, TS_ERR_INVALID, "transform: not a finite, invertible transform");
    /* unit cube → [p0, p1] → world */
    ts_xform box = ts_xform_scale((ts_dvec3){p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]});
    ts_xform at = ts_xform_translate(d->p0);
    ts_xform data = ts_xform_compose(&at, &box);
    m->to_unit = ts_xform_compose(&d->to_world, &data);
    m->nx = d->nx;
    m->ny = d->ny;
    m->nz = d->nz;
    m->density = den;
    m->max_density = mx;
    uint32_t kx, ky, kz;
    ts_medium_majorant_grid(m, &kx, &ky, &kz, NULL);
    float *maj = ts_arena_alloc(&b->s->arena, (size_t)kx * ky * kz * sizeof *maj, _Alignof(float));
    if (!maj) return nomem(err, "the medium's majorant grid");
    ts_medium_majorant_grid(m, &kx, &ky, &kz, maj);
    m->mx = kx, m->my = ky, m->mz = kz;
    m->majorant = maj;
    return TS_OK;
}

ts_status ts_scene_builder_add_medium(ts_scene_builder *b, const char *name, const ts_medium_desc *d, uint32_t *id,
                                      ts_error *err)
{
    TRY(usable(b, err));
    if (b->n_media >= MAX_MEDIA) return ts_error_set(err, TS_ERR_LIMIT, "more than the limit of %u media", MAX_MEDIA);
    if (name && ts_scene_builder_find_medium(b, name) != TS_NONE)
        return ts_error_set(err, TS_ERR_INVALID, "a medium named \"%s\" was added before", name);
    if (d->type != TS_MEDIUM_HOMOGENEOUS && d->type != TS_MEDIUM_GRID)
        return ts_error_set(err, TS_ERR_INVALID, "type: unknown medium type %d", (int)d->type);
    ts_medium m = {.type = d->type};
    TRY(medium_sigmas(d, &m.sigma_a, &m.sigma_s, err));
    m.sigma_t = ts_rgb_add(m.sigma_a, m.sigma_s);
    if (!rgb_finite_nonneg(m.sigma_t)) return bad_rgb(err, "sigma_a + sigma_s", "finite RGB ≥ 0", m.sigma_t);
    if (!(d->g > -1 && d->g < 1))
        return ts_error_set(err, TS_ERR_INVALID, "g: expected a number in (−1, 1), got %g", d->g);
    m.g = (float)d->g;
    if (m.g <= -1 || m.g >= 1) m.g = m.g < 0 ? -0x1.fffffep-1f : 0x1.fffffep-1f; /* rounding to float */
    if (d->type == TS_MEDIUM_GRID) TRY(medium_grid(b, d, &m, err));
    size_t need = (size_t)b->n_media + 1;
    if (!grow((void **)&b->media, &b->cap_media, need, sizeof *b->media) ||
        !grow((void **)&b->medium_names, &b->cap_medium_names, need, sizeof *b->medium_names))
        return nomem(err, "the media");
    const char *copy = NULL;
    if (name && !(copy = ts_arena_strdup(&b->s->arena, name))) return nomem(err, "the medium names");
    b->media[b->n_media] = m;
    b->medium_names[b->n_media] = copy;
    if (id) *id = b->n_media;
    b->n_media++;
    return TS_OK;
}

ts_status ts_scene_builder_set_camera_medium(ts_scene_builder *b, uint32_t medium, ts_error *err)
{
    TRY(usable(b, err));
    if (medium != TS_NONE && medium >= b->n_media)
        return ts_error_set(err, TS_ERR_INVALID, "camera.medium: no medium of id %u (%u were added)", medium,
                            b->n_media);
    b->camera_medium = medium;
    return TS_OK;
}

static ts_status check_shape_media(const ts_scene_builder *b, const ts_shape_desc *d, ts_error *err)
{
    if (d->material == TS_NONE && !ts_rgb_is_black(d->emission))
        return ts_error_set(err, TS_ERR_INVALID, "emission: a shape without a surface (material none) cannot emit");
    if (!d->medium_interface) return TS_OK;
    const uint32_t ids[2] = {d->medium_inside, d->medium_outside};
    for (int k = 0; k < 2; k++)
        if (ids[k] != TS_NONE && ids[k] >= b->n_media)
            return ts_error_set(err, TS_ERR_INVALID, "medium.%s: no medium of id %u (%u were added)",
                                k ? "outside" : "inside", ids[k], b->n_media);
    return TS_OK;
}

static void set_shape_media(const ts_shape_desc *d, ts_shape *sh)
{
    sh->medium_transition = d->medium_interface && d->medium_inside != d->medium_outside;
    sh->medium_inside = sh->medium_transition ? d->medium_inside : TS_NONE;
    sh->medium_outside = sh->medium_transition ? d->medium_outside : TS_NONE;
}

static ts_status lay_out_media(ts_scene_builder *b, ts_error *err)
{
    ts_scene *s = b->s;
    s->media = ts_arena_calloc(&s->arena, (size_t)b->n_media + 1, sizeof *s->media);
    if (!s->media) return nomem(err, "the media");
    if (b->n_media) memcpy(s->media, b->media, b->n_media * sizeof *b->media);
    s->n_media = b->n_media;
    s->camera_medium = b->camera_medium;
    return TS_OK;
}
