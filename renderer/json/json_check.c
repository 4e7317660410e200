/* json_check.c — path-aware JSON validation; see json_check.h. */
#include "json/json_check.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

ts_jpath ts_jpath_key(const char *parent, const char *key)
{
    ts_jpath p;
    if (parent && parent[0]) snprintf(p.s, sizeof p.s, "%s.%s", parent, key);
    else snprintf(p.s, sizeof p.s, "%s", key);
    return p;
}

ts_jpath ts_jpath_index(const char *parent, int i)
{
    ts_jpath p;
    snprintf(p.s, sizeof p.s, "%s[%d]", parent, i);
    return p;
}

void ts_json_describe(const cJSON *v, char *buf, size_t n)
{
    if (!v) snprintf(buf, n, "nothing");
    else if (cJSON_IsNumber(v)) snprintf(buf, n, "%.17g", v->valuedouble);
    else if (cJSON_IsString(v)) {
        const char *s = v->valuestring;
        size_t len = strlen(s);
        if (len > 40) snprintf(buf, n, "\"%.40s...\"", s);
        else snprintf(buf, n, "\"%s\"", s);
    } else if (cJSON_IsBool(v)) snprintf(buf, n, "%s", cJSON_IsTrue(v) ? "true" : "false");
    else if (cJSON_IsNull(v)) snprintf(buf, n, "null");
    else if (cJSON_IsArray(v)) snprintf(buf, n, "an array of %d", cJSON_GetArraySize(v));
    else if (cJSON_IsObject(v)) snprintf(buf, n, "an object");
    else snprintf(buf, n, "an invalid value");
}

static ts_status bad(ts_error *err, const char *path, const char *key, const char *expected, const cJSON *got)
{
    char d[64];
    ts_json_describe(got, d, sizeof d);
    ts_jpath p = key ? ts_jpath_key(path, key) : ts_jpath_key("", path);
    return ts_error_set(err, TS_ERR_INVALID, "%s: expected %s, got %s", p.s, expected, d);
}

static ts_status missing(ts_error *err, const char *path, const char *key, const char *expected)
{
    ts_jpath p = ts_jpath_key(path, key);
    return ts_error_set(err, TS_ERR_INVALID, "%s: required (%s) but missing", p.s, expected);
}

ts_status ts_json_check_object(const cJSON *obj, const char *path, const char *const *allowed, ts_error *err)
{
    if (!cJSON_IsObject(obj)) return bad(err, path[0] ? path : "(document)", NULL, "an object", obj);
    for (const cJSON *c = obj->child; c; c = c->next) {
        bool ok = false;
        for (const char *const *a = allowed; *a; a++)
            if (strcmp(*a, c->string) == 0) ok = true;
        ts_jpath p = ts_jpath_key(path, c->string);
        if (!ok) {
            char list[256] = "";
            size_t used = 0;
            for (const char *const *a = allowed; *a && used < sizeof list - 40; a++)
                used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", a == allowed ? "" : ", ", *a);
            return ts_error_set(err, TS_ERR_INVALID, "%s: unknown key (allowed here: %s)", p.s, list);
        }
        for (const cJSON *d = obj->child; d != c; d = d->next)
            if (strcmp(d->string, c->string) == 0)
                return ts_error_set(err, TS_ERR_INVALID, "%s: key given twice", p.s);
    }
    return TS_OK;
}

static const cJSON *get(const cJSON *obj, const char *key) { return cJSON_GetObjectItemCaseSensitive(obj, key); }

static const char *range_words(ts_jrange r)
{
    switch (r) {
    case TS_J_ANY: return "a finite number";
    case TS_J_POSITIVE: return "a positive number";
    case TS_J_NONNEG: return "a non-negative number";
    case TS_J_UNIT: return "a number in [0, 1]";
    }
    return "a number";
}

static bool in_range(double v, ts_jrange r)
{
    if (!isfinite(v)) return false;
    switch (r) {
    case TS_J_ANY: return true;
    case TS_J_POSITIVE: return v > 0;
    case TS_J_NONNEG: return v >= 0;
    case TS_J_UNIT: return v >= 0 && v <= 1;
    }
    return false;
}

/* Scene numbers become floats (docs/design.md §4): NULL when v (in range as a double) is
 * also usable as the float it becomes, else why not — beyond the float range (it would be
 * infinite), or a positive number so small it would be 0. */
static const char *float_trouble(double v, ts_jrange r)
{
    float f = (float)v;
    if (!isfinite(f)) return "beyond the range of a float (at most 3.4e38 in magnitude)";
    if (r == TS_J_POSITIVE && f == 0) return "too small for a float (it would be 0)";
    return NULL;
}

/* The refusal of a number in range as a double but not as a float (path.key or path). */
static ts_status not_a_float(ts_error *err, const char *path, const char *key, double v, const char *why)
{
    ts_jpath p = key ? ts_jpath_key(path, key) : ts_jpath_key("", path);
    return ts_error_set(err, TS_ERR_INVALID, "%s: %.9g is %s", p.s, v, why);
}

ts_status ts_json_number(const cJSON *obj, const char *path, const char *key, bool required, ts_jrange range,
                         double *out, ts_error *err)
{
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, range_words(range)) : TS_OK;
    if (!cJSON_IsNumber(v) || !in_range(v->valuedouble, range)) return bad(err, path, key, range_words(range), v);
    const char *why = float_trouble(v->valuedouble, range);
    if (why) return not_a_float(err, path, key, v->valuedouble, why);
    *out = v->valuedouble;
    return TS_OK;
}

ts_status ts_json_int(const cJSON *obj, const char *path, const char *key, bool required, int64_t lo, int64_t hi,
                      int64_t *out, ts_error *err)
{
    char words[96];
    snprintf(words, sizeof words, "an integer in [%lld, %lld]", (long long)lo, (long long)hi);
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, words) : TS_OK;
    if (!cJSON_IsNumber(v)) return bad(err, path, key, words, v);
    double d = v->valuedouble;
    if (!isfinite(d) || d != floor(d) || d < (double)lo || d > (double)hi) return bad(err, path, key, words, v);
    *out = (int64_t)d;
    return TS_OK;
}

ts_status ts_json_bool(const cJSON *obj, const char *path, const char *key, bool required, bool *out, ts_error *err)
{
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, "true or false") : TS_OK;
    if (!cJSON_IsBool(v)) return bad(err, path, key, "true or false", v);
    *out = cJSON_IsTrue(v);
    return TS_OK;
}

ts_status ts_json_string(const cJSON *obj, const char *path, const char *key, bool required, const char **out,
                         ts_error *err)
{
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, "a string") : TS_OK;
    if (!cJSON_IsString(v) || !v->valuestring[0]) return bad(err, path, key, "a non-empty string", v);
    *out = v->valuestring;
    return TS_OK;
}

ts_status ts_json_enum(const cJSON *obj, const char *path, const char *key, bool required, const char *const *choices,
                       int *out, ts_error *err)
{
    char words[200] = "one of ";
    size_t used = strlen(words);
    for (const char *const *c = choices; *c && used < sizeof words - 40; c++)
        used += (size_t)snprintf(words + used, sizeof words - used, "%s\"%s\"", c == choices ? "" : ", ", *c);
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, words) : TS_OK;
    if (cJSON_IsString(v))
        for (int i = 0; choices[i]; i++)
            if (strcmp(choices[i], v->valuestring) == 0) {
                *out = i;
                return TS_OK;
            }
    return bad(err, path, key, words, v);
}

static ts_status numbers(const cJSON *v, const char *path, const char *key, int n, ts_jrange range, float *out,
                         const char *words, ts_error *err)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n) return bad(err, path, key, words, v);
    int i = 0;
    for (const cJSON *c = v->child; c; c = c->next, i++) {
        if (!cJSON_IsNumber(c) || !in_range(c->valuedouble, range)) {
            ts_jpath p = ts_jpath_key(path, key);
            ts_jpath pi = ts_jpath_index(p.s, i);
            char d[64];
            ts_json_describe(c, d, sizeof d);
            return ts_error_set(err, TS_ERR_INVALID, "%s: expected %s, got %s", pi.s, range_words(range), d);
        }
        const char *why = float_trouble(c->valuedouble, range);
        if (why) {
            ts_jpath p = ts_jpath_key(path, key);
            ts_jpath pi = ts_jpath_index(p.s, i);
            return not_a_float(err, pi.s, NULL, c->valuedouble, why);
        }
        out[i] = (float)c->valuedouble;
    }
    return TS_OK;
}

ts_status ts_json_vec3(const cJSON *obj, const char *path, const char *key, bool required, bool nonzero,
                       ts_vec3 *out, ts_error *err)
{
    const char *words = nonzero ? "an array of 3 numbers, not all zero" : "an array of 3 numbers";
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, words) : TS_OK;
    float f[3];
    ts_status st = numbers(v, path, key, 3, TS_J_ANY, f, words, err);
    if (st) return st;
    if (nonzero && f[0] == 0 && f[1] == 0 && f[2] == 0) return bad(err, path, key, words, v);
    *out = (ts_vec3){f[0], f[1], f[2]};
    return TS_OK;
}

ts_status ts_json_rgb(const cJSON *obj, const char *path, const char *key, bool required, ts_jrange range,
                      ts_rgb *out, ts_error *err)
{
    const char *words = range == TS_J_UNIT ? "an RGB array of 3 numbers in [0, 1]"
                                            : "an RGB array of 3 non-negative numbers";
    const cJSON *v = get(obj, key);
    if (!v) return required ? missing(err, path, key, words) : TS_OK;
    if (cJSON_IsNumber(v)) {
        if (!in_range(v->valuedouble, range)) return bad(err, path, key, words, v);
        const char *why = float_trouble(v->valuedouble, range);
        if (why) return not_a_float(err, path, key, v->valuedouble, why);
        *out = ts_rgb_gray((float)v->valuedouble);
        return TS_OK;
    }
    float f[3];
    ts_status st = numbers(v, path, key, 3, range, f, words, err);
    if (st) return st;
    *out = (ts_rgb){f[0], f[1], f[2]};
    return TS_OK;
}

ts_status ts_json_array(const cJSON *obj, const char *path, const char *key, bool required, const cJSON **out,
                        ts_error *err)
{
    const cJSON *v = get(obj, key);
    *out = NULL;
    if (!v) return required ? missing(err, path, key, "an array") : TS_OK;
    if (!cJSON_IsArray(v)) return bad(err, path, key, "an array", v);
    *out = v;
    return TS_OK;
}

ts_status ts_json_object(const cJSON *obj, const char *path, const char *key, bool required, const cJSON **out,
                         ts_error *err)
{
    const cJSON *v = get(obj, key);
    *out = NULL;
    if (!v) return required ? missing(err, path, key, "an object") : TS_OK;
    if (!cJSON_IsObject(v)) return bad(err, path, key, "an object", v);
    *out = v;
    return TS_OK;
}

static bool strings_fit(const cJSON *o, char *path, size_t at, size_t cap, ts_error *err)
{
    if (cJSON_IsString(o)) {
        size_t n = strlen(o->valuestring);
        bool file = o->string && (!strcmp(o->string, "file") || !strcmp(o->string, "map"));
        size_t max = file ? TS_JSON_MAX_PATH_STRING : TS_JSON_MAX_STRING;
        if (n <= max) return true;
        ts_error_set(err, TS_ERR_INVALID, "%s: a string of %zu bytes is longer than the limit of %zu",
                     path[0] ? path : "(document)", n, max);
        return false;
    }
    int i = 0;
    for (const cJSON *c = o->child; c; c = c->next, i++) {
        if (cJSON_IsObject(o) && c->string && strlen(c->string) > TS_JSON_MAX_STRING) {
            ts_error_set(err, TS_ERR_INVALID, "%s: a key of %zu bytes is longer than the limit of %d",
                         path[0] ? path : "(document)", strlen(c->string), TS_JSON_MAX_STRING);
            return false;
        }
        int w = cJSON_IsArray(o) ? snprintf(path + at, cap - at, "[%d]", i)
                                 : snprintf(path + at, cap - at, "%s%s", at ? "." : "", c->string ? c->string : "");
        size_t n = w > 0 ? (size_t)w : 0;
        if (!strings_fit(c, path, at + n < cap ? at + n : cap - 1, cap, err)) return false;
        path[at] = '\0';
    }
    return true;
}

ts_status ts_json_check_strings(const cJSON *doc, ts_error *err)
{
    char path[TS_JPATH_MAX] = "";
    return strings_fit(doc, path, 0, sizeof path, err) ? TS_OK : TS_ERR_INVALID;
}

/* Offset of the first byte of text that does not start a complete, shortest-form UTF-8
 * sequence of a scalar value (no surrogates, at most U+10FFFF), or len. */
static size_t utf8_invalid_at(const unsigned char *t, size_t len)
{
    size_t i = 0;
    while (i < len) {
        unsigned c = t[i];
        size_t n = c < 0x80 ? 1 : (c & 0xe0) == 0xc0 ? 2 : (c & 0xf0) == 0xe0 ? 3 : (c & 0xf8) == 0xf0 ? 4 : 0;
        if (!n || i + n > len) return i;
        uint32_t v = n == 1 ? c : n == 2 ? (c & 0x1f) : n == 3 ? (c & 0x0f) : (c & 0x07);
        for (size_t k = 1; k < n; k++) {
            if ((t[i + k] & 0xc0) != 0x80) return i;
            v = (v << 6) | (t[i + k] & 0x3f);
        }
        static const uint32_t min[5] = {0, 0, 0x80, 0x800, 0x10000};
        if (v < min[n] || v > 0x10ffff || (v >= 0xd800 && v <= 0xdfff)) return i;
        i += n;
    }
    return len;
}

/* Line and column (1-based) of byte off. */
static void line_col(const char *text, size_t off, int *line, int *col)
{
    *line = 1, *col = 1;
    for (size_t i = 0; i < off; i++) {
        if (text[i] == '\n') ++*line, *col = 1;
        else ++*col;
    }
}

ts_status ts_json_check_utf8(const char *text, size_t len, ts_error *err)
{
    size_t bad = utf8_invalid_at((const unsigned char *)text, len);
    if (bad == len) return TS_OK;
    int line, col;
    line_col(text, bad, &line, &col);
    return ts_error_set(err, TS_ERR_INVALID, "the document is not valid UTF-8 at line %d, column %d (byte %zu)", line,
                        col, bad);
}

ts_status ts_json_parse(const char *text, size_t len, cJSON **out, ts_error *err)
{
    *out = NULL;
    /* JSON text is UTF-8 (RFC 8259); cJSON would pass other bytes through into names and
     * messages that the server then echoes. */
    ts_status ust = ts_json_check_utf8(text, len, err);
    if (ust) return ust;
    const char *end = NULL;
    /* cJSON records the position of a syntax error in a static variable; parses are
     * serialised so concurrent loads (server threads) do not race on it. */
    static pthread_mutex_t parse_lock = PTHREAD_MUTEX_INITIALIZER;
    pthread_mutex_lock(&parse_lock);
    errno = 0;
    cJSON *doc = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    /* cJSON answers NULL for a failed allocation too; malloc then set ENOMEM (nothing
     * else in a parse does: strtod sets at most ERANGE). */
    bool nomem = !doc && errno == ENOMEM;
    pthread_mutex_unlock(&parse_lock);
    if (nomem) return ts_error_set(err, TS_ERR_NOMEM, "out of memory while parsing the JSON document");
    if (!doc) {
        /* cJSON reports where it stopped; turn the offset into line and column. */
        size_t off = (end && end >= text && (size_t)(end - text) <= len) ? (size_t)(end - text) : 0;
        int line, col;
        line_col(text, off, &line, &col);
        if (len == 0) return ts_error_set(err, TS_ERR_INVALID, "the document is empty");
        return ts_error_set(err, TS_ERR_INVALID, "malformed JSON at line %d, column %d (byte %zu)", line, col, off);
    }
    /* Anything but white space after the value is an error too. */
    size_t off = (size_t)(end - text);
    for (size_t i = off; i < len; i++) {
        char c = text[i];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r' && c != '\0') {
            cJSON_Delete(doc);
            return ts_error_set(err, TS_ERR_INVALID, "malformed JSON: unexpected text after the document at byte %zu", i);
        }
    }
    *out = doc;
    return TS_OK;
}
