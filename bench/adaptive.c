/* adaptive.c — bench_adaptive: time to a target error with and without adaptive sampling
 * (render/adaptive.h), side by side, and the targets table of docs/performance.md.
 *
 *   bench_adaptive [--target E] [--side F] [--seconds S] [--threads N] SCENE...
 *
 * For each scene (JSON or pbrt-v3), on the central crop of 1/F of its width and height
 * (default F = 8: 1/64 of the pixels, so a measurement takes a minute or two on a shared
 * 2-CPU machine; at least 32 × 32 pixels), it renders one job uniformly and then one
 * adaptively, both to the target error E (default 0.01) of the film's estimate
 * (proto/error-estimate.md), each bounded by S seconds (default 150). The time to E is
 * the job's CPU time (the process's: on a loaded machine wall time is mostly waiting for
 * the CPUs; wall time is given too) scaled by (E_reached / E)²: the 1/n law of a uniform render's
 * error², which corrects the overshoot of its last doubling pass (and the adaptive job's
 * quarter-octave step, and a job that hit S before E: marked "*", extrapolated).
 *
 * Where the scene's folder holds NAME-pbrt3.exr (../shared/scenes/pbrt-v3), each image is
 * also compared with it: relative RMS error sqrt(mean (Y − Y_ref)² / (Y_ref² + 1e-3)) on
 * the crop, raw and with the reference's own noise taken out (its estimate: the uniform
 * job's E scaled to pbrt-v3's reference spp, given by --ref-spp NAME=SPP). The targets
 * table then gives the time to reach pbrt-v3's error at its reference spp (that estimate)
 * with adaptive sampling, scaled from the crop to the whole image by the pixel count, as
 * the wall time of the threads on free CPUs (CPU time ÷ threads), beside pbrt-v3's
 * recorded time (--ref-time NAME=SECONDS, from REFERENCES.md).
 *
 * Output: one markdown table on stdout with the load average at the start and end. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_util.h"
#include "tessera.h"

typedef struct waiter {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool done;
    ts_job_progress final;
} waiter;

static void on_done(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    (void)j;
    waiter *w = user;
    pthread_mutex_lock(&w->mu);
    w->done = true;
    w->final = *p;
    pthread_cond_signal(&w->cv);
    pthread_mutex_unlock(&w->mu);
}

typedef struct result {
    double seconds, cpu_s, error, spp, samples, ref_error; /* ref_error < 0: no reference */
    bool reached;
} result;

static double load_avg(void)
{
    double l = -1;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f && fscanf(f, "%lf", &l) != 1) l = -1;
    if (f) fclose(f);
    return l;
}

/* The relative RMS error of film against the reference image (full-image pixels). */
static double ref_error(const ts_film *f, const ts_image *ref)
{
    int cr = ts_image_channel(ref, "R"), cg = ts_image_channel(ref, "G"), cb = ts_image_channel(ref, "B");
    if (cr < 0 || cg < 0 || cb < 0 || ref->width != f->full_width || ref->height != f->full_height) return -1;
    double sum = 0;
    for (int y = f->y0; y < f->y0 + f->height; y++)
        for (int x = f->x0; x < f->x0 + f->width; x++) {
            const float *px = &ref->data[((size_t)y * ref->width + x) * ref->n_channels];
            double yr = ts_rgb_luminance((ts_rgb){px[cr], px[cg], px[cb]});
            double yt = ts_rgb_luminance(ts_film_pixel_rgb(f, x, y));
            sum += (yt - yr) * (yt - yr) / (yr * yr + 1e-3);
        }
    return sqrt(sum / ((double)f->width * f->height));
}

static ts_status run(const char *path, int side, int threads, double target, double seconds, bool adaptive,
                     const ts_image *ref, result *out, int *w_out, int *h_out, int *full_px, ts_error *err)
{
    ts_scene *s = NULL;
    ts_status st = ts_scene_load_path(path, NULL, NULL, NULL, &s, err);
    if (st) return st;
    int cw = s->crop_x1 - s->crop_x0, ch = s->crop_y1 - s->crop_y0;
    *full_px = cw * ch;
    int w = cw / side, h = ch / side;
    if (w < 32) w = cw < 32 ? cw : 32;
    if (h < 32) h = ch < 32 ? ch : 32;
    s->crop_x0 += (cw - w) / 2, s->crop_y0 += (ch - h) / 2;
    s->crop_x1 = s->crop_x0 + w, s->crop_y1 = s->crop_y0 + h;
    *w_out = w, *h_out = h;
    ts_scheduler *sch = ts_scheduler_create(threads, 1, err);
    if (!sch) {
        ts_scene_destroy(s);
        return err->status;
    }
    waiter wt = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, false, {0}};
    ts_sched_job_desc d = {0};
    d.scene = s;
    ts_job_settings_from_scene(s, &d.settings);
    d.settings.spp = 1u << 20;
    d.settings.target_error = target;
    d.settings.time_limit_s = seconds;
    d.settings.adaptive = adaptive;
    d.callbacks = (ts_job_callbacks){NULL, NULL, on_done, &wt};
    ts_sched_job *j = ts_scheduler_submit(sch, &d, err);
    if (!j) {
        ts_scene_destroy(s);
        ts_scheduler_destroy(sch);
        return err->status;
    }
    double cpu0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    pthread_mutex_lock(&wt.mu);
    while (!wt.done) pthread_cond_wait(&wt.cv, &wt.mu);
    pthread_mutex_unlock(&wt.mu);
    double cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
    ts_film *f = ts_sched_job_film(j, NULL, err);
    if (f) {
        out->error = ts_film_relative_error(f);
        out->reached = wt.final.halt == TS_HALT_ERROR;
        out->seconds = wt.final.elapsed_s * (out->error / target) * (out->error / target);
        out->cpu_s = cpu * (out->error / target) * (out->error / target);
        out->spp = wt.final.spp_done;
        out->samples = (double)wt.final.samples;
        out->ref_error = ref ? ref_error(f, ref) : -1;
        ts_film_destroy(f);
    }
    ts_sched_job_release(j);
    ts_scheduler_destroy(sch);
    return f ? TS_OK : err->status;
}

/* NAME=VALUE arguments of --ref-spp / --ref-time: the value for name, else -1. */
typedef struct named { const char *name; double value; } named;
static double lookup(const named *v, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(v[i].name, name)) return v[i].value;
    return -1;
}

int main(int argc, char **argv)
{
    double target = 0.01, seconds = 150;
    int side = 8, threads = 2, n_spp = 0, n_time = 0;
    named ref_spp[64], ref_time[64];
    int first = 1;
    for (; first < argc && argv[first][0] == '-'; first++) {
        if (first + 1 >= argc) break;
        const char *a = argv[first], *v = argv[++first];
        if (!strcmp(a, "--target")) target = atof(v);
        else if (!strcmp(a, "--side")) side = atoi(v);
        else if (!strcmp(a, "--seconds")) seconds = atof(v);
        else if (!strcmp(a, "--threads")) threads = atoi(v);
        else if ((!strcmp(a, "--ref-spp") || !strcmp(a, "--ref-time")) && strchr(v, '=')) {
            named *t = !strcmp(a, "--ref-spp") ? &ref_spp[n_spp++ % 64] : &ref_time[n_time++ % 64];
            t->name = strndup(v, (size_t)(strchr(v, '=') - v));
            t->value = atof(strchr(v, '=') + 1);
        } else {
            fprintf(stderr, "bench_adaptive: unknown option %s\n", a);
            return 2;
        }
    }
    if (first >= argc || !(target > 0) || side < 1 || threads < 1) {
        fprintf(stderr, "usage: bench_adaptive [--target E] [--side F] [--seconds S] [--threads N] "
                        "[--ref-spp NAME=SPP]... [--ref-time NAME=SECONDS]... SCENE...\n");
        return 2;
    }
    printf("Time to a relative error estimate of %g (proto/error-estimate.md), uniform then adaptive side by side, "
           "%d threads, central crop of 1/%d of each side (at least 32 px); load average %.1f at the start.\n\n",
           target, threads, side, load_avg());
    printf("| scene | crop | uniform CPU s (wall) | adaptive CPU s (wall) | uniform ÷ adaptive (CPU) | samples ratio | E uniform / adaptive | vs pbrt-v3 "
           "uniform / adaptive (noise-corrected) | pbrt-v3 ref spp, s | E at ref spp | adaptive s to it, whole image | "
           "÷ pbrt-v3 |\n");
    printf("|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
    int failed = 0;
    for (int i = first; i < argc; i++) {
        const char *path = argv[i];
        char name[256], refpath[4096];
        const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
        snprintf(name, sizeof name, "%s", base);
        if (strrchr(name, '.')) *strrchr(name, '.') = '\0';
        snprintf(refpath, sizeof refpath, "%.*s%s-pbrt3.exr", (int)(base - path), path, name);
        ts_image ref = {0};
        ts_error err = {0};
        bool have_ref = access(refpath, R_OK) == 0 && ts_exr_read(refpath, &ref, &err) == TS_OK;
        result u = {0}, a = {0};
        int w = 0, h = 0, full = 0;
        ts_status st = run(path, side, threads, target, seconds, false, have_ref ? &ref : NULL, &u, &w, &h, &full, &err);
        if (!st) st = run(path, side, threads, target, seconds, true, have_ref ? &ref : NULL, &a, &w, &h, &full, &err);
        if (st) {
            fprintf(stderr, "bench_adaptive: %s: %s\n", path, err.message);
            failed = 1;
            if (have_ref) ts_image_fini(&ref);
            continue;
        }
        double rspp = lookup(ref_spp, n_spp, name), rtime = lookup(ref_time, n_time, name);
        char refcol[160] = "—", tcol[64] = "—", ecol[32] = "—", acol[48] = "—", rcol[32] = "—";
        if (have_ref) {
            double e_ref = rspp > 0 ? u.error * sqrt(u.spp / rspp) : 0; /* the reference's own noise */
            double cu = sqrt(fmax(0, u.ref_error * u.ref_error - e_ref * e_ref));
            double ca = sqrt(fmax(0, a.ref_error * a.ref_error - e_ref * e_ref));
            snprintf(refcol, sizeof refcol, "%.4f / %.4f (%.4f / %.4f)", u.ref_error, a.ref_error, cu, ca);
        }
        if (rspp > 0) {
            double e_ref = u.error * sqrt(u.spp / rspp); /* tessera's error at pbrt-v3's spp (1/n law) */
            /* The adaptive job's time to it, by the same law, crop → whole image by pixels. */
            double t = a.cpu_s / threads * (target / e_ref) * (target / e_ref) * (double)full / ((double)w * h);
            snprintf(tcol, sizeof tcol, "%.0f, %.0f", rspp, rtime);
            snprintf(ecol, sizeof ecol, "%.4f", e_ref);
            snprintf(acol, sizeof acol, "%.0f", t);
            if (rtime > 0) snprintf(rcol, sizeof rcol, "%.2f", t / rtime);
        }
        printf("| %s | %d×%d | %.1f (%.1f)%s | %.1f (%.1f)%s | %.2f | %.2f | %.4f / %.4f | %s | %s | %s | %s | %s |\n",
               name, w, h, u.cpu_s, u.seconds, u.reached ? "" : "*", a.cpu_s, a.seconds, a.reached ? "" : "*",
               u.cpu_s / a.cpu_s,
               u.samples * (u.error / target) * (u.error / target) / (a.samples * (a.error / target) * (a.error / target)),
               u.error, a.error, refcol, tcol, ecol, acol, rcol);
        fflush(stdout);
        if (have_ref) ts_image_fini(&ref);
    }
    printf("\nLoad average %.1f at the end. \"*\": the job hit its time bound first; its time is extrapolated by the "
           "1/n law.\n", load_avg());
    return failed;
}
