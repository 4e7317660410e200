/* medium.h — participating media (pbrt-v3 ch. 15): homogeneous and grid media, the
 * Henyey–Greenstein phase function, distance sampling and transmittance.
 *
 * Design note: a medium is a plain tagged struct of the scene (no vtable), read by many
 * threads. pbrt-v3's two media:
 *  - homogeneous: σa, σs constant (per unit of world length), σt = σa + σs. Distance
 *    sampling in closed form: a channel picked uniformly, t = −ln(1 − u)/σt[channel],
 *    weighted by the one-sample MIS over the three channels (pbrt-v3's
 *    HomogeneousMedium::Sample); transmittance exp(−σt·d).
 *  - grid (pbrt-v3's "heterogeneous", GridDensityMedium): σa, σs scaled by a density
 *    interpolated trilinearly in an nx × ny × nz grid of samples at cell centres, which
 *    spans the box [p0, p1] of the medium's space (placed in the world by to_world); 0
 *    outside the grid. σt must be the same in every channel (pbrt-v3 uses the first).
 *    Distance sampling by delta tracking; transmittance by ratio tracking (pbrt-v3's Sample
 *    and Tr), both in the segment where the ray crosses the box, against a piecewise-
 *    constant majorant: σt times the bound of each cell of a coarse grid over the box that
 *    the ray crosses (walked cell by cell; pbrt-v3 takes σt·max density everywhere). A
 *    tentative collision past a cell's end restarts at the next cell with its own rate
 *    (the exponential's memorylessness), so both estimators stay exact in expectation;
 *    empty cells cost no step. docs/design.md §9 #22.
 * Rays here are segments o + t·d, t in [0, tmax) (d need not be unit; tmax may be ∞).
 *
 * Random numbers: the homogeneous closed form takes a 2-D sample value (x the channel, y
 * the distance) from the caller's sample stream; the trackers draw an unbounded number of
 * values from a walk's own PCG32 stream, which the caller seeds from the pixel sample, so
 * a value depends on the sample only and images do not depend on thread counts. A walk is
 * bounded: a tracking loop stops after TS_MEDIUM_MAX_STEPS steps (the path then carries
 * no light: counted in `truncated`) or, checked every 1024 steps, when `stop` is set. */
#ifndef TS_MEDIUM_H
#define TS_MEDIUM_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "core/hash.h"
#include "core/transform.h"
#include "core/vecmath.h"
#include "geometry/interaction.h"

typedef enum ts_medium_type { TS_MEDIUM_HOMOGENEOUS, TS_MEDIUM_GRID } ts_medium_type;

typedef struct ts_medium {
    ts_medium_type type;
    ts_rgb sigma_a, sigma_s; /* per unit length; grid: at density 1 */
    ts_rgb sigma_t;          /* σa + σs */
    float g;                 /* Henyey–Greenstein asymmetry, in (−1, 1) */
    /* grid only */
    uint32_t nx, ny, nz;
    const float *density;    /* nx·ny·nz values ≥ 0, x fastest: density[(z·ny + y)·nx + x] */
    float max_density;       /* the largest density (0: the medium is empty) */
    ts_xform to_unit;        /* world → the grid's unit cube ([p0, p1] in the medium's space ↦ [0, 1]³) */
    /* The majorant grid: the unit cube in mx × my × mz equal cells (TS_MEDIUM_MAJORANT_CELL
     * samples an axis each), each holding a bound on the interpolated density anywhere in
     * it (x fastest); the trackers' majorant is σt times the bound of the cell they cross. */
    uint32_t mx, my, mz;
    const float *majorant;
} ts_medium;

/* Henyey–Greenstein's density for the scattering cosine cos θ = dot(d_in, d_out) (the
 * direction travelled before and after): (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2}). */
float ts_hg_phase(float cos_theta, float g);
/* A direction d_out after scattering a ray travelling along unit d_in, drawn with density
 * ts_hg_phase(dot(d_in, d_out), g) per solid angle; *pdf that density (the phase
 * function's value: sampling is exact). */
ts_vec3 ts_hg_sample(ts_vec3 d_in, float g, ts_vec2 u, float *pdf);

#define TS_MEDIUM_MAX_STEPS (1u << 20)

typedef struct ts_medium_walk {
    ts_pcg32 rng;
    uint64_t steps;     /* tracking steps taken */
    uint64_t truncated; /* walks cut at TS_MEDIUM_MAX_STEPS or by stop */
    const atomic_bool *stop; /* or NULL */
} ts_medium_walk;

/* A walk for pixel sample `index` of (px, py) under sampler seed `seed`. */
void ts_medium_walk_init(ts_medium_walk *w, uint32_t seed, uint32_t px, uint32_t py, uint32_t index,
                         const atomic_bool *stop);

/* Transmittance along [0, tmax) of ray in medium m: exact (homogeneous) or a ratio-tracking
 * estimate whose mean is exact (grid). */
ts_rgb ts_medium_tr(const ts_medium *m, const ts_ray *ray, float tmax, ts_medium_walk *w);

/* pbrt-v3's Medium::Sample along [0, tmax): either a scattering point (*scattered true, *t
 * its ray parameter) or none before tmax (*scattered false); returns the factor the path
 * throughput is multiplied by (black: the path ends). u: the closed form's sample value. */
ts_rgb ts_medium_sample(const ts_medium *m, const ts_ray *ray, float tmax, ts_vec2 u, ts_medium_walk *w,
                        bool *scattered, float *t);

/* The majorant grid of a grid medium whose nx, ny, nz and density are set: its cells per
 * axis (*mx, *my, *mz, each ⌈n / TS_MEDIUM_MAJORANT_CELL⌉), and, with cells non-NULL (room
 * for mx·my·mz floats), their bounds: the largest of the samples the interpolation can
 * read anywhere in the cell, widened by one sample each side (a point rounded across a
 * cell face still finds its bound). */
#define TS_MEDIUM_MAJORANT_CELL 8u
void ts_medium_majorant_grid(const ts_medium *m, uint32_t *mx, uint32_t *my, uint32_t *mz, float *cells);

/* The density the trackers see at a world point: the grid's interpolation inside its box
 * (which ramps to 0 over the outer half cell), 0 outside; homogeneous 1. */
float ts_medium_density(const ts_medium *m, ts_vec3 p_world);

/* pbrt-v3's named scattering presets (GetMediumScatteringProperties: Jensen et al. 2001,
 * Narasimhan et al. 2006; σ in mm⁻¹): false if name is none of them. */
bool ts_medium_preset(const char *name, ts_rgb *sigma_a, ts_rgb *sigma_s);
/* The i-th preset's name, or NULL past the end (for error messages and tests). */
const char *ts_medium_preset_name(uint32_t i);

#endif
