/* texture_pbrt.c — pbrt-v3's Texture directives made into textures (see texture_pbrt.h). */
#include "pbrt3/texture_pbrt.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "pbrt3/pbrt_lexer.h"
#include "textures/noise.h"
#include "textures/texture_desc.h"
#include "textures/texture_image.h"

#define TRY(expr)                          \
    do {                                   \
        ts_status st_ = (expr);            \
        if (st_ != TS_OK) return st_;      \
    } while (0)

/* What the making of one texture needs to word its errors. */
typedef struct maker {
    const ts_texture_pbrt *tp;
    ts_pbrt_texture *def; /* the Texture directive */
    ts_pbrt_params *ps;
    bool rgb;
} maker;

/* "<file>:<line>:<column>: Texture \"name\": <text>" */
static ts_status tex_error(const maker *m, ts_error *err, ts_status st, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static ts_status tex_error(const maker *m, ts_error *err, ts_status st, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    ts_status r = ts_error_set(err, st, "%s:%u:%u: Texture \"%s\": %s", m->def->loc.file, m->def->loc.line,
                               m->def->loc.column, m->def->name, msg);
    /* The names in it (a class, a file) are the scene's bytes: one clean UTF-8 sentence. */
    if (err) ts_pbrt_sanitize_utf8(err->message);
    return r;
}

static ts_status make(const ts_texture_pbrt *tp, const ts_texture *proto, const ts_texture **out,
                      ts_error *err)
{
    return ts_texture_make(tp->arena, proto, out, err);
}

/* A texture-valued parameter (pbrt-v3's GetFloatTexture / GetSpectrumTexture). */
static ts_status param_texture(const ts_texture_pbrt *tp, ts_pbrt_params *ps, const char *name, bool want_rgb,
                               ts_rgb def, const ts_texture **out, ts_error *err)
{
    *out = NULL;
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    ts_texture proto;
    ts_status st;
    if (p && p->type == TS_PBRT_PARAM_TEXTURE) {
        int32_t idx = want_rgb ? p->texture_spectrum : p->texture_float;
        if (idx < 0)
            return ts_pbrt_param_error(ps, p, err, TS_ERR_INVALID,
                                       "names texture \"%s\", a %s texture, where a %s texture is needed",
                                       p->strings[0], want_rgb ? "float" : "color",
                                       want_rgb ? "color" : "float");
        if ((size_t)idx >= tp->count || !tp->textures[idx])
            return ts_pbrt_param_error(ps, p, err, TS_ERR_INTERNAL,
                                       "names texture \"%s\", which is not made yet", p->strings[0]);
        *out = tp->textures[idx];
        return TS_OK;
    }
    if (want_rgb) {
        ts_rgb v;
        if ((st = ts_pbrt_find_rgb(ps, name, def, &v, err))) return st;
        if (!ts_rgb_is_finite(v)) return ts_pbrt_param_error(ps, p, err, TS_ERR_INVALID, "must be finite");
        proto = ts_texture_constant_rgb(v);
    } else {
        float v;
        if ((st = ts_pbrt_find_float(ps, name, def.r, &v, err))) return st;
        if (!isfinite(v)) return ts_pbrt_param_error(ps, p, err, TS_ERR_INVALID, "must be finite");
        proto = ts_texture_constant_float(v);
    }
    return make(tp, &proto, out, err);
}

ts_status ts_texture_pbrt_float(const ts_texture_pbrt *tp, ts_pbrt_params *ps, const char *name, float def,
                                const ts_texture **out, ts_error *err)
{
    return param_texture(tp, ps, name, false, ts_rgb_gray(def), out, err);
}

ts_status ts_texture_pbrt_rgb(const ts_texture_pbrt *tp, ts_pbrt_params *ps, const char *name, ts_rgb def,
                              const ts_texture **out, ts_error *err)
{
    return param_texture(tp, ps, name, true, def, out, err);
}

static ts_status child(const maker *m, const char *name, float def, const ts_texture **out, ts_error *err)
{
    return param_texture(m->tp, m->ps, name, m->rgb, ts_rgb_gray(def), out, err);
}

/* A float parameter that must be finite. */
static ts_status find_finite(const maker *m, const char *name, float def, float *out, ts_error *err)
{
    ts_status st = ts_pbrt_find_float(m->ps, name, def, out, err);
    if (st) return st;
    if (!isfinite(*out))
        return ts_pbrt_param_error(m->ps, ts_pbrt_params_get(m->ps, name), err, TS_ERR_INVALID,
                                   "must be finite");
    return TS_OK;
}

static ts_status find_octaves(const maker *m, int *octaves, float *omega, ts_error *err)
{
    int32_t oct;
    ts_status st = ts_pbrt_find_int(m->ps, "octaves", 8, &oct, err);
    if (st) return st;
    if (oct < 0 || oct > TS_NOISE_MAX_OCTAVES)
        return ts_pbrt_param_error(m->ps, ts_pbrt_params_get(m->ps, "octaves"), err, TS_ERR_INVALID,
                                   "must be 0 … %d (tessera's bound on a lookup's cost), got %d",
                                   TS_NOISE_MAX_OCTAVES, (int)oct);
    *octaves = (int)oct;
    return find_finite(m, "roughness", 0.5f, omega, err);
}

/* A string parameter that must be one of the listed words; *index gets its position. */
static ts_status find_choice(const maker *m, const char *name, const char *const *words, int n, int *index,
                             ts_error *err)
{
    const char *v;
    ts_status st = ts_pbrt_find_string(m->ps, name, words[0], &v, err);
    if (st) return st;
    for (int i = 0; i < n; i++)
        if (strcmp(v, words[i]) == 0) {
            *index = i;
            return TS_OK;
        }
    char list[160] = "";
    for (int i = 0; i < n; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s\"%s\"",
                 i == 0       ? ""
                 : i == n - 1 ? " or "
                              : ", ",
                 words[i]);
    return ts_pbrt_param_error(m->ps, ts_pbrt_params_get(m->ps, name), err, TS_ERR_INVALID,
                               "must be %s, got \"%s\"", list, v);
}

static ts_status map2d(const maker *m, ts_texture_mapping2d *out, ts_error *err)
{
    static const char *const kinds[] = {"uv", "spherical", "cylindrical", "planar"};
    int kind = 0;
    ts_status st = find_choice(m, "mapping", kinds, 4, &kind, err);
    if (st) return st;
    if (kind == 0) {
        float su, sv, du, dv;
        if ((st = find_finite(m, "uscale", 1, &su, err)) || (st = find_finite(m, "vscale", 1, &sv, err)) ||
            (st = find_finite(m, "udelta", 0, &du, err)) || (st = find_finite(m, "vdelta", 0, &dv, err)))
            return st;
        *out = ts_texture_mapping2d_uv(su, sv, du, dv);
    } else if (kind == 3) {
        ts_vec3 v1, v2;
        float du, dv;
        if ((st = ts_pbrt_find_vector3(m->ps, "v1", (ts_vec3){1, 0, 0}, &v1, err)) ||
            (st = ts_pbrt_find_vector3(m->ps, "v2", (ts_vec3){0, 1, 0}, &v2, err)) ||
            (st = find_finite(m, "udelta", 0, &du, err)) || (st = find_finite(m, "vdelta", 0, &dv, err)))
            return st;
        if (!ts_vec3_is_finite(v1) || !ts_vec3_is_finite(v2))
            return tex_error(m, err, TS_ERR_INVALID, "\"v1\" and \"v2\" must be finite");
        *out = ts_texture_mapping2d_planar(v1, v2, du, dv);
    } else {
        ts_mat4 inv;
        if (!ts_mat4_invert(m->def->texture_to_world, &inv))
            return tex_error(m, err, TS_ERR_INVALID,
                             "the %s mapping needs an invertible transformation, and this "
                             "texture's is singular",
                             kinds[kind]);
        *out = kind == 1 ? ts_texture_mapping2d_spherical(&inv) : ts_texture_mapping2d_cylindrical(&inv);
    }
    return TS_OK;
}

/* pbrt-v3's IdentityMapping3D(tex2world): the CTM taken as world→texture. */
static ts_texture_mapping3d map3d(const maker *m)
{
    return (ts_texture_mapping3d){*m->def->texture_to_world};
}

static ts_status make_imagemap(const maker *m, ts_texture *t, ts_error *err)
{
    ts_status st;
    float max_aniso, scale;
    bool trilinear, invert, gamma;
    int wrap = 0;
    static const char *const wraps[] = {"repeat", "black", "clamp"};
    if ((st = find_finite(m, "maxanisotropy", 8, &max_aniso, err)) ||
        (st = ts_pbrt_find_bool(m->ps, "trilinear", false, &trilinear, err)) ||
        (st = find_choice(m, "wrap", wraps, 3, &wrap, err)) ||
        (st = find_finite(m, "scale", 1, &scale, err)) ||
        (st = ts_pbrt_find_bool(m->ps, "invert", false, &invert, err)))
        return st;
    if (!(max_aniso > 0 && max_aniso <= TS_MIPMAP_MAX_ANISOTROPY))
        return ts_pbrt_param_error(m->ps, ts_pbrt_params_get(m->ps, "maxanisotropy"), err, TS_ERR_INVALID,
                                   "must be in (0, %g] (tessera's bound on an EWA lookup's cost), got %g",
                                   (double)TS_MIPMAP_MAX_ANISOTROPY, (double)max_aniso);
    ts_pbrt_param *fp = ts_pbrt_params_get(m->ps, "filename");
    const char *filename = NULL;
    if ((st = ts_pbrt_find_string(m->ps, "filename", NULL, &filename, err))) return st;
    if (!filename) return tex_error(m, err, TS_ERR_INVALID, "an imagemap texture needs \"string filename\"");
    if ((st = ts_pbrt_find_bool(m->ps, "gamma", ts_texture_image_default_gamma(filename), &gamma, err)))
        return st;
    ts_texture_image_options opt = {
        .n_channels = m->rgb ? 3 : 1, .gamma = gamma, .scale = scale, .wrap = (ts_texture_wrap)wrap};
    const ts_mipmap *map = NULL;
    st =
        ts_texture_cache_get(m->tp->cache, m->tp->base_dir, filename, m->tp->max_file_bytes, &opt, &map, err);
    if (st) {
        ts_error_prefix(err, "%s:%u:%u: Texture \"%s\": \"string filename\"", fp->loc.file, fp->loc.line,
                        fp->loc.column, m->def->name);
        return st;
    }
    t->image.mipmap = map;
    t->image.trilinear = trilinear;
    t->image.max_anisotropy = max_aniso;
    t->image.invert = invert;
    return TS_OK;
}

/* One row of the type's description (textures/texture_desc.h) as pbrt-v3 reads it: a
 * texture parameter, a value (read as a value, FindFloat / FindSpectrum), a finite number. */
static ts_status texture_param(const maker *m, const ts_texture_param *p, ts_texture *t, ts_error *err)
{
    switch (p->kind) {
    case TS_TPARAM_CHILD: return child(m, p->pbrt3, p->pbrt3_def, ts_tparam_texture(t, p), err);
    case TS_TPARAM_AMOUNT:
        return param_texture(m->tp, m->ps, p->pbrt3, false, ts_rgb_gray(p->pbrt3_def), ts_tparam_texture(t, p), err);
    case TS_TPARAM_VALUE: {
        ts_rgb *dst = ts_tparam_rgb(t, p);
        if (m->rgb) return ts_pbrt_find_rgb(m->ps, p->pbrt3, ts_rgb_gray(p->pbrt3_def), dst, err);
        float v;
        TRY(ts_pbrt_find_float(m->ps, p->pbrt3, p->pbrt3_def, &v, err));
        *dst = ts_rgb_gray(v);
        return TS_OK;
    }
    case TS_TPARAM_NUMBER: return find_finite(m, p->pbrt3, p->pbrt3_def, ts_tparam_float(t, p), err);
    case TS_TPARAM_OCTAVES: return find_octaves(m, ts_tparam_octaves(t, p), ts_tparam_omega(t, p), err);
    }
    return TS_OK;
}

/* pbrt-v3's Texture def: the type whose description names its class (a checkerboard by
 * its "dimension"), read row by row. */
static ts_status make_one(const ts_texture_pbrt *tp, ts_pbrt_texture *def, const ts_texture **out,
                          ts_error *err)
{
    maker m = {.tp = tp, .def = def, .ps = &def->params, .rgb = !def->is_float};
    const char *cls = def->class_name;
    ts_status st = TS_OK;
    if (strcmp(cls, "ptex") == 0)
        return tex_error(
            &m, err, TS_ERR_UNSUPPORTED,
            "ptex textures are not supported (image textures are read from .exr, .png, .tga and .pfm "
            "files)");
    const ts_texture_desc *d = ts_texture_desc_by_pbrt3(cls, 2);
    if (!d) return tex_error(&m, err, TS_ERR_INVALID, "unknown texture class \"%s\"", cls);
    if (d->flags & TS_TDESC_RGB_ONLY && !m.rgb)
        return tex_error(&m, err, TS_ERR_INVALID,
                         "the %s texture is a color texture in pbrt-v3 (declare it "
                         "\"color\" or \"spectrum\", not \"float\")",
                         cls);
    if (d->dimension) {
        int32_t dim;
        TRY(ts_pbrt_find_int(m.ps, "dimension", 2, &dim, err));
        if (dim != 2 && dim != 3)
            return ts_pbrt_param_error(m.ps, ts_pbrt_params_get(m.ps, "dimension"), err, TS_ERR_INVALID,
                                       "must be 2 or 3, got %d", (int)dim);
        d = ts_texture_desc_by_pbrt3(cls, dim);
    }
    ts_texture t = {.is_rgb = m.rgb, .type = d->type};
    for (int i = 0; i < d->n_params; i++)
        TRY(texture_param(&m, &d->params[i], &t, err));
    if (d->flags & TS_TDESC_CONSTANT)
        t = m.rgb ? ts_texture_constant_rgb(t.constant.value) : ts_texture_constant_float(t.constant.value.r);
    if (d->flags & TS_TDESC_MAP2D) TRY(map2d(&m, ts_tdesc_map2d(&t, d), err));
    if (d->flags & TS_TDESC_MAP3D) *ts_tdesc_map3d(&t, d) = map3d(&m);
    if (d->flags & TS_TDESC_AAMODE) {
        static const char *const modes[] = {"closedform", "none"};
        int mode = 0;
        TRY(find_choice(&m, "aamode", modes, 2, &mode, err));
        t.checkerboard2d.closed_form = mode == 0;
    }
    if (d->flags & TS_TDESC_IMAGE) TRY(make_imagemap(&m, &t, err));
    if ((st = make(tp, &t, out, err))) {
        if (st != TS_ERR_NOMEM) {
            char msg[TS_ERROR_MAX];
            memcpy(msg, err ? err->message : "", err ? sizeof msg : 1);
            return tex_error(&m, err, st, "%s", msg);
        }
        return st;
    }
    return TS_OK;
}

ts_status ts_texture_pbrt_build(ts_texture_pbrt *tp, ts_pbrt_scene *scene, ts_arena *arena,
                                ts_texture_cache *cache, const char *base_dir, uint64_t max_file_bytes,
                                ts_error *err)
{
    *tp = (ts_texture_pbrt){.arena = arena,
                            .cache = cache,
                            .base_dir = base_dir,
                            .max_file_bytes = max_file_bytes,
                            .scene = scene};
    if (scene->texture_count == 0) return TS_OK;
    tp->textures = ts_arena_calloc(arena, scene->texture_count, sizeof *tp->textures);
    if (!tp->textures)
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for %zu textures", scene->texture_count);
    tp->count = scene->texture_count;
    for (size_t i = 0; i < scene->texture_count; i++) {
        ts_status st = make_one(tp, &scene->textures[i], &tp->textures[i], err);
        if (st) return st;
    }
    return TS_OK;
}
