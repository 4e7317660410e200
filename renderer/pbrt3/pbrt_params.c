/* pbrt_params.c — parameter lists: type names, lookups, messages; see pbrt_params.h. */
#include "pbrt3/pbrt_params.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const struct {
    const char *name;
    ts_pbrt_param_type type;
} type_names[] = {
    {"integer", TS_PBRT_PARAM_INTEGER}, {"float", TS_PBRT_PARAM_FLOAT},
    {"point2", TS_PBRT_PARAM_POINT2},   {"vector2", TS_PBRT_PARAM_VECTOR2},
    {"point3", TS_PBRT_PARAM_POINT3},   {"point", TS_PBRT_PARAM_POINT3},
    {"vector3", TS_PBRT_PARAM_VECTOR3}, {"vector", TS_PBRT_PARAM_VECTOR3},
    {"normal3", TS_PBRT_PARAM_NORMAL3}, {"normal", TS_PBRT_PARAM_NORMAL3},
    {"rgb", TS_PBRT_PARAM_RGB},         {"color", TS_PBRT_PARAM_RGB},
    {"xyz", TS_PBRT_PARAM_XYZ},         {"blackbody", TS_PBRT_PARAM_BLACKBODY},
    {"spectrum", TS_PBRT_PARAM_SPECTRUM}, {"bool", TS_PBRT_PARAM_BOOL},
    {"string", TS_PBRT_PARAM_STRING},   {"texture", TS_PBRT_PARAM_TEXTURE},
};

bool ts_pbrt_param_type_from_name(const char *type_name, ts_pbrt_param_type *out, const char **spelling)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++)
        if (strcmp(type_name, type_names[i].name) == 0) {
            *out = type_names[i].type;
            if (spelling) *spelling = type_names[i].name;
            return true;
        }
    return false;
}

const char *ts_pbrt_param_type_name(ts_pbrt_param_type type)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++)
        if (type_names[i].type == type) return type_names[i].name;
    return "?";
}

size_t ts_pbrt_param_arity(ts_pbrt_param_type type)
{
    switch (type) {
    case TS_PBRT_PARAM_POINT3:
    case TS_PBRT_PARAM_VECTOR3:
    case TS_PBRT_PARAM_NORMAL3:
    case TS_PBRT_PARAM_RGB:
    case TS_PBRT_PARAM_XYZ: return 3;
    case TS_PBRT_PARAM_POINT2:
    case TS_PBRT_PARAM_VECTOR2:
    case TS_PBRT_PARAM_SPECTRUM: return 2;
    default: return 1;
    }
}

size_t ts_pbrt_param_values(const ts_pbrt_param *p) { return p->n / ts_pbrt_param_arity(p->type); }

ts_pbrt_param *ts_pbrt_params_get(ts_pbrt_params *ps, const char *name)
{
    for (size_t i = 0; i < ps->count; i++)
        if (strcmp(ps->items[i].name, name) == 0) {
            ps->items[i].used = true;
            return &ps->items[i];
        }
    return NULL;
}

ts_status ts_pbrt_param_error(const ts_pbrt_params *ps, const ts_pbrt_param *p, ts_error *err, ts_status st,
                              const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    ts_error_set(err, st, "%s:%u:%u: %s \"%s\": \"%s %s\" %s", p->loc.file, p->loc.line, p->loc.column,
                 ps->directive ? ps->directive : "parameter list", ps->directive_arg ? ps->directive_arg : "",
                 p->type_name, p->name, msg);
    if (err) ts_pbrt_sanitize_utf8(err->message);
    return st;
}

/* The parameter name of type `want` (or NULL if absent); a present one of another type
 * is an error. */
static ts_status get_typed(ts_pbrt_params *ps, const char *name, ts_pbrt_param_type want, ts_pbrt_param **out,
                           ts_error *err)
{
    *out = ts_pbrt_params_get(ps, name);
    if (*out && (*out)->type != want)
        return ts_pbrt_param_error(ps, *out, err, TS_ERR_INVALID, "has the wrong type (expected \"%s %s\")",
                                   ts_pbrt_param_type_name(want), name);
    return TS_OK;
}

static ts_status get_one(ts_pbrt_params *ps, const char *name, ts_pbrt_param_type want, ts_pbrt_param **out,
                         ts_error *err)
{
    ts_status st = get_typed(ps, name, want, out, err);
    if (st || !*out) return st;
    size_t values = ts_pbrt_param_values(*out);
    if (values != 1)
        return ts_pbrt_param_error(ps, *out, err, TS_ERR_INVALID, "expects 1 value, got %zu", values);
    return TS_OK;
}

ts_status ts_pbrt_find_float(ts_pbrt_params *ps, const char *name, float def, float *out, ts_error *err)
{
    ts_pbrt_param *p;
    ts_status st = get_one(ps, name, TS_PBRT_PARAM_FLOAT, &p, err);
    if (st) return st;
    *out = p ? p->floats[0] : def;
    return TS_OK;
}

ts_status ts_pbrt_find_int(ts_pbrt_params *ps, const char *name, int32_t def, int32_t *out, ts_error *err)
{
    ts_pbrt_param *p;
    ts_status st = get_one(ps, name, TS_PBRT_PARAM_INTEGER, &p, err);
    if (st) return st;
    *out = p ? p->ints[0] : def;
    return TS_OK;
}

ts_status ts_pbrt_find_bool(ts_pbrt_params *ps, const char *name, bool def, bool *out, ts_error *err)
{
    ts_pbrt_param *p;
    ts_status st = get_one(ps, name, TS_PBRT_PARAM_BOOL, &p, err);
    if (st) return st;
    *out = p ? p->bools[0] : def;
    return TS_OK;
}

ts_status ts_pbrt_find_string(ts_pbrt_params *ps, const char *name, const char *def, const char **out,
                              ts_error *err)
{
    ts_pbrt_param *p;
    ts_status st = get_one(ps, name, TS_PBRT_PARAM_STRING, &p, err);
    if (st) return st;
    *out = p ? p->strings[0] : def;
    return TS_OK;
}

static ts_status find_vec3(ts_pbrt_params *ps, const char *name, ts_pbrt_param_type type, ts_vec3 def,
                           ts_vec3 *out, ts_error *err)
{
    ts_pbrt_param *p;
    ts_status st = get_one(ps, name, type, &p, err);
    if (st) return st;
    *out = p ? (ts_vec3){p->floats[0], p->floats[1], p->floats[2]} : def;
    return TS_OK;
}

ts_status ts_pbrt_find_point3(ts_pbrt_params *ps, const char *name, ts_vec3 def, ts_vec3 *out, ts_error *err)
{
    return find_vec3(ps, name, TS_PBRT_PARAM_POINT3, def, out, err);
}

ts_status ts_pbrt_find_vector3(ts_pbrt_params *ps, const char *name, ts_vec3 def, ts_vec3 *out, ts_error *err)
{
    return find_vec3(ps, name, TS_PBRT_PARAM_VECTOR3, def, out, err);
}

ts_status ts_pbrt_find_rgb(ts_pbrt_params *ps, const char *name, ts_rgb def, ts_rgb *out, ts_error *err)
{
    ts_pbrt_param *p = ts_pbrt_params_get(ps, name);
    if (!p) {
        *out = def;
        return TS_OK;
    }
    if (p->type == TS_PBRT_PARAM_SPECTRUM || p->type == TS_PBRT_PARAM_BLACKBODY)
        return ts_pbrt_param_error(ps, p, err, TS_ERR_UNSUPPORTED,
                                   "is a spectral value; spectral values are not converted to RGB yet");
    if (p->type != TS_PBRT_PARAM_RGB && p->type != TS_PBRT_PARAM_XYZ)
        return ts_pbrt_param_error(ps, p, err, TS_ERR_INVALID, "has the wrong type (expected \"rgb %s\")", name);
    if (ts_pbrt_param_values(p) != 1)
        return ts_pbrt_param_error(ps, p, err, TS_ERR_INVALID, "expects 1 value, got %zu",
                                   ts_pbrt_param_values(p));
    const float *v = p->floats;
    if (p->type == TS_PBRT_PARAM_RGB) {
        *out = (ts_rgb){v[0], v[1], v[2]};
    } else { /* CIE XYZ → linear sRGB (Rec. 709 primaries, D65 white) */
        *out = (ts_rgb){3.240479f * v[0] - 1.537150f * v[1] - 0.498535f * v[2],
                        -0.969256f * v[0] + 1.875991f * v[1] + 0.041556f * v[2],
                        0.055648f * v[0] - 0.204043f * v[1] + 1.057311f * v[2]};
    }
    return TS_OK;
}

static ts_status find_array(ts_pbrt_params *ps, const char *name, ts_pbrt_param_type type, const float **out,
                            size_t *n, ts_error *err)
{
    ts_pbrt_param *p;
    *out = NULL;
    *n = 0;
    ts_status st = get_typed(ps, name, type, &p, err);
    if (st || !p) return st;
    *out = p->floats;
    *n = ts_pbrt_param_values(p);
    return TS_OK;
}

ts_status ts_pbrt_find_floats(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err)
{
    return find_array(ps, name, TS_PBRT_PARAM_FLOAT, out, n, err);
}

ts_status ts_pbrt_find_point2s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err)
{
    return find_array(ps, name, TS_PBRT_PARAM_POINT2, out, n, err);
}

ts_status ts_pbrt_find_point3s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err)
{
    return find_array(ps, name, TS_PBRT_PARAM_POINT3, out, n, err);
}

ts_status ts_pbrt_find_vector3s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n,
                                ts_error *err)
{
    return find_array(ps, name, TS_PBRT_PARAM_VECTOR3, out, n, err);
}

ts_status ts_pbrt_find_normal3s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n,
                                ts_error *err)
{
    return find_array(ps, name, TS_PBRT_PARAM_NORMAL3, out, n, err);
}

ts_status ts_pbrt_find_ints(ts_pbrt_params *ps, const char *name, const int32_t **out, size_t *n, ts_error *err)
{
    ts_pbrt_param *p;
    *out = NULL;
    *n = 0;
    ts_status st = get_typed(ps, name, TS_PBRT_PARAM_INTEGER, &p, err);
    if (st || !p) return st;
    *out = p->ints;
    *n = p->n;
    return TS_OK;
}

ts_status ts_pbrt_find_strings(ts_pbrt_params *ps, const char *name, const char *const **out, size_t *n,
                               ts_error *err)
{
    ts_pbrt_param *p;
    *out = NULL;
    *n = 0;
    ts_status st = get_typed(ps, name, TS_PBRT_PARAM_STRING, &p, err);
    if (st || !p) return st;
    *out = p->strings;
    *n = p->n;
    return TS_OK;
}

const ts_pbrt_param *ts_pbrt_params_next_unused(const ts_pbrt_params *ps, size_t *cursor)
{
    for (; *cursor < ps->count; (*cursor)++)
        if (!ps->items[*cursor].used) return &ps->items[(*cursor)++];
    return NULL;
}
