/* display.c — what streaming to a tev display server costs a render (server/display.h).
 *
 *   bench_display [--reps R] [--spp N] [--threads T]
 *
 * Renders the built-in Cornell box (512×512, path) through the scheduler R times with a
 * display attached and R times without, in pairs whose order alternates (with, without;
 * without, with; …) so load changes on a shared machine hit both alike. The viewer is a
 * thread of this process that reads every packet as tev would (length, then the payload)
 * and discards it. Prints, per pair, both wall times (submit to on_done) and their ratio,
 * then the medians. Wall time on a shared machine moves with other people's load, so it
 * also reports the process's CPU time per render (workers + the display's thread; the
 * viewer thread's own CPU time subtracted, as tev would be another process): on a machine
 * whose cores the workers fill, the display's extra CPU is what it takes from them. Both
 * are at the mercy of other processes; two figures are not: the display thread's own CPU
 * time as a fraction of the process's (srv_display_stats.thread_cpu_s; the display paces
 * itself to at most 2 % of one core), and the time the workers spent inside the display's
 * on_tile as a fraction of worker time (an empty callback timed the same way beside it).
 * Exit status 0, 1 when rendering fails, 2 on usage errors. */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "display.h"
#include "bench_util.h"

/* ---------------------------------------------------------------- a viewer that reads */
static atomic_bool g_stop;
static atomic_ullong g_bytes;
static atomic_ullong g_viewer_cpu_ns; /* CPU time of the viewer thread (not the renderer's) */
static atomic_int g_connections_done;

static void *viewer(void *arg)
{
    int lfd = *(int *)arg;
    static char buf[1 << 16];
    while (!atomic_load(&g_stop)) {
        struct pollfd p = {lfd, POLLIN, 0};
        if (poll(&p, 1, 50) != 1) continue;
        int fd = accept(lfd, NULL, NULL);
        if (fd < 0) continue;
        for (;;) {
            ssize_t r = recv(fd, buf, sizeof buf, 0);
            if (r <= 0) break;
            atomic_fetch_add(&g_bytes, (unsigned long long)r);
        }
        close(fd);
        atomic_store(&g_viewer_cpu_ns, (unsigned long long)(clock_s(CLOCK_THREAD_CPUTIME_ID) * 1e9));
        atomic_fetch_add(&g_connections_done, 1);
    }
    return NULL;
}

/* ---------------------------------------------------------------- rendering */
typedef struct run {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    bool done;
    srv_display *d;
    atomic_ullong callback_ns;
    atomic_ullong max_ns; /* the longest single call */
    atomic_ullong worker_cpu_ns; /* workers' CPU time from their first to their last tile */
} run;

static void on_tile(void *user, ts_sched_job *j, const ts_tile_event *ev)
{
    run *r = user;
    /* The workers' own CPU time, summed between consecutive tiles of this run per thread. */
    static _Thread_local const run *seen;
    static _Thread_local double last_cpu;
    double cpu = clock_s(CLOCK_THREAD_CPUTIME_ID);
    if (seen == r) atomic_fetch_add(&r->worker_cpu_ns, (unsigned long long)((cpu - last_cpu) * 1e9));
    seen = r, last_cpu = cpu;
    double t = clock_s(CLOCK_MONOTONIC);
    if (r->d) srv_display_tile(r->d, j, ev); /* without a display: the timing alone, as a baseline */
    unsigned long long ns = (unsigned long long)((clock_s(CLOCK_MONOTONIC) - t) * 1e9), m = atomic_load(&r->max_ns);
    atomic_fetch_add(&r->callback_ns, ns);
    while (ns > m && !atomic_compare_exchange_weak(&r->max_ns, &m, ns)) {}
}
static void on_done(void *user, ts_sched_job *j, const ts_job_progress *p)
{
    (void)j, (void)p;
    run *r = user;
    pthread_mutex_lock(&r->mu);
    r->done = true;
    pthread_cond_signal(&r->cv);
    pthread_mutex_unlock(&r->mu);
}

/* Wall seconds of one render; *cb_s the time spent in the display's on_tile, *cpu the
 * process's CPU seconds from submit to the display's end, less the viewer thread's. */
static double g_display_cpu; /* the last render's display thread CPU seconds */

static double render(ts_scheduler *s, const char *address, uint32_t spp, double *cb_s, double *cpu)
{
    g_display_cpu = 0;
    int conns = atomic_load(&g_connections_done);
    double viewer0 = (double)atomic_load(&g_viewer_cpu_ns) * 1e-9, cpu0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    ts_error err = {0};
    ts_scene *scene = NULL;
    if (ts_scene_load_builtin(NULL, &scene, &err)) {
        fprintf(stderr, "bench_display: %s\n", err.message);
        exit(1);
    }
    run r = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, false, NULL, 0, 0, 0};
    if (address && !(r.d = srv_display_create(address, "bench", &err))) {
        fprintf(stderr, "bench_display: %s\n", err.message);
        exit(1);
    }
    ts_sched_job_desc desc = {0};
    desc.scene = scene;
    desc.settings.integrator = TS_INTEGRATOR_PATH;
    desc.settings.spp = spp;
    desc.callbacks = (ts_job_callbacks){on_tile, NULL, on_done, &r};
    double t0 = clock_s(CLOCK_MONOTONIC);
    ts_sched_job *j = ts_scheduler_submit(s, &desc, &err);
    if (!j) {
        fprintf(stderr, "bench_display: %s\n", err.message);
        exit(1);
    }
    pthread_mutex_lock(&r.mu);
    while (!r.done) pthread_cond_wait(&r.cv, &r.mu);
    pthread_mutex_unlock(&r.mu);
    double t = clock_s(CLOCK_MONOTONIC) - t0;
    if (r.d) {
        if (!srv_display_flush(r.d, 30)) fprintf(stderr, "bench_display: the display did not drain\n");
        srv_display_stats st;
        srv_display_get_stats(r.d, &st);
        g_display_cpu = st.thread_cpu_s;
        if (getenv("BENCH_DISPLAY_VERBOSE")) fprintf(stderr, "  display thread CPU %.3f s, %llu tiles\n", st.thread_cpu_s, (unsigned long long)st.tiles_sent);
        srv_display_destroy(r.d);
        while (atomic_load(&g_connections_done) == conns) poll(NULL, 0, 5); /* the viewer saw EOF */
    }
    *cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - cpu0 - ((double)atomic_load(&g_viewer_cpu_ns) * 1e-9 - viewer0);
    ts_sched_job_release(j);
    *cb_s = (double)atomic_load(&r.callback_ns) * 1e-9;
    if (getenv("BENCH_DISPLAY_VERBOSE"))
        fprintf(stderr, "  %s: on_tile total %.3f ms, longest %.3f ms; workers' CPU %.3f s, process %.3f s\n",
                address ? "with" : "without", (double)atomic_load(&r.callback_ns) * 1e-6,
                (double)atomic_load(&r.max_ns) * 1e-6, (double)atomic_load(&r.worker_cpu_ns) * 1e-9, *cpu);
    return t;
}

int main(int argc, char **argv)
{
    int reps = 7, threads = 2;
    uint32_t spp = 16;
    for (int i = 1; i < argc; i++) {
        if (i + 1 < argc && strcmp(argv[i], "--reps") == 0) reps = atoi(argv[++i]);
        else if (i + 1 < argc && strcmp(argv[i], "--spp") == 0) spp = (uint32_t)atoi(argv[++i]);
        else if (i + 1 < argc && strcmp(argv[i], "--threads") == 0) threads = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_display [--reps R] [--spp N] [--threads T]\n");
            return 2;
        }
    }
    if (reps < 1 || reps > 1000 || spp < 1 || threads < 1) {
        fprintf(stderr, "bench_display: reps 1-1000, spp and threads positive\n");
        return 2;
    }
    int lfd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t n = sizeof a;
    if (lfd < 0 || bind(lfd, (struct sockaddr *)&a, sizeof a) || listen(lfd, 4) || getsockname(lfd, (struct sockaddr *)&a, &n)) {
        perror("bench_display: listen");
        return 1;
    }
    char address[64];
    snprintf(address, sizeof address, "127.0.0.1:%d", ntohs(a.sin_port));
    pthread_t vt;
    pthread_create(&vt, NULL, viewer, &lfd);
    ts_error err = {0};
    ts_scheduler *s = ts_scheduler_create(threads, 1, &err);
    if (!s) {
        fprintf(stderr, "bench_display: %s\n", err.message);
        return 1;
    }
    double cb, cpu, warm = render(s, NULL, 1, &cb, &cpu); /* warm-up: page in the scene, caches */
    (void)warm;
    double *cpu_ratio = calloc((size_t)reps, sizeof *cpu_ratio);
    double *cb_base = calloc((size_t)reps, sizeof *cb_base), *disp_frac = calloc((size_t)reps, sizeof *disp_frac);
    double *with = calloc((size_t)reps, sizeof *with), *without = calloc((size_t)reps, sizeof *without);
    double *ratio = calloc((size_t)reps, sizeof *ratio), *cb_frac = calloc((size_t)reps, sizeof *cb_frac);
    printf("pair,with_s,without_s,ratio,cpu_with_s,cpu_without_s,cpu_ratio,display_cpu_fraction,on_tile_fraction,"
           "empty_on_tile_fraction\n");
    for (int r = 0; r < reps; r++) {
        double cb_with = 0, cb_none = 0, cpu_with = 0, cpu_none = 0;
        if (r % 2 == 0) {
            with[r] = render(s, address, spp, &cb_with, &cpu_with);
            disp_frac[r] = g_display_cpu / cpu_with;
            without[r] = render(s, NULL, spp, &cb_none, &cpu_none);
        } else {
            without[r] = render(s, NULL, spp, &cb_none, &cpu_none);
            with[r] = render(s, address, spp, &cb_with, &cpu_with);
            disp_frac[r] = g_display_cpu / cpu_with;
        }
        ratio[r] = with[r] / without[r];
        cpu_ratio[r] = cpu_with / cpu_none;
        cb_frac[r] = cb_with / (with[r] * threads);
        cb_base[r] = cb_none / (without[r] * threads);
        printf("%d,%.3f,%.3f,%.4f,%.3f,%.3f,%.4f,%.4f,%.2e,%.2e\n", r, with[r], without[r], ratio[r], cpu_with, cpu_none,
               cpu_ratio[r], disp_frac[r], cb_frac[r], cb_base[r]);
        fflush(stdout);
    }
    printf("# %d pairs, %u spp, %d threads, 512x512 path: median with %.3f s, without %.3f s, "
           "median wall ratio %.4f (%+.2f%%); median CPU ratio (renderer + display thread, viewer excluded) %.4f "
           "(%+.2f%%); the display thread's CPU %.2f%% of the process's; on_tile time %.2e of worker time (an "
           "empty callback timed alike: %.2e); %.1f MiB streamed\n",
           reps, spp, threads, median(with, reps), median(without, reps), median(ratio, reps),
           100 * (median(ratio, reps) - 1), median(cpu_ratio, reps), 100 * (median(cpu_ratio, reps) - 1),
           100 * median(disp_frac, reps),
           median(cb_frac, reps), median(cb_base, reps), (double)atomic_load(&g_bytes) / (1 << 20));
    atomic_store(&g_stop, true);
    pthread_join(vt, NULL);
    close(lfd);
    ts_scheduler_destroy(s);
    free(with), free(without), free(ratio), free(cb_frac), free(cpu_ratio), free(cb_base), free(disp_frac);
    return 0;
}
