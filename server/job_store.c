/* job_store.c — jobs, their events and status documents; see job_store.h. */
#include "job_store.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "tessera.h"

struct srv_store {
    srv_store_config cfg; /* immutable */
    pthread_mutex_t mu;
    srv_job *jobs; /* guarded by mu: newest first */
    int n_jobs;    /* guarded by mu: jobs in the list */
    int n_pending; /* guarded by mu: submissions that hold a slot and are not in the list yet */
};

srv_store *srv_store_create(const srv_store_config *cfg)
{
    srv_store *st = calloc(1, sizeof *st);
    if (!st) return NULL;
    st->cfg = *cfg;
    pthread_mutex_init(&st->mu, NULL);
    return st;
}

void srv_store_set_describe_user(srv_store *st, void *user) { st->cfg.describe_user = user; }

void srv_warnings_collect(void *ctx, const char *msg)
{
    srv_warnings *w = ctx;
    char *copy = w->n < SRV_WARNINGS_MAX ? strdup(msg) : NULL;
    char **items = copy ? realloc(w->items, (size_t)(w->n + 1) * sizeof *items) : NULL;
    if (!items) {
        free(copy);
        w->dropped++;
        return;
    }
    items[w->n++] = copy;
    w->items = items;
}

void srv_warnings_fini(srv_warnings *w)
{
    for (int i = 0; i < w->n; i++) free(w->items[i]);
    free(w->items);
    *w = (srv_warnings){0};
}

static void job_free(srv_job *j)
{
    srv_display_destroy(j->display); /* finished by on_done: returns at once */
    ts_sched_job_release(j->sj);
    srv_events_destroy(j->events);
    pthread_mutex_destroy(&j->ckpt_mu);
    pthread_mutex_destroy(&j->disk_mu);
    pthread_mutex_destroy(&j->hist_mu);
    free(j->hist);
    free(j->name);
    free(j->scene_text);
    free(j->files_dir);
    srv_warnings_fini(&j->warnings);
    free(j);
}

void srv_job_retain(srv_job *j) { atomic_fetch_add(&j->refs, 1); }

void srv_job_release(srv_job *j)
{
    if (j && atomic_fetch_sub(&j->refs, 1) == 1) job_free(j);
}

static void release_for_scheduler(srv_job *j);

void srv_store_destroy(srv_store *st)
{
    if (!st) return;
    srv_job *j = st->jobs;
    while (j) {
        srv_job *next = j->next;
        release_for_scheduler(j); /* the scheduler is gone: no callback runs any more */
        srv_job_release(j);
        j = next;
    }
    pthread_mutex_destroy(&st->mu);
    free(st);
}

static void store_add(srv_store *st, srv_job *j)
{
    atomic_fetch_add(&j->refs, 1); /* the store's reference */
    pthread_mutex_lock(&st->mu);
    j->next = st->jobs;
    st->jobs = j;
    st->n_jobs++;
    pthread_mutex_unlock(&st->mu);
}

srv_job *srv_store_get(srv_store *st, const char *id)
{
    pthread_mutex_lock(&st->mu);
    srv_job *j = st->jobs;
    while (j && strcmp(j->id, id) != 0) j = j->next;
    if (j) atomic_fetch_add(&j->refs, 1);
    pthread_mutex_unlock(&st->mu);
    return j;
}

bool srv_store_remove(srv_store *st, srv_job *j)
{
    pthread_mutex_lock(&st->mu);
    srv_job **link = &st->jobs;
    while (*link && *link != j) link = &(*link)->next;
    bool found = *link == j;
    if (found) {
        *link = j->next;
        j->next = NULL;
        st->n_jobs--;
    }
    pthread_mutex_unlock(&st->mu);
    if (found) srv_job_release(j); /* the list's reference */
    return found;
}

srv_job **srv_store_list(srv_store *st, int *n)
{
    pthread_mutex_lock(&st->mu);
    int count = 0;
    for (srv_job *j = st->jobs; j; j = j->next) count++;
    srv_job **a = malloc(sizeof *a * (size_t)(count ? count : 1));
    *n = 0;
    if (a)
        for (srv_job *j = st->jobs; j; j = j->next) {
            atomic_fetch_add(&j->refs, 1);
            a[(*n)++] = j;
        }
    pthread_mutex_unlock(&st->mu);
    return a;
}

/* ---------------------------------------------------------------- events */

static char *print_and_delete(cJSON *o)
{
    char *s = o ? cJSON_PrintUnformatted(o) : NULL;
    cJSON_Delete(o);
    return s;
}

/* item: the tile the event is about (its index in the grid), or -1 (events.h). */
static void publish_json(srv_job *j, const char *name, cJSON *o, int item)
{
    char *s = print_and_delete(o);
    if (s) srv_events_publish(j->events, name, s, item);
    free(s);
}

cJSON *srv_job_tile_json(const srv_job *j, const ts_tile_event *ev)
{
    cJSON *o = cJSON_CreateObject();
    char url[160];
    cJSON_AddNumberToObject(o, "tx", ev->tx);
    cJSON_AddNumberToObject(o, "ty", ev->ty);
    cJSON_AddNumberToObject(o, "x", ev->x);
    cJSON_AddNumberToObject(o, "y", ev->y);
    cJSON_AddNumberToObject(o, "w", ev->w);
    cJSON_AddNumberToObject(o, "h", ev->h);
    cJSON_AddNumberToObject(o, "spp", ev->spp);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/tiles/%d/%d.png", j->id, ev->tx, ev->ty);
    cJSON_AddStringToObject(o, "png", url);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/tiles/%d/%d.exr", j->id, ev->tx, ev->ty);
    cJSON_AddStringToObject(o, "exr", url);
    return o;
}

char *srv_job_tile_event(const srv_job *j, const ts_tile_event *ev)
{
    bool plain = j->id[0] != '\0';
    for (const char *c = j->id; *c; c++)
        plain = plain && ((*c >= '0' && *c <= '9') || (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                          *c == '-' || *c == '_');
    if (!plain) { /* an id JSON must escape (never one the server makes): through cJSON */
        char *doc = print_and_delete(srv_job_tile_json(j, ev));
        char *e = doc ? srv_events_format("tile", doc) : NULL;
        free(doc);
        return e;
    }
    char *e = malloc(512);
    if (e)
        snprintf(e, 512,
                 "event: tile\ndata: {\"tx\":%d,\"ty\":%d,\"x\":%d,\"y\":%d,\"w\":%d,\"h\":%d,\"spp\":%u,"
                 "\"png\":\"/api/v1/jobs/%s/tiles/%d/%d.png\",\"exr\":\"/api/v1/jobs/%s/tiles/%d/%d.exr\"}\n\n",
                 ev->tx, ev->ty, ev->x, ev->y, ev->w, ev->h, ev->spp, j->id, ev->tx, ev->ty, j->id, ev->tx, ev->ty);
    return e;
}

static void on_tile(void *user, ts_sched_job *sj, const ts_tile_event *ev)
{
    srv_job *j = user;
    atomic_fetch_add(&j->version, 1);
    if (j->display) srv_display_tile(j->display, sj, ev);
    char *e = srv_job_tile_event(j, ev);
    if (e) srv_events_publish_frame(j->events, e, ev->ty * j->nx + ev->tx);
    free(e);
    if (!atomic_exchange(&j->started_logged, true) && srv_log_enabled(j->store->cfg.log, SRV_LOG_INFO)) {
        ts_job_progress p;
        ts_sched_job_progress(sj, &p);
        srv_log_field f[] = {SRV_LOG_STR("id", j->id), SRV_LOG_NUM("queued_s", p.queued_s)};
        srv_log_event(j->store->cfg.log, SRV_LOG_INFO, "job.started", f, 2);
    }
}

/* ---------------------------------------------------------------- log */

static void log_progress(srv_job *j, const char *event, const ts_job_progress *p)
{
    srv_log *l = j->store->cfg.log;
    if (!srv_log_enabled(l, SRV_LOG_INFO)) return;
    srv_log_field f[] = {SRV_LOG_STR("id", j->id),
                         SRV_LOG_STR("state", srv_job_state_name(j, p)),
                         SRV_LOG_STR("halt", ts_halt_reason_name(p->halt)),
                         SRV_LOG_NUM("spp", p->spp_done),
                         SRV_LOG_NUM("spp_target", p->spp_target),
                         SRV_LOG_NUM("elapsed_s", p->elapsed_s),
                         SRV_LOG_NUM_OR_NULL("error_estimate", p->error_estimate),
                         SRV_LOG_NUM("samples_per_s", p->samples_per_s),
                         SRV_LOG_NUM_OR_NULL("eta_s", p->eta_s),
                         SRV_LOG_NUM("nonfinite_samples", (double)p->nonfinite),
                         SRV_LOG_NUM("walks_truncated", (double)p->walks_truncated)};
    srv_log_event(l, SRV_LOG_INFO, event, f, sizeof f / sizeof *f);
}

/* ---------------------------------------------------------------- history */

static void add_number_or_null(cJSON *o, const char *k, double v, bool known);

static void history_add(srv_job *j, const srv_history_point *pt)
{
    pthread_mutex_lock(&j->hist_mu);
    if (j->n_hist == SRV_HISTORY_MAX) { /* thin the ticks: keep pass ends, every other tick */
        int k = 0;
        bool keep = true;
        for (int i = 0; i < j->n_hist; i++) {
            if (j->hist[i].kind == 't') keep = !keep;
            if (j->hist[i].kind != 't' || keep) j->hist[k++] = j->hist[i];
        }
        j->n_hist = k;
    }
    if (j->n_hist == j->cap_hist && j->n_hist < SRV_HISTORY_MAX) {
        int cap = j->cap_hist ? 2 * j->cap_hist : 64;
        if (cap > SRV_HISTORY_MAX) cap = SRV_HISTORY_MAX;
        srv_history_point *h = realloc(j->hist, sizeof *h * (size_t)cap);
        if (h) j->hist = h, j->cap_hist = cap;
    }
    if (j->n_hist < j->cap_hist) j->hist[j->n_hist++] = *pt; /* out of memory: the point is lost */
    pthread_mutex_unlock(&j->hist_mu);
}

static void history_add_progress(srv_job *j, const ts_job_progress *p, char kind)
{
    /* One quantity at every kind of point, as the status's and events' spp_mean: samples held
     * ÷ pixels, which only grows (a pass end's is its spp; issue #32.2: ticks carried it and
     * pass ends spp_done, so a plot of both with live spp_done went backwards mid-pass). */
    (void)kind;
    srv_history_point pt = {p->elapsed_s, p->spp_fraction, p->error_estimate, p->samples_per_s, kind};
    history_add(j, &pt);
}

void srv_job_tick(srv_job *j)
{
    if (!j->sj) return;
    ts_job_progress p;
    ts_sched_job_progress(j->sj, &p);
    if (p.state != TS_JOB_RUNNING) return;
    history_add_progress(j, &p, 't');
    publish_json(j, "progress", srv_job_progress_json(j, &p), -1);
}

cJSON *srv_job_history_json(srv_job *j)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *a = cJSON_AddArrayToObject(o, "points");
    cJSON_AddStringToObject(o, "id", j->id);
    pthread_mutex_lock(&j->hist_mu);
    for (int i = 0; a && i < j->n_hist; i++) {
        const srv_history_point *pt = &j->hist[i];
        cJSON *e = cJSON_CreateObject();
        cJSON_AddNumberToObject(e, "elapsed_s", pt->elapsed_s);
        cJSON_AddNumberToObject(e, "spp", pt->spp);
        add_number_or_null(e, "error_estimate", pt->error_estimate, pt->error_estimate >= 0);
        cJSON_AddNumberToObject(e, "samples_per_s", pt->samples_per_s);
        cJSON_AddStringToObject(e, "kind", pt->kind == 'p' ? "pass" : pt->kind == 't' ? "tick" : "done");
        cJSON_AddItemToArray(a, e);
    }
    pthread_mutex_unlock(&j->hist_mu);
    if (!a || cJSON_GetArraySize(a) != j->n_hist) { /* out of memory */
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

/* Restores the series of a checkpoint (points that are not well-formed are skipped). */
static void history_restore(srv_job *j, const cJSON *a)
{
    const cJSON *e;
    cJSON_ArrayForEach(e, a)
    {
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(e, "elapsed_s"), *n = cJSON_GetObjectItemCaseSensitive(e, "spp"),
                    *er = cJSON_GetObjectItemCaseSensitive(e, "error_estimate"),
                    *r = cJSON_GetObjectItemCaseSensitive(e, "samples_per_s"),
                    *k = cJSON_GetObjectItemCaseSensitive(e, "kind");
        if (!cJSON_IsNumber(t) || !cJSON_IsNumber(n) || !cJSON_IsNumber(r) || !cJSON_IsString(k)) continue;
        srv_history_point pt = {t->valuedouble, n->valuedouble, cJSON_IsNumber(er) ? er->valuedouble : -1,
                                r->valuedouble, k->valuestring[0] == 'p' ? 'p' : k->valuestring[0] == 't' ? 't' : 'd'};
        history_add(j, &pt);
    }
}

static void on_pass(void *user, ts_sched_job *sj, const ts_job_progress *p)
{
    (void)sj;
    srv_job *j = user;
    history_add_progress(j, p, 'p');
    publish_json(j, "progress", srv_job_progress_json(j, p), -1);
    log_progress(j, "job.pass", p);
}

static void on_done(void *user, ts_sched_job *sj, const ts_job_progress *p)
{
    (void)sj;
    srv_job *j = user;
    history_add_progress(j, p, 'd');
    log_progress(j, p->state == TS_JOB_CANCELLED ? "job.cancelled" : p->state == TS_JOB_FAILED ? "job.failed" : "job.finished", p);
    atomic_fetch_add(&j->version, 1);
    publish_json(j, "progress", srv_job_progress_json(j, p), -1);
    publish_json(j, "done", srv_job_progress_json(j, p), -1);
    srv_events_close(j->events);
    if (j->display) srv_display_finish(j->display);
    if (j->store->cfg.on_job_finished) j->store->cfg.on_job_finished(j->store->cfg.user);
    /* The scheduler's reference, last: the job's state reads finished before this callback
     * runs, so a DELETE may drop the store's reference meanwhile (this one keeps j alive). */
    if (atomic_exchange(&j->sched_ref, false)) srv_job_release(j);
}

/* A reference for the scheduler's callbacks, taken before the job is submitted (its
 * on_done may run before ts_scheduler_submit returns) and dropped by on_done; undone when
 * the submission failed; a job that never ends (the server stopped first) gives it back
 * in srv_store_destroy. */
static void retain_for_scheduler(srv_job *j)
{
    srv_job_retain(j);
    atomic_store(&j->sched_ref, true);
}

static void release_for_scheduler(srv_job *j)
{
    if (atomic_exchange(&j->sched_ref, false)) srv_job_release(j);
}

/* ---------------------------------------------------------------- creation */

/* The display server a job of scene s streams to, or NULL; a job.display_server this
 * server does not allow gives NULL (at submit it was refused before; a restored job keeps
 * rendering without it when the server was restarted with other options). */
static const char *display_for(const srv_store_config *cfg, const ts_scene *s)
{
    const char *want = s ? s->job.display_server : NULL;
    if (!want) return cfg->display_server;
    if (cfg->allow_job_display_server || (cfg->display_server && strcmp(cfg->display_server, want) == 0)) return want;
    return NULL;
}

/* Starts j's display (when it has one): the image is called "NAME (ID)" or "ID". */
static bool start_display(srv_job *j, const char *address, ts_error *err)
{
    if (!address) return true;
    char name[SRV_DISPLAY_NAME_MAX];
    if (j->name) snprintf(name, sizeof name, "%s (%s)", j->name, j->id);
    else snprintf(name, sizeof name, "%s", j->id);
    return (j->display = srv_display_create(address, name, err)) != NULL;
}

static void make_id(char *out, size_t n)
{
    unsigned char b[8];
    if (getrandom(b, sizeof b, 0) != (ssize_t)sizeof b) {
        struct timespec t;
        clock_gettime(CLOCK_REALTIME, &t);
        uint64_t v = (uint64_t)t.tv_sec * 1000000007ull ^ (uint64_t)t.tv_nsec ^ (uint64_t)(uintptr_t)out;
        memcpy(b, &v, sizeof b);
    }
    snprintf(out, n, "%02x%02x%02x%02x%02x%02x%02x%02x", b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]);
}

static srv_job *job_new(srv_store *st, const char *id, const char *text, size_t len)
{
    srv_job *j = calloc(1, sizeof *j);
    if (!j) return NULL;
    atomic_init(&j->refs, 1);
    atomic_init(&j->version, 1);
    pthread_mutex_init(&j->ckpt_mu, NULL);
    pthread_mutex_init(&j->disk_mu, NULL);
    pthread_mutex_init(&j->hist_mu, NULL);
    j->store = st;
    j->events = srv_events_create();
    j->scene_text = malloc(len + 1);
    if (!j->events || !j->scene_text) {
        job_free(j);
        return NULL;
    }
    memcpy(j->scene_text, text, len);
    j->scene_text[len] = '\0';
    j->scene_len = len;
    if (id) snprintf(j->id, sizeof j->id, "%s", id);
    else make_id(j->id, sizeof j->id);
    return j;
}

/* False when out of memory for the name. */
static bool describe_scene(srv_job *j, const ts_scene *s)
{
    const char *name = ts_job_name(s);
    if (!j->name && name && !(j->name = strdup(name))) return false;
    snprintf(j->integrator, sizeof j->integrator, "%s", ts_integrator_name(s->integrator.type));
    ts_effects_format(s->effects, j->effects, sizeof j->effects);
    j->full_w = s->width, j->full_h = s->height;
    j->x0 = s->crop_x0, j->y0 = s->crop_y0, j->w = s->crop_x1 - s->crop_x0, j->h = s->crop_y1 - s->crop_y0;
    j->nx = (j->w + TS_TILE_SIZE - 1) / TS_TILE_SIZE;
    j->ny = (j->h + TS_TILE_SIZE - 1) / TS_TILE_SIZE;
    return true;
}

/* Takes a slot for one more job if the store holds fewer than cfg.max_jobs (0: no limit),
 * counting submissions under way, so concurrent POSTs cannot overshoot. */
static bool reserve_slot(srv_store *st, int max_jobs)
{
    pthread_mutex_lock(&st->mu);
    bool ok = max_jobs <= 0 || st->n_jobs + st->n_pending < max_jobs;
    if (ok) st->n_pending++;
    pthread_mutex_unlock(&st->mu);
    return ok;
}

static void release_slot(srv_store *st)
{
    pthread_mutex_lock(&st->mu);
    st->n_pending--;
    pthread_mutex_unlock(&st->mu);
}

static srv_job *submit(srv_store *st, const char *text, size_t len, const char *name, const srv_submit_files *files,
                       ts_cancel *cancel, bool external, int *http_status, ts_error *err);
static srv_job *submit_reserved(srv_store *st, const char *text, size_t len, const char *name,
                                const srv_submit_files *files, ts_cancel *cancel, bool external, int *http_status,
                                ts_error *err);

bool srv_store_has_room(srv_store *st)
{
    pthread_mutex_lock(&st->mu);
    bool ok = st->cfg.max_jobs <= 0 || st->n_jobs + st->n_pending < st->cfg.max_jobs;
    pthread_mutex_unlock(&st->mu);
    return ok;
}

srv_job *srv_store_submit(srv_store *st, const char *text, size_t len, int *http_status, ts_error *err)
{
    return submit_reserved(st, text, len, NULL, NULL, NULL, false, http_status, err);
}

srv_job *srv_store_submit_named(srv_store *st, const char *text, size_t len, const char *name, int *http_status,
                                ts_error *err)
{
    return submit_reserved(st, text, len, name, NULL, NULL, false, http_status, err);
}

srv_job *srv_store_submit_files(srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                                int *http_status, ts_error *err)
{
    return submit_reserved(st, text, len, files->name, files, NULL, false, http_status, err);
}

srv_job *srv_store_submit_cancellable(srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                                      ts_cancel *cancel, int *http_status, ts_error *err)
{
    return submit_reserved(st, text, len, files ? files->name : NULL, files, cancel, false, http_status, err);
}

srv_job *srv_store_submit_external(srv_store *st, const char *text, size_t len, const srv_submit_files *files,
                                   ts_cancel *cancel, int *http_status, ts_error *err)
{
    return submit_reserved(st, text, len, files ? files->name : NULL, files, cancel, true, http_status, err);
}

static srv_job *submit_reserved(srv_store *st, const char *text, size_t len, const char *name,
                                const srv_submit_files *files, ts_cancel *cancel, bool external, int *http_status,
                                ts_error *err)
{
    /* Checked before the document is parsed: a full server allocates nothing for it. */
    int max_jobs = st->cfg.max_jobs;
    if (!reserve_slot(st, max_jobs)) {
        *http_status = 503;
        ts_error_set(err, TS_ERR_LIMIT,
                     "this server already holds %d jobs, its limit (--max-jobs); no new job can be queued", max_jobs);
        return NULL;
    }
    srv_job *j = submit(st, text, len, name, files, cancel, external, http_status, err);
    release_slot(st); /* after store_add: the job now counts in n_jobs */
    return j;
}

/* Moves a bundle's unpacked folder to ROOT/jobs/<id>/files: false with errno on failure. */
static bool move_files(const srv_submit_files *files, const char *id, char **out)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/jobs", files->files_root);
    if (mkdir(path, 0700) != 0 && errno != EEXIST) return false;
    snprintf(path, sizeof path, "%s/jobs/%s", files->files_root, id);
    if (mkdir(path, 0700) != 0 && errno != EEXIST) return false;
    snprintf(path, sizeof path, "%s/jobs/%s/files", files->files_root, id);
    if (rename(files->staging_dir, path) != 0) {
        int e = errno;
        snprintf(path, sizeof path, "%s/jobs/%s", files->files_root, id);
        rmdir(path);
        errno = e;
        return false;
    }
    if (!(*out = strdup(path))) {
        /* Put it back, so the caller's clean-up finds it. */
        (void)rename(path, files->staging_dir);
        snprintf(path, sizeof path, "%s/jobs/%s", files->files_root, id);
        rmdir(path);
        errno = ENOMEM;
        return false;
    }
    return true;
}

/* One `job.warning` line (level warn) per import warning of j, and one counting those not kept. */
static void log_warnings(srv_log *log, const srv_job *j)
{
    if (!srv_log_enabled(log, SRV_LOG_WARN)) return;
    for (int i = 0; i < j->warnings.n; i++) {
        srv_log_field f[] = {SRV_LOG_STR("id", j->id), SRV_LOG_STR("message", j->warnings.items[i])};
        srv_log_event(log, SRV_LOG_WARN, "job.warning", f, 2);
    }
    if (j->warnings.dropped) {
        srv_log_field f[] = {SRV_LOG_STR("id", j->id), SRV_LOG_NUM("more_warnings", j->warnings.dropped)};
        srv_log_event(log, SRV_LOG_WARN, "job.warning", f, 2);
    }
}

static srv_job *submit(srv_store *st, const char *text, size_t len, const char *name, const srv_submit_files *files,
                       ts_cancel *cancel, bool external, int *http_status, ts_error *err)
{
    const srv_store_config *cfg = &st->cfg;
    /* Every string has a length limit (255 bytes, 1024 for file references: names end up
     * in EXR attributes, file names and HTTP headers), which the loader checks right after
     * parsing, before anything is built (400 naming the JSON path). */
    /* Resolution and spp are checked here (422) against the server's limits; the loader
     * gets the generous defaults for those and the server's for scene size (413). */
    ts_scene_limits lim = cfg->limits, def;
    ts_scene_limits_default(&def);
    lim.max_width = def.max_width, lim.max_height = def.max_height;
    lim.max_pixels = def.max_pixels, lim.max_spp = def.max_spp;
    lim.cancel = cancel;
    ts_scene *s = NULL;
    srv_warnings warnings = {0}; /* the job's once it is made */
    /* A scene without a name takes the one given (a pbrt-v3 scene never has one: its
     * positions still say scene.pbrt). */
    if (!name) name = "scene";
    ts_status stt = !files ? ts_scene_load_text(text, len, cfg->assets_dir, name, &lim, &s, err)
                    : files->pbrt ? ts_scene_load_pbrt_text(text, len, files->staging_dir, "scene.pbrt", &lim,
                                                            srv_warnings_collect, &warnings, &s, err)
                                  : ts_scene_load_text(text, len, files->staging_dir, name, &lim, &s, err);
    if (stt) {
        /* Stopped (core/cancel.h): past --max-load-seconds the scene is too costly for this
         * server (422); at shutdown, try again later (503). */
        *http_status = stt == TS_ERR_LIMIT ? 413 : stt == TS_ERR_NOMEM ? 500 : stt != TS_ERR_CANCELLED ? 400
                       : atomic_load(&cancel->timed_out) ? 422 : 503;
        srv_warnings_fini(&warnings);
        return NULL;
    }
    char media_note[600]; /* a JSON scene's: a .pbrt file's importer says it at its Integrator */
    if ((!files || !files->pbrt) && ts_integrator_media_warning(s, media_note, sizeof media_note))
        srv_warnings_collect(&warnings, media_note);
    uint64_t pixels = (uint64_t)(s->crop_x1 - s->crop_x0) * (uint64_t)(s->crop_y1 - s->crop_y0);
    ts_job_settings js;
    ts_job_settings_from_scene(s, &js);
    if (files && files->spp) js.spp = files->spp;
    uint32_t spp = js.spp;
    *http_status = 422;
    if (s->width > (int)cfg->limits.max_width || s->height > (int)cfg->limits.max_height ||
        pixels > cfg->limits.max_pixels) {
        ts_error_set(err, TS_ERR_LIMIT,
                     "film: %d × %d pixels is more than this server accepts (at most %u × %u and %llu pixels)",
                     s->width, s->height, cfg->limits.max_width, cfg->limits.max_height,
                     (unsigned long long)cfg->limits.max_pixels);
        goto fail_scene;
    }
    if (spp > cfg->limits.max_spp) {
        ts_error_set(err, TS_ERR_LIMIT, "%s: %u samples per pixel is more than this server accepts (%u)",
                     files && files->spp ? "the spp query parameter" : s->job.spp ? "job.spp" : "sampler.spp", spp,
                     cfg->limits.max_spp);
        goto fail_scene;
    }
    /* The work a job may ask for: an upper bound on the rays it traces, each weighted by
     * the texture lookups its hit may cost (ts_scene_ray_weight). */
    double rays = ts_integrator_rays_per_sample(s, js.integrator, s->effects), weight = ts_scene_ray_weight(s);
    double work = rays * weight * (double)spp * (double)pixels;
    if (cfg->max_work > 0 && work > cfg->max_work) {
        char textures[96] = "";
        if (weight > 1)
            snprintf(textures, sizeof textures, " × %.3g for its textures' %u lookups a hit", weight, s->shading_cost);
        ts_error_set(err, TS_ERR_LIMIT,
                     "this job may trace up to %.3g rays (%.0f a sample%s × %u spp × %llu pixels), more than this "
                     "server accepts (--max-work %.3g): lower the depth, the samples or the resolution",
                     work, rays, textures, spp, (unsigned long long)pixels, cfg->max_work);
        goto fail_scene;
    }
    if (s->job.display_server) {
        ts_error derr = {0};
        if (srv_display_parse_address(s->job.display_server, NULL, NULL, &derr)) {
            *http_status = 400;
            ts_error_set(err, TS_ERR_INVALID, "job.display_server: %s", derr.message);
            goto fail_scene;
        }
        if (!display_for(cfg, s)) {
            *http_status = 403;
            ts_error_set(err, TS_ERR_UNSUPPORTED,
                         "job.display_server: this server does not let a job choose where it connects (its operator can "
                         "name one with --display-server, or allow any with --allow-job-display-server)");
            goto fail_scene;
        }
    }
    *http_status = 500;
    srv_job *j = job_new(st, NULL, text, len);
    if (j && files && files->pbrt && !s->job.name && !(j->name = strdup(name))) {
        job_free(j);
        j = NULL;
    }
    if (!j || !describe_scene(j, s) || !start_display(j, display_for(cfg, s), err)) {
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job");
        if (j) job_free(j);
        goto fail_scene;
    }
    if (files) {
        /* The scene is loaded (files are read only while loading): the folder moves under
         * the job's id before the job is listed. */
        j->scene_pbrt = files->pbrt;
        if (!move_files(files, j->id, &j->files_dir)) {
            ts_error_set(err, TS_ERR_IO, "cannot move the bundle into the job's folder: %s", strerror(errno));
            job_free(j);
            goto fail_scene;
        }
    }
    j->settings = js;
    j->external = external;
    j->warnings = warnings;
    warnings = (srv_warnings){0};
    srv_events_set_items(j->events, j->nx * j->ny);
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    j->created_unix = (double)now.tv_sec + 1e-6 * (double)(now.tv_nsec / 1000); /* µs: orders restored jobs */
    ts_sched_job_desc d = {0};
    d.scene = s;
    d.settings = js;
    d.external = external;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, j};
    /* j->sj is set before the job is listed (store_add's lock publishes it to the threads
     * that find the job there); our reference keeps j alive for the scheduler's callbacks
     * until the store holds its own, which outlives them. */
    retain_for_scheduler(j);
    j->sj = ts_scheduler_submit(st->cfg.sched, &d, err);
    if (!j->sj) {
        release_for_scheduler(j);
        /* Unlikely (out of memory): it stays in the store as failed. */
        snprintf(j->failure, sizeof j->failure, "%s", err->message);
        srv_events_close(j->events);
        store_add(st, j);
        srv_job_release(j);
        ts_scene_destroy(s);
        return NULL;
    }
    store_add(st, j);
    *http_status = 201;
    if (srv_log_enabled(cfg->log, SRV_LOG_INFO)) {
        srv_log_field f[] = {SRV_LOG_STR("id", j->id),         SRV_LOG_STR("name", j->name ? j->name : ""),
                             SRV_LOG_STR("integrator", j->integrator), SRV_LOG_NUM("width", j->w),
                             SRV_LOG_NUM("height", j->h),       SRV_LOG_NUM("spp_target", js.spp),
                             SRV_LOG_NUM("priority", js.priority)};
        srv_log_event(cfg->log, SRV_LOG_INFO, "job.submitted", f, sizeof f / sizeof *f);
    }
    log_warnings(cfg->log, j);
    return j;
fail_scene:
    srv_warnings_fini(&warnings);
    ts_scene_destroy(s);
    return NULL;
}

srv_job *srv_store_restore(srv_store *st, const srv_restore *r, ts_error *err)
{
    srv_job *j = job_new(st, r->id, r->scene_text ? r->scene_text : "", r->scene_text ? r->scene_len : 0);
    if (!j) {
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job");
        return NULL;
    }
    j->settings = r->settings;
    j->created_unix = r->created_unix;
    if ((r->name && !(j->name = strdup(r->name))) || (r->scene && !describe_scene(j, r->scene))) {
        job_free(j);
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job");
        return NULL;
    }
    j->scene_pbrt = r->scene_pbrt;
    j->external = r->external;
    if (r->warnings) {
        j->warnings = *r->warnings;
        *r->warnings = (srv_warnings){0};
    }
    if (r->files_dir && !(j->files_dir = strdup(r->files_dir))) {
        job_free(j);
        ts_error_set(err, TS_ERR_NOMEM, "out of memory for a job");
        return NULL;
    }
    if (r->failure) snprintf(j->failure, sizeof j->failure, "%s", r->failure);
    if (r->scene && !r->failure && !ts_job_state_finished(r->state) && !start_display(j, display_for(&st->cfg, r->scene), err)) {
        job_free(j);
        return NULL;
    }
    if (r->history) history_restore(j, r->history);
    if (!r->scene && r->film) {
        j->full_w = r->film->full_width, j->full_h = r->film->full_height;
        j->x0 = r->film->x0, j->y0 = r->film->y0, j->w = r->film->width, j->h = r->film->height;
        ts_tile_grid_size(j->w, j->h, &j->nx, &j->ny);
    }
    srv_events_set_items(j->events, j->nx * j->ny);
    if (r->failure && !r->film) {
        /* Nothing to show: a failed job without a scheduler job. */
        srv_events_close(j->events);
        store_add(st, j);
        return j;
    }
    uint64_t samples = 0;
    if (r->film)
        for (size_t i = 0; i < (size_t)r->film->width * (size_t)r->film->height; i++) samples += r->film->pixels[i].count;
    ts_sched_job_desc d = {0};
    d.scene = r->scene;
    d.settings = r->settings;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, j};
    d.film = r->film;
    d.tile_spp = r->tile_spp;
    d.active = r->active;
    d.active_spp = r->active_spp;
    d.elapsed_s = r->elapsed_s;
    d.samples = samples;
    d.nonfinite = r->nonfinite;
    d.medium_steps = r->medium_steps;
    d.walks_truncated = r->walks_truncated;
    d.external = r->external;
    d.finished = r->failure ? TS_JOB_FAILED : ts_job_state_finished(r->state) ? r->state : TS_JOB_QUEUED;
    if (r->film) {
        d.full_width = r->film->full_width;
        d.full_height = r->film->full_height;
    }
    bool renders = !ts_job_state_finished(d.finished); /* only those get an on_done */
    if (renders) retain_for_scheduler(j);
    j->sj = ts_scheduler_submit(st->cfg.sched, &d, err);
    if (!j->sj && renders) release_for_scheduler(j);
    store_add(st, j); /* after j->sj is set, as in submit */
    if (!j->sj) {
        snprintf(j->failure, sizeof j->failure, "%s", err->message);
        srv_events_close(j->events);
        return j; /* the caller still owns scene and film */
    }
    if (ts_job_state_finished(d.finished)) srv_events_close(j->events);
    j->saved_version = atomic_load(&j->version); /* just loaded: nothing new to save */
    return j;
}

/* ---------------------------------------------------------------- status */

bool srv_job_set_checkpoint_error(srv_job *j, const char *message)
{
    pthread_mutex_lock(&j->ckpt_mu);
    bool changed = strcmp(j->checkpoint_error, message ? message : "") != 0;
    snprintf(j->checkpoint_error, sizeof j->checkpoint_error, "%s", message ? message : "");
    pthread_mutex_unlock(&j->ckpt_mu);
    return changed;
}

ts_job_state srv_job_state(srv_job *j)
{
    if (!j->sj) return TS_JOB_FAILED;
    ts_job_progress p;
    ts_sched_job_progress(j->sj, &p);
    return p.state;
}

static void add_number_or_null(cJSON *o, const char *k, double v, bool known)
{
    if (known) cJSON_AddNumberToObject(o, k, v);
    else cJSON_AddNullToObject(o, k);
}

const char *srv_job_state_name(const srv_job *j, const ts_job_progress *p)
{
    if (j->failure[0]) return "failed";
    if (p->cancelling) return "cancelling";
    return ts_job_state_name(p->state);
}

cJSON *srv_job_progress_json(srv_job *j, const ts_job_progress *p)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "id", j->id);
    cJSON_AddStringToObject(o, "state", srv_job_state_name(j, p));
    cJSON_AddNumberToObject(o, "spp", p->spp_done);
    cJSON_AddNumberToObject(o, "spp_mean", p->spp_fraction);
    cJSON_AddNumberToObject(o, "spp_target", p->spp_target);
    cJSON_AddNumberToObject(o, "pass_spp", p->pass_end);
    cJSON_AddNumberToObject(o, "elapsed_s", p->elapsed_s);
    cJSON_AddNumberToObject(o, "samples", (double)p->samples);
    cJSON_AddNumberToObject(o, "samples_per_s", p->samples_per_s);
    add_number_or_null(o, "error_estimate", p->error_estimate, p->error_estimate >= 0);
    cJSON_AddNumberToObject(o, "progress", p->progress);
    add_number_or_null(o, "eta_s", p->eta_s, p->eta_s >= 0);
    cJSON_AddStringToObject(o, "halt_reason", ts_halt_reason_name(p->halt));
    return o;
}

cJSON *srv_job_status_json(srv_job *j)
{
    ts_job_progress p = {0};
    if (j->sj) ts_sched_job_progress(j->sj, &p);
    else p.state = TS_JOB_FAILED, p.error_estimate = -1, p.spp_target = j->settings.spp;
    cJSON *o = cJSON_CreateObject();
    char url[160];
    cJSON_AddStringToObject(o, "id", j->id);
    if (j->name) cJSON_AddStringToObject(o, "name", j->name);
    else cJSON_AddNullToObject(o, "name");
    cJSON_AddStringToObject(o, "state", srv_job_state_name(j, &p));
    if (j->failure[0]) cJSON_AddStringToObject(o, "error", j->failure);
    pthread_mutex_lock(&j->ckpt_mu);
    if (j->checkpoint_error[0]) cJSON_AddStringToObject(o, "checkpoint_error", j->checkpoint_error);
    pthread_mutex_unlock(&j->ckpt_mu);
    cJSON_AddNumberToObject(o, "priority", j->settings.priority);
    cJSON_AddNumberToObject(o, "created_at", j->created_unix);
    cJSON_AddNumberToObject(o, "spp_done", p.spp_done);
    cJSON_AddNumberToObject(o, "spp_mean", p.spp_fraction);
    cJSON_AddNumberToObject(o, "spp_target", p.spp_target);
    cJSON_AddNumberToObject(o, "pass_spp", p.pass_end);
    cJSON_AddNumberToObject(o, "elapsed_s", p.elapsed_s);
    cJSON_AddNumberToObject(o, "queued_s", p.queued_s);
    cJSON_AddNumberToObject(o, "samples", (double)p.samples);
    cJSON_AddNumberToObject(o, "samples_per_s", p.samples_per_s);
    add_number_or_null(o, "error_estimate", p.error_estimate, p.error_estimate >= 0);
    cJSON_AddNumberToObject(o, "progress", p.progress);
    add_number_or_null(o, "eta_s", p.eta_s, p.eta_s >= 0);
    cJSON_AddNumberToObject(o, "nonfinite_samples", (double)p.nonfinite);
    cJSON_AddNumberToObject(o, "camera_rays", (double)p.camera_rays);
    cJSON_AddNumberToObject(o, "other_rays", (double)p.other_rays);
    cJSON_AddNumberToObject(o, "medium_steps", (double)p.medium_steps);
    cJSON_AddNumberToObject(o, "walks_truncated", (double)p.walks_truncated);
    cJSON_AddStringToObject(o, "halt_reason", ts_halt_reason_name(p.halt));
    add_number_or_null(o, "time_limit_s", j->settings.time_limit_s, j->settings.time_limit_s > 0);
    add_number_or_null(o, "target_error", j->settings.target_error, j->settings.target_error > 0);
    cJSON_AddBoolToObject(o, "adaptive", j->settings.adaptive);
    cJSON_AddStringToObject(o, "integrator", j->integrator);
    cJSON *warn = cJSON_AddArrayToObject(o, "warnings");
    for (int i = 0; warn && i < j->warnings.n; i++) cJSON_AddItemToArray(warn, cJSON_CreateString(j->warnings.items[i]));
    if (j->warnings.dropped) cJSON_AddNumberToObject(o, "warnings_dropped", j->warnings.dropped);
    cJSON *fx = cJSON_AddArrayToObject(o, "effects");
    for (uint32_t b = 1; b < (1u << TS_EFFECT_COUNT); b <<= 1) {
        const char *k = ts_effect_key(b);
        /* j->effects lists the keys, comma-separated; match whole words. */
        const char *at = k ? strstr(j->effects, k) : NULL;
        while (at) {
            size_t n = strlen(k);
            bool start = at == j->effects || at[-1] == ' ' || at[-1] == ',';
            bool end = at[n] == '\0' || at[n] == ',';
            if (start && end) {
                cJSON_AddItemToArray(fx, cJSON_CreateString(k));
                break;
            }
            at = strstr(at + 1, k);
        }
    }
    cJSON *film = cJSON_AddObjectToObject(o, "film");
    cJSON_AddNumberToObject(film, "width", j->full_w);
    cJSON_AddNumberToObject(film, "height", j->full_h);
    cJSON_AddNumberToObject(film, "x0", j->x0);
    cJSON_AddNumberToObject(film, "y0", j->y0);
    cJSON_AddNumberToObject(film, "crop_width", j->w);
    cJSON_AddNumberToObject(film, "crop_height", j->h);
    cJSON_AddNumberToObject(film, "tile_size", TS_TILE_SIZE);
    cJSON_AddNumberToObject(film, "tiles_x", j->nx);
    cJSON_AddNumberToObject(film, "tiles_y", j->ny);
    cJSON *urls = cJSON_AddObjectToObject(o, "urls");
    snprintf(url, sizeof url, "/api/v1/jobs/%s", j->id);
    cJSON_AddStringToObject(urls, "self", url);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/image.exr", j->id);
    cJSON_AddStringToObject(urls, "exr", url);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/image.png", j->id);
    cJSON_AddStringToObject(urls, "png", url);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/events", j->id);
    cJSON_AddStringToObject(urls, "events", url);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/tiles/{tx}/{ty}.png", j->id);
    cJSON_AddStringToObject(urls, "tile_png", url);
    snprintf(url, sizeof url, "/api/v1/jobs/%s/tiles/{tx}/{ty}.exr", j->id);
    cJSON_AddStringToObject(urls, "tile_exr", url);
    if (j->external && j->store->cfg.describe) j->store->cfg.describe(j->store->cfg.describe_user, j, o);
    return o;
}
