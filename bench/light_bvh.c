/* light_bvh.c — light selection at equal time: power, spatial and the light hierarchy (bvh)
 * on scenes of many lights (bench/README.md, "Many lights").
 *
 * The scene (made here, seeded): a corridor 46 units long (floor and side walls, diffuse)
 * seen from one end, under a ceiling of N_TRI small emitting triangles (one-sided, facing
 * down, their radiance spread over two decades) and N_SPH small emitting spheres scattered
 * all along it, plus a diffuse panel and sphere near the camera; path tracing, max_depth 2 (direct light and one bounce: the selection's share of the
 * variance is largest there), 2 threads, a 96×96 film. For each selection K independent
 * renders (sampler seeds 1…K) at SPP samples per pixel, the selections alternating within a
 * repetition so that the machine's load falls on all alike; per mode:
 *   - relative variance of one render: per pixel the sample variance of the K renders'
 *     values (independent estimates: no correlation between seeds) over the squared mean,
 *     averaged over the pixels without the 1% largest (those that see a small emitter
 *     directly: no light selection changes their variance);
 *   - render CPU time (the process's user + system during the renders) and the scene's
 *     load time (the hierarchy's build included);
 *   - efficiency = 1 / (variance × CPU time), and its ratio to power selection's.
 * The image means of the modes are printed too: they estimate the same integral and must
 * agree within their standard errors.
 *
 *   bench_light_bvh [--tris N] [--spheres N] [--spp N] [--renders K] [--threads T]
 *                   (defaults 1000, 200, 16, 6, 2)
 * Prints a markdown table. Not run by ctest; bench/run runs it. */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "film/film.h"
#include "json/scene_json.h"
#include "render/render.h"
#include "scene/scene.h"
#include "bench_util.h"
#include "text_buffer.h"

static uint64_t rng_state;
static double rnd(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * 0x1p-53;
}

static char *scene_doc(int n_tri, int n_sph, int spp, uint32_t seed, const char *mode)
{
    rng_state = 12345;
    text_buffer b = {0};
    text_put(&b, "{\"tessera\":1,\"camera\":{\"type\":\"perspective\",\"from\":[0,2,5],\"to\":[0,1.6,-10],\"fov\":60},"
            "\"film\":{\"width\":96,\"height\":96},\"sampler\":{\"type\":\"sobol\",\"spp\":%d,\"seed\":%u},"
            "\"integrator\":{\"type\":\"path\",\"max_depth\":2,\"light_sampling\":\"%s\"},"
            "\"materials\":{\"w\":{\"type\":\"diffuse\",\"reflectance\":0.6},\"k\":{\"type\":\"diffuse\",\"reflectance\":0}},"
            "\"shapes\":[{\"type\":\"mesh\",\"material\":\"w\",\"positions\":[-3,0,-40, 3,0,-40, 3,0,6, -3,0,6, "
            "-3,4,-40, -3,4,6, 3,4,-40, 3,4,6],\"indices\":[0,2,1, 0,3,2, 0,4,5, 0,5,3, 1,2,7, 1,7,6]},"
            "{\"type\":\"mesh\",\"material\":\"w\",\"positions\":[-2.5,0,-6, -1,0,-6, -1,1.5,-6, -2.5,1.5,-6],"
            "\"indices\":[0,1,2, 0,2,3]},"
            "{\"type\":\"sphere\",\"center\":[1.5,0.8,-3],\"radius\":0.8,\"material\":\"w\"}",
        spp, seed, mode);
    /* the ceiling's triangles: a jittered grid along the corridor's ceiling (y = 3.9), facing
     * down, radiance over two decades */
    int across = 6, along = (n_tri + across - 1) / across;
    for (int i = 0; i < n_tri; i++) {
        double x = -2.8 + 5.6 * ((i % across) + 0.5 * rnd()) / across;
        double z = -39.5 + 45.0 * ((i / across) + 0.5 * rnd()) / along;
        double s = 0.05 + 0.05 * rnd(), le = 0.5 * pow(10, 2 * rnd());
        text_put(&b, ",{\"type\":\"mesh\",\"material\":\"k\",\"emission\":%.4g,\"positions\":[%.4f,3.9,%.4f, %.4f,3.9,%.4f, "
                "%.4f,3.9,%.4f],\"indices\":[0,1,2]}",
            le, x, z, x + s, z, x, z + s);
    }
    /* small spheres all along the corridor, at any height */
    for (int i = 0; i < n_sph; i++)
        text_put(&b, ",{\"type\":\"sphere\",\"center\":[%.4f,%.4f,%.4f],\"radius\":%.3f,\"material\":\"k\",\"emission\":%.4g}",
            -2.7 + 5.4 * rnd(), 0.3 + 3.3 * rnd(), -39.5 + 45 * rnd(), 0.02 + 0.03 * rnd(), 2 * pow(10, 2 * rnd()));
    text_put(&b, "]}");
    return b.p;
}

static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

#define N_MODES 3
static const char *const modes[N_MODES] = {"power", "spatial", "bvh"};

int main(int argc, char **argv)
{
    int n_tri = 1000, n_sph = 200, spp = 16, K = 6, threads = 2;
    for (int i = 1; i + 1 < argc; i += 2) {
        int v = atoi(argv[i + 1]);
        if (!strcmp(argv[i], "--tris")) n_tri = v;
        else if (!strcmp(argv[i], "--spheres")) n_sph = v;
        else if (!strcmp(argv[i], "--spp")) spp = v;
        else if (!strcmp(argv[i], "--renders")) K = v;
        else if (!strcmp(argv[i], "--threads")) threads = v;
        else {
            fprintf(stderr, "usage: bench_light_bvh [--tris N] [--spheres N] [--spp N] [--renders K] [--threads T]\n");
            return 2;
        }
    }
    if (K < 2 || spp < 1 || threads < 1 || n_tri < 0 || n_sph < 0) {
        fprintf(stderr, "bench_light_bvh: --renders must be at least 2, the others positive\n");
        return 2;
    }
    int W = 96, H = 96, npx = W * H;
    double *sum = calloc((size_t)N_MODES * npx * 3, sizeof *sum), *sum2 = calloc((size_t)N_MODES * npx * 3, sizeof *sum2);
    double cpu[N_MODES] = {0}, load[N_MODES] = {0};
    uint32_t n_lights = 0;
    if (!sum || !sum2) return 1;
    float *rgb = malloc((size_t)npx * 3 * sizeof *rgb);
    double *rel = malloc((size_t)npx * sizeof *rel);
    if (!rgb || !rel) return 1;
    for (int k = 0; k < K; k++)
        for (int m = 0; m < N_MODES; m++) {
            char *doc = scene_doc(n_tri, n_sph, spp, (uint32_t)k + 1, modes[m]);
            ts_scene *s = NULL;
            ts_error err = {0};
            double t0 = clock_s(CLOCK_MONOTONIC);
            if (ts_scene_load_text(doc, strlen(doc), NULL, "many-lights", NULL, &s, &err)) {
                fprintf(stderr, "bench_light_bvh: %s\n", err.message);
                return 1;
            }
            load[m] += clock_s(CLOCK_MONOTONIC) - t0;
            free(doc);
            n_lights = s->n_lights;
            ts_film *f = ts_film_create(s->width, s->height, 0, 0, W, H, &err);
            if (!f) return 1;
            ts_render_stats stats = {0};
            ts_render_request req = {s, s->integrator.type, f, 0, (uint32_t)spp, threads, NULL, NULL, NULL, false};
            double c0 = cpu_seconds();
            if (ts_render(&req, &stats, &err)) {
                fprintf(stderr, "bench_light_bvh: %s\n", err.message);
                return 1;
            }
            cpu[m] += cpu_seconds() - c0;
            ts_film_resolve(f, rgb);
            for (int i = 0; i < npx * 3; i++) {
                sum[(size_t)m * npx * 3 + i] += rgb[i];
                sum2[(size_t)m * npx * 3 + i] += (double)rgb[i] * rgb[i];
            }
            ts_film_destroy(f);
            ts_scene_destroy(s);
        }
    printf("| selection | lights | load s | render CPU s / render | image mean ± se | relative variance of a render | "
           "efficiency ÷ power's |\n|---|--:|--:|--:|--:|--:|--:|\n");
    double eff0 = 0;
    for (int m = 0; m < N_MODES; m++) {
        double var = 0, mean = 0, mean_var = 0;
        const double *s1 = sum + (size_t)m * npx * 3, *s2 = sum2 + (size_t)m * npx * 3;
        /* per pixel: the sample variance of the K renders' luminance-free channel mean, and
         * its relative form; the efficiency uses the mean relative variance over the pixels
         * without the 1% largest (the pixels that see a small emitter directly, whose
         * variance no light selection touches) */
        for (int i = 0; i < npx; i++) {
            double mu = 0, v = 0;
            for (int c = 0; c < 3; c++) {
                double mc = s1[3 * i + c] / K, vc = (s2[3 * i + c] - K * mc * mc) / (K - 1);
                mu += mc / 3;
                v += (vc > 0 ? vc : 0) / 3;
            }
            rel[i] = mu > 0 ? v / (mu * mu) : 0;
            mean += mu;
            mean_var += v;
        }
        qsort(rel, (size_t)npx, sizeof *rel, cmp_double);
        int keep = npx - npx / 100;
        for (int i = 0; i < keep; i++)
            var += rel[i];
        var /= keep;
        mean /= npx;
        double se = sqrt(mean_var) / npx / sqrt((double)K); /* pixels independent: Σ var / n² */
        double t = cpu[m] / K, eff = 1 / (var * t);
        if (m == 0) eff0 = eff;
        printf("| %s | %u | %.3f | %.2f | %.5f ± %.5f | %.4g | %.2f |\n", modes[m], n_lights, load[m] / K, t, mean, se,
               var, eff / eff0);
    }
    printf("\n%d renders a selection at %d spp, 96×96, %d threads; %d ceiling triangles and %d spheres.\n", K, spp,
           threads, n_tri, n_sph);
    free(sum);
    free(sum2);
    free(rgb);
    free(rel);
    return 0;
}
