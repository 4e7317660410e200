/* doc_rows.h — the schema, and the rows of docs/pbrt-v3.md's tables, for the tests that hold a type's
 * description (test_*_desc.c) to what the user reads: the row whose first cell names a
 * pbrt-v3 type in backquotes must name each parameter the table reads, in backquotes. */
#ifndef TS_TEST_DOC_ROWS_H
#define TS_TEST_DOC_ROWS_H

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

/* The file at rel (from the repository root, TS_SOURCE_DIR) as one string (malloc'd), or
 * NULL. */
static inline char *doc_rows_read(const char *rel)
{
    const char *src = getenv("TS_SOURCE_DIR");
    if (!src) return NULL;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", src, rel);
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    if (buf) buf[n] = 0;
    fclose(f);
    return buf;
}

/* docs/pbrt-v3.md, or NULL. */
static inline char *doc_rows_load(void) { return doc_rows_read("docs/pbrt-v3.md"); }

/* proto/scene.schema.json parsed (the caller deletes it), or NULL. */
static inline cJSON *doc_rows_schema(void)
{
    char *text = doc_rows_read("proto/scene.schema.json");
    cJSON *s = text ? cJSON_Parse(text) : NULL;
    free(text);
    return s;
}

/* The entry of the schema's $defs.DEF.oneOf whose "type" is the constant `type` (its
 * object, with "properties" and "required"), or NULL. */
static inline const cJSON *doc_rows_schema_alt(const cJSON *schema, const char *def, const char *type)
{
    const cJSON *d = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(schema, "$defs"), def);
    const cJSON *alt;
    cJSON_ArrayForEach(alt, cJSON_GetObjectItemCaseSensitive(d, "oneOf"))
    {
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(
            cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(alt, "properties"), "type"), "const");
        if (cJSON_IsString(c) && strcmp(c->valuestring, type) == 0) return alt;
    }
    return NULL;
}

/* Whether a schema entry's "required" lists key. */
static inline bool doc_rows_schema_required(const cJSON *alt, const char *key)
{
    const cJSON *e;
    cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(alt, "required"))
    if (cJSON_IsString(e) && strcmp(e->valuestring, key) == 0) return true;
    return false;
}

/* The table row (a line starting "| ") whose first cell holds `type` in backquotes, copied
 * into row (false when there is none). `after`: a heading the row must follow ("## Lights"),
 * so that a name two tables share is looked up in the right one. */
static inline bool doc_rows_find(const char *doc, const char *after, const char *type, char *row, size_t n)
{
    const char *p = after ? strstr(doc, after) : doc;
    if (!p) return false;
    char want[128];
    snprintf(want, sizeof want, "`%s`", type);
    for (const char *line = p; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        if (strncmp(line, "## ", 3) == 0 && line != p) return false; /* the section ended */
        if (strncmp(line, "| ", 2) != 0) continue;
        const char *end = strchr(line + 2, '|'), *eol = strchr(line, '\n');
        if (!end) continue;
        const char *hit = strstr(line, want);
        if (hit && hit < end) {
            size_t len = eol ? (size_t)(eol - line) : strlen(line);
            if (len >= n) len = n - 1;
            memcpy(row, line, len);
            row[len] = 0;
            return true;
        }
    }
    return false;
}

/* Whether row names `param` in backquotes. */
static inline bool doc_rows_names(const char *row, const char *param)
{
    char want[128];
    snprintf(want, sizeof want, "`%s`", param);
    return strstr(row, want) != NULL;
}

#endif
