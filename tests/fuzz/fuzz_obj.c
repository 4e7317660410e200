/* fuzz_obj.c — libFuzzer harness: Wavefront OBJ meshes (mesh_file.h) from memory.
 * The bytes are parsed as "fuzz.obj" under limits like a server's; a loaded mesh must
 * keep the header's promises (indices in range, finite non-zero normals of any length,
 * finite numbers). */
#include "fuzz_common.h"

#include <math.h>

#include "mesh/mesh_file.h"

#ifndef FUZZ_MESH_NAME
#define FUZZ_MESH_NAME "fuzz.obj"
#endif

static void check_mesh(const ts_mesh_data *m)
{
    FUZZ_CHECK(m->n_vertices > 0 && m->n_triangles > 0 && m->p && m->index);
    for (uint64_t i = 0; i < 3ull * m->n_triangles; i++) FUZZ_CHECK(m->index[i] < m->n_vertices);
    for (uint64_t i = 0; i < 3ull * m->n_vertices; i++) FUZZ_CHECK(isfinite(m->p[i]));
    if (m->n)
        for (uint64_t v = 0; v < m->n_vertices; v++) {
            const float *n = m->n + 3 * v;
            FUZZ_CHECK(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2]));
            FUZZ_CHECK(n[0] != 0 || n[1] != 0 || n[2] != 0);
        }
    if (m->uv)
        for (uint64_t i = 0; i < 2ull * m->n_vertices; i++) FUZZ_CHECK(isfinite(m->uv[i]));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* Bounds like a server's, small enough that a hostile count is a limit error, not an
     * out-of-memory abort under libFuzzer's -rss_limit_mb. */
    ts_mesh_limits lim = {.max_vertices = 1u << 20, .max_triangles = 1u << 20, .max_file_bytes = 1u << 24};
    ts_mesh_data m;
    ts_error err = {0};
    ts_status st = ts_mesh_load_memory(FUZZ_MESH_NAME, data, size, &lim, &m, &err);
    if (st == TS_OK) {
        check_mesh(&m);
        ts_mesh_data_free(&m);
    } else {
        FUZZ_CHECK(err.status == st && err.message[0] != '\0');
        FUZZ_CHECK(m.p == NULL && m.index == NULL && m.n_triangles == 0);
    }
    return 0;
}
