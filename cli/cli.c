/* cli.c — the command line of docs/design.md §5b.
 *
 * `tessera render` loads a scene (or the built-in Cornell box), renders it in progressive
 * passes of 1, 1, 2, 4, … samples per pixel until the sample count, the time limit or the
 * target error is reached, and writes every -o file (the extension picks the encoder).
 * Exit status: 0 success, 1 bad input or failed output, 2 usage error. Nothing is written
 * unless the render succeeded. */
#include "cli.h"

#include <getopt.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "merge.h"
#include "outputs.h"
#include "serve.h"
#include "tessera.h"


static void usage(FILE *f)
{
    fprintf(f, "usage:\n"
               "  tessera render [SCENE] [-o OUT.exr] [-o OUT.png] [--spp N] [--threads N] [--seed N]\n"
               "                 [--time-limit SECONDS] [--target-error E] [--quiet]\n"
               "                 [--shard I/N|auto [--shard-count N]] [--checkpoint FILE [--checkpoint-interval S]]\n"
               "  tessera merge  SHARD.exr... [-o OUT.exr] [-o OUT.png] [--allow-partial]\n"
               "  tessera serve  [--bind 127.0.0.1] [--port 8080] [--threads N] [--data DIR] [--token TOKEN]\n"
               "  tessera --version\n"
               "With no SCENE, `render` renders the built-in Cornell box.\n");
}

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "tessera: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    usage(stderr);
    return 2;
}

static bool parse_uint(const char *s, unsigned long long max, unsigned long long *out)
{
    char *end;
    if (!s[0] || s[0] == '-') return false;
    unsigned long long v = strtoull(s, &end, 10);
    if (*end || v > max) return false;
    *out = v;
    return true;
}

static bool parse_positive(const char *s, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (!s[0] || *end || !(v > 0) || !isfinite(v)) return false;
    *out = v;
    return true;
}

/* ---------------------------------------------------------------- progress */

typedef struct progress {
    bool enabled;
    pthread_mutex_t lock;   /* guards the fields below and stderr writes */
    uint64_t total, done;   /* pixel-samples */
    uint32_t pass_spp;
    int last_permille;
    double t0;
} progress;

static void on_tile(void *user, int x, int y, int w, int h)
{
    (void)x, (void)y;
    progress *p = user;
    pthread_mutex_lock(&p->lock);
    p->done += (uint64_t)w * (uint64_t)h * p->pass_spp;
    int permille = p->total ? (int)(1000 * p->done / p->total) : 1000;
    if (p->enabled && permille != p->last_permille) {
        p->last_permille = permille;
        int bars = permille * 30 / 1000;
        char bar[31];
        for (int i = 0; i < 30; i++) bar[i] = i < bars ? '#' : '.';
        bar[30] = '\0';
        fprintf(stderr, "\rrendering [%s] %5.1f%%  %.1f s ", bar, permille / 10.0, ts_now_seconds() - p->t0);
        fflush(stderr);
    }
    pthread_mutex_unlock(&p->lock);
}

/* ---------------------------------------------------------------- output */

static ts_status write_outputs(const ts_scene *scene, const ts_film *film, const cli_outputs *outputs,
                               const ts_render_stats *stats, uint32_t spp_done, double error, const char *integrator,
                               ts_error *err)
{
    ts_image img;
    ts_status st = ts_film_to_image(film, TS_FILM_IMAGE_STATS, &img, err);
    if (st) return st;
    char version[64];
    snprintf(version, sizeof version, "tessera %s", TS_VERSION);
    if (!st) st = ts_image_set_string(&img, "software", version, err);
    if (!st) st = ts_image_set_string(&img, "tessera_scene", scene->name, err);
    if (!st) st = ts_image_set_string(&img, "tessera_integrator", integrator, err);
    if (!st) st = ts_image_set_int(&img, "tessera_spp", (int32_t)spp_done, err);
    if (!st) st = ts_image_set_int(&img, "tessera_seed", (int32_t)scene->sampler.seed, err);
    if (!st) st = ts_image_set_double(&img, "tessera_render_time_s", stats->seconds, err);
    if (!st) st = ts_image_set_double(&img, "tessera_error_estimate", error, err);
    if (!st) st = ts_image_set_double(&img, "tessera_nonfinite_samples", (double)stats->counters.nonfinite, err);
    for (int i = 0; !st && i < outputs->n; i++) {
        if (cli_output_is_exr(outputs->path[i])) st = ts_exr_write(outputs->path[i], &img, err);
        else st = ts_png_write(outputs->path[i], &img, 0.0f, err);
    }
    ts_image_fini(&img);
    return st;
}

/* ---------------------------------------------------------------- farm shards

 * With --checkpoint, SIGTERM and SIGINT stop the render between tiles and the last
 * complete pass is saved before exiting (docs/design.md §7). A signal handler can reach only
 * process-wide state, so these two atomics are the one exception to "no global mutable
 * state": written by the handler, read by the render loop and the workers. */
static atomic_bool g_cancel;
static volatile sig_atomic_t g_signal;

static void on_stop_signal(int sig)
{
    g_signal = sig;
    atomic_store(&g_cancel, true);
}

static void catch_stop_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
}

/* ---------------------------------------------------------------- render */

static int cmd_render(int argc, char **argv)
{
    enum { OPT_SPP = 256, OPT_THREADS, OPT_SEED, OPT_TIME, OPT_TARGET, OPT_QUIET, OPT_HELP, OPT_SHARD, OPT_SHARD_COUNT,
           OPT_CHECKPOINT, OPT_CHECKPOINT_INTERVAL };
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'},    {"spp", required_argument, NULL, OPT_SPP},
        {"threads", required_argument, NULL, OPT_THREADS}, {"seed", required_argument, NULL, OPT_SEED},
        {"time-limit", required_argument, NULL, OPT_TIME}, {"target-error", required_argument, NULL, OPT_TARGET},
        {"quiet", no_argument, NULL, OPT_QUIET},     {"help", no_argument, NULL, OPT_HELP},
        {"shard", required_argument, NULL, OPT_SHARD}, {"shard-count", required_argument, NULL, OPT_SHARD_COUNT},
        {"checkpoint", required_argument, NULL, OPT_CHECKPOINT},
        {"checkpoint-interval", required_argument, NULL, OPT_CHECKPOINT_INTERVAL},
        {NULL, 0, NULL, 0}};
    cli_outputs outputs = {0};
    unsigned long long spp = 0, threads = 0, seed = 0;
    bool have_seed = false, quiet = false;
    double time_limit = 0, target_error = 0;
    const char *shard_text = NULL, *checkpoint = NULL;
    unsigned long long shard_count = 0;
    double checkpoint_interval = 60;
    optind = 1;
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":o:", opts, NULL)) != -1) {
        switch (c) {
        case 'o':
            if (!cli_outputs_add(&outputs, optarg)) return usage_error("at most %s outputs", "8");
            break;
        case OPT_SPP:
            if (!parse_uint(optarg, 1u << 24, &spp) || spp == 0)
                return usage_error("--spp: expected a whole number from 1 to 16777216, got '%s'", optarg);
            break;
        case OPT_THREADS:
            if (!parse_uint(optarg, 1024, &threads) || threads == 0)
                return usage_error("--threads: expected a whole number from 1 to 1024, got '%s'", optarg);
            break;
        case OPT_SEED:
            if (!parse_uint(optarg, UINT32_MAX, &seed))
                return usage_error("--seed: expected a whole number from 0 to 4294967295, got '%s'", optarg);
            have_seed = true;
            break;
        case OPT_TIME:
            if (!parse_positive(optarg, &time_limit))
                return usage_error("--time-limit: expected a positive number of seconds, got '%s'", optarg);
            break;
        case OPT_TARGET:
            if (!parse_positive(optarg, &target_error))
                return usage_error("--target-error: expected a positive relative error, got '%s'", optarg);
            break;
        case OPT_QUIET: quiet = true; break;
        case OPT_HELP: usage(stdout); return 0;
        case OPT_SHARD: shard_text = optarg; break;
        case OPT_SHARD_COUNT:
            if (!parse_uint(optarg, 1000000, &shard_count) || shard_count == 0)
                return usage_error("--shard-count: expected a whole number from 1 to 1000000, got '%s'", optarg);
            break;
        case OPT_CHECKPOINT: checkpoint = optarg; break;
        case OPT_CHECKPOINT_INTERVAL:
            if (!parse_positive(optarg, &checkpoint_interval))
                return usage_error("--checkpoint-interval: expected a positive number of seconds, got '%s'", optarg);
            break;
        case ':': return usage_error("option '%s' needs a value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
    if (argc - optind > 1) return usage_error("render takes at most one scene file, got another: '%s'", argv[optind + 1]);
    const char *scene_path = optind < argc ? argv[optind] : NULL;
    const char *unsupported = cli_outputs_unsupported(&outputs);
    if (unsupported) return usage_error("-o %s: the extension must be .exr or .png", unsupported);
    if (shard_count && !shard_text) return usage_error("%s", "--shard-count goes with --shard auto");
    if (checkpoint && !cli_output_is_exr(checkpoint))
        return usage_error("--checkpoint %s: the checkpoint is an EXR file; give it the .exr extension", checkpoint);

    /* Which shard (docs/design.md §7): I/N given, or from the scheduler's environment. */
    uint32_t shard_i = 0, shard_n = 1;
    char shard_how[256] = "";
    if (shard_text) {
        ts_error serr = {0};
        ts_status sst = strcmp(shard_text, "auto") == 0
                            ? ts_shard_auto(getenv("JOB_COMPLETION_INDEX"), getenv("SLURM_ARRAY_TASK_ID"),
                                            getenv("SLURM_ARRAY_TASK_COUNT"), getenv("SLURM_ARRAY_TASK_MIN"),
                                            (uint32_t)shard_count, &shard_i, &shard_n, shard_how, sizeof shard_how, &serr)
                            : ts_shard_parse(shard_text, &shard_i, &shard_n, &serr);
        if (sst) return usage_error("--shard: %s", serr.message);
        if (!shard_how[0]) snprintf(shard_how, sizeof shard_how, "shard %u/%u", shard_i, shard_n);
    }

    ts_error err = {0};
    ts_scene *scene = NULL;
    ts_scene_limits limits;
    ts_scene_limits_default(&limits);
    ts_status st = scene_path ? ts_scene_load_file(scene_path, &limits, &scene, &err)
                              : ts_scene_load_builtin(&limits, &scene, &err);
    if (st) {
        fprintf(stderr, "tessera: %s%s%s\n", scene_path ? scene_path : "", scene_path ? ": " : "", err.message);
        return 1;
    }
    if (have_seed) scene->sampler.seed = (uint32_t)seed;
    uint32_t target_spp = spp ? (uint32_t)spp : (scene->job.spp ? scene->job.spp : scene->spp);
    if (!time_limit) time_limit = scene->job.time_limit_s;
    if (!target_error) target_error = scene->job.target_error;
    if (shard_n > target_spp) {
        fprintf(stderr, "tessera: %u shards of a %u-spp render would leave some without samples; use at most %u shards\n",
                shard_n, target_spp, target_spp);
        ts_scene_destroy(scene);
        return 1;
    }
    ts_sample_range range = ts_shard_range(shard_i, shard_n, target_spp);
    int n_threads = threads ? (int)threads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (n_threads < 1) n_threads = 1;

    ts_integrator_type integ = scene->integrator.type;
    if (!ts_integrator_available(integ)) {
        fprintf(stderr, "tessera: note: the '%s' integrator is not implemented yet; rendering the 'ao' debugging view\n",
                ts_integrator_name(integ));
        integ = TS_INTEGRATOR_AO;
    }

    if (!quiet) {
        char on[400], off[400];
        ts_effects_format(scene->effects, on, sizeof on);
        ts_effects_format(TS_EFFECTS_ALL & ~scene->effects, off, sizeof off);
        fprintf(stderr, "tessera: effects simulated: %s; skipped: %s\n", on, off);
    }

    ts_film *film = ts_film_create(scene->width, scene->height, scene->crop_x0, scene->crop_y0,
                                   scene->crop_x1 - scene->crop_x0, scene->crop_y1 - scene->crop_y0, &err);
    if (!film) {
        fprintf(stderr, "tessera: %s\n", err.message);
        ts_scene_destroy(scene);
        return 1;
    }
    uint32_t span = range.end - range.begin; /* samples per pixel this process must hold */
    uint32_t done = 0;                        /* of them, [range.begin, range.begin + done) are in the film */
    ts_shard_info info;
    if (checkpoint) {
        ts_shard_info_init(&info, scene, film, ts_integrator_name(integ), NULL, 0, target_spp, 0);
        ts_film *resumed = NULL;
        uint32_t at = range.begin;
        st = ts_shard_checkpoint_load(checkpoint, &info, range, &resumed, &at, &err);
        if (st) {
            fprintf(stderr, "tessera: %s\n", err.message);
            ts_film_destroy(film);
            ts_scene_destroy(scene);
            return 1;
        }
        if (resumed) {
            ts_film_destroy(film);
            film = resumed;
            done = at - range.begin;
            if (!quiet)
                fprintf(stderr, "tessera: resuming from checkpoint %s: samples [%u,%u) of [%u,%u) already done\n",
                        checkpoint, range.begin, at, range.begin, range.end);
        }
    }
    if (shard_text && !quiet)
        fprintf(stderr, "tessera: %s: samples [%u,%u) of %u\n", shard_how, range.begin, range.end, target_spp);
    /* With a checkpoint, each pass starts from a copy of the film so a signal mid-pass can
     * save the last complete state. */
    ts_film *snapshot = NULL;
    if (checkpoint) {
        snapshot = ts_film_create(film->full_width, film->full_height, film->x0, film->y0, film->width, film->height, &err);
        if (!snapshot) {
            fprintf(stderr, "tessera: %s\n", err.message);
            ts_film_destroy(film);
            ts_scene_destroy(scene);
            return 1;
        }
        catch_stop_signals();
    }
    progress prog = {0};
    prog.enabled = !quiet && isatty(STDERR_FILENO);
    pthread_mutex_init(&prog.lock, NULL);
    prog.total = (uint64_t)film->width * (uint64_t)film->height * (span - done);
    prog.t0 = ts_now_seconds();

    ts_render_stats stats = {0};
    uint32_t done0 = done, pass = done > 1 ? done : 1;
    double error = 0, last_checkpoint = prog.t0;
    const char *stop_reason = "sample count reached";
    while (done < span && !g_signal) {
        uint32_t n = pass < span - done ? pass : span - done;
        uint32_t here = done - done0; /* rendered by this process */
        double per_spp = here ? stats.seconds / here : 0;
        if (time_limit > 0 && here > 0) {
            double elapsed = ts_now_seconds() - prog.t0;
            if (elapsed >= time_limit) {
                stop_reason = "time limit reached";
                break;
            }
            /* Shrink the pass to what fits in the time left (at least one sample). */
            double fit = (time_limit - elapsed) / (per_spp > 0 ? per_spp : 1e-9);
            if (fit < n) n = fit >= 1 ? (uint32_t)fit : 1;
        }
        if (checkpoint && per_spp > 0) { /* a pass fits in one checkpoint interval */
            double fit = checkpoint_interval / per_spp;
            if (fit < n) n = fit >= 1 ? (uint32_t)fit : 1;
        }
        if (snapshot) memcpy(snapshot->pixels, film->pixels, (size_t)film->width * film->height * sizeof *film->pixels);
        prog.pass_spp = n;
        ts_render_request req = {scene, integ, film, range.begin + done, range.begin + done + n, n_threads,
                                 checkpoint ? &g_cancel : NULL, on_tile, &prog};
        st = ts_render(&req, &stats, &err);
        if (st) break;
        if (stats.cancelled) { /* part of the pass is in the film: go back to its start */
            ts_film *t = film;
            film = snapshot, snapshot = t;
            break;
        }
        done += n;
        if (done > 1) pass = done; /* 1, 1, 2, 4, 8, ... */
        if (target_error > 0 && done >= 4) {
            error = ts_film_relative_error(film);
            if (error <= target_error) {
                stop_reason = "target error reached";
                break;
            }
        }
        if (checkpoint && done < span && ts_now_seconds() - last_checkpoint >= checkpoint_interval) {
            ts_sample_range held = {range.begin, range.begin + done};
            ts_shard_info_init(&info, scene, film, ts_integrator_name(integ), &held, 1, target_spp, stats.seconds);
            st = ts_shard_write(checkpoint, film, &info, &err);
            if (st) break;
            last_checkpoint = ts_now_seconds();
        }
    }
    if (prog.enabled) fprintf(stderr, "\n");
    if (!st && g_signal) { /* stopped by SIGTERM/SIGINT: save, then exit as the signal would */
        ts_sample_range held = {range.begin, range.begin + done};
        ts_shard_info_init(&info, scene, film, ts_integrator_name(integ), &held, done ? 1 : 0, target_spp, stats.seconds);
        st = ts_shard_write(checkpoint, film, &info, &err);
        int sig = g_signal;
        if (st) fprintf(stderr, "tessera: %s; could not save the checkpoint: %s\n", strsignal(sig), err.message);
        else
            fprintf(stderr, "tessera: %s: saved samples [%u,%u) to checkpoint %s; run the same command to resume\n",
                    strsignal(sig), range.begin, range.begin + done, checkpoint);
        pthread_mutex_destroy(&prog.lock);
        ts_film_destroy(snapshot);
        ts_film_destroy(film);
        ts_scene_destroy(scene);
        return 128 + sig;
    }
    ts_film_destroy(snapshot);
    error = ts_film_relative_error(film);
    int rc = 0;
    if (st) {
        fprintf(stderr, "tessera: %s\n", err.message);
        rc = 1;
    } else {
        if (shard_text) {
            ts_sample_range held = {range.begin, range.begin + done};
            ts_shard_info_init(&info, scene, film, ts_integrator_name(integ), &held, done ? 1 : 0, target_spp,
                               stats.seconds);
            st = cli_outputs_write_shard(&outputs, film, &info, &err);
        } else {
            st = write_outputs(scene, film, &outputs, &stats, done, error, ts_integrator_name(integ), &err);
        }
        if (st) {
            fprintf(stderr, "tessera: %s\n", err.message);
            rc = 1;
        } else if (checkpoint && done == span) {
            unlink(checkpoint); /* finished: the outputs hold everything the checkpoint did */
        }
    }
    if (!quiet && rc == 0) {
        double msps = stats.seconds > 0 ? stats.counters.samples / stats.seconds / 1e6 : 0;
        fprintf(stderr,
                "tessera: %s: %d×%d, %u spp (%s), %s integrator, %d threads, %.2f s, %.2f Msamples/s, "
                "error estimate %.3g%%, %llu non-finite samples dropped\n",
                scene->name, film->width, film->height, done, stop_reason, ts_integrator_name(integ), n_threads,
                stats.seconds, msps, 100 * error, (unsigned long long)stats.counters.nonfinite);
        for (int i = 0; i < outputs.n; i++) fprintf(stderr, "tessera: wrote %s\n", outputs.path[i]);
    }
    pthread_mutex_destroy(&prog.lock);
    ts_film_destroy(film);
    ts_scene_destroy(scene);
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
        usage(stdout);
        return 0;
    }
    if (strcmp(cmd, "merge") == 0) return cli_merge(argc - 1, argv + 1);
    if (strcmp(cmd, "serve") == 0) {
        return srv_serve_main(argc - 1, argv + 1);
    }
    return usage_error("unknown command '%s'", cmd);
}
