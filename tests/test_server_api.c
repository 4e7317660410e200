/* test_server_api.c — `tessera serve` over real HTTP on loopback (libcurl): submit, event
 * streams, EXR/PNG contents, two jobs at once, priorities, cancel, time limit, target
 * error, every bad-request class, auth, 200 concurrent clients, and CLI/server identity.
 * Scenes are small `ao` films so the suite stays quick on two cores. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <curl/curl.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "image/exr.h"
#include "image/image.h"
#include "render/render.h"
#include "server_harness.h"

static test_server srv; /* the default server: 2 render threads */

/* An AO scene: a sphere on a floor, w × h, spp; `job` is extra JSON for the "job" object. */
static char *scene(int w, int h, int spp, const char *job)
{
    char *s = malloc(2048);
    snprintf(s, 2048,
             "{\"tessera\":1,\"name\":\"server-test\",\"camera\":{\"from\":[0,1.5,5],\"to\":[0,0.6,0],\"fov\":35},"
             "\"film\":{\"width\":%d,\"height\":%d,\"filter\":{\"type\":\"box\"}},"
             "\"sampler\":{\"spp\":%d,\"seed\":7},\"integrator\":{\"type\":\"ao\"},"
             "\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
             "\"shapes\":[{\"type\":\"sphere\",\"center\":[0,0.6,0],\"radius\":0.6,\"material\":\"w\"},"
             "{\"type\":\"mesh\",\"positions\":[-5,0,-5, 5,0,-5, 5,0,5, -5,0,5],\"indices\":[0,2,1, 0,3,2],\"material\":\"w\"}]"
             "%s%s%s}",
             w, h, spp, job ? ",\"job\":{" : "", job ? job : "", job ? "}" : "");
    return s;
}

static int setup(void **state)
{
    (void)state;
    curl_global_init(CURL_GLOBAL_DEFAULT);
    const char *args[] = {"--threads", "2", "--max-spp", "4000000", NULL};
    ts_server_start(&srv, args);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    assert_int_equal(ts_server_stop(&srv, SIGTERM), 0);
    curl_global_cleanup();
    return 0;
}

static void get_path(char *out, size_t n, const char *id, const char *suffix)
{
    snprintf(out, n, "/api/v1/jobs/%s%s", id, suffix);
}

static void decode_exr(const http_resp *r, ts_image *img)
{
    ts_error err = {0};
    assert_int_equal(r->status, 200);
    if (ts_exr_read_memory((const unsigned char *)r->body, r->len, img, &err)) fail_msg("%s", err.message);
}

static int count_substr(const char *s, const char *needle)
{
    int n = 0;
    for (const char *p = strstr(s, needle); p; p = strstr(p + 1, needle)) n++;
    return n;
}

/* Submit; the late-joining stream gets every tile, then progress and done; the images. */
static void test_submit_stream_and_images(void **state)
{
    (void)state;
    char *doc = scene(80, 48, 8, "\"name\":\"first\"");
    http_resp r;
    ts_http(&srv, "POST", "/api/v1/jobs", doc, strlen(doc), NULL, &r);
    assert_int_equal(r.status, 201);
    assert_non_null(strstr(r.headers, "Location: /api/v1/jobs/"));
    cJSON *o = cJSON_Parse(r.body);
    char id[32], path[160];
    snprintf(id, sizeof id, "%s", ts_json_str(o, "id"));
    assert_string_equal(ts_json_str(o, "name"), "first");
    cJSON_Delete(o);
    ts_http_free(&r);

    get_path(path, sizeof path, id, "/events");
    char *ev = ts_http_stream(&srv, path, 30);
    /* 80 × 48 is 3 × 2 tiles; whatever the moment we joined, each tile's last event says
     * spp 8, the stream ends with done, and events of one tile never go back in spp. */
    assert_non_null(strstr(ev, "event: done"));
    assert_true(count_substr(ev, "event: tile") >= 6);
    assert_int_equal(count_substr(ev, "\"spp\":8,\"png\""), 6);
    assert_non_null(strstr(ev, "event: progress"));
    const char *done = strstr(ev, "event: done");
    assert_null(strstr(done, "event: tile"));
    free(ev);

    get_path(path, sizeof path, id, "");
    o = ts_http_json(&srv, path, 200);
    assert_string_equal(ts_json_str(o, "state"), "done");
    assert_int_equal((int)ts_json_num(o, "spp_done"), 8);
    assert_int_equal((long)ts_json_num(o, "samples"), 80 * 48 * 8);
    assert_true(ts_json_num(o, "error_estimate") > 0);
    assert_string_equal(ts_json_str(o, "halt_reason"), "spp");
    assert_true(cJSON_IsArray(cJSON_GetObjectItem(o, "effects")));
    assert_int_equal((int)ts_json_num(o, "nonfinite_samples"), 0);
    cJSON_Delete(o);

    /* EXR: float RGB + variance + count, 8 samples in every pixel. */
    get_path(path, sizeof path, id, "/image.exr");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    assert_non_null(strstr(r.headers, "image/x-exr"));
    ts_image img;
    decode_exr(&r, &img);
    ts_http_free(&r);
    assert_int_equal(img.width, 80);
    assert_int_equal(img.height, 48);
    int cc = ts_image_channel(&img, "count"), cr = ts_image_channel(&img, "R"), cv = ts_image_channel(&img, "R.var");
    assert_true(cc >= 0 && cr >= 0 && cv >= 0);
    double sum = 0;
    for (int i = 0; i < 80 * 48; i++) {
        assert_float_equal(img.data[i * img.n_channels + cc], 8.0f, 0);
        float v = img.data[i * img.n_channels + cr];
        assert_true(v >= 0 && v <= 1); /* AO is a fraction */
        sum += v;
    }
    assert_true(sum / (80 * 48) > 0.2); /* mostly unoccluded */
    ts_image_fini(&img);

    /* PNG: signature and IHDR size. */
    get_path(path, sizeof path, id, "/image.png");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    assert_true(r.len > 33 && !memcmp(r.body, "\x89PNG\r\n\x1a\n", 8));
    const unsigned char *u = (const unsigned char *)r.body;
    assert_int_equal((u[16] << 24 | u[17] << 16 | u[18] << 8 | u[19]), 80);
    assert_int_equal((u[20] << 24 | u[21] << 16 | u[22] << 8 | u[23]), 48);
    ts_http_free(&r);

    /* One tile: the bottom-right one is 16 × 16. */
    get_path(path, sizeof path, id, "/tiles/2/1.exr");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    decode_exr(&r, &img);
    ts_http_free(&r);
    assert_int_equal(img.width, 16);
    assert_int_equal(img.height, 16);
    assert_float_equal(img.data[ts_image_channel(&img, "count")], 8.0f, 0);
    ts_image_fini(&img);
    get_path(path, sizeof path, id, "/tiles/1/0.png");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    get_path(path, sizeof path, id, "/tiles/3/0.png");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 404);
    ts_http_free(&r);

    /* Listed, newest first. */
    o = ts_http_json(&srv, "/api/v1/jobs", 200);
    cJSON *jobs = cJSON_GetObjectItem(o, "jobs");
    assert_true(cJSON_GetArraySize(jobs) >= 1);
    assert_string_equal(ts_json_str(cJSON_GetArrayItem(jobs, 0), "id"), id);
    cJSON_Delete(o);
    free(doc);
}

/* POST …/cancel, twice (a retried cancel): both answer 200 with the job, which is
 * "cancelling" or "cancelled", and neither deletes it. DELETE while it has not ended is 409. */
static void cancel(const char *id)
{
    char path[160];
    get_path(path, sizeof path, id, "");
    http_resp r;
    ts_http(&srv, "DELETE", path, NULL, 0, NULL, &r);
    long status = r.status;
    if (status == 409) assert_non_null(strstr(r.body, "cancel it first"));
    else assert_int_equal(status, 204); /* only when it had ended already */
    ts_http_free(&r);
    if (status == 204) return;
    const char *st = NULL;
    cJSON *o;
    get_path(path, sizeof path, id, "/cancel");
    for (int i = 0; i < 2; i++) {
        ts_http(&srv, "POST", path, NULL, 0, NULL, &r);
        assert_int_equal(r.status, 200);
        o = cJSON_Parse(r.body);
        assert_non_null(o);
        st = ts_json_str(o, "state");
        if (strcmp(st, "cancelling") && strcmp(st, "cancelled")) fail_msg("cancel answered state '%s'", st);
        cJSON_Delete(o);
        ts_http_free(&r);
    }
    get_path(path, sizeof path, id, "");
    o = ts_wait_done(&srv, id, 30);
    assert_string_equal(ts_json_str(o, "state"), "cancelled");
    cJSON_Delete(o);
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200); /* still there */
    ts_http_free(&r);
}

/* Two jobs render at once (the default allows 4); cancel keeps the pixels. */
static void test_two_jobs_at_once_and_cancel(void **state)
{
    (void)state;
    char *doc = scene(64, 64, 1000000, NULL);
    char a[32], b[32];
    ts_submit(&srv, doc, a, sizeof a);
    ts_submit(&srv, doc, b, sizeof b);
    ts_wait_field(&srv, a, "spp_done", 2, 20);
    ts_wait_field(&srv, b, "spp_done", 2, 20);
    char path[160];
    get_path(path, sizeof path, a, "");
    cJSON *o = ts_http_json(&srv, path, 200);
    assert_string_equal(ts_json_str(o, "state"), "running");
    cJSON_Delete(o);
    cancel(a);
    cancel(b);
    o = ts_wait_done(&srv, a, 20);
    assert_string_equal(ts_json_str(o, "state"), "cancelled");
    assert_string_equal(ts_json_str(o, "halt_reason"), "cancelled");
    int spp = (int)ts_json_num(o, "spp_done");
    assert_true(spp >= 2 && spp < 1000000);
    cJSON_Delete(o);
    o = ts_wait_done(&srv, b, 20);
    assert_string_equal(ts_json_str(o, "state"), "cancelled");
    cJSON_Delete(o);
    /* The pixels stay: every pixel has at least spp_done samples. */
    http_resp r;
    get_path(path, sizeof path, a, "/image.exr");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    ts_image img;
    decode_exr(&r, &img);
    ts_http_free(&r);
    int cc = ts_image_channel(&img, "count");
    for (int i = 0; i < 64 * 64; i++) assert_true(img.data[i * img.n_channels + cc] >= (float)spp);
    ts_image_fini(&img);
    free(doc);
}

/* Halting on the time limit and on the target error. */
/* Issue #32.2: the history's spp is one quantity at every kind of point, the status's
 * spp_mean (samples held ÷ pixels), so it never decreases, and its last point is the
 * finished job's spp_mean. A time limit stops tiles one pass apart, where spp_done (what
 * the done point carried) is below the ticks' fractional spp. */
static void assert_spp_series(const char *id, const cJSON *status)
{
    double mean = ts_json_num(status, "spp_mean");
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(status, "spp_mean")) && mean >= ts_json_num(status, "spp_done"));
    char path[160];
    get_path(path, sizeof path, id, "/history");
    cJSON *o = ts_http_json(&srv, path, 200);
    const cJSON *pt;
    double last = 0;
    int n = 0;
    cJSON_ArrayForEach(pt, cJSON_GetObjectItem(o, "points"))
    {
        double spp = ts_json_num(pt, "spp");
        if (spp < last) fail_msg("job %s: history spp went back from %g to %g (%s point %d)", id, last, spp,
                                 ts_json_str(pt, "kind"), n);
        last = spp, n++;
    }
    assert_true(n >= 2);
    if (last != mean) fail_msg("job %s: the history ends at %g spp, the status's spp_mean is %g", id, last, mean);
    cJSON_Delete(o);
}

static void test_time_limit_and_target_error(void **state)
{
    (void)state;
    char *doc = scene(64, 64, 1000000, "\"time_limit_s\":0.6");
    char id[32];
    ts_submit(&srv, doc, id, sizeof id);
    cJSON *o = ts_wait_done(&srv, id, 20);
    assert_string_equal(ts_json_str(o, "halt_reason"), "time_limit");
    assert_spp_series(id, o);
    double el = ts_json_num(o, "elapsed_s");
    /* The last pass is shrunk to fit the measured speed: a small overshoot at most. */
    assert_true(el >= 0.6 && el < 1.6);
    cJSON_Delete(o);
    free(doc);

    doc = scene(64, 64, 1000000, "\"target_error\":0.05");
    ts_submit(&srv, doc, id, sizeof id);
    o = ts_wait_done(&srv, id, 30);
    assert_string_equal(ts_json_str(o, "halt_reason"), "target_error");
    assert_true(ts_json_num(o, "error_estimate") <= 0.05);
    assert_true(ts_json_num(o, "progress") == 1); /* halted by its bound: done, not a 0.0004 bar */
    assert_true(ts_json_num(o, "spp_done") >= 4 && ts_json_num(o, "spp_done") < 1000000);
    cJSON_Delete(o);
    free(doc);
}

/* Progress and ETA while a job renders, 1 and 0 once it ends; the convergence series:
 * one point per pass end (spp doubling), ticks in between, and a final one. */
static void test_progress_eta_and_history(void **state)
{
    (void)state;
    char *doc = scene(64, 64, 1024, NULL);
    char id[32], path[160];
    ts_submit(&srv, doc, id, sizeof id);
    ts_wait_field(&srv, id, "spp_done", 4, 20);
    get_path(path, sizeof path, id, "");
    cJSON *o = ts_http_json(&srv, path, 200);
    double progress = ts_json_num(o, "progress");
    const cJSON *eta = cJSON_GetObjectItem(o, "eta_s");
    /* 4 of 1024 spp: progress is the samples held (≥ 4/1024), ETA a positive guess. */
    assert_true(progress >= 4.0 / 1024 && progress < 0.5);
    assert_true(cJSON_IsNumber(eta) && eta->valuedouble > 0);
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(o, "error_estimate")));
    cJSON_Delete(o);
    cJSON_Delete(ts_wait_done(&srv, id, 60));
    o = ts_http_json(&srv, path, 200);
    assert_true(ts_json_num(o, "progress") == 1);
    assert_true(ts_json_num(o, "eta_s") == 0);
    cJSON_Delete(o);
    get_path(path, sizeof path, id, "/history");
    o = ts_http_json(&srv, path, 200);
    const cJSON *pts = cJSON_GetObjectItem(o, "points"), *pt;
    double last_pass = 0, last_t = -1;
    int passes = 0, done = 0;
    cJSON_ArrayForEach(pt, pts)
    {
        const char *kind = ts_json_str(pt, "kind");
        double spp = ts_json_num(pt, "spp"), t = ts_json_num(pt, "elapsed_s");
        assert_true(t >= last_t);
        last_t = t;
        if (!strcmp(kind, "pass")) {
            assert_true(spp == (last_pass ? 2 * last_pass : 1)); /* 1, 2, 4, … */
            last_pass = spp;
            passes++;
            /* one sample gives no variance: no estimate at 1 spp */
            if (spp == 1) assert_true(cJSON_IsNull(cJSON_GetObjectItem(pt, "error_estimate")));
            else assert_true(ts_json_num(pt, "error_estimate") > 0);
        } else if (!strcmp(kind, "done")) {
            assert_true(spp == 1024);
            done++;
        }
    }
    assert_int_equal(passes, 10); /* pass ends 1 … 512; 1024 is the end */
    assert_int_equal(done, 1);
    cJSON_Delete(o);
    get_path(path, sizeof path, id, "");
    o = ts_http_json(&srv, path, 200);
    assert_spp_series(id, o);
    cJSON_Delete(o);
    free(doc);
}

/* One log line per job event, as JSON lines with --log-format json, and every request at
 * --log-level debug; the default text format names the same events. */
static void test_job_event_log(void **state)
{
    (void)state;
    test_server one;
    const char *args[] = {"--threads", "2", "--log-format", "json", "--log-level", "debug", NULL};
    ts_server_start(&one, args);
    char *doc = scene(32, 32, 8, "\"name\":\"log \\\"test\\\"\\nline\"");
    char id[32];
    ts_submit(&one, doc, id, sizeof id);
    cJSON_Delete(ts_wait_done(&one, id, 20));
    /* The job shows done just before its on_done writes job.finished: wait for the line. */
    char line[4096];
    bool seen = false;
    for (int k = 0; k < 500 && !seen; k++) {
        FILE *f = fopen(one.log, "r");
        assert_non_null(f);
        while (!seen && fgets(line, sizeof line, f)) seen = strstr(line, "\"job.finished\"") != NULL;
        fclose(f);
        if (!seen) ts_sleep_ms(10);
    }
    assert_true(seen);
    FILE *f = fopen(one.log, "r");
    assert_non_null(f);
    int submitted = 0, started = 0, passes = 0, finished = 0, requests = 0;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "{", 1)) continue; /* start-up notes are plain sentences */
        cJSON *o = cJSON_Parse(line);
        if (!o) fail_msg("not a JSON line: %s", line);
        const char *ev = ts_json_str(o, "event");
        assert_non_null(cJSON_GetObjectItem(o, "time"));
        const cJSON *jid = cJSON_GetObjectItem(o, "id");
        bool mine = cJSON_IsString(jid) && !strcmp(jid->valuestring, id);
        if (!strcmp(ev, "job.submitted") && mine) {
            submitted++;
            assert_string_equal(ts_json_str(o, "name"), "log \"test\"\nline"); /* escaped, one line */
        }
        if (!strcmp(ev, "job.started") && mine) started++;
        if (!strcmp(ev, "job.pass") && mine) passes++;
        if (!strcmp(ev, "job.finished") && mine) {
            finished++;
            assert_true(ts_json_num(o, "spp") == 8);
            assert_string_equal(ts_json_str(o, "halt"), "spp");
            assert_true(cJSON_IsNumber(cJSON_GetObjectItem(o, "error_estimate")));
        }
        if (!strcmp(ev, "http.request")) {
            requests++;
            assert_true(ts_json_num(o, "status") >= 200);
        }
        cJSON_Delete(o);
    }
    fclose(f);
    assert_int_equal(ts_server_stop(&one, SIGTERM), 0);
    assert_int_equal(submitted, 1);
    assert_int_equal(started, 1);
    assert_int_equal(passes, 3); /* pass ends 1, 2, 4; 8 is the end */
    assert_int_equal(finished, 1);
    assert_true(requests >= 2); /* the POST and the status polls */
    free(doc);
}

/* A two-sided mirror sphere seen from inside: every sample bounces 65535 times (about 0.1
 * s of one core each here), so one tile pass takes minutes. */
static void expect(const test_server *s, const char *method, const char *path, const char *body, long status,
                   const char *in_body);

static char *mirror_scene(int w, int h, int spp, const char *job)
{
    char *s = malloc(1024);
    snprintf(s, 1024,
             "{\"tessera\":1,\"name\":\"mirror\",\"camera\":{\"from\":[0,0,0],\"to\":[0,0,-1],\"fov\":60},"
             "\"film\":{\"width\":%d,\"height\":%d},\"sampler\":{\"spp\":%d},"
             "\"integrator\":{\"type\":\"path\",\"max_depth\":65535,\"rr_depth\":65535},"
             "\"materials\":{\"m\":{\"type\":\"mirror\"}},"
             "\"shapes\":[{\"type\":\"sphere\",\"radius\":10,\"material\":\"m\",\"two_sided\":true}],"
             "\"lights\":[{\"type\":\"point\",\"position\":[0,1,0],\"intensity\":1}]%s%s%s}",
             w, h, spp, job ? ",\"job\":{" : "", job ? job : "", job ? "}" : "");
    return s;
}

static double mono_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Until the job's state is `state` (polled every 2 ms); returns the seconds it took. */
static double wait_state(const test_server *s, const char *id, const char *state, double timeout_s)
{
    char path[160];
    get_path(path, sizeof path, id, "");
    double t0 = mono_s();
    for (;;) {
        cJSON *o = ts_http_json(s, path, 200);
        bool there = !strcmp(ts_json_str(o, "state"), state);
        cJSON_Delete(o);
        if (there) return mono_s() - t0;
        if (mono_s() - t0 > timeout_s) fail_msg("job %s: not %s after %g s", id, state, timeout_s);
        ts_sleep_ms(2);
    }
}

/* The target for a cancel, a time limit or a shutdown to take effect is 100 ms; the
 * assertions allow 1 s for a loaded 2-core machine (before stops inside tiles, the mirror
 * sphere's cancel took 55–110 s). */
#define STOP_BOUND_S 1.0

/* Cancel, the time limit and SIGTERM take effect inside a tile (even inside one sample),
 * and nothing of the interrupted tile is published; --max-work refuses a job asking for
 * more rays than it allows. */
static void test_stops_inside_a_sample_and_max_work(void **state)
{
    (void)state;
    char *doc = mirror_scene(64, 32, 16, NULL), id[32], path[160];
    ts_submit(&srv, doc, id, sizeof id);
    free(doc);
    wait_state(&srv, id, "running", 10);
    ts_sleep_ms(100);
    double t0 = mono_s();
    cancel(id);
    wait_state(&srv, id, "cancelled", 30);
    double took = mono_s() - t0;
    if (took > STOP_BOUND_S) fail_msg("cancelling the mirror sphere took %.3f s", took);
    get_path(path, sizeof path, id, "");
    cJSON *o = ts_http_json(&srv, path, 200);
    assert_int_equal((int)ts_json_num(o, "spp_done"), 0);
    assert_int_equal((int)ts_json_num(o, "samples"), 0);
    cJSON_Delete(o);
    http_resp r;
    get_path(path, sizeof path, id, "/image.exr");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    ts_image img;
    decode_exr(&r, &img);
    ts_http_free(&r);
    int cc = ts_image_channel(&img, "count");
    for (int i = 0; i < 64 * 32; i++) assert_true(img.data[i * img.n_channels + cc] == 0);
    ts_image_fini(&img);

    doc = mirror_scene(64, 32, 16, "\"time_limit_s\":0.3");
    ts_submit(&srv, doc, id, sizeof id);
    free(doc);
    o = ts_wait_done(&srv, id, 30);
    assert_string_equal(ts_json_str(o, "halt_reason"), "time_limit");
    assert_true(ts_json_num(o, "elapsed_s") >= 0.3 && ts_json_num(o, "elapsed_s") < 0.3 + STOP_BOUND_S);
    cJSON_Delete(o);

    /* --max-work: 64 × 32 pixels × 16 spp × 131071 rays a sample is 4.3e9 rays. */
    test_server small;
    const char *args[] = {"--threads", "2", "--max-work", "1e8", NULL};
    ts_server_start(&small, args);
    doc = mirror_scene(64, 32, 16, NULL);
    expect(&small, "POST", "/api/v1/jobs", doc, 422, "--max-work");
    free(doc);
    doc = mirror_scene(8, 8, 1, NULL); /* 8.4e6 rays: accepted */
    ts_submit(&small, doc, id, sizeof id);
    free(doc);
    wait_state(&small, id, "running", 10);
    ts_sleep_ms(100);
    t0 = mono_s();
    assert_int_equal(ts_server_stop(&small, SIGTERM), 0);
    took = mono_s() - t0;
    if (took > STOP_BOUND_S) fail_msg("SIGTERM during the mirror sphere took %.3f s to exit", took);
}

/* Priority, then arrival: with one running slot, a blocker runs; then a low-priority job
 * and a high-priority one queue; the high one starts first although it came later. */
static void test_priority_order(void **state)
{
    (void)state;
    test_server one;
    const char *args[] = {"--threads", "2", "--max-running", "1", "--max-spp", "4000000", NULL};
    ts_server_start(&one, args);
    char *blocker = scene(64, 64, 1000000, "\"priority\":9");
    char *low = scene(64, 64, 64, "\"priority\":0");
    char *high = scene(64, 64, 64, "\"priority\":5");
    char b[32], l[32], h[32];
    ts_submit(&one, blocker, b, sizeof b);
    ts_wait_field(&one, b, "spp_done", 1, 20);
    ts_submit(&one, low, l, sizeof l);
    ts_submit(&one, high, h, sizeof h);
    char path[160];
    get_path(path, sizeof path, h, "");
    cJSON *o = ts_http_json(&one, path, 200);
    assert_string_equal(ts_json_str(o, "state"), "queued");
    cJSON_Delete(o);
    get_path(path, sizeof path, b, "/cancel");
    http_resp r;
    ts_http(&one, "POST", path, NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    cJSON *ol = ts_wait_done(&one, l, 30), *oh = ts_wait_done(&one, h, 30);
    /* Low was submitted first but waited longer: it started after high finished. */
    assert_true(ts_json_num(ol, "queued_s") > ts_json_num(oh, "queued_s") + ts_json_num(oh, "elapsed_s") * 0.5);
    assert_string_equal(ts_json_str(oh, "state"), "done");
    cJSON_Delete(ol);
    cJSON_Delete(oh);
    free(blocker);
    free(low);
    free(high);
    assert_int_equal(ts_server_stop(&one, SIGTERM), 0);
}

static void expect(const test_server *s, const char *method, const char *path, const char *body, long status,
                   const char *in_body)
{
    http_resp r;
    ts_http(s, method, path, body, body ? strlen(body) : 0, NULL, &r);
    if (r.status != status) fail_msg("%s %s: %ld, expected %ld: %s", method, path, r.status, status, r.body);
    if (in_body && !strstr(r.body, in_body)) fail_msg("%s %s: '%s' not in '%s'", method, path, in_body, r.body);
    ts_http_free(&r);
}

/* Every bad-request class, then the server is still healthy. */
/* Every error reply has the one error body: {"error": a sentence, "status": the reply's status}. */
static void assert_error_body(const http_resp *r)
{
    cJSON *o = cJSON_Parse(r->body);
    assert_non_null(o);
    const cJSON *e = cJSON_GetObjectItemCaseSensitive(o, "error"), *st = cJSON_GetObjectItemCaseSensitive(o, "status");
    assert_true(cJSON_IsString(e) && e->valuestring[0]);
    assert_true(cJSON_IsNumber(st));
    assert_int_equal((long)st->valuedouble, r->status);
    cJSON_Delete(o);
}

static void test_bad_requests(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--max-body", "4096", "--max-pixels", "20000", "--max-spp", "1000", NULL};
    ts_server_start(&s, args);
    expect(&s, "POST", "/api/v1/jobs", "{\"tessera\":1,\n \"camera\": [1,", 400, "line 2");
    char *doc = scene(32, 32, 4, NULL);
    char *bad = strstr(doc, "\"radius\":0.6");
    memcpy(bad, "\"radius\":-.6", 12);
    expect(&s, "POST", "/api/v1/jobs", doc, 400, "shapes[0].radius");
    free(doc);
    char big[8192];
    memset(big, ' ', sizeof big - 1);
    big[0] = '{';
    big[sizeof big - 2] = '}';
    big[sizeof big - 1] = '\0';
    expect(&s, "POST", "/api/v1/jobs", big, 413, "limit");
    doc = scene(200, 200, 4, NULL);
    expect(&s, "POST", "/api/v1/jobs", doc, 422, "film");
    free(doc);
    doc = scene(32, 32, 5000, NULL);
    expect(&s, "POST", "/api/v1/jobs", doc, 422, "spp");
    free(doc);
    doc = scene(32, 32, 4, "\"spp\":5000");
    expect(&s, "POST", "/api/v1/jobs", doc, 422, "job.spp");
    free(doc);
    expect(&s, "POST", "/api/v1/jobs", "", 400, "empty");
    expect(&s, "GET", "/api/v1/nothing", NULL, 404, "no such");
    expect(&s, "GET", "/api/v1/jobs/0123456789abcdef", NULL, 404, "no job");
    expect(&s, "GET", "/api/v1/jobs/0123456789abcdef/image.exr", NULL, 404, "no job");
    http_resp r;
    ts_http(&s, "PUT", "/api/v1/jobs", "{}", 2, NULL, &r);
    assert_int_equal(r.status, 405);
    assert_non_null(strstr(r.headers, "Allow: GET, HEAD, POST"));
    assert_error_body(&r);
    ts_http_free(&r);
    ts_http(&s, "POST", "/healthz", "{}", 2, NULL, &r);
    assert_int_equal(r.status, 405);
    assert_non_null(strstr(r.headers, "Allow:"));
    assert_null(strstr(r.headers, "Access-Control-Allow-Origin")); /* no CORS unless configured */
    ts_http_free(&r);
    expect(&s, "GET", "/healthz", NULL, 200, "ok");
    /* Metrics count requests by route and status. */
    expect(&s, "GET", "/metrics", NULL, 200, "tessera_http_requests_total{route=\"/api/v1/jobs\",status=\"422\"} 3");
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

static void test_auth(void **state)
{
    (void)state;
    test_server s;
    const char *args[] = {"--threads", "1", "--token", "s3cret", "--cors-origin", "https://example.org", NULL};
    ts_server_start(&s, args);
    http_resp r;
    ts_http(&s, "GET", "/api/v1/jobs", NULL, 0, NULL, &r);
    assert_int_equal(r.status, 401);
    assert_non_null(strstr(r.headers, "WWW-Authenticate: Bearer"));
    assert_error_body(&r);
    ts_http_free(&r);
    ts_http(&s, "GET", "/api/v1/jobs", NULL, 0, "Authorization: Bearer wrong", &r);
    assert_int_equal(r.status, 401);
    ts_http_free(&r);
    ts_http(&s, "GET", "/api/v1/jobs", NULL, 0, "Authorization: Bearer s3cret", &r);
    assert_int_equal(r.status, 200);
    assert_non_null(strstr(r.headers, "Access-Control-Allow-Origin: https://example.org"));
    ts_http_free(&r);
    ts_http(&s, "GET", "/api/v1/jobs?access_token=s3cret", NULL, 0, NULL, &r);
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    ts_http(&s, "GET", "/metrics", NULL, 0, NULL, &r);
    assert_int_equal(r.status, 401);
    ts_http_free(&r);
    ts_http(&s, "GET", "/healthz", NULL, 0, NULL, &r); /* liveness needs no token */
    assert_int_equal(r.status, 200);
    ts_http_free(&r);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
}

/* 200 clients hold event streams of a rendering job; the server keeps answering. */
static void test_200_concurrent_clients(void **state)
{
    (void)state;
    char *doc = scene(64, 64, 1000000, NULL);
    char id[32], path[256];
    ts_submit(&srv, doc, id, sizeof id);
    free(doc);
    CURLM *m = curl_multi_init();
    enum { N = 200 };
    CURL *e[N];
    snprintf(path, sizeof path, "%s/api/v1/jobs/%s/events", srv.base, id);
    FILE *null = fopen("/dev/null", "w");
    for (int i = 0; i < N; i++) {
        e[i] = curl_easy_init();
        curl_easy_setopt(e[i], CURLOPT_URL, path);
        curl_easy_setopt(e[i], CURLOPT_WRITEDATA, null);
        curl_multi_add_handle(m, e[i]);
    }
    /* Drive the multi handle until every stream is connected and got data. */
    int running = 0;
    double t0 = ts_now_seconds();
    long connected = 0;
    while (ts_now_seconds() - t0 < 10) {
        curl_multi_perform(m, &running);
        int numfds;
        curl_multi_poll(m, NULL, 0, 50, &numfds);
        connected = 0;
        for (int i = 0; i < N; i++) {
            long code = 0;
            curl_easy_getinfo(e[i], CURLINFO_RESPONSE_CODE, &code);
            connected += code == 200;
        }
        if (connected == N) break;
    }
    assert_int_equal(connected, N);
    assert_int_equal(running, N);
    /* Meanwhile: health, status and an image answer promptly. */
    double t1 = ts_now_seconds();
    int n_req = 0;
    for (int k = 0; k < 50; k++, n_req++) {
        expect(&srv, "GET", "/healthz", NULL, 200, "ok");
        curl_multi_perform(m, &running);
    }
    snprintf(path, sizeof path, "/api/v1/jobs/%s", id);
    expect(&srv, "GET", path, NULL, 200, "running");
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.png", id);
    expect(&srv, "GET", path, NULL, 200, NULL);
    double dt = ts_now_seconds() - t1;
    print_message("50 health checks + status + PNG with %d open streams: %.3f s\n", N, dt);
    assert_true(dt < 5);
    cancel(id);
    /* Every stream ends after done. */
    t0 = ts_now_seconds();
    while (running > 0 && ts_now_seconds() - t0 < 20) {
        curl_multi_perform(m, &running);
        int numfds;
        curl_multi_poll(m, NULL, 0, 50, &numfds);
    }
    assert_int_equal(running, 0);
    for (int i = 0; i < N; i++) {
        curl_multi_remove_handle(m, e[i]);
        curl_easy_cleanup(e[i]);
    }
    curl_multi_cleanup(m);
    fclose(null);
}

/* A finished server job's EXR equals `tessera render` of the same scene and spp: every
 * channel bit for bit, every attribute but the render time. */
static void test_cli_server_identity(void **state)
{
    (void)state;
    char *doc = scene(72, 40, 12, NULL);
    char id[32], path[160];
    ts_submit(&srv, doc, id, sizeof id);
    cJSON *o = ts_wait_done(&srv, id, 30);
    cJSON_Delete(o);
    http_resp r;
    get_path(path, sizeof path, id, "/image.exr");
    ts_http(&srv, "GET", path, NULL, 0, NULL, &r);
    ts_image a, b;
    decode_exr(&r, &a);
    ts_http_free(&r);

    char dir[] = "/tmp/tessera-ident-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char scene_path[256], out[256];
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    snprintf(out, sizeof out, "%s/cli.exr", dir);
    FILE *f = fopen(scene_path, "w");
    fputs(doc, f);
    fclose(f);
    pid_t pid = fork();
    if (pid == 0) {
        int nul = open("/dev/null", O_WRONLY);
        dup2(nul, 2);
        execl(getenv("TS_BINARY"), getenv("TS_BINARY"), "render", scene_path, "-o", out, "--quiet", "--threads", "3",
              (char *)NULL);
        _exit(127);
    }
    int status;
    waitpid(pid, &status, 0);
    assert_int_equal(WEXITSTATUS(status), 0);
    ts_error err = {0};
    if (ts_exr_read(out, &b, &err)) fail_msg("%s", err.message);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    assert_int_equal(a.n_channels, b.n_channels);
    for (int c = 0; c < a.n_channels; c++) assert_string_equal(a.channel_names[c], b.channel_names[c]);
    assert_memory_equal(a.data, b.data, sizeof(float) * (size_t)a.width * a.height * a.n_channels);
    for (int i = 0; i < b.n_attrs; i++) {
        const ts_image_attr *x = &b.attrs[i], *y = ts_image_attr_find(&a, x->name);
        if (!strcmp(x->name, "tessera_render_time_s")) continue;
        if (!y) fail_msg("the server's EXR lacks attribute %s", x->name);
        assert_int_equal(x->type, y->type);
        if (x->type == TS_ATTR_STRING) assert_string_equal(x->s, y->s);
        else if (x->type == TS_ATTR_INT) assert_int_equal(x->i, y->i);
        else assert_memory_equal(&x->d, &y->d, sizeof x->d);
    }
    ts_image_fini(&a);
    ts_image_fini(&b);
    unlink(out);
    unlink(scene_path);
    rmdir(dir);
    free(doc);
}

/* A media scene whose every camera ray's walk is cut at the step bound (media/medium.h):
 * the camera sits in a grid medium whose density is 0 over the half x < 0.5 of its unit
 * box and 1 beyond, majorant σt·1 = 1e7 per unit, and looks along −z through the empty
 * half (a 1° field of view around x = 0.25): delta tracking rejects every tentative
 * collision, and crossing the box takes about 1e7 of them, past the bound of 2^20. So each
 * of the 4 × 4 × 1 samples ends in exactly one cut walk of exactly 2^20 steps. */
static const char walk_cut_scene[] =
    "{\"tessera\":1,\"name\":\"walk-cut\",\"camera\":{\"from\":[0.25,0.5,3],\"to\":[0.25,0.5,0],\"fov\":1,"
    "\"medium\":\"g\"},\"film\":{\"width\":4,\"height\":4,\"filter\":{\"type\":\"box\"}},"
    "\"sampler\":{\"type\":\"independent\",\"spp\":1,\"seed\":3},\"integrator\":{\"type\":\"volpath\",\"max_depth\":5},"
    "\"media\":{\"g\":{\"type\":\"grid\",\"sigma_a\":[1e7,1e7,1e7],\"sigma_s\":[0,0,0],\"nx\":4,\"ny\":1,\"nz\":1,"
    "\"density\":[0,0,0,1]}},\"lights\":[{\"type\":\"infinite\",\"radiance\":1}]}";

/* An EXR attribute's number (double attributes), failing when it is absent. */
static double exr_number(const ts_image *img, const char *name)
{
    const ts_image_attr *a = ts_image_attr_find(img, name);
    if (!a) fail_msg("the EXR lacks attribute %s", name);
    return a->type == TS_ATTR_INT ? a->i : a->d;
}

/* The walk-cut counters (integrators/counters.h) are reported like the other counters: in
 * the job's status (medium_steps, walks_truncated), its EXR's attributes, and `tessera
 * render`'s summary and EXR, the same figures; a scene without media writes no such
 * attribute. */
static void test_media_walk_counters(void **state)
{
    (void)state;
    const double walks = 16, steps = 16.0 * (1u << 20);
    char id[32];
    ts_submit(&srv, walk_cut_scene, id, sizeof id);
    cJSON *o = ts_wait_done(&srv, id, 60);
    assert_string_equal(ts_json_str(o, "state"), "done");
    assert_true(ts_json_num(o, "walks_truncated") == walks);
    assert_true(ts_json_num(o, "medium_steps") == steps);
    assert_int_equal((int)ts_json_num(o, "nonfinite_samples"), 0);
    cJSON_Delete(o);
    ts_image a;
    ts_job_exr(&srv, id, &a);
    assert_true(exr_number(&a, "tessera_walks_truncated") == walks);
    assert_true(exr_number(&a, "tessera_medium_steps") == steps);
    ts_image_fini(&a);

    char dir[] = "/tmp/tessera-walks-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char scene_path[256], out[256], log[256];
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    snprintf(out, sizeof out, "%s/cli.exr", dir);
    snprintf(log, sizeof log, "%s/stderr.txt", dir);
    FILE *f = fopen(scene_path, "w");
    fputs(walk_cut_scene, f);
    fclose(f);
    pid_t pid = fork();
    if (pid == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 2);
        execl(getenv("TS_BINARY"), getenv("TS_BINARY"), "render", scene_path, "-o", out, "--threads", "2",
              (char *)NULL);
        _exit(127);
    }
    int status;
    waitpid(pid, &status, 0);
    assert_int_equal(WEXITSTATUS(status), 0);
    char text[4096] = "";
    f = fopen(log, "r");
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = 0;
    fclose(f);
    if (!strstr(text, "media: 16777216 tracking steps, 16 walks cut short"))
        fail_msg("the summary does not report the cut walks:\n%s", text);
    ts_image b;
    ts_error err = {0};
    if (ts_exr_read(out, &b, &err)) fail_msg("%s", err.message);
    assert_true(exr_number(&b, "tessera_walks_truncated") == walks);
    assert_true(exr_number(&b, "tessera_medium_steps") == steps);
    ts_image_fini(&b);
    unlink(out);
    unlink(log);
    unlink(scene_path);
    rmdir(dir);

    /* Without media: neither attribute, and zero in the status. */
    char *doc = scene(16, 16, 1, NULL);
    ts_submit(&srv, doc, id, sizeof id);
    o = ts_wait_done(&srv, id, 30);
    assert_true(ts_json_num(o, "walks_truncated") == 0);
    cJSON_Delete(o);
    ts_job_exr(&srv, id, &a);
    assert_null(ts_image_attr_find(&a, "tessera_walks_truncated"));
    assert_null(ts_image_attr_find(&a, "tessera_medium_steps"));
    ts_image_fini(&a);
    free(doc);
}

/* GET /api/v1/jobs in pages: 105 jobs, a default page of 100 with a `next` cursor; pages
 * of 7 followed to the end give every job once, newest first, the last page's `next` null;
 * a cursor still places its page after its job was deleted; bad limits and cursors are 400.
 * A list once built every job's status at once (147 MB with 20 jobs of 7 MiB names). */
static void test_list_pages(void **state)
{
    (void)state;
    enum { JOBS = 105, PAGE = 7 };
    test_server s;
    const char *args[] = {"--threads", "1", NULL};
    ts_server_start(&s, args);
    char *doc = ts_ao_scene("page", 4, 4, 1), ids[JOBS][32];
    for (int i = 0; i < JOBS; i++) ts_submit(&s, doc, ids[i], sizeof ids[i]);
    cJSON *o = ts_http_json(&s, "/api/v1/jobs", 200);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(o, "jobs")), 100);
    assert_true(cJSON_IsString(cJSON_GetObjectItem(o, "next")));
    cJSON_Delete(o);
    char path[200], cursor[64] = "", third[64] = "";
    int seen = 0, pages = 0;
    for (;;) {
        snprintf(path, sizeof path, "/api/v1/jobs?limit=%d%s%s", PAGE, cursor[0] ? "&after=" : "", cursor);
        o = ts_http_json(&s, path, 200);
        const cJSON *jobs = cJSON_GetObjectItem(o, "jobs"), *next = cJSON_GetObjectItem(o, "next");
        int n = cJSON_GetArraySize(jobs);
        assert_true(n >= 1 && n <= PAGE);
        for (int k = 0; k < n; k++, seen++) /* newest first: the submission order reversed */
            assert_string_equal(ts_json_str(cJSON_GetArrayItem(jobs, k), "id"), ids[JOBS - 1 - seen]);
        pages++;
        if (pages == 3) snprintf(third, sizeof third, "%s", cursor);
        if (cJSON_IsNull(next)) {
            cJSON_Delete(o);
            break;
        }
        assert_true(cJSON_IsString(next));
        snprintf(cursor, sizeof cursor, "%s", next->valuestring);
        cJSON_Delete(o);
    }
    assert_int_equal(seen, JOBS);
    assert_int_equal(pages, (JOBS + PAGE - 1) / PAGE);
    /* The cursor of page 3 names the last job of page 2 (index 2·PAGE − 1 from the newest):
     * delete that job, and page 3 is still the same. */
    const char *named = ids[JOBS - 2 * PAGE];
    cJSON_Delete(ts_wait_done(&s, named, 20));
    snprintf(path, sizeof path, "/api/v1/jobs/%s", named);
    expect(&s, "DELETE", path, NULL, 204, NULL);
    snprintf(path, sizeof path, "/api/v1/jobs?limit=%d&after=%s", PAGE, third);
    o = ts_http_json(&s, path, 200);
    assert_string_equal(ts_json_str(cJSON_GetArrayItem(cJSON_GetObjectItem(o, "jobs"), 0), "id"), ids[JOBS - 1 - 2 * PAGE]);
    cJSON_Delete(o);
    static const char *const bad[] = {"limit=0", "limit=1001", "limit=01", "limit=+5", "limit=abc", "limit=",
                                      "after=123", "after=x.abc", "after=1.", "after=01.abc", "after=1.a%2fb"};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        snprintf(path, sizeof path, "/api/v1/jobs?%s", bad[k]);
        expect(&s, "GET", path, NULL, 400, bad[k][0] == 'l' ? "limit" : "after");
    }
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(doc);
}

/* The answer of POST …/cancel and DELETE is the state the job is in after the request
 * (docs/design.md §5, proto/openapi.yaml): a queued job is cancelled at once (nothing of it
 * runs, so "cancelled", not "queued" or "cancelling", even while the only worker is busy);
 * a running one answers "cancelling" or "cancelled"; an ended one is unchanged. DELETE of a
 * job that has not ended is 409 naming its state; of an ended one 204, then 404. */
static const char *post_state(const test_server *s, const char *id, const char *suffix, char *out, size_t n)
{
    char path[160];
    get_path(path, sizeof path, id, suffix);
    http_resp r;
    ts_http(s, "POST", path, NULL, 0, NULL, &r);
    if (r.status != 200) fail_msg("POST %s: %ld %s", path, r.status, r.body);
    cJSON *o = cJSON_Parse(r.body);
    assert_non_null(o);
    snprintf(out, n, "%s", ts_json_str(o, "state"));
    cJSON_Delete(o);
    ts_http_free(&r);
    return out;
}

static void test_cancel_and_delete_answers(void **state)
{
    (void)state;
    test_server one;
    const char *args[] = {"--threads", "1", "--max-running", "1", "--max-spp", "4000000", NULL};
    ts_server_start(&one, args);
    char *blocker = scene(64, 64, 1000000, NULL), *small = scene(16, 16, 4, NULL);
    char b[32], q[32], d[32], path[160], st[32];
    ts_submit(&one, blocker, b, sizeof b);
    ts_wait_field(&one, b, "spp_done", 1, 20);
    ts_submit(&one, small, q, sizeof q);
    get_path(path, sizeof path, q, "");
    expect(&one, "DELETE", path, NULL, 409, "is queued");
    assert_string_equal(post_state(&one, q, "/cancel", st, sizeof st), "cancelled");
    assert_string_equal(post_state(&one, q, "/cancel", st, sizeof st), "cancelled"); /* idempotent */
    cJSON *o = ts_http_json(&one, path, 200);
    assert_string_equal(ts_json_str(o, "state"), "cancelled");
    assert_string_equal(ts_json_str(o, "halt_reason"), "cancelled");
    assert_true(ts_json_num(o, "spp_done") == 0);
    cJSON_Delete(o);
    expect(&one, "DELETE", path, NULL, 204, NULL);
    expect(&one, "GET", path, NULL, 404, NULL);
    /* Running: 409 naming it, then the cancel answers what it will be in. */
    get_path(path, sizeof path, b, "");
    expect(&one, "DELETE", path, NULL, 409, "is running");
    post_state(&one, b, "/cancel", st, sizeof st);
    if (strcmp(st, "cancelling") && strcmp(st, "cancelled")) fail_msg("cancel of a running job answered '%s'", st);
    cJSON_Delete(ts_wait_done(&one, b, 30));
    assert_string_equal(post_state(&one, b, "/cancel", st, sizeof st), "cancelled");
    expect(&one, "DELETE", path, NULL, 204, NULL);
    /* Done: a cancel changes nothing. */
    ts_submit(&one, small, d, sizeof d);
    o = ts_wait_done(&one, d, 30);
    assert_string_equal(ts_json_str(o, "state"), "done");
    cJSON_Delete(o);
    assert_string_equal(post_state(&one, d, "/cancel", st, sizeof st), "done");
    get_path(path, sizeof path, d, "");
    o = ts_http_json(&one, path, 200);
    assert_string_equal(ts_json_str(o, "state"), "done");
    assert_string_equal(ts_json_str(o, "halt_reason"), "spp");
    cJSON_Delete(o);
    expect(&one, "DELETE", path, NULL, 204, NULL);
    expect(&one, "DELETE", path, NULL, 404, NULL);
    free(blocker);
    free(small);
    assert_int_equal(ts_server_stop(&one, SIGTERM), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_submit_stream_and_images),
        cmocka_unit_test(test_two_jobs_at_once_and_cancel),
        cmocka_unit_test(test_time_limit_and_target_error),
        cmocka_unit_test(test_progress_eta_and_history),
        cmocka_unit_test(test_job_event_log),
        cmocka_unit_test(test_stops_inside_a_sample_and_max_work),
        cmocka_unit_test(test_priority_order),
        cmocka_unit_test(test_cancel_and_delete_answers),
        cmocka_unit_test(test_bad_requests),
        cmocka_unit_test(test_auth),
        cmocka_unit_test(test_200_concurrent_clients),
        cmocka_unit_test(test_cli_server_identity),
        cmocka_unit_test(test_media_walk_counters),
        cmocka_unit_test(test_list_pages),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
