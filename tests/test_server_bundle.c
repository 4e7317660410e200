/* test_server_bundle.c — jobs that carry their files (server/bundle.h, docs/design.md §5):
 * POST /api/v1/jobs with a tar (plain, gzip detected, or Content-Encoding: gzip) of
 * scene.json or scene.pbrt with its meshes and an environment map, against a real
 * `tessera serve`. Good bundles render, keep their folder with the job (restored with
 * --data) and lose it on DELETE; every kind of bad entry and archive is refused with a
 * 4xx sentence naming the entry, and after each refusal nothing is left on disk (the
 * server's incoming/ and jobs/ folders are empty). The tars are written by libarchive in
 * the test, so every refused kind (links, devices, FIFOs, absolute paths, '..') is what a
 * real tar would hold. A scene.pbrt's import warnings are in the job's status (after a
 * restart too) and in the log; a bundle's ?spp= is its target, bad values refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <archive.h>
#include <archive_entry.h>
#include <curl/curl.h>
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "image/exr.h"
#include "image/image.h"
#include "server_harness.h"

/* ---------------------------------------------------------------- tars */

typedef struct tar_entry {
    const char *name;
    char type;        /* 'f' file, 'd' folder, 's' symbolic link, 'h' hard link, 'c' device, 'p' FIFO */
    const void *data; /* 'f': len bytes (NULL: len zero bytes); 's', 'h': the link's target */
    size_t len;
} tar_entry;

/* A pax tar of the entries, gzip-compressed when gzip; *len its size (caller frees). */
static unsigned char *make_tar(const tar_entry *e, int n, bool gzip, size_t *len)
{
    size_t cap = 1 << 20;
    for (int i = 0; i < n; i++) cap += gzip ? e[i].len / 64 : e[i].len + 1024;
    unsigned char *out = malloc(cap);
    assert_non_null(out);
    struct archive *a = archive_write_new();
    archive_write_set_format_pax_restricted(a);
    if (gzip) archive_write_add_filter_gzip(a);
    archive_write_set_bytes_in_last_block(a, 1);
    assert_int_equal(archive_write_open_memory(a, out, cap, len), ARCHIVE_OK);
    static const char zeros[65536];
    for (int i = 0; i < n; i++) {
        struct archive_entry *ae = archive_entry_new();
        archive_entry_set_pathname(ae, e[i].name);
        archive_entry_set_perm(ae, 0644);
        switch (e[i].type) {
        case 'f': archive_entry_set_filetype(ae, AE_IFREG), archive_entry_set_size(ae, (la_int64_t)e[i].len); break;
        case 'd': archive_entry_set_filetype(ae, AE_IFDIR), archive_entry_set_perm(ae, 0755); break;
        case 's': archive_entry_set_filetype(ae, AE_IFLNK), archive_entry_set_symlink(ae, e[i].data); break;
        case 'h': archive_entry_set_filetype(ae, AE_IFREG), archive_entry_set_hardlink(ae, e[i].data); break;
        case 'c': archive_entry_set_filetype(ae, AE_IFCHR), archive_entry_set_rdev(ae, 0x0103); break;
        case 'p': archive_entry_set_filetype(ae, AE_IFIFO); break;
        }
        assert_int_equal(archive_write_header(a, ae), ARCHIVE_OK);
        if (e[i].type == 'f')
            for (size_t at = 0; at < e[i].len;) {
                size_t k = e[i].len - at < sizeof zeros ? e[i].len - at : sizeof zeros;
                assert_true(archive_write_data(a, e[i].data ? (const char *)e[i].data + at : zeros, k) == (la_ssize_t)k);
                at += k;
            }
        archive_entry_free(ae);
    }
    assert_int_equal(archive_write_close(a), ARCHIVE_OK);
    archive_write_free(a);
    return out;
}

/* ---------------------------------------------------------------- files of the scene */

static const char tri_obj[] = "v -3 0 -3\nv 3 0 -3\nv 0 0 3\nf 1 3 2\n";
static const char quad_ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                               "-1 0 -1\n1 0 -1\n1 2 -1\n-1 2 -1\n3 0 1 2\n3 0 2 3\n";
static unsigned char *sky_exr;
static size_t sky_len;

static const char scene_json[] =
    "{\"tessera\":1,\"camera\":{\"from\":[0,1.5,5],\"to\":[0,0.6,0],\"fov\":35},"
    "\"film\":{\"width\":32,\"height\":24,\"filter\":{\"type\":\"box\"}},\"sampler\":{\"spp\":4},"
    "\"integrator\":{\"type\":\"path\",\"max_depth\":2},\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
    "\"shapes\":[{\"type\":\"mesh\",\"file\":\"meshes/tri.obj\",\"material\":\"w\"},"
    "{\"type\":\"mesh\",\"file\":\"meshes/quad.ply\",\"material\":\"w\"}],"
    "\"lights\":[{\"type\":\"infinite\",\"map\":\"textures/sky.exr\"}]}";

static const char scene_pbrt[] = "LookAt 0 1.5 5  0 0.6 0  0 1 0\nCamera \"perspective\" \"float fov\" [35]\n"
                                 "Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [24]\n"
                                 "Sampler \"sobol\" \"integer pixelsamples\" [4]\nWorldBegin\n"
                                 "LightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"matte\"\n"
                                 "Shape \"plymesh\" \"string filename\" \"meshes/quad.ply\"\nWorldEnd\n";

static int setup(void **state)
{
    (void)state;
    /* A 16 × 8 lat-long sky: brighter towards the pole. */
    ts_image img = {0};
    ts_error err = {0};
    const char *names[] = {"R", "G", "B"};
    if (ts_image_init(&img, 16, 8, 3, names, &err)) fail_msg("%s", err.message);
    for (int i = 0; i < 16 * 8 * 3; i++) img.data[i] = 0.2f + (float)(8 - i / 48) * 0.1f;
    if (ts_exr_write_memory(&img, &sky_exr, &sky_len, &err)) fail_msg("%s", err.message);
    ts_image_fini(&img);
    curl_global_init(CURL_GLOBAL_DEFAULT);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    free(sky_exr);
    curl_global_cleanup();
    return 0;
}

/* The good JSON bundle's entries (names as `tar -C folder .` writes them when dot). */
static int good_entries(tar_entry *e, bool dot)
{
    int n = 0;
    if (dot) e[n++] = (tar_entry){"./", 'd', NULL, 0};
    e[n++] = (tar_entry){dot ? "./scene.json" : "scene.json", 'f', scene_json, strlen(scene_json)};
    e[n++] = (tar_entry){dot ? "./meshes/" : "meshes/", 'd', NULL, 0};
    e[n++] = (tar_entry){dot ? "./meshes/tri.obj" : "meshes/tri.obj", 'f', tri_obj, strlen(tri_obj)};
    e[n++] = (tar_entry){dot ? "./meshes/quad.ply" : "meshes/quad.ply", 'f', quad_ply, strlen(quad_ply)};
    e[n++] = (tar_entry){dot ? "./textures/sky.exr" : "textures/sky.exr", 'f', sky_exr, sky_len};
    return n;
}

/* ---------------------------------------------------------------- HTTP */

/* POSTs body to path as type (with Content-Encoding enc unless NULL); returns the status,
 * *out the body (caller frees). */
static long post(const test_server *s, const void *body, size_t len, const char *type, const char *enc, char **out)
{
    return ts_http_post_body(s, "/api/v1/jobs", body, len, type, enc, out);
}

/* ---------------------------------------------------------------- disk */

/* The folder under which the server keeps bundles: --data, or its temporary folder under
 * TMPDIR (the only tessera-serve-* there: each server of this test has a TMPDIR of its own). */
static void files_root(const char *data, const char *tmp, char *out, size_t n)
{
    if (data) {
        snprintf(out, n, "%s", data);
        return;
    }
    DIR *d = opendir(tmp);
    assert_non_null(d);
    out[0] = '\0';
    for (struct dirent *e; (e = readdir(d));)
        if (!strncmp(e->d_name, "tessera-serve-", 14)) snprintf(out, n, "%s/%s", tmp, e->d_name);
    closedir(d);
    assert_true(out[0]);
}

static void make_tmp(char *out, size_t n, const char *tag)
{
    snprintf(out, n, "%s/ts_bundle_%s_XXXXXX", getenv("TMPDIR") && getenv("TMPDIR")[0] ? getenv("TMPDIR") : "/tmp", tag);
    assert_non_null(mkdtemp(out));
}

static void start_with_tmpdir(test_server *s, const char *tmp, const char *const *args)
{
    char *old = getenv("TMPDIR") ? strdup(getenv("TMPDIR")) : NULL;
    setenv("TMPDIR", tmp, 1);
    ts_server_start(s, args);
    if (old) setenv("TMPDIR", old, 1);
    else unsetenv("TMPDIR");
    free(old);
}

static void rm_rf(const char *dir)
{
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
}

static char *job_id_of(const char *body)
{
    cJSON *o = cJSON_Parse(body);
    assert_non_null(o);
    static char id[32];
    snprintf(id, sizeof id, "%s", ts_json_str(o, "id"));
    cJSON_Delete(o);
    return id;
}

/* ---------------------------------------------------------------- good bundles */

static void test_good_bundles(void **state)
{
    (void)state;
    char data[256], tmp[256], root[600], p[800];
    make_tmp(data, sizeof data, "data");
    make_tmp(tmp, sizeof tmp, "tmp");
    const char *args[] = {"--threads", "2", "--data", data, NULL};
    test_server s;
    start_with_tmpdir(&s, tmp, args);
    files_root(data, tmp, root, sizeof root);
    tar_entry e[8];
    int n = good_entries(e, false);
    size_t len;
    char *body;
    /* Plain tar; gzip (detected, either media type); gzip declared by Content-Encoding;
     * names as `tar -C folder .` writes them. */
    struct { bool gzip, dot; const char *type, *enc; } ways[] = {
        {false, false, "application/x-tar", NULL}, {true, false, "application/gzip", NULL},
        {true, true, "application/x-tar", "gzip"}, {true, true, "application/x-tar; charset=binary", NULL}};
    char ids[4][32];
    for (int w = 0; w < 4; w++) {
        n = good_entries(e, ways[w].dot);
        unsigned char *tar = make_tar(e, n, ways[w].gzip, &len);
        long st = post(&s, tar, len, ways[w].type, ways[w].enc, &body);
        if (st != 201) fail_msg("bundle %d: %ld %s", w, st, body);
        snprintf(ids[w], sizeof ids[w], "%s", job_id_of(body));
        free(body);
        free(tar);
        /* The job's own folder holds the files as they were in the bundle. */
        snprintf(p, sizeof p, "%s/jobs/%s/files/meshes/quad.ply", root, ids[w]);
        struct stat sb;
        assert_int_equal(lstat(p, &sb), 0);
        assert_true(S_ISREG(sb.st_mode) && (size_t)sb.st_size == strlen(quad_ply));
        snprintf(p, sizeof p, "%s/jobs/%s/files/textures/sky.exr", root, ids[w]);
        assert_int_equal(lstat(p, &sb), 0);
        assert_true((size_t)sb.st_size == sky_len);
    }
    /* pbrt-v3 text with a PLY mesh. */
    tar_entry pe[] = {{"scene.pbrt", 'f', scene_pbrt, strlen(scene_pbrt)},
                      {"meshes/quad.ply", 'f', quad_ply, strlen(quad_ply)}};
    unsigned char *tar = make_tar(pe, 2, true, &len);
    long st = post(&s, tar, len, "application/x-tar", NULL, &body);
    free(tar);
    if (st != 201) fail_msg("pbrt bundle: %ld %s", st, body);
    char pbrt_id[32];
    snprintf(pbrt_id, sizeof pbrt_id, "%s", job_id_of(body));
    free(body);
    /* They render; the four JSON ones to the same pixels (the same scene and files). */
    double mean[4];
    for (int w = 0; w < 5; w++) {
        const char *id = w < 4 ? ids[w] : pbrt_id;
        cJSON *done = ts_wait_done(&s, id, 60);
        assert_string_equal(ts_json_str(done, "state"), "done");
        cJSON_Delete(done);
        if (w == 4) break;
        http_resp r;
        snprintf(p, sizeof p, "/api/v1/jobs/%s/image.exr", id);
        ts_http(&s, "GET", p, NULL, 0, NULL, &r);
        assert_int_equal(r.status, 200);
        ts_image img;
        ts_error err = {0};
        if (ts_exr_read_memory((const unsigned char *)r.body, r.len, &img, &err)) fail_msg("%s", err.message);
        ts_http_free(&r);
        double sum = 0;
        for (int i = 0; i < img.width * img.height * img.n_channels; i++) sum += img.data[i];
        mean[w] = sum;
        ts_image_fini(&img);
        assert_true(mean[w] > 0 && mean[w] == mean[0]);
    }
    ts_assert_bundles_left(root, 5, "after five good bundles");
    /* Restarted on the same --data: the jobs and their folders are back, images served. */
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    start_with_tmpdir(&s, tmp, args);
    cJSON *o = ts_http_json(&s, "/api/v1/jobs", 200);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(o, "jobs")), 5);
    cJSON *j;
    cJSON_ArrayForEach(j, cJSON_GetObjectItem(o, "jobs"))
    {
        if (strcmp(ts_json_str(j, "state"), "done")) fail_msg("restored job %s is %s: %s", ts_json_str(j, "id"),
                                                              ts_json_str(j, "state"), cJSON_PrintUnformatted(j));
    }
    cJSON_Delete(o);
    /* DELETE removes the job's folder with its files. */
    for (int w = 0; w < 4; w++) {
        http_resp r;
        snprintf(p, sizeof p, "/api/v1/jobs/%s", ids[w]);
        ts_http(&s, "DELETE", p, NULL, 0, NULL, &r);
        assert_int_equal(r.status, 204);
        ts_http_free(&r);
        snprintf(p, sizeof p, "%s/jobs/%s", root, ids[w]);
        struct stat sb;
        if (lstat(p, &sb) == 0) fail_msg("jobs/%s is still there after DELETE", ids[w]);
    }
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    /* Without --data the bundle goes to the server's temporary folder, removed at the end. */
    const char *args2[] = {"--threads", "2", NULL};
    start_with_tmpdir(&s, tmp, args2);
    /* (made at the first bundle: a server that takes none leaves nothing in TMPDIR) */
    if (ts_count_entries(tmp)) fail_msg("the temporary folder exists before any bundle");
    n = good_entries(e, false);
    tar = make_tar(e, n, true, &len);
    st = post(&s, tar, len, "application/x-tar", NULL, &body);
    free(tar);
    files_root(NULL, tmp, root, sizeof root);
    if (st != 201) fail_msg("bundle without --data: %ld %s", st, body);
    char id[32];
    snprintf(id, sizeof id, "%s", job_id_of(body));
    free(body);
    cJSON_Delete(ts_wait_done(&s, id, 60));
    snprintf(p, sizeof p, "%s/jobs/%s/files/meshes/tri.obj", root, id);
    struct stat sb;
    assert_int_equal(lstat(p, &sb), 0);
    http_resp r;
    snprintf(p, sizeof p, "/api/v1/jobs/%s", id);
    ts_http(&s, "DELETE", p, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 204);
    ts_http_free(&r);
    ts_assert_bundles_left(root, 0, "after DELETE without --data");
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    if (ts_count_entries(tmp)) fail_msg("the server's temporary folder outlived it");
    rm_rf(data);
    rm_rf(tmp);
}

/* ---------------------------------------------------------------- warnings, ?spp= */

/* pbrt-v3 text whose import warns twice: bdpt is rendered with the path integrator, halton
 * is mapped to Sobol. */
static const char scene_pbrt_warns[] = "LookAt 0 1.5 5  0 0.6 0  0 1 0\nCamera \"perspective\" \"float fov\" [35]\n"
                                       "Film \"image\" \"integer xresolution\" [16] \"integer yresolution\" [12]\n"
                                       "Sampler \"halton\" \"integer pixelsamples\" [64]\nIntegrator \"bdpt\"\n"
                                       "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"matte\"\n"
                                       "Shape \"plymesh\" \"string filename\" \"meshes/quad.ply\"\nWorldEnd\n";

/* The status's warnings: two, naming scene.pbrt's lines 5 (bdpt) and 4 (halton). */
static void assert_two_warnings(const cJSON *status, const char *when)
{
    const cJSON *w = cJSON_GetObjectItemCaseSensitive(status, "warnings");
    const cJSON *w0 = cJSON_GetArrayItem(w, 0), *w1 = cJSON_GetArrayItem(w, 1);
    bool bdpt = false, halton = false;
    for (const cJSON *x = w0; x && cJSON_IsString(x); x = x == w0 ? w1 : NULL) {
        bdpt |= !strncmp(x->valuestring, "scene.pbrt:5:", 13) && strstr(x->valuestring, "bdpt") &&
                strstr(x->valuestring, "path integrator");
        halton |= !strncmp(x->valuestring, "scene.pbrt:4:", 13) && strstr(x->valuestring, "halton");
    }
    if (cJSON_GetArraySize(w) != 2 || !bdpt || !halton)
        fail_msg("%s: expected the bdpt and halton warnings, got %s", when, cJSON_PrintUnformatted(w));
}

static void test_pbrt_warnings_and_spp(void **state)
{
    (void)state;
    char data[256], tmp[256], root[600];
    make_tmp(data, sizeof data, "data");
    make_tmp(tmp, sizeof tmp, "tmp");
    const char *args[] = {"--threads", "1", "--data", data, "--max-spp", "64", NULL};
    test_server s;
    start_with_tmpdir(&s, tmp, args);
    files_root(data, tmp, root, sizeof root);
    tar_entry pe[] = {{"scene.pbrt", 'f', scene_pbrt_warns, strlen(scene_pbrt_warns)},
                      {"meshes/quad.ply", 'f', quad_ply, strlen(quad_ply)}};
    size_t len;
    unsigned char *tar = make_tar(pe, 2, false, &len);
    char *body;
    /* ?spp= is the job's target; the file's pixelsamples (64) stay the sampler's. */
    long st = ts_http_post_body(&s, "/api/v1/jobs?spp=2", tar, len, "application/x-tar", NULL, &body);
    if (st != 201) fail_msg("?spp=2: %ld %s", st, body);
    char id[32];
    snprintf(id, sizeof id, "%s", job_id_of(body));
    free(body);
    cJSON *done = ts_wait_done(&s, id, 60);
    assert_string_equal(ts_json_str(done, "state"), "done");
    assert_int_equal((int)ts_json_num(done, "spp_done"), 2);
    assert_int_equal((int)ts_json_num(done, "spp_target"), 2);
    assert_two_warnings(done, "the status");
    cJSON_Delete(done);
    /* Logged: one job.warning line (level warn) each. */
    FILE *f = fopen(s.log, "r");
    assert_non_null(f);
    char line[2048];
    int logged = 0;
    while (fgets(line, sizeof line, f))
        logged += strstr(line, " warn job.warning ") && strstr(line, id) && strstr(line, "scene.pbrt:");
    fclose(f);
    assert_int_equal(logged, 2);
    /* Bad values: 400 (or 422 over --max-spp, naming the parameter); refused before anything is unpacked. */
    static const struct { const char *query; long status; const char *says; } bad[] = {
        {"?spp=0", 400, "spp: expected a whole number"},   {"?spp=007", 400, "spp: expected a whole number"},
        {"?spp=two", 400, "spp: expected a whole number"}, {"?spp=", 400, "spp: expected a whole number"},
        {"?spp=65", 422, "the spp query parameter: 65 samples per pixel is more than this server accepts (64)"},
    };
    for (size_t b = 0; b < sizeof bad / sizeof *bad; b++) {
        char path[64];
        snprintf(path, sizeof path, "/api/v1/jobs%s", bad[b].query);
        st = ts_http_post_body(&s, path, tar, len, "application/x-tar", NULL, &body);
        if (st != bad[b].status || !strstr(body, bad[b].says))
            fail_msg("%s: %ld %s; expected %ld and '%s'", bad[b].query, st, body, bad[b].status, bad[b].says);
        free(body);
        ts_assert_bundles_left(root, 1, bad[b].query);
    }
    /* A JSON scene sets job.spp: the query parameter is refused there. */
    st = ts_http_post_body(&s, "/api/v1/jobs?spp=2", scene_json, strlen(scene_json), "application/json", NULL, &body);
    if (st != 400 || !strstr(body, "a JSON scene sets job.spp")) fail_msg("JSON with ?spp=2: %ld %s", st, body);
    free(body);
    free(tar);
    /* Restored from --data: the warnings again (the scene is loaded again), the target kept. */
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    start_with_tmpdir(&s, tmp, args);
    char p[64];
    snprintf(p, sizeof p, "/api/v1/jobs/%s", id);
    cJSON *o = ts_http_json(&s, p, 200);
    assert_int_equal((int)ts_json_num(o, "spp_target"), 2);
    assert_two_warnings(o, "after the restart");
    cJSON_Delete(o);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    rm_rf(data);
    rm_rf(tmp);
}

/* ---------------------------------------------------------------- bad bundles */

typedef struct bad_case {
    const char *what;
    tar_entry e[4];
    int n;
    long status;
    const char *says; /* a part of the error sentence */
} bad_case;

static void test_bad_entries(void **state)
{
    (void)state;
    char data[256], tmp[256], root[600];
    make_tmp(data, sizeof data, "data");
    make_tmp(tmp, sizeof tmp, "tmp");
    const char *args[] = {"--threads", "1", "--data", data, NULL};
    test_server s;
    start_with_tmpdir(&s, tmp, args);
    files_root(data, tmp, root, sizeof root);
    const tar_entry scene = {"scene.json", 'f', scene_json, strlen(scene_json)};
    const tar_entry obj = {"meshes/tri.obj", 'f', tri_obj, strlen(tri_obj)};
    const tar_entry ply = {"meshes/quad.ply", 'f', quad_ply, strlen(quad_ply)};
    const char *bad_scene = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
                            "\"shapes\":[{\"type\":\"sphere\",\"radius\":-1,\"material\":\"w\"}]}";
    const char *pbrt_include = "WorldBegin\nInclude \"nothere.pbrt\"\nWorldEnd\n";
    const char *unbundled = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
                            "\"shapes\":[{\"type\":\"mesh\",\"file\":\"meshes/missing.obj\",\"material\":\"w\"}]}";
    bad_case cases[] = {
        {"absolute path", {scene, {"/tmp/evil.obj", 'f', tri_obj, 5}}, 2, 400, "'/tmp/evil.obj' is refused: an absolute path"},
        {"'..' first", {scene, {"../evil.obj", 'f', tri_obj, 5}}, 2, 400, "'../evil.obj' is refused: a '..' component"},
        {"'..' inside", {scene, {"meshes/../../evil.obj", 'f', tri_obj, 5}}, 2, 400, "a '..' component"},
        {"symbolic link", {{"meshes/tri.obj", 's', "/etc/passwd", 0}, scene}, 2, 400, "'meshes/tri.obj' is refused: it is a symbolic link"},
        {"hard link", {scene, {"copy.json", 'h', "scene.json", 0}}, 2, 400, "'copy.json' is refused: it is a hard link"},
        {"device", {scene, {"dev/null", 'c', NULL, 0}}, 2, 400, "'dev/null' is refused: it is a character device"},
        {"FIFO", {scene, {"pipe", 'p', NULL, 0}}, 2, 400, "'pipe' is refused: it is a FIFO"},
        {"duplicate", {scene, obj, {"meshes/tri.obj", 'f', quad_ply, 10}}, 3, 400, "'meshes/tri.obj' is refused: a second entry of that name"},
        {"empty component", {scene, {"meshes//tri.obj", 'f', tri_obj, 5}}, 2, 400, "an empty path component"},
        {"backslash", {scene, {"meshes\\tri.obj", 'f', tri_obj, 5}}, 2, 400, "a backslash"},
        {"file over a folder", {scene, obj, {"meshes/tri.obj/x", 'f', tri_obj, 5}}, 3, 400, "'meshes/tri.obj/x' cannot be written"},
        {"no scene", {obj, ply}, 2, 400, "the bundle holds no scene.json or scene.pbrt at its root"},
        {"scene in a folder", {{"box/scene.json", 'f', scene_json, 10}, obj}, 2, 400, "but 'box/scene.json': make the tar from inside"},
        {"both scenes", {scene, {"scene.pbrt", 'f', scene_pbrt, 10}}, 2, 400, "holds both scene.json and scene.pbrt"},
        {"scene refused", {{"scene.json", 'f', bad_scene, strlen(bad_scene)}}, 1, 400, "scene.json: shapes[0].radius"},
        {"file not in the bundle", {{"scene.json", 'f', unbundled, strlen(unbundled)}}, 1, 400, "missing.obj"},
        {"mesh missing (the scene's files)", {scene, obj}, 2, 400, "quad.ply"},
        {"pbrt Include missing", {{"scene.pbrt", 'f', pbrt_include, strlen(pbrt_include)}}, 1, 400,
         "'nothere.pbrt': cannot open"},
    };
    size_t len;
    char *body;
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++)
        for (int gz = 0; gz < 2; gz++) {
            unsigned char *tar = make_tar(cases[c].e, cases[c].n, gz, &len);
            long st = post(&s, tar, len, "application/x-tar", NULL, &body);
            if (st != cases[c].status || !strstr(body, cases[c].says))
                fail_msg("%s (%s): %ld %s; expected %ld and '%s'", cases[c].what, gz ? "gzip" : "tar", st, body,
                         cases[c].status, cases[c].says);
            /* No answer names a path of the server's (docs/security.md): the bundle's
             * folder lies under --data or the temporary folder. */
            if (strstr(body, data) || strstr(body, tmp) || strstr(body, "/jobs/"))
                fail_msg("%s: the answer names a server path: %s", cases[c].what, body);
            free(body);
            free(tar);
            ts_assert_bundles_left(root, 0, cases[c].what);
        }
    /* Truncated archives: a good bundle cut short, plain and compressed, in an entry's data
     * and in a header; and bytes that are no tar at all. */
    tar_entry e[8];
    int n = good_entries(e, false);
    for (int gz = 0; gz < 2; gz++) {
        unsigned char *tar = make_tar(e, n, gz, &len);
        size_t cuts[] = {len / 2, len - 700, 600, 100};
        for (size_t k = 0; k < sizeof cuts / sizeof *cuts; k++) {
            long st = post(&s, tar, cuts[k], "application/x-tar", NULL, &body);
            if (st != 400 || (!strstr(body, "truncated") && !strstr(body, "not a tar archive")))
                fail_msg("%s cut at %zu of %zu: %ld %s", gz ? "tgz" : "tar", cuts[k], len, st, body);
            free(body);
            ts_assert_bundles_left(root, 0, "truncated");
        }
        free(tar);
    }
    long st = post(&s, scene_json, strlen(scene_json), "application/x-tar", NULL, &body);
    if (st != 400 || !strstr(body, "not a tar archive")) fail_msg("JSON sent as a tar: %ld %s", st, body);
    free(body);
    /* A compression the server does not take, and an empty body. */
    unsigned char *tar = make_tar(e, n, false, &len);
    st = post(&s, tar, len, "application/x-tar", "br", &body);
    if (st != 415 || !strstr(body, "'br'")) fail_msg("Content-Encoding br: %ld %s", st, body);
    free(body);
    st = post(&s, tar, 0, "application/x-tar", NULL, &body);
    if (st != 400 || !strstr(body, "empty")) fail_msg("empty bundle: %ld %s", st, body);
    free(body);
    free(tar);
    ts_assert_bundles_left(root, 0, "after every refusal");
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    rm_rf(data);
    rm_rf(tmp);
}

/* The limits, each with the case that reaches it first, on a server without --data. */
static void test_limits(void **state)
{
    (void)state;
    char tmp[256], root[600];
    make_tmp(tmp, sizeof tmp, "tmp");
    const char *args[] = {"--threads", "1", "--max-bundle-entries", "12", "--max-bundle-expanded", "1048576",
                          "--max-bundle-entry-bytes", "524288", "--max-bundle-path", "64", "--max-bundle-bytes",
                          "2097152", NULL};
    test_server s;
    start_with_tmpdir(&s, tmp, args);
    size_t len;
    char *body;
    tar_entry e[64];
    const tar_entry scene = {"scene.json", 'f', scene_json, strlen(scene_json)};
    /* Too many entries: 13 empty files. */
    char names[64][32];
    for (int i = 0; i < 13; i++) {
        snprintf(names[i], sizeof names[i], "f%02d", i);
        e[i] = (tar_entry){names[i], 'f', NULL, 0};
    }
    e[0] = scene;
    unsigned char *tar = make_tar(e, 13, true, &len);
    long st = post(&s, tar, len, "application/x-tar", NULL, &body);
    if (st != 413 || !strstr(body, "more than 12 entries")) fail_msg("13 entries: %ld %s", st, body);
    free(body), free(tar);
    files_root(NULL, tmp, root, sizeof root);
    ts_assert_bundles_left(root, 0, "too many entries");
    /* An expansion bomb: 11 files of 128 KiB (each under the per-entry limit), 1.4 MiB in
     * all over the 1 MiB limit; it stops at the 9th, whose bytes would pass it. */
    for (int i = 1; i < 12; i++) e[i] = (tar_entry){names[i], 'f', NULL, 128 << 10};
    tar = make_tar(e, 12, true, &len);
    st = post(&s, tar, len, "application/x-tar", NULL, &body);
    if (st != 413 || !strstr(body, "expands to more than this server accepts (1048576 bytes) at entry 'f08'"))
        fail_msg("expansion bomb (%zu bytes compressed): %ld %s", len, st, body);
    free(body), free(tar);
    ts_assert_bundles_left(root, 0, "expansion bomb");
    /* A gzip bomb: 256 MiB of zeros in one entry, about 0.26 MB compressed. */
    e[1] = (tar_entry){"zeros.bin", 'f', NULL, 256u << 20};
    tar = make_tar(e, 2, true, &len);
    assert_true(len < 2u << 20);
    st = post(&s, tar, len, "application/x-tar", NULL, &body);
    if (st != 413 || !strstr(body, "'zeros.bin' is 268435456 bytes, more than this server accepts (524288)"))
        fail_msg("gzip bomb (%zu bytes compressed): %ld %s", len, st, body);
    free(body), free(tar);
    ts_assert_bundles_left(root, 0, "gzip bomb");
    /* A path over 64 bytes. */
    e[1] = (tar_entry){"meshes/a-very-long-folder-name-for-a-mesh/and-a-long-file-name-too.obj", 'f', tri_obj, 5};
    tar = make_tar(e, 2, false, &len);
    st = post(&s, tar, len, "application/x-tar", NULL, &body);
    if (st != 413 || !strstr(body, "path is 70 bytes, longer than this server accepts (64)")) fail_msg("long path: %ld %s", st, body);
    free(body), free(tar);
    /* A bundle over --max-bundle-bytes (incompressible bytes in a plain tar). */
    unsigned char *noise = malloc(3u << 20);
    for (size_t i = 0; i < (3u << 20); i++) noise[i] = (unsigned char)((i * 2654435761u) >> 13);
    e[1] = (tar_entry){"noise.bin", 'f', noise, 400 << 10};
    for (int i = 2; i < 8; i++) e[i] = (tar_entry){names[i], 'f', noise + (size_t)i * (400 << 10), 400 << 10};
    tar = make_tar(e, 8, false, &len);
    assert_true(len > (2u << 20));
    st = post(&s, tar, len, "application/x-tar", NULL, &body);
    if (st != 413 || !strstr(body, "larger than the limit of 2097152 bytes")) fail_msg("large bundle: %ld %s", st, body);
    free(body), free(tar), free(noise);
    ts_assert_bundles_left(root, 0, "after the limits");
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    if (ts_count_entries(tmp)) fail_msg("the server's temporary folder outlived it");
    rm_rf(tmp);
}

/* ---------------------------------------------------------------- names and limits */

/* The job's name in its status and in its image.exr's tessera_scene. */
static void assert_named(const test_server *s, const char *id, const char *want, const char *what)
{
    char p[96];
    snprintf(p, sizeof p, "/api/v1/jobs/%s", id);
    cJSON *o = ts_http_json(s, p, 200);
    const char *name = ts_json_str(o, "name");
    if (!name || strcmp(name, want)) fail_msg("%s: the job is named '%s', expected '%s'", what, name ? name : "(none)", want);
    cJSON_Delete(o);
    ts_image img;
    ts_job_exr(s, id, &img);
    const ts_image_attr *a = ts_image_attr_find(&img, "tessera_scene");
    if (!a || a->type != TS_ATTR_STRING || strcmp(a->s, want))
        fail_msg("%s: image.exr's tessera_scene is '%s', expected '%s'", what, a ? a->s : "(none)", want);
    ts_image_fini(&img);
}

/* Issue #32.4 and .7: a job is named as `tessera render` names it — job.name, else the
 * scene's "name", else its file's (the built-in scene: "cornell-box"; a bundle: ?name=,
 * which the page fills with the bundle's file or folder name) — in its status and its EXR,
 * also after a restart; GET /api/v1/limits says the limits a POST is checked against. */
static void test_names_and_limits(void **state)
{
    (void)state;
    char data[256], tmp[256];
    make_tmp(data, sizeof data, "names");
    make_tmp(tmp, sizeof tmp, "names_tmp");
    const char *args[] = {"--threads", "1", "--data", data, "--max-spp", "64", "--max-resolution", "1024",
                          "--queue-builtin", NULL};
    test_server s;
    start_with_tmpdir(&s, tmp, args);
    cJSON *lim = ts_http_json(&s, "/api/v1/limits", 200);
    assert_int_equal((int)ts_json_num(lim, "max_spp"), 64);
    assert_int_equal((int)ts_json_num(lim, "max_resolution"), 1024);
    assert_true(ts_json_num(lim, "max_pixels") == 16777216.0 && ts_json_num(lim, "max_body") == 16777216.0);
    assert_true(ts_json_num(lim, "max_bundle_bytes") == 268435456.0 && ts_json_num(lim, "max_work") == 1e13);
    assert_true(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(lim, "bundles")));
    cJSON_Delete(lim);
    /* The built-in job, cancelled at once (it is the 512 × 512 Cornell box). */
    cJSON *list = ts_http_json(&s, "/api/v1/jobs", 200);
    const cJSON *jobs = cJSON_GetObjectItemCaseSensitive(list, "jobs");
    assert_int_equal(cJSON_GetArraySize(jobs), 1);
    char builtin[32];
    snprintf(builtin, sizeof builtin, "%s", ts_json_str(cJSON_GetArrayItem(jobs, 0), "id"));
    cJSON_Delete(list);
    char p[96];
    snprintf(p, sizeof p, "/api/v1/jobs/%s/cancel", builtin);
    http_resp r;
    ts_http(&s, "POST", p, "", 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    cJSON_Delete(ts_wait_done(&s, builtin, 60));
    assert_named(&s, builtin, "cornell-box", "the built-in job");

    tar_entry pe[] = {{"scene.pbrt", 'f', scene_pbrt, strlen(scene_pbrt)}, {"meshes/quad.ply", 'f', quad_ply, strlen(quad_ply)}};
    size_t len;
    unsigned char *tar = make_tar(pe, 2, false, &len);
    static const struct { const char *query; const char *name; } cases[] = {
        {"?name=box&spp=2", "box"}, {"?spp=2", "scene"}, {"?name=caf%C3%A9%20bundle&spp=2", "café bundle"}};
    char ids[3][32];
    for (int c = 0; c < 3; c++) {
        char path[96], *body;
        snprintf(path, sizeof path, "/api/v1/jobs%s", cases[c].query);
        long st = ts_http_post_body(&s, path, tar, len, "application/x-tar", NULL, &body);
        if (st != 201) fail_msg("%s: %ld %s", cases[c].query, st, body);
        snprintf(ids[c], sizeof ids[c], "%s", job_id_of(body));
        free(body);
        cJSON_Delete(ts_wait_done(&s, ids[c], 60));
        assert_named(&s, ids[c], cases[c].name, cases[c].query);
    }
    free(tar);
    /* A scene.json's own name comes first; without one, ?name=. */
    char named[sizeof scene_json + 32];
    snprintf(named, sizeof named, "{\"name\":\"its-own\",%s", scene_json + 1);
    tar_entry je[6];
    int n = good_entries(je, false);
    char jids[2][32];
    for (int c = 0; c < 2; c++) {
        je[0].data = c ? scene_json : named;
        je[0].len = strlen(je[0].data);
        tar = make_tar(je, n, false, &len);
        char *body;
        long st = ts_http_post_body(&s, "/api/v1/jobs?name=box", tar, len, "application/x-tar", NULL, &body);
        if (st != 201) fail_msg("scene.json bundle: %ld %s", st, body);
        snprintf(jids[c], sizeof jids[c], "%s", job_id_of(body));
        free(body);
        free(tar);
        cJSON_Delete(ts_wait_done(&s, jids[c], 60));
        assert_named(&s, jids[c], c ? "box" : "its-own", "a scene.json bundle");
    }
    /* Refused: an empty name, a control character; ?name= on a JSON POST. */
    tar = make_tar(pe, 2, false, &len);
    static const char *const bad[] = {"?name=", "?name=a%01b"};
    for (int b = 0; b < 2; b++) {
        char path[64], *body;
        snprintf(path, sizeof path, "/api/v1/jobs%s", bad[b]);
        long st = ts_http_post_body(&s, path, tar, len, "application/x-tar", NULL, &body);
        if (st != 400 || !strstr(body, "name: expected 1 to 255 bytes")) fail_msg("%s: %ld %s", bad[b], st, body);
        free(body);
    }
    free(tar);
    char *body;
    long st = ts_http_post_body(&s, "/api/v1/jobs?name=x", scene_json, strlen(scene_json), "application/json", NULL, &body);
    if (st != 400 || !strstr(body, "a JSON scene sets name or job.name")) fail_msg("JSON with ?name=: %ld %s", st, body);
    free(body);
    /* Restored from --data: the same names, in the status and the EXR. */
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    const char *again[] = {"--threads", "1", "--data", data, NULL};
    start_with_tmpdir(&s, tmp, again);
    assert_named(&s, builtin, "cornell-box", "the built-in job, restored");
    assert_named(&s, ids[0], "box", "a named bundle, restored");
    assert_named(&s, jids[1], "box", "a scene.json bundle named by ?name=, restored");
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    rm_rf(data);
    rm_rf(tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good_bundles),
        cmocka_unit_test(test_pbrt_warnings_and_spp),
        cmocka_unit_test(test_bad_entries),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_names_and_limits),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
