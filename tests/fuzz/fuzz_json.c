/* fuzz_json.c — libFuzzer harness: the JSON and path helpers under the scene loader.
 * The input is parsed with ts_json_parse; a document that parses is canonicalised and
 * digested (scene_digest.h) and walked, every member of every object read through every
 * typed getter of json_check.h (each must either succeed or fail with a sentence that
 * starts with the member's JSON path) and described. Independently, the input's first
 * line is taken as a file reference (scene_path.h: split, resolve against this process's
 * private folder, which must never resolve outside it) and as a `--shard I/N` argument. */
#include "fuzz_common.h"

#include <limits.h>
#include <math.h>
#include <stdbool.h>

#include "render/shard.h"
#include "json/json_check.h"
#include "json/scene_digest.h"
#include "core/scene_path.h"

static int g_calls;

static void check_getter(ts_status st, const ts_error *err, const char *path)
{
    if (st == TS_OK) return;
    FUZZ_CHECK(err->status == st && err->message[0] != '\0');
    /* The sentence names the member's path (truncated paths excepted). */
    if (strlen(path) < TS_JPATH_MAX - 1 && path[0]) FUZZ_CHECK(strncmp(err->message, path, strlen(path)) == 0);
}

static void walk(const cJSON *v, const char *path, int depth)
{
    char desc[64];
    ts_json_describe(v, desc, sizeof desc);
    FUZZ_CHECK(memchr(desc, '\0', sizeof desc) != NULL);
    if (depth > 64 || ++g_calls > 4096) return;
    if (cJSON_IsArray(v)) {
        int i = 0;
        for (const cJSON *e = v->child; e; e = e->next, i++) {
            ts_jpath p = ts_jpath_index(path, i);
            walk(e, p.s, depth + 1);
        }
        return;
    }
    if (!cJSON_IsObject(v)) return;
    static const char *const allowed[] = {"type", "camera", "film", "shapes", "name", NULL};
    static const char *const choices[] = {"sphere", "disk", "path", "direct", NULL};
    ts_error err = {0};
    (void)ts_json_check_object(v, path, allowed, &err);
    for (const cJSON *m = v->child; m; m = m->next) {
        const char *key = m->string ? m->string : "";
        ts_jpath p = ts_jpath_key(path, key);
        double d;
        int64_t i64;
        bool b;
        const char *s;
        int e;
        ts_vec3 v3;
        ts_rgb rgb;
        const cJSON *sub;
        for (int range = TS_J_ANY; range <= TS_J_UNIT; range++) {
            ts_error_clear(&err);
            check_getter(ts_json_number(v, path, key, true, (ts_jrange)range, &d, &err), &err, p.s);
        }
        ts_error_clear(&err);
        check_getter(ts_json_int(v, path, key, true, INT64_MIN, INT64_MAX, &i64, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_int(v, path, key, true, -3, 1000, &i64, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_bool(v, path, key, true, &b, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_string(v, path, key, true, &s, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_enum(v, path, key, true, choices, &e, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_vec3(v, path, key, true, true, &v3, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_rgb(v, path, key, true, TS_J_NONNEG, &rgb, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_rgb(v, path, key, true, TS_J_UNIT, &rgb, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_array(v, path, key, true, &sub, &err), &err, p.s);
        ts_error_clear(&err);
        check_getter(ts_json_object(v, path, key, true, &sub, &err), &err, p.s);
        walk(m, p.s, depth + 1);
    }
}

static bool has_nonfinite(const cJSON *v)
{
    if (cJSON_IsNumber(v) && !isfinite(v->valuedouble)) return true;
    for (const cJSON *c = v->child; c; c = c->next)
        if (has_nonfinite(c)) return true;
    return false;
}

static void use_path_helpers(const uint8_t *data, size_t size)
{
    char line[512];
    size_t n = 0;
    while (n < size && n < sizeof line - 1 && data[n] != '\n' && data[n] != '\0') n++;
    memcpy(line, data, n);
    line[n] = '\0';
    char dir[256], stem[64];
    ts_scene_path_split(line, dir, sizeof dir, stem, sizeof stem);
    FUZZ_CHECK(memchr(dir, '\0', sizeof dir) && memchr(stem, '\0', sizeof stem));
    char resolved[PATH_MAX + 1];
    ts_error err = {0};
    const char *base = fuzz_dir();
    if (ts_scene_path_resolve(base, line, resolved, sizeof resolved, &err) == TS_OK) {
        size_t bl = strlen(base);
        /* Inside the folder: the folder itself or below it. (/tmp may be a symlink, so
         * compare with the folder's own real path.) */
        char real_base[PATH_MAX + 1];
        FUZZ_CHECK(realpath(base, real_base) != NULL);
        bl = strlen(real_base);
        FUZZ_CHECK(strncmp(resolved, real_base, bl) == 0 && (resolved[bl] == '\0' || resolved[bl] == '/'));
    } else {
        FUZZ_CHECK(err.message[0] != '\0');
    }
    uint32_t index, count;
    ts_error_clear(&err);
    if (ts_shard_parse(line, &index, &count, &err) == TS_OK) FUZZ_CHECK(index < count && count <= 1000000);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    char path[128];
    fuzz_write_file("scene.json", "{}", 2, path, sizeof path); /* something to resolve to */
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    use_path_helpers(data, size);
    cJSON *doc = NULL;
    ts_error err = {0};
    ts_status st = ts_json_parse((const char *)data, size, &doc, &err);
    if (st != TS_OK) {
        FUZZ_CHECK(doc == NULL && err.message[0] != '\0');
        return 0;
    }
    char *canon = NULL;
    size_t len = 0;
    ts_error_clear(&err);
    if (ts_scene_canonical_text(doc, &canon, &len, &err) == TS_OK) {
        FUZZ_CHECK(canon && strlen(canon) == len);
    }
    /* Canonical text is a fixed point: parsing it and canonicalising again gives it back.
     * Not for documents with a number literal beyond double range (1e400): cJSON reads it
     * as inf, which the canonical form prints as `inf`, not JSON (scene_digest.c; such a
     * scene is refused by validation anyway; a known limit of the canonical form). */
    if (canon && !has_nonfinite(doc)) {
        cJSON *again = NULL;
        ts_error e2 = {0};
        FUZZ_CHECK(ts_json_parse(canon, len, &again, &e2) == TS_OK);
        char *canon2 = NULL;
        size_t len2 = 0;
        FUZZ_CHECK(ts_scene_canonical_text(again, &canon2, &len2, &e2) == TS_OK);
        FUZZ_CHECK(len2 == len && memcmp(canon, canon2, len) == 0);
        free(canon2);
        cJSON_Delete(again);
    }
    free(canon);
    char hex[TS_SCENE_DIGEST_HEX_LEN + 1];
    ts_error_clear(&err);
    (void)ts_scene_digest_text((const char *)data, size, hex, &err);
    g_calls = 0;
    walk(doc, "", 0);
    cJSON_Delete(doc);
    return 0;
}
