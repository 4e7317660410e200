/* persist.c — checkpoints under --data; see persist.h. */
#include "persist.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tessera.h"

#define FILM_MAGIC "TSFILM01"

typedef struct film_header {
    char magic[8];
    int32_t full_w, full_h, x0, y0, w, h, nx, ny;
} film_header;

static ts_status make_dir(const char *path, ts_error *err)
{
    if (mkdir(path, 0755) == 0 || errno == EEXIST) return TS_OK;
    return ts_error_set(err, TS_ERR_IO, "%s: cannot create the folder (%s)", path, strerror(errno));
}

ts_status srv_persist_init(const char *dir, ts_error *err)
{
    char p[4096];
    ts_status st = make_dir(dir, err);
    if (st) return st;
    snprintf(p, sizeof p, "%s/jobs", dir);
    return make_dir(p, err);
}

static ts_status write_json(const char *path, cJSON *o, ts_error *err)
{
    char *s = cJSON_Print(o);
    if (!s) return ts_error_set(err, TS_ERR_NOMEM, "out of memory writing %s", path);
    ts_status st = ts_image_write_file_atomic(path, s, strlen(s), err);
    free(s);
    return st;
}

/* Writes j's folder: scene.json once, film.bin when with_film and the job has rendered,
 * and job.json. */
static ts_status save_files(const char *dir, srv_job *j, bool with_film, ts_error *err)
{
    char folder[4096], path[4200];
    snprintf(folder, sizeof folder, "%s/jobs/%s", dir, j->id);
    ts_status st = make_dir(folder, err);
    if (st) return st;
    snprintf(path, sizeof path, "%s/scene.json", folder);
    struct stat sb;
    if (stat(path, &sb) != 0 && (st = ts_image_write_file_atomic(path, j->scene_text, j->scene_len, err))) return st;
    /* The state is taken before the film, so job.json is never ahead of film.bin (a job
     * recorded as done has its whole film on disk); restoring takes the sample counts
     * from the film. */
    cJSON *o = srv_job_status_json(j);
    cJSON *hist = o ? srv_job_history_json(j) : NULL;
    if (hist) cJSON_AddItemToObject(o, "history", cJSON_DetachItemFromObjectCaseSensitive(hist, "points"));
    cJSON_Delete(hist);
    if (!o) return ts_error_set(err, TS_ERR_NOMEM, "out of memory for a checkpoint");
    if (!j->sj) goto state; /* failed before rendering: no film */
    if (!with_film) {
        /* Just submitted: what is on disk is the job with no samples yet, however far it
         * has rendered meanwhile (the first checkpoint writes its film). */
        cJSON_ReplaceItemInObjectCaseSensitive(o, "state", cJSON_CreateString(ts_job_state_name(TS_JOB_QUEUED)));
        cJSON_ReplaceItemInObjectCaseSensitive(o, "spp_done", cJSON_CreateNumber(0));
        cJSON_ReplaceItemInObjectCaseSensitive(o, "samples", cJSON_CreateNumber(0));
        goto state;
    }

    /* The film, from the tile snapshots. */
    ts_job_progress p;
    ts_sched_job_progress(j->sj, &p);
    size_t n_tiles = (size_t)j->nx * (size_t)j->ny;
    uint32_t *tile_spp = calloc(n_tiles ? n_tiles : 1, sizeof *tile_spp);
    ts_film *f = tile_spp ? ts_sched_job_film(j->sj, tile_spp, err) : NULL;
    if (!f) {
        free(tile_spp);
        cJSON_Delete(o);
        return err->status ? err->status : ts_error_set(err, TS_ERR_NOMEM, "out of memory for a checkpoint");
    }
    size_t n_px = (size_t)f->width * (size_t)f->height;
    size_t bytes = sizeof(film_header) + n_tiles * sizeof(uint32_t) + n_px * sizeof(ts_film_pixel);
    unsigned char *buf = malloc(bytes);
    if (!buf) {
        ts_film_destroy(f);
        free(tile_spp);
        cJSON_Delete(o);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for a checkpoint of %zu bytes", bytes);
    }
    film_header h = {FILM_MAGIC, f->full_width, f->full_height, f->x0, f->y0, f->width, f->height, j->nx, j->ny};
    memcpy(h.magic, FILM_MAGIC, 8);
    memcpy(buf, &h, sizeof h);
    memcpy(buf + sizeof h, tile_spp, n_tiles * sizeof(uint32_t));
    memcpy(buf + sizeof h + n_tiles * sizeof(uint32_t), f->pixels, n_px * sizeof(ts_film_pixel));
    ts_film_destroy(f);
    free(tile_spp);
    snprintf(path, sizeof path, "%s/film.bin", folder);
    st = ts_image_write_file_atomic(path, buf, bytes, err);
    free(buf);
    if (st) {
        cJSON_Delete(o);
        return st;
    }

state:
    /* The status document has all we need; the halt settings come from the scene. */
    snprintf(path, sizeof path, "%s/job.json", folder);
    st = write_json(path, o, err);
    cJSON_Delete(o);
    return st;
}

/* save_files under the job's disk lock; a deleted job is not written again. */
static ts_status save_locked(const char *dir, srv_job *j, bool with_film, ts_error *err)
{
    pthread_mutex_lock(&j->disk_mu);
    ts_status st = j->removed ? TS_OK : save_files(dir, j, with_film, err);
    pthread_mutex_unlock(&j->disk_mu);
    return st;
}

ts_status srv_persist_save(const char *dir, srv_job *j, ts_error *err) { return save_locked(dir, j, true, err); }

ts_status srv_persist_save_submitted(const char *dir, srv_job *j, ts_error *err)
{
    return save_locked(dir, j, false, err);
}

void srv_persist_remove(const char *dir, srv_job *j)
{
    char folder[4096], path[4400];
    snprintf(folder, sizeof folder, "%s/jobs/%s", dir, j->id);
    pthread_mutex_lock(&j->disk_mu);
    j->removed = true;
    DIR *d = opendir(folder);
    for (struct dirent *e = d ? readdir(d) : NULL; e; e = readdir(d)) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(path, sizeof path, "%s/%s", folder, e->d_name);
        if (unlink(path) != 0) fprintf(stderr, "tessera: removing %s: %s\n", path, strerror(errno));
    }
    if (d) closedir(d);
    if (rmdir(folder) != 0 && errno != ENOENT) fprintf(stderr, "tessera: removing %s: %s\n", folder, strerror(errno));
    pthread_mutex_unlock(&j->disk_mu);
}

int srv_persist_save_changed(const char *dir, srv_store *st)
{
    int n = 0, count = 0;
    srv_job **jobs = srv_store_list(st, &n);
    for (int i = 0; jobs && i < n; i++) {
        srv_job *j = jobs[i];
        uint64_t v = atomic_load(&j->version);
        if (v != j->saved_version) {
            ts_error err = {0};
            if (srv_persist_save(dir, j, &err)) {
                /* Rendering goes on; the previous checkpoint files stay as they were (each
                 * is replaced only by an atomic rename). Logged when the reason changes. */
                if (srv_job_set_checkpoint_error(j, err.message))
                    fprintf(stderr, "tessera: checkpoint of job %s failed, the previous one is kept: %s\n", j->id,
                            err.message);
            } else {
                if (srv_job_set_checkpoint_error(j, NULL))
                    fprintf(stderr, "tessera: checkpoint of job %s written again\n", j->id);
                j->saved_version = v;
                count++;
            }
        }
        srv_job_release(j);
    }
    free(jobs);
    return count;
}

/* ---------------------------------------------------------------- restore */

static char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t cap = 0, n = 0;
    for (;;) {
        if (n + 65536 > cap) {
            cap = cap ? cap * 2 : 262144;
            char *b = realloc(buf, cap + 1);
            if (!b) {
                free(buf);
                fclose(f);
                return NULL;
            }
            buf = b;
        }
        size_t r = fread(buf + n, 1, cap - n, f);
        n += r;
        if (r == 0) break;
    }
    fclose(f);
    buf[n] = '\0';
    *len = n;
    return buf;
}

static ts_film *read_film(const char *path, int nx, int ny, uint32_t **tile_spp, ts_error *err)
{
    size_t len = 0;
    unsigned char *buf = (unsigned char *)read_all(path, &len);
    film_header h;
    if (!buf) {
        ts_error_set(err, TS_ERR_IO, "%s: cannot read the checkpoint", path);
        return NULL;
    }
    ts_film *f = NULL;
    if (len < sizeof h) goto bad;
    memcpy(&h, buf, sizeof h);
    if (memcmp(h.magic, FILM_MAGIC, 8) != 0 || h.nx != nx || h.ny != ny) goto bad;
    size_t n_tiles = (size_t)nx * (size_t)ny;
    f = ts_film_create(h.full_w, h.full_h, h.x0, h.y0, h.w, h.h, err);
    if (!f) goto fail;
    size_t n_px = (size_t)h.w * (size_t)h.h;
    if (len != sizeof h + n_tiles * 4 + n_px * sizeof(ts_film_pixel)) goto bad;
    *tile_spp = malloc(n_tiles * 4);
    if (!*tile_spp) goto bad;
    memcpy(*tile_spp, buf + sizeof h, n_tiles * 4);
    memcpy(f->pixels, buf + sizeof h + n_tiles * 4, n_px * sizeof(ts_film_pixel));
    free(buf);
    return f;
bad:
    ts_error_set(err, TS_ERR_INVALID, "%s: the checkpoint is truncated or does not match the scene", path);
fail:
    ts_film_destroy(f);
    free(buf);
    return NULL;
}

typedef struct entry { char id[24]; double created; } entry;

static int cmp_entry(const void *a, const void *b)
{
    const entry *x = a, *y = b;
    if (x->created != y->created) return x->created < y->created ? -1 : 1;
    return strcmp(x->id, y->id);
}

static double num(const cJSON *o, const char *k, double def)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsNumber(v) ? v->valuedouble : def;
}

static void restore_one(const char *dir, const char *id, srv_store *st, const ts_scene_limits *limits,
                        const char *assets_dir)
{
    char folder[4096], path[4200];
    snprintf(folder, sizeof folder, "%s/jobs/%s", dir, id);
    size_t jlen = 0, slen = 0;
    snprintf(path, sizeof path, "%s/job.json", folder);
    char *jtext = read_all(path, &jlen);
    snprintf(path, sizeof path, "%s/scene.json", folder);
    char *stext = read_all(path, &slen);
    cJSON *meta = jtext ? cJSON_ParseWithLength(jtext, jlen) : NULL;
    ts_error err = {0};
    srv_restore r = {0};
    r.id = id;
    r.scene_text = stext;
    r.scene_len = slen;
    ts_scene *scene = NULL;
    ts_film *film = NULL;
    uint32_t *tile_spp = NULL;
    char failure[600] = "";
    if (!meta || !stext) {
        snprintf(failure, sizeof failure, "checkpoint of job %s is unreadable (job.json or scene.json)", id);
        goto add;
    }
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(meta, "name");
    const cJSON *state = cJSON_GetObjectItemCaseSensitive(meta, "state");
    const cJSON *fail = cJSON_GetObjectItemCaseSensitive(meta, "error");
    r.name = cJSON_IsString(name) ? name->valuestring : NULL;
    r.created_unix = num(meta, "created_at", 0);
    r.elapsed_s = num(meta, "elapsed_s", 0);
    r.nonfinite = (uint64_t)num(meta, "nonfinite_samples", 0);
    r.history = cJSON_GetObjectItemCaseSensitive(meta, "history");
    if (!cJSON_IsArray(r.history)) r.history = NULL;
    r.settings.integrator = TS_INTEGRATOR_AO; /* the scene's, once it loads */
    r.settings.priority = (int)num(meta, "priority", 0);
    r.settings.spp = (uint32_t)num(meta, "spp_target", 1);
    r.settings.time_limit_s = num(meta, "time_limit_s", 0);
    r.settings.target_error = num(meta, "target_error", 0);
    r.state = TS_JOB_QUEUED;
    const char *sname = cJSON_IsString(state) ? state->valuestring : "queued";
    if (!strcmp(sname, "done")) r.state = TS_JOB_DONE;
    else if (!strcmp(sname, "cancelled")) r.state = TS_JOB_CANCELLED;
    else if (!strcmp(sname, "failed")) r.state = TS_JOB_FAILED;
    if (r.state == TS_JOB_FAILED) {
        snprintf(failure, sizeof failure, "%s", cJSON_IsString(fail) ? fail->valuestring : "failed");
    }
    if (ts_scene_load_text(stext, slen, assets_dir, "scene", limits, &scene, &err)) {
        snprintf(failure, sizeof failure, "the checkpointed scene no longer loads: %s", err.message);
        goto add;
    }
    r.settings.integrator = scene->integrator.type;
    int nx, ny;
    ts_tile_grid_size(scene->crop_x1 - scene->crop_x0, scene->crop_y1 - scene->crop_y0, &nx, &ny);
    snprintf(path, sizeof path, "%s/film.bin", folder);
    struct stat sb;
    if (stat(path, &sb) == 0) {
        film = read_film(path, nx, ny, &tile_spp, &err);
        if (!film) {
            snprintf(failure, sizeof failure, "%s", err.message);
            goto add;
        }
    }
    if (ts_job_state_finished(r.state) && !film && !failure[0]) snprintf(failure, sizeof failure, "the film checkpoint is missing");
add:
    if (failure[0]) r.failure = failure;
    r.scene = scene;
    r.film = film;
    r.tile_spp = tile_spp;
    srv_job *j = srv_store_restore(st, &r, &err);
    if (j && j->sj) scene = NULL, film = NULL; /* the job owns them now */
    if (j) {
        j->saved_version = atomic_load(&j->version);
        fprintf(stderr, "tessera: restored job %s (%s)\n", id, r.failure ? r.failure : ts_job_state_name(r.state));
    }
    srv_job_release(j);
    ts_scene_destroy(scene);
    ts_film_destroy(film);
    free(tile_spp);
    cJSON_Delete(meta);
    free(jtext);
    free(stext);
}

int srv_persist_restore_all(const char *dir, srv_store *st, const ts_scene_limits *limits, const char *assets_dir)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/jobs", dir);
    DIR *d = opendir(path);
    if (!d) return 0;
    entry *e = NULL;
    int n = 0, cap = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        if (de->d_name[0] == '.' || strlen(de->d_name) >= sizeof e->id) continue;
        if (n == cap) {
            cap = cap ? cap * 2 : 16;
            entry *ne = realloc(e, sizeof *e * (size_t)cap);
            if (!ne) break;
            e = ne;
        }
        snprintf(e[n].id, sizeof e[n].id, "%s", de->d_name);
        char jp[4200];
        snprintf(jp, sizeof jp, "%s/%s/job.json", path, de->d_name);
        size_t len = 0;
        char *t = read_all(jp, &len);
        cJSON *o = t ? cJSON_ParseWithLength(t, len) : NULL;
        e[n].created = o ? num(o, "created_at", 0) : 0;
        cJSON_Delete(o);
        free(t);
        n++;
    }
    closedir(d);
    if (n) qsort(e, (size_t)n, sizeof *e, cmp_entry); /* e may be NULL when the folder is empty */
    for (int i = 0; i < n; i++) restore_one(dir, e[i].id, st, limits, assets_dir);
    free(e);
    return n;
}
