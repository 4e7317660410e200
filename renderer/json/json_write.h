/* json_write.h — writing scene format v1 with cJSON: the one set of helpers every writer of
 * a v1 document uses (the pbrt-v3 importer's document for `tessera convert`, the textures
 * section's writer).
 *
 * Design note: each helper either adds its item to the object or, out of memory, frees it
 * and returns false (the array makers return NULL), so a writer chains them with && and
 * frees only its root on failure. Numbers are written as doubles (cJSON prints them
 * round-trip), so a float written and read back is the same float. One thread. */
#ifndef TS_JSON_WRITE_H
#define TS_JSON_WRITE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "core/vecmath.h"
#include "core/transform.h"

/* Arrays of n numbers; NULL when out of memory. */
cJSON *ts_jw_doubles(const double *v, size_t n);
cJSON *ts_jw_floats(const float *v, size_t n);
cJSON *ts_jw_uints(const uint32_t *v, size_t n);

/* obj[key] = item; false (item freed) when item is NULL or out of memory. */
bool ts_jw_add(cJSON *obj, const char *key, cJSON *item);

bool ts_jw_number(cJSON *obj, const char *key, double v);
bool ts_jw_string(cJSON *obj, const char *key, const char *v);
bool ts_jw_bool(cJSON *obj, const char *key, bool v);
bool ts_jw_vec3(cJSON *obj, const char *key, ts_vec3 v);
bool ts_jw_rgb(cJSON *obj, const char *key, ts_rgb c);
/* obj[key] = the 16 numbers of m, row-major */
bool ts_jw_matrix(cJSON *obj, const char *key, const ts_mat4 *m);

/* v1's transform list of one step: [{"matrix": the 16 numbers of m, row-major}]; NULL when
 * out of memory. */
cJSON *ts_jw_transform(const ts_mat4 *m);

#endif
