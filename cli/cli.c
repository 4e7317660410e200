/* cli.c — the command line of docs/design.md §5b.
 *
 * `tessera render` loads a scene (or the built-in Cornell box), renders it in progressive
 * passes of 1, 1, 2, 4, … samples per pixel until the sample count, the time limit or the
 * target error is reached, and writes every -o file (the extension picks the encoder).
 * Exit status: 0 success, 1 bad input or failed output, 2 usage error. Every output is
 * checked before rendering (outputs.h), and nothing is written unless the render succeeded
 * and every output could be. */
#include "cli.h"

#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stddef.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "convert.h"
#include "diagnostics.h"
#include "display.h"
#include "merge.h"
#include "options.h"
#include "outputs.h"
#include "serve.h"
#include "tessera.h"
#include "usage.h"


static void usage(FILE *f)
{
    fprintf(f, "usage: tessera COMMAND [OPTIONS]\n"
               "  render [SCENE]   render a scene (.json or pbrt-v3 .pbrt; none: the built-in Cornell box)\n"
               "                   to EXR/PNG\n"
               "  convert SCENE    write a pbrt-v3 scene (.pbrt) as the equivalent scene document (.json)\n"
               "  merge SHARD...   add farm shards (EXR) into one image\n"
               "  serve            the render server: HTTP API and web UI\n"
               "  help [COMMAND]   this text, or a command's options with their units and defaults\n"
               "  --version        tessera's version\n"
               "`tessera COMMAND --help` lists the command's options.\n");
}

#define usage_error(...) (srv_usage_error("tessera", usage, __VA_ARGS__), SRV_USAGE_EXIT)
#define render_usage_error(...) (srv_usage_error("tessera render", NULL, __VA_ARGS__), SRV_USAGE_EXIT)

/* A relative error as "0.01" or "1%": in (0, 1). */
static bool parse_relative_error(const char *s, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s) return false;
    if (*end == '%' && end[1] == '\0') v /= 100, end++;
    if (*end || !(v > 0) || !(v < 1) || !isfinite(v)) return false;
    *out = v;
    return true;
}

/* ---------------------------------------------------------------- options */

typedef struct render_opts {
    cli_outputs outputs;
    unsigned long long spp, threads, seed, shard_count;
    bool have_seed, quiet, adaptive;
    double time_limit, target_error, checkpoint_interval;
    const char *scene_path, *shard_text, *checkpoint;
    const char *display_server; /* --display-server HOST:PORT, or NULL */
} render_opts;

/* Why an adaptive render cannot take o's --shard or --checkpoint, or NULL. A shard must hold
 * one sample range in every pixel (tessera merge adds them exactly) and so must the
 * checkpoint EXR (it resumes at one sample index); an adaptive render's pixels stop at
 * different counts, chosen from the whole image. */
static const char *adaptive_refusal(const render_opts *o)
{
    if (o->shard_text)
        return "goes without --shard: an adaptive render's pixels stop at different sample counts, chosen from the "
               "whole image, and shards that did so could not be merged exactly; render it in one piece";
    if (o->checkpoint)
        return "goes without --checkpoint: a checkpoint resumes every pixel at one sample index, and an adaptive "
               "render's pixels stop at different counts (tessera serve --data resumes adaptive jobs)";
    return NULL;
}

static bool take_output(void *opts, const char *name, const char *arg, char *why, size_t why_len)
{
    (void)name;
    if (cli_outputs_add(&((render_opts *)opts)->outputs, arg)) return true;
    snprintf(why, why_len, "at most 8 outputs");
    return false;
}

static bool take_seed(void *opts, const char *name, const char *arg, char *why, size_t why_len)
{
    (void)name;
    render_opts *o = opts;
    char *end;
    unsigned long long v = arg[0] && arg[0] != '-' ? strtoull(arg, &end, 10) : 0;
    if (!arg[0] || arg[0] == '-' || *end || v > UINT32_MAX) {
        snprintf(why, why_len, "expected a whole number from 0 to 4294967295, got '%s'", arg);
        return false;
    }
    o->seed = v;
    o->have_seed = true;
    return true;
}

static bool take_target_error(void *opts, const char *name, const char *arg, char *why, size_t why_len)
{
    (void)name;
    if (parse_relative_error(arg, &((render_opts *)opts)->target_error)) return true;
    snprintf(why, why_len, "expected a relative error above 0 and below 1, as 0.01 or 1%%, got '%s'", arg);
    return false;
}

static bool take_display(void *opts, const char *name, const char *arg, char *why, size_t why_len)
{
    (void)name;
    ts_error derr = {0};
    if (srv_display_parse_address(arg, NULL, NULL, &derr)) {
        snprintf(why, why_len, "%s", derr.message);
        return false;
    }
    ((render_opts *)opts)->display_server = arg;
    return true;
}

#define F(field) offsetof(render_opts, field), sizeof(((render_opts *)0)->field)

/* Every option of `tessera render`: --help, the parser and the errors are made from this. */
static const srv_option render_options[] = {
    {"output", 'o', "FILE", SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0,
     "write FILE; .exr (colour, per-pixel variance, sample count) or .png;\nmay repeat (at most 8); each is checked "
     "before rendering, and all are\nwritten or none. Default: NAME.exr in this folder, NAME the job's\n(the scene's "
     "job.name, else its \"name\", else its file name)",
     "", take_output, NULL},
    {"spp", 0, "N", SRV_OPT_UINT, 1, 16777216, false, false, NULL, F(spp), "samples per pixel",
     "the scene's job.spp, else its sampler.spp", NULL, NULL},
    {"time-limit", 0, "SECONDS", SRV_OPT_NUMBER, 0, INFINITY, true, false, "seconds", F(time_limit),
     "stop after this much rendering time", "the scene's job.time_limit_s, else none", NULL, NULL},
    {"target-error", 0, "E", SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0,
     "stop at this relative error estimate, as 0.01 or 1%, below 1",
     "the scene's job.target_error, else none", take_target_error, NULL},
    {"adaptive", 0, NULL, SRV_OPT_FLAG, 0, 0, false, false, NULL, F(adaptive),
     "after the first 16 spp, only the pixels still short of their share\nof the target error (else 1%) take samples; not "
     "with --shard or\n--checkpoint", "the scene's job.adaptive", NULL, NULL},
    {"threads", 0, "N", SRV_OPT_UINT, 1, 1024, false, false, NULL, F(threads), "render threads", "one per core",
     NULL, NULL},
    {"seed", 0, "N", SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0, "the sampler's seed, 0 to 4294967295",
     "the scene's", take_seed, NULL},
    {"quiet", 0, NULL, SRV_OPT_FLAG, 0, 0, false, false, NULL, F(quiet), "no progress bar and no summary", "", NULL,
     NULL},
    {"shard", 0, "I/N | auto", SRV_OPT_STRING, 0, 0, false, false, NULL, F(shard_text),
     "render shard I of N: samples [I*S/N, (I+1)*S/N) of every pixel;\nauto takes I and N from JOB_COMPLETION_INDEX "
     "and --shard-count\n(Kubernetes) or SLURM_ARRAY_TASK_ID/_COUNT (Slurm). Needs an .exr\noutput (default: "
     "NAME.shard-I-of-N.exr), which tessera merge adds",
     "", NULL, "Farm nodes (docs/design.md section 7):"},
    {"shard-count", 0, "N", SRV_OPT_UINT, 1, 1000000, false, false, NULL, F(shard_count),
     "N for --shard auto under Kubernetes", "", NULL, NULL},
    {"checkpoint", 0, "FILE.exr", SRV_OPT_STRING, 0, 0, false, false, NULL, F(checkpoint),
     "save the shard's progress to FILE periodically and on SIGTERM or\nSIGINT, and resume from it when it exists", "",
     NULL, NULL},
    {"checkpoint-interval", 0, "S", SRV_OPT_NUMBER, 0, INFINITY, true, false, "seconds", F(checkpoint_interval),
     "seconds between checkpoints", NULL, NULL, NULL},
    {"display-server", 0, "HOST:PORT", SRV_OPT_CUSTOM, 0, 0, false, false, NULL, 0, 0,
     "stream tiles as they finish to a tev viewer listening there (tev's\ndefault is 127.0.0.1:14158); an "
     "unreachable one costs only a note",
     "", take_display, "Viewing:"},
    {"help", 0, NULL, SRV_OPT_HELP, 0, 0, false, false, NULL, 0, 0, NULL, "", NULL, NULL},
};
#undef F
#define N_RENDER_OPTIONS (sizeof render_options / sizeof *render_options)

static void render_defaults(render_opts *o)
{
    memset(o, 0, sizeof *o);
    o->checkpoint_interval = 60;
}

static void render_usage(FILE *f)
{
    render_opts defaults;
    render_defaults(&defaults);
    fprintf(f, "usage: tessera render [SCENE] [OPTIONS]\n"
               "Renders SCENE (a scene document, .json, or a pbrt-v3 scene, .pbrt; without one the built-in\n"
               "Cornell box; pbrt-v3's warnings are printed once each) in progressive\n"
               "passes of 1, 1, 2, 4, ... samples per pixel until the first of --spp, --time-limit and\n"
               "--target-error is reached.\n");
    srv_options_help(f, render_options, N_RENDER_OPTIONS, &defaults);
    fprintf(f, "Exit status: 0 done, 1 bad input or a failed output, 2 usage error, 128+signal when stopped\n"
               "by a signal with --checkpoint (the checkpoint saved).\n");
}

/* Fills o from the command line; -1 when the render should go ahead, else the exit status
 * (usage errors, --help). */
static int parse_render_options(int argc, char **argv, render_opts *o)
{
    render_defaults(o);
    char why[600];
    int first = 1;
    int rc = srv_options_parse(render_options, N_RENDER_OPTIONS, argc, argv, o, &first, why, sizeof why);
    if (rc == SRV_OPTIONS_HELP) {
        render_usage(stdout);
        return 0;
    }
    if (rc == SRV_OPTIONS_BAD) return render_usage_error("%s", why);
    if (argc - first > 1) return render_usage_error("render takes at most one scene file, got another: '%s'", argv[first + 1]);
    o->scene_path = first < argc ? argv[first] : NULL;
    const char *unsupported = cli_outputs_unsupported(&o->outputs);
    if (unsupported) return render_usage_error("-o %s: the extension must be .exr or .png", unsupported);
    if (o->shard_count && !o->shard_text) return render_usage_error("--shard-count goes with --shard auto");
    if (o->shard_text && o->outputs.n > 0) {
        bool exr = false;
        for (int i = 0; i < o->outputs.n; i++) exr = exr || cli_output_is_exr(o->outputs.path[i]);
        if (!exr)
            return render_usage_error("--shard: a shard is merged from its EXR; add -o %s.exr (a PNG alone cannot be "
                                      "merged)", "SHARD");
    }
    if (o->adaptive) {
        const char *why = adaptive_refusal(o);
        if (why) return render_usage_error("--adaptive %s", why);
    }
    if (o->checkpoint && !cli_output_is_exr(o->checkpoint))
        return render_usage_error("--checkpoint %s: the checkpoint is an EXR file; give it the .exr extension", o->checkpoint);
    return -1;
}

/* ---------------------------------------------------------------- the render in flight

 * `tessera render` renders through the scheduler of the server (render/scheduler.h, with
 * the pass and halt policy of render/progressive.h), as one job on a pool of its own, so
 * the CLI and the server produce the same pixels by construction. The callbacks below run
 * on the render threads: on_tile draws the progress bar, on_pass (while no tile of the job
 * renders) keeps the last complete pass for a checkpoint and writes the periodic one,
 * on_done wakes the main thread.
 *
 * With --checkpoint, SIGTERM and SIGINT stop the render: the main thread takes them with
 * sigwait (they are blocked in every thread, which inherit the mask), cancels the job, and
 * saves the last complete pass before exiting as the signal would (docs/design.md §7). */
typedef struct render_run {
    const ts_scene *scene;      /* immutable while the job runs (the job owns it) */
    const char *integrator;
    ts_sample_range range;
    uint32_t target_spp, span;  /* the render's spp; samples per pixel this process must hold */
    int nx, ny;
    const char *checkpoint;     /* NULL: no checkpoints, no signal handling */
    bool keep_complete;         /* keep the last complete pass (checkpoints; a shard with a time limit) */
    double checkpoint_interval;
    pthread_t main_thread;
    pthread_mutex_t mu;         /* guards everything below, and stderr writes of the bar */
    pthread_cond_t cv;
    bool finished;
    ts_job_progress final;
    bool bar;
    uint64_t done_px;           /* pixel-samples this process rendered */
    uint32_t *tile_spp;         /* per tile, what it holds */
    int last_permille;
    double last_bar_elapsed_s;  /* the job's elapsed time in the reading the bar last drew */
    double t0;
    /* checkpoints: only on_pass (one at a time per job) and, after the job, main */
    ts_film *complete;          /* the last complete pass (or the starting film) */
    uint32_t complete_spp;      /* samples per pixel in it, relative to range.begin */
    double last_checkpoint;
    ts_status ckpt_status;
    ts_error ckpt_err;
    srv_display *display;       /* --display-server: tiles stream to tev (thread-safe), or NULL */
} render_run;

/* "42 s", "3 min 20 s", "2 h 05 min". */
static void format_duration(double s, char *out, size_t len)
{
    if (s < 60) snprintf(out, len, "%.0f s", s);
    else if (s < 3600) snprintf(out, len, "%d min %02d s", (int)(s / 60), (int)fmod(s, 60));
    else snprintf(out, len, "%d h %02d min", (int)(s / 3600), (int)fmod(s / 60, 60));
}

static void on_tile(void *user, ts_sched_job *job, const ts_tile_event *ev)
{
    render_run *r = user;
    if (r->display) srv_display_tile(r->display, job, ev);
    ts_job_progress p;
    if (r->bar) ts_sched_job_progress(job, &p); /* takes the scheduler's lock: before ours */
    pthread_mutex_lock(&r->mu);
    uint32_t *held = &r->tile_spp[ev->ty * r->nx + ev->tx];
    r->done_px += (uint64_t)ev->w * (uint64_t)ev->h * (ev->spp - *held);
    *held = ev->spp;
    int permille = (int)(1000 * p.progress);
    /* Two threads' readings can reach the lock in either order: an older one is not drawn
     * over a newer one (the bar went 1 spp, 3.1% → 0 spp, 2.7%). */
    if (r->bar && permille != r->last_permille && p.elapsed_s >= r->last_bar_elapsed_s) {
        r->last_permille = permille;
        r->last_bar_elapsed_s = p.elapsed_s;
        int bars = permille * 30 / 1000;
        char bar[31], eta[32] = "?", error[32] = "n/a";
        for (int i = 0; i < 30; i++) bar[i] = i < bars ? '#' : '.';
        bar[30] = '\0';
        if (p.eta_s >= 0) format_duration(p.eta_s, eta, sizeof eta);
        if (p.error_estimate >= 0) snprintf(error, sizeof error, "%.2g%%", 100 * p.error_estimate);
        fprintf(stderr, "\rrendering [%s] %5.1f%%  %u/%u spp  error %s  %.2f Msamples/s  %.1f s, ETA %s   ", bar,
                permille / 10.0, p.spp_done, r->span, error, p.samples_per_s / 1e6, ts_now_seconds() - r->t0, eta);
        fflush(stderr);
    }
    pthread_mutex_unlock(&r->mu);
}

static ts_status write_checkpoint(render_run *r, const ts_film *film, uint32_t spp, double seconds, ts_error *err)
{
    ts_sample_range held = {r->range.begin, r->range.begin + spp};
    ts_shard_info info;
    ts_shard_info_init(&info, r->scene, film, r->integrator, &held, spp ? 1 : 0, r->target_spp, seconds);
    return ts_shard_write(r->checkpoint, film, &info, err);
}

static void on_pass(void *user, ts_sched_job *job, const ts_job_progress *p)
{
    render_run *r = user;
    if (!r->keep_complete || r->ckpt_status) return;
    ts_error err = {0};
    ts_film *film = ts_sched_job_film(job, NULL, &err);
    ts_status st = film ? TS_OK : err.status;
    if (film) {
        ts_film_destroy(r->complete);
        r->complete = film;
        r->complete_spp = p->spp_done;
        if (r->checkpoint && p->spp_done < r->span && ts_now_seconds() - r->last_checkpoint >= r->checkpoint_interval) {
            st = write_checkpoint(r, film, p->spp_done, p->elapsed_s, &err);
            r->last_checkpoint = ts_now_seconds();
        }
    }
    if (st) { /* the render cannot keep its promise of a checkpoint: stop it */
        r->ckpt_status = st;
        r->ckpt_err = err;
        ts_sched_job_cancel(job);
    }
}

static void on_done(void *user, ts_sched_job *job, const ts_job_progress *p)
{
    (void)job;
    render_run *r = user;
    pthread_mutex_lock(&r->mu);
    r->finished = true;
    r->final = *p;
    pthread_cond_signal(&r->cv);
    pthread_mutex_unlock(&r->mu);
    if (r->checkpoint) pthread_kill(r->main_thread, SIGUSR1); /* main waits in sigwait */
}

/* Waits for the job; with checkpoints, a SIGTERM/SIGINT meanwhile cancels it. Returns the
 * signal taken, or 0. */
static int wait_for_job(render_run *r, ts_sched_job *job, const sigset_t *sigs)
{
    int stop_signal = 0;
    if (!r->checkpoint) {
        pthread_mutex_lock(&r->mu);
        while (!r->finished) pthread_cond_wait(&r->cv, &r->mu);
        pthread_mutex_unlock(&r->mu);
        return 0;
    }
    for (;;) {
        int sig = 0;
        if (sigwait(sigs, &sig) != 0) continue;
        if (sig != SIGUSR1) {
            if (!stop_signal) stop_signal = sig;
            ts_sched_job_cancel(job);
        }
        pthread_mutex_lock(&r->mu);
        bool finished = r->finished;
        pthread_mutex_unlock(&r->mu);
        if (finished) return stop_signal;
    }
}

/* ---------------------------------------------------------------- output */

static ts_status write_outputs(const render_run *r, const ts_film *film, const cli_outputs *outputs, double error,
                               ts_error *err)
{
    ts_image img;
    ts_status st = ts_film_to_image(film, TS_FILM_IMAGE_STATS, &img, err);
    if (st) return st;
    ts_render_info info = {ts_job_name(r->scene), r->integrator, r->final.spp_done, true, r->scene->sampler.seed,
                           r->final.elapsed_s, error,        (double)r->final.nonfinite, NULL, film->scale};
    info.media = (r->scene->effects & TS_EFFECT_MEDIA) != 0;
    info.medium_steps = (double)r->final.medium_steps;
    info.walks_truncated = (double)r->final.walks_truncated;
    st = ts_image_set_render_info(&img, &info, err);
    if (!st) st = cli_outputs_write_image(outputs, &img, err);
    ts_image_fini(&img);
    return st;
}

/* ---------------------------------------------------------------- render */

/* Loads the scene and settles what to render: the settings (scene, then options), the
 * shard's sample range. Returns -1 to go ahead, else the exit status. */
static int prepare_render(const render_opts *o, ts_scene **scene_out, ts_job_settings *js, ts_sample_range *range,
                          char *shard_how, size_t shard_how_len, uint32_t *shard_i_out, uint32_t *shard_n_out)
{
    /* Which shard (docs/design.md §7): I/N given, or from the scheduler's environment. */
    uint32_t shard_i = 0, shard_n = 1;
    if (o->shard_text) {
        ts_error serr = {0};
        ts_status sst = strcmp(o->shard_text, "auto") == 0
                            ? ts_shard_auto(getenv("JOB_COMPLETION_INDEX"), getenv("SLURM_ARRAY_TASK_ID"),
                                            getenv("SLURM_ARRAY_TASK_COUNT"), getenv("SLURM_ARRAY_TASK_MIN"),
                                            (uint32_t)o->shard_count, &shard_i, &shard_n, shard_how, shard_how_len,
                                            &serr)
                            : ts_shard_parse(o->shard_text, &shard_i, &shard_n, &serr);
        if (sst) return usage_error("--shard: %s", serr.message);
        if (!shard_how[0]) snprintf(shard_how, shard_how_len, "shard %u/%u", shard_i, shard_n);
    }
    ts_error err = {0};
    ts_scene *scene = NULL;
    ts_scene_limits limits;
    ts_scene_limits_default(&limits);
    ts_status st = o->scene_path ? ts_scene_load_path(o->scene_path, &limits, cli_print_warning, NULL, &scene, &err)
                                 : ts_scene_load_builtin(&limits, &scene, &err);
    if (st) {
        cli_print_load_error(o->scene_path, err.message);
        return 1;
    }
    if (o->have_seed) scene->sampler.seed = (uint32_t)o->seed;
    ts_job_settings_from_scene(scene, js);
    if (o->spp) js->spp = (uint32_t)o->spp;
    if (o->time_limit) js->time_limit_s = o->time_limit;
    if (o->target_error) js->target_error = o->target_error;
    if (o->adaptive) js->adaptive = true;
    if (js->adaptive && adaptive_refusal(o)) {
        srv_usage_error("tessera render", NULL, "the scene's job.adaptive %s", adaptive_refusal(o));
        ts_scene_destroy(scene);
        return SRV_USAGE_EXIT;
    }
    if (shard_n > js->spp) {
        fprintf(stderr, "tessera: %u shards of a %u-spp render would leave some without samples; use at most %u shards\n",
                shard_n, js->spp, js->spp);
        ts_scene_destroy(scene);
        return 1;
    }
    *range = ts_shard_range(shard_i, shard_n, js->spp);
    *shard_i_out = shard_i, *shard_n_out = shard_n;
    if (!o->quiet) {
        char on[400], off[400];
        ts_effects_format(scene->effects, on, sizeof on);
        ts_effects_format(TS_EFFECTS_ALL & ~scene->effects, off, sizeof off);
        fprintf(stderr, "tessera: effects simulated: %s; skipped: %s\n", on, off);
    }
    *scene_out = scene;
    return -1;
}

/* The output when no -o is given: NAME.exr in the working folder (NAME.shard-I-of-N.exr
 * for a shard), NAME the scene's name with anything but letters, digits, '.', '_' and '-'
 * made '-', at most 100 characters ("render" when nothing is left). */
static void default_output(const char *scene_name, bool shard, uint32_t i, uint32_t n, char *out, size_t len)
{
    char name[101];
    size_t k = 0;
    for (const char *s = scene_name ? scene_name : ""; *s && k < sizeof name - 1; s++) {
        char ch = *s;
        bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '_' ||
                  ch == '-' || (ch == '.' && k > 0);
        name[k++] = ok ? ch : '-';
    }
    name[k] = '\0';
    if (!k) snprintf(name, sizeof name, "render");
    if (shard) snprintf(out, len, "%s.shard-%u-of-%u.exr", name, i, n);
    else snprintf(out, len, "%s.exr", name);
}

static ts_film *film_copy(const ts_film *f, ts_error *err)
{
    ts_film *c = ts_film_create(f->full_width, f->full_height, f->x0, f->y0, f->width, f->height, err);
    if (c) memcpy(c->pixels, f->pixels, (size_t)f->width * (size_t)f->height * sizeof *f->pixels);
    if (c) c->scale = f->scale;
    return c;
}

/* After the render: the last tiles reach the viewer if it is there (a few milliseconds;
 * at most 10 s for a slow one); an unreachable one costs a note and at most one connect
 * attempt (2 s). */
static void finish_display(render_run *r, const char *address, bool quiet)
{
    bool shown = srv_display_flush(r->display, 10);
    if (!shown && !quiet) fprintf(stderr, "tessera: display server %s: not reachable, the image was not shown there\n", address);
    srv_display_destroy(r->display);
    r->display = NULL;
}

static int cmd_render(int argc, char **argv)
{
    render_opts o;
    int rc = parse_render_options(argc, argv, &o);
    if (rc >= 0) return rc;
    ts_scene *scene = NULL;
    ts_job_settings js;
    ts_sample_range range;
    char shard_how[256] = "", default_out[160];
    uint32_t shard_i, shard_n;
    rc = prepare_render(&o, &scene, &js, &range, shard_how, sizeof shard_how, &shard_i, &shard_n);
    if (rc >= 0) return rc;
    if (o.outputs.n == 0) {
        default_output(ts_job_name(scene), o.shard_text != NULL, shard_i, shard_n, default_out, sizeof default_out);
        cli_outputs_add(&o.outputs, default_out);
        if (!o.quiet) fprintf(stderr, "tessera: no -o given: the image goes to %s\n", default_out);
    }
    /* Every output's folder, before any rendering: a file that cannot be made fails now. */
    ts_error oerr = {0};
    if (cli_outputs_open(&o.outputs, &oerr)) {
        fprintf(stderr, "tessera: %s\n", oerr.message);
        ts_scene_destroy(scene);
        return 1;
    }
    int n_threads = o.threads ? (int)o.threads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (n_threads < 1) n_threads = 1;

    render_run r = {0};
    r.scene = scene;
    r.integrator = ts_integrator_name(js.integrator);
    r.range = range;
    r.target_spp = js.spp;
    r.span = range.end - range.begin;
    r.checkpoint = o.checkpoint;
    r.checkpoint_interval = o.checkpoint_interval;
    /* A time limit stops a pass part-way (render/scheduler.h), leaving tiles one pass
     * apart; a shard must hold one sample range in every pixel, so it keeps the last
     * complete pass to write instead. */
    r.keep_complete = o.checkpoint || (o.shard_text && js.time_limit_s > 0);
    r.main_thread = pthread_self();
    pthread_mutex_init(&r.mu, NULL);
    pthread_cond_init(&r.cv, NULL);
    ts_tile_grid_size(scene->crop_x1 - scene->crop_x0, scene->crop_y1 - scene->crop_y0, &r.nx, &r.ny);

    ts_error err = {0};
    ts_status st = TS_OK;
    ts_scheduler *sched = NULL;
    ts_sched_job *job = NULL;
    ts_film *film = ts_film_create(scene->width, scene->height, scene->crop_x0, scene->crop_y0,
                                   scene->crop_x1 - scene->crop_x0, scene->crop_y1 - scene->crop_y0, &err);
    if (film) film->scale = scene->film_scale; /* the output factor (film.h) */
    r.tile_spp = calloc((size_t)r.nx * (size_t)r.ny, sizeof *r.tile_spp);
    if (!film || !r.tile_spp) {
        if (film) ts_error_set(&err, TS_ERR_NOMEM, "out of memory for the tile grid");
        goto fail;
    }
    uint32_t done = 0; /* of the range, [range.begin, range.begin + done) are in the film */
    if (o.checkpoint) {
        ts_shard_info info;
        ts_shard_info_init(&info, scene, film, r.integrator, NULL, 0, js.spp, 0);
        ts_film *resumed = NULL;
        uint32_t at = range.begin;
        if ((st = ts_shard_checkpoint_load(o.checkpoint, &info, range, &resumed, &at, &err))) goto fail;
        if (resumed) {
            ts_film_destroy(film);
            film = resumed;
            done = at - range.begin;
            if (!o.quiet)
                fprintf(stderr, "tessera: resuming from checkpoint %s: samples [%u,%u) of [%u,%u) already done\n",
                        o.checkpoint, range.begin, at, range.begin, range.end);
        }
    }
    if (r.keep_complete) {
        if (!(r.complete = film_copy(film, &err))) goto fail;
        r.complete_spp = done;
    }
    if (o.shard_text && !o.quiet)
        fprintf(stderr, "tessera: %s: samples [%u,%u) of %u\n", shard_how, range.begin, range.end, js.spp);
    for (int i = 0; i < r.nx * r.ny; i++) r.tile_spp[i] = done;
    r.bar = !o.quiet && isatty(STDERR_FILENO);
    r.t0 = r.last_checkpoint = ts_now_seconds();

    /* Taken by sigwait in wait_for_job; blocked before the render threads start, so they
     * inherit the mask and never run the default action. */
    sigset_t sigs;
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGUSR1);
    sigaddset(&sigs, SIGINT);
    sigaddset(&sigs, SIGTERM);
    if (o.checkpoint) pthread_sigmask(SIG_BLOCK, &sigs, NULL);
    if (!(sched = ts_scheduler_create(n_threads, 1, &err))) goto fail;
    if (o.display_server && !(r.display = srv_display_create(o.display_server, ts_job_name(scene), &err))) goto fail;
    if (scene->job.display_server && !o.display_server && !o.quiet)
        fprintf(stderr, "tessera: the scene's job.display_server is for tessera serve; tessera render streams to a "
                        "display server only with --display-server\n");
    ts_sched_job_desc d = {0};
    d.scene = scene;
    d.settings = js;
    d.settings.spp = r.span;
    d.sample_begin = range.begin;
    d.max_pass_s = o.checkpoint ? o.checkpoint_interval : 0;
    d.callbacks = (ts_job_callbacks){on_tile, on_pass, on_done, &r};
    d.film = film;
    d.tile_spp = r.tile_spp;
    if (!(job = ts_scheduler_submit(sched, &d, &err))) goto fail;
    scene = NULL, film = NULL; /* the job's now */
    int stop_signal = wait_for_job(&r, job, &sigs);
    if (r.bar) fprintf(stderr, "\n");
    if (r.display) finish_display(&r, o.display_server, o.quiet);
    if (r.ckpt_status) {
        err = r.ckpt_err;
        st = r.ckpt_status;
        goto fail;
    }
    if (!(film = ts_sched_job_film(job, r.tile_spp, &err))) goto fail;
    done = r.final.spp_done;
    bool uniform = true; /* every tile holds `done` samples per pixel */
    for (int i = 0; i < r.nx * r.ny; i++) uniform = uniform && r.tile_spp[i] == done;
    if (stop_signal) { /* stopped by SIGTERM/SIGINT: save, then exit as the signal would */
        const ts_film *keep = r.final.halt == TS_HALT_SPP ? film : r.complete;
        uint32_t keep_spp = r.final.halt == TS_HALT_SPP ? done : r.complete_spp;
        st = write_checkpoint(&r, keep, keep_spp, r.final.elapsed_s, &err);
        if (st) fprintf(stderr, "tessera: %s; could not save the checkpoint: %s\n", strsignal(stop_signal), err.message);
        else
            fprintf(stderr, "tessera: %s: saved samples [%u,%u) to checkpoint %s; run the same command to resume\n",
                    strsignal(stop_signal), range.begin, range.begin + keep_spp, o.checkpoint);
        rc = 128 + stop_signal;
        goto out;
    }
    if (o.shard_text && !uniform) { /* stopped part-way through a pass: the last whole one */
        ts_film_destroy(film);
        if (!(film = film_copy(r.complete, &err))) goto fail;
        done = r.complete_spp;
    }
    double error = ts_film_relative_error(film);
    if (o.shard_text) {
        ts_sample_range held = {range.begin, range.begin + done};
        ts_shard_info info;
        ts_shard_info_init(&info, r.scene, film, r.integrator, &held, done ? 1 : 0, js.spp, r.final.elapsed_s);
        st = cli_outputs_write_shard(&o.outputs, film, &info, &err);
    } else {
        st = write_outputs(&r, film, &o.outputs, error, &err);
    }
    if (!st) st = cli_outputs_commit(&o.outputs, &err);
    if (st) goto fail;
    if (o.checkpoint && done == r.span) unlink(o.checkpoint); /* finished: the outputs hold everything it did */
    if (!o.quiet) {
        char error_text[48] = "unavailable (fewer than 2 samples per pixel)";
        if (done >= 2) snprintf(error_text, sizeof error_text, "%.3g%%", 100 * error);
        double seconds = r.final.elapsed_s;
        double msps = seconds > 0 ? r.final.samples / seconds / 1e6 : 0;
        fprintf(stderr,
                "tessera: %s: %d×%d, %u spp (%s), %s integrator, %d thread%s, %.2f s, %.2f Msamples/s, "
                "error estimate %s, %llu non-finite samples dropped\n",
                ts_job_name(r.scene), film->width, film->height, done, ts_halt_reason_phrase(r.final.halt), r.integrator,
                n_threads, n_threads == 1 ? "" : "s", seconds, msps, error_text, (unsigned long long)r.final.nonfinite);
        if (r.scene->effects & TS_EFFECT_MEDIA)
            fprintf(stderr, "tessera: %s: media: %llu tracking steps, %llu walks cut short (a step or crossing bound)\n",
                    ts_job_name(r.scene), (unsigned long long)r.final.medium_steps,
                    (unsigned long long)r.final.walks_truncated);
        for (int i = 0; i < o.outputs.n; i++) fprintf(stderr, "tessera: wrote %s\n", o.outputs.path[i]);
    }
    rc = 0;
    goto out;
fail:
    fprintf(stderr, "tessera: %s\n", err.message);
    rc = 1;
out:
    cli_outputs_discard(&o.outputs); /* what was not committed: all the outputs or none */
    srv_display_destroy(r.display);
    ts_sched_job_release(job); /* the scene goes with the job, once the scheduler lets it go */
    ts_scheduler_destroy(sched);
    ts_film_destroy(film);
    ts_film_destroy(r.complete);
    ts_scene_destroy(scene);
    free(r.tile_spp);
    pthread_cond_destroy(&r.cv);
    pthread_mutex_destroy(&r.mu);
    return rc;
}

int cli_main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "render") == 0) return cmd_render(argc - 1, argv + 1);
    if (strcmp(cmd, "--version") == 0 || strcmp(cmd, "version") == 0) {
        printf("tessera %s\n", TS_VERSION);
        return 0;
    }
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        if (argc > 2 && strcmp(cmd, "help") == 0) { /* tessera help COMMAND: COMMAND --help */
            char *help_argv[] = {argv[2], "--help", NULL};
            if (!strcmp(argv[2], "render")) return cmd_render(2, help_argv);
            if (!strcmp(argv[2], "merge")) return cli_merge(2, help_argv);
            if (!strcmp(argv[2], "convert")) return cli_convert(2, help_argv);
            if (!strcmp(argv[2], "serve")) return srv_serve_main(2, help_argv);
            return usage_error("help: no command '%s'", argv[2]);
        }
        usage(stdout);
        return 0;
    }
    if (strcmp(cmd, "merge") == 0) return cli_merge(argc - 1, argv + 1);
    if (strcmp(cmd, "convert") == 0) return cli_convert(argc - 1, argv + 1);
    if (strcmp(cmd, "serve") == 0) {
        return srv_serve_main(argc - 1, argv + 1);
    }
    return usage_error("unknown command '%s'", cmd);
}
