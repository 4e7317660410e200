/* api.c — HTTP API v1 routes; see api.h and proto/openapi.yaml. */
#include "api.h"

#include <microhttpd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>

#include "assets.h"
#include "job_store.h"
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

static void parse_url(const char *url, parsed *p)
{
    memset(p, 0, sizeof *p);
    p->route = SRV_ROUTE_OTHER;
    if (!strcmp(url, "/") || !strcmp(url, "/index.html") || srv_asset_find(url)) p->route = SRV_ROUTE_UI;
    else if (!strcmp(url, "/healthz")) p->route = SRV_ROUTE_HEALTHZ;
    else if (!strcmp(url, "/metrics")) p->route = SRV_ROUTE_METRICS;
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
            char ext[8] = "";
            int tx, ty, used = 0;
            if (sscanf(slash + 7, "%d/%d.%4[a-z]%n", &tx, &ty, ext, &used) == 3 && slash[7 + used] == '\0' &&
                (!strcmp(ext, "png") || !strcmp(ext, "exr"))) {
                p->route = SRV_ROUTE_TILE;
                p->tx = tx, p->ty = ty, p->png = !strcmp(ext, "png");
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

/* True when given equals the configured token. The time taken depends only on the
 * configured token's length, never on where the first difference is: every byte of the
 * token is compared (no early exit; past the end of given, its terminating NUL is used),
 * and a length mismatch is folded into the result rather than tested first. */
static bool token_matches(const char *given, const char *token)
{
    size_t a = strlen(given), b = strlen(token);
    volatile unsigned diff = a != b;
    for (size_t i = 0; i < b; i++) diff |= (unsigned char)token[i] ^ (unsigned char)given[i < a ? i : a];
    return diff == 0;
}

static bool authorised(srv_request *r)
{
    const char *token = ((srv_api *)r->app)->token;
    if (!token) return true;
    const char *h = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION);
    const char *given = NULL;
    if (h && !strncasecmp(h, "Bearer ", 7)) given = h + 7;
    /* EventSource cannot send headers: the token may come as ?access_token=. */
    if (!given) given = MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, "access_token");
    return given && token_matches(given, token);
}

/* ---------------------------------------------------------------- images (deferred) */

typedef struct image_task {
    srv_job *job;
    bool tile, png;
    int tx, ty;
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
        ts_render_info info = {sc ? sc->name : NULL, j->integrator, p.spp_done, sc != NULL, sc ? sc->sampler.seed : 0,
                               p.elapsed_s, t->tile ? -1 : ts_film_relative_error(film), (double)p.nonfinite,
                               t->tile ? NULL : j->id};
        st = ts_image_set_render_info(&img, &info, &err);
        if (!st) st = t->png ? ts_png_encode(&img, 0.0f, &buf, &len, &err) : ts_exr_write_memory(&img, &buf, &len, &err);
    }
    ts_image_fini(&img);
    ts_film_destroy(film);
    if (st) {
        char msg[700];
        snprintf(msg, sizeof msg, "{\"error\":\"encoding failed: %s\",\"status\":500}", err.message);
        r->reply_body = (unsigned char *)strdup(msg);
        r->reply_len = r->reply_body ? strlen(msg) : 0;
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

static int post_job(srv_request *r)
{
    const char *type = MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    if (type && strncasecmp(type, "application/json", 16) != 0 && strncasecmp(type, "text/plain", 10) != 0 &&
        strncasecmp(type, "application/x-www-form-urlencoded", 33) != 0)
        return srv_http_error(r, 415, "a job is a JSON scene document (Content-Type: application/json), not %s", type);
    if (!r->body_len) return srv_http_error(r, 400, "the request body is empty: send a scene document (JSON)");
    ts_error err = {0};
    int status = 500;
    srv_job *j = srv_store_submit(((srv_api *)r->app)->store, r->body, r->body_len, &status, &err);
    if (!j) return srv_http_error(r, (unsigned)status, "%s", err.message);
    if (((srv_api *)r->app)->data_dir) {
        /* On disk before the 201: an accepted job is not lost to a crash before its first
         * checkpoint. If that fails the job renders on and its status says why. */
        ts_error perr = {0};
        if (srv_persist_save_submitted(((srv_api *)r->app)->data_dir, j, &perr) && srv_job_set_checkpoint_error(j, perr.message))
            fprintf(stderr, "tessera: recording job %s failed, it renders on unrecorded: %s\n", j->id, perr.message);
    }
    cJSON *o = srv_job_status_json(j);
    char loc[96];
    snprintf(loc, sizeof loc, API_PREFIX "/%s", j->id);
    srv_job_release(j);
    char *s = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    if (!s) return srv_http_error(r, 500, "out of memory");
    struct MHD_Response *resp = MHD_create_response_from_buffer(strlen(s), s, MHD_RESPMEM_MUST_FREE);
    if (!resp) {
        free(s);
        return MHD_NO;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "application/json");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_LOCATION, loc);
    return srv_http_queue(r, 201, resp);
}

static int list_jobs(srv_request *r)
{
    int n = 0;
    srv_job **jobs = srv_store_list(((srv_api *)r->app)->store, &n);
    if (!jobs) return srv_http_error(r, 500, "out of memory");
    cJSON *o = cJSON_CreateObject();
    cJSON *arr = cJSON_AddArrayToObject(o, "jobs");
    for (int i = 0; i < n; i++) {
        cJSON_AddItemToArray(arr, srv_job_status_json(jobs[i]));
        srv_job_release(jobs[i]);
    }
    free(jobs);
    return reply_cjson(r, 200, o);
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
    if (p.route == SRV_ROUTE_OTHER) return srv_http_error(r, 404, "no such resource: %s", r->url);
    bool get = !strcmp(m, "GET") || !strcmp(m, "HEAD");
    if (p.route != SRV_ROUTE_UI && p.route != SRV_ROUTE_HEALTHZ && !authorised(r)) {
        const char *msg = "{\"error\":\"this server needs a bearer token: Authorization: Bearer <token>\",\"status\":401}";
        struct MHD_Response *resp = MHD_create_response_from_buffer(strlen(msg), (void *)msg, MHD_RESPMEM_PERSISTENT);
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, "application/json");
        MHD_add_response_header(resp, MHD_HTTP_HEADER_WWW_AUTHENTICATE, "Bearer realm=\"tessera\"");
        return srv_http_queue(r, 401, resp);
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
        return srv_http_reply_json(r, 200, "{\"status\":\"ok\"}");
    case SRV_ROUTE_METRICS:
        if (!get) return srv_http_method_not_allowed(r, "GET, HEAD");
        return metrics(r);
    case SRV_ROUTE_JOBS:
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
                srv_job_release(j);
                return srv_http_error(r, 409, "job '%s' has not ended; cancel it first (POST %s/%s/cancel)", p.id,
                                      API_PREFIX, p.id);
            }
            if (srv_store_remove(cfg->store, j) && cfg->data_dir) srv_persist_remove(cfg->data_dir, j);
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
