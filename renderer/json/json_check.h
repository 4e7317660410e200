/* json_check.h — typed access to cJSON documents with errors that name the JSON path.
 *
 * Design note: the scene loader validates the whole document before building anything
 * (docs/design.md §4), and every complaint is one sentence starting with the path of the
 * offending value, e.g. "shapes[3].radius: expected a positive number, got -1". These
 * helpers do that formatting in one place. A getter returns TS_OK and writes *out when
 * the key is present and valid, TS_OK leaving *out untouched when it is absent and not
 * required, and TS_ERR_INVALID with the sentence otherwise. Paths are built by the
 * caller into a small buffer (ts_jpath). Pure, thread-safe (no cJSON global state). */
#ifndef TS_JSON_CHECK_H
#define TS_JSON_CHECK_H

#include <stdbool.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "core/error.h"
#include "core/vecmath.h"

#define TS_JPATH_MAX 192

typedef struct ts_jpath { char s[TS_JPATH_MAX]; } ts_jpath;

/* "parent.key" (or "key" at the root). */
ts_jpath ts_jpath_key(const char *parent, const char *key);
/* "parent[i]". */
ts_jpath ts_jpath_index(const char *parent, int i);

/* Ranges a number may be required to lie in. Every number is also checked as the float
 * the scene keeps: beyond ±3.4e38 (infinite as a float), or positive but rounding to 0,
 * is refused ("x: 1e+39 is beyond the range of a float …"). */
typedef enum ts_jrange {
    TS_J_ANY,      /* any finite number */
    TS_J_POSITIVE, /* > 0 */
    TS_J_NONNEG,   /* >= 0 */
    TS_J_UNIT,     /* [0, 1] */
} ts_jrange;

/* Short description of a JSON value for "got ..." ("-1", "\"abc\"", "an array", ...). */
void ts_json_describe(const cJSON *v, char *buf, size_t n);

/* obj must be an object whose keys are all in allowed (NULL-terminated) and unique. */
ts_status ts_json_check_object(const cJSON *obj, const char *path, const char *const *allowed, ts_error *err);

ts_status ts_json_number(const cJSON *obj, const char *path, const char *key, bool required, ts_jrange range,
                         double *out, ts_error *err);
/* Integer in [lo, hi]. */
ts_status ts_json_int(const cJSON *obj, const char *path, const char *key, bool required, int64_t lo, int64_t hi,
                      int64_t *out, ts_error *err);
ts_status ts_json_bool(const cJSON *obj, const char *path, const char *key, bool required, bool *out, ts_error *err);
/* A non-empty string; *out points into the document. */
ts_status ts_json_string(const cJSON *obj, const char *path, const char *key, bool required, const char **out,
                         ts_error *err);
/* One of choices (NULL-terminated): *out is its index. */
ts_status ts_json_enum(const cJSON *obj, const char *path, const char *key, bool required, const char *const *choices,
                       int *out, ts_error *err);
/* Array of 3 finite numbers. nonzero: the vector may not be (0,0,0). */
ts_status ts_json_vec3(const cJSON *obj, const char *path, const char *key, bool required, bool nonzero,
                       ts_vec3 *out, ts_error *err);
/* RGB: array of 3 numbers in range (TS_J_NONNEG or TS_J_UNIT), or a single number for gray. */
ts_status ts_json_rgb(const cJSON *obj, const char *path, const char *key, bool required, ts_jrange range,
                      ts_rgb *out, ts_error *err);
/* An array (of any length) or absent (*out NULL). */
ts_status ts_json_array(const cJSON *obj, const char *path, const char *key, bool required, const cJSON **out,
                        ts_error *err);
/* An object or absent (*out NULL). */
ts_status ts_json_object(const cJSON *obj, const char *path, const char *key, bool required, const cJSON **out,
                         ts_error *err);

/* String limits of a scene document: keys, names, types and other values at most
 * TS_JSON_MAX_STRING bytes; file references (keys "file", "map") TS_JSON_MAX_PATH_STRING. */
#define TS_JSON_MAX_STRING 255
#define TS_JSON_MAX_PATH_STRING 1024
/* TS_OK when every string in doc is within its limit; else TS_ERR_INVALID naming the first
 * that is not by its JSON path ("name: a string of 7340032 bytes is longer than the limit
 * of 255"). Checked before anything else is read, so an outsized name costs no work. */
ts_status ts_json_check_strings(const cJSON *doc, ts_error *err);

/* Parses text (length len, need not be NUL-terminated) into *out; on a syntax error the
 * sentence gives line and column. The caller frees *out with cJSON_Delete. */
ts_status ts_json_parse(const char *text, size_t len, cJSON **out, ts_error *err);
/* TS_OK when text[0..len) is valid UTF-8 (shortest forms, no surrogates), else TS_ERR_INVALID
 * naming the line, column and byte of the first bad one. */
ts_status ts_json_check_utf8(const char *text, size_t len, ts_error *err);

#endif
