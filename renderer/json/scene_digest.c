/* scene_digest.c — canonical scene text and its SHA-256; see scene_digest.h and
 * proto/scene-digest.md. */
#include "json/scene_digest.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <nettle/sha2.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json/json_check.h"

#define MAX_DEPTH 256

typedef struct buf {
    char *p;
    size_t len, cap;
    bool nomem;
} buf;

static void put(buf *b, const char *s, size_t n)
{
    if (b->nomem) return;
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 1024;
        while (cap < b->len + n + 1) cap *= 2;
        char *p = realloc(b->p, cap);
        if (!p) {
            b->nomem = true;
            return;
        }
        b->p = p, b->cap = cap;
    }
    memcpy(b->p + b->len, s, n);
    b->len += n;
    b->p[b->len] = '\0';
}

static void puts_(buf *b, const char *s) { put(b, s, strlen(s)); }

static void put_string(buf *b, const char *s)
{
    put(b, "\"", 1);
    for (const unsigned char *c = (const unsigned char *)s; *c; c++) {
        char esc[8];
        if (*c == '"') put(b, "\\\"", 2);
        else if (*c == '\\') put(b, "\\\\", 2);
        else if (*c < 0x20) {
            snprintf(esc, sizeof esc, "\\u%04x", *c);
            put(b, esc, 6);
        } else put(b, (const char *)c, 1);
    }
    put(b, "\"", 1);
}

/* Integers of magnitude below 2^53 without exponent or fraction; anything else the
 * shortest %.Ng (N = 1..17) that reads back to the same double. -0 is 0. */
static void put_number(buf *b, double v)
{
    char s[40];
    if (v == 0) v = 0; /* -0 → 0 */
    if (v == floor(v) && fabs(v) < 9007199254740992.0) {
        snprintf(s, sizeof s, "%.0f", v);
    } else {
        for (int prec = 1; prec <= 17; prec++) {
            snprintf(s, sizeof s, "%.*g", prec, v);
            if (strtod(s, NULL) == v) break;
        }
    }
    puts_(b, s);
}

static int key_cmp(const void *a, const void *b)
{
    const cJSON *x = *(const cJSON *const *)a, *y = *(const cJSON *const *)b;
    return strcmp(x->string ? x->string : "", y->string ? y->string : "");
}

/* Where a value sits, for the two keys the canonical form leaves out. */
typedef enum where { ANYWHERE, TOP, TOP_FILM } where;

static bool left_out(where w, const char *key)
{
    return key && ((w == TOP && strcmp(key, "job") == 0) || (w == TOP_FILM && strcmp(key, "crop") == 0));
}

/* False when nested deeper than MAX_DEPTH; out of memory is flagged in b. */
static bool emit(buf *b, const cJSON *v, int depth, where w)
{
    if (depth > MAX_DEPTH) return false;
    if (cJSON_IsObject(v)) {
        size_t n = 0;
        for (const cJSON *c = v->child; c; c = c->next) n++;
        const cJSON **kids = n ? malloc(n * sizeof *kids) : NULL;
        if (n && !kids) {
            b->nomem = true;
            return true;
        }
        size_t k = 0;
        for (const cJSON *c = v->child; c; c = c->next)
            if (!left_out(w, c->string)) kids[k++] = c;
        if (k > 1) qsort(kids, k, sizeof *kids, key_cmp);
        put(b, "{", 1);
        bool ok = true;
        for (size_t i = 0; i < k && ok; i++) {
            if (i) put(b, ",", 1);
            put_string(b, kids[i]->string ? kids[i]->string : "");
            put(b, ":", 1);
            where cw = w == TOP && kids[i]->string && strcmp(kids[i]->string, "film") == 0 ? TOP_FILM : ANYWHERE;
            ok = emit(b, kids[i], depth + 1, cw);
        }
        put(b, "}", 1);
        free(kids);
        return ok;
    }
    if (cJSON_IsArray(v)) {
        put(b, "[", 1);
        bool ok = true;
        int i = 0;
        for (const cJSON *c = v->child; c && ok; c = c->next, i++) {
            if (i) put(b, ",", 1);
            ok = emit(b, c, depth + 1, ANYWHERE);
        }
        put(b, "]", 1);
        return ok;
    }
    if (cJSON_IsString(v)) put_string(b, v->valuestring ? v->valuestring : "");
    else if (cJSON_IsNumber(v)) put_number(b, v->valuedouble);
    else if (cJSON_IsTrue(v)) puts_(b, "true");
    else if (cJSON_IsFalse(v)) puts_(b, "false");
    else puts_(b, "null");
    return true;
}

ts_status ts_scene_canonical_text(const cJSON *doc, char **out, size_t *len, ts_error *err)
{
    buf b = {0};
    *out = NULL;
    if (len) *len = 0;
    bool ok = emit(&b, doc, 0, TOP);
    if (!ok) {
        free(b.p);
        return ts_error_set(err, TS_ERR_INVALID, "the scene document is nested deeper than %d levels", MAX_DEPTH);
    }
    if (b.nomem || !b.p) {
        free(b.p);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory while computing the scene digest");
    }
    *out = b.p;
    if (len) *len = b.len;
    return TS_OK;
}

ts_status ts_scene_digest(const cJSON *doc, char hex[TS_SCENE_DIGEST_HEX_LEN + 1], ts_error *err)
{
    char *text;
    size_t len;
    hex[0] = '\0';
    ts_status st = ts_scene_canonical_text(doc, &text, &len, err);
    if (st) return st;
    struct sha256_ctx ctx;
    uint8_t d[SHA256_DIGEST_SIZE];
    sha256_init(&ctx);
    sha256_update(&ctx, len, (const uint8_t *)text);
    sha256_digest(&ctx, sizeof d, d);
    free(text);
    for (int i = 0; i < SHA256_DIGEST_SIZE; i++) snprintf(hex + 2 * i, 3, "%02x", d[i]);
    return TS_OK;
}

ts_status ts_scene_digest_text(const char *text, size_t len, char hex[TS_SCENE_DIGEST_HEX_LEN + 1], ts_error *err)
{
    cJSON *doc = NULL;
    hex[0] = '\0';
    ts_status st = ts_json_parse(text, len, &doc, err);
    if (st) return st;
    st = ts_scene_digest(doc, hex, err);
    cJSON_Delete(doc);
    return st;
}
