/* test_server_persist.c — `tessera serve --data DIR`: kill the server mid-job (SIGKILL, so
 * only the periodic checkpoints count; and SIGTERM, which checkpoints on the way out),
 * start it again on the same folder: jobs are listed, unfinished ones resume where they
 * stopped and finish with exactly the target number of samples in every pixel, and
 * finished jobs' images are still served; an adaptive job resumes bit-identical. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <curl/curl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "image/exr.h"
#include "image/image.h"
#include "server_harness.h"

static char data_dir[64];


static void start(test_server *s)
{
    const char *args[] = {"--threads", "2", "--data", data_dir, "--checkpoint-interval", "0.2", NULL};
    ts_server_start(s, args);
}

/* Every pixel of the job's EXR holds exactly `spp` samples. */
static void assert_counts(const test_server *s, const char *id, int w, int h, int spp)
{
    ts_image img;
    ts_job_exr(s, id, &img);
    assert_int_equal(img.width, w);
    assert_int_equal(img.height, h);
    int cc = ts_image_channel(&img, "count");
    for (int i = 0; i < w * h; i++)
        if (img.data[i * img.n_channels + cc] != (float)spp)
            fail_msg("pixel %d has %g samples, expected %d", i, img.data[i * img.n_channels + cc], spp);
    ts_image_fini(&img);
}

static bool file_exists(const char *id, const char *name)
{
    char p[256];
    struct stat sb;
    snprintf(p, sizeof p, "%s/jobs/%s/%s", data_dir, id, name);
    return stat(p, &sb) == 0;
}

static void test_restart_and_resume(void **state)
{
    (void)state;
    test_server s;
    start(&s);
    /* A finished job, then one killed mid-render. */
    char a[32], b[32], path[160];
    char *small = ts_ao_scene("persist", 40, 24, 16), *big = ts_ao_scene("persist", 64, 64, 1024);
    ts_submit(&s, small, a, sizeof a);
    cJSON *o = ts_wait_done(&s, a, 20);
    cJSON_Delete(o);
    ts_submit(&s, big, b, sizeof b);
    ts_wait_field(&s, b, "spp_done", 32, 20);
    /* Wait for a periodic checkpoint (0.2 s) that holds some samples. */
    for (int i = 0; i < 200 && !(file_exists(b, "film.bin") && file_exists(b, "job.json")); i++) ts_sleep_ms(20);
    ts_sleep_ms(300);
    assert_true(file_exists(a, "film.bin"));
    assert_int_equal(ts_server_stop(&s, SIGKILL), 128 + SIGKILL);

    start(&s);
    o = ts_http_json(&s, "/api/v1/jobs", 200);
    cJSON *jobs = cJSON_GetObjectItem(o, "jobs");
    assert_int_equal(cJSON_GetArraySize(jobs), 2);
    assert_string_equal(ts_json_str(cJSON_GetArrayItem(jobs, 0), "id"), b); /* newest first */
    assert_string_equal(ts_json_str(cJSON_GetArrayItem(jobs, 1), "state"), "done");
    double resumed_at = ts_json_num(cJSON_GetArrayItem(jobs, 0), "spp_done");
    cJSON_Delete(o);
    /* Resumed from the checkpoint, not from zero (a 0.2 s interval at most was lost). */
    assert_true(resumed_at >= 8);
    assert_counts(&s, a, 40, 24, 16);
    /* The finished job's convergence series came back with it: passes 1, 2, 4, 8, then done. */
    snprintf(path, sizeof path, "/api/v1/jobs/%s/history", a);
    o = ts_http_json(&s, path, 200);
    const cJSON *pts = cJSON_GetObjectItem(o, "points");
    int n_pts = cJSON_GetArraySize(pts);
    assert_true(n_pts >= 5);
    assert_string_equal(ts_json_str(cJSON_GetArrayItem(pts, n_pts - 1), "kind"), "done");
    assert_true(ts_json_num(cJSON_GetArrayItem(pts, n_pts - 1), "spp") == 16);
    cJSON_Delete(o);
    o = ts_wait_done(&s, b, 60);
    assert_string_equal(ts_json_str(o, "state"), "done");
    assert_int_equal((int)ts_json_num(o, "spp_done"), 1024);
    assert_int_equal((long)ts_json_num(o, "samples"), 64L * 64 * 1024);
    cJSON_Delete(o);
    assert_counts(&s, b, 64, 64, 1024);

    /* SIGTERM checkpoints on the way out: nothing is lost. */
    char c[32];
    ts_submit(&s, big, c, sizeof c);
    ts_wait_field(&s, c, "spp_done", 16, 20);
    snprintf(path, sizeof path, "/api/v1/jobs/%s", c);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    start(&s);
    o = ts_http_json(&s, path, 200);
    assert_true(ts_json_num(o, "spp_done") >= 16);
    cJSON_Delete(o);
    o = ts_wait_done(&s, c, 60);
    assert_int_equal((int)ts_json_num(o, "spp_done"), 1024);
    assert_int_equal((long)ts_json_num(o, "samples"), 64L * 64 * 1024);
    cJSON_Delete(o);
    assert_counts(&s, c, 64, 64, 1024);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(small);
    free(big);
}

/* An adaptive job (job.adaptive, docs/design.md §8) killed past its first checks resumes
 * from its checkpoint's film and active pixels: its image is bit-identical to the same job
 * rendered without a break (colour and per-pixel counts, which differ across the image). */
static void test_adaptive_resume(void **state)
{
    (void)state;
    test_server s;
    start(&s);
    /* 160² pixels: large enough that the job is still rendering when the server is killed
     * (at 64² a quiet machine finished it first, and the job came back "restored"). */
    enum { SIDE = 160 };
    char *doc = ts_ao_scene("adaptive", SIDE, SIDE, 4096);
    size_t n = strlen(doc);
    char *ad = malloc(n + 64);
    assert_non_null(ad);
    snprintf(ad, n + 64, "%.*s,\"job\":{\"adaptive\":true,\"target_error\":0.01}}", (int)(n - 1), doc);
    char a[32], b[32];
    ts_submit(&s, ad, a, sizeof a);
    ts_wait_field(&s, a, "spp_done", 40, 60);
    for (int i = 0; i < 200 && !(file_exists(a, "film.bin") && file_exists(a, "job.json")); i++) ts_sleep_ms(20);
    ts_sleep_ms(300);
    assert_int_equal(ts_server_stop(&s, SIGKILL), 128 + SIGKILL);
    start(&s);
    char path[160];
    snprintf(path, sizeof path, "/api/v1/jobs/%s", a);
    cJSON *o = ts_http_json(&s, path, 200);
    assert_true(ts_json_num(o, "spp_done") >= 16); /* resumed, not from zero */
    assert_null(cJSON_GetObjectItem(o, "checkpoint_error"));
    assert_true(cJSON_IsTrue(cJSON_GetObjectItem(o, "adaptive")));
    cJSON_Delete(o);
    o = ts_wait_done(&s, a, 120);
    assert_string_equal(ts_json_str(o, "halt_reason"), "target_error");
    cJSON_Delete(o);
    ts_submit(&s, ad, b, sizeof b);
    o = ts_wait_done(&s, b, 120);
    cJSON_Delete(o);
    ts_image ia, ib;
    ts_job_exr(&s, a, &ia);
    ts_job_exr(&s, b, &ib);
    const char *names[] = {"R", "G", "B", "count"};
    float least = 1e30f, most = 0;
    for (int k = 0; k < 4; k++) {
        int ca = ts_image_channel(&ia, names[k]), cb = ts_image_channel(&ib, names[k]);
        assert_true(ca >= 0 && cb >= 0);
        for (int i = 0; i < SIDE * SIDE; i++) {
            float va = ia.data[i * ia.n_channels + ca], vb = ib.data[i * ib.n_channels + cb];
            if (memcmp(&va, &vb, sizeof va)) fail_msg("%s of pixel %d: %g resumed, %g uninterrupted", names[k], i, va, vb);
            if (k == 3) least = va < least ? va : least, most = va > most ? va : most;
        }
    }
    assert_true(least == 16 && most > 2 * least); /* the counts do differ */
    ts_image_fini(&ia);
    ts_image_fini(&ib);
    assert_int_equal(ts_server_stop(&s, SIGTERM), 0);
    free(ad);
    free(doc);
}

int main(void)
{
    curl_global_init(CURL_GLOBAL_DEFAULT);
    snprintf(data_dir, sizeof data_dir, "/tmp/tessera-persist-XXXXXX");
    if (!mkdtemp(data_dir)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_restart_and_resume),
        cmocka_unit_test(test_adaptive_resume),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", data_dir);
    if (system(cmd) != 0) rc = rc ? rc : 1;
    curl_global_cleanup();
    return rc;
}
