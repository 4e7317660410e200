/* api.c — HTTP API v1 routes; see api.h and proto/openapi.yaml. */
#include "api.h"

#include <ctype.h>
#include <math.h>
#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <arpa/inet.h>
#include <errno.h>
#include <sys/random.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include "assets.h"
#include "bundle.h"
#include "farm.h"
#include "job_store.h"
#include "offload.h"
#include "persist.h"
#include "tessera.h"

#define API_PREFIX "/api/v1/jobs"

/* ---------------------------------------------------------------- routing */

typedef struct parsed {
    srv_route route;
    char id[24];
    int tx, ty;
    bool png; /* else exr (image and tile routes) */
} parsed;

static bool parse_ext(const char *s, const char *stem, bool *png)
{
    size_t n = strlen(stem);
    if (strncmp(s, stem, n) != 0) return false;
    if (!strcmp(s + n, ".png")) return *png = true, true;
    if (!strcmp(s + n, ".exr")) return *png = false, true;
    return false;
}

/* A tile index in canonical decimal: digits only, no sign, no leading zero (but "0"
 * itself), at most 9 digits (so it fits an int without wrapping); advances *s past it. */
static bool parse_index(const char **s, int *out)
{
    const char *p = *s;
    int n = 0, v = 0;
    while (p[n] >= '0' && p[n] <= '9' && n < 10) v = v * 10 + (p[n] - '0'), n++;
    if (n == 0 || n > 9 || (n > 1 && p[0] == '0')) return false;
    *s = p + n;
    *out = v;
    return true;
}

/* The URL arrives as the client sent it (http.c turns libmicrohttpd's unescaping off), so
 * "%2f" or "%00" never become a '/' or a NUL here: an id is [0-9A-Za-z_-] and any escape
 * in a path segment makes the route unknown (404). */
static void parse_url(const char *url, parsed *p)
{
    memset(p, 0, sizeof *p);
    p->route = SRV_ROUTE_OTHER;
    if (!strcmp(url, "/") || !strcmp(url, "/index.html") || srv_asset_find(url)) p->route = SRV_ROUTE_UI;
    else if (!strcmp(url, "/healthz")) p->route = SRV_ROUTE_HEALTHZ;
    else if (!strcmp(url, "/metrics")) p->route = SRV_ROUTE_METRICS;
    else if (!strcmp(url, "/api/v1/limits")) p->route = SRV_ROUTE_LIMITS;
    else if (!strcmp(url, API_PREFIX) || !strcmp(url, API_PREFIX "/")) p->route = SRV_ROUTE_JOBS;
    else if (!strncmp(url, API_PREFIX "/", sizeof API_PREFIX)) {
        const char *id = url + sizeof API_PREFIX;
        const char *slash = strchr(id, '/');
        size_t n = slash ? (size_t)(slash - id) : strlen(id);
        if (n == 0 || n >= sizeof p->id) return;
        for (size_t i = 0; i < n; i++)
            if (!((id[i] >= '0' && id[i] <= '9') || (id[i] >= 'a' && id[i] <= 'z') || (id[i] >= 'A' && id[i] <= 'Z') ||
                  id[i] == '-' || id[i] == '_'))
                return;
        memcpy(p->id, id, n);
        p->id[n] = '\0';
        if (!slash || !slash[1]) p->route = SRV_ROUTE_JOB;
        else if (!strcmp(slash, "/events")) p->route = SRV_ROUTE_EVENTS;
        else if (!strcmp(slash, "/history")) p->route = SRV_ROUTE_HISTORY;
        else if (!strcmp(slash, "/cancel")) p->route = SRV_ROUTE_CANCEL;
        else if (parse_ext(slash, "/image", &p->png)) p->route = SRV_ROUTE_IMAGE;
        else if (!strncmp(slash, "/tiles/", 7)) {
            const char *at = slash + 7;
            int tx, ty;
            if (parse_index(&at, &tx) && *at++ == '/' && parse_index(&at, &ty) && parse_ext(at, "", &p->png)) {
                p->route = SRV_ROUTE_TILE;
                p->tx = tx, p->ty = ty;
            }
        }
    }
}

srv_route srv_api_route(const char *url)
{
    parsed p;
    parse_url(url, &p);
    return p.route;
}

/* ---------------------------------------------------------------- helpers */

static int reply_cjson(srv_request *r, unsigned status, cJSON *o)
{
    char *s = o ? cJSON_PrintUnformatted(o) : NULL;
    cJSON_Delete(o);
    if (!s) return srv_http_error(r, 500, "out of memory");
    int ret = srv_http_reply_json(r, status, s);
    free(s);
    return ret;
}

/* True when the a bytes of given equal the configured token. The whole presented value
 * counts (a NUL inside it is a byte like any other, so "TOKEN\0x" is not "TOKEN"). The
 * time taken depends only on the configured token's length, never on where the first
 * difference is: every byte of the token is compared (no early exit; past the end of
 * given, a NUL is used), and a length mismatch is folded into the result rather than
 * tested first. */
static bool token_matches(const char *given, size_t a, const char *token)
{
    size_t b = strlen(token);
    volatile unsigned diff = a != b;
    for (size_t i = 0; i < b; i++) diff |= (unsigned char)token[i] ^ (i < a ? (unsigned char)given[i] : 0u);
    return diff == 0;
}

static int hex_digit(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

/* Percent-decodes s (n bytes) into out (at least n bytes); returns the decoded length, or
 * (size_t)-1 for a malformed escape. */
static size_t percent_decode(const char *s, size_t n, char *out)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] != '%') {
            out[k++] = s[i] == '+' ? ' ' : s[i];
            continue;
        }
        int hi = i + 2 < n ? hex_digit(s[i + 1]) : -1;
        int lo = i + 2 < n ? hex_digit(s[i + 2]) : -1;
        if (hi < 0 || lo < 0) return (size_t)-1;
        out[k++] = (char)(hi * 16 + lo);
        i += 2;
    }
    return k;
}

static bool authorised(srv_request *r)
{
    const char *token = ((srv_api *)r->app)->token;
    if (!token) return true;
    const char *h = NULL;
    size_t h_len = 0;
    if (MHD_lookup_connection_value_n(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION,
                                      strlen(MHD_HTTP_HEADER_AUTHORIZATION), &h, &h_len) == MHD_YES &&
        h && h_len >= 7 && !strncasecmp(h, "Bearer ", 7))
        return token_matches(h + 7, h_len - 7, token);
    /* EventSource cannot send headers: the token may come as ?access_token=, percent-encoded
     * (the URL reaches us undecoded). */
    const char *q = NULL;
    size_t q_len = 0;
    if (MHD_lookup_connection_value_n(r->conn, MHD_GET_ARGUMENT_KIND, "access_token", 12, &q, &q_len) != MHD_YES || !q)
        return false;
    char *dec = malloc(q_len + 1);
    size_t n = dec ? percent_decode(q, q_len, dec) : (size_t)-1;
    bool ok = n != (size_t)-1 && token_matches(dec, n, token);
    free(dec);
    return ok;
}

/* True when the Content-Type value v is the media type `want` (case-insensitive),
 * parameters after ';' allowed: "application/json; charset=utf-8" is JSON,
 * "application/jsonx" is not. */
static bool media_type_is(const char *v, const char *want)
{
    size_t n = strlen(want);
    while (*v == ' ' || *v == '\t') v++;
    if (strncasecmp(v, want, n) != 0) return false;
    v += n;
    while (*v == ' ' || *v == '\t') v++;
    return *v == '\0' || *v == ';';
}

/* Whether a POST's Content-Type is acceptable: without a token only application/json,
 * so no page of another site can post through a browser (HTML forms and "simple" fetches
 * can only send text/plain, form encodings or none); with a token (which such a page
 * cannot send) also text/plain, application/x-www-form-urlencoded or none, read as JSON. */
static bool post_type_ok(srv_request *r, srv_route route)
{
    const char *type = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    if (type && media_type_is(type, "application/json")) return true;
    /* A bundle's types are not ones a page of another site can send without a CORS
     * preflight either (docs/security.md). */
    if (route == SRV_ROUTE_JOBS && srv_bundle_media_type(type)) return true;
    if (!((srv_api *)r->app)->token) return false;
    return !type || media_type_is(type, "text/plain") || media_type_is(type, "application/x-www-form-urlencoded");
}

static bool is_ip_literal(const char *s)
{
    unsigned char b[16];
    return inet_pton(AF_INET, s, b) == 1 || inet_pton(AF_INET6, s, b) == 1;
}

/* The name part of a Host value ("name", "name:port", "[v6]", "[v6]:port") into out;
 * false when malformed or too long. */
static bool host_name(const char *v, char *out, size_t n)
{
    const char *end;
    if (v[0] == '[') {
        end = strchr(v, ']');
        if (!end || (end[1] && end[1] != ':')) return false;
        v++;
    } else {
        end = strchr(v, ':');
        if (!end) end = v + strlen(v);
        if (strchr(end + (*end == ':'), ':')) return false;
    }
    size_t len = (size_t)(end - v);
    if (len == 0 || len >= n) return false;
    memcpy(out, v, len);
    out[len] = '\0';
    return true;
}

/* DNS rebinding: a page of another site whose name was made to resolve to this server
 * sends its own name as Host. Only names the server was bound to pass: the bind address,
 * localhost (and any loopback address) for a loopback bind, any IP address for a
 * wildcard bind, and the names of --allowed-hosts. A request without Host (HTTP/1.0; no
 * browser sends one) passes. */
static bool host_allowed(srv_request *r, char *name, size_t n)
{
    const srv_api *a = r->app;
    const char *h = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    name[0] = '\0';
    if (!h) return true;
    snprintf(name, n, "%s", h);
    char host[256];
    if (!host_name(h, host, sizeof host)) return false;
    const char *bind = a->bind ? a->bind : "127.0.0.1";
    if (!strcasecmp(host, bind)) return true;
    bool loopback = !strncmp(bind, "127.", 4) || !strcmp(bind, "::1");
    if (loopback && (!strcasecmp(host, "localhost") || !strcmp(host, "::1") || (!strncmp(host, "127.", 4) && is_ip_literal(host))))
        return true;
    if ((!strcmp(bind, "0.0.0.0") || !strcmp(bind, "::")) && is_ip_literal(host)) return true;
    for (const char *at = a->allowed_hosts; at && *at;) {
        size_t len = strcspn(at, ",");
        if (len == strlen(host) && !strncasecmp(at, host, len)) return true;
        at += len + (at[len] == ',');
    }
    return false;
}

/* CSRF: a browser names the page's origin in Origin. Only the server's own origin (the
 * Host it was reached by, over http) and --cors-origin pass; a request without Origin
 * (not from a browser, or a same-origin GET) passes. */
static bool origin_allowed(srv_request *r)
{
    const srv_api *a = r->app;
    const char *o = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "Origin");
    if (!o) return true;
    if (a->cors_origin && !strcmp(o, a->cors_origin)) return true;
    const char *h = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    return h && !strncasecmp(o, "http://", 7) && !strcasecmp(o + 7, h);
}

/* ---------------------------------------------------------------- images (deferred) */

/* A deferred request's state (r->task, freed by request_done): an image's, or a load's
 * (job NULL; a bundle's spp its ?spp=, name its ?name= or ""; load its bound, from the
 * request's arrival). */
typedef struct image_task {
    srv_job *job;
    bool tile, png;
    int tx, ty;
    uint32_t spp;
    char name[256];
    uint32_t shards;             /* a bundle's ?shards= (a farm job), 0: none */
    ts_cancel load;
} image_task;


static void encode_task(void *arg)
{
    srv_request *r = arg;
    image_task *t = r->task;
    srv_job *j = t->job;
    ts_error err = {0};
    ts_film *film = NULL;
    r->reply_status = 500;
    r->reply_type = "application/json";
    if (t->tile) {
        ts_tile_snapshot *snap = ts_sched_job_tile(j->sj, t->tx, t->ty);
        if (!snap) {
            /* Not rendered yet: an empty tile of the right size. */
            ts_tile_rect tr = ts_tile_grid_rect(j->x0, j->y0, j->w, j->h, t->tx, t->ty);
            film = ts_film_create(j->full_w, j->full_h, tr.x, tr.y, tr.w, tr.h, &err);
        } else {
            film = ts_tile_snapshot_film(snap, j->full_w, j->full_h, &err);
        }
        ts_tile_snapshot_release(snap);
        const ts_scene *sc = ts_sched_job_scene(j->sj);
        if (film && sc) film->scale = sc->film_scale; /* the output factor (film.h) */
    } else {
        film = ts_sched_job_film(j->sj, NULL, &err);
    }
    ts_image img = {0};
    unsigned char *buf = NULL;
    size_t len = 0;
    ts_status st = film ? ts_film_to_image(film, TS_FILM_IMAGE_STATS, &img, &err) : err.status;
    if (!st) {
        /* The same metadata as `tessera render` writes (only the render time differs). */
        ts_job_progress p;
        ts_sched_job_progress(j->sj, &p);
        const ts_scene *sc = ts_sched_job_scene(j->sj);
        /* Named as the job is (a restored job's scene was loaded again without its name). */
        ts_render_info info = {j->name ? j->name : sc ? sc->name : NULL, j->integrator, p.spp_done, sc != NULL, sc ? sc->sampler.seed : 0,
                               p.elapsed_s, t->tile ? -1 : ts_film_relative_error(film), (double)p.nonfinite,
                               t->tile ? NULL : j->id, film->scale};
        info.media = (sc && (sc->effects & TS_EFFECT_MEDIA)) || p.medium_steps > 0 || p.walks_truncated > 0;
        info.medium_steps = (double)p.medium_steps;
        info.walks_truncated = (double)p.walks_truncated;
        st = ts_image_set_render_info(&img, &info, &err);
        if (!st) st = t->png ? ts_png_encode(&img, 0.0f, &buf, &len, &err) : ts_exr_write_memory(&img, &buf, &len, &err);
    }
    ts_image_fini(&img);
    ts_film_destroy(film);
    if (st) {
        srv_http_set_error(r, 500, "encoding failed: %s", err.message);
    } else {
        r->reply_status = 200;
        r->reply_type = t->png ? "image/png" : "image/x-exr";
        r->reply_body = buf;
        r->reply_len = len;
        if (t->tile) snprintf(r->reply_disposition, sizeof r->reply_disposition, "inline; filename=\"%s-tile-%d-%d.%s\"",
                              j->id, t->tx, t->ty, t->png ? "png" : "exr");
        else snprintf(r->reply_disposition, sizeof r->reply_disposition, "inline; filename=\"%s.%s\"", j->id,
                      t->png ? "png" : "exr");
    }
    srv_http_complete(r);
}

static void request_done(srv_request *r)
{
    image_task *t = r->task;
    if (!t) return;
    srv_job_release(t->job);
    free(t);
    r->task = NULL;
}

static int get_image(srv_request *r, srv_job *j, const parsed *p)
{
    if (!j->sj) {
        srv_job_release(j);
        return srv_http_error(r, 409, "job %s failed before rendering: %s", p->id, j->failure);
    }
    if (p->route == SRV_ROUTE_TILE && (p->tx < 0 || p->ty < 0 || p->tx >= j->nx || p->ty >= j->ny)) {
        int ret = srv_http_error(r, 404, "tile %d/%d does not exist: job %s has %d × %d tiles", p->tx, p->ty, p->id, j->nx,
                                 j->ny);
        srv_job_release(j);
        return ret;
    }
    image_task *t = calloc(1, sizeof *t);
    if (!t) {
        srv_job_release(j);
        return srv_http_error(r, 500, "out of memory");
    }
    t->job = j; /* the task owns this reference */
    t->tile = p->route == SRV_ROUTE_TILE;
    t->png = p->png;
    t->tx = p->tx, t->ty = p->ty;
    r->task = t;
    return srv_http_defer(r, encode_task);
}

/* ---------------------------------------------------------------- events */

/* A late subscriber's backlog (events.h): tile i's event as it stands, read from its
 * snapshot when the client gets to it; then the progress (and done) of the tail. */
static char *backlog_tile(void *arg, int i)
{
    srv_job *j = arg;
    ts_tile_snapshot *s = j->sj ? ts_sched_job_tile(j->sj, i % j->nx, i / j->nx) : NULL;
    if (!s) return NULL;
    /* The same event as the live ones (job_store.c). */
    ts_tile_event ev = {s->tx, s->ty, s->x, s->y, s->w, s->h, s->spp};
    ts_tile_snapshot_release(s);
    return srv_job_tile_event(j, &ev);
}

static char *backlog_tail(void *arg)
{
    srv_job *j = arg;
    if (!j->sj) return NULL;
    ts_job_progress p;
    ts_sched_job_progress(j->sj, &p);
    cJSON *o = srv_job_progress_json(j, &p);
    char *s = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    if (!s) return NULL;
    char *e = srv_events_format("progress", s);
    if (e && ts_job_state_finished(p.state)) {
        char *done = srv_events_format("done", s);
        char *both = done ? malloc(strlen(e) + strlen(done) + 1) : NULL;
        if (both) strcat(strcpy(both, e), done);
        free(done);
        free(e);
        e = both;
    }
    free(s);
    return e;
}

static void job_retain(void *j) { srv_job_retain(j); }
static void job_release(void *j) { srv_job_release(j); }

static int get_events(srv_request *r, srv_job *j)
{
    srv_events_source src = {j->sj ? j->nx * j->ny : 0, backlog_tile, backlog_tail, job_retain, job_release, j};
    unsigned status = 500;
    char msg[256] = "";
    struct MHD_Response *resp =
        srv_events_subscribe(j->events, r->conn, &src, ((srv_api *)r->app)->sse_limits, &status, msg, sizeof msg);
    srv_job_release(j); /* the stream holds its own reference (src.retain) */
    if (!resp) return srv_http_error(r, status, "%s", msg);
    /* A small send buffer: a client that stops reading stops costing the server work (the
     * backlog is only formatted as the socket takes it) within 64 KiB, instead of the
     * megabytes the kernel's autotuning would let it queue. */
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(r->conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    int sndbuf = 64 << 10;
    if (ci) setsockopt(ci->connect_fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "text/event-stream");
    MHD_add_response_header(resp, "X-Accel-Buffering", "no");
    return srv_http_queue(r, 200, resp);
}

/* ---------------------------------------------------------------- jobs */

static bool parse_decimal(const char *s, size_t n, uint64_t *out);

static void json_task(void *arg);
static int defer_load(srv_request *r, struct image_task *t, void (*fn)(void *));

/* The state of a load (a posted scene or bundle) about to go to the loader pool: its time
 * (--max-load-seconds) runs from now, so waiting in the queue counts. */
static image_task *load_state(srv_request *r)
{
    const srv_api *a = r->app;
    image_task *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    ts_cancel_init(&t->load, a->loads_stop, a->max_load_s);
    r->task = t;
    return t;
}

static int post_job(srv_request *r)
{
    if (MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "spp"))
        return srv_http_error(r, 400, "spp: the query parameter is for bundles; a JSON scene sets job.spp");
    if (MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "name"))
        return srv_http_error(r, 400, "name: the query parameter is for bundles; a JSON scene sets name or job.name");
    if (MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "shards"))
        return srv_http_error(r, 400, "shards: the query parameter is for bundles; a JSON scene sets job.farm.shards");
    if (!r->body_len) return srv_http_error(r, 400, "the request body is empty: send a scene document (JSON)");
    image_task *t = load_state(r);
    if (!t) return srv_http_error(r, 500, "out of memory");
    return defer_load(r, t, json_task);
}

/* ---------------------------------------------------------------- bundles */

/* The 201 of a job just accepted, as the reply of request r (deferred or not): its
 * status document and Location. Persists it first with --data. */
static void accepted(srv_request *r, srv_job *j)
{
    const srv_api *a = r->app;
    if (a->data_dir) {
        ts_error perr = {0};
        if (srv_persist_save_submitted(a->data_dir, j, &perr) && srv_job_set_checkpoint_error(j, perr.message))
            fprintf(stderr, "tessera: recording job %s failed, it renders on unrecorded: %s\n", j->id, perr.message);
    }
    cJSON *o = srv_job_status_json(j);
    char *s = o ? cJSON_PrintUnformatted(o) : NULL;
    cJSON_Delete(o);
    if (!s) {
        srv_http_set_error(r, 500, "out of memory");
        return;
    }
    r->reply_status = 201;
    r->reply_type = "application/json";
    r->reply_body = (unsigned char *)s;
    r->reply_len = strlen(s);
    snprintf(r->reply_location, sizeof r->reply_location, API_PREFIX "/%s", j->id);
}

/* A load whose time ran out while it waited for a loader (the pool's watchdog runs this
 * instead of its task): 503 at its bound. */
static void load_expired(void *arg)
{
    srv_request *r = arg;
    const srv_api *a = r->app;
    atomic_fetch_add(&a->loads->timed_out, 1);
    srv_http_set_error(r, 503, "the server's scene loaders were busy for this request's whole --max-load-seconds (%g s); "
                               "try again later", a->max_load_s);
    srv_http_complete(r);
}

/* Defers a load (its state made by load_state) to the loader pool, bounded by its deadline. */
static int defer_load(srv_request *r, struct image_task *t, void (*fn)(void *))
{
    const srv_api *a = r->app;
    return srv_http_defer_bounded(r, a->loaders, fn, t->load.deadline > 0 ? load_expired : NULL, t->load.deadline);
}

/* At a load's start on a loader thread: false, with the reply set, when the server is
 * shutting down or the request's time ran out while it waited in the queue. */
static bool load_begin(srv_request *r, image_task *t)
{
    const srv_api *a = r->app;
    if (!ts_cancel_requested(&t->load)) {
        atomic_fetch_add(&a->loads->started, 1);
        return true;
    }
    if (atomic_load(&t->load.timed_out)) {
        atomic_fetch_add(&a->loads->timed_out, 1);
        srv_http_set_error(r, 503, "the server's scene loaders were busy for this request's whole --max-load-seconds "
                                   "(%g s); try again later", a->max_load_s);
    } else {
        atomic_fetch_add(&a->loads->cancelled, 1);
        srv_http_set_error(r, 503, "the server is shutting down");
    }
    return false;
}

/* A load that failed with status: counts a stop, and says a time-out in the server's terms. */
static void load_failed(srv_request *r, image_task *t, int status, ts_error *err)
{
    const srv_api *a = r->app;
    if (err->status != TS_ERR_CANCELLED) return;
    if (atomic_load(&t->load.timed_out)) {
        atomic_fetch_add(&a->loads->timed_out, 1);
        ts_error_set(err, TS_ERR_CANCELLED, "the scene did not load within this server's --max-load-seconds (%g s): it "
                                            "is too costly to load here", a->max_load_s);
    } else if (status == 503) {
        atomic_fetch_add(&a->loads->cancelled, 1);
        ts_error_set(err, TS_ERR_CANCELLED, "the server is shutting down; the scene was not loaded");
    }
}

/* On a loader thread: a posted JSON document, loaded and queued. */
static void json_task(void *arg)
{
    srv_request *r = arg;
    image_task *t = r->task;
    if (load_begin(r, t)) {
        ts_error err = {0};
        int status = 500;
        /* A farm job ("job": {"farm": {"shards": N}}) goes to the farm without job.farm. */
        const srv_api *a = r->app;
        uint32_t shards = 0;
        char *plain = NULL;
        size_t plain_len = 0;
        srv_job *j = NULL;
        if (srv_farm_parse_request(r->body, r->body_len, srv_farm_max_shards(a->farm), &shards, &plain, &plain_len,
                                   &status, &err))
            j = shards ? srv_farm_submit(a->farm, a->store, plain, plain_len, NULL, &t->load, shards, &status, &err)
                       : srv_store_submit_cancellable(a->store, r->body, r->body_len, NULL, &t->load, &status, &err);
        free(plain);
        if (j) {
            accepted(r, j);
            srv_job_release(j);
        } else {
            load_failed(r, t, status, &err);
            srv_http_set_error(r, (unsigned)status, "%s", err.message);
        }
    }
    srv_http_complete(r);
}

/* Reads a regular file of at most max bytes (NUL-terminated); NULL with errno. */
static char *read_scene_file(const char *path, uint64_t max, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (n + 65537 > cap) {
            cap = cap ? 2 * cap : 65536 + 1;
            char *b = realloc(buf, cap);
            if (!b) break;
            buf = b;
        }
        size_t k = fread(buf + n, 1, cap - n - 1, f);
        n += k;
        if (k == 0 || n > max) break;
    }
    bool ok = buf && !ferror(f) && n <= max && n + 1 <= cap;
    fclose(f);
    if (!ok) {
        free(buf);
        errno = EIO;
        return NULL;
    }
    buf[n] = '\0';
    *len = n;
    return buf;
}

/* On an encoder thread (bundle.h: unpacking writes files): unpack into
 * ROOT/incoming/<random>, load the scene from there, and the store moves the folder to the
 * job's once the scene loaded; anything that fails removes the folder. */
static void bundle_task(void *arg)
{
    srv_request *r = arg;
    const srv_api *a = r->app;
    ts_error err = {0};
    int status = 500;
    char staging[4096] = "";
    unsigned char rnd[8];
    image_task *t = r->task;
    if (!load_begin(r, t)) goto done;
    if (!srv_store_has_room(a->store)) {
        srv_http_set_error(r, 503, "this server already holds as many jobs as its limit (--max-jobs); no new job can be "
                                   "queued");
        goto done;
    }
    const char *root = srv_bundle_root_get(a->files_root);
    if (!root) {
        srv_http_set_error(r, 500, "cannot make a temporary folder for bundles: %s", strerror(errno));
        goto done;
    }
    if (getrandom(rnd, sizeof rnd, 0) != (ssize_t)sizeof rnd) {
        srv_http_set_error(r, 500, "no random bytes for a folder name: %s", strerror(errno));
        goto done;
    }
    snprintf(staging, sizeof staging, "%s/incoming", root);
    if (mkdir(staging, 0700) != 0 && errno != EEXIST) {
        srv_http_set_error(r, 500, "cannot make the folder for bundles: %s", strerror(errno));
        staging[0] = '\0';
        goto done;
    }
    snprintf(staging, sizeof staging, "%s/incoming/%02x%02x%02x%02x%02x%02x%02x%02x", root, rnd[0], rnd[1],
             rnd[2], rnd[3], rnd[4], rnd[5], rnd[6], rnd[7]);
    srv_bundle_info info;
    srv_bundle_limits lim = *a->bundle;
    lim.cancel = &t->load;
    if (srv_bundle_unpack(r->body, r->body_len, staging, &lim, &info, &status, &err)) {
        load_failed(r, t, status, &err);
        srv_http_set_error(r, (unsigned)status, "%s", err.message);
        staging[0] = '\0'; /* the unpacker removed it */
        goto done;
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", staging, info.scene_file);
    size_t len = 0;
    char *text = read_scene_file(path, a->bundle->max_entry_bytes, &len);
    if (!text) {
        srv_http_set_error(r, 500, "the bundle's %s cannot be read back: %s", info.scene_file, strerror(errno));
        goto done;
    }
    srv_submit_files files = {!strcmp(info.scene_file, "scene.pbrt"), staging, root, t->spp, t->name[0] ? t->name : NULL};
    srv_job *j = t->shards ? srv_farm_submit(a->farm, a->store, text, len, &files, &t->load, t->shards, &status, &err)
                           : srv_store_submit_cancellable(a->store, text, len, &files, &t->load, &status, &err);
    free(text);
    if (!j) {
        load_failed(r, t, status, &err);
        /* The sentence names the scene file: scene.json then the JSON path, or the pbrt-v3
         * position (scene.pbrt:LINE:COLUMN, or an included file's) when it has one. */
        size_t n = strlen(info.scene_file);
        bool named = !strncmp(err.message, info.scene_file, n) && err.message[n] == ':';
        srv_http_set_error(r, (unsigned)status, "%s%s%s", named ? "" : info.scene_file, named ? "" : ": ", err.message);
        goto done;
    }
    staging[0] = '\0'; /* the job's now */
    accepted(r, j);
    srv_job_release(j);
done:
    if (staging[0] && srv_bundle_remove_tree(staging) != 0)
        fprintf(stderr, "tessera: removing a refused bundle's folder %s: %s\n", staging, strerror(errno));
    srv_http_complete(r);
}

/* Whether s is UTF-8 (complete sequences, no overlong two-byte forms) without control characters. */
static bool name_text_ok(const char *s)
{
    for (const unsigned char *u = (const unsigned char *)s; *u;) {
        unsigned c = *u;
        size_t n = c < 0x80 ? 1 : c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : c >= 0xf0 && c <= 0xf4 ? 4 : 0;
        if (!n || c < 0x20 || c == 0x7f) return false;
        for (size_t i = 1; i < n; i++)
            if ((u[i] & 0xc0) != 0x80) return false;
        u += n;
    }
    return true;
}

static int post_bundle(srv_request *r)
{
    const srv_api *a = r->app;
    if (!a->bundle || !a->files_root)
        return srv_http_error(r, 415, "this server takes no bundles: post the scene as JSON");
    const char *enc = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, "Content-Encoding");
    if (enc && strcasecmp(enc, "gzip") && strcasecmp(enc, "x-gzip") && strcasecmp(enc, "identity"))
        return srv_http_error(r, 415, "a bundle may be gzip-compressed, not '%s' (Content-Encoding)", enc);
    if (!r->body_len) return srv_http_error(r, 400, "the request body is empty: send a tar of scene.json or scene.pbrt and its files");
    /* ?spp=N: the job's spp target, the job.spp a scene.pbrt has no place for (its
     * sampler's spp, which scales ray differentials, stays the file's). */
    const char *spp = MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "spp");
    uint64_t v = 0;
    if (spp && (!parse_decimal(spp, strlen(spp), &v) || v < 1 || v > UINT32_MAX))
        return srv_http_error(r, 400, "spp: expected a whole number of samples per pixel from 1 (canonical decimal)");
    /* ?name=NAME (v1.4): the job's name when its scene has none (a scene.pbrt never has):
     * the page sends the bundle's file or folder name. */
    const char *raw = MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "name");
    char name[256] = "";
    if (raw) {
        char dec[3 * sizeof name]; /* decoding never lengthens */
        size_t n = strlen(raw) < sizeof dec ? percent_decode(raw, strlen(raw), dec) : 0;
        if (n == (size_t)-1 || n >= sizeof name) n = 0;
        if (n) dec[n] = '\0', snprintf(name, sizeof name, "%s", dec);
        if (!n || strlen(name) != n || !name_text_ok(name))
            return srv_http_error(r, 400, "name: expected 1 to 255 bytes of UTF-8 text without control characters");
    }
    /* ?shards=N: a farm job of N tasks (farm.h). */
    uint32_t shards = 0;
    ts_error serr = {0};
    if (!srv_farm_parse_shards(MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "shards"),
                               srv_farm_max_shards(a->farm), &shards, &serr))
        return srv_http_error(r, 400, "%s", serr.message);
    if (shards && !a->farm)
        return srv_http_error(r, 422, "shards: this server has no farm to send the job to (start it with --farm slurm "
                                      "--farm-dir DIR)");
    image_task *t = load_state(r);
    if (!t) return srv_http_error(r, 500, "out of memory");
    t->spp = (uint32_t)v;
    t->shards = shards;
    snprintf(t->name, sizeof t->name, "%s", name);
    return srv_http_defer_to(r, a->loaders, bundle_task);
}

/* GET /api/v1/jobs is paginated (API v1.2): a page of at most `limit` jobs (default
 * LIST_PAGE, at most LIST_PAGE_MAX), newest first, and `next`, the cursor of the page's last
 * job, when older ones remain (null otherwise); `after=CURSOR` starts below that cursor. A
 * cursor is "<created µs>.<id>": it places a page even when the job it names was deleted
 * meanwhile, and jobs submitted meanwhile (newer) never shift the pages after it. */
#define LIST_PAGE 100
#define LIST_PAGE_MAX 1000

typedef struct list_key { uint64_t created_us; const char *id; } list_key;

static list_key key_of(const srv_job *j)
{
    return (list_key){j->created_unix > 0 ? (uint64_t)llround(j->created_unix * 1e6) : 0, j->id};
}

/* Newest first: later creation, then the larger id. */
static int cmp_key(list_key a, list_key b)
{
    if (a.created_us != b.created_us) return a.created_us > b.created_us ? -1 : 1;
    return -strcmp(a.id, b.id);
}

static int cmp_jobs(const void *a, const void *b) { return cmp_key(key_of(*(srv_job *const *)a), key_of(*(srv_job *const *)b)); }

/* A canonical decimal of at most 19 digits ("0" or no leading zero). */
static bool parse_decimal(const char *s, size_t n, uint64_t *out)
{
    if (n == 0 || n > 19 || (n > 1 && s[0] == '0')) return false;
    uint64_t v = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return false;
        v = v * 10 + (uint64_t)(s[i] - '0');
    }
    *out = v;
    return true;
}

static bool id_chars(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= 24) return false;
    for (size_t i = 0; i < n; i++)
        if (!isalnum((unsigned char)s[i]) && s[i] != '_' && s[i] != '-') return false;
    return true;
}

static int list_jobs(srv_request *r)
{
    const char *lim = MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "limit");
    const char *after = MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "after");
    uint64_t limit = LIST_PAGE;
    if (lim && (!parse_decimal(lim, strlen(lim), &limit) || limit < 1 || limit > LIST_PAGE_MAX))
        return srv_http_error(r, 400, "limit: expected an integer from 1 to %d (canonical decimal)", LIST_PAGE_MAX);
    list_key cursor = {0, NULL};
    if (after) {
        const char *dot = strchr(after, '.');
        if (!dot || !parse_decimal(after, (size_t)(dot - after), &cursor.created_us) || !id_chars(dot + 1))
            return srv_http_error(r, 400, "after: expected a cursor from a previous page's \"next\"");
        cursor.id = dot + 1;
    }
    int n = 0;
    srv_job **jobs = srv_store_list(((srv_api *)r->app)->store, &n);
    if (!jobs && n) return srv_http_error(r, 500, "out of memory");
    if (n > 1) qsort(jobs, (size_t)n, sizeof *jobs, cmp_jobs);
    cJSON *o = cJSON_CreateObject();
    cJSON *arr = cJSON_AddArrayToObject(o, "jobs");
    int taken = 0, last = -1;
    bool more = false;
    for (int i = 0; i < n; i++) {
        if (!cursor.id || cmp_key(key_of(jobs[i]), cursor) > 0) {
            if ((uint64_t)taken < limit) {
                cJSON_AddItemToArray(arr, srv_job_status_json(jobs[i]));
                taken++, last = i;
            } else {
                more = true;
            }
        }
    }
    if (more && last >= 0) {
        char next[64];
        list_key k = key_of(jobs[last]);
        snprintf(next, sizeof next, "%llu.%s", (unsigned long long)k.created_us, k.id);
        cJSON_AddStringToObject(o, "next", next);
    } else {
        cJSON_AddNullToObject(o, "next");
    }
    for (int i = 0; i < n; i++) srv_job_release(jobs[i]);
    free(jobs);
    return reply_cjson(r, 200, o);
}

/* A pool's state for /healthz and /metrics (its bound: what a task may take). */
static void pool_status(const srv_api *a, bool loaders, srv_offload_status *out)
{
    srv_offload *o = loaders ? a->loaders : a->encoders;
    if (!o) {
        *out = (srv_offload_status){0};
        return;
    }
    srv_offload_get_status(o, loaders ? a->max_load_s + SRV_LOAD_GRACE_S : SRV_ENCODE_BOUND_S, out);
}

static cJSON *pool_json(const srv_offload_status *p, double bound_s)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "threads", p->threads);
    cJSON_AddNumberToObject(o, "busy", p->busy);
    cJSON_AddNumberToObject(o, "queued", p->queued);
    cJSON_AddNumberToObject(o, "oldest_task_s", p->oldest_task_s);
    cJSON_AddNumberToObject(o, "bound_s", bound_s);
    cJSON_AddNumberToObject(o, "stuck", p->stuck);
    return o;
}

/* Liveness that tells the truth: 503 "stuck" when a task of the encoder or loader pool has
 * run longer than its bound (the pool no longer answers its requests); reads only the
 * pools' states under their short locks. */
static int healthz(srv_request *r)
{
    const srv_api *a = r->app;
    srv_offload_status enc, load;
    pool_status(a, false, &enc);
    pool_status(a, true, &load);
    bool stuck = enc.stuck || load.stuck;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "status", stuck ? "stuck" : "ok");
    cJSON_AddItemToObject(o, "encoders", pool_json(&enc, SRV_ENCODE_BOUND_S));
    cJSON_AddItemToObject(o, "loaders", pool_json(&load, a->max_load_s + SRV_LOAD_GRACE_S));
    return reply_cjson(r, stuck ? 503 : 200, o);
}

static int metrics(srv_request *r)
{
    srv_api *srv = r->app;
    int n = 0, by_state[5] = {0};
    double sps = 0;
    srv_job **jobs = srv_store_list(srv->store, &n);
    for (int i = 0; jobs && i < n; i++) {
        ts_job_state s = TS_JOB_FAILED;
        if (jobs[i]->sj && !jobs[i]->failure[0]) {
            ts_job_progress p;
            ts_sched_job_progress(jobs[i]->sj, &p);
            s = p.state;
            if (s == TS_JOB_RUNNING) sps += p.samples_per_s;
        }
        by_state[s]++;
        srv_job_release(jobs[i]);
    }
    free(jobs);
    char *buf = NULL;
    size_t len = 0, cap = 0;
    srv_buf_printf(&buf, &len, &cap, "# HELP tessera_jobs Jobs by state.\n# TYPE tessera_jobs gauge\n");
    for (int s = 0; s < 5; s++)
        srv_buf_printf(&buf, &len, &cap, "tessera_jobs{state=\"%s\"} %d\n", ts_job_state_name((ts_job_state)s), by_state[s]);
    srv_buf_printf(&buf, &len, &cap,
                   "# HELP tessera_queue_length Jobs waiting for their first tile.\n# TYPE tessera_queue_length gauge\n"
                   "tessera_queue_length %d\n"
                   "# HELP tessera_samples_total Camera samples rendered by this process.\n"
                   "# TYPE tessera_samples_total counter\ntessera_samples_total %llu\n"
                   "# HELP tessera_samples_per_second Sum of the running jobs' average sampling rates.\n"
                   "# TYPE tessera_samples_per_second gauge\ntessera_samples_per_second %.6g\n"
                   "# HELP tessera_render_threads Threads of the shared render pool.\n"
                   "# TYPE tessera_render_threads gauge\ntessera_render_threads %d\n",
                   by_state[TS_JOB_QUEUED], (unsigned long long)ts_scheduler_samples(srv->sched), sps,
                   ts_scheduler_threads(srv->sched));
    srv_buf_printf(&buf, &len, &cap,
                   "# HELP tessera_event_streams Event streams (SSE subscribers) open now.\n"
                   "# TYPE tessera_event_streams gauge\ntessera_event_streams %d\n"
                   "# HELP tessera_event_streams_dropped_total Event streams ended for falling too far behind.\n"
                   "# TYPE tessera_event_streams_dropped_total counter\ntessera_event_streams_dropped_total %llu\n",
                   atomic_load(&srv->sse_limits->total), (unsigned long long)atomic_load(&srv->sse_limits->dropped));
    if (srv->persist && srv->data_dir)
        srv_buf_printf(&buf, &len, &cap,
                       "# HELP tessera_checkpoint_temporaries_removed_total Temporary files of interrupted checkpoint writes removed (--data).\n"
                       "# TYPE tessera_checkpoint_temporaries_removed_total counter\ntessera_checkpoint_temporaries_removed_total %llu\n"
                       "# HELP tessera_checkpoint_stray_entries Entries under --data's jobs/ that are not job folders (ignored).\n"
                       "# TYPE tessera_checkpoint_stray_entries gauge\ntessera_checkpoint_stray_entries %llu\n"
                       "# HELP tessera_checkpoint_damaged_total Checkpoints refused at restore (their jobs render again).\n"
                       "# TYPE tessera_checkpoint_damaged_total counter\ntessera_checkpoint_damaged_total %llu\n"
                       "# HELP tessera_checkpoint_failures_total Checkpoint attempts that failed (retried with backoff).\n"
                       "# TYPE tessera_checkpoint_failures_total counter\ntessera_checkpoint_failures_total %llu\n",
                       (unsigned long long)atomic_load(&srv->persist->temporaries_removed),
                       (unsigned long long)atomic_load(&srv->persist->stray_entries),
                       (unsigned long long)atomic_load(&srv->persist->damaged),
                       (unsigned long long)atomic_load(&srv->persist->failures));
    srv_offload_status pools[2];
    pool_status(srv, false, &pools[0]);
    pool_status(srv, true, &pools[1]);
    srv_buf_printf(&buf, &len, &cap,
                   "# HELP tessera_loads_total Posted scenes (JSON and bundles) whose load began on a loader thread.\n"
                   "# TYPE tessera_loads_total counter\ntessera_loads_total %llu\n"
                   "# HELP tessera_loads_timed_out_total Loads stopped at --max-load-seconds, or whose time ran out while queued.\n"
                   "# TYPE tessera_loads_timed_out_total counter\ntessera_loads_timed_out_total %llu\n"
                   "# HELP tessera_loads_cancelled_total Loads stopped by the server's shutdown.\n"
                   "# TYPE tessera_loads_cancelled_total counter\ntessera_loads_cancelled_total %llu\n"
                   "# HELP tessera_loads_stuck Loads running longer than --max-load-seconds and its grace (/healthz: stuck).\n"
                   "# TYPE tessera_loads_stuck gauge\ntessera_loads_stuck %d\n",
                   srv->loads ? (unsigned long long)atomic_load(&srv->loads->started) : 0ull,
                   srv->loads ? (unsigned long long)atomic_load(&srv->loads->timed_out) : 0ull,
                   srv->loads ? (unsigned long long)atomic_load(&srv->loads->cancelled) : 0ull, pools[1].stuck);
    srv_buf_printf(&buf, &len, &cap, "# HELP tessera_pool_busy Threads of the pool running a task.\n# TYPE tessera_pool_busy gauge\n");
    for (int k = 0; k < 2; k++)
        srv_buf_printf(&buf, &len, &cap, "tessera_pool_busy{pool=\"%s\"} %d\n", k ? "loader" : "encoder", pools[k].busy);
    srv_buf_printf(&buf, &len, &cap, "# HELP tessera_pool_queued Tasks waiting for a thread of the pool.\n# TYPE tessera_pool_queued gauge\n");
    for (int k = 0; k < 2; k++)
        srv_buf_printf(&buf, &len, &cap, "tessera_pool_queued{pool=\"%s\"} %d\n", k ? "loader" : "encoder", pools[k].queued);
    srv_buf_printf(&buf, &len, &cap, "# HELP tessera_pool_stuck_tasks Tasks running longer than the pool's bound.\n# TYPE tessera_pool_stuck_tasks gauge\n");
    for (int k = 0; k < 2; k++)
        srv_buf_printf(&buf, &len, &cap, "tessera_pool_stuck_tasks{pool=\"%s\"} %d\n", k ? "loader" : "encoder", pools[k].stuck);
    srv_metrics_format(srv->metrics, &buf, &len, &cap);
    if (!buf) return srv_http_error(r, 500, "out of memory");
    int ret = srv_http_reply(r, 200, "text/plain; version=0.0.4; charset=utf-8", buf, len);
    free(buf);
    return ret;
}

static const char ui_html[] =
    "<!doctype html><html><head><meta charset=utf-8><title>tessera</title>"
    "<style>body{font:14px sans-serif;margin:2em}canvas{border:1px solid #ccc;image-rendering:pixelated}</style>"
    "</head><body><h1>tessera</h1><p id=s>loading…</p><canvas id=c></canvas><ul id=l></ul><script>\n"
    "const q=new URLSearchParams(location.search),tok=q.get('access_token'),"
    "h=tok?{Authorization:'Bearer '+tok}:{},ts=tok?'?access_token='+encodeURIComponent(tok):'';\n"
    "fetch('/api/v1/jobs',{headers:h}).then(r=>r.json()).then(d=>{const l=document.getElementById('l');"
    "for(const j of d.jobs){const e=document.createElement('li');e.innerHTML='<a href=\"'+j.urls.png+ts+'\">'+j.id+'</a> '+"
    "(j.name||'')+' '+j.state+' '+j.spp_done+'/'+j.spp_target+' spp';l.appendChild(e);}"
    "const j=d.jobs.find(j=>j.state=='running'||j.state=='queued')||d.jobs[0];if(!j){s.textContent='no jobs';return;}"
    "const c=document.getElementById('c'),x=c.getContext('2d');c.width=j.film.crop_width;c.height=j.film.crop_height;"
    "const es=new EventSource(j.urls.events+ts);es.addEventListener('tile',ev=>{const t=JSON.parse(ev.data),"
    "i=new Image();i.onload=()=>x.drawImage(i,t.x-j.film.x0,t.y-j.film.y0);i.src=t.png+ts;});"
    "es.addEventListener('progress',ev=>{const p=JSON.parse(ev.data);s.textContent=j.id+': '+p.state+', '+p.spp+'/'+"
    "p.spp_target+' spp, '+p.elapsed_s.toFixed(1)+' s';});es.addEventListener('done',()=>es.close());});\n"
    "</script></body></html>\n";

static int handle(srv_request *r)
{
    parsed p;
    parse_url(r->url, &p);
    const char *m = r->method;
    const srv_api *cfg = r->app;
    if (!strcmp(m, "OPTIONS") && cfg->cors_origin && p.route != SRV_ROUTE_OTHER) {
        struct MHD_Response *resp = MHD_create_response_from_buffer(0, (void *)"", MHD_RESPMEM_PERSISTENT);
        MHD_add_response_header(resp, "Access-Control-Allow-Methods", "GET, POST, DELETE, OPTIONS");
        MHD_add_response_header(resp, "Access-Control-Allow-Headers", "Authorization, Content-Type");
        MHD_add_response_header(resp, "Access-Control-Max-Age", "600");
        return srv_http_queue(r, 204, resp);
    }
    char host[160];
    if (!host_allowed(r, host, sizeof host))
        return srv_http_error(r, 403, "Host '%s' is not a name of this server (tessera serve --bind, --allowed-hosts)",
                              host);
    if (!origin_allowed(r))
        return srv_http_error(r, 403, "requests from another site's pages are refused (Origin is not this server's "
                                      "and not --cors-origin)");
    if (p.route == SRV_ROUTE_OTHER) return srv_http_error(r, 404, "no such resource: %s", r->url);
    bool get = !strcmp(m, "GET") || !strcmp(m, "HEAD");
    if (p.route != SRV_ROUTE_UI && p.route != SRV_ROUTE_HEALTHZ && !authorised(r)) {
        return srv_http_error_header(r, 401, MHD_HTTP_HEADER_WWW_AUTHENTICATE, "Bearer realm=\"tessera\"",
                                     "this server needs a bearer token: Authorization: Bearer <token>");
    }
    /* A cancel carries nothing: with no body and no Content-Type it is accepted (a page of
     * another site that sends it names its Origin, refused above); a body still needs a type. */
    bool bare_cancel = p.route == SRV_ROUTE_CANCEL && !r->body_len &&
                       !MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    if (!strcmp(m, "POST") && !bare_cancel && !post_type_ok(r, p.route)) {
        const char *type = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
        if (p.route == SRV_ROUTE_JOBS)
            return srv_http_error(r, 415,
                                  "a job is posted as JSON (Content-Type: application/json) or as a tar bundle of a scene "
                                  "with its files (application/x-tar, optionally gzip-compressed); got %s",
                                  type ? type : "none");
        return srv_http_error(r, 415,
                              "a POST needs Content-Type: application/json (an empty body is fine): pages of other sites "
                              "cannot send it (got %s)",
                              type ? type : "none");
    }
    switch (p.route) {
    case SRV_ROUTE_UI:
        if (!get) return srv_http_method_not_allowed(r, "GET, HEAD");
        if (srv_asset_find(r->url)) /* the embedded web UI (server/assets.h); else the minimal page */
            return srv_http_reply(r, 200, srv_asset_find(r->url)->content_type, srv_asset_find(r->url)->data,
                                  srv_asset_find(r->url)->size);
        return srv_http_reply(r, 200, "text/html; charset=utf-8", ui_html, sizeof ui_html - 1);
    case SRV_ROUTE_HEALTHZ:
        if (!get) return srv_http_method_not_allowed(r, "GET, HEAD");
        return healthz(r);
    case SRV_ROUTE_METRICS:
        if (!get) return srv_http_method_not_allowed(r, "GET, HEAD");
        return metrics(r);
    case SRV_ROUTE_LIMITS: {
        if (!get) return srv_http_method_not_allowed(r, "GET, HEAD");
        const struct srv_api_limits *l = &cfg->limits;
        char body[400];
        snprintf(body, sizeof body,
                 "{\"max_spp\":%u,\"max_resolution\":%u,\"max_pixels\":%llu,\"max_work\":%.17g,\"max_body\":%llu,"
                 "\"max_bundle_bytes\":%llu,\"bundles\":%s}",
                 l->max_spp, l->max_resolution, (unsigned long long)l->max_pixels, l->max_work,
                 (unsigned long long)l->max_body, (unsigned long long)l->max_bundle_bytes,
                 cfg->bundle && cfg->files_root ? "true" : "false");
        return srv_http_reply_json(r, 200, body);
    }
    case SRV_ROUTE_JOBS:
        if (!strcmp(m, "POST") &&
            srv_bundle_media_type(MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE)))
            return post_bundle(r);
        if (!strcmp(m, "POST")) return post_job(r);
        if (!get) return srv_http_method_not_allowed(r, "GET, HEAD, POST");
        return list_jobs(r);
    default: break;
    }
    bool is_job = p.route == SRV_ROUTE_JOB, is_cancel = p.route == SRV_ROUTE_CANCEL;
    if (is_cancel ? strcmp(m, "POST") != 0 : !(get || (is_job && !strcmp(m, "DELETE"))))
        return srv_http_method_not_allowed(r, is_cancel ? "POST" : is_job ? "GET, HEAD, DELETE" : "GET, HEAD");
    srv_job *j = srv_store_get(cfg->store, p.id);
    if (!j) return srv_http_error(r, 404, "no job with id '%s'", p.id);
    switch (p.route) {
    case SRV_ROUTE_JOB: {
        if (!strcmp(m, "DELETE")) {
            /* Only a job that has ended is removed (its --max-jobs slot and its files are
             * freed); cancelling is POST …/cancel, so a retried request never deletes. */
            if (!j->failure[0] && !ts_job_state_finished(srv_job_state(j))) {
                ts_job_progress jp;
                ts_sched_job_progress(j->sj, &jp);
                const char *state = srv_job_state_name(j, &jp);
                srv_job_release(j);
                return srv_http_error(r, 409, "job '%s' is %s, not ended; cancel it first (POST %s/%s/cancel)", p.id,
                                      state, API_PREFIX, p.id);
            }
            bool removed = srv_store_remove(cfg->store, j);
            if (removed && j->external) srv_farm_forget(cfg->farm, j); /* its folder under --farm-dir */
            if (removed && cfg->data_dir) srv_persist_remove(cfg->data_dir, j); /* the bundle's folder with it */
            else if (removed && j->files_dir) {
                char folder[4096];
                const char *root = srv_bundle_root_get(cfg->files_root);
                snprintf(folder, sizeof folder, "%s/jobs/%s", root ? root : "", j->id);
                if (srv_bundle_remove_tree(folder) != 0)
                    fprintf(stderr, "tessera: removing %s: %s\n", folder, strerror(errno));
            }
            srv_job_release(j);
            return srv_http_reply(r, 204, NULL, "", 0);
        }
        cJSON *o = srv_job_status_json(j);
        srv_job_release(j);
        return reply_cjson(r, 200, o);
    }
    case SRV_ROUTE_CANCEL: {
        /* Idempotent: cancelling an ended job changes nothing; the answer is the job's
         * state, "cancelling" while its last tiles finish, then "cancelled". */
        if (j->sj) ts_sched_job_cancel(j->sj);
        cJSON *o = srv_job_status_json(j);
        srv_job_release(j);
        return reply_cjson(r, 200, o);
    }
    case SRV_ROUTE_HISTORY: {
        cJSON *o = srv_job_history_json(j);
        srv_job_release(j);
        if (!o) return srv_http_error(r, 500, "out of memory");
        return reply_cjson(r, 200, o);
    }
    case SRV_ROUTE_EVENTS: return get_events(r, j);
    case SRV_ROUTE_IMAGE:
    case SRV_ROUTE_TILE: return get_image(r, j, &p);
    default: srv_job_release(j); return srv_http_error(r, 404, "no such resource: %s", r->url);
    }
}

srv_http_handlers srv_api_handlers(srv_api *api)
{
    return (srv_http_handlers){srv_api_route, handle, request_done, api};
}
