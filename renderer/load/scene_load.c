/* scene_load.c — scene files of either format; see scene_load.h. */
#include "load/scene_load.h"

#include "integrators/integrator.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <cjson/cJSON.h>

#include "pbrt3/pbrt_parser.h"
#include "json/json_check.h"
#include "json/scene_json.h"
#include "core/scene_path.h"

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

ts_scene_format ts_scene_format_of(const char *path, const char *text, size_t len)
{
    if (path && ends_with(path, ".pbrt")) return TS_SCENE_FORMAT_PBRT;
    if (path && ends_with(path, ".json")) return TS_SCENE_FORMAT_JSON;
    size_t i = 0;
    if (text && len >= 3 && (unsigned char)text[0] == 0xEF && (unsigned char)text[1] == 0xBB &&
        (unsigned char)text[2] == 0xBF)
        i = 3;
    while (text && i < len && (text[i] == ' ' || text[i] == '\t' || text[i] == '\n' || text[i] == '\r'))
        i++;
    return text && i < len && text[i] == '{' ? TS_SCENE_FORMAT_JSON : TS_SCENE_FORMAT_PBRT;
}

static void pbrt_limits(const ts_scene_limits *l, ts_pbrt_limits *out)
{
    ts_pbrt_limits_default(out);
    out->max_file_bytes = l->max_file_bytes;
    out->max_memory = (size_t)l->max_memory;
    out->cancel = l->cancel;
}

/* Parses (path or text), imports into a new builder (and doc), finishes. */
static ts_status load_pbrt(const char *path, const char *text, size_t len, const char *base_dir,
                           const char *name, const ts_scene_limits *limits, ts_warning_fn warn,
                           void *warn_ctx, cJSON *doc, ts_scene **out, ts_error *err)
{
    ts_scene_limits def;
    if (!limits) {
        ts_scene_limits_default(&def);
        limits = &def;
    }
    ts_pbrt_limits pl;
    pbrt_limits(limits, &pl);
    ts_pbrt_scene *ps = NULL;
    ts_status st = path ? ts_pbrt_parse_file(path, NULL, &pl, &ps, err)
                        : ts_pbrt_parse_text(text, len, name, base_dir, &pl, &ps, err);
    if (st) return st;
    /* Text called "scene.pbrt" in positions is the scene "scene", as a file's stem names it. */
    char stem[256];
    size_t n = strlen(name);
    if (!path && n > 5 && n - 5 < sizeof stem && ends_with(name, ".pbrt")) {
        memcpy(stem, name, n - 5);
        stem[n - 5] = '\0';
        name = stem;
    }
    ts_scene_builder *b = NULL;
    st = ts_scene_builder_create(limits, ps->base_dir, &b, err);
    if (!st) st = ts_pbrt_import(ps, b, doc, warn, warn_ctx, err);
    if (!st) st = ts_scene_builder_set_name(b, name, err);
    if (!st && doc && !cJSON_AddStringToObject(doc, "name", name))
        st = ts_error_set(err, TS_ERR_NOMEM, "out of memory while converting the scene");
    ts_scene *scene = NULL;
    if (!st) st = ts_scene_builder_finish(b, &scene, err);
    if (st && !err->status) ts_error_set(err, st, "the scene could not be loaded");
    ts_scene_builder_destroy(b);
    ts_pbrt_scene_destroy(ps);
    if (!st && out)
        *out = scene;
    else
        ts_scene_destroy(scene);
    return st;
}

ts_status ts_scene_load_pbrt_text(const char *text, size_t len, const char *base_dir, const char *name,
                                  const ts_scene_limits *limits, ts_warning_fn warn, void *warn_ctx,
                                  ts_scene **out, ts_error *err)
{
    *out = NULL;
    ts_error local;
    if (!err) err = &local;
    ts_error_clear(err);
    return load_pbrt(NULL, text, len, base_dir, name ? name : "scene", limits, warn, warn_ctx, NULL, out,
                     err);
}

ts_status ts_scene_load_path(const char *path, const ts_scene_limits *limits, ts_warning_fn warn,
                             void *warn_ctx, ts_scene **out, ts_error *err)
{
    *out = NULL;
    ts_error local;
    if (!err) err = &local;
    ts_error_clear(err);
    ts_scene_format fmt = ts_scene_format_of(path, NULL, 0);
    if (!ends_with(path, ".pbrt") && !ends_with(path, ".json")) {
        /* Sniff the first bytes. */
        char head[256];
        size_t n = 0;
        FILE *f = fopen(path, "rb");
        if (f) {
            n = fread(head, 1, sizeof head, f);
            fclose(f);
        }
        fmt = ts_scene_format_of(NULL, head, n);
    }
    if (fmt == TS_SCENE_FORMAT_JSON) {
        ts_status st = ts_scene_load_file(path, limits, out, err);
        char msg[600], line[1200];
        if (!st && warn && ts_integrator_media_warning(*out, msg, sizeof msg)) {
            snprintf(line, sizeof line, "%s: %s", path, msg);
            warn(warn_ctx, line);
        }
        return st;
    }
    char dir[PATH_MAX], name[256];
    ts_scene_path_split(path, dir, sizeof dir, name, sizeof name);
    return load_pbrt(path, NULL, 0, NULL, name, limits, warn, warn_ctx, NULL, out, err);
}

ts_status ts_scene_convert_pbrt_path(const char *path, const ts_scene_limits *limits, ts_warning_fn warn,
                                     void *warn_ctx, char **json, size_t *len, ts_error *err)
{
    *json = NULL;
    *len = 0;
    ts_error local;
    if (!err) err = &local;
    ts_error_clear(err);
    cJSON *doc = cJSON_CreateObject();
    if (!doc) return ts_error_set(err, TS_ERR_NOMEM, "out of memory while converting the scene");
    char dir[PATH_MAX], name[256];
    ts_scene_path_split(path, dir, sizeof dir, name, sizeof name);
    ts_status st = load_pbrt(path, NULL, 0, NULL, name, limits, warn, warn_ctx, doc, NULL, err);
    if (!st) {
        char *text = cJSON_Print(doc);
        if (!text) {
            st = ts_error_set(err, TS_ERR_NOMEM, "out of memory while converting the scene");
        } else {
            *len = strlen(text);
            *json = text;
            /* A .pbrt name or string may hold any bytes; JSON holds UTF-8 text only. */
            ts_error u = {0};
            if (ts_json_check_utf8(text, *len, &u)) {
                st = ts_error_set(err, TS_ERR_UNSUPPORTED,
                                  "the scene holds a name or string that is not UTF-8 text, which JSON cannot hold "
                                  "(%s of the converted document): rename it in the .pbrt file",
                                  u.message + strlen("the document is not valid UTF-8 at "));
                free(text);
                *json = NULL;
                *len = 0;
            }
        }
    }
    cJSON_Delete(doc);
    return st;
}
