/* progressive.h — what a render is asked to do, and the pass and halt policy that every
 * progressive render follows (the server's jobs and `tessera render` alike).
 *
 * Design note: a render is described once, by ts_job_settings: the integrator, the samples
 * per pixel to reach, a priority, and two optional halting bounds (time, error). The
 * scene's "job" block gives the defaults (ts_job_settings_from_scene); the CLI's options
 * and the server's restore override fields of the same type. A render advances in passes
 * whose ends are 1, 2, 4, 8, … samples per pixel (passes of 1, 1, 2, 4, …), so a preview
 * improves evenly, capped at the target; with a time limit the last pass is shrunk to what
 * the measured speed says still fits, and a pass may be bounded in time (a checkpoint
 * interval). At every pass end the render halts on, in this order: cancellation, the
 * sample target, the target error (checked from TS_PROGRESSIVE_ERROR_MIN_SPP on, since an
 * estimate of a few samples is noise; for an adaptive job from TS_ADAPTIVE_MIN_SPP on only
 * at check points, adaptive.h), the time limit. The scheduler (scheduler.h) is the
 * one caller of the policy; these functions are pure and thread-safe. */
#ifndef TS_PROGRESSIVE_H
#define TS_PROGRESSIVE_H

#include <stdbool.h>
#include <stdint.h>

#include "scene/scene.h"

/* The error estimate is not used to halt before this many samples per pixel. */
#define TS_PROGRESSIVE_ERROR_MIN_SPP 4

typedef struct ts_job_settings {
    ts_integrator_type integrator;
    uint32_t spp;        /* samples per pixel to reach, ≥ 1 */
    int priority;        /* higher first, in a shared scheduler */
    double time_limit_s; /* rendering wall time; 0 = none */
    double target_error; /* relative error estimate (ts_film_relative_error) to reach; 0 = none */
    bool adaptive;       /* adaptive sampling (adaptive.h): passes after the first few go to the
                          * pixels still short of their share of the target */
} ts_job_settings;

/* The error an adaptive job's choice of pixels aims at: its target error, else
 * TS_ADAPTIVE_DEFAULT_ERROR (adaptive.h). */
double ts_job_adaptive_target(const ts_job_settings *js);

/* The settings a scene document asks for: its integrator, its "job" block's spp (else the
 * sampler's), priority, time limit and target error. */
void ts_job_settings_from_scene(const ts_scene *s, ts_job_settings *out);

/* A render's name, the same in `tessera render`, the server's job list and every EXR
 * (docs/design.md §5b): the scene's job.name, else its "name", else the name its loader gave
 * it (the file's stem; "cornell-box" for the built-in scene). */
const char *ts_job_name(const ts_scene *s);

/* Why a render stopped. */
typedef enum ts_halt_reason {
    TS_HALT_NONE,      /* not finished */
    TS_HALT_SPP,       /* sample target reached */
    TS_HALT_TIME,      /* time limit reached */
    TS_HALT_ERROR,     /* target error reached */
    TS_HALT_CANCELLED, /* cancelled */
    TS_HALT_RESTORED,  /* submitted already finished (restored from a checkpoint) */
} ts_halt_reason;

/* "none", "spp", "time_limit", "target_error", "cancelled", "restored". */
const char *ts_halt_reason_name(ts_halt_reason r);
/* A phrase for people: "sample count reached", "time limit reached", … */
const char *ts_halt_reason_phrase(ts_halt_reason r);

/* Where a render stands at a pass end. */
typedef struct ts_pass_state {
    uint32_t done;          /* samples per pixel every tile holds */
    uint32_t done_before;   /* of them, held before this process rendered any (a resume) */
    double elapsed_s;       /* rendering wall time, including elapsed_before */
    double elapsed_before;  /* of it, spent before this process (a resume) */
    double error;           /* error estimate at `done`; < 0 when unknown */
    bool cancelled;
    bool out_of_time;       /* the time limit stopped the pass part-way (scheduler.h) */
} ts_pass_state;

/* Whether (and why) the render halts at this pass end. */
ts_halt_reason ts_progressive_halt(const ts_job_settings *js, const ts_pass_state *st);

/* The end (samples per pixel) of the pass after st->done, for a render that does not
 * halt: double the samples (1 after 0), capped at js->spp, and for an adaptive job at the
 * next check point (adaptive.h: so from TS_ADAPTIVE_MIN_SPP on a pass runs from one check
 * point to the next); shrunk, once this process has
 * a measured speed, to what fits in the time limit's remainder and in max_pass_s (0 = no
 * bound), but always at least one more sample. */
uint32_t ts_progressive_next_pass_end(const ts_job_settings *js, const ts_pass_state *st, double max_pass_s);

/* What a progress estimate reads: where the render stands between pass ends. */
typedef struct ts_progress_in {
    double spp_fraction;     /* pixel-samples every tile holds ÷ pixels: spp that grows as tiles finish */
    double spp_before;       /* of it, held before this process rendered any (a resume) */
    double elapsed_s;        /* rendering wall time, including elapsed_before */
    double elapsed_before;
    double error;            /* the last error estimate; < 0 when unknown */
    uint32_t error_spp;      /* the spp it was made at */
    double prev_error;       /* the estimate before it (for the convergence slope); < 0 when unknown */
    uint32_t prev_error_spp;
    bool finished;
} ts_progress_in;

/* Progress (0–1) towards whichever halting bound comes first and the seconds still to go
 * (*eta_s < 0 while it cannot be estimated: no measured speed yet, or a target error
 * without an error estimate yet). The sample target
 * counts samples held; a time limit counts time; a target error is turned into the spp
 * expected to reach it from the convergence slope of the last two estimates (error ∝
 * spp^slope, slope clamped to [-1, -0.25]; -0.5, Monte Carlo's, until two are known). A
 * finished render is at 1 with 0 s to go. */
void ts_progressive_estimate(const ts_job_settings *js, const ts_progress_in *in, double *progress, double *eta_s);

#endif
