/* shard.c — farm shards: ranges, metadata, checkpoints, merge; see shard.h and
 * proto/shard-exr.md. */
#include "render/shard.h"

#include <errno.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "film/film_image.h"
#include "image/exr.h"
#include "render/render.h"

#define LAYOUT_NAME "shard-v1"

ts_sample_range ts_shard_range(uint32_t index, uint32_t count, uint32_t spp)
{
    ts_sample_range r = {(uint32_t)((uint64_t)index * spp / count), (uint32_t)((uint64_t)(index + 1) * spp / count)};
    return r;
}

static bool parse_u32(const char *s, uint32_t max, uint32_t *out)
{
    if (!s || !*s) return false;
    uint64_t v = 0;
    for (; *s; s++) {
        if (*s < '0' || *s > '9') return false;
        v = v * 10 + (uint64_t)(*s - '0');
        if (v > max) return false;
    }
    *out = (uint32_t)v;
    return true;
}

ts_status ts_shard_parse(const char *text, uint32_t *index, uint32_t *count, ts_error *err)
{
    char a[24], b[24];
    const char *slash = strchr(text, '/');
    size_t la = slash ? (size_t)(slash - text) : 0;
    if (!slash || la == 0 || la >= sizeof a || strlen(slash + 1) >= sizeof b)
        return ts_error_set(err, TS_ERR_INVALID, "expected I/N (e.g. 2/8) or auto, got '%s'", text);
    memcpy(a, text, la);
    a[la] = '\0';
    strcpy(b, slash + 1);
    if (!parse_u32(a, 1000000, index) || !parse_u32(b, 1000000, count) || *count == 0)
        return ts_error_set(err, TS_ERR_INVALID, "expected I/N with whole numbers, 1 ≤ N ≤ 1000000, got '%s'", text);
    if (*index >= *count)
        return ts_error_set(err, TS_ERR_INVALID, "shard index %u is out of range: shards of %u are numbered 0 to %u",
                            *index, *count, *count - 1);
    return TS_OK;
}

ts_status ts_shard_auto(const char *job_completion_index, const char *slurm_task_id, const char *slurm_task_count,
                        const char *slurm_task_min, uint32_t shard_count, uint32_t *index, uint32_t *count, char *how,
                        size_t how_len, ts_error *err)
{
    if (job_completion_index) {
        if (!parse_u32(job_completion_index, 1000000, index))
            return ts_error_set(err, TS_ERR_INVALID, "JOB_COMPLETION_INDEX='%s' is not a shard index",
                                job_completion_index);
        if (!shard_count)
            return ts_error_set(err, TS_ERR_INVALID,
                                "JOB_COMPLETION_INDEX=%u is set (Kubernetes Indexed Job) but the number of shards is "
                                "not: pass --shard-count with the Job's completions",
                                *index);
        *count = shard_count;
        if (*index >= *count)
            return ts_error_set(err, TS_ERR_INVALID, "JOB_COMPLETION_INDEX=%u is not below --shard-count %u", *index,
                                *count);
        snprintf(how, how_len, "shard %u/%u from JOB_COMPLETION_INDEX=%u and --shard-count %u (Kubernetes Indexed Job)",
                 *index, *count, *index, *count);
        return TS_OK;
    }
    if (slurm_task_id) {
        uint32_t id, min = 0;
        if (!parse_u32(slurm_task_id, 1000000, &id))
            return ts_error_set(err, TS_ERR_INVALID, "SLURM_ARRAY_TASK_ID='%s' is not a task index", slurm_task_id);
        if (slurm_task_min && !parse_u32(slurm_task_min, 1000000, &min))
            return ts_error_set(err, TS_ERR_INVALID, "SLURM_ARRAY_TASK_MIN='%s' is not a task index", slurm_task_min);
        if (!slurm_task_count || !parse_u32(slurm_task_count, 1000000, count) || *count == 0)
            return ts_error_set(err, TS_ERR_INVALID,
                                "SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is %s%s%s; is this a job array?",
                                slurm_task_count ? "'" : "not set", slurm_task_count ? slurm_task_count : "",
                                slurm_task_count ? "'" : "");
        if (shard_count && shard_count != *count)
            return ts_error_set(err, TS_ERR_INVALID, "--shard-count %u disagrees with SLURM_ARRAY_TASK_COUNT=%u",
                                shard_count, *count);
        if (id < min || id - min >= *count)
            return ts_error_set(err, TS_ERR_INVALID,
                                "SLURM_ARRAY_TASK_ID=%u is not within SLURM_ARRAY_TASK_MIN=%u + SLURM_ARRAY_TASK_COUNT=%u "
                                "(use a contiguous --array range)",
                                id, min, *count);
        *index = id - min;
        snprintf(how, how_len,
                 "shard %u/%u from SLURM_ARRAY_TASK_ID=%u, SLURM_ARRAY_TASK_MIN=%u, SLURM_ARRAY_TASK_COUNT=%u (Slurm job "
                 "array)",
                 *index, *count, id, min, *count);
        return TS_OK;
    }
    return ts_error_set(err, TS_ERR_INVALID,
                        "--shard auto: neither JOB_COMPLETION_INDEX (Kubernetes Indexed Job) nor SLURM_ARRAY_TASK_ID "
                        "(Slurm job array) is set; pass --shard I/N instead");
}

void ts_shard_format_ranges(const ts_sample_range *r, int n, char *out, size_t len)
{
    size_t used = 0;
    out[0] = '\0';
    for (int i = 0; i < n && used < len; i++) {
        int k = snprintf(out + used, len - used, "%s[%u,%u)", i ? " " : "", r[i].begin, r[i].end);
        if (k < 0) break;
        used += (size_t)k;
    }
    if (n == 0) snprintf(out, len, "none");
}

uint32_t ts_shard_range_samples(const ts_sample_range *r, int n)
{
    uint32_t s = 0;
    for (int i = 0; i < n; i++) s += r[i].end - r[i].begin;
    return s;
}

static void copy_str(char *dst, size_t n, const char *src)
{
    snprintf(dst, n, "%s", src ? src : "");
}

void ts_shard_info_init(ts_shard_info *info, const ts_scene *scene, const ts_film *film, const char *integrator,
                        const ts_sample_range *ranges, int n_ranges, uint32_t spp_total, double render_time_s)
{
    memset(info, 0, sizeof *info);
    copy_str(info->digest, sizeof info->digest, scene->digest);
    copy_str(info->scene, sizeof info->scene, scene->name);
    copy_str(info->integrator, sizeof info->integrator, integrator);
    copy_str(info->version, sizeof info->version, TS_VERSION);
    info->seed = scene->sampler.seed;
    info->spp_total = spp_total;
    info->full_width = film->full_width, info->full_height = film->full_height;
    info->x0 = film->x0, info->y0 = film->y0, info->width = film->width, info->height = film->height;
    info->n_ranges = n_ranges < TS_SHARD_MAX_RANGES ? n_ranges : TS_SHARD_MAX_RANGES;
    if (info->n_ranges) memcpy(info->ranges, ranges, (size_t)info->n_ranges * sizeof *ranges);
    info->render_time_s = render_time_s;
    info->film_scale = scene->film_scale;
}

/* ---------------------------------------------------------------- metadata */

static ts_status set_metadata(ts_image *img, const ts_shard_info *info, const ts_film *film, ts_error *err)
{
    char text[256];
    ts_status st = TS_OK;
    snprintf(text, sizeof text, "tessera %s", info->version);
    if (!st) st = ts_image_set_string(img, "software", text, err);
    if (!st) st = ts_image_set_string(img, "tessera_layout", LAYOUT_NAME, err);
    if (!st) st = ts_image_set_string(img, "tessera_version", info->version, err);
    if (!st) st = ts_image_set_string(img, "tessera_scene", info->scene, err);
    if (!st) st = ts_image_set_string(img, "tessera_scene_digest", info->digest, err);
    if (!st) st = ts_image_set_string(img, "tessera_integrator", info->integrator, err);
    if (!st) st = ts_image_set_int(img, "tessera_seed", (int32_t)info->seed, err); /* uint32 as two's complement */
    if (!st) st = ts_image_set_int(img, "tessera_spp_total", (int32_t)info->spp_total, err);
    if (!st) st = ts_image_set_int(img, "tessera_spp", (int32_t)ts_shard_range_samples(info->ranges, info->n_ranges), err);
    ts_shard_format_ranges(info->ranges, info->n_ranges, text, sizeof text);
    if (!st) st = ts_image_set_string(img, "tessera_samples", text, err);
    if (!st) st = ts_image_set_int(img, "tessera_uneven", info->uneven ? 1 : 0, err);
    if (!st) st = ts_image_set_int(img, "tessera_full_width", info->full_width, err);
    if (!st) st = ts_image_set_int(img, "tessera_full_height", info->full_height, err);
    if (!st) st = ts_image_set_int(img, "tessera_x0", info->x0, err);
    if (!st) st = ts_image_set_int(img, "tessera_y0", info->y0, err);
    if (!st) st = ts_image_set_double(img, "tessera_render_time_s", info->render_time_s, err);
    if (!st) st = ts_image_set_double(img, "tessera_error_estimate", ts_film_relative_error(film), err);
    if (!st) st = ts_image_set_double(img, "tessera_film_scale", info->film_scale, err);
    return st;
}

ts_status ts_shard_write(const char *path, const ts_film *film, const ts_shard_info *info, ts_error *err)
{
    ts_image img;
    ts_status st = ts_film_to_image(film, TS_FILM_IMAGE_SHARD, &img, err);
    if (st) return st;
    st = set_metadata(&img, info, film, err);
    if (!st) st = ts_exr_write(path, &img, err);
    ts_image_fini(&img);
    return st;
}

static bool get_string(const ts_image *img, const char *name, char *out, size_t n)
{
    const ts_image_attr *a = ts_image_attr_find(img, name);
    if (!a || a->type != TS_ATTR_STRING) return false;
    copy_str(out, n, a->s);
    return true;
}

static bool get_int(const ts_image *img, const char *name, int32_t *out)
{
    const ts_image_attr *a = ts_image_attr_find(img, name);
    if (!a || a->type != TS_ATTR_INT) return false;
    *out = a->i;
    return true;
}

static bool parse_ranges(const char *s, ts_shard_info *info)
{
    info->n_ranges = 0;
    if (strcmp(s, "none") == 0) return true;
    while (*s) {
        unsigned b, e;
        int used = 0;
        if (sscanf(s, "[%u,%u)%n", &b, &e, &used) != 2 || used == 0 || b >= e || e > info->spp_total) return false;
        if (info->n_ranges == TS_SHARD_MAX_RANGES) return false;
        if (info->n_ranges && b <= info->ranges[info->n_ranges - 1].end) return false; /* sorted, disjoint */
        info->ranges[info->n_ranges++] = (ts_sample_range){b, e};
        s += used;
        if (*s == ' ') s++;
        else if (*s) return false;
    }
    return true;
}

/* Fills info from img's attributes; path only for messages. */
static ts_status read_metadata(const ts_image *img, const char *path, ts_shard_info *info, ts_error *err)
{
    memset(info, 0, sizeof *info);
    char layout[32] = "", ranges[256] = "";
    if (!get_string(img, "tessera_layout", layout, sizeof layout) || !ts_film_image_is_shard(img))
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s is not a tessera shard (it lacks the shard channels and metadata); shards come from "
                            "`tessera render SCENE --shard I/N -o FILE.exr` or `tessera merge`",
                            path);
    if (strcmp(layout, LAYOUT_NAME) != 0)
        return ts_error_set(err, TS_ERR_UNSUPPORTED, "%s is a shard of layout '%s'; this tessera reads '%s'", path, layout,
                            LAYOUT_NAME);
    int32_t seed = 0, spp_total = 0, fw = 0, fh = 0, x0 = 0, y0 = 0, uneven = 0;
    bool ok = get_string(img, "tessera_scene_digest", info->digest, sizeof info->digest) &&
              get_string(img, "tessera_integrator", info->integrator, sizeof info->integrator) &&
              get_string(img, "tessera_samples", ranges, sizeof ranges) && get_int(img, "tessera_seed", &seed) &&
              get_int(img, "tessera_spp_total", &spp_total) && get_int(img, "tessera_full_width", &fw) &&
              get_int(img, "tessera_full_height", &fh) && get_int(img, "tessera_x0", &x0) &&
              get_int(img, "tessera_y0", &y0);
    get_string(img, "tessera_scene", info->scene, sizeof info->scene);
    get_string(img, "tessera_version", info->version, sizeof info->version);
    get_int(img, "tessera_uneven", &uneven);
    const ts_image_attr *t = ts_image_attr_find(img, "tessera_render_time_s");
    if (t && t->type == TS_ATTR_DOUBLE) info->render_time_s = t->d;
    const ts_image_attr *fs = ts_image_attr_find(img, "tessera_film_scale");
    info->film_scale = fs && fs->type == TS_ATTR_DOUBLE ? fs->d : 1; /* older shards: none */
    if (!(info->film_scale > 0 && info->film_scale <= FLT_MAX))
        return ts_error_set(err, TS_ERR_INVALID, "%s: tessera_film_scale %g is not a finite number > 0", path,
                            info->film_scale);
    if (!ok)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the shard metadata is incomplete (a tessera_* attribute is missing)",
                            path);
    info->seed = (uint32_t)seed;
    info->spp_total = (uint32_t)spp_total;
    info->full_width = fw, info->full_height = fh, info->x0 = x0, info->y0 = y0;
    info->width = img->width, info->height = img->height;
    info->uneven = uneven != 0;
    if (spp_total < 1 || fw < 1 || fh < 1 || x0 < 0 || y0 < 0 || x0 > fw - img->width || y0 > fh - img->height)
        return ts_error_set(err, TS_ERR_INVALID, "%s: the shard metadata is inconsistent (spp or film window)", path);
    if (!parse_ranges(ranges, info))
        return ts_error_set(err, TS_ERR_INVALID, "%s: tessera_samples '%s' is not a list of sample ranges within [0,%d)",
                            path, ranges, spp_total);
    return TS_OK;
}

ts_status ts_shard_read(const char *path, ts_shard_info *info, ts_film **film, ts_error *err)
{
    *film = NULL;
    ts_image img = {0};
    ts_status st = ts_exr_read(path, &img, err);
    if (st) return st;
    st = read_metadata(&img, path, info, err);
    if (!st) {
        *film = ts_film_from_image(&img, info->full_width, info->full_height, info->x0, info->y0, err);
        if (*film) (*film)->scale = (float)info->film_scale;
        if (!*film) {
            st = err->status ? err->status : TS_ERR_INVALID;
            ts_error_prefix(err, "%s", path);
        }
    }
    ts_image_fini(&img);
    return st;
}

/* Sentence for the first way b is not of the same render as a; TS_OK when it is. */
static ts_status same_render(const ts_shard_info *a, const char *fa, const ts_shard_info *b, const char *fb,
                             bool same_window, ts_error *err)
{
    if (strcmp(a->digest, b->digest) != 0)
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s and %s are of different scenes (digest %.12s… vs %.12s…); only shards of one scene "
                            "merge",
                            fa, fb, a->digest, b->digest);
    if (a->seed != b->seed)
        return ts_error_set(err, TS_ERR_INVALID, "%s and %s were rendered with different seeds (%u and %u)", fa, fb,
                            a->seed, b->seed);
    if (a->spp_total != b->spp_total)
        return ts_error_set(err, TS_ERR_INVALID, "%s and %s split different sample counts (%u and %u spp)", fa, fb,
                            a->spp_total, b->spp_total);
    if (a->full_width != b->full_width || a->full_height != b->full_height)
        return ts_error_set(err, TS_ERR_INVALID, "%s and %s are of different image sizes (%d×%d and %d×%d)", fa, fb,
                            a->full_width, a->full_height, b->full_width, b->full_height);
    if (strcmp(a->integrator, b->integrator) != 0)
        return ts_error_set(err, TS_ERR_INVALID, "%s and %s were rendered with different integrators ('%s' and '%s')", fa,
                            fb, a->integrator, b->integrator);
    if (a->film_scale != b->film_scale)
        return ts_error_set(err, TS_ERR_INVALID, "%s and %s have different film scales (%g and %g)", fa, fb,
                            a->film_scale, b->film_scale);
    if (same_window && (a->x0 != b->x0 || a->y0 != b->y0 || a->width != b->width || a->height != b->height))
        return ts_error_set(err, TS_ERR_INVALID, "%s covers a different film window than %s", fb, fa);
    return TS_OK;
}

ts_status ts_shard_checkpoint_load(const char *path, const ts_shard_info *want, ts_sample_range want_range,
                                   ts_film **film, uint32_t *resume_at, ts_error *err)
{
    *film = NULL;
    *resume_at = want_range.begin;
    struct stat sb;
    if (stat(path, &sb) != 0 && errno == ENOENT) return TS_OK;
    ts_shard_info have;
    ts_film *f;
    ts_status st = ts_shard_read(path, &have, &f, err);
    if (st) return st;
    ts_error why = {0};
    if (same_render(want, "this render", &have, path, true, &why)) {
        ts_film_destroy(f);
        return ts_error_set(err, TS_ERR_INVALID, "checkpoint %s is not of this render: %s; delete it or choose another file",
                            path, why.message);
    }
    if (have.n_ranges > 1 || have.uneven ||
        (have.n_ranges == 1 && (have.ranges[0].begin != want_range.begin || have.ranges[0].end > want_range.end))) {
        char got[256];
        ts_shard_format_ranges(have.ranges, have.n_ranges, got, sizeof got);
        ts_film_destroy(f);
        return ts_error_set(err, TS_ERR_INVALID,
                            "checkpoint %s holds samples %s, not a beginning of this shard's [%u,%u); delete it or "
                            "choose another file",
                            path, got, want_range.begin, want_range.end);
    }
    *film = f;
    *resume_at = have.n_ranges ? have.ranges[0].end : want_range.begin;
    return TS_OK;
}

/* ---------------------------------------------------------------- merge */

typedef struct merged_file {
    char *path;
    ts_shard_info info;
} merged_file;

struct ts_merge {
    merged_file *files;
    int n, cap;
    ts_film *full;   /* accumulator over the whole image */
    ts_film *result; /* the target window, made by ts_merge_result */
};

ts_merge *ts_merge_create(ts_error *err)
{
    ts_merge *m = calloc(1, sizeof *m);
    if (!m) ts_error_set(err, TS_ERR_NOMEM, "out of memory");
    return m;
}

void ts_merge_destroy(ts_merge *m)
{
    if (!m) return;
    for (int i = 0; i < m->n; i++) free(m->files[i].path);
    free(m->files);
    ts_film_destroy(m->full);
    ts_film_destroy(m->result);
    free(m);
}

static bool windows_intersect(const ts_shard_info *a, const ts_shard_info *b)
{
    return a->x0 < b->x0 + b->width && b->x0 < a->x0 + a->width && a->y0 < b->y0 + b->height &&
           b->y0 < a->y0 + a->height;
}

/* First sample range common to a and b, or false. */
static bool ranges_intersect(const ts_shard_info *a, const ts_shard_info *b, ts_sample_range *common)
{
    for (int i = 0; i < a->n_ranges; i++)
        for (int j = 0; j < b->n_ranges; j++) {
            uint32_t lo = a->ranges[i].begin > b->ranges[j].begin ? a->ranges[i].begin : b->ranges[j].begin;
            uint32_t hi = a->ranges[i].end < b->ranges[j].end ? a->ranges[i].end : b->ranges[j].end;
            if (lo < hi) {
                *common = (ts_sample_range){lo, hi};
                return true;
            }
        }
    return false;
}

ts_status ts_merge_add_file(ts_merge *m, const char *path, ts_error *err)
{
    ts_shard_info info;
    ts_film *film;
    ts_status st = ts_shard_read(path, &info, &film, err);
    if (st) return st;
    if (info.uneven) {
        ts_film_destroy(film);
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s is a partial merge of region shards whose pixels hold different sample ranges; merge "
                            "the original shards instead",
                            path);
    }
    for (int i = 0; i < m->n; i++) {
        const merged_file *o = &m->files[i];
        if (i == 0 && (st = same_render(&o->info, o->path, &info, path, false, err))) goto fail;
        ts_sample_range c;
        if (windows_intersect(&o->info, &info) && ranges_intersect(&o->info, &info, &c)) {
            st = ts_error_set(err, TS_ERR_INVALID,
                              "%s and %s overlap: both hold samples [%u,%u) of the same pixels, which would count them "
                              "twice",
                              o->path, path, c.begin, c.end);
            goto fail;
        }
    }
    if (m->n == m->cap) {
        int cap = m->cap ? 2 * m->cap : 8;
        merged_file *f = realloc(m->files, (size_t)cap * sizeof *f);
        if (!f) goto nomem;
        m->files = f, m->cap = cap;
    }
    if (!m->full && !(m->full = ts_film_create(info.full_width, info.full_height, 0, 0, info.full_width,
                                               info.full_height, err))) {
        st = err->status;
        goto fail;
    }
    char *p = strdup(path);
    if (!p) goto nomem;
    ts_film_merge(m->full, film);
    ts_film_destroy(film);
    m->files[m->n++] = (merged_file){p, info};
    ts_film_destroy(m->result);
    m->result = NULL;
    return TS_OK;
nomem:
    st = ts_error_set(err, TS_ERR_NOMEM, "out of memory while merging %s", path);
fail:
    ts_film_destroy(film);
    return st;
}

bool ts_merge_file_info(const ts_merge *m, int i, ts_shard_info *info)
{
    if (i < 0 || i >= m->n) return false;
    *info = m->files[i].info;
    return true;
}

/* The target window: the common window when all files share one, else the whole image. */
static void target_window(const ts_merge *m, ts_shard_info *t)
{
    *t = m->files[0].info;
    for (int i = 1; i < m->n; i++) {
        const ts_shard_info *o = &m->files[i].info;
        if (o->x0 != t->x0 || o->y0 != t->y0 || o->width != t->width || o->height != t->height) {
            t->x0 = t->y0 = 0;
            t->width = t->full_width, t->height = t->full_height;
            return;
        }
    }
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Sorted unique cuts of one axis: the target's ends plus every file's window/range ends
 * inside it. kind 0: x, 1: y, 2: samples. Returns the count; cuts has room for 2n+2. */
static int cuts(const ts_merge *m, const ts_shard_info *t, int kind, uint32_t *c)
{
    int n = 0;
    uint32_t lo = kind == 0 ? (uint32_t)t->x0 : kind == 1 ? (uint32_t)t->y0 : 0;
    uint32_t hi = kind == 0 ? (uint32_t)(t->x0 + t->width) : kind == 1 ? (uint32_t)(t->y0 + t->height) : t->spp_total;
    c[n++] = lo, c[n++] = hi;
    for (int i = 0; i < m->n; i++) {
        const ts_shard_info *o = &m->files[i].info;
        uint32_t v[2 * TS_SHARD_MAX_RANGES];
        int k = 0;
        if (kind == 0) v[k++] = (uint32_t)o->x0, v[k++] = (uint32_t)(o->x0 + o->width);
        else if (kind == 1) v[k++] = (uint32_t)o->y0, v[k++] = (uint32_t)(o->y0 + o->height);
        else
            for (int r = 0; r < o->n_ranges; r++) v[k++] = o->ranges[r].begin, v[k++] = o->ranges[r].end;
        for (int j = 0; j < k; j++)
            if (v[j] > lo && v[j] < hi) c[n++] = v[j];
    }
    qsort(c, (size_t)n, sizeof *c, cmp_u32);
    int u = 0;
    for (int i = 0; i < n; i++)
        if (!u || c[u - 1] != c[i]) c[u++] = c[i];
    return u;
}

static bool holds(const ts_shard_info *o, uint32_t x, uint32_t y, uint32_t s)
{
    if ((int)x < o->x0 || (int)x >= o->x0 + o->width || (int)y < o->y0 || (int)y >= o->y0 + o->height) return false;
    for (int r = 0; r < o->n_ranges; r++)
        if (s >= o->ranges[r].begin && s < o->ranges[r].end) return true;
    return false;
}

/* Walks the grid of cells (x cut × y cut × sample cut); for each cell of a rectangle
 * calls back with whether it is held. Used for both "missing" and "uneven". */
typedef struct cell_walk {
    uint32_t *xs, *ys, *ss;
    int nx, ny, ns;
} cell_walk;

static bool walk_init(const ts_merge *m, const ts_shard_info *t, cell_walk *w)
{
    size_t room = (size_t)(2 * TS_SHARD_MAX_RANGES * m->n + 2);
    w->xs = malloc(room * sizeof *w->xs), w->ys = malloc(room * sizeof *w->ys), w->ss = malloc(room * sizeof *w->ss);
    if (!w->xs || !w->ys || !w->ss) {
        free(w->xs), free(w->ys), free(w->ss);
        return false;
    }
    w->nx = cuts(m, t, 0, w->xs), w->ny = cuts(m, t, 1, w->ys), w->ns = cuts(m, t, 2, w->ss);
    return true;
}

static void walk_fini(cell_walk *w) { free(w->xs), free(w->ys), free(w->ss); }

static bool cell_held(const ts_merge *m, const cell_walk *w, int i, int j, int k)
{
    for (int f = 0; f < m->n; f++)
        if (holds(&m->files[f].info, w->xs[i], w->ys[j], w->ss[k])) return true;
    return false;
}

int ts_merge_missing(const ts_merge *m, char *out, size_t len)
{
    out[0] = '\0';
    if (m->n == 0) return 0;
    ts_shard_info t;
    target_window(m, &t);
    cell_walk w;
    if (!walk_init(m, &t, &w)) {
        snprintf(out, len, "(out of memory while listing missing samples)");
        return 1;
    }
    bool whole = t.x0 == 0 && t.y0 == 0 && t.width == t.full_width && t.height == t.full_height;
    bool one_rect = w.nx == 2 && w.ny == 2;
    int pieces = 0;
    size_t used = 0;
    for (int j = 0; j + 1 < w.ny; j++)
        for (int i = 0; i + 1 < w.nx; i++)
            for (int k = 0; k + 1 < w.ns; k++) {
                if (cell_held(m, &w, i, j, k)) continue;
                uint32_t s0 = w.ss[k], s1 = w.ss[k + 1];
                while (k + 2 < w.ns && !cell_held(m, &w, i, j, k + 1)) s1 = w.ss[++k + 1]; /* join neighbours */
                pieces++;
                if (used >= len) continue;
                int n;
                if (one_rect && whole)
                    n = snprintf(out + used, len - used, "%ssamples [%u,%u) of every pixel", used ? "\n" : "", s0, s1);
                else
                    n = snprintf(out + used, len - used, "%ssamples [%u,%u) of pixels x [%u,%u), y [%u,%u)",
                                 used ? "\n" : "", s0, s1, w.xs[i], w.xs[i + 1], w.ys[j], w.ys[j + 1]);
                used = n < 0 ? len : used + (size_t)n;
            }
    if (used >= len && len > 4) memcpy(out + len - 4, "...", 4);
    walk_fini(&w);
    return pieces;
}

const ts_film *ts_merge_result(ts_merge *m, ts_shard_info *info, int *n_files)
{
    if (n_files) *n_files = m->n;
    if (m->n == 0) return NULL;
    ts_shard_info t;
    target_window(m, &t);
    /* Sample ranges: the union over files; uneven when some cell lacks part of it. */
    t.n_ranges = 0;
    t.render_time_s = 0;
    for (int f = 0; f < m->n; f++) t.render_time_s += m->files[f].info.render_time_s;
    cell_walk w;
    if (walk_init(m, &t, &w)) {
        for (int k = 0; k + 1 < w.ns; k++) {
            bool any = false, all = true;
            for (int j = 0; j + 1 < w.ny; j++)
                for (int i = 0; i + 1 < w.nx; i++) {
                    bool h = cell_held(m, &w, i, j, k);
                    any |= h, all &= h;
                }
            if (any && !all) t.uneven = true;
            if (!any) continue;
            if (t.n_ranges && t.ranges[t.n_ranges - 1].end == w.ss[k]) t.ranges[t.n_ranges - 1].end = w.ss[k + 1];
            else if (t.n_ranges < TS_SHARD_MAX_RANGES) t.ranges[t.n_ranges++] = (ts_sample_range){w.ss[k], w.ss[k + 1]};
            else t.uneven = true;
        }
        walk_fini(&w);
    } else {
        t.uneven = true;
    }
    if (!m->result) {
        ts_error e = {0};
        m->result = ts_film_create(t.full_width, t.full_height, t.x0, t.y0, t.width, t.height, &e);
        if (!m->result) return NULL;
        m->result->scale = (float)t.film_scale;
        ts_film_merge(m->result, m->full);
    }
    if (info) *info = t;
    return m->result;
}
