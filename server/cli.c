/* cli.c — the command line of DESIGN.md §5b.
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
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "effects.h"
#include "exr.h"
#include "film.h"
#include "film_image.h"
#include "image.h"
#include "png_encode.h"
#include "render.h"
#include "scene.h"

#define MAX_OUTPUTS 8

static void usage(FILE *f)
{
    fprintf(f, "usage:\n"
               "  tessera render [SCENE] [-o OUT.exr] [-o OUT.png] [--spp N] [--threads N] [--seed N]\n"
               "                 [--time-limit SECONDS] [--target-error E] [--quiet]\n"
               "  tessera merge  SHARD.exr... [-o OUT.exr] [-o OUT.png]\n"
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

static const char *extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    return dot && (!slash || dot > slash) ? dot + 1 : "";
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

static ts_status write_outputs(const ts_scene *scene, const ts_film *film, char **outputs, int n_outputs,
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
    for (int i = 0; !st && i < n_outputs; i++) {
        const char *ext = extension(outputs[i]);
        if (strcasecmp(ext, "exr") == 0) st = ts_exr_write(outputs[i], &img, err);
        else st = ts_png_write(outputs[i], &img, 0.0f, err);
    }
    ts_image_fini(&img);
    return st;
}

static const char *integrator_name(ts_integrator_type t)
{
    switch (t) {
    case TS_INTEGRATOR_PATH: return "path";
    case TS_INTEGRATOR_DIRECT: return "direct";
    case TS_INTEGRATOR_AO: return "ao";
    case TS_INTEGRATOR_NORMALS: return "normals";
    }
    return "?";
}

/* ---------------------------------------------------------------- render */

static int cmd_render(int argc, char **argv)
{
    enum { OPT_SPP = 256, OPT_THREADS, OPT_SEED, OPT_TIME, OPT_TARGET, OPT_QUIET, OPT_HELP };
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'},    {"spp", required_argument, NULL, OPT_SPP},
        {"threads", required_argument, NULL, OPT_THREADS}, {"seed", required_argument, NULL, OPT_SEED},
        {"time-limit", required_argument, NULL, OPT_TIME}, {"target-error", required_argument, NULL, OPT_TARGET},
        {"quiet", no_argument, NULL, OPT_QUIET},     {"help", no_argument, NULL, OPT_HELP},
        {NULL, 0, NULL, 0}};
    char *outputs[MAX_OUTPUTS];
    int n_outputs = 0;
    unsigned long long spp = 0, threads = 0, seed = 0;
    bool have_seed = false, quiet = false;
    double time_limit = 0, target_error = 0;
    optind = 1;
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":o:", opts, NULL)) != -1) {
        switch (c) {
        case 'o':
            if (n_outputs == MAX_OUTPUTS) return usage_error("at most %s outputs", "8");
            outputs[n_outputs++] = optarg;
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
        case ':': return usage_error("option '%s' needs a value", argv[optind - 1]);
        default: return usage_error("unknown option '%s'", argv[optind - 1]);
        }
    }
    if (argc - optind > 1) return usage_error("render takes at most one scene file, got another: '%s'", argv[optind + 1]);
    const char *scene_path = optind < argc ? argv[optind] : NULL;
    for (int i = 0; i < n_outputs; i++) {
        const char *ext = extension(outputs[i]);
        if (strcasecmp(ext, "exr") != 0 && strcasecmp(ext, "png") != 0)
            return usage_error("-o %s: the extension must be .exr or .png", outputs[i]);
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
    int n_threads = threads ? (int)threads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (n_threads < 1) n_threads = 1;

    ts_integrator_type integ = scene->integrator.type;
    if (!ts_integrator_available(integ)) {
        fprintf(stderr, "tessera: note: the '%s' integrator is not implemented yet; rendering the 'ao' debugging view\n",
                integrator_name(integ));
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
    progress prog = {0};
    prog.enabled = !quiet && isatty(STDERR_FILENO);
    pthread_mutex_init(&prog.lock, NULL);
    prog.total = (uint64_t)film->width * (uint64_t)film->height * target_spp;
    prog.t0 = ts_now_seconds();

    ts_render_stats stats = {0};
    uint32_t done = 0, pass = 1;
    double error = 0;
    const char *stop_reason = "sample count reached";
    while (done < target_spp) {
        uint32_t n = pass < target_spp - done ? pass : target_spp - done;
        if (time_limit > 0 && done > 0) {
            double elapsed = ts_now_seconds() - prog.t0;
            double per_spp = stats.seconds / done;
            if (elapsed >= time_limit) {
                stop_reason = "time limit reached";
                break;
            }
            /* Shrink the pass to what fits in the time left (at least one sample). */
            double fit = (time_limit - elapsed) / (per_spp > 0 ? per_spp : 1e-9);
            if (fit < n) n = fit >= 1 ? (uint32_t)fit : 1;
        }
        prog.pass_spp = n;
        ts_render_request req = {scene, integ, film, done, done + n, n_threads, NULL, on_tile, &prog};
        st = ts_render(&req, &stats, &err);
        if (st) break;
        done += n;
        if (done > 1) pass = done; /* 1, 1, 2, 4, 8, ... */
        if (target_error > 0 && done >= 4) {
            error = ts_film_relative_error(film);
            if (error <= target_error) {
                stop_reason = "target error reached";
                break;
            }
        }
    }
    if (prog.enabled) fprintf(stderr, "\n");
    error = ts_film_relative_error(film);
    int rc = 0;
    if (st) {
        fprintf(stderr, "tessera: %s\n", err.message);
        rc = 1;
    } else {
        st = write_outputs(scene, film, outputs, n_outputs, &stats, done, error, integrator_name(integ), &err);
        if (st) {
            fprintf(stderr, "tessera: %s\n", err.message);
            rc = 1;
        }
    }
    if (!quiet && rc == 0) {
        double msps = stats.seconds > 0 ? stats.counters.samples / stats.seconds / 1e6 : 0;
        fprintf(stderr,
                "tessera: %s: %d×%d, %u spp (%s), %s integrator, %d threads, %.2f s, %.2f Msamples/s, "
                "error estimate %.3g%%, %llu non-finite samples dropped\n",
                scene->name, film->width, film->height, done, stop_reason, integrator_name(integ), n_threads,
                stats.seconds, msps, 100 * error, (unsigned long long)stats.counters.nonfinite);
        for (int i = 0; i < n_outputs; i++) fprintf(stderr, "tessera: wrote %s\n", outputs[i]);
    }
    pthread_mutex_destroy(&prog.lock);
    ts_film_destroy(film);
    ts_scene_destroy(scene);
    return rc;
}

int ts_cli_main(int argc, char **argv)
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
    if (strcmp(cmd, "serve") == 0 || strcmp(cmd, "merge") == 0) {
        fprintf(stderr, "tessera: '%s' is not available in this build yet\n", cmd);
        return 2;
    }
    return usage_error("unknown command '%s'", cmd);
}
