/* render.c — the tile loop and its thread pool; see render.h. */
#include "render/render.h"

#include <math.h>

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "camera/camera.h"
#include "integrators/effects.h"

double ts_now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void ts_tile_grid_size(int w, int h, int *nx, int *ny)
{
    *nx = (w + TS_TILE_SIZE - 1) / TS_TILE_SIZE;
    *ny = (h + TS_TILE_SIZE - 1) / TS_TILE_SIZE;
}

ts_tile_rect ts_tile_grid_rect(int x0, int y0, int w, int h, int tx, int ty)
{
    ts_tile_rect t = {tx, ty, x0 + tx * TS_TILE_SIZE, y0 + ty * TS_TILE_SIZE, 0, 0};
    t.w = (tx + 1) * TS_TILE_SIZE <= w ? TS_TILE_SIZE : w - tx * TS_TILE_SIZE;
    t.h = (ty + 1) * TS_TILE_SIZE <= h ? TS_TILE_SIZE : h - ty * TS_TILE_SIZE;
    return t;
}

typedef struct keyed { float key; int y, x, index; } keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *ta = a, *tb = b;
    if (ta->key != tb->key) return ta->key < tb->key ? -1 : 1;
    if (ta->y != tb->y) return ta->y < tb->y ? -1 : 1;
    return ta->x < tb->x ? -1 : (ta->x > tb->x);
}

void ts_tile_grid_order(int x0, int y0, int w, int h, int full_w, int full_h, int *order)
{
    int nx, ny;
    ts_tile_grid_size(w, h, &nx, &ny);
    keyed *k = malloc(sizeof *k * (size_t)nx * (size_t)ny);
    for (int ty = 0; ty < ny; ty++)
        for (int tx = 0; tx < nx; tx++) {
            int i = ty * nx + tx;
            ts_tile_rect t = ts_tile_grid_rect(x0, y0, w, h, tx, ty);
            float dx = t.x + t.w * 0.5f - full_w * 0.5f, dy = t.y + t.h * 0.5f - full_h * 0.5f;
            if (k) k[i] = (keyed){dx * dx + dy * dy, t.y, t.x, i};
            order[i] = i;
        }
    if (!k) return; /* out of memory: row-major order, still every tile once */
    qsort(k, (size_t)nx * (size_t)ny, sizeof *k, cmp_keyed);
    for (int i = 0; i < nx * ny; i++) order[i] = k[i].index;
    free(k);
}

typedef struct job {
    const ts_render_request *req;
    ts_tile_rect *tiles;
    int n_tiles;
    atomic_int next;        /* next tile to take */
    pthread_mutex_t lock;   /* guards stats while workers add their counters */
    ts_render_stats *stats;
} job;

bool ts_render_tile(const ts_render_request *req, int x0, int y0, int w, int h, ts_counters *c)
{
    c->stop = req->stop;
    const ts_scene *s = req->scene;
    uint32_t fx = req->generic ? TS_EFFECTS_ALL & ~s->job.effects_off : s->effects;
    ts_camera cam = s->camera;
    if (!(fx & TS_EFFECT_DEPTH_OF_FIELD)) cam.lens_radius = 0; /* the lens sample is still drawn */
    const float diff_scale = 1 / sqrtf((float)s->spp); /* pbrt-v3's ScaleDifferentials(1/√spp) */
    /* The scene's motion, not the specialisation's flags: the time dimension is there or not
     * whatever the effects analysis skips (a generic render of a static scene keeps its pixels). */
    const bool motion = (s->effects & TS_EFFECT_MOTION) != 0;
    for (int y = y0; y < y0 + h; y++)
        for (int x = x0; x < x0 + w; x++) {
            if (req->active &&
                !req->active[(size_t)(x - req->film->x0) + (size_t)(y - req->film->y0) * (size_t)req->film->width])
                continue;
            ts_sampler_pixel pixel; /* the pixel's scramble seeds, shared by its samples */
            ts_sampler_pixel_init(&s->sampler, (uint32_t)x, (uint32_t)y, &pixel);
            for (uint32_t i = req->sample_begin; i < req->sample_end; i++) {
                if (req->stop && atomic_load_explicit(req->stop, memory_order_relaxed)) return false;
                ts_sample_stream st;
                ts_sampler_begin_in_pixel(&pixel, i, &st);
                ts_vec2 u_film = ts_sample_2d(&st);
                /* The lens dimension is reserved either way, so later dimensions keep their
                 * values; a pinhole camera just does not compute it. */
                ts_vec2 u_lens = {0, 0};
                if (cam.lens_radius > 0) u_lens = ts_sample_2d(&st);
                else st.dim++;
                float weight;
                ts_vec2 off = ts_filter_sample(&s->filter, u_film, &weight);
                ts_vec2 p_raster = {(float)x + 0.5f + off.x, (float)y + 0.5f + off.y};
                /* The shutter sample: a dimension only in a scene with motion (effects.h), so
                 * every other scene keeps its dimensions and pixels. */
                float time = cam.shutter_open;
                if (motion) time = ts_camera_time(&cam, ts_sample_1d(&st));
                ts_ray ray = ts_camera_ray(&cam, p_raster, u_lens);
                /* Differentials only where a texture reads them (differential.h). */
                ts_ray_differential rd;
                if (s->textured) ts_ray_differential_camera(&cam, p_raster, u_lens, &ray, diff_scale, &rd);
                if (cam.moving) {
                    ts_camera_move_ray(&cam, &ray, time);
                    if (s->textured) {
                        ts_vec3 o[2] = {rd.rx_o, rd.ry_o}, d[2] = {rd.rx_d, rd.ry_d};
                        ts_camera_move_points(&cam, time, o, d, 2);
                        rd.rx_o = o[0], rd.ry_o = o[1], rd.rx_d = d[0], rd.ry_d = d[1];
                    }
                } else {
                    ray.time = time;
                }
                ts_rgb L = ts_integrator_li(s, req->integrator, fx, &ray, s->textured ? &rd : NULL, &st, c);
                c->samples++;
                if (!ts_rgb_is_finite(L) || L.r < 0 || L.g < 0 || L.b < 0 || L.r > TS_FILM_SAMPLE_MAX ||
                    L.g > TS_FILM_SAMPLE_MAX || L.b > TS_FILM_SAMPLE_MAX) {
                    c->nonfinite++;
                    continue;
                }
                L = ts_film_clamp_luminance(L, s->max_sample_luminance);
                ts_film_add_sample(req->film, x, y, L, weight);
            }
        }
    return true;
}

static void *worker(void *arg)
{
    job *j = arg;
    const ts_render_request *req = j->req;
    ts_counters c = {0};
    for (;;) {
        if (req->cancel && atomic_load(req->cancel)) break;
        int k = atomic_fetch_add(&j->next, 1);
        if (k >= j->n_tiles) break;
        const ts_tile_rect *t = &j->tiles[k];
        ts_render_tile(req, t->x, t->y, t->w, t->h, &c);
        if (req->on_tile) req->on_tile(req->user, t->x, t->y, t->w, t->h);
    }
    pthread_mutex_lock(&j->lock);
    ts_counters *sc = &j->stats->counters;
    sc->camera_rays += c.camera_rays;
    sc->other_rays += c.other_rays;
    sc->samples += c.samples;
    sc->nonfinite += c.nonfinite;
    sc->medium_steps += c.medium_steps;
    sc->walks_truncated += c.walks_truncated;
    pthread_mutex_unlock(&j->lock);
    return NULL;
}

ts_status ts_render(const ts_render_request *req, ts_render_stats *stats, ts_error *err)
{
    const ts_film *f = req->film;
    int nx, ny;
    ts_tile_grid_size(f->width, f->height, &nx, &ny);
    job j = {0};
    j.req = req;
    j.n_tiles = nx * ny;
    j.stats = stats;
    j.tiles = malloc(sizeof *j.tiles * (size_t)j.n_tiles);
    int *order = malloc(sizeof *order * (size_t)j.n_tiles);
    if (!j.tiles || !order) {
        free(j.tiles);
        free(order);
        return ts_error_set(err, TS_ERR_NOMEM, "out of memory for %d tiles", j.n_tiles);
    }
    ts_tile_grid_order(f->x0, f->y0, f->width, f->height, f->full_width, f->full_height, order);
    for (int k = 0; k < j.n_tiles; k++)
        j.tiles[k] = ts_tile_grid_rect(f->x0, f->y0, f->width, f->height, order[k] % nx, order[k] / nx);
    free(order);
    atomic_init(&j.next, 0);
    pthread_mutex_init(&j.lock, NULL);

    double t0 = ts_now_seconds();
    int n = req->threads < 1 ? 1 : req->threads;
    pthread_t *th = calloc((size_t)n, sizeof *th);
    int started = 0;
    if (th)
        while (started < n && pthread_create(&th[started], NULL, worker, &j) == 0) started++;
    /* Fewer threads than asked (or none) still render everything: the workers share
     * the tiles, and with no worker at all this thread does the work. */
    if (started == 0) worker(&j);
    for (int i = 0; i < started; i++) pthread_join(th[i], NULL);
    stats->seconds += ts_now_seconds() - t0;
    stats->cancelled = req->cancel && atomic_load(req->cancel);
    pthread_mutex_destroy(&j.lock);
    free(th);
    free(j.tiles);
    (void)err;
    return TS_OK;
}

double ts_film_relative_error(const ts_film *f)
{
    double sum = 0;
    uint64_t n = 0;
    for (int y = f->y0; y < f->y0 + f->height; y++)
        for (int x = f->x0; x < f->x0 + f->width; x++) {
            sum += ts_film_pixel_relative_variance(f, x, y);
            n++;
        }
    return n ? sqrt(sum / (double)n) : 0;
}

double ts_film_pixel_relative_variance(const ts_film *f, int x, int y)
{
    ts_rgb m = ts_film_pixel_rgb(f, x, y);
    ts_rgb v = ts_film_pixel_variance(f, x, y);
    double lum = ts_rgb_luminance(m);
    /* Var[Y] of a linear combination, ignoring channel covariance (an upper bound for
     * positively correlated channels is within a factor of 3 of it). */
    double var = 0.2126 * 0.2126 * v.r + 0.7152 * 0.7152 * v.g + 0.0722 * 0.0722 * v.b;
    return var / (lum * lum + 1e-3);
}
