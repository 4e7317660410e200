/* mesh_file.h — triangle meshes read from Wavefront OBJ and PLY files for `mesh` shapes.
 *
 * Design note: a mesh file is untrusted scene input. The path is confined to the scene's
 * folder (docs/design.md §4) after every symlink is resolved (scene_path.h, the one
 * confinement rule for every file a scene names); the whole file is read into
 * memory (bounded by max_file_bytes) and parsed in place; every count a header or a
 * pre-pass announces is checked against the limits and the file size before anything
 * of that size is allocated. Parse errors name the file and the line (OBJ, ASCII PLY) or
 * the byte offset and element (binary PLY). The result is a plain indexed triangle list
 * in the file's object space; the scene loader transforms and copies it into its arena.
 *
 * Formats (chosen by extension, case-insensitive):
 *   .obj  v (x y z [w ignored]; further numbers such as vertex colours are ignored),
 *         vt (u [v [w]]; v defaults to 0), vn (x y z), f with v, v/vt, v//vn, v/vt/vn and
 *         negative (relative) indices, polygons fan-triangulated. Each distinct
 *         (v, vt, vn) triple becomes one output vertex; positions no face uses are
 *         dropped. If some face corners carry a texture coordinate (or normal) and others
 *         do not, that attribute is dropped for the whole mesh (uv or n is NULL): a
 *         partial attribute cannot be interpolated consistently. Statements other than
 *         v vt vn f (o g s usemtl mtllib l p, free-form geometry, …) and comments are
 *         ignored; a line ending in '\' continues on the next one.
 *   .ply  format ascii 1.0 or binary_little_endian 1.0 (binary_big_endian is refused with
 *         TS_ERR_UNSUPPORTED). element vertex with scalar properties x y z (any PLY scalar
 *         type), optional nx ny nz, optional texture coordinates (u v, s t, texture_u
 *         texture_v or texture_s texture_t); element face with a list property
 *         vertex_indices (or vertex_index) of integer count and index types,
 *         fan-triangulated. Other elements and properties, lists included, are skipped;
 *         every vertex is kept. Data after the last declared element is ignored. An
 *         ASCII element takes one line.
 * Both: normals are normalised (a zero-length normal is an error), texture coordinates
 * are returned as written (no v flip), non-finite numbers are errors, faces need at
 * least 3 vertices, degenerate triangles are kept, a file without faces is an error. */
#ifndef TS_MESH_FILE_H
#define TS_MESH_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

/* Upper bounds on what a file may make the loader allocate; 0 = no limit. max_vertices
 * bounds the output vertices and, for OBJ, also the number of `v` statements. */
typedef struct ts_mesh_limits {
    uint64_t max_vertices, max_triangles, max_file_bytes;
} ts_mesh_limits;

typedef struct ts_mesh_data {
    uint32_t n_vertices, n_triangles;
    float *p;        /* 3·n_vertices, malloc-owned */
    float *n;        /* 3·n_vertices unit normals, or NULL */
    float *uv;       /* 2·n_vertices, or NULL */
    uint32_t *index; /* 3·n_triangles, every index < n_vertices */
} ts_mesh_data;

/* Loads base_dir/rel_path into *out (base_dir NULL or "" means the current directory;
 * limits may be NULL for no limits). rel_path must be relative and, once every symlink is
 * resolved, stay inside realpath(base_dir); otherwise TS_ERR_INVALID with "mesh file 'x':
 * path leaves the scene's folder" (or "absolute paths are not allowed"). Errors: TS_ERR_IO
 * (cannot open or read), TS_ERR_INVALID (bad path, unknown extension, not a regular file,
 * empty file, parse errors such as "mesh file 'bunny.obj', line 12: face index 40 out of
 * range (file has 38 vertices)"), TS_ERR_UNSUPPORTED (big-endian PLY), TS_ERR_LIMIT (a
 * limit exceeded; checked before the large allocation), TS_ERR_NOMEM. On failure *out is
 * zeroed and nothing leaks; on success the caller frees with ts_mesh_data_free.
 * Thread-safe (no shared state; numbers are parsed with strtod, so LC_NUMERIC must be the
 * "C" locale, which it is unless the program calls setlocale). */
ts_status ts_mesh_file_load(const char *base_dir, const char *rel_path, const ts_mesh_limits *limits,
                            ts_mesh_data *out, ts_error *err);

/* Parses an in-memory file image (for fuzzing and callers that already hold the bytes):
 * name is used in messages and its extension (.obj or .ply) picks the format; bytes (size
 * bytes, need not be NUL-terminated) are only read. Same results, limits (max_file_bytes
 * applies to size) and errors as ts_mesh_file_load without the path checks. Thread-safe. */
ts_status ts_mesh_load_memory(const char *name, const void *bytes, size_t size, const ts_mesh_limits *limits,
                              ts_mesh_data *out, ts_error *err);

/* Frees the arrays of m (NULL or zeroed is fine) and zeroes it. */
void ts_mesh_data_free(ts_mesh_data *m);

#endif
