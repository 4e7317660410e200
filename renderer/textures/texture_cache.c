/* texture_cache.c — the MIP maps of a scene's image textures (see texture_cache.h).
 * A scene names few image files: the entries are a list searched linearly. */
#include "textures/texture_cache.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "image/image.h"
#include "core/scene_path.h"
#include "textures/texture_image.h"

typedef struct cache_entry {
    struct cache_entry *next;
    char *path; /* canonical */
    char *file; /* as the first texture to name it wrote it */
    int n_channels;
    bool gamma;
    uint32_t scale_bits;
    ts_texture_wrap wrap;
    ts_mipmap *map;
} cache_entry;

struct ts_texture_cache {
    cache_entry *head;
    size_t max_bytes, bytes, count;
};

ts_texture_cache *ts_texture_cache_create(size_t max_bytes)
{
    ts_texture_cache *c = calloc(1, sizeof *c);
    if (c) c->max_bytes = max_bytes;
    return c;
}

void ts_texture_cache_destroy(ts_texture_cache *c)
{
    if (!c) return;
    for (cache_entry *e = c->head, *next; e; e = next) {
        next = e->next;
        ts_mipmap_destroy(e->map);
        free(e->path);
        free(e->file);
        free(e);
    }
    free(c);
}

size_t ts_texture_cache_bytes(const ts_texture_cache *c) { return c ? c->bytes : 0; }
size_t ts_texture_cache_count(const ts_texture_cache *c) { return c ? c->count : 0; }

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Whether an image of w × h pixels and `decoded` channels fits what is left of the budget:
 * its decoded floats, and its MIP map of n_channels (checked first: the message tests
 * and users know). */
static ts_status check_budget(const ts_texture_cache *c, const char *filename, int64_t w, int64_t h, int decoded,
                              int n_channels, ts_error *err)
{
    if (!c->max_bytes) return TS_OK;
    size_t left = c->max_bytes - c->bytes;
    size_t need = w <= INT32_MAX && h <= INT32_MAX ? ts_mipmap_bytes_for((int32_t)w, (int32_t)h, n_channels) : 0;
    if (need == 0)
        return ts_error_set(err, TS_ERR_LIMIT, "texture image '%s': %lld × %lld pixels, more than a MIP map's %d a side",
                            filename, (long long)w, (long long)h, TS_MIPMAP_MAX_SIZE);
    if (need > left)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "texture image '%s': its MIP map (%lld × %lld, %d channel%s) needs %zu bytes, more than the "
                            "%zu left of the textures' %zu",
                            filename, (long long)w, (long long)h, n_channels, n_channels == 1 ? "" : "s", need, left,
                            c->max_bytes);
    double image = (double)w * (double)h * (double)decoded * sizeof(float);
    if (image > (double)left)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "texture image '%s': decoding its %lld × %lld pixels of %d channels needs %.0f bytes, more "
                            "than the %zu left of the textures' %zu",
                            filename, (long long)w, (long long)h, decoded, image, left, c->max_bytes);
    return TS_OK;
}

ts_status ts_texture_cache_get(ts_texture_cache *c, const char *base_dir, const char *filename,
                               uint64_t max_file_bytes, const ts_texture_image_options *opt,
                               const ts_mipmap **out, ts_error *err)
{
    *out = NULL;
    if (opt->n_channels != 1 && opt->n_channels != 3)
        return ts_error_set(err, TS_ERR_INVALID, "texture image '%s': %d channels asked for (1 or 3)",
                            filename, opt->n_channels);
    if (!isfinite(opt->scale))
        return ts_error_set(err, TS_ERR_INVALID, "texture image '%s': the scale %g is not finite", filename,
                            (double)opt->scale);
    /* The format first: an unsupported file is named as such, present or not. */
    ts_image img = {0};
    ts_status st;
    if (ts_texture_image_format_of(filename) == TS_TEXTURE_IMAGE_UNKNOWN)
        return ts_texture_image_decode(filename, NULL, 0, &img, err);
    char path[PATH_MAX];
    st = ts_scene_path_resolve(base_dir, filename, path, sizeof path, err);
    if (st) { /* "'x.png': …" → "texture image 'x.png': …", as ts_scene_path_read words it */
        if (err) {
            char msg[TS_ERROR_MAX];
            memcpy(msg, err->message, sizeof msg);
            ts_error_set(err, st, "texture image %s", msg);
        }
        return st;
    }
    uint32_t scale_bits = float_bits(opt->scale);
    for (cache_entry *e = c->head; e; e = e->next)
        if (e->n_channels == opt->n_channels && e->gamma == opt->gamma && e->scale_bits == scale_bits &&
            e->wrap == opt->wrap && strcmp(e->path, path) == 0) {
            *out = e->map;
            return TS_OK;
        }

    char *bytes = NULL;
    size_t len = 0;
    if ((st = ts_scene_path_read(base_dir, filename, "texture image", max_file_bytes, &bytes, &len, err)))
        return st;
    /* The budget, from the header's size before anything is decoded (a small file may
     * claim a huge image), and again from the decoded size. */
    int64_t hw, hh;
    int hc;
    if (ts_texture_image_size(filename, (const unsigned char *)bytes, len, &hw, &hh, &hc) &&
        (st = check_budget(c, filename, hw, hh, hc, opt->n_channels, err))) {
        free(bytes);
        return st;
    }
    st = ts_texture_image_decode(filename, (const unsigned char *)bytes, len, &img, err);
    free(bytes);
    if (st) return st;
    if ((st = check_budget(c, filename, img.width, img.height, img.n_channels, opt->n_channels, err))) {
        ts_image_fini(&img);
        return st;
    }
    float *texels = NULL;
    st = ts_texture_image_texels(&img, filename, opt->n_channels, opt->gamma, opt->scale, &texels, err);
    int w = img.width, h = img.height;
    ts_image_fini(&img);
    if (st) return st;
    ts_mipmap *map = NULL;
    st = ts_mipmap_create(texels, w, h, opt->n_channels, opt->wrap, 0, &map, err);
    free(texels);
    if (st) {
        ts_error_prefix(err, "texture image '%s'", filename);
        return st;
    }
    cache_entry *e = calloc(1, sizeof *e);
    char *p = e ? strdup(path) : NULL;
    char *f = p ? strdup(filename) : NULL;
    if (!e || !p || !f) {
        free(p);
        free(e);
        ts_mipmap_destroy(map);
        return ts_error_set(err, TS_ERR_NOMEM, "texture image '%s': out of memory", filename);
    }
    *e = (cache_entry){.next = c->head,
                       .path = p,
                       .file = f,
                       .n_channels = opt->n_channels,
                       .gamma = opt->gamma,
                       .scale_bits = scale_bits,
                       .wrap = opt->wrap,
                       .map = map};
    c->head = e;
    c->bytes += map->bytes;
    c->count++;
    *out = map;
    return TS_OK;
}

bool ts_texture_cache_source(const ts_texture_cache *c, const ts_mipmap *map, const char **filename,
                             ts_texture_image_options *opt)
{
    for (const cache_entry *e = c ? c->head : NULL; e; e = e->next)
        if (e->map == map) {
            *filename = e->file;
            memcpy(&opt->scale, &e->scale_bits, sizeof opt->scale);
            opt->n_channels = e->n_channels;
            opt->gamma = e->gamma;
            opt->wrap = e->wrap;
            return true;
        }
    return false;
}
