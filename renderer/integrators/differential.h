/* differential.h — ray differentials as pbrt-v3 carries them (docs/design.md §4d).
 *
 * Design note: a ray differential is the pair of offset rays of a camera ray, through the
 * raster points one pixel to the right and one pixel down, with the same lens point
 * (pbrt-v3's Camera::GenerateRayDifferential), scaled towards the main ray by
 * 1/√spp (RayDifferential::ScaleDifferentials, spp the scene's sampler.spp, so an image
 * converges to the same footprints however many samples a render takes). At a hit the
 * offset rays give the texture context's footprint (ts_texture_context_set_differentials,
 * pbrt-v3's SurfaceInteraction::ComputeDifferentials, against the geometric normal).
 * After a specular reflection or transmission the direct integrator carries them on by
 * pbrt-v3's SamplerIntegrator::SpecularReflect / SpecularTransmit rules; the path
 * integrator, as pbrt-v3's PathIntegrator, has them on camera rays only. Every other
 * ray has none, and its hits point-sample textures.
 *
 * The rules take the shading normal's screen derivatives as pbrt-v3 does, ∂n/∂x =
 * ∂n/∂u·∂u/∂x + ∂n/∂v·∂v/∂x from the interaction's ∂n/∂u, ∂n/∂v (geometry/shape.h), so a
 * curved mirror or interface spreads the footprint as in pbrt-v3. Pure and thread-safe. */
#ifndef TS_DIFFERENTIAL_H
#define TS_DIFFERENTIAL_H

#include <stdbool.h>

#include "camera/camera.h"
#include "core/vecmath.h"
#include "geometry/interaction.h"
#include "textures/texture_mapping.h"

typedef struct ts_ray_differential {
    bool has;           /* false: no offset rays (the fields below unset) */
    ts_vec3 rx_o, rx_d; /* the ray one pixel to the right (scaled), world space */
    ts_vec3 ry_o, ry_d; /* … one pixel down */
} ts_ray_differential;

/* The offset rays of ts_camera_ray(cam, p_raster, u_lens) (whose result is *ray), scaled
 * by scale (pbrt-v3: 1/√spp). */
void ts_ray_differential_camera(const ts_camera *cam, ts_vec2 p_raster, ts_vec2 u_lens, const ts_ray *ray,
                                float scale, ts_ray_differential *out);

/* The texture context of hit si: with the footprint of rd, or none when rd is NULL or
 * has none. */
void ts_ray_differential_context(const ts_interaction *si, const ts_ray_differential *rd,
                                 ts_texture_context *c);

/* pbrt-v3's SpecularReflect rule: the differential of the ray leaving si (context c, with
 * rd's footprint) along the mirror direction wi, from the incoming rd (which must have
 * offset rays). */
void ts_ray_differential_reflect(const ts_ray_differential *rd, const ts_interaction *si,
                                 const ts_texture_context *c, ts_vec3 wi, ts_ray_differential *out);

/* pbrt-v3's SpecularTransmit rule for the refracted wi; eta is the BSDF's η (inside over
 * outside, ts_bsdf.eta). */
void ts_ray_differential_transmit(const ts_ray_differential *rd, const ts_interaction *si,
                                  const ts_texture_context *c, ts_vec3 wi, float eta,
                                  ts_ray_differential *out);

#endif
