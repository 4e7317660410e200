/* mesh_obj.h — triangle meshes from Wavefront OBJ files.
 *
 * Design note: accepted: v (x y z [w ignored]; further numbers such as vertex colours are
 * ignored), vt (u [v [w]]; v defaults to 0), vn (x y z), f with v, v/vt, v//vn, v/vt/vn and
 * negative (relative) indices, polygons fan-triangulated. Each distinct (v, vt, vn) triple
 * becomes one output vertex; positions no face uses are dropped. If some face corners carry
 * a texture coordinate (or normal) and others do not, that attribute is dropped for the
 * whole mesh (uv or n is NULL): a partial attribute cannot be interpolated consistently.
 * Statements other than v vt vn f (o g s usemtl mtllib l p, free-form geometry, …) and
 * comments are ignored; a line ending in '\' continues on the next one. Normals keep
 * their lengths, as the builder's inline normals (a zero normal is an error), texture coordinates are returned as
 * written (no v flip), non-finite numbers are errors, faces need at least 3 vertices,
 * degenerate triangles are kept, a file without faces is an error. Errors name the line.
 *
 * Two passes over the buffer: the first counts v/vt/vn statements so the attribute arrays
 * are allocated once, at a size checked against the limits, and positive indices can be
 * checked against the file's totals; the second parses, keeping face corners as
 * (v, vt, vn) triples. Corners are then deduplicated with an open-addressing hash table
 * (linear probing, load ≤ 1/2) and faces fanned into triangles. */
#ifndef TS_MESH_OBJ_H
#define TS_MESH_OBJ_H

#include <stddef.h>

#include "core/error.h"
#include "mesh/mesh_read.h"

/* Parses the OBJ file image text (size bytes, and text[size] must be '\0', so strtod stops
 * there) under r's limits, errors into r->err. On success *out holds the mesh (free with
 * ts_mesh_data_free); on failure *out is untouched and nothing leaks. Thread-safe. */
ts_status ts_mesh_obj_parse(const ts_mesh_reader *r, const char *text, size_t size, ts_mesh_data *out);

#endif
