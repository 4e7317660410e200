/* scene_json.c — scene format v1 loading; see scene_json.h.
 *
 * Every parse_* function reads one part of the document, checks it completely and hands
 * it to the builder; any failure returns the sentence and the caller destroys the builder
 * with whatever it holds, so nothing is half-loaded. The accelerator and light preparation,
 * the only expensive build steps, run in ts_scene_builder_finish, after the whole document
 * has been accepted. */
#include "json/scene_json.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "integrators/effects.h"
#include "json/json_check.h"
#include "mesh/mesh_read.h"
#include "mesh/mesh_subdiv.h"
#include "json/scene_digest.h"
#include "build/light_desc.h"
#include "build/medium_desc.h"
#include "json/scene_json_texture.h"
#include "materials/material_desc.h"
#include "core/scene_path.h"

extern const char ts_builtin_cornell_box[];
extern const size_t ts_builtin_cornell_box_size;

typedef struct loader {
    ts_scene_builder *b;
    const ts_scene_limits *lim;
    ts_error *err;
    bool named; /* the document has a "name" */
    ts_json_textures textures; /* "textures", by name */
} loader;

#define TRY(expr)                          \
    do {                                   \
        ts_status st_ = (expr);            \
        if (st_ != TS_OK) return st_;      \
    } while (0)

/* A builder call about the element at path: its sentence gets the path in front. */
static ts_status at(ts_status st, const char *path, ts_error *err)
{
    if (st) ts_error_prefix(err, "%s", path);
    return st;
}

static ts_status nomem(loader *ld, const char *what)
{
    return ts_error_set(ld->err, TS_ERR_NOMEM, "out of memory while loading %s", what);
}

static ts_status parse_transform(loader *ld, const cJSON *obj, const char *path, ts_xform *out);
static ts_status float_array(loader *ld, const cJSON *obj, const char *path, const char *key, int stride, bool required,
                             float **out, uint32_t *count);

/* ---------------------------------------------------------------- media */

/* "media": name → medium (docs/design.md §4): pbrt-v3's homogeneous and heterogeneous
 * (here "grid") media, their keys, kinds and defaults from the type's description
 * (build/medium_desc.h), checked by the builder. */
static ts_status parse_medium(loader *ld, const cJSON *m, const char *path)
{
    const char *types[TS_MEDIUM_DESC_COUNT + 1];
    for (int i = 0; i < TS_MEDIUM_DESC_COUNT; i++)
        types[i] = ts_medium_descs[i].name;
    types[TS_MEDIUM_DESC_COUNT] = NULL;
    int type = 0;
    TRY(ts_json_enum(m, path, "type", true, types, &type, ld->err));
    const ts_medium_type_desc *t = &ts_medium_descs[type];
    const char *keys[24];
    int n = 0;
    keys[n++] = "type";
    for (int i = 0; i < t->n_params && n < 20; i++)
        keys[n++] = t->params[i].key;
    if (t->flags & TS_VDESC_TRANSFORM) keys[n++] = "transform";
    keys[n] = NULL;
    TRY(ts_json_check_object(m, path, keys, ld->err));
    ts_medium_desc d = {.type = t->type};
    float *density = NULL;
    ts_status st = TS_OK;
    for (int i = 0; i < t->n_params && !st; i++) {
        const ts_medium_param *p = &t->params[i];
        void *f = ts_vparam_field(&d, p);
        switch (p->kind) {
        case TS_VPARAM_RGB:
            *ts_vparam_has(&d, p) = cJSON_GetObjectItemCaseSensitive(m, p->key) != NULL;
            *(ts_rgb *)f = ts_rgb_gray((float)p->def[0]);
            st = ts_json_rgb(m, path, p->key, false, TS_J_ANY, f, ld->err);
            break;
        case TS_VPARAM_NUMBER:
            *(double *)f = p->def[0];
            st = ts_json_number(m, path, p->key, false, TS_J_ANY, f, ld->err);
            break;
        case TS_VPARAM_STRING: st = ts_json_string(m, path, p->key, false, (const char **)f, ld->err); break;
        case TS_VPARAM_COUNT: {
            int64_t v = (int64_t)p->def[0];
            st = ts_json_int(m, path, p->key, true, 1, 1 << 20, &v, ld->err);
            *(uint32_t *)f = (uint32_t)v;
            break;
        }
        case TS_VPARAM_POINT: {
            ts_vec3 v = {(float)p->def[0], (float)p->def[1], (float)p->def[2]};
            st = ts_json_vec3(m, path, p->key, false, false, &v, ld->err);
            *(ts_dvec3 *)f = ts_dvec3_from(v);
            break;
        }
        case TS_VPARAM_DENSITY: {
            uint32_t count = 0;
            st = float_array(ld, m, path, p->key, 1, true, &density, &count);
            d.density = density;
            d.n_density = count;
            break;
        }
        }
    }
    if (!st && (t->flags & TS_VDESC_TRANSFORM)) st = parse_transform(ld, m, path, &d.to_world);
    if (!st) st = at(ts_scene_builder_add_medium(ld->b, path + strlen("media."), &d, NULL, ld->err), path, ld->err);
    free(density);
    return st;
}

static ts_status parse_media(loader *ld, const cJSON *doc)
{
    const cJSON *media;
    TRY(ts_json_object(doc, "", "media", false, &media, ld->err));
    for (const cJSON *m = media ? media->child : NULL; m; m = m->next) {
        ts_jpath p = ts_jpath_key("media", m->string);
        if (!cJSON_IsObject(m)) return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected an object", p.s);
        TRY(parse_medium(ld, m, p.s));
    }
    return TS_OK;
}

/* obj[key]: a medium's name in "media" (*id), or null or absent (TS_NONE: vacuum). */
static ts_status medium_ref(loader *ld, const cJSON *obj, const char *path, const char *key, uint32_t *id)
{
    *id = TS_NONE;
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v || cJSON_IsNull(v)) return TS_OK;
    const char *name;
    TRY(ts_json_string(obj, path, key, true, &name, ld->err));
    *id = ts_scene_builder_find_medium(ld->b, name);
    if (*id == TS_NONE) {
        ts_jpath mp = ts_jpath_key(path, key);
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: no medium named \"%s\" in 'media'", mp.s, name);
    }
    return TS_OK;
}

/* A shape's "medium": {"inside": name or null, "outside": name or null}. */
static ts_status parse_shape_medium(loader *ld, const cJSON *sh, const char *path, ts_shape_desc *d)
{
    const cJSON *mi;
    TRY(ts_json_object(sh, path, "medium", false, &mi, ld->err));
    if (!mi) return TS_OK;
    ts_jpath p = ts_jpath_key(path, "medium");
    static const char *const keys[] = {"inside", "outside", NULL};
    TRY(ts_json_check_object(mi, p.s, keys, ld->err));
    d->medium_interface = true;
    TRY(medium_ref(ld, mi, p.s, "inside", &d->medium_inside));
    return medium_ref(ld, mi, p.s, "outside", &d->medium_outside);
}

/* ---------------------------------------------------------------- transforms */

/* The transform list under key (absent: the identity, or an error when required). */
static ts_status parse_transform_key(loader *ld, const cJSON *obj, const char *path, const char *key, bool required,
                                     ts_xform *out)
{
    *out = ts_xform_identity();
    const cJSON *list;
    TRY(ts_json_array(obj, path, key, required, &list, ld->err));
    if (!list) return TS_OK;
    ts_jpath lp = ts_jpath_key(path, key);
    int i = 0;
    for (const cJSON *t = list->child; t; t = t->next, i++) {
        ts_jpath p = ts_jpath_index(lp.s, i);
        static const char *const keys[] = {"translate", "scale", "rotate", "matrix", NULL};
        TRY(ts_json_check_object(t, p.s, keys, ld->err));
        if (cJSON_GetArraySize(t) != 1)
            return ts_error_set(ld->err, TS_ERR_INVALID,
                                "%s: expected exactly one of translate, scale, rotate, matrix", p.s);
        ts_xform step;
        const char *key = t->child->string;
        if (strcmp(key, "translate") == 0) {
            ts_vec3 d;
            TRY(ts_json_vec3(t, p.s, "translate", true, false, &d, ld->err));
            step = ts_xform_translate(ts_dvec3_from(d));
        } else if (strcmp(key, "scale") == 0) {
            const cJSON *v = t->child;
            ts_vec3 sc;
            if (cJSON_IsNumber(v)) {
                double k;
                TRY(ts_json_number(t, p.s, "scale", true, TS_J_ANY, &k, ld->err));
                sc = (ts_vec3){(float)k, (float)k, (float)k};
            } else {
                TRY(ts_json_vec3(t, p.s, "scale", true, false, &sc, ld->err));
            }
            if (sc.x == 0 || sc.y == 0 || sc.z == 0) {
                ts_jpath sp = ts_jpath_key(p.s, "scale");
                return ts_error_set(ld->err, TS_ERR_INVALID, "%s: scale factors must be non-zero", sp.s);
            }
            step = ts_xform_scale(ts_dvec3_from(sc));
        } else if (strcmp(key, "rotate") == 0) {
            const cJSON *r = t->child;
            ts_jpath rp = ts_jpath_key(p.s, "rotate");
            static const char *const rkeys[] = {"angle", "axis", NULL};
            TRY(ts_json_check_object(r, rp.s, rkeys, ld->err));
            double angle;
            ts_vec3 axis;
            TRY(ts_json_number(r, rp.s, "angle", true, TS_J_ANY, &angle, ld->err));
            TRY(ts_json_vec3(r, rp.s, "axis", true, true, &axis, ld->err));
            step = ts_xform_rotate(angle, ts_dvec3_from(axis));
        } else {
            const cJSON *m = t->child;
            ts_jpath mp = ts_jpath_key(p.s, "matrix");
            if (!cJSON_IsArray(m) || cJSON_GetArraySize(m) != 16) {
                char d[64];
                ts_json_describe(m, d, sizeof d);
                return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected an array of 16 numbers (row-major), got %s",
                                    mp.s, d);
            }
            ts_mat4 mat;
            int k = 0;
            for (const cJSON *c = m->child; c; c = c->next, k++) {
                if (!cJSON_IsNumber(c) || !isfinite((float)c->valuedouble)) {
                    ts_jpath ep = ts_jpath_index(mp.s, k);
                    return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected a finite number within the float range", ep.s);
                }
                mat.m[k / 4][k % 4] = c->valuedouble;
            }
            if (!ts_xform_from_matrix(&mat, &step))
                return ts_error_set(ld->err, TS_ERR_INVALID, "%s: the matrix is singular", mp.s);
        }
        /* Applied first to last: the new step goes on the outside. Points are made in
         * double and kept as floats: a composition beyond the float range is refused here,
         * where it happens, rather than as a shape that vanishes. */
        *out = ts_xform_compose(&step, out);
        for (int r = 0; r < 4; r++)
            for (int c = 0; c < 4; c++)
                if (!isfinite((float)out->m.m[r][c]) || !isfinite((float)out->m_inv.m[r][c]))
                    return ts_error_set(ld->err, TS_ERR_INVALID,
                                        "%s: the transform so far overflows the float range (it or its inverse has "
                                        "an entry of %.3g)",
                                        p.s, isfinite((float)out->m.m[r][c]) ? out->m_inv.m[r][c] : out->m.m[r][c]);
    }
    return TS_OK;
}

static ts_status parse_transform(loader *ld, const cJSON *obj, const char *path, ts_xform *out)
{
    return parse_transform_key(ld, obj, path, "transform", false, out);
}

/* A pair of finite numbers [a, b] with a ≤ b under key (absent: *a, *b unchanged). */
static ts_status parse_interval(loader *ld, const cJSON *obj, const char *path, const char *key, double *a,
                                double *b)
{
    const cJSON *arr;
    TRY(ts_json_array(obj, path, key, false, &arr, ld->err));
    if (!arr) return TS_OK;
    ts_jpath kp = ts_jpath_key(path, key);
    const cJSON *x = arr->child, *y = x ? x->next : NULL;
    if (!x || !y || y->next || !cJSON_IsNumber(x) || !cJSON_IsNumber(y) || !isfinite((float)x->valuedouble) ||
        !isfinite((float)y->valuedouble) || !(x->valuedouble <= y->valuedouble))
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected [start, end], two finite numbers with start ≤ end",
                            kp.s);
    *a = x->valuedouble;
    *b = y->valuedouble;
    return TS_OK;
}

/* A shape's or instance's "motion" (docs/design.md §4): {"times": [t0, t1] (default
 * [0, 1]), "transform": the transform at t1 (required; "transform" beside it holds at t0)}.
 * *has false when absent. */
static ts_status parse_motion(loader *ld, const cJSON *obj, const char *path, bool *has, double *t0, double *t1,
                              ts_xform *end)
{
    *has = false;
    const cJSON *m;
    TRY(ts_json_object(obj, path, "motion", false, &m, ld->err));
    if (!m) return TS_OK;
    ts_jpath mp = ts_jpath_key(path, "motion");
    static const char *const keys[] = {"times", "transform", NULL};
    TRY(ts_json_check_object(m, mp.s, keys, ld->err));
    *t0 = 0, *t1 = 1;
    TRY(parse_interval(ld, m, mp.s, "times", t0, t1));
    TRY(parse_transform_key(ld, m, mp.s, "transform", true, end));
    *has = true;
    return TS_OK;
}

/* ---------------------------------------------------------------- camera, film, sampler, integrator */

/* ---------------------------------------------------------------- camera, film, sampler, integrator */

static ts_status parse_film(loader *ld, const cJSON *doc)
{
    ts_film_desc f = {.width = 512, .height = 512, .crop = {0, 1, 0, 1}};
    ts_filter_type ftype = TS_FILTER_GAUSSIAN;
    double fradius = 1.5;
    const cJSON *film;
    TRY(ts_json_object(doc, "", "film", false, &film, ld->err));
    if (film) {
        static const char *const keys[] = {"width", "height", "filter", "crop", "scale", "max_sample_luminance", NULL};
        TRY(ts_json_check_object(film, "film", keys, ld->err));
        double scale = 1, max_lum = 0; /* 0: no clamp */
        TRY(ts_json_number(film, "film", "scale", false, TS_J_POSITIVE, &scale, ld->err));
        TRY(ts_json_number(film, "film", "max_sample_luminance", false, TS_J_POSITIVE, &max_lum, ld->err));
        if (!((float)scale > 0 && (float)scale <= FLT_MAX))
            return ts_error_set(ld->err, TS_ERR_INVALID, "film.scale: expected a finite number > 0 within float range, got %g",
                                scale);
        f.scale = (float)scale;
        f.max_sample_luminance = max_lum > 0 && (float)max_lum == 0 ? FLT_MIN : (float)max_lum;
        int64_t w = f.width, h = f.height;
        TRY(ts_json_int(film, "film", "width", false, 1, ld->lim->max_width, &w, ld->err));
        TRY(ts_json_int(film, "film", "height", false, 1, ld->lim->max_height, &h, ld->err));
        if ((uint64_t)w * (uint64_t)h > ld->lim->max_pixels)
            return ts_error_set(ld->err, TS_ERR_LIMIT, "film: %lld × %lld pixels is more than the limit of %llu",
                                (long long)w, (long long)h, (unsigned long long)ld->lim->max_pixels);
        f.width = (uint32_t)w;
        f.height = (uint32_t)h;
        const cJSON *filter;
        TRY(ts_json_object(film, "film", "filter", false, &filter, ld->err));
        if (filter) {
            static const char *const types[] = {"box", "triangle", "gaussian", "mitchell", NULL};
            int t = 2;
            TRY(ts_json_enum(filter, "film.filter", "type", true, types, &t, ld->err));
            static const char *const fkeys[] = {"type", "radius", NULL};
            static const char *const gkeys[] = {"type", "radius", "alpha", NULL};
            static const char *const mkeys[] = {"type", "radius", "b", "c", NULL};
            TRY(ts_json_check_object(filter, "film.filter", t == 2 ? gkeys : (t == 3 ? mkeys : fkeys), ld->err));
            ftype = (ts_filter_type)t;
            fradius = t == 0 ? 0.5 : (t == 1 ? 1.0 : (t == 2 ? 1.5 : 2.0));
            TRY(ts_json_number(filter, "film.filter", "radius", false, TS_J_POSITIVE, &fradius, ld->err));
            if (t == 2) {
                double alpha = 0;
                TRY(ts_json_number(filter, "film.filter", "alpha", false, TS_J_POSITIVE, &alpha, ld->err));
                f.filter_params.gaussian_alpha = (float)alpha;
            } else if (t == 3 && (cJSON_GetObjectItemCaseSensitive(filter, "b") ||
                                  cJSON_GetObjectItemCaseSensitive(filter, "c"))) {
                double bv = 1.0 / 3.0, cv = 1.0 / 3.0;
                TRY(ts_json_number(filter, "film.filter", "b", false, TS_J_ANY, &bv, ld->err));
                TRY(ts_json_number(filter, "film.filter", "c", false, TS_J_ANY, &cv, ld->err));
                f.filter_params.mitchell_custom = true;
                f.filter_params.mitchell_b = (float)bv;
                f.filter_params.mitchell_c = (float)cv;
            }
            if (fradius > 16)
                return ts_error_set(ld->err, TS_ERR_INVALID, "film.filter.radius: expected at most 16 pixels, got %g",
                                    fradius);
        }
        const cJSON *crop;
        TRY(ts_json_array(film, "film", "crop", false, &crop, ld->err));
        if (crop) {
            float c[4];
            int n = 0;
            for (const cJSON *v = crop->child; v; v = v->next) {
                if (n >= 4 || !cJSON_IsNumber(v) || !(v->valuedouble >= 0 && v->valuedouble <= 1)) n = 5;
                else c[n++] = (float)v->valuedouble;
                if (n == 5) break;
            }
            if (n != 4 || !(c[0] < c[1]) || !(c[2] < c[3]))
                return ts_error_set(ld->err, TS_ERR_INVALID,
                                    "film.crop: expected [x0, x1, y0, y1] with 0 ≤ x0 < x1 ≤ 1 and 0 ≤ y0 < y1 ≤ 1");
            memcpy(f.crop, c, sizeof c);
        }
    }
    f.filter = ftype;
    f.filter_radius = (float)fradius;
    /* The builder turns the crop into pixels ("film.crop: the window holds no pixel"). */
    return ts_scene_builder_set_film(ld->b, &f, ld->err);
}

static ts_status parse_camera(loader *ld, const cJSON *doc)
{
    const cJSON *cam;
    TRY(ts_json_object(doc, "", "camera", true, &cam, ld->err));
    static const char *const types[] = {"perspective", "orthographic", NULL};
    int type = 0;
    TRY(ts_json_enum(cam, "camera", "type", false, types, &type, ld->err));
    static const char *const pkeys[] = {"type", "from", "to", "up", "fov", "lens_radius", "focus_distance",
                                        "mirror", "screen_window", "medium", "shutter", "motion", NULL};
    static const char *const okeys[] = {"type", "from",         "to",     "up", "height", "lens_radius",
                                        "focus_distance", "mirror", "screen_window", "medium", "shutter",
                                        "motion", NULL};
    TRY(ts_json_check_object(cam, "camera", type == 0 ? pkeys : okeys, ld->err));
    ts_camera_desc d = {0};
    d.type = (ts_camera_type)type;
    d.up = (ts_vec3){0, 1, 0};
    TRY(ts_json_vec3(cam, "camera", "from", true, false, &d.from, ld->err));
    TRY(ts_json_vec3(cam, "camera", "to", true, false, &d.to, ld->err));
    TRY(ts_json_vec3(cam, "camera", "up", false, true, &d.up, ld->err));
    double fov = 45, lens = 0, focus = 1, height = 1;
    TRY(ts_json_bool(cam, "camera", "mirror", false, &d.mirror, ld->err));
    const cJSON *win;
    TRY(ts_json_array(cam, "camera", "screen_window", false, &win, ld->err));
    if (win) {
        int n = 0;
        for (const cJSON *v = win->child; v; v = v->next) {
            if (n >= 4 || !cJSON_IsNumber(v) || !isfinite((float)v->valuedouble)) n = 5;
            else d.screen_window[n++] = (float)v->valuedouble;
            if (n == 5) break;
        }
        if (n != 4 || !(d.screen_window[0] < d.screen_window[1]) || !(d.screen_window[2] < d.screen_window[3]))
            return ts_error_set(ld->err, TS_ERR_INVALID,
                                "camera.screen_window: expected [x0, x1, y0, y1] with x0 < x1 and y0 < y1");
        d.has_window = true;
    }
    TRY(ts_json_number(cam, "camera", "lens_radius", false, TS_J_NONNEG, &lens, ld->err));
    TRY(ts_json_number(cam, "camera", "focus_distance", false, TS_J_POSITIVE, &focus, ld->err));
    if (type == 0) {
        TRY(ts_json_number(cam, "camera", "fov", false, TS_J_POSITIVE, &fov, ld->err));
        if (!((float)fov < 180)) /* as the float it becomes: 179.999999 is 180 */
            return ts_error_set(ld->err, TS_ERR_INVALID,
                                "camera.fov: expected an angle in (0, 180) degrees, got %.9g%s", fov,
                                fov < 180 ? " (180 as a float)" : "");
    } else {
        TRY(ts_json_number(cam, "camera", "height", !win, TS_J_POSITIVE, &height, ld->err));
    }
    d.fov_deg = (float)fov;
    d.lens_radius = (float)lens;
    d.focus_distance = (float)focus;
    d.ortho_height = (float)height;
    /* Motion blur: the shutter (pbrt-v3's shutteropen/close) and the camera-to-world
     * keyframes: a ray made by the frame above moves by M(t)·start⁻¹ (camera.h). */
    double open = 0, close = 1;
    TRY(parse_interval(ld, cam, "camera", "shutter", &open, &close));
    d.shutter_open = (float)open;
    d.shutter_close = (float)close;
    const cJSON *mo;
    TRY(ts_json_object(cam, "camera", "motion", false, &mo, ld->err));
    if (mo) {
        static const char *const mkeys[] = {"times", "start", "end", NULL};
        TRY(ts_json_check_object(mo, "camera.motion", mkeys, ld->err));
        d.motion_t0 = 0, d.motion_t1 = 1;
        TRY(parse_interval(ld, mo, "camera.motion", "times", &d.motion_t0, &d.motion_t1));
        TRY(parse_transform_key(ld, mo, "camera.motion", "start", true, &d.motion_start));
        TRY(parse_transform_key(ld, mo, "camera.motion", "end", true, &d.motion_end));
        d.moving = true;
    }
    /* The builder runs ts_camera_init's checks ("camera.up: must not be parallel …"). */
    TRY(ts_scene_builder_set_camera(ld->b, &d, ld->err));
    uint32_t medium = TS_NONE;
    TRY(medium_ref(ld, cam, "camera", "medium", &medium));
    return ts_scene_builder_set_camera_medium(ld->b, medium, ld->err);
}

static ts_status parse_sampler(loader *ld, const cJSON *doc)
{
    ts_sampler sampler = {TS_SAMPLER_SOBOL, 0};
    int64_t spp = 16, seed = 0;
    const cJSON *smp;
    TRY(ts_json_object(doc, "", "sampler", false, &smp, ld->err));
    if (smp) {
        static const char *const keys[] = {"type", "spp", "seed", NULL};
        static const char *const types[] = {"sobol", "independent", NULL};
        TRY(ts_json_check_object(smp, "sampler", keys, ld->err));
        int type = 0;
        TRY(ts_json_enum(smp, "sampler", "type", false, types, &type, ld->err));
        TRY(ts_json_int(smp, "sampler", "spp", false, 1, ld->lim->max_spp, &spp, ld->err));
        TRY(ts_json_int(smp, "sampler", "seed", false, 0, UINT32_MAX, &seed, ld->err));
        sampler.type = (ts_sampler_type)type;
        sampler.seed = (uint32_t)seed;
    }
    return ts_scene_builder_set_sampler(ld->b, &sampler, (uint32_t)spp, ld->err);
}

static ts_status parse_integrator(loader *ld, const cJSON *doc)
{
    ts_integrator_desc desc = ts_integrator_desc_default();
    ts_integrator_desc *in = &desc;
    const cJSON *it;
    TRY(ts_json_object(doc, "", "integrator", false, &it, ld->err));
    if (!it) {
        in->light_sampling = TS_LIGHT_SELECT_AUTO; /* path's default (scene.h) */
        return ts_scene_builder_set_integrator(ld->b, in, ld->err);
    }
    static const char *const types[] = {"path", "direct", "ao", "normals", "volpath", NULL};
    int type = 0;
    TRY(ts_json_enum(it, "integrator", "type", true, types, &type, ld->err));
    in->type = (ts_integrator_type)type;
    static const char *const path_keys[] = {"type", "max_depth", "rr_depth", "light_sampling", "sampling", NULL};
    static const char *const direct_keys[] = {"type",    "strategy",          "light_sampling", "max_depth",
                                              "samples_per_light", "sampling", NULL};
    static const char *const ao_keys[] = {"type", "max_distance", NULL};
    static const char *const normals_keys[] = {"type", NULL};
    static const char *const volpath_keys[] = {"type", "max_depth", "rr_depth", "light_sampling", NULL};
    const char *const *keys[] = {path_keys, direct_keys, ao_keys, normals_keys, volpath_keys};
    TRY(ts_json_check_object(it, "integrator", keys[type], ld->err));
    int64_t v;
    if (in->type == TS_INTEGRATOR_PATH || in->type == TS_INTEGRATOR_DIRECT) {
        static const char *const sampling[] = {"mis", "light", "bsdf", NULL};
        int k = 0;
        TRY(ts_json_enum(it, "integrator", "sampling", false, sampling, &k, ld->err));
        in->sampling = (ts_direct_sampling)k;
    }
    switch (in->type) {
    case TS_INTEGRATOR_PATH:
    case TS_INTEGRATOR_VOLPATH: {
        v = in->max_depth; /* the ranges: scene/scene.h */
        TRY(ts_json_int(it, "integrator", "max_depth", false, 0, TS_PATH_DEPTH_MAX, &v, ld->err));
        in->max_depth = (int)v;
        v = in->rr_depth;
        TRY(ts_json_int(it, "integrator", "rr_depth", false, 0, TS_PATH_DEPTH_MAX, &v, ld->err));
        in->rr_depth = (int)v;
        static const char *const sel[] = {"uniform", "power", "spatial", "bvh", NULL};
        int k = 1;
        TRY(ts_json_enum(it, "integrator", "light_sampling", false, sel, &k, ld->err));
        in->light_sampling = cJSON_GetObjectItemCaseSensitive(it, "light_sampling") ? (ts_light_selection)k
                                                                                     : TS_LIGHT_SELECT_AUTO;
        break;
    }
    case TS_INTEGRATOR_DIRECT: {
        static const char *const strat[] = {"all", "one", NULL};
        int k = 0;
        TRY(ts_json_enum(it, "integrator", "strategy", false, strat, &k, ld->err));
        in->strategy = (ts_light_strategy)k;
        /* Strategy one's light selection: uniform (pbrt-v3's directlighting), power or the
         * light hierarchy (no spatial: its voxels are path's). */
        static const char *const sel[] = {"uniform", "power", "bvh", NULL};
        static const ts_light_selection sel_of[] = {TS_LIGHT_SELECT_UNIFORM, TS_LIGHT_SELECT_POWER,
                                                    TS_LIGHT_SELECT_BVH};
        k = 1;
        TRY(ts_json_enum(it, "integrator", "light_sampling", false, sel, &k, ld->err));
        in->light_sampling = sel_of[k];
        v = in->max_depth;
        TRY(ts_json_int(it, "integrator", "max_depth", false, 0, TS_DIRECT_DEPTH_MAX, &v, ld->err));
        in->max_depth = (int)v;
        v = 1;
        TRY(ts_json_int(it, "integrator", "samples_per_light", false, 1, TS_LIGHT_SAMPLES_MAX, &v, ld->err));
        in->samples_per_light = (int)v;
        break;
    }
    case TS_INTEGRATOR_AO: {
        double d = INFINITY;
        TRY(ts_json_number(it, "integrator", "max_distance", false, TS_J_POSITIVE, &d, ld->err));
        in->ao_distance = (float)d;
        break;
    }
    case TS_INTEGRATOR_NORMALS: break;
    }
    return ts_scene_builder_set_integrator(ld->b, in, ld->err);
}

static ts_status parse_job(loader *ld, const cJSON *doc)
{
    ts_job_desc desc = {0}, *j = &desc;
    const cJSON *job;
    TRY(ts_json_object(doc, "", "job", false, &job, ld->err));
    if (!job) return TS_OK;
    static const char *const keys[] = {"name",    "priority",       "spp",      "time_limit_s", "target_error",
                                       "effects", "display_server", "adaptive", NULL};
    TRY(ts_json_check_object(job, "job", keys, ld->err));
    const cJSON *fx;
    TRY(ts_json_object(job, "job", "effects", false, &fx, ld->err));
    for (const cJSON *e = fx ? fx->child : NULL; e; e = e->next) {
        ts_jpath p = ts_jpath_key("job.effects", e->string);
        uint32_t bit = ts_effect_from_key(e->string);
        if (!bit) {
            char keys_text[400];
            ts_effects_format(TS_EFFECTS_ALL, keys_text, sizeof keys_text);
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: unknown effect (effects are: %s)", p.s, keys_text);
        }
        if (!cJSON_IsBool(e)) {
            char d[64];
            ts_json_describe(e, d, sizeof d);
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected true or false, got %s", p.s, d);
        }
        /* Switching a light type or a lobe off consistently would need the light
         * distribution and materials rebuilt; these two are switched off exactly. */
        if (cJSON_IsFalse(e) && bit != TS_EFFECT_INDIRECT && bit != TS_EFFECT_DEPTH_OF_FIELD)
            return ts_error_set(ld->err, TS_ERR_INVALID,
                                "%s: only 'indirect' and 'depth_of_field' can be switched off", p.s);
        if (cJSON_IsFalse(e)) j->effects_off |= bit;
    }
    const char *name = NULL;
    TRY(ts_json_string(job, "job", "name", false, &name, ld->err));
    j->name = name; /* copied by the builder */
    int64_t v = 0;
    TRY(ts_json_int(job, "job", "priority", false, -1000000, 1000000, &v, ld->err));
    j->priority = (int)v;
    v = 0;
    TRY(ts_json_int(job, "job", "spp", false, 1, ld->lim->max_spp, &v, ld->err));
    j->spp = (uint32_t)v;
    TRY(ts_json_number(job, "job", "time_limit_s", false, TS_J_POSITIVE, &j->time_limit_s, ld->err));
    TRY(ts_json_number(job, "job", "target_error", false, TS_J_POSITIVE, &j->target_error, ld->err));
    TRY(ts_json_bool(job, "job", "adaptive", false, &j->adaptive, ld->err));
    TRY(ts_json_string(job, "job", "display_server", false, &j->display_server, ld->err)); /* checked and copied by the builder */
    return ts_scene_builder_set_job(ld->b, j, ld->err);
}

/* ---------------------------------------------------------------- materials */

/* The range of a material parameter as the JSON checks name it (material_desc.h): the
 * angle's upper bound is checked after. */
static ts_jrange jrange_of(ts_mparam_range r)
{
    switch (r) {
    case TS_MRANGE_UNIT: return TS_J_UNIT;
    case TS_MRANGE_POSITIVE: return TS_J_POSITIVE;
    case TS_MRANGE_NONNEG:
    case TS_MRANGE_ANGLE: return TS_J_NONNEG;
    }
    return TS_J_ANY;
}

/* One parameter of the type's table (material_desc.h): its kind, range and default there. */
static ts_status parse_material_param(loader *ld, const cJSON *m, const char *path, const ts_material_param *p,
                                      ts_material *out)
{
    const ts_json_textures *tx = &ld->textures;
    ts_jrange range = jrange_of(p->range);
    switch (p->kind) {
    case TS_MPARAM_RGB: {
        ts_material_rgb *dst = ts_mparam_rgb(out, p);
        /* A required one absent gets ts_json_rgb's "required but missing". */
        if ((p->flags & TS_MPARAM_REQUIRED) && !cJSON_GetObjectItemCaseSensitive(m, p->key))
            TRY(ts_json_rgb(m, path, p->key, true, range, &dst->value, ld->err));
        return ts_json_material_rgb(tx, m, path, p->key, range, dst, ld->err);
    }
    case TS_MPARAM_FLOAT: {
        ts_material_float *dst = ts_mparam_float(out, p);
        TRY(ts_json_material_float(tx, m, path, p->key, range, dst, ld->err));
        if (p->range == TS_MRANGE_ANGLE && !dst->tex && dst->value > 90) {
            ts_jpath kp = ts_jpath_key(path, p->key);
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected %s, got %g", kp.s, ts_mrange_words(p->range, false),
                                cJSON_GetObjectItemCaseSensitive(m, p->key)->valuedouble);
        }
        return TS_OK;
    }
    case TS_MPARAM_ENUM: return ts_json_enum(m, path, p->key, false, p->names, ts_mparam_enum(out, p), ld->err);
    }
    return TS_OK;
}

/* A mix's "materials": the names of two materials defined before it. */
static ts_status parse_mix_names(loader *ld, const cJSON *m, const char *path, ts_material *out)
{
    const cJSON *list;
    TRY(ts_json_array(m, path, "materials", true, &list, ld->err));
    ts_jpath lp = ts_jpath_key(path, "materials");
    if (cJSON_GetArraySize(list) != 2)
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected the names of two materials, got %d values", lp.s,
                            cJSON_GetArraySize(list));
    for (int k = 0; k < 2; k++) {
        const cJSON *e = cJSON_GetArrayItem(list, k);
        ts_jpath ep = ts_jpath_index(lp.s, k);
        if (!cJSON_IsString(e)) {
            char d[64];
            ts_json_describe(e, d, sizeof d);
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected a material name, got %s", ep.s, d);
        }
        out->mix_id[k] = ts_scene_builder_find_material(ld->b, e->valuestring);
        if (out->mix_id[k] == TS_NONE)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: no material named \"%s\" before this one in 'materials'",
                                ep.s, e->valuestring);
    }
    return TS_OK;
}

/* A material: its type's description (materials/material_desc.h) says which keys it takes,
 * their kinds, ranges and defaults; the flags of the type the families a row cannot. */
static ts_status parse_material(loader *ld, const cJSON *m, const char *path, ts_material *out)
{
    const char *types[TS_MATERIAL_TYPE_COUNT + 1];
    for (int i = 0; i < TS_MATERIAL_TYPE_COUNT; i++)
        types[i] = ts_material_descs[i].name;
    types[TS_MATERIAL_TYPE_COUNT] = NULL;
    int type = 0;
    if (!cJSON_IsObject(m)) return ts_json_check_object(m, path, types, ld->err);
    const cJSON *tv = cJSON_GetObjectItemCaseSensitive(m, "type");
    if (cJSON_IsString(tv) && strcmp(tv->valuestring, "disney") == 0) {
        ts_jpath p = ts_jpath_key(path, "type");
        return ts_error_set(ld->err, TS_ERR_UNSUPPORTED, "%s: material 'disney' is not supported", p.s);
    }
    TRY(ts_json_enum(m, path, "type", true, types, &type, ld->err));
    const ts_material_desc *d = &ts_material_descs[type];

    /* The keys of this type: every type's three, its rows', its families'. */
    const char *keys[32];
    int n = 0;
    keys[n++] = "type";
    keys[n++] = "bumpmap";
    keys[n++] = "texture_clamp";
    for (int i = 0; i < d->n_params && n < 24; i++)
        keys[n++] = d->params[i].key;
    if (d->flags & TS_MDESC_ROUGH) {
        keys[n++] = "roughness";
        keys[n++] = "remap_roughness";
    }
    if (d->flags & TS_MDESC_ANISO) {
        keys[n++] = "uroughness";
        keys[n++] = "vroughness";
    }
    if (d->flags & TS_MDESC_FILE) keys[n++] = "file";
    if (d->flags & TS_MDESC_MIX) keys[n++] = "materials";
    keys[n] = NULL;
    TRY(ts_json_check_object(m, path, keys, ld->err));

    *out = (ts_material){0};
    out->type = d->type;
    ts_material_desc_defaults(out);
    static const char *const clamps[] = {"unit", "nonnegative", NULL};
    int clamp = 0;
    TRY(ts_json_enum(m, path, "texture_clamp", false, clamps, &clamp, ld->err));
    out->texture_clamp_nonneg = clamp == 1;
    /* Every type: pbrt-v3's bump map, the name of a float texture (docs/design.md §4d). */
    ts_material_float bump = {0, NULL};
    const cJSON *bv = cJSON_GetObjectItemCaseSensitive(m, "bumpmap");
    if (bv && !cJSON_IsString(bv)) {
        char desc[64];
        ts_json_describe(bv, desc, sizeof desc);
        ts_jpath bp = ts_jpath_key(path, "bumpmap");
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected the name of a float texture, got %s", bp.s, desc);
    }
    TRY(ts_json_material_float(&ld->textures, m, path, "bumpmap", TS_J_ANY, &bump, ld->err));
    out->bump = bump.tex;
    if (d->flags & TS_MDESC_MIX) TRY(parse_mix_names(ld, m, path, out));
    for (int i = 0; i < d->n_params; i++)
        TRY(parse_material_param(ld, m, path, &d->params[i], out));
    if (d->flags & TS_MDESC_FILE) {
        const char *file;
        TRY(ts_json_string(m, path, "file", true, &file, ld->err));
        ts_jpath fp = ts_jpath_key(path, "file");
        TRY(at(ts_scene_builder_load_fourier(ld->b, file, &out->fourier, ld->err), fp.s, ld->err));
    }
    if (d->flags & TS_MDESC_ROUGH) {
        TRY(ts_json_material_float(&ld->textures, m, path, "roughness", TS_J_NONNEG, &out->roughness, ld->err));
        TRY(ts_json_bool(m, path, "remap_roughness", false, &out->remap_roughness, ld->err));
    }
    if (d->flags & TS_MDESC_ANISO) {
        /* uroughness and vroughness each default to roughness (read only when present: an
         * absent key would reset a texture reference). */
        ts_material_float r = out->roughness;
        if (cJSON_GetObjectItemCaseSensitive(m, "uroughness"))
            TRY(ts_json_material_float(&ld->textures, m, path, "uroughness", TS_J_NONNEG, &out->roughness, ld->err));
        out->vroughness = r;
        if (cJSON_GetObjectItemCaseSensitive(m, "vroughness"))
            TRY(ts_json_material_float(&ld->textures, m, path, "vroughness", TS_J_NONNEG, &out->vroughness, ld->err));
        out->has_vroughness = out->vroughness.tex != out->roughness.tex || out->vroughness.value != out->roughness.value;
    }
    return TS_OK;
}

static ts_status parse_materials(loader *ld, const cJSON *doc)
{
    const cJSON *mats;
    TRY(ts_json_object(doc, "", "materials", false, &mats, ld->err));
    int n = mats ? cJSON_GetArraySize(mats) : 0;
    if ((uint32_t)n > ld->lim->max_materials)
        return ts_error_set(ld->err, TS_ERR_LIMIT, "materials: %d materials is more than the limit of %u", n,
                            ld->lim->max_materials);
    if (!mats) return TS_OK;
    for (const cJSON *m = mats->child; m; m = m->next) {
        ts_jpath p = ts_jpath_key("materials", m->string);
        if (ts_scene_builder_find_material(ld->b, m->string) != TS_NONE)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: material defined twice", p.s);
        ts_material mat;
        TRY(parse_material(ld, m, p.s, &mat));
        TRY(at(ts_scene_builder_add_material(ld->b, m->string, &mat, NULL, ld->err), p.s, ld->err));
    }
    return TS_OK;
}

/* ---------------------------------------------------------------- textures */

static ts_status parse_textures(loader *ld, const cJSON *doc)
{
    const cJSON *texs;
    TRY(ts_json_object(doc, "", "textures", false, &texs, ld->err));
    if (!texs) return TS_OK;
    for (const cJSON *t = texs->child; t; t = t->next) {
        ts_jpath p = ts_jpath_key("textures", t->string);
        if (ts_json_textures_find(&ld->textures, t->string))
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: texture defined twice", p.s);
        ts_xform to_world = ts_xform_identity();
        if (cJSON_IsObject(t)) TRY(parse_transform(ld, t, p.s, &to_world));
        TRY(ts_json_texture_parse(&ld->textures, ld->b, t, p.s, t->string, &to_world, ld->err));
    }
    return TS_OK;
}

/* ---------------------------------------------------------------- shapes */

/* Reads an array of numbers (multiple of `stride` entries) into malloc'd floats. */
static ts_status float_array(loader *ld, const cJSON *obj, const char *path, const char *key, int stride, bool required,
                             float **out, uint32_t *count)
{
    const cJSON *a;
    *out = NULL;
    *count = 0;
    TRY(ts_json_array(obj, path, key, required, &a, ld->err));
    if (!a) return TS_OK;
    ts_jpath ap = ts_jpath_key(path, key);
    int n = cJSON_GetArraySize(a);
    if (n == 0 || n % stride)
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected a non-empty array of numbers, a multiple of %d long, got %d",
                            ap.s, stride, n);
    float *f = malloc((size_t)n * sizeof *f);
    if (!f) return nomem(ld, ap.s);
    int i = 0;
    for (const cJSON *c = a->child; c; c = c->next, i++) {
        if (!cJSON_IsNumber(c) || !isfinite(c->valuedouble) || fabs(c->valuedouble) > 3.0e38) {
            ts_jpath ep = ts_jpath_index(ap.s, i);
            char d[64];
            ts_json_describe(c, d, sizeof d);
            free(f);
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected a finite number, got %s", ep.s, d);
        }
        f[i] = (float)c->valuedouble;
    }
    *out = f;
    *count = (uint32_t)(n / stride);
    return TS_OK;
}

/* Reads the mesh of shape sh, in object space, into *md (malloc'd arrays, inline or read from
 * a file, which the caller frees once the builder has copied them) and points mesh at them. */
static ts_status parse_mesh(loader *ld, const cJSON *sh, const char *path, ts_mesh_data *md, ts_mesh *mesh)
{
    const char *file = NULL;
    TRY(ts_json_string(sh, path, "file", false, &file, ld->err));
    if (file) {
        if (cJSON_GetObjectItemCaseSensitive(sh, "positions") || cJSON_GetObjectItemCaseSensitive(sh, "indices") ||
            cJSON_GetObjectItemCaseSensitive(sh, "normals") || cJSON_GetObjectItemCaseSensitive(sh, "uvs"))
            return ts_error_set(ld->err, TS_ERR_INVALID,
                                "%s: a mesh takes either 'file' or 'positions'/'indices', not both", path);
        /* The builder reads it within what is left of the scene's triangle budget. */
        ts_jpath fp = ts_jpath_key(path, "file");
        TRY(at(ts_scene_builder_load_mesh(ld->b, file, md, ld->err), fp.s, ld->err));
    } else {
        uint32_t nv = 0, nn = 0, nuv = 0;
        TRY(float_array(ld, sh, path, "positions", 3, true, &md->p, &nv));
        TRY(float_array(ld, sh, path, "normals", 3, false, &md->n, &nn));
        TRY(float_array(ld, sh, path, "uvs", 2, false, &md->uv, &nuv));
        md->n_vertices = nv;
        if (md->n && nn != nv)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s.normals: expected %u normals (one per position), got %u",
                                path, nv, nn);
        if (md->uv && nuv != nv)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s.uvs: expected %u uv pairs (one per position), got %u", path,
                                nv, nuv);
        const cJSON *ia;
        TRY(ts_json_array(sh, path, "indices", true, &ia, ld->err));
        int ni = cJSON_GetArraySize(ia);
        ts_jpath ip = ts_jpath_key(path, "indices");
        if (ni == 0 || ni % 3)
            return ts_error_set(ld->err, TS_ERR_INVALID,
                                "%s: expected a non-empty array of vertex indices, a multiple of 3 long, got %d", ip.s, ni);
        uint32_t nt = (uint32_t)(ni / 3);
        ts_scene_counts counts;
        ts_scene_builder_counts(ld->b, &counts);
        if (counts.triangles + nt > ld->lim->max_triangles)
            return ts_error_set(ld->err, TS_ERR_LIMIT, "%s: the scene's triangles exceed the limit of %llu", ip.s,
                                (unsigned long long)ld->lim->max_triangles);
        if (!(md->index = malloc((size_t)ni * sizeof *md->index))) return nomem(ld, ip.s);
        int i = 0;
        for (const cJSON *c = ia->child; c; c = c->next, i++) {
            if (!cJSON_IsNumber(c) || c->valuedouble != floor(c->valuedouble) || c->valuedouble < 0 ||
                c->valuedouble >= nv) {
                ts_jpath ep = ts_jpath_index(ip.s, i);
                char d[64];
                ts_json_describe(c, d, sizeof d);
                return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected a vertex index in [0, %u], got %s", ep.s,
                                    nv - 1, d);
            }
            md->index[i] = (uint32_t)c->valuedouble;
        }
        md->n_triangles = nt;
        const float *n = md->n;
        if (n)
            for (uint32_t k = 0; k < nv; k++) {
                float len = sqrtf(n[3 * k] * n[3 * k] + n[3 * k + 1] * n[3 * k + 1] + n[3 * k + 2] * n[3 * k + 2]);
                if (!(len > 0))
                    return ts_error_set(ld->err, TS_ERR_INVALID, "%s.normals[%u]: a normal must not be zero", path, k);
            }
    }
    *mesh = (ts_mesh){md->n_vertices, md->n_triangles, md->p, md->n, md->uv, md->index};
    return TS_OK;
}

/* The partial-quadric keys of shape sh (docs/design.md §4): any of z_min, z_max (spheres,
 * object space along the sphere's z, defaults ∓radius) and phi_max (degrees in (0, 360],
 * default 360) makes the shape partial; without them it is whole, as before. */
static ts_status parse_cut(loader *ld, const cJSON *sh, const char *path, double radius, ts_shape_cut *cut)
{
    *cut = (ts_shape_cut){0};
    const bool any = cJSON_GetObjectItemCaseSensitive(sh, "z_min") || cJSON_GetObjectItemCaseSensitive(sh, "z_max") ||
                     cJSON_GetObjectItemCaseSensitive(sh, "phi_max");
    if (!any) return TS_OK;
    double z_min = -radius, z_max = radius, phi_max = 360;
    TRY(ts_json_number(sh, path, "z_min", false, TS_J_ANY, &z_min, ld->err));
    TRY(ts_json_number(sh, path, "z_max", false, TS_J_ANY, &z_max, ld->err));
    TRY(ts_json_number(sh, path, "phi_max", false, TS_J_POSITIVE, &phi_max, ld->err));
    if (phi_max > 360) {
        ts_jpath pp = ts_jpath_key(path, "phi_max");
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected at most 360 degrees, got %g", pp.s, phi_max);
    }
    if (radius > 0 && !(fmin(fmax(z_min, -radius), radius) < fmin(fmax(z_max, -radius), radius))) {
        ts_jpath zp = ts_jpath_key(path, "z_max");
        return ts_error_set(ld->err, TS_ERR_INVALID,
                            "%s: expected more than z_min (%g) within [-radius, radius] ([%g, %g]), got %g", zp.s, z_min,
                            -radius, radius, z_max);
    }
    *cut = (ts_shape_cut){true, z_min, z_max, phi_max};
    return TS_OK;
}

/* A mesh's "alpha" or "shadow_alpha" (docs/design.md §4): a number in [0, 1], 0 cutting
 * the whole mesh out and any other leaving it opaque (pbrt-v3's test is alpha == 0), or the
 * name of a float texture. *out: the builder's texture (the constant 0 made here), or NULL. */
static ts_status parse_cutout(loader *ld, const cJSON *sh, const char *path, const char *key, const ts_texture **out)
{
    *out = NULL;
    if (!cJSON_GetObjectItemCaseSensitive(sh, key)) return TS_OK;
    ts_material_float f = ts_material_float_const(1);
    TRY(ts_json_material_float(&ld->textures, sh, path, key, TS_J_UNIT, &f, ld->err));
    if (f.tex || f.value != 0) {
        *out = f.tex;
        return TS_OK;
    }
    ts_texture zero = ts_texture_constant_float(0);
    ts_jpath p = ts_jpath_key(path, key);
    return at(ts_scene_builder_add_texture(ld->b, &zero, out, ld->err), p.s, ld->err);
}

/* A "curve" shape's keys (docs/design.md §4; pbrt-v3's curve parameters): points (its P,
 * object space), basis, degree, curve_type, normals (a ribbon's N), width (1) and width0,
 * width1 (defaulting to width). The arrays go into *arrays (the caller frees them); the
 * builder checks the counts against the basis and degree. */
static ts_status parse_curve(loader *ld, const cJSON *sh, const char *path, ts_mesh_data *arrays, ts_shape_desc *d)
{
    static const char *const bases[] = {"bezier", "bspline", NULL};
    static const char *const kinds[] = {"flat", "ribbon", "cylinder", NULL};
    int basis = 0, kind = 0;
    int64_t degree = 3;
    double width = 1, w0, w1;
    uint32_t np = 0, nn = 0;
    TRY(float_array(ld, sh, path, "points", 3, true, &arrays->p, &np));
    TRY(float_array(ld, sh, path, "normals", 3, false, &arrays->n, &nn));
    TRY(ts_json_enum(sh, path, "basis", false, bases, &basis, ld->err));
    TRY(ts_json_enum(sh, path, "curve_type", false, kinds, &kind, ld->err));
    TRY(ts_json_int(sh, path, "degree", false, 2, 3, &degree, ld->err));
    TRY(ts_json_number(sh, path, "width", false, TS_J_POSITIVE, &width, ld->err));
    w0 = w1 = width;
    TRY(ts_json_number(sh, path, "width0", false, TS_J_POSITIVE, &w0, ld->err));
    TRY(ts_json_number(sh, path, "width1", false, TS_J_POSITIVE, &w1, ld->err));
    d->curve.type = (ts_curve_type)kind;
    d->curve.basis = (ts_curve_basis)basis;
    d->curve.degree = (int)degree;
    d->curve.n_points = np;
    d->curve.p = arrays->p;
    d->curve.n_normals = nn;
    d->curve.n = arrays->n;
    d->curve.width0 = w0;
    d->curve.width1 = w1;
    return TS_OK;
}

/* Reads shape sh into *d (a mesh's arrays into *arrays, which the caller frees). */
/* A shape: *d with to_world = user ∘ place, user the shape's "transform" (*user_out) and
 * place the shape's own placement (a sphere's centre, a disk's frame, a cylinder's axis; the
 * identity for a mesh: *place_out), which a moving shape keeps inside its object. */
static ts_status parse_shape(loader *ld, const cJSON *sh, const char *path, ts_shape_desc *d, ts_mesh_data *arrays,
                             ts_xform *user_out, ts_xform *place_out)
{
    static const char *const types[] = {"sphere", "disk", "cylinder", "mesh", "loopsubdiv", "curve", NULL};
    if (!cJSON_IsObject(sh)) return ts_json_check_object(sh, path, types, ld->err);
    int type = 0;
    TRY(ts_json_enum(sh, path, "type", true, types, &type, ld->err));
#define COMMON "type", "material", "transform", "motion", "emission", "two_sided", "light_samples", "reverse_orientation", "medium"
    static const char *const k_sphere[] = {COMMON, "center", "radius", "z_min", "z_max", "phi_max", NULL};
    static const char *const k_disk[] = {COMMON, "center", "normal", "radius", "inner_radius", "phi_max", NULL};
    static const char *const k_cyl[] = {COMMON, "p0", "p1", "radius", "phi_max", NULL};
    static const char *const k_mesh[] = {COMMON, "positions", "indices", "normals", "uvs", "file", "alpha", "shadow_alpha", NULL};
    static const char *const k_subdiv[] = {COMMON, "positions", "indices", "levels", NULL};
    static const char *const k_curve[] = {COMMON, "points", "basis", "degree", "curve_type", "normals",
                                          "width", "width0", "width1", NULL};
#undef COMMON
    const char *const *keys[] = {k_sphere, k_disk, k_cyl, k_mesh, k_subdiv, k_curve};
    TRY(ts_json_check_object(sh, path, keys[type], ld->err));

    *d = (ts_shape_desc){0};
    const bool subdiv = type == 4; /* a loopsubdiv control mesh: refined into a mesh here */
    d->type = subdiv ? TS_SHAPE_MESH : type == 5 ? TS_SHAPE_CURVE : (ts_shape_type)type;
    const char *mat = NULL;
    const cJSON *mv = cJSON_GetObjectItemCaseSensitive(sh, "material");
    if (!cJSON_IsNull(mv)) TRY(ts_json_string(sh, path, "material", true, &mat, ld->err));
    d->material = mat ? ts_scene_builder_find_material(ld->b, mat) : TS_NONE; /* null: no surface */
    TRY(parse_shape_medium(ld, sh, path, d));
    if (mat && d->material == TS_NONE) {
        ts_jpath mp = ts_jpath_key(path, "material");
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: no material named \"%s\" in 'materials'", mp.s, mat);
    }
    d->emission = ts_rgb_gray(0);
    TRY(ts_json_rgb(sh, path, "emission", false, TS_J_NONNEG, &d->emission, ld->err));
    TRY(ts_json_bool(sh, path, "two_sided", false, &d->two_sided, ld->err));
    int64_t light_samples = 0; /* absent: the integrator's samples_per_light */
    TRY(ts_json_int(sh, path, "light_samples", false, 1, TS_LIGHT_SAMPLES_MAX, &light_samples, ld->err));
    d->light_samples = (uint32_t)light_samples;
    TRY(ts_json_bool(sh, path, "reverse_orientation", false, &d->reverse_orientation, ld->err));
    ts_xform user;
    TRY(parse_transform(ld, sh, path, &user));
    *user_out = user;
    *place_out = ts_xform_identity();

    /* Sizes go through float, as v1 has always stored them. */
    double radius = 1;
    ts_vec3 center = {0, 0, 0};
    switch (d->type) {
    case TS_SHAPE_SPHERE: {
        TRY(ts_json_vec3(sh, path, "center", false, false, &center, ld->err));
        TRY(ts_json_number(sh, path, "radius", true, TS_J_POSITIVE, &radius, ld->err));
        ts_xform place = ts_xform_translate(ts_dvec3_from(center));
        d->to_world = ts_xform_compose(&user, &place);
        *place_out = place;
        d->sphere.radius = (float)radius;
        TRY(parse_cut(ld, sh, path, d->sphere.radius, &d->cut));
        break;
    }
    case TS_SHAPE_DISK: {
        ts_vec3 normal = {0, 0, 1};
        double inner = 0;
        TRY(ts_json_vec3(sh, path, "center", false, false, &center, ld->err));
        TRY(ts_json_vec3(sh, path, "normal", false, true, &normal, ld->err));
        TRY(ts_json_number(sh, path, "radius", true, TS_J_POSITIVE, &radius, ld->err));
        TRY(ts_json_number(sh, path, "inner_radius", false, TS_J_NONNEG, &inner, ld->err));
        if (!(inner < radius)) {
            ts_jpath ip = ts_jpath_key(path, "inner_radius");
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected less than radius (%g), got %g", ip.s, radius, inner);
        }
        ts_xform place = ts_xform_frame(ts_dvec3_from(center), ts_dvec3_from(normal));
        d->to_world = ts_xform_compose(&user, &place);
        *place_out = place;
        d->disk.radius = (float)radius;
        d->disk.inner_radius = (float)inner;
        TRY(parse_cut(ld, sh, path, 0, &d->cut));
        break;
    }
    case TS_SHAPE_CYLINDER: {
        ts_vec3 p0, p1;
        TRY(ts_json_vec3(sh, path, "p0", true, false, &p0, ld->err));
        TRY(ts_json_vec3(sh, path, "p1", true, false, &p1, ld->err));
        TRY(ts_json_number(sh, path, "radius", true, TS_J_POSITIVE, &radius, ld->err));
        ts_dvec3 axis = ts_dvec3_sub(ts_dvec3_from(p1), ts_dvec3_from(p0));
        double h = ts_dvec3_length(axis);
        if (!(h > 0)) return ts_error_set(ld->err, TS_ERR_INVALID, "%s.p1: must differ from p0", path);
        ts_xform place = ts_xform_frame(ts_dvec3_from(p0), axis);
        d->to_world = ts_xform_compose(&user, &place);
        *place_out = place;
        d->cylinder.radius = (float)radius;
        d->cylinder.height = h;
        TRY(parse_cut(ld, sh, path, 0, &d->cut));
        if (d->cut.partial) d->cut.z_min = 0, d->cut.z_max = h; /* the tube from p0 to p1 */
        break;
    }
    case TS_SHAPE_MESH:
        d->to_world = user; /* the builder takes the vertices to world space */
        TRY(parse_mesh(ld, sh, path, arrays, &d->mesh));
        if (!subdiv) {
            TRY(parse_cutout(ld, sh, path, "alpha", &d->alpha));
            TRY(parse_cutout(ld, sh, path, "shadow_alpha", &d->shadow_alpha));
        }
        if (subdiv) {
            double levels = 3;
            TRY(ts_json_number(sh, path, "levels", false, TS_J_NONNEG, &levels, ld->err));
            ts_jpath lp = ts_jpath_key(path, "levels");
            if (levels != floor(levels) || levels > TS_SUBDIV_MAX_LEVELS)
                return ts_error_set(ld->err, TS_ERR_INVALID, "%s: expected an integer in [0, %d], got %g", lp.s,
                                    TS_SUBDIV_MAX_LEVELS, levels);
            ts_mesh_data fine = {0};
            TRY(at(ts_scene_builder_loop_subdivide(ld->b, &d->mesh, (uint32_t)levels, &fine, ld->err), path, ld->err));
            ts_mesh_data_free(arrays);
            *arrays = fine;
            d->mesh = (ts_mesh){fine.n_vertices, fine.n_triangles, fine.p, fine.n, fine.uv, fine.index};
        }
        break;
    case TS_SHAPE_CURVE:
        d->to_world = user; /* the builder takes the control points to world space */
        TRY(parse_curve(ld, sh, path, arrays, d));
        break;
    }
    return TS_OK;
}

static ts_status parse_shapes(loader *ld, const cJSON *doc)
{
    const cJSON *shapes;
    TRY(ts_json_array(doc, "", "shapes", false, &shapes, ld->err));
    int n = shapes ? cJSON_GetArraySize(shapes) : 0;
    if ((uint32_t)n > ld->lim->max_shapes)
        return ts_error_set(ld->err, TS_ERR_LIMIT, "shapes: %d shapes is more than the limit of %u", n, ld->lim->max_shapes);
    int i = 0;
    for (const cJSON *sh = shapes ? shapes->child : NULL; sh; sh = sh->next, i++) {
        ts_jpath p = ts_jpath_index("shapes", i);
        ts_shape_desc d;
        ts_mesh_data arrays = {0};
        ts_xform user, place, end;
        bool moving = false;
        double t0 = 0, t1 = 1;
        ts_status st = parse_shape(ld, sh, p.s, &d, &arrays, &user, &place);
        if (!st) st = parse_motion(ld, sh, p.s, &moving, &t0, &t1, &end);
        if (!st && moving) { /* pbrt-v3's animated shape: in its own space, under the motion */
            d.to_world = place;
            st = at(ts_scene_builder_add_moving_shape(ld->b, &d, &user, t0, &end, t1, NULL, ld->err), p.s, ld->err);
        } else if (!st) {
            st = at(ts_scene_builder_add_shape(ld->b, &d, NULL, ld->err), p.s, ld->err);
        }
        ts_mesh_data_free(&arrays);
        if (st) return st;
    }
    return TS_OK;
}

/* "objects": name → {"shapes": [shape, …]} (docs/design.md §4): each an object definition
 * whose shapes are in its own space. */
static ts_status parse_objects(loader *ld, const cJSON *doc)
{
    const cJSON *objs;
    TRY(ts_json_object(doc, "", "objects", false, &objs, ld->err));
    if (!objs) return TS_OK;
    for (const cJSON *o = objs->child; o; o = o->next) {
        ts_jpath p = ts_jpath_key("objects", o->string);
        static const char *const keys[] = {"shapes", NULL};
        TRY(ts_json_check_object(o, p.s, keys, ld->err));
        const cJSON *shapes;
        TRY(ts_json_array(o, p.s, "shapes", true, &shapes, ld->err));
        TRY(at(ts_scene_builder_begin_object(ld->b, o->string, NULL, ld->err), p.s, ld->err));
        int i = 0;
        for (const cJSON *sh = shapes->child; sh; sh = sh->next, i++) {
            ts_jpath sp = ts_jpath_index(ts_jpath_key(p.s, "shapes").s, i);
            ts_shape_desc d;
            ts_mesh_data arrays = {0};
            ts_xform user, place;
            ts_status st = parse_shape(ld, sh, sp.s, &d, &arrays, &user, &place);
            if (!st && cJSON_GetObjectItemCaseSensitive(sh, "motion"))
                st = ts_error_set(ld->err, TS_ERR_UNSUPPORTED,
                                  "%s.motion: a shape of an object cannot move (a moving shape is an instance of its "
                                  "own, and instances do not nest); move the object's instances instead",
                                  sp.s);
            if (!st) st = at(ts_scene_builder_add_shape(ld->b, &d, NULL, ld->err), sp.s, ld->err);
            ts_mesh_data_free(&arrays);
            if (st) return st;
        }
        TRY(at(ts_scene_builder_end_object(ld->b, ld->err), p.s, ld->err));
    }
    return TS_OK;
}

/* "instances": [{"object": name, "transform": […]}]: an object placed in the world. */
static ts_status parse_instances(loader *ld, const cJSON *doc)
{
    const cJSON *list;
    TRY(ts_json_array(doc, "", "instances", false, &list, ld->err));
    int i = 0;
    for (const cJSON *in = list ? list->child : NULL; in; in = in->next, i++) {
        ts_jpath p = ts_jpath_index("instances", i);
        static const char *const keys[] = {"object", "transform", "motion", NULL};
        TRY(ts_json_check_object(in, p.s, keys, ld->err));
        const char *name;
        TRY(ts_json_string(in, p.s, "object", true, &name, ld->err));
        uint32_t id = ts_scene_builder_find_object(ld->b, name);
        if (id == TS_NONE) {
            ts_jpath op = ts_jpath_key(p.s, "object");
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s: no object named \"%s\" in 'objects'", op.s, name);
        }
        ts_xform x, end;
        bool moving;
        double t0, t1;
        TRY(parse_transform(ld, in, p.s, &x));
        TRY(parse_motion(ld, in, p.s, &moving, &t0, &t1, &end));
        if (moving)
            TRY(at(ts_scene_builder_add_moving_instance(ld->b, id, &x, t0, &end, t1, ld->err), p.s, ld->err));
        else
            TRY(at(ts_scene_builder_add_instance(ld->b, id, &x, ld->err), p.s, ld->err));
    }
    return TS_OK;
}

/* One row of a light type's description (build/light_desc.h). */
static ts_status parse_light_param(loader *ld, const cJSON *l, const char *path, const ts_light_param *p,
                                   ts_light_desc *out)
{
    bool required = (p->flags & TS_LPARAM_REQUIRED) != 0;
    switch (p->kind) {
    case TS_LPARAM_POINT: {
        ts_vec3 *v = ts_lparam_point(out, p);
        *v = (ts_vec3){(float)p->def[0], (float)p->def[1], (float)p->def[2]};
        TRY(ts_json_vec3(l, path, p->key, required, false, v, ld->err));
        if ((p->flags & TS_LPARAM_NOT_FROM) && v->x == out->from.x && v->y == out->from.y && v->z == out->from.z)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s.%s: must differ from 'from'", path, p->key);
        return TS_OK;
    }
    case TS_LPARAM_RGB: {
        ts_rgb *c = ts_lparam_rgb(out, p);
        *c = ts_rgb_gray((float)p->def[0]);
        return ts_json_rgb(l, path, p->key, required, TS_J_NONNEG, c, ld->err);
    }
    case TS_LPARAM_ANGLE: {
        double *v = ts_lparam_angle(out, p);
        *v = p->def[0];
        bool upto = (p->flags & TS_LPARAM_UPTO_ANGLE) != 0;
        TRY(ts_json_number(l, path, p->key, required, upto ? TS_J_NONNEG : TS_J_POSITIVE, v, ld->err));
        if (!upto && *v > 180)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s.%s: expected at most 180 degrees, got %g", path, p->key, *v);
        if (upto && *v > out->cone_angle_deg)
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s.%s: expected at most cone_angle (%g), got %g", path,
                                p->key, out->cone_angle_deg, *v);
        return TS_OK;
    }
    }
    return TS_OK;
}

/* An infinite light: radiance, or a map with its scale; its transform and sample count. */
static ts_status parse_environment(loader *ld, const cJSON *l, const char *path, ts_light_desc *out)
{
    const char *map = NULL;
    TRY(ts_json_string(l, path, "map", false, &map, ld->err));
    bool has_radiance = cJSON_GetObjectItemCaseSensitive(l, "radiance") != NULL;
    if (map && has_radiance)
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: an infinite light takes either 'radiance' or 'map', not both", path);
    if (!map && !has_radiance)
        return ts_error_set(ld->err, TS_ERR_INVALID, "%s: an infinite light needs 'radiance' or 'map'", path);
    if (!map) {
        if (cJSON_GetObjectItemCaseSensitive(l, "scale"))
            return ts_error_set(ld->err, TS_ERR_INVALID, "%s.scale: only allowed with 'map'", path);
        TRY(ts_json_rgb(l, path, "radiance", true, TS_J_NONNEG, &out->color, ld->err));
    } else {
        out->color = ts_rgb_gray(1);
        TRY(ts_json_rgb(l, path, "scale", false, TS_J_NONNEG, &out->color, ld->err));
        ts_jpath mp = ts_jpath_key(path, "map");
        TRY(at(ts_scene_builder_load_envmap(ld->b, map, &out->map, ld->err), mp.s, ld->err));
    }
    TRY(parse_transform(ld, l, path, &out->to_world));
    int64_t samples = 0; /* absent: the integrator's samples_per_light */
    TRY(ts_json_int(l, path, "samples", false, 1, TS_LIGHT_SAMPLES_MAX, &samples, ld->err));
    out->samples = (uint32_t)samples;
    return TS_OK;
}

/* A light: its type's description (build/light_desc.h) says which keys it takes, their
 * kinds, ranges and defaults. */
static ts_status parse_light(loader *ld, const cJSON *l, const char *path, ts_light_desc *out)
{
    const char *types[TS_LIGHT_DESC_COUNT + 1];
    for (int i = 0; i < TS_LIGHT_DESC_COUNT; i++)
        types[i] = ts_light_descs[i].name;
    types[TS_LIGHT_DESC_COUNT] = NULL;
    if (!cJSON_IsObject(l)) return ts_json_check_object(l, path, types, ld->err);
    int type = 0;
    TRY(ts_json_enum(l, path, "type", true, types, &type, ld->err));
    const ts_light_type_desc *d = &ts_light_descs[type];
    const char *keys[16];
    int n = 0;
    keys[n++] = "type";
    for (int i = 0; i < d->n_params && n < 10; i++)
        keys[n++] = d->params[i].key;
    if (d->flags & TS_LDESC_ENVIRONMENT) {
        static const char *const env[] = {"radiance", "map", "scale", "transform", "samples"};
        for (size_t i = 0; i < sizeof env / sizeof *env; i++)
            keys[n++] = env[i];
    }
    keys[n] = NULL;
    TRY(ts_json_check_object(l, path, keys, ld->err));
    *out = (ts_light_desc){0};
    out->to_world = ts_xform_identity();
    out->type = d->type;
    for (int i = 0; i < d->n_params; i++)
        TRY(parse_light_param(ld, l, path, &d->params[i], out));
    if (d->flags & TS_LDESC_ENVIRONMENT) TRY(parse_environment(ld, l, path, out));
    return TS_OK;
}

static ts_status parse_lights(loader *ld, const cJSON *doc)
{
    const cJSON *lights;
    TRY(ts_json_array(doc, "", "lights", false, &lights, ld->err));
    int n = lights ? cJSON_GetArraySize(lights) : 0;
    /* Area lights: one per emissive analytic shape, one per triangle of an emissive mesh. */
    ts_scene_counts counts;
    ts_scene_builder_counts(ld->b, &counts);
    uint64_t n_area = counts.area_lights;
    if ((uint64_t)n + n_area > ld->lim->max_lights)
        return ts_error_set(ld->err, TS_ERR_LIMIT, "lights: %llu lights (with emitting triangles) is more than the limit of %u",
                            (unsigned long long)(n + n_area), ld->lim->max_lights);
    int i = 0;
    for (const cJSON *l = lights ? lights->child : NULL; l; l = l->next, i++) {
        ts_jpath p = ts_jpath_index("lights", i);
        ts_light_desc d;
        TRY(parse_light(ld, l, p.s, &d));
        TRY(at(ts_scene_builder_add_light(ld->b, &d, ld->err), p.s, ld->err));
    }
    return TS_OK;
}

/* ---------------------------------------------------------------- document */

static ts_status parse_document(loader *ld, const cJSON *doc)
{
    static const char *const keys[] = {"tessera", "name",   "camera",  "film",      "sampler", "integrator",
                                       "textures", "materials", "media", "shapes", "objects", "instances",
                                       "lights",  "job",     NULL};
    TRY(ts_json_check_object(doc, "", keys, ld->err));
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(doc, "tessera");
    if (!v)
        return ts_error_set(ld->err, TS_ERR_INVALID,
                            "tessera: required (the scene format version, 1) but missing: is this a tessera scene?");
    if (!cJSON_IsNumber(v) || v->valuedouble != 1) {
        char d[64];
        ts_json_describe(v, d, sizeof d);
        return ts_error_set(ld->err, TS_ERR_INVALID, "tessera: expected 1 (the scene format version), got %s", d);
    }
    const char *name = NULL;
    TRY(ts_json_string(doc, "", "name", false, &name, ld->err));
    if (name) {
        TRY(ts_scene_builder_set_name(ld->b, name, ld->err));
        ld->named = true;
    }
    TRY(parse_film(ld, doc));
    TRY(parse_media(ld, doc));
    TRY(parse_camera(ld, doc));
    TRY(parse_sampler(ld, doc));
    TRY(parse_integrator(ld, doc));
    TRY(parse_textures(ld, doc));
    TRY(parse_materials(ld, doc));
    TRY(parse_shapes(ld, doc));
    TRY(parse_objects(ld, doc));
    TRY(parse_instances(ld, doc));
    TRY(parse_lights(ld, doc));
    TRY(parse_job(ld, doc));
    return TS_OK;
}

ts_status ts_scene_load_text(const char *text, size_t len, const char *base_dir, const char *name,
                             const ts_scene_limits *limits, ts_scene **out, ts_error *err)
{
    *out = NULL;
    ts_scene_limits def;
    if (!limits) {
        ts_scene_limits_default(&def);
        limits = &def;
    }
    ts_error local;
    if (!err) err = &local;
    ts_error_clear(err);
    cJSON *doc = NULL;
    ts_status st = ts_json_parse(text, len, &doc, err);
    if (!st) st = ts_json_check_strings(doc, err);
    if (st) {
        cJSON_Delete(doc);
        return st;
    }
    ts_scene_builder *b = NULL;
    st = ts_scene_builder_create(limits, base_dir, &b, err);
    if (st) {
        cJSON_Delete(doc);
        return st;
    }
    loader ld = {b, limits, err, false, {0}};
    ts_json_textures_init(&ld.textures);
    st = parse_document(&ld, doc);
    ts_json_textures_fini(&ld.textures);
    if (!st) {
        char digest[TS_SCENE_DIGEST_HEX_LEN + 1];
        st = ts_scene_digest(doc, digest, err);
        if (!st) st = ts_scene_builder_set_digest(b, digest, err);
    }
    if (!st && !ld.named && name) st = ts_scene_builder_set_name(b, name, err);
    if (!st) st = ts_scene_builder_finish(b, out, err);
    if (st && !err->status) ts_error_set(err, st, "the scene could not be loaded");
    cJSON_Delete(doc);
    ts_scene_builder_destroy(b);
    return st;
}

ts_status ts_scene_load_file(const char *path, const ts_scene_limits *limits, ts_scene **out, ts_error *err)
{
    *out = NULL;
    ts_scene_limits def;
    if (!limits) {
        ts_scene_limits_default(&def);
        limits = &def;
    }
    char *text = NULL;
    size_t len = 0;
    ts_status st = ts_scene_path_read_file(path, limits->max_file_bytes, &text, &len, err);
    if (st) return st;
    char dir[PATH_MAX], name[256];
    ts_scene_path_split(path, dir, sizeof dir, name, sizeof name);
    st = ts_scene_load_text(text, len, dir, name, limits, out, err);
    free(text);
    return st;
}

const char *ts_scene_builtin_text(size_t *len)
{
    if (len) *len = ts_builtin_cornell_box_size;
    return ts_builtin_cornell_box;
}

ts_status ts_scene_load_builtin(const ts_scene_limits *limits, ts_scene **out, ts_error *err)
{
    return ts_scene_load_text(ts_builtin_cornell_box, ts_builtin_cornell_box_size, NULL, "cornell-box", limits, out,
                              err);
}
