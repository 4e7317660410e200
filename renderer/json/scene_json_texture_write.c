/* scene_json_texture_write.c — textures as scene format v1 (see scene_json_texture_write.h).
 * The keys are those scene_json_texture.c reads. */
#include "json/scene_json_texture_write.h"

#include "json/json_write.h"
#include "textures/texture_desc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TRY(expr)                                                                                            \
    do {                                                                                                     \
        ts_status st_ = (expr);                                                                              \
        if (st_ != TS_OK) return st_;                                                                        \
    } while (0)

void ts_json_texture_writer_init(ts_json_texture_writer *w, cJSON *textures, const ts_texture_cache *cache)
{
    *w = (ts_json_texture_writer){.textures = textures, .cache = cache};
}

void ts_json_texture_writer_fini(ts_json_texture_writer *w)
{
    for (uint32_t i = 0; i < w->n; i++)
        free(w->names[i]);
    free(w->names);
    free(w->written);
    *w = (ts_json_texture_writer){0};
}

const char *ts_json_texture_writer_name(const ts_json_texture_writer *w, const ts_texture *t)
{
    for (uint32_t i = 0; i < w->n; i++)
        if (w->written[i] == t) return w->names[i];
    return NULL;
}

static ts_status nomem(ts_error *err)
{
    return ts_error_set(err, TS_ERR_NOMEM, "out of memory while writing the textures");
}

static ts_status remember(ts_json_texture_writer *w, const ts_texture *t, const char *name, ts_error *err)
{
    if (w->n == w->cap) {
        uint32_t cap = w->cap ? 2 * w->cap : 16;
        char **n = realloc(w->names, cap * sizeof *n);
        if (n) w->names = n;
        const ts_texture **x = n ? realloc(w->written, cap * sizeof *x) : NULL;
        if (!x) return nomem(err);
        w->written = x;
        w->cap = cap;
    }
    char *copy = strdup(name);
    if (!copy) return nomem(err);
    w->names[w->n] = copy;
    w->written[w->n] = t;
    w->n++;
    return TS_OK;
}


/* A constant of the texture's kind: a number for float textures and for greys, else an
 * array; v1's colour constants are ≥ 0. */
static ts_status value(cJSON *obj, const char *key, bool rgb, ts_rgb v, const char *name, ts_error *err)
{
    if (rgb && !(v.r >= 0 && v.g >= 0 && v.b >= 0))
        return ts_error_set(err, TS_ERR_UNSUPPORTED,
                            "texture \"%s\": its %s (%g, %g, %g) is a negative colour, which scene format v1 "
                            "cannot hold",
                            name, key, (double)v.r, (double)v.g, (double)v.b);
    bool ok = !rgb || (v.r == v.g && v.g == v.b) ? ts_jw_number(obj, key, v.r) : ts_jw_vec3(obj, key, (ts_vec3){v.r, v.g, v.b});
    return ok ? TS_OK : nomem(err);
}

/* A child texture as obj[key]: its name, or its constant in place. */
static ts_status child(ts_json_texture_writer *w, cJSON *obj, const char *key, const ts_texture *c,
                       const char *parent, ts_error *err)
{
    const char *name = ts_json_texture_writer_name(w, c);
    if (!name && c->type == TS_TEXTURE_CONSTANT) return value(obj, key, c->is_rgb, c->constant.value, parent, err);
    if (!name) {
        char sub[400];
        snprintf(sub, sizeof sub, "%.300s.%s", parent, key);
        TRY(ts_json_texture_write(w, c, sub, err));
        name = ts_json_texture_writer_name(w, c);
    }
    return ts_jw_add(obj, key, cJSON_CreateString(name)) ? TS_OK : nomem(err);
}

/* A 2D mapping as obj.mapping (uv with its defaults written out), and a spherical or
 * cylindrical one's world → texture as obj.world_to_texture. */
static bool mapping2d(cJSON *obj, const ts_texture_mapping2d *m)
{
    static const char *const types[] = {"uv", "spherical", "cylindrical", "planar"};
    cJSON *j = cJSON_CreateObject();
    if (!ts_jw_add(obj, "mapping", j) || !ts_jw_add(j, "type", cJSON_CreateString(types[m->type]))) return false;
    switch (m->type) {
    case TS_TEXTURE_MAPPING_UV:
        return ts_jw_number(j, "uscale", m->su) && ts_jw_number(j, "vscale", m->sv) && ts_jw_number(j, "udelta", m->du) &&
               ts_jw_number(j, "vdelta", m->dv);
    case TS_TEXTURE_MAPPING_PLANAR:
        return ts_jw_vec3(j, "v1", m->vs) && ts_jw_vec3(j, "v2", m->vt) && ts_jw_number(j, "udelta", m->du) &&
               ts_jw_number(j, "vdelta", m->dv);
    case TS_TEXTURE_MAPPING_SPHERICAL:
    case TS_TEXTURE_MAPPING_CYLINDRICAL:
        return ts_jw_matrix(obj, "world_to_texture", &m->world_to_texture);
    }
    return false;
}

/* t's mapping as v1 has it: a 2D one as "mapping", a 3D one's world → texture. */
static bool write_mapping(cJSON *j, const ts_texture_desc *d, const ts_texture *t)
{
    ts_texture *u = (ts_texture *)t;
    if (d->flags & TS_TDESC_MAP2D) return mapping2d(j, ts_tdesc_map2d(u, d));
    if (d->flags & TS_TDESC_MAP3D) return ts_jw_matrix(j, "world_to_texture", &ts_tdesc_map3d(u, d)->world_to_texture);
    return true;
}

/* An image map's file and options. */
static ts_status write_image(ts_json_texture_writer *w, cJSON *j, const ts_texture *t, const char *name, ts_error *err)
{
    const char *file;
    ts_texture_image_options opt;
    if (!ts_texture_cache_source(w->cache, t->image.mipmap, &file, &opt))
        return ts_error_set(err, TS_ERR_INTERNAL,
                            "texture \"%s\": its image map is not one of the scene's texture cache", name);
    static const char *const wraps[] = {"repeat", "black", "clamp"};
    bool ok = ts_jw_add(j, "file", cJSON_CreateString(file)) && ts_jw_add(j, "wrap", cJSON_CreateString(wraps[opt.wrap])) &&
              ts_jw_add(j, "trilinear", cJSON_CreateBool(t->image.trilinear)) &&
              ts_jw_number(j, "max_anisotropy", t->image.max_anisotropy) && ts_jw_number(j, "scale", opt.scale) &&
              ts_jw_add(j, "gamma", cJSON_CreateBool(opt.gamma)) && ts_jw_add(j, "invert", cJSON_CreateBool(t->image.invert));
    return ok ? TS_OK : nomem(err);
}

/* t as v1 has it: its type's description (textures/texture_desc.h) in the table's order —
 * the mapping first where the description says so, else after the rows (and a
 * checkerboard's dimension). */
static ts_status fill(ts_json_texture_writer *w, cJSON *j, const ts_texture *t, const char *name, ts_error *err)
{
    const ts_texture_desc *d = &ts_texture_descs[t->type];
    if (!ts_jw_add(j, "type", cJSON_CreateString(d->name)) ||
        !ts_jw_add(j, "kind", cJSON_CreateString(t->is_rgb ? "rgb" : "float")))
        return nomem(err);
    bool rgb = t->is_rgb;
    ts_texture *u = (ts_texture *)t;
    if ((d->flags & TS_TDESC_MAP_FIRST) && !write_mapping(j, d, t)) return nomem(err);
    for (int i = 0; i < d->n_params; i++) {
        const ts_texture_param *p = &d->params[i];
        switch (p->kind) {
        case TS_TPARAM_CHILD:
        case TS_TPARAM_AMOUNT: TRY(child(w, j, p->key, *ts_tparam_texture(u, p), name, err)); break;
        case TS_TPARAM_VALUE: TRY(value(j, p->key, rgb, *ts_tparam_rgb(u, p), name, err)); break;
        case TS_TPARAM_NUMBER:
            if (!ts_jw_number(j, p->key, *ts_tparam_float(u, p))) return nomem(err);
            break;
        case TS_TPARAM_OCTAVES:
            if (!ts_jw_number(j, p->key, *ts_tparam_octaves(u, p)) || !ts_jw_number(j, "roughness", *ts_tparam_omega(u, p)))
                return nomem(err);
            break;
        }
    }
    if (d->dimension && !ts_jw_number(j, "dimension", d->dimension)) return nomem(err);
    if (!(d->flags & TS_TDESC_MAP_FIRST) && !write_mapping(j, d, t)) return nomem(err);
    if ((d->flags & TS_TDESC_AAMODE) &&
        !ts_jw_add(j, "aamode", cJSON_CreateString(t->checkerboard2d.closed_form ? "closedform" : "none")))
        return nomem(err);
    if (d->flags & TS_TDESC_IMAGE) TRY(write_image(w, j, t, name, err));
    return TS_OK;
}

ts_status ts_json_texture_write(ts_json_texture_writer *w, const ts_texture *t, const char *want, ts_error *err)
{
    if (ts_json_texture_writer_name(w, t)) return TS_OK;
    /* A name the document has already (a texture named like a generated one) gets "#k". */
    char name[420];
    snprintf(name, sizeof name, "%.400s", want);
    for (int k = 2; cJSON_GetObjectItemCaseSensitive(w->textures, name); k++)
        snprintf(name, sizeof name, "%.400s#%d", want, k);
    cJSON *j = cJSON_CreateObject();
    if (!j) return nomem(err);
    /* Children are written (into w->textures) before the texture itself is added. */
    ts_status st = fill(w, j, t, name, err);
    if (st) {
        cJSON_Delete(j);
        return st;
    }
    if (!cJSON_AddItemToObject(w->textures, name, j)) {
        cJSON_Delete(j);
        return nomem(err);
    }
    return remember(w, t, name, err);
}

cJSON *ts_json_texture_ref(ts_json_texture_writer *w, const ts_texture *t, const char *hint, ts_error *err)
{
    if (ts_json_texture_write(w, t, hint, err)) return NULL;
    cJSON *s = cJSON_CreateString(ts_json_texture_writer_name(w, t));
    if (!s) nomem(err);
    return s;
}
