/* fuzz_http.c — libFuzzer harness: the HTTP layer, through a real in-process server.
 *
 * Design note: the harness starts the server's parts as `tessera serve` does
 * (serve.c: metrics, job store, encoder pool, render scheduler, then the libmicrohttpd
 * daemon of http.c on 127.0.0.1, port 0) with small limits, a bearer token and a CORS
 * origin, and two jobs: a finished 40 × 40 render (2 × 2 tiles) and a job that failed
 * before rendering. Each input is a request, written over a loopback socket; the reply is
 * read to the end (Connection: close) and checked. So method, path, query, headers and
 * body go through the daemon's own code: MHD's parser, the body accumulation and limit of
 * http.c, the routing, authorisation and handlers of api.c, the offloaded encoders, SSE.
 *
 * Input format (text, so seeds are written by hand; tests/fuzz/corpus/http):
 *     METHOD TARGET            the request line (TARGET: path and query)
 *     Name: value              any number of header lines
 *     @chunked                 (optional) send the body with chunked transfer encoding
 *                              (an empty line)
 *     body…                    the rest, sent as the body
 * In all of it @ID@ stands for the finished job's id, @FAILED@ for the failed job's and
 * @TOKEN@ for the token. The harness frames the request itself (Host, Connection: close,
 * Content-Length or chunks, which it drops from the input's headers; bytes that would end
 * a line or a field are percent-encoded in the target and dropped elsewhere), so every
 * request is complete and must be answered.
 *
 * Checks: the reply is HTTP/1.1 with a status 200–599 and a well-framed body; no 5xx
 * (nothing shuts down while fuzzing) but the 503 of a job posted to a server at its job
 * limit (--max-jobs 8), and the store never holds more; a JSON reply parses; an error
 * reply is valid UTF-8, and so is any JSON reply to a request that was (unless a job
 * from a request that was not is in the store: listings show its name); a 2xx from a
 * route behind the token (anything but /, the UI assets and /healthz; OPTIONS preflights
 * excepted) only for a request that carried the token; a 201 names the new job. A reply
 * that does not come within 20 s is a hang. Before the next input, every job a request
 * created renders to its end (or is cancelled after 5 s) and the server is done with the
 * connection, so what an input covers depends little on timing. The server is restarted
 * (so new jobs can be made again) after 32 inputs at its job limit; every 256 inputs,
 * /healthz must answer 200. */
#define _GNU_SOURCE
#include "fuzz_common.h"

#include <arpa/inet.h>
#include <cjson/cJSON.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>

#include "api.h"
#include "http.h"
#include "job_store.h"
#include "metrics.h"
#include "offload.h"
#include "render/scheduler.h"
#include "serve.h"

#define FUZZ_TOKEN       "fz-7Qk2-token"
#define JOB_ID           "5eed0000f1c7a8e0"
#define FAILED_ID        "badc0ffee0ddf00d"
#define MAX_BODY         2048
#define MAX_JOBS         8  /* --max-jobs: a POST beyond it is answered 503 */
#define FULL_INPUTS      32 /* inputs run against a full store before a restart */
#define REPLY_TIMEOUT_MS 20000

static const char fixture_scene[] =
    "{\"tessera\": 1, \"name\": \"fixture\","
    " \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0], \"fov\": 30},"
    " \"film\": {\"width\": 40, \"height\": 40}, \"sampler\": {\"spp\": 2},"
    " \"materials\": {\"m\": {\"type\": \"diffuse\", \"reflectance\": [0.5, 0.5, 0.5]}},"
    " \"shapes\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"material\": \"m\"}],"
    " \"lights\": [{\"type\": \"point\", \"position\": [0, 2, 3], \"intensity\": [5, 5, 5]}]}";

static srv_server g_srv;
static bool g_running;
static int g_port;
static unsigned long g_inputs;
static int g_jobs;        /* in the store before this input */
static int g_full_inputs; /* inputs run while the store was full */
/* A job from a request that was not UTF-8 is in the store: its name may come back in any
 * later listing, so the UTF-8 check is off until the next restart. */
static bool g_store_not_utf8;

/* ------------------------------------------------------------------ the server */

/* Waits up to ms for the job to finish; whether it did. */
static bool wait_finished(srv_job *j, int ms)
{
    if (!j->sj) return true;
    for (int i = 0; i < 10 * ms; i++) {
        ts_job_progress p;
        ts_sched_job_progress(j->sj, &p);
        if (ts_job_state_finished(p.state)) return true;
        struct timespec ts = {0, 100000};
        nanosleep(&ts, NULL);
    }
    return false;
}

/* Lets a job render to its end (so its coverage does not depend on timing), cancelling it
 * if it takes more than 5 s. */
static void settle(srv_job *j)
{
    if (wait_finished(j, 5000)) return;
    ts_sched_job_cancel(j->sj);
    if (wait_finished(j, 20000)) return;
    fprintf(stderr, "fuzz_http: job %s did not finish\n", j->id);
    abort();
}

/* `tessera serve`'s own start-up (srv_server_start), without signals or --data, then two
 * fixture jobs. */
static void server_start(void)
{
    srv_server *srv = &g_srv;
    memset(srv, 0, sizeof *srv);
    srv_config *cfg = &srv->cfg;
    cfg->bind = "127.0.0.1";
    cfg->port = 0;
    cfg->threads = 1;
    cfg->max_running = 2;
    cfg->http_threads = 1;
    cfg->token = FUZZ_TOKEN;
    cfg->cors_origin = "https://ui.example";
    cfg->allowed_hosts = "fuzz"; /* the Host the harness sends */
    cfg->max_body = MAX_BODY;
    cfg->max_jobs = MAX_JOBS;
    cfg->checkpoint_interval_s = 30;
    ts_scene_limits_default(&cfg->limits);
    cfg->limits.max_width = cfg->limits.max_height = 64;
    cfg->limits.max_pixels = 64 * 64;
    cfg->limits.max_spp = 16;
    cfg->limits.max_triangles = 4096;
    cfg->limits.max_shapes = 64;
    cfg->limits.max_file_bytes = 0;
    cfg->limits.max_memory = 64u << 20;
    ts_error err = {0};
    char msg[TS_ERROR_MAX];
    if (!srv_server_start(srv, &g_port, msg, sizeof msg)) {
        fprintf(stderr, "fuzz_http: %s\n", msg);
        abort();
    }
    /* The finished job goes in as a job restored from scratch (the way --data brings jobs
     * back), for an id that is the same in every run: posted jobs get random ids, and an id
     * that differs between runs would change what the fuzzer learns from comparisons. */
    ts_scene *scene = NULL;
    if (ts_scene_load_text(fixture_scene, sizeof fixture_scene - 1, NULL, "fixture", &cfg->limits, &scene,
                           &err)) {
        fprintf(stderr, "fuzz_http: the fixture scene does not load: %s\n", err.message);
        abort();
    }
    srv_restore fr = {0};
    fr.id = JOB_ID;
    fr.scene_text = fixture_scene;
    fr.scene_len = sizeof fixture_scene - 1;
    fr.state = TS_JOB_QUEUED;
    fr.scene = scene;
    fr.settings.spp = scene->spp;
    fr.settings.integrator = scene->integrator.type;
    srv_job *j = srv_store_restore(srv->store, &fr, &err);
    FUZZ_CHECK(j != NULL && j->sj != NULL);
    settle(j);
    srv_job_release(j);
    memset(&fr, 0, sizeof fr);
    fr.id = FAILED_ID;
    fr.name = "broken";
    fr.state = TS_JOB_FAILED;
    fr.settings.spp = 4;
    fr.failure = "checkpoint unreadable: the fuzz harness made it so";
    j = srv_store_restore(srv->store, &fr, &err);
    FUZZ_CHECK(j != NULL);
    srv_job_release(j);
    g_running = true;
    g_store_not_utf8 = false;
    g_jobs = 2;
    g_full_inputs = 0;
}

/* serve.c's shutdown (no checkpoint: there is no --data). */
static void server_stop(void)
{
    srv_server_stop(&g_srv, false);
    g_running = false;
}

/* Waits for every job still rendering; the number of jobs in the store. */
static int settle_jobs(void)
{
    int n = 0;
    srv_job **jobs = srv_store_list(g_srv.store, &n);
    FUZZ_CHECK(jobs != NULL);
    for (int i = 0; i < n; i++) {
        settle(jobs[i]);
        srv_job_release(jobs[i]);
    }
    free(jobs);
    return n;
}

/* ------------------------------------------------------------------ buffers */

typedef struct buf {
    char *p;
    size_t len, cap;
} buf;

static void buf_add(buf *b, const void *data, size_t n)
{
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 1024;
        while (cap < b->len + n + 1)
            cap *= 2;
        char *p = realloc(b->p, cap);
        FUZZ_CHECK(p != NULL);
        b->p = p, b->cap = cap;
    }
    memcpy(b->p + b->len, data, n);
    b->len += n;
    b->p[b->len] = '\0';
}

static void buf_str(buf *b, const char *s) { buf_add(b, s, strlen(s)); }

/* Appends data[0..n) with the placeholders replaced. */
static void buf_subst(buf *b, const char *data, size_t n)
{
    static const struct {
        const char *from, *to;
    } subst[] = {{"@ID@", JOB_ID}, {"@FAILED@", FAILED_ID}, {"@TOKEN@", FUZZ_TOKEN}};
    for (size_t i = 0; i < n;) {
        size_t k;
        for (k = 0; k < sizeof subst / sizeof subst[0]; k++) {
            size_t m = strlen(subst[k].from);
            if (n - i >= m && !memcmp(data + i, subst[k].from, m)) {
                buf_str(b, subst[k].to);
                i += m;
                break;
            }
        }
        if (k == sizeof subst / sizeof subst[0]) buf_add(b, data + i++, 1);
    }
}

static bool utf8_valid(const char *s, size_t n)
{
    const unsigned char *u = (const unsigned char *)s;
    for (size_t i = 0; i < n;) {
        unsigned c = u[i];
        int more = c < 0x80             ? 0
                   : (c & 0xe0) == 0xc0 ? 1
                   : (c & 0xf0) == 0xe0 ? 2
                   : (c & 0xf8) == 0xf0 ? 3
                                        : -1;
        if (more < 0 || (more == 1 && c < 0xc2) || c > 0xf4 || i + (size_t)more >= n) return false;
        uint32_t cp = c & (0x3fu >> more);
        for (int k = 1; k <= more; k++) {
            if ((u[i + (size_t)k] & 0xc0) != 0x80) return false;
            cp = cp << 6 | (u[i + (size_t)k] & 0x3f);
        }
        if ((more == 2 && cp < 0x800) || (more == 3 && (cp < 0x10000 || cp > 0x10ffff)) ||
            (cp >= 0xd800 && cp <= 0xdfff))
            return false;
        i += (size_t)more + 1;
    }
    return true;
}

static int hexval(char c)
{
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                  : -1;
}

/* %XX-decodes s (as libmicrohttpd does; other bytes as they are) into out (NUL-terminated). */
static void percent_decode(const char *s, buf *out)
{
    out->len = 0;
    buf_add(out, "", 0);
    for (size_t i = 0; s[i]; i++) {
        int hi, lo;
        if (s[i] == '%' && (hi = hexval(s[i + 1])) >= 0 && (lo = hexval(s[i + 2])) >= 0) {
            char c = (char)(hi * 16 + lo);
            buf_add(out, &c, 1);
            i += 2;
        } else {
            buf_add(out, s + i, 1);
        }
    }
}

/* ------------------------------------------------------------------ one request */

typedef struct request {
    buf wire; /* the bytes sent */
    buf method, target, auth, body;
    bool head, options, has_token, utf8;
} request;

static bool is_framing_header(const char *name, size_t n)
{
    static const char *const names[] = {"host", "content-length", "transfer-encoding", "connection"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strlen(names[i]) == n && !strncasecmp(name, names[i], n)) return true;
    return false;
}

static void build_request(const uint8_t *data, size_t size, request *rq)
{
    buf in = {0};
    buf_subst(&in, (const char *)data, size);
    const char *p = in.p ? in.p : "", *end = p + in.len;
    const char *nl = memchr(p, '\n', (size_t)(end - p));
    const char *line_end = nl ? nl : end;
    const char *sp = memchr(p, ' ', (size_t)(line_end - p));
    /* method: any visible byte; target: bytes that would end it, %-encoded */
    for (const char *c = p; c < (sp ? sp : line_end); c++)
        if ((unsigned char)*c > 0x20 && *c != 0x7f) buf_add(&rq->method, c, 1);
    if (!rq->method.len) buf_str(&rq->method, "GET");
    for (const char *c = sp ? sp + 1 : line_end; c < line_end; c++) {
        if ((unsigned char)*c <= 0x20 || *c == 0x7f) {
            char esc[4];
            snprintf(esc, sizeof esc, "%%%02X", (unsigned char)*c);
            buf_str(&rq->target, esc);
        } else {
            buf_add(&rq->target, c, 1);
        }
    }
    if (!rq->target.len) buf_str(&rq->target, "/");
    rq->head = !strcmp(rq->method.p, "HEAD");
    rq->options = !strcmp(rq->method.p, "OPTIONS");
    buf_str(&rq->wire, rq->method.p);
    buf_str(&rq->wire, " ");
    buf_str(&rq->wire, rq->target.p);
    buf_str(&rq->wire, " HTTP/1.1\r\nHost: fuzz\r\nConnection: close\r\n");
    /* headers, up to the first empty line */
    bool chunked = false;
    buf headers_text = {0};
    buf_add(&headers_text, "", 0);
    const char *q = nl ? nl + 1 : end;
    int count = 0;
    while (q < end) {
        const char *e = memchr(q, '\n', (size_t)(end - q));
        const char *le = e ? e : end;
        size_t n = (size_t)(le - q);
        if (n && q[n - 1] == '\r') n--;
        const char *next = e ? e + 1 : end;
        if (n == 0) {
            q = next;
            break;
        }
        if (n == 8 && !memcmp(q, "@chunked", 8)) {
            chunked = true;
        } else if (count < 32) {
            const char *colon = memchr(q, ':', n);
            size_t name_len = colon ? (size_t)(colon - q) : n;
            buf line = {0};
            for (size_t i = 0; i < name_len; i++)
                if ((unsigned char)q[i] > 0x20 && q[i] != 0x7f) buf_add(&line, q + i, 1);
            if (line.len && !is_framing_header(line.p, line.len)) {
                bool auth = line.len == 13 && !strncasecmp(line.p, "authorization", 13);
                buf_str(&line, ":");
                size_t value_at = line.len;
                for (size_t i = colon ? name_len + 1 : n; i < n; i++)
                    if ((unsigned char)q[i] >= 0x20 || q[i] == '\t') buf_add(&line, q + i, 1);
                if (auth) buf_add(&rq->auth, line.p + value_at, line.len - value_at);
                buf_str(&line, "\r\n");
                buf_add(&rq->wire, line.p, line.len);
                buf_add(&headers_text, line.p, line.len);
                count++;
            }
            free(line.p);
        }
        q = next;
    }
    buf_add(&rq->body, q, (size_t)(end - q));
    char cl[64];
    if (chunked) {
        buf_str(&rq->wire, "Transfer-Encoding: chunked\r\n\r\n");
        size_t step = 1 + (rq->body.len ? (unsigned char)rq->body.p[0] % 97 : 0);
        for (size_t at = 0; at < rq->body.len; at += step) {
            size_t n = rq->body.len - at < step ? rq->body.len - at : step;
            snprintf(cl, sizeof cl, "%zx\r\n", n);
            buf_str(&rq->wire, cl);
            buf_add(&rq->wire, rq->body.p + at, n);
            buf_str(&rq->wire, "\r\n");
        }
        buf_str(&rq->wire, "0\r\n\r\n");
    } else {
        if (rq->body.len || !strcmp(rq->method.p, "POST")) {
            snprintf(cl, sizeof cl, "Content-Length: %zu\r\n", rq->body.len);
            buf_str(&rq->wire, cl);
        }
        buf_str(&rq->wire, "\r\n");
        buf_add(&rq->wire, rq->body.p ? rq->body.p : "", rq->body.len);
    }
    /* what the checks need: did the request carry the token, was it all UTF-8 */
    buf decoded = {0};
    percent_decode(rq->target.p, &decoded);
    rq->has_token = (rq->auth.len && memmem(rq->auth.p, rq->auth.len, FUZZ_TOKEN, strlen(FUZZ_TOKEN))) ||
                    memmem(decoded.p, decoded.len, FUZZ_TOKEN, strlen(FUZZ_TOKEN)); /* %00 may come first */
    rq->utf8 = utf8_valid(rq->method.p, rq->method.len) && utf8_valid(decoded.p, decoded.len) &&
               utf8_valid(headers_text.p, headers_text.len) &&
               (!rq->body.len || utf8_valid(rq->body.p, rq->body.len));
    free(decoded.p);
    free(headers_text.p);
    free(in.p);
}

static void request_free(request *rq)
{
    free(rq->wire.p), free(rq->method.p), free(rq->target.p), free(rq->auth.p), free(rq->body.p);
}

/* Sends the bytes and reads until the server closes; false if the connection was reset
 * before anything came back. */
static bool exchange(const buf *wire, buf *reply)
{
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    FUZZ_CHECK(fd >= 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)g_port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        /* libFuzzer's SIGALRM (its -timeout check) can interrupt connect(), which then
         * completes on its own: wait for it. */
        int e = errno, so_error = 0;
        socklen_t len = sizeof so_error;
        if (e == EINTR) {
            struct pollfd pfd = {fd, POLLOUT, 0};
            while (poll(&pfd, 1, REPLY_TIMEOUT_MS) < 0 && errno == EINTR) {
            }
            if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &so_error, &len) == 0 && so_error == 0)
                e = 0;
            else
                e = so_error ? so_error : errno;
        }
        if (e) {
            fprintf(stderr, "fuzz_http: connect: %s\n", strerror(e));
            abort();
        }
    }
    for (size_t at = 0; at < wire->len;) {
        ssize_t n = send(fd, wire->p + at, wire->len - at, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break; /* the server answered early and closed (413) */
        at += (size_t)n;
    }
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    bool ok = true;
    for (;;) {
        struct timespec t;
        clock_gettime(CLOCK_MONOTONIC, &t);
        long ms = (t.tv_sec - t0.tv_sec) * 1000 + (t.tv_nsec - t0.tv_nsec) / 1000000;
        if (ms >= REPLY_TIMEOUT_MS) {
            fprintf(stderr, "fuzz_http: no complete reply within %d ms (got %zu bytes)\n", REPLY_TIMEOUT_MS,
                    reply->len);
            abort();
        }
        struct pollfd pfd = {fd, POLLIN, 0};
        int pr = poll(&pfd, 1, (int)(REPLY_TIMEOUT_MS - ms));
        if (pr < 0 && errno == EINTR) continue;
        if (pr <= 0) continue;
        char chunk[16384];
        ssize_t n = recv(fd, chunk, sizeof chunk, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) {
            ok = reply->len > 0;
            break;
        }
        if (n == 0) break;
        buf_add(reply, chunk, (size_t)n);
    }
    close(fd);
    /* Until the server is done with the connection (its completion callback ran), so
     * that work is part of this input, not of the next one. */
    for (int i = 0; i < 200000 && srv_http_connections(g_srv.http); i++) {
        struct timespec ts = {0, 20000};
        nanosleep(&ts, NULL);
    }
    return ok;
}

/* ------------------------------------------------------------------ the reply */

typedef struct reply_info {
    int status;
    const char *headers; /* inside the reply buffer */
    size_t headers_len;
    buf body;
} reply_info;

/* The value of header `name` in the header block, or NULL (copied into out). */
static const char *header_value(const reply_info *ri, const char *name, char *out, size_t out_len)
{
    size_t n = strlen(name);
    for (const char *l = ri->headers; l < ri->headers + ri->headers_len;) {
        const char *e = strstr(l, "\r\n");
        if (!e) break;
        if ((size_t)(e - l) > n && !strncasecmp(l, name, n) && l[n] == ':') {
            const char *v = l + n + 1;
            while (*v == ' ' || *v == '\t')
                v++;
            size_t len = (size_t)(e - v) < out_len - 1 ? (size_t)(e - v) : out_len - 1;
            memcpy(out, v, len);
            out[len] = '\0';
            return out;
        }
        l = e + 2;
    }
    return NULL;
}

/* Parses one complete HTTP/1.1 reply (1xx interim replies skipped); aborts when it is
 * not one. */
static void parse_reply(const buf *reply, bool head, reply_info *ri)
{
    const char *p = reply->p, *end = reply->p + reply->len;
    for (;;) {
        FUZZ_CHECK(end - p >= 12 && (!memcmp(p, "HTTP/1.1 ", 9) || !memcmp(p, "HTTP/1.0 ", 9)));
        FUZZ_CHECK(p[9] >= '1' && p[9] <= '5' && p[10] >= '0' && p[10] <= '9' && p[11] >= '0' &&
                   p[11] <= '9');
        ri->status = (p[9] - '0') * 100 + (p[10] - '0') * 10 + (p[11] - '0');
        const char *eol = strstr(p, "\r\n");
        FUZZ_CHECK(eol != NULL);
        const char *hend = strstr(eol, "\r\n\r\n");
        FUZZ_CHECK(hend != NULL);
        ri->headers = eol + 2;
        ri->headers_len = (size_t)(hend + 2 - ri->headers);
        p = hend + 4;
        if (ri->status >= 200) break;
    }
    char v[64];
    const char *te = header_value(ri, "Transfer-Encoding", v, sizeof v);
    bool no_body = head || ri->status == 204 || ri->status == 304;
    if (!no_body && te && !strcasecmp(te, "chunked")) {
        for (;;) {
            char *e;
            unsigned long n = strtoul(p, &e, 16);
            FUZZ_CHECK(e != p);
            const char *crlf = strstr(e, "\r\n");
            FUZZ_CHECK(crlf != NULL);
            p = crlf + 2;
            if (n == 0) break;
            FUZZ_CHECK((size_t)(end - p) >= n + 2 && p[n] == '\r' && p[n + 1] == '\n');
            buf_add(&ri->body, p, n);
            p += n + 2;
        }
    } else if (!no_body) {
        const char *cl = header_value(ri, "Content-Length", v, sizeof v);
        if (cl) FUZZ_CHECK(strtoull(cl, NULL, 10) == (unsigned long long)(end - p));
        buf_add(&ri->body, p, (size_t)(end - p));
    }
    buf_add(&ri->body, "", 0);
}

/* The route of the request's target, as the server sees it. */
static srv_route request_route(const request *rq)
{
    buf path = {0};
    percent_decode(rq->target.p, &path);
    char *query = strchr(path.p, '?');
    if (query) *query = '\0';
    srv_route route = srv_api_route(path.p);
    free(path.p);
    return route;
}

static void check_reply(const request *rq, const buf *reply)
{
    reply_info ri = {0};
    parse_reply(reply, rq->head, &ri);
    /* The one legitimate 5xx: a job posted to a store at its --max-jobs. */
    bool full_post =
        g_jobs >= MAX_JOBS && !strcmp(rq->method.p, "POST") && request_route(rq) == SRV_ROUTE_JOBS;
    if (getenv("FUZZ_HTTP_VERBOSE")) /* to see what seeds do */
        fprintf(stderr, "fuzz_http: %s %s -> %d %.*s\n", rq->method.p, rq->target.p, ri.status,
                (int)(ri.body.len < 160 ? ri.body.len : 160), ri.body.p);
    if (ri.status >= 500 && !(ri.status == 503 && full_post)) {
        fprintf(stderr, "fuzz_http: answered %d: %.*s\n", ri.status, (int)ri.body.len, ri.body.p);
        abort();
    }
    char type[128];
    bool json =
        header_value(&ri, "Content-Type", type, sizeof type) && !strncmp(type, "application/json", 16);
    if (json && ri.body.len) {
        const char *parse_end = NULL;
        cJSON *doc = cJSON_ParseWithLengthOpts(ri.body.p, ri.body.len, &parse_end, false);
        if (!doc || parse_end != ri.body.p + ri.body.len) {
            fprintf(stderr, "fuzz_http: a JSON reply that is not JSON: %.*s\n", (int)ri.body.len, ri.body.p);
            abort();
        }
        if (ri.status == 201) {
            const cJSON *id = cJSON_GetObjectItemCaseSensitive(doc, "id");
            FUZZ_CHECK(cJSON_IsString(id) && id->valuestring[0]);
        }
        cJSON_Delete(doc);
        if (ri.status == 201 && !rq->utf8) g_store_not_utf8 = true;
        /* Error sentences are always made UTF-8 (http.c); other documents echo what jobs were
         * posted with. */
        bool must_be_utf8 = ri.status >= 400 || (rq->utf8 && !g_store_not_utf8);
        if (must_be_utf8 && !utf8_valid(ri.body.p, ri.body.len)) {
            fprintf(stderr, "fuzz_http: a JSON reply that is not UTF-8: %.*s\n", (int)ri.body.len, ri.body.p);
            abort();
        }
    }
    if (ri.status >= 200 && ri.status < 300 && !rq->options && !rq->has_token) {
        srv_route route = request_route(rq);
        if (route != SRV_ROUTE_UI && route != SRV_ROUTE_HEALTHZ && route != SRV_ROUTE_OTHER) {
            fprintf(stderr, "fuzz_http: %d without the token on %s\n", ri.status, rq->target.p);
            abort();
        }
    }
    free(ri.body.p);
}

static void check_healthz(void)
{
    buf wire = {0}, reply = {0};
    buf_str(&wire, "GET /healthz HTTP/1.1\r\nHost: fuzz\r\nConnection: close\r\n\r\n");
    FUZZ_CHECK(exchange(&wire, &reply));
    FUZZ_CHECK(reply.len > 12 && !memcmp(reply.p + 9, "200", 3));
    free(wire.p);
    free(reply.p);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    signal(SIGPIPE, SIG_IGN);
    /* Started here, so the fixture's render (on the scheduler's threads, in an order that
     * varies) counts as no input's coverage. */
    server_start();
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!g_running) server_start();
    request rq = {0};
    build_request(data, size, &rq);
    buf reply = {0};
    bool ok = exchange(&rq.wire, &reply);
    /* A body over the limit may be refused from its Content-Length before it is read:
     * the reply may then be lost to the connection's reset. */
    if (ok || rq.body.len <= MAX_BODY) {
        if (!reply.len) {
            fprintf(stderr, "fuzz_http: the server closed without a reply\n");
            abort();
        }
        check_reply(&rq, &reply);
    }
    free(reply.p);
    request_free(&rq);
    g_jobs = settle_jobs();
    FUZZ_CHECK(g_jobs <= MAX_JOBS);
    if (++g_inputs % 256 == 0) check_healthz();
    if (g_jobs >= MAX_JOBS && ++g_full_inputs > FULL_INPUTS) {
        server_stop();
        server_start();
    }
    return 0;
}
