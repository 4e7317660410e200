/* persist.c — checkpoints under --data; see persist.h. */
#include "persist.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <nettle/sha2.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bundle.h"
#include "tessera.h"

/* film.bin: the header, the tiles' spp (uint32 each), the pixels (ts_film_pixel each), and
 * for an adaptive job (render/adaptive.h) the check point its active pixels were chosen at
 * (uint32) and one byte per pixel, 1 where it takes samples. The
 * header's sha256 is the SHA-256 of every other byte of the file (the header up to it and
 * all that follows), so a file damaged anywhere is refused. "TSFILM01" files (no digest)
 * are refused as damaged: their jobs render again from their scenes. */
#define FILM_MAGIC "TSFILM02"

typedef struct film_header {
    char magic[8];
    int32_t full_w, full_h, x0, y0, w, h, nx, ny;
    uint8_t sha256[SHA256_DIGEST_SIZE];
} film_header;

#define FILM_DIGEST_AT offsetof(film_header, sha256)

/* The digest of a film file of len bytes (the header's own digest field skipped). */
static void film_digest(const unsigned char *buf, size_t len, uint8_t out[SHA256_DIGEST_SIZE])
{
    struct sha256_ctx ctx;
    sha256_init(&ctx);
    sha256_update(&ctx, FILM_DIGEST_AT, buf);
    sha256_update(&ctx, len - sizeof(film_header), buf + sizeof(film_header));
    sha256_digest(&ctx, SHA256_DIGEST_SIZE, out);
}

/* Rewrites err's sentence with every "DIR/" taken out, so paths read relative to --data
 * ("jobs/ID/film.bin"): answers and job statuses never name a path of the server's. */
static void relative_to(ts_error *err, const char *dir)
{
    char prefix[4200], out[sizeof err->message];
    int n = snprintf(prefix, sizeof prefix, "%s/", dir);
    if (n <= 1 || (size_t)n >= sizeof prefix) return;
    size_t o = 0;
    for (const char *m = err->message; *m && o + 1 < sizeof out;) {
        if (!strncmp(m, prefix, (size_t)n)) m += n;
        else out[o++] = *m++;
    }
    out[o] = '\0';
    memcpy(err->message, out, o + 1);
}

/* True for a name the atomic writer gives its temporary files ("<name>.tmp.<pid>.<n>"). */
static bool is_temporary(const char *name) { return strstr(name, ".tmp.") != NULL; }

/* Removes the temporary files in folder (debris of a crash, or of a write whose clean-up
 * failed); returns how many. The caller holds the job's disk lock or runs before any
 * writer starts, so none of them is being written. */
static int sweep_temporaries(const char *folder)
{
    DIR *d = opendir(folder);
    if (!d) return 0;
    int n = 0;
    char path[4400];
    for (struct dirent *e = readdir(d); e; e = readdir(d)) {
        if (!is_temporary(e->d_name)) continue;
        snprintf(path, sizeof path, "%s/%s", folder, e->d_name);
        if (unlink(path) == 0) n++;
    }
    closedir(d);
    return n;
}

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
    /* A bundle's job keeps its scene file in files/ (bundle.h), with the files it names. */
    if (!j->files_dir && stat(path, &sb) != 0 &&
        (st = ts_image_write_file_atomic(path, j->scene_text, j->scene_len, err)))
        return st;
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
    bool adaptive = ts_sched_job_adaptive(j->sj);
    size_t window = (size_t)j->w * (size_t)j->h;
    uint8_t *active = adaptive ? malloc(window ? window : 1) : NULL;
    uint32_t active_spp = 0;
    ts_film *f = tile_spp && (active || !adaptive)
                     ? ts_sched_job_film_adaptive(j->sj, tile_spp, active, &active_spp, err)
                     : NULL;
    if (!f) {
        free(tile_spp);
        free(active);
        cJSON_Delete(o);
        return err->status ? err->status : ts_error_set(err, TS_ERR_NOMEM, "out of memory for a checkpoint");
    }
    size_t n_px = (size_t)f->width * (size_t)f->height;
    size_t bytes = sizeof(film_header) + n_tiles * sizeof(uint32_t) + n_px * sizeof(ts_film_pixel) +
                   (adaptive ? sizeof(uint32_t) + n_px : 0);
    unsigned char *buf = malloc(bytes);
    if (!buf) {
        ts_film_destroy(f);
        free(tile_spp);
        free(active);
        cJSON_Delete(o);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for a checkpoint of %zu bytes", bytes);
    }
    film_header h = {{0}, f->full_width, f->full_height, f->x0, f->y0, f->width, f->height, j->nx, j->ny, {0}};
    memcpy(h.magic, FILM_MAGIC, 8);
    memcpy(buf + sizeof h, tile_spp, n_tiles * sizeof(uint32_t));
    memcpy(buf + sizeof h + n_tiles * sizeof(uint32_t), f->pixels, n_px * sizeof(ts_film_pixel));
    if (adaptive) {
        unsigned char *tail = buf + sizeof h + n_tiles * sizeof(uint32_t) + n_px * sizeof(ts_film_pixel);
        memcpy(tail, &active_spp, sizeof active_spp);
        memcpy(tail + sizeof active_spp, active, n_px);
    }
    free(active);
    memcpy(buf, &h, sizeof h);
    film_digest(buf, bytes, h.sha256);
    memcpy(buf + FILM_DIGEST_AT, h.sha256, sizeof h.sha256);
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
static ts_status save_locked(const char *dir, srv_job *j, bool with_film, srv_persist_stats *stats, ts_error *err)
{
    bool finished = with_film && ts_job_state_finished(srv_job_state(j));
    pthread_mutex_lock(&j->disk_mu);
    ts_status st = j->removed ? TS_OK : save_files(dir, j, with_film, err);
    if (!st && finished && !j->removed) {
        /* The job's last checkpoint: no write of its folder follows, so whatever temporary
         * file is left there (a crashed process's, or one whose removal failed) goes. */
        char folder[4096];
        snprintf(folder, sizeof folder, "%s/jobs/%s", dir, j->id);
        int n = sweep_temporaries(folder);
        if (n && stats) atomic_fetch_add(&stats->temporaries_removed, (uint64_t)n);
    }
    pthread_mutex_unlock(&j->disk_mu);
    if (st) relative_to(err, dir);
    return st;
}

ts_status srv_persist_save(const char *dir, srv_job *j, ts_error *err) { return save_locked(dir, j, true, NULL, err); }

ts_status srv_persist_save_submitted(const char *dir, srv_job *j, ts_error *err)
{
    return save_locked(dir, j, false, NULL, err);
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
        /* files/: a bundle's folder (bundle.h), removed whole, following no link */
        if (!strcmp(e->d_name, "files") ? srv_bundle_remove_tree(path) != 0 : unlink(path) != 0)
            fprintf(stderr, "tessera: removing %s: %s\n", path, strerror(errno));
    }
    if (d) closedir(d);
    if (rmdir(folder) != 0 && errno != ENOENT) fprintf(stderr, "tessera: removing %s: %s\n", folder, strerror(errno));
    pthread_mutex_unlock(&j->disk_mu);
}

int srv_persist_save_changed(const char *dir, srv_store *st, const srv_persist_retry *retry, srv_persist_stats *stats)
{
    int n = 0, count = 0;
    double now = ts_now_seconds();
    srv_job **jobs = srv_store_list(st, &n);
    for (int i = 0; jobs && i < n; i++) {
        srv_job *j = jobs[i];
        uint64_t v = atomic_load(&j->version);
        if (v != j->saved_version && (!retry || j->ckpt_backoff_s <= 0 || now >= j->ckpt_retry_at)) {
            ts_error err = {0};
            bool was_failing = j->ckpt_backoff_s > 0;
            if (save_locked(dir, j, true, stats, &err)) {
                /* Rendering goes on; the previous checkpoint files stay as they were (each
                 * is replaced only by an atomic rename). Retried after a delay that doubles
                 * from retry->first_s up to retry->max_s; one log line when the job's
                 * checkpoints start failing and one when they land again. */
                if (stats) atomic_fetch_add(&stats->failures, 1);
                if (retry) {
                    double d = was_failing ? 2 * j->ckpt_backoff_s : retry->first_s;
                    j->ckpt_backoff_s = d < retry->max_s ? d : retry->max_s;
                    j->ckpt_retry_at = now + j->ckpt_backoff_s;
                } else {
                    j->ckpt_backoff_s = 1; /* failing, for the log */
                }
                srv_job_set_checkpoint_error(j, err.message);
                if (!was_failing)
                    fprintf(stderr, "tessera: checkpoint of job %s failed, the previous one is kept (retrying with backoff): %s\n",
                            j->id, err.message);
            } else {
                srv_job_set_checkpoint_error(j, NULL);
                if (was_failing) fprintf(stderr, "tessera: checkpoint of job %s written again\n", j->id);
                j->ckpt_backoff_s = 0;
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

/* Reads a whole regular file; NULL with *why set (a sentence fragment) otherwise. Opened
 * with O_NOFOLLOW | O_NONBLOCK and checked with fstat before reading, so a symbolic link
 * cannot redirect a restore and a FIFO or device cannot block it. */
static char *read_all(const char *path, size_t *len, const char **why)
{
    *why = "cannot be read";
    int fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        *why = errno == ENOENT ? "is missing" : errno == ELOOP ? "is a symbolic link" : "cannot be opened";
        return NULL;
    }
    struct stat sb;
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        *why = "is not a regular file";
        close(fd);
        return NULL;
    }
    size_t cap = (size_t)sb.st_size, n = 0;
    char *buf = malloc(cap + 1);
    if (!buf) {
        *why = "does not fit in memory";
        close(fd);
        return NULL;
    }
    while (n < cap) {
        ssize_t r = read(fd, buf + n, cap - n);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) break;
        n += (size_t)r;
    }
    close(fd);
    if (n != cap) { /* changed under us */
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    *len = n;
    return buf;
}

/* Whether a restored film holds only finite sums (a matching digest makes this redundant
 * for damage; it keeps the film's own invariant, no NaN or Inf, whatever wrote the file). */
static bool film_finite(const ts_film *f)
{
    for (size_t i = 0; i < (size_t)f->width * (size_t)f->height; i++) {
        const ts_film_pixel *p = &f->pixels[i];
        for (int c = 0; c < 3; c++)
            if (!isfinite(p->sum[c]) || !isfinite(p->sum_sq[c]) || p->sum_sq[c] < 0) return false;
        if (!isfinite(p->weight) || !isfinite(p->weight_sq) || p->weight_sq < 0) return false;
    }
    return true;
}

/* Reads film.bin for a scene of that crop window and tile grid. NULL when there is none
 * (*missing) or it is damaged (err says how, naming the file relative to --data). */
static ts_film *read_film(const char *path, const char *rel, const ts_scene *s, int nx, int ny, uint32_t **tile_spp,
                          uint8_t **active, uint32_t *active_spp, bool *missing, ts_error *err)
{
    size_t len = 0;
    const char *why;
    unsigned char *buf = (unsigned char *)read_all(path, &len, &why);
    film_header h;
    *missing = false;
    if (!buf) {
        *missing = !strcmp(why, "is missing");
        ts_error_set(err, TS_ERR_IO, "%s %s", rel, why);
        return NULL;
    }
    ts_film *f = NULL;
    const char *bad = "is truncated or does not match the scene";
    size_t n_tiles = (size_t)nx * (size_t)ny, n_px = 0;
    uint8_t digest[SHA256_DIGEST_SIZE];
    if (len < sizeof h) goto bad;
    memcpy(&h, buf, sizeof h);
    if (memcmp(h.magic, FILM_MAGIC, 8) != 0) {
        bad = memcmp(h.magic, "TSFILM01", 8) ? "is not a film checkpoint" : "has no checksum (an older format)";
        goto bad;
    }
    if (h.nx != nx || h.ny != ny || h.full_w != s->width || h.full_h != s->height || h.x0 != s->crop_x0 ||
        h.y0 != s->crop_y0 || h.w != s->crop_x1 - s->crop_x0 || h.h != s->crop_y1 - s->crop_y0)
        goto bad;
    n_px = (size_t)h.w * (size_t)h.h;
    size_t base = sizeof h + n_tiles * 4 + n_px * sizeof(ts_film_pixel);
    bool with_active = len == base + 4 + n_px; /* an adaptive job's active pixels follow */
    if (len != base && !with_active) goto bad;
    film_digest(buf, len, digest);
    if (memcmp(digest, h.sha256, sizeof digest) != 0) {
        bad = "fails its checksum (damaged)";
        goto bad;
    }
    f = ts_film_create(h.full_w, h.full_h, h.x0, h.y0, h.w, h.h, err);
    if (!f) goto fail;
    *tile_spp = malloc(n_tiles * 4);
    if (!*tile_spp) {
        ts_error_set(err, TS_ERR_NOMEM, "%s does not fit in memory", rel);
        goto fail;
    }
    memcpy(*tile_spp, buf + sizeof h, n_tiles * 4);
    memcpy(f->pixels, buf + sizeof h + n_tiles * 4, n_px * sizeof(ts_film_pixel));
    if (!film_finite(f)) {
        free(*tile_spp);
        *tile_spp = NULL;
        bad = "holds sums that are not finite";
        goto bad;
    }
    if (with_active) {
        if (!(*active = malloc(n_px ? n_px : 1))) {
            free(*tile_spp);
            *tile_spp = NULL;
            ts_error_set(err, TS_ERR_NOMEM, "%s does not fit in memory", rel);
            goto fail;
        }
        memcpy(active_spp, buf + base, 4);
        memcpy(*active, buf + base + 4, n_px);
    }
    free(buf);
    return f;
bad:
    ts_error_set(err, TS_ERR_INVALID, "%s %s", rel, bad);
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

/* Restores one job folder. What the server finished stays finished; a checkpoint that
 * cannot be used (job.json unreadable, film.bin missing for a finished job, damaged or
 * of another scene) does not fail the job: it renders again from its scene, the log says
 * why and its status carries the reason in checkpoint_error until the next checkpoint
 * lands. A job fails here only when its scene no longer loads (or it had failed). */
static void restore_one(const char *dir, const char *id, srv_store *st, const ts_scene_limits *limits,
                        const char *assets_dir, srv_persist_stats *stats)
{
    char folder[4096], path[4200], rel[200];
    snprintf(folder, sizeof folder, "%s/jobs/%s", dir, id);
    size_t jlen = 0, slen = 0;
    const char *jwhy, *swhy;
    snprintf(path, sizeof path, "%s/job.json", folder);
    char *jtext = read_all(path, &jlen, &jwhy);
    /* A bundle's job: files/ holds its scene file (scene.json or scene.pbrt) and the files
     * it names, which resolve there. */
    char files[4200], sname_rel[64] = "scene.json";
    struct stat fsb;
    snprintf(files, sizeof files, "%s/files", folder);
    bool bundle = lstat(files, &fsb) == 0 && S_ISDIR(fsb.st_mode), pbrt = false;
    if (bundle) {
        snprintf(path, sizeof path, "%s/scene.pbrt", files);
        pbrt = lstat(path, &fsb) == 0;
        snprintf(sname_rel, sizeof sname_rel, "files/scene.%s", pbrt ? "pbrt" : "json");
    }
    snprintf(path, sizeof path, "%s/%s", folder, sname_rel);
    char *stext = read_all(path, &slen, &swhy);
    cJSON *meta = jtext ? cJSON_ParseWithLength(jtext, jlen) : NULL;
    ts_error err = {0};
    srv_restore r = {0};
    srv_warnings warnings = {0}; /* the reloaded scene.pbrt's, moved into the job */
    r.warnings = &warnings;
    r.id = id;
    r.scene_text = stext;
    r.scene_len = slen;
    r.files_dir = bundle ? files : NULL;
    r.scene_pbrt = pbrt;
    snprintf(path, sizeof path, "%s/farm.json", folder); /* a farm job (farm.h): its farm re-attaches */
    r.external = lstat(path, &fsb) == 0;
    ts_scene *scene = NULL;
    ts_film *film = NULL;
    uint32_t *tile_spp = NULL, active_spp = 0;
    uint8_t *active = NULL;
    char failure[600] = "", damaged[600] = "";
    if (!stext) {
        snprintf(failure, sizeof failure, "the checkpoint of job %s is unusable: jobs/%s/%s %s", id, id, sname_rel, swhy);
        goto add;
    }
    if (!meta) snprintf(damaged, sizeof damaged, "jobs/%s/job.json %s", id, jtext ? "does not parse" : jwhy);
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(meta, "name");
    const cJSON *state = cJSON_GetObjectItemCaseSensitive(meta, "state");
    const cJSON *fail = cJSON_GetObjectItemCaseSensitive(meta, "error");
    r.name = cJSON_IsString(name) ? name->valuestring : NULL;
    r.created_unix = num(meta, "created_at", 0);
    r.elapsed_s = num(meta, "elapsed_s", 0);
    r.nonfinite = (uint64_t)num(meta, "nonfinite_samples", 0);
    r.medium_steps = (uint64_t)num(meta, "medium_steps", 0);
    r.walks_truncated = (uint64_t)num(meta, "walks_truncated", 0);
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
    if (pbrt ? ts_scene_load_pbrt_text(stext, slen, files, "scene.pbrt", limits, srv_warnings_collect, &warnings, &scene, &err)
             : ts_scene_load_text(stext, slen, bundle ? files : assets_dir, "scene", limits, &scene, &err)) {
        snprintf(failure, sizeof failure, "the checkpointed scene no longer loads: %s", err.message);
        goto add;
    }
    r.settings.integrator = scene->integrator.type;
    r.settings.adaptive = scene->job.adaptive; /* only the scene asks for it */
    if (!meta) ts_job_settings_from_scene(scene, &r.settings);
    if (r.state == TS_JOB_FAILED) goto add;
    int nx, ny;
    ts_tile_grid_size(scene->crop_x1 - scene->crop_x0, scene->crop_y1 - scene->crop_y0, &nx, &ny);
    snprintf(path, sizeof path, "%s/film.bin", folder);
    snprintf(rel, sizeof rel, "jobs/%s/film.bin", id);
    bool missing = false;
    if (!damaged[0]) {
        film = read_film(path, rel, scene, nx, ny, &tile_spp, &active, &active_spp, &missing, &err);
        if (!film && (!missing || ts_job_state_finished(r.state))) snprintf(damaged, sizeof damaged, "%s", err.message);
        /* An adaptive job past its first check needs the pixels it chose (render/adaptive.h). */
        bool past_first = false;
        for (int i = 0; film && i < nx * ny; i++) past_first = past_first || tile_spp[i] > TS_ADAPTIVE_MIN_SPP;
        if (film && r.settings.adaptive && !ts_job_state_finished(r.state) && !active && past_first)
            snprintf(damaged, sizeof damaged, "%s holds no active pixels for the adaptive job", rel);
    }
    if (damaged[0]) {
        /* From the scene, as if just submitted: no samples, counters or series kept. */
        ts_film_destroy(film);
        free(tile_spp);
        free(active);
        film = NULL, tile_spp = NULL, active = NULL;
        r.state = TS_JOB_QUEUED;
        r.elapsed_s = 0, r.nonfinite = 0, r.medium_steps = 0, r.walks_truncated = 0, r.history = NULL;
        if (stats) atomic_fetch_add(&stats->damaged, 1);
    }
add:
    if (failure[0]) r.failure = failure;
    r.scene = scene;
    r.film = film;
    r.tile_spp = tile_spp;
    r.active = active;
    r.active_spp = active_spp;
    srv_job *j = srv_store_restore(st, &r, &err);
    if (j && j->sj) scene = NULL, film = NULL; /* the job owns them now */
    if (j) {
        if (damaged[0]) {
            char why[700];
            snprintf(why, sizeof why, "the checkpoint was damaged (%s): the job renders again from its scene", damaged);
            srv_job_set_checkpoint_error(j, why);
            j->saved_version = 0; /* write a good checkpoint at the next chance */
            fprintf(stderr, "tessera: restored job %s (queued): %s\n", id, why);
        } else {
            j->saved_version = atomic_load(&j->version);
            fprintf(stderr, "tessera: restored job %s (%s)\n", id, r.failure ? r.failure : ts_job_state_name(r.state));
        }
    }
    srv_job_release(j);
    srv_warnings_fini(&warnings);
    ts_scene_destroy(scene);
    ts_film_destroy(film);
    free(tile_spp);
    free(active);
    cJSON_Delete(meta);
    free(jtext);
    free(stext);
}

/* A job folder's name: what job ids are made of, [0-9A-Za-z_-], at most 23 characters. */
static bool job_id_name(const char *name)
{
    size_t n = strlen(name);
    if (n == 0 || n >= sizeof(((entry *)0)->id)) return false;
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == '-'))
            return false;
    }
    return true;
}

int srv_persist_restore_all(const char *dir, srv_store *st, const ts_scene_limits *limits, const char *assets_dir,
                            srv_persist_stats *stats)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/jobs", dir);
    DIR *d = opendir(path);
    if (!d) return 0;
    entry *e = NULL;
    int n = 0, cap = 0, stray = 0, swept = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
        char folder[4200], jp[4300];
        snprintf(folder, sizeof folder, "%s/%s", path, de->d_name);
        struct stat sb;
        /* Only folders named like a job are jobs (lstat: a symbolic link is not one); a
         * stray file or link is left alone and counted, and holds no --max-jobs place. */
        if (!job_id_name(de->d_name) || lstat(folder, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
            stray++;
            continue;
        }
        swept += sweep_temporaries(folder); /* before any writer starts */
        snprintf(jp, sizeof jp, "%s/scene.json", folder);
        if (lstat(jp, &sb) != 0 && errno == ENOENT) {
            snprintf(jp, sizeof jp, "%s/job.json", folder);
            if (lstat(jp, &sb) != 0 && errno == ENOENT) {
                /* Neither file ever landed (a submission on a full disk, a crash before
                 * the first rename): nothing was accepted from here (a bundle's files/
                 * may have been moved in: they go too). */
                snprintf(jp, sizeof jp, "%s/files", folder);
                if (lstat(jp, &sb) == 0 && S_ISDIR(sb.st_mode)) srv_bundle_remove_tree(jp);
                if (rmdir(folder) != 0) stray++;
                continue;
            }
        }
        if (n == cap) {
            cap = cap ? cap * 2 : 16;
            entry *ne = realloc(e, sizeof *e * (size_t)cap);
            if (!ne) break;
            e = ne;
        }
        snprintf(e[n].id, sizeof e[n].id, "%s", de->d_name);
        snprintf(jp, sizeof jp, "%s/job.json", folder);
        size_t len = 0;
        const char *why;
        char *t = read_all(jp, &len, &why);
        cJSON *o = t ? cJSON_ParseWithLength(t, len) : NULL;
        e[n].created = o ? num(o, "created_at", 0) : 0;
        cJSON_Delete(o);
        free(t);
        n++;
    }
    closedir(d);
    if (stats) {
        atomic_store(&stats->stray_entries, (uint64_t)stray);
        atomic_fetch_add(&stats->temporaries_removed, (uint64_t)swept);
    }
    if (swept || stray)
        fprintf(stderr, "tessera serve: --data: removed %d temporary file(s) left by an earlier run; %d entr%s under jobs/ %s not a job (left alone)\n",
                swept, stray, stray == 1 ? "y" : "ies", stray == 1 ? "is" : "are");
    if (n) qsort(e, (size_t)n, sizeof *e, cmp_entry); /* e may be NULL when the folder is empty */
    for (int i = 0; i < n; i++) restore_one(dir, e[i].id, st, limits, assets_dir, stats);
    free(e);
    return n;
}
