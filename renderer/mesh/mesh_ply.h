/* mesh_ply.h — triangle meshes from PLY files.
 *
 * Design note: accepted: format ascii 1.0 or binary_little_endian 1.0 (binary_big_endian
 * is refused with TS_ERR_UNSUPPORTED); element vertex with scalar properties x y z (any PLY
 * scalar type), optional nx ny nz, optional texture coordinates (u v, s t, texture_u
 * texture_v or texture_s texture_t); element face with a list property vertex_indices (or
 * vertex_index) of integer count and index types, fan-triangulated. Other elements and
 * properties, lists included, are skipped; every vertex is kept. Data after the last
 * declared element is ignored. An ASCII element takes one line. Normals keep their lengths,
 * as pbrt-v3's plymesh (a zero normal is an error), texture coordinates are returned as written, non-finite
 * numbers are errors, faces need at least 3 vertices, degenerate triangles are kept, a file
 * without faces is an error. Errors name the line (ASCII) or the byte offset and element
 * (binary).
 *
 * The header is read into element/property descriptions; each property gets a role (x,
 * nx, u, vertex_indices, or skip); element counts are checked against the limits and the
 * bytes left before anything of their size is allocated; then the elements are read in
 * order through one cursor that is either a line reader (ASCII) or a bounds-checked
 * little-endian byte reader (binary). */
#ifndef TS_MESH_PLY_H
#define TS_MESH_PLY_H

#include <stddef.h>

#include "core/error.h"
#include "mesh/mesh_read.h"

/* Parses the PLY file image text (size bytes, text[size] must be '\0') under r's limits,
 * errors into r->err. On success *out holds the mesh (free with ts_mesh_data_free); on
 * failure *out is untouched and nothing leaks. Thread-safe. */
ts_status ts_mesh_ply_parse(const ts_mesh_reader *r, const char *text, size_t size, ts_mesh_data *out);

#endif
