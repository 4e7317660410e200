/* progressive.c — the pass and halt policy; see progressive.h. */
#include "render/progressive.h"

#include <math.h>

#include "render/adaptive.h"

void ts_job_settings_from_scene(const ts_scene *s, ts_job_settings *out)
{
    out->integrator = s->integrator.type;
    out->spp = s->job.spp ? s->job.spp : s->spp;
    out->priority = s->job.priority;
    out->time_limit_s = s->job.time_limit_s;
    out->target_error = s->job.target_error;
    out->adaptive = s->job.adaptive;
}

double ts_job_adaptive_target(const ts_job_settings *js)
{
    return js->target_error > 0 ? js->target_error : TS_ADAPTIVE_DEFAULT_ERROR;
}

const char *ts_job_name(const ts_scene *s) { return s->job.name ? s->job.name : s->name; }

const char *ts_halt_reason_name(ts_halt_reason r)
{
    switch (r) {
    case TS_HALT_NONE: return "none";
    case TS_HALT_SPP: return "spp";
    case TS_HALT_TIME: return "time_limit";
    case TS_HALT_ERROR: return "target_error";
    case TS_HALT_CANCELLED: return "cancelled";
    case TS_HALT_RESTORED: return "restored";
    }
    return "unknown";
}

const char *ts_halt_reason_phrase(ts_halt_reason r)
{
    switch (r) {
    case TS_HALT_NONE: return "not finished";
    case TS_HALT_SPP: return "sample count reached";
    case TS_HALT_TIME: return "time limit reached";
    case TS_HALT_ERROR: return "target error reached";
    case TS_HALT_CANCELLED: return "cancelled";
    case TS_HALT_RESTORED: return "restored finished";
    }
    return "unknown";
}

ts_halt_reason ts_progressive_halt(const ts_job_settings *js, const ts_pass_state *st)
{
    if (st->cancelled) return TS_HALT_CANCELLED;
    if (st->done >= js->spp) return TS_HALT_SPP;
    /* An adaptive job halts on its error at check points only (adaptive.h), so where it
     * halts does not depend on how its passes were split. */
    bool at_check = !js->adaptive || st->done < TS_ADAPTIVE_MIN_SPP || ts_adaptive_is_check(st->done);
    if (js->target_error > 0 && st->done >= TS_PROGRESSIVE_ERROR_MIN_SPP && st->error >= 0 && at_check &&
        st->error <= js->target_error)
        return TS_HALT_ERROR;
    if (js->time_limit_s > 0 && (st->out_of_time || (st->done > 0 && st->elapsed_s >= js->time_limit_s)))
        return TS_HALT_TIME;
    return TS_HALT_NONE;
}

uint32_t ts_progressive_next_pass_end(const ts_job_settings *js, const ts_pass_state *st, double max_pass_s)
{
    uint32_t done = st->done;
    uint64_t end = done == 0 ? 1 : 2ull * done;
    if (js->adaptive && end > ts_adaptive_next_check(done)) end = ts_adaptive_next_check(done);
    if (end > js->spp) end = js->spp;
    /* This process's own speed: samples it rendered over the time it took. */
    uint32_t here = done > st->done_before ? done - st->done_before : 0;
    double seconds = st->elapsed_s - st->elapsed_before;
    if (here > 0 && seconds > 0) {
        double per_spp = seconds / here;
        if (js->time_limit_s > 0) {
            double fit = (js->time_limit_s - st->elapsed_s) / per_spp;
            if (fit < (double)(end - done)) end = done + (fit >= 1 ? (uint64_t)fit : 1);
        }
        if (max_pass_s > 0) {
            double fit = max_pass_s / per_spp;
            if (fit < (double)(end - done)) end = done + (fit >= 1 ? (uint64_t)fit : 1);
        }
    }
    return (uint32_t)end;
}

void ts_progressive_estimate(const ts_job_settings *js, const ts_progress_in *in, double *progress, double *eta_s)
{
    if (in->finished) {
        *progress = 1;
        *eta_s = 0;
        return;
    }
    double seconds = in->elapsed_s - in->elapsed_before, rendered = in->spp_fraction - in->spp_before;
    double rate = seconds > 0 && rendered > 0 ? rendered / seconds : -1; /* spp per second */
    double spp = js->spp > 0 ? (double)js->spp : 1;
    /* The sample target: always a bound. */
    double p = in->spp_fraction / spp;
    double eta = rate > 0 ? (spp - in->spp_fraction) / rate : -1;
    if (js->time_limit_s > 0) {
        double pt = in->elapsed_s / js->time_limit_s, et = js->time_limit_s - in->elapsed_s;
        if (pt > p) p = pt;
        if (et < 0) et = 0;
        if (eta < 0 || et < eta) eta = et;
    }
    /* A target error before its first estimate (below 2 spp): the render may stop at any
     * pass from 4 spp on, so the time to the spp cap (hours, for a large one) is no
     * estimate of when it ends; a time limit still bounds it. Else unknown, until the
     * error says. */
    if (js->target_error > 0 && !(in->error > 0 && in->error_spp > 0)) {
        double et = js->time_limit_s - in->elapsed_s;
        eta = js->time_limit_s > 0 ? (et > 0 ? et : 0) : -1;
    }
    if (js->target_error > 0 && in->error > 0 && in->error_spp > 0) {
        double slope = -0.5;
        if (in->prev_error > 0 && in->prev_error_spp > 0 && in->prev_error_spp != in->error_spp) {
            slope = log(in->error / in->prev_error) / log((double)in->error_spp / in->prev_error_spp);
            if (!(slope <= -0.25)) slope = -0.25; /* also NaN: the error did not fall (yet) */
            if (slope < -1) slope = -1;
        }
        /* error(n) = error · (n / error_spp)^slope reaches the target at n_target. */
        double n_target = in->error <= js->target_error
                              ? (double)in->error_spp
                              : in->error_spp * pow(js->target_error / in->error, 1 / slope);
        if (n_target > spp) n_target = spp;
        if (n_target < TS_PROGRESSIVE_ERROR_MIN_SPP) n_target = TS_PROGRESSIVE_ERROR_MIN_SPP;
        double pe = in->spp_fraction / n_target;
        if (pe > p) p = pe;
        if (rate > 0) {
            double ee = (n_target - in->spp_fraction) / rate;
            if (ee < 0) ee = 0;
            if (eta < 0 || ee < eta) eta = ee;
        }
    }
    *progress = p < 0 ? 0 : p > 1 ? 1 : p;
    *eta_s = eta;
}
