/* memory.c — peak memory per triangle of a loaded scene (bench/README.md, "Memory per
 * triangle").
 *
 * Writes binary PLY grids (a curved (s+1)² vertex grid, 2·s² triangles; positions only, or
 * positions, normals and uvs) and pbrt-v3 scenes naming them into a temporary folder, then
 * loads each scene in a fresh process (this program run again with --child), so that every
 * case starts from the same empty address space: the child loads the scene with
 * ts_scene_load_path — reader, builder, transform, the accelerator with its per-triangle
 * caches and Embree's BVH, exactly what `tessera render` does before its first sample — and
 * reports its peak resident set (VmHWM of /proc/self/status), its resident set after the
 * load (VmRSS), and what it knows it holds: the mesh arrays, the accelerator's per-triangle
 * caches (ts_accel_memory_get) and the bytes Embree's device holds and held at most (its
 * memory monitor). A two-triangle scene through the same path is the baseline (the
 * libraries, the process); a case's figure is (its VmHWM − the baseline's) ÷ its triangles.
 * Cases: 1 M and 4 M triangles with and without normals and uvs, and one 1 M-triangle
 * object placed 16 times (ObjectBegin / ObjectInstance).
 *
 * pbrt-v3's figure beside it is derived from pbrt-v3's data structures, not measured (there
 * is no pbrt-v3 binary here and none is built): docs/performance.md, "Memory per triangle",
 * writes the sum out with each term's source. This program evaluates that sum for each case
 * with the case's own vertex count, as a range over the BVH's node count (leaves of 4 down
 * to leaves of 1 primitive).
 *
 *   bench_memory [--mtri LIST] [--instances K] [--csv FILE]   (defaults: 1,4; 16)
 * Prints a markdown table. Not run by ctest; bench/run runs it. */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* mkdtemp */
#endif

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "geometry/accel.h"
#include "scene/scene.h"
#include "build/scene_builder.h"
#include "load/scene_load.h"

/* ---- the child: load one scene, report ---- */

/* A "Vm...:" line of /proc/self/status in bytes, or 0. */
static double status_bytes(const char *key)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return 0;
    char line[256];
    double v = 0;
    size_t n = strlen(key);
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && line[n] == ':') {
            v = 1024.0 * atof(line + n + 1); /* "kB" */
            break;
        }
    fclose(f);
    return v;
}

static int child(const char *scene_path)
{
    double rss0 = status_bytes("VmRSS");
    ts_scene_limits lim;
    ts_scene_limits_default(&lim); /* the CLI's */
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_path(scene_path, &lim, NULL, NULL, &s, &err)) {
        fprintf(stderr, "bench_memory: %s: %s\n", scene_path, err.message);
        return 1;
    }
    double hwm = status_bytes("VmHWM"), rss = status_bytes("VmRSS");
    /* The mesh arrays the scene holds (positions, normals, uvs, indices). */
    double mesh = 0, verts = 0, tris = 0;
    for (uint32_t i = 0; i < s->n_shapes; i++) {
        const ts_shape *sh = &s->shapes[i];
        if (sh->type != TS_SHAPE_MESH) continue;
        const ts_mesh *m = &sh->mesh;
        double v = m->n_vertices;
        mesh += 12.0 * v + (m->n ? 12.0 * v : 0) + (m->uv ? 8.0 * v : 0) + 12.0 * m->n_triangles;
        verts += v;
        tris += m->n_triangles;
    }
    ts_accel_memory am = {0};
    ts_accel_memory_get(s->accel, &am);
    /* unique triangles, vertices, instances, rss0, hwm, rss, mesh, tri cache, embree now, embree peak */
    printf("%.0f %.0f %u %.0f %.0f %.0f %.0f %zu %zu %zu\n", tris, verts, s->n_instances, rss0, hwm, rss, mesh,
           am.tri_cache_bytes, am.embree_bytes, am.embree_peak_bytes);
    ts_scene_destroy(s);
    return 0;
}

/* ---- the parent: write the cases, run a child per case ---- */

/* A (side+1)² vertex grid, 2·side² triangles; attrs adds normals and uvs. 0 on success. */
static int write_ply(const char *path, int side, int attrs)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    long nv = (long)(side + 1) * (side + 1), nf = 2L * side * side;
    fprintf(f, "ply\nformat binary_little_endian 1.0\nelement vertex %ld\nproperty float x\nproperty float y\n"
               "property float z\n", nv);
    if (attrs)
        fprintf(f, "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n");
    fprintf(f, "element face %ld\nproperty list uchar int vertex_indices\nend_header\n", nf);
    for (long i = 0; i < nv; i++) {
        float u = (float)(i % (side + 1)) / (float)side, v = (float)(i / (side + 1)) / (float)side;
        float nx = -0.5f * u, nz = 0.5f * v, inv = 1.0f / sqrtf(nx * nx + 1.0f + nz * nz);
        float rec[8] = {20 * u - 10, 0.25f * (u * u - v * v), 20 * v - 10, nx * inv, inv, nz * inv, u, v};
        fwrite(rec, sizeof(float), attrs ? 8 : 3, f); /* little-endian host (x86-64, arm64) */
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
    return fclose(f) == 0 ? 0 : -1;
}

/* A pbrt-v3 scene naming ply: as the scene's one shape, or (instances > 0) as an object
 * placed that many times side by side. */
static int write_scene(const char *path, const char *ply, int instances)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fprintf(f, "LookAt 0 10 -30  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
               "Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [24]\n"
               "Sampler \"sobol\" \"integer pixelsamples\" 1\nIntegrator \"path\"\nWorldBegin\n"
               "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\nMaterial \"matte\"\n");
    if (instances == 0)
        fprintf(f, "Shape \"plymesh\" \"string filename\" \"%s\"\n", ply);
    else {
        fprintf(f, "ObjectBegin \"grid\"\nShape \"plymesh\" \"string filename\" \"%s\"\nObjectEnd\n", ply);
        for (int k = 0; k < instances; k++)
            fprintf(f, "AttributeBegin\nTranslate %d 0 %d\nObjectInstance \"grid\"\nAttributeEnd\n", 21 * (k % 4),
                    21 * (k / 4));
    }
    fprintf(f, "WorldEnd\n");
    return fclose(f) == 0 ? 0 : -1;
}

/* label with its commas made semicolons, for a CSV field */
static const char *csv_label(const char *label)
{
    static char buf[128];
    snprintf(buf, sizeof buf, "%s", label);
    for (char *p = buf; *p; p++)
        if (*p == ',') *p = ';';
    return buf;
}

typedef struct result {
    double tris, verts, rss0, hwm, rss, mesh, tri_cache, embree, embree_peak;
    unsigned instances;
} result;

static int run_child(const char *self, const char *scene, result *r)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "'%s' --child '%s'", self, scene);
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    int n = fscanf(p, "%lf %lf %u %lf %lf %lf %lf %lf %lf %lf", &r->tris, &r->verts, &r->instances, &r->rss0,
                   &r->hwm, &r->rss, &r->mesh, &r->tri_cache, &r->embree, &r->embree_peak);
    int st = pclose(p);
    return n == 10 && st == 0 ? 0 : -1;
}

/* pbrt-v3's bytes at its peak (the BVH build) for one mesh of t triangles over v vertices,
 * with normals and uvs if attrs, for `nodes` BVH nodes: the sum docs/performance.md
 * derives term by term ("Memory per triangle"). */
static double pbrt_v3_bytes(double t, double v, int attrs, double nodes)
{
    double per_tri = 96    /* Triangle (64) in make_shared's block (+16), malloc chunk of 80 + 8 → 96 */
                     + 96  /* GeometricPrimitive (72) in make_shared's block (+16), chunk of 88 + 8 → 96 */
                     + 16  /* BVHAccel::primitives, shared_ptr<Primitive> */
                     + 16  /* the other vector of the swap with orderedPrims */
                     + 48  /* BVHPrimitiveInfo (size_t + Bounds3f + Point3f, 44 → 48), kept by resize(0) */
                     + 12; /* TriangleMesh::vertexIndices */
    double per_node = 64   /* BVHBuildNode (52 → 56) in a MemoryArena rounding to 16 */
                      + 32; /* LinearBVHNode */
    double per_vert = 12 + (attrs ? 12 + 8 : 0); /* TriangleMesh::p, n, uv */
    return per_tri * t + per_node * nodes + per_vert * v;
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "--child")) return child(argv[2]);
    const char *mtri_list = "1,4", *csv_path = NULL;
    int instances = 16;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--mtri") && i + 1 < argc) mtri_list = argv[++i];
        else if (!strcmp(argv[i], "--instances") && i + 1 < argc) instances = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--csv") && i + 1 < argc) csv_path = argv[++i];
        else {
            fprintf(stderr, "usage: %s [--mtri 1,4] [--instances 16] [--csv FILE]\n", argv[0]);
            return 2;
        }
    }
    if (instances < 0 || instances > 1024) {
        fprintf(stderr, "bench_memory: --instances must be 0..1024\n");
        return 2;
    }
    char self[1024];
    ssize_t sl = readlink("/proc/self/exe", self, sizeof self - 1);
    if (sl <= 0) {
        perror("bench_memory: /proc/self/exe");
        return 1;
    }
    self[sl] = 0;
    const char *tmp = getenv("TMPDIR");
    char dir[512];
    snprintf(dir, sizeof dir, "%s/ts_bench_memory_XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("bench_memory: mkdtemp");
        return 1;
    }
    FILE *csv = csv_path ? fopen(csv_path, "w") : NULL;
    if (csv)
        fprintf(csv, "case,triangles,instances,vertices,peak_rss_bytes,bytes_per_triangle,steady_bytes_per_triangle,"
                     "mesh_bytes_per_triangle,tri_cache_bytes_per_triangle,embree_bytes_per_triangle,"
                     "embree_peak_bytes_per_triangle,pbrt_v3_min_bytes_per_triangle,pbrt_v3_max_bytes_per_triangle\n");
    int status = 0;
    char ply[700], scene[700];
    result base;
    snprintf(ply, sizeof ply, "%s/base.ply", dir);
    snprintf(scene, sizeof scene, "%s/base.pbrt", dir);
    if (write_ply(ply, 1, 0) || write_scene(scene, "base.ply", 0) || run_child(self, scene, &base)) {
        fprintf(stderr, "bench_memory: the baseline scene failed\n");
        status = 1;
        goto out;
    }
    printf("Baseline (a 2-triangle scene through the same path): peak RSS %.1f MiB. Per triangle: "
           "(peak RSS − baseline) ÷ triangles; steady: (RSS after the load − baseline) ÷ triangles.\n\n",
           base.hwm / 1048576.0);
    printf("| case | triangles | vertices | peak RSS MiB | **bytes / triangle (peak)** | steady | mesh arrays | "
           "per-triangle cache | Embree held | Embree peak | rest of peak | pbrt-v3, derived (not measured) |\n");
    printf("|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
    /* cases: each size × {positions, positions + normals + uvs}, then the instanced one */
    for (const char *c = mtri_list; *c;) {
        double mtri = atof(c);
        int side = (int)ceil(sqrt(mtri * 1e6 / 2));
        for (int attrs = 0; attrs <= 1; attrs++) {
            char name[64];
            snprintf(name, sizeof name, "%gM%s.ply", mtri, attrs ? "-nuv" : "");
            snprintf(ply, sizeof ply, "%s/%s", dir, name);
            snprintf(scene, sizeof scene, "%s/%s.pbrt", dir, name);
            result r;
            if (write_ply(ply, side, attrs) || write_scene(scene, name, 0) || run_child(self, scene, &r)) {
                fprintf(stderr, "bench_memory: case %s failed\n", name);
                status = 1;
                goto out;
            }
            double t = r.tris, per = (r.hwm - base.hwm) / t, steady = (r.rss - base.rss) / t;
            double pmin = pbrt_v3_bytes(t, r.verts, attrs, 2 * ceil(t / 4) - 1) / t;
            double pmax = pbrt_v3_bytes(t, r.verts, attrs, 2 * t - 1) / t;
            double rest = per - (r.mesh + r.tri_cache + r.embree_peak) / t;
            char label[96];
            snprintf(label, sizeof label, "%g M, positions%s", mtri, attrs ? " + normals + uvs" : "");
            printf("| %s | %.0f | %.0f | %.0f | **%.0f** | %.0f | %.1f | %.0f | %.1f | %.1f | %.1f | %.0f–%.0f |\n",
                   label, t, r.verts, r.hwm / 1048576.0, per, steady, r.mesh / t, r.tri_cache / t, r.embree / t,
                   r.embree_peak / t, rest, pmin, pmax);
            fflush(stdout);
            if (csv)
                fprintf(csv, "%s,%.0f,0,%.0f,%.0f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f\n", csv_label(label), t, r.verts, r.hwm,
                        per, steady, r.mesh / t, r.tri_cache / t, r.embree / t, r.embree_peak / t, pmin, pmax);
            unlink(ply);
            unlink(scene);
        }
        /* instanced: the first size's positions-only grid, placed `instances` times */
        if (c == mtri_list && instances > 0) {
            char name[64];
            snprintf(name, sizeof name, "%gM.ply", mtri);
            snprintf(ply, sizeof ply, "%s/%s", dir, name);
            snprintf(scene, sizeof scene, "%s/inst.pbrt", dir);
            result r;
            if (write_ply(ply, side, 0) || write_scene(scene, name, instances) || run_child(self, scene, &r)) {
                fprintf(stderr, "bench_memory: the instanced case failed\n");
                status = 1;
                goto out;
            }
            double t = r.tris, per = (r.hwm - base.hwm) / t, steady = (r.rss - base.rss) / t;
            double rest = per - (r.mesh + r.tri_cache + r.embree_peak) / t;
            /* pbrt-v3: one BVH over the object's primitives, built once; each instance a
             * TransformedPrimitive (a few hundred bytes: not per triangle). */
            double pmin = pbrt_v3_bytes(t, r.verts, 0, 2 * ceil(t / 4) - 1) / t;
            double pmax = pbrt_v3_bytes(t, r.verts, 0, 2 * t - 1) / t;
            char label[96];
            snprintf(label, sizeof label, "%g M object × %u instances (per object triangle)", mtri, r.instances);
            printf("| %s | %.0f | %.0f | %.0f | **%.0f** | %.0f | %.1f | %.0f | %.1f | %.1f | %.1f | %.0f–%.0f |\n",
                   label, t, r.verts, r.hwm / 1048576.0, per, steady, r.mesh / t, r.tri_cache / t, r.embree / t,
                   r.embree_peak / t, rest, pmin, pmax);
            printf("| the same per instanced triangle (%.0f) | | | | **%.1f** | %.1f | | | | | | |\n",
                   t * r.instances, per / r.instances, steady / r.instances);
            fflush(stdout);
            if (csv)
                fprintf(csv, "%s,%.0f,%u,%.0f,%.0f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.2f\n", csv_label(label), t, r.instances,
                        r.verts, r.hwm, per, steady, r.mesh / t, r.tri_cache / t, r.embree / t, r.embree_peak / t,
                        pmin, pmax);
            unlink(ply);
            unlink(scene);
        }
        c = strchr(c, ',');
        if (!c) break;
        c++;
    }
out:
    if (csv) fclose(csv);
    snprintf(ply, sizeof ply, "%s/base.ply", dir);
    unlink(ply);
    snprintf(scene, sizeof scene, "%s/base.pbrt", dir);
    unlink(scene);
    rmdir(dir);
    return status;
}
