/* pbrt_import.c — a parsed pbrt-v3 scene onto the scene builder; see pbrt_import.h.
 *
 * The order is the JSON front end's: film, camera, sampler, integrator, then the shapes
 * (each shape's material mapped and added the first time a shape uses it), then the
 * lights. Every element is handed to the builder through the same transform and placement
 * calls scene_json.c makes for the JSON document written beside it, so the two agree bit
 * for bit. Positions in messages are the parser's (file:line:column of the directive or
 * of the parameter). */
#include "pbrt3/pbrt_import.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "geometry/curve.h"
#include "mesh/mesh_read.h"
#include "mesh/mesh_subdiv.h"
#include "build/light_desc.h"
#include "build/medium_desc.h"
#include "materials/material_desc.h"
#include "spectrum/spectrum.h"
#include "json/json_write.h"
#include "json/scene_json_texture_write.h"
#include "pbrt3/texture_pbrt.h"
#include "integrators/integrator.h"

#define TRY(expr)                                                                                            \
    do {                                                                                                     \
        ts_status st_ = (expr);                                                                              \
        if (st_ != TS_OK) return st_;                                                                        \
    } while (0)

enum { MAT_UNMAPPED, MAT_MAPPED, MAT_NO_SURFACE };

typedef struct imp {
    ts_pbrt_scene *s;
    ts_scene_builder *b;
    cJSON *doc, *jmaterials, *jshapes, *jlights; /* NULL unless converting */
    cJSON *jobjects, *jinstances;
    cJSON *jtarget; /* where map_shape puts a shape: jshapes, or an object's "shapes" */
    ts_warning_fn warn;
    void *warn_ctx;
    ts_error *err;
    char **seen; /* warnings given, less their position (open addressing) */
    size_t seen_cap, seen_n, repeats;
    uint32_t *mat_id; /* per material, the last for pbrt-v3's default matte */
    uint8_t *mat_state;
    bool direct_all;    /* the integrator takes several samples per light (nsamples matters) */
    ts_texture_pbrt tp; /* the scene's textures (pbrt3/texture_pbrt.h), when it has any */
    bool has_textures;
    ts_json_texture_writer jtex; /* the document's "textures", when converting */
    uint32_t *medium_id; /* per MakeNamedMedium, the builder's medium */
    cJSON *jmedia;       /* the document's "media", when converting and the scene has any */
} imp;

static ts_status map_media(imp *im);
static ts_status shape_media(imp *im, const ts_pbrt_shape *sh, ts_shape_desc *d, cJSON *j);

/* ---------------------------------------------------------------- messages */

static uint32_t hash_str(const char *s)
{
    uint32_t h = 2166136261u;
    for (; *s; s++)
        h = (h ^ (uint8_t)*s) * 16777619u;
    return h;
}

/* true if body was not given before (and remembers it). */
static bool first_time(imp *im, const char *body)
{
    if (im->seen_n * 2 >= im->seen_cap) {
        size_t cap = im->seen_cap ? im->seen_cap * 2 : 64;
        char **t = calloc(cap, sizeof *t);
        if (!t) return true; /* out of memory: repeat rather than lose a warning */
        for (size_t i = 0; i < im->seen_cap; i++)
            if (im->seen[i]) {
                size_t j = hash_str(im->seen[i]) & (cap - 1);
                while (t[j])
                    j = (j + 1) & (cap - 1);
                t[j] = im->seen[i];
            }
        free(im->seen);
        im->seen = t;
        im->seen_cap = cap;
    }
    size_t j = hash_str(body) & (im->seen_cap - 1);
    for (; im->seen[j]; j = (j + 1) & (im->seen_cap - 1))
        if (strcmp(im->seen[j], body) == 0) return false;
    im->seen[j] = strdup(body);
    if (im->seen[j]) im->seen_n++;
    return true;
}

static void emit(imp *im, ts_pbrt_loc loc, const char *body)
{
    if (!im->warn) return;
    if (!first_time(im, body)) {
        im->repeats++;
        return;
    }
    char line[TS_ERROR_MAX + 64];
    if (loc.file)
        snprintf(line, sizeof line, "%s:%u:%u: %s", loc.file, loc.line, loc.column, body);
    else
        snprintf(line, sizeof line, "%s", body);
    ts_pbrt_sanitize_utf8(line);
    im->warn(im->warn_ctx, line);
}

static void warnf(imp *im, ts_pbrt_loc loc, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void warnf(imp *im, ts_pbrt_loc loc, const char *fmt, ...)
{
    char body[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(body, sizeof body, fmt, ap);
    va_end(ap);
    emit(im, loc, body);
}

/* A warning about a whole directive: "<Directive> \"<arg>\": …". */
static void dwarn(imp *im, const ts_pbrt_params *ps, ts_pbrt_loc loc, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void dwarn(imp *im, const ts_pbrt_params *ps, ts_pbrt_loc loc, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    warnf(im, loc, "%s \"%s\"%s%s", ps->directive, ps->directive_arg,
          strncmp(msg, "is ", 3) == 0 ? " " : ": ", msg);
}

/* A warning about one parameter: "<Directive> \"<arg>\": \"<type> <name>\" …". */
static void pwarn(imp *im, const ts_pbrt_params *ps, const ts_pbrt_param *p, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void pwarn(imp *im, const ts_pbrt_params *ps, const ts_pbrt_param *p, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    warnf(im, p->loc, "%s \"%s\": \"%s %s\" %s", ps->directive, ps->directive_arg, p->type_name, p->name,
          msg);
}

static void warn_unused(imp *im, const ts_pbrt_params *ps)
{
    size_t cur = 0;
    for (const ts_pbrt_param *p; (p = ts_pbrt_params_next_unused(ps, &cur));)
        pwarn(im, ps, p, "is not used");
}

/* An error about a whole directive. */
static ts_status derr(imp *im, const ts_pbrt_params *ps, ts_pbrt_loc loc, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static ts_status derr(imp *im, const ts_pbrt_params *ps, ts_pbrt_loc loc, ts_status st, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    /* "Shape \"x\" is not supported", "Shape \"x\": the mesh is too large" */
    const char *sep = strncmp(msg, "is ", 3) == 0 ? " " : ": ";
    if (loc.file)
        ts_error_set(im->err, st, "%s:%u:%u: %s \"%s\"%s%s", loc.file, loc.line, loc.column, ps->directive,
                     ps->directive_arg, sep, msg);
    else
        ts_error_set(im->err, st, "%s \"%s\"%s%s", ps->directive, ps->directive_arg, sep, msg);
    ts_pbrt_sanitize_utf8(im->err->message);
    return st;
}

/* A builder's sentence about what a directive made gets the directive in front. */
static ts_status at(imp *im, ts_status st, const ts_pbrt_params *ps, ts_pbrt_loc loc)
{
    if (!st) return st;
    char inner[TS_ERROR_MAX];
    memcpy(inner, im->err->message, sizeof inner);
    return derr(im, ps, loc, st, "%s", inner);
}

static ts_status nomem(imp *im)
{
    return ts_error_set(im->err, TS_ERR_NOMEM, "out of memory while importing the pbrt-v3 scene");
}

/* ---------------------------------------------------------------- parameter values */

/* The value of a "constant" texture named by texture parameter p; other classes are
 * refused until materials take textures. */
static ts_status constant_texture(imp *im, ts_pbrt_params *ps, ts_pbrt_param *p, bool want_float, float *f,
                                  ts_rgb *c);

/* A light's "integer nsamples" (alias "samples"), pbrt-v3's nSamples: the samples it takes
 * per camera sample under directlighting's strategy "all" (pbrt-v3 clamps it below at 1;
 * every sampler's RoundCount keeps it as it is but 02sequence's, whose power of two the
 * Sobol sampler does not need). Other integrators take one light sample per vertex and
 * ignore it, as pbrt-v3's do: *out is 0 (the integrator's count) there and where it is 1. */
static ts_status light_samples(imp *im, ts_pbrt_params *ps, uint32_t *out)
{
    int32_t ns;
    *out = 0;
    TRY(ts_pbrt_find_int(ps, "nsamples", 1, &ns, im->err));
    TRY(ts_pbrt_find_int(ps, "samples", ns, &ns, im->err));
    if (!im->direct_all || ns <= 1) return TS_OK;
    if (ns > TS_LIGHT_SAMPLES_MAX) {
        ts_pbrt_param *p = ts_pbrt_params_get(ps, "samples");
        if (!p) p = ts_pbrt_params_get(ps, "nsamples");
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_LIMIT, "%d samples per light is above the limit of %d",
                                   (int)ns, TS_LIGHT_SAMPLES_MAX);
    }
    *out = (uint32_t)ns;
    return TS_OK;
}

static ts_status get_rgb(imp *im, ts_pbrt_params *ps, const char *name, ts_rgb def, ts_rgb *out)
{
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    *out = def;
    if (!p) return TS_OK;
    size_t values = ts_pbrt_param_values(p);
    switch (p->type) {
    case TS_PBRT_PARAM_RGB:
    case TS_PBRT_PARAM_XYZ:
        return ts_pbrt_find_rgb(ps, name, def, out, im->err);
    case TS_PBRT_PARAM_SPECTRUM:
        *out = ts_spectrum_to_rgb(p->floats, p->n / 2);
        return TS_OK;
    case TS_PBRT_PARAM_BLACKBODY:
        if (p->n == 1)
            *out = ts_spectrum_blackbody_rgb(p->floats[0], 1);
        else if (p->n == 2)
            *out = ts_spectrum_blackbody_rgb(p->floats[0], p->floats[1]);
        else
            return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID,
                                       "expects a temperature and a scale (2 values), got %zu values", p->n);
        return TS_OK;
    case TS_PBRT_PARAM_TEXTURE:
        return constant_texture(im, ps, p, false, NULL, out);
    default:
        (void)values;
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID,
                                   "expects a colour (rgb, xyz, spectrum, blackbody or a texture)");
    }
}

static ts_status get_float(imp *im, ts_pbrt_params *ps, const char *name, float def, float *out)
{
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    *out = def;
    if (!p) return TS_OK;
    if (p->type == TS_PBRT_PARAM_TEXTURE) return constant_texture(im, ps, p, true, out, NULL);
    return ts_pbrt_find_float(ps, name, def, out, im->err);
}

/* A material's colour parameter: a constant as get_rgb reads it, or a texture parameter
 * naming a texture of the scene (colour, or float read as grey), made by
 * ts_texture_pbrt_build. */
static ts_status get_mrgb(imp *im, ts_pbrt_params *ps, const char *name, ts_rgb def, ts_material_rgb *out)
{
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    *out = ts_material_rgb_const(def);
    if (p && p->type == TS_PBRT_PARAM_TEXTURE && im->has_textures) {
        int32_t ti = p->texture_spectrum >= 0 ? p->texture_spectrum : p->texture_float;
        if (ti >= 0 && strcmp(im->s->textures[ti].class_name, "constant") != 0) {
            *out = (ts_material_rgb){ts_rgb_gray(0), im->tp.textures[ti]}; /* value 0, as JSON v1 has it */
            return TS_OK;
        }
    }
    return get_rgb(im, ps, name, def, &out->value);
}

/* A material's float parameter: a constant, or a texture parameter naming a float texture. */
static ts_status get_mfloat(imp *im, ts_pbrt_params *ps, const char *name, float def, ts_material_float *out)
{
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    *out = ts_material_float_const(def);
    if (p && p->type == TS_PBRT_PARAM_TEXTURE && im->has_textures && p->texture_float >= 0 &&
        strcmp(im->s->textures[p->texture_float].class_name, "constant") != 0) {
        *out = (ts_material_float){0, im->tp.textures[p->texture_float]}; /* value 0, as JSON v1 has it */
        return TS_OK;
    }
    return get_float(im, ps, name, def, &out->value);
}

static ts_status constant_texture(imp *im, ts_pbrt_params *ps, ts_pbrt_param *p, bool want_float, float *f,
                                  ts_rgb *c)
{
    int32_t ti = want_float ? p->texture_float : p->texture_spectrum;
    if (ti < 0)
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID, "names no %s texture \"%s\" in scope",
                                   want_float ? "float" : "spectrum", p->strings[0]);
    ts_pbrt_texture *t = &im->s->textures[ti];
    if (strcmp(t->class_name, "constant") != 0)
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_UNSUPPORTED,
                                   "names the \"%s\" texture \"%s\": textured material parameters are not "
                                   "supported yet (only \"constant\" textures)",
                                   t->class_name, t->name);
    ts_status st = want_float ? ts_pbrt_find_float(&t->params, "value", 1, f, im->err)
                              : get_rgb(im, &t->params, "value", ts_rgb_gray(1), c);
    if (!st) warn_unused(im, &t->params);
    return st;
}

/* ---------------------------------------------------------------- JSON helpers */


/* The transform the JSON front end makes of a one-matrix "transform" list (its order of
 * composition, so both front ends hold the same bits). false: the matrix is singular. */
static bool user_xform(const ts_mat4 *m, ts_xform *out)
{
    ts_xform step, id = ts_xform_identity();
    if (!ts_xform_from_matrix(m, &step)) return false;
    *out = ts_xform_compose(&step, &id);
    return true;
}

/* ---------------------------------------------------------------- motion */

static bool mirrors(const ts_mat4 *m)
{
    const double(*a)[4] = m->m;
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
               a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]) <
           0;
}

/* The end keyframe of an entity whose CTM is animated (pbrt-v3's two CTMs differ): its
 * transform, after the checks pbrt-v3's AnimatedTransform needs — an interval
 * (TransformTimes' end after its start) and affine, invertible matrices — and the
 * warning for a mirroring keyframe (core/animated_transform.h's Decision). */
static ts_status motion_end(imp *im, const ts_pbrt_params *ps, ts_pbrt_loc loc, const ts_mat4 *start,
                            const ts_mat4 *end, ts_xform *out)
{
    const ts_pbrt_scene *s = im->s;
    if (!(s->transform_end_time > s->transform_start_time))
        return derr(im, ps, loc, TS_ERR_INVALID,
                    "the transformation is animated (ActiveTransform) but TransformTimes gives no interval "
                    "(start and end time %g)",
                    s->transform_start_time);
    if (!user_xform(end, out))
        return derr(im, ps, loc, TS_ERR_INVALID, "the transformation matrix at the end time is singular");
    ts_dvec3 t;
    ts_quat q;
    ts_mat4 sc;
    if (!ts_mat4_decompose(start, &t, &q, &sc) || !ts_mat4_decompose(end, &t, &q, &sc))
        return derr(im, ps, loc, TS_ERR_INVALID,
                    "an animated transformation must be affine (no projective row) to be interpolated");
    if (mirrors(start) || mirrors(end))
        dwarn(im, ps, loc,
              "the animated transformation mirrors: it is interpolated with the mirror kept apart from the "
              "rotation, where pbrt-v3 interpolates a mirroring matrix through one that is no rotation (its "
              "image differs during the shutter; docs/design.md §9)");
    return TS_OK;
}

/* "motion": {"times": [t0, t1], "transform": [end]} for the JSON document. */
static bool jmotion(imp *im, cJSON *j, const ts_mat4 *end)
{
    double times[2] = {im->s->transform_start_time, im->s->transform_end_time};
    cJSON *m = cJSON_CreateObject();
    bool ok = m && ts_jw_add(m, "times", ts_jw_doubles(times, 2)) && ts_jw_add(m, "transform", ts_jw_transform(end));
    if (!ok || !ts_jw_add(j, "motion", m)) {
        if (!ok) cJSON_Delete(m);
        return false;
    }
    return true;
}

/* ---------------------------------------------------------------- film, camera, sampler, integrator */

static ts_status map_film(imp *im, uint32_t *width, uint32_t *height)
{
    ts_pbrt_option *o = &im->s->film;
    ts_pbrt_params *ps = &o->params;
    if (strcmp(o->type, "image") != 0)
        return derr(im, ps, o->loc, TS_ERR_UNSUPPORTED, "is not supported (the film is \"image\")");
    int32_t xres, yres;
    TRY(ts_pbrt_find_int(ps, "xresolution", 1280, &xres, im->err));
    TRY(ts_pbrt_find_int(ps, "yresolution", 720, &yres, im->err));
    if (xres < 1 || yres < 1)
        return derr(im, ps, o->loc, TS_ERR_INVALID, "the resolution %d × %d has no pixel", xres, yres);
    ts_film_desc f = {.width = (uint32_t)xres, .height = (uint32_t)yres, .crop = {0, 1, 0, 1}};
    const float *cw;
    size_t ncw;
    TRY(ts_pbrt_find_floats(ps, "cropwindow", &cw, &ncw, im->err));
    if (cw) {
        if (ncw != 4)
            return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "cropwindow"), im->err, TS_ERR_INVALID,
                                       "expects 4 values (x0 x1 y0 y1), got %zu", ncw);
        /* pbrt-v3: each pair ordered, then clamped to [0, 1]. */
        for (int k = 0; k < 2; k++) {
            float a = cw[2 * k], b = cw[2 * k + 1];
            f.crop[2 * k] = ts_clampf(fminf(a, b), 0, 1);
            f.crop[2 * k + 1] = ts_clampf(fmaxf(a, b), 0, 1);
        }
    }
    /* pbrt-v3's ImageFilm: "scale" multiplies every written pixel, "maxsampleluminance"
     * clamps each sample's luminance before its filter weight (film.h). */
    TRY(ts_pbrt_find_float(ps, "scale", 1, &f.scale, im->err));
    if (!(f.scale > 0) || !isfinite(f.scale))
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "scale"), im->err, TS_ERR_INVALID,
                                   "must be a finite number > 0, got %g", f.scale);
    TRY(ts_pbrt_find_float(ps, "maxsampleluminance", INFINITY, &f.max_sample_luminance, im->err));
    if (!(f.max_sample_luminance > 0))
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "maxsampleluminance"), im->err, TS_ERR_INVALID,
                                   "must be a number > 0, got %g", f.max_sample_luminance);
    const char *filename;
    TRY(ts_pbrt_find_string(ps, "filename", NULL, &filename, im->err));
    if (filename)
        pwarn(im, ps, ts_pbrt_params_get(ps, "filename"),
              "is not used: tessera writes the files its -o options name");
    warn_unused(im, ps);

    ts_pbrt_option *fo = &im->s->filter;
    ts_pbrt_params *fps = &fo->params;
    static const char *const names[] = {"box", "triangle", "gaussian", "mitchell", "sinc"};
    static const float widths[] = {0.5f, 2, 2, 2, 4};
    int t = -1;
    for (int k = 0; k < 5; k++)
        if (strcmp(fo->type, names[k]) == 0) t = k;
    if (t < 0)
        return derr(im, fps, fo->loc, TS_ERR_UNSUPPORTED,
                    "is not a pbrt-v3 filter (box, triangle, gaussian, mitchell, sinc)");
    float xw, yw;
    TRY(ts_pbrt_find_float(fps, "xwidth", widths[t], &xw, im->err));
    TRY(ts_pbrt_find_float(fps, "ywidth", widths[t], &yw, im->err));
    if (!(xw > 0) || !(yw > 0))
        return derr(im, fps, fo->loc, TS_ERR_INVALID, "xwidth and ywidth must be positive, got %g and %g", xw,
                    yw);
    if (xw != yw)
        dwarn(im, fps, fo->loc, "tessera's filters are square: xwidth %g is taken for ywidth %g too", xw, yw);
    f.filter_radius = xw;
    switch (t) {
    case 0:
        f.filter = TS_FILTER_BOX;
        break;
    case 1:
        f.filter = TS_FILTER_TRIANGLE;
        break;
    case 2: {
        f.filter = TS_FILTER_GAUSSIAN;
        float alpha;
        TRY(ts_pbrt_find_float(fps, "alpha", 2, &alpha, im->err));
        if (!(alpha > 0) || !isfinite(alpha))
            return ts_pbrt_param_error(fps, ts_pbrt_params_get(fps, "alpha"), im->err, TS_ERR_INVALID,
                                       "must be a positive number, got %g", alpha);
        f.filter_params.gaussian_alpha = alpha;
        break;
    }
    case 3: {
        f.filter = TS_FILTER_MITCHELL;
        float bv, cv;
        TRY(ts_pbrt_find_float(fps, "B", 1.0f / 3, &bv, im->err));
        TRY(ts_pbrt_find_float(fps, "C", 1.0f / 3, &cv, im->err));
        f.filter_params.mitchell_custom = true;
        f.filter_params.mitchell_b = bv;
        f.filter_params.mitchell_c = cv;
        break;
    }
    default: {
        float tau;
        TRY(ts_pbrt_find_float(fps, "tau", 3, &tau, im->err));
        f.filter = TS_FILTER_MITCHELL;
        dwarn(
            im, fps, fo->loc,
            "the windowed sinc filter is not supported: a Mitchell filter (B = C = 1/3) of the same width is "
            "used");
        break;
    }
    }
    warn_unused(im, fps);
    TRY(at(im, ts_scene_builder_set_film(im->b, &f, im->err), fps, fo->loc));
    *width = f.width;
    *height = f.height;
    if (im->doc) {
        cJSON *film = cJSON_CreateObject(), *filter = cJSON_CreateObject();
        bool ok = film && filter && ts_jw_number(film, "width", f.width) && ts_jw_number(film, "height", f.height) &&
                  ts_jw_string(filter, "type", ts_filter_type_name(f.filter)) &&
                  ts_jw_number(filter, "radius", f.filter_radius);
        if (ok && f.filter == TS_FILTER_GAUSSIAN)
            ok = ts_jw_number(filter, "alpha", f.filter_params.gaussian_alpha);
        if (ok && f.filter == TS_FILTER_MITCHELL)
            ok = ts_jw_number(filter, "b", f.filter_params.mitchell_b) &&
                 ts_jw_number(filter, "c", f.filter_params.mitchell_c);
        ok = ok && ts_jw_add(film, "filter", filter);
        if (!ok) cJSON_Delete(filter);
        filter = NULL;
        if (ok && (f.crop[0] != 0 || f.crop[1] != 1 || f.crop[2] != 0 || f.crop[3] != 1)) {
            double c[4] = {f.crop[0], f.crop[1], f.crop[2], f.crop[3]};
            ok = ts_jw_add(film, "crop", ts_jw_doubles(c, 4));
        }
        if (ok && f.scale != 1) ok = ts_jw_number(film, "scale", f.scale);
        if (ok && isfinite(f.max_sample_luminance))
            ok = ts_jw_number(film, "max_sample_luminance", f.max_sample_luminance);
        if (!ok || !ts_jw_add(im->doc, "film", film)) {
            if (!ok) cJSON_Delete(film);
            return nomem(im);
        }
    }
    return TS_OK;
}

static double col_len(const ts_mat4 *m, int j)
{
    return sqrt(m->m[0][j] * m->m[0][j] + m->m[1][j] * m->m[1][j] + m->m[2][j] * m->m[2][j]);
}

static ts_status map_camera(imp *im, uint32_t width, uint32_t height)
{
    ts_pbrt_option *o = &im->s->camera;
    ts_pbrt_params *ps = &o->params;
    bool persp = strcmp(o->type, "perspective") == 0;
    if (!persp && strcmp(o->type, "orthographic") != 0)
        return derr(im, ps, o->loc, TS_ERR_UNSUPPORTED,
                    "is not supported (perspective and orthographic are)");
    const ts_mat4 *c2w = &im->s->camera_to_world;
    ts_camera_desc d = {0};
    d.type = persp ? TS_CAMERA_PERSPECTIVE : TS_CAMERA_ORTHOGRAPHIC;
    /* pbrt-v3's camera space: x to the image's right, y up, z forward (left-handed). */
    ts_dvec3 origin = {c2w->m[0][3], c2w->m[1][3], c2w->m[2][3]};
    ts_dvec3 x = {c2w->m[0][0], c2w->m[1][0], c2w->m[2][0]};
    ts_dvec3 y = {c2w->m[0][1], c2w->m[1][1], c2w->m[2][1]};
    ts_dvec3 z = {c2w->m[0][2], c2w->m[1][2], c2w->m[2][2]};
    double lx = col_len(c2w, 0), ly = col_len(c2w, 1), lz = col_len(c2w, 2);
    if (!(lx > 0 && ly > 0 && lz > 0) || !isfinite(lx * ly * lz))
        return derr(im, ps, o->loc, TS_ERR_INVALID, "the camera transform is singular");
    double det =
        x.x * (y.y * z.z - y.z * z.y) - y.x * (x.y * z.z - x.z * z.y) + z.x * (x.y * y.z - x.z * y.y);
    d.from = (ts_vec3){(float)origin.x, (float)origin.y, (float)origin.z};
    d.to =
        (ts_vec3){(float)(origin.x + z.x / lz), (float)(origin.y + z.y / lz), (float)(origin.z + z.z / lz)};
    d.up = (ts_vec3){(float)(y.x / ly), (float)(y.y / ly), (float)(y.z / ly)};
    /* A right-handed camera-to-world frame maps pbrt-v3's left-handed camera space to a
     * mirrored image of tessera's from/to/up frame (camera.h). */
    d.mirror = det > 0;

    float frame = (float)width / (float)height, fov = 90, halffov = -1, lens = 0, focus = 1e6f;
    bool has_frame = ts_pbrt_params_get(ps, "frameaspectratio") != NULL;
    TRY(ts_pbrt_find_float(ps, "frameaspectratio", frame, &frame, im->err));
    if (!(frame > 0) || !isfinite(frame))
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "frameaspectratio"), im->err, TS_ERR_INVALID,
                                   "must be a positive number, got %g", frame);
    float win[4] = {-frame, frame, -1, 1};
    if (frame <= 1) win[0] = -1, win[1] = 1, win[2] = -1 / frame, win[3] = 1 / frame;
    const float *sw;
    size_t nsw;
    TRY(ts_pbrt_find_floats(ps, "screenwindow", &sw, &nsw, im->err));
    if (sw) {
        if (nsw != 4)
            return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "screenwindow"), im->err, TS_ERR_INVALID,
                                       "expects 4 values (x0 x1 y0 y1), got %zu", nsw);
        memcpy(win, sw, sizeof win);
    }
    TRY(ts_pbrt_find_float(ps, "lensradius", 0, &lens, im->err));
    TRY(ts_pbrt_find_float(ps, "focaldistance", 1e6f, &focus, im->err));
    if (persp) {
        TRY(ts_pbrt_find_float(ps, "fov", 90, &fov, im->err));
        TRY(ts_pbrt_find_float(ps, "halffov", -1, &halffov, im->err));
        if (halffov > 0) fov = 2 * halffov;
        if (!(fov > 0 && fov < 180))
            return derr(im, ps, o->loc, TS_ERR_INVALID, "\"float fov\" must be in (0, 180) degrees, got %g",
                        fov);
    }
    /* pbrt-v3's shutter (camera.cpp): a ray's time is lerp(u, open, close); a close before
     * the open is swapped with its error message. */
    float open, close;
    TRY(ts_pbrt_find_float(ps, "shutteropen", 0, &open, im->err));
    TRY(ts_pbrt_find_float(ps, "shutterclose", 1, &close, im->err));
    if (close < open) {
        /* The parameter given (an absent shutterclose is its default 1, after a later open). */
        ts_pbrt_param *cp = ts_pbrt_params_get(ps, "shutterclose");
        if (cp)
            pwarn(im, ps, cp, "%g is before shutteropen %g: the two are swapped, as pbrt-v3 does", close, open);
        else
            pwarn(im, ps, ts_pbrt_params_get(ps, "shutteropen"),
                  "%g is after shutterclose's default %g: the two are swapped, as pbrt-v3 does", open, close);
        float tmp = open;
        open = close, close = tmp;
    }
    d.shutter_open = open;
    d.shutter_close = close;
    if (im->s->camera_animated) {
        ts_xform start, end;
        if (!user_xform(c2w, &start)) return derr(im, ps, o->loc, TS_ERR_INVALID, "the camera transform is singular");
        TRY(motion_end(im, ps, o->loc, c2w, &im->s->camera_to_world_end, &end));
        d.moving = true;
        d.motion_start = start;
        d.motion_end = end;
        d.motion_t0 = im->s->transform_start_time;
        d.motion_t1 = im->s->transform_end_time;
    }
    warn_unused(im, ps);
    /* Camera-space lengths to world units: the window's axes against the view axis, the
     * lens along x and the focus along z. */
    double kx = persp ? lx / lz : lx, ky = persp ? ly / lz : ly;
    bool unit_axes = fabs(kx - 1) < 1e-6 && fabs(ky - 1) < 1e-6;
    d.fov_deg = fov;
    d.lens_radius = (float)(lens * lx);
    d.focus_distance = (float)(focus * lz);
    if (!persp || sw || has_frame || !unit_axes) {
        d.has_window = true;
        d.screen_window[0] = (float)(win[0] * kx), d.screen_window[1] = (float)(win[1] * kx);
        d.screen_window[2] = (float)(win[2] * ky), d.screen_window[3] = (float)(win[3] * ky);
    }
    TRY(at(im, ts_scene_builder_set_camera(im->b, &d, im->err), ps, o->loc));
    if (im->doc) {
        cJSON *cam = cJSON_CreateObject();
        bool ok = cam && ts_jw_string(cam, "type", persp ? "perspective" : "orthographic") &&
                  ts_jw_vec3(cam, "from", d.from) && ts_jw_vec3(cam, "to", d.to) && ts_jw_vec3(cam, "up", d.up) &&
                  (!persp || ts_jw_number(cam, "fov", d.fov_deg)) && ts_jw_number(cam, "lens_radius", d.lens_radius) &&
                  ts_jw_number(cam, "focus_distance", d.focus_distance);
        if (ok && d.mirror) ok = ts_jw_bool(cam, "mirror", true);
        if (ok && d.has_window) {
            double w[4] = {d.screen_window[0], d.screen_window[1], d.screen_window[2], d.screen_window[3]};
            ok = ts_jw_add(cam, "screen_window", ts_jw_doubles(w, 4));
        }
        if (ok && (d.shutter_open != 0 || d.shutter_close != 1)) { /* JSON's default is pbrt-v3's [0, 1] */
            double sh[2] = {d.shutter_open, d.shutter_close};
            ok = ts_jw_add(cam, "shutter", ts_jw_doubles(sh, 2));
        }
        if (ok && d.moving) {
            double times[2] = {d.motion_t0, d.motion_t1};
            cJSON *m = cJSON_CreateObject();
            ok = m && ts_jw_add(m, "times", ts_jw_doubles(times, 2)) && ts_jw_add(m, "start", ts_jw_transform(c2w)) &&
                 ts_jw_add(m, "end", ts_jw_transform(&im->s->camera_to_world_end));
            if (!ok || !ts_jw_add(cam, "motion", m)) {
                if (!ok) cJSON_Delete(m);
                ok = false;
            }
        }
        if (!ok || !ts_jw_add(im->doc, "camera", cam)) {
            if (!ok) cJSON_Delete(cam);
            return nomem(im);
        }
    }
    return TS_OK;
}

static ts_status map_sampler(imp *im)
{
    ts_pbrt_option *o = &im->s->sampler;
    ts_pbrt_params *ps = &o->params;
    static const char *const known[] = {"halton",         "sobol",      "random",     "02sequence",
                                        "lowdiscrepancy", "maxmindist", "stratified", NULL};
    bool ok = false;
    for (int k = 0; known[k]; k++)
        ok |= strcmp(o->type, known[k]) == 0;
    if (!ok)
        return derr(im, ps, o->loc, TS_ERR_UNSUPPORTED,
                    "is not a pbrt-v3 sampler (halton, sobol, random, 02sequence, maxmindist, stratified)");
    int32_t spp = 16;
    if (strcmp(o->type, "stratified") == 0) {
        int32_t xs, ys;
        bool jitter;
        TRY(ts_pbrt_find_int(ps, "xsamples", 4, &xs, im->err));
        TRY(ts_pbrt_find_int(ps, "ysamples", 4, &ys, im->err));
        TRY(ts_pbrt_find_bool(ps, "jitter", true, &jitter, im->err));
        if (xs < 1 || ys < 1 || (int64_t)xs * ys > INT32_MAX)
            return derr(im, ps, o->loc, TS_ERR_INVALID,
                        "xsamples × ysamples must be a positive count, got %d × %d", xs, ys);
        spp = xs * ys;
    } else {
        TRY(ts_pbrt_find_int(ps, "pixelsamples", 16, &spp, im->err));
        if (strcmp(o->type, "sobol") != 0 && o->loc.file)
            dwarn(im, ps, o->loc,
                  "is mapped to tessera's Owen-scrambled Sobol sampler with its pixelsamples (%d)", spp);
    }
    int32_t dims;
    TRY(ts_pbrt_find_int(ps, "dimensions", 4, &dims, im->err));
    if (spp < 1)
        return derr(im, ps, o->loc, TS_ERR_INVALID, "the sample count must be positive, got %d", spp);
    warn_unused(im, ps);
    ts_sampler smp = {TS_SAMPLER_SOBOL, 0};
    TRY(at(im, ts_scene_builder_set_sampler(im->b, &smp, (uint32_t)spp, im->err), ps, o->loc));
    if (im->doc) {
        cJSON *j = cJSON_CreateObject();
        if (!j || !ts_jw_string(j, "type", "sobol") || !ts_jw_number(j, "spp", spp) || !ts_jw_number(j, "seed", 0) ||
            !ts_jw_add(im->doc, "sampler", j)) {
            cJSON_Delete(j);
            return nomem(im);
        }
    }
    return TS_OK;
}

static ts_status map_integrator(imp *im)
{
    ts_pbrt_option *o = &im->s->integrator;
    ts_pbrt_params *ps = &o->params;
    ts_integrator_desc d = ts_integrator_desc_default();
    const char *t = o->type;
    bool path_like = strcmp(t, "path") == 0 || strcmp(t, "volpath") == 0;
    if (strcmp(t, "volpath") == 0) d.type = TS_INTEGRATOR_VOLPATH;
    if (!path_like && (strcmp(t, "bdpt") == 0 || strcmp(t, "mlt") == 0 || strcmp(t, "sppm") == 0)) {
        path_like = true;
        dwarn(im, ps, o->loc,
              "rendered with the path integrator: the estimator differs (the image converges to the same "
              "surface light transport%s)",
              ts_pbrt_media_used(im->s) ? ", without the scene's media: use volpath" : "");
        /* Their parameters are theirs; only the depth carries over. */
        for (size_t k = 0; k < ps->count; k++)
            if (strcmp(ps->items[k].name, "maxdepth") != 0) ps->items[k].used = true;
    }
    int32_t depth;
    if (path_like) {
        TRY(ts_pbrt_find_int(ps, "maxdepth", 5, &depth, im->err));
        float rr;
        TRY(ts_pbrt_find_float(ps, "rrthreshold", 1, &rr, im->err));
        if (rr != 1)
            pwarn(
                im, ps, ts_pbrt_params_get(ps, "rrthreshold"),
                "is not used: roulette starts below a throughput of 1 after 3 bounces (unbiased either way)");
        const char *strat;
        TRY(ts_pbrt_find_string(ps, "lightsamplestrategy", "spatial", &strat, im->err));
        if (strcmp(strat, "uniform") == 0)
            d.light_sampling = TS_LIGHT_SELECT_UNIFORM;
        else if (strcmp(strat, "spatial") == 0)
            d.light_sampling = TS_LIGHT_SELECT_SPATIAL;
        else if (strcmp(strat, "power") != 0)
            return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "lightsamplestrategy"), im->err,
                                       TS_ERR_INVALID, "must be uniform, power or spatial, got \"%s\"",
                                       strat);
        if (depth < 0 || depth > TS_PATH_DEPTH_MAX)
            return derr(im, ps, o->loc, TS_ERR_INVALID, "\"integer maxdepth\" must be in [0, %d], got %d",
                        TS_PATH_DEPTH_MAX, depth);
        d.max_depth = depth;
    } else if (strcmp(t, "directlighting") == 0 || strcmp(t, "whitted") == 0) {
        d.type = TS_INTEGRATOR_DIRECT;
        TRY(ts_pbrt_find_int(ps, "maxdepth", 5, &depth, im->err));
        const char *strat = "all";
        if (t[0] == 'd')
            TRY(ts_pbrt_find_string(ps, "strategy", "all", &strat, im->err));
        else
            dwarn(im, ps, o->loc,
                  "rendered by the direct-lighting integrator (each light sampled once, specular "
                  "paths followed): Whitted's estimate");
        if (strcmp(strat, "one") == 0) {
            /* pbrt-v3's DirectLightingIntegrator calls UniformSampleOneLight without a
             * light distribution: every light equally likely. */
            d.strategy = TS_LIGHTS_ONE;
            d.light_sampling = TS_LIGHT_SELECT_UNIFORM;
        } else if (strcmp(strat, "all") != 0)
            return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "strategy"), im->err, TS_ERR_INVALID,
                                       "must be all or one, got \"%s\"", strat);
        if (depth < 0 || depth > TS_DIRECT_DEPTH_MAX)
            return derr(im, ps, o->loc, TS_ERR_INVALID, "\"integer maxdepth\" must be in [0, %d], got %d",
                        TS_DIRECT_DEPTH_MAX, depth);
        d.max_depth = depth;
        im->direct_all = d.strategy == TS_LIGHTS_ALL;
    } else {
        return derr(
            im, ps, o->loc, TS_ERR_UNSUPPORTED,
            "is not supported (path, volpath, directlighting and whitted are; bdpt, mlt and sppm render "
            "with path)");
    }
    const int32_t *pb;
    size_t npb;
    TRY(ts_pbrt_find_ints(ps, "pixelbounds", &pb, &npb, im->err));
    if (pb) pwarn(im, ps, ts_pbrt_params_get(ps, "pixelbounds"), "is not used: the film's cropwindow is");
    warn_unused(im, ps);
    TRY(at(im, ts_scene_builder_set_integrator(im->b, &d, im->err), ps, o->loc));
    if (im->doc) {
        cJSON *j = cJSON_CreateObject();
        bool ok = j && ts_jw_string(j, "type", ts_integrator_name(d.type)) && ts_jw_number(j, "max_depth", d.max_depth);
        if (ok && (d.type == TS_INTEGRATOR_PATH || d.type == TS_INTEGRATOR_VOLPATH))
            ok = ts_jw_number(j, "rr_depth", d.rr_depth) &&
                 ts_jw_string(j, "light_sampling",
                         d.light_sampling == TS_LIGHT_SELECT_UNIFORM   ? "uniform"
                         : d.light_sampling == TS_LIGHT_SELECT_SPATIAL ? "spatial"
                                                                       : "power");
        if (ok && d.type == TS_INTEGRATOR_DIRECT)
            ok = ts_jw_string(j, "strategy", d.strategy == TS_LIGHTS_ONE ? "one" : "all") &&
                 (d.strategy != TS_LIGHTS_ONE ||
                  ts_jw_string(j, "light_sampling", d.light_sampling == TS_LIGHT_SELECT_UNIFORM ? "uniform" : "power"));
        if (!ok || !ts_jw_add(im->doc, "integrator", j)) {
            if (!ok) cJSON_Delete(j);
            return nomem(im);
        }
    }
    return TS_OK;
}

/* ---------------------------------------------------------------- materials */

/* The roughness parameters of a microfacet material into m as pbrt-v3 reads them:
 * "roughness" (def; not read when !plain, pbrt-v3's glass and substrate have none), and
 * when uv, "uroughness" and "vroughness" each defaulting to it (pbrt-v3's metal, glass,
 * uber, substrate; substrate's and glass's default to def). Each may be a float texture;
 * remaproughness (true by default) becomes the builder's remap_roughness, so a textured
 * roughness is remapped where it is evaluated. uroughness ≠ vroughness makes the
 * material anisotropic (has_vroughness), which the builder takes on every type with uv. */
/* v_follows_u: a missing vroughness takes uroughness's value (pbrt-v3's UberMaterial:
 * roughv = roughu), not roughness's (its MetalMaterial). */
static ts_status get_roughness(imp *im, ts_pbrt_params *ps, ts_pbrt_loc loc, float def, bool plain, bool uv,
                               bool v_follows_u, ts_material *m)
{
    ts_material_float r = ts_material_float_const(def), u, v;
    if (plain) TRY(get_mfloat(im, ps, "roughness", def, &r));
    u = v = r;
    if (uv) {
        if (ts_pbrt_params_get(ps, "uroughness")) TRY(get_mfloat(im, ps, "uroughness", def, &u));
        if (ts_pbrt_params_get(ps, "vroughness")) TRY(get_mfloat(im, ps, "vroughness", def, &v));
        else if (v_follows_u) v = u;
    }
    TRY(ts_pbrt_find_bool(ps, "remaproughness", true, &m->remap_roughness, im->err));
    const ts_material_float *both[2] = {&u, &v};
    for (int k = 0; k < 2; k++)
        if (!both[k]->tex && !(both[k]->value >= 0 && isfinite(both[k]->value)))
            return derr(im, ps, loc, TS_ERR_INVALID, "roughness must be a finite number ≥ 0, got %g",
                        both[k]->value);
    bool differ = u.tex != v.tex || u.value != v.value;
    m->roughness = u;
    m->has_vroughness = differ;
    m->vroughness = differ ? v : u;
    return TS_OK;
}

static ts_status material_id(imp *im, int32_t mi, uint32_t *id, bool *no_surface);

/* pbrt-v3's "texture bumpmap" (a float texture of displacement) as the builder's bump.
 * A "constant" displacement moves every point alike, so its gradient, the only thing
 * Material::Bump uses with dn/du taken as 0 (docs/design.md), is 0: no bump map. */
static ts_status get_bump(imp *im, ts_pbrt_params *ps, ts_material *m)
{
    ts_pbrt_param *p = ts_pbrt_params_get(ps, "bumpmap");
    if (!p) return TS_OK;
    if (p->type != TS_PBRT_PARAM_TEXTURE)
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID, "expects a float texture (\"texture bumpmap\")");
    if (p->texture_float < 0)
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID, "names no float texture \"%s\" in scope",
                                   p->strings[0]);
    if (strcmp(im->s->textures[p->texture_float].class_name, "constant") == 0) {
        float unused;
        return constant_texture(im, ps, p, true, &unused, NULL);
    }
    m->bump = im->tp.textures[p->texture_float];
    return TS_OK;
}

/* One row of m's type's description (materials/material_desc.h) as pbrt-v3 reads it: its
 * pbrt-v3 name and default (v1's default where pbrt-v3 has no such parameter). */
static ts_status get_material_param(imp *im, ts_pbrt_params *ps, const ts_material_param *p, ts_material *m)
{
    switch (p->kind) {
    case TS_MPARAM_RGB: {
        ts_rgb def = ts_rgb_gray(p->pbrt3 ? p->pbrt3_def : p->def);
        if (p->pbrt3_def_rgb) p->pbrt3_def_rgb(&def);
        if (!p->pbrt3) {
            *ts_mparam_rgb(m, p) = ts_material_rgb_const(def);
            return TS_OK;
        }
        ts_pbrt_param *pp = ts_pbrt_params_get(ps, p->pbrt3);
        if ((p->flags & TS_MPARAM_PBRT3_FLOAT_GREY) && pp && pp->type == TS_PBRT_PARAM_FLOAT) {
            /* pbrt-v3 reads only a spectrum here (it would leave a float unused at its
             * default); a float is taken as the grey it means (docs/pbrt-v3.md). */
            float g;
            TRY(get_float(im, ps, p->pbrt3, p->pbrt3_def, &g));
            *ts_mparam_rgb(m, p) = ts_material_rgb_gray(g);
            return TS_OK;
        }
        return get_mrgb(im, ps, p->pbrt3, def, ts_mparam_rgb(m, p));
    }
    case TS_MPARAM_FLOAT: {
        float def = p->pbrt3 ? p->pbrt3_def : p->def;
        if (!p->pbrt3) {
            *ts_mparam_float(m, p) = ts_material_float_const(def);
            return TS_OK;
        }
        /* pbrt-v3's glass and uber: "float index", overridden by "eta" (a texture or not). */
        if (p->flags & TS_MPARAM_PBRT3_INDEX) TRY(get_float(im, ps, "index", def, &def));
        return get_mfloat(im, ps, p->pbrt3, def, ts_mparam_float(m, p));
    }
    case TS_MPARAM_ENUM: *ts_mparam_enum(m, p) = (int)p->def; return TS_OK; /* no pbrt-v3 name: v1's default */
    }
    return TS_OK;
}

/* pbrt-v3's MixMaterial's namedmaterial1/2: the parser resolved both names when the mix
 * was defined, so they are earlier materials and mapping them first cannot loop. */
static ts_status get_mix_materials(imp *im, int32_t mi, ts_pbrt_params *ps, ts_pbrt_loc loc, ts_material *m)
{
    static const char *const keys[2] = {"namedmaterial1", "namedmaterial2"};
    for (int k = 0; k < 2; k++) {
        int32_t sub = im->s->materials[mi].mix[k];
        ts_pbrt_param *kp = ts_pbrt_params_get(ps, keys[k]);
        if (sub < 0 || sub >= mi)
            return derr(im, ps, loc, TS_ERR_INVALID, "\"string %s\" names no earlier material", keys[k]);
        bool none = false;
        TRY(material_id(im, sub, &m->mix_id[k], &none));
        if (none)
            return ts_pbrt_param_error(ps, kp, im->err, TS_ERR_UNSUPPORTED,
                                       "names material \"%s\" of type \"%s\" (no surface), which cannot be mixed",
                                       kp->strings[0], im->s->materials[sub].type);
    }
    return TS_OK;
}

/* The tessera material for pbrt-v3 material index mi (-1: the default matte); *no_surface
 * for type "" / "none". The type is the one whose description names this pbrt-v3 material
 * (materials/material_desc.h), read row by row; its flags say what else pbrt-v3 reads. */
static ts_status make_material(imp *im, int32_t mi, ts_material *m, bool *no_surface, const char **json_type)
{
    static ts_pbrt_params default_params = {.directive = "Material", .directive_arg = "matte"};
    ts_pbrt_params *ps = mi >= 0 ? &im->s->materials[mi].params : &default_params;
    ts_pbrt_loc loc = mi >= 0 ? im->s->materials[mi].loc : (ts_pbrt_loc){0};
    const char *type = mi >= 0 ? im->s->materials[mi].type : "matte";
    *m = (ts_material){0};
    m->texture_clamp_nonneg = true; /* pbrt-v3's textured colours: clamped at 0 only (material.h) */
    *no_surface = false;
    if (type[0] == 0 || strcmp(type, "none") == 0) {
        *no_surface = true;
        return TS_OK;
    }
    /* pbrt-v3's MixMaterial reads no bumpmap (its materials' own apply): left unused, warned. */
    if (strcmp(type, "mix") != 0) TRY(get_bump(im, ps, m));
    if (strcmp(type, "disney") == 0 || strcmp(type, "subsurface") == 0 || strcmp(type, "kdsubsurface") == 0 ||
        strcmp(type, "hair") == 0)
        return derr(im, ps, loc, TS_ERR_UNSUPPORTED, "is not supported (%s)",
                    type[0] == 'd'   ? "the Disney BSDF is not implemented"
                    : type[0] == 'h' ? "hair is not implemented"
                                     : "subsurface scattering needs media, which tessera does not render");
    const ts_material_desc *d = ts_material_desc_by_pbrt3(type);
    if (!d) return derr(im, ps, loc, TS_ERR_UNSUPPORTED, "is not a pbrt-v3 material");
    m->type = d->type;
    *json_type = d->name;
    for (int i = 0; i < d->n_params; i++)
        TRY(get_material_param(im, ps, &d->params[i], m));
    if (d->flags & TS_MDESC_ROUGH)
        TRY(get_roughness(im, ps, loc, d->rough_def, (d->flags & TS_MDESC_PBRT3_ROUGH) != 0,
                          (d->flags & TS_MDESC_ANISO) != 0, (d->flags & TS_MDESC_PBRT3_V_FOLLOWS_U) != 0, m));
    if (d->flags & TS_MDESC_FILE) {
        const char *file;
        TRY(ts_pbrt_find_string(ps, "bsdffile", NULL, &file, im->err));
        if (!file) return derr(im, ps, loc, TS_ERR_INVALID, "\"string bsdffile\" is required");
        TRY(at(im, ts_scene_builder_load_fourier(im->b, file, &m->fourier, im->err), ps,
               ts_pbrt_params_get(ps, "bsdffile")->loc));
    }
    if (d->flags & TS_MDESC_MIX) TRY(get_mix_materials(im, mi, ps, loc, m));
    return TS_OK;
}

/* The name material mi is added to the builder (and the JSON document) under. */
static void material_name(imp *im, int32_t mi, char *name, size_t size)
{
    if (mi >= 0 && im->s->materials[mi].name)
        snprintf(name, size, "%.200s#%d", im->s->materials[mi].name, (int)mi);
    else if (mi >= 0)
        snprintf(name, size, "%s#%d", im->s->materials[mi].type, (int)mi);
    else
        snprintf(name, size, "default-matte");
}

/* A material parameter as v1 has it: the name of its texture, else its constant. */
static ts_status jparam(imp *im, cJSON *j, const char *mname, const char *key, const struct ts_texture *tex,
                        cJSON *constant)
{
    if (tex) {
        cJSON_Delete(constant);
        char hint[400];
        snprintf(hint, sizeof hint, "%.300s.%s", mname, key);
        constant = ts_json_texture_ref(&im->jtex, tex, hint, im->err);
        if (!constant) return im->err->status;
    }
    return ts_jw_add(j, key, constant) ? TS_OK : nomem(im);
}

static cJSON *jrgb_item(ts_rgb c)
{
    const double v[3] = {c.r, c.g, c.b};
    return ts_jw_doubles(v, 3);
}

static ts_status jmrgb(imp *im, cJSON *j, const char *mname, const char *key, const ts_material_rgb *p)
{
    return jparam(im, j, mname, key, p->tex, p->tex ? NULL : jrgb_item(p->value));
}

static ts_status jmfloat(imp *im, cJSON *j, const char *mname, const char *key, const ts_material_float *p)
{
    return jparam(im, j, mname, key, p->tex, p->tex ? NULL : cJSON_CreateNumber(p->value));
}

/* Roughness as scene format v1 has it: the values as pbrt-v3 gives them, remap_roughness
 * explicit (v1's default is false, pbrt-v3's true). */
static ts_status jroughness(imp *im, cJSON *j, const char *mname, const ts_material *m)
{
    TRY(jmfloat(im, j, mname, "roughness", &m->roughness));
    if (!cJSON_AddBoolToObject(j, "remap_roughness", m->remap_roughness)) return nomem(im);
    return m->has_vroughness ? jmfloat(im, j, mname, "vroughness", &m->vroughness) : TS_OK;
}

/* m as scene format v1 has it: its type's rows in the description's order (materials/
 * material_desc.h), the roughness family after them, then the enums. */
static ts_status json_material_fill(imp *im, cJSON *j, int32_t mi, const char *name, const char *type,
                                    const ts_material *m)
{
    const ts_material_desc *d = ts_material_desc_of(m->type);
    if (!ts_jw_string(j, "type", type)) return nomem(im);
    if (m->texture_clamp_nonneg && ts_material_uses_textures(m) && !ts_jw_string(j, "texture_clamp", "nonnegative"))
        return nomem(im);
    if (m->bump) TRY(jparam(im, j, name, "bumpmap", m->bump, NULL));
    if (d->flags & TS_MDESC_MIX) {
        cJSON *list = cJSON_CreateArray();
        if (!ts_jw_add(j, "materials", list)) return nomem(im); /* jadd frees list when it fails */
        for (int k = 0; k < 2; k++) {
            char sub[300];
            material_name(im, im->s->materials[mi].mix[k], sub, sizeof sub);
            cJSON *s = cJSON_CreateString(sub);
            if (!s || !cJSON_AddItemToArray(list, s)) {
                cJSON_Delete(s);
                return nomem(im);
            }
        }
    }
    for (int i = 0; i < d->n_params; i++) {
        const ts_material_param *p = &d->params[i];
        if (p->kind == TS_MPARAM_RGB) TRY(jmrgb(im, j, name, p->key, ts_mparam_crgb(m, p)));
        const ts_material_float *f = ts_mparam_cfloat(m, p);
        if (p->kind == TS_MPARAM_FLOAT && (f->tex || f->value != 0 || !(p->flags & TS_MPARAM_OMIT_ZERO)))
            TRY(jmfloat(im, j, name, p->key, f));
    }
    if (d->flags & TS_MDESC_ROUGH) TRY(jroughness(im, j, name, m));
    for (int i = 0; i < d->n_params; i++) {
        const ts_material_param *p = &d->params[i];
        int v = *(const int *)(const void *)((const char *)m + p->offset);
        if (p->kind == TS_MPARAM_ENUM && !ts_jw_string(j, p->key, p->names[v])) return nomem(im);
    }
    return TS_OK; /* a file (fourier) is added by the caller */
}

static ts_status json_material(imp *im, int32_t mi, const char *name, const char *type, const ts_material *m)
{
    cJSON *j = cJSON_CreateObject();
    if (!j) return nomem(im);
    ts_status st = json_material_fill(im, j, mi, name, type, m);
    if (!st && !ts_jw_add(im->jmaterials, name, j)) return nomem(im); /* jadd frees j */
    if (st) cJSON_Delete(j);
    return st;
}

/* The builder id of material mi (mapped on first use), or TS_NONE with *no_surface. */
static ts_status material_id(imp *im, int32_t mi, uint32_t *id, bool *no_surface)
{
    size_t slot = mi >= 0 ? (size_t)mi : im->s->material_count;
    *no_surface = false;
    if (im->mat_state[slot] == MAT_NO_SURFACE) {
        *no_surface = true;
        *id = TS_NONE;
        return TS_OK;
    }
    if (im->mat_state[slot] == MAT_MAPPED) {
        *id = im->mat_id[slot];
        return TS_OK;
    }
    ts_material m;
    const char *jtype = NULL;
    TRY(make_material(im, mi, &m, no_surface, &jtype));
    if (*no_surface) {
        im->mat_state[slot] = MAT_NO_SURFACE;
        *id = TS_NONE;
        return TS_OK;
    }
    char name[300];
    material_name(im, mi, name, sizeof name);
    ts_pbrt_params *ps = mi >= 0 ? &im->s->materials[mi].params : NULL;
    ts_pbrt_loc loc = mi >= 0 ? im->s->materials[mi].loc : (ts_pbrt_loc){0};
    if (ps) {
        ts_status st = ts_scene_builder_add_material(im->b, name, &m, id, im->err);
        if (st) return at(im, st, ps, loc);
    } else {
        TRY(ts_scene_builder_add_material(im->b, name, &m, id, im->err));
    }
    if (im->doc) {
        TRY(json_material(im, mi, name, jtype, &m));
        if (m.type == TS_MATERIAL_FOURIER) {
            const char *file = NULL;
            ts_pbrt_find_string(ps, "bsdffile", NULL, &file, im->err);
            if (!ts_jw_string(cJSON_GetObjectItemCaseSensitive(im->jmaterials, name), "file", file))
                return nomem(im);
        }
    }
    im->mat_state[slot] = MAT_MAPPED;
    im->mat_id[slot] = *id;
    return TS_OK;
}

/* ---------------------------------------------------------------- shapes */

/* pbrt-v3's facing: with shading normals a triangle's geometric normal is turned toward
 * them (Faceforward), else it follows the winding, flipped by ReverseOrientation. The
 * builder keeps each triangle's object-space winding (scene_builder.h), so the winding is
 * set here: toward the sum of the vertex normals, or reversed. */
static void orient_mesh(ts_mesh_data *md, bool reverse)
{
    for (uint32_t t = 0; t < md->n_triangles; t++) {
        uint32_t *ix = &md->index[3 * t];
        bool flip = reverse;
        if (md->n) {
            const float *p0 = &md->p[3 * ix[0]], *p1 = &md->p[3 * ix[1]], *p2 = &md->p[3 * ix[2]];
            double e1[3], e2[3], ns[3];
            for (int k = 0; k < 3; k++) {
                e1[k] = (double)p1[k] - p0[k];
                e2[k] = (double)p2[k] - p0[k];
                ns[k] = (double)md->n[3 * ix[0] + k] + md->n[3 * ix[1] + k] + md->n[3 * ix[2] + k];
            }
            double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                           e1[0] * e2[1] - e1[1] * e2[0]};
            flip = c[0] * ns[0] + c[1] * ns[1] + c[2] * ns[2] < 0;
        }
        if (flip) {
            uint32_t k = ix[1];
            ix[1] = ix[2];
            ix[2] = k;
        }
    }
}

/* A trianglemesh's arrays, checked as pbrt-v3 checks them, into malloc'd *md. */
static ts_status read_trianglemesh(imp *im, ts_pbrt_shape *sh, ts_mesh_data *md)
{
    ts_pbrt_params *ps = &sh->params;
    const float *P, *N, *uv = NULL;
    const int32_t *idx;
    size_t np, nn, ni, nuv = 0;
    TRY(ts_pbrt_find_point3s(ps, "P", &P, &np, im->err));
    TRY(ts_pbrt_find_ints(ps, "indices", &idx, &ni, im->err));
    TRY(ts_pbrt_find_normal3s(ps, "N", &N, &nn, im->err));
    if (!P) return derr(im, ps, sh->loc, TS_ERR_INVALID, "\"point3 P\" is required");
    static const int32_t three[3] = {0, 1, 2};
    if (!idx) {
        if (np != 3) return derr(im, ps, sh->loc, TS_ERR_INVALID, "\"integer indices\" is required");
        idx = three, ni = 3;
    }
    if (ni % 3 != 0)
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "indices"), im->err, TS_ERR_INVALID,
                                   "expects a multiple of 3 values, got %zu", ni);
    if (np > UINT32_MAX || ni / 3 > UINT32_MAX)
        return derr(im, ps, sh->loc, TS_ERR_LIMIT, "the mesh is too large");
    for (size_t k = 0; k < ni; k++)
        if (idx[k] < 0 || (size_t)idx[k] >= np)
            return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "indices"), im->err, TS_ERR_INVALID,
                                       "value %zu is %d, not a vertex index in [0, %zu]", k, idx[k], np - 1);
    const char *uvname = NULL;
    static const char *const uvnames[] = {"uv", "st"};
    for (int k = 0; k < 2 && !uvname; k++) {
        ts_pbrt_param *p = ts_pbrt_params_get(ps, uvnames[k]);
        if (!p) continue;
        uvname = uvnames[k];
        if (p->type == TS_PBRT_PARAM_FLOAT) {
            TRY(ts_pbrt_find_floats(ps, uvname, &uv, &nuv, im->err));
        } else {
            TRY(ts_pbrt_find_point2s(ps, uvname, &uv, &nuv, im->err));
            nuv *= 2;
        }
        if (nuv != 2 * np) {
            pwarn(im, ps, p, "holds %zu numbers, not 2 per vertex (%zu): the mesh has no uv", nuv, 2 * np);
            uv = NULL;
        }
    }
    if (N && nn != np) {
        pwarn(im, ps, ts_pbrt_params_get(ps, "N"),
              "holds %zu normals for %zu vertices: the mesh has no normals", nn, np);
        N = NULL;
    }
    if (N)
        for (size_t k = 0; k < np; k++)
            if (!(N[3 * k] != 0 || N[3 * k + 1] != 0 || N[3 * k + 2] != 0)) {
                pwarn(im, ps, ts_pbrt_params_get(ps, "N"), "normal %zu is zero: the mesh has no normals", k);
                N = NULL;
                break;
            }
    ts_pbrt_param *S = ts_pbrt_params_get(ps, "S");
    if (S) pwarn(im, ps, S, "is not used: shading tangents come from the normals and uv");
    md->n_vertices = (uint32_t)np;
    md->n_triangles = (uint32_t)(ni / 3);
    md->p = malloc(np * 3 * sizeof(float));
    md->index = malloc(ni * sizeof(uint32_t));
    if (N) md->n = malloc(np * 3 * sizeof(float));
    if (uv) md->uv = malloc(np * 2 * sizeof(float));
    if (!md->p || !md->index || (N && !md->n) || (uv && !md->uv)) return nomem(im);
    memcpy(md->p, P, np * 3 * sizeof(float));
    for (size_t k = 0; k < ni; k++)
        md->index[k] = (uint32_t)idx[k];
    if (N) memcpy(md->n, N, np * 3 * sizeof(float));
    if (uv) memcpy(md->uv, uv, np * 2 * sizeof(float));
    return TS_OK;
}

/* pbrt-v3's loopsubdiv: the control mesh's P and indices refined `levels` (3; `nlevels`
 * too) times by the builder (mesh_subdiv.h) into *md, with its limit normals. pbrt-v3's
 * limit normals point to the back of the control mesh's winding and its triangles face
 * their normals whatever ReverseOrientation says, so the surface faces away from the
 * control winding: the normals are negated here and orient_mesh turns the triangles to
 * them. */
static ts_status read_loopsubdiv(imp *im, ts_pbrt_shape *sh, ts_mesh_data *md)
{
    ts_pbrt_params *ps = &sh->params;
    const float *P;
    const int32_t *idx;
    size_t np, ni;
    int32_t levels;
    TRY(ts_pbrt_find_point3s(ps, "P", &P, &np, im->err));
    TRY(ts_pbrt_find_ints(ps, "indices", &idx, &ni, im->err));
    TRY(ts_pbrt_find_int(ps, "nlevels", 3, &levels, im->err));
    TRY(ts_pbrt_find_int(ps, "levels", levels, &levels, im->err));
    if (!P || !idx)
        return derr(im, ps, sh->loc, TS_ERR_INVALID, "\"point3 P\" and \"integer indices\" are required");
    if (ni % 3 != 0 || ni == 0)
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "indices"), im->err, TS_ERR_INVALID,
                                   "expects a positive multiple of 3 values, got %zu", ni);
    if (levels < 0 || levels > TS_SUBDIV_MAX_LEVELS)
        return derr(im, ps, sh->loc, TS_ERR_INVALID, "\"integer levels\" must be in [0, %d], got %d",
                    TS_SUBDIV_MAX_LEVELS, levels);
    if (np > UINT32_MAX || ni / 3 > UINT32_MAX)
        return derr(im, ps, sh->loc, TS_ERR_LIMIT, "the mesh is too large");
    for (size_t k = 0; k < ni; k++)
        if (idx[k] < 0 || (size_t)idx[k] >= np)
            return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "indices"), im->err, TS_ERR_INVALID,
                                       "value %zu is %d, not a vertex index in [0, %zu]", k, idx[k], np - 1);
    uint32_t *index = malloc(ni * sizeof *index);
    if (!index) return nomem(im);
    for (size_t k = 0; k < ni; k++)
        index[k] = (uint32_t)idx[k];
    ts_mesh control = {(uint32_t)np, (uint32_t)(ni / 3), P, NULL, NULL, index};
    ts_status st =
        at(im, ts_scene_builder_loop_subdivide(im->b, &control, (uint32_t)levels, md, im->err), ps, sh->loc);
    free(index);
    if (st) return st;
    if (md->n)
        for (size_t k = 0; k < 3 * (size_t)md->n_vertices; k++)
            md->n[k] = -md->n[k];
    return TS_OK;
}


/* A mesh's alpha cut-out texture as the builder takes it (scene_builder.h): NULL for
 * opaque; zero: the constant 0 (written to JSON as the number 0). */
typedef struct cutout {
    const ts_texture *tex;
    bool zero;
} cutout;

/* pbrt-v3's "alpha" / "shadowalpha" of a trianglemesh or plymesh (CreateTriangleMeshShape):
 * a "texture" naming a float texture in scope, or a "float" value, which pbrt-v3 makes a
 * cut-out only when it is 0 (any other value leaves the mesh opaque; a value in (0, 1) is
 * warned, as pbrt-v3 cuts out only where alpha is exactly 0). A "constant" texture is read
 * as its value. Refused, where pbrt-v3 prints an error and goes on opaque: a name that is
 * no float texture in scope (a spectrum texture's name said so), another parameter type,
 * and a value outside [0, 1]. */
static ts_status get_cutout(imp *im, ts_pbrt_params *ps, const char *name, cutout *out)
{
    *out = (cutout){0};
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    if (!p) return TS_OK;
    float v;
    if (p->type == TS_PBRT_PARAM_TEXTURE) {
        if (p->texture_float < 0 && p->texture_spectrum >= 0)
            return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID,
                                       "names the spectrum texture \"%s\": %s takes a float texture", p->strings[0],
                                       name);
        if (p->texture_float < 0)
            return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID, "names no float texture \"%s\" in scope",
                                       p->strings[0]);
        if (strcmp(im->s->textures[p->texture_float].class_name, "constant") != 0) {
            out->tex = im->tp.textures[p->texture_float];
            return TS_OK;
        }
        TRY(constant_texture(im, ps, p, true, &v, NULL));
    } else if (p->type == TS_PBRT_PARAM_FLOAT) {
        TRY(ts_pbrt_find_float(ps, name, 1, &v, im->err));
    } else {
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID,
                                   "expects a float in [0, 1] or a float texture (\"texture %s\")", name);
    }
    if (!(v >= 0 && v <= 1))
        return ts_pbrt_param_error(ps, p, im->err, TS_ERR_INVALID, "must be in [0, 1], got %g", v);
    if (v > 0) {
        if (v < 1)
            pwarn(im, ps, p, "is %g: pbrt-v3 cuts out only where %s is exactly 0, so the mesh is opaque", v, name);
        return TS_OK;
    }
    ts_texture zero = ts_texture_constant_float(0);
    TRY(at(im, ts_scene_builder_add_texture(im->b, &zero, &out->tex, im->err), ps, p->loc));
    out->zero = true;
    return TS_OK;
}

/* A cut-out as v1 has it (docs/design.md §4): 0, or the name of its texture; nothing when
 * opaque. */
static ts_status jcutout(imp *im, cJSON *j, const char *key, const cutout *c)
{
    if (!c->tex) return TS_OK;
    if (c->zero) return cJSON_AddNumberToObject(j, key, 0) ? TS_OK : nomem(im);
    char hint[64];
    snprintf(hint, sizeof hint, "%s", key);
    cJSON *ref = ts_json_texture_ref(&im->jtex, c->tex, hint, im->err);
    if (!ref) return im->err->status;
    return ts_jw_add(j, key, ref) ? TS_OK : nomem(im);
}

/* The index of s in the NULL-terminated names, or −1. */
static int name_index(const char *s, const char *const *names)
{
    for (int k = 0; names[k]; k++)
        if (strcmp(s, names[k]) == 0) return k;
    return -1;
}

/* pbrt-v3's "curve" (CreateCurveShape, geometry/curve.h) into d and, converting, its
 * document j. pbrt-v3's refusals (degree, basis, the control-point count for the basis, a
 * ribbon's normals) are errors at the parameter; where pbrt-v3 warns and goes on, so does
 * this: normals on another kind are dropped, an unknown type is a cylinder. *skip: one
 * Bézier point, no segment (pbrt-v3 draws nothing; warned). splitdepth is read and
 * checked but does not change the image: Embree's tessellation follows pbrt-v3's
 * flatness rule instead (curve.h). */
static ts_status read_curve(imp *im, ts_pbrt_shape *sh, ts_shape_desc *d, cJSON *j, bool *skip)
{
    ts_pbrt_params *ps = &sh->params;
    *skip = false;
    float width, w[2];
    int32_t degree;
    TRY(ts_pbrt_find_float(ps, "width", 1, &width, im->err));
    TRY(ts_pbrt_find_float(ps, "width0", width, &w[0], im->err));
    TRY(ts_pbrt_find_float(ps, "width1", width, &w[1], im->err));
    for (int k = 0; k < 2; k++) {
        if (w[k] > 0 && isfinite(w[k])) continue;
        const char *names[3] = {k ? "width1" : "width0", "width", k ? "width1" : "width0"};
        ts_pbrt_param *wp = ts_pbrt_params_get(ps, names[0]);
        if (!wp) wp = ts_pbrt_params_get(ps, names[1]);
        return ts_pbrt_param_error(ps, wp, im->err, TS_ERR_INVALID,
                                   "must be a positive finite number, got %g (pbrt-v3 draws nothing or misbounds "
                                   "the curve)",
                                   w[k]);
    }
    TRY(ts_pbrt_find_int(ps, "degree", 3, &degree, im->err));
    if (degree != 2 && degree != 3)
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "degree"), im->err, TS_ERR_INVALID,
                                   "is %d: only degree 2 and 3 curves are supported (as pbrt-v3)", (int)degree);
    static const char *const bases[] = {"bezier", "bspline", NULL}, *const kinds[] = {"flat", "ribbon", "cylinder", NULL};
    const char *basis_name, *kind_name;
    TRY(ts_pbrt_find_string(ps, "basis", "bezier", &basis_name, im->err));
    TRY(ts_pbrt_find_string(ps, "type", "flat", &kind_name, im->err));
    int basis = name_index(basis_name, bases), kind = name_index(kind_name, kinds);
    if (basis < 0)
        return ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "basis"), im->err, TS_ERR_INVALID,
                                   "is \"%s\": only \"bezier\" and \"bspline\" are supported (as pbrt-v3)",
                                   basis_name);
    const float *P;
    size_t np;
    TRY(ts_pbrt_find_point3s(ps, "P", &P, &np, im->err));
    ts_pbrt_param *pp = ts_pbrt_params_get(ps, "P");
    uint32_t nseg;
    if (!P || !ts_curve_segment_count(basis, degree, np, &nseg)) {
        if (!pp)
            return derr(im, ps, sh->loc, TS_ERR_INVALID, "\"point3 P\" (the control points) is required");
        if (basis == TS_CURVE_BEZIER)
            return ts_pbrt_param_error(ps, pp, im->err, TS_ERR_INVALID,
                                       "has %zu control points: for the degree %d Bézier basis %d + n * %d are "
                                       "required, for n >= 0 (as pbrt-v3)",
                                       np, (int)degree, (int)degree + 1, (int)degree);
        return ts_pbrt_param_error(ps, pp, im->err, TS_ERR_INVALID,
                                   "has %zu control points: the degree %d b-spline basis needs at least %d (as "
                                   "pbrt-v3)",
                                   np, (int)degree, (int)degree + 1);
    }
    if (kind < 0) {
        pwarn(im, ps, ts_pbrt_params_get(ps, "type"),
              "is \"%s\", not a curve type (flat, ribbon, cylinder): a \"cylinder\" curve, as pbrt-v3 makes it",
              kind_name);
        kind = TS_CURVE_CYLINDER;
    }
    const float *N;
    size_t nn;
    TRY(ts_pbrt_find_normal3s(ps, "N", &N, &nn, im->err));
    ts_pbrt_param *npar = ts_pbrt_params_get(ps, "N");
    if (N && kind != TS_CURVE_RIBBON) {
        pwarn(im, ps, npar, "is ignored: curve normals are only used with \"ribbon\" curves (as pbrt-v3)");
        N = NULL, nn = 0;
    } else if (N && nn != (size_t)nseg + 1) {
        return ts_pbrt_param_error(ps, npar, im->err, TS_ERR_INVALID,
                                   "has %zu normals: a ribbon curve of %u segments needs %u (as pbrt-v3)", nn, nseg,
                                   nseg + 1);
    } else if (!N && kind == TS_CURVE_RIBBON) {
        return derr(im, ps, sh->loc, TS_ERR_INVALID,
                    "a \"ribbon\" curve needs normals \"normal N\" at its segment ends (as pbrt-v3)");
    }
    for (size_t k = 0; N && k < nn; k++)
        if (N[3 * k] == 0 && N[3 * k + 1] == 0 && N[3 * k + 2] == 0)
            return ts_pbrt_param_error(ps, npar, im->err, TS_ERR_INVALID,
                                       "normal %zu is zero (pbrt-v3 normalises it to NaN)", k);
    ts_pbrt_param *sd = ts_pbrt_params_get(ps, "splitdepth");
    if (sd) {
        double v = sd->type == TS_PBRT_PARAM_INTEGER && sd->n == 1   ? sd->ints[0]
                   : sd->type == TS_PBRT_PARAM_FLOAT && sd->n == 1 ? (double)(int)sd->floats[0]
                                                                    : NAN;
        if (!(v >= 0 && v <= 20))
            return ts_pbrt_param_error(ps, sd, im->err, TS_ERR_INVALID,
                                       "expects one whole number in [0, 20] (pbrt-v3 makes 2^splitdepth pieces of "
                                       "each segment)");
    }
    if (nseg == 0) {
        dwarn(im, ps, sh->loc, "has one control point, which makes no segment: nothing to draw (as pbrt-v3)");
        *skip = true;
        return TS_OK;
    }
    ts_shape probe = {0};
    if (!user_xform(sh->object_to_world, &probe.to_world)) probe.to_world = ts_xform_identity();
    if (!ts_shape_is_similarity(&probe))
        dwarn(im, ps, sh->loc,
              "is placed by a non-uniform scale or shear: its width is scaled by the cube root of the transform's "
              "determinant in world space, where pbrt-v3 keeps it ray-facing in object space (the strip's width "
              "then differs with the view direction)");
    d->type = TS_SHAPE_CURVE;
    d->reverse_orientation = sh->reverse_orientation;
    d->curve.type = (ts_curve_type)kind;
    d->curve.basis = (ts_curve_basis)basis;
    d->curve.degree = degree;
    d->curve.n_points = (uint32_t)np;
    d->curve.p = P;
    d->curve.n = N;
    d->curve.n_normals = (uint32_t)nn;
    d->curve.width0 = w[0];
    d->curve.width1 = w[1];
    if (!j) return TS_OK;
    bool ok = ts_jw_string(j, "type", "curve") && ts_jw_add(j, "points", ts_jw_floats(P, 3 * np)) &&
              (basis == TS_CURVE_BEZIER || ts_jw_string(j, "basis", "bspline")) &&
              (degree == 3 || ts_jw_number(j, "degree", degree)) &&
              (kind == TS_CURVE_FLAT || ts_jw_string(j, "curve_type", kinds[kind])) &&
              (!N || ts_jw_add(j, "normals", ts_jw_floats(N, 3 * nn))) && ts_jw_number(j, "width0", w[0]) &&
              ts_jw_number(j, "width1", w[1]) && (!d->reverse_orientation || ts_jw_bool(j, "reverse_orientation", true));
    return ok ? TS_OK : nomem(im);
}

static ts_status map_shape(imp *im, size_t si)
{
    ts_pbrt_shape *sh = &im->s->shapes[si];
    ts_pbrt_params *ps = &sh->params;
    const char *t = sh->type;
    bool analytic = strcmp(t, "sphere") == 0 || strcmp(t, "disk") == 0 || strcmp(t, "cylinder") == 0;
    bool mesh = strcmp(t, "trianglemesh") == 0 || strcmp(t, "plymesh") == 0 || strcmp(t, "loopsubdiv") == 0;
    bool curve = strcmp(t, "curve") == 0;
    if (!analytic && !mesh && !curve)
        return derr(im, ps, sh->loc, TS_ERR_UNSUPPORTED,
                    "is not supported (sphere, disk, cylinder, trianglemesh, plymesh, loopsubdiv and curve are)");

    /* The surface, the emission and the cut-out first: they may make the shape vanish. */
    uint32_t mat;
    bool no_surface;
    TRY(material_id(im, sh->material, &mat, &no_surface));
    ts_shape_desc d = {0};
    d.type = TS_SHAPE_SPHERE;
    d.material = mat;
    d.emission = ts_rgb_gray(0);
    ts_pbrt_area_light *al = sh->area_light >= 0 ? &im->s->area_lights[sh->area_light] : NULL;
    /* pbrt-v3's animated shape (api.cpp pbrtShape): a TransformedPrimitive of the shape made
     * in its own space; inside an object definition that would be an instance in an
     * instance, which Embree here cannot nest. */
    const ts_mat4 *end_m = sh->object_to_world_end;
    if (end_m && sh->object >= 0) {
        dwarn(im, ps, sh->loc,
              "is animated inside an object definition, which is not supported (instances do not nest): it keeps "
              "its start-time transform");
        end_m = NULL;
    }
    if (al && end_m) {
        dwarn(im, ps, sh->loc, "is animated: its area light is ignored (as pbrt-v3 does: \"Ignoring currently set "
                               "area light when creating animated shape\")");
        /* pbrt-v3 never makes it, so never reports its parameters: nor does this. */
        for (size_t k = 0; k < al->params.count; k++) al->params.items[k].used = true;
        al = NULL;
    }
    if (al) {
        if (strcmp(al->type, "diffuse") != 0 && strcmp(al->type, "area") != 0)
            return derr(im, &al->params, al->loc, TS_ERR_UNSUPPORTED,
                        "is not a pbrt-v3 area light (diffuse)");
        ts_rgb L, scale;
        TRY(get_rgb(im, &al->params, "L", ts_rgb_gray(1), &L));
        TRY(get_rgb(im, &al->params, "scale", ts_rgb_gray(1), &scale));
        TRY(ts_pbrt_find_bool(&al->params, "twosided", false, &d.two_sided, im->err));
        TRY(light_samples(im, &al->params, &d.light_samples));
        d.emission = (ts_rgb){L.r * scale.r, L.g * scale.g, L.b * scale.b};
        if (curve && !ts_rgb_is_black(d.emission))
            return derr(im, &al->params, al->loc, TS_ERR_UNSUPPORTED,
                        "is refused on a \"curve\": pbrt-v3 cannot sample curves (its Curve::Sample is not "
                        "implemented and stops the render at the first light sample)");
    }
    bool emits = d.emission.r > 0 || d.emission.g > 0 || d.emission.b > 0;
    if (no_surface) {
        if (emits)
            return derr(im, ps, sh->loc, TS_ERR_UNSUPPORTED,
                        "an emitting shape with material \"none\" (no surface) is not supported");
        d.material = TS_NONE; /* rays pass through it; it may bound a medium */
    }
    /* pbrt-v3 reads alpha and shadowalpha on trianglemesh and plymesh only; on other shapes
     * they are unused parameters (warned below, as pbrt-v3 reports them). */
    cutout alpha = {0}, salpha = {0};
    if (strcmp(t, "trianglemesh") == 0 || strcmp(t, "plymesh") == 0) {
        TRY(get_cutout(im, ps, "alpha", &alpha));
        TRY(get_cutout(im, ps, "shadowalpha", &salpha));
        if (salpha.tex && strcmp(im->s->integrator.type, "volpath") == 0) {
            /* pbrt-v3's volpath traces every shadow ray with Scene::Intersect (VisibilityTester::Tr),
             * which tests alpha, never shadowalpha; tessera's volpath would honour it. */
            pwarn(im, ps, ts_pbrt_params_get(ps, "shadowalpha"),
                  "is not used: pbrt-v3's volpath integrator traces shadow rays that test alpha only, so the "
                  "mesh shadows where it is not cut out by alpha; left out");
            salpha = (cutout){0};
        }
        if (alpha.zero && !emits) {
            /* Cut out everywhere for every ray, and no light: nothing of it can be seen. */
            pwarn(im, ps, ts_pbrt_params_get(ps, "alpha"),
                  "is 0: the shape is cut out entirely (it neither shows nor shadows) and left out");
            ps->count = 0;
            return TS_OK;
        }
        d.alpha = alpha.tex;
        d.shadow_alpha = salpha.tex;
    }

    ts_xform user, user_end;
    if (!user_xform(sh->object_to_world, &user))
        return derr(im, ps, sh->loc, TS_ERR_INVALID, "the transformation matrix is singular");
    if (end_m) TRY(motion_end(im, ps, sh->loc, sh->object_to_world, end_m, &user_end));
    ts_xform place = ts_xform_identity(); /* the shape in its own space (a mesh: the identity) */
    cJSON *j = NULL;
    if (im->doc) {
        j = cJSON_CreateObject();
        if (!j) return nomem(im);
    }
    bool jok = true;
    ts_mesh_data md = {0};
    ts_status st = TS_OK;
    if (analytic) {
        /* pbrt-v3's partial quadrics (scene_builder.h's ts_shape_cut) and its
         * ReverseOrientation, which the builder applies as pbrt-v3's graphics state holds it. */
        float phimax, radius;
        if ((st = ts_pbrt_find_float(ps, "phimax", 360, &phimax, im->err)) ||
            (st = ts_pbrt_find_float(ps, "radius", 1, &radius, im->err)))
            goto fail;
        phimax = ts_clampf(phimax, 0, 360);
        if (!(radius > 0) || !isfinite(radius)) {
            st = ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "radius"), im->err, TS_ERR_INVALID,
                                     "must be a positive number, got %g", radius);
            goto fail;
        }
        if (!(phimax > 0)) {
            st = ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "phimax"), im->err, TS_ERR_INVALID,
                                     "leaves no surface (pbrt-v3 clamps it to [0, 360])");
            goto fail;
        }
        d.reverse_orientation = sh->reverse_orientation;
        if (t[0] == 's') {
            float zmin, zmax;
            if ((st = ts_pbrt_find_float(ps, "zmin", -radius, &zmin, im->err)) ||
                (st = ts_pbrt_find_float(ps, "zmax", radius, &zmax, im->err)))
                goto fail;
            d.type = TS_SHAPE_SPHERE;
            place = ts_xform_translate((ts_dvec3){0, 0, 0});
            d.sphere.radius = radius;
            if (phimax < 360 || fminf(zmin, zmax) > -radius || fmaxf(zmin, zmax) < radius)
                d.cut = (ts_shape_cut){true, zmin, zmax, phimax};
            if (j) {
                jok = ts_jw_string(j, "type", "sphere") && ts_jw_number(j, "radius", radius);
                if (jok && d.cut.partial)
                    jok = ts_jw_number(j, "z_min", zmin) && ts_jw_number(j, "z_max", zmax) &&
                          ts_jw_number(j, "phi_max", phimax);
            }
        } else if (t[0] == 'd') {
            float height, inner;
            if ((st = ts_pbrt_find_float(ps, "height", 0, &height, im->err)) ||
                (st = ts_pbrt_find_float(ps, "innerradius", 0, &inner, im->err)))
                goto fail;
            if (!(inner >= 0 && inner < radius)) {
                st = ts_pbrt_param_error(ps, ts_pbrt_params_get(ps, "innerradius"), im->err, TS_ERR_INVALID,
                                         "must be in [0, radius %g), got %g", radius, inner);
                goto fail;
            }
            d.type = TS_SHAPE_DISK;
            ts_vec3 center = {0, 0, height}, normal = {0, 0, 1};
            place = ts_xform_frame(ts_dvec3_from(center), ts_dvec3_from(normal));
            d.disk.radius = radius;
            d.disk.inner_radius = inner;
            if (phimax < 360) d.cut = (ts_shape_cut){true, 0, 0, phimax};
            if (j)
                jok = ts_jw_string(j, "type", "disk") && ts_jw_vec3(j, "center", center) &&
                      ts_jw_number(j, "radius", radius) && (inner == 0 || ts_jw_number(j, "inner_radius", inner)) &&
                      (!d.cut.partial || ts_jw_number(j, "phi_max", phimax));
        } else {
            float zmin, zmax;
            if ((st = ts_pbrt_find_float(ps, "zmin", -1, &zmin, im->err)) ||
                (st = ts_pbrt_find_float(ps, "zmax", 1, &zmax, im->err)))
                goto fail;
            float lo = fminf(zmin, zmax), hi = fmaxf(zmin, zmax);
            if (!(hi > lo)) {
                st = derr(im, ps, sh->loc, TS_ERR_INVALID, "zmin and zmax must differ, got %g and %g", zmin,
                          zmax);
                goto fail;
            }
            d.type = TS_SHAPE_CYLINDER;
            ts_vec3 p0 = {0, 0, lo}, p1 = {0, 0, hi};
            ts_dvec3 axis = ts_dvec3_sub(ts_dvec3_from(p1), ts_dvec3_from(p0));
            place = ts_xform_frame(ts_dvec3_from(p0), axis);
            d.cylinder.radius = radius;
            d.cylinder.height = ts_dvec3_length(axis);
            /* as the JSON front end gives it: the tube from p0 to p1 */
            if (phimax < 360) d.cut = (ts_shape_cut){true, 0, d.cylinder.height, phimax};
            if (j)
                jok = ts_jw_string(j, "type", "cylinder") && ts_jw_vec3(j, "p0", p0) && ts_jw_vec3(j, "p1", p1) &&
                      ts_jw_number(j, "radius", radius) && (!d.cut.partial || ts_jw_number(j, "phi_max", phimax));
        }
        if (j && d.reverse_orientation) jok = jok && ts_jw_bool(j, "reverse_orientation", true);
        d.to_world = ts_xform_compose(&user, &place);
    } else if (curve) {
        bool skip;
        d.to_world = user;
        st = read_curve(im, sh, &d, j, &skip);
        if (!st && skip) {
            ps->count = 0; /* nothing left to warn about */
            goto fail;
        }
    } else {
        d.type = TS_SHAPE_MESH;
        d.to_world = user;
        if (t[0] == 't') {
            st = read_trianglemesh(im, sh, &md);
        } else if (t[0] == 'l') {
            st = read_loopsubdiv(im, sh, &md);
        } else {
            const char *file;
            st = ts_pbrt_find_string(ps, "filename", NULL, &file, im->err);
            if (!st && !file) st = derr(im, ps, sh->loc, TS_ERR_INVALID, "\"string filename\" is required");
            if (!st)
                st = at(im, ts_scene_builder_load_mesh(im->b, file, &md, im->err), ps,
                        ts_pbrt_params_get(ps, "filename")->loc);
            ts_pbrt_param *disp = ts_pbrt_params_get(ps, "displacement");
            if (disp) pwarn(im, ps, disp, "is ignored: displacement is not supported");
        }
        if (!st) {
            orient_mesh(&md, sh->reverse_orientation);
            d.mesh = (ts_mesh){md.n_vertices, md.n_triangles, md.p, md.n, md.uv, md.index};
            if (j) {
                jok = ts_jw_string(j, "type", "mesh") &&
                      ts_jw_add(j, "positions", ts_jw_floats(md.p, 3 * (size_t)md.n_vertices)) &&
                      ts_jw_add(j, "indices", ts_jw_uints(md.index, 3 * (size_t)md.n_triangles)) &&
                      (!md.n || ts_jw_add(j, "normals", ts_jw_floats(md.n, 3 * (size_t)md.n_vertices))) &&
                      (!md.uv || ts_jw_add(j, "uvs", ts_jw_floats(md.uv, 2 * (size_t)md.n_vertices)));
            }
        }
    }
    if (!st && j && jok) st = jcutout(im, j, "alpha", &alpha);
    if (!st && j && jok) st = jcutout(im, j, "shadow_alpha", &salpha);
    if (!st) st = shape_media(im, sh, &d, j);
    if (!st) {
        warn_unused(im, ps);
        if (end_m) {
            d.to_world = d.type == TS_SHAPE_MESH ? ts_xform_identity() : place;
            st = at(im,
                    ts_scene_builder_add_moving_shape(im->b, &d, &user, im->s->transform_start_time, &user_end,
                                                      im->s->transform_end_time, NULL, im->err),
                    ps, sh->loc);
        } else {
            st = at(im, ts_scene_builder_add_shape(im->b, &d, NULL, im->err), ps, sh->loc);
        }
    }
    if (!st && j) {
        const char *mname = NULL;
        /* The material's name in the document is the one the builder holds it under. */
        char name[300];
        int32_t mi = sh->material;
        if (mi >= 0 && im->s->materials[mi].name)
            snprintf(name, sizeof name, "%.200s#%d", im->s->materials[mi].name, (int)mi);
        else if (mi >= 0)
            snprintf(name, sizeof name, "%s#%d", im->s->materials[mi].type, (int)mi);
        else
            snprintf(name, sizeof name, "default-matte");
        mname = name;
        jok = jok && (no_surface ? cJSON_AddNullToObject(j, "material") != NULL : ts_jw_string(j, "material", mname)) &&
              ts_jw_add(j, "transform", ts_jw_transform(sh->object_to_world));
        if (jok && end_m) jok = jmotion(im, j, end_m);
        if (jok && emits)
            jok = ts_jw_rgb(j, "emission", d.emission) && (!d.two_sided || ts_jw_bool(j, "two_sided", true)) &&
                  (!d.light_samples || ts_jw_number(j, "light_samples", d.light_samples));
        if (!jok || !cJSON_AddItemToArray(im->jtarget, j))
            st = nomem(im);
        else
            j = NULL;
    }
fail:
    cJSON_Delete(j);
    ts_mesh_data_free(&md);
    return st;
}

/* ---------------------------------------------------------------- lights */

static ts_dvec3 mat_point(const ts_mat4 *m, ts_vec3 p)
{
    double v[3] = {p.x, p.y, p.z}, o[3];
    for (int i = 0; i < 3; i++)
        o[i] = m->m[i][0] * v[0] + m->m[i][1] * v[1] + m->m[i][2] * v[2] + m->m[i][3];
    double w = m->m[3][0] * v[0] + m->m[3][1] * v[1] + m->m[3][2] * v[2] + m->m[3][3];
    if (w != 1 && w != 0) o[0] /= w, o[1] /= w, o[2] /= w;
    return (ts_dvec3){o[0], o[1], o[2]};
}

static ts_vec3 to_vec3(ts_dvec3 v) { return (ts_vec3){(float)v.x, (float)v.y, (float)v.z}; }

/* One row of a light type's description (build/light_desc.h) as pbrt-v3 reads it:
 * points through the light's CTM, colours times its "scale", angles as they are; a value
 * out of the row's range refused here, by its pbrt-v3 name. */
static ts_status get_light_param(imp *im, const ts_pbrt_light *l, ts_pbrt_params *ps, const ts_light_param *p,
                                 ts_rgb scale, ts_light_desc *d)
{
    switch (p->kind) {
    case TS_LPARAM_POINT: {
        ts_vec3 v, def = {(float)p->pbrt3_def[0], (float)p->pbrt3_def[1], (float)p->pbrt3_def[2]};
        TRY(ts_pbrt_find_point3(ps, p->pbrt3, def, &v, im->err));
        ts_vec3 *w = ts_lparam_point(d, p);
        *w = to_vec3(mat_point(l->light_to_world, v));
        if ((p->flags & TS_LPARAM_NOT_FROM) && w->x == d->from.x && w->y == d->from.y && w->z == d->from.z)
            return derr(im, ps, l->loc, TS_ERR_INVALID, "\"point from\" and \"point %s\" must differ", p->pbrt3);
        return TS_OK;
    }
    case TS_LPARAM_RGB: {
        ts_rgb c;
        TRY(get_rgb(im, ps, p->pbrt3, ts_rgb_gray((float)p->pbrt3_def[0]), &c));
        *ts_lparam_rgb(d, p) = (ts_rgb){c.r * scale.r, c.g * scale.g, c.b * scale.b};
        return TS_OK;
    }
    case TS_LPARAM_ANGLE: {
        float v;
        TRY(ts_pbrt_find_float(ps, p->pbrt3, (float)p->pbrt3_def[0], &v, im->err));
        *ts_lparam_angle(d, p) = v;
        if (!ts_lparam_angle_ok(p, v, d->cone_angle_deg)) {
            ts_pbrt_param *pp = ts_pbrt_params_get(ps, p->pbrt3);
            const char *range = (p->flags & TS_LPARAM_UPTO_ANGLE) ? "[0, coneangle]" : "(0, 180]";
            if (pp) return ts_pbrt_param_error(ps, pp, im->err, TS_ERR_INVALID, "must be in %s degrees, got %g", range, v);
            return derr(im, ps, l->loc, TS_ERR_INVALID, "\"float %s\" must be in %s degrees, got %g", p->pbrt3, range, v);
        }
        return TS_OK;
    }
    }
    return TS_OK;
}

/* pbrt-v3's infinite light: L, or mapname (then L × scale is the map's scale), its CTM as
 * the map's transform, nsamples. */
static ts_status get_environment(imp *im, const ts_pbrt_light *l, ts_pbrt_params *ps, ts_rgb scale, ts_light_desc *d,
                                 const char **map)
{
    ts_rgb L;
    TRY(get_rgb(im, ps, "L", ts_rgb_gray(1), &L));
    TRY(ts_pbrt_find_string(ps, "mapname", "", map, im->err));
    TRY(light_samples(im, ps, &d->samples));
    d->color = (ts_rgb){L.r * scale.r, L.g * scale.g, L.b * scale.b};
    if (!user_xform(l->light_to_world, &d->to_world))
        return derr(im, ps, l->loc, TS_ERR_INVALID, "the transformation matrix is singular");
    if ((*map)[0])
        TRY(at(im, ts_scene_builder_load_envmap(im->b, *map, &d->map, im->err), ps, ts_pbrt_params_get(ps, "mapname")->loc));
    return TS_OK;
}

/* A light as scene format v1 has it: its rows in the description's order. */
static bool json_light(cJSON *j, const ts_light_type_desc *t, const ts_light_desc *d, const ts_pbrt_light *l,
                       const char *map)
{
    bool ok = ts_jw_string(j, "type", t->name);
    for (int i = 0; ok && i < t->n_params; i++) {
        const ts_light_param *p = &t->params[i];
        ts_light_desc *dd = (ts_light_desc *)d;
        switch (p->kind) {
        case TS_LPARAM_POINT: ok = ts_jw_vec3(j, p->key, *ts_lparam_point(dd, p)); break;
        case TS_LPARAM_RGB: ok = ts_jw_rgb(j, p->key, *ts_lparam_rgb(dd, p)); break;
        case TS_LPARAM_ANGLE: ok = ts_jw_number(j, p->key, *ts_lparam_angle(dd, p)); break;
        }
    }
    if (ok && (t->flags & TS_LDESC_ENVIRONMENT))
        ok = (map[0] ? ts_jw_string(j, "map", map) && ts_jw_rgb(j, "scale", d->color)
                     : ts_jw_rgb(j, "radiance", d->color)) &&
             ts_jw_add(j, "transform", ts_jw_transform(l->light_to_world)) &&
             (!d->samples || ts_jw_number(j, "samples", d->samples));
    return ok;
}

/* pbrt-v3's LightSource li: the type whose description names it (build/light_desc.h), read
 * row by row. */
static ts_status map_light(imp *im, size_t li)
{
    ts_pbrt_light *l = &im->s->lights[li];
    ts_pbrt_params *ps = &l->params;
    ts_light_desc d = {0};
    d.to_world = ts_xform_identity();
    const ts_light_type_desc *t = ts_light_desc_by_pbrt3(l->type);
    if (!t)
        return derr(im, ps, l->loc, TS_ERR_UNSUPPORTED,
                    "is not supported (point, spot, distant, infinite and diffuse area lights are)");
    ts_rgb scale;
    TRY(get_rgb(im, ps, "scale", ts_rgb_gray(1), &scale));
    d.type = t->type;
    for (int i = 0; i < t->n_params; i++)
        TRY(get_light_param(im, l, ps, &t->params[i], scale, &d));
    const char *map = "";
    if (t->flags & TS_LDESC_ENVIRONMENT) TRY(get_environment(im, l, ps, scale, &d, &map));
    warn_unused(im, ps);
    ts_status st = at(im, ts_scene_builder_add_light(im->b, &d, im->err), ps, l->loc);
    if (st || !im->doc) return st;
    cJSON *j = cJSON_CreateObject();
    if (!j || !json_light(j, t, &d, l, map) || !cJSON_AddItemToArray(im->jlights, j)) {
        cJSON_Delete(j);
        return nomem(im);
    }
    return TS_OK;
}

static ts_status map_objects(imp *im)
{
    ts_pbrt_scene *s = im->s;
    if (s->instance_count == 0) return TS_OK;
    uint32_t *ids = malloc(s->object_count * sizeof *ids);
    if (!ids) return nomem(im);
    for (size_t o = 0; o < s->object_count; o++)
        ids[o] = TS_NONE;
    ts_status st = TS_OK;
    for (size_t o = 0; o < s->object_count && !st; o++) {
        ts_pbrt_object *ob = &s->objects[o];
        if (ob->instance_count == 0) continue;
        char name[300];
        snprintf(name, sizeof name, "%.200s#%zu", ob->name, o);
        ts_pbrt_params ps = {.directive = "ObjectBegin", .directive_arg = ob->name};
        st = at(im, ts_scene_builder_begin_object(im->b, name, &ids[o], im->err), &ps, ob->loc);
        if (!st && im->doc) {
            cJSON *jo = cJSON_CreateObject(), *jsh = cJSON_CreateArray();
            if (!jo || !jsh || !cJSON_AddItemToObject(jo, "shapes", jsh)) {
                cJSON_Delete(jsh);
                cJSON_Delete(jo);
                st = nomem(im);
            } else if (!cJSON_AddItemToObject(im->jobjects, name, jo)) {
                cJSON_Delete(jo);
                st = nomem(im);
            } else {
                im->jtarget = jsh;
            }
        }
        for (size_t k = 0; k < ob->shape_count && !st; k++)
            st = map_shape(im, ob->first_shape + k);
        im->jtarget = im->jshapes;
        if (!st) st = at(im, ts_scene_builder_end_object(im->b, im->err), &ps, ob->loc);
    }
    for (size_t i = 0; i < s->instance_count && !st; i++) {
        ts_pbrt_instance *in = &s->instances[i];
        ts_pbrt_params ps = {.directive = "ObjectInstance", .directive_arg = s->objects[in->object].name};
        ts_xform x, x_end;
        if (!user_xform(in->instance_to_world, &x)) {
            st = derr(im, &ps, in->loc, TS_ERR_INVALID, "the transformation matrix is singular");
            break;
        }
        if (in->instance_to_world_end) {
            if ((st = motion_end(im, &ps, in->loc, in->instance_to_world, in->instance_to_world_end, &x_end))) break;
            st = at(im,
                    ts_scene_builder_add_moving_instance(im->b, ids[in->object], &x, s->transform_start_time, &x_end,
                                                         s->transform_end_time, im->err),
                    &ps, in->loc);
        } else {
            st = at(im, ts_scene_builder_add_instance(im->b, ids[in->object], &x, im->err), &ps, in->loc);
        }
        if (!st && im->doc) {
            char name[300];
            snprintf(name, sizeof name, "%.200s#%d", s->objects[in->object].name, (int)in->object);
            cJSON *j = cJSON_CreateObject();
            if (!j || !ts_jw_string(j, "object", name) ||
                !ts_jw_add(j, "transform", ts_jw_transform(in->instance_to_world)) ||
                (in->instance_to_world_end && !jmotion(im, j, in->instance_to_world_end)) ||
                !cJSON_AddItemToArray(im->jinstances, j)) {
                cJSON_Delete(j);
                st = nomem(im);
            }
        }
    }
    free(ids);
    return st;
}

/* Options the scene did not give have empty parameter lists without a directive name. */
/* ---------------------------------------------------------------- media */

bool ts_pbrt_media_used(const ts_pbrt_scene *s)
{
    if (s->camera_medium && *s->camera_medium) return true;
    for (size_t i = 0; i < s->shape_count; i++) {
        const ts_pbrt_shape *sh = &s->shapes[i];
        if ((sh->inside_medium && *sh->inside_medium) || (sh->outside_medium && *sh->outside_medium)) return true;
    }
    return false;
}

/* The document's name of medium k: its own, made unique by "#k". */
static void medium_doc_name(const imp *im, size_t k, char *name, size_t n)
{
    snprintf(name, n, "%.200s#%zu", im->s->media[k].name, k);
}

/* The builder's medium named `name` (the last MakeNamedMedium of that name, as pbrt-v3's
 * map keeps it): *id, TS_NONE for "" (vacuum); false if none defines it. *k its index. */
static bool find_medium(const imp *im, const char *name, uint32_t *id, size_t *k)
{
    *id = TS_NONE;
    if (!name || !*name) return true;
    for (size_t i = im->s->medium_count; i-- > 0;)
        if (strcmp(im->s->media[i].name, name) == 0) {
            *id = im->medium_id[i];
            if (k) *k = i;
            return true;
        }
    return false;
}

/* pbrt-v3's MakeMedium (api.cpp): "homogeneous" and "heterogeneous" (GridDensityMedium),
 * with its parameters and defaults; the builder checks the values. */
/* pbrt-v3's MakeNamedMedium k: the type whose description names its "string type"
 * (build/medium_desc.h), read row by row; the builder checks every value. */
static ts_status map_medium(imp *im, size_t k)
{
    ts_pbrt_medium *m = &im->s->media[k];
    ts_pbrt_params *ps = &m->params;
    const ts_medium_type_desc *t = ts_medium_desc_by_pbrt3(m->type);
    if (!t)
        return derr(im, ps, m->loc, TS_ERR_UNSUPPORTED,
                    "has \"string type\" \"%s\", not a pbrt-v3 medium (homogeneous, heterogeneous)", m->type);
    ts_medium_desc d = {.type = t->type};
    for (int i = 0; i < t->n_params; i++) {
        const ts_medium_param *p = &t->params[i];
        void *f = ts_vparam_field(&d, p);
        switch (p->kind) {
        case TS_VPARAM_RGB:
            *ts_vparam_has(&d, p) = ts_pbrt_params_get(ps, p->key) != NULL;
            TRY(get_rgb(im, ps, p->key, ts_rgb_gray((float)p->def[0]), f));
            break;
        case TS_VPARAM_NUMBER: {
            float v;
            TRY(ts_pbrt_find_float(ps, p->key, (float)p->def[0], &v, im->err));
            *(double *)f = v;
            break;
        }
        case TS_VPARAM_STRING:
            TRY(ts_pbrt_find_string(ps, p->key, NULL, (const char **)f, im->err));
            if (*(const char **)f && !**(const char **)f) *(const char **)f = NULL; /* pbrt-v3: "" is none */
            break;
        case TS_VPARAM_COUNT: {
            int32_t v;
            TRY(ts_pbrt_find_int(ps, p->key, (int32_t)p->def[0], &v, im->err));
            if (v < 1) return derr(im, ps, m->loc, TS_ERR_INVALID, "\"integer %s\" must be at least 1, got %d", p->key, v);
            *(uint32_t *)f = (uint32_t)v;
            break;
        }
        case TS_VPARAM_POINT: {
            ts_vec3 v;
            TRY(ts_pbrt_find_point3(ps, p->key, (ts_vec3){(float)p->def[0], (float)p->def[1], (float)p->def[2]}, &v,
                                    im->err));
            *(ts_dvec3 *)f = ts_dvec3_from(v);
            break;
        }
        case TS_VPARAM_DENSITY: {
            size_t count;
            TRY(ts_pbrt_find_floats(ps, p->key, &d.density, &count, im->err));
            if (!d.density)
                return derr(im, ps, m->loc, TS_ERR_INVALID, "has no \"float %s\" values (pbrt-v3 refuses it too)", p->key);
            d.n_density = count;
            break;
        }
        }
    }
    if ((t->flags & TS_VDESC_TRANSFORM) && !user_xform(m->medium_to_world, &d.to_world))
        return derr(im, ps, m->loc, TS_ERR_INVALID, "the transformation matrix is singular");
    warn_unused(im, ps);
    TRY(at(im, ts_scene_builder_add_medium(im->b, NULL, &d, &im->medium_id[k], im->err), ps, m->loc));
    if (!im->jmedia) return TS_OK;
    /* The document holds the medium's parameters as given, in the description's order (the
     * JSON front end resolves the preset, the defaults and the scale as this one did). */
    char name[260];
    medium_doc_name(im, k, name, sizeof name);
    cJSON *j = cJSON_CreateObject();
    bool ok = j && ts_jw_string(j, "type", t->name);
    for (int i = 0; ok && i < t->n_params; i++) {
        const ts_medium_param *p = &t->params[i];
        void *f = ts_vparam_field(&d, p);
        switch (p->kind) {
        case TS_VPARAM_RGB: ok = !*ts_vparam_has(&d, p) || ts_jw_rgb(j, p->key, *(ts_rgb *)f); break;
        case TS_VPARAM_NUMBER: ok = ts_jw_number(j, p->key, *(double *)f); break;
        case TS_VPARAM_STRING: ok = !*(const char **)f || ts_jw_string(j, p->key, *(const char **)f); break;
        case TS_VPARAM_COUNT: ok = ts_jw_number(j, p->key, *(uint32_t *)f); break;
        case TS_VPARAM_POINT: {
            const ts_dvec3 *v = f;
            ok = ts_jw_vec3(j, p->key, (ts_vec3){(float)v->x, (float)v->y, (float)v->z});
            break;
        }
        case TS_VPARAM_DENSITY: ok = ts_jw_add(j, p->key, ts_jw_floats(d.density, d.n_density)); break;
        }
    }
    if (ok && (t->flags & TS_VDESC_TRANSFORM)) ok = ts_jw_add(j, "transform", ts_jw_transform(m->medium_to_world));
    if (!ok || !ts_jw_add(im->jmedia, name, j)) {
        if (!ok) cJSON_Delete(j);
        return nomem(im);
    }
    return TS_OK;
}

/* Every MakeNamedMedium, then the camera's medium (pbrt-v3's: the outside medium in force
 * at Camera). */
static ts_status map_media(imp *im)
{
    const ts_pbrt_scene *s = im->s;
    if (!s->medium_count) {
        if (s->camera_medium && *s->camera_medium)
            return derr(im, &s->camera.params, s->camera.loc, TS_ERR_INVALID,
                        "is in medium \"%s\" (MediumInterface), which no MakeNamedMedium defines", s->camera_medium);
        return TS_OK;
    }
    const char *integ = s->integrator.type;
    if (ts_pbrt_media_used(s) && strcmp(integ, "volpath") != 0 && strcmp(integ, "bdpt") != 0 &&
        strcmp(integ, "mlt") != 0 && strcmp(integ, "sppm") != 0)
        dwarn(im, &s->integrator.params, s->integrator.loc,
              "does not simulate the scene's participating media (as pbrt-v3 warns: rays pass through the "
              "shapes that bound them, shadow rays are blocked by them); use volpath");
    im->medium_id = calloc(s->medium_count, sizeof *im->medium_id);
    if (!im->medium_id) return nomem(im);
    if (im->doc && !ts_jw_add(im->doc, "media", im->jmedia = cJSON_CreateObject())) return nomem(im);
    for (size_t k = 0; k < s->medium_count; k++) TRY(map_medium(im, k));
    uint32_t id;
    size_t mk = 0;
    if (!find_medium(im, s->camera_medium, &id, &mk))
        return derr(im, &s->camera.params, s->camera.loc, TS_ERR_INVALID,
                    "is in medium \"%s\" (MediumInterface), which no MakeNamedMedium defines", s->camera_medium);
    TRY(ts_scene_builder_set_camera_medium(im->b, id, im->err));
    if (im->doc && id != TS_NONE) {
        char name[260];
        medium_doc_name(im, mk, name, sizeof name);
        if (!ts_jw_string(cJSON_GetObjectItemCaseSensitive(im->doc, "camera"), "medium", name)) return nomem(im);
    }
    return TS_OK;
}

/* The shape's MediumInterface (pbrt-v3's, from the graphics state at Shape) into d, and
 * into its document j; names no MakeNamedMedium defines are refused. */
static ts_status shape_media(imp *im, const ts_pbrt_shape *sh, ts_shape_desc *d, cJSON *j)
{
    const char *names[2] = {sh->inside_medium, sh->outside_medium};
    uint32_t ids[2];
    size_t ks[2] = {0, 0};
    for (int a = 0; a < 2; a++)
        if (!find_medium(im, names[a], &ids[a], &ks[a]))
            return derr(im, &sh->params, sh->loc, TS_ERR_INVALID,
                        "is inside MediumInterface medium \"%s\", which no MakeNamedMedium defines", names[a]);
    if (ids[0] == ids[1]) return TS_OK; /* no boundary: crossing it keeps a ray's medium (pbrt-v3) */
    d->medium_interface = true;
    d->medium_inside = ids[0];
    d->medium_outside = ids[1];
    if (!j) return TS_OK;
    cJSON *mi = cJSON_CreateObject();
    bool ok = mi != NULL;
    static const char *const keys[2] = {"inside", "outside"};
    for (int a = 0; a < 2 && ok; a++) {
        char name[260];
        medium_doc_name(im, ks[a], name, sizeof name);
        ok = ids[a] == TS_NONE ? cJSON_AddNullToObject(mi, keys[a]) != NULL : ts_jw_string(mi, keys[a], name);
    }
    if (!ok || !ts_jw_add(j, "medium", mi)) {
        if (!ok) cJSON_Delete(mi);
        return nomem(im);
    }
    return TS_OK;
}

static void name_option(ts_pbrt_option *o, const char *directive)
{
    if (!o->params.directive) o->params.directive = directive;
    if (!o->params.directive_arg) o->params.directive_arg = o->type;
}

static ts_status run(imp *im)
{
    ts_pbrt_scene *s = im->s;
    name_option(&s->camera, "Camera");
    name_option(&s->film, "Film");
    name_option(&s->sampler, "Sampler");
    name_option(&s->filter, "PixelFilter");
    name_option(&s->integrator, "Integrator");
    name_option(&s->accelerator, "Accelerator");
    for (size_t i = 0; i < s->warning_count; i++)
        emit(im, s->warnings[i].loc, s->warnings[i].message);
    if (s->warnings_dropped)
        warnf(im, (ts_pbrt_loc){0}, "%zu more warnings of the parser were not kept", s->warnings_dropped);
    if (s->accelerator.loc.file && s->accelerator.params.count)
        dwarn(im, &s->accelerator.params, s->accelerator.loc,
              "is not used: tessera builds Embree's BVH whatever the accelerator");
    uint32_t w, h;
    TRY(map_film(im, &w, &h));
    TRY(map_camera(im, w, h));
    TRY(map_sampler(im));
    TRY(map_integrator(im));
    TRY(map_media(im));
    if (s->texture_count > 0) {
        /* Every Texture directive, as pbrt-v3 makes them all (pbrt3/texture_pbrt.h). */
        ts_texture_cache *cache;
        TRY(ts_scene_builder_texture_cache(im->b, &cache, im->err));
        TRY(ts_texture_pbrt_build(&im->tp, s, ts_scene_builder_texture_arena(im->b), cache,
                                  ts_scene_builder_base_dir(im->b),
                                  ts_scene_builder_limits(im->b)->max_file_bytes, im->err));
        im->has_textures = true;
        for (size_t i = 0; i < s->texture_count; i++) {
            if (!strcmp(s->textures[i].class_name, "dots"))
                dwarn(im, &s->textures[i].params, s->textures[i].loc,
                      "paints its dots with \"outside\" and the rest with \"inside\", as pbrt-v3 renders it "
                      "(pbrt-v3's textures/dots.cpp passes the two swapped); its JSON conversion names them by "
                      "what they paint");
            if (!strcmp(s->textures[i].class_name, "marble"))
                dwarn(im, &s->textures[i].params, s->textures[i].loc,
                      "renders as the book's marble, not pbrt-v3's: its spline segment is min(floor(6t), 5) with "
                      "colours in [0.3, 0.9], where pbrt-v3's source clamps it to min(1, floor(6t)) and "
                      "extrapolates to reflectances up to about 40, so the image differs from pbrt-v3's (its mean "
                      "up to 15 times; docs/design.md, the marble Decision)");
            warn_unused(im, &s->textures[i].params);
        }
        if (im->doc) {
            /* Every texture in definition order (children before parents, as v1 wants),
             * under its name; a name given again in another scope gets "#k". */
            cJSON *jt = cJSON_CreateObject();
            if (!ts_jw_add(im->doc, "textures", jt)) return nomem(im);
            ts_json_texture_writer_init(&im->jtex, jt, cache);
            for (size_t i = 0; i < s->texture_count; i++) {
                ts_status st = ts_json_texture_write(&im->jtex, im->tp.textures[i], s->textures[i].name, im->err);
                if (st && st != TS_ERR_NOMEM)
                    ts_error_prefix(im->err, "%s:%u:%u", s->textures[i].loc.file,
                                    s->textures[i].loc.line, s->textures[i].loc.column);
                if (st) return st;
            }
        }
    }
    for (size_t i = 0; i < s->shape_count; i++) {
        if (s->shapes[i].object >= 0) continue; /* an object nothing instances */
        TRY(map_shape(im, i));
    }
    TRY(map_objects(im));
    for (size_t i = 0; i < s->light_count; i++)
        TRY(map_light(im, i));
    for (size_t i = 0; i < s->area_light_count; i++)
        warn_unused(im, &s->area_lights[i].params);
    for (size_t i = 0; i < s->material_count; i++)
        if (im->mat_state[i] == MAT_MAPPED) warn_unused(im, &s->materials[i].params);
    char hex[65];
    for (int i = 0; i < 32; i++)
        snprintf(hex + 2 * i, 3, "%02x", s->digest[i]);
    TRY(ts_scene_builder_set_digest(im->b, hex, im->err));
    if (im->repeats)
        warnf(im, (ts_pbrt_loc){0}, "%zu more warnings like the ones above were not repeated", im->repeats);
    return TS_OK;
}

ts_status ts_pbrt_import(ts_pbrt_scene *scene, ts_scene_builder *b, cJSON *doc, ts_warning_fn warn,
                         void *warn_ctx, ts_error *err)
{
    ts_error local;
    if (!err) err = &local;
    imp im = {.s = scene, .b = b, .doc = doc, .warn = warn, .warn_ctx = warn_ctx, .err = err};
    ts_status st = TS_OK;
    im.mat_id = calloc(scene->material_count + 1, sizeof *im.mat_id);
    im.mat_state = calloc(scene->material_count + 1, 1);
    if (!im.mat_id || !im.mat_state) st = nomem(&im);
    if (!st && doc) {
        im.jmaterials = cJSON_CreateObject();
        im.jshapes = cJSON_CreateArray();
        im.jtarget = im.jshapes;
        im.jobjects = cJSON_CreateObject();
        im.jinstances = cJSON_CreateArray();
        im.jlights = cJSON_CreateArray();
        bool ok = ts_jw_number(doc, "tessera", 1);
        /* film, camera, sampler and integrator are added by their mappings, then these. */
        if (!ok || !im.jmaterials || !im.jshapes || !im.jlights || !im.jobjects || !im.jinstances)
            st = nomem(&im);
    }
    if (!st) st = run(&im);
    if (doc) {
        bool objects = !st && im.jobjects && im.jobjects->child;
        if (!st && !(ts_jw_add(doc, "materials", im.jmaterials) && ts_jw_add(doc, "shapes", im.jshapes) &&
                     ts_jw_add(doc, "lights", im.jlights)))
            st = nomem(&im);
        else if (st) {
            cJSON_Delete(im.jmaterials);
            cJSON_Delete(im.jshapes);
            cJSON_Delete(im.jlights);
        }
        if (objects) {
            if (!(ts_jw_add(doc, "objects", im.jobjects) && ts_jw_add(doc, "instances", im.jinstances)))
                st = nomem(&im);
        } else {
            cJSON_Delete(im.jobjects);
            cJSON_Delete(im.jinstances);
        }
    }
    for (size_t i = 0; i < im.seen_cap; i++)
        free(im.seen[i]);
    free(im.seen);
    free(im.mat_id);
    free(im.mat_state);
    free(im.medium_id);
    ts_json_texture_writer_fini(&im.jtex);
    return st;
}
