/* material_frame.h — the canonical shading point of the material tests.
 *
 * Design note: tests/test_material.c, test_material_pbrt3.c and test_substrate.c build a
 * material's BSDF where the local frame is the world frame — n = ns = +z, dpdu = +x (so
 * a material's roughness / uroughness lies along x and vroughness along y) — and name
 * directions by cosθ and φ in it; the last two also make pbrt-v3's anisotropic substrate.
 * These helpers are that code, once. */
#ifndef TS_TESTS_MATERIAL_FRAME_H
#define TS_TESTS_MATERIAL_FRAME_H

#include <math.h>
#include <string.h>

#include "materials/bsdf.h"
#include "materials/material.h"

/* m's BSDF at the canonical point (untextured: no texture context). */
static inline void canonical_bsdf(const ts_material *m, ts_bsdf *b)
{
    ts_interaction si;
    memset(&si, 0, sizeof si);
    si.n = si.ns = (ts_vec3){0, 0, 1};
    si.dpdu = (ts_vec3){1, 0, 0};
    ts_material_bsdf(m, &si, NULL, b);
}

/* The unit direction of polar cosine cos_theta and azimuth phi (radians) from +x. */
static inline ts_vec3 dir_cos(double cos_theta, double phi)
{
    double s = sqrt(fmax(0, 1 - cos_theta * cos_theta));
    return (ts_vec3){(float)(s * cos(phi)), (float)(s * sin(phi)), (float)cos_theta};
}

/* pbrt-v3's SubstrateMaterial: FresnelBlend(kd, ks) over Trowbridge–Reitz with α au along
 * dpdu (+x here) and av across it (anisotropic when they differ), no remapping. */
static inline ts_material substrate_rgb(ts_rgb kd, ts_rgb ks, float au, float av)
{
    return (ts_material){.type = TS_MATERIAL_SUBSTRATE,
                         .diffuse = ts_material_rgb_const(kd),
                         .specular = ts_material_rgb_const(ks),
                         .roughness = ts_material_float_const(au),
                         .has_vroughness = au != av,
                         .vroughness = ts_material_float_const(av)};
}
static inline ts_material substrate_aniso(float kd, float ks, float au, float av)
{
    return substrate_rgb(ts_rgb_gray(kd), ts_rgb_gray(ks), au, av);
}

#endif
