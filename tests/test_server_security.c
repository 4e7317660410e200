/* test_server_security.c — docs/security.md against a real `tessera serve` on loopback:
 * posted scenes read files only under --assets (a mesh there renders exactly like the same
 * mesh inline; absolute paths, `..`, symlinks and symlinked folders leading out, for
 * meshes, Fourier tables and environment maps, are 400 naming the JSON path, and no
 * answer reveals the asset folder's absolute path); without --assets every file reference
 * is 400; --max-asset-bytes and --max-triangles apply to files read; the bearer token
 * (--token and --token-file) accepts only itself — not a prefix, an extension or a
 * same-length guess — and never appears in the server's output; --max-jobs refuses
 * submissions beyond it with 503 before parsing. Films are 24×24 `ao` renders so every
 * case takes well under a second. */
#define _GNU_SOURCE /* mkdtemp, symlink, nftw, realpath, strcasestr */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <arpa/inet.h>
#include <curl/curl.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <fcntl.h>
#include <ftw.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "image/exr.h"
#include "image/image.h"
#include "server_harness.h"

static char g_root[PATH_MAX];    /* temporary folder holding the two below */
static char g_assets[PATH_MAX];  /* g_root/assets: the --assets folder */
static char g_outside[PATH_MAX]; /* g_root/outside: files no posted scene may read */
static char g_assets_real[PATH_MAX];

/* A tetrahedron whose faces use the vertices in order, so the OBJ loader's vertex order
 * is the file's and the inline twin below is the same mesh. */
static const char tetra_obj[] = "# tetrahedron\nv -1 0 -1\nv 1 0 -1\nv 0 0 1\nv 0 1.5 0\n"
                                "f 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n";
static const char tetra_inline[] = "\"positions\":[-1,0,-1, 1,0,-1, 0,0,1, 0,1.5,0],"
                                   "\"indices\":[0,1,2, 0,2,3, 0,3,1, 1,3,2]";

/* A scene whose only shape is a mesh given by mesh_json ("\"file\":\"x\"" or inline
 * arrays); extra is more top-level JSON (with a leading comma) or "". */
static char *scene_doc(const char *mesh_json, const char *extra)
{
    char *s = malloc(4096);
    snprintf(s, 4096,
             "{\"tessera\":1,\"camera\":{\"from\":[0,1.2,4],\"to\":[0,0.5,0],\"fov\":40},"
             "\"film\":{\"width\":24,\"height\":24,\"filter\":{\"type\":\"box\"}},"
             "\"sampler\":{\"spp\":2,\"seed\":3},\"integrator\":{\"type\":\"ao\"},"
             "\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
             "\"shapes\":[{\"type\":\"mesh\",%s,\"material\":\"w\"}]%s}",
             mesh_json, extra);
    return s;
}

static char *mesh_file_doc(const char *file)
{
    char m[PATH_MAX + 32];
    snprintf(m, sizeof m, "\"file\":\"%s\"", file);
    return scene_doc(m, "");
}

static void write_file(const char *dir, const char *name, const char *text)
{
    char p[PATH_MAX + 64];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void link_to(const char *target, const char *name)
{
    char p[PATH_MAX + 64];
    snprintf(p, sizeof p, "%s/%s", g_assets, name);
    assert_int_equal(symlink(target, p), 0);
}

static int remove_entry(const char *p, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(p);
}

static int setup(void **state)
{
    (void)state;
    curl_global_init(CURL_GLOBAL_DEFAULT);
    snprintf(g_root, sizeof g_root, "/tmp/tessera-security-XXXXXX");
    if (!mkdtemp(g_root)) return -1;
    snprintf(g_assets, sizeof g_assets, "%s/assets", g_root);
    snprintf(g_outside, sizeof g_outside, "%s/outside", g_root);
    if (mkdir(g_assets, 0700) || mkdir(g_outside, 0700)) return -1;
    if (!realpath(g_assets, g_assets_real)) return -1;
    write_file(g_assets, "tetra.obj", tetra_obj);
    char sub[PATH_MAX + 8];
    snprintf(sub, sizeof sub, "%s/sub", g_assets);
    if (mkdir(sub, 0700)) return -1;
    write_file(sub, "tetra.obj", tetra_obj);
    write_file(g_outside, "secret.obj", tetra_obj);
    write_file(g_outside, "secret.exr", "not really an EXR");
    write_file(g_outside, "secret.bsdf", "not really a table");
    char target[PATH_MAX + 32];
    snprintf(target, sizeof target, "%s/secret.obj", g_outside);
    link_to(target, "link.obj");
    snprintf(target, sizeof target, "%s/secret.exr", g_outside);
    link_to(target, "sky.exr");
    snprintf(target, sizeof target, "%s/secret.bsdf", g_outside);
    link_to(target, "table.bsdf");
    link_to(g_outside, "linkdir");
    link_to("../outside/secret.obj", "rel-link.obj"); /* relative target, still outside */
    link_to("sub/tetra.obj", "inner-link.obj");       /* a symlink that stays inside is fine */
    /* A 200-triangle grid (for --max-triangles 100) and a file over --max-asset-bytes. */
    char *grid = malloc(16384);
    int n = 0;
    for (int y = 0; y <= 10; y++)
        for (int x = 0; x <= 10; x++)
            n += snprintf(grid + n, 16384 - (size_t)n, "v %d 0 %d\n", x, y);
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 10; x++) {
            int a = 1 + y * 11 + x;
            n += snprintf(grid + n, 16384 - (size_t)n, "f %d %d %d\nf %d %d %d\n", a, a + 11, a + 1, a + 1,
                          a + 11, a + 12);
        }
    write_file(g_assets, "grid.obj", grid);
    memset(grid, '#', 9000);
    memcpy(grid + 9000, "\n", 2);
    write_file(g_assets, "big.obj", grid);
    free(grid);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    nftw(g_root, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    curl_global_cleanup();
    return 0;
}

/* POSTs doc (freed here) and expects status; when want1/want2 are given, the error
 * sentence must contain them. Returns the job id for 201 (static buffer). */
static const char *post(const test_server *s, char *doc, const char *auth, long status, const char *want1,
                        const char *want2)
{
    static char id[64];
    id[0] = '\0';
    http_resp r;
    ts_http(s, "POST", "/api/v1/jobs", doc, strlen(doc), auth, &r);
    if (r.status != status) fail_msg("POST: status %ld, expected %ld: %s", r.status, status, r.body);
    if ((want1 && !strstr(r.body, want1)) || (want2 && !strstr(r.body, want2)))
        fail_msg("POST %ld: \"%s\" lacks \"%s\"%s%s", status, r.body, want1, want2 ? " / " : "",
                 want2 ? want2 : "");
    /* No answer names where the server keeps its files (unless the client wrote it). */
    if ((strstr(r.body, g_assets_real) && !strstr(doc, g_assets_real)) ||
        (strstr(r.body, g_root) && !strstr(doc, g_root)))
        fail_msg("the answer reveals a server path: %s", r.body);
    if (status == 201) {
        cJSON *o = cJSON_Parse(r.body);
        assert_non_null(o);
        snprintf(id, sizeof id, "%s", ts_json_str(o, "id"));
        cJSON_Delete(o);
    }
    ts_http_free(&r);
    free(doc);
    return id;
}

static void fetch_exr(const test_server *s, const char *id, ts_image *img)
{
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.exr", id);
    http_resp r;
    ts_http(s, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_error err = {0};
    if (ts_exr_read_memory((const unsigned char *)r.body, r.len, img, &err)) fail_msg("%s", err.message);
    ts_http_free(&r);
}

/* (a) a mesh under --assets renders, pixel for pixel as the same mesh inline; (b)–(d)
 * every way out is 400 naming the JSON path; limits apply to files read. */
static void test_assets(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads",       "1",   "--assets", g_assets, "--max-asset-bytes", "8192",
                          "--max-triangles", "100", NULL};
    ts_server_start(&s, args);

    char id_file[64], id_inline[64], id_sub[64];
    snprintf(id_file, sizeof id_file, "%s", post(&s, mesh_file_doc("tetra.obj"), NULL, 201, NULL, NULL));
    snprintf(id_inline, sizeof id_inline, "%s", post(&s, scene_doc(tetra_inline, ""), NULL, 201, NULL, NULL));
    /* `..` that stays inside, and a symlink whose target is inside, are fine. */
    snprintf(id_sub, sizeof id_sub, "%s",
             post(&s, mesh_file_doc("sub/../sub/./tetra.obj"), NULL, 201, NULL, NULL));
    post(&s, mesh_file_doc("inner-link.obj"), NULL, 201, NULL, NULL);
    const char *ids[] = {id_file, id_inline, id_sub};
    for (int i = 0; i < 3; i++) {
        cJSON *st = ts_wait_done(&s, ids[i], 30);
        assert_string_equal(ts_json_str(st, "state"), "done");
        cJSON_Delete(st);
    }
    ts_image a = {0}, b = {0}, c = {0};
    fetch_exr(&s, id_file, &a);
    fetch_exr(&s, id_inline, &b);
    fetch_exr(&s, id_sub, &c);
    assert_int_equal(a.width, 24);
    assert_int_equal(a.n_channels, b.n_channels);
    size_t n = (size_t)a.width * (size_t)a.height * (size_t)a.n_channels;
    assert_memory_equal(a.data, b.data, n * sizeof(float));
    assert_memory_equal(a.data, c.data, n * sizeof(float));
    int lit = 0; /* the mesh is really there: some pixels see it (AO > 0) */
    for (size_t i = 0; i < (size_t)a.width * (size_t)a.height; i++)
        lit += a.data[i * (size_t)a.n_channels] > 0;
    assert_true(lit > 20);
    ts_image_fini(&a);
    ts_image_fini(&b);
    ts_image_fini(&c);

    /* (b) absolute paths, inside or outside the folder */
    char abs[PATH_MAX + 32];
    snprintf(abs, sizeof abs, "%s/secret.obj", g_outside);
    post(&s, mesh_file_doc(abs), NULL, 400, "shapes[0].file: ", "absolute paths are not allowed");
    snprintf(abs, sizeof abs, "%s/tetra.obj", g_assets);
    post(&s, mesh_file_doc(abs), NULL, 400, "shapes[0].file: ", "absolute paths are not allowed");
    /* (c) `..` out of the folder, also when the target exists */
    post(&s, mesh_file_doc("../outside/secret.obj"), NULL, 400,
         "shapes[0].file: ", "leaves the scene's folder");
    post(&s, mesh_file_doc("sub/../../outside/secret.obj"), NULL, 400, "shapes[0].file: ", "leaves");
    post(&s, mesh_file_doc("../nothing.obj"), NULL, 400, "shapes[0].file: ", "leaves");
    /* (d) symlinks inside the folder pointing out: a file, a relative target, a folder,
     * and a missing file behind a symlinked folder (not reported as merely missing) */
    post(&s, mesh_file_doc("link.obj"), NULL, 400, "shapes[0].file: mesh file 'link.obj': ", "leaves");
    post(&s, mesh_file_doc("rel-link.obj"), NULL, 400, "shapes[0].file: ", "leaves");
    post(&s, mesh_file_doc("linkdir/secret.obj"), NULL, 400, "shapes[0].file: ", "leaves");
    post(&s, mesh_file_doc("linkdir/nothing.obj"), NULL, 400, "shapes[0].file: ", "leaves");
    /* The same rule for every kind of file: environment maps and Fourier tables. */
    post(&s, scene_doc(tetra_inline, ",\"lights\":[{\"type\":\"infinite\",\"map\":\"sky.exr\"}]"), NULL, 400,
         "lights[0].map: environment map 'sky.exr': ", "leaves");
    snprintf(abs, sizeof abs, ",\"lights\":[{\"type\":\"infinite\",\"map\":\"%s/secret.exr\"}]", g_outside);
    post(&s, scene_doc(tetra_inline, abs), NULL, 400, "lights[0].map: ", "absolute paths are not allowed");
    char *doc = scene_doc(tetra_inline, "");
    char *m = strstr(doc, "\"w\":{\"type\":\"diffuse\"}");
    assert_non_null(m);
    char fourier[4200];
    snprintf(fourier, sizeof fourier, "%.*s\"w\":{\"type\":\"fourier\",\"file\":\"table.bsdf\"}%s",
             (int)(m - doc), doc, m + strlen("\"w\":{\"type\":\"diffuse\"}"));
    free(doc);
    post(&s, strdup(fourier), NULL, 400, "materials.w.file: Fourier BSDF file 'table.bsdf': ", "leaves");
    /* Missing files inside are 400 too (a scene error), and say so. */
    post(&s, mesh_file_doc("missing.obj"), NULL, 400, "shapes[0].file: ", "no such file");
    /* Limits apply to files read: size before reading, triangles before the arrays. */
    post(&s, mesh_file_doc("big.obj"), NULL, 413, "shapes[0].file: ", "more than the limit of 8192");
    post(&s, mesh_file_doc("grid.obj"), NULL, 413, "shapes[0].file: ", "limit");

    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* Starts `tessera serve --port 0 args…` with stdout and stderr both going to log (so a
 * test can read everything the server printed); returns the port. */
static int start_logged(pid_t *pid, const char *log, const char *const *args)
{
    const char *bin = getenv("TS_BINARY");
    if (!bin) fail_msg("TS_BINARY is not set (run through ctest)");
    pid_t p = fork();
    if (p == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        if (fd < 0) _exit(127);
        dup2(fd, 1);
        dup2(fd, 2);
        char *argv[32];
        int n = 0;
        argv[n++] = (char *)bin;
        argv[n++] = "serve";
        argv[n++] = "--port";
        argv[n++] = "0";
        for (int i = 0; args[i] && n < 31; i++)
            argv[n++] = (char *)args[i];
        argv[n] = NULL;
        execv(bin, argv);
        _exit(127);
    }
    *pid = p;
    for (int tries = 0; tries < 500; tries++) {
        ts_sleep_ms(20);
        FILE *f = fopen(log, "r");
        char line[512];
        while (f && fgets(line, sizeof line, f)) {
            const char *at = strstr(line, "listening on http://127.0.0.1:");
            if (at) {
                fclose(f);
                return atoi(at + strlen("listening on http://127.0.0.1:"));
            }
        }
        if (f) fclose(f);
    }
    fail_msg("the server did not start (log %s)", log);
    return 0;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char *b = calloc(1, 1 << 16);
    size_t n = fread(b, 1, (1 << 16) - 1, f);
    b[n] = '\0';
    fclose(f);
    return b;
}

static long get_status(const test_server *s, const char *path, const char *auth)
{
    http_resp r;
    ts_http(s, "GET", path, NULL, 0, auth, &r);
    long st = r.status;
    ts_http_free(&r);
    return st;
}

#define TOKEN "k7Qx2Lm9Vt4Rz8Nw3Hp6Jd1Fs5Gb0Yc" /* 32 characters */

/* Only the exact token opens the API; it is never printed. Also (e): no --assets. */
static void test_token(void **state)
{
    (void)state;
    char log[PATH_MAX + 16];
    snprintf(log, sizeof log, "%s/server.log", g_root);
    const char *args[] = {"--threads", "1", "--token", TOKEN, NULL};
    test_server s = {0};
    s.port = start_logged(&s.pid, log, args);
    snprintf(s.base, sizeof s.base, "http://127.0.0.1:%d", s.port);

    const char *path = "/api/v1/jobs";
    assert_int_equal(get_status(&s, path, "Authorization: Bearer " TOKEN), 200);
    assert_int_equal(get_status(&s, path, "Authorization: bearer " TOKEN),
                     200); /* the scheme is case-insensitive */
    assert_int_equal(get_status(&s, path, NULL), 401);
    assert_int_equal(get_status(&s, path, "Authorization: Bearer k7Qx2Lm9Vt4Rz8Nw3Hp6Jd1Fs5Gb0Yd"),
                     401); /* same length */
    assert_int_equal(get_status(&s, path, "Authorization: Bearer X7Qx2Lm9Vt4Rz8Nw3Hp6Jd1Fs5Gb0Yc"), 401);
    assert_int_equal(get_status(&s, path, "Authorization: Bearer k7Qx2Lm9Vt4Rz8Nw3Hp6Jd1Fs5Gb0Y"),
                     401); /* prefix */
    assert_int_equal(get_status(&s, path, "Authorization: Bearer k7Qx"), 401);
    assert_int_equal(get_status(&s, path, "Authorization: Bearer " TOKEN "c"), 401); /* longer */
    assert_int_equal(get_status(&s, path, "Authorization: Bearer " TOKEN TOKEN), 401);
    assert_int_equal(get_status(&s, path, "Authorization: Bearer "), 401);
    assert_int_equal(get_status(&s, path, "Authorization: Basic " TOKEN), 401);
    assert_int_equal(get_status(&s, "/api/v1/jobs?access_token=" TOKEN, NULL), 200);
    assert_int_equal(get_status(&s, "/api/v1/jobs?access_token=k7Qx2Lm9Vt4Rz8Nw3Hp6Jd1Fs5Gb0Y", NULL), 401);
    assert_int_equal(get_status(&s, "/api/v1/jobs?access_token=" TOKEN "0", NULL), 401);
    assert_int_equal(get_status(&s, "/api/v1/nothing?access_token=" TOKEN "0", NULL), 404);
    http_resp r;
    ts_http(&s, "GET", path, NULL, 0, "Authorization: Bearer k7Qx2Lm9Vt4Rz8Nw3Hp6Jd1Fs5Gb0YX", &r);
    assert_null(strstr(r.body, "k7Qx")); /* the 401 echoes nothing */
    assert_null(strstr(r.headers, "k7Qx"));
    ts_http_free(&r);
    /* (e) no --assets: every file reference is refused, inside the folder or not */
    post(&s, mesh_file_doc("tetra.obj"), "Authorization: Bearer " TOKEN, 400,
         "shapes[0].file: ", "may not refer to files");
    post(&s, scene_doc(tetra_inline, ",\"lights\":[{\"type\":\"infinite\",\"map\":\"sky.exr\"}]"),
         "Authorization: Bearer " TOKEN, 400, "lights[0].map: ", "may not refer to files");

    kill(s.pid, SIGTERM);
    int status = 0;
    waitpid(s.pid, &status, 0);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    char *out = slurp(log);
    assert_non_null(strstr(out, "listening on")); /* the log is really the server's output */
    if (strstr(out, "k7Qx")) fail_msg("the token appears in the server's output:\n%s", out);
    free(out);

    /* --token-file: the first line, without its line end; the token is not echoed. */
    char tf[PATH_MAX + 16];
    snprintf(tf, sizeof tf, "%s/token", g_root);
    FILE *f = fopen(tf, "w");
    assert_non_null(f);
    fputs(TOKEN "\n", f);
    fclose(f);
    const char *args2[] = {"--threads", "1", "--token-file", tf, NULL};
    s.port = start_logged(&s.pid, log, args2);
    snprintf(s.base, sizeof s.base, "http://127.0.0.1:%d", s.port);
    assert_int_equal(get_status(&s, path, "Authorization: Bearer " TOKEN), 200);
    assert_int_equal(get_status(&s, path, "Authorization: Bearer " TOKEN "x"), 401);
    assert_int_equal(get_status(&s, path, NULL), 401);
    kill(s.pid, SIGTERM);
    waitpid(s.pid, &status, 0);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    out = slurp(log);
    if (strstr(out, "k7Qx")) fail_msg("the token appears in the server's output:\n%s", out);
    free(out);
}

/* Exit status and message of `tessera serve args…` that must refuse to start. */
static void expect_usage_error(const char *const *args, const char *want)
{
    char log[PATH_MAX + 16];
    snprintf(log, sizeof log, "%s/usage.log", g_root);
    pid_t p = fork();
    if (p == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        dup2(fd, 1);
        dup2(fd, 2);
        char *argv[16];
        int n = 0;
        argv[n++] = getenv("TS_BINARY");
        argv[n++] = "serve";
        for (int i = 0; args[i] && n < 15; i++)
            argv[n++] = (char *)args[i];
        argv[n] = NULL;
        execv(argv[0], argv);
        _exit(127);
    }
    int status = 0;
    waitpid(p, &status, 0);
    char *out = slurp(log);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 2 || !strstr(out, want))
        fail_msg("expected exit 2 and \"%s\", got %d: %s", want, WIFEXITED(status) ? WEXITSTATUS(status) : -1,
                 out);
    if (strstr(out, "k7Qx")) fail_msg("the token appears in the output: %s", out);
    free(out);
}

static void test_option_errors(void **state)
{
    (void)state;
    char missing[PATH_MAX + 16], file[PATH_MAX + 16];
    snprintf(missing, sizeof missing, "%s/no-such-folder", g_root);
    snprintf(file, sizeof file, "%s/tetra.obj", g_assets);
    const char *a1[] = {"--assets", missing, NULL};
    expect_usage_error(a1, "--assets");
    const char *a2[] = {"--assets", file, NULL};
    expect_usage_error(a2, "not a folder");
    const char *a3[] = {"--token", TOKEN, "--token-file", file, NULL};
    expect_usage_error(a3, "give one of them");
    const char *a4[] = {"--token-file", missing, NULL};
    expect_usage_error(a4, "--token-file");
    const char *a5[] = {"--max-jobs", "0", NULL};
    expect_usage_error(a5, "--max-jobs");
    const char *a6[] = {"--max-asset-bytes", "-1", NULL};
    expect_usage_error(a6, "--max-asset-bytes");
}

/* --max-jobs: the store holds at most N jobs; the next POST is 503 and allocates no job. */
static void test_max_jobs(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--max-jobs", "2", NULL};
    ts_server_start(&s, args);
    char ids[2][64];
    for (int i = 0; i < 2; i++)
        snprintf(ids[i], sizeof ids[i], "%s", post(&s, scene_doc(tetra_inline, ""), NULL, 201, NULL, NULL));
    post(&s, scene_doc(tetra_inline, ""), NULL, 503, "holds 2 jobs", "--max-jobs");
    /* Refused before parsing: even a malformed document gets the 503. */
    post(&s, strdup("{not json"), NULL, 503, "--max-jobs", NULL);
    cJSON *list = ts_http_json(&s, "/api/v1/jobs", 200);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(list, "jobs")), 2);
    cJSON_Delete(list);
    for (int i = 0; i < 2; i++)
        cJSON_Delete(ts_wait_done(&s, ids[i], 30));
    /* Finished jobs are still held (their images stay available): still full. */
    post(&s, scene_doc(tetra_inline, ""), NULL, 503, "--max-jobs", NULL);
    /* DELETE of a finished job removes it and frees its slot. */
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s", ids[0]);
    http_resp r;
    ts_http(&s, "DELETE", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 204);
    ts_http_free(&r);
    ts_http(&s, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 404);
    ts_http_free(&r);
    list = ts_http_json(&s, "/api/v1/jobs", 200);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(list, "jobs")), 1);
    cJSON_Delete(list);
    post(&s, scene_doc(tetra_inline, ""), NULL, 201, NULL, NULL);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* DELETE of a finished job under --data removes its folder too: a restart does not bring
 * it back. */
static void test_delete_with_data(void **state)
{
    (void)state;
    char data[PATH_MAX + 8], folder[PATH_MAX + 64], path[128];
    snprintf(data, sizeof data, "%s/data", g_root);
    if (mkdir(data, 0700)) fail_msg("mkdir %s", data);
    const char *args[] = {"--threads", "1", "--data", data, NULL};
    test_server s;
    ts_server_start(&s, args);
    char id[64];
    snprintf(id, sizeof id, "%s", post(&s, scene_doc(tetra_inline, ""), NULL, 201, NULL, NULL));
    snprintf(folder, sizeof folder, "%s/jobs/%s", data, id);
    struct stat sb;
    assert_int_equal(stat(folder, &sb), 0); /* recorded before the 201 */
    cJSON_Delete(ts_wait_done(&s, id, 30));
    snprintf(path, sizeof path, "/api/v1/jobs/%s", id);
    http_resp r;
    ts_http(&s, "DELETE", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 204);
    ts_http_free(&r);
    assert_int_not_equal(stat(folder, &sb), 0);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    assert_int_not_equal(stat(folder, &sb), 0); /* the shutdown checkpoint did not write it back */
    ts_server_start(&s, args);
    cJSON *list = ts_http_json(&s, "/api/v1/jobs", 200);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(list, "jobs")), 0);
    cJSON_Delete(list);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* One raw request (exactly these bytes, n of them) on a new connection; the answer's
 * status, and its body in body (when not NULL, at most 4 KiB, NUL-terminated). */
static int raw_request(const test_server *s, const char *req, size_t n, char *body, size_t body_len)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)s->port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) fail_msg("connect: %s", strerror(errno));
    if (send(fd, req, n, MSG_NOSIGNAL) != (ssize_t)n) fail_msg("send: %s", strerror(errno));
    char buf[8192];
    size_t got = 0;
    for (;;) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 5000) <= 0) break;
        ssize_t r = recv(fd, buf + got, sizeof buf - 1 - got, 0);
        if (r <= 0) break;
        got += (size_t)r;
        buf[got] = '\0';
        const char *end = strstr(buf, "\r\n\r\n");
        const char *cl = strcasestr(buf, "\r\nContent-Length: ");
        if (end && cl && cl < end && got >= (size_t)(end + 4 - buf) + (size_t)atol(cl + 18)) break;
    }
    close(fd);
    buf[got] = '\0';
    if (body) {
        const char *end = strstr(buf, "\r\n\r\n");
        snprintf(body, body_len, "%s", end ? end + 4 : "");
        if (got > 12 && !strstr(buf, "Cache-Control: no-store")) fail_msg("an answer without Cache-Control: no-store: %s", buf);
    }
    return got > 12 ? atoi(buf + 9) : -1;
}

/* A request with method, path, extra header lines (each ending in \r\n) and body; Host
 * 127.0.0.1:PORT unless extra gives one. Returns the status. */
static int req_status(const test_server *s, const char *method, const char *path, const char *extra, const char *body)
{
    char *req = malloc(16384);
    int n = snprintf(req, 16384, "%s %s HTTP/1.1\r\n%s%s%d\r\nConnection: close\r\nContent-Length: %zu\r\n\r\n%s",
                     method, path, extra, strcasestr(extra, "Host:") ? "X-Port: " : "Host: 127.0.0.1:", s->port,
                     body ? strlen(body) : 0, body ? body : "");
    char out[4096];
    int st = raw_request(s, req, (size_t)n, out, sizeof out);
    free(req);
    return st;
}

/* Browser pages cannot drive the server: without a token only application/json POSTs
 * (the exact media type); Origin must be the server's own or --cors-origin; Host must be
 * a name the server is bound to or --allowed-hosts (DNS rebinding). */
static void test_browser_pages(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--allowed-hosts", "render.example", NULL};
    ts_server_start(&s, args);
    char *doc = scene_doc(tetra_inline, "");
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: text/plain\r\n", doc), 415);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: application/x-www-form-urlencoded\r\n", doc), 415);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: application/jsonx\r\n", doc), 415);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "", doc), 415); /* none */
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: Application/JSON; charset=utf-8\r\n", doc), 201);
    char origin[128];
    snprintf(origin, sizeof origin, "Content-Type: application/json\r\nOrigin: http://127.0.0.1:%d\r\n", s.port);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", origin, doc), 201); /* the UI's own origin */
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: application/json\r\nOrigin: https://evil.example\r\n", doc), 403);
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs", "Origin: null\r\n", NULL), 403);
    /* Host */
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs", "Host: evil.example\r\n", NULL), 403);
    assert_int_equal(req_status(&s, "GET", "/", "Host: evil.example:80\r\n", NULL), 403);
    assert_int_equal(req_status(&s, "GET", "/healthz", "Host: localhost\r\n", NULL), 200);
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs", "Host: localhost:8080\r\n", NULL), 200);
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs", "Host: render.example\r\n", NULL), 200);
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs", "Host: 127.0.0.1\r\n", NULL), 200);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    /* --cors-origin lets that one origin post; with a token other content types pass. */
    const char *args2[] = {"--threads", "1", "--cors-origin", "https://ui.example", "--token", TOKEN, NULL};
    ts_server_start(&s, args2);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs",
                                "Content-Type: application/json\r\nOrigin: https://ui.example\r\nAuthorization: Bearer " TOKEN "\r\n", doc), 201);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: text/plain\r\nAuthorization: Bearer " TOKEN "\r\n", doc), 201);
    assert_int_equal(req_status(&s, "POST", "/api/v1/jobs", "Content-Type: application/jsonx\r\nAuthorization: Bearer " TOKEN "\r\n", doc), 415);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(doc);
}

/* URLs and tokens are read strictly: tile indices are canonical decimal in range, escapes
 * are never decoded before routing, the token is compared over the whole presented value,
 * and two Content-Length headers are refused. */
static void test_strict_urls_and_tokens(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--token", TOKEN, NULL};
    ts_server_start(&s, args);
    const char *auth = "Authorization: Bearer " TOKEN;
    char id[64], path[256], hdr[128];
    snprintf(id, sizeof id, "%s", post(&s, scene_doc(tetra_inline, ""), auth, 201, NULL, NULL));
    snprintf(hdr, sizeof hdr, "%s\r\n", auth);
    const char *good[] = {"0/0.png", "0/0.exr"};
    const char *bad[] = {"4294967296/0.png", "4294967297/0.png", "+0/0.png", "00/0.png", "-0/0.png", "0/01.png",
                         "0/0.PNG", "0/0.png/", "0x0/0.png", "99999999999/0.png"};
    for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
        snprintf(path, sizeof path, "/api/v1/jobs/%s/tiles/%s", id, good[i]);
        assert_int_equal(req_status(&s, "GET", path, hdr, NULL), 200);
    }
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        snprintf(path, sizeof path, "/api/v1/jobs/%s/tiles/%s", id, bad[i]);
        int st = req_status(&s, "GET", path, hdr, NULL);
        if (st != 404 && st != 400) fail_msg("GET %s answered %d", path, st);
    }
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs/%00", hdr, NULL), 404);
    snprintf(path, sizeof path, "/api/v1/jobs/%s%%2fimage.exr", id);
    assert_int_equal(req_status(&s, "GET", path, hdr, NULL), 404);
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image%%2eexr", id);
    assert_int_equal(req_status(&s, "GET", path, hdr, NULL), 404);
    /* The token over the whole value: %00 (or more) after it in the argument is not it.
     * (A NUL byte inside the Authorization header itself is cut off by libmicrohttpd
     * before the server sees the value: docs/security.md.) */
    int st;
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs?access_token=" TOKEN "%00", "", NULL), 401);
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs?access_token=" TOKEN "%00x", "", NULL), 401);
    assert_int_equal(req_status(&s, "GET", "/api/v1/jobs?access_token=" TOKEN, "", NULL), 200);
    snprintf(path, sizeof path, "/api/v1/jobs?access_token=%%6b%s", TOKEN + 1); /* %6b is the token's k */
    assert_int_equal(req_status(&s, "GET", path, "", NULL), 200);
    /* Two Content-Length headers: which frames the body? Refused. */
    static const char two_cl[] = "POST /api/v1/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer " TOKEN "\r\n"
                                 "Content-Type: application/json\r\nContent-Length: 2\r\nContent-Length: 20\r\n"
                                 "Connection: close\r\n\r\n{}";
    st = raw_request(&s, two_cl, sizeof two_cl - 1, NULL, 0);
    assert_int_equal(st, 400);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* Every string of a posted document has a length limit (255 bytes; 1024 for file
 * references), refused with 400 naming its JSON path before anything renders; a name at
 * the limit renders and its images are served. */
static void test_string_limits(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", NULL};
    ts_server_start(&s, args);
    char name[300], extra[400], path[128];
    memset(name, 'n', 256);
    name[256] = '\0';
    snprintf(extra, sizeof extra, ",\"name\":\"%s\"", name);
    post(&s, scene_doc(tetra_inline, extra), NULL, 400, "name: a string of 256 bytes", "limit of 255");
    snprintf(extra, sizeof extra, ",\"job\":{\"name\":\"%s\"}", name);
    post(&s, scene_doc(tetra_inline, extra), NULL, 400, "job.name: a string of 256 bytes", NULL);
    name[255] = '\0';
    snprintf(extra, sizeof extra, ",\"name\":\"%s\"", name);
    char id[64];
    snprintf(id, sizeof id, "%s", post(&s, scene_doc(tetra_inline, extra), NULL, 201, NULL, NULL));
    cJSON_Delete(ts_wait_done(&s, id, 30));
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.png", id);
    assert_int_equal(get_status(&s, path, NULL), 200);
    snprintf(path, sizeof path, "/api/v1/jobs/%s/tiles/0/0.exr", id);
    assert_int_equal(get_status(&s, path, NULL), 200);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* Oversized and malformed request heads. Up to libmicrohttpd's per-connection memory (32
 * KiB for the request line and headers together) tessera sees the request and answers its
 * own JSON 414 (URL over 8 KiB) and 431 (headers over 8 KiB) with Cache-Control: no-store
 * (raw_request checks it). Beyond that memory, and for a request line or header line that
 * does not parse, libmicrohttpd 0.9.75 answers with its built-in HTML page before any
 * callback of tessera runs (docs/security.md): for those the test asserts the status code
 * and that the server stays up. */
static void test_oversized_and_malformed_heads(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", NULL};
    ts_server_start(&s, args);
    char *path = malloc(48 * 1024), *hdrs = malloc(128 * 1024), *req = malloc(200 * 1024), out[4096];
    /* A URL at the limit is routed (404 JSON); one byte over is tessera's 414. */
    path[0] = '/';
    memset(path + 1, 'a', 8191);
    path[8192] = '\0';
    assert_int_equal(req_status(&s, "GET", path, "", NULL), 404);
    memset(path + 1, 'a', 8192);
    path[8193] = '\0';
    int n = snprintf(req, 200 * 1024, "GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", path);
    assert_int_equal(raw_request(&s, req, (size_t)n, out, sizeof out), 414);
    if (!strstr(out, "{\"error\":\"the request's URL") || !strstr(out, "limit of 8192 bytes"))
        fail_msg("the 414 body is not tessera's JSON: %s", out);
    /* 10 KiB of headers: tessera's 431; 7 KiB pass. */
    size_t h = 0;
    for (int i = 0; i < 35; i++) h += (size_t)snprintf(hdrs + h, 128 * 1024 - h, "X-Pad-%03d: %0190d\r\n", i, 0);
    n = snprintf(req, 200 * 1024, "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n%sConnection: close\r\n\r\n", hdrs);
    assert_int_equal(raw_request(&s, req, (size_t)n, out, sizeof out), 200);
    for (int i = 35; i < 50; i++) h += (size_t)snprintf(hdrs + h, 128 * 1024 - h, "X-Pad-%03d: %0190d\r\n", i, 0);
    n = snprintf(req, 200 * 1024, "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n%sConnection: close\r\n\r\n", hdrs);
    assert_int_equal(raw_request(&s, req, (size_t)n, out, sizeof out), 431);
    if (!strstr(out, "{\"error\":\"the request's headers") || !strstr(out, "limit of 8192 bytes"))
        fail_msg("the 431 body is not tessera's JSON: %s", out);
    /* Past the connection's memory, and unparsable heads: libmicrohttpd's own answers. */
    memset(path + 1, 'a', 40000);
    path[40001] = '\0';
    n = snprintf(req, 200 * 1024, "GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", path);
    assert_int_equal(raw_request(&s, req, (size_t)n, NULL, 0), 414);
    h = 0;
    for (int i = 0; i < 1000; i++) h += (size_t)snprintf(hdrs + h, 128 * 1024 - h, "X-Pad-%04d: %090d\r\n", i, 0);
    n = snprintf(req, 200 * 1024, "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n%sConnection: close\r\n\r\n", hdrs);
    assert_int_equal(raw_request(&s, req, (size_t)n, NULL, 0), 431);
    static const char garbage[] = "\x01\x02 garbage request line\r\n\r\n";
    assert_int_equal(raw_request(&s, garbage, sizeof garbage - 1, NULL, 0), 400);
    static const char bad_header[] = "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\nno colon here\r\nConnection: close\r\n\r\n";
    assert_int_equal(raw_request(&s, bad_header, sizeof bad_header - 1, NULL, 0), 400);
    assert_int_equal(req_status(&s, "GET", "/healthz", "", NULL), 200); /* still serving */
    free(path);
    free(hdrs);
    free(req);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_assets),
        cmocka_unit_test(test_token),
        cmocka_unit_test(test_option_errors),
        cmocka_unit_test(test_max_jobs),
        cmocka_unit_test(test_delete_with_data),
        cmocka_unit_test(test_browser_pages),
        cmocka_unit_test(test_strict_urls_and_tokens),
        cmocka_unit_test(test_string_limits),
        cmocka_unit_test(test_oversized_and_malformed_heads),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
