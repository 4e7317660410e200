/* progressive.c — the pass and halt policy; see progressive.h. */
#include "render/progressive.h"

void ts_job_settings_from_scene(const ts_scene *s, ts_job_settings *out)
{
    out->integrator = s->integrator.type;
    out->spp = s->job.spp ? s->job.spp : s->spp;
    out->priority = s->job.priority;
    out->time_limit_s = s->job.time_limit_s;
    out->target_error = s->job.target_error;
}

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
    if (js->target_error > 0 && st->done >= TS_PROGRESSIVE_ERROR_MIN_SPP && st->error >= 0 &&
        st->error <= js->target_error)
        return TS_HALT_ERROR;
    if (js->time_limit_s > 0 && st->done > 0 && st->elapsed_s >= js->time_limit_s) return TS_HALT_TIME;
    return TS_HALT_NONE;
}

uint32_t ts_progressive_next_pass_end(const ts_job_settings *js, const ts_pass_state *st, double max_pass_s)
{
    uint32_t done = st->done;
    uint64_t end = done == 0 ? 1 : 2ull * done;
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
