/* mesh_file.c — mesh files by extension; see mesh_file.h. The formats are mesh_obj.c's and
 * mesh_ply.c's; reading and confinement are scene_path.c's. */
#include "mesh/mesh_file.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/mesh_obj.h"
#include "mesh/mesh_ply.h"
#include "core/scene_path.h"

typedef enum mesh_format { FORMAT_NONE, FORMAT_OBJ, FORMAT_PLY } mesh_format;

static bool ext_is(const char *ext, const char *want)
{
    for (; *ext && *want; ext++, want++) {
        char ch = *ext >= 'A' && *ext <= 'Z' ? (char)(*ext - 'A' + 'a') : *ext;
        if (ch != *want) return false;
    }
    return *ext == '\0' && *want == '\0';
}

/* The format the extension of name's last path component names. */
static mesh_format format_of(const char *name)
{
    const char *slash = strrchr(name, '/'), *leaf = slash ? slash + 1 : name;
    const char *dot = strrchr(leaf, '.');
    if (dot && ext_is(dot + 1, "obj")) return FORMAT_OBJ;
    if (dot && ext_is(dot + 1, "ply")) return FORMAT_PLY;
    return FORMAT_NONE;
}

/* Parses a whole NUL-terminated file image; *out is set only on success. */
static ts_status parse_buffer(const ts_mesh_reader *r, mesh_format f, const char *buf, size_t size,
                              ts_mesh_data *out)
{
    return f == FORMAT_OBJ ? ts_mesh_obj_parse(r, buf, size, out) : ts_mesh_ply_parse(r, buf, size, out);
}

ts_status ts_mesh_file_load(const char *base_dir, const char *rel_path, const ts_mesh_limits *limits,
                            ts_mesh_data *out, ts_error *err)
{
    ts_mesh_reader r = {.name = rel_path ? rel_path : "", .err = err};
    if (limits) r.lim = *limits;
    if (!out) return ts_mesh_fail(&r, TS_ERR_INVALID, "no output mesh given");
    *out = (ts_mesh_data){0};
    if (!*r.name) return ts_mesh_fail(&r, TS_ERR_INVALID, "empty path");
    mesh_format f = format_of(r.name);
    if (f == FORMAT_NONE)
        return ts_mesh_fail(&r, TS_ERR_INVALID, "unknown extension (expected .obj or .ply)");
    char *buf;
    size_t size;
    ts_status st = ts_scene_path_read(base_dir && *base_dir ? base_dir : ".", r.name, "mesh file",
                                      r.lim.max_file_bytes, &buf, &size, err);
    if (st) return st;
    st = parse_buffer(&r, f, buf, size, out);
    free(buf);
    return st;
}

ts_status ts_mesh_load_memory(const char *name, const void *bytes, size_t size, const ts_mesh_limits *limits,
                              ts_mesh_data *out, ts_error *err)
{
    ts_mesh_reader r = {.name = name ? name : "", .err = err};
    if (limits) r.lim = *limits;
    if (!out) return ts_mesh_fail(&r, TS_ERR_INVALID, "no output mesh given");
    *out = (ts_mesh_data){0};
    mesh_format f = format_of(r.name);
    if (f == FORMAT_NONE)
        return ts_mesh_fail(&r, TS_ERR_INVALID, "unknown extension (expected .obj or .ply)");
    if (size == 0 || !bytes) return ts_mesh_fail(&r, TS_ERR_INVALID, "file is empty");
    if (ts_mesh_over(size, r.lim.max_file_bytes) || size >= SIZE_MAX)
        return ts_mesh_fail(&r, TS_ERR_LIMIT, "file is %llu bytes, more than the limit of %llu",
                            (unsigned long long)size,
                            (unsigned long long)(r.lim.max_file_bytes ? r.lim.max_file_bytes : SIZE_MAX - 1));
    /* The parsers rely on a terminating NUL (strtod), so parse a copy. */
    char *buf = malloc(size + 1);
    if (!buf) return ts_mesh_nomem(&r);
    memcpy(buf, bytes, size);
    buf[size] = '\0';
    ts_status st = parse_buffer(&r, f, buf, size, out);
    free(buf);
    return st;
}
