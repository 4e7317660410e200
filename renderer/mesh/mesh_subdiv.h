/* mesh_subdiv.h — pbrt-v3's Loop subdivision surface (its `loopsubdiv` shape) as a mesh
 * generator: a control triangle mesh in, the triangle mesh of its refined limit surface out,
 * which a front end hands to ts_scene_builder_add_shape as any other mesh.
 *
 * Design note. pbrt-v3 (shapes/loopsubdiv.cpp, the book §3.8 of the 3rd edition) refines
 * `levels` times — every triangle into four, so 4^levels × n triangles — with Loop's rules:
 *   - even (old) vertices: interior ones (1 − kβ)·v + β·Σ ring, β = 3/16 for valence 3,
 *     3/(8k) otherwise (1/16 for the regular valence 6); boundary ones ¾·v + ⅛·(the two
 *     boundary neighbours);
 *   - odd (edge) vertices: interior ⅜·(ends) + ⅛·(the two opposite vertices), boundary
 *     ½·(ends);
 * then moves every vertex to its limit position (interior: the one-ring rule with
 * γ = 1/(k + 3/(8β)); boundary: ⅔·v + ⅙·(boundary neighbours), the cubic B-spline's limit
 * mask, where pbrt-v3 has ⅗ and ⅕ — a departure, docs/design.md §4) and gives it the limit
 * normal, the cross product of pbrt-v3's two limit tangents (interior: Σ cos(2πj/k)·p_j
 * and Σ sin(2πj/k)·p_j over the ring; boundary: the chord between the boundary neighbours
 * and pbrt-v3's valence-dependent across tangent), taken as pbrt-v3 takes them: over the
 * ring's positions already pushed to the limit (and the vertex's own pushed position), and
 * left unnormalised, since pbrt-v3's triangles interpolate the vertex normals with their
 * lengths (docs/pbrt-v3.md, the comparison: without either, killeroo-simple's shading
 * differs visibly). The arithmetic is done in double, rounded to float once at the end.
 *
 * Orientation. Refinement keeps every triangle's winding, so the result faces the way the
 * control mesh does (docs/design.md §4); the normals are turned to the winding's side
 * (pbrt-v3's cross product, taken over a ring that runs clockwise seen from the front,
 * points to the back; pbrt-v3's triangles then turn the geometric normal towards it, so
 * there the surface faces away from the control mesh's winding unless the mesh is
 * reversed — here it faces along the winding, like every other mesh; docs/design.md §4).
 *
 * What is refused, with a sentence: an edge shared by more than two triangles, two
 * triangles that traverse a shared edge the same way (inconsistent winding), a vertex
 * whose triangles do not form one fan (non-manifold), a degenerate triangle (a repeated
 * index), more than TS_SUBDIV_MAX_LEVELS levels, and a result beyond max_triangles.
 * Vertices no triangle uses are kept as they are (pbrt-v3 crashes on them). Pure,
 * thread-safe; allocates with malloc. */
#ifndef TS_MESH_SUBDIV_H
#define TS_MESH_SUBDIV_H

#include <stdint.h>

#include "core/error.h"
#include "mesh/mesh_read.h"

#define TS_SUBDIV_MAX_LEVELS 12

/* Subdivides the control mesh (positions p, 3·n_vertices finite floats; index, 3·n_triangles,
 * each < n_vertices) `levels` times (0 … TS_SUBDIV_MAX_LEVELS; 0 still moves the vertices
 * to the limit surface, as pbrt-v3 does) into *out (malloc-owned, no uvs; free with
 * ts_mesh_data_free) with pbrt-v3's unnormalised normals (all scaled by one power of two
 * only if the longest is outside [2^-8, 2^64]; none shorter than 2^-60 of the longest). max_triangles bounds the result (0: none).
 * TS_ERR_INVALID / TS_ERR_LIMIT / TS_ERR_NOMEM with a sentence that names no place (the
 * caller prefixes it); *out is zeroed on failure. cancel (core/cancel.h; NULL: never) is
 * polled at every level: TS_ERR_CANCELLED once it says stop. */
ts_status ts_mesh_loop_subdivide(const float *p, uint32_t n_vertices, const uint32_t *index, uint32_t n_triangles,
                                 uint32_t levels, uint64_t max_triangles, ts_cancel *cancel, ts_mesh_data *out,
                                 ts_error *err);

#endif
