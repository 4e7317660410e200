/* texture.h — pbrt-v3's textures as tagged values, and their evaluation.
 *
 * Design note (pbrt-v3 ch. 10). A texture is plain data tagged by type; evaluation is a
 * switch on the tag (no function pointers, docs/style.md), recursing into the textures a
 * texture combines. A texture is a float texture or an RGB one (pbrt-v3's "float" and
 * "color"/"spectrum"); one evaluator serves both, float textures carrying their value in
 * all three channels, so ts_texture_eval_float is the red channel of the same code.
 * What each type computes at a context c (textures/texture_mapping.h), with pbrt-v3's
 * parameter names and defaults in pbrt3/texture_pbrt.h:
 *   constant        value
 *   scale           tex1 · tex2 (both of the texture's kind)
 *   mix             (1 − amount)·tex1 + amount·tex2 (amount a float texture)
 *   bilerp          (1−s)(1−t) v00 + (1−s) t v01 + s (1−t) v10 + s t v11 at the mapping's (s, t)
 *   uv              (s − ⌊s⌋, t − ⌊t⌋, 0) (RGB only, as in pbrt-v3)
 *   checkerboard2d  tex1 where ⌊s⌋ + ⌊t⌋ is even, tex2 where odd; "closed form": the box
 *                   filter of half-widths ds = max(|∂s/∂x|, |∂s/∂y|), dt likewise,
 *                   integrated exactly (pbrt-v3 §10.5.3) when the box crosses a check
 *                   edge, and pbrt-v3's 0.5 when ds or dt exceeds 1
 *   checkerboard3d  tex1 where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ of the 3D mapping's point is even, else tex2
 *   dots            pbrt-v3's polka dots: in the cell ⌊s + ½⌋, ⌊t + ½⌋ a dot of radius 0.35
 *                   exists where Noise(cell + ½, ½) > 0, its centre jittered by noise;
 *                   inside where the point is in it, else outside
 *   fbm, wrinkled   FBm / Turbulence (textures/noise.h) of the 3D point with `octaves`
 *                   and ω = roughness
 *   windy           |FBm(0.1 p, 0.1 ∂p, ω ½, 3 octaves)| · FBm(p, ∂p, ½, 6)
 *   marble          (RGB only) t = ½ + ½ sin(p_y·scale + variation·FBm(scale·p)), through a
 *                   cubic Bézier spline of nine colours, times 1.5
 *   imagemap        the MIP map's lookup at the mapping's (s, t) and footprint, trilinear
 *                   or EWA (textures/mipmap.h); with invert, max(0, 1 − value)
 * **Decision — marble's spline is the book's.** pbrt-v3's current source clamps the
 * spline segment to min(1, ⌊6t⌋), a slip in its fix of an out-of-bounds read at t = 1,
 * which extrapolates the spline to values up to ≈ 40 (a reflectance of 40); this takes
 * the segment min(⌊6t⌋, 5), the book's intent, with colours in [0.3, 0.9] (docs/design.md
 * §4b). **Decision — the closed-form checkerboard has no 0/0:** where a filter half-width
 * is 0 but the other crosses an edge, pbrt-v3 divides 0 by 0 (NaN); here that axis's
 * average is the parity of its cell, the limit of the formula.
 *
 * Lifetime: textures are made once per scene by ts_texture_make (copied into the
 * scene's arena, children and image maps referenced, not owned; pbrt3/texture_pbrt.h
 * makes them from a pbrt-v3 scene), and are immutable afterwards. Evaluation allocates
 * nothing, takes no lock, cannot fail and is thread-safe; nesting is at most
 * TS_TEXTURE_MAX_DEPTH deep, so its recursion is bounded. */
#ifndef TS_TEXTURE_H
#define TS_TEXTURE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/arena.h"
#include "core/error.h"
#include "core/vecmath.h"
#include "textures/mipmap.h"
#include "textures/texture_mapping.h"

/* The deepest nesting of textures in textures (a texture with no children is depth 1). */
#define TS_TEXTURE_MAX_DEPTH 32
/* The most textures one evaluation may visit: 1 + its children's, a child used twice
 * counted twice (evaluation recurses into each use). Depth alone does not bound it: a mix
 * of a texture with itself, 32 deep, is 2^32 evaluations a lookup. ts_texture_make counts
 * it from its children's (so counting is linear in the graph) and refuses beyond. */
#define TS_TEXTURE_MAX_COST 1024

typedef enum ts_texture_type {
    TS_TEXTURE_CONSTANT,
    TS_TEXTURE_SCALE,
    TS_TEXTURE_MIX,
    TS_TEXTURE_BILERP,
    TS_TEXTURE_UV,
    TS_TEXTURE_CHECKERBOARD2D,
    TS_TEXTURE_CHECKERBOARD3D,
    TS_TEXTURE_DOTS,
    TS_TEXTURE_FBM,
    TS_TEXTURE_WRINKLED,
    TS_TEXTURE_WINDY,
    TS_TEXTURE_MARBLE,
    TS_TEXTURE_IMAGEMAP,
} ts_texture_type;

typedef struct ts_texture ts_texture;

struct ts_texture {
    ts_texture_type type;
    bool is_rgb;   /* an RGB texture; else a float texture (its values grey) */
    uint8_t depth; /* set by ts_texture_make: 1 + the deepest child's */
    uint32_t cost; /* set by ts_texture_make: textures one evaluation visits, at most TS_TEXTURE_MAX_COST */
    union {
        struct {
            ts_rgb value;
        } constant; /* float: value.r = .g = .b */
        struct {
            const ts_texture *tex1, *tex2;
        } scale;
        struct {
            const ts_texture *tex1, *tex2, *amount;
        } mix; /* amount: a float texture */
        struct {
            ts_texture_mapping2d map;
            ts_rgb v00, v01, v10, v11;
        } bilerp;
        struct {
            ts_texture_mapping2d map;
        } uv;
        struct {
            ts_texture_mapping2d map;
            const ts_texture *tex1, *tex2;
            bool closed_form;
        } checkerboard2d;
        struct {
            ts_texture_mapping3d map;
            const ts_texture *tex1, *tex2;
        } checkerboard3d;
        struct {
            ts_texture_mapping2d map;
            const ts_texture *inside, *outside;
        } dots;
        struct {
            ts_texture_mapping3d map;
            int octaves;
            float omega;
        } fbm; /* fbm and wrinkled */
        struct {
            ts_texture_mapping3d map;
        } windy;
        struct {
            ts_texture_mapping3d map;
            int octaves;
            float omega, scale, variation;
        } marble;
        struct {
            ts_texture_mapping2d map;
            const ts_mipmap *mipmap; /* 3 channels for RGB, 1 for float; owned by a texture cache */
            bool trilinear;          /* else EWA */
            float max_anisotropy;    /* (0, TS_MIPMAP_MAX_ANISOTROPY] */
            bool invert;
        } image;
    };
};

/* Checks proto (children of the right kind and present, depth and cost, finite parameters, the
 * image's channel count matching the texture's kind, octaves in 0 … TS_NOISE_MAX_OCTAVES,
 * RGB-only types RGB) and copies it into the arena; *out points to the copy. Children
 * and the image map must outlive it. Errors (TS_ERR_INVALID with a sentence naming the
 * field; TS_ERR_NOMEM) leave *out NULL. */
ts_status ts_texture_make(ts_arena *arena, const ts_texture *proto, const ts_texture **out, ts_error *err);

/* A constant texture (float: v in all channels). */
ts_texture ts_texture_constant_float(float v);
ts_texture ts_texture_constant_rgb(ts_rgb v);

/* The value of an RGB texture at c (a float texture's value in all three channels). */
ts_rgb ts_texture_eval_rgb(const ts_texture *t, const ts_texture_context *c);
/* The value of a float texture at c (an RGB texture's red channel). */
float ts_texture_eval_float(const ts_texture *t, const ts_texture_context *c);

/* The closed-form box filter of pbrt-v3's 2D checkerboard: the fraction of the box
 * [s − ds, s + ds] × [t − dt, t + dt] covered by odd checks (tex2's), or the parity of
 * the check at (s, t) when the box lies inside it. For tests. */
float ts_texture_checkerboard_odd_fraction(ts_vec2 st, float ds, float dt);

#endif
