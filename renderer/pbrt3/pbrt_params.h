/* pbrt_params.h — a pbrt-v3 parameter list ("type name" value-or-[values]) and its lookup.
 *
 * Design note: the parser (pbrt_parser.h) reads each directive's parameter list into a
 * ts_pbrt_params held in the scene's arena: one ts_pbrt_param per name (a name given
 * twice keeps the last, as pbrt-v3 does, with a warning), with its type, the values as
 * written, and where it was written. Counts are checked there once per type (point3s in
 * threes, a texture has one name, …); what a value *means* is left to the importer,
 * which asks for each parameter by name and type. Every lookup marks the parameter used,
 * so the importer can warn about the ones nothing asked for, as pbrt-v3 does
 * (ts_pbrt_params_next_unused).
 *
 * Types and storage (pbrt-v3's names; the aliases on the right read the same):
 *   integer                         ints   (int32; the value must be a whole number)
 *   float                           floats
 *   point2 vector2                  floats, 2 per value
 *   point3 vector3 normal3          floats, 3 per value   (point, vector, normal)
 *   rgb                             floats, 3 per value   (color)
 *   xyz                             floats, 3 per value   (CIE XYZ)
 *   blackbody                       floats: 1 value (temperature in K, normalised to a peak
 *                                   of 1) or 2 (pbrt-v3's temperature + scale)
 *   spectrum                        floats: (wavelength nm, value) pairs, written inline or
 *                                   read from a .spd file (its name in strings[0])
 *   bool                            bools: "true"/"false", quoted or not
 *   string                          strings
 *   texture                         strings[0]: the texture's name, resolved by the parser
 *                                   in the scope where the parameter was written
 *                                   (texture_float / texture_spectrum)
 * Spectral values (spectrum, blackbody) stay as written: converting them to RGB needs the
 * CIE matching functions, which this step does not include; ts_pbrt_find_rgb says so
 * with TS_ERR_UNSUPPORTED. xyz converts exactly (a fixed matrix) and is accepted.
 *
 * Messages: "<file>:<line>:<column>: <directive>: \"<type> <name>\" <problem>", e.g.
 * "scene.pbrt:12:30: Shape \"sphere\": \"float radius\" expects 1 value, got 2". Lookups
 * mutate only the used flags; a ts_pbrt_params is used by one thread at a time. */
#ifndef TS_PBRT_PARAMS_H
#define TS_PBRT_PARAMS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "pbrt3/pbrt_lexer.h"
#include "core/vecmath.h"

typedef enum ts_pbrt_param_type {
    TS_PBRT_PARAM_INTEGER,
    TS_PBRT_PARAM_FLOAT,
    TS_PBRT_PARAM_POINT2,
    TS_PBRT_PARAM_VECTOR2,
    TS_PBRT_PARAM_POINT3,
    TS_PBRT_PARAM_VECTOR3,
    TS_PBRT_PARAM_NORMAL3,
    TS_PBRT_PARAM_RGB,
    TS_PBRT_PARAM_XYZ,
    TS_PBRT_PARAM_BLACKBODY,
    TS_PBRT_PARAM_SPECTRUM,
    TS_PBRT_PARAM_BOOL,
    TS_PBRT_PARAM_STRING,
    TS_PBRT_PARAM_TEXTURE,
} ts_pbrt_param_type;

typedef struct ts_pbrt_param {
    const char *name;      /* "radius" */
    const char *type_name; /* as written: "color", "point", … */
    ts_pbrt_param_type type;
    ts_pbrt_loc loc; /* of the "type name" string */
    size_t n;        /* number of scalars (ints, floats, bools or strings); points: 3 per point */
    const int32_t *ints;
    const float *floats;
    const bool *bools;
    const char *const *strings;
    /* texture: the float and the spectrum (color) texture of that name in scope where the
     * parameter was written, as indices into ts_pbrt_scene.textures, or -1 for none (at
     * least one is ≥ 0; which one a parameter needs depends on what reads it). */
    int32_t texture_float, texture_spectrum;
    bool used; /* set by every lookup of this parameter */
} ts_pbrt_param;

typedef struct ts_pbrt_params {
    ts_pbrt_param *items;
    size_t count;
    const char *directive;     /* for messages: "Shape", "Camera", "MakeNamedMaterial" */
    const char *directive_arg; /* its first argument: "sphere", "perspective", the material's name */
} ts_pbrt_params;

/* The type of a type name as pbrt-v3 spells it ("point" → POINT3); false if unknown.
 * *spelling (if not NULL) gets a static copy of the name. */
bool ts_pbrt_param_type_from_name(const char *type_name, ts_pbrt_param_type *out, const char **spelling);
/* pbrt-v3's canonical name of a type ("point3", "rgb", …). */
const char *ts_pbrt_param_type_name(ts_pbrt_param_type type);
/* Scalars per value: 3 for point3/vector3/normal3/rgb/xyz, 2 for point2/vector2 and the
 * pairs of a spectrum, else 1. */
size_t ts_pbrt_param_arity(ts_pbrt_param_type type);
/* Number of values (points, colours, pairs, …): n / arity. */
size_t ts_pbrt_param_values(const ts_pbrt_param *p);

/* The parameter called name, of any type, marked used; NULL if there is none. */
ts_pbrt_param *ts_pbrt_params_get(ts_pbrt_params *ps, const char *name);

/* Single values. Absent: *out = def, TS_OK. Present: it must have the type named by the
 * function (float for _float, integer for _int, …) and exactly one value, else
 * TS_ERR_INVALID with a sentence naming the parameter. */
ts_status ts_pbrt_find_float(ts_pbrt_params *ps, const char *name, float def, float *out, ts_error *err);
ts_status ts_pbrt_find_int(ts_pbrt_params *ps, const char *name, int32_t def, int32_t *out, ts_error *err);
ts_status ts_pbrt_find_bool(ts_pbrt_params *ps, const char *name, bool def, bool *out, ts_error *err);
ts_status ts_pbrt_find_string(ts_pbrt_params *ps, const char *name, const char *def, const char **out,
                              ts_error *err);
ts_status ts_pbrt_find_point3(ts_pbrt_params *ps, const char *name, ts_vec3 def, ts_vec3 *out, ts_error *err);
ts_status ts_pbrt_find_vector3(ts_pbrt_params *ps, const char *name, ts_vec3 def, ts_vec3 *out, ts_error *err);
/* An rgb value, or an xyz value converted to linear sRGB (pbrt-v3's XYZToRGB matrix).
 * spectrum and blackbody: TS_ERR_UNSUPPORTED ("spectral values are not converted to RGB
 * yet"); any other type: TS_ERR_INVALID. */
ts_status ts_pbrt_find_rgb(ts_pbrt_params *ps, const char *name, ts_rgb def, ts_rgb *out, ts_error *err);

/* Arrays. Absent: *out NULL and *n 0, TS_OK. Present with another type: TS_ERR_INVALID.
 * *n counts values: floats/ints/strings one each, point3s and normals 3 floats each,
 * point2s 2 floats each. The arrays belong to the scene's arena. */
ts_status ts_pbrt_find_floats(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err);
ts_status ts_pbrt_find_ints(ts_pbrt_params *ps, const char *name, const int32_t **out, size_t *n, ts_error *err);
ts_status ts_pbrt_find_point2s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err);
ts_status ts_pbrt_find_point3s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err);
ts_status ts_pbrt_find_vector3s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err);
ts_status ts_pbrt_find_normal3s(ts_pbrt_params *ps, const char *name, const float **out, size_t *n, ts_error *err);
ts_status ts_pbrt_find_strings(ts_pbrt_params *ps, const char *name, const char *const **out, size_t *n,
                               ts_error *err);

/* The next parameter no lookup has asked for, from *cursor on (start with 0); NULL when
 * there is none left. */
const ts_pbrt_param *ts_pbrt_params_next_unused(const ts_pbrt_params *ps, size_t *cursor);

/* Fills err with "<loc>: <directive> \"<arg>\": \"<type> <name>\" <printf text>" and returns st. */
ts_status ts_pbrt_param_error(const ts_pbrt_params *ps, const ts_pbrt_param *p, ts_error *err, ts_status st,
                              const char *fmt, ...) __attribute__((format(printf, 5, 6)));

#endif
