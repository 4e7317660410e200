/* texture_pbrt.c — pbrt-v3's Texture directives made into textures (see texture_pbrt.h). */
#include "pbrt3/texture_pbrt.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "pbrt3/pbrt_lexer.h"
#include "textures/noise.h"
#include "textures/texture_image.h"

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
    if ((st = map2d(m, &t->image.map, err))) return st;
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

static ts_status make_one(const ts_texture_pbrt *tp, ts_pbrt_texture *def, const ts_texture **out,
                          ts_error *err)
{
    maker m = {.tp = tp, .def = def, .ps = &def->params, .rgb = !def->is_float};
    ts_texture t = {.is_rgb = m.rgb};
    const char *cls = def->class_name;
    ts_status st = TS_OK;
    if (strcmp(cls, "constant") == 0) {
        /* pbrt-v3 reads "value" as a value here (FindFloat / FindSpectrum), not a texture. */
        if (m.rgb) {
            ts_rgb v;
            if ((st = ts_pbrt_find_rgb(m.ps, "value", ts_rgb_gray(1), &v, err))) return st;
            t = ts_texture_constant_rgb(v);
        } else {
            float v;
            if ((st = ts_pbrt_find_float(m.ps, "value", 1, &v, err))) return st;
            t = ts_texture_constant_float(v);
        }
    } else if (strcmp(cls, "scale") == 0) {
        t.type = TS_TEXTURE_SCALE;
        if ((st = child(&m, "tex1", 1, &t.scale.tex1, err)) ||
            (st = child(&m, "tex2", 1, &t.scale.tex2, err)))
            return st;
    } else if (strcmp(cls, "mix") == 0) {
        t.type = TS_TEXTURE_MIX;
        if ((st = child(&m, "tex1", 0, &t.mix.tex1, err)) || (st = child(&m, "tex2", 1, &t.mix.tex2, err)) ||
            (st = param_texture(tp, m.ps, "amount", false, ts_rgb_gray(0.5f), &t.mix.amount, err)))
            return st;
    } else if (strcmp(cls, "bilerp") == 0) {
        t.type = TS_TEXTURE_BILERP;
        if ((st = map2d(&m, &t.bilerp.map, err))) return st;
        const char *names[4] = {"v00", "v01", "v10", "v11"};
        ts_rgb *dst[4] = {&t.bilerp.v00, &t.bilerp.v01, &t.bilerp.v10, &t.bilerp.v11};
        for (int i = 0; i < 4; i++) {
            float def_v = (i == 1 || i == 3) ? 1.0f : 0.0f;
            if (m.rgb) {
                st = ts_pbrt_find_rgb(m.ps, names[i], ts_rgb_gray(def_v), dst[i], err);
            } else {
                float v;
                st = ts_pbrt_find_float(m.ps, names[i], def_v, &v, err);
                *dst[i] = ts_rgb_gray(v);
            }
            if (st) return st;
        }
    } else if (strcmp(cls, "uv") == 0) {
        if (!m.rgb)
            return tex_error(&m, err, TS_ERR_INVALID,
                             "the uv texture is a color texture in pbrt-v3 (declare it "
                             "\"color\" or \"spectrum\", not \"float\")");
        t.type = TS_TEXTURE_UV;
        if ((st = map2d(&m, &t.uv.map, err))) return st;
    } else if (strcmp(cls, "checkerboard") == 0) {
        int32_t dim;
        if ((st = ts_pbrt_find_int(m.ps, "dimension", 2, &dim, err))) return st;
        if (dim != 2 && dim != 3)
            return ts_pbrt_param_error(m.ps, ts_pbrt_params_get(m.ps, "dimension"), err, TS_ERR_INVALID,
                                       "must be 2 or 3, got %d", (int)dim);
        const ts_texture *t1, *t2;
        if ((st = child(&m, "tex1", 1, &t1, err)) || (st = child(&m, "tex2", 0, &t2, err))) return st;
        if (dim == 2) {
            t.type = TS_TEXTURE_CHECKERBOARD2D;
            t.checkerboard2d.tex1 = t1, t.checkerboard2d.tex2 = t2;
            static const char *const modes[] = {"closedform", "none"};
            int mode = 0;
            if ((st = map2d(&m, &t.checkerboard2d.map, err)) ||
                (st = find_choice(&m, "aamode", modes, 2, &mode, err)))
                return st;
            t.checkerboard2d.closed_form = mode == 0;
        } else {
            t.type = TS_TEXTURE_CHECKERBOARD3D;
            t.checkerboard3d.tex1 = t1, t.checkerboard3d.tex2 = t2;
            t.checkerboard3d.map = map3d(&m);
        }
    } else if (strcmp(cls, "dots") == 0) {
        /* pbrt-v3's CreateDotsFloatTexture / CreateDotsSpectrumTexture pass "inside" where
         * DotsTexture takes its outside texture and "outside" where it takes the inside one:
         * pbrt-v3 paints the dots with "outside". A .pbrt file means what pbrt-v3 renders,
         * so the two are swapped here (the importer warns; JSON keeps the names' meaning). */
        t.type = TS_TEXTURE_DOTS;
        if ((st = child(&m, "inside", 1, &t.dots.outside, err)) ||
            (st = child(&m, "outside", 0, &t.dots.inside, err)) || (st = map2d(&m, &t.dots.map, err)))
            return st;
    } else if (strcmp(cls, "fbm") == 0 || strcmp(cls, "wrinkled") == 0) {
        t.type = cls[0] == 'f' ? TS_TEXTURE_FBM : TS_TEXTURE_WRINKLED;
        t.fbm.map = map3d(&m);
        if ((st = find_octaves(&m, &t.fbm.octaves, &t.fbm.omega, err))) return st;
    } else if (strcmp(cls, "windy") == 0) {
        t.type = TS_TEXTURE_WINDY;
        t.windy.map = map3d(&m);
    } else if (strcmp(cls, "marble") == 0) {
        if (!m.rgb)
            return tex_error(&m, err, TS_ERR_INVALID,
                             "the marble texture is a color texture in pbrt-v3 (declare it "
                             "\"color\" or \"spectrum\", not \"float\")");
        t.type = TS_TEXTURE_MARBLE;
        t.marble.map = map3d(&m);
        if ((st = find_octaves(&m, &t.marble.octaves, &t.marble.omega, err)) ||
            (st = find_finite(&m, "scale", 1, &t.marble.scale, err)) ||
            (st = find_finite(&m, "variation", 0.2f, &t.marble.variation, err)))
            return st;
    } else if (strcmp(cls, "imagemap") == 0) {
        t.type = TS_TEXTURE_IMAGEMAP;
        if ((st = make_imagemap(&m, &t, err))) return st;
    } else if (strcmp(cls, "ptex") == 0) {
        return tex_error(
            &m, err, TS_ERR_UNSUPPORTED,
            "ptex textures are not supported (image textures are read from .exr, .png, .tga and .pfm "
            "files)");
    } else {
        return tex_error(&m, err, TS_ERR_INVALID, "unknown texture class \"%s\"", cls);
    }
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
