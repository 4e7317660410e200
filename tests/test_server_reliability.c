/* test_server_reliability.c — no request can hang the server (issue 27), against a real
 * `tessera serve` on loopback:
 *   - a posted JSON scene loads on a loader thread, never an HTTP thread: with one HTTP
 *     thread, /healthz answers while a costly scene loads, and the load stops at
 *     --max-load-seconds with a 422 naming the option (/metrics counts it);
 *   - bundles load on the loader threads too, so two costly bundles never hold up an image
 *     (the encoders stay free);
 *   - SIGTERM during a load (a large PLY mesh: its reading and BVH build poll the load's
 *     ts_cancel) exits within a second;
 *   - a cancel with no body and no Content-Type is accepted (415 stays for bodies).
 * The costly scene is 200 bytes: a loop subdivision surface of two triangles, 10 levels
 * (2 M triangles, ~4 s to load on this machine). The time bounds are the (healthz
 * 50 ms p99 is measured by bench/hostile/run.sh, where timing belongs); here each bound is
 * loose enough for a machine shared by five builds (a healthz answer within 1 s, where the
 * old code made it wait for the whole load). */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <curl/curl.h>
#include <dirent.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "server_harness.h"
#include "tmp_folder.h"

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A scene that is small to post and costly to load: two triangles subdivided `levels` times. */
static char *subdiv_scene(int levels)
{
    char *s = malloc(1024);
    snprintf(s, 1024,
             "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0],\"fov\":40},"
             "\"film\":{\"width\":16,\"height\":16},\"sampler\":{\"spp\":1},\"integrator\":{\"type\":\"ao\"},"
             "\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
             "\"shapes\":[{\"type\":\"loopsubdiv\",\"levels\":%d,\"positions\":[-1,-1,0, 1,-1,0, 1,1,0, -1,1,0],"
             "\"indices\":[0,1,2, 0,2,3],\"material\":\"m\"}]}",
             levels);
    return s;
}

/* One request that never fails the test (it may run on another thread, or meet a server
 * going away): the status, or -1 when the connection failed. type NULL: no Content-Type. */
typedef struct call {
    const test_server *srv;
    const char *method, *path, *type;
    const void *body;
    size_t len;
    long status;
    char text[1024];
    double seconds;
} call;

static size_t keep_text(char *data, size_t size, size_t n, void *user)
{
    call *c = user;
    size_t have = strlen(c->text), k = size * n;
    if (have + 1 < sizeof c->text) {
        size_t m = k < sizeof c->text - have - 1 ? k : sizeof c->text - have - 1;
        memcpy(c->text + have, data, m);
        c->text[have + m] = '\0';
    }
    return k;
}

static void *run_call(void *arg)
{
    call *c = arg;
    char url[256], type[128];
    snprintf(url, sizeof url, "%s%s", c->srv->base, c->path);
    CURL *h = curl_easy_init();
    struct curl_slist *hd = curl_slist_append(NULL, "Expect:");
    if (c->type) {
        snprintf(type, sizeof type, "Content-Type: %s", c->type);
        hd = curl_slist_append(hd, type);
    } else {
        hd = curl_slist_append(hd, "Content-Type:"); /* none at all */
    }
    curl_easy_setopt(h, CURLOPT_URL, url);
    curl_easy_setopt(h, CURLOPT_CUSTOMREQUEST, c->method);
    if (!strcmp(c->method, "POST")) {
        curl_easy_setopt(h, CURLOPT_POSTFIELDS, c->body ? c->body : "");
        curl_easy_setopt(h, CURLOPT_POSTFIELDSIZE_LARGE, (curl_off_t)c->len);
    }
    curl_easy_setopt(h, CURLOPT_HTTPHEADER, hd);
    curl_easy_setopt(h, CURLOPT_WRITEFUNCTION, keep_text);
    curl_easy_setopt(h, CURLOPT_WRITEDATA, c);
    curl_easy_setopt(h, CURLOPT_TIMEOUT, 60L);
    c->text[0] = '\0';
    double t0 = now_s();
    c->status = curl_easy_perform(h) == CURLE_OK ? 0 : -1;
    if (c->status == 0) curl_easy_getinfo(h, CURLINFO_RESPONSE_CODE, &c->status);
    c->seconds = now_s() - t0;
    curl_slist_free_all(hd);
    curl_easy_cleanup(h);
    return NULL;
}

static void do_call(call *c) { run_call(c); }

/* The value of a metric line "name value" in /metrics, or -1. */
static double metric(const test_server *s, const char *name)
{
    http_resp r;
    ts_http(s, "GET", "/metrics", NULL, 0, NULL, &r);
    double v = -1;
    char key[128];
    snprintf(key, sizeof key, "\n%s ", name);
    const char *at = strstr(r.body, key);
    if (at) v = strtod(at + strlen(key), NULL);
    ts_http_free(&r);
    return v;
}

/* /healthz answered while a slow load holds the server: the slowest of the answers polled
 * every 20 ms until done is set (each must be 200 "ok"). */
static double poll_healthz_until(const test_server *s, const volatile int *done, int *n_polls)
{
    double worst = 0;
    *n_polls = 0;
    while (!*done) {
        call h = {.srv = s, .method = "GET", .path = "/healthz", .type = NULL};
        do_call(&h);
        assert_int_equal(h.status, 200);
        assert_non_null(strstr(h.text, "\"status\":\"ok\""));
        if (h.seconds > worst) worst = h.seconds;
        (*n_polls)++;
        ts_sleep_ms(20);
    }
    return worst;
}

typedef struct bg { call c; volatile int done; } bg;

static void *run_bg(void *arg)
{
    bg *b = arg;
    run_call(&b->c);
    b->done = 1;
    return NULL;
}

/* A JSON scene that takes seconds to load, on a server with one HTTP thread and a 0.5 s
 * load bound: /healthz answers throughout, the POST is 422 naming --max-load-seconds
 * within the bound and the polling granularity, and /metrics counts one timed-out load.
 * Before the fix the load ran on the only HTTP thread: /healthz waited ~4 s and the POST
 * was 201. */
static void test_json_load_off_http_thread(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--http-threads", "1", "--threads", "1", "--max-load-seconds", "0.5", NULL};
    ts_server_start(&s, args);
    char *scene = subdiv_scene(10);
    bg post = {.c = {.srv = &s, .method = "POST", .path = "/api/v1/jobs", .type = "application/json",
                     .body = scene, .len = strlen(scene)}};
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, run_bg, &post), 0);
    ts_sleep_ms(100);
    int polls = 0;
    double worst = poll_healthz_until(&s, &post.done, &polls);
    pthread_join(th, NULL);
    print_message("healthz while loading: %d answers, slowest %.3f s; POST %ld in %.2f s: %s\n", polls, worst,
                  post.c.status, post.c.seconds, post.c.text);
    assert_true(worst < 1.0);
    assert_int_equal(post.c.status, 422);
    assert_non_null(strstr(post.c.text, "--max-load-seconds"));
    /* The bound, plus the longest unpolled step (one level's edge sort, ~1 s at 2 M
     * triangles on a loaded machine). */
    assert_true(post.c.seconds < 0.5 + 2.5);
    assert_true(metric(&s, "tessera_loads_timed_out_total") == 1);
    assert_true(metric(&s, "tessera_loads_total") == 1);
    /* The server is fine afterwards: a small scene is accepted. */
    char *ok = ts_ao_scene("after", 8, 8, 1);
    http_resp r;
    ts_http(&s, "POST", "/api/v1/jobs", ok, strlen(ok), NULL, &r);
    assert_int_equal(r.status, 201);
    ts_http_free(&r);
    free(ok);
    free(scene);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* One-file ustar archive (name, data) into a malloc'd buffer. */
static unsigned char *one_file_tar(const char *name, const char *data, size_t len, size_t *out_len)
{
    size_t padded = (len + 511) / 512 * 512, n = 512 + padded + 1024;
    unsigned char *t = calloc(1, n);
    char *h = (char *)t;
    snprintf(h, 100, "%s", name);
    snprintf(h + 100, 8, "%07o", 0644);
    snprintf(h + 108, 8, "%07o", 0);
    snprintf(h + 116, 8, "%07o", 0);
    snprintf(h + 124, 12, "%011zo", len);
    snprintf(h + 136, 12, "%011o", 0);
    h[156] = '0';
    memcpy(h + 257, "ustar", 6);
    memcpy(h + 263, "00", 2);
    memset(h + 148, ' ', 8);
    unsigned sum = 0;
    for (int i = 0; i < 512; i++) sum += t[i];
    snprintf(h + 148, 8, "%06o", sum);
    memcpy(t + 512, data, len);
    *out_len = n;
    return t;
}

/* Two costly bundles at once (issue 27's "the same chain in a bundle pins an encoder"):
 * they load on the loader threads, so an image of a finished job is answered meanwhile;
 * both end at the 1 s bound (422). Before the fix bundles loaded on the two encoder
 * threads: the image waited for a whole load (~4 s or more). */
static void test_bundles_leave_encoders_free(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--max-load-seconds", "1", NULL};
    ts_server_start(&s, args);
    char id[64];
    char *small = ts_ao_scene("small", 8, 8, 1);
    ts_submit(&s, small, id, sizeof id);
    free(small);
    cJSON_Delete(ts_wait_done(&s, id, 30));
    char *scene = subdiv_scene(10);
    size_t tar_len;
    unsigned char *tar = one_file_tar("scene.json", scene, strlen(scene), &tar_len);
    bg posts[2];
    pthread_t th[2];
    for (int k = 0; k < 2; k++) {
        posts[k] = (bg){.c = {.srv = &s, .method = "POST", .path = "/api/v1/jobs", .type = "application/x-tar",
                              .body = tar, .len = tar_len}};
        assert_int_equal(pthread_create(&th[k], NULL, run_bg, &posts[k]), 0);
    }
    ts_sleep_ms(200);
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.png", id);
    double worst = 0;
    for (int i = 0; i < 5; i++) {
        call img = {.srv = &s, .method = "GET", .path = path};
        do_call(&img);
        assert_int_equal(img.status, 200);
        if (img.seconds > worst) worst = img.seconds;
        ts_sleep_ms(50);
    }
    for (int k = 0; k < 2; k++) pthread_join(th[k], NULL);
    print_message("image while two bundles load: slowest %.3f s; bundles %ld (%.2f s), %ld (%.2f s)\n", worst,
                  posts[0].c.status, posts[0].c.seconds, posts[1].c.status, posts[1].c.seconds);
    assert_true(worst < 1.0);
    for (int k = 0; k < 2; k++) {
        assert_int_equal(posts[k].c.status, 422);
        assert_non_null(strstr(posts[k].c.text, "--max-load-seconds"));
    }
    free(tar);
    free(scene);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* A binary PLY grid of (n+1)² vertices and 2n² triangles. */
static void write_ply_grid(const char *path, int n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
               "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n",
            (n + 1) * (n + 1), 2 * n * n);
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float v[3] = {(float)i / (float)n * 2 - 1, (float)j / (float)n * 2 - 1, (float)((i * 7 + j * 3) % 5) * 1e-3f};
            fwrite(v, sizeof v, 1, f);
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            int t[2][3] = {{a, b, d}, {a, d, c}};
            for (int k = 0; k < 2; k++) {
                unsigned char three = 3;
                fwrite(&three, 1, 1, f);
                fwrite(t[k], sizeof t[k], 1, f);
            }
        }
    assert_int_equal(fclose(f), 0);
}

/* SIGTERM while a large mesh loads (its reading and BVH build poll the load's ts_cancel):
 * the server exits 0 within a second of the signal. Before the fix the load ran on an HTTP
 * thread that the shutdown waited for (seconds). */
static void test_sigterm_during_load(void **state)
{
    (void)state;
    const char *root = ts_tmp_dir;
    char ply[PATH_MAX];
    snprintf(ply, sizeof ply, "%s/grid.ply", root);
    write_ply_grid(ply, 1000); /* 2 M triangles, 38 MB */
    test_server s;
    const char *args[] = {"--threads", "1", "--assets", root, NULL};
    ts_server_start(&s, args);
    const char *scene = "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0],\"fov\":40},"
                        "\"film\":{\"width\":16,\"height\":16},\"sampler\":{\"spp\":1},\"integrator\":{\"type\":\"ao\"},"
                        "\"materials\":{\"m\":{\"type\":\"diffuse\"}},"
                        "\"shapes\":[{\"type\":\"mesh\",\"file\":\"grid.ply\",\"material\":\"m\"}]}";
    bg post = {.c = {.srv = &s, .method = "POST", .path = "/api/v1/jobs", .type = "application/json", .body = scene,
                     .len = strlen(scene)}};
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, run_bg, &post), 0);
    ts_sleep_ms(400); /* inside the load (it takes seconds) */
    assert_false(post.done);
    double t0 = now_s();
    kill(s.pid, SIGTERM);
    int status = 0;
    waitpid(s.pid, &status, 0);
    double took = now_s() - t0;
    pthread_join(th, NULL);
    unlink(s.log);
    print_message("SIGTERM during a load: exit %d after %.3f s; the POST: %ld %s\n",
                  WIFEXITED(status) ? WEXITSTATUS(status) : -1, took, post.c.status, post.c.text);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    assert_true(took < 1.0);
    /* The load was answered (503, shutting down) or its connection closed — never a job. */
    assert_true(post.c.status == 503 || post.c.status == -1);
    unlink(ply);
}

/* POST …/cancel with no body and no Content-Type is a cancel (nothing a page of another
 * site can send unseen: a browser's fetch names its Origin, refused below); a body still
 * needs application/json (415). */
static void test_cancel_without_body(void **state)
{
    (void)state;
    test_server s;
    ts_server_start(&s, (const char *[]){"--threads", "1", NULL});
    char id[64], path[128];
    char *scene = ts_ao_scene("long", 64, 64, 4096);
    ts_submit(&s, scene, id, sizeof id);
    free(scene);
    snprintf(path, sizeof path, "/api/v1/jobs/%s/cancel", id);
    call bare = {.srv = &s, .method = "POST", .path = path, .type = NULL};
    do_call(&bare);
    assert_int_equal(bare.status, 200);
    call with_body = {.srv = &s, .method = "POST", .path = path, .type = "text/plain", .body = "x", .len = 1};
    do_call(&with_body);
    assert_int_equal(with_body.status, 415);
    call no_type_body = {.srv = &s, .method = "POST", .path = path, .type = NULL, .body = "{}", .len = 2};
    do_call(&no_type_body);
    assert_int_equal(no_type_body.status, 415);
    cJSON *st = ts_wait_done(&s, id, 30);
    assert_string_equal(ts_json_str(st, "state"), "cancelled");
    cJSON_Delete(st);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* A scene whose material reads a texture chain of cost 638 lookups (t7: 1 + twice t6's +
 * its constant amount, from a checkerboard of two constants), w × h pixels. */
static char *costly_texture_scene(int w, int h, int spp)
{
    char *s = malloc(4096);
    int n = snprintf(s, 4096,
                     "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0],\"fov\":40},"
                     "\"film\":{\"width\":%d,\"height\":%d},\"sampler\":{\"spp\":%d},"
                     "\"integrator\":{\"type\":\"path\",\"max_depth\":2},"
                     "\"textures\":{\"t0\":{\"type\":\"checkerboard\",\"tex1\":0.2,\"tex2\":0.8}",
                     w, h, spp);
    for (int k = 1; k <= 7; k++)
        n += snprintf(s + n, 4096 - (size_t)n, ",\"t%d\":{\"type\":\"mix\",\"tex1\":\"t%d\",\"tex2\":\"t%d\"}", k, k - 1, k - 1);
    snprintf(s + n, 4096 - (size_t)n,
             "},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"t7\"}},"
             "\"shapes\":[{\"type\":\"sphere\",\"radius\":1.5,\"material\":\"m\"}],"
             "\"lights\":[{\"type\":\"point\",\"position\":[0,3,3],\"intensity\":10}]}");
    return s;
}

/* --max-work counts what a ray's hit costs in texture lookups (1 + 638/16 rays a ray for
 * the chain above): at --max-work 20000 a 16² path job of depth 2 at 1 spp (5 rays a
 * sample: 1280) is accepted without the texture and refused with it (52 k), naming the
 * textures. Before, textures were not counted and both were accepted. A job of that
 * texture cancels within 100 ms plus a loaded machine's scheduling (1 s here): a lookup
 * costs at most TS_TEXTURE_MAX_COST evaluations, and stops are checked every bounce. */
static void test_max_work_counts_textures(void **state)
{
    (void)state;
    test_server s;
    ts_server_start(&s, (const char *[]){"--threads", "1", "--max-work", "20000", NULL});
    char *plain = costly_texture_scene(16, 16, 1);
    char *at = strstr(plain, "\"reflectance\":\"t7\"");
    memcpy(at, "\"reflectance\":0.50", 18);
    http_resp r;
    ts_http(&s, "POST", "/api/v1/jobs", plain, strlen(plain), NULL, &r);
    assert_int_equal(r.status, 201);
    ts_http_free(&r);
    free(plain);
    char *costly = costly_texture_scene(16, 16, 1);
    ts_http(&s, "POST", "/api/v1/jobs", costly, strlen(costly), NULL, &r);
    print_message("with the texture: %ld %s\n", r.status, r.body);
    assert_int_equal(r.status, 422);
    assert_non_null(strstr(r.body, "for its textures' 638 lookups a hit"));
    ts_http_free(&r);
    free(costly);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);

    ts_server_start(&s, (const char *[]){"--threads", "2", NULL});
    char id[64], path[128];
    costly = costly_texture_scene(256, 256, 4096);
    ts_submit(&s, costly, id, sizeof id);
    free(costly);
    ts_wait_field(&s, id, "samples", 1, 30);
    snprintf(path, sizeof path, "/api/v1/jobs/%s/cancel", id);
    double t0 = now_s();
    call c = {.srv = &s, .method = "POST", .path = path};
    do_call(&c);
    assert_int_equal(c.status, 200);
    cJSON *st = ts_wait_done(&s, id, 30);
    double took = now_s() - t0;
    print_message("a job of that texture cancelled in %.3f s\n", took);
    assert_string_equal(ts_json_str(st, "state"), "cancelled");
    assert_true(took < 1.0);
    cJSON_Delete(st);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* A DELETE as a job ends: the job's state reads finished before the scheduler's on_done
 * has run, so a DELETE could free the job while on_done still used it (a crash,
 * "pthread_mutex_lock: Assertion `mutex->__data.__owner == 0'", or a server that never
 * starts the next job; seen in test_server_api once the posts went through the loaders).
 * 150 jobs, each DELETEd in a loop from its POST on until it is gone; the server must
 * answer every request and stop cleanly. The window is microseconds: against a server
 * built with ASan (make test-asan) the code before the fix failed 1 run in 2 here
 * (heap-use-after-free in on_done, freed by the DELETE), a plain build rarely; after it,
 * 0 in 3 under ASan (leak checking on). */
static void test_delete_as_job_ends(void **state)
{
    (void)state;
    test_server s;
    ts_server_start(&s, (const char *[]){"--threads", "2", NULL});
    char *doc = ts_ao_scene("brief", 8, 8, 2);
    for (int i = 0; i < 150; i++) {
        char id[64], path[128];
        ts_submit(&s, doc, id, sizeof id);
        snprintf(path, sizeof path, "/api/v1/jobs/%s", id);
        long st = 0;
        for (int k = 0; k < 20000 && st != 204; k++) {
            call del = {.srv = &s, .method = "DELETE", .path = path};
            do_call(&del);
            st = del.status;
            if (st != 409 && st != 204) fail_msg("DELETE %s answered %ld: %s", path, st, del.text);
        }
        assert_int_equal(st, 204);
    }
    free(doc);
    call h = {.srv = &s, .method = "GET", .path = "/healthz"};
    do_call(&h);
    assert_int_equal(h.status, 200);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* A document of n named materials (or textures), each looked up by name: the last one is
 * the sphere's (or its material's reflectance). */
static char *many_names(int n, bool textures)
{
    size_t cap = (size_t)n * 64 + 1024, len = 0;
    char *s = malloc(cap);
    len += (size_t)snprintf(s + len, cap - len,
                            "{\"tessera\":1,\"camera\":{\"from\":[0,0,5],\"to\":[0,0,0]},\"film\":{\"width\":8,"
                            "\"height\":8},\"sampler\":{\"spp\":1},\"integrator\":{\"type\":\"ao\"},\"%s\":{",
                            textures ? "textures" : "materials");
    for (int k = 0; k < n; k++)
        len += (size_t)snprintf(s + len, cap - len, "%s\"n%d\":{\"type\":\"%s\"}", k ? "," : "", k,
                                textures ? "constant" : "diffuse");
    if (textures)
        snprintf(s + len, cap - len, "},\"materials\":{\"m\":{\"type\":\"diffuse\",\"reflectance\":\"n%d\"}},"
                 "\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"m\"}]}", n - 1);
    else
        snprintf(s + len, cap - len, "},\"shapes\":[{\"type\":\"sphere\",\"radius\":1,\"material\":\"n%d\"}]}", n - 1);
    return s;
}

/* Loading is linear in the document: 60000 named materials (1.5 MB) and 60000 named
 * textures load well within a 5 s --max-load-seconds (0.5 s each on this machine). Before,
 * every name was searched for in a list (the builder's materials, the JSON textures): 21 s
 * and 32 s, so both were 422. */
static void test_many_names_load_linear(void **state)
{
    (void)state;
    test_server s;
    ts_server_start(&s, (const char *[]){"--threads", "1", "--max-load-seconds", "5", NULL});
    for (int textures = 0; textures < 2; textures++) {
        char *doc = many_names(60000, textures);
        call c = {.srv = &s, .method = "POST", .path = "/api/v1/jobs", .type = "application/json", .body = doc,
                  .len = strlen(doc)};
        do_call(&c);
        print_message("60000 named %s (%zu bytes): %ld in %.2f s\n", textures ? "textures" : "materials", strlen(doc),
                      c.status, c.seconds);
        assert_int_equal(c.status, 201);
        free(doc);
    }
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* Folders named tessera-serve-* in ts_tmp_dir. */
static int serve_folders(char first[PATH_MAX])
{
    DIR *d = opendir(ts_tmp_dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));)
        if (!strncmp(e->d_name, "tessera-serve-", 14)) {
            if (!n) snprintf(first, PATH_MAX, "%s/%s", ts_tmp_dir, e->d_name);
            n++;
        }
    if (d) closedir(d);
    return n;
}

/* Without --data, bundles go under a temporary folder that the server removes when it
 * stops; a server that is killed cannot, and the next one's start removes it (its .lock
 * is free), never a live server's. Before, every killed run left its folder behind. */
static void test_killed_server_folder_swept(void **state)
{
    (void)state;
    setenv("TMPDIR", ts_tmp_dir, 1);
    test_server a, b;
    ts_server_start(&a, (const char *[]){"--threads", "1", NULL});
    char *scene = ts_ao_scene("bundled", 8, 8, 1);
    size_t tar_len;
    unsigned char *tar = one_file_tar("scene.json", scene, strlen(scene), &tar_len);
    http_resp r;
    ts_http_post(&a, "/api/v1/jobs", tar, tar_len, "application/x-tar", NULL, &r);
    assert_int_equal(r.status, 201);
    ts_http_free(&r);
    char folder[PATH_MAX] = "";
    assert_int_equal(serve_folders(folder), 1);
    /* A second server beside a live one leaves the live one's folder alone. */
    ts_server_start(&b, (const char *[]){"--threads", "1", NULL});
    assert_int_equal(serve_folders(folder), 1);
    assert_int_equal(ts_server_stop(&b, SIGTERM), 0);
    ts_server_stop(&a, SIGKILL);
    struct stat sb;
    assert_int_equal(stat(folder, &sb), 0); /* left behind by the kill */
    ts_server_start(&b, (const char *[]){"--threads", "1", NULL});
    assert_int_equal(stat(folder, &sb), -1);
    assert_int_equal(serve_folders(folder), 0);
    assert_int_equal(ts_server_stop(&b, SIGTERM), 0);
    free(tar);
    free(scene);
    unsetenv("TMPDIR");
}

static int setup(void **state)
{
    curl_global_init(CURL_GLOBAL_DEFAULT);
    return ts_tmp_group_setup(state);
}

static int teardown(void **state)
{
    curl_global_cleanup();
    return ts_tmp_group_teardown(state);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_load_off_http_thread),
        cmocka_unit_test(test_bundles_leave_encoders_free),
        cmocka_unit_test(test_sigterm_during_load),
        cmocka_unit_test(test_cancel_without_body),
        cmocka_unit_test(test_max_work_counts_textures),
        cmocka_unit_test(test_killed_server_folder_swept),
        cmocka_unit_test(test_delete_as_job_ends),
        cmocka_unit_test(test_many_names_load_linear),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
