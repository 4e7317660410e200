/* film_image.c — film to image and back; see film_image.h (and proto/shard-exr.md). */
#include "film/film_image.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

/* SHARD channel order as written (the EXR file lists them sorted; readers go by name). */
enum { SH_R, SH_G, SH_B, SH_SUM_LO, SH_SQ_HI = SH_SUM_LO + 3, SH_SQ_LO = SH_SQ_HI + 3, SH_W_HI = SH_SQ_LO + 3,
       SH_W_LO, SH_WSQ, SH_COUNT, SH_N };
static const char *const shard_names[SH_N] = {"R", "G", "B", "sum.R.lo", "sum.G.lo", "sum.B.lo",
                                              "sq.R.hi", "sq.G.hi", "sq.B.hi", "sq.R.lo", "sq.G.lo", "sq.B.lo",
                                              "weight.hi", "weight.lo", "weight_sq", "count"};

#define MAX_EXACT_COUNT 16777216.0 /* 2^24: every whole number up to it is a float */

static bool fits_float(double x) { return fabs(x) <= FLT_MAX; }

/* x as an unevaluated pair hi + lo of floats. */
static void split(double x, float *hi, float *lo)
{
    *hi = (float)x;
    *lo = (float)(x - (double)*hi);
}

static ts_status shard_pixel(const ts_film_pixel *p, float *px, int x, int y, ts_error *err)
{
    bool ok = fits_float(p->weight) && fits_float(p->weight_sq);
    for (int c = 0; c < 3; c++) ok = ok && fits_float(p->sum[c]) && fits_float(p->sum_sq[c]);
    if (!ok)
        return ts_error_set(err, TS_ERR_LIMIT, "pixel (%d, %d) has sums beyond float range; it cannot be stored in a shard",
                            x, y);
    if ((double)p->count > MAX_EXACT_COUNT)
        return ts_error_set(err, TS_ERR_LIMIT,
                            "pixel (%d, %d) has %llu samples; a shard stores at most 16777216 per pixel", x, y,
                            (unsigned long long)p->count);
    split(p->weight, &px[SH_W_HI], &px[SH_W_LO]);
    double w = (double)px[SH_W_HI] + (double)px[SH_W_LO]; /* what a reader will see */
    for (int c = 0; c < 3; c++) {
        float m = 0;
        if (w != 0) {
            m = (float)(p->sum[c] / w);
            if (!isfinite(m))
                return ts_error_set(err, TS_ERR_LIMIT,
                                    "pixel (%d, %d) has a mean beyond float range; it cannot be stored in a shard", x, y);
            px[SH_R + c] = m;
            px[SH_SUM_LO + c] = (float)(p->sum[c] - (double)m * w);
        } else {
            split(p->sum[c], &px[SH_R + c], &px[SH_SUM_LO + c]);
        }
        split(p->sum_sq[c], &px[SH_SQ_HI + c], &px[SH_SQ_LO + c]);
    }
    px[SH_WSQ] = (float)p->weight_sq;
    px[SH_COUNT] = (float)p->count;
    return TS_OK;
}

ts_status ts_film_to_image(const ts_film *f, ts_film_image_layout layout, ts_image *img, ts_error *err)
{
    static const char *const rgb[] = {"R", "G", "B"};
    static const char *const stats[] = {"R", "G", "B", "R.var", "G.var", "B.var", "count"};
    int nc = layout == TS_FILM_IMAGE_RGB ? 3 : layout == TS_FILM_IMAGE_STATS ? 7 : SH_N;
    const char *const *names = layout == TS_FILM_IMAGE_RGB ? rgb : layout == TS_FILM_IMAGE_STATS ? stats : shard_names;
    ts_status st = ts_image_init(img, f->width, f->height, nc, names, err);
    if (st) return st;
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            float *px = img->data + ((size_t)y * f->width + x) * nc;
            if (layout == TS_FILM_IMAGE_SHARD) {
                st = shard_pixel(&f->pixels[(size_t)y * f->width + x], px, f->x0 + x, f->y0 + y, err);
                if (st) {
                    ts_image_fini(img);
                    return st;
                }
                continue;
            }
            ts_rgb m = ts_film_pixel_rgb(f, f->x0 + x, f->y0 + y);
            px[0] = m.r, px[1] = m.g, px[2] = m.b;
            if (layout == TS_FILM_IMAGE_STATS) {
                ts_rgb v = ts_film_pixel_variance(f, f->x0 + x, f->y0 + y);
                px[3] = v.r, px[4] = v.g, px[5] = v.b;
                px[6] = (float)f->pixels[(size_t)y * f->width + x].count;
            }
        }
    return TS_OK;
}

bool ts_film_image_is_shard(const ts_image *img)
{
    for (int c = 0; c < SH_N; c++)
        if (ts_image_channel(img, shard_names[c]) < 0) return false;
    return true;
}

ts_film *ts_film_from_image(const ts_image *img, int full_width, int full_height, int x0, int y0, ts_error *err)
{
    int idx[SH_N];
    for (int c = 0; c < SH_N; c++) {
        idx[c] = ts_image_channel(img, shard_names[c]);
        if (idx[c] < 0) {
            ts_error_set(err, TS_ERR_INVALID, "channel '%s' is missing: this is not a tessera shard image", shard_names[c]);
            return NULL;
        }
    }
    ts_film *f = ts_film_create(full_width, full_height, x0, y0, img->width, img->height, err);
    if (!f) return NULL;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            const float *px = img->data + ((size_t)y * img->width + x) * img->n_channels;
            ts_film_pixel *p = &f->pixels[(size_t)y * f->width + x];
            float count = px[idx[SH_COUNT]];
            if (!(count >= 0 && count <= MAX_EXACT_COUNT && count == floorf(count))) {
                ts_error_set(err, TS_ERR_INVALID, "pixel (%d, %d): the sample count %g is not a whole number of samples",
                             x0 + x, y0 + y, (double)count);
                ts_film_destroy(f);
                return NULL;
            }
            double w = (double)px[idx[SH_W_HI]] + (double)px[idx[SH_W_LO]];
            for (int c = 0; c < 3; c++) {
                double hi = px[idx[SH_R + c]], lo = px[idx[SH_SUM_LO + c]];
                p->sum[c] = w != 0 ? hi * w + lo : hi + lo;
                p->sum_sq[c] = (double)px[idx[SH_SQ_HI + c]] + (double)px[idx[SH_SQ_LO + c]];
            }
            p->weight = w;
            p->weight_sq = px[idx[SH_WSQ]];
            p->count = (uint64_t)count;
            bool finite = isfinite(p->weight) && isfinite(p->weight_sq);
            for (int c = 0; c < 3; c++) finite = finite && isfinite(p->sum[c]) && isfinite(p->sum_sq[c]);
            if (!finite) {
                ts_error_set(err, TS_ERR_INVALID, "pixel (%d, %d) holds a value that is not a finite number", x0 + x,
                             y0 + y);
                ts_film_destroy(f);
                return NULL;
            }
        }
    return f;
}

ts_status ts_image_set_render_info(ts_image *img, const ts_render_info *info, ts_error *err)
{
    char version[64];
    snprintf(version, sizeof version, "tessera %s", TS_VERSION);
    const char *scene = info->scene && info->scene[0] ? info->scene : "scene";
    ts_status st = ts_image_set_string(img, "software", version, err);
    if (!st) st = ts_image_set_string(img, "tessera_scene", scene, err);
    if (!st) st = ts_image_set_string(img, "tessera_integrator", info->integrator, err);
    if (!st) st = ts_image_set_int(img, "tessera_spp", (int32_t)info->spp, err);
    if (!st && info->has_seed) st = ts_image_set_int(img, "tessera_seed", (int32_t)info->seed, err);
    if (!st) st = ts_image_set_double(img, "tessera_render_time_s", info->render_time_s, err);
    if (!st && info->error_estimate >= 0)
        st = ts_image_set_double(img, "tessera_error_estimate", info->error_estimate, err);
    if (!st) st = ts_image_set_double(img, "tessera_nonfinite_samples", info->nonfinite_samples, err);
    if (!st && info->job) st = ts_image_set_string(img, "tessera_job", info->job, err);
    if (!st && info->film_scale > 0) st = ts_image_set_double(img, "tessera_film_scale", info->film_scale, err);
    if (!st && info->media) st = ts_image_set_double(img, "tessera_medium_steps", info->medium_steps, err);
    if (!st && info->media) st = ts_image_set_double(img, "tessera_walks_truncated", info->walks_truncated, err);
    return st;
}
