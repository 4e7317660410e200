/* server_harness.c — see server_harness.h. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "server_harness.h"

#include "image/exr.h"
#include "image/image.h"

#include <curl/curl.h>
#include <dirent.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

void ts_sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void ts_server_start(test_server *s, const char *const *args)
{
    const char *bin = getenv("TS_BINARY");
    if (!bin) fail_msg("TS_BINARY is not set (run through ctest)");
    static int counter;
    snprintf(s->log, sizeof s->log, "/tmp/tessera-test-server-%d-%d.log", (int)getpid(), counter++);
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    pid_t parent = getpid(), pid = fork();
    if (pid == 0) {
        /* A test that fails before it stops its server (cmocka goes on to the next case)
         * leaves it running at most until the test process ends, not rendering on for
         * the tests after it. */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(127);
        dup2(fds[1], 1);
        close(fds[0]);
        int fd = open(s->log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) dup2(fd, 2);
        char *argv[48];
        int n = 0;
        argv[n++] = (char *)bin;
        argv[n++] = "serve";
        argv[n++] = "--port";
        argv[n++] = "0";
        for (int i = 0; args && args[i] && n < 46; i++) argv[n++] = (char *)args[i];
        argv[n] = NULL;
        execv(bin, argv);
        _exit(127);
    }
    close(fds[1]);
    s->pid = pid;
    char line[256];
    size_t got = 0;
    double t0 = now_s();
    while (got < sizeof line - 1 && now_s() - t0 < 10) {
        struct pollfd p = {fds[0], POLLIN, 0};
        if (poll(&p, 1, 200) <= 0) continue;
        ssize_t r = read(fds[0], line + got, 1);
        if (r <= 0) break;
        got += (size_t)r;
        if (line[got - 1] == '\n') break;
    }
    line[got] = '\0';
    close(fds[0]);
    const char *colon = strrchr(line, ':');
    if (!strstr(line, "listening on") || !colon) fail_msg("the server did not start: '%s' (log %s)", line, s->log);
    s->port = atoi(colon + 1);
    snprintf(s->base, sizeof s->base, "http://127.0.0.1:%d", s->port);
}

int ts_server_stop(test_server *s, int sig)
{
    kill(s->pid, sig);
    int status = 0;
    waitpid(s->pid, &status, 0);
    unlink(s->log); /* kept only when a test fails before stopping its server */
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

typedef struct buf { char *p; size_t n, cap; } buf;

static size_t write_cb(char *data, size_t size, size_t nmemb, void *user)
{
    buf *b = user;
    size_t n = size * nmemb;
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + n + 1) cap *= 2;
        char *q = realloc(b->p, cap);
        if (!q) return 0;
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->n, data, n);
    b->n += n;
    b->p[b->n] = '\0';
    return n;
}

static size_t header_cb(char *data, size_t size, size_t nmemb, void *user)
{
    http_resp *r = user;
    size_t n = size * nmemb, have = strlen(r->headers);
    if (have + n < sizeof r->headers) {
        memcpy(r->headers + have, data, n);
        r->headers[have + n] = '\0';
    }
    return n;
}

/* One request: Content-Type type unless NULL, Content-Encoding enc unless NULL; it fails
 * the test after timeout_s seconds. */
static void request(const test_server *s, const char *method, const char *path, const void *body, size_t len,
                    const char *auth, const char *type, const char *enc, long timeout_s, http_resp *out)
{
    memset(out, 0, sizeof *out);
    CURL *c = curl_easy_init();
    assert_non_null(c);
    char url[512], h_type[160], h_enc[160];
    snprintf(url, sizeof url, "%s%s", s->base, path);
    buf b = {0};
    struct curl_slist *h = NULL;
    if (auth) h = curl_slist_append(h, auth);
    if (type) {
        snprintf(h_type, sizeof h_type, "Content-Type: %s", type);
        h = curl_slist_append(h, h_type);
    }
    if (enc) {
        snprintf(h_enc, sizeof h_enc, "Content-Encoding: %s", enc);
        h = curl_slist_append(h, h_enc);
    }
    h = curl_slist_append(h, "Expect:");
    curl_easy_setopt(c, CURLOPT_URL, url);
    curl_easy_setopt(c, CURLOPT_CUSTOMREQUEST, method);
    if (!strcmp(method, "HEAD")) curl_easy_setopt(c, CURLOPT_NOBODY, 1L);
    if (body) {
        curl_easy_setopt(c, CURLOPT_POSTFIELDS, body);
        curl_easy_setopt(c, CURLOPT_POSTFIELDSIZE_LARGE, (curl_off_t)len);
    }
    curl_easy_setopt(c, CURLOPT_HTTPHEADER, h);
    curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, write_cb);
    curl_easy_setopt(c, CURLOPT_WRITEDATA, &b);
    curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, header_cb);
    curl_easy_setopt(c, CURLOPT_HEADERDATA, out);
    curl_easy_setopt(c, CURLOPT_TIMEOUT, timeout_s);
    CURLcode rc = curl_easy_perform(c);
    if (rc != CURLE_OK) fail_msg("%s %s: %s", method, path, curl_easy_strerror(rc));
    curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &out->status);
    out->body = b.p ? b.p : calloc(1, 1);
    out->len = b.n;
    curl_slist_free_all(h);
    curl_easy_cleanup(c);
}

void ts_http(const test_server *s, const char *method, const char *path, const char *body, size_t len,
             const char *auth, http_resp *out)
{
    request(s, method, path, body, len, auth, body || !strcmp(method, "POST") ? "application/json" : NULL, NULL, 30,
            out);
}

void ts_http_post(const test_server *s, const char *path, const void *body, size_t len, const char *type,
                  const char *enc, http_resp *out)
{
    request(s, "POST", path, body, len, NULL, type, enc, 60, out); /* a bundle is unpacked before the answer */
}

long ts_http_post_body(const test_server *s, const char *path, const void *body, size_t len, const char *type,
                       const char *enc, char **out)
{
    http_resp r;
    ts_http_post(s, path, body, len, type, enc, &r);
    *out = r.body;
    return r.status;
}

int ts_count_entries(const char *folder)
{
    DIR *d = opendir(folder);
    if (!d) return 0;
    int n = 0;
    for (struct dirent *e; (e = readdir(d));) n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return n;
}

void ts_assert_bundles_left(const char *root, int jobs_expected, const char *what)
{
    char p[600];
    snprintf(p, sizeof p, "%s/incoming", root);
    if (ts_count_entries(p)) fail_msg("%s: %d entries left in incoming/", what, ts_count_entries(p));
    snprintf(p, sizeof p, "%s/jobs", root);
    if (ts_count_entries(p) != jobs_expected)
        fail_msg("%s: jobs/ holds %d entries, expected %d", what, ts_count_entries(p), jobs_expected);
}

void ts_http_free(http_resp *r)
{
    free(r->body);
    r->body = NULL;
}

cJSON *ts_http_json(const test_server *s, const char *path, long expect_status)
{
    http_resp r;
    ts_http(s, "GET", path, NULL, 0, NULL, &r);
    if (r.status != expect_status) fail_msg("GET %s: status %ld, expected %ld: %s", path, r.status, expect_status, r.body);
    cJSON *o = cJSON_Parse(r.body);
    ts_http_free(&r);
    assert_non_null(o);
    return o;
}

char *ts_http_stream(const test_server *s, const char *path, double timeout_s)
{
    CURL *c = curl_easy_init();
    char url[512];
    snprintf(url, sizeof url, "%s%s", s->base, path);
    buf b = {0};
    curl_easy_setopt(c, CURLOPT_URL, url);
    curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, write_cb);
    curl_easy_setopt(c, CURLOPT_WRITEDATA, &b);
    curl_easy_setopt(c, CURLOPT_TIMEOUT_MS, (long)(timeout_s * 1000));
    CURLcode rc = curl_easy_perform(c);
    long status = 0;
    curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &status);
    curl_easy_cleanup(c);
    if (rc != CURLE_OK) fail_msg("GET %s: %s after %zu bytes", path, curl_easy_strerror(rc), b.n);
    assert_int_equal(status, 200);
    return b.p ? b.p : calloc(1, 1);
}

void ts_submit(const test_server *s, const char *scene, char *id_out, size_t n)
{
    http_resp r;
    ts_http(s, "POST", "/api/v1/jobs", scene, strlen(scene), NULL, &r);
    if (r.status != 201) fail_msg("POST /api/v1/jobs: %ld %s", r.status, r.body);
    cJSON *o = cJSON_Parse(r.body);
    assert_non_null(o);
    snprintf(id_out, n, "%s", ts_json_str(o, "id"));
    cJSON_Delete(o);
    ts_http_free(&r);
}

cJSON *ts_wait_done(const test_server *s, const char *id, double timeout_s)
{
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/events", id);
    char *text = ts_http_stream(s, path, timeout_s);
    if (!strstr(text, "event: done")) fail_msg("the event stream of %s ended without done", id);
    free(text);
    snprintf(path, sizeof path, "/api/v1/jobs/%s", id);
    return ts_http_json(s, path, 200);
}

double ts_wait_field(const test_server *s, const char *id, const char *field, double value, double timeout_s)
{
    char path[128];
    snprintf(path, sizeof path, "/api/v1/jobs/%s", id);
    double t0 = now_s(), v = -1;
    while (now_s() - t0 < timeout_s) {
        cJSON *o = ts_http_json(s, path, 200);
        v = ts_json_num(o, field);
        cJSON_Delete(o);
        if (v >= value) return v;
        ts_sleep_ms(20);
    }
    fail_msg("job %s: %s stayed at %g, below %g, for %g s", id, field, v, value, timeout_s);
    return v;
}

double ts_json_num(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(v) ? v->valuedouble : -1;
}

const char *ts_json_str(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(v) ? v->valuestring : "";
}

char *ts_ao_scene(const char *name, int w, int h, int spp)
{
    char *s = malloc(2048);
    if (!s) fail_msg("out of memory");
    snprintf(s, 2048,
             "{\"tessera\":1,\"name\":\"%s\",\"camera\":{\"from\":[0,1.5,5],\"to\":[0,0.6,0],\"fov\":35},"
             "\"film\":{\"width\":%d,\"height\":%d,\"filter\":{\"type\":\"box\"}},"
             "\"sampler\":{\"spp\":%d},\"integrator\":{\"type\":\"ao\"},"
             "\"materials\":{\"w\":{\"type\":\"diffuse\"}},"
             "\"shapes\":[{\"type\":\"sphere\",\"center\":[0,0.6,0],\"radius\":0.6,\"material\":\"w\"},"
             "{\"type\":\"mesh\",\"positions\":[-5,0,-5, 5,0,-5, 5,0,5, -5,0,5],\"indices\":[0,2,1, 0,3,2],"
             "\"material\":\"w\"}]}",
             name, w, h, spp);
    return s;
}

void ts_job_exr(const test_server *s, const char *id, ts_image *out)
{
    char path[160];
    snprintf(path, sizeof path, "/api/v1/jobs/%s/image.exr", id);
    http_resp r;
    ts_http(s, "GET", path, NULL, 0, NULL, &r);
    if (r.status != 200) fail_msg("GET %s: %ld %s", path, r.status, r.body ? r.body : "");
    ts_error err = {0};
    if (ts_exr_read_memory((const unsigned char *)r.body, r.len, out, &err)) fail_msg("%s: %s", path, err.message);
    ts_http_free(&r);
}
