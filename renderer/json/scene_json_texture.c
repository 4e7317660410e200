/* scene_json_texture.c — the "textures" section and textured material parameters; see
 * scene_json_texture.h. Keys, defaults and meanings are pbrt-v3's (pbrt3/texture_pbrt.h),
 * written in the JSON format's snake case (max_anisotropy, file). */
#include "json/scene_json_texture.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "textures/noise.h"
#include "textures/texture_cache.h"
#include "textures/texture_desc.h"
#include "textures/texture_image.h"

#define TRY(expr)                                                                                            \
    do {                                                                                                     \
        ts_status st_ = (expr);                                                                              \
        if (st_ != TS_OK) return st_;                                                                        \
    } while (0)

void ts_json_textures_init(ts_json_textures *t) { *t = (ts_json_textures){0}; }

void ts_json_textures_fini(ts_json_textures *t)
{
    free(t->names);
    free(t->textures);
    ts_name_map_fini(&t->index);
    *t = (ts_json_textures){0};
}

const ts_texture *ts_json_textures_find(const ts_json_textures *t, const char *name)
{
    uint32_t i = ts_name_map_get(&t->index, name);
    return i == TS_NAME_MAP_NONE ? NULL : t->textures[i];
}

static ts_status add(ts_json_textures *t, const char *name, const ts_texture *tex, ts_error *err)
{
    if (t->n == t->cap) {
        uint32_t cap = t->cap ? 2 * t->cap : 16;
        const char **n = realloc(t->names, cap * sizeof *n);
        if (n) t->names = n;
        const ts_texture **x = n ? realloc(t->textures, cap * sizeof *x) : NULL;
        if (!x) return ts_error_set(err, TS_ERR_NOMEM, "out of memory while loading the textures");
        t->textures = x;
        t->cap = cap;
    }
    if (!ts_name_map_put(&t->index, name, t->n))
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory while loading the textures");
    t->names[t->n] = name;
    t->textures[t->n] = tex;
    t->n++;
    return TS_OK;
}

/* The texture a string value names, of the wanted kind (want_rgb, or either when any). */
static ts_status named(const ts_json_textures *t, const cJSON *v, const char *path, const char *key,
                       bool want_rgb, bool any, const ts_texture **out, ts_error *err)
{
    ts_jpath p = ts_jpath_key(path, key);
    const ts_texture *tex = ts_json_textures_find(t, v->valuestring);
    if (!tex)
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: no texture named \"%s\" in 'textures' (defined before it)", p.s,
                            v->valuestring);
    if (!any && tex->is_rgb != want_rgb)
        return ts_error_set(err, TS_ERR_INVALID, "%s: texture \"%s\" is a%s texture; expected a%s one", p.s,
                            v->valuestring, tex->is_rgb ? "n RGB" : " float", want_rgb ? "n RGB" : " float");
    *out = tex;
    return TS_OK;
}

ts_status ts_json_material_rgb(const ts_json_textures *t, const cJSON *obj, const char *path, const char *key,
                               ts_jrange range, ts_material_rgb *out, ts_error *err)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (cJSON_IsString(v)) {
        out->value = ts_rgb_gray(0);
        return named(t, v, path, key, true, true, &out->tex, err);
    }
    out->tex = NULL;
    return ts_json_rgb(obj, path, key, false, range, &out->value, err);
}

ts_status ts_json_material_float(const ts_json_textures *t, const cJSON *obj, const char *path,
                                 const char *key, ts_jrange range, ts_material_float *out, ts_error *err)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (cJSON_IsString(v)) {
        out->value = 0;
        return named(t, v, path, key, false, false, &out->tex, err);
    }
    out->tex = NULL;
    double d = out->value;
    TRY(ts_json_number(obj, path, key, false, range, &d, err));
    out->value = (float)d;
    return TS_OK;
}

/* ---------------------------------------------------------------- one texture */

typedef struct reader {
    ts_json_textures *t;
    ts_scene_builder *b;
    const cJSON *obj;
    const char *path;
    bool rgb; /* the texture's kind */
    const ts_mat4 *world_to_texture; /* the inverse of "transform", or "world_to_texture" */
    ts_error *err;
} reader;

static ts_status number(const reader *r, const char *key, double def, float *out)
{
    double d = def;
    TRY(ts_json_number(r->obj, r->path, key, false, TS_J_ANY, &d, r->err));
    if (!isfinite((float)d)) {
        ts_jpath p = ts_jpath_key(r->path, key);
        return ts_error_set(r->err, TS_ERR_INVALID, "%s: expected a number within the float range", p.s);
    }
    *out = (float)d;
    return TS_OK;
}

/* A value of the texture's kind: a number (float; for RGB a grey) or, for RGB, 3 numbers ≥ 0. */
static ts_status value(const reader *r, const cJSON *obj, const char *key, bool rgb, float def, ts_rgb *out)
{
    *out = ts_rgb_gray(def);
    if (rgb) return ts_json_rgb(obj, r->path, key, false, TS_J_NONNEG, out, r->err);
    double d = def;
    TRY(ts_json_number(obj, r->path, key, false, TS_J_ANY, &d, r->err));
    *out = ts_rgb_gray((float)d);
    return TS_OK;
}

/* A child texture: a texture's name (of kind rgb), a constant, or absent: the constant def. */
static ts_status child(const reader *r, const char *key, bool rgb, float def, const ts_texture **out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(r->obj, key);
    if (cJSON_IsString(v)) return named(r->t, v, r->path, key, rgb, false, out, r->err);
    ts_rgb c;
    TRY(value(r, r->obj, key, rgb, def, &c));
    ts_texture proto = rgb ? ts_texture_constant_rgb(c) : ts_texture_constant_float(c.r);
    ts_jpath p = ts_jpath_key(r->path, key);
    ts_status st = ts_scene_builder_add_texture(r->b, &proto, out, r->err);
    if (st) ts_error_prefix(r->err, "%s", p.s);
    return st;
}

static ts_status choice(const reader *r, const cJSON *obj, const char *path, const char *key,
                        const char *const *words, int *out)
{
    *out = 0;
    return ts_json_enum(obj, path, key, false, words, out, r->err);
}

static ts_status mapping2d(const reader *r, ts_texture_mapping2d *out)
{
    *out = ts_texture_mapping2d_uv(1, 1, 0, 0);
    const cJSON *m;
    TRY(ts_json_object(r->obj, r->path, "mapping", false, &m, r->err));
    if (!m) return TS_OK;
    ts_jpath mp = ts_jpath_key(r->path, "mapping");
    static const char *const types[] = {"uv", "spherical", "cylindrical", "planar", NULL};
    static const char *const k_uv[] = {"type", "uscale", "vscale", "udelta", "vdelta", NULL};
    static const char *const k_sph[] = {"type", NULL};
    static const char *const k_planar[] = {"type", "v1", "v2", "udelta", "vdelta", NULL};
    const char *const *keys[] = {k_uv, k_sph, k_sph, k_planar};
    int type = 0;
    TRY(ts_json_enum(m, mp.s, "type", false, types, &type, r->err));
    TRY(ts_json_check_object(m, mp.s, keys[type], r->err));
    reader mr = *r;
    mr.obj = m;
    mr.path = mp.s;
    float du = 0, dv = 0;
    if (type == 0 || type == 3) {
        TRY(number(&mr, "udelta", 0, &du));
        TRY(number(&mr, "vdelta", 0, &dv));
    }
    if (type == 0) {
        float su = 1, sv = 1;
        TRY(number(&mr, "uscale", 1, &su));
        TRY(number(&mr, "vscale", 1, &sv));
        *out = ts_texture_mapping2d_uv(su, sv, du, dv);
    } else if (type == 3) {
        ts_vec3 v1 = {1, 0, 0}, v2 = {0, 1, 0};
        TRY(ts_json_vec3(m, mp.s, "v1", false, false, &v1, r->err));
        TRY(ts_json_vec3(m, mp.s, "v2", false, false, &v2, r->err));
        *out = ts_texture_mapping2d_planar(v1, v2, du, dv);
    } else {
        /* World → texture: the inverse of the texture's "transform". */
        *out = type == 1 ? ts_texture_mapping2d_spherical(r->world_to_texture)
                         : ts_texture_mapping2d_cylindrical(r->world_to_texture);
    }
    return TS_OK;
}

/* Solid textures: world → texture is the inverse of "transform" (not pbrt-v3's quirk of
 * the CTM itself, which its importer reproduces: pbrt3/texture_pbrt.h), or
 * "world_to_texture" as given (which is how tessera convert writes pbrt-v3's). */
static ts_status mapping3d(const reader *r, ts_texture_mapping3d *out)
{
    out->world_to_texture = *r->world_to_texture;
    return TS_OK;
}

/* "world_to_texture": 16 numbers, row-major, within the float range; absent: *out untouched. */
static ts_status world_to_texture(const cJSON *obj, const char *path, ts_mat4 *out, ts_error *err)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, "world_to_texture");
    if (!m) return TS_OK;
    ts_jpath mp = ts_jpath_key(path, "world_to_texture");
    if (cJSON_GetObjectItemCaseSensitive(obj, "transform"))
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: give either 'transform' (texture → world) or 'world_to_texture', not both", mp.s);
    if (!cJSON_IsArray(m) || cJSON_GetArraySize(m) != 16) {
        char d[64];
        ts_json_describe(m, d, sizeof d);
        return ts_error_set(err, TS_ERR_INVALID, "%s: expected an array of 16 numbers (row-major), got %s", mp.s, d);
    }
    int k = 0;
    for (const cJSON *c = m->child; c; c = c->next, k++) {
        if (!cJSON_IsNumber(c) || !isfinite((float)c->valuedouble)) {
            ts_jpath ep = ts_jpath_index(mp.s, k);
            return ts_error_set(err, TS_ERR_INVALID, "%s: expected a finite number within the float range", ep.s);
        }
        out->m[k / 4][k % 4] = c->valuedouble;
    }
    return TS_OK;
}

static ts_status imagemap(const reader *r, ts_texture *t)
{
    const char *file;
    TRY(ts_json_string(r->obj, r->path, "file", true, &file, r->err));
    static const char *const wraps[] = {"repeat", "black", "clamp", NULL};
    int wrap;
    TRY(choice(r, r->obj, r->path, "wrap", wraps, &wrap));
    bool trilinear = false, invert = false, gamma = ts_texture_image_default_gamma(file);
    TRY(ts_json_bool(r->obj, r->path, "trilinear", false, &trilinear, r->err));
    TRY(ts_json_bool(r->obj, r->path, "invert", false, &invert, r->err));
    TRY(ts_json_bool(r->obj, r->path, "gamma", false, &gamma, r->err));
    float scale, aniso;
    TRY(number(r, "scale", 1, &scale));
    TRY(number(r, "max_anisotropy", 8, &aniso));
    if (!(aniso > 0 && aniso <= TS_MIPMAP_MAX_ANISOTROPY)) {
        ts_jpath p = ts_jpath_key(r->path, "max_anisotropy");
        return ts_error_set(r->err, TS_ERR_INVALID,
                            "%s: expected a number in (0, %g] (the bound on an EWA lookup's cost), got %g",
                            p.s, (double)TS_MIPMAP_MAX_ANISOTROPY, (double)aniso);
    }
    ts_texture_image_options opt = {
        .n_channels = r->rgb ? 3 : 1, .gamma = gamma, .scale = scale, .wrap = (ts_texture_wrap)wrap};
    ts_jpath fp = ts_jpath_key(r->path, "file");
    ts_status st = ts_scene_builder_load_texture_image(r->b, file, &opt, &t->image.mipmap, r->err);
    if (st) {
        ts_error_prefix(r->err, "%s", fp.s);
        return st;
    }
    t->image.trilinear = trilinear;
    t->image.max_anisotropy = aniso;
    t->image.invert = invert;
    return TS_OK;
}

/* One row of the type's description (textures/texture_desc.h). */
static ts_status texture_param(const reader *r, const ts_texture_param *p, ts_texture *t)
{
    switch (p->kind) {
    case TS_TPARAM_CHILD: return child(r, p->key, r->rgb, p->def, ts_tparam_texture(t, p));
    case TS_TPARAM_AMOUNT: return child(r, p->key, false, p->def, ts_tparam_texture(t, p));
    case TS_TPARAM_VALUE: return value(r, r->obj, p->key, r->rgb, p->def, ts_tparam_rgb(t, p));
    case TS_TPARAM_NUMBER: return number(r, p->key, p->def, ts_tparam_float(t, p));
    case TS_TPARAM_OCTAVES: {
        int64_t o = (int64_t)p->def;
        TRY(ts_json_int(r->obj, r->path, p->key, false, 0, TS_NOISE_MAX_OCTAVES, &o, r->err));
        *ts_tparam_octaves(t, p) = (int)o;
        return number(r, "roughness", 0.5, ts_tparam_omega(t, p));
    }
    }
    return TS_OK;
}

/* A texture: its type's description (textures/texture_desc.h) says which keys it takes,
 * their kinds and defaults; a checkerboard's "dimension" picks its 2D or 3D description. */
ts_status ts_json_texture_parse(ts_json_textures *tt, ts_scene_builder *b, const cJSON *obj, const char *path,
                                const char *name, const ts_xform *to_world, ts_error *err)
{
    /* v1's type names, each once (the two checkerboards share theirs). */
    const char *types[TS_TEXTURE_TYPE_COUNT + 1];
    int n_types = 0;
    for (int i = 0; i < TS_TEXTURE_TYPE_COUNT; i++)
        if (!n_types || strcmp(types[n_types - 1], ts_texture_descs[i].name) != 0) types[n_types++] = ts_texture_descs[i].name;
    types[n_types] = NULL;
    if (!cJSON_IsObject(obj)) return ts_json_check_object(obj, path, types, err);
    int type;
    TRY(ts_json_enum(obj, path, "type", true, types, &type, err));
    const ts_texture_desc *d = ts_texture_desc_by_name(types[type], 2);
    if (d->dimension) {
        int64_t dim = 2;
        TRY(ts_json_int(obj, path, "dimension", false, 2, 3, &dim, err));
        d = ts_texture_desc_by_name(types[type], (int)dim);
    }
    /* The keys of this type: every texture's, its rows', its flags'. A 3D checkerboard
     * takes the 2D one's keys so that a mapping or aamode given it gets the sentence below. */
    const ts_texture_desc *keyed = d->dimension ? ts_texture_desc_by_name(d->name, 2) : d;
    const char *keys[32];
    int n = 0;
    keys[n++] = "type", keys[n++] = "kind", keys[n++] = "transform", keys[n++] = "world_to_texture";
    if (keyed->dimension) keys[n++] = "dimension";
    if (keyed->flags & TS_TDESC_MAP2D) keys[n++] = "mapping";
    for (int i = 0; i < keyed->n_params; i++) {
        keys[n++] = keyed->params[i].key;
        if (keyed->params[i].kind == TS_TPARAM_OCTAVES) keys[n++] = "roughness";
    }
    if (keyed->flags & TS_TDESC_AAMODE) keys[n++] = "aamode";
    if (keyed->flags & TS_TDESC_IMAGE) {
        static const char *const image_keys[] = {"file", "wrap", "trilinear", "max_anisotropy", "scale", "gamma", "invert"};
        for (size_t i = 0; i < sizeof image_keys / sizeof *image_keys; i++)
            keys[n++] = image_keys[i];
    }
    keys[n] = NULL;
    TRY(ts_json_check_object(obj, path, keys, err));
    static const char *const kinds[] = {"rgb", "float", NULL};
    int kind = 0;
    TRY(ts_json_enum(obj, path, "kind", false, kinds, &kind, err));
    bool rgb = kind == 0;
    if (!rgb && (d->flags & TS_TDESC_RGB_ONLY)) {
        ts_jpath kp = ts_jpath_key(path, "kind");
        return ts_error_set(err, TS_ERR_INVALID, "%s: a %s texture is RGB only (as in pbrt-v3)", kp.s, d->name);
    }
    if (d->dimension == 3 &&
        (cJSON_GetObjectItemCaseSensitive(obj, "mapping") || cJSON_GetObjectItemCaseSensitive(obj, "aamode"))) {
        ts_jpath p = ts_jpath_key(path, "dimension");
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s: a 3D checkerboard takes no mapping or aamode (its space is 'transform')", p.s);
    }
    ts_mat4 w2t = to_world->m_inv;
    TRY(world_to_texture(obj, path, &w2t, err));
    reader r = {tt, b, obj, path, rgb, &w2t, err};
    ts_texture t = {.is_rgb = rgb, .type = d->type};
    if (d->flags & TS_TDESC_MAP3D) TRY(mapping3d(&r, ts_tdesc_map3d(&t, d)));
    if (d->flags & TS_TDESC_MAP2D) TRY(mapping2d(&r, ts_tdesc_map2d(&t, d)));
    for (int i = 0; i < d->n_params; i++)
        TRY(texture_param(&r, &d->params[i], &t));
    if (d->flags & TS_TDESC_CONSTANT)
        t = rgb ? ts_texture_constant_rgb(t.constant.value) : ts_texture_constant_float(t.constant.value.r);
    if (d->flags & TS_TDESC_AAMODE) {
        static const char *const modes[] = {"closedform", "none", NULL};
        int mode;
        TRY(choice(&r, obj, path, "aamode", modes, &mode));
        t.checkerboard2d.closed_form = mode == 0;
    }
    if (d->flags & TS_TDESC_IMAGE) TRY(imagemap(&r, &t));
    const ts_texture *made;
    ts_status st = ts_scene_builder_add_texture(b, &t, &made, err);
    if (st) {
        ts_error_prefix(err, "%s", path);
        return st;
    }
    return add(tt, name, made, err);
}
