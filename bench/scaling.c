/* scaling.c — where a 2-thread render's time goes, against a 1-thread one (bench/README.md,
 * "Thread scaling").
 *
 * bench_throughput's `scaling` column (samples/s at 2 threads ÷ at 1 thread, wall clock)
 * mixes what tessera does with what the machine gives it. This benchmark separates them.
 * It renders the scene (ts_render, the CLI's tile loop) at 1 and at 2 threads, alternating,
 * and for every worker thread records, at the end of each of its tiles (the on_tile
 * callback, on the worker itself), the kernel's per-thread scheduler statistics
 * (/proc/thread-self/schedstat: nanoseconds on a CPU and nanoseconds runnable but waiting
 * for one) and the time. A worker's life from the render's start to its last tile is then
 *   on CPU + waiting for a CPU (the machine's other load) + the rest (blocked: a lock, a
 *   page fault's I/O, a sleep — the part that would be tessera serialising),
 * and from its last tile to the render's end it is idle (the tile scheduler's end of pass:
 * nothing left to take). Reported per thread count, medians over repetitions:
 *   - CPU time per sample (user + system, the threads' own): 2 threads ÷ 1 thread above 1
 *     means the threads slow each other down (shared caches, false sharing, atomics,
 *     memory bandwidth); 1.00 means they do not;
 *   - the run-queue wait, blocked and end-of-pass idle shares of threads × wall time;
 *   - the machine's steal time (/proc/stat: the hypervisor running other guests);
 *   - busy: CPU ÷ (CPU + blocked + end-of-pass idle, the idle counted at the thread's CPU
 *     share of its life, as it would pass on a CPU of its own): 1 = a thread never lacks work;
 *   - the measured wall-clock scaling, and the scaling the code allows on free CPUs at equal
 *     CPU time per sample: threads × busy(N threads) ÷ busy(1 thread), at most N.
 * Pixels are not compared here: ts_render's output is thread-count independent by
 * construction (tests: render_threads), and this program only reads timings.
 *
 *   bench_scaling [--reps R] [--seconds S] [--threads N] SCENE.json...   (defaults 5, 3, 2)
 * Prints a markdown table. Not run by ctest; bench/run runs it on the Cornell box. */
#define _GNU_SOURCE /* gettid-free: /proc/thread-self */

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "film/film.h"
#include "render/render.h"
#include "scene/scene.h"
#include "json/scene_json.h"
#include "bench_util.h"

#define MAX_THREADS 16
#define MAX_REPS 50

/* What one worker of one render did, as of its last finished tile. */
typedef struct slot {
    double t_last;          /* monotonic seconds at its last tile's end */
    double cpu_s, wait_s;   /* schedstat: on a CPU, runnable and waiting */
    int tiles;
} slot;

typedef struct track {
    slot slots[MAX_THREADS];
    atomic_int n_slots;
} track;

static _Thread_local int my_slot = -1; /* a fresh worker thread starts at -1 */

static void read_schedstat(double *cpu_s, double *wait_s)
{
    unsigned long long run = 0, wait = 0;
    FILE *f = fopen("/proc/thread-self/schedstat", "r");
    if (f) {
        if (fscanf(f, "%llu %llu", &run, &wait) != 2) run = wait = 0;
        fclose(f);
    }
    *cpu_s = 1e-9 * (double)run;
    *wait_s = 1e-9 * (double)wait;
}

static void on_tile(void *user, int x, int y, int w, int h)
{
    (void)x, (void)y, (void)w, (void)h;
    track *tr = user;
    if (my_slot < 0) {
        my_slot = atomic_fetch_add(&tr->n_slots, 1);
        if (my_slot >= MAX_THREADS) my_slot = MAX_THREADS - 1;
    }
    slot *s = &tr->slots[my_slot]; /* written by this thread only; read after the join */
    read_schedstat(&s->cpu_s, &s->wait_s);
    s->t_last = clock_s(CLOCK_MONOTONIC);
    s->tiles++;
}

/* The machine's steal time so far (/proc/stat's 8th cpu field, in USER_HZ ticks), seconds. */
static double steal_s(void)
{
    FILE *f = fopen("/proc/stat", "r");
    if (!f) return 0;
    unsigned long long v[8] = {0};
    int n = fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                   &v[6], &v[7]);
    fclose(f);
    return n == 8 ? (double)v[7] / 100.0 : 0;
}

typedef struct run_result {
    double wall, samples, cpu, wait, blocked, idle, steal, rusage_cpu;
    double busy;    /* CPU ÷ (CPU + blocked + idle at the thread's CPU share): 1 = never without work */
} run_result;

static double rusage_cpu(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static int render(const ts_scene *s, uint32_t spp, int threads, run_result *out, ts_error *err)
{
    ts_film *film = ts_film_create(s->width, s->height, s->crop_x0, s->crop_y0, s->crop_x1 - s->crop_x0,
                                   s->crop_y1 - s->crop_y0, err);
    if (!film) return -1;
    track tr;
    memset(&tr, 0, sizeof tr);
    atomic_init(&tr.n_slots, 0);
    ts_render_request req = {.scene = s,
                             .integrator = s->integrator.type,
                             .film = film,
                             .sample_begin = 0,
                             .sample_end = spp,
                             .threads = threads,
                             .on_tile = on_tile,
                             .user = &tr};
    ts_render_stats stats = {0};
    double st0 = steal_s(), r0 = rusage_cpu(), t0 = clock_s(CLOCK_MONOTONIC);
    ts_status st = ts_render(&req, &stats, err);
    double t1 = clock_s(CLOCK_MONOTONIC), r1 = rusage_cpu(), st1 = steal_s();
    ts_film_destroy(film);
    if (st != TS_OK) return -1;
    memset(out, 0, sizeof *out);
    out->wall = t1 - t0;
    out->samples = (double)stats.counters.samples;
    out->steal = st1 - st0;
    out->rusage_cpu = r1 - r0;
    int n = atomic_load(&tr.n_slots);
    double proj_sum = 0;
    if (n > MAX_THREADS) n = MAX_THREADS;
    for (int i = 0; i < n; i++) {
        const slot *sl = &tr.slots[i];
        double life = sl->t_last - t0, idle = t1 - sl->t_last;
        double blocked = life - sl->cpu_s - sl->wait_s;
        out->cpu += sl->cpu_s;
        out->wait += sl->wait_s;
        out->blocked += blocked > 0 ? blocked : 0;
        out->idle += idle;
        /* On a CPU of its own the thread's wait would vanish; its idle tail is the other
         * thread's last tile, which on a free CPU takes that tile's CPU time: scale it by
         * the CPU share of the thread's life. */
        double share = life > 0 ? sl->cpu_s / life : 1;
        proj_sum += sl->cpu_s + (blocked > 0 ? blocked : 0) + idle * share;
    }
    out->busy = proj_sum > 0 ? out->cpu / proj_sum : 0;
    return 0;
}

static int bench_scene(const char *path, int reps, double seconds, int threads)
{
    ts_scene *s = NULL;
    ts_error err = {0};
    if (ts_scene_load_file(path, NULL, &s, &err) != TS_OK) {
        fprintf(stderr, "bench_scaling: %s: %s\n", path, err.message);
        return -1;
    }
    run_result cal;
    if (render(s, 1, 1, &cal, &err) != 0) goto fail;
    double want = ceil(seconds / fmax(cal.cpu > 0 ? cal.cpu : cal.wall, 1e-6));
    uint32_t spp = want < 1 ? 1 : (want > s->spp ? s->spp : (uint32_t)want);
    double m[2][10][MAX_REPS];
    for (int r = 0; r < reps; r++)
        for (int k = 0; k < 2; k++) {
            int c = (r & 1) ? 1 - k : k; /* alternate which thread count goes first */
            run_result rr;
            if (render(s, spp, c ? threads : 1, &rr, &err) != 0) goto fail;
            double tw = (c ? threads : 1) * rr.wall;
            m[c][0][r] = rr.wall;
            m[c][1][r] = 1e6 * rr.cpu / rr.samples; /* µs of CPU per sample */
            m[c][2][r] = rr.wait / tw;
            m[c][3][r] = rr.blocked / tw;
            m[c][4][r] = rr.idle / tw;
            m[c][5][r] = rr.steal / rr.wall; /* CPUs' worth of steal during the render */
            m[c][6][r] = rr.samples / rr.wall;
            m[c][7][r] = rr.busy;
            m[c][8][r] = 0;
            m[c][9][r] = rr.rusage_cpu / rr.cpu; /* the process's CPU ÷ the workers' (a check) */
        }
    /* per-repetition ratios */
    double scal[MAX_REPS], cpu_ratio[MAX_REPS], proj[MAX_REPS];
    for (int r = 0; r < reps; r++) {
        scal[r] = m[1][6][r] / m[0][6][r];
        cpu_ratio[r] = m[1][1][r] / m[0][1][r];
        proj[r] = threads * m[1][7][r] / m[0][7][r];
    }
    double med[2][10];
    for (int c = 0; c < 2; c++)
        for (int q = 0; q < 10; q++) med[c][q] = median(m[c][q], reps);
    const char *name = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    for (int c = 0; c < 2; c++)
        printf("| %s | %d | %u | %.2f | %.3g | %.2f | %.1f%% | %.2f%% | %.2f%% | %.2f | %.4f | | | %.3f |\n", name,
               c ? threads : 1, spp, med[c][0], med[c][6] / 1e3, med[c][1], 100 * med[c][2], 100 * med[c][3],
               100 * med[c][4], med[c][5], med[c][7], med[c][9]);
    double sc = median(scal, reps), cr = median(cpu_ratio, reps), pj = median(proj, reps);
    printf("| %s | **%d ÷ 1** | | | | **%.3f** | | | | | | **%.2f** | **%.3f** | |\n", name, threads, cr, sc, pj);
    fflush(stdout);
    ts_scene_destroy(s);
    return 0;
fail:
    fprintf(stderr, "bench_scaling: %s: %s\n", path, err.message);
    ts_scene_destroy(s);
    return -1;
}

int main(int argc, char **argv)
{
    int reps = 5, threads = 2, first = 1;
    double seconds = 3;
    for (; first < argc && argv[first][0] == '-'; first++) {
        if (!strcmp(argv[first], "--reps") && first + 1 < argc) reps = atoi(argv[++first]);
        else if (!strcmp(argv[first], "--seconds") && first + 1 < argc) seconds = atof(argv[++first]);
        else if (!strcmp(argv[first], "--threads") && first + 1 < argc) threads = atoi(argv[++first]);
        else break;
    }
    if (first >= argc || reps < 1 || reps > MAX_REPS || threads < 2 || threads > MAX_THREADS || !(seconds > 0)) {
        fprintf(stderr, "usage: %s [--reps 1..%d] [--seconds S] [--threads 2..%d] SCENE.json...\n", argv[0],
                MAX_REPS, MAX_THREADS);
        return 2;
    }
    printf("Medians of %d alternating repetitions; shares are of threads × wall time. CPU and run-queue wait "
           "per worker thread from /proc/thread-self/schedstat; steal from /proc/stat (CPUs' worth).\n\n",
           reps);
    printf("| scene | threads | spp | wall s | ksamples/s | CPU µs / sample | run-queue wait | blocked | "
           "end-of-pass idle | steal | busy | wall-clock scaling | scaling on free CPUs | process CPU ÷ workers' |\n");
    printf("|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
    int status = 0;
    for (int i = first; i < argc; i++)
        if (bench_scene(argv[i], reps, seconds, threads) != 0) status = 1;
    return status;
}
