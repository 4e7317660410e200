/* bench/effects.c — what simulating only the effects a scene calls for saves
 * (docs/design.md §8).
 *
 * For each scene given, renders the same samples alternately with the specialisation off
 * (`generic`: every effect simulated) and on, REPS times side by side, checks that the
 * two films are bit-identical, and prints one markdown row: the effects simulated and
 * skipped, the median wall seconds of each, and the per-repetition ratios
 * specialised/generic (below 1 = time saved) of three measures: wall time, CPU time of
 * the process (user + system, every render thread; less disturbed than wall time by
 * other work on a shared machine) and instructions retired in user space (hardware
 * counter through perf_event_open, inherited by the render threads; nearly free of
 * noise, "n/a" where the kernel refuses counters). Each ratio is the median over the
 * repetitions with its interquartile range. Ratios, not absolute times, are what mean
 * something on a shared machine.
 *
 * Where the processor's counters are out of reach (virtual machines), bench/run counts
 * instructions with valgrind instead: `--only generic|specialised` renders each scene
 * once in that mode, nothing else, under callgrind collecting inside ts_render_tile.
 *
 *   bench_effects [--spp N] [--reps N] [--threads N] [--width W] [--only MODE] SCENE.json...  */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <linux/perf_event.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>

#include "integrators/effects.h"
#include "render/render.h"
#include "json/scene_json.h"
#include "bench_util.h"

/* Quartiles of v (sorted in place): q[0] = 25 %, q[1] = median, q[2] = 75 %. */
static void quartiles(double *v, int n, double q[3])
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    for (int k = 0; k < 3; k++) {
        double x = (k + 1) * 0.25 * (n - 1);
        int i = (int)x;
        double f = x - i;
        q[k] = i + 1 < n ? v[i] * (1 - f) + v[i + 1] * f : v[i];
    }
}

/* User-space instructions of this process and of the threads it starts from now on; -1
 * when the kernel refuses (perf_event_paranoid, no PMU in a virtual machine). */
static int open_instruction_counter(void)
{
    struct perf_event_attr a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.type = PERF_TYPE_HARDWARE;
    a.config = PERF_COUNT_HW_INSTRUCTIONS;
    a.exclude_kernel = 1;
    a.exclude_hv = 1;
    a.inherit = 1;
    return (int)syscall(SYS_perf_event_open, &a, 0, -1, -1, 0);
}

static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

typedef struct measure {
    double wall, cpu, instructions; /* instructions < 0: not counted */
} measure;

static measure render_once(const ts_scene *s, ts_film *f, uint32_t spp, int threads, bool generic, int counter)
{
    ts_film_clear(f);
    ts_render_stats stats = {0};
    ts_error err = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, spp, threads, NULL, NULL, NULL, generic};
    uint64_t i0 = 0, i1 = 0;
    /* The render's threads have exited when ts_render returns, so their counts have been
     * folded into the inherited counter. */
    if (counter >= 0 && read(counter, &i0, sizeof i0) != sizeof i0) counter = -1;
    double c0 = cpu_seconds();
    if (ts_render(&req, &stats, &err)) {
        fprintf(stderr, "bench_effects: %s\n", err.message);
        exit(1);
    }
    measure m = {stats.seconds, cpu_seconds() - c0, -1};
    if (counter >= 0 && read(counter, &i1, sizeof i1) == sizeof i1) m.instructions = (double)(i1 - i0);
    return m;
}

/* Loads a scene and makes a film of it at most `width` pixels wide, of the same aspect (a
 * smaller film keeps the run short); exits with a message on failure. */
static ts_scene *load_scene(const char *path, int width, ts_film **f)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_file(path, NULL, &s, &err)) {
        fprintf(stderr, "bench_effects: %s: %s\n", path, err.message);
        exit(1);
    }
    int w = width < s->width ? width : s->width, h = (int)((double)s->height * w / s->width + 0.5);
    if (!(*f = ts_film_create(s->width, s->height, 0, 0, w, h, &err))) {
        fprintf(stderr, "bench_effects: %s\n", err.message);
        exit(1);
    }
    return s;
}

int main(int argc, char **argv)
{
    int spp = 8, reps = 9, threads = (int)sysconf(_SC_NPROCESSORS_ONLN), width = 256;
    int i = 1, only = -1; /* -1: both, side by side; 0: specialised only; 1: generic only */
    for (; i < argc && argv[i][0] == '-'; i += 2) {
        if (i + 1 >= argc) break;
        if (strcmp(argv[i], "--only") == 0) {
            if (strcmp(argv[i + 1], "generic") == 0) only = 1;
            else if (strcmp(argv[i + 1], "specialised") == 0) only = 0;
            else {
                fprintf(stderr, "bench_effects: --only: expected generic or specialised, got '%s'\n", argv[i + 1]);
                return 2;
            }
            continue;
        }
        int v = atoi(argv[i + 1]);
        if (v < 1) {
            fprintf(stderr, "bench_effects: %s needs a positive number\n", argv[i]);
            return 2;
        }
        if (strcmp(argv[i], "--spp") == 0) spp = v;
        else if (strcmp(argv[i], "--reps") == 0) reps = v;
        else if (strcmp(argv[i], "--threads") == 0) threads = v;
        else if (strcmp(argv[i], "--width") == 0) width = v;
        else {
            fprintf(stderr, "bench_effects: unknown option %s\n", argv[i]);
            return 2;
        }
    }
    if (i >= argc) {
        fprintf(stderr, "usage: bench_effects [--spp N] [--reps N] [--threads N] [--width W] [--only MODE] "
                        "SCENE.json...\n");
        return 2;
    }
    if (only >= 0) {
        for (; i < argc; i++) {
            ts_film *f;
            ts_scene *s = load_scene(argv[i], width, &f);
            measure m = render_once(s, f, (uint32_t)spp, threads, only == 1, -1);
            printf("%s %s %.3f s\n", s->name, only ? "generic" : "specialised", m.wall);
            ts_film_destroy(f);
            ts_scene_destroy(s);
        }
        return 0;
    }
    int counter = open_instruction_counter();
    if (counter >= 0) ioctl(counter, PERF_EVENT_IOC_ENABLE, 0);
    printf("Specialised ÷ generic, median over %d repetitions [interquartile range]; below 1 = saved.\n\n", reps);
    printf("| scene | effects simulated | skipped | spp | generic s | specialised s | wall time | CPU time | "
           "instructions |\n");
    printf("|---|---|---|--:|--:|--:|--:|--:|--:|\n");
    for (; i < argc; i++) {
        ts_film *a, *b;
        ts_scene *s = load_scene(argv[i], width, &a);
        ts_error err = {0};
        int w = a->width, h = a->height;
        b = ts_film_create(s->width, s->height, 0, 0, w, h, &err);
        double *tg = calloc((size_t)reps, sizeof *tg), *ts = calloc((size_t)reps, sizeof *ts),
               *ratio = calloc(3 * (size_t)reps, sizeof *ratio);
        if (!a || !b || !tg || !ts || !ratio) {
            fprintf(stderr, "bench_effects: out of memory\n");
            return 1;
        }
        render_once(s, a, 1, threads, false, -1); /* warm-up: page in the scene */
        bool counted = counter >= 0;
        for (int r = 0; r < reps; r++) {
            /* Alternate which goes first so drift in the machine's load cancels. */
            measure g, sp;
            if (r % 2 == 0) {
                g = render_once(s, a, (uint32_t)spp, threads, true, counter);
                sp = render_once(s, b, (uint32_t)spp, threads, false, counter);
            } else {
                sp = render_once(s, b, (uint32_t)spp, threads, false, counter);
                g = render_once(s, a, (uint32_t)spp, threads, true, counter);
            }
            tg[r] = g.wall;
            ts[r] = sp.wall;
            ratio[r] = sp.wall / g.wall;
            ratio[reps + r] = sp.cpu / g.cpu;
            ratio[2 * reps + r] = sp.instructions / g.instructions;
            if (!(g.instructions > 0 && sp.instructions > 0)) counted = false;
            if (memcmp(a->pixels, b->pixels, sizeof *a->pixels * (size_t)w * h) != 0) {
                fprintf(stderr, "bench_effects: %s: the specialised render differs from the generic one\n", argv[i]);
                return 1;
            }
        }
        char on[300], off[300];
        ts_effects_format(s->effects, on, sizeof on);
        ts_effects_format(TS_EFFECTS_ALL & ~s->effects, off, sizeof off);
        double q[3][3];
        for (int k = 0; k < 3; k++) quartiles(ratio + k * reps, reps, q[k]);
        char ins[64] = "n/a";
        if (counted) snprintf(ins, sizeof ins, "%.4f [%.4f, %.4f]", q[2][1], q[2][0], q[2][2]);
        printf("| %s | %s | %s | %d | %.3f | %.3f | %.3f [%.3f, %.3f] | %.3f [%.3f, %.3f] | %s |\n", s->name, on,
               off, spp, median(tg, reps), median(ts, reps), q[0][1], q[0][0], q[0][2], q[1][1], q[1][0], q[1][2],
               ins);
        fflush(stdout);
        free(tg), free(ts), free(ratio);
        ts_film_destroy(a), ts_film_destroy(b);
        ts_scene_destroy(s);
    }
    return 0;
}
