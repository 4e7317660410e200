/* bsdf.h — a BSDF at one shading point: up to TS_BSDF_MAX_BXDFS lobes in a shading frame,
 * and the interface the integrators call (pbrt-v3 §9.1, §14.1.6).
 *
 * Design note: ts_bsdf is built by ts_material_bsdf (material.h) into caller storage, no
 * allocation; it is a value, read-only afterwards, owned by one path. World-space
 * directions both point away from the surface (wo towards the viewer). Whether a pair is
 * reflection or transmission is decided by the geometric normal ng, so a shading normal
 * cannot make light leak through a surface: reflection lobes are evaluated only when wo
 * and wi are on the same side of ng, transmission lobes only otherwise.
 *
 * Sampling picks one lobe uniformly with u_lobe (all lobes, specular ones included) and
 * samples it with u. For a non-specular pick the returned pdf is the average of all lobes'
 * pdfs and f the sum of the f of the lobes matching reflection/transmission (so the
 * result equals ts_bsdf_f / ts_bsdf_pdf at the sampled wi); for a specular pick f is the
 * lobe's own (a delta) and pdf its discrete probability divided by the lobe count.
 * All values finite and ≥ 0; no NaN for degenerate input. Thread-safe (pure). */
#ifndef TS_BSDF_H
#define TS_BSDF_H

#include <stdbool.h>
#include <stdint.h>

#include "core/vecmath.h"
#include "materials/bxdf.h"

#define TS_BSDF_MAX_BXDFS 8 /* pbrt-v3's MaxBxDFs; uber has 5 lobes, a mix the sum of its two (scene_builder.h) */

typedef struct ts_bsdf {
    ts_vec3 ng;          /* geometric normal (world) */
    ts_vec3 ns, ss, ts;  /* shading frame (world): normal, tangent (along dpdu), bitangent */
    float eta;           /* relative index inside/outside (1 for opaque materials) */
    int n_bxdfs;
    ts_bxdf bxdfs[TS_BSDF_MAX_BXDFS];
} ts_bsdf;

/* Sets the frame from the geometric normal, shading normal and dpdu (any of which may be
 * degenerate: the frame is then built from ns alone) and clears the lobes. */
void ts_bsdf_init(ts_bsdf *b, ts_vec3 ng, ts_vec3 ns, ts_vec3 dpdu, float eta);
/* Appends a lobe (ignored, returning false, when the array is full). */
bool ts_bsdf_add(ts_bsdf *b, ts_bxdf bxdf);

ts_vec3 ts_bsdf_world_to_local(const ts_bsdf *b, ts_vec3 v);
ts_vec3 ts_bsdf_local_to_world(const ts_bsdf *b, ts_vec3 v);

/* Sum of the non-specular lobes' f for the pair (reflection vs transmission by ng). */
ts_rgb ts_bsdf_f(const ts_bsdf *b, ts_vec3 wo_world, ts_vec3 wi_world);
/* Solid-angle pdf of ts_bsdf_sample_f producing wi by a non-specular lobe. */
float ts_bsdf_pdf(const ts_bsdf *b, ts_vec3 wo_world, ts_vec3 wi_world);

typedef struct ts_bsdf_sample {
    ts_vec3 wi;     /* world */
    ts_rgb f;
    float pdf;
    uint32_t flags; /* TS_BXDF_* of the sampled event */
    float eta;      /* η(wi side) / η(wo side) for transmission, 1 for reflection */
} ts_bsdf_sample;

/* Draws wi (u_lobe picks the lobe, u samples it). False: no sample (absorbed, below the
 * horizon, grazing wo, or f = 0). */
bool ts_bsdf_sample_f(const ts_bsdf *b, ts_vec3 wo_world, float u_lobe, ts_vec2 u, ts_bsdf_sample *out);

/* Union of the lobes' flags (e.g. test TS_BXDF_SPECULAR-only BSDFs to skip MIS). */
uint32_t ts_bsdf_flags(const ts_bsdf *b);
/* Number of lobes that are not specular. */
int ts_bsdf_num_non_specular(const ts_bsdf *b);

/* ρ_hd(wo) (world wo) and ρ_hh by Monte Carlo over the whole BSDF, specular lobes
 * included (pbrt-v3 §14.1.5); samples are parameters (u_lobe[i], u[i]). */
ts_rgb ts_bsdf_rho_hd(const ts_bsdf *b, ts_vec3 wo_world, int n, const float *u_lobe, const ts_vec2 *u);
ts_rgb ts_bsdf_rho_hh(const ts_bsdf *b, int n, const ts_vec2 *u_wo, const float *u_lobe, const ts_vec2 *u_wi);

#endif
