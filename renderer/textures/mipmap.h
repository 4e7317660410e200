/* mipmap.h — pbrt-v3's MIPMap: an image pyramid and its filtered lookups.
 *
 * Design note (pbrt-v3 §10.4). Texels are float, 1 channel (a float texture) or 3 (RGB),
 * in (s, t) order: texel (s, t) of level 0 covers [s, s+1)/width × [t, t+1)/height of
 * texture space, t = 0 at the image's bottom row. Building:
 *   - an image whose width or height is not a power of two is first resampled up to the
 *     next powers of two, separably, s then t, with pbrt-v3's weights: four taps of a
 *     Lanczos windowed sinc (τ = 2) over a filter width of 2 source texels around the new
 *     texel's centre, normalised to sum 1; taps outside the image follow the wrap mode
 *     (black: 0); after the t pass values are clamped at 0 (the sinc's negative lobes);
 *   - level i + 1 is the box average of 2 × 2 texels of level i (a level 1 texel wide or
 *     high pairs its texels with the wrap mode's neighbours, as pbrt-v3 does), down to
 *     1 × 1: 1 + log₂ max(width, height) levels.
 * Lookups (wrap repeat, black or clamp at every level):
 *   - bilinear ("triangle" in pbrt-v3) at one level between texel centres;
 *   - trilinear with a filter width w (in texture space): level L − 1 + log₂ w, linear
 *     between the two nearest levels, the finest level's bilinear below 0, the 1 × 1
 *     texel above L − 1; from a footprint, w = 2·max |∂s/∂x|, |∂t/∂x|, |∂s/∂y|, |∂t/∂y|;
 *   - EWA (pbrt-v3's default, Heckbert's elliptically weighted average): the ellipse of
 *     the two footprint axes, its eccentricity clamped to max_anisotropy by growing the
 *     minor axis, the level from the minor axis, a Gaussian weight (α = 2, tabulated in
 *     128 steps of r²) over the texels inside the ellipse at the two nearest levels.
 * Arithmetic is pbrt-v3's, in float and in its order. Guards pbrt-v3 lacks: a non-finite
 * (s, t) is looked up at (0, 0) and a non-finite footprint as none; an ellipse with no
 * weighted texel (cannot happen with finite input) falls back to bilinear. An EWA lookup
 * visits at most about (4·max_anisotropy + 6)² texels, which is why max_anisotropy is
 * bounded (TS_MIPMAP_MAX_ANISOTROPY).
 *
 * Memory: a ts_mipmap owns one heap block with every level (freed by ts_mipmap_destroy;
 * textures/texture_cache.h owns the maps of a scene). Immutable after creation: every
 * lookup is pure, allocation-free, lock-free and thread-safe. */
#ifndef TS_MIPMAP_H
#define TS_MIPMAP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"
#include "core/vecmath.h"

typedef enum ts_texture_wrap {
    TS_TEXTURE_WRAP_REPEAT,
    TS_TEXTURE_WRAP_BLACK,
    TS_TEXTURE_WRAP_CLAMP,
} ts_texture_wrap;

#define TS_MIPMAP_MAX_LEVELS     32
#define TS_MIPMAP_EWA_LUT_SIZE   128
#define TS_MIPMAP_MAX_ANISOTROPY 64.0f
/* The largest texel magnitude: sums of up to ~10^5 weighted texels (an EWA lookup) then
 * stay far from float overflow, so a map of accepted texels gives finite lookups. */
#define TS_MIPMAP_MAX_TEXEL 1e30f
/* Width and height of a source image, each (TS_IMAGE_MAX_PIXELS bounds their product). */
#define TS_MIPMAP_MAX_SIZE 65536

typedef struct ts_mipmap_level {
    int32_t width, height;
    const float *texels; /* width·height·n_channels, row t = 0 first */
} ts_mipmap_level;

typedef struct ts_mipmap {
    int32_t n_channels; /* 1 or 3 */
    int32_t n_levels;   /* level 0 is the finest */
    ts_texture_wrap wrap;
    int32_t source_width, source_height; /* before resampling to powers of two */
    ts_mipmap_level levels[TS_MIPMAP_MAX_LEVELS];
    float ewa_weights[TS_MIPMAP_EWA_LUT_SIZE];
    size_t bytes; /* of the pyramid */
    float *block; /* owns every level's texels */
} ts_mipmap;

/* Bytes of the pyramid of a width × height image of n_channels (after resampling); 0 if
 * the size is out of range. For a memory budget checked before creating. */
size_t ts_mipmap_bytes_for(int32_t width, int32_t height, int32_t n_channels);

/* The pyramid of texels (width·height·n_channels floats, row t = 0 first; copied) with
 * wrap mode wrap. max_bytes (0 = none) bounds ts_mipmap_bytes_for before anything is
 * allocated (TS_ERR_LIMIT). Texels must be finite and within ±TS_MIPMAP_MAX_TEXEL
 * (TS_ERR_INVALID naming the first bad one); width, height in 1 … TS_MIPMAP_MAX_SIZE; n_channels 1 or 3. On
 * failure *out is NULL. */
ts_status ts_mipmap_create(const float *texels, int32_t width, int32_t height, int32_t n_channels,
                           ts_texture_wrap wrap, size_t max_bytes, ts_mipmap **out, ts_error *err);
/* Frees the map; NULL is a no-op. */
void ts_mipmap_destroy(ts_mipmap *m);

/* Texel (s, t) of level (clamped to the levels) with the wrap mode; 1-channel maps give
 * (v, v, v). */
ts_rgb ts_mipmap_texel(const ts_mipmap *m, int level, int64_t s, int64_t t);
/* Bilinear lookup at one level (pbrt-v3's MIPMap::triangle). */
ts_rgb ts_mipmap_bilinear(const ts_mipmap *m, int level, ts_vec2 st);
/* Trilinear lookup with filter width `width` in texture space (pbrt-v3's
 * Lookup(st, width)). */
ts_rgb ts_mipmap_trilinear(const ts_mipmap *m, ts_vec2 st, float width);
/* EWA lookup with footprint axes dst0, dst1 (pbrt-v3's Lookup(st, dst0, dst1) without
 * doTrilinear); max_anisotropy in (0, TS_MIPMAP_MAX_ANISOTROPY]. */
ts_rgb ts_mipmap_ewa(const ts_mipmap *m, ts_vec2 st, ts_vec2 dst0, ts_vec2 dst1, float max_anisotropy);
/* pbrt-v3's Lookup(st, dstdx, dstdy): trilinear with w = 2·max|component| if trilinear,
 * else EWA. */
ts_rgb ts_mipmap_lookup(const ts_mipmap *m, ts_vec2 st, ts_vec2 dstdx, ts_vec2 dstdy, bool trilinear,
                        float max_anisotropy);

#endif
