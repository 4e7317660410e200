/* bench/effects.c — what simulating only the effects a scene calls for saves (issue 5).
 *
 * For each scene given, renders the same samples alternately with the specialisation off
 * (`generic`: every effect simulated) and on, REPS times side by side, checks that the
 * two films are bit-identical, and prints one markdown row: the effects simulated and
 * skipped, the median seconds of each, and the median of the per-repetition ratios
 * specialised/generic (below 1 = time saved). Ratios, not absolute times, are what
 * mean something on a shared machine.
 *
 *   bench_effects [--spp N] [--reps N] [--threads N] [--width W] SCENE.json...  */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "effects.h"
#include "render.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static double render_once(const ts_scene *s, ts_film *f, uint32_t spp, int threads, bool generic)
{
    ts_film_clear(f);
    ts_render_stats stats = {0};
    ts_error err = {0};
    ts_render_request req = {s, s->integrator.type, f, 0, spp, threads, NULL, NULL, NULL, generic};
    if (ts_render(&req, &stats, &err)) {
        fprintf(stderr, "bench_effects: %s\n", err.message);
        exit(1);
    }
    return stats.seconds;
}

int main(int argc, char **argv)
{
    int spp = 8, reps = 5, threads = (int)sysconf(_SC_NPROCESSORS_ONLN), width = 256;
    int i = 1;
    for (; i < argc && argv[i][0] == '-'; i += 2) {
        if (i + 1 >= argc) break;
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
        fprintf(stderr, "usage: bench_effects [--spp N] [--reps N] [--threads N] [--width W] SCENE.json...\n");
        return 2;
    }
    printf("| scene | effects simulated | skipped | spp | generic s | specialised s | specialised ÷ generic |\n");
    printf("|---|---|---|--:|--:|--:|--:|\n");
    for (; i < argc; i++) {
        ts_scene *s = NULL;
        ts_error err = {0};
        if (ts_scene_load_file(argv[i], NULL, &s, &err)) {
            fprintf(stderr, "bench_effects: %s: %s\n", argv[i], err.message);
            return 1;
        }
        /* A smaller film of the same aspect keeps the run short. */
        int w = width < s->width ? width : s->width, h = (int)((double)s->height * w / s->width + 0.5);
        ts_film *a = ts_film_create(s->width, s->height, 0, 0, w, h, &err);
        ts_film *b = ts_film_create(s->width, s->height, 0, 0, w, h, &err);
        double *tg = calloc((size_t)reps, sizeof *tg), *ts = calloc((size_t)reps, sizeof *ts),
               *ratio = calloc((size_t)reps, sizeof *ratio);
        if (!a || !b || !tg || !ts || !ratio) {
            fprintf(stderr, "bench_effects: out of memory\n");
            return 1;
        }
        render_once(s, a, 1, threads, false); /* warm-up: page in the scene */
        for (int r = 0; r < reps; r++) {
            /* Alternate which goes first so drift in the machine's load cancels. */
            if (r % 2 == 0) {
                tg[r] = render_once(s, a, (uint32_t)spp, threads, true);
                ts[r] = render_once(s, b, (uint32_t)spp, threads, false);
            } else {
                ts[r] = render_once(s, b, (uint32_t)spp, threads, false);
                tg[r] = render_once(s, a, (uint32_t)spp, threads, true);
            }
            ratio[r] = ts[r] / tg[r];
            if (memcmp(a->pixels, b->pixels, sizeof *a->pixels * (size_t)w * h) != 0) {
                fprintf(stderr, "bench_effects: %s: the specialised render differs from the generic one\n", argv[i]);
                return 1;
            }
        }
        char on[300], off[300];
        ts_effects_format(s->effects, on, sizeof on);
        ts_effects_format(TS_EFFECTS_ALL & ~s->effects, off, sizeof off);
        double r_med = median(ratio, reps);
        printf("| %s | %s | %s | %d | %.3f | %.3f | %.3f |\n", s->name, on, off, spp, median(tg, reps),
               median(ts, reps), r_med);
        fflush(stdout);
        free(tg), free(ts), free(ratio);
        ts_film_destroy(a), ts_film_destroy(b);
        ts_scene_destroy(s);
    }
    return 0;
}
