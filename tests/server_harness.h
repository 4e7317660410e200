/* server_harness.h — `tessera serve` as the server tests see it: the real binary on a
 * loopback port chosen by the kernel (--port 0, read back from its first stdout line),
 * driven over HTTP with libcurl. */
#ifndef TS_SERVER_HARNESS_H
#define TS_SERVER_HARNESS_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/types.h>

#include <cjson/cJSON.h>

typedef struct test_server {
    pid_t pid;
    int port;
    char base[64];   /* "http://127.0.0.1:PORT" */
    char log[256];   /* the server's stderr */
} test_server;

/* Starts the server with extra args (NULL-terminated); fails the test if it does not
 * print its URL within 10 s. */
void ts_server_start(test_server *s, const char *const *args);
/* Sends sig and waits; returns the exit status (128+sig when killed). */
int ts_server_stop(test_server *s, int sig);

typedef struct http_resp {
    long status;
    char *body;
    size_t len;
    char headers[8192];
} http_resp;

/* One request; body may be NULL. auth: a full "Authorization: …" header line or NULL. */
void ts_http(const test_server *s, const char *method, const char *path, const char *body, size_t len,
             const char *auth, http_resp *out);
/* POSTs len bytes of body to path as Content-Type type (a bundle: application/x-tar, …),
 * with Content-Encoding enc unless NULL. */
void ts_http_post(const test_server *s, const char *path, const void *body, size_t len, const char *type,
                  const char *enc, http_resp *out);
/* ts_http_post, for a status and a body: returns the status, *out the body (caller frees). */
long ts_http_post_body(const test_server *s, const char *path, const void *body, size_t len, const char *type,
                       const char *enc, char **out);
void ts_http_free(http_resp *r);
/* GET path and parse the JSON body (caller deletes); asserts the status. */
cJSON *ts_http_json(const test_server *s, const char *path, long expect_status);

/* GET the job's image.exr and decode it into *out (caller finis it); fails the test on
 * another status or an unreadable file. */
struct ts_image;
void ts_job_exr(const test_server *s, const char *id, struct ts_image *out);
/* Streams the job's events until the server ends the stream (after `done`) or timeout_s;
 * returns the raw text (caller frees). */
char *ts_http_stream(const test_server *s, const char *path, double timeout_s);

/* Submits a scene; returns the job id (static buffer per call site: copy it). */
void ts_submit(const test_server *s, const char *scene, char *id_out, size_t n);
/* Waits (streaming the events) until the job finished; returns its status JSON. */
cJSON *ts_wait_done(const test_server *s, const char *id, double timeout_s);
/* Polls the status every 20 ms until field >= value (numbers) or timeout; returns it. */
double ts_wait_field(const test_server *s, const char *id, const char *field, double value, double timeout_s);

double ts_json_num(const cJSON *o, const char *key);
const char *ts_json_str(const cJSON *o, const char *key);
void ts_sleep_ms(int ms);

/* Entries in folder (0 when it does not exist), "." and ".." aside. */
int ts_count_entries(const char *folder);
/* What bundles leave under root (the server's --data, or its temporary bundle folder):
 * fails the test unless incoming/ is empty and jobs/ holds jobs_expected entries (a
 * refused bundle leaves nothing; an accepted one its job). what names the moment. */
void ts_assert_bundles_left(const char *root, int jobs_expected, const char *what);

/* A small scene document (malloc'd): ambient occlusion of a sphere on a square floor, w×h
 * pixels, spp samples, box filter — quick to render, for tests of jobs and checkpoints. */
char *ts_ao_scene(const char *name, int w, int h, int spp);

#endif
