/* ply_load.c — speed of loading a large binary PLY mesh (renderer/mesh/mesh_ply.h).
 *
 * Writes a binary little-endian PLY of about a million triangles (a curved grid: float
 * x y z, nx ny nz, u v per vertex; faces as a uchar count and int indices, the layout
 * most exporters write) into a temporary folder, then on one thread:
 *   1. reads it with ts_mesh_file_load (the file into memory, parsed and checked);
 *   2. loads a pbrt-v3 scene that names it with Shape "plymesh" through ts_scene_load_path
 *      (the reader, the builder's transform and copy into the scene, and everything else
 *      the load does — the BVH is built when rendering starts, not here);
 * a few times each, and prints wall and thread-CPU seconds (best and median). The target
 * (issue #16) is ≤ 1 s on one core for the file; on a shared machine the CPU figure is
 * the one-core speed. Not run by ctest.
 *
 *   bench_ply_load [MILLION_TRIANGLES] [RUNS]     (defaults: 1, 3) */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* mkdtemp */
#endif

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mesh/mesh_file.h"
#include "load/scene_load.h"
#include "bench_util.h"

/* A (side+1)² vertex grid, 2·side² triangles; returns the file's size or -1. */
static long write_ply(const char *path, int side)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    long nv = (long)(side + 1) * (side + 1), nf = 2L * side * side;
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\ncomment bench_ply_load: a %d x %d grid\n"
            "element vertex %ld\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
            "element face %ld\nproperty list uchar int vertex_indices\nend_header\n",
            side, side, nv, nf);
    for (long i = 0; i < nv; i++) {
        float u = (float)(i % (side + 1)) / (float)side, v = (float)(i / (side + 1)) / (float)side;
        float nx = -0.5f * u, nz = 0.5f * v, inv = 1.0f / sqrtf(nx * nx + 1.0f + nz * nz);
        float rec[8] = {20 * u - 10, 0.25f * (u * u - v * v), 20 * v - 10, nx * inv, inv, nz * inv, u, v};
        fwrite(rec, sizeof rec, 1, f); /* little-endian host (x86-64, arm64) */
    }
    for (int y = 0; y < side; y++)
        for (int x = 0; x < side; x++) {
            int32_t a = y * (side + 1) + x, b = a + 1, c = a + side + 1, d = c + 1;
            int32_t t[2][3] = {{a, b, d}, {a, d, c}};
            for (int k = 0; k < 2; k++) {
                unsigned char n = 3;
                fwrite(&n, 1, 1, f);
                fwrite(t[k], sizeof t[k], 1, f);
            }
        }
    long size = ftell(f);
    return fclose(f) == 0 ? size : -1;
}

static int write_scene(const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fprintf(f, "LookAt 0 10 -30  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
               "Film \"image\" \"integer xresolution\" [64] \"integer yresolution\" [48]\n"
               "Sampler \"sobol\" \"integer pixelsamples\" 1\nIntegrator \"path\"\nWorldBegin\n"
               "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\n"
               "Material \"matte\"\nShape \"plymesh\" \"string filename\" \"mesh.ply\"\nWorldEnd\n");
    return fclose(f) == 0 ? 0 : -1;
}

static void report(const char *what, double *wall, double *cpu, int runs)
{
    qsort(wall, (size_t)runs, sizeof wall[0], cmp_double);
    qsort(cpu, (size_t)runs, sizeof cpu[0], cmp_double);
    printf("bench_ply_load: %s: wall best %.3f s, median %.3f s; CPU best %.3f s, median %.3f s\n", what, wall[0],
           wall[runs / 2], cpu[0], cpu[runs / 2]);
}

int main(int argc, char **argv)
{
    double mtri = argc > 1 ? atof(argv[1]) : 1;
    int runs = argc > 2 ? atoi(argv[2]) : 3;
    if (!(mtri >= 0.01 && mtri <= 50) || runs < 1 || runs > 50) {
        fprintf(stderr, "usage: %s [MILLION_TRIANGLES 0.01..50] [RUNS 1..50]\n", argv[0]);
        return 2;
    }
    const char *tmp = getenv("TMPDIR");
    char dir[512], ply[600], scene[600];
    snprintf(dir, sizeof dir, "%s/ts_bench_ply_XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    snprintf(ply, sizeof ply, "%s/mesh.ply", dir);
    snprintf(scene, sizeof scene, "%s/scene.pbrt", dir);
    int side = (int)ceil(sqrt(mtri * 1e6 / 2));
    int status = 0;
    long bytes = write_ply(ply, side);
    if (bytes < 0 || write_scene(scene) < 0) {
        perror("writing the scene");
        status = 1;
        goto out;
    }
    printf("bench_ply_load: mesh.ply %.1f MB: %ld vertices (position, normal, uv), %ld triangles\n", bytes / 1e6,
           (long)(side + 1) * (side + 1), 2L * side * side);
    double wall[50], cpu[50];
    for (int r = 0; r < runs; r++) {
        ts_mesh_data m = {0};
        ts_error err = {0};
        double t0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        ts_status st = ts_mesh_file_load(dir, "mesh.ply", NULL, &m, &err);
        double t1 = clock_s(CLOCK_MONOTONIC), c1 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        if (st) {
            fprintf(stderr, "bench_ply_load: %s\n", err.message);
            status = 1;
            goto out;
        }
        wall[r] = t1 - t0;
        cpu[r] = c1 - c0;
        printf("  file run %d: %.3f s wall, %.3f s CPU (%u triangles, %.0f MB/s of file by CPU)\n", r + 1, wall[r],
               cpu[r], m.n_triangles, bytes / 1e6 / cpu[r]);
        ts_mesh_data_free(&m);
    }
    report("the PLY file (ts_mesh_file_load)", wall, cpu, runs);
    for (int r = 0; r < runs; r++) {
        ts_scene *s = NULL;
        ts_error err = {0};
        double t0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        ts_status st = ts_scene_load_path(scene, NULL, NULL, NULL, &s, &err);
        double t1 = clock_s(CLOCK_MONOTONIC), c1 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        if (st) {
            fprintf(stderr, "bench_ply_load: %s\n", err.message);
            status = 1;
            goto out;
        }
        wall[r] = t1 - t0;
        cpu[r] = c1 - c0;
        printf("  scene run %d: %.3f s wall, %.3f s CPU\n", r + 1, wall[r], cpu[r]);
        ts_scene_destroy(s);
    }
    report("the pbrt-v3 scene naming it (ts_scene_load_path)", wall, cpu, runs);
    printf("bench_ply_load: target: the file in <= 1 s on one core\n");
out:
    unlink(ply);
    unlink(scene);
    rmdir(dir);
    return status;
}
