/* texture_mapping.h — where a texture lookup happens, and pbrt-v3's texture mappings.
 *
 * Design note (pbrt-v3 §10.1–10.2). A lookup sees a ts_texture_context: the shading point
 * in world space, its (u, v), ∂p/∂u and ∂p/∂v, and its screen-space footprint — how p,
 * u and v change from one raster pixel to the next in x and in y. The footprint comes
 * from ray differentials (ts_texture_context_set_differentials, pbrt-v3's
 * SurfaceInteraction::ComputeDifferentials); without them it is zero, and every texture
 * then point-samples (the finest MIP level, every noise octave). The context is filled
 * by the caller from its surface interaction; this layer knows nothing of shapes.
 *
 * A 2D mapping gives texture coordinates (s, t) and their screen derivatives:
 *   uv           s = su·u + du, t = sv·v + dv; ∂s/∂x = su·∂u/∂x, …
 *   spherical    the direction of the point from the origin of texture space,
 *                (θ/π, φ/2π) with θ from +z and φ from +x towards +y; derivatives by a
 *                forward difference of 0.1·∂p/∂x, with pbrt-v3's correction of the
 *                derivative in t when φ wraps (it tests the difference quotient
 *                against ±½)
 *   cylindrical  ((π + atan2(y, x))/2π, z) of the normalised point in texture space;
 *                forward difference of 0.01·∂p/∂x, and pbrt-v3's wrap correction applied,
 *                as pbrt-v3 applies it, to t, not to the s that wraps — kept so images
 *                match pbrt-v3's (a footprint straddling the seam is blurred there)
 *   planar       s = du + p·vs, t = dv + p·vt with p in world space (pbrt-v3 applies no
 *                transform), ∂s/∂x = vs·∂p/∂x, …
 * A 3D mapping takes p and its footprint through one 4×4 transform.
 *
 * **pbrt-v3 compatibility:** pbrt-v3 builds the spherical and cylindrical mappings with
 * world→texture = the inverse of the texture's CTM, but passes the CTM itself (texture→
 * world) as world→texture to the 3D mapping of every solid texture (the 3D checkerboard,
 * fbm, wrinkled, windy, marble). The mapping here takes whatever
 * matrix it is given; pbrt3/texture_pbrt.c passes what pbrt-v3 passes, so a solid
 * texture under a `Scale 4 4 4` gets finer, as in pbrt-v3 (docs/design.md §4b).
 *
 * Transforms are held in double (core/transform.h) and applied in double; everything
 * else is float. A point at the origin of a spherical or cylindrical mapping gets the
 * direction's default (θ = π/2, φ = 0) instead of pbrt-v3's NaN. Pure, thread-safe. */
#ifndef TS_TEXTURE_MAPPING_H
#define TS_TEXTURE_MAPPING_H

#include "core/transform.h"
#include "core/vecmath.h"

typedef struct ts_texture_context {
    ts_vec3 p;          /* shading point, world space */
    ts_vec2 uv;         /* surface parameterisation at p */
    ts_vec3 dpdu, dpdv; /* ∂p/∂u, ∂p/∂v, world space */
    ts_vec3 dpdx, dpdy; /* change of p per raster pixel in x and in y; zero without differentials */
    float dudx, dvdx;   /* change of (u, v) per pixel in x … */
    float dudy, dvdy;   /* … and in y; zero without differentials */
} ts_texture_context;

/* The footprint of c (dpdx, dpdy, dudx, …) from the two offset rays of a ray differential
 * (origins rx_o, ry_o and directions rx_d, ry_d, world space) and the surface normal n at
 * c->p: each offset ray meets the tangent plane through p, and (du, dv) are solved from
 * ∂p/∂u, ∂p/∂v in the two coordinates where n is smallest. An offset ray parallel to the
 * plane zeroes the footprint; a degenerate (u, v) system zeroes that pixel direction's
 * (du, dv) — pbrt-v3's rules. c->p, dpdu and dpdv must be set. */
void ts_texture_context_set_differentials(ts_texture_context *c, ts_vec3 n, ts_vec3 rx_o, ts_vec3 rx_d,
                                          ts_vec3 ry_o, ts_vec3 ry_d);
/* Zeroes the footprint (no ray differentials). */
void ts_texture_context_clear_differentials(ts_texture_context *c);

typedef enum ts_texture_mapping2d_type {
    TS_TEXTURE_MAPPING_UV,
    TS_TEXTURE_MAPPING_SPHERICAL,
    TS_TEXTURE_MAPPING_CYLINDRICAL,
    TS_TEXTURE_MAPPING_PLANAR,
} ts_texture_mapping2d_type;

typedef struct ts_texture_mapping2d {
    ts_texture_mapping2d_type type;
    float su, sv;             /* uv: scales */
    float du, dv;             /* uv, planar: offsets (pbrt-v3's udelta, vdelta) */
    ts_vec3 vs, vt;           /* planar: the two axes (pbrt-v3's v1, v2) */
    ts_mat4 world_to_texture; /* spherical, cylindrical */
} ts_texture_mapping2d;

typedef struct ts_texture_mapping3d {
    ts_mat4 world_to_texture;
} ts_texture_mapping3d;

ts_texture_mapping2d ts_texture_mapping2d_uv(float su, float sv, float du, float dv);
ts_texture_mapping2d ts_texture_mapping2d_spherical(const ts_mat4 *world_to_texture);
ts_texture_mapping2d ts_texture_mapping2d_cylindrical(const ts_mat4 *world_to_texture);
ts_texture_mapping2d ts_texture_mapping2d_planar(ts_vec3 vs, ts_vec3 vt, float du, float dv);

/* (s, t) at c, and their changes per pixel in x (*dstdx) and in y (*dstdy). */
ts_vec2 ts_texture_mapping2d_map(const ts_texture_mapping2d *m, const ts_texture_context *c, ts_vec2 *dstdx,
                                 ts_vec2 *dstdy);

/* The texture-space point of c and its changes per pixel (the linear part applied to
 * c->dpdx, c->dpdy). */
ts_vec3 ts_texture_mapping3d_map(const ts_texture_mapping3d *m, const ts_texture_context *c, ts_vec3 *dpdx,
                                 ts_vec3 *dpdy);

#endif
