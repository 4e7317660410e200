/* texture.c — pbrt-v3's textures: validation and evaluation (see texture.h).
 * Arithmetic follows pbrt-v3's operation order, so values match its float results. */
#include "textures/texture.h"

#include <math.h>
#include <string.h>

#include "textures/noise.h"

static const char *const type_names[] = {
    [TS_TEXTURE_CONSTANT] = "constant",
    [TS_TEXTURE_SCALE] = "scale",
    [TS_TEXTURE_MIX] = "mix",
    [TS_TEXTURE_BILERP] = "bilerp",
    [TS_TEXTURE_UV] = "uv",
    [TS_TEXTURE_CHECKERBOARD2D] = "checkerboard",
    [TS_TEXTURE_CHECKERBOARD3D] = "checkerboard",
    [TS_TEXTURE_DOTS] = "dots",
    [TS_TEXTURE_FBM] = "fbm",
    [TS_TEXTURE_WRINKLED] = "wrinkled",
    [TS_TEXTURE_WINDY] = "windy",
    [TS_TEXTURE_MARBLE] = "marble",
    [TS_TEXTURE_IMAGEMAP] = "imagemap",
};

ts_texture ts_texture_constant_float(float v)
{
    return (ts_texture){.type = TS_TEXTURE_CONSTANT, .is_rgb = false, .constant.value = ts_rgb_gray(v)};
}

ts_texture ts_texture_constant_rgb(ts_rgb v)
{
    return (ts_texture){.type = TS_TEXTURE_CONSTANT, .is_rgb = true, .constant.value = v};
}

/* ---- evaluation ---- */

static inline ts_rgb rgb_lerp(float t, ts_rgb a, ts_rgb b)
{
    return (ts_rgb){(1 - t) * a.r + t * b.r, (1 - t) * a.g + t * b.g, (1 - t) * a.b + t * b.b};
}

/* 0 or 1: the parity of an integral float (all floats of magnitude ≥ 2^24 are even). */
static inline float parity(float f) { return f - 2 * floorf(f * 0.5f); }

/* ∫₀ˣ of the function that is 1 on odd cells [2k+1, 2k+2) and 0 on even ones (pbrt-v3's
 * bumpInt). */
static inline float bump_int(float x)
{
    float h = floorf(x / 2);
    return h + 2 * ts_maxf(x / 2 - h - 0.5f, 0);
}

float ts_texture_checkerboard_odd_fraction(ts_vec2 st, float ds, float dt)
{
    float s0 = st.x - ds, s1 = st.x + ds, t0 = st.y - dt, t1 = st.y + dt;
    float ps = parity(floorf(st.x)), pt = parity(floorf(st.y));
    if (floorf(s0) == floorf(s1) && floorf(t0) == floorf(t1)) return ps != pt ? 1.0f : 0.0f;
    /* A zero half-width is the limit of the average: the parity of the point's cell. */
    float sint = ds > 0 ? (bump_int(s1) - bump_int(s0)) / (2 * ds) : ps;
    float tint = dt > 0 ? (bump_int(t1) - bump_int(t0)) / (2 * dt) : pt;
    float area2 = sint + tint - 2 * sint * tint;
    if (ds > 1 || dt > 1) area2 = 0.5f;
    return area2;
}

/* pbrt-v3's marble colours and their cubic Bézier spline. */
static ts_rgb marble_color(float t)
{
    static const float c[9][3] = {
        {.58f, .58f, .6f}, {.58f, .58f, .6f}, {.58f, .58f, .6f}, {.5f, .5f, .5f},   {.6f, .59f, .58f},
        {.58f, .58f, .6f}, {.58f, .58f, .6f}, {.2f, .2f, .33f},  {.58f, .58f, .6f},
    };
    const int n_seg = 9 - 3;
    int first = (int)floorf(t * (float)n_seg);
    if (first > n_seg - 1) first = n_seg - 1; /* t = 1 (the book's intent; texture.h) */
    if (first < 0) first = 0;
    t = t * (float)n_seg - (float)first;
    ts_rgb p[4];
    for (int i = 0; i < 4; i++)
        p[i] = (ts_rgb){c[first + i][0], c[first + i][1], c[first + i][2]};
    /* de Casteljau */
    ts_rgb s0 = rgb_lerp(t, p[0], p[1]), s1 = rgb_lerp(t, p[1], p[2]), s2 = rgb_lerp(t, p[2], p[3]);
    s0 = rgb_lerp(t, s0, s1);
    s1 = rgb_lerp(t, s1, s2);
    return ts_rgb_scale(rgb_lerp(t, s0, s1), 1.5f);
}

static ts_rgb eval(const ts_texture *t, const ts_texture_context *c)
{
    ts_vec2 dstdx, dstdy;
    ts_vec3 dpdx, dpdy;
    switch (t->type) {
    case TS_TEXTURE_CONSTANT:
        return t->constant.value;
    case TS_TEXTURE_SCALE:
        return ts_rgb_mul(eval(t->scale.tex1, c), eval(t->scale.tex2, c));
    case TS_TEXTURE_MIX: {
        ts_rgb t1 = eval(t->mix.tex1, c), t2 = eval(t->mix.tex2, c);
        float amt = eval(t->mix.amount, c).r;
        return (ts_rgb){(1 - amt) * t1.r + amt * t2.r, (1 - amt) * t1.g + amt * t2.g,
                        (1 - amt) * t1.b + amt * t2.b};
    }
    case TS_TEXTURE_BILERP: {
        ts_vec2 st = ts_texture_mapping2d_map(&t->bilerp.map, c, &dstdx, &dstdy);
        float s = st.x, u = st.y;
        float w00 = (1 - s) * (1 - u), w01 = (1 - s) * u, w10 = s * (1 - u), w11 = s * u;
        const ts_rgb *v00 = &t->bilerp.v00, *v01 = &t->bilerp.v01, *v10 = &t->bilerp.v10,
                     *v11 = &t->bilerp.v11;
        return (ts_rgb){w00 * v00->r + w01 * v01->r + w10 * v10->r + w11 * v11->r,
                        w00 * v00->g + w01 * v01->g + w10 * v10->g + w11 * v11->g,
                        w00 * v00->b + w01 * v01->b + w10 * v10->b + w11 * v11->b};
    }
    case TS_TEXTURE_UV: {
        ts_vec2 st = ts_texture_mapping2d_map(&t->uv.map, c, &dstdx, &dstdy);
        return (ts_rgb){st.x - floorf(st.x), st.y - floorf(st.y), 0};
    }
    case TS_TEXTURE_CHECKERBOARD2D: {
        ts_vec2 st = ts_texture_mapping2d_map(&t->checkerboard2d.map, c, &dstdx, &dstdy);
        float odd;
        if (!t->checkerboard2d.closed_form) {
            odd = parity(floorf(st.x)) != parity(floorf(st.y)) ? 1.0f : 0.0f;
        } else {
            float ds = ts_maxf(fabsf(dstdx.x), fabsf(dstdy.x));
            float dt = ts_maxf(fabsf(dstdx.y), fabsf(dstdy.y));
            if (!(isfinite(ds) && isfinite(dt))) ds = dt = 0; /* no usable footprint: point-sample */
            odd = ts_texture_checkerboard_odd_fraction(st, ds, dt);
        }
        /* Inside one check only that check's texture is evaluated, as in pbrt-v3 (a
         * filtered fraction of exactly 0 or 1 gives the same value either way). */
        if (odd == 0) return eval(t->checkerboard2d.tex1, c);
        if (odd == 1) return eval(t->checkerboard2d.tex2, c);
        return rgb_lerp(odd, eval(t->checkerboard2d.tex1, c), eval(t->checkerboard2d.tex2, c));
    }
    case TS_TEXTURE_CHECKERBOARD3D: {
        ts_vec3 p = ts_texture_mapping3d_map(&t->checkerboard3d.map, c, &dpdx, &dpdy);
        float sum = parity(floorf(p.x)) + parity(floorf(p.y)) + parity(floorf(p.z));
        return parity(sum) == 0 ? eval(t->checkerboard3d.tex1, c) : eval(t->checkerboard3d.tex2, c);
    }
    case TS_TEXTURE_DOTS: {
        ts_vec2 st = ts_texture_mapping2d_map(&t->dots.map, c, &dstdx, &dstdy);
        float s_cell = floorf(st.x + .5f), t_cell = floorf(st.y + .5f);
        if (ts_noise(s_cell + .5f, t_cell + .5f, .5f) > 0) {
            const float radius = .35f, max_shift = 0.5f - radius;
            float s_center = s_cell + max_shift * ts_noise(s_cell + 1.5f, t_cell + 2.8f, .5f);
            float t_center = t_cell + max_shift * ts_noise(s_cell + 4.5f, t_cell + 9.8f, .5f);
            float ds = st.x - s_center, dt = st.y - t_center;
            if (ds * ds + dt * dt < radius * radius) return eval(t->dots.inside, c);
        }
        return eval(t->dots.outside, c);
    }
    case TS_TEXTURE_FBM:
    case TS_TEXTURE_WRINKLED: {
        ts_vec3 p = ts_texture_mapping3d_map(&t->fbm.map, c, &dpdx, &dpdy);
        float v = t->type == TS_TEXTURE_FBM
                      ? ts_noise_fbm(p, dpdx, dpdy, t->fbm.omega, t->fbm.octaves)
                      : ts_noise_turbulence(p, dpdx, dpdy, t->fbm.omega, t->fbm.octaves);
        return ts_rgb_gray(v);
    }
    case TS_TEXTURE_WINDY: {
        ts_vec3 p = ts_texture_mapping3d_map(&t->windy.map, c, &dpdx, &dpdy);
        float wind =
            ts_noise_fbm(ts_vec3_scale(p, .1f), ts_vec3_scale(dpdx, .1f), ts_vec3_scale(dpdy, .1f), .5f, 3);
        float wave = ts_noise_fbm(p, dpdx, dpdy, .5f, 6);
        return ts_rgb_gray(fabsf(wind) * wave);
    }
    case TS_TEXTURE_MARBLE: {
        ts_vec3 p = ts_texture_mapping3d_map(&t->marble.map, c, &dpdx, &dpdy);
        float sc = t->marble.scale;
        p = ts_vec3_scale(p, sc);
        float marble =
            p.y + t->marble.variation * ts_noise_fbm(p, ts_vec3_scale(dpdx, sc), ts_vec3_scale(dpdy, sc),
                                                     t->marble.omega, t->marble.octaves);
        return marble_color(.5f + .5f * sinf(marble));
    }
    case TS_TEXTURE_IMAGEMAP: {
        ts_vec2 st = ts_texture_mapping2d_map(&t->image.map, c, &dstdx, &dstdy);
        ts_rgb v =
            ts_mipmap_lookup(t->image.mipmap, st, dstdx, dstdy, t->image.trilinear, t->image.max_anisotropy);
        if (t->image.invert) v = (ts_rgb){ts_maxf(0, 1 - v.r), ts_maxf(0, 1 - v.g), ts_maxf(0, 1 - v.b)};
        return v;
    }
    }
    return (ts_rgb){0, 0, 0};
}

ts_rgb ts_texture_eval_rgb(const ts_texture *t, const ts_texture_context *c) { return eval(t, c); }
float ts_texture_eval_float(const ts_texture *t, const ts_texture_context *c) { return eval(t, c).r; }

/* ---- making ---- */

static bool finite_rgb(ts_rgb v) { return isfinite(v.r) && isfinite(v.g) && isfinite(v.b); }
static bool finite_vec3(ts_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

static bool finite_mat(const ts_mat4 *m)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!isfinite(m->m[i][j])) return false;
    return true;
}

static ts_status check_map2d(const ts_texture_mapping2d *m, const char *what, ts_error *err)
{
    if (m->type > TS_TEXTURE_MAPPING_PLANAR)
        return ts_error_set(err, TS_ERR_INVALID, "%s texture: unknown mapping %d", what, (int)m->type);
    if (!(isfinite(m->su) && isfinite(m->sv) && isfinite(m->du) && isfinite(m->dv) && finite_vec3(m->vs) &&
          finite_vec3(m->vt) && finite_mat(&m->world_to_texture)))
        return ts_error_set(err, TS_ERR_INVALID, "%s texture: the mapping's parameters must be finite", what);
    return TS_OK;
}

static ts_status check_map3d(const ts_texture_mapping3d *m, const char *what, ts_error *err)
{
    if (!finite_mat(&m->world_to_texture))
        return ts_error_set(err, TS_ERR_INVALID, "%s texture: the texture-space transform must be finite",
                            what);
    return TS_OK;
}

/* A child of the given kind; raises *depth to its depth. */
/* A child's depth and cost go into *depth (the deepest) and *cost (the sum, each use
 * counted: evaluation visits a child once for each field that names it). */
static ts_status check_child(const ts_texture *child, bool want_rgb, const char *what, const char *field,
                             int *depth, uint64_t *cost, ts_error *err)
{
    if (!child) return ts_error_set(err, TS_ERR_INVALID, "%s texture: %s is missing", what, field);
    if (child->is_rgb != want_rgb)
        return ts_error_set(err, TS_ERR_INVALID, "%s texture: %s must be a%s texture, not a%s one", what,
                            field, want_rgb ? "n RGB" : " float", child->is_rgb ? "n RGB" : " float");
    if (child->depth > *depth) *depth = child->depth;
    *cost += child->cost;
    return TS_OK;
}

static ts_status check_octaves(int octaves, float omega, const char *what, ts_error *err)
{
    if (octaves < 0 || octaves > TS_NOISE_MAX_OCTAVES)
        return ts_error_set(err, TS_ERR_INVALID, "%s texture: octaves must be 0 … %d, got %d", what,
                            TS_NOISE_MAX_OCTAVES, octaves);
    if (!isfinite(omega))
        return ts_error_set(err, TS_ERR_INVALID, "%s texture: roughness must be finite", what);
    return TS_OK;
}

ts_status ts_texture_make(ts_arena *arena, const ts_texture *proto, const ts_texture **out, ts_error *err)
{
    *out = NULL;
    if (proto->type > TS_TEXTURE_IMAGEMAP)
        return ts_error_set(err, TS_ERR_INVALID, "unknown texture type %d", (int)proto->type);
    ts_texture t = *proto;
    const char *what = type_names[t.type];
    bool rgb = t.is_rgb;
    int depth = 0;
    uint64_t cost = 0;
    ts_status st = TS_OK;
    switch (t.type) {
    case TS_TEXTURE_CONSTANT:
        if (!finite_rgb(t.constant.value))
            return ts_error_set(err, TS_ERR_INVALID, "constant texture: the value must be finite");
        if (!rgb) t.constant.value = ts_rgb_gray(t.constant.value.r);
        break;
    case TS_TEXTURE_SCALE:
        if ((st = check_child(t.scale.tex1, rgb, what, "tex1", &depth, &cost, err)) ||
            (st = check_child(t.scale.tex2, rgb, what, "tex2", &depth, &cost, err)))
            return st;
        break;
    case TS_TEXTURE_MIX:
        if ((st = check_child(t.mix.tex1, rgb, what, "tex1", &depth, &cost, err)) ||
            (st = check_child(t.mix.tex2, rgb, what, "tex2", &depth, &cost, err)) ||
            (st = check_child(t.mix.amount, false, what, "amount", &depth, &cost, err)))
            return st;
        break;
    case TS_TEXTURE_BILERP:
        if ((st = check_map2d(&t.bilerp.map, what, err))) return st;
        if (!finite_rgb(t.bilerp.v00) || !finite_rgb(t.bilerp.v01) || !finite_rgb(t.bilerp.v10) ||
            !finite_rgb(t.bilerp.v11))
            return ts_error_set(err, TS_ERR_INVALID, "bilerp texture: v00, v01, v10 and v11 must be finite");
        if (!rgb) {
            t.bilerp.v00 = ts_rgb_gray(t.bilerp.v00.r), t.bilerp.v01 = ts_rgb_gray(t.bilerp.v01.r);
            t.bilerp.v10 = ts_rgb_gray(t.bilerp.v10.r), t.bilerp.v11 = ts_rgb_gray(t.bilerp.v11.r);
        }
        break;
    case TS_TEXTURE_UV:
        if (!rgb)
            return ts_error_set(err, TS_ERR_INVALID,
                                "uv texture: it is an RGB texture (pbrt-v3 has no float uv texture)");
        if ((st = check_map2d(&t.uv.map, what, err))) return st;
        break;
    case TS_TEXTURE_CHECKERBOARD2D:
        if ((st = check_map2d(&t.checkerboard2d.map, what, err)) ||
            (st = check_child(t.checkerboard2d.tex1, rgb, what, "tex1", &depth, &cost, err)) ||
            (st = check_child(t.checkerboard2d.tex2, rgb, what, "tex2", &depth, &cost, err)))
            return st;
        break;
    case TS_TEXTURE_CHECKERBOARD3D:
        if ((st = check_map3d(&t.checkerboard3d.map, what, err)) ||
            (st = check_child(t.checkerboard3d.tex1, rgb, what, "tex1", &depth, &cost, err)) ||
            (st = check_child(t.checkerboard3d.tex2, rgb, what, "tex2", &depth, &cost, err)))
            return st;
        break;
    case TS_TEXTURE_DOTS:
        if ((st = check_map2d(&t.dots.map, what, err)) ||
            (st = check_child(t.dots.inside, rgb, what, "inside", &depth, &cost, err)) ||
            (st = check_child(t.dots.outside, rgb, what, "outside", &depth, &cost, err)))
            return st;
        break;
    case TS_TEXTURE_FBM:
    case TS_TEXTURE_WRINKLED:
        if ((st = check_map3d(&t.fbm.map, what, err)) ||
            (st = check_octaves(t.fbm.octaves, t.fbm.omega, what, err)))
            return st;
        break;
    case TS_TEXTURE_WINDY:
        if ((st = check_map3d(&t.windy.map, what, err))) return st;
        break;
    case TS_TEXTURE_MARBLE:
        if (!rgb)
            return ts_error_set(err, TS_ERR_INVALID,
                                "marble texture: it is an RGB texture (pbrt-v3 has no float marble texture)");
        if ((st = check_map3d(&t.marble.map, what, err)) ||
            (st = check_octaves(t.marble.octaves, t.marble.omega, what, err)))
            return st;
        if (!isfinite(t.marble.scale) || !isfinite(t.marble.variation))
            return ts_error_set(err, TS_ERR_INVALID, "marble texture: scale and variation must be finite");
        break;
    case TS_TEXTURE_IMAGEMAP:
        if ((st = check_map2d(&t.image.map, what, err))) return st;
        if (!t.image.mipmap) return ts_error_set(err, TS_ERR_INVALID, "imagemap texture: it has no image");
        if (t.image.mipmap->n_channels != (rgb ? 3 : 1))
            return ts_error_set(err, TS_ERR_INVALID,
                                "imagemap texture: a%s texture needs a %d-channel MIP map, not %d",
                                rgb ? "n RGB" : " float", rgb ? 3 : 1, t.image.mipmap->n_channels);
        if (!(t.image.max_anisotropy > 0 && t.image.max_anisotropy <= TS_MIPMAP_MAX_ANISOTROPY))
            return ts_error_set(err, TS_ERR_INVALID,
                                "imagemap texture: maxanisotropy must be in (0, %g], got %g",
                                (double)TS_MIPMAP_MAX_ANISOTROPY, (double)t.image.max_anisotropy);
        break;
    }
    if (depth + 1 > TS_TEXTURE_MAX_DEPTH)
        return ts_error_set(err, TS_ERR_LIMIT, "%s texture: textures nest more than %d deep", what,
                            TS_TEXTURE_MAX_DEPTH);
    if (cost + 1 > TS_TEXTURE_MAX_COST)
        return ts_error_set(err, TS_ERR_INVALID,
                            "%s texture: one lookup of it would evaluate %llu textures (each use of a child counted), "
                            "more than the limit of %d",
                            what, (unsigned long long)(cost + 1), TS_TEXTURE_MAX_COST);
    t.depth = (uint8_t)(depth + 1);
    t.cost = (uint32_t)(cost + 1);
    ts_texture *copy = ts_arena_alloc(arena, sizeof *copy, _Alignof(ts_texture));
    if (!copy) return ts_error_set(err, TS_ERR_NOMEM, "%s texture: out of memory", what);
    memcpy(copy, &t, sizeof t);
    *out = copy;
    return TS_OK;
}
