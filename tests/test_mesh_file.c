/* test_mesh_file.c — OBJ and PLY mesh files: values loaded, path confinement, errors.
 *
 * Every file is written by the test into a fresh folder under /tmp (plus a second folder
 * standing for "outside the scene") and both are removed at the end. Expected values are
 * exact: all coordinates are small binary fractions, so text and float agree bit for bit,
 * normals too: the readers keep their lengths (pbrt-v3's triangles interpolate them so). */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* mkdtemp, symlink, nftw */
#endif
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h> /* after setjmp.h, stdarg.h, stddef.h */

#include <ftw.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/hash.h"
#include "mesh/mesh_file.h"

static char g_dir[64], g_outside[64];

/* ---- files ---- */

static void write_file(const char *dir, const char *name, const void *data, size_t len)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (len) assert_int_equal(fwrite(data, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

static void write_text(const char *name, const char *text) { write_file(g_dir, name, text, strlen(text)); }

static int remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(path);
}

static int setup(void **state)
{
    (void)state;
    strcpy(g_dir, "/tmp/ts_mesh_test_XXXXXX");
    strcpy(g_outside, "/tmp/ts_mesh_outside_XXXXXX");
    if (!mkdtemp(g_dir) || !mkdtemp(g_outside)) return -1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    nftw(g_dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    nftw(g_outside, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    return 0;
}

/* ---- the cube: 8 corners, 6 outward quads (counter-clockwise seen from outside) ---- */

static const int cube_quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
static const float cube_face_normal[6][3] = {{-1, 0, 0}, {1, 0, 0},  {0, -1, 0},
                                             {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
static const float quad_uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

static void cube_corner(int i, float p[3])
{
    p[0] = (i & 1 ? 1.0f : -1.0f) + 0.25f;
    p[1] = (i & 2 ? 1.0f : -1.0f) * 0.5f;
    p[2] = (i & 4 ? 1.0f : -1.0f) * 2.0f - 0.125f;
}

static void assert_vec(const float *got, const float *want, int n, double tol)
{
    for (int k = 0; k < n; k++)
        if (fabs((double)got[k] - (double)want[k]) > tol)
            fail_msg("component %d: %.9g != %.9g (tolerance %g)", k, got[k], want[k], tol);
}

static ts_status load(const char *rel, const ts_mesh_limits *lim, ts_mesh_data *m, ts_error *err)
{
    ts_error_clear(err);
    memset(m, 0xab, sizeof *m); /* the loader must overwrite everything */
    return ts_mesh_file_load(g_dir, rel, lim, m, err);
}

/* Loads rel, expects failure with status st and a message containing each of the
 * given substrings, and checks *out was left zeroed. */
static void expect_error(const char *rel, const ts_mesh_limits *lim, ts_status st, const char *sub1,
                         const char *sub2)
{
    ts_mesh_data m;
    ts_error err;
    ts_status got = load(rel, lim, &m, &err);
    if (got != st) fail_msg("'%s': status %d, expected %d (%s)", rel, got, st, err.message);
    if (!strstr(err.message, sub1) || (sub2 && !strstr(err.message, sub2)))
        fail_msg("'%s': message \"%s\" lacks \"%s\"%s%s", rel, err.message, sub1, sub2 ? " / " : "",
                 sub2 ? sub2 : "");
    assert_int_equal(strncmp(err.message, "mesh file '", 11), 0);
    ts_mesh_data zero = {0};
    assert_memory_equal(&m, &zero, sizeof m);
}

static char *cube_obj(void)
{
    static char text[4096];
    int n = 0;
    n += snprintf(text + n, sizeof text - n, "# cube\r\nmtllib cube.mtl\no cube\ng box\n");
    for (int i = 0; i < 8; i++) {
        float p[3];
        cube_corner(i, p);
        n += snprintf(text + n, sizeof text - n, "v %g %g %g%s\n", p[0], p[1], p[2], i == 3 ? " 1.0" : "");
    }
    for (int j = 0; j < 4; j++)
        n += snprintf(text + n, sizeof text - n, "vt %g %g\n", quad_uv[j][0], quad_uv[j][1]);
    for (int f = 0; f < 6; f++) /* unnormalised on purpose */
        n += snprintf(text + n, sizeof text - n, "vn %g %g %g\n", 3 * cube_face_normal[f][0],
                      3 * cube_face_normal[f][1], 3 * cube_face_normal[f][2]);
    n += snprintf(text + n, sizeof text - n, "usemtl white\ns off\n");
    for (int f = 0; f < 6; f++) {
        n += snprintf(text + n, sizeof text - n, "f");
        for (int j = 0; j < 4; j++)
            n += snprintf(text + n, sizeof text - n, " %d/%d/%d%s", cube_quads[f][j] + 1, j + 1, f + 1,
                          f == 2 && j == 1 ? " \\\r\n " : "");
        n += snprintf(text + n, sizeof text - n, f == 5 ? "  # last face" : "\r\n");
    }
    return text;
}

static void test_obj_cube(void **state)
{
    (void)state;
    write_text("cube.obj", cube_obj());
    ts_mesh_data m;
    ts_error err;
    assert_int_equal(load("cube.obj", NULL, &m, &err), TS_OK);
    /* 6 faces × 4 corners, each with its own (v, vt, vn) triple: 24 vertices. */
    assert_int_equal(m.n_vertices, 24);
    assert_int_equal(m.n_triangles, 12);
    assert_non_null(m.n);
    assert_non_null(m.uv);
    for (int f = 0; f < 6; f++) {
        static const int fan[2][3] = {{0, 1, 2}, {0, 2, 3}};
        for (int t = 0; t < 2; t++)
            for (int k = 0; k < 3; k++) {
                uint32_t v = m.index[3 * (2 * f + t) + k];
                assert_true(v < m.n_vertices);
                int corner = fan[t][k];
                float p[3];
                cube_corner(cube_quads[f][corner], p);
                assert_vec(m.p + 3 * v, p, 3, 0);
                assert_vec(m.uv + 2 * v, quad_uv[corner], 2, 0);
                const float n3[3] = {3 * cube_face_normal[f][0], 3 * cube_face_normal[f][1], 3 * cube_face_normal[f][2]};
                assert_vec(m.n + 3 * v, n3, 3, 0); /* as written: length 3 */
            }
    }
    ts_mesh_data_free(&m);
    assert_null(m.p);
    /* Case-insensitive extension, a symlink that stays inside the folder. */
    write_text("CUBE2.OBJ", cube_obj());
    char target[256];
    snprintf(target, sizeof target, "%s/alias.obj", g_dir);
    assert_int_equal(symlink("CUBE2.OBJ", target), 0);
    assert_int_equal(load("./alias.obj", NULL, &m, &err), TS_OK);
    assert_int_equal(m.n_triangles, 12);
    ts_mesh_data_free(&m);
}

static void test_obj_negative_and_mixed(void **state)
{
    (void)state;
    write_text("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                          "v 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\nf 1 -1 2\n");
    ts_mesh_data m;
    ts_error err;
    assert_int_equal(load("neg.obj", NULL, &m, &err), TS_OK);
    assert_int_equal(m.n_vertices, 6);
    assert_int_equal(m.n_triangles, 3);
    assert_null(m.n);
    assert_null(m.uv);
    static const uint32_t want_index[9] = {0, 1, 2, 3, 4, 5, 0, 5, 1};
    static const float want_p[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
    assert_memory_equal(m.index, want_index, sizeof want_index);
    assert_vec(m.p, want_p, 18, 0);
    ts_mesh_data_free(&m);

    /* One face with uv and normals, one without: both attributes are dropped, and the
     * corners sharing a position collapse to one vertex. A pentagon makes 3 triangles. */
    write_text("mixed.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n"
                            "f 1/1/1 2/2/1 3/1/1\nf 1 3 4\nf 1//1 2//1 3//1 4//1 5//1\n");
    assert_int_equal(load("mixed.obj", NULL, &m, &err), TS_OK);
    assert_int_equal(m.n_vertices, 5);
    assert_int_equal(m.n_triangles, 5);
    assert_null(m.uv);
    assert_null(m.n);
    static const uint32_t want_mixed[15] = {0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3, 0, 3, 4};
    assert_memory_equal(m.index, want_mixed, sizeof want_mixed);
    ts_mesh_data_free(&m);
}

/* ---- the cube as PLY: 8 shared vertices with corner normals and (s, t) ---- */

static void ply_vertex(int i, float p[3], float n[3], float uv[2])
{
    cube_corner(i, p);
    n[0] = i & 1 ? 2.0f : -2.0f; /* unnormalised on purpose */
    n[1] = i & 2 ? 2.0f : -2.0f;
    n[2] = i & 4 ? 2.0f : -2.0f;
    uv[0] = i & 1 ? 1.0f : 0.0f;
    uv[1] = i & 2 ? 0.75f : 0.25f;
}

static void check_ply_cube(const char *rel)
{
    ts_mesh_data m;
    ts_error err;
    ts_status st = load(rel, NULL, &m, &err);
    if (st) fail_msg("%s: %s", rel, err.message);
    assert_int_equal(m.n_vertices, 8);
    assert_int_equal(m.n_triangles, 12);
    assert_non_null(m.n);
    assert_non_null(m.uv);
    for (int i = 0; i < 8; i++) {
        float p[3], n[3], uv[2];
        ply_vertex(i, p, n, uv);
        assert_vec(m.p + 3 * i, p, 3, 0);
        assert_vec(m.n + 3 * i, n, 3, 0); /* as written: length √12 */
        assert_vec(m.uv + 2 * i, uv, 2, 0);
    }
    for (int f = 0; f < 6; f++) {
        const int *q = cube_quads[f];
        uint32_t want[6] = {(uint32_t)q[0], (uint32_t)q[1], (uint32_t)q[2],
                            (uint32_t)q[0], (uint32_t)q[2], (uint32_t)q[3]};
        assert_memory_equal(m.index + 6 * f, want, sizeof want);
    }
    ts_mesh_data_free(&m);
}

static char *cube_ply_ascii(void)
{
    static char text[4096];
    int n = snprintf(text, sizeof text,
                     "ply\nformat ascii 1.0\ncomment written by test_mesh_file\nobj_info nothing\n"
                     "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                     "property float confidence\nproperty float nx\nproperty float ny\nproperty float nz\n"
                     "property float s\nproperty float t\n"
                     "element material 2\nproperty uchar red\nproperty list uchar float weights\n"
                     "element face 6\nproperty list uchar int vertex_indices\nproperty uchar flags\n"
                     "property list int uint16 extra\nend_header\n");
    for (int i = 0; i < 8; i++) {
        float p[3], nn[3], uv[2];
        ply_vertex(i, p, nn, uv);
        n += snprintf(text + n, sizeof text - n, "%g %g %g 0.5 %g %g %g %g %g\n", p[0], p[1], p[2], nn[0],
                      nn[1], nn[2], uv[0], uv[1]);
    }
    n += snprintf(text + n, sizeof text - n, "255 3 0.5 1 2\n\n7 0\n"); /* a blank line is allowed */
    for (int f = 0; f < 6; f++)
        n += snprintf(text + n, sizeof text - n, "4 %d %d %d %d %d 2 9 10\n", cube_quads[f][0],
                      cube_quads[f][1], cube_quads[f][2], cube_quads[f][3], f);
    return text;
}

/* A little-endian byte buffer. */
typedef struct bytes {
    unsigned char b[4096];
    size_t n;
} bytes;

static void put_le(bytes *o, uint64_t v, int size)
{
    for (int i = 0; i < size; i++)
        o->b[o->n++] = (unsigned char)(v >> (8 * i));
}
static void put_f32(bytes *o, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_le(o, u, 4);
}
static void put_f64(bytes *o, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    put_le(o, u, 8);
}
static void put_text(bytes *o, const char *s)
{
    memcpy(o->b + o->n, s, strlen(s));
    o->n += strlen(s);
}

static void cube_ply_binary(bytes *o, const char *format)
{
    o->n = 0;
    put_text(o, "ply\r\n");
    put_text(o, format);
    put_text(o,
             "\r\nelement vertex 8\r\nproperty double x\r\nproperty float y\r\nproperty float z\r\n"
             "property ushort unused\r\nproperty float nx\r\nproperty float ny\r\nproperty float nz\r\n"
             "property float texture_u\r\nproperty float texture_v\r\n"
             "element face 6\r\nproperty list int int16 other\r\nproperty list uchar int vertex_indices\r\n"
             "element edge 2\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n");
    for (int i = 0; i < 8; i++) {
        float p[3], n[3], uv[2];
        ply_vertex(i, p, n, uv);
        put_f64(o, p[0]);
        put_f32(o, p[1]);
        put_f32(o, p[2]);
        put_le(o, 0xbeef, 2);
        for (int k = 0; k < 3; k++)
            put_f32(o, n[k]);
        put_f32(o, uv[0]);
        put_f32(o, uv[1]);
    }
    for (int f = 0; f < 6; f++) {
        put_le(o, (uint64_t)(f % 3), 4); /* 0, 1 or 2 int16 values */
        for (int k = 0; k < f % 3; k++)
            put_le(o, (uint64_t)-5 & 0xffff, 2);
        put_le(o, 4, 1);
        for (int k = 0; k < 4; k++)
            put_le(o, (uint64_t)cube_quads[f][k], 4);
    }
    for (int e = 0; e < 2; e++) {
        put_le(o, (uint64_t)e, 4);
        put_le(o, (uint64_t)e + 1, 4);
    }
}

static void test_ply_cube(void **state)
{
    (void)state;
    write_text("cube_ascii.ply", cube_ply_ascii());
    check_ply_cube("cube_ascii.ply");
    bytes o;
    cube_ply_binary(&o, "format binary_little_endian 1.0");
    write_file(g_dir, "cube_binary.PLY", o.b, o.n);
    check_ply_cube("cube_binary.PLY");
    /* Same mesh as the OBJ cube? Positions of the PLY triangles equal the OBJ ones. */
    write_text("cube_ref.obj", cube_obj());
    ts_mesh_data a, b;
    ts_error err;
    assert_int_equal(load("cube_ref.obj", NULL, &a, &err), TS_OK);
    assert_int_equal(load("cube_binary.PLY", NULL, &b, &err), TS_OK);
    for (uint32_t t = 0; t < 12; t++)
        for (int k = 0; k < 3; k++)
            assert_vec(a.p + 3 * a.index[3 * t + k], b.p + 3 * b.index[3 * t + k], 3, 0);
    ts_mesh_data_free(&a);
    ts_mesh_data_free(&b);
}

/* ---- errors ---- */

static void test_path_errors(void **state)
{
    (void)state;
    write_text("cube.obj", cube_obj());
    write_file(g_outside, "secret.obj", cube_obj(), strlen(cube_obj()));
    expect_error("/etc/passwd.obj", NULL, TS_ERR_INVALID, "absolute paths are not allowed", NULL);
    expect_error("../x.obj", NULL, TS_ERR_INVALID, "path leaves the scene's folder", NULL);
    expect_error("sub/../../x.obj", NULL, TS_ERR_INVALID, "path leaves the scene's folder", NULL);
    char link[256], target[256];
    snprintf(link, sizeof link, "%s/link.obj", g_dir);
    snprintf(target, sizeof target, "%s/secret.obj", g_outside);
    assert_int_equal(symlink(target, link), 0);
    expect_error("link.obj", NULL, TS_ERR_INVALID, "mesh file 'link.obj': path leaves the scene's folder",
                 NULL);
    snprintf(link, sizeof link, "%s/linkdir", g_dir);
    assert_int_equal(symlink(g_outside, link), 0);
    expect_error("linkdir/secret.obj", NULL, TS_ERR_INVALID, "path leaves the scene's folder", NULL);
    /* A missing file behind an escaping symlink is not reported as merely missing. */
    expect_error("linkdir/nothing.obj", NULL, TS_ERR_INVALID, "path leaves the scene's folder", NULL);
    expect_error("missing.obj", NULL, TS_ERR_IO, "mesh file 'missing.obj': cannot open", "no such file");
    write_text("cube.stl", "solid x\n");
    expect_error("cube.stl", NULL, TS_ERR_INVALID, "unknown extension", NULL);
    expect_error("noext", NULL, TS_ERR_INVALID, "unknown extension", NULL);
    expect_error("", NULL, TS_ERR_INVALID, "empty path", NULL);
    expect_error(".", NULL, TS_ERR_INVALID, "unknown extension", NULL);
    char dir[256];
    snprintf(dir, sizeof dir, "%s/folder.obj", g_dir);
    assert_int_equal(mkdir(dir, 0700), 0);
    expect_error("folder.obj", NULL, TS_ERR_INVALID, "not a regular file", NULL);
}

static void test_parse_errors(void **state)
{
    (void)state;
    write_text("range.obj", "# three vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    expect_error("range.obj", NULL, TS_ERR_INVALID,
                 "mesh file 'range.obj', line 5: face index 4 out of range (file has 3 vertices)", NULL);
    write_text("rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n");
    expect_error("rel.obj", NULL, TS_ERR_INVALID, "line 3: face index -3 out of range", NULL);
    write_text("zero.obj", "v 0 0 0\nf 0 1 1\n");
    expect_error("zero.obj", NULL, TS_ERR_INVALID, "line 2: face index 0", NULL);
    write_text("nan.obj", "v 0 0 0\nv 0 nan 0\nv 1 1 1\nf 1 2 3\n");
    expect_error("nan.obj", NULL, TS_ERR_INVALID, "line 2: vertex: 'nan' is not a finite number", NULL);
    write_text("huge.obj", "v 0 0 1e39\n");
    expect_error("huge.obj", NULL, TS_ERR_INVALID, "line 1", "not a finite number");
    write_text("short.obj", "v 0 0\n");
    expect_error("short.obj", NULL, TS_ERR_INVALID, "line 1: vertex: expected 3 numbers, found 2", NULL);
    write_text("tok.obj", "v 0 0 1x\n");
    expect_error("tok.obj", NULL, TS_ERR_INVALID, "malformed number '1x'", NULL);
    write_text("corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2/ 3\n");
    expect_error("corner.obj", NULL, TS_ERR_INVALID, "line 4: malformed face vertex '2/'", NULL);
    write_text("two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
    expect_error("two.obj", NULL, TS_ERR_INVALID, "line 3: face has 2 vertices", NULL);
    write_text("vn0.obj", "vn 0 0 0\n");
    expect_error("vn0.obj", NULL, TS_ERR_INVALID, "line 1: normal has zero length", NULL);
    write_text("vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n");
    expect_error("vt.obj", NULL, TS_ERR_INVALID, "texture coordinate index 2 out of range", NULL);
    write_text("nofaces.obj", "v 0 0 0\n");
    expect_error("nofaces.obj", NULL, TS_ERR_INVALID, "no faces", NULL);
    write_file(g_dir, "empty.obj", "", 0);
    expect_error("empty.obj", NULL, TS_ERR_INVALID, "mesh file 'empty.obj': file is empty", NULL);
    write_file(g_dir, "empty.ply", "", 0);
    expect_error("empty.ply", NULL, TS_ERR_INVALID, "file is empty", NULL);
    write_file(g_dir, "binary.obj", "\x7f\x45LF\x02\x01", 6);
    expect_error("binary.obj", NULL, TS_ERR_INVALID, "line 1: unexpected", NULL);

    /* PLY */
    write_text("range.ply",
               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
               "property float z\nelement face 1\nproperty list uchar uint vertex_index\nend_header\n"
               "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    expect_error("range.ply", NULL, TS_ERR_INVALID,
                 "mesh file 'range.ply', line 13: face index 3 out of range (file has 3 vertices)", NULL);
    write_text("nan.ply",
               "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
               "property float z\nelement face 0\nproperty list uchar uint vertex_index\nend_header\n"
               "0 NaN 0\n");
    expect_error("nan.ply", NULL, TS_ERR_INVALID, "line 10: vertex 0: 'y' is not a finite number", NULL);
    /* Normals keep their lengths; only the zero vector is refused (its vertex named). */
    write_text("n0.ply",
               "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
               "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 0\n"
               "property list uchar uint vertex_index\nend_header\n0 0 0 0 0 1e-30\n1 0 0 0 0 0\n");
    expect_error("n0.ply", NULL, TS_ERR_INVALID, "line 14: vertex 1 has a zero-length normal", NULL);
    write_text("noface.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                             "property float z\nend_header\n0 0 0\n");
    expect_error("noface.ply", NULL, TS_ERR_INVALID, "no 'face' element", NULL);
    write_text("magic.ply", "solid\n");
    expect_error("magic.ply", NULL, TS_ERR_INVALID, "not a PLY file", NULL);

    bytes o;
    cube_ply_binary(&o, "format binary_big_endian 1.0");
    write_file(g_dir, "be.ply", o.b, o.n);
    expect_error("be.ply", NULL, TS_ERR_UNSUPPORTED, "line 2: binary_big_endian PLY is not supported", NULL);
    /* Truncated in the last face: found while reading, with the byte offset. */
    cube_ply_binary(&o, "format binary_little_endian 1.0");
    write_file(g_dir, "trunc1.ply", o.b, o.n - 16 - 2); /* edges, then 2 bytes of face #5 */
    expect_error("trunc1.ply", NULL, TS_ERR_INVALID, "(element 'face' #5): file is truncated", NULL);
    /* Truncated in the vertices: the counts do not fit the bytes, found before allocating. */
    write_file(g_dir, "trunc2.ply", o.b, o.n - 200);
    expect_error("trunc2.ply", NULL, TS_ERR_INVALID,
                 "file is truncated: 8 'vertex' elements need at least 38 bytes", NULL);
    /* A NaN in binary: offset of the value. */
    size_t header = (size_t)(strstr((char *)o.b, "end_header\r\n") - (char *)o.b) + 12;
    memcpy(o.b + header + 38 + 8, "\x00\x00\xc0\x7f", 4); /* vertex 1, y */
    write_file(g_dir, "nan_bin.ply", o.b, o.n);
    char want[96];
    snprintf(want, sizeof want, "byte %zu (element 'vertex' #1): vertex 1: 'y' is not a finite number",
             header + 38 + 8);
    expect_error("nan_bin.ply", NULL, TS_ERR_INVALID, want, NULL);
}

static void test_limits(void **state)
{
    (void)state;
    write_text("cube.obj", cube_obj());
    write_text("cube_ascii.ply", cube_ply_ascii());
    ts_mesh_limits lim = {.max_vertices = 4};
    expect_error("cube.obj", &lim, TS_ERR_LIMIT, "file has 8 vertices, more than the limit of 4", NULL);
    expect_error("cube_ascii.ply", &lim, TS_ERR_LIMIT, "file has 8 vertices, more than the limit of 4", NULL);
    /* OBJ: 8 positions, but 24 distinct corners. */
    lim = (ts_mesh_limits){.max_vertices = 23};
    expect_error("cube.obj", &lim, TS_ERR_LIMIT, "more than the limit of 23 vertices", NULL);
    lim = (ts_mesh_limits){.max_triangles = 11};
    expect_error("cube.obj", &lim, TS_ERR_LIMIT, "more than the limit of 11 triangles", NULL);
    expect_error("cube_ascii.ply", &lim, TS_ERR_LIMIT, "more than the limit of 11 triangles", NULL);
    lim = (ts_mesh_limits){.max_file_bytes = 100};
    expect_error("cube.obj", &lim, TS_ERR_LIMIT, "more than the limit of 100", NULL);
    /* A header announcing 4 billion faces is refused before anything is allocated. */
    write_text("many.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                           "property float y\nproperty float z\nelement face 4000000000\n"
                           "property list uchar int vertex_indices\nend_header\n");
    expect_error("many.ply", NULL, TS_ERR_INVALID, "file is truncated", NULL);
    /* Exactly at the limits: loads. */
    lim = (ts_mesh_limits){.max_vertices = 24, .max_triangles = 12, .max_file_bytes = strlen(cube_obj())};
    ts_mesh_data m;
    ts_error err;
    assert_int_equal(load("cube.obj", &lim, &m, &err), TS_OK);
    ts_mesh_data_free(&m);
}

/* Every prefix and a few hundred random corruptions of each valid file either load or
 * fail cleanly (zeroed output, a message naming the file); run under ASan/UBSan this is
 * what catches out-of-bounds reads and leaks. Fixed seed: the same cases every run. */
static void test_corruption(void **state)
{
    (void)state;
    bytes bin;
    cube_ply_binary(&bin, "format binary_little_endian 1.0");
    const struct {
        const char *name;
        const char *data;
        size_t n;
    } files[] = {
        {"fuzz.obj", cube_obj(), strlen(cube_obj())},
        {"fuzz.ply", cube_ply_ascii(), strlen(cube_ply_ascii())},
        {"fuzz.ply", (const char *)bin.b, bin.n},
    };
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 7, 1);
    static char buf[4096];
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        size_t n = files[f].n;
        for (size_t round = 0; round < n + 300; round++) {
            memcpy(buf, files[f].data, n);
            size_t len = n;
            if (round < n) {
                len = round; /* every prefix */
            } else {
                for (int k = 0, flips = 1 + (int)(ts_pcg32_next(&rng) % 4); k < flips; k++) {
                    static const char pool[] = "0123456789-./ \n\\#e\xff\x00";
                    uint32_t r = ts_pcg32_next(&rng);
                    buf[r % n] = (r >> 16) & 1 ? (char)(r >> 24) : pool[(r >> 24) % (sizeof pool - 1)];
                }
            }
            write_file(g_dir, files[f].name, buf, len);
            ts_mesh_data m;
            ts_error err;
            if (load(files[f].name, NULL, &m, &err) == TS_OK) {
                for (uint32_t i = 0; i < 3 * m.n_triangles; i++)
                    assert_true(m.index[i] < m.n_vertices);
                for (uint32_t i = 0; i < 3 * m.n_vertices; i++)
                    assert_true(isfinite(m.p[i]));
                ts_mesh_data_free(&m);
            } else {
                ts_mesh_data zero = {0};
                assert_memory_equal(&m, &zero, sizeof m);
                assert_int_equal(strncmp(err.message, "mesh file 'fuzz.", 16), 0);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_obj_cube, setup, teardown),
        cmocka_unit_test_setup_teardown(test_obj_negative_and_mixed, setup, teardown),
        cmocka_unit_test_setup_teardown(test_ply_cube, setup, teardown),
        cmocka_unit_test_setup_teardown(test_path_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_parse_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_limits, setup, teardown),
        cmocka_unit_test_setup_teardown(test_corruption, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
