/* envmap.h — lat-long environment maps with importance sampling.
 *
 * Design note (pbrt-v3 §12.6, §14.2.4). Parameterisation, in the light's own space (the
 * infinite light's `transform` maps it to world), as pbrt-v3's lat-long maps:
 *     θ = π·v from +z (v = 0 is the image's top row), φ = 2π·u from +x towards +y,
 *     w = (sinθ cosφ, sinθ sinφ, cosθ).
 * Lookups are bilinear between texel centres, wrap in u (no seam at φ = 0), and blend
 * towards the mean of the first/last row over the half-texel at each pole, so radiance is
 * a continuous function of direction everywhere, poles included.
 *
 * Sampling: a 2D piecewise-constant distribution over texels whose weight is the largest
 * radiance the filtered lookup can reach inside the texel (its 3×3 neighbourhood, and the
 * pole mean for the end rows) times sinθ at the texel centre. So the pdf is > 0 wherever
 * radiance is, and the per-sample weight L/pdf is bounded (by 4π²× the mean weight, see
 * envmap.c) even for a map that is black but for one texel. The solid-angle pdf is
 * p(u,v) / (2π² sinθ), and 0 — never ∞ — at sinθ = 0.
 *
 * Ownership: ts_envmap_create / ts_envmap_load return a heap object owning all its memory
 * (one arena), freed by ts_envmap_destroy; afterwards the map is immutable and every
 * query is pure and thread-safe. */
#ifndef TS_ENVMAP_H
#define TS_ENVMAP_H

#include <stdbool.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/error.h"
#include "core/vecmath.h"
#include "sampling/distribution.h"

/* A texel's radiance and its sampling weight, the distribution's value of its cell: the
 * weight sits beside the radiance because every sample and every pdf query reads both
 * (16 bytes, so a texel never straddles a cache line). */
typedef struct ts_envmap_texel {
    ts_rgb c;
    float weight;
} ts_envmap_texel;

typedef struct ts_envmap {
    ts_arena arena;            /* owns texels and the distribution */
    uint32_t width, height;
    const ts_envmap_texel *texels; /* width·height, row-major, row 0 = θ near 0 */
    ts_rgb pole_mean[2];       /* mean of row 0 and of the last row */
    ts_distribution2d distrib; /* over (u, v) */
    ts_rgb mean_radiance;      /* Σ texel · solid angle / 4π (for the light's power) */
} ts_envmap;

/* From width × height RGB texels (row-major, copied). Texels must be finite and
 * non-negative (TS_ERR_INVALID otherwise, naming the texel). *out NULL on failure. */
ts_status ts_envmap_create(const ts_rgb *texels, uint32_t width, uint32_t height, ts_envmap **out, ts_error *err);
/* From a lat-long EXR with channels R, G, B (ts_exr_read). On failure *out is NULL and
 * err holds TS_ERR_IO / TS_ERR_INVALID with a sentence naming the file. */
ts_status ts_envmap_load(const char *path, ts_envmap **out, ts_error *err);
/* From an image with channels R, G, B (e.g. from ts_exr_read_memory); name prefixes the
 * error sentence. *out NULL on failure. */
struct ts_image;
ts_status ts_envmap_from_image(const struct ts_image *img, const char *name, ts_envmap **out, ts_error *err);
/* Frees everything the map owns; NULL is a no-op. */
void ts_envmap_destroy(ts_envmap *m);

/* Radiance towards the map along unit direction w (light space). */
ts_rgb ts_envmap_lookup(const ts_envmap *m, ts_vec3 w);
/* Radiance at (u, v) in [0,1]² (u wraps). */
ts_rgb ts_envmap_lookup_uv(const ts_envmap *m, ts_vec2 uv);

/* Direction (light space) sampled with density *pdf per solid angle; false (pdf 0) in the
 * measure-zero case sinθ = 0 or for an all-black map. */
bool ts_envmap_sample(const ts_envmap *m, ts_vec2 u, ts_vec3 *w, float *pdf);
/* ts_envmap_sample with *L the radiance there, looked up at the sampled (u, v) itself
 * (pbrt-v3's Sample_Li: Lmap->Lookup(uv)), not at the (u, v) of the float direction
 * *w, which differs from it by rounding and costs two atan2. */
bool ts_envmap_sample_li(const ts_envmap *m, ts_vec2 u, ts_vec3 *w, float *pdf, ts_rgb *L);
/* Density per solid angle of ts_envmap_sample for unit direction w (light space). */
float ts_envmap_pdf(const ts_envmap *m, ts_vec3 w);

/* ts_envmap_lookup(m, w) with *pdf = ts_envmap_pdf(m, w), bit for bit, w's (u, v)
 * computed once (the MIS weight of a BSDF sample that escapes needs both). */
ts_rgb ts_envmap_lookup_pdf(const ts_envmap *m, ts_vec3 w, float *pdf);
/* The same in two halves, so the texels' cache lines can be fetched while the caller does
 * other work (traces the BSDF ray that may escape): ts_envmap_query_begin finds w's (u, v) and
 * prefetches the texels the lookup reads; ts_envmap_query_lookup_pdf is then
 * ts_envmap_lookup_pdf(m, w, pdf), bit for bit. */
typedef struct ts_envmap_query {
    ts_vec3 w;
    ts_vec2 uv;
} ts_envmap_query;
void ts_envmap_query_begin(const ts_envmap *m, ts_vec3 w, ts_envmap_query *q);
ts_rgb ts_envmap_query_lookup_pdf(const ts_envmap *m, const ts_envmap_query *q, float *pdf);

/* Lat-long coordinates of a unit direction and back. */
ts_vec2 ts_envmap_dir_to_uv(ts_vec3 w);
ts_vec3 ts_envmap_uv_to_dir(ts_vec2 uv);

#endif
