/* json_write.c — writing scene format v1 with cJSON (json_write.h). */
#include "json/json_write.h"

/* An array of n numbers, the k-th get(v, k). */
static cJSON *number_array(const void *v, size_t n, double (*get)(const void *, size_t))
{
    cJSON *a = cJSON_CreateArray();
    for (size_t i = 0; a && i < n; i++) {
        cJSON *x = cJSON_CreateNumber(get(v, i));
        if (!x || !cJSON_AddItemToArray(a, x)) {
            cJSON_Delete(x);
            cJSON_Delete(a);
            return NULL;
        }
    }
    return a;
}

static double get_double(const void *v, size_t k) { return ((const double *)v)[k]; }
static double get_float(const void *v, size_t k) { return ((const float *)v)[k]; }
static double get_uint(const void *v, size_t k) { return ((const uint32_t *)v)[k]; }

cJSON *ts_jw_doubles(const double *v, size_t n) { return number_array(v, n, get_double); }
cJSON *ts_jw_floats(const float *v, size_t n) { return number_array(v, n, get_float); }
cJSON *ts_jw_uints(const uint32_t *v, size_t n) { return number_array(v, n, get_uint); }

bool ts_jw_add(cJSON *obj, const char *key, cJSON *item)
{
    if (!item) return false;
    if (!cJSON_AddItemToObject(obj, key, item)) {
        cJSON_Delete(item);
        return false;
    }
    return true;
}

bool ts_jw_number(cJSON *obj, const char *key, double v) { return ts_jw_add(obj, key, cJSON_CreateNumber(v)); }
bool ts_jw_string(cJSON *obj, const char *key, const char *v) { return ts_jw_add(obj, key, cJSON_CreateString(v)); }
bool ts_jw_bool(cJSON *obj, const char *key, bool v) { return ts_jw_add(obj, key, cJSON_CreateBool(v)); }

bool ts_jw_vec3(cJSON *obj, const char *key, ts_vec3 v)
{
    double d[3] = {v.x, v.y, v.z};
    return ts_jw_add(obj, key, ts_jw_doubles(d, 3));
}

bool ts_jw_rgb(cJSON *obj, const char *key, ts_rgb c)
{
    double d[3] = {c.r, c.g, c.b};
    return ts_jw_add(obj, key, ts_jw_doubles(d, 3));
}

bool ts_jw_matrix(cJSON *obj, const char *key, const ts_mat4 *m)
{
    return ts_jw_add(obj, key, ts_jw_doubles(&m->m[0][0], 16));
}

cJSON *ts_jw_transform(const ts_mat4 *m)
{
    cJSON *list = cJSON_CreateArray(), *step = cJSON_CreateObject();
    if (!list || !step || !ts_jw_matrix(step, "matrix", m) || !cJSON_AddItemToArray(list, step)) {
        cJSON_Delete(step);
        cJSON_Delete(list);
        return NULL;
    }
    return list;
}
