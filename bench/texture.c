/* texture.c — cost of texture lookups (renderer/textures/), in ns per lookup on one thread.
 *
 * Builds a SIZE × SIZE RGB MIP map (default 1024², a smooth pattern with detail, made
 * here) and times, over a fixed pseudo-random set of query points (PCG32, seed 1, made
 * before the clock starts): bilinear at level 0, trilinear with footprints of 0.25 to 8
 * texels, EWA with isotropic and 8:1 anisotropic footprints (pbrt-v3's default
 * maxanisotropy), the imagemap texture through ts_texture_eval_rgb (mapping + EWA), and
 * the procedural textures that cost the most (fbm with 8 octaves, marble, the closed-form
 * checkerboard). The query points are shuffled over the whole texture, the worst case
 * for the cache; a renderer's coherent lookups are cheaper. Prints the best of RUNS runs
 * by the thread's CPU time (the figure that holds on a shared machine). A checksum of
 * the results is printed so the work cannot be optimised away. Not run by ctest.
 *
 *   bench_texture [SIZE] [LOOKUPS] [RUNS]     (defaults: 1024, 1000000, 5) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/arena.h"
#include "core/hash.h"
#include "textures/mipmap.h"
#include "textures/noise.h"
#include "textures/texture.h"
#include "bench_util.h"

typedef struct query {
    ts_vec2 st, dx, dy;
    ts_vec3 p;
} query;

enum { K_BILINEAR, K_TRILINEAR, K_EWA, K_TEXTURE, K_PROC };

static double run(int kind, const ts_mipmap *m, const ts_texture *tex, const query *q, int n, float scale,
                  int runs, double *checksum)
{
    double best = 1e30;
    for (int r = 0; r < runs; r++) {
        double sum = 0, t0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        for (int i = 0; i < n; i++) {
            ts_rgb v = {0, 0, 0};
            ts_vec2 dx = {q[i].dx.x * scale, q[i].dx.y * scale}, dy = {q[i].dy.x * scale, q[i].dy.y * scale};
            switch (kind) {
            case K_BILINEAR:
                v = ts_mipmap_bilinear(m, 0, q[i].st);
                break;
            case K_TRILINEAR:
                v = ts_mipmap_lookup(m, q[i].st, dx, dy, true, 8);
                break;
            case K_EWA:
                v = ts_mipmap_lookup(m, q[i].st, dx, dy, false, 8);
                break;
            case K_TEXTURE:
            case K_PROC: {
                ts_texture_context c = {
                    .p = q[i].p, .uv = q[i].st, .dudx = dx.x, .dvdx = dx.y, .dudy = dy.x, .dvdy = dy.y};
                c.dpdx = (ts_vec3){dx.x, dx.y, 0}, c.dpdy = (ts_vec3){dy.x, dy.y, 0};
                v = ts_texture_eval_rgb(tex, &c);
                break;
            }
            }
            sum += v.r + v.g + v.b;
        }
        double t = clock_s(CLOCK_THREAD_CPUTIME_ID) - t0;
        if (t < best) best = t;
        *checksum += sum;
    }
    return best / n * 1e9;
}

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 1024;
    int n = argc > 2 ? atoi(argv[2]) : 1000000;
    int runs = argc > 3 ? atoi(argv[3]) : 5;
    if (size < 1 || size > 8192 || n < 1 || runs < 1) {
        fprintf(stderr, "usage: bench_texture [SIZE 1..8192] [LOOKUPS] [RUNS]\n");
        return 2;
    }
    float *texels = malloc(sizeof *texels * (size_t)size * (size_t)size * 3);
    query *q = malloc(sizeof *q * (size_t)n);
    if (!texels || !q) return 1;
    for (int t = 0; t < size; t++)
        for (int s = 0; s < size; s++) {
            float *v = texels + ((size_t)t * (size_t)size + (size_t)s) * 3;
            float a = ts_noise((float)s * 0.05f, (float)t * 0.05f, 0.5f);
            v[0] = 0.5f + 0.5f * a, v[1] = (float)((s ^ t) & 15) / 15.0f, v[2] = (float)s / (float)size;
        }
    ts_mipmap *m = NULL;
    ts_error err = {0};
    if (ts_mipmap_create(texels, size, size, 3, TS_TEXTURE_WRAP_REPEAT, 0, &m, &err)) {
        fprintf(stderr, "bench_texture: %s\n", err.message);
        return 1;
    }
    ts_pcg32 rng;
    ts_pcg32_seed(&rng, 1, 0);
    float texel = 1.0f / (float)size;
    for (int i = 0; i < n; i++) {
        q[i].st = (ts_vec2){ts_pcg32_float(&rng) * 4 - 2, ts_pcg32_float(&rng) * 4 - 2};
        /* Footprint axes of about one texel, isotropic with a random orientation. */
        float a = ts_pcg32_float(&rng) * 2 * TS_PI;
        q[i].dx = (ts_vec2){cosf(a) * texel, sinf(a) * texel};
        q[i].dy = (ts_vec2){-sinf(a) * texel, cosf(a) * texel};
        q[i].p = (ts_vec3){ts_pcg32_float(&rng) * 10, ts_pcg32_float(&rng) * 10, ts_pcg32_float(&rng) * 10};
    }
    /* An 8:1 footprint: the second axis an eighth of the first. */
    query *qa = malloc(sizeof *qa * (size_t)n);
    if (!qa) return 1;
    for (int i = 0; i < n; i++) {
        qa[i] = q[i];
        qa[i].dx = (ts_vec2){q[i].dx.x * 8, q[i].dx.y * 8};
    }

    ts_arena arena;
    ts_arena_init(&arena, 0);
    const ts_texture *img = NULL, *fbm = NULL, *marble = NULL, *check = NULL, *t1, *t2;
    ts_texture proto = {
        .type = TS_TEXTURE_IMAGEMAP,
        .is_rgb = true,
        .image = {.map = ts_texture_mapping2d_uv(1, 1, 0, 0), .mipmap = m, .max_anisotropy = 8}};
    ts_mat4 id = ts_mat4_identity();
    ts_texture pf = {
        .type = TS_TEXTURE_FBM, .is_rgb = true, .fbm = {.map = {id}, .octaves = 8, .omega = 0.5f}};
    ts_texture pm = {.type = TS_TEXTURE_MARBLE,
                     .is_rgb = true,
                     .marble = {.map = {id}, .octaves = 8, .omega = 0.5f, .scale = 1, .variation = 0.2f}};
    ts_texture c1 = ts_texture_constant_rgb((ts_rgb){1, 1, 1}),
               c2 = ts_texture_constant_rgb((ts_rgb){0, 0, 0});
    if (ts_texture_make(&arena, &proto, &img, &err) || ts_texture_make(&arena, &pf, &fbm, &err) ||
        ts_texture_make(&arena, &pm, &marble, &err) || ts_texture_make(&arena, &c1, &t1, &err) ||
        ts_texture_make(&arena, &c2, &t2, &err)) {
        fprintf(stderr, "bench_texture: %s\n", err.message);
        return 1;
    }
    ts_texture pc = {
        .type = TS_TEXTURE_CHECKERBOARD2D,
        .is_rgb = true,
        .checkerboard2d = {
            .map = ts_texture_mapping2d_uv(16, 16, 0, 0), .tex1 = t1, .tex2 = t2, .closed_form = true}};
    if (ts_texture_make(&arena, &pc, &check, &err)) return 1;

    double sum = 0;
    printf(
        "texture lookups, %d × %d RGB MIP map (%d levels), %d random queries, best of %d (thread CPU time)\n",
        size, size, m->n_levels, n, runs);
    printf("  %-44s %8.1f ns\n", "bilinear, level 0", run(K_BILINEAR, m, NULL, q, n, 1, runs, &sum));
    const float widths[] = {0.25f, 1, 2, 8};
    for (int i = 0; i < 4; i++) {
        char label[64];
        snprintf(label, sizeof label, "trilinear, footprint %g texel%s", (double)widths[i],
                 widths[i] == 1 ? "" : "s");
        printf("  %-44s %8.1f ns\n", label, run(K_TRILINEAR, m, NULL, q, n, widths[i] / 2, runs, &sum));
    }
    printf("  %-44s %8.1f ns\n", "EWA, isotropic, 1 texel", run(K_EWA, m, NULL, q, n, 1, runs, &sum));
    printf("  %-44s %8.1f ns\n", "EWA, 8:1 anisotropic", run(K_EWA, m, NULL, qa, n, 1, runs, &sum));
    printf("  %-44s %8.1f ns\n", "imagemap texture (uv mapping + EWA)",
           run(K_TEXTURE, m, img, q, n, 1, runs, &sum));
    printf("  %-44s %8.1f ns\n", "fbm texture, 8 octaves (no footprint)",
           run(K_PROC, m, fbm, q, n, 0, runs, &sum));
    printf("  %-44s %8.1f ns\n", "marble texture, 8 octaves (no footprint)",
           run(K_PROC, m, marble, q, n, 0, runs, &sum));
    printf("  %-44s %8.1f ns\n", "checkerboard, closed form, 1-texel footprint",
           run(K_PROC, m, check, q, n, 1, runs, &sum));
    printf("checksum %.6g\n", sum);
    ts_arena_fini(&arena);
    ts_mipmap_destroy(m);
    free(texels), free(q), free(qa);
    return 0;
}
